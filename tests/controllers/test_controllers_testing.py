"""assert_closed_loops_close: the helper users put into their own test suites."""
import json
import math

import pytest

import controllers
from plants import modal_plant
from controllers.testing import compare_metrics


J = 250.0
CHAIN = modal_plant(J, [(2.0, 0.005, 0.06, 0.06)], disturbance=False)
BEAM = modal_plant(J, [(2.05, 0.005, 0.061, 0.061), (12.0, 0.005, 0.02, 0.02)],
                    disturbance=False)
EXPECTED = {"overshoot": 4.0, "settling_time": 30.0, "peak_torque": 0.5, "phase_margin": 45.0}


def test_passes_within_tolerance():
    actual = {"overshoot": 4.1, "settling_time": 30.5, "peak_torque": 0.49, "phase_margin": 44.0}
    controllers.assert_closed_loops_close(actual, EXPECTED, rtol=0.05)  # all within 5 %


def test_failure_message_is_a_readable_table():
    actual = {"overshoot": 6.0, "settling_time": 30.5, "peak_torque": 0.49, "phase_margin": 44.0}
    with pytest.raises(AssertionError) as info:
        controllers.assert_closed_loops_close(actual, EXPECTED, rtol=0.05, atol={"overshoot": 0.5})
    message = str(info.value)
    print(message)  # shown with pytest -s: what a user sees
    lines = message.splitlines()
    assert lines[0].startswith("closed loops differ in 1 of 4 metrics")
    assert lines[1].split() == ["metric", "unit", "actual", "expected", "abs", "diff", "rel",
                                "diff", "tolerance", "status"]
    row = next(line for line in lines if line.startswith("overshoot"))
    # overshoot: |6 - 4| = 2 > 0.5 + 0.05 * 4 = 0.7; relative difference 0.5
    assert row.split() == ["overshoot", "%", "6", "4", "2", "0.5", "0.7", "FAIL"]
    row = next(line for line in lines if line.startswith("settling_time"))
    assert row.split()[-1] == "PASS" and row.split()[1] == "s"
    assert sum(line.endswith("FAIL") for line in lines) == 1


def test_missing_metric_and_infinities():
    with pytest.raises(AssertionError, match=r"peak_torque .* missing .*FAIL"):
        controllers.assert_closed_loops_close({"overshoot": 4.0}, {"overshoot": 4.0,
                                                                   "peak_torque": 1.0})
    # equal infinities (no gain margin on either loop) agree; finite vs inf does not
    ok, _ = compare_metrics({"gain_margin": math.inf}, {"gain_margin": math.inf})
    assert ok
    ok, table = compare_metrics({"gain_margin": 12.0}, {"gain_margin": math.inf})
    assert not ok and "inf" in table and "nan" not in table
    # only the requested metrics are compared
    controllers.assert_closed_loops_close({"overshoot": 4.0, "peak_torque": 9.0},
                                          {"overshoot": 4.0, "peak_torque": 1.0},
                                          metrics=["overshoot"])


def test_closed_loops_and_stored_reference(tmp_path):
    K = controllers.pd(CHAIN, natural_frequency=0.3)
    chain_loop = controllers.close_loop(CHAIN, K)
    beam_loop = controllers.close_loop(BEAM, K)
    # the chain-tuned PD still meets its slew metrics on the beam within 5 %
    controllers.assert_closed_loops_close(beam_loop, chain_loop, angle=0.2, duration=30.0,
                                          rtol=0.05, atol={"final_attitude_error": 1e-6})
    # a stored reference (JSON) against a closed loop
    reference = controllers.metrics(controllers.slew(chain_loop, 0.2, 30.0))
    path = tmp_path / "reference.json"
    path.write_text(json.dumps(reference))
    controllers.assert_closed_loops_close(beam_loop, json.loads(path.read_text()), angle=0.2,
                                          duration=30.0, rtol=0.05,
                                          atol={"final_attitude_error": 1e-6})
    # a different controller fails, with the overshoot in the table
    stiff = controllers.close_loop(BEAM, controllers.pd(CHAIN, natural_frequency=0.3,
                                                        damping=0.3))
    with pytest.raises(AssertionError, match=r"overshoot\s+%.*FAIL"):
        controllers.assert_closed_loops_close(stiff, reference, angle=0.2, duration=30.0)


def test_errors():
    loop = controllers.close_loop(CHAIN, controllers.pd(CHAIN, natural_frequency=0.3))
    with pytest.raises(ValueError, match="give angle .* and duration"):
        controllers.assert_closed_loops_close(loop, EXPECTED)
    with pytest.raises(TypeError, match="actual must be a metrics mapping or a closed loop"):
        controllers.assert_closed_loops_close([1.0], EXPECTED)
    with pytest.raises(TypeError, match=r"expected\['overshoot'\] must be a number"):
        controllers.assert_closed_loops_close(EXPECTED, {"overshoot": "4"})
    with pytest.raises(ValueError, match="rtol for 'overshoot' must be non-negative"):
        controllers.assert_closed_loops_close(EXPECTED, EXPECTED, rtol=-0.1)
