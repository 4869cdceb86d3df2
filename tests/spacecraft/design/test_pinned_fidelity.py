"""``fidelity.modes_per_motion``: the modes a run from ``fidelity.tolerance`` chooses per motion,
pinned beside ``fidelity.n_modes``, so that a scene (a sweep's sample, a worst case written out)
reruns the very truth model the tolerance chose.

References: the tolerance run itself (the pinned run must build the same truncations, so every
number of its closed loops is the same), the truncation's own per-motion counts, and the
counting rule of :func:`spacecraft.scene.limits.estimate_cost` worked out by hand.
"""
import copy
import math
import tomllib

import numpy as np
import pytest

from spacecraft.design.loop import DesignLoop, run
from spacecraft.scene.limits import estimate_cost
from spacecraft.scene.read import SceneError, load_scene, scene_path
from scenes import rod_scene

# the small rod scene (tests/support/scenes.py), in three axes and in the plane
THREE_AXIS = rod_scene(three_axis=True)
PLANAR = rod_scene()


def _scene(base: dict, **fidelity) -> dict:
    raw = copy.deepcopy(base)
    raw["fidelity"].update(fidelity)
    return raw


def _numbers(value, path=""):
    """Every number of a results tree, by path (lists by index)."""
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _numbers(v, f"{path}.{k}")
    elif isinstance(value, list):
        for k, v in enumerate(value):
            yield from _numbers(v, f"{path}[{k}]")
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        yield path, float(value)


# -- honoured ------------------------------------------------------------------------------------
@pytest.mark.slow
def test_the_pinned_modes_rerun_the_truth_the_tolerance_chose():
    """The shipped three-axis scene, run from its tolerance, and again with the n_modes and
    per-motion modes that run reports (``fidelity.choice.tip.floors``): the same truth models
    (modes per motion, coupled frequencies) and the same closed loops, number for number (the
    same truncations build the same matrices: only the timing may differ)."""
    raw = tomllib.loads(scene_path("three_axis").read_text())
    raw["export"] = {"fmu": False}
    raw["report"] = {"plots": False}
    chosen = run(load_scene(copy.deepcopy(raw), source="tolerance")).data
    floors = chosen["fidelity"]["choice"]["tip"]["floors"]
    assert floors and any(f.get("torsion", 1) > 1 for f in floors.values())
    raw["fidelity"] = {"n_modes": chosen["fidelity"]["n_modes"], "modes_per_motion": floors}
    pinned = run(load_scene(raw, source="pinned")).data
    assert pinned["fidelity"]["modes_per_motion"] == chosen["fidelity"]["modes_per_motion"]
    assert pinned["truth"]["coupled_frequencies"] == chosen["truth"]["coupled_frequencies"]
    a, b = dict(_numbers(chosen["closed_loops"])), dict(_numbers(pinned["closed_loops"]))
    assert a.keys() == b.keys() and len(a) > 100
    for key, value in a.items():
        if "seconds" in key or "time_s" in key:
            continue
        assert math.isclose(b[key], value, rel_tol=1e-12, abs_tol=1e-300) or (
            math.isnan(value) and math.isnan(b[key])), (key, value, b[key])
    # the tip twist reads a value: the truth keeps its torsion modes
    twists = [v for k, v in a.items() if k.endswith("tip_twist")]
    assert twists and all(v > 0 for v in twists)


def test_pinned_modes_keep_a_mode_of_every_seen_motion_and_at_least_the_pins():
    """A rod with two modes of its own: alone the two lowest (the round rod's bending twins);
    with an empty table and tip outputs also its lowest torsion mode; with torsion pinned at 3,
    three torsion modes, the two lowest beyond them as before."""
    def per_motion(**fidelity):
        raw = _scene(THREE_AXIS, **fidelity)
        raw["outputs"] = {"tip_deflection": True}
        loop = DesignLoop(load_scene(raw))
        return loop.truth_modes_per_motion(loop.n_modes)["rod"]

    alone = per_motion()
    assert alone == {"xy": 1, "xz": 1, "torsion": 0, "axial": 0}
    seen = per_motion(modes_per_motion={})
    assert seen["torsion"] == 1 and seen["xy"] >= 1 and seen["xz"] >= 1
    pinned = per_motion(modes_per_motion={"rod": {"torsion": 3}})
    assert pinned["torsion"] == 3
    assert {k: pinned[k] for k in ("xy", "xz", "axial")} == {
        k: seen[k] for k in ("xy", "xz", "axial")}


def test_pins_hold_without_tip_outputs():
    """Without tip outputs no motion is 'seen', but a pin is still kept (never read and
    ignored)."""
    loop = DesignLoop(load_scene(_scene(THREE_AXIS, modes_per_motion={"rod": {"torsion": 2}})))
    assert loop.truth_modes_per_motion(2)["rod"]["torsion"] == 2


def test_a_planar_pin_adds_modes_beyond_n_modes():
    """In the plane the rule adds bending modes beyond n_modes: n_modes 2 with 3 pinned is
    the truncation to 5 modes."""
    pinned = DesignLoop(load_scene(_scene(PLANAR, modes_per_motion={"rod": {"bending": 3}})))
    five = DesignLoop(load_scene(_scene(PLANAR, n_modes=5)))
    a, b = (loop.truth_model(loop.scene.appendages[0], loop.n_modes) for loop in (pinned, five))
    assert a.n_modes == b.n_modes == 5
    for name in ("mass", "damping", "stiffness", "tip"):
        np.testing.assert_array_equal(getattr(a.root_model(), name), getattr(b.root_model(), name))


def test_the_cost_estimate_counts_the_pinned_modes_and_the_twins():
    """n_modes 2 of a round rod with a table: the lowest mode of xy, xz and torsion, and 2
    distinct frequencies beyond them, each at most a twin pair (4 modes): 7 modes, 2 (3 + 7) =
    20 plant states (the hub's 3 rigid motions); torsion pinned at 3, two torsion modes more:
    2 (3 + 9) = 24. Both are the truncation's own count here (the rod's next levels are
    bending pairs). The rod is designed on its truth (its three-body chain would have 2 (3 +
    4 x 2) = 22 states, each hinge moving in four ways)."""
    raw = _scene(THREE_AXIS, modes_per_motion={})
    raw["outputs"] = {"tip_deflection": True}
    del raw["appendages"][0]["fit"]
    raw["appendages"][0]["design"] = "truth"
    for pins, modes in (({}, 7), ({"rod": {"torsion": 3}}, 9)):
        raw["fidelity"]["modes_per_motion"] = pins
        scene = load_scene(raw)
        assert estimate_cost(scene).plant_states == 2 * (3 + modes)
        loop = DesignLoop(scene)
        assert sum(loop.truth_modes_per_motion(2)["rod"].values()) == modes


@pytest.mark.parametrize("n", [1, 3, 8])
@pytest.mark.parametrize("pins", [None, {}, {"boom": {"torsion": 5}}])
@pytest.mark.parametrize("tip", [True, False])
def test_the_cost_estimate_bounds_the_truth_the_run_builds(n, pins, tip):
    """An upper bound (a bound that is not one would let a scene past limits.states): the
    shipped three-axis scene (rectangular wings, a round boom whose bending modes come in
    pairs), n_modes given alone or with pins, tip outputs on or off: the estimated plant
    states are at least the truth's (its modes per motion summed)."""
    raw = tomllib.loads(scene_path("three_axis").read_text())
    raw["fidelity"] = {"n_modes": n} if pins is None else {"n_modes": n,
                                                         "modes_per_motion": pins}
    raw["outputs"]["tip_deflection"] = tip
    scene = load_scene(raw)
    loop = DesignLoop(scene)
    modes = sum(sum(c.values()) for c in loop.truth_modes_per_motion(n).values())
    assert estimate_cost(scene).plant_states >= 2 * (3 + modes)


def test_the_pinned_truth_is_the_same_with_tip_outputs_on_or_off():
    """Pins copied from a tolerance run with tip outputs rerun its truth in a scene that
    reports none: the lowest mode of both bending planes and torsion is kept either way."""
    raw = tomllib.loads(scene_path("three_axis").read_text())
    raw["fidelity"] = {"n_modes": 1, "modes_per_motion": {"boom": {"torsion": 5}}}
    counts = []
    for tip in (True, False):
        raw["outputs"]["tip_deflection"] = tip
        loop = DesignLoop(load_scene(copy.deepcopy(raw)))
        counts.append(loop.truth_modes_per_motion(1))
    assert counts[0] == counts[1]
    assert all(c["xy"] >= 1 and c["xz"] >= 1 and c["torsion"] >= 1 for c in counts[0].values())


def test_a_planar_pin_is_in_the_resolved_band_the_report_gives():
    """The truth of n_modes 2 with 3 bending modes pinned is a 5-mode truncation, and the run
    says so where it tells how far the truth resolves the beam."""
    data = run(load_scene(_scene(PLANAR, modes_per_motion={"rod": {"bending": 3}})),
               time_responses=False).data
    five = run(load_scene(_scene(PLANAR, n_modes=5)), time_responses=False).data
    assert data["truth"]["resolved"]["rod"]["model"] == "5 craig-bampton modes"
    assert data["truth"]["resolved"] == five["truth"]["resolved"]


# -- refused by name -----------------------------------------------------------------------------
@pytest.mark.parametrize("base, fidelity, match", [
    (THREE_AXIS, {"n_modes": None, "modes_per_motion": {"rod": {"torsion": 2}}},
     r"fidelity\.modes_per_motion: goes with fidelity\.n_modes"),
    (THREE_AXIS, {"modes_per_motion": {"rdo": {"torsion": 2}}},
     r"fidelity\.modes_per_motion\.rdo: unknown appendage; expected one of rod.*'rod'"),
    (THREE_AXIS, {"modes_per_motion": {"rod": {"bending": 2}}},
     r"fidelity\.modes_per_motion\.rod\.bending: not a motion of a uniform three-axis beam; "
     r"expected one of xy, xz, torsion, axial"),
    (PLANAR, {"modes_per_motion": {"rod": {"xy": 2}}},
     r"fidelity\.modes_per_motion\.rod\.xy: not a motion of a planar beam; expected one of "
     r"bending"),
    (THREE_AXIS, {"modes_per_motion": {"rod": {"torsion": 0}}},
     r"fidelity\.modes_per_motion\.rod\.torsion: must be an integer >= 1 \[-\]; got 0"),
    (THREE_AXIS, {"modes_per_motion": {"rod": {"torsion": 2.5}}},
     r"fidelity\.modes_per_motion\.rod\.torsion: must be an integer >= 1 \[-\]; got 2\.5"),
    (THREE_AXIS, {"modes_per_motion": {"rod": {"torsion": True}}},
     r"fidelity\.modes_per_motion\.rod\.torsion: must be an integer >= 1"),
    (THREE_AXIS, {"modes_per_motion": {"rod": {}}},
     r"fidelity\.modes_per_motion\.rod: must name at least one motion"),
    (THREE_AXIS, {"modes_per_motion": {"rod": 2}},
     r"fidelity\.modes_per_motion\.rod: must be a table"),
    (PLANAR, {"modes_per_motion": {}},
     r"fidelity\.modes_per_motion: is empty, which pins nothing in a planar scene"),
    (THREE_AXIS, {"modes_per_motion": {"rod": {"torsion": 100000}}},
     r"fidelity\.modes_per_motion\.rod\.torsion"),
])
def test_a_bad_pin_is_refused_by_name(base, fidelity, match):
    raw = _scene(base)
    for key, value in fidelity.items():
        if value is None:
            raw["fidelity"].pop(key, None)
            raw["fidelity"]["tolerance"] = 1e-3
        else:
            raw["fidelity"][key] = value
    with pytest.raises(SceneError, match=match):
        load_scene(raw)


def test_a_beam_with_a_tip_body_pins_its_lowest_modes_together():
    """A tip body couples the motions: its modes are ranked together, and a pin adds lowest
    modes beyond those an empty table keeps (the fewest lowest that move every tip motion,
    and n_modes beyond them)."""
    raw = _scene(THREE_AXIS, modes_per_motion={"rod": {"coupled": 2}})
    raw["appendages"][0]["tip"] = {"mass": 2.0, "inertia": [[0.01, 0.0, 0.0], [0.0, 0.02, 0.0],
                                                            [0.0, 0.0, 0.02]]}
    raw["appendages"][0]["design"] = "truth"
    raw["appendages"][0].pop("fit")
    loop = DesignLoop(load_scene(raw))
    plain = DesignLoop(load_scene(_scene({**raw, "fidelity": {"n_modes": 2,
                                                              "modes_per_motion": {}}})))
    spec = loop.scene.appendages[0]
    assert loop.truth_model(spec, 2).n_modes == plain.truth_model(spec, 2).n_modes + 2
    raw["fidelity"]["modes_per_motion"] = {"rod": {"torsion": 2}}
    with pytest.raises(SceneError, match=r"rod\.torsion: not a motion of a three-axis beam "
                                         r"whose modes are ranked together"):
        load_scene(raw)
