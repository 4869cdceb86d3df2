"""The margins' faster paths find what the slower ones found.

- The number of eigenvalues of L outside the unit circle (the delay margin's crossings) is
  decided from the characteristic polynomial by Rouche's theorem wherever one term dominates on
  the circle; everywhere it decides, it equals the count of the eigenvalues.
- The largest singular values on a grid are computed in closed form only where the Frobenius
  norm allows them to be the grid's peak; the peak, the points near it and their neighbours
  are those of the full computation.
- A unit-circle crossing of one eigenvalue is refined as a root of prod (|lambda_k| - 1), two
  in one grid interval by bisecting the count: against the crossings' closed form.
- The three-axis loop of benchmarks/three_axis.py keeps the margins it had before these paths
  (pinned, with tolerances from the spread between BLAS kernels).
"""
import cmath
import math
import pathlib
import sys

import numpy as np
import pytest

from controllers.margins import (_largest_singular_values, _outside_unit_circle,
                                 _peak_singular_values, multiloop_margins)


def _stack(rng, n, m, spread):
    """n random complex m x m matrices with singular values spread over 10^+-spread."""
    U = np.linalg.qr(rng.normal(size=(n, m, m)) + 1j * rng.normal(size=(n, m, m)))[0]
    V = np.linalg.qr(rng.normal(size=(n, m, m)) + 1j * rng.normal(size=(n, m, m)))[0]
    s = 10.0 ** rng.uniform(-spread, spread, size=(n, m))
    return np.einsum("fij,fj,fkj->fik", U, s, V.conj())


@pytest.mark.parametrize("m", [2, 3])
def test_rouche_count_equals_the_eigenvalue_count_where_it_decides(m):
    """Random stacks, well and badly scaled, and the resonance form (a large rank-one term
    over a small matrix, L near an undamped mode): where a count is given it is the number of
    eigenvalues with |lambda| > 1, and the resonance form is decided."""
    rng = np.random.default_rng(7)
    general = _stack(rng, 4000, m, 3.0)
    u = rng.normal(size=(4000, m)) + 1j * rng.normal(size=(4000, m))
    v = rng.normal(size=(4000, m)) + 1j * rng.normal(size=(4000, m))
    t = 10.0 ** rng.uniform(1.0, 8.0, 4000)
    resonance = (t[:, None, None] * u[:, :, None] * v[:, None, :].conj()
                 + 1e-2 * _stack(rng, 4000, m, 0.5))
    for L in (general, resonance):
        count = _outside_unit_circle(L)
        exact = np.sum(np.abs(np.linalg.eigvals(L)) > 1.0, axis=1)
        decided = count >= 0
        np.testing.assert_array_equal(count[decided], exact[decided])
        assert decided.mean() > 0.5
    # the resonance form: one eigenvalue lambda_1 outside, the others small inside; with
    # s = sum and p = product of the small ones' moduli, |c_(m-1)| >= |lambda_1| - s,
    # |c_(m-2)| <= |lambda_1| s + p and |c_(m-3)| = |lambda_1| p: z^(m-1) dominates where
    # |lambda_1| (1 - s - p) > 1 + s + p (with 1 % to spare), and the count must be given there
    # while the coefficients' rounding bounds stay below the 1 % (a determinant of entries
    # up to e carries 6e-12 e^3 of them: entries up to 1e3 here; beyond, eigenvalues decide)
    lam = np.sort(np.abs(np.linalg.eigvals(resonance)), axis=1)[:, ::-1]
    small_sum, small_product = lam[:, 1:].sum(axis=1), lam[:, 1:].prod(axis=1) * (m == 3)
    dominant = lam[:, 0] * (1 - small_sum - small_product) > 1.01 * (1 + small_sum
                                                                      + small_product)
    dominant &= np.abs(resonance).max(axis=(1, 2)) < 1e3
    assert dominant.sum() > 300
    assert np.all(_outside_unit_circle(resonance)[dominant] == 1)


@pytest.mark.parametrize("on_circle", [1.0, 1j, cmath.exp(0.3j)])
def test_rouche_count_is_undecided_with_an_eigenvalue_on_the_circle(on_circle):
    """An eigenvalue on the unit circle: no term can dominate there, no count is given (the
    eigenvalues are then computed)."""
    L = np.diag([on_circle, 0.5, 3.0])[None]
    assert _outside_unit_circle(L).tolist() == [-1]
    assert _outside_unit_circle(L[:, :2, :2]).tolist() == [-1]


def test_peak_singular_values_keep_the_grids_peak_and_its_neighbours():
    """A grid of 3 x 3 matrices with a sharp peak (a resonance) and a near tie: the largest
    value, every point within 1e-6 of it and their neighbours equal the closed form on the
    whole grid; elsewhere the values lie below (1 - 1e-5) times the peak and never above the
    true sigma_max."""
    rng = np.random.default_rng(3)
    f = 3000
    A = _stack(rng, f, 3, 0.3)
    w = np.linspace(0.0, 1.0, f)
    A = A + (1e-3 / (1e-3 + np.abs(w - 0.4)))[:, None, None] * np.eye(3) * 50.0
    A[2500] = A[np.argmax(_largest_singular_values(A))] * (1 + 5e-7)  # a second point near
    full = _largest_singular_values(A)
    fast = _peak_singular_values(A)
    top = full.max()
    near = np.flatnonzero(full >= top * (1 - 1e-6))
    assert near.size >= 2
    keep = np.unique(np.clip(np.concatenate([near - 1, near, near + 1]), 0, f - 1))
    np.testing.assert_array_equal(fast[keep], full[keep])
    assert np.argmax(fast) == np.argmax(full)
    others = np.setdiff1d(np.arange(f), keep)
    assert np.all(fast[others] <= full[others] * (1 + 1e-12))
    assert np.all(fast[np.setdiff1d(others, np.flatnonzero(fast == full))]
                  < (1 - 1e-5) * top)


def _diagonal_loop(k, a):
    """L = diag(k_i / (s (s + a_i))) at s = j omega, (f, 3, 3)."""
    def loop(omega):
        s = 1j * np.asarray(omega, dtype=float)[:, None]
        L = np.zeros((s.shape[0], 3, 3), dtype=complex)
        L[:, [0, 1, 2], [0, 1, 2]] = k / (s * (s + a))
        return L
    return loop


@pytest.mark.parametrize("k, a", [((2.0, 5.0, 11.0), (1.0, 0.5, 3.0)),
                                  ((4.0, 4.0, 9.0), (2.0, 2.0, 1.0))])
def test_delay_margin_from_the_crossings_closed_form(k, a):
    """A diagonal loop: each eigenvalue k/(s (s + a)) crosses the unit circle once, at
    omega_c^2 = (sqrt(a^4 + 4 k^2) - a^2) / 2, with phase -pi/2 - atan(omega_c / a); the delay
    margin is min over them of (pi + arg lambda) / omega_c. The second case has two equal
    loops: two eigenvalues cross in one grid interval (the count changes by two and is
    bisected). Frequencies to 1e-13 relative: the margin to rtol 1e-11."""
    k, a = np.array(k), np.array(a)
    wc = np.sqrt((np.sqrt(a ** 4 + 4 * k ** 2) - a ** 2) / 2)
    expected = min((math.pi - math.pi / 2 - math.atan(w / ai)) / w for w, ai in zip(wc, a))
    omega = np.geomspace(1e-2, 1e2, 301)
    result = multiloop_margins(_diagonal_loop(k, a), omega)
    assert result.delay_margin == pytest.approx(expected, rel=1e-11, abs=0)


# the three-axis loop of benchmarks/three_axis.py: its margins before the faster paths
# (commit 2998215), and their relative spread between OpenBLAS kernels (default, Prescott,
# Haswell): the modulus-type margins sit beside undamped modes, within 1e-13 of their
# frequency, where L is known to about 1 %; the phase and delay margins to 3e-4
_PINNED = {
    "gain_margin_x": (41.83006938981229, 1e-5), "gain_margin_y": (52.13012762648362, 1e-5),
    "gain_margin_z": (68.70348337262098, 1e-5),
    "phase_margin_x": (0.032892719185440455, 2e-3), "phase_margin_y": (0.008245760955645665, 2e-3),
    "phase_margin_z": (0.03316199927397179, 2e-3),
    "modulus_margin_x": (1.4212531065476238e-05, 5e-2),
    "modulus_margin_y": (0.0001439156778842134, 5e-2),
    "modulus_margin_z": (1.8064964047488806e-05, 5e-2),
    "disk_margin": (1.4212632064213604e-05, 5e-2),
    "min_singular_value": (1.4212531065476238e-05, 5e-2),
}
# the delay margin is the phase margin of the critical crossing (here the eigenvalue of L that
# crosses the unit circle beside the y loop's 0.008 deg crossover) over its frequency, which is
# resolved to 1e-13: it carries the phase margin's relative round-off, so the same tolerance
# (a round-off change of the rigid-body modes of 2e-19 moved both by 1e-5)
_PINNED_DELAY_MARGIN = (7.283198457491322e-08, 2e-3)


@pytest.mark.slow
def test_three_axis_benchmark_loop_keeps_its_margins():
    """The margins of benchmarks/three_axis.py's design loop (truth: 56 states, undamped) as
    before the faster paths, to the spread between BLAS kernels (a lost crossing or dip would
    move them by orders of magnitude)."""
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "benchmarks"))
    try:
        import three_axis
    finally:
        sys.path.pop(0)
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        _, margins = three_axis.evaluate(three_axis.design_chains())
    values = margins.as_dict()
    for key, (value, rtol) in _PINNED.items():
        assert values[key] == pytest.approx(value, rel=rtol, abs=0), key
    value, rtol = _PINNED_DELAY_MARGIN
    assert margins.delay_margin == pytest.approx(value, rel=rtol, abs=0)
