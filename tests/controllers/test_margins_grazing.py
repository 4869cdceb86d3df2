"""Crossings that come in pairs between two grid points: a loop whose |L| peaks just above 1 at
a lightly damped mode, or whose Nyquist curve just touches the negative real axis, between two
points of its frequency grid.

The grid shows no sign change there, yet the loop crosses twice, and those crossovers can set
the margins: at a flexible mode's resonance peak the phase margin is modest and the frequency
high, so the delay margin there is far below the rigid-body crossover's. A verdict that misses
them is too optimistic (a delay margin eight times the true one; a delayed loop called stable
that is not).

The loops are built so: a hub (1000 kg m^2) with two lightly damped collocated modes under a
rolled-off PD, the plant's torque gain scaled so that the true peak of |L| at a mode is
just above 1 (by half of what the grid's points beside it miss the peak by, some 1e-4 or
1e-6), the peak found by a bounded scalar search on an evaluation of L from the plain
state-space matrices (numpy only). The grid's largest |L| beside the peak stays below 1
(asserted: the case is a graze, not a sign change on the grid). The references are the crossings of
|L| = 1 bracketed on either side of the true peak and bisected on that same plain evaluation.
"""
import math
import warnings

import control
import numpy as np
import pytest
from scipy.optimize import brentq, minimize_scalar

import controllers
from controllers.loop import LoopTransfer
from controllers.margins import loop_margins, loop_verdict, multiloop_margins
from plants import modal_plant

J = 1000.0                                                        # kg m^2
MODES = [(3.0, 0.004, 0.02, 0.02), (7.5, 0.003, 0.015, 0.015)]   # (w rad/s, zeta, b, c)


def controller():
    rigid = modal_plant(J, [], disturbance=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return controllers.pd(rigid, natural_frequency=0.4, damping=0.7, roll_off=1.6)


def plant(gain: float) -> control.StateSpace:
    P = modal_plant(J, MODES, disturbance=False)
    return control.ss(P.A, P.B * gain, P.C, P.D, inputs=["torque"], outputs=["theta", "omega"])


def plain_loop(P: control.StateSpace, K: control.StateSpace):
    """L(j omega) = -K(j omega) P(j omega) from the state-space matrices alone."""
    fed = [list(K.input_labels).index(name) for name in ("theta", "omega")]

    def response(sys, rows, cols, s):
        n = sys.A.shape[0]
        return (sys.C[rows] @ np.linalg.solve(s * np.eye(n) - sys.A, sys.B[:, cols])
                + sys.D[np.ix_(rows, cols)])

    def L(w: float) -> complex:
        s = 1j * w
        p = response(P, [0, 1], [0], s)                       # (theta, omega) / torque
        k = response(K, [0], fed, s)                          # torque / (theta, omega)
        return complex(-(k @ p)[0, 0])

    return L


def grazing_case(mode: int):
    """(plant, controller, plain L, frequency of the true peak): the torque gain scaled so that
    the true peak of |L| at the mode lies above 1 by half of what the grid's points beside it
    lie below the peak (the grid does not depend on this gain: a planar loop's is made of the
    plant's and the controller's poles and the loop's zeros)."""
    K = controller()
    L1 = plain_loop(plant(1.0), K)
    w0 = MODES[mode][0]
    peak = minimize_scalar(lambda w: -abs(L1(w)), bounds=(0.99 * w0, 1.01 * w0),
                           method="bounded", options={"xatol": 1e-12})
    loop = LoopTransfer(plant(1.0), K)
    grid = loop.grid()
    near = grid[(grid > 0.98 * w0) & (grid < 1.02 * w0)]
    below = np.abs(loop.matrix(near)[:, 0, 0]).max() / -peak.fun    # < 1
    gain = (1.0 + 0.5 * (1.0 / below - 1.0)) / -peak.fun
    P = plant(gain)
    return P, K, plain_loop(P, K), float(peak.x)


def true_crossovers(L, w_peak: float) -> list[tuple[float, complex]]:
    """The two crossings of |L| = 1 beside the peak, bisected on L itself."""
    f = lambda w: abs(L(w)) - 1.0
    assert f(w_peak) > 0.0
    out = []
    for side in (-1.0, 1.0):
        step = 1e-6 * w_peak
        while f(w_peak + side * step) > 0.0:
            step *= 2.0
        a, b = sorted([w_peak, w_peak + side * step])
        w = brentq(f, a, b, xtol=1e-14 * w_peak, rtol=1e-15)
        out.append((w, L(w)))
    return out


def delay_margin(crossover: tuple[float, complex]) -> float:
    w, Lw = crossover
    return (math.pi + np.angle(Lw)) % (2.0 * math.pi) / w


def phase_margin(crossover: tuple[float, complex]) -> float:
    pm = 180.0 + math.degrees(np.angle(crossover[1]))
    return pm - 360.0 if pm > 180.0 else pm


@pytest.mark.parametrize("mode", [0, 1])
def test_the_case_is_a_graze_the_grid_does_not_show(mode):
    P, K, _, w_peak = grazing_case(mode)
    loop = LoopTransfer(P, K)
    grid = loop.grid()
    near = grid[(grid > 0.98 * w_peak) & (grid < 1.02 * w_peak)]
    assert near.size > 10
    # below 1 by far more than L's round-off (~1e-13)
    assert np.abs(loop.matrix(near)[:, 0, 0]).max() < 1.0 - 1e-7


@pytest.mark.parametrize("mode", [0, 1])
def test_margins_find_both_crossovers_of_a_peak_between_grid_points(mode):
    P, K, L, w_peak = grazing_case(mode)
    crossings = true_crossovers(L, w_peak)
    m = controllers.margins(P, K)
    # the delay margin is the least over every gain crossover: the peak's, at a high frequency
    truth = min(delay_margin(c) for c in crossings)
    # (the rigid-body crossover's, for comparison: far larger)
    assert m.delay_margin == pytest.approx(truth, rel=1e-8)
    # the phase margin is the least |PM| over the crossovers: at most the peak's
    assert abs(m.phase_margin) <= min(abs(phase_margin(c)) for c in crossings) * (1 + 1e-9)


def test_the_peaks_crossovers_set_the_delay_margin():
    """The premise of the cases above: the crossovers a grid can miss are the ones that
    matter. Without the peak's crossovers (the plant's gain 0.9 of the grazing one: the peak
    below 1, the rest of the loop as good as unchanged), the delay margin is the rigid-body
    crossover's, several times the peak's."""
    P, K, L, w_peak = grazing_case(0)
    below = control.ss(P.A, 0.9 * P.B, P.C, P.D, inputs=["torque"], outputs=["theta", "omega"])
    rigid = controllers.margins(below, K)
    assert rigid.delay_margin > 5.0 * min(delay_margin(c) for c in true_crossovers(L, w_peak))


def test_a_delay_inside_the_peaks_window_is_unstable():
    """Stability with a delay: each crossover of |L| = 1 moves a pair of closed-loop roots
    across the imaginary axis at the delay that turns L there onto -1, to the right where |L|
    falls through 1, back to the left where it rises. The peak's two crossovers so make the
    loop unstable for delays between theirs (a window: the delay margin is its start), stable
    again beyond (up to the rigid-body crossover's 1.8 s). Reference: the loop with a [10/10]
    Pade approximant of the delay (exact to far better than the window at omega tau < 1),
    its closed-loop eigenvalues."""
    P, K, L, w_peak = grazing_case(0)
    delays = sorted(delay_margin(c) for c in true_crossovers(L, w_peak))
    tau = 0.5 * (delays[0] + delays[1])
    num, den = control.pade(tau, 10)
    pade = control.ss(control.tf(num, den))
    delayed = control.ss(pade.A, pade.B, pade.C, pade.D, inputs=["u"], outputs=["torque"])
    Ku = control.ss(K.A, K.B, K.C, K.D, inputs=list(K.input_labels), outputs=["u"])
    closed = control.interconnect([P, delayed, Ku], inplist=["theta_ref"], outlist=["theta"])
    poles = np.linalg.eigvals(closed.A)
    n_reference = int(np.sum(poles.real > 0.0))
    assert n_reference == 2 and np.min(np.abs(poles.real)) > 1e-9 * np.max(np.abs(poles))
    verdict = controllers.spillover(P, K, delay=tau)
    assert not verdict.stable and verdict.n_unstable_poles == n_reference
    # the planar verdict of a loop known as a function of omega counts them the same way
    loop = LoopTransfer(P, K)
    function = loop_verdict(lambda w: loop.matrix(w)[:, 0, 0], loop.grid(), delay=tau)
    assert not function.stable and function.n_unstable_poles == n_reference


def test_loop_margins_find_a_touch_of_the_negative_real_axis_between_grid_points():
    """L(w) = -2 + j ((w - 1)^2 - eps) crosses the negative real axis at w = 1 +- sqrt(eps),
    both between the grid points 0.9 and 1.1, with L = -2 there: a gain margin of -6.02 dB
    (20 log10 2) that a sign change of Im L on the grid does not show."""
    eps = 1e-3

    def L(w):
        w = np.asarray(w, dtype=float)
        return -2.0 + 1j * ((w - 1.0) ** 2 - eps)

    grid = np.array([0.5, 0.7, 0.9, 1.1, 1.3, 1.5])
    assert np.all(L(grid).imag > 0)
    m = loop_margins(L, grid)
    assert m.gain_margin == pytest.approx(-20.0 * math.log10(2.0), rel=1e-12)
    assert m.phase_crossover_frequency == pytest.approx(1.0 - math.sqrt(eps), rel=1e-12)


def test_each_loop_at_a_time_finds_its_own_graze():
    """A diagonal three-axis loop: each loop at a time is its diagonal entry, the grazing
    planar loop on axis y; its loop-at-a-time margins are the planar loop's."""
    P, K, L, w_peak = grazing_case(1)
    loop = LoopTransfer(P, K)
    grid = loop.grid()

    def diagonal(w):
        w = np.asarray(w, dtype=float).reshape(-1)
        out = np.zeros((w.size, 3, 3), dtype=complex)
        out[:, 0, 0] = out[:, 2, 2] = 0.3 / (1j * w)   # benign: 90 deg margin at 0.3 rad/s
        out[:, 1, 1] = loop.matrix(w)[:, 0, 0]
        return out

    m = multiloop_margins(diagonal, grid, axes=["x", "y", "z"])
    truth = min(delay_margin(c) for c in true_crossovers(L, w_peak))
    assert m.loop_at_a_time["y"].delay_margin == pytest.approx(truth, rel=1e-8)
    # the multivariable delay margin (the eigenvalues of L crossing the unit circle)
    assert m.delay_margin == pytest.approx(truth, rel=1e-8)


def test_the_modulus_margin_is_the_lower_of_two_dips_the_coarser_grid_point_hides():
    """|1 + L| dips twice: to 0.3 at w = 1, on a grid point, and to 0.29 at w = 2, halfway
    between two grid points 0.1 apart, where the grid shows 0.415. The modulus margin is the
    lower dip, 0.29, which a refinement of the grid's least value alone misses."""

    def L(w):
        w = np.asarray(w, dtype=float)
        depth = np.minimum(0.3 + (w - 1.0) ** 2, 0.29 + 50.0 * (w - 2.0) ** 2)
        return -1.0 + depth * np.exp(0.3j)

    grid = np.concatenate([np.linspace(0.2, 1.4, 7), np.linspace(1.55, 3.05, 16)])
    assert np.isclose(grid, 1.0).any() and not np.isclose(grid, 2.0).any()
    assert np.abs(1.0 + L(grid)).min() == pytest.approx(0.3, rel=1e-12)
    m = loop_margins(L, grid)
    assert m.modulus_margin == pytest.approx(0.29, rel=1e-10)
    assert m.modulus_margin_frequency == pytest.approx(2.0, rel=1e-5)


def test_the_modulus_margin_at_a_broad_minimum_between_log_grid_points():
    """A hub (1746 kg m^2) with four lightly damped modes (one non-collocated) under a PD
    rolled off at 5.58 rad/s: |1 + L| has its grid's least value at the 56.3 rad/s mode
    (0.1311) and a broad minimum at 4.24 rad/s, between two points of the grid's logarithmic
    stretch (3 % apart: grid 0.1313), whose true value is 0.1276. Reference: a bounded scalar
    search of |1 + L| on the plain state-space evaluation."""
    modes = [(3.76629, 0.000587102, 0.0110859, 0.0110859),
             (11.2166, 0.00176084, 0.0181183, 0.0181183),
             (23.6699, 0.00825866, 0.0177282, -0.0251146),
             (56.2928, 0.00012146, 0.0171954, 0.0171954)]
    P = modal_plant(1746.3, modes, disturbance=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        K = controllers.pd(modal_plant(1746.3, [], disturbance=False), natural_frequency=1.6028,
                           damping=0.73574, roll_off=5.5782)
    L = plain_loop(P, K)
    broad = minimize_scalar(lambda w: abs(1.0 + L(w)), bounds=(4.0, 4.5), method="bounded",
                            options={"xatol": 1e-10})
    loop = LoopTransfer(P, K)
    grid = loop.grid()
    on_grid = np.abs(1.0 + loop.matrix(grid)[:, 0, 0])
    # the premise: the grid's least value is elsewhere, above the broad minimum by over 1 %
    assert abs(grid[np.argmin(on_grid)] - 56.29) < 0.1
    assert on_grid.min() > 1.01 * broad.fun
    m = controllers.margins(P, K)
    assert m.modulus_margin == pytest.approx(broad.fun, rel=1e-9)
    assert m.modulus_margin_frequency == pytest.approx(broad.x, rel=1e-4)
