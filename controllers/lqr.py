"""LQR attitude controller with an estimator: an implementable output-feedback controller.

The regulator minimises J = integral (y_w^T W y_w + r torque^2) dt with y_w the weighted outputs
(theta, omega, optionally tip deflections) of the design model, i.e. Q = C_w^T W C_w,
N = C_w^T W D_w, R = r + D_w^T W D_w on the design model's states. The states are not measured:
a Kalman filter (or a user-given Luenberger gain) built on the same design model estimates them
from the measured theta and omega. The controller handed to the spacecraft has inputs
['theta_ref', 'theta', 'omega'] and output ['torque'] only.

The design model is the plant without the modes the loop cannot influence
(:mod:`controllers.modes`), and both Riccati equations are solved with a prescribed degree of
stability sigma = 4 alpha (Anderson & Moore, sec. 3.5: the LQR of A + sigma I places every
closed-loop pole at Re(s) < -sigma), alpha the stability margin of :mod:`controllers.stability`,
so the guarantee holds by construction and is checked on the computed poles with room for
round-off (Re <= -alpha): the regulator's and estimator's spectra, and then the loop's own poles
on the plant. High-gain designs put regulator and estimator poles on the same transmission zeros,
where the loop's computed poles can sit further right than either spectrum by more than 3 alpha;
sigma is then raised above the round-off measured on the loop (adding at most a damping ratio of
SIGMA_CAP to any mode), or the design is refused naming the mode, estimator_speed and
attitude_weight.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping

import control
import numpy as np
import scipy.linalg

from .arguments import describe, positive, real_array
from .frequency import modal_evaluator
from .modes import design_model, inertia_matrix, rigid_body_inertia, verify_loop
from .pd import check_sampling, rigid_crossover
from .riccati import modal_correction, solve_care, solve_dare
from .signals import channels, check_plant, tip_outputs
from .loop import close_loop
from .stability import (MARGIN, MAX_SCALE_RATIO, RemovedMode, continuous_poles,
                        warn_removed_modes)
from .threads import limits_blas_threads, total_states

__all__ = ["lqr", "KalmanNoise", "LQRDesign", "lqr_design", "reference_state",
           "rate_reference_state",
           "PRESCRIBED_STABILITY", "ROUND_OFF_ATTEMPTS", "SIGMA_CAP"]

#: Redesigns with a higher degree of stability when round-off puts a pole of the loop itself
#: at Re > -alpha (see _loop_round_off); then the design is refused, naming the mode.
ROUND_OFF_ATTEMPTS = 3
#: The degree of stability sigma raised against round-off stays below this fraction of the
#: lowest flexible mode and of the rigid-body bandwidths [rad/s]: it adds a damping ratio of at
#: most 1e-4 to a mode, beyond which it would change the design rather than resolve it.
SIGMA_CAP = 1e-4

#: The Riccati equations are solved for A + sigma I with sigma = PRESCRIBED_STABILITY * alpha
#: (alpha the stability margin): every designed pole lies at Re(s) < -4 alpha, so the computed
#: ones meet Re(s) <= -alpha with 3 alpha of room for round-off (a condition number up to ~1e3).
PRESCRIBED_STABILITY = 4.0


@dataclass(frozen=True)
class KalmanNoise:
    """Noise intensities of the Kalman filter's model (continuous-time white noises).

    The design model is driven by a white torque disturbance w entering like the torque
    (x' = A x + B (torque + w)) and measured as theta + v_theta, omega + v_omega.

    Attributes
    ----------
    torque_noise : float or tuple of 3 floats, N^2 m^2 s
        Intensity of w (three axes: per torque axis, independent noises).
    attitude_noise : float or tuple of 3 floats, rad^2 s
        Intensity of v_theta (per axis).
    rate_noise : float or tuple of 3 floats, rad^2/s
        Intensity of v_omega (per axis).
    """

    torque_noise: float | tuple
    attitude_noise: float | tuple
    rate_noise: float | tuple

    def __post_init__(self):
        for name, unit in (("torque_noise", "N^2 m^2 s"), ("attitude_noise", "rad^2 s"),
                           ("rate_noise", "rad^2/s")):
            value = getattr(self, name)
            if isinstance(value, (tuple, list, np.ndarray)):
                if len(value) != 3:
                    raise ValueError(f"{name} must be a real number or 3 of them (one per axis) "
                                     f"[{unit}]; got {describe(value)}")
                object.__setattr__(self, name, tuple(
                    positive(v, f"{name}[{i}]", unit) for i, v in enumerate(value)))
            else:
                positive(value, name, unit)

    def per_axis(self, n_axes: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(torque, attitude, rate) intensities as arrays of n_axes entries."""
        out = []
        for value in (self.torque_noise, self.attitude_noise, self.rate_noise):
            array = np.asarray(value, dtype=float).reshape(-1)
            if array.size not in (1, n_axes):
                raise ValueError(f"KalmanNoise has {array.size} entries per noise; the plant has "
                                 f"{n_axes} axis(es)")
            out.append(np.broadcast_to(array, (n_axes,)).copy())
        return out[0], out[1], out[2]

    @classmethod
    def default(cls, inertia, attitude_weight, torque_weight,
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

        Three axes: the same per axis, with J_ii, q_i, r_i (a scalar weight for every axis).
        """
        k = positive(estimator_speed, "estimator_speed", "1")
        if all(np.ndim(x) == 0 for x in (inertia, attitude_weight, torque_weight)):
            w_r = (attitude_weight / (torque_weight * inertia ** 2)) ** 0.25
            w_e = k * w_r
            V = 1.0 / attitude_weight
            return cls(torque_noise=k ** 4 / torque_weight, attitude_noise=V,
                       rate_noise=V * w_e ** 2)
        Jd = np.diag(np.atleast_2d(np.asarray(inertia, dtype=float)))
        q = np.broadcast_to(np.asarray(attitude_weight, dtype=float), Jd.shape)
        r = np.broadcast_to(np.asarray(torque_weight, dtype=float), Jd.shape)
        w_e = k * (q / (r * Jd ** 2)) ** 0.25
        V = 1.0 / q
        return cls(torque_noise=tuple(k ** 4 / r), attitude_noise=tuple(V),
                   rate_noise=tuple(V * w_e ** 2))


@dataclass(frozen=True)
class LQRDesign:
    """Everything an LQR design produced (returned by :func:`lqr_design`).

    Attributes
    ----------
    controller : control.StateSpace
        Output-feedback controller, inputs ['theta_ref', 'theta', 'omega'], output ['torque']
        (three-axis: inputs theta_ref_x..z, theta_x..z, omega_x..z; outputs torque_x..z).
    K : ndarray, shape (m, n_states)
        State-feedback gain, torque = -K (x_hat - x_ref theta_ref); m = 1 or 3 torques.
    L : ndarray, shape (n_states, 2 m)
        Estimator gain on the (theta..., omega...) innovations.
    Q, R, N : ndarray
        Weights on the design plant's states (shapes (n, n), (m, m), (n, m)).
    x_ref : ndarray, shape (n_states,) or (n_states, 3)
        Equilibrium state of a unit rigid rotation (A x_ref = 0, theta = 1, omega = 0); three
        axes: one column per axis (theta = e_i).
    regulator_poles, estimator_poles : ndarray, complex128
        Eigenvalues of A - B K and A - L C_m (z-plane for a digital design), A, B, C_m those
        of the design model.
    design_plant : control.StateSpace
        The design model: the plant without ``removed_modes`` (the plant itself if none).
    removed_modes : tuple of RemovedMode
        Modes left out of the design model because the loop cannot influence them
        (:mod:`controllers.modes`); they keep their open-loop eigenvalues in the closed loop.
    margin : float, 1/s
        The stability margin alpha: every closed-loop pole of the controller on the design
        plant, other than the removed modes, has Re(s) <= -margin (|z| <= exp(-margin T)).
    x_rate : ndarray, shape (n_states,) or (n_states, 3), or None
        With feedforward: the state of a unit rigid rate (:func:`rate_reference_state`), the
        regulator's target x_ref theta_ref + x_rate omega_ref; None without.
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
    design_plant: control.StateSpace = field(repr=False, default=None)
    removed_modes: tuple[RemovedMode, ...] = ()
    margin: float = 0.0
    x_rate: np.ndarray | None = None


def _nonneg(value, name: str, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise TypeError(f"{name} must be a real number [{unit}]; got {type(value).__name__}")
    value = float(value)
    if not (np.isfinite(value) and value >= 0):
        raise ValueError(f"{name} must be non-negative and finite [{unit}]; got {value}")
    return value


def _deflection_weights(plant, deflection_weight) -> tuple[list[str], np.ndarray]:
    tips = tip_outputs(plant.output_labels)
    if deflection_weight is None:
        return [], np.zeros((0, 0))
    if not tips:
        raise ValueError("deflection_weight given but the plant has no '*tip_deflection' output; "
                         f"outputs are {describe(list(plant.output_labels))}")
    if isinstance(deflection_weight, Mapping):
        unknown = [k for k in deflection_weight if k not in tips]
        if unknown:
            raise ValueError(f"deflection_weight names {describe(unknown)} are not tip-deflection "
                             f"outputs {describe(tips)}")
        names = list(deflection_weight)
        W = np.diag([_nonneg(deflection_weight[n], f"deflection_weight[{n!r}]", "1/m^2")
                     for n in names])
        return names, W
    if np.isscalar(deflection_weight):
        w = _nonneg(deflection_weight, "deflection_weight", "1/m^2")
        return tips, w * np.eye(len(tips))
    W = real_array(deflection_weight, "deflection_weight", "1/m^2")
    if W.shape != (len(tips), len(tips)):
        raise ValueError(f"deflection_weight matrix must have shape ({len(tips)}, {len(tips)}) "
                         f"for the outputs {describe(tips)}; got {W.shape}")
    if not np.allclose(W, W.T, rtol=1e-12, atol=0) or np.min(np.linalg.eigvalsh(W)) < -1e-12 * max(
            1.0, np.abs(W).max()):
        raise ValueError("deflection_weight must be symmetric positive semidefinite [1/m^2]; got "
                         f"eigenvalues {describe(np.linalg.eigvalsh((W + W.T) / 2))}")
    return tips, W


def reference_state(plant: control.StateSpace) -> np.ndarray:
    """State x_ref of a unit rigid rotation: A x_ref = 0, theta(x_ref) = 1, omega(x_ref) = 0.

    A rigid rotation of a free-floating spacecraft is an equilibrium with zero torque, so the
    reference theta_ref shifts the regulator's state target to x_ref theta_ref.

    Returns
    -------
    ndarray, shape (n_states,) (planar) or (n_states, 3) (three-axis: column i a unit rotation
    about hub axis i, theta = e_i, omega = 0)

    Raises
    ------
    ValueError
        If no such equilibrium exists (the plant is not free-floating).
    """
    ch = check_plant(plant)
    labels = list(plant.output_labels)
    C_theta = plant.C[[labels.index(n) for n in ch.thetas]]
    C_omega = plant.C[[labels.index(n) for n in ch.omegas]]
    n, m = plant.nstates, ch.n_axes
    M = np.vstack([plant.A, C_theta, C_omega])
    rhs = np.zeros((n + 2 * m, m))
    rhs[n:n + m] = np.eye(m)
    x, *_ = np.linalg.lstsq(M, rhs, rcond=None)
    residual = np.linalg.norm(M @ x - rhs)
    if residual > 1e-8 * max(1.0, np.linalg.norm(M) * np.linalg.norm(x)):
        raise ValueError("plant has no rigid-rotation equilibrium (A x = 0 with theta = 1 rad, "
                         f"omega = 0): it is not free-floating (residual {residual:.3g})")
    return x[:, 0] if not ch.mimo else x


def rate_reference_state(plant: control.StateSpace) -> np.ndarray:
    """State x_rate of a unit rigid rate: A x_rate = x_ref, theta(x_rate) = 0, omega(x_rate) = 1.

    A rigid rotation at constant rate w is x(t) = x_ref w t + x_rate w, an exact motion of a
    free-floating plant with zero torque (A x_ref = 0); a slew reference with rate omega_ref
    moves the regulator's state target to x_ref theta_ref + x_rate omega_ref, with no
    deformation of the appendages (which the feedforward torque's acceleration then causes and
    the loop regulates).

    Returns
    -------
    ndarray, shape (n_states,) (planar) or (n_states, 3) (three-axis: column i a unit rate about
    hub axis i)

    Raises
    ------
    ValueError
        If no such state exists (the plant is not free-floating).
    """
    ch = check_plant(plant)
    x_ref = reference_state(plant).reshape(plant.nstates, ch.n_axes)
    labels = list(plant.output_labels)
    C_theta = plant.C[[labels.index(n) for n in ch.thetas]]
    C_omega = plant.C[[labels.index(n) for n in ch.omegas]]
    n, m = plant.nstates, ch.n_axes
    M = np.vstack([plant.A, C_theta, C_omega])
    rhs = np.zeros((n + 2 * m, m))
    rhs[:n] = x_ref
    rhs[n + m:] = np.eye(m)
    x, *_ = np.linalg.lstsq(M, rhs, rcond=None)
    residual = np.linalg.norm(M @ x - rhs)
    if residual > 1e-8 * max(1.0, np.linalg.norm(M) * np.linalg.norm(x), np.linalg.norm(rhs)):
        raise ValueError("plant has no rigid-rate motion (A x = x_ref with theta = 0, omega = 1 "
                         f"rad/s): it is not free-floating (residual {residual:.3g})")
    return x[:, 0] if not ch.mimo else x


def _weight_array(value, name: str, unit: str, n_axes: int, *, positive: bool) -> np.ndarray:
    """A weight per axis: a real number (every axis) or, for three axes, 3 of them."""
    check = _positive_weight if positive else _nonneg
    if n_axes > 1 and isinstance(value, (list, tuple, np.ndarray)):
        array = np.asarray(value)
        if array.shape != (n_axes,):
            raise ValueError(f"{name} must be a real number or {n_axes} of them (one per axis) "
                             f"[{unit}]; got {describe(value)}")
        return np.array([check(x.item() if hasattr(x, "item") else x, f"{name}[{i}]", unit)
                         for i, x in enumerate(array)])
    return np.full(n_axes, check(value, name, unit))


def _positive_weight(value, name: str, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise TypeError(f"{name} must be a real number [{unit}]; got {type(value).__name__}")
    r = float(value)
    if not (np.isfinite(r) and r > 0):
        raise ValueError(f"{name} R must be positive definite (> 0) [{unit}]; got {r}")
    return r


def _check_weights(attitude_weight, rate_weight, torque_weight, n_axes: int = 1):
    """(q_theta, q_omega, r), each an array of n_axes entries."""
    q_theta = _weight_array(attitude_weight, "attitude_weight", "1/rad^2", n_axes,
                            positive=False)
    q_omega = _weight_array(rate_weight, "rate_weight", "s^2/rad^2", n_axes, positive=False)
    r = _weight_array(torque_weight, "torque_weight", "1/(N*m)^2", n_axes, positive=True)
    if np.any(q_theta <= 0):
        got = q_theta[0] if n_axes == 1 else describe(q_theta)
        raise ValueError("attitude_weight must be positive [1/rad^2]: with no weight on theta the "
                         "rigid-body attitude mode is undetectable in the cost (A, sqrt(Q)) and "
                         f"the attitude is not regulated; got {got}")
    return q_theta, q_omega, r


def _weights_text(q_theta, q_omega, r, W_tip) -> str:
    def text(x):
        return f"{x[0]:.3g}" if x.size == 1 else describe(np.round(x, 6))

    out = (f"attitude_weight={text(q_theta)}, rate_weight={text(q_omega)}, "
           f"torque_weight={text(r)}")
    return out + (f", deflection_weight={describe(np.diag(W_tip))}" if W_tip.size else "")


class _LazyText:
    """A message fragment formatted when a message uses it (``f"{text}"``), not before: the
    design's success path formats none (the weights' text cost a twentieth of a design)."""

    def __init__(self, function, *args):
        self._function, self._args = function, args

    def __str__(self) -> str:
        return self._function(*self._args)

    def __format__(self, spec: str) -> str:
        return format(str(self), spec)


def _rigid_bandwidths(q_theta, r, Jd, speed, weights) -> tuple[np.ndarray, np.ndarray]:
    """Rigid-body bandwidths of regulator and estimator per axis, (q/(r J^2))^(1/4) and k times
    it [rad/s], computed in logarithms (the ratio q/r of extreme weights overflows)."""
    log_wr = 0.25 * (np.log(q_theta) - np.log(r) - 2.0 * np.log(Jd))
    log_we = log_wr + math.log(speed)
    # the Riccati equations hold w^4 (the scaled attitude weight q / (r J^2)): keep it, and its
    # inverse, well inside float64 (1e+-308): |ln w| <= 150, w within 7e-66 .. 1.4e65 rad/s
    worst = int(np.argmax(np.maximum(np.abs(log_wr), np.abs(log_we))))
    if max(abs(log_wr[worst]), abs(log_we[worst])) > 150.0:
        raise ValueError(f"lqr: the weights set a rigid-body bandwidth (attitude_weight / "
                         f"(torque_weight J^2))^(1/4) = 1e{log_wr[worst] / math.log(10):.1f} rad/s "
                         f"(estimator 1e{log_we[worst] / math.log(10):.1f} rad/s), whose 4th "
                         f"power leaves the floating-point range; got {weights}")
    return np.exp(log_wr), np.exp(log_we)


@limits_blas_threads(total_states)
def lqr_design(plant: control.StateSpace, *, attitude_weight, rate_weight, torque_weight,
               deflection_weight=None, estimator: str | KalmanNoise | np.ndarray = "kalman",
               estimator_speed: float = 3.0, sample_time: float | None = None,
               feedforward: bool = False) -> LQRDesign:
    """LQR + estimator design; see :func:`lqr` (which returns only the controller)."""
    ch = check_plant(plant)
    if not isinstance(feedforward, (bool, np.bool_)):
        raise TypeError(f"feedforward must be True or False; got {describe(feedforward)}")
    m = ch.n_axes
    if sample_time is not None and not isinstance(estimator, (str, KalmanNoise)):
        raise ValueError("a Luenberger gain array is a continuous-time estimator; with sample_time "
                         "use estimator='kalman' or a KalmanNoise")
    if isinstance(estimator, str) and estimator != "kalman":
        raise ValueError(f"estimator must be 'kalman', a KalmanNoise or a Luenberger gain array "
                         f"of shape (n_states, {2 * m}); got {describe(estimator)}")
    q_theta, q_omega, r = _check_weights(attitude_weight, rate_weight, torque_weight, m)
    speed = positive(estimator_speed, "estimator_speed", "1")
    if not 1e-6 <= speed <= 1e6:
        raise ValueError(f"estimator_speed must lie in [1e-6, 1e6] (the estimator's bandwidth "
                         f"over the regulator's; beyond, no loop resolves both) [-]; got "
                         f"{speed:.6g}")
    tip_names, W_tip = _deflection_weights(plant, deflection_weight)
    weights = _LazyText(_weights_text, q_theta, q_omega, r, W_tip)  # for messages only
    T = None if sample_time is None else positive(sample_time, "sample_time", "s")
    J = rigid_body_inertia(plant)
    Jd = np.diag(inertia_matrix(J)).copy()  # the inertia each torque sees first
    w_r, w_e = _rigid_bandwidths(q_theta, r, Jd, speed, weights)
    with np.errstate(all="ignore"):
        # O(n) for a modal plant (its decoupled parts), one Schur form otherwise; the
        # evaluator of theta/torque that rigid_body_inertia used (kept with the plant): its
        # poles are A's, whatever the channel
        w_modes = np.abs(modal_evaluator(plant, list(ch.torques), list(ch.thetas)).poles())
    w_plant = float(w_modes.max(initial=0.0))
    # the lowest flexible mode (the rigid-body eigenvalues are ~sqrt(eps ||A||) from 0)
    w_low = float(w_modes[w_modes > 1e-6 * math.sqrt(max(w_plant, 1.0))].min(initial=np.inf))
    # a dominant rate weight sets its own rigid-body pole, at about sqrt(q_omega / r) / J
    with np.errstate(divide="ignore"):
        w_rate = np.where(q_omega > 0, np.exp(0.5 * (np.log(np.where(q_omega > 0, q_omega, 1.0))
                                                     - np.log(r)) - np.log(Jd)), 0.0)
    scale = max(w_plant, w_r.max(), w_e.max(), w_rate.max())
    alpha = MARGIN * scale
    sigma = PRESCRIBED_STABILITY * alpha
    if scale > MAX_SCALE_RATIO * min(w_r.min(), w_e.min()):
        # sigma > 4e-3 w_r: the prescribed stability would move the rigid-body poles by ~1 %
        raise ValueError(
            f"lqr: the rigid-body bandwidth (attitude_weight / (torque_weight J^2))^(1/4) = "
            f"{w_r.min():.3g} rad/s (estimator {w_e.min():.3g} rad/s) is too low for this "
            f"plant, whose modes reach {w_plant:.4g} rad/s: the stability margin would move the "
            "rigid-body poles; raise attitude_weight (or lower torque_weight), raise "
            f"estimator_speed or leave the highest modes out of the plant; got {weights}")
    if scale > MAX_SCALE_RATIO * w_low or w_rate.max() > 1e65:
        raise ValueError(
            f"lqr: the rigid-body bandwidths set by the weights, (attitude_weight / "
            f"(torque_weight J^2))^(1/4) = {w_r.max():.3g} rad/s, estimator {w_e.max():.3g} "
            f"rad/s and sqrt(rate_weight / torque_weight) / J = {w_rate.max():.3g} rad/s, reach "
            f"more than {MAX_SCALE_RATIO:g} times the plant's lowest flexible mode "
            f"{w_low:.4g} rad/s, whose poles the stability margin then cannot resolve; lower "
            f"attitude_weight and rate_weight (or raise torque_weight); got {weights}")
    design_plant, removed, removed_eigs = design_model(plant, critical=sigma, J=J, what="lqr")
    noise = None
    if isinstance(estimator, KalmanNoise):
        noise = estimator
        noise.per_axis(m)  # the right number of axes
    elif isinstance(estimator, str):
        with np.errstate(all="ignore"):
            noise_values = np.concatenate([speed ** 4 / r, 1.0 / q_theta,
                                           (1.0 / q_theta) * (speed * w_r) ** 2])
        if not np.all(np.isfinite(noise_values) & (noise_values > 0)):
            raise ValueError("lqr: the default Kalman noises (estimator_speed^4 / torque_weight, "
                             "1 / attitude_weight, ...) leave the floating-point range for these "
                             f"weights; give a KalmanNoise or moderate weights; got {weights}")
        noise = (KalmanNoise.default(float(Jd[0]), float(q_theta[0]), float(r[0]), speed)
                 if m == 1 else KalmanNoise.default(inertia_matrix(J), q_theta, r, speed))
    else:
        L_given = real_array(estimator, "estimator", "-")
        n_d = design_plant.nstates
        if L_given.shape != (n_d, 2 * m):
            detail = (f" (the design model: the plant without the {len(removed)} mode(s) the "
                      "loop cannot influence, see LQRDesign.removed_modes)" if removed else "")
            what = "[theta, omega]" if m == 1 else "[theta_x..z, omega_x..z]"
            raise ValueError(f"Luenberger estimator gain must have shape ({n_d}, {2 * m}) "
                             f"(states x {what}){detail}; got {L_given.shape}")
    Q, N, R, r0 = _cost(design_plant, q_theta, q_omega, r, tip_names, W_tip)
    x_ref = reference_state(design_plant)
    x_rate = rate_reference_state(design_plant) if feedforward else None
    L_fixed = None if noise is not None else L_given

    def designed(sigma):
        for digital in ([False, True] if T is not None else [False]):
            try:
                with np.errstate(all="ignore"):
                    design = _design(design_plant, Q, N, R, r0, Jd, x_ref, noise, L_fixed,
                                     sigma, T if digital else None, x_rate)
            except (np.linalg.LinAlgError, ValueError, FloatingPointError,
                    ZeroDivisionError) as exc:
                if digital:  # the continuous design at these weights has just succeeded
                    raise ValueError(
                        f"lqr: the digital design at sample_time {T:.4g} s failed numerically "
                        f"({describe(str(exc))}) where the continuous design with the same "
                        f"weights succeeded: the sampling is the cause (plant modes up to "
                        f"{w_plant:.4g} rad/s, omega T up to {w_plant * T:.3g}; rigid-body "
                        f"bandwidth {describe(np.round(w_r, 4)) if m > 1 else f'{w_r[0]:.3g}'} "
                        f"rad/s): change sample_time, or use the continuous design") from None
                raise ValueError(
                    f"lqr: the {'digital ' if digital else ''}design failed numerically for "
                    f"these weights ({describe(str(exc))}); the rigid-body bandwidth is "
                    f"{describe(np.round(w_r, 4)) if m > 1 else f'{w_r[0]:.3g}'} rad/s "
                    f"against plant modes up to {w_plant:.4g} rad/s: choose weights that put "
                    f"it within a few decades of the modes; got {weights}") from None
            if T is not None and not digital:
                # the sampling rule on the continuous design loop's rigid-body crossover
                check_sampling(T, rigid_crossover(design_plant, design.controller), "lqr")
        return _checked(design, alpha, T, weights, estimator)

    # the guarantee is on the loop's own poles, which round-off can put further right than the
    # separate regulator and estimator spectra (see _loop_round_off): checked on the whole plant
    # (the design plant's loop and the removed modes, exactly), and the degree of stability
    # raised above the round-off measured on the loop (at most ROUND_OFF_ATTEMPTS times)
    sigma_cap = SIGMA_CAP * min(w_low, w_r.min(), w_e.min())
    for attempt in range(ROUND_OFF_ATTEMPTS + 1):
        design = designed(sigma)
        worst, excess = _loop_round_off(plant, design, alpha, removed_eigs if removed else (),
                                        T)
        if worst is None:
            break
        sigma = max(2.0 * sigma, sigma + PRESCRIBED_STABILITY * excess)
        if attempt == ROUND_OFF_ATTEMPTS or not sigma <= sigma_cap:
            speed_text = f"{speed:.3g}"
            raise ValueError(
                f"lqr: the closed loop on the design plant has a pole at {worst.real:.3g} "
                f"{'+' if worst.imag >= 0 else '-'} {abs(worst.imag):.6g}j "
                f"({abs(worst):.6g} rad/s), Re(s) > -{alpha:.2g} 1/s (the stability margin): "
                f"the gains of a regulator at {w_r.max():.3g} rad/s and an estimator at "
                f"{w_e.max():.3g} rad/s are too high for double precision to resolve the "
                "damping of this mode (round-off moves it by "
                f"{excess:.2g} 1/s); lower estimator_speed (now {speed_text}) or "
                f"attitude_weight; got {weights}")
    if removed:
        # the removed modes must keep their places in the loop on the whole plant
        def advise(pole, _alpha, _scale):
            if pole == 0j or not np.isfinite(pole):  # the loop's scale, or non-finite poles
                return ("lower attitude_weight and estimator_speed (or raise torque_weight) "
                        f"for a slower loop; got {weights}")
            # a removed mode is out of the loop's reach by construction: what moves it is
            # round-off of high gains, or a plant whose mode is only nearly decoupled
            return ("a mode left out of the design model is moved by the loop after all; "
                    "lower estimator_speed or attitude_weight (round-off of high gains), or "
                    f"prune the mode from the plant (Spacecraft.plant(prune=True)); got {weights}")

        verify_loop(plant, design.controller, J=J, what="lqr", removed_eigs=removed_eigs,
                    scale_floor=scale, advise=advise)
        warn_removed_modes("lqr", removed, "(left out of the design model; they keep their "
                           "open-loop eigenvalues in the closed loop)")
    return LQRDesign(design.controller, design.K, design.L, design.Q, design.R, design.N,
                     design.x_ref, design.regulator_poles, design.estimator_poles,
                     design_plant, tuple(removed), alpha, x_rate)


def _cost(plant, q_theta, q_omega, r, tip_names, W_tip):
    """Q, N, R of the cost on the design model's states, divided by r0, and r0.

    r0 is the torque weight (three axes: the geometric mean of the axes' weights). The LQR gain
    does not change when Q, N, R are scaled together; dividing by r0 keeps extreme but valid
    weights (r = 1e-300) away from the floating-point limits.
    """
    ch = channels(plant)
    labels = list(plant.output_labels)
    i_t = [list(plant.input_labels).index(n) for n in ch.torques]
    rows = [labels.index(name) for name in list(ch.thetas + ch.omegas) + tip_names]
    Cw = plant.C[rows]
    Dw = plant.D[np.ix_(rows, i_t)]
    r0 = float(r[0]) if r.size == 1 else float(np.exp(np.mean(np.log(r))))
    # W = blockdiag(diag(q_theta, q_omega), W_tip), assigned (scipy's block_diag costs more
    # than the rest of the cost's set-up)
    k = 2 * q_theta.size
    W = np.zeros((k + W_tip.shape[0],) * 2)
    W[np.arange(k), np.arange(k)] = np.concatenate([q_theta, q_omega])
    W[k:, k:] = W_tip
    with np.errstate(over="ignore", invalid="ignore"):
        Q = Cw.T @ (W / r0) @ Cw
        N = Cw.T @ (W / r0) @ Dw
        R = np.diag(r / r0) + Dw.T @ (W / r0) @ Dw
    if not (np.all(np.isfinite(Q)) and np.all(np.isfinite(N)) and np.all(np.isfinite(R))):
        raise ValueError("lqr: the weights divided by torque_weight overflow; got "
                         f"{_weights_text(q_theta, q_omega, r, W_tip)}")
    Q = 0.5 * (Q + Q.T)
    Qc = Q - N @ np.linalg.solve(R, N.T)
    eig_q = np.linalg.eigvalsh(0.5 * (Qc + Qc.T))
    if eig_q.min() < -1e-10 * max(1.0, abs(eig_q).max()):
        raise ValueError(f"state weight Q must be positive semidefinite; got eigenvalue "
                         f"{eig_q.min() * r0:.3g}")
    return Q, N, R, r0


def _design(plant, Q, N, R, r0, Jd, x_ref, noise, L_given, sigma, T, x_rate=None
            ) -> LQRDesign:
    """The LQR + estimator on the design model with prescribed degree of stability sigma
    (cost Q, N, R divided by r0); digital (ZOH, predictor estimator) if T is given; with
    x_rate (feedforward) also the inputs omega_ref and torque_ff."""
    ch = channels(plant)
    m = ch.n_axes
    labels = list(plant.output_labels)
    i_t = [list(plant.input_labels).index(n) for n in ch.torques]
    A = np.asarray(plant.A, dtype=float)
    B = np.asarray(plant.B[:, i_t], dtype=float)
    n = A.shape[0]
    meas_rows = [labels.index(name) for name in ch.thetas + ch.omegas]
    Cm = plant.C[meas_rows]
    Dm = plant.D[np.ix_(meas_rows, i_t)]
    I = np.eye(n)
    # Scaling: torque i in units of J_ii rad/s^2 (B_s = B S, S = diag(J_ii)) and the cost divided
    # by c = J^2 (three axes: the squared geometric mean of the J_ii), the noises divided by the
    # attitude noise (its geometric mean). Neither changes the gains (K = S K_s) but both bring
    # the Hamiltonians' entries to the plant's own scale (omega^2, omega_r^4): with hub and
    # weights in SI units they span 1e-16 (B B^T of a 5e7 kg m^2 hub) to 1e11 (q), and the
    # Schur vectors lose the weakly excited modes (Re = -3e-16 instead of < -sigma, measured).
    c_root = Jd[0] if m == 1 else float(np.exp(np.mean(np.log(Jd))))
    S = np.diag(Jd)
    Sn = np.diag(Jd / c_root)  # S / sqrt(c): 1 for the planar design
    Bs, Qs, Ns = B @ S, Q / c_root ** 2, N @ Sn / c_root
    Rs = Sn @ R @ Sn
    if noise is not None:
        W_t, V_t, V_w = noise.per_axis(m)
        v0 = V_t[0] if m == 1 else float(np.exp(np.mean(np.log(V_t))))
        Ws = (B * (W_t / v0)) @ B.T
        Vs = np.diag(np.concatenate([V_t, V_w]) / v0)
    if T is None:
        P = solve_care(A + sigma * I, Bs, Qs, Rs, Ns, "regulator")
        K = S @ np.linalg.solve(Rs, Bs.T @ P + Ns.T)
        if L_given is None:
            Sk = solve_care(A.T + sigma * I, Cm.T, Ws, Vs, np.zeros((n, 2 * m)),
                            "Kalman filter")
            L = Sk @ Cm.T @ np.linalg.inv(Vs)
        else:
            L = L_given
        Phi, Gamma = A, B
    else:
        # digital design on the zero-order-hold model (Phi, Gamma); the continuous cost sampled
        # at T to first order: Q_d = Q T, N_d = N T, R_d = R T (valid for T well below the
        # closed-loop time constants, which check_sample_time enforces); noises
        # W_d = B W B^T T, V_d = V / T. Prescribed degree of stability: the DAREs of
        # Phi / rho, Gamma / rho with rho = exp(-sigma T) put every closed-loop |z| < rho.
        # Predictor estimator: x_hat[k+1] = Phi x_hat + Gamma u + L (y[k] - C x_hat - D u).
        E = scipy.linalg.expm(np.block([[A, B], [np.zeros((m, n + m))]]) * T)
        Phi, Gamma = E[:n, :n], E[:n, n:]
        rho = math.exp(-sigma * T)
        Pt, Gt = Phi / rho, Gamma @ S / rho
        P = solve_dare(Pt, Gt, Qs * T, Rs * T, Ns * T, "digital regulator")
        K = S @ np.linalg.solve(Rs * T + Gt.T @ P @ Gt, Gt.T @ P @ Pt + (Ns * T).T)
        Wd, Vd = Ws * T, Vs / T
        Sk = solve_dare(Pt.T, Cm.T, Wd, Vd, None, "digital Kalman filter")
        L = rho * (Pt @ Sk @ Cm.T @ np.linalg.inv(Cm @ Sk @ Cm.T + Vd))
    # poles the Riccati solution could not resolve (below): moved by a modal correction
    if T is None:
        def flagged(x):
            return x.real > -0.5 * sigma

        def target(x):
            return complex(-sigma, x.imag)
    else:
        limit, rho = math.exp(-0.5 * sigma * T), math.exp(-sigma * T)

        def flagged(x):
            return abs(x) > limit

        def target(x):
            return rho * x / abs(x) if abs(x) > 0 else complex(0.0)
    dK, regulator_poles = modal_correction(Phi - Gamma @ K, Gamma, flagged, target)
    dL, estimator_poles = modal_correction((Phi - L @ Cm).T, Cm.T, flagged, target)
    K, L = K + dK, L + dL.T
    Bm = Gamma - L @ Dm
    Ac = Phi - L @ Cm - Bm @ K
    X_ref = x_ref.reshape(n, m)
    g = K @ X_ref  # torque per rad of reference (a rigid rotation needs no torque)
    refs, G = ch.refs, [g]
    if x_rate is not None:
        # torque = -K (x_hat - x_ref theta_ref - x_rate omega_ref) + torque_ff; the estimator
        # sees the whole torque (B u), feedforward included
        refs = ch.refs + ch.omega_refs + ch.feedforwards
        G = [g, K @ x_rate.reshape(n, m), np.eye(m)]
    Bc = np.hstack([Bm @ gi for gi in G] + [L])
    controller = control.ss(Ac, Bc, -K, np.hstack(G + [np.zeros((m, 2 * m))]),
                            0 if T is None else T,
                            inputs=list(refs + ch.thetas + ch.omegas),
                            outputs=list(ch.torques), name="lqr")
    return LQRDesign(controller, K, L, Q * r0, R * r0, N * r0, x_ref,
                     regulator_poles, estimator_poles)


def _loop_round_off(plant, design: LQRDesign, alpha: float, removed_eigs, T):
    """(worst pole, excess) of the loop on ``plant``, or (None, 0.0) if every pole has
    Re(s) <= -alpha (s = log(z) / T for a digital loop) other than those within alpha of a
    removed mode's eigenvalue ``removed_eigs`` (aliased for a digital loop); excess =
    Re(worst) + alpha [1/s].

    The loop's poles are, exactly, the regulator's and the estimator's (separation), and
    those each meet Re <= -2 alpha (_checked). But a high-gain regulator and estimator place
    poles near the same transmission zero (the antiresonances of a collocated plant, where
    cheap-control LQ poles converge), and in the loop the nearly coincident pair, coupled by
    B K, is computed with an error of about eps ||L C|| / gap-type sensitivity: measured
    2.4e-7 1/s for an estimator at 1e5 rad/s (gains L ~ 4 w_e^2 = 4e10), 20 times the margin,
    while the estimator pole itself was at -4e-8. The check is on the loop the guarantee is
    about, as a user (close_loop(...).poles()) computes it. A violating pole nearer a
    removed mode than any designed pole is not round-off but a removed mode the loop moves:
    (None, 0.0), and verify_loop refuses it with its own advice.

    References
    ----------
    J. H. Wilkinson, The Algebraic Eigenvalue Problem, 1965, ch. 2 (perturbation of close
    eigenvalues); B. D. O. Anderson, J. B. Moore, Optimal Control, 1990, sec. 7.4 (LQ poles
    at the transmission zeros as the control weight goes to zero).
    """
    with np.errstate(all="ignore"):
        poles = continuous_poles(close_loop(plant, design.controller))
        kept = np.asarray(removed_eigs, dtype=complex).reshape(-1)
        if T is not None:
            kept = np.log(np.exp(kept * T)) / T
    if not np.all(np.isfinite(poles)):
        return complex(np.inf), np.inf
    if kept.size:
        poles = poles[np.min(np.abs(poles[:, None] - kept[None, :]), axis=1) > alpha]
    if not poles.size or poles.real.max() <= -alpha:
        return None, 0.0
    worst = complex(poles[np.argmax(poles.real)])
    designed = np.concatenate([design.regulator_poles, design.estimator_poles]).astype(complex)
    if T is not None:
        with np.errstate(all="ignore"):
            designed = np.log(designed) / T
    if kept.size and np.min(np.abs(kept - worst)) < np.min(np.abs(designed - worst),
                                                             initial=np.inf):
        # a removed mode that the loop moves: not round-off (verify_loop says what to do)
        return None, 0.0
    return worst, worst.real + alpha


def _checked(design: LQRDesign, alpha: float, T, weights: str, estimator) -> LQRDesign:
    """Check the guarantee on the computed poles: Re(s) <= -alpha (|z| <= exp(-alpha T))."""
    for name, poles in (("regulator", design.regulator_poles),
                        ("estimator", design.estimator_poles)):
        with np.errstate(divide="ignore", invalid="ignore"):
            s = poles.astype(complex) if T is None else np.log(poles.astype(complex)) / T
        finite = np.all(np.isfinite(design.K)) and np.all(np.isfinite(design.L))
        worst = s[np.argmax(s.real)] if s.size else -np.inf
        if finite and (not s.size or worst.real <= -alpha):
            continue
        where = (f"{worst.real:.3g} {'+' if worst.imag >= 0 else '-'} {abs(worst.imag):.6g}j "
                 f"({abs(worst):.6g} rad/s)") if finite and s.size else "non-finite gains"
        if name == "estimator" and not isinstance(estimator, (str, KalmanNoise)):
            raise ValueError(f"estimator: the Luenberger gain L leaves the estimator A - L C "
                             f"with an eigenvalue at {where}, Re > -{alpha:.2g} 1/s (the "
                             "stability margin): the estimator is not stable; give a gain that "
                             "places every eigenvalue of A - L C in the left half-plane")
        raise ValueError(f"lqr: the {name} is not stable to the margin {alpha:.2g} 1/s: "
                         f"eigenvalue {where}; the Riccati equation cannot be solved accurately "
                         f"for these weights; moderate them; got {weights}")
    return design


@limits_blas_threads(total_states)
def lqr(plant: control.StateSpace, *, attitude_weight, rate_weight, torque_weight,
        deflection_weight=None,
        estimator: str | KalmanNoise | np.ndarray = "kalman", estimator_speed: float = 3.0,
        sample_time: float | None = None, feedforward: bool = False) -> control.StateSpace:
    """LQR attitude controller with a state estimator, as a dynamic output-feedback controller.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous free-floating design plant (e.g. hub + chain): input ``'torque'`` [N*m],
        outputs ``'theta'`` [rad], ``'omega'`` [rad/s], optionally ``'*tip_deflection'`` [m];
        or the three-axis signals ``'torque_x'``..``'omega_z'`` (:mod:`controllers.signals`).
    attitude_weight : float or 3 floats, 1/rad^2
        Weight q_theta > 0 on theta^2 in the cost (three axes: on each theta_i^2, one value for
        every axis or one per hub axis).
    rate_weight : float or 3 floats, s^2/rad^2
        Weight q_omega >= 0 on omega^2 (per axis likewise).
    torque_weight : float or 3 floats, 1/(N*m)^2
        R = r > 0 on torque^2 (per torque axis likewise; R = diag(r_i)).
    deflection_weight : float (1/m^2), mapping name -> float, or (n_tip, n_tip) PSD array, optional
        Weight on the plant's tip-deflection outputs (a float applies to each of them).
    estimator : "kalman", KalmanNoise or ndarray (n_states, 2) (three axes: (n_states, 6))
        "kalman" (default): steady-state Kalman filter on the design model with the noises of
        :meth:`KalmanNoise.default` (torque disturbance entering with the torque, attitude and rate
        sensor noise; filter about ``estimator_speed`` times faster than the regulator's rigid-body
        poles). A KalmanNoise: a Kalman filter with those intensities. An array: a Luenberger gain
        L on the innovations [theta - theta_hat, omega - omega_hat] (three axes: theta_x..z,
        omega_x..z; continuous designs only), for the states of the design model (the
        plant's, when no mode is removed). The default noises are per axis
        (:meth:`KalmanNoise.default` with J_ii and each axis's weights).
    estimator_speed : float
        Ratio of estimator to regulator bandwidth for the default Kalman noises (default 3).
    sample_time : float, s, optional
        Digital design at this sample time: discrete LQR and discrete (predictor) Kalman filter
        on the zero-order-hold discretisation of the design model; the controller has ``dt =
        sample_time``. The sampling frequency must be at least 10 times the continuous design
        loop's rigid-body gain crossover (:func:`controllers.pd.check_sample_time`).
    feedforward : bool
        Also take a rate reference and a feedforward torque (a slew profile's omega_ref and
        torque_ff, :mod:`controllers.profiles`): torque = -K (x_hat - x_ref theta_ref -
        x_rate omega_ref) + torque_ff (:func:`rate_reference_state`), the estimator driven by
        the whole torque. With omega_ref = torque_ff = 0 the controller is the one without
        feedforward (the same matrices, more input columns). Default False.

    Returns
    -------
    control.StateSpace
        Inputs ``['theta_ref', 'theta', 'omega']``, output ``['torque']`` (three axes: inputs
        ``theta_ref_x..z, theta_x..z, omega_x..z``, outputs ``torque_x..z``), states = the
        estimate x_hat of the design model's states:
        x_hat' = A x_hat + B torque + L (y - C x_hat - D torque),
        torque = -K (x_hat - x_ref theta_ref), with x_ref from :func:`reference_state`. On a
        free-floating truth plant the steady state is theta = theta_ref exactly (a rigid
        rotation is an equilibrium of plant and estimator, and K x_ref != 0).

    Notes
    -----
    Guarantee: on the design plant every closed-loop pole has Re(s) <= -alpha (|z| <=
    exp(-alpha T) for a digital design), alpha = MARGIN x the spectral scale (the largest of
    the plant's |eigenvalues| and the regulator's and estimator's rigid-body bandwidths; see
    :mod:`controllers.stability`), except the modes the loop cannot influence, which keep their
    open-loop eigenvalues. Those (undamped or nearly so, with a participation <= INFLUENCE_TOL:
    the symmetric bending of symmetric wings, the free-tip mode of a long hinged chain, a hub
    translation) are left out of the design model before the Riccati equations are solved,
    listed in :attr:`LQRDesign.removed_modes` (see :func:`lqr_design`) and announced by a
    :class:`~controllers.RemovedModesWarning`. The margin is reached by design: both Riccati
    equations are solved for A + sigma I, sigma = PRESCRIBED_STABILITY alpha (prescribed degree
    of stability), which moves a pole the cost barely sees (a high, weakly excited beam mode,
    left by the plain LQR at Re ~ -1e-10 or, in round-off, +3e-13) to Re < -sigma at a cost of
    gains O(sigma / participation); the rigid-body poles move by O(sigma / w_r), ~1e-12.
    The loop's own poles are then computed on the plant: where round-off puts one at
    Re > -alpha (nearly coincident regulator and estimator poles at a transmission zero of a
    high-gain design), sigma is raised above the measured round-off, at most
    ``ROUND_OFF_ATTEMPTS`` times and to ``SIGMA_CAP`` times the lowest flexible mode and
    rigid-body bandwidth (a damping ratio of at most 1e-4 added).

    Raises
    ------
    ValueError
        Negative or non-finite weights, R not > 0, Q not PSD, a design whose rigid-body
        bandwidth is too low or too high for the plant (the message names the weights), nearly
        repeated undamped modes that one torque cannot all reach, a Luenberger gain that does not
        stabilise the estimator (names ``estimator``), a sample time too long, gains too
        high for double precision to resolve a mode's damping in the loop (names the mode,
        ``estimator_speed`` and ``attitude_weight``).

    Three axes: the Riccati equations are those of the multi-input problem (R diagonal,
    B with three columns); each torque is scaled by its axis's inertia J_ii and the cost by the
    squared geometric mean of the J_ii, which leaves the gains unchanged and the Hamiltonian
    well scaled. On a rigid body with a diagonal inertia the gains are those of three planar
    designs, one per axis.

    References
    ----------
    B. D. O. Anderson, J. B. Moore, Optimal Control: Linear Quadratic Methods, Prentice Hall 1990
    (LQR with cross term N, stabilisability/detectability conditions; sec. 3.5, prescribed degree
    of stability); Franklin, Powell & Workman, Digital Control of Dynamic Systems, 3rd ed., ch. 9
    (discrete LQR, predictor estimator); M. J. Balas, IEEE TAC 23(4), 1978 (observer-based
    control of flexible structures).
    """
    return lqr_design(plant, attitude_weight=attitude_weight, rate_weight=rate_weight,
                      torque_weight=torque_weight, deflection_weight=deflection_weight,
                      estimator=estimator, estimator_speed=estimator_speed,
                      sample_time=sample_time, feedforward=feedforward).controller
