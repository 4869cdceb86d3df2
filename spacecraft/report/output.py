"""Output folders: claimed before the work starts, complete or absent, safe for simultaneous runs.

:class:`OutputFolder` checks the destination and claims it BEFORE anything is computed, so a
folder that cannot be written is reported at once, not after minutes of work. The files go to a
hidden sibling ``.<name>.partial`` that is renamed to ``<name>`` when the run completes and
removed when it fails, so a report folder is either complete (it holds ``.flexsat-complete``)
or absent.

Claiming is one atomic ``mkdir`` of ``.<name>.partial``: of several runs started at once for the
same folder exactly one wins; the others are refused with one line naming the winner's process.
The partial folder holds ``.flexsat-owner`` (pid, host, process start time). A partial folder
whose owner process is dead (the run was killed with SIGKILL, or the machine stopped) is stale:
the next run that meets it, for the same folder or in the same parent folder, removes it.
Without ``--out`` the folder is ``flexsat-YYYYmmdd-HHMMSS`` in the working directory, suffixed
``-2``, ``-3``... past names that exist or are being written, so simultaneous runs never collide.

Permissions follow the user's umask: folders are made with mode 0o777 and files with 0o666, both
masked by the umask, as any other program's; an existing empty destination keeps its mode.

Errors are :class:`OutputError` (a :class:`~appendages.interface.FlexsatError`): one line with
the folder, what went wrong and what to do; the command line exits with status 2.
"""

from __future__ import annotations

import datetime
import errno
import json
import os
import secrets
import shutil
import socket
import stat
import time
from pathlib import Path

from appendages.interface import FlexsatError

__all__ = ["OutputError", "OutputFolder", "output_folder", "default_output_folder",
           "ENVIRONMENT_ERRNOS", "MARKER", "OWNER", "LOCK", "FolderLock", "is_environment_error"]

#: File that marks a completed report folder.
MARKER = ".flexsat-complete"
#: File in a partial folder naming the process that writes it.
OWNER = ".flexsat-owner"
#: Folder inside a folder that flexsat writes in place (a sweep's), claimed as a partial folder
#: is: it holds the owner record while the writer runs (:class:`FolderLock`).
LOCK = ".flexsat-lock"
#: An owner-less partial folder younger than this [s] may still be starting up.
_YOUNG = 60.0
#: Tries at claiming one name (a stale partial folder removed by a concurrent run).
_TRIES = 5
#: Default folder names tried per second-stamp before giving up.
_MAX_SUFFIX = 10_000

#: errno values of OSError that are the environment's, not flexsat's: no space, quota, read-only
#: file system, permissions, I/O error, file too large, too many open files.
ENVIRONMENT_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES,
                                errno.EPERM, errno.EIO, errno.EFBIG, errno.EMFILE,
                                errno.ENFILE})


class OutputError(FlexsatError):
    """The output folder cannot be claimed or written (a user or environment error)."""


def is_environment_error(exc: BaseException) -> bool:
    """True for an OSError caused by the machine (disk full, read-only, permissions...)."""
    return isinstance(exc, OSError) and exc.errno in ENVIRONMENT_ERRNOS


def _why(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def _shown(path) -> str:
    text = str(path)
    text = text if text.isprintable() else repr(text)
    return text if len(text) <= 200 else f"{text[:200]}... ({len(text)} characters)"


# ---------------------------------------------------------------------------------------------
# owners of partial folders
# ---------------------------------------------------------------------------------------------
def _start_time(pid: int) -> str | None:
    """The kernel's start time of process ``pid`` (Linux /proc), None where unknown."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as stream:
            text = stream.read().decode("ascii", "replace")
    except OSError:
        return None
    # field 22 (starttime), counted after the parenthesised command name
    fields = text[text.rfind(")") + 2:].split()
    return fields[19] if len(fields) > 19 else None


def _owner_record(command: str = "flexsat run") -> dict:
    pid = os.getpid()
    return {"program": "flexsat", "command": command, "pid": pid,
            "host": socket.gethostname(), "start": _start_time(pid),
            "since": datetime.datetime.now().isoformat(timespec="seconds")}


def _who(record: dict | None, default: str) -> str:
    """The writer of a claimed folder, in words (its owner record may not be written yet)."""
    if not record:
        return default
    return (f"{record.get('command', default)} (pid {record['pid']} on {record['host']}, since "
            f"{record.get('since', '?')})")


def _read_owner(partial: Path) -> dict | None:
    try:
        record = json.loads((partial / OWNER).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not (isinstance(record, dict) and record.get("program") == "flexsat"
            and isinstance(record.get("pid"), int)):
        return None
    return record


def _alive(record: dict) -> bool:
    """Is the process that wrote ``record`` still running? (True when it cannot be told.)"""
    if record.get("host") != socket.gethostname() or os.name != "posix":
        return True
    pid = record["pid"]
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process with this pid
        pass
    start = record.get("start")
    current = _start_time(pid)
    # the pid was reused by another process if the start times differ
    return not (start is not None and current is not None and start != current)


def _state(partial: Path) -> tuple[str, dict | None]:
    """``("absent" | "alive" | "stale" | "unknown", owner)`` of a partial folder."""
    try:
        info = partial.lstat()
    except FileNotFoundError:
        return "absent", None
    if not stat.S_ISDIR(info.st_mode):
        return "unknown", None
    record = _read_owner(partial)
    if record is not None:
        return ("alive" if _alive(record) else "stale"), record
    # no owner file: a run between its mkdir and writing the owner, or a crash in that instant
    try:
        empty = not any(partial.iterdir())
    except OSError:
        return "unknown", None
    if empty and time.time() - info.st_mtime > _YOUNG:
        return "stale", None
    return ("alive" if empty else "unknown"), None


def _remove_stale(partial: Path) -> bool:
    """Remove a stale partial folder; False if another run took it first."""
    grave = partial.with_name(f"{partial.name}.stale-{os.getpid()}-{secrets.token_hex(4)}")
    try:
        os.rename(partial, grave)  # atomic: exactly one of several cleaners gets it
    except FileNotFoundError:
        return False
    except OSError:
        return False
    shutil.rmtree(grave, ignore_errors=True)
    return True


def sweep_stale(parent: Path) -> int:
    """Remove the stale partial folders of dead flexsat runs in ``parent``; returns how many."""
    removed = 0
    try:
        candidates = [p for p in parent.iterdir() if p.name.startswith(".")
                      and p.name.endswith(".partial")]
    except OSError:
        return 0
    for partial in candidates:
        state, record = _state(partial)
        if state == "stale" and record is not None and _remove_stale(partial):
            removed += 1
    return removed


# ---------------------------------------------------------------------------------------------
# the folder
# ---------------------------------------------------------------------------------------------
def default_output_folder(cwd: Path | None = None) -> Path:
    """The first free name ``flexsat-YYYYmmdd-HHMMSS[-k]`` in the working directory.

    Only a suggestion: :class:`OutputFolder` with ``path=None`` claims a default name atomically.
    """
    cwd = Path.cwd() if cwd is None else Path(cwd)
    for path in _default_names(cwd):
        if not os.path.lexists(path) and _state(_partial(path))[0] == "absent":
            return path
    raise OutputError(f"{_shown(cwd)}: no free flexsat-<time> folder name; give --out")


def _default_names(cwd: Path):
    stamp = datetime.datetime.now().strftime("%Y%m%d-%H%M%S")
    yield cwd / f"flexsat-{stamp}"
    for k in range(2, _MAX_SUFFIX):
        yield cwd / f"flexsat-{stamp}-{k}"


def _partial(path: Path) -> Path:
    return path.with_name(f".{path.name}.partial")


class _Busy(OutputError):
    """The name is being written by another live run (a default name tries the next one)."""


class OutputFolder:
    """Context manager: a claimed partial folder that becomes ``path`` if the block completes.

    Parameters
    ----------
    path : path or None
        Destination: must not exist, or be an empty folder (a symbolic link to one is followed).
        None: a new ``flexsat-<time>`` folder in the working directory.

    Attributes
    ----------
    path : Path
        The final folder (resolved through a symbolic link; set on entering for ``None``).
    partial : Path
        The folder written while the block runs (``.<name>.partial`` beside ``path``).

    Raises
    ------
    OutputError
        On entering: the destination exists and is not an empty folder, is a dangling link,
        cannot be created (read-only, no permission, not a folder, /proc...), or is being
        written by another run. On leaving: the files could not be written (disk full...) or
        the folder appeared meanwhile; the partial folder is then removed.
    """

    def __init__(self, path: str | os.PathLike | None = None):
        if path is not None and not isinstance(path, (str, os.PathLike)):
            raise TypeError(f"path must be a folder path (str or os.PathLike) or None; got "
                            f"{type(path).__name__} {path!r:.100}")
        self.requested = None if path is None else Path(path)
        self.path: Path | None = None
        self.partial: Path | None = None
        self._mode: int | None = None

    # -- entering ------------------------------------------------------------------------------
    def __enter__(self) -> Path:
        if self.requested is None:
            self._claim_default()
        else:
            self._claim(self._resolve(self.requested))
        return self.partial

    def _resolve(self, path: Path) -> Path:
        if os.path.islink(path):
            target = os.path.realpath(path)
            if not os.path.exists(target):
                raise OutputError(f"{_shown(path)}: a symbolic link to {_shown(target)}, which "
                                  "does not exist; create that folder or give another --out")
            return Path(target)
        return Path(os.path.abspath(path))

    def _check_destination(self, path: Path) -> None:
        try:
            info = os.stat(path)
        except FileNotFoundError:
            self._mode = None
            return
        except NotADirectoryError:
            raise OutputError(f"{_shown(path)}: a parent of the output folder is a file, not a "
                              "folder; give another --out") from None
        except OSError as exc:
            raise OutputError(f"{_shown(path)}: cannot use this output folder ({_why(exc)}); "
                              "give another --out") from None
        if not stat.S_ISDIR(info.st_mode):
            raise OutputError(f"{_shown(path)}: exists and is not a folder; choose another "
                              "--out or remove it")
        try:
            taken = any(os.scandir(path))
        except OSError as exc:
            raise OutputError(f"{_shown(path)}: cannot read this output folder ({_why(exc)}); "
                              "give another --out") from None
        if taken:
            raise OutputError(f"{_shown(path)}: output folder exists and is not empty; choose "
                              "another --out or remove it")
        self._mode = stat.S_IMODE(info.st_mode)

    def _make_parent(self, parent: Path) -> None:
        try:
            parent.mkdir(parents=True, exist_ok=True)
        except FileExistsError:
            raise OutputError(f"{_shown(parent)}: exists and is not a folder; give another "
                              "--out") from None
        except NotADirectoryError:
            raise OutputError(f"{_shown(parent)}: a parent of the output folder is a file, not "
                              "a folder; give another --out") from None
        except OSError as exc:
            raise OutputError(f"{_shown(parent)}: cannot create the folder ({_why(exc)}); give "
                              "another --out") from None

    def _claim(self, path: Path) -> None:
        """Claim ``path``; OutputError (_Busy if another live run writes it) if it is taken."""
        self._check_destination(path)
        parent = path.parent
        self._make_parent(parent)
        sweep_stale(parent)
        partial = _partial(path)
        for _ in range(_TRIES):
            try:
                os.mkdir(partial)  # mode 0o777 & ~umask; atomic: one run wins
                break
            except FileExistsError:
                state, record = _state(partial)
                if state == "stale":
                    _remove_stale(partial)
                    continue
                if state == "absent":
                    continue
                who = _who(record, "flexsat run")
                if state == "alive":
                    raise _Busy(f"{_shown(path)}: another {who} is writing this folder; wait "
                                "for it or choose another --out")
                raise OutputError(f"{_shown(path)}: {_shown(partial)} exists (left by a crash, "
                                  "or not flexsat's); remove it or choose another --out")
            except OSError as exc:
                raise OutputError(f"{_shown(path)}: cannot create the output folder here "
                                  f"({_why(exc)}); give another --out") from None
        else:
            raise OutputError(f"{_shown(path)}: could not claim the output folder (other runs "
                              "keep taking it); choose another --out")
        self.path, self.partial = path, partial
        try:
            (partial / OWNER).write_text(json.dumps(_owner_record()), encoding="utf-8")
            # another run may have completed this folder before our mkdir
            self._check_destination(path)
        except BaseException as exc:
            self._discard()
            if isinstance(exc, OSError):
                raise OutputError(f"{_shown(path)}: cannot write the output folder "
                                  f"({_why(exc)}); free some space or give another --out"
                                  ) from None
            raise

    def _claim_default(self) -> None:
        cwd = Path(os.path.abspath(os.getcwd()))
        for path in _default_names(cwd):
            if os.path.lexists(path):
                continue
            try:
                self._claim(path)
                return
            except _Busy:
                continue
            except OutputError:
                if os.path.lexists(path):  # created meanwhile by another run: next name
                    continue
                raise
        raise OutputError(f"{_shown(cwd)}: no free flexsat-<time> folder name; give --out")

    # -- leaving -------------------------------------------------------------------------------
    def __exit__(self, kind, exc, tb) -> bool:
        if exc is not None:
            self._discard()
            if is_environment_error(exc):
                raise OutputError(f"{_shown(self.path)}: cannot write the output "
                                  f"({_why(exc)}{': ' + _shown(exc.filename) if exc.filename else ''}"
                                  "); nothing was kept; free some space or choose another --out"
                                  ) from exc
            return False
        try:
            (self.partial / MARKER).write_text("flexsat run completed\n", encoding="utf-8")
            (self.partial / OWNER).unlink()
            if self._mode is not None:
                os.chmod(self.partial, self._mode)  # an existing empty folder keeps its mode
            os.rename(self.partial, self.path)  # replaces an empty folder atomically
        except OSError as exc:
            self._discard()
            if exc.errno in (errno.ENOTEMPTY, errno.EEXIST, errno.ENOTDIR, errno.EISDIR):
                raise OutputError(f"{_shown(self.path)}: appeared (not empty) while flexsat was "
                                  "running; nothing was kept; choose another --out") from None
            raise OutputError(f"{_shown(self.path)}: cannot complete the output folder "
                              f"({_why(exc)}); nothing was kept") from None
        return False

    def _discard(self) -> None:
        if self.partial is not None:
            shutil.rmtree(self.partial, ignore_errors=True)


class FolderLock:
    """Context manager: exclusive writing of a folder that is written in place (a sweep's, whose
    parts stay for a resume), claimed as :class:`OutputFolder` claims a partial folder.

    On entering, the lock folder :data:`LOCK` is made inside ``folder`` with one atomic
    ``mkdir`` and the owner record is written into it; a lock of a live process is refused
    naming that process, a stale one (its process is gone: killed, or the machine stopped) is
    removed and taken. On leaving, the lock is removed.

    Parameters
    ----------
    folder : path
        An existing folder.
    command : str
        What writes it, for the message another writer gets (``"flexsat sweep"``).

    Raises
    ------
    OutputError
        The folder is being written by another live process (named), or the lock cannot be
        made (read-only, no permission).
    """

    def __init__(self, folder: str | os.PathLike, command: str = "flexsat"):
        self.folder = Path(folder)
        self.command = command
        self.lock = self.folder / LOCK

    def __enter__(self) -> Path:
        for _ in range(_TRIES):
            try:
                os.mkdir(self.lock)
                break
            except FileExistsError:
                state, record = _state(self.lock)
                if state == "stale":
                    _remove_stale(self.lock)
                    continue
                if state == "absent":
                    continue
                raise OutputError(f"{_shown(self.folder)}: another {_who(record, 'flexsat')} "
                                  "is writing this folder; wait for it to finish, or choose "
                                  "another --out")
            except OSError as exc:
                raise OutputError(f"{_shown(self.folder)}: cannot lock the folder for writing "
                                  f"({_why(exc)}); give another --out") from None
        else:
            raise OutputError(f"{_shown(self.folder)}: could not lock the folder (other "
                              "processes keep taking it); choose another --out")
        try:
            (self.lock / OWNER).write_text(json.dumps(_owner_record(self.command)),
                                           encoding="utf-8")
        except BaseException as exc:
            shutil.rmtree(self.lock, ignore_errors=True)
            if isinstance(exc, OSError):
                raise OutputError(f"{_shown(self.folder)}: cannot write the folder "
                                  f"({_why(exc)}); free some space or give another --out"
                                  ) from None
            raise
        return self.folder

    def __exit__(self, kind, exc, tb) -> bool:
        shutil.rmtree(self.lock, ignore_errors=True)
        return False


def output_folder(path: str | os.PathLike | None) -> OutputFolder:
    """An :class:`OutputFolder` for ``path`` (None: a new default folder); use it in ``with``."""
    return OutputFolder(path)
