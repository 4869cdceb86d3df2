"""The rigid hub and the mounts of appendages on it."""

from __future__ import annotations

import math

import numpy as np

from appendages.interface import RANGES, check_range, describe

__all__ = ["ANGLE_LIMIT", "Hub", "Mount", "POSITION_LIMIT"]


#: Largest |coordinate| of a mount position [m] (the upper length bound of RANGES).
POSITION_LIMIT = RANGES["length"][1]
#: Largest |direction| given as an angle [rad]: 1e6 rad carries a rounding of 1e-10 rad.
ANGLE_LIMIT = 1e6


def _is_real_scalar(value) -> bool:
    return (isinstance(value, (int, float, np.integer, np.floating))
            and not isinstance(value, (bool, np.bool_)))


def _real_vector(name: str, value, unit: str) -> np.ndarray:
    """Two finite real numbers as a float64 array, or TypeError/ValueError naming ``name``."""
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(f"{name} must be two real numbers [{unit}]; got "
                        f"{type(value).__name__} {describe(value)}")
    try:
        arr = np.asarray(value)
    except (ValueError, TypeError) as exc:  # ragged nesting, unconvertible objects
        raise TypeError(f"{name} must be two real numbers [{unit}]; got {describe(value)}") from exc
    if arr.ndim == 0:
        raise TypeError(f"{name} must be two real numbers [{unit}]; got "
                        f"{type(value).__name__} {describe(value)}")
    if isinstance(value, (list, tuple)) and any(isinstance(v, (bool, np.bool_)) for v in value):
        raise TypeError(f"{name} must be two real numbers [{unit}]; got a bool in "
                        f"{describe(value)}")
    if arr.dtype == bool or arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be two real numbers [{unit}]; got {describe(value)} "
                        f"(dtype {arr.dtype})")
    if arr.shape != (2,):
        raise ValueError(f"{name} must be two coordinates [{unit}]; got shape {arr.shape}: "
                         f"{describe(value)}")
    with np.errstate(over="ignore"):
        arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be two finite coordinates [{unit}]; got {describe(value)}")
    return arr


class Hub:
    """Rigid spacecraft hub in planar motion.

    Parameters
    ----------
    mass : float, kg
        Hub mass, 1e-15 to 1e15 kg.
    inertia : float, kg*m**2
        Moment of inertia about the hub's centre of mass, about +z, 1e-20 to 1e20 kg*m**2.

    Raises
    ------
    TypeError
        If a parameter is not a real number.
    ValueError
        If it is not finite, not positive or outside its documented range
        (:data:`appendages.interface.RANGES`, which also explains the bounds).
    """

    def __init__(self, mass: float, inertia: float):
        self.mass = check_range("hub mass", mass, "mass")
        self.inertia = check_range("hub inertia", inertia, "inertia")

    def __repr__(self) -> str:
        return f"Hub(mass={self.mass!r}, inertia={self.inertia!r})"


class Mount:
    """An appendage fixed to the hub at a point, pointing along a direction.

    Parameters
    ----------
    appendage : Appendage
        Any object with the W-matrix interface: ``length``, ``mass``, ``inertia`` and ``W(s)``;
        finite models also ``root_model()`` (see :mod:`appendages.interface`).
    position : (float, float), m
        Attachment point in hub axes, relative to the hub's centre of mass; each coordinate
        at most 1e6 m in magnitude (the length range of :data:`appendages.interface.RANGES`).
    direction : float or (float, float)
        The appendage's x axis in hub axes: an angle [rad] from the hub's x axis (at most
        1e6 rad in magnitude: beyond, a double cannot resolve the angle to 1e-10 rad), or a
        non-zero vector of two real numbers.
    name : str, optional
        Signal prefix (``<name>_tip_deflection``); default ``appendage<k>`` by position in the
        spacecraft's list.
    """

    def __init__(self, appendage, position=(0.0, 0.0), direction=0.0, *, name: str | None = None):
        for attribute in ("length", "mass", "inertia", "W"):
            if not hasattr(appendage, attribute):
                raise TypeError(
                    "appendage must offer the W-matrix interface (length, mass, inertia, W(s)); "
                    f"got {type(appendage).__name__} without '{attribute}'"
                )
        position = _real_vector("position", position, "m")
        if np.any(np.abs(position) > POSITION_LIMIT):
            raise ValueError(f"position must have coordinates of at most {POSITION_LIMIT:g} in "
                             f"magnitude [m]; got {describe(tuple(position))}")
        if _is_real_scalar(direction):
            angle = float(direction)
            if not math.isfinite(angle) or abs(angle) > ANGLE_LIMIT:
                raise ValueError(f"direction must be a finite angle of at most {ANGLE_LIMIT:g} "
                                 f"in magnitude [rad] or a 2-vector; got {describe(direction)}")
        elif isinstance(direction, (str, bytes, complex, np.complexfloating, bool, np.bool_)) \
                or direction is None:
            raise TypeError(f"direction must be an angle [rad] (a real number) or a 2-vector; "
                            f"got {type(direction).__name__} {describe(direction)}")
        else:
            d = _real_vector("direction", direction, "-")
            if np.hypot(*d) == 0.0:
                raise ValueError("direction must be an angle [rad] or a non-zero 2-vector; got "
                                 f"{describe(direction)}")
            angle = math.atan2(d[1], d[0])
        if name is not None and not isinstance(name, str):
            raise TypeError(f"mount name must be a string; got {type(name).__name__} "
                            f"{describe(name)}")
        if name is not None and not name.isidentifier():
            raise ValueError(f"mount name must be an identifier-like string; got {describe(name)}")
        self.appendage = appendage
        self.position = position
        self.angle = angle
        self.name = name

    @property
    def axis(self) -> np.ndarray:
        """Unit vector along the appendage (its x axis) in hub axes."""
        return np.array([math.cos(self.angle), math.sin(self.angle)])

    @property
    def normal(self) -> np.ndarray:
        """Unit vector of the appendage's y axis (deflection direction) in hub axes."""
        return np.array([-math.sin(self.angle), math.cos(self.angle)])

    def kinematics(self) -> np.ndarray:
        """Rows mapping hub motion (X, Y, theta) to (axial, delta, phi) of the attachment end.

        A small hub rotation theta moves the point p by theta * (z x p) = theta * (-p_y, p_x), so
        ``delta = n . (X, Y) + theta (p . e_x)``, ``axial = e_x . (X, Y) - theta (p . n)``
        and ``phi = theta``.
        """
        p, e, n = self.position, self.axis, self.normal
        return np.array([
            [e[0], e[1], -float(p @ n)],
            [n[0], n[1], float(p @ e)],
            [0.0, 0.0, 1.0],
        ])

    def __repr__(self) -> str:
        return (f"Mount({self.appendage!r}, position={tuple(self.position)}, "
                f"direction={self.angle!r}, name={self.name!r})")
