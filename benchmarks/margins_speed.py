"""The margins of the design loops before and after a change, in one process, alternating.

``controllers.margins`` of the three-axis design loop of benchmarks/three_axis.py (truth: each
beam 10 Craig-Bampton modes, 56 states, undamped; LQR + Kalman on the 3-body chains) and of the
planar one of benchmarks/design_loop.py (the paper's rod, 20 modes), timed with the
``controllers`` package of this checkout and with the one of another checkout (``--before``,
a path to a source tree, e.g. a ``git worktree`` of an older commit), one call of each in turn:
CPU time (time.process_time) of this process, one BLAS thread (the other helpers of a shared
machine take the other cores), the load average beside. Both get the same plant and controller
objects (built with this checkout); every margin of the two is compared.

Run::

    git worktree add /tmp/before <commit>
    OPENBLAS_NUM_THREADS=1 python benchmarks/margins_speed.py --before /tmp/before [--repeats 15]

Writes benchmarks/results/margins_speed.{json,md}.
"""

from __future__ import annotations

import _common  # noqa: F401  (first: BLAS threads, sys.path)

import argparse
import importlib
import math
import os
import shutil
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

from _common import (RESULTS, machine_info, markdown_table, paper_rod, spacecraft_with,
                     write_json)
import controllers
from appendages.chain import HingedChain

import design_loop
import three_axis


def loops() -> dict:
    """{name: (truth plant, controller)} of the two design loops."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        chains = iter(three_axis.design_chains())
        truth = three_axis.example(lambda b: b.truncated(three_axis.N_MODES)).plant(
            tip_deflection=True, prune=True)
        design = three_axis.example(lambda b: next(chains)).plant(prune=True)
        j, _ = controllers.principal_axes(controllers.rigid_body_inertia(design))
        three = controllers.lqr(design, attitude_weight=(j * 0.1 ** 2) ** 2, rate_weight=0.0,
                                torque_weight=1.0)
        beam = paper_rod()
        planar_truth = spacecraft_with(beam.truncated(design_loop.N_MODES)).plant(
            tip_deflection=True)
        chain = HingedChain.three_body(beam.length, beam.mass, 0.26989, 37.134)
        planar_design = spacecraft_with(chain).plant()
        J = controllers.rigid_body_inertia(planar_design)
        planar = controllers.lqr(planar_design, attitude_weight=(J * 0.1 ** 2) ** 2,
                                 rate_weight=0.0, torque_weight=1.0)
    return {"three_axis": (truth, three), "design_loop": (planar_truth, planar)}


def before_package(source: Path):
    """The ``controllers`` package of another checkout, imported as ``controllers_before``
    (its modules import each other relatively)."""
    folder = Path(tempfile.mkdtemp(prefix="margins_before_"))
    shutil.copytree(source / "controllers", folder / "controllers_before",
                    ignore=shutil.ignore_patterns("__pycache__"))
    sys.path.insert(0, str(folder))
    return importlib.import_module("controllers_before")


def flat(m) -> dict:
    """Every field of a Margins or MultiLoopMargins, per axis for the loops at a time."""
    out = {}
    for key, value in vars(m).items():
        if isinstance(value, dict):
            for axis, one in value.items():
                out.update({f"{k}_{axis}": v for k, v in vars(one).items()})
        else:
            out[key] = value
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, required=True,
                        help="source tree of the version to compare with")
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    before = before_package(args.before.resolve())
    info = machine_info()
    results: dict = {"machine": info, "before": str(args.before), "repeats": args.repeats,
                     "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS", "default"),
                     "loops": {}}
    rows = []
    for name, (plant, controller) in loops().items():
        old, new = flat(before.margins(plant, controller)), flat(controllers.margins(plant,
                                                                                    controller))
        worst = max((abs(new[k] - v) / abs(v) if v != 0 and math.isfinite(v) and new[k] != v
                     else 0.0) for k, v in old.items())
        times: dict = {"before": [], "after": []}
        load = [os.getloadavg()]
        for _ in range(args.repeats):
            for key, package in (("before", before), ("after", controllers)):
                t0 = time.process_time()
                package.margins(plant, controller)
                times[key].append(time.process_time() - t0)
        load.append(os.getloadavg())
        median = {k: statistics.median(v) for k, v in times.items()}
        results["loops"][name] = {"cpu_s": times, "median_cpu_s": median,
                                  "largest_relative_change": worst, "before": old,
                                  "after": new, "load_before_after": load}
        rows.append([name, f"{median['before'] * 1e3:.1f}", f"{median['after'] * 1e3:.1f}",
                     f"{median['after'] / median['before']:.2f}",
                     f"{min(times['before']) * 1e3:.1f}", f"{min(times['after']) * 1e3:.1f}",
                     f"{worst:.1e}", f"{load[0][0]:.1f} / {load[1][0]:.1f}"])
    write_json("margins_speed.json", results)
    text = "\n".join([
        "# Margins of the design loops, before and after",
        "",
        f"`python benchmarks/margins_speed.py --before {args.before}` on "
        f"{info.get('date_utc', '')} UTC, {info.get('cpu', '')}, BLAS threads "
        f"{results['blas_threads']}; {args.repeats} calls of each, alternating.",
        "",
        markdown_table(["loop", "before CPU median [ms]", "after CPU median [ms]", "ratio",
                        "before min [ms]", "after min [ms]", "largest relative change of a "
                        "margin", "load (1 min) before / after"], rows),
    ])
    (RESULTS / "margins_speed.md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
