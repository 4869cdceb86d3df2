"""Closed-loop analysis of attitude controllers on plants with named signals.

Signal conventions (DESIGN.md): a plant is a continuous-time ``control.StateSpace`` (or, for the
frequency-domain functions, a ``control.FrequencyResponseData``) with input ``'torque'`` [N*m]
(possibly other inputs such as ``'disturbance_torque'``) and outputs ``'theta'`` [rad] and
``'omega'`` [rad/s], optionally ``'<appendage>.tip_deflection'`` [m] outputs. A controller is a
``control.StateSpace`` with output ``'torque'`` and inputs ``'theta_ref'``, ``'theta'``,
``'omega'`` (torque = controller(inputs), no hidden minus sign). A controller with ``dt`` set is
a digital controller: its loop with a continuous plant is the sampled-data loop (zero-order hold
on the torque, sampled measurements).

The loop transfer function is taken with the loop broken at the plant's torque input and the
negative-feedback convention, L(s) = -sum_i K_i(s) P_i(s), where P_i is the transfer from torque to
the i-th measured plant output and K_i the controller's transfer from that measurement to torque.
For a PD controller on a rigid hub, L(s) = (Kp + Kd s) / (J s^2).
"""
from __future__ import annotations

import cmath
import math
from dataclasses import dataclass
from typing import Callable, Sequence

import control
import numpy as np
import scipy.linalg
import scipy.optimize

from .simulate import simulate

__all__ = [
    "FlexibleMode",
    "Margins",
    "SpilloverVerdict",
    "METRIC_UNITS",
    "rigid_body_inertia",
    "flexible_modes",
    "close_loop",
    "loop_frequency_response",
    "slew_profile",
    "slew",
    "step_response",
    "disturbance_response",
    "metrics",
    "margins",
    "spillover",
]

#: Units of the metrics returned by :func:`metrics` and :func:`margins` (for tables).
METRIC_UNITS: dict[str, str] = {
    "overshoot": "%",
    "settling_time": "s",
    "peak_torque": "N*m",
    "peak_tip_deflection": "m",
    "peak_attitude_error": "rad",
    "final_attitude_error": "rad",
    "gain_margin": "dB",
    "phase_margin": "deg",
    "modulus_margin": "1",
}

TORQUE = "torque"
THETA = "theta"
OMEGA = "omega"
THETA_REF = "theta_ref"
TIP_SUFFIX = "tip_deflection"


# --------------------------------------------------------------------------------------------
# signal and system checks
# --------------------------------------------------------------------------------------------
def _labels(system, kind: str) -> list[str]:
    return list(system.input_labels if kind == "input" else system.output_labels)


def _require_signal(system, name: str, kind: str, what: str) -> int:
    labels = _labels(system, kind)
    if name not in labels:
        raise ValueError(f"{what} must have an {kind} named {name!r}; got {kind}s {labels}")
    return labels.index(name)


def _check_plant(plant, what: str = "plant", *, allow_frd: bool = False) -> None:
    allowed = (control.StateSpace, control.FrequencyResponseData) if allow_frd else (
        control.StateSpace,)
    if not isinstance(plant, allowed):
        expected = " or ".join(t.__name__ for t in allowed)
        raise TypeError(f"{what} must be a control.{expected}; got {type(plant).__name__}")
    if isinstance(plant, control.StateSpace) and not plant.isctime(strict=True):
        raise ValueError(f"{what} must be continuous-time (dt=0); got dt={plant.dt}")
    _require_signal(plant, TORQUE, "input", what)
    if isinstance(plant, control.FrequencyResponseData):
        # an FRD needs one of theta, omega: the other follows from omega = j w theta
        if THETA not in plant.output_labels and OMEGA not in plant.output_labels:
            raise ValueError(f"{what} must have an output named 'theta' or 'omega'; got outputs "
                             f"{list(plant.output_labels)}")
        return
    _require_signal(plant, THETA, "output", what)
    _require_signal(plant, OMEGA, "output", what)


def _check_controller(controller, what: str = "controller") -> None:
    if not isinstance(controller, control.StateSpace):
        raise TypeError(f"{what} must be a control.StateSpace; got {type(controller).__name__}")
    if controller.noutputs != 1 or controller.output_labels[0] != TORQUE:
        raise ValueError(f"{what} must have exactly one output named 'torque'; got outputs "
                         f"{list(controller.output_labels)}")
    if controller.dt is True:  # None: a static gain, usable in either time base
        raise ValueError(f"{what} must be continuous (dt=0) or have a sample time dt > 0 [s]; "
                         f"got dt={controller.dt}")


def _measurements(plant, controller) -> list[str]:
    """Controller inputs that are plant outputs (the fed-back signals)."""
    outputs = _labels(plant, "output")
    measured = [name for name in controller.input_labels if name in outputs]
    if not measured:
        raise ValueError(f"controller inputs {list(controller.input_labels)} contain none of the "
                         f"plant outputs {outputs}: nothing is fed back")
    return measured


def _reference_inputs(controller, plant_outputs: Sequence[str]) -> list[str]:
    others = [n for n in controller.input_labels if n not in plant_outputs]
    bad = [n for n in others if "ref" not in n]
    if bad:
        raise ValueError(f"controller inputs {bad} are neither plant outputs nor reference inputs "
                         "(names containing 'ref')")
    return others


def _is_digital(controller) -> bool:
    return bool(controller.isdtime(strict=True))


# --------------------------------------------------------------------------------------------
# fast frequency response of a state-space model
# --------------------------------------------------------------------------------------------
class _ModalEvaluator:
    """Evaluate C (sI - A)^-1 B + D at many complex points in O(n) per point.

    A is brought to complex Schur form with its near-zero eigenvalues (the rigid-body Jordan
    block of a free-floating plant, which is defective and cannot be diagonalised) first,
    T = [[T11, T12], [0, T22]]. The Sylvester equation T11 X - X T22 = -T12 block-diagonalises
    T with S = [[I, X], [0, I]]: S^-1 T S = diag(T11, T22). T22 (well separated, non-defective
    eigenvalues) is diagonalised; the small block T11 is solved directly.

    References
    ----------
    G. H. Golub and C. F. Van Loan, Matrix Computations, 4th ed., 2013, sec. 7.6.3
    (block diagonalisation by a Sylvester equation).
    """

    def __init__(self, A, B, C, D):
        A = np.asarray(A, dtype=float)
        self.B = np.asarray(B, dtype=float)
        self.C = np.asarray(C, dtype=float)
        self.D = np.asarray(D, dtype=float)
        n = A.shape[0]
        self.n = n
        if n == 0:
            self.k = 0
            self.modal = True
            self.rigid_tol = 0.0
            return
        # balancing (an exact diagonal similarity, powers of 2) brings a modal block
        # [[0, 1], [-w^2, -2 zeta w]] to norm ~w; the rigid-body Jordan block's eigenvalues are
        # then perturbed by ~sqrt(eps |A|), far below this tolerance
        Ab, (scale, perm) = scipy.linalg.matrix_balance(A, separate=True)
        Tb = np.zeros((n, n))
        Tb[perm, np.arange(n)] = scale  # A = Tb Ab Tb^-1
        self.rigid_tol = 1e-6 * math.sqrt(max(np.linalg.norm(Ab, 1), 1.0))
        T, Z, k = scipy.linalg.schur(Ab.astype(complex), output="complex",
                                     sort=lambda x: abs(x) <= self.rigid_tol)
        self.k = int(k)
        T11, T12, T22 = T[:k, :k], T[:k, k:], T[k:, k:]
        if 0 < k < n:
            X = scipy.linalg.solve_sylvester(T11, -T22, -T12)
        else:
            X = np.zeros((k, n - k), dtype=complex)
        CZ = (self.C @ Tb) @ Z
        ZB = Z.conj().T @ np.linalg.solve(Tb, self.B)
        # C Z S and S^-1 Z^H B with S = [[I, X], [0, I]], S^-1 = [[I, -X], [0, I]]
        self.C1 = CZ[:, :k]
        C2 = CZ[:, k:] + CZ[:, :k] @ X
        self.B1 = ZB[:k] - X @ ZB[k:]
        B2 = ZB[k:]
        self.T11 = T11
        self.modal = True
        if n - k:
            lam, V = np.linalg.eig(T22)
            cond = np.linalg.cond(V)
            if not np.isfinite(cond) or cond > 1e10:
                self.modal = False
            else:
                self.lam = lam
                self.Cm = C2 @ V
                self.Bm = np.linalg.solve(V, B2)
        else:
            self.lam = np.zeros(0, dtype=complex)
            self.Cm = np.zeros((self.C.shape[0], 0), dtype=complex)
            self.Bm = np.zeros((0, self.B.shape[1]), dtype=complex)
        if self.modal:
            # residues R_i = Cm[:, i] Bm[i, :] of the partial fractions, one row per pole:
            # G(s) = D + C1 (sI - T11)^-1 B1 + sum_i R_i / (s - lam_i) is then one matrix product
            p, m = self.C.shape[0], self.B.shape[1]
            self.residues = (self.Cm.T[:, :, None] * self.Bm[:, None, :]).reshape(-1, p * m)
        self.A = A

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """Return G(s), shape (len(s), n_outputs, n_inputs), complex128."""
        s = np.asarray(s, dtype=complex).reshape(-1)
        p, m = self.C.shape[0], self.B.shape[1]
        if self.n == 0:
            return np.broadcast_to(self.D.astype(complex), (s.size, p, m)).copy()
        if not self.modal:
            G = np.broadcast_to(self.D.astype(complex), (s.size, p, m)).copy()
            M = s[:, None, None] * np.eye(self.n) - self.A
            return G + self.C @ np.linalg.solve(M, np.broadcast_to(self.B, (s.size,) + self.B.shape))
        G = (1.0 / (s[:, None] - self.lam)) @ self.residues + self.D.reshape(1, p * m)
        G = G.reshape(s.size, p, m)
        if self.k:
            # (sI - T11) X = B1 by back substitution (T11 upper triangular), all s at once
            T11, k = self.T11, self.k
            X = np.empty((s.size, k, m), dtype=complex)
            for i in range(k - 1, -1, -1):
                rhs = self.B1[i] + np.einsum("j,fjm->fm", T11[i, i + 1:], X[:, i + 1:])
                X[:, i] = rhs / (s - T11[i, i])[:, None]
            G += np.einsum("pk,fkm->fpm", self.C1, X)
        return G

    def characteristic_frequencies(self) -> np.ndarray:
        """Undamped natural frequencies |lambda| of the non-rigid eigenvalues [rad/s]."""
        if self.n == 0:
            return np.zeros(0)
        lam = self.lam if self.modal else np.linalg.eigvals(self.A)
        w = np.abs(lam)
        return w[w > self.rigid_tol]


def _evaluator(system, inputs: Sequence[str], outputs: Sequence[str]) -> _ModalEvaluator:
    i_in = [list(system.input_labels).index(n) for n in inputs]
    i_out = [list(system.output_labels).index(n) for n in outputs]
    return _ModalEvaluator(system.A, system.B[:, i_in], system.C[i_out, :],
                           system.D[np.ix_(i_out, i_in)])


# --------------------------------------------------------------------------------------------
# plant properties
# --------------------------------------------------------------------------------------------
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


def _rigid_gain(ev: _ModalEvaluator) -> tuple[complex, complex]:
    """Coefficients (a1, a2) of the singular part a1/s + a2/s^2 at s = 0 of a SISO evaluator.

    With the rigid block T11 nilpotent of index 2, (sI - T11)^-1 = I/s + T11/s^2, so
    a1 = C1 B1 and a2 = C1 T11 B1.
    """
    if ev.k == 0:
        return 0j, 0j
    a1 = (ev.C1 @ ev.B1)[0, 0]
    a2 = (ev.C1 @ ev.T11 @ ev.B1)[0, 0]
    return a1, a2


def rigid_body_inertia(plant: control.StateSpace) -> float:
    """Total inertia J [kg*m^2] seen by the torque: lim_{s->0} s^2 theta(s)/torque(s) = 1/J.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous-time free-floating plant with input ``'torque'`` and output ``'theta'``.

    Returns
    -------
    float
        J in kg*m^2 (about the system's centre of mass for a free-floating spacecraft).

    Raises
    ------
    ValueError
        If the channel torque -> theta has no rigid-body double integrator.

    References
    ----------
    Low-frequency limit of the free-floating plant theta/torque -> 1/(J s^2); e.g. P. C. Hughes,
    Spacecraft Attitude Dynamics, Wiley 1986, ch. 12 (hybrid coordinates).
    """
    _check_plant(plant)
    ev = _evaluator(plant, [TORQUE], [THETA])
    a1, a2 = _rigid_gain(ev)
    scale = abs(a2) if a2 else 1.0
    # a frequency scale to compare the 1/s and 1/s^2 coefficients: a1/a2 is in rad/s
    w_scale = math.sqrt(max(np.linalg.norm(ev.A, 1), 1e-300))
    nilpotent_ok = ev.k == 0 or np.linalg.norm(ev.T11 @ ev.T11) <= 1e-6 * max(
        np.linalg.norm(ev.T11), 1e-300)
    if (ev.k == 0 or not nilpotent_ok or abs(a2.imag) > 1e-8 * scale or a2.real <= 0
            or abs(a1) > 1e-6 * scale * w_scale):
        raise ValueError(
            "plant must be free-floating: the channel torque -> theta needs a rigid-body double "
            f"integrator 1/(J s^2) with J > 0 [kg*m^2]; got singular part {a1:.3g}/s + {a2:.3g}/s^2 "
            f"({ev.k} eigenvalue(s) of A near zero)")
    return float(1.0 / a2.real)


def flexible_modes(plant: control.StateSpace, *, input: str = TORQUE, output: str = THETA,
                   min_participation: float = 1e-9) -> list[FlexibleMode]:
    """Flexible (lightly damped, complex) modes visible in one channel of a plant.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous-time plant with named signals.
    input, output : str
        Channel (default torque -> theta).
    min_participation : float
        Modes whose participation (see :class:`FlexibleMode`) is below this are dropped
        (uncontrollable or unobservable in the channel, e.g. symmetric modes of two wings).

    Returns
    -------
    list of FlexibleMode
        Sorted by frequency, one entry per complex-conjugate pair.
    """
    _check_plant(plant)
    _require_signal(plant, input, "input", "plant")
    _require_signal(plant, output, "output", "plant")
    ev = _evaluator(plant, [input], [output])
    try:
        J = rigid_body_inertia(plant)
    except ValueError:
        J = 1.0
    if not ev.modal:
        lam, V = np.linalg.eig(plant.A)
        raise ValueError("plant A is defective outside its rigid-body block; cannot list modes "
                         f"(eigenvalues {lam[:6]}...)")
    modes = []
    for lam, c, b in zip(ev.lam, ev.Cm[0], ev.Bm[:, 0]):
        if lam.imag <= 0:
            continue
        w = abs(lam)
        r = complex(c * b)
        participation = 2.0 * abs(r) * w * J
        if participation < min_participation:
            continue
        modes.append(FlexibleMode(float(w), float(-lam.real / w), r, float(participation)))
    return sorted(modes, key=lambda m: m.frequency)


# --------------------------------------------------------------------------------------------
# closing the loop
# --------------------------------------------------------------------------------------------
def close_loop(plant, controller: control.StateSpace):
    """Close the attitude loop by signal names.

    Parameters
    ----------
    plant : control.StateSpace or control.FrequencyResponseData
        Continuous-time plant (input ``'torque'``, outputs ``'theta'``, ``'omega'``, ...). An FRD
        plant (e.g. the exact distributed model) gives the closed loop's frequency response on
        its grid; it needs ``'theta'`` or ``'omega'`` (the other is j w times / divided by it).
    controller : control.StateSpace
        Controller with output ``'torque'``; its inputs are plant outputs (measurements) and
        reference inputs (names containing ``'ref'``). If the controller is discrete-time
        (``dt`` > 0), the plant is discretised with a zero-order hold at that ``dt`` and the
        result is the exact sampled-data loop at the sampling instants (every plant input,
        including disturbances, is then held constant over a sample). FRD plants need a
        continuous controller.

    Returns
    -------
    control.StateSpace or control.FrequencyResponseData
        Inputs: the controller's reference inputs, then the plant's inputs other than torque.
        Outputs: every plant output, then ``'torque'``. States: plant states, controller states.
        With u = torque, y_m the measurements and d the other plant inputs:
        torque = (K_r r + K_y (C_m x + D_md d)) / (1 - K_y D_mt), the algebraic loop through the
        feedthroughs solved exactly (an error if 1 - K_y D_mt = 0).
    """
    if isinstance(plant, control.FrequencyResponseData):
        return _close_loop_frd(plant, controller)
    _check_plant(plant)
    _check_controller(controller)
    measured = _measurements(plant, controller)
    refs = _reference_inputs(controller, _labels(plant, "output"))
    p_in, p_out = _labels(plant, "input"), _labels(plant, "output")
    c_in = list(controller.input_labels)
    disturbances = [n for n in p_in if n != TORQUE]
    if _is_digital(controller):
        plant = control.c2d(plant, controller.dt, method="zoh")
    Ap, Bp, Cp, Dp = (np.asarray(M, dtype=float) for M in (plant.A, plant.B, plant.C, plant.D))
    Ac, Bc, Cc, Dc = (np.asarray(M, dtype=float)
                      for M in (controller.A, controller.B, controller.C, controller.D))
    i_t = p_in.index(TORQUE)
    i_d = [p_in.index(n) for n in disturbances]
    i_m = [p_out.index(n) for n in measured]
    j_m = [c_in.index(n) for n in measured]
    j_r = [c_in.index(n) for n in refs]
    # torque = Cc xc + Dr r + Dy y_m,  y_m = Cm xp + Dmt torque + Dmd d: solve the (scalar)
    # algebraic loop torque (1 - Dy Dmt) = Cc xc + Dr r + Dy (Cm xp + Dmd d)
    Dy = Dc[:, j_m]
    gain = 1.0 - float((Dy @ Dp[i_m, i_t])[0])
    if abs(gain) < 1e-12:
        raise ValueError("algebraic loop: the controller's direct feedthrough times the plant's "
                         "feedthrough from torque to the measurements is 1")
    # torque = F [xp; xc; r; d]
    F = np.hstack([Dy @ Cp[i_m], Cc, Dc[:, j_r], Dy @ Dp[np.ix_(i_m, i_d)]]) / gain
    n_p, n_c = Ap.shape[0], Ac.shape[0]
    n_r = len(j_r)
    # the plant with the torque substituted, then the controller driven by r and y_m
    Fx, Fr, Fd = F[:, : n_p + n_c], F[:, n_p + n_c: n_p + n_c + n_r], F[:, n_p + n_c + n_r:]
    bt = Bp[:, [i_t]]
    A_top = np.hstack([Ap, np.zeros((n_p, n_c))]) + bt @ Fx
    ym_x = np.hstack([Cp[i_m], np.zeros((len(i_m), n_c))]) + Dp[np.ix_(i_m, [i_t])] @ Fx
    A_bot = np.hstack([np.zeros((n_c, n_p)), Ac]) + Bc[:, j_m] @ ym_x
    B_top = np.hstack([bt @ Fr, Bp[:, i_d] + bt @ Fd])
    ym_r = Dp[np.ix_(i_m, [i_t])] @ Fr
    ym_d = Dp[np.ix_(i_m, i_d)] + Dp[np.ix_(i_m, [i_t])] @ Fd
    B_bot = np.hstack([Bc[:, j_r] + Bc[:, j_m] @ ym_r, Bc[:, j_m] @ ym_d])
    C = np.vstack([np.hstack([Cp, np.zeros((Cp.shape[0], n_c))]) + Dp[:, [i_t]] @ Fx, Fx])
    D = np.vstack([np.hstack([Dp[:, [i_t]] @ Fr, Dp[:, i_d] + Dp[:, [i_t]] @ Fd]),
                   np.hstack([Fr, Fd])])
    inputs = refs + disturbances
    outputs = p_out + [TORQUE]
    states = [f"plant_x{i}" for i in range(n_p)] + [f"controller_x{i}" for i in range(n_c)]
    return control.ss(np.vstack([A_top, A_bot]), np.vstack([B_top, B_bot]), C, D, plant.dt,
                      inputs=inputs, outputs=outputs, states=states, name="closed_loop")


def _close_loop_frd(plant: control.FrequencyResponseData, controller: control.StateSpace
                    ) -> control.FrequencyResponseData:
    """Closed-loop frequency response on an FRD plant's grid (see :func:`close_loop`)."""
    _check_plant(plant, allow_frd=True)
    _check_controller(controller)
    if _is_digital(controller):
        raise ValueError("close_loop on a FrequencyResponseData plant needs a continuous "
                         f"controller; got dt={controller.dt}")
    loop = _Loop(plant, controller)  # measured rows of the plant (theta/omega derived)
    p_in, p_out = _labels(plant, "input"), _labels(plant, "output")
    refs = _reference_inputs(controller, sorted(set(p_out) | set(loop.measured)))
    disturbances = [n for n in p_in if n != TORQUE]
    omega = loop.omega
    jw = 1j * omega
    data = np.asarray(plant.frdata)[:, :, : omega.size]  # (p, m, f)
    K = _evaluator(controller, list(controller.input_labels), [TORQUE])(jw)[:, 0, :]  # (f, c)
    c_in = list(controller.input_labels)
    Ky = K[:, [c_in.index(n) for n in loop.measured]]  # (f, n_meas)
    Kr = K[:, [c_in.index(n) for n in refs]]  # (f, n_ref)

    def measured_rows(column: int) -> np.ndarray:  # (f, n_meas) response of y_m to one input
        rows = []
        for name in loop.measured:
            if name in p_out:
                rows.append(data[p_out.index(name), column])
            elif name == OMEGA:
                rows.append(jw * data[p_out.index(THETA), column])
            else:
                rows.append(data[p_out.index(OMEGA), column] / jw)
        return np.array(rows).T

    i_t = p_in.index(TORQUE)
    denominator = 1.0 - np.sum(Ky * measured_rows(i_t), axis=1)  # (f,)
    torque_r = Kr / denominator[:, None]  # (f, n_ref)
    torque_d = np.stack([np.sum(Ky * measured_rows(p_in.index(n)), axis=1) for n in disturbances],
                        axis=1).reshape(omega.size, len(disturbances)) / denominator[:, None]
    Pt = data[:, i_t, :].T  # (f, p)
    Pd = np.stack([data[:, p_in.index(n), :].T for n in disturbances], axis=2).reshape(
        omega.size, len(p_out), len(disturbances))
    y_r = Pt[:, :, None] * torque_r[:, None, :]
    y_d = Pt[:, :, None] * torque_d[:, None, :] + Pd
    response = np.concatenate([np.concatenate([y_r, y_d], axis=2),
                               np.concatenate([torque_r, torque_d], axis=1)[:, None, :]], axis=1)
    return control.frd(np.moveaxis(response, 0, 2), omega, inputs=refs + disturbances,
                       outputs=p_out + [TORQUE], name="closed_loop")


# --------------------------------------------------------------------------------------------
# loop transfer function
# --------------------------------------------------------------------------------------------
class _Loop:
    """L(omega) = -sum_i K_i P_i at real frequencies omega [rad/s] (see module docstring)."""

    def __init__(self, plant, controller):
        _check_plant(plant, allow_frd=True)
        _check_controller(controller)
        self.digital = _is_digital(controller)
        self.dt = float(controller.dt) if self.digital else 0.0
        self.frd = isinstance(plant, control.FrequencyResponseData)
        if self.frd:
            outputs = list(plant.output_labels)
            # theta or omega alone is enough: omega(jw) = jw theta(jw)
            derivable = {THETA, OMEGA} if (THETA in outputs or OMEGA in outputs) else set()
            self.measured = [n for n in controller.input_labels
                             if n in outputs or n in derivable]
            if not self.measured:
                raise ValueError(f"controller inputs {list(controller.input_labels)} contain none "
                                 f"of the plant outputs {outputs}: nothing is fed back")
            i_t = list(plant.input_labels).index(TORQUE)
            self.omega = np.asarray(plant.omega, dtype=float)
            if self.digital:
                self.omega = self.omega[self.omega < math.pi / self.dt]
            data = np.asarray(plant.frdata)[:, i_t, : self.omega.size]
            jw = 1j * self.omega
            rows = []
            for name in self.measured:
                if name in outputs:
                    rows.append(data[outputs.index(name)])
                elif name == OMEGA:
                    rows.append(jw * data[outputs.index(THETA)])
                else:
                    rows.append(data[outputs.index(OMEGA)] / jw)
            self.plant_data = np.array(rows, dtype=complex).reshape(len(rows), self.omega.size)
        else:
            self.measured = _measurements(plant, controller)
        self.controller_ev = _evaluator(controller, self.measured, [TORQUE])
        if not self.frd:
            p = control.c2d(plant, self.dt, method="zoh") if self.digital else plant
            self.plant_ev = _evaluator(p, [TORQUE], self.measured)
            self._plant_discretised = p
        self.plant = plant
        self.controller = controller

    def _point(self, omega: np.ndarray) -> np.ndarray:
        omega = np.asarray(omega, dtype=float)
        if self.digital:
            return np.exp(1j * omega * self.dt)
        return 1j * omega

    def __call__(self, omega) -> np.ndarray:
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        z = self._point(omega)
        K = self.controller_ev(z)[:, 0, :]  # (f, n_meas)
        if self.frd:
            P = self._interpolated_plant(omega)  # (f, n_meas)
            if self.digital:
                # zero-order hold seen from continuous time, aliasing neglected:
                # H(jw) = (1 - exp(-jwT)) / (jwT) (Franklin, Powell & Workman, sec. 6.3)
                wT = omega * self.dt
                P = P * ((1 - np.exp(-1j * wT)) / (1j * wT))[:, None]
        else:
            P = self.plant_ev(z)[:, :, 0]
        return -np.sum(K * P, axis=1)

    def _interpolated_plant(self, omega: np.ndarray) -> np.ndarray:
        """FRD plant rows at omega: exact on its grid, in between linear in log frequency for
        log|P| and arg P (P_i (P_i+1 / P_i)^t), so the grid must resolve the plant's resonances;
        the controller is always evaluated exactly."""
        grid = self.omega
        lo, hi = grid[0] * (1 - 1e-12), grid[-1] * (1 + 1e-12)
        if np.any(omega < lo) or np.any(omega > hi):
            raise ValueError(f"frequencies must lie within the FrequencyResponseData grid "
                             f"[{grid[0]:.4g}, {grid[-1]:.4g}] rad/s; got [{omega.min():.4g}, "
                             f"{omega.max():.4g}]")
        i = np.clip(np.searchsorted(grid, omega), 1, grid.size - 1)
        t = (np.log(omega) - np.log(grid[i - 1])) / (np.log(grid[i]) - np.log(grid[i - 1]))
        P0, P1 = self.plant_data[:, i - 1], self.plant_data[:, i]
        with np.errstate(divide="ignore", invalid="ignore"):
            P = P0 * (P1 / P0) ** t
        exact = np.isclose(t, 1.0, rtol=0, atol=1e-15)
        P[:, exact] = P1[:, exact]
        return P.T

    def _controller_roots(self) -> np.ndarray:
        """Poles of the controller and zeros of each of its measurement channels."""
        c = self.controller
        roots = [_poles_of(self.controller_ev)]
        n = c.nstates
        for name in self.measured:
            j = list(c.input_labels).index(name)
            M = np.block([[c.A, c.B[:, [j]]], [c.C, c.D[:, [j]]]])
            N = scipy.linalg.block_diag(np.eye(n), np.zeros((1, 1)))
            with np.errstate(divide="ignore", invalid="ignore"):
                z = scipy.linalg.eigvals(M, N)
            roots.append(z[np.isfinite(z) & (np.abs(z) < 1e12)])
        return np.concatenate(roots).astype(complex)

    def zeros(self) -> np.ndarray:
        """Invariant zeros of L (z-plane for a digital loop): finite generalized eigenvalues of
        ([[A, B], [C, D]], [[I, 0], [0, 0]]) for the series connection plant -> controller."""
        p, c = self._plant_discretised, self.controller
        i_t = list(p.input_labels).index(TORQUE)
        i_m = [list(p.output_labels).index(n) for n in self.measured]
        j_m = [list(c.input_labels).index(n) for n in self.measured]
        Ap, Bt, Cm, Dmt = p.A, p.B[:, [i_t]], p.C[i_m], p.D[np.ix_(i_m, [i_t])]
        Ac, Bcm, Cc, Dcm = c.A, c.B[:, j_m], c.C, c.D[:, j_m]
        n_p, n_c = Ap.shape[0], Ac.shape[0]
        A = np.block([[Ap, np.zeros((n_p, n_c))], [Bcm @ Cm, Ac]])
        B = np.vstack([Bt, Bcm @ Dmt])
        C = -np.hstack([Dcm @ Cm, Cc])
        D = -Dcm @ Dmt
        n = n_p + n_c
        M = np.block([[A, B], [C, D]])
        N = scipy.linalg.block_diag(np.eye(n), np.zeros((1, 1)))
        with np.errstate(divide="ignore", invalid="ignore"):
            z = scipy.linalg.eigvals(M, N)
        return z[np.isfinite(z) & (np.abs(z) < 1e12)]

    def grid(self, n_points: int = 600) -> np.ndarray:
        """Frequency grid [rad/s] refined around every lightly damped pole and zero of L."""
        if self.frd:
            # the FRD's own grid (it must resolve the plant) plus the controller's resonances
            roots = self._controller_roots()
        else:
            roots = np.concatenate([_poles_of(self.plant_ev), _poles_of(self.controller_ev),
                                    self.zeros()]).astype(complex)
        if self.digital:
            # z-plane roots: map back with s = log(z) / T (z = 0 is infinitely fast: drop it)
            roots = np.log(roots[np.abs(roots) > 1e-12]) / self.dt
        w_all = np.abs(roots)
        w_all = w_all[w_all > 1e-5 * max(w_all.max(initial=0.0), 1e-300)]
        if w_all.size == 0:
            w_all = np.array([1.0])
        w_lo, w_hi = 1e-3 * w_all.min(), 1e3 * w_all.max()
        if self.digital:
            w_hi = min(w_hi, math.pi / self.dt * (1 - 1e-9))
            w_lo = min(w_lo, 1e-3 * math.pi / self.dt)
        grid = [np.logspace(math.log10(w_lo), math.log10(w_hi), n_points)]
        # points concentrated in the half-power band of each lightly damped root: a pole
        # -zeta w + j w sqrt(1-zeta^2) has |response| falling to 1/sqrt(2) at about w(1 +/- zeta),
        # so steps of a fraction of zeta w resolve its peak and its 180 deg phase swing (the
        # same for the notch of a lightly damped zero, an antiresonance).
        # an even count: no point falls on the peak itself, where an undamped pole (zeta = 0,
        # a free beam mode) makes L infinite
        theta = np.linspace(-1.45, 1.45, 40)
        for lam in roots:
            w = abs(lam)
            if lam.imag <= 0 or w <= 0:
                continue
            zeta = max(abs(lam.real) / w, 1e-7)
            if zeta > 0.3:
                continue
            pts = lam.imag + zeta * w * np.tan(theta)
            grid.append(pts[(pts > w_lo) & (pts < w_hi)])
        if self.frd:
            inside = [g[(g >= self.omega[0]) & (g <= self.omega[-1])] for g in grid[1:]]
            return np.unique(np.concatenate([self.omega] + inside))
        return np.unique(np.concatenate(grid))


def _poles_of(ev: _ModalEvaluator) -> np.ndarray:
    if ev.n == 0:
        return np.zeros(0, dtype=complex)
    if ev.modal:
        return np.concatenate([np.diag(ev.T11), ev.lam])
    return np.linalg.eigvals(ev.A).astype(complex)


def loop_frequency_response(plant, controller, omega: np.ndarray | None = None
                            ) -> tuple[np.ndarray, np.ndarray]:
    """Open-loop transfer L(j omega) with the loop broken at the torque input.

    Parameters
    ----------
    plant : control.StateSpace or control.FrequencyResponseData
        Plant with named signals (FRD: frequencies within its grid, interpolated as in
        :func:`margins`).
    controller : control.StateSpace
        Continuous or digital controller.
    omega : array of float, rad/s, optional
        Frequencies; default a logarithmic grid refined around the lightly damped poles and
        zeros (for an FRD plant its own grid plus the controller's resonances).

    Returns
    -------
    omega : ndarray, shape (n,), rad/s
    L : ndarray, shape (n,), complex128
        L = -sum_i K_i P_i (negative-feedback convention: the loop is unstable at L = -1).
    """
    loop = _Loop(plant, controller)
    if omega is None:
        omega = loop.grid()
    omega = np.asarray(omega, dtype=float).reshape(-1)
    if omega.size == 0 or np.any(~np.isfinite(omega)) or np.any(omega <= 0):
        raise ValueError("omega must be positive finite frequencies [rad/s]; got "
                         f"{omega[:5]}...")
    return omega, loop(omega)


# --------------------------------------------------------------------------------------------
# margins
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Margins:
    """Classical stability margins of a loop (see :func:`margins`).

    Attributes
    ----------
    gain_margin : float, dB
        -20 log10 |L| at the phase crossover (L real and negative) closest to 0 dB;
        positive: the gain may rise by that much; negative: it may fall by that much (a
        conditionally stable loop). +inf if L never crosses the negative real axis.
    phase_margin : float, deg
        180 deg + arg L at the gain crossover (|L| = 1) with the smallest |margin|, wrapped to
        (-180, 180]; +inf if |L| never crosses 1.
    modulus_margin : float
        min over omega of |1 + L(j omega)| (the distance from L to the critical point -1;
        1/max|S|).
    gain_crossover_frequency, phase_crossover_frequency, modulus_margin_frequency : float, rad/s
        Where those margins are attained (nan-free: +inf when there is no crossover).
    """

    gain_margin: float
    phase_margin: float
    modulus_margin: float
    gain_crossover_frequency: float
    phase_crossover_frequency: float
    modulus_margin_frequency: float

    def as_dict(self) -> dict[str, float]:
        """The three margins under their metric names (gain_margin, phase_margin, modulus_margin)."""
        return {"gain_margin": self.gain_margin, "phase_margin": self.phase_margin,
                "modulus_margin": self.modulus_margin}


def _crossings(f: Callable[[np.ndarray], np.ndarray], omega: np.ndarray, values: np.ndarray
               ) -> np.ndarray:
    """Zeros of f: grid points where `values` is 0 and refined roots where it changes sign.

    Every sign-change bracket of the grid is refined at once by the Illinois variant of regula
    falsi, one vectorised evaluation of f per iteration (with a bisection step when a bracket
    fails to halve in three iterations), to |b - a| <= 1e-13 b. A sign change may also be a
    pass through an undamped pole (f -> +-inf): the bracket then closes in on the pole, where f
    is huge or not finite; such a point is no root and is dropped (|f| must fall below 1e-6
    of its size at the bracket's ends); its refinement stops once |f| at both ends exceeds
    1e3 times that size.

    References
    ----------
    M. Dowell, P. Jarratt, "A modified regula falsi method for computing the root of an
    equation", BIT 11, 1971 (the Illinois algorithm).
    """
    exact = omega[values == 0]
    sign = np.sign(values)
    i = np.nonzero(sign[:-1] * sign[1:] < 0)[0]
    if i.size == 0:
        return exact
    a, b = omega[i].copy(), omega[i + 1].copy()
    fa, fb = values[i].copy(), values[i + 1].copy()  # true values at the ends
    ga, gb = fa.copy(), fb.copy()  # Illinois-scaled values used for the secant
    scale = np.maximum(np.abs(fa), np.abs(fb))
    last = np.zeros(i.size, dtype=int)  # -1: a moved last time, +1: b moved
    width_before = np.full(i.size, np.inf)
    suspect = np.zeros(i.size, dtype=bool)
    active = np.ones(i.size, dtype=bool)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for iteration in range(200):
            active &= (b - a) > 1e-13 * b
            k = np.nonzero(active)[0]
            if k.size == 0:
                break
            mid = 0.5 * (a[k] + b[k])
            x = (a[k] * gb[k] - b[k] * ga[k]) / (gb[k] - ga[k])
            bisect = ~((x > a[k]) & (x < b[k]))
            if iteration % 3 == 2:
                bisect |= (b[k] - a[k]) > 0.5 * width_before[k]
                width_before[k] = b[k] - a[k]
            elif iteration == 0:
                width_before[k] = b[k] - a[k]
            bisect |= suspect[k]
            x = np.where(bisect, mid, x)
            fx = np.asarray(f(x), dtype=float)
            bad = ~np.isfinite(fx)
            if bad.any():  # on an undamped pole: step to the midpoint instead
                x[bad] = mid[bad]
                bisect = bisect | bad
                fx[bad] = np.asarray(f(x[bad]), dtype=float)
                lost = ~np.isfinite(fx)
                active[k[lost]] = False
                k, x, fx, bisect = k[~lost], x[~lost], fx[~lost], bisect[~lost]
            zero = fx == 0
            right = (np.sign(fx) == np.sign(fb[k])) & ~zero
            left = ~right & ~zero
            kr, kl, kz = k[right], k[left], k[zero]
            # Illinois: the end kept twice in a row has its value halved (not after bisection)
            ga[kr] = np.where((last[kr] == 1) & ~bisect[right], 0.5 * ga[kr], ga[kr])
            b[kr], fb[kr], gb[kr], last[kr] = x[right], fx[right], fx[right], 1
            gb[kl] = np.where((last[kl] == -1) & ~bisect[left], 0.5 * gb[kl], gb[kl])
            a[kl], fa[kl], ga[kl], last[kl] = x[left], fx[left], fx[left], -1
            # a bisection step restarts regula falsi from the true end values
            kb = k[bisect]
            ga[kb], gb[kb], last[kb] = fa[kb], fb[kb], 0
            a[kz] = b[kz] = x[zero]
            fa[kz] = fb[kz] = 0.0
            active[kz] = False
            # |f| inside above both starting ends: an undamped pole is likely in the bracket,
            # where regula falsi creeps; bisect it from now on. Both ends 1e3 times larger than
            # at the start: closing in on a pole, not a root.
            suspect[kr] |= np.abs(fx[right]) > scale[kr]
            suspect[kl] |= np.abs(fx[left]) > scale[kl]
            active[k] &= np.minimum(np.abs(fa[k]), np.abs(fb[k])) <= 1e3 * scale[k]
        root = np.where(np.abs(fa) <= np.abs(fb), a, b)
        at_root = np.minimum(np.abs(fa), np.abs(fb))
        keep = np.isfinite(at_root) & (at_root <= 1e-6 * scale)
    return np.concatenate([exact, root[keep]])


def margins(plant, controller, *, omega: np.ndarray | None = None) -> Margins:
    """Gain, phase and modulus margins of the loop plant-controller.

    Parameters
    ----------
    plant : control.StateSpace or control.FrequencyResponseData
        Plant with named signals. For a FrequencyResponseData plant the grid is the FRD's own
        plus the controller's resonances; between the FRD's points the plant is interpolated
        linearly in log frequency (log|P| and arg P), the controller is evaluated exactly, so the
        FRD grid must resolve the plant's resonances. It needs output 'theta' or 'omega' (the
        other is derived as omega = j w theta).
    controller : control.StateSpace
        Continuous or digital controller. For a digital controller and a StateSpace plant, L is
        the exact sampled-data loop gain L(e^{j omega T}) with the plant discretised by a
        zero-order hold; with an FRD plant, the hold is modelled as (1 - e^{-j omega T})/(j omega T)
        (aliasing neglected). Frequencies stop at the Nyquist frequency pi/T.
    omega : array of float, rad/s, optional
        Frequency grid; default: logarithmic, 1e-3 x the lowest to 1e3 x the highest
        characteristic frequency, refined with 41 points across the half-power band of every
        pole with damping ratio below 0.3 (lightly damped modes of plant and controller).
        Crossings and the minimum of |1 + L| are then refined on the exact L.

    Returns
    -------
    Margins

    References
    ----------
    G. F. Franklin, J. D. Powell, A. Emami-Naeini, Feedback Control of Dynamic Systems, 7th ed.,
    sec. 6.4 (gain and phase margins); S. Skogestad, I. Postlethwaite, Multivariable Feedback
    Control, 2nd ed., sec. 2.4.3 (modulus margin = 1/||S||_inf).
    """
    loop = _Loop(plant, controller)
    if omega is None:
        omega = loop.grid()
    omega = np.unique(np.asarray(omega, dtype=float).reshape(-1))
    if omega.size < 2 or np.any(~np.isfinite(omega)) or np.any(omega <= 0):
        raise ValueError("omega must hold at least two positive finite frequencies [rad/s]")
    with np.errstate(divide="ignore", invalid="ignore"):
        L = loop(omega)
    finite = np.isfinite(L)  # a grid point exactly on an undamped pole: L is infinite there
    omega, L = omega[finite], L[finite]

    def value(w: float) -> complex:
        return complex(loop(np.array([w]))[0])

    def log_gain(w: np.ndarray) -> np.ndarray:
        with np.errstate(divide="ignore"):
            return np.log(np.abs(loop(w)))

    # phase crossovers: L real and negative (Im L changes sign where Re L < 0). Crossings where
    # |L| < 1e-9 (a gain margin above 180 dB) are round-off in Im L, not a margin.
    gain_margin, w_pc = math.inf, math.inf
    w_roots = _crossings(lambda w: loop(w).imag, omega, L.imag)
    L_roots = loop(w_roots) if w_roots.size else np.zeros(0, dtype=complex)
    for w, Lw in zip(w_roots, L_roots):
        if Lw.real < 0 and abs(Lw) > 1e-9:
            gm = -20.0 * math.log10(abs(Lw))
            if abs(gm) < abs(gain_margin):
                gain_margin, w_pc = gm, float(w)
    # gain crossovers: |L| = 1
    phase_margin, w_gc = math.inf, math.inf
    w_roots = _crossings(log_gain, omega, np.log(np.abs(L)))
    L_roots = loop(w_roots) if w_roots.size else np.zeros(0, dtype=complex)
    for w, Lw in zip(w_roots, L_roots):
        pm = 180.0 + math.degrees(cmath.phase(Lw))  # in (0, 360]
        pm = pm - 360.0 if pm > 180.0 else pm
        if abs(pm) < abs(phase_margin):
            phase_margin, w_gc = pm, float(w)
    # modulus margin: min |1 + L|, refined between the neighbours of the grid minimum
    dist = np.abs(1.0 + L)
    i = int(np.argmin(dist))
    mm, w_mm = float(dist[i]), float(omega[i])
    if 0 < i < omega.size - 1:
        res = scipy.optimize.minimize_scalar(
            lambda lw: abs(1.0 + value(math.exp(lw))),
            bounds=(math.log(omega[i - 1]), math.log(omega[i + 1])), method="bounded",
            options={"xatol": 1e-12})
        if res.fun < mm:
            mm, w_mm = float(res.fun), float(math.exp(res.x))
    return Margins(float(gain_margin), float(phase_margin), mm, float(w_gc), float(w_pc), w_mm)


# --------------------------------------------------------------------------------------------
# spillover verdict
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SpilloverVerdict:
    """Is a controller (designed on one model) stable on a truth model, and by how much.

    Attributes
    ----------
    stable : bool
        True if the closed loop is asymptotically stable (every pole strictly in the open left
        half-plane, inside the unit circle for a digital loop).
    n_unstable_poles : int
        Closed-loop poles in the closed right half-plane (outside or on the unit circle).
    least_damping_ratio : float or None
        Damping ratio of the least-damped closed-loop pole (negative when unstable);
        None for a FrequencyResponseData truth plant (no poles available).
    least_damped_frequency : float or None, rad/s
        Natural frequency of that pole.
    margins : Margins
        Margins of the loop on the truth plant.
    method : str
        ``'eigenvalues'`` (StateSpace truth) or ``'nyquist'`` (FrequencyResponseData truth).
    """

    stable: bool
    n_unstable_poles: int
    least_damping_ratio: float | None
    least_damped_frequency: float | None
    margins: Margins
    method: str

    def __str__(self) -> str:
        state = "STABLE" if self.stable else f"UNSTABLE ({self.n_unstable_poles} unstable poles)"
        lines = [f"spillover verdict: {state} ({self.method})"]
        if self.least_damping_ratio is not None:
            lines.append(f"  least-damped pole: zeta = {self.least_damping_ratio:.4g} at "
                         f"{self.least_damped_frequency:.6g} rad/s")
        m = self.margins
        lines.append(f"  gain margin {m.gain_margin:.4g} dB, phase margin {m.phase_margin:.4g} deg,"
                     f" modulus margin {m.modulus_margin:.4g}")
        return "\n".join(lines)


def _continuous_poles(system) -> np.ndarray:
    """Poles in the s-plane; a digital system's z-plane poles mapped by s = log(z) / T
    (poles at z = 0, infinitely fast and deadbeat, are left out)."""
    lam = np.linalg.eigvals(system.A) if system.nstates else np.zeros(0, dtype=complex)
    lam = lam.astype(complex)
    if system.isdtime(strict=True):
        lam = np.log(lam[np.abs(lam) > 1e-300]) / float(system.dt)
    return lam


def spillover(truth_plant, controller) -> SpilloverVerdict:
    """Stability verdict of a controller on a truth model (never raises for an unstable loop).

    Parameters
    ----------
    truth_plant : control.StateSpace or control.FrequencyResponseData
        The high-fidelity plant (e.g. hub + beam with many modes, or the exact distributed
        model as FRD).
    controller : control.StateSpace
        Controller designed on another model.

    Returns
    -------
    SpilloverVerdict
        For a StateSpace truth plant, from the closed-loop eigenvalues (a pole counts as
        unstable if Re(s) >= -1e-10 max(1, |s|): undamped, uncontrolled modes make the loop
        only marginally stable, reported as not stable). For an FRD truth plant, from the Nyquist
        criterion: the plant is assumed to have no poles in the open right half-plane and
        n0 poles at s = 0 (n0 from the low-frequency slope of |L|, 2 for a free-floating plant);
        the contour is indented to the right around s = 0, so
        Z = P - (2 Delta - n0 pi) / (2 pi), where Delta is the phase change of 1 + L(j omega) over
        the FRD grid and P the controller's open right-half-plane poles. This needs |L| > 10 at the
        lowest and < 0.1 at the highest grid frequency, and a continuous controller.

    References
    ----------
    M. J. Balas, "Feedback control of flexible systems", IEEE Trans. Automatic Control 23(4),
    1978 (control and observation spillover); Skogestad & Postlethwaite, Multivariable Feedback
    Control, 2nd ed., sec. 4.9 (Nyquist criterion with poles on the imaginary axis).
    """
    _check_plant(truth_plant, "truth_plant", allow_frd=True)
    _check_controller(controller)
    mg = margins(truth_plant, controller)
    if isinstance(truth_plant, control.StateSpace):
        loop = close_loop(truth_plant, controller)
        s = _continuous_poles(loop)
        w = np.abs(s)
        unstable = s.real >= -1e-10 * np.maximum(1.0, w)
        zeta = np.where(w > 0, -s.real / np.where(w > 0, w, 1.0), 0.0)  # a pole at 0: zeta 0
        i = int(np.argmin(zeta)) if s.size else None
        return SpilloverVerdict(
            stable=bool(not unstable.any()), n_unstable_poles=int(unstable.sum()),
            least_damping_ratio=None if i is None else float(zeta[i]),
            least_damped_frequency=None if i is None else float(w[i]),
            margins=mg, method="eigenvalues")
    if _is_digital(controller):
        raise ValueError("spillover on a FrequencyResponseData truth_plant needs a continuous "
                         "controller (the sampled-data Nyquist count would need the aliased "
                         f"plant response); got dt={controller.dt}: use a StateSpace truth_plant")
    omega, L = loop_frequency_response(truth_plant, controller)
    if abs(L[0]) < 10 or abs(L[-1]) > 0.1:
        raise ValueError(
            "truth_plant frequency grid too narrow for the Nyquist criterion: need |L| > 10 at the "
            f"lowest and < 0.1 at the highest frequency; got |L| = {abs(L[0]):.3g} at "
            f"{omega[0]:.3g} rad/s and {abs(L[-1]):.3g} at {omega[-1]:.3g} rad/s")
    slope = (math.log(abs(L[1])) - math.log(abs(L[0]))) / (math.log(omega[1]) - math.log(omega[0]))
    n0 = int(round(-slope))
    phase = np.unwrap(np.angle(1.0 + L))
    delta = phase[-1] - phase[0]
    lam_c = _continuous_poles(controller)
    p_rhp = int(np.sum(lam_c.real > 1e-10 * np.maximum(1.0, np.abs(lam_c))))
    z = p_rhp - (2.0 * delta - n0 * math.pi) / (2.0 * math.pi)
    n_unstable = int(round(z))
    return SpilloverVerdict(stable=n_unstable == 0, n_unstable_poles=max(n_unstable, 0),
                            least_damping_ratio=None, least_damped_frequency=None,
                            margins=mg, method="nyquist")


# --------------------------------------------------------------------------------------------
# time responses
# --------------------------------------------------------------------------------------------
def _simulate(system, T, U):
    """Time response: controllers.simulate (exact, continuous) or forced_response (digital)."""
    if system.isdtime(strict=True):
        return control.forced_response(system, T, U, squeeze=False)
    return simulate(system, T, U)


def _time_grid(system, t_final: float, dt: float | None, default_dt: float) -> np.ndarray:
    if not (np.isfinite(t_final) and t_final > 0):
        raise ValueError(f"t_final must be positive and finite [s]; got {t_final}")
    if system.isdtime(strict=True):
        step = float(system.dt)
        if dt is not None and not math.isclose(dt, step, rel_tol=1e-9):
            raise ValueError(f"dt must equal the digital loop's sample time {step} [s]; got {dt}")
    else:
        step = default_dt if dt is None else float(dt)
        if not (np.isfinite(step) and step > 0):
            raise ValueError(f"dt must be positive and finite [s]; got {dt}")
    n = int(math.floor(t_final / step + 1e-9)) + 1
    if n < 2:
        raise ValueError(f"t_final {t_final} [s] must exceed one time step {step} [s]")
    return np.arange(n, dtype=float) * step


def _check_closed_loop(closed_loop) -> None:
    if not isinstance(closed_loop, control.StateSpace):
        raise TypeError("closed_loop must be a control.StateSpace (from close_loop); got "
                        f"{type(closed_loop).__name__}")
    for name in (THETA, TORQUE):
        _require_signal(closed_loop, name, "output", "closed_loop")


def slew_profile(t: np.ndarray, angle: float, duration: float) -> np.ndarray:
    """Cycloidal slew profile from 0 to ``angle`` in ``duration``.

    theta_ref(t) = angle (t/T - sin(2 pi t/T) / (2 pi)) for 0 <= t <= T, angle afterwards,
    0 before. Rate angle/T (1 - cos(2 pi t/T)) and acceleration 2 pi angle/T^2 sin(2 pi t/T) are
    zero at both ends (continuous acceleration, no torque jump); peak rate 2 angle/T, peak
    acceleration 2 pi angle/T^2.

    Parameters
    ----------
    t : array of float, s
    angle : float, rad
    duration : float, s

    Returns
    -------
    ndarray, rad, same shape as t

    References
    ----------
    R. L. Norton, Design of Machinery, 5th ed., sec. 8.6 (cycloidal displacement).
    """
    t = np.asarray(t, dtype=float)
    tau = np.clip(t / duration, 0.0, 1.0)
    return angle * (tau - np.sin(2.0 * np.pi * tau) / (2.0 * np.pi))


def _inputs(closed_loop, n_t: int, **rows: np.ndarray) -> np.ndarray:
    U = np.zeros((closed_loop.ninputs, n_t))
    labels = list(closed_loop.input_labels)
    for name, values in rows.items():
        U[labels.index(name)] = values
    return U


def slew(closed_loop: control.StateSpace, angle: float, duration: float, *,
         t_final: float | None = None, dt: float | None = None) -> control.TimeResponseData:
    """Response of a closed loop to a cycloidal slew of ``angle`` in ``duration``.

    Parameters
    ----------
    closed_loop : control.StateSpace
        From :func:`close_loop` (input ``'theta_ref'``).
    angle : float, rad
        Slew angle (non-zero, finite).
    duration : float, s
        Duration of the reference profile (:func:`slew_profile`).
    t_final : float, s, optional
        End of the simulation; default 3 * duration.
    dt : float, s, optional
        Output sample step; default duration / 500 (the digital loop's dt for a digital loop).
        The continuous simulation is exact for the piecewise-linear reference between samples,
        but peaks between samples are not seen: to resolve the peak tip deflection of a mode at
        w rad/s take dt well below pi / w.

    Returns
    -------
    control.TimeResponseData
        Outputs of the closed loop (``theta``, ``omega``, ``torque``, tip deflections, ...),
        inputs (``theta_ref`` profile, zero disturbances).
    """
    _check_closed_loop(closed_loop)
    _require_signal(closed_loop, THETA_REF, "input", "closed_loop")
    if not (np.isfinite(angle) and angle != 0):
        raise ValueError(f"angle must be non-zero and finite [rad]; got {angle}")
    if not (np.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be positive and finite [s]; got {duration}")
    t_final = 3.0 * duration if t_final is None else float(t_final)
    T = _time_grid(closed_loop, t_final, dt, duration / 500.0)
    U = _inputs(closed_loop, T.size, theta_ref=slew_profile(T, angle, duration))
    return _simulate(closed_loop, T, U)


def step_response(closed_loop: control.StateSpace, *, amplitude: float = 1.0,
                  t_final: float = 10.0, dt: float | None = None) -> control.TimeResponseData:
    """Response to a step of ``amplitude`` [rad] in theta_ref at t = 0.

    Parameters
    ----------
    closed_loop : control.StateSpace
    amplitude : float, rad
    t_final : float, s
    dt : float, s, optional
        Default t_final / 2000.
    """
    return _step_on(closed_loop, THETA_REF, amplitude, "rad", t_final, dt)


def disturbance_response(closed_loop: control.StateSpace, input: str = "disturbance_torque", *,
                         amplitude: float = 1.0, t_final: float = 10.0, dt: float | None = None
                         ) -> control.TimeResponseData:
    """Response to a step of ``amplitude`` on a disturbance input (theta_ref = 0).

    Parameters
    ----------
    closed_loop : control.StateSpace
    input : str
        Name of the closed-loop disturbance input (default ``'disturbance_torque'``).
    amplitude : float
        Step size in the input's unit (N*m for a torque).
    t_final : float, s
    dt : float, s, optional
        Default t_final / 2000.
    """
    return _step_on(closed_loop, input, amplitude, "input's unit", t_final, dt)


def _step_on(closed_loop, input: str, amplitude: float, unit: str, t_final: float,
             dt: float | None) -> control.TimeResponseData:
    """Step of ``amplitude`` on one closed-loop input at t = 0, every other input zero."""
    _check_closed_loop(closed_loop)
    _require_signal(closed_loop, input, "input", "closed_loop")
    if not (np.isfinite(amplitude) and amplitude != 0):
        raise ValueError(f"amplitude must be non-zero and finite [{unit}]; got {amplitude}")
    T = _time_grid(closed_loop, t_final, dt, t_final / 2000.0)
    U = _inputs(closed_loop, T.size, **{input: np.full(T.size, float(amplitude))})
    return _simulate(closed_loop, T, U)


def _trace(response, name: str, kind: str = "output") -> np.ndarray | None:
    labels = list(response.output_labels if kind == "output" else response.input_labels)
    if name not in labels:
        return None
    data = np.asarray(response.y if kind == "output" else response.u)
    data = data.reshape(len(labels), -1)
    return data[labels.index(name)]


def _peak(x: np.ndarray) -> float:
    """max |x|, +inf if any sample is not finite (a diverged response)."""
    x = np.asarray(x, dtype=float)
    return float(np.max(np.abs(x))) if np.all(np.isfinite(x)) else math.inf


def metrics(response: control.TimeResponseData, *, settling_band: float = 0.02
            ) -> dict[str, float]:
    """Time-domain metrics of a closed-loop response.

    Parameters
    ----------
    response : control.TimeResponseData
        From :func:`slew`, :func:`step_response` or :func:`disturbance_response` (outputs
        ``theta``, ``torque``, optionally ``*tip_deflection``; input ``theta_ref`` if any).
    settling_band : float
        Settling band as a fraction of the final reference (default 0.02, the 2 % criterion).

    Returns
    -------
    dict of str to float
        ``peak_torque`` [N*m] max |torque|; ``peak_attitude_error`` [rad] max |theta - theta_ref|;
        ``final_attitude_error`` [rad] |theta - theta_ref| at the last sample;
        ``peak_tip_deflection`` [m] max |tip deflection| over every ``*tip_deflection`` output
        (only if there is one). If the final reference r_f is non-zero also
        ``overshoot`` [%] = 100 max(0, max(theta/r_f) - 1), and ``settling_time`` [s], the first
        time after which |theta - r_f| <= settling_band |r_f| up to the end of the response
        (+inf if the last sample is still outside the band: simulate longer).
        A metric is +inf if the response diverged (non-finite samples); never NaN.

    References
    ----------
    Franklin, Powell & Emami-Naeini, Feedback Control of Dynamic Systems, 7th ed., sec. 3.4
    (overshoot, settling time).
    """
    if not isinstance(response, control.TimeResponseData):
        raise TypeError(f"response must be a control.TimeResponseData; got {type(response).__name__}")
    if not (0 < settling_band < 1):
        raise ValueError(f"settling_band must be in (0, 1) [fraction of the reference]; "
                         f"got {settling_band}")
    t = np.asarray(response.t, dtype=float).reshape(-1)
    theta = _trace(response, THETA)
    torque = _trace(response, TORQUE)
    if theta is None or torque is None:
        raise ValueError("response must have outputs 'theta' and 'torque'; got "
                         f"{list(response.output_labels)}")
    ref = _trace(response, THETA_REF, "input")
    ref = np.zeros_like(theta) if ref is None else ref
    with np.errstate(invalid="ignore", over="ignore"):
        error = theta - ref
        out = {"peak_torque": _peak(torque),
               "peak_attitude_error": _peak(error),
               "final_attitude_error": _peak(error[-1:])}
        tips = [n for n in response.output_labels if n.endswith(TIP_SUFFIX)]
        if tips:
            out["peak_tip_deflection"] = max(_peak(_trace(response, n)) for n in tips)
        r_f = float(ref[-1])
        if r_f != 0.0:
            ratio = theta / r_f
            out["overshoot"] = (math.inf if not np.all(np.isfinite(ratio))
                                else float(100.0 * max(0.0, np.max(ratio) - 1.0)))
            outside = np.nonzero(~(np.abs(theta - r_f) <= settling_band * abs(r_f)))[0]
            if outside.size == 0:
                out["settling_time"] = float(t[0])
            elif outside[-1] == t.size - 1:
                out["settling_time"] = math.inf
            else:
                out["settling_time"] = float(t[outside[-1] + 1])
    return out
