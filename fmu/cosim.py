"""Fixed-step co-simulation of a plant FMU with a controller FMU (FMI 2.0 or 3.0
Co-Simulation, in any combination).

A small master over fmpy's :class:`fmpy.fmi2.FMU2Slave` and :class:`fmpy.fmi3.FMU3Slave`:
it connects outputs to inputs of the same name, feeds the remaining inputs from user
signals, and advances both FMUs with the same communication step. Every FMU call goes
through one choke point that turns a failed status into a
:class:`~fmu.errors.CosimulationError` naming the FMU, the call and the time.

An FMI 3.0 FMU with a periodic time-based input Clock (a sampled controller exported by
:func:`fmu.export`) is instantiated with Event Mode, and at every communication point that
is one of its clock's ticks the master activates the clock: ``fmi3EnterEventMode``,
``fmi3SetClock``, ``fmi3UpdateDiscreteStates``, ``fmi3EnterStepMode``, after setting the
FMU's inputs of that instant (FMI 3.0.2, sections 2.2.10 and 4.2). Ticks between
communication points (a clock faster than the communication step, or not aligned with it)
are left to the FMU, which takes them in ``fmi3DoStep`` with the inputs held, as flexsat's
sampled FMUs do.
"""

from __future__ import annotations

import math
import os
import shutil
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Union

import numpy as np

from .checks import check_cosimulation_run, shorten
from .errors import CosimulationError

__all__ = ["FMUSlave", "Signal", "cosimulate", "run_loop"]

#: An external input: a constant, a function of time ``f(t) -> float`` (t in s), or a table
#: ``(times, values)`` (see :func:`cosimulate`).
Signal = Union[float, Callable[[float], float], tuple]

class FMUSlave:
    """One Co-Simulation FMU instance (FMI 2.0 or 3.0), with its real inputs and outputs
    by name and, for FMI 3.0, its periodic input clock if it has one.

    The master's view of an FMU over fmpy's ``FMU2Slave``/``FMU3Slave``: every call's status
    is checked in one place and a failure raised as a :class:`~fmu.errors.CosimulationError`
    naming the FMU (by ``role``), the call and the time.

    Parameters
    ----------
    path : str or os.PathLike
        The .fmu file.
    role : str
        The FMU's part in the loop for the messages ("plant", "controller", an SSP
        component's name); ``<role>_fmu`` is the parameter named when ``path`` is refused.
    """

    def __init__(self, path: str | Path, role: str):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave
        from fmpy.fmi3 import FMU3Slave

        self.role = role
        if not isinstance(path, (str, os.PathLike)):
            raise TypeError(f"{role}_fmu must be a str or os.PathLike (an .fmu file); got "
                            f"{type(path).__name__}")
        self.path = Path(path)
        self.unzip_dir = None
        self.fmu = None
        self.instantiated = False
        if not self.path.is_file():
            raise FileNotFoundError(f"{role}_fmu must be an existing .fmu file; got {shorten(str(path))}")
        try:
            description = read_model_description(str(self.path))
        except Exception as error:  # fmpy raises plain exceptions for unreadable FMUs
            raise CosimulationError(f"the {role} FMU {self.path.name} cannot be read: "
                                    f"{shorten(str(error), 300)}") from error
        version = description.fmiVersion
        if version not in ("2.0",) and not version.startswith("3."):
            raise CosimulationError(f"the {role} FMU {self.path.name} must be FMI 2.0 or 3.0; "
                                    f"got FMI {version}")
        if description.coSimulation is None:
            raise CosimulationError(f"the {role} FMU {self.path.name} must provide "
                                    f"Co-Simulation; got FMI {version} without a CoSimulation "
                                    "interface")
        self.fmi3 = version.startswith("3.")
        self.name = description.modelName
        real = "Float64" if self.fmi3 else "Real"
        self.variables = {v.name: v for v in description.modelVariables}
        self.inputs = {v.name: v.valueReference for v in description.modelVariables
                       if v.causality == "input" and v.type == real}
        self.outputs = {v.name: v.valueReference for v in description.modelVariables
                        if v.causality == "output" and v.type == real}
        clocks = [v for v in description.modelVariables
                  if v.type == "Clock" and v.causality == "input"]
        self.clock = None  # (value reference, interval [s], shift [s])
        if clocks:
            clock = clocks[0]
            # fmpy does not read intervalDecimal and shiftDecimal: read them here
            interval, shift = _clock_timing(self.path, clock.valueReference)
            if len(clocks) > 1 or clock.intervalVariability != "constant" or interval is None:
                raise CosimulationError(
                    f"the {role} FMU {self.path.name} has clocks this master cannot drive (it "
                    "drives one periodic input clock with a constant intervalDecimal)")
            self.clock = (clock.valueReference, interval, shift)
        self.unzip_dir = extract(str(self.path))
        kind = FMU3Slave if self.fmi3 else FMU2Slave
        self.fmu = kind(guid=description.guid, unzipDirectory=self.unzip_dir,
                        modelIdentifier=description.coSimulation.modelIdentifier,
                        instanceName=role)
        self.start_time = 0.0

    def call(self, what: str, time: float, function: Callable, *args: object, **kwargs) -> object:
        """The choke point: run one FMU call, raise CosimulationError if it fails."""
        try:
            return function(*args, **kwargs)
        except Exception as error:
            raise CosimulationError(f"{self.role} FMU {self.name}: {what} failed at t = {time!r} s: "
                                    f"{shorten(str(error), 300)}") from error

    def _prefix(self) -> str:
        return "fmi3" if self.fmi3 else "fmi2"

    def initialise(self, start_time: float, stop_time: float,
                   start_values: Mapping[str, float] | None) -> None:
        """Instantiate, set start values, initialise; leaves the FMU ready to step."""
        t0 = start_time
        self.start_time = t0
        p = self._prefix()
        if self.fmi3:
            self.call(f"{p}InstantiateCoSimulation", t0, self.fmu.instantiate,
                      eventModeUsed=self.clock is not None)
        else:
            self.call(f"{p}Instantiate", t0, self.fmu.instantiate)
        self.instantiated = True
        if not self.fmi3:
            self.call("fmi2SetupExperiment", t0, self.fmu.setupExperiment, None, t0, stop_time)
        for name, value in (start_values or {}).items():
            if name not in self.variables:
                raise ValueError(f"{self.role}_start_values names {shorten(name)}, which "
                                 f"the {self.role} FMU does not have; expected one of "
                                 f"{shorten(sorted(self.variables))}")
            self.set([self.variables[name].valueReference], [value], t0)
        if self.fmi3:
            self.call(f"{p}EnterInitializationMode", t0, self.fmu.enterInitializationMode,
                      startTime=t0, stopTime=stop_time)
        else:
            self.call(f"{p}EnterInitializationMode", t0, self.fmu.enterInitializationMode)
        self.call(f"{p}ExitInitializationMode", t0, self.fmu.exitInitializationMode)
        if self.fmi3 and self.clock is not None:
            # Event Mode after initialisation: nothing to update yet (the tick at the start
            # time comes with the inputs of that instant, in the loop)
            self.call("fmi3UpdateDiscreteStates", t0, self.fmu.updateDiscreteStates)
            self.call("fmi3EnterStepMode", t0, self.fmu.enterStepMode)

    def ticks_at(self, time: float) -> bool:
        """True if the FMU's clock ticks at this communication point."""
        if self.clock is None:
            return False
        _, interval, shift = self.clock
        ticks = (time - self.start_time - shift) / interval
        return ticks > -1e-9 and abs(ticks - round(ticks)) <= 1e-9 * max(1.0, abs(ticks))

    def tick(self, time: float) -> None:
        """Activate the clock in Event Mode if it ticks now (its inputs already set)."""
        if not self.ticks_at(time):
            return
        self.call("fmi3EnterEventMode", time, self.fmu.enterEventMode)
        self.call("fmi3SetClock", time, self.fmu.setClock, [self.clock[0]], [True])
        self.call("fmi3UpdateDiscreteStates", time, self.fmu.updateDiscreteStates)
        self.call("fmi3EnterStepMode", time, self.fmu.enterStepMode)

    def get(self, vrs: list[int], time: float) -> list[float]:
        if not vrs:
            return []
        if self.fmi3:
            return self.call("fmi3GetFloat64", time, self.fmu.getFloat64, vrs)
        return self.call("fmi2GetReal", time, self.fmu.getReal, vrs)

    def set(self, vrs: list[int], values: list[float], time: float) -> None:
        if not vrs:
            return
        values = [float(v) for v in values]
        if self.fmi3:
            self.call("fmi3SetFloat64", time, self.fmu.setFloat64, vrs, values)
        else:
            self.call("fmi2SetReal", time, self.fmu.setReal, vrs, values)

    def do_step(self, time: float, step: float) -> None:
        self.call(f"{self._prefix()}DoStep", time, self.fmu.doStep, time, step)

    def close(self) -> None:
        if self.fmu is not None and self.instantiated:
            try:
                self.fmu.terminate()
            except Exception:
                pass  # already terminated or in an error state: freeing is what matters
            try:
                self.fmu.freeInstance()
            except Exception:
                pass
        if self.unzip_dir is not None:
            shutil.rmtree(self.unzip_dir, ignore_errors=True)


def _clock_timing(path: Path, value_reference: int) -> tuple[float | None, float]:
    """intervalDecimal (None if absent or not positive and finite) and shiftDecimal of an
    FMI 3.0 Clock, read from the FMU's modelDescription.xml."""
    import zipfile
    from xml.etree import ElementTree

    with zipfile.ZipFile(path) as archive:
        root = ElementTree.fromstring(archive.read("modelDescription.xml"))
    for element in root.iter("Clock"):
        if element.get("valueReference") == str(value_reference):
            try:
                interval = float(element.get("intervalDecimal", "nan"))
                shift = float(element.get("shiftDecimal", "0"))
            except ValueError:
                return None, 0.0
            valid = math.isfinite(interval) and interval > 0 and math.isfinite(shift)
            return (interval, shift) if valid else (None, 0.0)
    return None, 0.0


def _evaluator(name: str, signal: Signal) -> Callable[[float], float]:
    """Turn a constant, callable or table into a function of time."""
    if callable(signal):
        return signal
    if isinstance(signal, (int, float, np.integer, np.floating)) and not isinstance(signal, bool):
        value = float(signal)
        return lambda t: value
    try:
        times, values = (np.asarray(part, dtype=np.float64) for part in signal)
    except (TypeError, ValueError) as error:
        raise TypeError(f"inputs[{shorten(name)}] must be a number, a function of time f(t) or "
                        f"a table (times, values); got {type(signal).__name__} "
                        f"{shorten(signal)}") from error
    if times.ndim != 1 or times.shape != values.shape or times.size == 0:
        raise ValueError(f"inputs[{shorten(name)}] table must be two 1-D arrays (times [s], values) of "
                         f"equal non-zero length; got shapes {times.shape} and {values.shape}")
    if not (np.all(np.isfinite(times)) and np.all(np.isfinite(values))):
        raise ValueError(f"inputs[{shorten(name)}] table must be finite; got a NaN or an "
                         "infinity")
    if np.any(np.diff(times) < 0):
        bad = int(np.flatnonzero(np.diff(times) < 0)[0])
        raise ValueError(f"inputs[{shorten(name)}] table times must be non-decreasing [s]; got "
                         f"{times[bad]!r} then {times[bad + 1]!r} at index {bad}")

    def table(t: float) -> float:
        # right-continuous linear interpolation: at a repeated time row (a step) the last
        # row wins, as fmpy applies inputs "after the event"; constant outside the table
        index = int(np.searchsorted(times, t, side="right"))
        if index == 0:
            return float(values[0])
        if index == times.size or times[index - 1] == t:
            return float(values[index - 1])
        t0, t1 = times[index - 1], times[index]
        return float(values[index - 1] + (values[index] - values[index - 1]) * (t - t0) / (t1 - t0))

    return table


def cosimulate(plant_fmu: str | Path, controller_fmu: str | Path, stop_time: float, step: float,
               *, method: str = "gauss-seidel", inputs: Mapping[str, Signal] | None = None,
               start_time: float = 0.0,
               plant_start_values: Mapping[str, float] | None = None,
               controller_start_values: Mapping[str, float] | None = None) -> np.ndarray:
    """Co-simulate a plant FMU and a controller FMU with a fixed communication step.

    Outputs are connected to inputs of the same name (plant outputs to controller inputs and
    controller outputs to plant inputs). Inputs that no output feeds are external: they take
    their values from ``inputs`` (or keep their start values).

    The master samples at ``t_k = start_time + k * step``, k = 0..N, and holds every input
    constant over ``[t_k, t_k+1)`` (zero-order hold), so with exact FMUs (as exported by
    :func:`fmu.export`) the result is the sampled-data closed loop exactly:

    ``method="gauss-seidel"`` (sequential exchange) - at each t_k:

    1. external inputs ``r_k = r(t_k)`` are set;
    2. the plant outputs ``y_k`` are read and set as controller inputs;
    3. the controller outputs ``u_k`` are read (they already reflect ``y_k`` and ``r_k``
       through the controller's direct feedthrough) and set as plant inputs;
    4. both FMUs step from t_k to t_k+1.

    This equals the monolithic loop ``x_p+ = Phi_p x_p + Gamma_p u_k``,
    ``u_k = C_c x_c + D_c [r_k; y_k]``, ``x_c+ = Phi_c x_c + Gamma_c [r_k; y_k]`` with
    ``y_k = C_p x_p,k`` (a plant with direct feedthrough sees ``u_{k-1}`` in ``y_k``: the
    algebraic loop is not iterated).

    ``method="jacobi"`` (parallel exchange) - at each t_k the outputs of both FMUs are read
    first, with the inputs they were given at t_k-1 (at k = 0: their start values); then
    external inputs and connections are set and both FMUs step. Each FMU's direct
    feedthrough therefore acts one step late: ``u_k = C_c x_c,k + D_c [r_k-1; y_k-1]``,
    while the controller state still integrates the fresh ``[r_k; y_k]``.

    Parameters
    ----------
    plant_fmu, controller_fmu : str or pathlib.Path
        FMI 2.0 or FMI 3.0 Co-Simulation FMUs (a sampled FMI 3.0 controller's clock is
        activated at its ticks, see the module docstring).
    stop_time : float, s
        Final time; ``stop_time - start_time`` must be a whole number of steps (to 1e-9
        relative).
    step : float, s
        Communication step h, positive.
    method : {"gauss-seidel", "jacobi"}, default "gauss-seidel"
    inputs : mapping of str to signal, optional
        External inputs by name: a number (constant), a function ``f(t)`` of time in s, or a
        table ``(times, values)`` evaluated by linear interpolation, right-continuous at
        repeated times (a step), constant beyond its ends. Values in the input's unit.
    start_time : float, default 0.0, s
    plant_start_values, controller_start_values : mapping of str to float, optional
        Start values (e.g. initial states) set before initialisation.

    Returns
    -------
    numpy.ndarray
        Structured array of shape (N + 1,), float64 fields ``time``, then the plant outputs,
        the controller outputs and the external inputs, each as exchanged at ``t_k``.

    Raises
    ------
    CosimulationError
        If the FMUs cannot be connected (no connection in one direction, a name that both
        output) or an FMU call fails.
    ValueError, TypeError
        For bad ``stop_time``, ``step``, ``method``, ``inputs`` or start values, or more than
        :data:`fmu.limits.MAX_COSIMULATION_STEPS` steps (checked before anything is done).

    References
    ----------
    M. Arnold, C. Clauss, T. Schierz, "Error analysis and error estimates for co-simulation
    in FMI for Model Exchange and Co-Simulation V2.0", Archive of Mechanical Engineering
    60(1), 75-94, 2013 (Jacobi and Gauss-Seidel master algorithms).
    """
    n_steps = check_cosimulation_run(method, step, stop_time, start_time, inputs,
                                     (("plant_start_values", plant_start_values),
                                      ("controller_start_values", controller_start_values)))
    slaves: list[FMUSlave] = []
    try:
        plant = FMUSlave(plant_fmu, "plant")
        slaves.append(plant)
        controller = FMUSlave(controller_fmu, "controller")
        slaves.append(controller)

        plant_to_controller = [(name, name) for name in plant.outputs if name in controller.inputs]
        controller_to_plant = [(name, name) for name in controller.outputs if name in plant.inputs]
        if not plant_to_controller or not controller_to_plant:
            raise CosimulationError(
                "the FMUs must be connected both ways by equal signal names; got plant outputs "
                f"{shorten(list(plant.outputs))}, controller inputs {shorten(list(controller.inputs))}, "
                f"controller outputs {shorten(list(controller.outputs))}, plant inputs "
                f"{shorten(list(plant.inputs))}")
        both = set(plant.outputs) & set(controller.outputs)
        if both:
            raise CosimulationError(f"plant and controller both output {shorten(sorted(both))}; "
                                    "rename one so every signal has one source")
        # external inputs: inputs that no output feeds, by name (one name may be an input
        # of both FMUs: it is then set on both)
        external: dict[str, list[tuple[FMUSlave, str]]] = {}
        for slave, connected in ((controller, plant_to_controller), (plant, controller_to_plant)):
            fed = {end for _, end in connected}
            for name in slave.inputs:
                if name not in fed:
                    external.setdefault(name, []).append((slave, name))
        return run_loop(plant, controller, plant_to_controller, controller_to_plant, external,
                        inputs, method=method, start_time=float(start_time), n_steps=n_steps,
                        step=step, plant_start_values=plant_start_values,
                        controller_start_values=controller_start_values)
    finally:
        for slave in slaves:
            slave.close()


def run_loop(plant: FMUSlave, controller: FMUSlave, plant_to_controller: list[tuple[str, str]],
             controller_to_plant: list[tuple[str, str]],
             external: Mapping[str, list[tuple[FMUSlave, str]]],
             inputs: Mapping[str, Signal] | None, *, method: str, start_time: float,
             n_steps: int, step: float, plant_start_values: Mapping[str, float] | None = None,
             controller_start_values: Mapping[str, float] | None = None) -> np.ndarray:
    """The master loop of :func:`cosimulate` over two open FMUs and explicit connections.

    Parameters
    ----------
    plant, controller : FMUSlave
        Not yet initialised; the caller closes them.
    plant_to_controller, controller_to_plant : list of (output name, input name)
    external : mapping of str to list of (FMUSlave, input name)
        Unconnected inputs by external name.
    inputs : mapping of str to signal, optional
        Values of external inputs by external name.
    method, start_time, n_steps, step, plant_start_values, controller_start_values
        As :func:`cosimulate` (already checked).

    Returns
    -------
    numpy.ndarray
        As :func:`cosimulate`.
    """
    signals = {}
    for name, signal in (inputs or {}).items():
        if name not in external:
            raise ValueError(f"inputs names {shorten(name)}, which is not an unconnected "
                             f"input of either FMU; expected one of {shorten(sorted(external))}")
        signals[name] = _evaluator(name, signal)

    t0 = start_time
    t_stop = t0 + n_steps * step
    for slave, values in ((plant, plant_start_values), (controller, controller_start_values)):
        slave.initialise(t0, t_stop, values)

    plant_out_names = list(plant.outputs)
    controller_out_names = list(controller.outputs)
    plant_out_vrs = [plant.outputs[n] for n in plant_out_names]
    controller_out_vrs = [controller.outputs[n] for n in controller_out_names]
    # connections as (position in the source's output list, input value reference)
    p2c_from = [plant_out_names.index(start) for start, _ in plant_to_controller]
    p2c_in = [controller.inputs[end] for _, end in plant_to_controller]
    c2p_from = [controller_out_names.index(start) for start, _ in controller_to_plant]
    c2p_in = [plant.inputs[end] for _, end in controller_to_plant]
    # a name that is also an output (of the same FMU, which cannot feed itself) would
    # clash in the result: such an input keeps its value and is not recorded
    recorded_external = [n for n in external if n not in plant.outputs and n not in controller.outputs]

    def apply_external(t: float) -> list[float]:
        values = []
        for name in recorded_external:
            if name in signals:
                value = float(signals[name](t))
                if not math.isfinite(value):
                    raise ValueError(f"inputs[{shorten(name)}] must be finite; got {value!r} "
                                     f"at t = {t!r} s")
                for slave, end in external[name]:
                    slave.set([slave.inputs[end]], [value], t)
            else:
                slave, end = external[name][0]
                value = slave.get([slave.inputs[end]], t)[0]
            values.append(value)
        return values

    rows = np.empty((n_steps + 1, 1 + len(plant_out_names) + len(controller_out_names)
                     + len(recorded_external)), dtype=np.float64)
    for k in range(n_steps + 1):
        t = t0 + k * step
        # a clocked FMU ticks once its inputs of this instant are set: before its
        # outputs are read (Gauss-Seidel), or before it steps (Jacobi)
        if method == "gauss-seidel":
            r = apply_external(t)
            plant.tick(t)
            y = plant.get(plant_out_vrs, t)
            controller.set(p2c_in, [y[i] for i in p2c_from], t)
            controller.tick(t)
            u = controller.get(controller_out_vrs, t)
            plant.set(c2p_in, [u[i] for i in c2p_from], t)
        else:
            y = plant.get(plant_out_vrs, t)
            u = controller.get(controller_out_vrs, t)
            r = apply_external(t)
            controller.set(p2c_in, [y[i] for i in p2c_from], t)
            plant.set(c2p_in, [u[i] for i in c2p_from], t)
            plant.tick(t)
            controller.tick(t)
        rows[k] = [t, *y, *u, *r]
        if k < n_steps:
            plant.do_step(t, step)
            controller.do_step(t, step)

    names = ["time", *plant_out_names, *controller_out_names, *recorded_external]
    result = np.empty(n_steps + 1, dtype=[(name, np.float64) for name in names])
    for column, name in enumerate(names):
        result[name] = rows[:, column]
    return result
