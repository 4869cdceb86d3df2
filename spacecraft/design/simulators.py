"""The scene's manoeuvre in another simulator: Basilisk (``simulator.name = "basilisk"`` or
``flexsat run --simulator basilisk``).

For each controller tuned on the first design model, :func:`basilisk_runs` runs the scene's
slew (and disturbance) in Basilisk through :func:`spacecraft.basilisk.slew_comparison`: the
design chains as hinged bodies on the hub, the controller as flight software at the simulator's
sample time (the controller's own when digital), and beside it flexsat's two linear predictions
of the same sampled-data loop: on the linear hub + chains and on the scene's truth plant (the
distributed beams, truncated to the modes the scene's tolerance needs). The differences answer:

- Basilisk - truth: what modelling the appendage as a hinged chain costs a Basilisk user (the
  chain against the distributed beam);
- Basilisk - linear chain: the nonlinearity of the manoeuvre (large hinge angles, the hub's
  finite rotation), plus RK4's error.

Basilisk's results are JSON-ready in ``data["basilisk"]`` (results.json), its responses beside
flexsat's in the report, the slew plot and the time series.

A three-axis scene runs the same way, branching only where the physics does: each 3-D chain
joint as two bending hinges and a torsion hinge (:mod:`spacecraft.basilisk.layout`), the
controller as three-axis flight software, the eigen-axis slew about ``manoeuvre.slew_axis``,
the signals per axis (``theta_x/_y/_z``...) and per tip motion (``<name>_tip_deflection_y``,
``_z``, ``<name>_tip_twist``), a reaction wheel as one such wheel on each hub axis.

Without ``simulator.sample_rate``, a continuous controller's flight-software rate is chosen
(:func:`spacecraft.basilisk.default_sample_time`) on the loop Basilisk flies: the chains as it
holds them (three axes: inextensible), so a chain's axial spring, held rigid, asks for no rate
(an undamped one, which an explicit chain may have, would ask for thousands of samples a
second).

Stiff chains: without ``simulator.dt`` the run is sized to what the flight software can act on.
A chain's torsion whose first frequency (root held) is above the flight software's sampling
frequency 2 pi / T is held rigid, in Basilisk and in the linear chain compared alike, and what
that costs is measured on flexsat's linear chains (``held_vs_chain``); the RK4 step resolves
the modes up to the Nyquist frequency pi / T and keeps the others stable with a margin
(:func:`spacecraft.basilisk.dynamics_step`, ``accurate_up_to``). The report says both
(``notes``). A scene that gives ``simulator.dt`` runs every torsion free at that step.

Before Basilisk runs, the scene's flight-software rate and RK4 step are checked against what
the comparison needs and Basilisk integrates accurately, and refused by scene key
(``simulator.sample_rate``, ``simulator.dt``, ``limits.basilisk_seconds``): a rate below the
sampled loop's rule (:func:`controllers.pd.check_sample_time`) or giving fewer than
:data:`MIN_SAMPLES` samples, a step that does not divide the sample time or lies beyond RK4's
stability limit for the chain's highest mode (a step past :data:`ACCURATE_STEP` is warned
about: RK4's phase error there is (w dt)**5 / 120 per step), a run estimated to take longer
than the limit. A reaction wheel that spins faster than :data:`WHEEL_SPEED_WARNING` is warned
about by key (``simulator.reaction_wheel.spin_inertia``): no real wheel does.
"""

from __future__ import annotations

import functools
import math
import warnings

import numpy as np

__all__ = ["basilisk_runs", "basilisk_disturbances", "summary", "basilisk_wheel_summary",
           "peak_difference_text", "step_notes",
           "SIGNALS", "MIN_SAMPLES", "ACCURATE_STEP", "WHEEL_SPEED_WARNING"]

#: Signals compared, in the report's order (those both responses have).
SIGNALS = ("theta", "omega", "torque")
#: Fewest flight-software samples a comparison is made on (two samples compared the initial
#: and one late state, and called the runs equal).
MIN_SAMPLES = 20
#: w_max * dt above which a user's RK4 step is warned about: RK4's phase error per step on the
#: highest mode is (w dt)**5 / 120 (8e-3 rad at 1), its numerical damping (w dt)**5 / 144;
#: the default step has w_max dt <= 1/2 (:mod:`spacecraft.basilisk.simulation`).
ACCURATE_STEP = 1.0
#: Peak wheel speed [rad/s] above which a reaction wheel is warned about (about 95,000 rpm,
#: ten times the fastest reaction wheels flown, 6,000-10,000 rpm).
WHEEL_SPEED_WARNING = 1e4


def basilisk_disturbances(manoeuvre) -> dict | None:
    """The scene's disturbance pulse as Basilisk inputs: name -> f(t) (None without one); three
    axes, a torque or force along ``axis`` as its components on the hub axes
    (:func:`spacecraft.design.responses.disturbance_weights`)."""
    from .responses import disturbance_weights

    d = manoeuvre.disturbance
    if d is None:
        return None
    end = np.inf if d.length is None else d.start + d.length

    def pulse(t, start=d.start, end=end, amplitude=d.amplitude, weight=1.0):
        t = np.asarray(t, dtype=float)
        return np.where((t >= start) & (t < end), weight * amplitude, 0.0)
    return {name: functools.partial(pulse, weight=weight)
            for name, weight in disturbance_weights(d).items()}


def _differences(comparison) -> dict:
    out = {}
    for which, table in comparison.differences.items():
        out[which] = {name: dict(values) for name, values in table.items()}
    return out


def _scene_error(scene, key: str, message: str):
    from ..scene.read import SceneError

    return SceneError(f"{scene.source}: {key}: {message}")


def _checked_steps(scene, plant, controller, kind: str, spacecraft) -> float:
    """The flight-software sample time of a run, with the scene's rate and RK4 step checked
    (module docstring); SceneError naming the key."""
    from controllers.pd import check_sample_time

    from ..basilisk import chain_spacecraft, default_sample_time, dynamics_step

    m, sim = scene.manoeuvre, scene.simulator
    digital = controller.dt not in (None, 0, True)
    given = sim.sample_time is not None
    # the loop Basilisk flies: its chains as it holds them (three axes: axial motion rigid,
    # so an undamped axial spring of a chain asks for no rate)
    flown = chain_spacecraft(spacecraft)
    if flown is not spacecraft:
        plant = flown.plant(prune=True)
    T = sim.sample_time or default_sample_time(plant, controller)
    source = ("simulator.sample_rate" if given and not digital else
              "the controller's sample rate" if digital else
              f"flexsat's default for this loop, {default_rate_note()}")
    if given and not digital:
        try:
            check_sample_time(T, plant, controller)
        except ValueError as exc:
            raise _scene_error(scene, "simulator.sample_rate", f"{1.0 / T:.6g} Hz (sample time "
                               f"{T:.6g} s) cannot run the {kind} loop as flight software: "
                               f"{str(exc).removeprefix('sample time: ')}; raise the rate, or remove simulator.sample_rate for "
                               f"{default_rate_note()}") from None
    n_samples = int(math.floor(m.duration / T + 1e-9)) + 1
    if n_samples < MIN_SAMPLES:
        key = "simulator.sample_rate" if given else "manoeuvre.duration"
        raise _scene_error(scene, key, f"the Basilisk run would be compared on {n_samples} "
                           f"flight-software samples (manoeuvre.duration {m.duration:g} s at a "
                           f"sample time of {T:.6g} s, {source}); a comparison needs at least "
                           f"{MIN_SAMPLES}: raise the rate or lengthen the manoeuvre")
    if sim.dt is not None:
        # the modes Basilisk integrates (three axes: its chains, axial motion held)
        modes = flown.modes()[0]
        w_max = float(np.max(modes)) if np.size(modes) else 0.0
        try:
            dynamics_step(w_max, T, sim.dt)
        except ValueError as exc:
            raise _scene_error(scene, "simulator.dt", f"{exc} (sample time from {source})"
                               ) from None
        if w_max * sim.dt > ACCURATE_STEP:
            y = w_max * sim.dt
            warnings.warn(
                f"simulator.dt = {sim.dt:g} s gives w*dt = {y:.3g} on the chain's highest mode "
                f"{w_max:.4g} rad/s: RK4's phase error there is about {y**5 / 120:.2g} rad per "
                f"step, so Basilisk's run differs from flexsat's by integration error too; the "
                f"default step has w*dt <= 0.5 (remove simulator.dt)", UserWarning, stacklevel=2)
    return T


def default_rate_note() -> str:
    from ..basilisk import SAMPLES_PER_CROSSOVER

    return (f"{SAMPLES_PER_CROSSOVER:g} samples per period of the loop's fastest crossover or "
            "controller pole")


def _check_wheel_speed(scene, response) -> None:
    """Warn, by key, about a wheel spinning faster than any real one."""
    labels = list(response.output_labels)
    rows = [k for k, name in enumerate(labels) if name.startswith("wheel_speed")]
    if not rows:
        return
    peak = float(np.max(np.abs(np.asarray(response.outputs)[rows])))
    if peak > WHEEL_SPEED_WARNING:
        J = scene.simulator.reaction_wheel.spin_inertia
        warnings.warn(
            f"simulator.reaction_wheel.spin_inertia = {J:g} kg m^2 spins the wheel up to "
            f"{peak:.3g} rad/s ({peak * 30 / math.pi:.3g} rpm) in this manoeuvre, beyond any "
            f"real reaction wheel (6,000-10,000 rpm); a wheel storing the same momentum at "
            f"{WHEEL_SPEED_WARNING:g} rad/s has {J * peak / WHEEL_SPEED_WARNING:.3g} kg m^2: "
            "check the unit of spin_inertia [kg m^2]", UserWarning, stacklevel=2)


def _wheel_signals(response) -> list:
    """(wheel name, speed signal, torque signal) of each Basilisk wheel in ``response``: the
    planar wheel ``"wheel"``, or three axes one wheel per hub axis, ``"wheel_x"``..."""
    labels = list(response.output_labels)
    if "wheel_speed" in labels:
        return [("wheel", "wheel_speed", "torque")]
    return [(f"wheel_{a}", f"wheel_speed_{a}", f"torque_{a}") for a in "xyz"
            if f"wheel_speed_{a}" in labels]


def basilisk_wheel_summary(response, wheel) -> dict | None:
    """Basilisk's reaction wheel in the words and numbers of flexsat's wheels
    (:meth:`controllers.WheelResponse.summary`, :func:`spacecraft.design.manoeuvre.wheel_words`).

    From the run's ``wheel_speed`` [rad/s] and the flight software's ``torque`` request [N m]
    at its samples, as Basilisk's reactionWheelStateEffector applies them: the torque limit acts
    where |request| > max_torque (the motor torque is clipped), the speed limit where |Omega| >=
    max_speed and the request would spin the wheel further (request x Omega < 0: the wheel's
    momentum changes at minus the hub torque); each sample's state lasts until the next.
    Momentum J_s Omega [N m s], its limit J_s max_speed. Three axes: the triad's wheels
    ``wheel_x``, ``wheel_y``, ``wheel_z`` (``wheel_speed_x`` with ``torque_x``...), each with
    the same limits.

    Parameters
    ----------
    response : control.TimeResponseData
        Basilisk's run (outputs ``wheel_speed``, ``torque``; three axes per axis).
    wheel : spacecraft.scene.specs.ReactionWheelSpec

    Returns
    -------
    dict or None
        The summary's fields per wheel (``"wheel"``; three axes ``"wheel_x"``...), and
        ``words``; None without a wheel speed in the response.
    """
    from .manoeuvre import wheel_words
    from .responses import trace

    signals = _wheel_signals(response)
    if not signals:
        return None
    t = np.asarray(response.t, dtype=float).reshape(-1)
    dt = np.diff(t)
    torque_limit = math.inf if wheel.max_torque is None else wheel.max_torque
    speed_limit = math.inf if wheel.max_speed is None else wheel.max_speed
    limit = wheel.spin_inertia * speed_limit

    def held(flags):
        return float(np.sum(dt[flags[:-1]]))

    fields = ("time_torque_saturated", "time_momentum_saturated", "peak_momentum",
              "momentum_margin", "momentum_margin_fraction", "peak_torque")
    summary = {name: {} for name in fields}
    any_flag = np.zeros(t.size, dtype=bool)
    for name, speed_signal, torque_signal in signals:
        speed, request = trace(response, speed_signal), trace(response, torque_signal)
        if speed is None or request is None:
            return None
        at_torque = np.abs(request) > torque_limit
        at_speed = (np.abs(speed) >= speed_limit * (1 - 1e-9)) & (request * speed < 0)
        applied = np.where(at_speed, 0.0, np.clip(request, -torque_limit, torque_limit))
        peak = float(np.max(wheel.spin_inertia * np.abs(speed)))
        any_flag |= at_torque | at_speed
        summary["time_torque_saturated"][name] = held(at_torque)
        summary["time_momentum_saturated"][name] = held(at_speed)
        summary["peak_momentum"][name] = peak
        summary["momentum_margin"][name] = None if math.isinf(limit) else limit - peak
        summary["momentum_margin_fraction"][name] = (None if math.isinf(limit)
                                                     else (limit - peak) / limit)
        summary["peak_torque"][name] = float(np.max(np.abs(applied)))
    first = np.flatnonzero(any_flag)
    summary = {"saturated": bool(first.size),
               "first_saturation": float(t[first[0]]) if first.size else None,
               "time_saturated": held(any_flag), **summary}
    summary["words"] = wheel_words(summary, duration=float(t[-1]))
    return summary


def basilisk_runs(runner, designs: dict, truth_sim) -> tuple[dict, dict]:
    """Run the manoeuvre in Basilisk for every controller of the first design model.

    Parameters
    ----------
    runner : spacecraft.DesignLoop
        The design loop (its ``scene`` and ``stats``).
    designs : dict
        The loop's designs (variant -> ``spacecraft``, ``plant``, ``controllers``...); planar
        or three-axis, as the spacecraft is.
    truth_sim : control.StateSpace
        The truth plant (tip deflections when the scene asks for them).

    Returns
    -------
    comparisons : dict
        Controller kind -> :class:`spacecraft.basilisk.SlewComparison`.
    data : dict
        JSON-ready, per controller kind: ``design`` (the variant simulated), ``bsk_version``,
        ``sample_time`` [s], ``dt`` [s], ``seconds`` (Basilisk's build and run wall time),
        ``out_of_plane`` (None in three axes, where the motion has no plane),
        ``differences`` (``basilisk_vs_truth``, ``basilisk_vs_chain``, ``chain_vs_truth``: per
        signal ``peak``, ``peak_difference``, ``relative``), ``truth`` (what the truth model
        is, :func:`truth_label`), ``summary`` (:func:`summary`), with a reaction wheel
        ``wheel`` (:func:`basilisk_wheel_summary`), and where Basilisk's chains differ from the
        design chains ``chains_as_held`` (per appendage: the motions ``held`` rigid and the
        ``axial_frequency`` left out [rad/s], the ``raised_inertias``; see
        :mod:`spacecraft.basilisk.layout`).

    Raises
    ------
    SceneError
        A flight-software rate, RK4 step or run time the scene cannot have (module docstring),
        naming the key.
    spacecraft.basilisk.BasiliskNotInstalled
        Without the ``bsk`` package (one line: how to install the extra).
    """
    from ..basilisk import BasiliskRunTooLong, ReactionWheel, require_basilisk, slew_comparison
    from ..basilisk.simulation import largest_stable_step

    version = require_basilisk()
    scene = runner.scene
    m, sim = scene.manoeuvre, scene.simulator
    variant = next(iter(designs))
    d = designs[variant]
    three_axis = bool(d["spacecraft"].three_axis)
    axis = tuple(m.slew_axis) if three_axis else None
    wheel = None
    if sim.reaction_wheel is not None:
        w = sim.reaction_wheel
        wheel = ReactionWheel(w.spin_inertia, max_torque=w.max_torque, max_speed=w.max_speed)
    comparisons, data = {}, {}
    for kind, K in d["controllers"].items():
        runner.stats.basilisk_runs += 1
        # the scene's rate, else the controller's own (digital), else 30 samples per period
        # of the loop's fastest crossover or the controller's fastest pole
        sample_time = _checked_steps(scene, d["plant"], K, kind, d["spacecraft"])
        # without a step from the scene: what the flight software can act on (module docstring)
        sized = {} if sim.dt is not None else {"rigid_above": 2.0 * math.pi / sample_time,
                                               "accurate_up_to": math.pi / sample_time}
        try:
            comparison = slew_comparison(
                d["spacecraft"], K, m.slew_angle, m.slew_time, duration=m.duration,
                sample_time=sample_time, dt=sim.dt, truth_plant=truth_sim,
                disturbances=basilisk_disturbances(m), reaction_wheel=wheel,
                max_seconds=scene.limits.basilisk_seconds, axis=axis, **sized)
        except BasiliskRunTooLong as exc:
            # the longest step RK4 keeps stable on the highest mode (which a slow manoeuvre
            # barely excites), when it is longer than the run's
            longest = (largest_stable_step(exc.highest_frequency, sample_time)
                       if exc.highest_frequency else None)
            step = (f", a longer RK4 step (simulator.dt up to {longest:.9g} s, the largest "
                    "stable one on the highest mode"
                    + ("; the default holds stiff torsion rigid and resolves only the modes the "
                       "flight software acts on" if sim.dt is not None else "") + ")"
                    if longest and longest > exc.step * (1 + 1e-9) else "")
            raise _scene_error(scene, "simulator.name", f"{exc.work}, over the limit "
                               f"{exc.limit:g} s (limits.basilisk_seconds, estimated wall time "
                               "of a Basilisk run); use design chains with fewer or softer "
                               f"bodies{step} or a shorter manoeuvre.duration, or if you really "
                               "want it raise the limit: [limits] basilisk_seconds = N in the "
                               "scene, or --limit basilisk_seconds=N") from None
        comparisons[kind] = comparison
        b = comparison.basilisk
        _check_wheel_speed(scene, b.response)
        differences = _differences(comparison)
        truth = truth_label(scene)
        data[kind] = {"design": variant, "bsk_version": version, "sample_time": b.sample_time,
                      "dt": b.dt, "seconds": dict(b.seconds),
                      # a three-axis run moves in every direction: no out-of-plane figure
                      "out_of_plane": None if three_axis else b.out_of_plane,
                      "differences": differences, "truth": truth,
                      "summary": summary(differences, truth)}
        held = {a.name: {"held": list(a.held), "axial_frequency": a.axial_frequency,
                         "torsion_frequency": a.torsion_frequency,
                         "raised_inertias": [list(r) for r in a.raised_inertias]}
                for a in b.layout.appendages if a.held or a.raised_inertias}
        data[kind]["highest_frequency"] = b.highest_frequency
        data[kind]["notes"] = step_notes(b, sim.dt is not None, differences)
        if held:
            # what Basilisk's chains (and the linear chain compared) hold differently from the
            # design chains (spacecraft.basilisk.layout: axial motion, moments of a body)
            data[kind]["chains_as_held"] = held
        if sim.reaction_wheel is not None:
            # (a name of its own: ``wheel`` is the next controller's wheel too)
            wheels = data[kind]["wheel"] = basilisk_wheel_summary(b.response, sim.reaction_wheel)
            if wheels is not None and wheels["saturated"]:
                data[kind]["summary"] += (f"; Basilisk's wheel: {wheels['words']} (flexsat's "
                                          "linear predictions have no wheel: the differences "
                                          "are mostly the wheel's limits, not the chain's "
                                          "nonlinearity)")
    return comparisons, data


def step_notes(result, given: bool, differences: dict) -> list:
    """Sentences for the report: the RK4 step of a Basilisk run against the chain's modes
    (``result``, a :class:`spacecraft.basilisk.BasiliskResult`; ``given``: the scene's
    ``simulator.dt``), and every torsion held rigid with what holding it costs
    (``differences["held_vs_chain"]``)."""
    from ..basilisk.simulation import DEFAULT_STEP_FACTOR, RK4_STABILITY_LIMIT

    w, dt, T = result.highest_frequency, result.dt, result.sample_time
    y = w * dt
    where = "simulator.dt" if given else "the default"
    notes = [f"RK4 step {dt:.4g} s ({where}): w dt = {y:.3g} on the chain's highest mode "
             f"{w:.4g} rad/s, inside RK4's stability limit 2 sqrt(2) = "
             f"{RK4_STABILITY_LIMIT:.3g} (Hairer & Wanner, Solving ODEs II, sec. IV.2)"]
    if y > DEFAULT_STEP_FACTOR:
        notes[0] += (f"; modes up to {DEFAULT_STEP_FACTOR / dt:.4g} rad/s are resolved "
                     f"accurately (w dt <= {DEFAULT_STEP_FACTOR:g}), those above, beyond the "
                     f"flight software's Nyquist frequency {math.pi / T:.4g} rad/s, are "
                     "integrated stably but damped numerically (their quasi-static response "
                     "is kept, their ringing after each torque step is not); give "
                     f"simulator.dt <= {DEFAULT_STEP_FACTOR / w:.3g} s to resolve every mode")
    else:
        notes[0] += f": every mode resolved accurately (w dt <= {DEFAULT_STEP_FACTOR:g})"
    held = [a for a in result.layout.appendages if "torsion" in a.held]
    if held:
        which = ", ".join(f"{a.name} (first torsion mode {a.torsion_frequency:.4g} rad/s)"
                          for a in held)
        cost = differences.get("held_vs_chain", {})
        twists = {f"{a.name}_tip_twist" for a in held}
        rest = {n: e for n, e in cost.items() if n not in twists and e["relative"] is not None}
        worst = max(rest, key=lambda n: rest[n]["relative"]) if rest else None
        sentence = (f"Torsion held rigid in Basilisk and in the linear chain compared: {which}, "
                    f"above the flight software's sampling frequency {2 * math.pi / T:.4g} "
                    "rad/s")
        if worst is not None:
            sentence += (f"; holding it changes flexsat's linear chain by at most "
                         f"{100 * rest[worst]['relative']:.2g} % of a signal's peak ({worst})")
        for name in sorted(twists & set(cost)):
            sentence += (f"; {name} is not simulated (its peak on the free linear chain "
                         f"{cost[name]['peak']:.3g} rad)")
        notes.append(sentence + "; give simulator.dt to run every torsion free")
    return notes


def peak_difference_text(entry, *, short: bool = False) -> str:
    """A peak difference of :func:`spacecraft.basilisk.compare` (``entry``, or None) in words:
    the difference and its share of the reference's peak, or, where it exceeds that peak (a
    motion the reference barely has, e.g. a tip twist that only Basilisk's nonlinear
    kinematics makes in a slew about the bending axes), the reference's peak itself: a share
    of millions of per cent says nothing the two numbers do not say better. ``short``: for a
    table whose heading says what the share is of."""
    if entry is None:
        return "n/a"
    difference = f"{entry['peak_difference']:.3g}"
    if entry["relative"] is None or entry["relative"] > 1.0:
        return f"{difference} ({'peak' if short else 'above its peak there,'} {entry['peak']:.3g})"
    return f"{difference} ({100.0 * entry['relative']:.3g} %{'' if short else ' of its peak'})"


def truth_label(scene) -> str:
    """What the scene's truth model is, for a sentence: ``"the distributed beam (truth)"``,
    ``"the 20-body truth chain"``, or both kinds for a mix."""
    beams = [a for a in scene.appendages if a.truth == "beam"]
    if len(beams) == len(scene.appendages):
        return ("the distributed beam (truth)" if len(beams) == 1
                else "the distributed beams (truth)")
    if not beams:
        sizes = sorted({_truth_bodies(a) for a in scene.appendages})
        if len(sizes) == 1:
            chains = "chain" if len(scene.appendages) == 1 else "chains"
            return f"the {sizes[0]}-body truth {chains}"
        return "the truth chains"
    return "the truth model (beams and chains)"


def _truth_bodies(spec) -> int:
    chain = spec.truth_chain or spec.chain
    return chain.n_bodies if chain.from_beam is not None else len(chain.lengths)


def _unit(name: str) -> str:
    """The unit of a compared signal, for a sentence."""
    if name.startswith("theta") or name.endswith("_tip_twist"):
        return "rad"
    return "m"


def summary(differences: dict, truth_name: str = "the distributed beam (truth)") -> str:
    """One sentence: how far Basilisk's nonlinear chain is from flexsat's truth model (named by
    ``truth_name``, :func:`truth_label`) and from flexsat's linear chain, in the attitude and the
    tip motions (planar: ``theta`` and the tip deflections; three axes: ``theta_x/_y/_z``, the
    tip deflections in both planes and the tip twists)."""
    truth = differences.get("basilisk_vs_truth", {})
    chain = differences.get("basilisk_vs_chain", {})
    attitude = [n for n in ("theta", "theta_x", "theta_y", "theta_z") if n in chain]
    tips = sorted(n for n in chain if n.endswith(("_tip_deflection", "_tip_deflection_y",
                                                  "_tip_deflection_z", "_tip_twist")))
    parts = [f"{name} [{_unit(name)}] differs from {truth_name} by "
             f"{peak_difference_text(truth.get(name))} and from the linear chain by "
             f"{peak_difference_text(chain.get(name))}"
             for name in attitude + tips]
    return "; ".join(parts) if parts else "no common signals"
