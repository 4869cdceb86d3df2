r"""Finite modal models of the distributed beam (truncations).

Two reductions of the exact beam, both realised in attachment-end coordinates (a
:class:`~appendages.interface.RootModel`, q = [delta, phi, eta_1..eta_n]):

``"free-free"`` (the paper's)
    ``W(s) = sum_k b_k b_k^T/(s**2 + 2 zeta w_k s + w_k**2)`` over the two rigid-body modes
    (w = 0) and the first n free-free bending modes, b_k = (phi_k(0), phi_k'(0)) mass-normalised.
    With the modal coordinates eta = T q, ``eta_rigid = B_r^-T (q_r - B_f^T eta_f)``, the mass
    matrix is ``T^T T`` and the stiffness ``diag(0, 0, w_k**2)``; an exact change of
    coordinates. The error of W near s = 0 is the missing static flexibility of the dropped
    modes, ``sum_{k>n} b_k b_k^T/w_k**2 ~ n**-3`` for W1.

``"residual"``
    The free-free truncation plus the static (inertia-relief) flexibility of every dropped mode,
    ``R_n = G - sum_{k<=n} b_k b_k^T/w_k**2`` in series at the attachment end, where
    ``G = sum_{all k} b_k b_k^T/w_k**2`` is the constant term of the Laurent series of the exact
    W at s = 0 (from the power series of the module :mod:`appendages.beam`):
    ``G = [[L**3/105, -11 L**2/210], [-11 L**2/210, 13 L/35]]/EJ``. The poles stay exact; W(s)
    has the constant part R_n (a massless spring at the attachment end), so the error of W
    near s = 0 drops from ``~ sum_{k>n} b b^T/w**2`` to ``~ s**2 sum_{k>n} b b^T/w**4``.
    Realised with the attachment end as two massless coordinates joined to the modal body by
    the spring R_n^-1 (mode-acceleration method).

``"craig-bampton"``
    Attachment-end motion q_r = (delta, phi) carries the beam rigidly (constraint modes
    w = delta + x phi) and the first n cantilever modes psi_k add to it:

        M = [[M_rr, L^T], [L, I]],  K = diag(0, 0, w_ck**2),  C = blockdiag(0, C_c)

    (C: the beam's free-free modal damping projected on the cantilever modes, not diagonal)
    with ``M_rr = rho*A [[L, L**2/2], [L**2/2, L**3/3]]`` and L the participation factors
    ``rho*A integral [1, x] psi_k dx`` (closed forms in :meth:`Beam.modal_participation`). The
    rigid-body inertia is exact for any n; the attachment-end dynamic stiffness is
    ``D(s) = s**2 M_rr - s**4 sum_k l_k l_k^T/(s**2 + w_ck**2)``, whose dropped terms decay like
    k**-6 (translation) and k**-12 (rotation), so zeros and coupled frequencies converge fast.

References
----------
.. [1] R. R. Craig, M. C. C. Bampton, "Coupling of substructures for dynamic analyses",
   AIAA J. 6(7), 1968.
.. [2] P. W. Likins, "Dynamics and control of flexible space vehicles", JPL TR 32-1329, 1970
   (hybrid coordinates, cantilever modes of appendages).
.. [3] R. R. Craig, A. J. Kurdila, "Fundamentals of Structural Dynamics", 2nd ed., 2006,
   sec. 14.5 (mode-acceleration method, residual flexibility, inertia relief).
.. [4] Belonozhko et al. 2009 (PAPER.md): the two-mode free-free reference.
"""

from __future__ import annotations

import math

import numpy as np

from .interface import FiniteAppendage, RootModel, as_frequency_array

__all__ = ["ModalBeam", "METHODS"]

METHODS = ("craig-bampton", "residual", "free-free")


class ModalBeam(FiniteAppendage):
    """A beam truncated to ``n_modes`` bending modes (see the module docstring).

    Parameters
    ----------
    beam : Beam
        The distributed beam.
    n_modes : int
        Number of bending modes kept, >= 1.
    method : {"craig-bampton", "residual", "free-free"}
        Reduction method.
    """

    def __init__(self, beam, n_modes: int, *, method: str = "craig-bampton"):
        if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
            raise ValueError(f"n_modes must be an integer >= 1 (number of bending modes); got {n_modes!r}")
        if method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}; got {method!r}")
        self.beam = beam
        self.n_modes = int(n_modes)
        self.method = method

    def __repr__(self) -> str:
        return f"ModalBeam({self.beam!r}, n_modes={self.n_modes}, method={self.method!r})"

    @property
    def length(self) -> float:
        """Length [m]."""
        return self.beam.length

    @property
    def mass(self) -> float:
        """Mass [kg] (exact: rigid-body modes are kept whole by both methods)."""
        return self.beam.mass

    @property
    def inertia(self) -> float:
        """Moment of inertia about the centre of mass [kg*m**2]."""
        return self.beam.inertia

    def W(self, s) -> np.ndarray:
        """Transfer matrix W(s) of the truncated beam, shape ``np.shape(s) + (2, 2)``.

        Free-free and residual models are summed mode by mode (plus the constant residual
        flexibility), which avoids the cancellation of the stiff residual spring in the
        attachment-end dynamic stiffness near s = 0; Craig-Bampton models invert the
        attachment-end dynamic stiffness (see :class:`RootModel`).
        """
        if self.method == "craig-bampton":
            return super().W(s)
        s = as_frequency_array(s)
        beam, n = self.beam, self.n_modes
        m, L, J = beam.mass, beam.length, beam.inertia
        w = beam.natural_frequencies(n)
        b_flex, _ = beam._free_free_root_values(n)
        ss = s[..., None]
        flex = 1.0 / (ss**2 + 2.0 * beam.damping_ratio * w * ss + w**2)
        out = np.empty(s.shape + (2, 2), dtype=np.complex128)
        rigid = np.array([[1.0 / m + 0.25 * L**2 / J, -0.5 * L / J], [-0.5 * L / J, 1.0 / J]])
        for i, j in ((0, 0), (0, 1), (1, 1)):
            out[..., i, j] = rigid[i, j] / s**2 + flex @ (b_flex[:, i] * b_flex[:, j])
        if self.method == "residual":
            out += self._residual_flexibility(w, b_flex)
        out[..., 1, 0] = out[..., 0, 1]
        return out

    def _residual_flexibility(self, w: np.ndarray, b_flex: np.ndarray) -> np.ndarray:
        """R_n = G - sum_{k<=n} b_k b_k^T/w_k**2 [m/N, 1/N; 1/N, 1/(N*m)]."""
        L, EJ = self.beam.length, self.beam.bending_stiffness
        G = np.array([[L**3 / 105.0, -11.0 * L**2 / 210.0],
                      [-11.0 * L**2 / 210.0, 13.0 * L / 35.0]]) / EJ
        R = G - (b_flex.T / w**2) @ b_flex
        return 0.5 * (R + R.T)

    def _projected_damping(self, n: int) -> np.ndarray:
        """The beam's damping operator in the cantilever-mode coordinates.

        The beam damps every free-free bending mode k with ratio zeta, i.e. its damping
        operator is ``sum_k 2 zeta w_k (M phi_k)(M phi_k)^T``. The constraint modes (rigid
        motions of the root) are M-orthogonal to every bending mode, so only the cantilever
        coordinates are damped: ``C_ij = sum_k 2 zeta w_k O_ki O_kj`` with the overlaps
        ``O = beam.free_cantilever_overlap``. The terms decay like k**-6; 4 n + 400 free-free
        modes leave a relative tail below 1e-12. With this, a damped Craig-Bampton model
        converges to the exact damped W(s) as modes are added, instead of to a beam whose
        cantilever modes (not its free-free ones) carry the damping.
        """
        beam = self.beam
        n_free = 4 * n + 400
        O = beam.free_cantilever_overlap(n_free, n)
        w = beam.natural_frequencies(n_free)
        C = (O.T * (2.0 * beam.damping_ratio * w)) @ O
        return 0.5 * (C + C.T)

    def _root_model(self) -> RootModel:
        beam, n = self.beam, self.n_modes
        zeta = beam.damping_ratio
        m, L = beam.mass, beam.length
        names = ("delta", "phi") + tuple(f"eta[{k + 1}]" for k in range(n))
        if self.method in ("free-free", "residual"):
            w = beam.natural_frequencies(n)
            b_flex, tip_flex = beam._free_free_root_values(n)
            J = beam.inertia
            # rigid modes: translation 1/sqrt(m); rotation about the centre (x - L/2)/sqrt(J)
            b_rigid = np.array([[1.0 / math.sqrt(m), 0.0],
                                [-0.5 * L / math.sqrt(J), 1.0 / math.sqrt(J)]])
            tip_rigid = np.array([1.0 / math.sqrt(m), 0.5 * L / math.sqrt(J)])
            if self.method == "free-free":
                # eta = T q: eta_rigid = B_r^-T (q_r - B_f^T eta_f), eta_f = eta_f
                Br_inv_T = np.linalg.inv(b_rigid.T)
                T = np.zeros((n + 2, n + 2))
                T[:2, :2] = Br_inv_T
                T[:2, 2:] = -Br_inv_T @ b_flex.T
                T[2:, 2:] = np.eye(n)
                mass = T.T @ T
                stiffness = np.zeros((n + 2, n + 2))
                stiffness[2:, 2:] = np.diag(w**2)
                damping = np.zeros((n + 2, n + 2))
                damping[2:, 2:] = np.diag(2.0 * zeta * w)
                tip_abs = np.concatenate([tip_rigid, tip_flex]) @ T
            else:
                # q = [delta, phi, eta_rigid(2), eta_f(n)]; the attachment end (massless) is
                # joined to the modal body's end point B^T eta by the residual spring R^-1.
                spring = np.linalg.inv(self._residual_flexibility(w, b_flex))
                B = np.vstack([b_rigid, b_flex])          # (n+2, 2): modal root values
                coupling = np.hstack([np.eye(2), -B.T])   # q_r - B^T eta
                stiffness = coupling.T @ spring @ coupling
                stiffness[4:, 4:] += np.diag(w**2)
                mass = np.zeros((n + 4, n + 4))
                mass[2:, 2:] = np.eye(n + 2)
                damping = np.zeros((n + 4, n + 4))
                damping[4:, 4:] = np.diag(2.0 * zeta * w)
                # the free end moves with the modal body (the residual spring acts at x = 0)
                tip_abs = np.concatenate([[0.0, 0.0], tip_rigid, tip_flex])
                names = ("delta", "phi", "eta_rigid[1]", "eta_rigid[2]") + names[2:]
        else:
            w = beam.cantilever_frequencies(n)
            participation = beam.modal_participation(n)
            mass = np.eye(n + 2)
            mass[:2, :2] = beam.linear_density * np.array([[L, L**2 / 2.0], [L**2 / 2.0, L**3 / 3.0]])
            mass[2:, :2] = participation
            mass[:2, 2:] = participation.T
            stiffness = np.zeros((n + 2, n + 2))
            stiffness[2:, 2:] = np.diag(w**2)
            damping = np.zeros((n + 2, n + 2))
            if zeta > 0.0:
                damping[2:, 2:] = self._projected_damping(n)
            tip_abs = np.concatenate([[1.0, L], beam._cantilever_tip_values(n)])
        tip = tip_abs.copy()
        tip[0] -= 1.0
        tip[1] -= L
        mass = 0.5 * (mass + mass.T)
        return RootModel(mass, damping, stiffness, tip, names)
