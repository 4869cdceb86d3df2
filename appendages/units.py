"""Units of modal data files, and the conversion of modal data to SI.

Finite-element models are built in the units their authors chose (mm-t-s, in-lbf-s, m-kg-s):
a solver output carries no units, and a data file names its own. The readers
(:mod:`appendages.modal_file`, :mod:`appendages.nastran`) take the units by name from these
tables and convert with :func:`modal_data_to_si`; everything downstream is SI.

Time is the second in every system here (frequencies in rad/s or Hz).
"""

from __future__ import annotations

import math
import types

import numpy as np

from .errors import describe

__all__ = ["FREQUENCY_UNITS", "LENGTH_UNITS", "MASS_UNITS", "modal_data_to_si", "unit_factor"]

#: Metres per length unit.
LENGTH_UNITS = types.MappingProxyType({
    "m": 1.0, "mm": 1e-3, "cm": 1e-2, "km": 1e3, "in": 0.0254, "ft": 0.3048,
})

#: Kilograms per mass unit. ``t`` (tonne, the mass of mm-N-s models), ``slinch`` (lbf*s^2/in,
#: of in-lbf-s models: 0.45359237 kg * 9.80665 m/s^2 / 0.0254 m), ``slug`` (lbf*s^2/ft).
MASS_UNITS = types.MappingProxyType({
    "kg": 1.0, "g": 1e-3, "t": 1e3, "lbm": 0.45359237,
    "slinch": 0.45359237 * 9.80665 / 0.0254, "slug": 0.45359237 * 9.80665 / 0.3048,
})

#: rad/s per frequency unit.
FREQUENCY_UNITS = types.MappingProxyType({"rad/s": 1.0, "Hz": 2.0 * math.pi})

_TABLES = {"length": LENGTH_UNITS, "mass": MASS_UNITS, "frequency": FREQUENCY_UNITS}


def unit_factor(kind: str, name, where: str = "") -> float:
    """SI value of one ``name`` unit of ``kind`` ("length", "mass", "frequency").

    Raises
    ------
    ValueError
        An unknown unit name (the message lists the known ones; ``where`` prefixes it, e.g.
        the file and key).
    """
    table = _TABLES[kind]
    if not isinstance(name, str) or name not in table:
        raise ValueError(f"{where}{kind} unit must be one of {list(table)}; got "
                         f"{describe(name)}")
    return table[name]


def modal_data_to_si(frequencies, participation, rigid_mass, tip_motion=None, length=None, *,
                     length_unit: float, mass_unit: float, frequency_unit: float = 1.0):
    """Modal data in consistent file units -> SI (:class:`~appendages.ModalAppendage`'s units).

    Parameters
    ----------
    frequencies : array_like, (n,)
        In the frequency unit (``frequency_unit`` rad/s each).
    participation : array_like, (n, 2) or (n, 6)
        Translations in sqrt(mass), rotations in sqrt(mass)*length (the columns' kinds follow
        the root motions: planar (y, theta_z); three axes (x, y, z, theta_x, theta_y, theta_z)).
    rigid_mass : array_like, (2, 2) or (6, 6)
        mass, mass*length and mass*length**2 entries.
    tip_motion : array_like, (n,) or (n, 3), optional
        Deflections in length/sqrt(mass), the twist (three axes, last column) in
        rad/sqrt(mass).
    length : float, optional
        In the length unit.
    length_unit, mass_unit : float
        Metres and kilograms per file unit (:data:`LENGTH_UNITS`, :data:`MASS_UNITS`).
    frequency_unit : float
        rad/s per file unit.

    Returns
    -------
    tuple
        ``(frequencies, participation, rigid_mass, tip_motion, length)`` in SI as float arrays
        (tip_motion and length None when not given). Shapes are not checked here
        (:class:`~appendages.ModalAppendage` does).
    """
    w = np.asarray(frequencies, dtype=float) * frequency_unit
    G = np.asarray(participation, dtype=float)
    M = np.asarray(rigid_mass, dtype=float)
    r = M.shape[-1] if M.ndim == 2 else 0
    # 1 for a rotation coordinate, 0 for a translation
    rotation = np.array([0, 1] if r == 2 else [0, 0, 0, 1, 1, 1] if r == 6 else [0] * r)
    root_mass = math.sqrt(mass_unit)
    G_si = G * root_mass * length_unit ** rotation if G.ndim == 2 and G.shape[1] == r else G
    M_si = (M * mass_unit * length_unit ** (rotation[:, None] + rotation[None, :])
            if r else M)
    tip = None
    if tip_motion is not None:
        tip = np.asarray(tip_motion, dtype=float)
        if tip.ndim == 2 and tip.shape[1] == 3:
            tip = tip * np.array([length_unit, length_unit, 1.0]) / root_mass
        else:
            tip = tip * length_unit / root_mass
    return w, G_si, M_si, tip, None if length is None else float(length) * length_unit
