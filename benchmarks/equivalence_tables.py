"""Equivalence of hinged chains and the paper's rod: the paper's table and errors vs the exact beam.

Prints, and writes to benchmarks/results/equivalence.json and equivalence.md:

1. the paper's table (2-mode free-free beam vs its three-body chain) as flexsat computes it,
   beside the numbers the paper printed;
2. pole and zero errors against the EXACT distributed beam for the paper's chain, flexsat's
   fitted three-body chain, RFEM and Molenaar superelement chains of 4-10 degrees of freedom and
   flexsat's fitted chains of the same sizes (a chain of n bodies has n + 1 degrees of freedom:
   delta, phi and n - 1 hinge angles; n - 1 elastic modes);
3. the six zeros of the two three-body chains against the exact beam;
4. fit times (median of several runs, each cold: the memo of appendages.fitting cleared first;
   benchmarks/bench_fit.py measures them in detail), and the cost of a chain's W(s), poles and
   zeros.

Error measures: "first two" is the largest |relative error| of w1, w2 and n_r1, n_r2 (r = 1, 2, 4:
the paper's quantities); "all" the largest over all n - 1 poles and the first n - 1 zeros of W1,
W2 (= W3) and W4 of the chain; "band" the largest over r of max |ln(W_r^chain/W_r^beam)| on
s = omega (0.02 + i) over the criterion's default band (appendages.equivalence).

Run: python benchmarks/equivalence_tables.py [--repeats N]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import pathlib
import statistics
import time

import numpy as np

from appendages import fitting
from appendages.beam import Beam
from appendages.chain import HingedChain
from appendages.equivalence import criterion, fit_chain, spectral_errors
from appendages.interface import FiniteAppendage

RESULTS = pathlib.Path(__file__).resolve().parent / "results"
PAPER_FREQUENCIES = (2.8744, 7.9231)
PAPER_TABLE = {  # PAPER.md: (beam, 2 modes), (chain)
    "k1": (1.9588, 1.5814), "k2 = k3": (-0.9145, -0.5647), "k4": (0.5639, 0.2627),
    "n11": (1.9965, 2.0583), "n21 = n31": (1.3322, 1.4653), "n41": (0.8793, 1.0524),
    "n12": (6.5858, 7.1097), "n22 = n32": (5.5945, 6.4729), "n42": (4.8272, 5.9092),
    "w1": (2.8744, 2.8744), "w2": (7.9231, 7.9231),
}


def timed(function, repeats):
    """(result of the last call, (median wall time, median CPU time of this process) [s]),
    each call cold (the fit memo cleared)."""
    wall, cpu = [], []
    for _ in range(repeats):
        fitting.clear_memo()
        start, start_cpu = time.perf_counter(), time.process_time()
        result = function()
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return result, (statistics.median(wall), statistics.median(cpu))


def errors_row(rod, name, chain, kind, fit_time=None):
    all_errors = spectral_errors(rod, chain)
    first_two = spectral_errors(rod, chain, 2) if chain.n_bodies >= 3 else all_errors
    band = criterion(rod, chain).max_log_error.max()
    return {
        "model": name, "kind": kind, "n_bodies": chain.n_bodies, "dof": chain.n_bodies + 1,
        "poles_first_two": float(np.abs(first_two["poles"]).max()),
        "zeros_first_two": float(max(np.abs(first_two[k]).max() for k in ("W1", "W2", "W4"))),
        "all": float(max(np.abs(e).max() for e in all_errors.values())),
        "band_log_error": float(band),
        "fit_time_s": None if fit_time is None else fit_time[0],
        "fit_cpu_time_s": None if fit_time is None else fit_time[1],
    }


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="runs per timing (median)")
    args = parser.parse_args(argv)
    rod = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)

    # 1. the paper's table
    paper_chain = fit_chain(rod, 3, match="frequencies", frequencies=PAPER_FREQUENCIES)
    table = criterion(rod.truncated(2, method="free-free"), paper_chain,
                      names=("beam (2 modes)", "chain"))
    paper_rows = []
    for label, unit, ref, cand, diff in table.rows():
        printed = PAPER_TABLE.get(label)
        paper_rows.append({"quantity": label, "unit": unit, "beam_2_modes": ref, "chain": cand,
                           "relative_difference": diff,
                           "paper_beam": printed[0] if printed else None,
                           "paper_chain": printed[1] if printed else None})
    k_L = paper_chain.lengths[1] / paper_chain.length

    # 2. errors against the exact beam
    rows = [errors_row(rod, "paper chain (k_L = 0.26989, c = 37.134)",
                       HingedChain.three_body(10.0, rod.mass, 0.26989, 37.134), "paper")]
    fitted = {}
    for n in range(3, 10):
        chain, seconds = timed(lambda n=n: fit_chain(rod, n), args.repeats)
        fitted[n] = (chain, seconds)
    rows.append(errors_row(rod, "fitted, 3 bodies", fitted[3][0], "fitted", fitted[3][1]))
    for n in range(3, 10):
        rows.append(errors_row(rod, f"RFEM, {n} bodies", HingedChain.rfem(rod, n), "rfem"))
    for n in range(1, 5):
        rows.append(errors_row(rod, f"superelements x{n}", HingedChain.superelements(rod, n),
                               "superelements"))
    for n in range(3, 10):
        chain, seconds = timed(lambda n=n: fit_chain(rod, n, match="frequencies"), args.repeats)
        rows.append(errors_row(rod, f"frequency fit, {n} bodies", chain, "frequencies", seconds))
    for n in range(4, 10):
        rows.append(errors_row(rod, f"fitted, {n} bodies", fitted[n][0], "fitted",
                               fitted[n][1]))

    # 3. the six zeros of the three-body chains
    zero_rows = []
    exact = {r: rod.zeros(r, 2) for r in (1, 2, 4)}
    for name, chain in (("paper chain", HingedChain.three_body(10.0, rod.mass, 0.26989, 37.134)),
                        ("fitted chain", fitted[3][0])):
        entry = {"model": name}
        for r in (1, 2, 4):
            z = chain.zeros(r)[:2]
            for k in range(2):
                entry[f"n{r}{k + 1}"] = float(z[k] / exact[r][k] - 1.0)
        entry["w1"], entry["w2"] = (float(e) for e in chain.poles()[:2]
                                    / rod.natural_frequencies(2) - 1.0)
        zero_rows.append(entry)

    # verdicts
    by_dof = {}
    for row in rows:
        by_dof.setdefault(row["dof"], {}).setdefault(row["kind"], row)
    verdicts = []
    for dof in sorted(by_dof):
        group = by_dof[dof]
        if "fitted" not in group:
            continue
        for other in ("rfem", "superelements", "frequencies"):
            if other in group:
                # the frequency fits match their poles exactly by construction: compare zeros
                keys = ["all", "zeros_first_two", "band_log_error"]
                if other != "frequencies":
                    keys.append("poles_first_two")
                better = all(group["fitted"][key] < group[other][key] for key in keys)
                verdicts.append({"dof": dof, "versus": other, "criteria": keys,
                                 "fitted_better": better})

    # 4. cost of evaluating chains (medians)
    costs = []
    omega = np.geomspace(0.1, 100.0, 2000)
    for n in (3, 10, 50, 200):
        chain = HingedChain.rfem(rod, n)
        _, (w_wall, _) = timed(lambda: chain.W(1j * omega), args.repeats)
        # the condensation takes about a minute at 200 bodies: one run there
        _, (lag_wall, _) = timed(lambda: FiniteAppendage.W(chain, 1j * omega),
                                 args.repeats if n < 200 else 1)
        _, (p_wall, _) = timed(lambda: (chain.poles(), [chain.zeros(r) for r in (1, 2, 4)]),
                               args.repeats)
        lagrangian = FiniteAppendage.W(chain, 1e-6j)[0, 0] * (1e-6j) ** 2
        recursion = chain.W(1e-6j)[0, 0] * (1e-6j) ** 2
        rigid = 1.0 / chain.mass + chain.center_of_mass**2 / chain.inertia
        costs.append({"n_bodies": n, "W_2000_points_s": w_wall,
                      "W_lagrangian_condensation_s": lag_wall, "poles_and_zeros_s": p_wall,
                      "rigid_limit_error_recursion": float(abs(recursion / rigid - 1)),
                      "rigid_limit_error_condensation": float(abs(lagrangian / rigid - 1))})

    fitted3 = fitted[3][0]
    out = {
        "rod": {"length": rod.length, "bending_stiffness": rod.bending_stiffness,
                "linear_density": rod.linear_density, "mass": rod.mass, "inertia": rod.inertia},
        "paper_fit": {"k_L": k_L, "c": float(paper_chain.hinge_stiffnesses[0]),
                      "target_frequencies": PAPER_FREQUENCIES},
        "paper_table": paper_rows,
        "errors_vs_exact_beam": rows,
        "three_body_zero_errors": zero_rows,
        "verdicts": verdicts,
        "evaluation_cost": costs,
        "fitted_three_body_chain": {
            "lengths": fitted3.lengths.tolist(), "masses": fitted3.masses.tolist(),
            "inertias": fitted3.inertias.tolist(), "com_offsets": fitted3.com_offsets.tolist(),
            "hinge_stiffnesses": fitted3.hinge_stiffnesses.tolist()},
        "repeats": args.repeats,
        "date_utc": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M"),
        "load_average_1_5_15min": list(os.getloadavg()),
    }
    RESULTS.mkdir(parents=True, exist_ok=True)
    (RESULTS / "equivalence.json").write_text(json.dumps(out, indent=2))
    markdown = to_markdown(out)
    (RESULTS / "equivalence.md").write_text(markdown)
    print(markdown)
    return out


def _f(value, fmt="{:.5g}"):
    return "n/a" if value is None else fmt.format(value)


def to_markdown(out: dict) -> str:
    lines = ["# Hinged chains equivalent to the paper's rod", "",
             "Generated by `benchmarks/equivalence_tables.py` "
             f"({out['date_utc']} UTC; load average {out['load_average_1_5_15min'][0]:.1f}, "
             "2 cores shared: times are CPU time stretched by the load). Fit times are "
             "cold (memo cleared); `benchmarks/bench_fit.py` measures them in detail.", "",
             "## 1. The paper's table", "",
             f"Paper's fit to its printed frequencies {out['paper_fit']['target_frequencies']} "
             f"1/s: k_L = {out['paper_fit']['k_L']:.6f}, c = {out['paper_fit']['c']:.5f} N*m "
             "(paper: 0.26989, 37.134). The 2-mode beam uses the exact frequencies; the paper's "
             "w2 = 7.9231 is 4.6 units of its last digit below the exact 7.92356 1/s, which "
             "shifts its second zeros by a few units.", "",
             "| quantity | beam, 2 modes | paper | chain | paper |", "|---|---|---|---|---|"]
    for row in out["paper_table"]:
        lines.append(f"| {row['quantity']} [{row['unit']}] | {_f(row['beam_2_modes'])} | "
                     f"{_f(row['paper_beam'])} | {_f(row['chain'])} | {_f(row['paper_chain'])} |")
    lines += ["", "## 2. Pole and zero errors against the exact distributed beam", "",
              "|relative error| (max); DOF = bodies + 1. 'first two': w1, w2, n_r1, n_r2; "
              "'all': every pole and zero the chain has (n - 1 of each); 'band': max over r of "
              "max |ln(W_r^chain / W_r^beam)| on s = omega (0.02 + i), default band.", "",
              "| model | bodies | DOF | poles (first two) | zeros (first two) | all | band | "
              "fit time [s] (wall / CPU) |", "|---|---|---|---|---|---|---|---|"]
    for row in out["errors_vs_exact_beam"]:
        lines.append(f"| {row['model']} | {row['n_bodies']} | {row['dof']} | "
                     f"{row['poles_first_two']:.2e} | {row['zeros_first_two']:.2e} | "
                     f"{row['all']:.2e} | {row['band_log_error']:.3f} | "
                     f"{_f(row['fit_time_s'], '{:.2f}')} / {_f(row['fit_cpu_time_s'], '{:.2f}')} |")
    lines += ["", "## 3. Three-body chains: relative error of each zero and pole vs the exact beam",
              "", "| model | n11 | n12 | n21 = n31 | n22 = n32 | n41 | n42 | w1 | w2 |",
              "|---|---|---|---|---|---|---|---|---|"]
    for row in out["three_body_zero_errors"]:
        lines.append(f"| {row['model']} | " + " | ".join(
            f"{row[k]:+.2e}" for k in ("n11", "n12", "n21", "n22", "n41", "n42", "w1", "w2"))
            + " |")
    lines += ["", "## 4. Verdicts: is the fitted chain better on every criterion listed?", "",
              "| DOF | versus | criteria | fitted better |", "|---|---|---|---|"]
    for v in out["verdicts"]:
        lines.append(f"| {v['dof']} | {v['versus']} | {', '.join(v['criteria'])} | "
                     f"{v['fitted_better']} |")
    lines += ["", "## 5. Cost of a chain's W(s), poles and zeros (median wall time)", "",
              "W at 2000 frequencies by HingedChain.W (tip-to-root recursion) and by the generic "
              "condensation FiniteAppendage.W; rigid-limit error: |s^2 W1 / rigid - 1| at "
              "s = 1e-6j (physical value ~1e-13).", "",
              "| bodies | W, recursion [s] | W, condensation [s] | poles + zeros [s] | "
              "rigid-limit error, recursion | condensation |", "|---|---|---|---|---|---|"]
    for c in out["evaluation_cost"]:
        lines.append(f"| {c['n_bodies']} | {c['W_2000_points_s']:.4f} | "
                     f"{c['W_lagrangian_condensation_s']:.4f} | {c['poles_and_zeros_s']:.4f} | "
                     f"{c['rigid_limit_error_recursion']:.1e} | "
                     f"{c['rigid_limit_error_condensation']:.1e} |")
    fc = out["fitted_three_body_chain"]
    lines += ["", "## Fitted three-body chain", "",
              "| body | length [m] | mass [kg] | inertia [kg*m^2] | com offset [m] |",
              "|---|---|---|---|---|"]
    for k in range(3):
        lines.append(f"| {k + 1} | {fc['lengths'][k]:.5f} | {fc['masses'][k]:.5f} | "
                     f"{fc['inertias'][k]:.5f} | {fc['com_offsets'][k]:.5f} |")
    lines.append(f"\nHinge stiffnesses: {', '.join(f'{c:.4f}' for c in fc['hinge_stiffnesses'])} "
                 "N*m/rad.")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
