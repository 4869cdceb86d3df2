"""Whether Basilisk is installed, which version, and the adapter's own errors.

Basilisk (PyPI package ``bsk``) is an optional dependency, the extra ``flexsat[basilisk]``:
nothing in flexsat imports it until a Basilisk function is called, and a missing install is
one :class:`BasiliskNotInstalled` error whose message says how to install it.
"""

from __future__ import annotations

import importlib.metadata
import re
import warnings

from appendages.interface import FlexsatError

__all__ = [
    "BasiliskNotInstalled",
    "BasiliskModelError",
    "BasiliskRunTooLong",
    "BasiliskIntegrationError",
    "BasiliskVersionWarning",
    "BasiliskModelWarning",
    "INSTALL_HINT",
    "TESTED_VERSIONS",
    "require_basilisk",
]

#: The ``bsk`` releases this adapter is tested with (pyproject's ``basilisk`` extra pins them).
TESTED_VERSIONS = ">=2.12.1,<2.13"
_TESTED_LOW, _TESTED_HIGH = (2, 12, 1), (2, 13)

#: The one line a user without Basilisk sees.
INSTALL_HINT = ("Basilisk is not installed; install flexsat's Basilisk extra: "
                f"pip install 'flexsat[basilisk]' (bsk {TESTED_VERSIONS})")


class BasiliskNotInstalled(FlexsatError, ImportError):
    """Basilisk (PyPI package ``bsk``) is not installed; the message says how to install it."""


class BasiliskModelError(FlexsatError, ValueError):
    """A spacecraft, chain or controller that the Basilisk model cannot represent."""


class BasiliskRunTooLong(BasiliskModelError):
    """A run whose estimated wall time exceeds its limit (``max_seconds``).

    Attributes
    ----------
    work : str
        What the run would cost (seconds, bodies, RK4 steps), for a message of the caller's.
    estimate, limit : float, s
        The estimated wall time and the limit it exceeds.
    highest_frequency : float, rad/s
        The highest mode the RK4 step was sized from (0: none given).
    step : float, s
        The RK4 step of the run (0: none given).
    """

    def __init__(self, message: str, *, work: str, estimate: float, limit: float,
                 highest_frequency: float = 0.0, step: float = 0.0):
        super().__init__(message)
        self.work, self.estimate, self.limit = work, estimate, limit
        self.highest_frequency, self.step = highest_frequency, step


class BasiliskIntegrationError(FlexsatError, ArithmeticError):
    """Basilisk's integration produced non-finite states (e.g. an unstable step size)."""


class BasiliskModelWarning(UserWarning):
    """The Basilisk model differs from the chain given (in a way the message names), and so
    does the linear chain it is compared with."""


class BasiliskVersionWarning(UserWarning):
    """The installed ``bsk`` is outside the tested range :data:`TESTED_VERSIONS`."""


def _release(version: str) -> tuple[int, ...]:
    """Leading numeric release of a version string ('2.12.1rc1' -> (2, 12, 1))."""
    match = re.match(r"\d+(\.\d+)*", version)
    return tuple(int(p) for p in match.group(0).split(".")) if match else ()


def require_basilisk() -> str:
    """Check that Basilisk is importable; return the installed ``bsk`` version.

    Returns
    -------
    str
        The version of the ``bsk`` distribution (e.g. ``'2.12.1'``).

    Raises
    ------
    BasiliskNotInstalled
        With :data:`INSTALL_HINT` as its message.

    Warns
    -----
    BasiliskVersionWarning
        When the version is outside :data:`TESTED_VERSIONS` (the adapter may still work).
    """
    try:
        import Basilisk  # noqa: F401
        version = importlib.metadata.version("bsk")
    except (ImportError, importlib.metadata.PackageNotFoundError):
        raise BasiliskNotInstalled(INSTALL_HINT) from None
    release = _release(version)
    if not (_TESTED_LOW <= release < _TESTED_HIGH):
        warnings.warn(f"bsk {version} is outside the tested range {TESTED_VERSIONS}; "
                      "results are not verified for it", BasiliskVersionWarning, stacklevel=2)
    return version
