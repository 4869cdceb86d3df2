"""The exact W(s) of a beam damped in its free-free modes (damping_convention="free-free"): the
damping correction and its repair near the poles. The cantilever convention (the default) is
tested in tests/appendages/test_cantilever_damping.py."""

import mpmath as mp
import numpy as np
import pytest

from appendages import Beam


def W_damped_mpmath(beam, s, dps=50, n_exact=30):
    """The damped W(s) in 50-digit arithmetic: the undamped closed form plus the damping of
    every mode, ``sum_k b_k b_k^T [1/(s^2 + 2 zeta w_k s + w_k^2) - 1/(s^2 + w_k^2)]``.

    The closed form is the module docstring's (appendages.beam), unscaled: 50 digits hold
    cosh x here; near a pole, where the two parts are up to ~1e13 times W, 37 digits remain (60 digits agree to 1e-16).
    b_k = (phi_k(0), phi_k'(0)) = (2, -2 sigma_k x_k/L)/sqrt(m) (Blevins, table 8-1, shapes with
    mean square 1), sigma_k = (cosh x_k - cos x_k)/(sinh x_k - sin x_k), x_k the roots of
    cos x = sech x, w_k = x_k^2 sqrt(EJ/(rho L^4)). The first ``n_exact`` roots are found by
    mpmath.findroot from (k + 1/2) pi; beyond, x_k = (k + 1/2) pi and sigma_k = 1 hold to
    e^-x_k < 1e-42 and the rest of the series is summed by mpmath.nsum (Richardson extrapolation: the terms are
    rational in k; Euler-Maclaurin summation agrees to 1e-50).
    Independent of the float code: no scaled exponentials, no tail series, no circle mean.
    """
    with mp.workdps(dps):
        s = mp.mpc(s)
        zeta = mp.mpf(beam.damping_ratio)
        EJ, L, rho = (mp.mpf(beam.bending_stiffness), mp.mpf(beam.length),
                      mp.mpf(beam.linear_density))
        # m = rho L in 50 digits (not the float beam.mass): the residues b_k b_k^T must be
        # those of the closed form's poles to 50 digits, or at s = i w_k the two O(1e13 W)
        # parts would leave 1e-16 of their size behind
        m = rho * L
        c0 = mp.sqrt(EJ / (rho * L**4))
        x = mp.root(-s**2 * rho / EJ, 4) * L
        D = 1 - mp.cos(x) * mp.cosh(x)
        W = mp.matrix([
            [L**3 / EJ * (mp.cos(x) * mp.sinh(x) - mp.sin(x) * mp.cosh(x)) / (x**3 * D),
             L**2 / EJ * mp.sin(x) * mp.sinh(x) / (x**2 * D)],
            [0, -L / EJ * (mp.cos(x) * mp.sinh(x) + mp.sin(x) * mp.cosh(x)) / (x * D)]])

        def factor(w):
            return 1 / (s**2 + 2 * zeta * w * s + w**2) - 1 / (s**2 + w**2)

        for k in range(1, n_exact + 1):
            xk = mp.findroot(lambda x: mp.cos(x) - mp.sech(x), (k + mp.mpf(0.5)) * mp.pi)
            sigma = (mp.cosh(xk) - mp.cos(xk)) / (mp.sinh(xk) - mp.sin(xk))
            f, b1 = factor(xk**2 * c0), -sigma * xk / L
            W += mp.matrix([[1, b1], [b1, b1 * b1]]) * (4 * f / m)
        # beyond: b_k = (2, -2 x_k/L)/sqrt(m), x_k = (k + 1/2) pi; sums of f x^p, p = 0, 1, 2
        tails = [mp.nsum(lambda k: factor(((k + mp.mpf(0.5)) * mp.pi) ** 2 * c0)
                         * ((k + mp.mpf(0.5)) * mp.pi) ** p, [n_exact + 1, mp.inf], method="richardson")
                 for p in range(3)]
        W += mp.matrix([[tails[0], -tails[1] / L], [-tails[1] / L, tails[2] / L**2]]) * (4 / m)
        W[1, 0] = W[0, 1]
        return np.array([[complex(W[i, j]) for j in range(2)] for i in range(2)])


@pytest.mark.parametrize("mode, offset", [(1, 0.0), (1, 0.5), (2, -0.3), (5, 2.0)])
def test_damped_W_near_a_pole_against_mpmath(mode, offset):
    """At and near an undamped pole i w_k (offset in units of zeta w_k: inside the half-power
    band, where the closed form and the damping correction cancel and the circle mean of the
    repair is used), W equals the 50-digit reference (:func:`W_damped_mpmath`). Tolerance 1e-12 of the
    matrix: the repair's rounding is eps times the closed form on its circle (about zeta w_k/r
    = 4e-3 of |W| here) plus eps times the correction sum; 1e-12 leaves room for the closed
    form's own rounding near x ~ 20 (a few hundred eps)."""
    zeta = 1e-3
    beam = Beam(1.5, 2.0, 0.7, damping_ratio=zeta, damping_convention="free-free")
    wk = beam.natural_frequencies(mode)[-1]
    s = 1j * wk * (1.0 + offset * zeta)
    near, _ = beam._near_poles(np.array([s]))
    assert near[0]  # the point is repaired
    reference = W_damped_mpmath(beam, s)
    W = beam.W(s)
    assert np.abs(W - reference).max() <= 1e-12 * np.abs(reference).max()


@pytest.mark.parametrize("zeta", [1e-5, 1e-4])
def test_repaired_W_equals_the_unrepaired_form_where_that_is_well_conditioned(zeta):
    """Inside the repair zone but well outside the half-power band (|s - i w_k| between 30 and
    1000 zeta w_k, and at most a tenth of the repair radius), the plain sum -- undamped closed
    form plus the full damping correction, no mode left out -- cancels little: its rounding is
    eps (1 + zeta w_k/|s - i w_k|) times |W| times the closed form's condition near its pole,
    eps x_k/|x - x_k| <= 1e3 eps. The repair (circle mean) must give the same W: 1e-11 of the
    matrix."""
    beam = Beam(1.0, 1.0, 1.0, damping_ratio=zeta, damping_convention="free-free")
    w = beam.natural_frequencies(6)
    checked = 0
    for k, wk in enumerate(w):
        gap = min(wk - (w[k - 1] if k else 0.0), w[k + 1] - wk if k + 1 < w.size else np.inf)
        distance = np.array([30.0, 100.0, 300.0, 1000.0]) * zeta * wk
        distance = distance[distance <= 0.1 * 0.25 * gap * 0.99]
        s = 1j * np.concatenate([wk + distance, wk - distance])
        near, modes = beam._near_poles(s)
        assert near.all() and np.all(modes == k)
        with np.errstate(divide="ignore", invalid="ignore"):
            u1, u2, u4 = beam._undamped_entries(s)
            d1, d2, d4 = beam._damping_correction(s)
        plain = np.stack([u1 + d1, u2 + d2, u4 + d4], axis=-1)
        W = beam.W(s)
        repaired = np.stack([W[:, 0, 0], W[:, 0, 1], W[:, 1, 1]], axis=-1)
        scale = np.abs(plain).max(axis=1, keepdims=True)
        assert np.all(np.abs(repaired - plain) <= 1e-11 * scale)
        checked += s.size
    assert checked >= 16


def test_damping_correction_tail_against_explicit_modes():
    """The tail after N modes (series in s/w_k, Hurwitz zeta sums) against the modes
    N < k <= N + 200000 summed explicitly (their own rest, O(zeta |s| N^-3) with N + 200000
    modes, below 1e-15 of the tail here), at |s| up to a tenth of w_{N+1}, where the series is
    used: relative 1e-9 (the series' truncation is below 1e-10, the explicit sum's rounding
    about 1e-12)."""
    beam = Beam(1.0, 1.0, 1.0, damping_ratio=0.05, damping_convention="free-free")
    n = 16
    w_next = beam.natural_frequencies(n + 1)[-1]
    s = np.array([0.1j, 1 + 2j, 0.05j * w_next, (0.06 + 0.07j) * w_next, 0.1j * w_next])
    tail = beam._damping_tail(s, n)
    K = n + 200_000
    root, _ = beam._free_free_root_values(K)
    w = beam.natural_frequencies(K)
    root, w = root[n:], w[n:]
    term = (-2 * 0.05 * w * s[:, None]) / ((s[:, None] ** 2 + w**2)
                                           * (s[:, None] ** 2 + 0.1 * w * s[:, None] + w**2))
    explicit = np.stack([term @ root[:, 0] ** 2, term @ (root[:, 0] * root[:, 1]),
                         term @ root[:, 1] ** 2])
    np.testing.assert_allclose(tail, explicit, rtol=1e-9, atol=0)
