r"""A rigid body at the free end of a beam: a reflector, a magnetometer, an instrument.

The body is fixed to the beam's free end (x = L, the "tip node"), which moves by the translation
``(u, v, w)`` and the small rotation vector ``theta = (theta_x, theta_y, theta_z)``, appendage axes.
Its centre of mass lies at the offset ``r`` from the tip node and moves by
``u_c = u + theta x r = u - [r]x theta``; with its inertia J about its centre of mass the kinetic
energy gives the mass matrix about the tip node (in ``(u, v, w, theta_x, theta_y, theta_z)``)::

    M_tip = [[m I,        -m [r]x                  ],
             [m [r]x,      J + m (|r|**2 I - r r^T)]],

``[r]x`` the cross-product matrix. In the plane (x-y, motions ``(v, theta_z)``) with the
offset along x (``r = (r_x, 0, r_z)``: ``r_z`` only moves the body out of the plane, which the
planar model does not see)::

    M_tip = [[m,        m r_x                      ],
             [m r_x,    J_zz + m r_x**2            ]].

An offset across the axis in the plane (``r_y != 0``) couples the tip rotation with axial
motion, which the planar interface (loads F_y, M only) cannot carry: the planar model refuses
it by name, the three-axis one (W6, axial motion included) takes it exactly.

References
----------
.. [1] H. Goldstein, "Classical Mechanics", 2nd ed., Addison-Wesley, 1980, sec. 5.3 (inertia
   tensor, parallel-axis theorem).
"""

from __future__ import annotations

import numbers

import numpy as np

from .checks import RANGES, check_range
from .errors import describe

__all__ = ["TipBody", "check_inertia_tensor", "check_tip", "cross_matrix"]

#: Relative tolerance of the symmetry, positivity and triangle checks of an inertia tensor
#: (a tensor typed with 12 significant digits passes).
_TENSOR_TOLERANCE = 1e-12


def check_inertia_tensor(name: str, value) -> np.ndarray:
    """A 3x3 inertia tensor [kg*m**2] of a rigid body, checked, as a read-only float array.

    Symmetric (to 1e-12 of its largest entry), positive semi-definite, and a body's: every
    principal moment at most the sum of the other two (``J_1 <= J_2 + J_3``, the triangle
    inequality that a mass distribution obeys: ``J_1 = integral (y**2 + z**2) dm <= ...``).
    A point mass (all zero) and a thin rod (``(0, J, J)``) pass.

    Raises
    ------
    TypeError
        Not an array of real numbers.
    ValueError
        Wrong shape, not finite, not symmetric, a negative principal moment, a triangle
        inequality violated, or an entry beyond the ``body_inertia`` range of
        :data:`~appendages.interface.RANGES`.
    """
    unit = RANGES["body_inertia"][2]
    try:
        J = np.array(value)
    except Exception:  # pragma: no cover - numpy raises many kinds here
        raise TypeError(f"{name} must be a 3x3 array of real numbers [{unit}]; got "
                        f"{describe(value)}") from None
    if J.dtype == bool or J.dtype.kind not in "iuf":
        raise TypeError(f"{name} must be a 3x3 array of real numbers [{unit}]; got "
                        f"{type(value).__name__} {describe(value)}")
    if J.shape != (3, 3):
        raise ValueError(f"{name} must be a 3x3 tensor [{unit}] (or a float about z in the "
                         f"plane); got shape {J.shape}")
    J = J.astype(float)
    if not np.all(np.isfinite(J)):
        raise ValueError(f"{name} must be finite [{unit}]; got {describe(J.tolist())}")
    size = float(np.max(np.abs(J)))
    if size > RANGES["body_inertia"][1]:
        raise ValueError(f"{name} must have entries of at most {RANGES['body_inertia'][1]:g} "
                         f"[{unit}]; got {describe(J.tolist())}")
    if np.max(np.abs(J - J.T)) > _TENSOR_TOLERANCE * size:
        raise ValueError(f"{name} must be symmetric [{unit}]; got {describe(J.tolist())}")
    J = 0.5 * (J + J.T)
    principal = np.linalg.eigvalsh(J)
    if principal[0] < -_TENSOR_TOLERANCE * size:
        raise ValueError(f"{name} must be positive semi-definite [{unit}]; got principal "
                         f"moments {describe(principal.tolist())}")
    if principal[2] > principal[0] + principal[1] + _TENSOR_TOLERANCE * size:
        raise ValueError(
            f"{name} must be a rigid body's inertia: its largest principal moment at most the "
            f"sum of the other two [{unit}]; got principal moments "
            f"{describe(principal.tolist())}")
    J.flags.writeable = False
    return J


def _check_offset(offset) -> np.ndarray:
    """The offset as a read-only (3,) array [m] from a float (along x) or 2-/3-vector."""
    low, high, unit = RANGES["length"]
    if isinstance(offset, (bool, np.bool_)):
        raise TypeError(f"offset must be a real number (along x) or 2 or 3 real numbers [{unit}]; "
                        f"got {describe(offset)}")
    if isinstance(offset, numbers.Real):
        vector = np.array([float(offset), 0.0, 0.0])
    else:
        try:
            array = np.array(offset)
        except Exception:  # pragma: no cover
            array = np.array(None)
        if array.dtype == bool or array.dtype.kind not in "iuf" or array.ndim != 1 \
                or array.size not in (2, 3):
            raise TypeError(f"offset must be a real number (along x) or a vector of 2 or 3 real "
                            f"numbers [{unit}]; got {type(offset).__name__} {describe(offset)}")
        vector = np.zeros(3)
        vector[:array.size] = array.astype(float)
    if not np.all(np.isfinite(vector)) or np.max(np.abs(vector)) > high:
        raise ValueError(f"offset must be finite, each coordinate at most {high:g} in magnitude "
                         f"[{unit}]; got {describe(offset)}")
    vector.flags.writeable = False
    return vector


def cross_matrix(r: np.ndarray) -> np.ndarray:
    """``[r]x`` with ``[r]x a = r x a``."""
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


class TipBody:
    """A rigid body fixed to the free end of a beam (see the module docstring).

    Parameters
    ----------
    mass : float, kg
        Non-negative (0 with zero inertia: no body; the beam is then exactly the bare beam).
    inertia : float or (3, 3) array_like, kg*m**2
        About the body's own centre of mass: a float, the moment about z for planar models;
        or the 3x3 tensor in the appendage's axes (symmetric, positive semi-definite, each
        principal moment at most the sum of the other two) for three-axis models.
    offset : float or sequence of 2 or 3 floats, m, optional
        Position of the body's centre of mass from the free end, appendage axes: a float
        along x (outward), or ``(x, y)`` / ``(x, y, z)``. Default 0.

    Raises
    ------
    TypeError
        A parameter of the wrong type.
    ValueError
        A negative or non-finite mass, an inertia that is negative, not symmetric, not
        positive semi-definite or not a body's (:func:`check_inertia_tensor`), an offset that
        is not finite or beyond 1e6 m, or values outside :data:`~appendages.interface.RANGES`.

    Attributes
    ----------
    mass : float
    inertia : float or ndarray (3, 3)
        As given (the tensor read-only).
    offset : ndarray, shape (3,)
        Read-only.
    """

    def __init__(self, mass: float, inertia, offset=0.0):
        self.mass = check_range("mass", mass, "mass", allow_zero=True)
        if isinstance(inertia, numbers.Real) and not isinstance(inertia, (bool, np.bool_)):
            self.inertia = check_range("inertia", inertia, "body_inertia", allow_zero=True)
        elif isinstance(inertia, (bool, np.bool_, str, bytes)) or inertia is None:
            raise TypeError(f"inertia must be a real number (about z, planar) or a 3x3 tensor "
                            f"[kg*m^2]; got {type(inertia).__name__} {describe(inertia)}")
        else:
            self.inertia = check_inertia_tensor("inertia", inertia)
        self.offset = _check_offset(offset)

    def __repr__(self) -> str:
        inertia = self.inertia if isinstance(self.inertia, float) else self.inertia.tolist()
        return (f"TipBody(mass={self.mass!r}, inertia={inertia!r}, "
                f"offset={self.offset.tolist()!r})")

    @property
    def is_null(self) -> bool:
        """True for a body of zero mass and zero inertia (the bare beam)."""
        return self.mass == 0.0 and not np.any(self.inertia)

    @property
    def planar_inertia(self) -> float:
        """Moment of inertia about z through the body's centre of mass [kg*m**2]."""
        return self.inertia if isinstance(self.inertia, float) else float(self.inertia[2, 2])

    @property
    def inertia_tensor(self) -> np.ndarray:
        """The 3x3 inertia about the body's centre of mass [kg*m**2]; ValueError for a planar
        body given a non-zero float moment (its other moments are unknown)."""
        if isinstance(self.inertia, float):
            if self.inertia != 0.0:
                raise ValueError(
                    "a three-axis model needs the tip body's inertia as a 3x3 tensor [kg*m^2] "
                    "about its centre of mass in the appendage's axes; got the planar moment "
                    f"inertia = {self.inertia!r} (give TipBody(mass, [[Jxx, Jxy, Jxz], ...]))")
            return np.zeros((3, 3))
        return np.array(self.inertia)

    def check_planar(self) -> None:
        """ValueError unless the planar model can carry the body (no offset along y)."""
        if self.offset[1] != 0.0:
            raise ValueError(
                "a tip body offset across the axis in the plane (offset y = "
                f"{float(self.offset[1])!r} m) couples the tip rotation with axial motion, which the "
                "planar interface (F_y, M) cannot carry; use the three-axis model (W6) or an "
                "offset along x")

    def mass_matrix(self, n_root: int = 2) -> np.ndarray:
        """The body's mass matrix about the beam's free end (module docstring).

        Parameters
        ----------
        n_root : {2, 6}
            2: planar motions ``(v, theta_z)`` [kg, kg*m; kg*m, kg*m**2]; 6: ``(u, v, w,
            theta_x, theta_y, theta_z)``.
        """
        m, r = self.mass, self.offset
        if n_root == 2:
            self.check_planar()
            return np.array([[m, m * r[0]], [m * r[0], self.planar_inertia + m * r[0] ** 2]])
        if n_root != 6:
            raise ValueError(f"n_root must be 2 or 6; got {describe(n_root)}")
        X = cross_matrix(r)
        M = np.zeros((6, 6))
        M[:3, :3] = m * np.eye(3)
        M[:3, 3:] = -m * X
        M[3:, :3] = m * X
        M[3:, 3:] = self.inertia_tensor + m * (float(r @ r) * np.eye(3) - np.outer(r, r))
        return 0.5 * (M + M.T)


def check_tip(tip) -> TipBody | None:
    """``tip`` itself if it is a :class:`TipBody` or None; TypeError naming it otherwise."""
    if tip is None or isinstance(tip, TipBody):
        return tip
    raise TypeError(f"tip must be a TipBody (appendages.TipBody(mass, inertia, offset)) or None; "
                    f"got {type(tip).__name__} {describe(tip)}")
