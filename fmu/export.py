"""Export of a python-control StateSpace as an FMI 2.0 or FMI 3.0 FMU.

The FMU holds ``modelDescription.xml``, the C sources under ``sources/`` (the fixed FMI API
layer of its version, ``lti_instance.c`` and ``linear_model.c`` from ``fmu/c``, the
generated ``model.c`` with the matrices and ``flexsat_interfaces.h``, and
``buildDescription.xml``), one shared library under ``binaries/<platform>/`` compiled at
export time (left out with ``sources_only=True``), ``documentation/`` and an icon.  Both
versions share the model code; they differ only in the API layer and the modelDescription
writer (:mod:`fmu.description`, :mod:`fmu.description3`).
"""

from __future__ import annotations

import dataclasses
import errno
import hashlib
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

from .build import SharedLibraryBuild, build_directory, platform_folder
from .cache import cache_root
from .build_description import build_description_xml
from .checks import c_identifier, positive_finite, real_number, shorten, xml_text
from .codegen import (FMI_VERSIONS, INTERFACES_HEADER, TEMPLATE_HEADERS, header_folder,
                      interfaces_header, model_c_source, standard_headers, template_dir,
                      template_sources)
from .description import model_description_xml
from .description3 import RESERVED_NAMES, model_description3_xml
from .documentation import documentation_html, icon_png, licence_text
from .errors import FMUBuildError
from .files import write_atomically
from .limits import MAX_REFERENCE_SAMPLES, check_length, check_reference_cost, reference_cost
from .reference import write_reference_files
from .system import LinearModel, linear_model_from, state_nominals, zoh_matrices
from .verify import probe_input, verify_library

__all__ = ["export", "DEFAULT_STEP", "DEFAULT_STOP_TIME", "FMI_VERSIONS"]

#: Default communication step [s] of a continuous-time system when ``step`` is not given
#: (a sampled system's default step is its sample period).
DEFAULT_STEP = 0.01
#: Default stop time of the DefaultExperiment and of the reference files [s].
DEFAULT_STOP_TIME = 10.0


def _sanitise_identifier(text: str) -> str:
    identifier = re.sub(r"[^A-Za-z0-9_]", "_", text)
    if not identifier or identifier[0].isdigit():
        identifier = "_" + identifier
    return identifier


def _guid(model: LinearModel, model_identifier: str, step: float,
          interfaces: tuple[str, ...], fmi_version: str) -> str:
    """A GUID that changes whenever anything the binary depends on changes."""
    digest = hashlib.sha256()
    for array in (model.A, model.B, model.C, model.D, model.x0, model.nominals):
        digest.update(np.ascontiguousarray(array, dtype=np.float64).tobytes())
        digest.update(repr(array.shape).encode())
    names = (model_identifier, repr(step), *model.input_names, "|", *model.output_names, "|",
             *model.state_names, "|", repr(sorted((k, v or "") for k, v in model.units.items())),
             "|", repr(model.sample_period), "|", fmi_version)
    if interfaces != ("me", "cs"):
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


def _flag(name: str, value: object) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False; got {type(value).__name__} "
                        f"{shorten(value)}")
    return bool(value)


def export(system: control.StateSpace, path: str | os.PathLike, *,
           fmi_version: str = "2.0", interfaces: Sequence[str] | None = None,
           model_name: str | None = None, step: float | None = None,
           stop_time: float = DEFAULT_STOP_TIME,
           x0: Sequence[float] | np.ndarray | None = None,
           units: Mapping[str, str | None] | None = None,
           nominals: Sequence[float] | np.ndarray | None = None, reference: bool = False,
           compiler: str | os.PathLike | None = None, description: str | None = None,
           max_reference_samples: float | None = None, sources_only: bool = False) -> Path:
    """Export a StateSpace as an FMI 2.0 or FMI 3.0 FMU.

    A continuous-time system (``dt = 0``) gives Model Exchange (derivatives ``A x + B u``
    and outputs ``C x + D u``, outputs always computed from the current inputs, so direct
    feedthrough is never stale) and Co-Simulation, whose step is exact for inputs held
    constant over the step (zero-order hold) for any step size: the transition matrices of
    the default step are computed here, those of any other step inside the FMU, both from
    the exponential of the augmented matrix (see :func:`fmu.system.zoh_matrices`). A stiff
    or lightly damped mode therefore never makes a step unstable.

    A discrete-time system (python-control ``dt = T > 0``, e.g. a digital controller) gives
    a Co-Simulation FMU that samples every T from the start time whatever the master's
    step, holding its outputs between samples (FMI 3.0: a clocked partition of a periodic
    input Clock; see ``fmu/c/lti_instance.h`` and :mod:`fmu.description3`).

    Both versions declare FMU states (get, set, free, serialise, deserialise: restoring a
    state and stepping again is bit-identical) and directional derivatives (FMI 3.0 also
    adjoint derivatives) from A, B, C, D; states carry nominals from the model's scaling
    (:func:`fmu.system.state_nominals`) unless ``nominals`` gives them; the FMU contains
    ``documentation/index.html`` and an icon. The binary needs no glibc newer than 2.17.

    Every FMU is checked before this function returns (:mod:`fmu.verify`): its library
    exports exactly the FMI functions of its version and interfaces, needs no newer glibc,
    loads, instantiates and computes one derivative evaluation (Model Exchange) and one
    step (Co-Simulation) equal to this module's own, its partial derivatives and FMU
    states work. A build that fails the check raises FMUBuildError; no FMU file is written
    then. With ``sources_only=True`` the binary is built and checked all the same, and
    left out of the FMU.

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
        LTI system with named signals, continuous-time or discrete-time with a sample
        period. Inputs, outputs and states become FMU variables of the same names (states
        are local variables, settable before initialisation, with start values ``x0``; the
        derivatives of continuous states are ``der(<state>)``). FMI 3.0 adds ``time`` (and
        ``sample_clock`` for a sampled system): signals must not have these names. At most
        :data:`fmu.limits.MAX_STATES` states and :data:`fmu.limits.MAX_SIGNALS` inputs plus
        outputs.
    path : str or os.PathLike
        The ``.fmu`` file to write, or an existing folder (the file is then
        ``<model_name>.fmu`` inside it). Missing parent folders are created.
    fmi_version : {"2.0", "3.0"}, default "2.0"
        FMI version of the FMU.
    interfaces : str or sequence of {"me", "cs"}, optional
        FMI interfaces to declare; default both for a continuous-time system, "cs" (the
        only one) for a sampled one. An FMI 2.0 binary provides exactly these; an FMI 3.0
        binary defines every function and refuses those of other interfaces.
    model_name : str, optional
        modelName and modelIdentifier (a C identifier of at most
        :data:`fmu.limits.MAX_MODEL_NAME_LENGTH` = 200 characters). Default: the file name's
        stem, or the system's name when ``path`` is a folder, with illegal characters
        replaced by "_".
    step : float, optional, s
        Default communication step (DefaultExperiment stepSize) whose transition matrices
        are precomputed. Default :data:`DEFAULT_STEP` (0.01 s), or the sample period of a
        sampled system.
    stop_time : float, default 10.0, s
        DefaultExperiment stopTime, also the length of the reference files.
    x0 : array_like of float, shape (n_states,), optional
        Initial state (start values), in the states' units; zeros by default.
    units : mapping of str to str or None, optional
        Units by signal name, overriding the guess from the names (``theta``/``phi`` -> rad,
        ``omega`` -> rad/s, ``torque``/``M`` -> N.m, ``F_y``/``force`` -> N,
        ``delta``/``deflection`` -> m; see :func:`fmu.units.guess_unit`). None removes a unit.
    nominals : array_like of float, shape (n_states,), optional
        Positive nominal magnitude of each state, in its unit; default from the model's
        scaling (:func:`fmu.system.state_nominals`).
    reference : bool, default False
        Also write FMI cross-check files ``<model_name>_in.csv``, ``_ref.csv`` and
        ``_ref.opt`` next to the FMU (see :mod:`fmu.reference`). Their cost is estimated
        first: at most ``max_reference_samples`` samples (stop_time / step) and
        :data:`fmu.limits.MAX_REFERENCE_MEMORY` of memory (for a sampled system the samples
        of the model count too, if more).
    compiler : str or os.PathLike, optional
        C compiler to use; default ``$CC``, else gcc or cc on PATH.
    description : str, optional
        Text of the modelDescription's description attribute (any Unicode text that XML 1.0
        allows: no control characters other than tab, newline and carriage return), at most
        :data:`fmu.limits.MAX_DESCRIPTION_LENGTH` (4096) characters.
    max_reference_samples : float, optional
        Raise (or lower) the limit on the samples of the reference files; default
        :data:`fmu.limits.MAX_REFERENCE_SAMPLES` (10^6).
    sources_only : bool, default False
        Ship no binary: only the C sources and ``sources/buildDescription.xml``, which any
        importer can compile (the binary is still built and checked here first).

    Returns
    -------
    pathlib.Path
        The FMU file written.

    Raises
    ------
    FMUBuildError
        If the system cannot be exported (not a StateSpace, discrete-time without a sample
        period, non-finite matrices, illegal, duplicate or reserved signal names) or the
        binary cannot be built or fails its check (no C compiler, a compiler error). The
        message says what to do.
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
    if not isinstance(fmi_version, str):
        raise TypeError(f"fmi_version must be a str, \"2.0\" or \"3.0\"; got "
                        f"{type(fmi_version).__name__} {shorten(fmi_version)}")
    if fmi_version not in FMI_VERSIONS:
        raise ValueError(f"fmi_version must be \"2.0\" or \"3.0\"; got {shorten(fmi_version)}")
    if interfaces is not None:
        interfaces = _interfaces(interfaces)
    sources_only = _flag("sources_only", sources_only)
    if model_name is not None:
        check_length("model_name", c_identifier("model_name", model_name),
                     "MAX_MODEL_NAME_LENGTH")
    if step is not None:
        step = positive_finite("step", step)
    stop_time = positive_finite("stop_time", stop_time)
    reference = _flag("reference", reference)
    if compiler is not None and not isinstance(compiler, (str, os.PathLike)):
        raise TypeError(f"compiler must be a str or os.PathLike (the C compiler); got "
                        f"{type(compiler).__name__} {shorten(compiler)}")
    if description is not None:
        check_length("description", xml_text("description", description),
                     "MAX_DESCRIPTION_LENGTH")
    if max_reference_samples is None:
        max_reference_samples = MAX_REFERENCE_SAMPLES
    elif not real_number("max_reference_samples", max_reference_samples, "samples") >= 1:
        raise ValueError("max_reference_samples must be at least 1; got "
                         f"{shorten(max_reference_samples)}")

    model = linear_model_from(system, x0=x0, units=units, nominals=nominals)
    if interfaces is None:
        interfaces = ("cs",) if model.discrete else ("me", "cs")
    elif model.discrete and "me" in interfaces:
        raise ValueError(f"interfaces must be 'cs' for a discrete-time system (sampled every "
                         f"{model.sample_period!r} s: Co-Simulation only); got {shorten(interfaces)}")
    if step is None:
        step = model.sample_period if model.discrete else DEFAULT_STEP
    if stop_time < step:
        raise ValueError(f"stop_time must be at least one step ({step!r} s) [s]; got {stop_time!r}")
    if fmi_version == "3.0":
        for name in (*model.input_names, *model.output_names, *model.state_names):
            if name in RESERVED_NAMES:
                raise FMUBuildError(
                    f"signal name {name!r} is used by the FMI 3.0 FMU itself (its variables "
                    f"{' and '.join(RESERVED_NAMES)}); rename the signal in the StateSpace.")
    if reference:
        # a sampled system is simulated on its own sample grid: the finer grid counts
        grid = min(step, model.sample_period) if model.discrete else step
        cost = reference_cost(model.n_states, model.n_inputs, model.n_outputs, grid, stop_time)
        check_reference_cost(cost, step, stop_time, float(max_reference_samples))
    if model.nominals is None:
        model = dataclasses.replace(model, nominals=state_nominals(model, stop_time))
    target = Path(path)
    if target.is_dir():
        identifier = model_name if model_name is not None else _sanitise_identifier(model.name or "model")
        target = target / f"{identifier}.fmu"
    else:
        if target.suffix != ".fmu":
            raise ValueError(f"path must be a .fmu file or an existing folder; got {shorten(str(path))}")
        identifier = model_name if model_name is not None else _sanitise_identifier(target.stem)
    check_length("model_name", c_identifier("model_name", identifier), "MAX_MODEL_NAME_LENGTH")
    if description is None:
        xml_text("system.name (part of the default description)", model.name)
        kind = (f"Discrete-time LTI system (sampled every {model.sample_period!r} s)"
                if model.discrete else "Continuous-time LTI system")
        description = f"{kind} {model.name or identifier} exported by flexsat.fmu"
        check_length("the default description (it quotes system.name)", description,
                     "MAX_DESCRIPTION_LENGTH")

    guid = _guid(model, identifier, step, interfaces, fmi_version)
    folder, suffix = platform_folder(fmi_version)
    templates_c = template_sources(fmi_version)
    source_files = (*templates_c, "model.c")

    try:
        _build_and_write(model, target, identifier, guid, folder, suffix, templates_c,
                         source_files, fmi_version, interfaces, step, stop_time, description,
                         sources_only, compiler)
    except OSError as error:
        raise _where_the_disk_failed(error, target) from error
    if reference:
        write_reference_files(model, identifier, target.parent, step, stop_time)
    return target


#: errno values of an OSError that the machine causes (no space, no permission, read-only).
_ENVIRONMENT_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES,
                                 errno.EPERM, errno.EIO, errno.EMFILE, errno.ENFILE})


def _where_the_disk_failed(error: OSError, target: Path) -> OSError | FMUBuildError:
    """The error to raise for an OSError of an export: unchanged if it concerns the target
    folder (the caller's) or is not the machine's doing; else an FMUBuildError naming the
    folder that failed, the build folder in $TMPDIR or the object cache, and what to do.
    (shutil.copyfile names the source file of a copy that failed, so a path under neither
    folder means the build folder, where every copy goes.)"""
    if error.errno not in _ENVIRONMENT_ERRNOS:
        return error
    named = [Path(os.path.abspath(p)) for p in (error.filename, error.filename2)
             if isinstance(p, (str, os.PathLike))]
    temporary = Path(os.path.abspath(tempfile.gettempdir()))
    try:
        cache = Path(os.path.abspath(cache_root() / "fmu-objects"))
    except RuntimeError:  # no home directory: the cache is a temporary folder
        cache = temporary

    def under(folder: Path) -> bool:
        return any(folder == p or folder in p.parents for p in named)

    if under(Path(os.path.abspath(target.parent))) and not under(temporary):
        return error
    if under(cache) and not under(temporary):
        return FMUBuildError(f"cannot write the FMU object cache {cache} ({error.strerror}); "
                             "free some space there or set FLEXSAT_CACHE_DIR to a folder "
                             "with room")
    return FMUBuildError(f"cannot write the FMU build folder in {temporary} ({error.strerror}); "
                         "free some space there or set TMPDIR to a folder with room")


def _build_and_write(model, target, identifier, guid, folder, suffix, templates_c, source_files,
                     fmi_version, interfaces, step, stop_time, description, sources_only,
                     compiler) -> None:
    """Build the FMU in a private folder of $TMPDIR and write it to ``target`` (see export)."""
    with build_directory() as root:
        sources = root / "sources"
        sources.mkdir()
        objects = root / "objects"
        objects.mkdir()
        # FMI 3.0 headers are supplied by the importer, not shipped (FMI 3.0.2, 2.5.1.4):
        # they are compiled against from a folder outside the FMU
        include = root / "include"
        include.mkdir()
        templates = template_dir()
        for name in (*templates_c, *TEMPLATE_HEADERS):
            shutil.copyfile(templates / name, sources / name)
        headers_dir = sources if fmi_version == "2.0" else include
        for name in standard_headers(fmi_version):
            shutil.copyfile(header_folder(fmi_version) / name, headers_dir / name)
        header_licence = (header_folder(fmi_version) / "LICENSE.txt").read_text(encoding="utf-8")
        if fmi_version == "2.0":
            shutil.copyfile(header_folder(fmi_version) / "LICENSE.txt",
                            sources / "LICENSE_fmi2_headers.txt")
        (sources / INTERFACES_HEADER).write_text(interfaces_header(interfaces), encoding="utf-8")
        (sources / "buildDescription.xml").write_text(
            build_description_xml(identifier, source_files), encoding="utf-8")
        library = root / "binaries" / folder / f"{identifier}{suffix}"
        with SharedLibraryBuild(library, [sources, include], objects, compiler) as build:
            if model.discrete:
                Phi = Gamma = np.zeros((0, 0))  # a sampled model has no transition matrices
            else:
                Phi, Gamma = zoh_matrices(model.A, model.B, step)
                if not (np.all(np.isfinite(Phi)) and np.all(np.isfinite(Gamma))):
                    raise FMUBuildError(
                        f"the transition matrix expm(A*step) overflows for step = {step!r} s: "
                        "the system grows too fast over one step. Choose a smaller step.")
            (sources / "model.c").write_text(model_c_source(model, identifier, guid, step, Phi, Gamma),
                                             encoding="utf-8")
            build.compile(sources / "model.c")
            # the fixed templates come from the cache (compiled there, in parallel with
            # model.c, when missing)
            headers = [headers_dir / h for h in standard_headers(fmi_version)]
            headers += [sources / h for h in (*TEMPLATE_HEADERS, INTERFACES_HEADER)]
            for name in templates_c:
                build.compile_cached(sources / name, headers)
            if fmi_version == "2.0":
                text = model_description_xml(
                    model, model_identifier=identifier, guid=guid, interfaces=interfaces,
                    step=step, stop_time=stop_time, source_files=source_files,
                    description=description)
            else:
                text = model_description3_xml(
                    model, model_identifier=identifier, guid=guid, interfaces=interfaces,
                    step=step, stop_time=stop_time, description=description)
            (root / "modelDescription.xml").write_text(text, encoding="utf-8")
            build.link()
            try:
                verify_library(library, probe_input(model, Phi, Gamma, step, interfaces, library,
                                                    guid, fmi_version), interfaces)
            except FMUBuildError:
                build.evict_cached()  # the next export compiles the templates afresh
                raise

        documentation = root / "documentation"
        (documentation / "licenses").mkdir(parents=True)
        page = documentation_html(model, model_identifier=identifier, fmi_version=fmi_version,
                                  interfaces=interfaces, step=step, stop_time=stop_time,
                                  description=description, sources_only=sources_only)
        (documentation / "index.html").write_text(page, encoding="utf-8")
        (documentation / "licenses" / "license.txt").write_text(
            licence_text(fmi_version, header_licence), encoding="utf-8")
        icon = icon_png(model)
        if fmi_version == "2.0":
            (documentation / "_main.html").write_text(page, encoding="utf-8")  # 2.0's entry point
            (root / "model.png").write_bytes(icon)
        else:
            (documentation / "diagram.png").write_bytes(icon)

        target.parent.mkdir(parents=True, exist_ok=True)
        left_out = [objects, include] + ([root / "binaries"] if sources_only else [])
        files = sorted(f for f in root.rglob("*")
                       if f.is_file() and not any(d in f.parents for d in left_out))

        def write_zip(handle) -> None:
            with zipfile.ZipFile(handle, "w", compression=zipfile.ZIP_DEFLATED) as archive:
                for file in files:
                    archive.write(file, file.relative_to(root).as_posix())

        write_atomically(target, write_zip)
