"""FMU states (get, set, free, serialise, deserialise) in FMI 2.0 and 3.0, through fmpy's
own API: a rollback - step, save, step, restore, step again - gives bit-identical results,
for Co-Simulation (continuous and sampled) and Model Exchange; a serialised state restores
the same in a fresh instance; states of other models and damaged bytes are refused.

Bit identity is the right test: restoring puts back exactly the doubles that were saved,
and the FMU computes the same products in the same order from them.
"""

import ctypes

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Model, FMU3Slave

from fmu_cases import SAMPLE_TIME, exported

VERSIONS = ["2.0", "3.0"]


class Instance:
    """A CS or ME instance of an exported FMU with version-neutral calls (fmpy's API)."""

    def __init__(self, name: str, version: str, interface: str = "cs", label: str = "x"):
        path = exported(name, version)
        self.description = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.description.modelVariables}
        self.version = version
        if interface == "cs":
            kind = FMU3Slave if version == "3.0" else FMU2Slave
            identifier = self.description.coSimulation.modelIdentifier
        else:
            kind = FMU3Model if version == "3.0" else FMU2Model
            identifier = self.description.modelExchange.modelIdentifier
        self.fmu = kind(guid=self.description.guid, unzipDirectory=extract(str(path)),
                        modelIdentifier=identifier, instanceName=label)
        self.fmu.instantiate()
        self.interface = interface

    def initialise(self) -> None:
        if self.version == "3.0":
            self.fmu.enterInitializationMode(startTime=0.0)
        else:
            self.fmu.setupExperiment(startTime=0.0)
            self.fmu.enterInitializationMode()
        self.fmu.exitInitializationMode()
        if self.interface == "me":
            if self.version == "3.0":
                self.fmu.updateDiscreteStates()
            else:
                self.fmu.newDiscreteStates()
            self.fmu.enterContinuousTimeMode()

    def get(self, *names):
        vrs = [self.vr[n] for n in names]
        return self.fmu.getFloat64(vrs) if self.version == "3.0" else self.fmu.getReal(vrs)

    def set(self, **values):
        vrs, numbers = [self.vr[n] for n in values], list(values.values())
        if self.version == "3.0":
            self.fmu.setFloat64(vrs, numbers)
        else:
            self.fmu.setReal(vrs, numbers)

    def serialize(self, state) -> bytes:
        if self.version == "3.0":
            return self.fmu.serializeFMUState(state)
        return self.fmu.serializeFMUstate(state)

    def deserialize(self, data: bytes):
        if self.version == "3.0":
            return self.fmu.deserializeFMUState(data)
        return self.fmu.deSerializeFMUstate(data)

    def close(self) -> None:
        self.fmu.freeInstance()


def run(instance: Instance, times: np.ndarray, torque, outputs: tuple[str, ...]) -> np.ndarray:
    """Co-simulation steps between consecutive times with torque(t) held; outputs after each."""
    rows = []
    for t0, t1 in zip(times[:-1], times[1:]):
        instance.set(torque=torque(t0))
        instance.fmu.doStep(t0, t1 - t0)
        rows.append(instance.get(*outputs))
    return np.array(rows)


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("name,h", [("hub", 0.01), ("hub", 0.023), ("sampled", 0.025)])
def test_rollback_is_bit_identical(version, name, h):
    """Step 20 times, save, step 30 times, restore, step the same 30 again: identical; then
    the same through the serialised bytes, deserialised in the same instance. h = 0.023 s
    is not the default step (its matrices are computed in C and cached); h = T/4 for the
    sampled system crosses sample instants between steps."""
    instance = Instance(name, version)
    try:
        instance.initialise()
        times = np.arange(51) * h
        torque = lambda t: np.sin(3.0 * t)  # noqa: E731 - a changing input
        run(instance, times[:21], torque, ("theta", "omega"))
        state = instance.fmu.getFMUState()
        first = run(instance, times[20:], torque, ("theta", "omega", "q", "q_dot"))
        instance.fmu.setFMUState(state)
        again = run(instance, times[20:], torque, ("theta", "omega", "q", "q_dot"))
        np.testing.assert_array_equal(again, first)
        restored = instance.deserialize(instance.serialize(state))
        instance.fmu.setFMUState(restored)
        third = run(instance, times[20:], torque, ("theta", "omega", "q", "q_dot"))
        np.testing.assert_array_equal(third, first)
        instance.fmu.freeFMUState(state)
        instance.fmu.freeFMUState(restored)
    finally:
        instance.close()


@pytest.mark.parametrize("version", VERSIONS)
def test_serialised_state_continues_in_a_fresh_instance(version):
    """A state serialised by one instance, deserialised in a fresh instance that was only
    instantiated: the mode is part of the state (as in the Reference-FMUs), so stepping
    goes on from where the first instance was, bit for bit (the digital LQR, clock ticks
    taken by fmi3DoStep)."""
    first = Instance("lqr", version, label="first")
    second = Instance("lqr", version, label="second")
    try:
        first.initialise()
        times = np.arange(41) * SAMPLE_TIME
        inputs = lambda k: dict(theta_ref=0.1, theta=0.01 * np.cos(k), omega=0.02 * np.sin(k))  # noqa: E731

        def steps(instance, start, stop):
            out = []
            for k in range(start, stop):
                instance.set(**inputs(k))
                out.append(instance.get("torque"))
                instance.fmu.doStep(times[k], SAMPLE_TIME)
            return np.array(out)

        steps(first, 0, 10)
        data = first.serialize(first.fmu.getFMUState())
        expected = steps(first, 10, 40)
        state = second.deserialize(data)
        second.fmu.setFMUState(state)
        np.testing.assert_array_equal(steps(second, 10, 40), expected)
    finally:
        first.close()
        second.close()


@pytest.mark.parametrize("version", VERSIONS)
def test_model_exchange_rollback(version):
    """ME: save, move the states and the time, restore: states, time and derivatives back."""
    instance = Instance("hub", version, interface="me")
    try:
        instance.initialise()
        x = (ctypes.c_double * 4)(0.1, -0.2, 0.03, 0.4)
        instance.fmu.setTime(0.5)
        instance.fmu.setContinuousStates(x, 4)
        instance.set(torque=2.0)
        state = instance.fmu.getFMUState()
        before = instance.get("der(q)", "der(q_dot)", "der(eta)", "der(eta_dot)", "theta")
        instance.fmu.setTime(0.9)
        instance.fmu.setContinuousStates((ctypes.c_double * 4)(9.0, 9.0, 9.0, 9.0), 4)
        instance.set(torque=-5.0)
        instance.fmu.setFMUState(state)
        assert instance.get("der(q)", "der(q_dot)", "der(eta)", "der(eta_dot)", "theta") == before
        back = (ctypes.c_double * 4)()
        instance.fmu.getContinuousStates(back, 4)
        assert list(back) == list(x)
        instance.fmu.freeFMUState(state)
    finally:
        instance.close()


@pytest.mark.parametrize("version", VERSIONS)
def test_foreign_and_damaged_states_are_refused(version):
    """Bytes of another model, of the other interface, truncated or holding a NaN are
    refused with an error; the instance is unchanged and usable."""
    hub = Instance("hub", version, label="hub")
    other = Instance("sampled", version, label="other")
    me = Instance("hub", version, interface="me", label="me")
    try:
        for instance in (hub, other, me):
            instance.initialise()
        good = hub.serialize(hub.fmu.getFMUState())
        foreign = other.serialize(other.fmu.getFMUState())
        damaged = bytearray(good)
        damaged[120:128] = np.float64(np.nan).tobytes()  # the first state value
        for data in (foreign, good[:-8], bytes(damaged)):
            with pytest.raises(Exception, match="(Error|failed)"):
                hub.deserialize(data)
        with pytest.raises(Exception, match="(Error|failed)"):
            me.deserialize(good)  # saved by a Co-Simulation instance
        hub.fmu.doStep(0.0, 0.01)  # still usable
    finally:
        for instance in (hub, other, me):
            instance.close()
