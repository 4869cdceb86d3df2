"""System Structure and Parameterization (SSP): a plant FMU and a controller FMU connected.

:func:`write_ssp` packs two Co-Simulation FMUs (FMI 2.0 or 3.0) into one ``.ssp`` file:
``SystemStructure.ssd`` at its root and the FMUs under ``resources/``. The system
description connects every output to the input of the other FMU that has the same name
(as :func:`fmu.cosimulate` does), makes every input that no output feeds an input of the
system, and every output an output of the system, with the units of the FMUs. The
``.ssd`` is validated against the SSP 1.0 schema (the one FMPy ships) before the file is
written, all or nothing, as FMUs are.

:func:`cosimulate_ssp` reads an SSP (validating it again), extracts its two FMUs and runs
them with flexsat's master (:func:`fmu.cosim.run_loop`) along the connections of the
``.ssd``: the first component is the plant, whose outputs the Gauss-Seidel master reads
first. FMPy's own SSP master (``fmpy.ssp.simulation.simulate_ssp``) runs SSPs of FMI 2.0
FMUs too; it exchanges values after each step (a Jacobi master whose outputs lag one
step), see the tests.

References
----------
Modelica Association, "System Structure and Parameterization 1.0", 2019, sections 5
(SystemStructureDescription: System, Component, Connector, Connection) and 4 (the SSP
archive: SystemStructure.ssd, resources/).
"""

from __future__ import annotations

import io
import os
import shutil
import tempfile
import zipfile
from collections.abc import Mapping
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from .checks import check_cosimulation_run, shorten, xml_text
from .cosim import FMUSlave, Signal, run_loop
from .errors import CosimulationError, FMUBuildError
from .files import write_atomically
from .units import SI_UNITS

__all__ = ["write_ssp", "cosimulate_ssp", "SSD_NAME", "SSP_VERSION"]

#: Name of the system structure description inside an SSP file.
SSD_NAME = "SystemStructure.ssd"
#: SSP version written (the schema FMPy validates against).
SSP_VERSION = "1.0"

_NAMESPACES = ('xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" '
               'xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription"')


def _interface(path: Path, role: str) -> tuple[str, dict, dict]:
    """Version, real inputs and real outputs (name -> unit or None) of a CS FMU."""
    from fmpy import read_model_description

    if not Path(path).is_file():
        raise FileNotFoundError(f"{role}_fmu must be an existing .fmu file; got {shorten(str(path))}")
    try:
        description = read_model_description(str(path))
    except Exception as error:  # fmpy raises plain exceptions for unreadable FMUs
        raise FMUBuildError(f"the {role} FMU {Path(path).name} cannot be read: "
                            f"{shorten(str(error), 300)}") from error
    if description.coSimulation is None:
        raise FMUBuildError(f"the {role} FMU {Path(path).name} must provide Co-Simulation")
    real = ("Real", "Float64")
    inputs = {v.name: v.unit for v in description.modelVariables
              if v.causality == "input" and v.type in real}
    outputs = {v.name: v.unit for v in description.modelVariables
               if v.causality == "output" and v.type in real}
    return description.fmiVersion, inputs, outputs


def _connector(name: str, kind: str, unit: str | None, indent: int) -> str:
    unit_text = f" unit={quoteattr(unit)}" if unit in SI_UNITS else ""
    return (f"{' ' * indent}<ssd:Connector name={quoteattr(name)} kind=\"{kind}\">"
            f"<ssc:Real{unit_text}/></ssd:Connector>")


def _ssd(name: str, description: str, components: list[tuple[str, str, dict, dict]],
         stop_time: float | None) -> str:
    """Text of SystemStructure.ssd for components (name, source, inputs, outputs)."""
    connections = []
    fed = set()
    for start, _, _, outputs in components:
        for end, _, inputs, _ in components:
            if end == start:
                continue
            for signal in outputs:
                if signal in inputs:
                    connections.append((start, signal, end, signal))
                    fed.add((end, signal))
    system_inputs: dict[str, str | None] = {}
    for component, _, inputs, _ in components:
        for signal, unit in inputs.items():
            if (component, signal) not in fed:
                system_inputs.setdefault(signal, unit)
                connections.append((None, signal, component, signal))
    system_outputs: dict[str, str | None] = {}
    for component, _, _, outputs in components:
        for signal, unit in outputs.items():
            system_outputs[signal] = unit
            connections.append((component, signal, None, signal))
    units = sorted({u for _, _, i, o in components for u in (*i.values(), *o.values())
                    if u in SI_UNITS})

    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<ssd:SystemStructureDescription {_NAMESPACES} version="{SSP_VERSION}"'
             f' name={quoteattr(name)} generationTool="flexsat.fmu">',
             f'  <ssd:System name={quoteattr(name)} description={quoteattr(description)}>',
             "    <ssd:Connectors>"]
    lines += [_connector(s, "input", u, 6) for s, u in system_inputs.items()]
    lines += [_connector(s, "output", u, 6) for s, u in system_outputs.items()]
    lines.append("    </ssd:Connectors>")
    lines.append("    <ssd:Elements>")
    for component, source, inputs, outputs in components:
        lines.append(f'      <ssd:Component name={quoteattr(component)}'
                     f' type="application/x-fmu-sharedlibrary" source={quoteattr(source)}'
                     ' implementation="CoSimulation">')
        lines.append("        <ssd:Connectors>")
        lines += [_connector(s, "input", u, 10) for s, u in inputs.items()]
        lines += [_connector(s, "output", u, 10) for s, u in outputs.items()]
        lines.append("        </ssd:Connectors>")
        lines.append("      </ssd:Component>")
    lines.append("    </ssd:Elements>")
    lines.append("    <ssd:Connections>")
    for start, start_connector, end, end_connector in connections:
        start_text = f" startElement={quoteattr(start)}" if start is not None else ""
        end_text = f" endElement={quoteattr(end)}" if end is not None else ""
        lines.append(f"      <ssd:Connection{start_text} startConnector={quoteattr(start_connector)}"
                     f"{end_text} endConnector={quoteattr(end_connector)}/>")
    lines.append("    </ssd:Connections>")
    lines.append("  </ssd:System>")
    if units:
        lines.append("  <ssd:Units>")
        for unit in units:
            exponents = " ".join(f'{k}="{v}"' for k, v in SI_UNITS[unit].items())
            lines.append(f'    <ssc:Unit name="{unit}"><ssc:BaseUnit {exponents}/></ssc:Unit>')
        lines.append("  </ssd:Units>")
    if stop_time is not None:
        lines.append(f'  <ssd:DefaultExperiment startTime="0.0" stopTime="{stop_time!r}"/>')
    lines.append("</ssd:SystemStructureDescription>")
    return "\n".join(lines) + "\n"


def _validate_ssd(text: str) -> None:
    """Validate an SSD against the SSP 1.0 schema that FMPy ships; FMUBuildError if not."""
    from lxml import etree
    from fmpy.ssp.ssd import validate_tree

    try:
        validate_tree(etree.parse(io.BytesIO(text.encode("utf-8"))).getroot(),
                      "SystemStructureDescription.xsd")
    except Exception as error:
        raise FMUBuildError(f"the system structure description does not validate against the "
                            f"SSP {SSP_VERSION} schema: {shorten(str(error), 500)}; this is a "
                            "bug in flexsat.fmu, please report it.") from error


def write_ssp(path: str | os.PathLike, plant_fmu: str | os.PathLike,
              controller_fmu: str | os.PathLike, *, name: str = "loop",
              description: str | None = None, stop_time: float | None = None) -> Path:
    """Write an SSP file connecting a plant FMU and a controller FMU by signal name.

    Parameters
    ----------
    path : str or os.PathLike
        The ``.ssp`` file to write (missing parent folders are created).
    plant_fmu, controller_fmu : str or os.PathLike
        Co-Simulation FMUs (FMI 2.0 or 3.0), e.g. from :func:`fmu.export`; they become the
        components ``plant`` and ``controller`` (in this order) and are copied into the
        SSP under ``resources/``.
    name : str, default "loop"
        Name of the system structure and of the system.
    description : str, optional
        Description of the system.
    stop_time : float, optional, s
        DefaultExperiment stopTime.

    Returns
    -------
    pathlib.Path
        The SSP file written.

    Raises
    ------
    FMUBuildError
        If an FMU cannot be read or has no Co-Simulation, or if the FMUs are not connected
        both ways by equal signal names.
    FileNotFoundError
        If an FMU does not exist.
    ValueError, TypeError
        For a bad ``path``, ``name``, ``description`` or ``stop_time``.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike (a .ssp file); got "
                        f"{type(path).__name__} {shorten(path)}")
    target = Path(path)
    if target.suffix != ".ssp":
        raise ValueError(f"path must be a .ssp file; got {shorten(str(path))}")
    xml_text("name", name)
    if not name:
        raise ValueError("name must be a non-empty str")
    description = xml_text("description", description if description is not None else
                           "plant and controller FMUs, outputs connected to the inputs of the "
                           "same name (written by flexsat.fmu)")
    if stop_time is not None:
        from .checks import positive_finite
        stop_time = positive_finite("stop_time", stop_time)
    for label, value in (("plant_fmu", plant_fmu), ("controller_fmu", controller_fmu)):
        if not isinstance(value, (str, os.PathLike)):
            raise TypeError(f"{label} must be a str or os.PathLike (an .fmu file); got "
                            f"{type(value).__name__} {shorten(value)}")
    components = []
    for role, fmu_path in (("plant", plant_fmu), ("controller", controller_fmu)):
        _, inputs, outputs = _interface(Path(fmu_path), role)
        components.append((role, f"resources/{role}.fmu", inputs, outputs))
    (_, _, plant_in, plant_out), (_, _, controller_in, controller_out) = components
    if not (set(plant_out) & set(controller_in)) or not (set(controller_out) & set(plant_in)):
        raise FMUBuildError(
            "the FMUs must be connected both ways by equal signal names; got plant outputs "
            f"{shorten(list(plant_out))}, controller inputs {shorten(list(controller_in))}, "
            f"controller outputs {shorten(list(controller_out))}, plant inputs "
            f"{shorten(list(plant_in))}")
    if set(plant_out) & set(controller_out):
        raise FMUBuildError(f"plant and controller both output "
                            f"{shorten(sorted(set(plant_out) & set(controller_out)))}; rename one "
                            "so every signal has one source")
    text = _ssd(name, description, components, stop_time)
    _validate_ssd(text)
    target.parent.mkdir(parents=True, exist_ok=True)

    def write_zip(handle) -> None:
        with zipfile.ZipFile(handle, "w", compression=zipfile.ZIP_DEFLATED) as archive:
            archive.writestr(SSD_NAME, text)
            for role, fmu_path in (("plant", plant_fmu), ("controller", controller_fmu)):
                archive.write(fmu_path, f"resources/{role}.fmu")

    return write_atomically(target, write_zip)


def cosimulate_ssp(ssp: str | os.PathLike, stop_time: float, step: float, *,
                   method: str = "gauss-seidel", inputs: Mapping[str, Signal] | None = None,
                   start_time: float = 0.0,
                   start_values: Mapping[str, Mapping[str, float]] | None = None) -> np.ndarray:
    """Co-simulate the two FMUs of an SSP file along its connections.

    Parameters
    ----------
    ssp : str or os.PathLike
        An SSP file with two Co-Simulation FMU components (as :func:`write_ssp` writes):
        the first is run as the plant, the second as the controller.
    stop_time, step, method, start_time
        As :func:`fmu.cosimulate`.
    inputs : mapping of str to signal, optional
        Values of the system's input connectors, by name (as :func:`fmu.cosimulate`).
    start_values : mapping of str to mapping of str to float, optional
        Start values by component name, then variable name.

    Returns
    -------
    numpy.ndarray
        As :func:`fmu.cosimulate`: ``time``, the plant's outputs, the controller's outputs
        and the system inputs.

    Raises
    ------
    CosimulationError
        If the SSP does not validate, does not hold two FMU components connected both
        ways, or an FMU call fails.
    FileNotFoundError, ValueError, TypeError
        For a missing file or bad arguments (as :func:`fmu.cosimulate`).
    """
    from fmpy.ssp.ssd import find_components, read_ssd

    if not isinstance(ssp, (str, os.PathLike)) or not Path(ssp).is_file():
        raise FileNotFoundError(f"ssp must be an existing .ssp file; got {shorten(str(ssp))}")
    if start_values is not None and not isinstance(start_values, Mapping):
        raise TypeError(f"start_values must be a mapping {{component: {{name: value}}}}; got "
                        f"{type(start_values).__name__} {shorten(start_values)}")
    n_steps = check_cosimulation_run(method, step, stop_time, start_time, inputs, ())
    try:
        structure = read_ssd(str(ssp), validate=True)
    except Exception as error:  # fmpy raises plain exceptions
        raise CosimulationError(f"the SSP {Path(ssp).name} cannot be read: "
                                f"{shorten(str(error), 300)}") from error
    components = find_components(structure.system)
    if len(components) != 2:
        raise CosimulationError(f"the SSP {Path(ssp).name} must hold two FMU components (plant "
                                f"and controller); got {len(components)}")
    folder = Path(tempfile.mkdtemp(prefix="flexsat-ssp-"))
    slaves: list[FMUSlave] = []
    try:
        with zipfile.ZipFile(ssp) as archive:
            for component in components:
                member = component.source
                if member not in archive.namelist():
                    raise CosimulationError(f"the SSP {Path(ssp).name} has no {member!r} (the "
                                            f"source of component {component.name!r})")
                # written under a name of ours: a source path never leaves the folder
                destination = folder / f"{len(slaves)}.fmu"
                destination.write_bytes(archive.read(member))
                slaves.append(FMUSlave(destination, component.name))
        plant, controller = slaves
        by_name = {slave.role: slave for slave in slaves}
        plant_to_controller, controller_to_plant = [], []
        external: dict[str, list[tuple[FMUSlave, str]]] = {}
        for connection in structure.system.connections:
            start, end = connection.startElement, connection.endElement
            if start in by_name and end in by_name:
                pairs = plant_to_controller if by_name[start] is plant else controller_to_plant
                pairs.append((connection.startConnector, connection.endConnector))
            elif start is None and end in by_name:
                external.setdefault(connection.startConnector, []).append(
                    (by_name[end], connection.endConnector))
        for pairs, source, sink in ((plant_to_controller, plant, controller),
                                    (controller_to_plant, controller, plant)):
            for output, input_name in pairs:
                if output not in source.outputs or input_name not in sink.inputs:
                    raise CosimulationError(
                        f"the SSP connects {source.role}.{output} to {sink.role}.{input_name}, "
                        "which are not an output and an input of those FMUs")
        if not plant_to_controller or not controller_to_plant:
            raise CosimulationError(f"the SSP {Path(ssp).name} must connect its two components "
                                    "both ways")
        values = start_values or {}
        return run_loop(plant, controller, plant_to_controller, controller_to_plant, external,
                        inputs, method=method, start_time=float(start_time), n_steps=n_steps,
                        step=step, plant_start_values=values.get(plant.role),
                        controller_start_values=values.get(controller.role))
    finally:
        for slave in slaves:
            slave.close()
        shutil.rmtree(folder, ignore_errors=True)
