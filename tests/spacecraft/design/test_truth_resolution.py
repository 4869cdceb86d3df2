"""The truth model's resolution against the loops' band: the rule of thumb (a truncation to n
modes resolves a beam up to its n-th clamped frequency) warns only where nothing checked it.

The tolerance-driven fidelity closes every loop with one more mode per beam and compares the
poles up to the loops' band, the least damping and the margins; when that check converged over
the band, the question the rule of thumb estimates has been answered, and a warning that
'modes are missing' would contradict it (the shipped three-axis scene gave both)."""
import copy

import pytest

import spacecraft
from spacecraft.design.loop import DesignLoop
from spacecraft.design.verdicts import design_warnings
from spacecraft.report.pages import markdown
from spacecraft.report.write import report_blocks
from scenes import LOOP_SCENE as ROD_SCENE

# the design-loop tests' rod and slew, one truth mode and a faster PD (its band above 1 rad/s)
SCENE = {**{key: copy.deepcopy(ROD_SCENE[key]) for key in ("hub", "appendages", "manoeuvre")},
         "fidelity": {"n_modes": 1},
         "controller": {"types": ["pd"], "pd": {"natural_frequency": 0.3}}}


@pytest.fixture(scope="module")
def one_mode():
    return spacecraft.run(copy.deepcopy(SCENE))


def test_one_mode_below_the_band_unchecked_is_warned(one_mode):
    truth = one_mode.data["truth"]
    # the rod's first clamped frequency 3.516 sqrt(EI/(rho A L^4)) = 0.452 rad/s, the loops'
    # band 5 x the PD's crossover, above 1 rad/s
    assert truth["resolved"]["rod"]["frequency"] == pytest.approx(0.4517, rel=1e-3)
    assert truth["loop_band"] > 1.0
    assert truth["resolved"]["rod"]["covers_loops"] is False
    assert "truth_resolution" in [w["code"] for w in one_mode.data["design_warnings"]]
    assert "modes missing there" in markdown(report_blocks(one_mode.data, []))


def test_a_closed_loop_check_over_the_band_answers_it(one_mode):
    loop = DesignLoop(copy.deepcopy(SCENE))
    rows = one_mode.data["closed_loops"]
    band = one_mode.data["truth"]["loop_band"]

    def covers(record):
        _, resolved = loop.truth_resolution(1, rows, {"choice": {"closed_loop": record}})
        return resolved["rod"][2]

    assert covers({"converged": True, "band": band}) is True
    assert covers({"converged": True, "band": 2.0 * band}) is True
    assert covers({"converged": False, "band": 2.0 * band}) is False   # not converged
    assert covers({"converged": True, "band": 0.9 * band}) is False    # not over the band
    assert covers(None) is False                                         # n_modes given


@pytest.mark.parametrize("covers, warned", [(True, False), (False, True)])
def test_the_warning_follows_the_check(one_mode, covers, warned):
    data = copy.deepcopy(one_mode.data)
    warnings = design_warnings(data, loop_band=data["truth"]["loop_band"],
                               resolved={"rod": (0.45, "1 craig-bampton mode", covers)})
    assert ("truth_resolution" in [w["code"] for w in warnings]) is warned


def test_the_tolerance_driven_scene_covers_its_band():
    scene = copy.deepcopy(SCENE)
    scene["fidelity"] = {"tolerance": 1e-3}
    data = spacecraft.run(scene).data
    record = data["fidelity"]["choice"]["closed_loop"]
    assert record["converged"]
    assert data["truth"]["resolved"]["rod"]["covers_loops"] is True
    assert "truth_resolution" not in [w["code"] for w in data["design_warnings"]]


def test_the_report_says_why_a_band_beyond_the_rule_is_covered(one_mode):
    data = copy.deepcopy(one_mode.data)
    data["truth"]["resolved"]["rod"]["covers_loops"] = True
    text = markdown(report_blocks(data, []))
    assert "changes the closed loops in that band by less than the tolerance" in text
    assert "modes missing there" not in text
