"""Export of a python-control StateSpace as an FMI 2.0 FMU (Model Exchange + Co-Simulation).

The FMU holds ``modelDescription.xml``, the C sources under ``sources/`` (the fixed FMI API
layer and arithmetic from ``fmu/c`` plus a generated ``model.c`` with the matrices) and one
shared library under ``binaries/<platform>/`` compiled at export time, serving both
interfaces.
"""

from __future__ import annotations

import hashlib
import math
import os
import re
import shutil
import tempfile
import uuid
import zipfile
from collections.abc import Mapping, Sequence
from pathlib import Path

import control
import numpy as np

from .build import SharedLibraryBuild, platform_folder
from .codegen import FMI2_HEADERS, TEMPLATE_HEADERS, TEMPLATE_SOURCES, model_c_source, template_dir
from .description import model_description_xml
from .errors import FMUBuildError
from .reference import write_reference_files
from .system import LinearModel, linear_model_from, zoh_matrices

__all__ = ["export", "DEFAULT_STEP", "DEFAULT_STOP_TIME"]

#: Default communication step [s] when ``step`` is not given.
DEFAULT_STEP = 0.01
#: Default stop time of the DefaultExperiment and of the reference files [s].
DEFAULT_STOP_TIME = 10.0

_C_IDENTIFIER = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def _positive_finite(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise TypeError(f"{name} must be a real number [s]; got {type(value).__name__}")
    number = float(value)
    if not (math.isfinite(number) and number > 0.0):
        raise ValueError(f"{name} must be positive and finite [s]; got {number!r}")
    return number


def _sanitise_identifier(text: str) -> str:
    identifier = re.sub(r"[^A-Za-z0-9_]", "_", text)
    if not identifier or identifier[0].isdigit():
        identifier = "_" + identifier
    return identifier


def _guid(model: LinearModel, model_identifier: str, step: float) -> str:
    """A GUID that changes whenever anything the binary depends on changes."""
    digest = hashlib.sha256()
    for array in (model.A, model.B, model.C, model.D, model.x0):
        digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
        digest.update(repr(array.shape).encode())
    names = (model_identifier, repr(step), *model.input_names, "|", *model.output_names, "|",
             *model.state_names, "|", repr(sorted((k, v or "") for k, v in model.units.items())))
    digest.update("\x00".join(names).encode())
    return "{" + str(uuid.UUID(bytes=digest.digest()[:16], version=4)) + "}"


def export(system: control.StateSpace, path: str | os.PathLike, *,
           interfaces: Sequence[str] = ("me", "cs"), model_name: str | None = None,
           step: float | None = None, stop_time: float = DEFAULT_STOP_TIME,
           x0: Sequence[float] | np.ndarray | None = None,
           units: Mapping[str, str | None] | None = None, reference: bool = False,
           compiler: str | None = None, description: str | None = None) -> Path:
    """Export a continuous-time StateSpace as an FMI 2.0 FMU.

    The FMU provides Model Exchange (derivatives ``A x + B u`` and outputs ``C x + D u``,
    outputs always computed from the current inputs, so direct feedthrough is never stale)
    and Co-Simulation, whose ``fmi2DoStep`` is exact for inputs held constant over the step
    (zero-order hold) for any step size: the transition matrices of the default step are
    computed here, those of any other step inside the FMU, both from the exponential of the
    augmented matrix (see :func:`fmu.system.zoh_matrices`). A stiff or lightly damped mode
    therefore never makes a step unstable.

    Parameters
    ----------
    system : control.StateSpace
        Continuous-time LTI system with named signals. Inputs, outputs and states become FMU
        variables of the same names (states are local variables, settable before
        initialisation, with start values ``x0``; their derivatives are ``der(<state>)``).
    path : str or os.PathLike
        The ``.fmu`` file to write, or an existing folder (the file is then
        ``<model_name>.fmu`` inside it). Missing parent folders are created.
    interfaces : sequence of {"me", "cs"}, default ("me", "cs")
        FMI interfaces to declare; one binary serves both.
    model_name : str, optional
        modelName and modelIdentifier (a C identifier). Default: the file name's stem, or
        the system's name when ``path`` is a folder, with illegal characters replaced by "_".
    step : float, optional, s
        Default communication step (DefaultExperiment stepSize) whose transition matrices
        are precomputed. Default :data:`DEFAULT_STEP` (0.01 s).
    stop_time : float, default 10.0, s
        DefaultExperiment stopTime, also the length of the reference files.
    x0 : array_like of float, shape (n_states,), optional
        Initial state (start values), in the states' units; zeros by default.
    units : mapping of str to str or None, optional
        Units by signal name, overriding the guess from the names (``theta``/``phi`` -> rad,
        ``omega`` -> rad/s, ``torque``/``M`` -> N.m, ``F_y``/``force`` -> N,
        ``delta``/``deflection`` -> m; see :func:`fmu.units.guess_unit`). None removes a unit.
    reference : bool, default False
        Also write FMI cross-check files ``<model_name>_in.csv``, ``_ref.csv`` and
        ``_ref.opt`` next to the FMU (see :mod:`fmu.reference`).
    compiler : str, optional
        C compiler to use; default ``$CC``, else gcc or cc on PATH. The fixed C templates
        are compiled once per process and reused; each export compiles its ``model.c``.
    description : str, optional
        Text of the modelDescription's description attribute.

    Returns
    -------
    pathlib.Path
        The FMU file written.

    Raises
    ------
    FMUBuildError
        If the system cannot be exported (not a StateSpace, discrete-time, non-finite
        matrices, illegal or duplicate signal names) or the binary cannot be built (no C
        compiler). The message says what to do.
    ValueError, TypeError
        For bad keyword arguments (step, stop_time, interfaces, model_name, x0, units).

    Examples
    --------
    >>> import control
    >>> body = control.ss([[0, 1], [0, 0]], [[0], [0.01]], [[1, 0], [0, 1]], 0,
    ...                   inputs=["torque"], outputs=["theta", "omega"], states=["angle", "rate"])
    >>> export(body, "body.fmu")  # doctest: +SKIP
    PosixPath('body.fmu')
    """
    if isinstance(interfaces, str):
        interfaces = (interfaces,)
    interfaces = tuple(interfaces)
    if not interfaces or any(i not in ("me", "cs") for i in interfaces) or len(set(interfaces)) != len(interfaces):
        raise ValueError(f"interfaces must be a non-empty selection of 'me' and 'cs'; got {interfaces!r}")
    step = DEFAULT_STEP if step is None else _positive_finite("step", step)
    stop_time = _positive_finite("stop_time", stop_time)
    if stop_time < step:
        raise ValueError(f"stop_time must be at least one step ({step!r} s) [s]; got {stop_time!r}")

    model = linear_model_from(system, x0=x0, units=units)

    target = Path(path)
    if target.is_dir():
        identifier = model_name if model_name is not None else _sanitise_identifier(model.name or "model")
        target = target / f"{identifier}.fmu"
    else:
        if target.suffix != ".fmu":
            raise ValueError(f"path must be a .fmu file or an existing folder; got {str(path)!r}")
        identifier = model_name if model_name is not None else _sanitise_identifier(target.stem)
    if not isinstance(identifier, str) or not _C_IDENTIFIER.match(identifier):
        raise ValueError("model_name must be a C identifier (letters, digits, '_', not starting "
                         f"with a digit); got {identifier!r}")

    guid = _guid(model, identifier, step)
    folder, suffix = platform_folder()
    source_files = (*TEMPLATE_SOURCES, "model.c")

    with tempfile.TemporaryDirectory(prefix="flexsat-fmu-") as build_dir:
        root = Path(build_dir)
        sources = root / "sources"
        sources.mkdir()
        templates = template_dir()
        for name in (*TEMPLATE_SOURCES, *TEMPLATE_HEADERS):
            shutil.copyfile(templates / name, sources / name)
        for name in FMI2_HEADERS:
            shutil.copyfile(templates / "fmi2" / name, sources / name)
        shutil.copyfile(templates / "fmi2" / "LICENSE.txt", sources / "LICENSE_fmi2_headers.txt")
        with SharedLibraryBuild(root / "binaries" / folder / f"{identifier}{suffix}", [sources],
                                compiler) as build:
            # the fixed templates compile while the matrices are computed and written
            headers = [sources / h for h in (*TEMPLATE_HEADERS, *FMI2_HEADERS)]
            for name in TEMPLATE_SOURCES:
                build.compile_cached(sources / name, headers)
            Phi, Gamma = zoh_matrices(model.A, model.B, step)
            if not (np.all(np.isfinite(Phi)) and np.all(np.isfinite(Gamma))):
                raise FMUBuildError(
                    f"the transition matrix expm(A*step) overflows for step = {step!r} s: the "
                    "system grows too fast over one step. Choose a smaller step.")
            (sources / "model.c").write_text(model_c_source(model, identifier, guid, step, Phi, Gamma))
            build.compile(sources / "model.c")
            (root / "modelDescription.xml").write_text(model_description_xml(
                model, model_identifier=identifier, guid=guid, interfaces=interfaces, step=step,
                stop_time=stop_time, source_files=source_files,
                description=description if description is not None else
                f"Continuous-time LTI system {model.name or identifier} exported by flexsat.fmu"))
            build.link()

        target.parent.mkdir(parents=True, exist_ok=True)
        partial = target.with_name(target.name + ".partial")
        with zipfile.ZipFile(partial, "w", compression=zipfile.ZIP_DEFLATED) as archive:
            for file in sorted(root.rglob("*")):
                if file.is_file():
                    archive.write(file, file.relative_to(root).as_posix())
        os.replace(partial, target)

    if reference:
        write_reference_files(model, identifier, target.parent, step, stop_time)
    return target
