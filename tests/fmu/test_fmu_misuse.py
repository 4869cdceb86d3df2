"""The FMU binary under misuse: it returns fmi2Error/fmi2Discard with a logged message and
never crashes. The binary is called directly through ctypes (null pointers, wrong GUID,
calls in the wrong state, NaN inputs) and through fmpy's low-level FMU2Model API (direct
feedthrough in Model Exchange).
"""

import ctypes
from ctypes import POINTER, byref, c_char_p, c_double, c_int, c_size_t, c_uint, c_void_p

import control
import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model, fmi2CallbackFunctions

from fmu import export

from fmi_binary import (CO_SIMULATION, DISCARD, ERROR, LAST_SUCCESSFUL_TIME, MODEL_EXCHANGE, OK,
                        Binary)


def plant():
    """Rigid body J theta'' = torque, J = 10 kg m^2; outputs theta, omega."""
    return control.ss([[0, 1], [0, 0]], [[0], [0.1]], np.eye(2), 0, inputs=["torque"],
                      outputs=["theta", "omega"], states=["angle", "rate"], name="body")


def pd_controller():
    """torque = 20 (theta_ref - theta) - 30 omega: 0 states, D != 0."""
    return control.ss(np.zeros((0, 0)), np.zeros((0, 3)), np.zeros((1, 0)), [[20.0, -20.0, -30.0]],
                      inputs=["theta_ref", "theta", "omega"], outputs=["torque"], name="pd")


def unstable():
    """x' = 100 x: exp(100 h) overflows for h > 7.1 s."""
    return control.ss([[100.0]], [[1.0]], [[1.0]], 0, inputs=["u"], outputs=["y"], states=["x"])


@pytest.fixture(scope="module")
def binaries(tmp_path_factory):
    folder = tmp_path_factory.mktemp("misuse")
    result = {}
    for name, system in (("body", plant()), ("pd", pd_controller()), ("unstable", unstable())):
        path = export(system, folder / f"{name}.fmu")
        result[name] = Binary(path, folder / name)
    return result


@pytest.fixture
def body(binaries):
    binary = binaries["body"]
    binary.messages.clear()
    return binary


def test_wrong_guid_is_refused_with_a_message(body):
    assert not body.instantiate(guid=b"{00000000-0000-0000-0000-000000000000}")
    assert body.messages[-1][0] == ERROR
    assert "wrong GUID {00000000-0000-0000-0000-000000000000}" in body.last_message()
    assert body.guid.decode() in body.last_message()


def test_null_arguments_to_instantiate(body):
    assert not body.Instantiate(None, CO_SIMULATION, body.guid, None, byref(body.callbacks), 0, 0)
    assert "instanceName must be a non-empty string" in body.last_message()
    assert not body.Instantiate(b"x", CO_SIMULATION, None, None, byref(body.callbacks), 0, 0)
    assert "wrong GUID (null)" in body.last_message()
    assert not body.Instantiate(b"x", CO_SIMULATION, body.guid, None, None, 0, 0)  # no callbacks
    assert not body.Instantiate(b"x", 7, body.guid, None, byref(body.callbacks), 0, 0)
    assert "unknown fmuType 7" in body.last_message()


def test_memory_callbacks(body):
    """Without allocateMemory/freeMemory the FMU falls back to calloc/free; with only one
    of them it refuses (it could not free what it allocated)."""
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = body.callbacks.logger
    c = body.Instantiate(b"libc", CO_SIMULATION, body.guid, None, byref(callbacks), 0, 0)
    assert c
    body.FreeInstance(c)
    callbacks.allocateMemory = body.callbacks.allocateMemory
    assert not body.Instantiate(b"half", CO_SIMULATION, body.guid, None, byref(callbacks), 0, 0)
    assert "allocateMemory and freeMemory must both be given" in body.last_message()


def test_null_instance_is_an_error_not_a_crash(body):
    values = (c_double * 1)()
    vrs = (c_uint * 1)(0)
    assert body.GetReal(None, vrs, 1, values) == ERROR
    assert body.SetReal(None, vrs, 1, values) == ERROR
    assert body.DoStep(None, 0.0, 0.01, 1) == ERROR
    assert body.Terminate(None) == ERROR
    assert body.Reset(None) == ERROR
    body.FreeInstance(None)  # returns without touching anything


def test_null_arrays_are_errors(body):
    c = body.initialised()
    try:
        values = (c_double * 2)()
        vrs = (c_uint * 2)(body.vr["theta"], body.vr["omega"])
        assert body.GetReal(c, None, 2, values) == ERROR
        assert "fmi2GetReal: argument vr is NULL although 2 values were requested" in body.last_message()
        assert body.GetReal(c, vrs, 2, None) == ERROR
        assert "argument value is NULL" in body.last_message()
        assert body.SetReal(c, vrs, 1, None) == ERROR
        assert body.GetReal(c, None, 0, None) == OK  # nothing requested, nothing read
        assert body.GetRealStatus(c, LAST_SUCCESSFUL_TIME, None) == ERROR
        assert body.SetDebugLogging(c, 1, 1, None) == ERROR
    finally:
        body.FreeInstance(c)


def test_calls_in_the_wrong_state(body):
    c = body.instantiate()
    try:
        assert body.DoStep(c, 0.0, 0.01, 1) == ERROR
        assert body.last_message() == "fmi2DoStep must not be called in state Instantiated."
        assert body.get(c, "theta")[0] == ERROR
        assert body.ExitInitializationMode(c) == ERROR
        assert "fmi2ExitInitializationMode must not be called in state Instantiated" in body.last_message()
        assert body.EnterInitializationMode(c) == OK
        assert body.SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == ERROR
        assert body.ExitInitializationMode(c) == OK
        # Model Exchange functions on a Co-Simulation instance
        assert body.SetTime(c, 1.0) == ERROR
        assert "Model Exchange function; this instance is Co-Simulation" in body.last_message()
        assert body.Terminate(c) == OK
        assert body.DoStep(c, 0.0, 0.01, 1) == ERROR
        assert "state Terminated" in body.last_message()
        assert body.get(c, "theta") == (OK, [0.0])  # reading after termination is allowed
        assert body.Reset(c) == OK  # back to Instantiated, usable again
        assert body.EnterInitializationMode(c) == OK
    finally:
        body.FreeInstance(c)


def test_nan_input_is_refused_and_changes_nothing(body):
    c = body.initialised()
    try:
        assert body.set(c, torque=2.0) == OK
        assert body.set(c, torque=float("nan")) == ERROR
        assert "input torque must be finite; got nan" in body.last_message()
        assert body.set(c, torque=float("inf")) == ERROR
        assert body.get(c, "torque") == (OK, [2.0])
        # the instance stays usable: one exact step of J theta'' = 2 N m from rest
        assert body.DoStep(c, 0.0, 0.1, 1) == OK
        status, (theta, omega) = body.get(c, "theta", "omega")
        assert status == OK
        assert theta == pytest.approx(2.0 / 10.0 * 0.1**2 / 2, rel=1e-14)  # torque/J t^2/2
        assert omega == pytest.approx(2.0 / 10.0 * 0.1, rel=1e-14)
    finally:
        body.FreeInstance(c)


def test_bad_value_references_and_causalities(body):
    c = body.instantiate()
    try:
        assert body.set(c, angle=0.3) == OK  # a state before initialisation: start value
        vrs = (c_uint * 1)(999)
        value = (c_double * 1)(1.0)
        assert body.SetReal(c, vrs, 1, value) == ERROR
        assert "unknown value reference 999" in body.last_message()
        assert body.set(c, theta=1.0) == ERROR
        assert "theta is calculated and cannot be set" in body.last_message()
        assert body.EnterInitializationMode(c) == OK
        assert body.ExitInitializationMode(c) == OK
        assert body.get(c, "theta") == (OK, [0.3])
        assert body.set(c, angle=0.0) == ERROR
        assert "state angle can only be set before initialisation" in body.last_message()
        ints = (c_int * 1)()
        assert body.GetInteger(c, vrs, 1, ints) == ERROR
        assert "only Real variables" in body.last_message()
    finally:
        body.FreeInstance(c)


def test_bad_steps(body):
    c = body.initialised()
    try:
        assert body.DoStep(c, 0.0, 0.0, 1) == ERROR
        assert "communicationStepSize must be positive and finite [s]; got 0" in body.last_message()
        assert body.DoStep(c, 0.0, float("nan"), 1) == ERROR
        assert body.DoStep(c, 5.0, 0.01, 1) == ERROR
        assert "currentCommunicationPoint must equal the time reached so far" in body.last_message()
        assert body.DoStep(c, 0.0, 0.01, 1) == OK
        time = c_double()
        assert body.GetRealStatus(c, LAST_SUCCESSFUL_TIME, byref(time)) == OK
        assert time.value == 0.01
    finally:
        body.FreeInstance(c)


def test_unknown_log_category_is_an_error(body):
    c = body.initialised()
    try:
        categories = (c_char_p * 1)(b"logEverything")
        assert body.SetDebugLogging(c, 1, 1, categories) == ERROR
        assert 'unknown log category "logEverything"' in body.last_message()
    finally:
        body.FreeInstance(c)


def test_overflowing_step_is_discarded(binaries):
    """x' = 100 x over 10 s: exp(1000) overflows; the step is discarded, state kept."""
    binary = binaries["unstable"]
    c = binary.instantiate()
    try:
        assert binary.set(c, x=1.0) == OK
        assert binary.SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == OK
        assert binary.EnterInitializationMode(c) == OK
        assert binary.ExitInitializationMode(c) == OK
        assert binary.DoStep(c, 0.0, 10.0, 1) == DISCARD
        assert "not finite" in binary.last_message()
        assert binary.get(c, "x") == (OK, [1.0])
        time = c_double(-1.0)
        assert binary.GetRealStatus(c, LAST_SUCCESSFUL_TIME, byref(time)) == OK
        assert time.value == 0.0
        assert binary.DoStep(c, 0.0, 0.01, 1) == ERROR  # StepFailed: only reset or free
        assert binary.Terminate(c) == OK
    finally:
        binary.FreeInstance(c)


def test_model_exchange_misuse(body):
    c = body.initialised(MODEL_EXCHANGE)
    try:
        assert body.NewDiscreteStates(c, None) == ERROR
        assert "eventInfo is NULL" in body.last_message()
        derivatives = (c_double * 2)()
        assert body.GetDerivatives(c, derivatives, 3) == ERROR
        assert "nx must be 2; got 3" in body.last_message()
        assert body.SetContinuousStates(c, derivatives, 2) == ERROR  # EventMode: not allowed
        assert body.SetTime(c, float("nan")) == ERROR
        assert body.DoStep(c, 0.0, 0.01, 1) == ERROR
        assert "Co-Simulation function; this instance is Model Exchange" in body.last_message()
    finally:
        body.FreeInstance(c)


def test_direct_feedthrough_in_model_exchange(binaries, tmp_path):
    """Outputs read right after setting inputs reflect them (fmpy's FMU2Model API)."""
    path = tmp_path / "pd.fmu"
    export(pd_controller(), path)
    description = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in description.modelVariables}
    model = FMU2Model(guid=description.guid, unzipDirectory=extract(str(path)),
                      modelIdentifier=description.modelExchange.modelIdentifier, instanceName="pd")
    model.instantiate()
    try:
        model.setupExperiment(startTime=0.0)
        model.enterInitializationMode()
        model.setReal([vr["theta_ref"], vr["theta"], vr["omega"]], [0.5, 0.1, 0.2])
        assert model.getReal([vr["torque"]]) == [20.0 * (0.5 - 0.1) - 30.0 * 0.2]
        model.exitInitializationMode()
        model.enterContinuousTimeMode()
        model.setReal([vr["theta"]], [0.4])
        assert model.getReal([vr["torque"]]) == [20.0 * (0.5 - 0.4) - 30.0 * 0.2]
        model.terminate()
    finally:
        model.freeInstance()


# ---------------------------------------------------------------- FMU states, derivatives


def bind(binary, name, restype, argtypes):
    function = getattr(binary.lib, name)
    function.restype, function.argtypes = restype, argtypes
    return function


def test_fmu_state_misuse(binaries):
    """fmi2 FMU state functions with null pointers, another instance's state, a freed
    state, a short buffer and foreign bytes: fmi2Error with a message, nothing crashes."""
    body = binaries["body"]
    body.messages.clear()
    set_state = bind(body, "fmi2SetFMUstate", c_int, [c_void_p, c_void_p])
    free_state = bind(body, "fmi2FreeFMUstate", c_int, [c_void_p, POINTER(c_void_p)])
    size_of = bind(body, "fmi2SerializedFMUstateSize", c_int, [c_void_p, c_void_p, POINTER(c_size_t)])
    serialize = bind(body, "fmi2SerializeFMUstate", c_int, [c_void_p, c_void_p, c_char_p, c_size_t])
    deserialize = bind(body, "fmi2DeSerializeFMUstate", c_int,
                       [c_void_p, c_char_p, c_size_t, POINTER(c_void_p)])
    first, second = body.initialised(), body.initialised()
    try:
        state = c_void_p()
        assert body.GetFMUstate(first, None) == ERROR
        assert "argument FMUstate is NULL" in body.last_message()
        assert body.GetFMUstate(first, byref(state)) == OK
        assert set_state(second, state) == ERROR
        assert "FMUstate is not a state of this instance" in body.last_message()
        size = c_size_t()
        assert size_of(first, state, byref(size)) == OK
        buffer = ctypes.create_string_buffer(size.value)
        assert serialize(first, state, buffer, size.value - 1) == ERROR
        assert f"size must be at least {size.value} bytes" in body.last_message()
        assert serialize(first, state, buffer, size.value) == OK
        copy = c_void_p()
        assert deserialize(second, buffer.raw[:-1], size.value - 1, byref(copy)) == ERROR
        assert "its size is not that of a state of this model" in body.last_message()
        assert deserialize(second, buffer.raw, size.value, byref(copy)) == OK  # same model
        assert free_state(first, byref(state)) == OK and state.value is None
        assert free_state(first, byref(copy)) == ERROR  # second's state, not first's
        assert "not a state of this instance" in body.last_message()
        assert free_state(second, byref(copy)) == OK
        assert free_state(second, byref(copy)) == OK  # NULL now: nothing to free
    finally:
        body.FreeInstance(first)
        body.FreeInstance(second)


def test_rollback_after_a_discarded_step(binaries):
    """The mode is part of the FMU state: a state saved in StepComplete restores an
    instance that a discarded step left in StepFailed, and stepping goes on."""
    binary = binaries["unstable"]
    set_state = bind(binary, "fmi2SetFMUstate", c_int, [c_void_p, c_void_p])
    c = binary.instantiate()
    try:
        assert binary.set(c, x=1.0) == OK
        assert binary.SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == OK
        assert binary.EnterInitializationMode(c) == OK
        assert binary.ExitInitializationMode(c) == OK
        state = c_void_p()
        assert binary.GetFMUstate(c, byref(state)) == OK
        assert binary.DoStep(c, 0.0, 10.0, 1) == DISCARD
        assert binary.DoStep(c, 0.0, 0.01, 1) == ERROR  # StepFailed
        assert set_state(c, state) == OK
        assert binary.DoStep(c, 0.0, 0.01, 1) == OK
        assert binary.get(c, "x")[1][0] == pytest.approx(np.exp(1.0), rel=1e-14)
    finally:
        binary.FreeInstance(c)


def test_directional_derivative_misuse(binaries):
    body = binaries["body"]
    body.messages.clear()
    directional = bind(body, "fmi2GetDirectionalDerivative", c_int,
                       [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_uint), c_size_t,
                        POINTER(c_double), POINTER(c_double)])
    c = body.initialised()
    out = (c_double * 1)()
    try:
        theta, torque = (c_uint * 1)(body.vr["theta"]), (c_uint * 1)(body.vr["torque"])
        one = (c_double * 1)(1.0)
        assert directional(c, torque, 1, theta, 1, one, out) == ERROR
        assert f"value reference {body.vr['torque']} is not an unknown of this model" in body.last_message()
        assert directional(c, theta, 1, theta, 1, one, out) == ERROR
        assert f"value reference {body.vr['theta']} is not a known of this model (an input " \
               "or a state)" in body.last_message()
        assert directional(c, theta, 1, torque, 1, None, out) == ERROR
        assert "argument dvKnown is NULL" in body.last_message()
        assert directional(c, theta, 1, torque, 1, (c_double * 1)(float("inf")), out) == ERROR
        assert "dvKnown[0] must be finite; got inf" in body.last_message()
        angle = (c_uint * 1)(body.vr["angle"])
        assert directional(c, theta, 1, angle, 1, one, out) == OK and out[0] == 1.0  # C[0, 0]
    finally:
        body.FreeInstance(c)
