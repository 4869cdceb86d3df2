"""Compiling the FMU's shared library with the system C compiler, in a private build folder.

One direct compiler call per C file, no build system: the four C files and the FMI headers
compile to a shared library that needs only libc and libm (and pthread, in libc on current
systems; no symbol newer than glibc 2.17, see :mod:`fmu.verify`), with every symbol hidden
except the FMI functions (``-fvisibility=hidden`` plus ``FMI2_Export`` / ``FMI3_Export``
on the API functions).

The fixed templates come from the persistent object cache (:mod:`fmu.cache`): compiled once
per machine and compiler, written atomically under a cross-process lock, checked against a
hash on every use. Only the generated ``model.c`` is compiled by every export.

Build folders
    Each export works in its own folder ``<tmp>/flexsat-fmu-<pid>-<random>`` (``<tmp>`` is
    :func:`tempfile.gettempdir`), removed when the export ends, also when it ends with an
    exception (including the ``SystemExit`` or ``KeyboardInterrupt`` that a signal handler
    raises); compiler processes still running are killed first. A process killed outright
    (SIGKILL, or SIGTERM without a handler) cannot clean up: the first export of every
    later process removes the folders of processes that no longer exist once they are older
    than :data:`STALE_BUILD_AGE` (a day; the age guards against a process of the same pid
    in another pid namespace sharing the temporary folder). Leftovers are harmless
    meanwhile: no export reads another's folder.
"""

from __future__ import annotations

import errno
import os
import platform
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from .cache import ObjectCache, compiler_identity, object_key
from .checks import shorten
from .errors import FMUBuildError, FMUCompilerError

__all__ = ["COMPILE_FLAGS", "STALE_BUILD_AGE", "platform_folder", "find_compiler",
           "build_directory", "remove_stale_build_dirs", "SharedLibraryBuild",
           "compile_shared_library"]

COMPILE_FLAGS = ("-shared", "-fPIC", "-std=c99", "-O2", "-fvisibility=hidden", "-pthread")

#: A compiler that failed where less than this is free [bytes] is taken to have found the
#: disk full (the objects of one FMU take about 1 MiB).
_LEAST_FREE = 16 * 2**20

#: Age after which the build folder of a dead process is removed [s].
STALE_BUILD_AGE = 86400.0

_BUILD_PREFIX = "flexsat-fmu-"
# flexsat-fmu-<pid>-..., flexsat-fmu-cache-<pid>-... (fallback object caches); older
# versions wrote flexsat-fmu-<random>, flexsat-fmu-obj-<random>, flexsat-fmu-cache-<random>
_STALE_NAME = re.compile(r"flexsat-fmu-(?:cache-)?(?:(\d+)-)?.+")
_swept = False
_sweep_guard = threading.Lock()


def platform_folder(fmi_version: str = "2.0") -> tuple[str, str]:
    """Platform folder under ``binaries/`` and the library suffix for this machine.

    FMI 2.0 names it ``linux64``, ``darwin64``...; FMI 3.0 by the platform tuple
    ``<arch>-<sys>`` (``x86_64-linux``, ``aarch64-darwin``...; FMI 3.0.2, section 2.5.1.5).

    Raises
    ------
    FMUBuildError
        On a platform this exporter does not build for.
    """
    bits = 64 if sys.maxsize > 2**32 else 32
    system = platform.system()
    if system not in ("Linux", "Darwin"):
        raise FMUBuildError(
            f"building FMU binaries on {system} is not supported; export on Linux or macOS, or "
            "export with sources_only=True and compile the sources/ folder of the FMU with "
            "your own tool chain.")
    suffix = ".so" if system == "Linux" else ".dylib"
    if fmi_version == "2.0":
        return f"{system.lower()}{bits}", suffix
    machine = platform.machine().lower()
    arch = {"x86_64": "x86_64", "amd64": "x86_64", "i386": "x86", "i686": "x86",
            "aarch64": "aarch64", "arm64": "aarch64", "armv7l": "aarch32"}.get(machine)
    if arch is None:
        raise FMUBuildError(f"the FMI 3.0 platform tuple of the machine {machine!r} is not "
                            "known; export with sources_only=True and compile the sources/ "
                            "folder of the FMU with your own tool chain.")
    return f"{arch}-{system.lower()}", suffix


def find_compiler(compiler: str | os.PathLike | None = None) -> str:
    """Path of the C compiler: ``compiler`` if given, else ``$CC``, else gcc or cc on PATH.

    Raises
    ------
    FMUBuildError
        If no compiler is found; the message says how to get one.
    """
    candidates = [os.fspath(compiler)] if compiler is not None else [os.environ.get("CC"), "gcc", "cc"]
    for candidate in candidates:
        if not candidate:
            continue
        path = shutil.which(candidate)
        if path is not None:
            return path
    wanted = shorten(candidates[0]) if compiler is not None else "gcc or cc (or $CC)"
    raise FMUBuildError(
        f"no C compiler found (looked for {wanted}); an FMU binary must be compiled at export "
        "time. Install one (Debian/Ubuntu: `apt-get install gcc`), put it on PATH, or pass "
        "compiler='/path/to/gcc' (or set the CC environment variable).")


def _process_exists(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # e.g. PermissionError: it exists, owned by someone else
        return True
    return True


def remove_stale_build_dirs(parent: Path | None = None, max_age: float | None = None) -> list[Path]:
    """Remove build folders left by processes that were killed (see the module docstring).

    A folder ``flexsat-fmu-<pid>-*`` (or ``flexsat-fmu-cache-<pid>-*``) is removed when no
    process ``pid`` exists and it was last modified more than ``max_age`` seconds ago;
    folders of older versions, without a pid, on age alone.

    Parameters
    ----------
    parent : pathlib.Path, optional
        Default :func:`tempfile.gettempdir`.
    max_age : float, optional, s
        Default :data:`STALE_BUILD_AGE`.

    Returns
    -------
    list of pathlib.Path
        The folders removed.
    """
    parent = Path(tempfile.gettempdir() if parent is None else parent)
    max_age = STALE_BUILD_AGE if max_age is None else max_age
    removed = []
    now = time.time()
    try:
        entries = list(os.scandir(parent))
    except OSError:
        return removed
    for entry in entries:
        match = _STALE_NAME.fullmatch(entry.name)
        if match is None:
            continue
        try:
            if not entry.is_dir(follow_symlinks=False) or entry.stat(follow_symlinks=False).st_uid != os.getuid():
                continue
            age = now - entry.stat(follow_symlinks=False).st_mtime
        except OSError:
            continue
        pid = int(match.group(1)) if match.group(1) else None
        if age <= max_age or pid == os.getpid() or (pid is not None and _process_exists(pid)):
            continue
        shutil.rmtree(entry.path, ignore_errors=True)
        removed.append(Path(entry.path))
    return removed


@contextmanager
def build_directory() -> Iterator[Path]:
    """A private build folder ``flexsat-fmu-<pid>-*``, removed on exit, also on exceptions.

    The first call in a process also removes stale folders of killed processes
    (:func:`remove_stale_build_dirs`).
    """
    global _swept
    with _sweep_guard:
        sweep, _swept = not _swept, True
    if sweep:
        remove_stale_build_dirs()
    folder = Path(tempfile.mkdtemp(prefix=f"{_BUILD_PREFIX}{os.getpid()}-"))
    try:
        yield folder
    finally:
        shutil.rmtree(folder, ignore_errors=True)


class SharedLibraryBuild:
    """Compile C files into one shared library.

    ``compile`` starts a compiler process and returns at once (the generated model.c
    compiles while the templates are fetched); ``compile_cached`` takes a template's object
    from the persistent cache, compiling it there first if needed; ``link`` waits for the
    compilers, checks them and links. Use as a context manager so that compiler processes
    are killed on errors.

    Parameters
    ----------
    output : pathlib.Path
        The shared library to write.
    include_dirs : list of pathlib.Path
    work_dir : pathlib.Path
        A private folder for the object files (see :func:`build_directory`).
    compiler : str, optional
        See :func:`find_compiler`.
    cache : ObjectCache, optional
        Default: the persistent cache (:func:`fmu.cache.object_cache_dir`).
    """

    def __init__(self, output: Path, include_dirs: list[Path], work_dir: Path,
                 compiler: str | os.PathLike | None = None, cache: ObjectCache | None = None):
        self.cc = find_compiler(compiler)
        self.origin = ("passed as compiler=" if compiler is not None else
                       "from $CC" if os.environ.get("CC")
                       and shutil.which(os.environ["CC"]) == self.cc else "found on PATH")
        self.output = output
        self.includes = [f"-I{d}" for d in include_dirs]
        self.work_dir = work_dir
        self.objects: list[Path] = []
        self.processes: list[tuple[list[str], subprocess.Popen]] = []
        self.cache = cache
        self.cached: list[tuple[str, Path, Path, list[Path]]] = []  # key, object, source, headers
        self.cache_hits = 0

    def __enter__(self) -> "SharedLibraryBuild":
        return self

    def __exit__(self, *exc_info: object) -> None:
        for _, process in self.processes:
            _stop(process)

    def _object_path(self, source: Path) -> Path:
        return self.work_dir / f"{len(self.objects)}_{source.stem}.o"

    def _compile_command(self, source: Path, obj: Path) -> list[str]:
        return [self.cc, "-c", *COMPILE_FLAGS[1:], *self.includes, "-o", str(obj), str(source)]

    def _start(self, command: list[str]) -> subprocess.Popen:
        try:
            return _start_compiler(command)
        except OSError as error:
            raise FMUBuildError(f"the C compiler {self.cc} could not be run ({error}); check the "
                                "installation or pass another compiler=...") from error

    def _compile_now(self, source: Path, obj: Path) -> None:
        command = self._compile_command(source, obj)
        process = self._start(command)
        try:
            _, stderr = process.communicate()
        except BaseException:
            _stop(process)
            raise
        self._check(command, process.returncode, stderr)

    def compile_cached(self, source: Path, headers: list[Path]) -> None:
        """Add the object of a template (a file the same in every FMU) from the cache.

        Parameters
        ----------
        source : pathlib.Path
        headers : list of pathlib.Path
            Every file of ours the source may include: their contents are part of the key.
        """
        if self.cache is None:
            self.cache = ObjectCache()
        key = object_key(compiler_identity(self.cc), COMPILE_FLAGS[1:], source, headers)
        obj = self._object_path(source)
        if self.cache.fetch(key, obj, lambda path: self._compile_now(source, path)):
            self.cache_hits += 1
        self.objects.append(obj)
        self.cached.append((key, obj, source, headers))

    def compile(self, source: Path, obj: Path | None = None) -> None:
        """Start compiling one C file into the build folder."""
        if obj is None:
            obj = self._object_path(source)
        command = self._compile_command(source, obj)
        process = self._start(command)
        self.objects.append(obj)
        self.processes.append((command, process))

    def evict_cached(self) -> None:
        """Drop the cache entries this build used (after a broken library)."""
        for key, *_ in self.cached:
            self.cache.evict(key)

    def link(self) -> None:
        """Wait for every compilation and link the library.

        If the link fails and objects came from the cache, those entries are evicted,
        rebuilt and the link is tried once more: a cache entry that passed its checks but
        does not link (e.g. written by a broken compiler) costs one rebuild, not a failure.
        """
        for command, process in self.processes:
            _, stderr = process.communicate()
            self._check(command, process.returncode, stderr)
        self.output.parent.mkdir(parents=True, exist_ok=True)
        command = [self.cc, *COMPILE_FLAGS, "-o", str(self.output),
                   *(str(o) for o in self.objects), "-lm"]
        code, stderr = self._link(command)
        if code != 0 and self.cache_hits:
            self.evict_cached()
            for key, obj, source, headers in self.cached:
                self.cache.fetch(key, obj, lambda path, source=source: self._compile_now(source, path))
            code, stderr = self._link(command)
        self._check(command, code, stderr)

    def _check(self, command: list[str], code: int, stderr: str) -> None:
        """Raise if a compiler run failed: FMUCompilerError if the compiler fails a trivial
        C file too (the environment's fault), else FMUBuildError (ours: the compiler's
        messages on our code, and a request to report it)."""
        if code == 0:
            return
        written = Path(command[command.index("-o") + 1]).parent
        try:
            status = os.statvfs(written)
            free = status.f_bavail * status.f_frsize
        except OSError:
            free = None
        if free is not None and free < _LEAST_FREE:
            # the compiler could not write its output: the disk's fault, not the compiler's
            raise OSError(errno.ENOSPC, f"{os.strerror(errno.ENOSPC)} ({free} bytes free "
                          "after the compiler failed)", str(written))
        probe = self.work_dir / "probe"
        probe.mkdir(exist_ok=True)
        (probe / "trivial.c").write_text("int flexsat_probe(void) { return 0; }\n")
        try:
            done = subprocess.run([self.cc, *COMPILE_FLAGS, "-o", str(probe / "trivial.so"),
                                   str(probe / "trivial.c")], capture_output=True, text=True,
                                  errors="replace", timeout=120, check=False)
            works, detail = done.returncode == 0, f"exit code {done.returncode}"
            said = " ".join(done.stderr.split())
        except (OSError, subprocess.TimeoutExpired) as error:
            works, detail, said = False, type(error).__name__, " ".join(str(error).split())
        if not works:
            def cut(text):
                return text if len(text) <= 100 else text[:97] + "..."

            raise FMUCompilerError(
                f"the C compiler {cut(self.cc)} ({self.origin}) does not work: it fails on a "
                f"trivial C file too ({detail}{': ' + cut(said) if said else ''}); "
                "install a working C compiler and set CC to it (or pass compiler=... to "
                "fmu.export)")
        _check(command, code, stderr)

    def _link(self, command: list[str]) -> tuple[int, str]:
        process = self._start(command)
        try:
            _, stderr = process.communicate()
        except BaseException:
            _stop(process)
            raise
        return process.returncode, stderr


def _start_compiler(command: list[str]) -> subprocess.Popen:
    """Start a compiler in a process group of its own, so that :func:`_stop` can end the
    driver together with the programs it runs (cc1, as, ld)."""
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            errors="replace", start_new_session=True)


def _stop(process: subprocess.Popen) -> None:
    """Kill a compiler's whole process group if it still runs, and reap it.

    Killing only the driver would leave cc1 or as running, holding the output pipes open
    (reading them to the end would wait for those) and perhaps writing files later."""
    if process.poll() is None:
        try:
            os.killpg(process.pid, signal.SIGKILL)  # the group id is the driver's pid
        except OSError:
            process.kill()
    process.wait()
    for stream in (process.stdout, process.stderr):
        if stream is not None:
            stream.close()


def _tail(text: str, limit: int) -> str:
    return text if len(text) <= limit else "..." + text[-limit:]


def _check(command: list[str], code: int, stderr: str) -> None:
    if code != 0:
        raise FMUBuildError(
            f"compiling the FMU binary failed (exit code {code}):\n{' '.join(command)}\n"
            f"{_tail(stderr.strip(), 4000)}\nThis is a bug in flexsat.fmu if the compiler itself works; "
            "please report it.")


def compile_shared_library(sources: list[Path], include_dirs: list[Path], output: Path,
                           compiler: str | None = None) -> None:
    """Compile ``sources`` into the shared library ``output`` (all files in parallel).

    Raises
    ------
    FMUBuildError
        If the compiler is missing or fails (its messages are included).
    """
    with build_directory() as work_dir, \
            SharedLibraryBuild(output, include_dirs, work_dir, compiler) as build:
        for source in sources:
            build.compile(source)
        build.link()
