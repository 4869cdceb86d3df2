"""Scene keys of real appendages: tip bodies, stepped and tapered beams (spacecraft.scene.read).

Each structure read from a scene is the one the Python API builds from the same numbers (bit for
bit: the reader adds no arithmetic); bad values are refused by key, misspelt keys named, values
that look like unit slips warned about by key; a run takes the structure as truth, fits chains to
it and tabulates the fit against its exact W.
"""

from __future__ import annotations

import copy
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from appendages import Beam, HingedChain, SteppedBeam, TipBody
from spacecraft import Hub, Mount, SceneError, Spacecraft, load_scene

ROOT = Path(__file__).resolve().parents[3]
S = np.array([0.3j, 2.0 + 7.0j, 45.0j, 1.0 + 300.0j])

WING_ROOT = {"section": "rectangular", "length": 1.0, "width": 0.3, "thickness": 0.04,
             "density": 2700.0, "youngs_modulus": 7.0e10}
WING_PANEL = {"section": "rectangular", "length": 6.0, "width": 1.0, "thickness": 0.02,
              "density": 1600.0, "youngs_modulus": 7.0e10}
BOOM = {"section": "tube", "length": 4.0, "n_segments": 6,
        "root_dimensions": {"outer_diameter": 0.08, "wall_thickness": 0.002},
        "tip_dimensions": {"outer_diameter": 0.04, "wall_thickness": 0.002},
        "density": 1600.0, "youngs_modulus": 1.0e11, "damping_ratio": 0.003}


def scene_data() -> dict:
    """A hub with a stepped wing carrying a tip body, a tapered boom and a rod with a tip."""
    return {
        "hub": {"mass": 1200.0, "inertia": 800.0},
        "appendages": [
            {"name": "wing", "position": [1.0, 0.0],
             "stepped_beam": {"damping_ratio": 0.005,
                              "segments": [dict(WING_ROOT), dict(WING_PANEL)]},
             "tip": {"mass": 5.0, "inertia": 0.5, "offset": 0.1}},
            {"name": "boom", "position": [0.0, 1.0], "direction": 90.0,
             "tapered_beam": copy.deepcopy(BOOM)},
            {"name": "rod", "position": [0.0, -1.0], "direction": -90.0,
             "beam": {"section": "rod", "length": 3.0, "diameter": 0.02, "density": 7800.0,
                      "youngs_modulus": 2.06e11, "damping_ratio": 0.002},
             "tip": {"mass": 2.0, "inertia": 0.01}},
        ],
        "controller": {"pd": {"natural_frequency": 0.2}},
    }


def python_models():
    """The same three structures built with the Python API."""
    wing = SteppedBeam([Beam.rectangular(1.0, 0.3, 0.04, 2700.0, 7.0e10, damping_ratio=0.005),
                        Beam.rectangular(6.0, 1.0, 0.02, 1600.0, 7.0e10, damping_ratio=0.005)],
                       tip=TipBody(5.0, 0.5, 0.1))
    boom = SteppedBeam.tapered(4.0, 6, section="tube",
                               root_dimensions={"outer_diameter": 0.08, "wall_thickness": 0.002},
                               tip_dimensions={"outer_diameter": 0.04, "wall_thickness": 0.002},
                               density=1600.0, youngs_modulus=1.0e11, damping_ratio=0.003)
    rod = Beam.circular_rod(3.0, 0.02, 7800.0, 2.06e11, damping_ratio=0.002,
                            tip=TipBody(2.0, 0.01))
    return wing, boom, rod


# -- read as the Python API builds them --------------------------------------------------------
@pytest.mark.slow
def test_each_structure_is_the_python_apis_bit_for_bit():
    scene = load_scene(scene_data())
    for spec, model in zip(scene.appendages, python_models()):
        built = spec.beam.build()
        assert type(built) is type(model)
        np.testing.assert_array_equal(built.W(S), model.W(S))
        assert built.mass == model.mass
    kinds = [a.beam.kind for a in scene.appendages]
    assert kinds == ["stepped_beam", "tapered_beam", "beam"]
    assert scene.appendages[0].beam.tip.mass == 5.0 and scene.appendages[1].beam.tip is None


@pytest.mark.slow
def test_defaults_fit_and_truth_of_a_real_appendage():
    scene = load_scene(scene_data())
    for a in scene.appendages:
        assert (a.truth, a.design) == ("beam", "fit")
        # the paper's frequency fit is of a bare uniform rod: not the default here
        assert a.fit.match == ("poles-and-zeros",)
    data = scene_data()
    del data["appendages"][2]["tip"]
    assert load_scene(data).appendages[2].fit.match == ("poles-and-zeros", "frequencies")
    data = scene_data()
    del data["appendages"][1]["tapered_beam"]["n_segments"]
    assert load_scene(data).appendages[1].beam.n_segments == 20


@pytest.mark.slow
def test_rfem_chains_of_every_beam_are_the_python_apis():
    """``chain.from_beam = "rfem"`` divides any beam of a scene (stepped with a tip body,
    tapered, uniform with a tip body) as ``HingedChain.rfem`` divides the same structure, bit
    for bit: its lengths, masses, inertias and hinge stiffnesses, so its mass too."""
    from spacecraft.design.models import ModelBuilder, RunStats

    data = scene_data()
    for appendage in data["appendages"]:
        appendage.update(chain={"from_beam": "rfem", "n_bodies": 4}, design="chain")
    scene = load_scene(data)
    builder = ModelBuilder(scene, None, RunStats())
    for spec, structure in zip(scene.appendages, python_models()):
        got = builder.chain(spec, spec.chain)
        want = HingedChain.rfem(structure, 4)
        for name in ("lengths", "masses", "inertias", "hinge_stiffnesses"):
            np.testing.assert_array_equal(getattr(got, name), getattr(want, name), err_msg=name)


@pytest.mark.slow
def test_a_null_tip_body_is_the_bare_beam():
    data = scene_data()
    data["appendages"][2]["tip"] = {"mass": 0.0}
    beam = load_scene(data).appendages[2].beam.build()
    bare = Beam.circular_rod(3.0, 0.02, 7800.0, 2.06e11, damping_ratio=0.002)
    np.testing.assert_array_equal(beam.W(S), bare.W(S))


@pytest.mark.slow
def test_a_stepped_beam_with_a_uniform_segment_is_planar():
    data = scene_data()
    data["appendages"][0]["stepped_beam"]["segments"][0] = {
        "section": "uniform", "length": 1.0, "bending_stiffness": 1.12e4,
        "linear_density": 32.4}
    beam = load_scene(data).appendages[0].beam.build()
    assert not beam.three_axis and beam.length == 7.0


@pytest.mark.slow
def test_the_resolved_scene_names_each_structure():
    from spacecraft.scene.specs import scene_dict

    resolved = scene_dict(load_scene(scene_data()))
    wing, boom, rod = resolved["appendages"]
    assert wing["beam"]["kind"] == "stepped_beam"
    assert wing["beam"]["segments"][1]["dimensions"] == {"width": 1.0, "thickness": 0.02}
    assert wing["beam"]["tip"] == {"mass": 5.0, "inertia": 0.5, "offset": 0.1}
    assert boom["beam"]["root_dimensions"] == {"outer_diameter": 0.08, "wall_thickness": 0.002}
    assert rod["beam"]["kind"] == "beam" and rod["beam"]["tip"]["mass"] == 2.0


# -- refused by key ------------------------------------------------------------------------------
def _change(edit):
    data = scene_data()
    edit(data)
    return data


@pytest.mark.slow
@pytest.mark.parametrize("edit, match", [
    (lambda d: d["appendages"][0]["tip"].update(mass=-1.0),
     r"appendages\[0\]\.tip\.mass: must be non-negative \[kg\]; got -1\.0"),
    (lambda d: d["appendages"][0]["tip"].update(inertia=[[1, 0, 0], [0, 1, 0], [0, 0, 1]]),
     r"appendages\[0\]\.tip\.inertia: must be a number \[kg m\^2\] in a planar scene"),
    (lambda d: d["appendages"][0]["tip"].update(offset=[0.1, 0.2]),
     r"appendages\[0\]\.tip\.offset: must be a number \[m\] in a planar scene"),
    (lambda d: d["appendages"][0]["tip"].update(mas=1.0),
     r"appendages\[0\]\.tip\.mas: unknown key.*did you mean 'mass'\?"),
    (lambda d: d["appendages"][0]["tip"].pop("mass"),
     r"appendages\[0\]\.tip\.mass: missing required value"),
    (lambda d: d["appendages"][0]["stepped_beam"].update(
        segments=d["appendages"][0]["stepped_beam"].pop("segments") and []),
     r"appendages\[0\]\.stepped_beam\.segments: must be a non-empty array of tables"),
    (lambda d: d["appendages"][0]["stepped_beam"].update(
        segment=d["appendages"][0]["stepped_beam"].pop("segments")),
     r"appendages\[0\]\.stepped_beam\.segments: missing required value \(is 'segment' a "
     r"misspelling of 'segments'\?\)"),
    (lambda d: d["appendages"][0]["stepped_beam"]["segments"][1].update(damping_ratio=0.01),
     r"appendages\[0\]\.stepped_beam\.segments\[1\]\.damping_ratio: a segment has no damping "
     r"ratio of its own"),
    (lambda d: d["appendages"][0]["stepped_beam"]["segments"][1].update(width=-1.0),
     r"segments\[1\]\.width: must be positive \[m\]; got -1\.0"),
    (lambda d: d["appendages"][0]["stepped_beam"]["segments"][0].update(lenght=1.0),
     r"segments\[0\]\.lenght: unknown key.*did you mean 'length'\?"),
    (lambda d: d["appendages"][1]["tapered_beam"].update(n_segments=0),
     r"appendages\[1\]\.tapered_beam\.n_segments: must be at least 1; got 0"),
    (lambda d: d["appendages"][1]["tapered_beam"].update(section="uniform"),
     r"appendages\[1\]\.tapered_beam\.section: must be one of 'rod', 'tube', 'rectangular'"),
    (lambda d: d["appendages"][1]["tapered_beam"]["tip_dimensions"].pop("wall_thickness"),
     r"tapered_beam\.tip_dimensions\.wall_thickness: missing required value"),
    (lambda d: d["appendages"][1]["tapered_beam"]["root_dimensions"].update(
        wall_thickness=0.05), r"root_dimensions\.wall_thickness: must be at most "
                              r"outer_diameter/2 = 0\.04 \[m\]"),
    (lambda d: d["appendages"][1].update(tip={"mass": 1.0}, chain={
        "lengths": [1.0, 1.0], "masses": [1.0, 1.0], "inertias": [0.1, 0.1],
        "hinge_stiffnesses": [10.0]}, tapered_beam=None) or d["appendages"][1].pop(
        "tapered_beam"), r"appendages\[1\]\.tip: a tip body sits at the free end of a beam"),
    (lambda d: d["appendages"][1].update(beam=d["appendages"][2]["beam"]),
     r"appendages\[1\]\.tapered_beam: an appendage is one structure: give one of beam, "
     r"stepped_beam, tapered_beam, modal; got beam and tapered_beam"),
    (lambda d: d["appendages"][0].update(fit={"match": "frequencies"}),
     r"appendages\[0\]\.fit\.match: 'frequencies' \(the paper's fit.*needs a uniform beam "
     r"without a tip body; this appendage is a stepped beam"),
    (lambda d: d["appendages"][2].update(fit={"match": ["poles-and-zeros", "frequencies"]}),
     r"appendages\[2\]\.fit\.match: .*this appendage is a beam with a tip body"),
    (lambda d: d["appendages"][0].update(truth="chain"),
     r"appendages\[0\]\.truth: is 'chain' but the appendage has no chain table"),
    (lambda d: d["appendages"][0]["stepped_beam"]["segments"][1].update(length=1e-2, width=1e-3,
                                                                       thickness=1e-5),
     None),  # legal: a short flimsy segment
    (lambda d: d["appendages"][1]["tapered_beam"].update(youngs_modulus=2.0e5, length=900.0),
     r"appendages\[1\]\.tapered_beam: first bending frequency .* lies outside \[0\.0001, "
     r"100000\] rad/s"),
])
def test_bad_values_are_refused_by_key(edit, match):
    data = _change(edit)
    if match is None:
        load_scene(data)
        return
    with pytest.raises(SceneError, match=match):
        load_scene(data)


@pytest.mark.slow
def test_unit_slips_are_warned_about_by_key():
    data = scene_data()
    data["appendages"][0]["stepped_beam"]["segments"][1]["youngs_modulus"] = 2.0e5
    data["appendages"][0]["stepped_beam"]["damping_ratio"] = 0.5
    data["appendages"][1]["tapered_beam"]["youngs_modulus"] = 1.0e5
    warnings = load_scene(data, source="w.toml").input_warnings
    assert [w.split(": ")[1] for w in warnings] == [
        "appendages[0].stepped_beam.damping_ratio",
        "appendages[0].stepped_beam.segments[1].youngs_modulus",
        "appendages[1].tapered_beam.youngs_modulus"]
    assert warnings[1].endswith("did you give MPa? 200000 MPa = 2e+11 Pa")


def test_three_axis_tip_body_and_sections():
    from spacecraft.scene.read import scene_path
    import tomllib

    with open(scene_path("three_axis"), "rb") as stream:
        data = tomllib.load(stream)
    beam = data["appendages"][0]["beam"]
    data["appendages"][0]["tip"] = {"mass": 3.0, "inertia": [[0.2, 0, 0], [0, 0.1, 0],
                                                             [0, 0, 0.1]],
                                    "offset": [0.1, 0.0, 0.05]}
    tip = load_scene(data).appendages[0].beam.tip
    assert tip.inertia[0] == (0.2, 0.0, 0.0) and tip.offset == (0.1, 0.0, 0.05)
    data["appendages"][0]["tip"]["inertia"] = 0.1
    with pytest.raises(SceneError, match=r"tip\.inertia: must be a 3x3 array \[kg m\^2\] in a "
                                         r"three-axis scene"):
        load_scene(data)
    data["appendages"][0]["tip"]["inertia"] = [[1.0, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]
    with pytest.raises(SceneError, match=r"tip\.inertia: must be a rigid body's inertia"):
        load_scene(data)
    data["appendages"][0]["tip"]["inertia"] = [[0.2, 0.1, 0], [0, 0.1, 0], [0, 0, 0.1]]
    with pytest.raises(SceneError, match=r"tip\.inertia: must be symmetric"):
        load_scene(data)
    del data["appendages"][0]["tip"]
    del data["appendages"][0]["beam"]
    beam.pop("damping_ratio", None)
    data["appendages"][0]["stepped_beam"] = {"segments": [
        {**beam, "length": 2.0}, {"section": "uniform", "length": 2.0,
                                  "bending_stiffness": 100.0, "linear_density": 1.0}]}
    with pytest.raises(SceneError, match=r"stepped_beam\.segments\[1\]\.section: a three-axis "
                                         r"scene needs the torsional"):
        load_scene(data)


# -- a run -----------------------------------------------------------------------------------------
@pytest.mark.slow
def test_a_run_takes_the_structures_as_truth_and_fits_chains_to_them(tmp_path):
    """Exact coupled frequencies through the structures' W (against the Python API's spacecraft:
    the same numbers), chains that keep each structure's mass, first moment and inertia, and an
    equivalence table against each structure's exact W without the paper's columns."""
    from spacecraft import run, write_report, output_folder

    data = scene_data()
    data["fidelity"] = {"n_modes": 4}
    data["outputs"] = {"exact_reference": True}
    data["export"] = {"fmu": False}
    data["report"] = {"plots": False}
    result = run(load_scene(data, source="real.toml"))   # no manoeuvre: no simulation
    hub = Hub(1200.0, 800.0)
    mounts = [Mount(m, p, d) for m, p, d in zip(
        python_models(), [(1.0, 0.0), (0.0, 1.0), (0.0, -1.0)], [0.0, np.pi / 2, -np.pi / 2])]
    exact = Spacecraft(hub, mounts).natural_frequencies(8, exact=True)
    # the same Wittrick-Williams roots of the same W: to the bisection's tolerance
    np.testing.assert_allclose(result.data["exact"]["coupled_frequencies"], exact, rtol=1e-9)
    for a, model in zip(("wing", "boom", "rod"), python_models()):
        chain = result.models[a]["fits"]["poles-and-zeros"]
        assert isinstance(chain, HingedChain)
        # m, S and J kept exactly by construction: to round-off
        np.testing.assert_allclose([chain.mass, chain.center_of_mass, chain.inertia],
                                   [model.mass, model.center_of_mass, model.inertia],
                                   rtol=1e-10)
    tables = {t["appendage"]: t for t in result.data["equivalence"]}
    assert tables["wing"]["reference"] == "stepped beam with tip body (exact)"
    assert tables["rod"]["reference"] == "beam with tip body (exact)"
    assert [c["name"] for c in tables["wing"]["columns"]] == ["chain, flexsat fit"]
    assert "neither is a column" in tables["wing"]["notes"][0]
    # the fitted chain's first free-free frequency, a target of the fit weighted 10x
    w = tables["boom"]["quantities"].index("w1")
    assert abs(tables["boom"]["columns"][0]["relative_error"][w]) < 1e-3
    with output_folder(tmp_path / "out") as folder:
        write_report(result, folder)
    report = (tmp_path / "out" / "report.md").read_text()
    assert "stepped beam of 2 segments from the root" in report
    assert "tip body 5 kg, 0.5 kg m^2, centre 0.1 m beyond the free end" in report
    assert "tapered tube, length 4 m, outer_diameter 0.08 to 0.04" in report


# -- the command line --------------------------------------------------------------------------------
def _flexsat(*args):
    return subprocess.run([sys.executable, "-m", "spacecraft.cli", *args], capture_output=True,
                          text=True, cwd=ROOT, timeout=600)


SCENE_TOML = """
[hub]
mass = 1200.0
inertia = 800.0

[[appendages]]
name = "wing"
[appendages.stepped_beam]
damping_ratio = 0.005
[[appendages.stepped_beam.segments]]
section = "rectangular"
length = 1.0
width = 0.3
thickness = 0.04
density = 2700.0
youngs_modulus = 7.0e10
[[appendages.stepped_beam.segments]]
section = "rectangular"
length = 6.0
width = 1.0
thickness = 0.02
density = 1600.0
youngs_modulus = 7.0e10
[appendages.tip]
mass = 5.0
inertia = 0.5
offset = 0.1

[controller.pd]
natural_frequency = 0.2
"""


@pytest.mark.slow
def test_table_and_fit_take_any_appendage_of_a_scene(tmp_path):
    path = tmp_path / "wing.toml"
    path.write_text(SCENE_TOML)
    done = _flexsat("table", "--scene", str(path), "--appendage", "wing", "--quiet")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("stepped beam with tip body (") and "mass 229.4 kg" in lines[0]
    assert lines[1].split() [:7] == ["quantity", "stepped", "beam", "with", "tip", "body",
                                     "(exact)"]
    assert "beam, 2 modes (paper)" not in done.stdout
    assert lines[-1].startswith("The paper's two-mode free-free beam and its frequency fit")
    done = _flexsat("fit", "--scene", str(path), "--json", "--quiet")
    assert done.returncode == 0, done.stderr
    import json

    fitted = json.loads(done.stdout)
    assert fitted["beam"]["kind"] == "stepped beam with tip body"
    assert fitted["chain"]["mass"] == pytest.approx(229.4, rel=1e-12)
    done = _flexsat("fit", "--scene", str(path), "--appendage", "boom", "--quiet")
    assert done.returncode == 2 and "has no such appendage (it has wing)" in done.stderr


@pytest.mark.slow
def test_the_command_line_tip_body_and_a_refused_paper_fit():
    done = _flexsat("fit", "--tip-mass", "0.5", "--tip-inertia", "0.001", "--match",
                    "frequencies", "--quiet")
    assert done.returncode == 2
    assert "--match frequencies (the paper's fit" in done.stderr
    assert "this is a beam with tip body: use --match poles-and-zeros" in done.stderr
    done = _flexsat("fit", "--tip-offset", "0.1", "--quiet")
    assert done.returncode == 2 and "give its --tip-mass [kg] too" in done.stderr
