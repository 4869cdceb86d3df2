"""Export of a python-control StateSpace as an FMI 2.0 FMU (Model Exchange + Co-Simulation).

The FMU holds ``modelDescription.xml``, the C sources under ``sources/`` (the fixed FMI API
layer and arithmetic from ``fmu/c``, the generated ``model.c`` with the matrices and
``flexsat_interfaces.h``) and one shared library under ``binaries/<platform>/`` compiled
at export time, serving the declared interfaces.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import uuid
import zipfile
from collections.abc import Mapping, Sequence
from pathlib import Path

import control
import numpy as np

from .build import SharedLibraryBuild, build_directory, platform_folder
from .checks import c_identifier, positive_finite, real_number, shorten, xml_text
from .codegen import (FMI2_HEADERS, INTERFACES_HEADER, TEMPLATE_HEADERS, TEMPLATE_SOURCES,
                      interfaces_header, model_c_source, template_dir)
from .description import model_description_xml
from .errors import FMUBuildError
from .files import write_atomically, write_text_atomically
from .limits import MAX_REFERENCE_SAMPLES, check_reference_cost, reference_cost
from .reference import write_reference_files
from .system import LinearModel, linear_model_from, zoh_matrices
from .verify import probe_input, verify_library

__all__ = ["export", "DEFAULT_STEP", "DEFAULT_STOP_TIME"]

#: Default communication step [s] when ``step`` is not given.
DEFAULT_STEP = 0.01
#: Default stop time of the DefaultExperiment and of the reference files [s].
DEFAULT_STOP_TIME = 10.0


def _sanitise_identifier(text: str) -> str:
    identifier = re.sub(r"[^A-Za-z0-9_]", "_", text)
    if not identifier or identifier[0].isdigit():
        identifier = "_" + identifier
    return identifier


def _guid(model: LinearModel, model_identifier: str, step: float,
          interfaces: tuple[str, ...]) -> str:
    """A GUID that changes whenever anything the binary depends on changes."""
    digest = hashlib.sha256()
    for array in (model.A, model.B, model.C, model.D, model.x0):
        digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
        digest.update(repr(array.shape).encode())
    names = (model_identifier, repr(step), *model.input_names, "|", *model.output_names, "|",
             *model.state_names, "|", repr(sorted((k, v or "") for k, v in model.units.items())))
    if interfaces != ("me", "cs"):  # the binary differs; GUIDs of both-interface FMUs stay
        names += ("|", *sorted(interfaces))
    digest.update("\x00".join(names).encode())
    return "{" + str(uuid.UUID(bytes=digest.digest()[:16], version=4)) + "}"


def _interfaces(value: object) -> tuple[str, ...]:
    if isinstance(value, str):
        value = (value,)
    try:
        interfaces = tuple(value)
    except TypeError:
        raise TypeError("interfaces must be 'me', 'cs' or a sequence of them; got "
                        f"{type(value).__name__} {shorten(value)}") from None
    if (not interfaces or any(not isinstance(i, str) or i not in ("me", "cs") for i in interfaces)
            or len(set(interfaces)) != len(interfaces)):
        raise ValueError("interfaces must be a non-empty selection of 'me' and 'cs'; got "
                         f"{shorten(interfaces)}")
    return tuple(i for i in ("me", "cs") if i in interfaces)


def export(system: control.StateSpace, path: str | os.PathLike, *,
           interfaces: Sequence[str] = ("me", "cs"), model_name: str | None = None,
           step: float | None = None, stop_time: float = DEFAULT_STOP_TIME,
           x0: Sequence[float] | np.ndarray | None = None,
           units: Mapping[str, str | None] | None = None, reference: bool = False,
           compiler: str | os.PathLike | None = None, description: str | None = None,
           max_reference_samples: float | None = None) -> Path:
    """Export a continuous-time StateSpace as an FMI 2.0 FMU.

    The FMU provides Model Exchange (derivatives ``A x + B u`` and outputs ``C x + D u``,
    outputs always computed from the current inputs, so direct feedthrough is never stale)
    and Co-Simulation, whose ``fmi2DoStep`` is exact for inputs held constant over the step
    (zero-order hold) for any step size: the transition matrices of the default step are
    computed here, those of any other step inside the FMU, both from the exponential of the
    augmented matrix (see :func:`fmu.system.zoh_matrices`). A stiff or lightly damped mode
    therefore never makes a step unstable.

    Every FMU is checked before this function returns (:mod:`fmu.verify`): its library
    exports exactly the FMI 2.0 functions of the declared interfaces, loads, instantiates
    and computes one derivative evaluation (Model Exchange) and one step (Co-Simulation)
    equal to this module's own. A build that fails the check raises FMUBuildError; no FMU
    file is written then.

    The FMU file is written all or nothing (a temporary file in the destination folder,
    created without following any symlink, then renamed over ``path``); the reference
    files likewise. Text files are UTF-8 whatever the locale.

    Compiling: the fixed C templates come from a persistent cache of object files, compiled
    once per machine and compiler (``$FLEXSAT_CACHE_DIR``, else ``$XDG_CACHE_HOME/flexsat``,
    else ``~/.cache/flexsat``; a temporary folder of the process if that cannot be
    written), written atomically under a lock shared by threads and processes and checked
    against a hash at every use (see :mod:`fmu.cache`). Each export compiles its
    ``model.c`` in a private build folder that is removed when it ends, also on an
    exception; folders of killed processes are removed later (see :mod:`fmu.build`).
    Exports may run concurrently in threads and processes.

    Parameters
    ----------
    system : control.StateSpace
        Continuous-time LTI system with named signals. Inputs, outputs and states become FMU
        variables of the same names (states are local variables, settable before
        initialisation, with start values ``x0``; their derivatives are ``der(<state>)``).
        At most :data:`fmu.limits.MAX_STATES` states and :data:`fmu.limits.MAX_SIGNALS`
        inputs plus outputs.
    path : str or os.PathLike
        The ``.fmu`` file to write, or an existing folder (the file is then
        ``<model_name>.fmu`` inside it). Missing parent folders are created.
    interfaces : str or sequence of {"me", "cs"}, default ("me", "cs")
        FMI interfaces to declare; the binary provides exactly these.
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
        ``_ref.opt`` next to the FMU (see :mod:`fmu.reference`). Their cost is estimated
        first: at most ``max_reference_samples`` samples (stop_time / step) and
        :data:`fmu.limits.MAX_REFERENCE_MEMORY` of memory.
    compiler : str or os.PathLike, optional
        C compiler to use; default ``$CC``, else gcc or cc on PATH.
    description : str, optional
        Text of the modelDescription's description attribute (any Unicode text that XML 1.0
        allows: no control characters other than tab, newline and carriage return).
    max_reference_samples : float, optional
        Raise (or lower) the limit on the samples of the reference files; default
        :data:`fmu.limits.MAX_REFERENCE_SAMPLES` (10^6).

    Returns
    -------
    pathlib.Path
        The FMU file written.

    Raises
    ------
    FMUBuildError
        If the system cannot be exported (not a StateSpace, discrete-time, non-finite
        matrices, illegal or duplicate signal names) or the binary cannot be built or fails
        its check (no C compiler, a compiler error). The message says what to do.
    ValueError
        For bad values of the keyword arguments, and for work beyond the limits of
        :mod:`fmu.limits`, estimated before any of it is done.
    TypeError
        For keyword arguments of the wrong type.

    Examples
    --------
    >>> import control
    >>> body = control.ss([[0, 1], [0, 0]], [[0], [0.01]], [[1, 0], [0, 1]], 0,
    ...                   inputs=["torque"], outputs=["theta", "omega"], states=["angle", "rate"])
    >>> export(body, "body.fmu")  # doctest: +SKIP
    PosixPath('body.fmu')
    """
    # ---- every argument checked before any work
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path must be a str or os.PathLike (a .fmu file or a folder); got "
                        f"{type(path).__name__} {shorten(path)}")
    interfaces = _interfaces(interfaces)
    if model_name is not None:
        c_identifier("model_name", model_name)
    step = DEFAULT_STEP if step is None else positive_finite("step", step)
    stop_time = positive_finite("stop_time", stop_time)
    if stop_time < step:
        raise ValueError(f"stop_time must be at least one step ({step!r} s) [s]; got {stop_time!r}")
    if not isinstance(reference, (bool, np.bool_)):
        raise TypeError(f"reference must be True or False; got {type(reference).__name__} "
                        f"{shorten(reference)}")
    if compiler is not None and not isinstance(compiler, (str, os.PathLike)):
        raise TypeError(f"compiler must be a str or os.PathLike (the C compiler); got "
                        f"{type(compiler).__name__} {shorten(compiler)}")
    if description is not None:
        xml_text("description", description)
    if max_reference_samples is None:
        max_reference_samples = MAX_REFERENCE_SAMPLES
    elif not real_number("max_reference_samples", max_reference_samples, "samples") >= 1:
        raise ValueError("max_reference_samples must be at least 1; got "
                         f"{shorten(max_reference_samples)}")

    model = linear_model_from(system, x0=x0, units=units)
    if reference:
        cost = reference_cost(model.n_states, model.n_inputs, model.n_outputs, step, stop_time)
        check_reference_cost(cost, step, stop_time, float(max_reference_samples))
    target = Path(path)
    if target.is_dir():
        identifier = model_name if model_name is not None else _sanitise_identifier(model.name or "model")
        target = target / f"{identifier}.fmu"
    else:
        if target.suffix != ".fmu":
            raise ValueError(f"path must be a .fmu file or an existing folder; got {shorten(str(path))}")
        identifier = model_name if model_name is not None else _sanitise_identifier(target.stem)
    c_identifier("model_name", identifier)
    if description is None:
        xml_text("system.name (part of the default description)", model.name)
        description = f"Continuous-time LTI system {model.name or identifier} exported by flexsat.fmu"

    guid = _guid(model, identifier, step, interfaces)
    folder, suffix = platform_folder()
    source_files = (*TEMPLATE_SOURCES, "model.c")

    with build_directory() as root:
        sources = root / "sources"
        sources.mkdir()
        objects = root / "objects"
        objects.mkdir()
        templates = template_dir()
        for name in (*TEMPLATE_SOURCES, *TEMPLATE_HEADERS):
            shutil.copyfile(templates / name, sources / name)
        for name in FMI2_HEADERS:
            shutil.copyfile(templates / "fmi2" / name, sources / name)
        shutil.copyfile(templates / "fmi2" / "LICENSE.txt", sources / "LICENSE_fmi2_headers.txt")
        (sources / INTERFACES_HEADER).write_text(interfaces_header(interfaces), encoding="utf-8")
        library = root / "binaries" / folder / f"{identifier}{suffix}"
        with SharedLibraryBuild(library, [sources], objects, compiler) as build:
            Phi, Gamma = zoh_matrices(model.A, model.B, step)
            if not (np.all(np.isfinite(Phi)) and np.all(np.isfinite(Gamma))):
                raise FMUBuildError(
                    f"the transition matrix expm(A*step) overflows for step = {step!r} s: the "
                    "system grows too fast over one step. Choose a smaller step.")
            (sources / "model.c").write_text(model_c_source(model, identifier, guid, step, Phi, Gamma),
                                             encoding="utf-8")
            build.compile(sources / "model.c")
            # the fixed templates come from the cache (compiled there, in parallel with
            # model.c, when missing)
            headers = [sources / h for h in (*TEMPLATE_HEADERS, *FMI2_HEADERS, INTERFACES_HEADER)]
            for name in TEMPLATE_SOURCES:
                build.compile_cached(sources / name, headers)
            (root / "modelDescription.xml").write_text(model_description_xml(
                model, model_identifier=identifier, guid=guid, interfaces=interfaces, step=step,
                stop_time=stop_time, source_files=source_files, description=description),
                encoding="utf-8")
            build.link()
            try:
                verify_library(library, probe_input(model, Phi, Gamma, step, interfaces, library,
                                                    guid), interfaces)
            except FMUBuildError:
                build.evict_cached()  # the next export compiles the templates afresh
                raise

        target.parent.mkdir(parents=True, exist_ok=True)
        files = sorted(f for f in root.rglob("*") if f.is_file() and objects not in f.parents)

        def write_zip(handle) -> None:
            with zipfile.ZipFile(handle, "w", compression=zipfile.ZIP_DEFLATED) as archive:
                for file in files:
                    archive.write(file, file.relative_to(root).as_posix())

        write_atomically(target, write_zip)

    if reference:
        write_reference_files(model, identifier, target.parent, step, stop_time)
    return target
