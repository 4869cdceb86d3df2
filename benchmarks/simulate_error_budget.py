"""What dominates the modal simulator's error: one ingredient at a time in long double.

Run from the repository root::

    python benchmarks/simulate_error_budget.py            # 20, 100 and 400 states (~2 min)
    python benchmarks/simulate_error_budget.py --quick    # 20 states (~10 s)

On issue 10's general systems (``benchmarks/issue10.py``: lightly damped modes and two free
rigid bodies hidden by a similarity, random inputs linear between samples, dt = 0.01 s), the
output error max |y - y_exact| / range(y_exact) against the extended-precision solution of the
float64 system, for:

- ``forced_response`` and ``flexsat`` (``Simulator(method="modal")``);
- ``recursion in long double``: flexsat's own float64 modal data (transition blocks, input
  and output maps) propagated in long double: what the recursion's round-off adds;
- ``form exact in long double``, variants: the float64 transformation V, everything else
  computed from it in long double (``M = V^-1 A V``, its exponential, ``V^-1 B``, ``C V``)
  and simulated with ``M`` reduced to its diagonal blocks (what a modal method that
  ignores the round-off of V^-1 A V off its blocks can reach), plus the refined blocks'
  rows and columns of M (what flexsat's decoupling Z keeps), and the full M (the float64
  V itself is exact: the extended-precision solution again, computed another way; the two
  differ by their own long-double round-off, which the rigid bodies' drift integrates:
  ~1e-19 N^1.5 ~ 1e-13 of the range over N = 1e4 samples, the floor of this comparison).

The result, on this machine (see the commit that added this script): the recursion, the
discretisation and the maps in float64 add nothing visible (flexsat's modal data run in
long double: the same error); what dominated before the refinement of the rigid bodies'
blocks (``controllers/modal_form.py``) was the Schur form's backward error in the rigid
bodies' block (20 to 200 states) and in its couplings to the other blocks (400 states).
Not a test: it asserts nothing; results print and go to
``results/simulate_error_budget.json``.
"""

from __future__ import annotations

import _common  # noqa: F401  (first: BLAS settings before numpy)

import argparse  # noqa: E402
import sys  # noqa: E402

import control  # noqa: E402
import numpy as np  # noqa: E402
from threadpoolctl import threadpool_limits  # noqa: E402

from _common import machine_info, write_json  # noqa: E402
from issue10 import (exact_response, general_system, long_double_response,  # noqa: E402
                     relative_error)

from controllers.simulate import Simulator  # noqa: E402

LD = np.longdouble


def long_double_inverse(V: np.ndarray) -> np.ndarray:
    """V^-1 in long double: the float64 inverse refined by three Newton steps."""
    V_ld = np.asarray(V, LD)
    X = np.asarray(np.linalg.inv(V), LD)
    eye = np.eye(V.shape[0], dtype=LD)
    for _ in range(3):
        X = X + X @ (eye - V_ld @ X)
    return X


def recursion_in_long_double(modal, U: np.ndarray) -> np.ndarray:
    """Outputs of flexsat's float64 modal data (modal_recursion.ModalRecursion) propagated
    in long double."""
    f00, f01, f10, f11 = (np.asarray(f, LD) for f in modal._f)
    cl_phi = np.asarray(modal._cl_phi, LD)
    G0, G1, HD = (np.asarray(M, LD) for M in (modal._G0, modal._G1, modal._HD))
    nz, pairs = modal._nz, modal.n_pairs
    N, m = U.shape[1], U.shape[0]
    U_rows = np.zeros((N + 1, m), LD)
    U_rows[:N] = U.T
    W = U_rows[:-1] @ G0 + U_rows[1:] @ G1
    Z = np.zeros((N, nz), LD)
    z = np.zeros(nz, LD)
    starts, offsets = modal._cl_starts, modal._cl_offsets
    for k in range(N):
        Z[k] = z
        new = np.empty(nz, LD)
        a, b = z[:pairs], z[pairs:2 * pairs]
        new[:pairs], new[pairs:2 * pairs] = f00 * a + f01 * b, f10 * a + f11 * b
        for c in range(len(starts) - 1):
            i0, i1 = starts[c], starts[c + 1]
            # cl_phi holds Phi - I (see controllers/_modal_kernel.py)
            new[i0:i1] = z[i0:i1] + cl_phi[offsets[c]:offsets[c + 1]].reshape(
                i1 - i0, i1 - i0) @ z[i0:i1]
        z = new + W[k]
    return (np.concatenate([Z, U_rows[:-1]], axis=1) @ HD).T.astype(float)


def budget(n: int, hold: str = "linear") -> dict:
    dt = 0.01
    system = general_system(n)
    N = 10_000 if n <= 100 else 2000           # issue10.py's accuracy window
    U = np.random.default_rng(n).standard_normal((system.ninputs, 100_000))[:, :N]
    T = np.arange(N) * dt
    y_exact, _ = exact_response(system, dt, U, hold)
    fr_system = system if hold == "linear" else control.c2d(system, dt, "zoh")
    simulator = Simulator(system, dt, hold=hold, method="modal")
    errors = {
        "forced_response": relative_error(control.forced_response(fr_system, T, U).y, y_exact),
        "flexsat": relative_error(simulator.outputs(T, U), y_exact),
    }
    modal = simulator._modal
    errors["recursion in long double"] = relative_error(recursion_in_long_double(modal, U),
                                                        y_exact)
    form = modal.form
    V = np.asarray(form.V, LD)
    V_inv = long_double_inverse(form.V)
    M = V_inv @ np.asarray(system.A, LD) @ V
    Bz, H = V_inv @ np.asarray(system.B, LD), np.asarray(system.C, LD) @ V
    m = Bz.shape[1]
    blocks = np.zeros((n, n), bool)
    for a, b in zip(form.starts[:-1], form.starts[1:]):
        blocks[a:b, a:b] = True
    refined = np.zeros(n, bool)
    refined[form.coupled] = True
    for name, mask in (("form exact in long double, blocks only", blocks),
                       ("form exact in long double, blocks and refined rows, columns",
                        blocks | refined[:, None] | refined[None, :]),
                       ("form exact in long double, full", np.ones((n, n), bool))):
        y, _ = long_double_response(np.where(mask, M, 0), Bz, H, np.zeros((H.shape[0], m)),
                                    dt, U, hold)
        errors[name] = relative_error(y, y_exact)
    return {"n": n, "hold": hold, "samples": N, "refined_states": int(refined.sum()),
            "condition": form.condition, "errors": errors}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="20 states only")
    args = parser.parse_args(argv)
    rows = []
    with threadpool_limits(limits=1, user_api="blas"):
        for n in (20,) if args.quick else (20, 100, 400):
            row = budget(n)
            rows.append(row)
            print(f"n = {n} ({row['samples']} samples, cond V {row['condition']:.0f}, "
                  f"{row['refined_states']} refined states):")
            for name, value in row["errors"].items():
                print(f"    {name:60s} {value:.1e}", flush=True)
    write_json("simulate_error_budget.json", {"machine": machine_info(), "rows": rows,
                                              "quick": args.quick})
    return 0


if __name__ == "__main__":
    sys.exit(main())
