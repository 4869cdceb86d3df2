"""``modelDescription.xml`` of an exported LTI system (FMI 3.0).

The same variables, value references and sparsity as the FMI 2.0 description
(:mod:`fmu.description`), written with the FMI 3.0 schema: ``Float64`` variables,
dependencies by value reference, the independent variable ``time`` (value reference after
the derivatives), and ``ContinuousStateDerivative`` / ``InitialUnknown`` elements.

A discrete-time (sampled) system is a Co-Simulation FMU with one clocked partition: a
periodic time-based input ``Clock`` named :data:`CLOCK_NAME` (``intervalVariability=
"constant"``, ``intervalDecimal`` = T, first tick at the start time) and outputs clocked by
it; the states are discrete local variables updated at its ticks (see ``fmi3Functions.c``
for the importer's side).

References
----------
FMI 3.0.2 standard (Modelica Association, 2024), sections 2.4 (modelDescription.xml),
2.4.8 (ModelStructure), 2.2.10 (clocks) and 4.4 (Co-Simulation attributes).
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

from .codegen import c_double
from .description import GENERATION_TOOL, dependency_indices, unit_definitions, variable_units
from .system import LinearModel

__all__ = ["model_description3_xml", "TIME_NAME", "CLOCK_NAME", "RESERVED_NAMES"]

#: Name of the independent variable.
TIME_NAME = "time"
#: Name of the sample clock of a discrete-time system.
CLOCK_NAME = "sample_clock"
#: Variable names that an FMI 3.0 export uses itself.
RESERVED_NAMES = (TIME_NAME, CLOCK_NAME)


def _join(values: list[int]) -> str:
    return " ".join(str(v) for v in values)


def model_description3_xml(model: LinearModel, *, model_identifier: str, guid: str,
                           interfaces: tuple[str, ...], step: float, stop_time: float,
                           description: str = "") -> str:
    """Text of ``modelDescription.xml`` (FMI 3.0).

    Parameters
    ----------
    model : LinearModel
    model_identifier : str
        C identifier; also the name of the binary.
    guid : str
        The instantiationToken.
    interfaces : tuple of {"me", "cs"}
        ("cs",) only for a discrete-time system.
    step : float, s
        Default communication step (DefaultExperiment stepSize).
    stop_time : float, s
        DefaultExperiment stopTime.
    description : str, optional

    Returns
    -------
    str
    """
    n, m, p = model.n_states, model.n_inputs, model.n_outputs
    discrete = model.discrete
    units = variable_units(model)
    units[TIME_NAME] = "s"
    used_units = sorted({u for u in units.values() if u is not None})
    first_output, first_state, first_derivative = m, m + p, m + p + n
    time_vr = m + p + n + (0 if discrete else n)
    clock_vr = time_vr + 1

    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             f'<fmiModelDescription fmiVersion="3.0" modelName={quoteattr(model_identifier)}'
             f' instantiationToken="{guid}" description={quoteattr(description)}'
             f' generationTool="{GENERATION_TOOL}" variableNamingConvention="structured">']
    capabilities = (' canGetAndSetFMUState="true" canSerializeFMUState="true"'
                    ' providesDirectionalDerivatives="true" providesAdjointDerivatives="true"')
    if "me" in interfaces:
        lines.append(f'  <ModelExchange modelIdentifier="{model_identifier}"{capabilities}'
                     ' needsCompletedIntegratorStep="false"/>')
    if "cs" in interfaces:
        sampled = (f' hasEventMode="true" fixedInternalStepSize="{c_double(model.sample_period)}"'
                   if discrete else ' hasEventMode="false"')
        lines.append(f'  <CoSimulation modelIdentifier="{model_identifier}"{capabilities}'
                     f' canHandleVariableCommunicationStepSize="true"{sampled}/>')
    lines += unit_definitions(used_units)  # never empty: the time is in s
    lines.append("  <LogCategories>")
    lines.append('    <Category name="logStatusError" description="Errors"/>')
    lines.append('    <Category name="logStatusWarning" description="Warnings"/>')
    lines.append("  </LogCategories>")
    lines.append(f'  <DefaultExperiment startTime="0.0" stopTime="{c_double(stop_time)}"'
                 f' stepSize="{c_double(step)}"/>')

    def unit_attribute(name: str) -> str:
        unit = units.get(name)
        return f' unit="{unit}"' if unit is not None else ""

    lines.append("  <ModelVariables>")
    lines.append(f'    <Float64 name="{TIME_NAME}" valueReference="{time_vr}"'
                 ' causality="independent" variability="continuous" unit="s"'
                 ' description="Simulation time"/>')
    clocked = ""
    if discrete:
        lines.append(f'    <Clock name="{CLOCK_NAME}" valueReference="{clock_vr}"'
                     ' causality="input" intervalVariability="constant"'
                     f' intervalDecimal="{c_double(model.sample_period)}"'
                     f' description="Samples every {c_double(model.sample_period)} s from the'
                     ' start time"/>')
        clocked = f' clocks="{clock_vr}"'
    for k, name in enumerate(model.input_names):
        lines.append(f'    <Float64 name="{name}" valueReference="{k}"'
                     f' description="input {k + 1} of {m}" causality="input"'
                     f' variability="continuous"{unit_attribute(name)} start="0.0"/>')
    variability = "discrete" if discrete else "continuous"
    for i, name in enumerate(model.output_names):
        lines.append(f'    <Float64 name="{name}" valueReference="{first_output + i}"'
                     f' description="output {i + 1} of {p}" causality="output"'
                     f' variability="{variability}"{clocked} initial="calculated"'
                     f'{unit_attribute(name)}/>')
    for j, name in enumerate(model.state_names):
        lines.append(f'    <Float64 name="{name}" valueReference="{first_state + j}"'
                     f' description="state {j + 1} of {n}" causality="local"'
                     f' variability="{variability}" initial="exact"{unit_attribute(name)}'
                     f' start="{c_double(model.x0[j])}" nominal="{c_double(model.nominals[j])}"/>')
    if not discrete:
        for j, name in enumerate(model.state_names):
            derivative = f"der({name})"
            lines.append(f'    <Float64 name="{derivative}" valueReference="{first_derivative + j}"'
                         f' description="time derivative of state {j + 1}" causality="local"'
                         f' variability="continuous" initial="calculated"'
                         f'{unit_attribute(derivative)} derivative="{first_state + j}"/>')
    lines.append("  </ModelVariables>")

    lines.append("  <ModelStructure>")
    initial_unknowns = []
    for i in range(p):
        if discrete:
            # a clocked output: computed at the clock's ticks from the inputs it feeds through
            deps = [clock_vr] + dependency_indices(None, model.D[i], first_state, 0)
            lines.append(f'    <Output valueReference="{first_output + i}"'
                         f' dependencies="{_join(sorted(deps))}"/>')
            continue
        deps = dependency_indices(model.C[i], model.D[i], first_state, 0)
        lines.append(f'    <Output valueReference="{first_output + i}" dependencies="{_join(deps)}"'
                     f' dependenciesKind="{" ".join("constant" for _ in deps)}"/>')
        initial_unknowns.append((first_output + i, deps))
    if not discrete:
        for j in range(n):
            deps = dependency_indices(model.A[j], model.B[j], first_state, 0)
            lines.append(f'    <ContinuousStateDerivative valueReference="{first_derivative + j}"'
                         f' dependencies="{_join(deps)}"'
                         f' dependenciesKind="{" ".join("constant" for _ in deps)}"/>')
            initial_unknowns.append((first_derivative + j, deps))
    # during initialisation the states' start values and the inputs are the knowns
    for vr, deps in sorted(initial_unknowns):
        lines.append(f'    <InitialUnknown valueReference="{vr}" dependencies="{_join(deps)}"/>')
    lines.append("  </ModelStructure>")
    lines.append("</fmiModelDescription>")
    return "\n".join(lines) + "\n"
