"""Damping where engineers define it: an appendage's ratio is that of its cantilever modes.

References: the damped root dynamic stiffness of appendages.damping's docstring,
D(s) = s^2 M_rr - s^4 sum_k l_k l_k^T/(s^2 + 2 zeta w_k s + w_k^2), summed here in 40-digit
arithmetic with the modes of Blevins' table 8-1 (cantilever roots of cos x cosh x = -1, found by
mpmath) and the series' tail by mpmath.nsum; the heavy-hub limit (a root held fixed: the first
coupled mode is the first cantilever mode, damped at the entered ratio).
"""

import math

import mpmath as mp
import numpy as np
import pytest

from appendages import Beam, HingedChain, Rod, SteppedBeam, TipBody
from spacecraft import Hub, Mount, Spacecraft


def D_cantilever_mpmath(beam, s, dps=40, n_exact=30):
    """The damped root dynamic stiffness of a uniform beam in 40 digits (module docstring).

    Mass-normalised cantilever modes psi_k (Blevins table 8-1, integral of the square L before
    normalising): participation factors ``l_k = rho A/sqrt(m) (2 sigma_k/beta_k,
    2/beta_k^2)``, ``sigma_k = (sinh x - sin x)/(cosh x + cos x)`` at the roots x_k of
    ``cos x cosh x = -1``; beyond n_exact modes ``x_k = (k - 1/2) pi``, ``sigma_k = 1`` (to
    e^-x_k < 1e-40) and the rest of the series by mpmath.nsum. Independent of the float code
    (no Hurwitz series, no circle mean, no closed-form undamped D).
    """
    with mp.workdps(dps):
        s = mp.mpc(s)
        zeta = mp.mpf(beam.damping_ratio)
        EJ, L, rho = (mp.mpf(beam.bending_stiffness), mp.mpf(beam.length),
                      mp.mpf(beam.linear_density))
        m = rho * L
        c0 = mp.sqrt(EJ / (rho * L**4))
        M = mp.matrix([[m, m * L / 2], [m * L / 2, m * L**2 / 3]])

        def term(x, sigma):
            beta = x / L
            l0, l1 = 2 * sigma / beta * rho / mp.sqrt(m), 2 / beta**2 * rho / mp.sqrt(m)
            w = x**2 * c0
            f = s**4 / (s**2 + 2 * zeta * w * s + w**2)
            return f * l0 * l0, f * l0 * l1, f * l1 * l1

        D = M * s**2
        for k in range(1, n_exact + 1):
            x = mp.findroot(lambda x: mp.cos(x) + mp.sech(x), (k - mp.mpf(0.5)) * mp.pi)
            sigma = (mp.sinh(x) - mp.sin(x)) / (mp.cosh(x) + mp.cos(x))
            a, b, c = term(x, sigma)
            D[0, 0] -= a
            D[0, 1] -= b
            D[1, 1] -= c
        for index, (i, j) in enumerate(((0, 0), (0, 1), (1, 1))):
            D[i, j] -= mp.nsum(lambda k: term((k - mp.mpf(0.5)) * mp.pi, 1)[index],
                               [n_exact + 1, mp.inf])
        D[1, 0] = D[0, 1]
        return np.array([[complex(D[i, j]) for j in range(2)] for i in range(2)])


@pytest.mark.slow
@pytest.mark.parametrize("where", ["far", "pole1", "pole3", "high"])
def test_uniform_beam_cantilever_damping_against_40_digits(where):
    """The damped D(s) of a uniform beam (closed form + explicit modes + Hurwitz tail, and the
    circle mean near an undamped cantilever pole) against the 40-digit modal sum: 1e-11 of the
    matrix (the float code's rounding is a few hundred eps of its terms near a pole, where
    the closed form is 1e3 times D; the tail series stops below 1e-10 of its first term,
    itself below 1e-3 of D)."""
    beam = Beam(1.5, 2.0, 0.7, damping_ratio=2e-3)
    wc = beam.cantilever_frequencies(3)
    s = {"far": 0.3 + 7.0j, "pole1": 1j * wc[0] * (1 + 1e-4),
         "pole3": 1j * wc[2] * (1 - 1e-3), "high": 4.0 + 900.0j}[where]
    if where.startswith("pole"):
        assert beam._cantilever_damping()._near_poles(np.array([s]), 64)[0][0]
    reference = D_cantilever_mpmath(beam, s)
    D = beam.dynamic_stiffness(s)                    # the modal sum
    assert np.abs(D - reference).max() <= 1e-11 * np.abs(reference).max()
    closed = beam._cantilever_damping()(np.array([s]))[0]     # closed form + corrections
    assert np.abs(closed - reference).max() <= 1e-11 * np.abs(reference).max()
    np.testing.assert_allclose(beam.W(s), np.linalg.inv(reference), rtol=1e-10, atol=0)


@pytest.mark.parametrize("zeta", [1e-4, 5e-3, 0.05, 0.15])
def test_modal_sum_of_the_damped_rod_equals_the_closed_form(zeta):
    """The uniform beam's damped D(s) by its modal sum (Beam._cantilever_modal_stiffness,
    the sweeps' exact loops) against the closed form with damping corrections and the circle
    mean near the undamped poles (appendages.damping), two independent evaluations of one
    function: from 1e-4 to 3000 times the frequency scale, on and off the imaginary axis, at
    and next to the cantilever and free-free frequencies, 1e-11 of the matrix at each point
    (measured: below 1e-12; the closed form's rounding near a pole is eps/zeta of D); s = 0
    gives 0; beyond its cap on modes the closed form answers."""
    rng = np.random.default_rng(3)
    for beam in (Beam(10.0, 101.0, 0.612, damping_ratio=zeta),
                 Beam(2.0, 2e5, 3.0, damping_ratio=zeta)):
        c0 = beam.frequency_scale
        wc, wf = beam.cantilever_frequencies(30), beam.natural_frequencies(30)
        w = np.concatenate([np.logspace(-4, 3.5, 300) * c0, wc, wc * (1 + 1e-9),
                            wc * (1 - 1e-3), wf, wf * (1 + 1e-7)])
        s = np.concatenate([1j * w, w * np.exp(1j * rng.uniform(0, np.pi, w.size))])
        modal = beam._cantilever_modal_stiffness(s)
        closed = beam._cantilever_damping()(s)
        size = np.abs(closed).reshape(-1, 4).max(axis=1)[:, None, None]
        assert np.all(np.abs(modal - closed) <= 1e-11 * size)
        axis = s.size // 2           # the imaginary axis alone: the real-arithmetic path
        np.testing.assert_array_equal(s[:axis].real, 0.0)
        modal_axis = beam._cantilever_modal_stiffness(s[:axis])
        assert np.all(np.abs(modal_axis - closed[:axis]) <= 1e-11 * size[:axis])
        np.testing.assert_array_equal(beam.dynamic_stiffness(0.0), np.zeros((2, 2)))
        far = np.array([1j * 1e4 * wc[-1]])
        assert beam._cantilever_modal_stiffness(far) is None
        np.testing.assert_allclose(beam.dynamic_stiffness(far[0]),
                                   beam._cantilever_damping()(far)[0], rtol=1e-14)


@pytest.mark.slow
def test_rod_cantilever_damping_against_the_modal_sum():
    """D = m s^2 - s^4 sum_k l_k^2/(s^2 + 2 zeta w_k s + w_k^2) with l_k^2 = 2 m/((k - 1/2)
    pi)^2 and w_k = (k - 1/2) pi/tau (Blevins table 8-19), by mpmath.nsum in 30 digits:
    rtol 1e-12."""
    rod = Rod(2.0, 900.0, 0.5, damping_ratio=0.05)
    m, Omega = rod.rigid_inertia, math.pi / rod.travel_time
    with mp.workdps(30):
        for s in (0.7j, 3.0 + 40.0j, 0.5j * Omega * (1 + 1e-5), 1e-3j, 500.0j):
            sm = mp.mpc(s)
            total = m * sm**2 - mp.nsum(
                lambda k: sm**4 * 2 * m / ((k - 0.5) * mp.pi) ** 2
                / (sm**2 + 2 * 0.05 * (k - 0.5) * Omega * sm + ((k - 0.5) * Omega) ** 2),
                [1, mp.inf])
            assert abs(rod.dynamic_stiffness(s) / complex(total) - 1) < 1e-12, s


def D_rod_mpmath(rod, s, dps=40):
    """The damped rod's D(s) = m s^2 - s^4 sum_k l_k^2/(s^2 + 2 zeta w_k s + w_k^2) (l_k, w_k of
    Blevins table 8-19 as above) in 40 digits: the modes up to 20 |s|/Omega summed one by one,
    the rest by its series in s/w_k, 40 terms (|s/w_k| < 1/20: below 1e-50 of it) with Hurwitz
    zeta sums. mpmath.nsum alone loses digits above about 50 Omega (the resonance of the
    summand spoils its extrapolation)."""
    with mp.workdps(dps):
        m, zeta = mp.mpf(rod.rigid_inertia), mp.mpf(rod.damping_ratio)
        Omega = mp.pi / (mp.mpf(rod.length) * mp.sqrt(mp.mpf(rod.inertia) / mp.mpf(rod.stiffness)))
        sm = mp.mpc(s)
        K = max(16, int(20 * abs(sm) / Omega))

        def term(k):
            w = (k - mp.mpf(0.5)) * Omega
            return sm**4 * 2 * m / ((k - mp.mpf(0.5)) * mp.pi) ** 2 / (sm**2 + 2 * zeta * w * sm
                                                                        + w**2)

        tail = mp.fsum(mp.chebyu(j, -zeta) * (sm / Omega) ** (4 + j) * Omega**2 * 2 * m
                       / mp.pi**2 * mp.zeta(4 + j, K + mp.mpf(0.5)) for j in range(40))
        return complex(m * sm**2 - mp.fsum(term(k) for k in range(1, K + 1)) - tail)


@pytest.mark.parametrize("zeta", [1e-4, 5e-3, 0.05, 0.15])
@pytest.mark.slow
def test_modal_sum_of_the_damped_rod_member_equals_the_closed_form(zeta):
    """A rod's damped D(s) by its modal sum (Rod._cantilever_modal_stiffness: the torsion and
    axial entries of W6 in the three-axis sweeps' exact loops) against the closed form
    m s^2 tanh(z)/z with damping corrections and the circle mean near the undamped poles
    (appendages.damping), two independent evaluations of one function: from 1e-4 to 1000
    times Omega = pi/tau, on and off the imaginary axis, at and next to the cantilever and
    free-free frequencies. Tolerance 1e-12 of |D| + |D_u| + m |s|^2: the closed form's rounding
    is eps of its undamped part D_u (huge next to a cantilever pole, where the correction
    cancels it) amplified by 1/zeta there, and both forms round at eps of their m s^2-sized
    terms where D passes through 0 (a free-free frequency); measured below 2e-13. s = 0 gives
    0; beyond its cap on modes the closed form answers."""
    rng = np.random.default_rng(3)
    for rod in (Rod(2.0, 900.0, 0.5, damping_ratio=zeta),
                Rod(10.0, 8e10, 0.3, damping_ratio=zeta, motion="torsion")):
        Omega = math.pi / rod.travel_time
        wc, wf = rod.cantilever_frequencies(30), rod.natural_frequencies(30)
        w = np.concatenate([np.logspace(-4, 3, 300) * Omega, wc, wc * (1 + 1e-9),
                            wc * (1 - 1e-3), wf, wf * (1 + 1e-7)])
        s = np.concatenate([1j * w, w * np.exp(1j * rng.uniform(0, np.pi, w.size))])
        modal = rod._cantilever_modal_stiffness(s)
        closed = rod._cantilever_damping()(s)[:, 0, 0]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            undamped = np.abs(rod._undamped_D(s))
        undamped = np.where(np.isfinite(undamped), undamped, 0.0)
        scale = np.abs(closed) + undamped + rod.rigid_inertia * np.abs(s) ** 2
        assert np.all(np.abs(modal - closed) <= 1e-12 * scale)
        axis = s.size // 2           # the imaginary axis alone: the real-arithmetic path
        np.testing.assert_array_equal(s[:axis].real, 0.0)
        modal_axis = rod._cantilever_modal_stiffness(s[:axis])
        assert np.all(np.abs(modal_axis - closed[:axis]) <= 1e-12 * scale[:axis])
        np.testing.assert_array_equal(rod.dynamic_stiffness(s), modal)
        assert rod.dynamic_stiffness(0.0) == 0
        far = np.array([1j * 1e5 * Omega])
        assert rod._cantilever_modal_stiffness(far) is None
        np.testing.assert_allclose(rod.dynamic_stiffness(far[0]),
                                   rod._cantilever_damping()(far)[0, 0, 0], rtol=1e-14)


@pytest.mark.slow
def test_modal_sums_keep_their_data_for_every_number_of_modes():
    """A rod's and a beam's damped modal sums (the exact loops evaluate a long grid, whose top
    needs many modes, between evaluations at a few low frequencies, which need 16) keep the
    data of each number of modes: the few points after the grid give what a fresh appendage
    gives, to the bit (the same operations on the same numbers), and so does the grid; a rod
    evaluated at a beam's checked s without checking it again (check=False) gives the same."""
    def rod():
        return Rod(2.0, 900.0, 0.5, damping_ratio=0.005)

    def beam():
        return Beam(10.0, 101.0, 0.612, damping_ratio=0.005)

    for make, scale in ((rod, math.pi / rod().travel_time), (beam, beam().frequency_scale)):
        few = 1j * scale * np.array([0.01, 0.3, 2.0])
        grid = 1j * scale * np.logspace(-2, 3, 900)       # the top needs more than 16 modes
        used = make()
        first = used.dynamic_stiffness(few)
        on_grid = used.dynamic_stiffness(grid)
        np.testing.assert_array_equal(used.dynamic_stiffness(few), first)
        np.testing.assert_array_equal(make().dynamic_stiffness(few), first)
        np.testing.assert_array_equal(make().dynamic_stiffness(grid), on_grid)
        if isinstance(used, Rod):
            np.testing.assert_array_equal(used.dynamic_stiffness(few, check=False), first)


@pytest.mark.slow
def test_modal_sum_of_the_damped_rod_against_40_digits():
    """The rod's modal sum against the 40-digit D(s) of D_rod_mpmath, high in frequency too
    (where the explicit sum holds hundreds of modes and the Hurwitz tail the rest), next to a
    cantilever pole and off the axis: rtol 1e-12 (measured: below 1e-14)."""
    rod = Rod(10.0, 8e10, 0.3, damping_ratio=5e-3, motion="torsion")
    Omega = math.pi / rod.travel_time
    for x in (1e-3, 0.7, 0.5 * (1 + 1e-5), 3.3, 27.4725, 98.4716, 305.4568, 60.0 * (1 + 1j)):
        s = 1j * x * Omega
        assert abs(rod.dynamic_stiffness(s) / D_rod_mpmath(rod, s) - 1) < 1e-12, x


def test_modal_factor_sum_on_the_axis_equals_the_complex_form():
    """appendages.damping.modal_factor_sum: on the imaginary axis (real arithmetic) against the
    complex form, the same sum at points off the axis by 1e-300 of |s| (which take the complex
    form): 1e-14 of the sum of |weight| x |factor| (each factor a few eps in either form),
    at and next to the modes' frequencies too; frequencies whose squares leave double
    precision take the complex form (finite, equal)."""
    from appendages.damping import modal_factor_sum

    rng = np.random.default_rng(5)
    w = np.sort(rng.uniform(0.5, 3e3, 40))
    weights = rng.normal(size=(40, 3))
    omega = np.concatenate([np.logspace(-4, 4, 400), w, w * (1 + 1e-9), w * (1 - 1e-6)])
    for zeta in (1e-4, 0.005, 0.3):
        on = modal_factor_sum(1j * omega, w, weights, zeta)
        off = modal_factor_sum(omega * (1e-300 + 1j), w, weights, zeta)
        ss = (1j * omega)[:, None]
        factor = (w**2 + 2 * zeta * w * ss) / ((ss - 1j * w) * (ss + 1j * w)
                                               + 2 * zeta * w * ss)
        size = np.abs(factor) @ np.abs(weights)
        assert np.all(np.abs(on - off) <= 1e-14 * size)
    huge = np.array([1e100, 2e100])          # w^4 overflows, w^2 does not
    s = 1j * np.logspace(90, 99, 3000)
    on = modal_factor_sum(s, huge, np.ones(2), 0.01)
    assert np.all(np.isfinite(on))
    np.testing.assert_allclose(on, modal_factor_sum(s * (1 + 1e-300j), huge, np.ones(2), 0.01),
                               rtol=1e-14)


def test_tail_series_few_and_many_points():
    """appendages.damping.tail_series, sum_j c_j v^(4+j), by integer powers (a few points) and
    by Horner's scheme (many) against the 40-digit sum: 1e-14 of sum_j |c_j| |v|^(4+j)."""
    from appendages.damping import tail_series

    rng = np.random.default_rng(7)
    coefficients = rng.normal(size=(12, 3))
    for n in (1, 5, 32, 33, 500):
        v = rng.uniform(0.01, 1.5, n) * np.exp(1j * rng.uniform(0, np.pi, n))
        got = tail_series(v, coefficients)
        assert got.shape == (n, 3)
        np.testing.assert_allclose(tail_series(v, coefficients[:, 0]), got[:, 0], rtol=1e-13,
                                   atol=1e-14 * np.abs(got[:, 0]).max())
        with mp.workdps(40):
            for i in range(0, n, max(1, n // 7)):
                for k in range(3):
                    exact = mp.fsum(mp.mpf(coefficients[j, k]) * mp.mpc(v[i]) ** (4 + j)
                                    for j in range(12))
                    size = sum(abs(coefficients[j, k]) * abs(v[i]) ** (4 + j) for j in range(12))
                    assert abs(got[i, k] - complex(exact)) <= 1e-14 * size


def _motion_alone(member, s):
    """One motion's damped D at flat s through its own modal sum (the per-motion path)."""
    D = member.dynamic_stiffness(s)
    return D.reshape(s.size, -1)[:, [0, 1, 3]] if D.ndim == 3 else D[:, None]


def _terms_size(member, s):
    """Sum over its terms of the size of a motion's modal sum at s (each column): s^2 times
    |weight| |factor| of every explicit mode and |R|, plus |t_j| |v|^(4+j) of its series; the
    rounding of any order of summation is a few eps per term of it."""
    w, weights, rest, coefficients, scale = member._modal_motion(
        member._modal_sum_size(float(np.abs(s).max())))
    zeta = member.damping_ratio
    ss = s[:, None]
    factor = (w**2 + 2 * zeta * w * ss) / ((ss - 1j * w) * (ss + 1j * w) + 2 * zeta * w * ss)
    powers = np.abs(s / scale)[:, None] ** np.arange(4, 4 + coefficients.shape[0])
    return (np.abs(s)[:, None] ** 2 * (np.abs(factor) @ np.abs(weights) + np.abs(rest))
            + powers @ np.abs(coefficients))


@pytest.mark.parametrize("n", [1, 3, 32, 33, 200, 3000])
@pytest.mark.parametrize("section", ["rectangular", "tube"])
def test_three_axis_modal_sums_of_every_motion_at_once(section, n):
    """Beam.dynamic_stiffness6 sums the modes of both bending planes, torsion and axial motion
    together (appendages.damping.CantileverModalSums): every entry is each motion's own sum
    (the planar beam of its plane, the rod), to a few eps of the size of its terms (only the
    order of summation and the choice of real or complex arithmetic differ), placed as
    W6's layout places it (the x-z coupling negated), zero elsewhere; on and off the axis, a
    few points (integer powers in the series), tens (Horner) and a grid (each motion alone);
    bending planes that differ (a plate-like wing) and equal ones (a tube)."""
    beam = (Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8, damping_ratio=0.005)
            if section == "rectangular" else
            Beam.tube(4.0, 0.05, 0.001, 1600.0, 1.2e11, damping_ratio=0.02))
    rng = np.random.default_rng(n)
    w1 = float(beam.cantilever_frequencies(1)[0])
    omega = w1 * 10 ** rng.uniform(-2, 2.5, n)
    xy, xz = beam, beam.planar_view("xz")
    places = [(xy, [(1, 1), (1, 5), (5, 5)], 1), (xz, [(2, 2), (2, 4), (4, 4)], -1),
              (beam.axial_rod(), [(0, 0)], 1), (beam.torsion_rod(), [(3, 3)], 1)]
    for s in (1j * omega, omega * (-0.02 + 1j)):
        D6 = beam.dynamic_stiffness6(s)
        filled = np.zeros((6, 6), bool)
        for member, entries, sign in places:
            alone, size = _motion_alone(member, s), _terms_size(member, s)
            for column, (i, j) in enumerate(entries):
                expected = alone[:, column] * (sign if i != j else 1)
                assert np.all(np.abs(D6[:, i, j] - expected) <= 64 * 2.2e-16 * size[:, column])
                np.testing.assert_array_equal(D6[:, j, i], D6[:, i, j])
                filled[i, j] = filled[j, i] = True
        assert np.all(D6[:, ~filled] == 0)


def test_joint_modal_sums_keep_a_non_finite_value_in_its_own_motion():
    """appendages.damping.CantileverModalSums: one motion's sum that is not finite (here a mode
    whose square overflows) does not reach the other motions' columns through the zero
    weights between them (0 x inf): they come out as each motion alone gives them."""
    from appendages.damping import CantileverModalSums

    beam = Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8, damping_ratio=0.005)
    good = beam._modal_motion(16)
    w, weights, rest, coefficients, scale = beam.torsion_rod()._modal_motion(16)
    broken = (np.concatenate([w[:-1], [1e200]]), weights, rest, coefficients, scale)
    s = 1j * np.array([0.5, 3.0, 40.0])
    joint = CantileverModalSums([good, broken], 0.005)(s)
    np.testing.assert_array_equal(joint[:, :3], CantileverModalSums([good], 0.005)(s))
    assert not np.isfinite(joint[:, 3]).all()


def _coupled_pole(beam, hub_mass, hub_inertia, guess):
    """The coupled pole near ``guess`` of a hub carrying the beam at its centre, from the exact
    Z(s) = M_hub s^2 + G^T D(s) G: a root of ``(s - guess) det Z(s)`` (the factor removes the
    damped cantilever pole of D next to it), by the secant method in complex s from 1e-3 of
    |guess| away (near the pole Z is dominated by its rank-one pole term and its determinant
    is rounding; at the coupled pole it is not)."""
    sc = Spacecraft(Hub(hub_mass, hub_inertia), [Mount(beam, (0.0, 0.0), 0.0)])

    def f(s):
        Z = sc.exact.hub_dynamic_stiffness(np.array([s]))[0]
        scale = np.abs(np.diag(Z))
        return (s - guess) * np.linalg.det(Z / np.sqrt(np.outer(scale, scale)))

    a, b = guess * (1 + 1e-3), guess * (1 + 1e-3j)
    fa, fb = f(a), f(b)
    for _ in range(60):
        c = b - fb * (b - a) / (fb - fa)
        if abs(c - b) < 1e-15 * abs(c):
            return c
        a, fa, b, fb = b, fb, c, f(c)
    return b


@pytest.mark.parametrize("kind", ["uniform", "tip", "stepped"])
def test_a_very_heavy_hub_sees_the_entered_damping(kind):
    """Issue 21's check: with a hub much heavier than the beam (its root held, in effect) the
    first coupled mode is the first cantilever mode, damped at the entered ratio. The coupled
    pole tends to the damped cantilever pole like m/M (its distance falls by 10 when M and J
    grow by 10); at M/m = 1e4 the damping ratio agrees to 1e-3 relative (the shift of the pole
    is about 1e-4 of it)."""
    zeta = 0.005
    if kind == "uniform":
        beam = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=zeta)
    elif kind == "tip":
        beam = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=zeta,
                                 tip=TipBody(2.0, 0.01, 0.05))
    else:
        beam = SteppedBeam([Beam.circular_rod(4.0, 0.014, 7800.0, 2.06e11, damping_ratio=zeta),
                            Beam.circular_rod(6.0, 0.01, 7800.0, 2.06e11, damping_ratio=zeta)])
    wc = float(beam.cantilever_frequencies(1)[0])
    pole = wc * complex(-zeta, math.sqrt(1 - zeta**2))
    m, J = beam.mass, beam.inertia + beam.mass * beam.center_of_mass**2
    distances = []
    for ratio in (1e3, 1e4):
        s = _coupled_pole(beam, ratio * m, ratio * J, pole)
        distances.append(abs(s - pole))
    assert 5.0 < distances[0] / distances[1] < 20.0
    assert -s.real / abs(s) == pytest.approx(zeta, rel=1e-3)


@pytest.mark.slow
def test_craig_bampton_truncations_converge_to_the_damped_beam():
    """The Craig-Bampton model carries the convention exactly (its cantilever modes damped at
    zeta, diag(2 zeta w)): its W converges to the exact damped W as modes are added, for the
    uniform beam and with a tip body (measured errors 5e-10 and 1e-11 at 256 modes; the
    truncation's own rest decays like n^-3)."""
    s = np.concatenate([1j * np.linspace(0.3, 60.0, 7) + 0.2, [40j + 0.01]])
    for beam in (Beam(1.7, 2.3, 0.9, damping_ratio=0.01),
                 Beam(1.7, 2.3, 0.9, damping_ratio=0.01, tip=TipBody(3.0, 0.2, 0.15))):
        exact = beam.W(s)
        errors = [np.abs(beam.truncated(n).W(s) - exact).max() / np.abs(exact).max()
                  for n in (8, 32, 128)]
        assert errors[0] > errors[1] > errors[2] and errors[2] < 1e-7


def test_free_interface_truncations_carry_the_cantilever_damping():
    """Free-free and residual models project the cantilever modes' damping on their own
    coordinates: their W converges to the exact damped W too (measured 8e-4 and 1e-10 at 16
    modes)."""
    beam = Beam(1.7, 2.3, 0.9, damping_ratio=0.01)
    s = 1j * np.linspace(0.3, 60.0, 7) + 0.2
    exact = beam.W(s)
    for method, bound in (("free-free", 2e-3), ("residual", 1e-8)):
        errors = [np.abs(beam.truncated(n, method=method).W(s) - exact).max()
                  / np.abs(exact).max() for n in (4, 16)]
        assert errors[1] < errors[0] and errors[1] < bound


def test_free_free_convention_is_kept_by_name():
    """damping_convention="free-free" is the previous meaning: W is the undamped closed form
    plus the damping of every free-free mode; its first free-free resonance has the peak
    height b b^T/(2 i zeta w^2) (to O(zeta)); the cantilever convention's differs."""
    zeta = 1e-4
    old = Beam(1.0, 1.0, 1.0, damping_ratio=zeta, damping_convention="free-free")
    new = Beam(1.0, 1.0, 1.0, damping_ratio=zeta)
    w1 = old.natural_frequencies(1)[0]
    _, b, _ = old.free_free_modes(1)
    peak = abs(old.W(1j * w1)[1, 1]) * 2 * zeta * w1**2
    assert peak == pytest.approx(b[0, 1] ** 2, rel=1e-3)
    assert abs(new.W(1j * w1)[1, 1]) * 2 * zeta * w1**2 != pytest.approx(b[0, 1] ** 2,
                                                                          rel=1e-2)


def test_chain_hinge_damping_matches_the_first_cantilever_mode():
    """The RFEM chain's stiffness-proportional hinges 2 zeta c/w_c1 damp each of its modes at
    zeta w/w_c1: its first cantilever mode (root held) at zeta, to the chain's discretisation
    of w_c1 (2e-4 with 64 bodies)."""
    zeta = 0.01
    beam = Beam(2.0, 3.0, 0.5, damping_ratio=zeta)
    chain = HingedChain.rfem(beam, 64)
    rm = chain.root_model()
    r = rm.n_root
    M, C, K = rm.mass[r:, r:], rm.damping[r:, r:], rm.stiffness[r:, r:]
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)],
                  [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    poles = np.linalg.eigvals(A)
    first = poles[np.argmin(np.abs(poles))]
    assert -first.real / abs(first) == pytest.approx(zeta, rel=1e-3)


def test_damping_convention_is_checked():
    with pytest.raises(ValueError, match="damping_convention"):
        Beam(1.0, 1.0, 1.0, damping_ratio=0.01, damping_convention="modal")
    with pytest.raises(ValueError, match="damping_convention"):
        Beam(1.0, 1.0, 1.0, damping_convention="free-free", tip=TipBody(1.0, 0.0))
    with pytest.raises(ValueError, match="damping_convention"):
        Rod(1.0, 1.0, 1.0, damping_convention=3)
