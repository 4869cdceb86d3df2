"""``modelDescription.xml`` of an exported LTI system (FMI 2.0), and what the FMI 3.0
writer (:mod:`fmu.description3`) shares with it.

Variables, in this order (the value reference of each is its position, counted from 0):
inputs, outputs, states, state derivatives ``der(<state>)`` (continuous time only).  The C
layer (``lti_instance.h``) uses the same layout.

ModelStructure declares the sparsity of the linear maps: output ``y_i`` depends on the states
``j`` with ``C[i, j] != 0`` and the inputs ``k`` with ``D[i, k] != 0``; derivative
``der(x_i)`` on the states with ``A[i, j] != 0`` and the inputs with ``B[i, k] != 0``; all
with ``dependenciesKind="constant"`` (a constant factor, the matrix entry).  A discrete-time
(sampled) system is a Co-Simulation FMU whose states and outputs are discrete variables; an
output depends (among the knowns, which exclude discrete states) on the inputs with
``D[i, k] != 0``, through the sample, so without a dependency kind (default "dependent").

Both interfaces declare ``canGetAndSetFMUstate``, ``canSerializeFMUstate`` and
``providesDirectionalDerivative``; states carry a ``nominal`` (:func:`fmu.system.state_nominals`).

References
----------
FMI 2.0.1 standard (Modelica Association, 2019), sections 2.2 (modelDescription.xml) and
2.2.8 (ModelStructure).
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

import numpy as np

from .codegen import c_double
from .system import LinearModel
from .units import SI_UNITS, derivative_unit

__all__ = ["model_description_xml", "value_references", "variable_units", "dependency_indices",
           "unit_definitions", "GENERATION_TOOL"]

GENERATION_TOOL = "flexsat.fmu"


def value_references(model: LinearModel) -> dict[str, int]:
    """Value reference of every variable name (inputs, outputs, states, derivatives of a
    continuous-time system)."""
    names = (list(model.input_names) + list(model.output_names) + list(model.state_names)
             + ([] if model.discrete else [f"der({s})" for s in model.state_names]))
    return {name: vr for vr, name in enumerate(names)}


def variable_units(model: LinearModel) -> dict[str, str | None]:
    """Unit of every variable, the derivatives' included (``der(x)`` in unit(x)/s)."""
    units = dict(model.units)
    if not model.discrete:
        for state in model.state_names:
            units[f"der({state})"] = derivative_unit(model.units.get(state))
    return units


def unit_definitions(units: list[str]) -> list[str]:
    """Lines of ``<UnitDefinitions>`` (the same in FMI 2.0 and 3.0) for the named units."""
    lines = ["  <UnitDefinitions>"]
    for unit in units:
        exponents = " ".join(f'{k}="{v}"' for k, v in SI_UNITS[unit].items())
        lines.append(f'    <Unit name="{unit}"><BaseUnit {exponents}/></Unit>')
    lines.append("  </UnitDefinitions>")
    return lines


def dependency_indices(row_states: np.ndarray | None, row_inputs: np.ndarray,
                       state_index0: int, input_index0: int) -> list[int]:
    """Indices (or value references) of the states and inputs with a nonzero entry, sorted.

    ``row_states`` None leaves the states out (discrete states are not knowns).
    """
    indices = [] if row_states is None else [state_index0 + j for j in np.flatnonzero(row_states)]
    indices += [input_index0 + k for k in np.flatnonzero(row_inputs)]
    return sorted(indices)


def _dependencies(row_states: np.ndarray | None, row_inputs: np.ndarray, state_index0: int,
                  input_index0: int, with_kind: bool) -> str:
    indices = dependency_indices(row_states, row_inputs, state_index0, input_index0)
    text = f' dependencies="{" ".join(str(i) for i in indices)}"'
    if with_kind:
        text += f' dependenciesKind="{" ".join("constant" for _ in indices)}"'
    return text


def model_description_xml(model: LinearModel, *, model_identifier: str, guid: str,
                          interfaces: tuple[str, ...], step: float, stop_time: float,
                          source_files: tuple[str, ...], description: str = "") -> str:
    """Text of ``modelDescription.xml``.

    Parameters
    ----------
    model : LinearModel
    model_identifier : str
        C identifier; also the name of the binary.
    guid : str
    interfaces : tuple of {"me", "cs"}
    step : float, s
        Default communication step (DefaultExperiment stepSize).
    stop_time : float, s
        DefaultExperiment stopTime.
    source_files : tuple of str
        The .c files under sources/ to compile (SourceFiles).
    description : str, optional

    Returns
    -------
    str
    """
    n, m, p = model.n_states, model.n_inputs, model.n_outputs
    units = variable_units(model)
    used_units = sorted({u for u in units.values() if u is not None})
    discrete = model.discrete
    variability = "discrete" if discrete else "continuous"

    files = "".join(f'      <File name="{f}"/>\n' for f in source_files)
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<fmiModelDescription fmiVersion="2.0" modelName={quoteattr(model_identifier)}'
             f' guid="{guid}" description={quoteattr(description)}'
             f' generationTool="{GENERATION_TOOL}" variableNamingConvention="structured"'
             ' numberOfEventIndicators="0">']
    if "me" in interfaces:
        lines.append(f'  <ModelExchange modelIdentifier="{model_identifier}"'
                     ' completedIntegratorStepNotNeeded="true" canGetAndSetFMUstate="true"'
                     ' canSerializeFMUstate="true" providesDirectionalDerivative="true">')
        lines.append(f"    <SourceFiles>\n{files}    </SourceFiles>")
        lines.append("  </ModelExchange>")
    if "cs" in interfaces:
        lines.append(f'  <CoSimulation modelIdentifier="{model_identifier}"'
                     ' canHandleVariableCommunicationStepSize="true" canInterpolateInputs="false"'
                     ' maxOutputDerivativeOrder="0" canRunAsynchronuously="false"'
                     ' canGetAndSetFMUstate="true" canSerializeFMUstate="true"'
                     ' providesDirectionalDerivative="true">')
        lines.append(f"    <SourceFiles>\n{files}    </SourceFiles>")
        lines.append("  </CoSimulation>")
    if used_units:
        lines += unit_definitions(used_units)
    lines.append("  <LogCategories>")
    lines.append('    <Category name="logStatusError" description="Errors (always logged)"/>')
    lines.append('    <Category name="logStatusWarning" description="Warnings"/>')
    lines.append("  </LogCategories>")
    lines.append(f'  <DefaultExperiment startTime="0.0" stopTime="{c_double(stop_time)}"'
                 f' stepSize="{c_double(step)}"/>')

    lines.append("  <ModelVariables>")

    def unit_attribute(name: str) -> str:
        unit = units.get(name)
        return f' unit="{unit}"' if unit is not None else ""

    index = 0
    for k, name in enumerate(model.input_names):
        lines.append(f'    <ScalarVariable name="{name}" valueReference="{index}"'
                     f' description="input {k + 1} of {m}" causality="input"'
                     f' variability="continuous">')
        lines.append(f'      <Real{unit_attribute(name)} start="0.0"/>')
        lines.append("    </ScalarVariable>")
        index += 1
    for i, name in enumerate(model.output_names):
        lines.append(f'    <ScalarVariable name="{name}" valueReference="{index}"'
                     f' description="output {i + 1} of {p}" causality="output"'
                     f' variability="{variability}" initial="calculated">')
        lines.append(f"      <Real{unit_attribute(name)}/>")
        lines.append("    </ScalarVariable>")
        index += 1
    for j, name in enumerate(model.state_names):
        lines.append(f'    <ScalarVariable name="{name}" valueReference="{index}"'
                     f' description="state {j + 1} of {n}" causality="local"'
                     f' variability="{variability}" initial="exact">')
        lines.append(f'      <Real{unit_attribute(name)} start="{c_double(model.x0[j])}"'
                     f' nominal="{c_double(model.nominals[j])}"/>')
        lines.append("    </ScalarVariable>")
        index += 1
    first_state = m + p + 1  # 1-based ScalarVariable index of the first state
    for j, name in enumerate(model.state_names if not discrete else ()):
        derivative = f"der({name})"
        lines.append(f'    <ScalarVariable name="{derivative}" valueReference="{index}"'
                     f' description="time derivative of state {j + 1}" causality="local"'
                     f' variability="continuous" initial="calculated">')
        lines.append(f'      <Real{unit_attribute(derivative)} derivative="{first_state + j}"/>')
        lines.append("    </ScalarVariable>")
        index += 1
    lines.append("  </ModelVariables>")

    # ModelStructure, indices are 1-based ScalarVariable positions
    first_input, first_output, first_derivative = 1, m + 1, m + p + n + 1
    output_rows = [(first_output + i, model.C[i], model.D[i]) for i in range(p)]
    derivative_rows = [] if discrete else [(first_derivative + j, model.A[j], model.B[j])
                                           for j in range(n)]
    lines.append("  <ModelStructure>")
    if output_rows:
        lines.append("    <Outputs>")
        for idx, c_row, d_row in output_rows:
            # knowns are inputs and continuous states: a sampled output depends on the
            # inputs through the sample (kind "dependent", the default)
            deps = _dependencies(None if discrete else c_row, d_row, first_state, first_input,
                                 with_kind=not discrete)
            lines.append(f'      <Unknown index="{idx}"{deps}/>')
        lines.append("    </Outputs>")
    if derivative_rows:
        lines.append("    <Derivatives>")
        for idx, a_row, b_row in derivative_rows:
            deps = _dependencies(a_row, b_row, first_state, first_input, with_kind=True)
            lines.append(f'      <Unknown index="{idx}"{deps}/>')
        lines.append("    </Derivatives>")
    if output_rows or derivative_rows:
        # during initialisation the states' start values and the inputs are the knowns
        lines.append("    <InitialUnknowns>")
        for idx, row_x, row_u in sorted(output_rows + derivative_rows, key=lambda r: r[0]):
            deps = _dependencies(row_x, row_u, first_state, first_input, with_kind=False)
            lines.append(f'      <Unknown index="{idx}"{deps}/>')
        lines.append("    </InitialUnknowns>")
    lines.append("  </ModelStructure>")
    lines.append("</fmiModelDescription>")
    return "\n".join(lines) + "\n"
