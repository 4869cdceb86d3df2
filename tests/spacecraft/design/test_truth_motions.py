"""A three-axis truth model chosen from the tolerance keeps a mode of every motion a tip output
sees (bending in both planes, torsion), so no tip figure of the truth model reads 0 for want of
a mode; a given fidelity.n_modes is kept as given (and warned about).

References: :attr:`appendages.ModalBeam.modes_per_motion` (the lowest-of-all rule without a
floor). The tip figures of the floored motions against a much finer truth:
test_tip_fidelity.py."""
import math

import pytest

import spacecraft
from appendages import Beam
from spacecraft.design.fidelity import motion_counts
from spacecraft.design.loop import DesignLoop
from scenes import rod_scene

SEEN = ("xy", "xz", "torsion")
# the shipped three-axis scene's wing (in-plane bending first at 236 rad/s) and boom (a round
# tube: its two bending planes are twins; torsion first at about 1e4 rad/s)
WING = Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8, damping_ratio=0.005)
BOOM = Beam.tube(4.0, 0.05, 0.001, 1600.0, 1.2e11, damping_ratio=0.005)
METHODS = ("craig-bampton", "free-free")


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("beam", [WING, BOOM], ids=["wing", "boom"])
def test_without_a_floor_the_counts_are_the_lowest_of_all_motions(beam, method):
    for n in range(1, 7):
        assert motion_counts(beam, n, method) == beam.truncated(
            n, method=method).modes_per_motion


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("beam", [WING, BOOM], ids=["wing", "boom"])
def test_the_floor_keeps_every_seen_motion_and_each_n_adds_a_mode(beam, method):
    before = None
    for n in range(1, 7):
        counts = motion_counts(beam, n, method, SEEN)
        plain = beam.truncated(n, method=method).modes_per_motion
        for motion in SEEN:
            assert counts[motion] >= 1
        # never fewer than the lowest-of-all rule, and beyond the floor exactly that rule
        # on the rest (twins of the round boom counted once)
        assert all(counts[m] >= plain[m] for m in counts)
        if before is not None:
            assert all(counts[m] >= before[m] for m in counts)
            assert sum(counts.values()) > sum(before.values())
        before = counts


def test_the_floor_adds_only_what_the_lowest_modes_lack():
    # the wing's 3 lowest modes: two out-of-plane bending modes and the first torsion mode;
    # the floor adds its in-plane bending mode (the stiff one) and nothing else, and its n = 1
    # keeps, beyond the floor, the second out-of-plane mode
    assert WING.truncated(3).modes_per_motion == {"xy": 2, "xz": 0, "torsion": 1, "axial": 0}
    assert motion_counts(WING, 1, "craig-bampton", SEEN) == {"xy": 2, "xz": 1, "torsion": 1,
                                                             "axial": 0}


def _run(**overrides):
    scene = spacecraft.load_scene("three_axis", overrides={
        "export.fmu": False, "report.plots": False, **overrides})
    return DesignLoop(scene).run().data


@pytest.mark.slow
def test_the_tolerance_driven_truth_moves_every_tip_output(tmp_path):
    from spacecraft import write_report

    scene = spacecraft.load_scene("three_axis", overrides={"export.fmu": False,
                                                           "report.plots": False})
    result = DesignLoop(scene).run()
    data = result.data
    write_report(result, tmp_path)
    text = (tmp_path / "report.md").read_text()
    assert "truncated to the lowest mode of every motion a reported output sees and " in text
    counts = data["fidelity"]["modes_per_motion"]["boom"]
    assert ("boom " + ", ".join(f"{m} {c}" for m, c in counts.items())) in text
    assert not [w for w in data["design_warnings"] if w["code"] == "truth_output_unmodelled"]
    per_motion = data["fidelity"]["modes_per_motion"]
    assert set(per_motion) == {"wing_left", "wing_right", "boom"}
    assert data["fidelity"]["motions_kept"] == list(SEEN)
    for counts in per_motion.values():
        assert all(counts[m] >= 1 for m in SEEN)
    for truth in data["truth"]["models"].values():
        assert all(truth["modes_per_motion"][m] >= 1 for m in SEEN)
    for row in data["closed_loops"]:
        for name, peaks in row["appendages"]["truth"].items():
            for key, value in peaks.items():
                assert value > 0.0, (row["controller"], name, key)


@pytest.mark.slow
def test_root_loads_keep_the_axial_motion_too():
    """The root force along an appendage sees its axial motion: with outputs.root_loads each
    uniform beam keeps its lowest axial mode too (and, without tip outputs, still the lowest of
    both bending planes and torsion, which the root's other loads see)."""
    data = _run(**{"outputs.root_loads": True, "outputs.tip_deflection": False,
                   "outputs.exact_reference": False, "manoeuvre": None})
    assert data["fidelity"]["motions_kept"] == [*SEEN, "axial"]
    for counts in data["fidelity"]["modes_per_motion"].values():
        assert all(counts[m] >= 1 for m in (*SEEN, "axial"))


@pytest.mark.slow
def test_a_given_n_modes_is_kept_and_its_unmodelled_tips_are_named():
    data = _run(**{"fidelity.n_modes": 3, "fidelity.tolerance": None})
    assert data["fidelity"]["motions_kept"] == []
    # the 3 lowest of all: no in-plane bending of the wings, no torsion of the boom
    per_motion = data["fidelity"]["modes_per_motion"]
    assert per_motion["wing_left"]["xz"] == per_motion["boom"]["torsion"] == 0
    assert data["truth"]["models"]["wing_left"]["modes_per_motion"] == per_motion["wing_left"]
    (warning,) = [w for w in data["design_warnings"] if w["code"] == "truth_output_unmodelled"]
    for name in ("wing_left_tip_deflection_z", "wing_right_tip_deflection_z", "boom_tip_twist"):
        assert name in warning["message"]
    assert "leave fidelity.n_modes out" in warning["message"]


@pytest.mark.slow
@pytest.mark.parametrize("diameter", [0.05, 0.01])
def test_a_beam_with_a_tip_body_keeps_the_fewest_lowest_modes_that_move_every_tip(diameter):
    """A tip body's beam has its modes ranked together (no split by motion): the truth keeps
    the fewest lowest modes k0 that move every tip motion, and k0 - 1 + n for n_modes = n;
    one fewer leaves a tip row zero. A 50 mm steel rod's first torsion mode (about 500 rad/s)
    lies among its lowest 40 modes; a 10 mm rod's lies above them (bending frequencies scale
    with the diameter, torsion's do not), beyond the search: its twist stays unmodelled and
    the warning names it."""
    import numpy as np

    # the small three-axis rod scene (tests/support/scenes.py) with a tip body and the
    # diameter given, tuned on the truth itself, its fidelity from the tolerance, slewed about
    # (1, 1, 1)
    raw = rod_scene(three_axis=True, **{
        "appendages.0.beam.diameter": diameter, "appendages.0.tip": {"mass": 1.0},
        "appendages.0.design": "truth", "appendages.0.fit": None, "fidelity": None,
        "controller.pd.damping": None, "manoeuvre.slew_axis": [1.0, 1.0, 1.0],
        "outputs": {"tip_deflection": True}, "title": None, "report": None, "export": None})
    loop = DesignLoop(spacecraft.load_scene(raw, source="tip body"))
    beam = loop.beam(loop.scene.appendages[0])
    k0 = loop.coupled_floor(beam)
    data = loop.run().data
    unmodelled = [w for w in data["design_warnings"] if w["code"] == "truth_output_unmodelled"]
    if diameter == 0.01:
        assert k0 == 1 and "rod_tip_twist" in unmodelled[0]["message"]
        return
    assert k0 > 1
    rows = [beam.truncated(k).root_model(6).tip_rows for k in (k0 - 1, k0)]
    assert not all(np.asarray(row).any() for row in rows[0])
    assert all(np.asarray(row).any() for row in rows[1])
    for n in (1, 2):
        assert loop.truncation(beam, n).n_modes == k0 - 1 + n
    assert data["fidelity"]["modes_per_motion"]["rod"]["lowest coupled modes"] >= k0
    assert not unmodelled
    for row in data["closed_loops"]:
        assert min(row["appendages"]["truth"]["rod"].values()) > 0.0


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("beam", [WING, BOOM], ids=["wing", "boom"])
def test_the_resolved_frequency_of_counts_per_motion(beam, method):
    """The frequency a truncation with modes per motion resolves the beam up to: every mode of
    the beam up to it is kept, the lowest mode left out lies above it, and for the n lowest of
    all motions it is the rule of thumb's n-th (resolved_frequency without counts)."""
    from spacecraft.design.verdicts import resolved_frequency

    kind = "cantilever_frequencies" if method == "craig-bampton" else "natural_frequencies"
    rods = {"torsion": beam.torsion_rod(), "axial": beam.axial_rod()}
    for n in range(1, 5):
        assert resolved_frequency(beam, n, method, three_axis=True, modes_per_motion=motion_counts(
            beam, n, method)) == pytest.approx(resolved_frequency(beam, n, method,
                                                                  three_axis=True), rel=1e-12)
        counts = motion_counts(beam, n, method, SEEN)
        w = resolved_frequency(beam, n, method, three_axis=True, modes_per_motion=counts)
        for motion, count in counts.items():
            model = beam.planar_view(motion) if motion in ("xy", "xz") else rods[motion]
            f = getattr(model, kind)(count + 1)
            # no mode left out at or below w (1e-12: the frequencies' rounding)
            assert f[count] > w * (1.0 + 1e-12), (n, motion)
        assert w in [float(x) for motion, count in counts.items()
                     for x in getattr(beam.planar_view(motion) if motion in ("xy", "xz")
                                      else rods[motion], kind)(max(count, 1))[:count]]


@pytest.mark.slow
def test_the_truth_models_planar_view_is_its_x_y_part_and_the_report_names_every_mode():
    """The truth beam's planar model (x-y bending: its W, poles, the W plot's resonances) is
    the x-y part of its three-axis model, and the report counts every motion's modes."""
    data = _run(**{"outputs.exact_reference": False, "manoeuvre": None})
    for name, truth in data["truth"]["models"].items():
        counts = truth["modes_per_motion"]
        assert truth["n_modes"] == counts["xy"]
        beam = WING if name.startswith("wing") else BOOM
        planar = beam.truncated(counts["xy"], method="craig-bampton").poles()
        assert truth["natural_frequencies"] == pytest.approx(list(planar[:6]), rel=1e-12)
        resolved = data["truth"]["resolved"][name]
        assert resolved["model"].startswith(f"{sum(counts.values())} craig-bampton modes: ")
