"""The FMI 3.0 binary under misuse: it returns fmi3Error/fmi3Discard with a logged message
and never crashes. The binary is called directly through ctypes (null pointers, a wrong
instantiation token, calls in the wrong state, NaN inputs, wrong array sizes, clocks,
FMU states and partial derivatives used wrongly); C harnesses check several FMUs' sources
in one program (FMI3_FUNCTION_PREFIX) and a double free under AddressSanitizer.
"""

import ctypes
import subprocess
import zipfile
from ctypes import POINTER, byref, c_bool, c_char_p, c_double, c_int, c_size_t, c_uint, c_void_p
from pathlib import Path

import control
import numpy as np
import pytest
from fmpy import read_model_description

import fmpy
from fmu import export

from fmu_cases import SAMPLE_TIME, exported

OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3
LOGGER = ctypes.CFUNCTYPE(None, c_void_p, c_int, c_char_p, c_char_p)


class Binary3:
    """An FMI 3.0 FMU's shared library with typed functions and a logger that records."""

    signatures = {
        "fmi3InstantiateModelExchange": (c_void_p, [c_char_p, c_char_p, c_char_p, c_bool, c_bool,
                                                    c_void_p, LOGGER]),
        "fmi3InstantiateCoSimulation": (c_void_p, [c_char_p, c_char_p, c_char_p, c_bool, c_bool,
                                                   c_bool, c_bool, POINTER(c_uint), c_size_t,
                                                   c_void_p, LOGGER, c_void_p]),
        "fmi3InstantiateScheduledExecution": (c_void_p, [c_char_p, c_char_p, c_char_p, c_bool,
                                                         c_bool, c_void_p, LOGGER, c_void_p,
                                                         c_void_p, c_void_p]),
        "fmi3FreeInstance": (None, [c_void_p]),
        "fmi3EnterInitializationMode": (c_int, [c_void_p, c_bool, c_double, c_double, c_bool,
                                                c_double]),
        "fmi3ExitInitializationMode": (c_int, [c_void_p]),
        "fmi3EnterEventMode": (c_int, [c_void_p]),
        "fmi3EnterStepMode": (c_int, [c_void_p]),
        "fmi3UpdateDiscreteStates": (c_int, [c_void_p] + [POINTER(c_bool)] * 5 + [POINTER(c_double)]),
        "fmi3Terminate": (c_int, [c_void_p]),
        "fmi3Reset": (c_int, [c_void_p]),
        "fmi3GetFloat64": (c_int, [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_double), c_size_t]),
        "fmi3SetFloat64": (c_int, [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_double), c_size_t]),
        "fmi3GetInt32": (c_int, [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_int), c_size_t]),
        "fmi3GetClock": (c_int, [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_bool)]),
        "fmi3SetClock": (c_int, [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_bool)]),
        "fmi3GetIntervalDecimal": (c_int, [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_double),
                                           POINTER(c_int)]),
        "fmi3DoStep": (c_int, [c_void_p, c_double, c_double, c_bool, POINTER(c_bool),
                               POINTER(c_bool), POINTER(c_bool), POINTER(c_double)]),
        "fmi3GetFMUState": (c_int, [c_void_p, POINTER(c_void_p)]),
        "fmi3SetFMUState": (c_int, [c_void_p, c_void_p]),
        "fmi3FreeFMUState": (c_int, [c_void_p, POINTER(c_void_p)]),
        "fmi3SerializedFMUStateSize": (c_int, [c_void_p, c_void_p, POINTER(c_size_t)]),
        "fmi3SerializeFMUState": (c_int, [c_void_p, c_void_p, c_char_p, c_size_t]),
        "fmi3DeserializeFMUState": (c_int, [c_void_p, c_char_p, c_size_t, POINTER(c_void_p)]),
        "fmi3GetDirectionalDerivative": (c_int, [c_void_p, POINTER(c_uint), c_size_t,
                                                 POINTER(c_uint), c_size_t, POINTER(c_double),
                                                 c_size_t, POINTER(c_double), c_size_t]),
        "fmi3EnterConfigurationMode": (c_int, [c_void_p]),
        "fmi3ActivateModelPartition": (c_int, [c_void_p, c_uint, c_double]),
        "fmi3GetNumberOfContinuousStates": (c_int, [c_void_p, POINTER(c_size_t)]),
        "fmi3SetDebugLogging": (c_int, [c_void_p, c_bool, c_size_t, POINTER(c_char_p)]),
    }

    def __init__(self, path: Path, folder: Path):
        with zipfile.ZipFile(path) as archive:
            archive.extractall(folder)
        description = read_model_description(str(path))
        self.token = description.guid.encode()
        self.vr = {v.name: v.valueReference for v in description.modelVariables}
        identifier = description.coSimulation.modelIdentifier
        self.lib = ctypes.CDLL(str(folder / "binaries" / "x86_64-linux" / f"{identifier}.so"))
        self.messages = []

        def logger(environment, status, category, message):
            self.messages.append((status, category.decode(), message.decode()))

        self.logger = LOGGER(logger)
        for name, (restype, argtypes) in self.signatures.items():
            function = getattr(self.lib, name)
            function.restype, function.argtypes = restype, argtypes
            setattr(self, name[4:], function)

    def instantiate(self, token=None, name=b"test", event_mode=False, logging=True):
        return self.InstantiateCoSimulation(name, self.token if token is None else token, None,
                                            False, logging, event_mode, False, None, 0, None,
                                            self.logger, None)

    def initialised(self, event_mode=False):
        c = self.instantiate(event_mode=event_mode)
        assert c
        assert self.EnterInitializationMode(c, False, 0.0, 0.0, False, 0.0) == OK
        assert self.ExitInitializationMode(c) == OK
        return c

    def get(self, c, *names):
        values = (c_double * len(names))()
        status = self.GetFloat64(c, (c_uint * len(names))(*(self.vr[n] for n in names)),
                                 len(names), values, len(names))
        return status, list(values)

    def set(self, c, **values):
        return self.SetFloat64(c, (c_uint * len(values))(*(self.vr[n] for n in values)),
                               len(values), (c_double * len(values))(*values.values()), len(values))

    def step(self, c, t, h):
        flags = [c_bool() for _ in range(3)]
        last = c_double()
        return self.DoStep(c, t, h, True, *(byref(f) for f in flags), byref(last)), last.value

    def last_message(self):
        return self.messages[-1][2] if self.messages else ""


@pytest.fixture(scope="module")
def binaries(tmp_path_factory):
    folder = tmp_path_factory.mktemp("misuse3")
    return {name: Binary3(exported(name, "3.0"), folder / name) for name in ("hub", "lqr")}


@pytest.fixture
def hub(binaries):
    binary = binaries["hub"]
    binary.messages.clear()
    return binary


@pytest.fixture
def lqr(binaries):
    binary = binaries["lqr"]
    binary.messages.clear()
    return binary


def test_instantiation_errors(hub, lqr):
    assert not hub.instantiate(token=b"{00000000-0000-0000-0000-000000000000}")
    assert "wrong instantiationToken {00000000-0000-0000-0000-000000000000}" in hub.last_message()
    assert not hub.instantiate(name=b"")
    assert "instanceName must be a non-empty string" in hub.last_message()
    assert not hub.instantiate(event_mode=True)
    assert "eventModeUsed must be fmi3False: this FMU has no events" in hub.last_message()
    assert not hub.InstantiateScheduledExecution(b"se", hub.token, None, False, True, None,
                                                 hub.logger, None, None, None)
    assert "does not provide Scheduled Execution" in hub.last_message()
    assert not lqr.InstantiateModelExchange(b"me", lqr.token, None, False, True, None, lqr.logger)
    assert "does not provide Model Exchange" in lqr.last_message()
    hub.FreeInstance(None)  # ignored


def test_nothing_is_logged_without_logging(hub):
    """FMI 3.0.2, section 2.3.1: loggingOn = fmi3False disables every message."""
    assert not hub.instantiate(token=b"{bad}", logging=False)
    assert hub.messages == []
    c = hub.instantiate(logging=False)
    try:
        assert hub.step(c, 0.0, 0.01)[0] == ERROR  # wrong state
        assert hub.messages == []
        assert hub.SetDebugLogging(c, True, 0, None) == OK
        assert hub.step(c, 0.0, 0.01)[0] == ERROR
        assert hub.last_message() == "fmi3DoStep must not be called in state Instantiated."
    finally:
        hub.FreeInstance(c)


def test_calls_in_the_wrong_state_and_bad_values(hub):
    c = hub.instantiate()
    try:
        assert hub.set(c, q=0.3) == OK  # a start value
        assert hub.ExitInitializationMode(c) == ERROR
        assert "fmi3ExitInitializationMode must not be called in state Instantiated" in hub.last_message()
        assert hub.EnterInitializationMode(c, False, 0.0, float("nan"), False, 0.0) == ERROR
        assert "startTime must be finite [s]; got nan" in hub.last_message()
        assert hub.EnterInitializationMode(c, False, 0.0, 0.0, False, 0.0) == OK
        assert hub.ExitInitializationMode(c) == OK
        assert hub.set(c, torque=float("nan")) == ERROR
        assert "input torque must be finite; got nan" in hub.last_message()
        assert hub.set(c, q=1.0) == ERROR
        assert "state q can only be set before initialisation" in hub.last_message()
        assert hub.set(c, time=1.0) == ERROR
        assert "the time (the independent variable) is calculated" in hub.last_message()
        values = (c_double * 2)()
        vrs = (c_uint * 2)(hub.vr["theta"], hub.vr["omega"])
        assert hub.GetFloat64(c, vrs, 2, values, 3) == ERROR
        assert "nValues must equal nValueReferences (2" in hub.last_message()
        assert hub.GetFloat64(c, (c_uint * 1)(999), 1, values, 1) == ERROR
        assert "unknown value reference 999" in hub.last_message()
        ints = (c_int * 1)()
        assert hub.GetInt32(c, (c_uint * 1)(0), 1, ints, 1) == ERROR
        assert "only Float64 variables" in hub.last_message()
        assert hub.step(c, 0.0, -1.0)[0] == ERROR
        assert "communicationStepSize must be positive and finite [s]; got -1" in hub.last_message()
        assert hub.step(c, 5.0, 0.01)[0] == ERROR
        assert hub.EnterEventMode(c) == ERROR
        assert "eventModeUsed = fmi3False" in hub.last_message()
        assert hub.get(c, "theta") == (OK, [0.3])
        assert hub.step(c, 0.0, 0.01) == (OK, 0.01)
        assert hub.EnterConfigurationMode(c) == ERROR
        assert "no structural parameters" in hub.last_message()
        assert hub.ActivateModelPartition(c, 0, 0.0) == ERROR
        count = c_size_t()
        assert hub.GetNumberOfContinuousStates(c, byref(count)) == ERROR
        assert "Model Exchange function; this instance is Co-Simulation" in hub.last_message()
        assert hub.Terminate(c) == OK
        assert hub.Reset(c) == OK
    finally:
        hub.FreeInstance(c)


def test_clock_misuse(lqr):
    """The sample clock: read with fmi3GetClock, set in Event Mode at its ticks only."""
    c = lqr.initialised(event_mode=True)  # Event Mode at t = 0: a tick
    clock = (c_uint * 1)(lqr.vr["sample_clock"])
    try:
        interval, qualifier = (c_double * 1)(), (c_int * 1)()
        assert lqr.GetIntervalDecimal(c, clock, 1, interval, qualifier) == OK
        assert interval[0] == SAMPLE_TIME and qualifier[0] == 1  # fmi3IntervalUnchanged
        assert lqr.GetFloat64(c, clock, 1, (c_double * 1)(), 1) == ERROR
        assert "is the sample clock; use fmi3GetClock" in lqr.last_message()
        assert lqr.SetClock(c, (c_uint * 1)(lqr.vr["torque"]), 1, (c_bool * 1)(True)) == ERROR
        assert "is not a Clock (only the sample clock is)" in lqr.last_message()
        assert lqr.SetClock(c, clock, 1, (c_bool * 1)(True)) == OK
        active = (c_bool * 1)()
        assert lqr.GetClock(c, clock, 1, active) == OK and active[0]
        flags = [c_bool() for _ in range(5)]
        assert lqr.UpdateDiscreteStates(c, *(byref(f) for f in flags), byref(c_double())) == OK
        assert lqr.EnterStepMode(c) == OK
        assert lqr.step(c, 0.0, SAMPLE_TIME / 2)[0] == OK
        assert lqr.EnterEventMode(c) == OK
        assert lqr.SetClock(c, clock, 1, (c_bool * 1)(True)) == ERROR  # t = T/2: no tick
        assert "ticks at 0.050000000000000003 s (every 0.05 s); it cannot be activated at " \
               "t = 0.025000000000000001 s" in lqr.last_message()
    finally:
        lqr.FreeInstance(c)


def test_fmu_state_misuse(hub):
    first, second = hub.initialised(), hub.initialised()
    try:
        state = c_void_p()
        assert hub.GetFMUState(first, None) == ERROR
        assert "argument FMUState is NULL" in hub.last_message()
        assert hub.GetFMUState(first, byref(state)) == OK
        assert hub.SetFMUState(second, state) == ERROR  # another instance's
        assert "FMUState is not a state of this instance" in hub.last_message()
        size = c_size_t()
        assert hub.SerializedFMUStateSize(first, state, byref(size)) == OK
        buffer = ctypes.create_string_buffer(size.value)
        assert hub.SerializeFMUState(first, state, buffer, size.value - 1) == ERROR
        assert f"size must be at least {size.value} bytes" in hub.last_message()
        copy = c_void_p()
        assert hub.DeserializeFMUState(second, b"x" * size.value, size.value, byref(copy)) == ERROR
        assert "does not start like a flexsat FMU state" in hub.last_message()
        assert hub.FreeFMUState(first, byref(state)) == OK and state.value is None
        stale = c_void_p(id(state))  # an address that is not a state
        assert hub.FreeFMUState(first, byref(stale)) == ERROR
        assert "not a state of this instance" in hub.last_message()
        empty = c_void_p()
        assert hub.FreeFMUState(first, byref(empty)) == OK  # NULL: nothing to free
    finally:
        hub.FreeInstance(first)
        hub.FreeInstance(second)


def test_rollback_after_a_discarded_step(tmp_path):
    """x' = 100 x: a step of 10 s overflows and is discarded (the instance stays in Step
    Mode, lastSuccessfulTime = t); a saved state restores it and a short step succeeds."""
    unstable = control.ss([[100.0]], [[1.0]], [[1.0]], 0, inputs=["u"], outputs=["y"], states=["x"])
    binary = Binary3(export(unstable, tmp_path / "u.fmu", fmi_version="3.0", x0=[1.0]),
                     tmp_path / "u")
    c = binary.initialised()
    try:
        state = c_void_p()
        assert binary.GetFMUState(c, byref(state)) == OK
        assert binary.step(c, 0.0, 10.0) == (DISCARD, 0.0)
        assert "not finite" in binary.last_message()
        assert binary.SetFMUState(c, state) == OK
        status, last = binary.step(c, 0.0, 0.01)
        assert (status, last) == (OK, 0.01)
        # the C code's exponential of the 1 x 1 step matrix: a few ulp of e (a scaled Pade
        # approximant, Higham 2005); rel 45 eps
        assert binary.get(c, "x")[1][0] == pytest.approx(np.exp(1.0), rel=1e-14)
        assert binary.FreeFMUState(c, byref(state)) == OK
    finally:
        binary.FreeInstance(c)


def test_directional_derivative_misuse(hub, lqr):
    c = hub.initialised()
    d = lqr.initialised()
    out = (c_double * 2)()
    try:
        unknowns, knowns = (c_uint * 1)(hub.vr["theta"]), (c_uint * 1)(hub.vr["torque"])
        seed = (c_double * 1)(1.0)
        assert hub.GetDirectionalDerivative(c, unknowns, 1, knowns, 1, seed, 1, out, 2) == ERROR
        assert "nSeed must be 1 and nSensitivity 1" in hub.last_message()
        assert hub.GetDirectionalDerivative(c, knowns, 1, unknowns, 1, seed, 1, out, 1) == ERROR
        assert f"value reference {hub.vr['torque']} is not an unknown of this model (an output " \
               "or a state derivative)" in hub.last_message()
        nan = (c_double * 1)(float("nan"))
        assert hub.GetDirectionalDerivative(c, unknowns, 1, knowns, 1, nan, 1, out, 1) == ERROR
        assert "seed[0] must be finite; got nan" in hub.last_message()
        # a sampled FMU's states are not knowns
        states = (c_uint * 1)(lqr.vr["xhat0"])
        assert lqr.GetDirectionalDerivative(d, (c_uint * 1)(lqr.vr["torque"]), 1, states, 1,
                                            seed, 1, out, 1) == ERROR
        assert "is not a known of this model (an input)" in lqr.last_message()
    finally:
        hub.FreeInstance(c)
        lqr.FreeInstance(d)


HARNESS_TWO_FMUS = r"""
#include <stdio.h>
#include "fmi3FunctionTypes.h"

fmi3InstantiateCoSimulationTYPE hub_fmi3InstantiateCoSimulation, pd_fmi3InstantiateCoSimulation;
fmi3EnterInitializationModeTYPE hub_fmi3EnterInitializationMode, pd_fmi3EnterInitializationMode;
fmi3ExitInitializationModeTYPE hub_fmi3ExitInitializationMode, pd_fmi3ExitInitializationMode;
fmi3SetFloat64TYPE hub_fmi3SetFloat64, pd_fmi3SetFloat64;
fmi3GetFloat64TYPE hub_fmi3GetFloat64, pd_fmi3GetFloat64;
fmi3DoStepTYPE hub_fmi3DoStep;
fmi3FreeInstanceTYPE hub_fmi3FreeInstance, pd_fmi3FreeInstance;

int main(void)
{
    fmi3Instance h = hub_fmi3InstantiateCoSimulation("hub", HUB_TOKEN, NULL, fmi3False, fmi3False,
                                                     fmi3False, fmi3False, NULL, 0, NULL, NULL, NULL);
    fmi3Instance p = pd_fmi3InstantiateCoSimulation("pd", PD_TOKEN, NULL, fmi3False, fmi3False,
                                                    fmi3False, fmi3False, NULL, 0, NULL, NULL, NULL);
    if (!h || !p) return 2;
    int bad = 0;
    bad |= hub_fmi3EnterInitializationMode(h, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    bad |= hub_fmi3ExitInitializationMode(h);
    bad |= pd_fmi3EnterInitializationMode(p, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    bad |= pd_fmi3ExitInitializationMode(p);
    const fmi3ValueReference pd_in[3] = {0, 1, 2}, pd_out[1] = {3}, hub_in[1] = {0}, hub_out[1] = {1};
    const fmi3Float64 measured[3] = {0.5, 0.1, 0.2};
    fmi3Float64 torque, theta, last;
    fmi3Boolean event, terminate, early;
    bad |= pd_fmi3SetFloat64(p, pd_in, 3, measured, 3) | pd_fmi3GetFloat64(p, pd_out, 1, &torque, 1);
    bad |= hub_fmi3SetFloat64(h, hub_in, 1, &torque, 1);
    bad |= hub_fmi3DoStep(h, 0.0, 0.1, fmi3True, &event, &terminate, &early, &last);
    bad |= hub_fmi3GetFloat64(h, hub_out, 1, &theta, 1);
    printf("%.17g %.17g\n", torque, theta);
    hub_fmi3FreeInstance(h);
    pd_fmi3FreeInstance(p);
    return bad;
}
"""


@pytest.mark.slow
def test_two_fmus_sources_link_into_one_program(tmp_path):
    """FMI 3.0.2, section 2.2.1: with FMI3_FUNCTION_PREFIX per FMU, the sources of several
    FMUs compile into one program (with the importer's headers: fmpy's)."""
    headers = Path(fmpy.__file__).parent / "c-code"
    objects, defines = [], []
    for name in ("hub", "pd"):
        folder = tmp_path / name
        with zipfile.ZipFile(exported(name, "3.0")) as archive:
            archive.extractall(folder)
        token = read_model_description(str(exported(name, "3.0"))).guid
        defines.append(f'-D{name.upper()}_TOKEN="{token}"')
        for source in ("model.c", "fmi3Functions.c", "lti_instance.c", "linear_model.c"):
            obj = tmp_path / f"{name}_{source}.o"
            subprocess.run(["gcc", "-c", "-std=c99", "-O2", "-pthread", f"-DFMI3_FUNCTION_PREFIX={name}_",
                            f"-I{folder / 'sources'}", f"-I{headers}", "-o", str(obj),
                            str(folder / "sources" / source)], check=True)
            objects.append(str(obj))
    (tmp_path / "main.c").write_text(HARNESS_TWO_FMUS)
    subprocess.run(["gcc", "-std=c99", *defines, f"-I{headers}", str(tmp_path / "main.c"), *objects,
                    "-o", str(tmp_path / "both"), "-lm", "-pthread"], check=True)
    result = subprocess.run([str(tmp_path / "both")], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stdout + result.stderr
    torque, theta = (float(v) for v in result.stdout.split())
    assert torque == 20.0 * (0.5 - 0.1) - 30.0 * 0.2  # 2.0, exact in binary
    # one exact step of the hub from rest with 2 N m for 0.1 s: rigid q = 2/J h^2/2 plus
    # the mode eta = (0.5 * 2 / J)(1 - cos 3h)/9 (damping 0.01 changes it by < 1e-3 relative)
    rigid = 2.0 / 10.0 * 0.1**2 / 2
    mode = 0.5 * 2.0 / 10.0 * (1 - np.cos(0.3)) / 9.0
    assert theta == pytest.approx(rigid + mode, rel=1e-3)


HARNESS_DOUBLE_FREE = r"""
#include <stdio.h>
#include "fmi3Functions.h"

int main(void)
{
    fmi3Instance first = fmi3InstantiateCoSimulation("first", TOKEN, NULL, fmi3False, fmi3False,
                                                     fmi3False, fmi3False, NULL, 0, NULL, NULL, NULL);
    fmi3Instance second = fmi3InstantiateCoSimulation("second", TOKEN, NULL, fmi3False, fmi3False,
                                                      fmi3False, fmi3False, NULL, 0, NULL, NULL, NULL);
    if (!first || !second) return 2;
    fmi3FMUState state = NULL;
    if (fmi3GetFMUState(first, &state) != fmi3OK) return 3;
    fmi3FreeInstance(first);               /* frees its FMU states too */
    fmi3FreeInstance(first);               /* undefined by the standard: refused */
    if (fmi3SetFMUState(first, state) != fmi3Error) return 4;   /* a stale handle */
    if (fmi3SetFMUState(second, state) != fmi3Error) return 5;  /* a freed state */
    if (fmi3EnterInitializationMode(second, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK) return 6;
    fmi3FreeInstance(second);
    printf("done\n");
    return 0;
}
"""


@pytest.mark.slow
def test_double_free_reads_no_freed_memory(tmp_path):
    """Under AddressSanitizer: a second fmi3FreeInstance, calls on the freed handle and on
    a state freed with its instance neither read nor free freed memory."""
    folder = tmp_path / "hub"
    with zipfile.ZipFile(exported("hub", "3.0")) as archive:
        archive.extractall(folder)
    token = read_model_description(str(exported("hub", "3.0"))).guid
    headers = Path(fmpy.__file__).parent / "c-code"
    sources = folder / "sources"
    files = [str(sources / f) for f in ("model.c", "fmi3Functions.c", "lti_instance.c", "linear_model.c")]
    (tmp_path / "main.c").write_text(HARNESS_DOUBLE_FREE)
    subprocess.run(["gcc", "-std=c99", "-g", "-fsanitize=address", "-fno-omit-frame-pointer",
                    f'-DTOKEN="{token}"', f"-I{sources}", f"-I{headers}", str(tmp_path / "main.c"),
                    *files, "-o", str(tmp_path / "double_free"), "-lm", "-pthread"], check=True)
    result = subprocess.run([str(tmp_path / "double_free")], capture_output=True, text=True,
                            timeout=60)
    assert "AddressSanitizer" not in result.stderr, result.stderr[:2000]
    assert result.returncode == 0 and result.stdout == "done\n", result.stdout + result.stderr


def test_variable_dependencies_match_the_model_structure(hub, lqr):
    """fmi3GetNumberOfVariableDependencies / fmi3GetVariableDependencies: the same
    dependencies as ModelStructure (for the sampled controller, the inputs through D, without
    the clock, which is not a Float64 variable); an input is not a dependent."""
    for binary, name in ((hub, "hub"), (lqr, "lqr")):
        count_of = bind3(binary, "fmi3GetNumberOfVariableDependencies",
                         [c_void_p, c_uint, POINTER(c_size_t)])
        list_of = bind3(binary, "fmi3GetVariableDependencies",
                        [c_void_p, c_uint, POINTER(c_size_t), POINTER(c_uint), POINTER(c_size_t),
                         POINTER(c_int), c_size_t])
        description = read_model_description(str(exported(name, "3.0")))
        c = binary.instantiate()
        try:
            for unknown in description.outputs + description.derivatives:
                vr = unknown.variable.valueReference
                count = c_size_t()
                assert count_of(c, vr, byref(count)) == OK
                expected = sorted(d.valueReference for d in unknown.dependencies
                                  if d.type == "Float64")
                n = count.value
                assert n == len(expected)
                independents, kinds = (c_uint * max(n, 1))(), (c_int * max(n, 1))()
                elements, elements2 = (c_size_t * max(n, 1))(), (c_size_t * max(n, 1))()
                assert list_of(c, vr, elements, independents, elements2, kinds, n) == OK
                assert sorted(independents[:n]) == expected
                assert set(kinds[:n]) <= {1}  # fmi3Constant
            input_vr = binary.vr["torque" if name == "hub" else "theta_ref"]
            assert count_of(c, input_vr, byref(c_size_t())) == ERROR
            assert "is not an output" in binary.last_message()
        finally:
            binary.FreeInstance(c)


def bind3(binary, name, argtypes):
    function = getattr(binary.lib, name)
    function.restype, function.argtypes = c_int, argtypes
    return function
