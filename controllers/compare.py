"""One-call comparison of a controller on its design plant and on a truth plant.

Typical use: a controller tuned on hub + chain (the design plant) is closed around hub + beam
with many modes (the truth plant); :func:`compare` returns the metrics of both loops side by
side, both slew responses and their difference, the spillover verdict on the truth plant, and
plots.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import Sequence

import control
import numpy as np

from .loop import close_loop, loop_frequency_response
from .margins import SpilloverVerdict, margins, spillover
from .signals import (THETA, TORQUE, check_controller, check_plant, channels,
                      tip_outputs)
from .timeresp import METRIC_UNITS, check_slew, metrics, signal_trace, slew, time_grid

__all__ = ["Comparison", "compare", "metric_table", "difference_columns"]


def difference_columns(actual, expected) -> tuple[float | None, float | None]:
    """(|actual - expected|, |actual - expected| / |expected|) with inf handled, never NaN.

    Equal values (including equal infinities) differ by 0; a finite value against an infinite
    one differs by inf; the relative difference against expected = 0 is inf unless both are 0.
    A flag (bool) or a missing value (None, e.g. the metrics of a diverged response) has no
    difference: (None, None).
    """
    if any(v is None or isinstance(v, bool) for v in (actual, expected)):
        return None, None
    if actual == expected:
        return 0.0, 0.0
    if not (math.isfinite(actual) and math.isfinite(expected)):
        return math.inf, math.inf
    diff = abs(actual - expected)
    return diff, (diff / abs(expected) if expected != 0 else math.inf)


def _fmt(value) -> str:
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, str):
        return value
    return f"{value:.6g}"


def metric_table(rows: Sequence[Sequence], header: Sequence[str]) -> str:
    """Plain-text table with left-aligned columns (numbers with 6 significant digits)."""
    cells = [[str(h) for h in header]] + [[_fmt(v) for v in row] for row in rows]
    widths = [max(len(r[i]) for r in cells) for i in range(len(header))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in cells]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


@dataclass
class Comparison:
    """Result of :func:`compare`.

    Attributes
    ----------
    design_metrics, truth_metrics : dict of str to float, bool or None
        :func:`controllers.metrics` of the slew plus the margins (``gain_margin`` [dB],
        ``phase_margin`` [deg], ``modulus_margin``) of each loop. A loop whose response left
        the float64 range has ``diverged`` True, ``diverged_at`` [s] and None for the time
        metrics (:func:`controllers.metrics`).
    design_response, truth_response : control.TimeResponseData
        Slew responses on the same time grid; a diverged one stops at ``diverged_at``.
    difference : dict of str to ndarray
        truth - design for every output both loops have (theta, omega, torque, tip
        deflections), over the time both responses cover.
    verdict : SpilloverVerdict
        Stability of the controller on the truth plant.
    design_plant, truth_plant, controller
        What was compared (kept for :meth:`plot`).
    """

    design_metrics: dict[str, float]
    truth_metrics: dict[str, float]
    design_response: control.TimeResponseData
    truth_response: control.TimeResponseData
    difference: dict[str, np.ndarray]
    verdict: SpilloverVerdict
    design_plant: object = field(repr=False)
    truth_plant: object = field(repr=False)
    controller: control.StateSpace = field(repr=False)

    @property
    def t(self) -> np.ndarray:
        """Time grid of ``difference`` [s] (both responses; a diverged one ends earlier)."""
        t = np.asarray(self.design_response.t, dtype=float).reshape(-1)
        return t[: len(next(iter(self.difference.values()), t))]

    @property
    def diverged(self) -> bool:
        """True if either loop's response left the float64 range (see ``diverged_at``)."""
        return bool(self.design_metrics.get("diverged") or self.truth_metrics.get("diverged"))

    @property
    def rows(self) -> list[tuple[str, str, float, float, float, float]]:
        """(metric, unit, design, truth, |truth - design|, relative difference) per metric.

        Every metric of either loop, in the design loop's order (``diverged_at`` exists only for
        a loop that diverged; the other side shows None there)."""
        names = list(self.design_metrics) + [n for n in self.truth_metrics
                                             if n not in self.design_metrics]
        names = [n for n in names if n != "diverged_at"] + (
            ["diverged_at"] if self.diverged else [])
        out = []
        for name in names:
            d, t = self.design_metrics.get(name), self.truth_metrics.get(name)
            out.append((name, METRIC_UNITS.get(name, ""), d, t, *difference_columns(t, d)))
        return out

    @property
    def peak_difference(self) -> dict[str, float]:
        """max |truth - design| of each common output over the time both responses cover."""
        return {name: float(np.max(np.abs(v))) for name, v in self.difference.items()}

    def table(self) -> str:
        """The metrics table (design vs truth, absolute and relative difference)."""
        return metric_table(self.rows, ("metric", "unit", "design", "truth", "abs diff",
                                        "rel diff"))

    def __str__(self) -> str:
        peaks = ", ".join(f"{k} {v:.3g}" for k, v in self.peak_difference.items())
        lines = [self.table(), f"peak |truth - design|: {peaks}"]
        for which, m in (("design", self.design_metrics), ("truth", self.truth_metrics)):
            if m.get("diverged"):
                lines.append(f"the {which} loop's response DIVERGED at {m['diverged_at']:.6g} s "
                             "(left the float64 range; its time metrics are not given)")
        return "\n".join(lines + [str(self.verdict)])

    def plot(self, path=None):
        """Figure of both slew responses, their difference and both open-loop responses.

        Parameters
        ----------
        path : str or os.PathLike, optional
            Save the figure there (PNG, PDF, SVG... by the suffix) and return the path.

        Returns
        -------
        matplotlib.figure.Figure or pathlib.Path
            The figure (on the Agg canvas: no display needed; ``fig.savefig(...)`` saves it,
            and in a notebook it shows itself), or the path it was saved to. Left: theta (with
            theta_ref), torque, tip deflection (or omega); right: |L(j omega)| [dB] and arg L
            [deg] (wrapped into (-270, 90]) of both loops over the frequencies that matter (a
            decade and a half below the gain crossover to a decade above the fastest plant or
            controller pole), theta_truth - theta_design.
        """
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        fig = Figure(figsize=(12, 9), layout="constrained")
        FigureCanvasAgg(fig)
        axes = fig.subplots(3, 2)
        t = self.t
        ch = channels(self.controller, "controller")
        third = tip_outputs(self.difference)[:3] or list(ch.omegas)
        units = {THETA: "rad", TORQUE: "N*m", "omega": "rad/s"}
        for ax, (kind, names) in zip(axes[:, 0], ((THETA, ch.thetas), (TORQUE, ch.torques),
                                                   (third[0], third))):
            for name in names:
                for label, resp, style in (("design", self.design_response, "-"),
                                           ("truth", self.truth_response, "--")):
                    y = signal_trace(resp, name)
                    if y is not None:
                        stop = getattr(resp, "diverged_at", None)
                        ax.plot(np.asarray(resp.t).reshape(-1), y, style,
                                label=f"{name} ({label})" + (f", diverged at {stop:.4g} s"
                                                             if stop is not None else ""))
            if kind == THETA:
                for ref_name in ch.refs:
                    ref = signal_trace(self.design_response, ref_name, "input")
                    if ref is not None:
                        ax.plot(np.asarray(self.design_response.t).reshape(-1), ref, ":",
                                color="gray", label=ref_name)
            name = kind if kind in (THETA, TORQUE) else (
                "omega" if kind in ch.omegas else kind)
            ax.set_ylabel(f"{name} [{units.get(name, 'm')}]")
            ax.legend(loc="best", fontsize="small")
            ax.grid(True)
        axes[-1, 0].set_xlabel("time [s]")
        band = []
        for label, plant, style in (("design", self.design_plant, "-"),
                                    ("truth", self.truth_plant, "--")):
            omega, L = loop_frequency_response(plant, self.controller)
            band.append(_frequency_band(omega, L, plant, self.controller))
            if L.ndim == 3:  # three axes: the diagonal of L
                for i, a in enumerate(ch.axes):
                    axes[0, 1].semilogx(omega, 20 * np.log10(np.abs(L[:, i, i])), style,
                                        label=f"L_{a}{a} ({label})")
                    axes[1, 1].semilogx(omega, _wrapped_degrees(L[:, i, i]),
                                        style, label=f"L_{a}{a} ({label})")
                continue
            axes[0, 1].semilogx(omega, 20 * np.log10(np.abs(L)), style, label=f"L ({label})")
            axes[1, 1].semilogx(omega, _wrapped_degrees(L), style, label=f"L ({label})")
        lo, hi = min(b[0] for b in band), max(b[1] for b in band)
        for ax in axes[:2, 1]:
            ax.set_xlim(lo, hi)
        axes[1, 1].set_ylim(-270.0, 90.0)
        axes[1, 1].set_yticks([-270, -180, -90, 0, 90])
        axes[0, 1].axhline(0.0, color="gray", lw=0.5)
        axes[0, 1].set_ylabel("|L| [dB]")
        axes[1, 1].set_ylabel("arg L [deg]")
        axes[1, 1].set_xlabel("frequency [rad/s]")
        for ax in axes[:2, 1]:
            ax.legend(loc="best", fontsize="small")
            ax.grid(True, which="both")
        for name in ch.thetas:
            axes[2, 1].plot(t, self.difference[name], label=name)
        axes[2, 1].set_ylabel("theta truth - design [rad]")
        axes[2, 1].set_xlabel("time [s]")
        axes[2, 1].grid(True)
        fig.suptitle("design vs truth: " + ("stable" if self.verdict.stable else "UNSTABLE")
                     + " on truth")
        if path is not None:
            from pathlib import Path

            fig.savefig(path)
            return Path(path)
        return fig


def _wrapped_degrees(L: np.ndarray) -> np.ndarray:
    """arg L in (-270, 90] deg (the rigid-body loop's -180 mid-range), NaN where it wraps so
    that no vertical line is drawn across: a lightly damped mode's phase swing stays on the
    axis instead of being unwrapped to thousands of degrees."""
    phase = 90.0 - np.mod(90.0 - np.degrees(np.angle(L)), 360.0)
    phase[1:][np.abs(np.diff(phase)) > 180.0] = np.nan
    return phase


def _frequency_band(omega: np.ndarray, L: np.ndarray, plant, controller) -> tuple[float, float]:
    """[rad/s] from 1/30 of the lowest gain crossover of |L| to 10 x the fastest pole of plant
    and controller, inside the grid of ``omega``."""
    gain = np.abs(L) if L.ndim == 1 else np.abs(np.diagonal(L, axis1=1, axis2=2)).max(axis=1)
    down = np.nonzero((gain[:-1] >= 1.0) & (gain[1:] < 1.0))[0]
    lo = omega[down[0]] / 30.0 if down.size else omega[0]
    poles = np.concatenate([np.linalg.eigvals(np.asarray(m.A, dtype=float)) for m in
                            (plant, controller) if m.nstates and not m.isdtime(strict=True)]
                           or [np.zeros(0)])
    size = np.abs(poles)
    hi = 10.0 * size.max() if size.size and size.max() > 0 else omega[-1]
    return max(lo, omega[0]), min(max(hi, 10.0 * lo), omega[-1])


def compare(design_plant: control.StateSpace, truth_plant: control.StateSpace,
            controller: control.StateSpace, *, angle: float, slew_time: float | None = None,
            t_final: float | None = None, dt: float | None = None,
            max_samples: int | None = None, axis=None,
            duration: float | None = None) -> Comparison:
    """Close one controller around a design plant and a truth plant and compare.

    Parameters
    ----------
    design_plant : control.StateSpace
        Plant the controller was tuned on (e.g. hub + chain).
    truth_plant : control.StateSpace
        High-fidelity plant (e.g. hub + beam with many modes). Both plants need the signals of
        :mod:`controllers.signals`.
    controller : control.StateSpace
        Continuous or digital controller (output ``'torque'``).
    angle : float, rad
        Slew angle.
    slew_time : float, s
        Duration of the slew (cycloidal profile, :func:`controllers.slew_profile`): a scene's
        ``manoeuvre.slew_time``.
    t_final : float, s, optional
        Simulation length (a scene's ``manoeuvre.duration``); default 3 * slew_time.
    dt : float, s, optional
        Output step; default slew_time / 500 (the controller's dt if digital).
    duration : float, s, optional
        Deprecated name of ``slew_time`` (a DeprecationWarning): in a scene ``duration`` is the
        simulated time.

    max_samples : int, optional
        Most samples per response (default :data:`controllers.timeresp.MAX_SAMPLES`); more
        are refused by name before any work.
    axis : {'x', 'y', 'z'} or sequence of 3 floats, optional
        Three-axis plants (required there): the eigen-axis of the slew (:func:`slew`). The
        metrics are then the three-axis ones of :func:`metrics` and the margins those of
        :class:`~controllers.MultiLoopMargins` (per axis, disk margin).

    Returns
    -------
    Comparison
        An unstable truth loop is reported, not raised: ``verdict.stable`` False and, if its
        response leaves the float64 range within t_final, ``truth_metrics["diverged"]`` True
        with ``truth_metrics["diverged_at"]`` [s] and None for its time metrics.
    """
    check_plant(design_plant, "design_plant")
    if isinstance(truth_plant, control.FrequencyResponseData):
        raise TypeError("truth_plant must be a control.StateSpace for time responses; for a "
                        "FrequencyResponseData truth use controllers.spillover / margins")
    check_plant(truth_plant, "truth_plant")
    check_controller(controller)
    if duration is not None:
        if slew_time is not None:
            raise TypeError("give slew_time [s] only (duration is its deprecated name)")
        warnings.warn("compare(duration=...) is the slew time: use slew_time=... (a scene's "
                      "duration is the simulated time, compare's t_final)", DeprecationWarning,
                      stacklevel=2)
        slew_time, keyword = duration, "duration"
    else:
        keyword = "slew_time"
    if slew_time is None:
        raise TypeError("compare() needs slew_time [s], the duration of the slew")
    angle, duration = check_slew(angle, slew_time, keyword)
    design_loop = close_loop(design_plant, controller)
    truth_loop = close_loop(truth_plant, controller)
    # the time grid (and its size limit) first: refuse before any simulation
    time_grid(design_loop, 3.0 * duration if t_final is None else t_final, dt,
              duration / 500.0, max_samples, keyword)
    design_response = slew(design_loop, angle, duration, t_final=t_final, dt=dt,
                           max_samples=max_samples, axis=axis)
    truth_response = slew(truth_loop, angle, duration, t_final=t_final, dt=dt,
                          max_samples=max_samples, axis=axis)
    verdict = spillover(truth_plant, controller)
    design_metrics = metrics(design_response) | margins(design_plant, controller).as_dict()
    truth_metrics = metrics(truth_response) | verdict.margins.as_dict()
    difference = {}
    for name in design_response.output_labels:
        a, b = signal_trace(truth_response, name), signal_trace(design_response, name)
        if a is not None and b is not None:
            n = min(a.size, b.size)  # a diverged response ends early
            difference[name] = a[:n] - b[:n]
    return Comparison(design_metrics, truth_metrics, design_response, truth_response,
                      difference, verdict, design_plant, truth_plant, controller)
