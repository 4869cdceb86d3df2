r"""Exact root dynamics of a beam of uniform segments carrying a tip body.

A straight beam made of uniform segments joined end to end from the root (node 0, x = 0) to the
free end (node n), with a rigid body fixed to the free end (:mod:`appendages.tip`), is described
exactly at any Laplace variable s by the segments' member dynamic stiffness matrices
(:mod:`appendages.members`) assembled at the nodes. Condensing every node but the root gives the
root's dynamic stiffness D(s) (loads per root motion) and W(s) = D(s)^-1. No transfer matrix is
multiplied along the beam: each member matrix is bounded at any |s| (scaled exponentials), and
the condensation is a block Gaussian elimination from the tip to the root.

Degrees of freedom
------------------
The root carries ``d`` motions: planar ``(v, theta_z)`` (x-y bending, the planar interface's
``(delta, phi)``), three-axis ``(u, v, w, theta_x, theta_y, theta_z)``. Every other node carries
the elastic motions only: planar ``(v, theta_z)``; three-axis ``(v, theta_z)``, ``(w, theta_y)``,
and ``theta_x``, ``u`` where the segments are torsionally and axially elastic. A torsionally
rigid or inextensible beam moves rigidly in that motion: its inertia (``rho*I_p L``, ``rho*A L``)
goes to the root, and the tip body sees the root's motion. The x-z plane's member matrices are
written in ``(w, dw/dx)`` and mapped with ``theta_y = -dw/dx``.

Two forms of the same algebra
-----------------------------
The block matrix (root r, nodes e_1..e_n) is block tridiagonal in the nodes, with a border to the
root; eliminating e_n, ..., e_1 leaves ``D = R``::

    R -= C_j^T S_j^-1 C_j,   S_(j-1) -= B_j S_j^-1 B_j^T,   C_(j-1) -= B_j S_j^-1 C_j.

* Absolute coordinates (node motions as they are) at high |s|: the border is only the first
  segment's (and, in three axes, the tip body's coupling to rigid motions).
* Relative coordinates ``e_j = u_j - T(x_j) r`` (motion relative to the root's rigid motion) at
  low |s|: each member's static stiffness K0 annihilates rigid motion exactly, so it acts on the
  e's alone, and only the dynamic part ``s**2 M(s) = K(s) - K0`` (a series at small |x|) reaches
  the root; then ``D = s**2 A_rr - s**4 A_re (K0_ee + s**2 A_ee)^-1 A_er`` with ``A_rr(0)`` the
  rigid mass matrix about the root: the rigid limit ``W -> A_rr^-1/s**2`` is exact, with no
  cancellation of static stiffness against inertia (which costs the absolute form
  ``K0/(|s|**2 m)`` in relative accuracy).

The relative form loses ``|s|**2 m/K_c`` (inertia against the cantilever's stiffness, a heavy tip
body pinning the tip), the absolute one ``K0_max/(|s|**2 m)`` (the stiffest segment's static
stiffness against the inertia); each point takes the form with the smaller loss, at most
``sqrt(K0_max/K_c)`` (about 3.5 for one segment, growing like n**1.5 with n equal segments).

Wittrick-Williams count
-----------------------
At s = i w (undamped, real symmetric) the number of natural frequencies below w of the structure
with the root held in the motions F held fixed is ``J0 + sum_j s{S_j} + s{R_FF} - n_rigid``: J0
the members' clamped-clamped frequencies below w, s{.} the negative eigenvalues of the pivots of
the elimination (Sylvester's law of inertia), n_rigid the rigid-body modes that the held motions
leave (counted below any w > 0). Bisection on the count finds every frequency, none missed.

Modes by contour integrals
--------------------------
The modal data that truncations and modal damping need come from residues of exact functions,
evaluated on a circle of radius ``rho`` (a quarter of the gap to the nearest other pole) around
each eigenvalue ``lambda_k = w_k**2`` with the trapezoidal rule (32 points: error
``(rho/gap)**32 < 1e-19``)::

    free-free:   res W = -sum b_k b_k^T,       res H = -sum phi_k(tip) b_k^T
    cantilever:  res D = lambda_k**2 sum l_k l_k^T,   res G = -lambda_k sum psi_k(tip) l_k^T

(residues in lambda = -s**2; H: tip motions per root load, G: tip motions per root motion with the
root driven, the clamped problem; b_k root values of mass-normalised free-free modes, l_k the
cantilever modes' participation factors ``psi_k^T M D``). A cluster of equal frequencies (the
two bending planes of a round section) shares one circle; its modes are the eigenvectors of the
residue. No derivative of a determinant, no mode shape integral.

Static expansion
----------------
The static flexibility of the free beam and the next term, ``G = sum b b^T/w**2`` and
``G2 = sum b b^T/w**4``, follow from the relative form's series
``D = s**2 M + s**4 X + s**6 Y + ...``: ``G = -M^-1 X M^-1``, ``G2 = M^-1 (Y - X M^-1 X) M^-1``,
exact (the residual truncation's tails are G and G2 minus the kept modes).

References
----------
.. [1] W. H. Wittrick, F. W. Williams, "A general algorithm for computing natural frequencies of
   elastic structures", Q. J. Mech. Appl. Math. 24(3), 1971.
.. [2] F. W. Williams, D. Kennedy, "Reliable use of determinants to solve non-linear structural
   eigenvalue problems efficiently", Int. J. Numer. Meth. Eng. 26, 1988.
.. [3] R. R. Craig, A. J. Kurdila, "Fundamentals of Structural Dynamics", 2nd ed., Wiley, 2006,
   ch. 14 and 17 (static condensation, participation factors, residual flexibility).
.. [4] L. N. Trefethen, J. A. C. Weideman, "The exponentially convergent trapezoidal rule",
   SIAM Review 56(3), 2014 (contour integrals of analytic functions).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from . import members
from .checks import check_positive
from .errors import ConvergenceError, describe
from .interface import inverse_symmetric

__all__ = ["BeamAssembly", "Segment", "CONTOUR_POINTS", "check_segments"]

#: Trapezoidal points on each residue circle.
CONTOUR_POINTS = 32
#: Relative gap below which natural frequencies form one cluster (one residue circle).
_CLUSTER = 1e-9
#: Frequencies evaluated at once (bounded memory).
_CHUNK = 8192
#: Where each segment is split into two elements (fraction of its length from its start).
_GOLDEN = 0.5 * (math.sqrt(5.0) - 1.0)


class Segment(NamedTuple):
    """A uniform segment's properties [SI]; None where the beam is planar, torsionally rigid
    or inextensible."""

    length: float
    bending_stiffness: float
    linear_density: float
    bending_stiffness_y: float | None = None
    torsional_stiffness: float | None = None
    torsional_inertia: float | None = None
    axial_stiffness: float | None = None


_UNITS = {"length": "m", "bending_stiffness": "N*m^2", "linear_density": "kg/m",
          "bending_stiffness_y": "N*m^2", "torsional_stiffness": "N*m^2",
          "torsional_inertia": "kg*m", "axial_stiffness": "N"}


def check_segments(segments, three_axis: bool = False) -> list:
    """The segments as a list of :class:`Segment`, every value positive and finite (None allowed
    for the three-axis ones), or TypeError/ValueError naming ``segments[k].<property>``.
    Three axes: every segment has the x-z plane's stiffness and the torsional inertia, and the
    torsional and axial stiffnesses are given for all segments or for none."""
    if isinstance(segments, (str, bytes)) or not hasattr(segments, "__len__") or not segments:
        raise ValueError(f"segments must be a non-empty sequence of Segment; got "
                         f"{describe(segments)}")
    out = []
    for k, segment in enumerate(segments):
        try:
            segment = Segment(*segment)
        except TypeError:
            raise TypeError(f"segments[{k}] must be a Segment (length, bending_stiffness, "
                            f"linear_density, ...); got {describe(segment)}") from None
        values = {}
        for name, value in segment._asdict().items():
            values[name] = None if value is None else check_positive(
                f"segments[{k}].{name}", value, _UNITS[name])
        out.append(Segment(**values))
    if three_axis:
        for name in ("bending_stiffness_y", "torsional_inertia"):
            for k, seg in enumerate(out):
                if getattr(seg, name) is None:
                    raise ValueError(f"segments[{k}].{name} [{_UNITS[name]}] is needed by a "
                                     "three-axis model; got None")
        for name in ("torsional_stiffness", "axial_stiffness"):
            given = [getattr(seg, name) is not None for seg in out]
            if any(given) and not all(given):
                k = given.index(not given[0])
                raise ValueError(f"segments[{k}].{name} [{_UNITS[name]}] must be given for every "
                                 "segment or for none (rigid in that motion)")
    return out


def _solve(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """np.linalg.solve on stacked systems; a system that is singular to the last bit (a
    frequency exactly on a pole of the recursion) gets a perturbation of one rounding of its
    norm instead of failing the whole stack."""
    try:
        return np.linalg.solve(A, B)
    except np.linalg.LinAlgError:
        out = np.empty(A.shape[:-1] + B.shape[-1:], dtype=np.result_type(A, B))
        for i in range(A.shape[0]):
            try:
                out[i] = np.linalg.solve(A[i], B[i])
            except np.linalg.LinAlgError:
                shift = np.finfo(float).eps * max(float(np.abs(A[i]).max()), 1e-300)
                out[i] = np.linalg.solve(A[i] + shift * np.eye(A.shape[-1]), B[i])
        return out


def _neg_count(A: np.ndarray) -> np.ndarray:
    """Negative eigenvalues of real symmetric matrices (stacked), each equilibrated first."""
    if A.shape[-1] == 0:
        return np.zeros(A.shape[:-2], dtype=np.int64)
    diagonal = np.abs(np.diagonal(A, axis1=-2, axis2=-1))
    scale = np.where(diagonal > 0, 1.0 / np.sqrt(np.where(diagonal > 0, diagonal, 1.0)), 1.0)
    A = A * scale[..., :, None] * scale[..., None, :]
    return (np.linalg.eigvalsh(0.5 * (A + np.swapaxes(A, -1, -2))) < 0).sum(axis=-1)


class BeamAssembly:
    """The exact root dynamics of uniform segments with a tip body (module docstring).

    Parameters
    ----------
    segments : sequence of Segment
        From the root; checked by the caller (three-axis: every segment has the x-z plane's
        stiffness and the torsional inertia, and all or none have GJ, all or none EA).
    tip_mass : ndarray, shape (n_root, n_root), or None
        The tip body's mass matrix about the free end (:meth:`TipBody.mass_matrix`).
    n_root : {1, 2, 6}
        2: the planar model (x-y bending); 6: three axes; 1: one rod motion alone
        (``rod_motion``).
    rod_motion : {"torsion", "axial"}, optional
        With ``n_root=1``: which motion (root ``theta_x`` or ``u``; the tip mass matrix is then
        the body's 1x1 moment about the axis or its mass).
    """

    def __init__(self, segments, tip_mass, n_root: int, rod_motion: str | None = None):
        # each segment as two elements split at the golden section: a uniform member's
        # clamped-clamped frequencies (the poles of its matrix) coincide with every free-free
        # frequency of the same member alone; split in an irrational ratio, no element's pole
        # falls on a frequency of the uniform beam (the closest, 0.056/k**2 relative at mode
        # k, costs the count eps k**2/0.056 there)
        if isinstance(n_root, (bool, np.bool_)) or n_root not in (1, 2, 6):
            raise ValueError(f"n_root must be 1 (a rod), 2 (planar) or 6 (three axes); got "
                             f"{describe(n_root)}")
        if n_root == 1 and rod_motion not in ("torsion", "axial"):
            raise ValueError(f"rod_motion must be 'torsion' or 'axial' with n_root=1; got "
                             f"{describe(rod_motion)}")
        self.segments = []
        for seg in check_segments(segments, three_axis=n_root == 6):
            self.segments += [seg._replace(length=seg.length * _GOLDEN),
                              seg._replace(length=seg.length * (1.0 - _GOLDEN))]
        self.n_root = n_root
        self.tip_mass = (np.zeros((n_root, n_root)) if tip_mass is None
                         else np.asarray(tip_mass, dtype=float))
        if self.tip_mass.shape != (n_root, n_root) or not np.all(np.isfinite(self.tip_mass)):
            raise ValueError(f"tip_mass must be a finite ({n_root}, {n_root}) mass matrix [SI]; "
                             f"got {describe(tip_mass)}")
        self.x = np.concatenate([[0.0], np.cumsum([seg.length for seg in self.segments])])
        self.length = float(self.x[-1])
        first = self.segments[0]
        if n_root == 1:
            needed = (("torsional_stiffness", "torsional_inertia") if rod_motion == "torsion"
                      else ("axial_stiffness",))
            for k, seg in enumerate(self.segments):
                for name in needed:
                    if getattr(seg, name) is None:
                        raise ValueError(f"segments[{k // 2}].{name} [{_UNITS[name]}] is needed "
                                         f"by the {rod_motion} rod; got None")
            self.motions = [(rod_motion, (0,), (1.0,))]
            self.rigid = []
        elif n_root == 2:
            self.motions = [("xy", (0, 1), (1.0, 1.0))]
            self.rigid = []
        else:
            self.motions = [("xy", (1, 5), (1.0, 1.0)), ("xz", (2, 4), (1.0, -1.0))]
            self.rigid = []
            if first.torsional_stiffness is not None:
                self.motions.append(("torsion", (3,), (1.0,)))
            else:
                self.rigid.append((3, "torsional_inertia"))
            if first.axial_stiffness is not None:
                self.motions.append(("axial", (0,), (1.0,)))
            else:
                self.rigid.append((0, "linear_density"))
        # elastic degrees of freedom of a node, as root indices, and where each motion sits
        self.elastic = [i for _, dofs, _ in self.motions for i in dofs]
        self.n_elastic = len(self.elastic)
        self.embed = np.zeros((n_root, self.n_elastic))   # root vector <- elastic node vector
        self.embed[self.elastic, np.arange(self.n_elastic)] = 1.0
        self.rigid_select = np.zeros((n_root, n_root))
        for index, _ in self.rigid:
            self.rigid_select[index, index] = 1.0
        self.tip_rows = [0] if n_root <= 2 else [1, 2, 3]
        self._cache: dict = {}
        self._set_scales()

    # -- kinematics -----------------------------------------------------------------------------
    def transfer(self, x: float) -> np.ndarray:
        """T(x): the motions at x of a rigid motion of the root, shape (d, d)."""
        T = np.eye(self.n_root)
        if self.n_root == 1:
            return T
        if self.n_root == 2:
            T[0, 1] = x
        else:
            T[1, 5] = x       # v = v0 + x theta_z
            T[2, 4] = -x      # w = w0 - x theta_y
        return T

    # -- member matrices on a node pair's elastic motions ---------------------------------------
    def _motion_member(self, seg: Segment, motion: str, s, part: str):
        if motion in ("xy", "xz"):
            EJ = seg.bending_stiffness if motion == "xy" else seg.bending_stiffness_y
            if part == "static":
                return members.bending_static_stiffness(seg.length, EJ)
            if part == "series":
                return members.bending_mass_series(seg.length, EJ, seg.linear_density)
            return members.bending_member(seg.length, EJ, seg.linear_density, s, part)
        S, mu = ((seg.torsional_stiffness, seg.torsional_inertia) if motion == "torsion"
                 else (seg.axial_stiffness, seg.linear_density))
        if part == "static":
            return members.rod_static_stiffness(seg.length, S)
        if part == "series":
            return members.rod_mass_series(seg.length, S, mu)
        return members.rod_member(seg.length, S, mu, s, part)

    def _member(self, seg: Segment, s, part: str) -> np.ndarray:
        """The segment's matrix on (a-end elastic, b-end elastic), shape (..., 2de, 2de)."""
        de = self.n_elastic
        shape = () if part == "static" else ((3,) if part == "series" else s.shape)
        dtype = float if part in ("static", "series") else np.complex128
        out = np.zeros(shape + (2 * de, 2 * de), dtype=dtype)
        start = 0
        for motion, dofs, signs in self.motions:
            k = len(dofs)
            block = self._motion_member(seg, motion, s, part)
            sign = np.array(signs * 2)
            block = block * sign[:, None] * sign[None, :]
            index = np.concatenate([start + np.arange(k), de + start + np.arange(k)])
            out[..., index[:, None], index[None, :]] = block
            start += k
        return out

    def _rigid_inertia(self, seg: Segment) -> np.ndarray:
        """The rigid motions' inertia of a segment on the root, shape (d, d)."""
        out = np.zeros((self.n_root, self.n_root))
        for index, attribute in self.rigid:
            out[index, index] = getattr(seg, attribute) * seg.length
        return out

    # -- scales and the choice of form ----------------------------------------------------------
    def _set_scales(self) -> None:
        """The frequency below which the relative form is used (module docstring)."""
        switches = []
        m_tip = self.tip_mass
        for motion, dofs, _ in self.motions:
            segs = self.segments
            if motion in ("xy", "xz"):
                EJ = [s.bending_stiffness if motion == "xy" else s.bending_stiffness_y
                      for s in segs]
                k_max = max(12.0 * e / s.length**3 for e, s in zip(EJ, segs))
                # tip deflection of the cantilever under a tip force: int (L - x)**2/EJ dx
                L = self.length
                flex = sum(((L - a) ** 3 - (L - b) ** 3) / (3.0 * e)
                           for e, a, b in zip(EJ, self.x[:-1], self.x[1:]))
                mass = sum(s.linear_density * s.length for s in segs) + m_tip[dofs[0], dofs[0]]
                k_c = 1.0 / flex
            else:
                S = [s.torsional_stiffness if motion == "torsion" else s.axial_stiffness
                     for s in segs]
                mu = [s.torsional_inertia if motion == "torsion" else s.linear_density
                      for s in segs]
                k_max = max(e / s.length for e, s in zip(S, segs))
                k_c = 1.0 / sum(s.length / e for e, s in zip(S, segs))
                mass = sum(m * s.length for m, s in zip(mu, segs)) + m_tip[dofs[0], dofs[0]]
            switches.append((k_max * k_c) ** 0.25 / math.sqrt(mass))
        self.switch = min(switches)

    # -- the elimination ------------------------------------------------------------------------
    def _pieces(self, s: np.ndarray, relative: bool, real: bool):
        """R, S_j, C_j, B_j before elimination at the points s (flat)."""
        d, de, n = self.n_root, self.n_elastic, len(self.segments)
        npts = s.size
        dtype = float if real else np.complex128
        s2 = (s**2).real if real else s**2
        R = np.zeros((npts, d, d), dtype=dtype)
        S = [None] + [np.zeros((npts, de, de), dtype=dtype) for _ in range(n)]
        C = [None] + [np.zeros((npts, de, d), dtype=dtype) for _ in range(n)]
        B = [None] * (n + 1)
        E = self.embed
        for j, seg in enumerate(self.segments, start=1):
            R += s2[:, None, None] * self._rigid_inertia(seg)
            if not relative:
                K = self._member(seg, s, "full")
                K = K.real if real else K
                Kaa, Kab, Kba, Kbb = K[:, :de, :de], K[:, :de, de:], K[:, de:, :de], K[:, de:, de:]
                if j == 1:
                    R += E @ Kaa @ E.T
                    C[1] += Kba @ E.T
                else:
                    S[j - 1] += Kaa
                    B[j] = Kab
                S[j] += Kbb
            else:
                K0 = self._member(seg, s, "static")
                M = self._member(seg, s, "dynamic")
                M = M.real if real else M
                Tab = np.vstack([self.transfer(self.x[j - 1])[self.elastic],
                                 self.transfer(self.x[j])[self.elastic]])
                MT = M @ Tab
                R += s2[:, None, None] * (Tab.T @ MT)
                sM = s2[:, None, None] * M
                sMT = s2[:, None, None] * MT
                if j > 1:
                    S[j - 1] += K0[:de, :de] + sM[:, :de, :de]
                    C[j - 1] += sMT[:, :de]
                    B[j] = K0[:de, de:] + sM[:, :de, de:]
                S[j] += K0[de:, de:] + sM[:, de:, de:]
                C[j] += sMT[:, de:]
        Gr = self.transfer(self.length) if relative else self.rigid_select
        Mt = self.tip_mass
        if np.any(Mt):
            R += s2[:, None, None] * (Gr.T @ Mt @ Gr)
            C[n] += s2[:, None, None] * (E.T @ Mt @ Gr)
            S[n] += s2[:, None, None] * (E.T @ Mt @ E)
        return R, S, C, B, Gr

    def _eliminate(self, s: np.ndarray, relative: bool, *, real: bool = False,
                   count: bool = False, back: bool = False):
        """Condense the nodes at the points s (flat, one form): returns R (= D), the negative
        pivots (count) and, with ``back``, the tip node's motions per root motion (d, d)."""
        n = len(self.segments)
        R, S, C, B, Gr = self._pieces(s, relative, real)
        negative = np.zeros(s.size, dtype=np.int64)
        factors = []
        for j in range(n, 0, -1):
            if count:
                negative += _neg_count(S[j])
            rhs = C[j] if j == 1 else np.concatenate([C[j], np.swapaxes(B[j], -1, -2)], axis=-1)
            X = _solve(S[j], rhs)
            SinvC = X[..., :self.n_root]
            R -= np.swapaxes(C[j], -1, -2) @ SinvC
            if j > 1:
                SinvBt = X[..., self.n_root:]
                S[j - 1] -= B[j] @ SinvBt
                C[j - 1] -= B[j] @ SinvC
            else:
                SinvBt = None
            if back:
                factors.append((SinvC, SinvBt))
        R = 0.5 * (R + np.swapaxes(R, -1, -2))
        tip = None
        if back:
            # e_1 = -S1^-1 C1 r, e_j = -Sj^-1 (B_j^T e_(j-1) + C_j r): per unit root motion
            factors.reverse()
            e = -factors[0][0]
            for SinvC, SinvBt in factors[1:]:
                e = -(SinvBt @ e + SinvC)
            tip = Gr + self.embed @ e
        return R, negative, tip

    def _evaluate(self, s: np.ndarray, *, real: bool = False, count: bool = False,
                  back: bool = False):
        """Both forms over a flat s, each point in its form; chunked."""
        d = self.n_root
        dtype = float if real else np.complex128
        R = np.empty((s.size, d, d), dtype=dtype)
        negative = np.zeros(s.size, dtype=np.int64)
        tip = np.empty((s.size, d, d), dtype=dtype) if back else None
        relative = np.abs(s) < self.switch
        for form in (True, False):
            where = np.flatnonzero(relative == form)
            for start in range(0, where.size, _CHUNK):
                idx = where[start:start + _CHUNK]
                r, neg, t = self._eliminate(s[idx], form, real=real, count=count, back=back)
                R[idx] = r
                negative[idx] = neg
                if back:
                    tip[idx] = t
        return R, negative, tip

    # -- public evaluations ---------------------------------------------------------------------
    def root_stiffness(self, s: np.ndarray) -> np.ndarray:
        """Undamped D(s) = W(s)^-1 of the free beam, shape ``s.shape + (d, d)``; s = 0 gives 0.
        Infinite or NaN entries exactly at a member's clamped-clamped frequency (undamped)."""
        s = np.asarray(s, dtype=np.complex128)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            R, _, _ = self._evaluate(s.ravel())
        return R.reshape(s.shape + (self.n_root,) * 2)

    def root_and_tip(self, s: np.ndarray):
        """(D(s), tip motions per root motion (d, d)), flat s."""
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            R, _, tip = self._evaluate(np.asarray(s, dtype=np.complex128).ravel(), back=True)
        return R, tip

    # -- counts and frequencies -----------------------------------------------------------------
    def _member_count(self, omega: np.ndarray) -> np.ndarray:
        total = np.zeros(omega.shape, dtype=np.int64)
        for seg in self.segments:
            for motion, _, _ in self.motions:
                if motion in ("xy", "xz"):
                    EJ = seg.bending_stiffness if motion == "xy" else seg.bending_stiffness_y
                    total += members.bending_clamped_count(seg.length, EJ, seg.linear_density,
                                                           omega)
                else:
                    S, mu = ((seg.torsional_stiffness, seg.torsional_inertia)
                             if motion == "torsion" else (seg.axial_stiffness, seg.linear_density))
                    total += members.rod_clamped_count(seg.length, S, mu, omega)
        return total

    @staticmethod
    def _free_dofs(kind: str, d: int):
        if kind == "free":
            return list(range(d)), d
        if kind == "clamped":
            return [], 0
        if kind == "pinned":      # root translation held: rotation about the root is free
            return [1], 1
        if kind == "sliding":     # root rotation held: translation is free
            return [0], 1
        raise ValueError(f"kind must be 'free', 'clamped', 'pinned' or 'sliding' (how the root "
                         f"is held); got {describe(kind)}")

    def count(self, omega: np.ndarray, kind: str) -> np.ndarray:
        """Natural frequencies strictly below each omega [rad/s] with the root ``kind``
        ("free", "clamped", "pinned", "sliding"), rigid-body modes left out."""
        omega = np.asarray(omega, dtype=float).ravel()
        free, n_rigid = self._free_dofs(kind, self.n_root)
        if self.n_root != 2 and kind in ("pinned", "sliding"):
            raise ValueError(f"kind {kind!r} is planar; a three-axis model is 'free' or "
                             "'clamped'")
        out = np.empty(omega.size, dtype=np.int64)
        for start in range(0, omega.size, _CHUNK):
            w = omega[start:start + _CHUNK].copy()
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                R, negative, _ = self._evaluate(1j * w, real=True, count=True)
                bad = ~(np.all(np.isfinite(R), axis=(-2, -1)))
                step = 0
                while np.any(bad) and step < 30:  # a member's pole: its limit from below
                    step += 1
                    w[bad] *= 1.0 - 2.0**step * np.finfo(float).eps
                    R[bad], negative[bad], _ = self._evaluate(1j * w[bad], real=True, count=True)
                    bad = ~(np.all(np.isfinite(R), axis=(-2, -1)))
            root = _neg_count(R[:, free][:, :, free]) if free else 0
            if kind == "free" and self._chain_free:
                # above the switch: the elimination that ends inside the beam (see
                # _interior_pivots); below it the root-last count is sound
                high = np.abs(w) >= self.switch
                if np.any(high):
                    negative[high] = self._interior_pivots(w[high])
                    root = np.where(high, 0, root)
            total = self._member_count(w) + negative + root - n_rigid
            total[w <= 0] = 0
            out[start:start + _CHUNK] = np.maximum(total, 0)
        return out

    @property
    def _chain_free(self) -> bool:
        """True when the free structure is a plain chain of nodes in the absolute form: no
        rigid motion that the tip body couples to elastic ones."""
        if not self.rigid:
            return True
        coupling = self.rigid_select @ self.tip_mass @ self.embed
        return not np.any(coupling)

    def _interior_pivots(self, w: np.ndarray) -> np.ndarray:
        """Negative pivots of the free structure at s = i w (absolute form), eliminated from
        both ends towards the node nearest mid-length, which comes last.

        Eliminating towards the root (the root-last order of the condensation) ends on the
        root's dynamic stiffness, whose zero (a free-free frequency) lies within about
        exp(-x) of its pole (a clamped-root frequency: the free and the clamped root differ by
        half a wavelength, so free-free mode k and clamped mode k + 1 meet as k grows); the
        sign of its small eigenvalue is lost in the pole's rounding. An interior node held
        fixed gives no such coincidence.
        """
        n, de = len(self.segments), self.n_elastic
        s = 1j * w
        s2 = -(w**2)
        S = [np.zeros((w.size, de, de)) for _ in range(n + 1)]
        B = [None] * (n + 1)
        rigid = np.zeros((w.size, self.n_root, self.n_root))
        for j, seg in enumerate(self.segments, start=1):
            K = self._member(seg, s, "full").real
            S[j - 1] += K[:, :de, :de]
            B[j] = K[:, :de, de:]
            S[j] += K[:, de:, de:]
            rigid += s2[:, None, None] * self._rigid_inertia(seg)
        S[n] += s2[:, None, None] * (self.embed.T @ self.tip_mass @ self.embed)
        rigid += s2[:, None, None] * (self.rigid_select @ self.tip_mass @ self.rigid_select)
        m = int(np.argmin(np.abs(self.x - 0.5 * self.length)))
        m = min(max(m, 1), n - 1) if n > 1 else n
        negative = np.zeros(w.size, dtype=np.int64)
        for j in range(n, m, -1):                       # from the tip inwards
            negative += _neg_count(S[j])
            S[j - 1] -= B[j] @ _solve(S[j], np.swapaxes(B[j], -1, -2))
        for j in range(0, m):                           # from the root outwards
            negative += _neg_count(S[j])
            Bt = np.swapaxes(B[j + 1], -1, -2)
            S[j + 1] -= Bt @ _solve(S[j], B[j + 1])
        negative += _neg_count(S[m])
        if self.rigid:
            index = [i for i, _ in self.rigid]
            negative += _neg_count(rigid[:, index][:, :, index])
        return negative

    def frequencies(self, kind: str, n: int, rtol: float = 0.0) -> np.ndarray:
        """The first n natural frequencies [rad/s] with the root ``kind``, by bisection on the
        count to the last bit (cached; a longer list extends the cached one, from its last
        frequency up, and at least doubles it). ``rtol > 0``: brackets only that narrow
        (relative), cached apart: the centres of :meth:`modes`' residue circles."""
        self._free_dofs(kind, self.n_root)
        if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"n must be a positive integer (number of frequencies); got "
                             f"{describe(n)}")
        key = ("frequencies", kind, rtol)
        cached = self._cache.get(key)
        done = 0 if cached is None else cached.size
        if done >= n:
            return cached[:n]
        n_want = max(n + 1, 4, 2 * done)
        start = 0.0 if done == 0 else float(cached[-1]) * (1.0 - 1e-9)
        hi = max(self.switch, 2.0 * start)
        while self.count(np.array([hi]), kind)[0] < n_want:
            hi *= 2.0
        k = np.arange(done + 1, n_want + 1)
        # one shared coarse grid first: brackets of one grid cell for every new k
        low = start if done else hi * 1e-9
        grid = np.geomspace(low, hi, 4 * k.size + 64)
        counts = self.count(grid, kind)
        below = np.searchsorted(counts, k, side="left")  # first grid point with count >= k
        hi_w = grid[np.minimum(below, grid.size - 1)]
        lo_w = np.where(below > 0, grid[np.maximum(below - 1, 0)], 0.0)
        for _ in range(400):
            mid = np.where(lo_w > 0, np.sqrt(lo_w * hi_w), 0.5 * hi_w)
            active = (hi_w - lo_w) > max(rtol, 2.0 * np.finfo(float).eps) * hi_w
            if not np.any(active):
                break
            c = self.count(mid[active], kind)
            idx = np.flatnonzero(active)
            up = c >= k[idx]
            hi_w[idx[up]] = mid[active][up]
            lo_w[idx[~up]] = mid[active][~up]
        else:  # pragma: no cover - bisection halves every bracket
            raise ConvergenceError("the frequency bisection did not converge")
        new = 0.5 * (lo_w + hi_w)
        result = new if cached is None else np.concatenate([cached, new])
        self._cache[key] = result
        return result[:n]

    # -- modes ----------------------------------------------------------------------------------
    def _clusters(self, w: np.ndarray):
        """Groups of indices of w whose frequencies agree to _CLUSTER (relative)."""
        groups, current = [], [0]
        for k in range(1, w.size):
            if w[k] - w[current[-1]] <= _CLUSTER * w[k]:
                current.append(k)
            else:
                groups.append(current)
                current = [k]
        groups.append(current)
        return groups

    def modes(self, kind: str, n: int):
        """Modal data of the first n modes, root "free" or "clamped".

        Returns
        -------
        w : ndarray (n,), rad/s
        root : ndarray (n, d)
            free: root values b_k of mass-normalised modes; clamped: participation factors
            l_k (``psi_k^T M D``).
        tip : ndarray (n, len(tip_rows))
            The modes' tip-node values (absolute), rows :attr:`tip_rows`.
        """
        if kind not in ("free", "clamped"):
            raise ValueError(f"kind must be 'free' or 'clamped'; got {describe(kind)}")
        key = ("modes", kind)
        cached = self._cache.get(key)
        if cached is not None and cached[0].size >= n:
            return tuple(c[:n] for c in cached)
        done = 0 if cached is None else cached[0].size
        n_all = max(n, 16, 2 * done)
        # circles centred on brackets of 1e-7: the residues give the exact eigenvalue too
        w = self.frequencies(kind, n_all + 1, rtol=1e-7).copy()
        lam = w**2
        groups = self._clusters(w)
        d = self.n_root
        root = np.zeros((n_all, d))
        tip = np.zeros((n_all, len(self.tip_rows)))
        # the cached modes are kept, but for the last group of them (it may have grown)
        first_new = 0
        for group in groups:
            if done and group[0] <= done - 1 <= group[-1]:
                first_new = group[0]       # the last cached group is done again
                break
        if cached is not None:
            w[:first_new] = cached[0][:first_new]
            root[:first_new], tip[:first_new] = cached[1][:first_new], cached[2][:first_new]
        theta = 2.0 * math.pi * (np.arange(CONTOUR_POINTS) + 0.5) / CONTOUR_POINTS
        centres, radii, members_of = [], [], []
        for g, group in enumerate(groups):
            if group[0] < first_new:
                continue
            if group[0] >= n_all:
                break
            below = lam[groups[g - 1][-1]] if g > 0 else 0.0
            above = lam[groups[g + 1][0]] if g + 1 < len(groups) else 2.0 * lam[group[-1]]
            centre = float(np.mean(lam[group]))
            radius = 0.25 * min(lam[group[0]] - below, above - lam[group[-1]])
            centres.append(centre)
            radii.append(radius)
            members_of.append(group)
        if not centres:
            result = (w[:n_all], root, tip)
            self._cache[key] = result
            return tuple(r[:n] for r in result)
        centres, radii = np.array(centres), np.array(radii)
        points = centres[:, None] + radii[:, None] * np.exp(1j * theta)[None, :]  # lambda
        s = np.sqrt(-points.astype(np.complex128))      # any root: D is even in s
        D, Tip = self.root_and_tip(s.ravel())
        D = D.reshape(points.shape + (d, d))
        Tip = Tip.reshape(points.shape + (d, d))[..., self.tip_rows, :]
        weight = (radii[:, None] * np.exp(1j * theta)[None, :] / CONTOUR_POINTS)[..., None, None]
        if kind == "free":
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                F = inverse_symmetric(D)
            Tip = Tip @ F
        else:
            F = D
        # the eigenvalue: lambda_k = c + (sum (lambda - c) F w)/(sum F w) (first moment over
        # the residue, exact for a pole inside the circle; traces for a group)
        zeroth = np.sum(F * weight, axis=1)
        first = np.sum(F * (weight * (points - centres[:, None])[..., None, None]), axis=1)
        exact = centres + (np.trace(first, axis1=-2, axis2=-1)
                           / np.trace(zeroth, axis1=-2, axis2=-1)).real
        if kind == "free":
            residue = -zeroth.real                                   # sum b b^T
            residue_tip = -np.sum(Tip * weight, axis=1).real         # sum phi_tip b^T
        else:
            residue = zeroth.real / (exact**2)[:, None, None]        # sum l l^T
            residue_tip = -np.sum(Tip * weight, axis=1).real / exact[:, None, None]
        for c, group in enumerate(members_of):
            w[group] = math.sqrt(exact[c])
            P = 0.5 * (residue[c] + residue[c].T)
            values, vectors = np.linalg.eigh(P)
            m = len(group)
            values, vectors = values[::-1][:m], vectors[:, ::-1][:, :m]
            values = np.maximum(values, 0.0)
            for i, k in enumerate(group):
                if k >= n_all:
                    continue
                v = vectors[:, i]
                # a definite sign: the largest root component positive (the translation for
                # the planar uniform beam, as its closed forms)
                j = int(np.argmax(np.abs(v) * self._root_weights()))
                if v[j] < 0:
                    v = -v
                root[k] = v * math.sqrt(values[i])
                tip[k] = residue_tip[c] @ v / math.sqrt(values[i]) if values[i] > 0 else 0.0
        result = (w[:n_all], root, tip)
        self._cache[key] = result
        return tuple(r[:n] for r in result)

    def _root_weights(self) -> np.ndarray:
        """Scales that make root components comparable (rotations times the length)."""
        if self.n_root == 1:
            return np.ones(1)
        if self.n_root == 2:
            return np.array([1.0, 1e-3 * self.length])
        return np.array([1.0, 1.0, 1.0] + [1e-3 * self.length] * 3)

    # -- rigid properties and the static expansion ----------------------------------------------
    def _static_matrices(self):
        """Dense relative-form matrices at s -> 0: K0 (N, N) and A_k (3, N, N), N = d + n de."""
        cached = self._cache.get("static")
        if cached is not None:
            return cached
        d, de, n = self.n_root, self.n_elastic, len(self.segments)
        N = d + n * de
        K0 = np.zeros((N, N))
        A = np.zeros((3, N, N))

        def node(j):  # indices of node j's elastic motions (j >= 1)
            return d + (j - 1) * de + np.arange(de)

        for j, seg in enumerate(self.segments, start=1):
            A[0, :d, :d] += self._rigid_inertia(seg)
            K0_seg = self._member(seg, None, "static")
            series = self._member(seg, None, "series")       # (3, 2de, 2de)
            Tab = np.vstack([self.transfer(self.x[j - 1])[self.elastic],
                             self.transfer(self.x[j])[self.elastic]])
            # member coordinates (a, b) = Tab r + (e_(j-1), e_j), e_0 = 0
            P = np.zeros((2 * de, N))
            P[:, :d] = Tab
            if j > 1:
                P[:de, node(j - 1)] = np.eye(de)
            P[de:, node(j)] = np.eye(de)
            Pe = P.copy()
            Pe[:, :d] = 0.0
            K0 += Pe.T @ K0_seg @ Pe
            for k in range(3):
                A[k] += P.T @ series[k] @ P
        Pt = np.zeros((d, N))
        Pt[:, :d] = self.transfer(self.length)
        Pt[:, node(n)] = self.embed
        A[0] += Pt.T @ self.tip_mass @ Pt
        cached = self._cache["static"] = (K0, A)
        return cached

    @property
    def rigid_mass_matrix(self) -> np.ndarray:
        """The rigid mass matrix about the root, ``D^T M D`` (d, d) [kg, kg*m; kg*m, kg*m**2]."""
        _, A = self._static_matrices()
        M = A[0, :self.n_root, :self.n_root]
        return 0.5 * (M + M.T)

    def static_expansion(self):
        """(M, G, G2, G_tip): rigid mass about the root, ``G = sum b b^T/w**2``,
        ``G2 = sum b b^T/w**4`` and ``G_tip = sum phi_tip b^T/w**2`` (module docstring)."""
        cached = self._cache.get("expansion")
        if cached is not None:
            return cached
        K0, A = self._static_matrices()
        d = self.n_root
        r, e = slice(0, d), slice(d, None)
        Ke = K0[e, e]
        solve = np.linalg.solve
        KA0 = solve(Ke, A[0, e, r])          # Ke^-1 A0_er
        KA1 = solve(Ke, A[1, e, r])
        M = A[0, r, r]
        X = A[1, r, r] - A[0, r, e] @ KA0
        Y = (A[2, r, r] - A[1, r, e] @ KA0 - A[0, r, e] @ KA1
             + A[0, r, e] @ solve(Ke, A[0, e, e] @ KA0))
        Minv = np.linalg.inv(M)
        G = -Minv @ X @ Minv
        G2 = Minv @ (Y - X @ Minv @ X) @ Minv
        n_nodes = len(self.segments)
        last = slice((n_nodes - 1) * self.n_elastic, None)   # node n among the e's
        tip_full = self.transfer(self.length) @ G - self.embed @ (KA0[last] @ Minv)
        result = (0.5 * (M + M.T), 0.5 * (G + G.T), 0.5 * (G2 + G2.T), tip_full[self.tip_rows])
        self._cache["expansion"] = result
        return result
