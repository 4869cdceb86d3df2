"""Tip bodies: TipBody, Beam(tip=...), exact W and W6 with the body as the free end's boundary
condition, mass properties, frequencies, truncations and chains.

References: a 50-digit solution of the boundary-value problem (the beam's closed-form solution
``a cosh bx + b sinh bx + c cos bx + d sin bx`` with the tip body's inertia as the end
condition), the closed form of a beam pinned at its tip derived below, and the rigid body's mass
properties.
"""

import math

import mpmath as mp
import numpy as np
import pytest

from appendages import Beam, HingedChain, SteppedBeam, TipBody

EJ, L, RHO = 2.3, 1.7, 0.9                  # N m^2, m, kg/m
TIP = (3.0, 0.2, 0.15)                      # kg, kg m^2 (about its centre), m (along x)


def _basis(beta, x, d):
    """d-th derivative of (cosh, sinh, cos, sin)(beta x) at x."""
    c, s, C, S = mp.cos(beta * x), mp.sin(beta * x), mp.cosh(beta * x), mp.sinh(beta * x)
    hyper = (C, S) if d % 2 == 0 else (S, C)
    trig = [(c, s), (-s, c), (-c, -s), (s, -c)][d % 4]
    return [beta**d * v for v in (*hyper, *trig)]


def _bvp_matrix(s, ej, length, rho, mass, inertia, offset, root="free"):
    """Rows: the root's two conditions (loads, or clamped motions) and the tip body's two
    (the beam's end loads equal the body's inertia: -EJ w'''(L) = -s^2 (M_t u)_1,
    EJ w''(L) = -s^2 (M_t u)_2, M_t = [[m, m a], [m a, J + m a^2]], u = (w(L), w'(L)))."""
    beta = mp.root(-s**2 * rho / ej, 4)
    Mt = [[mass, mass * offset], [mass * offset, inertia + mass * offset**2]]
    wL, tL = _basis(beta, length, 0), _basis(beta, length, 1)
    shear_L, moment_L = _basis(beta, length, 3), _basis(beta, length, 2)
    A = mp.matrix(4, 4)
    for j in range(4):
        if root == "free":
            A[0, j] = ej * _basis(beta, 0, 3)[j]
            A[1, j] = -ej * _basis(beta, 0, 2)[j]
        else:
            A[0, j] = _basis(beta, 0, 0)[j]
            A[1, j] = _basis(beta, 0, 1)[j]
        A[2, j] = -ej * shear_L[j] + s**2 * (Mt[0][0] * wL[j] + Mt[0][1] * tL[j])
        A[3, j] = ej * moment_L[j] + s**2 * (Mt[1][0] * wL[j] + Mt[1][1] * tL[j])
    return A


def W_tip_mpmath(s, tip=TIP, dps=50):
    """W(s) of the beam with a tip body: unit root loads, 50 digits."""
    with mp.workdps(dps):
        s = mp.mpc(s)
        A = _bvp_matrix(s, mp.mpf(EJ), mp.mpf(L), mp.mpf(RHO), *map(mp.mpf, tip))
        beta = mp.root(-s**2 * mp.mpf(RHO) / mp.mpf(EJ), 4)
        W = np.empty((2, 2), dtype=complex)
        for col in range(2):
            c = mp.lu_solve(A, mp.matrix([int(col == 0), int(col == 1), 0, 0]))
            W[0, col] = complex(sum(c[j] * _basis(beta, 0, 0)[j] for j in range(4)))
            W[1, col] = complex(sum(c[j] * _basis(beta, 0, 1)[j] for j in range(4)))
        return W


def W_pinned_tip(s):
    """W of a beam loaded at x = 0 and pinned at x = L (w(L) = w''(L) = 0).

    With xi = L - x, ``w = A sinh(b xi) + B sin(b xi)`` meets both tip conditions; the root's
    ``EJ w'''(0) = F``, ``-EJ w''(0) = M`` (d/dx = -d/dxi) give, with x = b L,
    ``Delta = cos x sinh x - sin x cosh x``::

        W1 = L^3/EJ 2 sin x sinh x/(x^3 Delta),     W2 = -L^2/EJ (cos x sinh x + sin x cosh x)/(x^2 Delta),
        W4 = L/EJ 2 cos x cosh x/(x Delta).

    The limit of a tip body of infinite mass and no rotary inertia. Evaluated in 50 digits.
    """
    with mp.workdps(50):
        x = mp.root(-mp.mpc(s) ** 2 * RHO / EJ, 4) * L
        c, sn, C, S = mp.cos(x), mp.sin(x), mp.cosh(x), mp.sinh(x)
        delta = c * S - sn * C
        W1 = L**3 / EJ * 2 * sn * S / (x**3 * delta)
        W2 = -(L**2) / EJ * (c * S + sn * C) / (x**2 * delta)
        W4 = L / EJ * 2 * c * C / (x * delta)
        return np.array([[complex(W1), complex(W2)], [complex(W2), complex(W4)]])


def _beam(**kw):
    return Beam(L, EJ, RHO, tip=TipBody(*TIP), **kw)


# -- the body ---------------------------------------------------------------------------------
@pytest.mark.parametrize("args, name", [
    ((-1.0, 0.1), "mass"), ((math.nan, 0.1), "mass"), (("1", 0.1), "mass"),
    ((1.0, -0.1), "inertia"), ((1.0, "0.1"), "inertia"),
    ((1.0, [[1.0, 0.2, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), "symmetric"),
    ((1.0, np.diag([1.0, 1.0, -0.1])), "semi-definite"),
    ((1.0, np.diag([1.0, 1.0, 3.0])), "sum of the other two"),
    ((1.0, np.eye(2)), "inertia"),
    ((1.0, 0.1, [1.0, 2.0, 3.0, 4.0]), "offset"), ((1.0, 0.1, math.inf), "offset"),
    ((1.0, 0.1, "x"), "offset"),
])
def test_bad_tip_bodies_are_refused_by_name(args, name):
    with pytest.raises((TypeError, ValueError), match=name):
        TipBody(*args)


def test_tip_must_be_a_tip_body():
    with pytest.raises(TypeError, match="tip"):
        Beam(L, EJ, RHO, tip=(1.0, 0.1))
    with pytest.raises(TypeError, match="tip"):
        Beam.tube(1.0, 0.05, 0.002, 2700.0, 7e10, tip=1.0)


def test_a_body_across_the_axis_is_refused_by_the_planar_model_and_taken_in_three_axes():
    beam = Beam.tube(1.0, 0.05, 0.002, 2700.0, 7e10,
                     tip=TipBody(0.5, np.diag([1e-3, 2e-3, 2e-3]), (0.1, 0.05, 0.0)))
    with pytest.raises(ValueError, match="offset"):
        beam.W(1j)
    assert np.all(np.isfinite(beam.W6(np.array([1j, 30j]))))
    planar = Beam.tube(1.0, 0.05, 0.002, 2700.0, 7e10, tip=TipBody(0.5, 0.01))
    with pytest.raises(ValueError, match="inertia"):
        planar.W6(1j)


# -- limiting cases -----------------------------------------------------------------------------
def test_a_tip_of_zero_mass_is_the_bare_beam_bit_for_bit():
    s = np.array([1e-6j, 0.3 + 2j, 40j, 1e5j])
    for bare, tipped in (
            (Beam(L, EJ, RHO), Beam(L, EJ, RHO, tip=TipBody(0.0, 0.0, 0.4))),
            (Beam(L, EJ, RHO, damping_ratio=0.01),
             Beam(L, EJ, RHO, damping_ratio=0.01, tip=TipBody(0.0, 0.0))),
            (Beam.tube(1.0, 0.05, 0.002, 2700.0, 7e10),
             Beam.tube(1.0, 0.05, 0.002, 2700.0, 7e10, tip=TipBody(0.0, np.zeros((3, 3)))))):
        assert np.array_equal(bare.W(s), tipped.W(s))
        assert np.array_equal(bare.natural_frequencies(5), tipped.natural_frequencies(5))
        assert np.array_equal(bare.truncated(4).W(s), tipped.truncated(4).W(s))
        assert (bare.mass, bare.inertia) == (tipped.mass, tipped.inertia)
        if bare.three_axis:
            assert np.array_equal(bare.W6(s), tipped.W6(s))


@pytest.mark.parametrize("s", [1e-7j, 1e-3 + 1e-2j, 0.5j, 3.0 + 2.0j, 7j, 1.0 + 40j,
                               10.0 + 500j])
def test_W_against_the_50_digit_boundary_value_problem(s):
    """Exact to the rounding of its terms: 1e-13 of the matrix away from the poles."""
    W = _beam().W(s)
    reference = W_tip_mpmath(s)
    assert np.abs(W - reference).max() <= 1e-13 * np.abs(reference).max()


def test_natural_and_cantilever_frequencies_against_the_50_digit_determinant():
    """Free-free and clamped frequencies are roots of the boundary-value determinant
    (mpmath.findroot from flexsat's values): agreement to 1e-13."""
    beam = _beam()
    for kind, w in (("free", beam.natural_frequencies(5)),
                    ("clamped", beam.cantilever_frequencies(5))):
        with mp.workdps(50):
            for wk in w:
                root = mp.findroot(
                    lambda omega: mp.det(_bvp_matrix(1j * omega, EJ, L, RHO, *TIP, root=kind)),
                    mp.mpf(wk))
                assert abs(float(mp.re(root)) / wk - 1) < 1e-13


def test_mass_properties_include_the_body():
    """The rigid body's sums: mass, first moment, inertia about the centre of mass
    (parallel-axis theorem), and W's rigid limit s^2 W -> M_rr^-1 to 1e-12 at s = 1e-7 j."""
    m_t, J_t, a = TIP
    beam = _beam()
    m = RHO * L + m_t
    S = RHO * L**2 / 2 + m_t * (L + a)
    c = S / m
    J = RHO * L**3 / 12 + RHO * L * (L / 2 - c) ** 2 + J_t + m_t * (L + a - c) ** 2
    assert beam.mass == pytest.approx(m, rel=1e-15)
    assert beam.center_of_mass == pytest.approx(c, rel=1e-14)
    assert beam.inertia == pytest.approx(J, rel=1e-14)
    M_rr = np.array([[m, S], [S, J + m * c**2]])
    np.testing.assert_allclose(beam.rigid_mass_matrix, M_rr, rtol=1e-14)
    s = 1e-7j
    np.testing.assert_allclose(s**2 * beam.W(s), np.linalg.inv(M_rr), rtol=1e-12, atol=0)


def test_a_very_heavy_tip_without_rotary_inertia_pins_the_tip():
    """A point mass mu at the tip: W -> W of the beam pinned there (W_pinned_tip), the rest
    of order m/mu (measured: the error falls by 1000 when mu grows by 1000)."""
    s = np.array([0.7j, 3 + 8j, 60j])
    reference = np.array([W_pinned_tip(si) for si in s])
    errors = []
    for mu in (1e4, 1e7):
        W = Beam(L, EJ, RHO, tip=TipBody(mu * RHO * L, 0.0)).W(s)
        errors.append(np.abs(W - reference).max() / np.abs(reference).max())
    assert 300 < errors[0] / errors[1] < 3000
    assert errors[1] < 1e-6


def test_W_is_symmetric_conjugate_symmetric_and_tends_to_the_bare_beam_at_high_s():
    """W(s) symmetric, W(conj s) = conj W(s); at |s| -> infinity off the imaginary axis the root
    sees no tip (the waves decay like e^-Re(x) on their way): W equals the bare beam's to 1e-13
    at |s| = 1e8, with no overflow; on the axis (propagating waves) W is finite."""
    for beam in (_beam(), _beam(damping_ratio=0.01)):
        s = np.array([0.3 + 2j, 5j + 1, 40j, 2 - 300j])
        W = beam.W(s)
        np.testing.assert_array_equal(W, np.swapaxes(W, -1, -2))
        np.testing.assert_allclose(beam.W(np.conj(s)), np.conj(W), rtol=1e-13, atol=0)
    assert np.all(np.isfinite(_beam().W(np.array([1e8j, 3e7j]))))
    high = np.array([1e8 * (1 + 1j), -1e8 + 1j, 1e6 + 1e8j])
    W = _beam().W(high)
    bare = Beam(L, EJ, RHO).W(high)
    np.testing.assert_allclose(W, bare, rtol=1e-13, atol=0)


# -- truncations and chains ---------------------------------------------------------------------
@pytest.mark.parametrize("method, n, bound", [("craig-bampton", 32, 1e-7),
                                              ("residual", 16, 1e-9),
                                              ("free-free", 32, 2e-3)])
def test_every_truncation_converges_to_the_tip_beam(method, n, bound):
    """W of the truncation against the exact W on 0.3-60 rad/s (the tip beam's first five
    free-free modes): errors fall as modes are added (measured 3e-8, 9e-11, 7e-4 at the n
    used), and the kept poles are the exact free-free frequencies (free-interface models)."""
    beam = _beam()
    s = 1j * np.linspace(0.3, 60.0, 7) + 0.2
    exact = beam.W(s)
    errors = [np.abs(beam.truncated(k, method=method).W(s) - exact).max() / np.abs(exact).max()
              for k in (n // 4, n)]
    assert errors[1] < errors[0] and errors[1] < bound
    if method != "craig-bampton":
        np.testing.assert_allclose(beam.truncated(4, method=method).poles()[:4],
                                   beam.natural_frequencies(4), rtol=1e-10)


def test_chains_carry_the_tip_body():
    """HingedChain.rfem and .superelements add the body to their last body: the chain's mass,
    centre of mass and inertia are the tip beam's to rounding, and its frequencies converge to
    the tip beam's like n^-2 (RFEM) and n^-4 (Molenaar superelements; error ratios measured
    20, 29, 17 at n = 4-8, 8-16, 16-32)."""
    beam = _beam()
    w = beam.natural_frequencies(2)
    rfem = [HingedChain.rfem(beam, n) for n in (16, 32)]
    supers = [HingedChain.superelements(beam, n) for n in (16, 32)]
    for chain in rfem + supers:
        assert chain.mass == pytest.approx(beam.mass, rel=1e-14)
        assert chain.center_of_mass == pytest.approx(beam.center_of_mass, rel=1e-13)
        assert chain.inertia == pytest.approx(beam.inertia, rel=1e-13)
    e = [np.abs(c.poles()[:2] / w - 1).max() for c in rfem]
    assert 3.0 < e[0] / e[1] < 5.0
    e = [np.abs(c.poles()[:2] / w - 1).max() for c in supers]
    assert 10.0 < e[0] / e[1] < 22.0
    with pytest.raises(ValueError, match="offset"):
        HingedChain.rfem(Beam.tube(1.0, 0.05, 0.002, 2700.0, 7e10,
                                   tip=TipBody(1.0, np.eye(3) * 1e-3, (0.0, 0.1, 0.0))), 8)


def test_a_stepped_beam_of_one_segment_with_the_body_is_the_tip_beam():
    """SteppedBeam([beam], tip) and Beam(..., tip) are the same model (one assembly)."""
    s = np.array([0.5j, 3 + 2j, 70j])
    np.testing.assert_array_equal(SteppedBeam([Beam(L, EJ, RHO)], tip=TipBody(*TIP)).W(s),
                                  _beam().W(s))
