"""Benchmark: controllers.simulate against control.forced_response and scipy lsim.

Run from the repository root::

    python benchmarks/bench_simulate.py                   # full set (~2 min)
    python benchmarks/bench_simulate.py --blas-threads 1  # single-thread BLAS
    python benchmarks/bench_simulate.py --quick           # 100 states only

Every case is simulated by each method in the same process, the methods taking
turns in each repetition (so load changes on a shared machine hit them alike);
the table shows the median wall time of the repetitions and the ratios of
those medians.  All methods use the same input interpretation (linear between
samples), so they must agree to round-off: the error columns give the largest
output difference relative to the output's range (max over outputs and
samples).  Results go to ``benchmarks/results/simulate.json``.

Methods:

- ``forced_response``: ``control.forced_response(sys, T, U, X0)``;
- ``lsim``: ``scipy.signal.lsim((A, B, C, D), U.T, T, X0)``;
- ``simulate``: ``controllers.simulate.simulate(sys, T, U, X0)``, one shot
  (set-up included), states read (they are filled in on first use);
  ``simulate, outputs read``: the same reading only the outputs (a design
  loop that builds a new closed loop each time);
- ``Simulator.run``: ``Simulator(sys, dt).run(T, U, X0)`` with the set-up
  (``Simulator(...)``, timed separately) paid once, as in a design loop,
  states read; ``Simulator.run, outputs read``: the same reading only the
  outputs (the states are then never computed);
- ``Simulator.outputs``: the same without the state trajectory (its chunk
  maps are built on its first call, outside the timing).

The systems are attitude loops of a hub with flexible appendages in modal
form: a rigid body (inertia 50 kg*m^2) plus n_modes lightly damped bending
modes (zeta = 0.005, 0.5 to 200 rad/s), closed by a PD attitude controller
(0.5 rad/s, damping 0.7) and driven by a smooth 10 deg slew command plus a
small random torque disturbance; and the open-loop plant (defective
rigid-body mode, eigenvalue 0 in a 2x2 Jordan block) driven by torque.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import control
import numpy as np
import scipy
import scipy.signal

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from controllers.simulate import Simulator, simulate  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results" / "simulate.json"

HUB_INERTIA = 50.0          # kg*m^2
MODE_DAMPING = 0.005        # -
PD_BANDWIDTH = 0.5          # rad/s
PD_DAMPING = 0.7            # -
SLEW_ANGLE = np.radians(10.0)   # rad
SLEW_DURATION = 30.0        # s


def flexible_plant(n_modes: int, seed: int = 0) -> control.StateSpace:
    """Hub + n_modes bending modes in modal form; input torque [N*m].

    States: theta, omega, then (q_i, q_i') per mode; outputs theta [rad],
    omega [rad/s].  Torque excites mode i with participation b_i (m^-1
    kg^-1/2 scale absorbed), the hub angle sees the modes through c_i.
    """
    rng = np.random.default_rng(seed)
    w = np.geomspace(0.5, 200.0, n_modes)
    b = rng.uniform(0.2, 1.0, n_modes) / np.sqrt(HUB_INERTIA)
    n = 2 + 2 * n_modes
    A = np.zeros((n, n))
    A[0, 1] = 1.0
    B = np.zeros((n, 1))
    B[1, 0] = 1.0 / HUB_INERTIA
    C = np.zeros((2, n))
    C[0, 0] = C[1, 1] = 1.0
    for i in range(n_modes):
        k = 2 + 2 * i
        A[k, k + 1] = 1.0
        A[k + 1, k] = -w[i] ** 2
        A[k + 1, k + 1] = -2.0 * MODE_DAMPING * w[i]
        B[k + 1, 0] = b[i]
        C[0, k] = 0.05 * b[i]          # hub angle sees the mode shapes
        C[1, k + 1] = 0.05 * b[i]
    return control.ss(A, B, C, 0, inputs=["torque"],
                      outputs=["theta", "omega"], name=f"plant{n}")


def attitude_loop(n_modes: int, seed: int = 0) -> control.StateSpace:
    """PD loop around flexible_plant; inputs theta_ref [rad], torque_d [N*m].

    torque = J (wn^2 (theta_ref - theta) - 2 zeta wn omega) + torque_d.
    """
    plant = flexible_plant(n_modes, seed)
    A, B, C = (np.asarray(M) for M in (plant.A, plant.B, plant.C))
    kp = HUB_INERTIA * PD_BANDWIDTH ** 2
    kd = HUB_INERTIA * 2 * PD_DAMPING * PD_BANDWIDTH
    K = np.array([[kp, kd]])
    A_cl = A - B @ K @ C
    B_cl = np.hstack([B * kp, B])
    return control.ss(A_cl, B_cl, C, 0, inputs=["theta_ref", "torque_d"],
                      outputs=["theta", "omega"], name=f"loop{A.shape[0]}")


def slew_inputs(T: np.ndarray, n_inputs: int, seed: int = 1) -> np.ndarray:
    """Cycloidal slew command (rad) and a small random torque (N*m)."""
    rng = np.random.default_rng(seed)
    tau = np.clip(T / SLEW_DURATION, 0.0, 1.0)
    slew = SLEW_ANGLE * (tau - np.sin(2 * np.pi * tau) / (2 * np.pi))
    if n_inputs == 1:
        return 0.05 * rng.standard_normal((1, T.size))
    return np.vstack([slew, 0.05 * rng.standard_normal(T.size)])


def relative_error(y: np.ndarray, y_ref: np.ndarray) -> float:
    """max |y - y_ref| / range(y_ref), max over outputs."""
    y, y_ref = np.atleast_2d(y), np.atleast_2d(y_ref)
    scale = np.maximum(np.ptp(y_ref, axis=1), np.finfo(float).tiny)
    return float(np.max(np.abs(y - y_ref).max(axis=1) / scale))


def long_double_expm(M: np.ndarray) -> np.ndarray:
    """expm(M) in numpy.longdouble (64-bit mantissa on x86-64).

    Scaling and squaring with a Taylor polynomial: with ||M / 2^s||_inf
    <= 1/2, the degree-24 remainder is below 0.5^25 / 25! ~ 1e-33, far
    under the long double round-off (~1e-19).
    """
    M = np.asarray(M, dtype=np.longdouble)
    norm = float(np.abs(M).sum(axis=1).max())
    s = max(0, int(np.ceil(np.log2(max(norm, 1e-300) / 0.5))))
    X = M / np.longdouble(2.0) ** s
    eye = np.eye(M.shape[0], dtype=np.longdouble)
    E = eye.copy()
    for k in range(24, 0, -1):
        E = eye + (X @ E) / k
    for _ in range(s):
        E = E @ E
    return E


def extended_precision_reference(sim: Simulator, T, U, X0, *,
                                 exact: bool) -> np.ndarray:
    """Outputs propagated sequentially in numpy.longdouble.

    x[k+1] = Ad x[k] + Bd0 u[k] + Bd1 u[k+1], y = C x + D u.  With
    exact=False the float64 Ad, Bd0, Bd1 that all three methods share (the
    same Van Loan block exponential) are used: this isolates the round-off
    of each method's propagation (and favours forced_response and lsim,
    which multiply by exactly that Ad).  With exact=True the block
    exponential itself is evaluated in long double: the reference is the
    exact solution of the continuous system under linearly interpolated
    input, to ~1e-17.
    """
    ld = np.longdouble
    if exact:
        A = np.asarray(sim.system.A, dtype=ld)
        B = np.asarray(sim.system.B, dtype=ld)
        n, m = B.shape
        dt = ld(T[1]) - ld(T[0])
        M = np.zeros((n + 2 * m, n + 2 * m), dtype=ld)
        M[:n, :n], M[:n, n:n + m] = A * dt, B * dt
        M[n:n + m, n + m:] = np.eye(m, dtype=ld)
        E = long_double_expm(M)
        Ad, Bd1 = E[:n, :n], E[:n, n + m:]
        Bd0 = E[:n, n:n + m] - Bd1
    else:
        Ad, Bd0, Bd1 = (M.astype(ld) for M in (sim.Ad, sim.Bd0, sim.Bd1))
    C = np.asarray(sim.system.C, dtype=ld)
    D = np.asarray(sim.system.D, dtype=ld)
    U = U.astype(ld)
    W = Bd0 @ U[:, :-1] + Bd1 @ U[:, 1:]
    X = np.empty((Ad.shape[0], U.shape[1]), dtype=ld)
    X[:, 0] = X0
    for k in range(U.shape[1] - 1):
        X[:, k + 1] = Ad @ X[:, k] + W[:, k]
    return (C @ X + D @ U).astype(float)


def run_case(name: str, sys_: control.StateSpace, n_samples: int, dt: float,
             repeats: int, reference: bool) -> dict:
    T = np.arange(n_samples) * dt
    U = slew_inputs(T, sys_.ninputs)
    X0 = np.zeros(sys_.nstates)
    A, B, C, D = (np.asarray(M) for M in (sys_.A, sys_.B, sys_.C, sys_.D))
    # One simulator for the runs (set-up paid once, outputs' map built on
    # its first call, before the timing); set-up timed on fresh ones.
    simulator = {"sim": Simulator(sys_, dt)}

    def setup():
        Simulator(sys_, dt)

    def with_states(resp):
        resp.states            # simulate()/run() fill the states on first use
        return resp

    methods = {
        "forced_response": lambda: control.forced_response(sys_, T, U, X0),
        "lsim": lambda: scipy.signal.lsim((A, B, C, D), U.T, T, X0),
        "simulate": lambda: with_states(simulate(sys_, T, U, X0)),
        "simulate, outputs read": lambda: simulate(sys_, T, U, X0).outputs,
        "Simulator.run": lambda: with_states(simulator["sim"].run(T, U, X0)),
        "Simulator.run, outputs read":
            lambda: simulator["sim"].run(T, U, X0).outputs,
        "Simulator.outputs": lambda: simulator["sim"].outputs(T, U, X0),
        "Simulator(...)": setup,
    }
    outputs = {
        "forced_response": np.asarray(methods["forced_response"]().y),
        "lsim": np.atleast_2d(methods["lsim"]()[1].T),
        "simulate": np.asarray(methods["simulate"]().y),
        "Simulator.run": np.asarray(methods["Simulator.run"]().y),
    }
    times = {k: [] for k in methods}
    order = list(methods)
    for r in range(repeats):
        for k in order[r % len(order):] + order[:r % len(order)]:
            t0 = time.perf_counter()
            methods[k]()
            times[k].append(time.perf_counter() - t0)
    med = {k: statistics.median(v) for k, v in times.items()}
    ref = outputs["forced_response"]
    errors = {
        "simulate_vs_forced_response":
            relative_error(outputs["simulate"], ref),
        "Simulator.run_vs_forced_response":
            relative_error(outputs["Simulator.run"], ref),
        "simulate_vs_lsim":
            relative_error(outputs["simulate"], outputs["lsim"]),
        "lsim_vs_forced_response": relative_error(outputs["lsim"], ref)}
    if reference:
        for exact, label in ((False, "float64_discrete"), (True, "exact")):
            y_ref = extended_precision_reference(simulator["sim"], T, U, X0,
                                                 exact=exact)
            for k in ("forced_response", "lsim", "simulate"):
                errors[f"{k}_vs_{label}"] = relative_error(outputs[k], y_ref)
    return {
        "case": name,
        "n_states": sys_.nstates, "n_inputs": sys_.ninputs,
        "n_outputs": sys_.noutputs, "n_samples": n_samples, "dt_s": dt,
        "chunk_length": {
            "run": simulator["sim"].chunk_length(with_states=True),
            "outputs": simulator["sim"].chunk_length(with_states=False)},
        "repeats": repeats,
        "median_time_s": med,
        "all_times_s": times,
        "speedup_vs_forced_response": {
            "simulate": med["forced_response"] / med["simulate"],
            "Simulator.run": med["forced_response"] / med["Simulator.run"]},
        "speedup_vs_lsim": {
            "simulate": med["lsim"] / med["simulate"],
            "Simulator.run": med["lsim"] / med["Simulator.run"]},
        "speedup_outputs_only_vs_forced_response": {
            "simulate, outputs read":
                med["forced_response"] / med["simulate, outputs read"],
            "Simulator.run, outputs read":
                med["forced_response"] / med["Simulator.run, outputs read"],
            "Simulator.outputs":
                med["forced_response"] / med["Simulator.outputs"]},
        "max_error_rel_range": errors,
    }


def machine_info() -> dict:
    cpu = platform.processor()
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return {
        "date_utc": datetime.datetime.now(datetime.timezone.utc)
        .strftime("%Y-%m-%d %H:%M"),
        "cpu": cpu, "nproc": os.cpu_count(),
        "load_average_1_5_15": list(os.getloadavg()),
        "blas_threads_env": {k: os.environ[k] for k in
                             ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                              "MKL_NUM_THREADS") if k in os.environ},
        "python": platform.python_version(), "numpy": np.__version__,
        "scipy": scipy.__version__, "control": control.__version__,
    }


def print_table(cases: list) -> None:
    """Timing table (medians, ms) and accuracy table (relative to range)."""
    head = (f"{'case':27s} {'n':>4s} {'N':>6s} {'fr':>7s} {'lsim':>7s} "
            f"{'sim':>7s} {'sim-y':>6s} {'setup':>6s} {'run':>7s} "
            f"{'run-y':>6s} {'outputs':>7s} {'fr/sim':>6s} {'fr/sim-y':>8s} "
            f"{'fr/run':>6s} {'fr/run-y':>8s} {'fr/out':>6s} {'lsim/run':>8s}")
    print(head)
    print("-" * len(head))
    for c in cases:
        t = {k: 1e3 * v for k, v in c["median_time_s"].items()}
        fr = t["forced_response"]
        print(f"{c['case']:27s} {c['n_states']:4d} {c['n_samples']:6d} "
              f"{fr:7.1f} {t['lsim']:7.1f} {t['simulate']:7.1f} "
              f"{t['simulate, outputs read']:6.1f} "
              f"{t['Simulator(...)']:6.1f} {t['Simulator.run']:7.1f} "
              f"{t['Simulator.run, outputs read']:6.1f} "
              f"{t['Simulator.outputs']:7.1f} {fr / t['simulate']:6.1f} "
              f"{fr / t['simulate, outputs read']:8.1f} "
              f"{fr / t['Simulator.run']:6.1f} "
              f"{fr / t['Simulator.run, outputs read']:8.1f} "
              f"{fr / t['Simulator.outputs']:6.1f} "
              f"{t['lsim'] / t['Simulator.run']:8.1f}")
    print()
    head = (f"{'case':27s} {'sim-fr':>8s} {'lsim-fr':>8s} | {'fr-ref64':>8s} "
            f"{'lsim-ref64':>10s} {'sim-ref64':>9s} | {'fr-exact':>8s} "
            f"{'lsim-exact':>10s} {'sim-exact':>9s}")
    print(head)
    print("-" * len(head))
    for c in cases:
        e = c["max_error_rel_range"]

        def fmt(key, width):
            return f"{e[key]:{width}.1e}" if key in e else f"{'-':>{width}s}"
        print(f"{c['case']:27s} {fmt('simulate_vs_forced_response', 8)} "
              f"{fmt('lsim_vs_forced_response', 8)} | "
              f"{fmt('forced_response_vs_float64_discrete', 8)} "
              f"{fmt('lsim_vs_float64_discrete', 10)} "
              f"{fmt('simulate_vs_float64_discrete', 9)} | "
              f"{fmt('forced_response_vs_exact', 8)} "
              f"{fmt('lsim_vs_exact', 10)} {fmt('simulate_vs_exact', 9)}")


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="only the 100-state, 1e4-sample closed loop")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument(
        "--blas-threads", type=int, default=None,
        help="re-run with OPENBLAS_NUM_THREADS/OMP_NUM_THREADS set to this "
        "(1 is the fair setting on a loaded shared machine, where threaded "
        "BLAS calls stall); results of each setting are kept side by side")
    args = parser.parse_args(argv)
    if args.blas_threads is not None and os.environ.get(
            "OPENBLAS_NUM_THREADS") != str(args.blas_threads):
        # BLAS reads its thread count when it is loaded: start afresh.
        env = dict(os.environ, OPENBLAS_NUM_THREADS=str(args.blas_threads),
                   OMP_NUM_THREADS=str(args.blas_threads))
        os.execve(sys.executable, [sys.executable, *sys.argv], env)
    dt = 0.01
    few = max(3, args.repeats // 2)
    # (name, system, samples, repeats, long-double reference?)
    cases = [("closed loop, 49 modes", attitude_loop(49), 10_000,
              args.repeats, True)]
    if not args.quick:
        cases += [
            ("closed loop, 4 modes", attitude_loop(4), 10_000, args.repeats,
             True),
            ("open-loop plant, 49 modes", flexible_plant(49), 10_000,
             args.repeats, True),
            ("closed loop, 49 modes, 1e5", attitude_loop(49), 100_000, few,
             True),
            ("closed loop, 249 modes", attitude_loop(249), 10_000, few,
             False),
        ]
    info = machine_info()
    results = []
    for name, sys_, n_samples, repeats, reference in cases:
        results.append(run_case(name, sys_, n_samples, dt, repeats,
                                reference))
        print(f"done: {name}, N = {n_samples}", flush=True)
    info["load_average_after"] = list(os.getloadavg())
    print()
    print_table(results)
    print("\nTimes [ms]: medians of interleaved runs in one process. fr = "
          "control.forced_response, lsim = scipy.signal.lsim, sim = "
          "simulate() (set-up included), setup = Simulator(...), run = "
          "Simulator.run; sim and run include reading the states (filled in "
          "on first use), sim-y and run-y read only the outputs; outputs = "
          "Simulator.outputs (no states, long chunks).\n"
          "Errors: max output difference / output range. ref64 = the "
          "float64 discrete matrices (shared by all) propagated in long "
          "double; exact = the block exponential and the propagation in "
          "long double.")
    print(f"load average before {info['load_average_1_5_15']}, after "
          f"{info['load_average_after']}")
    # One entry per BLAS thread setting (and --quick), the latest run each.
    label = ("blas_threads=" + os.environ.get("OPENBLAS_NUM_THREADS",
                                              "default")
             + (", quick" if args.quick else ""))
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    runs = {}
    if RESULTS.exists():
        try:
            runs = json.loads(RESULTS.read_text()).get("runs", {})
        except (json.JSONDecodeError, AttributeError):
            runs = {}
    runs[label] = {"machine": info, "cases": results}
    RESULTS.write_text(json.dumps({"runs": runs}, indent=1) + "\n")
    print(f"wrote {RESULTS.relative_to(ROOT)} [{label}]")


if __name__ == "__main__":
    main()
