"""Roots and minima of many real functions refined together, few evaluations each.

The margins of a loop are found on the loop function itself (:mod:`controllers.margins`): the
crossings of |L| = 1 and of the negative real axis are roots, the modulus margin and the
extrema of singular values are minima, each bracketed on a frequency grid. Evaluating the loop
costs much more per call than per point (the exact distributed beam's W(s): a fixed cost of
about a hundred points per call), so :func:`refine` refines every bracket of every function at
once, each iteration one vectorised call at three points per bracket, and converges in a few
iterations:

- a root: while many brackets are left (more than 16: a three-axis loop's hundreds, whose
  points cost more than the calls), each gets one probe, the Illinois step of regula falsi
  (M. Dowell, P. Jarratt, BIT 11, 1971); once few are left, the bracket [a, b]
  (f(a) f(b) < 0) is probed at c - h, c, c + h inside it; it shrinks
  to the sign change nearest c among the five points; the next centre c is the Newton step from
  the middle point with the slope of the outer two (a regula falsi step, or bisection, where
  Newton leaves the bracket, stalls, or nears a pole), the next h half that step, so that the
  three points straddle the root once Newton converges (quadratically): the bracket then
  collapses to about the step's size. It ends at |b - a| <= ROOT_TOLERANCE b. A sign change
  may also be a pass through an undamped pole (f -> +-inf): the bracket then closes in on the
  pole, where f is huge or not finite; such a point is no root and is dropped (|f| must fall
  below 1e-6 of its size at the bracket's ends, or, where f is so steep that the converged
  bracket's ends are not that small, beside a pole, |f| must grow outside the bracket, at
  OUTSIDE_PROBE widths from it, beyond its values at the ends, as it does about a root and
  not about a pole); its refinement stops once |f| at both ends exceeds 1e3 times that size.
- a minimum: the bracket [lo, hi] around the best point x is probed at c - h, c, c + h; the
  best point and the nearest probed points around it become the new bracket; the next centre
  is the vertex of the parabola through the three probes (successive parabolic interpolation,
  Newton's step on f' with f' and f'' from the same points; a ternary step where the parabola
  does not open upwards or leaves the bracket), h at least 1e-4 of the initial half-width
  (below it f'' drowns in round-off). It ends when the parabola through probes near that
  floor predicts no value below the best by more than MINIMUM_VALUE_TOLERANCE (relative), when
  the best point is the probed centre and the next vertex lies within 1e-2 of that floor of it,
  or when hi - lo <= MINIMUM_TOLERANCE x. A minimum whose sign alone is wanted (the extremum
  of a function that may cross zero twice between two grid points, positive at both) also
  ends at a probe below zero, or once the parabola through probes near that floor predicts
  no value below half the best: the value there is then positive by a margin far beyond what
  the same parabola is trusted to for the first rule.

References
----------
J. F. Traub, Iterative Methods for the Solution of Equations, Prentice-Hall 1964 (Newton's
method with difference quotients); R. P. Brent, Algorithms for Minimization without
Derivatives, Prentice-Hall 1973, ch. 5 (successive parabolic interpolation, safeguarded by a
bracket).
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

__all__ = ["ROOT_TOLERANCE", "OUTSIDE_PROBE", "MINIMUM_TOLERANCE", "MINIMUM_VALUE_TOLERANCE", "refine"]

#: Relative width |b - a| / b to which a root's bracket is refined.
ROOT_TOLERANCE = 1e-13
#: Relative width (hi - lo) / x at which a minimum's bracket is taken as converged.
MINIMUM_TOLERANCE = 1e-12
#: A converged root bracket whose end values are not small (f steep there) is told from a pole
#: by |f| at this many bracket widths outside it: larger than at the ends at a root, smaller
#: at a pole.
OUTSIDE_PROBE = 100.0
#: A minimum is also converged when the parabola through probes a local spacing apart predicts
#: no value below the best by more than this, relative (the value is what is wanted).
MINIMUM_VALUE_TOLERANCE = 1e-13
# iterations at most (every iteration at least halves a root's bracket)
_MAX_ITERATIONS = 100
# probes are kept this fraction of their spacing inside the bracket
_INSIDE = 1e-3
# the floor of a minimum's probe spacing, relative to its initial half-width
_MINIMUM_SPACING = 1e-4
# the probes' offsets from their centre, in units of their spacing
_OFFSETS = np.array([-1.0, 0.0, 1.0])
# root brackets are probed three at a time once at most this many are left: until then one
# probe each (the Illinois step), when the points rather than the calls cost; up to this many
# brackets are stepped one by one in Python floats, more in numpy arrays
_FEW = 16
# the probes of no bracket
_NO_PROBES = np.zeros((0, 3))


def _illinois_points(k, a, b, ga, gb, checked, suspect, iteration):
    """The Illinois probe of each root bracket ``k`` (regula falsi on the scaled end values,
    bisection where it leaves the bracket, a bracket fails to halve in three iterations, or a
    pole is suspected): (points (n, 1), bisected)."""
    mid = 0.5 * (a[k] + b[k])
    x = (a[k] * gb[k] - b[k] * ga[k]) / (gb[k] - ga[k])
    bisect = ~((x > a[k]) & (x < b[k]))
    if iteration % 3 == 2:
        bisect |= (b[k] - a[k]) > 0.5 * checked[k]
        checked[k] = b[k] - a[k]
    bisect |= suspect[k]
    return np.where(bisect, mid, x)[:, None], bisect


def _illinois_step(k, x, fx, bisect, a, b, fa, fb, ga, gb, last, scale, suspect, active):
    """One Illinois iteration of the root brackets ``k`` probed at ``x`` (values ``fx``), in
    place (M. Dowell, P. Jarratt, "A modified regula falsi method for computing the root of an
    equation", BIT 11, 1971)."""
    bad = ~np.isfinite(fx)
    if bad.any():
        suspect[k[bad]] = True   # on an undamped pole: bisect from now on
        keep = ~bad
        k, x, fx, bisect = k[keep], x[keep], fx[keep], bisect[keep]
    zero = fx == 0
    right = (np.sign(fx) == np.sign(fb[k])) & ~zero
    left = ~right & ~zero
    kr, kl, kz = k[right], k[left], k[zero]
    # the end kept twice in a row has its value halved (not after bisection)
    ga[kr] = np.where((last[kr] == 1) & ~bisect[right], 0.5 * ga[kr], ga[kr])
    b[kr], fb[kr], gb[kr], last[kr] = x[right], fx[right], fx[right], 1
    gb[kl] = np.where((last[kl] == -1) & ~bisect[left], 0.5 * gb[kl], gb[kl])
    a[kl], fa[kl], ga[kl], last[kl] = x[left], fx[left], fx[left], -1
    # a bisection step restarts regula falsi from the true end values
    if bisect.any():
        kb = k[bisect]
        ga[kb], gb[kb], last[kb] = fa[kb], fb[kb], 0
    if kz.size:
        a[kz] = b[kz] = x[zero]
        fa[kz] = fb[kz] = 0.0
        active[kz] = False
    # |f| inside above both starting ends: an undamped pole is likely in the bracket
    suspect[kr] |= np.abs(fx[right]) > scale[kr]
    suspect[kl] |= np.abs(fx[left]) > scale[kl]
    active[k] &= ((b[k] - a[k]) > ROOT_TOLERANCE * b[k]) & (
        np.minimum(np.abs(fa[k]), np.abs(fb[k])) <= 1e3 * scale[k])


def _probes(centre, spacing, lo, hi) -> np.ndarray:
    """Three probes (n, 3) at centre - spacing, centre, centre + spacing, each kept a fraction
    _INSIDE of the spacing (or of the width, if smaller) inside [lo, hi] (which keeps them in
    order): a root next to an end of its bracket is probed there."""
    inside = _INSIDE * np.minimum(spacing, hi - lo)
    return np.minimum(np.maximum(centre[:, None] + spacing[:, None] * _OFFSETS,
                                 (lo + inside)[:, None]), (hi - inside)[:, None])


def refine(evaluate: Callable[[np.ndarray, np.ndarray], np.ndarray],
           roots: tuple | None = None, minima: tuple | None = None, *,
           guesses: tuple | None = None, sign_only: np.ndarray | None = None
           ) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """Refine root brackets and minimum brackets of many functions together.

    Parameters
    ----------
    evaluate : callable
        ``evaluate(x, task)`` -> real values: function ``task[k]`` at ``x[k]`` (1-D arrays of
        the same size); one call per iteration serves every bracket. Non-finite values are
        allowed (a point on a pole): they carry no information.
    roots : (task, a, b, fa, fb), optional
        Root brackets: arrays of the function index, the ends a < b and the values there,
        fa fb < 0 (finite).
    minima : (task, lo, x, hi, flo, fx, fhi), optional
        Minimum brackets: arrays of the function index, the ends lo < x < hi and the values
        there, fx the least (the function is taken as unimodal in [lo, hi]; flo and fhi only
        place the first probes, they may be approximate).
    guesses : callable, optional
        ``guesses()`` -> (centre, spacing): per root bracket, a first estimate of the root and
        of its error (NaN: none), e.g. from an interpolation of the grid that bracketed it:
        the first three probes are placed there instead of about regula falsi's point a
        quarter of the bracket apart (called only when the brackets are few enough to be
        probed so from the start).
    sign_only : array of bool, optional
        Per minimum bracket (given ``fx > 0``): only whether the minimum lies below zero is
        wanted. Such a bracket also ends at the first probe below zero (returned as its
        point), or once the local parabola predicts no value below half the best (module
        docstring); its point and value are then the best found, not the converged minimum.

    Returns
    -------
    (root, found), (x, fx)
        Per root bracket: the root (the end of the final bracket with the smaller |f|) and
        whether it is one (False: the bracket closed in on a pole); per minimum bracket: the
        best point and its value (never worse than the given one).
    """
    empty = np.zeros(0)
    rt, a, b, fa, fb = ((np.asarray(v) for v in roots) if roots is not None
                        else (np.zeros(0, dtype=int), empty, empty, empty, empty))
    mt, lo, xm, hi, flo, fm, fhi = ((np.asarray(v) for v in minima) if minima is not None
                                    else (np.zeros(0, dtype=int),) + (empty,) * 6)
    a, b, fa, fb = (np.array(v, dtype=float) for v in (a, b, fa, fb))
    lo, xm, hi, flo, fm, fhi = (np.array(v, dtype=float) for v in (lo, xm, hi, flo, fm, fhi))
    rt, mt = np.asarray(rt, dtype=int), np.asarray(mt, dtype=int)
    nr = a.size
    sign = (np.zeros(mt.size, dtype=bool) if sign_only is None
            else np.asarray(sign_only, dtype=bool).reshape(-1))
    if sign.size != mt.size:
        raise ValueError(f"sign_only must have one entry per minimum bracket ({mt.size}); got "
                         f"{sign.size}")

    with np.errstate(all="ignore"):
        scale = np.maximum(np.abs(fa), np.abs(fb))
        r_active = (b - a) > ROOT_TOLERANCE * b
        # roots, many brackets: the Illinois state (scaled end values, the end moved last,
        # the width at the last halving check, a pole suspected)
        ga, gb = fa.copy(), fb.copy()
        last = np.zeros(nr, dtype=int)
        checked = b - a
        suspect = np.zeros(nr, dtype=bool)
        # roots, few brackets: the centre and spacing of the three probes
        c, h = np.zeros(nr), np.zeros(nr)
        stalls = np.zeros(nr, dtype=int)
        newton = False
        # minima: the first centre at the vertex of the parabola through the bracket (at x if
        # it has none inside), the spacing's floor from the bracket
        d0, d1 = (fm - flo) / (xm - lo), (fhi - fm) / (hi - xm)
        curvature = (d1 - d0) / (hi - lo)
        vertex = 0.5 * (lo + xm) - 0.5 * d0 / curvature
        inside = np.isfinite(vertex) & (curvature > 0) & (vertex > lo) & (vertex < hi)
        cm = np.where(inside, vertex, xm)
        hm = np.where(inside, np.abs(vertex - xm), 0.25 * np.minimum(xm - lo, hi - xm))
        hm = np.minimum(hm, 0.5 * np.minimum(cm - lo, hi - cm))
        floor = np.maximum(_MINIMUM_SPACING * 0.5 * (hi - lo), 0.5 * MINIMUM_TOLERANCE * xm)
        m_active = (hi - lo) > MINIMUM_TOLERANCE * xm

        for iteration in range(_MAX_ITERATIONS):
            kr, km = np.nonzero(r_active)[0], np.nonzero(m_active)[0]
            if kr.size == 0 and km.size == 0:
                break
            if not newton and kr.size <= _FEW:
                # from now on three probes per bracket, starting from regula falsi
                newton = True
                c = (a * fb - b * fa) / (fb - fa)
                c = np.where((c > a) & (c < b), c, 0.5 * (a + b))
                h = 0.25 * (b - a)
                checked = b - a
                if guesses is not None and iteration == 0:
                    c0, h0 = (np.asarray(v, dtype=float) for v in guesses())
                    use = (c0 > a) & (c0 < b) & (h0 >= 0) & (h0 < 0.25 * (b - a))
                    c = np.where(use, c0, c)
                    h = np.where(use, np.maximum(h0, ROOT_TOLERANCE * b), h)
            pm = _probes(cm[km], hm[km], lo[km], hi[km]) if km.size else _NO_PROBES
            if not kr.size:
                pr = _NO_PROBES
            elif newton:
                pr = _probes(c[kr], h[kr], a[kr], b[kr])
            else:
                pr, bisect = _illinois_points(kr, a, b, ga, gb, checked, suspect, iteration)
            per = pr.shape[1]
            if not km.size:
                x, task = pr.ravel(), np.repeat(rt[kr], per)
            elif not kr.size:
                x, task = pm.ravel(), np.repeat(mt[km], 3)
            else:
                x = np.concatenate([pr.ravel(), pm.ravel()])
                task = np.concatenate([np.repeat(rt[kr], per), np.repeat(mt[km], 3)])
            values = np.asarray(evaluate(x, task), dtype=float)
            fr = values[:per * kr.size].reshape(-1, per)
            fmp = values[per * kr.size:].reshape(-1, 3)
            if kr.size and newton:
                _root_step(kr, pr, fr, a, b, fa, fb, c, h, scale, checked, stalls, r_active,
                           iteration)
            elif kr.size:
                _illinois_step(kr, pr[:, 0], fr[:, 0], bisect, a, b, fa, fb, ga, gb, last,
                               scale, suspect, r_active)
            if km.size:
                (_minimum_step if km.size <= _FEW else _minimum_steps)(
                    km, pm, fmp, lo, xm, hi, fm, cm, hm, floor, sign, m_active)

        found = np.where(np.abs(fa) <= np.abs(fb), a, b)
        at_root = np.minimum(np.abs(fa), np.abs(fb))
        ok = np.isfinite(at_root) & (at_root <= 1e-6 * scale)
        # a converged bracket whose ends are not small next to the starting ends: a root where f
        # is steep (beside a pole: the slope is about 1/distance) or a pole; outside the
        # bracket, at D = OUTSIDE_PROBE times its width, |f| grows to about |f'| D at a root
        # and falls to about r / D at a pole (r / width or more at the ends)
        doubt = np.nonzero(~ok & np.isfinite(at_root) & (b - a <= 2.0 * ROOT_TOLERANCE * b))[0]
        if doubt.size:
            distance = np.maximum(OUTSIDE_PROBE * (b[doubt] - a[doubt]),
                                  ROOT_TOLERANCE * found[doubt])
            x = np.concatenate([found[doubt] - distance, found[doubt] + distance])
            fx = np.abs(np.asarray(evaluate(x, np.tile(rt[doubt], 2)), dtype=float))
            fx = np.where(np.isfinite(fx), fx, 0.0).reshape(2, -1).max(axis=0)
            ok[doubt] = fx > np.maximum(np.abs(fa[doubt]), np.abs(fb[doubt]))
    return (found, ok), (xm, fm)


# the pairs (a, p0), (p0, p1), (p1, p2), (p2, b) in the order a bracket prefers them: those
# beside the centre probe p1 first
_PAIR_PRIORITY = (1, 0, 0, 1)


def _quotient(x: float, y: float) -> float:
    """x / y of Python floats as numpy divides them: +-inf or NaN where y is zero."""
    if y != 0.0:
        return x / y
    if x == 0.0 or x != x:
        return math.nan
    return math.copysign(math.inf, x) * math.copysign(1.0, y)


def _root_step(k, p, fp, a, b, fa, fb, c, h, scale, checked, stalls, active,
               iteration) -> None:
    """One iteration of the root brackets ``k`` probed at ``p`` (values ``fp``), in place.

    The brackets are few (at most _FEW): each is stepped in Python floats (the arithmetic of
    numpy's elementwise operations, without their per-call cost on arrays of a few entries)."""
    check = iteration % 2 == 1
    rows = zip(k.tolist(), p.tolist(), fp.tolist(), a[k].tolist(), b[k].tolist(),
               fa[k].tolist(), fb[k].tolist(), scale[k].tolist(), checked[k].tolist(),
               stalls[k].tolist())
    for i, (p0, p1, p2), (f0, f1, f2), ai, bi, fai, fbi, si, ci, ti in rows:
        # the bracket: a sign change among a, p0, p1, p2, b (a non-finite value replaced by
        # its left neighbour, point and value), one beside the centre p1 first
        xs, fs = [ai, p0, p1, p2, bi], [fai, f0, f1, f2, fbi]
        for q in range(1, 5):
            if not math.isfinite(fs[q]):
                xs[q], fs[q] = xs[q - 1], fs[q - 1]
        j = 0
        best = 9
        for q in range(4):
            if (fs[q] > 0.0 > fs[q + 1]) or (fs[q] < 0.0 < fs[q + 1]):
                if _PAIR_PRIORITY[q] < best:
                    j, best = q, _PAIR_PRIORITY[q]
        na, nb, nfa, nfb = xs[j], xs[j + 1], fs[j], fs[j + 1]
        # a probe exactly on the root ends its bracket there
        hit = f0 == 0.0 or f1 == 0.0 or f2 == 0.0
        if hit:
            na = nb = p0 if f0 == 0.0 else p1 if f1 == 0.0 else p2
            nfa = nfb = 0.0
        a[i], b[i], fa[i], fb[i] = na, nb, nfa, nfb
        width = nb - na
        # Newton from the middle probe, the slope from the outer two
        step = _quotient(-f1 * (p2 - p0), f2 - f0)
        newton = p1 + step
        # a Newton point just beyond an end (the root at the end, to round-off) is taken at
        # the end: the probes about it then close the bracket from the other side
        good = (na - 0.5 * abs(step) < newton < nb + 0.5 * abs(step)) and abs(f1) <= si
        if check:
            # a bracket that fails to halve in two iterations twice in a row is bisected (a
            # pole, a flat stretch); once, it may be Newton closing in from one side
            ti = ti + 1 if width > 0.5 * ci else 0
            good = good and ti < 2
            stalls[i] = 0 if ti >= 2 else ti
            checked[i] = width
        if good:
            # probes that straddled the root (the bracket between two of them): the next ones
            # half the Newton step apart; else a whole step, the estimate having been further
            # off
            centre = min(max(newton, na), nb)
            spacing = max((0.5 if j in (1, 2) else 1.0) * abs(step), 0.3 * ROOT_TOLERANCE * nb)
        else:
            centre = _quotient(na * nfb - nb * nfa, nfb - nfa)
            if not na < centre < nb:
                centre = 0.5 * (na + nb)
            spacing = 0.25 * width
        c[i], h[i] = centre, min(spacing, 0.5 * width)
        active[i] = (not hit and width > ROOT_TOLERANCE * nb
                     and min(abs(nfa), abs(nfb)) <= 1e3 * si)


def _minimum_step(k, p, fp, lo, x, hi, fx, c, h, floor, sign, active) -> None:
    """One iteration of the minimum brackets ``k`` probed at ``p`` (values ``fp``), in place,
    each in Python floats: for a few brackets (at most _FEW), the arithmetic of numpy's
    elementwise operations without their per-call cost (:func:`_minimum_steps` for many);
    ``sign``: the brackets whose sign alone is wanted (:func:`refine`)."""
    inf = math.inf
    rows = zip(k.tolist(), p.tolist(), fp.tolist(), lo[k].tolist(), x[k].tolist(),
               hi[k].tolist(), fx[k].tolist(), h[k].tolist(), floor[k].tolist(),
               sign[k].tolist())
    for j, (p0, p1, p2), (f0, f1, f2), lj, xj, hj, fj, sj, floor_j, sign_j in rows:
        # the best of the known point and the probes (a non-finite value: none; ties keep the
        # known best, as np.argmin the first)
        points = (xj, p0, p1, p2)
        candidates = (fj, f0 if math.isfinite(f0) else inf, f1 if math.isfinite(f1) else inf,
                      f2 if math.isfinite(f2) else inf)
        i = 0
        if fj == fj:
            for q in (1, 2, 3):
                if candidates[q] < candidates[i]:
                    i = q
        best, fbest = points[i], candidates[i]
        # the new bracket: the nearest points on either side of the best
        below, above = -inf, inf
        for point in (lj, hj, xj, p0, p1, p2):
            if best > point > below:
                below = point
            if best < point < above:
                above = point
        nlo = below if math.isfinite(below) else lj
        nhi = above if math.isfinite(above) else hj
        # the vertex of the parabola through the probes (Newton on f' with f', f'' from them)
        d01, d12 = _quotient(f1 - f0, p1 - p0), _quotient(f2 - f1, p2 - p1)
        curvature = _quotient(d12 - d01, p2 - p0)
        vertex = 0.5 * (p0 + p1) - _quotient(0.5 * d01, curvature)
        good = (math.isfinite(vertex) and math.isfinite(curvature) and curvature > 0.0
                and nlo < vertex < nhi)
        converged = False
        if good:
            step = abs(vertex - p1)
            # converged: the parabola through probes a local spacing apart predicts no value
            # below the best beyond round-off (the value is what is wanted), or the vertex is
            # the best probe
            predicted = f0 + d01 * (vertex - p0) + curvature * (vertex - p0) * (vertex - p1)
            converged = ((sj <= 100.0 * floor_j
                          and fbest - predicted <= MINIMUM_VALUE_TOLERANCE * abs(fbest))
                         or (i == 2 and step <= 1e-2 * floor_j)
                         or (sign_j and sj <= 100.0 * floor_j and predicted >= 0.5 * fbest))
            centre, spacing = vertex, max(step, floor_j)
        else:
            centre, spacing = best, 0.25 * (nhi - nlo)
        # the sign alone wanted: a value below zero settles it
        converged = converged or (sign_j and fbest < 0.0)
        lo[j], hi[j], x[j], fx[j] = nlo, nhi, best, fbest
        c[j] = centre
        h[j] = min(spacing, 0.5 * (nhi - nlo))
        active[j] = not converged and (nhi - nlo) > MINIMUM_TOLERANCE * best


def _minimum_steps(k, p, fp, lo, x, hi, fx, c, h, floor, sign, active) -> None:
    """One iteration of the minimum brackets ``k`` probed at ``p`` (values ``fp``), in place,
    vectorised: :func:`_minimum_step`'s arithmetic on many brackets at once."""
    rows = np.arange(k.size)
    values = np.where(np.isfinite(fp), fp, np.inf)
    points = np.column_stack([x[k], p])
    candidates = np.column_stack([fx[k], values])
    i = np.argmin(candidates, axis=1)          # ties keep the known best
    best, fbest = points[rows, i], candidates[rows, i]
    # the new bracket: the nearest points on either side of the best
    everything = np.column_stack([lo[k], hi[k], points])
    below = np.where(everything < best[:, None], everything, -np.inf).max(axis=1)
    above = np.where(everything > best[:, None], everything, np.inf).min(axis=1)
    nlo = np.where(np.isfinite(below), below, lo[k])
    nhi = np.where(np.isfinite(above), above, hi[k])
    # the vertex of the parabola through the probes (Newton on f' with f', f'' from them)
    p0, p1, p2 = p[:, 0], p[:, 1], p[:, 2]
    f0, f1, f2 = fp[:, 0], fp[:, 1], fp[:, 2]
    d01, d12 = (f1 - f0) / (p1 - p0), (f2 - f1) / (p2 - p1)
    curvature = (d12 - d01) / (p2 - p0)
    vertex = 0.5 * (p0 + p1) - 0.5 * d01 / curvature
    good = (np.isfinite(vertex) & np.isfinite(curvature) & (curvature > 0)
            & (vertex > nlo) & (vertex < nhi))
    step = np.abs(vertex - p1)
    # converged: the parabola through probes a local spacing apart predicts no value below
    # the best beyond round-off (the value is what is wanted), or the vertex is the best probe
    predicted = f0 + d01 * (vertex - p0) + curvature * (vertex - p0) * (vertex - p1)
    local = h[k] <= 100.0 * floor[k]
    converged = good & ((local & (fbest - predicted <= MINIMUM_VALUE_TOLERANCE * np.abs(fbest)))
                        | ((i == 2) & (step <= 1e-2 * floor[k])))
    # the sign alone wanted: a value below zero settles it, or a local parabola whose least
    # value is above half the best
    wanted = sign[k]
    converged |= wanted & ((fbest < 0.0) | (good & local & (predicted >= 0.5 * fbest)))
    centre = np.where(good, vertex, best)
    spacing = np.where(good, np.maximum(step, floor[k]), 0.25 * (nhi - nlo))
    lo[k], hi[k], x[k], fx[k] = nlo, nhi, best, fbest
    c[k] = centre
    h[k] = np.minimum(spacing, 0.5 * (nhi - nlo))
    active[k] = ~converged & ((nhi - nlo) > MINIMUM_TOLERANCE * best)
