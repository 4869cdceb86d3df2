"""The public design loop (spacecraft.DesignLoop): a scene's loop one controller at a time, and a
Python user's own Spacecraft objects through the same loop.

References: the scene's own run (spacecraft.run). The same truth, design and exact models given
as Spacecraft objects must give the scene's numbers: the loop does the same arithmetic on the
same matrices, so they agree to round-off (rtol 1e-12 on margins, metrics and poles: a few
hundred flops of well-conditioned eigen- and Riccati solutions on identical inputs).
"""

import math

import control

import numpy as np
import pytest

import spacecraft
from spacecraft import DesignLoop, Spacecraft
from spacecraft.scene.read import SceneError

from scenes import LOOP_SCENE

@pytest.fixture(scope="module")
def scene_run():
    return spacecraft.run(LOOP_SCENE)


def _own_models(loop: DesignLoop) -> dict:
    """The scene's truth, design and exact spacecraft as a Python user would hold them."""
    return {"truth": loop.truth_spacecraft(12),
            "design": {"poles-and-zeros": loop.design_spacecraft("poles-and-zeros", 12)},
            "exact": loop.exact_spacecraft()}


def test_own_spacecraft_give_the_scenes_numbers(scene_run):
    models = _own_models(DesignLoop(LOOP_SCENE))
    own = DesignLoop(**models, controller=LOOP_SCENE["controller"],
                     manoeuvre=LOOP_SCENE["manoeuvre"], outputs={"tip_deflection": True}).run()
    assert len(own.data["closed_loops"]) == len(scene_run.data["closed_loops"]) == 2
    for mine, theirs in zip(own.data["closed_loops"], scene_run.data["closed_loops"]):
        assert (mine["design"], mine["controller"]) == (theirs["design"], theirs["controller"])
        for table in ("verdict", "design_margins"):
            for k in ("gain_margin", "phase_margin", "modulus_margin"):
                assert mine[table][k] == pytest.approx(theirs[table][k], rel=1e-12, abs=0)
        assert mine["verdict"]["stable"] == theirs["verdict"]["stable"]
        assert mine["exact_verdict"]["stable"] == theirs["exact_verdict"]["stable"]
        for k in ("overshoot", "settling_time", "peak_torque", "peak_tip_deflection"):
            assert mine["metrics"]["truth"][k] == pytest.approx(theirs["metrics"]["truth"][k],
                                                                rel=1e-12, abs=0)
        assert mine["appendages"]["truth"]["rod"]["peak_tip_deflection"] == pytest.approx(
            theirs["appendages"]["truth"]["rod"]["peak_tip_deflection"], rel=1e-12)
    # the warnings speak of the same loops
    assert ([w["code"] for w in own.data["design_warnings"]]
            == [w["code"] for w in scene_run.data["design_warnings"]
                if w["code"] not in ("truth_resolution", "missed_modes")])


def test_one_controller_at_a_time_is_the_runs_row(scene_run):
    loop = DesignLoop(LOOP_SCENE)
    loop.n_modes = 12
    c = loop.closed_loops("poles-and-zeros", "pd")
    row = scene_run.data["closed_loops"][0]
    assert c.row["verdict"]["phase_margin"] == pytest.approx(row["verdict"]["phase_margin"],
                                                            rel=1e-12)
    assert c.verdict.stable and set(c.loops) == {"design", "truth"}
    np.testing.assert_allclose(np.sort_complex(c.poles["truth"]),
                               np.sort_complex(scene_run.poles[("poles-and-zeros", "pd",
                                                                "truth")]), rtol=1e-12)
    # the truth model alone, the manoeuvre whole: what a sweep's sample asks
    truth_only = loop.closed_loops("poles-and-zeros", "pd", models=("truth",),
                                   whole_manoeuvre=True)
    assert set(truth_only.loops) == {"truth"} and "design_margins" not in truth_only.row
    assert truth_only.row["metrics"]["truth"]["overshoot"] == pytest.approx(
        row["metrics"]["truth"]["overshoot"], rel=1e-12)


def test_a_given_controller_is_judged_as_it_is():
    """A controller held fixed (a sweep's nominal one) gives the verdict of that controller:
    the PD with a 5 rad/s roll-off, whose gain margin is finite on the design and the truth
    model (an LQR on a fitted chain damped at the rod's first cantilever frequency has none on
    its design model)."""
    scene = dict(LOOP_SCENE, controller={"types": ["pd"], "pd": {"natural_frequency": 0.1,
                                                            "roll_off": 5.0}})
    scene.pop("manoeuvre")
    nominal = spacecraft.run(scene)
    loop = DesignLoop(scene)
    loop.n_modes = 12
    K = nominal.designs["poles-and-zeros"]["controllers"]["pd"]
    half = control.ss(K.A, K.B, 0.5 * K.C, 0.5 * K.D, inputs=K.input_labels,
                      outputs=K.output_labels)
    c = loop.closed_loops("poles-and-zeros", "pd", controller=half)
    assert c.controller is half
    # half the gain: the phase crossover stays where it is and the gain margin grows by
    # 20 log10(2) dB (the GM of k L is GM(L) - 20 log10 k), to the margins' refinement
    # tolerance (crossings found to 1e-13 in frequency)
    for table in ("design_margins", "verdict"):
        full = nominal.data["closed_loops"][0][table]["gain_margin"]
        assert math.isfinite(full)
        assert c.row[table]["gain_margin"] - full == pytest.approx(20.0 * math.log10(2.0),
                                                                   abs=1e-8)


def test_own_models_without_a_manoeuvre_tune_and_judge_only():
    models = _own_models(DesignLoop(LOOP_SCENE))
    result = DesignLoop(truth=models["truth"], design=models["design"]["poles-and-zeros"],
                        controller={"pd": {"natural_frequency": 0.1}}).run()
    (row,) = result.data["closed_loops"]
    assert row["design"] == "design" and row["verdict"]["stable"]
    assert "metrics" not in row and not result.responses
    assert "exact" not in result.data and "exact_verdict" not in row


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(scene="default", truth="T"), TypeError, r"truth: give a scene or your own models"),
    (dict(design="D"), TypeError, r"design: your own models need a truth Spacecraft"),
    (dict(truth=1.0, controller={}), TypeError, r"truth must be a spacecraft\.Spacecraft"),
    (dict(truth="T"), TypeError, r"controller: your own models need a controller"),
    (dict(scene="default", controller={"pd": {}}), TypeError, r"controller: goes with your "),
    (dict(truth="T", controller={"pid": {}}), SceneError, r"controller\.pid: unknown key"),
    (dict(truth="T", controller={"pd": {"natural_frequency": 0.1}},
          manoeuvre={"slew_angle": 10.0}), SceneError,
     r"manoeuvre\.slew_time: missing required value"),
    (dict(truth="T", controller={"lqr": {"attitude_weight": 1.0, "torque_weight": 1.0,
                                         "deflection_weight": 1.0}}), SceneError,
     r"controller\.lqr\.deflection_weight: needs tip-deflection outputs"),
    (dict(truth="T", controller={"pd": {"natural_frequency": 0.1}},
          outputs={"exact_reference": True}), SceneError, r"outputs\.exact_reference: unknown"),
    (dict(progress=3), TypeError, r"progress must be None or a function"),
])
def test_bad_arguments_are_named(kwargs, error, match):
    if kwargs.get("truth") == "T":
        kwargs["truth"] = _own_models(DesignLoop(LOOP_SCENE))["truth"]
    with pytest.raises(error, match=match):
        DesignLoop(**kwargs)


def test_spacecraft_exports_the_design_loop():
    assert spacecraft.DesignLoop is DesignLoop and "DesignLoop" in spacecraft.__all__
    assert isinstance(DesignLoop(LOOP_SCENE).truth_spacecraft(3), Spacecraft)
