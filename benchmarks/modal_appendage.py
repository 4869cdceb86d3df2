"""Finite-element modal data as appendages: the chain fit's accuracy and the cost of W.

Writes benchmarks/results/modal_appendage.json and modal_appendage.md:

1. Chains fitted to ModalAppendages (appendages.equivalence.fit_chain, flexsat's fit of any
   appendage that gives W), their accuracy measured as for the uniform beam: the largest
   |relative error| of the chain's n - 1 poles and first n - 1 zeros of W1, W2 (= W3) and W4
   against the appendage's own, and the criterion's band error (largest over r of
   max |ln(W_r^chain/W_r^appendage)| on s = omega (0.02 + i) over its default band); the fit's
   CPU time (cold: memo cleared) and whether it stopped at its budget (FitWarning). Cases:
   the paper's rod as 60 cantilever modes (against the rod's own fit and the exact rod), the
   stepped boom with a tip body of tests/support/fe_planar.py (30 modes), and NASTRAN's beam_modes
   (tests/data/nastran: a round rod with a tip mass, its x-y plane: 4 modes).
2. The cost of one W(s) evaluation: ModalAppendage with 10 to 1000 modes (the paper's rod's
   cantilever modes; undamped, and damped 0.5 %) against the exact uniform beam's closed form,
   for one s and per point of a 1000-point sweep; W6 likewise (three-axis data of a tube
   against Beam.W6). Median wall time; the load average beside every block.

Run: python benchmarks/modal_appendage.py [--quick]; with FLEXSAT_BENCH_BLAS_THREADS=1 the
results go to modal_appendage_blas1.* (OpenBLAS threads woken for the small products of W on a
busy machine cost more than the products: compare the two files).
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads, puts the worktree on sys.path)

import argparse
import os
import sys
import time
import warnings

import numpy as np

from _common import ROOT, fmt, machine_info, markdown_table, median_time, paper_rod, write_json

sys.path.insert(0, str(ROOT / "tests" / "support"))
import fe_planar  # noqa: E402  (the independent FE reference, shipped with the tests)

from appendages import Beam, ModalAppendage, fit_chain, fitting, nastran  # noqa: E402
from appendages.equivalence import criterion, spectral_errors  # noqa: E402
from appendages.fitting import FitWarning  # noqa: E402


def _load() -> float:
    return os.getloadavg()[0]


def _beam_data(beam: Beam, n: int, *, damping: float = 0.0, three_axis: bool = False):
    L, rho = beam.length, beam.linear_density
    rigid = rho * np.array([[L, L**2 / 2.0], [L**2 / 2.0, L**3 / 3.0]])
    w, G = beam.cantilever_frequencies(n), beam.modal_participation(n)
    if not three_axis:
        return ModalAppendage(w, G, rigid, damping=damping, length=L)
    # both planes' modes (equal planes: twins), torsion and axial motion held rigid (no mode)
    w2 = np.repeat(w, 2)
    G6 = np.zeros((2 * n, 6))
    G6[0::2, 1], G6[0::2, 5] = G[:, 0], G[:, 1]
    G6[1::2, 2], G6[1::2, 4] = G[:, 0], -G[:, 1]
    M6 = np.zeros((6, 6))
    M6[:3, :3] = beam.mass * np.eye(3)
    M6[1, 5] = M6[5, 1] = rigid[0, 1]
    M6[2, 4] = M6[4, 2] = -rigid[0, 1]
    M6[3, 3] = beam.torsional_inertia * L
    M6[4, 4] = M6[5, 5] = rigid[1, 1]
    return ModalAppendage(w2, G6, M6, damping=damping, length=L)


def _cases():
    rod = paper_rod()
    segments = [(3.0, 2.0e4, 4.0, 12), (4.0, 6.0e3, 2.0, 16)]
    w, G, rigid, _ = fe_planar.cantilever_modal_data(segments, (5.0, 0.8, 0.3))
    boom = ModalAppendage(w[:30], G[:30], rigid, damping=0.005, length=7.0)
    from test_nastran import lumped_mass_matrix  # the deck's mass matrix, checked there

    modes = nastran.NastranModes.load(ROOT / "tests" / "data" / "nastran" / "beam_modes.npz")
    nastran_rod = nastran.modal_appendage(modes, root=1, units=("in", "slinch"),
                                          mass_matrix=lumped_mass_matrix()).planar_view("xy")
    return [("paper's rod, 60 cantilever modes", _beam_data(rod, 60), rod, range(3, 9)),
            ("stepped boom + tip body (FE, 30 modes)", boom, None, range(3, 9)),
            ("NASTRAN beam_modes, x-y plane (4 modes)", nastran_rod, None, range(3, 5))]


def _fit_row(appendage, n: int, exact) -> dict:
    fitting.clear_memo()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", FitWarning)
        t0 = time.process_time()
        chain = fit_chain(appendage, n)
        cpu = time.process_time() - t0
    errors = {k: float(np.max(np.abs(v))) for k, v in spectral_errors(appendage, chain).items()}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        band = float(np.max(criterion(appendage, chain).max_log_error))
    row = {"n_bodies": n, "cpu_s": cpu, "stopped": any(issubclass(w.category, FitWarning)
                                                        for w in caught),
           "poles": errors["poles"], "zeros": max(errors["W1"], errors["W2"], errors["W4"]),
           "band": band, "load": _load()}
    if exact is not None:
        fitting.clear_memo()
        own = fit_chain(exact, n)
        e = {k: float(np.max(np.abs(v))) for k, v in spectral_errors(exact, own).items()}
        row["uniform_fit"] = {"poles": e["poles"], "zeros": max(e["W1"], e["W2"], e["W4"])}
        e = {k: float(np.max(np.abs(v))) for k, v in spectral_errors(exact, chain).items()}
        row["against_exact"] = {"poles": e["poles"], "zeros": max(e["W1"], e["W2"], e["W4"])}
    return row


def fits() -> list:
    out = []
    for name, appendage, exact, sizes in _cases():
        rows = [_fit_row(appendage, n, exact) for n in sizes]
        out.append({"case": name, "mass": appendage.mass, "length": appendage.length,
                    "center_of_mass": appendage.center_of_mass, "rows": rows})
        print(name)
        for row in rows:
            print(f"  {row['n_bodies']:2d} bodies: poles {row['poles']:.2e}, zeros "
                  f"{row['zeros']:.2e}, band {row['band']:.3f}, {row['cpu_s']:.2f} s CPU"
                  f"{' (stopped)' if row['stopped'] else ''}, load {row['load']:.1f}")
    return out


def w_costs(quick: bool) -> dict:
    rod = paper_rod()
    w1 = float(rod.natural_frequencies(1)[0])
    one = np.array([0.7 * w1 * (0.02 + 1j)])
    sweep = np.geomspace(0.01, 100.0, 1000) * w1 * (0.02 + 1j)
    sizes = (10, 30, 100) if quick else (10, 30, 100, 300, 1000)
    out = {"load_before": _load(), "planar": [], "three_axis": []}
    out["beam"] = {"one": median_time(lambda: rod.W(one), min_total=0.2),
                   "sweep": median_time(lambda: rod.W(sweep), repeats=5)}
    damped_rod = paper_rod(damping_ratio=0.005)
    out["beam_damped"] = {"one": median_time(lambda: damped_rod.W(one), min_total=0.2),
                          "sweep": median_time(lambda: damped_rod.W(sweep), repeats=5)}
    for n in sizes:
        for zeta in (0.0, 0.005):
            app = _beam_data(rod, n, damping=zeta)
            app.W(one)  # the operator (for damping: one eigen-decomposition) built once
            out["planar"].append({"n_modes": n, "damping": zeta,
                                  "one": median_time(lambda: app.W(one), min_total=0.2),
                                  "sweep": median_time(lambda: app.W(sweep), repeats=5),
                                  "load": _load()})
    tube = Beam.tube(4.0, 0.1, 0.002, 2700.0, 70e9)
    out["beam6"] = {"one": median_time(lambda: tube.W6(one), min_total=0.2),
                    "sweep": median_time(lambda: tube.W6(sweep), repeats=5)}
    for n in sizes[:-1] if not quick else sizes[:2]:
        app = _beam_data(tube, n, three_axis=True)
        app.W6(one)
        out["three_axis"].append({"n_modes": 2 * n, "one": median_time(lambda: app.W6(one),
                                                                       min_total=0.2),
                                  "sweep": median_time(lambda: app.W6(sweep), repeats=5),
                                  "load": _load()})
    out["load_after"] = _load()
    return out


def markdown(data: dict) -> str:
    info = data["machine"]
    lines = ["# Modal appendages: chain fits and the cost of W", "",
             f"Generated by `benchmarks/modal_appendage.py`, {info['date_utc']} UTC, "
             f"{info['cpu']}, {info['nproc']} cores (shared), numpy {info['numpy']}, scipy "
             f"{info['scipy']}, BLAS threads {info['blas_threads']}.", "",
             "## Chains fitted to modal appendages", "",
             "flexsat's fit (`fit_chain(appendage, n)`, match = poles-and-zeros): largest "
             "|relative error| of the chain's n - 1 poles and first n - 1 zeros of W1, W2, W4 "
             "against the appendage's own; band: the criterion's largest max |ln(W_r^chain / "
             "W_r)| over its default band; CPU: one cold fit; stopped: the budget cut its first "
             "path (FitWarning). The stepped boom is damped 0.5 % on every cantilever mode; its "
             "chains have the fits' stiffness-proportional hinge damping, the boom's first-mode "
             "ratio at the chain's first mode and w_k/w_1 times it at mode k (3.2 times at the "
             "second): that difference, not the poles and zeros, sets its band error from 5 "
             "bodies on (0.32; the undamped rod's keeps falling).", ""]
    for case in data["fits"]:
        lines += [f"### {case['case']}", "",
                  f"mass {case['mass']:.6g} kg, length {case['length']:.6g} m, centre of mass "
                  f"{case['center_of_mass']:.6g} m (kept exactly by every chain).", ""]
        has_exact = "uniform_fit" in case["rows"][0]
        header = ["bodies", "poles", "zeros", "band", "CPU [s]", "stopped", "load"]
        if has_exact:
            header += ["rod's own fit: poles", "zeros", "this chain vs exact rod: poles",
                       "zeros"]
        rows = []
        for r in case["rows"]:
            row = [r["n_bodies"], fmt(r["poles"]), fmt(r["zeros"]), f"{r['band']:.3f}",
                   f"{r['cpu_s']:.2f}", "yes" if r["stopped"] else "no", f"{r['load']:.1f}"]
            if has_exact:
                row += [fmt(r["uniform_fit"]["poles"]), fmt(r["uniform_fit"]["zeros"]),
                        fmt(r["against_exact"]["poles"]), fmt(r["against_exact"]["zeros"])]
            rows.append(row)
        lines += [markdown_table(header, rows), ""]
    w = data["w_costs"]
    lines += ["## Cost of one W evaluation", "",
              f"Median wall time; one s (a single complex frequency) and per point of a "
              f"1000-point sweep (the sweep's time / 1000). Load average (1 min) "
              f"{w['load_before']:.1f} before, {w['load_after']:.1f} after.", ""]
    header = ["model", "modes", "damping", "one s [us]", "per point of 1000 [us]",
              "one s / beam's", "per point / beam's", "load"]
    rows = []
    for label, ref in (("exact uniform beam (closed form)", w["beam"]),
                       ("exact uniform beam, damped 0.005", w["beam_damped"])):
        rows.append([label, "-", "0" if ref is w["beam"] else "0.005",
                     f"{ref['one'] * 1e6:.1f}", f"{ref['sweep'] * 1e3:.2f}", "1", "1", "-"])
    for r in w["planar"]:
        ref = w["beam"] if r["damping"] == 0.0 else w["beam_damped"]
        rows.append(["ModalAppendage W", r["n_modes"], f"{r['damping']:g}",
                     f"{r['one'] * 1e6:.1f}", f"{r['sweep'] * 1e3:.2f}",
                     f"{r['one'] / ref['one']:.2f}", f"{r['sweep'] / ref['sweep']:.2f}",
                     f"{r['load']:.1f}"])
    rows.append(["exact tube, W6", "-", "0", f"{w['beam6']['one'] * 1e6:.1f}",
                 f"{w['beam6']['sweep'] * 1e3:.2f}", "1", "1", "-"])
    for r in w["three_axis"]:
        rows.append(["ModalAppendage W6", r["n_modes"], "0", f"{r['one'] * 1e6:.1f}",
                     f"{r['sweep'] * 1e3:.2f}", f"{r['one'] / w['beam6']['one']:.2f}",
                     f"{r['sweep'] / w['beam6']['sweep']:.2f}", f"{r['load']:.1f}"])
    lines += [markdown_table(header, rows), ""]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer sizes")
    parser.add_argument("--markdown-from", type=str, help="only rewrite the .md of a .json")
    args = parser.parse_args()
    if args.markdown_from:
        import json

        source = ROOT / "benchmarks" / "results" / args.markdown_from
        source.with_suffix(".md").write_text(markdown(json.loads(source.read_text())) + "\n")
        return
    data = {"machine": machine_info(), "fits": fits(), "w_costs": w_costs(args.quick)}
    data["machine"]["load_average_end"] = list(os.getloadavg())
    name = "modal_appendage" + ("" if _common.BLAS_THREADS == "default"
                                else f"_blas{_common.BLAS_THREADS}") + ("_quick" if args.quick
                                                                       else "")
    write_json(f"{name}.json", data)
    text = markdown(data)
    (ROOT / "benchmarks" / "results" / f"{name}.md").write_text(text + "\n")
    print(text)


if __name__ == "__main__":
    main()
