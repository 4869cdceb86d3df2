"""A diverging loop's time metrics are withheld, per hub axis and per tip motion too: the numbers
of a growing response's first seconds would read as those of a loop that settles."""
from spacecraft.design.verdicts import withheld_metrics

THREE_AXIS = {
    "peak_torque": 1.0, "overshoot": 0.1, "settling_time": 90.0, "peak_attitude_error": 0.2,
    "final_attitude_error": 1e-4, "peak_tip_deflection": 1e-3,
    "peak_torque_x": 0.5, "peak_attitude_error_y": 0.1, "final_attitude_error_z": 1e-5,
    "peak_wing_left_tip_deflection_y": 1e-3, "peak_wing_left_tip_deflection_z": 2e-3,
    "peak_boom_tip_twist": 1e-6,
}


def test_every_time_metric_of_a_diverging_three_axis_loop_is_withheld():
    for kind in ("diverges", "unstable"):
        values, flags = withheld_metrics(THREE_AXIS, {"status": kind})
        assert all(values[k] is None for k in THREE_AXIS), kind
        assert set(flags) == set(THREE_AXIS) and set(flags.values()) == {"diverges"}
        assert values["diverged"] is True


def test_an_unfinished_slew_withholds_overshoot_and_settling_only():
    metrics = {**THREE_AXIS, "overshoot_x": 0.1, "settling_time_y": 80.0}
    values, flags = withheld_metrics(metrics, {"status": "slew unfinished"})
    assert set(flags) == {"overshoot", "settling_time", "overshoot_x", "settling_time_y"}
    assert values["peak_torque_x"] == 0.5 and values["peak_boom_tip_twist"] == 1e-6


def test_a_settling_loop_keeps_every_number():
    values, flags = withheld_metrics(THREE_AXIS, {"status": "settles"})
    assert flags == {} and all(values[k] == v for k, v in THREE_AXIS.items())
    assert values["diverged"] is False
