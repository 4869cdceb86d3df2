"""A damped beam's D6 by its motions' cantilever modal sums together or each alone, one process.

``Beam.dynamic_stiffness6`` of a damped beam (cantilever convention) sums the cantilever modal
sums of all its motions (both bending planes, torsion, axial motion) together, in one
``appendages.damping.CantileverModalSums`` (``Beam._modal_stiffness6``); without it (that method
returning False) it evaluates each motion alone, each its own one-motion sums. The joint class
itself evaluates each motion alone above ``appendages.damping._JOINT`` points x modes (its
arrays of points x modes no longer stay in the cache). Two members:

- ``wing``: the three-axis scene's solar-array wing (``spacecraft/scene/embedded/
  three_axis.toml``), ``Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8, damping_ratio=0.005)``:
  6 m long, 2 m wide (along local z), 0.04 m thick (along local y, the x-y bending plane),
  40 kg/m^3, Young's modulus 7e8 Pa, cantilever damping ratio 0.005; its planes differ, so
  four motions (x-y plane, x-z plane, axial, torsion);
- ``boom``: the same scene's CFRP boom, ``Beam.tube(4.0, 0.05, 0.001, 1600.0, 1.2e11,
  damping_ratio=0.005)``: 4 m long, 0.05 m outer diameter, 0.001 m wall, 1600 kg/m^3,
  1.2e11 Pa, damping ratio 0.005; equal planes, so three motions (one plane's sums serve both).

Points: n on the imaginary axis, ``1j * linspace(1, 30, n)`` rad/s (each motion keeps 16 modes
there: every mode up to 10 max|s|). Measured in this process, one BLAS thread
(``threadpoolctl.threadpool_limits(1)``), CPU time (``time.process_time``) of one call, the
garbage collector off during each; the two sides of a comparison called in pairs, alternating
which goes first, both sides warmed up (their modal data built) before; the number of pairs of
a row sized from a warm-up call to fill about ``--seconds`` (at least 15, at most 2000).
Medians (and minima in the JSON) of each side's times and the median of the pairs' ratios:

1. Table 1: one ``dynamic_stiffness6`` call, all motions together (as shipped) against each
   motion alone (``Beam._modal_stiffness6`` patched to return False for that call and
   restored, as ``sample_speed.py --rod-modal-sum`` switches off a method), n = 1 to 10,000;
2. Table 2: the threshold. One ``dynamic_stiffness6`` call with the joint sum forced at every
   size (``appendages.damping._JOINT`` patched to 2**62 for that call) against the shipped
   threshold, points x modes about 4k to 300k: where together stops paying.

Both sides of each row are compared: the largest ``max|a - b| / max|a|`` over the D6 entries
of all points, against 64 eps (a guard that each row compares like with like, not a test).

Run::

    python benchmarks/modal_sums.py            # ~1.5-2 min on 2 cores
    python benchmarks/modal_sums.py --quick    # ~20 s, fewer pairs

Writes ``benchmarks/results/modal_sums.json`` and ``modal_sums.md`` (``--quick``:
``modal_sums_quick.*``).
"""

from __future__ import annotations

# _common first: the BLAS settings before numpy is loaded, this checkout on sys.path
from _common import RESULTS, ROOT, machine_info, markdown_table, revision, write_json

import argparse
import contextlib
import gc
import os
import platform
import statistics
import sys
import time
import warnings

import numpy as np
from threadpoolctl import threadpool_limits

import appendages.damping as damping
from appendages.beam import Beam

POINTS = (1, 3, 30, 300, 1000, 3000, 10000)
#: Table 2's points x modes (the points: the nearest whole number for each member).
THRESHOLD_SIZES = (4096, 8192, 16384, 24576, 32768, 40960, 49152, 65536, 81920, 98304, 131072,
                   196608, 294912)
OMEGA_MIN, OMEGA_MAX = 1.0, 30.0     # rad/s
TOLERANCE = 64 * np.finfo(float).eps
MIN_PAIRS, MAX_PAIRS = 15, 2000
FORCED = 2**62                       # _JOINT for "joint sum at every size"


def members() -> dict:
    """{name: damped three-axis beam} (module docstring)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {"wing": Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8, damping_ratio=0.005),
                "boom": Beam.tube(4.0, 0.05, 0.001, 1600.0, 1.2e11, damping_ratio=0.005)}


def points(n: int) -> np.ndarray:
    """n points on the imaginary axis from 1 to 30 rad/s."""
    return 1j * np.linspace(OMEGA_MIN, OMEGA_MAX, n)


def joint_sums(beam: Beam) -> list:
    """The joint modal sums (``CantileverModalSums``) the beam has built, read from its cache:
    one per set of modes a motion."""
    return [value[0] for key, value in beam._cache.items()
            if isinstance(key, tuple) and key[0] == "cantilever_modal_sums6"]


@contextlib.contextmanager
def together():
    """As shipped: ``dynamic_stiffness6`` sums every motion together."""
    yield


@contextlib.contextmanager
def alone():
    """``Beam._modal_stiffness6`` switched off: ``dynamic_stiffness6`` takes each motion
    alone."""
    shipped = Beam._modal_stiffness6
    Beam._modal_stiffness6 = lambda self, s, D6: False
    try:
        yield
    finally:
        Beam._modal_stiffness6 = shipped


@contextlib.contextmanager
def forced():
    """The joint sum at every size (``appendages.damping._JOINT`` raised)."""
    shipped = damping._JOINT
    damping._JOINT = FORCED
    try:
        yield
    finally:
        damping._JOINT = shipped


def evaluate(side, beam: Beam, s: np.ndarray) -> np.ndarray:
    """``beam.dynamic_stiffness6(s)`` on ``side`` (one of the context managers above)."""
    with side():
        return beam.dynamic_stiffness6(s)


def timed(side, beam: Beam, s: np.ndarray) -> tuple[float, float]:
    """(CPU, wall) [s] of one ``beam.dynamic_stiffness6(s)`` on ``side``, the garbage
    collector off (the patch set and undone outside the timed call)."""
    with side():
        gc.disable()
        try:
            c, w = time.process_time(), time.perf_counter()
            beam.dynamic_stiffness6(s)
            return time.process_time() - c, time.perf_counter() - w
        finally:
            gc.enable()


def compare(first, second, beam: Beam, s: np.ndarray, seconds: float) -> dict:
    """``first`` against ``second`` on ``beam`` at ``s``: pairs alternating, their D6 compared."""
    a, b = evaluate(first, beam, s), evaluate(second, beam, s)   # warm-up: sums built
    difference = float(np.max(np.abs(a - b)) / np.max(np.abs(a)))
    cost = sum(min(timed(side, beam, s)[0] for _ in range(3)) for side in (first, second))
    n_pairs = int(min(MAX_PAIRS, max(MIN_PAIRS, seconds / max(cost, 1e-6))))
    cpu = {0: [], 1: []}
    wall = {0: [], 1: []}
    load_before = os.getloadavg()[0]
    for i in range(n_pairs):
        for side in ((0, 1) if i % 2 == 0 else (1, 0)):
            c, w = timed((first, second)[side], beam, s)
            cpu[side].append(c)
            wall[side].append(w)
    load_after = os.getloadavg()[0]
    ratios = [x / y for x, y in zip(cpu[0], cpu[1]) if y > 0.0]
    return {"pairs": n_pairs,
            "cpu_median_s": [statistics.median(cpu[0]), statistics.median(cpu[1])],
            "cpu_min_s": [min(cpu[0]), min(cpu[1])],
            "wall_median_s": [statistics.median(wall[0]), statistics.median(wall[1])],
            "ratio_median": statistics.median(ratios),
            "ratio_of_minima": min(cpu[0]) / min(cpu[1]) if min(cpu[1]) > 0 else None,
            "largest_difference": difference, "within_64_eps": bool(difference <= TOLERANCE),
            "load_1min": [load_before, load_after]}


def load() -> list:
    """The load average (1, 5, 15 min), rounded."""
    return [round(x, 2) for x in os.getloadavg()]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer pairs (~20 s)")
    parser.add_argument("--seconds", type=float, default=None,
                        help="CPU seconds of pairs per row (default 2.5; --quick 0.4)")
    args = parser.parse_args()
    seconds = args.seconds if args.seconds is not None else (0.4 if args.quick else 2.5)
    warnings.simplefilter("ignore")
    result = {"machine": machine_info(), "host": platform.node(), "revision": revision(ROOT),
              "blas_threads_measured": 1, "joint_threshold": damping._JOINT,
              "seconds_per_row": seconds, "tolerance": TOLERANCE,
              "load_before": load(), "members": {},
              "arguments": "".join(" " + a for a in sys.argv[1:])}
    with threadpool_limits(1):
        for name, beam in members().items():
            # 1 and 30 rad/s: every row's points lie between (the top sets the modes a motion)
            beam.dynamic_stiffness6(points(2))
            [sums] = joint_sums(beam)
            modes = int(sums.n_modes)
            loads = [load()]

            def rows(label, first, second, point_counts):
                out = []
                for n in point_counts:
                    r = compare(first, second, beam, points(n), seconds)
                    r.update(points=n, points_x_modes=n * modes,
                             joint=n * modes <= damping._JOINT)
                    out.append(r)
                    print(name, label, n, f"{r['ratio_median']:.3f}",
                          f"{r['largest_difference']:.1e}", file=sys.stderr, flush=True)
                loads.append(load())
                return out

            rows1 = rows("together/alone", together, alone, POINTS)
            rows2 = rows("forced/shipped", forced, together,
                         [max(1, round(size / modes)) for size in THRESHOLD_SIZES])
            if len(joint_sums(beam)) != 1:
                print(f"warning: {name}: the rows did not all use the same modes; points x "
                      "modes is wrong for some", file=sys.stderr)
            # where together stops paying: the smallest size from which forcing it costs more
            # at every larger size
            losing = [r["points_x_modes"] for k, r in enumerate(rows2)
                      if all(q["ratio_median"] > 1.0 for q in rows2[k:])]
            result["members"][name] = {"modes": modes, "together_vs_alone": rows1,
                                       "forced_vs_shipped": rows2, "load": loads,
                                       "together_stops_paying_from": min(losing, default=None)}
    result["load_after"] = load()
    worst = max(r["largest_difference"] for m in result["members"].values()
                for r in m["together_vs_alone"] + m["forced_vs_shipped"])
    result["largest_difference"] = worst
    result["all_within_64_eps"] = bool(worst <= TOLERANCE)
    stem = "modal_sums_quick" if args.quick else "modal_sums"
    write_json(stem + ".json", result)
    text = report(result)
    (RESULTS / (stem + ".md")).write_text(text)
    print(text)
    if not result["all_within_64_eps"]:
        print(f"warning: the two sides differ by {worst:.1e} of D6's scale, more than 64 eps",
              file=sys.stderr)
        return 1
    return 0


def report(result: dict) -> str:
    """The Markdown of ``result``."""
    info = result["machine"]
    us = 1e6
    lines = [
        "# A damped beam's D6: its motions' modal sums together or each alone", "",
        f"`python benchmarks/modal_sums.py{result['arguments']}` on {info['date_utc']} "
        f"UTC, host {result['host']}, {info['cpu']}, {info['nproc']} cores, one BLAS thread "
        f"(threadpoolctl), revision {result['revision']}, numpy {info['numpy']}; load average "
        f"(1, 5, 15 min) {result['load_before']} -> {result['load_after']}. One "
        "`Beam.dynamic_stiffness6` call on n points `1j * linspace(1, 30, n)` rad/s; CPU time "
        "(`time.process_time`), the two sides in pairs alternating which goes first, about "
        f"{result['seconds_per_row']} s of pairs a row; medians of each side and of the pairs' "
        "ratios (on a shared host the absolute times swing with its other work; the ratios, "
        "each from calls side by side, are the figures to read). The joint class evaluates each motion alone above "
        f"{result['joint_threshold']} points x modes ('joint': at or below it). Members: the "
        "three-axis scene's wing `Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8, "
        "damping_ratio=0.005)` (planes differ: 4 motions) and boom `Beam.tube(4.0, 0.05, "
        "0.001, 1600.0, 1.2e11, damping_ratio=0.005)` (equal planes: 3 motions).", ""]
    for name, m in result["members"].items():
        rows = [[r["points"], r["points_x_modes"], "yes" if r["joint"] else "no",
                 f"{r['cpu_median_s'][0] * us:.0f}", f"{r['cpu_median_s'][1] * us:.0f}",
                 f"{r['ratio_median']:.3f}", r["pairs"], f"{r['largest_difference']:.1e}"]
                for r in m["together_vs_alone"]]
        lines += [f"## {name} ({m['modes']} modes): all motions together against each alone", "",
                  f"Load (1, 5, 15 min) {m['load'][0]} -> {m['load'][1]}.", "",
                  markdown_table(["points", "points x modes", "joint", "together [us]",
                                  "alone [us]", "together / alone", "pairs",
                                  "max diff / max|D6|"], rows), ""]
        rows = [[r["points"], r["points_x_modes"], "yes" if r["joint"] else "no",
                 f"{r['cpu_median_s'][0] * us:.0f}", f"{r['cpu_median_s'][1] * us:.0f}",
                 f"{r['ratio_median']:.3f}", r["pairs"], f"{r['largest_difference']:.1e}"]
                for r in m["forced_vs_shipped"]]
        stop = m["together_stops_paying_from"]
        lines += [f"## {name}: the joint sum forced at every size against the shipped threshold",
                  "", f"Load (1, 5, 15 min) {m['load'][1]} -> {m['load'][2]}. 'joint': the "
                  "shipped side uses the joint sum (both sides then run the same code: the "
                  "ratio is the noise). Forcing costs more (median ratio above 1) at every size "
                  "from " + (f"{stop} points x modes." if stop else "none measured."), "",
                  markdown_table(["points", "points x modes", "joint (shipped)", "forced [us]",
                                  "shipped [us]", "forced / shipped", "pairs",
                                  "max diff / max|D6|"], rows), ""]
    lines += [f"Largest difference between the two sides of any row: "
              f"{result['largest_difference']:.1e} of max|D6| (64 eps = "
              f"{result['tolerance']:.1e}; all within: "
              f"{'yes' if result['all_within_64_eps'] else 'NO'}).", ""]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
