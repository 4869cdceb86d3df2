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
    come from :meth:`Beam._free_free_tail` (Hurwitz zeta tails, no cancellation). Then

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
    n + 1 converge (tests/test_spacecraft.py).

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
from .interface import FiniteAppendage, RootModel, as_frequency_array, describe, inverse_2x2

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

    Raises
    ------
    LimitError
        n_modes above the ``modes`` limit of :mod:`appendages.limits` (1000; raise it with
        ``appendages.limits.raised(modes=...)``).
    """

    def __init__(self, beam, n_modes: int, *, method: str = "craig-bampton"):
        if isinstance(n_modes, (bool, np.bool_)) or not isinstance(n_modes, (int, np.integer)):
            raise TypeError(f"n_modes must be an integer (number of bending modes); got "
                            f"{type(n_modes).__name__} {describe(n_modes)}")
        if n_modes < 1:
            raise ValueError(f"n_modes must be an integer >= 1 (number of bending modes); got "
                             f"{n_modes!r}")
        limits.check("n_modes", int(n_modes), "modes", "bending modes")
        if not isinstance(method, str) or method not in METHODS:
            raise ValueError(f"method must be one of {METHODS}; got {describe(method)}")
        for attribute in ("length", "bending_stiffness", "linear_density", "natural_frequencies"):
            if not hasattr(beam, attribute):
                raise TypeError(f"beam must be a uniform Beam; got {type(beam).__name__} "
                                f"without '{attribute}'")
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

        Free-free and residual models are summed mode by mode (the residual modes' 2x2 block
        as ``B^T (s**2 I + s C + Lambda)^-1 B``), which keeps the rigid-body term 1/s**2 and
        the static flexibility apart near s = 0; Craig-Bampton models invert the
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
            b_res, lam, C_res, _ = self._residual_modes()
            H = (s**2)[..., None, None] * np.eye(2) + s[..., None, None] * C_res + np.diag(lam)
            residual = b_res.T @ inverse_2x2(H) @ b_res
            for i, j in ((0, 0), (0, 1), (1, 1)):
                out[..., i, j] += residual[..., i, j]
        out[..., 1, 0] = out[..., 0, 1]
        return out

    def _residual_modes(self):
        """The two residual modes of the ``"residual"`` truncation (module docstring).

        Returns ``(B, lam, C, tip)``: root values ``B`` (2, 2) (row j: mode j's
        ``(delta, phi)``), squared frequencies ``lam`` (2,) [rad^2/s^2], damping ``C`` (2, 2)
        [1/s] and tip values (2,), all for mass-normalised residual modes ``xi = V nu`` with
        ``R V = R2 V diag(lam)``, ``V^T R2 V = I``.
        """
        cached = self.__dict__.get("_residual_cache")
        if cached is None:
            beam, n = self.beam, self.n_modes
            R, tip_R = beam._free_free_tail(n, 2)
            R3, _ = beam._free_free_tail(n, 3)
            R2, _ = beam._free_free_tail(n, 4)
            lam, V = scipy.linalg.eigh(R, R2)
            C = V.T @ (2.0 * beam.damping_ratio * R3) @ V
            cached = ((R @ V).T, lam, 0.5 * (C + C.T), tip_R @ V)
            self.__dict__["_residual_cache"] = cached
        return cached

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
            b_modes, tip_modes = beam._free_free_root_values(n)
            stiffness_modes = w**2
            damping_modes = np.diag(2.0 * zeta * w)
            if self.method == "residual":
                # two more "modes": the residual attachment modes with their own inertia
                b_res, lam, C_res, tip_res = self._residual_modes()
                b_modes = np.vstack([b_modes, b_res])
                tip_modes = np.concatenate([tip_modes, tip_res])
                stiffness_modes = np.concatenate([stiffness_modes, lam])
                damping_modes = scipy.linalg.block_diag(damping_modes, C_res)
                names = names + ("residual[1]", "residual[2]")
            N = stiffness_modes.size
            J = beam.inertia
            # rigid modes: translation 1/sqrt(m); rotation about the centre (x - L/2)/sqrt(J)
            b_rigid = np.array([[1.0 / math.sqrt(m), 0.0],
                                [-0.5 * L / math.sqrt(J), 1.0 / math.sqrt(J)]])
            tip_rigid = np.array([1.0 / math.sqrt(m), 0.5 * L / math.sqrt(J)])
            # eta = T q: eta_rigid = B_r^-T (q_r - B_f^T eta_f), eta_f = eta_f
            Br_inv_T = np.linalg.inv(b_rigid.T)
            T = np.zeros((N + 2, N + 2))
            T[:2, :2] = Br_inv_T
            T[:2, 2:] = -Br_inv_T @ b_modes.T
            T[2:, 2:] = np.eye(N)
            mass = T.T @ T
            stiffness = np.zeros((N + 2, N + 2))
            stiffness[2:, 2:] = np.diag(stiffness_modes)
            damping = np.zeros((N + 2, N + 2))
            damping[2:, 2:] = damping_modes
            tip_abs = np.concatenate([tip_rigid, tip_modes]) @ T
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
