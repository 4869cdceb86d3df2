"""Data of the model-selection rule :func:`appendages.selection.cheapest_model`.

For every model family and size, the relative errors of the first two free-free poles and of
the first two zeros of W1, W2 (= W3) and W4 against the exact uniform beam. For a uniform free
beam these errors are dimensionless and the same for every length, stiffness and density
(all frequencies scale with sqrt(EJ/(rho*A L**4))), so one table serves every uniform beam.

For each tolerance of a grid (10**(-k/2), k = 2..20) and each family, the smallest size from
which the error stays below the tolerance up to the largest size measured; written to
benchmarks/results/selection_table.json and printed as the Python literal that
appendages/selection.py ships (regenerate it there when the models change).

Run::

    python benchmarks/selection_table.py [--fitted]
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import argparse
import math
import pprint
import sys
import warnings

import numpy as np

from _common import machine_info, paper_rod, write_json

from appendages.chain import HingedChain

GRID = [10.0 ** (-k / 2.0) for k in range(2, 21)]
SIZES = {
    "craig-bampton": range(1, 65),
    "residual": range(1, 65),
    "free-free": range(1, 65),
    "rfem": range(2, 65),
    "superelements": range(1, 33),
    "fitted": range(2, 5),
}


def _max_relative(values, exact) -> float:
    if values.size < exact.size:
        return math.inf
    return float(np.max(np.abs(values[: exact.size] / exact - 1.0)))


def build(family: str, beam, size: int):
    if family in ("craig-bampton", "residual", "free-free"):
        return beam.truncated(size, method=family)
    if family == "rfem":
        return HingedChain.rfem(beam, size)
    if family == "superelements":
        return HingedChain.superelements(beam, size)
    if family == "fitted":
        from appendages.equivalence import fit_chain

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return fit_chain(beam, size)
    raise ValueError(family)


def measure(families) -> dict:
    beam = paper_rod()
    poles = beam.natural_frequencies(2)
    zeros = {r: beam.zeros(r, 2) for r in (1, 2, 4)}
    rows = {}
    for family in families:
        rows[family] = []
        for size in SIZES[family]:
            try:
                model = build(family, beam, size)
            except Exception as exc:  # a fit that fails: recorded, not selected
                print(f"{family} {size}: {type(exc).__name__}: {exc}", file=sys.stderr)
                continue
            e_p = _max_relative(model.poles(), poles)
            e_z = max(_max_relative(model.zeros(r), zeros[r]) for r in (1, 2, 4))
            # dynamic degrees of freedom: half the states (massless coordinates condensed)
            rows[family].append({"size": size, "n_dof": model.state_space().nstates // 2,
                                 "poles": e_p, "zeros": e_z})
    return rows


def thresholds(rows: dict) -> dict:
    """{quantity: {family: [(tolerance, size, n_dof) or None per grid tolerance]}}."""
    out = {}
    for quantity in ("poles", "zeros", "poles-and-zeros"):
        out[quantity] = {}
        for family, entries in rows.items():
            picks = []
            for tol in GRID:
                best = None
                for entry in reversed(entries):
                    error = (max(entry["poles"], entry["zeros"]) if quantity == "poles-and-zeros"
                             else entry[quantity])
                    if not error < tol:
                        break
                    best = entry
                picks.append(None if best is None else (best["size"], best["n_dof"]))
            out[quantity][family] = picks
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fitted", action="store_true", help="include fit_chain (slow)")
    args = parser.parse_args(argv)
    families = [f for f in SIZES if f != "fitted" or args.fitted]
    rows = measure(families)
    table = thresholds(rows)
    write_json("selection_table.json", {"machine": machine_info(), "grid": GRID,
                                        "thresholds": table, "errors": rows})
    print("TOLERANCE_GRID = " + pprint.pformat([float(f"{t:.6g}") for t in GRID], compact=True))
    print("SMALLEST_SIZE = " + pprint.pformat(table, compact=True, width=99))
    return 0


if __name__ == "__main__":
    sys.exit(main())
