"""The worst case of a sweep: the smallest stability margin over the parameter box.

Objective
    For margin m (modulus margin min|1 + L(jw)|, or phase margin [deg]) of the loop on the exact
    beams (on the truth model where the scene has no exact reference), the *signed margin*
    ``s = |m|`` if the loop is stable and ``s = -|m|`` if it is not, as every sample records it
    (:func:`.evaluate.signed_margin`). It is continuous where the Nyquist curve crosses the
    critical point (there m = 0 and the verdict changes), so minimising it finds the least
    stable point of the box: the smallest margin if every point is stable, the most unstable
    one otherwise. An infinite margin (|L| never crosses 1) counts as :data:`CAP` with its sign.
    A failed evaluation has no margin: it is never the worst and never seeds the search (its
    objective is +inf), and the failures are counted (``failed``).

Method
    Differential evolution (``scipy.optimize.differential_evolution``, the ``best1bin``
    strategy, ``popsize`` 15 per parameter, no gradient polish: the objective is a minimum over
    frequency and has kinks), its first population seeded with the sweep's samples of lowest
    objective inside the box (Latin-hypercube points of the box where there are too few), run
    until the budget ``worst_case_evaluations`` or DE's convergence test. The population has
    15 members per parameter, fewer (at least 5) when the budget would allow fewer than four
    generations. Each generation's
    population is evaluated on the Dask workers at once (``updating="deferred"``). The box:
    :meth:`.parameters.Parameter.box`; log-uniform parameters are searched in log scale,
    discrete ones by index (``integrality``).

Verification
    The worst parameter set is written as a scene (``worst.toml``: the sweep's scene with those
    numbers, without ``[sweep]``, the exact reference on, and the very controller the sweep
    closed there as ``[controller.given]``, :mod:`spacecraft.scene.given`: the nominal one,
    or the one tuned on that sample) and run by :func:`spacecraft.design.loop.run` itself, whose
    verdict and margins on the exact beam are reported beside the sweep's, with a check on a
    grid four times as dense (:func:`verify`): ``flexsat run worst.toml`` gives the sweep's
    verdict.

References
----------
.. [1] R. Storn, K. Price, "Differential evolution - a simple and efficient heuristic for global
   optimization over continuous spaces", J. Global Optimization 11, 1997.
.. [2] S. Skogestad, I. Postlethwaite, Multivariable Feedback Control, 2nd ed., sec. 2.4.3
   (modulus margin).
"""

from __future__ import annotations

import copy
import dataclasses
import json
import math
import re

import numpy as np

from ..scene.read import SceneError
from .evaluate import signed_margin, summary_margins
from .parameters import SweepSpec, apply_values

__all__ = ["CAP", "DENSE_GRID", "WorstCase", "objective", "search", "worst_scene", "to_toml",
           "verify"]

#: Size of the objective of an infinite margin (its sign is the verdict's).
CAP = {"modulus_margin": 10.0, "phase_margin": 180.0}


def objective(row: dict, metric: str, exact: bool) -> float:
    """The objective of an evaluated sample (module docstring): its signed margin, at most
    :data:`CAP` in size; +inf for a failed sample (no margin)."""
    prefix = "exact" if exact else "truth"
    value = row.get(f"{prefix}_{metric}")
    if row.get("error") or value is None or math.isnan(value):
        return math.inf
    return max(-CAP[metric], min(float(value), CAP[metric]))


@dataclasses.dataclass
class WorstCase:
    """Outcome of :func:`search`.

    Attributes
    ----------
    metric : str
        ``"modulus_margin"`` or ``"phase_margin"``.
    values : dict
        Key path -> worst value (file units).
    row : dict
        The evaluation of the worst point (every metric).
    objective : float
        Its signed margin.
    evaluations : int
        Design-loop evaluations of the search.
    best_sample : dict
        The sweep's own sample of lowest objective: ``sample``, ``objective``.
    message : str
        Why DE stopped.
    failed : int
        Evaluations of the search that failed (no margin; never the worst).
    verification : dict or None
        The runner's verdict on ``worst.toml`` (:func:`verify`).
    """

    metric: str
    values: dict
    row: dict
    objective: float
    evaluations: int
    best_sample: dict
    message: str
    failed: int = 0
    verification: dict | None = None

    def as_dict(self) -> dict:
        """JSON-ready form."""
        return dataclasses.asdict(self)


class _Coordinates:
    """Search coordinates of the box: linear, log (loguniform) or an index (discrete)."""

    def __init__(self, spec: SweepSpec):
        self.parameters = spec.parameters
        lo, hi, integral = [], [], []
        for p in self.parameters:
            a, b = p.box()
            if p.distribution == "discrete":
                lo.append(0.0)
                hi.append(float(len(p.values) - 1))
                integral.append(True)
            elif p.distribution == "loguniform":
                lo.append(math.log(a))
                hi.append(math.log(b))
                integral.append(False)
            else:
                lo.append(a)
                hi.append(b)
                integral.append(False)
        self.lo, self.hi = np.array(lo), np.array(hi)
        self.integral = np.array(integral)

    def values(self, x: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(np.asarray(x, dtype=float))
        out = np.empty_like(x)
        for k, p in enumerate(self.parameters):
            if p.distribution == "discrete":
                idx = np.clip(np.rint(x[:, k]).astype(int), 0, len(p.values) - 1)
                out[:, k] = np.asarray(p.values)[idx]
            elif p.distribution == "loguniform":
                out[:, k] = np.exp(x[:, k])
            else:
                out[:, k] = x[:, k]
        return out

    def point(self, values: np.ndarray) -> np.ndarray:
        values = np.atleast_2d(np.asarray(values, dtype=float))
        x = np.empty_like(values)
        for k, p in enumerate(self.parameters):
            if p.distribution == "discrete":
                x[:, k] = [list(p.values).index(v) if v in p.values else 0 for v in values[:, k]]
            elif p.distribution == "loguniform":
                x[:, k] = np.log(values[:, k])
            else:
                x[:, k] = values[:, k]
        return x

    def inside(self, x: np.ndarray) -> np.ndarray:
        return np.all((x >= self.lo) & (x <= self.hi), axis=1)


def search(context, spec: SweepSpec, executor, table, metric: str, *, batch: int = 8,
           popsize: int = 15) -> WorstCase:
    """Differential evolution on the signed margin, seeded with the sweep's samples.

    Parameters
    ----------
    context : .evaluate.Context
    spec : SweepSpec
    executor : .execute.Executor
    table : pyarrow.Table or None
        The sweep's samples (their parameters and metrics).
    metric : {"modulus_margin", "phase_margin"}
    batch : int
        Samples per Dask task.
    popsize : int
        DE population per parameter.

    Returns
    -------
    WorstCase
    """
    import scipy.optimize
    from scipy.stats import qmc

    exact = context.exact
    coords = _Coordinates(spec)
    d = len(spec.parameters)
    # the population: popsize per parameter, fewer when the budget would not allow four
    # generations (DE needs at least 5 members)
    n_pop = max(5, min(popsize * d, spec.worst_case_evaluations // 4))
    # the sweep's samples, best first, as the first population
    seeds = np.zeros((0, d))
    best_sample = {"sample": None, "objective": None}
    if table is not None and table.num_rows:
        columns = table.to_pydict()
        objective_of_sample = np.array([objective({k: columns[k][i] for k in columns}, metric,
                                                   exact) for i in range(table.num_rows)])
        values = np.column_stack([columns[p.key] for p in spec.parameters])
        x = coords.point(values)
        order = np.argsort(objective_of_sample, kind="stable")
        order = order[np.isfinite(objective_of_sample[order])]   # failed samples seed nothing
        if order.size:
            i0 = int(order[0])
            best_sample = {"sample": int(columns["sample"][i0]),
                           "objective": float(objective_of_sample[i0])}
        chosen, seen = [], set()
        for i in order:
            if coords.inside(x[i:i + 1])[0] and x[i].tobytes() not in seen:
                seen.add(x[i].tobytes())
                chosen.append(x[i])
                if len(chosen) == n_pop:
                    break
        seeds = np.array(chosen, dtype=float).reshape(-1, d)
    if seeds.shape[0] < n_pop:
        fill = qmc.LatinHypercube(d, rng=np.random.default_rng(spec.seed)).random(
            n_pop - seeds.shape[0])
        seeds = np.vstack([seeds, coords.lo + fill * (coords.hi - coords.lo)])
    cache: dict = {}
    count = [0, 0]
    width = coords.hi - coords.lo

    def snap(x):
        # DE maps its population to the unit cube and back: a seed on the box's edge comes
        # back a few ulps inside; put it on the edge again
        x = np.asarray(x, dtype=float)
        x = np.where(np.abs(x - coords.lo) <= 1e-12 * width, coords.lo, x)
        return np.where(np.abs(x - coords.hi) <= 1e-12 * width, coords.hi, x)

    def evaluate_population(func, xs):
        xs = [snap(x) for x in xs]
        fresh = list({x.tobytes(): x for x in xs if x.tobytes() not in cache}.values())
        if fresh:
            rows = executor.evaluate_rows(context, coords.values(np.array(fresh)), batch)
            count[0] += len(fresh)
            for x, row in zip(fresh, rows):
                cache[x.tobytes()] = (objective(row, metric, exact), row)
                count[1] += bool(row.get("error"))
        return [func(x) for x in xs]

    def objective_of(x):
        return cache[snap(x).tobytes()][0]

    # evaluations: the first population, then one population per generation
    generations = max(1, spec.worst_case_evaluations // n_pop - 1)
    result = scipy.optimize.differential_evolution(
        objective_of, list(zip(coords.lo, coords.hi)), init=seeds,
        maxiter=generations, polish=False, updating="deferred", workers=evaluate_population,
        rng=np.random.default_rng(spec.seed), integrality=coords.integral if
        coords.integral.any() else None)
    x = snap(result.x)
    key = x.tobytes()
    if key not in cache:
        evaluate_population(lambda z: None, [x])
    value, row = cache[key]
    if not math.isfinite(value):
        # DE keeps a failed point only where every point failed; the least stable point
        # evaluated is the worst found
        finite = [(v, k) for k, (v, _) in cache.items() if math.isfinite(v)]
        if finite:
            value, key = min(finite)
            x = np.frombuffer(key, dtype=float)
            row = cache[key][1]
    worst = coords.values(x)[0]
    return WorstCase(metric, {p.key: float(v) for p, v in zip(spec.parameters, worst)}, row,
                     float(value), count[0], best_sample, str(result.message), count[1])


# ---------------------------------------------------------------------------------------------
# worst.toml and its verification
# ---------------------------------------------------------------------------------------------
def worst_scene(context, values: dict, row: dict) -> dict:
    """The scene mapping of a worst case: the sweep's scene with its numbers, the exact
    reference on, and the controller the sweep closed there given as numbers.

    Parameters
    ----------
    context : .evaluate.Context
    values : dict
        Key path -> value (file units).
    row : dict
        Its evaluation (``controller``: the sample's controller with ``design =
        "per-sample"``).

    Raises
    ------
    ValueError
        If the controller of that point is not known (a failed evaluation).
    """
    params = context.parameters
    raw = apply_values(context.base, params, [values[p.key] for p in params])
    raw.setdefault("outputs", {})["exact_reference"] = True
    if context.nominal_record is not None:
        record = context.nominal_record
    elif row.get("controller"):
        record = json.loads(row["controller"])
    else:
        raise ValueError("the worst point's controller is not known (its evaluation failed)")
    raw.setdefault("controller", {})["given"] = {k: record[k] for k in ("kind", "A", "B", "C",
                                                                       "D")}
    return raw


def _key(name: str) -> str:
    return name if re.fullmatch(r"[A-Za-z0-9_-]+", name) else json.dumps(name)


def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {type(value).__name__} as TOML")


def to_toml(mapping: dict, header: str = "") -> str:
    """TOML text of a scene mapping (tables, arrays of tables, numbers, strings, booleans).

    Floats are written with ``repr`` (the shortest text that reads back to the same double).
    """
    lines = [f"# {line}" if line else "#" for line in header.splitlines()]

    def table(node: dict, path: list[str]):
        scalars = {k: v for k, v in node.items() if not isinstance(v, dict)
                   and not (isinstance(v, list) and v and all(isinstance(i, dict) for i in v))}
        for k, v in scalars.items():
            lines.append(f"{_key(k)} = {_value(v)}")
        for k, v in node.items():
            if isinstance(v, dict):
                lines.append("")
                lines.append(f"[{'.'.join(_key(p) for p in path + [k])}]")
                table(v, path + [k])
            elif isinstance(v, list) and v and all(isinstance(i, dict) for i in v):
                for item in v:
                    lines.append("")
                    lines.append(f"[[{'.'.join(_key(p) for p in path + [k])}]]")
                    table(item, path + [k])

    table(mapping, [])
    return "\n".join(lines).strip("\n") + "\n"


def _verdict(v) -> dict:
    stable = bool(v.stable)
    return {"stable": stable, "n_unstable_poles": int(v.n_unstable_poles),
            **{k: signed_margin(value, stable)
               for k, value in summary_margins(v.margins).items()}}


#: The grid of the dense check of a worst case (:func:`verify`): points per decade and across
#: each coupled mode's half-power band, four times a sample's (:data:`.evaluate.SAMPLE_GRID`).
DENSE_GRID = {"points_per_decade": 400, "points_per_mode": 96}


def verify(context, values: dict, raw: dict, source: str) -> dict:
    """Check a worst case on the exact beams two ways.

    ``exact_reference``: the sweep's own loop (the same controller, the scene's loop delay)
    judged on the exact beams through a grid four times as dense as a sample's
    (:data:`DENSE_GRID`, the design loop's
    :meth:`~spacecraft.design.models.ModelBuilder.exact_grid` and
    :meth:`~spacecraft.design.models.ModelBuilder.exact_verdict`): the sweep's verdict does
    not hang on its grid. ``runner``: the scene ``raw`` (``worst.toml``, the same controller
    given) run by :func:`spacecraft.design.loop.run`: what a user re-running it gets, its
    margins signed as the sweep's. Failures are recorded as ``error`` texts.
    """
    import warnings

    from ..design.loop import DesignLoop, run
    from ..scene.given import given_state_space
    from ..scene.read import load_scene

    out: dict = {}
    try:
        scene = load_scene(copy.deepcopy(raw), source=source)
        loop = DesignLoop(scene)
        K = given_state_space(scene.controller.given, scene.controller.sample_time)
        frd = loop.exact_reference_frd(**DENSE_GRID)
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore", RuntimeWarning)
            out["exact_reference"] = _verdict(loop.exact_verdict(K, frd))
    except (SceneError, ValueError, ArithmeticError) as exc:
        out["exact_reference"] = {"error": f"{type(exc).__name__}: {exc}"}
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            result = run(load_scene(copy.deepcopy(raw), source=source), time_responses=True)
        row = result.data["closed_loops"][0]
        runner_out = {"truth": _signed(row["verdict"])}
        if "exact_verdict" in row:
            runner_out["exact"] = (_signed(row["exact_verdict"]) if "error" not in
                                   row["exact_verdict"] else dict(row["exact_verdict"]))
        out["runner"] = runner_out
    except (SceneError, ValueError, ArithmeticError) as exc:
        out["runner"] = {"error": f"{type(exc).__name__}: {exc}"}
    return out


def _signed(verdict: dict) -> dict:
    stable = verdict.get("stable")
    return {"stable": stable, **{k: signed_margin(value, stable)
                                 for k, value in summary_margins(verdict).items()}}
