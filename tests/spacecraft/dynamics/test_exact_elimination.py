"""The planar attitude response's elimination over a stack of 3x3 matrices
(spacecraft/dynamics/exact.py: planar_rotation_response) against LAPACK's per-matrix solve, and
the exact response on a long grid (the elimination) against the same points a few at a time
(LAPACK)."""

import math

import numpy as np
import pytest

from appendages import Beam
from spacecraft import Hub, Mount, Spacecraft
from spacecraft.dynamics.exact import planar_rotation_response

E3 = np.array([[0.0], [0.0], [1.0]])


def lapack(Z):
    return np.linalg.solve(Z, np.broadcast_to(E3, Z.shape[:-1] + (1,)))[..., 2, 0]


def test_random_stacks_agree_with_a_solve_per_matrix():
    # Both are Gaussian elimination with partial pivoting (backward stable): their results
    # differ by at most a small multiple of cond(Z) eps; the matrices kept have cond < 1e4,
    # so rtol 1e-10 leaves a factor of 100 to that bound.
    rng = np.random.default_rng(7)
    Z = rng.standard_normal((4000, 3, 3)) + 1j * rng.standard_normal((4000, 3, 3))
    Z = Z[np.linalg.cond(Z) < 1e4]
    np.testing.assert_allclose(planar_rotation_response(Z), lapack(Z), rtol=1e-10, atol=0.0)


def test_pivoting_in_both_columns_and_the_closed_forms():
    # zero leading pivot: rows 0 and 1 exchanged; Z = [[0, 1, 0], [1, 0, 0], [0, 0, c]] has
    # (Z^-1)[2, 2] = 1/c exactly
    c = 2.5 - 0.5j
    Z1 = np.array([[0, 1, 0], [1, 0, 0], [0, 0, c]], dtype=complex)
    # the second column's pivot below: Z = [[1, 0, 0], [0, 0, 1], [0, 1, 0]] is its own
    # inverse, (Z^-1)[2, 2] = 0; Z = [[2, 0, 0], [0, 0.5, 1], [0, 3, 1]]: the lower block's
    # inverse [[1, -1], [-3, 0.5]] / (0.5 - 3) gives (Z^-1)[2, 2] = -0.2 (a few roundings:
    # rtol 1e-15)
    Z2 = np.array([[1, 0, 0], [0, 0, 1], [0, 1, 0]], dtype=complex)
    Z3 = np.array([[2, 0, 0], [0, 0.5, 1], [0, 3, 1]], dtype=complex)
    got = planar_rotation_response(np.stack([Z1, Z2, Z3]))
    np.testing.assert_allclose(got, [1 / c, 0.0, -0.2], rtol=1e-15, atol=1e-300)


def test_a_singular_matrix_gives_a_non_finite_entry_and_leaves_the_others():
    rng = np.random.default_rng(3)
    Z = rng.standard_normal((5, 3, 3)) + 1j * rng.standard_normal((5, 3, 3))
    Z[2] = 0.0
    got = planar_rotation_response(Z)
    assert not np.isfinite(got[2])
    keep = [0, 1, 3, 4]
    np.testing.assert_allclose(got[keep], lapack(Z[keep]), rtol=1e-10, atol=0.0)


@pytest.mark.parametrize("damping_ratio", [0.0, 0.005])
def test_the_exact_response_on_a_long_grid_equals_it_a_few_points_at_a_time(damping_ratio):
    # the paper's rod on a 100 kg hub, off its axis (every hub coordinate coupled); a long
    # grid takes the elimination, chunks of 8 points LAPACK's solve: equal to rounding
    # (rtol 1e-9: cond(Z) up to ~1e5 near the undamped resonances the grid passes)
    rod = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=damping_ratio)
    craft = Spacecraft(Hub(100.0, 50.0), [Mount(rod, (0.5, 0.3), math.radians(20.0))])
    omega = np.geomspace(1e-3, 3e2, 400)
    if damping_ratio == 0.0:   # off the undamped spacecraft's natural frequencies
        w = craft.natural_frequencies(8, exact=True)
        omega = omega[np.min(np.abs(omega[:, None] / w[None, :] - 1.0), axis=1) > 1e-3]
    reference = craft.exact
    whole = reference.attitude_compliance(omega)
    parts = np.concatenate([reference.attitude_compliance(omega[k:k + 8])
                            for k in range(0, omega.size, 8)])
    assert whole.shape == parts.shape == (omega.size, 1, 1)
    np.testing.assert_allclose(whole, parts, rtol=1e-9, atol=0.0)
