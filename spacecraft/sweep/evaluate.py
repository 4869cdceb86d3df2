"""One sample of a sweep: one evaluation of the design loop, as the scene says, reduced to numbers.

A sample is the sweep's scene with the sampled numbers put in (:func:`~.parameters.apply_values`)
and validated by :func:`spacecraft.scene.read.load_scene`. Its evaluation is one
:meth:`spacecraft.DesignLoop.closed_loops` of the public design loop, for one controller and
one design model, on the truth model alone and the manoeuvre simulated whole:

1. design (``design = "per-sample"``): the design chain of each beam (the loop's fit:
   :func:`appendages.equivalence.fit_chain` solves the dimensionless fit once per process and
   scales it to each beam, :mod:`appendages.fitting`), its plant, the controller tuned on it as
   every run tunes it; ``design = "nominal"``: the controller tuned once on the nominal scene,
   held fixed;
2. truth: hub + beams truncated as the nominal scene's truth (fixed for the sweep); the
   closed-loop verdict from its eigenvalues and its gain, phase and modulus margins
   (:func:`controllers.spillover`);
3. the slew on the truth loop (if the scene has a manoeuvre), slew and disturbance at once:
   overshoot, settling time, peak tip deflection, peak torque, attitude errors
   (:func:`controllers.metrics`);
4. the exact distributed beam (if ``outputs.exact_reference``): the loop's verdict by the
   Nyquist criterion on the exact frequency response of hub + beams through W(s), its margins
   found on the exact loop function (:func:`spacecraft.design.verdicts.exact_loop_verdict`, on
   the loop's one exact grid, :meth:`spacecraft.design.models.ModelBuilder.exact_grid`, at
   :data:`SAMPLE_GRID`'s density).

The fidelity (``n_modes`` of the truth model) is chosen once, on the nominal scene with its tip
outputs on, by the loop's rule, and held: the sample's scene gets ``fidelity.n_modes`` and, for
what the rule adds per motion (a three-axis truth's lowest mode of each motion a tip output
sees, the modes the tip-output rule adds), ``fidelity.modes_per_motion``, so that every
sample's truth model has as many modes per motion as the nominal run's, and a sample's scene
reruns alone (``flexsat run``) to the same numbers. Where the exact reference
is on, the report gives the largest difference between the truth model's and the exact beam's
modulus margins over the samples, and the number of verdicts they disagree on.

A three-axis scene (a 3 x 3 hub inertia) is swept through the same loop: its verdict is the
multiloop one (:class:`controllers.margins.MultiLoopMargins`): the gain, phase and modulus
margins of each axis' loop at a time (``truth_gain_margin_x``...), the disk margin and its
gain and phase (``truth_disk_margin``...), the smallest singular value of the return
difference I + L, and, as the summary the report, the worst-case search and every ranking
use, ``truth_gain_margin``, ``truth_phase_margin`` (the least over the three loops at a time)
and ``truth_modulus_margin`` (the least of the loops at a time and of the smallest singular
value of I + L: never above any of them); the slew's torque and attitude errors per axis
(``peak_torque_x``...). The exact beam's verdict is the same through W6 (``exact_*``).

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
  a PD's gains also in ``pd_kp``, ``pd_kd``, a three-axis PD's per hub axis in ``pd_kp_x``..
  ``pd_kd_z``, the diagonals of its gain matrices); with ``design = "nominal"`` the one controller in
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

from controllers.threads import blas_threads_for

from ..design.loop import DesignLoop
from ..design.verdicts import TIME_METRICS, withheld_metrics
from ..scene.given import controller_record
from ..scene.limits import estimate_cost
from ..design.manoeuvre import flown_keys
from ..scene.read import SceneError, load_scene
from ..scene.reader import shorten
from .parameters import SweepError, SweepSpec, apply_values

__all__ = ["Context", "METRICS", "THREE_AXIS_METRICS", "STATUSES", "SAMPLE_GRID", "prepare",
           "evaluate", "evaluate_batch", "evaluate_scene", "controller_description", "columns",
           "signed_margin", "summary_margins"]

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
    "n_modes": ("int", "-", "the truth's fidelity.n_modes (the modes each beam keeps, per "
                "motion: the summary's loop.truth_modes)"),
    "controller": ("str", "-", "the sample's controller (design = per-sample): JSON of kind, "
                               "A, B, C, D (spacecraft.scene.given)"),
    "pd_kp": ("float", "N*m/rad", "the sample's PD proportional gain Kp (design = per-sample)"),
    "pd_kd": ("float", "N*m*s/rad", "the sample's PD derivative gain Kd (design = per-sample)"),
    "error": ("str", "-", "why the sample failed (empty: it did not)"),
    "warning": ("str", "-", "first warning raised while evaluating it (empty: none)"),
    "seconds": ("float", "s", "evaluation time"),
}

def _three_axis_metrics() -> dict[str, tuple[str, str, str]]:
    out: dict[str, tuple[str, str, str]] = {}
    for prefix, model in (("truth", "the truth model"), ("exact", "the exact beam")):
        for axis in "xyz":
            loop = f"the loop at a time about {axis} on {model}, signed"
            out[f"{prefix}_gain_margin_{axis}"] = ("float", "dB", f"gain margin of {loop}")
            out[f"{prefix}_phase_margin_{axis}"] = ("float", "deg", f"phase margin of {loop}")
            out[f"{prefix}_modulus_margin_{axis}"] = ("float", "-",
                                                      f"modulus margin of {loop}")
        out[f"{prefix}_disk_margin"] = ("float", "-", f"disk margin alpha (all loops at once) "
                                                      f"on {model}, signed")
        out[f"{prefix}_disk_gain_margin"] = ("float", "dB", f"gain margin of the disk margin on "
                                                            f"{model}, signed")
        out[f"{prefix}_disk_phase_margin"] = ("float", "deg", f"phase margin of the disk margin "
                                                              f"on {model}, signed")
        out[f"{prefix}_min_singular_value"] = ("float", "-", "smallest singular value of the "
                                                             f"return difference I + L on "
                                                             f"{model}, signed")
    for axis in "xyz":
        out[f"pd_kp_{axis}"] = ("float", "N*m/rad", f"the sample's PD proportional gain about "
                                                    f"{axis}: Kp[{axis}{axis}] of its 3 x 3 Kp "
                                                    "(design = per-sample)")
        out[f"pd_kd_{axis}"] = ("float", "N*m*s/rad", f"the sample's PD derivative gain about "
                                                      f"{axis}: Kd[{axis}{axis}] of its 3 x 3 Kd "
                                                      "(design = per-sample)")
    for axis in "xyz":
        out[f"peak_torque_{axis}"] = ("float", "N*m", f"peak torque about {axis} during the slew")
        out[f"peak_attitude_error_{axis}"] = ("float", "rad", f"peak attitude error about "
                                                              f"{axis} during the slew")
        out[f"final_attitude_error_{axis}"] = ("float", "rad", f"attitude error about {axis} "
                                                               "at the end of the slew")
    return out


#: Columns a three-axis sweep records besides :data:`METRICS` (whose summary margins are then
#: the worst over the axes: module docstring).
THREE_AXIS_METRICS = _three_axis_metrics()
METRICS.update(THREE_AXIS_METRICS)
#: Values of the ``status`` column.
STATUSES = ("settles", "not settled", "slew unfinished", "unstable", "diverges", "stable",
            "failed")
_PER_SAMPLE = ("controller",)
_PD = ("pd_kp", "pd_kd")
#: A three-axis PD's gains per hub axis (the diagonals; the whole matrices: ``controller``).
_PD_3 = tuple(f"pd_k{g}_{a}" for a in "xyz" for g in "pd")
_TIME_METRICS = TIME_METRICS + tuple(k for k in THREE_AXIS_METRICS
                                      if not k.startswith(("truth_", "exact_", "pd_")))
_EXACT = tuple(k for k in METRICS if k.startswith("exact_"))

#: The exact grid of a sample (:meth:`spacecraft.design.models.ModelBuilder.exact_grid`): a
#: sample's verdict needs it only to count the encirclements and bracket the margins (found
#: then on the exact loop function), for which 24 points across each mode's half-power band
#: suffice; the run's denser default also serves its plots and interpolated responses.
SAMPLE_GRID = {"points_per_mode": 24}


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
    three_axis : bool
        A three-axis scene (the multiloop verdict's columns, :data:`THREE_AXIS_METRICS`).
    truth_modes : dict
        The modes every sample's truncated truth beam keeps, by appendage: per motion in three
        axes (``{"xy": .., "xz": .., "torsion": .., "axial": ..}``, or
        ``{"lowest coupled modes": k}``), ``{"bending": k}`` in the plane (empty without a
        truncated beam).
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
    three_axis: bool = False
    truth_modes: dict = dataclasses.field(default_factory=dict)

    def columns(self) -> list[str]:
        """The metric columns this sweep records."""
        return columns(self.exact, self.time_responses, per_sample=self.design == "per-sample",
                       controller=self.controller, three_axis=self.three_axis)


def columns(exact: bool, time_responses: bool, *, per_sample: bool = False,
            controller: str = "lqr", three_axis: bool = False) -> list[str]:
    """Metric columns of a sweep with/without the exact reference and the slew; the
    controller's columns with ``design = "per-sample"`` (a PD's gains for a PD: planar
    ``pd_kp``, ``pd_kd``, three-axis per hub axis ``pd_kp_x``..``pd_kd_z``); the multiloop
    verdict's and the per-axis columns of a three-axis sweep."""
    gains = (_PD_3 if three_axis else _PD) if controller == "pd" and per_sample else ()
    return [k for k in METRICS if (exact or k not in _EXACT)
            and (time_responses or k not in _TIME_METRICS)
            and (per_sample or k not in _PER_SAMPLE)
            and (k in gains or k not in _PD + _PD_3)
            and (three_axis or k not in THREE_AXIS_METRICS)]


def signed_margin(value, stable) -> float:
    """A margin signed by the verdict: ``|value|`` if stable, ``-|value|`` if not (NaN where
    there is no verdict or no value; an infinite margin keeps its size)."""
    if stable is None or value is None or math.isnan(value):
        return math.nan
    return abs(float(value)) if stable else -abs(float(value))


def controller_description(tuned, kind: str) -> dict:
    """The record of a tuned controller: its numbers, and a PD's gains ``Kp`` [N m/rad], ``Kd``
    [N m s/rad] (floats; a three-axis PD's 3 x 3 gain matrices as lists of rows)."""
    record = controller_record(tuned.controller, kind)
    if kind == "pd" and "Kp" in tuned.description:
        for name in ("Kp", "Kd"):
            gain = np.asarray(tuned.description[name], dtype=float)
            record[name] = float(gain) if gain.ndim == 0 else gain.tolist()
    return record


def summary_margins(margins) -> dict:
    """A loop's gain [dB], phase [deg] and modulus margins, unsigned: a planar loop's own; a
    three-axis loop's the least over its loops at a time, the modulus margin also over the
    smallest singular value of the return difference I + L (module docstring), and its
    per-axis and disk margins as they are.

    Parameters
    ----------
    margins : controllers.margins result or mapping
        :func:`controllers.margins` (planar or :class:`controllers.margins.MultiLoopMargins`)
        or its dict (:func:`spacecraft.design.verdicts.margins_dict`).

    Returns
    -------
    dict
        ``gain_margin``, ``phase_margin``, ``modulus_margin`` and, for a three-axis loop, the
        names of :data:`THREE_AXIS_METRICS` without their prefix (None where not given).
    """
    m = dict(margins) if isinstance(margins, dict) else dict(margins.as_dict())
    if "gain_margin_x" not in m:
        return {k: m.get(k) for k in ("gain_margin", "phase_margin", "modulus_margin")}

    def least(names):
        values = [float(m[k]) for k in names if m.get(k) is not None]
        values = [v for v in values if not math.isnan(abs(v))]
        return min((abs(v) for v in values), default=None)

    out = {"gain_margin": least([f"gain_margin_{a}" for a in "xyz"]),
           "phase_margin": least([f"phase_margin_{a}" for a in "xyz"]),
           "modulus_margin": least([f"modulus_margin_{a}" for a in "xyz"]
                                   + ["min_singular_value"])}
    for key in THREE_AXIS_METRICS:
        name = key.split("_", 1)[1]
        if key.startswith("truth_"):
            out[name] = m.get(name)
    return out


def _margins(prefix: str, verdict) -> dict:
    stable = bool(verdict.stable)
    out = {f"{prefix}_stable": stable,
           f"{prefix}_n_unstable_poles": int(verdict.n_unstable_poles)}
    out.update({f"{prefix}_{k}": signed_margin(v, stable)
                for k, v in summary_margins(verdict.margins).items()})
    if verdict.least_damping_ratio is not None:
        out[f"{prefix}_least_damping_ratio"] = float(verdict.least_damping_ratio)
    return out


def evaluate_scene(context: Context, scene) -> dict:
    """The metrics of one sample's validated scene (:data:`METRICS`; module docstring), by
    one evaluation of the design loop.

    Raises
    ------
    SceneError
        A controller that cannot be tuned on the sample's design model, or a loop over
        ``limits.states`` (the sample's truth can keep more modes than the nominal's).
    """
    import json

    loop = DesignLoop(scene)
    loop.n_modes = n = context.n_modes
    out: dict = {"n_modes": -1 if n is None else int(n)}
    K = context.nominal_controller
    # the sample's loop within limits.states, before a controller is tuned on it
    loop.check_loop_states(n, variants=(context.variant,), kinds=(context.controller,),
                           controller=K, models=("truth",))
    if K is None:
        tuned = loop.tuned(context.variant, context.controller, n)
        K = tuned.controller
        record = controller_description(tuned, context.controller)
        out["controller"] = json.dumps({k: v for k, v in record.items()
                                        if k not in ("Kp", "Kd")})
        if "Kp" in record and not context.three_axis:
            out["pd_kp"], out["pd_kd"] = record["Kp"], record["Kd"]
        elif "Kp" in record:   # per hub axis: the diagonals of the 3 x 3 gains
            for i, a in enumerate("xyz"):
                out[f"pd_kp_{a}"], out[f"pd_kd_{a}"] = record["Kp"][i][i], record["Kd"][i][i]
    exact_frd = loop.exact_reference_frd(**SAMPLE_GRID) if context.exact else None
    c = loop.closed_loops(context.variant, context.controller, controller=K,
                          models=("truth",), whole_manoeuvre=True, exact_frd=exact_frd)
    out.update(_margins("truth", c.verdict))
    stable = out["truth_stable"]
    if context.exact:
        if c.exact_verdict is None:
            raise ValueError(c.row["exact_verdict"]["error"])
        out.update(_margins("exact", c.exact_verdict))
        stable = out["exact_stable"]
    out["stable"] = stable
    status = c.row.get("status", {}).get("truth")
    if context.time_responses and status is not None:
        values = c.row["metrics"]["truth"]
        if not stable and status["status"] not in ("unstable", "diverges"):
            # settles on the truth model, unstable on the exact beam: the verdict is the
            # exact beam's, and a slew's numbers are not those of an unstable loop
            status = {**status, "status": "unstable"}
            values, _ = withheld_metrics(values, status)
        gone = status["status"] in ("unstable", "diverges")
        # an unstable loop's time metrics are withheld, the per-axis ones with the rest
        out.update({k: None if values[k] is None or gone else float(values[k])
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
            scene = load_scene(apply_values(context.base, context.parameters, values,
                                            shared=True), source=source)
            # one BLAS-thread region for the whole sample, sized as spacecraft.run sizes a
            # run: the stages' own regions nested in it cost no call into the BLAS library
            with blas_threads_for(estimate_cost(scene).loop_states):
                metrics = evaluate_scene(context, scene)
            row.update({k: v for k, v in metrics.items() if k in row})
        except Exception as exc:  # a failed sample is recorded; the sweep goes on
            row = {k: _missing(METRICS[k][0]) for k in context.columns()}
            row["error"] = shorten(f"{type(exc).__name__}: {exc}", 300, one_line=True)
            row["status"] = "failed"
    if caught:
        w = caught[0]
        row["warning"] = shorten(f"{w.category.__name__}: {w.message}", 300, one_line=True)
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


# ---------------------------------------------------------------------------------------------
# preparing a sweep
# ---------------------------------------------------------------------------------------------
def _trim(raw: dict, scene, spec: SweepSpec, n_modes, floors=None) -> tuple[dict, str, str]:
    """The scene mapping reduced to the swept loop, and (variant, controller); with ``n_modes``
    its fidelity fixed to it and (``floors``: ``{appendage: {motion: count}}``, a truth chosen
    from the tolerance) to the modes pinned per motion (``fidelity.modes_per_motion``)."""
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
        if floors is not None:
            fidelity["modes_per_motion"] = {name: dict(f) for name, f in floors.items()}
    return base, variant, kind


def _truth_modes(scene, n_modes) -> dict:
    """:attr:`Context.truth_modes` of the trimmed scene."""
    if n_modes is None:
        return {}
    loop = DesignLoop(scene)
    per_motion = loop.truth_modes_per_motion(n_modes)
    if per_motion:
        return per_motion
    return {a.name: {"bending": int(loop.truth_model(a, n_modes).n_modes)}
            for a in scene.appendages if a.truth == "beam"}


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
    flown = flown_keys(scene)
    if flown:
        raise SweepError(f"{source}: {flown[0]}: a sweep's sample is the ideal slew (the step "
                         "reference, no loop delay, wheels or sensor noise); sweep a scene "
                         "without it, or run this one with flexsat run")
    n_modes = floors = None
    if scene.has_beam_truth:
        if scene.fidelity.n_modes is not None:
            n_modes = scene.fidelity.n_modes
        else:
            # chosen as a run of the scene chooses it, with the tip outputs every sample
            # reports (a three-axis truth keeps a mode of each motion they see, and the modes
            # the tip-output rule adds): pinned for the samples beside n_modes
            chooser = scene
            if not scene.outputs.tip_deflection:
                chooser = scene.replace(outputs=dataclasses.replace(scene.outputs,
                                                                    tip_deflection=True))
            loop = DesignLoop(chooser)
            try:
                n_modes = loop.n_modes
            except ValueError as exc:
                raise SceneError(f"{source}: fidelity: {exc}") from None
            if loop.three_axis or loop.tip_floors:
                floors = loop.tip_floors
    base, variant, kind = _trim(raw, scene, spec, n_modes, floors)
    trimmed = load_scene(base, source=source)
    context = Context(base=base, source=source, parameters=spec.parameters, design=spec.design,
                      variant=variant, controller=kind, n_modes=n_modes,
                      exact=(trimmed.outputs.exact_reference and trimmed.has_beam_truth
                             and trimmed.controller.sample_time is None),
                      time_responses=trimmed.manoeuvre is not None,
                      three_axis=trimmed.three_axis,
                      truth_modes=_truth_modes(trimmed, n_modes))
    if spec.design == "nominal":
        nominal = DesignLoop(trimmed)
        nominal.check_loop_states(n_modes, variants=(variant,), kinds=(kind,),
                                  models=("truth",))
        tuned = nominal.tuned(variant, kind, n_modes)
        context.nominal_controller = tuned.controller
        context.nominal_record = controller_description(tuned, kind)
    return context
