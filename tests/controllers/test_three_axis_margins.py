"""The three-axis margins' grid scan: the closed-form largest singular value of a 3 x 3 stack
against LAPACK's SVD, and the grid that places its points once for coincident roots."""

import numpy as np

from controllers.loop import LoopTransfer
from controllers.margins import _largest_singular_values
from plants import three_axis_plant

import controllers


def test_largest_singular_value_of_3x3_stacks_matches_the_svd():
    """Random complex matrices, scaled ones, the identity (p = 0), rank one and two equal
    largest singular values (acos near -1, where the closed form loses half the digits:
    sqrt(eps) ~ 1.5e-8, so 1e-7 there and 1e-12 elsewhere, a few hundred eps of the cubic's
    evaluation)."""
    rng = np.random.default_rng(11)
    A = rng.standard_normal((2000, 3, 3)) + 1j * rng.standard_normal((2000, 3, 3))
    A[:100] *= 1e-150
    A[100:200] *= 1e150
    exact = np.linalg.svd(A, compute_uv=False)[:, 0]
    np.testing.assert_allclose(_largest_singular_values(A), exact, rtol=1e-12)
    special = np.array([np.eye(3), np.diag([2.0, 2.0, 1e-9]), np.outer([1.0, 2.0, 3.0], [1, -1, 2]),
                        np.zeros((3, 3)), np.diag([1.0, 1.0 + 1e-12, 0.5])], dtype=complex)
    np.testing.assert_allclose(_largest_singular_values(special),
                               np.linalg.svd(special, compute_uv=False)[:, 0], rtol=1e-7, atol=0)
    assert _largest_singular_values(special).dtype == np.float64


def test_other_sizes_use_the_svd():
    rng = np.random.default_rng(2)
    A = rng.standard_normal((50, 2, 2))
    np.testing.assert_array_equal(_largest_singular_values(A),
                                  np.linalg.svd(A, compute_uv=False)[:, 0])


def test_grid_places_coincident_roots_once_and_keeps_distinct_ones():
    """A mode that the loop-at-a-time functions keep (a pole of the plant, of the loops with
    one axis open, and zeros of the channels that do not see it: several copies of one root,
    equal to round-off) gets one set of 40 points, not one per copy (observed: 71 points
    within 0.05 rad/s of it, 139 when each copy placed its own); two coincident modes are
    placed once too, and a mode 1 % away keeps its own points."""
    J = np.diag([1200.0, 900.0, 1500.0])
    b1, b2 = np.array([0.01, 0.0, 0.0]), np.array([0.0, 0.01, 0.0])

    def points_near_2(modes):
        plant = three_axis_plant(J, modes)
        K = controllers.pd(plant, natural_frequency=0.1, damping=0.7)
        return np.count_nonzero(np.abs(LoopTransfer(plant, K).grid() - 2.0) < 0.05)

    single = points_near_2([(2.0, 0.005, b1, b1)])
    coincident = points_near_2([(2.0, 0.005, b1, b1), (2.0, 0.005, b2, b2)])
    distinct = points_near_2([(2.0, 0.005, b1, b1), (2.02, 0.005, b2, b2)])
    assert 40 <= single < 100
    assert distinct - coincident >= 30
