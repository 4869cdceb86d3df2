"""The report of a scene run: Markdown and HTML pages, PNG plots, results.json, FMUs.

:func:`write_report` writes a :class:`~spacecraft.runner.RunResult` into a folder. The same
list of blocks (headings, paragraphs, tables, images) renders to ``report.md`` and
``report.html``, so both say the same; every number shown is also in ``results.json``
(machine-readable, non-finite numbers written as the strings ``"inf"``/``"-inf"`` and NaN as
null). :func:`output_folder` makes the folder appear only when complete: files go to a hidden
temporary sibling that is renamed at the end, and removed if anything fails.

Files

- ``report.md``, ``report.html``: equivalence table (the paper's layout plus errors against the
  exact beam), closed-loop metrics (design vs truth, PD and LQR), verdicts (spillover, margins);
- ``plots/slew_<controller>.png`` (theta, torque, tip deflection; design vs truth),
  ``plots/bode_W.png`` (|W_r| of the exact beam, the truncated beam and the chains),
  ``plots/pole_zero.png`` (poles and zeros of theta/torque of the truth and design plants);
- ``results.json``;
- ``fmu/plant.fmu``, ``fmu/<controller>.fmu``, ``fmu/closed_loop_<controller>.fmu`` with their
  FMI cross-check files ``<name>_in.csv``, ``<name>_ref.csv``, ``<name>_ref.opt``.
"""

from __future__ import annotations

import concurrent.futures
import datetime
import html
import json
import math
import os
import re
from pathlib import Path

import numpy as np

from .output import MARKER, default_output_folder, output_folder

__all__ = ["write_report", "output_folder", "default_output_folder", "to_json", "markdown",
           "render_html", "equivalence_markdown", "metric_rows", "summary_lines", "MARKER",
           "markdown_text"]


# ---------------------------------------------------------------------------------------------
# JSON
# ---------------------------------------------------------------------------------------------
def _clean(value):
    """JSON-ready copy: numpy scalars and arrays to Python, inf to "inf", NaN to None."""
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_clean(v) for v in value.tolist()]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        if math.isnan(value):
            return None
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return value
    if isinstance(value, complex):
        return {"re": _clean(value.real), "im": _clean(value.imag)}
    return value


def to_json(data: dict) -> str:
    """Strict JSON text of a results dict (no NaN or Infinity literals)."""
    return json.dumps(_clean(data), indent=2, allow_nan=False)


# ---------------------------------------------------------------------------------------------
# blocks -> Markdown / HTML
# ---------------------------------------------------------------------------------------------
def _fmt(value, digits: int = 5) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, str):
        return value
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    value = float(value)
    if math.isnan(value):
        return "n/a"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:.{digits}g}"


def _percent(value) -> str:
    if value is None or not math.isfinite(value):
        return "n/a"
    return f"{100.0 * value:+.2f} %"


# Inline Markdown markup (CommonMark + GFM): code, emphasis, links and images, tables,
# strikethrough; each is a literal character when backslash-escaped (CommonMark 0.31, sec. 2.4).
_MD_INLINE = re.compile(r"([\\`*\[\]|~])")
# "_" opens or closes emphasis only at a word boundary (left/right-flanking delimiter runs)
_MD_UNDERSCORE = re.compile(r"(?<![A-Za-z0-9])_|_(?![A-Za-z0-9])")
# what turns the start of a line into a block (heading, quote, list, thematic break)
_MD_BLOCK_START = re.compile(r"^([#>+=-])|^(\d+)([.)])")


def markdown_text(text, *, line_start: bool = False) -> str:
    """Plain text as Markdown that renders as exactly that text.

    ``&``, ``<`` and ``>`` become HTML entities (no raw HTML: a title cannot inject a
    ``<script>``); inline markup characters are backslash-escaped; line breaks become spaces.
    ``line_start``: the text begins a line (a paragraph or list item), so block markers
    (``#``, ``>``, ``-``, ``1.``) at its start are escaped too.
    """
    text = str(text).replace("\r", " ").replace("\n", " ")
    text = html.escape(text, quote=False)
    text = _MD_INLINE.sub(r"\\\1", text)
    text = _MD_UNDERSCORE.sub(r"\\_", text)
    if line_start:
        text = _MD_BLOCK_START.sub(lambda m: ("\\" + m.group(1)) if m.group(1)
                                   else f"{m.group(2)}\\{m.group(3)}", text, count=1)
    return text


def markdown(blocks: list) -> str:
    """Render blocks as Markdown; every text is escaped (:func:`markdown_text`)."""
    md = markdown_text
    out = []
    for block in blocks:
        kind = block[0]
        if kind in ("h1", "h2", "h3"):
            text = md(block[1])
            # a heading's closing #s would be dropped: escape a final one
            text = text[:-1] + "\\#" if text.endswith("#") else text
            out.append("#" * int(kind[1]) + " " + text)
        elif kind == "p":
            out.append(md(block[1], line_start=True))
        elif kind == "ul":
            out.append("\n".join(f"- {md(item, line_start=True)}" for item in block[1]))
        elif kind == "table":
            header, rows = block[1], block[2]
            lines = ["| " + " | ".join(md(h) for h in header) + " |", "|" + "---|" * len(header)]
            lines += ["| " + " | ".join(md(c) for c in row) + " |" for row in rows]
            out.append("\n".join(lines))
        elif kind == "img":
            out.append(f"![{md(block[2])}](<{block[1]}>)")
        elif kind == "pre":
            fence = "`" * max(3, 1 + max((len(r) for r in re.findall("`+", block[1])),
                                         default=0))
            out.append(f"{fence}\n{block[1]}\n{fence}")
    return "\n\n".join(out) + "\n"


def render_html(blocks: list, title: str) -> str:
    """Render the same blocks as a self-contained HTML page."""
    esc = html.escape
    body = []
    for block in blocks:
        kind = block[0]
        if kind in ("h1", "h2", "h3"):
            body.append(f"<{kind}>{esc(block[1])}</{kind}>")
        elif kind == "p":
            body.append(f"<p>{esc(block[1])}</p>")
        elif kind == "ul":
            body.append("<ul>" + "".join(f"<li>{esc(i)}</li>" for i in block[1]) + "</ul>")
        elif kind == "table":
            head = "".join(f"<th>{esc(h)}</th>" for h in block[1])
            rows = "".join("<tr>" + "".join(f"<td>{esc(str(c))}</td>" for c in row) + "</tr>"
                           for row in block[2])
            body.append(f"<table><thead><tr>{head}</tr></thead><tbody>{rows}</tbody></table>")
        elif kind == "img":
            body.append(f'<figure><img src="{esc(block[1])}" alt="{esc(block[2])}">'
                        f"<figcaption>{esc(block[2])}</figcaption></figure>")
        elif kind == "pre":
            body.append(f"<pre>{esc(block[1])}</pre>")
    style = ("body{font-family:sans-serif;max-width:70em;margin:2em auto;padding:0 1em}"
             "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;"
             "padding:.2em .5em;text-align:right}th{background:#eee}td:first-child,"
             "th:first-child{text-align:left}img{max-width:100%}")
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{esc(title)}</title><style>{style}</style></head><body>\n"
            + "\n".join(body) + "\n</body></html>\n")


# ---------------------------------------------------------------------------------------------
# content
# ---------------------------------------------------------------------------------------------
def equivalence_markdown(table: dict) -> tuple[list, list]:
    """Header and rows of the paper's table with errors against the exact beam."""
    header = ["quantity", "beam (exact)"]
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
    "overshoot": "overshoot [%]", "settling_time": "settling time [s]",
    "peak_torque": "peak torque [N m]", "peak_tip_deflection": "peak tip deflection [m]",
    "peak_attitude_error": "peak attitude error [rad]",
    "final_attitude_error": "final attitude error [rad]",
}
MARGIN_LABELS = {"gain_margin": "gain margin [dB]", "phase_margin": "phase margin [deg]",
                 "modulus_margin": "modulus margin [-]"}


def metric_rows(rows: list, controller: str) -> tuple[list, list]:
    """Header and rows of the closed-loop metrics of one controller, design vs truth."""
    mine = [r for r in rows if r["controller"] == controller and "metrics" in r]
    header = ["metric"]
    for r in mine:
        header += [f"{_label(r['design'])}: design", f"{_label(r['design'])}: truth",
                   "difference"]
    out = []
    names = list(METRIC_LABELS)
    for name in names:
        if not any(name in r["metrics"]["design"] for r in mine):
            continue
        row = [METRIC_LABELS[name]]
        for r in mine:
            d, t = r["metrics"]["design"].get(name), r["metrics"]["truth"].get(name)
            diff = None if d is None or t is None else t - d
            gone = {w: _diverged(r, w) is not None for w in ("design", "truth")}
            row += ["diverged" if gone["design"] else _fmt(d),
                    "diverged" if gone["truth"] else _fmt(t),
                    "-" if any(gone.values()) else _fmt(diff, 3)]
        out.append(row)
    for name, label in MARGIN_LABELS.items():
        row = [label]
        for r in mine:
            d, t = r["design_margins"].get(name), r["verdict"].get(name)
            diff = None if d is None or t is None or not (math.isfinite(d) and math.isfinite(t)) \
                else t - d
            row += [_fmt(d, 4), _fmt(t, 4), _fmt(diff, 3)]
        out.append(row)
    return header, out


def _diverged(row: dict, which: str) -> float | None:
    """Time [s] at which the ``which`` ("design"/"truth") response of a closed-loop row
    stopped because it diverged, or None."""
    return (row.get("diverged") or {}).get(which)


def _divergence(row: dict) -> str:
    """``"diverges, simulation stopped at t = ... s"`` for a row whose truth (or design)
    response diverged, else ''."""
    for which in ("truth", "design"):
        at = _diverged(row, which)
        if at is not None:
            where = "" if which == "truth" else " (on the design model)"
            return f"diverges{where}, simulation stopped at t = {_fmt(at, 6)} s"
    return ""


def _label(variant: str) -> str:
    """Display name of a design variant (a fit criterion)."""
    from .runner import FIT_LABELS

    return FIT_LABELS.get(variant, variant)


def _verdict_rows(rows: list) -> tuple[list, list]:
    exact = any("exact_verdict" in r for r in rows)
    header = ["design model", "controller", "on truth model", "least damping [-]",
              "at [rad/s]", "gain margin [dB]", "phase margin [deg]", "modulus margin [-]"]
    if exact:
        header += ["on exact beam (Nyquist)"]
    out = []
    for r in rows:
        v = r["verdict"]
        state = "stable" if v["stable"] else f"UNSTABLE ({v['n_unstable_poles']} poles)"
        if _divergence(r):
            state = f"UNSTABLE: {_divergence(r)}"
        row = [_label(r["design"]), r["controller"].upper(), state, _fmt(v["least_damping_ratio"], 3),
               _fmt(v["least_damped_frequency"], 4), _fmt(v["gain_margin"], 4),
               _fmt(v["phase_margin"], 4), _fmt(v["modulus_margin"], 3)]
        if exact:
            e = r.get("exact_verdict", {})
            row.append("n/a" if "stable" not in e else
                       ("stable" if e["stable"] else f"UNSTABLE ({e['n_unstable_poles']} poles)"))
        out.append(row)
    return header, out


def summary_lines(data: dict) -> list[str]:
    """Short summary of a run (the CLI prints it)."""
    lines = []
    fid = data.get("fidelity", {})
    if fid.get("n_modes"):
        how = "chosen for tolerance " + _fmt(fid["choice"]["tolerance"]) if fid.get("choice") \
            else "given"
        modes = "mode" if fid["n_modes"] == 1 else "modes"
        lines.append(f"truth model: {fid['n_modes']} bending {modes} per beam ({fid['method']}, "
                     f"{how}); "
                     f"plant {data['truth']['n_states']} states, "
                     f"{data['truth']['modes_dropped']} modes pruned")
    else:
        lines.append(f"truth model: chains, plant {data['truth']['n_states']} states")
    for r in data.get("closed_loops", []):
        v = r["verdict"]
        state = "stable" if v["stable"] else "UNSTABLE"
        text = (f"{r['controller'].upper()} tuned on {_label(r['design'])}: {state} on truth, phase "
                f"margin {_fmt(v['phase_margin'], 3)} deg")
        if _divergence(r):
            lines.append(f"{r['controller'].upper()} tuned on {_label(r['design'])}: UNSTABLE: "
                         f"{_divergence(r)}; phase margin {_fmt(v['phase_margin'], 3)} deg")
            continue
        if "metrics" in r:
            m = r["metrics"]["truth"]
            if "overshoot" in m:
                text += f", overshoot {_fmt(m['overshoot'], 3)} %"
            if "peak_tip_deflection" in m:
                text += f", peak tip deflection {_fmt(m['peak_tip_deflection'], 3)} m"
        lines.append(text)
    return lines


def _blocks(data: dict, images: list) -> list:
    b: list = [("h1", data.get("title") or "flexsat report"),
               ("p", f"Scene: {data['scene']}. Generated by flexsat {data.get('version', '')} "
                     f"on {data.get('created', '')}."),
               ("h2", "Summary"), ("ul", summary_lines(data))]
    b.append(("h2", "Models"))
    fid = data["fidelity"]
    truth = data["truth"]
    if fid.get("n_modes"):
        b.append(("p", f"Truth model: every distributed beam truncated to {fid['n_modes']} "
                       f"bending modes ({fid['method']}); the coupled plant keeps "
                       f"{truth['modes_kept']} of {truth['modes_total']} modes "
                       f"({truth['modes_dropped']} pruned: not excited by the inputs or not seen "
                       f"by the outputs) and has {truth['n_states']} states."))
        choice = fid.get("choice")
        if choice:
            b.append(("p", f"n_modes was chosen for a relative tolerance of "
                           f"{_fmt(choice['tolerance'])}: coupled frequencies up to "
                           f"{_fmt(choice['reference_frequencies'][-1], 4)} rad/s and the gain "
                           f"|theta/torque| on [{_fmt(choice['band'][0], 3)}, "
                           f"{_fmt(choice['band'][1], 3)}] rad/s against the exact beam."))
            b.append(("table", ["n_modes", "frequency error [-]", "gain error [-]"],
                      [[t["n_modes"], _fmt(t["frequency_error"], 3), _fmt(t["gain_error"], 3)]
                       for t in choice["trials"]]))
    else:
        b.append(("p", f"Truth model: the chains as given; the plant has {truth['n_states']} "
                       f"states ({truth['modes_dropped']} of {truth['modes_total']} modes "
                       "pruned)."))
    header = ["mode"]
    columns = []
    if "exact" in data:
        header.append("exact beam")
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
    for table in data.get("equivalence", []):
        b.append(("h2", f"Equivalence criterion: {table['appendage']}"))
        b.append(("p", "The paper's quantities (m, J, L, gains k_r, zeros n_r1, n_r2, natural "
                       "frequencies w1, w2) of the paper's two-mode beam and of each fitted "
                       "chain, with relative errors against the exact distributed beam, and the "
                       "largest |ln(W_r/W_r,exact)| over the band (gain and phase error of W)."))
        header, rows = equivalence_markdown(table)
        b.append(("table", header, rows))
    rows = data.get("closed_loops", [])
    if rows:
        b.append(("h2", "Closed loops"))
        for kind in dict.fromkeys(r["controller"] for r in rows):
            header, mrows = metric_rows(rows, kind)
            b.append(("h3", f"{kind.upper()}: design model vs truth model"))
            b.append(("table", header, mrows))
        b.append(("h3", "Verdicts: spillover and margins on the truth model"))
        header, vrows = _verdict_rows(rows)
        b.append(("table", header, vrows))
    if images:
        b.append(("h2", "Plots"))
        for path, caption in images:
            b.append(("img", path, caption))
    files = data.get("files", {}).get("fmu", [])
    if files:
        b.append(("h2", "FMUs"))
        b.append(("ul", [f"{f['path']}: {f['description']}" for f in files]))
    if data.get("warnings"):
        b.append(("h2", "Warnings"))
        b.append(("p", "Numerical warnings raised while running the scene (each once):"))
        b.append(("ul", list(data["warnings"])))
    stats = data.get("stats", {})
    b.append(("h2", "Work done"))
    b.append(("p", ", ".join(f"{k} {v}" for k, v in stats.items() if k != "seconds")))
    return b


# ---------------------------------------------------------------------------------------------
# plots
# ---------------------------------------------------------------------------------------------
def _figure(rows: int, cols: int, size):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    # a fixed layout: constrained layout redraws every figure several times (half the cost)
    fig = Figure(figsize=size)
    FigureCanvasAgg(fig)
    fig.subplots_adjust(left=0.09, right=0.98, bottom=0.08, top=0.92, hspace=0.35, wspace=0.25)
    return fig, fig.subplots(rows, cols, squeeze=False)


def _trace(response, name):
    labels = list(response.output_labels)
    if name not in labels:
        return None
    return np.asarray(response.y).reshape(len(labels), -1)[labels.index(name)]


#: Points drawn per curve: a longer response is drawn as its min/max envelope (peaks kept).
_PLOT_POINTS = 4000


def _envelope(t: np.ndarray, y: np.ndarray, points: int = _PLOT_POINTS):
    """``(t, y)`` to draw: all samples when few, else the min and max of each of ``points / 2``
    buckets in time order, so that a plot of 10^7 samples costs what one of 10^4 does."""
    per = t.size // (points // 2)
    if per < 2:
        return t, y
    m = (t.size // per) * per
    tb, yb = t[:m].reshape(-1, per), y[:m].reshape(-1, per)
    lo, hi = np.argmin(yb, axis=1), np.argmax(yb, axis=1)
    first, second = np.minimum(lo, hi), np.maximum(lo, hi)
    rows = np.arange(tb.shape[0])
    tt = np.stack([tb[rows, first], tb[rows, second]], axis=1).reshape(-1)
    yy = np.stack([yb[rows, first], yb[rows, second]], axis=1).reshape(-1)
    return np.concatenate([tt, t[m:]]), np.concatenate([yy, y[m:]])


def _plot_slews(result, folder: Path) -> list:
    from .runner import diverged_at

    out = []
    kinds = list(dict.fromkeys(k[1] for k in result.responses))
    for kind in kinds:
        keys = [k for k in result.responses if k[1] == kind]
        first = result.responses[keys[0]]
        tips = [n for n in first.output_labels if n.endswith("tip_deflection")]
        signals = [("theta", "deg"), ("torque", "N m")] + [(n, "m") for n in tips[:2]]
        fig, axes = _figure(len(signals), 1, (9, 2.4 * len(signals)))
        for ax, (name, unit) in zip(axes[:, 0], signals):
            curves = []
            for variant, _, which in keys:
                resp = result.responses[(variant, kind, which)]
                y = _trace(resp, name)
                if y is None:
                    continue
                with np.errstate(over="ignore", invalid="ignore"):
                    y = np.degrees(y) if name == "theta" else np.asarray(y, dtype=float)
                label = f"{_label(variant)}: {which}"
                at = diverged_at(resp)
                if at is not None:
                    label += f" (diverges, stopped at t = {_fmt(at, 4)} s)"
                curves.append((np.asarray(resp.t, dtype=float).reshape(-1), y, which, label,
                               at is not None))
            # a diverging response would squash the others to a line: the axis shows the
            # range of the bounded ones, and the diverging one is clipped just outside it
            bounded = [y for _, y, _, _, gone in curves if not gone and y.size]
            if bounded and any(gone for *_, gone in curves):
                lo = min(float(np.min(y)) for y in bounded)
                hi = max(float(np.max(y)) for y in bounded)
                pad = 0.2 * (hi - lo) or 1.0
                lo, hi = lo - pad, hi + pad
            else:
                lo = hi = None
            for t, y, which, label, gone in curves:
                if gone and lo is not None:
                    y = np.clip(y, lo - (hi - lo), hi + (hi - lo))
                ax.plot(*_envelope(t, y), "-" if which == "truth" else "--", label=label)
            if lo is not None:
                ax.set_ylim(lo, hi)
            ax.set_ylabel(f"{name} [{unit}]")
            ax.grid(True)
            ax.legend(fontsize="small", loc="best")
        axes[-1, 0].set_xlabel("time [s]")
        fig.suptitle(f"{kind.upper()} slew: design model (chain) vs truth model")
        path = folder / f"slew_{kind}.png"
        fig.savefig(path, dpi=100)
        out.append((path, f"{kind.upper()} slew responses: theta, torque, tip deflection; "
                          "design vs truth"))
    return out


def _plot_bode(result, folder: Path, stats, exact: bool) -> list:
    scene = result.scene
    a = scene.appendages[0]
    models = result.models[a.name]
    curves = []
    if exact and "beam" in models and a.truth == "beam":
        curves.append(("beam (exact)", models["beam"], "-"))
        stats.exact_reference_evaluations += 1
    curves.append((f"truth model ({type(models['truth']).__name__})", models["truth"], "--"))
    for match, chain in models.get("fits", {}).items():
        from .runner import FIT_LABELS

        curves.append((FIT_LABELS.get(match, match), chain, ":"))
    if not models.get("fits"):
        for variant, d in result.designs.items():
            model = d["appendages"][a.name]
            if model is not models["truth"]:
                curves.append((f"design ({type(model).__name__})", model, ":"))
    w_ref = []
    for _, model, _ in curves:
        if hasattr(model, "poles"):
            w_ref.append(float(np.asarray(model.poles())[0]))
    w1 = min(w_ref) if w_ref else 1.0
    omega = np.geomspace(w1 / 30.0, w1 * 30.0, 800)
    s = 1j * omega
    fig, axes = _figure(2, 2, (11, 7))
    entries = [((0, 0), "W1 = delta/F_y [m/N]"), ((0, 1), "W2 = W3 = delta/M [1/N]"),
               ((1, 1), "W4 = phi/M [1/(N m)]")]
    for label, model, style in curves:
        W = model.W(s)
        for (i, j), title in entries:
            axes[i if (i, j) != (1, 1) else 1, j].loglog(omega, np.abs(W[:, i, j]), style,
                                                         label=label)
    for (i, j), title in entries:
        ax = axes[i, j]
        ax.set_title(title, fontsize="medium")
        ax.grid(True)
        ax.minorticks_off()  # hundreds of minor log ticks cost seconds to draw
        ax.set_xlabel("frequency [rad/s]")
        ax.legend(fontsize="small")
    axes[1, 0].axis("off")
    axes[1, 0].text(0.0, 0.5, f"appendage '{a.name}' at its attachment end\n(free appendage, "
                              "rigid-body term included)", fontsize="medium")
    fig.suptitle("Bode magnitude of W_r")
    path = folder / "bode_W.png"
    fig.savefig(path, dpi=100)
    return [(path, "Bode magnitude of W_r: exact beam, truncated beam, chains")]


def _plot_pole_zero(result, folder: Path) -> list:
    import control

    fig, axes = _figure(1, 1, (8, 6))
    ax = axes[0, 0]
    plants = [("truth", result.truth["verdict"], "C0")]
    for k, (variant, d) in enumerate(result.designs.items()):
        plants.append((f"design: {variant}", d["plant"], f"C{k + 1}"))
    for label, plant, color in plants:
        siso = plant[list(plant.output_labels).index("theta"),
                     list(plant.input_labels).index("torque")]
        poles = np.asarray(control.poles(siso))
        zeros = np.asarray(control.zeros(siso))
        ax.plot(poles.real, poles.imag, "x", color=color, label=f"poles, {label}")
        ax.plot(zeros.real, zeros.imag, "o", mfc="none", color=color, label=f"zeros, {label}")
    ax.set_xlabel("Re s [1/s]")
    ax.set_ylabel("Im s [rad/s]")
    ax.axvline(0.0, color="gray", lw=0.5)
    ax.grid(True)
    ax.legend(fontsize="small")
    fig.suptitle("Poles and zeros of theta/torque")
    path = folder / "pole_zero.png"
    fig.savefig(path, dpi=100)
    return [(path, "Pole/zero map of theta/torque: truth and design plants")]


# ---------------------------------------------------------------------------------------------
# FMUs
# ---------------------------------------------------------------------------------------------
def _fmu_jobs(result) -> list:
    """(name, system, description) of every FMU the scene asks for."""
    scene = result.scene
    primary = next(iter(result.designs))
    jobs = []
    if "plant" in scene.export.systems:
        jobs.append(("plant", result.truth["sim"], "truth plant (hub + appendages)"))
    for kind, K in result.designs[primary]["controllers"].items():
        if "controller" in scene.export.systems:
            jobs.append((kind, K, f"{kind.upper()} controller tuned on {_label(primary)}"))
        if "closed_loop" in scene.export.systems:
            loop = result.loops.get((primary, kind, "truth"))
            if loop is None:
                import controllers

                loop = controllers.close_loop(result.truth["sim"], K)
            jobs.append((f"closed_loop_{kind}", loop,
                         f"{kind.upper()} loop closed on the truth plant"))
    return jobs


def _start_fmu_exports(result, folder: Path, pool) -> list:
    """Submit the FMU builds to a thread pool; returns [(job, future)]."""
    import fmu

    scene = result.scene
    step = scene.export.step or (scene.manoeuvre.step if scene.manoeuvre else None)
    stop = scene.manoeuvre.duration if scene.manoeuvre else 100.0 * step

    def build(job):
        name, system, description = job
        return fmu.export(system, folder / f"{name}.fmu", model_name=name, step=step,
                          stop_time=stop, reference=scene.export.reference_files,
                          description=f"flexsat: {description}")

    return [(job, pool.submit(build, job)) for job in _fmu_jobs(result)]


def _finish_fmu_exports(started: list, stats) -> list:
    out = []
    for (name, system, description), future in started:
        path = future.result()
        stats.fmu_builds += 1
        out.append({"path": f"fmu/{path.name}", "description": description,
                    "inputs": list(system.input_labels), "outputs": list(system.output_labels),
                    "n_states": int(system.nstates)})
    return out


# ---------------------------------------------------------------------------------------------
# the writer
# ---------------------------------------------------------------------------------------------
def write_report(result, folder: str | os.PathLike, *, fmus: bool | None = None,
                 plots: bool | None = None, pages: bool = True, progress=None) -> dict:
    """Write the report of a run into ``folder`` (which must exist).

    Parameters
    ----------
    result : spacecraft.runner.RunResult
    folder : path
        Destination (use :func:`output_folder` for an all-or-nothing folder).
    fmus, plots : bool, optional
        Override the scene's ``export.fmu`` / ``report.plots`` (False: skip).
    pages : bool
        Write report.md, report.html and results.json (False: FMUs only).
    progress : callable, optional
        Called with a short message per step.

    Returns
    -------
    dict
        The results (``result.data`` plus ``files``, ``version``, ``created``), as written to
        results.json.
    """
    folder = Path(folder)
    progress = progress or (lambda message: None)
    scene = result.scene
    stats = result.stats
    do_fmus = scene.export.fmu if fmus is None else (fmus and scene.export.fmu)
    wanted_plots = scene.report.plots if plots is None or plots else ()
    data = dict(result.data)
    data["version"] = _version()
    data["created"] = datetime.datetime.now().isoformat(timespec="seconds")
    files: dict = {"fmu": [], "plots": []}
    # The C compiler runs in subprocesses: the FMU builds (two at a time, both cores) proceed
    # while the plots are drawn.
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=2)
    try:
        started = []
        if do_fmus:
            (folder / "fmu").mkdir(exist_ok=True)
            started = _start_fmu_exports(result, folder / "fmu", pool)
            progress(f"exporting {len(started)} FMUs")
        images = _plots(result, folder, wanted_plots if pages else (), progress)
        if started:
            progress("waiting for the FMU builds")
        files["fmu"] = _finish_fmu_exports(started, stats)
    finally:
        # on an error or a signal the builds not yet started are dropped; running ones (a few
        # tenths of a second of gcc) finish before the folder is removed
        pool.shutdown(wait=True, cancel_futures=True)
    images = [(f"plots/{Path(p).name}", caption) for p, caption in images]
    files["plots"] = [p for p, _ in images]
    data["files"] = files
    data["stats"] = stats.as_dict()
    if pages:
        progress("writing report")
        blocks = _blocks(data, images)
        (folder / "report.md").write_text(markdown(blocks), encoding="utf-8")
        (folder / "report.html").write_text(render_html(blocks, data.get("title") or "flexsat"),
                                            encoding="utf-8")
        data["files"]["pages"] = ["report.md", "report.html", "results.json"]
        (folder / "results.json").write_text(to_json(data), encoding="utf-8")
    return data


def _plots(result, folder: Path, wanted, progress) -> list:
    """Draw the plots asked for; returns [(path, caption)]."""
    scene, stats = result.scene, result.stats
    images = []
    if not wanted:
        return images
    (folder / "plots").mkdir(exist_ok=True)
    progress("plotting")
    if "slew" in wanted and result.responses:
        images += _plot_slews(result, folder / "plots")
    if "bode" in wanted:
        images += _plot_bode(result, folder / "plots", stats, scene.outputs.exact_reference)
    if "pole_zero" in wanted:
        images += _plot_pole_zero(result, folder / "plots")
    stats.plots += len(images)
    return images


def _version() -> str:
    try:
        from importlib.metadata import version

        return version("flexsat")
    except Exception:  # not installed (a source checkout)
        return "unknown"
