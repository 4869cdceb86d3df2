"""The exact three-axis frequency response through W6 and the exact-beam verdict of a
three-axis loop (spacecraft.dynamics.exact, spacecraft.design.verdicts.exact_loop_verdict,
spacecraft.design.exact_grid).

References: the state-space plant of the same spacecraft with every appendage truncated to
Craig-Bampton modes (an independent route: assembled mass and stiffness matrices, their modes,
a modal realisation), which converges to the exact response as modes are added; the planar
exact response for a three-axis spacecraft that moves in its plane; the rigid body's
-J_c^-1/omega^2; and the state-space verdict (closed-loop eigenvalues, controllers.spillover)
of the same truncated spacecraft, which the frequency-response verdict must reproduce.
"""
import math
import warnings

import control
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import controllers
from appendages import Beam, ModalAppendage, SteppedBeam, TipBody
from spacecraft import Hub, Mount, Spacecraft
from spacecraft.design.exact_grid import exact_grid, locator_model
from spacecraft.design.verdicts import exact_loop_verdict

from loops import assert_same_margins, with_unstable_pole

R1 = Rotation.from_euler("zyx", [0.3, -0.4, 0.7]).as_matrix()
R2 = Rotation.from_euler("zyx", [2.2, 0.5, -1.0]).as_matrix()
J = np.array([[95.0, 1.2, -0.8], [1.2, 78.0, 1.5], [-0.8, 1.5, 64.0]])
ZETA = 0.005
WING = Beam.rectangular(3.0, 1.0, 0.02, 40.0, 7e8, poisson_ratio=0.3, damping_ratio=ZETA)
# a tip body on the boom's axis (Spacecraft.inertia places an appendage's centre of mass on
# its axis; the dynamics take any offset)
BOOM = Beam.tube(2.0, 0.05, 0.001, 1600.0, 1.2e11, poisson_ratio=0.3, damping_ratio=ZETA,
                 tip=TipBody(0.5, np.diag([1e-3, 2e-3, 2e-3]), offset=(0.05, 0.0, 0.0)))
STEPPED = SteppedBeam([Beam.tube(1.0, 0.06, 0.002, 1600.0, 1.2e11, poisson_ratio=0.3,
                                 damping_ratio=ZETA),
                       Beam.tube(1.5, 0.04, 0.001, 1600.0, 1.2e11, poisson_ratio=0.3,
                                 damping_ratio=ZETA)])
PLACES = [([0.0, 0.6, 0.0], R1), ([0.3, 0.1, -0.4], R2), ([-0.3, -0.2, 0.3], R2.T)]


def craft(model=lambda a: a, appendages=(WING, BOOM, STEPPED)):
    return Spacecraft(Hub(80.0, J), [Mount(model(a), p, orientation=R, name=f"a{k}")
                                     for k, (a, (p, R)) in enumerate(zip(appendages, PLACES))])


def modal_appendage(beam, n):
    """A three-axis ModalAppendage holding the n-mode Craig-Bampton model of a beam: its
    cantilever modes (root_model(6)'s internal block: unit mass, diagonal stiffness), their
    participation and the rigid mass about the root."""
    rm = beam.truncated(n).root_model(6)
    w = np.sqrt(np.diag(rm.stiffness)[6:])
    order = np.argsort(w)
    return ModalAppendage(w[order], rm.mass[6:, :6][order], rm.mass[:6, :6], damping=ZETA,
                          length=beam.length)


def plant_response(plant, omega):
    """theta and omega per torque of a state-space plant, (f, 6, 3)."""
    return np.moveaxis(controllers.frequency_response_data(plant, omega).frdata, -1, 0)[:, :6, :3]


# -- the exact response --------------------------------------------------------------------------
@pytest.mark.slow
def test_craig_bampton_plants_converge_to_the_exact_response():
    """Uniform, tip-body and stepped beams at skewed mounts: the state-space plant of their
    n-mode truncations (attitudes and rates per torque) against the exact response through
    W6, below the seventh coupled mode. Measured relative errors (largest entry at each
    frequency): 16 modes 3.7e-5, 32 modes 2.0e-6, 64 modes 5.3e-7; at least a factor 3 per
    doubling, below 1e-6 at 64 modes, and 1e-13 at 0.05 rad/s (the rigid body dominates)."""
    exact = craft()
    w = exact.natural_frequencies(7)
    omega = np.array([0.05, 0.5, 0.5 * w[0], 1.3 * w[0], 0.5 * (w[2] + w[3]), 0.9 * w[6]])
    G = np.moveaxis(exact.frequency_response(omega, output="both").frdata, -1, 0)
    errors = []
    for n in (16, 32, 64):
        H = plant_response(craft(lambda a: a.truncated(n)).plant(), omega)
        errors.append(np.max(np.abs(H - G).max(axis=(1, 2)) / np.abs(G).max(axis=(1, 2))))
        if n == 64:
            assert np.abs(H - G)[0].max() < 1e-13 * np.abs(G[0]).max()
    assert errors[1] < errors[0] / 3 and errors[2] < errors[1] / 3, errors
    assert errors[2] < 1e-6


@pytest.mark.slow
def test_a_modal_appendage_through_W6_is_its_state_space_plant():
    """A finite appendage two ways: its W6 in the exact response, its realisation in the
    plant; equal to the plant's rounding (1e-10 of the largest entry)."""
    sc = craft(appendages=(modal_appendage(WING, 12), modal_appendage(BOOM, 10),
                           modal_appendage(STEPPED, 10)))
    omega = np.array([0.02, 0.7, 9.0, 40.0, 130.0])
    G = np.moveaxis(sc.frequency_response(omega, output="both").frdata, -1, 0)
    H = plant_response(sc.plant(), omega)
    assert np.all(np.abs(H - G).max(axis=(1, 2)) < 1e-10 * np.abs(G).max(axis=(1, 2)))


@pytest.mark.parametrize("kind", ["uniform", "tip body", "stepped", "modal"])
def test_the_rigid_limit_is_the_inverse_inertia_without_a_near_singular_solve(kind):
    """theta/torque -> -J_c^-1/omega^2 (J_c the inertia about the spacecraft's centre of mass):
    Z(s) = s^2 (M_rigid + O(s^2)) is solved as it is, the 1/s^2 exact, the flexible part a
    relative O(omega^2/w_1^2) (1e-2 at 1e-8 ... 1e-4 rad/s: below 1e-9 relative, no loss
    from the tiny s^2). rtol 1e-12 + (omega/w_1)^2."""
    appendage = {"uniform": WING, "tip body": BOOM, "stepped": STEPPED,
                 "modal": modal_appendage(WING, 8)}[kind]
    sc = craft(appendages=(appendage,))
    # the first coupled frequency for the tolerance (a truncation's: an upper bound, close)
    w1 = craft(lambda a: a.truncated(4), appendages=(appendage,)).natural_frequencies(
        1, exact=False)[0]
    for omega in (1e-8, 1e-6, 1e-4):
        G = sc.frequency_response([omega]).frdata[..., 0]
        expected = -np.linalg.inv(sc.inertia) / omega**2
        assert np.abs(G - expected).max() <= (1e-12 + 10 * (omega / w1) ** 2) * np.abs(
            expected).max(), omega


def test_a_spacecraft_in_its_plane_gives_the_planar_exact_response():
    """Stepped beams with tip bodies mounted in the hub's x-y plane (inextensible, as the
    planar model is): theta_z/torque_z and omega_z/torque_z are the planar spacecraft's
    theta/torque and omega/torque (1e-12: one solve of 6x6 against one of 3x3), and the
    in-plane torque does not move the out-of-plane attitudes (1e-15 relative)."""
    tip = TipBody(0.3, np.diag([2e-3, 4e-3, 4e-3]), offset=(0.04, 0.0, 0.0))
    segments = [Beam(1.0, 40.0, 0.5, bending_stiffness_y=60.0, torsional_stiffness=10.0,
                     torsional_inertia=0.002),
                Beam(1.5, 15.0, 0.3, bending_stiffness_y=25.0, torsional_stiffness=6.0,
                     torsional_inertia=0.001)]
    beams = [SteppedBeam(segments, tip=tip), SteppedBeam(segments[::-1], tip=tip)]
    places = [((0.6, 0.2), 0.4), ((-0.4, -0.3), 2.6)]
    planar = Spacecraft(Hub(60.0, 40.0), [Mount(b, p, a, name=f"a{k}")
                                          for k, (b, (p, a)) in enumerate(zip(beams, places))])
    three = Spacecraft(Hub(60.0, np.diag([35.0, 30.0, 40.0])),
                       [Mount(b, p, a, name=f"a{k}")
                        for k, (b, (p, a)) in enumerate(zip(beams, places))])
    omega = np.array([0.03, 0.8, 4.0, 17.0, 60.0])
    G2 = planar.frequency_response(omega, output="both").frdata[:, 0]
    G3 = three.frequency_response(omega, output="both").frdata
    np.testing.assert_allclose(G3[[2, 5], 2], G2, rtol=1e-12, atol=0)
    assert np.all(np.abs(G3[[0, 1, 3, 4], 2]) <= 1e-15 * np.abs(G3[[2, 5], 2]).max(axis=0))
    response = three.frequency_response(omega, output="both")
    assert list(response.output_labels) == ["theta_x", "theta_y", "theta_z", "omega_x",
                                            "omega_y", "omega_z"]
    np.testing.assert_allclose(G3[3:], G3[:3] * 1j * omega, rtol=1e-15)


# -- the grid ------------------------------------------------------------------------------------
@pytest.mark.slow
def test_the_exact_grid_resolves_every_exact_coupled_mode_in_three_axes():
    """The grid's modes are located on undamped Craig-Bampton truncations of every motion
    (both bending planes, torsion, axial): each exact coupled frequency below the grid's top
    (Wittrick-Williams through W6) has grid points within 0.1 zeta w on both sides, so the
    phase of det(I + L) through each resonance is resolved (measured: the located modes are
    within 3e-8 of the exact ones, a thousandth of the half-power band)."""
    sc = craft()
    wb = 0.5
    grid = exact_grid(sc, wb)
    assert grid[0] == pytest.approx(1e-3 * wb) and grid[-1] == pytest.approx(1e3 * wb)
    exact = sc.natural_frequencies(40)
    exact = exact[exact < 1e3 * wb]
    assert exact.size >= 10
    for w in exact:
        below = grid[(grid < w) & (grid > w * (1 - 0.1 * ZETA))]
        above = grid[(grid > w) & (grid < w * (1 + 0.1 * ZETA))]
        assert below.size and above.size, w
    # the locating model of a three-axis beam keeps every motion's clamped modes below the top
    located = locator_model(WING, 1e3 * wb, three_axis=True)
    clamped = WING.clamped_frequencies6(1e3 * wb)
    assert located.root_model(6).n - 6 >= np.count_nonzero(clamped < 1e3 * wb)


# -- the verdict ---------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def truncated():
    """Two beams truncated to 8 Craig-Bampton modes: a finite spacecraft whose exact response
    (through the truncations' W6) and state-space plant are one model."""
    sc = craft(lambda a: a.truncated(8), appendages=(WING, BOOM))
    return sc, sc.plant(prune=True)


def controllers_of(plant):
    pd = controllers.pd(plant, natural_frequency=0.5, damping=0.7)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        lqr = controllers.lqr(plant, attitude_weight=1e2, rate_weight=1e3, torque_weight=1.0)
    return {"pd 0.1": controllers.pd(plant, natural_frequency=0.1, damping=0.7), "pd 0.5": pd,
            "lqr": lqr,
            # an open-loop unstable controller, stable closed (its poles counted) and not
            "unstable controller, stable loop": with_unstable_pole(pd, 0.02, 10.0),
            "unstable controller, unstable loop": with_unstable_pole(pd, 0.02, 0.2)}


@pytest.mark.slow
def test_the_exact_verdict_of_a_truncated_spacecraft_is_its_state_space_verdict(truncated):
    """Same stability, same number of unstable poles, every margin (loop-at-a-time gain,
    phase and modulus margins, disk margin and its gain and phase, smallest singular value,
    delay margin) to 1e-9 (measured 1e-14 to 4e-12)."""
    sc, plant = truncated
    stable = []
    for name, K in controllers_of(plant).items():
        expected = controllers.spillover(plant, K)
        found = exact_loop_verdict(sc, K, exact_grid(sc, 0.5))
        assert found.method == "nyquist"
        assert (found.stable, found.n_unstable_poles) == (expected.stable,
                                                          expected.n_unstable_poles), name
        assert_same_margins(expected.margins, found.margins)
        stable.append(found.stable)
    assert stable == [True, True, True, True, False]


@pytest.mark.slow
def test_a_delay_that_destabilises_is_detected_on_the_exact_loop(truncated):
    """A PD's delay margin on the truncated spacecraft: 2 % below it stable, 2 % above
    unstable with two roots across, in the state-space and the exact verdicts alike (a PD
    at 2 rad/s: its delay margin, 0.3 s, is resolved by the state-space grid's 2e6 points)."""
    sc, plant = truncated
    K = controllers.pd(plant, natural_frequency=2.0, damping=0.7)
    grid = exact_grid(sc, 2.0)
    margin = exact_loop_verdict(sc, K, grid).margins.delay_margin
    assert margin == pytest.approx(controllers.margins(plant, K).delay_margin, rel=1e-9)
    for delay, stable in ((0.98 * margin, True), (1.02 * margin, False)):
        expected = controllers.spillover(plant, K, delay=delay)
        found = exact_loop_verdict(sc, K, grid, delay=delay)
        assert found.method == "nyquist+delay"
        assert expected.stable is stable and found.stable is stable
        assert found.n_unstable_poles == expected.n_unstable_poles
        assert found.margins.delay_margin == pytest.approx(margin - delay, rel=1e-9)
        assert_same_margins(expected.margins, found.margins)


def test_the_given_response_is_used_and_a_digital_or_planar_controller_refused(truncated):
    sc, plant = truncated
    K = controllers_of(plant)["pd 0.5"]
    grid = exact_grid(sc, 0.5)
    theta = sc.exact.attitude_compliance(grid)
    a = exact_loop_verdict(sc, K, grid)
    b = exact_loop_verdict(sc, K, grid[::-1], theta=theta[::-1])
    assert a.margins.as_dict() == b.margins.as_dict()
    with pytest.raises(ValueError, match=r"theta must be .*\(\d+, 3, 3\); got .*shape"):
        exact_loop_verdict(sc, K, grid, theta=theta[:, 0, 0])
    digital = controllers.pd(plant, natural_frequency=0.5, damping=0.7, sample_time=0.1)
    with pytest.raises(ValueError, match="continuous controller"):
        exact_loop_verdict(sc, digital, grid)
    planar = control.ss([], [], [], [[-1.0, -2.0]], inputs=["theta", "omega"],
                        outputs=["torque"])
    with pytest.raises(ValueError, match="planar controller"):
        exact_loop_verdict(sc, planar, grid)


@pytest.mark.slow
def test_the_exact_verdict_of_the_distributed_spacecraft_is_the_limit_of_truncations():
    """On the distributed beams (damped, cantilever convention), the margins of the PD and
    the LQR (tuned on a 6-mode design model) on truth models with more and more modes
    approach the exact verdict's: the largest margin difference falls by at least 3x from 8
    to 32 modes and is below 1e-3 at 32 (measured: 1.9e-4 at 8, 2.4e-6 at 32)."""
    exact = craft(appendages=(WING, BOOM))
    design = craft(lambda a: a.truncated(6), appendages=(WING, BOOM)).plant(prune=True)
    grid = exact_grid(exact, 0.5)
    for name, K in list(controllers_of(design).items())[:3]:
        reference = exact_loop_verdict(exact, K, grid)
        assert reference.stable
        differences = []
        for n in (8, 32):
            truth = craft(lambda a: a.truncated(n), appendages=(WING, BOOM)).plant(prune=True)
            verdict = controllers.spillover(truth, K)
            assert verdict.stable
            a, b = verdict.margins.as_dict(), reference.margins.as_dict()
            differences.append(max(abs(a[k] - b[k]) / max(1.0, abs(b[k])) for k in a
                                   if math.isfinite(b[k])))
        assert differences[1] < differences[0] / 3 or differences[1] < 1e-9, (name, differences)
        assert differences[1] < 1e-3, (name, differences)


# -- the planar limit ----------------------------------------------------------------------------
def in_plane_spacecraft(three_axis: bool):
    """Damped beams, one with a tip body, mounted in the hub's x-y plane: planar, or three-axis
    with a diagonal hub inertia, whose yaw (z) decouples from roll and pitch (x, y)."""
    tip = TipBody(0.3, np.diag([2e-3, 4e-3, 4e-3]), offset=(0.04, 0.0, 0.0))
    beams = [Beam(2.5, 25.0, 0.4, bending_stiffness_y=40.0, torsional_stiffness=8.0,
                  torsional_inertia=0.002, damping_ratio=ZETA, tip=tip),
             Beam(1.5, 15.0, 0.3, bending_stiffness_y=25.0, torsional_stiffness=6.0,
                  torsional_inertia=0.001, damping_ratio=ZETA)]
    places = [((0.6, 0.2), 0.4), ((-0.4, -0.3), 2.6)]
    hub = Hub(60.0, np.diag([35.0, 30.0, 40.0]) if three_axis else 40.0)
    return Spacecraft(hub, [Mount(b, p, a, name=f"a{k}")
                            for k, (b, (p, a)) in enumerate(zip(beams, places))])


def yaw_and_roll_pitch(planar_K, kp, kd):
    """A three-axis controller: the planar controller on yaw (theta_z, omega_z -> torque_z), a
    static PD -kp theta - kd omega on roll and pitch."""
    A, B, C, D = (np.asarray(x, dtype=float) for x in (planar_K.A, planar_K.B, planar_K.C,
                                                        planar_K.D))
    inputs = list(planar_K.input_labels)
    n = A.shape[0]
    B3 = np.zeros((n, 6))
    D3 = np.zeros((3, 6))
    for k, name in enumerate(("theta", "omega")):
        B3[:, 3 * k + 2] = B[:, inputs.index(name)]
        D3[2, 3 * k + 2] = D[0, inputs.index(name)]
    D3[0, 0] = D3[1, 1] = -kp
    D3[0, 3] = D3[1, 4] = -kd
    C3 = np.zeros((3, n))
    C3[2] = C[0]
    return control.ss(A, B3, C3, D3,
                      inputs=[f"{q}_{a}" for q in ("theta", "omega") for a in "xyz"],
                      outputs=[f"torque_{a}" for a in "xyz"])


@pytest.mark.slow
@pytest.mark.parametrize("case", ["pd", "roll-off, delayed", "unstable yaw"])
def test_a_spacecraft_whose_axes_decouple_gives_the_planar_exact_verdict(case):
    """The planar spacecraft's exact verdict is the limit of the three-axis one: with yaw
    decoupled, the yaw loop at a time is the planar loop, so its margins (gain, phase, modulus,
    their frequencies, the delay margin) equal the planar exact verdict's to 1e-9 (both refined
    on exact functions to 1e-13 in frequency; the three-axis one through W6 and a 6 x 6
    solve), and the loop's unstable poles are the planar loop's (roll and pitch are stable)."""
    planar, three = in_plane_spacecraft(False), in_plane_spacecraft(True)
    design = Spacecraft(planar.hub, [m.with_appendage(m.appendage.truncated(6))
                                     for m in planar.mounts]).plant(prune=True)
    delay = 0.0
    if case == "pd":
        K = controllers.pd(design, natural_frequency=0.4, damping=0.7)
    elif case == "roll-off, delayed":
        K = controllers.pd(design, natural_frequency=0.4, damping=0.7, roll_off=4.0)
        delay = 0.1
    else:   # a negative attitude gain: one real closed-loop root in the right half-plane
        K = control.ss([], [], [], [[8.0, -60.0]], inputs=["theta", "omega"],
                       outputs=["torque"])
    K3 = yaw_and_roll_pitch(K, 6.0, 25.0)
    expected = exact_loop_verdict(planar, K, exact_grid(planar, 0.4), delay=delay)
    found = exact_loop_verdict(three, K3, exact_grid(three, 0.4), delay=delay)
    assert found.stable == expected.stable == (case != "unstable yaw")
    assert found.n_unstable_poles == expected.n_unstable_poles == (0 if expected.stable else 1)
    a, b = found.margins.loop_at_a_time["z"].as_dict(), expected.margins.as_dict()
    assert a.keys() == b.keys()
    for key in b:
        if math.isinf(b[key]):
            assert a[key] == b[key], key
        else:
            assert a[key] == pytest.approx(b[key], rel=1e-9, abs=1e-12), key
    yaw, planar_margins = found.margins.loop_at_a_time["z"], expected.margins
    for name in ("gain_crossover_frequency", "phase_crossover_frequency"):
        a, b = getattr(yaw, name), getattr(planar_margins, name)
        assert a == b if math.isinf(b) or math.isnan(b) else a == pytest.approx(b, rel=1e-9), name
    assert yaw.delay_margin == pytest.approx(planar_margins.delay_margin, rel=1e-9)
    # the multivariable delay margin (one extra delay on every torque) is no larger
    assert found.margins.delay_margin <= planar_margins.delay_margin * (1 + 1e-9)


# -- in the design loop --------------------------------------------------------------------------
@pytest.mark.slow
def test_the_design_loop_gives_a_three_axis_loop_its_exact_verdict(truncated):
    """spacecraft.DesignLoop with a user's three-axis models: the row's exact verdict (the
    exact reference through W6 on the loop's exact grid) of a truncated spacecraft given as its
    own exact model is the truth verdict, margin by margin to 1e-9, and names the three-axis
    margins (per axis, disk margin, smallest singular value)."""
    from spacecraft import DesignLoop

    sc, _ = truncated
    design = craft(lambda a: a.truncated(4), appendages=(WING, BOOM))
    loop = DesignLoop(truth=sc, design=design, exact=sc,
                      controller={"pd": {"natural_frequency": 0.5}, "delay": 0.05})
    c = loop.closed_loops("design", "pd", models=("truth",))
    truth, exact = c.row["verdict"], c.row["exact_verdict"]
    assert c.exact_verdict.method == "nyquist+delay" and exact["stable"] and truth["stable"]
    for key in ("phase_margin_x", "modulus_margin_y", "gain_crossover_frequency_z",
                "disk_margin", "disk_phase_margin", "min_singular_value", "delay_margin"):
        assert exact[key] == pytest.approx(truth[key], rel=1e-9), key
    assert exact["delay"] == 0.05
    # an unstable loop: no margin of its exact verdict counts (each flagged 'unstable')
    K = with_unstable_pole(c.controller, 0.02, 0.2)
    c = loop.closed_loops("design", "pd", models=("truth",), controller=K)
    exact = c.row["exact_verdict"]
    assert not exact["stable"] and not c.row["verdict"]["stable"]
    assert exact["n_unstable_poles"] == c.row["verdict"]["n_unstable_poles"] > 0
    margins = [k for k in exact if k.startswith(("gain_margin", "phase_margin", "modulus_margin",
                                                  "disk_", "min_singular_value"))
               and "frequency" not in k]
    assert margins and all(exact["margin_flags"][k] == "unstable" for k in margins)
