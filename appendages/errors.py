"""The appendages package's errors and the one way its messages show a user's value.

Every error flexsat raises on purpose derives from :class:`FlexsatError` (the other packages
build on it: ``LimitError`` in :mod:`appendages.limits`, the scene and run errors of
``spacecraft``); a numerical procedure that did not converge raises :class:`ConvergenceError`.
A message names the parameter, its unit, what was expected and what was got; the value got is
shown by :func:`describe`, so that a message stays one readable line whatever was passed.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FlexsatError", "ConvergenceError", "MESSAGE_VALUE_WIDTH", "describe"]

#: Longest text of a value echoed in an error message (characters).
MESSAGE_VALUE_WIDTH = 100


class FlexsatError(Exception):
    """Base class of flexsat's own errors."""


class ConvergenceError(FlexsatError, RuntimeError):
    """A numerical procedure (root search, fit) did not converge."""


def describe(value, width: int = MESSAGE_VALUE_WIDTH) -> str:
    """``repr(value)`` shortened to about ``width`` characters, for error messages.

    A long value (a 200,000-element array, a huge string) is cut in the middle and its length
    is said, so that a message stays one readable line.
    """
    if isinstance(value, np.ndarray) and value.size > 20:
        text = np.array2string(value.ravel()[:6], separator=", ", threshold=6)[:-1]
        return f"array of shape {value.shape} ({text}, ...])"
    try:
        text = repr(value)
    except Exception:  # a broken __repr__ must not hide the real error
        text = f"<{type(value).__name__}>"
    if len(text) <= width:
        return text
    keep = max(width - 30, 10)
    return f"{text[: keep // 2 + keep % 2]}...{text[-(keep // 2):]} ({len(text):,} characters)"
