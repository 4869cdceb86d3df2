"""Scene keys of modal appendages (``appendages[i].modal``): a modal data file, a NASTRAN
solution or the numbers in the scene, read into the Python API's ModalAppendage.

Data: the NASTRAN boom of the embedded scene real_appendages (spacecraft/scene/embedded/data, from
tests/data/nastran: pyNastran's BSD-licensed solver output). The three sources of the same data
give the same appendage (bit for bit where no arithmetic is added: the file format writes every
number's shortest repr); bad values are refused by key and paths are the scene's folder's.
"""

from __future__ import annotations

import copy
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from appendages import ModalAppendage, read_nastran, write_modal_data
from spacecraft import Hub, Mount, SceneError, Spacecraft, load_scene
from spacecraft.scene.read import scene_path

DATA = Path(scene_path("real_appendages")).parent / "data"
S = np.array([0.5j, 2.0 + 300.0j, 3000.0j, 10.0 + 2.0e4j])


def nastran_boom(**options) -> ModalAppendage:
    """The boom as the Python API reads it (three-axis)."""
    return read_nastran(DATA / "boom_modes.npz", root=1, units=("in", "slinch"),
                        mass_matrix=np.load(DATA / "boom_mass.npy"), tip=11, **options)


def scene(modal: dict, **appendage) -> dict:
    return {"hub": {"mass": 1200.0, "inertia": 900.0},
            "appendages": [{"name": "boom", "position": [0.0, 1.0], "direction": 90.0,
                            "modal": modal, **appendage}],
            "controller": {"pd": {"natural_frequency": 0.1}}}


NASTRAN = {"nastran": str(DATA / "boom_modes.npz"), "root": 1, "units": ["in", "slinch"],
           "mass_matrix": str(DATA / "boom_mass.npy"), "tip_grid": 11, "damping": 0.003}


def test_a_nastran_solution_is_the_python_apis_planar_view_bit_for_bit():
    spec = load_scene(scene(NASTRAN)).appendages[0]
    assert (spec.truth, spec.design, spec.fit.match) == ("modal", "fit", ("poles-and-zeros",))
    built = spec.modal.build()
    boom = nastran_boom(damping=0.003).planar_view("xy")
    np.testing.assert_array_equal(built.W(S), boom.W(S))
    np.testing.assert_array_equal(built.frequencies, boom.frequencies)
    m = spec.modal
    assert (m.n_modes, m.has_tip_motion, m.damping_range) == (4, True, (0.003, 0.003))
    assert m.mass == boom.mass and m.first_frequency == boom.frequencies[0]


def test_the_modal_data_file_and_the_numbers_give_the_same_appendage(tmp_path):
    """The TOML route (units in the file, mm and g here) and the numbers in the scene (SI)."""
    boom = nastran_boom(damping=0.003)
    write_modal_data(boom, tmp_path / "boom.toml")
    from_file = load_scene(scene({"file": "boom.toml"}), base=tmp_path).appendages[0].modal
    np.testing.assert_array_equal(from_file.build().W(S), boom.planar_view("xy").W(S))
    planar = boom.planar_view("xy")
    inline = {"frequencies": planar.frequencies.tolist(),
              "participation": planar.participation.tolist(),
              "rigid_mass": planar.rigid_mass.tolist(), "tip_motion": planar.tip_motion.tolist(),
              "damping": 0.003, "length": planar.length}
    np.testing.assert_array_equal(load_scene(scene(inline)).appendages[0].modal.build().W(S),
                                  planar.W(S))
    hz = dict(inline, frequencies_hz=(planar.frequencies / (2 * np.pi)).tolist())
    del hz["frequencies"]
    np.testing.assert_allclose(load_scene(scene(hz)).appendages[0].modal.build().frequencies,
                               planar.frequencies, rtol=1e-15)
    # the scene's damping, length and n_modes replace the file's
    kept = load_scene(scene({"file": "boom.toml", "damping": 0.02, "n_modes": 6, "length": 0.3}),
                      base=tmp_path).appendages[0].modal
    # modes 1-2 and 3-4 are the round rod's twins, 5 torsion, 6 axial: the x-y plane sees two
    assert kept.n_modes == 2 and kept.damping_range == (0.02, 0.02)
    assert kept.build().length == 0.3


def test_paths_are_relative_to_the_scene_file(tmp_path, monkeypatch):
    folder = tmp_path / "scenes"
    (folder / "fe").mkdir(parents=True)
    for name in ("boom_modes.npz", "boom_mass.npy"):
        shutil.copy(DATA / name, folder / "fe" / name)
    (folder / "boom.toml").write_text(
        '[hub]\nmass = 1200.0\ninertia = 900.0\n[[appendages]]\nname = "boom"\n'
        '[appendages.modal]\nnastran = "fe/boom_modes.npz"\nroot = 1\n'
        'units = ["in", "slinch"]\nmass_matrix = "fe/boom_mass.npy"\n'
        '[controller.pd]\nnatural_frequency = 0.1\n')
    monkeypatch.chdir(tmp_path)
    modal = load_scene(folder / "boom.toml").appendages[0].modal
    assert modal.path == str((folder / "fe" / "boom_modes.npz").resolve())
    assert not modal.has_tip_motion
    with pytest.raises(SceneError, match=r"appendages\[0\]\.modal\.nastran: no such file: .*"
                                         r"a path relative to the scene's folder"):
        load_scene(scene(dict(NASTRAN, nastran="fe/boom_modes.npz")))


@pytest.mark.parametrize("edit, match", [
    (lambda m: m.update(file="boom.toml"),
     r"modal\.nastran: give one source of modal data; got file and nastran"),
    (lambda m: m.pop("root"), r"modal\.root: missing required value"),
    (lambda m: m.update(units=["inch", "slinch"]),
     r"modal\.units: the length unit must be one of 'm', 'mm', .*; got 'inch'; did you mean "
     r"'in'\?"),
    (lambda m: m.update(units="SI"), r"modal\.units: must be \[length unit, mass unit\]"),
    (lambda m: m.update(root=2), r"modal\.nastran: .*the root grid 2 moves in mode 1"),
    (lambda m: m.update(mass_matrix=str(DATA / "README.md")),
     r"modal\.mass_matrix: must be a \.npy or \.npz file"),
    (lambda m: m.update(tip_motion=[0.1]),
     r"modal\.tip_motion: does not apply to modal data from a NASTRAN solution; it takes "
     r"axes, damping, length, mass_matrix, n_modes, nastran, root, subcase, tip_grid, units"),
    (lambda m: m.update(damping=2.0),
     r"modal\.damping: must be below 1 \[-\].*; did you give per cent\? 2 % = 0\.02"),
    (lambda m: m.update(n_modes=0), r"modal\.n_modes: must be at least 1; got 0"),
    (lambda m: m.update(n_modes=11),
     r"modal\.nastran: n_modes must be between 1 and 10 \(the modes of the data\)"),
    (lambda m: m.update(axes=[[1, 0], [0, 1]]), r"modal\.axes: must have 3 rows"),
    (lambda m: m.update(rootgrid=1), r"modal\.rootgrid: unknown key.*did you mean 'root'\?"),
    (lambda m: m.clear() or m.update(frequencies=[10.0, 20.0], participation=[[1.0, 2.0]],
                                     rigid_mass=[[5.0, 10.0], [10.0, 30.0]]),
     r"modal\.participation: must have 2 rows"),
    (lambda m: m.clear() or m.update(frequencies=[10.0], participation=[[1.0, 2.0]],
                                     rigid_mass=[[5.0, 10.0, 0.0], [10.0, 30.0, 0.0]]),
     r"modal\.rigid_mass: must have rows of 2 or 6 numbers"),
    (lambda m: m.clear() or m.update(frequencies=[10.0], participation=[[1.0, 2.0]],
                                     rigid_mass=[[5.0, 10.0], [10.0, 30.0]]),
     r"modal\.length: missing: the data do not give the appendage's length"),
    (lambda m: m.clear() or m.update(frequencies=[10.0], participation=[[3.0, 2.0]],
                                     rigid_mass=[[5.0, 10.0], [10.0, 30.0]], length=4.0),
     r"appendages\[0\]\.modal: .*effective masses exceed"),
    (lambda m: m.clear() or m.update(frequencies=[20.0, 10.0], participation=[[1.0, 2.0]] * 2,
                                     rigid_mass=[[5.0, 10.0], [10.0, 30.0]], length=4.0),
     r"appendages\[0\]\.modal: frequencies must be"),
    (lambda m: m.clear(), r"appendages\[0\]\.modal: needs its data: file = "),
])
def test_bad_modal_values_are_refused_by_key(edit, match):
    modal = copy.deepcopy(NASTRAN)
    edit(modal)
    with pytest.raises(SceneError, match=match):
        load_scene(scene(modal))


@pytest.mark.parametrize("appendage, match", [
    ({"tip": {"mass": 1.0}}, r"appendages\[0\]\.tip: a tip body sits at the free end of a beam.*"
                             r"modal data carry their tip body in the finite-element model"),
    ({"fit": {"match": "frequencies"}},
     r"fit\.match: 'frequencies' .*this appendage is given by modal data"),
    ({"truth": "beam"}, r"truth: is 'beam' but .*its modal data are truth = 'modal'"),
    ({"beam": {"section": "rod", "length": 1.0, "diameter": 0.01, "density": 7800.0,
               "youngs_modulus": 2e11}}, r"an appendage is one structure.*got beam and modal"),
    ({"chain": {"from_beam": "rfem", "n_bodies": 3}, "design": "chain"},
     r"chain\.from_beam: 'rfem' .*needs a beam, stepped_beam or tapered_beam table"),
])
def test_what_modal_data_cannot_have(appendage, match):
    with pytest.raises(SceneError, match=match):
        load_scene(scene(copy.deepcopy(NASTRAN), **appendage))


def test_a_damping_ratio_in_per_cent_is_warned_about_by_key():
    lines = load_scene(scene(dict(NASTRAN, damping=0.3)), source="m.toml").input_warnings
    assert list(lines) == ["m.toml: appendages[0].modal.damping: above 0.2, more than structures have "
                           "(1e-4 to 0.05 without added dampers); did you give per cent? 0.3 % "
                           "= 0.003"]


def test_tip_outputs_of_modal_data_without_tip_motion_are_warned_about():
    """Before: the tip deflection of such an appendage was silently zero."""
    boom = nastran_boom(damping=0.003).planar_view("xy")
    bare = ModalAppendage(boom.frequencies, boom.participation, boom.rigid_mass,
                          damping=0.003, length=boom.length)
    craft = Spacecraft(Hub(1200.0, 900.0), [Mount(bare, (0.0, 1.0), np.pi / 2, name="boom")])
    with pytest.warns(UserWarning, match=r"appendage 'boom': its modal data have no tip motion .*"
                                         r"its tip deflection outputs are zero"):
        craft.plant(tip_deflection=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        craft.plant()
        Spacecraft(Hub(1200.0, 900.0), [Mount(boom, (0.0, 1.0), np.pi / 2)]).plant(
            tip_deflection=True)
    from spacecraft import run

    data = scene(dict(NASTRAN, tip_grid=None))
    del data["appendages"][0]["modal"]["tip_grid"]
    data["outputs"] = {"tip_deflection": True}
    lines = run(load_scene(data), time_responses=False).data["warnings"]
    assert any("appendage 'boom': its modal data have no tip motion" in line for line in lines)


def test_three_axis_needs_six_axis_data():
    import tomllib

    with open(scene_path("three_axis"), "rb") as stream:
        data = tomllib.load(stream)
    appendage = data["appendages"][0]
    del appendage["beam"]
    appendage["modal"] = {"frequencies": [10.0], "participation": [[1.0, 2.0]],
                          "rigid_mass": [[5.0, 10.0], [10.0, 30.0]], "length": 4.0}
    with pytest.raises(SceneError, match=r"modal\.participation: must have rows of 6 numbers"):
        load_scene(data)
    appendage["modal"] = copy.deepcopy(NASTRAN)
    boom = load_scene(data).appendages[0].modal
    assert boom.n_modes == 10 and not boom.planar
    assert boom.build().three_axis


def _pynastran_works() -> bool:
    from appendages import nastran

    try:
        nastran._import_read_op2()
    except ImportError:
        return False
    return True


@pytest.mark.skipif(not _pynastran_works(), reason="pyNastran missing or not importable "
                                                   "(pip install \"flexsat[nastran]\")")
def test_the_op2_file_itself_gives_the_extracts_appendage():
    op2 = Path(__file__).parent.parent.parent / "data" / "nastran" / "beam_modes.op2"
    from_op2 = load_scene(scene(dict(NASTRAN, nastran=str(op2)))).appendages[0].modal.build()
    from_npz = load_scene(scene(NASTRAN)).appendages[0].modal.build()
    np.testing.assert_array_equal(from_op2.W(S), from_npz.W(S))


@pytest.mark.slow
def test_table_and_fit_take_a_scenes_modal_appendage():
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-m", "spacecraft.cli", "table", "--scene",
                           "real_appendages", "--appendage", "boom", "--quiet"],
                          capture_output=True, text=True, timeout=600,
                          cwd=Path(__file__).resolve().parents[3])
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("modal data (real_appendages (embedded scene): boom): length "
                               "0.254 m, mass 4.5717 kg")
    assert "modal data (FE-exact)" in lines[1]
    assert lines[-1].startswith("The gains k_r of modal data, lim s^2 W_r, are the inverse of "
                                "their residual mass")
