"""Run a scene: build only what it asks for, tune, close the loops, collect every number.

:func:`run` turns a :class:`~spacecraft.scene.read.Scene` into a :class:`RunResult`: the models
(truth: distributed beams truncated to the modes the scene's tolerance needs, or chains; design:
chains fitted to the beams; :mod:`spacecraft.design.models`), the controllers tuned on each design
model with their gains (:mod:`spacecraft.design.tuning`), the slew (and disturbance) responses of the
design and truth loops with their metrics and verdicts (:mod:`spacecraft.design.responses`,
:mod:`spacecraft.design.verdicts`), the design warnings, optionally Basilisk's run of the same
manoeuvre (:mod:`spacecraft.design.simulators`), and the equivalence tables. The report
(:mod:`spacecraft.report.write`) writes files from it; FMUs and plots are built there.

Nothing the scene does not ask for is built. :class:`RunStats` counts the work the code did
(FMU builds, plots, exact-beam evaluations, LQR designs, simulations, modes kept and dropped...),
so tests can prove each skip. Expensive results are cached within a run: one chain fit per
(beam, criterion), one Spacecraft (one eigen-decomposition) per model set, one plant per signal
set, one simulator (matrix exponential) per closed loop.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from pathlib import Path

import control
import numpy as np

import controllers
from controllers.threads import blas_threads_for

from ..scene.limits import estimate_cost, library_limits
from .models import (LQR_FREQUENCY_RANGE, ModelBuilder, ProgressCallback, RunStats,
                     raised_by_flexsat)
from .naming import FIT_LABELS
from .responses import (appendage_peaks, diverged_at, outputs_until_overflow,
                        simulate_manoeuvre, trace)
from ..scene.read import Scene, load_scene, scene_dict
from .tables import describe_model, equivalence_table
from .tuning import digital_facts, rigid_crossover
from .verdicts import (closed_loop_poles, design_warnings, exact_loop_verdict, growing,
                       loop_status, margin_flags, resolved_frequency, verdict_dict,
                       withheld_metrics)

__all__ = ["RunStats", "RunResult", "run", "ProgressCallback", "equivalence_table", "FIT_LABELS",
           "raised_by_flexsat", "LQR_FREQUENCY_RANGE", "diverged_at", "warning_lines",
           "input_warning_lines", "check_options"]

# Most distinct warnings kept in a run's results.
_MAX_WARNINGS = 20

# kept for callers of the earlier names
_outputs_until_overflow = outputs_until_overflow
_describe = describe_model


@dataclasses.dataclass
class RunResult:
    """Everything a run produced.

    Attributes
    ----------
    scene : Scene
    data : dict
        Every number of the report, JSON-ready (see :mod:`spacecraft.report.write`).
    stats : RunStats
    truth : dict
        ``verdict`` and ``sim`` truth plants (control.StateSpace), ``spacecraft``.
    designs : dict
        Per design variant: ``plant``, ``sim_plant``, ``controllers`` {type: StateSpace},
        ``spacecraft``, ``appendages`` (models per appendage name).
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
    three_axis : dict
        A three-axis scene's run (:func:`spacecraft.design.three_axis.run_three_axis`): plants,
        controllers, loops, responses; empty for a planar scene.
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
    three_axis: dict = dataclasses.field(default_factory=dict)


def _margins(m) -> dict:
    return {**m.as_dict(), "gain_crossover_frequency": m.gain_crossover_frequency,
            "phase_crossover_frequency": m.phase_crossover_frequency,
            "modulus_margin_frequency": m.modulus_margin_frequency}


class _Runner(ModelBuilder):
    """The scene runner: the model builder plus tuning, loops, responses and verdicts."""

    def run(self) -> RunResult:
        scene = self.scene
        stats = self.stats
        outputs = scene.outputs
        m = scene.manoeuvre
        disturbances = m is not None and m.disturbance is not None
        data: dict = {"title": scene.title, "scene": scene.source,
                      "scene_resolved": scene_dict(scene)}

        with self.stage("building models"):
            if scene.controller.lqr is not None:
                self.lqr_frequency(self.exact_spacecraft().inertia)
            for a in scene.appendages:
                if a.design == "fit":
                    for match in a.fit.match:
                        self.fit(a, match)
        n_modes, choice = self.choose_fidelity()
        self.n_modes = n_modes
        data["fidelity"] = {
            "n_modes": n_modes, "method": scene.fidelity.method if n_modes else None,
            "prune": scene.fidelity.prune, "chosen_from_tolerance": choice is not None,
            "bandwidth_factor": scene.fidelity.bandwidth_factor,
            **({"choice": choice.as_dict()} if choice is not None else {}),
        }

        with self.stage("building plants"):
            truth_models = [self.truth_model(a, n_modes) for a in scene.appendages]
            truth_sc = self.spacecraft(("truth", n_modes), truth_models)
            prune = scene.fidelity.prune
            truth_verdict, truth_info = self.plant(truth_sc, ("truth", n_modes), prune=prune)
            truth_sim, sim_info = self.plant(truth_sc, ("truth", n_modes),
                                             tip=outputs.tip_deflection,
                                             root_loads=outputs.root_loads,
                                             disturbances=disturbances, prune=prune)
            stats.modes_kept = sim_info["modes_kept"]
            stats.modes_dropped = sim_info["modes_dropped"]
            data["truth"] = {
                "models": {a.name: describe_model(m_) for a, m_ in zip(scene.appendages,
                                                                        truth_models)},
                "n_states": int(truth_sim.nstates), **sim_info,
                "coupled_frequencies": truth_sc.modes()[0][3:3 + 8].tolist(),
            }
            designs = {}
            for variant in scene.design_variants:
                models = [self.design_model(a, variant, n_modes) for a in scene.appendages]
                sc = self.design_spacecraft(variant, n_modes)
                design_plant, info = self.design_plant(variant, n_modes)
                sim_plant, _ = self.plant(sc, self.design_key(variant, n_modes),
                                          tip=outputs.tip_deflection,
                                          root_loads=outputs.root_loads,
                                          disturbances=disturbances, prune=prune)
                designs[variant] = {"spacecraft": sc, "plant": design_plant,
                                    "sim_plant": sim_plant, "controllers": {}, "tuned": {},
                                    "appendages": dict(zip([a.name for a in scene.appendages],
                                                           models))}
                data.setdefault("designs", {})[variant] = {
                    "models": {a.name: describe_model(m_) for a, m_ in zip(scene.appendages,
                                                                            models)},
                    "n_states": int(sim_plant.nstates), **info,
                    "coupled_frequencies": sc.modes()[0][3:3 + 8].tolist(),
                }

        exact_frd = None
        if outputs.exact_reference:
            with self.stage("exact frequency-domain reference"):
                exact_frd = self.exact_reference_frd()
                data["exact"] = {"coupled_frequencies": self.exact_frequencies(8).tolist(),
                                 "inertia": self.exact_spacecraft().inertia}

        with self.stage("tuning controllers"):
            c = scene.controller
            for variant, d in designs.items():
                for kind in c.types:
                    tuned = self.tuned(variant, kind, n_modes)
                    d["controllers"][kind] = tuned.controller
                    d["tuned"][kind] = tuned
                    data.setdefault("controllers", {}).setdefault(variant, {})[kind] = {
                        **tuned.description, "removed_modes": tuned.removed_modes}

        responses, disturbance_responses, loops, poles, rows = {}, {}, {}, {}, []
        names = [a.name for a in scene.appendages]
        with self.stage("closing the loops"):
            for variant, d in designs.items():
                for kind, K in d["controllers"].items():
                    row = self.loop_row(variant, kind, K, d, truth_verdict, truth_sim,
                                        exact_frd, names, responses, disturbance_responses,
                                        loops, poles)
                    rows.append(row)
        data["closed_loops"] = rows

        models = {}
        for a in scene.appendages:
            entry = {"truth": truth_models[scene.appendages.index(a)]}
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

        loop_band, resolved = self.truth_resolution(n_modes, rows)
        data["truth"]["resolved"] = {k: {"frequency": w, "model": what}
                                     for k, (w, what) in resolved.items()}
        data["truth"]["loop_band"] = loop_band
        data["design_warnings"] = design_warnings(data, loop_band=loop_band, resolved=resolved)
        data["stats"] = stats.as_dict()
        truth = {"spacecraft": truth_sc, "verdict": truth_verdict, "sim": truth_sim}
        return RunResult(scene, data, stats, truth, designs, responses, loops, models, exact_frd,
                         disturbance_responses, poles, basilisk)

    # -- one loop ------------------------------------------------------------------------------
    def loop_row(self, variant, kind, K, d, truth_verdict, truth_sim, exact_frd, names,
                 responses, disturbance_responses, loops, poles) -> dict:
        """Margins, verdicts, responses, metrics and status of one controller on its design
        model and on the truth model (the row of ``closed_loops``)."""
        scene = self.scene
        m = scene.manoeuvre
        row = {"design": variant, "controller": kind}
        design_margins = self.design_margins(variant, kind, self.n_modes)
        verdict = self.truth_spillover(truth_verdict, K)
        row["design_margins"] = _margins(design_margins)
        row["verdict"] = verdict_dict(verdict)
        digital = None
        if scene.controller.sample_time is not None:
            digital = digital_facts(scene.controller.sample_time,
                                    rigid_crossover(d["plant"], K))
        if digital is not None:
            row["digital"] = digital
        if exact_frd is not None:
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                try:
                    row["exact_verdict"] = verdict_dict(exact_loop_verdict(
                        self.exact_spacecraft(), K, exact_frd.omega,
                        theta=np.asarray(exact_frd.frdata)[0, 0]))
                except ValueError as exc:
                    row["exact_verdict"] = {"error": str(exc)}
        plants = (("design", d["sim_plant"]), ("truth", truth_sim))
        if m is None or not self.time_responses:
            loop = controllers.close_loop(truth_sim, K)
            loops[(variant, kind, "truth")] = loop
            poles[(variant, kind, "truth")] = closed_loop_poles(loop)
            return row
        for key in ("metrics", "metric_flags", "status", "appendages", "disturbance_metrics",
                    "disturbance_flags"):
            row[key] = {}
        for which, plant in plants:
            key = (variant, kind, which)
            loop = controllers.close_loop(plant, K)
            loops[key] = loop
            poles[key] = closed_loop_poles(loop)
            runs = self.simulate_runs(loop)
            slew, shock = runs["slew"], runs["disturbance"]
            responses[key] = slew
            with np.errstate(all="ignore"):
                metrics = controllers.metrics(slew)
            status = loop_status(poles[key], slew, m, metrics)
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
            if shock is not None:
                disturbance_responses[key] = shock
                with np.errstate(all="ignore"):
                    values = controllers.metrics(shock)
                shock_status = loop_status(poles[key], shock, None, values)
                row["disturbance_metrics"][which], row["disturbance_flags"][which] = (
                    withheld_metrics(values, shock_status))
                row["disturbance_metrics"][which]["appendages"] = appendage_peaks(shock, names)
        row["diverged"] = {w: diverged_at(responses[(variant, kind, w)]) for w, _ in plants}
        gone = any(row["status"][w]["status"] in ("diverges", "unstable") for w, _ in plants)
        diff, flags = {}, {}
        pair = [responses[(variant, kind, w)] for w in ("truth", "design")]
        for name in pair[1].output_labels:
            a, b = trace(pair[0], name), trace(pair[1], name)
            if a is None or b is None:
                continue
            if gone:
                diff[name], flags[name] = None, "diverges"
            else:
                diff[name] = float(np.max(np.abs(a - b)))
        row["peak_difference"] = diff
        if flags:
            row["peak_difference_flags"] = flags
        return row

    def simulate_runs(self, loop, *, together: bool = False) -> dict:
        """The manoeuvre on a closed loop: ``{"slew": ..., "disturbance": ... or None}``
        (see :func:`spacecraft.design.responses.simulate_manoeuvre`)."""
        m = self.scene.manoeuvre
        simulator = None
        if not loop.isdtime(strict=True):
            self.stats.simulator_setups += 1
            with self.scene_values("manoeuvre.step"):
                simulator = controllers.Simulator(loop, m.step)
        self.stats.simulations += 1 + (m.disturbance is not None and not together)
        return simulate_manoeuvre(loop, m, simulator=simulator, together=together)

    def simulate(self, loop) -> control.TimeResponseData:
        """The whole manoeuvre's response of a closed loop (slew and disturbance at once;
        outputs only): what :mod:`spacecraft.sweep` evaluates. A response that leaves the
        float64 range stops at its last finite sample (``diverged``, ``diverged_at``)."""
        return self.simulate_runs(loop, together=True)["slew"]

    def truth_resolution(self, n_modes, rows) -> tuple[float | None, dict]:
        """The band the loops act in, bandwidth_factor x the fastest crossover [rad/s], and per
        beam appendage the frequency up to which its truth model resolves it."""
        scene = self.scene
        crossovers = [r["design_margins"]["gain_crossover_frequency"] for r in rows]
        crossovers = [w for w in crossovers if w is not None and math.isfinite(w)]
        if not rows:
            return None, {}
        with self.scene_values("controller"):
            wn = self.design_bandwidth(self.exact_spacecraft().inertia)
        band = scene.fidelity.bandwidth_factor * max([wn] + crossovers)
        resolved = {}
        if n_modes is not None:
            method = scene.fidelity.method
            for a in scene.appendages:
                if a.truth == "beam":
                    w = resolved_frequency(self.beam(a), n_modes, method)
                    resolved[a.name] = (w, f"{n_modes} {method} mode"
                                           f"{'s' if n_modes != 1 else ''}")
        return band, resolved

    def equivalence_tables(self, models) -> list:
        """Paper's table per fitted beam: exact beam, 2-mode beam, each fitted chain."""
        tables = []
        done = set()
        for a in self.scene.appendages:
            if a.design != "fit":
                continue
            key = (a.beam, a.fit.n_bodies, a.fit.match)
            if key in done:
                continue
            done.add(key)
            fits = {m: models[a.name]["fits"][m] for m in a.fit.match}
            table = equivalence_table(self.beam(a), fits, stats=self.stats)
            table["appendage"] = a.name
            tables.append(table)
        return tables


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

    Examples
    --------
    >>> import spacecraft
    >>> result = spacecraft.run("two_wings.toml")          # doctest: +SKIP
    >>> [w["message"] for w in result.data["design_warnings"]]   # doctest: +SKIP
    """
    check_options(progress=progress, time_responses=time_responses)
    if stats is not None and not isinstance(stats, RunStats):
        raise TypeError(f"stats must be a RunStats or None; got {type(stats).__name__}")
    scene = load_scene(scene)
    stats = RunStats() if stats is None else stats
    if scene.three_axis:
        return _run_three_axis(scene, progress, stats, time_responses)
    # the whole run sized like its largest loop (controllers/threads.py): the models' and
    # tables' own small products and factorisations single-threaded too, not only the
    # controllers' entry points (with default threads a run spent ~0.1-0.2 s more CPU)
    with warnings.catch_warnings(record=True) as caught, library_limits(scene.limits), \
            blas_threads_for(estimate_cost(scene).loop_states):
        warnings.simplefilter("default")
        result = _Runner(scene, progress, stats, time_responses).run()
    result.data["warnings"] = input_warning_lines(scene) + warning_lines(caught)
    return result


def _run_three_axis(scene, progress, stats, time_responses) -> RunResult:
    """A three-axis scene (:mod:`spacecraft.design.three_axis`) in a RunResult: ``data`` its
    numbers, ``loops``/``responses``/``designs`` its systems."""
    from .three_axis import run_three_axis

    with warnings.catch_warnings(record=True) as caught, library_limits(scene.limits):
        warnings.simplefilter("default")
        out = run_three_axis(scene, progress=progress, time_responses=time_responses)
    out["data"]["warnings"] = (input_warning_lines(scene) + out["data"]["warnings"]
                               + warning_lines(caught))
    return RunResult(scene=scene, data=out["data"], stats=stats,
                     truth={"plant": out["plants"]["truth"]},
                     designs={"design": {"plant": out["plants"]["design"],
                                         "controllers": out["controllers"]}},
                     responses=out["responses"], loops=out["loops"], models={},
                     three_axis=out)


def input_warning_lines(scene) -> list[str]:
    """The scene's values that look like unit slips (:attr:`Scene.input_warnings`), as warning
    lines (``UnitWarning: <file>: <key>: ...``)."""
    return [f"UnitWarning: {line}" for line in scene.input_warnings]


def check_options(**options) -> None:
    """TypeError naming an option of :func:`run` or :func:`spacecraft.write_report` that is
    not what it must be: ``progress`` None or a function of one message, the others a bool
    (``fmus`` and ``plots`` also None: the scene's choice)."""
    for name, value in options.items():
        if name == "progress":
            if value is not None and not callable(value):
                raise TypeError(f"progress must be None or a function of one message; got "
                                f"{type(value).__name__}")
        elif not isinstance(value, bool) and not (value is None and name in ("fmus", "plots")):
            allowed = "True, False or None" if name in ("fmus", "plots") else "True or False"
            raise TypeError(f"{name} must be {allowed}; got {type(value).__name__} {value!r:.60}")


def warning_lines(caught) -> list[str]:
    """Distinct warnings as one line each (``Category: message (module:line)``), at most 20,
    each at most about 300 characters: what the report and the command line show instead of
    numpy's or scipy's multi-line output."""
    seen: dict = {}
    for w in caught:
        if issubclass(w.category, controllers.RemovedModesWarning):
            continue  # the report's section on the modes left out of the design
        message = " ".join(str(w.message).split())
        if len(message) > 250:
            message = message[:250] + "..."
        key = (w.category.__name__, message)
        seen.setdefault(key, f"{Path(w.filename).name}:{w.lineno}")
    lines = [f"{category}: {message} ({where})"
             for (category, message), where in list(seen.items())[:_MAX_WARNINGS]]
    if len(seen) > _MAX_WARNINGS:
        lines.append(f"... and {len(seen) - _MAX_WARNINGS} more distinct warnings")
    return lines
