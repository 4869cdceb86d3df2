"""The exact distributed beam: W(s), frequencies, zeros, mode shapes, truncations."""

import math

import mpmath as mp
import numpy as np
import scipy.special
import pytest

from appendages import Beam, characteristic_roots

PAPER_ROD = dict(length=10.0, diameter=0.01, density=7800.0, youngs_modulus=2.06e11)


@pytest.fixture(scope="module")
def rod():
    return Beam.circular_rod(**PAPER_ROD)


def W_mpmath(beam, s, dps=None):
    """Reference W(s) by solving the boundary-value problem in 60-digit arithmetic.

    w = a cosh(bx) + b sinh(bx) + c cos(bx) + d sin(bx), b**4 = -s**2 rho*A/EJ, with
    EJ w'''(0) = F, EJ w''(0) = -M, w''(L) = w'''(L) = 0 (virtual work, module docstring).
    Independent of the closed form and its branches. The working precision grows with |beta L|
    so that the exponentially large basis functions keep 40 significant digits.
    """
    beta_L = (abs(s) ** 2 * beam.linear_density / beam.bending_stiffness) ** 0.25 * beam.length
    if beta_L > 300:
        return W_mpmath_closed_form(beam, s)
    if dps is None:
        dps = int(50 + 2 * beta_L / math.log(10))
    with mp.workdps(dps):
        s = mp.mpc(s)
        EJ, rhoA, L = mp.mpf(beam.bending_stiffness), mp.mpf(beam.linear_density), mp.mpf(beam.length)
        be = mp.root(-s**2 * rhoA / EJ, 4)
        ch, sh, c, sn = mp.cosh, mp.sinh, mp.cos, mp.sin

        def rows(x):
            bx = be * x
            return {0: [ch(bx), sh(bx), c(bx), sn(bx)],
                    1: [be * sh(bx), be * ch(bx), -be * sn(bx), be * c(bx)],
                    2: [be**2 * ch(bx), be**2 * sh(bx), -be**2 * c(bx), -be**2 * sn(bx)],
                    3: [be**3 * sh(bx), be**3 * ch(bx), be**3 * sn(bx), -be**3 * c(bx)]}
        r0, rL = rows(0), rows(L)
        A = mp.matrix([r0[3], r0[2], rL[2], rL[3]])
        out = np.empty((2, 2), dtype=complex)
        for j, (F, M) in enumerate([(1, 0), (0, 1)]):
            co = mp.lu_solve(A, mp.matrix([F / EJ, -M / EJ, 0, 0]))
            out[0, j] = complex(sum(r0[0][i] * co[i] for i in range(4)))
            out[1, j] = complex(sum(r0[1][i] * co[i] for i in range(4)))
        return out


def W_mpmath_closed_form(beam, s, dps=50):
    """The unscaled closed form (module docstring of appendages.beam) in 50-digit arithmetic.

    Used where |beta L| > 300: mpmath's exponent range holds cosh(beta L) without overflow and
    50 digits leave no cancellation there. The closed form is checked against the
    boundary-value solution above over the overlapping range.
    """
    with mp.workdps(dps):
        s = mp.mpc(s)
        EJ, L = mp.mpf(beam.bending_stiffness), mp.mpf(beam.length)
        x = mp.root(-s**2 * mp.mpf(beam.linear_density) / EJ, 4) * L
        D = 1 - mp.cos(x) * mp.cosh(x)
        w1 = L**3 / EJ * (mp.cos(x) * mp.sinh(x) - mp.sin(x) * mp.cosh(x)) / (x**3 * D)
        w2 = L**2 / EJ * mp.sin(x) * mp.sinh(x) / (x**2 * D)
        w4 = -L / EJ * (mp.cos(x) * mp.sinh(x) + mp.sin(x) * mp.cosh(x)) / (x * D)
        return np.array([[complex(w1), complex(w2)], [complex(w2), complex(w4)]])


def test_closed_form_reference_agrees_with_boundary_value_reference(rod):
    for s in [3.0j, 40 + 300j, 2e4j * (1 + 0.01j)]:
        np.testing.assert_allclose(W_mpmath_closed_form(rod, s), W_mpmath(rod, s), rtol=1e-25)


# -- exact W -------------------------------------------------------------------------------------
@pytest.mark.parametrize("magnitude", [1e-8, 1e-5, 1e-3, 0.1, 1.0, 3.0, 30.0, 1e3, 1e5, 1e8])
@pytest.mark.parametrize("angle_deg", [90.0, 60.0, 135.0, 10.0])
def test_W_matches_high_precision_boundary_value_solution(rod, magnitude, angle_deg):
    # Reference: 60-digit mpmath solution of the BVP. Tolerance 1e-10 relative to the largest
    # entry (the requirement), at |s| from 1e-8 to 1e8 and angles including the
    # imaginary axis (90 deg) and the left half plane. Points are kept off the poles by the
    # irrational angles/magnitudes relative to the natural frequencies.
    s = magnitude * np.exp(1j * np.deg2rad(angle_deg)) * (1 + 0.0123j)
    ours = rod.W(s)
    ref = W_mpmath(rod, s)
    assert ours.shape == (2, 2) and ours.dtype == np.complex128
    np.testing.assert_allclose(ours, ref, rtol=1e-10, atol=1e-10 * np.abs(ref).max())


def test_W_entrywise_relative_accuracy_on_imaginary_axis(rod):
    # Each entry separately, not only relative to the largest one (1e-10, issue 2), up to 1e6
    # rad/s. Beyond, W2 = L^2/EJ sin x sinh x/(x^2 D) oscillates with phase x = beta L ~ 1e4;
    # the rounding of the float inputs alone (a few ulp of x, ~1e-11 rad) limits any
    # double-precision evaluation's entrywise accuracy to ~ x eps/|sin x|; the matrix-relative
    # accuracy (test above) stays at 1e-10.
    for omega in [1e-8, 1e-4, 0.5, 2.0, 5.0, 11.0, 300.0, 1e4, 1e6]:
        s = 1j * omega * 1.000123
        ref = W_mpmath(rod, s)
        np.testing.assert_allclose(rod.W(s), ref, rtol=1e-10, atol=0)


def test_W_shapes_dtype_and_no_overflow():
    beam = Beam(1.0, 1.0, 1.0)
    s = 1j * np.logspace(-8, 8, 401).reshape(401, 1) * np.array([1.0, 1 + 1e-3j])
    W = beam.W(s)
    assert W.shape == (401, 2, 2, 2)
    assert W.dtype == np.complex128
    assert np.all(np.isfinite(W))
    assert beam.W(1j).shape == (2, 2)


def test_W_symmetry_and_conjugate_symmetry():
    beam = Beam(3.0, 50.0, 0.4)
    rng = np.random.default_rng(1)
    s = rng.normal(size=50) * 10 + 1j * rng.normal(size=50) * 10
    W = beam.W(s)
    np.testing.assert_array_equal(W[..., 0, 1], W[..., 1, 0])
    # measured bit-equal: each operation of W (complex +, -, *, /, exp, sqrt of numpy and
    # libm) commutes with conjugation here; the tolerance allows for a libm whose complex
    # functions do not (1 ulp each, times W's condition number, ~1e2 near poles)
    np.testing.assert_allclose(beam.W(np.conj(s)), np.conj(W), rtol=1e-13, atol=0)


def test_W_rigid_body_limit():
    # s -> 0: W -> [[1/m + (L/2)^2/J, -(L/2)/J], [-(L/2)/J, 1/J]]/s^2 (rigid rod, J = mL^2/12),
    # next term the constant static flexibility G (O(1)), so at s = 1e-6 the relative
    # difference is ~ G s^2 m ~ 1e-12.
    beam = Beam(2.0, 7.0, 3.0)
    m, J, L = beam.mass, beam.inertia, beam.length
    s = 1e-6j
    rigid = np.array([[1 / m + L**2 / (4 * J), -L / (2 * J)], [-L / (2 * J), 1 / J]]) / s**2
    np.testing.assert_allclose(beam.W(s), rigid, rtol=1e-10)


def test_paper_signs(rod):
    # DESIGN.md conventions: k1 > 0, k2 = k3 < 0, k4 > 0 (high-frequency gains s^2 W of the
    # two-mode model) and likewise the rigid-body parts.
    k = rod.truncated(2, method="free-free").gains()
    assert k[0] > 0 and k[1] < 0 and k[1] == k[2] and k[3] > 0


def test_s_zero_and_bad_types_rejected(rod):
    with pytest.raises(ValueError, match="s = 0"):
        rod.W(0.0)
    with pytest.raises(TypeError, match="s must be"):
        rod.W("1j")
    with pytest.raises(ValueError, match="finite"):
        rod.W(np.nan)


# -- frequencies and zeros --------------------------------------------------------------------
def test_characteristic_roots_textbook_values():
    # Blevins (1979), table 8-1: beta_k L to 9 significant digits.
    np.testing.assert_allclose(characteristic_roots("free-free", 5),
                               [4.730040745, 7.853204624, 10.99560784, 14.13716549, 17.27875966],
                               rtol=1e-9)
    np.testing.assert_allclose(characteristic_roots("clamped-free", 4),
                               [1.875104069, 4.694091133, 7.854757438, 10.99554073], rtol=1e-9)
    # pinned-free (tan x = tanh x): 3.926602312, 7.068582745 (Blevins table 8-1)
    np.testing.assert_allclose(characteristic_roots("pinned-free", 2), [3.926602312, 7.068582745],
                               rtol=1e-9)
    # sliding-free (tan x = -tanh x): 2.365020372, 5.497803919
    np.testing.assert_allclose(characteristic_roots("sliding-free", 2), [2.365020372, 5.497803919],
                               rtol=1e-9)


def test_characteristic_roots_up_to_1000_against_mpmath():
    # Roots of cos x cosh x = 1 tend to (k + 1/2) pi with an exponentially small correction;
    # checked against 50-digit findroot of cos x - sech x at selected k up to 1000.
    roots = characteristic_roots("free-free", 1000)
    assert np.all(np.diff(roots) > 3.0)
    with mp.workdps(50):
        for k in [1, 2, 10, 16, 50, 230, 1000]:
            ref = mp.findroot(lambda x: mp.cos(x) - mp.sech(x), (k + mp.mpf(1) / 2) * mp.pi)
            assert abs(roots[k - 1] - float(ref)) <= 4e-16 * float(ref)
    clamped = characteristic_roots("clamped-free", 1000)
    with mp.workdps(50):
        for k in [1, 3, 500, 1000]:
            ref = mp.findroot(lambda x: mp.cos(x) + mp.sech(x), (k - mp.mpf(1) / 2) * mp.pi)
            assert abs(clamped[k - 1] - float(ref)) <= 4e-16 * float(ref)


def test_paper_frequencies(rod):
    # PAPER.md: m = 6.1261 kg, w1 = 2.8744, w2 = 7.9231 1/s. The paper's figures are truncated,
    # not rounded (2.87446 -> 2.8744), and its second root is slightly low (7.9231 against the
    # exact 7.92356, 5.8e-5 relative): compare at 1e-4 relative, the printed precision.
    assert rod.mass == pytest.approx(6.1261, abs=1e-4)
    np.testing.assert_allclose(rod.natural_frequencies(2), [2.8744, 7.9231], rtol=1e-4)


def test_zeros_are_where_exact_W_vanishes(rod):
    for r, (i, j) in {1: (0, 0), 2: (0, 1), 4: (1, 1)}.items():
        zeros = rod.zeros(r, 3)
        scale = np.abs(rod.W(1j * zeros * 1.01)[..., i, j])
        assert np.all(np.abs(rod.W(1j * zeros)[..., i, j]) < 1e-9 * scale)
    np.testing.assert_array_equal(rod.zeros(2, 2), rod.zeros(3, 2))


def test_W_poles_at_natural_frequencies(rod):
    w = rod.natural_frequencies(3)
    near = np.abs(rod.W(1j * w * (1 + 1e-9))[..., 1, 1])
    assert np.all(near > 1e6 * np.abs(rod.W(1j * w * 1.1)[..., 1, 1]))


# -- mode shapes -------------------------------------------------------------------------------
@pytest.mark.slow
def test_mode_shapes_orthonormal_at_high_mode_numbers():
    # Gauss-Legendre quadrature of rho*A phi_j phi_k over [0, L] must give the identity; the
    # textbook form loses this beyond ~16 modes (Tang 2003); the stable form keeps it at 200.
    beam = Beam(1.0, 1.0, 2.0)
    n = 200
    nodes, weights = scipy.special.roots_legendre(2000)
    x = 0.5 * (nodes + 1.0)
    for boundary in ("free-free", "clamped-free"):
        phi = beam.mode_shapes(x, n, boundary=boundary)
        gram = (phi * (0.5 * weights * beam.linear_density)[:, None]).T @ phi
        np.testing.assert_allclose(gram, np.eye(n), atol=1e-9)
        assert np.all(np.isfinite(beam.mode_shapes(x, 1000, boundary=boundary)))


def test_mode_shapes_boundary_values():
    beam = Beam(2.0, 3.0, 0.5)
    x = np.array([0.0, beam.length])
    phi = beam.mode_shapes(x, 50)
    # free-free, unnormalised |phi(0)| = |phi(L)| = 2 for every mode (Blevins)
    np.testing.assert_allclose(np.abs(phi) * math.sqrt(beam.mass), 2.0, rtol=1e-12)
    psi = beam.mode_shapes(x, 50, boundary="clamped-free")
    np.testing.assert_allclose(psi[0], 0.0, atol=1e-12)
    np.testing.assert_allclose(np.abs(psi[1]) * math.sqrt(beam.mass), 2.0, rtol=1e-12)


def test_modal_participation_sums_to_rigid_mass_properties():
    # Effective masses of cantilever modes sum to the rigid mass m and to m L^2/3 about the
    # clamp; the rotational series converges like k^-4, the translational like k^-2.
    beam = Beam(3.0, 10.0, 2.0)
    P = beam.modal_participation(20000)
    np.testing.assert_allclose((P[:, 0] ** 2).sum(), beam.mass, rtol=1e-4)
    np.testing.assert_allclose((P[:, 1] ** 2).sum(), beam.mass * beam.length**2 / 3, rtol=1e-12)
    np.testing.assert_allclose((P[:, 0] * P[:, 1]).sum(), beam.mass * beam.length / 2, rtol=1e-8)


# -- constructors and validation ---------------------------------------------------------------
def test_sections():
    rod = Beam.circular_rod(1.0, 0.02, 1000.0, 1e9)
    assert rod.linear_density == pytest.approx(1000.0 * math.pi * 0.01**2)
    assert rod.bending_stiffness == pytest.approx(1e9 * math.pi * 0.02**4 / 64)
    solid = Beam.tube(1.0, 0.02, 0.01, 1000.0, 1e9)
    assert solid.bending_stiffness == pytest.approx(rod.bending_stiffness)
    thin = Beam.tube(1.0, 0.02, 0.001, 1000.0, 1e9)
    assert thin.bending_stiffness / thin.linear_density > rod.bending_stiffness / rod.linear_density
    strip = Beam.rectangular(1.0, 0.1, 0.002, 2700.0, 7e10)
    assert strip.bending_stiffness == pytest.approx(7e10 * 0.1 * 0.002**3 / 12)


@pytest.mark.parametrize("kwargs,match", [
    (dict(length=-1.0, bending_stiffness=1.0, linear_density=1.0), r"length must be positive.*\[m\]"),
    (dict(length=1.0, bending_stiffness=np.nan, linear_density=1.0), r"bending_stiffness.*N\*m\^2"),
    (dict(length=1.0, bending_stiffness=1.0, linear_density=0.0), r"linear_density.*kg/m.*got 0.0"),
    (dict(length=1.0, bending_stiffness=1.0, linear_density=1.0, damping_ratio=1.5), "damping_ratio"),
])
def test_bad_beam_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        Beam(**kwargs)


def test_bad_types_and_counts(rod):
    with pytest.raises(TypeError, match="length must be a real number"):
        Beam("10", 1.0, 1.0)
    with pytest.raises(ValueError, match="n must be a positive integer"):
        rod.natural_frequencies(0)
    with pytest.raises(ValueError, match="n_modes must be an integer >= 1"):
        rod.truncated(0)
    with pytest.raises(ValueError, match="method must be one of"):
        rod.truncated(3, method="guyan")
    with pytest.raises(ValueError, match="wall_thickness"):
        Beam.tube(1.0, 0.02, 0.02, 1000.0, 1e9)
    with pytest.raises(ValueError, match="x must lie in"):
        rod.mode_shapes([11.0], 2)


def test_section_constructors_blame_their_own_parameters():
    """Issue 9: Beam.circular_rod(diameter=1e-300) blamed bending_stiffness (E pi d**4/64
    underflows to 0). Each section checks its own parameters, and a derived property out of
    its range names the parameters it came from, with their units."""
    with pytest.raises(ValueError, match=r"^diameter must lie in .*\[m\].*got 1e-300$"):
        Beam.circular_rod(10.0, 1e-300, 7800.0, 2.06e11)
    # each in range, the product not: both named, with their units
    with pytest.raises(ValueError, match=r"diameter = 1e-06 m and youngs_modulus = 1000\.0 Pa "
                                         r"give bending_stiffness"):
        Beam.circular_rod(10.0, 1e-6, 7800.0, 1e3)
    with pytest.raises(ValueError, match=r"outer_diameter = .* m and wall_thickness = .* m and "
                                         r"density = .* kg/m\^3 give linear_density"):
        Beam.tube(1.0, 4e-6, 1e-6, 1e-3, 2e11)
    with pytest.raises(ValueError, match=r"^thickness must lie in"):
        Beam.rectangular(1.0, 0.1, 1e300, 2700.0, 7e10)
    with pytest.raises(TypeError, match=r"^youngs_modulus must be a real number \[Pa\]; got complex"):
        Beam.circular_rod(10.0, 0.01, 7800.0, 2e11 + 0j)
    with pytest.raises(ValueError, match=r"^length must lie in \[1e-06, 1e\+06\] \[m\].*got 1e-09"):
        Beam(1e-9, 1.0, 1.0)


def test_thin_walled_tube_has_no_cancellation():
    """EJ of a tube, E pi (D**4 - d**4)/64 with d = D - 2t, cancels for t << D: the rounding
    of d alone (eps D) moves it by eps D/(2t) relative, 5e-7 at t/D = 1e-10. Factored as
    E pi 2t (D - t)(D**2 + d**2)/32 it keeps full precision and equals the thin-wall form
    E pi D**3 t/8 (1 - 3t/D + ...): checked to 1e-8 (3t/D = 3e-10 plus round-off)."""
    D, t, E, rho = 1e4, 1e-6, 1e9, 2700.0
    tube = Beam.tube(1.0, D, t, rho, E)
    np.testing.assert_allclose(tube.bending_stiffness, E * math.pi * D**3 * t / 8, rtol=1e-8)
    np.testing.assert_allclose(tube.linear_density, rho * math.pi * D * t, rtol=1e-8)


def test_damped_W_equals_modal_sum_with_damping():
    # Reference: the undamped closed form plus the damping correction of each of 200000 modes
    # summed explicitly (its own tail after 200000 modes is below 1e-12 here). Tolerance 1e-9
    # relative to the matrix.
    beam = Beam(2.0, 3.0, 0.5, damping_ratio=0.02, damping_convention="free-free")
    undamped = Beam(2.0, 3.0, 0.5)
    s = np.array([0.3j, 2 + 5j, 40j, -1 + 30j, 300j])
    n = 200_000
    root, _ = beam._free_free_root_values(n)
    w = beam.natural_frequencies(n)
    ref = undamped.W(s).copy()
    for i, si in enumerate(s):
        term = 1 / (si**2 + 2 * 0.02 * w * si + w**2) - 1 / (si**2 + w**2)
        ref[i, 0, 0] += term @ root[:, 0] ** 2
        ref[i, 0, 1] += term @ (root[:, 0] * root[:, 1])
        ref[i, 1, 1] += term @ root[:, 1] ** 2
    ref[:, 1, 0] = ref[:, 0, 1]
    W = beam.W(s)
    scale = np.abs(ref).max(axis=(1, 2))[:, None, None]
    assert np.all(np.abs(W - ref) <= 1e-9 * scale)


def test_damped_resonance_peak_height():
    # At s = i w_1 the first mode's term is b b^T/(2 i zeta w_1^2), which dominates W4 for
    # light damping: |W4| * 2 zeta w_1^2 -> b_phi^2 as zeta -> 0 (other modes O(zeta) smaller).
    # The free-free convention: each free-free mode damped at zeta.
    zeta = 1e-4
    beam = Beam(1.0, 1.0, 1.0, damping_ratio=zeta, damping_convention="free-free")
    w1 = beam.natural_frequencies(1)[0]
    root, _ = beam._free_free_root_values(1)
    peak = abs(beam.W(1j * w1)[1, 1]) * 2 * zeta * w1**2
    assert peak == pytest.approx(root[0, 1] ** 2, rel=1e-3)


def test_damped_W_is_smooth_through_the_undamped_poles():
    # Near s = i w_k the undamped closed form and the damping correction cancel; the circle
    # mean keeps full accuracy. W is analytic there (the damped poles are off the axis, the
    # peak has relative width zeta), so values 2e-9 apart in frequency differ by ~2e-9/zeta
    # = 2e-7 relative, and the second difference is ~(2e-9/zeta)^2: any cancellation error
    # (~eps/distance to the pole) would show in it.
    beam = Beam(1.0, 1.0, 1.0, damping_ratio=0.01)
    w = beam.natural_frequencies(3)
    for wk in w:
        s = 1j * wk * (1 + np.array([-2e-9, -1e-9, 0.0, 1e-9, 2e-9]))
        W = beam.W(s)
        assert np.all(np.isfinite(W))
        np.testing.assert_allclose(W, np.broadcast_to(W[2], W.shape), rtol=1e-6)
        second = W[0] - 2 * W[2] + W[4]
        assert np.abs(second).max() < 1e-9 * np.abs(W[2]).max()


def test_undamped_pole_is_an_error_not_a_nan():
    beam = Beam(1.0, 1.0, 1.0)
    # exactly at the (float) root the denominator underflows to 0 only if it rounds there;
    # check that no NaN is ever returned: either finite or ValueError
    w1 = beam.natural_frequencies(1)[0]
    try:
        W = beam.W(1j * w1)
    except ValueError as error:
        assert "natural frequency" in str(error)
    else:
        assert np.all(np.isfinite(W))


@pytest.mark.slow
def test_free_cantilever_overlap_against_quadrature():
    # Closed form from the beam equation (docstring) against 4000-point Gauss-Legendre
    # quadrature of the stable shapes, including the nearly coincident pairs (free-free k,
    # cantilever k + 1) where the closed form would cancel.
    beam = Beam(2.0, 3.0, 0.7)
    O = beam.free_cantilever_overlap(120, 20)
    nodes, weights = scipy.special.roots_legendre(4000)
    x = 0.5 * (nodes + 1) * beam.length
    phi = beam.mode_shapes(x, 120)
    psi = beam.mode_shapes(x, 20, boundary="clamped-free")
    reference = (phi * (0.5 * beam.length * weights * beam.linear_density)[:, None]).T @ psi
    np.testing.assert_allclose(O, reference, atol=1e-11)


def test_damped_craig_bampton_converges_to_exact_damped_W():
    # The beam damps its free-free modes; the Craig-Bampton model carries that damping
    # projected on its cantilever modes, so it converges to the exact damped W (also at the
    # resonance peaks, where a model damping its cantilever modes instead stays off).
    beam = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=0.005)
    s = 1j * np.concatenate([beam.natural_frequencies(2), [0.5, 3.0, 20.0]])
    exact = beam.W(s)
    errors = []
    for n in (5, 10, 20, 40):
        W = beam.truncated(n).W(s)
        errors.append((np.abs(W - exact).max(axis=(1, 2)) / np.abs(exact).max(axis=(1, 2))).max())
    assert all(b < a / 4 for a, b in zip(errors, errors[1:]))
    assert errors[-1] < 2e-5
