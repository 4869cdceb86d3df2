"""A sweep sample and a sweep end to end, before and after a change, measured in one run.

Two checkouts of flexsat (``--before PATH``, e.g. ``git worktree add /tmp/before <rev>``, and
this one), each measured in fresh processes that put their checkout first on the path, the
rounds alternating so that both see the same load:

1. ``sweep_sample``: one sample of the shipped sweep scene
   (``spacecraft/scene/embedded/sweeps/default.toml``: the paper's rod, LQR + Kalman held from
   the nominal scene, 2 modes of truth, the slew, the exact-beam verdict) in process, as a
   Dask worker runs it (one BLAS thread): :func:`spacecraft.sweep.evaluate.evaluate` on
   ``--samples`` samples after a warm-up, CPU (``time.process_time``) min and median;
2. ``three_axis_sample``: the same for the three_axis sweep scene
   (``spacecraft/scene/embedded/sweeps/three_axis.toml``: every sample judged on the exact
   beams through W6), ``--three-axis-samples`` samples;
3. ``planar_loop``: one planar design-loop evaluation of ``benchmarks/design_loop.py`` (the
   paper's rod, 20 modes), the loop that must not get slower;
4. ``end_to_end``: ``run_sweep`` of ``--end-to-end`` samples as ``flexsat sweep`` runs it: its
   own LocalCluster of 2 worker processes (start, the workers' imports, prepare, every sample
   streamed to Parquet, the report without plots and without the worst-case search). Wall
   time; the CPU time of this process (client and scheduler) and of its children (the
   workers and their nannies, ``resource.getrusage(RUSAGE_CHILDREN)`` once the cluster is
   closed); the load average before and after.

The 10,000-sample estimates scale the end-to-end run: its fixed part (everything but the
samples' stage, ``timings.samples`` of the summary) plus 10,000 / n times its samples' stage;
the CPU of both processes per sample times 10,000 over the two cores plus the fixed part; and,
for a quiet machine, the least CPU of a sample (1.) times 10,000 over the two cores plus the
fixed part (Dask's own CPU, a few per cent, left out).

Run::

    python benchmarks/sample_speed.py --before /tmp/before [--rounds 3] [--samples 60]
                                      [--three-axis-samples 10] [--end-to-end 1000]

Writes ``benchmarks/results/sample_speed.json`` and ``sample_speed.md``.

``--rod-modal-sum [SCENE]`` (default ``three_axis``) measures instead, in one process with one
BLAS thread, the damped rods' modal sum (the torsion and axial entries of W6,
``Rod._cantilever_modal_stiffness``) against the closed form with damping corrections it
replaced (the modal sum switched off): each sample evaluated both ways, alternating, CPU of
each; every column compared (the exact margins to rtol 1e-9, every other one equal). Writes
``sample_speed_rods.json`` and ``sample_speed_rods.md``.
"""

from __future__ import annotations

import _common  # noqa: F401  (BLAS threads, sys.path)

import argparse
import os
import sys
import textwrap
from pathlib import Path

from _common import (RESULTS, machine_info, markdown_table, revision, run_in_checkout,
                     write_json)

HERE = Path(__file__).resolve().parent.parent

CHILD = textwrap.dedent("""
    import json, os, resource, statistics, sys, tempfile, time, warnings
    tree, workload, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
    sys.path[:0] = [tree, os.path.join(tree, "benchmarks")]
    warnings.simplefilter("ignore")

    def load():
        return [round(x, 2) for x in os.getloadavg()]

    def timed(call, items):
        cpu, wall = [], []
        for item in items:
            c, w = time.process_time(), time.perf_counter()
            call(item)
            cpu.append(time.process_time() - c)
            wall.append(time.perf_counter() - w)
        return {"cpu_min_s": min(cpu), "cpu_median_s": statistics.median(cpu),
                "wall_min_s": min(wall), "wall_median_s": statistics.median(wall),
                "n": len(cpu), "cpu_s": cpu}

    before = load()
    if workload in ("sweep_sample", "three_axis_sample"):
        import spacecraft.sweep as S
        from spacecraft.sweep.evaluate import evaluate, prepare
        scene = None if workload == "sweep_sample" else "three_axis"
        raw, spec, source = S.load_sweep(scene, samples=n + 5)
        context = prepare(raw, spec, source)
        values = spec.values()
        for v in values[:5]:
            evaluate(context, v)
        out = timed(lambda v: evaluate(context, v), values[5:])
    elif workload == "planar_loop":
        import design_loop
        design_loop.evaluate()
        out = timed(lambda _: design_loop.evaluate(), range(n))
    else:
        from spacecraft.sweep import run_sweep
        with tempfile.TemporaryDirectory() as tmp:
            t, c = time.perf_counter(), time.process_time()
            result = run_sweep(None, samples=n, worst_case=False, out=os.path.join(tmp, "s"),
                               plots=False, progress=False, workers=2)
            wall, own = time.perf_counter() - t, time.process_time() - c
        children = resource.getrusage(resource.RUSAGE_CHILDREN)
        s = result.summary
        out = {"samples": n, "wall_s": wall, "client_scheduler_cpu_s": own,
               "workers_cpu_s": children.ru_utime + children.ru_stime,
               "timings": s["timings"], "executor": s["executor"],
               "failed": s["samples"]["failed"]}
    out["load_before"], out["load_after"] = before, load()
    print(json.dumps(out))
""")

WORKLOADS = {"sweep_sample": "one sample of the shipped sweep scene (CPU, one BLAS thread)",
             "three_axis_sample": "one sample of the three_axis sweep scene (CPU, one BLAS "
                                  "thread)",
             "planar_loop": "one planar design-loop evaluation (paper's rod, 20 modes)"}


def run_child(tree: Path, workload: str, n: int) -> dict:
    # a sample as a Dask worker runs it: one BLAS thread
    return run_in_checkout(tree, CHILD, tree, workload, n, what=workload,
                           blas="one" if workload.endswith("_sample") else "inherit")


def estimate(run: dict, n_target: int = 10_000, cores: int = 2) -> dict:
    """The end-to-end run scaled to n_target samples (module docstring)."""
    n = run["samples"]
    samples_s = run["timings"]["samples"]
    fixed = run["wall_s"] - samples_s
    cpu_per_sample = (run["workers_cpu_s"] + run["client_scheduler_cpu_s"]) / n
    return {"fixed_s": fixed, "scaled_wall_s": fixed + samples_s * n_target / n,
            "cpu_per_sample_s": cpu_per_sample,
            "quiet_wall_s": fixed + cpu_per_sample * n_target / cores}


def rod_modal_sum(scene: str, n: int) -> int:
    """``--rod-modal-sum`` (module docstring)."""
    import math
    import statistics
    import time
    import warnings

    from appendages.rod import Rod
    import spacecraft.sweep as S
    from spacecraft.sweep.evaluate import evaluate, prepare

    warnings.simplefilter("ignore")
    modal = Rod._cantilever_modal_stiffness
    raw, spec, source = S.load_sweep(scene, samples=n + 1)
    context = prepare(raw, spec, source)
    values = spec.values()
    evaluate(context, values[0])
    cpu = {"modal sum": [], "closed form": []}
    worst, differ = 0.0, []
    load_before = [round(x, 2) for x in os.getloadavg()]
    for i, v in enumerate(values[1:n + 1]):
        rows = {}
        for which in (("modal sum", "closed form") if i % 2 == 0
                      else ("closed form", "modal sum")):
            Rod._cantilever_modal_stiffness = (modal if which == "modal sum"
                                               else lambda self, s: None)
            c = time.process_time()
            rows[which] = evaluate(context, v)
            cpu[which].append(time.process_time() - c)
        Rod._cantilever_modal_stiffness = modal
        a, b = rows["modal sum"], rows["closed form"]
        for name in context.columns():
            if name in ("seconds",):
                continue
            x, y = a[name], b[name]
            if isinstance(x, float) and isinstance(y, float) and not (math.isnan(x)
                                                                      and math.isnan(y)):
                if x != y:
                    rel = abs(x - y) / max(abs(y), 1e-300)
                    if name.startswith("exact_"):
                        worst = max(worst, rel)
                    if not name.startswith("exact_") or rel > 1e-9:
                        differ.append((i, name, x, y))
            elif x != y and not (isinstance(x, float) and math.isnan(x)):
                differ.append((i, name, x, y))
    load_after = [round(x, 2) for x in os.getloadavg()]
    summary = {k: {"median_s": statistics.median(c), "min_s": min(c), "mean_s": sum(c) / len(c)}
               for k, c in cpu.items()}
    result = {"machine": machine_info(), "revision": revision(HERE), "scene": scene,
              "samples": n, "cpu_s": cpu, "summary": summary,
              "ratio_median": summary["modal sum"]["median_s"]
              / summary["closed form"]["median_s"],
              "largest_relative_difference_exact": worst, "differing": differ,
              "load_before": load_before, "load_after": load_after}
    write_json("sample_speed_rods.json", result)
    info = result["machine"]
    rows = [[k, f"{s['median_s'] * 1e3:.1f}", f"{s['min_s'] * 1e3:.1f}",
             f"{s['mean_s'] * 1e3:.1f}"] for k, s in summary.items()]
    text = "\n".join([
        f"# The damped rods' modal sum in a {scene} sweep sample: before and after, one process",
        "", f"`python benchmarks/sample_speed.py --rod-modal-sum {scene} --samples {n}` on "
        f"{info['date_utc']} UTC, {info['cpu']}, {info['nproc']} cores, one BLAS thread, "
        f"revision {result['revision']}; load average (1, 5, 15 min) {load_before} -> "
        f"{load_after}. Each sample evaluated with the rods' modal sum and with the closed "
        "form with damping corrections it replaced (the modal sum switched off), alternating "
        "which goes first; CPU (time.process_time) a sample.", "",
        markdown_table(["W6's torsion and axial entries by", "CPU median [ms]", "min [ms]",
                        "mean [ms]"], rows), "",
        f"After / before (median): {result['ratio_median']:.3f}. Every column the same number "
        f"but the exact-beam margins, which differ by at most "
        f"{worst:.1e} (relative; margins refined on the exact loop function); columns that "
        f"differ otherwise: {len(differ)}.", ""])
    (RESULTS / "sample_speed_rods.md").write_text(text)
    print(text)
    return 0 if not differ else 1


def main() -> int:
    if "--rod-modal-sum" in sys.argv:
        parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
        parser.add_argument("--rod-modal-sum", nargs="?", const="three_axis", metavar="SCENE")
        parser.add_argument("--samples", type=int, default=40)
        args = parser.parse_args()
        return rod_modal_sum(args.rod_modal_sum, args.samples)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, required=True,
                        help="a checkout of flexsat before the change")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--samples", type=int, default=60, help="sweep samples per round")
    parser.add_argument("--loops", type=int, default=15, help="planar loops per round")
    parser.add_argument("--three-axis-samples", type=int, default=10,
                        help="three_axis sweep samples per round")
    parser.add_argument("--end-to-end", type=int, default=1000,
                        help="samples of the end-to-end sweep (0: skip it)")
    args = parser.parse_args()
    trees = {"before": args.before.resolve(), "after": HERE}
    result = {"machine": machine_info(), "revisions": {k: revision(v) for k, v in trees.items()},
              "rounds": args.rounds, "workloads": {}}
    for workload in WORKLOADS:
        n = {"sweep_sample": args.samples, "three_axis_sample": args.three_axis_samples,
             "planar_loop": args.loops}[workload]
        runs = {"before": [], "after": []}
        for _ in range(args.rounds):
            for which, tree in trees.items():
                print(f"{workload} {which}...", file=sys.stderr)
                runs[which].append(run_child(tree, workload, n))
        best = {k: min(v, key=lambda r: r["cpu_median_s"]) for k, v in runs.items()}
        # each item (a sample, an evaluation) at its least CPU over the rounds: the same
        # work in both checkouts, each seen at its quietest moment
        least = {k: [min(r["cpu_s"][i] for r in v) for i in range(n)]
                 for k, v in runs.items()}
        mean = {k: sum(v) / n for k, v in least.items()}
        result["workloads"][workload] = {
            "runs": runs, "best": best, "least_mean_s": mean,
            "least_ratio": mean["after"] / mean["before"],
            "cpu_median_ratio": best["after"]["cpu_median_s"] / best["before"]["cpu_median_s"],
            "cpu_min_ratio": best["after"]["cpu_min_s"] / best["before"]["cpu_min_s"]}
    if args.end_to_end:
        ends = {}
        for which, tree in trees.items():
            print(f"end to end {which}...", file=sys.stderr)
            ends[which] = run_child(tree, "end_to_end", args.end_to_end)
            ends[which]["estimate_10000"] = estimate(ends[which])
            # a quiet machine: each sample at its least CPU, the two cores busy
            least = result["workloads"]["sweep_sample"]["least_mean_s"][which]
            ends[which]["estimate_10000"]["least_cpu_wall_s"] = (
                ends[which]["estimate_10000"]["fixed_s"] + least * 10_000 / 2)
        result["end_to_end"] = ends
    write_json("sample_speed.json", result)
    info = result["machine"]
    rows = []
    for workload, r in result["workloads"].items():
        for which in ("before", "after"):
            b = r["best"][which]
            rows.append([WORKLOADS[workload], which,
                         f"{r['least_mean_s'][which] * 1e3:.1f}",
                         f"{b['cpu_median_s'] * 1e3:.1f} / {b['cpu_min_s'] * 1e3:.1f}",
                         f"{b['wall_median_s'] * 1e3:.1f} / {b['wall_min_s'] * 1e3:.1f}",
                         f"{b['load_before']} -> {b['load_after']}"])
        rows.append([WORKLOADS[workload], "after / before", f"{r['least_ratio']:.2f}",
                     f"{r['cpu_median_ratio']:.2f} / {r['cpu_min_ratio']:.2f}", "", ""])
    lines = [
        "# A sweep sample and a sweep end to end: before and after, one run", "",
        f"`python benchmarks/sample_speed.py --before ...` on {info['date_utc']} UTC, "
        f"{info['cpu']}, {info['nproc']} cores; before: {result['revisions']['before']}, "
        f"after: {result['revisions']['after']}. Each checkout {args.rounds} rounds in fresh "
        "processes, alternating. 'Least CPU': the mean over the items (samples, evaluations) "
        "of each item's least CPU time over the rounds (the same work in both checkouts, each "
        "item at its quietest moment: the closest measure on a shared machine); then the "
        "best round (lowest median CPU) of each, the load average (1, 5, 15 min) before and "
        "after it.", "",
        markdown_table(["workload", "checkout", "least CPU [ms]", "CPU median / min [ms]",
                        "wall median / min [ms]", "load"], rows), ""]
    if args.end_to_end:
        rows = []
        for which, r in result["end_to_end"].items():
            e = r["estimate_10000"]
            rows.append([which, f"{r['wall_s']:.1f} s",
                         f"{r['timings']['samples']:.1f} s",
                         f"{r['workers_cpu_s'] / r['samples'] * 1e3:.1f} ms",
                         f"{r['client_scheduler_cpu_s']:.1f} s",
                         f"{e['scaled_wall_s']:.0f} s", f"{e['quiet_wall_s']:.0f} s",
                         f"{e['least_cpu_wall_s']:.0f} s",
                         f"{r['failed']}", f"{r['load_before']} -> {r['load_after']}"])
        lines += [f"`run_sweep` of {args.end_to_end} samples end to end (its own LocalCluster "
                  "of 2 workers, Parquet, the report without plots or worst-case search); "
                  "10,000 samples estimated by scaling the samples' stage, from the CPU "
                  "of both processes over the two cores, and (a quiet machine) from the least "
                  "CPU of a sample above over the two cores plus the run's fixed part:", "",
                  markdown_table(["checkout", "wall", "samples' stage",
                                  "workers' CPU a sample", "client + scheduler CPU",
                                  "10,000 scaled", "10,000 from CPU",
                                  "10,000 from least CPU", "failed", "load"], rows),
                  ""]
    text = "\n".join(lines)
    (RESULTS / "sample_speed.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
