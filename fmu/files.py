"""Writing output files safely: all or nothing, never through a planted symlink.

A file is written to a new temporary file in the destination folder, created with
``O_CREAT | O_EXCL`` (which fails rather than follow any existing name, a symlink
included), and then renamed over the destination with :func:`os.replace`, which is atomic
and replaces a symlink at the destination itself rather than the file it points to. On any
error the temporary file is removed. A reader therefore sees the old file or the complete
new one, and no file outside the destination is ever written.

Text is always encoded as UTF-8, whatever the locale: modelDescription.xml declares
UTF-8, and the other files are read back by tools that assume it.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO

__all__ = ["write_atomically", "write_text_atomically"]


def _create_exclusive(folder: Path, stem: str) -> tuple[int, Path]:
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_NOFOLLOW", 0) \
        | getattr(os, "O_CLOEXEC", 0)
    for _ in range(100):
        candidate = folder / f".{stem}.{secrets.token_hex(6)}.tmp"
        try:
            # mode 0o666 as open() would use: the umask applies, as for any new file
            return os.open(candidate, flags, 0o666), candidate
        except FileExistsError:
            continue
    raise FileExistsError(f"could not create a temporary file in {folder}")


def write_atomically(path: Path, write: Callable[[BinaryIO], None]) -> Path:
    """Write ``path`` through ``write(handle)`` on a temporary file, then rename it.

    Parameters
    ----------
    path : pathlib.Path
        The destination; its folder must exist.
    write : callable
        Writes the content to the binary file object it is given.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    descriptor, temporary = _create_exclusive(path.parent, path.name)
    try:
        with os.fdopen(descriptor, "wb") as handle:
            write(handle)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    return path


def write_text_atomically(path: Path, text: str) -> Path:
    """Write ``text`` to ``path`` as UTF-8 (see :func:`write_atomically`)."""
    data = text.encode("utf-8")
    return write_atomically(path, lambda handle: handle.write(data))
