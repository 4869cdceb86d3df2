"""Benchmark: the default scene's flown slew through reaction wheels against today's slew.

Run from the repository root::

    python benchmarks/wheels.py            # ~1 min
    python benchmarks/wheels.py --quick    # fewer repetitions

The loops are the default scene's (``spacecraft.run(None)``: the paper's rod on a 100 kg hub,
PD and LQR tuned on both fitted chains, each closed on its design chain and on the truth beam,
8 loops of 6 to 12 states). For each loop:

- ``today``: what the runner does for the scene's slew today, ``Simulator(loop, 0.1)`` and
  ``spacecraft.design.responses.simulate_manoeuvre`` (cycloidal 10 deg / 60 s, 200 s at 0.1 s);
- ``flown``: the flown slew without wheels, the same controller tuned with ``feedforward=True``
  on a shaped profile (bang-coast-bang, 10 deg in 60 s, ZVD shaper on the design chain's first
  flexible mode) with its rate reference and feedforward torque, ``Simulator`` + outputs;
- ``wheels``: the flown slew through one reaction wheel, ``WheelLoop(plant, controller,
  wheels).simulate(T, U)`` (set-up included; "simulate only": a built WheelLoop's first
  simulation, its caches emptied), with the issue's torque limit 0.03 N m and a
  momentum limit 1.2 N m s (the slew needs 0.054 N m and 1.6 N m s: both limits act), spin
  inertia 0.01 kg m^2; and ``wheels, unsaturated`` with limits it never reaches.

Times are CPU seconds (``time.process_time``) of one call, median and minimum over the
repetitions, the variants taking turns so that the machine's load hits them alike; the load
average is recorded beside them. Accuracy: the saturated theta at dt = 0.1 s against the same
simulation at dt = 0.1 / 32 s. Results go to ``benchmarks/results/wheels.{json,md}``.
"""

from __future__ import annotations

import _common  # noqa: F401  (BLAS settings before numpy)

import argparse
import gc
import math
import os
import statistics
import time

import numpy as np

import controllers
import spacecraft
from _common import machine_info, markdown_table, write_json, RESULTS
from spacecraft.design.responses import simulate_manoeuvre

ANGLE, DURATION, T_FINAL, STEP = math.radians(10.0), 60.0, 200.0, 0.1
TORQUE_LIMIT, MOMENTUM_LIMIT, SPIN_INERTIA = 0.03, 1.2, 0.01


def cpu_times(functions: dict, repeats: int) -> dict:
    """CPU time [s] of each function, taking turns, after one warm-up call each."""
    for f in functions.values():
        f()
    times = {name: [] for name in functions}
    for _ in range(repeats):
        for name, f in functions.items():
            gc.disable()
            t0 = time.process_time()
            f()
            times[name].append(time.process_time() - t0)
            gc.enable()
    return {name: {"median": statistics.median(v), "min": min(v)} for name, v in times.items()}


def flown_controller(kind: str, plant, scene):
    c = scene.controller
    if kind == "pd":
        return controllers.pd(plant, natural_frequency=c.pd.natural_frequency,
                              damping=c.pd.damping, feedforward=True)
    return controllers.lqr(plant, attitude_weight=c.lqr.attitude_weight,
                           rate_weight=c.lqr.rate_weight, torque_weight=c.lqr.torque_weight,
                           feedforward=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    repeats = 10 if args.quick else 40

    result = spacecraft.run(None)
    scene = result.scene
    T = np.arange(int(round(T_FINAL / STEP)) + 1) * STEP
    saturating = controllers.WheelSet(controllers.ReactionWheel(
        torque_limit=TORQUE_LIMIT, momentum_limit=MOMENTUM_LIMIT, spin_inertia=SPIN_INERTIA))
    free = controllers.WheelSet(controllers.ReactionWheel(
        torque_limit=1.0, momentum_limit=100.0, spin_inertia=SPIN_INERTIA))
    rows, out = [], []
    for (variant, kind, which), loop in result.loops.items():
        design = result.designs[variant]["sim_plant"]
        plant = design if which == "design" else result.truth["sim"]
        inertia = controllers.rigid_body_inertia(design)
        shaper = controllers.mode_shaper(controllers.flexible_modes(design)[:1])
        profile = controllers.reference_profile("shaped", ANGLE, DURATION, shaper=shaper)
        K = flown_controller(kind, design, scene)
        flown_loop = controllers.close_loop(plant, K)
        refs = profile.references(T, inertia)
        U = np.array([refs[name] for name in flown_loop.input_labels])

        def today():
            simulate_manoeuvre(loop, scene.manoeuvre,
                               simulator=controllers.Simulator(loop, scene.manoeuvre.step))

        def flown():
            controllers.Simulator(flown_loop, STEP).outputs(T, U)

        def wheels():
            return controllers.WheelLoop(plant, K, saturating).simulate(T, U)

        def wheels_free():
            return controllers.WheelLoop(plant, K, free).simulate(T, U)

        built = controllers.WheelLoop(plant, K, saturating)

        def wheels_simulate():
            built._simulators.clear()
            built._mode_cache.clear()
            return built.simulate(T, U)

        load_before = os.getloadavg()[0]
        timing = cpu_times({"today": today, "flown": flown, "wheels": wheels,
                            "wheels, simulate only": wheels_simulate,
                            "wheels, unsaturated": wheels_free}, repeats)
        load_after = os.getloadavg()[0]
        run = wheels()
        fine_T = np.arange(int(round(T_FINAL / STEP)) * 32 + 1) * (STEP / 32)
        fine_refs = profile.references(fine_T, inertia)
        fine = controllers.WheelLoop(plant, K, saturating).simulate(
            fine_T, np.array([fine_refs[name] for name in flown_loop.input_labels]))
        labels = list(run.response.output_labels)
        theta = np.asarray(run.response.outputs)[labels.index("theta")]
        theta_fine = np.asarray(fine.response.outputs)[labels.index("theta")][::32]
        error = float(np.max(np.abs(theta - theta_fine)))
        entry = {"variant": variant, "controller": kind, "plant": which,
                 "n_states": int(flown_loop.nstates), "times_cpu_s": timing,
                 "ratio_wheels_to_today_median": timing["wheels"]["median"]
                 / timing["today"]["median"],
                 "ratio_wheels_to_today_min": timing["wheels"]["min"] / timing["today"]["min"],
                 "ratio_wheels_to_flown_median": timing["wheels"]["median"]
                 / timing["flown"]["median"],
                 "ratio_unsaturated_to_today_median": timing["wheels, unsaturated"]["median"]
                 / timing["today"]["median"],
                 "load_average_1min": [load_before, load_after],
                 "saturated": run.saturated, "time_saturated_s": run.time_saturated,
                 "momentum_margin_Nms": run.momentum_margin["wheel"],
                 "theta_error_at_0.1s_rad": error,
                 "theta_peak_rad": float(np.max(np.abs(theta_fine)))}
        out.append(entry)
        rows.append([variant, kind, which, entry["n_states"],
                     f"{1e3 * timing['today']['median']:.2f}",
                     f"{1e3 * timing['flown']['median']:.2f}",
                     f"{1e3 * timing['wheels']['median']:.2f}",
                     f"{1e3 * timing['wheels, simulate only']['median']:.2f}",
                     f"{1e3 * timing['wheels, unsaturated']['median']:.2f}",
                     f"{entry['ratio_wheels_to_today_median']:.2f} "
                     f"({entry['ratio_wheels_to_today_min']:.2f})",
                     f"{run.time_saturated:.1f}", f"{error:.1e} / {entry['theta_peak_rad']:.3f}",
                     f"{load_before:.1f}-{load_after:.1f}"])
        print(rows[-1], flush=True)
    info = machine_info()
    totals = {name: sum(e["times_cpu_s"][name]["median"] for e in out)
              for name in out[0]["times_cpu_s"]}
    ratio = totals["wheels"] / totals["today"]
    rows.append(["all 8 loops", "", "", "", f"{1e3 * totals['today']:.2f}",
                 f"{1e3 * totals['flown']:.2f}", f"{1e3 * totals['wheels']:.2f}",
                 f"{1e3 * totals['wheels, simulate only']:.2f}",
                 f"{1e3 * totals['wheels, unsaturated']:.2f}", f"{ratio:.2f}", "", "", ""])
    write_json("wheels.json", {"machine": info, "repeats": repeats, "loops": out,
                               "totals_cpu_s": totals, "ratio_wheels_to_today_total": ratio,
                               "wheel": {"torque_limit": TORQUE_LIMIT,
                                         "momentum_limit": MOMENTUM_LIMIT,
                                         "spin_inertia": SPIN_INERTIA}})
    header = ["design", "controller", "plant", "states", "today [ms]", "flown [ms]",
              "wheels [ms]", "of which simulate [ms]", "wheels, unsaturated [ms]",
              "wheels / today: median (min)",
              "saturated [s]", "theta error at 0.1 s / peak [rad]", "load (1 min)"]
    text = (f"# The flown slew through reaction wheels vs today's slew\n\n"
            f"{info['date_utc']} UTC, {info['cpu']}, {info['nproc']} CPUs, BLAS threads "
            f"{info['blas_threads']}; CPU time of one call, medians of {repeats} (ratio of "
            "medians; of minima in brackets). Wheel: torque limit 0.03 N m, momentum limit "
            "1.2 N m s, spin inertia 0.01 kg m^2.\n\n" + markdown_table(header, rows) + "\n")
    (RESULTS / "wheels.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
