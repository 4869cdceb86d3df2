"""Argument checks at the public boundary of the controllers package.

Every check raises at once with a message that names the parameter, its unit, what was expected
and what was got ("torque_limit must be positive and finite [N*m]; got -1"): TypeError for a
value that is not a real number (a string such as ``"5 arcsec"``, a bool, None where a number is
required), ValueError for a number outside its range.
"""
from __future__ import annotations

import math
import os
import sys

import numpy as np

__all__ = ["MESSAGE_VALUE_CHARS", "describe", "real_number", "positive", "non_negative",
           "optional_positive", "finite_vector", "real_array", "frequency_grid", "check_choice",
           "check_inertia", "user_stacklevel"]

#: Longest echo of a user's value in an error message [characters].
MESSAGE_VALUE_CHARS = 100


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


def real_array(value, name: str, unit: str) -> np.ndarray:
    """Real numbers (a number or a sequence of them) as a float64 array, or TypeError naming
    ``name`` (strings, None, complex numbers, bools and other objects are refused)."""
    if isinstance(value, (str, bytes, bool, np.bool_)) or value is None:
        raise TypeError(f"{name} must be real numbers [{unit}]; got {type(value).__name__} "
                        f"{describe(value)}")
    try:
        array = np.asarray(value)
    except (ValueError, TypeError):  # ragged nesting, objects numpy cannot hold
        array = np.asarray([object()], dtype=object)
    if array.dtype == bool or array.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be real numbers [{unit}]; got {type(value).__name__} "
                        f"{describe(value)}")
    with np.errstate(over="ignore"):
        return array.astype(float)


def frequency_grid(omega, name: str = "omega", *, minimum: int = 1) -> np.ndarray:
    """``omega`` as a 1-D float64 array of positive finite frequencies [rad/s], at least
    ``minimum`` of them; TypeError or ValueError naming ``name`` (the values are those a
    frequency response is evaluated at: from 1e-150 rad/s, where omega**2 stays a normal float)."""
    grid = real_array(omega, name, "rad/s").reshape(-1)
    if grid.size < minimum or not np.all(np.isfinite(grid)) or np.any(grid < 1e-150):
        raise ValueError(f"{name} must be positive finite frequencies [rad/s], at least "
                         f"{minimum} of them, each at least 1e-150 (its square stays a normal "
                         f"float); got {describe(grid)}")
    return grid


def check_choice(value, name: str, choices) -> str:
    """``value`` if it is one of the strings ``choices``, else TypeError (not a string) or
    ValueError naming ``name``."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be one of {tuple(choices)}; got {type(value).__name__} "
                        f"{describe(value)}")
    if value not in choices:
        raise ValueError(f"{name} must be one of {tuple(choices)}; got {describe(value)}")
    return value


def check_inertia(inertia, name: str = "inertia") -> np.ndarray:
    """A 3x3 inertia tensor [kg*m**2] of a body, as float64, symmetrised.

    Symmetric to 1e-9 of its largest entry, positive definite, finite, and its principal
    moments j1 <= j2 <= j3 obey the triangle inequality j3 <= j1 + j2 (to 1e-9 relative;
    equality is a flat plate): the checks of the hub's tensor in
    :func:`spacecraft.dynamics.kinematics.check_inertia_tensor`, kept here because controllers imports
    no other flexsat package.

    Raises
    ------
    TypeError
        Not real numbers.
    ValueError
        Not 3x3, not finite, not symmetric, not positive definite, or no body's (the message
        gives the principal moments).
    """
    J = real_array(inertia, name, "kg*m^2")
    if J.shape != (3, 3):
        raise ValueError(f"{name} must be a 3x3 tensor [kg*m^2]; got shape {J.shape}: "
                         f"{describe(inertia)}")
    if not np.all(np.isfinite(J)):
        raise ValueError(f"{name} must be finite [kg*m^2]; got {describe(J)}")
    scale = float(np.max(np.abs(J)))
    if np.max(np.abs(J - J.T)) > 1e-9 * scale:
        raise ValueError(f"{name} must be symmetric [kg*m^2] (to 1e-9 of its largest entry); "
                         f"got {describe(J)}")
    J = 0.5 * (J + J.T)
    moments = np.linalg.eigvalsh(J)
    if not moments[0] > 0.0:
        raise ValueError(f"{name} must be positive definite [kg*m^2]; got principal moments "
                         f"{describe(moments)}")
    if moments[2] > (moments[0] + moments[1]) * (1.0 + 1e-9):
        raise ValueError(f"{name} must be the inertia of a body [kg*m^2]: its largest principal "
                         f"moment at most the sum of the other two (triangle inequality); got "
                         f"principal moments {describe(moments)}")
    return J


def user_stacklevel() -> int:
    """The ``stacklevel`` that makes a warning point at the user's line.

    For a ``warnings.warn(..., stacklevel=user_stacklevel())`` in the function that calls this
    one: the number of frames from that function out to the first frame outside the controllers
    package, so that a warning raised deep inside a design (a discretisation that overflows, a
    mode left out of the loop's reach) names the line of the user's code that asked for it.
    """
    frame, level = sys._getframe(2), 2
    package = os.path.dirname(os.path.abspath(__file__))
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(package):
        frame, level = frame.f_back, level + 1
    return level
