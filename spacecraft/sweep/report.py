"""The sweep's report: statistics, probability of instability, sensitivities, plots, files.

``summary.json`` holds every figure of the report; ``report.md`` and ``report.html`` show them
with the plots (``plots/*.png``):

* a histogram of each metric (failed samples left out, infinite values counted apart);
* each margin against each parameter (scatter), the worst cases marked;
* the stability map: the samples over the two most influential parameters, coloured by the
  modulus margin, unstable ones crossed, the worst case marked;
* the probability of instability with its 95 % Clopper-Pearson interval (exact binomial:
  the interval of p for which the observed count is not in either 2.5 % tail), over the samples
  that did not fail;
* the sensitivity ranking: Spearman's rank correlation of each parameter with the modulus margin
  (with the signed margin, negative when unstable: :func:`.worst.signed_margin`), largest
  magnitude first; rank correlation is blind to monotone re-scaling, so a log-uniform stiffness
  and a uniform inertia are compared fairly.

References
----------
.. [1] C. J. Clopper, E. S. Pearson, "The use of confidence or fiducial limits illustrated in the
   case of the binomial", Biometrika 26(4), 1934.
.. [2] A. Saltelli et al., Global Sensitivity Analysis: The Primer, Wiley 2008, ch. 1 (rank
   correlation as a screening measure).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..report import _fmt, markdown, render_html, to_json
from .evaluate import METRICS
from .worst import signed_margin

__all__ = ["clopper_pearson", "summarise", "write_report", "spearman", "CONFIDENCE"]

#: Confidence level of the interval on the probability of instability.
CONFIDENCE = 0.95
_HISTOGRAMS = ("exact_modulus_margin", "exact_phase_margin", "exact_gain_margin",
               "truth_modulus_margin", "truth_phase_margin", "truth_gain_margin", "overshoot",
               "settling_time", "peak_tip_deflection", "peak_torque")


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


def _stats(values: np.ndarray) -> dict:
    finite = values[np.isfinite(values)]
    out = {"count": int(values.size), "infinite": int(np.sum(np.isinf(values)))}
    if finite.size:
        q = np.percentile(finite, [0, 5, 50, 95, 100])
        out.update(min=float(q[0]), p5=float(q[1]), median=float(q[2]), p95=float(q[3]),
                   max=float(q[4]), mean=float(finite.mean()))
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
    lo, hi = clopper_pearson(n_unstable, n_ok)
    prefix = "exact" if context.exact else "truth"
    margin = np.array([signed_margin({k: cols[k][i] for k in cols}, "modulus_margin",
                                     context.exact) for i in range(n)])
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
            metrics[name] = {"unit": METRICS[name][1], "meaning": METRICS[name][2],
                             **_stats(np.asarray(cols[name], dtype=float)[ok])}
    seconds = np.asarray(cols["seconds"], dtype=float)
    fidelity = None
    if context.exact:
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
                 "exact_reference": context.exact},
        "executor": executor,
        "samples": {"total": n, "failed": int(errors.sum()), "evaluated_now": info["evaluated"],
                    "resumed_from_folder": info["skipped"], "batch": info["batch"],
                    "tasks": info["tasks"]},
        "instability": {"verdict": prefix, "unstable": n_unstable, "of": n_ok,
                        "probability": n_unstable / n_ok if n_ok else None,
                        "confidence": CONFIDENCE, "interval": [lo, hi],
                        "method": "Clopper-Pearson"},
        "sensitivity": {"measure": f"Spearman rank correlation with the signed {prefix} "
                                   "modulus margin", "ranking": ranking},
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


def _label(name: str) -> str:
    unit = METRICS[name][1] if name in METRICS else ""
    return f"{name} [{unit}]" if unit and unit != "-" else name


def _plots(table, context, spec, summary, folder: Path) -> list[dict]:
    cols = table.to_pydict()
    ok = np.array([not e for e in cols["error"]], dtype=bool)
    if not ok.any():
        return []
    folder.mkdir(parents=True, exist_ok=True)
    files = []
    stable = np.array([bool(s) for s, good in zip(cols["stable"], ok) if good])
    names = [n for n in _HISTOGRAMS if n in cols]
    # histograms
    k = len(names)
    ncol = 3
    fig, axes = _figure(math.ceil(k / ncol), ncol, (12, 3.0 * math.ceil(k / ncol)))
    for ax, name in zip(axes.flat, names):
        v = np.asarray(cols[name], dtype=float)[ok]
        finite = v[np.isfinite(v)]
        if finite.size:
            ax.hist(finite, bins=min(40, max(5, int(math.sqrt(finite.size)))), color="tab:blue")
        extra = f" ({int(np.sum(np.isinf(v)))} infinite)" if np.isinf(v).any() else ""
        ax.set_xlabel(_label(name) + extra)
        ax.set_ylabel("samples")
    for ax in list(axes.flat)[k:]:
        ax.set_visible(False)
    fig.savefig(folder / "histograms.png", dpi=90)
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
            ax.scatter(x[stable], y[stable], s=4, color="tab:blue", label="stable")
            if (~stable).any():
                ax.scatter(x[~stable], y[~stable], s=10, marker="x", color="tab:red",
                           label="unstable")
            for w in worst:
                if w["row"].get(m) is not None and math.isfinite(w["row"][m]):
                    _worst_marker(ax, w, w["values"][p.key], w["row"][m], 80)
            if p.distribution == "loguniform":
                ax.set_xscale("log")
                _log_axis(ax.xaxis)
            ax.set_xlabel(p.key)
            ax.set_ylabel(_label(m))
    axes[0, 0].legend(fontsize=7)
    fig.savefig(folder / "margins.png", dpi=90)
    files.append({"path": "plots/margins.png",
                  "description": "modulus and phase margins against each parameter"})
    # stability map over the two most influential parameters
    ranking = [r["parameter"] for r in summary["sensitivity"]["ranking"]]
    if len(ranking) >= 2:
        a, b = ranking[0], ranking[1]
        pa = next(p for p in spec.parameters if p.key == a)
        pb = next(p for p in spec.parameters if p.key == b)
        fig, axes = _figure(1, 1, (6.5, 5.0))
        ax = axes[0, 0]
        x = np.asarray(cols[a], dtype=float)[ok]
        y = np.asarray(cols[b], dtype=float)[ok]
        mm = np.asarray(cols[f"{prefix}_modulus_margin"], dtype=float)[ok]
        sc = ax.scatter(x[stable], y[stable], c=mm[stable], s=8, cmap="viridis")
        fig.colorbar(sc, ax=ax, label=_label(f"{prefix}_modulus_margin"))
        if (~stable).any():
            ax.scatter(x[~stable], y[~stable], marker="x", s=16, color="tab:red",
                       label="unstable")
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
        fig.savefig(folder / "stability_map.png", dpi=90)
        files.append({"path": "plots/stability_map.png",
                      "description": f"stability map over {a} and {b}"})
    return files


# ---------------------------------------------------------------------------------------------
# pages
# ---------------------------------------------------------------------------------------------
def _f(value, digits: int = 4) -> str:
    return _fmt(value, digits)


def _blocks(summary: dict, images: list) -> list:
    s = summary
    inst = s["instability"]
    loop = s["loop"]
    b: list = [("h1", s["title"]),
               ("p", f"{s['samples']['total']} samples ({s['settings']['method']}, seed "
                     f"{s['settings']['seed']}), {s['samples']['failed']} failed; controller "
                     f"{loop['controller']} tuned on the {loop['design_model']} design model, "
                     f"design = {loop['design']}; truth: {loop['n_modes']} modes per beam"
                     + ("; every sample also closed on the exact beam" if loop["exact_reference"]
                        else "") + f". Ran on {s['executor']}.")]
    b.append(("h2", "Parameters"))
    b.append(("table", ["key path", "distribution", "nominal"],
              [[p["key"], _describe(p), _f(p["nominal"], 6)] for p in s["settings"]["parameters"]]))
    b.append(("h2", "Probability of instability"))
    prob = inst["probability"]
    b.append(("p", f"{inst['unstable']} unstable of {inst['of']} ({inst['verdict']} verdict): "
                   f"p = {_f(prob)}, {100 * inst['confidence']:.0f} % interval "
                   f"[{_f(inst['interval'][0])}, {_f(inst['interval'][1])}] "
                   f"({inst['method']})."))
    b.append(("h2", "Sensitivity"))
    b.append(("p", s["sensitivity"]["measure"] + ", largest first."))
    b.append(("table", ["parameter", "Spearman rho"],
              [[r["parameter"], _f(r["spearman"], 3)] for r in s["sensitivity"]["ranking"]]))
    if s["worst_case"]:
        b.append(("h2", "Worst case"))
        rows = []
        for w in s["worst_case"]:
            ver = w.get("verification") or {}
            exact = ver.get("exact_reference", {})
            rows.append([w["metric"], ", ".join(f"{k} = {_f(v, 6)}" for k, v in w["values"].items()),
                         _f(w["objective"]), str(w["evaluations"]),
                         _f(exact.get(w["metric"])) if exact else "n/a",
                         _f(exact.get("stable")) if exact else "n/a"])
        b.append(("table", ["margin", "worst parameters", "signed margin (sweep)",
                            "evaluations", "verified on the exact beam", "stable"], rows))
        for w in s["worst_case"]:
            ver = w.get("verification") or {}
            r = ver.get("runner", {})
            if "error" in r:
                text = f"the runner failed on it: {r['error']}"
            else:
                e = r.get("exact", r.get("truth", {}))
                text = (f"the runner gives {w['metric']} {_f(e.get(w['metric']))}, stable "
                        f"{_f(e.get('stable'))}")
            note = f" ({ver['note']})" if ver.get("note") else ""
            b.append(("p", f"{w['metric']}: flexsat run {ver.get('scene', '')}: {text}{note}."))
    b.append(("h2", "Metrics"))
    b.append(("table", ["metric", "unit", "min", "5 %", "median", "95 %", "max", "infinite"],
              [[k, v["unit"], _f(v.get("min")), _f(v.get("p5")), _f(v.get("median")),
                _f(v.get("p95")), _f(v.get("max")), str(v["infinite"])]
               for k, v in s["metrics"].items()]))
    if s.get("fidelity_check"):
        fc = s["fidelity_check"]
        b.append(("p", f"Truth model against the exact beam: modulus margins differ by at most "
                       f"{_f(fc['max_modulus_margin_difference'])}; verdicts disagree in "
                       f"{fc['verdicts_disagree']} samples."))
    if s["failures"]:
        b.append(("h2", "Failed samples"))
        b.append(("table", ["error", "samples"], [[f["error"], str(f["count"])]
                                                  for f in s["failures"]]))
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
    """Write ``summary.json``, ``report.md``, ``report.html`` and the plots into ``folder``.

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
    (folder / "report.md").write_text(markdown(blocks))
    (folder / "report.html").write_text(render_html(blocks, summary["title"]))
    (folder / "summary.json").write_text(to_json(summary) + "\n")
    return summary
