"""Checks of a user's arguments at the public boundary of the appendages package.

Every physical parameter has a documented range (:data:`RANGES`) and the Laplace variable one
of magnitudes (:data:`S_RANGE`) inside which flexsat's numerics have been shown sound; a value
beyond, or one that is not a real number, is refused by name with its unit, what was expected
and what was got ("length must be positive and finite [m]; got -1.0"): TypeError for a value
that is not a number, ValueError for one out of range, :class:`~appendages.limits.LimitError`
for a request of more work than the documented limits.
"""

from __future__ import annotations

import types

import numpy as np

from . import limits
from .errors import describe

__all__ = ["RANGES", "S_RANGE", "as_frequency_array", "check_derived", "check_positive",
           "check_range"]

#: Documented ranges of the physical parameters, SI: ``name -> (low, high, unit)``.
#:
#: Inside them every quantity that flexsat derives from the parameters (W(s) = L**3/EJ f(y),
#: the frequency scale ``c = sqrt(EJ/(rho*A L**4))``, the residual tails ``4/(m c**4) =
#: 4 rho*A L**7/EJ**2``, the mass matrices ``rho*A L**3``, ``m p**2``...) stays between about
#: 1e-100 and 1e100, far from the overflow and underflow of double precision (1e+-308), and the
#: eigen-solvers see problems made dimensionless by diagonal scaling
#: (:func:`appendages.interface.equilibrate`), so their accuracy depends on the dimensionless
#: groups only (mass ratios, offsets over lengths, damping), never on the units. Values beyond are refused by name (:func:`check_range`), not
#: because nothing could be computed there but because nothing there has been shown sound.
#: The bounds are wide: lengths from a micrometre to 1000 km, masses from 1e-15 kg (the
#: "massless hub" of the limiting-case tests) to 1e15 kg.
RANGES = types.MappingProxyType({
    "length": (1e-6, 1e6, "m"),                    # beam and body lengths, section sizes, |position|
    "bending_stiffness": (1e-15, 1e15, "N*m^2"),   # EJ
    "linear_density": (1e-12, 1e6, "kg/m"),        # rho*A
    "density": (1e-3, 1e5, "kg/m^3"),
    "youngs_modulus": (1e3, 1e13, "Pa"),
    "mass": (1e-15, 1e15, "kg"),                   # hub, rigid bodies
    "inertia": (1e-20, 1e20, "kg*m^2"),            # hub
    "body_inertia": (0.0, 1e20, "kg*m^2"),         # a chain's body (0: a point mass)
    "hinge_stiffness": (1e-15, 1e15, "N*m/rad"),
    "hinge_damping": (0.0, 1e15, "N*m*s/rad"),
    # three axes: GJ like EJ; rho*I_p = rho*A r**2 with r up to the length bound;
    # EA = E*A from the youngs_modulus and section ranges
    "torsional_stiffness": (1e-15, 1e15, "N*m^2"),  # GJ
    "torsional_inertia": (1e-30, 1e12, "kg*m"),     # rho*I_p per unit length
    "axial_stiffness": (1e-9, 1e20, "N"),           # EA
    "axial_spring": (1e-15, 1e20, "N/m"),           # a chain joint's axial spring
})


def _real(name: str, value, unit: str) -> float:
    """``value`` as a float; TypeError naming ``name`` and ``unit`` unless it is a real number."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(
            value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a real number [{unit}]; got {type(value).__name__} "
                        f"{describe(value)}")
    try:
        return float(value)
    except OverflowError:  # a Python int beyond the double range
        raise ValueError(f"{name} must be finite [{unit}]; got {describe(value)}") from None


def check_positive(name: str, value, unit: str, *, allow_zero: bool = False) -> float:
    """Return ``value`` as float after checking that it is a positive finite real number.

    Raises
    ------
    TypeError
        If ``value`` is not a real number.
    ValueError
        If it is not finite or not positive (or negative when ``allow_zero``).
    """
    value_f = _real(name, value, unit)
    ok = np.isfinite(value_f) and (value_f >= 0.0 if allow_zero else value_f > 0.0)
    if not ok:
        what = "non-negative" if allow_zero else "positive"
        raise ValueError(f"{name} must be {what} and finite [{unit}]; got {describe(value)}")
    return value_f


def check_range(name: str, value, quantity: str, *, allow_zero: bool = False) -> float:
    """Return ``value`` as float after checking it lies in the documented range of ``quantity``.

    Parameters
    ----------
    name : str
        The parameter's name, for the message.
    value : real
    quantity : str
        A key of :data:`RANGES` (gives the bounds and the unit).
    allow_zero : bool
        Also accept exactly 0 (a point mass's inertia, an undamped hinge).

    Raises
    ------
    TypeError
        If ``value`` is not a real number.
    ValueError
        If it is not finite or lies outside the range (the message gives the range).
    """
    low, high, unit = RANGES[quantity]
    value_f = check_positive(name, value, unit, allow_zero=allow_zero)
    if (allow_zero and value_f == 0.0) or low <= value_f <= high:
        return value_f
    raise ValueError(
        f"{name} must lie in [{low:g}, {high:g}] [{unit}]{' or be 0' if allow_zero else ''}, "
        f"the range where flexsat's numerics are sound (appendages.checks.RANGES); "
        f"got {describe(value)}")


def check_derived(value: float, quantity: str, formula: str, given) -> float:
    """Check a value derived from the user's parameters; blame those parameters if it is out.

    Parameters
    ----------
    value : float
        The derived value (e.g. ``E pi d**4/64``, possibly 0 or inf after underflow/overflow).
    quantity : str
        Its key in :data:`RANGES` (e.g. ``"bending_stiffness"``).
    formula : str
        How it was derived, for the message (``"youngs_modulus*pi*diameter**4/64"``).
    given : sequence of (name, value, unit)
        The parameters it came from, as the user gave them.

    Raises
    ------
    ValueError
        Naming every parameter of ``given`` with its value and unit, the derived value and
        its range.
    """
    low, high, unit = RANGES[quantity]
    if np.isfinite(value) and low <= value <= high:
        return float(value)
    names = " and ".join(f"{name} = {describe(v)} {u}" for name, v, u in given)
    raise ValueError(
        f"{names} give {quantity} = {formula} = {value:.3g} {unit}, outside the range "
        f"[{low:g}, {high:g}] {unit} where flexsat's numerics are sound "
        f"(appendages.checks.RANGES); change {' or '.join(n for n, _, _ in given)}")


#: Smallest and largest |s| [rad/s] at which W(s) is evaluated (s = 0 aside, the rigid-body
#: pole). W ~ 1/(m s**2) near 0 and the mass matrices times s**2 grow like s**2: with the
#: parameters in RANGES, 1e-80 <= |s| <= 1e80 keeps every intermediate below 1e300.
S_RANGE = (1e-80, 1e80)


def as_frequency_array(s) -> np.ndarray:
    """Return the Laplace variable ``s`` [rad/s] as a complex128 array, checking its type.

    Raises
    ------
    TypeError
        Not a number or an array of numbers.
    ValueError
        A NaN or infinite value, or a non-zero magnitude outside :data:`S_RANGE`.
    """
    if isinstance(s, (str, bytes)) or s is None:
        raise TypeError(f"s must be a complex number or array of them [rad/s]; got {type(s).__name__}")
    try:
        arr = np.asarray(s)
    except Exception as exc:  # pragma: no cover - numpy raises many kinds here
        raise TypeError(f"s must be a complex number or array of them [rad/s]; got {describe(s)}") from exc
    if arr.dtype.kind not in "biufc":
        raise TypeError(f"s must be a complex number or array of them [rad/s]; got dtype {arr.dtype}")
    limits.check("s (number of points)", arr.size, "points", "points at once")
    arr = arr.astype(np.complex128)
    magnitude = np.abs(arr)
    # one pass for the common case: NaN fails every comparison, inf the upper bound
    if (((magnitude >= S_RANGE[0]) & (magnitude <= S_RANGE[1])) | (magnitude == 0)).all():
        return arr
    if not np.all(np.isfinite(arr)):
        raise ValueError("s must be finite [rad/s]; got a NaN or infinite value")
    outside = (magnitude != 0) & ((magnitude < S_RANGE[0]) | (magnitude > S_RANGE[1]))
    if np.any(outside):
        raise ValueError(
            f"s must have a magnitude between {S_RANGE[0]:g} and {S_RANGE[1]:g} [rad/s] "
            f"(appendages.checks.S_RANGE: beyond, W(s) leaves double precision); got "
            f"{describe(arr[outside][0])}")
    return arr
