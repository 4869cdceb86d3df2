"""Exact discretisation of continuous-time LTI blocks (zero- and first-order hold).

``x' = A x + B u`` sampled every ``dt`` with the input held constant (zero-order hold) or
linear between samples (first-order hold) is, exactly,
``x[k+1] = Ad x[k] + Bd0 u[k] + Bd1 u[k+1]`` (``Bd1 = 0`` for the zero-order hold), with the
three matrices read off one matrix exponential of a Van Loan block matrix [1]_.  The same
block matrix is behind :func:`control.forced_response` and :func:`scipy.signal.lsim`, so the
first-order hold here is their input interpretation.

References
----------
.. [1] C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE Trans.
   Automatic Control 23(3), 395-404, 1978.
.. [2] G. F. Franklin, J. D. Powell, M. L. Workman, *Digital Control of Dynamic Systems*,
   3rd ed., Addison-Wesley, 1998, sec. 6.3 (zero- and first-order hold equivalents).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import scipy.linalg

from .arguments import user_stacklevel
from .frequency import decoupled_parts

__all__ = ["DiscretisationOverflowWarning", "discretise", "discretise_blocks", "expm_2x2"]


class DiscretisationOverflowWarning(UserWarning):
    """The exact discrete matrices of one step leave the float64 range: the system grows by
    more than ~1e308 within one step dt (a simulation on that grid diverges at its first
    step; the matrices hold inf or NaN)."""

def discretise(A, B, dt, hold):
    """Exact discrete matrices, block by block of A (see discretise_blocks).

    When A is block diagonal up to a permutation (decoupled modes in modal
    coordinates, a free rigid body), its exponential and the input
    integrals are computed per block: mathematically the same matrices,
    with smaller norms (fewer scaling-and-squaring steps in expm) and exact
    zeros between blocks; an undamped 2 x 2 block's exponential is the
    closed form.  This matters for long undamped runs: expm of the whole
    A dt of a plant with a 71 rad/s mode at dt = 1 s misses |lambda| = 1 by
    6e-14 per step (energy drift 2e-9 in 1e5 steps; expm of the 2 x 2 block
    alone as well), the closed form by ~1e-16.
    """
    n, m = B.shape
    if n <= 2:
        labels = np.zeros(n, dtype=int)
    else:
        labels = decoupled_parts(A != 0.0)[1]
    # Blocks of equal size go through one stacked expm call (a modal plant
    # has dozens of 2 x 2 blocks; one BLAS-heavy call each would add up).
    by_size: dict[int, list] = {}
    for block in range(labels.max(initial=-1) + 1):
        i = np.flatnonzero(labels == block)
        by_size.setdefault(i.size, []).append(i)
    Ad, Bd0, Bd1 = np.zeros((n, n)), np.zeros((n, m)), np.zeros((n, m))
    for size, blocks in by_size.items():
        idx = np.array(blocks)                                  # (K, size)
        rows, cols = idx[:, :, None], idx[:, None, :]
        Ad[rows, cols], Bd0[idx], Bd1[idx] = discretise_blocks(
            A[rows, cols], B[idx], dt, hold)
    return Ad, Bd0, Bd1


def expm_2x2(M):
    """expm of a real 2 x 2 matrix in closed form.

    With M = mu I + N, mu = tr(M)/2, N traceless: N^2 = q2 I with
    q2 = N00^2 + N01 N10, so expm(M) = e^mu (cosh(q) I + sinh(q)/q N),
    q = sqrt(q2); for q2 < 0, cos(w) and sin(w)/w with w = sqrt(-q2):
    the determinant is e^(2 mu) (cos^2 + sin^2) to round-off, whatever w.
    """
    mu = 0.5 * (M[0, 0] + M[1, 1])
    N = M - mu * np.eye(2)
    q2 = N[0, 0] ** 2 + N[0, 1] * N[1, 0]
    if q2 < 0.0:
        w = np.sqrt(-q2)
        c, s = np.cos(w), np.sin(w) / w
        return np.exp(mu) * (c * np.eye(2) + s * N)
    q = np.sqrt(q2)
    if q < 1e-4:
        # Series: cosh q = 1 + q2/2 + q2^2/24, sinh(q)/q = 1 + q2/6 + q2^2/120.
        c = 1.0 + q2 / 2.0 + q2 * q2 / 24.0
        s = 1.0 + q2 / 6.0 + q2 * q2 / 120.0
        return np.exp(mu) * (c * np.eye(2) + s * N)
    # e^mu cosh q and e^mu sinh q from e^(mu +- q): no overflow of cosh
    # for stiff blocks whose e^mu underflows.
    ep, em = np.exp(mu + q), np.exp(mu - q)
    return 0.5 * (ep + em) * np.eye(2) + (0.5 * (ep - em) / q) * N


def discretise_blocks(A, B, dt, hold):
    """Exact discrete matrices from ONE matrix exponential (Van Loan), for
    a stack of blocks A (K, n, n), B (K, n, m) at once.

    Zero-order hold (u constant on [0, dt]): the augmented state [x; u]
    obeys d/dt [x; u] = [[A, B], [0, 0]] [x; u], hence

        expm([[A dt, B dt], [0, 0]]) = [[Ad, Bd], [0, I]],
        Ad = e^{A dt},  Bd = int_0^dt e^{A s} ds B,
        x[k+1] = Ad x[k] + Bd u[k].

    First-order hold (u(t) = u0 + (u1 - u0) t/dt on [0, dt]): with the
    step's input change v = u1 - u0 (constant) the state [x; u; v] obeys
    dx/dt = A x + B u,  du/dt = v / dt,  dv/dt = 0;  in the scaled time
    t/dt the generator is [[A dt, B dt, 0], [0, 0, I], [0, 0, 0]], so

        expm([[A dt, B dt, 0], [0, 0, I], [0, 0, 0]])
            = [[Ad, G1, G2], [0, I, I], [0, 0, I]],
        x(dt) = Ad x0 + G1 u0 + G2 (u1 - u0)
              = Ad x0 + (G1 - G2) u0 + G2 u1,
        G1 = int_0^dt e^{A s} ds B,
        G2 = int_0^dt e^{A (dt - s)} (s / dt) ds B.

    This is the block matrix of control.forced_response and
    scipy.signal.lsim (the same Ad, Bd0 = G1 - G2 and Bd1 = G2 up to
    round-off).  A 1 x 1 A, or a 2 x 2 A with zero trace, takes Ad from the
    closed form (exp, expm_2x2), which keeps |lambda| exact.
    """
    with np.errstate(over="ignore", invalid="ignore"):
        # an unstable block can grow beyond float64 within one step: numpy's warnings from
        # expm's squarings are replaced by one of ours (below)
        Ad, Bd0, Bd1 = _exact_blocks(A, B, dt, hold)
    if not (np.isfinite(Ad).all() and np.isfinite(Bd0).all() and np.isfinite(Bd1).all()):
        with np.errstate(all="ignore"):
            lam = np.linalg.eigvals(np.where(np.isfinite(A), A, 0.0)) if A.size else A
        growth = float(np.max(lam.real, initial=0.0))
        warnings.warn(
            f"exact discretisation: the transition matrix e^(A dt) over one step dt = {dt:.3g} "
            f"s leaves the float64 range (growth rate max Re(lambda) = {growth:.3g} 1/s, "
            f"e^({growth * dt:.3g}) per step, above e^{math.log(np.finfo(float).max):.1f}); a "
            "simulation on this grid diverges at its first step: shorten dt to follow the "
            "growth", DiscretisationOverflowWarning, stacklevel=user_stacklevel())
    return Ad, Bd0, Bd1


def _exact_blocks(A, B, dt, hold):
    """The matrices of discretise_blocks (its docstring), without the overflow check."""
    K, n, m = B.shape                  # a stack of K blocks
    if hold == "zero":
        M = np.zeros((K, n + m, n + m))
        M[:, :n, :n] = A * dt
        M[:, :n, n:] = B * dt
        E = scipy.linalg.expm(M)
        Ad, Bd0, Bd1 = E[:, :n, :n], E[:, :n, n:], np.zeros((K, n, m))
    else:
        M = np.zeros((K, n + 2 * m, n + 2 * m))
        M[:, :n, :n] = A * dt
        M[:, :n, n:n + m] = B * dt
        M[:, n:n + m, n + m:] = np.identity(m)
        E = scipy.linalg.expm(M)
        Ad = E[:, :n, :n]
        Bd1 = E[:, :n, n + m:]
        Bd0 = E[:, :n, n:n + m] - Bd1
    if n == 1:
        Ad = np.exp(A * dt)
    elif n == 2:
        for k in np.flatnonzero(A[:, 0, 0] + A[:, 1, 1] == 0.0):
            # Undamped oscillator or free rigid body (det Ad = 1 exactly):
            # the closed form keeps |lambda| = 1 to round-off, where expm's
            # scaling and squaring of a large-norm block does not.  Damped
            # blocks keep expm's result, measured the more accurate there.
            Ad[k] = expm_2x2(A[k] * dt)
    return Ad, Bd0, Bd1
