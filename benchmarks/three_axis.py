"""Three axes (issue 11) and the Craig-Bampton costs of issue 10: accuracy and timings.

The example spacecraft of issue 11: an 820 kg hub with a full inertia tensor, two
rectangular-section solar-array wings along +-y of the hub, canted 20 deg about their own axes,
and a CFRP tube boom at a point off the hub's axes, pointing along (1, -0.5, -1.2) (off every
principal axis). Measured here:

- exact coupled frequencies (Wittrick-Williams on the 6x6 Z through W6) of the spacecraft, time
  of the first 10 and 20 (a fresh Spacecraft each run, caches included);
- the plant of the hub with each appendage truncated to its 10 lowest Craig-Bampton modes
  (inputs torque_x/y/z; outputs attitude, rates, tip motions), build time;
- accuracy: the exact coupled frequencies against the independent 3-D finite-element model of
  tests/fe3d.py at 10, 20 and 40 elements per appendage, and the wing's W6 against fe3d's;
- issue 10: the planar Craig-Bampton W at 400 modes on 1000 and 10000 frequencies (time, peak
  memory of the call) and the damped Craig-Bampton build at 1000 modes.

Run: ``python benchmarks/three_axis.py`` (about a minute on 2 cores). Output:
``results/three_axis.{json,md}``.
"""

from __future__ import annotations

import _common  # noqa: F401  (BLAS threads, sys.path)

import math
import sys
import time
import tracemalloc

import numpy as np

from _common import ROOT, machine_info, markdown_table, median_time, write_json
from appendages import Beam, limits
from spacecraft import Hub, Mount, Spacecraft
from spacecraft.kinematics import euler_orientation, orientation_from_axis

sys.path.insert(0, str(ROOT / "tests"))
import fe3d  # noqa: E402  (the independent reference, shipped with the tests)

HUB_MASS = 820.0                                                       # kg
HUB_INERTIA = np.array([[950.0, 12.0, -8.0], [12.0, 780.0, 15.0], [-8.0, 15.0, 640.0]])  # kg m^2
CANT = math.radians(20.0)                                              # rad


def wing() -> Beam:
    """6 m x 2 m panel strip, 40 mm equivalent thickness, 40 kg/m^3, 0.7 GPa (19.2 kg)."""
    return Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8)


def boom() -> Beam:
    """4 m CFRP tube, 50 mm diameter, 1 mm wall (1.0 kg)."""
    return Beam.tube(4.0, 0.05, 0.001, 1600.0, 1.2e11)


def placements():
    """(position [m], orientation) of the left wing, the right wing and the boom."""
    return [((0.0, 1.1, 0.0), euler_orientation("ZYX", (math.pi / 2, 0.0, CANT))),
            ((0.0, -1.1, 0.0), euler_orientation("ZYX", (-math.pi / 2, 0.0, CANT))),
            ((0.6, 0.3, -0.9), orientation_from_axis((1.0, -0.5, -1.2)))]


def example(model=lambda beam: beam) -> Spacecraft:
    """The example spacecraft with each beam replaced by ``model(beam)``."""
    beams = [wing(), wing(), boom()]
    names = ["wing_left", "wing_right", "boom"]
    return Spacecraft(Hub(HUB_MASS, HUB_INERTIA),
                      [Mount(model(b), p, orientation=R, name=n)
                       for b, (p, R), n in zip(beams, placements(), names)])


def median_cpu_time(function, repeats: int = 7) -> float:
    """Median CPU time [s] of this process in ``function()`` (after one warm-up run): on a
    shared, oversubscribed machine the wall time also counts the waits for a core."""
    function()
    times = []
    for _ in range(repeats):
        t0 = time.process_time()
        function()
        times.append(time.process_time() - t0)
    return float(np.median(times))


def main() -> None:
    info = machine_info()
    results: dict = {"machine": info}
    craft = example()
    exact = craft.natural_frequencies(20)
    results["exact_frequencies_rad_s"] = exact

    # -- timings --------------------------------------------------------------------------------
    timings = {
        "exact_frequencies_10": median_time(lambda: example().natural_frequencies(10), repeats=7),
        "exact_frequencies_20": median_time(lambda: example().natural_frequencies(20), repeats=7),
        "plant_10_modes_each": median_time(
            lambda: example(lambda b: b.truncated(10)).plant(tip_deflection=True), repeats=7),
        "plant_10_modes_each_pruned": median_time(
            lambda: example(lambda b: b.truncated(10)).plant(tip_deflection=True, prune=True),
            repeats=7),
        "exact_response_3x3_200_points": median_time(
            lambda: example().frequency_response(np.geomspace(0.1, 100.0, 200)), repeats=7),
    }
    cpu = {"exact_frequencies_10": median_cpu_time(lambda: example().natural_frequencies(10)),
           "exact_frequencies_20": median_cpu_time(lambda: example().natural_frequencies(20)),
           "plant_10_modes_each": median_cpu_time(
               lambda: example(lambda b: b.truncated(10)).plant(tip_deflection=True))}
    results["cpu_times_s"] = cpu
    plant = example(lambda b: b.truncated(10)).plant(tip_deflection=True, prune=True)
    results["plant_states_pruned"] = plant.nstates
    results["timings_s"] = timings

    # -- accuracy against the finite-element model ------------------------------------------------
    mounts = [(b, p, R) for b, (p, R) in zip([wing(), wing(), boom()], placements())]
    accuracy = []
    for n_elements in (10, 20, 40):
        K, M = fe3d.spacecraft_matrices(HUB_MASS, HUB_INERTIA, mounts, n_elements)
        t0 = time.perf_counter()
        fe = fe3d.natural_frequencies(K, M, 24)[:20]
        accuracy.append({"n_elements": n_elements, "fe_seconds": time.perf_counter() - t0,
                         "relative_difference": np.abs(fe / exact - 1)})
    results["fe_comparison"] = accuracy
    s = 1j * np.array([0.5, 5.0, 30.0, 150.0])
    W_exact, W_fe = wing().W6(s), fe3d.root_compliance(wing(), s, 40)
    results["wing_W6_relative_difference"] = (np.abs(W_exact - W_fe).max(axis=(1, 2))
                                              / np.abs(W_fe).max(axis=(1, 2)))

    # -- issue 10 ---------------------------------------------------------------------------------
    rod = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)
    model = rod.truncated(400)
    model.W(1j)  # realisation and modal stiffness once
    issue10 = {}
    for n_points in (1000, 10000):
        omega = 1j * np.geomspace(1e-2, 1e4, n_points)
        tracemalloc.start()
        t0 = time.perf_counter()
        model.W(omega)
        elapsed = time.perf_counter() - t0
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        issue10[f"W_400_modes_{n_points}_points"] = {"seconds": elapsed, "peak_MB": peak / 1e6}
    damped = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=0.005)
    t0 = time.perf_counter()
    with limits.raised(modes=1000):
        damped.truncated(1000).root_model()
    issue10["damped_craig_bampton_1000_modes_build_s"] = time.perf_counter() - t0
    results["issue10"] = issue10
    info["load_average_after"] = list(__import__("os").getloadavg())

    # -- report -----------------------------------------------------------------------------------
    rows = [[f"{k + 1}", f"{exact[k]:.10g}"]
            + [f"{a['relative_difference'][k]:.1e}" for a in accuracy] for k in range(20)]
    lines = ["# Three axes: exact coupled frequencies against the FE model, and timings", "",
             f"{info['date_utc']} UTC, {info['cpu']}, {info['nproc']} cores, BLAS threads "
             f"{info['blas_threads']}, load average {info['load_average_1_5_15min']} before, "
             f"{info['load_average_after']} after.", "",
             "Example spacecraft: 820 kg hub (full inertia tensor), two 6 m rectangular wings "
             "canted 20 deg, a 4 m tube boom off the principal axes.", "",
             markdown_table(["mode", "exact [rad/s]", "FE 10 el.", "FE 20 el.", "FE 40 el."],
                            rows), "",
             "Wing W6, exact vs FE (40 elements), relative to the largest entry at s = i(0.5, "
             "5, 30, 150): " + ", ".join(f"{v:.1e}" for v in results["wing_W6_relative_difference"]),
             "", markdown_table(["timing (median of 7)", "wall ms", "CPU ms"],
                                [[k, f"{v * 1e3:.1f}",
                                  f"{cpu[k] * 1e3:.1f}" if k in cpu else "-"]
                                 for k, v in timings.items()]), "",
             f"Pruned plant: {plant.nstates} states.", "",
             markdown_table(["issue 10", "value"],
                            [[k, (f"{v['seconds']:.3f} s, peak {v['peak_MB']:.0f} MB"
                                  if isinstance(v, dict) else f"{v:.2f} s")]
                             for k, v in issue10.items()])]
    text = "\n".join(lines) + "\n"
    (_common.RESULTS / "three_axis.md").write_text(text)
    write_json("three_axis.json", results)
    print(text)


if __name__ == "__main__":
    main()
