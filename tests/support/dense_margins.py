"""A brute-force reference for the margins of a three-axis loop: the loop's functions on a very
dense frequency grid, from the plain state-space matrices.

It imports nothing from flexsat (numpy and scipy only), so agreement is evidence. The loop is
broken at the plant's torque inputs, negative-feedback convention: L = -K P (3 x 3), with P the
plant from the torques to the measurements the controller reads and K the controller from those
measurements to the torques; a digital controller (``dt`` > 0) sees the plant sampled with a
zero-order hold and L is evaluated at z = exp(j omega dt), up to the Nyquist frequency.

Evaluation
----------
P(x) = C (x I - A)^-1 B + D at each point x (j omega or exp(j omega dt)) from the complex Schur
form A = Z T Z^H (unitary Z, T upper triangular): (x I - T) y = Z^H B is solved by back
substitution for all frequencies at once, then P = C Z y + D. The Schur form is backward stable
and, unlike an eigendecomposition, needs no diagonalisable A (the hub's rigid modes are Jordan
blocks); the same as np.linalg.solve on (x I - A) to round-off (:func:`frequency_response`
checks itself against it at a few points).

Grid
----
A logarithmic grid of ``n_log`` points (default 1e5) from 1e-3 times the slowest to 1e3 times
the fastest root below, plus, around every root r = -zeta |r| + j w_r with zeta <= 0.5 of the
plant, the controller, the closed loop, each loop with one torque's loop open (the poles of
the loop-at-a-time function L_i = 1/S_ii - 1) and each L_i's zeros (the zeros of the SISO
system of the loop cut at torque i, from torque i in to the controller's torque i out: the
true zeros of L_i, not those of -K_ii P_ii), the window w_r + zeta |r| tan(t), t in
``n_window`` (default 401) even steps over [-1.56, 1.56] (+-93 half-widths; the root's factor
1/(j omega - r) turns by 0.45 deg between points).

What it returns, and how exact
------------------------------
Every value is a bound on the true one in the direction that makes a comparison safe: a margin
found by flexsat that is LARGER than the reference's bound is larger than the truth.

- per axis, min |1 + L_i| on the grid: at least the true minimum;
- per axis, the smallest |phase margin| over the gain crossovers (|L_i| changes across 1
  between neighbours): at each crossover, the largest |180 deg + arg L_i| of its two bracketing
  points (the phase at the crossover lies between them where arg L_i is monotonic across the
  bracket; a bracket whose phase wraps through +-180 deg counts 180 deg), at least the true
  one; also the estimate by linear interpolation of the phase in log|L_i| and the bracket's
  phase change, the estimate's accuracy;
- per axis, the smallest |gain margin| [dB] over the phase crossovers (Im L_i changes sign
  between neighbours with Re L_i < 0 at both and |L_i| > 1e-9): the larger |20 log10 |L_i||
  of the two points;
- per axis, the delay margin min ((pi + arg L_i) mod 2 pi) / omega over the gain crossovers,
  each the larger of its two bracketing points (2 pi / omega_lo where the phase wraps);
- min sigma_min(I + L) on the grid (at least the true minimum) and 1 / max sigma_max(S - I/2)
  on the grid, S = (I + L)^-1 (the disk margin alpha; at least the true one);
- the three-axis delay margin over the unit-circle crossings of the eigenvalues of L (the
  number of eigenvalues outside the unit circle changes by one between neighbours): at each,
  the larger ((pi + arg lambda) mod 2 pi) / omega of the eigenvalue nearest the unit circle at
  the two points (2 pi / omega_lo where it wraps).

The grid's spacing decides how far the true values can lie below these bounds; ``accuracy``
reports the largest phase change of an L_i across a crossover bracket (the phase margin's
linear interpolation error is below half of it).

Every crossover is also bisected to 1e-13 relative in frequency on the reference's own
evaluation (``*_bisected``): a gain crossover on the sign of log|L_i|, a phase crossover on the
sign of Im L_i (kept where Re L_i < 0 there and |L_i| lies within its bracket's: a sign change
through a pole is none), both evaluated on the SISO system of the loop cut at torque i, and a
unit-circle crossing of L's eigenvalues on their count outside the circle (the crossing
eigenvalue then the one nearest the circle). These are the crossings' margins to round-off,
for the crossings the grid brackets.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.linalg

__all__ = ["DenseLoop", "dense_margins", "loop_roots"]

AXES = ("x", "y", "z")


def _select(system, inputs, outputs):
    """(A, B, C, D) of ``system`` restricted to the named inputs and outputs."""
    i_in = [list(system.input_labels).index(n) for n in inputs]
    i_out = [list(system.output_labels).index(n) for n in outputs]
    return (np.asarray(system.A, dtype=float), np.asarray(system.B, dtype=float)[:, i_in],
            np.asarray(system.C, dtype=float)[i_out],
            np.asarray(system.D, dtype=float)[np.ix_(i_out, i_in)])


def _blocks(plant, controller):
    """(Ap, Bp, Cp, Dp) torques -> measurements and (Ac, Bc, Cc, Dc) measurements -> torques,
    the plant sampled (zero-order hold) for a digital controller."""
    torques = [f"torque_{a}" for a in AXES]
    measured = [n for n in controller.input_labels if n in list(plant.output_labels)]
    Ap, Bp, Cp, Dp = _select(plant, torques, measured)
    dt = float(controller.dt or 0.0)
    if dt > 0.0:
        # zero-order hold: exp([[A, B], [0, 0]] dt) = [[Ad, Bd], [0, I]]
        n, m = Bp.shape
        E = scipy.linalg.expm(np.block([[Ap, Bp], [np.zeros((m, n + m))]]) * dt)
        Ap, Bp = E[:n, :n], E[:n, n:]
    return (Ap, Bp, Cp, Dp), _select(controller, measured, torques), dt


def frequency_response(A, B, C, D, x, chunk: int = 20000) -> np.ndarray:
    """C (x I - A)^-1 B + D at the points x, shape (f, p, m), by the complex Schur form and back
    substitution (module docstring), checked against np.linalg.solve at a few points."""
    x = np.asarray(x, dtype=complex).reshape(-1)
    n = A.shape[0]
    p, m = C.shape[0], B.shape[1]
    out = np.empty((x.size, p, m), dtype=complex)
    if n == 0:
        out[:] = D
        return out
    T, Z = scipy.linalg.schur(A.astype(complex), output="complex")
    ZB = Z.conj().T @ B
    CZ = C @ Z
    for start in range(0, x.size, chunk):
        xs = x[start:start + chunk]
        y = np.empty((n, xs.size, m), dtype=complex)
        for k in range(n - 1, -1, -1):
            rhs = ZB[k][None, :] + np.einsum("j,jfm->fm", T[k, k + 1:], y[k + 1:])
            y[k] = rhs / (xs - T[k, k])[:, None]
        out[start:start + chunk] = np.einsum("pk,kfm->fpm", CZ, y) + D
    check = np.unique(np.linspace(0, x.size - 1, 5).astype(int))
    M = x[check, None, None] * np.eye(n) - A
    direct = C @ np.linalg.solve(M, np.broadcast_to(B, (check.size,) + B.shape)) + D
    # both are backward stable: y = (x I - A)^-1 B to cond(x I - A) eps of its norm
    # ||B|| / sigma_min each, so C y to ||C|| times that (an absolute bound: a small P is
    # a cancellation)
    sv = np.linalg.svd(M, compute_uv=False)
    bound = (1e3 * np.finfo(float).eps * sv[:, 0] / sv[:, -1] ** 2
             * np.linalg.norm(C, 2) * np.linalg.norm(B, 2))
    error = np.abs(out[check] - direct).max(axis=(1, 2))
    assert np.all(error <= 1e-8 * np.abs(direct).max(axis=(1, 2)) + bound), \
        "Schur evaluation disagrees with np.linalg.solve"
    return out


def _closed(plant_blocks, controller_blocks, cut: int | None = None):
    """State-space matrices of the loop closed on every torque but ``cut`` (all: None). With a
    cut, input: the torque ``cut`` applied to the plant; output: minus the controller's torque
    ``cut`` (so its transfer is the loop-at-a-time L_cut, negative-feedback convention)."""
    Ap, Bp, Cp, Dp = plant_blocks
    Ac, Bc, Cc, Dc = controller_blocks
    n_p, n_c = Ap.shape[0], Ac.shape[0]
    E = np.eye(3)
    e = np.zeros((3, 1))
    if cut is not None:
        E[cut, cut] = 0.0
        e[cut, 0] = 1.0
    # command u_c = Cc xc + Dc (Cp xp + Dp u_a), applied u_a = E u_c + e v:
    # (I - E Dc Dp) u_a = E (Dc Cp xp + Cc xc) + e v
    M = np.linalg.inv(np.eye(3) - E @ Dc @ Dp)
    Fx = M @ E @ np.hstack([Dc @ Cp, Cc])
    Fv = M @ e
    A = np.block([[Ap, np.zeros((n_p, n_c))], [Bc @ Cp, Ac]])
    Bu = np.vstack([Bp, Bc @ Dp])
    A_cl = A + Bu @ Fx
    B_cl = Bu @ Fv
    # u_c = [Dc Cp, Cc] x + Dc Dp u_a
    G = np.hstack([Dc @ Cp, Cc])
    C_cut = -(G + Dc @ Dp @ Fx)
    D_cut = -(Dc @ Dp @ Fv)
    return A_cl, B_cl, C_cut, D_cut


def _siso_zeros(A, b, c, d) -> np.ndarray:
    """Finite zeros of a SISO system: the generalised eigenvalues of the Rosenbrock pencil
    [[A, b], [c, d]] - s [[I, 0], [0, 0]] (infinite ones dropped)."""
    n = A.shape[0]
    M = np.block([[A, b.reshape(n, 1)], [c.reshape(1, n), np.reshape(d, (1, 1))]])
    N = np.zeros((n + 1, n + 1))
    N[:n, :n] = np.eye(n)
    with np.errstate(all="ignore"):
        z = scipy.linalg.eigvals(M, N)
    return z[np.isfinite(z) & (np.abs(z) < 1e12)]


def loop_roots(plant, controller) -> dict:
    """The roots whose neighbourhoods the reference grid resolves (s-plane, rad/s; a digital
    loop's mapped by s = log(z) / dt): ``plant``, ``controller``, ``closed`` (the closed
    loop's poles), ``cut_poles`` and ``cut_zeros`` (per axis: the loop-at-a-time function's
    poles and true zeros)."""
    pb, cb, dt = _blocks(plant, controller)
    roots = {"plant": np.linalg.eigvals(pb[0]), "controller": np.linalg.eigvals(cb[0]),
             "closed": np.linalg.eigvals(_closed(pb, cb)[0]), "cut_poles": [], "cut_zeros": []}
    for i in range(3):
        A, B, C, D = _closed(pb, cb, cut=i)
        roots["cut_poles"].append(np.linalg.eigvals(A))
        roots["cut_zeros"].append(_siso_zeros(A, B[:, 0], C[i], D[i, 0]))
    if dt > 0.0:
        def to_s(z):
            z = np.asarray(z, dtype=complex)
            z = z[np.abs(z) > 1e-12]
            return np.log(z) / dt
        return {k: ([to_s(r) for r in v] if isinstance(v, list) else to_s(v))
                for k, v in roots.items()}
    return roots


class DenseLoop:
    """L(j omega) of a three-axis loop from its matrices (module docstring).

    Parameters
    ----------
    plant, controller : control.StateSpace
        With flexsat's three-axis signal names (torque_x..z in, theta/omega_x..z measured).
    """

    def __init__(self, plant, controller):
        self.plant_blocks, self.controller_blocks, self.dt = _blocks(plant, controller)
        self.roots = loop_roots(plant, controller)
        self._cut = [_closed(self.plant_blocks, self.controller_blocks, cut=i) for i in range(3)]

    def point(self, omega) -> np.ndarray:
        omega = np.asarray(omega, dtype=float)
        return np.exp(1j * omega * self.dt) if self.dt > 0.0 else 1j * omega

    def __call__(self, omega) -> np.ndarray:
        """L(j omega), shape (f, 3, 3)."""
        x = self.point(omega)
        P = frequency_response(*self.plant_blocks, x)
        K = frequency_response(*self.controller_blocks, x)
        return -(K @ P)

    def cut(self, omega, i: int) -> np.ndarray:
        """L_i(j omega) from the SISO system of the loop cut at torque i, shape (f,)."""
        A, B, C, D = self._cut[i]
        return frequency_response(A, B, C[[i]], D[[i]], self.point(omega))[:, 0, 0]

    def all_roots(self) -> np.ndarray:
        r = self.roots
        return np.concatenate([r["plant"], r["controller"], r["closed"], *r["cut_poles"],
                               *r["cut_zeros"]]).astype(complex)

    def grid(self, n_log: int = 100_000, n_window: int = 401) -> np.ndarray:
        roots = self.all_roots()
        w = np.abs(roots)
        w = w[np.isfinite(w) & (w > 1e-6 * max(w.max(initial=0.0), 1e-300))]
        w_lo, w_hi = 1e-3 * w.min(), 1e3 * w.max()
        if self.dt > 0.0:
            w_hi = math.pi / self.dt * (1.0 - 1e-9)
        parts = [np.geomspace(w_lo, w_hi, n_log)]
        upper = roots[(roots.imag > 0) & np.isfinite(roots)]
        zeta = np.abs(upper.real) / np.abs(upper)
        upper = upper[zeta <= 0.5]
        half = np.maximum(np.abs(upper.real), 1e-9 * np.abs(upper))
        t = np.tan(np.linspace(-1.56, 1.56, n_window))
        windows = (upper.imag[:, None] + half[:, None] * t[None, :]).ravel()
        parts.append(windows[(windows > w_lo) & (windows < w_hi)])
        return np.unique(np.concatenate(parts))


def _bisect(f, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Sign changes of f between lo and hi (arrays), bisected to 1e-13 relative."""
    lo, hi = np.array(lo, dtype=float), np.array(hi, dtype=float)
    if lo.size == 0:
        return lo
    f_lo = np.sign(f(lo))
    for _ in range(60):
        if np.all(hi - lo <= 1e-13 * hi):
            break
        mid = 0.5 * (lo + hi)
        left = np.sign(f(mid)) == f_lo
        lo, hi = np.where(left, mid, lo), np.where(left, hi, mid)
    return 0.5 * (lo + hi)


def _pm(L: np.ndarray) -> np.ndarray:
    """180 deg + arg L, wrapped to (-180, 180] [deg]."""
    return np.degrees(np.angle(-L))


def dense_margins(plant, controller, *, n_log: int = 100_000, n_window: int = 401) -> dict:
    """The reference bounds of the margins of a three-axis loop (module docstring).

    Returns
    -------
    dict
        ``axes``: per axis ``modulus_margin``, ``phase_margin`` (bound on the smallest |PM|,
        deg), ``phase_margin_estimate`` (interpolated, signed), ``gain_margin`` (bound on the
        smallest |GM|, dB), ``delay_margin`` (s), and ``phase_margin_bisected``,
        ``gain_margin_bisected``, ``delay_margin_bisected``; ``min_singular_value``,
        ``disk_margin``, ``delay_margin``, ``delay_margin_bisected``, ``crossings`` (rows:
        frequency, delay of each bisected unit-circle crossing); ``accuracy``:
        ``phase_bracket_deg`` (largest phase change of an L_i across a crossover bracket);
        ``n_points``; ``omega``, ``L``.
    """
    loop = DenseLoop(plant, controller)
    omega = loop.grid(n_log, n_window)
    L = loop(omega)
    finite = np.all(np.isfinite(L), axis=(1, 2))
    omega, L = omega[finite], L[finite]
    R = np.eye(3) + L
    S = np.linalg.inv(R)
    Li = 1.0 / np.diagonal(S, axis1=1, axis2=2) - 1.0        # (f, 3)
    # the reference checks itself: L_i from S against the cut loop's own SISO system
    probe = np.unique(np.linspace(0, omega.size - 1, 7).astype(int))
    for i in range(3):
        direct = loop.cut(omega[probe], i)
        A = loop._cut[i][0]
        # both to round-off times the conditioning of the resolvents (the rigid modes at the
        # grid's low end), and 1/S_ii - 1 to eps where S_ii is near 1
        cond = np.linalg.cond(loop.point(omega[probe])[:, None, None] * np.eye(A.shape[0]) - A)
        rtol = np.maximum(1e-6, 1e3 * np.finfo(float).eps * cond)
        # (where |L_i| >= 1e-6: the margins' range; below, both are cancellations)
        big = np.abs(direct) >= 1e-6
        assert np.all(np.abs(Li[probe, i] - direct)[big] <= (rtol * np.abs(direct))[big]), \
            "L_i from S disagrees with the cut loop's SISO system"
    axes, worst_bracket = {}, 0.0
    for i, a in enumerate(AXES):
        l = Li[:, i]
        ok = np.isfinite(l)
        w, l = omega[ok], l[ok]
        modulus = float(np.min(np.abs(1.0 + l)))
        # gain crossovers
        g = np.log(np.abs(l))
        k = np.flatnonzero(np.sign(g[1:]) != np.sign(g[:-1]))
        pm_lo, pm_hi = _pm(l[k]), _pm(l[k + 1])
        wraps = np.abs(pm_hi - pm_lo) > 180.0
        bracket = np.where(wraps, 360.0 - np.abs(pm_hi - pm_lo), np.abs(pm_hi - pm_lo))
        pm_bound = np.where(wraps, 180.0, np.maximum(np.abs(pm_lo), np.abs(pm_hi)))
        s = g[k] / (g[k] - g[k + 1])
        pm_est = np.where(wraps, np.nan, pm_lo + s * (pm_hi - pm_lo))
        worst_bracket = max(worst_bracket, float(bracket.max(initial=0.0)))
        j = int(np.argmin(pm_bound)) if k.size else None
        d_lo = np.mod(np.radians(pm_lo), 2 * np.pi) / w[k]
        d_hi = np.mod(np.radians(pm_hi), 2 * np.pi) / w[k + 1]
        d_wrap = np.abs(np.mod(np.radians(pm_hi), 2 * np.pi)
                        - np.mod(np.radians(pm_lo), 2 * np.pi)) > np.pi
        delay = np.where(d_wrap, 2 * np.pi / w[k], np.maximum(d_lo, d_hi))
        # phase crossovers
        q = np.flatnonzero((np.sign(l.imag[1:]) != np.sign(l.imag[:-1]))
                           & ((l.real[1:] < 0) | (l.real[:-1] < 0))
                           & (np.abs(l[1:]) > 1e-9) & (np.abs(l[:-1]) > 1e-9))
        both = (l.real[q] < 0) & (l.real[q + 1] < 0)
        gm = np.maximum(np.abs(20 * np.log10(np.abs(l[q]))),
                        np.abs(20 * np.log10(np.abs(l[q + 1]))))
        # every crossover bisected on the cut loop's own SISO response (to 1e-13 relative):
        # a gain crossover's sign of log|L_i|; a phase crossover's sign of Im L_i, kept where
        # Re L_i < 0 there and |L_i| lies within its bracket's ends (not a pass through a pole)
        gain_at = _bisect(lambda x: np.log(np.abs(loop.cut(x, i))), w[k], w[k + 1])
        l_gain = loop.cut(gain_at, i) if k.size else np.zeros(0, complex)
        phase_at = _bisect(lambda x: loop.cut(x, i).imag, w[q], w[q + 1])
        l_phase = loop.cut(phase_at, i) if q.size else np.zeros(0, complex)
        real = ((l_phase.real < 0) & (np.abs(l_phase) > 1e-9)
                & (np.abs(l_phase) <= 1.001 * np.maximum(np.abs(l[q]), np.abs(l[q + 1]))))
        pm_at = np.abs(_pm(l_gain))
        axes[a] = {"modulus_margin": modulus,
                   "phase_margin_bisected": float(pm_at.min(initial=math.inf)),
                   "delay_margin_bisected": float((np.mod(np.radians(_pm(l_gain)), 2 * np.pi)
                                                   / gain_at).min(initial=math.inf)),
                   "gain_margin_bisected": float(np.abs(20 * np.log10(np.abs(l_phase[real])))
                                                 .min(initial=math.inf)),
                   "phase_margin": float(pm_bound[j]) if k.size else math.inf,
                   "phase_margin_estimate": float(pm_est[j]) if k.size else math.inf,
                   "gain_margin": float(gm[both].min(initial=math.inf)),
                   "delay_margin": float(delay.min(initial=math.inf)),
                   "n_gain_crossovers": int(k.size), "n_phase_crossovers": int(q.size)}
    sv = np.linalg.svd(R, compute_uv=False)
    disk = np.linalg.svd(S - 0.5 * np.eye(3), compute_uv=False)[:, 0]
    # the eigenvalues of L crossing the unit circle
    lam = np.linalg.eigvals(L)
    outside = np.count_nonzero(np.abs(lam) > 1.0, axis=1)
    k = np.flatnonzero(np.abs(np.diff(outside)) == 1)
    nearest = lam[np.arange(lam.shape[0]), np.argmin(np.abs(np.log(np.abs(lam))), axis=1)]
    ph = np.mod(np.pi + np.angle(nearest), 2 * np.pi)
    d_lo, d_hi = ph[k] / omega[k], ph[k + 1] / omega[k + 1]
    wrap = np.abs(ph[k + 1] - ph[k]) > np.pi
    mimo_delay = np.where(wrap, 2 * np.pi / omega[k], np.maximum(d_lo, d_hi))
    # ... each crossing bisected on the count (to 1e-13 relative): the eigenvalue that crosses
    # is then the one nearest the unit circle; a bracket whose count changes by more (several
    # crossings) is bisected again from there to its end, until its whole change is taken
    k = np.flatnonzero(outside[1:] != outside[:-1])
    lo, hi, n_lo, n_hi = omega[k].copy(), omega[k + 1].copy(), outside[k], outside[k + 1]
    found_at, found_delay = [], []
    while lo.size:
        end, n_end = hi.copy(), n_hi.copy()
        for _ in range(60):
            if np.all(hi - lo <= 1e-13 * hi):
                break
            mid = 0.5 * (lo + hi)
            n_mid = np.count_nonzero(np.abs(np.linalg.eigvals(loop(mid))) > 1.0, axis=1)
            left = n_mid == n_lo
            lo, hi = np.where(left, mid, lo), np.where(left, hi, mid)
            n_hi = np.where(left, n_hi, n_mid)
        at = 0.5 * (lo + hi)
        lam_at = np.linalg.eigvals(loop(at))
        change = np.abs(n_hi - n_lo)
        for j in range(at.size):
            nearest = np.argsort(np.abs(np.log(np.abs(lam_at[j]))))[:change[j]]
            found_at += [at[j]] * nearest.size
            found_delay += list(np.mod(np.pi + np.angle(lam_at[j, nearest]), 2 * np.pi) / at[j])
        rest = np.flatnonzero(n_hi != n_end)
        lo, hi, n_lo, n_hi = hi[rest], end[rest], n_hi[rest], n_end[rest]
    crossing_delays = np.array(found_delay)
    at = np.array(found_at)
    return {"axes": axes, "min_singular_value": float(sv[:, -1].min()),
            "delay_margin_bisected": float(crossing_delays.min(initial=math.inf)),
            "crossings": np.column_stack([at, crossing_delays]),
            "disk_margin": float(1.0 / disk.max()),
            "delay_margin": float(mimo_delay.min(initial=math.inf)),
            "accuracy": {"phase_bracket_deg": worst_bracket},
            "n_points": int(omega.size), "omega": omega, "L": L}
