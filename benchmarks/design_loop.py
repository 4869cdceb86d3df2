"""Cost of one whole design-loop evaluation, stage by stage, and where it goes (issue 3, 6).

One evaluation (the default scenario of benchmarks/_common.py):

1. ``build_truth``: the paper's rod truncated to 20 modes (Craig-Bampton), on the default hub,
   ``Spacecraft.plant(tip_deflection=True)``;
2. ``build_design``: the paper's three-body chain (k_L = 0.26989, c = 37.134 N*m) on the same
   hub, its plant;
3. ``lqr``: ``controllers.lqr`` on the chain plant (LQR + Kalman filter; weights giving a
   0.1 rad/s, 1/sqrt(2) rigid-body regulator: q_theta = (J wn**2)**2, q_omega = 0, r = 1);
4. ``close_loop``: the chain-tuned controller on the 20-mode beam plant;
5. ``simulate``: the slew (10 deg in 60 s), 100 s at 100 Hz, ``controllers.simulate``;
6. ``margins``: ``controllers.margins`` of the loop on the beam plant.

Also timed once per run, outside the loop: ``fit_chain`` (flexsat's 3-body fit; a design
computes it once). Medians of ``--repeats`` evaluations; then a cProfile of ``--profile``
evaluations, the top functions by own time and by cumulative time.

Run::

    python benchmarks/design_loop.py [--repeats 20] [--profile 10]

Writes benchmarks/results/design_loop.json and .md.
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import argparse
import cProfile
import io
import pstats
import statistics
import sys
import time
import warnings

import numpy as np

from _common import (RESULTS, machine_info, markdown_table, paper_rod, slew_inputs,
                     spacecraft_with, write_json)

import controllers
from appendages.chain import HingedChain

T = np.arange(10001) * 0.01  # 100 s at 100 Hz
N_MODES = 20


def evaluate(times: dict | None = None):
    """One design-loop evaluation; stage times [s] added to ``times`` when given."""
    clock = time.perf_counter
    t0 = clock()
    beam = paper_rod()
    truth = spacecraft_with(beam.truncated(N_MODES)).plant(tip_deflection=True)
    t1 = clock()
    chain = HingedChain.three_body(beam.length, beam.mass, 0.26989, 37.134)
    design = spacecraft_with(chain).plant()
    t2 = clock()
    J = controllers.rigid_body_inertia(design)
    controller = controllers.lqr(design, attitude_weight=(J * 0.1**2) ** 2, rate_weight=0.0,
                                 torque_weight=1.0)
    t3 = clock()
    loop = controllers.close_loop(truth, controller)
    t4 = clock()
    response = controllers.simulate(loop, T, slew_inputs(loop, T))
    t5 = clock()
    margins = controllers.margins(truth, controller)
    t6 = clock()
    if times is not None:
        for key, value in (("build_truth", t1 - t0), ("build_design", t2 - t1), ("lqr", t3 - t2),
                           ("close_loop", t4 - t3), ("simulate", t5 - t4),
                           ("margins", t6 - t5), ("total", t6 - t0)):
            times.setdefault(key, []).append(value)
    return response, margins


def profile(n: int, top: int = 25) -> dict:
    profiler = cProfile.Profile()
    profiler.enable()
    for _ in range(n):
        evaluate()
    profiler.disable()
    out = {}
    for key in ("tottime", "cumulative"):
        stream = io.StringIO()
        stats = pstats.Stats(profiler, stream=stream).strip_dirs().sort_stats(key)
        stats.print_stats(top)
        out[key] = stream.getvalue()
    # structured top list by own time, per evaluation
    stats = pstats.Stats(profiler)
    rows = []
    for (filename, line, name), (cc, nc, tt, ct, _) in stats.stats.items():
        rows.append({"function": f"{filename}:{line}({name})", "calls": nc / n,
                     "tottime_ms": tt / n * 1e3, "cumtime_ms": ct / n * 1e3})
    out["top_by_tottime"] = sorted(rows, key=lambda r: -r["tottime_ms"])[:top]
    out["top_by_cumtime"] = sorted(rows, key=lambda r: -r["cumtime_ms"])[:top]
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--profile", type=int, default=10)
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    evaluate()  # warm-up: imports, caches of the first call
    times: dict = {}
    for _ in range(args.repeats):
        evaluate(times)
    medians = {k: statistics.median(v) for k, v in times.items()}
    spreads = {k: (min(v), max(v)) for k, v in times.items()}
    response, margins = evaluate()
    beam = paper_rod()
    t0 = time.perf_counter()
    try:
        from appendages.equivalence import fit_chain

        fit_chain(beam, 3)
        fit_time = time.perf_counter() - t0
    except ImportError:
        fit_time = None
    prof = profile(args.profile)
    result = {"machine": machine_info(), "repeats": args.repeats, "median_s": medians,
              "min_max_s": spreads, "fit_chain_3_bodies_s": fit_time,
              "margins": margins.as_dict() if hasattr(margins, "as_dict") else str(margins),
              "profile_evaluations": args.profile,
              "profile_top_by_tottime": prof["top_by_tottime"],
              "profile_top_by_cumtime": prof["top_by_cumtime"]}
    write_json("design_loop.json", result)
    m = result["machine"]
    lines = ["# One design-loop evaluation", "",
             f"`python benchmarks/design_loop.py` on {m['date_utc']} UTC ({m['cpu']}, "
             f"{m['nproc']} cores). Medians of {args.repeats} evaluations (after a warm-up).", "",
             markdown_table(["stage", "median [ms]", "min [ms]", "max [ms]"],
                            [[k, f"{medians[k] * 1e3:.2f}", f"{spreads[k][0] * 1e3:.2f}",
                              f"{spreads[k][1] * 1e3:.2f}"] for k in medians]), "",
             f"fit_chain(beam, 3) (once per design, not in the loop): "
             f"{'-' if fit_time is None else f'{fit_time:.3f} s'}", "",
             f"Margins of the chain-tuned LQR on the 20-mode beam: {result['margins']}", "",
             f"## Profile: top functions by own time, per evaluation ({args.profile} profiled)",
             "",
             markdown_table(["function", "calls", "own [ms]", "cumulative [ms]"],
                            [[r["function"], f"{r['calls']:.0f}", f"{r['tottime_ms']:.3f}",
                              f"{r['cumtime_ms']:.3f}"] for r in prof["top_by_tottime"][:20]]),
             "", "## Profile: top functions by cumulative time", "",
             markdown_table(["function", "calls", "own [ms]", "cumulative [ms]"],
                            [[r["function"], f"{r['calls']:.0f}", f"{r['tottime_ms']:.3f}",
                              f"{r['cumtime_ms']:.3f}"] for r in prof["top_by_cumtime"][:25]]),
             ""]
    text = "\n".join(lines)
    (RESULTS / "design_loop.md").write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
