"""The Basilisk adapter in three axes: 3-D chains as spinning bodies, three-axis flight software.

What the comparisons can expect (their tolerances)
    Basilisk's model linearised about rest (:func:`spacecraft.basilisk.linearised`, central
    differences of its own equations of motion with steps of 1e-6) is flexsat's linear chain
    spacecraft exactly: its eigenvalues agree to the differences' truncation (1e-12 relative)
    times the eigenvalues' conditioning; measured 1e-12, asserted 1e-9.

    A slew in Basilisk differs from flexsat's sampled-data loop by RK4's error (below 1e-7 of
    the peaks at the default step, as in tests/spacecraft/basilisk/test_basilisk.py) and by the terms the linear
    model drops, second order in the amplitude. In three axes they include the gyroscopic
    torque omega x J omega of a slew about a non-principal axis and the centrifugal loads of
    chains mounted off every axis: relative to the first-order response they are the slew
    angle [rad] times factors of order one (measured at most 0.84 x the angle, 1.5e-3 of the
    peak tip deflection at 0.1 deg). Hence the bound "relative difference <= angle in rad" at
    0.1 deg, and the proof that what remains is second order: halving the angle halves every
    relative difference (measured 2.000 to 2.001; a convention error would leave it constant).
"""

from __future__ import annotations

import math
import warnings

import control
import numpy as np
import pytest

import controllers
from appendages import Beam, fit_chain_3d
from appendages.chain import HingedChain
from appendages.fit3d import rod_chain_frequencies
from spacecraft import Hub, Mount, Spacecraft
from spacecraft import basilisk as sb
from spacecraft.dynamics.kinematics import euler_orientation, orientation_from_axis

from scenes import soft_three_axis_scene

# runs Basilisk: skipped with the install hint where bsk is not installed (tests/conftest.py)
needs_bsk = pytest.mark.basilisk

SLEW_TIME = 20.0        # s
DURATION = 40.0         # s
SMALL = math.radians(0.1)
SAMPLE_TIME = 0.1       # s
AXIS = (1.0, 1.0, 0.5)  # a non-principal eigen-axis, hub axes
HUB = Hub(100.0, [[50.0, 2.0, -1.0], [2.0, 40.0, 3.0], [-1.0, 3.0, 30.0]])


def tapered_chain_3d(n_bodies: int, root: str = "rigid", *, torsion: bool = True,
                     axial: bool = False) -> HingedChain:
    """A 10 m, 6 kg three-axis chain whose bodies and motions all differ.

    The bending in the x-y plane is tests/spacecraft/basilisk/test_basilisk.py's tapered chain; the x-z plane has
    inertias 1.2 times and hinges 1.7 times those, torsion inertias 0.25 J_z + 0.02 m (enough
    for every body's moments to obey the triangle inequality) and springs 0.3 times the
    bending ones; dampers proportional to each spring (0.002, 0.003, 0.001 s). Optionally
    axial springs (1e4 N/m per metre of spacing), which Basilisk cannot represent.
    """
    w = np.linspace(1.4, 0.6, n_bodies)
    lengths = 10.0 * w / w.sum()
    masses = 6.0 * w * lengths / np.sum(w * lengths)
    inertias = masses * lengths**2 / 12.0 * (1.0 + 0.3 * np.arange(n_bodies) / n_bodies)
    offsets = lengths * (0.5 - 0.1 * w)
    k = 100.0 / (0.5 * (lengths[:-1] + lengths[1:]))
    if root == "hinged":
        k = np.concatenate([[200.0 / lengths[0]], k])
    extra = {}
    if torsion:
        extra.update(torsion_stiffnesses=0.3 * k, torsion_dampings=0.0003 * k)
    if axial:
        extra.update(axial_stiffnesses=1e4 * np.ones(k.size))
    return HingedChain(lengths, masses, inertias, k, hinge_dampings=0.002 * k,
                       com_offsets=offsets, root=root, inertias_y=1.2 * inertias,
                       hinge_stiffnesses_y=1.7 * k, hinge_dampings_y=0.0034 * k,
                       torsional_inertias=0.25 * inertias + 0.02 * masses, **extra)


def craft(wing: HingedChain | None = None, boom: HingedChain | None = None) -> Spacecraft:
    """HUB with a rigid-root 'wing' along (1, 0.5, -0.3) and a hinged-root 'boom' turned by
    Euler angles (160, 10, 30) deg, both mounted off the hub's centre of mass and axes."""
    wing = tapered_chain_3d(3) if wing is None else wing
    boom = tapered_chain_3d(3, "hinged") if boom is None else boom
    return Spacecraft(HUB, [
        Mount(wing, (0.3, -0.2, 0.1), orientation=orientation_from_axis([1.0, 0.5, -0.3]),
              name="wing"),
        Mount(boom, (-0.4, 0.1, 0.2),
              orientation=euler_orientation("ZYX", np.radians([160.0, 10.0, 30.0])),
              name="boom")])


def digital_pd(spacecraft, sample_time=SAMPLE_TIME):
    return controllers.pd(spacecraft.plant(prune=True), natural_frequency=0.3, damping=0.7,
                          sample_time=sample_time)


def relative_differences(spacecraft, controller, angle, **kwargs):
    """{signal: max |Basilisk - flexsat linear| / max |flexsat linear|} for one slew."""
    result = sb.simulate_slew(spacecraft, controller, angle, SLEW_TIME, duration=DURATION,
                              axis=AXIS, **kwargs)
    linear = sb.linear_slew(spacecraft, controller, angle, SLEW_TIME, duration=DURATION,
                            sample_time=kwargs.get("sample_time"), axis=AXIS,
                            disturbances=kwargs.get("disturbances"))
    return {k: v["relative"] for k, v in sb.compare(result.response, linear).items()}, result


# -- the layout: flexsat -> Basilisk parameters (no Basilisk needed) ----------------------------
def _frames(appendage):
    """(hinge position, axes) of each spinning body at zero angles, hub axes."""
    R, origin, out = np.eye(3), np.zeros(3), []
    for body in appendage.bodies:
        origin = origin + R @ body.r_SP_P
        R = R @ body.dcm_S0P.T
        out.append((origin, R))
    return out


def _layout_mass_properties(lay):
    """Mass, centre of mass and inertia tensor of a layout at zero angles, body by body."""
    items = [(lay.hub.mHub, lay.hub.r_BcB_B, lay.hub.IHubPntBc_B)]
    for a in lay.appendages:
        for body, (origin, R) in zip(a.bodies, _frames(a)):
            items.append((body.mass, origin + R @ body.r_ScS_S, R @ body.ISPntSc_S @ R.T))
    mass = sum(m for m, _, _ in items)
    centre = sum(m * r for m, r, _ in items) / mass
    inertia = sum(J + m * (float((r - centre) @ (r - centre)) * np.eye(3)
                           - np.outer(r - centre, r - centre)) for m, r, J in items)
    return mass, centre, inertia


@pytest.mark.parametrize("root", ["rigid", "hinged"])
def test_layout_keeps_mass_centre_of_mass_and_inertia_tensor(root):
    # sums of a few dozen terms of order 1..1e3 both ways: 1e-12 relative (the planar test's)
    sc = craft(tapered_chain_3d(4, root))
    lay = sb.layout(sc)
    mass, centre, inertia = _layout_mass_properties(lay)
    assert mass == pytest.approx(sc.mass, rel=1e-14)
    np.testing.assert_allclose(centre, sc.center_of_mass, rtol=0, atol=1e-13)
    np.testing.assert_allclose(inertia, sc.inertia, rtol=0, atol=1e-12 * np.abs(sc.inertia).max())
    assert lay.three_axis and lay.appendages[0].n_folded == (1 if root == "rigid" else 0)


def test_each_joint_is_two_bending_hinges_and_a_torsion_hinge():
    chain = tapered_chain_3d(4, "hinged")
    sc = craft(boom=chain)
    boom = sb.layout(sc).appendages[1]
    bodies = boom.bodies
    assert len(bodies) == 3 * 4
    assert [b.spin_axis for b in bodies] == ["z", "y", "x"] * 4
    z, y, x = bodies[0::3], bodies[1::3], bodies[2::3]
    np.testing.assert_array_equal([b.k for b in z], chain.hinge_stiffnesses)
    np.testing.assert_array_equal([b.c for b in z], chain.hinge_dampings)
    np.testing.assert_array_equal([b.k for b in y], chain.hinge_stiffnesses_y)
    np.testing.assert_array_equal([b.c for b in y], chain.hinge_dampings_y)
    np.testing.assert_array_equal([b.k for b in x], chain.torsion_stiffnesses)
    np.testing.assert_array_equal([b.c for b in x], chain.torsion_dampings)
    # the body rides on the joint's last spinning body; the other two are massless
    assert all(b.mass == 0.0 and not np.any(b.ISPntSc_S) for b in z + y)
    np.testing.assert_array_equal([b.mass for b in x], chain.masses)
    for b, Jx, Jy, Jz in zip(x, chain.torsional_inertias, chain.inertias_y, chain.inertias):
        np.testing.assert_array_equal(b.ISPntSc_S, np.diag([Jx, Jy, Jz]))
    np.testing.assert_array_equal([b.r_ScS_S[0] for b in x], chain.com_offsets)
    # the first hinge at the mount, turned into the mount's axes; the joints' other bodies at
    # their joint; the next joint one body length along the body
    mount = sc.mounts[1]
    np.testing.assert_array_equal(bodies[0].r_SP_P, mount.point)
    np.testing.assert_array_equal(bodies[0].dcm_S0P, mount.orientation.T)
    assert all(not np.any(b.r_SP_P) for b in y + x)
    np.testing.assert_array_equal([b.r_SP_P[0] for b in z[1:]], chain.lengths[:-1])
    # torsionally rigid: two spinning bodies a joint, the body on the second
    rigid = sb.layout(craft(boom=tapered_chain_3d(4, "hinged", torsion=False))).appendages[1]
    assert [b.spin_axis for b in rigid.bodies] == ["z", "y"] * 4
    np.testing.assert_array_equal([b.mass for b in rigid.bodies[1::2]], chain.masses)


@pytest.mark.parametrize("root", ["rigid", "hinged"])
def test_tip_motions_linearise_to_flexsats(root):
    # The exact tip motions of angles ~1e-6 rad are flexsat's tip rows (on the absolute angles
    # of each motion: sums of the joints' relative angles; the x-z plane's dw/dx is -theta_y)
    # plus second-order terms, angle**2 / angle = 1e-6 of the first-order ones: 1e-5 relative.
    chain = tapered_chain_3d(4, root)
    appendage = sb.layout(craft(wing=chain)).appendages[0]
    rng = np.random.default_rng(1)
    relative = 1e-6 * rng.standard_normal((5, len(appendage.bodies)))
    rm = chain.root_model(6)
    q = np.zeros((5, rm.n))  # root motions 0: the hub at rest
    names = rm.coordinate_names
    for motion, sign, column in (("xy", 1.0, 0), ("xz", -1.0, 1), ("torsion", 1.0, 2)):
        absolute = sign * np.cumsum(relative[:, column::3], axis=1)
        internal = [k for k, n in enumerate(names) if n.startswith(f"{motion}.")]
        # xy/xz: rigid root theta_2..theta_n (theta_1 is the root's), hinged theta_1..theta_n
        # after the massless mount's delta, phi; torsion: the bodies that move on their own
        q[:, internal] = absolute[:, -len(internal):]
    expected = q @ rm.tip.T
    got = appendage.tip_motions(relative)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-5 * np.abs(expected).max())


def test_axial_springs_are_held_rigid_and_said_so():
    chain = tapered_chain_3d(3, axial=True)
    lay = sb.layout(craft(wing=chain))
    wing = lay.appendages[0]
    assert wing.held == ("axial",) and lay.appendages[1].held == ()
    # the dropped mode: the spring chain's first frequency with body 1 (the root) held
    _, clamped = rod_chain_frequencies(chain.masses, chain.axial_stiffnesses)
    assert wing.axial_frequency == pytest.approx(clamped, rel=1e-12)
    # Basilisk's chain and flexsat's comparison model: the same chain, inextensible
    modelled = lay.spacecraft.mounts[0].appendage
    assert modelled.axial_stiffnesses is None and wing.chain is modelled
    for name in ("lengths", "masses", "inertias", "inertias_y", "torsional_inertias",
                 "hinge_stiffnesses", "hinge_stiffnesses_y", "torsion_stiffnesses",
                 "hinge_dampings", "com_offsets"):
        np.testing.assert_array_equal(getattr(modelled, name), getattr(chain, name))
    assert sb.inextensible(modelled) is modelled


def test_moments_no_body_has_are_raised_on_the_stiffer_motion_and_said_so():
    chain = tapered_chain_3d(3)
    # J_x = 3 J_z > J_y + J_z = 2.2 J_z: a beam's torsional inertia without rotary inertia in
    # bending; the joints' x-z springs per inertia (1.7 k / 1.2 J) beat the x-y ones (k / J)
    Jx = 3.0 * chain.inertias
    wide = HingedChain(chain.lengths, chain.masses, chain.inertias, chain.hinge_stiffnesses,
                       com_offsets=chain.com_offsets, inertias_y=chain.inertias_y,
                       hinge_stiffnesses_y=chain.hinge_stiffnesses_y, torsional_inertias=Jx,
                       torsion_stiffnesses=chain.torsion_stiffnesses)
    with pytest.warns(sb.BasiliskModelWarning, match=r"chain 'wing': Basilisk accepts only a "
                                                     r"body's inertia.*body 2 J_y \+ .*x-z "
                                                     r"bending.*body 3 J_y"):
        lay = sb.layout(craft(wing=wide))
    wing = lay.appendages[0]
    deficit = Jx - chain.inertias_y - chain.inertias
    assert [(i, axis) for i, axis, _ in wing.raised_inertias] == [(2, "y"), (3, "y")]
    np.testing.assert_allclose([added for _, _, added in wing.raised_inertias], deficit[1:],
                               rtol=1e-15)
    # Basilisk's bodies and the compared chain carry the raised moment (the folded first body
    # is the hub's: left as it is), J_x = J_y + J_z: a body's
    modelled = lay.spacecraft.mounts[0].appendage
    np.testing.assert_allclose(modelled.inertias_y[1:], Jx[1:] - chain.inertias[1:], rtol=1e-15)
    assert modelled.inertias_y[0] == chain.inertias_y[0]
    np.testing.assert_array_equal(modelled.torsional_inertias, Jx)
    for body in wing.bodies[2::3]:
        J = np.diag(body.ISPntSc_S)
        assert J[0] <= (J[1] + J[2]) * (1 + 1e-15)
    assert sb.basilisk_chain(modelled) is modelled
    # a moment of zero cannot be made a body's: refused by name
    point = HingedChain([1.0, 1.0], [1.0, 1.0], [0.1, 0.0], [10.0], com_offsets=[0.5, 1.0],
                        inertias_y=[0.1, 0.0], torsional_inertias=[0.1, 0.1])
    with pytest.raises(sb.BasiliskModelError, match=r"body 2 has inertia 0.0 \[kg\*m\^2\] "
                                                    r"about its y axis"):
        sb.layout(craft(wing=point))


# -- the controller as a three-axis digital law (no Basilisk needed) --------------------------
def test_a_continuous_three_axis_controller_is_discretised_exactly():
    plant = craft().plant(prune=True)
    continuous = controllers.pd(plant, natural_frequency=0.3, damping=0.7, roll_off=5.0)
    law = sb.flight_software_law(continuous, 0.05)
    reference = controllers.pd(plant, natural_frequency=0.3, damping=0.7, roll_off=5.0,
                               sample_time=0.05)
    # both are control.c2d(zoh) of the same system: identical to round-off
    for ours, theirs in zip((law.A, law.B, law.C, law.D),
                            (reference.A, reference.B, reference.C, reference.D)):
        np.testing.assert_allclose(ours, theirs, rtol=1e-13, atol=1e-15)
    assert law.three_axis and law.outputs == sb.TORQUES_3
    assert law.inputs == sb.SIGNALS_3
    digital = controllers.lqr(plant, attitude_weight=1.0, rate_weight=1.0, torque_weight=1.0,
                              sample_time=0.1)
    assert sb.flight_software_law(digital).sample_time == 0.1  # at its own rate


def test_three_axis_controller_errors_name_what_and_why():
    two = control.ss([], [], [], np.eye(2, 3), 0, inputs=["theta_x", "theta_y", "theta_z"],
                     outputs=["torque_x", "torque_y"])
    with pytest.raises(sb.BasiliskModelError, match=r"or three axes the outputs \['torque_x', "
                                                    r"'torque_y', 'torque_z'\]"):
        sb.flight_software_law(two, 0.1)
    tip = control.ss([], [], [], np.eye(3), 0, inputs=["theta_x", "theta_y", "wing_tip_twist"],
                     outputs=["torque_x", "torque_y", "torque_z"])
    with pytest.raises(sb.BasiliskModelError, match=r"\['wing_tip_twist'\] are not signals"):
        sb.flight_software_law(tip, 0.1)
    sc = craft()
    with pytest.raises(ValueError, match=r"axis is required for a three-axis spacecraft"):
        sb.simulate_slew(sc, digital_pd(sc), SMALL, SLEW_TIME)
    with pytest.raises(ValueError, match=r"axis must be 'x', 'y', 'z' or three finite numbers"):
        sb.simulate_slew(sc, digital_pd(sc), SMALL, SLEW_TIME, axis=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match=r"axis is required for a three-axis controller"):
        sb.linear_slew(sc, digital_pd(sc), SMALL, SLEW_TIME)


def test_the_attitude_is_the_rotation_vector_unwrapped_across_the_shadow_set():
    e = np.array([1.0, -2.0, 0.5]) / np.linalg.norm([1.0, -2.0, 0.5])
    for angle in (1e-9, 0.3, math.pi - 1e-6):
        # sigma = tan(phi/4) e: 4 atan is exact to a few ulp of phi
        np.testing.assert_allclose(sb.rotation_vector(math.tan(angle / 4) * e), angle * e,
                                   rtol=4e-16, atol=0)
    # 190 deg: Basilisk holds the shadow set -sigma/|sigma|^2 (a rotation of -170 deg); the
    # previous sample at 185 deg brings it back to 190 deg
    phi = math.radians(190.0)
    shadow = -math.tan(phi / 4) * e / math.tan(phi / 4) ** 2
    np.testing.assert_allclose(sb.rotation_vector(shadow), (phi - 2 * math.pi) * e, rtol=1e-14)
    np.testing.assert_allclose(sb.rotation_vector(shadow, math.radians(185.0) * e), phi * e,
                               rtol=1e-14)
    assert not np.any(sb.rotation_vector(np.zeros(3)))


def test_default_sample_time_gives_thirty_samples_per_crossover_in_every_direction():
    plant = craft().plant(prune=True)
    K = controllers.pd(plant, natural_frequency=0.3, damping=0.7)
    T = sb.default_sample_time(plant, K)
    omega, L = controllers.loop_frequency_response(plant, K)
    gain = np.linalg.norm(L, ord=2, axis=(1, 2))  # the largest singular value
    crossover = float(omega[np.nonzero(gain >= 1.0)[0][-1]])
    assert 2 * math.pi / T >= 30 * crossover
    assert 2 * math.pi / (2.5 * T) < 30 * crossover  # the next 1-2-5 step up would be too long


# -- Basilisk's model against flexsat's --------------------------------------------------------
def _elastic(system: control.StateSpace) -> np.ndarray:
    lam = np.linalg.eigvals(system.A)
    lam = lam[np.argsort(np.abs(lam))][12:]  # 6 rigid motions, two zeros each
    return lam[np.lexsort((lam.real, lam.imag))]


def shipped_spacecraft():
    """The shipped three_axis scene's hub, mounts and 3-body chains (fit_chain_3d of its
    rectangular wings and CFRP boom; axial springs held, torsion up to 5.7e3 rad/s)."""
    from spacecraft import load_scene

    scene = load_scene("three_axis")
    hub = Hub(scene.hub.mass, np.array(scene.hub.inertia))
    return Spacecraft(hub, [Mount(fit_chain_3d(a.beam.build(), a.fit.n_bodies), a.position,
                                  orientation=np.array(a.orientation), name=a.name)
                            for a in scene.appendages])


@pytest.mark.slow
@needs_bsk
@pytest.mark.parametrize("which", ["tapered", "shipped"])
def test_the_linearised_basilisk_model_has_flexsats_modes(which):
    sc = craft() if which == "tapered" else shipped_spacecraft()
    if which == "tapered":
        model = sb.linearised(sc)
    else:  # the wide wings' tip bodies: torsional inertia beyond J_y + J_z (module docstring)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            model = sb.linearised(sc)
        said = [str(w.message) for w in caught if w.category is sb.BasiliskModelWarning]
        assert len(said) == 2 and all("body 3 J_y" in m for m in said)
        assert "'wing_left'" in said[0] and "'wing_right'" in said[1]
    flexsat = model.layout.spacecraft
    # damped eigenvalues (both models' dampers) and, undamped, the coupled frequencies
    np.testing.assert_allclose(model.elastic_eigenvalues(),
                               _elastic(flexsat.plant(disturbances=True)), rtol=1e-9)
    assert np.all(model.elastic_eigenvalues().real < 0)  # every joint damped
    if which == "shipped":
        assert [a.held for a in model.layout.appendages] == [("axial",)] * 3


@needs_bsk
def test_undamped_basilisk_modes_are_flexsats_coupled_frequencies():
    def undamped(chain):
        return HingedChain(chain.lengths, chain.masses, chain.inertias, chain.hinge_stiffnesses,
                           com_offsets=chain.com_offsets, root=chain.root,
                           inertias_y=chain.inertias_y,
                           hinge_stiffnesses_y=chain.hinge_stiffnesses_y,
                           torsional_inertias=chain.torsional_inertias,
                           torsion_stiffnesses=chain.torsion_stiffnesses)

    sc = craft(undamped(tapered_chain_3d(4)), undamped(tapered_chain_3d(3, "hinged")))
    model = sb.linearised(sc)
    poles = model.elastic_eigenvalues()
    assert np.max(np.abs(poles.real)) <= 1e-9 * np.max(np.abs(poles))  # conservative
    w = np.sort(poles.imag[poles.imag > 0])
    np.testing.assert_allclose(w, sc.natural_frequencies(w.size, exact=False), rtol=1e-9)


@pytest.mark.slow
@needs_bsk
def test_energy_and_momentum_are_conserved_to_rk4_accuracy():
    # No control, no damping: a tumbling spacecraft (rates about every axis) with both chains
    # vibrating in every motion conserves energy and angular momentum; Basilisk's totals drift
    # only by RK4's error, O(dt^5) (tests/spacecraft/basilisk/test_basilisk.py): halving dt cuts it by >= 16.
    def undamped(chain):
        return HingedChain(chain.lengths, chain.masses, chain.inertias, chain.hinge_stiffnesses,
                           com_offsets=chain.com_offsets, root=chain.root,
                           inertias_y=chain.inertias_y,
                           hinge_stiffnesses_y=chain.hinge_stiffnesses_y,
                           torsional_inertias=chain.torsional_inertias,
                           torsion_stiffnesses=chain.torsion_stiffnesses)

    sc = craft(undamped(tapered_chain_3d(3)), undamped(tapered_chain_3d(3, "hinged")))
    duration = 10.0
    angles = {"wing": 0.02 * np.sin(np.arange(6) + 1.0),
              "boom": 0.02 * np.cos(np.arange(9) + 1.0)}

    def drift(k):
        result = sb.simulate(sc, duration=duration, sample_time=0.1, dt=0.1 / k,
                             initial_rate=[0.02, -0.03, 0.05], initial_angles=angles,
                             conservation=True)
        c = result.conservation
        E, H = c["rotational_energy"], c["angular_momentum"]
        return (float(np.max(np.abs(E - E[0]))) / E[0],
                float(np.max(np.linalg.norm(H - H[0], axis=1))) / np.linalg.norm(H[0]),
                result)

    energy, momentum, _ = drift(8)
    energy_half, momentum_half, result = drift(16)
    assert energy_half < energy / 16 and momentum_half < momentum / 16
    y = result.highest_frequency * result.dt
    assert energy_half < duration / result.dt * y**6 / 144
    E_orbit = result.conservation["orbital_energy"]  # translation of the centre of mass
    E_rotation = result.conservation["rotational_energy"][0]
    assert np.max(np.abs(E_orbit - E_orbit[0])) <= 1e-12 * E_rotation


# -- the eigen-axis slew against flexsat's linear loop -----------------------------------------
@pytest.mark.slow
@needs_bsk
def test_a_small_eigen_axis_slew_agrees_to_second_order():
    sc = craft()
    K = digital_pd(sc)
    full, result = relative_differences(sc, K, SMALL)
    half, _ = relative_differences(sc, K, SMALL / 2)
    expected = ([f"{q}_{a}" for q in ("theta", "omega", "torque") for a in "xyz"]
                + [f"{n}_{m}" for n in ("wing", "boom")
                   for m in ("tip_deflection_y", "tip_deflection_z", "tip_twist")])
    assert sorted(full) == sorted(expected)
    for name in expected:
        assert full[name] <= SMALL, name          # second-order terms: the angle x O(1)
        assert full[name] / half[name] == pytest.approx(2.0, rel=0.02), name
    assert result.highest_frequency * result.dt <= sb.simulation.DEFAULT_STEP_FACTOR


@pytest.mark.slow
@needs_bsk
def test_a_large_eigen_axis_slew_differs_by_physics_not_integration():
    # 10 deg: the terms the linear model drops grow with the angle, 100 x the 0.1 deg figures
    # to within the third-order terms, the angle (0.17 rad) x O(1) of the second-order ones:
    # 10 % allows a factor 0.6 (measured 97 to 106); halving RK4's step leaves the differences
    # as they are (measured 1.3e-6 relative: RK4's own error is below 1e-7 of the peaks)
    sc = craft()
    K = digital_pd(sc)
    large, result = relative_differences(sc, K, math.radians(10.0))
    small, _ = relative_differences(sc, K, SMALL)
    finer, _ = relative_differences(sc, K, math.radians(10.0), dt=result.dt / 2)
    for name in large:
        assert large[name] / small[name] == pytest.approx(100.0, rel=0.1), name
        assert finer[name] == pytest.approx(large[name], rel=1e-4), name


@pytest.mark.slow
@needs_bsk
def test_controller_kinds_and_disturbances_in_three_axes():
    # a continuous PD with roll-off run at the flight-software rate, and a digital LQR (an
    # estimator with states) with a torque pulse about y and a force along z on the hub, held
    # over each sample as in flexsat's sampled loop
    sc = craft()
    plant = sc.plant(prune=True)
    pd = controllers.pd(plant, natural_frequency=0.3, damping=0.7, roll_off=5.0)
    relative, _ = relative_differences(sc, pd, SMALL, sample_time=0.05)
    assert max(relative.values()) <= SMALL
    pulse = {"disturbance_torque_y": lambda t: np.where((t >= 5.0) & (t < 7.0), 1e-3, 0.0),
             "force_z": lambda t: np.where(t >= 12.0, -2e-4, 0.0)}
    lqr = controllers.lqr(sc.plant(prune=True), attitude_weight=1.0, rate_weight=1.0,
                          torque_weight=1.0, sample_time=0.1)
    relative, _ = relative_differences(sc, lqr, SMALL, disturbances=pulse)
    assert max(relative.values()) <= SMALL
    with pytest.raises(sb.BasiliskModelError, match=r"'wing_tip_force_y' is not applied"):
        sb.simulate_slew(sc, lqr, SMALL, SLEW_TIME, axis=AXIS,
                         disturbances={"wing_tip_force_y": np.zeros})


@needs_bsk
def test_a_planar_controller_on_a_three_axis_spacecraft_is_refused():
    planar = control.ss([], [], [], [[1.0, -1.0, -10.0]], 0.1,
                        inputs=["theta_ref", "theta", "omega"], outputs=["torque"])
    with pytest.raises(sb.BasiliskModelError, match=r"the spacecraft is three-axis but the "
                                                    r"controller's outputs are \['torque'\]"):
        sb.simulate_slew(craft(), planar, SMALL, SLEW_TIME, axis=AXIS)


@pytest.mark.slow
@needs_bsk
def test_a_reaction_wheel_triad_applies_the_commanded_torques():
    # One balanced wheel per hub axis: the hub gets the commanded torques and the gyroscopic
    # torque omega x h of the wheels' momentum h, second order in the motion (h starts at 0):
    # the loop agrees with flexsat's linear loop as the external torque does. Each wheel's
    # absolute momentum J_s (Omega + omega_axis) is minus the impulse of its axis' torque,
    # sum torque_j T: Basilisk's spin equation J_s (Omega' + g.omega') = u_s, integrated by RK4
    # to round-off (1e-12 of the impulse, as in tests/spacecraft/basilisk/test_basilisk.py).
    sc = craft()
    K = digital_pd(sc)
    wheel = sb.ReactionWheel(spin_inertia=0.05)
    relative, result = relative_differences(sc, K, SMALL, reaction_wheel=wheel)
    assert max(relative.values()) <= SMALL
    y = dict(zip(result.response.output_labels, np.asarray(result.response.outputs)))
    for a in "xyz":
        momentum = wheel.spin_inertia * (y[f"wheel_speed_{a}"] + y[f"omega_{a}"])
        impulse = np.concatenate([[0.0], np.cumsum(y[f"torque_{a}"][:-1]) * SAMPLE_TIME])
        np.testing.assert_allclose(momentum, -impulse, rtol=0,
                                   atol=1e-12 * np.max(np.abs(impulse)))
    biased = sb.ReactionWheel(spin_inertia=0.05, initial_speed=100.0)
    with pytest.raises(sb.BasiliskModelError, match=r"reaction_wheel\.initial_speed must be 0 "
                                                    r"\[rad/s\] on a three-axis spacecraft"):
        sb.simulate_slew(sc, K, SMALL, SLEW_TIME, axis=AXIS, reaction_wheel=biased)


@pytest.mark.slow
@needs_bsk
def test_slew_comparison_against_a_beam_truth_in_three_axes():
    # The three differences of one call are consistent: per signal, |Basilisk - truth| <=
    # |Basilisk - chain| + |chain - truth| (triangle inequality of the peaks, round-off 1e-12),
    # and Basilisk - truth is the chain's cost to within the (second-order) nonlinearity.
    beam = Beam(10.0, 100.0, 0.6, bending_stiffness_y=170.0, torsional_stiffness=30.0,
                torsional_inertia=0.02, damping_ratio=0.005)
    chain = fit_chain_3d(beam, 4)
    sc = craft(wing=chain)
    truth = Spacecraft(HUB, [sc.mounts[0].with_appendage(beam.truncated(6)),
                             sc.mounts[1]]).plant(tip_deflection=True)
    K = digital_pd(sc)
    c = sb.slew_comparison(sc, K, SMALL, SLEW_TIME, duration=DURATION, truth_plant=truth,
                           axis=AXIS)
    d = c.differences
    assert set(d) == {"basilisk_vs_chain", "basilisk_vs_truth", "chain_vs_truth"}
    for name in ("theta_x", "omega_y", "wing_tip_deflection_z", "wing_tip_twist", "torque_z"):
        total = d["basilisk_vs_truth"][name]["peak_difference"]
        assert total <= (d["basilisk_vs_chain"][name]["peak_difference"]
                         + d["chain_vs_truth"][name]["peak_difference"]) * (1 + 1e-12)
        assert d["basilisk_vs_truth"][name]["relative"] == pytest.approx(
            d["chain_vs_truth"][name]["relative"], abs=SMALL)
    np.testing.assert_array_equal(c.truth.time, c.basilisk.response.time)


# -- the design loop's Basilisk run (spacecraft.design.simulators) -----------------------------
def _loop_of(spacecraft, controllers_by_kind, **simulator):
    """What the design loop hands :func:`basilisk_runs`: a runner with the scene (the shipped
    three_axis scene's, with a 0.1 deg slew in 20 s of 40 s, a torque pulse along an axis and
    ``simulator`` keys) and its
    stats, the designs of one variant, the truth plant (here the linear chains themselves)."""
    import dataclasses
    import types

    from spacecraft import load_scene
    from spacecraft.scene.specs import DisturbanceSpec, ReactionWheelSpec, SimulatorSpec

    scene = load_scene("three_axis")
    wheel = simulator.pop("reaction_wheel", None)
    # a torque pulse about (0, 0.6, 0.8), of the size of the slew's own torques
    pulse = DisturbanceSpec("disturbance_torque", 1e-3, start=5.0, length=2.0,
                            axis=(0.0, 0.6, 0.8))
    scene = scene.replace(
        manoeuvre=dataclasses.replace(scene.manoeuvre, slew_angle=SMALL, slew_time=SLEW_TIME,
                                      duration=DURATION, slew_axis=AXIS, disturbance=pulse),
        simulator=SimulatorSpec("basilisk", reaction_wheel=None if wheel is None
                                else ReactionWheelSpec(**wheel), **simulator))
    runner = types.SimpleNamespace(scene=scene, stats=types.SimpleNamespace(basilisk_runs=0))
    designs = {"fit": {"spacecraft": spacecraft, "plant": spacecraft.plant(prune=True),
                       "controllers": controllers_by_kind}}
    return runner, designs, spacecraft.plant(tip_deflection=True, disturbances=True)


@pytest.mark.slow
@needs_bsk
def test_the_design_loops_basilisk_run_is_three_axis_too():
    # basilisk_runs, the design loop's call, on a three-axis design: the eigen-axis slew about
    # manoeuvre.slew_axis, every controller through one wheel triad each, results per axis
    # and per tip motion, JSON without NaN. The truth here is the linear chain spacecraft
    # itself, so Basilisk - truth is Basilisk - linear chain (to round-off) and both are the
    # second-order difference of the 0.1 deg slew (test above).
    import json

    from spacecraft.design.simulators import basilisk_runs

    sc = craft()
    plant = sc.plant(prune=True)
    ks = {"pd": digital_pd(sc),
          "lqr": controllers.lqr(plant, attitude_weight=1.0, rate_weight=1.0,
                                 torque_weight=1.0, sample_time=SAMPLE_TIME)}
    runner, designs, truth = _loop_of(sc, ks, reaction_wheel={"spin_inertia": 0.05})
    comparisons, data = basilisk_runs(runner, designs, truth)
    assert runner.stats.basilisk_runs == 2 and set(comparisons) == set(data) == {"pd", "lqr"}
    json.dumps(data, allow_nan=False)
    for kind, entry in data.items():
        d = entry["differences"]
        names = {f"{q}_{a}" for q in ("theta", "omega", "torque") for a in "xyz"} | {
            f"{n}_{m}" for n in ("wing", "boom")
            for m in ("tip_deflection_y", "tip_deflection_z", "tip_twist")}
        assert names <= set(d["basilisk_vs_chain"])
        for name in names:
            assert d["basilisk_vs_chain"][name]["relative"] <= SMALL, (kind, name)
            assert d["basilisk_vs_truth"][name]["peak_difference"] == pytest.approx(
                d["basilisk_vs_chain"][name]["peak_difference"], rel=1e-9, abs=1e-15)
        assert entry["out_of_plane"] is None
        assert "theta_x [rad] differs from" in entry["summary"]
        assert "wing_tip_twist [rad] differs from" in entry["summary"]
        assert "boom_tip_deflection_z [m] differs from" in entry["summary"]
        # the triad: a wheel per hub axis, each holding its axis' momentum
        assert set(entry["wheel"]["peak_momentum"]) == {"wheel_x", "wheel_y", "wheel_z"}
        assert entry["wheel"]["words"].startswith("no wheel reached a limit")
        response = comparisons[kind].basilisk.response
        y = dict(zip(response.output_labels, np.asarray(response.outputs)))
        for a in "xyz":
            assert entry["wheel"]["peak_momentum"][f"wheel_{a}"] == pytest.approx(
                0.05 * np.max(np.abs(y[f"wheel_speed_{a}"])), rel=1e-15)
        # the reference the flight software flew: the eigen-axis slew about slew_axis; the
        # pulse about (0, 0.6, 0.8) as its components
        inputs = dict(zip(response.input_labels, np.asarray(response.inputs)))
        on = (response.time >= 5.0) & (response.time < 7.0)
        np.testing.assert_array_equal(inputs["disturbance_torque_y"], np.where(on, 6e-4, 0.0))
        np.testing.assert_array_equal(inputs["disturbance_torque_z"], np.where(on, 8e-4, 0.0))
        assert "disturbance_torque_x" not in inputs
        reference = sb.slew_reference(SMALL, SLEW_TIME, AXIS)(response.time)
        for k, a in enumerate("xyz"):
            np.testing.assert_array_equal(inputs[f"theta_ref_{a}"], reference[:, k])


@pytest.mark.slow
@needs_bsk
def test_a_three_axis_scene_runs_in_basilisk(tmp_path):
    # simulator.name = "basilisk" on a three-axis scene: the design loop's run in Basilisk
    # (0.1 deg: second order, every attitude within the angle of the linear chain's, as in
    # the tests above), in results.json per axis and tip motion, in the report's Basilisk
    # section and on the slew plot
    from spacecraft import run
    from spacecraft.report.write import write_report

    data = soft_three_axis_scene()
    data["report"] = {"plots": ["slew"]}
    result = run(data)
    entry = result.data["basilisk"]["pd"]
    chain = entry["differences"]["basilisk_vs_chain"]
    for a in "xyz":
        assert chain[f"theta_{a}"]["relative"] <= SMALL
    for m in ("tip_deflection_y", "tip_deflection_z", "tip_twist"):
        assert f"wing_{m}" in chain and f"wing_{m}" in entry["differences"]["basilisk_vs_truth"]
    assert "theta_x [rad] differs from the distributed beam (truth)" in entry["summary"]
    assert entry["out_of_plane"] is None
    write_report(result, tmp_path)
    report = (tmp_path / "report.md").read_text()
    assert "## Basilisk: the manoeuvre in a nonlinear multibody simulator" in report
    assert "| PD | wing_tip_twist |" in report
    assert "dotted black: Basilisk's nonlinear run of the design chains" in report
    assert (tmp_path / "timeseries" / "pd_basilisk.csv").exists()
