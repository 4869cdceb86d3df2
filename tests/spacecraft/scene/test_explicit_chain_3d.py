"""An explicit chain in a three-axis scene: its arrays of every motion (x-y and x-z bending,
torsion, axial) reach :class:`appendages.HingedChain` as given, with a rigid or a hinged root,
each changes the spacecraft, bad values are refused by key with unit, expected and got, and a
planar scene refuses the three-axis keys by name.

Reference: the same HingedChain built in Python from the same arrays (bit for bit)."""
import copy

import numpy as np
import pytest

from appendages import HingedChain
from spacecraft import SceneError, load_scene
from spacecraft.design.models import ModelBuilder, RunStats
from scenes import rod_chain, rod_scene

# the rigid finite elements of the small rod scene's 10 m steel rod of 10 mm
# (tests/support/scenes.py), with torsion and axial springs by the lumped rule
CHAIN = rod_chain(three_axis=True)
THREE_D = {"inertias_y": [0.9, 6.0, 0.9], "hinge_stiffnesses_y": [25.0, 25.0],
           "hinge_dampings_y": [0.2, 0.2], "torsion_dampings": [1e-3, 1e-3],
           "axial_dampings": [10.0, 10.0]}
# the same chain with a hinged root: every per-joint array one entry longer, its first the
# joint between mount and body 1 (a drive hinge softer than the others in both bending
# planes, the other motions' root joint as the next)
HINGED = {"root": "hinged", "hinge_stiffnesses": [5.0, 20.2, 20.2],
          "hinge_dampings": [0.05, 0.1, 0.1], "hinge_stiffnesses_y": [8.0, 25.0, 25.0],
          "hinge_dampings_y": [0.1, 0.2, 0.2], "torsion_stiffnesses": [20.7] * 3,
          "torsion_dampings": [1e-3] * 3, "axial_stiffnesses": [4.3e6] * 3,
          "axial_dampings": [10.0] * 3}
# the small rod scene with the chain as the rod's truth and design, no title, manoeuvre, report
# or export tables (planar: no fidelity table either, the PD at its default damping)
_AS_CHAIN = {"appendages.0.beam": None, "appendages.0.fit": None, "appendages.0.truth": "chain",
             "title": None, "manoeuvre": None, "report": None, "export": None}
SCENE = rod_scene(three_axis=True, **_AS_CHAIN, **{"appendages.0.chain": CHAIN})
PLANAR_SCENE = rod_scene(**_AS_CHAIN, **{"appendages.0.chain": rod_chain(), "fidelity": None,
                                         "controller.pd.damping": None})


def _scene(change=None, base=SCENE):
    """The scene with the chain's keys changed (None removes one)."""
    data = copy.deepcopy(base)
    chain = data["appendages"][0]["chain"]
    for key, value in (change or {}).items():
        if value is None:
            chain.pop(key, None)
        else:
            chain[key] = value
    return load_scene(data, source="chain3")


def _built(scene):
    builder = ModelBuilder(scene, None, RunStats())
    spec = scene.appendages[0]
    return builder, builder.chain(spec, spec.chain)


def test_the_arrays_reach_the_chain_as_given():
    scene = _scene(THREE_D)
    _, chain = _built(scene)
    arrays = {**CHAIN, **THREE_D}
    expected = HingedChain(arrays.pop("lengths"), arrays.pop("masses"), arrays.pop("inertias"),
                           arrays.pop("hinge_stiffnesses"), **arrays)
    for name in ("lengths", "masses", "inertias", "hinge_stiffnesses", "hinge_dampings",
                 "com_offsets", "inertias_y", "hinge_stiffnesses_y", "hinge_dampings_y",
                 "torsional_inertias", "torsion_stiffnesses", "torsion_dampings",
                 "axial_stiffnesses", "axial_dampings"):
        np.testing.assert_array_equal(getattr(chain, name), getattr(expected, name), name)
    assert chain.three_axis
    s = np.array([0.3j, 2.0j, 40.0j])
    np.testing.assert_array_equal(chain.W6(s), expected.W6(s))


def test_a_hinged_root_reaches_the_chain_as_given():
    """root = 'hinged': the arrays, one entry per joint with the mount's first, make the same
    HingedChain as Python does from them, bit for bit (its physics against an independent
    Lagrangian model: tests/spacecraft/dynamics/test_three_axis_chain_hub.py), and the root
    joint's springs are in the spacecraft: softer drive hinges lower its frequencies."""
    _, chain = _built(_scene(HINGED))
    arrays = {**CHAIN, **HINGED}
    expected = HingedChain(arrays.pop("lengths"), arrays.pop("masses"), arrays.pop("inertias"),
                           arrays.pop("hinge_stiffnesses"), **arrays)
    assert chain.root == "hinged" and chain.three_axis
    s = np.array([0.3j, 2.0j, 40.0j])
    np.testing.assert_array_equal(chain.W6(s), expected.W6(s))

    def frequencies(change):
        builder, _ = _built(_scene(change))
        return builder.truth_spacecraft(None).frequencies()

    stiff, soft = frequencies(HINGED), frequencies(
        {**HINGED, "hinge_stiffnesses": [2.0, 20.2, 20.2], "hinge_stiffnesses_y": [3.0, 25.0,
                                                                                   25.0]})
    assert stiff.shape == soft.shape
    elastic = stiff > 1e-6 * stiff.max()
    assert np.all(soft[elastic] <= stiff[elastic] * (1 + 1e-12))
    assert np.any(soft[elastic] < stiff[elastic] * (1 - 1e-3))


def test_a_hinged_root_of_rigid_finite_elements_is_refused_in_three_axes():
    """from_beam = 'rfem' takes one drive spring (root_stiffness) about the bending axis: a
    planar notion; a three-axis hinged root gives its arrays."""
    data = copy.deepcopy(SCENE)
    data["appendages"][0]["chain"] = {"from_beam": "rfem", "n_bodies": 3, "root": "hinged",
                                      "root_stiffness": 5.0}
    data["appendages"][0]["beam"] = copy.deepcopy(rod_scene(three_axis=True)["appendages"][0]
                                                  ["beam"])
    with pytest.raises(SceneError) as info:
        load_scene(data, source="chain3")
    message = str(info.value)
    assert "appendages[0].chain.root" in message and "from_beam = 'rfem'" in message, message


def test_without_the_x_z_arrays_the_chain_bends_alike_in_both_planes():
    _, chain = _built(_scene())
    np.testing.assert_array_equal(chain.inertias_y, chain.inertias)
    np.testing.assert_array_equal(chain.hinge_stiffnesses_y, chain.hinge_stiffnesses)
    assert chain.torsion_dampings is None and chain.axial_dampings is None


@pytest.mark.parametrize("key, value", [
    ("inertias_y", [0.9, 6.0, 0.9]), ("hinge_stiffnesses_y", [25.0, 25.0]),
    ("hinge_dampings_y", [0.5, 0.5]), ("torsional_inertias", [1.9e-5, 5.0e-5, 1.9e-5]),
    ("torsion_stiffnesses", [30.0, 30.0]), ("torsion_dampings", [1e-3, 1e-3]),
    ("axial_stiffnesses", [5e6, 5e6]), ("axial_dampings", [10.0, 10.0]),
    ("torsion_stiffnesses", None), ("axial_stiffnesses", None)])
def test_each_array_changes_the_spacecraft(key, value):
    """The coupled poles of the spacecraft with the chain (damped: complex) move when any one
    array changes (None: torsionally rigid or inextensible joints, those modes gone)."""
    def poles(change):
        builder, _ = _built(_scene(change))
        plant, _ = builder.plant(builder.truth_spacecraft(None), "truth", prune=False)
        return np.sort_complex(np.linalg.eigvals(np.asarray(plant.A)))

    before, after = poles({}), poles({key: value})
    assert before.shape != after.shape or not np.allclose(after, before, rtol=1e-9, atol=0)


@pytest.mark.parametrize("change, key, words", [
    ({"torsional_inertias": None}, "chain.torsional_inertias", ""),
    ({"inertias_y": [0.9, 6.0]}, "chain.inertias_y", "must have 3 entries, one per body; got 2"),
    ({"torsion_stiffnesses": [20.0]}, "chain.torsion_stiffnesses",
     "must have 2 entries, one per hinge (root = 'rigid'); got 1"),
    ({"torsional_inertias": [1e-5, -1e-5, 1e-5]}, "chain.torsional_inertias[1]", "kg*m^2"),
    ({"torsional_inertias": [1e-5, 0.0, 1e-5]}, "chain.torsional_inertias[1]", "kg*m^2"),
    ({"hinge_stiffnesses_y": [25.0, -1.0]}, "chain.hinge_stiffnesses_y[1]", "N*m/rad"),
    ({"axial_stiffnesses": [4e6, "stiff"]}, "chain.axial_stiffnesses[1]", "string 'stiff'"),
    ({"axial_dampings": [-1.0, 1.0]}, "chain.axial_dampings[0]", "N*s/m"),
    ({"torsion_stiffnesses": None, "torsion_dampings": [1.0, 1.0]}, "chain.torsion_dampings",
     "needs the springs it damps"),
    ({"root": "hinged"}, "chain.hinge_stiffnesses",
     "must have 3 entries, one per hinge (root = 'hinged'); got 2"),
    ({"inertia_y": [0.9, 6.0, 0.9]}, "chain.inertia_y", ""),
])
def test_bad_arrays_are_refused_by_key(change, key, words):
    with pytest.raises(SceneError) as info:
        _scene(change)
    message = str(info.value)
    assert f"appendages[0].{key}" in message and words in message, message


@pytest.mark.parametrize("key", sorted(THREE_D) + ["torsional_inertias", "torsion_stiffnesses",
                                                   "axial_stiffnesses"])
def test_a_planar_scene_refuses_the_three_axis_keys_by_name(key):
    with pytest.raises(SceneError, match=rf"appendages\[0\]\.chain\.{key}: is a three-axis"):
        _scene({key: {**CHAIN, **THREE_D}[key]}, base=PLANAR_SCENE)


@pytest.mark.parametrize("root", ["rigid", "hinged"])
def test_a_three_axis_appendage_may_be_an_explicit_chain_alone(root):
    """No structure needed beside the arrays (as in a planar scene): the chain, rooted rigidly
    or on a hinge, is truth and design, its loop closes (every motion damped: undamped
    torsion and axial springs would leave marginal modes), and its tip moves in both planes
    and twists."""
    from spacecraft import run

    data = copy.deepcopy(SCENE)
    given = THREE_D if root == "rigid" else HINGED
    data["appendages"][0]["chain"].update(given)   # every motion damped
    data.update(outputs={"tip_deflection": True},
                manoeuvre={"slew_angle": 10.0, "slew_time": 30.0, "duration": 45.0,
                           "step": 0.25, "slew_axis": [1.0, 1.0, 1.0]})
    result = run(load_scene(data, source="chain3"))
    described = result.data["truth"]["models"]["rod"]
    assert described["type"] == "HingedChain"
    for key, value in {**CHAIN, **given}.items():   # results.json gives every array
        assert described[key] == value, key
    (row,) = result.data["closed_loops"]
    assert row["verdict"]["stable"]
    peaks = row["appendages"]["truth"]["rod"]
    assert min(peaks.values()) > 0.0, peaks
    assert not [w for w in result.data["design_warnings"]
                if w["code"] == "truth_output_unmodelled"]
