"""LQR attitude controller with an estimator: an implementable output-feedback controller.

The regulator minimises J = integral (y_w^T W y_w + r torque^2) dt with y_w the weighted outputs
(theta, omega, optionally tip deflections) of the design plant, i.e. Q = C_w^T W C_w,
N = C_w^T W D_w, R = r + D_w^T W D_w on the design plant's states. The states are not measured:
a Kalman filter (or a user-given Luenberger gain) built on the same design model estimates them
from the measured theta and omega. The controller handed to the spacecraft has inputs
['theta_ref', 'theta', 'omega'] and output ['torque'] only.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import control
import numpy as np
import scipy.linalg

from .modes import rigid_body_inertia
from .signals import OMEGA, THETA, THETA_REF, TIP_SUFFIX, TORQUE, _check_plant
from .pd import _positive, check_sample_time

__all__ = ["lqr", "KalmanNoise", "LQRDesign", "lqr_design", "reference_state"]


@dataclass(frozen=True)
class KalmanNoise:
    """Noise intensities of the Kalman filter's model (continuous-time white noises).

    The design model is driven by a white torque disturbance w entering like the torque
    (x' = A x + B (torque + w)) and measured as theta + v_theta, omega + v_omega.

    Attributes
    ----------
    torque_noise : float, N^2 m^2 s
        Intensity of w.
    attitude_noise : float, rad^2 s
        Intensity of v_theta.
    rate_noise : float, rad^2/s
        Intensity of v_omega.
    """

    torque_noise: float
    attitude_noise: float
    rate_noise: float

    def __post_init__(self):
        for name, unit in (("torque_noise", "N^2 m^2 s"), ("attitude_noise", "rad^2 s"),
                           ("rate_noise", "rad^2/s")):
            _positive(getattr(self, name), name, unit)

    @classmethod
    def default(cls, inertia: float, attitude_weight: float, torque_weight: float,
                estimator_speed: float = 3.0) -> "KalmanNoise":
        """Noises that make the filter about ``estimator_speed`` times faster than the regulator.

        For the rigid body theta'' = (torque + w)/J the LQR with weights q (theta), r (torque) has
        poles of natural frequency w_r = (q / (r J^2))^(1/4), and the dual Kalman filter with
        intensities W (w), V (v_theta) has w_e = (W / (V J^2))^(1/4). Taking V = 1/q and
        W = k^4 / r gives w_e = k w_r. The rate noise V_omega = V w_e^2 makes a rate
        measurement as informative as the attitude one at the estimator bandwidth. On a rigid
        hub the filter's Riccati equation is then solved by
        P = V [[a w_e, b w_e^2], [b w_e^2, c w_e^3]] with b = 1/2, a = c = sqrt(3)/2, and the
        estimator poles are exactly the roots of s^2 + sqrt(3) w_e s + w_e^2.

        References
        ----------
        B. D. O. Anderson, J. B. Moore, Optimal Control: Linear Quadratic Methods, 1990, sec. 5.2
        (asymptotic LQ poles: w_r = (q/r)^(1/4) for a double integrator) and the duality of
        LQR and Kalman filtering.
        """
        k = _positive(estimator_speed, "estimator_speed", "1")
        w_r = (attitude_weight / (torque_weight * inertia ** 2)) ** 0.25
        w_e = k * w_r
        V = 1.0 / attitude_weight
        return cls(torque_noise=k ** 4 / torque_weight, attitude_noise=V,
                   rate_noise=V * w_e ** 2)


@dataclass(frozen=True)
class LQRDesign:
    """Everything an LQR design produced (returned by :func:`lqr_design`).

    Attributes
    ----------
    controller : control.StateSpace
        Output-feedback controller, inputs ['theta_ref', 'theta', 'omega'], output ['torque'].
    K : ndarray, shape (1, n_states)
        State-feedback gain, torque = -K (x_hat - x_ref theta_ref).
    L : ndarray, shape (n_states, 2)
        Estimator gain on (theta, omega) innovations.
    Q, R, N : ndarray
        Weights on the design plant's states (shapes (n, n), (1, 1), (n, 1)).
    x_ref : ndarray, shape (n_states,)
        Equilibrium state of a unit rigid rotation (A x_ref = 0, theta = 1, omega = 0).
    regulator_poles, estimator_poles : ndarray, complex128
        Eigenvalues of A - B K and A - L C_m (z-plane for a digital design).
    """

    controller: control.StateSpace
    K: np.ndarray
    L: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    N: np.ndarray
    x_ref: np.ndarray
    regulator_poles: np.ndarray
    estimator_poles: np.ndarray


def _nonneg(value, name: str, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise TypeError(f"{name} must be a real number [{unit}]; got {type(value).__name__}")
    value = float(value)
    if not (np.isfinite(value) and value >= 0):
        raise ValueError(f"{name} must be non-negative and finite [{unit}]; got {value}")
    return value


def _deflection_weights(plant, deflection_weight) -> tuple[list[str], np.ndarray]:
    tips = [n for n in plant.output_labels if n.endswith(TIP_SUFFIX)]
    if deflection_weight is None:
        return [], np.zeros((0, 0))
    if not tips:
        raise ValueError("deflection_weight given but the plant has no '*tip_deflection' output; "
                         f"outputs are {list(plant.output_labels)}")
    if isinstance(deflection_weight, Mapping):
        unknown = [k for k in deflection_weight if k not in tips]
        if unknown:
            raise ValueError(f"deflection_weight names {unknown} are not tip-deflection outputs "
                             f"{tips}")
        names = list(deflection_weight)
        W = np.diag([_nonneg(deflection_weight[n], f"deflection_weight[{n!r}]", "1/m^2")
                     for n in names])
        return names, W
    if np.isscalar(deflection_weight):
        w = _nonneg(deflection_weight, "deflection_weight", "1/m^2")
        return tips, w * np.eye(len(tips))
    W = np.asarray(deflection_weight, dtype=float)
    if W.shape != (len(tips), len(tips)):
        raise ValueError(f"deflection_weight matrix must have shape ({len(tips)}, {len(tips)}) "
                         f"for the outputs {tips}; got {W.shape}")
    if not np.allclose(W, W.T, rtol=1e-12, atol=0) or np.min(np.linalg.eigvalsh(W)) < -1e-12 * max(
            1.0, np.abs(W).max()):
        raise ValueError("deflection_weight must be symmetric positive semidefinite [1/m^2]; got "
                         f"eigenvalues {np.linalg.eigvalsh((W + W.T) / 2)}")
    return tips, W


def _pbh_defective(A, M, *, side: str, tol: float = 1e-12) -> list[complex]:
    """Eigenvalues lambda of A with Re >= 0 that M does not reach (PBH test, scale-invariant).

    ``side="input"``: lambda is uncontrollable from B = M iff w^H B = 0 for a left eigenvector
    w^H A = lambda w^H (Hautus); ``side="output"``: unobservable through C = M iff C v = 0 for a
    right eigenvector, i.e. the input test on (A^T, C^T).

    The test is made in coordinates A_b = D^-1 A D balanced by a diagonal similarity (powers of
    2, exact), which equilibrates the rows and columns of every coupled block: a modal pair
    (q, q') with q'' = -w^2 q + b u becomes (w q, q') with entries ~w, so the displacement and
    rate coordinates are on one scale ("energy" coordinates) and b keeps its size. For a simple
    eigenvalue with unit left eigenvector w_b, the mode counts as uncontrollable if
    |w_b^H m_j| <= tol ||m_j|| for every column m_j of M_b = D^-1 M: the input's reach into that
    mode measured against the input's own size, independent of how far the mode's frequency is
    from the others (the plain test sigma_min([A - lambda I, B]) <= tol sigma_max compares it
    with the largest frequency squared and wrongly rejects high, weakly excited beam modes).
    Measured on hub + free-free rod plants: round-off in a structurally zero participation
    (symmetric modes of two wings, the mode of a 200-body chain localised at its free tip) is
    <= 3e-14; genuine modes of a 40-mode beam reach >= 1e-6 (input) and theta alone sees those
    of a 200-body chain at >= 2e-10 (energy coordinates divide a displacement output by w),
    hence tol = 1e-12 (also the threshold of ``Spacecraft.plant(prune=True)``).

    Eigenvalues within 1e-8 ||A_b|| of each other (the rigid-body Jordan block at 0, repeated
    frequencies) are tested together: the left null space U of A_b - lambda I (singular values
    <= 1e-8 ||A_b||) must be reached in every direction, sigma_min(U^H M_b / ||M_b||) > tol;
    with more null directions than inputs it cannot be.

    References
    ----------
    M. L. J. Hautus, "Controllability and observability conditions of linear autonomous
    systems", Proc. KNAW A 72, 1969 (eigenvector test); B. N. Parlett, C. Reinsch, "Balancing a
    matrix for calculation of eigenvalues and eigenvectors", Numer. Math. 13, 1969.
    """
    A = np.asarray(A, dtype=float)
    M = np.asarray(M, dtype=float)
    if side == "output":
        A, M = A.T, M.T
    n = A.shape[0]
    if n == 0:
        return []
    Ab, (d, _) = scipy.linalg.matrix_balance(A, permute=False, separate=True)
    Mb = M / d[:, None]
    col_norms = np.linalg.norm(Mb, axis=0)
    live = col_norms > 0
    Mn = Mb[:, live] / col_norms[live]  # unit columns: invariant to the inputs' scaling
    lam, W = scipy.linalg.eig(Ab, left=True, right=False)
    norm_a = max(np.linalg.norm(Ab, 1), np.finfo(float).tiny)
    close = 1e-8 * norm_a
    critical = np.nonzero(lam.real >= -1e-9 * np.abs(lam))[0]
    bad: list[complex] = []
    done = np.zeros(n, dtype=bool)
    for i in critical:
        if done[i]:
            continue
        group = np.nonzero(np.abs(lam - lam[i]) <= close)[0]
        done[group] = True
        if group.size == 1:
            w = W[:, i] / np.linalg.norm(W[:, i])
            reach = np.abs(w.conj() @ Mn).max(initial=0.0)
        else:
            center = lam[group].mean()
            U, s, _ = np.linalg.svd(Ab - center * np.eye(n))
            null = U[:, s <= close]
            if null.shape[1] == 0:
                null = U[:, -1:]
            if null.shape[1] > Mn.shape[1]:
                reach = 0.0
            else:
                sv = np.linalg.svd(null.conj().T @ Mn, compute_uv=False)
                reach = sv.min() if sv.size else 0.0
        if reach <= tol:
            bad.extend(complex(x) for x in lam[group] if x.real >= -1e-9 * abs(x))
    return bad


def _solve_care(A, B, Q, R, N, what: str) -> np.ndarray:
    """Stabilising solution X of A^T X + X A - (X B + N) R^-1 (B^T X + N^T) + Q = 0.

    scipy's generalized-Schur solver first; if its eigenvalue reordering fails (lightly damped
    flexible modes whose Hamiltonian eigenvalues lie very close to the imaginary axis), the
    stable invariant subspace of the balanced Hamiltonian from an ordered complex Schur form
    (swaps of 1x1 blocks do not fail), X = U_21 U_11^-1. Weakly excited undamped modes (a
    40-mode beam weighted through theta only) have Hamiltonian pairs +-1e-12 + j w, at
    round-off: one member of each such pair is taken, the one with the smaller real part.

    References
    ----------
    A. J. Laub, "A Schur method for solving algebraic Riccati equations", IEEE TAC 24(6), 1979.
    """
    try:
        return scipy.linalg.solve_continuous_are(A, B, Q, R, s=N)
    except (np.linalg.LinAlgError, ValueError):
        pass
    n = A.shape[0]
    Ri = np.linalg.inv(R)
    F = A - B @ Ri @ N.T
    H = np.block([[F, -B @ Ri @ B.T], [-(Q - N @ Ri @ N.T), -F.T]])
    Hb, (d, _) = scipy.linalg.matrix_balance(H, permute=False, separate=True)
    T, Z = scipy.linalg.schur(Hb.astype(complex), output="complex")
    ev = np.diag(T)
    # the eigenvalues come in pairs (lambda, -conj(lambda)), one of each stable. A lightly
    # damped mode the cost barely moves has its pair within round-off of the imaginary axis,
    # where the sign of the computed real part is noise: such pairs are matched explicitly and
    # the member with the smaller real part taken.
    select = (ev.real < 0).astype(np.int32)
    near = np.nonzero(np.abs(ev.real) <= 1e-9 * max(np.abs(ev).max(), 1.0))[0]
    select[near] = 0
    free = list(near)
    while len(free) > 1:
        i = free.pop(0)
        j = min(free, key=lambda k: abs(ev[k] + np.conj(ev[i])))
        free.remove(j)
        select[i if ev[i].real <= ev[j].real else j] = 1
    if free or select.sum() != n:
        raise ValueError(
            f"{what}: the Riccati equation has no stabilising solution: the Hamiltonian has "
            f"{int(np.sum(ev.real < 0))} of {2 * n} eigenvalues in the open left half-plane, "
            f"{n} needed (a mode neither stabilisable nor detectable on the imaginary axis)")
    _, U, _, _, _, _, info = scipy.linalg.lapack.ztrsen(select, T, Z, job="N")
    if info != 0:
        raise ValueError(f"{what}: reordering the Hamiltonian's Schur form failed (info={info})")
    U = U[:, :n] * d[:, None]
    X = np.linalg.solve(U[:n].T, U[n:].T).T
    return np.real(0.5 * (X + X.conj().T))


def reference_state(plant: control.StateSpace) -> np.ndarray:
    """State x_ref of a unit rigid rotation: A x_ref = 0, theta(x_ref) = 1, omega(x_ref) = 0.

    A rigid rotation of a free-floating spacecraft is an equilibrium with zero torque, so the
    reference theta_ref shifts the regulator's state target to x_ref theta_ref.

    Raises
    ------
    ValueError
        If no such equilibrium exists (the plant is not free-floating).
    """
    _check_plant(plant)
    labels = list(plant.output_labels)
    c_theta = plant.C[labels.index(THETA)]
    c_omega = plant.C[labels.index(OMEGA)]
    n = plant.nstates
    M = np.vstack([plant.A, c_theta, c_omega])
    rhs = np.zeros(n + 2)
    rhs[n] = 1.0
    x, *_ = np.linalg.lstsq(M, rhs, rcond=None)
    residual = np.linalg.norm(M @ x - rhs)
    if residual > 1e-8 * max(1.0, np.linalg.norm(M) * np.linalg.norm(x)):
        raise ValueError("plant has no rigid-rotation equilibrium (A x = 0 with theta = 1 rad, "
                         f"omega = 0): it is not free-floating (residual {residual:.3g})")
    return x


def _check_weights(attitude_weight, rate_weight, torque_weight):
    q_theta = _nonneg(attitude_weight, "attitude_weight", "1/rad^2")
    q_omega = _nonneg(rate_weight, "rate_weight", "s^2/rad^2")
    if isinstance(torque_weight, bool) or not isinstance(torque_weight, (int, float, np.floating,
                                                                         np.integer)):
        raise TypeError(f"torque_weight must be a real number [1/(N*m)^2]; got "
                        f"{type(torque_weight).__name__}")
    r = float(torque_weight)
    if not (np.isfinite(r) and r > 0):
        raise ValueError(f"torque_weight R must be positive definite (> 0) [1/(N*m)^2]; got {r}")
    if q_theta <= 0:
        raise ValueError("attitude_weight must be positive [1/rad^2]: with no weight on theta the "
                         "rigid-body attitude mode is undetectable in the cost (A, sqrt(Q)) and "
                         f"the attitude is not regulated; got {q_theta}")
    return q_theta, q_omega, r


def lqr_design(plant: control.StateSpace, *, attitude_weight: float, rate_weight: float,
               torque_weight: float, deflection_weight=None,
               estimator: str | KalmanNoise | np.ndarray = "kalman",
               estimator_speed: float = 3.0, sample_time: float | None = None) -> LQRDesign:
    """LQR + estimator design; see :func:`lqr` (which returns only the controller)."""
    _check_plant(plant)
    if sample_time is not None and not isinstance(estimator, (str, KalmanNoise)):
        raise ValueError("a Luenberger gain array is a continuous-time estimator; with sample_time "
                         "use estimator='kalman' or a KalmanNoise")
    q_theta, q_omega, r = _check_weights(attitude_weight, rate_weight, torque_weight)
    tip_names, W_tip = _deflection_weights(plant, deflection_weight)
    labels = list(plant.output_labels)
    i_t = list(plant.input_labels).index(TORQUE)
    A = np.asarray(plant.A, dtype=float)
    B = np.asarray(plant.B[:, [i_t]], dtype=float)
    n = A.shape[0]
    weighted = [THETA, OMEGA] + tip_names
    rows = [labels.index(name) for name in weighted]
    Cw = plant.C[rows]
    Dw = plant.D[np.ix_(rows, [i_t])]
    W = scipy.linalg.block_diag(np.diag([q_theta, q_omega]), W_tip)
    Q = Cw.T @ W @ Cw
    Q = 0.5 * (Q + Q.T)
    N = Cw.T @ W @ Dw
    R = np.array([[r]]) + Dw.T @ W @ Dw
    # checks: Q - N R^-1 N^T >= 0 (cost PSD), (A, B) stabilisable, (A, sqrt Q) detectable
    Qc = Q - N @ np.linalg.solve(R, N.T)
    eig_q = np.linalg.eigvalsh(0.5 * (Qc + Qc.T))
    if eig_q.min() < -1e-10 * max(1.0, abs(eig_q).max()):
        raise ValueError(f"state weight Q must be positive semidefinite; got eigenvalue "
                         f"{eig_q.min():.3g}")
    uncontrollable = _pbh_defective(A, B, side="input")
    if uncontrollable:
        raise ValueError(
            "uncontrollable design: (A, B) from 'torque' is not stabilisable; modes with "
            f"eigenvalues {np.round(uncontrollable, 6)} (Re >= 0) cannot be moved by the torque "
            "(remove modes the torque cannot excite, e.g. symmetric modes of symmetric wings or a "
            "chain's tip-localised mode: Spacecraft.plant(prune=True); or give them damping)")
    # symmetric PSD square root (sqrtm warns on the singular W of a zero rate weight)
    eig_w, vec_w = np.linalg.eigh(W)
    sqrtW = (vec_w * np.sqrt(np.clip(eig_w, 0.0, None))) @ vec_w.T
    undetectable = _pbh_defective(A, sqrtW @ Cw, side="output")
    if undetectable:
        raise ValueError(f"(A, sqrt(Q)) is not detectable: modes with eigenvalues "
                         f"{np.round(undetectable, 6)} (Re >= 0) are not seen by the weighted "
                         f"outputs {weighted}; weight them or remove them from the design plant")
    x_ref = reference_state(plant)
    meas_rows = [labels.index(THETA), labels.index(OMEGA)]
    Cm = plant.C[meas_rows]
    Dm = plant.D[np.ix_(meas_rows, [i_t])]
    J = rigid_body_inertia(plant)
    if isinstance(estimator, str):
        if estimator != "kalman":
            raise ValueError(f"estimator must be 'kalman', a KalmanNoise or a Luenberger gain "
                             f"array of shape ({n}, 2); got {estimator!r}")
        noise = KalmanNoise.default(J, q_theta, r, estimator_speed)
    elif isinstance(estimator, KalmanNoise):
        noise = estimator
    else:
        noise = None
        L_given = np.asarray(estimator, dtype=float)
        if L_given.shape != (n, 2):
            raise ValueError(f"Luenberger estimator gain must have shape ({n}, 2) (states x "
                             f"[theta, omega]); got {L_given.shape}")
    if noise is not None:
        unobservable = _pbh_defective(A, Cm, side="output")
        if unobservable:
            raise ValueError(f"(A, C) from theta and omega is not detectable: modes with "
                             f"eigenvalues {np.round(unobservable, 6)} are invisible to the "
                             "sensors; remove them from the design plant")

    u_ref = 0.0  # a rigid rotation needs no torque
    if sample_time is None:
        P = _solve_care(A, B, Q, R, N, "regulator")
        K = np.linalg.solve(R, B.T @ P + N.T)
        if noise is not None:
            Wn = noise.torque_noise * (B @ B.T)
            V = np.diag([noise.attitude_noise, noise.rate_noise])
            S = _solve_care(A.T, Cm.T, Wn, V, np.zeros((n, 2)), "Kalman filter")
            L = S @ Cm.T @ np.linalg.inv(V)
        else:
            L = L_given
        Bm = B - L @ Dm
        Ac = A - L @ Cm - Bm @ K
        g = K @ x_ref + u_ref  # torque per rad of reference
        Bc = np.hstack([Bm * g, L])
        Cc = -K
        Dc = np.array([[g[0], 0.0, 0.0]])
        controller = control.ss(Ac, Bc, Cc, Dc, inputs=[THETA_REF, THETA, OMEGA],
                                outputs=[TORQUE], name="lqr")
        reg_poles = np.linalg.eigvals(A - B @ K)
        est_poles = np.linalg.eigvals(A - L @ Cm)
        if est_poles.real.max() >= 0:
            raise ValueError(f"estimator is not stable: A - L C has eigenvalue "
                             f"{est_poles[np.argmax(est_poles.real)]:.4g}")
        design = LQRDesign(controller, K, L, Q, R, N, x_ref, reg_poles, est_poles)
        return design
    # digital design on the zero-order-hold plant (Phi, Gamma); the continuous cost sampled at T
    # to first order: Q_d = Q T, N_d = N T, R_d = R T (valid for T well below the closed-loop time
    # constants, which check_sample_time enforces); noises W_d = B W B^T T, V_d = V / T.
    # Predictor estimator: x_hat[k+1] = Phi x_hat + Gamma u + L (y[k] - C x_hat - D u), so the
    # torque at k uses measurements up to k-1 (one sample for computation).
    continuous = lqr_design(plant, attitude_weight=attitude_weight, rate_weight=rate_weight,
                            torque_weight=torque_weight, deflection_weight=deflection_weight,
                            estimator=estimator, estimator_speed=estimator_speed)
    T = _positive(sample_time, "sample_time", "s")
    check_sample_time(T, plant, continuous.controller)
    Phi = scipy.linalg.expm(A * T)
    # Gamma = integral_0^T e^{A t} dt B via the block exponential of [[A, B], [0, 0]] T
    E = scipy.linalg.expm(np.block([[A, B], [np.zeros((1, n + 1))]]) * T)
    Gamma = E[:n, n:]
    P = scipy.linalg.solve_discrete_are(Phi, Gamma, Q * T, R * T, s=N * T)
    K = np.linalg.solve(R * T + Gamma.T @ P @ Gamma, Gamma.T @ P @ Phi + (N * T).T)
    # (noise is set: a Luenberger gain array with sample_time was rejected at the top)
    Wd = noise.torque_noise * T * (B @ B.T)
    Vd = np.diag([noise.attitude_noise, noise.rate_noise]) / T
    S = scipy.linalg.solve_discrete_are(Phi.T, Cm.T, Wd, Vd)
    L = Phi @ S @ Cm.T @ np.linalg.inv(Cm @ S @ Cm.T + Vd)
    Bm = Gamma - L @ Dm
    Ac = Phi - L @ Cm - Bm @ K
    g = K @ x_ref + u_ref
    Bc = np.hstack([Bm * g, L])
    controller = control.ss(Ac, Bc, -K, np.array([[g[0], 0.0, 0.0]]), T,
                            inputs=[THETA_REF, THETA, OMEGA], outputs=[TORQUE], name="lqr")
    return LQRDesign(controller, K, L, Q, R, N, x_ref, np.linalg.eigvals(Phi - Gamma @ K),
                     np.linalg.eigvals(Phi - L @ Cm))


def lqr(plant: control.StateSpace, *, attitude_weight: float, rate_weight: float,
        torque_weight: float, deflection_weight=None,
        estimator: str | KalmanNoise | np.ndarray = "kalman", estimator_speed: float = 3.0,
        sample_time: float | None = None) -> control.StateSpace:
    """LQR attitude controller with a state estimator, as a dynamic output-feedback controller.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous free-floating design plant (e.g. hub + chain): input ``'torque'`` [N*m],
        outputs ``'theta'`` [rad], ``'omega'`` [rad/s], optionally ``'*tip_deflection'`` [m].
    attitude_weight : float, 1/rad^2
        Weight q_theta > 0 on theta^2 in the cost.
    rate_weight : float, s^2/rad^2
        Weight q_omega >= 0 on omega^2.
    torque_weight : float, 1/(N*m)^2
        R = r > 0 on torque^2.
    deflection_weight : float (1/m^2), mapping name -> float, or (n_tip, n_tip) PSD array, optional
        Weight on the plant's tip-deflection outputs (a float applies to each of them).
    estimator : "kalman", KalmanNoise or ndarray (n_states, 2)
        "kalman" (default): steady-state Kalman filter on the design model with the noises of
        :meth:`KalmanNoise.default` (torque disturbance entering with the torque, attitude and rate
        sensor noise; filter about ``estimator_speed`` times faster than the regulator's rigid-body
        poles). A KalmanNoise: a Kalman filter with those intensities. An array: a Luenberger gain
        L on the innovations [theta - theta_hat, omega - omega_hat] (continuous designs only).
    estimator_speed : float
        Ratio of estimator to regulator bandwidth for the default Kalman noises (default 3).
    sample_time : float, s, optional
        Digital design at this sample time: discrete LQR and discrete (predictor) Kalman filter
        on the zero-order-hold discretisation of the plant; the controller has ``dt =
        sample_time``. The sampling frequency must be at least 10 times the continuous design's
        highest gain crossover (:func:`controllers.pd.check_sample_time`).

    Returns
    -------
    control.StateSpace
        Inputs ``['theta_ref', 'theta', 'omega']``, output ``['torque']``, states = the estimate
        x_hat of the design plant's states:
        x_hat' = A x_hat + B torque + L (y - C x_hat - D torque),
        torque = -K (x_hat - x_ref theta_ref), with x_ref from :func:`reference_state`. On a
        free-floating truth plant the steady state is theta = theta_ref exactly (a rigid
        rotation is an equilibrium of plant and estimator, and K x_ref != 0).

    Raises
    ------
    ValueError
        Negative or non-finite weights, R not > 0, Q not PSD, (A, B) not stabilisable (an
        uncontrollable design: an undamped or unstable mode the torque does not reach, tested
        per mode in balanced coordinates, see ``_pbh_defective``), (A, sqrt(Q)) or (A, C_meas)
        not detectable, a Riccati equation without a numerically stabilising solution, a sample
        time too long.

    References
    ----------
    B. D. O. Anderson, J. B. Moore, Optimal Control: Linear Quadratic Methods, Prentice Hall 1990
    (LQR with cross term N, stabilisability/detectability conditions); Franklin, Powell &
    Workman, Digital Control of Dynamic Systems, 3rd ed., ch. 9 (discrete LQR, predictor
    estimator); M. J. Balas, IEEE TAC 23(4), 1978 (observer-based control of flexible structures).
    """
    return lqr_design(plant, attitude_weight=attitude_weight, rate_weight=rate_weight,
                      torque_weight=torque_weight, deflection_weight=deflection_weight,
                      estimator=estimator, estimator_speed=estimator_speed,
                      sample_time=sample_time).controller
