"""PD attitude controller tuned from a closed-loop specification.

On the rigid-body part of the plant, theta/torque = 1/(J s^2), the control law
torque = Kp (theta_ref - theta) - Kd omega gives the closed loop J s^2 + Kd s + Kp = 0, i.e.
s^2 + 2 zeta wn s + wn^2 = 0 with Kp = J wn^2 and Kd = 2 zeta wn J.

Three axes: the same law with 3 x 3 gains on the vectors theta, omega, theta_ref (hub axes) and
the rigid-body plant J theta'' = torque, J the inertia tensor. From a specification per axis
(natural frequencies wn_i, dampings zeta_i; a scalar applies to every axis):

``axes="principal"`` (default)
    J = R diag(j) R^T (principal moments j_i, principal axes the columns of R, each matched to
    the hub axis it is closest to), Kp = R diag(j_i wn_i^2) R^T, Kd = R diag(2 j_i zeta_i wn_i)
    R^T: symmetric positive definite gains, so the loop on collocated attitude and rate is
    passive and damps every flexible mode; the rigid loop decouples along the principal axes
    into j_i s^2 + 2 j_i zeta_i wn_i s + j_i wn_i^2.
``axes="hub"``
    Kp = J diag(wn^2), Kd = J diag(2 zeta wn): the rigid loop decouples along the hub axes into
    s^2 + 2 zeta_i wn_i s + wn_i^2 (each hub axis exactly as specified), at the price of
    non-symmetric gains when J is not diagonal and the axes' specifications differ (no passivity
    argument then; the design is checked on the plant all the same).

With one wn and zeta for all axes both give Kp = wn^2 J, Kd = 2 zeta wn J.
"""
from __future__ import annotations

import itertools
import math

import control
import numpy as np

from .frequency import modal_evaluator
from .margins import zero_crossings
from .modes import flexible_modes, inertia_matrix, rigid_body_inertia, verify_loop
from .arguments import check_choice, check_inertia, describe, positive, real_array, real_number
from .signals import channels, check_plant
from .stability import warn_removed_modes
from .threads import limits_blas_threads, total_states

__all__ = [
    "pd",
    "pd_gains",
    "principal_axes",
    "natural_frequency_from_bandwidth",
    "check_sample_time",
    "check_sampling",
    "rigid_crossover",
    "ROLL_OFF_DAMPING",
    "NOTCH_ZERO_DAMPING",
    "NOTCH_POLE_DAMPING",
    "MIN_SAMPLES_PER_CROSSOVER",
    "MIN_CROSSOVER_ANGLE",
]

#: Damping of the second-order roll-off low-pass (1/sqrt(2): Butterworth, flat pass band).
ROLL_OFF_DAMPING = 1.0 / math.sqrt(2.0)
#: Damping of the notch's zeros: depth at the notch frequency = 20 log10(0.02 / 0.5) = -28 dB.
NOTCH_ZERO_DAMPING = 0.02
#: Damping of the notch's poles: sets its width (about +/- 50 % of the frequency at -3 dB),
#: wide enough to cover the usual mismatch between a chain model's and the beam's first mode.
NOTCH_POLE_DAMPING = 0.5
#: A digital controller needs a sampling frequency 2 pi / T at least this many times the
#: rigid-body gain-crossover frequency of its continuous design loop (Franklin, Powell &
#: Workman, Digital Control of Dynamic Systems, 3rd ed., sec. 11.2: 10 to 30 times the bandwidth;
#: below 10 the hold's phase lag omega T / 2 at crossover exceeds 18 deg).
MIN_SAMPLES_PER_CROSSOVER = 10.0


def natural_frequency_from_bandwidth(bandwidth: float, damping: float) -> float:
    """Natural frequency wn [rad/s] of the second-order prototype with a given -3 dB bandwidth.

    For T(s) = wn^2 / (s^2 + 2 zeta wn s + wn^2), |T(j wb)| = 1/sqrt(2) at
    wb = wn sqrt(1 - 2 zeta^2 + sqrt(4 zeta^4 - 4 zeta^2 + 2)); this inverts it. (The PD loop's
    complementary sensitivity also has the zero of Kd s + Kp, so its own bandwidth is somewhat
    higher than this prototype value.)

    Parameters
    ----------
    bandwidth : float, rad/s
    damping : float
        Damping ratio zeta > 0.

    References
    ----------
    Franklin, Powell & Emami-Naeini, Feedback Control of Dynamic Systems, 7th ed., ch. 6
    (bandwidth of the standard second-order system); K. Ogata, Modern Control Engineering, 5th ed.,
    ch. 7 (same relation).
    """
    bandwidth = positive(bandwidth, "bandwidth", "rad/s")
    damping = positive(damping, "damping", "1")
    # wn = wb / sqrt(hypot(a, 1) - a), a = 2 zeta^2 - 1 (4 zeta^4 - 4 zeta^2 + 2 = a^2 + 1);
    # for a > 0 the difference cancels, and 1 / (hypot(a, 1) - a) = hypot(a, 1) + a is exact.
    # Written with a = zeta^2 b, b = 2 - zeta^-2, so that no zeta^2 overflows.
    if damping <= 1.0:
        a = 2.0 * damping * damping - 1.0
        factor = 1.0 / math.sqrt(math.hypot(a, 1.0) - a)
    else:
        b = 2.0 - 1.0 / (damping * damping)
        factor = damping * math.sqrt(b + math.hypot(b, 1.0 / (damping * damping)))
    wn = bandwidth * factor
    if not math.isfinite(wn):
        raise ValueError(f"bandwidth {bandwidth:.6g} rad/s with damping {damping:.6g} needs a "
                         f"natural frequency of about {bandwidth:.3g} x {factor:.3g} rad/s, "
                         "beyond the floating-point range; choose a smaller bandwidth or damping")
    return wn


def pd_gains(inertia, natural_frequency, damping, *, axes: str = "principal"):
    """Kp [N*m/rad] = J wn^2 and Kd [N*m*s/rad] = 2 zeta wn J (closed loop J s^2 + Kd s + Kp).

    A scalar inertia gives float gains. A (3, 3) inertia tensor gives (3, 3) gain matrices from
    per-axis natural frequencies and dampings (scalars or 3-sequences) in the principal axes of
    J or in the hub axes (``axes``, see the module docstring).

    Computed in IEEE arithmetic: a gain beyond the float64 range is inf (0 below it), never an
    OverflowError.

    Parameters
    ----------
    inertia : float or (3, 3) array, kg*m**2
        Positive and finite; a tensor symmetric positive definite and a body's
        (:func:`controllers.arguments.check_inertia`).
    natural_frequency : float or 3 floats, rad/s
        Positive and finite (per axis for a tensor).
    damping : float or 3 floats, -
        Positive and finite (per axis for a tensor).
    axes : {"principal", "hub"}

    Raises
    ------
    TypeError, ValueError
        A parameter that is not as above (named in the message).
    """
    n_axes = 1 if np.ndim(inertia) == 0 and not isinstance(inertia, (list, tuple)) else 3
    wn = _per_axis(natural_frequency, "natural_frequency", "rad/s", n_axes)
    zeta = _per_axis(damping, "damping", "1", n_axes)
    check_choice(axes, "axes", ("principal", "hub"))
    if n_axes == 1:
        return _gains(positive(inertia, "inertia", "kg*m^2"), wn[0], zeta[0], axes)
    return _gains(check_inertia(inertia), wn, zeta, axes)


def _gains(J, wn, zeta, axes: str):
    """pd_gains on checked arguments (a float J with floats wn, zeta; or a 3x3 J with 3 each)."""
    if np.ndim(J) == 0:
        with np.errstate(over="ignore", under="ignore"):
            J, wn, zeta = np.float64(J), np.float64(wn), np.float64(zeta)
            return float(J * wn * wn), float(2.0 * zeta * wn * J)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        if axes == "hub":
            return J * (wn * wn)[None, :], J * (2.0 * zeta * wn)[None, :]
        j, R = _principal_axes(J)
        return (R * (j * wn * wn)) @ R.T, (R * (2.0 * zeta * wn * j)) @ R.T


def principal_axes(inertia) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments j [kg*m^2] and axes R (columns, hub axes) of an inertia tensor,
    J = R diag(j) R^T, ordered so that column i is the principal axis closest to hub axis i
    (the permutation maximising the product of |R_ii|) with R_ii > 0. A diagonal J gives
    R = I exactly.

    Raises
    ------
    TypeError, ValueError
        ``inertia`` not a 3x3 inertia tensor of a body (:func:`controllers.arguments.check_inertia`).
    """
    return _principal_axes(check_inertia(inertia))


def _principal_axes(J: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if np.count_nonzero(J - np.diag(np.diag(J))) == 0:
        return np.diag(J).copy(), np.eye(3)
    j, V = np.linalg.eigh(0.5 * (J + J.T))
    best = max(itertools.permutations(range(3)),
               key=lambda p: float(np.prod(np.abs(V[np.arange(3), list(p)]))))
    R = V[:, list(best)]
    R = R * np.where(np.diag(R) < 0, -1.0, 1.0)[None, :]
    return j[list(best)], R


def rigid_crossover(plant, controller) -> float:
    """Gain-crossover frequency [rad/s] of a continuous controller on the plant's rigid body.

    The loop is taken on the rigid-body part of the plant alone, theta/torque = 1/(J s^2) and
    omega/torque = 1/(J s), J from :func:`~controllers.rigid_body_inertia`:
    L_r(j w) = -(K_theta(j w) / (J (j w)^2) + K_omega(j w) / (J j w)). Its crossover is the
    lowest frequency where |L_r| falls through 1: the loop's bandwidth, which flexible
    resonances (crossings of |L| = 1 at undamped modes) do not move.

    Parameters
    ----------
    plant : control.StateSpace
        A checked plant (its rigid-body inertia is read from it).
    controller : control.StateSpace
        A continuous controller of the plant's convention.

    Returns
    -------
    float
        The crossover [rad/s]; 0 when the controller feeds back neither attitude nor rate, or
        its loop gain never reaches 1.
    """
    ch = channels(plant)
    Jinv = np.linalg.inv(inertia_matrix(rigid_body_inertia(plant)))
    inputs = [name for name in ch.thetas + ch.omegas if name in controller.input_labels]
    if not inputs:
        return 0.0
    ev = modal_evaluator(controller, inputs, list(ch.torques))
    # rigid-body plant rows: theta_i = (J^-1 u)_i / s^2, omega_i = (J^-1 u)_i / s
    rows = np.array([Jinv[(ch.thetas + ch.omegas).index(n) % ch.n_axes] for n in inputs])
    powers = np.array([2.0 if name in ch.thetas else 1.0 for name in inputs])

    def gain(w):
        w = np.asarray(w, dtype=float)
        with np.errstate(all="ignore"):
            K = ev(1j * w)  # (f, m, n_in)
            P = rows[None, :, :] / (1j * w[:, None, None]) ** powers[None, :, None]
            L = K @ P
            if L.shape[1] == 1:
                return np.abs(L[:, 0, 0])
            return np.linalg.svd(L, compute_uv=False)[:, 0]

    with np.errstate(all="ignore"):
        K0 = np.abs(ev(np.array([0.0]))[0]).max(axis=0)
    j_max = float(np.abs(Jinv).max())
    w0 = max(math.sqrt(K0[i] * j_max) if name in ch.thetas else K0[i] * j_max
             for i, name in enumerate(inputs))
    if not (math.isfinite(w0) and w0 > 0):
        return 0.0
    omega = w0 * np.logspace(-4.0, 4.0, 801)
    with np.errstate(divide="ignore"):
        log_gain = np.log(gain(omega))
    down = np.nonzero((log_gain[:-1] >= 0) & (log_gain[1:] < 0))[0]
    if down.size == 0:
        return float(omega[-1]) if log_gain[-1] >= 0 else 0.0
    i = down[0]
    with np.errstate(divide="ignore"):
        roots = zero_crossings(lambda w: np.log(gain(w)), omega[i:i + 2], log_gain[i:i + 2])
    return float(roots[0]) if roots.size else float(omega[i])


#: |sin(omega T)| at or below which a sample time is refused as pathological for a mode omega
#: (the two sampled eigenvalues exp(+-j omega T) are then 2 |sin(omega T)| apart).
PATHOLOGICAL_SAMPLING = 1e-6


#: Smallest rigid-body crossover angle per sample, omega_c T, of a digital loop. The sampled
#: loop's poles z = exp(s T) then lie about omega_c T from z = 1, and s = log(z) / T is
#: resolved only to eps / T: at omega_c T = 1e-9 that is 2.2e-7 of omega_c (the loop's own
#: decay rates, the flexible modes' damping, are resolved), below it the digital loop's poles,
#: margins and stability verdict are round-off (a PD at T = 1e-14 s had its rigid-body poles
#: computed at z = 1 exactly).
MIN_CROSSOVER_ANGLE = 1e-9


def check_sampling(sample_time: float, omega_c: float, what: str) -> None:
    """Check a sample time T [s] against a loop's rigid-body crossover omega_c [rad/s].

    Raises
    ------
    ValueError
        ``omega_c T < MIN_CROSSOVER_ANGLE`` (too fast for double precision) or
        ``2 pi / T < MIN_SAMPLES_PER_CROSSOVER omega_c`` (too slow for the bandwidth); the
        message starts with ``what`` (the design) and gives the sample times that would do.
    """
    if 0.0 < omega_c * sample_time < MIN_CROSSOVER_ANGLE:
        raise ValueError(
            f"{what}: sample_time {sample_time:.4g} s is too short for double precision: the "
            f"loop turns by omega_c T = {omega_c * sample_time:.3g} rad per sample at its "
            f"rigid-body crossover {omega_c:.4g} rad/s, so its sampled poles z = exp(s T) lie "
            f"within that of z = 1, where a float resolves s only to eps / T = "
            f"{np.finfo(float).eps / sample_time:.3g} 1/s; use sample_time >= "
            f"{MIN_CROSSOVER_ANGLE / omega_c:.4g} s (omega_c T >= {MIN_CROSSOVER_ANGLE:g}), or "
            "the continuous design")
    omega_s = 2.0 * math.pi / sample_time
    if omega_s < MIN_SAMPLES_PER_CROSSOVER * omega_c:
        raise ValueError(
            f"{what}: sample_time {sample_time:.4g} s is too long for the loop bandwidth: the "
            f"sampling frequency 2*pi/T = {omega_s:.4g} rad/s must be at least "
            f"{MIN_SAMPLES_PER_CROSSOVER:g} x the loop's rigid-body gain-crossover frequency "
            f"{omega_c:.4g} rad/s (the zero-order hold's lag omega T / 2 there would exceed "
            f"18 deg), i.e. sample_time <= "
            f"{2 * math.pi / (MIN_SAMPLES_PER_CROSSOVER * omega_c):.4g} s")


def check_sample_time(sample_time: float, plant, continuous_controller) -> float:
    """Validate a sample time against the continuous design loop's rigid-body crossover.

    Raises ValueError if 2 pi / sample_time < MIN_SAMPLES_PER_CROSSOVER * omega_c, with omega_c
    the gain crossover of the controller's loop on the plant's rigid-body part
    (:func:`rigid_crossover`): the loop's bandwidth, not a crossing of |L| = 1 at a flexible
    resonance. Whether the sampled loop is stable is a separate check on its poles (the exact
    zero-order-hold discretisation of plant and controller), made by :func:`pd` and
    :func:`controllers.lqr`.

    Returns
    -------
    float
        omega_c [rad/s].
    """
    sample_time = positive(sample_time, "sample_time", "s")
    omega_c = rigid_crossover(plant, continuous_controller)
    check_sampling(sample_time, omega_c, "sample time")
    for mode in _safe_modes(plant):
        # omega T = k pi, k >= 1, puts the pair exp(+-j omega T) on one point z = +-1: the
        # sampled plant loses that mode's controllability (pathological sampling; Kalman, Ho
        # and Narendra 1963), whatever the gains. sin(omega T) is computed to ~eps omega T, far
        # below the bound. omega T near 0 (k = 0) is fast sampling, not pathological: the pair
        # 1 +- j omega T stays apart (the precision of a fast rate is MIN_CROSSOVER_ANGLE's).
        if (mode.frequency * sample_time > math.pi / 2
                and abs(math.sin(mode.frequency * sample_time)) <= PATHOLOGICAL_SAMPLING):
            k = round(mode.frequency * sample_time / math.pi)
            raise ValueError(
                f"sample_time {sample_time:.6g} s samples the {mode.frequency:.6g} rad/s mode at "
                f"a multiple of half its period (omega T = {k} pi): pathological sampling, the "
                "sampled loop cannot control that mode; change sample_time by a few per cent")
    return omega_c


def _second_order(numerator: tuple[float, float, float], w: float, zeta: float):
    """(n2 s^2 + n1 s + n0) / (s^2 + 2 zeta w s + w^2) as a SISO StateSpace."""
    return control.ss(control.tf(list(numerator), [1.0, 2.0 * zeta * w, w * w]))


@limits_blas_threads(total_states)
def pd(plant: control.StateSpace, *, natural_frequency=None, bandwidth=None, damping=0.7,
       roll_off: float | None = None, notch: float | str | None = None,
       sample_time: float | None = None, axes: str = "principal",
       feedforward: bool = False) -> control.StateSpace:
    """PD attitude controller tuned on a free-floating design plant.

    The control law is torque = F(s) N(s) [Kp (theta_ref - theta) - Kd omega] with
    Kp = J wn^2, Kd = 2 zeta wn J, J the plant's total inertia from its rigid-body low-frequency
    gain (lim s^2 theta/torque = 1/J, :func:`controllers.rigid_body_inertia`); the
    rigid-body closed loop is then J s^2 + Kd s + Kp = 0, natural frequency wn and damping zeta.
    The rate is measured (omega), so no derivative filter is needed.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous design plant: input ``'torque'`` [N*m], outputs ``'theta'`` [rad],
        ``'omega'`` [rad/s]; free-floating (rigid-body double integrator).
    natural_frequency : float or sequence of 3 floats, rad/s, optional
        Closed-loop natural frequency wn (three-axis plant: one per axis, or one for all).
        Give exactly one of natural_frequency, bandwidth.
    bandwidth : float, rad/s, optional
        Closed-loop -3 dB bandwidth wb of the second-order prototype, converted with
        :func:`natural_frequency_from_bandwidth`.
    damping : float or sequence of 3 floats
        Closed-loop damping ratio zeta (default 0.7; three-axis: per axis or one for all).
    roll_off : float, rad/s, optional
        Corner wr of a second-order Butterworth low-pass F(s) = wr^2 / (s^2 + sqrt(2) wr s + wr^2)
        on the controller output (-40 dB/decade above wr, gain-stabilising the flexible modes).
        Must exceed 2 wn (it costs about 2 zeta_r wn / wr rad of phase at wn).
    notch : float (rad/s) or "first_mode", optional
        Notch N(s) = (s^2 + 2 zeta_z wz s + wz^2) / (s^2 + 2 zeta_p wz s + wz^2),
        zeta_z = NOTCH_ZERO_DAMPING, zeta_p = NOTCH_POLE_DAMPING, at wz = the given frequency, or
        with "first_mode" at the natural frequency of the plant's first flexible mode visible from
        torque to theta. Must exceed 2 wn.
    sample_time : float, s, optional
        Digital implementation: the continuous controller is discretised with a zero-order hold
        (``control.c2d(..., method="zoh")``) and returned with ``dt = sample_time``;
        :func:`controllers.close_loop` closes it on the ZOH-discretised plant (the
        sampled-data loop). The sampling frequency must be at least MIN_SAMPLES_PER_CROSSOVER
        times the continuous loop's rigid-body gain crossover (:func:`check_sample_time`), and
        the exact sampled loop on the design plant must meet the guarantee below (a flexible
        mode above the Nyquist frequency can alias into instability).

    axes : {"principal", "hub"}
        Three-axis plants: the axes of the per-axis specification (module docstring); ignored
        for a planar plant.
    feedforward : bool
        Also take a rate reference and a feedforward torque (a slew profile's omega_ref and
        torque_ff, :mod:`controllers.profiles`): torque = F N [Kp (theta_ref - theta) +
        Kd (omega_ref - omega)] + torque_ff, the feedforward added after the filters (they shape
        the feedback, not the command). With omega_ref = torque_ff = 0 the controller is the
        one without feedforward. Default False: the inputs of the law above.

    Returns
    -------
    control.StateSpace
        Inputs ``['theta_ref', 'theta', 'omega']``, output ``['torque']``; three-axis: inputs
        ``theta_ref_x, theta_ref_y, theta_ref_z, theta_x, ..., omega_z``, outputs
        ``torque_x, torque_y, torque_z`` (the filters act on each torque alike). With
        feedforward the inputs ``omega_ref`` [rad/s] and ``torque_ff`` [N*m] follow
        ``theta_ref`` (three axes: ``omega_ref_x..z``, ``torque_ff_x..z``). Continuous, or
        discrete with ``dt = sample_time``. The gains themselves are given by :func:`pd_gains`.

    Notes
    -----
    Guarantee: every pole of the loop on the design plant has Re(s) <= -alpha (s = log(z) / T
    for the sampled loop), alpha = MARGIN x the loop's spectral scale (its fastest pole or the
    plant's highest mode, whichever is larger; :mod:`controllers.stability`), except the modes
    the loop cannot move: undamped (Re >= -alpha) modes whose closed-loop pole stays within
    alpha of their open-loop eigenvalue, such as the symmetric bending of symmetric wings or
    the free-tip mode of a long chain. Those are announced by a
    :class:`~controllers.RemovedModesWarning` (frequency, damping, participation). A PD on
    collocated theta and omega damps every flexible mode by about zeta wn p, p the mode's
    participation (:class:`~controllers.FlexibleMode`); a filter's lag, a sampled loop or an
    extreme natural frequency may not, and the design is then refused with the mode and the
    parameter to change. The margin is numerical (450 eps relative): it makes the verdict
    independent of round-off, while the damping the loop adds is set by the specification.

    Raises
    ------
    ValueError
        Bad specification (names the parameter and unit), a plant without a rigid-body mode, a
        roll-off or notch too close to wn, a plant without flexible modes for "first_mode", a
        sample time too long for the bandwidth, a natural frequency whose gains leave float64,
        or a loop that misses the guarantee on the design plant (names the pole, its frequency
        and what to change).
    TypeError
        A parameter that is not a real number.

    References
    ----------
    Franklin, Powell & Emami-Naeini, Feedback Control of Dynamic Systems, 7th ed., ch. 4 (PD
    control) and ch. 10 (control of a satellite with a flexible appendage, notch filters);
    B. Wie, Space Vehicle Dynamics and Control, 2nd ed., AIAA 2008 (gain and phase stabilisation
    of flexible modes).
    """
    ch = check_plant(plant)
    if (natural_frequency is None) == (bandwidth is None):
        raise ValueError("give exactly one of natural_frequency [rad/s] or bandwidth [rad/s]; got "
                         f"natural_frequency={describe(natural_frequency)}, "
                         f"bandwidth={describe(bandwidth)}")
    if not isinstance(axes, str) or axes not in ("principal", "hub"):
        raise ValueError(f"axes must be 'principal' or 'hub'; got {describe(axes)}")
    damping = _per_axis(damping, "damping", "1", ch.n_axes)
    if natural_frequency is not None:
        spec = "natural_frequency"
        wn = _per_axis(natural_frequency, "natural_frequency", "rad/s", ch.n_axes)
    else:
        spec = "bandwidth"
        wb = _per_axis(bandwidth, "bandwidth", "rad/s", ch.n_axes)
        wn = np.array([natural_frequency_from_bandwidth(b, z) for b, z in zip(wb, damping)])
    given = natural_frequency if bandwidth is None else bandwidth
    spec_text = (f"{spec} = {float(given):.4g} rad/s" if np.ndim(given) == 0 else
                 f"{spec} = {describe(np.asarray(given, dtype=float))} rad/s")
    J = rigid_body_inertia(plant)
    with np.errstate(over="ignore", under="ignore"):
        if ch.mimo:
            Kp, Kd = _gains(J, wn, damping, axes)
        else:
            Kp, Kd = _gains(J, wn[0], damping[0], axes)
    if not (np.all(np.isfinite(Kp)) and np.all(np.isfinite(Kd))
            and np.all(np.diag(np.atleast_2d(Kp)) > 0) and np.all(np.diag(np.atleast_2d(Kd)) > 0)):
        J_text = f"{J:.4g}" if not ch.mimo else describe(np.round(J, 6))
        damping_text = describe(damping if ch.mimo else damping[0])
        raise ValueError(f"pd: {spec_text} with damping {damping_text}"
                         f" and the plant's inertia J = {J_text} kg*m^2 gives gains "
                         f"Kp = J wn^2 = {describe(Kp)} N*m/rad, Kd = 2 zeta wn J = "
                         f"{describe(Kd)} N*m*s/rad outside the floating-point range; choose "
                         f"a {spec} within a few decades of the plant's modes")
    if not isinstance(feedforward, (bool, np.bool_)):
        raise TypeError(f"feedforward must be True or False; got {describe(feedforward)}")
    # the feedback law on [theta_ref (, omega_ref), theta, omega]; torque_ff joins after the
    # filters (below)
    blocks = [Kp] + ([Kd] if feedforward else []) + [-Kp, -Kd]
    if ch.mimo:
        gains = np.hstack(blocks)
    else:
        gains = [blocks]
    controller = control.ss([], [], [], gains)
    wn_max = float(np.max(wn))
    filters = []
    if notch is not None:
        if isinstance(notch, str):
            if notch != "first_mode":
                raise ValueError(f"notch must be a frequency [rad/s] or 'first_mode'; got "
                                 f"{describe(notch)}")
            modes = flexible_modes(plant)
            if not modes:
                raise ValueError("notch='first_mode' but the plant has no flexible mode visible "
                                 "from torque to theta")
            wz = modes[0].frequency
        else:
            wz = _filter_frequency(notch, "notch")
        if wz <= 2.0 * wn_max:
            raise ValueError(f"notch frequency must exceed 2 x natural frequency = "
                             f"{2 * wn_max:.4g} rad/s (it would cut into the rigid-body loop); "
                             f"got {wz:.4g} rad/s")
        controller = _per_output(_second_order((1.0, 2.0 * NOTCH_ZERO_DAMPING * wz, wz * wz), wz,
                                               NOTCH_POLE_DAMPING), ch.n_axes) * controller
        filters.append(f"notch = {wz:.4g} rad/s")
    if roll_off is not None:
        wr = _filter_frequency(roll_off, "roll_off")
        if wr <= 2.0 * wn_max:
            raise ValueError(f"roll_off corner must exceed 2 x natural frequency = "
                             f"{2 * wn_max:.4g} rad/s; got {wr:.4g} rad/s")
        controller = _per_output(_second_order((0.0, 0.0, wr * wr), wr, ROLL_OFF_DAMPING),
                                 ch.n_axes) * controller
        filters.append(f"roll_off = {wr:.4g} rad/s")
    refs = ch.refs + (ch.omega_refs + ch.feedforwards if feedforward else ())
    signals = dict(inputs=list(refs + ch.thetas + ch.omegas), outputs=list(ch.torques),
                   name="pd")
    A, B, C, D = (np.asarray(M, dtype=float).reshape(shape) for M, shape in zip(
        (controller.A, controller.B, controller.C, controller.D),
        ((controller.nstates,) * 2, (controller.nstates, controller.ninputs),
         (ch.n_axes, controller.nstates), (ch.n_axes, controller.ninputs))))
    if feedforward:
        # torque_ff straight to the torque: zero columns of B, identity columns of D
        k = 2 * ch.n_axes  # after theta_ref and omega_ref
        B = np.hstack([B[:, :k], np.zeros((B.shape[0], ch.n_axes)), B[:, k:]])
        D = np.hstack([D[:, :k], np.eye(ch.n_axes), D[:, k:]])
    controller = control.ss(A, B, C, D, 0, **signals)
    T = None
    if sample_time is not None:
        T = positive(real_number(sample_time, "sample_time", "s"), "sample_time", "s")
        check_sample_time(T, plant, controller)
        digital = control.c2d(controller, T, method="zoh")
        controller = control.ss(digital.A, digital.B, digital.C, digital.D, T, **signals)
    rigid_poles = np.concatenate([np.roots([1.0, 2.0 * z * w, w * w])
                                  for w, z in zip(wn, damping)]).astype(complex)
    damping_text = describe(damping) if ch.mimo else f"{damping[0]:.4g}"

    def advise(pole: complex, alpha: float, scale: float) -> str:
        w = abs(pole)
        if not math.isfinite(w):
            return f"choose a {spec} within a few decades of the plant's modes; got {spec_text}"
        if w == 0.0:  # the loop's scale cannot resolve the plant's modes
            return f"lower {spec} toward the plant's modes; got {spec_text}"
        rigid = np.min(np.abs(rigid_poles - pole) / np.abs(rigid_poles)) <= 0.5
        if rigid and pole.real > 0 and (filters or T is not None):
            lag = f"the filter ({', '.join(filters)})" if filters else "the zero-order hold"
            return (f"the phase lag of {lag} destabilises the rigid-body loop ({spec_text}, "
                    f"damping {damping_text}): raise damping, or move the filter up / shorten "
                    "sample_time")
        if rigid:
            return (f"{spec_text} with damping {damping_text} puts the rigid-body poles inside "
                    f"the margin: raise {spec} or damping (the margin scales with the loop's "
                    f"fastest pole or mode, {scale:.4g} rad/s)")
        if T is not None:
            above = sorted(m.frequency for m in _safe_modes(plant) if m.frequency > math.pi / T)
            alias = (f" (the plant's modes above the Nyquist frequency, "
                     f"{', '.join(f'{f:.4g}' for f in above[:3])}"
                     f"{' ...' if len(above) > 3 else ''} rad/s, alias into the loop's band)"
                     if above else "")
            return (f"the sampled loop at sample_time = {T:.4g} s (Nyquist frequency "
                    f"pi/T = {math.pi / T:.4g} rad/s) does not damp this mode{alias}: shorten "
                    "sample_time, or roll it off / notch it")
        if filters:
            return (f"the phase lag of the filter ({', '.join(filters)}) at {w:.4g} rad/s does "
                    "not let the loop damp this mode: move the filter, or give the mode damping")
        return (f"{spec_text} with damping {damping_text} is too high for this plant: the loop "
                "cannot damp this pole (a flexible mode pushed toward a zero of theta/torque, or "
                f"round-off of a loop {scale / max(w, 1e-300):.1e} times faster than it); "
                f"lower {spec}")

    _, excused = verify_loop(plant, controller, J=J, what="pd", advise=advise,
                             scale_floor=wn_max)
    warn_removed_modes("pd", excused, "(the loop moves them by less than the stability margin; "
                       "they keep their open-loop eigenvalues)")
    return controller


#: Largest filter frequency [rad/s]: its square, a coefficient of the filter, stays finite.
MAX_FILTER_FREQUENCY = 1e150


def _filter_frequency(value, name: str) -> float:
    w = positive(real_number(value, name, "rad/s"), name, "rad/s")
    if w > MAX_FILTER_FREQUENCY:
        raise ValueError(f"{name} must be at most {MAX_FILTER_FREQUENCY:g} [rad/s] (its square "
                         f"is a coefficient of the filter); got {w:.6g}")
    return w


def _per_axis(value, name: str, unit: str, n_axes: int) -> np.ndarray:
    """A positive specification per axis: a real number (every axis) or, for three axes, a
    sequence of 3 positive finite numbers [unit]."""
    if n_axes > 1 and isinstance(value, (list, tuple, np.ndarray)):
        array = real_array(value, name, unit)
        if array.shape != (n_axes,):
            raise ValueError(f"{name} must be a real number or {n_axes} of them (one per axis) "
                             f"[{unit}]; got {describe(value)}")
        return np.array([positive(float(x), f"{name}[{i}]", unit)
                         for i, x in enumerate(array)])
    return np.full(n_axes, positive(value, name, unit))


def _per_output(siso: control.StateSpace, n: int) -> control.StateSpace:
    """The SISO filter on each of n outputs (block diagonal)."""
    return siso if n == 1 else control.append(*([siso] * n))


def _safe_modes(plant):
    """flexible_modes of the plant, or none if they cannot be listed."""
    try:
        return flexible_modes(plant)
    except ValueError:
        return []
