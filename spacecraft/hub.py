"""The rigid hub and the mounts of appendages on it."""

from __future__ import annotations

import math

import numpy as np

from appendages.interface import check_positive

__all__ = ["Hub", "Mount"]


class Hub:
    """Rigid spacecraft hub in planar motion.

    Parameters
    ----------
    mass : float, kg
        Hub mass.
    inertia : float, kg*m**2
        Moment of inertia about the hub's centre of mass, about +z.
    """

    def __init__(self, mass: float, inertia: float):
        self.mass = check_positive("hub mass", mass, "kg")
        self.inertia = check_positive("hub inertia", inertia, "kg*m^2")

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
        Attachment point in hub axes, relative to the hub's centre of mass.
    direction : float or (float, float)
        The appendage's x axis in hub axes: an angle [rad] from the hub's x axis, or a vector.
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
        position = np.asarray(position, dtype=float)
        if position.shape != (2,) or not np.all(np.isfinite(position)):
            raise ValueError(f"position must be two finite coordinates [m]; got {position!r}")
        if np.ndim(direction) == 0:
            angle = float(direction)
            if not math.isfinite(angle):
                raise ValueError(f"direction must be a finite angle [rad]; got {direction!r}")
        else:
            d = np.asarray(direction, dtype=float)
            if d.shape != (2,) or not np.all(np.isfinite(d)) or np.hypot(*d) == 0.0:
                raise ValueError(f"direction must be an angle [rad] or a non-zero 2-vector; got {direction!r}")
            angle = math.atan2(d[1], d[0])
        if name is not None and (not isinstance(name, str) or not name.isidentifier()):
            raise ValueError(f"mount name must be an identifier-like string; got {name!r}")
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
