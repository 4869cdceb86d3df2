"""How a sweep's two workers share this machine: samples in one process alone and in two at once.

A sweep runs its samples in worker processes, one per core (``spacecraft.sweep``). Its end-to-end
time is bounded by how many samples the cores together evaluate in a second, whatever the
scheduler does. This benchmark measures that bound without Dask: every round starts

- ``alone``: one process evaluating ``--samples`` samples of the shipped sweep scene
  (``spacecraft/scene/embedded/sweeps/default.toml``), nothing else of ours running;
- ``pair``: two such processes at once, each its own samples,

each process preparing the sweep (its nominal run, the compiled kernels) before a common start
time, then timing each sample (``time.process_time``, one BLAS thread as a sweep's worker has)
and the whole run (wall). Rounds alternate alone and pair so that the host's drift falls on
both. Per round: each process's median CPU per sample and its wall time per sample; the
throughput (samples per second, summed over the processes) of the pair against the process
alone; and the host's steal time over the round (``/proc/stat``: CPU time the hypervisor gave
to others). A pair throughput of 2 would mean two cores as good as two machines.

What it says about a sweep's end-to-end time: 10,000 samples need at least
``10,000 / throughput`` seconds of the samples' stage on these two cores (plus imports,
cluster start and the nominal preparation).

Run::

    python benchmarks/process_scaling.py             # 3 rounds of 200 samples, ~2 min
    python benchmarks/process_scaling.py --quick     # 2 rounds of 60 samples

Writes ``benchmarks/results/process_scaling.json`` and ``process_scaling.md`` (``--quick``:
``process_scaling_quick.*``).
"""

from __future__ import annotations

# _common first: the BLAS settings before numpy is loaded, this checkout on sys.path
from _common import RESULTS, ROOT, machine_info, markdown_table, revision, write_json

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

WARM_UP = 10            # samples evaluated before the common start (kernels, caches)
START_DELAY = 25.0      # s: the processes' preparation must end before the common start


def child(samples: int, start: float) -> None:
    """One process: prepare the shipped sweep, wait for ``start`` (epoch s), time ``samples``
    samples; print a JSON line with the per-sample CPU times [s] and the wall time [s]."""
    import warnings
    warnings.simplefilter("ignore")
    from threadpoolctl import threadpool_limits

    import spacecraft.sweep as sweep
    from spacecraft.sweep.evaluate import evaluate, prepare

    raw, spec, source = sweep.load_sweep(None, samples=WARM_UP + samples)
    context = prepare(raw, spec, source)
    values = spec.values()
    with threadpool_limits(1):
        for value in values[:WARM_UP]:
            evaluate(context, value)
        late = time.time() > start
        while time.time() < start:
            time.sleep(0.005)
        cpu = []
        t0 = time.perf_counter()
        for value in values[WARM_UP:WARM_UP + samples]:
            c = time.process_time()
            evaluate(context, value)
            cpu.append(time.process_time() - c)
        wall = time.perf_counter() - t0
    print(json.dumps({"cpu": cpu, "wall": wall, "late": late}))


def _steal() -> int:
    """The host's steal time so far [clock ticks] (0 where /proc/stat has none)."""
    try:
        with open("/proc/stat") as stat:
            fields = stat.readline().split()
        return int(fields[8]) if len(fields) > 8 else 0
    except OSError:
        return 0


def _processes(count: int, samples: int) -> list[dict]:
    """``count`` child processes started together; their JSON results."""
    start = time.time() + START_DELAY
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    procs = [subprocess.Popen([sys.executable, os.path.abspath(__file__), "--child", str(samples), repr(start)],
                              stdout=subprocess.PIPE, text=True, env=env, cwd=ROOT)
             for _ in range(count)]
    out = []
    for proc in procs:
        stdout, _ = proc.communicate()
        if proc.returncode:
            raise SystemExit(f"a measuring process failed (exit {proc.returncode})")
        result = json.loads(stdout.strip().splitlines()[-1])
        if result["late"]:
            raise SystemExit(f"a process prepared for longer than {START_DELAY} s: raise "
                             f"START_DELAY")
        out.append(result)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(int(args.child[0]), float(args.child[1]))
        return
    rounds, samples = (2, 60) if args.quick else (3, 200)
    info = machine_info()
    load_before = os.getloadavg()
    rows, records = [], []
    for k in range(rounds):
        for mode, count in (("alone", 1), ("pair", 2)):
            steal0, load0 = _steal(), os.getloadavg()
            results = _processes(count, samples)
            steal = _steal() - steal0
            medians = [statistics.median(r["cpu"]) for r in results]
            walls = [r["wall"] / samples for r in results]
            throughput = sum(1.0 / w for w in walls)
            record = {"round": k + 1, "mode": mode, "median_cpu_ms": [1e3 * m for m in medians],
                      "wall_per_sample_ms": [1e3 * w for w in walls],
                      "throughput_per_s": throughput, "steal_ticks": steal,
                      "load_before": list(load0), "load_after": list(os.getloadavg())}
            records.append(record)
            print(record, flush=True)
    alone = [r["throughput_per_s"] for r in records if r["mode"] == "alone"]
    pair = [r["throughput_per_s"] for r in records if r["mode"] == "pair"]
    for r in records:
        rows.append([r["round"], r["mode"], ", ".join(f"{m:.1f}" for m in r["median_cpu_ms"]),
                     ", ".join(f"{w:.1f}" for w in r["wall_per_sample_ms"]),
                     f"{r['throughput_per_s']:.1f}", r["steal_ticks"],
                     f"{[round(x, 2) for x in r['load_before']]} -> "
                     f"{[round(x, 2) for x in r['load_after']]}"])
    ratios = [p / a for a, p in zip(alone, pair)]
    load_after = os.getloadavg()
    data = {"machine": info, "revision": revision(ROOT), "rounds": rounds, "samples": samples,
            "records": records, "pair_over_alone": ratios,
            "load_before": list(load_before), "load_after": list(load_after)}
    name = "process_scaling_quick" if args.quick else "process_scaling"
    write_json(f"{name}.json", data)
    best_pair = max(pair)
    text = [
        "# A sweep's samples in one process alone and in two at once (no Dask)", "",
        f"`python benchmarks/process_scaling.py{' --quick' if args.quick else ''}` on "
        f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {info.get('cpu', '')}, "
        f"{os.cpu_count()} cores, one BLAS thread a process, revision {data['revision']}; "
        f"load average (1, 5, 15 min) {[round(x, 2) for x in load_before]} -> "
        f"{[round(x, 2) for x in load_after]}. Each process: {samples} samples of the shipped "
        f"sweep scene after {WARM_UP} to warm up; rounds alternate one process alone and two "
        f"at once.", "",
        markdown_table(["round", "processes", "median CPU a sample [ms]",
                        "wall a sample [ms]", "samples / s (all processes)",
                        "steal [ticks]", "load"], rows), "",
        f"Two processes at once against one alone, samples per second: "
        f"{', '.join(f'{r:.2f}' for r in ratios)} (round by round; 2 would be two cores as "
        f"good as two machines).", "",
        f"At the best pair throughput measured here, {best_pair:.1f} samples / s, 10,000 "
        f"samples need {10000 / best_pair:.0f} s of the samples' stage alone.", ""]
    (RESULTS / f"{name}.md").write_text("\n".join(text))
    print("\n".join(text))


if __name__ == "__main__":
    main()
