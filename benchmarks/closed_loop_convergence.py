"""Convergence of the closed-loop slew of hub + truncated beam as modes are added (issue 3).

Default hub (100 kg, 50 kg*m^2) with the paper's rod at (0.5, 0) m along +x; PD designed on the
plant (natural frequency 0.1 rad/s, damping 0.7); cycloidal slew of 10 deg in 60 s; 200 s
sampled at 10 Hz, exact simulation (controllers.simulate). For each truncation method and
n_modes = 1..N, the peak errors against the reference (Craig-Bampton, 64 modes):

- theta: max |theta - theta_ref| / slew angle,
- tip: max |tip deflection - reference| / max |reference tip deflection|,
- torque: max |torque - reference| / max |reference torque|.

The reference's own convergence is checked against 48 modes Craig-Bampton and 64 modes
residual (written to the results). The summary gives, per method, the smallest n_modes from
which the peak error stays below 1e-3 (and 1e-6) up to N.

Run::

    python benchmarks/closed_loop_convergence.py           # n_modes = 1..40
    python benchmarks/closed_loop_convergence.py --quick   # n_modes = 1..12

Writes benchmarks/results/closed_loop_convergence.json and .md.
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import argparse
import sys
import time

from _common import (RESULTS, fmt, machine_info, markdown_table, paper_rod, pd_closed_loop,
                     slew_errors, slew_response, write_json)

METHODS = ("free-free", "residual", "craig-bampton")
N_REF = 64
SIGNALS = ("theta", "tip", "torque")
THRESHOLDS = (1e-3, 1e-6)


def first_sustained(rows, key, threshold):
    best = None
    for row in reversed(rows):
        if not row[key] < threshold:
            break
        best = row["n_modes"]
    return best


def run(n_max: int) -> dict:
    beam = paper_rod()
    t0 = time.perf_counter()
    reference = slew_response(pd_closed_loop(beam.truncated(N_REF))[2])
    checks = {
        "craig-bampton 48": slew_errors(slew_response(pd_closed_loop(beam.truncated(48))[2]),
                                        reference),
        "residual 64": slew_errors(slew_response(pd_closed_loop(
            beam.truncated(64, method="residual"))[2]), reference),
    }
    table = {}
    for method in METHODS:
        rows = []
        for n in range(1, n_max + 1):
            response = slew_response(pd_closed_loop(beam.truncated(n, method=method))[2])
            rows.append({"n_modes": n, **slew_errors(response, reference)})
        table[method] = rows
    summary = {m: {f"{s}<{t:g}": first_sustained(rows, s, t) for s in SIGNALS for t in THRESHOLDS}
               for m, rows in table.items()}
    return {"machine": machine_info(), "n_max": n_max,
            "reference": f"hub + Beam.truncated({N_REF}, method='craig-bampton')",
            "reference_checks": checks,
            "reference_peaks": {"theta_rad": float(abs(reference["theta"]).max()),
                                "tip_m": float(abs(reference["tip"]).max()),
                                "torque_Nm": float(abs(reference["torque"]).max())},
            "summary": summary, "errors": table, "seconds": time.perf_counter() - t0}


def markdown(result: dict) -> str:
    m = result["machine"]
    lines = [
        "# Closed-loop slew convergence with n_modes",
        "",
        f"`python benchmarks/closed_loop_convergence.py` on {m['date_utc']} UTC ({m['cpu']}, "
        f"{m['nproc']} cores). Default hub, PD 0.1 rad/s / 0.7, 10 deg in 60 s, 200 s at 10 Hz. "
        f"Reference: {result['reference']}; its own differences: " + "; ".join(
            f"{k}: " + ", ".join(f"{s} {fmt(v)}" for s, v in c.items())
            for k, c in result["reference_checks"].items()) + ". Reference peaks: " + ", ".join(
            f"{k} {v:.4g}" for k, v in result["reference_peaks"].items()) + ".",
        "",
        f"## Smallest n_modes from which the peak error stays below the threshold "
        f"(n_modes <= {result['n_max']})",
        "",
    ]
    header = ["method"] + list(next(iter(result["summary"].values())).keys())
    lines += [markdown_table(header, [[k] + ["-" if v is None else v for v in s.values()]
                                      for k, s in result["summary"].items()]), ""]
    shown = [n for n in (1, 2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 24, 32, 40, 48, 64)
             if n <= result["n_max"]]
    header = ["n_modes"] + [f"{meth} {s}" for meth in result["errors"] for s in SIGNALS]
    body = []
    for n in shown:
        row = [n]
        for meth, rows in result["errors"].items():
            row += [fmt(rows[n - 1][s], 1) for s in SIGNALS]
        body.append(row)
    lines += ["## Peak errors (relative)", "", markdown_table(header, body), ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="n_modes = 1..12")
    args = parser.parse_args(argv)
    result = run(12 if args.quick else 40)
    suffix = "_quick" if args.quick else ""
    write_json(f"closed_loop_convergence{suffix}.json", result)
    text = markdown(result)
    (RESULTS / f"closed_loop_convergence{suffix}.md").write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
