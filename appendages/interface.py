"""The W-matrix interface shared by every appendage model.

An appendage is loaded only at its attachment end (x = 0) by a transverse force ``F_y`` [N] and a
moment ``M`` [N*m]; it answers with the attachment end's transverse displacement ``delta`` [m] and
rotation ``phi`` [rad]. In Laplace form (zero initial conditions)

    [delta]   [W1  W2] [F_y]
    [ phi ] = [W3  W4] [ M ],      W2 = W3 (reciprocity),

where W(s) includes the free rigid-body motion (the 1/s**2 term).

Finite models (truncated beams, hinged chains) also expose a realisation of W in *attachment-end
coordinates*, a :class:`RootModel`: generalised coordinates ``q = [delta, phi, q_2, ...]`` with

    M q'' + C q' + K q = [F_y, M, 0, ..., 0]^T,

so that ``W(s) = [(M s**2 + C s + K)^-1]`` restricted to the first two coordinates. This is the
form in which a hub couples to any appendage: the first two coordinates are set equal to the hub's
motion at the mount, whatever the appendage's class (``spacecraft.dynamics.coupling``). The mass matrix may
be singular (a massless spring between the mount and the first body); the coupled system is not.

Three axes (issue 11)
---------------------
A three-axis appendage is loaded at its attachment end by ``(F_x, F_y, F_z, M_x, M_y, M_z)``
(beam axes: x along the appendage, y the planar deflection direction) and answers with
``(u, v, w, theta_x, theta_y, theta_z)``: ``W6(s)`` (6x6, symmetric, rigid-body motion
included), with ``theta_y = -dw/dx``. Its finite realisation is a :class:`RootModel` with
``n_root = 6`` (``root_model(n_root=6)``) and three tip rows (:data:`TIP_MOTIONS`); a straight
appendage with a symmetric section is built from its four decoupled motions by
:func:`three_axis_root_model`. The x-y plane of a three-axis model is the planar model, so the
planar interface above is its special case. What a three-axis hub needs of an appendage is
:class:`ThreeAxisAppendage`.

References
----------
.. [1] P. A. Belonozhko, P. P. Belonozhko, A. A. Fokov et al., "On the equivalence of mechanical
   design schemes with distributed and lumped parameters for spatially developed peripheral
   elements of spacecraft", Institute of Technical Mechanics, NAS of Ukraine, 2009 (eq. (2)-(5)).
.. [2] R. R. Craig, A. J. Kurdila, "Fundamentals of Structural Dynamics", 2nd ed., Wiley, 2006,
   ch. 17 (component-mode synthesis, constraint modes).
"""

from __future__ import annotations

import dataclasses
from typing import Protocol, runtime_checkable

import numpy as np
import scipy.linalg

# The errors and the argument checks have modules of their own (appendages.errors,
# appendages.checks); their names stay importable from here, where they were first defined.
from .checks import (RANGES, S_RANGE, as_frequency_array, check_derived, check_positive,
                     check_range)
from .errors import ConvergenceError, FlexsatError, describe

__all__ = [
    "Appendage",
    "FiniteAppendage",
    "RootModel",
    "as_frequency_array",
    "RANGES",
    "S_RANGE",
    "check_derived",
    "check_positive",
    "check_range",
    "describe",
    "equilibrate",
    "inverse_2x2",
    "inverse_symmetric",
    "ROOT_MOTIONS",
    "ROOT_LOADS",
    "TIP_MOTIONS",
    "three_axis_root_model",
    "ThreeAxisAppendage",
    "FlexsatError",
    "ConvergenceError",
    "place_bending_planes",
]


def equilibrate(K: np.ndarray, M: np.ndarray) -> np.ndarray:
    """Diagonal scaling d (K' = d K d, M' = d M d) that makes a pencil independent of units.

    ``d_i = 1/sqrt(M_ii)`` for coordinates with mass; ``sqrt(w**2/K_ii)`` for massless ones
    (w**2 the largest K_ii/M_ii of the others); for a coordinate with neither (a Lagrange
    multiplier of a Rosenbrock pencil) the d that brings its row of K' to the size of the rest.
    The eigenvalues are unchanged; the eigenvectors of (K', M') are those of (K, M) divided by
    d. LAPACK's generalized eigen-solvers are backward stable in norm, so without it a
    coordinate in small units (the rotation of a 1 um beam in rad against its translation in
    m) loses the digits that a change of units would keep.
    """
    m = np.diag(M).astype(float).copy()
    k = np.abs(np.diag(K)).astype(float)
    has_mass = m > 0.0
    d = np.ones(m.size)
    d[has_mass] = 1.0 / np.sqrt(m[has_mass])
    massless = ~has_mass & (k > 0.0)
    if np.any(massless):
        both = has_mass & (k > 0.0)
        omega2 = np.max(k[both] / m[both]) if np.any(both) else 1.0
        d[massless] = np.sqrt(omega2 / k[massless])
    neither = ~has_mass & ~massless
    if np.any(neither) and np.any(~neither):
        scaled = np.abs(K[np.ix_(~neither, ~neither)]) * np.outer(d[~neither], d[~neither])
        size = max(scaled.max(), np.finfo(float).tiny)
        for j in np.flatnonzero(neither):
            row = np.abs(K[~neither, j]) * d[~neither]
            if row.max() > 0.0:
                d[j] = size / row.max()
    return d


def inverse_2x2(D: np.ndarray) -> np.ndarray:
    """Inverse of symmetric 2x2 matrices (stacked in the last two axes), by the adjugate.

    Each matrix is first divided by its largest entry, so that the determinant of matrices
    with entries up to 1e300 neither overflows nor underflows; the result is exactly
    symmetric. A singular matrix gives inf or NaN entries (the caller decides).
    """
    scale = np.max(np.abs(D), axis=(-2, -1), keepdims=True)
    scale = np.where(scale > 0, scale, 1.0)
    A = D / scale
    off = 0.5 * (A[..., 0, 1] + A[..., 1, 0])
    det = A[..., 0, 0] * A[..., 1, 1] - off * off
    W = np.empty_like(A)
    W[..., 0, 0] = A[..., 1, 1] / det
    W[..., 1, 1] = A[..., 0, 0] / det
    W[..., 0, 1] = W[..., 1, 0] = -off / det
    return W / scale


@runtime_checkable
class Appendage(Protocol):
    """What the hub needs of an appendage: its rigid properties and W(s)."""

    @property
    def length(self) -> float: ...  # m

    @property
    def mass(self) -> float: ...  # kg

    @property
    def inertia(self) -> float: ...  # kg*m**2 about the centre of mass, undeformed

    def W(self, s) -> np.ndarray: ...


#: Root motions of an appendage in three axes, beam axes (the rows of W6).
ROOT_MOTIONS = ("u", "v", "w", "theta_x", "theta_y", "theta_z")
#: Root loads of an appendage in three axes, beam axes (the columns of W6).
ROOT_LOADS = ("F_x", "F_y", "F_z", "M_x", "M_y", "M_z")
#: Elastic tip motions of a three-axis root model (the rows of ``RootModel.tip``).
TIP_MOTIONS = ("tip_deflection_y", "tip_deflection_z", "tip_twist")


def inverse_symmetric(D: np.ndarray) -> np.ndarray:
    """Inverse of complex symmetric matrices (stacked in the last two axes), scaled.

    2x2 matrices go through :func:`inverse_2x2`. Larger ones are equilibrated first,
    ``d_i = 1/sqrt(|D_ii|)`` (1 where D_ii = 0), so that entries in mixed units (N/m, N,
    N*m of a 6x6 root stiffness) do not decide the accuracy; the result is symmetrised.
    A singular matrix gives inf or NaN entries (the caller decides).
    """
    D = np.asarray(D)
    if D.shape[-1] == 2:
        return inverse_2x2(D)
    diag = np.abs(np.diagonal(D, axis1=-2, axis2=-1))
    d = np.where(diag > 0, 1.0 / np.sqrt(np.where(diag > 0, diag, 1.0)), 1.0)
    scale = d[..., :, None] * d[..., None, :]
    try:
        inv = np.linalg.inv(D * scale) * scale
    except np.linalg.LinAlgError:
        inv = np.empty(D.shape, dtype=np.result_type(D.dtype, np.complex128))
        flat_in, flat_out = (D * scale).reshape(-1, *D.shape[-2:]), inv.reshape(-1, *D.shape[-2:])
        flat_scale = np.broadcast_to(scale, D.shape).reshape(flat_in.shape)
        for k, A in enumerate(flat_in):
            try:
                flat_out[k] = np.linalg.inv(A) * flat_scale[k]
            except np.linalg.LinAlgError:
                flat_out[k] = np.inf
    return 0.5 * (inv + np.swapaxes(inv, -1, -2))


@runtime_checkable
class ThreeAxisAppendage(Protocol):
    """What a three-axis hub needs of an appendage (beam axes, rigid-body motion included)."""

    @property
    def mass(self) -> float: ...  # kg

    @property
    def center_of_mass(self) -> float: ...  # m, along x from the attachment end

    @property
    def inertia_tensor(self) -> np.ndarray: ...  # kg*m**2, 3x3 about the centre of mass

    def W6(self, s) -> np.ndarray: ...


@dataclasses.dataclass(frozen=True)
class RootModel:
    """Second-order realisation of W(s) (or W6(s)) in attachment-end coordinates.

    Attributes
    ----------
    mass, damping, stiffness : ndarray, shape (n, n)
        Symmetric matrices [SI units of the coordinates]. The first ``n_root`` coordinates are
        the attachment end's motions on which the root loads act: planar (``n_root = 2``)
        ``delta`` [m] and ``phi`` [rad] loaded by ``F_y``, ``M``; three-axis (``n_root = 6``)
        ``u, v, w`` [m] and ``theta_x, theta_y, theta_z`` [rad] in beam axes
        (:data:`ROOT_MOTIONS`) loaded by :data:`ROOT_LOADS`; one motion of a rod
        (``n_root = 1``, a building block of the three-axis models).
    tip : ndarray, shape (n,) or (3, n)
        Planar and rod models: the row giving the elastic tip motion, the free end's
        transverse displacement relative to the line tangent to the appendage at its
        attachment end, ``w(L) - delta - L*phi`` [m] (a rod: ``u(L) - u(0)`` or the tip
        twist). Three-axis models: three rows (:data:`TIP_MOTIONS`), the tip deflections along
        local y and z and the tip twist, each relative to the rigidly moving root section:
        ``v(L) - v(0) - L theta_z(0)``, ``w(L) - w(0) + L theta_y(0)`` [m] and
        ``theta_x(L) - theta_x(0)`` [rad].
    coordinate_names : tuple of str
        Names of the coordinates (for state names).
    n_root : int
        Number of attachment-end coordinates: 2 (planar, the default), 6 (three axes) or 1.
    """

    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    tip: np.ndarray
    coordinate_names: tuple
    n_root: int = 2

    @property
    def n(self) -> int:
        """Number of generalised coordinates."""
        return self.mass.shape[0]

    @property
    def tip_rows(self) -> np.ndarray:
        """The tip row(s) as a 2-D array, shape (1, n) or (3, n)."""
        return np.atleast_2d(self.tip)

    def dynamic_stiffness(self, s: np.ndarray) -> np.ndarray:
        """Attachment-end dynamic stiffness D(s) = W(s)^-1, by static condensation.

        ``D = Z_rr - Z_ri Z_ii^-1 Z_ir`` with ``Z = M s**2 + C s + K`` partitioned into the
        ``n_root`` attachment-end coordinates (r) and the internal ones (i). Returns shape
        ``s.shape + (n_root, n_root)``.
        """
        r = self.n_root
        s = np.asarray(s, dtype=complex)[..., None, None]
        Z = self.mass * s**2 + self.damping * s + self.stiffness
        Zrr, Zri, Zir, Zii = Z[..., :r, :r], Z[..., :r, r:], Z[..., r:, :r], Z[..., r:, r:]
        if self.n == r:
            return Zrr
        try:
            return Zrr - Zri @ np.linalg.solve(Zii, Zir)
        except np.linalg.LinAlgError:
            pass
        # some s is exactly a natural frequency with the attachment end clamped (Z_ii
        # singular in floating point): D is infinite there; the others are solved one by one
        D = np.empty(Zrr.shape, dtype=complex)
        flat_D, flat = D.reshape(-1, r, r), np.broadcast_to(Z, Z.shape).reshape(-1, *Z.shape[-2:])
        for k, Zk in enumerate(flat):
            try:
                flat_D[k] = Zk[:r, :r] - Zk[:r, r:] @ np.linalg.solve(Zk[r:, r:], Zk[r:, :r])
            except np.linalg.LinAlgError:
                flat_D[k] = np.inf
        return D


#: Where each motion's root coordinates go in a three-axis root model, and their signs:
#: the x-y plane's (delta, phi) are (v, theta_z); the x-z plane's are (w, -theta_y), since
#: theta_y = -dw/dx (a rotation about +y turns +x towards -z); torsion theta_x; axial u.
_THREE_AXIS_LAYOUT = (("xy", (1, 5), (1.0, 1.0)), ("xz", (2, 4), (1.0, -1.0)),
                      ("torsion", (3,), (1.0,)), ("axial", (0,), (1.0,)))


def place_bending_planes(out: np.ndarray, xy: np.ndarray, xz: np.ndarray) -> None:
    """Write the two bending planes' planar 2x2 matrices into 6x6 ones (``W6``/``D6``), in place.

    The x-y plane's ``(delta, phi)`` are ``(v, theta_z)``, rows and columns (1, 5) of the
    :data:`ROOT_MOTIONS` order; the x-z plane's are ``(w, -theta_y)``, rows and columns
    (2, 4), so its off-diagonal entry changes sign (``theta_y = -dw/dx``), the layout of
    :func:`three_axis_root_model`. The other entries of ``out`` are left as they are.

    Parameters
    ----------
    out : ndarray, shape (..., 6, 6)
        The three-axis matrices, written in place.
    xy, xz : ndarray, shape (..., 2, 2)
        Each plane's matrix in the planar convention: a compliance W (entries in m/N, 1/N and
        rad/(N*m)) or a dynamic stiffness D (their inverses), stacked like ``out``.
    """
    out[..., 1, 1], out[..., 5, 5] = xy[..., 0, 0], xy[..., 1, 1]
    out[..., 1, 5] = out[..., 5, 1] = xy[..., 0, 1]
    out[..., 2, 2], out[..., 4, 4] = xz[..., 0, 0], xz[..., 1, 1]
    out[..., 2, 4] = out[..., 4, 2] = -xz[..., 0, 1]


def three_axis_root_model(xy: RootModel, xz: RootModel, torsion: RootModel,
                          axial: RootModel) -> RootModel:
    """A three-axis root model from the four decoupled motions of a straight appendage.

    A straight appendage whose section is symmetric (shear centre on the axis, principal axes
    along local y and z) moves, to first order, in four uncoupled ways: bending in the x-y
    plane, bending in the x-z plane, torsion and axial motion. Each is realised on its own
    (planar models with ``n_root = 2`` and the planar sign conventions; rods with
    ``n_root = 1``); this function places them in one model with the root coordinates
    ``(u, v, w, theta_x, theta_y, theta_z)`` first (:data:`ROOT_MOTIONS`), then the
    internal coordinates of each motion in the order of the arguments.

    The x-z plane is written in the planar convention (``delta = w(0)``, ``phi = dw/dx(0)``,
    loads ``F_z`` and the moment conjugate to ``dw/dx``, which is ``-M_y``); with
    ``theta_y = -phi`` its coordinates are mapped by ``S = diag(1, -1, 1, ...)``, so its
    matrices become ``S M S`` (the couplings between ``w`` and ``theta_y`` change sign) and
    its tip row ``tip S``.

    Parameters
    ----------
    xy, xz : RootModel
        Planar models (``n_root = 2``) of the bending in each plane.
    torsion, axial : RootModel
        Rod models (``n_root = 1``): a rigid motion is a 1x1 model with the rigid inertia.

    Returns
    -------
    RootModel
        ``n_root = 6``; ``tip`` has three rows (:data:`TIP_MOTIONS`); internal coordinates
        are named ``xy.<name>``, ``xz.<name>``, ``torsion.<name>``, ``axial.<name>``.
    """
    parts = {"xy": xy, "xz": xz, "torsion": torsion, "axial": axial}
    for name, rm in parts.items():
        n_root = 2 if name in ("xy", "xz") else 1
        if not isinstance(rm, RootModel):
            raise TypeError(f"{name} must be a RootModel (n_root = {n_root}); got "
                            f"{type(rm).__name__} {describe(rm)}")
        if rm.n_root != n_root:
            raise ValueError(f"{name} must be a RootModel with n_root = {n_root}; got "
                             f"n_root = {rm.n_root}")
    n = 6 + sum(rm.n - rm.n_root for rm in parts.values())
    M, C, K = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    tip = np.zeros((3, n))
    names = list(ROOT_MOTIONS)
    offset = 6
    for label, root_index, root_sign in _THREE_AXIS_LAYOUT:
        rm = parts[label]
        if rm.n_root != len(root_index):
            raise ValueError(f"the {label} part must have n_root = {len(root_index)}; got "
                             f"{rm.n_root}")
        n_internal = rm.n - rm.n_root
        index = np.concatenate([root_index, offset + np.arange(n_internal)]).astype(int)
        sign = np.concatenate([root_sign, np.ones(n_internal)])
        flip = np.outer(sign, sign)
        block = np.ix_(index, index)
        M[block] += rm.mass * flip
        C[block] += rm.damping * flip
        K[block] += rm.stiffness * flip
        row = {"xy": 0, "xz": 1, "torsion": 2}.get(label)
        if row is not None:
            tip[row, index] = np.asarray(rm.tip, dtype=float).reshape(-1) * sign
        names += [f"{label}.{c}" for c in rm.coordinate_names[rm.n_root:]]
        offset += n_internal
    return RootModel(M, C, K, tip, tuple(names), n_root=6)


class FiniteAppendage:
    """Base of appendage models with a finite number of degrees of freedom.

    Subclasses implement :meth:`_root_model` (and the properties ``length``, ``mass``,
    ``inertia``); this class derives from it W(s), the poles, the zeros and gains of every W_r,
    and a python-control state-space model, the paper's quantities (eq. (4)) [1]_.

    References
    ----------
    .. [1] Belonozhko et al. 2009, see :mod:`appendages.interface`.
    """

    def _root_model(self) -> RootModel:  # pragma: no cover - abstract
        raise NotImplementedError

    def _three_axis_root_model(self) -> RootModel:
        """The three-axis realisation (n_root = 6); planar-only models do not have one."""
        raise ValueError(f"{type(self).__name__} is a planar model: it has no three-axis "
                         "realisation (W6, root_model(n_root=6))")

    def root_model(self, n_root: int = 2) -> RootModel:
        """The realisation of W(s) in attachment-end coordinates (computed once).

        Parameters
        ----------
        n_root : {2, 6}
            2: the planar model (x-y plane: ``delta``, ``phi``); 6: the three-axis model
            (root motions :data:`ROOT_MOTIONS`), for models that have one.
        """
        if isinstance(n_root, (bool, np.bool_)) or n_root not in (2, 6):
            raise ValueError(f"n_root must be 2 (planar) or 6 (three axes); got "
                             f"{describe(n_root)}")
        key = "_root_model_cache" if n_root == 2 else "_root_model6_cache"
        cached = self.__dict__.get(key)
        if cached is None:
            cached = self._root_model() if n_root == 2 else self._three_axis_root_model()
            self.__dict__[key] = cached
        return cached

    def dynamic_stiffness6(self, s) -> np.ndarray:
        """Three-axis attachment-end dynamic stiffness D6(s) = W6(s)^-1, shape ``(..., 6, 6)``.

        Root loads (:data:`ROOT_LOADS`) per unit root motion (:data:`ROOT_MOTIONS`), beam
        axes, by static condensation of :meth:`root_model` (n_root=6). s = 0 gives 0.
        """
        s = as_frequency_array(s)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return self.root_model(6).dynamic_stiffness(s)

    def W6(self, s) -> np.ndarray:
        """Three-axis transfer matrix W6(s) of the free appendage, shape ``np.shape(s) + (6, 6)``.

        Root motions ``(u, v, w, theta_x, theta_y, theta_z)`` caused by root loads
        ``(F_x, F_y, F_z, M_x, M_y, M_z)`` at x = 0, beam axes, rigid-body motion included.

        Parameters
        ----------
        s : complex or array_like of complex, rad/s
            Laplace variable, not 0 (the rigid-body pole).
        """
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError("s = 0 is the rigid-body pole of W6 (W6 is infinite there) [rad/s]")
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            W = inverse_symmetric(self.root_model(6).dynamic_stiffness(s))
        if not np.all(np.isfinite(W)):
            raise ValueError("s is a natural frequency of the undamped model: W6 is infinite "
                             "there [rad/s]")
        return W

    # -- W(s) ---------------------------------------------------------------------------------
    def W(self, s) -> np.ndarray:
        """Transfer matrix W(s) of the free appendage [m/N, 1/N; 1/N, 1/(N*m)].

        Parameters
        ----------
        s : complex or array_like of complex, rad/s
            Laplace variable. ``s = 0`` is a pole (rigid-body motion).

        Returns
        -------
        ndarray of complex128, shape ``np.shape(s) + (2, 2)``
        """
        s = as_frequency_array(s)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            W = inverse_2x2(self.root_model().dynamic_stiffness(s))
        if not np.all(np.isfinite(W)):
            raise ValueError("s is a natural frequency of the undamped model (or the rigid-body "
                             "pole s = 0): W is infinite there [rad/s]")
        return W

    # -- poles, zeros, gains ------------------------------------------------------------------
    @staticmethod
    def _pencil_frequencies(K: np.ndarray, M: np.ndarray, n_rigid: int) -> np.ndarray:
        """Non-zero undamped frequencies [rad/s] of ``(K - w**2 M) v = 0``, ascending.

        M may be singular (massless coordinates, a Lagrange multiplier row) and K singular
        (rigid-body modes); both are symmetric. Infinite eigenvalues are recognised in the
        homogeneous form (alpha, beta) with each part measured against its own matrix norm.
        The ``n_rigid`` smallest finite eigenvalues are the rigid-body ones (their number is
        known from the mechanics: 2 for a free appendage, 1 pinned or with the rotation
        held); they are dropped by count, not by a threshold, so a wide spectrum (a first
        eigenvalue 1e-12 of the last) keeps its genuine low modes. A "rigid" eigenvalue that
        is not small (above 1e-6 of the largest) is a model without that rigid-body mode and
        is kept.
        """
        if K.shape[0] == 0:
            return np.zeros(0)
        d = equilibrate(K, M)
        K, M = K * np.outer(d, d), M * np.outer(d, d)
        alpha, beta = scipy.linalg.eigvals(K, M, homogeneous_eigvals=True)
        k_norm = max(np.abs(K).max(), 1e-300)
        m_norm = max(np.abs(M).max(), 1e-300)
        finite = np.abs(beta) / m_norm > 1e-13 * np.abs(alpha) / k_norm
        values = np.sort((alpha[finite] / beta[finite]).real)
        if values.size == 0:
            return np.zeros(0)
        scale = np.abs(values).max()
        by_size = np.argsort(np.abs(values))
        rigid = [i for i in by_size[:n_rigid] if abs(values[i]) <= 1e-6 * scale]
        values = np.delete(values, rigid)
        if np.any(values <= 0):
            raise ValueError(
                "the model has a negative or zero eigenvalue besides its rigid-body modes "
                f"(smallest {values.min()!r} [rad^2/s^2]): a mechanism or a stiffness range too "
                "wide for double precision"
            )
        return np.sqrt(values)

    def poles(self) -> np.ndarray:
        """Undamped natural frequencies w_k of the free appendage [rad/s], ascending.

        The rigid-body modes (double pole at s = 0) are left out.
        """
        rm = self.root_model()
        cached = self.__dict__.get("_poles_cache")
        if cached is None:
            cached = self._pencil_frequencies(rm.stiffness, rm.mass, 2)
            self.__dict__["_poles_cache"] = cached
        return cached.copy()

    def zeros(self, r: int) -> np.ndarray:
        """Undamped zero frequencies n_r of W_r [rad/s], ascending (r = 1, 2, 3, 4).

        W_r(i n) = 0 at these frequencies. For W1 they are the natural frequencies with the
        attachment end pinned (delta = 0); for W4 with its rotation held (phi = 0); for W2 = W3
        the transmission zeros of the force-to-rotation path, from the Rosenbrock pencil
        ``[[K - n**2 M, b], [c^T, 0]]``. Zeros at s = 0 (cancelled by the rigid-body poles) are
        left out.
        """
        if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r not in (1, 2, 3, 4):
            raise ValueError(f"r must be 1, 2, 3 or 4 (W1, W2, W3, W4); got {describe(r)}")
        rm = self.root_model()
        n = rm.n
        out_index, in_index = {1: (0, 0), 2: (0, 1), 3: (1, 0), 4: (1, 1)}[r]
        # Rosenbrock pencil (A - lambda E) with lambda = n**2 = -s**2.
        A = np.zeros((n + 1, n + 1))
        E = np.zeros((n + 1, n + 1))
        A[:n, :n] = rm.stiffness
        E[:n, :n] = rm.mass
        A[in_index, n] = 1.0
        A[n, out_index] = 1.0
        return self._pencil_frequencies(A, E, 1)

    def gains(self) -> np.ndarray:
        """High-frequency gains k_r = lim s**2 W_r(s), r = 1..4 [m/(N s^2), 1/(N s^2), ...].

        For a model with a mass matrix M these are the attachment-end block of M^-1 (the
        paper's k_1, k_2 = k_3, k_4). Raises ValueError for a model with a massless attachment
        end (W tends to a constant flexibility, the gains are infinite).
        """
        rm = self.root_model()
        # scaled to unit diagonal (units do not change the condition that matters)
        d = equilibrate(rm.stiffness, rm.mass)
        scaled = rm.mass * np.outer(d, d)
        try:
            inv = np.linalg.inv(scaled) * np.outer(d, d)
        except np.linalg.LinAlgError:
            inv = None
        if inv is None or not np.all(np.isfinite(inv)) or np.linalg.cond(scaled) > 1e14:
            raise ValueError(
                "gains are undefined for a model whose attachment end carries no mass "
                "(W(s) tends to a constant flexibility as s -> infinity)"
            )
        return np.array([inv[0, 0], inv[0, 1], inv[0, 1], inv[1, 1]])

    # -- realisation --------------------------------------------------------------------------
    def state_space(self, *, tip: bool = False, name: str | None = None):
        """python-control StateSpace of W: inputs ``F_y``, ``M``; outputs ``delta``, ``phi``.

        Built in modal coordinates of the free appendage (mass-normalised mode shapes of
        ``K v = w**2 M v``), states ``[eta, eta_dot]``: A = [[0, I], [-Omega**2, -V^T C V]],
        a well-scaled realisation for any number of modes. Massless coordinates (a spring at
        the mount) are condensed statically, which gives W a constant part (D != 0).

        Parameters
        ----------
        tip : bool
            Also output ``tip_deflection`` [m] (elastic, relative to the attachment-end tangent).
        name : str, optional
            System name.
        """
        import control

        rm = self.root_model()
        M, C, K = rm.mass, rm.damping, rm.stiffness
        n = rm.n
        out_rows = np.zeros((3, n))
        out_rows[0, 0] = out_rows[1, 1] = 1.0
        out_rows[2] = rm.tip
        load = np.zeros((n, 2))
        load[0, 0] = load[1, 1] = 1.0
        massless = np.flatnonzero(np.all(rm.mass == 0.0, axis=1))
        feedthrough = np.zeros((3, 2))
        if massless.size:
            if np.any(C[massless] != 0.0):
                raise ValueError(
                    "state_space() of a free appendage cannot condense a damped massless "
                    "coordinate (a damped root hinge); couple it to a hub instead"
                )
            keep = np.setdiff1d(np.arange(n), massless)
            Kmm, Kmk = K[np.ix_(massless, massless)], K[np.ix_(massless, keep)]
            # q_m = Kmm^-1 (f_m - Kmk q_k): exact for massless, undamped coordinates.
            G = np.linalg.solve(Kmm, np.hstack([Kmk, load[massless]]))
            Gq, Gf = G[:, : keep.size], G[:, keep.size:]
            Kk = K[np.ix_(keep, keep)] - K[np.ix_(keep, massless)] @ Gq
            load_k = load[keep] - K[np.ix_(keep, massless)] @ Gf
            feedthrough = out_rows[:, massless] @ Gf
            out_rows = out_rows[:, keep] - out_rows[:, massless] @ Gq
            M, C, K, load = M[np.ix_(keep, keep)], C[np.ix_(keep, keep)], 0.5 * (Kk + Kk.T), load_k
        d = equilibrate(K, M)
        lam, V = scipy.linalg.eigh(K * np.outer(d, d), M * np.outer(d, d))
        V = V * d[:, None]
        # the two smallest are the free appendage's rigid-body modes (zero up to round-off)
        lam[:2] = np.where(np.abs(lam[:2]) <= 1e-6 * np.abs(lam).max(initial=0.0), 0.0, lam[:2])
        m = lam.size
        A = np.block([[np.zeros((m, m)), np.eye(m)], [-np.diag(lam), -(V.T @ C @ V)]])
        B = np.vstack([np.zeros((m, 2)), V.T @ load])
        Cout = np.hstack([out_rows @ V, np.zeros((3, m))])
        outputs = ["delta", "phi", "tip_deflection"]
        rows = 3 if tip else 2
        states = [f"eta[{k}]" for k in range(m)] + [f"eta_dot[{k}]" for k in range(m)]
        return control.ss(
            A, B, Cout[:rows], feedthrough[:rows], inputs=["F_y", "M"], outputs=outputs[:rows],
            states=states, name=name,
        )
