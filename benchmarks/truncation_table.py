"""Convergence of the beam's modal truncations to the exact distributed beam (issue 2).

For each reduction method of :meth:`appendages.Beam.truncated` ("free-free", the paper's;
"residual"; "craig-bampton") and n_modes = 1..64, the relative errors against the exact beam of

- the first two zeros of W1, W2 (= W3) and W4 (exact: pinned-free, x = k pi and sliding-free
  roots, :meth:`Beam.zeros`),
- the first two free-free poles (exact: roots of cos x cosh x = 1),
- the first two coupled natural frequencies of the default hub (100 kg, 50 kg*m^2) carrying the
  beam at (0.5, 0) m (exact: roots of the coupled characteristic equation through the exact W,
  ``Spacecraft.natural_frequencies(n, exact=True)``).

The aim of issue 2: every zero within 1e-3 with 10 modes or fewer. The summary reports, per
method, the smallest n_modes from which every quantity of a group stays below 1e-3 (and 1e-6)
up to n_modes = 64.

Run::

    python benchmarks/truncation_table.py            # n_modes = 1..64
    python benchmarks/truncation_table.py --quick    # n_modes = 1..16

Writes benchmarks/results/truncation.json and truncation.md.
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import argparse
import sys
import time

import numpy as np

from _common import (fmt, machine_info, markdown_table, paper_rod, spacecraft_with,
                     write_json, RESULTS)

METHODS = ("free-free", "residual", "craig-bampton")
ZERO_KEYS = ("W1_zero1", "W1_zero2", "W2_zero1", "W2_zero2", "W4_zero1", "W4_zero2")
POLE_KEYS = ("pole1", "pole2")
COUPLED_KEYS = ("coupled1", "coupled2")
THRESHOLDS = (1e-3, 1e-6)


def _relative(values: np.ndarray, exact: np.ndarray) -> list:
    """|value/exact - 1| for each exact entry; None where the model has too few values."""
    out = []
    for k, reference in enumerate(exact):
        out.append(abs(values[k] / reference - 1.0) if k < values.size else None)
    return out


def exact_reference(beam) -> dict:
    """Exact zeros, poles and coupled frequencies [rad/s]."""
    return {
        "zeros": {r: beam.zeros(r, 2) for r in (1, 2, 4)},
        "poles": beam.natural_frequencies(2),
        "coupled": spacecraft_with(beam).natural_frequencies(2, exact=True),
    }


def errors_of(beam, n_modes: int, method: str, reference: dict) -> dict:
    """Relative errors of one truncation (None where the model lacks the quantity)."""
    model = beam.truncated(n_modes, method=method)
    row: dict = {}
    for r in (1, 2, 4):
        e = _relative(model.zeros(r), reference["zeros"][r])
        row[f"W{r}_zero1"], row[f"W{r}_zero2"] = e
    row["pole1"], row["pole2"] = _relative(model.poles(), reference["poles"])
    craft = spacecraft_with(model)
    n_elastic = craft.modes()[0].size - 3
    coupled = craft.natural_frequencies(min(2, n_elastic), exact=False)
    row["coupled1"], row["coupled2"] = _relative(coupled, reference["coupled"])
    return row


def first_sustained(rows: list[dict], keys, threshold: float):
    """Smallest n_modes from which every ``keys`` error stays below ``threshold`` (or None)."""
    best = None
    for row in reversed(rows):
        values = [row[k] for k in keys]
        if any(v is None or not v < threshold for v in values):
            break
        best = row["n_modes"]
    return best


def run(n_max: int) -> dict:
    beam = paper_rod()
    reference = exact_reference(beam)
    table: dict = {}
    t0 = time.perf_counter()
    for method in METHODS:
        rows = []
        for n in range(1, n_max + 1):
            row = {"n_modes": n}
            row.update(errors_of(beam, n, method, reference))
            rows.append(row)
        table[method] = rows
    summary = {}
    for method, rows in table.items():
        summary[method] = {
            f"{group}<{threshold:g}": first_sustained(rows, keys, threshold)
            for group, keys in (("zeros", ZERO_KEYS), ("poles", POLE_KEYS),
                                ("coupled", COUPLED_KEYS))
            for threshold in THRESHOLDS
        }
    return {
        "machine": machine_info(),
        "beam": repr(beam),
        "hub": {"mass": 100.0, "inertia": 50.0, "mount_position": [0.5, 0.0]},
        "exact": {
            "zeros_rad_s": {f"W{r}": reference["zeros"][r] for r in (1, 2, 4)},
            "poles_rad_s": reference["poles"],
            "coupled_rad_s": reference["coupled"],
        },
        "n_max": n_max,
        "seconds": time.perf_counter() - t0,
        "summary": summary,
        "errors": table,
    }


SHOWN_N = (1, 2, 3, 4, 5, 6, 8, 10, 12, 16, 24, 32, 48, 64)


def markdown(result: dict) -> str:
    lines = [
        "# Convergence of the beam truncations to the exact beam",
        "",
        f"Produced by `python benchmarks/truncation_table.py` on {result['machine']['date_utc']} "
        f"UTC ({result['machine']['cpu']}, {result['machine']['nproc']} cores). Beam: "
        f"{result['beam']}; coupled frequencies with Hub(100 kg, 50 kg*m^2), mount at "
        "(0.5, 0) m. Relative errors |model/exact - 1|; '-' where the model has fewer "
        "zeros/poles than asked.",
        "",
        "Exact values [rad/s]: " + "; ".join(
            f"{k} {', '.join(f'{v:.8g}' for v in vals)}"
            for k, vals in list(result["exact"]["zeros_rad_s"].items())
            + [("poles", result["exact"]["poles_rad_s"]),
               ("coupled", result["exact"]["coupled_rad_s"])]),
        "",
        "## Summary: smallest n_modes from which every error of the group stays below the "
        "threshold (up to n_modes = %d)" % result["n_max"],
        "",
    ]
    header = ["method"] + list(next(iter(result["summary"].values())).keys())
    rows = [[m] + [("-" if v is None else v) for v in s.values()]
            for m, s in result["summary"].items()]
    lines += [markdown_table(header, rows), ""]
    aim = [m for m, s in result["summary"].items()
           if s["zeros<0.001"] is not None and s["zeros<0.001"] <= 10]
    lines += [f"Issue 2's aim (every zero within 1e-3 with 10 modes or fewer) is met by: "
              f"{', '.join(aim) if aim else 'no method'}.", ""]
    keys = ZERO_KEYS + POLE_KEYS + COUPLED_KEYS
    for method, rows_m in result["errors"].items():
        lines += [f"## {method}", ""]
        body = [[row["n_modes"]] + [fmt(row[k], 1) for k in keys]
                for row in rows_m if row["n_modes"] in SHOWN_N]
        lines += [markdown_table(["n_modes"] + list(keys), body), ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="n_modes = 1..16 only")
    args = parser.parse_args(argv)
    result = run(16 if args.quick else 64)
    suffix = "_quick" if args.quick else ""
    write_json(f"truncation{suffix}.json", result)
    text = markdown(result)
    (RESULTS / f"truncation{suffix}.md").write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
