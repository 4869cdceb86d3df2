r"""Hinged chains fitted to a uniform beam: the dimensionless problem, its exact Jacobian, a memo.

:func:`appendages.equivalence.fit_chain` validates its arguments and scales; this module does
the work.

Scale invariance
----------------
A uniform beam is fixed by its length L, bending stiffness EJ and linear density rho; each of its
natural frequencies and zeros is ``x**2 s0`` with ``s0 = sqrt(EJ/(rho L**4))`` and x a root of a
dimensionless characteristic equation (Blevins [2]_; :func:`~appendages.beam.characteristic_roots`).
A chain with lengths ``l_i = L l'_i``, centre-of-mass offsets ``a_i = L a'_i``, masses
``m_i = rho L m'_i``, inertias ``J_i = rho L**3 J'_i`` and hinge stiffnesses ``c_h = (EJ/L) c'_h``
has, in the coordinates ``(delta/L, theta_1, ..., theta_n)``, the mass matrix ``rho L**3 M'`` and
the stiffness matrix ``(EJ/L) K'`` (the kinetic energy is quadratic in ``y_i = L y'_i`` and the
angles are dimensionless), so every pole and zero is ``s0`` times the primed chain's. The fit's
residuals are log-frequency *ratios*, in which s0 cancels: the least-squares problem, hence the
fitted chain in primed form, depends only on the number of bodies and the fit's options, never on
the beam's size or material. It is solved once for ``L = EJ = rho = 1`` (targets ``x**2``
exactly), kept in an in-process memo, and scaled to each beam (one multiplication per value:
2 ulp). Hinge dampings ``2 zeta c_h / w_1`` (stiffness-proportional, damping ratio zeta at the
first mode, as :meth:`HingedChain.rfem <appendages.chain.HingedChain.rfem>`) scale with
``(EJ/L)/s0`` and are added after scaling.

Jacobian
--------
Every pole and zero is ``sqrt(lambda)`` of a small pencil ``(K - lambda M) v = 0`` of the chain's
matrices (:mod:`appendages.chain`, eq. (1), (2)): the free chain (poles), the chain with
``delta = 0`` (zeros of W1) or ``phi = 0`` (zeros of W4), symmetric definite, and for W2 = W3
the square minor of ``K - lambda M`` without the rotation equation and the translation
coordinate (a vector v with ``v_delta = 0`` that satisfies every equation but the moment's:
the transmission zeros of moment to translation), not symmetric. For a simple eigenvalue with
right vector v and left vector u (u = v for the symmetric ones) the first-order perturbation is

    d lambda = u^T (dK - lambda dM) v / (u^T M v),                                       (1)

and both forms are sums over bodies and hinges (:mod:`appendages.chain`, eq. (1)):
``u^T M v = sum_i m_i y_i(u) y_i(v) + J_i theta_i(u) theta_i(v)`` with
``y_i(v) = v_delta + sum_(j<i) l_j theta_j(v) + a_i theta_i(v)`` the motion of body i's centre of
mass, and ``u^T K v = sum_h c_h dtheta_h(u) dtheta_h(v)``. Their derivatives with respect to
m_i, J_i, a_i, l_j and c_h are products of these (:func:`_log_frequency_derivatives`); with the
exact derivative of the parametrisation (:class:`_Layout`) the least-squares Jacobian costs one
set of vectors, against 5 n - 5 more residual evaluations by finite differences, and is exact to
round-off. Eq. (1) needs simple eigenvalues: the targets of one kind are at least 15 % apart
(the ratio of consecutive beam roots squared), and so are the chains' near them.

The optimisation
----------------
A chain's W(s) is its rigid part (fixed by m, J and the centre of mass) plus one rank-one term
per mode: n - 1 frequencies and n - 1 root participation vectors of 2 entries, 3 (n - 1)
numbers, on which every pole and zero depends. The 5 n - 5 layout parameters therefore move the
4 (n - 1) residuals in only 3 (n - 1) directions: the Jacobian has exactly 2 n - 2 zero singular
values (measured: 1e-16 of the largest), a family of chains with the same W lies behind every
fit, and which member is returned depends on the path. A *path* of
:func:`fit_poles_and_zeros` goes from a start in two stages (measured on 3 to 14 bodies,
benchmarks/results/fit.md):

1. all targets weighted equally, tolerance 1e-5, the parameters scaled by the Jacobian's column
   norms, either updated at every iteration (``x_scale="jac"``) or those of the start held
   fixed (another way through the valley);
2. the poles weighted, unscaled parameters (``x_scale=1``), tolerance 1e-8 or 5 evaluations per
   parameter: column scaling zigzags in the rank-deficient valley (three bodies: 140 iterations
   against 13) and beyond six bodies every method creeps along it; the budget ends the creep
   (5 more evaluations per parameter would lower the cost by 0.01 % at 10 bodies).

How far a path's chain lies above the lowest cost that a least-squares fit over the 3 (n - 1)
modal numbers themselves finds (a well-conditioned problem: the *bound*) depends on its start
and scaling. From the RFEM chain (end rods H/2) with updated scaling, up to six bodies end at
the bound (the same cost to 6 digits), from 7 bodies on 2 %, 5.6 %,
11 % above it at 7, 8, 9 bodies and 42 % at 12; with the start's norms fixed, 12 bodies end at
the bound, 7 to 9 not. From the chain of n equal bodies with the start's norms fixed, 7, 8 and
9 bodies end at the bound (within 0.02 %), and every n from 3 to 14 within 0.07 % of it.

The work schedule
-----------------
Issue 10 asks for a cost that grows with the number of bodies. A path ends where its tolerances
say, and the paths' lengths are not monotonic in n (the first path: 203 evaluations at 6
bodies, 126 and 121 at 7 and 8), so a fit of a fixed set of paths is not either (measured
before this schedule: 0.31 s CPU at 7 bodies, 0.22 s at 8). Instead every fit spends a fixed
budget, :func:`evaluation_budget`: 3 n evaluations per parameter, 3 n (5 n - 5) in all (90 at 3
bodies, 1350 at 10, 2730 at 14), growing by a factor (n + 1)/(n - 1) >= 1.17 per body while
the cost of one evaluation grows too. The budget is spent on paths in a fixed order
(:func:`_paths`): the RFEM chain updated, the equal chain fixed, the RFEM chain fixed, the
equal chain updated, then uniform chains with end rods between H/2 and H; the path that the
budget reaches last is cut short at it. Its chain competes like the others: Levenberg-Marquardt
and TRF never increase the cost along their iterates, so a cut path returns the best point it
reached. The chain of lowest cost is kept; a later path must lower the cost by more than 1e-5
(relative) to replace it: where several paths end near the bound (their costs 2e-6 to 6e-4
apart), smaller differences count as ties and the earlier chain stays (6 bodies: the second
path was 2e-6 lower). The chains of 3 to 6, 10 and 11 bodies are those of the fit before this
schedule, bit for bit.

Measured on 3 to 14 bodies (benchmarks/results/fit.md): the first path always ends within the
budget (at least 70 % to spare: 53 of 90 evaluations at 3 bodies), and the path whose chain is
kept ends with 19 % (10 bodies) to 220 % to spare, except at 13 bodies, where the cut fourth
path's chain is 0.02 % lower than the first's. Every fit ends within 0.02 % of the bound (the
cost at 7, 8, 9 bodies 1.9 %, 5.3 %, 9.9 % lower than before; the largest error of any pole or
zero there 3 %, 7 %, 13 % higher: the fit spreads its errors evenly over the modes, as it does
from 10 bodies on); the cold CPU time grows by 20 % or more per body (3 bodies 0.04 s, 10
bodies 0.95 s, 14 bodies 2.5 s, single-threaded BLAS at load 1.6 to 2.3). If the budget
(``max_nfev``) cuts the first path short, the fit says so (``stopped``, and
:func:`~appendages.equivalence.fit_chain` warns). The result is deterministic: the same chain
for every beam and every BLAS thread count.

Beyond the ``fit_bodies`` limit of :mod:`appendages.limits` (14): before this schedule the RFEM
paths ended in poor basins at 15 and 16 bodies (4.9 and 390 times the bound); with it both end
within 0.02 % of the bound, at about 3 and 4 s of CPU (the limit is not this module's).

Measured and rejected: a warm start from the (n - 1)-body fit (one body split in two: it reached
the bound at 7 and 8 bodies, then poor basins from 9 on); a homotopy of the targets from the
RFEM chain's own frequencies (no better, slower); a single pole-weighted stage (poor basins from
9 bodies); fitting the 3 (n - 1) modal numbers first and then a chain that realises them (no
chain found for 7 to 9 and 11 bodies: the bound is not reached by the chains near the path); a
small Tikhonov term on the null directions (no fewer iterations, a higher cost). For the
budget: continuing stage 2 to the end of the budget with its tolerances off (once converged
the trust region shrinks to zero: overflow and division by zero inside the solver), restarting
stage 2 until the budget ends (hundreds of restarts that change nothing at the bodies already
at the bound), and starts perturbed at random from the RFEM chain (standard deviation 0.1 in
every parameter: none below the first two paths, most in poor basins, up to 4e4 times the
bound).

References
----------
.. [1] P. A. Belonozhko, P. P. Belonozhko, A. A. Fokov et al., "On the equivalence of mechanical
   design schemes with distributed and lumped parameters for spatially developed peripheral
   elements of spacecraft", 2009 (the fit's criterion).
.. [2] R. D. Blevins, "Formulas for Natural Frequency and Mode Shape", Van Nostrand, 1979,
   table 8-1 (the exact targets).
.. [3] J. H. Wilkinson, "The Algebraic Eigenvalue Problem", Oxford, 1965, ch. 2 (first-order
   perturbation of a simple eigenvalue, eq. (1)).
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import math
import threading
import warnings

import numpy as np
import scipy.linalg
import scipy.optimize

from .beam import characteristic_roots
from .chain import HingedChain, chain_matrices, proportional_hinge_dampings
from .errors import ConvergenceError

__all__ = ["DimensionlessChain", "FitWarning", "clear_memo", "evaluation_budget",
           "fit_frequencies", "fit_plane_on_layout", "fit_poles_and_zeros",
           "fit_poles_and_zeros_to"]

#: Changes whenever a change of the algorithm may change a fitted chain (part of the memo key).
FIT_VERSION = 4

# Stage 1 (equal weights): x_scale per path, tolerance 1e-5. Stage 2 (poles weighted): x_scale=1,
# tolerance 1e-8, at most 5 evaluations per parameter (module docstring, "The optimisation").
_STAGE_TOLERANCES = (1e-5, 1e-8)
_STAGE2_PER_PARAMETER = 5

# The work schedule: a fit spends this many residual evaluations per parameter and per body,
# 3 n (5 n - 5) in all, on a fixed sequence of paths (module docstring, "The work schedule").
_EVALUATIONS_PER_PARAMETER_AND_BODY = 3

# A later path's chain replaces the best one only if its cost is lower by more than this
# fraction; smaller differences count as ties, kept by the earlier path (module docstring, "The
# work schedule").
_BETTER = 1e-5


class FitWarning(RuntimeWarning):
    """A chain fit stopped at its evaluation budget; the chain returned is the best found."""


# ---------------------------------------------------------------------------------------------
# the parametrisation
# ---------------------------------------------------------------------------------------------
class _Layout:
    """Parametrisation of a dimensionless chain (L = EJ = rho = 1) with exact m, J, L and
    centre of mass at L/2 (or, for any other appendage, L = m = 1 with the given central
    inertia J/(m L**2) and centre of mass c/L).

    x = [u (n-1), s (n), v (n-2), g (n-1), c (n-1)]:

    * lengths ``l = e^u / sum e^u`` (u_n = 0);
    * centre-of-mass fractions ``a_i = s_i l_i``, s_i in [0, 1];
    * masses: frozen pieces ``l_i`` times ``e^v`` (v_1 = v_n = 0), then *tilted*,
      ``m_i ~ e^(v_i + tau d_i)`` with d_i the distance of body i's centre of mass from 1/2 and
      tau the root of ``sum m_i d_i = 0`` (a monotone equation: its derivative is a variance;
      d_i measured from the centre of mass when it is not at 1/2),
      scaled to the total mass 1: this keeps m and the centre of mass exact;
    * inertias: frozen ``m_i l_i**2/12`` times ``e^g`` (g_n = 0), scaled by the one factor that
      makes ``sum J_i + m_i d_i**2 = 1/12`` (parallel-axis theorem): J exact;
    * stiffnesses ``e^c (n - 1)`` (``e^c EJ/H``, H = L/(n - 1)).

    :meth:`arrays` also gives the exact derivative of the chain's arrays with respect to x
    (forward mode through each step above; tau by the implicit function theorem).
    """

    def __init__(self, n: int, inertia: float = 1.0 / 12.0, center: float = 0.5):
        self.n = n
        self.mass = 1.0
        self.inertia = inertia
        self.center = center
        self.sizes = (n - 1, n, n - 2, n - 1, n - 1)
        self.size = sum(self.sizes)
        self.offsets = np.cumsum((0,) + self.sizes)

    def block(self, k: int) -> slice:
        return slice(self.offsets[k], self.offsets[k + 1])

    def bounds(self):
        n = self.n
        lo = np.concatenate([np.full(n - 1, -4.0), np.zeros(n), np.full(n - 2, -4.0),
                             np.full(n - 1, -8.0), np.full(n - 1, -6.0)])
        hi = np.concatenate([np.full(n - 1, 4.0), np.ones(n), np.full(n - 2, 4.0),
                             np.full(n - 1, 4.0), np.full(n - 1, 6.0)])
        return lo, hi

    def from_arrays(self, lengths, masses, inertias, com_offsets, stiffnesses) -> np.ndarray:
        """Parameters of a dimensionless chain (approximately; used as a starting point)."""
        n = self.n
        u = np.log(lengths[:-1] / lengths[-1])
        s = com_offsets / lengths
        v = np.log(masses[1:-1] / lengths[1:-1])
        g_all = np.log(inertias / (masses * lengths**2 / 12.0))
        g = g_all[:-1] - g_all[-1]
        c = np.log(stiffnesses / (n - 1))
        lo, hi = self.bounds()
        return np.clip(np.concatenate([u, s, v, g, c]), lo + 1e-9, hi - 1e-9)

    def arrays(self, x, jacobian: bool = False):
        """(lengths, masses, inertias, com_offsets, stiffnesses, penalty) of parameters x, and
        with ``jacobian`` their derivatives (arrays of shape (size, len(x))) as a second tuple.

        penalty > 0 when the layout cannot hold J (mass too far out) or the centre of mass.
        """
        n = self.n
        u, s, v, g, c = (x[self.block(k)] for k in range(5))
        weights = np.exp(np.concatenate([u, [0.0]]))
        lengths = weights / weights.sum()
        offsets = s * lengths
        starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
        d = starts + offsets - self.center
        logm = np.log(lengths) + np.concatenate([[0.0], v, [0.0]])
        penalty = 0.0
        spans = d.min() < 0.0 < d.max()
        if spans:
            tau = _tilt(logm, d)
        else:  # every centre on one side of L/2: keep the masses, penalise the offset
            tau = 0.0
            penalty += abs(float(np.mean(d)))
        z = logm + tau * d
        p = np.exp(z - z.max())
        p /= p.sum()
        masses = self.mass * p
        rest = self.inertia - np.dot(masses, d**2)
        raw = np.exp(np.concatenate([g, [0.0]])) * masses * lengths**2 / 12.0
        clipped = rest <= 1e-6 * self.inertia
        if clipped:
            penalty += (1e-6 * self.inertia - rest) / self.inertia
            rest = 1e-6 * self.inertia
        inertias = raw * (rest / raw.sum())
        stiffnesses = np.exp(c) * (n - 1)
        values = (lengths, masses, inertias, np.minimum(offsets, lengths), stiffnesses, penalty)
        if not jacobian:
            return values

        # forward mode: dX[i, j] = d X_i / d x_j
        nx = x.size
        eye = np.eye(nx)
        dlengths = np.zeros((n, nx))
        dlengths[:, self.block(0)] = (np.diag(lengths) - np.outer(lengths, lengths))[:, :n - 1]
        doffsets = s[:, None] * dlengths
        doffsets[:, self.block(1)] += np.diag(lengths)
        dstarts = np.concatenate([np.zeros((1, nx)), np.cumsum(dlengths, axis=0)[:-1]])
        dd = dstarts + doffsets
        dlogm = dlengths / lengths[:, None]
        dlogm[1:-1] += eye[self.block(2)]
        dpenalty = np.zeros(nx)
        if spans:
            # sum_i p_i d_i = 0 with p = softmax(logm + tau d), differentiated:
            # Var_p(d) dtau + Cov_p(d, dlogm + tau dd) + E_p(dd) = 0
            centred = d - np.dot(p, d)
            variance = np.dot(p, centred**2)
            dtau = -(centred * p) @ (dlogm + tau * dd) / variance - p @ dd / variance
            dz = dlogm + tau * dd + np.outer(d, dtau)
        else:
            dpenalty += np.sign(np.mean(d)) * dd.mean(axis=0)
            dz = dlogm
        dlogp = dz - p @ dz
        dmasses = masses[:, None] * dlogp
        if clipped:
            drest = np.zeros(nx)
            dpenalty += (dmasses.T @ d**2 + 2.0 * (masses * d) @ dd) / self.inertia
        else:
            drest = -(dmasses.T @ d**2) - 2.0 * (masses * d) @ dd
        dlograw = dlogp + 2.0 * dlengths / lengths[:, None]
        dlograw[:-1] += eye[self.block(3)]
        dlogsum = (raw / raw.sum()) @ dlograw
        dinertias = inertias[:, None] * (dlograw - dlogsum + drest / rest)
        dstiffnesses = np.zeros((n - 1, nx))
        dstiffnesses[:, self.block(4)] = np.diag(stiffnesses)
        return values, (dlengths, dmasses, dinertias, doffsets, dstiffnesses, dpenalty)


def _tilt(logm: np.ndarray, d: np.ndarray) -> float:
    """tau with sum_i exp(logm_i + tau d_i) d_i = 0 (min d < 0 < max d).

    The weighted mean of d is increasing in tau (its derivative is the weighted variance), so
    Newton's method from 0 is safeguarded by a bracket that it keeps shrinking.
    """
    lo, hi, tau = -np.inf, np.inf, 0.0
    for _ in range(100):
        z = logm + tau * d
        e = np.exp(z - z.max())
        e /= e.sum()
        mean = np.dot(e, d)
        if mean > 0.0:
            hi = tau
        else:
            lo = tau
        variance = np.dot(e, (d - mean) ** 2)
        if abs(mean) < 1e-15 * max(1.0, np.abs(d).max()):
            return tau
        step = tau - mean / variance if variance > 0.0 else np.nan
        if not (lo < step < hi):  # outside the bracket: bisect (or expand a half-open one)
            if np.isfinite(lo) and np.isfinite(hi):
                step = 0.5 * (lo + hi)
            else:
                step = (tau - 1.0) * 2.0 if np.isfinite(hi) else (tau + 1.0) * 2.0
        tau = step
    return tau


# ---------------------------------------------------------------------------------------------
# poles and zeros with their derivatives
# ---------------------------------------------------------------------------------------------
def _body_motions(V: np.ndarray, lengths: np.ndarray, offsets: np.ndarray):
    """(theta, y) of coordinate vectors V (columns; rigid root: [delta, theta_1..theta_n]):
    body rotations and centre-of-mass motions y_i = delta + sum_(j<i) l_j theta_j + a_i theta_i,
    each of shape (n, columns)."""
    theta = V[1:]
    reach = np.cumsum(lengths[:, None] * theta, axis=0)
    y = V[0] + offsets[:, None] * theta
    y[1:] += reach[:-1]
    return theta, y


def _pinned(index: np.ndarray, held: int) -> np.ndarray:
    """The coordinates of a pencil with coordinate ``held`` removed."""
    return index[index != held]


def _spectrum(arrays, n_values: int, jacobian: bool = False):
    """First n_values poles and zeros of W1, W2, W4 [rad/s] of a rigid-root chain, concatenated
    (None if a pencil fails or a value is missing, not positive or not real), and with
    ``jacobian`` the derivatives of their logarithms with respect to (lengths, masses,
    inertias, com_offsets, stiffnesses), shape (4 n_values, 5n - 1).

    The same quantities as HingedChain.poles()/zeros() (module docstring: pencils, eq. (1)),
    from LAPACK directly (dsygv, dggev: the scipy.linalg wrappers cost ten times the solve at
    these sizes). The vectors of the zeros come from the free chain's modes: the response
    ``u = (K - lambda M)^-1 e_j = sum_k v_k v_k[j] / (lambda_k - lambda)`` to a unit force
    (j = delta) or moment (j = phi) satisfies every equation but the loaded one, so at a zero
    of W1 (u_delta = W11 = 0), of W4 (phi, u_phi = W22 = 0) and of W2 (left: force, u_phi =
    W21 = 0; right: moment, v_delta = W12 = 0) it is the vector of eq. (1); the entry that
    vanishes is set to 0.
    """
    lengths, masses, inertias, offsets, stiffnesses = arrays[:5]
    M, _, K, _ = chain_matrices(lengths, masses, inertias, offsets, stiffnesses, None, False)
    size = K.shape[0]
    index = np.arange(size)
    no_delta, no_phi = _pinned(index, 0), _pinned(index, 1)
    with np.errstate(all="ignore"):
        # free chain (two rigid-body modes), delta = 0 and phi = 0 (one each): symmetric definite
        lam, modes, info = _sygv(K, M, "V")
        lam1, _, info1 = _sygv(K[np.ix_(no_delta, no_delta)], M[np.ix_(no_delta, no_delta)], "N")
        lam4, _, info4 = _sygv(K[np.ix_(no_phi, no_phi)], M[np.ix_(no_phi, no_phi)], "N")
        # W2: the minor without the moment equation (rows) and delta (columns)
        rows, columns = np.ix_(no_phi, no_delta)
        alphar, alphai, beta, _, _, _, info2 = _ggev(K[rows, columns], M[rows, columns],
                                                     compute_vl=0, compute_vr=0)
        if info or info1 or info4 or info2:
            return (None, None) if jacobian else None
        finite = beta != 0.0
        if np.any(np.abs(alphai[finite]) > 1e-9 * np.abs(alphar[finite])):
            return (None, None) if jacobian else None
        lam2 = np.sort(alphar[finite] / beta[finite])
        out = np.concatenate([lam[2:2 + n_values], lam1[1:1 + n_values], lam2[1:1 + n_values],
                              lam4[1:1 + n_values]])
        if out.size < 4 * n_values or not np.all(np.isfinite(out)) or not np.all(out > 0.0):
            return (None, None) if jacobian else None
        if not jacobian:
            return np.sqrt(out)
        zeros = out[n_values:].reshape(3, n_values)
        # responses to a unit force (row 0 of the modes) and moment (row 1) at each zero
        force = modes @ (modes[0][:, None] / (lam[:, None] - zeros[None, [0, 1]].reshape(1, -1)))
        moment = modes @ (modes[1][:, None] / (lam[:, None] - zeros[None, [2, 1]].reshape(1, -1)))
    force = force.reshape(size, 2, n_values)
    moment = moment.reshape(size, 2, n_values)
    w1, w2_left = force[:, 0], force[:, 1]
    w4, w2_right = moment[:, 0], moment[:, 1]
    w1[0] = w2_right[0] = 0.0
    w4[1] = w2_left[1] = 0.0
    free = modes[:, 2:2 + n_values]
    left = np.hstack([free, w1, w2_left, w4])
    right = np.hstack([free, w1, w2_right, w4])
    if not np.all(np.isfinite(left)) or not np.all(np.isfinite(right)):
        return None, None
    return np.sqrt(out), _log_frequency_derivatives(left, right, out, arrays)


def _sygv(K, M, jobz):
    """(eigenvalues ascending, M-normalised vectors, info) of the pencil (K, M) (dsygv)."""
    return scipy.linalg.lapack.dsygv(K, M, itype=1, jobz=jobz)


_ggev = scipy.linalg.lapack.dggev


def _log_frequency_derivatives(U, V, lam, arrays) -> np.ndarray:
    """d ln(sqrt(lambda_k)) / d(lengths, masses, inertias, com_offsets, stiffnesses) from the
    left and right vectors U, V (columns, full coordinates) by eq. (1), shape (k, 5n - 1)."""
    lengths, masses, inertias, offsets, stiffnesses = arrays[:5]
    tu, yu = _body_motions(U, lengths, offsets)
    tv, yv = _body_motions(V, lengths, offsets)
    my_u, my_v = masses[:, None] * yu, masses[:, None] * yv
    # d(u^T M v): masses, inertias, offsets; lengths through y_i of the bodies beyond j
    d_m = yu * yv
    d_J = tu * tv
    d_a = tu * my_v + my_u * tv
    beyond_u = np.cumsum(my_u[::-1], axis=0)[::-1]
    beyond_v = np.cumsum(my_v[::-1], axis=0)[::-1]
    d_l = np.zeros_like(d_m)
    d_l[:-1] = tu[:-1] * beyond_v[1:] + beyond_u[1:] * tv[:-1]
    d_c = np.diff(tu, axis=0) * np.diff(tv, axis=0)
    norm = np.sum(my_u * yv + inertias[:, None] * tu * tv, axis=0)  # u^T M v
    scale = -lam / norm
    rows = np.concatenate([d_l * scale, d_m * scale, d_J * scale, d_a * scale, d_c / norm])
    return (rows / (2.0 * lam)).T


# ---------------------------------------------------------------------------------------------
# the least-squares problem
# ---------------------------------------------------------------------------------------------
_KINDS = ("free-free", "pinned-free", "w2", "sliding-free")  # poles, zeros of W1, W2, W4


def _targets(n_values: int) -> np.ndarray:
    """The exact beam's first n_values poles and zeros of W1, W2, W4 for L = EJ = rho = 1."""
    return np.concatenate([characteristic_roots(kind, n_values) ** 2 for kind in _KINDS])


class _Problem:
    """Residuals ``weights * ln(values/targets)`` and the layout penalty, with their Jacobian.

    ``log_target``: the logarithms of the 4 (n - 1) targets (poles, zeros of W1, W2, W4);
    default the uniform beam's (:func:`_targets`).
    """

    def __init__(self, layout: _Layout, weights: np.ndarray, log_target=None):
        self.layout = layout
        self.k = layout.n - 1
        self.log_target = np.log(_targets(self.k)) if log_target is None else log_target
        self.weights = weights
        self._cache = (None, None)

    def _evaluate(self, x):
        if self._cache[0] is not None and np.array_equal(self._cache[0], x):
            return self._cache[1]
        size = 4 * self.k + 1
        out = (np.full(size, 10.0), np.zeros((size, x.size)))  # a trial chain that fails
        with np.errstate(all="ignore"):  # extreme trial layouts: caught as non-finite below
            values, dvalues = self.layout.arrays(x, jacobian=True)
            spectrum, dspectrum = _spectrum(values, self.k, jacobian=True)
            if spectrum is not None:
                residual = np.concatenate([self.weights * (np.log(spectrum) - self.log_target),
                                           [10.0 * values[5]]])
                jac = np.empty((size, x.size))
                jac[:-1] = self.weights[:, None] * (dspectrum @ np.concatenate(dvalues[:5]))
                jac[-1] = 10.0 * dvalues[5]
                if np.all(np.isfinite(residual)) and np.all(np.isfinite(jac)):
                    out = (residual, jac)
        self._cache = (x.copy(), out)
        return out

    def residual(self, x):
        return self._evaluate(x)[0]

    def jacobian(self, x):
        return self._evaluate(x)[1]

    def cost(self, x) -> float:
        return 0.5 * float(np.sum(self.residual(x) ** 2))


# ---------------------------------------------------------------------------------------------
# results, threads, memo
# ---------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True, eq=False)
class DimensionlessChain:
    """A chain fitted to the beam with L = EJ = rho = 1 (module docstring), and how its fit ended.

    Attributes
    ----------
    lengths, masses, inertias, com_offsets, hinge_stiffnesses : ndarray
        Read-only; in units of L, rho L, rho L**3, L and EJ/L.
    cost : float
        Final least-squares cost ``sum(residuals**2)/2`` of the fit [-].
    start_cost : float
        Cost of the fit's start (the RFEM chain) [-]; nan for the frequency fit.
    stopped : bool
        Whether the fit's evaluation budget cut its first path (from the RFEM chain) short
        before its tolerances were met.
    max_nfev : int or None
        The budget of the fit asked for (None: the default).
    nfev : int
        Residual evaluations spent.
    """

    lengths: np.ndarray
    masses: np.ndarray
    inertias: np.ndarray
    com_offsets: np.ndarray
    hinge_stiffnesses: np.ndarray
    cost: float
    start_cost: float
    stopped: bool
    max_nfev: int | None = None
    nfev: int = 0

    def __post_init__(self):
        for name in ("lengths", "masses", "inertias", "com_offsets", "hinge_stiffnesses"):
            values = np.array(getattr(self, name), dtype=np.float64)
            values.flags.writeable = False
            object.__setattr__(self, name, values)

    def to_chain(self, beam) -> HingedChain:
        """The chain of ``beam`` (``length``, ``bending_stiffness``, ``linear_density``, and
        optionally ``damping_ratio``): each array times its unit (one rounding each), hinge
        dampings ``2 zeta c_h / w_1`` as :meth:`HingedChain.rfem` when zeta > 0.

        Raises ValueError (from :class:`HingedChain`) when a scaled value leaves the documented
        ranges.
        """
        L, EJ, rho = (float(beam.length), float(beam.bending_stiffness),
                      float(beam.linear_density))
        stiffnesses = self.hinge_stiffnesses * (EJ / L)
        return HingedChain(self.lengths * L, self.masses * (rho * L),
                           self.inertias * (rho * L**3), stiffnesses,
                           com_offsets=self.com_offsets * L,
                           hinge_dampings=proportional_hinge_dampings(beam, stiffnesses))

    def scaled(self, length: float, mass: float, frequency_unit: float, *,
               damping_ratio: float = 0.0, first_frequency: float | None = None) -> HingedChain:
        """The chain in SI from a fit in units of ``length`` [m], ``mass`` [kg] and
        ``frequency_unit`` [rad/s] (:func:`fit_poles_and_zeros_to`): inertias in
        ``mass length**2``, hinge stiffnesses in ``mass length**2 frequency_unit**2``; hinge
        dampings ``2 zeta c_h / w`` (stiffness-proportional: ratio zeta at w =
        ``first_frequency`` [rad/s]) when ``damping_ratio`` > 0.

        Raises ValueError (from :class:`HingedChain`) when a scaled value leaves the documented
        ranges.
        """
        stiffnesses = self.hinge_stiffnesses * (mass * length**2 * frequency_unit**2)
        dampings = None
        if damping_ratio > 0.0:
            dampings = 2.0 * damping_ratio * stiffnesses / float(first_frequency)
        return HingedChain(self.lengths * length, self.masses * mass,
                           self.inertias * (mass * length**2), stiffnesses,
                           com_offsets=self.com_offsets * length, hinge_dampings=dampings)


_THREADS_LOCK = threading.Lock()
_THREADS = {"controller": None, "limiter": None, "depth": 0}


@contextlib.contextmanager
def _one_blas_thread():
    """Run the block with one BLAS thread (threadpoolctl).

    The fit's matrices are small (at most 5 n parameters): with threads, OpenBLAS spends more
    time waking and synchronising them than computing, much more on a busy machine, and its
    summation order, hence the last bits of each step and, through the optimiser's path, the
    fitted chain, depended on the thread count (measured without this limit, 2 cores at load
    10: a 10-body fit with the thread variables unset took 15.7 s of CPU against 0.8 s with
    one thread, and ended at another chain). The limit is process-wide (BLAS has one thread pool): the
    first of concurrent fits sets it, the last restores it; meanwhile other threads' BLAS
    calls run on one thread too.
    """
    with _THREADS_LOCK:
        if _THREADS["controller"] is None:
            import threadpoolctl  # here: 20-100 ms, paid by the first cold fit only

            _THREADS["controller"] = threadpoolctl.ThreadpoolController()
        if _THREADS["depth"] == 0:
            _THREADS["limiter"] = _THREADS["controller"].limit(limits=1, user_api="blas")
        _THREADS["depth"] += 1
    try:
        yield
    finally:
        with _THREADS_LOCK:
            _THREADS["depth"] -= 1
            if _THREADS["depth"] == 0:
                _THREADS["limiter"].restore_original_limits()
                _THREADS["limiter"] = None


def clear_memo() -> None:
    """Forget every memoised fit (the next fits are computed afresh)."""
    _fit_poles_and_zeros.cache_clear()
    _fit_poles_and_zeros_to.cache_clear()
    _fit_frequencies.cache_clear()


# ---------------------------------------------------------------------------------------------
# flexsat's fit: poles and zeros
# ---------------------------------------------------------------------------------------------
def _uniform_arrays(n: int, end_fraction: float):
    """A chain of frozen pieces for L = EJ = rho = 1: inner rods H, end rods ``end_fraction``
    H (H = 1/(n - 2 + 2 end_fraction)), hinge stiffnesses 1/H (EJ/H)."""
    units = n - 2 + 2.0 * end_fraction  # L/H
    lengths = np.full(n, 1.0 / units)
    lengths[0] = lengths[-1] = end_fraction / units
    return lengths, lengths.copy(), lengths**3 / 12.0, 0.5 * lengths, np.full(n - 1, units)


def _rfem_arrays(n: int):
    """The RFEM chain (end rods H/2, inner rods H = 1/(n - 1), c = 1/H) for L = EJ = rho = 1."""
    return _uniform_arrays(n, 0.5)


def _paths():
    """The fit's paths in order, endlessly: (end fraction of the start, stage-1 scaling).

    The RFEM chain (end rods H/2) with the updated column scaling ("jac"), the chain of n equal
    bodies with the start's column norms held fixed ("fixed"), the RFEM chain fixed, the equal
    chain updated, then end fractions 3/4, 5/8, 7/8, 9/16, ... (the binary midpoints of
    (1/2, 1), coarse to fine), fixed then updated (module docstring, "The work schedule").
    """
    yield 0.5, "jac"
    yield 1.0, "fixed"
    yield 0.5, "fixed"
    yield 1.0, "jac"
    level = 1
    while True:
        level += 1
        for odd in range(1, 2**level, 2):
            fraction = 0.5 + 0.5 * odd / 2**level
            yield fraction, "fixed"
            yield fraction, "jac"


def evaluation_budget(n_bodies: int) -> int:
    """Residual evaluations of one poles-and-zeros fit: 3 n (5 n - 5) (module docstring, "The
    work schedule"); strictly increasing in n."""
    return _EVALUATIONS_PER_PARAMETER_AND_BODY * n_bodies * _Layout(n_bodies).size


def fit_poles_and_zeros(n_bodies: int, *, pole_weight: float = 10.0,
                        max_nfev: int | None = None) -> DimensionlessChain:
    """flexsat's chain fit (:func:`appendages.equivalence.fit_chain`) in dimensionless form.

    Least squares in log-frequency over a :class:`_Layout`: the first n - 1 natural frequencies
    and zeros of W1, W2 (= W3) and W4 against the exact beam's, the poles weighted by
    ``pole_weight``, with the exact Jacobian (module docstring). Memoised by its arguments (and
    :data:`FIT_VERSION`); the result is immutable.

    A fixed budget of residual evaluations (:func:`evaluation_budget`) is spent on a fixed
    sequence of paths (:func:`_paths`), each from a uniform chain in two stages: all targets
    weighted equally to tolerance 1e-5, then the poles weighted with unscaled parameters to
    tolerance 1e-8 or 5 evaluations per parameter, which ends the creep along the valley of
    this rank-deficient problem (not a failure). The path that the budget reaches last is cut
    short (by design: its chain competes like the others); the chain of lowest cost is kept
    (module docstring, "The work schedule").

    Parameters
    ----------
    n_bodies : int
        Number of bodies (>= 2; validated by the caller).
    pole_weight : float
        Weight of the poles relative to the zeros (> 0).
    max_nfev : int, optional
        Budget of residual evaluations of the whole fit instead of :func:`evaluation_budget`.

    Returns
    -------
    DimensionlessChain
        ``stopped`` when the budget cut the first path (the RFEM start) short; ``nfev`` the
        evaluations spent: the budget (the sequence of paths is endless).

    Raises
    ------
    ConvergenceError
        If the fit ends outside the physical layout or no better than its start.
    """
    return _fit_poles_and_zeros(int(n_bodies), float(pole_weight),
                                None if max_nfev is None else int(max_nfev), FIT_VERSION)


@functools.lru_cache(maxsize=256)
def _fit_poles_and_zeros(n: int, pole_weight: float, max_nfev, version: int):
    del version  # part of the memo key only
    return _run_fit(_Layout(n), None, pole_weight, max_nfev)


def fit_poles_and_zeros_to(targets, n_bodies: int, *, inertia: float, center: float,
                           pole_weight: float = 10.0,
                           max_nfev: int | None = None) -> DimensionlessChain:
    """flexsat's chain fit to any appendage's poles and zeros, in dimensionless form.

    The problem of :func:`fit_poles_and_zeros` with other targets and rigid properties: a chain
    of length 1 and mass 1 whose central inertia is ``inertia`` and centre of mass ``center``,
    exactly, fitted by the same schedule (the same paths from the same uniform starts, the same
    budget) to ``targets``. Memoised by its arguments.

    Parameters
    ----------
    targets : array_like, shape (4, n_bodies - 1)
        The first n - 1 natural frequencies and zeros of W1, W2 (= W3) and W4, rows in that
        order, in a frequency unit in which a uniform beam's first natural frequency would be
        about 22.4 (the starts are uniform chains with hinges EJ/H in that unit).
    n_bodies : int
        Number of bodies (>= 2; validated by the caller).
    inertia : float
        Central moment of inertia over m L**2, in (0, center (1 - center)).
    center : float
        Centre of mass over L, in (0, 1).
    pole_weight, max_nfev
        As :func:`fit_poles_and_zeros`.

    Returns
    -------
    DimensionlessChain
        In units of L, m, m L**2, L and (m L**2) times the frequency unit squared
        (:meth:`DimensionlessChain.scaled`).

    Raises
    ------
    ConvergenceError
        If the fit ends outside the physical layout or no better than its start.
    """
    values = np.asarray(targets, dtype=np.float64)
    return _fit_poles_and_zeros_to(tuple(values.ravel().tolist()), int(n_bodies),
                                   float(inertia), float(center), float(pole_weight),
                                   None if max_nfev is None else int(max_nfev), FIT_VERSION)


@functools.lru_cache(maxsize=256)
def _fit_poles_and_zeros_to(targets: tuple, n: int, inertia: float, center: float,
                            pole_weight: float, max_nfev, version: int):
    del version  # part of the memo key only
    log_target = np.log(np.asarray(targets, dtype=np.float64))
    return _run_fit(_Layout(n, inertia, center), log_target, pole_weight, max_nfev)


def _run_fit(layout: _Layout, log_target, pole_weight: float, max_nfev) -> DimensionlessChain:
    """The work schedule of :func:`fit_poles_and_zeros` on a layout and targets."""
    n = layout.n
    k = n - 1
    lo, hi = layout.bounds()
    flat = _Problem(layout, np.ones(4 * k), log_target)
    weighted = _Problem(layout, np.concatenate([np.full(k, pole_weight), np.ones(3 * k)]),
                        log_target)
    budget = evaluation_budget(n) if max_nfev is None else max_nfev
    start = layout.from_arrays(*_rfem_arrays(n))
    used, best, stopped = 0, None, False
    with _one_blas_thread():
        start_cost = weighted.cost(start)
        for path, (end_fraction, scaling) in enumerate(_paths()):
            if used >= budget:
                break
            x = start if path == 0 else layout.from_arrays(*_uniform_arrays(n, end_fraction))
            if scaling == "fixed":  # the start's column norms (module docstring)
                scaling = 1.0 / np.maximum(np.linalg.norm(flat.jacobian(x), axis=0),
                                           np.finfo(float).tiny)
            stages = [(flat, scaling, _STAGE_TOLERANCES[0], budget)]
            if pole_weight != 1.0:
                stages.append((weighted, 1.0, _STAGE_TOLERANCES[1],
                               _STAGE2_PER_PARAMETER * layout.size))
            for problem, x_scale, tol, stage_budget in stages:
                left = budget - used
                if left <= 0:
                    break
                result = scipy.optimize.least_squares(
                    problem.residual, x, jac=problem.jacobian, bounds=(lo, hi), x_scale=x_scale,
                    xtol=tol, ftol=tol, gtol=tol, max_nfev=min(stage_budget, left))
                x = result.x
                used += result.nfev
                # stage 2's own budget is its designed end; the fit's budget ending the first
                # path is not (FitWarning): the later paths are the ones it is meant to cut
                if path == 0 and result.status == 0 and left <= stage_budget:
                    stopped = True
            cost = weighted.cost(x)
            if best is None or cost < best[0] * (1.0 - _BETTER):
                best = (cost, x)
        cost, x = best
        arrays = layout.arrays(x)
    penalty = arrays[5]
    if penalty > 0.0 or not math.isfinite(cost) or cost >= start_cost:
        raise ConvergenceError(
            f"fit_chain(match='poles-and-zeros', n_bodies={n}) did not converge to a physical "
            f"chain better than the RFEM start (cost {cost:.3e} vs {start_cost:.3e}, layout "
            f"penalty {penalty:.2e})")
    return DimensionlessChain(*arrays[:5], cost=cost, start_cost=start_cost, stopped=stopped,
                              max_nfev=max_nfev, nfev=used)


def fit_plane_on_layout(lengths, masses, com_offsets, inertias, hinge_stiffnesses, targets,
                        inertia: float, *, pole_weight: float = 10.0):
    """A chain's other bending plane: its bodies kept, their inertias and hinges refitted.

    A three-axis chain has one set of bodies (lengths, masses, centres of mass) for both
    bending planes; what the x-z plane alone sees are the bodies' inertias about y and the
    hinges' springs in that plane. For an appendage whose x-z plane is not a scaled copy of its
    x-y plane (:mod:`appendages.fit3d`), these 2 n - 2 numbers are fitted, from the x-y fit's,
    to the x-z plane's 4 (n - 1) poles and zeros (log-frequency least squares, the poles
    weighted by ``pole_weight``, exact Jacobian by eq. (1) of the module docstring), with the
    plane's central inertia held exactly: ``J_i = r_i (J - sum m_i d_i**2)/sum r`` with
    ``r_i = J0_i e^(g_i)`` (g_n = 0) and d_i the bodies' centres from the centre of mass.

    Parameters
    ----------
    lengths, masses, com_offsets : array_like, (n,)
        The bodies [m, kg, m], kept.
    inertias : array_like, (n,)
        Their inertias in the x-y plane [kg*m^2], the start.
    hinge_stiffnesses : array_like, (n - 1,)
        The x-y plane's hinges [N*m/rad], the start (scaled to the first target).
    targets : array_like, (4, n - 1)
        The x-z plane's first poles and zeros of W1, W2, W4 [rad/s].
    inertia : float
        The x-z plane's central inertia [kg*m^2] (about y through the centre of mass).
    pole_weight : float

    Returns
    -------
    (inertias, hinge_stiffnesses) : ndarray
        Of the x-z plane [kg*m^2, N*m/rad].

    Raises
    ------
    ValueError
        If the bodies' masses alone exceed the plane's inertia (no inertias can hold it).
    ConvergenceError
        If the fit ends no better than its start or with a failed chain.
    """
    lengths, masses, offsets = (np.asarray(a, dtype=np.float64) for a in
                                (lengths, masses, com_offsets))
    J0, k0 = np.asarray(inertias, dtype=np.float64), np.asarray(hinge_stiffnesses, np.float64)
    targets = np.asarray(targets, dtype=np.float64)
    n = lengths.size
    L, m = float(lengths.sum()), float(masses.sum())
    unit = float(targets[0, 0]) / float(characteristic_roots("free-free", 1)[0]) ** 2
    scale_J, scale_k = m * L**2, m * L**2 * unit**2
    lengths, masses, offsets = lengths / L, masses / m, offsets / L
    J0, k0 = J0 / scale_J, k0 / scale_k
    centres = np.concatenate([[0.0], np.cumsum(lengths)[:-1]]) + offsets
    d = centres - float(masses @ centres)
    rest = inertia / scale_J - float(masses @ d**2)
    if not rest > 0.0:
        raise ValueError(f"the x-z plane's central inertia {inertia:.6g} kg*m^2 is below what "
                         f"the bodies' masses alone give ({(inertia / scale_J - rest) * scale_J:.6g} "
                         "kg*m^2): no inertias about y can hold it")
    k = n - 1
    log_target = np.log(targets.ravel() / unit)
    weights = np.concatenate([np.full(k, pole_weight), np.ones(3 * k)])
    cache = {}

    def layout(x):
        raw = J0 * np.exp(np.concatenate([x[:k], [0.0]]))
        return raw, raw * (rest / raw.sum()), k0 * np.exp(x[k:])

    def evaluate(x):
        key = x.tobytes()
        if key not in cache:
            raw, J, c = layout(x)
            out = (np.full(4 * k, 10.0), np.zeros((4 * k, x.size)), False)  # a failed chain
            with np.errstate(all="ignore"):
                spectrum, dspectrum = _spectrum((lengths, masses, J, offsets, c), k,
                                                jacobian=True)
            if spectrum is not None:
                dJ = J[:, None] * (np.eye(n)[:, :k] - (raw / raw.sum())[:k][None, :])
                jac = np.hstack([dspectrum[:, 2 * n:3 * n] @ dJ, dspectrum[:, 4 * n:] * c])
                residual = weights * (np.log(spectrum) - log_target)
                if np.all(np.isfinite(residual)) and np.all(np.isfinite(jac)):
                    out = (residual, weights[:, None] * jac, True)
            cache.clear()
            cache[key] = out
        return cache[key]

    x0 = np.zeros(2 * k)
    x0[k:] = 2.0 * math.log(float(targets[0, 0]) / unit
                            / max(_first_pole(lengths, masses, J0 * (rest / J0.sum()),
                                              offsets, k0), 1e-300))
    lo = np.concatenate([np.full(k, -8.0), np.full(k, -6.0 + x0[k])])
    hi = np.concatenate([np.full(k, 4.0), np.full(k, 6.0 + x0[k])])
    x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)
    start_cost = 0.5 * float(np.sum(evaluate(x0)[0] ** 2))
    with _one_blas_thread():
        # a budget of 50 evaluations per parameter, resumed from where it stopped up to three
        # times: a fit cut at its budget ends wherever the CPU's rounding led it (a stepped
        # wing with a tip body: its inertias 1.8 % apart between two OpenBLAS kernels)
        result, x = None, x0
        for _ in range(4):
            result = scipy.optimize.least_squares(lambda x: evaluate(x)[0], x,
                                                  jac=lambda x: evaluate(x)[1], bounds=(lo, hi),
                                                  x_scale="jac", xtol=1e-10, ftol=1e-10,
                                                  gtol=1e-10, max_nfev=50 * x0.size)
            x = np.clip(result.x, lo + 1e-9, hi - 1e-9)
            if result.status != 0:
                break
    cost = 0.5 * float(np.sum(evaluate(result.x)[0] ** 2))
    if result.status == 0:
        warnings.warn(f"the x-z plane's inertias and hinges stopped at the fit's evaluation "
                      f"budget ({4 * 50 * x0.size} evaluations, cost {cost:.3e} from "
                      f"{start_cost:.3e}): the chain returned is the best found", FitWarning,
                      stacklevel=2)
    if not math.isfinite(cost) or cost > start_cost or not evaluate(result.x)[2]:
        raise ConvergenceError(f"the x-z plane's inertias and hinges did not converge (cost "
                               f"{cost:.3e} from {start_cost:.3e})")
    _, J, c = layout(result.x)
    return J * scale_J, c * scale_k


def _first_pole(lengths, masses, inertias, offsets, stiffnesses) -> float:
    M, _, K, _ = chain_matrices(lengths, masses, inertias, offsets, stiffnesses, None, False)
    lam = np.sort(scipy.linalg.eigvalsh(K, M))
    return math.sqrt(max(lam[2], 0.0)) if lam.size > 2 else 0.0


# ---------------------------------------------------------------------------------------------
# the paper's fit: frequencies
# ---------------------------------------------------------------------------------------------
def _symmetric(half: np.ndarray, n: int) -> np.ndarray:
    """Full symmetric profile of n entries from its first ceil(n/2)."""
    return np.concatenate([half, half[: n // 2][::-1]])


def _frequencies_arrays(x: np.ndarray, n: int):
    """Symmetric frozen-piece chain (L = EJ = rho = 1) from x = [log length weights
    (ceil(n/2) - 1), log stiffness factors (ceil((n-1)/2))]."""
    h = (n + 1) // 2
    weights = _symmetric(np.exp(np.concatenate([x[: h - 1], [0.0]])), n)
    lengths = weights / weights.sum()
    factors = _symmetric(np.exp(x[h - 1:]), n - 1) if n > 1 else np.zeros(0)
    return lengths, lengths.copy(), lengths**3 / 12.0, 0.5 * lengths, factors * (n - 1)


def fit_frequencies(n_bodies: int, targets=None) -> DimensionlessChain:
    """The paper's fit (:func:`appendages.equivalence.fit_chain`, ``match="frequencies"``) in
    dimensionless form: a symmetric chain of frozen pieces whose n - 1 natural frequencies
    equal ``targets`` (in units of sqrt(EJ/(rho L**4)); default the exact beam's, then
    memoised).

    Parameters
    ----------
    n_bodies : int
        Number of bodies (>= 2; validated by the caller).
    targets : sequence of n_bodies - 1 float, optional
        Increasing positive frequencies in units of sqrt(EJ/(rho L**4)) (validated by the
        caller); default the exact beam's x_k**2.

    Returns
    -------
    DimensionlessChain

    Raises
    ------
    ConvergenceError
        If the frequencies cannot be matched to 1e-9.
    """
    if targets is None:
        return _fit_frequencies(int(n_bodies), None, FIT_VERSION)
    return _fit_frequencies.__wrapped__(int(n_bodies), tuple(map(float, targets)), FIT_VERSION)


@functools.lru_cache(maxsize=256)
def _fit_frequencies(n: int, targets, version: int):
    del version  # part of the memo key only
    target = (characteristic_roots("free-free", n - 1) ** 2 if targets is None
              else np.asarray(targets, dtype=np.float64))
    h = (n + 1) // 2
    # Start: the RFEM chain (end rods half as long as the inner ones, c = EJ/H).
    x0 = np.zeros(h - 1 + n // 2)
    if h > 1:
        x0[0] = math.log(0.5)

    def residual(x):
        lengths, masses, inertias, _, stiffnesses = _frequencies_arrays(x, n)
        poles = HingedChain(lengths, masses, inertias, stiffnesses).poles()
        return np.log(poles[: n - 1] / target) if poles.size >= n - 1 else np.full(n - 1, 10.0)

    bounds = (np.full(x0.size, -8.0), np.full(x0.size, 8.0))
    with _one_blas_thread():
        result = scipy.optimize.least_squares(residual, x0, bounds=bounds, xtol=1e-15,
                                              ftol=1e-15, gtol=1e-15, max_nfev=200 * (x0.size + 1))
    worst = float(np.max(np.abs(result.fun)))
    if worst > 1e-9:
        raise ConvergenceError(
            f"fit_chain(match='frequencies', n_bodies={n}) did not match the frequencies: "
            f"largest relative mismatch {worst:.2e} after {result.nfev} evaluations "
            f"({result.message})")
    return DimensionlessChain(*_frequencies_arrays(result.x, n), cost=float(result.cost),
                              start_cost=math.nan, stopped=False, nfev=result.nfev)
