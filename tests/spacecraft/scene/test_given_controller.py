"""A controller given as numbers in a scene (spacecraft/scene/given.py): the same loop as
the tuned controller it records, and bad tables refused by key."""
import copy
import tomllib

import numpy as np
import pytest

from spacecraft.scene.given import controller_record, given_state_space, read_given
from spacecraft.report.write import write_report
from spacecraft.design.loop import run
from spacecraft.scene.read import SceneError, load_scene, scene_path


def single_boom():
    return tomllib.loads(scene_path("single_boom").read_text())


def with_given(raw, record):
    raw = copy.deepcopy(raw)
    raw["controller"]["given"] = record
    raw.pop("report", None)
    return raw


def loop_numbers(result):
    row = result.data["closed_loops"][0]
    return row["verdict"], row["metrics"]["truth"]


def test_a_recorded_controller_given_back_runs_the_same_loop(tmp_path):
    """The PD with roll-off of single_boom, recorded and given back: the runner closes the same
    matrices (bit for bit: the record writes every double in full), so the margins and the
    slew's metrics are equal to round-off (same process, same BLAS: 1e-12 relative)."""
    raw = single_boom()
    raw.pop("report", None)
    tuned = run(load_scene(raw))
    K = tuned.designs["poles-and-zeros"]["controllers"]["pd"]
    record = controller_record(K, "pd")
    assert record["kind"] == "pd" and len(record["A"]) == K.nstates == 2
    again = run(load_scene(with_given(raw, record),
                           overrides={"export.fmu": False, "report.plots": False}))
    K2 = again.designs["poles-and-zeros"]["controllers"]["pd"]
    for name in ("A", "B", "C", "D"):
        assert np.array_equal(getattr(K2, name), getattr(K, name)), name
    described = again.data["controllers"]["poles-and-zeros"]["pd"]
    assert described["given"] is True and described["D"] == record["D"]
    (v1, m1), (v2, m2) = loop_numbers(tuned), loop_numbers(again)
    for name in ("stable", "n_unstable_poles"):
        assert v1[name] == v2[name]
    for name in ("gain_margin", "phase_margin", "modulus_margin"):
        assert v2[name] == pytest.approx(v1[name], rel=1e-12), name
    for name in ("overshoot", "settling_time", "peak_torque"):
        assert m2[name] == pytest.approx(m1[name], rel=1e-12, abs=1e-15), name
    # the report says the controller was given, not tuned
    write_report(again, tmp_path)
    assert "given in the scene (controller.given): 2 states" in (tmp_path / "report.md").read_text()


def test_a_static_pd_given_by_its_gains():
    """D = [[Kp, -Kp, -Kd]] without states is torque = Kp (theta_ref - theta) - Kd omega:
    the same controller as a PD tuned without filters (whose gains these are)."""
    raw = single_boom()
    raw.pop("report", None)
    del raw["controller"]["pd"]["roll_off"]
    tuned = run(load_scene(raw), time_responses=False)
    c = tuned.data["controllers"]["poles-and-zeros"]["pd"]
    record = {"kind": "pd", "D": [[c["Kp"], -c["Kp"], -c["Kd"]]]}
    again = run(load_scene(with_given(raw, record)), time_responses=False)
    K = again.designs["poles-and-zeros"]["controllers"]["pd"]
    assert K.nstates == 0 and K.dt == 0
    assert list(K.input_labels) == ["theta_ref", "theta", "omega"]
    for name in ("gain_margin", "phase_margin", "modulus_margin"):
        assert (again.data["closed_loops"][0]["verdict"][name]
                == pytest.approx(tuned.data["closed_loops"][0]["verdict"][name], rel=1e-9))


def test_a_digital_given_controller_samples_at_the_scene_rate():
    given = read_given({"kind": "pd", "A": [[0.5]], "B": [[1.0, -1.0, 0.0]], "C": [[0.1]],
                        "D": [[2.0, -2.0, -3.0]]}, "controller.given", ("pd",),
                       lambda key, problem: SceneError(f"{key}: {problem}"))
    K = given_state_space(given, 0.1)
    assert K.dt == 0.1 and K.nstates == 1 and list(K.output_labels) == ["torque"]


@pytest.mark.parametrize("given, match", [
    ({"kind": "lqr", "D": [[1.0, -1.0, -1.0]]}, r"controller\.given\.kind: must name one of "
                                                r"controller\.types \('pd'\); got 'lqr'"),
    ({"kind": "pd"}, r"controller\.given\.D: missing required value"),
    ({"kind": "pd", "D": [[1.0, -1.0]]}, r"controller\.given\.D: must be 1 x 3 .*got 1 x 2"),
    ({"kind": "pd", "A": [[1.0]], "D": [[1.0, -1.0, -1.0]]},
     r"controller\.given\.B: must be 1 x 3 \(the controller has 1 states"),
    ({"kind": "pd", "D": [[1.0, float("nan"), -1.0]]},
     r"controller\.given\.D\[0\]\[1\]: must be a finite number"),
    ({"kind": "pd", "D": [[1.0, -1.0, -1.0]], "gains": 1}, r"controller\.given\.gains: unknown"),
    ("K.json", r"controller\.given: must be a table"),
])
def test_bad_given_controllers_are_refused_by_key(given, match):
    raw = with_given(single_boom(), given)
    with pytest.raises(SceneError, match=match):
        load_scene(raw)


def test_a_three_axis_scene_refuses_a_given_controller():
    raw = tomllib.loads(scene_path("three_axis").read_text())
    kind = raw["controller"]["types"][0]
    raw["controller"]["given"] = {"kind": kind, "D": [[1.0, -1.0, -1.0]]}
    with pytest.raises(SceneError, match=r"controller\.given: a given controller is planar"):
        load_scene(raw)
