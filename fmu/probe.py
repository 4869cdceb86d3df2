"""Load a freshly built FMU library with ctypes and exercise it once (run as a script).

Run by :func:`fmu.verify.verify_library` in a separate process as
``python -I -S probe.py`` with a JSON request on standard input (see
:func:`fmu.verify.probe_input`); prints ``{"errors": [...], "log": [...]}`` on standard
output. Standard library only, no imports of its own package: it runs by file path.

For each declared interface: ``fmi2GetVersion`` and ``fmi2GetTypesPlatform``, then
``fmi2Instantiate`` (with a logger and calloc/free), ``fmi2SetupExperiment``, the test
states and inputs set in Instantiated mode, initialisation, then

- Model Exchange: ``fmi2GetDerivatives`` and ``fmi2GetReal`` of the outputs, compared with
  ``A x + B u`` and ``C x + D u``;
- Co-Simulation: one ``fmi2DoStep`` of the default step, the states compared with
  ``Phi x + Gamma u``, the outputs with ``C x1 + D u`` at the FMU's own new state x1;

then ``fmi2Terminate`` and ``fmi2FreeInstance``. Any status other than fmi2OK, a value
outside the rounding bound, or a message logged at error level is reported.
"""

from __future__ import annotations

import ctypes
import json
import sys

__all__ = ["run", "main"]

_OK = 0
_STATUS = {0: "fmi2OK", 1: "fmi2Warning", 2: "fmi2Discard", 3: "fmi2Error", 4: "fmi2Fatal",
           5: "fmi2Pending"}
_EPS = 2.220446049250313e-16

_Logger = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int,
                           ctypes.c_char_p, ctypes.c_char_p)
_Allocate = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t)
_Free = ctypes.CFUNCTYPE(None, ctypes.c_void_p)
_StepFinished = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int)


class _Callbacks(ctypes.Structure):
    _fields_ = [("logger", _Logger), ("allocateMemory", _Allocate), ("freeMemory", _Free),
                ("stepFinished", _StepFinished), ("componentEnvironment", ctypes.c_void_p)]


def _close(a: float, b: float, tolerance: float) -> bool:
    return abs(a - b) <= tolerance


def run(request: dict) -> dict:
    """Exercise the library described by ``request``; returns ``{"errors", "log"}``."""
    errors: list[str] = []
    log: list[str] = []
    lib = ctypes.CDLL(request["library"])
    libc = ctypes.CDLL(None)

    def logger(environment, instance, status, category, message):
        text = (message or b"").decode("utf-8", "replace")
        log.append(f"{_STATUS.get(status, status)}: {text}")
        if status >= 3:
            errors.append(f"the FMU logged an error: {text}")

    callbacks = _Callbacks()
    callbacks.logger = _Logger(logger)
    callbacks.allocateMemory = ctypes.cast(libc.calloc, _Allocate)
    callbacks.freeMemory = ctypes.cast(libc.free, _Free)
    callbacks.stepFinished = _StepFinished()
    callbacks.componentEnvironment = None

    c_void_p, c_int, c_double, c_size_t = ctypes.c_void_p, ctypes.c_int, ctypes.c_double, ctypes.c_size_t
    c_uint_p, c_double_p = ctypes.POINTER(ctypes.c_uint), ctypes.POINTER(ctypes.c_double)
    signatures = {
        "fmi2GetVersion": (ctypes.c_char_p, []),
        "fmi2GetTypesPlatform": (ctypes.c_char_p, []),
        "fmi2Instantiate": (c_void_p, [ctypes.c_char_p, c_int, ctypes.c_char_p, ctypes.c_char_p,
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
        "fmi2DoStep": (c_int, [c_void_p, c_double, c_double, c_int]),
    }
    functions = {}
    interfaces = request["interfaces"]
    for name, (restype, argtypes) in signatures.items():
        if name in ("fmi2NewDiscreteStates", "fmi2EnterContinuousTimeMode", "fmi2GetDerivatives") \
                and "me" not in interfaces:
            continue
        if name == "fmi2DoStep" and "cs" not in interfaces:
            continue
        function = getattr(lib, name)
        function.restype, function.argtypes = restype, argtypes
        functions[name] = function

    if functions["fmi2GetVersion"]() != b"2.0":
        errors.append(f"fmi2GetVersion returned {functions['fmi2GetVersion']()!r}, not b'2.0'")
    if functions["fmi2GetTypesPlatform"]() != b"default":
        errors.append("fmi2GetTypesPlatform did not return b'default'")

    n, m, p = request["n_states"], request["n_inputs"], request["n_outputs"]
    x, u = request["states"], request["inputs"]
    step = request["step"]

    def call(name, *args):
        status = functions[name](*args)
        if status != _OK:
            errors.append(f"{name} returned {_STATUS.get(status, status)}")
        return status == _OK

    def compare(what, names, got, expected, tolerance):
        for i, (a, b, t) in enumerate(zip(got, expected, tolerance)):
            if not _close(a, b, t):
                errors.append(f"{what} {names[i]}: the FMU computed {a!r}, expected {b!r} "
                              f"(rounding bound {t:.3g})")
                return

    for kind, code in (("me", 0), ("cs", 1)):
        if kind not in interfaces:
            continue
        instance = functions["fmi2Instantiate"](f"check_{kind}".encode(), code,
                                                request["guid"].encode(), b"file:///",
                                                ctypes.byref(callbacks), 0, 0)
        if not instance:
            errors.append(f"fmi2Instantiate ({kind}) returned NULL")
            continue
        try:
            inputs_vr = (ctypes.c_uint * max(m, 1))(*range(m))
            outputs_vr = (ctypes.c_uint * max(p, 1))(*range(m, m + p))
            states_vr = (ctypes.c_uint * max(n, 1))(*range(m + p, m + p + n))
            if not call("fmi2SetupExperiment", instance, 0, 0.0, 0.0, 0, 0.0):
                continue
            if n and not call("fmi2SetReal", instance, states_vr, n, (c_double * n)(*x)):
                continue
            if m and not call("fmi2SetReal", instance, inputs_vr, m, (c_double * m)(*u)):
                continue
            if not (call("fmi2EnterInitializationMode", instance)
                    and call("fmi2ExitInitializationMode", instance)):
                continue
            outputs = (c_double * max(p, 1))()
            if kind == "me":
                event_info = (ctypes.c_byte * 64)()  # fmi2EventInfo is smaller
                if not (call("fmi2NewDiscreteStates", instance, event_info)
                        and call("fmi2EnterContinuousTimeMode", instance)):
                    continue
                derivatives = (c_double * max(n, 1))()
                if call("fmi2GetDerivatives", instance, derivatives, n):
                    compare("derivative of state", request["state_names"], derivatives[:n],
                            request["derivatives"], request["derivatives_tolerance"])
                if p and call("fmi2GetReal", instance, outputs_vr, p, outputs):
                    compare("output", request["output_names"], outputs[:p],
                            request["outputs"], request["outputs_tolerance"])
            else:
                if not call("fmi2DoStep", instance, 0.0, step, 1):
                    continue
                states = (c_double * max(n, 1))()
                if n and call("fmi2GetReal", instance, states_vr, n, states):
                    compare("state after one step", request["state_names"], states[:n],
                            request["next_states"], request["next_states_tolerance"])
                if p and call("fmi2GetReal", instance, outputs_vr, p, outputs):
                    x1 = states[:n]
                    expected, tolerance = [], []
                    for row_c, row_d in zip(request["C"], request["D"]):
                        terms = [a * b for a, b in zip(row_c, x1)] + [a * b for a, b in zip(row_d, u)]
                        expected.append(sum(terms))
                        tolerance.append(2.0 * (len(terms) + 1) * _EPS * sum(abs(t) for t in terms))
                    compare("output after one step", request["output_names"], outputs[:p],
                            expected, tolerance)
            call("fmi2Terminate", instance)
        finally:
            functions["fmi2FreeInstance"](instance)
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
