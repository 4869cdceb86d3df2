"""Three-axis scenes (issue 11, item 5): the keys (hub inertia tensor, 3-D mount position and
Euler-angle orientation, sections with Poisson's ratio, slew axis), their errors, and the
shipped example run through ``flexsat run three_axis`` with its report and FMUs.

References: the scene's spacecraft against the same spacecraft built in Python (the exact
coupled frequencies agree to the precision of the scene's Euler angles, printed with 6
decimals of a degree: 1e-8 rad, a relative change of the frequencies of that order); the
report's numbers against controllers called directly on the scene's models.
"""

import copy
import json
import math
import tomllib

import numpy as np
import pytest
from fmpy import read_model_description

from appendages import Beam
from spacecraft import Hub, Mount, Spacecraft, cli
from spacecraft.dynamics.kinematics import euler_orientation
from spacecraft.scene.read import SceneError, load_scene, scene_path

AXES = ("x", "y", "z")
SCENE = tomllib.loads(scene_path("three_axis").read_text())


def scene_with(change) -> dict:
    data = copy.deepcopy(SCENE)
    change(data)
    return data


def test_the_shipped_scene_reads_as_three_axes():
    scene = load_scene(scene_path("three_axis"))
    assert scene.three_axis
    np.testing.assert_array_equal(np.array(scene.hub.inertia),
                                  [[950.0, 12.0, -8.0], [12.0, 780.0, 15.0], [-8.0, 15.0, 640.0]])
    for a in scene.appendages:
        R = np.array(a.orientation)
        # euler_orientation's rotation: orthonormal to round-off (1e-15)
        np.testing.assert_allclose(R.T @ R, np.eye(3), rtol=0, atol=1e-15)
        assert len(a.position) == 3 and a.beam.poisson_ratio == 0.3
    boom = scene.appendages[2]
    # the boom along (1, -0.5, -1.2): angles printed to 1e-6 deg (2e-8 rad)
    np.testing.assert_allclose(np.array(boom.orientation)[:, 0],
                               np.array([1.0, -0.5, -1.2]) / math.sqrt(2.69), rtol=0, atol=1e-7)
    # a wing along +y, canted 20 deg about its own axis
    np.testing.assert_allclose(np.array(scene.appendages[0].orientation),
                               euler_orientation("ZYX", (math.pi / 2, 0.0, math.radians(20.0))),
                               rtol=0, atol=1e-15)
    np.testing.assert_allclose(scene.manoeuvre.slew_axis, np.array([1.0, 1.0, 0.5]) / 1.5,
                               rtol=1e-15)
    # the slew axis is off every principal axis of the hub
    _, R = np.linalg.eigh(np.array(scene.hub.inertia))
    assert np.max(np.abs(R.T @ np.array(scene.manoeuvre.slew_axis))) < 0.95


def test_poisson_ratio_reaches_the_beam():
    """G = E / (2 (1 + nu)): GJ scales as 1 / (1 + nu) (closed form of the section)."""
    scene = load_scene(scene_with(lambda d: d["appendages"][2]["beam"].update(poisson_ratio=0.4)))
    default = load_scene(SCENE)
    beam, base = scene.appendages[2].beam.build(), default.appendages[2].beam.build()
    assert beam.torsional_stiffness / base.torsional_stiffness == pytest.approx(1.3 / 1.4,
                                                                                rel=1e-14)
    assert beam.bending_stiffness == base.bending_stiffness


@pytest.mark.parametrize("change, match", [
    (lambda d: d["hub"].update(inertia=[[950.0, 12.0, 0.0], [11.0, 780.0, 0.0], [0, 0, 640.0]]),
     r"hub\.inertia: must be a symmetric tensor \[kg\*m\^2\].*got max \|J - J\^T\| = 1"),
    (lambda d: d["hub"].update(inertia=[[950.0, 900.0, 0.0], [900.0, 780.0, 0.0], [0, 0, 640.0]]),
     r"hub\.inertia: must be positive definite \[kg\*m\^2\]; got principal moments"),
    (lambda d: d["hub"].update(inertia=[[1.0, 0.0], [0.0, 1.0]]),
     r"hub\.inertia: must be a number \(planar\) or a 3x3 array of numbers \[kg m\^2\]"),
    (lambda d: d["hub"].update(inertia=[[1.0, 0.0, "a"], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
     r"hub\.inertia\[0\]\[2\]"),
    (lambda d: d["appendages"][0].update(orientation_sequence="ZZX"),
     r"appendages\[0\]\.orientation_sequence: sequence must be three axes .*no two "
     r"consecutive alike.*got 'ZZX'"),
    (lambda d: d["appendages"][0].update(orientation=[90.0, 0.0]),
     r"appendages\[0\]\.orientation: must have 3 entries \[deg\]; got 2"),
    (lambda d: d["appendages"][0].update(direction=90.0),
     r"appendages\[0\]\.direction: is planar; a three-axis appendage has an orientation"),
    (lambda d: d["appendages"][0].update(position=[0.0, 1.1]),
     r"appendages\[0\]\.position: must have 3 entries \[m\]; got 2"),
    (lambda d: d["appendages"][2]["beam"].update(poisson_ratio=0.6),
     r"appendages\[2\]\.beam\.poisson_ratio"),
    (lambda d: d["appendages"][2].update(beam={"section": "uniform", "length": 4.0,
                                               "bending_stiffness": 1e4, "linear_density": 1.0}),
     r"appendages\[2\]\.beam\.section: a three-axis scene needs the torsional and axial "
     r"properties .*got 'uniform'"),
    (lambda d: d["manoeuvre"].pop("slew_axis"), r"manoeuvre\.slew_axis: missing required value"),
    (lambda d: d["manoeuvre"].update(slew_axis=[0.0, 0.0, 0.0]),
     r"manoeuvre\.slew_axis: must be a non-zero vector"),
    (lambda d: d["manoeuvre"].update(slew_axis="w"),
     r"manoeuvre\.slew_axis: must be 'x', 'y', 'z' or an array of 3 numbers"),
    (lambda d: d.update(wheels={"torque_limit": 0.1, "momentum_limit": 4.0}),
     r"wheels: a three-axis scene needs the wheels' spin axes"),
])
def test_bad_three_axis_keys_are_named(change, match):
    with pytest.raises(SceneError, match=match):
        load_scene(scene_with(change), source="s.toml")


def test_three_axis_keys_in_a_planar_scene_are_refused():
    planar = tomllib.loads(scene_path("two_wings").read_text())
    planar["manoeuvre"]["slew_axis"] = "z"
    with pytest.raises(SceneError, match=r"manoeuvre\.slew_axis: applies to three-axis scenes "
                                         r"only \(hub\.inertia a 3x3 tensor"):
        load_scene(planar)
    planar = tomllib.loads(scene_path("two_wings").read_text())
    planar["appendages"][0]["orientation"] = [0.0, 0.0, 0.0]
    with pytest.raises(SceneError, match=r"appendages\[0\]\.orientation: applies to three-axis"):
        load_scene(planar)


def test_the_exact_verdict_and_basilisk_are_three_axis_keys_too():
    """outputs.exact_reference and simulator.name = "basilisk" are read, not refused, in a
    three-axis scene (the loop judges three-axis loops on the exact beams through W6 and
    flies three-axis designs in Basilisk)."""
    raw = tomllib.loads(scene_path("three_axis").read_text())
    raw["outputs"]["exact_reference"] = True
    raw["simulator"] = {"name": "basilisk"}
    scene = load_scene(raw)
    assert scene.outputs.exact_reference and scene.simulator.name == "basilisk"


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    out = tmp_path_factory.mktemp("run") / "three_axis"
    assert cli.main(["run", "three_axis", "--out", str(out), "--quiet"]) == 0
    return out, json.loads((out / "results.json").read_text())


@pytest.mark.slow
def test_run_writes_the_per_axis_report_plots_fmus_and_ssp(report):
    """The shipped scene through the design loop every scene runs: the planar report's
    sections, per axis where the physics has axes; every plot; FMUs and SSPs of both FMI
    versions; the time series."""
    out, data = report
    assert data["three_axis"] and [r["controller"] for r in data["closed_loops"]] == ["pd", "lqr"]
    text = (out / "report.md").read_text()
    for section in ("## Summary", "## The question", "## Models", "## Controllers",
                    "## Equivalence criterion: wing_left (x-y bending plane)", "## Closed loops",
                    "## Plots", "## FMUs", "## Time series"):
        assert section in text, section
    for row in data["closed_loops"]:
        assert row["verdict"]["stable"]
        assert row["status"]["design"]["status"] == row["status"]["truth"]["status"] == "settles"
        metrics = row["metrics"]["truth"]
        for a in AXES:
            assert f"peak_attitude_error_{a}" in metrics and f"gain_margin_{a}" in row["verdict"]
        for name in ("wing_left", "wing_right", "boom"):
            peaks = row["appendages"]["truth"][name]
            for motion in ("tip_deflection_y", "tip_deflection_z", "tip_twist"):
                assert peaks[f"peak_{motion}"] == metrics[f"peak_{name}_{motion}"]
        # the tip deflection is a deflection's [m], not a twist's [rad]
        assert metrics["peak_tip_deflection"] == max(
            metrics[f"peak_{n}_tip_deflection_{p}"] for n in ("wing_left", "wing_right", "boom")
            for p in "yz")
        # the slew ends at the target: 10 deg about the axis, to 1e-2 of the angle after 120 s
        assert metrics["final_attitude_error"] < 1e-2 * math.radians(10.0)
        assert row["verdict"]["disk_margin"] > 0.5
        # outputs.exact_reference: the loop judged on the exact beams too (MIMO Nyquist through
        # W6); the truth model resolves the loops' band, so its disk margin is the exact one's
        # to the truncation's error (the fidelity's tolerance, 1e-3, with a margin of 10)
        exact = row["exact_verdict"]
        assert exact["stable"] is True
        assert math.isclose(exact["disk_margin"], row["verdict"]["disk_margin"], rel_tol=1e-2)
        # the disturbance (0.05 N m about z for 5 s) moves the attitude about z most
        shock = row["disturbance_metrics"]["truth"]
        assert shock["peak_attitude_error_z"] > max(shock["peak_attitude_error_x"],
                                                    shock["peak_attitude_error_y"])
    for label in ("peak tip deflection y [m]", "peak tip twist [rad]", "disk margin alpha [-]",
                  "peak attitude error about z [rad]", "the disturbance alone"):
        # (Markdown escapes the brackets)
        assert label.replace("[", "\\[").replace("]", "\\]") in text, label
    # the PD's notch at the design model's first flexible mode, on every axis
    pd = data["controllers"]["poles-and-zeros"]["pd"]
    assert pd["notch_spec"] == "first_mode" and pd["n_states"] == 6   # a 2nd-order notch per axis
    assert sorted(data["files"]["plots"]) == ["plots/W.png", "plots/loop.png", "plots/poles.png",
                                              "plots/slew_lqr.png", "plots/slew_pd.png"]
    for p in data["files"]["plots"]:
        assert (out / p).stat().st_size > 10_000
    fmus = {f["path"] for f in data["files"]["fmu"]}
    assert {"fmu/plant.fmu", "fmu/plant_fmi3.fmu", "fmu/lqr_fmi3.fmu",
            "fmu/closed_loop_pd.fmu"} <= fmus
    variables = {v.name: v for v in read_model_description(str(out / "fmu/plant.fmu"))
                 .modelVariables}
    for a in AXES:
        assert variables[f"torque_{a}"].causality == "input"
        assert variables[f"torque_{a}"].unit == "N.m"
        assert variables[f"theta_{a}"].unit == "rad"
    assert variables["boom_tip_twist"].unit == "rad"
    assert variables["wing_left_tip_deflection_z"].unit == "m"
    # an SSP per controller and version connects the plant's three torques and attitudes
    from fmpy.ssp.ssd import read_ssd

    ssps = sorted(f["path"] for f in data["files"]["ssp"])
    assert ssps == ["fmu/loop_lqr.ssp", "fmu/loop_lqr_fmi3.ssp", "fmu/loop_pd.ssp",
                    "fmu/loop_pd_fmi3.ssp"]
    structure = read_ssd(str(out / "fmu/loop_pd.ssp"), validate=True)
    connected = {(c.startElement, c.startConnector) for c in structure.system.connections}
    for a in AXES:
        assert any(name == f"torque_{a}" for _, name in connected)
        assert any(name == f"theta_{a}" for _, name in connected)
    columns = {f["path"]: f for f in data["files"]["timeseries"]}
    series = columns["timeseries/pd_poles-and-zeros_truth.csv"]
    assert series["units"][series["columns"].index("theta_x")] == "rad"
    assert series["units"][series["columns"].index("wing_left_tip_twist")] == "rad"


@pytest.mark.slow
def test_run_frequencies_equal_the_spacecraft_built_in_python(report):
    """The scene's exact coupled frequencies against the example built directly (the boom's
    orientation from its axis; an axisymmetric tube, so its roll does not matter): agreement
    to the precision of the scene's printed angles (1e-7 relative)."""
    from spacecraft import DesignLoop

    _, data = report
    wing = Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8, damping_ratio=0.005)
    boom = Beam.tube(4.0, 0.05, 0.001, 1600.0, 1.2e11, damping_ratio=0.005)
    from spacecraft.dynamics.kinematics import orientation_from_axis

    craft = Spacecraft(Hub(820.0, np.array(SCENE["hub"]["inertia"])), [
        Mount(wing, (0.0, 1.1, 0.0), orientation=euler_orientation("ZYX", (math.pi / 2, 0.0,
                                                                           math.radians(20.0)))),
        Mount(wing, (0.0, -1.1, 0.0), orientation=euler_orientation("ZYX", (-math.pi / 2, 0.0,
                                                                            math.radians(20.0)))),
        Mount(boom, (0.6, 0.3, -0.9), orientation=orientation_from_axis((1.0, -0.5, -1.2)))])
    loop = DesignLoop("three_axis")
    exact = loop.exact_frequencies(12)
    np.testing.assert_allclose(craft.natural_frequencies(exact.size), exact, rtol=1e-7)
    # the run's tolerance was met against these (its reference: the first exact frequency)
    choice = data["fidelity"]["choice"]
    np.testing.assert_allclose(choice["reference_frequencies"],
                               exact[:len(choice["reference_frequencies"])], rtol=1e-12)
    assert choice["trials"][-1]["frequency_error"] <= choice["tolerance"]
    # 10 Craig-Bampton modes per beam converge to them (1e-5; observed 2e-6)
    truth = loop.truth_spacecraft(10)
    np.testing.assert_allclose(truth.natural_frequencies(12), exact, rtol=1e-5)


@pytest.mark.slow
def test_digital_controllers_in_a_three_axis_scene():
    """controller.sample_rate = 10 Hz: PD and LQR discretised, closed as sampled-data loops;
    both stable on the truth model and at the target after 120 s (1e-2 of the slew)."""
    from spacecraft.design.loop import run

    data = run(scene_with(lambda d: (d["controller"].update(sample_rate=10.0),
                                     d["export"].update(fmu=False),
                                     d["report"].update(plots=False)))).data
    for row in data["closed_loops"]:
        assert row["digital"]["sample_time"] == pytest.approx(0.1)
        assert row["verdict"]["stable"] and row["status"]["design"]["status"] == "settles"
        assert row["metrics"]["truth"]["final_attitude_error"] < 1e-2 * math.radians(10.0)
