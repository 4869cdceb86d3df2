r"""A plain file format for finite-element modal data (TOML), read and written.

The format carries what :class:`~appendages.ModalAppendage` needs, with its units in the file::

    format = "flexsat-modal-appendage"
    version = 1

    [units]                       # all three required
    length = "m"                  # m, mm, cm, km, in, ft
    mass = "kg"                   # kg, g, t, lbm, slinch (lbf*s^2/in), slug (lbf*s^2/ft)
    frequency = "rad/s"           # rad/s or Hz

    [appendage]
    length = 7.0                  # optional: extent along x from the root [length]
    frequencies = [3.74, 20.4]    # cantilever (root clamped) modes, non-decreasing [frequency]
    damping = 0.005               # optional: one ratio, or one per mode [-]
    # rigid mass about the root, appendage axes: 2x2 (y, rotation z) or 6x6 (x, y, z,
    # rotations about x, y, z) [mass, mass*length, mass*length^2]
    rigid_mass = [[25.0, 94.5], [94.5, 513.9]]
    # participation factors of the mass-normalised modes, one row per mode, one column per
    # root motion [sqrt(mass), sqrt(mass)*length]
    participation = [[3.52, 21.6], [1.9, 3.1]]
    # optional: each mode's elastic tip motion, (n,) planar or (n, 3) three axes (deflection
    # along y, along z, twist) [length/sqrt(mass), rad/sqrt(mass)]
    tip_motion = [0.41, -0.39]

Every key is checked: an unknown key is an error, not ignored. :func:`write_modal_data` writes
an appendage in this format in SI units, with every number's shortest repr, so that reading it
back gives the same floats.

References
----------
.. [1] TOML v1.0.0, https://toml.io/en/v1.0.0 (Python's ``tomllib``).
"""

from __future__ import annotations

import math
import os
import tomllib

import numpy as np

from .errors import describe
from .modal_data import ModalAppendage
from .units import modal_data_to_si, unit_factor

__all__ = ["FORMAT", "VERSION", "ModalFileError", "read_modal_data", "write_modal_data"]

FORMAT = "flexsat-modal-appendage"
VERSION = 1

_TOP_KEYS = {"format", "version", "units", "appendage"}
_UNIT_KEYS = ("length", "mass", "frequency")
_APPENDAGE_KEYS = {"length", "frequencies", "damping", "rigid_mass", "participation",
                   "tip_motion"}


class ModalFileError(ValueError):
    """A modal data file that cannot be read as this format (the message names file and key)."""



def read_modal_data(path) -> ModalAppendage:
    """Read a :class:`~appendages.ModalAppendage` from a modal data file (module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        A TOML file in this format.

    Returns
    -------
    ModalAppendage
        In SI units.

    Raises
    ------
    ModalFileError
        The file is not TOML, not this format or version, misses a required key or has an
        unknown one, or names an unknown unit (the message names the file and the key).
    OSError
        The file cannot be opened.
    ValueError, TypeError
        The data themselves are refused by :class:`~appendages.ModalAppendage` (the message is
        prefixed with the file's name).
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a file path (str or os.PathLike); got "
                        f"{type(path).__name__}")
    name = os.fspath(path)
    if not os.path.isfile(name):
        raise FileNotFoundError(f"path must be an existing modal data file; got {name!r:.200}")
    with open(name, "rb") as handle:
        try:
            document = tomllib.load(handle)
        except tomllib.TOMLDecodeError as exc:
            raise ModalFileError(f"{name}: not a TOML file ({exc})") from None
    where = f"{name}: "
    unknown = sorted(set(document) - _TOP_KEYS)
    if unknown:
        raise ModalFileError(f"{where}unknown key(s) {unknown}; expected {sorted(_TOP_KEYS)}")
    if document.get("format") != FORMAT:
        raise ModalFileError(f"{where}format must be {FORMAT!r} (a flexsat modal data file); "
                             f"got {describe(document.get('format'))}")
    if document.get("version") != VERSION:
        raise ModalFileError(f"{where}version must be {VERSION}; got "
                             f"{describe(document.get('version'))}")
    units = document.get("units")
    if not isinstance(units, dict):
        raise ModalFileError(f"{where}a [units] table with length, mass and frequency is "
                             f"required (the file's units); got {describe(units)}")
    unknown = sorted(set(units) - set(_UNIT_KEYS))
    missing = [k for k in _UNIT_KEYS if k not in units]
    if unknown or missing:
        raise ModalFileError(f"{where}[units] must give exactly {list(_UNIT_KEYS)}; missing "
                             f"{missing}, unknown {unknown}")
    try:
        factors = {k: unit_factor(k, units[k], f"{where}units.") for k in _UNIT_KEYS}
    except ValueError as exc:
        raise ModalFileError(str(exc)) from None
    data = document.get("appendage")
    if not isinstance(data, dict):
        raise ModalFileError(f"{where}an [appendage] table is required; got {describe(data)}")
    unknown = sorted(set(data) - _APPENDAGE_KEYS)
    if unknown:
        raise ModalFileError(f"{where}unknown key(s) {unknown} in [appendage]; expected "
                             f"{sorted(_APPENDAGE_KEYS)}")
    missing = [k for k in ("frequencies", "rigid_mass", "participation") if k not in data]
    if missing:
        raise ModalFileError(f"{where}[appendage] misses {missing}")
    try:
        arrays = [np.asarray(data[k], dtype=float) if k in data else None
                  for k in ("frequencies", "participation", "rigid_mass", "tip_motion")]
        length = data.get("length")
        if length is not None and (isinstance(length, bool) or
                                   not isinstance(length, (int, float))):
            raise TypeError(f"length must be a number [{units['length']}]; got "
                            f"{describe(length)}")
    except (TypeError, ValueError) as exc:
        raise ModalFileError(f"{where}[appendage] holds a value that is not a number or a "
                             f"rectangular array of numbers: {exc}") from None
    w, G, M, tip, length_si = modal_data_to_si(
        *arrays, length, length_unit=factors["length"], mass_unit=factors["mass"],
        frequency_unit=factors["frequency"])
    try:
        return ModalAppendage(w, G, M, damping=data.get("damping", 0.0), length=length_si,
                              tip_motion=tip)
    except (TypeError, ValueError) as exc:
        raise type(exc)(f"{where}{exc} (after conversion to SI from the file's units "
                        f"{units})") from None


def _number(value: float) -> str:
    value = float(value)
    if not math.isfinite(value):  # pragma: no cover - a ModalAppendage holds finite data
        raise ValueError(f"cannot write a non-finite number {value!r}")
    return repr(value)


def _array(values) -> str:
    arr = np.asarray(values, dtype=float)
    if arr.ndim == 1:
        return "[" + ", ".join(_number(v) for v in arr) + "]"
    rows = ",\n    ".join(_array(row) for row in arr)
    return "[\n    " + rows + ",\n]"


def write_modal_data(appendage: ModalAppendage, path) -> None:
    """Write ``appendage`` to ``path`` in this format, SI units (module docstring).

    Reading the file back (:func:`read_modal_data`) gives the same data bit for bit.
    """
    if not isinstance(appendage, ModalAppendage):
        raise TypeError(f"appendage must be a ModalAppendage; got {type(appendage).__name__}")
    lines = [f'format = "{FORMAT}"', f"version = {VERSION}", "",
             "[units]", 'length = "m"', 'mass = "kg"', 'frequency = "rad/s"', "",
             "[appendage]"]
    try:
        lines.append(f"length = {_number(appendage.length)}")
    except ValueError:
        pass  # no length given
    damping = appendage.damping_ratios
    lines.append("damping = " + (_number(damping[0]) if np.all(damping == damping[0])
                                 else _array(damping)))
    lines.append("frequencies = " + _array(appendage.frequencies))
    lines.append("rigid_mass = " + _array(appendage.rigid_mass))
    lines.append("participation = " + _array(appendage.participation))
    if appendage.tip_motion is not None:
        lines.append("tip_motion = " + _array(appendage.tip_motion))
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a file path (str or os.PathLike); got "
                        f"{type(path).__name__}")
    with open(os.fspath(path), "w", encoding="utf-8") as handle:
        handle.write("\n".join(lines) + "\n")
