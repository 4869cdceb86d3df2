"""``limits.states`` holds for the loops a run builds, whatever its truth keeps.

A three-axis beam whose modes are ranked together (here a steel rod with a tip body) keeps, for
a truth that must move every tip motion, the fewest lowest modes k0 that do and n_modes - 1
more (:meth:`spacecraft.design.models.ModelBuilder.truncation`). k0 follows from the beam's
modes, which the read-time estimate (:func:`spacecraft.scene.limits.estimate_cost`) does not
compute: it counts n_modes and a mode per motion. The run counts the loops it builds and
refuses, by name, one over the limit before any controller is tuned or loop judged or simulated:
from ``flexsat run``, ``spacecraft.run``, the design loop's API and a sweep's sample.

References: the counts worked out by hand from the rod's k0 (found by
:meth:`~spacecraft.design.models.ModelBuilder.coupled_floor` and checked against the tip rows of
its truncations in test_truth_motions.py): a 10 m steel rod of 0.2 m diameter with a 2 kg tip
body has k0 = 9, one of 0.1 m k0 = 13 (their first torsion mode lies among more bending modes
the thinner the rod). A plant of N elastic coordinates on a three-axis hub turned by torques has
2 (3 + N) states (the hub's three rotations; the centre of mass does not move).
"""
import copy
import warnings

import numpy as np
import pytest

import spacecraft
from spacecraft.cli import main as flexsat_main
from spacecraft.design.loop import DesignLoop, RunStats, run
from spacecraft.scene.limits import controller_states, estimate_cost
from spacecraft.scene.read import SceneError, load_scene
from spacecraft.sweep.evaluate import evaluate, prepare
from spacecraft.sweep.parameters import read_sweep
from spacecraft.sweep.worst import to_toml

ROD = {"section": "rod", "length": 10.0, "diameter": 0.2, "density": 7800.0,
       "youngs_modulus": 2.06e11, "damping_ratio": 0.005}
#: k0 of the rods above (diameter [m] -> k0)
K0 = {0.2: 9, 0.1: 13}
N_MODES = 6
SCENE = {
    "title": "rod with a tip body",
    "hub": {"mass": 100.0, "inertia": [[60.0, 2.0, 0.0], [2.0, 50.0, 1.0], [0.0, 1.0, 40.0]]},
    "appendages": [{"name": "rod", "position": [0.5, 0.0, 0.1], "orientation": [0.0, 0.0, 0.0],
                    "beam": dict(ROD), "tip": {"mass": 2.0}, "design": "truth"}],
    # modes pinned per motion (none here): the truth keeps a mode of every tip motion
    "fidelity": {"n_modes": N_MODES, "modes_per_motion": {}},
    "controller": {"types": ["pd"], "pd": {"natural_frequency": 0.1}},
    "manoeuvre": {"slew_angle": 10.0, "slew_time": 30.0, "duration": 45.0, "step": 0.25,
                  "slew_axis": [1.0, 1.0, 1.0]},
    "outputs": {"tip_deflection": True},
    "report": {"plots": False},
    "export": {"fmu": False},
}
#: The truth's states: 2 (3 + k0 - 1 + n_modes) = 34 for the 0.2 m rod (a PD without filters
#: has no states: its loop has the plant's).
BUILT = 2 * (3 + K0[0.2] - 1 + N_MODES)
#: What the read-time estimate counts: n_modes and the lowest mode of xy, xz and torsion, and
#: two controller states of margin: 2 (3 + 6 + 3) + 2 = 26.
ESTIMATED = 2 * (3 + N_MODES + 3) + 2
#: Over the truth's states, and enough for the search of k0 (k0 = 9 modes within the loop the
#: read-time count lets limits.states hold: 2 (3 + 9 + 3) + 2 = 32)
LIMIT = BUILT - 2


def scene(limit=LIMIT, **changes):
    raw = copy.deepcopy(SCENE)
    raw["limits"] = {"states": limit}
    for key, value in changes.items():
        raw[key] = value
    return raw


REFUSAL = (rf"appendages\[0\]\.tip: the closed loop of the PD on the truth model would have "
           rf"{BUILT} states \({BUILT} of the plant, 0 of the controller\), over the limit "
           rf"{LIMIT} \(limits\.states, states of the largest closed loop\): appendage 'rod' "
           rf"keeps {K0[0.2] - 1 + N_MODES} modes: the {K0[0.2]} lowest, .*a tip body.*"
           r"pin fewer modes.*raise it: \[limits\] states = N in the scene, or --limit states=N")


def test_the_read_time_estimate_passes_what_the_run_builds_larger():
    """The gap the run's check closes: the estimate is under the limit, the truth over it."""
    loaded = load_scene(scene())
    assert estimate_cost(loaded).loop_states == ESTIMATED < LIMIT
    loop = DesignLoop(loaded)
    assert loop.coupled_floor(loop.beam(loaded.appendages[0])) == K0[0.2]
    assert loop.simulation_plant("truth", None, N_MODES).nstates == BUILT > LIMIT


def test_run_refuses_by_name_before_tuning_or_simulating():
    stats = RunStats()
    with pytest.raises(SceneError, match=REFUSAL):
        DesignLoop(load_scene(scene()), stats=stats).run()
    assert stats.pd_designs == stats.lqr_designs == stats.simulations == 0
    assert stats.simulator_setups == stats.exact_reference_evaluations == 0
    with pytest.raises(SceneError, match=REFUSAL):
        spacecraft.run(scene())


def test_an_lqr_is_refused_before_it_is_designed():
    """The LQR's Kalman estimator has the design plant's states (here the truth itself):
    the loop 2 x 34 states, refused before the LQR is designed."""
    raw = scene(limit=2 * BUILT - 1, controller={
        "types": ["lqr"], "lqr": {"attitude_weight": 1.0, "torque_weight": 1.0}})
    stats = RunStats()
    loop = DesignLoop(load_scene(raw), stats=stats)
    with pytest.raises(SceneError, match=rf"would have {2 * BUILT} states \({BUILT} of the "
                                         rf"plant, {BUILT} of the controller\), over the limit "
                                         rf"{2 * BUILT - 1} \(limits\.states"):
        loop.closed_loops("design", "lqr")
    assert stats.lqr_designs == 0 and stats.simulations == 0


@pytest.mark.slow
def test_a_scene_at_the_limit_runs():
    result = run(load_scene(scene(limit=BUILT)))
    assert max(loop.nstates for loop in result.loops.values()) == BUILT
    assert result.data["fidelity"]["modes_per_motion"]["rod"] == {
        "lowest coupled modes": K0[0.2] - 1 + N_MODES}


@pytest.mark.slow
def test_flexsat_run_exits_2_with_one_line_and_no_folder(tmp_path, capsys):
    path = tmp_path / "rod.toml"
    path.write_text(to_toml(scene()))
    out = tmp_path / "out"
    assert flexsat_main(["run", str(path), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert "limits.states" in err and "appendages[0].tip" in err
    assert not out.exists() or not any(out.iterdir())
    # raised on the command line, it runs
    assert flexsat_main(["run", str(path), "--out", str(tmp_path / "raised"), "--quiet",
                         "--limit", f"states={BUILT}"]) == 0


@pytest.mark.slow
def test_a_sweep_sample_over_the_limit_fails_with_its_reason():
    """The nominal rod (0.2 m: 34 states) runs; a sample of a thinner rod (0.1 m: k0 = 13,
    2 (3 + 12 + 6) = 42 states) is over the limit 40 and fails, counted with its reason."""
    raw = scene(limit=40)
    spec = read_sweep({"parameters": {"appendages.rod.beam.diameter": {
        "distribution": "uniform", "low": 0.1, "high": 0.2}}}, raw, "test")
    context = prepare(raw, spec, "test")
    good = evaluate(context, [0.2], index=0)
    assert good["status"] != "failed" and good["error"] == ""
    bad = evaluate(context, [0.1], index=1)
    assert bad["status"] == "failed"
    assert "limits.states" in bad["error"] and "would have 42 states" in bad["error"]
    assert "appendages[0].tip" in bad["error"]


@pytest.mark.slow
def test_the_tolerance_search_tries_no_truth_over_the_limit():
    """From the tolerance, the most modes the search may try are sized by the rod's real
    count: the truth at that n fits the limit and one more mode would not."""
    raw = scene(limit=40, fidelity={})
    loop = DesignLoop(load_scene(raw))
    n_max = loop.max_modes()
    spec = loop.scene.appendages[0]

    def states(n):
        # the PD's read-time margin of two controller states, as the search counts it
        return 2 * (3 + loop.truncation(loop.undamped_beam(spec), n).n_modes) + 2
    assert states(n_max) <= 40 < states(n_max + 1)
    assert loop.n_modes <= n_max


@pytest.mark.parametrize("three_axis", [False, True])
@pytest.mark.parametrize("pd", [{}, {"roll_off": 5.0}, {"roll_off": 5.0, "notch": 2.0}])
def test_the_pd_states_counted_before_tuning_are_the_tuned_ones(three_axis, pd):
    """:func:`controller_states` against the PD flexsat tunes (each filter second order per
    torque), on a rod's truth in the plane and in three axes."""
    raw = copy.deepcopy(SCENE)
    raw["controller"] = {"types": ["pd"], "pd": {"natural_frequency": 0.1, **pd}}
    raw["fidelity"] = {"n_modes": 1}
    raw["appendages"][0].pop("tip")
    if not three_axis:
        raw["hub"]["inertia"] = 50.0
        raw["appendages"][0].update(position=[0.5, 0.0], direction=0.0)
        del raw["appendages"][0]["orientation"]
        del raw["manoeuvre"]["slew_axis"]
    loaded = load_scene(raw)
    K = DesignLoop(loaded).tuned("design", "pd", 1).controller
    assert controller_states(loaded.controller, "pd", 0, three_axis) == K.nstates
    assert K.nstates == (3 if three_axis else 1) * 2 * len(pd)


def test_the_lqr_states_counted_before_tuning_bound_the_tuned_ones():
    raw = scene(limit=1200, controller={
        "types": ["lqr"], "lqr": {"attitude_weight": 1.0, "torque_weight": 1.0}})
    loop = DesignLoop(load_scene(raw))
    plant, _ = loop.design_plant("design", N_MODES)
    K = loop.tuned("design", "lqr", N_MODES).controller
    assert K.nstates <= controller_states(loop.scene.controller, "lqr", plant.nstates, True)
    assert np.isfinite(K.A).all()


def _rod_scene(three_axis: bool, controller: dict) -> dict:
    """The rod without its tip body, one mode, in the plane or in three axes."""
    raw = copy.deepcopy(SCENE)
    raw["controller"] = controller
    raw["fidelity"] = {"n_modes": 1}
    raw["appendages"][0].pop("tip")
    del raw["manoeuvre"]["step"]   # the default fits a digital or delayed loop
    if not three_axis:
        raw["hub"]["inertia"] = 50.0
        raw["appendages"][0].update(position=[0.5, 0.0], direction=0.0)
        del raw["appendages"][0]["orientation"]
        del raw["manoeuvre"]["slew_axis"]
    return raw


PD = {"natural_frequency": 0.1, "roll_off": 5.0}
LQR = {"attitude_weight": 1.0, "torque_weight": 1.0}


@pytest.mark.parametrize("three_axis", [False, True])
@pytest.mark.parametrize("controller", [
    {"types": ["pd"], "pd": PD, "delay": 0.05},
    {"types": ["pd"], "pd": {"natural_frequency": 0.1}, "delay": 0.3},
    {"types": ["pd"], "pd": PD, "sample_rate": 10.0, "delay": 0.25},
    # 0.2 s and one sample: 3 samples (tau / T = 2.9999... snapped)
    {"types": ["lqr"], "lqr": LQR, "sample_rate": 10.0, "delay": 0.2,
     "computation_delay": True},
    {"types": ["lqr"], "lqr": LQR, "sample_rate": 10.0},
], ids=["continuous", "continuous-long", "digital", "digital-computation", "no-delay"])
def test_the_states_counted_before_tuning_are_those_of_the_loops_built(three_axis, controller):
    """Plant, controller and a delayed loop's delay line (the past commands, per torque),
    counted before any controller is tuned: the largest loop the run then closes has that
    many states."""
    loop = DesignLoop(load_scene(_rod_scene(three_axis, controller)), time_responses=False)
    counted = loop.check_loop_states(1)
    kind = controller["types"][0]
    built = loop.closed_loops("design", kind).loops
    assert counted == max(x.nstates for x in built.values())


def test_a_long_delay_line_is_refused_by_its_key_when_the_scene_is_read():
    """A digital PD at 10 Hz with a 5 s delay: the loop holds the last 50 commands; a planar
    rod's truth of one mode has 2 (3 + 1) = 8 states (the estimate's), its loop 8 + 2 + 50."""
    raw = _rod_scene(False, {"types": ["pd"], "pd": {"natural_frequency": 0.1},
                             "sample_rate": 10.0, "delay": 5.0})
    raw["manoeuvre"]["duration"] = 60.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # the reader's word on a long delay: not tested here
        with pytest.raises(SceneError, match=r"controller\.delay: .*60 states.*limits\.states"):
            load_scene(raw, limits={"states": 59})


@pytest.mark.parametrize("three_axis", [False, True])
@pytest.mark.parametrize("design", ["truth", "fit", "chain"])
@pytest.mark.parametrize("prune", [True, False])
@pytest.mark.parametrize("force", [False, True])
def test_the_read_time_estimate_bounds_the_loops_of_beams_with_separate_motions(
        three_axis, design, prune, force):
    """Where no beam's modes are ranked together, the read-time estimate is an upper bound of
    the loops the run builds: a three-axis chain's hinges move in four ways (a three-body fit
    of the rod, 2 x 4 hinge coordinates), a three-axis plant with disturbance inputs may keep
    the hub's translations."""
    from scenes import rod_chain

    raw = _rod_scene(three_axis, {"types": ["pd"], "pd": PD})
    rod = raw["appendages"][0]
    rod["design"] = design
    if design == "fit":
        rod["fit"] = {"n_bodies": 3}
    elif design == "chain":
        rod["chain"] = rod_chain(three_axis)
    raw["fidelity"]["prune"] = prune
    if force:
        raw["manoeuvre"]["disturbance"] = (
            {"input": "force", "amplitude": 1.0, "axis": [0.0, 1.0, 0.0]} if three_axis
            else {"input": "force_y", "amplitude": 1.0})
    loaded = load_scene(raw)
    built = DesignLoop(loaded, time_responses=False).check_loop_states(1)
    assert estimate_cost(loaded).loop_states >= built
