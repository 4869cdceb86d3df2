"""The Basilisk adapter: flexsat's chains and controllers run in Basilisk (``bsk``, optional).

Tests that run Basilisk are skipped, with the install hint as the reason, when ``bsk`` is not
installed; the layout (flexsat -> Basilisk parameters), the controller law and the
not-installed error are tested without it.

What the Basilisk comparisons can expect (their tolerances)
    Basilisk integrates the nonlinear hinged-chain dynamics with RK4; flexsat's prediction is the
    linearised loop, exact at the sample instants. Their difference is (a) RK4's error, below
    1e-7 of the peak at the default step (w_max dt <= 1/2; the modes that carry the response have
    w dt < 0.1, phase error ~ w t (w dt)**4 / 120), and (b) the nonlinear terms the linear model
    drops. For a mount whose axis misses the spacecraft's centre of mass, the centrifugal load
    w**2 r has a transverse part, second order in the slew amplitude: measured 5e-5 of the peak
    tip deflection at 0.1 deg (and proportional to the angle, see the scaling tests). Hence the
    issue's bound 1e-4 of the peak at 0.1 deg, and, in the scaling tests, the proof that what
    remains is second order in the amplitude (a convention error would be first order).
"""

from __future__ import annotations

import math
import re
import subprocess
import sys
import warnings

import control
import numpy as np
import pytest

import controllers
from appendages import Beam
from appendages.chain import HingedChain
from spacecraft import Hub, Mount, Spacecraft
from spacecraft import basilisk as sb

# runs Basilisk: skipped with the install hint where bsk is not installed (tests/conftest.py)
needs_bsk = pytest.mark.basilisk

SLEW_TIME = 20.0        # s
DURATION = 40.0         # s
SMALL = math.radians(0.1)
SAMPLE_TIME = 0.1       # s: >= 10 samples per crossover for every test loop (pd checks it)


def tapered_chain(n_bodies: int, root: str = "rigid") -> HingedChain:
    """A 10 m, 6 kg chain whose bodies all differ: lengths, masses, inertias, com offsets.

    Lengths taper 1.4 : 0.6, masses follow length x taper, inertias are 1 to 1.3 times a rod's,
    centres of mass sit 36 % to 44 % along each body, hinges are c = EJ / (mean adjacent length)
    with EJ = 100 N*m^2 (the root hinge 2 EJ / l_1), damped 0.002 s * c (damping ratio
    0.001 * w: light on the first mode, about 0.1 on the highest).
    """
    w = np.linspace(1.4, 0.6, n_bodies)
    lengths = 10.0 * w / w.sum()
    masses = 6.0 * w * lengths / np.sum(w * lengths)
    inertias = masses * lengths**2 / 12.0 * (1.0 + 0.3 * np.arange(n_bodies) / n_bodies)
    offsets = lengths * (0.5 - 0.1 * w)
    stiffnesses = 100.0 / (0.5 * (lengths[:-1] + lengths[1:]))
    if root == "hinged":
        stiffnesses = np.concatenate([[200.0 / lengths[0]], stiffnesses])
    return HingedChain(lengths, masses, inertias, stiffnesses, hinge_dampings=0.002 * stiffnesses,
                       com_offsets=offsets, root=root)


def winged(chain, position=(0.3, -0.2), direction=math.radians(30.0), name="wing"):
    """Hub(100 kg, 50 kg*m^2) with one chain; by default a mount off the centre of mass, at 30 deg."""
    return Spacecraft(Hub(100.0, 50.0), [Mount(chain, position, direction, name=name)])


def digital_pd(spacecraft, sample_time=SAMPLE_TIME):
    plant = spacecraft.plant(tip_deflection=True)
    return controllers.pd(plant, natural_frequency=0.3, damping=0.7, sample_time=sample_time)


def relative_differences(spacecraft, controller, angle, **kwargs):
    """{signal: max |Basilisk - flexsat linear| / max |flexsat linear|} for one slew."""
    result = sb.simulate_slew(spacecraft, controller, angle, SLEW_TIME, duration=DURATION,
                              **kwargs)
    linear = sb.linear_slew(spacecraft, controller, angle, SLEW_TIME, duration=DURATION,
                            sample_time=kwargs.get("sample_time"),
                            disturbances=kwargs.get("disturbances"))
    return {k: v["relative"] for k, v in sb.compare(result.response, linear).items()}, result


# -- the layout: flexsat -> Basilisk parameters (no Basilisk needed) ----------------------------
def _layout_mass_properties(lay):
    """Mass, centre of mass and z inertia of a layout at zero angles, body by body."""
    items = [(lay.hub.mHub, lay.hub.r_BcB_B, lay.hub.IHubPntBc_B[2, 2])]
    for a in lay.appendages:
        R, origin = np.eye(3), np.zeros(3)  # parent frame (B first) in B axes
        for body in a.bodies:
            origin = origin + R @ body.r_SP_P
            R = R @ body.dcm_S0P.T
            items.append((body.mass, origin + R @ body.r_ScS_S, body.ISPntSc_S[2, 2]))
    mass = sum(m for m, _, _ in items)
    centre = sum(m * r for m, r, _ in items) / mass
    inertia = sum(J + m * float((r - centre)[:2] @ (r - centre)[:2]) for m, r, J in items)
    return mass, centre, inertia


@pytest.mark.parametrize("root", ["rigid", "hinged"])
def test_layout_keeps_mass_centre_of_mass_and_inertia(root):
    # Two chains on different mounts; the Basilisk layout (hub with folded bodies + spinning
    # bodies) must carry flexsat's total mass, centre of mass and inertia about it (sums of a
    # dozen terms of order 1..1e3: agreement to 1e-12 relative).
    left = tapered_chain(4, root)
    right = tapered_chain(3, "hinged")
    sc = Spacecraft(Hub(80.0, 40.0), [Mount(left, (0.4, 0.3), math.radians(20), name="left"),
                                      Mount(right, (-0.5, 0.1), math.radians(170), name="right")])
    lay = sb.layout(sc)
    mass, centre, inertia = _layout_mass_properties(lay)
    # mass: a sum of ~10 positive terms both ways, gamma_10 ~ 10 eps relative (rel 45 eps);
    # centre: sum m_i x_i / m, within ~gamma_10 max|x_i| ~ 10 eps x a few metres = 1e-14 m
    # of exact both ways; atol 1e-13 m
    assert mass == pytest.approx(sc.mass, rel=1e-14)
    np.testing.assert_allclose(centre[:2], sc.center_of_mass, rtol=0, atol=1e-13)
    assert inertia == pytest.approx(sc.inertia, rel=1e-12)
    assert lay.appendages[0].n_folded == (1 if root == "rigid" else 0)
    assert len(lay.appendages[0].bodies) == (3 if root == "rigid" else 4)


def test_layout_hinges_and_springs_follow_the_chain():
    chain = tapered_chain(4, "hinged")
    lay = sb.layout(winged(chain))
    bodies = lay.appendages[0].bodies
    np.testing.assert_array_equal([b.k for b in bodies], chain.hinge_stiffnesses)
    np.testing.assert_array_equal([b.c for b in bodies], chain.hinge_dampings)
    np.testing.assert_array_equal([b.r_ScS_S[0] for b in bodies], chain.com_offsets)
    # first hinge at the mount, the others one body length further along the parent's x axis
    np.testing.assert_array_equal(bodies[0].r_SP_P, [0.3, -0.2, 0.0])
    np.testing.assert_array_equal([b.r_SP_P[0] for b in bodies[1:]], chain.lengths[:-1])
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    np.testing.assert_allclose(bodies[0].dcm_S0P, [[c, s, 0], [-s, c, 0], [0, 0, 1]], atol=1e-16)


@pytest.mark.parametrize("root", ["rigid", "hinged"])
def test_tip_deflection_linearises_to_flexsats(root):
    # tip = sum l_i sin(beta_i); for angles ~1e-6 rad the cubic term is 1e-12 relative, so it
    # must match flexsat's tip row (sum l_i (theta_i - phi), absolute angles) to ~1e-12.
    chain = tapered_chain(5, root)
    appendage = sb.layout(winged(chain)).appendages[0]
    rng = np.random.default_rng(1)
    relative = 1e-6 * rng.standard_normal((4, len(appendage.bodies)))
    absolute = np.cumsum(relative, axis=1)  # body angles with the mount (hub) at 0
    rm = chain.root_model()
    q = np.zeros((4, rm.n))  # [delta, phi, spinning bodies' absolute angles], delta = phi = 0
    q[:, 2:] = absolute  # rigid root: theta_2..theta_n (phi = theta_1); hinged: theta_1..theta_n
    np.testing.assert_allclose(appendage.tip_deflection(relative), q @ rm.tip, rtol=1e-10)


def test_a_beam_needs_a_chain():
    beam = Beam(10.0, 100.0, 0.6)
    sc = Spacecraft(Hub(100.0, 50.0), [Mount(beam, (0.5, 0.0), 0.0, name="boom")])
    with pytest.raises(sb.BasiliskModelError, match=r"'boom' is a Beam.*fit_chain.*chains="):
        sb.layout(sc)
    lay = sb.layout(sc, chains={"boom": tapered_chain(3)})
    assert lay.spacecraft.mounts[0].appendage.n_bodies == 3
    with pytest.raises(sb.BasiliskModelError, match=r"\['tail'\] are not mounts"):
        sb.layout(sc, chains={"tail": tapered_chain(3)})


def test_a_point_mass_body_cannot_be_represented():
    chain = HingedChain([1.0, 1.0], [1.0, 1.0], [0.1, 0.0], [10.0], com_offsets=[0.5, 1.0])
    with pytest.raises(sb.BasiliskModelError, match=r"body 2 has inertia 0.0 \[kg\*m\^2\].*positive"):
        sb.layout(winged(chain))
    # the same zero inertia on a body folded into the hub is fine
    folded = HingedChain([1.0, 1.0], [1.0, 1.0], [0.0, 0.1], [10.0])
    assert len(sb.layout(winged(folded)).appendages[0].bodies) == 1


# -- the controller as a digital law (no Basilisk needed) -------------------------------------
def test_continuous_controller_is_discretised_exactly():
    sc = winged(tapered_chain(3))
    plant = sc.plant()
    continuous = controllers.pd(plant, natural_frequency=0.3, damping=0.7, roll_off=3.0)
    law = sb.flight_software_law(continuous, 0.05)
    reference = controllers.pd(plant, natural_frequency=0.3, damping=0.7, roll_off=3.0,
                               sample_time=0.05)
    # both are control.c2d(zoh) of the same system: identical to round-off
    for ours, theirs in zip((law.A, law.B, law.C, law.D),
                            (reference.A, reference.B, reference.C, reference.D)):
        np.testing.assert_allclose(ours, theirs, rtol=1e-13, atol=1e-15)
    assert law.controller.dt == 0.05 and law.inputs == ("theta_ref", "theta", "omega")


def test_controller_errors_name_what_and_why():
    sc = winged(tapered_chain(3))
    plant = sc.plant(tip_deflection=True)
    K = controllers.pd(plant, natural_frequency=0.3, damping=0.7)
    with pytest.raises(ValueError, match=r"continuous controller needs sample_time"):
        sb.flight_software_law(K)
    digital = controllers.pd(plant, natural_frequency=0.3, damping=0.7, sample_time=0.1)
    with pytest.raises(ValueError, match=r"must equal the digital controller's dt = 0.1"):
        sb.flight_software_law(digital, 0.05)
    tip_feedback = control.ss([], [], [], [[1.0, -2.0, -3.0]], 0,
                              inputs=["theta_ref", "theta", "wing_tip_deflection"],
                              outputs=["torque"])
    with pytest.raises(sb.BasiliskModelError, match=r"\['wing_tip_deflection'\] are not signals"):
        sb.flight_software_law(tip_feedback, 0.1)
    two_outputs = control.ss([], [], [], [[1.0], [2.0]], 0, inputs=["theta"],
                             outputs=["torque", "force"])
    with pytest.raises(sb.BasiliskModelError, match=r"single output 'torque'"):
        sb.flight_software_law(two_outputs, 0.1)


def test_dynamics_step_is_sized_from_the_highest_mode():
    # largest T/k with w dt <= 1/2, k dividing T = 1e8 ns in whole nanoseconds
    assert sb.dynamics_step(0.0, 0.1) == pytest.approx(0.1, rel=1e-15)
    assert sb.dynamics_step(187.36, 0.1) == pytest.approx(0.1 / 40, rel=1e-15)  # k=38 -> 40
    assert sb.dynamics_step(10.0, 0.1) == pytest.approx(0.1 / 2, rel=1e-15)
    assert sb.dynamics_step(50.0, 0.1, 0.01) == pytest.approx(0.01, rel=1e-15)
    with pytest.raises(ValueError, match=r"beyond RK4's stability limit.*2\.83"):
        sb.dynamics_step(500.0, 0.1, 0.01)
    with pytest.raises(ValueError, match=r"dt must divide"):
        sb.dynamics_step(5.0, 0.1, 0.03)
    with pytest.raises(ValueError, match=r"whole number of nanoseconds"):
        sb.dynamics_step(5.0, 1e-10)


def test_default_sample_time_gives_thirty_samples_per_crossover():
    sc = winged(tapered_chain(3))
    plant = sc.plant()
    K = controllers.pd(plant, natural_frequency=0.3, damping=0.7)
    T = sb.default_sample_time(plant, K)
    omega, L = controllers.loop_frequency_response(plant, K)
    crossover = float(omega[np.nonzero(np.abs(L) >= 1.0)[0][-1]])
    assert 2 * math.pi / T >= 30 * crossover
    assert 2 * math.pi / (2.5 * T) < 30 * crossover  # the next 1-2-5 step up would be too long
    digital = controllers.pd(plant, natural_frequency=0.3, damping=0.7, sample_time=0.1)
    assert sb.default_sample_time(plant, digital) == 0.1
    # a controller with dynamics (an estimator holding the chain's modes): its poles count
    # too, up to the band where the loop has gain (|L| >= LOOP_GAIN_FLOOR)
    lqr = controllers.lqr(plant, attitude_weight=1.0, rate_weight=1.0, torque_weight=1.0)
    omega, L = controllers.loop_frequency_response(plant, lqr)
    crossover = float(omega[np.nonzero(np.abs(L) >= 1.0)[0][-1]])
    acting = float(omega[np.nonzero(np.abs(L) >= sb.LOOP_GAIN_FLOOR)[0][-1]])
    poles = np.abs(np.linalg.eigvals(lqr.A))
    counted = max([crossover] + [p for p in poles if p <= acting])
    assert counted > crossover  # a pole sets it here
    assert poles.max() > acting  # and one where the loop has no gain does not
    T = sb.default_sample_time(plant, lqr)
    assert 2 * math.pi / T >= 30 * counted
    assert 2 * math.pi / (2.5 * T) < 30 * counted


# -- without Basilisk ---------------------------------------------------------------------------
def test_missing_basilisk_is_one_line_with_the_install_hint(monkeypatch):
    monkeypatch.setitem(sys.modules, "Basilisk", None)  # import Basilisk -> ImportError
    with pytest.raises(sb.BasiliskNotInstalled) as info:
        sb.require_basilisk()
    message = str(info.value)
    assert "\n" not in message and "pip install 'flexsat[basilisk]'" in message
    assert isinstance(info.value, ImportError)
    sc = winged(tapered_chain(3))
    with pytest.raises(sb.BasiliskNotInstalled):
        sb.simulate_slew(sc, digital_pd(sc), SMALL, SLEW_TIME)


def test_an_untested_bsk_version_warns(monkeypatch):
    import types

    import spacecraft.basilisk.install as install

    monkeypatch.setitem(sys.modules, "Basilisk", types.ModuleType("Basilisk"))
    monkeypatch.setattr(install.importlib.metadata, "version", lambda name: "2.11.0")
    with pytest.warns(sb.BasiliskVersionWarning, match=r"bsk 2.11.0 is outside the tested range"):
        assert sb.require_basilisk() == "2.11.0"
    monkeypatch.setattr(install.importlib.metadata, "version", lambda name: "2.12.4")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # inside the range: a warning would fail here
        assert sb.require_basilisk() == "2.12.4"


def test_compare_interpolates_a_reference_on_another_grid():
    # sin on a 0.01 s grid vs the same sin on a 0.1 s grid: linear interpolation error of the
    # fine reference at the coarse points is at most h^2/8 max|sin''| = 1.25e-5
    fine_t, coarse_t = np.arange(0, 1001) * 0.01, np.arange(0, 101) * 0.1
    reference = control.TimeResponseData(fine_t, np.sin(fine_t)[None], output_labels=["theta"],
                                         issiso=False)
    response = control.TimeResponseData(coarse_t, np.sin(coarse_t)[None] + 1e-3,
                                        output_labels=["theta"], issiso=False)
    d = sb.compare(response, reference)["theta"]
    assert d["peak"] == pytest.approx(1.0, abs=1e-4)
    assert d["peak_difference"] == pytest.approx(1e-3, abs=1.25e-5)


@pytest.mark.slow
def test_importing_flexsat_does_not_import_basilisk():
    code = ("import sys, spacecraft, spacecraft.basilisk; "
            "sys.exit(1 if 'Basilisk' in sys.modules else 0)")
    assert subprocess.run([sys.executable, "-c", code], cwd=str(_root())).returncode == 0


def _root():
    import pathlib
    return pathlib.Path(__file__).resolve().parents[3]


# -- Basilisk against flexsat's linear loop -----------------------------------------------------
@pytest.mark.slow
@needs_bsk
@pytest.mark.parametrize("n_bodies, root", [(3, "rigid"), (5, "rigid"), (10, "rigid"),
                                            (5, "hinged")])
def test_small_slew_agrees_with_the_linear_loop(n_bodies, root):
    sc = winged(tapered_chain(n_bodies, root))
    relative, result = relative_differences(sc, digital_pd(sc), SMALL)
    assert relative["theta"] <= 1e-4 and relative["wing_tip_deflection"] <= 1e-4
    assert relative["torque"] <= 1e-4 and relative["omega"] <= 1e-4
    assert result.out_of_plane == 0.0  # planar motion stays planar
    assert result.highest_frequency * result.dt <= sb.simulation.DEFAULT_STEP_FACTOR


@pytest.mark.slow
@needs_bsk
def test_the_remaining_difference_is_second_order_in_the_amplitude():
    # A wrong convention (sign, angle, offset) would leave a relative difference independent of
    # the amplitude; the physics the linear model drops (centrifugal loads, ~ rate^2) gives one
    # proportional to it. Halving the angle must halve the relative tip difference (to a few
    # percent: the RK4 part, < 1e-7, does not scale).
    sc = winged(tapered_chain(5))
    K = digital_pd(sc)
    full, _ = relative_differences(sc, K, SMALL)
    half, _ = relative_differences(sc, K, SMALL / 2)
    assert full["wing_tip_deflection"] / half["wing_tip_deflection"] == pytest.approx(2.0, rel=0.02)
    # mounted on the centre of mass's axis, the mirror symmetry y -> -y makes the response odd
    # in the amplitude: no second-order term, the difference drops by orders of magnitude
    radial = winged(tapered_chain(5), position=(0.5, 0.0), direction=0.0)
    on_axis, _ = relative_differences(radial, digital_pd(radial), SMALL)
    assert on_axis["wing_tip_deflection"] < 1e-6


@pytest.mark.slow
@needs_bsk
def test_two_chains_and_controller_kinds():
    # a rigid-root and a hinged-root chain on one hub; a continuous PD with roll-off run at the
    # flight-software rate, and a digital LQR (an estimator with states)
    left, right = tapered_chain(4), tapered_chain(3, "hinged")
    sc = Spacecraft(Hub(80.0, 40.0), [Mount(left, (0.4, 0.3), math.radians(20), name="left"),
                                      Mount(right, (-0.5, 0.1), math.radians(170), name="right")])
    plant = sc.plant(tip_deflection=True)
    pd = controllers.pd(plant, natural_frequency=0.3, damping=0.7, roll_off=3.0)
    relative, _ = relative_differences(sc, pd, SMALL, sample_time=0.05)
    assert max(relative.values()) <= 1e-4
    lqr = controllers.lqr(plant, attitude_weight=1.0, rate_weight=1.0, torque_weight=1.0,
                          sample_time=0.1)
    relative, _ = relative_differences(sc, lqr, SMALL)
    assert max(relative.values()) <= 1e-4


@needs_bsk
@pytest.mark.slow
def test_slew_comparison_against_a_beam_truth():
    # The three differences of one call are consistent: per signal, |Basilisk - truth| <=
    # |Basilisk - chain| + |chain - truth| (triangle inequality of the peaks, with round-off
    # 1e-15 of the peak), and Basilisk - truth is the chain's cost to within the (tiny)
    # nonlinearity.
    beam = Beam(10.0, 100.0, 0.6, damping_ratio=0.005)
    sc = winged(tapered_chain(5))
    truth = Spacecraft(Hub(100.0, 50.0), [Mount(beam.truncated(6), (0.3, -0.2), math.radians(30),
                                                name="wing")]).plant(tip_deflection=True)
    K = digital_pd(sc)
    c = sb.slew_comparison(sc, K, SMALL, SLEW_TIME, duration=DURATION, truth_plant=truth)
    d = c.differences
    assert set(d) == {"basilisk_vs_chain", "basilisk_vs_truth", "chain_vs_truth"}
    for name in ("theta", "omega", "wing_tip_deflection", "torque"):
        total = d["basilisk_vs_truth"][name]["peak_difference"]
        assert total <= (d["basilisk_vs_chain"][name]["peak_difference"]
                         + d["chain_vs_truth"][name]["peak_difference"]) * (1 + 1e-12)
        assert d["basilisk_vs_truth"][name]["relative"] == pytest.approx(
            d["chain_vs_truth"][name]["relative"], abs=1e-4)
    np.testing.assert_array_equal(c.truth.time, c.basilisk.response.time)


@needs_bsk
@pytest.mark.slow
def test_disturbances_are_held_as_in_the_sampled_loop():
    sc = winged(tapered_chain(3))
    # pulses of the size of the slew's own torque (7e-3 N*m peak at 0.1 deg): the terms the
    # linear model drops stay second order
    pulse = {"disturbance_torque": lambda t: np.where((t >= 5.0) & (t < 7.0), 1e-3, 0.0),
             "force_y": lambda t: np.where(t >= 12.0, -2e-4, 0.0)}
    plant = sc.plant(tip_deflection=True, disturbances=True)
    # the force inputs bring the free translation of the whole spacecraft into the plant: rigid
    # motion no torque reaches, which pd leaves out of its guarantee and says so
    with pytest.warns(controllers.RemovedModesWarning, match=r"rigid-body motion, 4 states"):
        K = controllers.pd(plant, natural_frequency=0.3, damping=0.7, sample_time=SAMPLE_TIME)
    relative, _ = relative_differences(sc, K, SMALL, disturbances=pulse)
    assert max(relative.values()) <= 1e-4
    with pytest.raises(sb.BasiliskModelError, match=r"'wing_tip_force' is not applied"):
        sb.simulate_slew(sc, K, SMALL, SLEW_TIME, disturbances={"wing_tip_force": np.zeros})


@needs_bsk
@pytest.mark.slow
def test_rigid_spacecraft_slews_past_180_degrees_exactly():
    # A one-body chain on a rigid root is folded into the hub: a rigid body, whose planar
    # rotation J theta'' = torque is linear at any angle. Basilisk's MRPs switch to the shadow
    # set at 180 deg; the flight software unwraps theta. The only error left is RK4's on the
    # nonlinear MRP kinematics sigma' = (1 + sigma^2) omega / 4: fourth order in dt, so ten
    # times smaller steps must shrink it by >= 1000 (theory 1e4).
    rigid = HingedChain([2.0], [3.0], [1.0], [])
    sc = winged(rigid)
    K = digital_pd(sc)
    coarse, result = relative_differences(sc, K, math.radians(270.0))
    fine, _ = relative_differences(sc, K, math.radians(270.0), dt=SAMPLE_TIME / 10)
    assert result.dt == SAMPLE_TIME  # no elastic mode: one RK4 step per sample
    assert fine["theta"] < coarse["theta"] / 1000 and fine["torque"] < coarse["torque"] / 1000
    assert coarse["theta"] < 1e-8 and coarse["torque"] < 1e-8
    assert np.max(result.response.outputs[0]) > math.radians(260.0)  # well past 180 deg


@pytest.mark.slow
@needs_bsk
def test_large_slew_documents_the_nonlinear_difference():
    # 10 deg: the linear model drops terms second order in the amplitude (centrifugal loads),
    # so the relative difference grows in proportion to the angle: 100 x the 0.1 deg figure,
    # about 5e-3 of the peak tip deflection for this mount (benchmarks/results for the paper's
    # rod). It is physics, not integration error: halving dt leaves it unchanged.
    sc = winged(tapered_chain(5))
    K = digital_pd(sc)
    large, result = relative_differences(sc, K, math.radians(10.0))
    small, _ = relative_differences(sc, K, SMALL)
    assert large["wing_tip_deflection"] / small["wing_tip_deflection"] == pytest.approx(100.0, rel=0.05)
    finer, _ = relative_differences(sc, K, math.radians(10.0), dt=result.dt / 2)
    assert finer["wing_tip_deflection"] == pytest.approx(large["wing_tip_deflection"], rel=1e-3)


@needs_bsk
@pytest.mark.parametrize("spin_inertia", [1e-9, 1e-8, 0.05, 1e3])
def test_reaction_wheel_applies_the_commanded_torque(spin_inertia):
    # A balanced wheel about z gives the hub exactly the commanded torque (its gyroscopic term
    # vanishes for planar motion): the same loop as the external torque; the wheel's state does
    # not feed back into the hub's, so RK4 gives the same hub trajectory up to round-off
    # (1e-15 of the peaks measured; 1e-12 allows for ~1e4 steps). Its absolute momentum J_s (Omega + omega) is minus
    # the impulse the hub received, sum of torque_j T over the held samples: a linear equation
    # with a constant derivative on each step, which RK4 integrates to round-off.
    # Whatever the wheel: 1e-9 and 1e-8 kg*m^2 reach Basilisk's default wheel-acceleration guard
    # (1e6 rad/s^2, where it used to clip the torque: 47 % off in theta); 1e3 kg*m^2, above the
    # hub's 50, made the hub's tensor plus J_s about z no body's, which Basilisk refused.
    sc = winged(tapered_chain(3))
    K = digital_pd(sc)
    wheel = sb.ReactionWheel(spin_inertia=spin_inertia)
    external = sb.simulate_slew(sc, K, SMALL, SLEW_TIME, duration=DURATION)
    wheeled = sb.simulate_slew(sc, K, SMALL, SLEW_TIME, duration=DURATION, reaction_wheel=wheel)
    differences = sb.compare(wheeled.response, external.response)
    assert max(d["relative"] for d in differences.values()) <= 1e-12
    y = dict(zip(wheeled.response.output_labels, np.asarray(wheeled.response.outputs)))
    momentum = wheel.spin_inertia * (y["wheel_speed"] + y["omega"])
    impulse = np.concatenate([[0.0], np.cumsum(y["torque"][:-1]) * SAMPLE_TIME])
    np.testing.assert_allclose(momentum, -impulse, rtol=0, atol=1e-12 * np.max(np.abs(impulse)))
    with pytest.raises(ValueError, match=r"spin_inertia must be positive and finite \[kg\*m\^2\]"):
        sb.ReactionWheel(spin_inertia=-1.0)


# -- conservation ---------------------------------------------------------------------------------
@pytest.mark.slow
@needs_bsk
def test_energy_and_momentum_are_conserved_to_rk4_accuracy():
    # No control, no damping: a spinning chain vibrating in all its modes (initial hinge angles)
    # conserves energy and angular momentum; Basilisk's own totals must drift only by RK4's
    # error. RK4's amplitude error on a mode is (w dt)^6 / 144 per step, so the energy drift over
    # N steps is at most N (w_max dt)^6 / 144 (all the energy in the top mode), O(dt^5): halving
    # dt must cut it by >= 16 (theory 32; measured 32 for energy, 24 for momentum).
    chain = tapered_chain(5, "hinged")
    undamped = HingedChain(chain.lengths, chain.masses, chain.inertias, chain.hinge_stiffnesses,
                           com_offsets=chain.com_offsets, root="hinged")
    sc = winged(undamped)
    duration = 20.0

    def drift(k):
        result = sb.simulate(sc, duration=duration, sample_time=0.1, dt=0.1 / k,
                             initial_rate=0.05,
                             initial_angles={"wing": [0.05, -0.03, 0.02, 0.0, 0.01]},
                             conservation=True)
        c = result.conservation
        E, H = c["rotational_energy"], c["angular_momentum"]
        return (float(np.max(np.abs(E - E[0]))) / E[0],
                float(np.max(np.linalg.norm(H - H[0], axis=1))) / np.linalg.norm(H[0]),
                result)

    energy, momentum, _ = drift(16)
    energy_half, momentum_half, result = drift(32)
    assert energy_half < energy / 16 and momentum_half < momentum / 16
    y = result.highest_frequency * result.dt
    assert energy_half < duration / result.dt * y**6 / 144
    E_orbit = result.conservation["orbital_energy"]  # translation of the centre of mass
    assert np.max(np.abs(E_orbit - E_orbit[0])) <= 1e-12 * result.conservation["rotational_energy"][0]


@needs_bsk
def test_a_run_too_long_is_refused_before_it_starts():
    # 40 bodies (39 spinning, the first folded): w_max ~ 3.7e3 rad/s, dt ~ 1.3e-4 s, 1.6e6 RK4
    # steps of O(39^3): hours
    sc = winged(tapered_chain(40))
    pd = control.ss([], [], [], [[1.0, -1.0, -10.0]], 0.01, inputs=["theta_ref", "theta", "omega"],
                    outputs=["torque"])
    with pytest.raises(sb.BasiliskModelError, match=r"would take about .* s \(39 spinning bodies"):
        sb.simulate_slew(sc, pd, SMALL, 60.0, duration=200.0)


@needs_bsk
def test_a_diverging_run_is_an_error_not_nan():
    # positive feedback torque = -1e6 (theta_ref - theta) grows like exp(sqrt(1e6 / J) t),
    # J ~ 300 kg*m^2: past 1e308 within a few seconds
    sc = winged(tapered_chain(3))
    unstable = control.ss([], [], [], [[-1e6, 1e6, 0.0]], SAMPLE_TIME,
                          inputs=["theta_ref", "theta", "omega"], outputs=["torque"])
    with pytest.raises(sb.BasiliskIntegrationError, match=r"non-finite states at t = "):
        sb.simulate_slew(sc, unstable, SMALL, SLEW_TIME, duration=DURATION)


@needs_bsk
def test_a_diverging_step_is_refused_before_the_run():
    sc = winged(tapered_chain(10))
    w_max = float(sc.modes()[0].max())
    with pytest.raises(ValueError, match=r"beyond RK4's stability limit"):
        sb.simulate_slew(sc, digital_pd(sc), SMALL, SLEW_TIME, dt=SAMPLE_TIME / 2)
    assert w_max * SAMPLE_TIME / 2 > sb.simulation.RK4_STABILITY_LIMIT


# -- a scene's Basilisk keys: checked by name against what the comparison and RK4 need ----------
def hinged_wing(**simulator):
    """The embedded hinged_wing scene (3-body design chain) run in Basilisk, with
    ``simulator`` keys and no plots."""
    import tomllib

    from spacecraft.scene.read import scene_path

    with open(scene_path("hinged_wing"), "rb") as stream:
        data = tomllib.load(stream)
    data["report"] = {"plots": False}
    data["simulator"] = {"name": "basilisk", **simulator}
    return data


@needs_bsk
def test_a_flight_software_rate_too_slow_for_the_loop_is_refused_by_key():
    """0.01 Hz on a loop crossing over at 0.23 rad/s: Basilisk ran it on 2 samples and reported
    "differs by 0". The sampled loop's rule (2 pi / T >= 10 crossovers) names the key."""
    from spacecraft import SceneError, run

    with pytest.raises(SceneError, match=r"simulator\.sample_rate: 0\.01 Hz \(sample time 100 s\) "
                                         r"cannot run the pd loop as flight software: .*"
                                         r"sample_time <= 2\.7\d* s"):
        run(hinged_wing(sample_rate=0.01))
    # fast enough for the loop, too few samples to compare: 30 s at 0.5 Hz is 16
    data = hinged_wing(sample_rate=0.5)
    data["manoeuvre"]["duration"] = 30.0
    with pytest.raises(SceneError, match=r"simulator\.sample_rate: the Basilisk run would be "
                                         r"compared on 16 flight-software samples.*at least 20"):
        run(data)


@needs_bsk
def test_a_step_that_does_not_divide_the_default_sample_time_is_refused_by_key():
    """The default flight-software rate is only known once the loop is designed: the step is
    checked then, naming simulator.dt and the nearest steps that divide it (was exit 1, a
    ValueError)."""
    from spacecraft import SceneError, run

    with pytest.raises(SceneError, match=r"simulator\.dt: dt must divide the flight-software "
                                         r"sample time 0\.02 s .*got 0\.003 .*the nearest that "
                                         r"do: 0\.0025 or 0\.004 \(sample time from flexsat's "
                                         r"default"):
        run(hinged_wing(dt=0.003))


def test_a_step_that_does_not_divide_the_given_rate_is_refused_when_read():
    from spacecraft import SceneError, load_scene

    with pytest.raises(SceneError, match=r"simulator\.dt: must divide the flight-software sample "
                                         r"time 1/sample_rate = 0\.1 s .*got 0\.003 "
                                         r"\(T / dt = 33\.3333\)"):
        load_scene(hinged_wing(sample_rate=10.0, dt=0.003))
    data = hinged_wing(sample_rate=10.0)
    data["controller"]["sample_rate"] = 20.0
    del data["manoeuvre"]["step"]
    with pytest.raises(SceneError, match=r"simulator\.sample_rate: must equal "
                                         r"controller\.sample_rate = 20 Hz.*got 10 Hz"):
        load_scene(data)


@needs_bsk
def test_a_basilisk_run_over_its_time_limit_names_the_limit():
    """Was "raise max_seconds", neither a scene key nor a --limit."""
    from spacecraft import SceneError, run

    data = hinged_wing()
    data["limits"] = {"basilisk_seconds": 1}
    with pytest.raises(SceneError, match=r"simulator\.name: the Basilisk run would take about "
                                         r".* s \(3 spinning bodies.*over the limit 1 s "
                                         r"\(limits\.basilisk_seconds.*--limit "
                                         r"basilisk_seconds=N") as refused:
        run(data)
    # without simulator.dt, the longest step RK4 keeps stable is offered: the longest T/k
    # (whole nanoseconds) with w_max dt <= 2 sqrt(2)
    w_max = float(re.search(r"highest mode ([\d.e+]+) rad/s", str(refused.value)).group(1))
    longest = float(re.search(r"simulator\.dt up to ([\d.e+-]+) s", str(refused.value)).group(1))
    # (w_max printed to 4 significant digits: 5e-4 at worst)
    assert 2.0 * math.sqrt(2.0) / 4 < w_max * longest <= 2.0 * math.sqrt(2.0) * (1 + 5e-4)


def test_the_summary_names_the_truth_model_it_compares_with():
    """hinged_wing's truth is a 20-body chain, not "the distributed beam"."""
    from spacecraft import load_scene
    from spacecraft.design.simulators import summary, truth_label

    assert truth_label(load_scene("hinged_wing")) == "the 20-body truth chain"
    assert truth_label(load_scene("single_boom")) == "the distributed beam (truth)"
    differences = {name: {"theta": {"peak": 1.0, "peak_difference": 0.5, "relative": 0.5}}
                   for name in ("basilisk_vs_truth", "basilisk_vs_chain")}
    said = summary(differences, truth_label(load_scene("hinged_wing")))
    assert "theta [rad] differs from the 20-body truth chain by 0.5" in said
    assert "beam" not in said


def test_a_difference_above_the_references_peak_is_given_beside_that_peak():
    """A signal that the reference barely has (a tip twist of 1e-9 rad on the linear chain in
    a slew about the bending axes, 6e-5 rad in Basilisk from its nonlinear kinematics) is
    reported with the reference's peak, not as millions of per cent of it; a difference below
    the peak keeps its share; a reference at exactly 0 is named so too."""
    from spacecraft.design.simulators import peak_difference_text, summary

    twist = {"peak": 1.0e-9, "peak_difference": 6.0e-5, "relative": 6.0e4}
    assert peak_difference_text(twist) == "6e-05 (above its peak there, 1e-09)"
    assert peak_difference_text({"peak": 0.0, "peak_difference": 2e-6, "relative": None}) == \
        "2e-06 (above its peak there, 0)"
    assert peak_difference_text({"peak": 2.0, "peak_difference": 0.5, "relative": 0.25}) == \
        "0.5 (25 % of its peak)"
    assert peak_difference_text(None) == "n/a"
    assert peak_difference_text(twist, short=True) == "6e-05 (peak 1e-09)"
    assert peak_difference_text({"peak": 2.0, "peak_difference": 0.5, "relative": 0.25},
                                short=True) == "0.5 (25 %)"
    said = summary({"basilisk_vs_chain": {"wing_tip_twist": twist}})
    assert "wing_tip_twist [rad] differs from the distributed beam (truth) by n/a and from " \
           "the linear chain by 6e-05 (above its peak there, 1e-09)" in said
    assert "%" not in said


@pytest.mark.slow
@needs_bsk
def test_a_wheel_no_motor_could_spin_is_warned_about_by_key():
    """1e-8 kg m^2: Basilisk now follows flexsat (its wheel-acceleration guard is lifted), and
    the wheel's 1e7 rad/s is named as no real wheel's."""
    from spacecraft import run

    result = run(hinged_wing(reaction_wheel={"spin_inertia": 1e-8}))
    assert result.data["basilisk"]["pd"]["differences"]["basilisk_vs_chain"]["theta"][
        "relative"] < 1e-7
    said = " ".join(result.data["warnings"])
    assert "simulator.reaction_wheel.spin_inertia = 1e-08 kg m^2 spins the wheel up to" in said
    clean = run(hinged_wing(reaction_wheel={"spin_inertia": 0.1}))
    assert not [w for w in clean.data["warnings"] if "spin_inertia" in w]


@pytest.mark.slow
@needs_bsk
def test_basilisks_wheel_is_reported_in_the_words_of_flexsats(tmp_path):
    """A wheel of half the slew's peak torque: results.json says in words that it saturated,
    the Basilisk summary says its limits, not the chain's nonlinearity, make the difference, a
    design warning names it, and the wheel plot draws it (the torque it applies, within its
    limit)."""
    from spacecraft import run
    from spacecraft.report.write import write_report

    free = run(hinged_wing(reaction_wheel={"spin_inertia": 0.1}))
    entry = free.data["basilisk"]["pd"]["wheel"]
    assert entry["words"].startswith("no wheel reached a limit")
    limit = 0.5 * entry["peak_torque"]["wheel"]
    data = hinged_wing(reaction_wheel={"spin_inertia": 0.1, "max_torque": limit})
    data["report"] = {"plots": ["wheels"]}
    result = run(data)
    entry = result.data["basilisk"]["pd"]
    assert entry["wheel"]["saturated"] and entry["wheel"]["time_torque_saturated"]["wheel"] > 0
    assert entry["wheel"]["peak_torque"]["wheel"] == pytest.approx(limit, rel=1e-12)
    assert "the wheels SATURATED from t = " in entry["wheel"]["words"]
    assert "not the chain's nonlinearity" in entry["summary"]
    assert any(w["code"] == "wheel_saturation" for w in result.data["design_warnings"])
    write_report(result, tmp_path)
    assert "Basilisk's reaction wheel: the wheels SATURATED" in (tmp_path / "report.md").read_text()
    assert (tmp_path / "plots" / "wheels.png").stat().st_size > 10_000


@pytest.mark.slow
@needs_bsk
def test_every_controller_flies_the_scenes_wheel():
    """With PD and LQR and a reaction wheel, the second controller was handed the first's wheel
    summary in place of the wheel (a TypeError from inside the run)."""
    from spacecraft import run

    data = hinged_wing(reaction_wheel={"spin_inertia": 0.1})
    data["controller"]["types"] = ["pd", "lqr"]
    data["controller"]["lqr"] = {"attitude_weight": 1.0, "rate_weight": 10.0,
                                 "torque_weight": 1.0}
    result = run(data)
    for kind in ("pd", "lqr"):
        entry = result.data["basilisk"][kind]
        assert entry["wheel"]["words"].startswith("no wheel reached a limit"), kind
        assert entry["differences"]["basilisk_vs_chain"]["theta"]["relative"] < 1e-4, kind
