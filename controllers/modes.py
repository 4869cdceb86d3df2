"""Modal properties of a plant: rigid-body inertia, flexible modes, and the modes a loop can
influence (the design model of :func:`controllers.lqr`).

Modes the loop cannot influence
    The first-order shift of a simple mode lambda under any feedback torque = K(s) y is
    delta lambda = K(lambda) r, r the residue of the channel y/torque at lambda: the loop reaches
    a mode only through its participation p = 2 |r| |lambda| J (the fraction of the inertia
    taking part in it, see :class:`FlexibleMode`; independent of the state coordinates). A
    loop whose gains are of the order of the plant's own (|K| ~ J omega_s^2) moves it by about
    p omega_s, less than the margin alpha when p <= INFLUENCE_TOL = MARGIN: such a mode is out
    of the loop's reach (MARGIN, alpha: :mod:`controllers.stability`). When it has no damping to speak of (Re lambda >= -alpha, e.g. the
    symmetric bending of two symmetric wings, p ~ 1e-29, or the free-tip mode of a hinged chain
    of 25 bodies, p ~ 1e-16) it stays at its open-loop place on the imaginary axis in any closed
    loop, neither stabilised nor destabilised. :func:`controllers.lqr` leaves such modes out of
    its design model (the Riccati equations could not stabilise them) and lists them in
    :attr:`LQRDesign.removed_modes <controllers.LQRDesign>`; both designs warn
    (:class:`RemovedModesWarning`) and make their guarantee about the other modes.

References
----------
M. L. J. Hautus, "Controllability and observability conditions of linear autonomous systems",
Proc. KNAW A 72, 1969 (modal test); T. Kato, Perturbation Theory for Linear Operators, 1966,
ch. 2 (first-order eigenvalue shift); B. N. Parlett, C. Reinsch, Numer. Math. 13, 1969
(balancing); G. H. Golub, C. F. Van Loan, Matrix Computations, 4th ed., 2013, sec. 7.6.3
(block diagonalisation by a Sylvester equation).
"""
from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg

from .arguments import describe, real_number
from .frequency import ModalEvaluator, decoupled_parts, modal_evaluator
from .loop import close_loop
from .signals import channels, check_plant, is_digital, require_signal
from .stability import MARGIN, MAX_SCALE_RATIO, RemovedMode, continuous_poles

__all__ = ["FlexibleMode", "INFLUENCE_TOL", "design_model", "flexible_modes", "inertia_matrix",
           "rigid_body_inertia", "verify_loop"]

#: Participation at or below which a loop cannot influence a mode (module docstring).
INFLUENCE_TOL = MARGIN
# Eigenvalues closer than this (relative to the balanced ||A||_1) form one cluster.
_CLUSTER_RTOL = 1e-8

@dataclass(frozen=True)
class FlexibleMode:
    """One flexible mode of a plant channel.

    Attributes
    ----------
    frequency : float, rad/s
        Undamped natural frequency |lambda|.
    damping_ratio : float
        -Re(lambda) / |lambda|.
    residue : complex
        Residue r of the channel's transfer function at lambda (the term r / (s - lambda)),
        units of output / (input * s).
    participation : float
        2 |r| omega J: for a collocated modal form phi^2 / (s^2 + 2 zeta omega s + omega^2) this is
        phi^2 J, the fraction of the total inertia that takes part in the mode.
    """

    frequency: float
    damping_ratio: float
    residue: complex
    participation: float


def _rigid_gain(ev: ModalEvaluator) -> tuple[np.ndarray, np.ndarray]:
    """Coefficients (A1, A2) of the singular part A1/s + A2/s^2 at s = 0 of an evaluator.

    With the rigid block T11 nilpotent of index 2, (sI - T11)^-1 = I/s + T11/s^2, so
    A1 = C1 B1 and A2 = C1 T11 B1 (shapes (outputs, inputs)).
    """
    p, m = ev.C.shape[0], ev.B.shape[1]
    if ev.k == 0:
        return np.zeros((p, m), dtype=complex), np.zeros((p, m), dtype=complex)
    return ev.C1 @ ev.B1, ev.C1 @ ev.T11 @ ev.B1


def rigid_body_inertia(plant: control.StateSpace) -> float | np.ndarray:
    """Total inertia seen by the torque(s): lim_{s->0} s^2 theta(s)/torque(s) = J^-1.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous-time free-floating plant with input ``'torque'`` and output ``'theta'``
        (planar), or inputs ``'torque_x'``, ... and outputs ``'theta_x'``, ... (three-axis).

    Returns
    -------
    float or ndarray (3, 3)
        J in kg*m^2 (about the system's centre of mass for a free-floating spacecraft): a float
        for a planar plant; for a three-axis plant the symmetric positive definite inertia
        tensor in hub axes, the inverse of the 1/s^2 coefficient of the 3 x 3 transfer
        theta/torque.

    Raises
    ------
    ValueError
        If the channel torque -> theta has no rigid-body double integrator (three-axis: if its
        1/s^2 coefficient is not symmetric positive definite).

    References
    ----------
    Low-frequency limit of the free-floating plant theta/torque -> 1/(J s^2); e.g. P. C. Hughes,
    Spacecraft Attitude Dynamics, Wiley 1986, ch. 12 (hybrid coordinates).
    """
    ch = check_plant(plant)
    ev = modal_evaluator(plant, list(ch.torques), list(ch.thetas))
    known = _INERTIAS.get(ev)
    if known is not None:
        # the evaluator is the plant's own while its matrices are unchanged (modal_evaluator)
        return known if np.ndim(known) == 0 else known.copy()
    J = _inertia_of(ev, ch)
    try:
        _INERTIAS[ev] = J if np.ndim(J) == 0 else J.copy()
    except TypeError:  # an evaluator that cannot be weakly referenced: not kept
        pass
    return J


# the inertia of each evaluator's plant, while the evaluator lives (rigid_body_inertia: a
# design loop asks for it in several places)
_INERTIAS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _inertia_of(ev: ModalEvaluator, ch) -> float | np.ndarray:
    """rigid_body_inertia from the evaluator of theta/torque (``ch`` the plant's channels)."""
    A1, A2 = _rigid_gain(ev)
    scale = float(np.linalg.norm(A2, 2)) if np.any(A2) else 1.0
    # a frequency scale to compare the 1/s and 1/s^2 coefficients: A1/A2 is in rad/s
    w_scale = math.sqrt(max(np.linalg.norm(ev.A, 1), 1e-300))
    nilpotent_ok = ev.k == 0 or np.linalg.norm(ev.T11 @ ev.T11) <= 1e-6 * max(
        np.linalg.norm(ev.T11), 1e-300)
    bad = (ev.k == 0 or not nilpotent_ok or np.abs(A2.imag).max() > 1e-8 * scale
           or np.abs(A1).max() > 1e-6 * scale * w_scale)
    if not ch.mimo:
        a1, a2 = complex(A1[0, 0]), complex(A2[0, 0])
        if bad or a2.real <= 0:
            raise ValueError(
                "plant must be free-floating: the channel torque -> theta needs a rigid-body "
                f"double integrator 1/(J s^2) with J > 0 [kg*m^2]; got singular part "
                f"{a1:.3g}/s + {a2:.3g}/s^2 ({ev.k} eigenvalue(s) of A near zero)")
        return float(1.0 / a2.real)
    Jinv = A2.real
    asymmetric = np.abs(Jinv - Jinv.T).max() > 1e-8 * scale
    eig = np.linalg.eigvalsh(0.5 * (Jinv + Jinv.T))
    if bad or asymmetric or eig.min() <= 1e-12 * eig.max():
        raise ValueError(
            "plant must be free-floating: the channels torque_* -> theta_* need a rigid-body "
            "double integrator J^-1/s^2 with J symmetric positive definite [kg*m^2]; got the "
            f"1/s^2 coefficient {describe(np.round(Jinv, 12))} and 1/s coefficient of norm "
            f"{np.abs(A1).max():.3g} ({ev.k} eigenvalue(s) of A near zero)")
    J = np.linalg.inv(0.5 * (Jinv + Jinv.T))
    return 0.5 * (J + J.T)


def inertia_matrix(J) -> np.ndarray:
    """An inertia [kg*m**2] as an (m, m) float64 array: a planar one (a number) as (1, 1), a
    three-axis tensor as it is (no checks: :func:`rigid_body_inertia` gives a checked one)."""
    return np.atleast_2d(np.asarray(J, dtype=float))


def _sqrt_inertia(J) -> np.ndarray:
    """Symmetric square root of the inertia, (m, m)."""
    Jm = inertia_matrix(J)
    w, V = np.linalg.eigh(Jm)
    return (V * np.sqrt(np.maximum(w, 0.0))) @ V.T


def flexible_modes(plant: control.StateSpace, *, input: str | None = None,
                   output: str | None = None, min_participation: float = 1e-9
                   ) -> list[FlexibleMode]:
    """Flexible (lightly damped, complex) modes visible in one channel of a plant.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous-time plant with named signals.
    input, output : str, optional
        Channel. Default: torque -> theta (planar); for a three-axis plant the 3 x 3 channel
        torque_* -> theta_* (each mode's residue is then a (3, 3) matrix and its
        participation 2 |lambda| ||J^1/2 R J^1/2||_2, the planar 2 |r| |lambda| J in any axis).
    min_participation : float
        Modes whose participation (see :class:`FlexibleMode`) is below this are dropped
        (uncontrollable or unobservable in the channel, e.g. symmetric modes of two wings).

    Returns
    -------
    list of FlexibleMode
        Sorted by frequency, one entry per complex-conjugate pair.
    """
    ch = check_plant(plant)
    for value, name in ((input, "input"), (output, "output")):
        if value is not None and not isinstance(value, str):
            raise TypeError(f"{name} must be a signal name (str) or None; got "
                            f"{type(value).__name__} {describe(value)}")
    min_participation = real_number(min_participation, "min_participation", "-")
    if not (math.isfinite(min_participation) and min_participation >= 0):
        raise ValueError(f"min_participation must be non-negative and finite [-]; got "
                         f"{min_participation:.6g}")
    if input is None and output is None:
        inputs, outputs = list(ch.torques), list(ch.thetas)
    else:
        inputs = [ch.torques[0] if input is None else input]
        outputs = [ch.thetas[0] if output is None else output]
    require_signal(plant, inputs[0], "input", "plant")
    require_signal(plant, outputs[0], "output", "plant")
    ev = modal_evaluator(plant, inputs, outputs)
    try:
        J = rigid_body_inertia(plant)
    except ValueError:
        J = np.eye(ch.n_axes)
    Jh = _sqrt_inertia(J)
    if len(inputs) == 1:  # one channel: the inertia seen by that torque
        i = list(ch.torques).index(inputs[0]) if inputs[0] in ch.torques else 0
        Jh = np.array([[math.sqrt(inertia_matrix(J)[i, i])]])
    if not ev.modal:
        lam, V = np.linalg.eig(plant.A)
        raise ValueError("plant A is defective outside its rigid-body block; cannot list modes "
                         f"(eigenvalues {lam[:6]}...)")
    modes = []
    for k, lam in enumerate(ev.lam):
        if lam.imag <= 0:
            continue
        w = abs(lam)
        R = np.outer(ev.Cm[:, k], ev.Bm[k])
        participation = 2.0 * w * np.linalg.norm(Jh @ R @ Jh, 2)
        if participation < min_participation:
            continue
        residue = complex(R[0, 0]) if R.size == 1 else R
        modes.append(FlexibleMode(float(w), float(-lam.real / w), residue, float(participation)))
    return sorted(modes, key=lambda m: m.frequency)


# --------------------------------------------------------------------------------------------
# the modes a loop can influence: the design model
# --------------------------------------------------------------------------------------------
def _channel_rows(plant) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Input columns of the torques and output rows of the thetas and omegas (float64):
    B (n, m), C_theta (m, n), C_omega (m, n); m = 1 (planar) or 3."""
    ch = channels(plant)
    inputs, outputs = list(plant.input_labels), list(plant.output_labels)
    B = np.asarray(plant.B, dtype=float)[:, [inputs.index(n) for n in ch.torques]]
    C = np.asarray(plant.C, dtype=float)
    return (B, C[[outputs.index(n) for n in ch.thetas]],
            C[[outputs.index(n) for n in ch.omegas]])


def _cluster_null_spaces(A, lam, group, tol):
    """Right and left null spaces (V, U) of A - mu I for a cluster of eigenvalues."""
    mu = lam[group].mean()
    U, s, Vh = np.linalg.svd(A - mu * np.eye(A.shape[0]))
    null = s <= tol
    if not null.any():
        null[-len(group):] = True
    return Vh[null].conj().T, U[:, null], mu


def _cluster_participation(A, lam, Wl, Vr, group, B, C_theta, C_omega, Jh, tol) -> float:
    """Participation max(2 |lambda| ||J^1/2 R_theta J^1/2||, 2 ||J^1/2 R_omega J^1/2||) of a
    cluster of eigenvalues (planar: max(2 |r_theta| |lambda| J, 2 |r_omega| J)).

    A simple eigenvalue's residue is R = (C v)(w^H B) / (w^H v) with right and left
    eigenvectors v, w (any scaling). A cluster's is C P B with the spectral projector
    P = V (U^H V)^-1 U^H on its right and left null spaces V, U (the SVD of A - mu I).
    Both are invariant under a change of state coordinates; J^1/2 (Jh) makes them invariant
    under a change of torque units per axis too.
    """
    if len(group) == 1:
        i = group[0]
        v, w = Vr[:, i], Wl[:, i]
        wB = Jh.T @ ((w.conj() @ B) / np.vdot(w, v))
        # a simple eigenvalue's residue is of rank one, J^1/2 (C v)(w^H B) J^1/2: its 2-norm
        # is the product of the two vectors' norms (no SVD)
        b = np.linalg.norm(wB)
        return float(max(2.0 * abs(lam[i]) * np.linalg.norm(Jh @ (C_theta @ v)) * b,
                         2.0 * np.linalg.norm(Jh @ (C_omega @ v)) * b))
    else:
        Vn, Un, mu = _cluster_null_spaces(A, lam, group, tol)
        PB = Vn @ np.linalg.lstsq(Un.conj().T @ Vn, Un.conj().T @ B, rcond=None)[0]
        R_theta, R_omega = C_theta @ PB, C_omega @ PB
    return float(max(2.0 * abs(mu) * np.linalg.norm(Jh @ R_theta @ Jh, 2),
                     2.0 * np.linalg.norm(Jh @ R_omega @ Jh, 2)))


def _cluster_reachable(A, lam, group, B, C_meas, tol) -> bool:
    """Multi-input PBH test of a cluster of k (nearly) repeated eigenvalues: the torques reach
    and the measurements see all k of them, rank(U^H B) = rank(C V) = k (singular values above
    1e-8 of the largest). One torque reaches one combination only (rank 1)."""
    Vn, Un, _ = _cluster_null_spaces(A, lam, group, tol)
    k = len(group)

    def rank(M):
        sv = np.linalg.svd(M, compute_uv=False)
        return int(np.sum(sv > 1e-8 * sv.max())) if sv.size and sv.max() > 0 else 0

    return rank(Un.conj().T @ B) >= k and rank(C_meas @ Vn) >= k


def _clusters(lam: np.ndarray, mask: np.ndarray, tol: float) -> list[list[int]]:
    """Groups of the eigenvalues lam[mask] closer than tol to one another (chained)."""
    left = [int(i) for i in np.nonzero(mask)[0]]
    groups = []
    while left:
        group = [left.pop(0)]
        grown = True
        while grown:
            near = [j for j in left if np.min(np.abs(lam[group] - lam[j])) <= tol]
            grown = bool(near)
            group += near
            left = [j for j in left if j not in near]
        groups.append(group)
    return groups


def design_model(plant: control.StateSpace, *, critical: float, J, what: str
                 ) -> tuple[control.StateSpace, list[RemovedMode], np.ndarray]:
    """The plant without the modes a loop cannot influence (see the module docstring).

    A mode is left out when Re(lambda) >= -critical [1/s] (no damping to speak of) and its
    participation is <= INFLUENCE_TOL; so is rigid-body motion (eigenvalue 0) that carries no
    part of theta/torque = 1/(J s^2) (a hub translation). The plant's decoupled parts (connected
    components of A's sparsity graph: the modes of a modal realisation) are kept or dropped
    whole, exactly; a part holding both kinds is split along its invariant subspaces (ordered
    real Schur form, Sylvester equation), the kept spectrum first.

    Parameters
    ----------
    plant : control.StateSpace
        The plant (checked by the caller).
    critical : float, 1/s
        Modes with Re(lambda) >= -critical count as undamped.
    J : float or ndarray, kg*m**2
        The plant's rigid-body inertia (:func:`rigid_body_inertia`).
    what : str
        The caller's name for the messages ("pd", "lqr").

    Returns
    -------
    (control.StateSpace, list of RemovedMode, ndarray of complex)
        The design plant (the plant itself when nothing is removed; same signals), the
        removed modes sorted by frequency and their eigenvalues (every one, conjugates too).

    Raises
    ------
    ValueError
        Repeated (within 1e-8 of ||A||) critical modes that the torques do not all reach or the
        measurements do not all see (multi-input PBH test, :func:`_cluster_reachable`; a single
        torque reaches one combination only): the loop cannot control them all.
    """
    A = np.asarray(plant.A, dtype=float)
    n = A.shape[0]
    if n == 0:
        return plant, [], np.zeros(0, dtype=complex)
    b, c_theta, c_omega = _channel_rows(plant)
    Jh = _sqrt_inertia(J)
    Ab, (d, _) = scipy.linalg.matrix_balance(A, permute=False, separate=True)
    norm = max(np.linalg.norm(Ab, 1), np.finfo(float).tiny)
    rigid_tol = 1e-6 * math.sqrt(max(norm, 1.0))  # as ModalEvaluator: sqrt(eps)-perturbed
    cluster_tol = _CLUSTER_RTOL * norm            # Jordan blocks and repeated frequencies
    n_parts, part_of = decoupled_parts(A != 0.0)
    if _nothing_to_remove(Ab, d, part_of, n_parts, b, c_theta, c_omega, Jh, critical,
                          rigid_tol, cluster_tol):
        return plant, [], np.zeros(0, dtype=complex)
    keep_whole: list[np.ndarray] = []
    split: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
    removed: list[RemovedMode] = []
    removed_eigs: list[np.ndarray] = []
    for idx, (lam, Wl, Vr) in _joint_parts(Ab, part_of, n_parts, critical, rigid_tol,
                                           cluster_tol):
        Ap = Ab[np.ix_(idx, idx)]
        bp = b[idx] / d[idx, None]
        ctp, cop = c_theta[:, idx] * d[None, idx], c_omega[:, idx] * d[None, idx]
        rigid = np.abs(lam) <= rigid_tol
        if rigid.all():
            # nilpotent part: its share of the rigid-body response 1/(J s^2) (theta: the
            # 1/s^2 coefficient C A B; omega: the 1/s coefficient C B)
            share = max(np.linalg.norm(Jh @ (ctp @ Ap @ bp) @ Jh, 2),
                        np.linalg.norm(Jh @ (cop @ bp) @ Jh, 2))
            if share <= INFLUENCE_TOL:
                removed.append(RemovedMode(0.0, 0.0, float(share), idx.size,
                                           "rigid-body motion that carries no part of "
                                           "theta/torque (e.g. a translation)"))
                removed_eigs.append(lam)
            else:
                keep_whole.append(idx)
            continue
        removable = np.zeros(lam.size, dtype=bool)
        for group in _clusters(lam, (~rigid) & (lam.real >= -critical), cluster_tol):
            p = _cluster_participation(Ap, lam, Wl, Vr, group, bp, ctp, cop, Jh, cluster_tol)
            mu = lam[group].mean()
            if p <= INFLUENCE_TOL:
                removable[group] = True
                removed_eigs.append(lam[group])
                if mu.imag >= 0:
                    w = abs(mu)
                    removed.append(RemovedMode(float(w), float(-mu.real / w) if w else 0.0, p,
                                               len(group), "participation <= INFLUENCE_TOL"))
            elif len(group) > 1 and not _cluster_reachable(
                    Ap, lam, group, bp, np.vstack([ctp, cop]), cluster_tol):
                reach = ("a single torque reaches only one combination of them" if
                         b.shape[1] == 1 else "the torques reach (or the measurements see) "
                         "fewer independent combinations of them")
                raise ValueError(
                    f"{what}: {len(group)} modes at {abs(mu):.6g} rad/s are (nearly) repeated "
                    f"and undamped: {reach}, the "
                    "others stay undamped; give them damping or remove all but one from the "
                    "design plant")
        if not removable.any():
            keep_whole.append(idx)
        elif not removable.all():
            dropped = lam[removable]

            def kept(re, im):
                return np.min(np.abs(re + 1j * im - dropped)) > cluster_tol

            T, Z, k = scipy.linalg.schur(Ap, output="real", sort=kept)
            if k != int((~removable).sum()):
                raise ValueError(f"{what}: could not separate the modes to remove from the "
                                 "others (eigenvalues too close)")
            X = scipy.linalg.solve_sylvester(T[:k, :k], -T[k:, k:], -T[:k, k:])
            # x_b = Z [[I, X], [0, I]] xi: the kept coordinates xi_1 = (Z^T x_b)_1 - X (Z^T x_b)_2
            V = d[idx, None] * Z[:, :k]
            W = (Z[:, :k].T - X @ Z[:, k:].T) / d[idx][None, :]
            split.append((idx, V, W, T[:k, :k]))
    if not removed:
        return plant, [], np.zeros(0, dtype=complex)
    B = np.asarray(plant.B, dtype=float)
    C = np.asarray(plant.C, dtype=float)
    whole = np.sort(np.concatenate(keep_whole)) if keep_whole else np.zeros(0, dtype=int)
    labels = list(plant.state_labels)
    A_blocks = [A[np.ix_(whole, whole)]] + [Tk for _, _, _, Tk in split]
    Bd = np.vstack([B[whole]] + [W @ B[idx] for idx, _, W, _ in split])
    Cd = np.hstack([C[:, whole]] + [C[:, idx] @ V for idx, V, _, _ in split])
    states = [labels[i] for i in whole]
    for j, (_, V, _, _) in enumerate(split):
        states += [f"design_part{j}_x{i}" for i in range(V.shape[1])]
    design = control.ss(scipy.linalg.block_diag(*A_blocks), Bd, Cd, plant.D, 0,
                        inputs=list(plant.input_labels), outputs=list(plant.output_labels),
                        states=states, name=plant.name)
    return design, sorted(removed, key=lambda m: m.frequency), np.concatenate(removed_eigs)


# A participation this many times INFLUENCE_TOL or more decides "kept" in the batched check
# of _nothing_to_remove; nearer the threshold the per-part analysis decides (round-off of the
# two computations differs by ~eps cond, far below this factor).
_CLEARLY_KEPT = 1e3


def _nothing_to_remove(Ab, d, part_of, n_parts, b, c_theta, c_omega, Jh, critical,
                       rigid_tol, cluster_tol) -> bool:
    """True when a modal realisation (every decoupled part 1 x 1 or 2 x 2) clearly has no
    mode to remove: every rigid-body part carries its share of theta/torque and every
    undamped mode's participation is far above INFLUENCE_TOL, with no two undamped
    eigenvalues within ``cluster_tol`` (which the per-part analysis would join or test).

    The same quantities as design_model's per-part analysis (the balanced matrix ``Ab`` with
    scaling ``d``), computed for all parts at once: each part's eigenvectors V from one
    batched eigen-decomposition and its left eigenvectors as the rows of V^-1 (a simple
    eigenvalue's residue (C v)(w^H B) / (w^H v) is (C v)(V^-1 B)_i). False (the per-part
    analysis decides) for any other realisation, a cluster, a defective non-rigid part or a
    participation within a factor _CLEARLY_KEPT of the threshold.
    """
    sizes = np.bincount(part_of, minlength=n_parts)
    if sizes.max(initial=0) > 2:
        return False
    order = np.argsort(part_of, kind="stable")
    starts = np.concatenate([[0], np.cumsum(sizes)])
    bs = b / d[:, None]
    cts, cos = c_theta * d[None, :], c_omega * d[None, :]
    critical_lam = []
    for size in (1, 2):
        parts = np.flatnonzero(sizes == size)
        if not parts.size:
            continue
        idx = order[starts[parts][:, None] + np.arange(size)]                # (g, size)
        M = Ab[idx[:, :, None], idx[:, None, :]]                            # (g, size, size)
        lam, V = np.linalg.eig(M)
        rigid = np.abs(lam) <= rigid_tol
        whole = rigid.all(axis=1)
        if whole.any():
            # nilpotent parts: the share of theta/torque (C A B, C B), as design_model
            Mr, ir = M[whole], idx[whole]
            bp = bs[ir]                                                     # (g, size, m)
            share_t = np.einsum("pgi,gij,gjm->gpm", cts[:, ir], Mr, bp)
            share_o = np.einsum("pgi,gim->gpm", cos[:, ir], bp)
            share = np.maximum(np.linalg.norm(Jh @ share_t @ Jh, 2, axis=(1, 2)),
                               np.linalg.norm(Jh @ share_o @ Jh, 2, axis=(1, 2)))
            if np.any(share <= _CLEARLY_KEPT * INFLUENCE_TOL):
                return False
        undamped = ~rigid & (lam.real >= -critical) & ~whole[:, None]
        if not undamped.any():
            continue
        parts_u = np.flatnonzero(undamped.any(axis=1))
        with np.errstate(all="ignore"):
            cond = np.linalg.cond(V[parts_u]) if size > 1 else np.ones(parts_u.size)
        if not np.all(np.isfinite(cond) & (cond < 1e8)):
            return False
        Vu, iu = V[parts_u], idx[parts_u]
        WB = np.linalg.solve(Vu, bs[iu].astype(complex))                   # (g, size, m)
        Cv_t = np.einsum("pgi,gik->gkp", cts[:, iu], Vu)                    # (g, size, p)
        Cv_o = np.einsum("pgi,gik->gkp", cos[:, iu], Vu)
        sel = undamped[parts_u]
        wb = np.linalg.norm(WB[sel] @ Jh, axis=1)
        p_t = 2.0 * np.abs(lam[parts_u][sel]) * np.linalg.norm(Cv_t[sel] @ Jh.T, axis=1) * wb
        p_o = 2.0 * np.linalg.norm(Cv_o[sel] @ Jh.T, axis=1) * wb
        p = np.maximum(p_t, p_o)
        if not np.all(np.isfinite(p)) or np.any(p <= _CLEARLY_KEPT * INFLUENCE_TOL):
            return False
        critical_lam.append(lam[parts_u][sel])
    if critical_lam:
        # two eigenvalues within cluster_tol have imaginary parts within it: sorted by them,
        # each is compared with the few that follow within cluster_tol (O(n log n))
        lam = np.concatenate(critical_lam)
        lam = lam[np.argsort(lam.imag, kind="stable")]
        last = np.searchsorted(lam.imag, lam.imag + cluster_tol, side="right")
        for i in np.flatnonzero(last > np.arange(lam.size) + 1):
            if np.min(np.abs(lam[i + 1:last[i]] - lam[i])) <= cluster_tol:
                return False
    return True


def _joint_parts(Ab, part_of, n_parts, critical, rigid_tol, cluster_tol):
    """The decoupled parts of A (connected components), joined where a (nearly) repeated
    critical eigenvalue (non-rigid, Re >= -critical) occurs in several of them, each with its
    eigen-decomposition (eigenvalues, left and right eigenvectors).

    Identical modes in separate parts (two identical wings in a modal realisation) are one
    repeated eigenvalue of A: which combinations of them the torques reach is a question about
    them together (the PBH test of _cluster_reachable), so their parts are analysed as one.
    Critical eigenvalues lie within critical of the imaginary axis: sorted by their imaginary
    parts, repeated ones are neighbours (O(n log n), no pairwise search).
    """
    parts = [np.flatnonzero(part_of == p) for p in range(n_parts)]
    eigs = [scipy.linalg.eig(Ab[np.ix_(idx, idx)], left=True, right=True) for idx in parts]
    owner = np.concatenate([np.full(e[0].size, p) for p, e in enumerate(eigs)]) if eigs else \
        np.zeros(0, dtype=int)
    lam = np.concatenate([e[0] for e in eigs]) if eigs else np.zeros(0, dtype=complex)
    root = list(range(n_parts))

    def find(p):
        while root[p] != p:
            root[p] = root[root[p]]
            p = root[p]
        return p

    critical_ones = np.nonzero((np.abs(lam) > rigid_tol) & (lam.real >= -critical))[0]
    order = critical_ones[np.argsort(lam[critical_ones].imag, kind="stable")]
    for i, j in zip(order[:-1], order[1:]):
        if owner[i] != owner[j] and abs(lam[i] - lam[j]) <= cluster_tol:
            root[find(owner[i])] = find(owner[j])
    groups: dict[int, list[int]] = {}
    for p in range(n_parts):
        groups.setdefault(find(p), []).append(p)
    for members in groups.values():
        if len(members) == 1:
            yield parts[members[0]], eigs[members[0]]
        else:
            idx = np.sort(np.concatenate([parts[p] for p in members]))
            yield idx, scipy.linalg.eig(Ab[np.ix_(idx, idx)], left=True, right=True)


def _mode_participations(plant, J, eigenvalues) -> list[float]:
    """Participation (see the module docstring) of the plant's modes nearest ``eigenvalues``
    (one eigendecomposition for all)."""
    b, c_theta, c_omega = _channel_rows(plant)
    Ab, (d, _) = scipy.linalg.matrix_balance(np.asarray(plant.A, dtype=float), permute=False,
                                             separate=True)
    lam, Wl, Vr = scipy.linalg.eig(Ab, left=True, right=True)
    Jh = _sqrt_inertia(J)
    return [_cluster_participation(Ab, lam, Wl, Vr, [int(np.argmin(np.abs(lam - x)))],
                                   b / d[:, None], c_theta * d[None, :], c_omega * d[None, :],
                                   Jh, 0.0) for x in eigenvalues]


def verify_loop(plant: control.StateSpace, controller: control.StateSpace, *, J,
                what: str, advise, removed_eigs: np.ndarray | None = None,
                scale_floor: float = 0.0) -> tuple[float, list[RemovedMode]]:
    """Check the stability guarantee of a designed loop on its design plant.

    Every pole s of ``close_loop(plant, controller)`` (s = log(z) / T for a digital loop) must
    have Re(s) <= -alpha, alpha = MARGIN * omega_s, omega_s the largest of |s|, |lambda| over
    the plant's eigenvalues and ``scale_floor`` [rad/s]. A pole with Re(s) > -alpha is excused
    only as a mode the loop leaves where it was: within alpha of a plant eigenvalue lambda with
    Re(lambda) >= -alpha (aliased to the sampling band for a digital loop) that is in
    ``removed_eigs`` (the modes left out of a design model) or, when ``removed_eigs`` is None,
    any flexible mode (this loop moves it by less than the margin) and rigid-body motion that
    carries no part of theta/torque (a translation).

    Parameters
    ----------
    plant, controller : control.StateSpace
        The design plant and the designed controller.
    J : float or ndarray, kg*m**2
        The plant's rigid-body inertia (:func:`rigid_body_inertia`).
    what : str
        The design's name for the messages ("pd", "lqr").
    advise : callable (pole: complex, alpha: float, scale: float) -> str
        The message's second half: which parameter to change and how.
    removed_eigs : ndarray of complex, optional
        The eigenvalues of the modes left out of a design model (:func:`design_model`).
    scale_floor : float, rad/s
        A lower bound of the loop's spectral scale omega_s (a design's rigid-body bandwidth).

    Returns
    -------
    (float, list of RemovedMode)
        alpha [1/s] and the excused modes.

    Raises
    ------
    ValueError
        A pole violates the guarantee (the message names the mode, its frequency and the
        advice).
    """
    loop = close_loop(plant, controller)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        poles = continuous_poles(loop)
        A = np.asarray(plant.A, dtype=float)
        lam = np.linalg.eigvals(A).astype(complex) if A.size else np.zeros(0, dtype=complex)
        T = float(controller.dt) if is_digital(controller) else 0.0
        if T:
            lam = np.log(np.exp(lam * T)) / T  # the sampled plant's modes, aliased
    if not np.all(np.isfinite(poles)):
        raise ValueError(f"{what}: the closed loop on the design plant has non-finite poles; "
                         f"{advise(complex(np.inf), np.inf, np.inf)}")
    scale = max(np.abs(poles).max(initial=0.0), np.abs(lam).max(initial=0.0), scale_floor,
                np.finfo(float).tiny)
    alpha = MARGIN * scale
    norm = np.linalg.norm(scipy.linalg.matrix_balance(A, permute=False)[0], 1) if A.size else 0.0
    rigid = np.abs(lam) <= 1e-6 * math.sqrt(max(norm, 1.0))
    w_low = np.abs(lam[~rigid]).min(initial=np.inf)
    if scale > MAX_SCALE_RATIO * w_low:
        raise ValueError(
            f"{what}: the loop's spectral scale {scale:.4g} rad/s is more than "
            f"{MAX_SCALE_RATIO:g} times the plant's lowest flexible mode {w_low:.4g} rad/s: its "
            f"stability margin {alpha:.2g} 1/s cannot resolve that mode's poles; "
            f"{advise(0j, alpha, scale)}")
    bad = sorted(np.nonzero(poles.real > -alpha)[0], key=lambda i: -poles[i].real)
    if not bad:
        return alpha, []
    allowed = (np.zeros(lam.size, dtype=bool) if removed_eigs is None else
               np.array([np.min(np.abs(removed_eigs - x), initial=np.inf)
                         <= _CLUSTER_RTOL * max(norm, 1.0) for x in lam], dtype=bool))
    if removed_eigs is None:
        allowed = ~rigid
        if rigid.any():
            # rigid-body motion the loop cannot move (translations): from the design model
            _, removed, _ = design_model(plant, critical=alpha, J=J, what=what)
            n_free = sum(m.multiplicity for m in removed if m.frequency == 0.0)
            allowed[np.nonzero(rigid)[0][:n_free]] = True
    allowed &= lam.real >= -alpha
    used = np.zeros(lam.size, dtype=bool)
    for i in bad:
        distance = np.where(allowed & ~used, np.abs(lam - poles[i]), np.inf)
        j = int(np.argmin(distance)) if lam.size else -1
        if j < 0 or distance[j] > alpha:
            raise ValueError(
                f"{what}: the closed loop on the design plant has a pole at "
                f"{_pole_text(poles[i])}, Re(s) > -{alpha:.2g} 1/s (the stability margin, "
                f"{MARGIN:g} x the loop's spectral scale {scale:.4g} rad/s); "
                f"{advise(complex(poles[i]), alpha, scale)}")
        used[j] = True
    excused: list[RemovedMode] = []
    flexible = np.nonzero(used & ~rigid & (lam.imag >= 0))[0]
    shares = _mode_participations(plant, J, lam[flexible]) if flexible.size else []
    for j, p in zip(flexible, shares):
        w = abs(lam[j])
        excused.append(RemovedMode(
            float(w), 0.0 + float(-lam[j].real / w) if w else 0.0, p, 1,
            "participation <= INFLUENCE_TOL" if p <= INFLUENCE_TOL else
            "this loop moves it by less than the margin"))
    if (used & rigid).any():
        excused.append(RemovedMode(0.0, 0.0, 0.0, int((used & rigid).sum()),
                                   "rigid-body motion that carries no part of theta/torque "
                                   "(e.g. a translation)"))
    return alpha, sorted(excused, key=lambda m: m.frequency)


def _pole_text(s: complex) -> str:
    """'-1.2e-13 + 656.3j (656.3 rad/s)' for a message."""
    return f"{s.real:.3g} {'+' if s.imag >= 0 else '-'} {abs(s.imag):.6g}j ({abs(s):.6g} rad/s)"
