"""Basilisk vs flexsat on the scenes' manoeuvres: differences and run times, in one run (issue 12).

For each embedded scene (``default``: the paper's rod, truth = distributed beam; ``hinged_wing``:
truth = a 20-body chain; ``two_wings``: two beams) and each design chain and controller the
runner builds, the scene's slew runs

- in Basilisk through :mod:`spacecraft.basilisk` (the design chain as a
  ``spinningBodyNDOFStateEffector``, nonlinear; the controller as flight software at T), and
- in flexsat: the same sampled-data loop (digital controller at T) on the linear chain
  (``linear_slew``) and on the scene's truth (the beam truncated to the scene's tolerance, or
  the truth chain),

and the script reports Basilisk - truth ("what the chain costs a Basilisk user"), Basilisk -
linear chain ("the nonlinearity of the slew", plus RK4's error) and linear chain - truth
(flexsat's own chain-vs-beam figure) as peak differences relative to the truth's peak. T is
the scene's digital rate or :func:`spacecraft.basilisk.default_sample_time`.

Then: the same for the paper's rod with flexsat fits of 3, 5 and 10 bodies; the difference
against the slew angle (0.1 to 45 deg) on the default mount (on the centre-of-mass axis: the
response is odd in the angle, the difference third order) and on an offset, angled mount
(second order); where ``peer_basilisk.py``'s equal-panel chains diverge at dt = 0.01 s
(RK4's stability limit w_max dt = 2 sqrt(2)).

Timings: medians of 5 (Basilisk build + run; flexsat's linear sampled loop; flexsat's
continuous loop as the runner simulates it), with the load average.

    python benchmarks/basilisk_vs_flexsat.py [--quick]

Needs ``bsk`` (``pip install 'flexsat[basilisk]'``); writes results/basilisk_vs_flexsat.{json,md}.
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import argparse
import math
import os
import time
import warnings

import numpy as np

from _common import fmt, machine_info, markdown_table, median_time, paper_rod, write_json

__all__ = ["main", "scene_rows", "fit_rows", "amplitude_rows", "panel_rows"]


def _relative(differences: dict, name: str):
    entry = differences.get(name)
    return None if entry is None else entry["relative"]


def _tip_name(response) -> str | None:
    tips = [n for n in response.output_labels if n.endswith("tip_deflection")]
    return tips[0] if tips else None


def _continuous_time(plant, K, scene) -> float:
    """flexsat's simulation of the continuous loop, as the runner does it (median of 5)."""
    import controllers

    m = scene.manoeuvre
    n = int(math.floor(m.duration / m.step + 1e-9)) + 1
    T = np.arange(n) * m.step

    def once():
        loop = controllers.close_loop(plant, K)
        U = np.zeros((loop.ninputs, n))
        U[list(loop.input_labels).index("theta_ref")] = controllers.slew_profile(
            T, m.slew_angle, m.slew_time)
        if loop.isdtime(strict=True):
            import control
            return control.forced_response(loop, T, U)
        return controllers.Simulator(loop, m.step).run(T, U)
    return median_time(once, repeats=5)


def one_case(label: str, spacecraft, K, truth_plant, scene, *, repeats: int = 5) -> dict:
    """Basilisk, linear chain and truth for one design spacecraft and controller."""
    from spacecraft import basilisk as sb

    m = scene.manoeuvre
    T = sb.default_sample_time(spacecraft.plant(), K)
    kwargs = dict(duration=m.duration, sample_time=T)
    comparison = sb.slew_comparison(spacecraft, K, m.slew_angle, m.slew_time,
                                    truth_plant=truth_plant, **kwargs)
    result = comparison.basilisk
    tip = _tip_name(result.response)

    def triple(differences):
        return {"theta": _relative(differences, "theta"), "tip": _relative(differences, tip),
                "torque": _relative(differences, "torque")}

    times = [sb.simulate_slew(spacecraft, K, m.slew_angle, m.slew_time, **kwargs).seconds
             for _ in range(repeats)]
    d = comparison.differences
    row = {
        "case": label, "sample_time": T, "dt": result.dt,
        "highest_frequency": result.highest_frequency, "n_bodies": result.layout.n_bodies,
        "basilisk_vs_truth": triple(d["basilisk_vs_truth"]),
        "basilisk_vs_chain": triple(d["basilisk_vs_chain"]),
        "chain_vs_truth": triple(d["chain_vs_truth"]),
        "peak_tip_truth": d["basilisk_vs_truth"][tip]["peak"] if tip else None,
        "time_basilisk_build": float(np.median([t["build"] for t in times])),
        "time_basilisk_run": float(np.median([t["run"] for t in times])),
        "time_flexsat_sampled_chain": median_time(
            lambda: sb.linear_slew(spacecraft, K, m.slew_angle, m.slew_time, **kwargs), repeats=5),
        "time_flexsat_continuous_truth": _continuous_time(truth_plant, K, scene),
        "out_of_plane": result.out_of_plane,
    }
    row["time_basilisk"] = row["time_basilisk_build"] + row["time_basilisk_run"]
    print(f"  {label}: T={T:g} s dt={result.dt:.3g} s  Basilisk-truth tip "
          f"{fmt(row['basilisk_vs_truth']['tip'])}, Basilisk-chain tip "
          f"{fmt(row['basilisk_vs_chain']['tip'])}, chain-truth tip "
          f"{fmt(row['chain_vs_truth']['tip'])}; Basilisk {row['time_basilisk']:.3f} s, "
          f"flexsat {row['time_flexsat_sampled_chain'] * 1e3:.1f} ms", flush=True)
    return row


def scene_rows(names) -> list:
    """Every design variant x controller of the embedded scenes."""
    from spacecraft.design.loop import run
    from spacecraft.scene.read import load_scene, scene_path

    rows = []
    for name in names:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            result = run(load_scene(scene_path(name)), time_responses=False)
        truth = result.truth["sim"]
        for variant, design in result.designs.items():
            for kind, K in design["controllers"].items():
                row = one_case(f"{name}: {variant}, {kind}", design["spacecraft"], K, truth,
                               result.scene)
                row["scene"], row["design"], row["controller"] = name, variant, kind
                rows.append(row)
    return rows


def _damped_fit(beam, n_bodies: int):
    """flexsat's fit with the beam's modal damping at the chain's first mode (as the runner)."""
    from appendages.chain import HingedChain
    from appendages.equivalence import fit_chain

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        chain = fit_chain(beam, n_bodies)
    w1 = float(chain.poles()[0])
    return HingedChain(chain.lengths, chain.masses, chain.inertias, chain.hinge_stiffnesses,
                       hinge_dampings=2.0 * beam.damping_ratio * chain.hinge_stiffnesses / w1,
                       com_offsets=chain.com_offsets, root=chain.root)


def _default_scene_parts(position=(0.5, 0.0), direction=0.0):
    """(beam, truth plant, scene) of the default scene with the rod at another mount."""
    from spacecraft import Hub, Mount, Spacecraft
    from spacecraft.scene.read import default_scene

    scene = default_scene()
    beam = paper_rod(damping_ratio=0.005)
    truth = Spacecraft(Hub(100.0, 50.0), [Mount(beam.truncated(24, method="craig-bampton"),
                                                position, direction, name="rod")])
    return beam, truth.plant(tip_deflection=True), scene


def fit_rows(sizes) -> list:
    """The paper's rod with flexsat fits of several sizes, PD of the default scene."""
    import controllers
    from spacecraft import Hub, Mount, Spacecraft

    beam, truth_plant, scene = _default_scene_parts()
    rows = []
    for n in sizes:
        chain = _damped_fit(beam, n)
        sc = Spacecraft(Hub(100.0, 50.0), [Mount(chain, (0.5, 0.0), 0.0, name="rod")])
        K = controllers.pd(sc.plant(), natural_frequency=0.1, damping=0.7)
        row = one_case(f"rod, fit {n} bodies, pd", sc, K, truth_plant, scene)
        row["n_fit"] = n
        rows.append(row)
    return rows


def amplitude_rows(angles_deg) -> list:
    """Basilisk - linear chain against the slew angle, mount on and off the centre-of-mass axis."""
    import controllers
    from spacecraft import Hub, Mount, Spacecraft
    from spacecraft import basilisk as sb

    beam, _, scene = _default_scene_parts()
    chain = _damped_fit(beam, 3)
    rows = []
    for mount_label, position, direction in (("on axis (0.5, 0) m, 0 deg", (0.5, 0.0), 0.0),
                                             ("offset (0.5, 0.3) m, 30 deg", (0.5, 0.3),
                                              math.radians(30.0))):
        sc = Spacecraft(Hub(100.0, 50.0), [Mount(chain, position, direction, name="rod")])
        K = controllers.pd(sc.plant(), natural_frequency=0.1, damping=0.7)
        T = sb.default_sample_time(sc.plant(), K)
        m = scene.manoeuvre
        for angle in angles_deg:
            a = math.radians(angle)
            result = sb.simulate_slew(sc, K, a, m.slew_time, duration=m.duration, sample_time=T)
            linear = sb.linear_slew(sc, K, a, m.slew_time, duration=m.duration, sample_time=T)
            d = sb.compare(result.response, linear)
            rows.append({"mount": mount_label, "angle_deg": angle,
                         "theta": d["theta"]["relative"], "tip": d["rod_tip_deflection"]["relative"],
                         "torque": d["torque"]["relative"],
                         "peak_tip": d["rod_tip_deflection"]["peak"]})
            print(f"  {mount_label}, {angle:g} deg: theta {fmt(rows[-1]['theta'])}, tip "
                  f"{fmt(rows[-1]['tip'])}, torque {fmt(rows[-1]['torque'])}", flush=True)
    return rows


def panel_rows(sizes) -> list:
    """peer_basilisk.py's equal-panel chains at its 0.01 s step: w_max dt, and whether it diverges.

    The peer's own Basilisk model (``nHingedRigidBodyStateEffector``, RK4 at 0.01 s) runs 20 s of
    its slew; the first non-finite sample is recorded. The adapter's default step and its check
    of a 0.01 s step are shown beside it.
    """
    from peer_basilisk import panel_chain, simulate_basilisk

    import controllers
    from spacecraft import Hub, Mount, Spacecraft
    from spacecraft import basilisk as sb

    beam = paper_rod()
    rows = []
    for n in sizes:
        chain = panel_chain(beam, n)
        sc = Spacecraft(Hub(100.0, 50.0), [Mount(chain, (0.5, 0.0), 0.0, name="rod")])
        w_max = float(sc.modes()[0].max())
        row = {"n_panels": n, "highest_frequency": w_max, "w_dt_at_0.01": w_max * 0.01,
               "rk4_stable_at_0.01": w_max * 0.01 <= sb.simulation.RK4_STABILITY_LIMIT,
               "default_dt": sb.dynamics_step(w_max, 0.01)}
        with np.errstate(all="ignore"):
            t, theta, _, _, _ = simulate_basilisk(chain, t_final=20.0, record_dt=0.1,
                                                  dt_dynamics=0.01)
        bad = np.flatnonzero(~np.isfinite(theta))
        row["peer_first_nonfinite_t"] = float(t[bad[0]]) if bad.size else None
        K = controllers.pd(sc.plant(), natural_frequency=0.1, damping=0.7)
        try:
            sb.simulate_slew(sc, K, math.radians(10.0), 60.0, duration=1.0, sample_time=0.01,
                             dt=0.01)
            row["adapter_at_0.01"] = "runs"
        except ValueError as exc:
            row["adapter_at_0.01"] = "refused (RK4 stability)" if "stability" in str(exc) else \
                f"refused: {str(exc)[:80]}"
        rows.append(row)
        peer = ("finite" if row["peer_first_nonfinite_t"] is None
                else f"NaN from t = {row['peer_first_nonfinite_t']:g} s")
        print(f"  {n} panels: w_max {w_max:.1f} rad/s, w_max*0.01 = {w_max * 0.01:.2f} "
              f"(RK4 limit 2.83); peer at 0.01 s: {peer}; adapter: default dt "
              f"{row['default_dt']:.2g} s, dt = 0.01 s {row['adapter_at_0.01']}", flush=True)
    return rows


def _markdown(data: dict) -> str:
    info = data["machine"]
    lines = [f"# Basilisk vs flexsat (issue 12), {info['date_utc']} UTC",
             f"bsk {data['bsk']}, {info['cpu']}, {info['nproc']} cores, load average "
             f"{', '.join(f'{x:.2f}' for x in info['load_average_1_5_15min'])} (before), "
             f"{', '.join(f'{x:.2f}' for x in data['load_after'])} (after).", "",
             "Peak differences relative to the truth's peak (theta / tip deflection / torque); "
             "Basilisk on the design chain, nonlinear, RK4; flexsat's linear sampled-data loop "
             "at the same T on the chain and on the truth (beam truncated to the scene's "
             "tolerance or truth chain). Times: medians of 5.", ""]

    def triple(d):
        return " / ".join(fmt(d[k]) for k in ("theta", "tip", "torque"))

    header = ["case", "T [s]", "dt [s]", "Basilisk - truth", "Basilisk - linear chain",
              "linear chain - truth", "Basilisk [s]", "flexsat sampled [ms]",
              "flexsat continuous truth [ms]"]
    rows = [[r["case"], f"{r['sample_time']:g}", f"{r['dt']:.3g}", triple(r["basilisk_vs_truth"]),
             triple(r["basilisk_vs_chain"]), triple(r["chain_vs_truth"]),
             f"{r['time_basilisk']:.3f}", f"{r['time_flexsat_sampled_chain'] * 1e3:.1f}",
             f"{r['time_flexsat_continuous_truth'] * 1e3:.1f}"]
            for r in data["scenes"] + data["fits"]]
    lines += [markdown_table(header, rows), "", "## Basilisk - linear chain against the slew angle "
              "(default scene, 3-body fit, PD)", ""]
    rows = [[r["mount"], f"{r['angle_deg']:g}", fmt(r["theta"]), fmt(r["tip"]), fmt(r["torque"])]
            for r in data["amplitudes"]]
    lines += [markdown_table(["mount", "slew [deg]", "theta", "tip", "torque"], rows), "",
              "## peer_basilisk.py's equal panels at dt = 0.01 s", ""]
    rows = [[r["n_panels"], f"{r['highest_frequency']:.1f}", f"{r['w_dt_at_0.01']:.2f}",
             "yes" if r["rk4_stable_at_0.01"] else "no",
             "finite" if r["peer_first_nonfinite_t"] is None
             else f"NaN from {r['peer_first_nonfinite_t']:g} s",
             f"{r['default_dt']:.3g}", r["adapter_at_0.01"]]
            for r in data["panels"]]
    lines += [markdown_table(["panels", "w_max [rad/s]", "w_max * 0.01", "RK4 stable (<= 2.83)",
                              "peer (nHinged, RK4 0.01 s, 20 s)", "adapter's default dt [s]",
                              "adapter at dt = 0.01 s"], rows), ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="default scene and 3 bodies only")
    args = parser.parse_args()
    from spacecraft import basilisk as sb

    version = sb.require_basilisk()
    info = machine_info()
    t0 = time.perf_counter()
    print("scenes", flush=True)
    scenes = scene_rows(["default"] if args.quick else ["default", "hinged_wing", "two_wings"])
    print("fits of the paper's rod", flush=True)
    fits = fit_rows([3] if args.quick else [3, 5, 10])
    print("slew angle", flush=True)
    amplitudes = amplitude_rows([0.1, 10.0] if args.quick else [0.1, 1.0, 10.0, 45.0])
    print("peer_basilisk's panels", flush=True)
    panels = panel_rows([10, 20] if args.quick else [4, 10, 16, 18, 20, 24])
    data = {"bsk": version, "machine": info, "load_after": list(os.getloadavg()),
            "seconds": time.perf_counter() - t0, "scenes": scenes, "fits": fits,
            "amplitudes": amplitudes, "panels": panels}
    path = write_json("basilisk_vs_flexsat.json", data)
    (path.parent / "basilisk_vs_flexsat.md").write_text(_markdown(data) + "\n")
    print(_markdown(data))
    print(f"wrote {path} and basilisk_vs_flexsat.md ({data['seconds']:.0f} s)")


if __name__ == "__main__":
    main()
