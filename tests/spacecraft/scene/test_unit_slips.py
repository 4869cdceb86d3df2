"""Inputs checked for physics and for unit slips (issue 20, item 4).

A legal value that looks like a unit mistake is warned about, naming the likely mistake: in a
scene (its key, in the run's warnings: terminal, report, results.json) and in the Python API
(:class:`appendages.unit_slips.UnitWarning`). Physically impossible or meaningless values of the
Python API are refused naming the parameter.
"""
import math
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest

import controllers
from appendages import Beam, SteppedBeam
from appendages.unit_slips import (UnitWarning, damping_in_percent, degrees_in_radians,
                              modulus_in_megapascals, radians_in_degrees)
from spacecraft import Mount, SceneError, load_scene
from spacecraft.dynamics.kinematics import euler_orientation, orientation_from_axis
from spacecraft.scene.read import example_scenes, scene_path


# -- the rules ------------------------------------------------------------------------------
@pytest.mark.parametrize("typed, degrees", [
    (0.1745, 10), (0.17453, 10), (0.01745, 1), (0.0873, 5), (0.5236, 30), (0.7854, 45),
    (1.5708, 90), (1.571, 90), (3.1416, 180), (3.14, 180), (6.2832, 360), (-0.1745, -10),
])
def test_a_round_angle_typed_in_radians_is_recognised(typed, degrees):
    assert radians_in_degrees(typed) == f"did you give radians? {typed:g} rad = {degrees} deg"


@pytest.mark.parametrize("typed", [0.0, 0.1, 0.2, 0.25, 0.5, 0.75, 1, 1.5, 2, 2.5, 3, 4, 5, 6,
                                   10, 30, 45, 90, 180, 360, 0.001, 1e-6, 0.125, 12.5])
def test_angles_typed_in_degrees_are_not_taken_for_radians(typed):
    """Whole numbers and halves (what people type in degrees) have too few digits to say."""
    assert radians_in_degrees(typed) is None


def test_every_whole_and_half_degree_passes_without_a_warning():
    values = np.arange(0.5, 360.5, 0.5)
    assert [v for v in values if radians_in_degrees(float(v)) is not None] == []


def test_a_radian_angle_beyond_a_turn_is_taken_for_degrees():
    assert degrees_in_radians(180.0) == ("more than a turn (2 pi rad); did you give degrees? "
                                         "180 deg = 3.14159 rad")
    assert degrees_in_radians(2 * math.pi) is None and degrees_in_radians(-3.0) is None


@pytest.mark.parametrize("modulus, density, unit", [
    (2.0e5, 7800.0, "MPa"), (7.0e4, 2700.0, "MPa"), (1.1e5, 4500.0, "MPa"),
    (200.0, 7800.0, "GPa"), (70.0, 2700.0, "GPa")])
def test_a_metal_modulus_in_mega_or_gigapascals_is_recognised(modulus, density, unit):
    said = modulus_in_megapascals(modulus, density)
    factor = {"MPa": 1e6, "GPa": 1e9}[unit]
    assert said.endswith(f"did you give {unit}? {modulus:g} {unit} = {modulus * factor:g} Pa")


@pytest.mark.parametrize("modulus, density", [
    (2.06e11, 7800.0), (7.0e10, 2700.0), (1.5e11, 1600.0), (3.0e9, 1200.0), (2.0e8, 920.0)])
def test_structural_materials_pass(modulus, density):
    """Steel, aluminium, CFRP, epoxy, polyethylene: bar wave speeds from 466 to 9,700 m/s."""
    assert modulus_in_megapascals(modulus, density) is None


def test_a_damping_ratio_above_0_2_is_taken_for_per_cent():
    assert damping_in_percent(0.5).endswith("did you give per cent? 0.5 % = 0.005")
    assert damping_in_percent(0.2) is None and damping_in_percent(0.02) is None


# -- scenes ---------------------------------------------------------------------------------
def default_scene_data():
    with open(scene_path("default"), "rb") as stream:
        return tomllib.load(stream)


@pytest.mark.slow
def test_the_embedded_scenes_look_meant():
    for name in example_scenes():
        assert load_scene(name).input_warnings == (), name


@pytest.mark.parametrize("change, key, said", [
    (lambda d: d["manoeuvre"].update(slew_angle=0.1745), "manoeuvre.slew_angle",
     "did you give radians? 0.1745 rad = 10 deg"),
    (lambda d: d["appendages"][0].update(direction=1.5708), "appendages[0].direction",
     "did you give radians? 1.5708 rad = 90 deg"),
    (lambda d: d["appendages"][0]["beam"].update(youngs_modulus=2.06e5),
     "appendages[0].beam.youngs_modulus", "did you give MPa? 206000 MPa = 2.06e+11 Pa"),
    (lambda d: d["appendages"][0]["beam"].update(damping_ratio=0.5),
     "appendages[0].beam.damping_ratio", "did you give per cent? 0.5 % = 0.005"),
])
def test_a_scene_value_that_looks_like_a_unit_slip_is_warned_about_by_key(change, key, said):
    """Before: a 0.17 deg slew, a rod that deflects 1.85 m, damping 0.5, all silently run."""
    data = default_scene_data()
    change(data)
    scene = load_scene(data, source="slip.toml")
    assert len(scene.input_warnings) == 1
    assert scene.input_warnings[0].startswith(f"slip.toml: {key}: ")
    assert scene.input_warnings[0].endswith(said)


@pytest.mark.parametrize("change, match", [
    (lambda d: d["appendages"][0]["beam"].update(youngs_modulus=7.0e4),
     r"youngs_modulus: must lie between 100000 and 1e\+13 \[Pa\]; got 70000\.0; did you give "
     r"MPa\? 70000 MPa = 7e\+10 Pa"),
    (lambda d: d["appendages"][0]["beam"].update(damping_ratio=2.0),
     r"damping_ratio: must be below 1 \[-\].*; got 2\.0; did you give per cent\? 2 % = 0\.02"),
])
def test_a_refused_value_names_the_likely_unit_slip(change, match):
    data = default_scene_data()
    change(data)
    with pytest.raises(SceneError, match=match):
        load_scene(data)


def test_a_run_reports_a_unit_slip_once_by_key_not_again_by_the_constructor():
    data = default_scene_data()
    data["appendages"][0]["beam"]["damping_ratio"] = 0.5
    data.pop("export")
    from spacecraft import run

    lines = [line for line in run(load_scene(data, source="slip.toml"), time_responses=False)
             .data["warnings"] if "damping" in line]
    assert lines == ["UnitWarning: slip.toml: appendages[0].beam.damping_ratio: above 0.2, more "
                     "than structures have (1e-4 to 0.05 without added dampers); did you give "
                     "per cent? 0.5 % = 0.005"]


def test_a_tiny_slew_axis_is_the_axis_it_points_along():
    """[1e-300, 0, 0] was refused as "got [0, 0, 0]" (its squares underflow): it is x."""
    with open(scene_path("three_axis"), "rb") as stream:
        data = tomllib.load(stream)
    data["manoeuvre"]["slew_axis"] = [1e-300, 0.0, 0.0]
    assert load_scene(data).manoeuvre.slew_axis == (1.0, 0.0, 0.0)
    data["manoeuvre"]["slew_axis"] = [1e-300, -1e-300, 0.0]
    np.testing.assert_allclose(load_scene(data).manoeuvre.slew_axis,
                               (math.sqrt(0.5), -math.sqrt(0.5), 0.0), rtol=1e-15)
    e = orientation_from_axis([1e-300, 0.0, 0.0])
    np.testing.assert_array_equal(e[:, 0], [1.0, 0.0, 0.0])


def test_a_run_reports_the_unit_slips_with_its_warnings(tmp_path):
    """In result.data["warnings"] (results.json, the report's Warnings section, printed by the
    command line), one line each naming the key."""
    from spacecraft import output_folder, run, write_report

    data = {"hub": {"mass": 100.0, "inertia": 50.0},
            "appendages": [{"name": "wing", "position": [0.5, 0.0], "direction": 0.7854,
                            "chain": {"lengths": [1.0, 1.0], "masses": [1.0, 1.0],
                                      "inertias": [0.1, 0.1], "hinge_stiffnesses": [100.0]}}],
            "controller": {"pd": {"natural_frequency": 0.5}}}
    result = run(data, time_responses=False)
    line = ("UnitWarning: <dict>: appendages[0].direction: did you give radians? 0.7854 rad = "
            "45 deg")
    assert result.data["warnings"][0] == line
    with output_folder(tmp_path / "out") as folder:
        write_report(result, folder)
    report = (tmp_path / "out" / "report.md").read_text()
    section = report[report.index("## Warnings"):]
    assert "direction: did you give radians? 0.7854 rad = 45 deg" in section


# -- the Python API's angles: radians, a turn or more warned about --------------------------
def test_a_mount_direction_in_degrees_is_warned_about():
    beam = Beam(2.0, 100.0, 1.0)
    with pytest.warns(UnitWarning, match=r"direction = 180 rad is more than a turn \(2 pi rad\)"
                                         r"; did you give degrees\? 180 deg = 3\.14159 rad"):
        Mount(beam, (0.0, 0.0), 180.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert Mount(beam, (0.0, 0.0), math.pi).angle == math.pi


def test_euler_angles_and_slew_angles_in_degrees_are_warned_about():
    with pytest.warns(UnitWarning, match=r"angles\[1\] = 90 rad is more than a turn"):
        euler_orientation("ZYX", (0.0, 90.0, 0.0))
    t = np.linspace(0.0, 10.0, 11)
    with pytest.warns(UserWarning, match=r"angle = 30 rad is more than a turn .*did you give "
                                         r"degrees\? 30 deg = 0\.523599 rad"):
        controllers.slew_profile(t, 30.0, 10.0)


# -- the Python API's beams: a modulus in MPa or GPa, a damping ratio in per cent -----------
@pytest.mark.parametrize("build, match", [
    (lambda: Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e5), r"youngs_modulus = 206000 Pa: a bar "
     r"wave speed sqrt\(E/rho\) of 5\.14 m/s .*did you give MPa\? 206000 MPa = 2\.06e\+11 Pa"),
    (lambda: Beam.tube(5.0, 0.1, 0.002, 2700.0, 7.0e4), r"youngs_modulus = 70000 Pa: .*did you "
     r"give MPa\? 70000 MPa = 7e\+10 Pa"),
    (lambda: Beam.rectangular(6.0, 0.5, 0.02, 1600.0, 7.0e10, damping_ratio=0.5),
     r"damping_ratio = 0\.5: above 0\.2, .*did you give per cent\? 0\.5 % = 0\.005"),
    (lambda: Beam(2.0, 100.0, 1.0, damping_ratio=0.3), r"damping_ratio = 0\.3: above 0\.2"),
    (lambda: SteppedBeam.tapered(4.0, 8, section="tube", root_dimensions={
        "outer_diameter": 0.1, "wall_thickness": 0.002}, tip_dimensions={
        "outer_diameter": 0.05, "wall_thickness": 0.002}, density=2700.0, youngs_modulus=7.0e4),
     r"youngs_modulus = 70000 Pa: .*did you give MPa\?"),
])
def test_a_beam_constructor_warns_about_a_unit_slip_as_the_scene_reader(build, match):
    """The rules of the scene's keys (appendages.unit_slips), at the caller's line."""
    with pytest.warns(UnitWarning, match=match) as caught:
        build()
    assert all(Path(w.filename).resolve() == Path(__file__).resolve() or
               w.filename.endswith("stepped.py") for w in caught)


def test_a_beam_warns_once_and_its_views_do_not_warn_again():
    with pytest.warns(UnitWarning) as caught:
        beam = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=0.25)
    assert len(caught) == 1
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        beam.planar_view("xz")
        beam.W6(1j)
        assert beam.undamped().damping_ratio == 0.0
        Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=0.2)  # the bound itself
        Beam.rectangular(6.0, 0.5, 0.02, 1600.0, 7.0e10, damping_ratio=0.005)


def test_the_constructors_warn_after_refusing_what_is_not_a_number():
    with pytest.raises(TypeError, match="damping_ratio"):
        Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio="0.5")


# -- the Python API refuses what is not physics, naming the parameter -----------------------
@pytest.mark.parametrize("call, error, match", [
    # returned (-0.5, -7.0)
    (lambda: controllers.pd_gains(-50.0, 0.1, 0.7), ValueError,
     r"inertia must be positive and finite \[kg\*m\^2\]; got -50"),
    # returned NaN gains
    (lambda: controllers.pd_gains(50.0, math.nan, 0.7), ValueError,
     r"natural_frequency must be positive and finite \[rad/s\]; got nan"),
    (lambda: controllers.pd_gains(50.0, 0.1, math.nan), ValueError, r"damping must be positive"),
    # an indefinite tensor, and no body's, were accepted
    (lambda: controllers.pd_gains(np.diag([1.0, -1.0, 1.0]), 0.1, 0.7), ValueError,
     r"inertia must be positive definite \[kg\*m\^2\]"),
    (lambda: controllers.pd_gains(np.diag([1.0, 1.0, 100.0]), 0.1, 0.7), ValueError,
     r"inertia must be the inertia of a body"),
    # any axes= value was accepted
    (lambda: controllers.pd_gains(np.eye(3), 0.1, 0.7, axes="x"), ValueError,
     r"axes must be one of \('principal', 'hub'\); got 'x'"),
    # an empty matrix and the identity
    (lambda: controllers.principal_axes([]), ValueError,
     r"inertia must be a 3x3 tensor \[kg\*m\^2\]; got shape \(0,\)"),
    (lambda: controllers.principal_axes(np.diag([1.0, 1.0, 100.0])), ValueError,
     r"inertia must be the inertia of a body"),
    # NaN at t = 0 and an all-zero profile
    (lambda: controllers.slew_profile(np.linspace(0.0, 1.0, 5), 0.1, 0.0), ValueError,
     r"duration must be positive and finite \[s\]; got 0"),
    (lambda: controllers.slew_profile(np.linspace(0.0, 1.0, 5), 0.1, -1.0), ValueError,
     r"duration must be positive and finite \[s\]; got -1"),
    (lambda: controllers.slew_profile([0.0, math.nan], 0.1, 1.0), ValueError,
     r"t must be finite times \[s\]"),
    # returned NaN
    (lambda: controllers.natural_frequency_from_bandwidth(0.2, 1e308), ValueError,
     r"bandwidth 0\.2 rad/s with damping 1e\+308 needs a natural frequency .* beyond the "
     r"floating-point range"),
])
def test_the_python_api_refuses_what_is_not_physics_by_name(call, error, match):
    with pytest.raises(error, match=match):
        call()


@pytest.mark.parametrize("damping", [0.05, 0.5, 0.7, 1 / math.sqrt(2), 0.9, 1.0, 1.5, 3.0,
                                     30.0, 300.0])
def test_natural_frequency_from_bandwidth_against_the_direct_formula(damping):
    """The cancellation-free form inverts the prototype's |T(j wb)| = 1/sqrt(2) (Franklin,
    Powell & Emami-Naeini, ch. 6) to round-off at every damping, and agrees with the direct
    formula wb / sqrt(1 - 2 z^2 + sqrt(4 z^4 - 4 z^2 + 2)) where that one is accurate (z <= 1:
    beyond, its cancellation costs ~8 z^4 eps, 7e-6 relative at z = 300)."""
    wn = controllers.natural_frequency_from_bandwidth(2.0, damping)
    z2 = damping * damping
    if damping <= 1.0:
        direct = 2.0 / math.sqrt(1.0 - 2.0 * z2 + math.sqrt(4.0 * z2 * z2 - 4.0 * z2 + 2.0))
        assert wn == pytest.approx(direct, rel=1e-14, abs=0.0)
    s = 2.0j
    T = wn * wn / (s * s + 2.0 * damping * wn * s + wn * wn)
    assert abs(T) == pytest.approx(1.0 / math.sqrt(2.0), rel=1e-13)
    # far beyond the direct formula's reach: wn -> 2 z wb
    assert controllers.natural_frequency_from_bandwidth(1.0, 1e150) == pytest.approx(2e150,
                                                                                     rel=1e-15)


@pytest.mark.slow
def test_a_run_reports_a_sensor_noise_slip_once_by_key():
    """A sensor level in arcsec/sqrt(Hz) given as rad/sqrt(Hz): warned about by key when the
    scene is read, and not again by :class:`controllers.SensorNoise` when the run builds the
    noise (controllers.LargeNoiseWarning is the constructor's own)."""
    from spacecraft import run

    data = tomllib.loads(scene_path("default_flown").read_text())
    data["sensors"]["attitude_density"] = 0.05
    data["export"] = {"fmu": False}
    data["report"] = {"plots": False}
    lines = [line for line in run(load_scene(data, source="noise.toml")).data["warnings"]
             if "large for a spacecraft sensor" in line]
    assert lines == ["UnitWarning: noise.toml: sensors.attitude_density: 0.05 rad/sqrt(Hz) is "
                     "large for a spacecraft sensor: was it given in arcsec/sqrt(Hz) or "
                     "deg/sqrt(Hz)? It is used as rad/sqrt(Hz)"]
    with pytest.warns(controllers.LargeNoiseWarning, match=r"attitude_density = 0\.05"):
        controllers.SensorNoise(attitude_density=0.05)
