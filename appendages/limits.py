"""Limits on the work one call may do, and the one explicit way to raise them.

Every entry point of flexsat that can be asked for an unbounded amount of work estimates it
before doing any and refuses, at once and by name, a request beyond these limits, with a
:class:`LimitError` (a ``ValueError``) that names the parameter, the value asked for, the limit
and how to raise it. The limits are sized so that a request at a limit finishes in about a
minute or less on the project's reference machine (2 cores shared with other jobs, load
average 7 to 9 during the measurements of issue 9, BLAS threads as a user has them) and needs
well under 2 GiB; the measurements behind each are given beside it.

=================  =======  ===================================================================
name               default  what it bounds
=================  =======  ===================================================================
``modes``          1000     bending modes of a truncation (``Beam.truncated(n_modes)``): root
                            model and poles of an undamped 1000-mode beam 25-30 s; a damped
                            Craig-Bampton one also projects 4400 free-free modes on the
                            cantilever ones: 1.4 s for its root model since the overlaps are
                            closed forms (100 s by quadrature before issue 10; load 14); its
                            W(s) costs O(n) per frequency (400 modes, 1000 frequencies: 22 ms,
                            13 MB)
``bodies``         500      bodies of a :class:`~appendages.chain.HingedChain` (also through
                            ``HingedChain.rfem``, ``superelements``: 2 n + 1 bodies)
``fit_bodies``     14       bodies of ``fit_chain(match="poles-and-zeros")``: the range the fit
                            is benchmarked and tested on (3 to 14 bodies end within 0.02 % of
                            the modal bound, appendages.fitting; 15 and 16 measured there too,
                            at 3 and 4 s CPU). Cold fits, CPU medians of 5 at load 1.6-2.7:
                            0.04 s at 3 bodies, 0.95 s at 10, 2.5 s at 14, growing by at least
                            20 % per body; memoised 0.1 ms (benchmarks/results/fit.md)
``roots``          1e6      frequencies or zeros of a distributed beam asked at once
                            (``Beam.natural_frequencies(n)`` etc.: O(n), ~1 s and 40 MB at 1e6)
``frequencies``    100000   exact coupled frequencies asked of
                            ``Spacecraft.natural_frequencies(n, exact=True)`` (count and
                            secant, O(n) per appendage and step: 5.4 s on one rod, 32 s on
                            eight at 1e5, load 9-14)
``coordinates``    2500     generalised coordinates of an assembled hub + appendages model
                            (``Spacecraft.plant``, ``modes``: dense generalized eigen-
                            decomposition and modal projections, O(n**3); undamped plants:
                            17 s at 1003 coordinates, 52 s at 2003, 130 s at 3003)
``appendages``     100      mounts on one spacecraft
``points``         1e6      Laplace variables (frequencies) at which W(s) or a frequency
                            response is evaluated at once (~1 GiB of temporaries at 1e6)
``elements``       50e6     entries of an array whose size is the product of two requests
                            (``Beam.mode_shapes(x, n)``: 0.4 GiB of float64)
``segments``       1000     segments of a :class:`~appendages.stepped.SteppedBeam` (each
                            evaluation of its W(s) is O(segments) per frequency)
=================  =======  ===================================================================

Raising a limit
---------------
A user who really wants more says so explicitly, for a block of code::

    from appendages import limits
    with limits.raised(modes=5000):
        model = beam.truncated(5000)

:func:`raised` works on a :class:`contextvars.ContextVar`, so it applies to the current thread
(and asyncio task) only and is undone on leaving the block, also on an exception. A keyword on
every entry point (``max_modes=``) was rejected: it would have to be threaded through every
layer (scene -> spacecraft -> appendages) and every signature; a mutable module constant was
rejected: a change made by one part of a program (or by a test) would leak into every other.
"""

from __future__ import annotations

import contextlib
import contextvars
import math
import types
from collections.abc import Iterator

from .errors import FlexsatError, describe

__all__ = ["DEFAULTS", "LimitError", "check", "current", "raised"]

#: The documented limits (module docstring); read-only.
DEFAULTS = types.MappingProxyType({
    "modes": 1000,
    "bodies": 500,
    "fit_bodies": 14,
    "roots": 1_000_000,
    "frequencies": 100_000,
    "coordinates": 2500,
    "appendages": 100,
    "points": 1_000_000,
    "elements": 50_000_000,
    "segments": 1000,
})

_CURRENT: contextvars.ContextVar = contextvars.ContextVar("flexsat_limits", default=DEFAULTS)


class LimitError(FlexsatError, ValueError):
    """A request exceeds a documented work limit (:mod:`appendages.limits`).

    Attributes
    ----------
    parameter : str
        The parameter of the call that asked for the work (e.g. ``"n_modes"``).
    value : int or float
        What was asked for.
    limit_name : str
        The key of the limit (``"modes"``, ``"bodies"``...), the keyword of :func:`raised`.
    limit : int or float
        Its current value.
    """

    def __init__(self, parameter: str, value, limit_name: str, limit, what: str):
        self.parameter = parameter
        self.value = value
        self.limit_name = limit_name
        self.limit = limit
        super().__init__(
            f"{parameter} = {describe(value)} exceeds the limit of {limit:,} {what} "
            f"(appendages.limits: '{limit_name}'); ask for less, or raise the limit explicitly "
            f"with `with appendages.limits.raised({limit_name}=...)`")


def current(name: str):
    """The limit ``name`` in force (a key of :data:`DEFAULTS`)."""
    return _CURRENT.get()[name]


def check(parameter: str, value, limit_name: str, what: str) -> None:
    """Raise :class:`LimitError` if ``value`` exceeds the limit ``limit_name`` in force.

    Parameters
    ----------
    parameter : str
        The caller's parameter name, for the message.
    value : int or float
        The work asked for, in the units of the limit.
    limit_name : str
        A key of :data:`DEFAULTS`.
    what : str
        What is counted ("bending modes", "bodies"...), for the message.
    """
    limit = current(limit_name)
    if value > limit:
        raise LimitError(parameter, value, limit_name, limit, what)


@contextlib.contextmanager
def raised(**limits) -> Iterator[None]:
    """Raise (or lower) limits for the duration of a ``with`` block (module docstring).

    Parameters
    ----------
    **limits : int
        New values by name (keys of :data:`DEFAULTS`), positive integers; ``math.inf`` lifts a
        limit entirely.

    Raises
    ------
    TypeError
        For an unknown limit name or a value that is not a number.
    ValueError
        For a value that is not positive.
    """
    for name, value in limits.items():
        if name not in DEFAULTS:
            raise TypeError(f"unknown limit {name!r}; the limits are {', '.join(DEFAULTS)}")
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise TypeError(f"limit {name} must be a number; got {type(value).__name__}")
        if not (value > 0) or (isinstance(value, float) and math.isnan(value)):
            raise ValueError(f"limit {name} must be positive; got {value!r}")
    new = dict(_CURRENT.get())
    new.update(limits)
    token = _CURRENT.set(types.MappingProxyType(new))
    try:
        yield
    finally:
        _CURRENT.reset(token)
