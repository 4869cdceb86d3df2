"""Load a freshly built FMU library with ctypes and exercise it once (run as a script).

Run by :func:`fmu.verify.verify_library` in a separate process as
``python -I -S probe.py`` with a JSON request on standard input (see
:func:`fmu.verify.probe_input`); prints ``{"errors": [...], "log": [...]}`` on standard
output. Standard library only, no imports of its own package: it runs by file path.

For each declared interface, through the FMI 2.0 or FMI 3.0 API of the library: the version
query, instantiation with a logger, the test states and inputs set before initialisation,
initialisation, then

- Model Exchange: the derivatives and the outputs, compared with ``A x + B u`` and
  ``C x + D u``; the directional derivatives (and FMI 3.0's adjoint derivatives) with seeds
  of ones, compared with the products with ``[[C, D], [A, B]]``; an FMU state saved,
  the states changed, the FMU state restored: the states must be back, bit for bit;
- Co-Simulation: an FMU state saved; one step of the default step (one sample period for a
  sampled model), the states compared with ``Phi x + Gamma u``, the outputs with
  ``C x1 + D u`` at the FMU's own new state x1; the partial derivatives as above; the FMU
  state restored, directly and through its serialised bytes, and the step taken again:
  the states must equal x1 bit for bit; for a sampled FMI 3.0 FMU a second instance in
  Event Mode takes the sample through its clock (fmi3SetClock, fmi3UpdateDiscreteStates)
  and must reach the same x1;

then the FMU states are freed, the instance terminated and freed. Any status other than OK,
a value outside the rounding bound, or a message logged at error level is reported.
"""

from __future__ import annotations

import ctypes
import json
import sys

__all__ = ["run", "main"]

_OK = 0
_STATUS = {0: "OK", 1: "Warning", 2: "Discard", 3: "Error", 4: "Fatal", 5: "Pending"}
_EPS = 2.220446049250313e-16

c_void_p, c_int, c_double, c_size_t = ctypes.c_void_p, ctypes.c_int, ctypes.c_double, ctypes.c_size_t
c_bool, c_char_p, c_uint = ctypes.c_bool, ctypes.c_char_p, ctypes.c_uint
c_uint_p, c_double_p = ctypes.POINTER(ctypes.c_uint), ctypes.POINTER(ctypes.c_double)

_Logger2 = ctypes.CFUNCTYPE(None, c_void_p, c_char_p, c_int, c_char_p, c_char_p)
_Allocate = ctypes.CFUNCTYPE(c_void_p, c_size_t, c_size_t)
_Free = ctypes.CFUNCTYPE(None, c_void_p)
_StepFinished = ctypes.CFUNCTYPE(None, c_void_p, c_int)
_Logger3 = ctypes.CFUNCTYPE(None, c_void_p, c_int, c_char_p, c_char_p)


class _Callbacks(ctypes.Structure):
    _fields_ = [("logger", _Logger2), ("allocateMemory", _Allocate), ("freeMemory", _Free),
                ("stepFinished", _StepFinished), ("componentEnvironment", c_void_p)]


def _array(ctype, values):
    values = list(values)
    return (ctype * max(len(values), 1))(*values)


class _Fmi2:
    """The FMI 2.0 functions the probe uses."""

    signatures = {
        "fmi2GetVersion": (c_char_p, []),
        "fmi2GetTypesPlatform": (c_char_p, []),
        "fmi2Instantiate": (c_void_p, [c_char_p, c_int, c_char_p, c_char_p,
                                       ctypes.POINTER(_Callbacks), c_int, c_int]),
        "fmi2FreeInstance": (None, [c_void_p]),
        "fmi2SetupExperiment": (c_int, [c_void_p, c_int, c_double, c_double, c_int, c_double]),
        "fmi2EnterInitializationMode": (c_int, [c_void_p]),
        "fmi2ExitInitializationMode": (c_int, [c_void_p]),
        "fmi2Terminate": (c_int, [c_void_p]),
        "fmi2GetReal": (c_int, [c_void_p, c_uint_p, c_size_t, c_double_p]),
        "fmi2SetReal": (c_int, [c_void_p, c_uint_p, c_size_t, c_double_p]),
        "fmi2NewDiscreteStates": (c_int, [c_void_p, c_void_p]),
        "fmi2EnterContinuousTimeMode": (c_int, [c_void_p]),
        "fmi2GetDerivatives": (c_int, [c_void_p, c_double_p, c_size_t]),
        "fmi2SetContinuousStates": (c_int, [c_void_p, c_double_p, c_size_t]),
        "fmi2GetContinuousStates": (c_int, [c_void_p, c_double_p, c_size_t]),
        "fmi2DoStep": (c_int, [c_void_p, c_double, c_double, c_int]),
        "fmi2GetFMUstate": (c_int, [c_void_p, ctypes.POINTER(c_void_p)]),
        "fmi2SetFMUstate": (c_int, [c_void_p, c_void_p]),
        "fmi2FreeFMUstate": (c_int, [c_void_p, ctypes.POINTER(c_void_p)]),
        "fmi2SerializedFMUstateSize": (c_int, [c_void_p, c_void_p, ctypes.POINTER(c_size_t)]),
        "fmi2SerializeFMUstate": (c_int, [c_void_p, c_void_p, c_char_p, c_size_t]),
        "fmi2DeSerializeFMUstate": (c_int, [c_void_p, c_char_p, c_size_t, ctypes.POINTER(c_void_p)]),
        "fmi2GetDirectionalDerivative": (c_int, [c_void_p, c_uint_p, c_size_t, c_uint_p, c_size_t,
                                                 c_double_p, c_double_p]),
    }
    me_only = ("fmi2NewDiscreteStates", "fmi2EnterContinuousTimeMode", "fmi2GetDerivatives",
               "fmi2SetContinuousStates", "fmi2GetContinuousStates")

    def __init__(self, lib, interfaces, log, errors):
        self.f = {}
        for name, (restype, argtypes) in self.signatures.items():
            if (name in self.me_only and "me" not in interfaces) or (
                    name == "fmi2DoStep" and "cs" not in interfaces):
                continue
            function = getattr(lib, name)
            function.restype, function.argtypes = restype, argtypes
            self.f[name] = function
        libc = ctypes.CDLL(None)

        def logger(environment, instance, status, category, message):
            text = (message or b"").decode("utf-8", "replace")
            log.append(f"{_STATUS.get(status, status)}: {text}")
            if status >= 3:
                errors.append(f"the FMU logged an error: {text}")

        self.callbacks = _Callbacks()
        self.callbacks.logger = _Logger2(logger)
        self.callbacks.allocateMemory = ctypes.cast(libc.calloc, _Allocate)
        self.callbacks.freeMemory = ctypes.cast(libc.free, _Free)
        self.callbacks.stepFinished = _StepFinished()
        self.callbacks.componentEnvironment = None

    def version(self):
        return self.f["fmi2GetVersion"]()

    def instantiate(self, kind, guid, event_mode=False):
        return self.f["fmi2Instantiate"](f"check_{kind}".encode(), 0 if kind == "me" else 1,
                                         guid.encode(), b"file:///", ctypes.byref(self.callbacks),
                                         0, 0)

    def enter_initialization(self, c):
        return [("fmi2SetupExperiment", self.f["fmi2SetupExperiment"](c, 0, 0.0, 0.0, 0, 0.0)),
                ("fmi2EnterInitializationMode", self.f["fmi2EnterInitializationMode"](c))]

    def exit_initialization(self, c, kind):
        calls = [("fmi2ExitInitializationMode", self.f["fmi2ExitInitializationMode"](c))]
        if kind == "me":
            event_info = (ctypes.c_byte * 64)()  # fmi2EventInfo is smaller
            calls.append(("fmi2NewDiscreteStates", self.f["fmi2NewDiscreteStates"](c, event_info)))
            calls.append(("fmi2EnterContinuousTimeMode", self.f["fmi2EnterContinuousTimeMode"](c)))
        return calls

    def get(self, c, vrs):
        values = _array(c_double, [0.0] * len(vrs))
        return self.f["fmi2GetReal"](c, _array(c_uint, vrs), len(vrs), values), values[:len(vrs)]

    def set(self, c, vrs, values):
        return self.f["fmi2SetReal"](c, _array(c_uint, vrs), len(vrs), _array(c_double, values))

    def derivatives(self, c, n):
        values = _array(c_double, [0.0] * n)
        return self.f["fmi2GetDerivatives"](c, values, n), values[:n]

    def set_continuous_states(self, c, x):
        return self.f["fmi2SetContinuousStates"](c, _array(c_double, x), len(x))

    def get_continuous_states(self, c, n):
        values = _array(c_double, [0.0] * n)
        return self.f["fmi2GetContinuousStates"](c, values, n), values[:n]

    def do_step(self, c, t, h):
        return self.f["fmi2DoStep"](c, t, h, 1)

    def get_state(self, c):
        state = c_void_p()
        return self.f["fmi2GetFMUstate"](c, ctypes.byref(state)), state

    def set_state(self, c, state):
        return self.f["fmi2SetFMUstate"](c, state)

    def free_state(self, c, state):
        return self.f["fmi2FreeFMUstate"](c, ctypes.byref(state))

    def serialize(self, c, state):
        size = c_size_t()
        status = self.f["fmi2SerializedFMUstateSize"](c, state, ctypes.byref(size))
        if status != _OK:
            return status, b""
        buffer = ctypes.create_string_buffer(size.value)
        return self.f["fmi2SerializeFMUstate"](c, state, buffer, size.value), buffer.raw

    def deserialize(self, c, data):
        state = c_void_p()
        return self.f["fmi2DeSerializeFMUstate"](c, data, len(data), ctypes.byref(state)), state

    def directional(self, c, unknowns, knowns, seed):
        out = _array(c_double, [0.0] * len(unknowns))
        status = self.f["fmi2GetDirectionalDerivative"](
            c, _array(c_uint, unknowns), len(unknowns), _array(c_uint, knowns), len(knowns),
            _array(c_double, seed), out)
        return status, out[:len(unknowns)]

    adjoint = None

    def terminate(self, c):
        return self.f["fmi2Terminate"](c)

    def free(self, c):
        self.f["fmi2FreeInstance"](c)


class _Fmi3:
    """The FMI 3.0 functions the probe uses."""

    signatures = {
        "fmi3GetVersion": (c_char_p, []),
        "fmi3InstantiateModelExchange": (c_void_p, [c_char_p, c_char_p, c_char_p, c_bool, c_bool,
                                                    c_void_p, _Logger3]),
        "fmi3InstantiateCoSimulation": (c_void_p, [c_char_p, c_char_p, c_char_p, c_bool, c_bool,
                                                   c_bool, c_bool, c_uint_p, c_size_t, c_void_p,
                                                   _Logger3, c_void_p]),
        "fmi3FreeInstance": (None, [c_void_p]),
        "fmi3EnterInitializationMode": (c_int, [c_void_p, c_bool, c_double, c_double, c_bool,
                                                c_double]),
        "fmi3ExitInitializationMode": (c_int, [c_void_p]),
        "fmi3UpdateDiscreteStates": (c_int, [c_void_p] + [ctypes.POINTER(c_bool)] * 5
                                     + [c_double_p]),
        "fmi3EnterContinuousTimeMode": (c_int, [c_void_p]),
        "fmi3EnterStepMode": (c_int, [c_void_p]),
        "fmi3SetClock": (c_int, [c_void_p, c_uint_p, c_size_t, ctypes.POINTER(c_bool)]),
        "fmi3Terminate": (c_int, [c_void_p]),
        "fmi3GetFloat64": (c_int, [c_void_p, c_uint_p, c_size_t, c_double_p, c_size_t]),
        "fmi3SetFloat64": (c_int, [c_void_p, c_uint_p, c_size_t, c_double_p, c_size_t]),
        "fmi3GetContinuousStateDerivatives": (c_int, [c_void_p, c_double_p, c_size_t]),
        "fmi3SetContinuousStates": (c_int, [c_void_p, c_double_p, c_size_t]),
        "fmi3GetContinuousStates": (c_int, [c_void_p, c_double_p, c_size_t]),
        "fmi3DoStep": (c_int, [c_void_p, c_double, c_double, c_bool, ctypes.POINTER(c_bool),
                               ctypes.POINTER(c_bool), ctypes.POINTER(c_bool), c_double_p]),
        "fmi3GetFMUState": (c_int, [c_void_p, ctypes.POINTER(c_void_p)]),
        "fmi3SetFMUState": (c_int, [c_void_p, c_void_p]),
        "fmi3FreeFMUState": (c_int, [c_void_p, ctypes.POINTER(c_void_p)]),
        "fmi3SerializedFMUStateSize": (c_int, [c_void_p, c_void_p, ctypes.POINTER(c_size_t)]),
        "fmi3SerializeFMUState": (c_int, [c_void_p, c_void_p, c_char_p, c_size_t]),
        "fmi3DeserializeFMUState": (c_int, [c_void_p, c_char_p, c_size_t, ctypes.POINTER(c_void_p)]),
        "fmi3GetDirectionalDerivative": (c_int, [c_void_p, c_uint_p, c_size_t, c_uint_p, c_size_t,
                                                 c_double_p, c_size_t, c_double_p, c_size_t]),
        "fmi3GetAdjointDerivative": (c_int, [c_void_p, c_uint_p, c_size_t, c_uint_p, c_size_t,
                                             c_double_p, c_size_t, c_double_p, c_size_t]),
    }

    def __init__(self, lib, interfaces, log, errors):
        self.f = {}
        for name, (restype, argtypes) in self.signatures.items():
            function = getattr(lib, name)  # FMI 3.0: every function is defined
            function.restype, function.argtypes = restype, argtypes
            self.f[name] = function

        def logger(environment, status, category, message):
            text = (message or b"").decode("utf-8", "replace")
            log.append(f"{_STATUS.get(status, status)}: {text}")
            if status >= 3:
                errors.append(f"the FMU logged an error: {text}")

        self.logger = _Logger3(logger)

    def version(self):
        return self.f["fmi3GetVersion"]()

    def instantiate(self, kind, guid, event_mode=False):
        name = f"check_{kind}".encode()
        if kind == "me":
            return self.f["fmi3InstantiateModelExchange"](name, guid.encode(), None, False, True,
                                                          None, self.logger)
        return self.f["fmi3InstantiateCoSimulation"](name, guid.encode(), None, False, True,
                                                     event_mode, False, None, 0, None,
                                                     self.logger, None)

    def enter_initialization(self, c):
        return [("fmi3EnterInitializationMode",
                 self.f["fmi3EnterInitializationMode"](c, False, 0.0, 0.0, False, 0.0))]

    def update_discrete_states(self, c):
        flags = [c_bool() for _ in range(5)]
        next_time = c_double()
        return self.f["fmi3UpdateDiscreteStates"](c, *(ctypes.byref(f) for f in flags),
                                                  ctypes.byref(next_time))

    def exit_initialization(self, c, kind):
        calls = [("fmi3ExitInitializationMode", self.f["fmi3ExitInitializationMode"](c))]
        if kind == "me":
            calls.append(("fmi3UpdateDiscreteStates", self.update_discrete_states(c)))
            calls.append(("fmi3EnterContinuousTimeMode", self.f["fmi3EnterContinuousTimeMode"](c)))
        return calls

    def set_clock(self, c, vr):
        return self.f["fmi3SetClock"](c, _array(c_uint, [vr]), 1, _array(c_bool, [True]))

    def enter_step_mode(self, c):
        return self.f["fmi3EnterStepMode"](c)

    def get(self, c, vrs):
        values = _array(c_double, [0.0] * len(vrs))
        status = self.f["fmi3GetFloat64"](c, _array(c_uint, vrs), len(vrs), values, len(vrs))
        return status, values[:len(vrs)]

    def set(self, c, vrs, values):
        return self.f["fmi3SetFloat64"](c, _array(c_uint, vrs), len(vrs), _array(c_double, values),
                                        len(vrs))

    def derivatives(self, c, n):
        values = _array(c_double, [0.0] * n)
        return self.f["fmi3GetContinuousStateDerivatives"](c, values, n), values[:n]

    def set_continuous_states(self, c, x):
        return self.f["fmi3SetContinuousStates"](c, _array(c_double, x), len(x))

    def get_continuous_states(self, c, n):
        values = _array(c_double, [0.0] * n)
        return self.f["fmi3GetContinuousStates"](c, values, n), values[:n]

    def do_step(self, c, t, h):
        flags = [c_bool() for _ in range(3)]
        last = c_double()
        return self.f["fmi3DoStep"](c, t, h, True, *(ctypes.byref(f) for f in flags),
                                    ctypes.byref(last))

    def get_state(self, c):
        state = c_void_p()
        return self.f["fmi3GetFMUState"](c, ctypes.byref(state)), state

    def set_state(self, c, state):
        return self.f["fmi3SetFMUState"](c, state)

    def free_state(self, c, state):
        return self.f["fmi3FreeFMUState"](c, ctypes.byref(state))

    def serialize(self, c, state):
        size = c_size_t()
        status = self.f["fmi3SerializedFMUStateSize"](c, state, ctypes.byref(size))
        if status != _OK:
            return status, b""
        buffer = ctypes.create_string_buffer(size.value)
        return self.f["fmi3SerializeFMUState"](c, state, buffer, size.value), buffer.raw

    def deserialize(self, c, data):
        state = c_void_p()
        return self.f["fmi3DeserializeFMUState"](c, data, len(data), ctypes.byref(state)), state

    def _partials(self, name, c, unknowns, knowns, seed, n_out):
        out = _array(c_double, [0.0] * n_out)
        status = self.f[name](c, _array(c_uint, unknowns), len(unknowns), _array(c_uint, knowns),
                              len(knowns), _array(c_double, seed), len(seed), out, n_out)
        return status, out[:n_out]

    def directional(self, c, unknowns, knowns, seed):
        return self._partials("fmi3GetDirectionalDerivative", c, unknowns, knowns, seed,
                              len(unknowns))

    def adjoint(self, c, unknowns, knowns, seed):
        return self._partials("fmi3GetAdjointDerivative", c, unknowns, knowns, seed, len(knowns))

    def terminate(self, c):
        return self.f["fmi3Terminate"](c)

    def free(self, c):
        self.f["fmi3FreeInstance"](c)


def run(request: dict) -> dict:
    """Exercise the library described by ``request``; returns ``{"errors", "log"}``."""
    errors: list[str] = []
    log: list[str] = []
    lib = ctypes.CDLL(request["library"])
    version = request.get("fmi_version", "2.0")
    interfaces = request["interfaces"]
    api = (_Fmi2 if version == "2.0" else _Fmi3)(lib, interfaces, log, errors)
    prefix = "fmi2" if version == "2.0" else "fmi3"

    if api.version() != version.encode():
        errors.append(f"{prefix}GetVersion returned {api.version()!r}, not {version.encode()!r}")
    if version == "2.0" and api.f["fmi2GetTypesPlatform"]() != b"default":
        errors.append("fmi2GetTypesPlatform did not return b'default'")

    n, m, p = request["n_states"], request["n_inputs"], request["n_outputs"]
    x, u = request["states"], request["inputs"]
    step = request["step"]
    inputs_vr = list(range(m))
    outputs_vr = list(range(m, m + p))
    states_vr = list(range(m + p, m + p + n))

    def ok(name, status):
        if status != _OK:
            errors.append(f"{name} returned {_STATUS.get(status, status)}")
        return status == _OK

    def compare(what, names, got, expected, tolerance):
        for i, (a, b, t) in enumerate(zip(got, expected, tolerance)):
            if not abs(a - b) <= t:
                label = names[i] if names is not None else str(i)
                errors.append(f"{what} {label}: the FMU computed {a!r}, expected {b!r} "
                              f"(rounding bound {t:.3g})")
                return

    def initialised(kind, event_mode=False):
        instance = api.instantiate(kind, request["guid"], event_mode)
        if not instance:
            errors.append(f"{prefix} instantiation ({kind}) returned NULL")
            return None
        # start values of the states and the inputs, set in Initialization Mode
        good = all(ok(name, status) for name, status in api.enter_initialization(instance))
        good = good and (not n or ok(f"{prefix} set states", api.set(instance, states_vr, x)))
        good = good and (not m or ok(f"{prefix} set inputs", api.set(instance, inputs_vr, u)))
        good = good and all(ok(name, status) for name, status in api.exit_initialization(instance, kind))
        if not good:
            api.free(instance)
            return None
        return instance

    def check_partials(instance):
        unknowns, knowns = request["unknowns"], request["knowns"]
        if not unknowns or not knowns:
            return
        status, values = api.directional(instance, unknowns, knowns, [1.0] * len(knowns))
        if ok(f"{prefix}GetDirectionalDerivative", status):
            compare("directional derivative of unknown", None, values, request["directional"],
                    request["directional_tolerance"])
        if api.adjoint is not None:
            status, values = api.adjoint(instance, unknowns, knowns, [1.0] * len(unknowns))
            if ok("fmi3GetAdjointDerivative", status):
                compare("adjoint derivative of known", None, values, request["adjoint"],
                        request["adjoint_tolerance"])

    def read_states(instance):
        if not n:
            return []
        status, values = api.get(instance, states_vr)
        return values if ok(f"{prefix} get states", status) else None

    for kind in ("me", "cs"):
        if kind not in interfaces:
            continue
        instance = initialised(kind)
        if instance is None:
            continue
        states = []
        try:
            outputs = [0.0] * p
            if kind == "me":
                status, derivatives = api.derivatives(instance, n)
                if ok(f"{prefix} derivatives", status):
                    compare("derivative of state", request["state_names"], derivatives,
                            request["derivatives"], request["derivatives_tolerance"])
                if p:
                    status, outputs = api.get(instance, outputs_vr)
                    if ok(f"{prefix} get outputs", status):
                        compare("output", request["output_names"], outputs, request["outputs"],
                                request["outputs_tolerance"])
                check_partials(instance)
                status, saved = api.get_state(instance)
                if ok(f"{prefix}GetFMUstate", status) and n:
                    states.append(saved)
                    ok(f"{prefix}SetContinuousStates",
                       api.set_continuous_states(instance, [2.0 * v + 1.0 for v in x]))
                    ok(f"{prefix}SetFMUstate", api.set_state(instance, saved))
                    status, back = api.get_continuous_states(instance, n)
                    if ok(f"{prefix}GetContinuousStates", status) and back != x:
                        errors.append(f"a restored FMU state gave the states {back!r}, not the "
                                      f"saved {x!r}")
            else:
                status, saved = api.get_state(instance)
                if ok(f"{prefix}GetFMUstate", status):
                    states.append(saved)
                check_partials(instance)
                if not ok(f"{prefix}DoStep", api.do_step(instance, 0.0, step)):
                    continue
                x1 = read_states(instance)
                if x1 is not None and n:
                    compare("state after one step", request["state_names"], x1,
                            request["next_states"], request["next_states_tolerance"])
                if p and x1 is not None:
                    status, outputs = api.get(instance, outputs_vr)
                    if ok(f"{prefix} get outputs", status):
                        expected, tolerance = [], []
                        for row_c, row_d in zip(request["C"], request["D"]):
                            terms = [a * b for a, b in zip(row_c, x1)] + [a * b for a, b in zip(row_d, u)]
                            expected.append(sum(terms))
                            tolerance.append(2.0 * (len(terms) + 1) * _EPS * sum(abs(t) for t in terms))
                        compare("output after one step", request["output_names"], outputs,
                                expected, tolerance)
                if states and x1 is not None:
                    # rollback: the same step from the restored state, bit for bit
                    status, data = api.serialize(instance, states[0])
                    if ok(f"{prefix}SerializeFMUstate", status):
                        status, copy = api.deserialize(instance, data)
                        if ok(f"{prefix}DeSerializeFMUstate", status):
                            states.append(copy)
                    for label, state in zip(("restored", "deserialised"), states):
                        if not (ok(f"{prefix}SetFMUstate", api.set_state(instance, state))
                                and ok(f"{prefix}DoStep", api.do_step(instance, 0.0, step))):
                            continue
                        again = read_states(instance)
                        if again is not None and again != x1:
                            errors.append(f"the step from the {label} FMU state gave the "
                                          f"states {again!r}, not {x1!r} as before")
            ok(f"{prefix}Terminate", api.terminate(instance))
        finally:
            for state in states:
                api.free_state(instance, state)
            api.free(instance)

    if version == "3.0" and request.get("discrete") and "cs" in interfaces:
        # the clocked partition driven by an importer in Event Mode
        instance = initialised("cs", event_mode=True)
        if instance is not None:
            try:
                if ok("fmi3SetClock", api.set_clock(instance, request["clock_vr"])):
                    if p:
                        status, outputs = api.get(instance, outputs_vr)
                        if ok("fmi3GetFloat64", status):
                            compare("output at the clock tick", request["output_names"], outputs,
                                    request["outputs"], request["outputs_tolerance"])
                    if ok("fmi3UpdateDiscreteStates", api.update_discrete_states(instance)) \
                            and ok("fmi3EnterStepMode", api.enter_step_mode(instance)):
                        x1 = read_states(instance)
                        if x1 is not None and n:
                            compare("state after the clock tick", request["state_names"], x1,
                                    request["next_states"], request["next_states_tolerance"])
            finally:
                api.free(instance)
    return {"errors": errors, "log": log}


def main() -> None:
    request = json.loads(sys.stdin.read())
    try:
        report = run(request)
    except (OSError, AttributeError) as error:  # does not load, or a function is missing
        report = {"errors": [f"{type(error).__name__}: {error}"], "log": []}
    sys.stdout.write(json.dumps(report))


if __name__ == "__main__":
    main()
