"""The report of a scene run: Markdown and HTML pages, PNG plots, results.json, time series, FMUs.

:func:`write_report` writes a :class:`~spacecraft.design.loop.RunResult` into a folder. The same list
of blocks (:mod:`spacecraft.report.pages`) renders to ``report.md`` and ``report.html``, so both say
the same; every number shown is also in ``results.json`` (numbers only, :mod:`spacecraft.report.results`).
:func:`output_folder` makes the folder appear only when complete.

The report, in the order an attitude engineer reads it:

- Summary: per loop its verdict on the truth model (stable, or UNSTABLE: diverges, in red),
  its margins, the slew's overshoot and settling time, the peak tip deflection per appendage;
  then the design warnings (:mod:`spacecraft.design.verdicts`);
- The question asked: hub, appendages, manoeuvre, disturbance, sample rate, outputs;
- Models: the truth model's fidelity and why (the tolerance, the band it had to match), the
  coupled frequencies of exact beam, truth and design models;
- Controllers: the control law, gains (PD: J, wn, zeta, Kp, Kd, filters; LQR: weights, K, L,
  regulator and estimator poles), sample rate and Nyquist frequency, the modes left out of the
  design and why;
- Equivalence criterion of the fitted chains (the paper's table against the exact beam);
- Closed loops: per controller the slew's metrics design vs truth (withheld for a diverging
  loop), the margins with their crossover frequencies, the peaks per appendage (tip
  deflection, root force and moment when asked), the disturbance response apart from the slew,
  the verdicts (spillover on the truth model, Nyquist on the exact beam);
- Basilisk's run of the manoeuvre, when asked (:mod:`spacecraft.design.simulators`);
- Plots (:mod:`spacecraft.report.plots`), FMUs and SSP files (:mod:`spacecraft.report.exports`), the time
  series, numerical warnings, the work done.
"""

from __future__ import annotations

import datetime
import math
import os
from pathlib import Path

import numpy as np

from ..design.naming import MOTION_WORDS, controller_label, design_label, plural
from ..design.simulators import peak_difference_text
from .flown import basilisk_wheel_blocks, flown_blocks, flown_summary_lines
from .output import MARKER, default_output_folder, output_folder
from .pages import Tone, bad, markdown, markdown_text, number, render_html, warn
from .results import to_json, write_timeseries
from .modes import modal_table_blocks
from .structures import structure_text, truth_text

__all__ = ["write_report", "output_folder", "default_output_folder", "to_json", "markdown",
           "render_html", "equivalence_markdown", "metric_rows", "summary_lines", "MARKER",
           "markdown_text", "report_blocks", "METRIC_LABELS", "MARGIN_LABELS"]


# ---------------------------------------------------------------------------------------------
# numbers
# ---------------------------------------------------------------------------------------------
_fmt = number


def _percent(value) -> str:
    if value is None or not math.isfinite(value):
        return "n/a"
    return f"{100.0 * value:+.2f} %"


def _label(variant: str) -> str:
    return design_label(variant)


# ---------------------------------------------------------------------------------------------
# tables
# ---------------------------------------------------------------------------------------------
def equivalence_markdown(table: dict) -> tuple[list, list]:
    """Header and rows of the paper's table with errors against the exact model."""
    header = ["quantity", table.get("reference", "beam (exact)")]
    for column in table["columns"]:
        header += [column["name"], "error"]
    rows = []
    for i, (label, unit) in enumerate(zip(table["quantities"], table["units"])):
        row = [f"{label} [{unit}]", _fmt(table["exact"][i])]
        for column in table["columns"]:
            row += [_fmt(column["values"][i]), _percent(column["relative_error"][i])]
        rows.append(row)
    for r, name in enumerate(("W1", "W2", "W3", "W4")):
        row = [f"max abs ln(W/W_exact), {name}", "0"]
        for column in table["columns"]:
            row += [_fmt(column["max_log_error"][r], 3), ""]
        rows.append(row)
    return header, rows


METRIC_LABELS = {
    "overshoot": "overshoot [%]", "settling_time": "settling time (2 %) [s]",
    "peak_torque": "peak torque [N m]", "peak_tip_deflection": "peak tip deflection [m]",
    "peak_attitude_error": "peak attitude error [rad]",
    "final_attitude_error": "attitude error at the end [rad]",
    # three axes: the attitude error's norm above, then each hub axis
    **{f"{name}_{axis}": f"{text} about {axis} [{unit}]" for axis in "xyz"
       for name, text, unit in (("peak_torque", "peak torque", "N m"),
                                ("peak_attitude_error", "peak attitude error", "rad"),
                                ("final_attitude_error", "attitude error at the end", "rad"))},
}
MARGIN_LABELS = {"gain_margin": "gain margin [dB]", "phase_margin": "phase margin [deg]",
                 "modulus_margin": "modulus margin [-]",
                 "gain_crossover_frequency": "gain crossover [rad/s]",
                 "phase_crossover_frequency": "phase crossover [rad/s]",
                 # three axes: the multivariable margins, then each loop at a time
                 "disk_margin": "disk margin alpha [-]",
                 "disk_gain_margin": "disk gain margin, every channel at once [dB]",
                 "disk_phase_margin": "disk phase margin, every channel at once [deg]",
                 "min_singular_value": "smallest singular value of I + L [-]",
                 **{f"{name}_{axis}": f"{text} about {axis}, loop at a time [{unit}]"
                    for axis in "xyz" for name, text, unit in (
                        ("gain_margin", "gain margin", "dB"),
                        ("phase_margin", "phase margin", "deg"),
                        ("modulus_margin", "modulus margin", "-"),
                        ("gain_crossover_frequency", "gain crossover", "rad/s"))}}
#: The margins of a loop's verdict in the summary and the verdicts' table: (name, label, unit).
HEADLINE_MARGINS = {
    "planar": (("gain_margin", "gain margin", "dB"), ("phase_margin", "phase margin", "deg"),
               ("modulus_margin", "modulus margin", "")),
    "three_axis": (("disk_margin", "disk margin", ""),
                   ("disk_gain_margin", "disk gain margin", "dB"),
                   ("disk_phase_margin", "disk phase margin", "deg"),
                   ("min_singular_value", "min singular value of I + L", "")),
}


def _headline(verdict: dict) -> tuple:
    """The headline margins of a verdict: planar, or the three-axis (multivariable) ones."""
    return HEADLINE_MARGINS["three_axis" if "disk_margin" in verdict else "planar"]
_FLAG_TEXT = {"diverges": "diverges", "slew unfinished": "slew unfinished",
              "not settled": "not settled"}


def _cell(row: dict, table: str, which: str, name: str):
    """A metric's cell: its value, or why it is withheld (toned)."""
    flag = (row.get(table.replace("metrics", "flags") if table != "metrics" else "metric_flags")
            or {}).get(which, {}).get(name)
    if flag is not None:
        text = _FLAG_TEXT.get(flag, flag)
        return bad(text) if flag == "diverges" else warn(text)
    return _fmt((row.get(table) or {}).get(which, {}).get(name))


def metric_rows(rows: list, controller: str, table: str = "metrics") -> tuple[list, list]:
    """Header and rows of the closed-loop metrics of one controller, design vs truth
    (``table``: ``"metrics"`` of the slew or ``"disturbance_metrics"``)."""
    mine = [r for r in rows if r["controller"] == controller and r.get(table)]
    header = ["metric"]
    for r in mine:
        header += [f"{_label(r['design'])}: on design model", f"{_label(r['design'])}: on "
                   "truth model", "truth - design"]
    out = []
    if table == "metrics":
        status_row = ["response"]
        for r in mine:
            for which in ("design", "truth"):
                s = r["status"][which]
                text = s["text"] if s["status"] != "settles" else "settles"
                status_row.append(bad(text) if s["status"] in ("unstable", "diverges")
                                  else warn(text) if s["status"] != "settles" else text)
            status_row.append("")
        out.append(status_row)
    for name, label in METRIC_LABELS.items():
        if not any(name in r[table]["design"] for r in mine):
            continue
        row = [label]
        for r in mine:
            d, t = r[table]["design"].get(name), r[table]["truth"].get(name)
            diff = None if d is None or t is None else t - d
            row += [_cell(r, table, "design", name), _cell(r, table, "truth", name),
                    _fmt(diff, 3) if diff is not None else "-"]
        out.append(row)
    if table != "metrics":
        return header, out
    for name, label in MARGIN_LABELS.items():
        if not any(name in r["design_margins"] or name in r["verdict"] for r in mine):
            continue
        row = [label]
        for r in mine:
            d, t = r["design_margins"].get(name), r["verdict"].get(name)
            diff = None if d is None or t is None or not (math.isfinite(d) and math.isfinite(t)) \
                else t - d
            row += [_fmt(d, 4), _margin_cell(name, t, r["verdict"].get("margin_flags")),
                    _fmt(diff, 3)]
        out.append(row)
    return header, out


def _margin_cell(name: str, value, flags: dict | None = None):
    """A margin's cell: red for a margin of an unstable loop (it guarantees nothing), orange
    below its threshold (:func:`spacecraft.design.verdicts.margin_flags`)."""
    text = _fmt(value, 4)
    flag = (flags or {}).get(name)
    if flag == "unstable":
        return bad(f"{text} (unstable: no margin)")
    return warn(text) if flag == "low" else text


def _damping_cell(verdict: dict):
    """The least closed-loop damping ratio, orange below MIN_DAMPING on a loop that does not
    diverge (one that does is red already)."""
    from ..design.verdicts import MIN_DAMPING

    zeta = verdict.get("least_damping_ratio")
    text = _fmt(zeta, 3)
    return warn(text) if zeta is not None and 0 <= zeta < MIN_DAMPING else text


def _loop_cautions(row: dict, warnings: list) -> list[str]:
    """Short texts of the cautions on a loop that does not diverge (low margins, lowered or
    light damping, unstable on the exact beam), from its design warnings."""
    from ..design.verdicts import CAUTIONS as texts

    out = []
    for w in warnings:
        if (w.get("design"), w.get("controller")) == (row["design"], row["controller"]) \
                and w["code"] in texts:
            text = texts[w["code"]]
            if w["code"] == "light_damping":
                v = row["verdict"]
                text += (f" (zeta {_fmt(v['least_damping_ratio'], 2)} at "
                         f"{_fmt(v['least_damped_frequency'], 3)} rad/s)")
            out.append(text)
    return out


def _appendage_rows(rows: list, names: list) -> tuple[list, list]:
    """Peak tip deflection, root force and root moment per appendage, per loop."""
    from ..design.responses import APPENDAGE_SIGNALS

    header = ["loop", "appendage"]
    present = [(metric, unit) for _, metric, unit in APPENDAGE_SIGNALS
               if any(metric in p for r in rows for p in
                      (r.get("appendages") or {}).get("truth", {}).values())]
    if not present:
        return header, []
    for metric, unit in present:
        label = metric.replace("peak_", "peak ").replace("_", " ")
        header += [f"{label} [{unit}]: design", f"{label} [{unit}]: truth"]
    out = []
    for r in rows:
        if "appendages" not in r:
            continue
        for name in names:
            row = [f"{controller_label(r['controller'])} tuned on {_label(r['design'])}", name]
            for metric, _ in present:
                for which in ("design", "truth"):
                    value = r["appendages"][which].get(name, {}).get(metric)
                    gone = r["status"][which]["status"] in ("unstable", "diverges")
                    row.append(bad("diverges") if gone else _fmt(value, 4))
            out.append(row)
    return header, out


def _verdict_rows(rows: list, warnings: list = ()) -> tuple[list, list]:
    from ..design.verdicts import growing

    exact = any("exact_verdict" in r for r in rows)
    headline = _headline(rows[0]["verdict"]) if rows else HEADLINE_MARGINS["planar"]
    header = ["design model", "controller", "on truth model", "least damping [-]",
              "at [rad/s]"] + [f"{label} [{unit or '-'}]" for _, label, unit in headline]
    if exact:
        header += ["on exact beam (Nyquist)"]
    out = []
    for r in rows:
        v = r["verdict"]
        status = (r.get("status") or {}).get("truth")
        cautions = _loop_cautions(r, warnings)
        if growing(v, status):
            state = bad(status["text"] if status is not None else
                        f"UNSTABLE ({plural(v['n_unstable_poles'], 'pole')})")
        else:
            state = "stable" if v["stable"] else "marginally stable"
            if cautions:
                state = warn(f"{state}; " + ", ".join(cautions))
        flags = v.get("margin_flags")
        row = [_label(r["design"]), controller_label(r["controller"]), state,
               _damping_cell(v), _fmt(v["least_damped_frequency"], 4)]
        row += [_margin_cell(name, v.get(name), flags) for name, _, _ in headline]
        if exact:
            e = r.get("exact_verdict", {})
            row.append("n/a" if "stable" not in e else
                       ("stable" if e["stable"] else
                        bad(f"UNSTABLE ({plural(e['n_unstable_poles'], 'pole')})")))
        out.append(row)
    return header, out


# ---------------------------------------------------------------------------------------------
# summary
# ---------------------------------------------------------------------------------------------
def _fidelity_line(data: dict) -> str:
    fid = data.get("fidelity", {})
    truth = data["truth"]
    if fid.get("n_modes"):
        how = ("chosen for tolerance " + _fmt(fid["choice"]["tolerance"]) if fid.get("choice")
               else "given")
        return (f"truth model: {_modes(data, fid['n_modes'])} per beam "
                f"({fid['method']}, {how}); plant {plural(truth['n_states'], 'state')}, "
                f"{plural(truth['modes_dropped'], 'mode')} pruned")
    what = "as given (your Spacecraft)" if fid.get("given") else "the chains as given"
    return f"truth model: {what}; plant {plural(truth['n_states'], 'state')}"


def _loop_line(r: dict, warnings: list = ()) -> str | Tone:
    from ..design.verdicts import growing

    who = f"{controller_label(r['controller'])} tuned on {_label(r['design'])}"
    v = r["verdict"]
    status = (r.get("status") or {}).get("truth")
    margins = ", ".join(f"{label} {_fmt(v.get(name), 3)}{' ' + unit if unit else ''}"
                        for name, label, unit in _headline(v))
    if growing(v, status):
        # the classical numbers of a diverging loop are no margins: said so, never as margins
        bare = ", ".join(f"{label.replace(' margin', '')} {_fmt(v.get(name), 3)}"
                         f"{' ' + unit if unit else ''}" for name, label, unit in _headline(v))
        figures = (f"no margins: it diverges unperturbed (the margin figures, {bare}, "
                   "guarantee nothing)")
        what = (status["text"] if status is not None else
                f"UNSTABLE ({plural(v['n_unstable_poles'], 'pole')})")
        return bad(f"{who}: {what} on the truth model; {figures}")
    cautions = _loop_cautions(r, warnings)
    state = "stable" if v["stable"] else "marginally stable"
    text = (f"{who}: {state} on the truth model"
            + (f" ({', '.join(cautions)})" if cautions else "") + f"; {margins}")
    if status is not None:
        m = r["metrics"]["truth"]
        if status["status"] == "slew unfinished":
            text += "; the simulated time ends before the slew"
        else:
            if m.get("overshoot") is not None:
                text += f"; overshoot {_fmt(m['overshoot'], 3)} %"
            if m.get("settling_time") is not None:
                text += f", settles in {_fmt(m['settling_time'], 4)} s"
            elif status["status"] == "not settled":
                text += ", does not settle within the simulated time"
        peaks = r.get("appendages", {}).get("truth", {})
        tips = [(n, _tip_peak(p)) for n, p in peaks.items() if _tip_peak(p) is not None]
        if tips:
            text += "; peak tip deflection " + ", ".join(
                f"{_fmt(value, 3)} m ({name})" for name, value in tips)
    caution = cautions or (status is not None and status["status"] != "settles")
    return warn(text) if caution else text


def _modes(data: dict, n: int) -> str:
    """What a truncated beam keeps: n bending modes (planar), the n lowest modes of every
    motion (three axes: both bending planes, torsion and axial motion together)."""
    if data.get("three_axis"):
        if (data.get("fidelity") or {}).get("motions_kept"):
            return (f"the lowest mode of every motion a reported output sees and "
                    f"{plural(n, 'mode')} more (the lowest of the rest)")
        return f"{plural(n, 'mode')} (the lowest of all motions)"
    return plural(n, "bending mode")


def _tip_peak(peaks: dict) -> float | None:
    """An appendage's peak tip deflection [m]: planar, or the larger of a three-axis
    appendage's two bending planes."""
    values = [peaks.get(k) for k in ("peak_tip_deflection", "peak_tip_deflection_y",
                                     "peak_tip_deflection_z")]
    values = [v for v in values if v is not None]
    return max(values) if values else None


def summary_lines(data: dict) -> list:
    """Short summary of a run (the CLI prints it): the truth model, one line per loop, one per
    design warning (``warning: ...``)."""
    lines: list = [_fidelity_line(data)]
    lines += [_loop_line(r, data.get("design_warnings", []))
              for r in data.get("closed_loops", [])]
    b = data.get("basilisk")
    if b:
        for kind, entry in b.items():
            lines.append(f"Basilisk, {controller_label(kind)}: " + entry["summary"])
    lines += flown_summary_lines(data)
    lines += [warn(f"warning: {w['message']}") for w in data.get("design_warnings", [])]
    return lines


# ---------------------------------------------------------------------------------------------
# sections
# ---------------------------------------------------------------------------------------------
def _question(data: dict) -> list:
    """What the scene asked: hub, appendages, controllers, manoeuvre, outputs."""
    s = data.get("scene_resolved")
    if not s:
        return []
    J = s["hub"]["inertia"]
    three_axis = isinstance(J, list)
    inertia = ("[" + "; ".join(", ".join(_fmt(v) for v in row) for row in J) + "] (hub axes)"
               if three_axis else _fmt(J))
    items = [f"hub: mass {_fmt(s['hub']['mass'])} kg, inertia {inertia} kg m^2 about its "
             "centre of mass"]
    for a in s["appendages"]:
        truth = truth_text(a)
        design = {"fit": "chains fitted to it (" + " and ".join(
            _label(m) for m in (a["fit"] or {}).get("match", [])) + ")",
                  "chain": "the given chain", "truth": "the truth model itself"}[a["design"]]
        what = structure_text(a)
        position = ", ".join(_fmt(x) for x in a["position"])
        if a.get("orientation") is not None:
            # the appendage's axis: the first column of its orientation (hub axes)
            # (the Euler angles' round-off, 1e-16, shown as 0)
            along = ", ".join(_fmt(row[0] if abs(row[0]) > 1e-12 else 0.0, 4)
                              for row in a["orientation"])
            mount = f"at ({position}) m, along ({along}) in hub axes"
        else:
            mount = (f"at ({position}) m, direction {_fmt(math.degrees(a['direction']), 4)} "
                     "deg")
        items.append(f"appendage {a['name']}{what} {mount}: truth model {truth}, design model "
                     f"{design}")
    c = s["controller"]
    rate = c.get("sample_time")
    items.append("controllers: " + ", ".join(controller_label(k) for k in c["types"]) + "; "
                 + (f"digital at {_fmt(1.0 / rate)} Hz (sample time {_fmt(rate)} s, zero-order "
                    "hold)" if rate else "continuous-time"))
    m = s.get("manoeuvre")
    if m:
        about = ("" if m.get("slew_axis") is None else " about (" + ", ".join(
            _fmt(e, 4) for e in m["slew_axis"]) + ") in hub axes (an eigen-axis slew)")
        items.append(f"manoeuvre: slew of {_fmt(math.degrees(m['slew_angle']), 5)} deg{about} "
                     f"in {_fmt(m['slew_time'])} s (cycloidal), simulated for "
                     f"{_fmt(m['duration'])} s at a step of {_fmt(m['step'])} s")
        d = m.get("disturbance")
        if d:
            unit = "N m" if d["input"].startswith("disturbance_torque") else "N"
            length = (f"for {_fmt(d['length'])} s" if d.get("length") is not None
                      else "to the end")
            along = ("" if d.get("axis") is None else " along (" + ", ".join(
                _fmt(e, 4) for e in d["axis"]) + ") in hub axes")
            items.append(f"disturbance: {_fmt(d['amplitude'])} {unit} on {d['input']}{along} "
                         f"from t = {_fmt(d['start'])} s {length} (its response is reported "
                         "apart from the slew's)")
    o = s["outputs"]
    asked = [k.replace("_", " ") for k in ("tip_deflection", "root_loads", "exact_reference")
             if o.get(k)]
    items.append("outputs: " + (", ".join(asked) if asked else "attitude, rate and torque only"))
    sim = s.get("simulator", {})
    if sim.get("name") == "basilisk":
        items.append("simulator: flexsat and Basilisk (the design chains, nonlinear)")
    return [("h2", "The question"), ("ul", items)]



def _models(data: dict) -> list:
    b: list = [("h2", "Models")]
    fid = data["fidelity"]
    truth = data["truth"]
    if fid.get("n_modes"):
        b.append(("p", f"Truth model: every distributed beam truncated to "
                       f"{_modes(data, fid['n_modes'])} ({fid['method']}); the coupled "
                       f"plant keeps {truth['modes_kept']} of {plural(truth['modes_total'], 'mode')}"
                       f" ({truth['modes_dropped']} pruned: not excited by the inputs or not "
                       f"seen by the outputs) and has {plural(truth['n_states'], 'state')}."))
        per_motion = fid.get("modes_per_motion")
        if per_motion:
            kept = fid.get("motions_kept") or []
            text = ("Modes per motion of each truncated beam (bending in its x-y and x-z planes, "
                    "torsion, axial): " + "; ".join(
                        f"{name} " + ", ".join(f"{m} {c}" for m, c in counts.items())
                        for name, counts in per_motion.items()) + ".")
            if kept:
                text += (" Each keeps the lowest mode of every motion a reported output sees (" +
                         ", ".join(MOTION_WORDS.get(m, m) for m in kept) + "), however stiff, "
                         "so that no output of the truth model misses that motion for want of a "
                         "mode; n_modes counts the modes beyond those.")
            b.append(("p", text))
        pinned = fid.get("pinned")
        if pinned is not None:
            b.append(("p", "The scene pins the modes per motion beside n_modes "
                           "(fidelity.modes_per_motion" + (": " + "; ".join(
                               f"{name} " + ", ".join(f"{m} {c}" for m, c in counts.items())
                               for name, counts in pinned.items()) if pinned else
                               ", empty: the lowest mode of every seen motion only") +
                           "): the modes a run from fidelity.tolerance adds for its tip "
                           "outputs, given here rather than chosen, so this run does not check "
                           "them against a tolerance."))
        choice = fid.get("choice")
        if choice:
            b.append(("p", f"Why {fid['n_modes']}: n_modes is the smallest number meeting the "
                           f"relative tolerance {_fmt(choice['tolerance'])} on the coupled "
                           f"frequencies up to {_fmt(choice['reference_frequencies'][-1], 4)} "
                           f"rad/s (bandwidth_factor {_fmt(fid.get('bandwidth_factor'))} x the "
                           "controllers' bandwidth, and the first mode above) and on the gain "
                           f"|theta/torque| on [{_fmt(choice['band'][0], 3)}, "
                           f"{_fmt(choice['band'][1], 3)}] rad/s, against the exact beam."))
            b.append(("table", ["n_modes", "frequency error [-]", "gain error [-]"],
                      [[t["n_modes"], _fmt(t["frequency_error"], 3), _fmt(t["gain_error"], 3)]
                       for t in choice["trials"]]))
            b += _tip_fidelity(choice)
            b += _closed_loop_fidelity(choice)
        else:
            b.append(("p", "n_modes was given by the scene (fidelity.n_modes)."))
        for name, r in truth.get("resolved", {}).items():
            band = truth.get("loop_band")
            text = (f"The truth model of {name} ({r['model']}) represents it up to about "
                    f"{_fmt(r['frequency'], 4)} rad/s")
            if band is not None:
                text += (f"; the loops act below {_fmt(band, 4)} rad/s (bandwidth_factor x "
                         "the fastest crossover)")
                if band <= r["frequency"]:
                    text += "."
                elif r.get("covers_loops"):
                    text += (": one more mode per beam changes the closed loops in that band by "
                             "less than the tolerance (above), so no mode that matters there "
                             "is missing.")
                else:
                    text = warn(text + ": modes missing there.")
            b.append(("p", text))
    else:
        what = ("as given (your Spacecraft)" if fid.get("given") else
                "the modal data (all their modes) and chains as given" if any(
                    a.get("truth") == "modal" for a in data.get("scene_resolved", {}).get(
                        "appendages", [])) else "the chains as given")
        b.append(("p", f"Truth model: {what}; the plant has "
                       f"{plural(truth['n_states'], 'state')} ({truth['modes_dropped']} of "
                       f"{plural(truth['modes_total'], 'mode')} pruned)."))
    header = ["mode"]
    columns = []
    if "exact" in data:
        header.append("exact (through W)")
        columns.append(data["exact"]["coupled_frequencies"])
    header.append("truth model")
    columns.append(truth["coupled_frequencies"])
    for name, d in data.get("designs", {}).items():
        header.append(f"design: {_label(name)}")
        columns.append(d["coupled_frequencies"])
    n = min(6, max(len(c) for c in columns))
    b.append(("h3", "Coupled natural frequencies [rad/s]"))
    b.append(("table", header, [[k + 1] + [_fmt(c[k]) if k < len(c) else "-" for c in columns]
                                for k in range(n)]))
    b += modal_table_blocks(data)
    return b


def _controllers(data: dict) -> list:
    ctrl = data.get("controllers")
    if not ctrl:
        return []
    b: list = [("h2", "Controllers")]
    removed = []
    digital = {(r["design"], r["controller"]): r.get("digital") for r in
               data.get("closed_loops", [])}
    for variant, kinds in ctrl.items():
        for kind, c in kinds.items():
            who = f"{controller_label(kind)} tuned on {_label(variant)}"
            b.append(("h3", who))
            items = [f"control law: {c['structure']}"]
            if c.get("given"):
                items.append("the controller's matrices are in results.json (controllers)")
            elif c["kind"] == "pd" and "principal_moments" in c:
                # three axes: J, Kp and Kd are matrices, diagonal in the principal axes
                J = np.asarray(c["principal_moments"], dtype=float)
                wn, zeta = c["natural_frequency"], c["damping"]
                items += [f"design inertia J: principal moments {_vector(J)} kg m^2 (rigid-body "
                          "limit of the design plant; the gains act along its principal axes)",
                          f"natural frequency wn = {_fmt(wn)} rad/s, damping ratio "
                          f"{_fmt(zeta)} about every axis",
                          f"Kp = J wn^2 = {_vector(J * wn**2)} N m/rad, Kd = 2 zeta wn J = "
                          f"{_vector(2.0 * zeta * wn * J)} N m s/rad about the principal axes"]
                items += _filters(c)
            elif c["kind"] == "pd":
                items += [f"design inertia J = {_fmt(c['inertia'])} kg m^2 (rigid-body limit of "
                          "the design plant)",
                          f"natural frequency wn = {_fmt(c['natural_frequency'])} rad/s, damping "
                          f"ratio {_fmt(c['damping'])}",
                          f"Kp = J wn^2 = {_fmt(c['Kp'])} N m/rad, Kd = 2 zeta wn J = "
                          f"{_fmt(c['Kd'])} N m s/rad"] + _filters(c)
            else:
                items += [f"weights: attitude {_fmt(c['attitude_weight'])} 1/rad^2, rate "
                          f"{_fmt(c['rate_weight'])} s^2/rad^2, torque {_fmt(c['torque_weight'])}"
                          " 1/(N m)^2" + (f", tip deflection {_fmt(c['deflection_weight'])} 1/m^2"
                                          if c.get("deflection_weight") else ""),
                          (f"rigid-body regulator frequency (q / (r J^2))^(1/4) = "
                           f"{_fmt(c['rigid_body_frequency'], 4)} rad/s" if
                           "rigid_body_frequencies" not in c else
                           "rigid-body regulator frequencies (q / (r J^2))^(1/4) about the "
                           f"principal axes (J = {_vector(c['principal_moments'])} kg m^2): "
                           f"{_vector(c['rigid_body_frequencies'], 4)} rad/s")
                          + f"; estimator {_fmt(c['estimator_speed'])} x faster",
                          f"controller states: {c['n_states']} (the estimate of the design "
                          "model's states)",
                          "regulator poles [1/s]: " + _poles_text(c["regulator_poles"])
                          + (" (mapped from the z-plane by s = ln(z)/T)"
                             if c.get("sample_time") else ""),
                          "estimator poles [1/s]: " + _poles_text(c["estimator_poles"])]
            facts = digital.get((variant, kind))
            if facts:
                items.append(f"digital: {_fmt(facts['sample_rate'])} Hz (T = "
                             f"{_fmt(facts['sample_time'])} s), Nyquist frequency pi/T = "
                             f"{_fmt(facts['nyquist_frequency'], 4)} rad/s"
                             + (f"; the zero-order hold lags {_fmt(facts['hold_phase_lag_at_crossover'], 3)}"
                                f" deg at the rigid-body crossover "
                                f"{_fmt(facts['crossover_frequency'], 3)} rad/s"
                                if "hold_phase_lag_at_crossover" in facts
                                else ""))
            else:
                items.append("continuous-time")
            b.append(("ul", items))
            if c["kind"] == "lqr" and not c.get("given"):
                b.append(("table", *_lqr_gains(c)))
            for line in c.get("removed_modes", []):
                removed.append(f"{who}: {line}")
    b.append(("h3", "Modes left out of the design and why"))
    if removed:
        b.append(("p", "A mode that the loop cannot influence (its participation seen from "
                       "torque to theta and omega is below controllers.INFLUENCE_TOL, e.g. the "
                       "symmetric bending of symmetric wings, or undamped and unreachable) is "
                       "left out of the design's guarantee; it keeps its open-loop eigenvalue "
                       "in the closed loop:"))
        b.append(("ul", removed))
    else:
        b.append(("p", "None: every mode of the design plants is within the loops' reach."))
    return b


def _vector(values, digits: int = 5) -> str:
    """``(a, b, c)`` of numbers, each as :func:`_fmt` gives it."""
    return "(" + ", ".join(_fmt(float(v), digits) for v in np.ravel(values)) + ")"


def _filters(c: dict) -> list:
    """A PD's roll-off and notch, as the controllers' section lists them."""
    return ["roll-off: " + (f"second-order Butterworth at {_fmt(c['roll_off'])} rad/s"
                            if c["roll_off"] else "none"),
            "notch: " + (f"at {_fmt(c['notch'])} rad/s"
                         + (" (the first flexible mode)" if c.get("notch_spec") else "")
                         if c["notch"] else "none")]


def _lqr_gains(c: dict) -> tuple[list, list]:
    """Header and rows of an LQR's gains per design-model state: K (torque per state; three
    axes one column per torque) and L (per innovation: theta and omega, per axis)."""
    K = np.asarray(c["K"], dtype=float)
    K = K.reshape(1, -1) if K.ndim == 1 else K
    L = np.asarray(c["L"], dtype=float)
    if K.shape[0] == 1:
        header = ["design-model state", "K (torque per state)", "L (theta innovation)",
                  "L (omega innovation)"]
    else:
        header = (["design-model state"] + [f"K (torque_{a})" for a in "xyz"]
                  + [f"L ({q}_{a} innovation)" for q in ("theta", "omega") for a in "xyz"])
    rows = [[state, *(_fmt(k, 4) for k in K[:, i]), *(_fmt(v, 4) for v in L[i])]
            for i, state in enumerate(c["states"])]
    return header, rows


def _tip_fidelity(choice: dict) -> list:
    """What the tip-output rule added (spacecraft.design.fidelity.refine_for_tip_outputs)."""
    record = choice.get("tip")
    if not record:
        return []
    added = "; ".join(f"{name} " + ", ".join(f"{m} {k}" for m, k in f.items())
                      for name, f in record["floors"].items() if f)
    text = (f"Then the tip outputs: at {plural(record['n_modes'], 'mode')} per beam, each "
            "reported tip deflection, twist and root load per hub torque on "
            f"[{_fmt(record['band'][0], 3)}, {_fmt(record['band'][1], 3)}] rad/s is compared "
            "with a model holding one more mode of the motion that moves it, and modes of that "
            "motion are added until it changes by less than the tolerance. ")
    text += (f"Modes kept for them: {added} (a motion of a three-axis beam: at least so "
             "many of its modes, n_modes counting those beyond; bending in the plane, or a beam "
             "whose modes are ranked together ('coupled'): so many modes more than n_modes)."
             if added else "No mode was needed for them.")
    if not record["converged"]:
        text = warn(text + " The search stopped at the scene's limits without meeting it.")
    rows = [["; ".join(" ".join(k) for k in t["added"]), _fmt(t["largest"], 3),
             _largest_changes(t["changes"])] for t in record["trials"]]
    return [("p", text), ("table", ["a mode more of", "largest change [-]", "output"], rows)]


def _largest_changes(changes: dict) -> str:
    """The outputs whose change is within 1e-3 of the largest (twin appendages tie to round-off,
    which of them is larger is the CPU's rounding), in name order; "-" for none."""
    if not changes:
        return "-"
    top = max(changes.values())
    return ", ".join(sorted(o for o, c in changes.items() if c >= top * (1.0 - 1e-3)))


def _closed_loop_fidelity(choice: dict) -> list:
    """Why the closed-loop rule kept n_modes (spacecraft.design.fidelity): the changes of the loops
    from each n to the next."""
    record = choice.get("closed_loop")
    if not record:
        return []
    n0, n = choice["open_loop_n_modes"], choice["n_modes"]
    text = (f"Then the closed loops: from {n0} mode{'s' if n0 != 1 else ''}, a mode per beam is "
            "added until every loop of the scene, closed on the truth model, changes by less "
            f"than the tolerance when one more is added: its stability, its poles up to "
            f"{_fmt(record['band'], 4)} rad/s, its least damping ratio and, once those have "
            "settled, its margins (the largest relative changes below). ")
    if record["converged"]:
        text += f"{plural(n, 'mode')} per beam meet{'s' if n == 1 else ''} it."
    else:
        text = warn(text + f"The search stopped at {n} modes per beam (the scene's limits) "
                           "without meeting it.")
    # the margins are compared only once the poles have settled ("-": not computed)
    rows = [[t["n_modes"], _fmt(t["poles"], 3), _fmt(t["least_damping"], 3),
             *(_fmt(t[k], 3) if k in t else "-"
               for k in ("gain_margin", "phase_margin", "modulus_margin")),
             "no" if t["verdict"] else "yes"] for t in record["trials"]]
    return [("p", text),
            ("table", ["n_modes", "poles [-]", "least damping [-]", "gain margin [-]",
                       "phase margin [-]", "modulus margin [-]", "same verdict"], rows)]


def _poles_text(poles: list) -> str:
    shown = [p for p in poles if p["im"] >= 0][:6]
    text = ", ".join(f"{_fmt(p['re'], 3)}" + (f" +/- {_fmt(p['im'], 3)}j" if p["im"] > 0 else "")
                     for p in shown)
    more = len([p for p in poles if p["im"] >= 0]) - len(shown)
    return text + (f" and {more} more" if more > 0 else "")


def _closed_loops(data: dict) -> list:
    rows = data.get("closed_loops", [])
    if not rows:
        return []
    b: list = [("h2", "Closed loops")]
    for kind in dict.fromkeys(r["controller"] for r in rows):
        header, mrows = metric_rows(rows, kind)
        if mrows:
            b.append(("h3", f"{controller_label(kind)}: the slew, design model vs truth model"))
            b.append(("table", header, mrows))
        if any(r.get("disturbance_metrics") for r in rows):
            header, drows = metric_rows(rows, kind, "disturbance_metrics")
            if drows:
                b.append(("h3", f"{controller_label(kind)}: the disturbance alone (theta_ref "
                                "= 0)"))
                b.append(("table", header, drows))
    names = [a["name"] for a in data.get("scene_resolved", {}).get("appendages", [])]
    header, arows = _appendage_rows(rows, names)
    if arows:
        b.append(("h3", "Peaks per appendage during the slew"))
        b.append(("table", header, arows))
    b.append(("h3", "Verdicts: spillover and margins on the truth model"))
    header, vrows = _verdict_rows(rows, data.get("design_warnings", []))
    b.append(("table", header, vrows))
    b.append(("p", _marking_rules()))
    return b


def _marking_rules() -> str:
    """What the colours of the margin and damping cells mean."""
    from ..design.verdicts import (DAMPING_DROP, MIN_DAMPING, MIN_GAIN_MARGIN, MIN_MODULUS_MARGIN,
                           MIN_PHASE_MARGIN)

    return (f"Margins below gain {MIN_GAIN_MARGIN:g} dB, phase {MIN_PHASE_MARGIN:g} deg or "
            f"modulus {MIN_MODULUS_MARGIN:g} are marked orange, a negative one included "
            "(Skogestad and Postlethwaite, Multivariable Feedback Control, sec. 2.4.3); the "
            "margins of an unstable loop are red: they guarantee nothing, the loop diverges "
            f"unperturbed. A closed-loop damping ratio below {MIN_DAMPING:g}, and a loop that "
            f"lowers a flexible mode's damping ratio by more than {100 * DAMPING_DROP:g} % of "
            "its open-loop value, are marked orange. An unstable loop's time metrics are "
            "withheld: it diverges.")


def _basilisk(data: dict) -> list:
    entries = data.get("basilisk")
    if not entries:
        return []
    b: list = [("h2", "Basilisk: the manoeuvre in a nonlinear multibody simulator")]
    first = next(iter(entries.values()))
    b.append(("p", f"Basilisk {first['bsk_version']} runs the design chains ("
                   f"{_label(first['design'])}) with their nonlinear kinematics and each "
                   f"controller as flight software at {_fmt(first['sample_time'])} s (RK4 step "
                   f"{_fmt(first['dt'])} s); flexsat predicts the same sampled-data loop on the "
                   "linear chain and on the truth model (exact at the samples). Peak "
                   "differences over the manoeuvre, relative to the reference's peak (its "
                   "peak itself where the difference is larger):"))
    header = ["controller", "signal", f"Basilisk - flexsat: {first.get('truth', 'truth model')}",
              "Basilisk - flexsat linear chain (nonlinearity)",
              "flexsat: linear chain - truth (the chain's cost)"]
    out = []
    for kind, e in entries.items():
        d = e["differences"]
        for name in d.get("basilisk_vs_chain", {}):
            row = [controller_label(kind), name]
            for key in ("basilisk_vs_truth", "basilisk_vs_chain", "chain_vs_truth"):
                # 3 significant digits: the nonlinearity is often 1e-5 of the peak, which a
                # fixed "0.00 %" would hide
                row.append(peak_difference_text(d.get(key, {}).get(name), short=True))
            out.append(row)
        b.append(("p", f"{controller_label(kind)}: {e['summary']}"))
        b += [("p", f"{controller_label(kind)}: {note}.") for note in e.get("notes", [])]
        b += basilisk_wheel_blocks(kind, e)
    b.append(("table", header, out))
    return b


def report_blocks(data: dict, images: list) -> list:
    """The report as blocks (:mod:`spacecraft.report.pages`)."""
    b: list = [("h1", data.get("title") or "flexsat report"),
               ("p", f"Scene: {data['scene']}. Generated by flexsat {data.get('version', '')} "
                     f"on {data.get('created', '')}."),
               ("h2", "Summary"), ("ul", summary_lines(data))]
    if data.get("design_warnings"):
        b.append(("h2", "Warnings"))
        b.append(("ul", [warn(w["message"]) for w in data["design_warnings"]]))
    b += _question(data)
    b += _models(data)
    b += _controllers(data)
    for table in data.get("equivalence", []):
        plane = f" ({table['plane']} bending plane)" if table.get("plane") else ""
        b.append(("h2", f"Equivalence criterion: {table['appendage']}{plane}"))
        b.append(("p", "The paper's quantities (m, J, L, gains k_r, zeros n_r1, n_r2, natural "
                       "frequencies w1, w2) of each model, with relative errors against "
                       f"the {table.get('reference', 'beam (exact)')}, and the largest "
                       "|ln(W_r/W_r,exact)| over the band (gain and phase error of W)."))
        header, rows = equivalence_markdown(table)
        b.append(("table", header, rows))
        for note in table.get("notes", []):
            b.append(("p", note))
    b += _closed_loops(data)
    b += flown_blocks(data)
    b += _basilisk(data)
    if images:
        b.append(("h2", "Plots"))
        for path, caption in images:
            b.append(("img", path, caption))
    files = data.get("files", {})
    if files.get("fmu") or files.get("ssp"):
        b.append(("h2", "FMUs"))
        b.append(("ul", [f"{f['path']}: {f['description']}" for f in
                         files.get("fmu", []) + files.get("ssp", [])]))
    if files.get("timeseries"):
        b.append(("h2", "Time series"))
        b.append(("p", "Every response as CSV (time and every signal, SI units in the header), "
                       "listed in results.json under files.timeseries:"))
        b.append(("ul", [f"{f['path']}: {controller_label(f['controller'])} tuned on "
                         f"{_label(f['design']) if f['design'] else 'the design chain'}, "
                         f"{f['input']} on the {f['model']} model" for f in files["timeseries"]]))
    if data.get("warnings"):
        b.append(("h2", "Warnings"))
        b.append(("p", "Scene values that look like unit slips (UnitWarning), then warnings "
                       "raised while running the scene (each once):"))
        b.append(("ul", list(data["warnings"])))
    stats = data.get("stats", {})
    b.append(("h2", "Work done"))
    b.append(("p", _work(stats)))
    return b


def _work(stats: dict) -> str:
    parts = [plural(stats.get("chain_fits", 0), "chain fit"),
             plural(stats.get("pd_designs", 0) + stats.get("lqr_designs", 0),
                    "controller design"),
             plural(stats.get("simulations", 0), "simulation"),
             plural(stats.get("plots", 0), "plot"),
             plural(stats.get("fmu_builds", 0), "FMU") + " built",
             plural(stats.get("exact_reference_evaluations", 0), "exact-beam evaluation")]
    seconds = stats.get("seconds", {})
    if seconds:
        parts.append("time per stage: " + ", ".join(f"{k} {v:.2f} s" for k, v in seconds.items()))
    return "; ".join(parts) + " (every counter in results.json, stats)."


# ---------------------------------------------------------------------------------------------
# the writer
# ---------------------------------------------------------------------------------------------
def write_report(result, folder: str | os.PathLike, *, progress=None) -> dict:
    """Write the report of a run into ``folder`` (which must exist), as its scene asks: the
    pages, results.json, the time series (``report.timeseries``), the plots
    (``report.plots``) and the FMUs and SSP files (``export``).

    Parameters
    ----------
    result : spacecraft.design.loop.RunResult
    folder : path
        Destination (use :func:`output_folder` for an all-or-nothing folder).
    progress : callable, optional
        Called with a short message per step.

    Returns
    -------
    dict
        The results (``result.data`` plus ``files``, ``version``, ``created``), as written to
        results.json.

    See Also
    --------
    spacecraft.report.exports.write_exports : the FMUs alone (``flexsat export``).
    """
    from ..design.loop import RunResult, check_options
    from .exports import write_exports

    if not isinstance(result, RunResult):
        raise TypeError(f"result must be a RunResult (spacecraft.run); got {type(result).__name__}")
    if not isinstance(folder, (str, os.PathLike)) or not os.path.isdir(folder):
        raise ValueError(f"folder must be an existing folder (str or os.PathLike; see "
                         f"spacecraft.output_folder); got {folder!r:.200}")
    check_options(progress=progress)
    folder = Path(folder)
    progress = progress or (lambda message: None)
    scene = result.scene
    data = dict(result.data)
    data["version"] = version()
    data["created"] = datetime.datetime.now().isoformat(timespec="seconds")
    # the plots are drawn while the C compiler builds the FMUs
    files, images = write_exports(result, folder, progress=progress,
                                  meanwhile=lambda: _plots(result, folder, scene.report.plots,
                                                           progress))
    files = {"fmu": files["fmu"], "plots": [], **({"ssp": files["ssp"]} if files["ssp"]
                                                  else {})}
    images = [(f"plots/{Path(p).name}", caption) for p, caption in images]
    files["plots"] = [p for p, _ in images]
    if scene.report.timeseries and (result.responses or result.basilisk):
        files["timeseries"] = write_timeseries(result, folder / "timeseries")
    data["files"] = files
    data["stats"] = result.stats.as_dict()
    progress("writing report")
    blocks = report_blocks(data, images)
    (folder / "report.md").write_text(markdown(blocks), encoding="utf-8")
    (folder / "report.html").write_text(render_html(blocks, data.get("title") or "flexsat"),
                                        encoding="utf-8")
    data["files"]["pages"] = ["report.md", "report.html", "results.json"]
    (folder / "results.json").write_text(to_json(data), encoding="utf-8")
    return data


def _plots(result, folder: Path, wanted, progress) -> list:
    """Draw the plots asked for; returns [(path, caption)]."""
    if not wanted:
        return []
    from .plots import draw

    (folder / "plots").mkdir(exist_ok=True)
    progress("plotting")
    return draw(result, folder / "plots", wanted, result.stats,
                exact=result.scene.outputs.exact_reference)


def version() -> str:
    """flexsat's version: pyproject.toml's in a source checkout, else the installed
    distribution's, else ``"unknown"``."""
    root = Path(__file__).resolve().parents[1] / "pyproject.toml"
    if root.is_file():
        import tomllib

        try:
            return tomllib.loads(root.read_text(encoding="utf-8"))["project"]["version"]
        except (OSError, KeyError, tomllib.TOMLDecodeError):
            pass
    try:
        from importlib.metadata import version as installed

        return installed("flexsat")
    except Exception:  # not installed
        return "unknown"
