"""The report's figures: what an attitude-control engineer looks at first.

One figure per question, every controller side by side in it (so a planar scene's plots are at
most four PNG files, drawn on matplotlib's Agg canvas without pyplot):

- ``slew.png``: per controller, theta with theta_ref [deg], the attitude error |theta -
  theta_ref| on a log scale [deg] (an overshoot of a few percent is visible there, with the
  2 % settling band and the end of the slew), the torque [N m], the tip deflection of every
  appendage [m] (one panel each, named) and, with a disturbance, the attitude response to the
  disturbance alone;
- ``loop.png``: per controller, the open-loop transfer L(j omega) with the loop broken at the
  torque (negative-feedback convention, unstable at L = -1): |L| [dB] and arg L [deg] on the
  design model, the truth model and (when computed) the exact distributed beam, the gain and
  phase crossovers marked with the margins; and its Nyquist plot near -1 with the unit circle
  and the modulus-margin circle;
- ``poles.png``: per controller, the closed-loop poles on the design and truth models in the
  s-plane near the loop's bandwidth with lines of constant damping ratio, and damping ratio
  against natural frequency for every pole (the flexible modes far above the bandwidth);
  unstable poles red, the right half-plane shaded;
- ``W.png``: |W1|, |W2| = |W3|, |W4| of every (distinct) appendage: the exact beam, the truth
  model and the design chains, with the band where the truth model is resolved;
- ``profile.png``: the reference profile per design model: theta_ref [deg], omega_ref [deg/s]
  and the feedforward torque J alpha_ref [N m] against the profile's limits, the end of the
  profile and (shaped) the shaper's impulses;
- ``wheels.png``: per controller, each wheel's torque (applied, and the controller's command)
  and momentum against their limits, the time a limit acts shaded; Basilisk's wheel dotted.

A three-axis scene gets the same figures per axis where the physics has axes: the slew of each
controller in ``slew_<controller>.png`` with a column per hub axis (attitude with its reference,
torque) and per appendage the tip deflections in its two bending planes and its twist;
``loop.png`` with each axis' loop at a time (L_i = 1/S_ii - 1: magnitude, phase, Nyquist) and
the smallest singular value of the return difference I + L; ``poles.png`` as it is;
``W.png`` with the diagonal of W6 (both bending planes, torsion, axial).

Names and colours are those of :mod:`spacecraft.design.naming`: one colour per design model, the loop
on the truth model solid, on the design model dashed, the exact beam black, Basilisk dotted,
anything unstable red. A figure has one legend (above the panels).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..design.naming import (BASILISK_COLOUR, BASILISK_STYLE, CAUTION_COLOUR, DESIGN_STYLE, EXACT_COLOUR,
                     REFERENCE_COLOUR, TRUTH_STYLE, UNSTABLE_COLOUR, controller_label, design_label, plural,
                     variant_colour)
from ..design.responses import trace
from ..design.verdicts import crossover_frequencies

__all__ = ["plot_slew", "plot_slew_axes", "plot_loop", "plot_loop_axes", "plot_poles", "plot_W",
           "plot_profile", "plot_wheels", "draw", "PLOT_FILES", "AXIS_COLOURS", "envelope",
           "identical"]

#: File of each plot of ``report.plots``.
PLOT_FILES = {"slew": "slew.png", "loop": "loop.png", "poles": "poles.png", "W": "W.png",
              "profile": "profile.png", "wheels": "wheels.png"}

#: Points drawn per curve: a longer response is drawn as its min/max envelope (peaks kept).
_PLOT_POINTS = 4000
#: Resolution of the PNG files [dots per inch].
_DPI = 90
#: Largest number of appendages with a tip-deflection panel of their own.
_MAX_TIP_PANELS = 6
_AXES = ("x", "y", "z")
#: Colours of the hub axes in three-axis plots (of the loop at a time).
AXIS_COLOURS = {"x": "#1f77b4", "y": "#ff7f0e", "z": "#2ca02c"}
#: The wheels of a set of several, one colour each (wheels.png).
WHEEL_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf",
                 "#bcbd22")


def _figure(rows: int, cols: int, size, *, top: float = 0.9, left: float = 0.08,
            hspace: float = 0.45, wspace: float = 0.28, bottom: float | None = None):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    # a fixed layout: constrained or tight layout redraws every figure several times
    fig = Figure(figsize=size)
    FigureCanvasAgg(fig)
    fig.subplots_adjust(left=left, right=0.98, bottom=bottom or 0.62 / size[1], top=top,
                        hspace=hspace, wspace=wspace)
    return fig, fig.subplots(rows, cols, squeeze=False)


def _legend(fig, handles: list, top: float | None = None) -> None:
    """One legend for the figure at its top; the panels start below it (and below their
    titles)."""
    seen, unique = set(), []
    for h in handles:
        if h.get_label() not in seen and not h.get_label().startswith("_"):
            seen.add(h.get_label())
            unique.append(h)
    ncol = min(3, len(unique))
    fig.legend(handles=unique, loc="upper center", bbox_to_anchor=(0.5, 0.995), ncol=ncol,
               fontsize="small", frameon=False)
    rows = -(-len(unique) // max(ncol, 1))
    height = fig.get_figheight()
    fig.subplots_adjust(top=1.0 - (0.12 + 0.2 * rows + 0.4) / height)


def _plain_number(value, _position=None) -> str:
    """Tick label of a log axis without mathtext ("0.01", "100", "1e+06")."""
    return f"{value:g}"


def _tidy(fig) -> None:
    """Cheaper axes, same information: no minor ticks (hundreds of tick objects on log axes),
    log- and symlog-axis labels as plain numbers instead of mathtext ($10^{-2}$ is parsed and laid out
    for every label), at most 6 major ticks on a linear axis."""
    from matplotlib.ticker import (AutoLocator, FuncFormatter, LogLocator, MaxNLocator,
                                   SymmetricalLogLocator)

    for ax in fig.axes:
        ax.minorticks_off()
        for axis in (ax.xaxis, ax.yaxis):
            scale = axis.get_scale()
            if scale == "symlog" and type(axis.get_major_locator()) is SymmetricalLogLocator:
                # "-0.1", "0", "0.001": the first mathtext label of a process costs ~0.15 s
                axis.set_major_formatter(FuncFormatter(_plain_number))
                continue
            default = type(axis.get_major_locator()) in (AutoLocator, LogLocator)
            if not default:
                continue   # ticks a plot set itself (the phase axis' multiples of 90 deg)
            if scale == "log":
                axis.set_major_locator(LogLocator(numticks=7))
                axis.set_major_formatter(FuncFormatter(_plain_number))
            elif scale == "linear":
                # a square panel (equal aspect) is narrow: fewer labels, or they overlap
                axis.set_major_locator(MaxNLocator(nbins=4 if ax.get_aspect() == 1.0 else 6))


def _save(fig, path: Path) -> None:
    """Write the PNG (:func:`_tidy` axes). zlib level 1 instead of 6: a fifth of the encoding
    time for files a few percent larger (line plots compress well at any level)."""
    _tidy(fig)
    fig.savefig(path, dpi=_DPI, pil_kwargs={"compress_level": 1})


def _line(**style):
    from matplotlib.lines import Line2D

    return Line2D([], [], **style)


def envelope(t: np.ndarray, y: np.ndarray, points: int = _PLOT_POINTS):
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


def identical(a: np.ndarray, b: np.ndarray) -> bool:
    """Two curves that would be drawn on top of each other: same length, equal within 1e-9 of
    their range (round-off of two realisations of the same loop is ~1e-12)."""
    if a.shape != b.shape:
        return False
    with np.errstate(invalid="ignore", over="ignore"):
        scale = max(float(np.max(np.abs(a), initial=0.0)), 1e-300)
        return bool(np.all(np.abs(a - b) <= 1e-9 * scale))


def _rows(result, kind: str) -> list:
    return [r for r in result.data.get("closed_loops", []) if r["controller"] == kind]


def _unstable(row, which: str = "truth") -> bool:
    status = (row.get("status") or {}).get(which)
    if status is not None:
        return status["status"] in ("unstable", "diverges")
    return which == "truth" and not row["verdict"]["stable"]


def _cautions(result, kind: str) -> str:
    """The cautions of a controller's loops (low margins, lowered or light damping: the design
    warnings of :mod:`spacecraft.design.verdicts`), as a title says them; "" when none."""
    from ..design.verdicts import CAUTIONS

    codes = [w["code"] for w in result.data.get("design_warnings", [])
             if w.get("controller") == kind and w["code"] in CAUTIONS]
    return ", ".join(CAUTIONS[c] for c in dict.fromkeys(codes))


# ---------------------------------------------------------------------------------------------
# slew
# ---------------------------------------------------------------------------------------------
def plot_slew(result, path: Path) -> str:
    """Draw ``slew.png``; returns its caption."""
    scene = result.scene
    m = scene.manoeuvre
    kinds = list(dict.fromkeys(k[1] for k in result.responses))
    first = result.responses[next(iter(result.responses))]
    names = [a.name for a in scene.appendages
             if f"{a.name}_tip_deflection" in first.output_labels][:_MAX_TIP_PANELS]
    panels = [("theta", "attitude theta [deg]"), ("error", "|theta - theta_ref| [deg]"),
              ("torque", "torque [N m]")]
    panels += [(f"{n}_tip_deflection", f"tip deflection, {n} [m]") for n in names]
    if result.disturbance_responses:
        panels.append(("disturbance", "theta, disturbance alone [deg]"))
    n_rows, n_cols = len(panels), len(kinds)
    height = 1.9 * n_rows + 1.3
    top = 1.0 - 1.0 / height
    fig, axes = _figure(n_rows, n_cols, (6.2 * n_cols + 0.6, height), top=top,
                        left=0.1 if n_cols == 1 else 0.07)
    handles = []
    angle = math.degrees(m.slew_angle)
    wheels = _basilisk_wheels(result)
    for col, kind in enumerate(kinds):
        rows = {r["design"]: r for r in _rows(result, kind)}
        bad = [v for v, r in rows.items() if _unstable(r)]
        cautions = _cautions(result, kind)
        title = f"{controller_label(kind)}: " + (
            "UNSTABLE on the truth model when tuned on " + ", ".join(map(design_label, bad))
            if bad else "stable on the truth model" + (f"; {cautions}" if cautions else ""))
        axes[0, col].set_title(title, fontsize="medium",
                               color=UNSTABLE_COLOUR if bad else
                               CAUTION_COLOUR if cautions else "black")
        for row_index, (signal, label) in enumerate(panels):
            ax = axes[row_index, col]
            curves = []
            for (variant, k, which), resp in result.responses.items():
                if k != kind:
                    continue
                source = result.disturbance_responses if signal == "disturbance" else None
                if source is not None:
                    resp = source.get((variant, k, which))
                    if resp is None:
                        continue
                y = _slew_signal(resp, signal)
                if y is None:
                    continue
                row = rows.get(variant)
                curves.append((variant, which, np.asarray(resp.t, float).reshape(-1), y,
                               row is not None and _unstable(row, which)))
            _draw_curves(ax, curves, handles, log=signal == "error", note=row_index == 0)
            _draw_basilisk(ax, result, kind, signal, handles,
                           wheels[kind][1] if signal == "torque" and kind in wheels else None)
            if signal == "theta":
                t = np.asarray(first.t, float).reshape(-1)
                # the reference the loops read (the scene's profile)
                ref = np.degrees(trace(first, "theta_ref", "input"))
                handles += ax.plot(t, ref, ":", color=REFERENCE_COLOUR, lw=1.2,
                                   label="theta_ref (reference)")
            if signal == "error":
                band = 0.02 * abs(angle)
                handles.append(ax.axhline(band, color=REFERENCE_COLOUR, lw=0.8, ls="-.",
                                          label="2 % settling band"))
            if signal in ("theta", "error", "torque") or signal.endswith("_tip_deflection"):
                if m.slew_time <= m.duration:
                    handles.append(ax.axvline(m.slew_time, color=REFERENCE_COLOUR, lw=0.6,
                                              ls="--", label="end of the slew"))
            ax.set_ylabel(label, fontsize="small")
            ax.grid(True, alpha=0.4)
            ax.tick_params(labelsize="small")
        axes[-1, col].set_xlabel("time [s]")
    _legend(fig, handles, top)
    _save(fig, path)
    caption = (f"Slew of {angle:g} deg in {m.slew_time:g} s, simulated {m.duration:g} s: "
               "theta and theta_ref; the attitude error on a log scale with the 2 % settling "
               "band; torque; tip deflection of each appendage")
    if result.disturbance_responses:
        caption += "; the attitude response to the disturbance alone"
    if result.scene.wheels is not None:
        caption += ("; through the reaction wheels (the slew and the disturbance together: the "
                    "wheels are nonlinear)")
    if result.scene.controller.total_delay > 0:
        caption += f"; with the loop delay of {result.scene.controller.total_delay:g} s"
    if result.basilisk:
        caption += ("; dotted black: Basilisk's nonlinear run of the design chains (the whole "
                    "manoeuvre, flight software at its sample time"
                    + ("; the torque its reaction wheel applies, within its limits" if wheels
                       else "") + ")" + _basilisk_caption_note(result))
    return caption + (". Solid: loop on the truth model, dashed: on the design model; one "
                      "colour per design model; red: unstable.")


def _basilisk_caption_note(result) -> str:
    """What a slew plot's Basilisk curves hold that flexsat's beside them do not: the
    disturbance pulse (shaded), and motions Basilisk holds rigid (their tip motion is 0)."""
    note = ""
    if result.scene.manoeuvre.disturbance is not None:
        note += ("; Basilisk flies the slew and the disturbance pulse together (shaded), "
                 "flexsat's curves here the slew alone, so they part there")
    held = sorted({name for entry in (result.data.get("basilisk") or {}).values()
                   for name, h in (entry.get("chains_as_held") or {}).items()
                   if "torsion" in h["held"]})
    if held:
        note += (f"; Basilisk holds the torsion of {', '.join(held)} rigid (its twist is 0 "
                 "there; the report's Basilisk section says why and what it costs)")
    return note


def _draw_basilisk(ax, result, kind: str, signal: str, handles: list, y=None) -> None:
    """Basilisk's run of a controller in a slew panel (dotted black), when there is one: its
    ``signal`` as :func:`_slew_signal` forms it, or ``y`` (e.g. the torque its wheel applies)."""
    comparison = result.basilisk.get(kind)
    if comparison is None or signal == "disturbance":
        return
    resp = comparison.basilisk.response
    y = _slew_signal(resp, signal) if y is None else y
    if y is None:
        return
    variant = result.data["basilisk"][kind]["design"]
    t = np.asarray(resp.t, float).reshape(-1)
    if signal == "error":
        y = np.maximum(y, 1e-9)
    pulse = result.scene.manoeuvre.disturbance
    if pulse is not None and pulse.start < t[-1]:
        # Basilisk flies the slew and the pulse together, flexsat's slew curves the slew alone
        end = t[-1] if pulse.length is None else min(pulse.start + pulse.length, t[-1])
        handles.append(ax.axvspan(pulse.start, end, color=BASILISK_COLOUR, alpha=0.08, lw=0,
                                  label="disturbance pulse (in Basilisk's run only)"))
    handles += (ax.semilogy if signal == "error" else ax.plot)(
        *envelope(t, y), BASILISK_STYLE, color=BASILISK_COLOUR, lw=1.6,
        label=f"Basilisk: {design_label(variant)}, nonlinear", zorder=3)


def plot_slew_axes(result, path: Path, kind: str) -> str:
    """Draw a three-axis loop's slew, ``slew_<kind>.png``: one column per hub axis; returns its
    caption."""
    scene = result.scene
    m = scene.manoeuvre
    first = result.responses[next(k for k in result.responses if k[1] == kind)]
    names = [n for n in _appendage_names(result)
             if f"{n}_tip_deflection_y" in first.output_labels][:_MAX_TIP_PANELS]
    # (signal, panel title, unit)
    grid = [[(f"theta_{a}", f"attitude about {a}", "deg") for a in _AXES],
            [(f"torque_{a}", f"torque about {a}", "N m") for a in _AXES],
            [("error", "attitude error |theta - theta_ref| (norm)", "deg"),
             ("disturbance", "attitude |theta| (norm), disturbance alone", "deg")
             if result.disturbance_responses else None, None]]
    for n in names:
        grid.append([(f"{n}_tip_deflection_y", f"{n}: tip deflection in its x-y plane", "m"),
                     (f"{n}_tip_deflection_z", f"{n}: tip deflection in its x-z plane", "m"),
                     (f"{n}_tip_twist", f"{n}: tip twist", "deg")])
    height = 2.1 * len(grid) + 1.5
    top = 1.0 - 1.0 / height
    fig, axes = _figure(len(grid), 3, (17.0, height), top=top, left=0.05, hspace=0.6)
    handles = []
    rows = {r["design"]: r for r in _rows(result, kind)}
    bad = [v for v, r in rows.items() if _unstable(r)]
    cautions = _cautions(result, kind)
    verdict = (f"{controller_label(kind)}: " + (
        "UNSTABLE on the truth model when tuned on " + ", ".join(map(design_label, bad))
        if bad else "stable on the truth model" + (f"; {cautions}" if cautions else "")))
    # the verdict beside the legend's first entries, in the loop's colour
    fig.text(0.01, 0.995, verdict, ha="left", va="top", fontsize="medium",
             color=UNSTABLE_COLOUR if bad else CAUTION_COLOUR if cautions else "black")
    angle = math.degrees(m.slew_angle)
    import controllers

    t_ref = np.asarray(first.t, float).reshape(-1)
    reference = controllers.slew_profile(t_ref, m.slew_angle, m.slew_time)
    for i, panels in enumerate(grid):
        for j, panel in enumerate(panels):
            ax = axes[i, j]
            if panel is None:
                ax.set_visible(False)
                continue
            signal, title, unit = panel
            curves = []
            for (variant, k, which), resp in result.responses.items():
                if k != kind:
                    continue
                if signal == "disturbance":
                    resp = result.disturbance_responses.get((variant, k, which))
                    if resp is None:
                        continue
                y = _slew_signal(resp, signal)
                if y is None:
                    continue
                row = rows.get(variant)
                curves.append((variant, which, np.asarray(resp.t, float).reshape(-1), y,
                               row is not None and _unstable(row, which)))
            _draw_curves(ax, curves, handles, log=signal == "error", note=(i, j) == (0, 0))
            _draw_basilisk(ax, result, kind, signal, handles)
            if signal.startswith("theta_"):
                # the reference the loops read (the scene's profile), else the cycloid
                read = trace(first, f"theta_ref_{signal[-1]}", "input")
                e = m.slew_axis["xyz".index(signal[-1])]
                handles += ax.plot(t_ref, np.degrees(e * reference if read is None else read),
                                   ":",
                                   color=REFERENCE_COLOUR, lw=1.2,
                                   label="theta_ref (reference, per axis)")
            if signal == "error":
                handles.append(ax.axhline(0.02 * abs(angle), color=REFERENCE_COLOUR, lw=0.8,
                                          ls="-.", label="2 % settling band"))
            if signal != "disturbance" and m.slew_time <= m.duration:
                handles.append(ax.axvline(m.slew_time, color=REFERENCE_COLOUR, lw=0.6, ls="--",
                                          label="end of the slew"))
            ax.set_title(title, fontsize="small")
            ax.set_ylabel(f"[{unit}]", fontsize="small")
            ax.grid(True, alpha=0.4)
            ax.tick_params(labelsize="small")
            if i == len(grid) - 1 or grid[i + 1][j] is None:
                ax.set_xlabel("time [s]")
    _legend(fig, handles, top)
    _save(fig, path)
    caption = (f"{controller_label(kind)}: eigen-axis slew of {angle:g} deg about "
               f"({', '.join(f'{e:.3g}' for e in m.slew_axis)}) (hub axes) in "
               f"{m.slew_time:g} s, simulated {m.duration:g} s; per hub axis (columns) the "
               "attitude with its reference and the torque; the attitude error's norm on a log "
               "scale with the 2 % settling band")
    if result.disturbance_responses:
        caption += "; the attitude's norm under the disturbance alone"
    if names:
        caption += ("; per appendage its tip deflections in its own x-y and x-z planes [m] "
                    "and its twist [deg]")
    if kind in result.basilisk:
        caption += ("; dotted black: Basilisk's nonlinear run of the design chains (the whole "
                    "manoeuvre, three-axis flight software at its sample time; the torques it "
                    "commands)" + _basilisk_caption_note(result))
    return caption + (". Solid: loop on the truth model, dashed: on the design model; one "
                      "colour per design model; red: unstable.")


def _appendage_names(result) -> list[str]:
    """The appendages' names in mount order (a scene's, or a user's own truth model's)."""
    sc = result.truth.get("spacecraft")
    if sc is not None:
        return list(sc.names)
    return [a.name for a in result.scene.appendages]


def _slew_signal(resp, signal: str) -> np.ndarray | None:
    """A panel's curve: an output as it is (degrees for angles), the attitude error (three
    axes: its norm) [deg], or the attitude alone (three axes: its norm) [deg]."""
    with np.errstate(over="ignore", invalid="ignore"):
        three_axis = "theta" not in resp.output_labels
        if signal == "error":
            pairs = ([(f"theta_{a}", f"theta_ref_{a}") for a in _AXES] if three_axis
                     else [("theta", "theta_ref")])
            parts = [(trace(resp, y), trace(resp, r, "input")) for y, r in pairs]
            if any(y is None or r is None for y, r in parts):
                return None
            return np.degrees(np.sqrt(sum((y - r) ** 2 for y, r in parts)))
        if signal in ("theta", "disturbance"):
            if three_axis:
                parts = [trace(resp, f"theta_{a}") for a in _AXES]
                if any(y is None for y in parts):
                    return None
                return np.degrees(np.sqrt(sum(y ** 2 for y in parts)))
            y = trace(resp, "theta")
            return None if y is None else np.degrees(y)
        y = trace(resp, signal)
        if y is None:
            return None
        angle = signal.startswith("theta_") or signal.endswith("_tip_twist")
        return np.degrees(y) if angle else np.asarray(y, float)


def _draw_curves(ax, curves: list, handles: list, *, log: bool = False,
                 note: bool = False) -> None:
    """Draw responses: identical ones once (noted), diverging ones red and clipped just
    outside the range of the bounded ones."""
    drawn: list = []
    merged = []
    for c in curves:
        twin = next((d for d in drawn if d[1] == c[1] and d[4] == c[4]
                     and identical(d[3], c[3])), None)
        if twin is None:
            drawn.append(c)
        else:
            merged.append((twin[0], c[0], c[1]))
    bounded = [y for *_, y, gone in drawn if not gone and y.size]
    lo = hi = None
    if bounded and any(gone for *_, gone in drawn) and not log:
        lo = min(float(np.min(y)) for y in bounded)
        hi = max(float(np.max(y)) for y in bounded)
        pad = 0.25 * (hi - lo) or 1.0
        lo, hi = lo - pad, hi + pad
    for variant, which, t, y, gone in drawn:
        style = TRUTH_STYLE if which == "truth" else DESIGN_STYLE
        colour = UNSTABLE_COLOUR if gone else variant_colour(variant)
        label = (f"UNSTABLE: {design_label(variant)}, loop on the {which} model" if gone
                 else f"{design_label(variant)}: loop on the {which} model")
        if gone and lo is not None:
            y = np.clip(y, lo - (hi - lo), hi + (hi - lo))
        if log:
            y = np.maximum(y, 1e-9)
        tt, yy = envelope(t, y)
        # the unstable curve beneath: the stable ones it would hide stay visible
        handles += (ax.semilogy if log else ax.plot)(
            tt, yy, style, color=colour, lw=1.6 if gone else 1.2, label=label,
            zorder=1.5 if gone else 2.5)
    if lo is not None:
        ax.set_ylim(lo, hi)
    if log and drawn:
        tops = [float(np.max(y)) for *_, y, _ in drawn if y.size and np.isfinite(y).any()]
        if tops:
            top = max(tops)
            ax.set_ylim(max(top * 1e-6, 1e-9), top * 3.0)
    if note:
        for a, b, which in merged:
            ax.text(0.99, 0.05, f"loops on the {which} model: {design_label(a)} and "
                    f"{design_label(b)} coincide", transform=ax.transAxes, ha="right",
                    va="bottom", fontsize="x-small", color=REFERENCE_COLOUR,
                    bbox=dict(facecolor="white", edgecolor="none", alpha=0.85, pad=1))


# ---------------------------------------------------------------------------------------------
# open loop: Bode and Nyquist
# ---------------------------------------------------------------------------------------------
def _wrapped_phase(L: np.ndarray) -> np.ndarray:
    """arg L in (-270, 90] deg, NaN where it wraps (no vertical line drawn across): the
    rigid-body loop's -180 deg sits mid-range, and a lightly damped mode's +180 deg swing
    above a PD's -90 deg stays on the axis."""
    phase = 90.0 - np.mod(90.0 - np.degrees(np.angle(L)), 360.0)
    jumps = np.abs(np.diff(phase)) > 180.0
    phase = phase.copy()
    phase[1:][jumps] = np.nan
    return phase


def loop_band(result) -> tuple[float, float]:
    """Frequency range [rad/s] of the loop plots, from the models: from 1/30 of the slowest
    crossover (or natural frequency) to 30 x the fastest, extended to 1.5 x the design
    plants' highest mode (at most 1e3 x the crossover)."""
    crossings = [w for r in result.data.get("closed_loops", [])
                 for source in (r["design_margins"], r["verdict"])
                 for w in crossover_frequencies(source)]
    spec = result.scene.controller
    if spec.pd is not None and spec.pd.natural_frequency is not None:
        crossings.append(spec.pd.natural_frequency)
    if not crossings:
        crossings = [1.0]
    w_lo, w_hi = min(crossings) / 30.0, max(crossings) * 30.0
    modes = []
    for d in result.designs.values():
        A = np.asarray(d["plant"].A, dtype=float)
        if A.size:
            modes.append(float(np.max(np.abs(np.linalg.eigvals(A)))))
    if modes:
        w_hi = min(max(w_hi, 1.5 * max(modes)), 1e3 * max(crossings))
    return w_lo, w_hi


def plot_loop(result, path: Path) -> str:
    """Draw ``loop.png``; returns its caption."""
    import controllers

    kinds = list(dict.fromkeys(r["controller"] for r in result.data["closed_loops"]))
    w_lo, w_hi = loop_band(result)
    n = len(kinds)
    height = 3.6 * n + 1.0
    top = 1.0 - 0.8 / height
    fig, axes = _figure(n, 3, (16.5, height), top=top, wspace=0.3, left=0.06)
    handles = []
    for i, kind in enumerate(kinds):
        mag, ph, nyq = axes[i]
        notes = []
        for row in _rows(result, kind):
            variant = row["design"]
            d = result.designs[variant]
            K = d["controllers"][kind]
            colour = variant_colour(variant)
            sources = [("design", d["plant"], DESIGN_STYLE, colour),
                       ("truth", result.truth["verdict"], TRUTH_STYLE,
                        UNSTABLE_COLOUR if _unstable(row) else colour)]
            if result.exact_frd is not None and not K.isdtime(strict=True):
                sources.append(("exact beam", result.exact_frd, ":", colour))
            for which, plant, style, c in sources:
                with np.errstate(all="ignore"):
                    omega, L = controllers.loop_frequency_response(plant, K)
                keep = (omega >= w_lo) & (omega <= w_hi) & np.isfinite(L)
                omega, L = omega[keep], L[keep]
                if omega.size < 2:
                    continue
                where = "the exact beam" if which == "exact beam" else f"the {which} model"
                label = f"{design_label(variant)}: L on {where}"
                with np.errstate(divide="ignore"):
                    handles += mag.semilogx(omega, 20 * np.log10(np.abs(L)), style, color=c,
                                            lw=1.2, label=label)
                ph.semilogx(omega, _wrapped_phase(L), style, color=c, lw=1.2)
                if which != "exact beam":   # near -1 it is the truth model's curve
                    inside = np.abs(L + 1.0) < 6.0
                    nyq.plot(np.where(inside, L.real, np.nan),
                             np.where(inside, L.imag, np.nan), style, color=c, lw=1.2)
            v = row["verdict"]
            wc, pm, gm = v["gain_crossover_frequency"], v["phase_margin"], v["gain_margin"]
            if wc is not None and math.isfinite(wc) and w_lo <= wc <= w_hi:
                mag.axvline(wc, color=colour, lw=0.7, ls="-.")
                ph.axvline(wc, color=colour, lw=0.7, ls="-.")
                if math.isfinite(pm):
                    ph.plot([wc, wc], [-180.0, -180.0 + pm], color=colour, lw=3, alpha=0.6)
            wp = v["phase_crossover_frequency"]
            if wp is not None and math.isfinite(wp) and w_lo <= wp <= w_hi and math.isfinite(gm):
                mag.plot([wp, wp], [0.0, -gm], color=colour, lw=3, alpha=0.6)
            mm = v["modulus_margin"]
            if mm is not None and math.isfinite(mm):
                circle = np.exp(1j * np.linspace(0, 2 * np.pi, 200))
                nyq.plot((-1 + mm * circle).real, (-1 + mm * circle).imag, color=colour,
                         lw=0.7, ls="-.")
            notes.append(f"{design_label(variant)}, on the truth model:\n  GM {_num(gm, 'dB')}, "
                         f"PM {_num(pm, 'deg')}, modulus margin {_num(mm, '')}")
        mag.axhline(0.0, color=REFERENCE_COLOUR, lw=0.7)
        ph.axhline(-180.0, color=REFERENCE_COLOUR, lw=0.7)
        ph.set_ylim(-270, 90)
        ph.set_yticks([-270, -180, -90, 0, 90])
        circle = np.exp(1j * np.linspace(0, 2 * np.pi, 200))
        nyq.plot(circle.real, circle.imag, color=REFERENCE_COLOUR, lw=0.7, ls=":")
        nyq.plot([-1], [0], "x", color=UNSTABLE_COLOUR, ms=9, mew=2)
        nyq.set_xlim(-3.0, 1.0)
        nyq.set_ylim(-2.0, 2.0)
        nyq.set_aspect("equal", adjustable="box")
        label = controller_label(kind)
        mag.set_title(f"{label}: |L(j omega)|", fontsize="medium")
        ph.set_title(f"{label}: arg L(j omega)", fontsize="medium")
        nyq.set_title(f"{label}: Nyquist near -1", fontsize="medium")
        mag.set_ylabel("|L| [dB]")
        ph.set_ylabel("arg L [deg]")
        nyq.set_ylabel("Im L")
        nyq.set_xlabel("Re L")
        for ax in (mag, ph):
            ax.set_xlim(w_lo, w_hi)
            ax.set_xlabel("frequency [rad/s]")
            ax.grid(True, alpha=0.4)
            ax.minorticks_off()   # hundreds of minor log ticks cost time to draw
        nyq.grid(True, alpha=0.4)
        # top right, two lines a loop (|L| falls from the top left); translucent: a resonance
        # peak under it stays visible
        mag.text(0.98, 0.97, "\n".join(notes), transform=mag.transAxes, fontsize="x-small",
                 va="top", ha="right",
                 bbox=dict(facecolor="white", edgecolor="0.8", alpha=0.6, lw=0.5))
    handles.append(_line(color=REFERENCE_COLOUR, lw=3, alpha=0.6,
                         label="margins: phase at the gain crossover, gain at the phase crossover"))
    _legend(fig, handles, top)
    _save(fig, path)
    return ("Open-loop transfer L(j omega), loop broken at the torque (unstable at L = -1), of "
            "each controller on its design model (dashed), on the truth model (solid) and on "
            "the exact beam (dotted, when computed): magnitude and phase with the gain "
            "crossover (dash-dotted) and the margins as bars; Nyquist near -1 with the unit "
            f"circle and the modulus-margin circle. Frequencies {w_lo:.3g} to {w_hi:.3g} "
            "rad/s, from the crossovers and the design plant's modes.")


def plot_loop_axes(result, path: Path) -> str:
    """Draw a three-axis ``loop.png``: per controller, the loop at a time about each hub axis
    (L_i = 1/S_ii - 1, the other two loops closed) as |L_i|, arg L_i and its Nyquist plot near
    -1, and the smallest singular value of the return difference I + L at the plant input;
    returns its caption."""
    import controllers

    from ..design.verdicts import MIN_MODULUS_MARGIN

    kinds = list(dict.fromkeys(r["controller"] for r in result.data["closed_loops"]))
    w_lo, w_hi = loop_band(result)
    n = len(kinds)
    height = 3.6 * n + 1.0
    top = 1.0 - 0.8 / height
    fig, axes = _figure(n, 4, (21.0, height), top=top, wspace=0.3, left=0.05)
    handles = []
    circle = np.exp(1j * np.linspace(0, 2 * np.pi, 200))
    for i, kind in enumerate(kinds):
        mag, ph, nyq, sv = axes[i]
        notes = []
        lowest = math.inf
        for row in _rows(result, kind):
            variant = row["design"]
            d = result.designs[variant]
            K = d["controllers"][kind]
            for which, plant, style in (("design", d["plant"], DESIGN_STYLE),
                                        ("truth", result.truth["verdict"], TRUTH_STYLE)):
                with np.errstate(all="ignore"):
                    omega, L = controllers.loop_frequency_response(plant, K)
                    keep = (omega >= w_lo) & (omega <= w_hi)
                    omega, L = omega[keep], np.asarray(L)[keep]
                    R = np.eye(3) + L
                    S = np.linalg.solve(R, np.broadcast_to(np.eye(3), R.shape))
                    loops = 1.0 / np.diagonal(S, axis1=1, axis2=2) - 1.0
                    sigma = np.linalg.svd(R, compute_uv=False)[:, -1]
                if omega.size < 2:
                    continue
                where = f"{design_label(variant)}, on the {which} model"
                for a, L_a in zip(_AXES, loops.T):
                    c = AXIS_COLOURS[a]
                    handles += mag.semilogx(omega, 20 * np.log10(np.abs(L_a)), style, color=c,
                                            lw=1.1,
                                            label=f"about {a}, loop at a time ({which} model)")
                    ph.semilogx(omega, _wrapped_phase(L_a), style, color=c, lw=1.1)
                    inside = np.abs(L_a + 1.0) < 6.0
                    nyq.plot(np.where(inside, L_a.real, np.nan),
                             np.where(inside, L_a.imag, np.nan), style, color=c, lw=1.1)
                # the axes' colours are the loops' here: the return difference in grey
                colour = (UNSTABLE_COLOUR if which == "truth" and _unstable(row)
                          else "#444444")
                handles += sv.loglog(omega, sigma, style, color=colour, lw=1.2,
                                     label=f"{where}: smallest singular value of I + L")
                lowest = min(lowest, float(np.nanmin(sigma)))
            v = row["verdict"]
            notes.append(f"{design_label(variant)}, on the truth model:\n  disk margin "
                         f"{_num(v.get('disk_margin'), '')} (gain "
                         f"{_num(v.get('disk_gain_margin'), 'dB')}, phase "
                         f"{_num(v.get('disk_phase_margin'), 'deg')}),\n  min sigma(I + L) "
                         f"{_num(v.get('min_singular_value'), '')}")
        mag.axhline(0.0, color=REFERENCE_COLOUR, lw=0.7)
        ph.axhline(-180.0, color=REFERENCE_COLOUR, lw=0.7)
        ph.set_ylim(-270, 90)
        ph.set_yticks([-270, -180, -90, 0, 90])
        nyq.plot(circle.real, circle.imag, color=REFERENCE_COLOUR, lw=0.7, ls=":")
        nyq.plot([-1], [0], "x", color=UNSTABLE_COLOUR, ms=9, mew=2)
        nyq.set_xlim(-3.0, 1.0)
        nyq.set_ylim(-2.0, 2.0)
        nyq.set_aspect("equal", adjustable="box")
        handles.append(sv.axhline(MIN_MODULUS_MARGIN, color=CAUTION_COLOUR, lw=0.8, ls="--",
                                  label=f"{MIN_MODULUS_MARGIN:g}: below it the loop is warned "
                                        "about"))
        if math.isfinite(lowest):
            sv.set_ylim(bottom=min(0.5 * MIN_MODULUS_MARGIN, 0.5 * lowest))
        label = controller_label(kind)
        mag.set_title(f"{label}: |L_i(j omega)|, each axis' loop at a time", fontsize="medium")
        ph.set_title(f"{label}: arg L_i(j omega)", fontsize="medium")
        nyq.set_title(f"{label}: Nyquist of L_i near -1", fontsize="medium")
        sv.set_title(f"{label}: return difference", fontsize="medium")
        mag.set_ylabel("|L_i| [dB]")
        ph.set_ylabel("arg L_i [deg]")
        nyq.set_ylabel("Im L_i")
        nyq.set_xlabel("Re L_i")
        sv.set_ylabel("min singular value of I + L [-]")
        for ax in (mag, ph, sv):
            ax.set_xlim(w_lo, w_hi)
            ax.set_xlabel("frequency [rad/s]")
            ax.grid(True, alpha=0.4)
            ax.minorticks_off()
        nyq.grid(True, alpha=0.4)
        sv.text(0.98, 0.97, "\n".join(notes), transform=sv.transAxes, fontsize="x-small",
                va="top", ha="right",
                bbox=dict(facecolor="white", edgecolor="0.8", alpha=0.6, lw=0.5))
    _legend(fig, handles, top)
    _save(fig, path)
    return ("Each three-axis loop broken at one torque input at a time, the other two closed "
            "(L_i = 1/S_ii - 1, unstable at -1; x blue, y orange, z green): magnitude, phase "
            "and Nyquist near -1, on the design model (dashed) and the truth model (solid); "
            "right, the smallest singular value of the return difference I + L(j omega) at "
            "the plant input (its minimum is the multivariable modulus margin; a perturbation "
            "of every torque at once smaller than it keeps the loop stable). Frequencies "
            f"{w_lo:.3g} to {w_hi:.3g} rad/s.")


def _num(value, unit: str) -> str:
    if value is None:
        return "n/a"
    if not math.isfinite(value):
        return "inf"
    return f"{value:.3g}{(' ' + unit) if unit else ''}"


# ---------------------------------------------------------------------------------------------
# closed-loop poles
# ---------------------------------------------------------------------------------------------
_DAMPING_LINES = (0.05, 0.2, 0.4, 0.7)


def plot_poles(result, path: Path) -> str:
    """Draw ``poles.png``; returns its caption."""
    from ..design.verdicts import MIN_DAMPING

    kinds = list(dict.fromkeys(k[1] for k in result.poles))
    n = len(kinds)
    height = 8.2
    top = 1.0 - 0.9 / height
    fig, axes = _figure(2, n, (6.4 * n + 0.6, height), top=top, hspace=0.35)
    handles = []
    for col, kind in enumerate(kinds):
        near, spread = axes[0, col], axes[1, col]
        rows = {r["design"]: r for r in _rows(result, kind)}
        scale = max([w for r in rows.values() for source in (r["design_margins"], r["verdict"])
                     for w in crossover_frequencies(source)], default=0.0)
        if scale == 0.0:
            spec = result.scene.controller
            scale = (spec.pd.natural_frequency if spec.pd is not None
                     and spec.pd.natural_frequency else 1.0)
        radius = 4.0 * scale
        # and the first flexible mode beyond, where spillover shows first
        above = [abs(z) for s_ in result.poles.values() for z in np.asarray(s_)
                 if abs(z) > 1.5 * scale]
        if above:
            radius = max(radius, 1.3 * min(above))
        for (variant, k, which), s in result.poles.items():
            if k != kind:
                continue
            s = np.asarray(s, dtype=complex)
            marker = "o" if which == "truth" else "x"
            colour = variant_colour(variant)
            w = np.abs(s)
            zeta = np.where(w > 0, -s.real / np.where(w > 0, w, 1.0), 0.0)
            growing = s.real > 1e-10 * np.maximum(1.0, w)
            # the colour set explicitly (a marker-only line otherwise takes the next colour
            # of the axes' cycle as its own, which says nothing and may even be red)
            style = dict(marker=marker, ls="none", ms=6 if which == "truth" else 7,
                         color=colour, mfc="none" if which == "truth" else colour, mec=colour,
                         mew=1.3)
            label = f"{design_label(variant)}: poles of the loop on the {which} model"
            sel = (w <= radius) & ~growing
            handles += near.plot(s.real[sel], s.imag[sel], label=label, **style)
            spread.semilogx(w[~growing & (w > 0)], zeta[~growing & (w > 0)], **style)
            if growing.any():
                bad = dict(style, color=UNSTABLE_COLOUR, mfc=UNSTABLE_COLOUR,
                           mec=UNSTABLE_COLOUR, ms=8)
                handles += near.plot(s.real[growing & (w <= radius)],
                                     s.imag[growing & (w <= radius)],
                                     label="unstable poles (Re s > 0)", **bad)
                spread.semilogx(w[growing], zeta[growing], **bad)
                for z in s[growing & (s.imag >= 0)][:3]:
                    target = near if abs(z) <= radius else spread
                    xy = (z.real, z.imag) if target is near else (abs(z), -z.real / abs(z))
                    target.annotate(f"unstable: {abs(z):.3g} rad/s, zeta {-z.real / abs(z):.2g}",
                                    xy=xy, xytext=(8, 8), textcoords="offset points",
                                    color=UNSTABLE_COLOUR, fontsize="x-small")
        # damping lines: rays s = w (-zeta + j sqrt(1 - zeta^2))
        for k, zeta in enumerate(_DAMPING_LINES):
            x, y = -zeta * radius, math.sqrt(1 - zeta * zeta) * radius
            near.plot([0, x], [0, y], color=REFERENCE_COLOUR, lw=0.5, ls=":")
            near.plot([0, x], [0, -y], color=REFERENCE_COLOUR, lw=0.5, ls=":")
            # labels at decreasing radii: the light-damping rays are nearly vertical, and
            # labels at their ends would overlap
            f = 0.95 - 0.17 * k
            near.text(f * x, f * y, f"zeta {zeta:g} ", fontsize="x-small",
                      color=REFERENCE_COLOUR, ha="right", va="center", rotation=0)
        near.axvspan(0, radius * 0.25, color=UNSTABLE_COLOUR, alpha=0.06, lw=0)
        near.axvline(0, color=REFERENCE_COLOUR, lw=0.7)
        near.set_xlim(-1.05 * radius, 0.25 * radius)
        near.set_ylim(-1.05 * radius, 1.05 * radius)
        near.set_aspect("equal", adjustable="box")
        near.set_title(f"{controller_label(kind)}: closed-loop poles near the bandwidth "
                       f"(|s| <= {radius:.3g} rad/s; dotted: damping ratio)", fontsize="small")
        near.set_xlabel("Re s [1/s]")
        near.set_ylabel("Im s [rad/s]")
        spread.axhspan(-1.0, 0.0, color=UNSTABLE_COLOUR, alpha=0.06, lw=0)
        spread.axhline(0.0, color=REFERENCE_COLOUR, lw=0.7)
        if col == 0:
            handles.append(spread.axhline(MIN_DAMPING, color=CAUTION_COLOUR, lw=0.8, ls="--",
                                          label=f"light damping (zeta {MIN_DAMPING:g}): "
                                                "a pole below is warned about"))
        else:
            spread.axhline(MIN_DAMPING, color=CAUTION_COLOUR, lw=0.8, ls="--")
        spread.set_yscale("symlog", linthresh=1e-3)
        spread.set_ylim(-1.0, 1.05)
        spread.set_xlabel("natural frequency |s| [rad/s]")
        spread.set_ylabel("damping ratio zeta [-]")
        spread.set_title(f"{controller_label(kind)}: every closed-loop pole", fontsize="small")
        for ax in (near, spread):
            ax.grid(True, alpha=0.4)
    _legend(fig, handles, top)
    _save(fig, path)
    return ("Closed-loop poles of each controller on its design model (crosses) and on the "
            "truth model (circles), one colour per design model: top, the s-plane near the "
            "loop's bandwidth with lines of constant damping ratio; bottom, damping ratio "
            "against natural frequency of every pole (symmetric log scale below 1e-3), the "
            "light-damping threshold dashed orange. Unstable poles red; the unstable region "
            "shaded.")


# ---------------------------------------------------------------------------------------------
# W(s) of the appendages
# ---------------------------------------------------------------------------------------------
def plot_W(result, path: Path, stats, exact: bool) -> str:
    """Draw ``W.png``; returns its caption."""
    scene = result.scene
    groups: list = []     # (appendage names, spec) of distinct appendages
    for a in scene.appendages:
        key = (a.beam, a.chain, a.truth_chain, a.fit, a.truth, a.design)
        for g in groups:
            if g[1] == key:
                g[0].append(a.name)
                break
        else:
            groups.append(([a.name], key, a))
    groups = groups[:_MAX_TIP_PANELS]
    panels = _W_PANELS["three_axis" if scene.three_axis else "planar"]
    height = 3.1 * len(groups) + 1.2
    top = 1.0 - 0.9 / height
    fig, axes = _figure(len(groups), len(panels), (5.3 * len(panels) + 0.1, height), top=top,
                        wspace=0.25, left=0.06)
    handles = []
    notes = []
    loop_band_top = result.data.get("truth", {}).get("loop_band")
    resolved = result.data.get("truth", {}).get("resolved", {})
    for g, (names, _, a) in enumerate(groups):
        models = result.models[a.name]
        curves = []
        if "beam" in models and a.truth == "beam" and exact:
            curves.append(("exact beam", models["beam"], "-", EXACT_COLOUR, 1.6))
            stats.exact_reference_evaluations += 1
        truth = models["truth"]
        truth_name = _model_name(truth, scene.three_axis)
        curves.append((f"truth model: {truth_name}", truth, "--", "#7f7f7f", 1.4))
        for variant, d in result.designs.items():
            model = d["appendages"][a.name]
            if model is truth:
                continue
            label = f"{design_label(variant)}: {_model_name(model, scene.three_axis)}"
            if any(c[1] is model for c in curves):
                continue
            curves.append((label, model, "-.", variant_colour(variant), 1.2))
        w_first = []
        for _, model, *_ in curves:
            try:
                p = np.asarray(model.poles(), dtype=float)
                if p.size:
                    w_first.append(float(p[0]))
            except (AttributeError, ValueError):
                pass
        w1 = min(w_first) if w_first else 1.0
        w_lo, w_hi = w1 / 30.0, w1 * 30.0
        res = resolved.get(a.name)
        if res is not None:
            w_hi = max(w_hi, 3.0 * res["frequency"])
        omega = np.geomspace(w_lo, w_hi, 1200)
        s = 1j * omega
        for label, model, style, colour, lw in curves:
            with np.errstate(all="ignore"):
                W = np.asarray(model.W6(s) if scene.three_axis else model.W(s))
            for c, ((i, j), _) in enumerate(panels):
                ax = axes[g, c]
                handles += ax.loglog(omega, np.abs(W[:, i, j]), style, color=colour, lw=lw,
                                     label=label)
        for c, (_, title) in enumerate(panels):
            ax = axes[g, c]
            ax.set_title(f"{', '.join(names)}: {title}", fontsize="small")
            ax.grid(True, alpha=0.4)
            ax.minorticks_off()
            ax.set_xlim(w_lo, w_hi)
            ax.set_xlabel("frequency [rad/s]")
            if res is not None and res["frequency"] < w_hi:
                ax.axvspan(res["frequency"], w_hi, color="0.85", alpha=0.5, lw=0)
            if loop_band_top is not None and w_lo < loop_band_top < w_hi:
                ax.axvline(loop_band_top, color=REFERENCE_COLOUR, lw=0.8, ls="-.")
        notes.append(_truncation_note(names, a, models, res, loop_band_top))
    handles.append(_line(color="0.85", lw=6, alpha=0.5,
                         label="beyond the truth model's resolution"))
    if loop_band_top is not None:
        handles.append(_line(color=REFERENCE_COLOUR, lw=0.8, ls="-.",
                             label="top of the loops' band (bandwidth_factor x crossover)"))
    _legend(fig, handles, top)
    _save(fig, path)
    what = ("the diagonal of W6: bending in the appendage's x-y and x-z planes, torsion and "
            "axial motion" if scene.three_axis else "W1, W2 = W3 and W4")
    return (f"W(s) of each appendage at its attachment end (free appendage, rigid-body term "
            f"included): magnitudes of {what} of the exact distributed beam (when asked), the "
            "truth model and the design chains; the phase of these lightly damped models is 0 "
            "or 180 deg between resonances and anti-resonances (the loop's phase is in the loop "
            "plot). " + " ".join(n for n in notes if n))


#: The panels of W.png: (entry of W or W6, title), planar and three-axis.
_W_PANELS = {
    "planar": (((0, 0), "W1 = delta / F_y [m/N]"), ((0, 1), "W2 = W3 = delta / M [1/N]"),
               ((1, 1), "W4 = phi / M [1/(N m)]")),
    "three_axis": (((1, 1), "v / F_y: bending in x-y [m/N]"),
                   ((2, 2), "w / F_z: bending in x-z [m/N]"),
                   ((3, 3), "theta_x / M_x: torsion [1/(N m)]"),
                   ((0, 0), "u / F_x: axial [m/N]")),
}


def _model_name(model, three_axis: bool = False) -> str:
    name = type(model).__name__
    if hasattr(model, "n_modes"):
        method = getattr(model, "method", None)
        n = model.n_modes
        if three_axis:
            try:
                n = sum(model.modes_per_motion.values())   # every motion's, not x-y's
            except (AttributeError, ValueError):
                pass   # a beam whose motions couple: its n_modes lowest coupled modes
        return f"beam, {plural(n, (method + ' mode') if method else 'mode')}"
    if hasattr(model, "n_bodies"):
        return f"{model.n_bodies}-body chain"
    return name


def _truncation_note(names, a, models, res, band) -> str:
    """Why the truth model's W departs from the exact beam's, with the numbers."""
    if res is None or "beam" not in models:
        return ""
    beam, truth = models["beam"], models["truth"]
    try:
        exact_w = np.asarray(beam.natural_frequencies(3), dtype=float)
        truth_w = np.asarray(truth.poles(), dtype=float)[:3]
    except (AttributeError, ValueError):
        return ""
    text = (f"{', '.join(names)}: the truth model ({res['model']}) represents the beam up to "
            f"about {res['frequency']:.3g} rad/s (shaded beyond); its free-free resonances "
            + ", ".join(f"{w:.3g}" for w in truth_w) + " rad/s against the exact beam's "
            + ", ".join(f"{w:.3g}" for w in exact_w) + " rad/s")
    if band is not None:
        text += (f"; the loops act below {band:.3g} rad/s, "
                 + ("inside the resolved band." if band <= res["frequency"] else
                    "beyond it, where one more mode changes the closed loops by less than "
                    "the tolerance." if res.get("covers_loops") else
                    "BEYOND the resolved band: raise fidelity.n_modes."))
    return text


def draw(result, folder: Path, wanted, stats, *, exact: bool) -> list:
    """Draw the plots asked for into ``folder``; returns ``[(path, caption)]``."""
    out = []
    three_axis = result.scene.three_axis
    if "slew" in wanted and result.responses:
        if three_axis:   # one figure per controller: a column per hub axis
            for kind in dict.fromkeys(k[1] for k in result.responses):
                path = folder / f"slew_{kind}.png"
                out.append((path, plot_slew_axes(result, path, kind)))
        else:
            path = folder / PLOT_FILES["slew"]
            out.append((path, plot_slew(result, path)))
    if "loop" in wanted and result.data.get("closed_loops"):
        path = folder / PLOT_FILES["loop"]
        out.append((path, (plot_loop_axes if three_axis else plot_loop)(result, path)))
    if "poles" in wanted and result.poles:
        path = folder / PLOT_FILES["poles"]
        out.append((path, plot_poles(result, path)))
    if "W" in wanted and result.models:
        path = folder / PLOT_FILES["W"]
        out.append((path, plot_W(result, path, stats, exact)))
    if "profile" in wanted and result.scene.manoeuvre is not None and result.designs:
        path = folder / PLOT_FILES["profile"]
        out.append((path, plot_profile(result, path)))
    if "wheels" in wanted and (_wheel_runs(result) or _basilisk_wheels(result)):
        path = folder / PLOT_FILES["wheels"]
        out.append((path, plot_wheels(result, path)))
    stats.plots += len(out)
    return out


# ---------------------------------------------------------------------------------------------
# the manoeuvre as flown: the profile and the wheels
# ---------------------------------------------------------------------------------------------
def plot_profile(result, path: Path) -> str:
    """Draw ``profile.png``; returns its caption."""
    from ..design.manoeuvre import build_profile

    scene = result.scene
    m = scene.manoeuvre
    t = np.linspace(0.0, m.duration, 4001)
    fig, axes = _figure(3, 1, (7.4, 7.6), top=0.86, left=0.12)
    handles: list = []
    end = None
    for variant, d in result.designs.items():
        profile, facts = build_profile(scene, d["plant"], variant)
        colour = variant_colour(variant)
        end = profile.end_time
        label = design_label(variant)
        # three axes: the angle and rate along the eigen-axis, the torque per hub axis (the axes'
        # colours; the path in the design model's colour unless it is one of them)
        if profile.axis is not None and len(result.designs) == 1:
            colour = "black"
        handles += axes[0, 0].plot(t, np.degrees(profile.path(t)), color=colour,
                                   lw=1.3, label=f"profile for {label}")
        axes[1, 0].plot(t, np.degrees(profile.path(t, 1)), color=colour, lw=1.3)
        torque = profile.torque_ff(t, facts["inertia"], **(
            {} if profile.axis is None else {"gyroscopic": False}))
        if profile.axis is None:
            axes[2, 0].plot(t, torque, color=colour, lw=1.3)
        else:
            style = "-" if variant == next(iter(result.designs)) else "--"
            for i, (axis, axis_colour) in enumerate(AXIS_COLOURS.items()):
                line = axes[2, 0].plot(t, torque[i], style, color=axis_colour, lw=1.3,
                                       label=f"about hub {axis}")
                if style == "-":
                    handles += line
        if profile.shaper is not None:
            for time in profile.shaper.times:
                axes[2, 0].axvline(time, color=colour, lw=0.6, ls=":")
    limits = [(1, None if m.rate_limit is None else math.degrees(m.rate_limit), "rate limit"),
              (2, m.torque_limit, "torque limit")]
    for row, value, text in limits:
        if value is not None:
            for sign in (1.0, -1.0):
                line = axes[row, 0].axhline(sign * value, color=CAUTION_COLOUR, lw=0.9, ls="--",
                                            label=f"the profile's {text}s")
            handles.append(line)
    for ax in axes[:, 0]:
        if end is not None:
            handles.append(ax.axvline(end, color=REFERENCE_COLOUR, lw=0.6, ls="--",
                                      label="end of the profile"))
        ax.grid(True, alpha=0.4)
        ax.tick_params(labelsize="small")
    three = m.slew_axis is not None
    axes[0, 0].set_ylabel("angle about the slew axis [deg]" if three else "theta_ref [deg]",
                          fontsize="small")
    axes[1, 0].set_ylabel("rate about the slew axis [deg/s]" if three
                          else "omega_ref [deg/s]", fontsize="small")
    axes[2, 0].set_ylabel("J alpha_ref [N m]", fontsize="small")
    axes[2, 0].set_xlabel("time [s]")
    kinds = {"step": "the step reference (the cycloid of theta_ref alone)",
             "bang-coast-bang": "a bang-coast-bang profile", "smooth": "a jerk-limited profile",
             "shaped": f"a {m.shaper.kind.upper()}-shaped {m.shaper.base} profile"
             if m.shaper is not None else "a shaped profile"}
    axes[0, 0].set_title(f"{kinds[m.profile]} of {math.degrees(m.slew_angle):g} deg in "
                         f"{m.slew_time:g} s", fontsize="medium")
    _legend(fig, handles)
    _save(fig, path)
    caption = (f"The reference profile ({kinds[m.profile]}) for the controllers tuned on each "
               "design model: theta_ref, omega_ref and the feedforward torque J alpha_ref (J "
               "the design model's rigid-body inertia)")
    if three:
        caption = (f"The reference profile ({kinds[m.profile]}, an eigen-axis slew about ("
                   + ", ".join(f"{e:.3g}" for e in m.slew_axis) + ") in hub axes) for the "
                   "controllers tuned on each design model: the angle s and the rate s' about "
                   "the slew axis (theta_ref = e s, omega_ref = e s') and the feedforward "
                   "torque J e s'' about each hub axis (J the design model's inertia tensor; "
                   "the gyroscopic term, absent from the linear plants, is not fed)")
    if m.shaper is not None:
        caption += "; dotted: the shaper's impulses"
    caption += ("; dashed orange: the profile's limits" if any(v is not None for _, v, _ in
                                                               limits) else "")
    if not m.feedforward:
        caption += (". The controllers read theta_ref only (manoeuvre.feedforward = false): "
                    "omega_ref and the torque are the profile's, not fed")
    return caption + "."


def _wheel_runs(result) -> list:
    """(key, response) of the loops flown through flexsat's wheels."""
    return [(key, r) for key, r in result.responses.items()
            if any(name.endswith("_momentum_saturated") for name in r.output_labels)]


def _basilisk_wheels(result) -> dict:
    """kind -> (t, torque applied, torque command, momentum, limits) of Basilisk's wheel runs:
    its speed times the spin inertia, the command clipped to the torque limit (and held at
    zero where the wheel is at its speed limit and the command drives it further), as
    Basilisk's reactionWheelStateEffector applies it."""
    wheel = result.scene.simulator.reaction_wheel
    out = {}
    if wheel is None:
        return out
    for kind, comparison in result.basilisk.items():
        resp = comparison.basilisk.response
        speed, command = trace(resp, "wheel_speed"), trace(resp, "torque")
        if speed is None or command is None:
            continue
        applied = (command if wheel.max_torque is None
                   else np.clip(command, -wheel.max_torque, wheel.max_torque))
        if wheel.max_speed is not None:
            # the wheel's momentum changes at minus the hub torque: a command that would spin
            # it beyond its limit (command x speed < 0) is not applied
            held = (np.abs(speed) >= wheel.max_speed * (1 - 1e-9)) & (command * speed < 0)
            applied = np.where(held, 0.0, applied)
        out[kind] = (np.asarray(resp.t, float).reshape(-1), applied, command,
                     wheel.spin_inertia * speed,
                     (wheel.max_torque, None if wheel.max_speed is None
                      else wheel.spin_inertia * wheel.max_speed))
    return out


def plot_wheels(result, path: Path) -> str:
    """Draw ``wheels.png``; returns its caption."""
    runs = _wheel_runs(result)
    basilisk = _basilisk_wheels(result)
    kinds = list(dict.fromkeys([k[1] for k, _ in runs] + list(basilisk)))
    spec = (result.data.get("manoeuvre") or {}).get("wheels") or {}
    names = spec.get("names", ["wheel"] if runs else [])
    n_cols = len(kinds)
    fig, axes = _figure(2, n_cols, (6.2 * n_cols + 0.6, 6.4), top=0.86,
                        left=0.1 if n_cols == 1 else 0.07)
    handles: list = []
    for col, kind in enumerate(kinds):
        ax_t, ax_h = axes[0, col], axes[1, col]
        for (variant, k, which), resp in runs:
            if k != kind:
                continue
            t = np.asarray(resp.t, float).reshape(-1)
            style = TRUTH_STYLE if which == "truth" else DESIGN_STYLE
            colour = variant_colour(variant)
            for w, name in enumerate(names):
                if len(names) > 1:
                    # a set of wheels: a colour per wheel (the design models by line style)
                    # (the legend names the wheels; the caption the line styles)
                    colour = WHEEL_COLOURS[w % len(WHEEL_COLOURS)]
                    label = ("_design" if which != "truth" else f"{name}" + (
                        f" ({design_label(variant)})" if len(result.designs) > 1 else ""))
                else:
                    label = f"{design_label(variant)}: loop on the {which} model"
                handles += ax_t.plot(*envelope(t, trace(resp, f"{name}_torque")), style,
                                     color=colour, lw=1.2, label=label)
                ax_h.plot(*envelope(t, trace(resp, f"{name}_momentum")), style, color=colour,
                          lw=1.2)
                if which == "truth":
                    command = trace(resp, f"{name}_torque_command")
                    handles += ax_t.plot(*envelope(t, command), "-", color=colour, lw=0.6,
                                         alpha=0.5, label="the controller's command (truth)")
                    flag = (trace(resp, f"{name}_torque_saturated")
                            + trace(resp, f"{name}_momentum_saturated")) > 0
                    for ax in (ax_t, ax_h):
                        if flag.any():
                            handles.append(ax.fill_between(
                                t, 0, 1, where=flag, transform=ax.get_xaxis_transform(),
                                color=CAUTION_COLOUR, alpha=0.15, lw=0,
                                label="a limit acts (truth model)"))
        if kind in basilisk:
            t, applied, command, momentum, _ = basilisk[kind]
            handles += ax_t.plot(*envelope(t, applied), BASILISK_STYLE, color=BASILISK_COLOUR,
                                 lw=1.4, label="Basilisk's wheel (design chains, nonlinear)")
            ax_h.plot(*envelope(t, momentum), BASILISK_STYLE, color=BASILISK_COLOUR, lw=1.4)
        limits = [(spec.get("torque_limits") or [None])[0],
                  (spec.get("momentum_limits") or [None])[0]]
        if kind in basilisk and not runs:
            limits = list(basilisk[kind][4])
        for ax, value in zip((ax_t, ax_h), limits):
            if value is not None and math.isfinite(value):
                for sign in (1.0, -1.0):
                    line = ax.axhline(sign * value, color=UNSTABLE_COLOUR, lw=0.9, ls="--",
                                      label="the wheel's limits")
                handles.append(line)
            ax.grid(True, alpha=0.4)
            ax.tick_params(labelsize="small")
        saturated = [r for r in _rows(result, kind) if (r.get("wheels") or {}).get("truth", {})
                     .get("saturated")]
        in_basilisk = (((result.data.get("basilisk") or {}).get(kind) or {}).get("wheel")
                       or {}).get("saturated", False)
        said = ("a wheel SATURATES on the truth model" if saturated else
                "Basilisk's wheel SATURATES" if in_basilisk else
                "the wheels stay within their limits")
        ax_t.set_title(f"{controller_label(kind)}: {said}", fontsize="medium",
                       color=CAUTION_COLOUR if saturated or in_basilisk else "black")
        ax_t.set_ylabel("wheel torque on the hub [N m]", fontsize="small")
        ax_h.set_ylabel("wheel momentum J_s Omega [N m s]", fontsize="small")
        ax_h.set_xlabel("time [s]")
    _legend(fig, handles)
    _save(fig, path)
    caption = ("Reaction wheels: the torque each applies to the hub (thin: the controller's "
               "command, on the truth model) and its momentum, against the wheel's limits "
               "(dashed red); shaded: a limit acts on the truth model")
    if basilisk:
        caption += ("; dotted black: Basilisk's wheel (its speed times the spin inertia; the "
                    "command clipped to the torque limit as Basilisk applies it)")
    return caption + ". Solid: loop on the truth model, dashed: on the design model."
