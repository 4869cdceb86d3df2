"""Three axes, the appendage side: exact rods, the beam's W6, sections, truncations in 3-D.

References used here and nowhere in flexsat: the independent finite-element model of
tests/support/fe3d.py (verified in tests/support/test_fe3d_reference.py: W6 to ~1e-12 at 40 elements), mpmath
at 30-40 digits, and closed forms derived in the docstrings.
"""

import math

import mpmath as mp
import numpy as np
import pytest

import fe3d
from appendages import Beam, limits
from appendages.rod import Rod

# Every stiffness different, so no two motions share a frequency by accident (fe3d's BEAM).
BEAM = Beam(2.0, 3.0, 0.5, bending_stiffness_y=7.0, torsional_stiffness=1.5,
            torsional_inertia=0.02, axial_stiffness=900.0)
PAPER_ROD = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)
S_POINTS = np.array([1e-6j, 0.3j, 2.0 + 5.0j, 17.0j, -1.5 + 40.0j, 400.0 + 3000.0j])


def relative(A, B):
    """Largest entry difference over the largest entry, per leading index."""
    return np.abs(A - B).max(axis=(-2, -1)) / np.abs(B).max(axis=(-2, -1))


# -- rods ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("motion", ["axial", "torsion"])
def test_rod_W_is_the_closed_form_coth(motion):
    """W = coth(s tau)/(c s) (appendages.rod docstring), against mpmath at 40 digits. The
    argument z = s tau carries a relative rounding eps; coth(z) amplifies it by
    |z/(sinh z cosh z)| <= 1 off the poles, so a few eps: rtol 1e-14."""
    rod = Rod(2.0, 900.0 if motion == "axial" else 1.5, 0.5 if motion == "axial" else 0.02,
              motion=motion)
    s = np.concatenate([S_POINTS, [1e-40 + 1e-40j, 1e30j + 1e28]])
    W = rod.W(s)
    with mp.workdps(40):
        for sk, Wk in zip(s, W):
            exact = mp.coth(mp.mpc(sk) * rod.travel_time) / (rod.impedance * mp.mpc(sk))
            assert abs(Wk / complex(exact) - 1) < 1e-14, sk


def test_rod_limits_and_frequencies():
    """s -> 0: W = 1/(m s**2) + L/(3 S) + O(s**2) (z coth z = 1 + z**2/3 - ...); the poles
    are k pi/tau, the zeros (k - 1/2) pi/tau (Blevins table 8-19)."""
    rod = Rod(2.0, 900.0, 0.5)
    tau = rod.travel_time
    z = 1e-2
    # (m s^2 W - 1)/z^2 = 1/3 - z^2/45 + O(z^4): W m s^2 carries ~2 eps, so the difference
    # ~4e-16/z^2 = 4e-12 relative; the O(z^4) term 2/945 z^4 ~ 2e-11: rtol 1e-10
    s = 1j * z / tau
    flexible = (rod.W(s) * rod.rigid_inertia * s**2 - 1) / (1j * z) ** 2
    assert flexible.real == pytest.approx(1 / 3 + z**2 / 45, rel=1e-10)
    # that is the static flexibility L/(3 S) of the member under its own inertia
    assert (1 / 3) * tau**2 / rod.rigid_inertia == pytest.approx(rod.length / (3 * rod.stiffness),
                                                                 rel=1e-15)
    np.testing.assert_allclose(rod.natural_frequencies(3), np.array([1, 2, 3]) * math.pi / tau,
                               rtol=1e-15)
    zeros = rod.cantilever_frequencies(3)
    np.testing.assert_allclose(zeros, np.array([0.5, 1.5, 2.5]) * math.pi / tau, rtol=1e-15)
    # D = 1/W vanishes at no zero but is infinite at the zeros of W (the clamped frequencies)
    assert abs(rod.W(1j * zeros[0] * (1 + 1e-9))) < 1e-8 * abs(rod.W(1j * zeros[0] * 0.5))
    D = rod.dynamic_stiffness(np.array([0.0, 1j * 0.7 * zeros[0]]))
    assert D[0] == 0 and np.isfinite(D[1])


@pytest.mark.slow
def test_damped_rod_digamma_form_is_the_modal_sum():
    """W = 1/(m s^2) + (2/m) sum_k 1/(s^2 + 2 zeta w_k s + w_k^2), summed by mpmath (nsum
    with its Richardson extrapolation, 30 digits) against the digamma closed form: rtol 1e-12
    (scipy's complex digamma is good to ~1e-15 relative). The free-free convention (every
    free-free mode damped); the cantilever one is tests/appendages/test_cantilever_damping.py's."""
    rod = Rod(2.0, 900.0, 0.5, damping_ratio=0.05, damping_convention="free-free")
    m, Omega = rod.rigid_inertia, math.pi / rod.travel_time
    with mp.workdps(30):
        for s in (0.7j, 3.0 + 40.0j, 1j * Omega, 1e-3j, 500.0j):
            sm = mp.mpc(s)
            total = 1 / (m * sm**2) + mp.nsum(
                lambda k: 2 / (m * (sm**2 + 2 * 0.05 * k * Omega * sm + (k * Omega) ** 2)),
                [1, mp.inf])
            assert abs(rod.W(s) / complex(total) - 1) < 1e-12, s


def test_rod_projected_damping_is_the_sum_over_free_free_modes():
    """C_ii' = sum_j 2 zeta w_j O_ji O_ji' (appendages.rod) summed by mpmath (nsum, 25 digits)
    against the digamma closed form: the closed form loses ~eps log(b)/|g(b') - g(b)| to the
    difference of digammas, below 1e-14 here: rtol 1e-13."""
    rod = Rod(2.0, 900.0, 0.5, damping_ratio=0.05)
    n = 5
    C = rod.projected_damping(n)
    Omega = math.pi / rod.travel_time
    with mp.workdps(25):
        for i in range(n):
            for k in range(i, n):
                b, c = mp.mpf(i) + 0.5, mp.mpf(k) + 0.5
                total = mp.nsum(lambda j: 2 * 0.05 * j * Omega * (2 / mp.pi) ** 2 * b * c
                                / ((b**2 - j**2) * (c**2 - j**2)), [1, mp.inf])
                assert C[i, k] == pytest.approx(float(total), rel=1e-13), (i, k)
    # participation factors: their squares and the tail add up to the rigid inertia exactly
    l, _, _ = rod.cantilever_modes(50)
    assert math.fsum(l**2) + rod.cantilever_participation_tail(50) == pytest.approx(
        rod.rigid_inertia, rel=1e-14)


# -- W6 of the beam -----------------------------------------------------------------------------
def test_W6_against_the_finite_element_model():
    """fe3d's W6 (p = 5 elements, 40 of them: ~1e-12, its docstring) against the exact W6,
    relative to the largest entry at each s: 1e-10 (measured 7e-13)."""
    s = S_POINTS[1:5]  # the FE mesh resolves these; not |s| ~ 3000 (wavelength ~ 2 elements)
    W = BEAM.W6(s)
    W_fe = fe3d.root_compliance(BEAM, s, 40)
    assert np.all(relative(W, W_fe) < 1e-10)


def test_W6_rigid_limit_is_the_hand_computed_table():
    """s^2 W6 -> fe3d.rigid_root_compliance (its docstring table, derived by hand) as s -> 0;
    the flexible part is O(s^2) relative: (1e-5/w_1)^2 ~ 1e-12 here."""
    s = 1e-5j
    np.testing.assert_allclose(s**2 * BEAM.W6(s), fe3d.rigid_root_compliance(BEAM),
                               rtol=0, atol=1e-10 * np.abs(fe3d.rigid_root_compliance(BEAM)).max())


def test_W6_structure_symmetry_and_planar_blocks():
    s = S_POINTS
    W = BEAM.W6(s)
    assert W.shape == (s.size, 6, 6) and W.dtype == np.complex128
    np.testing.assert_array_equal(W, np.swapaxes(W, -1, -2))
    np.testing.assert_allclose(BEAM.W6(np.conj(s)), np.conj(W), rtol=1e-15, atol=0)
    # x-y plane: exactly the planar W; x-z plane: the planar W of EJ_y with the w-theta_y
    # coupling of opposite sign (theta_y = -dw/dx)
    planar = BEAM.W(s)
    np.testing.assert_array_equal(W[:, [1, 5]][:, :, [1, 5]], planar)
    xz = Beam(2.0, 7.0, 0.5).W(s)
    np.testing.assert_array_equal(W[:, [2, 4]][:, :, [2, 4]], xz * np.array([[1, -1], [-1, 1]]))
    # the motions decouple: nothing else
    mask = np.zeros((6, 6), bool)
    for i, j in ((0, 0), (1, 1), (1, 5), (5, 1), (5, 5), (2, 2), (2, 4), (4, 2), (4, 4), (3, 3)):
        mask[i, j] = True
    assert np.all(W[:, ~mask] == 0)
    D = BEAM.dynamic_stiffness6(s)
    assert np.all(relative(D @ W, np.broadcast_to(np.eye(6), W.shape)) < 1e-12)


def test_W6_is_stable_at_extreme_s():
    """No overflow or NaN from 1e-80 to 1e80 rad/s (the S_RANGE): the rigid term dominates at
    the bottom (s^2 W6 -> the rigid table) and every entry tends to zero at the top."""
    s = np.array([1e-80j, 1e-40 + 1e-40j, 1e40j, 9e79 + 1e79j])
    W = BEAM.W6(s)
    assert np.all(np.isfinite(W))
    np.testing.assert_allclose(s[0] ** 2 * W[0], fe3d.rigid_root_compliance(BEAM), rtol=1e-14,
                               atol=1e-14)
    assert np.abs(W[-1]).max() < 1e-30


def test_damped_W6_converges_to_the_undamped_one():
    """Damping zeta enters each mode's denominator as 2 zeta w s: at a point between poles the
    change is O(zeta) relative. Rods and planes agree with their own damped forms."""
    damped = Beam(2.0, 3.0, 0.5, bending_stiffness_y=7.0, torsional_stiffness=1.5,
                  torsional_inertia=0.02, axial_stiffness=900.0, damping_ratio=1e-7)
    s = np.array([0.3j, 2.0 + 5.0j, 17.0j])
    assert np.all(relative(damped.W6(s), BEAM.W6(s)) < 1e-5)
    strong = Beam(2.0, 3.0, 0.5, bending_stiffness_y=7.0, torsional_stiffness=1.5,
                  torsional_inertia=0.02, axial_stiffness=900.0, damping_ratio=0.05)
    W = strong.W6(s)
    np.testing.assert_allclose(W[:, 3, 3], strong.torsion_rod().W(s), rtol=1e-15)
    np.testing.assert_allclose(W[:, 1, 1], strong.W(s)[:, 0, 0], rtol=1e-15)


def test_rigid_torsion_and_inextensible_axial_motion():
    """torsional_stiffness None (with the inertia) and axial_stiffness None: the rigid limits,
    W = 1/(m_r s^2) exactly; and a stiff beam (GJ, EA 1e6 times larger) approaches them like
    1/stiffness."""
    rigid = Beam(2.0, 3.0, 0.5, torsional_inertia=0.02)
    s = np.array([0.3j, 2.0 + 5.0j])
    W = rigid.W6(s)
    np.testing.assert_allclose(W[:, 0, 0], 1 / (rigid.mass * s**2), rtol=1e-15)
    np.testing.assert_allclose(W[:, 3, 3], 1 / (0.02 * 2.0 * s**2), rtol=1e-15)
    stiff = Beam(2.0, 3.0, 0.5, torsional_stiffness=1.5e6, torsional_inertia=0.02,
                 axial_stiffness=9e8)
    # the static flexibility L/(3 S) relative to the rigid 1/(m_r |s|^2): ~1e-8 here
    W_stiff = stiff.W6(s)
    np.testing.assert_allclose(W_stiff[:, [0, 3], [0, 3]], W[:, [0, 3], [0, 3]], rtol=1e-6)
    assert rigid.clamped_frequencies6(10.0)[0] == pytest.approx(rigid.cantilever_frequencies(1)[0])


def test_planar_beam_is_refused_in_three_axes_by_name():
    planar = Beam(1.0, 1.0, 1.0)
    for call in (lambda: planar.W6(1j), lambda: planar.dynamic_stiffness6(1j),
                 lambda: planar.inertia_tensor, lambda: planar.truncated(3).W6(1j)):
        with pytest.raises(ValueError, match=r"torsional_inertia \[kg\*m\].*got torsional_inertia = None"):
            call()
    with pytest.raises(ValueError, match=r"torsional_inertia \[kg\*m\].*torsional_stiffness"):
        Beam(1.0, 1.0, 1.0, torsional_stiffness=2.0)
    with pytest.raises(ValueError, match=r"axial_stiffness must lie in .*\[N\]"):
        Beam(1.0, 1.0, 1.0, axial_stiffness=1e30)
    with pytest.raises(ValueError, match=r"poisson_ratio must lie in \(-1, 0.5\)"):
        Beam.circular_rod(1.0, 0.01, 7800.0, 2e11, poisson_ratio=0.5)


# -- sections -----------------------------------------------------------------------------------
def test_section_constructors_fill_every_property():
    E, nu, rho, d = 2.06e11, 0.3, 7800.0, 0.01
    G = E / (2 * (1 + nu))
    rod = PAPER_ROD
    I = math.pi * d**4 / 64
    assert rod.bending_stiffness == pytest.approx(E * I, rel=1e-15)
    assert rod.bending_stiffness_y == rod.bending_stiffness
    assert rod.torsional_stiffness == pytest.approx(G * 2 * I, rel=1e-15)
    assert rod.torsional_inertia == pytest.approx(rho * 2 * I, rel=1e-15)
    assert rod.axial_stiffness == pytest.approx(E * math.pi * d**2 / 4, rel=1e-15)
    # a thin tube: polar moment pi (D^4 - d^4)/32 (in mpmath: D^4 - d^4 cancels 3 digits)
    tube = Beam.tube(4.0, 0.05, 1e-4, 1600.0, 1.2e11)
    with mp.workdps(30):
        polar = mp.pi * (mp.mpf("0.05") ** 4 - mp.mpf("0.0498") ** 4) / 32
    assert tube.torsional_stiffness == pytest.approx(1.2e11 / 2.6 * float(polar), rel=1e-14)
    assert tube.torsional_inertia == pytest.approx(1600.0 * float(polar), rel=1e-14)
    # a plate strip: EJ_z uses thickness^3, EJ_y width^3, rho*I_p = rho b h (b^2 + h^2)/12
    b, h = 2.0, 0.04
    wing = Beam.rectangular(6.0, b, h, 40.0, 7e8)
    assert wing.bending_stiffness == pytest.approx(7e8 * b * h**3 / 12, rel=1e-15)
    assert wing.bending_stiffness_y == pytest.approx(7e8 * h * b**3 / 12, rel=1e-15)
    assert wing.torsional_inertia == pytest.approx(40.0 * b * h * (b * b + h * h) / 12, rel=1e-15)
    # the planar behaviour of the constructors is unchanged
    assert Beam(10.0, E * I, rho * math.pi * d**2 / 4).W(0.5j) == pytest.approx(rod.W(0.5j))


def test_rectangle_torsion_constant_against_the_series():
    """J_t = a b^3 [1/3 - (64/pi^5)(b/a) sum_{n odd} tanh(n pi a/(2b))/n^5] (Timoshenko &
    Goodier sec. 109) summed by mpmath at 30 digits: rtol 1e-14. Roark's table: 0.1406 a^4 for a
    square (0.141 printed, 3 digits), a b^3/3 for a thin strip (b/a -> 0)."""
    from appendages.beam import rectangle_torsion_constant

    for a, b in ((1.0, 1.0), (2.0, 1.0), (10.0, 1.0), (1.0, 0.02)):
        long, short = max(a, b), min(a, b)
        with mp.workdps(30):
            series = mp.nsum(lambda k: mp.tanh((2 * k + 1) * mp.pi * long / (2 * short))
                             / (2 * k + 1) ** 5, [0, mp.inf])
            exact = long * short**3 * (mp.mpf(1) / 3 - 64 / mp.pi**5 * short / long * series)
        assert rectangle_torsion_constant(a, b) == pytest.approx(float(exact), rel=1e-14)
    assert rectangle_torsion_constant(1.0, 1.0) == pytest.approx(0.1406, abs=5e-5)
    assert rectangle_torsion_constant(1000.0, 1.0) == pytest.approx(1000.0 / 3, rel=1e-3)


# -- truncations --------------------------------------------------------------------------------
@pytest.mark.parametrize("method, factor", [("craig-bampton", 4), ("residual", 4),
                                            ("free-free", 1.2)])
def test_three_axis_truncations_converge_to_W6(method, factor):
    """Every motion's truncation converges to the exact W6 at points between the poles. The
    error falls at least 4x per doubling of the modes kept with Craig-Bampton and residual
    models (measured 8-60x); a free-free truncation of a rod misses the static flexibility
    sum_{k>n} 2/(m (k pi/tau)^2) ~ 1/n, so only slowly (measured 1.4-1.7x: the rods get a
    share of the modes, ranked by frequency) - the reason for the other two methods."""
    s = np.array([0.7j, 3.0 + 4.0j, 9.0j])
    exact = BEAM.W6(s)
    errors = [relative(BEAM.truncated(n, method=method).W6(s), exact).max() for n in (8, 16, 32)]
    assert errors[1] < errors[0] / factor and errors[2] < errors[1] / factor, errors


@pytest.mark.parametrize("method", ["craig-bampton", "residual", "free-free"])
def test_three_axis_W6_equals_its_realisation(method):
    """W6 (mode sums and modal stiffness, O(n)) against the static condensation of
    root_model(6): the same model two ways, within the condensation's rounding (1e-10)."""
    model = Beam(2.0, 3.0, 0.5, bending_stiffness_y=7.0, torsional_stiffness=1.5,
                 torsional_inertia=0.02, axial_stiffness=900.0,
                 damping_ratio=0.02).truncated(12, method=method)
    s = np.array([0.7j, 3.0 + 4.0j, 9.0j, 30.0j])
    rm = model.root_model(6)
    assert rm.n_root == 6 and rm.tip.shape == (3, rm.n)
    from appendages.interface import inverse_symmetric

    assert np.all(relative(model.W6(s), inverse_symmetric(rm.dynamic_stiffness(s))) < 1e-10)
    # the planar model is the x-y part, unchanged
    np.testing.assert_array_equal(model.W(s), model.W(s))
    assert model.root_model().n_root == 2


def test_modes_are_chosen_by_frequency_across_motions_with_ties():
    """The three-axis truncation keeps the n lowest modes of all motions; a round section's
    two planes tie and are kept together (so the model stays symmetric)."""
    counts = BEAM.truncated(10).modes_per_motion
    freqs = {"xy": Beam(2.0, 3.0, 0.5).cantilever_frequencies(10),
             "xz": Beam(2.0, 7.0, 0.5).cantilever_frequencies(10),
             "torsion": BEAM.torsion_rod().cantilever_frequencies(10),
             "axial": BEAM.axial_rod().cantilever_frequencies(10)}
    cutoff = np.sort(np.concatenate(list(freqs.values())))[9]
    assert counts == {k: int(np.sum(v <= cutoff)) for k, v in freqs.items()}
    assert sum(counts.values()) == 10
    round_counts = PAPER_ROD.truncated(5).modes_per_motion
    assert round_counts["xy"] == round_counts["xz"] == 3 and sum(round_counts.values()) == 6


def test_three_axis_tip_rows_measure_the_elastic_tip_motion():
    """A static tip load on the cantilevered truncation (root coordinates held): the tip rows
    give the cantilever's tip deflections F L^3/(3 EJ) in each plane and twist T L/GJ.
    Craig-Bampton spans the static shapes only in the limit: the dropped modes' share
    sum_{k>n} psi_k(L)^2/w_k^2 falls like n^-3 in bending (6e-5 with the 35 modes of the x-y
    plane here) and like 1/n for the rod (1e-2 with 15): rtol 2e-4 and 2e-2."""
    model = BEAM.truncated(60)
    rm = model.root_model(6)
    K, n = rm.stiffness, rm.n
    tip_v, tip_w, twist = rm.tip_rows
    for row, expected, rtol in ((tip_v, 2.0**3 / (3 * 3.0), 2e-4),
                                (tip_w, 2.0**3 / (3 * 7.0), 2e-4), (twist, 2.0 / 1.5, 2e-2)):
        # unit load at the tip in that motion: f = row (virtual work), q = K^-1 f on the
        # internal coordinates, tip motion = row . q
        internal = np.arange(6, n)
        q = np.linalg.solve(K[np.ix_(internal, internal)], row[internal])
        assert row[internal] @ q == pytest.approx(expected, rel=rtol)


def test_craig_bampton_W_is_linear_in_modes_and_bounded_in_memory():
    """Issue 10: the Craig-Bampton W at 400 modes on 5000 frequencies, O(n) per frequency in
    chunks: the same values as a direct evaluation at a few points (the condensation, O(n^3)
    per frequency, feasible for 3 points)."""
    model = PAPER_ROD.truncated(400)
    omega = np.geomspace(1e-2, 1e4, 5000)
    W = model.W(1j * omega)
    assert W.shape == (5000, 2, 2) and np.all(np.isfinite(W))
    from appendages.interface import inverse_2x2

    pick = [0, 2500, 4999]
    direct = inverse_2x2(model.root_model().dynamic_stiffness(1j * omega[pick]))
    assert np.all(relative(W[pick], direct) < 1e-9)


@pytest.mark.slow
def test_damped_craig_bampton_build_at_many_modes_uses_closed_form_overlaps():
    """The damping projection needs 4 n + 400 free-free modes' overlaps with n cantilever
    modes: closed forms now (appendages.beam._shape_products), checked at the nearly
    coincident pairs against mpmath quadrature of the stable shapes at 20 digits."""
    beam = Beam(2.0, 3.0, 0.7)
    O = beam.free_cantilever_overlap(300, 300)
    from appendages.beam import _shape_terms

    def shape(x, kind):
        e = mp.exp(-x)
        if kind == "free-free":
            den = (1 - e * e) - 2 * mp.sin(x) * e
            sigma = ((1 + e * e) - 2 * mp.cos(x) * e) / den
            c_plus, sign = (mp.cos(x) - mp.sin(x) - e) / den, 1
        else:
            den = (1 - e * e) + 2 * mp.sin(x) * e
            sigma = ((1 + e * e) + 2 * mp.cos(x) * e) / den
            c_plus, sign = (mp.sin(x) - mp.cos(x) - e) / den, -1
        return lambda t: (sign * (mp.cos(x * t) - sigma * mp.sin(x * t)) + c_plus * mp.exp(x * (t - 1))
                          + (1 + sigma) / 2 * mp.exp(-x * t))

    assert _shape_terms  # the shapes above restate the module's stable form in mpmath
    with mp.workdps(20):
        for k, i in ((0, 1), (1, 2), (30, 31), (30, 32)):
            xk = mp.findroot(lambda x: mp.cos(x) - 1 / mp.cosh(x), (k + 1.5) * mp.pi)
            xi = mp.findroot(lambda x: mp.cos(x) + 1 / mp.cosh(x), (i + 0.5) * mp.pi)
            f, g = shape(xk, "free-free"), shape(xi, "clamped-free")
            exact = mp.quad(lambda t: f(t) * g(t), mp.linspace(0, 1, 2 * i + 8))
            # a few ulps of 1 for the near pairs; the boundary formula's eps x/|dx| beyond
            assert abs(O[k, i] - float(exact)) < 1e-14 * max(1, abs(float(exact))) + 2e-16 * xk, (k, i)
    with limits.raised(modes=1000):
        assert np.all(np.isfinite(beam.free_cantilever_overlap(4400, 1000)[-3:, -3:]))
