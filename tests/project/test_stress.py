"""Numerical stress tests (issue 6): extreme mode numbers, frequencies, chain sizes, stiffness
and mass ratios, and long simulations. Each result is checked against a closed form or a limit,
or must raise a clear error.
"""

import math

import mpmath as mp
import numpy as np
import pytest

import controllers
from appendages import Beam
from appendages.chain import HingedChain
from spacecraft import Hub, Mount, Spacecraft

ROD = dict(length=10.0, diameter=0.01, density=7800.0, youngs_modulus=2.06e11)


@pytest.fixture(scope="module")
def rod():
    return Beam.circular_rod(**ROD)


def rigid_W_times_s2(length, mass, inertia, com):
    """lim s**2 W(s) for s -> 0 of any free appendage: its rigid-body flexibility.

    A rigid body of mass m and inertia J about its centre of mass at x = com, loaded at x = 0
    by F and M: m a_c = F, J alpha = M - com*F, delta'' = a_c - com*alpha, phi'' = alpha, so
    s**2 W = [[1/m + com**2/J, -com/J], [-com/J, 1/J]].
    """
    return np.array([[1.0 / mass + com**2 / inertia, -com / inertia],
                     [-com / inertia, 1.0 / inertia]])


# -- beam -----------------------------------------------------------------------------------
def test_1000_modes_frequencies_are_the_asymptotic_roots(rod):
    """cos x cosh x = 1: x_k = (k + 1/2) pi + O(e**-x_k), i.e. exact in double beyond k ~ 12.

    The first two against Blevins (1979) table 8-1: 4.73004074, 7.85320462.
    """
    w = rod.natural_frequencies(1000)
    x = np.sqrt(w / rod.frequency_scale)
    assert np.all(np.isfinite(w)) and np.all(np.diff(w) > 0)
    np.testing.assert_allclose(x[:2], [4.73004074, 7.85320462], rtol=2e-9, atol=0)
    k = np.arange(1, 1001)
    # rtol 4e-15: x_k computed through sqrt(w/scale), a few ulps of round-off
    np.testing.assert_allclose(x[20:], (k[20:] + 0.5) * np.pi, rtol=4e-15, atol=0)


@pytest.mark.parametrize("angle_deg", [0.0, 30.0, 89.0, 89.999, 135.0, 180.0])
def test_W_finite_and_reciprocal_for_s_from_1e_minus8_to_1e8(rod, angle_deg):
    """No overflow, NaN or asymmetry anywhere on rays from |s| = 1e-8 to 1e8 rad/s.

    89.999 deg: 1.7e-5 off the imaginary axis, where the undamped W peaks at ~3e4 times its
    smooth size (on the axis itself Beam.W refuses the poles with a ValueError).
    """
    s = np.geomspace(1e-8, 1e8, 801) * np.exp(1j * math.radians(angle_deg))
    W = rod.W(s)
    assert W.shape == (801, 2, 2) and W.dtype == np.complex128
    assert np.all(np.isfinite(W))
    assert np.array_equal(W[:, 0, 1], W[:, 1, 0])
    # measured bit-equal: each operation of W (complex +, -, *, /, exp, sqrt of numpy and
    # libm) commutes with conjugation here; the tolerance allows for a libm whose complex
    # functions do not (1 ulp each, times W's condition number, ~1e2 near poles)
    np.testing.assert_allclose(rod.W(np.conj(s)), np.conj(W), rtol=1e-13, atol=0)


def test_W_small_s_limit_is_the_rigid_body(rod):
    """s**2 W(s) -> rigid flexibility with error O(s**2 m/EJ L**3): < 1e-14 at |s| = 1e-8."""
    s = np.array([1e-8, 1e-8j, 1e-8 * np.exp(0.7j)])
    rigid = rigid_W_times_s2(rod.length, rod.mass, rod.inertia, rod.length / 2)
    got = (s[:, None, None] ** 2) * rod.W(s)
    np.testing.assert_allclose(got, np.broadcast_to(rigid, got.shape), rtol=1e-12, atol=0)


def test_W_large_s_matches_60_digit_closed_form(rod):
    """At |s| = 1e8 rad/s (|beta L| ~ 3.6e4) against the closed form in mpmath (60 digits).

    cosh(beta L) ~ 10**15000 there: only the scaled evaluation stays finite in double.
    The mpmath form: W1 = L**3/EJ (cos x sinh x - sin x cosh x)/(x**3 (1 - cos x cosh x)) etc.
    """
    EJ, rhoA, L = rod.bending_stiffness, rod.linear_density, rod.length
    for s in (1e8 * np.exp(1j * 0.3), 1e8j * (1 + 1e-3j), -3e7 + 2e7j):
        got = rod.W(s)
        with mp.workdps(60):
            x = mp.root(-mp.mpc(s) ** 2 * rhoA * L**4 / EJ, 4)
            D = 1 - mp.cos(x) * mp.cosh(x)
            w1 = L**3 / EJ * (mp.cos(x) * mp.sinh(x) - mp.sin(x) * mp.cosh(x)) / (x**3 * D)
            w2 = L**2 / EJ * mp.sin(x) * mp.sinh(x) / (x**2 * D)
            w4 = -L / EJ * (mp.cos(x) * mp.sinh(x) + mp.sin(x) * mp.cosh(x)) / (x * D)
        for value, ref in ((got[0, 0], w1), (got[0, 1], w2), (got[1, 1], w4)):
            # rtol 1e-9: the double-precision argument s**2 carries ~1e-16 relative error,
            # amplified by |x| ~ 3.6e4 in the phase of the exponentials
            assert abs(value - complex(ref)) <= 1e-9 * abs(complex(ref))


def test_mode_shapes_orthonormal_up_to_mode_300(rod):
    """integral rho*A phi_j phi_k dx = delta_jk (mass normalisation), free-free and cantilever.

    Composite 40-point Gauss-Legendre on 120 panels: exact for the polynomial part and far
    beyond the oscillation of mode 300 (x_300 ~ 944 rad: ~1.25 oscillations per panel).
    """
    nodes, weights = np.polynomial.legendre.leggauss(40)
    edges = np.linspace(0.0, rod.length, 121)
    half = np.diff(edges)[:, None] / 2
    x = ((edges[:-1, None] + edges[1:, None]) / 2 + half * nodes).ravel()
    wq = (half * weights).ravel()
    for boundary in ("free-free", "clamped-free"):
        phi = rod.mode_shapes(x, 300, boundary=boundary)
        assert np.all(np.isfinite(phi))
        gram = rod.linear_density * (phi * wq[:, None]).T @ phi
        np.testing.assert_allclose(gram, np.eye(300), rtol=0, atol=1e-10)


def test_free_free_mode_ends_at_high_mode_numbers(rod):
    """Free-free modes normalised to integral phi**2 = L have |phi(0)| = |phi(L)| = 2 at any k.

    (Blevins table 8-1: phi(0) = 2; by symmetry |phi(L)| = 2.) Mass-normalised: 2/sqrt(m).
    """
    phi = rod.mode_shapes([0.0, rod.length], 1000)
    np.testing.assert_allclose(np.abs(phi), 2.0 / math.sqrt(rod.mass), rtol=1e-12, atol=0)


def test_participation_tails_match_trigamma_closed_form(rod):
    """Cantilever participation factors at 1000 modes, through their exact tails.

    Sum over all modes of l_1**2 = m and of l_2**2 = m L**2/3 (effective masses). With
    l_1 = 2 sigma_k rho/(beta_k sqrt(m)), l_2 = 2 rho/(beta_k**2 sqrt(m)) (unnormalised
    shapes with integral psi**2 = L), sigma_k = 1 to e**-x_k and beta_k L = (k - 1/2) pi to
    e**-x_k for k > 12, the tails beyond N modes are
        m - sum_{k<=N} l_1**2 = 4 m/pi**2 psi_1(N + 1/2),
        m L**2/3 - sum l_2**2 = 4 m L**2/pi**4 psi_3(N + 1/2)/6,
    psi_n the polygamma functions (sum_{k>N} 1/(k - 1/2)**p = psi_{p-1}(N + 1/2)/(p-1)!).
    """
    N = 1000
    part = rod.modal_participation(N)
    assert part.shape == (N, 2) and np.all(np.isfinite(part))
    m, L = rod.mass, rod.length
    tail_1 = 4 * m / math.pi**2 * float(mp.polygamma(1, N + 0.5))
    tail_2 = 4 * m * L**2 / math.pi**4 * float(mp.polygamma(3, N + 0.5)) / 6
    # the tails are 4e-4 m and 1e-11 m L**2/3: comparing the differences at 1e-7 (resp. 1e-3)
    # of themselves means the sums are right to ~4e-11 (resp. ~1e-14) of the totals
    np.testing.assert_allclose(m - math.fsum(part[:, 0] ** 2), tail_1, rtol=1e-7)
    np.testing.assert_allclose(m * L**2 / 3 - math.fsum(part[:, 1] ** 2), tail_2, rtol=1e-3)


# -- chains -----------------------------------------------------------------------------------
def test_one_body_chains_have_closed_form_W():
    """n = 1: a free rigid rod (root='rigid'), and the rod behind a root spring (root='hinged').

    Rigid: W = rigid flexibility / s**2 (no elastic pole). Hinged: the massless mount adds the
    spring's flexibility 1/c to the rotation, W4 = rigid_4/s**2 + 1/c.
    """
    L, m, J, c = 2.0, 3.0, 3.0 * 4.0 / 12.0, 50.0
    s = np.array([0.3j, 2.0 + 1.0j, 40.0j])
    rigid = rigid_W_times_s2(L, m, J, L / 2)
    chain = HingedChain([L], [m], [J], [])
    # one body: W is a 2 x 2 closed form of a dozen operations on O(1) numbers each side
    # (no cancellation at these s), ~20 eps relative; rtol 450 eps
    np.testing.assert_allclose(chain.W(s), rigid / (s[:, None, None] ** 2), rtol=1e-13, atol=0)
    assert chain.poles().size == 0
    hinged = HingedChain([L], [m], [J], [c], root="hinged")
    expected = rigid / (s[:, None, None] ** 2) + np.array([[0.0, 0.0], [0.0, 1.0 / c]])
    np.testing.assert_allclose(hinged.W(s), expected, rtol=1e-12, atol=0)


def test_one_body_hinged_chain_has_no_elastic_pole():
    """One rigid body behind a spring hinge at a massless mount: the free appendage's motion is
    rigid (the massless mount carries no inertia), so W has no finite pole besides s = 0."""
    chain = HingedChain([10.0], [6.0], [50.0], [20.0], root="hinged")
    assert chain.poles().size == 0


@pytest.mark.parametrize("n_bodies", [2, 10, 50, 200])
def test_rfem_chains_up_to_200_bodies_are_accurate(rod, n_bodies):
    """Rigid-body properties exact at every n; W symmetric and finite; the first poles converge
    to the exact beam's at second order in 1/n (RFEM: error ~ C/n**2)."""
    chain = HingedChain.rfem(rod, n_bodies)
    np.testing.assert_allclose([chain.mass, chain.length], [rod.mass, rod.length], rtol=1e-13)
    # the frozen pieces have the rod's mass distribution: J about the centre of mass is m L**2/12
    np.testing.assert_allclose(chain.inertia, rod.inertia, rtol=1e-12)
    s = 1j * np.geomspace(1e-3, 1e3, 50) + 0.01
    W = chain.W(s)
    assert np.all(np.isfinite(W)) and np.array_equal(W[:, 0, 1], W[:, 1, 0])
    if n_bodies >= 10:
        exact = rod.natural_frequencies(3)
        error = np.abs(chain.poles()[:3] / exact - 1)
        coarse = np.abs(HingedChain.rfem(rod, n_bodies // 2).poles()[:3] / exact - 1)
        assert np.all(error < coarse / 3.0)      # second order: ratio ~ 4 per halving
        assert error[0] < 40.0 / n_bodies**2     # ~ 0.3/n**2 measured; a generous bound


@pytest.mark.parametrize("n_bodies", [10, 200])
def test_chain_W_rigid_body_limit_at_small_s(rod, n_bodies):
    """s**2 W(s) -> rigid flexibility with error ~ (|s|/w_1)**2 ~ 1e-13 at |s| = 1e-6 rad/s."""
    chain = HingedChain.rfem(rod, n_bodies)
    small = np.array([1e-6j])
    np.testing.assert_allclose((small[:, None, None] ** 2 * chain.W(small))[0],
                               rigid_W_times_s2(rod.length, rod.mass, rod.inertia,
                                                rod.length / 2), rtol=1e-9)


def test_200_body_chain_poles_pass_the_sylvester_inertia_count():
    """A 200-body uniform chain: all 199 poles finite and distinct, and each of the first three
    confirmed independently of the eigensolver: just below pole k, K - w**2 M has exactly
    2 + k negative eigenvalues (the two rigid-body modes and k elastic ones; Sylvester's law of
    inertia, Wittrick-Williams style), just above it 3 + k.
    """
    n = 200
    lengths = np.full(n, 0.05)
    masses = np.full(n, 0.02)
    chain = HingedChain(lengths, masses, masses * 0.05**2 / 12, np.full(n - 1, 3.0))
    poles = chain.poles()
    assert poles.size == n - 1 and np.all(np.isfinite(poles)) and np.all(np.diff(poles) > 0)
    rm = chain.root_model()
    K, M = rm.stiffness, rm.mass

    def inertia_count(w):
        # number of eigenvalues of (K, M) below w**2 = negative eigenvalues of K - w**2 M
        # (Sylvester's law of inertia), by an LDL^T in double precision
        import scipy.linalg
        _, d, _ = scipy.linalg.ldl(K - w**2 * M)
        return int(np.sum(np.linalg.eigvalsh(d) < 0))

    for k in range(3):
        w = poles[k]
        # 2 rigid-body modes count below any w > 0
        assert inertia_count(w * (1 - 1e-9)) == 2 + k
        assert inertia_count(w * (1 + 1e-9)) == 3 + k


@pytest.mark.parametrize("stiffness", [1e-6, 1e-3, 1.0, 1e3, 1e6, 1e9])
def test_hinge_stiffness_range_scales_frequencies_by_sqrt(rod, stiffness):
    """K is linear in c, M independent of it: poles and zeros scale exactly as sqrt(c).

    Checked for the free chain and for the chain on the default hub (coupled frequencies).
    """
    base = HingedChain.three_body(rod.length, rod.mass, 0.26989, 1.0)
    chain = HingedChain.three_body(rod.length, rod.mass, 0.26989, stiffness)
    scale = math.sqrt(stiffness)
    np.testing.assert_allclose(chain.poles(), base.poles() * scale, rtol=1e-9)
    for r in (1, 2, 4):
        np.testing.assert_allclose(chain.zeros(r), base.zeros(r) * scale, rtol=1e-9)
    hub = Hub(100.0, 50.0)
    coupled = Spacecraft(hub, [Mount(chain, (0.5, 0.0), 0.0)]).natural_frequencies(2)
    coupled_1 = Spacecraft(hub, [Mount(base, (0.5, 0.0), 0.0)]).natural_frequencies(2)
    np.testing.assert_allclose(coupled, coupled_1 * scale, rtol=1e-9)


@pytest.mark.parametrize("stiffness", [1e-6, 1.0, 1e9])
def test_chain_tends_to_the_rigid_rod_well_below_its_first_pole(rod, stiffness):
    """At s = 1e-3 w_1 j, s**2 W = rigid flexibility + s**2 G (G the static flexibility,
    ~ rigid/w_1**2): relative difference ~ (s/w_1)**2 = 1e-6, at any hinge stiffness."""
    chain = HingedChain.three_body(rod.length, rod.mass, 0.26989, stiffness)
    s = np.array([1e-3j * chain.poles()[0]])
    rigid = rigid_W_times_s2(rod.length, rod.mass, rod.inertia, rod.length / 2)
    got = (s[:, None, None] ** 2 * chain.W(s))[0]
    np.testing.assert_allclose(got, rigid, rtol=1e-5, atol=0)


# -- hub ratios -------------------------------------------------------------------------------
@pytest.mark.parametrize("ratio", [1e-6, 1e-3, 1.0, 1e3, 1e6])
def test_hub_ratios_coupled_frequencies_exact_and_limits(rod, ratio):
    """Hub mass and inertia = ratio x the beam's (mount at the hub's centre).

    The truncated plant's first coupled frequencies match the exact ones (Wittrick-Williams on
    the exact W) at every ratio, and the limits hold: ratio -> 0 gives the free-free
    frequencies, ratio -> infinity the cantilever ones, with corrections of order
    min(ratio, 1/ratio).
    """
    hub = Hub(ratio * rod.mass, ratio * rod.inertia)
    exact = Spacecraft(hub, [Mount(rod, (0.0, 0.0), 0.0)]).natural_frequencies(3, exact=True)
    model = Spacecraft(hub, [Mount(rod.truncated(24), (0.0, 0.0), 0.0)])
    # rtol 1e-5: near the free-free limit (light hub) Craig-Bampton frequencies converge like
    # the free-free poles of the truncation table (n**-5: 2.4e-6 for the third at n = 24)
    np.testing.assert_allclose(model.natural_frequencies(3), exact, rtol=1e-5)
    if ratio <= 1e-6:
        np.testing.assert_allclose(exact, rod.natural_frequencies(3), rtol=1e-4)
    if ratio >= 1e6:
        np.testing.assert_allclose(exact, rod.cantilever_frequencies(3), rtol=1e-4)


def test_extreme_hub_ratios_are_accurate_or_refused(rod):
    """At 1e-12 and 1e12 the assembled model is ill-conditioned: either the frequencies are
    still right (compared with the exact roots) or Spacecraft raises a ValueError saying why."""
    for ratio in (1e-12, 1e12):
        hub = Hub(ratio * rod.mass, ratio * rod.inertia)
        exact = Spacecraft(hub, [Mount(rod, (0.0, 0.0), 0.0)]).natural_frequencies(2, exact=True)
        craft = Spacecraft(hub, [Mount(rod.truncated(24), (0.0, 0.0), 0.0)])
        try:
            got = craft.natural_frequencies(2)
        except ValueError as exc:
            assert "stiffness" in str(exc) or "precision" in str(exc)
            continue
        np.testing.assert_allclose(got, exact, rtol=1e-5)  # truncation error, as above


# -- long simulation --------------------------------------------------------------------------
@pytest.fixture(scope="module")
def long_free_run(rod):
    """1e5 s of free motion of the undamped hub + 8-mode beam, sampled every 1 s (exact).

    The plant's states are mass-normalised modal coordinates [eta, eta_dot] with A =
    [[0, I], [-Omega**2, 0]]: energy = (|eta_dot|**2 + sum w_k**2 eta_k**2)/2 is constant, and
    the rigid-body coordinates (w_k = 0: the attitude; translations only when forces act)
    move as eta0 + eta_dot0 t exactly.
    """
    craft = Spacecraft(Hub(100.0, 50.0), [Mount(rod.truncated(8), (0.5, 0.0), 0.0)])
    plant = craft.plant()
    n = plant.nstates // 2
    A = np.asarray(plant.A)
    lam = -np.diag(A[n:, :n])
    n_rigid = int(np.sum(lam == 0.0))
    assert n_rigid >= 1 and np.all(lam[n_rigid:] > 0)
    rng = np.random.default_rng(6)
    x0 = rng.standard_normal(2 * n) * np.concatenate([1.0 / np.sqrt(np.maximum(lam, 1.0)),
                                                      np.ones(n)])
    T = np.arange(100_001, dtype=float)
    response = controllers.simulate(plant, T, 0.0, x0, squeeze=False)
    return T, np.asarray(response.states), x0, lam, n, n_rigid


def test_long_undamped_simulation_conserves_energy(long_free_run):
    """Energy of the free undamped system constant to 1e-9 relative over 1e5 steps."""
    T, X, x0, lam, n, r = long_free_run
    eta, rate = X[:n], X[n:]
    energy = 0.5 * (np.sum(rate[r:] ** 2, axis=0) + lam[r:] @ eta[r:] ** 2)
    np.testing.assert_allclose(energy, energy[0], rtol=1e-9, atol=0)


def test_long_undamped_simulation_has_no_rigid_body_drift(long_free_run):
    """Rigid-body coordinates exactly eta0 + eta_dot0 t after 1e5 steps, to round-off
    (1e-11 of their size: ~1e5 steps of 1e-16 accumulated)."""
    T, X, x0, lam, n, r = long_free_run
    eta, rate = X[:n], X[n:]
    rigid_expected = x0[:r, None] + x0[n:n + r, None] * T
    scale = np.abs(rigid_expected).max()
    np.testing.assert_allclose(eta[:r], rigid_expected, rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(rate[:r], np.broadcast_to(x0[n:n + r, None], rate[:r].shape),
                               rtol=0, atol=1e-12 * np.abs(x0[n:n + r]).max())
