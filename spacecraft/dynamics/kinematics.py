r"""Small-motion kinematics of a rigid hub in three axes, and the checks of its inputs.

The hub's motion is the translation ``u_G`` of its centre of mass and its small rotation
vector ``theta`` (hub axes). A point of the hub at ``r`` (from the centre of mass, hub axes)
moves by ``u_P = u_G + theta x r = u_G - [r]x theta`` and every line through it turns by
``theta``. An appendage mounted there with its local axes the columns of a rotation R sees
these motions in its own axes (``R^T``), so its root motions ``(u, v, w, theta_x, theta_y,
theta_z)`` are

    q_root = G h,     G = [[R^T, 0], [0, R^T]] [[I, -[r]x], [0, I]],     h = (u_G, theta),

and, by virtual work, its root loads act on the hub as ``-G^T`` times them. A planar mount at
angle a in the x-y plane is ``R = R_z(a)``, ``r = (x, y, 0)``; its rows (v, theta_z) and the
axial row u restricted to (X, Y, theta_z) are the planar ``Mount.kinematics()``.

References
----------
.. [1] P. W. Likins, "Dynamics and control of flexible space vehicles", JPL TR 32-1329, 1970
   (hub and appendage kinematics, small rotations).
.. [2] M. Geradin, A. Cardona, "Flexible Multibody Dynamics", Wiley, 2001, ch. 4 (small
   rotation vectors, rigid-body motion of a point).
"""

from __future__ import annotations

import math

import numpy as np

from appendages.interface import RANGES, describe
from appendages.unit_slips import warn_angle_in_degrees

__all__ = ["ORTHONORMALITY_TOLERANCE", "SYMMETRY_TOLERANCE", "TRIANGLE_TOLERANCE",
           "check_inertia_tensor",
           "check_rotation", "cross_matrix", "euler_orientation", "mount_transformation",
           "orientation_from_axis", "planar_orientation", "real_vector3"]

#: Largest |R^T R - I| entry accepted for a rotation matrix (the issue's 1e-9): a matrix
#: typed with ten significant digits passes, a scaled or sheared one does not.
ORTHONORMALITY_TOLERANCE = 1e-9
#: Largest |J - J^T| accepted for an inertia tensor, relative to its largest entry.
SYMMETRY_TOLERANCE = 1e-9
#: Largest excess of the largest principal moment over the sum of the other two accepted,
#: relative to that sum (a flat plate has equality; eigvalsh is exact to ~1e-16 of |J|).
TRIANGLE_TOLERANCE = 1e-9


def cross_matrix(r) -> np.ndarray:
    """The matrix ``[r]x`` with ``[r]x a = r x a``."""
    r = np.asarray(r, dtype=float)
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _real_matrix(name: str, value, unit: str, shape: tuple) -> np.ndarray:
    """A finite real array of the given shape, or TypeError/ValueError naming ``name``."""
    what = "three real numbers" if shape == (3,) else f"a {shape[0]}x{shape[1]} real matrix"
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(f"{name} must be {what} [{unit}]; got "
                        f"{type(value).__name__} {describe(value)}")
    try:
        arr = np.asarray(value)
    except (ValueError, TypeError) as exc:
        raise TypeError(f"{name} must be {what} [{unit}]; got {describe(value)}") from exc
    if arr.dtype == bool or arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be {what} [{unit}]; got "
                        f"dtype {arr.dtype}: {describe(value)}")
    if arr.shape != shape:
        raise ValueError(f"{name} must have shape {shape} [{unit}]; got shape {arr.shape}: "
                         f"{describe(value)}")
    with np.errstate(over="ignore"):
        arr = arr.astype(float)
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite [{unit}]; got {describe(value)}")
    return arr


def real_vector3(name: str, value, unit: str) -> np.ndarray:
    """Three finite real numbers as a float64 array, or TypeError/ValueError naming ``name``."""
    if isinstance(value, (list, tuple)) and any(isinstance(v, (bool, np.bool_)) for v in value):
        raise TypeError(f"{name} must be three real numbers [{unit}]; got a bool in "
                        f"{describe(value)}")
    return _real_matrix(name, value, unit, (3,))


def check_rotation(name: str, value) -> np.ndarray:
    """A proper rotation matrix (3x3, ``R^T R = I`` to 1e-9, det +1), as float64.

    Raises
    ------
    TypeError
        Not a real 3x3 array.
    ValueError
        Wrong shape, not finite, columns not orthonormal to :data:`ORTHONORMALITY_TOLERANCE`,
        or a reflection (det -1); the message gives the largest deviation and the determinant.
    """
    R = _real_matrix(name, value, "-", (3, 3))
    deviation = float(np.max(np.abs(R.T @ R - np.eye(3))))
    det = float(np.linalg.det(R))
    if deviation > ORTHONORMALITY_TOLERANCE or det < 0.0:
        raise ValueError(
            f"{name} must be a rotation matrix [-] (columns the appendage's local x, y, z axes "
            f"in hub axes: orthonormal to {ORTHONORMALITY_TOLERANCE:g}, det = +1); got "
            f"max |R^T R - I| = {deviation:.3g}, det = {det:.6g}: {describe(R.tolist())}")
    return R


def check_inertia_tensor(name: str, value) -> np.ndarray:
    """A symmetric positive-definite 3x3 inertia tensor [kg*m**2], symmetrised, as float64.

    Symmetric to :data:`SYMMETRY_TOLERANCE` of its largest entry; every principal moment in
    the ``inertia`` range of :data:`appendages.interface.RANGES` (1e-20 to 1e20 kg*m**2); and
    the tensor of a body: its principal moments j1 <= j2 <= j3 obey the triangle inequality
    j3 <= j1 + j2 (to :data:`TRIANGLE_TOLERANCE`). In principal axes j1 + j2 - j3 is twice the
    integral of the squared coordinate along the axis of j3 over the mass, never negative;
    equality is a flat plate. ``diag(1, 1, 100)`` is no body's.

    Raises
    ------
    TypeError
        Not a real 3x3 array.
    ValueError
        Not finite, not symmetric, or a principal moment not positive (indefinite), out of
        range or larger than the sum of the other two; the message gives the asymmetry or the
        principal moments.

    References
    ----------
    .. [1] H. Goldstein, C. Poole, J. Safko, "Classical Mechanics", 3rd ed., 2002, sec. 5.3
       (principal moments; the triangle inequality of a rigid body's moments).
    """
    J = _real_matrix(name, value, "kg*m^2", (3, 3))
    scale = float(np.max(np.abs(J)))
    asymmetry = float(np.max(np.abs(J - J.T)))
    if asymmetry > SYMMETRY_TOLERANCE * scale:
        raise ValueError(f"{name} must be a symmetric tensor [kg*m^2] (J = J^T to "
                         f"{SYMMETRY_TOLERANCE:g} relative); got max |J - J^T| = "
                         f"{asymmetry:.3g} of {scale:.3g}: {describe(J.tolist())}")
    J = 0.5 * (J + J.T)
    moments = np.linalg.eigvalsh(J)
    low, high, _ = RANGES["inertia"]
    if moments[0] <= 0.0:
        raise ValueError(f"{name} must be positive definite [kg*m^2]; got principal moments "
                         f"{describe(tuple(float(m) for m in moments))}")
    if moments[0] < low or moments[-1] > high:
        raise ValueError(f"{name} must have principal moments in [{low:g}, {high:g}] "
                         f"[kg*m^2] (appendages.interface.RANGES); got "
                         f"{describe(tuple(float(m) for m in moments))}")
    if moments[2] > (moments[0] + moments[1]) * (1.0 + TRIANGLE_TOLERANCE):
        raise ValueError(
            f"{name} must be the inertia of a body [kg*m^2]: its largest principal moment at "
            f"most the sum of the other two (triangle inequality; equality for a flat plate); "
            f"got principal moments {describe(tuple(float(m) for m in moments))}, "
            f"{moments[2]:.6g} > {moments[0]:.6g} + {moments[1]:.6g}")
    return J


def planar_orientation(angle: float) -> np.ndarray:
    """R_z(angle): the orientation of a planar mount whose x axis is at ``angle`` [rad]."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def euler_orientation(sequence: str, angles) -> np.ndarray:
    """Orientation from Euler angles [rad] (scipy's convention).

    Parameters
    ----------
    sequence : str
        Three axes, e.g. ``"ZYX"`` (upper case: intrinsic rotations, each about the axes
        already turned; lower case: extrinsic, about the hub's fixed axes).
    angles : sequence of three floats, rad
        Radians, as everywhere in the Python API (a scene file gives degrees); an angle of
        more than a turn is warned about (:class:`appendages.unit_slips.UnitWarning`).

    Returns
    -------
    ndarray (3, 3)
        Columns the appendage's local x, y, z axes in hub axes. ``euler_orientation("ZYX",
        (yaw, pitch, roll))`` turns the appendage by yaw about the hub's z, then pitch about
        the new y, then roll about the new x (its own axis).
    """
    from scipy.spatial.transform import Rotation

    if not isinstance(sequence, str) or len(sequence) != 3 or \
            not (set(sequence) <= set("xyz") or set(sequence) <= set("XYZ")) or \
            sequence[0] == sequence[1] or sequence[1] == sequence[2]:
        raise ValueError(f"sequence must be three axes from 'xyz' (extrinsic) or 'XYZ' "
                         f"(intrinsic), no two consecutive alike (e.g. 'ZYX', 'zxz'); got "
                         f"{describe(sequence)}")
    angles = real_vector3("angles", angles, "rad")
    for k, angle in enumerate(angles):
        warn_angle_in_degrees(f"angles[{k}]", float(angle))
    return Rotation.from_euler(sequence, angles).as_matrix()


def orientation_from_axis(x_axis, y_axis=None) -> np.ndarray:
    """Orientation whose local x axis points along ``x_axis`` (hub axes).

    Parameters
    ----------
    x_axis : three floats
        Direction of the appendage (nonzero; normalised here).
    y_axis : three floats, optional
        Approximate direction of the local y axis (a wing's thickness direction, the
        planar bending direction); made orthogonal to x. Default: the hub axis least aligned
        with x_axis, made orthogonal.

    Returns
    -------
    ndarray (3, 3)
        ``[x, y, z]`` columns, ``z = x x y``.
    """
    x = real_vector3("x_axis", x_axis, "-")
    if not np.any(x):
        raise ValueError("x_axis must be a nonzero vector [-]; got (0, 0, 0)")
    x = x / np.max(np.abs(x))  # scaled first: the norm of tiny or huge entries stays normal
    x = x / np.linalg.norm(x)
    if y_axis is None:
        y = np.eye(3)[int(np.argmin(np.abs(x)))]
    else:
        y = real_vector3("y_axis", y_axis, "-")
        if np.any(y):
            y = y / np.max(np.abs(y))
    size = np.linalg.norm(y)
    y = y - (y @ x) * x
    if np.linalg.norm(y) <= 1e-9 * size:
        raise ValueError(f"y_axis must not be parallel to x_axis [-]; got x_axis "
                         f"{describe(tuple(x))}, y_axis {describe(y_axis)}")
    y = y / np.linalg.norm(y)
    return np.column_stack([x, y, np.cross(x, y)])


def mount_transformation(position, orientation) -> np.ndarray:
    """G with (root motions in beam axes) = G (hub motions), shape (6, 6) (module docstring).

    Parameters
    ----------
    position : three floats, m
        Attachment point, hub axes, from the hub's centre of mass.
    orientation : (3, 3)
        Rotation whose columns are the appendage's local axes in hub axes (checked by the
        caller, :func:`check_rotation`).
    """
    R = np.asarray(orientation, dtype=float)
    rigid = np.eye(6)
    rigid[:3, 3:] = -cross_matrix(position)
    return np.kron(np.eye(2), R.T) @ rigid
