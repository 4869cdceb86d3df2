"""Closed-loop time responses (slew, step, disturbance) and their metrics.

Bounded work: a response has t_final / dt + 1 samples, each holding every output and input of
the loop; more than ``max_samples`` (default MAX_SAMPLES) are refused before anything is
allocated, with the estimate in the message.

Divergence is a result: a loop that is unstable (on a truth model, say) leaves the float64
range in a long enough run. Its response then stops at the last sample before (the
simulation is not continued into inf and NaN), and ``response.diverged_at`` [s] is the time of
the first sample past the range (None for a response that did not diverge). Its metrics are
None, with ``diverged`` True and ``diverged_at`` set (see :func:`metrics`).
"""
from __future__ import annotations

import math
import warnings

import control
import numpy as np

from .signals import (AXES, PLANAR, THETA, THETA_REF, THREE_AXIS, TIP_SUFFIX, TORQUE, Channels,
                      require_signal, tip_outputs)
from .arguments import describe, real_array, real_number
from .chunked import OVERFLOW
from .simulate import simulate

__all__ = ["METRIC_UNITS", "MAX_SAMPLES", "slew_profile", "slew", "step_response",
           "disturbance_response", "metrics", "profile_response", "manoeuvre_metrics",
           "check_slew", "signal_trace", "time_grid"]

#: Units of the metrics returned by :func:`metrics` and :func:`margins` (for tables).
METRIC_UNITS: dict[str, str] = {
    "overshoot": "%",
    "settling_time": "s",
    "peak_torque": "N*m",
    "peak_tip_deflection": "m",
    "peak_attitude_error": "rad",
    "final_attitude_error": "rad",
    "diverged": "-",
    "diverged_at": "s",
    "gain_margin": "dB",
    "phase_margin": "deg",
    "modulus_margin": "1",
    "disk_margin": "1",
    "disk_gain_margin": "dB",
    "disk_phase_margin": "deg",
    "min_singular_value": "1",
    "profile_end": "s",
    "settling_time_after_end": "s",
    "residual_attitude_error": "rad",
    "residual_tip_deflection": "m",
    "peak_attitude_error_during": "rad",
    "peak_torque_during": "N*m",
}
# three-axis metrics per hub axis carry the unit of their planar name
METRIC_UNITS.update({f"{name}_{axis}": METRIC_UNITS[name] for axis in AXES for name in (
    "peak_torque", "peak_attitude_error", "final_attitude_error", "gain_margin", "phase_margin",
    "modulus_margin", "residual_attitude_error", "peak_attitude_error_during",
    "peak_torque_during")})

#: Most samples a time response may have unless the caller raises ``max_samples``: 1e7
#: samples of a loop with 10 outputs and inputs hold 0.8 GB of float64.
MAX_SAMPLES = 10_000_000


def _simulate(system, T, U):
    """Time response that stops where it leaves the float range (``diverged_at`` set):
    controllers.simulate (exact, continuous) or forced_response (digital)."""
    if not system.isdtime(strict=True):
        return simulate(system, T, U, on_overflow="stop")
    with np.errstate(over="ignore", invalid="ignore"):
        response = control.forced_response(system, T, U, squeeze=False)
    n_out, n_states = system.noutputs, system.nstates
    y = np.asarray(response.y, dtype=float).reshape(n_out, -1)
    x = np.asarray(response.x, dtype=float).reshape(n_states, -1)
    with np.errstate(invalid="ignore"):
        bad = ~(np.isfinite(y).all(axis=0) & (np.abs(y).max(axis=0, initial=0.0) < OVERFLOW)
                & np.isfinite(x).all(axis=0) & (np.abs(x).max(axis=0, initial=0.0) < OVERFLOW))
    if not bad.any():
        response.diverged_at = None
        return response
    k = int(np.argmax(bad))
    if k == 0:
        raise FloatingPointError("simulation overflowed at the first sample: the initial state "
                                 "or input exceeds the float64 range")
    t = np.asarray(response.t, dtype=float)
    u = np.asarray(response.u, dtype=float).reshape(system.ninputs, -1)
    stopped = control.TimeResponseData(
        t[:k], y[:, :k], x[:, :k], u[:, :k], issiso=system.issiso(),
        output_labels=list(system.output_labels), state_labels=list(system.state_labels),
        input_labels=list(system.input_labels), sysname=system.name,
        title="Simulated response for " + system.name, trace_types=["forced"],
        plot_inputs=True, squeeze=False)
    stopped.diverged_at = float(t[k])
    return stopped


def time_grid(system, t_final, dt, default_dt: float, max_samples,
              default_from: str = "t_final") -> np.ndarray:
    """Sample times 0, dt, ..., <= t_final [s] of a response, refused beyond max_samples before
    any allocation.

    Parameters
    ----------
    system : control.StateSpace
        The loop to simulate; a digital one fixes dt at its sample time.
    t_final : float, s
        Positive and finite.
    dt : float or None, s
        The step; None: ``default_dt`` (a digital loop: its sample time).
    default_dt : float, s
        The step when ``dt`` is None.
    max_samples : int or None
        The most samples allowed (None: :data:`MAX_SAMPLES`).
    default_from : str
        What t_final (when it is not "t_final") and the default dt were derived from, for the
        messages.

    Raises
    ------
    TypeError, ValueError
        A bad t_final, dt or max_samples (by name), or more samples than allowed.
    """
    t_final = real_number(t_final, "t_final", "s")
    if not (np.isfinite(t_final) and t_final > 0):
        where = "" if default_from == "t_final" else f" (3 x {default_from} by default)"
        raise ValueError(f"t_final must be positive and finite [s]{where}; got {t_final:.6g}")
    limit = MAX_SAMPLES if max_samples is None else real_number(max_samples, "max_samples",
                                                                "1")
    if not limit >= 2:
        raise ValueError(f"max_samples must be at least 2; got {limit:.6g}")
    if system.isdtime(strict=True):
        step = float(system.dt)
        if dt is not None and not math.isclose(real_number(dt, "dt", "s"), step, rel_tol=1e-9):
            raise ValueError(f"dt must equal the digital loop's sample time {step} [s]; got "
                             f"{float(dt):.6g}")
    else:
        step = default_dt if dt is None else real_number(dt, "dt", "s")
        if not (np.isfinite(step) and step > 0):
            where = "" if dt is not None else f" (by default a fraction of {default_from})"
            raise ValueError(f"dt must be positive and finite [s]{where}; got {step:.6g}")
    n_float = t_final / step + 1.0
    if n_float > limit:
        signals = system.noutputs + system.ninputs
        raise ValueError(
            f"t_final / dt = {t_final:.4g} s / {step:.4g} s gives {n_float:.4g} samples "
            f"(~{n_float * signals * 8 / 1e9:.3g} GB for {signals} signals), more than "
            f"max_samples = {limit:.4g} (controllers.timeresp.MAX_SAMPLES by default): use a "
            "larger dt or a shorter t_final, or raise max_samples explicitly")
    n = int(math.floor(t_final / step + 1e-9)) + 1
    if n < 2:
        raise ValueError(f"t_final {t_final:.6g} [s] must exceed one time step dt = {step:.6g} "
                         "[s]")
    return np.arange(n, dtype=float) * step


def _check_closed_loop(closed_loop) -> Channels:
    """A closed loop from close_loop; its convention (by its attitude and torque outputs)."""
    if not isinstance(closed_loop, control.StateSpace):
        raise TypeError("closed_loop must be a control.StateSpace (from close_loop); got "
                        f"{type(closed_loop).__name__}")
    ch = _response_channels(list(closed_loop.output_labels))
    if ch is None:
        for name in (THETA, TORQUE):
            require_signal(closed_loop, name, "output", "closed_loop")
    return ch


def _response_channels(outputs) -> Channels | None:
    """PLANAR or THREE_AXIS by the outputs theta/torque or theta_x..z/torque_x..z; else None."""
    for ch in (PLANAR, THREE_AXIS):
        if all(n in outputs for n in ch.thetas + ch.torques):
            return ch
    return None


def _axis_vector(axis, ch: Channels) -> np.ndarray:
    """The unit slew axis: None for a planar loop; for three axes 'x', 'y', 'z' or a non-zero
    3-vector (normalised; hub axes)."""
    if not ch.mimo:
        if axis is not None:
            raise ValueError(f"axis is for three-axis loops; this planar loop turns about its "
                             f"one axis; got axis={describe(axis)}")
        return np.ones(1)
    if axis is None:
        raise ValueError("axis must be given for a three-axis loop: 'x', 'y', 'z' or a 3-vector "
                         "(hub axes) of the eigen-axis slew")
    if isinstance(axis, str):
        if axis not in AXES:
            raise ValueError(f"axis must be 'x', 'y', 'z' or a 3-vector; got {describe(axis)}")
        return np.eye(3)[AXES.index(axis)]
    e = np.asarray(axis, dtype=float)
    if e.shape != (3,) or not np.all(np.isfinite(e)) or not np.any(e):
        raise ValueError(f"axis must be a non-zero finite 3-vector (hub axes); got "
                         f"{describe(axis)}")
    e = e / np.max(np.abs(e))  # scaled first: the norm of 1e-300 or 1e200 entries stays normal
    return e / np.linalg.norm(e)


def check_slew(angle, duration, name: str = "duration") -> tuple[float, float]:
    """The checked (angle [rad], slew duration [s]) of a slew; ``name`` is the caller's keyword
    for the duration.

    Raises
    ------
    TypeError, ValueError
        Not real numbers, a zero or infinite angle, a duration not positive and finite.

    Warns
    -----
    UserWarning
        An angle beyond a turn (2 pi rad): degrees given for radians?
    """
    angle = real_number(angle, "angle", "rad")
    duration = real_number(duration, name, "s")
    if not (np.isfinite(angle) and angle != 0):
        raise ValueError(f"angle must be non-zero and finite [rad]; got {angle:.6g}")
    if not (np.isfinite(duration) and duration > 0):
        raise ValueError(f"{name} must be positive and finite [s]; got {duration:.6g}")
    if abs(angle) > 2.0 * math.pi:
        # radians here, as everywhere in the Python API; a scene file gives degrees
        warnings.warn(f"angle = {angle:g} rad is more than a turn (2 pi rad); did you give "
                      f"degrees? {angle:g} deg = {math.radians(angle):.6g} rad", UserWarning,
                      stacklevel=3)
    return angle, duration


def slew_profile(t: np.ndarray, angle: float, duration: float) -> np.ndarray:
    """Cycloidal slew profile from 0 to ``angle`` in ``duration``.

    theta_ref(t) = angle (t/T - sin(2 pi t/T) / (2 pi)) for 0 <= t <= T, angle afterwards,
    0 before. Rate angle/T (1 - cos(2 pi t/T)) and acceleration 2 pi angle/T^2 sin(2 pi t/T) are
    zero at both ends (continuous acceleration, no torque jump); peak rate 2 angle/T, peak
    acceleration 2 pi angle/T^2.

    Parameters
    ----------
    t : array of float, s
        Finite times.
    angle : float, rad
        Non-zero and finite (more than a turn, 2 pi, is warned about: degrees given?).
    duration : float, s
        Positive and finite.

    Returns
    -------
    ndarray, rad, same shape as t

    Raises
    ------
    TypeError, ValueError
        A parameter that is not as above (named in the message).

    References
    ----------
    R. L. Norton, Design of Machinery, 5th ed., sec. 8.6 (cycloidal displacement).
    """
    t = real_array(t, "t", "s")
    if not np.all(np.isfinite(t)):
        raise ValueError(f"t must be finite times [s]; got {describe(t)}")
    angle, duration = check_slew(angle, duration)
    with np.errstate(over="ignore"):  # t / a subnormal duration: inf, clipped to 1
        tau = np.clip(t / duration, 0.0, 1.0)
    return angle * (tau - np.sin(2.0 * np.pi * tau) / (2.0 * np.pi))


def _inputs(closed_loop, n_t: int, **rows: np.ndarray) -> np.ndarray:
    U = np.zeros((closed_loop.ninputs, n_t))
    labels = list(closed_loop.input_labels)
    for name, values in rows.items():
        U[labels.index(name)] = values
    return U


def slew(closed_loop: control.StateSpace, angle: float, duration: float, *,
         t_final: float | None = None, dt: float | None = None,
         max_samples: int | None = None, axis=None) -> control.TimeResponseData:
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
    max_samples : int, optional
        Most samples allowed (default MAX_SAMPLES); more raise ValueError before any work.
    axis : {'x', 'y', 'z'} or sequence of 3 floats, optional
        Three-axis loops only (and required there): the eigen-axis e (hub axes, normalised) of
        the slew, theta_ref(t) = e * slew_profile(t, angle, duration) (small angles: a rotation
        by angle about e).

    Returns
    -------
    control.TimeResponseData
        Outputs of the closed loop (``theta``, ``omega``, ``torque``, tip deflections, ...),
        inputs (``theta_ref`` profile, zero disturbances). ``diverged_at`` [s]: None, or the
        time at which an unstable loop left the float64 range; the response then ends at the
        sample before (see the module docstring).
    """
    ch = _check_closed_loop(closed_loop) or PLANAR
    e = _axis_vector(axis, ch)
    for name in ch.refs:
        require_signal(closed_loop, name, "input", "closed_loop")
    angle, duration = check_slew(angle, duration)
    t_final = 3.0 * duration if t_final is None else t_final
    T = time_grid(closed_loop, t_final, dt, duration / 500.0, max_samples, "duration")
    profile = slew_profile(T, angle, duration)
    U = _inputs(closed_loop, T.size, **{name: e_i * profile if ch.mimo else profile
                                        for name, e_i in zip(ch.refs, e)})
    return _simulate(closed_loop, T, U)


def step_response(closed_loop: control.StateSpace, *, amplitude: float = 1.0,
                  t_final: float = 10.0, dt: float | None = None,
                  max_samples: int | None = None, axis=None) -> control.TimeResponseData:
    """Response to a step of ``amplitude`` [rad] in theta_ref at t = 0.

    Parameters
    ----------
    closed_loop : control.StateSpace
    amplitude : float, rad
    t_final : float, s
    dt : float, s, optional
        Default t_final / 2000.
    max_samples : int, optional
        Most samples allowed (default MAX_SAMPLES).
    axis : {'x', 'y', 'z'} or sequence of 3 floats, optional
        Three-axis loops (required there): theta_ref = amplitude * e, e the unit axis.

    Returns
    -------
    control.TimeResponseData
        With ``diverged_at`` as for :func:`slew`.
    """
    ch = _check_closed_loop(closed_loop) or PLANAR
    if not ch.mimo:
        _axis_vector(axis, ch)
        return _step_on(closed_loop, THETA_REF, amplitude, "rad", t_final, dt, max_samples)
    e = _axis_vector(axis, ch)
    for name in ch.refs:
        require_signal(closed_loop, name, "input", "closed_loop")
    amplitude = real_number(amplitude, "amplitude", "rad")
    if not (np.isfinite(amplitude) and amplitude != 0):
        raise ValueError(f"amplitude must be non-zero and finite [rad]; got {amplitude:.6g}")
    T = time_grid(closed_loop, real_number(t_final, "t_final", "s"), dt,
                  float(t_final) / 2000.0, max_samples)
    U = _inputs(closed_loop, T.size, **{name: np.full(T.size, amplitude * e_i)
                                        for name, e_i in zip(ch.refs, e)})
    return _simulate(closed_loop, T, U)


def disturbance_response(closed_loop: control.StateSpace, input: str = "disturbance_torque", *,
                         amplitude: float = 1.0, t_final: float = 10.0, dt: float | None = None,
                         max_samples: int | None = None) -> control.TimeResponseData:
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
    max_samples : int, optional
        Most samples allowed (default MAX_SAMPLES).

    Returns
    -------
    control.TimeResponseData
        With ``diverged_at`` as for :func:`slew`.
    """
    return _step_on(closed_loop, input, amplitude, "input's unit", t_final, dt, max_samples)


def _step_on(closed_loop, input: str, amplitude, unit: str, t_final, dt, max_samples
             ) -> control.TimeResponseData:
    """Step of ``amplitude`` on one closed-loop input at t = 0, every other input zero."""
    if not isinstance(input, str):
        raise TypeError(f"input must be the name of a closed-loop input (str); got "
                        f"{type(input).__name__} {describe(input)}")
    _check_closed_loop(closed_loop)
    require_signal(closed_loop, input, "input", "closed_loop")
    amplitude = real_number(amplitude, "amplitude", unit)
    if not (np.isfinite(amplitude) and amplitude != 0):
        raise ValueError(f"amplitude must be non-zero and finite [{unit}]; got {amplitude:.6g}")
    t_final = real_number(t_final, "t_final", "s")
    T = time_grid(closed_loop, t_final, dt, t_final / 2000.0, max_samples)
    U = _inputs(closed_loop, T.size, **{input: np.full(T.size, amplitude)})
    return _simulate(closed_loop, T, U)


def signal_trace(response, name: str, kind: str = "output") -> np.ndarray | None:
    """The samples of one output (``kind="output"``) or input (any other ``kind``) of a
    ``control.TimeResponseData``, in the signal's units; None if it has no such signal."""
    labels = list(response.output_labels if kind == "output" else response.input_labels)
    if name not in labels:
        return None
    data = np.asarray(response.y if kind == "output" else response.u)
    data = data.reshape(len(labels), -1)
    return data[labels.index(name)]


def _divergence(response, t: np.ndarray, traces) -> float | None:
    """The response's diverged_at, or the time of its first non-finite sample, or None."""
    diverged_at = getattr(response, "diverged_at", None)
    if diverged_at is not None:
        return float(diverged_at)
    finite = np.ones(t.size, dtype=bool)
    for x in traces:
        finite &= np.isfinite(x)
    return None if finite.all() else float(t[int(np.argmin(finite))])


def metrics(response: control.TimeResponseData, *, settling_band: float = 0.02
            ) -> dict[str, float | bool | None]:
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
    dict of str to float, bool or None
        ``peak_torque`` [N*m] max |torque|; ``peak_attitude_error`` [rad] max |theta - theta_ref|;
        ``final_attitude_error`` [rad] |theta - theta_ref| at the last sample;
        ``peak_tip_deflection`` [m] max |tip deflection| over every ``*tip_deflection`` output
        (only if there is one). If the final reference r_f is non-zero also
        ``overshoot`` [%] = 100 max(0, max(theta/r_f) - 1), and ``settling_time`` [s], the first
        time after which |theta - r_f| <= settling_band |r_f| up to the end of the response
        (None if the last sample is still outside the band: simulate longer).
        Always ``diverged`` (bool). A response that left the float64 range
        (``response.diverged_at`` set, or non-finite samples) has ``diverged`` True, also
        ``diverged_at`` [s], the time it did, and None for every other metric: the numbers of
        its finite part would read as those of a loop that settles. Never NaN or inf.

        Three-axis responses (outputs theta_x..z, torque_x..z): the same names with vector
        norms, ``peak_torque`` the largest |torque_i|, ``peak_attitude_error`` max
        ||theta - theta_ref||, ``final_attitude_error`` ||theta - theta_ref|| at the end,
        ``overshoot`` along the final reference r_f, 100 max(0, max(theta . r_f) / |r_f|^2 - 1),
        ``settling_time`` on ||theta - r_f|| <= settling_band |r_f| (for a planar response
        these are the planar definitions); then per hub axis ``peak_torque_x``,
        ``peak_attitude_error_x``, ``final_attitude_error_x``, ... and per tip output
        ``peak_<name>`` ([m] for a deflection, [rad] for a twist); ``peak_tip_deflection``
        [m] the largest of the deflections (the twists are no deflections).

    References
    ----------
    Franklin, Powell & Emami-Naeini, Feedback Control of Dynamic Systems, 7th ed., sec. 3.4
    (overshoot, settling time).
    """
    if not isinstance(response, control.TimeResponseData):
        raise TypeError(f"response must be a control.TimeResponseData; got {type(response).__name__}")
    settling_band = real_number(settling_band, "settling_band", "1")
    if not (0 < settling_band < 1):
        raise ValueError(f"settling_band must be in (0, 1) [fraction of the reference]; "
                         f"got {settling_band:.6g}")
    t = np.asarray(response.t, dtype=float).reshape(-1)
    if _response_channels(list(response.output_labels)) is THREE_AXIS:
        return _three_axis_metrics(response, t, settling_band)
    theta = signal_trace(response, THETA)
    torque = signal_trace(response, TORQUE)
    if theta is None or torque is None:
        raise ValueError("response must have outputs 'theta' and 'torque' (or theta_x..z and "
                         f"torque_x..z); got {describe(list(response.output_labels))}")
    ref = signal_trace(response, THETA_REF, "input")
    ref = np.zeros_like(theta) if ref is None else ref
    tips = tip_outputs(response.output_labels)
    r_f = float(ref[-1]) if ref.size else 0.0
    names = ["peak_torque", "peak_attitude_error", "final_attitude_error"]
    names += ["peak_tip_deflection"] if tips else []
    names += ["overshoot", "settling_time"] if r_f != 0.0 else []
    diverged_at = _divergence(response, t, [theta, torque, ref] + [signal_trace(response, n)
                                                                  for n in tips])
    if diverged_at is not None:
        return {**{name: None for name in names}, "diverged": True, "diverged_at": diverged_at}
    error = theta - ref
    out: dict[str, float | bool | None] = {
        "peak_torque": float(np.max(np.abs(torque))),
        "peak_attitude_error": float(np.max(np.abs(error))),
        "final_attitude_error": float(abs(error[-1]))}
    if tips:
        out["peak_tip_deflection"] = max(float(np.max(np.abs(signal_trace(response, n))))
                                         for n in tips)
    if r_f != 0.0:
        out["overshoot"] = float(100.0 * max(0.0, np.max(theta / r_f) - 1.0))
        outside = np.nonzero(np.abs(theta - r_f) > settling_band * abs(r_f))[0]
        if outside.size == 0:
            out["settling_time"] = float(t[0])
        elif outside[-1] == t.size - 1:
            out["settling_time"] = None
        else:
            out["settling_time"] = float(t[outside[-1] + 1])
    out["diverged"] = False
    return out


def _three_axis_metrics(response, t: np.ndarray, settling_band: float) -> dict:
    """:func:`metrics` of a three-axis response (see its docstring)."""
    ch = THREE_AXIS
    theta = np.array([signal_trace(response, n) for n in ch.thetas])
    torque = np.array([signal_trace(response, n) for n in ch.torques])
    refs = [signal_trace(response, n, "input") for n in ch.refs]
    ref = np.array([np.zeros(t.size) if r is None else r for r in refs])
    tips = tip_outputs(response.output_labels)
    # the deflections [m]: a twist [rad] is no deflection
    deflections = [n for n in tips if TIP_SUFFIX in n]
    r_f = ref[:, -1]
    phi = float(np.linalg.norm(r_f))
    per_axis = [f"{name}_{a}" for a in ch.axes for name in
                ("peak_torque", "peak_attitude_error", "final_attitude_error")]
    names = ["peak_torque", "peak_attitude_error", "final_attitude_error"]
    names += ["peak_tip_deflection"] if deflections else []
    names += ["overshoot", "settling_time"] if phi != 0.0 else []
    names += per_axis + [f"peak_{n}" for n in tips]
    diverged_at = _divergence(response, t, list(theta) + list(torque) + list(ref)
                              + [signal_trace(response, n) for n in tips])
    if diverged_at is not None:
        return {**{name: None for name in names}, "diverged": True, "diverged_at": diverged_at}
    error = theta - ref
    norm = np.sqrt(np.sum(error * error, axis=0))
    out: dict[str, float | bool | None] = {
        "peak_torque": float(np.max(np.abs(torque))),
        "peak_attitude_error": float(np.max(norm)),
        "final_attitude_error": float(norm[-1])}
    peaks = {n: float(np.max(np.abs(signal_trace(response, n)))) for n in tips}
    if deflections:
        out["peak_tip_deflection"] = max(peaks[n] for n in deflections)
    if phi != 0.0:
        along = (r_f @ theta) / (phi * phi)  # progress along the slew axis, 1 at the target
        out["overshoot"] = float(100.0 * max(0.0, np.max(along) - 1.0))
        miss = theta - r_f[:, None]
        outside = np.nonzero(np.sqrt(np.sum(miss * miss, axis=0)) > settling_band * phi)[0]
        if outside.size == 0:
            out["settling_time"] = float(t[0])
        elif outside[-1] == t.size - 1:
            out["settling_time"] = None
        else:
            out["settling_time"] = float(t[outside[-1] + 1])
    for i, a in enumerate(ch.axes):
        out[f"peak_torque_{a}"] = float(np.max(np.abs(torque[i])))
        out[f"peak_attitude_error_{a}"] = float(np.max(np.abs(error[i])))
        out[f"final_attitude_error_{a}"] = float(abs(error[i, -1]))
    out.update({f"peak_{n}": v for n, v in peaks.items()})
    out["diverged"] = False
    return out


def profile_response(closed_loop: control.StateSpace, profile, *, inertia=None,
                     t_final: float | None = None, dt: float | None = None,
                     hold: str = "linear", gyroscopic: bool = False,
                     max_samples: int | None = None) -> control.TimeResponseData:
    """Response of a closed loop to a slew profile (:mod:`controllers.profiles`).

    The loop's reference inputs are fed from the profile sampled on the grid: ``theta_ref``
    always, ``omega_ref`` and ``torque_ff`` where the loop has them (a controller designed with
    ``feedforward=True``); a loop without them sees the attitude reference alone.

    Parameters
    ----------
    closed_loop : control.StateSpace
        From :func:`close_loop`.
    profile : controllers.Profile
        Planar for a planar loop; three-axis (an axis) for a three-axis loop.
    inertia : float or (3, 3) array, kg*m^2, optional
        The rigid-body inertia of the feedforward torque (:func:`rigid_body_inertia` of the
        design plant); required when the loop has ``torque_ff`` inputs.
    t_final : float, s, optional
        End of the simulation; default twice the profile's end.
    dt : float, s, optional
        Sample step; default profile.end_time / 500 (the loop's own for a digital loop).
    hold : {"linear", "zero", "generator"}
        How a continuous loop sees the profile: its samples interpolated linearly or held, the
        difference from the exact profile bounded by ``profile.hold_error(dt, hold=hold,
        inertia=inertia)``; or ``"generator"``: the loop driven by the profile's generator
        (:meth:`Profile.driving`) whose piecewise-constant input is held, exact on a grid
        through every breakpoint of the profile (the gyroscopic term left out). A digital loop
        reads the samples.
    gyroscopic : bool
        Feed the gyroscopic term omega_ref x J omega_ref of a three-axis feedforward. Default
        False: flexsat's plants are linearised about rest and do not have it.
    max_samples : int, optional
        Most samples allowed (default MAX_SAMPLES).

    Returns
    -------
    control.TimeResponseData
        As :func:`slew`, with attribute ``profile_end`` [s], the profile's end time (for
        :func:`manoeuvre_metrics`).
    """
    if not (hasattr(profile, "references") and hasattr(profile, "end_time")):
        raise TypeError(f"profile must be a controllers.Profile; got {type(profile).__name__}")
    ch = _check_closed_loop(closed_loop) or PLANAR
    if ch.mimo != (profile.axis is not None):
        raise ValueError(f"profile must be {'three-axis (with an axis)' if ch.mimo else 'planar'}"
                         f" for this {'three-axis' if ch.mimo else 'planar'} closed loop")
    if not isinstance(hold, str) or hold not in ("linear", "zero", "generator"):
        raise ValueError(f"hold must be 'linear', 'zero' or 'generator'; got {describe(hold)}")
    if hold == "generator" and gyroscopic is True and ch.mimo:
        raise ValueError("gyroscopic=True cannot be fed through the profile's generator (the "
                         "term omega_ref x J omega_ref is not linear in its state): use "
                         "hold='linear' or 'zero', or gyroscopic=False")
    labels = list(closed_loop.input_labels)
    for name in ch.refs:
        require_signal(closed_loop, name, "input", "closed_loop")
    wants_ff = any(name in labels for name in ch.feedforwards)
    if wants_ff and inertia is None:
        raise ValueError("inertia [kg*m^2] must be given: the closed loop has feedforward torque "
                         f"inputs {describe(list(ch.feedforwards))}")
    end = float(profile.end_time)
    t_final = 2.0 * end if t_final is None else t_final
    T = time_grid(closed_loop, t_final, dt, end / 500.0, max_samples)
    references = profile.references(T, inertia if wants_ff else None, gyroscopic=gyroscopic)
    with np.errstate(invalid="ignore"):
        if any(not np.all(np.abs(v) < OVERFLOW) for v in references.values()):
            raise ValueError("the feedforward torque J s'' leaves the float64 range: check "
                             "inertia [kg*m^2]")
    U = _inputs(closed_loop, T.size, **{name: values for name, values in references.items()
                                        if name in labels})
    if closed_loop.isdtime(strict=True):
        response = _simulate(closed_loop, T, U)
    elif hold == "generator":
        driven = profile.driving(closed_loop, inertia)
        fed = [labels.index(n) for n in labels if n in driven.input_labels]
        Ud = np.vstack([profile.generator_input(T)[None, :], U[fed]])
        run = simulate(driven, T, Ud, hold="zero", on_overflow="stop")
        # the loop's inputs as the samples of the references (what the generator produced)
        response = control.TimeResponseData(
            run.t, run.y, None, U[:, :run.t.size], issiso=False,
            output_labels=list(closed_loop.output_labels), input_labels=labels, sysname=closed_loop.name,
            title="Simulated response for " + closed_loop.name, trace_types=["forced"],
            plot_inputs=True, squeeze=False)
        response.diverged_at = run.diverged_at
    else:
        response = simulate(closed_loop, T, U, hold=hold, on_overflow="stop")
    response.profile_end = end
    return response


def manoeuvre_metrics(response: control.TimeResponseData, end_time: float | None = None, *,
                      settling_band: float = 0.02) -> dict[str, float | bool | None]:
    """Metrics of a slew measured against the end of its profile.

    During the manoeuvre (t <= end_time) the peak attitude error |theta - theta_ref| and the
    peak torque; after it (t >= end_time) the residual vibration: the peak attitude error and
    peak tip deflection left, and the settling time counted from the end of the profile.

    Parameters
    ----------
    response : control.TimeResponseData
        From :func:`profile_response` (or any response with outputs theta, torque and input
        theta_ref; three-axis names likewise).
    end_time : float, s, optional
        End of the profile; default ``response.profile_end``.
    settling_band : float
        Band as a fraction of the final reference (default 2 %).

    Returns
    -------
    dict of str to float, bool or None
        ``profile_end`` [s]; ``peak_attitude_error_during`` [rad] and ``peak_torque_during``
        [N*m] (t <= end); ``residual_attitude_error`` [rad] (max |theta - theta_ref| for
        t >= end) and, with tip outputs, ``residual_tip_deflection`` [m] (max |tip deflection|
        over them for t >= end); ``settling_time_after_end`` [s], the time after the end of the
        profile from which |theta - r_f| <= settling_band |r_f| up to the end of the response
        (0 if already settled; None if the last sample is outside: simulate longer);
        ``diverged`` (bool). Three axes: norms as :func:`metrics` takes them, then
        ``residual_attitude_error_x``, ``peak_attitude_error_during_x``,
        ``peak_torque_during_x``... per hub axis. A diverged response gives None for every
        metric with ``diverged_at`` [s]. Never NaN.

    Raises
    ------
    ValueError
        An end time outside the response, a settling band outside (0, 1), missing signals.
    """
    if not isinstance(response, control.TimeResponseData):
        raise TypeError(f"response must be a control.TimeResponseData; got "
                        f"{type(response).__name__}")
    if end_time is None:
        end_time = getattr(response, "profile_end", None)
        if end_time is None:
            raise ValueError("end_time [s] must be given for a response that does not carry "
                             "profile_end (from profile_response)")
    end_time = real_number(end_time, "end_time", "s")
    settling_band = real_number(settling_band, "settling_band", "1")
    if not (0 < settling_band < 1):
        raise ValueError(f"settling_band must be in (0, 1) [fraction of the reference]; "
                         f"got {settling_band:.6g}")
    t = np.asarray(response.t, dtype=float).reshape(-1)
    ch = _response_channels(list(response.output_labels))
    if ch is None:
        raise ValueError("response must have outputs 'theta' and 'torque' (or theta_x..z and "
                         f"torque_x..z); got {describe(list(response.output_labels))}")
    if not (np.isfinite(end_time) and t[0] <= end_time <= t[-1]):
        raise ValueError(f"end_time must lie within the response [{t[0]:.6g}, {t[-1]:.6g}] s; "
                         f"got {end_time:.6g}")
    theta = np.array([signal_trace(response, n) for n in ch.thetas])
    torque = np.array([signal_trace(response, n) for n in ch.torques])
    refs = [signal_trace(response, n, "input") for n in ch.refs]
    ref = np.array([np.zeros(t.size) if r is None else r for r in refs])
    tips = tip_outputs(response.output_labels)
    tip = np.array([signal_trace(response, n) for n in tips]).reshape(len(tips), t.size)
    names = ["profile_end", "peak_attitude_error_during", "peak_torque_during",
             "residual_attitude_error", "settling_time_after_end"]
    names += ["residual_tip_deflection"] if tips else []
    if ch.mimo:
        names += [f"{n}_{a}" for a in ch.axes for n in
                  ("peak_attitude_error_during", "peak_torque_during", "residual_attitude_error")]
    diverged_at = _divergence(response, t, list(theta) + list(torque) + list(ref) + list(tip))
    if diverged_at is not None:
        return {**{n: None for n in names}, "profile_end": end_time, "diverged": True,
                "diverged_at": diverged_at}
    during = t <= end_time
    after = t >= end_time
    error = theta - ref
    norm = np.sqrt(np.sum(error * error, axis=0))
    torque_peak = np.max(np.abs(torque), axis=0)
    out: dict[str, float | bool | None] = {
        "profile_end": end_time,
        "peak_attitude_error_during": float(np.max(norm[during])),
        "peak_torque_during": float(np.max(torque_peak[during])),
        "residual_attitude_error": float(np.max(norm[after]))}
    r_f = ref[:, -1]
    scale = float(np.linalg.norm(r_f))
    miss = np.sqrt(np.sum((theta - r_f[:, None]) ** 2, axis=0))
    outside = np.nonzero(after & (miss > settling_band * scale))[0]
    if outside.size == 0:
        out["settling_time_after_end"] = 0.0
    elif outside[-1] == t.size - 1:
        out["settling_time_after_end"] = None
    else:
        out["settling_time_after_end"] = float(t[outside[-1] + 1] - end_time)
    if tips:
        out["residual_tip_deflection"] = float(np.max(np.abs(tip[:, after])))
    if ch.mimo:
        for i, a in enumerate(ch.axes):
            out[f"peak_attitude_error_during_{a}"] = float(np.max(np.abs(error[i, during])))
            out[f"peak_torque_during_{a}"] = float(np.max(np.abs(torque[i, during])))
            out[f"residual_attitude_error_{a}"] = float(np.max(np.abs(error[i, after])))
    out["diverged"] = False
    return out
