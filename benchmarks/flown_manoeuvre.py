"""Run time of the flown-manoeuvre library pieces on the default scene's plants (issue 22).

The default scene (``flexsat run`` without a scene: the paper's rod on its hub, PD and LQR tuned
on the 3-body chain, 10 deg slew in 60 s simulated for 200 s at 0.1 s) is run once to take its
models: the design plant, the truth plant, the exact beam's frequency response and the two
controllers. Then each new piece is timed against what the run does today:

- profiles: building a step, bang-coast-bang, jerk-limited and ZVD-shaped profile (the shaper on
  the design model's first flexible mode) and sampling its references on the run's grid;
- feedforward designs: ``pd`` / ``lqr`` with ``feedforward=True`` against without;
- responses: the shaped feedforward slew on the truth loop (``profile_response``, samples with
  the linear hold, and exactly through the profile's generator) against today's cycloid on the
  loop without feedforward (``controllers.slew``), and ``manoeuvre_metrics``;
- delay: ``margins`` and ``spillover`` on the truth plant and on the exact beam's FRD with a loop
  delay of 0.2 s against without; the delayed loop in sampled time (continuous PD on the run's
  step, digital PD at 0.5 s with 1.3 samples of delay) against the loop without delay.

Medians of several runs (``_common.median_time``); the 1-minute load average is read beside
every figure (a shared machine: 2 cores, up to 8 processes).

Run::

    python benchmarks/flown_manoeuvre.py [--repeats 7]

Writes benchmarks/results/flown_manoeuvre.json and .md.
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import argparse
import math
import os
import warnings

import numpy as np

from _common import RESULTS, machine_info, markdown_table, median_time, write_json

import controllers
import spacecraft
from controllers import profiles as P

DELAY = 0.2  # s, the loop delay of the delay rows


def default_scene_models() -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = spacecraft.run()
    design = result.designs["poles-and-zeros"]
    m = result.scene.manoeuvre
    return {"design": design["plant"], "truth": result.truth["sim"],
            "pd": design["controllers"]["pd"], "lqr": design["controllers"]["lqr"],
            "frd": result.exact_frd, "angle": m.slew_angle, "slew_time": m.slew_time,
            "duration": m.duration, "step": m.step,
            "pd_spec": result.scene.controller.pd, "lqr_spec": result.scene.controller.lqr}


def measure(rows: list, section: str, what: str, function, repeats: int, **extra) -> float:
    seconds = median_time(function, repeats=repeats, min_total=0.2, max_total=20.0)
    rows.append({"section": section, "what": what, "seconds": seconds,
                 "load_1min": os.getloadavg()[0], **extra})
    print(f"{section:12s} {what:62s} {seconds * 1e3:10.3f} ms  load {os.getloadavg()[0]:.2f}",
          flush=True)
    return seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    r = args.repeats
    info = machine_info()
    models = default_scene_models()
    design, truth, frd = models["design"], models["truth"], models["frd"]
    J = controllers.rigid_body_inertia(design)
    angle, slew_time = models["angle"], models["slew_time"]
    T = np.arange(int(round(models["duration"] / models["step"])) + 1) * models["step"]
    modes = controllers.flexible_modes(design)
    sizes = {"design_states": design.nstates, "truth_states": truth.nstates,
             "exact_frd_frequencies": int(np.asarray(frd.omega).size), "samples": T.size,
             "first_mode": modes[0].frequency, "inertia": J}
    print(sizes)
    rows: list = []
    pd_spec = models["pd_spec"]
    lqr_spec = models["lqr_spec"]
    pd_kw = dict(natural_frequency=pd_spec.natural_frequency, damping=pd_spec.damping)
    lqr_kw = dict(attitude_weight=lqr_spec.attitude_weight, rate_weight=lqr_spec.rate_weight,
                  torque_weight=lqr_spec.torque_weight)

    # -- profiles ------------------------------------------------------------------------------
    torque_limit = 2.0 * J * 4 * angle / slew_time ** 2   # twice the bang-bang's need
    shaper = P.zvd_shaper(modes[0].frequency, modes[0].damping_ratio)
    measure(rows, "profiles", "step_reference", lambda: P.step_reference(angle, slew_time), r)
    measure(rows, "profiles", "bang_coast_bang (given time, torque and rate limits)",
            lambda: P.bang_coast_bang(angle, slew_time, inertia=J, torque_limit=torque_limit,
                                      rate_limit=0.01), r)
    measure(rows, "profiles", "jerk_limited (given time)",
            lambda: P.jerk_limited(angle, slew_time, inertia=J, torque_limit=torque_limit), r)
    measure(rows, "profiles", "zvd_shaper (first mode)",
            lambda: P.zvd_shaper(modes[0].frequency, modes[0].damping_ratio), r)
    measure(rows, "profiles", "reference_profile shaped (jerk-limited base, ZVD)",
            lambda: P.reference_profile("shaped", angle, slew_time, inertia=J,
                                        shaper=shaper, base="smooth"), r)
    shaped = P.reference_profile("shaped", angle, slew_time, inertia=J, shaper=shaper,
                                 base="smooth")
    measure(rows, "profiles", f"references on the run's grid ({T.size} samples)",
            lambda: shaped.references(T, J), r)
    measure(rows, "profiles", "hold_error (linear hold, sup)",
            lambda: shaped.hold_error(models["step"], inertia=J), r)

    # -- feedforward designs ---------------------------------------------------------------
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        measure(rows, "design", "pd (today)", lambda: controllers.pd(design, **pd_kw), r)
        measure(rows, "design", "pd feedforward=True",
                lambda: controllers.pd(design, **pd_kw, feedforward=True), r)
        measure(rows, "design", "lqr (today)", lambda: controllers.lqr(design, **lqr_kw), r)
        measure(rows, "design", "lqr feedforward=True",
                lambda: controllers.lqr(design, **lqr_kw, feedforward=True), r)
        K_ff = controllers.lqr(design, **lqr_kw, feedforward=True)
        K_pd_ff = controllers.pd(design, **pd_kw, feedforward=True)

    # -- responses ---------------------------------------------------------------------------
    loop_today = controllers.close_loop(truth, models["lqr"])
    loop_ff = controllers.close_loop(truth, K_ff)
    dt, t_final = models["step"], models["duration"]
    measure(rows, "response", "slew: today's cycloid on the LQR truth loop",
            lambda: controllers.slew(loop_today, angle, slew_time, dt=dt, t_final=t_final), r)
    measure(rows, "response", "profile_response: shaped + feedforward, linear hold",
            lambda: controllers.profile_response(loop_ff, shaped, inertia=J, dt=dt,
                                                 t_final=t_final), r)
    measure(rows, "response", "profile_response: shaped + feedforward, generator (exact)",
            lambda: controllers.profile_response(loop_ff, shaped, inertia=J, dt=dt,
                                                 t_final=t_final, hold="generator"), r)
    response = controllers.profile_response(loop_ff, shaped, inertia=J, dt=dt, t_final=t_final)
    measure(rows, "response", "manoeuvre_metrics", lambda: controllers.manoeuvre_metrics(
        response), r)
    flown = controllers.manoeuvre_metrics(response)
    today = controllers.manoeuvre_metrics(
        controllers.slew(loop_today, angle, slew_time, dt=dt, t_final=t_final), slew_time)

    # -- delay ---------------------------------------------------------------------------------
    K = models["pd"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        measure(rows, "delay", "margins truth (no delay)", lambda: controllers.margins(truth, K),
                r)
        measure(rows, "delay", f"margins truth, delay {DELAY} s",
                lambda: controllers.margins(truth, K, delay=DELAY), r)
        measure(rows, "delay", "spillover truth (no delay)",
                lambda: controllers.spillover(truth, K), r)
        measure(rows, "delay", f"spillover truth, delay {DELAY} s",
                lambda: controllers.spillover(truth, K, delay=DELAY), r)
        measure(rows, "delay", "spillover exact-beam FRD (no delay)",
                lambda: controllers.spillover(frd, K), r)
        measure(rows, "delay", f"spillover exact-beam FRD, delay {DELAY} s",
                lambda: controllers.spillover(frd, K, delay=DELAY), r)
        margins0 = controllers.margins(truth, K)
        margins_delay = controllers.margins(truth, K, delay=DELAY)
        # the delay-free phase margin at the crossover the delayed loop's margin is taken at
        w_c = margins_delay.gain_crossover_frequency
        L0 = controllers.loop_frequency_response(truth, K, np.array([w_c]))[1][0]
        pm0_there = 180.0 + math.degrees(np.angle(L0))
        frd_verdict = controllers.spillover(frd, K, delay=DELAY)

        def simulate(loop):
            U = np.zeros((loop.ninputs, T.size))
            U[list(loop.input_labels).index("theta_ref")] = controllers.slew_profile(
                T, angle, slew_time)
            return controllers.simulate(loop, T, U)

        measure(rows, "delay", "close_loop + simulate, PD truth (no delay)",
                lambda: simulate(controllers.close_loop(truth, K)), r)
        measure(rows, "delay", f"close_loop + simulate, PD truth, delay {DELAY} s (dt {dt} s)",
                lambda: simulate(controllers.close_loop(truth, K, delay=DELAY, dt=dt)), r)
        Kd = controllers.pd(design, **pd_kw, sample_time=0.5)
        Td = np.arange(int(t_final / 0.5) + 1) * 0.5

        def simulate_digital(loop):
            U = np.zeros((loop.ninputs, Td.size))
            U[list(loop.input_labels).index("theta_ref")] = controllers.slew_profile(
                Td, angle, slew_time)
            return controllers.simulate(loop, Td, U)

        measure(rows, "delay", "digital PD 0.5 s: close_loop + simulate (no delay)",
                lambda: simulate_digital(controllers.close_loop(truth, Kd)), r)
        measure(rows, "delay", "digital PD 0.5 s: close_loop + simulate, delay 0.65 s (exact)",
                lambda: simulate_digital(controllers.close_loop(truth, Kd, delay=0.65)), r)

    figures = {
        "delay_margin_truth_pd": margins0.delay_margin,
        "phase_margin_truth_pd": margins0.phase_margin,
        "phase_margin_truth_pd_with_delay": margins_delay.phase_margin,
        "crossover_of_the_delayed_margin": w_c,
        "phase_margin_there_without_delay": pm0_there,
        "gain_crossover_frequency": margins0.gain_crossover_frequency,
        "exact_frd_verdict_with_delay": {"stable": frd_verdict.stable,
                                         "delay_margin": frd_verdict.margins.delay_margin},
        "lqr_today_step_reference": today,
        "lqr_shaped_feedforward": flown,
    }
    data = {"machine": info, "sizes": sizes, "delay": DELAY, "rows": rows, "figures": figures,
            "load_after_1_5_15min": list(os.getloadavg())}
    write_json("flown_manoeuvre.json", data)
    lines = ["# Flown manoeuvre: run time of the new library pieces (issue 22)", "",
             f"Default scene's models: design plant {design.nstates} states, truth plant "
             f"{truth.nstates} states, exact beam FRD {sizes['exact_frd_frequencies']} "
             f"frequencies, {T.size} samples (200 s at 0.1 s); first flexible mode "
             f"{modes[0].frequency:.4g} rad/s. {info['date_utc']} UTC, {info['cpu']}, "
             f"{info['nproc']} cores, load average at start "
             f"{', '.join(f'{x:.2f}' for x in info['load_average_1_5_15min'])} (1, 5, 15 min), "
             f"after {', '.join(f'{x:.2f}' for x in data['load_after_1_5_15min'])}. Medians of "
             f"{r} runs or more; the 1-minute load beside each.", "",
             markdown_table(["section", "what", "ms", "load (1 min)"],
                            [[row["section"], row["what"], f"{row['seconds'] * 1e3:.3f}",
                              f"{row['load_1min']:.2f}"] for row in rows]), "",
             "Figures of the run (PD on the truth plant; LQR slews):", "",
             f"- delay margin {margins0.delay_margin:.4g} s; phase margin "
             f"{margins0.phase_margin:.4g} deg at {margins0.gain_crossover_frequency:.4g} rad/s; "
             f"with {DELAY} s of delay the smallest is {margins_delay.phase_margin:.4g} deg at "
             f"the crossover {w_c:.4g} rad/s (at a flexible mode), where the loop without delay "
             f"has {pm0_there:.4g} deg: {pm0_there:.4g} - {math.degrees(w_c * DELAY):.4g} "
             f"(omega_c tau) = {pm0_there - math.degrees(w_c * DELAY):.4g} deg;",
             f"- exact beam with {DELAY} s of delay: stable {frd_verdict.stable}, delay margin "
             f"left {frd_verdict.margins.delay_margin:.4g} s;",
             f"- LQR, today's cycloid on theta_ref alone: peak attitude error during the slew "
             f"{today['peak_attitude_error_during']:.3g} rad, residual after it "
             f"{today['residual_attitude_error']:.3g} rad; shaped (ZVD) jerk-limited profile "
             f"with rate reference and feedforward: {flown['peak_attitude_error_during']:.3g} "
             f"rad and {flown['residual_attitude_error']:.3g} rad."]
    (RESULTS / "flown_manoeuvre.md").write_text("\n".join(lines) + "\n")
    print("wrote", RESULTS / "flown_manoeuvre.json")


if __name__ == "__main__":
    main()
