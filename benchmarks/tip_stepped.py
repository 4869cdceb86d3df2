"""Tip bodies, stepped and tapered beams: accuracy against independent finite elements, cost of W.

Writes benchmarks/results/tip_stepped.json and tip_stepped.md (issue 21, items 1, 2 and 4):

1. W against the independent finite-element models of the tests (tests/support/fe3d.py: degree-5 bending
   elements, degree-5 rods, the tip body's mass matrix at the last node, its own derivation):
   the largest error of W6 relative to the largest entry at each s, for 1 to 16 elements per
   segment, on a stepped tube with an off-axis tip body (three segments, 3.5 m) and the uniform
   tube with a tip body.
2. Coupled frequencies: a 60 kg three-axis hub with two such booms (flexsat's exact
   Wittrick-Williams count on W6 against fe3d's spacecraft) and a 40 kg planar hub with two
   stepped booms (the planar FE model of tests/appendages/test_stepped_beam.py), largest relative
   difference of the first 8 (6) frequencies per element count.
3. The cost of one W (and W6) evaluation: the uniform beam's closed form against the tip beam
   and stepped beams of 2, 5 and 20 segments (tubes), undamped and damped 0.5 % (cantilever
   convention), at one s and per point of a 1000-point sweep (0.1 to 100 times the first
   frequency); the one-time costs (the damped models' cantilever modes) apart. Median wall
   times, the 1-minute load beside every block.
4. Tapered tube (0.1 m to 0.04 m over 3 m): the first three free-free frequencies for 2 to 128
   midpoint segments against their Richardson limit, and the observed order.
5. The damping convention: a 1e4-times heavier hub than the beam; the first coupled mode's
   damping ratio against the entered one (uniform, tip, stepped).

Run: python benchmarks/tip_stepped.py [--quick]
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads, puts the worktree on sys.path)

import argparse
import math
import os
import sys
import time

import numpy as np

from _common import ROOT, fmt, machine_info, markdown_table, median_time, write_json

sys.path.insert(0, str(ROOT / "tests" / "support"))
import fe3d  # noqa: E402  (the independent 3-D FE reference, shipped with the tests)

from appendages import Beam, SteppedBeam, TipBody  # noqa: E402
from spacecraft import Hub, Mount, Spacecraft  # noqa: E402

J_TIP = np.array([[0.02, 0.001, 0.0], [0.001, 0.03, 0.002], [0.0, 0.002, 0.04]])
OFFSET = np.array([0.1, 0.05, -0.03])


def _load() -> float:
    return os.getloadavg()[0]


def _tube(length, outer, wall, density=2700.0, E=7e10, **kw):
    return Beam.tube(length, outer, wall, density, E, **kw)


def _segments(n: int = 3, **kw):
    base = [_tube(1.2, 0.06, 0.003, **kw), _tube(0.8, 0.04, 0.002, **kw),
            _tube(1.5, 0.03, 0.001, 1600.0, 1.2e11, **kw)]
    if n == 3:
        return base
    # n equal-length segments of a tube whose diameter steps down from 0.06 to 0.03 m
    return [_tube(3.5 / n, 0.06 - 0.03 * k / max(n - 1, 1), 0.002, **kw) for k in range(n)]


def w_against_fe(quick: bool) -> dict:
    s = np.array([0.5j, 3 + 10j, 40j, 150j + 2, 800j])
    cases = {"stepped tube (3 segments) + off-axis tip body": _segments(),
             "uniform tube + off-axis tip body": [_tube(3.5, 0.05, 0.002)]}
    out = {"s": [f"{complex(v):.6g}" for v in s], "cases": {}, "load": _load()}
    for name, segments in cases.items():
        exact = SteppedBeam(segments, tip=TipBody(1.5, J_TIP, OFFSET)).W6(s)
        rows = {}
        for n in ((1, 2, 4) if quick else (1, 2, 4, 8, 16)):
            Wfe = fe3d.appendage_root_compliance(segments, n, s,
                                                 fe3d.TipSpec(1.5, J_TIP, OFFSET))
            rows[n] = np.abs(Wfe - exact).max(axis=(1, 2)) / np.abs(exact).max(axis=(1, 2))
        out["cases"][name] = rows
    return out


def coupled_frequencies(quick: bool) -> dict:
    from test_stepped_beam import _planar_fe

    hub_inertia = np.array([[8.0, 0.2, 0.0], [0.2, 10.0, 0.1], [0.0, 0.1, 12.0]])
    booms = []
    for k, (R, position) in enumerate(((np.eye(3), (0.5, 0.0, 0.1)),
                                       (np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0],
                                                  [0.0, 0.0, 1.0]]), (0.0, 0.6, -0.1)))):
        segs = _segments()[k:]
        J, offset = J_TIP * (1 + k), np.array([0.1, 0.05 * k, -0.03])
        booms.append((segs, TipBody(1.5 - k, J, offset), fe3d.TipSpec(1.5 - k, J, offset),
                      position, R))
    sc = Spacecraft(Hub(60.0, hub_inertia), [
        Mount(SteppedBeam(segs, tip=tip), pos, orientation=R) for segs, tip, _, pos, R in booms])
    t0 = time.process_time()
    exact3 = sc.natural_frequencies(8)
    cost3 = time.process_time() - t0
    three = {}
    for n in ((2, 4) if quick else (2, 4, 8)):
        K, M = fe3d.appendage_spacecraft_matrices(
            60.0, hub_inertia, [(segs, spec, pos, R) for segs, _, spec, pos, R in booms], n)
        three[n] = float(np.abs(fe3d.natural_frequencies(K, M, 8) / exact3 - 1).max())
    segs_a = [Beam(1.0, 400.0, 1.2), Beam(1.5, 150.0, 0.7), Beam(0.8, 60.0, 0.4)]
    segs_b = [Beam(2.0, 300.0, 1.0), Beam(1.0, 90.0, 0.5)]
    tips = [(2.0, 0.05, 0.1), (0.8, 0.01, 0.0)]
    mounts = [((0.4, 0.1), 0.0), ((-0.3, -0.2), math.pi - 0.3)]
    planar_sc = Spacecraft(Hub(40.0, 6.0), [
        Mount(SteppedBeam(segs, tip=TipBody(*tip)), p, a)
        for segs, tip, (p, a) in zip((segs_a, segs_b), tips, mounts)])
    t0 = time.process_time()
    exact2 = planar_sc.natural_frequencies(6)
    cost2 = time.process_time() - t0
    planar = {}
    for n in ((2, 4) if quick else (2, 4, 8)):
        K, M = _planar_fe(40.0, 6.0, [(segs, tip, p, a) for segs, tip, (p, a)
                                      in zip((segs_a, segs_b), tips, mounts)], n)
        planar[n] = float(np.abs(fe3d.natural_frequencies(K, M, 6, n_rigid=3) / exact2 - 1).max())
    return {"three_axis": {"exact": exact3, "cpu_s": cost3, "fe_error": three},
            "planar": {"exact": exact2, "cpu_s": cost2, "fe_error": planar}, "load": _load()}


def cost(quick: bool) -> dict:
    models = {
        "uniform tube (closed form)": lambda **kw: _tube(3.5, 0.05, 0.002, **kw),
        "tube + tip body": lambda **kw: _tube(3.5, 0.05, 0.002, tip=TipBody(1.5, J_TIP), **kw),
        "stepped, 2 segments": lambda **kw: SteppedBeam(_segments(2, **kw)),
        "stepped, 5 segments": lambda **kw: SteppedBeam(_segments(5, **kw)),
        "stepped, 20 segments": lambda **kw: SteppedBeam(_segments(20, **kw)),
    }
    out = {}
    for name, make in models.items():
        t_model = time.perf_counter()
        row = {"load_start": _load()}
        for label, kw in (("undamped", {}), ("damped", {"damping_ratio": 0.005})):
            beam = make(**kw)
            w1 = float(beam.natural_frequencies(1)[0])
            sweep = 1j * w1 * np.logspace(-1.0, 2.0, 1000) + 1e-3 * w1
            one = np.array([3.3j * w1])
            t0 = time.perf_counter()
            beam.W(sweep)                           # first call: modes, caches
            row[f"{label}_first_sweep_s"] = time.perf_counter() - t0
            repeats = 3 if quick else 5
            row[f"{label}_W_one_s"] = median_time(lambda: beam.W(one), repeats=repeats,
                                                  min_total=0.2)
            row[f"{label}_W_sweep_per_point_s"] = median_time(lambda: beam.W(sweep),
                                                              repeats=repeats) / sweep.size
            beam.W6(sweep)
            row[f"{label}_W6_one_s"] = median_time(lambda: beam.W6(one), repeats=repeats,
                                                   min_total=0.2)
            row[f"{label}_W6_sweep_per_point_s"] = median_time(lambda: beam.W6(sweep),
                                                               repeats=repeats) / sweep.size
        row["load_end"] = _load()
        out[name] = row
        print(f"  {name}: {time.perf_counter() - t_model:.1f} s", flush=True)
    return out


def tapered(quick: bool) -> dict:
    counts = (2, 4, 8, 16, 32) if quick else (2, 4, 8, 16, 32, 64, 128)
    w = {}
    for n in counts:
        w[n] = SteppedBeam.tapered(
            3.0, n, section="tube",
            root_dimensions={"outer_diameter": 0.1, "wall_thickness": 0.003},
            tip_dimensions={"outer_diameter": 0.04, "wall_thickness": 0.001},
            density=2700.0, youngs_modulus=7e10).natural_frequencies(3)
    last, before = w[counts[-1]], w[counts[-2]]
    limit = last + (last - before) / 3.0         # Richardson, order 2
    errors = {n: np.abs(w[n] / limit - 1) for n in counts}
    order = {f"{a}->{b}": np.log2(errors[a] / errors[b]) for a, b in zip(counts[:-2], counts[1:-1])}
    return {"frequencies": w, "limit": limit, "errors": errors, "observed_order": order,
            "load": _load()}


def heavy_hub() -> dict:
    from test_cantilever_damping import _coupled_pole

    zeta = 0.005
    beams = {
        "uniform rod": Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=zeta),
        "rod + tip body": Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=zeta,
                                            tip=TipBody(2.0, 0.01, 0.05)),
        "stepped rod": SteppedBeam([
            Beam.circular_rod(4.0, 0.014, 7800.0, 2.06e11, damping_ratio=zeta),
            Beam.circular_rod(6.0, 0.01, 7800.0, 2.06e11, damping_ratio=zeta)]),
    }
    out = {}
    for name, beam in beams.items():
        wc = float(beam.cantilever_frequencies(1)[0])
        pole = wc * complex(-zeta, math.sqrt(1 - zeta**2))
        m, J = beam.mass, beam.inertia + beam.mass * beam.center_of_mass**2
        row = {}
        for ratio in (1e2, 1e3, 1e4):
            s = _coupled_pole(beam, ratio * m, ratio * J, pole)
            row[ratio] = {"frequency": abs(s), "damping_ratio": -s.real / abs(s)}
        out[name] = row
    # the former meaning, for comparison: the coupled pole of the hub and a 64-mode
    # Craig-Bampton model of the rod damped in its free-free modes (its D has no known pole to
    # take out, so the pole is an eigenvalue of the assembled plant)
    old = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=zeta,
                            damping_convention="free-free")
    wc = float(old.cantilever_frequencies(1)[0])
    m, J = old.mass, old.inertia + old.mass * old.center_of_mass**2
    plant = Spacecraft(Hub(1e4 * m, 1e4 * J), [Mount(old.truncated(64), (0.0, 0.0), 0.0)]).plant()
    poles = np.linalg.eigvals(np.asarray(plant.A))
    s = poles[np.argmin(np.abs(poles - 1j * wc))]
    out["uniform rod, free-free convention (before), 64-mode model"] = {
        1e4: {"frequency": abs(s), "damping_ratio": -s.real / abs(s)}}
    return {"entered": zeta, "cases": out, "load": _load()}


def markdown(data: dict) -> str:
    lines = [f"# Tip bodies, stepped and tapered beams (issue 21)", "",
             f"{data['machine']['date_utc']} UTC, {data['machine']['cpu']}, "
             f"{data['machine']['nproc']} cores, BLAS threads {data['machine']['blas_threads']}.", ""]
    fe = data["w_against_fe"]
    lines += ["## W6 against the 3-D finite-element model (tests/support/fe3d.py)", "",
              f"Largest |W6_FE - W6| / max|W6| at each s (load {fe['load']:.1f}).", ""]
    s = fe["s"]
    for name, rows in fe["cases"].items():
        lines += [f"**{name}**", "", markdown_table(
            ["elements per segment"] + [f"s = {v}" for v in s],
            [[n] + [fmt(e) for e in errors] for n, errors in rows.items()]), ""]
    cf = data["coupled_frequencies"]
    lines += ["## Coupled frequencies against the finite-element models", "",
              f"Largest relative difference (load {cf['load']:.1f}); exact: Wittrick-Williams on "
              "the exact W/W6.", "",
              markdown_table(["model", "exact (rad/s)", "CPU of the exact [s]"] +
                             [f"FE, {n} el./segment" for n in cf["three_axis"]["fe_error"]],
                             [["3-D hub + 2 stepped tubes with off-axis tip bodies",
                               ", ".join(f"{v:.6g}" for v in cf["three_axis"]["exact"]),
                               f"{cf['three_axis']['cpu_s']:.2f}"]
                              + [fmt(e) for e in cf["three_axis"]["fe_error"].values()],
                              ["planar hub + 2 stepped booms with tip bodies",
                               ", ".join(f"{v:.6g}" for v in cf["planar"]["exact"]),
                               f"{cf['planar']['cpu_s']:.2f}"]
                              + [fmt(e) for e in cf["planar"]["fe_error"].values()]]), ""]
    lines += ["## Cost of one W / W6 evaluation", "",
              "Median wall time; 'first sweep' includes the one-time modal data of a damped "
              "model (its cantilever modes) and caches.", "",
              markdown_table(
                  ["model", "load", "W one s", "W per point (1000)", "W6 one s",
                   "W6 per point", "first sweep", "damped W one s", "damped W per point",
                   "damped W6 per point", "damped first sweep"],
                  [[name, f"{row['load_start']:.1f}-{row['load_end']:.1f}",
                    f"{row['undamped_W_one_s'] * 1e6:.0f} us",
                    f"{row['undamped_W_sweep_per_point_s'] * 1e6:.1f} us",
                    f"{row['undamped_W6_one_s'] * 1e6:.0f} us",
                    f"{row['undamped_W6_sweep_per_point_s'] * 1e6:.1f} us",
                    f"{row['undamped_first_sweep_s']:.2f} s",
                    f"{row['damped_W_one_s'] * 1e6:.0f} us",
                    f"{row['damped_W_sweep_per_point_s'] * 1e6:.1f} us",
                    f"{row['damped_W6_sweep_per_point_s'] * 1e6:.1f} us",
                    f"{row['damped_first_sweep_s']:.2f} s"]
                   for name, row in data["cost"].items()]), ""]
    base = data["cost"]["uniform tube (closed form)"]
    lines += ["Ratios to the uniform beam's closed form (undamped W per point of the sweep): " +
              ", ".join(f"{name} {row['undamped_W_sweep_per_point_s'] / base['undamped_W_sweep_per_point_s']:.1f}x"
                        for name, row in data["cost"].items()) + ".", ""]
    tp = data["tapered"]
    lines += ["## Tapered tube: convergence in the number of segments", "",
              f"Relative error of the first three free-free frequencies against the Richardson "
              f"limit {', '.join(f'{v:.8g}' for v in tp['limit'])} rad/s (load {tp['load']:.1f}).",
              "", markdown_table(["segments", "w1", "w2", "w3"],
                                 [[n] + [fmt(e) for e in err] for n, err in tp["errors"].items()]),
              "", "Observed order (log2 of successive error ratios): " +
              "; ".join(f"{k}: {', '.join(f'{v:.2f}' for v in o)}"
                        for k, o in tp["observed_order"].items()) + ".", ""]
    hh = data["heavy_hub"]
    rows = []
    for name, row in hh["cases"].items():
        for ratio, v in row.items():
            rows.append([name, f"{float(ratio):.0e}", f"{v['frequency']:.6g}",
                         f"{v['damping_ratio']:.6g}"])
    lines += ["## Damping where engineers define it", "",
              f"Entered damping ratio {hh['entered']}; hub mass and inertia (about the root) "
              f"this many times the beam's; the first coupled mode (load {hh['load']:.1f}).", "",
              markdown_table(["beam", "hub / beam", "frequency [rad/s]", "damping ratio"], rows),
              ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    data = {"machine": machine_info()}
    for name, step in (("w_against_fe", w_against_fe), ("coupled_frequencies", coupled_frequencies),
                       ("cost", cost), ("tapered", tapered)):
        t0 = time.perf_counter()
        data[name] = step(args.quick)
        print(f"{name}: {time.perf_counter() - t0:.1f} s (load {_load():.1f})", flush=True)
    data["heavy_hub"] = heavy_hub()
    data["machine"]["load_average_end"] = list(os.getloadavg())
    suffix = "_quick" if args.quick else ""
    write_json(f"tip_stepped{suffix}.json", data)
    text = markdown(data)
    (ROOT / "benchmarks" / "results" / f"tip_stepped{suffix}.md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
