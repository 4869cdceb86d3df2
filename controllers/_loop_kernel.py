"""Compiled evaluation of a loop transfer function at a batch of frequencies (numba; imported
on first use by :mod:`controllers.loop`, which falls back to the evaluators' numpy path when
numba is missing).

:func:`loop_matrix` sums the partial fractions of plant and controller,
G(s) = D + sum_k R_k / (s - lambda_k) + sum_j M_j / s^(j+1) (the modal sums of
:class:`controllers.frequency.ModalEvaluator`, the last term its rigid-body Markov sum), and
forms L = -K P, a block of frequencies at a time (the sums vectorised over the block): no
temporaries of (frequencies x poles), and a call on a few frequencies (a refinement step)
costs microseconds, not numpy's per-call overhead of several array operations. :func:`sensitivity` gives (I + L)^-1 (the loop-at-a-time
functions and the singular values follow from it) from a pivoted LU factorisation, the same
arithmetic as numpy's inverse without its per-call cost; :func:`unit_circle_count` the
eigenvalues of L outside the unit circle where no eigenvalue problem is needed, and
:func:`eigenvalues` those of small matrices where it is (the steps of LAPACK's zgeev, without
its per-matrix cost; its helpers inlined into it: one function to compile), and
:func:`shifted_frobenius` the norms that screen a grid for the peak singular value. All are
cached on disk as :mod:`controllers._modal_kernel`'s loop is
(:func:`controllers._modal_kernel.cached_njit`).
"""

from __future__ import annotations

import numpy as np

from ._modal_kernel import cached_njit

__all__ = ["eigenvalues", "loop_matrix", "sensitivity", "shifted_frobenius", "unit_circle_count"]


@cached_njit(error_model="numpy")
def _inverse(x):
    """1 / x for complex x: conj(x) / |x|^2, scaled by max(|Re x|, |Im x|) where |x|^2 would
    leave the normal range; inf + NaN j at x = 0, as numpy divides (numba's complex division
    raises there)."""
    xr = x.real
    xi = x.imag
    norm = xr * xr + xi * xi
    if 1e-300 < norm < 1e300:
        return complex(xr / norm, -xi / norm)
    t = max(abs(xr), abs(xi))
    if t == 0.0:
        return complex(np.inf, np.nan)
    a = xr / t
    b = xi / t
    n = (a * a + b * b) * t
    return complex(a / n, -b / n)


# frequencies evaluated together: the sums over poles run over this many at once (vectorised)
_BLOCK = 32


@cached_njit(error_model="numpy", fastmath={"contract"})
def _modal_sums(s, lam, res_re, res_im, d, markov, G_re, G_im, nb):
    """G = d + sum_k res_k / (s - lam_k) + sum_j markov_j / s^(j+1) at the nb points s, into
    the real and imaginary parts G_re, G_im (qm * _BLOCK,), entry e of point t at
    e * _BLOCK + t: 1 / (s - lam_k) = conj(x) / |x|^2, x = s - lam_k (:func:`_inverse`, scaled,
    where |x|^2 leaves the normal range), the sums over the poles in their order, in real
    arithmetic over the block's points (vectorised; multiply-adds may be fused, which only
    rounds less)."""
    qm = d.shape[0]
    rr = np.empty(_BLOCK)
    ri = np.empty(_BLOCK)
    for e in range(qm):
        o = e * _BLOCK
        for t in range(nb):
            G_re[o + t] = 0.0
            G_im[o + t] = 0.0
    for k in range(lam.shape[0]):
        lr = lam[k].real
        li = lam[k].imag
        outside = False
        for t in range(nb):
            xr = s[t].real - lr
            xi = s[t].imag - li
            norm = xr * xr + xi * xi
            inverse = 1.0 / norm
            rr[t] = xr * inverse
            ri[t] = -xi * inverse
            outside |= not (1e-300 < norm < 1e300)
        if outside:     # |s - lam_k|^2 beyond the normal range (0 on a pole): scaled
            for t in range(nb):
                r = _inverse(s[t] - lam[k])
                rr[t] = r.real
                ri[t] = r.imag
        for e in range(qm):
            a = res_re[k, e]
            b = res_im[k, e]
            o = e * _BLOCK
            for t in range(nb):
                G_re[o + t] += rr[t] * a - ri[t] * b
                G_im[o + t] += rr[t] * b + ri[t] * a
    for e in range(qm):
        o = e * _BLOCK
        for t in range(nb):
            G_re[o + t] += d[e].real
            G_im[o + t] += d[e].imag
    if markov.shape[0]:
        for t in range(nb):
            inverse = _inverse(s[t])
            power = inverse
            for j in range(markov.shape[0]):
                for e in range(qm):
                    o = e * _BLOCK
                    value = power * markov[j, e]
                    G_re[o + t] += value.real
                    G_im[o + t] += value.imag
                power = power * inverse


@cached_njit(error_model="numpy", fastmath={"contract"})
def loop_matrix(sp, sc, lam_p, res_p_re, res_p_im, d_p, markov_p, lam_c, res_c_re, res_c_im,
                d_c, markov_c, L):
    """Write L = -K P at each frequency into ``L`` (f, m, m).

    Parameters (C-contiguous; complex128 unless stated)
    ---------------------------------------------------
    sp, sc : (f,)
        The points at which plant and controller are evaluated (s, or z - 1 for a sampled
        system: each evaluator's point minus its centre).
    lam_p, res_p_re, res_p_im, d_p, markov_p : (n_p,), (n_p, q m) float64 twice, (q m,),
        (r_p, q m)
        The plant's poles, residues (real and imaginary parts; rows of the q x m transfer from
        the m torques to the q measurements, row-major), feedthrough and rigid-body Markov
        parameters (r_p = 0: none).
    lam_c, res_c_re, res_c_im, d_c, markov_c
        The controller's, from the q measurements to the m torques (m x q, row-major).
    L : (f, m, m)
        Output.
    """
    f = sp.shape[0]
    m = L.shape[1]
    qm = d_p.shape[0]
    q = qm // m
    P_re = np.empty(qm * _BLOCK)
    P_im = np.empty(qm * _BLOCK)
    K_re = np.empty(qm * _BLOCK)
    K_im = np.empty(qm * _BLOCK)
    acc_re = np.empty(_BLOCK)
    acc_im = np.empty(_BLOCK)
    for i0 in range(0, f, _BLOCK):
        nb = min(_BLOCK, f - i0)
        _modal_sums(sp[i0:i0 + nb], lam_p, res_p_re, res_p_im, d_p, markov_p, P_re, P_im, nb)
        _modal_sums(sc[i0:i0 + nb], lam_c, res_c_re, res_c_im, d_c, markov_c, K_re, K_im, nb)
        for a in range(m):
            for b in range(m):
                for t in range(nb):
                    acc_re[t] = 0.0
                    acc_im[t] = 0.0
                for c in range(q):
                    ok = (a * q + c) * _BLOCK
                    op = (c * m + b) * _BLOCK
                    for t in range(nb):
                        kr = K_re[ok + t]
                        ki = K_im[ok + t]
                        pr = P_re[op + t]
                        pi = P_im[op + t]
                        acc_re[t] += kr * pr - ki * pi
                        acc_im[t] += kr * pi + ki * pr
                for t in range(nb):
                    L[i0 + t, a, b] = complex(-acc_re[t], -acc_im[t])


@cached_njit(error_model="numpy")
def sensitivity(L, S):
    """Write S = (I + L)^-1 of m x m loops L (f, m, m) into ``S`` (f, m, m).

    From the LU factors of I + L with partial pivoting (pivots by |Re| + |Im|, as LAPACK's
    zgetrf), solved for each unit vector: the factorisation numpy's inverse uses, at a few
    flops per frequency and without its per-call cost. A closed-form adjugate is no
    substitute: beside an undamped pole L is nearly rank one and huge, and the loop-at-a-time
    functions 1 / S_ii - 1 from its 2 x 2 minors lose about eps |L| relative (measured 3e-5
    against 6e-11 with pivoting at |L| ~ 1e9). NaN or infinite where a pivot is zero
    (I + L singular).
    """
    m = L.shape[1]
    R = np.empty((m, m), dtype=np.complex128)
    x = np.empty(m, dtype=np.complex128)
    perm = np.empty(m, dtype=np.int64)
    for i in range(L.shape[0]):
        for a in range(m):
            perm[a] = a
            for b in range(m):
                R[a, b] = L[i, a, b]
            R[a, a] += 1.0
        # P (I + L) = L U: unit lower L stored below the diagonal, U on and above it
        for c in range(m):
            best = c
            size = abs(R[c, c].real) + abs(R[c, c].imag)
            for a in range(c + 1, m):
                v = abs(R[a, c].real) + abs(R[a, c].imag)
                if v > size:
                    best, size = a, v
            if best != c:
                for b in range(m):
                    t = R[c, b]
                    R[c, b] = R[best, b]
                    R[best, b] = t
                t2 = perm[c]
                perm[c] = perm[best]
                perm[best] = t2
            pivot = _inverse(R[c, c])
            for a in range(c + 1, m):
                factor = R[a, c] * pivot
                R[a, c] = factor
                for b in range(c + 1, m):
                    R[a, b] -= factor * R[c, b]
        for a in range(m):
            # column a of the inverse: L U x = P e_a
            for b in range(m):
                x[b] = 1.0 if perm[b] == a else 0.0
            for b in range(1, m):
                for c in range(b):
                    x[b] -= R[b, c] * x[c]
            for b in range(m - 1, -1, -1):
                for c in range(b + 1, m):
                    x[b] -= R[b, c] * x[c]
                x[b] = x[b] * _inverse(R[b, b])
            for b in range(m):
                S[i, b, a] = x[b]


@cached_njit(error_model="numpy")
def unit_circle_count(L, error_factor, count):
    """Write into ``count`` (f,) the number of eigenvalues outside the unit circle of each
    2 x 2 or 3 x 3 matrix of L (f, m, m) where it is decided without eigenvalues: 0 where
    ||L||_F < 1; else m - k where the term c_k z^k of det(z I - L) dominates on the circle
    (Rouche's theorem, each |c_k| taken with its rounding bound ``error_factor`` times the sum
    of the moduli of its products; :func:`controllers.margins._outside_unit_circle`, the same
    arithmetic); -1 where undecided, -2 where L is not finite."""
    m = L.shape[1]
    size = np.empty(4)
    error = np.empty(4)
    for i in range(L.shape[0]):
        finite = True
        frobenius = 0.0
        for a in range(m):
            for b in range(m):
                v = L[i, a, b]
                if not (np.isfinite(v.real) and np.isfinite(v.imag)):
                    finite = False
                frobenius += v.real * v.real + v.imag * v.imag
        if not finite:
            count[i] = -2
            continue
        if np.sqrt(frobenius) < 1.0:
            count[i] = 0
            continue
        if m == 3:
            l00, l01, l02 = L[i, 0, 0], L[i, 0, 1], L[i, 0, 2]
            l10, l11, l12 = L[i, 1, 0], L[i, 1, 1], L[i, 1, 2]
            l20, l21, l22 = L[i, 2, 0], L[i, 2, 1], L[i, 2, 2]
            m12 = l11 * l22 - l12 * l21
            a12 = abs(l11) * abs(l22) + abs(l12) * abs(l21)
            m02 = l00 * l22 - l02 * l20
            a02 = abs(l00) * abs(l22) + abs(l02) * abs(l20)
            m01 = l00 * l11 - l01 * l10
            a01 = abs(l00) * abs(l11) + abs(l01) * abs(l10)
            n12 = l10 * l22 - l12 * l20
            b12 = abs(l10) * abs(l22) + abs(l12) * abs(l20)
            n11 = l10 * l21 - l11 * l20
            b11 = abs(l10) * abs(l21) + abs(l11) * abs(l20)
            det = l00 * m12 - l01 * n12 + l02 * n11
            size[0] = abs(det)
            size[1] = abs(m01 + m02 + m12)
            size[2] = abs(l00 + l11 + l22)
            error[0] = error_factor * (abs(l00) * a12 + abs(l01) * b12 + abs(l02) * b11)
            error[1] = error_factor * (a01 + a02 + a12)
            error[2] = error_factor * (abs(l00) + abs(l11) + abs(l22))
        else:
            l00, l01, l10, l11 = L[i, 0, 0], L[i, 0, 1], L[i, 1, 0], L[i, 1, 1]
            size[0] = abs(l00 * l11 - l01 * l10)
            size[1] = abs(l00 + l11)
            error[0] = error_factor * (abs(l00) * abs(l11) + abs(l01) * abs(l10))
            error[1] = error_factor * (abs(l00) + abs(l11))
        size[m] = 1.0
        error[m] = 0.0
        total = 0.0
        for k in range(m + 1):
            total += size[k] + error[k]
        decided = -1
        for k in range(m + 1):
            if (size[k] - error[k]) > total - (size[k] + error[k]):
                decided = m - k
        count[i] = decided


_ULP = 2.220446049250313e-16      # LAPACK's dlamch('P'): the unit round-off times the base
_MAX_SWEEPS = 30                  # QR steps per eigenvalue before it counts as not converged


@cached_njit(error_model="numpy", inline="always")
def _cabs1(x):
    """|Re x| + |Im x| (LAPACK's cabs1)."""
    return abs(x.real) + abs(x.imag)


@cached_njit(error_model="numpy", inline="always")
def _balance(H, m):
    """Scale H in place by a diagonal similarity of powers of two (exact) until each row and
    column have comparable off-diagonal sizes (LAPACK's zgebal without permutations; Parlett &
    Reinsch's rule: scale by f where (c f + r / f) < 0.95 (c + r))."""
    radix = 2.0
    for _ in range(64):
        converged = True
        for i in range(m):
            c = 0.0
            r = 0.0
            for j in range(m):
                if j != i:
                    c += _cabs1(H[j, i])
                    r += _cabs1(H[i, j])
            if c == 0.0 or r == 0.0:
                continue
            g = r / radix
            f = 1.0
            s = c + r
            while c < g and f < 1e150:
                f *= radix
                c *= radix * radix
            g = r * radix
            while c >= g and f > 1e-150:
                f /= radix
                c /= radix * radix
            if (c + r) / f < 0.95 * s:
                converged = False
                for j in range(m):
                    H[i, j] = H[i, j] / f
                    H[j, i] = H[j, i] * f
        if converged:
            break


@cached_njit(error_model="numpy", inline="always")
def _hessenberg(H, m):
    """Reduce H to upper Hessenberg form in place by unitary Householder similarities
    H <- P H P, P = I - 2 v v^H / (v^H v) zeroing column k below its subdiagonal."""
    v = np.empty(m, dtype=np.complex128)
    for k in range(m - 2):
        norm = 0.0
        for a in range(k + 1, m):
            norm += H[a, k].real * H[a, k].real + H[a, k].imag * H[a, k].imag
        norm = np.sqrt(norm)
        tail = 0.0
        for a in range(k + 2, m):
            tail += _cabs1(H[a, k])
        if tail == 0.0:
            continue
        x0 = H[k + 1, k]
        phase = x0 / abs(x0) if x0 != 0 else complex(1.0, 0.0)
        for a in range(m):
            v[a] = 0.0
        v[k + 1] = x0 + phase * norm
        for a in range(k + 2, m):
            v[a] = H[a, k]
        vv = 0.0
        for a in range(k + 1, m):
            vv += v[a].real * v[a].real + v[a].imag * v[a].imag
        beta = 2.0 / vv
        # P H: rows k+1.., every column
        for b in range(m):
            dot = complex(0.0, 0.0)
            for a in range(k + 1, m):
                dot += v[a].conjugate() * H[a, b]
            dot *= beta
            for a in range(k + 1, m):
                H[a, b] -= v[a] * dot
        # (P H) P: columns k+1.., every row
        for a in range(m):
            dot = complex(0.0, 0.0)
            for b in range(k + 1, m):
                dot += H[a, b] * v[b]
            dot *= beta
            for b in range(k + 1, m):
                H[a, b] -= dot * v[b].conjugate()
        for a in range(k + 2, m):
            H[a, k] = 0.0


@cached_njit(error_model="numpy", inline="always")
def _hessenberg_eigenvalues(H, m, lam):
    """The eigenvalues of an upper Hessenberg H (m x m) into lam, by single-shift implicit
    complex QR steps (Wilkinson's shift, an exceptional shift every 10 steps without
    deflation; a subdiagonal entry is set to zero where it is below the unit round-off times
    its two diagonal neighbours, LAPACK zlahqr's classical test). False if some eigenvalue
    did not converge in _MAX_SWEEPS steps (H is then left part-reduced)."""
    hi = m - 1
    steps = 0
    while hi >= 0:
        # the active block [lo, hi]: from the last negligible subdiagonal entry
        lo = hi
        while lo > 0:
            h = _cabs1(H[lo, lo - 1])
            if h <= _ULP * (_cabs1(H[lo - 1, lo - 1]) + _cabs1(H[lo, lo])) or h < 1e-300:
                H[lo, lo - 1] = 0.0
                break
            lo -= 1
        if lo == hi:
            lam[hi] = H[hi, hi]
            hi -= 1
            steps = 0
            continue
        steps += 1
        if steps > _MAX_SWEEPS:
            return False
        a = H[hi - 1, hi - 1]
        b = H[hi - 1, hi]
        c = H[hi, hi - 1]
        d = H[hi, hi]
        if steps % 10 == 0:
            shift = d + 0.75 * abs(c.real)
        else:
            # the eigenvalue of the trailing 2 x 2 nearer d: d - b c / (p + q),
            # p = (a - d) / 2, q = sqrt(p^2 + b c) signed so that |p + q| is the larger
            p = 0.5 * (a - d)
            q = np.sqrt(p * p + b * c)
            if (p.real * q.real + p.imag * q.imag) < 0.0:
                q = -q
            pq = p + q
            shift = d - (b * c) / pq if pq != 0 else d
        # one implicit QR step on the active block: the first rotation from the shifted first
        # column, then the bulge chased down the subdiagonal
        for k in range(lo, hi):
            if k == lo:
                x = H[lo, lo] - shift
                y = H[lo + 1, lo]
            else:
                x = H[k, k - 1]
                y = H[k + 1, k - 1]
            ax = abs(x)
            ay = abs(y)
            if ay == 0.0:
                continue
            norm = np.hypot(ax, ay)
            if ax == 0.0:
                cr = 0.0
                s = y.conjugate() / ay
            else:
                cr = ax / norm
                s = (x / ax) * y.conjugate() / norm
            # rows k, k + 1 by G = [[c, s], [-conj(s), c]]
            start = k - 1 if k > lo else lo
            for j in range(start, hi + 1):
                t1 = H[k, j]
                t2 = H[k + 1, j]
                H[k, j] = cr * t1 + s * t2
                H[k + 1, j] = -s.conjugate() * t1 + cr * t2
            if k > lo:
                H[k + 1, k - 1] = 0.0
            # columns k, k + 1 by G^H
            stop = k + 2 if k + 2 < hi else hi
            for i in range(lo, stop + 1):
                t1 = H[i, k]
                t2 = H[i, k + 1]
                H[i, k] = cr * t1 + s.conjugate() * t2
                H[i, k + 1] = -s * t1 + cr * t2
    return True


@cached_njit(error_model="numpy")
def eigenvalues(L, lam, converged):
    """Write the eigenvalues of each small matrix of L (f, m, m), finite, into ``lam`` (f, m)
    and whether they converged into ``converged`` (f,): balanced by powers of two, reduced to
    Hessenberg form by Householder reflections and deflated by shifted complex QR steps, the
    steps of LAPACK's zgeev for the eigenvalues alone (Golub & Van Loan, Matrix Computations,
    4th ed., secs. 7.4-7.5) and as backward stable (each set is that of a matrix within a few
    unit round-offs of L in norm), without its per-matrix cost (a few microseconds a 3 x 3)."""
    m = L.shape[1]
    H = np.empty((m, m), dtype=np.complex128)
    for i in range(L.shape[0]):
        for a in range(m):
            for b in range(m):
                H[a, b] = L[i, a, b]
        _balance(H, m)
        _hessenberg(H, m)
        converged[i] = _hessenberg_eigenvalues(H, m, lam[i])


@cached_njit(error_model="numpy")
def shifted_frobenius(S, shift, out):
    """Write ||S_i - shift I||_F of each matrix of S (f, m, m) into ``out`` (f,) (inf or NaN
    where S_i is not finite), without forming S - shift I."""
    m = S.shape[1]
    for i in range(S.shape[0]):
        total = 0.0
        for a in range(m):
            for b in range(m):
                v = S[i, a, b]
                re = v.real - shift if a == b else v.real
                total += re * re + v.imag * v.imag
        out[i] = np.sqrt(total)
