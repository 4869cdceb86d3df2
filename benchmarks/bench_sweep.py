"""Cost of a sweep (issue 13): one sample, Dask's per-task overhead, 1 -> 2 worker speed-up,
10,000 samples of the default sweep scene.

Measured on the shipped sweep scene (``spacecraft/scenes/sweeps/default.toml``: the paper's rod
on a 100 kg hub, LQR + Kalman tuned on the fitted 3-body chain and held (design = "nominal"),
2 modes of truth, the slew, every sample also closed on the exact beam), no FMUs and no plots:

1. ``per_sample``: one evaluation (:func:`spacecraft.sweep.evaluate.evaluate`) in this process,
   median over ``--samples-per-sample`` samples after a warm-up, with the stage costs of a
   cProfile run; beside it one ``spacecraft.run`` of the same one-loop scene (the runner refits
   the chain, picks the fidelity and builds the equivalence data every time);
2. ``task_overhead``: on a LocalCluster of 2 single-threaded worker processes, the wall time
   per task of tasks that evaluate no sample (``evaluate_batch`` on an empty batch: argument
   transfer, scheduling, result), 2 x 200 tasks in flight as the sweep keeps them; its ratio
   to a task of the sweep (``TASK_SECONDS`` of work);
3. ``speed_up``: the same ``--speed-up-samples`` samples on LocalClusters of 1 and 2 workers
   (cluster started and warmed before the clock), median of ``--repeats`` runs each;
4. ``ten_thousand``: ``run_sweep`` of 10,000 samples end to end (read, prepare, local cluster,
   samples streamed to Parquet, report without plots), no worst-case search; then the shipped
   scene as shipped (1000 samples and the worst-case search, its worst case).

Every figure carries the load average (``os.getloadavg``) before and after it: the machine has
2 cores and is shared, so a speed-up measured under load measures the load.

Run::

    python benchmarks/bench_sweep.py [--quick] [--only-per-sample]

Writes ``benchmarks/results/sweep.json`` and ``sweep.md`` (``--only-per-sample``:
``sweep_per_sample.json``, the first item alone, with CPU times beside wall times: on a loaded
machine the process's CPU time is the closer measure of the work).
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import argparse
import cProfile
import io
import logging
import os
import pstats
import statistics
import sys
import tempfile
import time
from pathlib import Path

from _common import RESULTS, machine_info, markdown_table, write_json


def load() -> list[float]:
    return [round(x, 2) for x in os.getloadavg()]


def per_sample(n: int) -> dict:
    import spacecraft.sweep as S
    from spacecraft.runner import run
    from spacecraft.scene import load_scene
    from spacecraft.sweep.evaluate import apply_values, evaluate, prepare

    raw, spec, source = S.load_sweep(None, samples=n)
    context = prepare(raw, spec, source)
    values = spec.values()
    evaluate(context, values[0])
    before = load()
    times, cpu = [], []
    for v in values:
        t, c = time.perf_counter(), time.process_time()
        evaluate(context, v)
        times.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    after = load()
    # the same without the exact-beam verdict (outputs.exact_reference = false)
    raw["outputs"]["exact_reference"] = False
    lean = prepare(raw, spec, source)
    evaluate(lean, values[0])
    lean_cpu = []
    for v in values:
        c = time.process_time()
        evaluate(lean, v)
        lean_cpu.append(time.process_time() - c)
    profiler = cProfile.Profile()
    profiler.enable()
    for v in values[: max(5, n // 4)]:
        evaluate(context, v)
    profiler.disable()
    stream = io.StringIO()
    pstats.Stats(profiler, stream=stream).strip_dirs().sort_stats("cumulative").print_stats(25)
    scene = load_scene(apply_values(context.base, context.parameters, spec.nominal))
    run(scene)
    runner_times = []
    for _ in range(3):
        t = time.perf_counter()
        run(scene)
        runner_times.append(time.perf_counter() - t)
    return {"median_s": statistics.median(times), "min_s": min(times), "max_s": max(times),
            "cpu_median_s": statistics.median(cpu),
            "without_exact_cpu_median_s": statistics.median(lean_cpu),
            "n": len(times), "load_before": before, "load_after": after,
            "runner_run_median_s": statistics.median(runner_times),
            "profile": stream.getvalue()}


def cluster(n_workers: int):
    from distributed import Client, LocalCluster

    c = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True,
                     dashboard_address=None, silence_logs=logging.ERROR)
    return c, Client(c, set_as_default=False)


def task_overhead(n_tasks: int) -> dict:
    import numpy as np
    import spacecraft.sweep as S
    from spacecraft.sweep.evaluate import prepare
    from spacecraft.sweep.execute import Executor, TASK_SECONDS

    raw, spec, source = S.load_sweep(None, samples=10)
    context = prepare(raw, spec, source)
    c, client = cluster(2)
    try:
        executor = Executor("client", client, 2)
        empty = [([], np.zeros((0, len(spec.parameters))))] * n_tasks
        list(executor.run(context, empty[:20]))          # warm-up: imports, context scatter
        before = load()
        t = time.perf_counter()
        for _ in executor.run(context, empty):
            pass
        wall = time.perf_counter() - t
        after = load()
    finally:
        client.close()
        c.close()
    # two workers run tasks side by side: per task of one worker, the overhead is 2 x wall / n
    per_task = 2.0 * wall / n_tasks
    return {"tasks": n_tasks, "wall_s": wall, "per_task_s": per_task,
            "task_seconds": TASK_SECONDS, "fraction_of_a_task": per_task / TASK_SECONDS,
            "load_before": before,
            "load_after": after}


def speed_up(n: int, repeats: int) -> dict:
    import spacecraft.sweep as S
    from spacecraft.sweep.evaluate import evaluate, prepare
    from spacecraft.sweep.execute import Executor, run_samples

    raw, spec, source = S.load_sweep(None, samples=n)
    context = prepare(raw, spec, source)
    t = time.perf_counter()
    evaluate(context, spec.nominal)
    evaluate(context, spec.nominal)
    one = (time.perf_counter() - t) / 2
    out = {"samples": n, "repeats": repeats}
    for workers in (1, 2):
        c, client = cluster(workers)
        try:
            executor = Executor("client", client, workers)
            run_samples(context, spec, executor, seconds_per_sample=one, progress=False)  # warm
            walls, loads = [], []
            for _ in range(repeats):
                loads.append(load())
                t = time.perf_counter()
                _, info = run_samples(context, spec, executor, seconds_per_sample=one,
                                      progress=False)
                walls.append(time.perf_counter() - t)
            loads.append(load())
        finally:
            client.close()
            c.close()
        out[f"workers_{workers}"] = {"median_s": statistics.median(walls), "runs_s": walls,
                                     "batch": info["batch"], "tasks": info["tasks"],
                                     "loads": loads}
    out["speed_up"] = out["workers_1"]["median_s"] / out["workers_2"]["median_s"]
    return out


def ten_thousand(n: int) -> dict:
    from spacecraft.sweep import run_sweep

    with tempfile.TemporaryDirectory() as tmp:
        before = load()
        t = time.perf_counter()
        result = run_sweep(None, samples=n, worst_case=False, out=Path(tmp) / "sweep",
                           plots=False, progress=False)
        wall = time.perf_counter() - t
        after = load()
    s = result.summary
    return {"samples": n, "wall_s": wall, "load_before": before, "load_after": after,
            "executor": s["executor"], "timings": s["timings"], "failed": s["samples"]["failed"],
            "instability": s["instability"]}


def shipped() -> dict:
    from spacecraft.sweep import run_sweep

    with tempfile.TemporaryDirectory() as tmp:
        before = load()
        t = time.perf_counter()
        result = run_sweep(None, out=Path(tmp) / "sweep", progress=False)
        wall = time.perf_counter() - t
        after = load()
    s = result.summary
    return {"wall_s": wall, "load_before": before, "load_after": after,
            "executor": s["executor"], "timings": s["timings"], "samples": s["samples"],
            "instability": s["instability"], "sensitivity": s["sensitivity"],
            "worst_case": s["worst_case"], "nominal": s["nominal"]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small counts (a smoke run)")
    parser.add_argument("--samples-per-sample", type=int, default=40)
    parser.add_argument("--speed-up-samples", type=int, default=400)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--tasks", type=int, default=400)
    parser.add_argument("--big", type=int, default=10_000)
    parser.add_argument("--skip-shipped", action="store_true")
    parser.add_argument("--only-per-sample", action="store_true",
                        help="measure one sample only (sweep_per_sample.json)")
    args = parser.parse_args(argv)
    if args.only_per_sample:
        result = {"machine": machine_info(), "per_sample": per_sample(args.samples_per_sample)}
        write_json("sweep_per_sample.json", result)
        p = result["per_sample"]
        print(f"one sample: {p['median_s'] * 1e3:.1f} ms wall, {p['cpu_median_s'] * 1e3:.1f} ms "
              f"CPU, {p['without_exact_cpu_median_s'] * 1e3:.1f} ms CPU without the exact-beam "
              f"verdict; load {p['load_before']} -> {p['load_after']}")
        return 0
    if args.quick:
        args.samples_per_sample, args.speed_up_samples, args.repeats = 10, 40, 2
        args.tasks, args.big = 40, 100
    result = {"machine": machine_info()}
    print("per sample...", file=sys.stderr)
    result["per_sample"] = per_sample(args.samples_per_sample)
    print("task overhead...", file=sys.stderr)
    result["task_overhead"] = task_overhead(args.tasks)
    print("speed-up...", file=sys.stderr)
    result["speed_up"] = speed_up(args.speed_up_samples, args.repeats)
    print(f"{args.big} samples...", file=sys.stderr)
    result["ten_thousand"] = ten_thousand(args.big)
    if not args.skip_shipped:
        print("the shipped scene...", file=sys.stderr)
        result["shipped"] = shipped()
    name = "sweep_quick" if args.quick else "sweep"
    write_json(f"{name}.json", result)
    p, o, s, b = (result["per_sample"], result["task_overhead"], result["speed_up"],
                  result["ten_thousand"])
    rows = [
        ["one sample (median)", f"{p['median_s'] * 1e3:.1f} ms wall, "
         f"{p['cpu_median_s'] * 1e3:.1f} ms CPU", f"{p['load_before']}"],
        ["one sample without the exact-beam verdict (CPU)",
         f"{p['without_exact_cpu_median_s'] * 1e3:.1f} ms", f"{p['load_after']}"],
        ["spacecraft.run of the same scene (median of 3)",
         f"{p['runner_run_median_s'] * 1e3:.0f} ms", f"{p['load_after']}"],
        ["Dask per-task overhead", f"{o['per_task_s'] * 1e3:.2f} ms "
         f"({100 * o['fraction_of_a_task']:.2f} % of a {o.get('task_seconds', 0.5):g} s task)",
         f"{o['load_before']}"],
        [f"{s['samples']} samples, 1 worker (median of {s['repeats']})",
         f"{s['workers_1']['median_s']:.2f} s", f"{s['workers_1']['loads']}"],
        [f"{s['samples']} samples, 2 workers", f"{s['workers_2']['median_s']:.2f} s",
         f"{s['workers_2']['loads']}"],
        ["speed-up 1 -> 2 workers", f"{s['speed_up']:.2f}x", ""],
        [f"{b['samples']} samples end to end ({b['executor']})", f"{b['wall_s']:.1f} s",
         f"{b['load_before']} -> {b['load_after']}"],
    ]
    lines = ["# Sweep benchmark", "",
             f"`python benchmarks/bench_sweep.py` on {result['machine']['date_utc']} UTC "
             f"({result['machine']['cpu']}, {result['machine']['nproc']} cores, shared).", "",
             markdown_table(["what", "time", "load average (1, 5, 15 min)"], rows), ""]
    if "shipped" in result:
        sh = result["shipped"]
        lines += [f"Shipped scene as shipped: {sh['wall_s']:.1f} s ({sh['executor']}), "
                  f"probability of instability {sh['instability']['probability']:.4g} "
                  f"(95 % {sh['instability']['interval'][0]:.3g} to "
                  f"{sh['instability']['interval'][1]:.3g}).", ""]
        for w in sh["worst_case"]:
            lines.append(f"- worst {w['metric']}: signed {w['objective']:.4g} at "
                         + ", ".join(f"{k} = {v:.6g}" for k, v in w["values"].items())
                         + f" ({w['evaluations']} evaluations); exact-beam check "
                         f"{w['verification'].get('exact_reference')}")
        lines.append("")
    lines += ["## Profile of one sample (cumulative)", "", "```", p["profile"].strip(), "```",
              ""]
    text = "\n".join(lines)
    (RESULTS / f"{name}.md").write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
