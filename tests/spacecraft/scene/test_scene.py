"""Scene files: the embedded scenes load; every class of bad input gives a SceneError naming
the file, the key path and the problem."""
import math

import pytest

from appendages.interface import FlexsatError
from spacecraft.scene.read import SceneError, example_scenes, load_scene, scene_path
from scenes import scene_with


@pytest.mark.slow
def test_embedded_scenes_load():
    names = example_scenes()
    assert {"default", "single_boom", "two_wings", "hinged_wing"} <= set(names)
    for name in names:
        scene = load_scene(scene_path(name))
        assert scene.appendages and scene.controller.types


def test_default_scene_is_the_papers_rod_in_si_units():
    scene = load_scene(None)
    rod = scene.appendages[0]
    beam = rod.beam.build()
    # PAPER.md: m = 6.1261 kg for L = 10 m, d = 0.01 m, rho = 7800 kg/m^3 (printed to 5 digits)
    assert beam.mass == pytest.approx(6.1261, abs=5e-5)
    assert rod.position == (0.5, 0.0) and rod.direction == 0.0
    assert scene.hub.mass == 100.0 and scene.hub.inertia == 50.0
    # the file's degrees are radians inside: 10 deg exactly
    assert scene.manoeuvre.slew_angle == pytest.approx(math.radians(10.0), rel=1e-15)
    assert scene.manoeuvre.step == 0.1 and scene.manoeuvre.duration == 200.0
    assert scene.fidelity.tolerance == 1e-3 and scene.fidelity.n_modes is None
    assert scene.design_variants == ("poles-and-zeros", "frequencies")
    assert scene.controller.types == ("pd", "lqr")
    assert scene.export.fmu and set(scene.export.systems) == {"plant", "controller", "closed_loop"}
    assert set(scene.report.plots) == {"slew", "loop", "poles", "W"}
    assert scene.outputs.tip_deflection


def test_direction_in_degrees_or_as_a_vector():
    by_angle = load_scene(scene_with(**{"appendages.0.direction": 135.0}))
    by_vector = load_scene(scene_with(**{"appendages.0.direction": [-1.0, 1.0]}))
    # atan2(1, -1) = 3 pi / 4 exactly up to round-off
    assert by_angle.appendages[0].direction == pytest.approx(3 * math.pi / 4, rel=1e-15)
    assert by_vector.appendages[0].direction == pytest.approx(3 * math.pi / 4, rel=1e-15)


def test_scene_error_is_a_flexsat_error():
    assert issubclass(SceneError, FlexsatError)


@pytest.mark.parametrize("changes, match", [
    # unknown keys, at the top, nested and in an array of tables
    ({"colour": "red"}, r"<dict>: colour: unknown key"),
    ({"appendages.0.beam.diamter": 0.01}, r"appendages\[0\]\.beam\.diamter: (unknown key|does not)"),
    ({"hub.volume": 1.0}, r"hub\.volume: unknown key"),
    # wrong types
    ({"hub.mass": "heavy"}, r"hub\.mass: must be a number \[kg\]; got string 'heavy'"),
    ({"appendages.0.position": 0.5}, r"appendages\[0\]\.position: must be an array"),
    ({"fidelity.prune": 1}, r"fidelity\.prune: must be true or false"),
    ({"fidelity.n_modes": 2.5}, r"fidelity\.n_modes: must be an integer"),
    # missing required values
    ({"hub.inertia": None}, r"hub\.inertia: missing required value"),
    ({"appendages.0.beam.diameter": None}, r"appendages\[0\]\.beam\.diameter: missing"),
    ({"controller": None}, r"controller: missing required value"),
    # negative, zero and NaN physical values
    ({"appendages.0.beam.diameter": -0.01},
     r"appendages\[0\]\.beam\.diameter: must be positive \[m\]; got -0\.01"),
    ({"hub.mass": 0.0}, r"hub\.mass: must be positive \[kg\]"),
    ({"appendages.0.beam.density": math.nan}, r"appendages\[0\]\.beam\.density: must be finite"),
    ({"appendages.0.beam.damping_ratio": 1.5}, r"damping_ratio: must be below 1"),
    ({"manoeuvre.slew_angle": 0.0}, r"manoeuvre\.slew_angle: must be non-zero"),
    ({"controller.sample_rate": 10.0}, r"manoeuvre\.step: must equal the controller's sample "
                                       r"time 1/sample_rate = 0\.1 s"),
    # bad choices
    ({"appendages.0.beam.section": "hexagon"}, r"section: must be one of 'rod'"),
    ({"appendages.0.fit.match": ["frequencies", "frequencies"]}, r"match\[1\]: .* listed twice"),
    ({"fidelity.tolerance": 1e-3}, r"fidelity: give n_modes or tolerance, not both"),
    # outputs the scene cannot produce
    ({"report.plots": ["slew"], "manoeuvre": None}, r"report\.plots: asks for 'slew'"),
    ({"controller.types": ["lqr"], "controller.pd": None,
      "controller.lqr": {"attitude_weight": 1.0, "torque_weight": 1.0, "deflection_weight": 1.0}},
     r"controller\.lqr\.deflection_weight: needs tip-deflection outputs"),
    ({"manoeuvre.disturbance": {"input": "wing_tip_force", "amplitude": 1.0}},
     r"manoeuvre\.disturbance\.input: must be one of .*'rod_tip_force'"),
    # typos: the closest known key is named, also for a misspelt required key
    ({"appendages.0.beam.youngs_modulus": None, "appendages.0.beam.youngs_modulu": 2e11},
     r"appendages\[0\]\.beam\.youngs_modulus: missing required value \(is 'youngs_modulu' a "
     r"misspelling of 'youngs_modulus'\?\)"),
    ({"controller.pid": {"natural_frequency": 0.1}, "controller.pd": None},
     r"controller\.pid: unknown key; expected one of .*; did you mean 'pd'\?"),
    ({"manoeuvre.slew_tme": 60.0, "manoeuvre.slew_time": None},
     r"manoeuvre\.slew_time: missing required value \(is 'slew_tme' a misspelling"),
    ({"hub.inertai": 50.0}, r"hub\.inertai: unknown key; expected one of inertia, mass; did "
                            r"you mean 'inertia'\?"),
    # FMI versions, SSP, simulator
    ({"export.fmi_version": "4.0"}, r"export\.fmi_version\[0\]: must be one of '2\.0', '3\.0'"),
    ({"export.ssp": True, "export.systems": ["plant", "closed_loop"]},
     r"export\.ssp: needs both 'plant' and 'controller'"),
    ({"simulator.name": "simulink"}, r"simulator\.name: must be one of 'flexsat', 'basilisk'"),
    ({"simulator.dt": 0.01}, r"simulator: sample_rate, dt and reaction_wheel apply to name = "
                             r"'basilisk' only"),
    ({"simulator.name": "basilisk", "appendages.0.design": "truth", "appendages.0.fit": None},
     r"appendages\[0\]\.design: Basilisk simulates the design chains"),
    ({"simulator.name": "basilisk", "simulator.sample_rate": 10.0, "simulator.dt": 0.5},
     r"simulator\.dt: must not exceed the flight-software sample time"),
])
def test_bad_scenes_name_the_key_and_the_problem(changes, match):
    with pytest.raises(SceneError, match=match):
        load_scene(scene_with(**changes))


def test_exact_reference_needs_a_beam_truth():
    chain = {"lengths": [1.0, 1.0], "masses": [1.0, 1.0], "inertias": [0.1, 0.1],
             "hinge_stiffnesses": [10.0]}
    data = scene_with(**{"appendages.0.beam": None, "appendages.0.fit": None,
                         "appendages.0.chain": chain, "outputs.exact_reference": True})
    with pytest.raises(SceneError, match=r"outputs\.exact_reference: needs an appendage whose "
                                         r"truth has an exact W \(a distributed beam, truth = "
                                         r"'beam', or modal data, truth = 'modal'\)"):
        load_scene(data)
    del data["outputs"]
    assert load_scene(data).appendages[0].truth == "chain"


def test_chain_array_sizes_are_checked_per_hinge():
    chain = {"lengths": [1.0, 1.0], "masses": [1.0, 1.0], "inertias": [0.1, 0.1],
             "hinge_stiffnesses": [10.0], "root": "hinged"}
    data = scene_with(**{"appendages.0.beam": None, "appendages.0.fit": None,
                         "appendages.0.chain": chain})
    with pytest.raises(SceneError, match=r"appendages\[0\]\.chain\.hinge_stiffnesses: must have "
                                         r"2 entries, one per hinge \(root = 'hinged'\)"):
        load_scene(data)


def test_errors_name_the_file(tmp_path):
    path = tmp_path / "boom.toml"
    path.write_text('[hub]\nmass = 100.0\ninertia = -5.0\n')
    with pytest.raises(SceneError, match=r"boom\.toml: hub\.inertia: must be positive"):
        load_scene(path)
    path.write_text("[hub\nmass = 1")
    with pytest.raises(SceneError, match=r"boom\.toml: invalid TOML"):
        load_scene(path)
    with pytest.raises(SceneError, match=r"missing\.toml: no such scene file"):
        load_scene(tmp_path / "missing.toml")


def test_toml_nan_is_rejected(tmp_path):
    path = tmp_path / "nan.toml"
    path.write_text("[hub]\nmass = nan\ninertia = 1.0\n")
    with pytest.raises(SceneError, match=r"nan\.toml: hub\.mass: must be finite \[kg\]; got nan"):
        load_scene(path)


def test_digital_controllers_and_loops_can_be_exported():
    """FMUs of sampled systems are Co-Simulation FMUs that sample at their own period: a digital
    controller's export is no longer refused."""
    scene = load_scene(scene_with(**{"controller.sample_rate": 2.0, "manoeuvre.step": None,
                                     "export.fmu": True, "export.fmi_version": ["2.0", "3.0"],
                                     "export.ssp": True}))
    assert scene.controller.sample_time == 0.5 and scene.manoeuvre.step == 0.5
    assert scene.export.fmi_versions == ("2.0", "3.0") and scene.export.ssp


def test_old_plot_names_are_accepted():
    scene = load_scene(scene_with(**{"report.plots": ["bode", "pole_zero", "slew"]}))
    assert scene.report.plots == ("W", "poles", "slew")


def test_basilisk_simulator_takes_the_digital_controllers_rate():
    scene = load_scene(scene_with(**{"simulator.name": "basilisk", "controller.sample_rate": 10.0,
                                     "manoeuvre.step": None}))
    assert scene.simulator.name == "basilisk" and scene.simulator.sample_time == 0.1
    wheel = load_scene(scene_with(**{"simulator.name": "basilisk",
                                     "simulator.reaction_wheel": {"spin_inertia": 0.05}}))
    assert wheel.simulator.reaction_wheel.spin_inertia == 0.05


def test_resolved_scene_is_json_ready():
    import json

    from spacecraft.scene.read import scene_dict

    data = scene_dict(load_scene(None))
    text = json.dumps(data, allow_nan=False)   # no NaN or inf anywhere
    back = json.loads(text)
    assert back["manoeuvre"]["slew_angle"] == pytest.approx(math.radians(10.0), rel=1e-15)
    assert back["appendages"][0]["beam"]["dimensions"] == {"diameter": 0.01}
    assert back["controller"]["types"] == ["pd", "lqr"] and "SI" in back["units"]


def test_an_embedded_scene_loads_by_name_and_a_typo_suggests_it(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)   # no file of that name here
    scene = load_scene("two_wings")
    assert scene.source == "two_wings (embedded scene)"
    assert [a.name for a in scene.appendages] == [a.name for a in
                                                  load_scene(scene_path("two_wings")).appendages]
    with pytest.raises(SceneError, match=r"two_wing: no such scene file or embedded scene .*did "
                                         r"you mean 'two_wings'\?"):
        load_scene("two_wing")
    # a path that looks like a file keeps the file's message
    with pytest.raises(SceneError, match=r"two_wings\.toml: no such scene file"):
        load_scene("two_wings.toml")
