"""Independent references for the FMU simulation tests: input tables as fmpy reads them, the
zero-order-hold response by python-control, and the augmented matrix exponential in 40-digit
arithmetic."""
from __future__ import annotations

import control
import mpmath
import numpy as np

__all__ = ["augmented_exponential_mp", "step_table", "zoh_reference"]


def step_table(times, values, name="torque"):
    """fmpy input table for a piecewise-constant signal: values[i] from times[i] on."""
    rows = [(0.0, values[0])]
    for t, before, after in zip(times[1:], values[:-1], values[1:]):
        rows += [(t, before), (t, after)]
    rows.append((1e3, values[-1]))
    return np.array(rows, dtype=[("time", np.float64), (name, np.float64)])


def zoh_reference(system, h, t_end, switch_times, values, x0=None):
    """Outputs of c2d(system, h, zoh) at t_k = k h for the right-continuous steps."""
    t = np.arange(int(round(t_end / h)) + 1) * h
    u = np.array([values[np.searchsorted(switch_times, tk + 1e-12, side="right") - 1] for tk in t])
    response = control.forced_response(control.c2d(system, h, "zoh"), T=t, U=u,
                                       X0=0.0 if x0 is None else x0)
    return t, np.asarray(response.outputs)


def augmented_exponential_mp(system, h, x, u):
    """x(h) = expm([[A, B], [0, 0]] h) [x; u] in 40-digit arithmetic (Van Loan 1978)."""
    A, B = np.asarray(system.A), np.asarray(system.B)
    n = A.shape[0]
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n:] = A * h, B * h
    mpmath.mp.dps = 40
    E = mpmath.expm(mpmath.matrix(M.tolist()))
    z = list(x) + [u]
    return np.array([float(mpmath.fsum(E[i, j] * z[j] for j in range(n + 1))) for i in range(n)])
