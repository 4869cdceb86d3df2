"""Benchmark: FMU export time (generate + compile) and co-simulation speed.

Measures the wall-clock time of ``fmu.export`` for modal plants of 2, 50 and 200 states
(rigid body plus lightly damped modes up to 1000 rad/s, one input, two outputs): the median
of several runs, each a complete export (validation, exact zero-order-hold matrices,
model.c and modelDescription.xml, gcc, the check of the built library, zip). "cold" runs
start from an empty object cache folder (the C templates compile too, as on a new machine
or with a new compiler); the others reuse the warm persistent cache and compile only the
generated model.c. Also times the parts: Python generation alone
and the C-side transition matrix for a non-default step (one fmi2DoStep with a new step
size), and a plant + PD co-simulation in steps per second.

Timings depend on the machine's load: record it (the JSON has the 1-minute load average).
On a busy machine a multithreaded BLAS can make scipy's expm of the 201 x 201 augmented
matrix 30x slower (0.02 s -> 0.7 s); ``OPENBLAS_NUM_THREADS=1`` avoids that.

Usage::

    python benchmarks/bench_fmu_export.py [--runs 7] [--json results.json]
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads, puts the worktree on sys.path)

import argparse
import dataclasses
import json
import os
import platform
import statistics
import tempfile
import time
from pathlib import Path

import control
import numpy as np
import scipy.linalg
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

import fmu
from fmu.codegen import model_c_source
from fmu.description import model_description_xml
from fmu.system import linear_model_from, state_nominals, zoh_matrices


def modal_plant(n_states: int, seed: int = 0) -> control.StateSpace:
    """Rigid body plus (n_states - 2) / 2 modes from 1 to 1000 rad/s, damping 0.005."""
    rng = np.random.default_rng(seed)
    n_modes = (n_states - 2) // 2
    blocks = [np.array([[0.0, 1.0], [0.0, 0.0]])]
    blocks += [np.array([[0.0, 1.0], [-w * w, -2 * 0.005 * w]])
               for w in np.linspace(1.0, 1000.0, n_modes)]
    A = scipy.linalg.block_diag(*blocks)
    B = rng.standard_normal((A.shape[0], 1)) * 0.1
    C = np.zeros((2, A.shape[0]))
    C[0, 0::2] = 1.0  # theta: rigid angle plus modal angles
    C[1, 1::2] = 1.0  # omega
    return control.ss(A, B, C, 0, inputs=["torque"], outputs=["theta", "omega"], name=f"modal{n_states}")


def time_runs(function, runs: int) -> list[float]:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return times


def bench_export(n_states: int, runs: int, folder: Path) -> dict:
    system = modal_plant(n_states)
    path = folder / f"modal{n_states}.fmu"
    warm_cache = os.environ.get("FLEXSAT_CACHE_DIR")
    cold_count = iter(range(10**6))

    def cold_export():
        os.environ["FLEXSAT_CACHE_DIR"] = str(folder / f"cold-cache-{n_states}-{next(cold_count)}")
        try:
            fmu.export(system, path)
        finally:
            os.environ["FLEXSAT_CACHE_DIR"] = warm_cache

    cold_times = time_runs(cold_export, runs)
    fmu.export(system, path)  # the warm cache holds the templates from here on
    export_times = time_runs(lambda: fmu.export(system, path), runs)

    def generate_only():
        model = linear_model_from(system)
        model = dataclasses.replace(model, nominals=state_nominals(model, 10.0))
        Phi, Gamma = zoh_matrices(model.A, model.B, fmu.DEFAULT_STEP)
        model_c_source(model, "m", "{0}", fmu.DEFAULT_STEP, Phi, Gamma)
        model_description_xml(model, model_identifier="m", guid="{0}", interfaces=("me", "cs"),
                              step=fmu.DEFAULT_STEP, stop_time=10.0, source_files=("model.c",))

    generate_times = time_runs(generate_only, runs)

    # one fmi2DoStep with a step size other than the default: the C exponential
    description = read_model_description(str(path))
    unzipped = extract(str(path))
    step_times = []
    for _ in range(runs):
        slave = FMU2Slave(guid=description.guid, unzipDirectory=unzipped,
                          modelIdentifier=description.coSimulation.modelIdentifier,
                          instanceName="bench")
        slave.instantiate()
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        slave.exitInitializationMode()
        start = time.perf_counter()
        slave.doStep(0.0, 0.0123)
        step_times.append(time.perf_counter() - start)
        slave.terminate()
        slave.freeInstance()
    return {
        "n_states": n_states,
        "export_cold_median_s": statistics.median(cold_times),
        "export_median_s": statistics.median(export_times),
        "export_min_s": min(export_times),
        "export_max_s": max(export_times),
        "generate_only_median_s": statistics.median(generate_times),
        "new_step_size_dostep_median_s": statistics.median(step_times),
        "fmu_size_bytes": path.stat().st_size,
        "runs": runs,
    }


def bench_cosim(folder: Path, runs: int) -> dict:
    w, z, J = 3.0, 0.01, 10.0  # a stable PD loop: hub (10 kg m^2) with one 3 rad/s mode
    hub = control.ss([[0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1], [0, 0, -w * w, -2 * z * w]],
                     [[0], [1 / J], [0], [0.5 / J]], [[1, 0, 1, 0], [0, 1, 0, 1]], 0,
                     inputs=["torque"], outputs=["theta", "omega"])
    plant = fmu.export(hub, folder / "plant.fmu")
    controller = control.ss(np.zeros((0, 0)), np.zeros((0, 3)), np.zeros((1, 0)),
                            [[20.0, -20.0, -30.0]], inputs=["theta_ref", "theta", "omega"],
                            outputs=["torque"])
    pd = fmu.export(controller, folder / "pd.fmu")
    n_steps = 1000
    times = time_runs(lambda: fmu.cosimulate(plant, pd, n_steps * 0.01, 0.01,
                                             inputs={"theta_ref": 0.1}), runs)
    return {"plant_states": 4, "steps": n_steps, "median_s": statistics.median(times),
            "steps_per_s": n_steps / statistics.median(times)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--json", type=Path, default=None, help="also write the results here")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        os.environ["FLEXSAT_CACHE_DIR"] = str(folder / "warm-cache")
        results = {
            "machine": {"python": platform.python_version(), "processor": platform.machine(),
                        "cpus": os.cpu_count(), "load_average_1min": os.getloadavg()[0],
                        "OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS")},
            "export": [bench_export(n, args.runs, folder) for n in (2, 50, 200)],
            "cosimulation": bench_cosim(folder, max(3, args.runs // 2)),
        }
    for row in results["export"]:
        print(f"export n_states={row['n_states']:4d}: median {row['export_median_s']:.3f} s "
              f"(empty object cache, templates compiled too: {row['export_cold_median_s']:.3f} s) "
              f"(min {row['export_min_s']:.3f}, max {row['export_max_s']:.3f}; generation alone "
              f"{row['generate_only_median_s']:.3f} s; DoStep with a new step size "
              f"{row['new_step_size_dostep_median_s'] * 1e3:.1f} ms)")
    cosim = results["cosimulation"]
    print(f"co-simulation: {cosim['steps']} steps of plant({cosim['plant_states']} states) + PD "
          f"in {cosim['median_s']:.3f} s ({cosim['steps_per_s']:.0f} steps/s)")
    text = json.dumps(results, indent=2)
    print(text)
    if args.json is not None:
        args.json.write_text(text + "\n")


if __name__ == "__main__":
    main()
