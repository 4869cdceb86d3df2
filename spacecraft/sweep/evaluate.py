"""One sample of a sweep: one design-loop evaluation, as the scene says, reduced to numbers.

A sample is the sweep's scene with the sampled numbers put in (:func:`~.parameters.apply_values`)
and validated by :func:`spacecraft.scene.read.load_scene`. Its evaluation is the runner's design loop
for one controller and one design model, built with the runner's own model builders
(:class:`spacecraft.design.loop._Runner`: beams, truncations, chains, spacecraft, plants, the slew):

1. design (``design = "per-sample"``): the design chain of each beam (the runner's fit:
   :func:`appendages.equivalence.fit_chain` solves the dimensionless fit once per process and
   scales it to each beam, :mod:`appendages.fitting`), its plant, the controller tuned on it as
   the runner tunes it;
   ``design = "nominal"``: the controller tuned once on the nominal scene, held fixed;
2. truth: hub + beams truncated to the nominal scene's ``n_modes`` (fixed for the sweep); the
   closed-loop verdict from its eigenvalues and its gain, phase and modulus margins
   (:func:`controllers.spillover`);
3. the slew on the truth loop (if the scene has a manoeuvre): overshoot, settling time, peak tip
   deflection, peak torque, attitude errors (:func:`controllers.metrics`);
4. the exact distributed beam (if ``outputs.exact_reference``): the loop closed on the exact
   frequency response of hub + beams through W(s) (:meth:`Spacecraft.frequency_response`),
   verdict by the Nyquist criterion and margins (:func:`controllers.spillover` on an FRD).

The exact reference's frequency grid (:func:`exact_grid`, :func:`exact_verdict`) is the
runner's construction (1e-3 to 1e3 times the design bandwidth, 100 points a decade, dense points
across the half-power band of every coupled mode) with three changes that make it affordable per
sample and more accurate: the modes are located on an undamped Craig-Bampton truncation (two
modes more than the cantilever modes below the top of the grid; within 3e-7 of the exact coupled
frequencies) instead of the exact Wittrick-Williams roots; a mode gets 24 points (the runner 60)
and only if the loop feels it (|L| >= 1e-3 there); and the grid is refined where the margins are
attained. The worst case found is checked on the runner's own grid (:mod:`.worst`).

The fidelity (``n_modes`` of the truth model) is chosen once, on the nominal scene, by the
runner's rule, and held: every sample's truth model has as many modes. Where the exact reference
is on, the report gives the largest difference between the truth model's and the exact beam's
modulus margins over the samples, and the number of verdicts they disagree on.

What a sample records, so that every verdict can be read and checked:

* margins signed by the verdict (:func:`signed_margin`): ``|m|`` for a stable loop, ``-|m|`` for
  an unstable one, so that every unstable sample ranks below every stable one in any table,
  plot, ranking or search (a stable loop's gain or phase margin counted by its size, as the
  run's warnings count a conditionally stable loop's negative gain margin);
* ``status``: the slew of the truth loop as the run reports it (:func:`spacecraft.design.verdicts.
  loop_status`: settles, not settled, slew unfinished, unstable, diverges), ``"unstable"`` also
  where the truth loop settles but the exact beam's verdict is unstable; without a manoeuvre
  ``"stable"`` or ``"unstable"``. A slew that does not settle or diverges is a result: its
  settling time (and, for an unstable loop, every time metric) is withheld (null), as the run's
  report withholds it (:func:`spacecraft.design.verdicts.withheld_metrics`);
* the controller: with ``design = "per-sample"`` each sample's in the column ``controller``
  (JSON: kind and state-space matrices, :func:`spacecraft.scene.given.controller_record`;
  a PD's gains also in ``pd_kp``, ``pd_kd``); with ``design = "nominal"`` the one controller in
  :attr:`Context.nominal_record` (the sweep's ``sweep.json`` and ``summary.json``).

A sample that genuinely fails (a scene the scene reader refuses, a controller that cannot be
tuned, any numerical failure) is recorded with its error message, status ``"failed"`` and no
verdict or margin (null booleans, NaN numbers); the report counts it apart. Warnings raised
while it ran are recorded too (the first one), never printed.
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings

import numpy as np

from ..scene.given import controller_record
from ..design.loop import DesignLoop, RunStats
from ..scene.read import SceneError, load_scene
from ..design.tuning import tune
from ..design.verdicts import TIME_METRICS, closed_loop_poles, loop_status, withheld_metrics
from .parameters import SweepError, SweepSpec, apply_values

__all__ = ["Context", "METRICS", "STATUSES", "prepare", "evaluate", "evaluate_batch",
           "exact_grid", "exact_verdict", "design_controller", "SampleRunner", "columns",
           "signed_margin"]

#: Columns of a sample's result: name -> (kind, unit, meaning). Kinds: "float", "int", "bool",
#: "str". "truth_*": hub + truncated beams (eigenvalue verdict); "exact_*": hub + exact beams
#: (Nyquist verdict); the time metrics are those of the slew on the truth loop.
METRICS: dict[str, tuple[str, str, str]] = {
    "stable": ("bool", "-", "closed loop stable (exact beam if computed, else truth model)"),
    "status": ("str", "-", "the truth loop's slew: settles, not settled, slew unfinished, "
                           "unstable, diverges (stable or unstable without a manoeuvre); failed"),
    "truth_stable": ("bool", "-", "stable on the truth model (eigenvalues)"),
    "truth_n_unstable_poles": ("int", "-", "unstable closed-loop poles on the truth model"),
    "truth_least_damping_ratio": ("float", "-", "least closed-loop damping ratio"),
    "truth_gain_margin": ("float", "dB", "gain margin on the truth model, signed: |GM| if "
                                         "stable, -|GM| if unstable"),
    "truth_phase_margin": ("float", "deg", "phase margin on the truth model, signed: |PM| if "
                                           "stable, -|PM| if unstable"),
    "truth_modulus_margin": ("float", "-", "modulus margin min|1 + L| on the truth model, "
                                           "signed: negative if unstable"),
    "exact_stable": ("bool", "-", "stable on the exact beam (Nyquist)"),
    "exact_n_unstable_poles": ("int", "-", "unstable closed-loop poles on the exact beam"),
    "exact_gain_margin": ("float", "dB", "gain margin on the exact beam, signed: |GM| if "
                                         "stable, -|GM| if unstable"),
    "exact_phase_margin": ("float", "deg", "phase margin on the exact beam, signed: |PM| if "
                                           "stable, -|PM| if unstable"),
    "exact_modulus_margin": ("float", "-", "modulus margin min|1 + L| on the exact beam, "
                                           "signed: negative if unstable"),
    "overshoot": ("float", "%", "slew overshoot (null where withheld: see status)"),
    "settling_time": ("float", "s", "2 % settling time of the slew (null where withheld: "
                                    "not settled, unstable)"),
    "peak_tip_deflection": ("float", "m", "peak tip deflection during the slew"),
    "peak_torque": ("float", "N*m", "peak torque during the slew"),
    "peak_attitude_error": ("float", "rad", "peak |theta - theta_ref| during the slew"),
    "final_attitude_error": ("float", "rad", "|theta - theta_ref| at the end of the slew"),
    "n_modes": ("int", "-", "bending modes per truncated beam of the truth model"),
    "controller": ("str", "-", "the sample's controller (design = per-sample): JSON of kind, "
                               "A, B, C, D (spacecraft.scene.given)"),
    "pd_kp": ("float", "N*m/rad", "the sample's PD proportional gain Kp (design = per-sample)"),
    "pd_kd": ("float", "N*m*s/rad", "the sample's PD derivative gain Kd (design = per-sample)"),
    "error": ("str", "-", "why the sample failed (empty: it did not)"),
    "warning": ("str", "-", "first warning raised while evaluating it (empty: none)"),
    "seconds": ("float", "s", "evaluation time"),
}
#: Values of the ``status`` column.
STATUSES = ("settles", "not settled", "slew unfinished", "unstable", "diverges", "stable",
            "failed")
_TIME_METRICS = TIME_METRICS
_PER_SAMPLE = ("controller",)
_PD = ("pd_kp", "pd_kd")
_EXACT = tuple(k for k in METRICS if k.startswith("exact_"))

#: The exact reference grid: points per decade, points across each mode's half-power band, and
#: cantilever modes beyond the top of the grid in the truncation that locates the modes.
POINTS_PER_DECADE = 100
POINTS_PER_MODE = 24
EXTRA_LOCATOR_MODES = 2
#: Points added around each frequency where a margin is attained (:func:`exact_verdict`).
REFINE_POINTS = 24
#: Exact loop gain |L| at a mode below which the mode gets no points across its band.
NEGLIGIBLE_LOOP_GAIN = 1e-3
#: Crossings refined besides the smallest margin's: phase margins within this many degrees,
#: gain margins within this many dB of the smallest on the grid (:func:`_margin_brackets`).
_PHASE_MARGIN_SLACK = 10.0
_GAIN_MARGIN_SLACK = 3.0


@dataclasses.dataclass
class Context:
    """What every sample of a sweep shares (built once by :func:`prepare`, sent to workers).

    Attributes
    ----------
    base : dict
        The scene mapping (file units) trimmed to the swept loop: one controller type, one fit
        criterion, ``n_modes`` fixed, tip deflections on, no FMUs, plots or tables.
    source : str
        The scene's name (messages).
    parameters : tuple of Parameter
    design : str
        ``"per-sample"`` or ``"nominal"``.
    variant : str
        The design model: a fit criterion, or ``"design"`` without fitted chains.
    controller : str
        ``"pd"`` or ``"lqr"``.
    n_modes : int or None
        Bending modes per truncated beam (None: no beam truth).
    nominal_controller : control.StateSpace or None
        ``design = "nominal"``: the controller tuned on the nominal scene.
    nominal_record : dict or None
        Its numbers (:func:`spacecraft.scene.given.controller_record`) and, for a PD, its
        gains ``Kp`` [N m/rad], ``Kd`` [N m s/rad].
    exact : bool
        Close the loop on the exact beams too.
    time_responses : bool
        The scene has a manoeuvre (slew metrics).
    """

    base: dict
    source: str
    parameters: tuple
    design: str
    variant: str
    controller: str
    n_modes: int | None
    nominal_controller: object = None
    exact: bool = False
    time_responses: bool = False
    nominal_record: dict | None = None

    def columns(self) -> list[str]:
        """The metric columns this sweep records."""
        return columns(self.exact, self.time_responses, per_sample=self.design == "per-sample",
                       controller=self.controller)


def columns(exact: bool, time_responses: bool, *, per_sample: bool = False,
            controller: str = "lqr") -> list[str]:
    """Metric columns of a sweep with/without the exact reference and the slew; the
    controller's columns with ``design = "per-sample"`` (the PD's gains for a PD)."""
    return [k for k in METRICS if (exact or k not in _EXACT)
            and (time_responses or k not in _TIME_METRICS)
            and (per_sample or k not in _PER_SAMPLE + _PD)
            and (controller == "pd" or k not in _PD)]


def signed_margin(value, stable) -> float:
    """A margin signed by the verdict: ``|value|`` if stable, ``-|value|`` if not (NaN where
    there is no verdict or no value; an infinite margin keeps its size)."""
    if stable is None or value is None or math.isnan(value):
        return math.nan
    return abs(float(value)) if stable else -abs(float(value))


class SampleRunner(DesignLoop):
    """The runner's model builders for one sample (time responses on, no output folder).

    Chains come from the runner's own fit (:meth:`_Runner.fit`): ``fit_chain`` memoises the
    dimensionless fit in each process (:mod:`appendages.fitting`), so a worker fits each
    ``(n_bodies, match)`` once (0.04 s for three bodies) and scales it to every sample's beam.
    """

    def __init__(self, scene):
        super().__init__(scene)


def design_controller(runner: SampleRunner, context: Context):
    """The controller of a sample tuned on its design model as the runner tunes it
    (:func:`spacecraft.design.tuning.tune`).

    Returns
    -------
    spacecraft.design.tuning.Tuned

    Raises
    ------
    SceneError
        If it cannot be tuned on this design model.
    """
    scene = runner.scene
    models = [runner.design_model(a, context.variant, context.n_modes) for a in scene.appendages]
    sc = runner.spacecraft(("design", context.variant), models)
    needs_tip = scene.controller.lqr is not None and \
        scene.controller.lqr.deflection_weight is not None and context.controller == "lqr"
    plant, _ = runner.plant(sc, ("design", context.variant), tip=needs_tip,
                            prune=scene.fidelity.prune)
    try:
        return tune(context.controller, plant, scene.controller)
    except ValueError as exc:
        raise SceneError(f"controller.{context.controller}: cannot tune on the design model: "
                         f"{exc}") from None


def controller_description(tuned, kind: str) -> dict:
    """The record of a tuned controller: its numbers, and a PD's gains ``Kp``, ``Kd``."""
    record = controller_record(tuned.controller, kind)
    if kind == "pd" and "Kp" in tuned.description:
        record["Kp"] = float(tuned.description["Kp"])
        record["Kd"] = float(tuned.description["Kd"])
    return record


def _grid_parts(runner: DesignLoop) -> tuple[np.ndarray, np.ndarray, float]:
    """(logarithmic grid, coupled modes below its top, damping ratio of the spread)."""
    scene = runner.scene
    exact = runner.exact_spacecraft()
    wb = runner.design_bandwidth(exact.inertia)
    w_lo, w_hi = wb * 1e-3, wb * 1e3
    models = []
    for a in scene.appendages:
        if a.truth == "beam":
            beam = runner.undamped_beam(a)
            k = 8
            cantilever = beam.cantilever_frequencies(k)
            while cantilever[-1] < w_hi and k < 1024:
                k *= 2
                cantilever = beam.cantilever_frequencies(k)
            n = int(np.searchsorted(cantilever, w_hi)) + EXTRA_LOCATOR_MODES
            models.append(runner.cached(("locator", a.name, n),
                                        lambda: beam.truncated(n, method="craig-bampton")))
        else:
            models.append(runner.truth_model(a, None))
    modes = runner.spacecraft(("locator",), models).modes()[0][3:]
    zeta = max([a.beam.damping_ratio for a in scene.appendages if a.beam is not None]
               + [1e-4])
    log_grid = np.geomspace(w_lo, w_hi, int(round(POINTS_PER_DECADE * math.log10(w_hi / w_lo))))
    return log_grid, modes[modes < w_hi], zeta


def _spread(modes: np.ndarray, zeta: float) -> np.ndarray:
    spread = np.tan(np.linspace(-1.5, 1.5, POINTS_PER_MODE))
    if modes.size == 0:
        return np.zeros(0)
    return np.concatenate([w * (1.0 + zeta * spread) for w in modes])


def exact_grid(runner: DesignLoop) -> np.ndarray:
    """Frequencies [rad/s] of the exact reference of a sample, every mode resolved.

    Logarithmic from 1e-3 to 1e3 times the design bandwidth wb (:data:`POINTS_PER_DECADE`),
    plus :data:`POINTS_PER_MODE` points ``w_k (1 + zeta tan(t))``, t evenly in [-1.5, 1.5] (an
    even count: no point exactly on an undamped mode), across every coupled mode w_k below
    1e3 wb, zeta the largest modal damping ratio of the beams (at least 1e-4). The modes are
    located on an undamped Craig-Bampton truncation with :data:`EXTRA_LOCATOR_MODES` modes more
    than the cantilever modes below 1e3 wb (on the default sweep scene within 3e-7 of the
    exact coupled frequencies, a small fraction of the half-power band 2 zeta).
    """
    log_grid, modes, zeta = _grid_parts(runner)
    omega = np.unique(np.concatenate([log_grid, modes, _spread(modes, zeta)]))
    return omega[(omega > 0) & (omega <= log_grid[-1])]


def _frd(omega: np.ndarray, theta: np.ndarray):
    import control

    data = np.stack([theta, 1j * omega * theta]).reshape(2, 1, -1)
    return control.frd(data, omega, inputs=["torque"], outputs=["theta", "omega"])


def _refinement(omega: np.ndarray, brackets, half_width: int) -> np.ndarray:
    """:data:`REFINE_POINTS` points between the grid points ``half_width`` below and above
    bracket ``(i, j)`` of grid indices: from grid point i - half_width + 1 to j + half_width - 1."""
    extra = []
    for lo_index, hi_index in brackets:
        lo = omega[max(lo_index - half_width + 1, 0)]
        hi = omega[min(hi_index + half_width - 1, omega.size - 1)]
        if hi > lo:
            extra.append(np.geomspace(lo, hi, REFINE_POINTS + 2)[1:-1])
    return np.setdiff1d(np.concatenate(extra), omega) if extra else np.zeros(0)


def _margin_brackets(L: np.ndarray) -> list[tuple[int, int]]:
    """Grid intervals where the margins of the loop L (on a grid) are attained.

    The rules of :func:`controllers.margins` read on the grid: the grid minimum of
    |1 + L| (both neighbouring intervals); every interval where |L| crosses 1 whose phase
    margin (at the end nearer |L| = 1) is within :data:`_PHASE_MARGIN_SLACK` of the smallest;
    every interval where Im L changes sign with Re L < 0 whose gain margin is within
    :data:`_GAIN_MARGIN_SLACK` of the smallest. The margins function picks the smallest of
    each after refining the crossings, so the one it picks lies in one of these intervals
    unless refinement moves a margin by more than the slack.
    """
    brackets: list[tuple[int, int]] = []
    finite = np.isfinite(L)
    if not finite.any():
        return brackets
    distance = np.where(finite, np.abs(1.0 + L), np.inf)
    i = int(np.argmin(distance))
    brackets.append((i, i))
    with np.errstate(divide="ignore", invalid="ignore"):
        log_gain = np.log(np.abs(L))
    cross = np.nonzero(finite[:-1] & finite[1:] & (np.sign(log_gain[:-1]) * np.sign(log_gain[1:])
                                                    < 0))[0]
    if cross.size:
        nearer = np.where(np.abs(log_gain[cross]) <= np.abs(log_gain[cross + 1]), cross,
                          cross + 1)
        pm = 180.0 + np.degrees(np.angle(L[nearer]))
        pm = np.abs(np.where(pm > 180.0, pm - 360.0, pm))
        brackets += [(int(j), int(j) + 1) for j in cross[pm <= pm.min() + _PHASE_MARGIN_SLACK]]
    imag = L.imag
    cross = np.nonzero(finite[:-1] & finite[1:] & (np.sign(imag[:-1]) * np.sign(imag[1:]) < 0)
                       & (L.real[:-1] + L.real[1:] < 0))[0]
    if cross.size:
        nearer = np.where(np.abs(imag[cross]) <= np.abs(imag[cross + 1]), cross, cross + 1)
        gm = np.abs(log_gain[nearer]) * (20.0 / math.log(10.0))
        keep = (gm <= gm.min() + _GAIN_MARGIN_SLACK) & (np.abs(L[nearer]) > 1e-9)
        brackets += [(int(j), int(j) + 1) for j in cross[keep]]
    return brackets


def exact_verdict(runner: DesignLoop, controller):
    """The loop on the exact beams: Nyquist verdict and margins (module docstring).

    The grid is :func:`exact_grid`'s, with one economy and one refinement:

    * a mode where the exact loop gain is below :data:`NEGLIGIBLE_LOOP_GAIN` (evaluated at the
      located mode, within 3e-7 of the exact peak) gets no points across its band: there
      |1 + L| stays within 1e-3 of 1, so its phase changes by less than 2e-3 rad (the Nyquist
      count cannot change) and the modulus margin is not attained there; a phase crossover
      there would be a gain margin above 60 dB, which is left unresolved;
    * the margins of an FRD plant interpolate the plant between grid points
      (:func:`controllers.margins`), which near a lightly damped mode costs accuracy (on the
      default sweep scene 24 points a mode put the modulus margin 0.14 % and the phase margin
      1.2 % off the converged values), so the grid is refined where the margins are attained:
      the exact loop gain L on the grid locates them (:func:`_margin_brackets`: the grid
      minimum of |1 + L|, the crossings of |L| = 1 and of the negative real axis whose margins
      on the grid are near the smallest), :data:`REFINE_POINTS` more points go between the
      grid points around each (from the second below to the second above a crossing, between
      the neighbours of the minimum), and the verdict is taken on the refined grid. (Locating
      them by a first :func:`controllers.margins` pass on the unrefined grid, as before, costs
      ten times this loop-gain evaluation and refines only the smallest margin of
      each kind, which is a factor 2 to 50 less accurate where two crossings compete;
      refining instead around the truth model's crossovers loses a factor ten.)

    On 30 samples of the default sweep scene the verdicts equal those on a converged grid (600
    points a mode, 400 a decade) and the margins are within 1e-3 of it (modulus margin; phase
    margin 1.3e-4, gain margin 5e-4; medians 5e-6, 2e-8, 4e-5; the largest errors where a
    resonance peak just crosses |L| = 1, a pair of crossings closer than the grid resolves).

    Parameters
    ----------
    runner : spacecraft.design.loop._Runner
        The sample's model builders.
    controller : control.StateSpace
        Continuous-time controller.

    Returns
    -------
    controllers.SpilloverVerdict
    """
    import controllers

    sc = runner.exact_spacecraft()
    runner.stats.exact_reference_evaluations += 1

    def response(w):
        return np.asarray(sc.frequency_response(w).frdata).reshape(-1)

    def merged(omega, theta, new):
        order = np.argsort(np.concatenate([omega, new]))
        return (np.concatenate([omega, new])[order],
                np.concatenate([theta, response(new)])[order])

    log_grid, modes, zeta = _grid_parts(runner)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        theta_modes = response(modes) if modes.size else np.zeros(0, dtype=complex)
        if modes.size >= 2:
            _, L = controllers.loop_frequency_response(_frd(modes, theta_modes), controller,
                                                       modes)
            significant = modes[np.abs(L) >= NEGLIGIBLE_LOOP_GAIN]
        else:
            significant = modes
        rest = np.setdiff1d(np.concatenate([log_grid, _spread(significant, zeta)]), modes)
        rest = rest[(rest > 0) & (rest <= log_grid[-1])]
        omega = np.concatenate([modes, rest])
        theta = np.concatenate([theta_modes, response(rest)])
        order = np.argsort(omega)
        omega, theta = omega[order], theta[order]
        _, L = controllers.loop_frequency_response(_frd(omega, theta), controller, omega)
        new = _refinement(omega, _margin_brackets(L), 2)
        if new.size:
            omega, theta = merged(omega, theta, new)
        return controllers.spillover(_frd(omega, theta), controller)


def _margins(prefix: str, verdict) -> dict:
    m = verdict.margins
    stable = bool(verdict.stable)
    out = {f"{prefix}_stable": stable,
           f"{prefix}_n_unstable_poles": int(verdict.n_unstable_poles),
           f"{prefix}_gain_margin": signed_margin(m.gain_margin, stable),
           f"{prefix}_phase_margin": signed_margin(m.phase_margin, stable),
           f"{prefix}_modulus_margin": signed_margin(m.modulus_margin, stable)}
    if verdict.least_damping_ratio is not None:
        out[f"{prefix}_least_damping_ratio"] = float(verdict.least_damping_ratio)
    return out


def _evaluate_scene(context: Context, scene) -> dict:
    import json

    import controllers

    runner = SampleRunner(scene)
    n = context.n_modes
    prune = scene.fidelity.prune
    truth_models = [runner.truth_model(a, n) for a in scene.appendages]
    truth_sc = runner.spacecraft(("truth", n), truth_models)
    m = scene.manoeuvre
    truth_verdict, _ = runner.plant(truth_sc, ("truth", n), prune=prune)
    out: dict = {"n_modes": -1 if n is None else int(n)}
    K = context.nominal_controller
    if K is None:
        tuned = design_controller(runner, context)
        K = tuned.controller
        record = controller_description(tuned, context.controller)
        out["controller"] = json.dumps({k: v for k, v in record.items()
                                        if k not in ("Kp", "Kd")})
        if "Kp" in record:
            out["pd_kp"], out["pd_kd"] = record["Kp"], record["Kd"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        truth = controllers.spillover(truth_verdict, K)
    out.update(_margins("truth", truth))
    stable = out["truth_stable"]
    if context.exact:
        out.update(_margins("exact", exact_verdict(runner, K)))
        stable = out["exact_stable"]
    out["stable"] = stable
    if context.time_responses and m is not None:
        truth_sim, _ = runner.plant(truth_sc, ("truth", n), tip=scene.outputs.tip_deflection,
                                    root_loads=scene.outputs.root_loads,
                                    disturbances=m.disturbance is not None, prune=prune)
        loop = controllers.close_loop(truth_sim, K)
        response = runner.simulate(loop, whole=True)["slew"]
        with np.errstate(all="ignore"):
            metrics = controllers.metrics(response)
        status = loop_status(closed_loop_poles(loop), response, m, metrics)
        if not stable and status["status"] not in ("unstable", "diverges"):
            # settles on the truth model, unstable on the exact beam: the verdict is the
            # exact beam's, and a slew's numbers are not those of an unstable loop
            status = {**status, "status": "unstable"}
        values, _ = withheld_metrics(metrics, status)
        out.update({k: None if values[k] is None else float(values[k])
                    for k in _TIME_METRICS if k in values})
        out["status"] = status["status"]
    else:
        out["status"] = "stable" if stable else "unstable"
    return out


def evaluate(context: Context, values, *, index: int | None = None) -> dict:
    """Evaluate one sample: its metrics (:data:`METRICS`), never raising for a failed sample.

    Parameters
    ----------
    context : Context
    values : sequence of float
        The parameters' values (file units), in the order of ``context.parameters``.
    index : int, optional
        Sample index, for messages.

    Returns
    -------
    dict
        Every column of :meth:`Context.columns`: NaN (float), -1 (int) or None (bool) where
        not computed, None (null) where withheld (the time metrics, by ``status``); ``error``
        and ``warning`` texts ("" if none); ``seconds``.
    """
    t0 = time.perf_counter()
    row = {k: _missing(METRICS[k][0]) for k in context.columns()}
    source = f"{context.source} (sample {index})" if index is not None else context.source
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            scene = load_scene(apply_values(context.base, context.parameters, values),
                               source=source)
            row.update({k: v for k, v in _evaluate_scene(context, scene).items() if k in row})
        except Exception as exc:  # a failed sample is recorded; the sweep goes on
            row = {k: _missing(METRICS[k][0]) for k in context.columns()}
            row["error"] = _short(f"{type(exc).__name__}: {exc}")
            row["status"] = "failed"
    if caught:
        w = caught[0]
        row["warning"] = _short(f"{w.category.__name__}: {w.message}")
    row["seconds"] = time.perf_counter() - t0
    return row


def evaluate_batch(context: Context, indices, values) -> dict:
    """Evaluate samples; columns ``sample``, the parameters' key paths, then the metrics.

    Parameters
    ----------
    context : Context
    indices : sequence of int
        Sample indices.
    values : ndarray, shape (n, d)
        Their parameter values.

    Returns
    -------
    dict of str to list
        Column name -> values, one per sample (the order of ``indices``).
    """
    values = np.asarray(values, dtype=float).reshape(len(indices), len(context.parameters))
    cols: dict = {"sample": [int(i) for i in indices]}
    for k, p in enumerate(context.parameters):
        cols[p.key] = values[:, k].tolist()
    names = context.columns()
    for name in names:
        cols[name] = []
    for i, v in zip(indices, values):
        row = evaluate(context, v, index=int(i))
        for name in names:
            cols[name].append(row[name])
    return cols


def _missing(kind: str):
    return {"float": math.nan, "int": -1, "bool": None, "str": ""}[kind]


def _short(text: str, limit: int = 300) -> str:
    text = " ".join(str(text).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."


# ---------------------------------------------------------------------------------------------
# preparing a sweep
# ---------------------------------------------------------------------------------------------
def _trim(raw: dict, scene, spec: SweepSpec, n_modes) -> tuple[dict, str, str]:
    """The scene mapping reduced to the swept loop, and (variant, controller)."""
    import copy

    base = copy.deepcopy(raw)
    kind = spec.controller or scene.controller.types[0]
    if kind not in scene.controller.types:
        raise SweepError(f"{scene.source}: sweep.controller: {kind!r} is not among the scene's "
                         f"controller.types {list(scene.controller.types)}")
    variants = scene.design_variants
    variant = spec.fit or variants[0]
    if variant not in variants:
        raise SweepError(f"{scene.source}: sweep.fit: {variant!r} is not a design model of the "
                         f"scene (fits: {', '.join(v for v in variants if v != 'design') or 'none'})")
    c = base.setdefault("controller", {})
    c["types"] = [kind]
    c.pop("pd" if kind == "lqr" else "lqr", None)
    for item, a in zip(base["appendages"], scene.appendages):
        if a.design == "fit":
            item.setdefault("fit", {})["match"] = [variant]
    base.setdefault("outputs", {})["tip_deflection"] = True
    base["outputs"].setdefault("exact_reference", False)
    base["export"] = {"fmu": False}
    base["report"] = {"plots": False, "equivalence": False}
    if n_modes is not None:
        fidelity = base.setdefault("fidelity", {})
        fidelity.pop("tolerance", None)
        fidelity["n_modes"] = int(n_modes)
    return base, variant, kind


def prepare(raw: dict, spec: SweepSpec, source: str) -> Context:
    """The shared part of every sample: trimmed scene, fixed fidelity, nominal controller.

    Parameters
    ----------
    raw : dict
        The scene mapping without ``sweep`` (file units).
    spec : SweepSpec
    source : str

    Returns
    -------
    Context

    Raises
    ------
    SceneError
        If the nominal scene is invalid or its fidelity cannot be chosen.
    """
    # a swept key the scene leaves out is nominally the centre of its distribution
    raw = apply_values(raw, spec.parameters, spec.nominal)
    scene = load_scene(raw, source=source)
    if scene.three_axis:
        raise SweepError(f"{source}: hub.inertia is a 3 x 3 tensor: a three-axis scene cannot "
                         "be swept yet (a sample is the planar design loop: one torque, theta "
                         "and omega about z); sweep a planar scene, or run this one with "
                         "flexsat run")
    n_modes = None
    if scene.has_beam_truth:
        if scene.fidelity.n_modes is not None:
            n_modes = scene.fidelity.n_modes
        else:
            try:
                n_modes, _ = DesignLoop(scene).choose_fidelity()
            except ValueError as exc:
                raise SceneError(f"{source}: fidelity: {exc}") from None
    base, variant, kind = _trim(raw, scene, spec, n_modes)
    trimmed = load_scene(base, source=source)
    context = Context(base=base, source=source, parameters=spec.parameters, design=spec.design,
                      variant=variant, controller=kind, n_modes=n_modes,
                      exact=(trimmed.outputs.exact_reference and trimmed.has_beam_truth
                             and trimmed.controller.sample_time is None),
                      time_responses=trimmed.manoeuvre is not None)
    if spec.design == "nominal":
        tuned = design_controller(SampleRunner(trimmed), context)
        context.nominal_controller = tuned.controller
        context.nominal_record = controller_description(tuned, kind)
    return context
