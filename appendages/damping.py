r"""Modal damping of an appendage's cantilever modes, exact on its root dynamic stiffness.

Finite-element data gives an appendage's damping as the ratio zeta of each cantilever
(fixed-root) mode. With the root driven by the motion q_r, the cantilever modes eta_k
(frequency w_k, participation factor l_k = psi_k^T M D) obey
``eta_k'' + 2 zeta w_k eta_k' + w_k**2 eta_k = -l_k^T q_r''``, and the root's loads are
``f = M_rr q_r'' + sum_k l_k eta_k''`` (Craig-Bampton coordinates, complete), so

    D(s) = s**2 M_rr - s**4 sum_k l_k l_k^T / (s**2 + 2 zeta w_k s + w_k**2)

(M_rr = sum_k l_k l_k^T the rigid mass about the root). Written as the undamped dynamic
stiffness D_u (a closed form or an exact assembly) plus each mode's damping::

    D(s) = D_u(s) + sum_k l_k l_k^T s**4 2 zeta w_k s / ((s**2 + w_k**2)(s**2 + 2 zeta w_k s + w_k**2)),

a product in each term (no difference of nearly equal fractions). Each term is
``l_k l_k^T s**4/w_k**2 g(s/w_k)`` with ``g(u) = 2 zeta u/((1 + u**2)(1 + 2 zeta u + u**2))``,
small for the modes far above |s|: the sum is taken explicitly over the modes up to N and the rest
either exactly (a uniform member's asymptotic modes: Hurwitz zeta sums, passed in as ``tail``) or
left out once a bound on it is below ``tolerance`` of D (1e-9 by default): with
``w_k >= w_(N+1)``, ``|sum_{k>N}| <= 2 zeta |s|**5 (M_rr - sum_{k<=N} l l^T)/w_(N+1)**3`` (each
diagonal entry against ``|s|**2 M_rr``; the bound is about 7 times the rest, whose terms decay
like k**-8). The bound falls like ``w_(N+1)**-3`` only: 1e-9 keeps the modes up to about 30 |s|
(zeta = 0.005), 1e-15 would need 3000 |s| (thousands of modes of a three-axis beam at a hundred
times its first frequency). Near an undamped pole ``+-i w_k``, where D_u is huge and the correction
cancels it, D is evaluated as the mean of the analytic ``D_u(z) + z**4 l_k l_k^T/(z**2 + w_k**2)``
over a circle around s (mean-value property, 32 points) plus the damped pole term and the other
modes' corrections, as :class:`appendages.beam.Beam` does for free-free damping.

W = D^-1 then has the accuracy the problem allows: near a lightly damped resonance of the free
appendage its relative error is eps/zeta, the condition of W itself to a perturbation of s.

References
----------
.. [1] R. R. Craig, M. C. C. Bampton, "Coupling of substructures for dynamic analyses", AIAA J.
   6(7), 1968.
.. [2] P. W. Likins, "Dynamics and control of flexible space vehicles", JPL TR 32-1329, 1970
   (cantilever modes, modal damping in hybrid coordinates).
"""

from __future__ import annotations

import math

import numpy as np

from .checks import check_positive
from .errors import describe

__all__ = ["CantileverDamping", "CONVENTIONS", "MAX_MODES", "check_damping_convention",
           "check_damping_ratio", "chebyshev_resonance_coefficients",
           "hurwitz_tail_coefficients", "mode_groups", "modal_factor_sum", "CantileverModalSums",
           "ModalFactorSum", "tail_series"]

_REPAIR_POINTS = 32
#: Most entries (points x modes) for which CantileverModalSums evaluates its motions together.
_JOINT = 49152
#: Most cantilever modes summed explicitly at one point.
MAX_MODES = 16384
#: Relative gap below which cantilever frequencies form one group (equal frequencies).
_GROUP = 1e-9


def mode_groups(w: np.ndarray) -> np.ndarray:
    """Group index of each frequency: equal frequencies (to 1e-9) share a group."""
    if w.size == 0:
        return np.zeros(0, dtype=np.int64)
    new = np.concatenate([[True], np.diff(w) > _GROUP * w[1:]])
    return np.cumsum(new) - 1


class CantileverDamping:
    """The damped root dynamic stiffness of an appendage (module docstring).

    Parameters
    ----------
    zeta : float
        Modal damping ratio of every cantilever mode, 0 < zeta < 1.
    undamped : callable
        ``undamped(s)`` for a flat complex array: the undamped D(s), shape (npts, d, d),
        infinite at the cantilever frequencies.
    modes : callable
        ``modes(n)``: (frequencies (n,) ascending [rad/s], participation factors (n, d)) of
        the first n cantilever modes.
    rigid_mass : ndarray, shape (d, d)
        M_rr, the rigid mass matrix about the root.
    tail : callable, optional
        ``tail(s, N)``: the exact correction of the modes k > N, shape (npts, d, d); without
        it, N is chosen by the bound of the module docstring.
    tolerance : float, optional
        Without ``tail``: the relative size of D below which the bound on the modes left out
        must fall (module docstring); default 1e-9.
    """

    def __init__(self, zeta: float, undamped, modes, rigid_mass: np.ndarray, tail=None,
                 tolerance: float = 1e-9):
        self.zeta = check_damping_ratio(zeta)
        for name, function in (("undamped", undamped), ("modes", modes)):
            if not callable(function):
                raise TypeError(f"{name} must be callable; got {describe(function)}")
        if tail is not None and not callable(tail):
            raise TypeError(f"tail must be callable or None; got {describe(tail)}")
        self.undamped, self.modes, self.tail = undamped, modes, tail
        self.tolerance = check_positive("tolerance", tolerance, "-")
        self.rigid_mass = np.asarray(rigid_mass, dtype=float)
        if self.rigid_mass.ndim != 2 or self.rigid_mass.shape[0] != self.rigid_mass.shape[1] \
                or not np.all(np.isfinite(self.rigid_mass)):
            raise ValueError(f"rigid_mass must be a finite square matrix [kg, kg*m, kg*m^2]; got "
                             f"{describe(rigid_mass)}")
        self.d = self.rigid_mass.shape[0]
        self._data = None

    # -- modal data -----------------------------------------------------------------------------
    def _modes_up_to(self, n: int):
        """(w, products l l^T (n, d, d), w-weighted products, groups) of the first n modes."""
        if self._data is None or self._data[0].size < n:
            n_get = max(n, 32)
            w, l = self.modes(n_get)
            products = l[:, :, None] * l[:, None, :]
            self._data = (w, products, products * w[:, None, None], mode_groups(w))
        w, products, weighted, groups = self._data
        return w[:n], products[:n], weighted[:n], groups[:n]

    def _modes_needed(self, s: np.ndarray) -> np.ndarray:
        """N per point (powers of two, at least 16): every mode up to 10 |s|, and with no
        exact tail, enough that the bound on the rest is below the tolerance of D."""
        size = np.abs(s)
        n = np.full(s.size, 16, dtype=np.int64)
        while True:
            top = int(n.max(initial=16))
            w, products, _, _ = self._modes_up_to(top + 1)
            short = np.zeros(s.size, dtype=bool)
            for value in np.unique(n):
                where = n == value
                w_next = w[value]
                bad = w_next < 10.0 * size[where]
                if self.tail is None:
                    rest = self.rigid_mass - products[:value].sum(axis=0)
                    ratio = float(np.max(np.abs(np.diagonal(rest))
                                         / np.abs(np.diagonal(self.rigid_mass))))
                    bound = 2.0 * self.zeta * (size[where] / w_next) ** 3 * ratio
                    bad = bad | (bound > self.tolerance)
                short[np.flatnonzero(where)[bad]] = True
            grow = short & (n < MAX_MODES)
            if not np.any(grow):
                return n
            n[grow] *= 2

    # -- evaluation -----------------------------------------------------------------------------
    def _correction(self, s: np.ndarray, n: int, exclude: np.ndarray | None = None) -> np.ndarray:
        """Sum of the damping corrections of modes 1..n at the points s (flat), leaving out, per
        point, the modes of group ``exclude`` (-1: none). Shape (npts, d, d)."""
        w, _, weighted, groups = self._modes_up_to(n)
        d = self.d
        out = np.empty((s.size, d, d), dtype=np.complex128)
        flat_weighted = weighted.reshape(n, d * d)
        chunk = max(1, 1_000_000 // max(n, 1))
        for start in range(0, s.size, chunk):
            ss = s[start:start + chunk, None]
            undamped = ss**2 + w**2
            with np.errstate(divide="ignore", invalid="ignore"):
                factor = 1.0 / (undamped * (undamped + (2.0 * self.zeta) * w * ss))
            if exclude is not None:
                skip = groups[None, :] == exclude[start:start + chunk, None]
                factor = np.where(skip, 0.0, factor)
            factor = factor * (2.0 * self.zeta) * ss[:, :1] ** 5
            out[start:start + chunk] = (factor @ flat_weighted).reshape(-1, d, d)
        return out

    def __call__(self, s) -> np.ndarray:
        """The damped D(s), flat complex s -> (npts, d, d); s = 0 gives 0."""
        s = np.asarray(s, dtype=np.complex128).ravel()
        d = self.d
        out = np.zeros((s.size, d, d), dtype=np.complex128)
        nonzero = np.flatnonzero(s != 0)
        if nonzero.size == 0:
            return out
        s = s[nonzero]
        n_needed = self._modes_needed(s)
        near, group = self._near_poles(s, int(n_needed.max()))
        result = np.empty((s.size, d, d), dtype=np.complex128)
        far = np.flatnonzero(~near)
        if far.size:
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                result[far] = self.undamped(s[far])
            for value in np.unique(n_needed[far]):
                idx = far[n_needed[far] == value]
                result[idx] += self._correction(s[idx], int(value))
                if self.tail is not None:
                    result[idx] += self.tail(s[idx], int(value))
        near_idx = np.flatnonzero(near)
        if near_idx.size:
            result[near_idx] = self._repair(s[near_idx], group[near_idx], n_needed[near_idx])
        out[nonzero] = result
        return out

    def _radius(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Per group of the first n modes: its frequency and the repair radius (a quarter of
        the smaller gap to the neighbouring groups and to 0)."""
        w, _, _, groups = self._modes_up_to(n + 1)
        first = np.concatenate([[0], np.flatnonzero(np.diff(groups)) + 1])
        wg = w[first]
        gaps = np.diff(np.concatenate([[0.0], wg, [2.0 * wg[-1]]]))
        return wg, 0.25 * np.minimum(gaps[:-1], gaps[1:])

    def _near_poles(self, s: np.ndarray, n: int):
        """Which points lie within a tenth of the repair radius of an undamped pole +-i w_g,
        and that group (-1 elsewhere)."""
        wg, radius = self._radius(n)
        size = np.abs(s)
        k = np.clip(np.searchsorted(wg, size), 1, wg.size - 1)
        nearest = np.where(np.abs(wg[k] - size) < np.abs(wg[k - 1] - size), k, k - 1)
        pole = np.where(s.imag >= 0, 1j, -1j) * wg[nearest]
        near = np.abs(s - pole) <= 0.1 * radius[nearest]
        return near, np.where(near, nearest, -1)

    def _repair(self, s: np.ndarray, group: np.ndarray, n_needed: np.ndarray) -> np.ndarray:
        """D at points near an undamped pole (module docstring)."""
        wg, radius = self._radius(int(n_needed.max()))
        w, products, _, groups = self._modes_up_to(int(n_needed.max()))
        P = np.zeros((wg.size, self.d, self.d))
        np.add.at(P, groups[groups < wg.size], products[groups < wg.size])
        theta = 2.0 * math.pi * (np.arange(_REPAIR_POINTS) + 0.5) / _REPAIR_POINTS
        z = s[:, None] + radius[group][:, None] * np.exp(1j * theta)[None, :]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            Du = self.undamped(z.ravel()).reshape(z.shape + (self.d, self.d))
        wk = wg[group]
        pole = (z**4 / (z**2 + (wk**2)[:, None]))[..., None, None] * P[group][:, None]
        analytic = np.mean(Du + pole, axis=1)
        damped = (s**4 / (s**2 + 2.0 * self.zeta * wk * s + wk**2))[:, None, None] * P[group]
        result = analytic - damped
        for value in np.unique(n_needed):
            idx = np.flatnonzero(n_needed == value)
            result[idx] += self._correction(s[idx], int(value), exclude=group[idx])
            if self.tail is not None:
                result[idx] += self.tail(s[idx], int(value))
        return result


#: The meanings of an appendage's modal damping ratio.
CONVENTIONS = ("cantilever", "free-free")


def check_damping_convention(convention) -> str:
    """``convention`` if it is one of :data:`CONVENTIONS`; ValueError naming it otherwise.

    ``"cantilever"`` (the default everywhere): the ratio of every cantilever (fixed-root) mode,
    as finite-element data carries it; ``"free-free"``: the ratio of every free-free mode (the
    paper's and flexsat's meaning before), kept for comparisons.
    """
    if isinstance(convention, str) and convention in CONVENTIONS:
        return convention
    raise ValueError(f"damping_convention must be 'cantilever' (the ratio of the cantilever, "
                     f"fixed-root modes) or 'free-free'; got {convention!r}")


def modal_factor_sum(s: np.ndarray, w: np.ndarray, weights: np.ndarray,
                     zeta: float) -> np.ndarray:
    r"""``sum_k weights_k (w_k**2 + 2 zeta w_k s)/(s**2 + 2 zeta w_k s + w_k**2)`` at flat s.

    :class:`ModalFactorSum` of the modes, evaluated once (an appendage that evaluates the same
    modes at many s keeps the object instead).

    Parameters
    ----------
    s : ndarray of complex, shape (npts,)
    w : ndarray, shape (N,)
        The modes' frequencies [rad/s].
    weights : ndarray, shape (N,) or (N, k)
    zeta : float
        Their damping ratio.

    Returns
    -------
    ndarray of complex, shape (npts,) or (npts, k)
    """
    return ModalFactorSum(w, weights, zeta)(s)


class ModalFactorSum:
    r"""``sum_k weights_k (w_k**2 + 2 zeta w_k s)/(s**2 + 2 zeta w_k s + w_k**2)`` of fixed
    modes, at any flat s; its s-independent parts (``2 zeta w_k``, ``w_k**2``, ``i w_k``)
    worked out once.

    The modal sums of the damped root dynamic stiffness (:class:`~appendages.rod.Rod`,
    :class:`~appendages.beam.Beam`): each mode's factor, 1 far below its frequency, about
    ``w_k**2/s**2`` far above, ``1/(2 zeta)`` in size at resonance. The denominator is written
    ``(s - i w_k)(s + i w_k) + 2 zeta w_k s`` (no difference of squares near a resonance). On
    the imaginary axis (every s = i omega, a frequency response; many points) in real
    arithmetic, several times quicker:
    with ``a = (w_k - omega)(w_k + omega)`` and ``b = 2 zeta w_k omega`` the factor is
    ``(w_k**2 a + b**2 - i b omega**2)/(a**2 + b**2)`` (no term cancels another beyond eps
    of the factor's size; where a square leaves double precision, the complex form answers).

    Parameters
    ----------
    w : ndarray, shape (N,)
        The modes' frequencies [rad/s].
    weights : ndarray, shape (N,) or (N, k)
        Each mode's weight (e.g. its participation factors' products, kg or kg*m...).
    zeta : float
        Their damping ratio [-].
    """

    def __init__(self, w: np.ndarray, weights: np.ndarray, zeta: float):
        self.w, self.weights, self.zeta = w, weights, zeta
        self.two_zeta_w = (2.0 * zeta) * w
        self.w_squared = w * w
        self.i_w = 1j * w

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """The sum at flat complex s [rad/s], shape (npts,) or (npts, k) (complex)."""
        w, weights = self.w, self.weights
        if s.size * w.size >= 4096 and not np.any(s.real):     # (small: complex is quicker)
            # the operations of the formula in the class docstring, each into an array of its
            # own kept for the next (no temporary per operation: these arrays are npts x N)
            omega = s.imag[:, None]
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                a = np.subtract(w, omega)
                a *= w + omega                          # a = (w_k - omega)(w_k + omega)
                b = np.multiply(self.two_zeta_w, omega)  # b = 2 zeta w_k omega
                bb = np.multiply(b, b)
                scale = np.multiply(a, a)
                scale += bb
                np.divide(1.0, scale, out=scale)        # 1/(a**2 + b**2)
                sound = np.isfinite(scale).all() and scale.min() > 0.0
            if sound:
                a *= self.w_squared
                a += bb
                a *= scale                              # (w_k**2 a + b**2)/(a**2 + b**2)
                b *= omega
                b *= omega
                b *= scale                              # b omega**2/(a**2 + b**2)
                out = (a @ weights).astype(np.complex128)
                out.imag = b @ weights
                np.negative(out.imag, out=out.imag)
                return out
        col = s[:, None]
        damping = self.two_zeta_w * col
        with np.errstate(divide="ignore", invalid="ignore"):
            factor = (self.w_squared + damping) / ((col - self.i_w) * (col + self.i_w) + damping)
        return factor @ weights


def tail_series(v: np.ndarray, coefficients: np.ndarray, first_power: int = 4) -> np.ndarray:
    """``sum_j coefficients_j v**(first_power + j)`` at complex v: the Hurwitz tails of the
    modal sums.

    A few points: the integer powers at once (numpy's integer power, a few ulp each: one array
    operation); many: Horner's scheme (numpy's complex integer power is slow on long arrays).

    Parameters
    ----------
    v : ndarray of complex, shape (npts,) or (npts, k)
        One v for every column of ``coefficients``, or (2-D) one per column.
    coefficients : ndarray, shape (J,) or (J, k)
    first_power : int

    Returns
    -------
    ndarray of complex, shape (npts,) or (npts, k)
    """
    J = coefficients.shape[0]
    powers = np.arange(first_power, first_power + J)
    if v.shape[0] <= 32:
        if v.ndim == 1:
            return (v[:, None] ** powers) @ coefficients
        return np.einsum("nkj,jk->nk", v[:, :, None] ** powers, coefficients)
    # Horner in place, one row per column of coefficients (contiguous rows), transposed back
    columns = coefficients.reshape(J, -1)
    rows = v if v.ndim == 1 else v.T
    out = np.zeros((columns.shape[1], v.shape[0]), dtype=np.complex128)
    for j in range(J - 1, -1, -1):
        out *= rows
        out += columns[j][:, None]
    out *= rows**first_power
    return out[0] if coefficients.ndim == 1 else out.T


class CantileverModalSums:
    r"""The damped root dynamic stiffness of one or several motions of an appendage by their
    cantilever modal sums, evaluated together.

    Each motion (a bending plane, torsion, axial motion) with its first N modes is

        D(s) = s**2 (F(s) + R) - T(s/c),

    F the :class:`ModalFactorSum` of those modes with their weights (products of participation
    factors), R the participation of the modes beyond N and T the series
    ``sum_j t_j v**(4+j)`` of their resonance factors in ``v = s/c`` (c the motion's frequency
    scale; :func:`tail_series`), as :meth:`appendages.beam.Beam.dynamic_stiffness` and
    :meth:`appendages.rod.Rod.dynamic_stiffness` derive them (cantilever convention). The
    motions of one appendage share its damping ratio, so at a few points (a step of a
    refinement) the factors of all their modes are formed in one pass and summed with
    block-diagonal weights, and the series of all motions are taken together: numpy's cost per
    operation is paid once, not once per motion. At many points each motion is evaluated
    alone (arrays of one motion's modes stay in the cache; together they cost more per entry,
    measured). A motion's value is its own sum either way, to rounding: the zero weights of
    the other motions add exact zeros, and a value that is not finite (an overflow, s exactly
    on a damped pole) is recomputed motion by motion, so that it stays in its own motion's
    columns.

    Parameters
    ----------
    motions : sequence of tuple
        Per motion ``(w, weights, rest, coefficients, scale)``: the frequencies, shape (N,)
        [rad/s]; their weights, (N, k); the rest R, (k,); the coefficients t_j, (J, k), J the
        same for every motion; the frequency scale c [rad/s].
    zeta : float
        The damping ratio of every mode [-].

    Attributes
    ----------
    columns : list of slice
        Each motion's columns of the result.
    """

    def __init__(self, motions, zeta: float):
        motions = list(motions)
        # several motions: each alone too, for many points and for a value not finite
        self._parts = None if len(motions) == 1 else [CantileverModalSums([motion], zeta)
                                                      for motion in motions]
        widths = [motion[1].shape[1] for motion in motions]
        edges = np.cumsum([0] + widths)
        self.columns = [slice(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:])]
        self.n_modes = sum(motion[0].size for motion in motions)
        # every motion's modes and weights side by side (the weights block-diagonal), its rest
        # and its series' coefficients
        weights = np.zeros((self.n_modes, edges[-1]))
        row = 0
        for (w, weight, _, _, _), columns in zip(motions, self.columns):
            weights[row:row + w.size, columns] = weight
            row += w.size
        self.factors = ModalFactorSum(np.concatenate([motion[0] for motion in motions]),
                                      weights, zeta)
        self._rest = np.concatenate([motion[2] for motion in motions])
        self._coefficients = np.concatenate([motion[3] for motion in motions], axis=1)
        self._motion_of_column = np.repeat(np.arange(len(motions)), widths)
        self._scales = np.array([float(motion[4]) for motion in motions])
        self._scale = float(motions[0][4])
        self._chunk = max(1, 1_000_000 // max(self.n_modes, 1))    # (arrays of points x modes)

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """Every motion's D at flat complex s [rad/s], shape (npts, K) (complex): motion m in
        the columns ``columns[m]`` (its k entries)."""
        if self._parts is None:         # one motion
            if s.size <= self._chunk:
                return self._evaluate(s)
            return np.concatenate([self._evaluate(s[start:start + self._chunk])
                                   for start in range(0, s.size, self._chunk)])
        if s.size * self.n_modes > _JOINT:
            return np.concatenate([part(s) for part in self._parts], axis=1)
        out = self._evaluate(s)
        if not np.isfinite(out).all():
            return np.concatenate([part(s) for part in self._parts], axis=1)
        return out

    def _evaluate(self, s: np.ndarray) -> np.ndarray:
        total = self.factors(s)
        total += self._rest
        np.multiply((s**2)[:, None], total, out=total)  # (this order: one motion's rounding)
        if self._parts is None:
            v = s / self._scale
        else:   # each column at its own motion's v
            v = (s[:, None] / self._scales)[:, self._motion_of_column]
        total -= tail_series(v, self._coefficients)
        return total


def chebyshev_resonance_coefficients(zeta: float, n_terms: int) -> np.ndarray:
    """U_0..U_(J-1) at -zeta: ``h(u) = 1/(1 + 2 zeta u + u**2) = sum_m U_m(-zeta) u**m``.

    The generating function of the Chebyshev polynomials of the second kind (DLMF 18.12.10),
    by their recurrence ``U_m = -2 zeta U_(m-1) - U_(m-2)`` (|U_m| <= m + 1 for zeta < 1):
    the series of one mode's resonance factor in u = s/w_k, |u| < 1.
    """
    cheb = np.empty(n_terms)
    if n_terms > 0:
        cheb[0] = 1.0
    if n_terms > 1:
        cheb[1] = -2.0 * zeta
    for j in range(2, n_terms):
        cheb[j] = -2.0 * zeta * cheb[j - 1] - cheb[j - 2]
    return cheb


def hurwitz_tail_coefficients(zeta: float, n_terms: int) -> np.ndarray:
    """c_1..c_J of ``g(u) = 2 zeta u/((1 + u**2)(1 + 2 zeta u + u**2)) = sum_j c_j u**j``.

    The product of ``sum (-1)**i u**(2i)`` and the Chebyshev series ``sum U_m(-zeta) u**m`` of
    ``1/(1 + 2 zeta u + u**2)`` (|U_m| <= m + 1), times 2 zeta u: ``|c_j| <= zeta j**2``.
    """
    cheb = chebyshev_resonance_coefficients(zeta, n_terms)
    alternating = np.zeros(n_terms)
    alternating[::2] = (-1.0) ** np.arange((n_terms + 1) // 2)
    return 2.0 * zeta * np.convolve(alternating, cheb)[:n_terms]


def check_damping_ratio(damping_ratio) -> float:
    """The modal damping ratio as a float in [0, 1), or TypeError/ValueError naming it."""
    zeta = check_positive("damping_ratio", damping_ratio, "-", allow_zero=True)
    if zeta >= 1.0:
        raise ValueError(f"damping_ratio must be below 1 (underdamped modes) [-]; got "
                         f"{describe(damping_ratio)}")
    return zeta
