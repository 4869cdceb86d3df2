"""The sweep's report: statistics, probability of instability, sensitivities, plots, files.

``summary.json`` holds every figure of the report; ``report.md`` and ``report.html`` show them
with the plots (``plots/*.png``), in colour as the run's report (:mod:`spacecraft.report.pages`: what
is unstable or failed in red, warnings in orange):

* a histogram of each metric (failed samples and withheld values left out, infinite values
  counted apart);
* each margin against each parameter (scatter), the worst cases marked; the margins are
  signed (:func:`.evaluate.signed_margin`), so an unstable sample lies below zero, below every
  stable one;
* the stability map: the samples over the two most influential parameters, coloured by the
  signed modulus margin (red below zero), unstable ones crossed, the worst case marked;
* the probability of instability with its 95 % Clopper-Pearson interval (exact binomial:
  the interval of p for which the observed count is not in either 2.5 % tail) over the samples
  evaluated, and, when some samples failed, the bound that counts every failed sample as
  unstable (a failed sample has no verdict: it is neither counted stable nor left to chance);
* the sensitivity ranking: Spearman's rank correlation of each parameter with the signed
  modulus margin, largest magnitude first; rank correlation is blind to monotone re-scaling,
  so a log-uniform stiffness and a uniform inertia are compared fairly.

Every file is written to a temporary name and renamed (:func:`fmu.files.write_text_atomically`):
a reader sees the previous file or the complete new one.

References
----------
.. [1] C. J. Clopper, E. S. Pearson, "The use of confidence or fiducial limits illustrated in the
   case of the binomial", Biometrika 26(4), 1934.
.. [2] A. Saltelli et al., Global Sensitivity Analysis: The Primer, Wiley 2008, ch. 1 (rank
   correlation as a screening measure).
"""

from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np

from fmu.files import write_text_atomically

from ..report.pages import bad, markdown, render_html, warn
from ..report.results import to_json
from .evaluate import METRICS

__all__ = ["clopper_pearson", "summarise", "write_report", "spearman", "CONFIDENCE",
           "format_number", "instability", "instability_text", "metric_label"]

#: Confidence level of the interval on the probability of instability.
CONFIDENCE = 0.95
_HISTOGRAMS = ("exact_modulus_margin", "exact_phase_margin", "exact_gain_margin",
               "truth_modulus_margin", "truth_phase_margin", "truth_gain_margin", "overshoot",
               "settling_time", "peak_tip_deflection", "peak_torque")
#: Histograms a three-axis sweep adds: the multiloop verdict (all loops at once).
_HISTOGRAMS_3D = ("exact_disk_margin", "exact_disk_phase_margin", "exact_min_singular_value",
                  "truth_disk_margin", "truth_disk_phase_margin", "truth_min_singular_value")


def clopper_pearson(k: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float]:
    """Exact binomial confidence interval of a probability from k successes in n trials."""
    from scipy.stats import beta

    if n == 0:
        return 0.0, 1.0
    alpha = 1.0 - confidence
    lo = 0.0 if k == 0 else float(beta.ppf(alpha / 2, k, n - k + 1))
    hi = 1.0 if k == n else float(beta.ppf(1 - alpha / 2, k + 1, n - k))
    return lo, hi


def spearman(x: np.ndarray, y: np.ndarray) -> float:
    """Spearman's rank correlation (average ranks for ties); NaN if either is constant."""
    from scipy.stats import rankdata

    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    if x.size < 3:
        return math.nan
    rx, ry = rankdata(x), rankdata(y)
    if np.ptp(rx) == 0 or np.ptp(ry) == 0:
        return math.nan
    return float(np.corrcoef(rx, ry)[0, 1])


def format_number(value, digits: int = 4) -> str:
    """A number as the report and the command print it ("n/a" for None or NaN)."""
    if value is None:
        return "n/a"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "n/a"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return f"{value:.{digits}g}"
    return str(value)


def _values(column) -> tuple[np.ndarray, int]:
    """A column as floats (NaN where there is no value) and the count of withheld (null)
    values."""
    withheld = sum(1 for v in column if v is None)
    return np.array([math.nan if v is None else v for v in column], dtype=float), withheld


def _stats(values: np.ndarray, withheld: int) -> dict:
    has = values[~np.isnan(values)]
    finite = has[np.isfinite(has)]
    out = {"count": int(has.size), "infinite": int(np.sum(np.isinf(has))),
           "withheld": int(withheld)}
    if finite.size:
        q = np.percentile(finite, [0, 5, 50, 95, 100])
        out.update(min=float(q[0]), p5=float(q[1]), median=float(q[2]), p95=float(q[3]),
                   max=float(q[4]), mean=float(finite.mean()))
    return out


def instability(n_unstable: int, n_evaluated: int, n_failed: int) -> dict:
    """The probability of instability and how failures are counted (module docstring).

    Returns
    -------
    dict
        ``probability`` (unstable / evaluated; None if none was evaluated) with its
        ``interval``; ``bound``: the probability and the upper end of its interval when every
        failed sample is counted as unstable (None without failures).
    """
    lo, hi = clopper_pearson(n_unstable, n_evaluated)
    total = n_evaluated + n_failed
    out = {"unstable": n_unstable, "of": n_evaluated, "failed": n_failed, "total": total,
           "probability": n_unstable / n_evaluated if n_evaluated else None,
           "confidence": CONFIDENCE, "interval": [lo, hi], "method": "Clopper-Pearson",
           "counting": "over the samples evaluated; failed samples (no verdict) left out, "
                       "and counted as unstable in 'bound'", "bound": None}
    if n_failed:
        out["bound"] = {"unstable": n_unstable + n_failed, "of": total,
                        "probability": (n_unstable + n_failed) / total,
                        "upper": clopper_pearson(n_unstable + n_failed, total)[1]}
    return out


def summarise(table, context, spec, *, nominal: dict, worst: list, timings: dict,
              executor: str, info: dict) -> dict:
    """Every figure of the report, JSON-ready.

    Parameters
    ----------
    table : pyarrow.Table
        The sweep's samples.
    context : .evaluate.Context
    spec : .parameters.SweepSpec
    nominal : dict
        The nominal scene's evaluation.
    worst : list of .worst.WorstCase
    timings : dict
        Seconds per stage.
    executor : str
        Where it ran.
    info : dict
        From :func:`.execute.run_samples`.
    """
    cols = table.to_pydict()
    n = table.num_rows
    errors = np.array([bool(e) for e in cols["error"]], dtype=bool)
    ok = ~errors
    stable = np.array([bool(s) if s is not None else False for s in cols["stable"]])
    n_ok = int(ok.sum())
    n_unstable = int(np.sum(ok & ~stable))
    prefix = "exact" if context.exact else "truth"
    margin, _ = _values(cols[f"{prefix}_modulus_margin"])
    ranking = []
    for p in spec.parameters:
        x = np.asarray(cols[p.key], dtype=float)
        rho = spearman(x[ok], margin[ok]) if n_ok else math.nan
        ranking.append({"parameter": p.key, "spearman": rho})
    ranking.sort(key=lambda r: -abs(r["spearman"]) if math.isfinite(r["spearman"]) else 0.0)
    metrics = {}
    for name in context.columns():
        kind = METRICS[name][0]
        if kind == "float" and name != "seconds":
            values, withheld = _values([v for v, good in zip(cols[name], ok) if good])
            metrics[name] = {"unit": METRICS[name][1], "meaning": METRICS[name][2],
                             **_stats(values, withheld)}
    statuses: dict = {}
    for status in cols["status"]:
        statuses[status] = statuses.get(status, 0) + 1
    seconds = np.asarray(cols["seconds"], dtype=float)
    fidelity = None
    if context.exact and n_ok:
        a = np.asarray(cols["exact_modulus_margin"], dtype=float)[ok]
        b = np.asarray(cols["truth_modulus_margin"], dtype=float)[ok]
        both = np.isfinite(a) & np.isfinite(b)
        agree = np.array([cols["exact_stable"][i] == cols["truth_stable"][i]
                          for i in np.flatnonzero(ok)], dtype=bool)
        fidelity = {"max_modulus_margin_difference": float(np.max(np.abs(a - b)[both]))
                    if both.any() else None,
                    "verdicts_disagree": int(np.sum(~agree))}
    failures = {}
    for e in np.asarray(cols["error"], dtype=object)[errors]:
        failures[e] = failures.get(e, 0) + 1
    return {
        "title": f"Sweep of {context.source}",
        "scene": context.source,
        "settings": spec.as_dict(),
        "loop": {"controller": context.controller, "design_model": context.variant,
                 "design": context.design, "n_modes": context.n_modes,
                 "truth_modes": context.truth_modes,
                 "exact_reference": context.exact,
                 "nominal_controller": context.nominal_record,
                 "three_axis": context.three_axis},
        "executor": executor,
        "samples": {"total": n, "evaluated": n_ok, "failed": int(errors.sum()),
                    "status": statuses, "evaluated_now": info["evaluated"],
                    "resumed_from_folder": info["skipped"], "batch": info["batch"],
                    "tasks": info["tasks"], "recomputed_parts": info.get("recomputed", [])},
        "instability": {"verdict": prefix, **instability(n_unstable, n_ok, int(errors.sum()))},
        "sensitivity": {"measure": f"Spearman rank correlation with the signed {prefix} "
                                   "modulus margin", "ranking": ranking if n_ok else []},
        "metrics": metrics,
        "nominal": nominal,
        "worst_case": [w.as_dict() for w in worst],
        "fidelity_check": fidelity,
        "failures": [{"error": e, "count": c} for e, c in sorted(failures.items(),
                                                                 key=lambda t: -t[1])][:20],
        "timings": {**timings, "per_sample_median": float(np.median(seconds)) if n else None,
                    "per_sample_mean": float(np.mean(seconds)) if n else None},
    }


# ---------------------------------------------------------------------------------------------
# plots
# ---------------------------------------------------------------------------------------------
def _figure(rows: int, cols: int, size):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, layout="constrained")
    FigureCanvasAgg(fig)
    return fig, fig.subplots(rows, cols, squeeze=False)


_WORST_STYLE = {"modulus_margin": ("*", "black"), "phase_margin": ("D", "tab:purple")}


def _save(fig, path: Path) -> None:
    from fmu.files import write_atomically

    write_atomically(path, lambda handle: fig.savefig(handle, format="png", dpi=90))


def _worst_marker(ax, w, x, y, size):
    """Mark a worst case (its own marker per margin; a red edge when it is unstable)."""
    marker, colour = _WORST_STYLE.get(w["metric"], ("*", "black"))
    stable = w["row"].get("stable")
    label = f"worst {w['metric'].replace('_', ' ')}" + ("" if stable else " (unstable)")
    ax.scatter([x], [y], s=size, marker=marker, color=colour, zorder=5, label=label,
               edgecolors="tab:red" if not stable else colour, linewidths=1.5)


def _log_axis(axis) -> None:
    from matplotlib.ticker import NullFormatter

    axis.set_minor_formatter(NullFormatter())


_MODELS = {"truth": "truth model", "exact": "exact beam"}
_WORDS = {"pd_kp": "PD proportional gain", "pd_kd": "PD derivative gain",
          "min_singular_value": "smallest singular value of I + L",
          "n_unstable_poles": "unstable poles", "least_damping_ratio": "least damping ratio"}


def metric_label(name: str, three_axis: bool = False) -> str:
    """A metric column in words, with its unit: ``exact_modulus_margin_x`` -> "modulus margin
    about x, exact beam (signed)"; a three-axis summary margin says it is the least over the
    axes ("modulus margin, least of the axes and I + L, exact beam (signed)")."""
    unit = METRICS[name][1] if name in METRICS else ""
    model = ""
    rest = name
    for prefix, words in _MODELS.items():
        if name.startswith(prefix + "_"):
            model, rest = words, name[len(prefix) + 1:]
    axis = ""
    if rest[-2:] in ("_x", "_y", "_z"):
        axis, rest = f" about {rest[-1]}", rest[:-2]
    text = _WORDS.get(rest, rest.replace("_", " ")) + axis
    if three_axis and model and not axis and rest in ("gain_margin", "phase_margin"):
        text += ", least of the axes"
    elif three_axis and model and not axis and rest == "modulus_margin":
        text += ", least of the axes and I + L"
    if model:
        text += f", {model}"
    signed = " (signed)" if rest.endswith(("_margin", "singular_value")) else ""
    return f"{text}{signed} [{unit}]" if unit and unit != "-" else f"{text}{signed}"


def _plots(table, context, spec, summary, folder: Path) -> list[dict]:
    three_axis = context.three_axis

    def _label(name, width=44):
        return textwrap.fill(metric_label(name, three_axis), width)

    cols = table.to_pydict()
    ok = np.array([not e for e in cols["error"]], dtype=bool)
    if not ok.any():
        return []
    folder.mkdir(parents=True, exist_ok=True)
    files = []
    stable = np.array([bool(s) for s, good in zip(cols["stable"], ok) if good])
    names = [n for n in _HISTOGRAMS + (_HISTOGRAMS_3D if three_axis else ()) if n in cols]
    # histograms
    k = len(names)
    ncol = 3
    fig, axes = _figure(math.ceil(k / ncol), ncol, (12, 3.0 * math.ceil(k / ncol)))
    for ax, name in zip(axes.flat, names):
        v, withheld = _values([x for x, good in zip(cols[name], ok) if good])
        v = v[~np.isnan(v)]
        finite = v[np.isfinite(v)]
        if finite.size:
            ax.hist(finite, bins=min(40, max(5, int(math.sqrt(finite.size)))), color="tab:blue")
        else:
            ax.text(0.5, 0.5, "no finite value" + (" (all infinite)" if v.size else ""),
                    ha="center", va="center", transform=ax.transAxes)
        extra = [f"{int(np.sum(np.isinf(v)))} infinite"] if np.isinf(v).any() else []
        extra += [f"{withheld} withheld"] if withheld else []
        ax.set_xlabel(textwrap.fill(metric_label(name, three_axis)
                                    + (f" ({', '.join(extra)})" if extra else ""), 44))
        ax.set_ylabel("samples")
    for ax in list(axes.flat)[k:]:
        ax.set_visible(False)
    _save(fig, folder / "histograms.png")
    files.append({"path": "plots/histograms.png", "description": "histogram of each metric"})
    # margins against parameters
    prefix = "exact" if context.exact else "truth"
    margins = [f"{prefix}_modulus_margin", f"{prefix}_phase_margin"]
    d = len(spec.parameters)
    fig, axes = _figure(len(margins), d, (3.6 * d, 3.0 * len(margins)))
    worst = summary["worst_case"]
    for i, m in enumerate(margins):
        y = np.asarray(cols[m], dtype=float)[ok]
        for j, p in enumerate(spec.parameters):
            ax = axes[i, j]
            x = np.asarray(cols[p.key], dtype=float)[ok]
            ax.axhline(0.0, color="tab:red", linewidth=0.8, zorder=1)
            ax.scatter(x[stable], y[stable], s=4, color="tab:blue", label="stable")
            if (~stable).any():
                ax.scatter(x[~stable], y[~stable], s=10, marker="x", color="tab:red",
                           label="unstable (margin < 0)")
            for w in worst:
                if w["row"].get(m) is not None and math.isfinite(w["row"][m]):
                    _worst_marker(ax, w, w["values"][p.key], w["row"][m], 80)
            if p.distribution == "loguniform":
                ax.set_xscale("log")
                _log_axis(ax.xaxis)
            ax.set_xlabel(p.key)
            if j == 0:   # one label a row: the margin is the row's
                ax.set_ylabel(_label(m, 30))
    axes[0, 0].legend(fontsize=7)
    _save(fig, folder / "margins.png")
    files.append({"path": "plots/margins.png",
                  "description": "signed modulus and phase margins against each parameter "
                                 "(negative: unstable)"})
    # stability map over the two most influential parameters
    ranking = [r["parameter"] for r in summary["sensitivity"]["ranking"]]
    if len(ranking) >= 2:
        from matplotlib.colors import TwoSlopeNorm

        a, b = ranking[0], ranking[1]
        pa = next(p for p in spec.parameters if p.key == a)
        pb = next(p for p in spec.parameters if p.key == b)
        fig, axes = _figure(1, 1, (6.5, 5.0))
        ax = axes[0, 0]
        x = np.asarray(cols[a], dtype=float)[ok]
        y = np.asarray(cols[b], dtype=float)[ok]
        mm = np.asarray(cols[f"{prefix}_modulus_margin"], dtype=float)[ok]
        finite = mm[np.isfinite(mm)]
        lo = min(float(finite.min()), -1e-3) if finite.size else -1.0
        hi = max(float(finite.max()), 1e-3) if finite.size else 1.0
        # red below zero (unstable), green above: the least stable corner reads at a glance
        sc = ax.scatter(x, y, c=mm, s=10, cmap="RdYlGn", norm=TwoSlopeNorm(0.0, lo, hi))
        fig.colorbar(sc, ax=ax, label=_label(f"{prefix}_modulus_margin"))
        if (~stable).any():
            ax.scatter(x[~stable], y[~stable], marker="x", s=16, color="black",
                       label="unstable", linewidths=0.8)
        for w in worst:
            _worst_marker(ax, w, w["values"][a], w["values"][b], 160)
        if pa.distribution == "loguniform":
            ax.set_xscale("log")
            _log_axis(ax.xaxis)
        if pb.distribution == "loguniform":
            ax.set_yscale("log")
            _log_axis(ax.yaxis)
        ax.set_xlabel(a)
        ax.set_ylabel(b)
        ax.set_title("stability map (two most influential parameters)")
        if (~stable).any() or worst:
            ax.legend(fontsize=7)
        _save(fig, folder / "stability_map.png")
        files.append({"path": "plots/stability_map.png",
                      "description": f"stability map over {a} and {b}, coloured by the signed "
                                     "modulus margin (red: unstable)"})
    return files


# ---------------------------------------------------------------------------------------------
# pages
# ---------------------------------------------------------------------------------------------
_f = format_number
_verdicts = {"exact": "exact beam (Nyquist verdict)", "truth": "truth model (eigenvalues)"}


def instability_text(summary: dict) -> str:
    """The probability of instability in words, failures counted as the summary says."""
    inst = summary["instability"]
    ci = f"{100 * inst['confidence']:.0f} %"
    if not inst["of"]:
        text = (f"unknown: every one of the {inst['total']} samples failed (no verdict); see "
                "the failed samples")
    else:
        text = (f"{_f(inst['probability'])} ({inst['unstable']} unstable of {inst['of']} "
                f"evaluated; {ci} interval {_f(inst['interval'][0])} to "
                f"{_f(inst['interval'][1])})")
    bound = inst.get("bound")
    if bound:
        text += (f"; counting the {inst['failed']} failed sample"
                 f"{'s' if inst['failed'] != 1 else ''} as unstable: {_f(bound['probability'])} "
                 f"({bound['unstable']} of {bound['of']}; {ci} upper bound "
                 f"{_f(bound['upper'])})")
    return text


def _truth_words(loop: dict) -> str:
    """The truth model's modes per beam, in words (from the summary's loop)."""
    modes = loop.get("truth_modes") or {}
    if not modes:
        return (f"truth: {loop['n_modes']} modes per beam" if loop.get("n_modes") is not None
                else "truth: no truncated beam")
    words = {"bending": "", "lowest coupled modes": "lowest "}
    return "truth modes per beam: " + "; ".join(
        f"{name} " + ", ".join(f"{words.get(m, m + ' ')}{c}" for m, c in counts.items() if c)
        for name, counts in modes.items())


def _blocks(summary: dict, images: list) -> list:
    s = summary
    inst = s["instability"]
    loop = s["loop"]
    failed = s["samples"]["failed"]
    b: list = [("h1", s["title"]),
               ("p", f"{s['samples']['total']} samples ({s['settings']['method']}, seed "
                     f"{s['settings']['seed']}); controller "
                     f"{loop['controller']} tuned on the {loop['design_model']} design model, "
                     f"design = {loop['design']}; {_truth_words(loop)}"
                     + ("; every sample also closed on the exact beam" if loop["exact_reference"]
                        else "") + f". Ran on {s['executor']}.")]
    if failed:
        text = (f"{failed} of {s['samples']['total']} samples failed: they have no verdict and "
                "no margin, and are counted apart (section Failed samples).")
        b.append(("p", bad(text) if failed == s["samples"]["total"] else warn(text)))
    b.append(("h2", "Parameters"))
    b.append(("table", ["key path", "distribution", "nominal"],
              [[p["key"], _describe(p), _f(p["nominal"], 6)] for p in s["settings"]["parameters"]]))
    b.append(("h2", "Probability of instability"))
    text = f"On the {_verdicts[inst['verdict']]}: " + instability_text(s)
    b.append(("p", bad(text) if inst["unstable"] or not inst["of"] else text))
    b.append(("p", f"Counted {inst['counting']} ({inst['method']} intervals)."))
    statuses = s["samples"].get("status") or {}
    if statuses:
        b.append(("table", ["the slew on the truth model", "samples"],
                  [[bad(k) if k in ("unstable", "diverges", "failed") else
                    warn(k) if k in ("not settled", "slew unfinished") else k, str(v)]
                   for k, v in statuses.items()]))
    if s["sensitivity"]["ranking"]:
        b.append(("h2", "Sensitivity"))
        b.append(("p", s["sensitivity"]["measure"] + ", largest first."))
        b.append(("table", ["parameter", "Spearman rho"],
                  [[r["parameter"], _f(r["spearman"], 3)] for r in s["sensitivity"]["ranking"]]))
    if loop.get("nominal_controller"):
        c = loop["nominal_controller"]
        gains = (f": Kp = {_f(c['Kp'], 6)} N m/rad, Kd = {_f(c['Kd'], 6)} N m s/rad"
                 if "Kp" in c and not isinstance(c["Kp"], list) else
                 ": 3 x 3 gain matrices Kp [N m/rad], Kd [N m s/rad] in summary.json"
                 if "Kp" in c else "")
        b.append(("h2", "Controller"))
        b.append(("p", f"The nominal {c['kind']} controller held for every sample, "
                       f"{len(c['A'])} states{gains}; its matrices are in summary.json "
                       "(loop.nominal_controller) and sweep.json."))
    elif loop["design"] == "per-sample":
        b.append(("h2", "Controller"))
        b.append(("p", "Each sample's controller is in its row of the Parquet table (column "
                       "controller: kind and state-space matrices"
                       + ("; pd_kp, pd_kd: the PD's gains" if loop["controller"] == "pd"
                          and "pd_kp" in s["metrics"] else "")
                       + ("; pd_kp_x.. pd_kd_z: the PD's gains about each hub axis (the "
                          "diagonals of its 3 x 3 gain matrices)"
                          if loop["controller"] == "pd" and "pd_kp_x" in s["metrics"] else "")
                       + ")."))
    if s["worst_case"]:
        b.append(("h2", "Worst case"))
        rows = []
        for w in s["worst_case"]:
            ver = w.get("verification") or {}
            exact = ver.get("exact_reference", {})
            objective = w["objective"]
            rows.append([w["metric"], ", ".join(f"{k} = {_f(v, 6)}" for k, v in w["values"].items()),
                         bad(_f(objective)) if objective < 0 else _f(objective),
                         str(w["evaluations"]) + (f" ({w['failed']} failed)" if w.get("failed")
                                                  else ""),
                         _f(exact.get(w["metric"])) if exact else "n/a",
                         (_f(exact.get("stable")) if exact.get("stable") else
                          bad("no: UNSTABLE")) if "stable" in exact else "n/a"])
        b.append(("table", ["margin", "worst parameters", "signed margin (sweep)",
                            "evaluations", "signed margin on a grid four times as dense",
                            "stable"], rows))
        for w in s["worst_case"]:
            ver = w.get("verification") or {}
            r = ver.get("runner", {})
            if "error" in r:
                text = warn(f"{w['metric']}: flexsat run {ver.get('scene', '')}: the runner "
                            f"failed on it: {r['error']}")
            elif r:
                e = r.get("exact", r.get("truth", {}))
                text = (f"{w['metric']}: flexsat run {ver.get('scene', '')} (the same "
                        f"controller, given in the scene) gives {w['metric']} "
                        f"{_f(e.get(w['metric']))} (signed), "
                        + ("stable" if e.get("stable") else "UNSTABLE") + ".")
                text = text if e.get("stable") else bad(text)
            else:
                text = warn(f"{w['metric']}: {ver.get('note', 'not verified')}.")
            b.append(("p", text))
    b.append(("h2", "Metrics"))
    b.append(("p", "Over the samples evaluated. Margins are signed (negative: unstable); "
                   "withheld: time metrics of slews that do not settle (settling time) or of "
                   "unstable loops (all), as the run's report withholds them."))
    if loop.get("three_axis"):
        b.append(("p", "Three axes: each loop at a time about x, y and z, and all loops at "
                       "once (the disk margin; the smallest singular value of the return "
                       "difference I + L). The gain and phase margins without an axis are the "
                       "least of the three loops at a time; the modulus margin without an axis "
                       "the least of those and of the smallest singular value of I + L (the "
                       "one the sensitivity ranking and the worst case use)."))
    b.append(("table", ["metric", "meaning", "unit", "min", "5 %", "median", "95 %", "max",
                        "infinite", "withheld"],
              [[k, metric_label(k, bool(loop.get("three_axis"))).split(" [")[0], v["unit"],
                bad(_f(v.get("min"))) if k.endswith("_margin") and
                v.get("min") is not None and v["min"] < 0 else _f(v.get("min")),
                _f(v.get("p5")), _f(v.get("median")), _f(v.get("p95")), _f(v.get("max")),
                str(v["infinite"]), str(v["withheld"])]
               for k, v in s["metrics"].items()]))
    if s.get("fidelity_check"):
        fc = s["fidelity_check"]
        text = (f"Truth model against the exact beam: modulus margins differ by at most "
                f"{_f(fc['max_modulus_margin_difference'])}; verdicts disagree in "
                f"{fc['verdicts_disagree']} samples.")
        b.append(("p", warn(text) if fc["verdicts_disagree"] else text))
    if s["failures"]:
        b.append(("h2", "Failed samples"))
        b.append(("table", ["error", "samples"], [[bad(f["error"]), str(f["count"])]
                                                  for f in s["failures"]]))
    if s["samples"].get("recomputed_parts"):
        b.append(("p", warn("Damaged Parquet parts recomputed on resume: "
                            + ", ".join(s["samples"]["recomputed_parts"]))))
    t = s["timings"]
    b.append(("h2", "Timings"))
    b.append(("table", ["stage", "seconds"], [[k, _f(v)] for k, v in t.items()]))
    for path, description in images:
        b.append(("img", path, description))
    return b


def _describe(p: dict) -> str:
    d = p["distribution"]
    if d in ("uniform", "loguniform"):
        return f"{d} [{_f(p['low'], 6)}, {_f(p['high'], 6)}]"
    if d == "normal":
        return f"normal (mean {_f(p['mean'], 6)}, std {_f(p['std'], 6)})"
    return "discrete {" + ", ".join(_f(v, 6) for v in p["values"]) + "}"


def write_report(folder, table, context, spec, summary: dict, *, plots: bool = True) -> dict:
    """Write ``summary.json``, ``report.md``, ``report.html`` and the plots into ``folder``,
    each atomically.

    Returns
    -------
    dict
        The summary with ``files`` added.
    """
    folder = Path(folder)
    files = _plots(table, context, spec, summary, folder / "plots") if plots else []
    summary = {**summary, "files": {"plots": files}}
    images = [(f["path"], f["description"]) for f in files]
    blocks = _blocks(summary, images)
    write_text_atomically(folder / "report.md", markdown(blocks))
    write_text_atomically(folder / "report.html", render_html(blocks, summary["title"]))
    write_text_atomically(folder / "summary.json", to_json(summary) + "\n")
    return summary
