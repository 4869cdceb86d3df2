"""Run a three-axis scene and write its report (issue 11, item 5).

A scene whose hub has a 3x3 inertia tensor (:attr:`spacecraft.scene.read.Scene.three_axis`) runs
here, beside the planar runner (:mod:`spacecraft.design.loop`), through the same steps:

- models: each appendage's distributed beam (every motion: bending in two planes, torsion,
  axial), its truth model (the beam truncated to ``fidelity.n_modes`` Craig-Bampton modes, 10
  when the scene gives a tolerance instead: the tolerance-driven choice of
  :mod:`spacecraft.design.fidelity` is planar) and its design model (the 3-D chain fitted with
  :func:`appendages.fit_chain_3d`, first criterion of ``fit.match``);
- plants: the truth spacecraft with tip motions in both planes and twist (when asked) and the
  design spacecraft, pruned as the scene says;
- controllers tuned on the design plant (PD per principal axis, LQR + Kalman with the scene's
  weights on every axis), continuous or digital;
- loops closed on the design and truth plants, the eigen-axis slew about ``manoeuvre.slew_axis``
  simulated on both, metrics per axis, loop-at-a-time and disk margins on the truth plant;
- the exact coupled frequencies of the distributed spacecraft (through W6) beside the truth
  model's.

:func:`write_three_axis_report` writes results.json, report.md and report.html, the slew plots
(attitude per axis, tip deflection in both planes and twist per appendage) and the FMUs asked
for (plant, controller, closed loop; FMI 2.0 and/or 3.0).
"""

from __future__ import annotations

import datetime
import math
import warnings
from pathlib import Path

import numpy as np

import controllers
import fmu
from appendages import fit_chain_3d

from ..dynamics.coupling import Spacecraft
from ..dynamics.hub import Hub, Mount
from ..report.pages import Tone, bad, markdown, render_html, warn
from ..scene.reader import SceneError
from ..scene.specs import scene_dict
from .verdicts import CAUTIONS, growing, loop_warnings, verdict_dict

__all__ = ["run_three_axis", "write_three_axis_report", "three_axis_summary", "DEFAULT_MODES"]

#: Craig-Bampton modes per beam when the scene gives a tolerance rather than ``n_modes``.
DEFAULT_MODES = 10
AXES = ("x", "y", "z")


def _spacecraft(scene, models: dict) -> Spacecraft:
    """The scene's hub carrying ``models[name]`` at each appendage's mount."""
    hub = Hub(scene.hub.mass, np.array(scene.hub.inertia))
    return Spacecraft(hub, [Mount(models[a.name], a.position,
                                  orientation=np.array(a.orientation), name=a.name)
                            for a in scene.appendages])


def _controller(scene, kind: str, design):
    spec = scene.controller
    T = spec.sample_time
    if kind == "pd":
        pd = spec.pd
        return controllers.pd(design, natural_frequency=pd.natural_frequency,
                              bandwidth=pd.bandwidth, damping=pd.damping, roll_off=pd.roll_off,
                              sample_time=T)
    lqr = spec.lqr
    return controllers.lqr(design, attitude_weight=lqr.attitude_weight,
                           rate_weight=lqr.rate_weight, torque_weight=lqr.torque_weight,
                           estimator_speed=lqr.estimator_speed, sample_time=T)


def _scene_error(scene, key: str, exc: Exception) -> SceneError:
    return SceneError(f"{scene.source}: {key}: {str(exc)[:400]}")


def run_three_axis(scene, *, progress=None, time_responses: bool = True) -> dict:
    """Models, controllers, loops, responses and margins of a three-axis scene.

    Parameters
    ----------
    scene : spacecraft.scene.read.Scene
        A validated three-axis scene.
    progress : callable, optional
        Called with a short message at the start of each stage.
    time_responses : bool
        Simulate the slew (False: tune and close the loops only, e.g. to export FMUs).

    Returns
    -------
    dict
        ``data`` (JSON-ready numbers of the report), ``plants``, ``controllers``, ``loops``,
        ``responses`` (python-control objects for the report writer).

    Raises
    ------
    SceneError
        A controller that cannot be tuned on the design model, named by its scene key.
    """
    progress = progress or (lambda message: None)
    beams = {a.name: a.beam.build() for a in scene.appendages}
    n_modes = scene.fidelity.n_modes or DEFAULT_MODES
    progress("fitting 3-D chains")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        chains = {a.name: fit_chain_3d(beams[a.name], a.fit.n_bodies, match=a.fit.match[0])
                  for a in scene.appendages}
    truth_craft = _spacecraft(scene, {n: b.truncated(n_modes) for n, b in beams.items()})
    design_craft = _spacecraft(scene, chains)
    exact_craft = _spacecraft(scene, beams)
    prune = scene.fidelity.prune
    truth = truth_craft.plant(tip_deflection=scene.outputs.tip_deflection,
                              root_loads=scene.outputs.root_loads, prune=prune, name="truth")
    design = design_craft.plant(prune=True, name="design")
    n_freq = min(12, truth.nstates // 2 - 3)
    data: dict = {
        "three_axis": True, "title": scene.title, "source": scene.source,
        "truth_model": f"each beam {n_modes} Craig-Bampton modes"
                       + (" (pruned)" if prune else ""),
        "design_model": ", ".join(f"{a.name}: {a.fit.n_bodies}-body 3-D chain "
                                  f"({a.fit.match[0]})" for a in scene.appendages),
        "truth_states": truth.nstates, "design_states": design.nstates,
        "exact_frequencies_rad_s": exact_craft.natural_frequencies(n_freq).tolist(),
        "truth_frequencies_rad_s": truth_craft.natural_frequencies(n_freq).tolist(),
        "design_frequencies_rad_s": design_craft.natural_frequencies(
            min(n_freq, design.nstates // 2 - 3)).tolist(),
        "closed_loops": [], "design_warnings": [], "warnings": [], "scene": scene_dict(scene),
    }
    out = {"data": data, "plants": {"truth": truth, "design": design}, "controllers": {},
           "loops": {}, "responses": {}}
    m = scene.manoeuvre
    for kind in scene.controller.types:
        progress(f"tuning {kind.upper()}")
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                K = _controller(scene, kind, design)
            except ValueError as exc:
                raise _scene_error(scene, f"controller.{kind}", exc) from None
            data["warnings"] += [f"{kind}: {w.message}"[:300] for w in caught]
        out["controllers"][kind] = K
        row = {"controller": kind, "digital": bool(K.dt), "states": K.nstates}
        for model, plant in (("design", design), ("truth", truth)):
            loop = controllers.close_loop(plant, K)
            out["loops"][kind, model] = loop
            poles = np.linalg.eigvals(loop.A)
            if K.dt:
                poles = np.log(poles[np.abs(poles) > 0]) / K.dt
            row[f"{model}_stable"] = bool(np.max(poles.real) < 0)
            if time_responses and m is not None:
                progress(f"simulating the {kind.upper()} loop on the {model} model")
                response = controllers.slew(loop, m.slew_angle, m.slew_time, t_final=m.duration,
                                            dt=m.step, axis=np.array(m.slew_axis))
                out["responses"][kind, model] = response
                row[f"{model}_metrics"] = controllers.metrics(response)
        progress(f"margins of the {kind.upper()} loop")
        verdict = verdict_dict(controllers.spillover(truth, K))
        row["verdict"] = verdict
        row["truth_margins"] = _margins_of(verdict)
        data["closed_loops"].append(row)
        data["design_warnings"] += [
            {**w, "controller": kind} for w in loop_warnings(_who(row), verdict)]
    return out


def _who(row: dict) -> str:
    return f"{row['controller'].upper()}{' (digital)' if row['digital'] else ''}"


def _margins_of(verdict: dict) -> dict:
    """The margins of a three-axis verdict (per axis, disk, return difference), as the report
    lists them."""
    names = [f"{k}_{a}" for a in AXES for k in ("gain_margin", "phase_margin", "modulus_margin")]
    names += ["disk_margin", "disk_gain_margin", "disk_phase_margin", "min_singular_value"]
    return {k: verdict[k] for k in names if k in verdict}


def _fmt(value) -> str:
    """The report's number format (4 significant digits; None as "n/a", booleans as yes/no)."""
    from ..report.write import _fmt as report_format  # report imports this module
    return report_format(value.item() if isinstance(value, np.generic) else value, 4)


def _state(row: dict, warnings: list) -> str | Tone:
    """A loop's verdict on the truth model, toned: red when it diverges (its margin figures
    then guarantee nothing and are not given as margins), orange with a caution (low margins,
    lowered or light damping), else plain."""
    v = row["verdict"]
    if growing(v):
        zeta, w = v.get("least_damping_ratio"), v.get("least_damped_frequency")
        where = (f" (growing pole at {w:.4g} rad/s, damping ratio {zeta:.3g})"
                 if zeta is not None and w is not None else "")
        return bad(f"UNSTABLE{where}: no margins, it diverges unperturbed")
    state = "stable" if row["truth_stable"] else "marginally stable"
    text = (f"{state}, disk margin {v['disk_margin']:.3g} (gain {v['disk_gain_margin']:.3g} "
            f"dB, phase {v['disk_phase_margin']:.3g} deg in every channel at once)")
    mine = [w["code"] for w in warnings if w.get("controller") == row["controller"]]
    if mine:
        return warn(text + "; " + ", ".join(dict.fromkeys(CAUTIONS.get(c, c) for c in mine)))
    return text


def three_axis_summary(data: dict) -> list:
    """Short summary lines of a three-axis run (the command line prints them): the models, one
    line per loop, one per design warning (``warning: ...``)."""
    lines: list = [f"truth: {data['truth_model']} ({data['truth_states']} states); design: "
                   f"{data['design_model']}"]
    warnings = data.get("design_warnings", [])
    for row in data["closed_loops"]:
        state = _state(row, warnings)
        line = f"{_who(row)} on the truth model: {state}"
        lines.append(Tone(line, state.tone) if isinstance(state, Tone) else line)
    lines += [warn(f"warning: {w['message']}") for w in warnings]
    return lines


def _margin_rows(row: dict) -> list:
    """The margins table of a loop: red when the loop diverges, orange below a threshold."""
    flags = row["verdict"].get("margin_flags", {})
    out = []
    for k, value in row["truth_margins"].items():
        text = _fmt(value)
        flag = flags.get(k)
        out.append([k, bad(f"{text} (unstable: no margin)") if flag == "unstable"
                    else warn(text) if flag == "low" else text])
    return out


def _blocks(scene, data: dict, images: list) -> list:
    blocks: list = [("h1", data["title"] or "flexsat three-axis run"),
                    ("p", f"Scene {data['source']}: hub {scene.hub.mass:g} kg, inertia tensor "
                          f"{[list(r) for r in scene.hub.inertia]} kg m^2; "
                          f"{len(scene.appendages)} appendages."),
                    ("ul", [f"truth: {data['truth_model']}, {data['truth_states']} states",
                            f"design: {data['design_model']}, {data['design_states']} states"])]
    n = len(data["truth_frequencies_rad_s"])
    blocks += [("h2", "Coupled frequencies"),
               ("table", ["mode", "exact (W6) [rad/s]", "truth [rad/s]", "truth error",
                          "design [rad/s]", "design error"],
                [[str(k + 1), f"{e:.6g}", f"{t:.6g}", f"{t / e - 1:.1e}",
                  *((f"{d:.6g}", f"{d / e - 1:.1e}") if k < len(data["design_frequencies_rad_s"])
                    else ("-", "-"))]
                 for k, (e, t, d) in enumerate(zip(data["exact_frequencies_rad_s"],
                                                   data["truth_frequencies_rad_s"],
                                                   data["design_frequencies_rad_s"]
                                                   + [math.nan] * n))])]
    for row in data["closed_loops"]:
        kind = row["controller"].upper() + (" (digital)" if row["digital"] else "")
        blocks.append(("h2", f"{kind} loop"))
        stable = [f"design: " + ("stable" if row["design_stable"] else bad("UNSTABLE")),
                  Tone("truth: " + _state(row, data.get("design_warnings", [])),
                       getattr(_state(row, data.get("design_warnings", [])), "tone", ""))]
        blocks.append(("ul", stable))
        metrics = {model: row.get(f"{model}_metrics") for model in ("design", "truth")}
        if metrics["truth"]:
            keys = [k for k in metrics["truth"] if not isinstance(metrics["truth"][k], dict)]
            blocks.append(("p", "Metrics of the slew (SI: attitude errors in rad, torques in "
                                "N m, tip deflections in m, twist in rad, overshoot in %, "
                                "settling time in s); the attitude error is the norm of the "
                                "three axes' errors, then each axis."))
            blocks.append(("table", ["metric", "design", "truth"],
                           [[k, _fmt(metrics["design"].get(k)), _fmt(metrics["truth"][k])]
                            for k in keys]))
        if growing(row["verdict"]):
            blocks.append(("p", bad("The loop is UNSTABLE on the truth model: it diverges "
                                    "without any perturbation, so the figures below are no "
                                    "margins and guarantee nothing (loop-at-a-time per axis, "
                                    "the disk margin alpha with its gain [dB] and phase [deg], "
                                    "the smallest singular value of I + L).")))
        else:
            blocks.append(("p", "Margins on the truth model: loop-at-a-time per axis (gain in "
                                "dB, phase in deg), the multivariable disk margin (alpha, and "
                                "the gain [dB] and phase [deg] it guarantees in all loops at "
                                "once) and the smallest singular value of the return "
                                "difference I + L; below the thresholds of "
                                "spacecraft.design.verdicts (6 dB, 30 deg, 0.5, alpha 2/3) in "
                                "orange."))
        blocks.append(("table", ["margin", "value"], _margin_rows(row)))
        v = row["verdict"]
        blocks.append(("p", f"Least-damped closed-loop pole: {_fmt(v['least_damped_frequency'])} "
                            f"rad/s, damping ratio {_fmt(v['least_damping_ratio'])}."))
    if data.get("design_warnings") or data["warnings"]:
        blocks += [("h2", "Warnings"),
                   ("ul", [warn(w["message"]) for w in data.get("design_warnings", [])]
                    + list(data["warnings"]))]
    for path, caption in images:
        blocks.append(("img", path, caption))
    return blocks


def _plots(scene, out: dict, folder: Path) -> list:
    """Slew plots per loop: attitude per axis, tip motions per appendage (both planes,
    twist), design and truth overlaid."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    images = []
    folder.mkdir(exist_ok=True)
    for kind in scene.controller.types:
        if (kind, "truth") not in out["responses"]:
            continue
        responses = {model: out["responses"][kind, model] for model in ("design", "truth")}
        truth = responses["truth"]
        names = list(truth.output_labels)
        tips = [n for n in names if "_tip_" in n]
        fig, axes = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
        for model, style in (("design", "--"), ("truth", "-")):
            r = responses[model]
            labels = list(r.output_labels)
            for a in AXES:
                y = np.asarray(r.outputs)[labels.index(f"theta_{a}")]
                axes[0].plot(r.time, np.degrees(y), style, label=f"theta_{a} ({model})")
        axes[0].set_ylabel("attitude [deg]")
        axes[0].legend(fontsize=7, ncol=2)
        for name in tips:
            y = np.asarray(truth.outputs)[names.index(name)]
            scale, unit = (1e3, "mm") if "deflection" in name else (math.degrees(1.0) * 1e3,
                                                                     "mdeg")
            axes[1].plot(truth.time, scale * y, label=f"{name} [{unit}]")
        axes[1].set_xlabel("time [s]")
        axes[1].set_ylabel("tip motion (truth)")
        if tips:
            axes[1].legend(fontsize=6, ncol=2)
        fig.suptitle(f"{kind.upper()}: slew of {math.degrees(scene.manoeuvre.slew_angle):g} deg "
                     f"about {np.round(scene.manoeuvre.slew_axis, 3).tolist()}")
        path = folder / f"slew_{kind}.png"
        fig.savefig(path, dpi=90)
        plt.close(fig)
        images.append((f"plots/{path.name}", f"{kind.upper()} slew: attitude per axis, tip "
                       "deflections in both planes and twist"))
    return images


def _fmus(scene, out: dict, folder: Path) -> list:
    folder.mkdir(exist_ok=True)
    step = scene.export.step or (scene.manoeuvre.step if scene.manoeuvre else None)
    stop = scene.manoeuvre.duration if scene.manoeuvre else 100.0 * step
    files = []
    systems = []
    if "plant" in scene.export.systems:
        systems.append(("plant", out["plants"]["truth"], "the truth plant (three axes)"))
    for kind, K in out["controllers"].items():
        if "controller" in scene.export.systems:
            systems.append((f"controller_{kind}", K, f"the {kind.upper()} controller"))
        if "closed_loop" in scene.export.systems:
            systems.append((f"closed_loop_{kind}", out["loops"][kind, "truth"],
                            f"the {kind.upper()} loop on the truth plant"))
    for version in scene.export.fmi_versions:
        for name, system, description in systems:
            model = f"{name}_fmi{version[0]}"
            path = fmu.export(system, folder / f"{model}.fmu", fmi_version=version,
                              step=None if system.dt else step, stop_time=stop,
                              reference=scene.export.reference_files,
                              sources_only=scene.export.sources_only,
                              description=f"flexsat: {description}")
            files.append({"path": f"fmu/{path.name}", "description": description,
                          "fmi_version": version})
    return files


def write_three_axis_report(scene, out: dict, folder, *, fmus: bool | None = None,
                            plots: bool | None = None, pages: bool = True, progress=None) -> dict:
    """Write the report of a three-axis run into ``folder`` (see the module docstring);
    returns the results written to results.json."""
    from ..report.write import to_json, version

    folder = Path(folder)
    progress = progress or (lambda message: None)
    data = dict(out["data"])
    data["version"] = version()
    data["created"] = datetime.datetime.now().isoformat(timespec="seconds")
    files: dict = {"fmu": [], "plots": []}
    if scene.export.fmu if fmus is None else (fmus and scene.export.fmu):
        progress("exporting FMUs")
        files["fmu"] = _fmus(scene, out, folder / "fmu")
    images = []
    if pages and "slew" in scene.report.plots and plots is not False:
        progress("plotting")
        images = _plots(scene, out, folder / "plots")
    files["plots"] = [p for p, _ in images]
    data["files"] = files
    if pages:
        progress("writing report")
        blocks = _blocks(scene, data, images)
        (folder / "report.md").write_text(markdown(blocks), encoding="utf-8")
        (folder / "report.html").write_text(render_html(blocks, data["title"] or "flexsat"),
                                            encoding="utf-8")
        data["files"]["pages"] = ["report.md", "report.html", "results.json"]
        (folder / "results.json").write_text(to_json(data), encoding="utf-8")
    return data
