"""The one-second main job (issue 10, item 4): ``flexsat`` commands timed end to end.

Each case runs the command as a user does (a fresh ``python -m spacecraft.cli`` process from the
repository root) and records its wall time and its CPU time (user + system of the child,
``resource.getrusage(RUSAGE_CHILDREN)``: a ratio that holds on a loaded machine), with the load
average before the case. Medians of the repetitions. Cases:

- ``--help``: the parser only (no numpy, scipy, python-control, matplotlib or Dask);
- ``run --no-fmu --no-plots``: the default scene's computation, report.md/html, results.json;
- ``run`` (FMU objects cached): the default scene with its 4 plots and 5 FMUs, the fixed C
  templates' object files already in ``$FLEXSAT_CACHE_DIR``;
- ``run`` (first run on a machine): the same with an empty ``$FLEXSAT_CACHE_DIR``.

Also the import time of the modules a run needs, in-process, and the wall time of a process that
only imports python-control (``python -c "import control"``): the floor of every ``flexsat run``,
whatever flexsat does, since its plants, controllers and loops are python-control objects.

Bytecode: a user's ``pip install .`` writes the ``.pyc`` files of flexsat's modules; a checkout
run with ``PYTHONDONTWRITEBYTECODE=1`` (set in some shells and CI images) would compile every
module from source at every start (about 0.25 s here). The children therefore run without that
variable, with ``PYTHONPYCACHEPREFIX`` in the benchmark's scratch folder (filled by the warm-up
run, removed at the end), as an installed flexsat runs.

Not a test: timings depend on the machine and on whatever else runs on it. Writes
``benchmarks/results/flexsat_run.json`` and ``.md``.

    python benchmarks/bench_flexsat_run.py [--quick]    # quick: 5 repetitions, full: 9
"""
from __future__ import annotations

import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"


def _child_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed(args: list, env: dict) -> tuple[float, float]:
    """Wall and CPU seconds of one command (its exit code must be 0)."""
    cpu0, t0 = _child_cpu(), time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "spacecraft.cli", *args], cwd=ROOT, env=env,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall, cpu = time.perf_counter() - t0, _child_cpu() - cpu0
    if done.returncode != 0:
        raise RuntimeError(f"flexsat {' '.join(args)} failed: {done.stderr.strip()}")
    return wall, cpu


def case(name: str, args_of, repetitions: int, env_of) -> dict:
    walls, cpus, loads = [], [], []
    for k in range(repetitions):
        loads.append(os.getloadavg()[0])
        wall, cpu = timed(args_of(k), env_of(k))
        walls.append(wall)
        cpus.append(cpu)
    out = {"case": name, "repetitions": repetitions, "wall_median": statistics.median(walls),
           "cpu_median": statistics.median(cpus), "wall": walls, "cpu": cpus,
           "load_average_1min": loads}
    print(f"{name:42s} wall {out['wall_median']:6.3f} s  cpu {out['cpu_median']:6.3f} s  "
          f"(median of {repetitions}; load {statistics.median(loads):.2f})", flush=True)
    return out


def import_floor(env: dict) -> dict:
    """CPU and wall seconds to import what a run needs (one fresh process)."""
    code = ("import time; c = time.process_time(); t = time.perf_counter(); "
            "import control; a = time.process_time() - c; "
            "import spacecraft.design.loop, spacecraft.report.write; "
            "print(a, time.process_time() - c, time.perf_counter() - t)")
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env,
                          capture_output=True, text=True, check=True)
    control_cpu, cpu, wall = map(float, done.stdout.split())
    return {"control_cpu": control_cpu, "cpu": cpu, "wall": wall}


def process_wall(code: str, env: dict) -> float:
    """Wall seconds of ``python -c code`` (a fresh process: interpreter start included)."""
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, check=True,
                   stdout=subprocess.DEVNULL)
    return time.perf_counter() - t0


def main(quick: bool) -> None:
    repetitions = 5 if quick else 9
    base = {k: v for k, v in os.environ.items()
            if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
                         "PYTHONDONTWRITEBYTECODE")}
    base["PYTHONPATH"] = str(ROOT)
    scratch = Path(tempfile.mkdtemp(prefix="flexsat-bench-"))
    base["PYTHONPYCACHEPREFIX"] = str(scratch / "pycache")
    warm_cache = scratch / "cache"
    env_warm = {**base, "FLEXSAT_CACHE_DIR": str(warm_cache)}
    try:
        timed(["run", "--quiet", "--out", str(scratch / "warm-up")], env_warm)  # fills it
        out = lambda k, tag: ["--out", str(scratch / f"{tag}{k}")]   # noqa: E731
        floors = [import_floor(base) for _ in range(repetitions)]
        floor = {key: statistics.median(f[key] for f in floors) for key in floors[0]}
        print(f"{'imports (control; all a run needs)':42s} cpu {floor['control_cpu']:.3f} s; "
              f"{floor['cpu']:.3f} s (wall {floor['wall']:.3f} s)")
        floor["python_wall"] = statistics.median(process_wall("pass", base)
                                                 for _ in range(repetitions))
        floor["control_process_wall"] = statistics.median(
            process_wall("import control", base) for _ in range(repetitions))
        label = "python -c pass; python -c 'import control'"
        print(f"{label:42s} wall "
              f"{floor['python_wall']:.3f} s; {floor['control_process_wall']:.3f} s")
        cases = [
            case("flexsat --help", lambda k: ["--help"], repetitions, lambda k: base),
            case("flexsat run --no-fmu --no-plots",
                 lambda k: ["run", "--no-fmu", "--no-plots", "--quiet", *out(k, "lean")],
                 repetitions, lambda k: env_warm),
            case("flexsat run (FMU objects cached)",
                 lambda k: ["run", "--quiet", *out(k, "full")], repetitions,
                 lambda k: env_warm),
            case("flexsat run (first run: empty cache)",
                 lambda k: ["run", "--quiet", *out(k, "cold")], repetitions,
                 lambda k: {**base, "FLEXSAT_CACHE_DIR": str(scratch / f"cold-cache{k}")}),
        ]
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    record = {"machine": platform.platform(), "cpus": os.cpu_count(),
              "python": platform.python_version(), "quick": quick,
              "date": time.strftime("%Y-%m-%dT%H:%M:%S"), "imports": floor, "cases": cases}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "flexsat_run.json").write_text(json.dumps(record, indent=2) + "\n")
    lines = ["# flexsat run: wall and CPU time (medians)", "",
             f"{record['date']}, {record['machine']}, {record['cpus']} CPUs, Python "
             f"{record['python']}, {'quick' if quick else 'full'} mode; BLAS threads unset.",
             "", "| command | wall [s] | CPU [s] | load average (1 min) | repetitions |",
             "|---|---|---|---|---|"]
    for c in cases:
        lines.append(f"| `{c['case']}` | {c['wall_median']:.3f} | {c['cpu_median']:.3f} | "
                     f"{statistics.median(c['load_average_1min']):.2f} | {c['repetitions']} |")
    lines += ["", f"Imports a run needs: {floor['cpu']:.3f} s CPU, of which python-control "
                  f"(scipy.signal, scipy.stats, matplotlib.pyplot) {floor['control_cpu']:.3f} s.",
              "", f"Floor of any run: `python -c \"import control\"` takes "
                  f"{floor['control_process_wall']:.3f} s wall (`python -c pass`: "
                  f"{floor['python_wall']:.3f} s), medians of {repetitions}.", ""]
    (RESULTS / "flexsat_run.md").write_text("\n".join(lines))
    print(f"wrote {RESULTS / 'flexsat_run.json'} and .md")


if __name__ == "__main__":
    main(quick="--quick" in sys.argv[1:])
