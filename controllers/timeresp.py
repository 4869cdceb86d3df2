"""Closed-loop time responses (slew, step, disturbance) and their metrics."""
from __future__ import annotations

import math

import control
import numpy as np

from .signals import THETA, THETA_REF, TIP_SUFFIX, TORQUE, _require_signal
from .simulate import simulate

__all__ = ["METRIC_UNITS", "slew_profile", "slew", "step_response", "disturbance_response",
           "metrics"]

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
