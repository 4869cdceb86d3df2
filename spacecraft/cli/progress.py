"""Progress lines of the ``flexsat`` commands on stderr: ``[  1.2 s] stage...``."""

from __future__ import annotations

import sys
import time

__all__ = ["Progress"]


class Progress:
    """Progress lines on stderr: '[  1.2 s] stage...'."""

    def __init__(self, quiet: bool):
        self.quiet = quiet
        self.t0 = time.perf_counter()

    def __call__(self, message: str) -> None:
        if not self.quiet:
            try:
                print(f"[{time.perf_counter() - self.t0:6.1f} s] {message}...",
                      file=sys.stderr, flush=True)
            except (BrokenPipeError, ValueError):
                # stderr closed (piped into head, or a closed file): the run goes on silently
                self.quiet = True
