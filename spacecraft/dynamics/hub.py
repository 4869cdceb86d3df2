"""The rigid hub and the mounts of appendages on it, planar or in three axes."""

from __future__ import annotations

import math

import numpy as np

from appendages.interface import RANGES, check_range, describe
from appendages.unit_slips import warn_angle_in_degrees

from .kinematics import (check_inertia_tensor, check_rotation, mount_transformation,
                         planar_orientation, real_vector3)

__all__ = ["ANGLE_LIMIT", "Hub", "Mount", "POSITION_LIMIT"]


#: Largest |coordinate| of a mount position [m] (the upper length bound of RANGES).
POSITION_LIMIT = RANGES["length"][1]
#: Largest |direction| given as an angle [rad]: 1e6 rad carries a rounding of 1e-10 rad.
ANGLE_LIMIT = 1e6


class _Unset:
    """The default of Mount's direction: 0 rad for a planar mount, absent with orientation."""

    def __repr__(self) -> str:
        return "0.0"


_UNSET = _Unset()


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
    """Rigid spacecraft hub, planar or three-axis.

    Parameters
    ----------
    mass : float, kg
        Hub mass, 1e-15 to 1e15 kg.
    inertia : float or (3, 3) array, kg*m**2
        A float: the moment of inertia about the hub's centre of mass about +z, 1e-20 to
        1e20 kg*m**2 (the planar hub). A 3x3 symmetric positive-definite tensor about the
        hub's centre of mass in hub axes: the spacecraft is three-axis (principal moments in
        the same range; symmetric to 1e-9 of its largest entry, then symmetrised).

    Attributes
    ----------
    mass : float
    inertia : float or ndarray (3, 3)
        As given (the tensor symmetrised).
    three_axis : bool

    Raises
    ------
    TypeError
        If a parameter is not a real number (or a real 3x3 array).
    ValueError
        If it is not finite, not positive or outside its documented range
        (:data:`appendages.interface.RANGES`, which also explains the bounds); a tensor that
        is not symmetric or not positive definite (the message gives its asymmetry or its
        principal moments).
    """

    def __init__(self, mass: float, inertia):
        self.mass = check_range("hub mass", mass, "mass")
        try:
            scalar = np.ndim(inertia) == 0 or isinstance(inertia, (str, bytes))
        except (ValueError, TypeError):  # ragged nesting: the tensor check names it
            scalar = False
        if scalar:
            self.inertia = check_range("hub inertia", inertia, "inertia")
            self.three_axis = False
        else:
            self.inertia = check_inertia_tensor("hub inertia", inertia)
            self.inertia.flags.writeable = False
            self.three_axis = True

    @property
    def mass_matrix(self) -> np.ndarray:
        """The hub's rigid mass matrix in its coordinates: diag(m, m, J) (planar, X, Y,
        theta) or [[m I, 0], [0, J]] (three axes, translations then rotations)."""
        if not self.three_axis:
            return np.diag([self.mass, self.mass, self.inertia])
        M = np.zeros((6, 6))
        M[:3, :3] = self.mass * np.eye(3)
        M[3:, 3:] = self.inertia
        return M

    def __repr__(self) -> str:
        inertia = self.inertia.tolist() if self.three_axis else self.inertia
        return f"Hub(mass={self.mass!r}, inertia={inertia!r})"


class Mount:
    """An appendage fixed to the hub at a point, planar or in three axes.

    Parameters
    ----------
    appendage : Appendage
        Any object with the W-matrix interface: ``length``, ``mass``, ``inertia`` and ``W(s)``;
        finite models also ``root_model()`` (see :mod:`appendages.interface`). A three-axis
        mount also needs ``W6(s)`` and ``inertia_tensor`` (the beam's torsion): a planar
        appendage is refused by name.
    position : (float, float) or (float, float, float), m
        Attachment point in hub axes, relative to the hub's centre of mass: two coordinates
        for a planar mount, three with ``orientation``; each at most 1e6 m in magnitude (the
        length range of :data:`appendages.interface.RANGES`).
    direction : float or (float, float), optional
        Planar mounts: the appendage's x axis in hub axes, an angle [rad] from the hub's x
        axis (at most 1e6 rad in magnitude: beyond, a double cannot resolve the angle to
        1e-10 rad), or a non-zero vector of two real numbers; default 0. Radians, as
        everywhere in the Python API (a scene file gives degrees): an angle of more than a
        turn (|direction| > 2 pi) is warned about (:class:`appendages.unit_slips.UnitWarning`), as
        it is more likely degrees.
    orientation : (3, 3) array, optional
        Three-axis mounts: a rotation matrix whose columns are the appendage's local x, y, z
        axes in hub axes (orthonormal to 1e-9, det +1; helpers in
        :mod:`spacecraft.dynamics.kinematics`: ``euler_orientation``, ``orientation_from_axis``).
    name : str, optional
        Signal prefix (``<name>_tip_deflection``); default ``appendage<k>`` by position in the
        spacecraft's list.

    Notes
    -----
    A planar mount on a three-axis hub lies in the hub's x-y plane: ``position (x, y, 0)``,
    ``orientation R_z(direction)``.
    """

    def __init__(self, appendage, position=(0.0, 0.0), direction=_UNSET, *, orientation=None,
                 name: str | None = None):
        for attribute in ("length", "mass", "inertia", "W"):
            if not hasattr(appendage, attribute):
                raise TypeError(
                    "appendage must offer the W-matrix interface (length, mass, inertia, W(s)); "
                    f"got {type(appendage).__name__} without '{attribute}'"
                )
        if orientation is not None:
            if direction is not _UNSET:
                raise TypeError("give direction (a planar mount) or orientation (three axes), "
                                f"not both; got direction {describe(direction)}")
            self._orientation = check_rotation("orientation", orientation)
            self._orientation.flags.writeable = False
            position = real_vector3("position", position, "m")
            if not hasattr(appendage, "W6"):
                raise TypeError(
                    "a three-axis mount needs an appendage with W6(s) (root motions per root "
                    f"loads in three axes); got {type(appendage).__name__} without 'W6'")
            try:
                appendage.inertia_tensor  # a planar appendage says by name what it lacks
            except ValueError as exc:
                label = f" '{name}'" if isinstance(name, str) else ""
                raise ValueError(f"three-axis mount{label} (orientation given): {exc}") from None
            angle = None
        else:
            if direction is _UNSET:
                direction = 0.0
            if isinstance(position, (list, tuple, np.ndarray)) and len(position) == 3:
                raise ValueError(f"position must be two coordinates for a planar mount [m]; "
                                 f"got three, {describe(position)}: "
                                 "give orientation= (a 3x3 rotation) for a three-axis mount")
            position = _real_vector("position", position, "m")
            angle = self._planar_angle(direction)
            self._orientation = None
        if np.any(np.abs(position) > POSITION_LIMIT):
            raise ValueError(f"position must have coordinates of at most {POSITION_LIMIT:g} in "
                             f"magnitude [m]; got {describe(tuple(position))}")
        if name is not None and not isinstance(name, str):
            raise TypeError(f"mount name must be a string; got {type(name).__name__} "
                            f"{describe(name)}")
        if name is not None and not name.isidentifier():
            raise ValueError(f"mount name must be an identifier-like string; got {describe(name)}")
        self.appendage = appendage
        self.position = position
        self.angle = angle
        self.name = name

    @staticmethod
    def _planar_angle(direction) -> float:
        if _is_real_scalar(direction):
            angle = float(direction)
            if not math.isfinite(angle) or abs(angle) > ANGLE_LIMIT:
                raise ValueError(f"direction must be a finite angle of at most {ANGLE_LIMIT:g} "
                                 f"in magnitude [rad] or a 2-vector; got {describe(direction)}")
            warn_angle_in_degrees("direction", angle, stacklevel=4)
            return angle
        if isinstance(direction, (str, bytes, complex, np.complexfloating, bool, np.bool_)) \
                or direction is None:
            raise TypeError(f"direction must be an angle [rad] (a real number) or a 2-vector; "
                            f"got {type(direction).__name__} {describe(direction)}")
        d = _real_vector("direction", direction, "-")
        if np.hypot(*d) == 0.0:
            raise ValueError("direction must be an angle [rad] or a non-zero 2-vector; got "
                             f"{describe(direction)}")
        return math.atan2(d[1], d[0])

    @property
    def three_axis(self) -> bool:
        """True for a mount given an orientation (three axes)."""
        return self._orientation is not None

    @property
    def orientation(self) -> np.ndarray:
        """Rotation whose columns are the appendage's x, y, z axes in hub axes (3, 3).

        A planar mount: ``R_z(angle)``.
        """
        if self._orientation is None:
            return planar_orientation(self.angle)
        return self._orientation

    @property
    def point(self) -> np.ndarray:
        """Attachment point (x, y, z) in hub axes [m] (z = 0 for a planar mount)."""
        if self._orientation is None:
            return np.array([self.position[0], self.position[1], 0.0])
        return self.position.copy()

    @property
    def axis(self) -> np.ndarray:
        """Unit vector along the appendage (its x axis) in hub axes (2 entries if planar)."""
        if self._orientation is None:
            return np.array([math.cos(self.angle), math.sin(self.angle)])
        return self._orientation[:, 0].copy()

    @property
    def normal(self) -> np.ndarray:
        """Unit vector of the appendage's y axis (planar deflection direction) in hub axes."""
        if self._orientation is None:
            return np.array([-math.sin(self.angle), math.cos(self.angle)])
        return self._orientation[:, 1].copy()

    def kinematics(self) -> np.ndarray:
        """Rows mapping hub motion (X, Y, theta) to (axial, delta, phi) of the attachment end.

        Planar mounts only. A small hub rotation theta moves the point p by
        theta * (z x p) = theta * (-p_y, p_x), so ``delta = n . (X, Y) + theta (p . e_x)``,
        ``axial = e_x . (X, Y) - theta (p . n)`` and ``phi = theta``.
        """
        if self._orientation is not None:
            raise ValueError("kinematics() is the planar map; a three-axis mount has "
                             "transformation() (6x6)")
        p, e, n = self.position, self.axis, self.normal
        return np.array([
            [e[0], e[1], -float(p @ n)],
            [n[0], n[1], float(p @ e)],
            [0.0, 0.0, 1.0],
        ])

    def with_appendage(self, appendage) -> "Mount":
        """The same mount (position, direction or orientation, name) carrying another model
        of the appendage (e.g. a truncation of the beam mounted here)."""
        if self._orientation is not None:
            return Mount(appendage, self.position, orientation=self._orientation,
                         name=self.name)
        return Mount(appendage, self.position, self.angle, name=self.name)

    def transformation(self) -> np.ndarray:
        """G (6x6): root motions (u, v, w, theta_x, theta_y, theta_z) in the appendage's axes
        from hub motions (X, Y, Z, theta_x, theta_y, theta_z) (:mod:`spacecraft.dynamics.kinematics`).

        Defined for planar mounts too (in the hub's x-y plane)."""
        return mount_transformation(self.point, self.orientation)

    def __repr__(self) -> str:
        if self._orientation is not None:
            return (f"Mount({self.appendage!r}, position={tuple(self.position.tolist())}, "
                    f"orientation={self._orientation.tolist()}, name={self.name!r})")
        return (f"Mount({self.appendage!r}, position={tuple(self.position)}, "
                f"direction={self.angle!r}, name={self.name!r})")
