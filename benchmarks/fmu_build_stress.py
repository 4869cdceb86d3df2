"""Stress measurement of FMU builds: many exports at once through one persistent cache.

1. Stress: ``--exports`` (50) FMU exports, each in a fresh Python process, ``--parallel``
   (4) at a time, all sharing one initially empty object cache, with a deliberately slow
   compiler: a shell script that waits ``--delay`` s, then runs gcc (and that fails if two
   compilers write one output file at once, the fault that once produced libraries without
   fmi2 symbols). Every FMU is then checked independently of the exporter: its library
   loads with ctypes, its dynamic symbol table holds exactly the 44 FMI 2.0 functions
   (``nm -D``), and one fmpy Co-Simulation run equals ``control.c2d`` + ``forced_response``.
2. Cold vs warm: the wall-clock time of ``fmu.export`` (real gcc) with an empty cache
   folder (the templates compile too: a new machine or compiler) and with a warm one,
   alternating, medians of ``--runs`` (7) each.

The machine's 1-minute load average is recorded before and after; the JSON goes to
``benchmarks/results/fmu_build_stress.json``.

Usage::

    python benchmarks/fmu_build_stress.py [--exports 50] [--parallel 4] [--delay 0.5] [--runs 7]
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads, puts the worktree on sys.path)

import argparse
import ctypes
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import control
import numpy as np
from _common import ROOT, RESULTS, machine_info
from fmpy import simulate_fmu

import fmu

SLOW_COMPILER = """#!/bin/sh
# A slow C compiler: waits {delay} s, then runs gcc; fails if another compiler process
# writes the same output file at the same time.
out=""
prev=""
for arg in "$@"; do
  [ "$prev" = "-o" ] && out="$arg"
  prev="$arg"
done
if [ -n "$out" ]; then
  if ! mkdir "$out.writing" 2>/dev/null; then
    echo "two compilers write $out at once" >&2
    exit 1
  fi
  sleep {delay}
fi
gcc "$@"
status=$?
[ -n "$out" ] && rmdir "$out.writing"
exit $status
"""

EXPORT_ONE = """
import sys, time
sys.path.insert(0, {root!r})
import control, numpy as np
from fmu import export
gain = {gain!r}
body = control.ss([[0, 1], [0, 0]], [[0], [gain / 10.0]], np.eye(2), 0, inputs=["torque"],
                  outputs=["theta", "omega"], states=["angle", "rate"])
start = time.perf_counter()
export(body, {target!r}, compiler={cc!r})
print(time.perf_counter() - start)
"""


def body(gain: float) -> control.StateSpace:
    return control.ss([[0, 1], [0, 0]], [[0], [gain / 10.0]], np.eye(2), 0, inputs=["torque"],
                      outputs=["theta", "omega"], states=["angle", "rate"])


def check_fmu(path: Path, gain: float, folder: Path) -> str | None:
    """None if the FMU loads, exports exactly the fmi2 API and simulates exactly; else why not."""
    try:
        with zipfile.ZipFile(path) as archive:
            library = folder / f"{path.stem}.so"
            library.write_bytes(archive.read(f"binaries/linux64/{path.stem}.so"))
        ctypes.CDLL(str(library)).fmi2Instantiate  # loads, and has the entry point
        listing = subprocess.run(["nm", "-D", "--defined-only", str(library)], capture_output=True,
                                 text=True, check=True).stdout
        symbols = {line.split()[-1] for line in listing.splitlines() if line.strip()}
        if len(symbols) != 44 or not all(s.startswith("fmi2") for s in symbols):
            return f"symbols: {sorted(symbols)[:5]}... ({len(symbols)})"
        table = np.array([(0.0, 1.0), (1.0, 1.0)], dtype=[("time", np.float64), ("torque", np.float64)])
        result = simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=0.1,
                              output_interval=0.01, input=table)
        t = np.arange(11) * 0.01
        expected = control.forced_response(control.c2d(body(gain), 0.01, "zoh"), T=t, U=np.ones_like(t))
        if not np.allclose(result["theta"], expected.outputs[0], rtol=1e-12, atol=1e-18):
            return "simulation differs from c2d"
    except Exception as error:  # report every way an FMU can be broken
        return f"{type(error).__name__}: {error}"
    return None


def stress(n_exports: int, parallel: int, delay: float, folder: Path) -> dict:
    cc = folder / "slow-cc"
    cc.write_text(SLOW_COMPILER.format(delay=delay))
    cc.chmod(0o755)
    environment = {**os.environ, "FLEXSAT_CACHE_DIR": str(folder / "cache")}
    pending = list(range(n_exports))
    running: list[tuple[int, subprocess.Popen]] = []
    outcomes: dict[int, dict] = {}
    start = time.perf_counter()
    while pending or running:
        while pending and len(running) < parallel:
            k = pending.pop(0)
            script = EXPORT_ONE.format(root=str(ROOT), gain=1.0 + k / 10, cc=str(cc),
                                       target=str(folder / f"m{k}.fmu"))
            running.append((k, subprocess.Popen([sys.executable, "-c", script], env=environment,
                                                stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                                text=True)))
        k, process = running.pop(0)
        stdout, stderr = process.communicate()
        outcomes[k] = {"exit_code": process.returncode,
                       "export_s": float(stdout) if process.returncode == 0 else None,
                       "error": stderr.strip().splitlines()[-1] if process.returncode else None}
    wall = time.perf_counter() - start
    checks = folder / "checks"
    checks.mkdir()
    for k, outcome in outcomes.items():
        path = folder / f"m{k}.fmu"
        outcome["problem"] = (check_fmu(path, 1.0 + k / 10, checks) if path.is_file()
                              else "no FMU written")
    good = sum(1 for o in outcomes.values() if o["exit_code"] == 0 and o["problem"] is None)
    export_times = [o["export_s"] for o in outcomes.values() if o["export_s"] is not None]
    return {
        "exports": n_exports, "parallel_processes": parallel, "compiler_delay_s": delay,
        "exit_ok": sum(1 for o in outcomes.values() if o["exit_code"] == 0),
        "loadable_and_correct": good,
        "failures": {k: o for k, o in outcomes.items() if o["exit_code"] or o["problem"]},
        "wall_s": wall,
        "export_in_process_median_s": statistics.median(export_times) if export_times else None,
        "objects_compiled": len(list((folder / "cache" / "fmu-objects").glob("*.o"))),
    }


def cold_vs_warm(runs: int, folder: Path) -> dict:
    system = body(1.0)
    warm_dir = folder / "warm"
    os.environ["FLEXSAT_CACHE_DIR"] = str(warm_dir)
    fmu.export(system, folder / "first.fmu")  # fills the warm cache
    cold, warm = [], []
    for k in range(runs):
        os.environ["FLEXSAT_CACHE_DIR"] = str(folder / f"cold{k}")
        start = time.perf_counter()
        fmu.export(system, folder / "cold.fmu")
        cold.append(time.perf_counter() - start)
        os.environ["FLEXSAT_CACHE_DIR"] = str(warm_dir)
        start = time.perf_counter()
        fmu.export(system, folder / "warm.fmu")
        warm.append(time.perf_counter() - start)
    return {"runs": runs, "cold_median_s": statistics.median(cold), "cold_s": cold,
            "warm_median_s": statistics.median(warm), "warm_s": warm}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--exports", type=int, default=50)
    parser.add_argument("--parallel", type=int, default=4)
    parser.add_argument("--delay", type=float, default=0.5, help="compiler delay [s]")
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--json", type=Path, default=RESULTS / "fmu_build_stress.json")
    args = parser.parse_args()
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "stress").mkdir()
        (folder / "timing").mkdir()
        results = {
            "machine": {**machine_info(), "load_average_1min_before": load_before},
            "stress": stress(args.exports, args.parallel, args.delay, folder / "stress"),
            "cold_vs_warm": cold_vs_warm(args.runs, folder / "timing"),
        }
        results["machine"]["load_average_1min_after"] = os.getloadavg()[0]
    s, t = results["stress"], results["cold_vs_warm"]
    print(f"stress: {s['loadable_and_correct']} of {s['exports']} exports ({s['parallel_processes']} "
          f"processes at a time, compiler delay {s['compiler_delay_s']} s) loadable and correct; "
          f"{s['exit_ok']} exited 0; templates compiled {s['objects_compiled']} times in all; "
          f"{s['wall_s']:.1f} s wall")
    print(f"export time: cold cache {t['cold_median_s']:.3f} s, warm cache {t['warm_median_s']:.3f} s "
          f"(medians of {t['runs']}; load {results['machine']['load_average_1min_before']:.2f} -> "
          f"{results['machine']['load_average_1min_after']:.2f})")
    args.json.write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
