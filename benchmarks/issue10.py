"""Issue 10, every measurement in one command: simulator, threads, scaling, design loop, CLI.

Run from the repository root (the user's BLAS settings, as a user runs flexsat)::

    python benchmarks/issue10.py            # everything (~15 min on 2 busy cores)
    python benchmarks/issue10.py --quick    # fewer sizes and repeats (~3 min)
    python benchmarks/issue10.py --only simulate,threads

Sections (each a table in ``results/performance.md``, data in ``results/performance.json``):

``simulate``
    issue 10's general system: lightly damped modes (0.1 to 1000 rad/s, damping 1e-3 to
    0.05) and two free rigid bodies, hidden by a random similarity transform of condition 4;
    2 inputs (random, linear between samples), 4 outputs; n = 20..400 states, N = 1e4 and 1e5
    samples, dt = 0.01 s.  Side by side in one process, methods taking turns: 
    ``control.forced_response``; flexsat ``simulate`` one shot (set-up included), outputs
    read or states read; a reused ``Simulator`` (set-up paid once); the compiled limit, a
    hand-written C modal recursion (gcc -O3 -march=native) on the same modal data (outputs
    fused; states: its modal states mapped by one BLAS product); and option (b) of the issue,
    a vectorised formulation without a compiler (one complex ``scipy.signal.lfilter`` per
    mode, inputs and outputs by matrix products: its timing, the least work it must do).
    Accuracy: max |y - y_ref| / range(y_ref) against an extended-precision solution (the
    Van Loan exponential and the recursion in long double) over the first 2000 samples
    (10^4 up to 100 states).
``first_call``
    the one-time cost of the compiled loop in a fresh process: import and load from the
    on-disk cache, and compiling with an empty cache.
``threads``
    one design-loop evaluation (``benchmarks/design_loop.py``) and a 196-state simulation
    in fresh processes: the user's default BLAS threads vs ``OPENBLAS_NUM_THREADS=1``, with
    flexsat's limiter as shipped, and with the whole evaluation inside
    ``controllers.threads.blas_threads_for`` (what limits at every entry point give); the
    cost of entering a limit.
``scaling``
    plant build, LQR, margins, loop frequency response and simulate against the number of
    states, and the log-log slope of each.
``design``
    the design loop with a 400-mode truth model.
``cli``
    ``flexsat --help`` and ``flexsat run`` (default scene, --no-fmu and full) wall times.

Medians of >= 5 repetitions; the load average is recorded with every section (the machine
is shared).  Not a test: nothing here asserts a time.
"""

from __future__ import annotations

import os

# The user's BLAS settings (flexsat limits threads itself): set before _common is imported.
os.environ.setdefault("FLEXSAT_BENCH_BLAS_THREADS", "default")

import _common  # noqa: E402,F401  (first: BLAS settings before numpy)

import argparse  # noqa: E402
import ctypes  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import control  # noqa: E402
import numpy as np  # noqa: E402
import scipy.signal  # noqa: E402

from _common import RESULTS, ROOT, machine_info, markdown_table, write_json  # noqa: E402

from controllers.modal_recursion import ModalRecursion  # noqa: E402
from controllers.simulate import Simulator, simulate  # noqa: E402


def load() -> list[float]:
    return [round(x, 2) for x in os.getloadavg()]


# -- the general system and its exact solution --------------------------------------------
def general_system(n: int, *, n_inputs: int = 2, n_outputs: int = 4, n_rigid: int = 2,
                   condition: float = 4.0, seed: int = 0) -> control.StateSpace:
    """Issue 10's general LTI system (see the module docstring)."""
    rng = np.random.default_rng(seed)
    n_modes = n // 2 - n_rigid
    w = np.exp(rng.uniform(np.log(0.1), np.log(1000.0), n_modes))
    zeta = np.exp(rng.uniform(np.log(1e-3), np.log(0.05), n_modes))
    A = np.zeros((n, n))
    for i in range(n_modes):
        sigma, wd = -zeta[i] * w[i], w[i] * np.sqrt(1 - zeta[i] ** 2)
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[sigma, wd], [-wd, sigma]]
    for i in range(n_modes, n // 2):
        A[2 * i, 2 * i + 1] = 1.0
    Q1, _ = np.linalg.qr(rng.standard_normal((n, n)))
    Q2, _ = np.linalg.qr(rng.standard_normal((n, n)))
    S = Q1 @ np.diag(np.geomspace(1.0, condition, n)) @ Q2
    S_inv = np.linalg.inv(S)
    return control.ss(S @ A @ S_inv, S @ rng.standard_normal((n, n_inputs)),
                      rng.standard_normal((n_outputs, n)) @ S_inv, 0)


def long_double_expm(M: np.ndarray) -> np.ndarray:
    """expm(M) in numpy.longdouble: scaling and squaring, degree-18 Taylor polynomial of
    M / 2^s with ||M / 2^s||_inf <= 1/2 (remainder 0.5^19 / 19! ~ 1.6e-23, below the
    long-double round-off ~1e-19)."""
    M = np.asarray(M, dtype=np.longdouble)
    norm = float(np.abs(M).sum(axis=1).max())
    s = max(0, int(np.ceil(np.log2(max(norm, 1e-300) / 0.5))))
    X = M / np.longdouble(2.0) ** s
    eye = np.eye(M.shape[0], dtype=np.longdouble)
    E = eye.copy()
    for k in range(18, 0, -1):
        E = eye + (X @ E) / k
    for _ in range(s):
        E = E @ E
    return E


def exact_response(sys: control.StateSpace, dt: float, U: np.ndarray, hold: str):
    """Outputs and states from x(0) = 0, in long double (Van Loan exponential and
    recursion): the exact solution of the float64 system to ~1e-16."""
    ld = np.longdouble
    A, B, C, D = (np.asarray(M, dtype=ld) for M in (sys.A, sys.B, sys.C, sys.D))
    n, m = B.shape
    M = np.zeros((n + 2 * m, n + 2 * m), dtype=ld)
    M[:n, :n], M[:n, n:n + m] = A * ld(dt), B * ld(dt)
    M[n:n + m, n + m:] = np.eye(m, dtype=ld)
    E = long_double_expm(M)
    Ad, G1, G2 = E[:n, :n], E[:n, n:n + m], E[:n, n + m:]
    Bd0, Bd1 = (G1 - G2, G2) if hold == "linear" else (G1, 0 * G2)
    U = U.astype(ld)
    W = Bd0 @ U[:, :-1] + Bd1 @ U[:, 1:]
    X = np.zeros((n, U.shape[1]), dtype=ld)
    for k in range(U.shape[1] - 1):
        X[:, k + 1] = Ad @ X[:, k] + W[:, k]
    return (C @ X + D @ U).astype(float), X.astype(float)


def relative_error(y, y_ref) -> float:
    """max |y - y_ref| / range(y_ref), max over signals."""
    y, y_ref = np.atleast_2d(y), np.atleast_2d(y_ref)
    scale = np.maximum(np.ptp(y_ref, axis=1), np.finfo(float).tiny)
    return float(np.max(np.abs(y - y_ref).max(axis=1) / scale))


# -- the compiled limit: a hand-written C modal recursion --------------------------------
C_SOURCE = r"""
#include <stddef.h>
/* z[k+1] = Phi z[k] + G0^T u[k] + G1^T u[k+1]; y[k] = HD^T [z[k]; u[k]]; optional Z out.
   Pairs: (z[j], z[np + j]) with 2x2 blocks f; clusters dense (row-major) after them. */
void modal(int N, int np_, int nz, int m, int p, const double *f00, const double *f01,
           const double *f10, const double *f11, int ncl, const long *cls, const long *clo,
           const double *clphi, const double *G0, const double *G1, const double *HD,
           const double *U, const double *z0, double *Y, double *Z, double *z, double *w)
{
    for (int j = 0; j < nz; j++) z[j] = z0[j];
    for (int k = 0; k < N; k++) {
        const double *u = U + (size_t)k * m, *u1 = u + m;
        double *y = Y + (size_t)k * p;
        for (int i = 0; i < p; i++) {
            double acc = 0.0;
            for (int j = 0; j < nz; j++) acc += HD[(size_t)j * p + i] * z[j];
            for (int j = 0; j < m; j++) acc += HD[(size_t)(nz + j) * p + i] * u[j];
            y[i] = acc;
        }
        if (Z) for (int j = 0; j < nz; j++) Z[(size_t)k * nz + j] = z[j];
        for (int j = 0; j < nz; j++) {
            double acc = 0.0;
            for (int i = 0; i < m; i++) acc += G0[(size_t)i * nz + j] * u[i] + G1[(size_t)i * nz + j] * u1[i];
            w[j] = acc;
        }
        for (int j = 0; j < np_; j++) {
            double a = z[j], b = z[np_ + j];
            z[j] = f00[j] * a + f01[j] * b + w[j];
            z[np_ + j] = f10[j] * a + f11[j] * b + w[np_ + j];
        }
        for (int c = 0; c < ncl; c++) {
            long i0 = cls[c], s = cls[c + 1] - cls[c];
            double tmp[256];
            for (long i = 0; i < s; i++) {
                double acc = w[i0 + i];
                for (long l = 0; l < s; l++) acc += clphi[clo[c] + i * s + l] * z[i0 + l];
                tmp[i] = acc;
            }
            for (long i = 0; i < s; i++) z[i0 + i] = tmp[i];
        }
    }
}
"""


class CompiledLimit:
    """The C modal recursion above, compiled with gcc into a temporary directory."""

    def __init__(self, directory: Path):
        source = directory / "modal.c"
        library = directory / "modal.so"
        source.write_text(C_SOURCE)
        subprocess.run(["gcc", "-O3", "-march=native", "-shared", "-fPIC", "-o", str(library),
                        str(source)], check=True)
        self.lib = ctypes.CDLL(str(library))
        self.lib.modal.restype = None

    def run(self, mr: ModalRecursion, U: np.ndarray, *, with_states: bool):
        N = U.shape[1]
        m, nz, p = mr._m, mr._nz, mr._p
        U_rows = np.zeros((N + 1, m))
        U_rows[:N] = U.T
        Y = np.empty((N, p))
        Z = np.empty((N, nz)) if with_states else None
        z, w = np.empty(nz), np.empty(nz)
        ptr = lambda a: a.ctypes.data_as(ctypes.c_void_p)  # noqa: E731
        f00, f01, f10, f11 = mr._f
        self.lib.modal(ctypes.c_int(N), ctypes.c_int(mr.n_pairs), ctypes.c_int(nz),
                       ctypes.c_int(m), ctypes.c_int(p), ptr(f00), ptr(f01), ptr(f10),
                       ptr(f11), ctypes.c_int(len(mr.cluster_sizes)), ptr(mr._cl_starts),
                       ptr(mr._cl_offsets), ptr(mr._cl_phi), ptr(mr._G0), ptr(mr._G1),
                       ptr(mr._HD), ptr(U_rows), ptr(np.zeros(nz)), ptr(Y),
                       ptr(Z) if Z is not None else None, ptr(z), ptr(w))
        X = (Z @ mr._VT[:nz]).T if with_states else None
        return Y.T, X


def lfilter_option(mr: ModalRecursion, U: np.ndarray) -> np.ndarray:
    """Timing model of the issue's option (b): every 2 x 2 block as one complex first-order
    section z[k+1] = mu z[k] + w[k] run by scipy.signal.lfilter (a Python loop over the
    modes), inputs and outputs by matrix products.  It does the work the option must do
    (one complex section per mode); it is not a full implementation (the eigenvectors of the
    blocks are not applied), so only its time is reported."""
    npair = mr.n_pairs
    f00, f01, f10, f11 = mr._f
    tr, det = f00 + f11, f00 * f11 - f01 * f10
    mu = 0.5 * tr + np.sqrt((0.5 * tr) ** 2 - det + 0j)
    W = (mr._G0[:, :npair] + 1j * mr._G0[:, npair:2 * npair]).T @ U
    Z = np.empty_like(W)
    for j in range(npair):
        Z[j] = scipy.signal.lfilter([0.0, 1.0], [1.0, -mu[j]], W[j])
    H = mr._HD[:npair] + 1j * mr._HD[npair:2 * npair]
    return (H.T @ Z).real


def interleaved(methods: dict, repeats: int, max_seconds: float = 120.0
                ) -> tuple[dict, dict]:
    """Median wall time and median CPU time [s] of each method, the methods taking turns
    (load changes hit them alike); fewer repeats (>= 3) when the rounds exceed max_seconds.

    The CPU time is the calling thread's (time.thread_time): it does not count the time a
    loaded machine keeps the process waiting, so its ratios hold under load.  It leaves out
    BLAS worker threads, whose work helps only forced_response here (flexsat runs these
    sizes single-threaded), so its ratios are conservative for flexsat.
    """
    wall = {k: [] for k in methods}
    cpu = {k: [] for k in methods}
    order = list(methods)
    start = time.perf_counter()
    for r in range(repeats):
        for k in order[r % len(order):] + order[:r % len(order)]:
            c0, t0 = time.thread_time(), time.perf_counter()
            methods[k]()
            wall[k].append(time.perf_counter() - t0)
            cpu[k].append(time.thread_time() - c0)
        if r >= 2 and time.perf_counter() - start > max_seconds:
            break
    return ({k: statistics.median(v) for k, v in wall.items()},
            {k: statistics.median(v) for k, v in cpu.items()})


def section_simulate(sizes, lengths, repeats, limit: CompiledLimit) -> list[dict]:
    rows = []
    dt = 0.01
    # Load the compiled loop first (its one-time cost is the first_call section's).
    simulate(general_system(20), np.arange(20_000) * dt, 1.0).outputs
    for n in sizes:
        sys = general_system(n)
        # One input sequence per size: the runs of every length share their first samples,
        # and so their exact solution (causality).
        U_all = np.random.default_rng(n).standard_normal((sys.ninputs, max(lengths)))
        N_acc = min(lengths[0], 10_000 if n <= 100 else 2000)
        references = {}
        for N in lengths:
            for hold in (("linear", "zero") if n == 100 else ("linear",)):
                T = np.arange(N) * dt
                U = U_all[:, :N]
                sim = Simulator(sys, dt, hold=hold)
                t0 = time.perf_counter()
                method = sim.method_for(N)           # the set-up (form, discretisation)
                setup = time.perf_counter() - t0
                mr = sim._modal
                fr_sys = sys if hold == "linear" else control.c2d(sys, dt, "zoh")
                methods = {
                    "forced_response": lambda: control.forced_response(fr_sys, T, U),
                    "simulate, outputs": lambda: simulate(sys, T, U, hold=hold).outputs,
                    "simulate, states": lambda: simulate(sys, T, U, hold=hold).states,
                    "Simulator.outputs": lambda: sim.outputs(T, U),
                    "Simulator.run, states": lambda: sim.run(T, U).states,
                    "C limit, outputs": lambda: limit.run(mr, U, with_states=False),
                    "C limit, states": lambda: limit.run(mr, U, with_states=True),
                    "lfilter (b), outputs": lambda: lfilter_option(mr, U),
                }
                med, cpu = interleaved(methods, repeats)
                if hold not in references:
                    references[hold] = exact_response(sys, dt, U[:, :N_acc], hold)
                y_ref, x_ref = references[hold]
                fr = control.forced_response(fr_sys, T[:N_acc], U[:, :N_acc])
                flex = Simulator(sys, dt, hold=hold, method=method).run(T[:N_acc],
                                                                        U[:, :N_acc])
                y_limit, x_limit = limit.run(mr, U[:, :N_acc], with_states=True)
                errors = {
                    "forced_response": relative_error(fr.y, y_ref),
                    "flexsat": relative_error(flex.y, y_ref),
                    "C limit": relative_error(y_limit, y_ref),
                    "forced_response, states": relative_error(fr.x, x_ref),
                    "flexsat, states": relative_error(flex.states, x_ref),
                }
                fr_t = med["forced_response"]
                row = {
                    "n": n, "N": N, "hold": hold, "method": method,
                    "modal_condition": None if mr is None else mr.form.condition,
                    "clusters": None if mr is None else mr.cluster_sizes,
                    "setup_s": setup, "median_s": med, "median_cpu_s": cpu,
                    "error_samples": N_acc,
                    "errors": errors,
                    "speedup_vs_forced_response": {k: fr_t / v for k, v in med.items()},
                    "speedup_vs_forced_response_cpu": {
                        k: cpu["forced_response"] / v for k, v in cpu.items()},
                    "vs_limit": {
                        "Simulator.outputs": med["Simulator.outputs"] / med["C limit, outputs"],
                        "Simulator.run, states":
                            med["Simulator.run, states"] / med["C limit, states"],
                        "lfilter (b), outputs":
                            med["lfilter (b), outputs"] / med["C limit, outputs"]},
                    "load": load(),
                }
                rows.append(row)
                print(f"simulate n={n} N={N} {hold}: fr {fr_t * 1e3:.1f} ms, one-shot outputs "
                      f"x{fr_t / med['simulate, outputs']:.1f}, states "
                      f"x{fr_t / med['simulate, states']:.1f}, reused outputs "
                      f"x{fr_t / med['Simulator.outputs']:.1f}, states "
                      f"x{fr_t / med['Simulator.run, states']:.1f}; errors flexsat "
                      f"{errors['flexsat']:.1e} fr {errors['forced_response']:.1e}; cpu ratios "
                      f"{ {k: round(cpu['forced_response'] / v, 1) for k, v in cpu.items()} }; "
                      f"load {load()}", flush=True)
    return rows


# -- fresh-process measurements ------------------------------------------------------------
def run_python(code: str, env_update: dict | None = None, unset=()) -> dict:
    """Run code in a fresh interpreter at the repository root; it prints one JSON line."""
    env = dict(os.environ)
    for key in unset:
        env.pop(key, None)
    # _common.py leaves the BLAS variables as this environment has them.
    env["FLEXSAT_BENCH_BLAS_THREADS"] = "default"
    env.update(env_update or {})
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), str(ROOT / "benchmarks")])
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=env, check=True,
                         capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


FIRST_CALL = r"""
import json, time
t0 = time.perf_counter()
import numpy as np, control
from controllers.simulate import Simulator
t1 = time.perf_counter()
from benchmarks_general import general_system
sys = general_system(20)
T = np.arange(10000) * 0.01; U = np.ones((2, T.size))
t2 = time.perf_counter(); Simulator(sys, 0.01).outputs(T, U); t3 = time.perf_counter()
Simulator(sys, 0.01).outputs(T, U); t4 = time.perf_counter()
print(json.dumps({"import_s": t1 - t0, "first_simulation_s": t3 - t2,
                  "second_simulation_s": t4 - t3}))
"""


def section_first_call(repeats: int) -> dict:
    code = FIRST_CALL.replace("from benchmarks_general import general_system",
                              "from issue10 import general_system")
    warm = [run_python(code) for _ in range(repeats)]
    cold = []
    for _ in range(max(1, repeats // 2)):
        with tempfile.TemporaryDirectory() as cache:
            cold.append(run_python(code, {"NUMBA_CACHE_DIR": cache}))
    med = lambda rows, k: statistics.median(r[k] for r in rows)  # noqa: E731
    out = {"warm_cache": {k: med(warm, k) for k in warm[0]},
           "cold_cache": {k: med(cold, k) for k in cold[0]}, "load": load()}
    print("first call:", json.dumps(out), flush=True)
    return out


THREADS = r"""
import json, statistics, time, warnings
warnings.simplefilter("ignore")
import numpy as np
import design_loop
import controllers.threads as threads
from controllers.threads import blas_threads_for
from issue10 import general_system
from controllers.simulate import simulate
mode = "MODE"
if mode == "no limiter":
    threads.SINGLE_THREAD_BELOW = 0
def evaluate():
    if mode == "whole evaluation limited":
        with blas_threads_for(0):
            design_loop.evaluate()
    else:
        design_loop.evaluate()
sys196 = general_system(196)
T = np.arange(10000) * 0.01; U = np.ones((2, T.size))
def sim196():
    if mode == "whole evaluation limited":
        with blas_threads_for(0):
            simulate(sys196, T, U).states
    else:
        simulate(sys196, T, U).states
out = {}
for name, f in (("design_loop", evaluate), ("simulate_196_states", sim196)):
    f()
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter(); f(); times.append(time.perf_counter() - t0)
    out[name] = statistics.median(times)
print(json.dumps(out))
"""


def section_threads(repeats: int) -> dict:
    blas_vars = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
    out = {}
    for mode in ("no limiter", "as shipped", "whole evaluation limited"):
        code = THREADS.replace("MODE", mode).replace("REPEATS", str(max(repeats, 15)))
        default = run_python(code, unset=blas_vars)
        single = run_python(code, {k: "1" for k in blas_vars})
        out[mode] = {"default_threads_s": default, "single_thread_s": single,
                     "ratio_default_over_single": {k: default[k] / single[k] for k in default},
                     "load": load()}
        print(f"threads, {mode}: {json.dumps(out[mode])}", flush=True)
    # The cost of entering and leaving a limit (outermost region: two calls into BLAS).
    from controllers.threads import blas_threads_for

    def enter_exit():
        with blas_threads_for(10):
            pass
    n = 2000
    t0 = time.perf_counter()
    for _ in range(n):
        enter_exit()
    out["limit_enter_exit_us"] = (time.perf_counter() - t0) / n * 1e6
    with blas_threads_for(10):
        t0 = time.perf_counter()
        for _ in range(n):
            enter_exit()
        out["nested_limit_enter_exit_us"] = (time.perf_counter() - t0) / n * 1e6
    return out


SCALING = r"""
import json, statistics, time, warnings
warnings.simplefilter("ignore")
import numpy as np
import controllers
from _common import paper_rod, spacecraft_with, slew_inputs
beam = paper_rod()
out = {}
for n_modes in SIZES:
    times = {}
    def build():
        return spacecraft_with(beam.truncated(n_modes)).plant()
    plant = build()
    J = controllers.rigid_body_inertia(plant)
    def lqr():
        return controllers.lqr(plant, attitude_weight=(J * 0.1 ** 2) ** 2, rate_weight=0.0,
                               torque_weight=1.0)
    controller = controllers.pd(plant, natural_frequency=0.1, damping=0.7)
    loop = controllers.close_loop(plant, controller)
    T = np.arange(10001) * 0.01
    U = slew_inputs(loop, T)
    stages = {"plant build": build, "lqr": lqr,
              "margins": lambda: controllers.margins(plant, controller),
              "frequency response": lambda: controllers.loop_frequency_response(plant, controller),
              "simulate": lambda: controllers.simulate(loop, T, U).outputs}
    row = {"n_states": plant.nstates}
    for name, f in stages.items():
        try:
            f()
            ts = []
            for _ in range(REPEATS):
                t0 = time.perf_counter(); f(); ts.append(time.perf_counter() - t0)
            row[name] = statistics.median(ts)
        except Exception as error:
            row[name] = None
            row[name + " error"] = str(error)[:100]
    out[n_modes] = row
print(json.dumps(out))
"""


def section_scaling(sizes, repeats: int) -> dict:
    data = run_python(SCALING.replace("SIZES", repr(list(sizes))).replace("REPEATS",
                                                                          str(repeats)))
    rows = list(data.values())
    slopes = {}
    for stage in ("plant build", "lqr", "margins", "frequency response", "simulate"):
        pts = [(r["n_states"], r[stage]) for r in rows if r.get(stage)]
        pts = pts[-3:]                       # the largest sizes: the asymptotic slope
        if len(pts) >= 2:
            x, y = np.log([p[0] for p in pts]), np.log([p[1] for p in pts])
            slopes[stage] = float(np.polyfit(x, y, 1)[0])
    out = {"rows": rows, "loglog_slope_largest_3": slopes, "load": load()}
    print("scaling:", json.dumps(out), flush=True)
    return out


DESIGN = r"""
import json, statistics, time, warnings
warnings.simplefilter("ignore")
import design_loop
design_loop.N_MODES = NMODES
times = {}
design_loop.evaluate(times)
times = {}
for _ in range(REPEATS):
    design_loop.evaluate(times)
print(json.dumps({k: statistics.median(v) for k, v in times.items()}))
"""


def section_design(repeats: int) -> dict:
    out = {}
    for n_modes in (20, 400):
        out[f"{n_modes} modes"] = run_python(DESIGN.replace("NMODES", str(n_modes))
                                             .replace("REPEATS", str(repeats)))
        print(f"design loop, {n_modes} modes: {json.dumps(out[f'{n_modes} modes'])}",
              flush=True)
    out["load"] = load()
    return out


def section_cli(repeats: int) -> dict:
    out = {}
    env = dict(os.environ)
    env.pop("FLEXSAT_BENCH_BLAS_THREADS", None)
    for label, args in (("flexsat --help", ["--help"]),
                        ("flexsat run --no-fmu", ["run", "--no-fmu", "--quiet"]),
                        ("flexsat run", ["run", "--quiet"])):
        times = []
        for _ in range(repeats if label == "flexsat --help" else max(3, repeats // 2)):
            with tempfile.TemporaryDirectory() as tmp:
                extra = ["--out", str(Path(tmp) / "out")] if args[0] == "run" else []
                t0 = time.perf_counter()
                subprocess.run([sys.executable, "-m", "spacecraft.cli", *args, *extra],
                               cwd=ROOT, env=env, check=True, capture_output=True)
                times.append(time.perf_counter() - t0)
        out[label] = statistics.median(times)
        print(f"{label}: {out[label]:.2f} s", flush=True)
    out["load"] = load()
    return out


# -- report ---------------------------------------------------------------------------------
def markdown(results: dict) -> str:
    m = results["machine"]
    lines = ["# Issue 10: performance, every figure side by side", "",
             f"`python benchmarks/issue10.py` on {m['date_utc']} UTC ({m['cpu']}, "
             f"{m['nproc']} cores, shared; load average at the start "
             f"{m['load_average_1_5_15min']}), the user's default BLAS settings. Medians of "
             f">= {results['repeats']} runs (3 where one round took over 2 min); ratios "
             "measured in one process.", ""]
    if "simulate" in results:
        lines += ["## Simulation: flexsat vs forced_response vs the compiled limit", "",
                  "Speed-ups over `control.forced_response` (its time in ms). one-shot = "
                  "`simulate()` with its set-up; reused = a `Simulator` built once (set-up "
                  "in its own column). limit = hand-written C modal recursion on the same "
                  "modal data; x limit = flexsat's time over the limit's. (b) = one "
                  "`lfilter` per mode. cpu: the same speed-ups from the main thread's CPU "
                  "time (robust to a loaded machine's waits; BLAS worker threads, which help "
                  "only forced_response, left out). Errors: max |y - y_exact| "
                  "/ range over the first samples given, against long double; err x: the "
                  "states.", ""]
        header = ["n", "N", "hold", "fr [ms]", "setup [ms]", "one-shot y", "one-shot x",
                  "reused y", "reused x", "cpu: one-shot y", "one-shot x", "reused y",
                  "reused x", "x limit (y)", "x limit (x)", "(b) y / limit",
                  "err flexsat", "err fr", "err limit", "err x flexsat", "err x fr",
                  "cond V", "load"]
        body = []
        for r in results["simulate"]:
            s, e, v = r["speedup_vs_forced_response"], r["errors"], r["vs_limit"]
            c = r.get("speedup_vs_forced_response_cpu", s)
            body.append([r["n"], r["N"], r["hold"], f"{r['median_s']['forced_response'] * 1e3:.0f}",
                         f"{r['setup_s'] * 1e3:.1f}", f"{s['simulate, outputs']:.1f}",
                         f"{s['simulate, states']:.1f}", f"{s['Simulator.outputs']:.1f}",
                         f"{s['Simulator.run, states']:.1f}", f"{c['simulate, outputs']:.1f}",
                         f"{c['simulate, states']:.1f}", f"{c['Simulator.outputs']:.1f}",
                         f"{c['Simulator.run, states']:.1f}", f"{v['Simulator.outputs']:.2f}",
                         f"{v['Simulator.run, states']:.2f}", f"{v['lfilter (b), outputs']:.1f}",
                         f"{e['flexsat']:.1e}", f"{e['forced_response']:.1e}",
                         f"{e['C limit']:.1e}", f"{e['flexsat, states']:.1e}",
                         f"{e['forced_response, states']:.1e}",
                         "-" if r["modal_condition"] is None else f"{r['modal_condition']:.0f}",
                         r["load"][0]])
        lines += [markdown_table(header, body), ""]
    if "first_call" in results:
        f = results["first_call"]
        lines += ["## First call (fresh process)", "",
                  markdown_table(["cache", "import flexsat [s]", "first simulation [s]",
                                  "second [s]"],
                                 [[k, f"{f[k]['import_s']:.2f}",
                                   f"{f[k]['first_simulation_s']:.2f}",
                                   f"{f[k]['second_simulation_s']:.4f}"]
                                  for k in ("warm_cache", "cold_cache")]),
                  f"(load {f['load']})", ""]
    if "threads" in results:
        t = results["threads"]
        rows = []
        for mode in ("no limiter", "as shipped", "whole evaluation limited"):
            for stage in ("design_loop", "simulate_196_states"):
                rows.append([mode, stage, f"{t[mode]['default_threads_s'][stage] * 1e3:.1f}",
                             f"{t[mode]['single_thread_s'][stage] * 1e3:.1f}",
                             f"{t[mode]['ratio_default_over_single'][stage]:.2f}",
                             t[mode]["load"][0]])
        lines += ["## BLAS threads: default vs OPENBLAS_NUM_THREADS=1", "",
                  markdown_table(["limiter", "work", "default [ms]", "1 thread [ms]",
                                  "default / 1", "load"], rows), "",
                  f"Entering and leaving a limit: {t['limit_enter_exit_us']:.1f} us "
                  f"(nested: {t['nested_limit_enter_exit_us']:.2f} us).", ""]
    if "scaling" in results:
        sc = results["scaling"]
        stages = ["plant build", "lqr", "margins", "frequency response", "simulate"]
        lines += ["## Scaling with the number of states (times in ms)", "",
                  markdown_table(["states", *stages],
                                 [[r["n_states"], *("-" if r.get(s) is None else
                                                    f"{r[s] * 1e3:.1f}" for s in stages)]
                                  for r in sc["rows"]]), "",
                  "Log-log slopes over the three largest sizes: " + ", ".join(
                      f"{k} {v:.2f}" for k, v in sc["loglog_slope_largest_3"].items())
                  + f" (load {sc['load']}).", ""]
    if "design" in results:
        d = results["design"]
        keys = list(d["20 modes"])
        lines += ["## Design-loop evaluation, stage by stage (ms)", "",
                  markdown_table(["truth model", *keys],
                                 [[k, *(f"{d[k][s] * 1e3:.1f}" for s in keys)]
                                  for k in ("20 modes", "400 modes")]),
                  f"(load {d['load']})", ""]
    if "cli" in results:
        c = results["cli"]
        lines += ["## Command line (wall time, s)", "",
                  markdown_table(["command", "median [s]"],
                                 [[k, f"{v:.2f}"] for k, v in c.items() if k != "load"]),
                  f"(load {c['load']})", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--only", default="simulate,first_call,threads,scaling,design,cli")
    parser.add_argument("--markdown", action="store_true",
                        help="only rewrite performance.md from performance.json")
    args = parser.parse_args(argv)
    if args.markdown:
        text = markdown(json.loads((RESULTS / "performance.json").read_text()))
        (RESULTS / "performance.md").write_text(text + "\n")
        print(text)
        return 0
    sections = args.only.split(",")
    repeats = max(args.repeats, 5)
    results = {}
    if args.only != parser.get_default("only") and (RESULTS / "performance.json").exists():
        # Some sections only: keep the others' results from the last run.
        results = json.loads((RESULTS / "performance.json").read_text())
    results.update({"machine": machine_info(), "repeats": repeats})
    if "simulate" in sections:
        sizes = (20, 100) if args.quick else (20, 50, 100, 200, 400)
        lengths = (10_000,) if args.quick else (10_000, 100_000)
        with tempfile.TemporaryDirectory() as tmp:
            results["simulate"] = section_simulate(sizes, lengths, repeats,
                                                   CompiledLimit(Path(tmp)))
    if "first_call" in sections:
        results["first_call"] = section_first_call(repeats)
    if "threads" in sections:
        results["threads"] = section_threads(repeats)
    if "scaling" in sections:
        sizes = (10, 40) if args.quick else (10, 25, 50, 100, 200)
        results["scaling"] = section_scaling(sizes, repeats)
    if "design" in sections:
        results["design"] = section_design(repeats)
    if "cli" in sections:
        results["cli"] = section_cli(repeats)
    results["load_at_end"] = load()
    write_json("performance.json", results)
    text = markdown(results)
    (RESULTS / "performance.md").write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
