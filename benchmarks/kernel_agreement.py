"""Does any shipped scene's result depend on the CPU's BLAS kernel?

Runs every embedded scene (``flexsat run SCENE --no-fmu --no-plots``) under three OpenBLAS
kernels -- the machine's own, ``OPENBLAS_CORETYPE=Prescott`` (SSE3 only) and
``OPENBLAS_NUM_THREADS=4 OPENBLAS_CORETYPE=Haswell`` -- and two sweeps (``default``, 200
samples, and ``three_axis``, 20 samples, no worst-case search) under the first two, then
compares the outputs against the machine's own kernel:

- every discrete item (strings, booleans, integers, ``None``, list lengths, dictionary keys,
  non-float Parquet columns) must be identical; a string that differs only in its numbers is
  counted as a number difference (its numbers compared as floats), any other string difference
  is discrete;
- every float is compared by ``|a - b| / max(|a|, |b|)``; the largest per key name is listed, so
  the figures of one kind (frequencies, margins, times, gains) can be read off.  A float whose
  both values are below ``1e-300`` in magnitude counts as equal.

The report.md texts are compared the same way (their numbers masked).

Usage::

    PYTHONPATH=$PWD python benchmarks/kernel_agreement.py [--work DIR] [--reuse]

writes ``benchmarks/results/kernel_agreement.{json,md}``.  ``--reuse`` compares the runs
already in ``--work`` (default ``/tmp/flexsat-kernel-agreement``) without rerunning them.
About 3 minutes on one core.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

__all__ = ["KERNELS", "SCENES", "SWEEPS", "compare_json", "compare_text", "main"]

KERNELS = {
    "default": {},
    "prescott": {"OPENBLAS_CORETYPE": "Prescott"},
    "haswell4": {"OPENBLAS_NUM_THREADS": "4", "OPENBLAS_CORETYPE": "Haswell"},
}
SCENES = ("default", "default_flown", "hinged_wing", "real_appendages", "real_appendages_3d",
          "single_boom", "three_axis", "three_axis_flown", "two_wings")
SWEEPS = {"default": 200, "three_axis": 20}
SWEEP_KERNELS = ("default", "prescott")

_NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")
_TINY = 1e-300
# run times and time stamps, not results
_IGNORED = {"created", "started", "finished", "seconds", "per_sample_median", "per_sample_mean",
            "samples", "nominal_evaluation", "prepare", "parquet:seconds", "worst_case",
            "created (text)", "started (text)", "finished (text)"}


def _numeric(x) -> bool:
    if isinstance(x, list):
        return all(_numeric(v) for v in x)
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def _flat(x) -> list:
    return [float(w) for v in x for w in _flat(v)] if isinstance(x, list) else [float(x)]


def _rel(a: float, b: float) -> float:
    if a == b:
        return 0.0
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.inf
    scale = max(abs(a), abs(b))
    if scale < _TINY:
        return 0.0
    return abs(a - b) / scale


class _Diff:
    """The differences between two outputs: discrete ones and the largest float ones."""

    def __init__(self) -> None:
        self.discrete: list[str] = []
        self.numbers: dict[str, tuple[float, str, float, float]] = {}
        self.signs: dict[str, list[str]] = {}

    def number(self, key: str, path: str, a: float, b: float, scale: float = 0.0) -> None:
        if key in _IGNORED:
            return
        r = _rel(a, b) if scale <= 0.0 else min(_rel(a, b), abs(a - b) / scale)
        flipped = _rel(a, -b) if scale <= 0.0 else min(_rel(a, -b), abs(a + b) / scale)
        if r > 1e-6 and flipped < 1e-6:
            # the same figure of the opposite sign: a sign convention the solver chose
            self.signs.setdefault(key, []).append(path)
            return
        if key not in self.numbers or r > self.numbers[key][0]:
            self.numbers[key] = (r, path, a, b)

    def as_dict(self) -> dict:
        every = {k: {"rel": v[0]} for k, v in self.numbers.items()}
        return {"discrete": self.discrete,
                "by_kind": {k: {"rel": v[0], "key": v[1]} for k, v in _by_kind(every).items()},
                "sign_flips": {k: {"count": len(v), "first": v[:5]} for k, v in self.signs.items()},
                "numbers": {k: {"rel": v[0], "path": v[1], "a": v[2], "b": v[3]}
                            for k, v in sorted(self.numbers.items(),
                                               key=lambda kv: -kv[1][0])[:60]
                            if v[0] > 0.0}}


def compare_text(a: str, b: str, key: str, path: str, diff: _Diff) -> None:
    """Compare two strings: discrete if they differ beyond their numbers."""
    if a == b:
        return
    if _NUMBER.sub("#", a) != _NUMBER.sub("#", b):
        diff.discrete.append(f"{path}: {a!r} != {b!r}")
        return
    for x, y in zip(_NUMBER.findall(a), _NUMBER.findall(b)):
        diff.number(key + " (text)", path, float(x), float(y))


def compare_json(a, b, path: str = "", key: str = "", diff: _Diff | None = None) -> _Diff:
    """Compare two JSON trees; floats by relative difference, everything else exactly."""
    diff = _Diff() if diff is None else diff
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            diff.discrete.append(f"{path}: keys {sorted(set(a) ^ set(b))} in one only")
        for k in a.keys() & b.keys():
            if k in ("seconds", "timings") or k in _IGNORED:
                continue  # run times, not results
            compare_json(a[k], b[k], f"{path}/{k}", str(k), diff)
    elif isinstance(a, list) and isinstance(b, list) and _numeric(a) and _numeric(b) \
            and len(a) == len(b) and a:
        # an array: each entry relative to the array's largest (a norm-wise difference)
        fa, fb = _flat(a), _flat(b)
        if len(fa) != len(fb):
            diff.discrete.append(f"{path}: shape differs")
            return diff
        finite = [abs(x) for x in fa + fb if math.isfinite(x)]
        scale = max(finite, default=0.0)
        for i, (x, y) in enumerate(zip(fa, fb)):
            if math.isfinite(x) != math.isfinite(y) or (not math.isfinite(x) and x != y):
                diff.discrete.append(f"{path}[{i}]: {x!r} != {y!r}")
            elif math.isfinite(x):
                diff.number(key, f"{path}[{i}]", x, y, scale)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            diff.discrete.append(f"{path}: length {len(a)} != {len(b)}")
        for i, (x, y) in enumerate(zip(a, b)):
            compare_json(x, y, f"{path}[{i}]", key, diff)
    elif (isinstance(a, float) and isinstance(b, (int, float)) and not isinstance(b, bool)) or \
            (isinstance(b, float) and isinstance(a, (int, float)) and not isinstance(a, bool)):
        diff.number(key, path, float(a), float(b))
    elif isinstance(a, str) and isinstance(b, str):
        compare_text(a, b, key, path, diff)
    elif a != b or type(a) is not type(b):
        diff.discrete.append(f"{path}: {a!r} != {b!r}")
    return diff


def _compare_report(a: Path, b: Path, diff: _Diff) -> None:
    la, lb = a.read_text().splitlines(), b.read_text().splitlines()
    if len(la) != len(lb):
        diff.discrete.append(f"report.md: {len(la)} != {len(lb)} lines")
    timings = False
    for i, (x, y) in enumerate(zip(la, lb)):
        if x.startswith("#"):
            timings = x.strip("# ").lower() == "timings"  # a sweep's run times
        if timings or "time per stage" in x:  # run times, not results
            continue
        compare_text(x, y, "report.md", f"report.md:{i + 1}", diff)


def _compare_parquet(a: Path, b: Path, diff: _Diff) -> None:
    import numpy as np
    import pandas as pd

    da, db = pd.read_parquet(a), pd.read_parquet(b)
    if list(da.columns) != list(db.columns) or len(da) != len(db):
        diff.discrete.append(f"{a.name}: shape/columns {da.shape} != {db.shape}")
        return
    for c in da.columns:
        x, y = da[c].to_numpy(), db[c].to_numpy()
        if x.dtype.kind == "f" and y.dtype.kind == "f":
            nan = np.isnan(x) | np.isnan(y)
            if (np.isnan(x) != np.isnan(y)).any():
                diff.discrete.append(f"{a.name}:{c}: NaN in rows "
                                     f"{np.flatnonzero(np.isnan(x) != np.isnan(y)).tolist()[:10]}")
            for i in np.flatnonzero(~nan):
                diff.number(f"parquet:{c}", f"{a.name}:{c}[{i}]", float(x[i]), float(y[i]))
        else:
            bad = [i for i, (p, q) in enumerate(zip(x, y)) if not (p == q or (p != p and q != q))]
            if bad:
                diff.discrete.append(f"{a.name}:{c}: rows {bad[:10]} differ, e.g. "
                                     f"{x[bad[0]]!r} != {y[bad[0]]!r}")


# kinds of figure, by the key's name (first match wins); differences of near-equal models
# (agreement tables, fidelity trials' changes, peak differences) are round-off by construction
_KINDS = [("agreement", r"relative_error|changes|peak_difference|_error$|^largest$|difference"),
          ("text", r"\(text\)|report\.md"),
          ("frequency", r"freq|band|natural|omega_n|estimator_poles|poles"),
          ("margin", r"margin|singular|least_damping|damping"),
          ("time", r"settl|rise|time|delay"),
          ("gain", r"^(K|L|A|B|C|D|Kp|Kd)$|gain|weight"),
          ("response", r"peak|deflection|twist|overshoot|residual|torque|attitude")]


def _by_kind(numbers: dict) -> dict:
    out: dict = {}
    for key, v in numbers.items():
        kind = next((k for k, rx in _KINDS if re.search(rx, key)), "other")
        if kind not in out or v["rel"] > out[kind][0]:
            out[kind] = (v["rel"], key)
    return out


def _run(argv: list[str], env_extra: dict, log: Path) -> int:
    env = dict(os.environ, **env_extra)
    with log.open("w") as f:
        return subprocess.call([sys.executable, "-m", "spacecraft.cli", *argv],
                               env=env, stdout=f, stderr=subprocess.STDOUT)


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--work", type=Path, default=Path("/tmp/flexsat-kernel-agreement"))
    parser.add_argument("--reuse", action="store_true")
    args = parser.parse_args(argv)
    work: Path = args.work
    runs = [(k, s, ["run", s, "--no-fmu", "--no-plots", "--quiet"]) for k in KERNELS
            for s in SCENES]
    runs += [(k, f"sweep_{s}", ["sweep", s, "--samples", str(n), "--no-worst-case",
                                "--no-plots", "--quiet", "--workers", "1"])
             for k in SWEEP_KERNELS for s, n in SWEEPS.items()]
    rcs = {}
    for kernel, name, cmd in runs:
        out = work / kernel / name
        if not args.reuse:
            out.parent.mkdir(parents=True, exist_ok=True)
            rcs[f"{kernel}/{name}"] = _run([*cmd, "--out", str(out)], KERNELS[kernel],
                                           work / f"{kernel}.{name}.log")
    result: dict = {"kernels": KERNELS, "return_codes": rcs, "comparisons": {}}
    for kernel, name, _ in runs:
        if kernel == "default":
            continue
        a, b = work / "default" / name, work / kernel / name
        diff = _Diff()
        for fname in ("results.json", "summary.json", "sweep.json"):
            if (a / fname).exists() or (b / fname).exists():
                if not ((a / fname).exists() and (b / fname).exists()):
                    diff.discrete.append(f"{fname} missing in one run")
                    continue
                compare_json(json.loads((a / fname).read_text()),
                             json.loads((b / fname).read_text()), fname, "", diff)
        if (a / "report.md").exists() and (b / "report.md").exists():
            _compare_report(a / "report.md", b / "report.md", diff)
        for pq in sorted(a.rglob("*.parquet")):
            _compare_parquet(pq, b / pq.relative_to(a), diff)
        result["comparisons"][f"{name} ({kernel})"] = diff.as_dict()
    here = Path(__file__).parent / "results"
    here.mkdir(exist_ok=True)
    (here / "kernel_agreement.json").write_text(json.dumps(result, indent=0, default=str))
    lines = ["# Kernel agreement: the default kernel vs Prescott and Haswell (4 threads)", "",
             "Relative difference |a - b| / max(|a|, |b|); an array's entries relative to the "
             "array's largest; a figure that is itself round-off (a mode's torque "
             "participation of 1e-25, a difference between two models) differs by up to 2, so "
             "read a large entry with its key and values in kernel_agreement.json. Kinds: " + "; ".join(f"{k}: /{v}/" for k, v in _KINDS), "",
             "| run | discrete | sign flips (keys) | " + " | ".join(k for k, _ in _KINDS)
             + " | other (key) |", "|---" * (4 + len(_KINDS)) + "|"]
    for name, d in result["comparisons"].items():
        kinds = {k: (v["rel"], v["key"]) for k, v in d["by_kind"].items()}
        flips = ", ".join(f"{k} {v['count']}" for k, v in d["sign_flips"].items()) or "-"
        cells = [f"{kinds[k][0]:.1e}" if k in kinds else "-" for k, _ in _KINDS]
        other = kinds.get("other")
        cells.append(f"{other[0]:.1e} ({other[1]})" if other else "-")
        lines.append(f"| {name} | {len(d['discrete'])} | {flips} | " + " | ".join(cells) + " |")
    for name, d in result["comparisons"].items():
        if d["discrete"]:
            lines += ["", f"## {name}: discrete differences", ""]
            lines += [f"- `{x}`" for x in d["discrete"][:40]]
    (here / "kernel_agreement.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return result


if __name__ == "__main__":
    main()
