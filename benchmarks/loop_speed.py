"""Where the design loop runs most, before and after a change, measured in one run.

Three workloads, each timed in a fresh process per round, the rounds alternating between two
checkouts of flexsat (``--before PATH``, e.g. ``git worktree add /tmp/before <rev>``, and this
one), so that both see the same load:

1. ``sweep_sample``: one sample of the shipped sweep scene
   (``spacecraft/scene/embedded/sweeps/default.toml``: the paper's rod, LQR + Kalman held from
   the nominal scene, 2 modes of truth, the slew, the exact-beam verdict):
   :func:`spacecraft.sweep.evaluate.evaluate` on ``--samples`` samples after a warm-up;
2. ``three_axis_loop``: one three-axis design-loop evaluation of ``benchmarks/three_axis.py``
   (two wings and a boom, 56 truth states; build, LQR, close, simulate, margins);
3. ``planar_loop``: one planar design-loop evaluation of ``benchmarks/design_loop.py`` (the
   paper's rod, 20 modes; build, LQR, close, simulate, margins).

CPU time (``time.process_time``: the machine is shared, so wall time measures the load as much
as the work) and wall time, min and median over the evaluations of a round, then the best
round of each checkout; ``uptime``'s load average beside every round. Ratios (after / before)
are taken from the same run.

Run::

    python benchmarks/loop_speed.py --before /tmp/before [--rounds 3] [--samples 60]
        [--workloads planar_loop ...] [--name loop_speed]

Writes ``benchmarks/results/<name>.json`` and ``<name>.md`` (``--name``, default ``loop_speed``).
"""

from __future__ import annotations

import _common  # noqa: F401  (BLAS threads, sys.path)

import argparse
import sys
import textwrap
from pathlib import Path

from _common import (RESULTS, machine_info, markdown_table, revision, run_in_checkout,
                     write_json)

HERE = Path(__file__).resolve().parent.parent

# the child: put the checkout first on the path, time one workload, print JSON
CHILD = textwrap.dedent("""
    import json, os, statistics, sys, time, warnings
    tree, workload, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
    sys.path[:0] = [tree, os.path.join(tree, "benchmarks")]
    warnings.simplefilter("ignore")

    def timed(call, items):
        cpu, wall = [], []
        for item in items:
            c, w = time.process_time(), time.perf_counter()
            call(item)
            cpu.append(time.process_time() - c)
            wall.append(time.perf_counter() - w)
        return cpu, wall

    if workload == "sweep_sample":
        import spacecraft.sweep as S
        from spacecraft.sweep.evaluate import evaluate, prepare
        raw, spec, source = S.load_sweep(None, samples=n)
        context = prepare(raw, spec, source)
        values = spec.values()
        evaluate(context, values[0])
        cpu, wall = timed(lambda v: evaluate(context, v), values)
    elif workload == "three_axis_loop":
        import three_axis
        chains = three_axis.design_chains()
        three_axis.evaluate(chains)
        cpu, wall = timed(lambda _: three_axis.evaluate(chains), range(n))
    else:
        import design_loop
        design_loop.evaluate()
        cpu, wall = timed(lambda _: design_loop.evaluate(), range(n))
    print(json.dumps({"cpu_min_s": min(cpu), "cpu_median_s": statistics.median(cpu),
                      "wall_min_s": min(wall), "wall_median_s": statistics.median(wall),
                      "n": len(cpu), "load": [round(x, 2) for x in os.getloadavg()]}))
""")

WORKLOADS = {"sweep_sample": "one sample of the shipped sweep scene (exact-beam verdict on)",
             "three_axis_loop": "one three-axis design-loop evaluation (56 truth states)",
             "planar_loop": "one planar design-loop evaluation (paper's rod, 20 modes)"}


def run_child(tree: Path, workload: str, n: int) -> dict:
    return run_in_checkout(tree, CHILD, tree, workload, n, what=workload)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, required=True,
                        help="a checkout of flexsat before the change")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--samples", type=int, default=60, help="sweep samples per round")
    parser.add_argument("--loops", type=int, default=15,
                        help="design-loop evaluations per round")
    parser.add_argument("--workloads", nargs="+", choices=list(WORKLOADS), default=list(WORKLOADS),
                        help="the workloads to time (default: all three)")
    parser.add_argument("--name", default="loop_speed",
                        help="the results' file name under benchmarks/results/ (no suffix)")
    args = parser.parse_args()
    trees = {"before": args.before.resolve(), "after": HERE}
    result = {"machine": machine_info(), "revisions": {k: revision(v) for k, v in trees.items()},
              "rounds": args.rounds, "workloads": {}}
    for workload in args.workloads:
        n = args.samples if workload == "sweep_sample" else args.loops
        runs = {"before": [], "after": []}
        for _ in range(args.rounds):
            for which, tree in trees.items():
                print(f"{workload} {which}...", file=sys.stderr)
                runs[which].append(run_child(tree, workload, n))
        best = {k: min(v, key=lambda r: r["cpu_median_s"]) for k, v in runs.items()}
        result["workloads"][workload] = {
            "runs": runs, "best": best,
            "cpu_median_ratio": best["after"]["cpu_median_s"] / best["before"]["cpu_median_s"],
            "cpu_min_ratio": best["after"]["cpu_min_s"] / best["before"]["cpu_min_s"],
            "wall_median_ratio": best["after"]["wall_median_s"] / best["before"]["wall_median_s"]}
    write_json(f"{args.name}.json", result)
    info = result["machine"]
    rows = []
    for workload, r in result["workloads"].items():
        for which in ("before", "after"):
            b = r["best"][which]
            rows.append([WORKLOADS[workload], which,
                         f"{b['cpu_median_s'] * 1e3:.1f} / {b['cpu_min_s'] * 1e3:.1f}",
                         f"{b['wall_median_s'] * 1e3:.1f} / {b['wall_min_s'] * 1e3:.1f}",
                         f"{b['load']}"])
        rows.append([WORKLOADS[workload], "after / before",
                     f"{r['cpu_median_ratio']:.2f} / {r['cpu_min_ratio']:.2f}",
                     f"{r['wall_median_ratio']:.2f}", ""])
    text = "\n".join([
        "# The design loop where it runs most: before and after, one run", "",
        f"`python benchmarks/loop_speed.py --before ...` on {info['date_utc']} UTC, "
        f"{info['cpu']}, {info['nproc']} cores, BLAS threads {info['blas_threads']}; before: "
        f"{result['revisions']['before']}, after: {result['revisions']['after']}. Each "
        f"checkout {args.rounds} rounds in fresh processes, alternating; the best round "
        "(lowest median CPU) of each; the load average (1, 5, 15 min) at its end.", "",
        markdown_table(["workload", "checkout", "CPU median / min [ms]",
                        "wall median / min [ms]", "load"], rows), ""])
    (RESULTS / f"{args.name}.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
