"""Verdicts and margins of a loop known by its frequency response: controllers.margins'
loop_nyquist_count, multiloop_margins and loop_verdict against the state-space verdicts
(controllers.spillover and controllers.margins) of the same loops.

The state-space verdict counts closed-loop eigenvalues; the frequency-response verdict counts
encirclements of det(I + L) on a grid and finds the margins on the loop function. Both use one
set of definitions (loop-at-a-time L_i = 1/S_ii - 1, the balanced disk margin, the smallest
singular value of I + L, the delay's imaginary-axis crossings), each margin refined on the
function to 1e-13 relative in frequency, so the two must agree to the rounding of the loop's
evaluation: 1e-9 (measured 1e-14 to 4e-12).
"""
import math

import control
import numpy as np
import pytest

import controllers
from controllers.loop import LoopTransfer, controller_roots, resonance_points
from controllers.margins import (loop_nyquist_count, loop_verdict, multiloop_margins,
                                 unstable_poles)
from loops import assert_same_margins, with_unstable_pole
from plants import modal_plant, three_axis_plant

J3 = np.array([[1200.0, 40.0, -25.0], [40.0, 900.0, 30.0], [-25.0, 30.0, 1500.0]])
#: Two modes that several axes see, one of them not collocated (b != c): finite gain margins.
MODES = [(1.2, 0.004, np.array([0.012, -0.006, 0.004]), np.array([0.012, -0.006, 0.004])),
         (3.1, 0.006, np.array([0.002, 0.015, -0.008]), np.array([-0.004, 0.02, 0.006]))]


def plant_and_loop(natural_frequency=0.15, augment=None):
    plant = three_axis_plant(J3, MODES)
    K = controllers.pd(plant, natural_frequency=natural_frequency, damping=0.7)
    if augment is not None:
        K = with_unstable_pole(K, *augment)
    return plant, K


def loop_function(plant, K):
    """(L(omega), the grid that resolves it) of the state-space loop."""
    transfer = LoopTransfer(plant, K)
    return transfer.matrix, transfer.grid()


def closed_loop_unstable(plant, K) -> int:
    s = np.linalg.eigvals(controllers.close_loop(plant, K).A)
    return int(np.sum(s.real > 1e-10 * np.maximum(1.0, np.abs(s))))


@pytest.mark.slow
@pytest.mark.parametrize("delay", [0.0, 0.4])
def test_multiloop_margins_of_the_loop_function_are_the_state_space_margins(delay):
    # the same definitions, one code: on the state-space loop's own grid the two are equal to
    # rounding (the delayed grid refined alike)
    plant, K = plant_and_loop()
    matrix, grid = loop_function(plant, K)
    expected = controllers.margins(plant, K, delay=delay)
    found = multiloop_margins(matrix, grid, delay=delay)
    assert_same_margins(expected, found, 1e-12)
    assert found.delay == delay
    assert set(found.loop_at_a_time) == {"x", "y", "z"}
    assert math.isfinite(found.gain_margin)  # the non-collocated mode gives a phase crossover


@pytest.mark.parametrize("augment, expected", [(None, 0), ((0.02, 2.0), 0), ((0.02, 0.2), 3),
                                               ((0.02, 20.0), 6)])
def test_the_nyquist_count_of_det_I_plus_L_is_the_eigenvalue_count(augment, expected):
    # Routh on each principal axis (with_unstable_pole: kp = j w^2 ~ 20-34, kd ~ 185-320 at
    # 0.15 rad/s, a = 0.02): stable for 0.4-0.7 < c < 3.5-5.9, so c = 2 is stable on every
    # axis, c = 0.2 leaves one real root per axis, c = 20 a complex pair per axis (the
    # eigenvalues confirm each count); the open loop has three right half-plane poles
    plant, K = plant_and_loop(augment=augment)
    assert closed_loop_unstable(plant, K) == expected
    matrix, grid = loop_function(plant, K)
    P = unstable_poles(K)
    assert P == (0 if augment is None else 3)
    assert loop_nyquist_count(grid, matrix(grid), open_loop_unstable=P) == expected
    # without the controller's own unstable poles the count is wrong: they matter
    if P:
        assert loop_nyquist_count(grid, matrix(grid)) == expected - P


def test_the_planar_count_is_nyquist_counts():
    plant = modal_plant(50.0, [(2.0, 0.005, 0.04, 0.04)])
    K = controllers.pd(plant, natural_frequency=0.5)
    frd = control.frd(plant, np.logspace(-4.0, 4.0, 2000))
    omega, L = controllers.loop_frequency_response(frd, K)
    assert L.ndim == 1
    assert loop_nyquist_count(omega, L) == controllers.nyquist_count(frd, K) == 0
    # a planar loop given as (f, 1, 1) is the same loop
    assert loop_nyquist_count(omega, L[:, None, None]) == 0


def test_loop_verdict_is_spillovers_verdict():
    for augment in (None, (0.02, 2.0), (0.02, 20.0)):
        plant, K = plant_and_loop(augment=augment)
        matrix, grid = loop_function(plant, K)
        expected = controllers.spillover(plant, K)
        found = loop_verdict(matrix, grid, open_loop_unstable=unstable_poles(K))
        assert found.method == "nyquist"
        assert found.stable == expected.stable
        assert found.n_unstable_poles == expected.n_unstable_poles
        assert_same_margins(expected.margins, found.margins)


@pytest.mark.slow
def test_a_destabilising_delay_is_found_as_spillover_finds_it():
    # the delay margin of the loop without delay: a delay a little below it keeps the loop
    # stable, a little above it destabilises it (two roots cross), in both verdicts
    plant, K = plant_and_loop(natural_frequency=0.3)
    matrix, grid = loop_function(plant, K)
    margin = controllers.margins(plant, K).delay_margin
    assert 0.1 < margin < 10.0
    for delay, stable in ((0.98 * margin, True), (1.02 * margin, False)):
        expected = controllers.spillover(plant, K, delay=delay)
        found = loop_verdict(matrix, grid, delay=delay)
        assert found.method == "nyquist+delay"
        assert expected.stable is stable and found.stable is stable
        assert found.n_unstable_poles == expected.n_unstable_poles == (0 if stable else 2)
        assert abs(found.margins.delay_margin - expected.margins.delay_margin) < 1e-9 * margin
        assert abs(found.margins.delay_margin - (margin - delay)) < 1e-9 * margin


def test_controller_roots_and_resonance_points_resolve_a_notch():
    # a three-axis PD with a notch: its lightly damped zeros get 40 points each
    plant = three_axis_plant(J3, MODES)
    K = controllers.pd(plant, natural_frequency=0.15, damping=0.7, notch=1.2)
    roots = controller_roots(K, [n for n in K.input_labels if not n.startswith("theta_ref")],
                             [f"torque_{a}" for a in "xyz"])
    light = roots[(roots.imag > 0) & (np.abs(roots.real) < 0.3 * np.abs(roots))]
    assert light.size
    points = resonance_points(roots, 1e-3, 1e3)
    for root in light:
        near = np.abs(points - root.imag) < 8.2 * abs(root.real)
        assert np.count_nonzero(near) >= 40 or np.any(np.abs(light - root) < 0.02 * abs(root.real))


def test_bad_arguments_are_named():
    plant, K = plant_and_loop()
    matrix, grid = loop_function(plant, K)
    L = matrix(grid)
    with pytest.raises(ValueError, match="frequency grid too narrow.*singular value"):
        loop_nyquist_count(grid[grid > 1.0], L[grid > 1.0])
    with pytest.raises(ValueError, match="L must be"):
        loop_nyquist_count(grid, L[:-1])
    with pytest.raises(ValueError, match="omega must be increasing"):
        loop_nyquist_count(grid[::-1], L[::-1])
    with pytest.raises(ValueError, match="open_loop_unstable"):
        loop_nyquist_count(grid, L, open_loop_unstable=-1)
    with pytest.raises(TypeError, match="loop must be"):
        loop_verdict(L, grid)
    with pytest.raises(TypeError, match="loop must be"):
        multiloop_margins(L, grid)
    with pytest.raises(ValueError, match="axes"):
        multiloop_margins(matrix, grid, axes=("a", "b"))
    with pytest.raises(ValueError, match="delay"):
        loop_verdict(matrix, grid, delay=-1.0)
