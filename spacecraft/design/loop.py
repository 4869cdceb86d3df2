"""The design loop: from a spacecraft's models to tuned controllers, closed loops and verdicts.

:class:`DesignLoop` is the one evaluator of flexsat's design loop; :func:`run` (a scene, as
``flexsat run`` runs it), the sweeps (:mod:`spacecraft.sweep`, one evaluation per sample) and
a Python user with Spacecraft objects of their own all go through it. For a spacecraft and a
controller specification it gives:

- the models (truth: distributed beams truncated to the modes the scene's tolerance needs, or
  chains; design: chains fitted to the beams; :mod:`spacecraft.design.models`), or the
  user's own truth, design and exact :class:`~spacecraft.Spacecraft` objects;
- the controllers tuned on each design model with their gains (:mod:`spacecraft.design.tuning`);
- per controller, the closed loops on the design and the truth model, the slew (and
  disturbance) responses with their metrics, the margins on the design model, the verdict and
  margins on the truth model, the exact beam's verdict when asked
  (:mod:`spacecraft.design.responses`, :mod:`spacecraft.design.verdicts`): a
  :class:`ClosedLoops` each;
- the design warnings, optionally Basilisk's run of the same manoeuvre
  (:mod:`spacecraft.design.simulators`) and the equivalence tables, all in a
  :class:`RunResult`. The report (:mod:`spacecraft.report.write`) writes files from it; FMUs
  and plots are built there.

Nothing the specification does not ask for is built. :class:`RunStats` counts the work the code
did (FMU builds, plots, exact-beam evaluations, LQR designs, simulations, modes kept and
dropped...), so tests can prove each skip. Expensive results are cached within a loop: one
chain fit per (beam, criterion), one Spacecraft (one eigen-decomposition) per model set, one
plant per signal set, one simulator (matrix exponential) per closed loop.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping
from pathlib import Path

import control
import numpy as np

import controllers
from controllers.threads import blas_threads_for

from ..dynamics.survey import modal_survey
from ..scene.limits import estimate_cost, library_limits
from ..scene.read import Scene, load_scene, models_scene, scene_dict
from .manoeuvre import (FlownManoeuvre, check_slew_limits, close_flown_loop, delay_facts,
                        flies)
from .models import ModelBuilder, ProgressCallback, RunStats
from .naming import MOTION_WORDS, plural
from .responses import appendage_peaks, diverged_at, simulate_manoeuvre, trace
from .tables import describe_model, equivalence_table
from .tuning import digital_facts, rigid_crossover
from .verdicts import (closed_loop_poles, crossover_frequencies, design_warnings, growing,
                       loop_status, margin_flags, margins_dict, resolved_frequency,
                       verdict_dict, withheld_metrics)

__all__ = ["DesignLoop", "ClosedLoops", "RunResult", "RunStats", "run", "warning_lines",
           "input_warning_lines", "check_options", "unmodelled_outputs"]

#: Coupled modes of the open-loop truth model in the report's modal table (from the lowest).
MODAL_TABLE_MODES = 12

# Most distinct warnings kept in a run's results.
_MAX_WARNINGS = 20


@dataclasses.dataclass
class RunResult:
    """Everything a run of the design loop produced.

    Attributes
    ----------
    scene : Scene
        The question (for a Python user's own models: a scene without appendage tables,
        :func:`spacecraft.scene.read.models_scene`).
    data : dict
        Every number of the report, JSON-ready (see :mod:`spacecraft.report.write`).
    stats : RunStats
    truth : dict
        ``verdict`` and ``sim`` truth plants (control.StateSpace), ``spacecraft``.
    designs : dict
        Per design variant: ``plant``, ``sim_plant``, ``controllers`` {type: StateSpace},
        ``tuned`` {type: :class:`~spacecraft.design.tuning.Tuned`}, ``spacecraft``,
        ``appendages`` (models per appendage name).
    responses : dict
        ``(variant, controller, "design"|"truth")`` -> the slew response
        (control.TimeResponseData; without the disturbance).
    loops : dict
        ``(variant, controller, "design"|"truth")`` -> closed-loop StateSpace.
    models : dict
        Per appendage name: ``beam``, ``truth``, ``fits`` {match: HingedChain}.
    exact_frd : control.FrequencyResponseData or None
    disturbance_responses : dict
        As ``responses``, the response to the scene's disturbance alone (theta_ref = 0).
    poles : dict
        As ``loops``, the closed-loop poles [1/s] (s-plane; a digital loop's mapped from z).
    basilisk : dict
        Controller kind -> :class:`spacecraft.basilisk.SlewComparison` (Basilisk's run of the
        manoeuvre beside flexsat's), when the scene asks for it.
    """

    scene: Scene
    data: dict
    stats: RunStats
    truth: dict
    designs: dict
    responses: dict
    loops: dict
    models: dict
    exact_frd: object = None
    disturbance_responses: dict = dataclasses.field(default_factory=dict)
    poles: dict = dataclasses.field(default_factory=dict)
    basilisk: dict = dataclasses.field(default_factory=dict)


@dataclasses.dataclass
class ClosedLoops:
    """One controller closed on its design model and on the truth model
    (:meth:`DesignLoop.closed_loops`).

    Attributes
    ----------
    variant : str
        The design model it was tuned on (a fit criterion, or ``"design"``).
    kind : str
        ``"pd"`` or ``"lqr"``.
    controller : control.StateSpace
        The controller (tuned, or given).
    row : dict
        JSON-ready, the row of ``closed_loops`` in results.json: ``design``, ``controller``,
        ``design_margins``, ``verdict`` (:func:`~spacecraft.design.verdicts.verdict_dict`),
        ``digital``, ``exact_verdict``, and with a manoeuvre per model (``"design"``,
        ``"truth"``) ``status``, ``metrics``, ``metric_flags``, ``appendages`` (peaks),
        ``disturbance_metrics``, ``diverged``, ``peak_difference`` (truth - design).
    verdict : controllers.SpilloverVerdict
        On the truth model.
    exact_verdict : controllers.SpilloverVerdict or None
        On the exact distributed beams (Nyquist), when asked.
    loops, poles, responses, disturbance_responses : dict
        Per model (``"design"``, ``"truth"``): the closed loop (StateSpace), its poles [1/s]
        (s-plane), the slew response and the disturbance response (control.TimeResponseData;
        the slew's alone unless the manoeuvre was simulated whole).
    """

    variant: str
    kind: str
    controller: control.StateSpace
    row: dict
    verdict: object
    exact_verdict: object = None
    loops: dict = dataclasses.field(default_factory=dict)
    poles: dict = dataclasses.field(default_factory=dict)
    responses: dict = dataclasses.field(default_factory=dict)
    disturbance_responses: dict = dataclasses.field(default_factory=dict)


class DesignLoop(ModelBuilder):
    """The design loop of one spacecraft: tune on the design model, judge on the truth model.

    Parameters
    ----------
    scene : Scene, path, dict or None
        Anything :func:`~spacecraft.scene.read.load_scene` accepts: the spacecraft's models
        are built from it. Leave it out to give your own models instead.
    truth : Spacecraft, optional
        Your truth model (instead of a scene): e.g. the hub with every beam truncated to many
        modes. Needs ``controller``.
    design : Spacecraft or dict of str to Spacecraft, optional
        The model(s) the controllers are tuned on (e.g. the hub with fitted chains), by label
        (a single Spacecraft is labelled ``"design"``); default: the truth model itself.
    exact : Spacecraft, optional
        The spacecraft with its distributed appendages: the loops are also judged on its exact
        frequency response (Nyquist), as ``outputs.exact_reference`` asks.
    controller : dict or ControllerSpec, optional
        With your own models: the controllers to tune, as a scene's ``[controller]`` table
        (units of the scene file) or a validated
        :class:`~spacecraft.scene.specs.ControllerSpec`.
    manoeuvre : dict or ManoeuvreSpec, optional
        With your own models: the slew (and disturbance), as a scene's ``[manoeuvre]`` table
        (degrees) or a :class:`~spacecraft.scene.specs.ManoeuvreSpec`; none: no responses.
    outputs : dict, optional
        With your own models: a scene's ``[outputs]`` table (``tip_deflection``,
        ``root_loads``; ``exact_reference`` follows from ``exact``).
    progress : callable, optional
        Called with a short message at the start of each stage.
    stats : RunStats, optional
        Counters to add to (a new one by default).
    time_responses : bool
        Simulate the manoeuvre (False: only tune and close the loops, e.g. for FMU export).

    Raises
    ------
    SceneError
        An invalid scene or specification, named by its key; later, a controller that cannot
        be tuned on a design model (``controller.<kind>``).
    TypeError
        A scene given together with your own models, or models of the wrong type.

    See Also
    --------
    run : a scene's whole run, as ``flexsat run`` does it.

    Notes
    -----
    Planar and three-axis spacecraft go through the same steps; they differ where the physics
    does: a three-axis loop has three torques, so its margins are the multivariable ones
    (loop-at-a-time per axis, disk margin, the smallest singular value of the return
    difference; :func:`controllers.margins`) and its metrics are given per axis besides the
    norms (:func:`controllers.metrics`).

    Examples
    --------
    A scene's design loop, one controller at a time:

    >>> import spacecraft
    >>> loop = spacecraft.DesignLoop("default")                     # doctest: +SKIP
    >>> loops = loop.closed_loops("poles-and-zeros", "pd")          # doctest: +SKIP
    >>> loops.verdict.stable, loops.row["metrics"]["truth"]["overshoot"]   # doctest: +SKIP

    Your own models:

    >>> from appendages import Beam
    >>> from appendages.equivalence import fit_chain
    >>> from spacecraft import DesignLoop, Hub, Mount, Spacecraft
    >>> rod = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)
    >>> def craft(model):
    ...     return Spacecraft(Hub(100.0, 50.0), [Mount(model, (0.5, 0.0), 0.0, name="rod")])
    >>> loop = DesignLoop(truth=craft(rod.truncated(20)), design=craft(fit_chain(rod, 3)),
    ...                   controller={"pd": {"natural_frequency": 0.1}},
    ...                   manoeuvre={"slew_angle": 10.0, "slew_time": 60.0})
    >>> result = loop.run()
    >>> result.data["closed_loops"][0]["verdict"]["stable"]
    True
    """

    def __init__(self, scene=None, *, truth=None, design=None, exact=None, controller=None,
                 manoeuvre=None, outputs=None, progress: ProgressCallback | None = None,
                 stats: RunStats | None = None, time_responses: bool = True):
        check_options(progress=progress, time_responses=time_responses)
        if stats is not None and not isinstance(stats, RunStats):
            raise TypeError(f"stats must be a RunStats or None; got {type(stats).__name__}")
        given = None
        models = {"truth": truth, "design": design, "exact": exact}
        if any(v is not None for v in models.values()):
            if scene is not None:
                name = next(k for k, v in models.items() if v is not None)
                raise TypeError(f"{name}: give a scene or your own models (truth, design, "
                                "exact), not both")
            scene, given = _models_question(truth, design, exact, controller, manoeuvre,
                                            outputs)
        else:
            specs = {"controller": controller, "manoeuvre": manoeuvre, "outputs": outputs}
            for name, value in specs.items():
                if value is not None:
                    raise TypeError(f"{name}: goes with your own models (truth=...); a scene "
                                    "has its own tables")
            scene = load_scene(scene)
        super().__init__(scene, progress, RunStats() if stats is None else stats,
                         bool(time_responses), given=given)
        self._fidelity = None
        self.flown = FlownManoeuvre(self) if self.scene.manoeuvre is not None else None

    @property
    def n_modes(self) -> int | None:
        """Modes per truncated beam of the truth model: the scene's ``fidelity.n_modes``, or
        chosen from its tolerance when first asked (None: no beam truth, or your own
        models)."""
        if self._fidelity is None:
            self._fidelity = self.choose_fidelity()
        return self._fidelity[0]

    @n_modes.setter
    def n_modes(self, value: int | None) -> None:
        self._fidelity = (value, None)

    # -- the whole loop ------------------------------------------------------------------------
    def run(self) -> RunResult:
        """Build the models, tune every controller, close and judge every loop.

        Returns
        -------
        RunResult
            ``data`` holds every number (``closed_loops``: margins, verdicts, metrics and
            status per loop; ``controllers``: gains; ``design_warnings``...).
        """
        scene = self.scene
        stats = self.stats
        outputs = scene.outputs
        m = scene.manoeuvre
        disturbances = m is not None and m.disturbance is not None
        data: dict = {"title": scene.title, "scene": scene.source,
                      "scene_resolved": scene_dict(scene)}
        if self.three_axis:
            data["three_axis"] = True

        with self.stage("building models"):
            if scene.controller.lqr is not None:
                self.lqr_frequency(self.rigid_inertia())
            for a in scene.appendages:
                if a.design == "fit":
                    for match in a.fit.match:
                        self.fit(a, match)
            if m is not None and flies(scene):
                # limits that cannot fly the slew: refused before the work
                check_slew_limits(scene, self.rigid_inertia())
        self._fidelity = n_modes, choice = self.choose_fidelity()
        data["fidelity"] = {
            "n_modes": n_modes, "method": scene.fidelity.method if n_modes else None,
            "prune": scene.fidelity.prune, "chosen_from_tolerance": choice is not None,
            "bandwidth_factor": scene.fidelity.bandwidth_factor,
            **({"choice": choice.as_dict()} if choice is not None else {}),
            **({"given": True} if self.given is not None else {}),
            **({"pinned": scene.fidelity.pinned_floors()}
               if scene.fidelity.modes_per_motion is not None else {}),
        }
        per_motion = self.truth_modes_per_motion(n_modes)
        if per_motion:
            data["fidelity"]["modes_per_motion"] = per_motion
            data["fidelity"]["motions_kept"] = list(self.seen_motions())

        with self.stage("building plants"):
            truth_sc = self.truth_spacecraft(n_modes)
            truth_verdict = self.truth_plant(n_modes)
            truth_sim, sim_info = self.plant(truth_sc, ("truth", n_modes),
                                             tip=outputs.tip_deflection,
                                             root_loads=outputs.root_loads,
                                             disturbances=disturbances,
                                             prune=scene.fidelity.prune)
            stats.modes_kept = sim_info["modes_kept"]
            stats.modes_dropped = sim_info["modes_dropped"]
            data["truth"] = {"models": _described(truth_sc), "n_states": int(truth_sim.nstates),
                             **sim_info, "coupled_frequencies": _coupled(truth_sc),
                             "modes": [mode.as_dict() for mode in
                                       modal_survey(truth_sc, MODAL_TABLE_MODES)]}
            designs = {}
            for variant in self.variants:
                sc = self.design_spacecraft(variant, n_modes)
                design_plant, info = self.design_plant(variant, n_modes)
                sim_plant = self.simulation_plant("design", variant, n_modes)
                designs[variant] = {"spacecraft": sc, "plant": design_plant,
                                    "sim_plant": sim_plant, "controllers": {}, "tuned": {},
                                    "appendages": dict(zip(sc.names,
                                                           (m_.appendage for m_ in sc.mounts)))}
                data.setdefault("designs", {})[variant] = {
                    "models": _described(sc), "n_states": int(sim_plant.nstates), **info,
                    "coupled_frequencies": _coupled(sc)}

        # the loops' real size (a beam's modes can ask for more than the read-time estimate
        # counted): refused before the exact reference, tuning, margins and simulations
        self.check_loop_states(n_modes)
        exact_frd = None
        if outputs.exact_reference:
            with self.stage("exact frequency-domain reference"):
                exact_frd = self.exact_reference_frd()
                data["exact"] = {"coupled_frequencies": self.exact_frequencies(8).tolist(),
                                 "inertia": self.rigid_inertia()}

        with self.stage("tuning controllers"):
            for variant, d in designs.items():
                for kind in scene.controller.types:
                    tuned = self.tuned(variant, kind, n_modes)
                    d["controllers"][kind] = tuned.controller
                    d["tuned"][kind] = tuned
                    data.setdefault("controllers", {}).setdefault(variant, {})[kind] = {
                        **tuned.description, "removed_modes": tuned.removed_modes}

        responses, disturbance_responses, loops, poles, rows = {}, {}, {}, {}, []
        with self.stage("closing the loops"):
            for variant, d in designs.items():
                for kind in d["controllers"]:
                    c = self.closed_loops(variant, kind, exact_frd=exact_frd)
                    rows.append(c.row)
                    for which in c.loops:
                        key = (variant, kind, which)
                        loops[key], poles[key] = c.loops[which], c.poles[which]
                        if which in c.responses:
                            responses[key] = c.responses[which]
                        if which in c.disturbance_responses:
                            disturbance_responses[key] = c.disturbance_responses[which]
        data["closed_loops"] = rows
        if self.flown is not None and self.time_responses:
            data["manoeuvre"] = self.flown.facts(truth_verdict)

        models = {}
        for k, a in enumerate(scene.appendages):
            entry = {"truth": truth_sc.mounts[k].appendage}
            if a.beam is not None:
                entry["beam"] = self.beam(a)
            if a.design == "fit":
                entry["fits"] = {m_: self.fit(a, m_) for m_ in a.fit.match}
            models[a.name] = entry
        if (scene.report.equivalence and self.time_responses
                and any(a.design == "fit" for a in scene.appendages)):
            with self.stage("equivalence tables"):
                data["equivalence"] = self.equivalence_tables(models)

        basilisk = {}
        if scene.simulator.name == "basilisk" and self.time_responses:
            from .simulators import basilisk_runs

            with self.stage("running the manoeuvre in Basilisk"):
                basilisk, data["basilisk"] = basilisk_runs(self, designs, truth_sim)

        loop_band, resolved = self.truth_resolution(n_modes, rows, data["fidelity"])
        data["truth"]["resolved"] = {k: {"frequency": w, "model": what, "covers_loops": covers}
                                     for k, (w, what, covers) in resolved.items()}
        data["truth"]["loop_band"] = loop_band
        data["design_warnings"] = design_warnings(data, loop_band=loop_band, resolved=resolved)
        data["design_warnings"] += unmodelled_outputs(truth_sim)
        if self.flown is not None:
            data["design_warnings"] += self.flown.warnings(data)
        data["stats"] = stats.as_dict()
        truth = {"spacecraft": truth_sc, "verdict": truth_verdict, "sim": truth_sim}
        return RunResult(scene, data, stats, truth, designs, responses, loops, models, exact_frd,
                         disturbance_responses, poles, basilisk)

    # -- one controller ------------------------------------------------------------------------
    def closed_loops(self, variant: str, kind: str, *, controller=None,
                     models: tuple = ("design", "truth"), whole_manoeuvre: bool = False,
                     exact_frd=None) -> ClosedLoops:
        """One controller on its design model and on the truth model: margins, verdicts,
        responses, metrics and status.

        Parameters
        ----------
        variant : str
            The design model (one of :attr:`variants`).
        kind : str
            ``"pd"`` or ``"lqr"`` (one of the scene's ``controller.types``).
        controller : control.StateSpace, optional
            A controller to judge instead of tuning ``kind`` on the design model (a sweep's
            nominal controller).
        models : tuple of str
            The models to close the loop on and simulate: ``"design"`` (also gives the margins
            on the design model and, for a digital controller, the sampling facts) and/or
            ``"truth"``. The verdict on the truth model is always given.
        whole_manoeuvre : bool
            Simulate slew and disturbance at once (the response is what the spacecraft does
            under both; its metrics are the whole manoeuvre's) instead of apart.
        exact_frd : control.FrequencyResponseData, optional
            The exact reference (:meth:`exact_reference_frd`) when the specification asks for
            the exact beam's verdict; built here if needed and not given.

        Returns
        -------
        ClosedLoops
        """
        scene = self.scene
        m = scene.manoeuvre
        n_modes = self.n_modes
        self.check_loop_states(n_modes, variants=(variant,), kinds=(kind,),
                               controller=controller, models=models)
        K = controller if controller is not None else self.tuned(variant, kind,
                                                                 n_modes).controller
        row: dict = {"design": variant, "controller": kind}
        if "design" in models:
            design_margins = self.design_margins(variant, kind, n_modes, controller)
            row["design_margins"] = {**margins_dict(design_margins),
                                     **delay_facts(design_margins)}
        verdict = self.truth_spillover(self.truth_plant(n_modes), K, delayed=True)
        row["verdict"] = {**verdict_dict(verdict), **delay_facts(verdict.margins)}
        if scene.controller.total_delay > 0:
            row["undelayed_stable"] = bool(self.truth_spillover(self.truth_plant(n_modes),
                                                                K).stable)
        if "design" in models and scene.controller.sample_time is not None:
            row["digital"] = digital_facts(scene.controller.sample_time, rigid_crossover(
                self.design_plant(variant, n_modes)[0], K))
        exact = None
        if scene.outputs.exact_reference:
            frd = exact_frd if exact_frd is not None else self.exact_reference_frd()
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                try:
                    exact = self.exact_verdict(K, frd)
                    row["exact_verdict"] = {**verdict_dict(exact), **delay_facts(exact.margins)}
                except ValueError as exc:
                    row["exact_verdict"] = {"error": str(exc)}
        out = ClosedLoops(variant, kind, K, row, verdict, exact)
        plants = {which: self.simulation_plant(which, variant, n_modes) for which in models}
        if m is None or not self.time_responses:
            for which, plant in plants.items():
                out.loops[which] = loop = close_flown_loop(plant, K, scene)
                out.poles[which] = closed_loop_poles(loop)
            return out
        for key in ("metrics", "metric_flags", "status", "appendages", "disturbance_metrics",
                    "disturbance_flags"):
            row[key] = {}
        names = self.names
        for which, plant in plants.items():
            flight = (self.flown.fly(variant, plant, K, whole=whole_manoeuvre)
                      if flies(scene) else None)
            out.loops[which] = loop = flight.loop if flight else controllers.close_loop(plant, K)
            out.poles[which] = poles = closed_loop_poles(loop)
            runs = flight.runs if flight else self.simulate(loop, whole=whole_manoeuvre)
            slew, shock = runs["slew"], runs["disturbance"]
            out.responses[which] = slew
            with np.errstate(all="ignore"):
                metrics = controllers.metrics(slew)
            status = loop_status(poles, slew, m, metrics)
            row["status"][which] = status
            if which == "truth":
                # the slew's status decides (its poles): a loop with undamped modes it does not
                # reach is marginal, its margins hold
                row["verdict"]["margin_flags"] = margin_flags(
                    row["verdict"], not growing(row["verdict"], status))
            row["metrics"][which], row["metric_flags"][which] = withheld_metrics(metrics,
                                                                                 status)
            peaks = appendage_peaks(slew, names)
            if status["status"] in ("diverges", "unstable"):
                peaks = {n: {k: None for k in p} for n, p in peaks.items()}
            row["appendages"][which] = peaks
            self.flown.record(row, which, flight, slew, status, plant, K)
            if shock is not None:
                out.disturbance_responses[which] = shock
                with np.errstate(all="ignore"):
                    values = controllers.metrics(shock)
                shock_status = loop_status(poles, shock, None, values)
                row["disturbance_metrics"][which], row["disturbance_flags"][which] = (
                    withheld_metrics(values, shock_status))
                row["disturbance_metrics"][which]["appendages"] = appendage_peaks(shock, names)
        row["diverged"] = {w: diverged_at(r) for w, r in out.responses.items()}
        if set(out.responses) == {"design", "truth"}:
            gone = any(row["status"][w]["status"] in ("diverges", "unstable")
                       for w in out.responses)
            diff, flags = {}, {}
            truth, design = out.responses["truth"], out.responses["design"]
            for name in design.output_labels:
                a, b = trace(truth, name), trace(design, name)
                if a is None or b is None:
                    continue
                if gone:
                    diff[name], flags[name] = None, "diverges"
                else:
                    diff[name] = float(np.max(np.abs(a - b)))
            row["peak_difference"] = diff
            if flags:
                row["peak_difference_flags"] = flags
        return out

    def simulate(self, loop, *, whole: bool = False) -> dict:
        """The manoeuvre on a closed loop: ``{"slew": ..., "disturbance": ... or None}``
        (:func:`spacecraft.design.responses.simulate_manoeuvre`; ``whole``: slew and
        disturbance at once, in ``"slew"``). A response that leaves the float64 range stops
        at its last finite sample (``diverged``, ``diverged_at``)."""
        m = self.scene.manoeuvre
        simulator = None
        if not loop.isdtime(strict=True):
            self.stats.simulator_setups += 1
            with self.scene_values("manoeuvre.step"):
                simulator = controllers.Simulator(loop, m.step)
        self.stats.simulations += 1 + (m.disturbance is not None and not whole)
        return simulate_manoeuvre(loop, m, simulator=simulator, together=whole)

    # -- what the run adds around the loops -----------------------------------------------------
    def truth_resolution(self, n_modes, rows, fidelity: dict) -> tuple[float | None, dict]:
        """The band the loops act in, bandwidth_factor x the fastest crossover [rad/s], and per
        beam appendage ``(frequency, model, covers_loops)``: the frequency up to which its truth
        model resolves it by the rule of thumb of :func:`resolved_frequency`, and whether the
        truth model is shown good enough for the loops' band: that frequency is above the band,
        or the tolerance-driven fidelity closed every loop with one more mode per beam and its
        poles up to at least the band, its damping and margins changed by less than the
        tolerance (:func:`spacecraft.design.fidelity.refine_for_closed_loop`), a check of the
        very question the rule of thumb estimates."""
        scene = self.scene
        if not rows:
            return None, {}
        crossovers = [w for r in rows
                      for w in crossover_frequencies(r.get("design_margins", {}))]
        with self.scene_values("controller"):
            wn = self.design_bandwidth(self.rigid_inertia())
        band = scene.fidelity.bandwidth_factor * max([wn] + crossovers)
        record = (fidelity.get("choice") or {}).get("closed_loop")
        # the same crossovers set both bands; the slack only absorbs their rounding
        converged = (record is not None and record["converged"]
                     and record["band"] >= band * (1.0 - 1e-9))
        resolved = {}
        if n_modes is not None:
            method = scene.fidelity.method
            per_motion = self.truth_modes_per_motion(n_modes)
            for a in scene.appendages:
                if a.truth != "beam":
                    continue
                counts = per_motion.get(a.name, {})
                if "lowest coupled modes" in counts:      # modes ranked together: the k lowest
                    k = counts["lowest coupled modes"]
                    w = resolved_frequency(self.beam(a), k, method, three_axis=True)
                    what = plural(k, f"{method} mode")
                elif counts:                              # a mode count per motion
                    w = resolved_frequency(self.beam(a), n_modes, method, three_axis=True,
                                           modes_per_motion=counts)
                    what = (plural(sum(counts.values()), f"{method} mode") + ": " + ", ".join(
                        f"{MOTION_WORDS[m]} {c}" for m, c in counts.items() if c))
                else:
                    # the truncation's own count (a planar one keeps its floor beyond n_modes)
                    k = (n_modes if self.three_axis
                         else int(self.truth_model(a, n_modes).n_modes))
                    w = resolved_frequency(self.beam(a), k, method,
                                           three_axis=self.three_axis)
                    what = plural(k, f"{method} mode")
                resolved[a.name] = (w, what, bool(w >= band or converged))
        return band, resolved

    def equivalence_tables(self, models) -> list:
        """Paper's table per fitted beam: exact beam, 2-mode beam, each fitted chain."""
        tables = []
        done = set()
        for a in self.scene.appendages:
            if a.design != "fit":
                continue
            key = (a.structure, a.fit.n_bodies, a.fit.match)
            if key in done:
                continue
            done.add(key)
            fits = {m: models[a.name]["fits"][m] for m in a.fit.match}
            beam = self.beam(a)
            if self.three_axis:
                # the paper's table is planar: the x-y bending plane of beam and chains
                beam = beam.planar_view("xy")
                fits = {m: chain.planar_view("xy") for m, chain in fits.items()}
            table = equivalence_table(beam, fits, stats=self.stats)
            table["appendage"] = a.name
            if self.three_axis:
                table["plane"] = "x-y"
            tables.append(table)
        return tables


def unmodelled_outputs(plant: control.StateSpace) -> list[dict]:
    """The warning ``truth_output_unmodelled`` for the truth model's tip outputs that no kept
    mode moves: their C and D rows are zero by construction (a truncation keeps the lowest
    modes of all motions together, so a stiff motion, a wing's in-plane bending or a boom's
    torsion, may have none), so their figures read 0 in the truth model, which is not the
    structure's value. Exact zeros, not small ones: a row is zero only when no mode enters it.
    A truncation chosen from the tolerance keeps a mode of every motion a tip output sees
    (:meth:`spacecraft.design.models.ModelBuilder.truncation`): this is for a given
    ``fidelity.n_modes`` and for beams whose motions couple."""
    C, D = np.asarray(plant.C), np.asarray(plant.D)
    names = [name for i, name in enumerate(plant.output_labels)
             if "_tip_" in name and not C[i].any() and not D[i].any()]
    if not names:
        return []
    return [{"code": "truth_output_unmodelled", "message": (
        "the truth model keeps no mode that moves " + ", ".join(names) + ": their figures "
        "read 0 on the truth model (the design model's are its own); raise fidelity.n_modes "
        "until each appendage keeps a mode of that motion, or leave fidelity.n_modes out: the "
        "number chosen from fidelity.tolerance keeps the lowest mode of every motion a tip "
        "output sees")}]


def _described(sc) -> dict:
    """Each appendage model of a spacecraft, JSON-ready, by name."""
    return {name: describe_model(mount.appendage) for name, mount in zip(sc.names, sc.mounts)}


def _coupled(sc) -> list:
    """The first 8 coupled elastic frequencies of a spacecraft model [rad/s]."""
    return sc.modes()[0][sc.n_rigid:sc.n_rigid + 8].tolist()


def _models_question(truth, design, exact, controller, manoeuvre, outputs):
    """The scene of a Python user's own models and their :class:`GivenModels`."""
    from ..dynamics.coupling import Spacecraft
    from .models import GivenModels

    if truth is None:
        name = "design" if design is not None else "exact"
        raise TypeError(f"{name}: your own models need a truth Spacecraft too (truth=...)")
    designs = ({"design": truth} if design is None else
               dict(design) if isinstance(design, Mapping) else {"design": design})
    for name, sc in [("truth", truth), ("exact", exact)] + [
            (f"design[{k!r}]", v) for k, v in designs.items()]:
        if sc is not None and not isinstance(sc, Spacecraft):
            raise TypeError(f"{name} must be a spacecraft.Spacecraft; got {type(sc).__name__}")
    if controller is None:
        raise TypeError("controller: your own models need a controller specification (a "
                        "scene's [controller] table, e.g. {'pd': {'natural_frequency': 0.1}})")
    scene = models_scene(truth.hub, truth.names, controller=controller, manoeuvre=manoeuvre,
                         outputs=outputs, exact=exact is not None)
    return scene, GivenModels(truth, designs, exact)


def run(scene=None, *, progress: ProgressCallback | None = None,
        stats: RunStats | None = None, time_responses: bool = True) -> RunResult:
    """Run a scene: build the models it needs, tune, close the loops, collect the numbers.

    Parameters
    ----------
    scene : Scene, path, dict or None
        Anything :func:`~spacecraft.scene.read.load_scene` accepts (None: the default scene).
    progress : callable, optional
        Called with a short message at the start of each stage.
    stats : RunStats, optional
        Counters to add to (a new one by default).
    time_responses : bool
        Simulate the manoeuvre (False: only tune and close the loops, e.g. for FMU export).

    Returns
    -------
    RunResult
        ``result.data`` holds every number (``closed_loops``: margins, verdicts, metrics and
        status per loop; ``controllers``: gains; ``design_warnings``...); files (report,
        plots, FMUs) are written by :func:`spacecraft.report.write_report`.

    Raises
    ------
    SceneError
        Invalid scene, or a controller that cannot be tuned on the design model.

    See Also
    --------
    DesignLoop : the evaluator it runs (one controller at a time, or your own models).

    Examples
    --------
    >>> import spacecraft
    >>> result = spacecraft.run("two_wings")                          # doctest: +SKIP
    >>> [w["message"] for w in result.data["design_warnings"]]        # doctest: +SKIP
    """
    check_options(progress=progress, time_responses=time_responses)
    if stats is not None and not isinstance(stats, RunStats):
        raise TypeError(f"stats must be a RunStats or None; got {type(stats).__name__}")
    scene = load_scene(scene)
    # the whole run sized like its largest loop (controllers/threads.py): the models' and
    # tables' own small products and factorisations single-threaded too, not only the
    # controllers' entry points
    with warnings.catch_warnings(record=True) as caught, library_limits(scene.limits), \
            blas_threads_for(estimate_cost(scene).loop_states):
        warnings.simplefilter("default")
        result = DesignLoop(scene, progress=progress, stats=stats,
                            time_responses=time_responses).run()
    result.data["warnings"] = input_warning_lines(scene) + warning_lines(caught)
    return result


def input_warning_lines(scene) -> list[str]:
    """The scene's values that look like unit slips (:attr:`Scene.input_warnings`), as warning
    lines (``UnitWarning: <file>: <key>: ...``)."""
    return [f"UnitWarning: {line}" for line in scene.input_warnings]


def check_options(**options) -> None:
    """TypeError naming an option of :func:`run`, :class:`DesignLoop` or
    :func:`spacecraft.write_report` that is not what it must be: ``progress`` None or a
    function of one message, the others True or False."""
    for name, value in options.items():
        if name == "progress":
            if value is not None and not callable(value):
                raise TypeError(f"progress must be None or a function of one message; got "
                                f"{type(value).__name__}")
        elif not isinstance(value, bool):
            raise TypeError(f"{name} must be True or False; got {type(value).__name__} "
                            f"{value!r:.60}")


def warning_lines(caught) -> list[str]:
    """Distinct warnings as one line each (``Category: message (module:line)``), at most 20,
    each at most about 300 characters: what the report and the command line show instead of
    numpy's or scipy's multi-line output."""
    from ..scene.reader import shorten

    seen: dict = {}
    for w in caught:
        if issubclass(w.category, controllers.RemovedModesWarning):
            continue  # the report's section on the modes left out of the design
        key = (w.category.__name__, shorten(str(w.message), 250, one_line=True))
        seen.setdefault(key, f"{Path(w.filename).name}:{w.lineno}")
    lines = [f"{category}: {message} ({where})"
             for (category, message), where in list(seen.items())[:_MAX_WARNINGS]]
    if len(seen) > _MAX_WARNINGS:
        lines.append(f"... and {len(seen) - _MAX_WARNINGS} more distinct warnings")
    return lines
