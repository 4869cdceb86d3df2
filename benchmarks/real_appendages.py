"""Real appendages: the accuracy tables and the cost of W, in one place.

Writes benchmarks/results/real_appendages.json and real_appendages.md: what the work on tip
bodies, stepped and tapered beams and finite-element modal data measured, collected from
benchmarks/results/tip_stepped.md and modal_appendage.md (their tables, with their dates), and
completed here on the embedded scene ``real_appendages`` (two stepped 7 m wings with 5 kg tip
bodies on a 1200 kg hub, and pyNastran's SOL 103 rod as a boom):

1. W against an independent finite-element model: the scene's wing (stepped, tip body), its
   exact W against the planar Hermite model of tests/support/fe_planar.py condensed to the
   root, 1 to 16 elements per segment; the round trip, the FE model's own cantilever modes as a
   ModalAppendage against its condensed W.
2. Coupled frequencies: the scene's exact ones (through each appendage's W) against the planar
   FE model of the whole spacecraft (the wings as Hermite booms, the boom as its modes'
   Craig-Bampton model), per element count; and the same spacecraft in three axes (the wings
   with off-axis tip bodies, the boom's six root motions, a full hub inertia tensor: the
   spacecraft of tests/spacecraft/design/test_real_appendages_3d.py) against
   tests/support/fe_scene.py's 3-D model.
3. Chains' poles and zeros against each appendage of the scene (and a tapered boom and a rod
   with a tip body): flexsat's fit with 3 to 6 bodies, the largest relative error of the
   chain's n - 1 poles and of its first n - 1 zeros of W1, W2, W4, and the fit's CPU time;
   in three axes, ``fit_chain_3d`` on the wing and the boom, per bending plane and for the
   torsion and axial motions.
4. The cost of one W evaluation of each new kind (a tip body; stepped beams of 2, 5 and 20
   segments; modal data) against the uniform beam's closed form (one s, and per point of a
   1000-point sweep), undamped and damped, and of one W6 evaluation against the uniform
   beam's; and of the scene's whole run against the default scene's.

Run: python benchmarks/real_appendages.py [--quick]
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads, puts the worktree on sys.path)

import argparse
import math
import os
import re
import sys
import time
import warnings

import numpy as np

from _common import RESULTS, ROOT, fmt, machine_info, markdown_table, median_time, write_json

# the independent FE references (tests/support) and the real-appendage tests' spacecraft
sys.path.insert(0, str(ROOT / "tests" / "support"))
sys.path.insert(0, str(ROOT / "tests" / "spacecraft" / "design"))
import fe_planar  # noqa: E402  (the independent planar FE reference, shipped with the tests)

from appendages import Beam, ModalAppendage, SteppedBeam, TipBody  # noqa: E402
from appendages.equivalence import fit_chain, fit_targets  # noqa: E402
from spacecraft import DesignLoop, load_scene  # noqa: E402


def _load() -> float:
    return os.getloadavg()[0]


def _wing_segments(spec, n_elements: int) -> list:
    """(length, EI, rho A, n_elements) of each segment of a scene's stepped rectangular wing."""
    out = []
    for s in spec.segments:
        d = dict(s.dimensions)
        out.append((s.length, s.youngs_modulus * d["width"] * d["thickness"] ** 3 / 12.0,
                    s.density * d["width"] * d["thickness"], n_elements))
    return out


def _fe_W(K: np.ndarray, M: np.ndarray, s: complex) -> np.ndarray:
    """W(s) of a free FE boom at its root (dofs 0, 1): the inverse of its dynamic stiffness
    condensed to the root, without cancellation at low |s|.

    ``D_rr - D_ri D_ii^-1 D_ir`` of ``D = K + s^2 M`` cancels K's entries down to the
    ``s^2`` rigid mass (eps |K|/(|s|^2 m) relative: 1e-6 at 16 elements per segment and
    s = 0.05j w1). In the coordinates (root motion, interior motion relative to the rigid
    motion ``T = [I; -K_ii^-1 K_ir]``, for which K T = 0) the same condensation reads
    ``s^2 T^T M T - s^4 B^T (K_ii + s^2 M_ii)^-1 B`` with ``B = (M T)_i``: no cancellation.
    """
    r, i = slice(0, 2), slice(2, None)
    T = np.vstack([np.eye(2), -np.linalg.solve(K[i, i], K[i, r])])
    MT = M @ T
    B = MT[i]
    s2 = s * s
    condensed = s2 * (T.T @ MT) - s2 * s2 * (B.T @ np.linalg.solve(K[i, i] + s2 * M[i, i], B))
    return np.linalg.inv(condensed)


# -- 1. W against the FE model ------------------------------------------------------------------
def w_against_fe(scene, quick: bool) -> dict:
    wing_spec = scene.appendages[0].beam
    wing = wing_spec.build().undamped()
    tip = wing_spec.tip
    w1 = float(wing.natural_frequencies(1)[0])
    # off the imaginary axis by a few per cent: W of the undamped models is finite everywhere
    points = [0.05j * w1, (0.02 + 0.7j) * w1, (0.05 + 2.3j) * w1, (0.2 + 6.0j) * w1,
              (0.5 + 15.0j) * w1]
    exact = [wing.W(s) for s in points]
    rows = []
    for n in (1, 2, 4, 8) if quick else (1, 2, 4, 8, 16):
        K, M = fe_planar.boom_matrices(_wing_segments(wing_spec, n),
                                       (tip.mass, tip.inertia, tip.offset))
        errors = [float(np.max(np.abs(_fe_W(K, M, s) - W)) / np.max(np.abs(W)))
                  for s, W in zip(points, exact)]
        rows.append({"elements": n, "errors": errors})
    # the round trip: the FE model's own cantilever modes as modal data
    K, M = fe_planar.boom_matrices(_wing_segments(wing_spec, 8),
                                   (tip.mass, tip.inertia, tip.offset))
    w, G, rigid, tip_motion = fe_planar.cantilever_modal_data(_wing_segments(wing_spec, 8),
                                                              (tip.mass, tip.inertia, tip.offset))
    trip = []
    for k in (4, 8, 16, w.size):
        modal = ModalAppendage(w[:k], G[:k], rigid, length=wing.length)
        errors = [float(np.max(np.abs(modal.W(s) - _fe_W(K, M, s)))
                        / np.max(np.abs(_fe_W(K, M, s)))) for s in points]
        trip.append({"modes": int(k), "errors": errors})
    return {"points": [[p.real, p.imag] for p in points], "first_frequency": w1, "fe": rows,
            "round_trip": trip}


# -- 2. coupled frequencies ---------------------------------------------------------------------
def coupled_against_fe(scene, quick: bool) -> dict:
    from test_real_appendages import fe_coupled_frequencies

    loop = DesignLoop(scene)
    t0 = time.process_time()
    exact = loop.exact_spacecraft().natural_frequencies(8, exact=True)
    cpu = time.process_time() - t0
    boom = loop.beam(scene.appendages[2])
    rows = []
    for n in (2, 4, 8) if quick else (2, 4, 8, 16, 32):
        fe = fe_coupled_frequencies(scene, boom.root_model(), boom.mass, n)
        rows.append({"elements": n, "errors": np.abs(fe / exact - 1.0).tolist()})
    return {"exact": exact.tolist(), "cpu_exact": cpu, "fe": rows, "load": _load()}


def coupled_3d(quick: bool) -> dict:
    """The three-axis spacecraft's exact coupled frequencies against tests/support/fe_scene.py."""
    import copy

    import fe_scene
    from test_real_appendages_3d import EMBEDDED, OFF_AXIS_SCENE, spacecraft_of

    scene = load_scene(copy.deepcopy(OFF_AXIS_SCENE), base=EMBEDDED)
    craft, models = spacecraft_of(scene)
    load = _load()
    t0 = time.process_time()
    exact = craft.natural_frequencies(12)
    cpu = time.process_time() - t0
    rows = []
    for n in (1, 2, 4) if quick else (1, 2, 4, 8):
        fe = fe_scene.coupled_frequencies(scene, models, n, 12)
        rows.append({"elements": n, "errors": np.abs(fe / exact - 1.0).tolist()})
    return {"exact": exact.tolist(), "cpu_exact": cpu, "fe": rows, "load": load}


# -- 3. chains' poles and zeros ---------------------------------------------------------------
def appendages_of(scene) -> dict:
    loop = DesignLoop(scene)
    out = {"wing (stepped, tip body)": loop.beam(scene.appendages[0]),
           "boom (NASTRAN modes, x-y plane)": loop.beam(scene.appendages[2])}
    out["tapered tube (20 segments)"] = SteppedBeam.tapered(
        4.0, 20, section="tube", root_dimensions={"outer_diameter": 0.08, "wall_thickness": 0.002},
        tip_dimensions={"outer_diameter": 0.04, "wall_thickness": 0.002}, density=1600.0,
        youngs_modulus=1.0e11, damping_ratio=0.003)
    out["rod + tip body"] = Beam.circular_rod(3.0, 0.02, 7800.0, 2.06e11, damping_ratio=0.002,
                                              tip=TipBody(2.0, 0.01))
    out["paper's rod (uniform)"] = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)
    return out


def chains(scene, quick: bool) -> dict:
    out = {}
    for name, appendage in appendages_of(scene).items():
        rows = []
        n_max = 5 if "NASTRAN" in name else (4 if quick else 6)
        for n in range(3, n_max + 1):
            t0 = time.process_time()
            load = _load()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                try:
                    chain = fit_chain(appendage, n)
                    reference = fit_targets(appendage, n)["targets"]
                except ValueError as exc:
                    rows.append({"bodies": n, "error": str(exc)[:120]})
                    continue
            cpu = time.process_time() - t0
            got = fit_targets(chain, n)["targets"]
            relative = np.abs(got / reference - 1.0)
            rows.append({"bodies": n, "poles": float(relative[0].max()),
                         "zeros_W1": float(relative[1].max()),
                         "zeros_W2": float(relative[2].max()),
                         "zeros_W4": float(relative[3].max()), "cpu": cpu, "load": load})
        out[name] = {"mass": float(appendage.mass), "length": float(appendage.length),
                     "rows": rows}
    return out


def chains_3d(quick: bool) -> dict:
    """fit_chain_3d on the three-axis scene's wing (tip body on its axis) and boom (six root
    motions): each bending plane's poles and zeros, and the torsion and axial first pole and
    zero, against the appendage's own."""
    import copy

    from appendages.fit3d import fit_chain_3d, motion_frequencies, rod_chain_frequencies
    from test_real_appendages_3d import EMBEDDED, SCENE

    scene = load_scene(copy.deepcopy(SCENE), base=EMBEDDED)
    out = {}
    for index, name in ((0, "wing (stepped, tip body)"), (2, "boom (NASTRAN, 6 root motions)")):
        appendage = scene.appendages[index].structure.build()
        rows = []
        for n in (3,) if quick else (3, 4):
            load = _load()
            t0 = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                chain = fit_chain_3d(appendage, n)
            cpu = time.process_time() - t0
            row = {"bodies": n, "cpu": cpu, "load": load}
            for plane in ("xy", "xz"):
                exact = fit_targets(appendage.planar_view(plane), n)["targets"]
                got = fit_targets(chain.planar_view(plane), n)["targets"]
                relative = np.abs(got / exact - 1.0)
                row[plane] = {"poles": float(relative[0].max()),
                              "zeros": float(relative[1:].max())}
            scale = float(fit_targets(appendage.planar_view("xy"), 2)["targets"][0][0])
            center = np.asarray(appendage.center_of_mass_vector, dtype=float)
            about_axis = float(appendage.inertia_tensor[0, 0]) + appendage.mass * float(
                center[1] ** 2 + center[2] ** 2)
            for motion, k, rigid, inertias, springs in (
                    ("torsion", 3, about_axis, chain.torsional_inertias,
                     chain.torsion_stiffnesses),
                    ("axial", 0, appendage.mass, chain.masses, chain.axial_stiffnesses)):
                rod = motion_frequencies(appendage, k, scale, rigid)
                if rod is None or springs is None:
                    row[motion] = None
                    continue
                free, clamped = rod_chain_frequencies(inertias, springs)
                row[motion] = {"pole": abs(free / rod.free - 1.0),
                               "zero": abs(clamped / rod.clamped - 1.0),
                               "exact": [rod.free, rod.clamped]}
            rows.append(row)
        out[name] = rows
    return out


# -- 4. cost --------------------------------------------------------------------------------------
def _five_segments(damping_ratio: float) -> SteppedBeam:
    """A 7 m stepped tube of five segments, thinner outward, with a 5 kg tip body."""
    return SteppedBeam([Beam.tube(1.4, d, 0.002, 1600.0, 7.0e10, damping_ratio=damping_ratio)
                        for d in (0.14, 0.12, 0.10, 0.08, 0.06)],
                       tip=TipBody(5.0, np.diag([0.1, 0.2, 0.2]), 0.1))


def costs(scene, quick: bool) -> dict:
    items = appendages_of(scene)
    tip = TipBody(5.0, np.diag([0.1, 0.2, 0.2]), 0.1)
    uniform = Beam.tube(7.0, 0.1, 0.002, 1600.0, 7.0e10)
    tapered = items["tapered tube (20 segments)"]
    models = {"uniform tube (closed form)": uniform,
              "uniform tube, damped 0.005": Beam.tube(7.0, 0.1, 0.002, 1600.0, 7.0e10,
                                                      damping_ratio=0.005),
              "uniform tube + tip body, undamped": Beam.tube(7.0, 0.1, 0.002, 1600.0, 7.0e10,
                                                             tip=tip),
              "uniform tube + tip body, damped 0.005": Beam.tube(
                  7.0, 0.1, 0.002, 1600.0, 7.0e10, damping_ratio=0.005, tip=tip),
              "wing: 2 segments + tip body, undamped": items["wing (stepped, tip body)"].undamped(),
              "wing: 2 segments + tip body, damped 0.005": items["wing (stepped, tip body)"],
              "5 segments + tip body, undamped": _five_segments(0.0),
              "5 segments + tip body, damped 0.005": _five_segments(0.005),
              "tapered tube, 20 segments, undamped": tapered.undamped(),
              "tapered tube, 20 segments, damped 0.003": tapered,
              "NASTRAN boom, x-y plane (4 modes), damped 0.003":
                  items["boom (NASTRAN modes, x-y plane)"]}
    rows = _cost_rows(models, "W", quick)
    three = {"uniform tube (closed forms per motion)": uniform,
             "uniform tube + tip body, undamped": models["uniform tube + tip body, undamped"],
             "5 segments + tip body, undamped": models["5 segments + tip body, undamped"],
             "5 segments + tip body, damped 0.005": models["5 segments + tip body, damped 0.005"],
             "NASTRAN boom, 6 root motions (10 modes), damped 0.003": _boom_6()}
    rows6 = _cost_rows(three, "W6", quick)
    runs = []
    if not quick:
        from spacecraft import run

        for name in ("default", "real_appendages"):
            load = _load()
            t0, c0 = time.perf_counter(), time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                run(name)
            runs.append({"scene": name, "wall": time.perf_counter() - t0,
                         "cpu": time.process_time() - c0, "load": load})
    return {"W": rows, "W6": rows6, "runs": runs}


def _boom_6():
    """The scene's boom with its six root motions (the three-axis scene's)."""
    import copy

    from test_real_appendages_3d import EMBEDDED, SCENE

    scene = load_scene(copy.deepcopy(SCENE), base=EMBEDDED)
    return scene.appendages[2].structure.build()


def _cost_rows(models: dict, which: str, quick: bool) -> list:
    rows = []
    for name, model in models.items():
        w1 = float(model.poles()[0]) if hasattr(model, "participation") \
            else float(model.natural_frequencies(1)[0])
        s1 = 1j * 0.7 * w1
        sweep = 1j * np.geomspace(0.1 * w1, 100.0 * w1, 1000)
        evaluate = getattr(model, which)
        load = _load()
        t0 = time.perf_counter()
        evaluate(sweep)                     # the first sweep: one-time modal data and caches
        first = time.perf_counter() - t0
        one = median_time(lambda: evaluate(s1), repeats=7, min_total=0.2,
                          max_total=3.0 if quick else 10.0)
        per_point = median_time(lambda: evaluate(sweep), repeats=3,
                                max_total=5.0 if quick else 20.0) / sweep.size
        rows.append({"model": name, "one_s": one, "per_point": per_point, "first_sweep": first,
                     "load": load})
    base_one, base_point = rows[0]["one_s"], rows[0]["per_point"]
    for r in rows:
        r["one_s_ratio"] = r["one_s"] / base_one
        r["per_point_ratio"] = r["per_point"] / base_point
    return rows


# -- the collected tables --------------------------------------------------------------------------
def collected() -> str:
    """The tables of the earlier benchmarks, as they were written (with their dates)."""
    parts = []
    for name, sections in (("tip_stepped.md", ("W6 against the 3-D finite-element model",
                                               "Coupled frequencies against the finite-element "
                                               "models", "Cost of one W / W6 evaluation",
                                               "Tapered tube: convergence in the number of "
                                               "segments")),
                           ("modal_appendage.md", ("Chains fitted to modal appendages",
                                                   "Cost of one W evaluation"))):
        path = RESULTS / name
        if not path.is_file():
            parts.append(f"(benchmarks/results/{name} is missing: run its benchmark)\n")
            continue
        text = path.read_text()
        header = text.split("\n\n")[1] if "\n\n" in text else ""
        parts.append(f"### From benchmarks/results/{name}\n\n{header.strip()}\n")
        for title in sections:
            match = re.search(rf"^## {re.escape(title)}.*?(?=^## |\Z)", text, re.M | re.S)
            if match:
                parts.append("#" + match.group(0).strip() + "\n")
    return "\n".join(parts)


def markdown(data: dict) -> str:
    m = data["machine"]
    lines = ["# Real appendages: accuracy and cost", "",
             f"Generated by `benchmarks/real_appendages.py`, {m['date_utc']} UTC, {m['cpu']}, "
             f"{m['nproc']} cores (shared with other jobs), numpy {m['numpy']}, scipy "
             f"{m['scipy']}, BLAS threads {m['blas_threads']}. Scene: the embedded "
             "`real_appendages` (hub 1200 kg, 900 kg m^2; two wings: a 1 m CFRP yoke and a 6 m "
             "sandwich panel, 49 kg, with a 5 kg tip body; the boom: pyNastran's SOL 103 rod, "
             "4.57 kg, 0.254 m, first cantilever mode 2869 rad/s).", ""]
    w = data["W"]
    lines += ["## 1. W against an independent finite-element model", "",
              "The scene's wing, undamped: largest |W_FE - W| / max|W| at each s (s in units of "
              f"its first free-free frequency {w['first_frequency']:.5g} rad/s); W_FE the "
              "planar Hermite model of tests/support/fe_planar.py (consistent mass, the tip "
              "body's mass and inertia at the last node), condensed to the root.", ""]
    header = ["elements per segment"] + [f"s = {p[0] / w['first_frequency']:.2g}"
                                         f"{p[1] / w['first_frequency']:+.2g}j w1"
                                         for p in w["points"]]
    lines += [markdown_table(header, [[r["elements"]] + [fmt(e) for e in r["errors"]]
                                      for r in w["fe"]]), ""]
    lines += ["The round trip: the FE model's (8 elements per segment) first k cantilever modes "
              "as a ModalAppendage (participation and rigid mass from its mass matrix) against "
              "the same FE model's condensed W: exact with every mode, converging with k "
              "(the residual mass carries the rest).", ""]
    lines += [markdown_table(["modes"] + header[1:], [[r["modes"]] + [fmt(e) for e in r["errors"]]
                                                       for r in w["round_trip"]]), ""]
    c = data["coupled"]
    lines += ["## 2. Coupled frequencies of the scene against a finite-element model", "",
              f"Exact (Wittrick-Williams on each appendage's W; the boom's W its own: FE-exact; "
              f"{c['cpu_exact']:.2f} s CPU, load {c['load']:.1f}): "
              + ", ".join(f"{v:.6g}" for v in c["exact"]) + " rad/s. Relative difference of "
              "the planar FE model of the whole spacecraft "
              "(tests/spacecraft/design/test_real_appendages.py: Hermite wings with their tip "
              "bodies, the boom as its modes' Craig-Bampton model; fe3d's subspace iteration, "
              "the rigid modes removed exactly). Every mode converges like h^4 (16x per "
              "halving) to flexsat's exact ones.", ""]
    lines += [markdown_table(["elements per segment"] + [f"mode {k + 1}" for k in
                                                        range(len(c["exact"]))],
                             [[r["elements"]] + [fmt(e) for e in r["errors"]] for r in c["fe"]]),
              ""]
    c3 = data["coupled_3d"]
    lines += ["Three axes: the same spacecraft with a hub inertia tensor, the wings along +-y "
              "with their 5 kg tip bodies 0.05 m off their mid-planes (3x3 inertias), the boom "
              "along -z with its six root motions "
              "(tests/spacecraft/design/test_real_appendages_3d.py). Exact (through each "
              f"appendage's W6; {c3['cpu_exact']:.2f} s CPU for 12, load {c3['load']:.1f}): "
              + ", ".join(f"{v:.6g}" for v in c3["exact"])
              + " rad/s. Relative difference of the 3-D FE model (tests/support/fe_scene.py: "
              "fe3d's quintic beam elements per segment with the tip bodies' 6x6 mass matrices, "
              "the boom's Craig-Bampton data, rigid mounts).", ""]
    lines += [markdown_table(["elements per segment"] + [f"mode {k + 1}" for k in
                                                        range(len(c3["exact"]))],
                             [[r["elements"]] + [fmt(e) for e in r["errors"]]
                              for r in c3["fe"]]), ""]
    lines += ["## 3. Chains' poles and zeros against each appendage", "",
              "flexsat's fit (`fit_chain(appendage, n)`, poles-and-zeros): largest relative "
              "error of the chain's n - 1 natural frequencies and of its first n - 1 zeros of "
              "W1, W2 (= W3), W4 against the appendage's own (its exact ones; modal data's "
              "own). CPU: one fit (a uniform beam's fit is memoised per n: its first only "
              "counts). The NASTRAN boom's x-y plane has 4 modes: chains of up to 5 bodies.", ""]
    for name, entry in data["chains"].items():
        lines += [f"**{name}** (mass {entry['mass']:.5g} kg, length {entry['length']:.4g} m)", ""]
        rows = []
        for r in entry["rows"]:
            if "error" in r:
                rows.append([r["bodies"], r["error"], "", "", "", "", ""])
            else:
                rows.append([r["bodies"], fmt(r["poles"]), fmt(r["zeros_W1"]),
                             fmt(r["zeros_W2"]), fmt(r["zeros_W4"]), f"{r['cpu']:.2f}",
                             f"{r['load']:.1f}"])
        lines += [markdown_table(["bodies", "poles", "zeros W1", "zeros W2", "zeros W4",
                                  "CPU [s]", "load"], rows), ""]
    lines += ["Three axes (`fit_chain_3d`, the three-axis scene's wing with its tip body on the "
              "axis and its boom): largest relative error of each bending plane's n - 1 poles "
              "and first n - 1 zeros of W1, W2, W4 (the plane's view, the root's other motions "
              "held), and of the first pole and zero of torsion and axial motion (the chain's "
              "spring chain against the appendage's own, the other root motions held). One "
              "body layout serves both planes: the wing's x-z plane, whose flexibility lies "
              "in its narrow yoke (in x-y: in its thin panel), does not fit on the x-y "
              "plane's bodies (its first x-z mode lies two decades above the x-y plane's). "
              "A motion whose pole/zero ratio the bounded tilt cannot reach (the boom's "
              "torsion: a heavy tip on a short rod) keeps its pole and is warned.", ""]
    rows = []
    for name, entries in data["chains_3d"].items():
        for r in entries:
            def pair(entry):
                return "rigid" if entry is None else f"{fmt(entry['pole'])} / {fmt(entry['zero'])}"
            rows.append([name, r["bodies"], fmt(r["xy"]["poles"]), fmt(r["xy"]["zeros"]),
                         fmt(r["xz"]["poles"]), fmt(r["xz"]["zeros"]), pair(r["torsion"]),
                         pair(r["axial"]), f"{r['cpu']:.2f}", f"{r['load']:.1f}"])
    lines += [markdown_table(["appendage", "bodies", "x-y poles", "x-y zeros", "x-z poles",
                              "x-z zeros", "torsion pole / zero", "axial pole / zero",
                              "CPU [s]", "load"], rows), ""]
    k = data["cost"]
    lines += ["## 4. Cost of one W evaluation", "",
              "Median wall time; one s at 0.7 times the first frequency, and per point of a "
              "1000-point sweep from 0.1 to 100 times it; the first sweep includes the one-time "
              "work (a damped model's cantilever modes, caches). Ratios to the uniform tube's "
              "closed form (7 m, undamped). Load: the 1-minute average before each model.", ""]
    lines += [markdown_table(["model", "one s [us]", "per point [us]", "first sweep [s]",
                              "one s / uniform", "per point / uniform", "load"],
                             [[r["model"], f"{1e6 * r['one_s']:.1f}",
                               f"{1e6 * r['per_point']:.2f}", f"{r['first_sweep']:.3f}",
                               f"{r['one_s_ratio']:.1f}", f"{r['per_point_ratio']:.1f}",
                               f"{r['load']:.1f}"] for r in k["W"]]), ""]
    lines += ["One W6 evaluation (three axes), ratios to the uniform tube's (its motions' "
              "closed forms):", ""]
    lines += [markdown_table(["model", "one s [us]", "per point [us]", "first sweep [s]",
                              "one s / uniform", "per point / uniform", "load"],
                             [[r["model"], f"{1e6 * r['one_s']:.1f}",
                               f"{1e6 * r['per_point']:.2f}", f"{r['first_sweep']:.3f}",
                               f"{r['one_s_ratio']:.1f}", f"{r['per_point_ratio']:.1f}",
                               f"{r['load']:.1f}"] for r in k["W6"]]), ""]
    if k["runs"]:
        lines += ["The whole run (`flexsat run`'s design loop without the report: models, "
                  "fits, the fidelity search, tuning, loops, slews):", ""]
        lines += [markdown_table(["scene", "wall [s]", "CPU [s]", "load"],
                                 [[r["scene"], f"{r['wall']:.1f}", f"{r['cpu']:.1f}",
                                   f"{r['load']:.1f}"] for r in k["runs"]]), ""]
    lines += ["## Collected: the earlier measurements", "", data["collected"]]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer points (a smoke test)")
    args = parser.parse_args()
    scene = load_scene("real_appendages")
    data = {"machine": machine_info()}
    print("W against FE...", flush=True)
    data["W"] = w_against_fe(scene, args.quick)
    print("coupled frequencies...", flush=True)
    data["coupled"] = coupled_against_fe(scene, args.quick)
    data["coupled_3d"] = coupled_3d(args.quick)
    print("chains...", flush=True)
    data["chains"] = chains(scene, args.quick)
    data["chains_3d"] = chains_3d(args.quick)
    print("cost...", flush=True)
    data["cost"] = costs(scene, args.quick)
    data["collected"] = collected()
    suffix = "_quick" if args.quick else ""
    write_json(f"real_appendages{suffix}.json", data)
    (RESULTS / f"real_appendages{suffix}.md").write_text(markdown(data))
    print(f"wrote {RESULTS / f'real_appendages{suffix}.md'}")


if __name__ == "__main__":
    main()
