"""An exported FMU's binary called directly through ctypes, for the misuse tests: its FMI 2.0
functions bound with their argument types, and the status and kind codes of the standard."""
from __future__ import annotations

import ctypes
import zipfile
from ctypes import POINTER, byref, c_char_p, c_double, c_int, c_size_t, c_uint, c_void_p

from fmpy import calloc, free, read_model_description
from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2EventInfo)

__all__ = ["CO_SIMULATION", "DISCARD", "ERROR", "LAST_SUCCESSFUL_TIME", "MODEL_EXCHANGE", "OK",
           "WARNING", "Binary"]

#: fmi2Status, fmi2Type and fmi2StatusKind values (FMI 2.0.4, section 2.1).
OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3
MODEL_EXCHANGE, CO_SIMULATION = 0, 1
LAST_SUCCESSFUL_TIME = 2


class Binary:
    """The FMU's shared library with typed FMI functions and a logger that records."""

    def __init__(self, path, folder):
        with zipfile.ZipFile(path) as archive:
            archive.extractall(folder)
        description = read_model_description(str(path))
        self.guid = description.guid.encode()
        self.vr = {v.name: v.valueReference for v in description.modelVariables}
        identifier = (description.coSimulation or description.modelExchange).modelIdentifier
        self.lib = ctypes.CDLL(str(folder / "binaries" / "linux64" / f"{identifier}.so"))
        self.messages = []

        def logger(environment, instance, status, category, message):
            self.messages.append((status, category.decode(), message.decode()))

        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(logger)
        self.callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self.callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        signatures = {
            "fmi2Instantiate": (c_void_p, [c_char_p, c_int, c_char_p, c_char_p,
                                           POINTER(fmi2CallbackFunctions), c_int, c_int]),
            "fmi2FreeInstance": (None, [c_void_p]),
            "fmi2SetupExperiment": (c_int, [c_void_p, c_int, c_double, c_double, c_int, c_double]),
            "fmi2EnterInitializationMode": (c_int, [c_void_p]),
            "fmi2ExitInitializationMode": (c_int, [c_void_p]),
            "fmi2Terminate": (c_int, [c_void_p]),
            "fmi2Reset": (c_int, [c_void_p]),
            "fmi2GetReal": (c_int, [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_double)]),
            "fmi2SetReal": (c_int, [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_double)]),
            "fmi2GetInteger": (c_int, [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_int)]),
            "fmi2DoStep": (c_int, [c_void_p, c_double, c_double, c_int]),
            "fmi2GetRealStatus": (c_int, [c_void_p, c_int, POINTER(c_double)]),
            "fmi2SetDebugLogging": (c_int, [c_void_p, c_int, c_size_t, POINTER(c_char_p)]),
            "fmi2NewDiscreteStates": (c_int, [c_void_p, POINTER(fmi2EventInfo)]),
            "fmi2GetDerivatives": (c_int, [c_void_p, POINTER(c_double), c_size_t]),
            "fmi2SetContinuousStates": (c_int, [c_void_p, POINTER(c_double), c_size_t]),
            "fmi2SetTime": (c_int, [c_void_p, c_double]),
            "fmi2GetFMUstate": (c_int, [c_void_p, POINTER(c_void_p)]),
        }
        for name, (restype, argtypes) in signatures.items():
            function = getattr(self.lib, name)
            function.restype, function.argtypes = restype, argtypes
            setattr(self, name[4:], function)

    def instantiate(self, kind=CO_SIMULATION, guid=None, name=b"test"):
        return self.Instantiate(name, kind, self.guid if guid is None else guid, None,
                                byref(self.callbacks), 0, 0)

    def initialised(self, kind=CO_SIMULATION):
        c = self.instantiate(kind)
        assert c
        assert self.SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == OK
        assert self.EnterInitializationMode(c) == OK
        assert self.ExitInitializationMode(c) == OK
        return c

    def get(self, c, *names):
        vrs = (c_uint * len(names))(*(self.vr[n] for n in names))
        values = (c_double * len(names))()
        status = self.GetReal(c, vrs, len(names), values)
        return status, list(values)

    def set(self, c, **values):
        vrs = (c_uint * len(values))(*(self.vr[n] for n in values))
        array = (c_double * len(values))(*values.values())
        return self.SetReal(c, vrs, len(values), array)

    def last_message(self):
        return self.messages[-1][2] if self.messages else ""
