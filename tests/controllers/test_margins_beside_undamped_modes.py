"""Margins never more optimistic than the truth beside undamped and lightly damped modes.

An undamped mode makes |L| infinite at its frequency, so |L| = 1 is crossed on both sides of
it, as close to it as the mode's residue is small (a mode the loop barely feels: 1e-11 of the
frequency on the three-axis example of benchmarks/three_axis.py), with a phase margin set by
the residue's phase, often a fraction of a degree. Such crossings were lost in two ways: the
grid put no point close enough to the pole to bracket them, and a bracket refined to 1e-13 of
the frequency, where log|L| is so steep that its ends stay far from 0, was dropped as a pole
(with more than 16 brackets open, the three axes' case). The reference here is independent of
the grid and of the refinement: a dense scan of the same loop function (a logarithmic grid
plus a geometric ladder of points down to 1e-13 of the frequency on both sides of every pole),
whose crossings bound the true margins from above.
"""
import cmath
import math

import numpy as np
import pytest
from scipy.optimize import brentq

import controllers
from controllers.loop import LoopTransfer
from controllers.margins import loop_margins
from controllers.refine import ROOT_TOLERANCE, refine
from plants import modal_plant, three_axis_plant


def test_steep_roots_beside_poles_are_roots_with_many_brackets_open():
    """log|c + r / (x - p)| = 0 at x = p + r / (1 - c) and p - r / (1 + c) (closed form, c in
    (0, 1), r > 0): 20 such functions, 40 brackets (more than 16: one probe each), r down to
    1e-9 p, where the slope at the root is about 1 / r. Every root is found (before: the
    steepest were dropped as poles), to the stopping width (rtol 2e-13: the root is an end of
    a bracket 1e-13 x wide)."""
    rng = np.random.default_rng(1)
    n = 20
    p = np.sort(rng.uniform(10.0, 1000.0, n))
    c = rng.uniform(0.05, 0.9, n)
    r = p * 10.0 ** rng.uniform(-9.0, -4.0, n)

    def f(x, task):
        with np.errstate(divide="ignore"):
            return np.log(np.abs(c[task] + r[task] / (x - p[task])))

    right, left = p + r / (1 - c), p - r / (1 + c)
    task = np.concatenate([np.arange(n), np.arange(n)])
    # brackets from inside the other root, across the pole (f = +inf there: the refinement
    # bisects), to well beyond the root, as a grid brackets a crossing beside an undamped mode
    a = np.concatenate([p - 0.1 * (p - left), p - 10.0 * (p - left)])
    b = np.concatenate([p + 10.0 * (right - p), p + 0.1 * (right - p)])
    fa, fb = f(a, task), f(b, task)
    assert np.all(fa * fb < 0)
    (root, found), _ = refine(f, roots=(task, a, b, fa, fb))
    assert found.all()
    np.testing.assert_allclose(root, np.concatenate([right, left]), rtol=2 * ROOT_TOLERANCE,
                               atol=0)


def test_a_pole_is_still_no_root_when_the_function_is_steep():
    """tan(x) (a pole at pi/2) and 1e-9 / (x - 2) (a pole at 2, small residue) change sign
    at their poles only: no root found; tan's root at pi is."""
    def f(x, task):
        return np.where(task == 0, np.tan(x), 1e-9 / (x - 2.0))

    task = np.array([0, 0, 1])
    a, b = np.array([1.4, 3.0, 1.9]), np.array([1.7, 3.3, 2.1])
    (root, found), _ = refine(f, roots=(task, a, b, f(a, task), f(b, task)))
    assert found.tolist() == [False, True, False]


def _pole_ladder(poles, lo, hi):
    """Points about each pole frequency down to 1e-13 of it, both sides, and across the
    half-power band of the damped ones."""
    w = np.abs(poles[poles.imag > 0])
    zeta = -poles[poles.imag > 0].real / w
    steps = np.geomspace(1e-13, 1e-2, 400)
    out = [np.concatenate([wk * (1 - steps), wk * (1 + steps),
                           wk * (1 + max(z, 1e-9) * np.tan(np.linspace(-1.55, 1.55, 801)))])
           for wk, z in zip(w, zeta)]
    points = np.concatenate(out) if out else np.zeros(0)
    return points[(points > lo) & (points < hi)]


def _dense_margins(f, omega, poles):
    """(min |PM| [deg], min |GM| [dB], min |1 + L|) of the scalar loop function f on the
    increasing dense grid omega. Every sign change of log|L| is a gain crossover (log|L| has no
    sign-changing pole); a sign change of Im L with Re L < 0 at both ends and no pole between
    is a phase crossover; each is refined by scipy's brentq (an independent root finder) and
    the margin taken there."""
    def value(x):
        with np.errstate(all="ignore"):
            return complex(f(np.array([x]))[0])

    with np.errstate(all="ignore"):
        L = f(omega)
    ok = np.isfinite(L)
    omega, L = omega[ok], L[ok]
    g = np.log(np.abs(L))
    pm = [np.inf]
    for i in np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0)[0]:
        x = brentq(lambda w: math.log(abs(value(w))), omega[i], omega[i + 1], xtol=1e-300,
                   rtol=1e-15)
        pm.append(abs(math.degrees(cmath.phase(-value(x)))))
    im = L.imag
    k = np.nonzero((np.sign(im[:-1]) * np.sign(im[1:]) < 0) & (L.real[:-1] < 0)
                   & (L.real[1:] < 0))[0]
    pole_w = np.sort(np.abs(poles.imag))
    k = k[np.searchsorted(pole_w, omega[k]) == np.searchsorted(pole_w, omega[k + 1])]
    gm = [np.inf]
    for i in k:
        x = brentq(lambda w: value(w).imag, omega[i], omega[i + 1], xtol=1e-300, rtol=1e-15)
        gm.append(abs(20 * math.log10(abs(value(x)))))
    return min(pm), min(gm), float(np.abs(1 + L).min())


def _random_modes(rng, n_modes, scale):
    """(w, zeta, b, c) of n_modes modes: frequencies 2 to 300 times the bandwidth, half of
    them undamped, the others zeta 1e-6 to 1e-3, non-collocated (b and c of either sign), some
    barely felt (residues down to 1e-14)."""
    w = np.sort(scale * 10.0 ** rng.uniform(math.log10(2.0), math.log10(300.0), n_modes))
    zeta = np.where(rng.random(n_modes) < 0.5, 0.0, 10.0 ** rng.uniform(-6, -3, n_modes))
    b = rng.choice([-1.0, 1.0], n_modes) * 10.0 ** rng.uniform(-7.0, -1.0, n_modes)
    c = rng.choice([-1.0, 1.0], n_modes) * 10.0 ** rng.uniform(-7.0, 0.0, n_modes)
    return list(zip(w, zeta, b, c))


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(6))
def test_planar_margins_never_above_a_dense_scan(seed):
    """Random planar loops (a PD with roll-off, its phase near -90 deg at the modes so that
    the loop's is near 0 or 180 deg there, tuned on the rigid hub, closed on the hub with 14 lightly
    damped, non-collocated modes, stable or not: margins are defined either way): the
    reported phase, gain and modulus margins are never above the dense scan's minimum.
    Tolerances: 1e-3 deg and 1e-3 dB (brentq's crossings to 1e-15 relative in frequency; at a
    crossing 1e-13 from a pole a relative frequency error of 1e-15 moves |L| by 1 %, the phase
    little); |1 + L| 1e-5 relative: within 1e-13 of an undamped pole L is evaluated only to
    about eps / 1e-13 of the pole's term (the difference w - w0 of two nearly equal numbers),
    and the scan takes its least value, round-off included."""
    rng = np.random.default_rng(seed)
    plant = modal_plant(100.0, _random_modes(rng, 14, 0.1), disturbance=False)
    K = controllers.pd(modal_plant(100.0, disturbance=False), natural_frequency=0.1,
                       damping=0.7, roll_off=0.5)
    m = controllers.margins(plant, K)
    loop = LoopTransfer(plant, K)
    grid = loop.grid()
    poles = np.concatenate([loop.plant_ev.poles(), loop.controller_ev.poles()])
    omega = np.unique(np.concatenate([np.geomspace(grid[0], grid[-1], 200_000),
                                      _pole_ladder(poles, grid[0], grid[-1])]))
    pm, gm, mm = _dense_margins(loop, omega, poles)
    assert abs(m.phase_margin) <= pm + 1e-3
    assert abs(m.gain_margin) <= gm + 1e-3
    assert m.modulus_margin <= mm * (1 + 1e-5)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(3))
def test_three_axis_margins_never_above_a_dense_scan(seed):
    """Random three-axis loops (a PD with roll-off tuned on a full-inertia rigid hub, closed on it with 12
    lightly damped modes
    participating in every axis, more than 16 crossings open): each loop-at-a-time margin is
    never above the dense scan of its L_i, and the disk margin and the smallest singular value
    of I + L never above what the loop-at-a-time functions prove (sigma_min(I + L) <= |1 + L_i|,
    alpha <= 2 |1 + L_i| / (2 - |1 + L_i|)); tolerances as in the planar test."""
    rng = np.random.default_rng(100 + seed)
    J = np.array([[950.0, 12.0, -8.0], [12.0, 780.0, 15.0], [-8.0, 15.0, 640.0]])
    modes = [(w, z, b * rng.normal(size=3), c * rng.normal(size=3))
             for w, z, b, c in _random_modes(rng, 12, 0.1)]
    plant = three_axis_plant(J, modes)
    K = controllers.pd(three_axis_plant(J), natural_frequency=0.1, damping=0.7, roll_off=0.5)
    m = controllers.margins(plant, K)
    loop = LoopTransfer(plant, K)
    grid = loop.grid()
    poles = np.concatenate([loop.plant_ev.poles(), loop.controller_ev.poles(),
                            loop.loop_at_a_time_poles()])
    omega = np.unique(np.concatenate([np.geomspace(grid[0], grid[-1], 100_000),
                                      _pole_ladder(poles, grid[0], grid[-1])]))
    smallest = math.inf
    for i, axis in enumerate("xyz"):
        pm, gm, mm = _dense_margins(lambda w: loop.broken(w, i), omega, poles)
        mi = m.loop_at_a_time[axis]
        assert abs(mi.phase_margin) <= pm + 1e-3
        assert abs(mi.gain_margin) <= gm + 1e-3
        assert mi.modulus_margin <= mm * (1 + 1e-5)
        smallest = min(smallest, mm)
    assert m.min_singular_value <= smallest * (1 + 1e-5)
    assert m.disk_margin <= 2 * smallest / (2 - smallest) * (1 + 1e-5)


@pytest.mark.parametrize("undamped, error", [([-1.0], ValueError), ([np.nan], ValueError),
                                             ("fast", TypeError)])
def test_undamped_frequencies_are_checked(undamped, error):
    """loop_margins' undamped pole frequencies: positive and finite [rad/s], by name."""
    omega = np.geomspace(0.01, 100.0, 50)
    with pytest.raises(error, match="undamped"):
        loop_margins(lambda w: 1.0 / (1j * w) ** 2, omega, undamped=undamped)
