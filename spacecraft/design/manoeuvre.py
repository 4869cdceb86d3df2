r"""The scene's manoeuvre as flown: the profile, the loop delay, the wheels and the sensors.

A scene flies its manoeuvre (:func:`flies`) when it asks for more than the step reference of
an ideal, instantaneous loop: a profile other than ``"step"`` or feedforward
(``manoeuvre.profile``, ``manoeuvre.feedforward``), a loop delay (``controller.delay``,
``controller.computation_delay``) or reaction wheels (``[wheels]``). Then, for each loop:

- **The reference** (:meth:`FlownManoeuvre.profile`): the profile of
  :func:`controllers.reference_profile` for each design model, ending at ``slew_time``; a
  ``"shaped"`` profile's shaper on the design model's lowest flexible modes
  (:func:`controllers.flexible_modes`, :func:`controllers.mode_shaper`); the feedforward torque
  J alpha_ref with J the design model's rigid-body inertia. Three axes: the eigen-axis slew
  about ``manoeuvre.slew_axis`` (theta_ref = e s, omega_ref = e s'), the modes those of the
  3 x 3 channel torque -> theta, J the inertia tensor and the torque limit on each hub-axis
  component of J e s''. A flight computer feeds J alpha_ref + omega_ref x J omega_ref (Euler's
  equation); flexsat's plants are linearised about rest and have no gyroscopic torque, so the
  loop is fed the part its plant has, J alpha_ref: the linear plant with it and the spacecraft
  with the whole feedforward see the same (no) rigid-body error; the gyroscopic term's peak
  |e x J e| max s'^2 is reported (``gyroscopic_peak_torque``). The loop reads theta_ref (and, when
  its controller was tuned with feedforward, omega_ref and torque_ff) at the samples, linearly
  interpolated between them as :class:`controllers.Simulator` reads every input: the difference
  from the exact profile is at most :meth:`controllers.Profile.hold_error` per signal (reported).
- **The delay**: the loop closed with it (:func:`controllers.close_loop`): a digital
  controller's delayed loop exactly (delay-line states); a continuous controller's delayed loop,
  infinite-dimensional, with the command held every ``manoeuvre.step`` and delayed by
  delay - step / 2 (:mod:`controllers.delay`): the references the controller reads at the
  samples (the rate reference and feedforward torque as their means over the step centred
  there), the disturbance held at the plant at the step midpoints: O(step^2) (tested). Every verdict takes the delay exactly (e^(-j omega tau) on the
  loop: margins, Nyquist, the delay margin; :mod:`spacecraft.design.models`).
- **The wheels** (:func:`controllers.simulate_wheels`): torque and momentum saturation and
  friction around the linear loop, exact between switching instants decided at the samples
  (:mod:`controllers.wheel_loop`: O(step^2) where the applied torque is continuous across a
  switch, O(step) where it jumps). The wheels are nonlinear, so the slew and the disturbance
  are simulated together: the response is the whole manoeuvre's.
- **The metrics** (:func:`controllers.manoeuvre_metrics`), beside today's from t = 0: during
  the profile (t <= its end) the peak attitude error |theta - theta_ref| and the peak torque;
  after it the residual vibration (peak attitude error, peak tip deflection) and the settling
  time counted from the end of the profile.
- **The pointing** (``[sensors]``, :func:`controllers.pointing`): APE, MPE and RPE over the
  window per axis and the tip jitter, standard deviations of the stationary closed loop under
  the sensor noise, by exact covariance analysis (ECSS-E-ST-60-10C definitions; the wheels are
  linear there: a pointing loop stays inside their limits).

Errors by scene key: limits that cannot complete the slew in ``slew_time`` (the shortest time
they allow is given), wheels that cannot (:func:`controllers.shortest_slew_time`), a shaper as
long as the slew, a design model with fewer flexible modes than ``manoeuvre.shaper.modes``. A
delay beyond a loop's delay margin is a result: the loop is unstable, and its verdicts and
status say so.

References
----------
B. Wie, Space Vehicle Dynamics and Control, 2nd ed., AIAA 2008, sec. 7.3 (slews, feedforward);
N. C. Singer, W. P. Seering, J. Dyn. Sys. Meas. Control 112(1), 1990 (input shapers);
ECSS-E-ST-60-10C, Space engineering: Control performance, 2008 (pointing errors).
"""

from __future__ import annotations

import math
import warnings

import control
import numpy as np

import controllers
from controllers.pointing import PointingNotComputed
from controllers.signals import tip_outputs

from ..scene.reader import SceneError
from ..scene.specs import quiet_unit_slips
from .responses import (discrete_outputs, disturbance_inputs, disturbance_weights,
                        outputs_until_overflow, response_data, time_grid)

__all__ = ["flies", "flown_keys", "loop_delay", "build_profile", "close_flown_loop", "FlownManoeuvre", "Flight",
           "check_slew_limits", "wheel_words", "withheld_manoeuvre_metrics", "delay_facts",
           "pointing_figures", "MANOEUVRE_METRIC_LABELS", "ECSS_DEFINITIONS",
           "POINTING_METHODS"]

#: The metrics measured against the end of the profile, for the report.
MANOEUVRE_METRIC_LABELS = {
    "peak_attitude_error_during": "peak attitude error during the profile [rad]",
    "peak_torque_during": "peak torque during the profile [N m]",
    "residual_attitude_error": "residual attitude error after the profile [rad]",
    "residual_tip_deflection": "residual tip deflection after the profile [m]",
    "settling_time_after_end": "settling time after the end of the profile [s]",
}
#: The definitions the pointing figures follow.
ECSS_DEFINITIONS = (
    "ECSS-E-ST-60-10C sec. 3.2: APE(t) = e(t), the absolute performance error; MPE, the mean "
    "of e over a window; RPE(t) = e(t) - MPE of a window containing t (t {placement}); for a "
    "stationary zero-mean Gaussian error (annex A.1: temporal, ensemble and mixed "
    "interpretations coincide), each a standard deviation per axis, from the closed loop's "
    "exact stationary covariance under the sensor noise, no Monte Carlo ({method})")
#: How the pointing figures are computed, by loop.
POINTING_METHODS = {
    "continuous": "the continuous loop's Lyapunov equation",
    "sampled": "the sampled loop's discrete Lyapunov equation, at its samples",
    "spectral": "a continuous controller with a loop delay: the same statistics as integrals "
                "over the noise spectrum, exact in the delay (to 1e-9)"}


def flies(scene) -> bool:
    """True if the scene's manoeuvre is flown (module docstring), False for today's ideal
    step-reference slew."""
    m = scene.manoeuvre
    return m is not None and (m.flown or scene.wheels is not None
                              or scene.controller.total_delay > 0)


def flown_keys(scene) -> list[str]:
    """The scene's keys that ask for more than today's ideal slew (``controller.delay``,
    ``controller.computation_delay``, ``manoeuvre.profile``, ``manoeuvre.feedforward``,
    ``wheels``, ``sensors``), in that order."""
    m, c = scene.manoeuvre, scene.controller
    return [key for key, asked in (
        ("controller.delay", c.delay > 0), ("controller.computation_delay", c.computation_delay),
        ("manoeuvre.profile", m is not None and m.profile != "step"),
        ("manoeuvre.feedforward", m is not None and m.feedforward),
        ("wheels", scene.wheels is not None), ("sensors", scene.sensors is not None)) if asked]


def loop_delay(controller_spec) -> dict:
    """The scene's loop delay as keyword arguments of :func:`controllers.close_loop`,
    :func:`controllers.margins` and :func:`controllers.spillover` (called under
    :func:`~spacecraft.scene.specs.quiet_unit_slips`: the reader warned about a long delay by
    key)."""
    return {"delay": controller_spec.delay,
            "computation_delay": controller_spec.computation_delay}


def _midpoint(K, controller_spec) -> bool:
    """A continuous controller with a delay: its delayed loop is discrete on the step, its
    command held over each step (controllers.delay)."""
    return controller_spec.total_delay > 0 and not K.isdtime(strict=True)


def close_flown_loop(plant, K, scene) -> control.StateSpace:
    """The loop of ``plant`` and ``K`` with the scene's delay (:func:`controllers.close_loop`)."""
    c = scene.controller
    if c.total_delay == 0:
        return controllers.close_loop(plant, K)
    dt = scene.manoeuvre.step if (_midpoint(K, c) and scene.manoeuvre is not None) else None
    if dt is None and not K.isdtime(strict=True):
        # no manoeuvre: the loop's poles only, sampled finely enough for the delay
        dt = 2.0 * c.delay
    with quiet_unit_slips():
        return controllers.close_loop(plant, K, dt=dt, **loop_delay(c))


def _error(scene, key: str, message: str) -> SceneError:
    return SceneError(f"{scene.source}: {key}: {message}")


def _limits_words(m) -> str:
    parts = [f"manoeuvre.{name} = {value:.4g} {unit}" for name, value, unit in (
        ("torque_limit", m.torque_limit, "N m"),
        ("rate_limit", None if m.rate_limit is None else math.degrees(m.rate_limit), "deg/s"),
        ("jerk_limit", None if m.jerk_limit is None else math.degrees(m.jerk_limit),
         "deg/s^3")) if value is not None]
    return " and ".join(parts) if parts else "no limits"


def _base_kind(m) -> str:
    return m.shaper.base if m.profile == "shaped" else m.profile


def _inertia_words(inertia, axis) -> str:
    """The spacecraft's inertia about the slew axis, in words."""
    if axis is None:
        return f"the spacecraft's inertia {inertia:.6g} kg m^2"
    e = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return (f"the spacecraft's inertia {float(e @ np.asarray(inertia) @ e):.6g} kg m^2 about "
            "the slew axis")


def slew_axis(scene):
    """The unit eigen-axis of a three-axis scene's slew (hub axes), None for a planar one."""
    axis = scene.manoeuvre.slew_axis
    if axis is None:
        return None
    e = np.asarray(axis, dtype=float)
    return e / np.linalg.norm(e)


def check_slew_limits(scene, inertia, shaper_duration: float = 0.0) -> dict:
    """Refuse, by key, limits that cannot complete the slew in ``slew_time``.

    Parameters
    ----------
    scene : Scene
    inertia : float or ndarray (3, 3), kg m^2
        The spacecraft's rigid-body inertia: about the planar axis, or the tensor in hub axes
        (three axes: the slew is the eigen-axis one about ``manoeuvre.slew_axis``).
    shaper_duration : float, s
        What a shaper adds to the base profile (0 before the shaper is known).

    Returns
    -------
    dict
        ``profile_shortest_time`` [s] (the profile's limits; None for the step) and
        ``wheels_shortest_time`` [s] (the wheels' limits; None without wheels).

    Raises
    ------
    SceneError
        ``manoeuvre.slew_time`` shorter than either, the shortest time given.
    """
    m = scene.manoeuvre
    axis = slew_axis(scene)
    words = _inertia_words(inertia, axis)
    out = {"profile_shortest_time": None, "wheels_shortest_time": None}
    if m.profile != "step":
        base = _base_kind(m)
        shortest = controllers.minimum_time(
            base, m.slew_angle, inertia=inertia, torque_limit=m.torque_limit,
            rate_limit=m.rate_limit, jerk_limit=m.jerk_limit if base == "smooth" else None,
            axis=axis)
        shortest += shaper_duration
        out["profile_shortest_time"] = shortest
        if m.slew_time < shortest * (1.0 - 1e-12):
            shaper = (f" plus the {m.shaper.kind.upper()} shaper's {shaper_duration:.4g} s"
                      if shaper_duration > 0 else "")
            raise _error(scene, "manoeuvre.slew_time", f"{m.slew_time:g} s is too short for a "
                         f"{base} slew of {math.degrees(m.slew_angle):g} deg under "
                         f"{_limits_words(m)} ({words}):"
                         f" the shortest time they allow is {shortest:.6g} s{shaper}; lengthen "
                         "the slew or raise the limits")
    if scene.wheels is not None:
        wheels = scene.wheels.build()
        shortest = controllers.shortest_slew_time(wheels, m.slew_angle, inertia, axis=axis)
        out["wheels_shortest_time"] = shortest
        if m.slew_time < shortest * (1.0 - 1e-12):
            raise _error(scene, "manoeuvre.slew_time", f"{m.slew_time:g} s is too short for the "
                         f"wheels: their torque limit {_per_wheel_words(scene.wheels.torque_limit)}"
                         f" N m and momentum limit "
                         f"{_per_wheel_words(scene.wheels.momentum_limit)} N m s allow the "
                         f"{math.degrees(m.slew_angle):g} deg slew ({words}) in no less than "
                         f"{shortest:.6g} s; lengthen the "
                         "slew or raise wheels.torque_limit / wheels.momentum_limit")
    return out


def _per_wheel_words(value) -> str:
    """A wheel limit as given: one number, or one per wheel."""
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(f"{v:.4g}" for v in value) + "]"
    return f"{value:.4g}"


def build_profile(scene, design_plant, variant: str = "design"):
    """The scene's reference profile for the controllers tuned on one design model.

    Parameters
    ----------
    scene : Scene
    design_plant : control.StateSpace
        The design model's plant: its rigid-body inertia scales the feedforward torque and the
        torque limit, its lowest flexible modes are the ones a ``"shaped"`` profile cancels
        (three axes: the modes of the 3 x 3 channel torque -> theta, the slew the eigen-axis
        one about ``manoeuvre.slew_axis``).
    variant : str
        The design model's label (for messages).

    Returns
    -------
    profile : controllers.Profile
    facts : dict
        JSON-ready: ``kind``, ``feedforward``, ``inertia`` [kg m^2] (three axes: the 3 x 3
        tensor, hub axes), ``axis`` (three axes: the unit slew axis), ``end_time`` [s],
        ``peak_rate`` [rad/s], ``peak_acceleration`` [rad/s^2], ``peak_torque`` [N m] (of the
        feedforward, three axes the largest hub-axis component of J alpha_ref; None for the
        step), three axes ``gyroscopic_peak_torque`` [N m] (module docstring), ``reading`` (how the loop reads the profile:
        ``"samples"``, a digital controller; ``"linear"``, a continuous loop interpolating its
        samples; ``"held"``, a continuous controller's delayed loop), ``hold_error`` (per
        reference signal, the largest difference between the profile and its samples linearly
        interpolated, :meth:`controllers.Profile.hold_error`), the shortest
        times the profile's and the wheels' limits allow [s], and for a shaper its impulses,
        duration and modes (frequency [rad/s], damping ratio, the band of frequency ratios
        within which its residual vibration stays below the tolerance).

    Raises
    ------
    SceneError
        By key: limits that cannot fly the slew in slew_time, a design model with fewer
        flexible modes than the shaper asks for.
    """
    m = scene.manoeuvre
    J = controllers.rigid_body_inertia(design_plant)
    axis = slew_axis(scene)
    facts: dict = {"kind": m.profile, "feedforward": m.feedforward,
                   "inertia": J if axis is None else np.asarray(J).tolist(),
                   "end_time": m.slew_time}
    if axis is not None:
        facts["axis"] = axis.tolist()
    shaper = None
    if m.profile == "step":
        profile = controllers.step_reference(m.slew_angle, m.slew_time, axis=axis)
    else:
        if m.profile == "shaped":
            modes = controllers.flexible_modes(design_plant)
            if len(modes) < m.shaper.modes:
                raise _error(scene, "manoeuvre.shaper.modes", f"asks for {m.shaper.modes} "
                             f"modes, and the design model ({variant}) has {len(modes)} "
                             f"flexible mode{'s' * (len(modes) != 1)} the torque excites: "
                             "ask for at most that many")
            shaper = controllers.mode_shaper(modes[:m.shaper.modes], kind=m.shaper.kind)
        facts.update(check_slew_limits(scene, J, shaper.duration if shaper else 0.0))
        base = _base_kind(m)
        profile = controllers.reference_profile(
            m.profile, m.slew_angle, m.slew_time, inertia=J, torque_limit=m.torque_limit,
            rate_limit=m.rate_limit, jerk_limit=m.jerk_limit if base == "smooth" else None,
            shaper=shaper, base=base, axis=axis)
    c = scene.controller
    facts["reading"] = ("samples" if c.sample_time is not None else
                        "held" if c.total_delay > 0 else "linear")
    facts.update(
        end_time=profile.end_time, peak_rate=profile.peak_rate,
        peak_acceleration=profile.peak_acceleration,
        peak_torque=(None if m.profile == "step" else profile.peak_torque(J) if axis is None
                     else profile.peak_torque(J, gyroscopic=False)),
        hold_error=profile.hold_error(m.step, inertia=J if m.feedforward else None)
        if m.step <= profile.end_time else None)
    if axis is not None and m.profile != "step":
        # |e x J e| s'^2 at the peak rate: what a flight computer adds to the feedforward, and
        # what the plants linearised about rest do not have
        facts["gyroscopic_peak_torque"] = float(np.max(np.abs(np.cross(axis, J @ axis)))
                                                * profile.peak_rate ** 2)
    if shaper is not None:
        facts["shaper"] = {
            "kind": m.shaper.kind, "base": m.shaper.base, "duration": shaper.duration,
            "times": shaper.times.tolist(), "amplitudes": shaper.amplitudes.tolist(),
            "tolerance": m.shaper.tolerance, "frequency_error": m.shaper.frequency_error,
            "modes": [{"frequency": w, "damping_ratio": z,
                       "band": list(shaper.insensitivity(w, z, tolerance=m.shaper.tolerance))}
                      for w, z in shaper.modes]}
    return profile, facts


# --------------------------------------------------------------------------------------------
# one loop's flight
# --------------------------------------------------------------------------------------------
class Flight:
    """One loop's flown manoeuvre (:meth:`FlownManoeuvre.fly`).

    Attributes
    ----------
    loop : control.StateSpace
        The linear closed loop (with its delay): its poles judge the response.
    runs : dict
        ``"slew"`` (the slew; with wheels the whole manoeuvre) and ``"disturbance"`` (the
        disturbance alone; None with wheels or without one), control.TimeResponseData with
        ``diverged`` and ``diverged_at``; their inputs are the references and disturbances at
        the samples.
    wheels : controllers.WheelResponse or None
    profile_end : float, s
    """

    def __init__(self, loop, runs: dict, wheels, profile_end: float):
        self.loop = loop
        self.runs = runs
        self.wheels = wheels
        self.profile_end = profile_end


class FlownManoeuvre:
    """The scene's manoeuvre as flown, for one run (module docstring).

    Parameters
    ----------
    builder : spacecraft.design.models.ModelBuilder
        The run's models (``design_plant``, ``scene``, ``stats``, ``n_modes``).
    """

    def __init__(self, builder):
        self.builder = builder
        self.scene = builder.scene
        self._profiles: dict = {}

    # -- the reference ---------------------------------------------------------------------
    def profile(self, variant: str):
        """(Profile, facts) of a design variant, built once (:func:`build_profile`)."""
        if variant not in self._profiles:
            plant, _ = self.builder.design_plant(variant, self.builder.n_modes)
            self._profiles[variant] = build_profile(self.scene, plant, variant)
        return self._profiles[variant]

    def truth_residual(self, variant: str, truth_plant) -> list:
        """The shaper's residual vibration (a fraction of the unshaped profile's) at the truth
        model's modes nearest the shaped ones: what the design model's frequency error
        costs."""
        profile, facts = self.profile(variant)
        if profile.shaper is None:
            return []
        truth = controllers.flexible_modes(truth_plant)
        out = []
        for w, z in profile.shaper.modes:
            if not truth:
                break
            near = min(truth, key=lambda mode: abs(mode.frequency - w))
            out.append({"design_frequency": w, "truth_frequency": near.frequency,
                        "frequency_error": near.frequency / w - 1.0,
                        "residual_vibration": float(profile.shaper.residual_vibration(
                            near.frequency, near.damping_ratio))})
        return out

    # -- the flight ------------------------------------------------------------------------
    def fly(self, variant: str, plant, K, *, whole: bool = False) -> Flight:
        """Fly the manoeuvre on ``plant`` with ``K`` (tuned on ``variant``): module docstring.
        ``whole``: the slew and the disturbance together (as with wheels) in ``"slew"``."""
        scene, m = self.scene, self.scene.manoeuvre
        profile, facts = self.profile(variant)
        J = facts["inertia"]
        T = time_grid(m)
        held = m.step if _midpoint(K, scene.controller) else None
        stats = self.builder.stats
        if scene.wheels is not None:
            with quiet_unit_slips():
                wheel_loop = controllers.WheelLoop(plant, K, scene.wheels.build(), dt=held,
                                                   **loop_delay(scene.controller))
            labels = wheel_loop.inputs
            U_in = self._inputs(labels, profile, J, T, together=True, held=held)
            stats.simulations += 1
            run, k = _until_overflow(lambda n: wheel_loop.simulate(T[:n], U_in[:, :n]), T.size)
            U = U_in if held is None else self._inputs(labels, profile, J, T, together=True)
            Y = np.full((len(run.response.output_labels), T.size), np.inf)
            Y[:, :k] = np.asarray(run.response.outputs).reshape(-1, k)
            slew = _named_response(wheel_loop.linear_loop, T, U, Y, labels,
                                   list(run.response.output_labels), "manoeuvre")
            return Flight(wheel_loop.linear_loop, {"slew": slew, "disturbance": None}, run,
                          profile.end_time)
        loop = close_flown_loop(plant, K, scene)
        labels = list(loop.input_labels)
        if loop.isdtime(strict=True):
            def outputs(U_):
                return discrete_outputs(loop, T, U_)
        else:
            stats.simulator_setups += 1
            with self.builder.scene_values("manoeuvre.step"):
                simulator = controllers.Simulator(loop, m.step)

            def outputs(U_):
                return outputs_until_overflow(simulator, T, U_)
        runs = {"slew": None, "disturbance": None}
        for what in runs:
            alone = what == "disturbance"
            if alone and (m.disturbance is None or whole):
                continue
            stats.simulations += 1
            U_in = self._inputs(labels, profile, J, T, only_disturbance=alone, held=held,
                                together=whole)
            U = U_in if held is None else self._inputs(labels, profile, J, T,
                                                       only_disturbance=alone, together=whole)
            runs[what] = response_data(loop, T, U, outputs(U_in), what)
        return Flight(loop, runs, None, profile.end_time)

    def _inputs(self, labels, profile, J, T, *, together: bool = False,
                only_disturbance: bool = False, held: float | None = None) -> np.ndarray:
        """The loop's inputs at the samples T: the references it reads (not with
        ``only_disturbance``) and the disturbance (with ``together`` or ``only_disturbance``).

        ``held`` [s]: the step of a continuous controller's delayed loop, which samples its
        command at T and holds it, delayed by delay - step / 2 (:mod:`controllers.delay`): the
        references the controller reads are taken at T, the rate reference and the feedforward
        torque as their means over the step centred there, (s(t + h/2) - s(t - h/2)) / h and
        J (s'(t + h/2) - s'(t - h/2)) / h (exact impulses also across the jumps of a
        bang-coast-bang acceleration, where the sample would be off by a jump for up to half a
        step: O(h) where the mean is O(h^2)); the disturbance, held at the plant over each
        step, as its mean over each step [t, t + h) (exact impulses at its edges)."""
        U = np.zeros((len(labels), T.size))
        if not only_disturbance:
            wants_ff = any(name == controllers.signals.TORQUE_FF
                           or name.startswith(controllers.signals.TORQUE_FF + "_")
                           for name in labels)
            references = profile.references(T, J if wants_ff else None, gyroscopic=False)
            if held is not None:
                a, b = T - 0.5 * held, T + 0.5 * held
                rate = (profile.path(b) - profile.path(a)) / held
                if profile.axis is None:
                    references["omega_ref"] = rate
                    if wants_ff:
                        references["torque_ff"] = J * (profile.path(b, 1)
                                                       - profile.path(a, 1)) / held
                else:
                    e = profile.axis
                    Je = np.asarray(J, dtype=float) @ e
                    acceleration = (profile.path(b, 1) - profile.path(a, 1)) / held
                    for i, name in enumerate("xyz"):
                        references[f"omega_ref_{name}"] = e[i] * rate
                        if wants_ff:
                            references[f"torque_ff_{name}"] = Je[i] * acceleration
            for name, values in references.items():
                if name in labels:
                    U[labels.index(name)] = values
        if together or only_disturbance:
            D = (disturbance_inputs(labels, self.scene.manoeuvre, T) if held is None
                 else _held_pulse(labels, self.scene.manoeuvre, T, held))
            if D is not None:
                U = U + D
        return U

    # -- what the flight measures ----------------------------------------------------------
    def metrics(self, end: float, response) -> dict | None:
        """:func:`controllers.manoeuvre_metrics` of a response against the profile's end
        ``end`` [s] (None when the simulated time ends before it)."""
        t = np.asarray(response.t).reshape(-1)
        if end > time_grid(self.scene.manoeuvre)[-1]:
            return None
        with np.errstate(all="ignore"):
            if t[-1] < end:   # diverged before the end
                values = {name: None for name in MANOEUVRE_METRIC_LABELS}
                return {**values, "profile_end": end, "diverged": True,
                        "diverged_at": float(t[-1])}
            return controllers.manoeuvre_metrics(response, end)


    def record(self, row: dict, which: str, flight: Flight | None, response, status: dict,
               plant, K) -> None:
        """Add to a loop's row (``closed_loops`` of results.json) what the flight measured on
        the ``which`` model: ``manoeuvre_metrics`` and their flags, ``wheels`` (the
        wheels' summary with ``words``), ``pointing`` (:func:`pointing_figures`)."""
        scene = self.scene
        if response is not None:
            end = flight.profile_end if flight is not None else scene.manoeuvre.slew_time
            values = self.metrics(end, response)
            if values is not None:
                values, flags = withheld_manoeuvre_metrics(values, status)
                row.setdefault("manoeuvre_metrics", {})[which] = values
                row.setdefault("manoeuvre_flags", {})[which] = flags
        if flight is not None and flight.wheels is not None:
            summary = flight.wheels.summary()
            summary["words"] = wheel_words(summary, duration=float(
                np.asarray(flight.wheels.response.t)[-1]))
            row.setdefault("wheels", {})[which] = summary
        if scene.sensors is not None:
            self.builder.stats.pointing_analyses += 1
            row.setdefault("pointing", {})[which] = pointing_figures(plant, K, scene)

    def facts(self, truth_plant) -> dict:
        """JSON-ready: per design variant the profile's facts (:meth:`profile`, with the
        shaper's residual vibration on the truth model's modes), the delay, the wheels and the
        sensors as the run took them."""
        scene = self.scene
        out: dict = {"flown": flies(scene), "profiles": {}}
        for variant, (profile, facts) in self._profiles.items():
            entry = dict(facts)
            residual = self.truth_residual(variant, truth_plant)
            if residual:
                entry["truth_residual"] = residual
            out["profiles"][variant] = entry
        c = scene.controller
        out["delay"] = {"delay": c.delay, "computation_delay": c.computation_delay,
                        "total": c.total_delay}
        if scene.wheels is not None:
            wheels = scene.wheels.build()
            out["wheels"] = {"names": list(wheels.names),
                             "torque_limits": wheels.torque_limits.tolist(),
                             "momentum_limits": wheels.momentum_limits.tolist(),
                             "saturation": wheels.saturation,
                             "method": "exact between switching instants decided at the "
                                       "samples (controllers.wheel_loop): O(step^2) where the "
                                       "applied torque is continuous across a switch, O(step) "
                                       "where it jumps (the momentum limit, Coulomb friction)"}
        return out


    def warnings(self, data: dict) -> list[dict]:
        """The flight's design warnings (``code``, ``message``; ``design``, ``controller`` of a
        loop): ``wheel_saturation`` (a wheel reached a limit on the truth model),
        ``delay_destabilises`` (stable without the loop delay, unstable with it),
        ``shaper_residual`` (the shaper leaves more than its tolerance of vibration on a truth
        model's mode)."""
        from .naming import controller_label, design_label

        out = []
        scene = self.scene
        for row in data.get("closed_loops", []):
            who = (f"{controller_label(row['controller'])} tuned on "
                   f"{design_label(row['design'])}")
            tag = {"design": row["design"], "controller": row["controller"]}
            wheels = (row.get("wheels") or {}).get("truth")
            if wheels is not None and wheels["saturated"]:
                out.append({"code": "wheel_saturation", "message": f"{who}: {wheels['words']} "
                            "on the truth model: the loop is not the linear one its margins "
                            "describe while a limit acts; lower the slew's torque "
                            "(manoeuvre.torque_limit, a longer slew_time) or use larger wheels",
                            **tag})
            v = row["verdict"]
            if (scene.controller.total_delay > 0 and not v["stable"]
                    and row.get("undelayed_stable")):
                out.append({"code": "delay_destabilises", "message": f"{who} is stable without "
                            f"its loop delay and UNSTABLE with {scene.controller.total_delay:g}"
                            " s (at or beyond its delay margin): shorten the delay or lower "
                            "the bandwidth (a slower loop tolerates more delay)", **tag})
        for kind, entry in (data.get("basilisk") or {}).items():
            wheel = entry.get("wheel")
            if wheel is not None and wheel["saturated"]:
                out.append({"code": "wheel_saturation", "message": (
                    f"{controller_label(kind)} in Basilisk: {wheel['words']}: the run is not "
                    "the linear loop flexsat's margins describe while a limit acts; raise "
                    "simulator.reaction_wheel.max_torque / max_speed or slew slower"),
                    "controller": kind, "design": entry.get("design")})
        for variant, facts in (data.get("manoeuvre") or {}).get("profiles", {}).items():
            tolerance = (facts.get("shaper") or {}).get("tolerance")
            for r in facts.get("truth_residual", []):
                if tolerance is not None and r["residual_vibration"] > tolerance:
                    out.append({"code": "shaper_residual", "message": (
                        f"the shaper designed on {design_label(variant)} leaves "
                        f"{100 * r['residual_vibration']:.3g} % of the unshaped vibration of "
                        f"the truth model's mode at {r['truth_frequency']:.4g} rad/s (the design "
                        f"model has it at {r['design_frequency']:.4g} rad/s, "
                        f"{100 * r['frequency_error']:+.3g} %), over its tolerance "
                        f"{100 * tolerance:.3g} %: a better design model, or a more robust "
                        "shaper (manoeuvre.shaper.kind = 'zvd', frequency_error)"),
                        "design": variant})
        return out


def _held_pulse(labels, manoeuvre, T: np.ndarray, h: float) -> np.ndarray | None:
    """The disturbance pulse's mean over each step [t, t + h) (its amplitude times the part of
    the step it covers), as the input array of :func:`disturbance_inputs`."""
    d = manoeuvre.disturbance
    if d is None:
        return None
    labels = list(labels)
    end = math.inf if d.length is None else d.start + d.length
    covered = np.clip(np.minimum(T + h, end) - np.maximum(T, d.start), 0.0, h) / h
    D = np.zeros((len(labels), T.size))
    for name, weight in disturbance_weights(d).items():
        D[labels.index(name)] = weight * d.amplitude * covered
    return D


def _until_overflow(run, n: int):
    """``run(n)``; where it overflows (FloatingPointError), the longest prefix that does not
    (bisection): (result, number of samples)."""
    try:
        return run(n), n
    except FloatingPointError:
        pass
    good, bad, result = 2, n, None
    while bad - good > 1:
        mid = (good + bad) // 2
        try:
            result = run(mid)
            good = mid
        except FloatingPointError:
            bad = mid
    if result is None or np.asarray(result.response.t).size != good:
        result = run(good)
    return result, good


def _named_response(loop, T, U, Y, input_labels, output_labels, what: str):
    """A TimeResponseData with the given signal names, cut at its first non-finite sample."""
    finite = np.all(np.isfinite(Y), axis=0)
    k = T.size if finite.all() else max(int(np.argmin(finite)), 1)
    out = control.TimeResponseData(
        T[:k], Y[:, :k], None, U[:, :k], issiso=False, output_labels=list(output_labels),
        input_labels=list(input_labels), sysname=loop.name, title=f"{what} of {loop.name}",
        trace_types=["forced"], plot_inputs=True, squeeze=False)
    out.diverged = k < T.size
    out.diverged_at = float(T[k - 1]) if k < T.size else None
    return out


def withheld_manoeuvre_metrics(values: dict, status: dict) -> tuple[dict, dict]:
    """The manoeuvre metrics to report under a loop's status, and the flags of those withheld
    (as :func:`spacecraft.design.verdicts.withheld_metrics` does for today's)."""
    values, flags = dict(values), {}
    kind = status["status"]
    if kind in ("diverges", "unstable"):
        for name in MANOEUVRE_METRIC_LABELS:
            if name in values:
                values[name] = None
                flags[name] = "diverges"
    elif values.get("settling_time_after_end") is None and "settling_time_after_end" in values:
        flags["settling_time_after_end"] = "not settled"
    values.pop("diverged_at", None)
    values["diverged"] = kind in ("diverges", "unstable")
    return values, flags


def wheel_words(summary: dict, *, duration: float) -> str:
    """One sentence on a wheel run (:meth:`controllers.WheelResponse.summary`): whether a wheel
    saturated, which limit, for how long and from when, and the momentum margin."""
    margins = summary["momentum_margin"]
    fractions = summary["momentum_margin_fraction"]
    name = min(margins, key=lambda n: -math.inf if margins[n] is None else margins[n])
    margin, fraction = margins[name], fractions[name]
    margin_text = ("momentum margin unlimited" if margin is None else
                   f"momentum margin {margin:.3g} N m s ({100 * fraction:.3g} % of the limit"
                   + (f", {name}" if len(margins) > 1 else "") + ")")
    if not summary["saturated"]:
        return f"no wheel reached a limit; {margin_text}"
    parts = []
    for limit, key in (("torque", "time_torque_saturated"),
                       ("momentum", "time_momentum_saturated")):
        for wheel, t in summary[key].items():
            if t > 0:
                who = f"{wheel} " if len(summary[key]) > 1 else ""
                parts.append(f"{who}{limit} limit for {t:.3g} s")
    return (f"the wheels SATURATED from t = {summary['first_saturation']:.4g} s: "
            + ", ".join(parts or ["a limit at one sample"])
            + f" ({summary['time_saturated']:.3g} s of {duration:g} s saturated in all); "
            + margin_text)


def delay_facts(margins) -> dict:
    """The loop's delay [s] and its delay margin [s] (the extra delay it tolerates; for a loop
    the delay destabilised, 0 or minus how far the delay lies beyond the destabilising one)
    from :class:`controllers.Margins` (None where a margin object has none)."""
    return {"delay": getattr(margins, "delay", None),
            "delay_margin": getattr(margins, "delay_margin", None)}


def pointing_figures(plant, K, scene) -> dict:
    """The pointing figures of a loop under the scene's sensor noise (:func:`controllers.pointing`):
    ``ape``, ``mpe``, ``rpe`` per attitude output [rad], ``jitter``, ``jitter_mpe``,
    ``jitter_rpe`` per tip output [m] (1 sigma), the same at ``probability`` (``at``, with
    ``factor``), ``window`` [s], ``placement``, ``sampled``, ``definitions``; or ``error``
    (e.g. an unstable loop has no stationary pointing error), with ``not_computed`` True for
    a stable loop whose figures could not be computed to their accuracy (the error says why)."""
    s = scene.sensors
    tips = tip_outputs(list(plant.output_labels))
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings(), quiet_unit_slips():
            warnings.simplefilter("ignore", RuntimeWarning)
            budget = controllers.pointing(plant, K, s.noise(), window=s.rpe_window,
                                          placement=s.placement, outputs=tips,
                                          **loop_delay(scene.controller))
    except PointingNotComputed as exc:    # a stable loop whose figures missed their accuracy
        return {"error": " ".join(str(exc).split()), "not_computed": True,
                "window": s.rpe_window, "placement": s.placement}
    except ValueError as exc:
        return {"error": " ".join(str(exc).split()), "window": s.rpe_window,
                "placement": s.placement}
    at = budget.at(s.probability)
    return {"ape": budget.ape, "mpe": budget.mpe, "rpe": budget.rpe, "jitter": budget.jitter,
            "jitter_mpe": budget.jitter_mpe, "jitter_rpe": budget.jitter_rpe,
            "probability": s.probability, "at": at, "window": budget.window,
            "placement": budget.placement, "sampled": budget.sampled,
            "definitions": ECSS_DEFINITIONS.format(
                placement="uniform in its window" if budget.placement == "random"
                else "at its window's end",
                method=POINTING_METHODS["sampled" if budget.sampled else
                                        "spectral" if scene.controller.total_delay > 0
                                        else "continuous"])}
