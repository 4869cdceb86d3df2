"""Shared scenario, timing and output helpers of the flexsat benchmarks (not a public API).

The default scenario of every benchmark (issue 6 and issue 3):

- the paper's rod, ``Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)`` (10 m steel rod, 0.01 m
  diameter; Belonozhko et al. 2009), undamped;
- on ``Hub(mass=100.0, inertia=50.0)``, mounted at (0.5, 0.0) m along +x;
- a PD attitude loop with natural frequency 0.1 rad/s and damping 0.7, designed on the model
  under test; a cycloidal slew of 10 deg in 60 s.
"""

from __future__ import annotations

import os
import sys

# The user's BLAS settings unless asked otherwise (FLEXSAT_BENCH_BLAS_THREADS=1 or another
# number sets OPENBLAS/OMP/MKL_NUM_THREADS before numpy is loaded): flexsat limits the BLAS
# threads of small problems itself (controllers/threads.py), so its figures must hold with a
# user's default settings.  Every benchmark script imports this module first.
BLAS_THREADS = os.environ.get("FLEXSAT_BENCH_BLAS_THREADS", "default")
if BLAS_THREADS != "default":
    if "numpy" in sys.modules:
        print("warning: numpy imported before benchmarks/_common.py; BLAS threads not limited",
              file=sys.stderr)
    for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[_name] = BLAS_THREADS

import datetime
import gc
import json
import math
import platform
import subprocess
import statistics
import time
from pathlib import Path
from typing import Callable

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from appendages import Beam  # noqa: E402
from spacecraft import Hub, Mount, Spacecraft  # noqa: E402

__all__ = [
    "RESULTS", "SLEW_ANGLE", "SLEW_DURATION", "PD_NATURAL_FREQUENCY", "PD_DAMPING",
    "paper_rod", "default_hub", "spacecraft_with", "median_time", "machine_info",
    "write_json", "markdown_table", "fmt", "slew_inputs", "pd_closed_loop", "slew_response",
    "slew_errors", "revision", "run_in_checkout",
]

RESULTS = Path(__file__).resolve().parent / "results"

SLEW_ANGLE = math.radians(10.0)      # rad
SLEW_DURATION = 60.0                 # s
PD_NATURAL_FREQUENCY = 0.1           # rad/s
PD_DAMPING = 0.7                     # -
HUB_MASS = 100.0                     # kg
HUB_INERTIA = 50.0                   # kg*m^2
MOUNT_POSITION = (0.5, 0.0)          # m, hub axes


def paper_rod(*, damping_ratio: float = 0.0) -> Beam:
    """The paper's rod: 10 m long, 0.01 m diameter, steel (7800 kg/m^3, 2.06e11 Pa)."""
    return Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=damping_ratio)


def default_hub() -> Hub:
    """Hub(mass=100 kg, inertia=50 kg*m^2)."""
    return Hub(mass=HUB_MASS, inertia=HUB_INERTIA)


def spacecraft_with(appendage) -> Spacecraft:
    """The default hub carrying ``appendage`` at (0.5, 0) m along +x."""
    return Spacecraft(default_hub(), [Mount(appendage, MOUNT_POSITION, 0.0)])


def median_time(function: Callable[[], object], *, repeats: int = 5,
                min_total: float = 0.0, max_total: float = 30.0) -> float:
    """Median wall time [s] of ``function()`` over ``repeats`` runs (after one warm-up run).

    Runs more repetitions while their total stays below ``min_total`` seconds (useful for
    sub-millisecond calls) and stops early once ``max_total`` seconds are spent.
    """
    function()
    times: list[float] = []
    spent = 0.0
    while len(times) < repeats or (spent < min_total and len(times) < 1000):
        gc_was = gc.isenabled()
        gc.disable()
        t0 = time.perf_counter()
        try:
            function()
        finally:
            elapsed = time.perf_counter() - t0
            if gc_was:
                gc.enable()
        times.append(elapsed)
        spent += elapsed
        if spent > max_total and len(times) >= 1:
            break
    return statistics.median(times)


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.lower().startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def machine_info() -> dict:
    """Date, CPU, core count and library versions, for the results files."""
    import control
    import scipy

    return {
        "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M"),
        "cpu": _cpu_model(),
        "nproc": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "control": control.__version__,
        "platform": platform.platform(),
        "blas_threads": BLAS_THREADS,
        "load_average_1_5_15min": list(os.getloadavg()),
    }


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return [_jsonable(v) for v in value.tolist()]
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, np.integer):
        return int(value)
    return value


def write_json(name: str, data: dict) -> Path:
    """Write ``data`` (NaN/inf as null) to benchmarks/results/<name>."""
    RESULTS.mkdir(parents=True, exist_ok=True)
    path = RESULTS / name
    path.write_text(json.dumps(_jsonable(data), indent=1) + "\n")
    return path


def fmt(value, digits: int = 2) -> str:
    """Short scientific format; '-' for a missing value."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    if isinstance(value, (int, np.integer)):
        return str(value)
    return f"{value:.{digits}e}"


def markdown_table(header: list[str], rows: list[list]) -> str:
    """A GitHub markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for row in rows:
        lines.append("| " + " | ".join(str(c) for c in row) + " |")
    return "\n".join(lines)


# -- the closed-loop slew scenario ------------------------------------------------------------
def slew_inputs(closed_loop, T: np.ndarray) -> np.ndarray:
    """Closed-loop input array with the cycloidal 10 deg / 60 s slew on ``theta_ref``."""
    import controllers

    U = np.zeros((closed_loop.ninputs, T.size))
    U[list(closed_loop.input_labels).index("theta_ref")] = controllers.slew_profile(
        T, SLEW_ANGLE, SLEW_DURATION)
    return U


def pd_closed_loop(appendage, *, tip_deflection: bool = True):
    """(plant, PD controller, closed loop) of the default hub carrying ``appendage``.

    The PD (natural frequency 0.1 rad/s, damping 0.7) is designed on the same plant it is
    closed around, as a user designs on the chain and predicts the response with it.
    """
    import controllers

    plant = spacecraft_with(appendage).plant(tip_deflection=tip_deflection)
    controller = controllers.pd(plant, natural_frequency=PD_NATURAL_FREQUENCY, damping=PD_DAMPING)
    return plant, controller, controllers.close_loop(plant, controller)


def slew_response(closed_loop, *, t_final: float = 200.0, dt: float = 0.1) -> dict:
    """theta [rad], tip deflection [m] and torque [N*m] of the slew, exact simulation."""
    import control

    import controllers

    n = int(round(t_final / dt)) + 1
    T = np.arange(n) * dt
    if closed_loop.isdtime(strict=True):  # a sampled-data loop: its own sample step
        response = control.forced_response(closed_loop, T, slew_inputs(closed_loop, T),
                                           squeeze=False)
    else:
        response = controllers.simulate(closed_loop, T, slew_inputs(closed_loop, T),
                                        squeeze=False)
    labels = list(closed_loop.output_labels)
    y = np.asarray(response.outputs).reshape(len(labels), -1)
    out = {"t": T, "theta": y[labels.index("theta")], "torque": y[labels.index("torque")]}
    tips = [k for k, name in enumerate(labels) if name.endswith("tip_deflection")]
    if tips:
        out["tip"] = y[tips[0]]
    return out


def slew_errors(response: dict, reference: dict) -> dict:
    """Peak errors of a slew response against the reference response (same time grid).

    theta: max |theta - theta_ref| / slew angle; tip: max |tip - tip_ref| / max |tip_ref|;
    torque: max |torque - torque_ref| / max |torque_ref|.
    """
    out = {"theta": float(np.max(np.abs(response["theta"] - reference["theta"])) / SLEW_ANGLE),
           "torque": float(np.max(np.abs(response["torque"] - reference["torque"]))
                           / np.max(np.abs(reference["torque"])))}
    if "tip" in response and "tip" in reference:
        out["tip"] = float(np.max(np.abs(response["tip"] - reference["tip"]))
                           / np.max(np.abs(reference["tip"])))
    return out


# ---------------------------------------------------------------------------------------------
# before/after runs: a workload timed in a fresh process of another checkout
# ---------------------------------------------------------------------------------------------
_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def revision(tree: Path) -> str:
    """The checkout's commit and whether it has changes of its own ("unknown" outside git)."""
    try:
        head = subprocess.run(["git", "-C", str(tree), "rev-parse", "--short", "HEAD"],
                              capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(tree), "status", "--porcelain",
                                "--untracked-files=no"], capture_output=True, text=True,
                               check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + (" + local changes" if dirty else "")


def run_in_checkout(tree: Path, code: str, *args, what: str, blas: str = "inherit") -> dict:
    """Run ``python -c code *args`` in a fresh process with the checkout ``tree`` first on the
    path; its last line of output read as JSON, with ``load_before`` (the load average when
    it started) added unless the child gave one.

    ``blas``: ``"inherit"`` this process's BLAS thread settings, ``"one"`` one BLAS thread (as
    a Dask worker runs), ``"default"`` none set (a user's default). ``what`` names the workload
    in the error raised when the child fails.
    """
    env = dict(os.environ, PYTHONPATH=str(tree))
    if blas == "one":
        env.update({k: "1" for k in _THREAD_VARIABLES})
    elif blas == "default":
        for k in _THREAD_VARIABLES:
            env.pop(k, None)
    elif blas != "inherit":
        raise ValueError(f"blas must be 'inherit', 'one' or 'default'; got {blas!r}")
    load = [round(x, 2) for x in os.getloadavg()]
    done = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True,
                          text=True, env=env, cwd=str(tree))
    if done.returncode != 0:
        raise RuntimeError(f"{what} in {tree} failed:\n{done.stderr[-2000:]}")
    result = json.loads(done.stdout.strip().splitlines()[-1])
    result.setdefault("load_before", load)
    return result
