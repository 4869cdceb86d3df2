"""Argument checks at the public boundary of the controllers package.

Every check raises at once with a message that names the parameter, its unit, what was expected
and what was got ("torque_limit must be positive and finite [N*m]; got -1"): TypeError for a
value that is not a real number (a string such as ``"5 arcsec"``, a bool, None where a number is
required), ValueError for a number outside its range.
"""
from __future__ import annotations

import math

import numpy as np

from .signals import MESSAGE_VALUE_CHARS

__all__ = ["describe", "real_number", "positive", "non_negative", "optional_positive",
           "finite_vector"]


def describe(value, limit: int = MESSAGE_VALUE_CHARS) -> str:
    """A user's value for an error message: short repr (floats to 6 digits), cut to ``limit``
    characters."""
    if isinstance(value, (float, np.floating)):
        text = f"{float(value):.6g}"
    else:
        try:
            with np.printoptions(threshold=20, edgeitems=3, precision=6):
                text = repr(value)
        except Exception:  # noqa: BLE001 - a repr that fails must not hide the real error
            text = f"<{type(value).__name__}>"
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def real_number(value, name: str, unit: str) -> float:
    """``value`` as a float if it is a real number (int, float, numpy scalar; not a bool, not a
    string), else TypeError naming ``name`` and its unit."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(
            value, (int, float, np.integer, np.floating)):
        hint = " (give the number in SI units, without a unit string)" if isinstance(
            value, str) else ""
        raise TypeError(f"{name} must be a real number [{unit}]{hint}; got "
                        f"{type(value).__name__} {describe(value)}")
    return float(value)


def positive(value, name: str, unit: str) -> float:
    """A positive finite real number, or an error naming ``name``."""
    x = real_number(value, name, unit)
    if not (math.isfinite(x) and x > 0.0):
        raise ValueError(f"{name} must be positive and finite [{unit}]; got {describe(value)}")
    return x


def non_negative(value, name: str, unit: str) -> float:
    """A non-negative finite real number, or an error naming ``name``."""
    x = real_number(value, name, unit)
    if not (math.isfinite(x) and x >= 0.0):
        raise ValueError(f"{name} must be non-negative and finite [{unit}]; got "
                         f"{describe(value)}")
    return x


def optional_positive(value, name: str, unit: str) -> float | None:
    """None (the quantity is absent or unlimited), or a positive finite real number."""
    return None if value is None else positive(value, name, unit)


def finite_vector(value, name: str, unit: str, length: int | None = None) -> np.ndarray:
    """A 1-D float64 array of finite real numbers (of ``length`` elements when given)."""
    try:
        array = np.asarray(value)
    except Exception as exc:  # noqa: BLE001 - ragged or exotic input: one clear error
        raise TypeError(f"{name} must be a sequence of real numbers [{unit}]; got "
                        f"{describe(value)}") from exc
    if array.dtype == bool or not (np.issubdtype(array.dtype, np.integer)
                                   or np.issubdtype(array.dtype, np.floating)):
        raise TypeError(f"{name} must be a sequence of real numbers [{unit}]; got "
                        f"{describe(value)}")
    array = array.astype(float)
    if array.ndim != 1 or (length is not None and array.size != length):
        shape = f"({length},)" if length is not None else "(n,)"
        raise ValueError(f"{name} must have shape {shape} [{unit}]; got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite [{unit}]; got {describe(value)}")
    return array
