"""Cost of a sweep (issue 13): one sample, Dask's per-task overhead, 1 -> 2 worker speed-up,
10,000 samples of the default sweep scene.

Measured on the shipped sweep scene (``spacecraft/scene/embedded/sweeps/default.toml``: the paper's rod
on a 100 kg hub, LQR + Kalman tuned on the fitted 3-body chain and held (design = "nominal"),
2 modes of truth, the slew, every sample also closed on the exact beam), no FMUs and no plots:

1. ``per_sample``: one evaluation (:func:`spacecraft.sweep.evaluate.evaluate`) in this process,
   median over ``--samples-per-sample`` samples after a warm-up, with the stage costs of a
   cProfile run; beside it one ``spacecraft.run`` of the same one-loop scene (the runner refits
   the chain, picks the fidelity and builds the equivalence data every time);
2. ``task_overhead``: on a LocalCluster of 2 single-threaded worker processes, tasks that
   evaluate no sample (``evaluate_batch`` on an empty batch: argument transfer, scheduling,
   result), 2 x 200 tasks in flight as the sweep keeps them: the wall time per task of one
   worker and the CPU time per task of the client, the scheduler (in this process) and the
   workers; their ratio to a task of the sweep (``TASK_SECONDS`` of work);
3. ``speed_up``: the same ``--speed-up-samples`` samples on LocalClusters of 1 and 2 workers
   (cluster started and every worker warmed before the clock), median of ``--repeats`` runs
   each; beside the wall times, the workers' CPU time per sample, how busy the workers were
   (their CPU time over workers x wall time) and the CPU time of the client and scheduler as
   a fraction of the workers' (Dask's share of the work);
4. ``ten_thousand``: ``run_sweep`` of 10,000 samples end to end on a fresh LocalCluster of 2
   workers (the cluster's start, the workers' imports, prepare, every sample streamed to
   Parquet, the report without plots), no worst-case search; then the shipped scene as shipped
   (1000 samples and the worst-case searches, their worst cases).

With ``--scene NAME`` (an embedded sweep scene, e.g. ``three_axis``: the three-axis spacecraft,
its PD + notch held, every sample judged on the exact beams through W6) the same measures of
that scene: 1. one sample (CPU with and without the exact-beam verdict), 4. ``--big`` samples
end to end on a fresh LocalCluster of 2 workers, and the command as a user runs it
(``flexsat sweep NAME --workers 2 --samples --cli-samples`` with its worst-case search, in a
fresh process); the 10,000-sample figure is scaled from the end-to-end run (module function
:func:`scaled`), written to ``sweep_NAME.json`` and ``sweep_NAME.md``.

Every figure carries the load average (``os.getloadavg``) before and after it: the machine has
2 cores and is shared, so a speed-up measured under load measures the load.

Modes::

    python benchmarks/bench_sweep.py            # everything (a quiet machine: ~7 min)
    python benchmarks/bench_sweep.py --shared   # CPU per sample, per-task overhead, Dask's
                                                # CPU share (a shared machine: ~3 min)
    python benchmarks/bench_sweep.py --quick    # a smoke run of everything (~1 min)
    python benchmarks/bench_sweep.py --only-per-sample
    python benchmarks/bench_sweep.py --scene three_axis --big 400 --cli-samples 200
                                                # a three-axis sweep scene (sweep_three_axis.*)
    python benchmarks/bench_sweep.py --idle [--seconds 20] [--repeats 3]
                                                # the CPU an idle LocalCluster of the sweep
                                                # takes, with Dask's default timers and with
                                                # the sweep's (sweep_idle.*)
    python benchmarks/bench_sweep.py --ten-thousand-before PATH [--big N]
                                                # 4. only, with the checkout at PATH (before
                                                # a change) and this one, one after the other
                                                # (sweep_end_to_end.*)

Writes ``benchmarks/results/sweep.json`` and ``sweep.md`` (``--shared``: ``sweep_shared.*``;
``--quick``: ``sweep_quick.*``; ``--only-per-sample``: ``sweep_per_sample.json``). CPU times
(``time.process_time``, and the workers' own through ``Client.run``) stand beside wall times:
on a loaded machine they are the closer measure of the work.
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


def per_sample(n: int, scene: str | None = None) -> dict:
    import spacecraft.sweep as S
    from spacecraft.design.loop import run
    from spacecraft.scene.read import load_scene
    from spacecraft.sweep.evaluate import apply_values, evaluate, prepare

    raw, spec, source = S.load_sweep(scene, samples=n)
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
    nominal = load_scene(apply_values(context.base, context.parameters, spec.nominal))
    run(nominal)
    runner_times = []
    for _ in range(3):
        t = time.perf_counter()
        run(nominal)
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


def _cpu(client) -> tuple[float, float]:
    """(this process's CPU time: the client and, for a LocalCluster, its scheduler; the
    workers' CPU time summed) [s]."""
    workers = client.run(time.process_time)
    return time.process_time(), float(sum(workers.values()))


def _accounted(client, run) -> dict:
    """Wall time, the client's + scheduler's CPU time and the workers' CPU time of ``run()``."""
    before = load()
    c0, w0 = _cpu(client)
    t = time.perf_counter()
    out = run()
    wall = time.perf_counter() - t
    c1, w1 = _cpu(client)
    return {"wall_s": wall, "client_cpu_s": c1 - c0, "workers_cpu_s": w1 - w0,
            "load_before": before, "load_after": load(), "result": out}


def task_overhead(n_tasks: int) -> dict:
    """Per-task cost of Dask itself: tasks that evaluate no sample (module docstring, 2)."""
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
        run = _accounted(client, lambda: sum(1 for _ in executor.run(context, empty)))
    finally:
        client.close()
        c.close()
    wall = run["wall_s"]
    # two workers run tasks side by side: per task of one worker, the overhead is 2 x wall / n
    per_task = 2.0 * wall / n_tasks
    cpu_per_task = (run["client_cpu_s"] + run["workers_cpu_s"]) / n_tasks
    return {"tasks": n_tasks, "wall_s": wall, "per_task_s": per_task,
            "cpu_per_task_s": cpu_per_task,
            "client_cpu_per_task_s": run["client_cpu_s"] / n_tasks,
            "workers_cpu_per_task_s": run["workers_cpu_s"] / n_tasks,
            "task_seconds": TASK_SECONDS, "fraction_of_a_task": per_task / TASK_SECONDS,
            "cpu_fraction_of_a_task": cpu_per_task / TASK_SECONDS,
            "load_before": run["load_before"], "load_after": run["load_after"]}


#: Dask's defaults of the settings :data:`spacecraft.sweep.execute.LOCAL_CLUSTER_CONFIG` changes.
DASK_DEFAULTS = {"distributed.worker.profile.enabled": True,
                 "distributed.admin.system-monitor.interval": "500ms",
                 "distributed.admin.tick.interval": "20ms",
                 "distributed.worker.memory.monitor-interval": "100ms"}
#: The settings the sweep's LocalCluster had before the event-loop and memory timers.
SWEEP_BEFORE = {"distributed.worker.profile.enabled": False,
                "distributed.admin.system-monitor.interval": "5s"}


def idle(seconds: float, repeats: int) -> dict:
    """CPU time an idle LocalCluster of 2 workers takes [s of CPU per s of wall], started as
    the sweep starts it (:func:`spacecraft.sweep.execute.open_executor`), with Dask's default
    timers and with the sweep's (:data:`spacecraft.sweep.execute.LOCAL_CLUSTER_CONFIG`),
    alternating: this process (client, scheduler and nannies) and the two worker processes
    (``psutil``), measured over ``seconds`` after 2 s of settling."""
    import psutil
    from spacecraft.sweep import execute

    def cpu(process) -> float:
        t = process.cpu_times()
        return t.user + t.system

    sweep = dict(execute.LOCAL_CLUSTER_CONFIG)
    configs = {"Dask's defaults": {**sweep, **DASK_DEFAULTS},
               "profiler off, system monitor 5 s (the sweep's earlier settings)":
                   {**sweep, **DASK_DEFAULTS, **SWEEP_BEFORE},
               "the sweep's": sweep}
    rounds: dict = {name: [] for name in configs}
    try:
        for _ in range(repeats):
            for name, config in configs.items():
                execute.LOCAL_CLUSTER_CONFIG.clear()
                execute.LOCAL_CLUSTER_CONFIG.update(config)
                executor = execute.open_executor(workers=2)
                try:
                    workers = psutil.Process().children(recursive=True)
                    time.sleep(2.0)
                    before, c0 = load(), time.process_time()
                    w0 = [cpu(w) for w in workers]
                    time.sleep(seconds)
                    c1, w1 = time.process_time(), [cpu(w) for w in workers]
                finally:
                    executor.close()
                rounds[name].append({"main_cpu_per_s": (c1 - c0) / seconds,
                                     "workers_cpu_per_s": (sum(w1) - sum(w0)) / seconds,
                                     "load_before": before, "load_after": load()})
    finally:
        execute.LOCAL_CLUSTER_CONFIG.clear()
        execute.LOCAL_CLUSTER_CONFIG.update(sweep)
    return {"seconds": seconds, "sweep_config": sweep, "dask_defaults": DASK_DEFAULTS,
            "rounds": rounds}


def speed_up(n: int, repeats: int) -> dict:
    """The same n samples on LocalClusters of 1 and 2 workers (module docstring, 3)."""
    import spacecraft.sweep as S
    from spacecraft.sweep.evaluate import evaluate, prepare
    from spacecraft.sweep.execute import Executor, run_samples

    raw, spec, source = S.load_sweep(None, samples=n)
    context = prepare(raw, spec, source)
    evaluate(context, spec.nominal)
    c = time.process_time()
    for _ in range(5):
        evaluate(context, spec.nominal)
    one = (time.process_time() - c) / 5  # CPU: the batch size must not follow the load
    out = {"samples": n, "repeats": repeats, "seconds_per_sample_for_batches": one}
    for workers in (1, 2):
        c, client = cluster(workers)
        try:
            executor = Executor("client", client, workers)
            # warm: every worker imports flexsat and receives the context before the clock
            list(executor.run(context, [([0], spec.nominal.reshape(1, -1))] * (2 * workers)))
            runs = []
            for _ in range(repeats):
                runs.append(_accounted(client, lambda: run_samples(
                    context, spec, executor, seconds_per_sample=one, progress=False)))
        finally:
            client.close()
            c.close()
        info = runs[-1]["result"][1]
        walls = [r["wall_s"] for r in runs]
        work = [r["workers_cpu_s"] for r in runs]
        client_cpu = [r["client_cpu_s"] for r in runs]
        out[f"workers_{workers}"] = {
            "median_s": statistics.median(walls), "runs_s": walls,
            "batch": info["batch"], "tasks": info["tasks"],
            "workers_cpu_per_sample_s": statistics.median(work) / n,
            "client_cpu_s": statistics.median(client_cpu),
            # the client's and scheduler's CPU against the workers': Dask's share of the work
            "client_cpu_fraction": statistics.median(client_cpu) / statistics.median(work),
            # the workers' CPU time against their wall-time capacity: 1 on an idle machine,
            # lower when tasks wait (scheduling gaps, stragglers) or the machine is shared
            "workers_busy_fraction": statistics.median(work) / (workers * statistics.median(walls)),
            "loads": [r["load_before"] for r in runs] + [runs[-1]["load_after"]]}
    out["speed_up"] = out["workers_1"]["median_s"] / out["workers_2"]["median_s"]
    return out


def ten_thousand(n: int, scene: str | None = None) -> dict:
    """``run_sweep`` of n samples end to end on a fresh LocalCluster of 2 workers (module
    docstring, 4): the cluster's start, the workers' imports, every sample to Parquet, the
    report without plots."""
    from spacecraft.sweep import run_sweep

    with tempfile.TemporaryDirectory() as tmp:
        before = load()
        t = time.perf_counter()
        c, client = cluster(2)
        start = time.perf_counter() - t
        try:
            run = _accounted(client, lambda: run_sweep(
                scene, samples=n, worst_case=False, out=Path(tmp) / "sweep", plots=False,
                progress=False, client=client))
        finally:
            client.close()
            c.close()
        wall = time.perf_counter() - t
    s = run["result"].summary
    return {"samples": n, "wall_s": wall, "cluster_start_s": start, "sweep_s": run["wall_s"],
            "client_cpu_s": run["client_cpu_s"], "workers_cpu_s": run["workers_cpu_s"],
            "workers_cpu_per_sample_s": run["workers_cpu_s"] / n,
            "load_before": before, "load_after": run["load_after"],
            "executor": s["executor"], "timings": s["timings"], "failed": s["samples"]["failed"],
            "batch": s.get("batch"), "instability": s["instability"]}


def before_and_after(before: Path, n: int) -> int:
    """``ten_thousand(n)`` with the checkout at ``before`` and with this one, each in a fresh
    process (the checkout first on the path, its workers too), one after the other; the ratio
    of their wall times (sweep_end_to_end.json and .md)."""
    import json
    import subprocess

    here = Path(__file__).resolve().parent.parent
    runs = {}
    for which, tree in (("before", before), ("after", here)):
        print(f"{n} samples, {which} ({tree})...", file=sys.stderr)
        code = ("import json, sys; sys.path[:0] = [sys.argv[1], sys.argv[1] + '/benchmarks']; "
                "import bench_sweep; r = bench_sweep.ten_thousand(int(sys.argv[2])); "
                "r.pop('instability', None); print(json.dumps(r, default=str))")
        out = subprocess.run([sys.executable, "-c", code, str(tree), str(n)], cwd=str(tree),
                             env=dict(os.environ, PYTHONPATH=str(tree)), capture_output=True,
                             text=True)
        if out.returncode != 0:
            raise RuntimeError(out.stderr[-3000:])
        runs[which] = json.loads(out.stdout.strip().splitlines()[-1])
    result = {"machine": machine_info(), "samples": n, "before_checkout": str(before),
              "runs": runs, "wall_ratio": runs["after"]["wall_s"] / runs["before"]["wall_s"],
              "workers_cpu_ratio": runs["after"]["workers_cpu_s"] / runs["before"]["workers_cpu_s"]}
    write_json("sweep_end_to_end.json", result)
    rows = [[which, f"{r['wall_s']:.1f} s (cluster start {r['cluster_start_s']:.1f} s)",
             f"{r['workers_cpu_per_sample_s'] * 1e3:.1f} ms", f"{r['client_cpu_s']:.1f} s",
             f"{r['failed']}", f"{r['load_before']} -> {r['load_after']}"]
            for which, r in runs.items()]
    rows.append(["after / before", f"{result['wall_ratio']:.2f}",
                 f"{result['workers_cpu_ratio']:.2f}", "", "", ""])
    machine = result["machine"]
    text = "\n".join([
        f"# {n} samples of the shipped sweep scene end to end, before and after", "",
        f"`python benchmarks/bench_sweep.py --ten-thousand-before PATH` on "
        f"{machine['date_utc']} UTC ({machine['cpu']}, {machine['nproc']} cores): run_sweep on "
        "a fresh LocalCluster of 2 workers (its start, the workers' imports, every sample to "
        "Parquet, the report without plots), the checkout before the change first, then this "
        "one.", "",
        markdown_table(["checkout", "wall", "workers' CPU a sample", "client + scheduler CPU",
                        "failed samples", "load average (1, 5, 15 min)"], rows), ""])
    (RESULTS / "sweep_end_to_end.md").write_text(text + "\n")
    print(text)
    return 0


def scaled(end_to_end: dict, n: int = 10_000, workers: int = 2) -> dict:
    """The end-to-end time of n samples scaled from a shorter run: its fixed part (cluster
    start and what the sweep does before and after its samples: prepare, the nominal
    evaluation, the report) plus n times the workers' CPU a sample over the workers (each
    worker busy all the time, as in the measured run when its busy fraction is near 1)."""
    fixed = end_to_end["cluster_start_s"] + sum(
        v for k, v in end_to_end["timings"].items()
        if k not in ("samples", "per_sample_median", "per_sample_mean") and v is not None)
    per_sample = end_to_end["workers_cpu_per_sample_s"]
    busy = end_to_end["workers_cpu_s"] / (workers * end_to_end["timings"]["samples"])
    return {"samples": n, "fixed_s": fixed, "workers_cpu_per_sample_s": per_sample,
            "workers": workers, "measured_busy_fraction": busy,
            "estimate_s": fixed + n * per_sample / workers}


def command_line(scene: str, n: int) -> dict:
    """``flexsat sweep SCENE --samples n --workers 2`` in a fresh process, as a user runs it
    (its own LocalCluster, the worst-case search and its checks, the report with plots)."""
    import json
    import subprocess

    here = Path(__file__).resolve().parent.parent
    with tempfile.TemporaryDirectory() as tmp:
        before = load()
        t = time.perf_counter()
        out = subprocess.run([sys.executable, "-m", "spacecraft.cli", "sweep", scene,
                              "--samples", str(n), "--workers", "2", "--quiet", "--json",
                              "--out", str(Path(tmp) / "sweep")], cwd=str(here),
                             capture_output=True, text=True,
                             env=dict(os.environ, PYTHONPATH=str(here)))
        wall = time.perf_counter() - t
        after = load()
    if out.returncode != 0:
        raise RuntimeError(out.stderr[-3000:])
    s = json.loads(out.stdout)
    return {"samples": n, "wall_s": wall, "exit_code": out.returncode, "load_before": before,
            "load_after": after, "executor": s["executor"], "timings": s["timings"],
            "counts": {k: s["samples"][k] for k in ("total", "evaluated", "failed", "status")},
            "instability": s["instability"], "sensitivity": s["sensitivity"]["ranking"],
            "worst_case": [{k: w[k] for k in ("metric", "values", "objective", "evaluations",
                                               "failed", "verification")}
                           for w in s["worst_case"]],
            "fidelity_check": s["fidelity_check"]}


def scene_benchmark(scene: str, args) -> int:
    """``--scene NAME`` (module docstring): one sample, ``--big`` samples end to end on 2
    workers, the command line with its worst case; sweep_NAME.json and .md."""
    result = {"machine": machine_info(), "scene": scene}
    print("per sample...", file=sys.stderr)
    result["per_sample"] = per_sample(args.samples_per_sample, scene)
    print(f"{args.big} samples end to end...", file=sys.stderr)
    big = ten_thousand(args.big, scene)
    big.pop("instability", None)
    result["end_to_end"] = big
    result["ten_thousand_scaled"] = scaled(big)
    if args.cli_samples:
        print(f"flexsat sweep {scene} --samples {args.cli_samples}...", file=sys.stderr)
        result["command_line"] = command_line(scene, args.cli_samples)
    write_json(f"sweep_{scene}.json", result)
    p, e, x = result["per_sample"], result["end_to_end"], result["ten_thousand_scaled"]
    rows = [["one sample (median)", f"{p['median_s'] * 1e3:.0f} ms wall, "
             f"{p['cpu_median_s'] * 1e3:.0f} ms CPU", f"{p['load_before']}"],
            ["one sample without the exact-beam verdict (CPU)",
             f"{p['without_exact_cpu_median_s'] * 1e3:.0f} ms", f"{p['load_after']}"],
            ["spacecraft.run of the sample's one-loop scene (median of 3)",
             f"{p['runner_run_median_s'] * 1e3:.0f} ms", f"{p['load_after']}"],
            [f"{e['samples']} samples end to end ({e['executor']}, cluster start "
             f"{e['cluster_start_s']:.1f} s included)",
             f"{e['wall_s']:.1f} s; workers' CPU {e['workers_cpu_per_sample_s'] * 1e3:.0f} ms "
             f"a sample, busy {100 * x['measured_busy_fraction']:.0f} %; client + scheduler "
             f"CPU {e['client_cpu_s']:.1f} s", f"{e['load_before']} -> {e['load_after']}"],
            [f"10,000 samples, scaled (fixed {x['fixed_s']:.1f} s + 10,000 x "
             f"{x['workers_cpu_per_sample_s'] * 1e3:.0f} ms / 2 workers)",
             f"{x['estimate_s']:.0f} s ({x['estimate_s'] / 60:.1f} min)", ""]]
    if "command_line" in result:
        c = result["command_line"]
        rows.append([f"flexsat sweep {scene} --samples {c['samples']} --workers 2 (worst "
                     "case, plots)", f"{c['wall_s']:.1f} s, exit {c['exit_code']}",
                     f"{c['load_before']} -> {c['load_after']}"])
    machine = result["machine"]
    lines = [f"# Sweep benchmark: the {scene} sweep scene", "",
             f"`python benchmarks/bench_sweep.py --scene {scene} --big {args.big} "
             f"--cli-samples {args.cli_samples}` on {machine['date_utc']} UTC "
             f"({machine['cpu']}, {machine['nproc']} cores, shared: the load beside every "
             "figure; the workers' CPU a sample is the measure of the work).", "",
             markdown_table(["what", "time", "load average (1, 5, 15 min)"], rows), "",
             "The 10,000-sample figure is scaled, not run: the end-to-end run's fixed part "
             "(cluster start, prepare, the nominal evaluation, the report) plus 10,000 times "
             "the workers' CPU a sample shared by 2 workers kept busy (benchmarks/"
             "bench_sweep.py, scaled()): the two cores free, where the measured run's workers "
             "got the busy fraction of a core each (the load).", ""]
    if "command_line" in result:
        c = result["command_line"]
        inst = c["instability"]
        lines += [f"Command line: {c['counts']['total']} samples, {c['counts']['failed']} "
                  f"failed, statuses {c['counts']['status']}; probability of instability "
                  f"{inst['probability']} (95 % {inst['interval'][0]:.3g} to "
                  f"{inst['interval'][1]:.3g}); most influential "
                  + ", ".join(f"{r['parameter']} ({r['spearman']:.2f})"
                              for r in c["sensitivity"][:3]) + "."]
        for w in c["worst_case"]:
            ver = w["verification"] or {}
            dense = (ver.get("exact_reference") or {}).get(w["metric"])
            runner = ((ver.get("runner") or {}).get("exact") or {}).get(w["metric"])
            lines.append(f"- worst {w['metric']}: signed {w['objective']:.6g} "
                         f"({w['evaluations']} evaluations) at "
                         + ", ".join(f"{k} = {v:.6g}" for k, v in w["values"].items())
                         + f"; on a grid four times as dense {dense}; flexsat run worst.toml "
                         f"(the same controller given): {runner}")
        lines.append("")
    lines += ["## Profile of one sample (cumulative)", "", "```", p["profile"].strip(), "```",
              ""]
    text = "\n".join(lines)
    (RESULTS / f"sweep_{scene}.md").write_text(text + "\n")
    print(text)
    return 0


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


def _rows(result: dict) -> list[list[str]]:
    p = result["per_sample"]
    rows = [
        ["one sample (median)", f"{p['median_s'] * 1e3:.1f} ms wall, "
         f"{p['cpu_median_s'] * 1e3:.1f} ms CPU", f"{p['load_before']}"],
        ["one sample without the exact-beam verdict (CPU)",
         f"{p['without_exact_cpu_median_s'] * 1e3:.1f} ms", f"{p['load_after']}"],
        ["spacecraft.run of the same scene (median of 3)",
         f"{p['runner_run_median_s'] * 1e3:.0f} ms", f"{p['load_after']}"]]
    if "task_overhead" in result:
        o = result["task_overhead"]
        rows.append(["Dask per-task overhead (empty tasks, 2 workers)",
                     f"{o['per_task_s'] * 1e3:.2f} ms wall, {o['cpu_per_task_s'] * 1e3:.2f} ms "
                     f"CPU ({100 * o['cpu_fraction_of_a_task']:.2f} % of a "
                     f"{o['task_seconds']:g} s task)", f"{o['load_before']}"])
    if "speed_up" in result:
        s = result["speed_up"]
        for w in (1, 2):
            r = s[f"workers_{w}"]
            rows.append([f"{s['samples']} samples, {w} worker{'s' if w > 1 else ''} "
                         f"(median of {s['repeats']}; {r['tasks']} tasks of {r['batch']})",
                         f"{r['median_s']:.2f} s; workers' CPU "
                         f"{r['workers_cpu_per_sample_s'] * 1e3:.1f} ms a sample, busy "
                         f"{100 * r['workers_busy_fraction']:.0f} %; client + scheduler CPU "
                         f"{100 * r['client_cpu_fraction']:.2f} % of the workers'",
                         f"{r['loads']}"])
        rows.append(["speed-up 1 -> 2 workers", f"{s['speed_up']:.2f}x", ""])
    if "ten_thousand" in result:
        b = result["ten_thousand"]
        rows.append([f"{b['samples']} samples end to end ({b['executor']}, cluster start "
                     f"{b['cluster_start_s']:.1f} s included)",
                     f"{b['wall_s']:.1f} s; workers' CPU {b['workers_cpu_per_sample_s'] * 1e3:.1f}"
                     f" ms a sample; client + scheduler CPU {b['client_cpu_s']:.1f} s",
                     f"{b['load_before']} -> {b['load_after']}"])
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--quick", action="store_true", help="small counts (a smoke run, ~1 min)")
    mode.add_argument("--shared", action="store_true",
                      help="what a shared machine can measure: CPU per sample, per-task "
                           "overhead, Dask's CPU share (sweep_shared.json)")
    mode.add_argument("--only-per-sample", action="store_true",
                      help="measure one sample only (sweep_per_sample.json)")
    mode.add_argument("--ten-thousand-before", type=Path, metavar="PATH",
                      help="only the --big samples end to end, first with the flexsat checkout "
                           "at PATH (before a change), then with this one, in one run "
                           "(sweep_end_to_end.json)")
    mode.add_argument("--idle", action="store_true",
                      help="only the CPU an idle LocalCluster of the sweep takes, Dask's "
                           "default timers against the sweep's (sweep_idle.json)")
    parser.add_argument("--seconds", type=float, default=20.0,
                        help="with --idle: seconds each idle cluster is measured")
    parser.add_argument("--samples-per-sample", type=int, default=40)
    parser.add_argument("--speed-up-samples", type=int, default=2000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--tasks", type=int, default=400)
    parser.add_argument("--big", type=int, default=10_000)
    parser.add_argument("--skip-shipped", action="store_true")
    parser.add_argument("--scene", metavar="NAME",
                        help="measure this embedded sweep scene instead (sweep_NAME.json)")
    parser.add_argument("--cli-samples", type=int, default=200,
                        help="with --scene: samples of the command-line run (0: skip it)")
    args = parser.parse_args(argv)
    if args.scene is not None:
        return scene_benchmark(args.scene, args)
    if args.ten_thousand_before is not None:
        return before_and_after(args.ten_thousand_before.resolve(), args.big)
    if args.idle:
        result = {"machine": machine_info(), "idle": idle(args.seconds, args.repeats)}
        write_json("sweep_idle.json", result)
        rows = []
        for name, runs in result["idle"]["rounds"].items():
            for r in runs:
                rows.append([name, f"{1e3 * r['main_cpu_per_s']:.1f}",
                             f"{1e3 * r['workers_cpu_per_s']:.1f}",
                             f"{r['load_before']} -> {r['load_after']}"])
        text = "\n".join([
            "# An idle LocalCluster of a sweep: the CPU its timers take", "",
            f"`python benchmarks/bench_sweep.py --idle` on {result['machine']['date_utc']} UTC "
            f"({result['machine']['cpu']}, {result['machine']['nproc']} cores): 2 workers "
            f"started as `flexsat sweep` starts them, idle for {args.seconds:g} s, with Dask's "
            "default timers, the sweep's earlier settings and its own "
            "(`spacecraft.sweep.execute.LOCAL_CLUSTER_CONFIG`), alternating.", "",
            markdown_table(["settings", "this process (client, scheduler, nannies) [ms CPU/s]",
                            "the 2 workers [ms CPU/s]", "load"], rows), ""])
        (RESULTS / "sweep_idle.md").write_text(text + "\n")
        print(text)
        return 0
    if args.only_per_sample:
        result = {"machine": machine_info(), "per_sample": per_sample(args.samples_per_sample)}
        write_json("sweep_per_sample.json", result)
        p = result["per_sample"]
        print(f"one sample: {p['median_s'] * 1e3:.1f} ms wall, {p['cpu_median_s'] * 1e3:.1f} ms "
              f"CPU, {p['without_exact_cpu_median_s'] * 1e3:.1f} ms CPU without the exact-beam "
              f"verdict; load {p['load_before']} -> {p['load_after']}")
        return 0
    if args.quick:
        args.samples_per_sample, args.speed_up_samples, args.repeats = 10, 100, 1
        args.tasks, args.big = 40, 200
    if args.shared:
        args.speed_up_samples, args.repeats = 600, 1
    result = {"machine": machine_info()}
    print("per sample...", file=sys.stderr)
    result["per_sample"] = per_sample(args.samples_per_sample)
    print("task overhead...", file=sys.stderr)
    result["task_overhead"] = task_overhead(args.tasks)
    print("speed-up...", file=sys.stderr)
    result["speed_up"] = speed_up(args.speed_up_samples, args.repeats)
    if not args.shared:
        print(f"{args.big} samples...", file=sys.stderr)
        result["ten_thousand"] = ten_thousand(args.big)
        if not args.skip_shipped:
            print("the shipped scene...", file=sys.stderr)
            result["shipped"] = shipped()
    name = "sweep_quick" if args.quick else "sweep_shared" if args.shared else "sweep"
    write_json(f"{name}.json", result)
    p = result["per_sample"]
    machine = result["machine"]
    lines = ["# Sweep benchmark", "",
             f"`python benchmarks/bench_sweep.py{' --quick' if args.quick else ''}"
             f"{' --shared' if args.shared else ''}` on {machine['date_utc']} UTC "
             f"({machine['cpu']}, {machine['nproc']} cores).", ""]
    if args.shared:
        lines += ["A shared machine: the CPU times are the measure; wall times and the speed-up "
                  "measure the load as much as the sweep.", ""]
    lines += [markdown_table(["what", "time", "load average (1, 5, 15 min)"], _rows(result)), ""]
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
