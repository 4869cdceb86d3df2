"""The dense linear algebra a three-axis design-loop evaluation cannot do without, timed.

The workload is the three-axis design-loop evaluation of ``benchmarks/three_axis.py`` (two
wings and a boom, 56 truth states; a 46-state LQR + Kalman controller tuned on the 3-body
chains; build, LQR, close, a 100 s slew at 100 Hz, the multiloop margins on the truth plant).
Every call into the dense eigenvalue, Schur, Sylvester and ordering routines of LAPACK (through
numpy.linalg and scipy.linalg) is counted and timed where it is made, by call site and matrix
order; each call of order >= 40 is also timed again alone, on a copy of the same matrix, with
one BLAS thread. Beside them the evaluation's own CPU time (medians of ``--repeats``).

Which of these calls the method needs: the LQR and the Kalman filter each solve a Riccati
equation (the ordered real Schur form of a Hamiltonian of twice the design order); the
simulation puts the closed loop in modal form (its real Schur form); the margins need the poles
of each loop-at-a-time function (the closed loop with one torque's loop open: one eigenvalue
problem per axis) and the zeros that the frequency grid resolves (one eigenvalue problem per
axis); the stability verdict needs the closed loop's poles. Their sum, alone, is a lower bound
on an evaluation by this method on this machine, whatever the Python around it costs.

Run: ``python benchmarks/three_axis_floor.py [--repeats 15]``. Output:
``results/three_axis_floor.{json,md}``.
"""

from __future__ import annotations

import _common  # noqa: F401  (BLAS threads, sys.path)

import argparse
import collections
import os
import statistics
import sys
import time
import traceback
import warnings

import numpy as np
import scipy.linalg
import scipy.linalg.lapack
from threadpoolctl import threadpool_limits

from _common import RESULTS, machine_info, markdown_table, write_json
import three_axis

# (module, name) of the dense O(n^3) routines a design loop calls
ROUTINES = [(np.linalg, "eigvals"), (np.linalg, "eig"), (np.linalg, "eigh"),
            (scipy.linalg, "schur"), (scipy.linalg, "eig"), (scipy.linalg, "eigvals"),
            (scipy.linalg, "eigh"), (scipy.linalg, "hessenberg"),
            (scipy.linalg.lapack, "dtrsen"), (scipy.linalg.lapack, "ztrsen"),
            (scipy.linalg.lapack, "dtrsyl"), (scipy.linalg.lapack, "ztrsyl"),
            (scipy.linalg.lapack, "dtrexc")]
LARGE = 40  # matrices of at least this order are timed again alone


def _site() -> str:
    """The flexsat functions that made the call, innermost first (three frames)."""
    frames = [f for f in traceback.extract_stack()[:-2]
              if "site-packages" not in f.filename and "three_axis_floor" not in f.filename]
    return " < ".join(f"{os.path.basename(f.filename)}:{f.name}" for f in frames[-3:][::-1])


class Recorder:
    """Wraps :data:`ROUTINES`; records (routine, order, site) -> [CPU seconds], and the
    arguments of the first large call of each key (to time it again alone)."""

    def __init__(self):
        self.times = collections.defaultdict(list)
        self.args = {}
        self.originals = []
        self.active = False

    def __enter__(self):
        for module, name in ROUTINES:
            original = getattr(module, name)
            self.originals.append((module, name, original))
            setattr(module, name, self._wrap(name, original))
        return self

    def __exit__(self, *exc):
        for module, name, original in self.originals:
            setattr(module, name, original)

    def _wrap(self, name, original):
        def wrapped(*args, **kwargs):
            if not self.active:
                return original(*args, **kwargs)
            a = np.asarray(args[0]) if args else np.zeros((0, 0))
            if a.ndim < 2 and len(args) > 1:   # ?trsen(select, T, ...): the order of T
                a = np.asarray(args[1])
            order = a.shape[-1] if a.ndim >= 2 else 0
            batch = int(np.prod(a.shape[:-2])) if a.ndim > 2 else 1
            key = (name, order, batch, _site())
            if order >= LARGE and key not in self.args:
                # copied before the call: a routine may overwrite its input
                self.args[key] = (original, [np.copy(x) if isinstance(x, np.ndarray) else x
                                             for x in args], dict(kwargs))
            t0 = time.process_time()
            out = original(*args, **kwargs)
            self.times[key].append(time.process_time() - t0)
            return out
        return wrapped


def alone(original, args, kwargs, repeats: int = 20) -> float:
    """Median CPU time [s] of ``original(*args)`` alone, one BLAS thread."""
    with threadpool_limits(1):
        original(*[np.copy(x) if isinstance(x, np.ndarray) else x for x in args], **kwargs)
        times = []
        for _ in range(repeats):
            copies = [np.copy(x) if isinstance(x, np.ndarray) else x for x in args]
            t0 = time.process_time()
            original(*copies, **kwargs)
            times.append(time.process_time() - t0)
    return statistics.median(times)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    chains = three_axis.design_chains()
    three_axis.evaluate(chains)  # warm-up: numba caches, imports
    load_before = [round(x, 2) for x in os.getloadavg()]
    stages: dict = {}
    for _ in range(args.repeats):
        three_axis.evaluate(chains, stages)
    cpu = stages["total"]
    recorder = Recorder()
    with recorder:
        recorder.active = True
        three_axis.evaluate(chains)
        recorder.active = False
        rows = []
        for key, times in recorder.times.items():
            name, order, batch, site = key
            single = (alone(*recorder.args[key]) * len(times) if key in recorder.args
                      else None)
            rows.append({"routine": name, "order": order, "batch": batch, "site": site,
                         "calls": len(times), "cpu_s": sum(times), "alone_s": single})
    load_after = [round(x, 2) for x in os.getloadavg()]
    rows.sort(key=lambda r: -r["cpu_s"])
    large = [r for r in rows if r["order"] >= LARGE]
    total = statistics.median(cpu)
    floor_in_place = sum(r["cpu_s"] for r in large)
    floor_alone = sum(r["alone_s"] for r in large)
    info = machine_info()
    names = ("build_truth", "build_design", "lqr", "close_loop", "simulate", "margins", "total")
    stage_rows = [[name, f"{statistics.median(stages[name]) * 1e3:.1f}",
                   f"{statistics.median(stages[name + '_wall']) * 1e3:.1f}"] for name in names]
    result = {"machine": info, "repeats": args.repeats, "load_before": load_before,
              "stages_cpu_median_s": {n: statistics.median(stages[n]) for n in names},
              "load_after": load_after, "evaluation_cpu_median_s": total,
              "evaluation_cpu_min_s": min(cpu), "calls": rows,
              "large_in_place_s": floor_in_place, "large_alone_s": floor_alone,
              "all_in_place_s": sum(r["cpu_s"] for r in rows)}
    write_json("three_axis_floor.json", result)
    table = markdown_table(
        ["routine", "order", "calls", "made by (innermost first)", "CPU in place [ms]",
         "CPU alone, 1 thread [ms]"],
        [[r["routine"], f"{r['order']}" + (f" x{r['batch']}" if r["batch"] > 1 else ""),
          r["calls"], r["site"], f"{r['cpu_s'] * 1e3:.2f}",
          f"{r['alone_s'] * 1e3:.2f}" if r["alone_s"] is not None else "-"]
         for r in rows if r["cpu_s"] >= 5e-5])
    text = "\n".join([
        "# A three-axis design-loop evaluation: its dense eigenvalue work, timed", "",
        f"`python benchmarks/three_axis_floor.py` on {info['date_utc']} UTC, {info['cpu']}, "
        f"{info['nproc']} cores, BLAS threads {info['blas_threads']}; load average "
        f"{load_before} before, {load_after} after.", "",
        f"One evaluation (benchmarks/three_axis.py: 56 truth states, 46-state LQR + Kalman, "
        f"100 s slew at 100 Hz, multiloop margins): CPU median {total * 1e3:.1f} ms, min "
        f"{min(cpu) * 1e3:.1f} ms over {args.repeats}; by stage (medians):", "",
        markdown_table(["stage", "CPU [ms]", "wall [ms]"], stage_rows), "",
        "Every dense eigenvalue / Schur / Sylvester / reordering call of one evaluation "
        "(calls below 0.05 ms left out):", "", table, "",
        f"Calls on matrices of order >= {LARGE}: {floor_in_place * 1e3:.1f} ms in place, "
        f"{floor_alone * 1e3:.1f} ms alone on one BLAS thread; all recorded calls "
        f"{result['all_in_place_s'] * 1e3:.1f} ms.", ""])
    (RESULTS / "three_axis_floor.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
