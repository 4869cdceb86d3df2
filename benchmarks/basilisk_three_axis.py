"""Basilisk vs flexsat in three axes: a slew's differences per axis and per tip motion, in one run.

As ``basilisk_vs_flexsat.py`` does for planar scenes, the slew runs

- in Basilisk through :mod:`spacecraft.basilisk` (each 3-D chain as a
  ``spinningBodyNDOFStateEffector``, two bending hinges and a torsion hinge per joint, the
  nonlinear rigid-body and chain dynamics; the controller as three-axis flight software at T),
- in flexsat: the same sampled-data loop (digital controller at T) on the linear chains
  (``linear_slew``) and on the truth (the scene's truth model),

and the script reports Basilisk - truth (what the chains cost a Basilisk user), Basilisk -
linear chain (the nonlinearity of the slew, plus RK4's error) and linear chain - truth
(flexsat's own chain-vs-beam figure), per signal, as peak differences relative to the
reference's peak.

Cases:

- ``shipped``: ``flexsat run three_axis --simulator basilisk --ssp`` as a user runs it (820 kg
  hub with a full inertia tensor, two canted rectangular wings and a CFRP boom off every
  principal axis, each a 3-body ``fit_chain_3d``; PD with a notch and LQR; a 10 deg eigen-axis
  slew in 60 s about (1, 1, 0.5) and a torque pulse about z at 80 s; every plot, FMUs and
  SSP), its wall time with the load beside it and the design loop's Basilisk figures from
  results.json. Its chains are stiff (the wings' in-plane bending to 1.3e3 rad/s, the boom's
  torsion to 5.7e3 rad/s); the run holds the boom's torsion rigid (above the flight
  software's sampling frequency) and steps RK4 accurately up to the Nyquist frequency only
  (``spacecraft.design.simulators``), and measures what holding costs on the linear chains.
- ``step``: what the default step costs: the PD slew with the disturbance pulse, the whole
  manoeuvre, in Basilisk at the default step (w_max dt <= 2 above the Nyquist frequency) and
  at the accurate one (w_max dt <= 1/2 on every mode), the same torsion held; Basilisk
  against Basilisk.
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
import json
import math
import os
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from _common import fmt, machine_info, markdown_table, write_json

__all__ = ["main", "shipped_rows", "amplitude_rows", "step_check"]

ROOT = Path(__file__).resolve().parent.parent


def _shipped():
    """(design spacecraft, scene) of the shipped three_axis scene (its 3-body chains)."""
    from appendages import fit_chain_3d
    from spacecraft import Hub, Mount, Spacecraft, load_scene

    scene = load_scene("three_axis")
    hub = Hub(scene.hub.mass, np.array(scene.hub.inertia))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the boom's torsion zero (a FitWarning)
        chains = {a.name: fit_chain_3d(a.beam.build(), a.fit.n_bodies, match=a.fit.match[0])
                  for a in scene.appendages}
    craft = Spacecraft(hub, [Mount(chains[a.name], a.position,
                                   orientation=np.array(a.orientation), name=a.name)
                             for a in scene.appendages])
    return craft, scene


def _relatives(table: dict) -> dict:
    return {name: entry["relative"] for name, entry in table.items()}


def shipped_rows() -> list:
    """``flexsat run three_axis --simulator basilisk --ssp``: wall time and, per controller,
    the design loop's Basilisk figures (results.json)."""
    out = Path(tempfile.mkdtemp(prefix="flexsat-bench-"))
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    load = os.getloadavg()
    t0 = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "spacecraft.cli", "run", "three_axis",
                           "--simulator", "basilisk", "--ssp", "--quiet", "--out",
                           str(out / "run")], capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    load_after = os.getloadavg()
    if done.returncode != 0:
        raise SystemExit(f"flexsat run failed ({done.returncode}): {done.stderr}")
    data = json.loads((out / "run" / "results.json").read_text())
    stages = data.get("stats", {})
    print(f"  flexsat run three_axis --simulator basilisk --ssp: exit 0 in {wall:.0f} s "
          f"(load {load[0]:.1f} -> {load_after[0]:.1f})", flush=True)
    rows = []
    for kind, e in data["basilisk"].items():
        d = e["differences"]
        rows.append({
            "case": f"three_axis: {kind}", "controller": kind, "sample_time": e["sample_time"],
            "dt": e["dt"], "highest_frequency": e["highest_frequency"],
            "held": {n: h["held"] for n, h in e.get("chains_as_held", {}).items()},
            "torsion_frequency": {n: h["torsion_frequency"]
                                  for n, h in e.get("chains_as_held", {}).items()
                                  if h.get("torsion_frequency")},
            "peaks": {n: v["peak"] for n, v in d["basilisk_vs_truth"].items()},
            "basilisk_vs_truth": _relatives(d["basilisk_vs_truth"]),
            "basilisk_vs_chain": _relatives(d["basilisk_vs_chain"]),
            "chain_vs_truth": _relatives(d["chain_vs_truth"]),
            "held_vs_chain": _relatives(d.get("held_vs_chain", {})),
            "seconds": e["seconds"], "notes": e.get("notes", []),
            "run_wall": wall, "stage_seconds": stages, "load_before": list(load),
            "load_after": list(load_after)})
    return rows


def step_check() -> dict:
    """The shipped scene's PD slew with its disturbance pulse in Basilisk at the default RK4
    step and at the accurate one (w_max dt <= 1/2), the boom's torsion held in both: the
    largest difference per signal relative to its peak."""
    import controllers
    from spacecraft import basilisk as sb
    from spacecraft.basilisk.simulation import DEFAULT_STEP_FACTOR
    from spacecraft.design.simulators import basilisk_disturbances

    sc, scene = _shipped()
    design = sc.plant(prune=True)
    m = scene.manoeuvre
    K = controllers.pd(design, natural_frequency=scene.controller.pd.natural_frequency,
                       damping=scene.controller.pd.damping)
    T = sb.default_sample_time(design, K)
    sized = {"rigid_above": 2 * math.pi / T}
    runs = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", sb.BasiliskModelWarning)
        w_max = float(np.max(sb.layout(sc, **sized).spacecraft.modes()[0]))
        accurate = sb.dynamics_step(w_max, T)
        for label, kwargs in (("default", {"accurate_up_to": math.pi / T}),
                              ("accurate", {"dt": accurate})):
            load = os.getloadavg()
            runs[label] = sb.simulate_slew(sc, K, m.slew_angle, m.slew_time,
                                           duration=m.duration, sample_time=T,
                                           axis=m.slew_axis, max_seconds=1e5,
                                           disturbances=basilisk_disturbances(m),
                                           **sized, **kwargs)
            runs[label].load = load
    d = sb.compare(runs["default"].response, runs["accurate"].response)
    row = {"duration": m.duration, "sample_time": T, "w_max": w_max,
           "dt_default": runs["default"].dt, "dt_accurate": runs["accurate"].dt,
           "accurate_factor": DEFAULT_STEP_FACTOR,
           "seconds_default": dict(runs["default"].seconds),
           "seconds_accurate": dict(runs["accurate"].seconds),
           "load_default": runs["default"].load[0], "load_accurate": runs["accurate"].load[0],
           "relative": _relatives(d)}
    worst = max(row["relative"], key=lambda n: row["relative"][n] or 0.0)
    print(f"  dt {row['dt_default']:.3g} s vs {row['dt_accurate']:.3g} s: largest difference "
          f"{fmt(row['relative'][worst])} of the peak ({worst}); run "
          f"{row['seconds_default']['run']:.0f} s vs {row['seconds_accurate']['run']:.0f} s",
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
             "same T on the same chains and on the scene's truth model (each beam's "
             "Craig-Bampton modes, as many as its fidelity.tolerance needs).", "",
             "Reading: Basilisk - linear chain is what the linear plant (linearised about rest) "
             "leaves out, second order in the angle (the last table: each column grows with the "
             "angle, 10x per decade). In three axes it includes the rigid spacecraft's "
             "gyroscopic torque omega x J omega of a slew about a non-principal axis, "
             "centrifugal loads on "
             "chains mounted off the axes, and the composition of finite bending rotations "
             "into the tip twist; none acts in a planar slew about a principal axis, hence the "
             "planar adapter's far smaller figures (basilisk_vs_flexsat.md). The tip motions "
             "of the stiff wings and boom are micrometres: their relative differences are "
             "large fractions of small peaks; the torque pulse at 80 s rings the stiff "
             "bending modes in Basilisk and in the linear chain alike. RK4's share is the step "
             "check's (the stiff in-plane bending of the wings, above the Nyquist frequency, "
             "is where the default step's numerical damping shows), holding the boom's "
             "torsion rigid the last column's (measured on the linear chains; its tip twist, "
             "1e-11 rad, is then not simulated). A truth peak of 0 is a motion the truth "
             "model's modes do not reach (the tolerance's modes per beam: the wings' in-plane "
             "bending, the boom's torsion).", ""]
    for row in data["shipped"]:
        lines += [f"## {row['case']}", "",
                  f"`flexsat run three_axis --simulator basilisk --ssp` (every plot, FMUs, SSP): "
                  f"exit 0 in {row['run_wall']:.0f} s wall (load {row['load_before'][0]:.1f} -> "
                  f"{row['load_after'][0]:.1f}), of which Basilisk {row['seconds']['build']:.1f}"
                  f" s build + {row['seconds']['run']:.0f} s run for this controller. T = "
                  f"{row['sample_time']:g} s, dt = {row['dt']:.3g} s (w_max "
                  f"{row['highest_frequency']:.4g} rad/s, w_max dt = "
                  f"{row['highest_frequency'] * row['dt']:.2f}). Held rigid: "
                  + ", ".join(f"{n}: {', '.join(h) or 'nothing'}" for n, h in row["held"].items())
                  + ".", ""]
        lines += [f"- {note}." for note in row["notes"]] + [""]
        names = _groups(row["basilisk_vs_chain"])
        table = [[n, fmt(row["peaks"].get(n)), fmt(row["basilisk_vs_truth"].get(n)),
                  fmt(row["basilisk_vs_chain"].get(n)), fmt(row["chain_vs_truth"].get(n)),
                  fmt(row["held_vs_chain"].get(n))]
                 for n in names]
        lines += [markdown_table(["signal", "truth peak [rad, rad/s, N m, m]",
                                  "Basilisk - truth", "Basilisk - linear chain",
                                  "linear chain - truth",
                                  "linear chain held - free (holding's cost)"], table), ""]
    if data.get("step"):
        r = data["step"]
        lines += ["## RK4 step of the shipped scene's runs", "",
                  f"The PD slew with its disturbance pulse ({r['duration']:g} s, T = "
                  f"{r['sample_time']:g} s, the boom's torsion held) in Basilisk at the default "
                  f"step {r['dt_default']:.3g} s (w_max dt = {r['w_max'] * r['dt_default']:.2f}"
                  f" on {r['w_max']:.4g} rad/s; run {r['seconds_default']['run']:.0f} s, load "
                  f"{r['load_default']:.1f}) and at the accurate step {r['dt_accurate']:.3g} s "
                  f"(w_max dt = {r['w_max'] * r['dt_accurate']:.2f}; run "
                  f"{r['seconds_accurate']['run']:.0f} s, load {r['load_accurate']:.1f}): "
                  "largest difference per signal relative to its peak, "
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
                        help="no step check; two slew angles")
    args = parser.parse_args()
    from spacecraft import basilisk as sb

    version = sb.require_basilisk()
    info = machine_info()
    t0 = time.perf_counter()
    print("slew angle", flush=True)
    amplitudes = amplitude_rows([0.1, 10.0] if args.quick else [0.1, 1.0, 10.0, 45.0])
    print("shipped three_axis scene", flush=True)
    shipped = shipped_rows()
    print("RK4 step of the shipped scene's runs", flush=True)
    step = None if args.quick else step_check()
    data = {"bsk": version, "machine": info, "load_after": list(os.getloadavg()),
            "seconds": time.perf_counter() - t0, "shipped": shipped, "step": step,
            "amplitudes": amplitudes}
    path = write_json("basilisk_three_axis.json", data)
    (path.parent / "basilisk_three_axis.md").write_text(_markdown(data) + "\n")
    print(_markdown(data))
    print(f"wrote {path} and basilisk_three_axis.md ({data['seconds']:.0f} s)")


if __name__ == "__main__":
    main()
