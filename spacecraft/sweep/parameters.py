"""What a sweep varies and how: key paths into a scene, distributions, sampling plans.

A sweep is a ``[sweep]`` table in a scene file (or the same as a dict)::

    [sweep]
    samples = 1000            # Monte Carlo or Latin-hypercube samples
    seed = 1
    method = "monte-carlo"    # or "latin-hypercube", "grid"
    design = "per-sample"     # or "nominal"
    worst_case = true         # then a worst-case search on the stability margins
    [sweep.parameters]
    "hub.inertia" = {distribution = "uniform", low = 40.0, high = 60.0}
    "appendages.rod.beam.youngs_modulus" = {distribution = "normal", mean = 2.06e11, std = 1.0e10}
    "appendages.rod.beam.damping_ratio" = {distribution = "loguniform", low = 0.001, high = 0.02}

Keys of ``[sweep]``

==========================  ===============================================================
key                         meaning
==========================  ===============================================================
``parameters`` *            table: key path -> distribution (below); at least one
``method``                  ``"monte-carlo"`` (default), ``"latin-hypercube"`` or ``"grid"``
``samples``                 samples of monte-carlo and latin-hypercube (default 1000)
``levels``                  grid: values per parameter (default 5; a parameter's own
                            ``levels`` overrides it)
``seed``                    integer >= 0 (default 0)
``design``                  ``"per-sample"`` (default: every sample fits its design chain and
                            tunes its controller: how robust is the design procedure) or
                            ``"nominal"`` (one controller tuned on the nominal scene and held
                            fixed: how robust is this controller)
``controller``              the controller swept (default: the scene's first type)
``fit``                     the design chain's fit criterion (default: the scene's first)
``worst_case``              false (default), true (modulus and phase margins) or a list of
                            ``"modulus_margin"``, ``"phase_margin"``
``worst_case_evaluations``  budget of design-loop evaluations per worst-case search
                            (default 600)
``max_samples``             raise the sample limit :data:`MAX_SAMPLES`
==========================  ===============================================================

Key paths name a number of the scene in the file's units (deg, Hz, as the file writes them):
``hub.inertia``, ``appendages.<name>.beam.youngs_modulus`` (appendages by their ``name``),
``appendages.<name>.position[0]``, ``controller.lqr.attitude_weight``... A key that the scene
leaves at its default (``appendages.rod.beam.damping_ratio``) may be swept too. Each sample is
the scene with these numbers replaced, validated by :func:`spacecraft.scene.read.load_scene` like any
scene (so every bound a scene has applies to every sample).

Three-axis scenes are swept the same way, by the indices of their arrays: an entry of the hub's
inertia tensor (``hub.inertia[0][0]``; an off-diagonal entry ``hub.inertia[0][1]`` is the
product of inertia and moves ``hub.inertia[1][0]`` with it, the tensor stays symmetric), a
mount's position (``appendages.<name>.position[2]``) or Euler angle [deg]
(``appendages.<name>.orientation[2]``, the cant of a wing about its own axis with the ``"ZYX"``
sequence), any section property of a beam (``appendages.<name>.beam.thickness``,
``...youngs_modulus``, ``...wall_thickness``). A sample whose inertia tensor is no rigid body's
(not positive definite, or its principal moments break the triangle inequality) is refused by
the scene reader, so it is a failed sample with that reason, counted apart; a box whose end
alone reaches one refuses the sweep (:func:`check_box`).

Distributions (the worst-case box in brackets)

* ``{distribution = "uniform", low, high}`` [low, high];
* ``{distribution = "loguniform", low, high}``, 0 < low < high: log-uniform [low, high];
* ``{distribution = "normal", mean, std}``, optionally truncated to ``low``/``high``
  [mean - 3 std, mean + 3 std] within the truncation (:data:`BOX_SIGMAS`);
* ``{distribution = "discrete", values = [...]}``: equally likely values [the values].

Sampling. Every plan maps points u of the unit cube to values by each parameter's inverse
distribution function, so sample i is decided by i alone, whatever the batching:

* monte-carlo: u_i from the PCG64 stream seeded with ``SeedSequence(seed, spawn_key=(i,))``:
  sample i is the same in any sweep with that seed and those parameters, whatever the sample
  count (a longer sweep extends a shorter one);
* latin-hypercube: ``scipy.stats.qmc.LatinHypercube(d, rng=default_rng(seed))`` (a plan of
  ``samples`` points: it depends on the count);
* grid: the cartesian product of each parameter's levels (uniform: evenly spaced from low to
  high; loguniform: geometrically; normal: its 0.135 % .. 99.865 % quantiles, mean +- 3 std;
  discrete: its values), the last parameter varying fastest.

References
----------
.. [1] M. D. McKay, R. J. Beckman, W. J. Conover, "A comparison of three methods for selecting
   values of input variables in the analysis of output from a computer code", Technometrics
   21(2), 1979 (Latin hypercube sampling).
.. [2] NumPy, "Parallel random number generation" (SeedSequence spawn keys), numpy.org/doc.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import math
import re
from collections.abc import Mapping, Sequence

import numpy as np

from ..scene.read import SceneError, load_scene

__all__ = [
    "SweepError", "Parameter", "SweepSpec", "read_sweep", "resolve_key", "numeric_keys",
    "apply_values", "mirror_path", "check_box", "MAX_SAMPLES", "METHODS", "DESIGNS", "DISTRIBUTIONS", "WORST_METRICS",
    "BOX_SIGMAS",
]

#: Largest number of samples a sweep runs unless ``max_samples`` (``--max-samples``) raises it:
#: a million samples of a design loop of some tens of milliseconds are hours on two cores.
MAX_SAMPLES = 1_000_000
METHODS = ("monte-carlo", "latin-hypercube", "grid")
DESIGNS = ("per-sample", "nominal")
DISTRIBUTIONS = ("uniform", "loguniform", "normal", "discrete")
WORST_METRICS = ("modulus_margin", "phase_margin")
#: Half-width of a normal parameter's worst-case box and grid, in standard deviations.
BOX_SIGMAS = 3.0
#: Sections of a scene whose numbers may not be swept (the sweep fixes the fidelity on the
#: nominal scene; the rest is not part of the design loop).
_FIXED_SECTIONS = ("fidelity", "export", "report", "outputs", "title", "sweep")
_TOKEN = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)$")
_DEFAULT_SAMPLES = 1000
_DEFAULT_LEVELS = 5
_DEFAULT_EVALUATIONS = 600


class SweepError(SceneError):
    """A sweep that cannot be run: bad ``[sweep]`` table or parameter, a box reaching
    non-physical values, an output folder or scheduler that cannot be used. One line, naming
    the key."""


def _fmt(value) -> str:
    text = f"{value:.6g}" if isinstance(value, float) else repr(value)
    return text if len(text) <= 100 else text[:97] + "..."


# ---------------------------------------------------------------------------------------------
# key paths
# ---------------------------------------------------------------------------------------------
def _appendage_names(raw: Mapping) -> list[str]:
    items = raw.get("appendages")
    if not isinstance(items, list):
        return []
    return [item.get("name", f"appendage{k + 1}") if isinstance(item, Mapping)
            else f"appendage{k + 1}" for k, item in enumerate(items)]


def numeric_keys(raw: Mapping) -> list[str]:
    """Key paths of every number written in a scene mapping (appendages by name)."""
    names = _appendage_names(raw)
    out: list[str] = []

    def walk(node, prefix):
        if isinstance(node, Mapping):
            for key, value in node.items():
                walk(value, f"{prefix}.{key}" if prefix else str(key))
        elif isinstance(node, list):
            for k, value in enumerate(node):
                if isinstance(value, (int, float)) and not isinstance(value, bool):
                    out.append(f"{prefix}[{k}]")
                elif isinstance(value, (Mapping, list)):
                    walk(value, f"{prefix}[{k}]")
        elif isinstance(node, (int, float)) and not isinstance(node, bool):
            out.append(prefix)

    for key, value in raw.items():
        if key == "appendages" and isinstance(value, list):
            for name, item in zip(names, value):
                walk(item, f"appendages.{name}")
        elif key != "sweep":
            walk(value, str(key))
    return out


def _unknown(source: str, key: str, problem: str, raw: Mapping) -> SweepError:
    match = difflib.get_close_matches(key, numeric_keys(raw), n=1, cutoff=0.6)
    hint = f"; did you mean {match[0]!r}?" if match else ""
    return SweepError(f"{source}: sweep.parameters.{key!r}: {problem}{hint}")


def resolve_key(key: str, raw: Mapping, source: str = "<dict>") -> tuple:
    """The path of a key path in the scene mapping, e.g. ``("appendages", 0, "beam", "length")``.

    Parameters
    ----------
    key : str
        ``hub.inertia``, ``appendages.<name>.beam.youngs_modulus``, ``...position[0]``.
    raw : mapping
        The scene as read from TOML (file units).
    source : str
        Scene name for messages.

    Returns
    -------
    tuple
        Keys (str) and list indices (int) from the top of the mapping to the number.

    Raises
    ------
    SweepError
        Unknown key (with the closest key of the scene), a key of a fixed section, or a key that
        names something other than a number.
    """
    if not isinstance(key, str) or not key:
        raise SweepError(f"{source}: sweep.parameters: keys must be non-empty strings; got "
                         f"{_fmt(key)}")
    tokens = key.split(".")
    parsed = []
    for token in tokens:
        m = _TOKEN.match(token)
        if m is None:
            raise _unknown(source, key, f"{_fmt(token)} is not a key, key[index] or "
                                        "key[index][index]", raw)
        parsed.append((m.group(1), [int(i) for i in re.findall(r"\d+", m.group(2))]))
    if parsed[0][0] in _FIXED_SECTIONS:
        raise SweepError(f"{source}: sweep.parameters.{key!r}: {parsed[0][0]} settings cannot "
                         "be swept (the sweep fixes the fidelity on the nominal scene; exports, "
                         "outputs and reports are not part of the design loop)")
    path: list = []
    node = raw
    k = 0
    if parsed[0] == ("appendages", []):
        names = _appendage_names(raw)
        if len(parsed) < 3:
            raise _unknown(source, key, "needs appendages.<name>.<key>", raw)
        name, indices = parsed[1]
        if indices or name not in names:
            close = difflib.get_close_matches(name, names, n=1, cutoff=0.5)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise SweepError(f"{source}: sweep.parameters.{key!r}: no appendage named {name!r} "
                             f"(appendages: {', '.join(names) or 'none'}){hint}")
        path = ["appendages", names.index(name)]
        node = raw["appendages"][names.index(name)]
        k = 2
    for j, (name, indices) in enumerate(parsed[k:], start=k):
        last = j == len(parsed) - 1
        if not isinstance(node, Mapping):
            raise _unknown(source, key, f"{'.'.join(tokens[:j])} is not a table", raw)
        if name not in node:
            if last and not indices:
                path.append(name)   # a key left at its default: load_scene decides
                return tuple(path)
            raise _unknown(source, key, f"the scene has no {'.'.join(tokens[:j + 1])}", raw)
        path.append(name)
        node = node[name]
        for index in indices:
            if not isinstance(node, list) or not 0 <= index < len(node):
                what = (f"{len(node)} entries" if isinstance(node, list) else
                        f"{_kind(node)} is not an array")
                raise _unknown(source, key, f"index {index} out of range ({what})", raw)
            path.append(index)
            node = node[index]
    if isinstance(node, list):
        # an array: its first number is the key the reader accepts
        first = key
        while isinstance(node, list) and node:
            first, node = f"{first}[0]", node[0]
        hint = (f"; its entries are numbers: e.g. {first!r}" if isinstance(node, (int, float))
                and not isinstance(node, bool) else "")
        raise SweepError(f"{source}: sweep.parameters.{key!r}: names {_kind(_get(raw, path))}, "
                         f"not a number{hint}")
    if isinstance(node, bool) or not isinstance(node, (int, float)):
        raise _unknown(source, key, f"names {_kind(node)}, not a number", raw)
    return tuple(path)


def _kind(node) -> str:
    if isinstance(node, Mapping):
        return "a table"
    if isinstance(node, list):
        return f"an array of {len(node)}"
    return f"{type(node).__name__} {_fmt(node)}"


def _get(raw, path):
    node = raw
    for p in path:
        if isinstance(p, int):
            node = node[p]
        else:
            if p not in node:
                return None
            node = node[p]
    return node


def mirror_path(path: tuple, raw: Mapping) -> tuple | None:
    """The symmetric partner of an off-diagonal entry of an inertia tensor, or None.

    An inertia tensor (the hub's ``inertia`` or a tip body's, a 3 x 3 array) is symmetric: its
    entry ``[i][j]``, i != j, is the product of inertia of both ``[i][j]`` and ``[j][i]``, and a
    sweep moves both (:func:`apply_values`).

    Parameters
    ----------
    path : tuple
        A parameter's place in the scene mapping (:func:`resolve_key`).
    raw : mapping
        The scene mapping.
    """
    if len(path) < 3 or path[-3] != "inertia" or not all(
            isinstance(k, int) and not isinstance(k, bool) for k in path[-2:]):
        return None
    i, j = path[-2:]
    tensor = _get(raw, path[:-2])
    if i == j or not isinstance(tensor, list) or len(tensor) != 3 or not all(
            isinstance(row, list) and len(row) == 3 for row in tensor):
        return None
    return (*path[:-2], j, i)


def apply_values(raw: Mapping, parameters: Sequence["Parameter"], values, *,
                 shared: bool = False) -> dict:
    """A deep copy of the scene mapping with each parameter set to its value (file units); an
    off-diagonal entry of an inertia tensor sets its symmetric partner too
    (:func:`mirror_path`).

    ``shared``: copy only the tables and arrays on the parameters' paths and share the rest
    with ``raw`` (for a mapping handed straight to
    :func:`spacecraft.scene.read.load_scene`, which reads a copy of it, and changed nowhere
    else: a sweep's sample)."""
    out = dict(raw) if shared else copy.deepcopy(dict(raw))
    copied: set = set()
    for p, value in zip(parameters, values):
        value = float(value)
        if p.integer and value.is_integer():
            value = int(value)
        mirror = mirror_path(p.path, out)
        for path in (p.path,) if mirror is None else (p.path, mirror):
            node = out
            for k, step in enumerate(path[:-1]):
                if shared and path[:k + 1] not in copied:
                    node[step] = (dict(node[step]) if isinstance(node[step], Mapping)
                                  else list(node[step]))
                    copied.add(path[:k + 1])
                node = node[step]
            node[path[-1]] = value
    return out


# ---------------------------------------------------------------------------------------------
# distributions
# ---------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class Parameter:
    """One swept number of the scene and its distribution (file units).

    Attributes
    ----------
    key : str
        The key path as written (``appendages.rod.beam.youngs_modulus``).
    path : tuple
        Its place in the scene mapping (:func:`resolve_key`).
    distribution : str
        One of :data:`DISTRIBUTIONS`.
    low, high : float or None
        Bounds (uniform, loguniform; optional truncation of a normal).
    mean, std : float or None
        Normal distribution.
    values : tuple or None
        Discrete values.
    levels : int or None
        Grid levels of this parameter (None: the sweep's).
    nominal : float
        Its value in the scene (the distribution's centre where the scene leaves it out).
    integer : bool
        The scene writes it as an integer (kept an integer where the value is integral).
    """

    key: str
    path: tuple
    distribution: str
    low: float | None = None
    high: float | None = None
    mean: float | None = None
    std: float | None = None
    values: tuple | None = None
    levels: int | None = None
    nominal: float = math.nan
    integer: bool = False

    def ppf(self, u: np.ndarray) -> np.ndarray:
        """Values at probabilities u in [0, 1) (the inverse distribution function)."""
        import scipy.special
        import scipy.stats

        u = np.asarray(u, dtype=float)
        d = self.distribution
        if d == "uniform":
            return self.low + u * (self.high - self.low)
        if d == "loguniform":
            a, b = math.log(self.low), math.log(self.high)
            return np.exp(a + u * (b - a))
        if d == "normal":
            if self.low is None and self.high is None:
                # 0 < u < 1 for every draw of Generator.random except exactly 0 (probability
                # 2^-53): clipped to the smallest positive double's quantile
                return self.mean + self.std * scipy.special.ndtri(np.clip(u, 1e-300, None))
            a = -math.inf if self.low is None else (self.low - self.mean) / self.std
            b = math.inf if self.high is None else (self.high - self.mean) / self.std
            return self.mean + self.std * scipy.stats.truncnorm.ppf(u, a, b)
        values = np.asarray(self.values, dtype=float)
        return values[np.minimum((u * values.size).astype(int), values.size - 1)]

    def box(self) -> tuple[float, float]:
        """The worst-case search interval (see the module docstring)."""
        if self.distribution in ("uniform", "loguniform"):
            return float(self.low), float(self.high)
        if self.distribution == "normal":
            lo = self.mean - BOX_SIGMAS * self.std
            hi = self.mean + BOX_SIGMAS * self.std
            if self.low is not None:
                lo = max(lo, self.low)
            if self.high is not None:
                hi = min(hi, self.high)
            return float(lo), float(hi)
        return float(min(self.values)), float(max(self.values))

    def grid(self, levels: int) -> np.ndarray:
        """The grid values of this parameter."""
        if self.distribution == "discrete":
            return np.asarray(self.values, dtype=float)
        lo, hi = self.box()
        if self.distribution == "loguniform":
            return np.geomspace(lo, hi, levels)
        return np.linspace(lo, hi, levels)

    def describe(self) -> str:
        """Short text: ``uniform [40, 60]``."""
        d = self.distribution
        if d in ("uniform", "loguniform"):
            return f"{d} [{self.low:.6g}, {self.high:.6g}]"
        if d == "normal":
            cut = ""
            if self.low is not None or self.high is not None:
                cut = (f", truncated to [{'-inf' if self.low is None else f'{self.low:.6g}'}, "
                       f"{'inf' if self.high is None else f'{self.high:.6g}'}]")
            return f"normal (mean {self.mean:.6g}, std {self.std:.6g}{cut})"
        return "discrete {" + ", ".join(f"{v:.6g}" for v in self.values) + "}"

    def as_dict(self) -> dict:
        """JSON-ready form (also the resume check's record)."""
        out = {"key": self.key, "distribution": self.distribution}
        for name in ("low", "high", "mean", "std", "levels"):
            if getattr(self, name) is not None:
                out[name] = getattr(self, name)
        if self.values is not None:
            out["values"] = list(self.values)
        out["nominal"] = self.nominal
        return out


def _number(table: dict, name: str, where: str, *, required: bool = True):
    if name not in table:
        if required:
            raise SweepError(f"{where}: missing {name!r}")
        return None
    value = table.pop(name)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise SweepError(f"{where}: {name} must be a finite number; got {_fmt(value)}")
    return float(value)


def _read_parameter(key: str, spec, raw: Mapping, source: str) -> Parameter:
    where = f"{source}: sweep.parameters.{key!r}"
    path = resolve_key(key, raw, source)
    if not isinstance(spec, Mapping):
        raise SweepError(f"{where}: must be a table such as {{distribution = \"uniform\", "
                         f"low = ..., high = ...}}; got {_kind(spec)}")
    t = dict(spec)
    d = t.pop("distribution", None)
    if d not in DISTRIBUTIONS:
        raise SweepError(f"{where}: distribution must be one of "
                         f"{', '.join(map(repr, DISTRIBUTIONS))}; got {_fmt(d)}")
    levels = None
    if "levels" in t:
        levels = t.pop("levels")
        if isinstance(levels, bool) or not isinstance(levels, int) or levels < 2:
            raise SweepError(f"{where}: levels must be an integer >= 2; got {_fmt(levels)}")
    low = high = mean = std = None
    values = None
    if d in ("uniform", "loguniform"):
        low, high = _number(t, "low", where), _number(t, "high", where)
        if not low < high:
            raise SweepError(f"{where}: low must be below high; got low = {low:.6g}, "
                             f"high = {high:.6g}")
        if d == "loguniform" and low <= 0:
            raise SweepError(f"{where}: loguniform needs 0 < low; got low = {low:.6g}")
    elif d == "normal":
        mean, std = _number(t, "mean", where), _number(t, "std", where)
        if std <= 0:
            raise SweepError(f"{where}: std must be positive; got {std:.6g}")
        low = _number(t, "low", where, required=False)
        high = _number(t, "high", where, required=False)
        if low is not None and high is not None and not low < high:
            raise SweepError(f"{where}: low must be below high; got low = {low:.6g}, "
                             f"high = {high:.6g}")
        import scipy.special

        a = 0.0 if low is None else float(scipy.special.ndtr((low - mean) / std))
        b = 1.0 if high is None else float(scipy.special.ndtr((high - mean) / std))
        if b - a < 1e-9:
            raise SweepError(f"{where}: the truncation [low, high] holds a probability of "
                             f"{max(b - a, 0.0):.3g} of the normal distribution; it must hold "
                             "at least 1e-9")
    else:
        values = t.pop("values", None)
        if not isinstance(values, list) or not values or any(
                isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)
                for v in values):
            raise SweepError(f"{where}: values must be a non-empty array of finite numbers; got "
                             f"{_fmt(values)}")
        if len(set(values)) != len(values):
            raise SweepError(f"{where}: values must be distinct; got {_fmt(values)}")
    if t:
        allowed = {"uniform": "low, high", "loguniform": "low, high",
                   "normal": "mean, std, low, high", "discrete": "values"}[d]
        raise SweepError(f"{where}: unknown key {sorted(t)[0]!r} for a {d} distribution; "
                         f"expected {allowed} (and levels)")
    current = _get(raw, path)
    integer = isinstance(current, int) and not isinstance(current, bool) and (
        d == "discrete" and all(isinstance(v, int) for v in values))
    if current is None:
        centre = {"uniform": lambda: 0.5 * (low + high),
                  "loguniform": lambda: math.sqrt(low * high),
                  "normal": lambda: mean,
                  "discrete": lambda: values[0]}[d]()
        nominal = float(centre)
    else:
        nominal = float(current)
    parameter = Parameter(key, path, d, low, high, mean, std,
                          None if values is None else tuple(float(v) for v in values), levels,
                          nominal, integer)
    return parameter


def _check_alone(parameter: "Parameter", raw: Mapping, source: str,
                 scene_error: str | None) -> None:
    """The scene with this one parameter at its nominal value: an error the scene alone does
    not have is this key's (a key the scene does not know, a value of the wrong kind)."""
    try:
        load_scene(apply_values(raw, [parameter], [parameter.nominal]), source=source)
    except SceneError as exc:
        if str(exc) == scene_error:
            return
        problem = str(exc).split(": ", 1)[-1]
        if _get(raw, parameter.path) is None:
            raise _unknown(source, parameter.key, f"is not a key the scene knows ({problem})",
                           raw) from None
        raise SweepError(f"{source}: sweep.parameters.{parameter.key!r} "
                         f"({parameter.describe()}): at its nominal value "
                         f"{_fmt(parameter.nominal)} the scene refuses it: {problem}"
                         + ("; a key that takes integers is swept with distribution = "
                            "\"discrete\" and integer values" if "integer" in problem else "")
                         ) from None


# ---------------------------------------------------------------------------------------------
# the sweep
# ---------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class SweepSpec:
    """A validated ``[sweep]`` table (see the module docstring)."""

    parameters: tuple
    method: str = "monte-carlo"
    samples: int = _DEFAULT_SAMPLES
    levels: int = _DEFAULT_LEVELS
    seed: int = 0
    design: str = "per-sample"
    controller: str | None = None
    fit: str | None = None
    worst_case: tuple = ()
    worst_case_evaluations: int = _DEFAULT_EVALUATIONS
    max_samples: int = MAX_SAMPLES

    @property
    def n_samples(self) -> int:
        """Samples of the plan (the grid's product for a grid, in Python integers: a product
        of levels beyond int64 is a number too large, not a wrapped one)."""
        if self.method == "grid":
            return math.prod(int(p.levels or self.levels) if p.distribution != "discrete"
                             else len(p.values) for p in self.parameters)
        return self.samples

    @property
    def keys(self) -> list[str]:
        """Key paths of the parameters (the columns of the table)."""
        return [p.key for p in self.parameters]

    @property
    def nominal(self) -> np.ndarray:
        """Nominal values (the scene's)."""
        return np.array([p.nominal for p in self.parameters])

    def unit_points(self, indices: np.ndarray | None = None) -> np.ndarray:
        """Points of the unit cube, shape (n, d), for sample indices (default all)."""
        n, d = self.n_samples, len(self.parameters)
        indices = np.arange(n) if indices is None else np.asarray(indices, dtype=np.int64)
        if self.method == "monte-carlo":
            out = np.empty((indices.size, d))
            for row, i in enumerate(indices):
                stream = np.random.SeedSequence(self.seed, spawn_key=(int(i),))
                out[row] = np.random.Generator(np.random.PCG64(stream)).random(d)
            return out
        if self.method == "latin-hypercube":
            from scipy.stats import qmc

            plan = qmc.LatinHypercube(d, rng=np.random.default_rng(self.seed)).random(n)
            return plan[indices]
        raise ValueError("a grid has no unit-cube points; use values()")

    def values(self, indices: np.ndarray | None = None) -> np.ndarray:
        """Parameter values of samples (file units), shape (n, d)."""
        n = self.n_samples
        indices = np.arange(n) if indices is None else np.asarray(indices, dtype=np.int64)
        if self.method == "grid":
            axes = [p.grid(p.levels or self.levels) for p in self.parameters]
            shape = [a.size for a in axes]
            digits = np.unravel_index(indices, shape)
            return np.column_stack([a[k] for a, k in zip(axes, digits)]) if axes else \
                np.zeros((indices.size, 0))
        u = self.unit_points(indices)
        return np.column_stack([p.ppf(u[:, k]) for k, p in enumerate(self.parameters)])

    def as_dict(self) -> dict:
        """JSON-ready form (recorded in the output folder; resume checks it)."""
        return {"method": self.method, "samples": self.n_samples, "seed": self.seed,
                "levels": self.levels if self.method == "grid" else None,
                "design": self.design, "controller": self.controller, "fit": self.fit,
                "worst_case": list(self.worst_case),
                "worst_case_evaluations": self.worst_case_evaluations,
                "parameters": [p.as_dict() for p in self.parameters]}


def _integer(table: dict, name: str, where: str, default: int, minimum: int) -> int:
    value = table.pop(name, default)
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise SweepError(f"{where}.{name}: must be an integer >= {minimum}; got {_fmt(value)}")
    return value


def _choice(table: dict, name: str, where: str, choices, default):
    value = table.pop(name, default)
    if value is default and default is None:
        return None
    if value not in choices:
        raise SweepError(f"{where}.{name}: must be one of {', '.join(map(repr, choices))}; got "
                         f"{_fmt(value)}")
    return value


def read_sweep(table, raw: Mapping, source: str = "<dict>", *,
               max_samples: int | None = None) -> SweepSpec:
    """Validate a ``[sweep]`` table against its scene.

    Parameters
    ----------
    table : mapping
        The ``[sweep]`` table.
    raw : mapping
        The scene mapping without ``sweep`` (file units).
    source : str
        Scene name for messages.
    max_samples : int, optional
        Raise the sample limit (the command line's ``--max-samples``); the table's
        ``max_samples`` raises it too.

    Returns
    -------
    SweepSpec

    Raises
    ------
    SweepError
        Naming the key: unknown keys, bad values, unknown key paths (with a "did you mean"),
        invalid distributions, too many samples, a controller parameter with ``design =
        "nominal"``, a box that reaches values the scene refuses.
    """
    where = f"{source}: sweep"
    if not isinstance(table, Mapping):
        raise SweepError(f"{where}: must be a table; got {_kind(table)}")
    t = dict(table)
    method = _choice(t, "method", where, METHODS, "monte-carlo")
    samples = _integer(t, "samples", where, _DEFAULT_SAMPLES, 1)
    levels = _integer(t, "levels", where, _DEFAULT_LEVELS, 2)
    seed = _integer(t, "seed", where, 0, 0)
    design = _choice(t, "design", where, DESIGNS, "per-sample")
    controller = _choice(t, "controller", where, ("pd", "lqr"), None)
    fit = _choice(t, "fit", where, ("poles-and-zeros", "frequencies"), None)
    worst = t.pop("worst_case", False)
    if worst is True:
        worst = WORST_METRICS
    elif worst is False:
        worst = ()
    elif isinstance(worst, list) and worst and all(w in WORST_METRICS for w in worst) \
            and len(set(worst)) == len(worst):
        worst = tuple(worst)
    else:
        raise SweepError(f"{where}.worst_case: must be true, false or a list of "
                         f"{', '.join(map(repr, WORST_METRICS))}; got {_fmt(worst)}")
    evaluations = _integer(t, "worst_case_evaluations", where, _DEFAULT_EVALUATIONS, 10)
    limit = _integer(t, "max_samples", where, MAX_SAMPLES, 1)
    if max_samples is not None:
        limit = max(limit, int(max_samples))
    parameters = t.pop("parameters", None)
    if t:
        raise SweepError(f"{where}.{sorted(t)[0]}: unknown key; expected one of controller, "
                         "design, fit, levels, max_samples, method, parameters, samples, seed, "
                         "worst_case, worst_case_evaluations")
    if not isinstance(parameters, Mapping) or not parameters:
        raise SweepError(f"{where}.parameters: missing: give at least one key path with its "
                         "distribution")
    params = tuple(_read_parameter(k, v, raw, source) for k, v in parameters.items())
    paths = {p.path: p.key for p in params}
    for p in params:
        mirror = mirror_path(p.path, raw)
        if mirror is not None and mirror in paths:
            raise SweepError(f"{source}: sweep.parameters.{p.key!r} and {paths[mirror]!r}: the "
                             "inertia tensor is symmetric, one product of inertia moves both "
                             "entries; sweep one of them")
    # blame each key for what it alone breaks, before any combination is tried
    try:
        load_scene(raw, source=source)
        scene_error = None
    except SceneError as exc:
        scene_error = str(exc)
    for p in params:
        _check_alone(p, raw, source, scene_error)
    if design == "nominal":
        for p in params:
            if p.path[0] == "controller":
                raise SweepError(f"{source}: sweep.parameters.{p.key!r}: a controller setting "
                                 "has no effect with design = \"nominal\" (the controller is "
                                 "tuned once on the nominal scene); use design = \"per-sample\"")
    spec = SweepSpec(params, method, samples, levels, seed, design, controller, fit, worst,
                     evaluations, limit)
    n = spec.n_samples
    if n > limit:
        raise SweepError(f"{where}: {n} samples exceed the limit of {limit} (about "
                         f"{n * 0.03 / 3600:.3g} core-hours at 30 ms a sample); raise it with "
                         "max_samples in [sweep] or --max-samples")
    return spec


def check_box(spec: SweepSpec, raw: Mapping, source: str, sampled: np.ndarray | None = None
              ) -> None:
    """Refuse a box that reaches values the scene refuses, naming the parameter.

    Each parameter is set, the others nominal, to the ends of its worst-case box and (when
    ``sampled`` is given) to the smallest and largest value drawn, and the scene validated.
    Combinations that only fail together are left to the samples (recorded as failed).
    """
    for k, p in enumerate(spec.parameters):
        lo, hi = p.box()
        ends = [lo, hi]
        if sampled is not None and sampled.shape[0]:
            ends += [float(sampled[:, k].min()), float(sampled[:, k].max())]
        for value in sorted(set(ends)):
            values = spec.nominal.copy()
            values[k] = value
            try:
                load_scene(apply_values(raw, spec.parameters, values), source=source)
            except SceneError as exc:
                problem = str(exc).split(": ", 1)[-1]
                raise SweepError(f"{source}: sweep.parameters.{p.key!r} ({p.describe()}) "
                                 f"reaches {value:.6g}, which the scene refuses: {problem}"
                                 ) from None

