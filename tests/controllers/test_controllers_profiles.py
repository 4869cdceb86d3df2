"""Slew profiles and input shapers (controllers.profiles): closed forms, limits, shaping.

Tolerances: the profiles are closed forms evaluated in double precision, a few operations per
value, so values agree with the formulas to ~1e-15 relative; 1e-12 leaves room for the sums of
a shaped profile's shifted pieces (up to 27 terms). Simulations of a piecewise-constant input
fed with a zero-order hold on a grid through every breakpoint are exact up to the simulator's
round-off (~1e-13 relative over 1e4 steps, benchmarks/results/simulate_error_budget.json).
"""
import math

import numpy as np
import pytest

import controllers
from controllers import profiles as P
from plants import modal_plant

RTOL = 1e-12


def gauss_integral(profile, derivative, n=4):
    """Integral of s^(d) over the profile, by Gauss-Legendre on each piece (exact for the
    polynomial pieces of degree <= 3 with n = 4)."""
    x, w = np.polynomial.legendre.leggauss(n)
    total = 0.0
    for a, b in zip(profile.breakpoints[:-1], profile.breakpoints[1:]):
        t = 0.5 * (b - a) * x + 0.5 * (a + b)
        total += 0.5 * (b - a) * np.sum(w * profile.path(t, derivative))
    return total


# ---------------------------------------------------------------------------------------------
# bang-coast-bang
# ---------------------------------------------------------------------------------------------
def test_bang_coast_bang_shortest_against_its_closed_form():
    """theta = 0.2 rad, J = 250 kg m^2, torque 0.05 N m (a = 2e-4 rad/s^2), rate 0.005 rad/s:
    accelerate W / a = 25 s to W, coast theta / W - W / a = 15 s, decelerate 25 s: T = 65 s
    (Wie 2008, sec. 7.3); the angle covered while accelerating is W^2 / (2 a) = 0.0625 rad."""
    p = P.bang_coast_bang(0.2, inertia=250.0, torque_limit=0.05, rate_limit=0.005)
    np.testing.assert_allclose(p.breakpoints, [0.0, 25.0, 40.0, 65.0], rtol=RTOL, atol=0)
    assert p.end_time == pytest.approx(65.0, rel=RTOL)
    assert p.peak_rate == pytest.approx(0.005, rel=RTOL)
    assert p.peak_acceleration == pytest.approx(2e-4, rel=RTOL)
    assert p.peak_torque(250.0) == pytest.approx(0.05, rel=RTOL)
    assert math.isinf(p.peak_jerk)
    np.testing.assert_allclose(p.path(np.array([25.0, 40.0, 65.0, 100.0])),
                               [0.0625, 0.2 - 0.0625, 0.2, 0.2], rtol=RTOL, atol=0)
    # the area under the rate is the angle; under the acceleration zero (rest to rest)
    assert gauss_integral(p, 1) == pytest.approx(0.2, rel=RTOL)
    assert abs(gauss_integral(p, 2)) <= 1e-15
    assert P.minimum_time("bang-coast-bang", 0.2, inertia=250.0, torque_limit=0.05,
                          rate_limit=0.005) == pytest.approx(65.0, rel=RTOL)


def test_bang_bang_when_the_rate_limit_is_not_reached():
    """Without coast: T = 2 sqrt(theta / a), peak rate sqrt(theta a)."""
    p = P.bang_coast_bang(-0.1, inertia=100.0, torque_limit=0.04)
    a = 0.04 / 100.0
    assert p.end_time == pytest.approx(2.0 * math.sqrt(0.1 / a), rel=RTOL)
    assert p.peak_rate == pytest.approx(math.sqrt(0.1 * a), rel=RTOL)
    assert p.path(np.array([p.end_time]))[0] == pytest.approx(-0.1, rel=RTOL)
    assert np.all(p.path(np.linspace(0, p.end_time, 101), 1) <= 0)


def test_bang_coast_bang_in_a_given_time_takes_the_least_acceleration():
    """In a given T the acceleration theta / (t_a (T - t_a)) is least for the largest t_a the
    rate limit allows; checked against a brute-force scan of t_a."""
    theta, T, W = 0.3, 100.0, 0.004
    p = P.bang_coast_bang(theta, T, rate_limit=W)
    t_a = np.linspace(1e-3, T / 2, 200_001)
    rate = theta / (T - t_a)
    a = theta / (t_a * (T - t_a))
    best = a[rate <= W].min()
    assert p.peak_acceleration <= best * (1 + 1e-9)
    assert p.peak_acceleration == pytest.approx(best, rel=1e-4)  # the scan step 2.5e-4 s
    assert p.peak_rate <= W * (1 + RTOL)
    assert p.end_time == pytest.approx(T, rel=RTOL)


def test_bang_coast_bang_limits_hold_for_random_cases():
    rng = np.random.default_rng(7)
    for _ in range(200):
        theta = rng.uniform(0.01, 3.0) * rng.choice([-1, 1])
        J = 10 ** rng.uniform(0, 4)
        tau = 10 ** rng.uniform(-3, 0)
        W = 10 ** rng.uniform(-3, -1)
        t_min = P.minimum_time("bang-coast-bang", theta, inertia=J, torque_limit=tau,
                               rate_limit=W)
        T = t_min * rng.uniform(1.0, 3.0)
        p = P.bang_coast_bang(theta, T, inertia=J, torque_limit=tau, rate_limit=W)
        assert p.end_time == pytest.approx(T, rel=RTOL)
        assert p.peak_rate <= W * (1 + 1e-10)
        assert p.peak_torque(J) <= tau * (1 + 1e-10)
        assert p.path(np.array([T]))[0] == pytest.approx(theta, rel=1e-12)
        with pytest.raises(ValueError, match=f"shortest time they allow is {t_min:.6g} s"):
            P.bang_coast_bang(theta, t_min * 0.999, inertia=J, torque_limit=tau, rate_limit=W)


def test_bang_coast_bang_too_short_names_duration_and_the_shortest_time():
    with pytest.raises(ValueError, match=r"duration 30 s; the shortest time they allow is 65 s"):
        P.bang_coast_bang(0.2, 30.0, inertia=250.0, torque_limit=0.05, rate_limit=0.005)


# ---------------------------------------------------------------------------------------------
# the jerk-limited ("smooth") profile
# ---------------------------------------------------------------------------------------------
def test_smooth_profile_without_limits_is_the_least_jerk_triangle():
    """No active limit: the triangular-acceleration profile, peak jerk 32 theta / T^3 (below the
    cycloid's 4 pi^2 theta / T^3), t_j = T / 4, continuous acceleration."""
    p = P.jerk_limited(0.2, 60.0)
    assert p.peak_jerk == pytest.approx(32 * 0.2 / 60.0 ** 3, rel=RTOL)
    np.testing.assert_allclose(p.breakpoints, [0, 15, 30, 45, 60], rtol=RTOL, atol=0)
    for d in (0, 1, 2):
        assert p._jumps(d).max() <= 1e-15
    assert gauss_integral(p, 1) == pytest.approx(0.2, rel=RTOL)


def test_smooth_profile_jerk_bound_and_shortest_time():
    """The shortest profile under all three limits reaches each (closed form, Biagiotti &
    Melchiorri 2008, sec. 3.4: t_j = a/j = 2 s, constant acceleration 23 s, coast 13 s,
    T = 67 s), and in a longer given time the jerk stays below the limit."""
    kw = dict(inertia=250.0, torque_limit=0.05, rate_limit=0.005, jerk_limit=1e-4)
    fastest = P.jerk_limited(0.2, **kw)
    assert fastest.end_time == pytest.approx(67.0, rel=1e-10)
    assert fastest.peak_jerk == pytest.approx(1e-4, rel=1e-9)
    assert fastest.peak_acceleration == pytest.approx(2e-4, rel=1e-9)
    assert fastest.peak_rate == pytest.approx(0.005, rel=1e-9)
    rng = np.random.default_rng(3)
    for _ in range(200):
        theta = rng.uniform(0.01, 3.0)
        J, tau = 10 ** rng.uniform(0, 4), 10 ** rng.uniform(-3, 0)
        W, Jm = 10 ** rng.uniform(-3, -1), 10 ** rng.uniform(-6, -2)
        limits = dict(inertia=J, torque_limit=tau, rate_limit=W, jerk_limit=Jm)
        t_min = P.minimum_time("smooth", theta, **limits)
        p = P.jerk_limited(theta, t_min * rng.uniform(1.0 + 1e-9, 3.0), **limits)
        assert p.peak_jerk <= Jm * (1 + 1e-9)
        assert p.peak_acceleration * J <= tau * (1 + 1e-9)
        assert p.peak_rate <= W * (1 + 1e-9)
        assert p.path(np.array([p.end_time]))[0] == pytest.approx(theta, rel=1e-12)
        # at the shortest time one limit is met with equality: the minimum is tight
        q = P.jerk_limited(theta, t_min * (1 + 1e-9), **limits)
        assert max(q.peak_jerk / Jm, q.peak_acceleration * J / tau, q.peak_rate / W) == \
            pytest.approx(1.0, rel=1e-5)
        with pytest.raises(ValueError, match="shortest time they allow"):
            P.jerk_limited(theta, t_min * 0.999, **limits)


def test_smooth_profile_in_a_given_time_has_the_least_jerk_of_its_family():
    """Brute force over the 7-segment family (t_j, t_c, coast) that ends at T within the
    acceleration and rate limits: none has a lower peak jerk."""
    theta, T, A, W = 0.2, 80.0, 2e-4, 0.005
    p = P.jerk_limited(theta, T, inertia=1.0, torque_limit=A, rate_limit=W)
    best = math.inf
    for S in np.linspace(1e-3, T / 2, 400):
        w = theta / (T - S)
        if w > W:
            continue
        u = np.linspace(S / 2, S, 400)[:-1]
        tj = S - u
        a = w / u
        j = a / tj
        ok = a <= A
        if ok.any():
            best = min(best, j[ok].min())
    assert p.peak_jerk <= best * (1 + 1e-9)


# ---------------------------------------------------------------------------------------------
# three axes and the step reference
# ---------------------------------------------------------------------------------------------
def test_three_axis_references_and_feedforward():
    J = np.array([[300.0, 20.0, -5.0], [20.0, 250.0, 10.0], [-5.0, 10.0, 400.0]])
    e = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    p = P.bang_coast_bang(0.3, 90.0, inertia=J, torque_limit=0.1, rate_limit=0.006,
                          axis=[1.0, 2.0, -0.5])
    np.testing.assert_allclose(p.axis, e, rtol=RTOL)
    # the torque limit bounds each component of J e a
    assert np.max(np.abs(J @ e)) * p.peak_acceleration <= 0.1 * (1 + RTOL)
    t = np.linspace(0, 100, 1001)
    refs = p.references(t, J)
    assert sorted(refs) == sorted(f"{n}_{a}" for n in ("theta_ref", "omega_ref", "torque_ff")
                                  for a in "xyz")
    s, ds, dds = p.path(t), p.path(t, 1), p.path(t, 2)
    for i, a in enumerate("xyz"):
        np.testing.assert_allclose(refs[f"theta_ref_{a}"], e[i] * s, rtol=0, atol=1e-16)
        expected = (J @ e)[i] * dds + np.cross(e, J @ e)[i] * ds ** 2
        np.testing.assert_allclose(refs[f"torque_ff_{a}"], expected, rtol=0, atol=1e-16)
    # the exact peak torque includes the gyroscopic term: |b_i| a + |g_i| w^2 at the phase ends
    b, g = J @ e, np.cross(e, J @ e)
    expected_peak = np.max(np.abs(b) * p.peak_acceleration + np.abs(g) * p.peak_rate ** 2)
    assert p.peak_torque(J) == pytest.approx(expected_peak, rel=1e-12)


def test_step_reference_is_the_cycloid_alone():
    t = np.linspace(0, 80, 801)
    p = P.step_reference(0.2, 60.0)
    np.testing.assert_array_equal(p.theta_ref(t), controllers.slew_profile(t, 0.2, 60.0))
    refs = p.references(t, 250.0)
    assert not refs["omega_ref"].any() and not refs["torque_ff"].any()
    assert p.end_time == 60.0


# ---------------------------------------------------------------------------------------------
# shapers
# ---------------------------------------------------------------------------------------------
def test_zv_and_zvd_shapers_closed_forms():
    """Singer & Seering 1990: K = exp(-zeta pi / sqrt(1 - zeta^2)); ZV [1, K] / (1 + K) at
    [0, pi / w_d]; ZVD [1, 2K, K^2] / (1 + K)^2 at [0, pi / w_d, 2 pi / w_d]."""
    w, zeta = 2.0, 0.05
    K = math.exp(-zeta * math.pi / math.sqrt(1 - zeta ** 2))
    wd = w * math.sqrt(1 - zeta ** 2)
    zv, zvd = P.zv_shaper(w, zeta), P.zvd_shaper(w, zeta)
    np.testing.assert_allclose(zv.amplitudes, [1 / (1 + K), K / (1 + K)], rtol=RTOL)
    np.testing.assert_allclose(zv.times, [0, math.pi / wd], rtol=RTOL)
    np.testing.assert_allclose(zvd.amplitudes, np.array([1, 2 * K, K * K]) / (1 + K) ** 2,
                               rtol=RTOL)
    np.testing.assert_allclose(zvd.times, [0, math.pi / wd, 2 * math.pi / wd], rtol=RTOL)
    for s in (zv, zvd):
        assert s.residual_vibration(w, zeta) <= 1e-15
        assert s.amplitudes.sum() == pytest.approx(1.0, rel=1e-15)


def test_zvd_stays_below_five_percent_over_its_stated_band():
    """Undamped ZVD: V = cos^2(pi w / (2 w_n)) <= 5 % for |w / w_n - 1| <= (2 / pi)
    asin(sqrt(0.05)) = 14.36 %; ZV: V = |cos(pi w / (2 w_n))|, +-3.2 %."""
    half = 2 / math.pi * math.asin(math.sqrt(0.05))
    zvd = P.zvd_shaper(1.5)
    lo, hi = zvd.insensitivity(1.5, tolerance=0.05)
    assert lo == pytest.approx(1 - half, abs=1e-10) and hi == pytest.approx(1 + half, abs=1e-10)
    ratios = np.linspace(1 - half, 1 + half, 2001)
    assert zvd.residual_vibration(1.5 * ratios).max() <= 0.05 * (1 + 1e-12)
    np.testing.assert_allclose(zvd.residual_vibration(1.5 * ratios),
                               np.cos(np.pi * ratios / 2) ** 2, rtol=0, atol=1e-15)
    lo, hi = P.zv_shaper(1.5).insensitivity(1.5, tolerance=0.05)
    assert hi - 1 == pytest.approx(2 / math.pi * math.asin(0.05), abs=1e-10)


def test_shaped_profile_is_the_convolution_and_keeps_the_limits():
    base = P.jerk_limited(0.2, 60.0, rate_limit=0.005)
    shaper = P.mode_shaper([(0.9, 0.01), (3.1, 0.0)], kind="zvd")
    p = P.shaped(base, shaper)
    assert p.kind == "shaped" and p.end_time == pytest.approx(60.0 + shaper.duration, rel=RTOL)
    t = np.random.default_rng(1).uniform(-5, p.end_time + 5, 2000)
    for d in range(3):
        direct = sum(A * base.path(t - ti, d) for A, ti in zip(shaper.amplitudes, shaper.times))
        scale = [0.2, base.peak_rate, base.peak_acceleration][d]
        np.testing.assert_allclose(p.path(t, d), direct, rtol=0, atol=1e-12 * scale)
    assert p.peak_rate <= base.peak_rate * (1 + RTOL)
    assert p.peak_acceleration <= base.peak_acceleration * (1 + RTOL)
    assert p.peak_jerk <= base.peak_jerk * (1 + RTOL)
    assert shaper.residual_vibration(0.9, 0.01) <= 1e-15
    assert shaper.residual_vibration(3.1, 0.0) <= 1e-15


def residual(plant, profile, J, dt, t_after):
    """Peak |tip deflection| after the profile, in an open-loop simulation of the feedforward
    torque alone (J s'' through the generator's piecewise-constant input, zero-order hold)."""
    T = np.arange(int(round((profile.end_time + t_after) / dt)) + 1) * dt
    u = J * profile.generator_input(T)
    y = controllers.simulate(plant, T, np.vstack([u, np.zeros_like(u)]), hold="zero").y
    tip = y[list(plant.output_labels).index("tip_deflection")]
    return np.max(np.abs(tip[T >= profile.end_time]))


def test_zv_removes_the_residual_vibration_of_its_mode_exactly():
    """An undamped mode at 2 pi / 5 rad/s (ZV delay 2.5 s): a bang-bang slew of 21 s leaves it
    vibrating (its 10.5 s pulses are no whole number of periods); shaped, the residual is at
    round-off. Every breakpoint (0, 2.5, 10.5, 13, 21, 23.5 s) lies on the 0.01 s grid, so the
    zero-order-hold simulation is exact."""
    J, w = 250.0, 2 * math.pi / 5
    plant = modal_plant(J, [(w, 0.0, 0.05, 0.05)], tips=[("tip_deflection", [1.0])])
    base = P.bang_coast_bang(0.2, 21.0)
    raw = residual(plant, base, J, 0.01, 30.0)
    shaped = residual(plant, P.shaped(base, P.zv_shaper(w)), J, 0.01, 30.0)
    assert raw > 1e-4
    assert shaped <= 1e-10 * raw


@pytest.mark.parametrize("error", [-0.14, 0.14])
def test_zvd_residual_over_the_frequency_error_band(error):
    """The mode 14 % off the shaper's frequency: the residual after the ZVD-shaped slew is at
    most 5 % of the unshaped one's (the shaper's stated band), and equals V of the shaper."""
    J, w_design = 250.0, 2 * math.pi / 5
    w = w_design * (1 + error)
    plant = modal_plant(J, [(w, 0.0, 0.05, 0.05)], tips=[("tip_deflection", [1.0])])
    base = P.bang_coast_bang(0.2, 21.0)
    shaper = P.zvd_shaper(w_design)
    ratio = residual(plant, P.shaped(base, shaper), J, 0.01, 40.0) / residual(
        plant, base, J, 0.01, 40.0)
    assert ratio <= 0.05
    assert ratio == pytest.approx(float(shaper.residual_vibration(w)), rel=1e-3)


# ---------------------------------------------------------------------------------------------
# sampling for the simulators
# ---------------------------------------------------------------------------------------------
def test_generator_reproduces_the_profile_exactly_on_a_grid_through_its_breakpoints():
    p = P.shaped(P.jerk_limited(0.2, 40.0), P.zvd_shaper(2 * math.pi / 5))   # breaks on 0.01 s
    gen = p.generator(250.0)
    T = np.arange(int(round((p.end_time + 5) / 0.01)) + 1) * 0.01
    y = controllers.simulate(gen, T, p.generator_input(T), hold="zero").y
    refs = p.references(T, 250.0)
    for i, name in enumerate(gen.output_labels):
        scale = np.max(np.abs(refs[name]))
        np.testing.assert_allclose(y[i], refs[name], rtol=0, atol=1e-11 * scale)


@pytest.mark.parametrize("hold", ["linear", "zero"])
def test_hold_error_bounds_the_interpolation_error(hold):
    """The stated bound is at least the measured sup difference between each signal and what
    the simulator interpolates (fine evaluation inside every step), and within a factor 10."""
    p = P.shaped(P.bang_coast_bang(0.2, 30.0, rate_limit=0.009), P.zv_shaper(1.7))
    dt = 0.37  # breakpoints off the grid
    T = np.arange(int(p.end_time / dt) + 3) * dt
    bound = p.hold_error(dt, hold=hold, inertia=250.0)
    fine = np.linspace(0, 1, 201)[:-1]
    for name, samples in p.references(T, 250.0).items():
        t = (T[:-1, None] + dt * fine[None, :]).reshape(-1)
        exact = p.references(t, 250.0)[name]
        if hold == "linear":
            seen = np.interp(t, T, samples)
        else:
            seen = np.repeat(samples[:-1], fine.size)
        measured = np.max(np.abs(exact - seen))
        assert measured <= bound[name] * (1 + 1e-9), (name, measured, bound[name])
        assert bound[name] <= 10 * measured + 1e-300, (name, measured, bound[name])


# ---------------------------------------------------------------------------------------------
# bad input
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("call, name", [
    (lambda: P.bang_coast_bang(0.0, 10.0), "angle"),
    (lambda: P.bang_coast_bang(10.0, 10.0), "angle"),
    (lambda: P.bang_coast_bang(0.1, -1.0), "duration"),
    (lambda: P.bang_coast_bang(0.1, 10.0, torque_limit=0.1), "inertia"),
    (lambda: P.bang_coast_bang(0.1, 10.0, inertia=-1.0, torque_limit=0.1), "inertia"),
    (lambda: P.bang_coast_bang(0.1, 10.0, inertia=1.0, torque_limit=np.nan), "torque_limit"),
    (lambda: P.bang_coast_bang(0.1, 10.0, rate_limit=0.0), "rate_limit"),
    (lambda: P.bang_coast_bang(0.1), "duration"),
    (lambda: P.bang_coast_bang(0.1, 10.0, axis="w"), "axis"),
    (lambda: P.bang_coast_bang(0.1, 10.0, inertia=np.eye(3), torque_limit=1.0), "inertia"),
    (lambda: P.jerk_limited(0.1, 10.0, jerk_limit=-1.0), "jerk_limit"),
    (lambda: P.jerk_limited(0.1), "duration"),
    (lambda: P.zv_shaper(-1.0), "frequency"),
    (lambda: P.zvd_shaper(1.0, 1.0), "damping"),
    (lambda: P.mode_shaper([(1.0, 0.0)], kind="ei"), "kind"),
    (lambda: P.mode_shaper([]), "modes"),
    (lambda: P.shaped(P.step_reference(0.1, 10.0), P.zv_shaper(1.0)), "base"),
    (lambda: P.reference_profile("ramp", 0.1, 10.0), "kind"),
    (lambda: P.reference_profile("shaped", 0.1, 10.0), "shaper"),
    (lambda: P.reference_profile("shaped", 0.1, 1.0, shaper=P.zv_shaper(1.0)), "duration"),
    (lambda: P.bang_coast_bang(0.1, 10.0).hold_error(0.0), "dt"),
    (lambda: P.bang_coast_bang(0.1, 10.0).hold_error(0.1, hold="cubic"), "hold"),
])
def test_bad_arguments_name_the_parameter(call, name):
    with pytest.raises((ValueError, TypeError), match=name):
        call()
