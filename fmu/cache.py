"""The persistent cache of compiled C templates, safe across threads and processes.

The FMI API layers (``fmi2Functions.c``, ``fmi3Functions.c``), the instance code
(``lti_instance.c``) and the arithmetic (``linear_model.c``) are the same in every FMU of an
FMI version, up to the generated ``flexsat_interfaces.h`` (three variants). Their object
files are kept in a folder on disk, so that they compile once per machine and compiler,
not once per export or per process; each export then compiles only its generated
``model.c``.

Where
    ``$FLEXSAT_CACHE_DIR/fmu-objects``, else ``$XDG_CACHE_HOME/flexsat/fmu-objects``, else
    ``~/.cache/flexsat/fmu-objects``. If that folder cannot be created or written, a
    temporary folder of the process is used instead (removed at exit), without an error:
    exports then work as before, compiling the templates once per process.
Key
    SHA-256 of the compiler (its resolved path and the output of ``cc --version``), the
    compile flags, and the names and contents of the source and of every header it may
    include. A new compiler, other flags or an edited template give a new key; nothing
    is ever looked up by file time.
Entries
    ``<key>.o`` with a sidecar ``<key>.json`` holding the object's SHA-256. An object is
    used only if its bytes hash to the sidecar's value and start like an object file of
    this platform; anything else (a truncated or overwritten file, a missing sidecar) is
    rebuilt.
Concurrency
    A writer holds a thread lock and an exclusive ``fcntl.flock`` on ``<key>.lock`` while
    it compiles into a temporary file of its own (``<key>.o.tmp-*``, created with
    ``O_EXCL``), checks it, and publishes it with ``os.replace`` (sidecar first, then the
    object). Readers take no lock: ``os.replace`` is atomic, so they see either the old or
    the new complete file, and a sidecar that does not match sends them to the locked
    path, where they wait and read again. A writer that dies leaves its temporary file
    behind and releases its lock (the kernel drops a dead process's flock); the next
    writer of that key deletes the leftovers, and so does the first use of the cache in
    every process, for each key whose lock it can take at once (nobody is writing it). Each export copies the objects it uses into
    its own build folder, so a later replacement cannot change an object under its linker.
    Where file locks do not work (some network file systems), objects are compiled in the
    build folder and not cached.
"""

from __future__ import annotations

import atexit
import hashlib
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
from collections.abc import Callable, Sequence
from pathlib import Path

from .errors import FMUBuildError

__all__ = ["OBJECT_CACHE_ENV", "cache_root", "object_cache_dir", "compiler_identity",
           "object_key", "looks_like_object", "ObjectCache"]

#: Environment variable naming flexsat's cache folder.
OBJECT_CACHE_ENV = "FLEXSAT_CACHE_DIR"

# Bumped whenever the layout of the cache or the meaning of a key changes.
_FORMAT = "flexsat-fmu-object-cache-1"

_thread_locks: dict[str, threading.Lock] = {}
_thread_locks_guard = threading.Lock()
_identities: dict[tuple, str] = {}
_identities_guard = threading.Lock()
_fallback_dir: Path | None = None
_fallback_guard = threading.Lock()
_swept: set[Path] = set()
_swept_guard = threading.Lock()


def cache_root() -> Path:
    """flexsat's cache folder: ``$FLEXSAT_CACHE_DIR``, ``$XDG_CACHE_HOME/flexsat`` or
    ``~/.cache/flexsat`` (not created here)."""
    explicit = os.environ.get(OBJECT_CACHE_ENV)
    if explicit:
        return Path(explicit).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    if xdg and os.path.isabs(xdg):  # the XDG spec ignores relative paths
        return Path(xdg) / "flexsat"
    return Path.home() / ".cache" / "flexsat"


def _writable(folder: Path) -> bool:
    try:
        folder.mkdir(parents=True, exist_ok=True)
        descriptor, probe = tempfile.mkstemp(dir=folder, prefix=".probe-")
        os.close(descriptor)
        os.unlink(probe)
        return True
    except (OSError, RuntimeError):  # RuntimeError: Path.home() without a home
        return False


def _process_fallback() -> Path:
    global _fallback_dir
    with _fallback_guard:
        if _fallback_dir is None or not _fallback_dir.is_dir():
            _fallback_dir = Path(tempfile.mkdtemp(prefix=f"flexsat-fmu-cache-{os.getpid()}-"))
            atexit.register(shutil.rmtree, _fallback_dir, True)
        return _fallback_dir


def object_cache_dir() -> Path:
    """The folder of cached objects (created); a per-process temporary one if the
    persistent one cannot be written."""
    try:
        folder = cache_root() / "fmu-objects"
    except RuntimeError:  # no home directory to expand
        return _process_fallback()
    return folder if _writable(folder) else _process_fallback()


def compiler_identity(compiler: str) -> str:
    """Resolved path and ``--version`` output of ``compiler`` (memoised per process, keyed
    by the file's path, size and modification time)."""
    resolved = os.path.realpath(compiler)
    try:
        status = os.stat(resolved)
        memo_key = (resolved, status.st_size, status.st_mtime_ns)
    except OSError:
        memo_key = (resolved, None, None)
    with _identities_guard:
        known = _identities.get(memo_key)
    if known is not None:
        return known
    try:
        result = subprocess.run([compiler, "--version"], capture_output=True, text=True,
                                errors="replace", timeout=120, check=False)
        version = f"exit {result.returncode}\n{result.stdout}\n{result.stderr}"
    except (OSError, subprocess.TimeoutExpired) as error:
        version = f"--version failed: {type(error).__name__}"
    identity = f"{resolved}\n{version}"
    with _identities_guard:
        _identities[memo_key] = identity
    return identity


def object_key(identity: str, flags: Sequence[str], source: Path, headers: Sequence[Path]) -> str:
    """SHA-256 (hex) of everything an object file depends on."""
    digest = hashlib.sha256()
    for part in (_FORMAT, identity, "\0".join(flags), sys.platform):
        digest.update(part.encode("utf-8", "surrogateescape") + b"\0")
    for path in (source, *headers):
        digest.update(path.name.encode("utf-8", "surrogateescape") + b"\0")
        content = path.read_bytes()
        digest.update(len(content).to_bytes(8, "little"))
        digest.update(content)
    return digest.hexdigest()


def looks_like_object(data: bytes) -> bool:
    """True if ``data`` starts like a relocatable object of this platform (ELF, Mach-O)."""
    if sys.platform == "darwin":
        return data[:4] in (b"\xcf\xfa\xed\xfe", b"\xce\xfa\xed\xfe", b"\xca\xfe\xba\xbe")
    return len(data) > 64 and data[:4] == b"\x7fELF"


def _thread_lock(key: str) -> threading.Lock:
    with _thread_locks_guard:
        return _thread_locks.setdefault(key, threading.Lock())


class ObjectCache:
    """Cached object files in one folder (see the module docstring for the protocol).

    Parameters
    ----------
    folder : pathlib.Path, optional
        Default :func:`object_cache_dir`.
    """

    def __init__(self, folder: Path | None = None):
        self.folder = object_cache_dir() if folder is None else Path(folder)

    def _paths(self, key: str) -> tuple[Path, Path, Path]:
        return (self.folder / f"{key}.o", self.folder / f"{key}.json",
                self.folder / f"{key}.lock")

    def read(self, key: str) -> bytes | None:
        """The cached object's bytes if the entry is complete and intact, else None."""
        obj, sidecar, _ = self._paths(key)
        try:
            data = obj.read_bytes()
            expected = json.loads(sidecar.read_text(encoding="utf-8"))["sha256"]
        except (OSError, ValueError, KeyError, TypeError):
            return None
        if hashlib.sha256(data).hexdigest() != expected or not looks_like_object(data):
            return None
        return data

    def fetch(self, key: str, destination: Path, build: Callable[[Path], None]) -> bool:
        """Write the object of ``key`` to ``destination``, building it if needed.

        Parameters
        ----------
        key : str
            From :func:`object_key`.
        destination : pathlib.Path
            A private path (the export's build folder).
        build : callable
            ``build(path)`` compiles the object into ``path`` (an existing empty file),
            raising on failure.

        Returns
        -------
        bool
            True if the object came from the cache, False if it was built now.
        """
        with _swept_guard:
            sweep = self.folder not in _swept
            _swept.add(self.folder)
        if sweep:
            self.remove_leftovers()
        data = self.read(key)
        if data is not None:
            destination.write_bytes(data)
            return True
        import fcntl  # POSIX only, as is building FMU binaries here

        obj, sidecar, lock_path = self._paths(key)
        with _thread_lock(key):
            lock = None
            try:
                lock = open(lock_path, "a+b")
                fcntl.flock(lock.fileno(), fcntl.LOCK_EX)
            except OSError:
                # no working file locks here (e.g. some network file systems): compile
                # privately and cache nothing rather than risk two writers
                if lock is not None:
                    lock.close()
                build(destination)
                return False
            with lock:
                try:
                    data = self.read(key)  # another thread or process may just have built it
                    if data is not None:
                        destination.write_bytes(data)
                        return True
                    for stale in self.folder.glob(f"{key}.*.tmp-*"):
                        try:  # a dead writer's: we hold the lock
                            stale.unlink()
                        except OSError:
                            pass
                    data = self._build(key, build)
                    destination.write_bytes(data)
                    return False
                finally:
                    fcntl.flock(lock.fileno(), fcntl.LOCK_UN)

    def _build(self, key: str, build: Callable[[Path], None]) -> bytes:
        obj, sidecar, _ = self._paths(key)
        descriptor, temporary = tempfile.mkstemp(dir=self.folder, prefix=f"{key}.o.tmp-")
        os.close(descriptor)
        temporary = Path(temporary)
        try:
            build(temporary)
            data = temporary.read_bytes()
            if not looks_like_object(data):
                raise FMUBuildError(
                    f"the C compiler wrote no object file to {temporary} (got {len(data)} "
                    "bytes that are not an object file); check the compiler.")
            descriptor, side_temporary = tempfile.mkstemp(dir=self.folder,
                                                          prefix=f"{key}.json.tmp-")
            with os.fdopen(descriptor, "w", encoding="utf-8") as handle:
                json.dump({"sha256": hashlib.sha256(data).hexdigest(), "bytes": len(data)},
                          handle)
            os.replace(side_temporary, sidecar)
            os.replace(temporary, obj)
            return data
        finally:
            temporary.unlink(missing_ok=True)

    def remove_leftovers(self) -> list[Path]:
        """Delete the temporary files of writers that died, for every key nobody is
        writing now (its lock can be taken without waiting). Returns the files deleted."""
        import fcntl

        removed = []
        keys = {p.name.split(".", 1)[0] for p in self.folder.glob("*.tmp-*")}
        for key in sorted(keys):
            try:
                lock = open(self._paths(key)[2], "a+b")
            except OSError:
                continue
            with lock:
                try:
                    fcntl.flock(lock.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
                except OSError:
                    continue  # being written right now (or no working locks)
                try:
                    for stale in self.folder.glob(f"{key}.*.tmp-*"):
                        try:
                            stale.unlink()
                            removed.append(stale)
                        except OSError:
                            pass
                finally:
                    fcntl.flock(lock.fileno(), fcntl.LOCK_UN)
        return removed

    def evict(self, key: str) -> None:
        """Remove an entry (e.g. one whose object made a broken library)."""
        import fcntl

        obj, sidecar, lock_path = self._paths(key)
        with _thread_lock(key), open(lock_path, "a+b") as lock:
            fcntl.flock(lock.fileno(), fcntl.LOCK_EX)
            try:
                obj.unlink(missing_ok=True)
                sidecar.unlink(missing_ok=True)
            finally:
                fcntl.flock(lock.fileno(), fcntl.LOCK_UN)
