"""Roots and minima refined together in few vectorised calls (controllers.refine), and the
margins built on them: against closed forms, against a brute-force scan of the function, and
against the margins the previous one-point-at-a-time search gave (scipy's bounded Brent for the
minima: several times the calls, and on a three-axis loop with undamped modes a local minimum
0.5 % above the one found now)."""
import math

import numpy as np
import pytest

import controllers
from controllers.loop import LoopTransfer
from controllers.margins import _refined_extremum, loop_margins
from controllers.refine import MINIMUM_TOLERANCE, ROOT_TOLERANCE, refine
from plants import three_axis_plant


def _brackets(f, grid):
    values = f(grid, np.zeros(grid.size, dtype=int))
    i = np.nonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)[0]
    return (np.zeros(i.size, dtype=int), grid[i], grid[i + 1], values[i], values[i + 1])


@pytest.mark.parametrize("n_brackets", [3, 40])
def test_roots_to_the_stopping_width_with_few_and_many_brackets(n_brackets):
    """sin(x) on (0.5, (n + 0.5) pi): roots k pi (closed form). Below 16 brackets three probes
    each (Newton), above one each (Illinois) until few are left: either way to the stopping
    width 1e-13 b (rtol 2e-13: the root is an end of a bracket that narrow), and in few calls
    (the old loop: about 10)."""
    calls = []

    def f(x, task):
        calls.append(x.size)
        return np.sin(x)

    grid = np.linspace(0.5, (n_brackets + 0.5) * math.pi, 7 * n_brackets)
    brackets = _brackets(f, grid)
    calls.clear()
    (root, found), _ = refine(f, roots=brackets)
    assert found.all() and root.size == n_brackets
    np.testing.assert_allclose(root, math.pi * np.arange(1, n_brackets + 1), rtol=2e-13, atol=0)
    assert len(calls) <= (8 if n_brackets < 16 else 16)
    assert all(n <= 3 * n_brackets for n in calls)


def test_a_pass_through_a_pole_is_no_root():
    """tan(x) changes sign at pi/2 (a pole) and at pi (a root): only the root is kept."""
    f = lambda x, task: np.tan(x)  # noqa: E731
    (root, found), _ = refine(f, roots=([0, 0], [1.4, 3.0], [1.7, 3.3],
                                        [math.tan(1.4), math.tan(3.0)],
                                        [math.tan(1.7), math.tan(3.3)]))
    assert found.tolist() == [False, True]
    assert root[1] == pytest.approx(math.pi, rel=2e-13, abs=0)


@pytest.mark.parametrize("width", [1e-1, 1e-4, 1e-7])
def test_a_minimum_of_any_sharpness_to_round_off_in_value(width):
    """|1 + L| near a resonance of relative half-width ``width`` (zeta = width): the minimum
    over the bracket, found on the function, is its closed-form value to round-off (1e-14)
    and no brute-force scan of 2e5 points about it finds a lower one."""
    zeta = width

    def g(w):
        # 1 - w^2 as (1 - w)(1 + w): no cancellation near the resonance, L to round-off
        T = 2j * zeta * w / ((1.0 - w) * (1.0 + w) + 2j * zeta * w)
        return np.abs(0.3 - 0.5 * T)  # |1 + L|, L = -0.5 T - 0.7

    grid = np.concatenate([np.geomspace(0.1, 10.0, 200), 1.0 + zeta * np.tan(np.linspace(
        -1.45, 1.45, 40))])
    grid = np.unique(grid)
    values = g(grid)
    i = int(np.argmin(values))
    calls = []

    def f(x, task):
        calls.append(x.size)
        return g(x)

    _, (x, fx) = refine(f, minima=([0], [grid[i - 1]], [grid[i]], [grid[i + 1]],
                                   [values[i - 1]], [values[i]], [values[i + 1]]))
    scan = np.linspace(x[0] * (1 - 2 * zeta), x[0] * (1 + 2 * zeta), 200001)
    assert fx[0] <= values[i] and g(x)[0] == fx[0]
    assert fx[0] <= g(scan).min() * (1 + 1e-14)
    # closed form: L runs on the circle of centre -0.95, radius 0.25 (T on |T - 1/2| = 1/2),
    # nearest to -1 at w = 1 (T = 1): |1 + L| = 0.2
    assert fx[0] == pytest.approx(0.2, rel=1e-14, abs=0)
    assert len(calls) <= 12 and all(n == 3 for n in calls)


def test_refined_extremum_finds_a_maximum_between_grid_points():
    """A Lorentzian peak 1 / ((x - 1.2345)^2 + 1e-6) on a grid with no point on it: the maximum
    1e6 at 1.2345 (closed form) to 1e-12 in value, the location to 1e-7."""
    f = lambda w: 1.0 / ((w - 1.2345) ** 2 + 1e-6)  # noqa: E731
    omega = np.linspace(1.0, 1.5, 251)
    peak, where = _refined_extremum(f, omega, f(omega), maximum=True)
    assert peak == pytest.approx(1e6, rel=1e-12)
    assert where == pytest.approx(1.2345, rel=1e-7)


def test_tolerances_are_the_documented_ones():
    assert ROOT_TOLERANCE == 1e-13 and MINIMUM_TOLERANCE == 1e-12


def test_planar_loop_margins_agree_with_the_previous_search():
    """A PD on a hub with one lightly damped mode, margins from the closed form of L (no
    state-space model), refined on it: the previous search (Illinois crossings, scipy's bounded
    Brent minimum, the same grid) gave the values below; they agree to 1e-9 (its accuracy, as
    tests/spacecraft/design/test_exact_margins.py checks it). The minimum equals a dense scan's (2e-12: the
    scan's spacing of 5e-9 relative costs about that at a smooth minimum)."""
    J, w1, z1, k1 = 50.0, 2.0, 0.005, 0.4

    def loop(w):
        s = 1j * np.asarray(w, dtype=float)
        P = 1.0 / (J * s ** 2) + k1 / (s ** 2 + 2 * z1 * w1 * s + w1 ** 2)
        return (0.5 + 7.0 * s) * P  # PD: Kp 0.5 N m/rad, Kd 7 N m s/rad

    omega = np.unique(np.concatenate([np.geomspace(1e-3, 1e3, 600),
                                      w1 * (1 + z1 * np.tan(np.linspace(-1.45, 1.45, 40)))]))
    m = loop_margins(loop, omega)
    previous = {"phase_margin": 63.16829616853734, "modulus_margin": 0.9695486313312462,
                "gain_crossover_frequency": 0.14118264659918905,
                "delay_margin": 0.397406384178643}
    for name, value in previous.items():
        assert getattr(m, name) == pytest.approx(value, rel=1e-9, abs=0), name
    assert m.gain_margin == math.inf
    dense = m.modulus_margin_frequency * np.linspace(1 - 1e-3, 1 + 1e-3, 400001)
    assert m.modulus_margin <= np.abs(1 + loop(dense)).min() * (1 + 1e-14)
    assert m.modulus_margin == pytest.approx(np.abs(1 + loop(dense)).min(), rel=2e-12)
    assert abs(loop(np.array([m.gain_crossover_frequency]))[0]) == pytest.approx(1.0, abs=1e-12)


def test_three_axis_modulus_margins_are_the_functions_minima():
    """A three-axis hub with undamped modes, PD: each loop-at-a-time modulus margin and the
    smallest singular value of I + L are no higher than a dense scan of the function around
    the reported frequency finds (1e-12 relative): the minimum is the function's, not a local
    one (the previous bounded Brent search reported up to 0.5 % above the minimum on the
    benchmark spacecraft of benchmarks/three_axis.py)."""
    J = np.diag([1200.0, 900.0, 1500.0])
    b1, b2 = np.array([0.03, 0.01, 0.0]), np.array([0.0, 0.02, 0.04])
    plant = three_axis_plant(J, [(1.3, 0.0, b1, b1), (2.1, 0.0, b2, b2), (2.15, 0.001, b1, b2)])
    K = controllers.pd(plant, natural_frequency=0.3, damping=0.7)
    m = controllers.margins(plant, K)
    # the previous search's margins (Illinois, bounded Brent): the same to 1e-9 here
    previous = {"x": (62.78049139036797, 0.6746518057496057), "y": (-54.193529564887626,
                0.47018354617605995), "z": (39.888603564200054, 0.5904769390287733)}
    for axis, (pm, mm) in previous.items():
        assert m.loop_at_a_time[axis].phase_margin == pytest.approx(pm, rel=1e-9), axis
        assert m.loop_at_a_time[axis].modulus_margin == pytest.approx(mm, rel=1e-9), axis
    assert m.loop_at_a_time["y"].gain_margin == pytest.approx(7.001409766774614, rel=1e-9)
    assert m.disk_margin == pytest.approx(0.04835628502132963, rel=1e-9)
    assert m.min_singular_value == pytest.approx(0.04830844981193427, rel=1e-9)
    assert m.delay_margin == pytest.approx(0.5051796226809253, rel=1e-9)
    loop = LoopTransfer(plant, K)
    for i, axis in enumerate("xyz"):
        mm = m.loop_at_a_time[axis]
        w = mm.modulus_margin_frequency * np.linspace(1 - 1e-3, 1 + 1e-3, 20001)
        scan = np.abs(1.0 + loop.broken_all(w)[:, i])
        assert mm.modulus_margin <= scan.min() * (1 + 1e-12), axis
    w = m.min_singular_value_frequency * np.linspace(1 - 1e-3, 1 + 1e-3, 20001)
    sigma = np.linalg.svd(np.eye(3) + loop.matrix(w), compute_uv=False)[:, -1]
    assert m.min_singular_value <= sigma.min() * (1 + 1e-12)


def test_flat_stretches_and_exact_zeros_do_not_break_a_step():
    """The steps divide by differences of probed values and points; where those are zero (a
    function constant about the probes, a probe exactly on the root) the step falls back to
    bisection or ends, as numpy's inf and NaN would make it, instead of dividing by zero.
    A jump of f = sign(x - r) is bisected down to the stopping width about r (it is no root:
    |f| stays 1 at the ends, so not found); f = x - 2 on a grid whose first probe lands on 2
    exactly ends there; a constant function's minimum stays where it was, at its value."""
    r = math.sqrt(2.0)
    (root, found), _ = refine(lambda x, task: np.sign(x - r),
                              roots=(np.array([0]), np.array([1.0]), np.array([2.0]),
                                     np.array([-1.0]), np.array([1.0])))
    assert not found[0]
    assert abs(root[0] - r) <= 2.0 * ROOT_TOLERANCE * r
    (root, found), _ = refine(lambda x, task: x - 2.0,
                              roots=(np.array([0]), np.array([1.0]), np.array([3.0]),
                                     np.array([-1.0]), np.array([1.0])))
    assert found[0] and root[0] == 2.0
    _, (x, fx) = refine(lambda x, task: np.full(x.size, 3.0),
                        minima=(np.array([0]), np.array([1.0]), np.array([2.0]),
                                np.array([3.0]), np.array([3.0]), np.array([3.0]),
                                np.array([3.0])))
    assert fx[0] == 3.0 and 1.0 <= x[0] <= 3.0


@pytest.mark.parametrize("n_brackets", [3, 40])
def test_a_minimum_whose_sign_alone_is_wanted(n_brackets):
    """f(x) = (x - c)^2 / w^2 + d on brackets [c - w, c + w] about points c + 3 w / 4 where
    f > 0, with depths d from -0.5 to 0.5 (closed form: the minimum d at c): a sign-only
    bracket comes back with a value below zero exactly where d < 0 (a point inside, where f
    is that value), and with one never below the true minimum d where d > 0 and at most 2 d
    (the bracket stops once the parabola through its probes, f itself, predicts a least value
    d of at least half the best): the sign is right either way. A sign_only mask of the wrong
    size is refused."""
    rng = np.random.default_rng(3)
    c = rng.uniform(1.0, 2.0, n_brackets)
    w = 10.0 ** rng.uniform(-6, -2, n_brackets)
    d = np.linspace(-0.5, 0.5, n_brackets + 1)[:n_brackets] + 0.5 / (n_brackets + 1)
    f = lambda x, t: (x - c[t]) ** 2 / w[t] ** 2 + d[t]   # noqa: E731
    t = np.arange(n_brackets)
    lo, x0, hi = c - w, c + 0.75 * w, c + w
    minima = (t, lo, x0, hi, f(lo, t), f(x0, t), f(hi, t))
    assert np.all(minima[5] > 0)
    _, (x, fx) = refine(f, minima=minima, sign_only=np.ones(n_brackets, dtype=bool))
    assert np.all((lo < x) & (x < hi))
    np.testing.assert_array_equal(fx, f(x, t))
    assert np.array_equal(fx < 0, d < 0)
    assert np.all(fx[d > 0] >= d[d > 0]) and np.all(fx[d > 0] <= 2.0 * d[d > 0] * (1 + 1e-12))
    with pytest.raises(ValueError, match="sign_only must have one entry per minimum bracket"):
        refine(f, minima=minima, sign_only=np.ones(n_brackets + 1, dtype=bool))


def test_a_few_minima_are_stepped_as_many_are():
    """A few minimum brackets are stepped one by one in Python floats, many in numpy arrays:
    the same arithmetic, so the same new brackets, probes and stopping decisions to the bit,
    on random parabolas, kinks, non-finite probes and probes below zero, half the brackets
    wanting the sign of their minimum alone."""
    from controllers.refine import _minimum_step, _minimum_steps
    rng = np.random.default_rng(7)
    n = 200
    k = np.arange(n)
    x = rng.uniform(1.0, 2.0, n)
    width = 10.0 ** rng.uniform(-9, -1, n)
    lo, hi = x - width * rng.uniform(0.1, 1.0, n), x + width * rng.uniform(0.1, 1.0, n)
    p = np.sort(rng.uniform(lo[:, None], hi[:, None], (n, 3)), axis=1)
    p[::17, 1] = p[::17, 0]                         # coinciding probes
    centre = x + width * rng.uniform(-0.5, 0.5, n)
    fp = np.where((np.arange(n) % 3 == 0)[:, None], np.abs(p - centre[:, None]),
                  (p - centre[:, None]) ** 2) + 1.0
    fp[::11, 2] = np.nan
    fp[::13, 0] = np.inf
    fp[::19] = 1.0                                  # flat
    fp[::23, 1] = -0.5                              # below zero: a sign-only bracket ends
    sign = rng.uniform(size=n) < 0.5
    fx = np.where(np.arange(n) % 5 == 0, 1.0, 1.0 + width)
    h = width * rng.uniform(1e-6, 0.5, n)
    floor = width * 1e-4
    states = []
    with np.errstate(all="ignore"):
        for step in (_minimum_step, _minimum_steps):
            state = [v.copy() for v in (lo, x, hi, fx)] + [np.zeros(n), h.copy(), floor,
                                                             sign, np.ones(n, dtype=bool)]
            step(k, p, fp, *state)
            states.append(state)
    for one, many in zip(*states):
        np.testing.assert_array_equal(one, many)


def test_a_loop_that_reuses_its_output_buffer_has_the_margins_of_one_that_does_not():
    """The margins read L at the refined crossovers from the refinement's own evaluations: a
    loop function that returns (a view of) the same array every call, overwritten by the next
    call, must give exactly the margins of one that returns a new array (same arithmetic,
    same points)."""
    J, w1, z1, k1 = 50.0, 2.0, 0.005, 0.4

    def loop(w):
        s = 1j * np.asarray(w, dtype=float)
        P = 1.0 / (J * s ** 2) + k1 / (s ** 2 + 2 * z1 * w1 * s + w1 ** 2)
        return (0.5 + 7.0 * s) * P  # PD: Kp 0.5 N m/rad, Kd 7 N m s/rad

    buffer = np.zeros(0, dtype=complex)

    def reusing(w):
        nonlocal buffer
        values = loop(w)
        if buffer.size < values.size:
            buffer = np.zeros(values.size, dtype=complex)
        buffer[:] = np.nan   # the whole buffer as scratch: earlier results are gone
        out = buffer[:values.size]
        out[:] = values
        return out

    omega = np.unique(np.concatenate([np.geomspace(1e-3, 1e3, 600),
                                      w1 * (1 + z1 * np.tan(np.linspace(-1.45, 1.45, 40)))]))
    assert loop_margins(reusing, omega) == loop_margins(loop, omega)
