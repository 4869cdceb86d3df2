"""SI units of exported variables: the units the FMU knows and a guess from signal names.

FMI 2.0 declares each unit once in ``<UnitDefinitions>`` with its exponents of the SI base
units (kg, m, s, A, K, mol, cd) and rad; variables then refer to it by name.  Unit names
follow the FMI/Modelica convention: ``.`` multiplies, ``/`` divides, a trailing digit is an
exponent (``N.m``, ``rad/s2``).

References
----------
FMI 2.0.1 standard, section 2.2.2 "Definition of Units (UnitDefinitions)".
"""

from __future__ import annotations

import re
from collections.abc import Mapping

from .checks import shorten

__all__ = ["SI_UNITS", "guess_unit", "derivative_unit", "resolve_units"]

#: Known units and their exponents of the base units (rad counted as a base unit, as FMI
#: allows, so that angles and angular rates are distinguishable).
SI_UNITS: dict[str, dict[str, int]] = {
    "rad": {"rad": 1},
    "rad/s": {"rad": 1, "s": -1},
    "rad/s2": {"rad": 1, "s": -2},
    "rad/s3": {"rad": 1, "s": -3},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "m/s3": {"m": 1, "s": -3},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/s": {"kg": 1, "m": 1, "s": -3},
    "N.s": {"kg": 1, "m": 1, "s": -1},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "N.m/s": {"kg": 1, "m": 2, "s": -3},
    "N.m.s": {"kg": 1, "m": 2, "s": -1},
    "N.m/rad": {"kg": 1, "m": 2, "s": -2, "rad": -1},
    "N/m": {"kg": 1, "s": -2},
    "kg": {"kg": 1},
    "kg.m2": {"kg": 1, "m": 2},
    "s": {"s": 1},
    "1/s": {"s": -1},
}

_TIME_DERIVATIVE = {
    "rad": "rad/s", "rad/s": "rad/s2", "rad/s2": "rad/s3",
    "m": "m/s", "m/s": "m/s2", "m/s2": "m/s3",
    "N": "N/s", "N.m": "N.m/s", "N.m.s": "N.m", "N.s": "N", "s": None,
}

# Word -> unit, matched against the parts of a signal name split at "_", ".", "[" ...
# Matching is case-insensitive except for the one-letter symbols below.
_WORD_UNITS = {
    "theta": "rad", "phi": "rad", "psi": "rad", "angle": "rad", "attitude": "rad",
    "twist": "rad",
    "omega": "rad/s", "rate": "rad/s",
    "alpha": "rad/s2",
    "torque": "N.m", "tau": "N.m", "moment": "N.m",
    "force": "N",
    "delta": "m", "deflection": "m", "displacement": "m", "position": "m",
    "velocity": "m/s", "speed": "m/s",
}
_SYMBOL_UNITS = {"M": "N.m", "F": "N", "w": "m"}


def guess_unit(name: str) -> str | None:
    """Guess the SI unit of a signal from its name.

    The name is split into words at non-alphanumeric characters and at camelCase
    boundaries; the first word with a known meaning decides. A trailing word ``dot``
    (``theta_dot``) takes one time derivative. Words that qualify without changing the
    unit (``ref``, ``cmd``, ``error``, ``tip``...) are simply not matched.

    Parameters
    ----------
    name : str
        Signal name, e.g. ``"theta"``, ``"theta_ref"``, ``"F_y"``, ``"M"``, ``"omega"``.

    Returns
    -------
    str or None
        A key of :data:`SI_UNITS`, or None when nothing is known about the name.

    Examples
    --------
    >>> guess_unit("theta_ref"), guess_unit("omega"), guess_unit("M"), guess_unit("F_y")
    ('rad', 'rad/s', 'N.m', 'N')
    """
    if not isinstance(name, str):
        raise TypeError(f"name must be a signal name (str); got {type(name).__name__}")
    words = [w for w in re.split(r"[^A-Za-z0-9]+|(?<=[a-z])(?=[A-Z])", name) if w]
    unit = None
    for word in words:
        if word in _SYMBOL_UNITS:
            unit = _SYMBOL_UNITS[word]
            break
        unit = _WORD_UNITS.get(word.lower())
        if unit is not None:
            break
    if unit is not None and any(w.lower() == "dot" for w in words):
        unit = _TIME_DERIVATIVE.get(unit)
    return unit


def derivative_unit(unit: str | None) -> str | None:
    """Unit of the time derivative of a quantity in ``unit`` (None if not in the table)."""
    if unit is None:
        return None
    return _TIME_DERIVATIVE.get(unit)


def resolve_units(names: list[str], overrides: Mapping[str, str | None] | None) -> dict[str, str | None]:
    """Units of all signals: guessed from names, replaced by the user's overrides.

    Parameters
    ----------
    names : list of str
        Every input, output and state name of the system.
    overrides : mapping of str to str or None, optional
        ``{name: unit}``; a unit of None removes the guessed unit.

    Returns
    -------
    dict of str to str or None

    Raises
    ------
    ValueError
        If an override names no signal of the system or gives a unit not in
        :data:`SI_UNITS`.
    """
    units = {name: guess_unit(name) for name in names}
    if overrides is None:
        return units
    if not isinstance(overrides, Mapping):
        raise TypeError(f"units must be a mapping {{signal name: unit}}; got "
                        f"{type(overrides).__name__} {shorten(overrides)}")
    for name, unit in overrides.items():
        if not isinstance(name, str) or name not in units:
            raise ValueError(f"units names the signal {shorten(name)}, which the system does "
                             f"not have; expected one of {shorten(sorted(units))}")
        if unit is not None and (not isinstance(unit, str) or unit not in SI_UNITS):
            raise ValueError(f"units[{shorten(name)}] must be one of {sorted(SI_UNITS)} or None; "
                             f"got {shorten(unit)}")
        units[name] = unit
    return units
