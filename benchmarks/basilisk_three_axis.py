"""Basilisk vs flexsat in three axes: a slew's differences per axis and per tip motion, in one run.

As ``basilisk_vs_flexsat.py`` does for planar scenes, the slew runs

- in Basilisk through :mod:`spacecraft.basilisk` (each 3-D chain as a
  ``spinningBodyNDOFStateEffector``, two bending hinges and a torsion hinge per joint, the
  nonlinear rigid-body and chain dynamics; the controller as three-axis flight software at T),
- in flexsat: the same sampled-data loop (digital controller at T) on the linear chains
  (``linear_slew``) and on the truth (each beam truncated to the scene's modes),

and the script reports Basilisk - truth (what the chains cost a Basilisk user), Basilisk -
linear chain (the nonlinearity of the slew, plus RK4's error) and linear chain - truth
(flexsat's own chain-vs-beam figure), per signal, as peak differences relative to the
reference's peak.

Cases:

- ``shipped``: the shipped ``three_axis`` scene (820 kg hub with a full inertia tensor, two
  canted rectangular wings and a CFRP boom off every principal axis, each a 3-body
  ``fit_chain_3d``; the scene's PD and LQR; its 10 deg eigen-axis slew in 60 s about (1, 1,
  0.5), 120 s). Its chains are stiff (the wings' in-plane bending and the boom's torsion up to
  5.7e3 rad/s): at the adapter's default step (w_max dt <= 1/2, 8e-5 s) the run takes 1.5e6
  RK4 steps, beyond the default limits.basilisk_seconds. The slew runs at dt = 4e-4 s instead
  (``simulator.dt``; w_max dt = 2.26, inside RK4's stability limit 2.83; the modes that carry
  the response, below 32 rad/s, have w dt < 0.013), and ``step`` checks that choice: the first
  ``STEP_CHECK`` seconds of the PD slew at both steps, Basilisk against Basilisk.
- ``amplitude``: Basilisk - linear chain against the slew angle (0.1 to 45 deg) on a softer
  spacecraft (a full inertia tensor, a 4-body wing chain fitted to a 10 m beam, mounted off the
  centre of mass along (1, 0.5, -0.3), slewed about (1, 1, 0.5)): second order in the angle.

Timings are one run each, with the load average before and after.

    python benchmarks/basilisk_three_axis.py [--quick]

Needs ``bsk`` (``pip install 'flexsat[basilisk]'``); writes results/basilisk_three_axis.{json,md}.
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import argparse
import math
import os
import time
import warnings

import numpy as np

from _common import fmt, machine_info, markdown_table, write_json

__all__ = ["main", "shipped_rows", "amplitude_rows", "step_check", "SHIPPED_DT", "STEP_CHECK"]

#: RK4 step [s] of the shipped scene's runs (w_max dt = 2.26 on its 5655 rad/s mode).
SHIPPED_DT = 4e-4
#: Simulated time [s] of the step check (the default step's run is 5 x as long per second).
STEP_CHECK = 12.0


def _shipped():
    """(design spacecraft, truth plant, scene) of the shipped three_axis scene."""
    from appendages import fit_chain_3d
    from spacecraft import Hub, Mount, Spacecraft, load_scene

    scene = load_scene("three_axis")
    hub = Hub(scene.hub.mass, np.array(scene.hub.inertia))

    def craft(models):
        return Spacecraft(hub, [Mount(models[a.name], a.position,
                                      orientation=np.array(a.orientation), name=a.name)
                                for a in scene.appendages])

    beams = {a.name: a.beam.build() for a in scene.appendages}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        chains = {a.name: fit_chain_3d(beams[a.name], a.fit.n_bodies, match=a.fit.match[0])
                  for a in scene.appendages}
    n_modes = scene.fidelity.n_modes
    truth = craft({n: b.truncated(n_modes) for n, b in beams.items()}).plant(
        tip_deflection=True, name="truth")
    return craft(chains), truth, scene


def _controller(scene, kind, design):
    import controllers

    spec = scene.controller
    if kind == "pd":
        return controllers.pd(design, natural_frequency=spec.pd.natural_frequency,
                              damping=spec.pd.damping, sample_time=spec.sample_time)
    return controllers.lqr(design, attitude_weight=spec.lqr.attitude_weight,
                           rate_weight=spec.lqr.rate_weight,
                           torque_weight=spec.lqr.torque_weight, sample_time=spec.sample_time)


def _relatives(table: dict) -> dict:
    return {name: entry["relative"] for name, entry in table.items()}


def shipped_rows(kinds) -> list:
    """The shipped three_axis scene's slew in Basilisk beside flexsat, per controller."""
    from spacecraft import basilisk as sb

    sc, truth, scene = _shipped()
    design = sc.plant(prune=True)
    m = scene.manoeuvre
    rows = []
    # the PD's flight-software rate for both: the LQR's default would follow its estimator's
    # copy of the chains' fastest mode (5.7e3 rad/s: T = 2e-5 s)
    T = sb.default_sample_time(design, _controller(scene, "pd", design))
    # the rigid spacecraft's gyroscopic torque omega x J omega at the slew's peak rate (a
    # cycloid's: twice the mean, along the eigen-axis), the term the linear plant drops
    e = np.asarray(m.slew_axis, dtype=float) / np.linalg.norm(m.slew_axis)
    w = 2.0 * m.slew_angle / m.slew_time * e
    gyroscopic = dict(zip("xyz", np.abs(np.cross(w, sc.inertia @ w)).tolist()))
    for kind in kinds:
        K = _controller(scene, kind, design)
        load = os.getloadavg()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", sb.BasiliskModelWarning)
            c = sb.slew_comparison(sc, K, m.slew_angle, m.slew_time, duration=m.duration,
                                   sample_time=T, dt=SHIPPED_DT, truth_plant=truth,
                                   axis=m.slew_axis, max_seconds=1e5)
        b = c.basilisk
        d = c.differences
        row = {"case": f"three_axis: {kind}", "controller": kind, "sample_time": T, "dt": b.dt,
               "highest_frequency": b.highest_frequency, "n_bodies": b.layout.n_bodies,
               "held": {a.name: list(a.held) for a in b.layout.appendages},
               "raised_inertias": {a.name: [list(r) for r in a.raised_inertias]
                                   for a in b.layout.appendages},
               "model_warnings": [str(w.message) for w in caught],
               "peaks": {n: e["peak"] for n, e in d["basilisk_vs_truth"].items()},
               "basilisk_vs_truth": _relatives(d["basilisk_vs_truth"]),
               "basilisk_vs_chain": _relatives(d["basilisk_vs_chain"]),
               "chain_vs_truth": _relatives(d["chain_vs_truth"]),
               "torque_differences": {a: d["basilisk_vs_chain"][f"torque_{a}"]["peak_difference"]
                                      for a in "xyz"},
               "gyroscopic_torque": gyroscopic,
               "seconds": dict(b.seconds), "load_before": list(load),
               "load_after": list(os.getloadavg())}
        rows.append(row)
        print(f"  {row['case']}: T={T:g} s, dt={b.dt:.3g} s (w_max {b.highest_frequency:.4g} "
              f"rad/s), {b.layout.n_bodies} spinning bodies; Basilisk {sum(b.seconds.values()):.0f}"
              f" s (load {load[0]:.1f}); max Basilisk - linear chain "
              f"{fmt(max(row['basilisk_vs_chain'].values()))}", flush=True)
    return rows


def step_check() -> dict:
    """The shipped scene's PD slew, its first :data:`STEP_CHECK` s in Basilisk at the default
    RK4 step and at :data:`SHIPPED_DT`: the largest difference per signal relative to its peak."""
    from spacecraft import basilisk as sb

    sc, _, scene = _shipped()
    design = sc.plant(prune=True)
    m = scene.manoeuvre
    K = _controller(scene, "pd", design)
    T = sb.default_sample_time(design, K)
    runs = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sb.BasiliskModelWarning)
        for label, dt in (("default", None), ("large", SHIPPED_DT)):
            runs[label] = sb.simulate_slew(sc, K, m.slew_angle, m.slew_time, duration=STEP_CHECK,
                                           sample_time=T, dt=dt, axis=m.slew_axis,
                                           max_seconds=1e5)
    d = sb.compare(runs["large"].response, runs["default"].response)
    row = {"duration": STEP_CHECK, "dt_default": runs["default"].dt, "dt_large": SHIPPED_DT,
           "w_dt_default": runs["default"].highest_frequency * runs["default"].dt,
           "w_dt_large": runs["large"].highest_frequency * SHIPPED_DT,
           "seconds_default": dict(runs["default"].seconds),
           "seconds_large": dict(runs["large"].seconds), "relative": _relatives(d)}
    worst = max(row["relative"], key=lambda n: row["relative"][n] or 0.0)
    print(f"  first {STEP_CHECK:g} s: dt {runs['default'].dt:.3g} s vs {SHIPPED_DT:g} s: largest "
          f"difference {fmt(row['relative'][worst])} of the peak ({worst}); run "
          f"{runs['default'].seconds['run']:.0f} s vs {runs['large'].seconds['run']:.0f} s",
          flush=True)
    return row


def _amplitude_craft():
    from appendages import Beam, fit_chain_3d
    from spacecraft import Hub, Mount, Spacecraft
    from spacecraft.dynamics.kinematics import orientation_from_axis

    beam = Beam(10.0, 100.0, 0.6, bending_stiffness_y=170.0, torsional_stiffness=30.0,
                torsional_inertia=0.02, damping_ratio=0.005)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        chain = fit_chain_3d(beam, 4)
    hub = Hub(100.0, [[50.0, 2.0, -1.0], [2.0, 40.0, 3.0], [-1.0, 3.0, 30.0]])
    return Spacecraft(hub, [Mount(chain, (0.3, -0.2, 0.1),
                                  orientation=orientation_from_axis([1.0, 0.5, -0.3]),
                                  name="wing")])


def amplitude_rows(angles_deg) -> list:
    """Basilisk - linear chain against the slew angle (softer spacecraft, PD at 0.1 s)."""
    import controllers
    from spacecraft import basilisk as sb

    sc = _amplitude_craft()
    K = controllers.pd(sc.plant(prune=True), natural_frequency=0.3, damping=0.7,
                       sample_time=0.1)
    axis, slew_time, duration = (1.0, 1.0, 0.5), 20.0, 40.0
    rows = []
    for angle in angles_deg:
        a = math.radians(angle)
        result = sb.simulate_slew(sc, K, a, slew_time, duration=duration, axis=axis)
        linear = sb.linear_slew(sc, K, a, slew_time, duration=duration, axis=axis)
        row = {"angle_deg": angle, "dt": result.dt, "seconds": dict(result.seconds),
               "relative": _relatives(sb.compare(result.response, linear))}
        rows.append(row)
        worst = max(row["relative"], key=row["relative"].get)
        print(f"  {angle:g} deg: largest Basilisk - linear chain {fmt(row['relative'][worst])} "
              f"({worst}), x angle^-1 {row['relative'][worst] / a:.3g}", flush=True)
    return rows


def _groups(names):
    """Signals in the report's order: attitude, rate, torque per axis, then tips per appendage."""
    first = [f"{q}_{a}" for q in ("theta", "omega", "torque") for a in "xyz"]
    return [n for n in first if n in names] + sorted(n for n in names if n not in first)


def _markdown(data: dict) -> str:
    info = data["machine"]
    lines = [f"# Basilisk vs flexsat in three axes, {info['date_utc']} UTC",
             f"bsk {data['bsk']}, {info['cpu']}, {info['nproc']} cores, load average "
             f"{', '.join(f'{x:.2f}' for x in info['load_average_1_5_15min'])} (before), "
             f"{', '.join(f'{x:.2f}' for x in data['load_after'])} (after).", "",
             "Peak differences relative to the reference's peak, per signal: Basilisk on the "
             "design chains (3-D, nonlinear, RK4), flexsat's linear sampled-data loop at the "
             "same T on the same chains and on the truth (each beam's Craig-Bampton modes, as "
             "many as the scene's fidelity.n_modes).", "",
             "Reading: Basilisk - linear chain is what the linear plant (linearised about rest) "
             "leaves out, second order in the angle (the last table: each column grows with the "
             "angle, 10x per decade). In three axes it includes the rigid spacecraft's "
             "gyroscopic torque omega x J omega of a slew about a non-principal axis (above "
             "each table: the torque differences are of its size, the loop's answer to it), "
             "centrifugal loads on "
             "chains mounted off the axes, and the composition of finite bending rotations "
             "into the tip twist; none acts in a planar slew about a principal axis, hence the "
             "planar adapter's far smaller figures (basilisk_vs_flexsat.md). The tip motions "
             "of the stiff wings and boom are micrometres: their relative differences are "
             "large fractions of small peaks. RK4's share is the step check's. A truth peak "
             "of 0 is a motion the truth model's modes do not reach (the boom's torsion, "
             "above its 10 Craig-Bampton modes).", ""]
    for row in data["shipped"]:
        lines += [f"## {row['case']}", "",
                  f"T = {row['sample_time']:g} s, dt = {row['dt']:.3g} s (w_max "
                  f"{row['highest_frequency']:.4g} rad/s), {row['n_bodies']} spinning bodies; "
                  f"Basilisk build {row['seconds']['build']:.1f} s + run "
                  f"{row['seconds']['run']:.0f} s (load {row['load_before'][0]:.1f} -> "
                  f"{row['load_after'][0]:.1f}). Held rigid: "
                  + ", ".join(f"{n}: {', '.join(h) or 'nothing'}" for n, h in row["held"].items())
                  + ".", ""]
        lines += ["Torque: Basilisk - linear chain " + ", ".join(
            f"{a} {row['torque_differences'][a]:.3g}" for a in "xyz") + " N m; the rigid "
            "spacecraft's gyroscopic torque |omega x J omega| at the slew's peak rate "
            + ", ".join(f"{a} {row['gyroscopic_torque'][a]:.3g}" for a in "xyz") + " N m.", ""]
        names = _groups(row["basilisk_vs_chain"])
        table = [[n, fmt(row["peaks"].get(n)), fmt(row["basilisk_vs_truth"].get(n)),
                  fmt(row["basilisk_vs_chain"].get(n)), fmt(row["chain_vs_truth"].get(n))]
                 for n in names]
        lines += [markdown_table(["signal", "truth peak [rad, rad/s, N m, m]",
                                  "Basilisk - truth", "Basilisk - linear chain",
                                  "linear chain - truth"], table), ""]
    if data.get("step"):
        r = data["step"]
        lines += ["## RK4 step of the shipped scene's runs", "",
                  f"The PD slew's first {r['duration']:g} s in Basilisk at the default step "
                  f"{r['dt_default']:.3g} s (w_max dt = {r['w_dt_default']:.2f}; run "
                  f"{r['seconds_default']['run']:.0f} s) and at {r['dt_large']:g} s (w_max dt "
                  f"= {r['w_dt_large']:.2f}; run {r['seconds_large']['run']:.0f} s): largest "
                  "difference per signal relative to its peak, "
                  + ", ".join(f"{n} {fmt(v)}" for n, v in r["relative"].items()) + ".", ""]
    if data["amplitudes"]:
        lines += ["## Basilisk - linear chain against the slew angle (softer spacecraft, PD)", ""]
        names = _groups(data["amplitudes"][0]["relative"])
        table = [[f"{r['angle_deg']:g}"] + [fmt(r["relative"][n]) for n in names]
                 for r in data["amplitudes"]]
        lines += [markdown_table(["slew [deg]"] + names, table), ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="the shipped scene's PD only; two slew angles")
    args = parser.parse_args()
    from spacecraft import basilisk as sb

    version = sb.require_basilisk()
    info = machine_info()
    t0 = time.perf_counter()
    print("slew angle", flush=True)
    amplitudes = amplitude_rows([0.1, 10.0] if args.quick else [0.1, 1.0, 10.0, 45.0])
    print("shipped three_axis scene", flush=True)
    shipped = shipped_rows(["pd"] if args.quick else ["pd", "lqr"])
    print("RK4 step of the shipped scene's runs", flush=True)
    step = step_check()
    data = {"bsk": version, "machine": info, "load_after": list(os.getloadavg()),
            "seconds": time.perf_counter() - t0, "shipped": shipped, "step": step,
            "amplitudes": amplitudes}
    path = write_json("basilisk_three_axis.json", data)
    (path.parent / "basilisk_three_axis.md").write_text(_markdown(data) + "\n")
    print(_markdown(data))
    print(f"wrote {path} and basilisk_three_axis.md ({data['seconds']:.0f} s)")


if __name__ == "__main__":
    main()
