r"""Pointing error statistics of a closed loop with sensor noise, by exact covariance analysis.

The loop (:func:`close_loop_with_sensors`) is the attitude loop with its measurements corrupted
at the controller's inputs: the controller reads ``theta_measured = theta + theta_noise`` and
``omega_measured = omega + omega_noise`` (three axes: ``theta_noise_x``, ...). The noise is
:class:`.SensorNoise`: white angle noise, white rate noise and a Gauss-Markov gyro bias (a shaping
state per axis appended to the loop). With the reference at rest, the loop's state is a
stationary zero-mean Gaussian process; its covariance P solves

    A P + P A^T + B W B^T = 0                  (continuous loop),
    P = Phi P Phi^T + B_d W_d B_d^T            (digital controller: the sampled loop at its
                                                samples, each noise discretised over the sample,
                                                :mod:`.noise`),

and the pointing errors are outputs e = C x (the true attitude, theta_ref = 0; tip deflections
for the jitter), with no direct feedthrough of white noise (checked).

Definitions (ECSS-E-ST-60-10C, sec. 3.2 [1]_): the absolute performance error APE(t) = e(t);
the mean performance error over a window of length Delta, MPE = (1/Delta) int e over the window;
the relative performance error RPE(t) = e(t) - MPE of a window containing t. Statistical
interpretation (ECSS-E-ST-60-10C annex A.1): a stationary, ergodic, zero-mean Gaussian process,
for which the temporal, ensemble and mixed interpretations coincide; every figure is a standard
deviation (1 sigma) per axis; :meth:`PointingBudget.at` scales them to a probability level
(two-sided Gaussian: 99.73 % -> 3 sigma). The standard leaves where t lies in its window open
(its note 2 to RPE); ``placement="random"`` takes t uniformly within the window (the "windowed
variance" of [2]_, whose spectral weighting is 1 - sinc^2(omega Delta / 2), ECSS-E-HB-60-10A
[3]_), ``placement="end"`` at the window's end (a causal mean).

Derivation (continuous). With R(tau) = E[e(t + tau) e(t)] = C e^(A tau) P C^T (tau >= 0), the
window mean's variance is

    MPE^2 = Var(e_bar) = (1 / Delta^2) int int R(t1 - t2) = (2 / Delta^2) C I2 P C^T,
    I2 = int_0^Delta (Delta - tau) e^(A tau) dtau,

(the symmetric part is meant throughout). For t uniform in the window, averaging
Var(e(t) - e_bar) = R(0) - 2 Cov(e(t), e_bar) + Var(e_bar) over t gives R(0) - Var(e_bar):

    RPE_random^2 = (2 / Delta^2) C [int_0^Delta (Delta - tau)(I - e^(A tau)) dtau] P C^T
                 = -(2 / Delta^2) C A J3 P C^T,       J3 = int_0^Delta (Delta - tau)^2 / 2 e^(A tau),

(integrating by parts: int (Delta - tau)(e^(A tau) - I) = A J3), a form without the
cancellation of R(0) - Var(e_bar) for short windows. For t at the window's end,
Cov(e(t), e_bar) = (1 / Delta) C I1 P C^T, I1 = int_0^Delta e^(A tau), and

    RPE_end^2 = (2 / Delta) C [int_0^Delta (I - e^(A tau))] P C^T - RPE_random^2
              = -(2 / Delta) C A I2 P C^T - RPE_random^2.

I2 and J3 are blocks of one matrix exponential, e^(M Delta) with M = [[A, I, 0, 0], [0, 0, I,
0], [0, 0, 0, I], [0, 0, 0, 0]]: blocks (1, 3) and (1, 4) [4]_ (computed in time scaled by
Delta, accurate for any window).

Continuous controller with a loop delay (the frequency domain). The delayed continuous loop is
infinite-dimensional: no Lyapunov equation. Its statistics are the same integrals over the
spectrum, exact in the delay: with the loop broken at the torques, the plant P (measured rows
P_m, error rows P_e), the controller K from its measurements and the delay D = e^(-j omega tau),
the torque is u = D K (P_m u + n), so the errors are e = H n with

    H(j omega) = P_e (I - D K P_m)^-1 D K,

and per error output, with S(omega) the noise's two-sided spectral density per measurement
(q^2 for the angle noise; N^2 + (2 sigma_b^2 / tau_b) / (omega^2 + 1 / tau_b^2) for the rate
noise and the Gauss-Markov bias),

    Var = (1 / pi) int_0^inf sum_j |H_ij(j omega)|^2 S_j(omega) W(omega) d omega,

W = 1 (APE), sinc^2(omega Delta / 2) (the window mean's, MPE), 1 - sinc^2(omega Delta / 2) (RPE,
t uniform in its window) and |1 - (1 - e^(-j omega Delta)) / (j omega Delta)|^2 (RPE, t at its
window's end): the weighting functions of ECSS-E-HB-60-10A [3]_ (the Lyapunov forms above are
these integrals in closed form). The weights are computed without cancellation for small
omega Delta. The integral is taken on ln(omega) by adaptive Gauss-Kronrod (7-15) panels,
graded around every resonance the loop may have (the poles of the plant, of the controller and
of the loop without delay, and the peaks of a 200-per-decade scan), to a relative error of
1e-9 per figure: the panels' error estimates are summed and the panels carrying the excess
bisected until the sum is within it, which refines a resonance of any damping where it lies
(a figure that does not reach it raises :class:`PointingNotComputed`, never a number). The
delayed loop's stability is the Nyquist count on the quadrature's own frequencies (they
resolve each resonance), or where that is not conclusive the exact count of
:func:`.spillover`. From 0 to 1e-4 x and beyond 1e4 x the loop's characteristic frequencies by a
Gauss-Legendre rule in omega and in 1 / omega (the integrand is flat below, and falls at least
as omega^-2 above, or the output would be fed by white noise, refused as for the Lyapunov
form). Without delay the two forms agree to 1e-9 (tested); the delay's figures are checked
against Pade approximants of rising order.

Derivation (sampled, step T, window of N samples, mean e_bar = (1/N) sum of its samples,
R(m) = C Phi^m P C^T): Var(e_bar) = (1 / N^2) [2 C S2 P C^T - N R(0)],
RPE_random^2 = (2 / N^2) C (I - Phi) S3 P C^T and
RPE_end^2 = (2 / N) C (I - Phi) S2' P C^T - RPE_random^2, with S2 = sum_(j<N) (N - j) Phi^j,
S2' = sum_(j<N-1) (N - 1 - j) Phi^j, S3 = sum_(j<N-1) (N - 1 - j)(N - j) / 2 Phi^j: blocks
(1, 3) and (1, 4) of powers N and N + 1 of [[Phi, I, 0, 0], [0, I, I, 0], [0, 0, I, I],
[0, 0, 0, I]] (by repeated squaring). The statistics of a sampled loop are those at its
samples.

References
----------
.. [1] ECSS-E-ST-60-10C, *Space engineering: Control performance*, ESA-ESTEC, 15 November 2008,
   sec. 3.2 (APE, MPE, RPE) and annex A (statistical interpretation).
.. [2] M. E. Pittelkau, "Pointing error definitions, metrics, and algorithms", AAS 03-559,
   2003; R. L. Lucke, S. W. Sirlin, A. M. San Martin, "New definitions of pointing stability:
   AC and DC effects", J. Astronautical Sciences 40(4), 557-576, 1992 (windowed variance).
.. [3] ECSS-E-HB-60-10A, *Space engineering: Control performance guidelines*, ESA-ESTEC, 14
   December 2010 (weighting functions of the error indices).
.. [4] C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE Trans.
   Automatic Control 23(3), 395-404, 1978.
"""
from __future__ import annotations

import dataclasses
import math
from statistics import NormalDist

import control
import numpy as np
import scipy.linalg

from .arguments import describe, positive, real_number
from .delay import check_delay, total_delay, warns_long_delay
from .frequency import modal_evaluator
from .loop import close_loop
from .margins import loop_nyquist_count, spillover, unstable_poles
from .noise import SensorNoise
from .signals import OMEGA, THETA, channels, tip_outputs
from .threads import one_blas_thread

__all__ = ["close_loop_with_sensors", "noise_input_names", "pointing", "PointingBudget",
           "PointingNotComputed", "PLACEMENTS", "NOISE", "MEASURED"]

#: Where t lies in its RPE window (module docstring).
PLACEMENTS = ("random", "end")
#: Infix of the noise inputs (``theta_noise``, ``omega_noise_x``...) and of the measured
#: signals (``theta_measured``...).
NOISE, MEASURED = "_noise", "_measured"


class PointingNotComputed(ValueError):
    """A stable loop whose pointing figures could not be computed to their accuracy (the
    message says why); raised instead of a figure that may be wrong."""


def noise_input_names(ch) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """(attitude noise inputs, rate noise inputs) of a loop of convention ``ch``: ``theta_noise``
    and ``omega_noise`` (planar), ``theta_noise_x``, ... (three axes)."""
    return (tuple(f"{THETA}{NOISE}{ch.suffix(i)}" for i in range(ch.n_axes)),
            tuple(f"{OMEGA}{NOISE}{ch.suffix(i)}" for i in range(ch.n_axes)))


@warns_long_delay
def close_loop_with_sensors(plant: control.StateSpace, controller: control.StateSpace, *,
                            delay: float = 0.0, computation_delay: bool = False,
                            dt: float | None = None) -> control.StateSpace:
    """The attitude loop with noise inputs at the controller's measurements.

    Parameters
    ----------
    plant : control.StateSpace
        As for :func:`.close_loop` (continuous, named signals).
    controller : control.StateSpace
        Continuous or digital, with the measurement inputs ``theta``, ``omega`` (three axes:
        ``theta_x``...).
    delay, computation_delay, dt
        A loop delay, as for :func:`.close_loop`.

    Returns
    -------
    control.StateSpace
        :func:`.close_loop` of the plant with the extra outputs ``theta_measured`` =
        theta + theta_noise and ``omega_measured`` = omega + omega_noise [rad, rad/s] (three
        axes: ``theta_measured_x``...) and the controller reading them. Inputs: the loop's
        (references, disturbances), then ``theta_noise``, ``omega_noise`` (three axes:
        ``theta_noise_x``, ..., ``omega_noise_z``) for the measurements the controller uses.
        Outputs: the plant's (the true attitude), the measured signals, the torque(s).
    """
    if not isinstance(plant, control.StateSpace):
        raise TypeError(f"plant must be a control.StateSpace; got {type(plant).__name__}")
    if not isinstance(controller, control.StateSpace):
        raise TypeError(f"controller must be a control.StateSpace; got "
                        f"{type(controller).__name__}")
    ch = channels(plant)
    thetas, omegas = noise_input_names(ch)
    inputs, outputs = list(plant.input_labels), list(plant.output_labels)
    c_in = list(controller.input_labels)
    measured = [m for m in ch.measurements if m in c_in]
    if not measured:
        raise ValueError(f"controller must read the attitude or rate measurements "
                         f"{list(ch.measurements)}; got inputs {describe(c_in)}")
    noise_names = {m: (thetas + omegas)[list(ch.measurements).index(m)] for m in measured}
    reserved = [n for n in list(noise_names.values()) + [_measured(m) for m in measured]
                if n in inputs or n in outputs]
    if reserved:
        raise ValueError(f"plant must not have signals named {reserved} (reserved for the "
                         "sensor noise and the measured signals)")
    A, B, C, D = (np.asarray(M, dtype=float) for M in (plant.A, plant.B, plant.C, plant.D))
    rows = [outputs.index(m) for m in measured]
    k = len(measured)
    B_aug = np.hstack([B, np.zeros((A.shape[0], k))])
    C_aug = np.vstack([C, C[rows]])
    D_aug = np.block([[D, np.zeros((D.shape[0], k))], [D[rows], np.eye(k)]])
    noisy = control.ss(A, B_aug, C_aug, D_aug, plant.dt,
                       inputs=inputs + [noise_names[m] for m in measured],
                       outputs=outputs + [_measured(m) for m in measured],
                       states=list(plant.state_labels), name=plant.name)
    reader = control.ss(controller.A, controller.B, controller.C, controller.D, controller.dt,
                         inputs=[_measured(n) if n in measured else n for n in c_in],
                         outputs=list(controller.output_labels),
                         states=list(controller.state_labels), name=controller.name)
    return close_loop(noisy, reader, delay=delay, computation_delay=computation_delay, dt=dt)


def _measured(name: str) -> str:
    """theta -> theta_measured, theta_x -> theta_measured_x."""
    for base in (THETA, OMEGA):
        if name == base:
            return base + MEASURED
        if name.startswith(base + "_"):
            return base + MEASURED + name[len(base):]
    raise ValueError(f"not a measurement: {name!r}")


@dataclasses.dataclass(frozen=True)
class PointingBudget:
    """Stationary pointing statistics of a loop with sensor noise (1 sigma, per output).

    Attributes
    ----------
    ape, mpe, rpe : dict of str to float, rad
        Per attitude output (``theta`` or ``theta_x``..``theta_z``): the standard deviations
        of the absolute performance error, of the window mean (the MPE's) and of the relative
        performance error over ``window`` (module docstring).
    jitter, jitter_mpe, jitter_rpe : dict of str to float, m
        The same for each tip output (``*tip_deflection``...).
    window : float, s
    placement : str
        "random" or "end" (where t lies in its RPE window).
    sampled : bool
        True for a digital controller: statistics at the samples.
    covariance : numpy.ndarray
        The stationary state covariance P (the loop's states, then the gyro biases'); NaN for
        a continuous controller with a delay (its loop has no finite state: the figures come
        from the spectral integrals).
    state_labels : list of str
    """

    ape: dict
    mpe: dict
    rpe: dict
    jitter: dict
    jitter_mpe: dict
    jitter_rpe: dict
    window: float
    placement: str
    sampled: bool
    covariance: np.ndarray
    state_labels: list

    def at(self, probability: float) -> dict:
        """The figures at a probability level: each standard deviation times the two-sided
        Gaussian quantile k with P(|e| <= k sigma) = probability (0.9973 -> 3.0).

        Returns
        -------
        dict
            ``{"ape": {...}, "mpe": ..., "rpe": ..., "jitter": ..., "jitter_mpe": ...,
            "jitter_rpe": ...}`` in rad and m, and ``"factor"``, k.
        """
        p = real_number(probability, "probability", "1")
        if not 0.0 < p < 1.0:
            raise ValueError(f"probability must lie in (0, 1); got {describe(probability)}")
        k = NormalDist().inv_cdf(0.5 + 0.5 * p)
        out = {name: {key: k * value for key, value in getattr(self, name).items()}
               for name in ("ape", "mpe", "rpe", "jitter", "jitter_mpe", "jitter_rpe")}
        out["factor"] = k
        return out


@warns_long_delay
def pointing(plant: control.StateSpace, controller: control.StateSpace, noise: SensorNoise,
             *, window: float, placement: str = "random", outputs=None, delay: float = 0.0,
             computation_delay: bool = False) -> PointingBudget:
    """Pointing error statistics of the loop under sensor noise (module docstring).

    Parameters
    ----------
    plant, controller : control.StateSpace
        As for :func:`close_loop_with_sensors`.
    noise : SensorNoise
        One level per axis or three (three-axis loops).
    window : float, s
        The RPE and MPE window Delta; for a digital controller a whole number of samples.
    placement : {"random", "end"}
        Where t lies in its window.
    outputs : sequence of str, optional
        Tip outputs for the jitter (default: every ``*tip_deflection`` and tip output of the
        plant).
    delay : float, s
        A loop delay (:func:`.close_loop`): a digital controller's delayed loop is exact in its
        samples (Lyapunov); a continuous controller's, infinite-dimensional, by the spectral
        integrals of the module docstring (exact in the delay, quadrature to 1e-9).
    computation_delay : bool
        One sample of a digital controller added to the delay.

    Returns
    -------
    PointingBudget

    Raises
    ------
    TypeError
        ``noise`` not a SensorNoise; bad plant or controller.
    ValueError
        A loop that is not asymptotically stable (no stationary error), an output fed directly
        by white noise (infinite variance in continuous time), a window that is not positive
        (or not a whole number of samples), unknown placement or outputs.
    """
    if not isinstance(noise, SensorNoise):
        raise TypeError(f"noise must be a controllers.SensorNoise; got {type(noise).__name__}")
    if not isinstance(placement, str) or placement not in PLACEMENTS:
        raise ValueError(f"placement must be one of {PLACEMENTS}; got {describe(placement)}")
    window = positive(window, "window", "s")
    spectral = (isinstance(controller, control.StateSpace)
                and not controller.isdtime(strict=True)
                and not (isinstance(delay, (int, float)) and not isinstance(delay, bool)
                         and delay == 0))
    if spectral:
        delay = check_delay(delay)
        if computation_delay is not False:
            total_delay(controller, delay, computation_delay)   # refused for a continuous one
    # the loop without its delay for a continuous controller (its checks, its resonances)
    loop = close_loop_with_sensors(plant, controller, delay=0.0 if spectral else delay,
                                   computation_delay=computation_delay)
    ch = channels(plant)
    levels = noise.per_axis(ch.n_axes)
    sampled = loop.isdtime(strict=True)
    T = float(loop.dt) if sampled else None
    if sampled:
        n_window = window / T
        if abs(n_window - round(n_window)) > 1e-9 * n_window or round(n_window) < 1:
            raise ValueError(f"window must be a whole number of the digital loop's samples "
                             f"(T = {T:.6g} s) [s]; got {window:.6g} s ({n_window:.6g} samples)")
    plant_outputs = list(plant.output_labels)
    if outputs is None:
        tips = tip_outputs(plant_outputs)
    else:
        if isinstance(outputs, str) or not isinstance(outputs, (list, tuple)) or not all(
                isinstance(n, str) for n in outputs):
            raise TypeError(f"outputs must be a list of plant output names (tip deflections); "
                            f"got {describe(outputs)}")
        tips = list(outputs)
        unknown = [n for n in tips if n not in plant_outputs]
        if unknown:
            raise ValueError(f"outputs must be plant outputs; got {unknown} (the plant has "
                             f"{describe(plant_outputs)})")
    A, Bw, W, C, labels, state_labels = _noise_model(loop, ch, levels, T)
    names = list(ch.thetas) + tips
    rows = [labels.index(n) for n in names]
    C = C[rows]
    with one_blas_thread():
        if spectral:
            sigma2, mpe2, rpe2 = _spectral_statistics(plant, controller, ch, levels, names,
                                                      window, placement, delay, A)
            P = np.full((A.shape[0], A.shape[0]), np.nan)
        else:
            P = _stationary_covariance(A, Bw, W, sampled)
            sigma2, mpe2, rpe2 = _window_statistics(A, C, P, window, T, placement)
    values = {name: tuple(math.sqrt(max(v, 0.0)) for v in (s, m, r))
              for name, s, m, r in zip(names, sigma2, mpe2, rpe2)}
    attitude, jitter = list(ch.thetas), tips
    return PointingBudget(
        ape={n: values[n][0] for n in attitude}, mpe={n: values[n][1] for n in attitude},
        rpe={n: values[n][2] for n in attitude}, jitter={n: values[n][0] for n in jitter},
        jitter_mpe={n: values[n][1] for n in jitter},
        jitter_rpe={n: values[n][2] for n in jitter}, window=window, placement=placement,
        sampled=sampled, covariance=P, state_labels=state_labels)


def _noise_model(loop, ch, levels, T):
    """The loop with the gyro biases as states, driven by white noise: (A, B_w, W, C, output
    labels, state labels) with W the intensities (continuous) or the per-sample covariances
    (sampled loop, T the step) of the noises (module docstring of :mod:`.noise`)."""
    A, B, C, D = (np.asarray(M, dtype=float) for M in (loop.A, loop.B, loop.C, loop.D))
    inputs = list(loop.input_labels)
    thetas, omegas = noise_input_names(ch)
    n = A.shape[0]
    columns, intensities, biases = [], [], []
    for i, level in enumerate(levels):
        for name, key in ((thetas[i], "attitude_density"), (omegas[i], "angle_random_walk")):
            q = level[key]
            if q > 0 and name in inputs:
                columns.append(("input", inputs.index(name)))
                intensities.append(q * q / T if T else q * q)
        sigma, tau = level["bias_instability"], level["bias_correlation_time"]
        if sigma > 0 and omegas[i] in inputs:
            biases.append((inputs.index(omegas[i]), sigma, tau))
    nb = len(biases)
    A_aug = np.zeros((n + nb, n + nb))
    A_aug[:n, :n] = A
    for j, (col, sigma, tau) in enumerate(biases):
        A_aug[:n, n + j] = B[:, col]              # the bias adds to the rate measurement
        if T:
            phi = math.exp(-T / tau)
            A_aug[n + j, n + j] = phi
            columns.append(("bias", j))
            intensities.append(sigma * sigma * -math.expm1(-2.0 * T / tau))
        else:
            A_aug[n + j, n + j] = -1.0 / tau
            columns.append(("bias", j))
            intensities.append(2.0 * sigma * sigma / tau)
    Bw = np.zeros((n + nb, len(columns)))
    Dw = np.zeros((C.shape[0], len(columns)))
    for k, (kind, index) in enumerate(columns):
        if kind == "input":
            Bw[:n, k] = B[:, index]
            Dw[:, k] = D[:, index]
        else:
            Bw[n + index, k] = 1.0
    C_aug = np.hstack([C, D[:, [b[0] for b in biases]]]) if nb else C
    labels = list(loop.output_labels)
    fed = [labels[r] for r in range(C.shape[0]) if np.any(Dw[r] != 0.0)]
    wanted = set(ch.thetas) | set(tip_outputs(labels))
    direct = [name for name in fed if name in wanted]
    if direct:
        raise ValueError(f"outputs {direct} are fed directly by white sensor noise (a "
                         "feedthrough from torque in the plant): their variance is not "
                         "defined by this model")
    states = list(loop.state_labels) + [f"gyro_bias{ch.suffix(i)}"
                                        for i, level in enumerate(levels)
                                        if level["bias_instability"] > 0]
    return A_aug, Bw, np.array(intensities), C_aug, labels, states


def _stationary_covariance(A, Bw, W, sampled: bool) -> np.ndarray:
    """P of the Lyapunov equation (module docstring), after checking asymptotic stability."""
    lam = np.linalg.eigvals(A) if A.size else np.zeros(0)
    if sampled:
        worst = float(np.max(np.abs(lam), initial=0.0))
        if not worst < 1.0:
            raise ValueError(f"the sampled closed loop must be asymptotically stable for a "
                             f"stationary pointing error; its largest |eigenvalue| is "
                             f"{worst:.6g} >= 1")
    else:
        worst = float(np.max(lam.real, initial=-math.inf))
        if not worst < 0.0:
            raise ValueError(f"the closed loop must be asymptotically stable for a stationary "
                             f"pointing error; its rightmost eigenvalue has real part "
                             f"{worst:.6g} >= 0 [1/s]")
    Q = (Bw * W) @ Bw.T
    solve = ((lambda R: scipy.linalg.solve_discrete_lyapunov(A, R)) if sampled else
             (lambda R: scipy.linalg.solve_continuous_lyapunov(A, -R)))
    P = solve(Q)
    P = 0.5 * (P + P.T)
    # one step of iterative refinement: the error of P solves the same equation with the
    # residual in place of Q. A lightly damped loop's solution loses digits to the equation's
    # conditioning (an output of small variance beside large states: its C P C^T may come out
    # of the wrong sign); the residual, formed in working precision, carries that error
    R = (A @ P @ A.T + Q - P) if sampled else (A @ P + P @ A.T + Q)
    dP = solve(0.5 * (R + R.T))
    return P + 0.5 * (dP + dP.T)


def _window_statistics(A, C, P, window, T, placement):
    """Variances of e, of its window mean and of the RPE (module docstring), per output."""
    n = A.shape[0]
    CP = C @ P

    def sym_diag(M):                     # diag of C M P C^T, symmetric part: rows of M
        return np.einsum("ij,ij->i", C @ M, CP)

    sigma2 = np.einsum("ij,ij->i", CP, C)
    I = np.eye(n)
    if T is None:
        # in the time scaled by Delta (s = tau / Delta): e^M with M = [[A Delta, I, 0, 0], ...]
        # has the blocks I2 / Delta^2 and J3 / Delta^3; with A Delta the only large block it is
        # accurate to round-off for any Delta (unscaled, the identity blocks times Delta lose
        # (Delta |A|)^2 eps: 3e-4 at Delta |A| = 1e4)
        M = np.zeros((4 * n, 4 * n))
        M[:n, :n] = A * window
        M[:n, n:2 * n] = M[n:2 * n, 2 * n:3 * n] = M[2 * n:3 * n, 3 * n:] = I
        E = scipy.linalg.expm(M)
        I2_scaled, J3_scaled = E[:n, 2 * n:3 * n], E[:n, 3 * n:]
        mpe2 = 2.0 * sym_diag(I2_scaled)                        # (2 / Delta^2) C I2 P C^T
        rpe2 = -2.0 * window * sym_diag(A @ J3_scaled)          # -(2 / Delta^2) C A J3 P C^T
        if placement == "end":
            rpe2 = -2.0 * window * sym_diag(A @ I2_scaled) - rpe2   # -(2/Delta) C A I2 P C^T
        return sigma2, mpe2, rpe2
    N = int(round(window / T))
    M = np.zeros((4 * n, 4 * n))
    M[:n, :n] = A
    M[:n, n:2 * n] = I
    for b in (1, 2):
        M[b * n:(b + 1) * n, b * n:(b + 1) * n] = I
        M[b * n:(b + 1) * n, (b + 1) * n:(b + 2) * n] = I
    M[3 * n:, 3 * n:] = I
    MN = np.linalg.matrix_power(M, N)
    MN1 = MN @ M
    S2, S2p, S3 = MN1[:n, 2 * n:3 * n], MN[:n, 2 * n:3 * n], MN1[:n, 3 * n:]
    mpe2 = (2.0 * sym_diag(S2) - N * sigma2) / N ** 2
    rpe2 = 2.0 / N ** 2 * sym_diag((I - A) @ S3)
    if placement == "end":
        rpe2 = 2.0 / N * sym_diag((I - A) @ S2p) - rpe2
    return sigma2, mpe2, rpe2


# --------------------------------------------------------------------------------------------
# a continuous controller with a delay: the spectral integrals (module docstring)
# --------------------------------------------------------------------------------------------
# Gauss-Kronrod 7-15 (QUADPACK's qk15): the Kronrod abscissae (the Gauss ones at odd indices
# 1, 3, 5 and the centre) and weights on [-1, 1], half of them (symmetric)
_XK = np.array([0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                0.207784955007898467600689403773245, 0.0])
_WK = np.array([0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                0.204432940075298892414161999234649, 0.209482141084727828012999174891714])
_WG = np.array([0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                0.381830050505118944950369775488975, 0.417959183673469387755102040816327])
_NODES = np.concatenate([-_XK[:-1], _XK[::-1]])                      # 15 abscissae, ascending
_KRONROD = np.concatenate([_WK[:-1], _WK[::-1]])
_GAUSS = np.zeros(15)
_GAUSS[[1, 3, 5, 7, 9, 11, 13]] = np.concatenate([_WG[:-1], _WG[::-1]])
#: Relative accuracy of each spectral figure; most panels and refinement rounds.
_SPECTRAL_RTOL, _MAX_PANELS, _MAX_ROUNDS = 1e-9, 100_000, 200
#: The loop's band: from 1e-4 x its slowest to 1e4 x its fastest characteristic frequency.
_BAND = 1e4


def _one_minus_sinc2(x: np.ndarray) -> np.ndarray:
    """1 - (sin x / x)^2 without cancellation (its series below |x| = 0.1: error < 1e-17)."""
    x = np.abs(x)
    out = np.empty_like(x)
    small = x < 0.1
    y = x[small] ** 2
    # 1 - sinc^2 = 2 y / 6 - 2 y^2 / 45 + y^3 / 315 - 2 y^4 / 14175 (y = x^2)
    out[small] = y * (1.0 / 3.0 - y * (2.0 / 45.0 - y * (1.0 / 315.0 - y * 2.0 / 14175.0)))
    big = x[~small]
    out[~small] = 1.0 - (np.sin(big) / big) ** 2
    return out


def _end_weight(x: np.ndarray) -> np.ndarray:
    """|1 - (1 - e^(-j x)) / (j x)|^2 = |e^(-j x) - 1 + j x|^2 / x^2 (x = omega Delta), with
    cos x - 1 = -2 sin^2(x / 2) and x - sin x by its series below x = 0.1."""
    x = np.abs(x)
    re = -2.0 * np.sin(0.5 * x) ** 2
    im = np.empty_like(x)
    small = x < 0.1
    y = x[small] ** 2
    im[small] = x[small] * y * (1.0 / 6.0 - y * (1.0 / 120.0 - y * (1.0 / 5040.0)))
    im[~small] = x[~small] - np.sin(x[~small])
    with np.errstate(invalid="ignore", divide="ignore"):
        out = (re * re + im * im) / (x * x)
    return np.where(x == 0.0, 0.0, out)


def _spectral_statistics(plant, controller, ch, levels, names, window, placement, delay,
                         A_loop):
    """Variances of each error output, of its window mean and of its RPE for a continuous
    controller with a delay (module docstring)."""
    c_in = list(controller.input_labels)
    measured = [m for m in ch.measurements if m in c_in]
    torques = list(ch.torques)
    P_ev = modal_evaluator(plant, torques, measured + names)
    K_ev = modal_evaluator(controller, measured, torques)
    k, m = len(measured), len(torques)
    # white-noise feedthrough to an error output (its variance is infinite): P_e(inf) K(inf)
    D_p = np.asarray(plant.D, dtype=float)[np.ix_([list(plant.output_labels).index(n)
                                                   for n in names],
                                                  [list(plant.input_labels).index(t)
                                                   for t in torques])]
    D_k = np.asarray(controller.D, dtype=float)[np.ix_(
        [list(controller.output_labels).index(t) for t in torques],
        [c_in.index(n) for n in measured])]
    direct = [names[i] for i in range(len(names)) if np.any(D_p[i] @ D_k != 0.0)]
    if direct:
        raise ValueError(f"outputs {direct} are fed directly by white sensor noise (a "
                         "feedthrough from torque in the plant): their variance is not defined "
                         "by this model")
    thetas, omegas = noise_input_names(ch)
    # per measured channel: (white level^2, bias sigma^2, bias tau)
    channel = []
    for name in measured:
        axis = (list(ch.thetas) + list(ch.omegas)).index(name) % ch.n_axes
        level = levels[axis]
        if name in ch.thetas:
            channel.append((level["attitude_density"] ** 2, 0.0, None))
        else:
            channel.append((level["angle_random_walk"] ** 2, level["bias_instability"] ** 2,
                            level["bias_correlation_time"]))
    white = np.array([c[0] for c in channel])

    def spectrum(omega: np.ndarray) -> np.ndarray:          # (f, k) two-sided densities
        S = np.broadcast_to(white, (omega.size, k)).copy()
        for j, (_, sigma2, tau) in enumerate(channel):
            if sigma2 > 0:
                S[:, j] += 2.0 * sigma2 / tau / (omega ** 2 + 1.0 / tau ** 2)
        return S

    eye = np.eye(m)
    seen = []                    # (omega, L(j omega)) of every evaluation: the Nyquist check

    def power(omega: np.ndarray) -> np.ndarray:            # (f, n_out): sum_j |H_ij|^2 S_j
        s = 1j * omega
        G = P_ev(s)
        Pm, Pe = G[:, :k, :], G[:, k:, :]
        K = K_ev(s) * np.exp(-1j * omega * delay)[:, None, None]
        L = -K @ Pm                                           # negative-feedback loop
        seen.append((omega, L))
        X = np.linalg.solve(eye + L, K)                       # (f, m, k)
        H = Pe @ X                                            # (f, n_out, k)
        return np.einsum("fij,fj->fi", (H * H.conj()).real, spectrum(omega))

    def integrand(omega: np.ndarray) -> np.ndarray:        # (3, f, n_out), d omega
        g = power(omega)
        x = 0.5 * omega * window
        mean = 1.0 - _one_minus_sinc2(x)                        # sinc^2(omega Delta / 2)
        rpe = _one_minus_sinc2(x) if placement == "random" else _end_weight(omega * window)
        return np.stack([g, g * mean[:, None], g * rpe[:, None]])

    # the frequencies the loop may resonate at
    poles = [np.linalg.eigvals(np.asarray(M, dtype=float)) for M in (plant.A, controller.A)]
    poles.append(np.linalg.eigvals(A_loop))
    lam = np.concatenate([p.astype(complex) for p in poles if p.size])
    lam = lam[np.abs(lam) > 0]
    for extra in [1.0 / window] + [1.0 / c[2] for c in channel if c[2] is not None]:
        lam = np.append(lam, -extra)
    if delay > 0 and 1.0 / delay < _BAND * float(np.max(np.abs(lam))):
        # the delay's own scale, where it acts (a far shorter delay only turns the phase
        # of a loop gain far below 1 there)
        lam = np.append(lam, -1.0 / delay)
    w = np.abs(lam)
    w_lo, w_hi = float(w.min()) / _BAND, float(w.max()) * _BAND
    u_lo, u_hi = math.log(w_lo), math.log(w_hi)
    # breakpoints: 10 per decade, graded about each resonance, and the peaks of a scan
    cuts = list(np.linspace(u_lo, u_hi, int(math.ceil((u_hi - u_lo) / math.log(10) * 10)) + 1))
    for z in lam:
        wn = abs(z)
        zeta = max(abs(z.real) / wn, 1e-7)
        for step in zeta * 2.0 ** np.arange(0, 12):
            for f in (1.0 - step, 1.0 + step):
                if f > 0:
                    cuts.append(math.log(wn * f))
    scan = np.exp(np.linspace(u_lo, u_hi, int((u_hi - u_lo) / math.log(10) * 200) + 1))
    g = power(scan).sum(axis=1)
    peaks = np.nonzero((g[1:-1] > g[:-2]) & (g[1:-1] >= g[2:]))[0] + 1
    for i in peaks:
        for f in (0.995, 1.0, 1.005):
            cuts.append(math.log(scan[i] * f))
    cuts = np.unique(np.clip(np.array(cuts), u_lo, u_hi))
    panels = np.column_stack([cuts[:-1], cuts[1:]])
    panels = panels[panels[:, 1] > panels[:, 0]]

    def panel_sums(panels):
        mid, half = 0.5 * (panels[:, 0] + panels[:, 1]), 0.5 * (panels[:, 1] - panels[:, 0])
        u = mid[:, None] + half[:, None] * _NODES[None, :]       # (n, 15)
        omega = np.exp(u)
        values = integrand(omega.reshape(-1)).reshape(3, u.shape[0], 15, -1)
        values = values * (omega * half[:, None])[None, :, :, None]   # d omega = omega du
        kron = np.einsum("qpnk,n->qpk", values, _KRONROD)
        gauss = np.einsum("qpnk,n->qpk", values, _GAUSS)
        return kron, np.abs(kron - gauss)

    # adaptive refinement to a global error: every panel keeps its Kronrod sum and error
    # estimate; a figure has converged when the sum of its panels' errors is within its
    # tolerance; each round bisects the panels that carry the excess (largest errors first,
    # until the rest are within half of it), so a narrow resonance is refined where it is
    # and nothing is asked of a panel beyond what the whole figure needs
    kron, err = panel_sums(panels)                                # (3, n, n_out)
    for _ in range(_MAX_ROUNDS):
        tol = _SPECTRAL_RTOL * np.abs(kron.sum(axis=1))          # (3, n_out)
        excess = err.sum(axis=1) > tol
        if not excess.any():
            break
        with np.errstate(divide="ignore", invalid="ignore"):
            score = np.where(excess[:, None, :], err / tol[:, None, :], 0.0)
        score = np.nan_to_num(score, nan=0.0, posinf=1e300).max(axis=(0, 2))   # (n,)
        order = np.argsort(score)[::-1]
        rest = score.sum() - np.cumsum(score[order])
        n_split = int(np.searchsorted(-rest, -0.5)) + 1           # first where rest <= 0.5
        split = np.zeros(panels.shape[0], dtype=bool)
        split[order[:n_split]] = True
        if panels.shape[0] + n_split > _MAX_PANELS:
            raise PointingNotComputed(
                f"the spectral pointing integrals did not reach their relative accuracy "
                f"{_SPECTRAL_RTOL:g} within {_MAX_PANELS} quadrature panels (a resonance "
                "narrower than the quadrature resolves)")
        halves = panels[split]
        mid = 0.5 * (halves[:, 0] + halves[:, 1])
        halves = np.concatenate([np.column_stack([halves[:, 0], mid]),
                                 np.column_stack([mid, halves[:, 1]])])
        k_new, e_new = panel_sums(halves)
        panels = np.concatenate([panels[~split], halves])
        kron = np.concatenate([kron[:, ~split], k_new], axis=1)
        err = np.concatenate([err[:, ~split], e_new], axis=1)
    else:
        raise PointingNotComputed(
            f"the spectral pointing integrals did not reach their relative accuracy "
            f"{_SPECTRAL_RTOL:g} in {_MAX_ROUNDS} refinements")
    done_sum = kron.sum(axis=1)
    # below w_lo (flat: 7-point Gauss-Legendre) and above w_hi (in x = w_hi / omega)
    xg, wg = np.polynomial.legendre.leggauss(7)
    low = 0.5 * w_lo * (xg + 1.0)
    done_sum = done_sum + np.einsum("qfk,f->qk", integrand(low), 0.5 * w_lo * wg)
    x = 0.5 * (xg + 1.0)
    high = w_hi / x
    done_sum = done_sum + np.einsum("qfk,f->qk", integrand(high), 0.5 * wg * w_hi / x ** 2)
    sigma2, mpe2, rpe2 = done_sum / math.pi
    _check_delayed_stability(plant, controller, delay, seen)
    return sigma2, mpe2, rpe2


def _check_delayed_stability(plant, controller, delay, seen) -> None:
    """Refuse a delayed continuous loop that is not asymptotically stable (its spectral
    integrals are then finite but not its error's statistics).

    The Nyquist count (:func:`.loop_nyquist_count`) on every frequency the quadrature
    evaluated: the converged panels are graded about each resonance of the closed loop, so
    they resolve the phase of det(I + L); it is trusted only when the phase of det(I + L)
    moves by less than pi / 4 between neighbouring frequencies and the count is 0; otherwise
    (or for a grid too narrow for the criterion) the exact count from the loop's delay-free
    roots and imaginary-axis crossings (:func:`.spillover`) decides.
    """
    omega = np.concatenate([w for w, _ in seen])
    L = np.concatenate([l for _, l in seen])
    order = np.argsort(omega)
    omega, L = omega[order], L[order]
    keep = np.concatenate([[True], np.diff(omega) > 0])
    omega, L = omega[keep], L[keep]
    count = None
    with np.errstate(all="ignore"):
        det = np.linalg.det(np.eye(L.shape[1]) + L)
        steps = np.abs(np.angle(det[1:] / det[:-1]))
    if np.all(np.isfinite(steps)) and float(np.max(steps, initial=0.0)) < 0.25 * math.pi:
        try:
            count = loop_nyquist_count(omega, L,
                                       open_loop_unstable=unstable_poles(controller))
        except ValueError:
            count = None
    if count == 0:
        return
    verdict = spillover(plant, controller, delay=delay)
    if not verdict.stable:
        raise ValueError(f"the closed loop with its delay {delay:.6g} s must be asymptotically "
                         f"stable for a stationary pointing error; it has "
                         f"{verdict.n_unstable_poles} roots in the closed right half-plane (the "
                         "delay is at or beyond the loop's delay margin)")
