"""Real appendages in three axes: two stepped wings with off-axis tip bodies and a boom given as
a NASTRAN normal-modes solution (six root motions) on a hub with a full inertia tensor.

flexsat's exact coupled frequencies (through each appendage's W6: the wings' exact dynamic
stiffness, the boom's modal data, FE-exact) against an independent finite-element model of the
same spacecraft (tests/support/fe_scene.py: fe3d's high-order beam elements per segment with the tip
bodies' 6x6 mass matrices, the boom's Craig-Bampton realisation, the mounts' rigid kinematics).
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

import fe_scene
from spacecraft import Hub, Mount, Spacecraft, load_scene
from spacecraft.scene.limits import library_limits

EMBEDDED = Path(__file__).resolve().parents[3] / "spacecraft" / "scene" / "embedded"

WING = {"stepped_beam": {"damping_ratio": 0.005, "segments": [
    {"section": "rectangular", "length": 1.0, "width": 0.1, "thickness": 0.05,
     "density": 1600.0, "youngs_modulus": 1.0e11, "poisson_ratio": 0.3},
    {"section": "rectangular", "length": 6.0, "width": 1.5, "thickness": 0.025,
     "density": 160.0, "youngs_modulus": 7.2e9, "poisson_ratio": 0.3}]},
    "tip": {"mass": 5.0, "inertia": [[0.15, 0.0, 0.0], [0.0, 0.2, 0.0], [0.0, 0.0, 0.2]],
            "offset": [0.1, 0.0, 0.0]}}

#: The three-axis real-appendages scene (its tip bodies on the wings' axes: chains carry them).
SCENE = {
    "hub": {"mass": 1200.0,
            "inertia": [[900.0, 15.0, -10.0], [15.0, 800.0, 20.0], [-10.0, 20.0, 1000.0]]},
    "appendages": [
        dict(copy.deepcopy(WING), name="wing_py", position=[0.0, 1.2, 0.0],
             orientation=[90.0, 0.0, 0.0]),
        dict(copy.deepcopy(WING), name="wing_my", position=[0.0, -1.2, 0.0],
             orientation=[-90.0, 0.0, 0.0]),
        {"name": "boom", "position": [0.3, 0.0, -0.8], "orientation": [0.0, 90.0, 0.0],
         "modal": {"nastran": "data/boom_modes.npz", "root": 1, "units": ["in", "slinch"],
                   "mass_matrix": "data/boom_mass.npy", "tip_grid": 11, "damping": 0.003}}],
    "controller": {"types": ["pd"], "pd": {"natural_frequency": 0.1, "damping": 0.7}},
    "manoeuvre": {"slew_angle": 10.0, "slew_time": 120.0, "duration": 360.0, "step": 0.2,
                  "slew_axis": [1.0, 1.0, 0.5]},
}


#: The same spacecraft with the tip bodies 0.05 m off the wings' mid-planes (along their z).
OFF_AXIS_SCENE = copy.deepcopy(SCENE)
for _wing in OFF_AXIS_SCENE["appendages"][:2]:
    _wing["tip"]["offset"] = [0.1, 0.0, 0.05]


def spacecraft_of(scene):
    """The scene's exact spacecraft, built from its specs with the library alone."""
    with library_limits(scene.limits):
        models = [a.structure.build() for a in scene.appendages]
    craft = Spacecraft(Hub(scene.hub.mass, np.array(scene.hub.inertia)),
                       [Mount(model, a.position, orientation=np.array(a.orientation),
                              name=a.name) for model, a in zip(models, scene.appendages)])
    return craft, models


@pytest.fixture(scope="module")
def case():
    scene = load_scene(copy.deepcopy(OFF_AXIS_SCENE), base=EMBEDDED)
    craft, models = spacecraft_of(scene)
    return scene, craft, models


@pytest.mark.slow
def test_exact_coupled_frequencies_agree_with_an_independent_finite_element_model(case):
    # Twelve modes: the wings' bending in and out of their plane and torsion, coupled through
    # the hub, and the boom's first modes. fe3d's quintic elements converge fast: measured
    # largest relative difference 1.2e-6 at 4 elements per segment, 5.4e-9 at 8 (the exact
    # frequencies are located to ~1e-14 in three axes). rtol 1e-7 at 8 and a fall of at least
    # 100x from 4 to 8 (measured 220x).
    scene, craft, models = case
    exact = craft.natural_frequencies(12)
    errors = {n: np.abs(fe_scene.coupled_frequencies(scene, models, n, 12) / exact - 1.0)
              for n in (4, 8)}
    assert np.all(errors[8] < 1e-7), errors[8]
    assert errors[8].max() < errors[4].max() / 100.0, (errors[4], errors[8])
    # the three kinds of appendage are all there, three-axis
    assert [type(m).__name__ for m in models] == ["SteppedBeam", "SteppedBeam",
                                                  "ModalAppendage"]
    assert models[2].three_axis and models[0].three_axis


def test_the_spacecrafts_rigid_properties_place_the_tip_bodies_off_the_wings_axes(case):
    # The tip bodies sit 0.05 m off the wings' mid-planes (along their z, the hub's z): the
    # spacecraft's centre of mass moves by sum(m_tip) 0.05 / m_total along z beside the boom's
    # pull along -z, by hand: hub at the origin, wings symmetric about it.
    scene, craft, models = case
    wing, boom = models[0], models[2]
    m_total = 1200.0 + 2.0 * wing.mass + boom.mass
    boom_centre = np.array([0.3, 0.0, -0.8]) + np.array(scene.appendages[2].orientation) \
        @ boom.center_of_mass_vector
    z = (2.0 * 5.0 * 0.05 + boom.mass * boom_centre[2]) / m_total
    assert craft.center_of_mass[2] == pytest.approx(z, rel=1e-12)
    assert craft.center_of_mass[1] == pytest.approx(0.0, abs=1e-15)


def test_a_chain_cannot_carry_a_tip_body_off_the_axis_and_says_so(case):
    # a chain's bodies lie on its axis with their principal axes along it: a tip body off the
    # axis (or with products of inertia) is refused by name, on the axis it is fitted
    from appendages import SteppedBeam, TipBody
    from appendages.fit3d import fit_chain_3d

    _, _, models = case
    wing = models[0]
    with pytest.raises(ValueError, match=r"fit_chain_3d: the tip body's centre lies off the "
                                         r"appendage's axis \(offset \[0\.1, 0\.0, 0\.05\] m\)"):
        fit_chain_3d(wing, 3)
    products = TipBody(5.0, [[0.15, 0.01, 0.0], [0.01, 0.2, 0.0], [0.0, 0.0, 0.2]], 0.1)
    with pytest.raises(ValueError, match="inertia has products"):
        fit_chain_3d(SteppedBeam(wing.segments, tip=products), 3)


@pytest.mark.slow
def test_the_three_axis_fit_matches_each_rod_motions_own_pole_and_zero():
    # fit_chain_3d on the stepped wing (tip body on its axis): its torsion and axial spring
    # chains have the wing's own first pole and zero (ratio 2.06 and 1.82, not the uniform
    # rod's 2), to the root search's 1e-12. The boom's torsion (a heavy tip mass on a short rod:
    # ratio 31) is beyond what three bodies reach with the bounded tilt: its pole is matched and
    # a FitWarning says how far its zero is.
    from appendages import FitWarning
    from appendages.fit3d import fit_chain_3d, motion_frequencies, rod_chain_frequencies
    from appendages.equivalence import fit_targets

    scene = load_scene(copy.deepcopy(SCENE), base=EMBEDDED)
    wing, boom = (scene.appendages[k].structure.build() for k in (0, 2))
    chain = fit_chain_3d(wing, 3)
    scale = float(fit_targets(wing.planar_view("xy"), 2)["targets"][0][0])
    for motion, index, rigid, inertias, springs in (
            ("torsion", 3, float(wing.inertia_tensor[0, 0]), chain.torsional_inertias,
             chain.torsion_stiffnesses),
            ("axial", 0, wing.mass, chain.masses, chain.axial_stiffnesses)):
        rod = motion_frequencies(wing, index, scale, rigid)
        free, clamped = rod_chain_frequencies(inertias, springs)
        np.testing.assert_allclose([free, clamped], [rod.free, rod.clamped], rtol=1e-10,
                                   err_msg=motion)
        assert abs(rod.free / rod.clamped - 2.0) > 0.05  # not the uniform rod's ratio
    with pytest.warns(FitWarning, match=r"torsion chain of 3 bodies cannot reach the "
                                        r"appendage's first pole/zero ratio 31\.3"):
        fit_chain_3d(boom, 3)


@pytest.mark.slow
def test_the_embedded_scene_is_this_spacecraft():
    # the embedded scene real_appendages_3d holds SCENE's hub and appendages
    embedded = load_scene("real_appendages_3d")
    ours = load_scene(copy.deepcopy(SCENE), base=EMBEDDED)
    assert embedded.three_axis and embedded.hub == ours.hub
    assert embedded.appendages == ours.appendages


@pytest.mark.slow
def test_the_scene_runs_fits_chains_to_all_three_and_its_exact_frequencies_agree_with_fe():
    # flexsat run real_appendages_3d: chains fitted to the two stepped wings and the NASTRAN
    # boom (three-axis chains keeping each appendage's mass), both controllers tuned on them
    # and stable on the truth model, settling; the run's exact coupled frequencies (its
    # outputs.exact_reference) against the independent FE model at 8 quintic elements per
    # segment (5e-9 measured on the off-axis variant above): rtol 1e-7.
    from spacecraft import run

    result = run(load_scene("real_appendages_3d",
                            overrides={"export.fmu": False, "report.plots": False}))
    scene = result.scene
    assert [a.truth for a in scene.appendages] == ["beam", "beam", "modal"]
    for a in scene.appendages:
        chain = result.models[a.name]["fits"]["poles-and-zeros"]
        assert chain.three_axis
        assert chain.mass == pytest.approx(result.models[a.name]["truth"].mass, rel=1e-12)
    assert {row["controller"] for row in result.data["closed_loops"]} == {"pd", "lqr"}
    for row in result.data["closed_loops"]:
        assert row["verdict"]["stable"]
        assert row["status"]["truth"]["status"] == "settles"
    # the run's exact reference is the library's, and the FE model agrees with it
    craft, models = spacecraft_of(scene)
    exact = np.array(result.data["exact"]["coupled_frequencies"])
    np.testing.assert_allclose(exact, craft.natural_frequencies(exact.size), rtol=1e-12)
    np.testing.assert_allclose(fe_scene.coupled_frequencies(scene, models, 8, exact.size), exact,
                               rtol=1e-7)
    np.testing.assert_allclose(result.data["exact"]["inertia"], craft.inertia, rtol=1e-12)
