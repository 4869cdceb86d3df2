"""A controller given as numbers in a scene (spacecraft/scene/given.py): the same loop as
the tuned controller it records, and bad tables refused by key."""
import copy
import math
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


def three_axis_soft():
    """The shipped three-axis scene, trimmed to a PD with notch on the fitted chains, its
    truth at a fixed two modes a beam, without exports, plots or the exact reference."""
    raw = tomllib.loads(scene_path("three_axis").read_text())
    raw["controller"]["types"] = ["pd"]
    raw["controller"].pop("lqr")
    raw["fidelity"] = {"n_modes": 2}
    raw["outputs"]["exact_reference"] = False
    raw.pop("export")
    raw.pop("report")
    return raw


def test_a_three_axis_controller_given_back_runs_the_same_loop():
    """A three-axis PD with notch (6 states, 9 inputs, 3 torques), recorded and given back in
    the three-axis scene: the design loop closes the same matrices bit for bit, so its
    multiloop margins (loop at a time and disk) and slew metrics are the tuned one's to
    round-off (same process: 1e-12 relative)."""
    raw = three_axis_soft()
    tuned = run(load_scene(raw))
    K = tuned.designs["poles-and-zeros"]["controllers"]["pd"]
    record = controller_record(K, "pd")
    assert np.shape(record["B"]) == (K.nstates, 9) and np.shape(record["D"]) == (3, 9)
    assert np.shape(record["C"]) == (3, K.nstates)
    again = run(load_scene(with_given(raw, record)))
    K2 = again.designs["poles-and-zeros"]["controllers"]["pd"]
    assert list(K2.input_labels) == list(K.input_labels)
    assert list(K2.output_labels) == list(K.output_labels)
    for name in ("A", "B", "C", "D"):
        assert np.array_equal(getattr(K2, name), getattr(K, name)), name
    described = again.data["controllers"]["poles-and-zeros"]["pd"]
    assert described["given"] is True and "about x, y, z" in described["structure"]
    (v1, m1), (v2, m2) = loop_numbers(tuned), loop_numbers(again)
    assert v1["stable"] == v2["stable"] and v1["n_unstable_poles"] == v2["n_unstable_poles"]
    names = [k for k in v1 if k.startswith(("gain_margin_", "phase_margin_", "modulus_margin_",
                                            "disk_", "min_singular_value"))
             and not k.endswith("frequency")]
    assert len(names) >= 13
    for name in names:
        assert v2[name] == pytest.approx(v1[name], rel=1e-12), name
    for name in ("peak_torque_x", "peak_torque_y", "peak_torque_z", "settling_time"):
        assert m2[name] == pytest.approx(m1[name], rel=1e-12, abs=1e-15), name


def test_the_three_axis_signals_are_the_controllers_convention():
    from controllers.signals import THREE_AXIS

    from spacecraft.scene.given import INPUTS_3D, OUTPUTS_3D

    assert INPUTS_3D == THREE_AXIS.refs + THREE_AXIS.thetas + THREE_AXIS.omegas
    assert OUTPUTS_3D == THREE_AXIS.torques


def test_a_three_axis_record_keeps_the_signal_order():
    """A controller whose inputs and outputs come in another order is recorded in the order of
    channel_names, and read back to the same transfer (D permuted, not copied)."""
    import control

    from spacecraft.scene.given import INPUTS_3D, OUTPUTS_3D, GivenController

    rng = np.random.default_rng(3)
    D = rng.normal(size=(3, 9))
    inputs, outputs = list(INPUTS_3D)[::-1], list(OUTPUTS_3D)[::-1]
    K = control.ss([], [], [], D, 0, inputs=inputs, outputs=outputs)
    record = controller_record(K, "pd")
    expected = D[::-1, ::-1]
    assert np.array_equal(np.array(record["D"]), expected)
    back = given_state_space(GivenController("pd", (), (), (), tuple(map(tuple, expected))),
                             None)
    assert list(back.input_labels) == list(INPUTS_3D)
    assert list(back.output_labels) == list(OUTPUTS_3D)


@pytest.mark.parametrize("given, match", [
    ({"kind": "pd", "D": [[1.0, -1.0, -1.0]]},
     r"controller\.given\.D: must be 3 x 9 .*9 inputs and 3 outputs in a three-axis scene"),
    ({"kind": "pd", "A": [[-1.0]], "B": [[0.0] * 9], "C": [[1.0]], "D": [[0.0] * 9] * 3},
     r"controller\.given\.C: must be 3 x 1"),
    ({"kind": "pd"}, r"controller\.given\.D: missing required value \(3 x 9"),
    ({"kind": "pd", "D": [[0.0] * 9, [0.0] * 9, [0.0] * 8 + [math.nan]]},
     r"controller\.given\.D\[2\]\[8\]: must be a finite number"),
])
def test_bad_three_axis_given_controllers_are_refused_by_key(given, match):
    raw = with_given(three_axis_soft(), given)
    with pytest.raises(SceneError, match=match):
        load_scene(raw)
