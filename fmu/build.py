"""Compiling the FMU's shared library with the system C compiler.

One direct compiler call, no build system: the three C files and the FMI headers compile to a
shared library that needs only libc and libm, with every symbol hidden except the FMI 2.0
functions (``-fvisibility=hidden`` plus ``FMI2_Export`` on the API functions).
"""

from __future__ import annotations

import atexit
import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from .errors import FMUBuildError

__all__ = ["platform_folder", "find_compiler", "SharedLibraryBuild", "compile_shared_library"]

COMPILE_FLAGS = ("-shared", "-fPIC", "-std=c99", "-O2", "-fvisibility=hidden")

# Object files of the fixed templates, compiled once per process (see compile_cached).
_OBJECT_CACHE: dict[str, Path] = {}
_CACHE_DIR: Path | None = None


def platform_folder() -> tuple[str, str]:
    """FMI 2.0 platform folder under ``binaries/`` and the library suffix for this machine.

    Raises
    ------
    FMUBuildError
        On a platform this exporter does not build for.
    """
    bits = 64 if sys.maxsize > 2**32 else 32
    system = platform.system()
    if system == "Linux":
        return f"linux{bits}", ".so"
    if system == "Darwin":
        return f"darwin{bits}", ".dylib"
    raise FMUBuildError(
        f"building FMU binaries on {system} is not supported; export on Linux or macOS, or "
        "compile the sources/ folder of the FMU with your own tool chain.")


def find_compiler(compiler: str | None = None) -> str:
    """Path of the C compiler: ``compiler`` if given, else ``$CC``, else gcc or cc on PATH.

    Raises
    ------
    FMUBuildError
        If no compiler is found; the message says how to get one.
    """
    candidates = [compiler] if compiler is not None else [os.environ.get("CC"), "gcc", "cc"]
    for candidate in candidates:
        if not candidate:
            continue
        path = shutil.which(candidate)
        if path is not None:
            return path
    wanted = compiler if compiler is not None else "gcc or cc (or $CC)"
    raise FMUBuildError(
        f"no C compiler found (looked for {wanted}); an FMU binary must be compiled at export "
        "time. Install one (Debian/Ubuntu: `apt-get install gcc`), put it on PATH, or pass "
        "compiler='/path/to/gcc' (or set the CC environment variable).")


class SharedLibraryBuild:
    """Compile C files into one shared library, each file in its own compiler process.

    ``compile`` starts a compiler process and returns at once, so the fixed templates can
    compile while Python still generates ``model.c``; ``link`` waits for them all, checks
    them and links. Use as a context manager so that processes and object files are cleaned
    up on errors.

    Parameters
    ----------
    output : pathlib.Path
        The shared library to write.
    include_dirs : list of pathlib.Path
    compiler : str, optional
        See :func:`find_compiler`.
    """

    def __init__(self, output: Path, include_dirs: list[Path], compiler: str | None = None):
        self.cc = find_compiler(compiler)
        self.output = output
        self.includes = [f"-I{d}" for d in include_dirs]
        self.objects: list[Path] = []
        self.processes: list[tuple[list[str], subprocess.Popen]] = []
        self.object_dir = Path(tempfile.mkdtemp(prefix="flexsat-fmu-obj-"))
        self.pending_cache: dict[str, Path] = {}

    def __enter__(self) -> "SharedLibraryBuild":
        return self

    def __exit__(self, *exc_info: object) -> None:
        for _, process in self.processes:
            if process.poll() is None:
                process.kill()
            process.communicate()
        shutil.rmtree(self.object_dir, ignore_errors=True)

    def compile_cached(self, source: Path, headers: list[Path]) -> None:
        """Like :meth:`compile` for a file that is the same in every FMU (a template).

        The object file is kept for the life of the process, keyed by the compiler, the
        flags and the contents of the source and its headers, so that later exports compile
        only their generated model.c.
        """
        # the include folder is a fresh temporary one each time: hash header contents instead
        digest = hashlib.sha256("\0".join([self.cc, *COMPILE_FLAGS]).encode())
        for path in (source, *headers):
            digest.update(path.read_bytes())
        key = digest.hexdigest()
        cached = _OBJECT_CACHE.get(key)
        if cached is not None and cached.is_file():
            self.objects.append(cached)
            return
        global _CACHE_DIR
        if _CACHE_DIR is None:
            _CACHE_DIR = Path(tempfile.mkdtemp(prefix="flexsat-fmu-cache-"))
            atexit.register(shutil.rmtree, _CACHE_DIR, True)
        self.compile(source, _CACHE_DIR / f"{key[:16]}_{source.stem}.o")
        self.pending_cache[key] = self.objects[-1]

    def compile(self, source: Path, obj: Path | None = None) -> None:
        """Start compiling one C file."""
        if obj is None:
            obj = self.object_dir / f"{len(self.objects)}_{source.stem}.o"
        command = [self.cc, "-c", *COMPILE_FLAGS[1:], *self.includes, "-o", str(obj), str(source)]
        try:
            process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                       text=True)
        except OSError as error:
            raise FMUBuildError(f"the C compiler {self.cc} could not be run ({error}); check the "
                                "installation or pass another compiler=...") from error
        self.objects.append(obj)
        self.processes.append((command, process))

    def link(self) -> None:
        """Wait for every compilation and link the library."""
        for command, process in self.processes:
            _, stderr = process.communicate()
            _check(command, process.returncode, stderr)
        self.output.parent.mkdir(parents=True, exist_ok=True)
        command = [self.cc, *COMPILE_FLAGS, "-o", str(self.output),
                   *(str(o) for o in self.objects), "-lm"]
        result = subprocess.run(command, capture_output=True, text=True, check=False)
        _check(command, result.returncode, result.stderr)
        _OBJECT_CACHE.update(self.pending_cache)


def _check(command: list[str], code: int, stderr: str) -> None:
    if code != 0:
        raise FMUBuildError(
            f"compiling the FMU binary failed (exit code {code}):\n{' '.join(command)}\n"
            f"{stderr.strip()}\nThis is a bug in flexsat.fmu if the compiler itself works; "
            "please report it.")


def compile_shared_library(sources: list[Path], include_dirs: list[Path], output: Path,
                           compiler: str | None = None) -> None:
    """Compile ``sources`` into the shared library ``output`` (all files in parallel).

    Raises
    ------
    FMUBuildError
        If the compiler is missing or fails (its messages are included).
    """
    with SharedLibraryBuild(output, include_dirs, compiler) as build:
        for source in sources:
            build.compile(source)
        build.link()
