"""Margins on the exact distributed beam, found on the exact loop function (not on a grid).

Reference: the loop of a hub carrying the paper's rod, closed by a PD, evaluated in 40-digit
arithmetic from the closed form of the free-free beam's W(s) (written out here, independent of
appendages.beam and spacecraft.dynamics.exact), the hub's planar kinematics and the controller's
state-space matrices; its crossings and the minimum of |1 + L| found by mpmath's root finder
on that function. flexsat's exact response is right to about 1e-13 relative, so its margins
must agree to 1e-9 (the promised accuracy, four orders of magnitude above the response's
error); a grid interpolation (100 points a decade) was off by up to 4e-4 deg.
"""
import math

import mpmath as mp
import numpy as np
import pytest

import controllers
from spacecraft.design.loop import DesignLoop, run
from spacecraft.scene.read import load_scene

from scenes import scene_with

DPS = 40


def _beam_W(EJ, rhoA, L, s):
    """W(s) of the free-free Euler-Bernoulli beam (delta, phi per F_y, M at x = 0), closed form
    in mpmath: x = (-s^2 rho A / EJ)^(1/4) L, D = 1 - cos x cosh x (PAPER.md)."""
    x = mp.root(-s**2 * rhoA / EJ, 4) * L
    D = 1 - mp.cos(x) * mp.cosh(x)
    w1 = L**3 / EJ * (mp.cos(x) * mp.sinh(x) - mp.sin(x) * mp.cosh(x)) / (x**3 * D)
    w2 = L**2 / EJ * mp.sin(x) * mp.sinh(x) / (x**2 * D)
    w4 = -L / EJ * (mp.cos(x) * mp.sinh(x) + mp.sin(x) * mp.cosh(x)) / (x * D)
    return mp.matrix([[w1, w2], [w2, w4]])


class _Reference:
    """theta/torque and L(j w) of hub + beam + controller in mpmath.

    Hub coordinates (Y, theta) (the axial X decouples for a beam along the hub's x axis);
    the root of a beam mounted at (r, 0) along +x moves by delta = Y + r theta, phi = theta,
    so with D = W^-1 the hub's dynamic stiffness is
    Z = [[m s^2, 0], [0, J s^2]] + G^T D G, G = [[1, r], [0, 1]], and theta/torque = (Z^-1)_22.
    """

    def __init__(self, mass, inertia, r, beam, controller):
        self.m, self.J, self.r = mp.mpf(mass), mp.mpf(inertia), mp.mpf(r)
        self.EJ, self.rhoA = mp.mpf(beam.bending_stiffness), mp.mpf(beam.linear_density)
        self.length = mp.mpf(beam.length)
        inputs = list(controller.input_labels)
        row = list(controller.output_labels).index("torque")
        self.A = mp.matrix(np.asarray(controller.A).tolist()) if controller.nstates else None
        self.B = [mp.matrix(np.asarray(controller.B)[:, inputs.index(n)].tolist())
                  for n in ("theta", "omega")]
        self.C = mp.matrix([np.asarray(controller.C)[row].tolist()])
        self.D = [mp.mpf(float(controller.D[row, inputs.index(n)])) for n in ("theta", "omega")]

    def theta(self, w):
        s = mp.mpc(0, w)
        D = mp.inverse(_beam_W(self.EJ, self.rhoA, self.length, s))
        G = mp.matrix([[1, self.r], [0, 1]])
        Z = G.T * D * G + mp.diag([self.m * s**2, self.J * s**2])
        return mp.inverse(Z)[1, 1]

    def K(self, w, k):
        s = mp.mpc(0, w)
        if self.A is None:
            return self.D[k]
        n = self.A.rows
        x = mp.lu_solve(s * mp.eye(n) - self.A, self.B[k])
        return (self.C * x)[0, 0] + self.D[k]

    def L(self, w):
        return -(self.K(w, 0) + mp.mpc(0, w) * self.K(w, 1)) * self.theta(w)


@pytest.fixture(scope="module")
def loop():
    """The base scene (undamped paper's rod, PD at 0.1 rad/s) with the exact reference on."""
    scene = load_scene(scene_with(**{"outputs.exact_reference": True, "manoeuvre": None}))
    result = run(scene)
    row = result.data["closed_loops"][0]
    K = result.designs[row["design"]]["controllers"]["pd"]
    beam = scene.appendages[0].beam.build()
    return result, row, K, _Reference(100.0, 50.0, 0.5, beam, K)


def test_the_reference_is_flexsats_exact_response(loop):
    # the reference model's conventions (signs, kinematics) against flexsat's exact response
    result, _, _, ref = loop
    runner = DesignLoop(result.scene)
    omega = np.array([0.05, 0.7, 2.3, 9.0])
    theta = runner.exact_spacecraft().exact.attitude_compliance(omega)[:, 0, 0]
    with mp.workdps(DPS):
        expected = np.array([complex(ref.theta(w)) for w in omega])
    # the exact response is right to ~1e-13 relative (tests/appendages/test_beam.py, test_spacecraft.py)
    np.testing.assert_allclose(theta, expected, rtol=1e-11, atol=0)


def test_exact_margins_are_found_on_the_exact_loop_to_1e_9(loop):
    _, row, _, ref = loop
    e = row["exact_verdict"]
    assert e["stable"]
    with mp.workdps(DPS):
        # gain crossover: |L| = 1, from flexsat's frequency (the root finder converges to the
        # reference's own root: 40 digits, not flexsat's)
        w_gc = mp.findroot(lambda w: abs(ref.L(w)) - 1, mp.mpf(e["gain_crossover_frequency"]))
        phase = mp.degrees(mp.arg(ref.L(w_gc)))
        pm = 180 + phase if 180 + phase <= 180 else phase - 180
        # modulus margin: d|1 + L|^2/dw = 0
        w_mm = mp.findroot(lambda w: mp.diff(lambda v: abs(1 + ref.L(v)) ** 2, w),
                           mp.mpf(e["modulus_margin_frequency"]))
        mm = abs(1 + ref.L(w_mm))
    # the crossings and the minimum found by flexsat are the reference's to 1e-9 relative
    assert abs(e["gain_crossover_frequency"] / float(w_gc) - 1) < 1e-9
    # margins to 1e-9 (deg; absolute on a modulus margin of order 1)
    assert abs(e["phase_margin"] - float(pm)) < 1e-9
    assert abs(e["modulus_margin"] - float(mm)) < 1e-9
    if math.isfinite(e["gain_margin"]):
        with mp.workdps(DPS):
            w_pc = mp.findroot(lambda w: mp.im(ref.L(w)), mp.mpf(e["phase_crossover_frequency"]))
            gm = -20 * mp.log10(abs(ref.L(w_pc)))
        assert abs(e["gain_margin"] - float(gm)) < 1e-9


def test_the_exact_verdict_keeps_the_nyquist_count_and_refines_only_margins(loop):
    # the count is the FRD's (controllers.spillover); only the margins differ from a grid
    # interpolation, and there by far more than 1e-9 (the finding: 3.7e-4 deg on the default
    # scene's PD)
    result, row, K, _ = loop
    grid = controllers.spillover(result.exact_frd, K)
    assert grid.stable == row["exact_verdict"]["stable"]
    assert grid.n_unstable_poles == row["exact_verdict"]["n_unstable_poles"]
    assert abs(grid.margins.phase_margin - row["exact_verdict"]["phase_margin"]) < 1e-2


def test_a_loop_delay_enters_the_exact_margins(loop):
    # a delay tau multiplies L by exp(-j omega tau): |L| unchanged, the phase lowered by
    # omega tau. At the delayed loop's own gain crossover (on this undamped rod a resonance's:
    # 10 ms is beyond what its undamped modes tolerate, at 92 rad/s), the reference's |L| is 1
    # and its phase margin less omega tau is the delayed margin.
    from spacecraft.design.verdicts import exact_loop_verdict

    result, row, K, ref = loop
    theta = np.asarray(result.exact_frd.frdata)[0, 0]
    runner = DesignLoop(result.scene)
    tau = 0.01
    delayed = exact_loop_verdict(runner.exact_spacecraft(), K, result.exact_frd.omega,
                                 theta=theta, delay=tau).margins
    w = delayed.gain_crossover_frequency
    with mp.workdps(DPS):
        L = ref.L(mp.mpf(w))
        # the crossover is found to 1e-13 relative in frequency: at a resonance's steep
        # crossing |L| is 1 to within its change over that step
        step = abs(float(abs(ref.L(mp.mpf(w) * (1 + mp.mpf("1e-13")))) - abs(L)))
        pm = float(mp.degrees(mp.arg(L))) + 180.0 - math.degrees(w * tau)
    pm = (pm + 180.0) % 360.0 - 180.0
    assert abs(float(abs(L)) - 1.0) < 1e-9 + 2.0 * step
    assert abs(delayed.phase_margin - pm) < 1e-9
    assert delayed.delay == tau


def test_a_controller_changed_in_place_is_judged_anew(loop):
    # the exact verdict keeps what it works out of a controller alone (its gains, roots and
    # unstable poles) while the controller lives: judged again after its matrices changed in
    # place, it must give the verdict of a new controller with those matrices, not the old one
    import copy

    from spacecraft.design.verdicts import exact_loop_verdict

    result, _, K, _ = loop
    sc = DesignLoop(result.scene).exact_spacecraft()
    omega = np.asarray(result.exact_frd.omega)
    theta = np.asarray(result.exact_frd.frdata)[0, 0]
    K = copy.deepcopy(K)
    first = exact_loop_verdict(sc, K, omega, theta=theta)
    assert exact_loop_verdict(sc, K, omega, theta=theta).margins == first.margins
    K.D[...] *= 3.0                    # three times the gains, the same object
    changed = exact_loop_verdict(sc, K, omega, theta=theta)
    fresh = exact_loop_verdict(sc, copy.deepcopy(K), omega, theta=theta)
    assert changed.margins == fresh.margins
    assert changed.margins.phase_margin != first.margins.phase_margin
