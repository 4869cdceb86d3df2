"""The frequency grid's windows about close lightly damped roots, merged, are nowhere coarser.

Each lightly damped root -zeta w + j c (half-width w_i = zeta |root|) has its own window of 40
points c + w_i tan(t), t in steps s0 = 2.9 / 39 over [-1.45, 1.45]; t is the phase the root's
factor 1 / (j omega - root) turns. Close roots share one window (controllers.loop.resonance_points):
across every gap of the grid that meets a root's own window, that root's t must turn by at most
s0, and the grid must reach both ends of every root's window.
"""
import math

import numpy as np
import pytest

from controllers.loop import resonance_points, window_angle_steps

STEP = 2.9 / 39
THETA = 1.45


def _assert_no_coarser(points, roots):
    for root in roots:
        w = abs(root.real)
        steps = window_angle_steps(points, root.imag, w)
        # 1e-6 of a step: the round-off of frequencies 1e-7 of their size apart
        assert steps.size and steps.max() <= STEP * (1 + 1e-6), (root, steps.max() / STEP)
        t = np.arctan((points - root.imag) / w)
        assert t.min() <= -THETA + 1e-6 * STEP and t.max() >= THETA - 1e-6 * STEP


@pytest.mark.parametrize("seed", range(6))
def test_merged_windows_are_nowhere_coarser_than_each_roots_own(seed):
    """Clusters of copies of one mode (undamped: zeta at its floor 1e-7; and damped ones),
    centres spread over up to one half-width, half-widths up to 1.25 apart, beside separate
    roots: every root's phase turns by at most one step between neighbouring points, and the
    clusters take fewer points than 40 per root."""
    rng = np.random.default_rng(seed)
    roots = []
    for _ in range(8):
        w0 = 10.0 ** rng.uniform(-1, 3)
        zeta = rng.choice([0.0, 10.0 ** rng.uniform(-6, -1)])
        width = max(zeta, 1e-7) * w0
        n = int(rng.integers(2, 7))
        spread = rng.uniform(0, 1.0) * width
        c = w0 + rng.uniform(0, spread, n)
        z = max(zeta, 0.0) * rng.uniform(1.0, 1.2, n) if zeta > 0 else np.zeros(n)
        roots.append(-z * c + 1j * c)
    roots = np.concatenate(roots)
    points = resonance_points(roots, 1e-6, 1e6)
    floor = np.maximum(np.abs(roots.real), 1e-7 * np.abs(roots))
    _assert_no_coarser(points, -floor + 1j * roots.imag)
    assert points.size < 40 * roots.size


def test_a_lone_root_keeps_its_own_window_and_copies_share_one():
    """A root alone: exactly its 40 points. Six copies of an undamped mode 1e-9 apart
    (relative; a tenth of the window's half-width at the damping floor 1e-7): one window of
    about 40 points, not 240, nowhere coarser."""
    root = -0.01 * 3.0 + 3.0j
    np.testing.assert_allclose(resonance_points([root], 1e-3, 1e3),
                               3.0 + 0.03 * np.tan(np.linspace(-THETA, THETA, 40)),
                               rtol=1e-15, atol=0)
    copies = 1j * 2.0 * (1.0 + 1e-9 * np.arange(6) / 5)
    points = resonance_points(copies, 1e-3, 1e3)
    assert points.size <= 50
    _assert_no_coarser(points, -2e-7 + 1j * copies.imag)


def test_roots_too_far_apart_keep_their_own_windows():
    """Two undamped copies three half-widths apart: both windows, 80 points."""
    copies = 1j * np.array([5.0, 5.0 * (1 + 3e-7)])
    points = resonance_points(copies, 1e-3, 1e3)
    assert points.size == 80
    _assert_no_coarser(points, -5e-7 + 1j * copies.imag)
