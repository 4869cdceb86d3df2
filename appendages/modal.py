r"""Finite modal models of the distributed beam (truncations).

Three reductions of the exact beam, all realised in attachment-end coordinates (a
:class:`~appendages.interface.RootModel`, q = [delta, phi, eta_1..eta_n]):

``"free-free"`` (the paper's)
    ``W(s) = sum_k b_k b_k^T/(s**2 + 2 zeta w_k s + w_k**2)`` over the two rigid-body modes
    (w = 0) and the first n free-free bending modes, b_k = (phi_k(0), phi_k'(0)) mass-normalised.
    With the modal coordinates eta = T q, ``eta_rigid = B_r^-T (q_r - B_f^T eta_f)``, the mass
    matrix is ``T^T T`` and the stiffness ``diag(0, 0, w_k**2)``; an exact change of
    coordinates. The error of W near s = 0 is the missing static flexibility of the dropped
    modes, ``sum_{k>n} b_k b_k^T/w_k**2 ~ n**-3`` for W1.

``"residual"``
    The free-free truncation plus the two *residual attachment modes* of the dropped modes, a
    Rayleigh-Ritz reduction (Craig & Chang's free-interface method with residual flexibility
    and its inertia). The residual modes are the static shapes of the dropped modes under a
    unit root force and moment, ``psi = sum_{k>n} phi_k b_k^T/w_k**2``; they are orthogonal to
    the kept modes, have stiffness ``R = sum_{k>n} b_k b_k^T/w_k**2`` (the residual
    flexibility) and mass ``R2 = sum_{k>n} b_k b_k^T/w_k**4``, and move the root by R. In
    mass-normalised form (``R V = R2 V Lambda``) they are two more modes with root values
    ``(R V)^T`` and frequencies ``sqrt(Lambda)`` (above w_{n+1}), damped by the beam's damping
    operator projected on them, ``2 zeta V^T (sum_{k>n} b b^T/w**3) V``. The sums over k > n
    come from :meth:`Beam.free_free_tail` (Hurwitz zeta tails, no cancellation). Then

        W(s) = rigid/s**2 + sum_{k<=n} b b^T/(s**2 + 2 zeta w s + w**2) + R (s**2 R2 + R)^-1 R,

    with the first n free-free poles exact, the static flexibility exact (W - rigid/s**2 -> G)
    and the error of W near s = 0 of order ``s**4 sum_{k>n} b b^T/w**6``.
    The massless form ``W + R`` (MacNeal's mode-acceleration correction, flexsat's up to
    issue 9) has the same static flexibility but no residual inertia: on a hub of finite mass
    the hub then oscillates on the massless spring R^-1, a spurious coupled mode that
    matches no mode of the real spacecraft (32.6 rad/s with 2 modes on the default 100 kg
    hub, 7.68 rad/s on a 1 kg hub where the exact modes are 6.02 and 11.65 rad/s). As a
    Rayleigh-Ritz model of the coupled system the residual form cannot have one: every
    coupled frequency is an upper bound of the exact one of the same rank, and the first
    n + 1 converge (tests/spacecraft/dynamics/test_spacecraft.py).

``"craig-bampton"``
    Attachment-end motion q_r = (delta, phi) carries the beam rigidly (constraint modes
    w = delta + x phi) and the first n cantilever modes psi_k add to it:

        M = [[M_rr, L^T], [L, I]],  K = diag(0, 0, w_ck**2),  C = blockdiag(0, C_c)

    (C: ``diag(2 zeta w_ck)``, the beam's damping ratio being that of its cantilever modes;
    with ``damping_convention="free-free"`` the beam's free-free modal damping projected on the
    cantilever modes, not diagonal) with ``M_rr = rho*A [[L, L**2/2], [L**2/2, L**3/3]]`` and L
    the participation factors ``rho*A integral [1, x] psi_k dx`` (closed forms in
    :meth:`Beam.modal_participation`). The rigid-body inertia is exact for any n; the
    attachment-end dynamic stiffness is ``D(s) = s**2 M_rr - s**4 sum_k l_k l_k^T/(s**2 +
    w_ck**2)``, whose dropped terms decay like k**-6 (translation) and k**-12 (rotation), so
    zeros and coupled frequencies converge fast.

Any beam from its exact modal data
----------------------------------
A beam with a tip body or of several segments (:mod:`appendages.segmented`) has no closed-form
modes; :class:`GeneralTruncation` builds the same three reductions from the modal data its exact
model provides (free-free root values b_k and tip values, cantilever participation factors l_k
and tip values, the rigid mass matrix M_rr about the root, the free-free tails
``sum_{k>n} b b^T/w**2`` and ``/w**4``), planar (``n_root = 2``), three-axis (6, the coupled modes
of all motions) or for one rod (1). A free model's rigid-body part is ``M_rr^-1/s**2``: with
``M_rr = L L^T`` (Cholesky) the rows of ``B_r = L^-1`` are root values of mass-normalised rigid
modes (``B_r^T B_r = M_rr^-1``), whatever the mass distribution. Damping: a Craig-Bampton model
carries the cantilever modes' damping exactly, ``diag(2 zeta w_ck)``; a free-interface model
needs the operator ``sum_i 2 zeta w_ci g_i g_i^T`` in its own coordinates, g_i the cantilever
coordinate i of each of its modes. Closed forms of g_i through ``lambda_k - lambda_i`` cancel
where a free-free and a cantilever frequency nearly coincide (free-free mode k and cantilever
mode k + 1 meet as k grows), so the free-free modes are taken from a Craig-Bampton model of
``4 n + 64`` cantilever modes (an eigen-decomposition) whose cantilever coordinates are the g_i;
the residual modes' are the dropped modes' sums over that model. The terms decay like ``i**-8``.
A uniform beam's free-interface truncation with the cantilever convention is built the same way.

References
----------
.. [1] R. R. Craig, M. C. C. Bampton, "Coupling of substructures for dynamic analyses",
   AIAA J. 6(7), 1968.
.. [2] P. W. Likins, "Dynamics and control of flexible space vehicles", JPL TR 32-1329, 1970
   (hybrid coordinates, cantilever modes of appendages).
.. [3] R. R. Craig, A. J. Kurdila, "Fundamentals of Structural Dynamics", 2nd ed., 2006,
   sec. 14.5 (mode-acceleration method, residual flexibility, inertia relief).
.. [4] Belonozhko et al. 2009 (PAPER.md): the two-mode free-free reference.
.. [5] R. R. Craig, C.-J. Chang, "On the use of attachment modes in substructure coupling for
   dynamic analysis", AIAA paper 77-405, 1977 (residual attachment modes, Ritz coupling).
.. [6] R. H. MacNeal, "A hybrid method of component mode synthesis", Computers & Structures
   1(4), 1971 (residual flexibility and its inertia).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.linalg

from . import limits
from .checks import as_frequency_array
from .errors import describe
from .interface import (ROOT_MOTIONS, FiniteAppendage, RootModel, equilibrate, inverse_2x2,
                        inverse_symmetric, place_bending_planes, three_axis_root_model)

__all__ = ["ModalBeam", "METHODS", "MOTION_NAMES", "ModalStiffness", "fixed_root_model",
           "GeneralTruncation"]

METHODS = ("craig-bampton", "residual", "free-free")

#: The four motions of a three-axis model, in the order of :func:`three_axis_root_model`.
MOTION_NAMES = ("xy", "xz", "torsion", "axial")

#: Complex entries of the largest temporary array of one frequency chunk (32 MB).
_CHUNK_ELEMENTS = 2_000_000


def _chunks(size: int, width: int):
    """Slices of range(size), each at most _CHUNK_ELEMENTS/width long (bounded memory)."""
    step = max(1, _CHUNK_ELEMENTS // max(width, 1))
    for start in range(0, size, step):
        yield slice(start, min(start + step, size))


class ModalStiffness:
    r"""Attachment-end dynamic stiffness of a Craig-Bampton model in O(n) per frequency.

    The model ``[[M_rr, L^T], [L, I]] [q_r; eta]'' + [[0, 0], [0, C]] [..]' +
    [[0, 0], [0, Omega**2]] [..] = [f; 0]`` gives ``D(s) = s**2 M_rr - s**4 L^T H(s) L`` with
    ``H = (s**2 I + s C + Omega**2)^-1``, which cancels at large |s| (``M_rr - L^T L`` is the
    small mass left to the dropped modes) and costs O(n**3) per frequency as a solve. Instead:

    * undamped: ``D = s**2 [R + sum_k l_k l_k^T w_k**2/(s**2 + w_k**2)]`` with the tail
      ``R = M_rr - L^T L = sum_{k>n} l_k l_k^T`` given in closed form by the caller;
    * damped: the first-order form of the cantilever coordinates, ``x = [Omega eta; eta']``,
      ``A = [[0, Omega], [-Omega, -C]]`` (nearly skew for light damping, so its eigenvectors
      are well conditioned), diagonalised once, ``A = V Lambda V^-1``. Then
      ``H(s) = sum_j u_j v_j^T/(s - lambda_j)`` with ``u_j = Omega^-1 V[:n, j]``,
      ``v_j^T = V^-1[j, n:]``; the expansion at infinity gives ``sum_j u_j v_j^T = 0`` and
      ``sum_j lambda_j u_j v_j^T = I``, so ``s**2 H = I + sum_j lambda_j**2 u_j v_j^T/(s -
      lambda_j)`` and

          D(s) = s**2 [R - sum_j lambda_j**2 (L^T u_j)(v_j^T L)/(s - lambda_j)],

      2n rank-one terms. A realisation too close to defective (condition of V above 1e8,
      damping near critical) is solved directly instead, chunk by chunk.
    """

    def __init__(self, M_rr: np.ndarray, participation: np.ndarray, w: np.ndarray,
                 damping: np.ndarray | None, tail: np.ndarray):
        self.M_rr, self.L, self.w, self.C, self.R = M_rr, participation, w, damping, tail
        self.r = M_rr.shape[0]
        self.damped = damping is not None and np.any(damping)
        if self.damped:
            n = w.size
            A = np.block([[np.zeros((n, n)), np.diag(w)], [-np.diag(w), -damping]])
            lam, V = scipy.linalg.eig(A)
            self.direct = np.linalg.cond(V) > 1e8
            if not self.direct:
                V_inv = np.linalg.inv(V)
                X = participation.T @ (V[:n] / w[:, None])      # L^T u_j, (r, 2n)
                Y = V_inv[:, n:] @ participation                 # v_j^T L, (2n, r)
                self.lam = lam
                self.terms = (lam**2)[:, None, None] * (X.T[:, :, None] * Y[:, None, :])
        else:
            self.terms = (w**2)[:, None, None] * (participation[:, :, None]
                                                  * participation[:, None, :])

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """D(s), shape ``s.shape + (r, r)``; infinite at a clamped frequency (undamped)."""
        flat = s.ravel()
        out = np.empty((flat.size, self.r, self.r), dtype=np.complex128)
        n_terms = self.terms.shape[0] if not (self.damped and self.direct) else self.w.size ** 2
        for part in _chunks(flat.size, max(n_terms, 1)):
            ss = flat[part]
            if self.damped and self.direct:
                n = self.w.size
                Z = ((ss**2)[:, None, None] * np.eye(n) + ss[:, None, None] * self.C
                     + np.diag(self.w**2))
                HL = np.linalg.solve(Z, np.broadcast_to(self.L, (ss.size,) + self.L.shape))
                out[part] = ((ss**2)[:, None, None] * self.M_rr
                             - (ss**4)[:, None, None] * (self.L.T @ HL))
                continue
            if self.damped:
                weights = -1.0 / (ss[:, None] - self.lam)
            else:
                s2 = (ss**2)[:, None]
                weights = 1.0 / (s2 + self.w**2)
            bracket = self.R + np.tensordot(weights, self.terms, axes=(1, 0))
            out[part] = (ss**2)[:, None, None] * bracket
        return out.reshape(s.shape + (self.r, self.r))


# -- realisations in attachment-end coordinates --------------------------------------------------
def _free_root_model(b_rigid, tip_rigid, rigid_line, b_modes, stiffness_modes, damping_modes,
                     tip_modes, names, n_root) -> RootModel:
    """Free-interface modal model (rigid + elastic modes) in attachment-end coordinates.

    ``eta = T q``: the rigid modal coordinates ``eta_r = B_r^-T (q_r - B_f^T eta_f)`` (B_r the
    rigid modes' root values, B_f the elastic ones'), the elastic ones unchanged; an exact
    change of coordinates, so ``M = T^T T``, ``K = diag(0, w**2)``, ``C = diag(0, C_f)``.
    The tip row is the modal tip values through T minus the rigid line (``rigid_line``:
    the root coordinates' contribution to the tip, (1, L) planar, (1,) for a rod).
    """
    N = stiffness_modes.size
    r = n_root
    Br_inv_T = np.linalg.inv(b_rigid.T)
    T = np.zeros((N + r, N + r))
    T[:r, :r] = Br_inv_T
    T[:r, r:] = -Br_inv_T @ b_modes.T
    T[r:, r:] = np.eye(N)
    mass = T.T @ T
    stiffness = np.zeros((N + r, N + r))
    stiffness[r:, r:] = np.diag(stiffness_modes)
    damping = np.zeros((N + r, N + r))
    damping[r:, r:] = damping_modes
    tip_abs = np.concatenate([tip_rigid, tip_modes]) @ T
    tip = tip_abs.copy()
    tip[:r] -= rigid_line
    mass = 0.5 * (mass + mass.T)
    return RootModel(mass, damping, stiffness, tip, names, n_root=n_root)


def fixed_root_model(M_rr, participation, w, damping, tip_modes, rigid_line, names,
                     n_root) -> RootModel:
    """Craig-Bampton model: constraint modes (rigid motion of the root) + cantilever modes.

    ``M = [[M_rr, G^T], [G, I]]``, ``K = diag(0, w**2)``, ``C = blockdiag(0, damping)`` in the
    coordinates ``[q_r, eta]`` (root motions, mass-normalised cantilever coordinates), with
    ``participation`` G of shape (n, n_root) and ``damping`` (n, n) or None; the tip row is
    ``[0, tip_modes]``. Shared by the beam truncations and :class:`appendages.ModalAppendage`.
    """
    n, r = w.size, n_root
    mass = np.eye(n + r)
    mass[:r, :r] = M_rr
    mass[r:, :r] = participation
    mass[:r, r:] = participation.T
    stiffness = np.zeros((n + r, n + r))
    stiffness[r:, r:] = np.diag(w**2)
    damping_full = np.zeros((n + r, n + r))
    if damping is not None:
        damping_full[r:, r:] = damping
    tip_abs = np.concatenate([rigid_line, tip_modes])
    tip = tip_abs.copy()
    tip[:r] -= rigid_line
    mass = 0.5 * (mass + mass.T)
    return RootModel(mass, damping_full, stiffness, tip, names, n_root=n_root)


# -- one bending plane ----------------------------------------------------------------------------
def _bending_residual_modes(beam, n: int):
    """The two residual attachment modes of the ``"residual"`` truncation (module docstring).

    Returns ``(B, lam, C, tip)``: root values ``B`` (2, 2) (row j: mode j's
    ``(delta, phi)``), squared frequencies ``lam`` (2,) [rad^2/s^2], damping ``C`` (2, 2)
    [1/s] and tip values (2,), all for mass-normalised residual modes ``xi = V nu`` with
    ``R V = R2 V diag(lam)``, ``V^T R2 V = I``.
    """
    R, tip_R = beam.free_free_tail(n, 2)
    R3, _ = beam.free_free_tail(n, 3)
    R2, _ = beam.free_free_tail(n, 4)
    lam, V = scipy.linalg.eigh(R, R2)
    C = V.T @ (2.0 * beam.damping_ratio * R3) @ V
    return (R @ V).T, lam, 0.5 * (C + C.T), tip_R[0] @ V


def _bending_projected_damping(beam, n: int) -> np.ndarray:
    """The beam's damping operator in its first n cantilever-mode coordinates.

    The beam damps every free-free bending mode k with ratio zeta, i.e. its damping
    operator is ``sum_k 2 zeta w_k (M phi_k)(M phi_k)^T``. The constraint modes (rigid
    motions of the root) are M-orthogonal to every bending mode, so only the cantilever
    coordinates are damped: ``C_ij = sum_k 2 zeta w_k O_ki O_kj`` with the overlaps
    ``O = beam.free_cantilever_overlap`` (closed forms). The terms decay like k**-6; 4 n + 400
    free-free modes leave a relative tail below 1e-12. With this, a damped Craig-Bampton
    model converges to the exact damped W(s) as modes are added, instead of to a beam whose
    cantilever modes (not its free-free ones) carry the damping.
    """
    n_free = 4 * n + 400
    O = beam.free_cantilever_overlap(n_free, n)
    w = beam.natural_frequencies(n_free)
    C = (O.T * (2.0 * beam.damping_ratio * w)) @ O
    return 0.5 * (C + C.T)


class _Bending:
    """One bending plane truncated to n modes (n >= 0): its planar root model and W/D."""

    def __init__(self, beam, n: int, method: str):
        self.beam, self.n, self.method = beam, n, method

    def root_model(self) -> RootModel:
        beam, n = self.beam, self.n
        zeta = beam.damping_ratio
        L = beam.length
        names = ("delta", "phi") + tuple(f"eta[{k + 1}]" for k in range(n))
        if self.method in ("free-free", "residual"):
            if n:
                w, b_modes, tip_modes = beam.free_free_modes(n)
                tip_modes = tip_modes[:, 0]
            else:
                w, b_modes, tip_modes = np.zeros(0), np.zeros((0, 2)), np.zeros(0)
            stiffness_modes = w**2
            damping_modes = np.diag(2.0 * zeta * w)
            if self.method == "residual":
                # two more "modes": the residual attachment modes with their own inertia
                b_res, lam, C_res, tip_res = self.residual_modes()
                b_modes = np.vstack([b_modes, b_res])
                tip_modes = np.concatenate([tip_modes, tip_res])
                stiffness_modes = np.concatenate([stiffness_modes, lam])
                damping_modes = scipy.linalg.block_diag(damping_modes, C_res)
                names = names + ("residual[1]", "residual[2]")
            m, J = beam.mass, beam.inertia
            # rigid modes: translation 1/sqrt(m); rotation about the centre (x - L/2)/sqrt(J)
            b_rigid = np.array([[1.0 / math.sqrt(m), 0.0],
                                [-0.5 * L / math.sqrt(J), 1.0 / math.sqrt(J)]])
            tip_rigid = np.array([1.0 / math.sqrt(m), 0.5 * L / math.sqrt(J)])
            return _free_root_model(b_rigid, tip_rigid, np.array([1.0, L]), b_modes,
                                    stiffness_modes, damping_modes, tip_modes, names, 2)
        M_rr, participation, w, damping = self.craig_bampton_data()
        tip_modes = beam.cantilever_modes(n)[2][:, 0] if n else np.zeros(0)
        return fixed_root_model(M_rr, participation, w, damping, tip_modes,
                                np.array([1.0, L]), names, 2)

    def residual_modes(self):
        cached = getattr(self, "_residual", None)
        if cached is None:
            cached = self._residual = _bending_residual_modes(self.beam, self.n)
        return cached

    def craig_bampton_data(self):
        """(M_rr, participation (n, 2), cantilever frequencies (n,), damping (n, n) or None)."""
        cached = getattr(self, "_cb", None)
        if cached is None:
            beam, n, L = self.beam, self.n, self.beam.length
            M_rr = beam.linear_density * np.array([[L, L**2 / 2.0], [L**2 / 2.0, L**3 / 3.0]])
            if n:
                w = beam.cantilever_frequencies(n)
                participation = beam.modal_participation(n)
            else:
                w, participation = np.zeros(0), np.zeros((0, 2))
            damping = None
            if beam.damping_ratio > 0.0 and n:
                damping = (np.diag(2.0 * beam.damping_ratio * w)
                           if beam.damping_convention == "cantilever"
                           else _bending_projected_damping(beam, n))
            cached = self._cb = (M_rr, participation, w, damping)
        return cached

    def stiffness_operator(self) -> ModalStiffness:
        cached = getattr(self, "_stiffness", None)
        if cached is None:
            M_rr, participation, w, damping = self.craig_bampton_data()
            cached = self._stiffness = ModalStiffness(
                M_rr, participation, w, damping, self.beam.cantilever_participation_tail(self.n))
        return cached

    def W(self, s: np.ndarray) -> np.ndarray:
        """W(s), shape ``s.shape + (2, 2)`` (inf/NaN at an undamped pole; s != 0)."""
        if self.method == "craig-bampton":
            return inverse_2x2(self.stiffness_operator()(s))
        beam, n = self.beam, self.n
        m, L, J = beam.mass, beam.length, beam.inertia
        if n:
            w, b_flex, _ = beam.free_free_modes(n)
        else:
            w, b_flex = np.zeros(0), np.zeros((0, 2))
        products = np.stack([b_flex[:, 0] ** 2, b_flex[:, 0] * b_flex[:, 1],
                             b_flex[:, 1] ** 2], axis=1)
        out = np.empty(s.shape + (2, 2), dtype=np.complex128)
        flat_out = out.reshape(-1, 2, 2)
        flat = s.ravel()
        rigid = np.array([[1.0 / m + 0.25 * L**2 / J, -0.5 * L / J], [-0.5 * L / J, 1.0 / J]])
        if self.method == "residual":
            b_res, lam, C_res, _ = self.residual_modes()
        for part in _chunks(flat.size, max(n, 1)):
            ss = flat[part]
            flex = 1.0 / (ss[:, None] ** 2 + 2.0 * beam.damping_ratio * w * ss[:, None] + w**2)
            entries = flex @ products
            for k, (i, j) in enumerate(((0, 0), (0, 1), (1, 1))):
                flat_out[part, i, j] = rigid[i, j] / ss**2 + entries[:, k]
            if self.method == "residual":
                H = ((ss**2)[:, None, None] * np.eye(2) + ss[:, None, None] * C_res
                     + np.diag(lam))
                residual = b_res.T @ inverse_2x2(H) @ b_res
                for i, j in ((0, 0), (0, 1), (1, 1)):
                    flat_out[part, i, j] += residual[:, i, j]
        out[..., 1, 0] = out[..., 0, 1]
        return out

    def D(self, s: np.ndarray) -> np.ndarray:
        """D(s) = W(s)^-1, shape ``s.shape + (2, 2)``; s = 0 gives 0."""
        if self.method == "craig-bampton":
            return self.stiffness_operator()(s)
        D = np.zeros(s.shape + (2, 2), dtype=np.complex128)
        nonzero = s != 0
        D[nonzero] = inverse_2x2(self.W(s[nonzero]))
        return D


# -- one rod (torsion or axial motion) -----------------------------------------------------------
class _RodMotion:
    """Torsion or axial motion truncated to n modes (n >= 0); ``rod`` None: rigid."""

    def __init__(self, rod, rigid_inertia: float, n: int, method: str):
        self.rod, self.m, self.n, self.method = rod, rigid_inertia, n, method

    def root_model(self) -> RootModel:
        rod, n, m = self.rod, self.n, self.m
        names = ("q",) + tuple(f"eta[{k + 1}]" for k in range(n))
        if rod is None:
            return RootModel(np.array([[m]]), np.zeros((1, 1)), np.zeros((1, 1)),
                             np.zeros(1), ("q",), n_root=1)
        zeta = rod.damping_ratio
        if self.method in ("free-free", "residual"):
            b, tip_modes, w = rod.free_free_modes(n)
            b_modes = b[:, None]
            stiffness_modes, damping_modes = w**2, np.diag(2.0 * zeta * w)
            if self.method == "residual":
                b_res, lam, c_res, tip_res = self.residual_mode()
                b_modes = np.vstack([b_modes, [[b_res]]])
                tip_modes = np.concatenate([tip_modes, [tip_res]])
                stiffness_modes = np.concatenate([stiffness_modes, [lam]])
                damping_modes = scipy.linalg.block_diag(damping_modes, [[c_res]])
                names = names + ("residual[1]",)
            root = math.sqrt(1.0 / m)
            return _free_root_model(np.array([[root]]), np.array([root]), np.array([1.0]),
                                    b_modes, stiffness_modes, damping_modes, tip_modes, names, 1)
        M_rr, participation, w, damping = self.craig_bampton_data()
        _, tip_modes, _ = rod.cantilever_modes(n)
        return fixed_root_model(M_rr, participation, w, damping, tip_modes, np.array([1.0]),
                                names, 1)

    def residual_mode(self):
        """(root value, squared frequency, damping, tip value) of the one residual mode:
        the scalar case of :func:`_bending_residual_modes` with the rod's Hurwitz tails."""
        R, tip_R = self.rod.free_free_tail(self.n, 2)
        R3, _ = self.rod.free_free_tail(self.n, 3)
        R4, _ = self.rod.free_free_tail(self.n, 4)
        v = 1.0 / math.sqrt(R4)
        return R * v, R / R4, 2.0 * self.rod.damping_ratio * R3 / R4, tip_R * v

    def craig_bampton_data(self):
        cached = getattr(self, "_cb", None)
        if cached is None:
            rod, n = self.rod, self.n
            l, _, w = rod.cantilever_modes(n)
            damping = None
            if rod.damping_ratio > 0.0 and n:
                damping = (np.diag(2.0 * rod.damping_ratio * w)
                           if rod.damping_convention == "cantilever" else rod.projected_damping(n))
            cached = self._cb = (np.array([[self.m]]), l[:, None], w, damping)
        return cached

    def W(self, s: np.ndarray) -> np.ndarray:
        """W(s), shape ``s.shape + (1, 1)``."""
        if self.rod is None:
            return (1.0 / (self.m * s**2))[..., None, None]
        if self.method == "craig-bampton":
            return 1.0 / self.D(s)
        rod, n = self.rod, self.n
        b, _, w = rod.free_free_modes(n)
        flat = s.ravel()
        out = np.empty(flat.shape, dtype=np.complex128)
        if self.method == "residual":
            b_res, lam, c_res, _ = self.residual_mode()
        for part in _chunks(flat.size, max(n, 1)):
            ss = flat[part]
            flex = 1.0 / (ss[:, None] ** 2 + 2.0 * rod.damping_ratio * w * ss[:, None] + w**2)
            out[part] = 1.0 / (self.m * ss**2) + flex @ b**2
            if self.method == "residual":
                out[part] += b_res**2 / (ss**2 + c_res * ss + lam)
        return out.reshape(s.shape)[..., None, None]

    def D(self, s: np.ndarray) -> np.ndarray:
        """D(s), shape ``s.shape + (1, 1)``; s = 0 gives 0."""
        if self.rod is None:
            return (self.m * s**2)[..., None, None]
        if self.method == "craig-bampton":
            cached = getattr(self, "_stiffness", None)
            if cached is None:
                M_rr, participation, w, damping = self.craig_bampton_data()
                tail = np.array([[self.rod.cantilever_participation_tail(self.n)]])
                cached = self._stiffness = ModalStiffness(M_rr, participation, w, damping, tail)
            return cached(s)
        D = np.zeros(s.shape + (1, 1), dtype=np.complex128)
        nonzero = s != 0
        D[nonzero] = 1.0 / self.W(s[nonzero])
        return D


class _RodData:
    """A rod's modal data in the form :class:`GeneralTruncation` reads (n_root = 1)."""

    def __init__(self, rod):
        self.rod, self.length, self.damping_ratio = rod, rod.length, rod.damping_ratio
        self.rigid_mass_matrix = np.array([[rod.rigid_inertia]])

    def free_free_modes(self, n, n_root=1):
        b, tip, w = self.rod.free_free_modes(n)
        return w, b[:, None], tip[:, None]

    def cantilever_modes(self, n, n_root=1):
        l, tip, w = self.rod.cantilever_modes(n)
        return w, l[:, None], tip[:, None]

    def free_free_tail(self, n, power, n_root=1):
        bb, tb = self.rod.free_free_tail(n, power)
        return np.array([[bb]]), np.array([[tb]])

    def cantilever_participation_tail(self, n, n_root=1):
        return np.array([[self.rod.cantilever_participation_tail(n)]])


# -- any beam from its exact modal data ----------------------------------------------------------
def _rigid_line(beam_length: float, n_root: int) -> np.ndarray:
    """Tip motions (rows) of a unit rigid motion of the root: planar (1, 2), three-axis (3, 6)
    with the rows of :data:`~appendages.interface.TIP_MOTIONS`."""
    if n_root == 1:
        return np.array([[1.0]])
    if n_root == 2:
        return np.array([[1.0, beam_length]])
    T = np.zeros((3, 6))
    T[0, 1], T[0, 5] = 1.0, beam_length     # v(L) = v + L theta_z
    T[1, 2], T[1, 4] = 1.0, -beam_length    # w(L) = w - L theta_y
    T[2, 3] = 1.0                           # theta_x(L) = theta_x
    return T


def _tip_rows(tip: np.ndarray, n_root: int) -> np.ndarray:
    """The RootModel's tip: 1-D planar or rod, (3, n) three-axis."""
    return tip[0] if n_root <= 2 else tip


def _names(n_root: int, n_modes: int, extra: tuple = ()) -> tuple:
    root = {1: ("q",), 2: ("delta", "phi")}.get(n_root, ROOT_MOTIONS)
    return tuple(root) + tuple(f"eta[{k + 1}]" for k in range(n_modes)) + extra


class GeneralTruncation:
    """A truncation of a beam from its exact modal data (module docstring).

    Parameters
    ----------
    beam : SegmentedBeam-like
        Offers ``rigid_mass_matrix`` / ``rigid_mass_matrix6``, ``free_free_modes(n, n_root=)``,
        ``cantilever_modes(n, n_root=)``, ``free_free_tail(n, power, n_root=)``,
        ``cantilever_participation_tail(n, n_root=)``, ``length`` and ``damping_ratio``.
    n : int
        Elastic modes kept.
    method : {"craig-bampton", "residual", "free-free"}
    n_root : {2, 6}
    """

    def __init__(self, beam, n: int, method: str, n_root: int):
        self.beam, self.n, self.method, self.n_root = beam, n, method, n_root
        self._root_model = None

    @property
    def rigid_mass(self) -> np.ndarray:
        M = self.beam.rigid_mass_matrix if self.n_root <= 2 else self.beam.rigid_mass_matrix6
        return np.asarray(M, dtype=float)

    def _modes(self, kind: str, n: int):
        """(w, root values or participation, tip values) of the first n modes (n may be 0)."""
        if n == 0:
            rows = 1 if self.n_root <= 2 else 3
            return np.zeros(0), np.zeros((0, self.n_root)), np.zeros((0, rows))
        get = self.beam.free_free_modes if kind == "free" else self.beam.cantilever_modes
        w, root, tip = get(n, n_root=self.n_root)
        return w, root, np.asarray(tip).reshape(w.size, -1)

    def craig_bampton_data(self):
        """(M_rr, participation (n, d), cantilever frequencies (n,), damping (n, n) or None,
        tip values (n, rows))."""
        w, l, tip = self._modes("clamped", self.n)
        zeta = self.beam.damping_ratio
        damping = np.diag(2.0 * zeta * w) if zeta > 0.0 else None
        return self.rigid_mass, l, w, damping, tip

    def root_model(self) -> RootModel:
        if self._root_model is None:
            self._root_model = (self._craig_bampton() if self.method == "craig-bampton"
                                else self._free_interface())
        return self._root_model

    # -- Craig-Bampton --------------------------------------------------------------------------
    def _craig_bampton(self) -> RootModel:
        M_rr, l, w, damping, tip = self.craig_bampton_data()
        n, r = w.size, self.n_root
        mass = np.eye(n + r)
        mass[:r, :r] = M_rr
        mass[r:, :r] = l
        mass[:r, r:] = l.T
        stiffness = np.zeros((n + r, n + r))
        stiffness[r:, r:] = np.diag(w**2)
        C = np.zeros((n + r, n + r))
        if damping is not None:
            C[r:, r:] = damping
        tip_rows = np.zeros((tip.shape[1], n + r))
        tip_rows[:, r:] = tip.T
        return RootModel(0.5 * (mass + mass.T), C, stiffness, _tip_rows(tip_rows, r),
                         _names(r, n), n_root=r)

    # -- free interface -------------------------------------------------------------------------
    def _free_interface(self) -> RootModel:
        beam, n, r = self.beam, self.n, self.n_root
        w, b, tip = self._modes("free", n)
        b_modes, tip_modes, stiffness_modes = b, tip, w**2
        extra = ()
        if self.method == "residual":
            b_res, lam, tip_res = self.residual_modes()
            b_modes = np.vstack([b_modes, b_res])
            tip_modes = np.vstack([tip_modes, tip_res])
            stiffness_modes = np.concatenate([stiffness_modes, lam])
            extra = tuple(f"residual[{k + 1}]" for k in range(lam.size))
        N = stiffness_modes.size
        L_chol = np.linalg.cholesky(self.rigid_mass)
        b_rigid = np.linalg.inv(L_chol)                  # rows: rigid modes' root values
        line = _rigid_line(beam.length, r)
        tip_rigid = b_rigid @ line.T                     # (r, rows)
        T = np.zeros((N + r, N + r))
        Br_inv_T = np.linalg.inv(b_rigid.T)
        T[:r, :r] = Br_inv_T
        T[:r, r:] = -Br_inv_T @ b_modes.T
        T[r:, r:] = np.eye(N)
        mass = T.T @ T
        stiffness = np.zeros((N + r, N + r))
        stiffness[r:, r:] = np.diag(stiffness_modes)
        damping = np.zeros((N + r, N + r))
        if beam.damping_ratio > 0.0:
            damping[r:, r:] = self._projected_damping()
        tip_abs = np.vstack([tip_rigid, tip_modes]).T @ T   # (rows, N + r)
        tip_abs[:, :r] -= line
        return RootModel(0.5 * (mass + mass.T), damping, stiffness, _tip_rows(tip_abs, r),
                         _names(r, n, extra), n_root=r)

    def residual_modes(self):
        """(root values (d', d), squared frequencies (d',), tip values (d', rows)) of the residual
        attachment modes: ``R V = R2 V diag(lam)``, ``V^T R2 V = I``, root values ``(R V)^T``
        (:mod:`appendages.modal`); d' = d less the directions without residual flexibility."""
        R, tip_R = self.beam.free_free_tail(self.n, 2, n_root=self.n_root)
        lam, V = self._residual_basis()
        return (R @ V).T, lam, (tip_R @ V).T

    def _residual_basis(self):
        """(lam, V) of ``R V = R2 V diag(lam)`` on the range of R2 (a motion that is rigid,
        inextensible or torsionally rigid, has no residual flexibility and no residual mode)."""
        R, _ = self.beam.free_free_tail(self.n, 2, n_root=self.n_root)
        R2, _ = self.beam.free_free_tail(self.n, 4, n_root=self.n_root)
        d = np.sqrt(np.abs(np.diag(R2)))
        d = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 1.0)
        values, U = np.linalg.eigh(R2 * np.outer(d, d))
        keep = values > 1e-12 * values.max(initial=0.0)
        U = d[:, None] * U[:, keep]
        lam, V = scipy.linalg.eigh(U.T @ R @ U, U.T @ R2 @ U)
        return lam, U @ V

    # -- W and D --------------------------------------------------------------------------------
    def D(self, s: np.ndarray) -> np.ndarray:
        """Attachment-end dynamic stiffness, shape ``s.shape + (d, d)``; s = 0 gives 0.
        Craig-Bampton: O(n) per frequency (:class:`~appendages.modal.ModalStiffness`); the
        others: static condensation of the root model."""
        if self.method == "craig-bampton":
            if getattr(self, "_stiffness", None) is None:
                M_rr, l, w, damping, _ = self.craig_bampton_data()
                tail = self.beam.cantilever_participation_tail(self.n, n_root=self.n_root)
                self._stiffness = ModalStiffness(M_rr, l, w, damping, tail)
            return self._stiffness(s)
        return self.root_model().dynamic_stiffness(s)

    def W(self, s: np.ndarray) -> np.ndarray:
        """W(s) = D(s)^-1, shape ``s.shape + (d, d)`` (inf/NaN at an undamped pole; s != 0)."""
        D = self.D(s)
        if self.n_root == 1:
            return 1.0 / D
        return inverse_2x2(D) if self.n_root == 2 else inverse_symmetric(D)

    def _projected_damping(self) -> np.ndarray:
        """The cantilever modes' damping in this model's elastic coordinates (module docstring)."""
        beam, n, r = self.beam, self.n, self.n_root
        n_c = 4 * n + 64
        w_c, l, _ = self._modes("clamped", n_c)
        M_rr = self.rigid_mass
        mass = np.eye(n_c + r)
        mass[:r, :r] = M_rr
        mass[r:, :r] = l
        mass[:r, r:] = l.T
        K = np.zeros((n_c + r, n_c + r))
        K[r:, r:] = np.diag(w_c**2)
        d = equilibrate(K, mass)
        lam, V = scipy.linalg.eigh(K * np.outer(d, d), mass * np.outer(d, d))
        V = V * d[:, None]
        V, lam = V[:, r:], lam[r:]                       # elastic modes (rigid ones first)
        # the exact modes' signs: the root parts of V are the modes' root values b_k
        w, b, _ = self._modes("free", n)
        sign = np.sign(np.sum(V[:r, :n] * b.T, axis=0))
        sign[sign == 0] = 1.0
        G = V[r:, :n] * sign                             # (n_c, n): g_i of the kept modes
        if self.method == "residual":
            V_res = self._residual_basis()[1]
            # residual shapes: sum over the dropped modes of phi_k b_k^T V/w_k**2
            dropped = V[:, n:]
            weights = (dropped[:r].T @ V_res) / lam[n:, None]      # (modes, d')
            G = np.hstack([G, dropped[r:] @ weights])
        C = (G.T * (2.0 * beam.damping_ratio * w_c)) @ G
        return 0.5 * (C + C.T)


class ModalBeam(FiniteAppendage):
    """A beam truncated to ``n_modes`` modes (see the module docstring).

    Parameters
    ----------
    beam : Beam
        The distributed beam.
    n_modes : int
        Number of elastic modes kept, >= 1. The planar model (x-y bending: :meth:`W`,
        ``root_model()``) keeps the first ``n_modes`` bending modes of that plane. The
        three-axis model (:meth:`W6`, ``root_model(n_root=6)``) keeps the ``n_modes`` lowest
        modes of all four motions together (bending in both planes, torsion, axial motion:
        the method's kind of modes, cantilever or free-free, ranked by frequency) and any
        that tie with the last (a round section's twin), :attr:`modes_per_motion`.
    method : {"craig-bampton", "residual", "free-free"}
        Reduction method.
    modes_per_motion : dict, optional
        The three-axis model's modes per motion instead (keys ``"xy"``, ``"xz"``,
        ``"torsion"``, ``"axial"``; missing ones 0): e.g. the planar model's modes in x-y
        and a few in the other motions.

    Raises
    ------
    LimitError
        n_modes above the ``modes`` limit of :mod:`appendages.limits` (1000; raise it with
        ``appendages.limits.raised(modes=...)``).
    """

    def __init__(self, beam, n_modes: int, *, method: str = "craig-bampton",
                 modes_per_motion: dict | None = None):
        if isinstance(n_modes, (bool, np.bool_)) or not isinstance(n_modes, (int, np.integer)):
            raise TypeError(f"n_modes must be an integer (number of bending modes); got "
                            f"{type(n_modes).__name__} {describe(n_modes)}")
        if n_modes < 1:
            raise ValueError(f"n_modes must be an integer >= 1 (number of bending modes); got "
                             f"{n_modes!r}")
        limits.check("n_modes", int(n_modes), "modes", "bending modes")
        if not isinstance(method, str) or method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}; got {describe(method)}")
        # a bare uniform beam: its closed forms; any other beam (a tip body, segments): its
        # exact modal data (GeneralTruncation)
        self._uniform = bool(getattr(beam, "is_uniform", False))
        needed = (("length", "bending_stiffness", "linear_density", "natural_frequencies")
                  if self._uniform else ("length", "damping_ratio", "rigid_mass_matrix",
                                         "free_free_modes", "cantilever_modes"))
        for attribute in needed:
            if not hasattr(beam, attribute):
                raise TypeError(f"beam must be a Beam or SteppedBeam; got {type(beam).__name__} "
                                f"without '{attribute}'")
        if modes_per_motion is not None and not self._uniform:
            raise ValueError("modes_per_motion applies to a uniform beam's four separate "
                             "motions; a beam with a tip body or segments keeps its n_modes "
                             f"lowest coupled modes; got {describe(modes_per_motion)}")
        self.beam = beam
        self.n_modes = int(n_modes)
        self.method = method
        if modes_per_motion is not None:
            if not isinstance(modes_per_motion, dict) or set(modes_per_motion) - set(MOTION_NAMES):
                raise ValueError(f"modes_per_motion must be a dict with keys among "
                                 f"{MOTION_NAMES}; got {describe(modes_per_motion)}")
            counts = {name: modes_per_motion.get(name, 0) for name in MOTION_NAMES}
            for name, count in counts.items():
                if isinstance(count, (bool, np.bool_)) or not isinstance(count, (int, np.integer)) \
                        or count < 0:
                    raise ValueError(f"modes_per_motion['{name}'] must be a non-negative "
                                     f"integer (modes); got {describe(count)}")
                limits.check(f"modes_per_motion['{name}']", int(count), "modes", "modes")
            self.__dict__["_modes_per_motion"] = {k: int(v) for k, v in counts.items()}

    def __repr__(self) -> str:
        return f"ModalBeam({self.beam!r}, n_modes={self.n_modes}, method={self.method!r})"

    @property
    def length(self) -> float:
        """Length [m]."""
        return self.beam.length

    @property
    def mass(self) -> float:
        """Mass [kg] (exact: rigid-body modes are kept whole by every method)."""
        return self.beam.mass

    @property
    def inertia(self) -> float:
        """Moment of inertia about the centre of mass [kg*m**2]."""
        return self.beam.inertia

    @property
    def center_of_mass(self) -> float:
        """Distance of the centre of mass from the attachment end [m] (the beam's)."""
        return self.beam.center_of_mass

    @property
    def inertia_tensor(self) -> np.ndarray:
        """Inertia about the centre of mass in beam axes [kg*m**2] (the beam's, exact)."""
        return self.beam.inertia_tensor

    def undamped(self) -> "ModalBeam":
        """The same truncation of the undamped beam (itself when undamped)."""
        if self.beam.damping_ratio == 0.0:
            return self
        cached = self.__dict__.get("_undamped")
        if cached is None:
            counts = self.modes_per_motion if self.beam.three_axis and self._uniform else None
            cached = self.__dict__["_undamped"] = ModalBeam(self.beam.undamped(), self.n_modes,
                                                            method=self.method,
                                                            modes_per_motion=counts)
        return cached

    # -- the motions ----------------------------------------------------------------------------
    def _planar(self):
        cached = self.__dict__.get("_planar_motion")
        if cached is None:
            cached = (_Bending(self.beam, self.n_modes, self.method)
                      if self._uniform and not self._projected(self.beam) else
                      GeneralTruncation(self.beam, self.n_modes, self.method, 2))
            self.__dict__["_planar_motion"] = cached
        return cached

    def _projected(self, part) -> bool:
        """True when a uniform motion's free-interface truncation carries the damping of its
        cantilever modes (projected, :class:`GeneralTruncation`), not its own modes'."""
        return (self.method != "craig-bampton" and part is not None
                and part.damping_ratio > 0.0 and part.damping_convention == "cantilever")

    def _general6(self) -> GeneralTruncation:
        """The three-axis truncation of a non-uniform beam (its coupled modes)."""
        self.beam.require_three_axis("a three-axis truncation")
        cached = self.__dict__.get("_general6_model")
        if cached is None:
            cached = self.__dict__["_general6_model"] = GeneralTruncation(
                self.beam, self.n_modes, self.method, 6)
        return cached

    @property
    def modes_per_motion(self) -> dict:
        """Modes the three-axis model keeps per motion: ``{"xy": .., "xz": .., "torsion": ..,
        "axial": ..}`` (rigid motions: 0). Their sum is ``n_modes`` or more (ties). A uniform
        beam's only: with a tip body or segments the modes couple."""
        self.beam.require_three_axis("a three-axis truncation")
        if not self._uniform:
            raise ValueError("modes_per_motion: the modes of a beam with a tip body or "
                             "segments are not split by motion")
        cached = self.__dict__.get("_modes_per_motion")
        if cached is None:
            beam, n = self.beam, self.n_modes
            kind = "cantilever_frequencies" if self.method == "craig-bampton" \
                else "natural_frequencies"
            frequencies = {"xy": getattr(beam.planar_view("xy"), kind)(n),
                           "xz": getattr(beam.planar_view("xz"), kind)(n)}
            for name, rod in (("torsion", beam.torsion_rod()), ("axial", beam.axial_rod())):
                frequencies[name] = getattr(rod, kind)(n) if rod is not None else np.zeros(0)
            cutoff = np.sort(np.concatenate(list(frequencies.values())))[n - 1]
            cached = {name: int(np.count_nonzero(f <= cutoff * (1.0 + 1e-12)))
                      for name, f in frequencies.items()}
            self.__dict__["_modes_per_motion"] = cached
        return dict(cached)

    def _motions(self) -> dict:
        cached = self.__dict__.get("_motion_models")
        if cached is None:
            beam, counts = self.beam, self.modes_per_motion

            def bending(plane):
                view = beam.planar_view(plane)
                if self._projected(view):
                    return GeneralTruncation(view, counts[plane], self.method, 2)
                return _Bending(view, counts[plane], self.method)

            def rod(name, model, rigid_inertia):
                if self._projected(model):
                    return GeneralTruncation(_RodData(model), counts[name], self.method, 1)
                return _RodMotion(model, rigid_inertia, counts[name], self.method)

            cached = {
                "xy": bending("xy"), "xz": bending("xz"),
                "torsion": rod("torsion", beam.torsion_rod(),
                               beam.torsional_inertia * beam.length),
                "axial": rod("axial", beam.axial_rod(), beam.mass),
            }
            self.__dict__["_motion_models"] = cached
        return cached

    # -- W(s) -----------------------------------------------------------------------------------
    def W(self, s) -> np.ndarray:
        """Transfer matrix W(s) of the truncated beam, shape ``np.shape(s) + (2, 2)``.

        Free-free and residual models are summed mode by mode (the residual modes' 2x2 block
        as ``B^T (s**2 I + s C + Lambda)^-1 B``), which keeps the rigid-body term 1/s**2 and
        the static flexibility apart near s = 0; Craig-Bampton models invert their
        attachment-end dynamic stiffness in its modal form (:class:`ModalStiffness`). Both
        cost O(n_modes) per frequency and evaluate the frequencies in chunks, so memory stays
        bounded (about 32 MB of temporaries) for any number of points.
        """
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError("s = 0 is the rigid-body pole of W (W is infinite there) [rad/s]")
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            W = self._planar().W(s)
        if not np.all(np.isfinite(W)):
            raise ValueError("s is a natural frequency of the undamped model (or the rigid-body "
                             "pole s = 0): W is infinite there [rad/s]")
        return W

    def dynamic_stiffness(self, s) -> np.ndarray:
        """Attachment-end dynamic stiffness D(s) = W(s)^-1 [N/m, N; N, N*m], O(n) per frequency.

        Craig-Bampton: the modal form of :class:`ModalStiffness`, infinite exactly at the
        model's clamped frequencies (undamped); the others: the inverse of :meth:`W`.
        s = 0 gives 0.
        """
        s = as_frequency_array(s)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return self._planar().D(s)

    def W6(self, s) -> np.ndarray:
        """Three-axis transfer matrix W6(s) of the truncated beam, shape ``np.shape(s) + (6, 6)``.

        The four motions' truncated models (:attr:`modes_per_motion`) placed as in
        :meth:`Beam.W6`; O(n_modes) per frequency.
        """
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError("s = 0 is the rigid-body pole of W6 (W6 is infinite there) [rad/s]")
        if not self._uniform:
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                W6 = self._general6().W(s)
        else:
            W6 = self._six(s, "W")
        if not np.all(np.isfinite(W6)):
            raise ValueError("s is a natural frequency of the undamped model: W6 is infinite "
                             "there [rad/s]")
        return W6

    def dynamic_stiffness6(self, s) -> np.ndarray:
        """Three-axis D6(s) = W6(s)^-1, shape ``np.shape(s) + (6, 6)``; s = 0 gives 0."""
        if not self._uniform:
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                return self._general6().D(as_frequency_array(s))
        return self._six(as_frequency_array(s), "D")

    def _six(self, s: np.ndarray, which: str) -> np.ndarray:
        """The motions' W (``which="W"``) or D ("D") placed in a 6x6 as in :meth:`Beam.W6`."""
        motions = self._motions()
        out = np.zeros(s.shape + (6, 6), dtype=np.complex128)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            part = {name: getattr(motion, which)(s) for name, motion in motions.items()}
            place_bending_planes(out, part["xy"], part["xz"])
            out[..., 0:1, 0:1] = part["axial"]
            out[..., 3:4, 3:4] = part["torsion"]
        return out

    # -- realisations ---------------------------------------------------------------------------
    def _residual_modes(self):
        """The planar model's two residual modes (``method="residual"``), see
        :func:`_bending_residual_modes`."""
        return self._planar().residual_modes()

    def _projected_damping(self, n: int) -> np.ndarray:
        """The beam's damping in its first n cantilever coordinates
        (:func:`_bending_projected_damping`)."""
        return _bending_projected_damping(self.beam, n)

    def _root_model(self) -> RootModel:
        return self._planar().root_model()

    def _three_axis_root_model(self) -> RootModel:
        if not self._uniform:
            return self._general6().root_model()
        motions = self._motions()
        return three_axis_root_model(*(motions[name].root_model() for name in MOTION_NAMES))
