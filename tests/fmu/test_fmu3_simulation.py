"""FMI 3.0 FMUs simulated by fmpy against python-control, and against the FMI 2.0 FMUs of
the same systems (one model code: the two versions must agree to the last bit).

- Co-Simulation: exact for inputs held over each step, so it equals
  ``control.c2d(sys, h, "zoh")`` + ``forced_response`` to round-off: the ZOH map is the same
  on both sides and each step adds a few ulps of |x|, so over N = 400 steps of a lightly
  damped (non-growing) mode the difference stays below N * 10 eps relative, 1e-12.
- Model Exchange: the continuous response to the solver's tolerance (as for FMI 2.0).
- Steps other than the default one (computed in C), checked against 40-digit arithmetic.
"""

import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi3 import FMU3Slave

from fmu_cases import exported, hub
from fmu_references import augmented_exponential_mp, step_table, zoh_reference

SWITCH_TIMES, VALUES = [0.0, 0.5, 1.5, 2.5], [0.0, 1.0, -2.0, 0.5]


def simulate(version: str, interface: str, h: float, **kwargs) -> np.ndarray:
    return simulate_fmu(str(exported("hub", version)), fmi_type=interface, stop_time=4.0,
                        output_interval=h, input=step_table(SWITCH_TIMES, VALUES), **kwargs)


@pytest.mark.parametrize("h", [0.01, 0.025, 0.1])
def test_cs_equals_c2d_zoh(h):
    """h = 0.01 s is the default step (matrices precomputed in Python), the others are
    computed in C; every switch time lies on each grid."""
    result = simulate("3.0", "CoSimulation", h)
    t, y = zoh_reference(hub(), h, 4.0, SWITCH_TIMES, VALUES)
    np.testing.assert_allclose(result["time"], t, rtol=0, atol=1e-12)
    for i, name in enumerate(["theta", "omega"]):
        np.testing.assert_allclose(result[name], y[i], rtol=0, atol=1e-12 * np.max(np.abs(y[i])))


def test_me_equals_continuous_response():
    """CVode (rtol 1e-10): the error is the solver's, as for the FMI 2.0 FMU
    (test_fmu_simulation.test_me_equals_continuous_response)."""
    h = 0.01
    t, y = zoh_reference(hub(), h, 4.0, SWITCH_TIMES, VALUES)
    result = simulate("3.0", "ModelExchange", h, relative_tolerance=1e-10)
    last = np.r_[np.diff(result["time"]) > 0, True]
    np.testing.assert_allclose(result["time"][last], t, rtol=0, atol=1e-9)
    for i, name in enumerate(["theta", "omega"]):
        assert np.max(np.abs(result[name][last] - y[i])) < 1e-6 * np.max(np.abs(y[i]))


@pytest.mark.parametrize("interface", ["CoSimulation", "ModelExchange"])
def test_fmi3_equals_fmi2_bit_for_bit(interface):
    """The same model code, the same arithmetic: FMI 3.0 and FMI 2.0 give identical
    results through fmpy's CS loop and through CVode (same right-hand sides, same calls)."""
    a = simulate("2.0", interface, 0.01, relative_tolerance=1e-8)
    b = simulate("3.0", interface, 0.01, relative_tolerance=1e-8)
    for name in ("time", "theta", "omega"):
        np.testing.assert_array_equal(a[name], b[name])


@pytest.mark.parametrize("h", [0.037, 1e-6, 2.5])
def test_any_step_size_is_exact(h):
    """One fmi3DoStep of size h from x = [1, 2, 3, 4] with torque = 0.7, against the
    augmented exponential in 40-digit arithmetic: 1e-12 relative (as for FMI 2.0)."""
    path = exported("hub", "3.0")
    description = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in description.modelVariables}
    slave = FMU3Slave(guid=description.guid, unzipDirectory=extract(str(path)),
                      modelIdentifier=description.coSimulation.modelIdentifier, instanceName="h")
    states = [vr[s] for s in ("q", "q_dot", "eta", "eta_dot")]
    x = np.array([1.0, 2.0, 3.0, 4.0])
    slave.instantiate()
    try:
        slave.setFloat64(states, list(x))  # start values, settable when instantiated
        slave.enterInitializationMode(startTime=0.0)
        slave.exitInitializationMode()
        slave.setFloat64([vr["torque"]], [0.7])
        event, terminate, early, last = slave.doStep(0.0, h)
        got = np.array(slave.getFloat64(states))
        slave.terminate()
    finally:
        slave.freeInstance()
    assert (event, terminate, early, last) == (False, False, False, h)
    expected = augmented_exponential_mp(hub(), h, x, 0.7)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12 * np.max(np.abs(expected)))


def test_time_variable_follows_the_simulation():
    """The independent variable 'time' reads the instance's time (fmi3GetFloat64)."""
    path = exported("hub", "3.0")
    description = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in description.modelVariables}
    slave = FMU3Slave(guid=description.guid, unzipDirectory=extract(str(path)),
                      modelIdentifier=description.coSimulation.modelIdentifier, instanceName="t")
    slave.instantiate()
    try:
        slave.enterInitializationMode(startTime=1.5)
        slave.exitInitializationMode()
        assert slave.getFloat64([vr["time"]]) == [1.5]
        slave.doStep(1.5, 0.25)
        assert slave.getFloat64([vr["time"]]) == [1.75]
        slave.terminate()
    finally:
        slave.freeInstance()
