"""The ``flexsat`` command.

Subcommands
-----------
``flexsat run [SCENE] [--out DIR] [--json] [--no-fmu] [--no-plots] [--quiet]``
    Run a scene (a TOML file, or the name of an embedded scene such as ``two_wings``; the
    default scene without argument) and write its report folder.
``flexsat table [beam options | --scene SCENE [--appendage NAME]] [--n-bodies N] [--json]``
    The paper's equivalence table for a beam (with ``--tip-mass``... a tip body) or for any
    appendage of a scene (a stepped or tapered beam, modal data): its exact model, the paper's
    two-mode beam (bare uniform beams), the chains fitted by flexsat and by the paper's
    criterion (bare uniform beams), with errors against the exact model.
``flexsat fit [beam options | --scene SCENE [--appendage NAME]] [--n-bodies N] [--match M] [--json]``
    Fit a chain to a beam or a scene's appendage and print its parameters.
``flexsat export [SCENE] [--out DIR] [--quiet]``
    FMUs only (plant, controllers, closed loops) with their cross-check files.
``flexsat sweep [SCENE] [--samples N] [--out DIR] [--scheduler ADDRESS] [--workers N] [--resume]``
    Sweep a scene's numbers on Dask (its ``[sweep]`` table; the embedded default sweep without
    argument): every sample a design-loop evaluation, samples streamed to Parquet, the worst
    case searched, a report (:mod:`spacecraft.sweep`).
``flexsat scenes``
    List the embedded scenes.

``--limit NAME=VALUE`` (run, export, table, fit; repeatable) raises or lowers a work limit of
:mod:`spacecraft.scene.limits` (``modes``, ``bodies``, ``fit_bodies``, ``appendages``, ``states``,
``samples``, ``memory``, ``string_length``, ``file_size``, ``basilisk_seconds``) over the
scene's own ``[limits]``.

Exit codes
----------
0
    Success (also when stdout is closed early, e.g. piped into ``head``: the report folder is
    complete; ``flexsat run --json | head`` is not an error of flexsat).
1
    A bug in flexsat: one line ``flexsat: internal error: ...``; ``--debug`` shows the
    traceback. Please report it.
2
    A user or environment error, one line ``flexsat: error: ...`` on stderr naming the file,
    key, value, unit and what to do: a bad option or scene, a value outside its range, work
    beyond a limit, a fidelity tolerance no truncation meets, an output folder that is taken,
    not writable, on a full disk or being written by another run, an FMU that cannot be built
    on this machine (no C compiler), too little memory.
130
    Interrupted by SIGINT (Ctrl-C); nothing half-written is left.
128 + n
    Terminated by signal n: 143 for SIGTERM, 129 for SIGHUP; cleaned up as for SIGINT.

Warnings of numpy or scipy never reach the terminal as they come: a run collects them into
its report (section "Warnings", ``results.json``) and the command prints each once, on one line
``flexsat: warning: ...``.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import os
import signal
import sys
import threading
import time
import traceback
import warnings
from pathlib import Path

from .progress import Progress

__all__ = ["main", "build_parser", "Terminated"]

#: Longest error line printed [characters].
_LINE = 1000

#: The paper's rod (PAPER.md): the default beam of ``flexsat table`` and ``flexsat fit``.
PAPER_ROD = {"section": "rod", "length": 10.0, "diameter": 0.01, "density": 7800.0,
             "youngs_modulus": 2.06e11}

_BEAM_OPTIONS = (
    ("--section", str, "rod, tube, rectangular or uniform (default: rod)"),
    ("--length", float, "beam length [m] (default 10)"),
    ("--diameter", float, "rod diameter [m] (default 0.01)"),
    ("--outer-diameter", float, "tube outer diameter [m]"),
    ("--wall-thickness", float, "tube wall thickness [m]"),
    ("--width", float, "rectangular width [m]"),
    ("--thickness", float, "rectangular thickness (bending plane) [m]"),
    ("--density", float, "material density [kg/m^3] (default 7800)"),
    ("--youngs-modulus", float, "Young's modulus [Pa] (default 2.06e11)"),
    ("--bending-stiffness", float, "uniform: EJ [N m^2]"),
    ("--linear-density", float, "uniform: mass per length [kg/m]"),
    ("--damping-ratio", float, "modal damping ratio [-] (default 0)"),
    ("--tip-mass", float, "a tip body at the free end: its mass [kg]"),
    ("--tip-inertia", float, "its moment of inertia about z through its centre of mass "
                             "[kg m^2] (default 0)"),
    ("--tip-offset", float, "its centre of mass beyond the free end, along the beam [m] "
                            "(default 0)"),
)
_TIP_OPTIONS = {"tip_mass": "mass", "tip_inertia": "inertia", "tip_offset": "offset"}


class _UserError(Exception):
    """A command-line mistake (exit code 2)."""


class Terminated(BaseException):
    """Raised in the main thread by SIGTERM or SIGHUP, so that ``with`` blocks and ``finally``
    clauses clean up as for SIGINT's KeyboardInterrupt (a BaseException: ``except Exception``
    does not swallow it)."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))


def _raise_terminated(signum, frame):
    # the first signal interrupts; further ones are ignored while the run cleans up
    for other in _SIGNALS:
        signal.signal(other, signal.SIG_IGN)
    raise Terminated(signum)


@contextlib.contextmanager
def _terminate_by_exception():
    """Within the block, SIGTERM and SIGHUP raise :class:`Terminated` (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {number: signal.signal(number, _raise_terminated) for number in _SIGNALS}
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


def _limit_option(text: str) -> tuple[str, float]:
    """``NAME=VALUE`` of --limit."""
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE (e.g. modes=800); got {text!r}")
    try:
        number = int(value)
    except ValueError:
        try:
            number = float(value)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{name}: expected a number; got {value!r}") from None
    return name.strip(), number


def _one_line(text: str) -> str:
    """A message on one line, at most about 1000 characters."""
    text = " ".join(str(text).split())
    return text if len(text) <= _LINE else text[:_LINE] + "..."


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # argparse's own errors: one line (no usage), exit 2
        print(_one_line(f"flexsat: error: {message} (see '{self.prog} --help')"),
              file=sys.stderr)
        raise SystemExit(2)


def build_parser(*, sweep_arguments: bool = True) -> argparse.ArgumentParser:
    """The argument parser of the ``flexsat`` command.

    ``sweep_arguments=False`` leaves the options of ``flexsat sweep`` out (they come from
    :mod:`spacecraft.sweep`, whose import loads the whole runner): :func:`main` adds them only
    when the command line asks for the sweep, so that ``flexsat --help`` stays fast.
    """
    parser = _Parser(prog="flexsat", description=(
        "Attitude control design for spacecraft with flexible appendages: exact beams, "
        "equivalent hinged chains, PD/LQR tuned on the chain and checked on the beam, FMUs."))
    parser.add_argument("--debug", action="store_true", help="show tracebacks of errors")
    parser.add_argument("--version", action="version", version=f"flexsat {_version()}")
    # --debug is accepted after the subcommand too; SUPPRESS: a subcommand without it does not
    # reset the top level's
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--debug", action="store_true", default=argparse.SUPPRESS,
                        help="show tracebacks of errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    def command(name, **kwargs):
        return sub.add_parser(name, parents=[common], **kwargs)

    run = command("run", help="run a scene and write its report folder",
                  description="Run a scene (TOML file or embedded scene name; the default "
                              "scene without argument) and write report.md, report.html, "
                              "results.json, plots and FMUs into a folder.")
    run.add_argument("scene", nargs="?", help="scene file or embedded scene name "
                                              "(see 'flexsat scenes')")
    run.add_argument("--out", type=Path, help="output folder (default: a new "
                                              "flexsat-<timestamp> folder here)")
    run.add_argument("--json", action="store_true", help="print results.json to stdout")
    run.add_argument("--no-fmu", action="store_true", help="skip FMU export")
    run.add_argument("--no-plots", action="store_true", help="skip plots")
    run.add_argument("--quiet", action="store_true", help="no progress display")
    _add_export_options(run)
    run.add_argument("--simulator", choices=("flexsat", "basilisk"),
                     help="also run the manoeuvre in Basilisk (needs flexsat[basilisk]); "
                          "overrides the scene's simulator.name")
    _add_limit(run)

    export = command("export", help="export FMUs only",
                     description="Tune the scene's controllers and export the FMUs of plant, "
                                 "controllers and closed loops (with cross-check files) into a "
                                 "folder; no report, plots or slews.")
    export.add_argument("scene", nargs="?", help="scene file or embedded scene name")
    export.add_argument("--out", type=Path, help="output folder (default: a new folder here)")
    export.add_argument("--quiet", action="store_true", help="no progress display")
    _add_export_options(export)
    _add_limit(export)

    for name, helptext, description in (
            ("table", "the paper's equivalence table for a beam",
             "The paper's equivalence table for a beam (default: the paper's steel rod): exact "
             "beam, the paper's two-mode beam and the chains fitted by flexsat and by the paper, "
             "with relative errors against the exact beam."),
            ("fit", "fit a chain to a beam and print its parameters",
             "Fit a chain of rigid bodies to a beam (default: the paper's steel rod) and print "
             "its body lengths, masses, inertias and hinge stiffnesses.")):
        p = command(name, help=helptext, description=description)
        p.add_argument("--scene", help="take the scene's first appendage with a structure "
                                       "(a beam, stepped or tapered beam, or modal data)")
        p.add_argument("--appendage", help="with --scene: the appendage of that name")
        for option, kind, text in _BEAM_OPTIONS:
            p.add_argument(option, type=kind, help=text)
        p.add_argument("--n-bodies", type=int, default=3, help="bodies of the chain (default 3)")
        if name == "fit":
            p.add_argument("--match", choices=("poles-and-zeros", "frequencies"),
                           default="poles-and-zeros",
                           help="flexsat's fit (default) or the paper's")
        p.add_argument("--json", action="store_true", help="JSON on stdout")
        p.add_argument("--quiet", action="store_true", help="no progress display")
        _add_limit(p)

    sweep = command(
        "sweep", help="sweep a scene on Dask: probability of instability, worst case",
        description="Sweep the numbers of a scene's [sweep] table (Monte Carlo, Latin hypercube "
                    "or grid) on Dask; every sample is a design-loop evaluation checked on the "
                    "exact beam. Writes the samples (Parquet), summary.json, report.md, "
                    "report.html, plots and worst.toml into a folder.")
    if sweep_arguments:
        from .sweep import add_arguments as add_sweep_arguments

        add_sweep_arguments(sweep)

    scenes = command("scenes", help="list the embedded scenes",
                            description="List the embedded scenes (usable as 'flexsat run "
                                        "NAME').")
    scenes.add_argument("--json", action="store_true",
                        help="JSON on stdout: name, title and path of each scene")
    return parser


def _version() -> str:
    """flexsat's version (:func:`spacecraft.report.write.version`, without importing the report)."""
    root = Path(__file__).resolve().parents[1] / "pyproject.toml"
    try:
        for line in root.read_text(encoding="utf-8").splitlines():
            if line.startswith("version"):
                return line.partition("=")[2].strip().strip('"')
    except OSError:
        pass
    try:
        from importlib.metadata import version

        return version("flexsat")
    except Exception:  # not installed
        return "unknown"


def _add_export_options(parser) -> None:
    """FMU options that override the scene's [export] table (and turn the export on)."""
    parser.add_argument("--fmi-version", choices=("2.0", "3.0", "both"),
                        help="FMI version of the FMUs (both: a set of each); overrides "
                             "export.fmi_version")
    parser.add_argument("--sources-only", action="store_true",
                        help="FMUs with C sources and build description, no binary")
    parser.add_argument("--ssp", action="store_true",
                        help="also an SSP file per controller connecting plant and controller "
                             "FMUs")


def _overrides(args, *, export_only: bool = False) -> tuple[dict, dict]:
    """The scene keys the command line's options set (key path -> value, for the scene
    reader, which checks them with the rest) and the option that set each key."""
    changes, given = {}, {}

    def put(key, value, option):
        changes[key] = value
        if option is not None:
            given[key] = option

    version = getattr(args, "fmi_version", None)
    if version is not None:
        put("export.fmi_version", ["2.0", "3.0"] if version == "both" else [version],
            f"--fmi-version {version}")
    if getattr(args, "sources_only", False):
        put("export.sources_only", True, "--sources-only")
    if getattr(args, "ssp", False):
        put("export.ssp", True, "--ssp")
    if changes:
        if getattr(args, "no_fmu", False):
            raise _UserError("--no-fmu contradicts --fmi-version, --sources-only and --ssp")
        put("export.fmu", True, None)
    if export_only:
        put("export.fmu", True, None)
    if getattr(args, "no_fmu", False):
        put("export.fmu", False, "--no-fmu")
    if getattr(args, "no_plots", False):
        put("report.plots", False, "--no-plots")
    simulator = getattr(args, "simulator", None)
    if simulator is not None:
        # flexsat alone: the whole table (Basilisk's rate, step and wheel go with Basilisk)
        if simulator == "flexsat":
            put("simulator", {"name": "flexsat"}, f"--simulator {simulator}")
        else:
            put("simulator.name", simulator, f"--simulator {simulator}")
    return changes, given


def _add_limit(parser) -> None:
    parser.add_argument("--limit", type=_limit_option, action="append", default=[],
                        metavar="NAME=VALUE",
                        help="raise (or lower) a work limit, e.g. --limit modes=800 (names: "
                             "modes, bodies, fit_bodies, appendages, states, samples, memory "
                             "[bytes], string_length, file_size [bytes], basilisk_seconds "
                             "[s]); repeatable")


def _limits(args) -> dict:
    return dict(getattr(args, "limit", []) or [])


def _scene(argument, limits=None, overrides=None, options=None):
    """The scene of the command line: a file or an embedded scene's name, with the options'
    ``overrides`` read by the scene reader, which checks them with the rest; a refusal of a
    key an option set names the option (``options``: key path -> option)."""
    from ..scene.read import SceneError, example_scenes, load_scene, scene_path

    try:
        if argument is None:
            return load_scene(None, limits=limits, overrides=overrides)
        path = Path(argument)
        if not path.exists():
            names = example_scenes()
            if argument in names:
                return load_scene(scene_path(argument), source=f"{argument} (embedded scene)",
                                  limits=limits, overrides=overrides)
            if path.suffix == "" and path.parent == Path("."):
                import difflib

                close = difflib.get_close_matches(argument, names, n=1)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                raise _UserError(f"{_one_line(argument)[:100]}: no such scene file or embedded "
                                 f"scene (embedded: {', '.join(names)}){hint}")
        return load_scene(path, limits=limits, overrides=overrides)
    except SceneError as exc:
        message = str(exc)
        named = [option for key, option in (options or {}).items() if f": {key}" in message]
        if not named:
            raise
        raise SceneError(f"{message} (set by {', '.join(dict.fromkeys(named))})") from None


def _beam_from(args):
    """The appendage of ``table`` and ``fit``: the scene's (``--scene``, ``--appendage``) or
    the beam of the beam options; with its source for the printout and the reader's unit-slip
    warnings (printed as ``flexsat: warning:`` lines)."""
    from ..scene.limits import library_limits
    from ..scene.read import SceneError, read_beam_table

    given = {option[2:].replace("-", "_"): getattr(args, option[2:].replace("-", "_"))
             for option, _, _ in _BEAM_OPTIONS}
    given = {k: v for k, v in given.items() if v is not None}
    name = getattr(args, "appendage", None)
    if args.scene is not None:
        if given:
            raise _UserError("give either --scene or beam options, not both")
        scene = _scene(args.scene, _limits(args))
        for line in scene.input_warnings:
            print(f"flexsat: warning: {_one_line(line)}", file=sys.stderr)
        names = [a.name for a in scene.appendages]
        for a in scene.appendages:
            if (name is None or a.name == name) and a.structure is not None:
                with library_limits(scene.limits):
                    return a.structure.build(), f"{scene.source}: {a.name}"
        if name is not None and name not in names:
            raise _UserError(f"--appendage {_one_line(name)[:100]}: {scene.source} has no such "
                             f"appendage (it has {', '.join(names)})")
        raise SceneError(f"{scene.source}: " + (f"appendage {name!r} has no structure to fit "
                                                "(a chain only)" if name is not None else
                                                "no appendage has a structure to fit (chains "
                                                "only)"))
    if name is not None:
        raise _UserError("--appendage chooses an appendage of --scene; give --scene too")
    tip = {_TIP_OPTIONS[k]: given.pop(k) for k in list(given) if k in _TIP_OPTIONS}
    if tip and "mass" not in tip:
        raise _UserError("--tip-inertia and --tip-offset describe a tip body: give its "
                         "--tip-mass [kg] too")
    section = given.get("section", "rod")
    if section == "rod":
        spec = {**PAPER_ROD, **given}
    elif section in ("tube", "rectangular"):
        spec = {k: PAPER_ROD[k] for k in ("length", "density", "youngs_modulus")} | given
    else:
        spec = {"length": PAPER_ROD["length"]} | given
    spec["section"] = section
    beam, warned = read_beam_table(spec, tip=tip or None)
    for line in warned:
        print(f"flexsat: warning: {_one_line(line)}", file=sys.stderr)
    return beam.build(), "command line"


def _matches(model, asked: str | None = None) -> tuple:
    """The fits ``table`` and ``fit`` make of a model: the paper's frequency fit needs a bare
    uniform beam (a _UserError if ``asked`` for another)."""
    from ..design.tables import reference_name

    paper = bool(getattr(model, "is_uniform", False))
    if asked == "frequencies" and not paper:
        raise _UserError(f"--match frequencies (the paper's fit: a symmetric chain of frozen "
                         f"pieces of a uniform rod) needs a uniform beam without a tip body; "
                         f"this is a {reference_name(model).split(' (')[0]}: use --match "
                         "poles-and-zeros")
    if asked is not None:
        return (asked,)
    return ("poles-and-zeros", "frequencies") if paper else ("poles-and-zeros",)


def _cmd_run(args, *, export_only: bool = False) -> int:
    from ..design.loop import run
    from ..report.exports import write_exports
    from ..report.output import OutputFolder
    from ..report.write import summary_lines, to_json, write_report

    progress = Progress(args.quiet)
    changes, options = _overrides(args, export_only=export_only)
    scene = _scene(args.scene, _limits(args), changes, options)
    if scene.simulator.name == "basilisk" and not export_only:
        from ..basilisk import require_basilisk

        require_basilisk()   # before any work: one line saying how to install the extra
    # the output folder is checked and claimed before anything is computed
    target = OutputFolder(args.out)
    with target as folder:
        result = run(scene, progress=progress, time_responses=not export_only)
        if export_only:
            files, _ = write_exports(result, folder, progress=progress)
            data = {**result.data, "files": files}
        else:
            data = write_report(result, folder, progress=progress)
    out = target.path
    progress(f"done in {time.perf_counter() - progress.t0:.1f} s")
    for line in data.get("warnings", []):
        print(f"flexsat: warning: {_one_line(line)}", file=sys.stderr)
    if getattr(args, "json", False):
        print(to_json(data))
        return 0
    fmus = data["files"].get("fmu", [])
    if export_only:
        for f in fmus + data["files"].get("ssp", []):
            print(f"{out / f['path']}: {f['description']}")
        return 0
    for line in summary_lines(data):
        print(line)
    what = ["report.md", "report.html", "results.json"]
    from ..design.naming import plural

    if data["files"].get("plots"):
        what.append(plural(len(data["files"]["plots"]), "plot"))
    if fmus:
        what.append(plural(len(fmus), "FMU"))
    if data["files"].get("ssp"):
        what.append(plural(len(data["files"]["ssp"]), "SSP file"))
    print(f"wrote {', '.join(what)} to {out}")
    return 0


def _check_n_bodies(args):
    """--n-bodies of table and fit: at least 2, at most limits.fit_bodies."""
    from ..scene.limits import Limits
    from ..scene.read import read_limits

    if args.n_bodies < 2:
        raise _UserError(f"--n-bodies must be at least 2; got {args.n_bodies}")
    limits = Limits(**read_limits(_limits(args), "--limit"))
    bound = limits.fit_bodies
    if args.n_bodies > bound:
        raise _UserError(f"--n-bodies {args.n_bodies}: over the limit {bound} (limits."
                         f"fit_bodies: the range the fit is tested on); ask for "
                         f"fewer, or raise it with --limit fit_bodies=N")
    return limits


def _equivalence(args):
    from ..design.tables import equivalence_table

    beam, source = _beam_from(args)
    from appendages.equivalence import fit_chain
    import warnings

    from ..scene.limits import library_limits

    progress = Progress(args.quiet)
    fits = {}
    with warnings.catch_warnings(), library_limits(args.checked_limits):
        warnings.simplefilter("ignore", RuntimeWarning)
        for match in _matches(beam):
            progress(_fit_message(args.n_bodies, match))
            fits[match] = fit_chain(beam, args.n_bodies, match=match)
    progress("equivalence table")
    return beam, source, equivalence_table(beam, fits)


def _fit_message(n_bodies: int, match: str) -> str:
    """Progress line of a chain fit (an optimisation: seconds for ten bodies)."""
    return f"fitting a chain of {n_bodies} bodies (match = {match!r})"


def _cmd_table(args) -> int:
    from ..report.write import equivalence_markdown, to_json

    args.checked_limits = _check_n_bodies(args)
    beam, source, table = _equivalence(args)
    if args.json:
        print(to_json({"beam": _beam_dict(beam), "source": source, **table}))
        return 0
    header, rows = equivalence_markdown(table)
    print(_appendage_line(beam, source, table["reference"]))
    cells = [header] + rows
    widths = [max(len(str(r[i])) for r in cells) for i in range(len(header))]
    for k, row in enumerate(cells):
        print("  ".join(str(c).rjust(w) if i else str(c).ljust(w)
                        for i, (c, w) in enumerate(zip(row, widths))).rstrip())
        if k == 0:
            print("  ".join("-" * w for w in widths))
    for note in table.get("notes", []):
        print(note)
    return 0


def _appendage_line(model, source: str, reference: str) -> str:
    """One line saying what the appendage is: a uniform beam's EJ and rho*A, any other's
    kind, length and mass."""
    kind = reference.split(" (")[0]
    if getattr(model, "is_uniform", False):
        return (f"beam ({source}): length {model.length:g} m, EJ {model.bending_stiffness:.6g} "
                f"N m^2, rho*A {model.linear_density:.6g} kg/m, mass {model.mass:.5g} kg")
    return (f"{kind} ({source}): length {model.length:g} m, mass {model.mass:.5g} kg, inertia "
            f"about its centre of mass {model.inertia:.5g} kg m^2")


def _beam_dict(beam) -> dict:
    """The appendage of ``table``/``fit`` as JSON: a uniform beam's section properties, any
    other's kind and rigid properties."""
    from ..design.tables import describe_model, reference_name

    if getattr(beam, "is_uniform", False):
        return {"length": beam.length, "bending_stiffness": beam.bending_stiffness,
                "linear_density": beam.linear_density, "damping_ratio": beam.damping_ratio,
                "mass": beam.mass, "inertia": beam.inertia}
    return {"kind": reference_name(beam).split(" (")[0], **describe_model(beam)}


def _natural_frequencies(model, n: int) -> list:
    """The first n free-free natural frequencies [rad/s] of an appendage (its poles)."""
    if hasattr(model, "natural_frequencies"):
        return model.natural_frequencies(n).tolist()
    return [float(w) for w in model.poles()[:n]]


def _cmd_fit(args) -> int:
    import warnings

    from appendages.equivalence import fit_chain

    from ..report.write import to_json
    from ..design.tables import describe_model as _describe

    from ..scene.limits import library_limits

    limits = _check_n_bodies(args)
    beam, source = _beam_from(args)
    _matches(beam, args.match)
    progress = Progress(args.quiet)
    progress(_fit_message(args.n_bodies, args.match))
    with warnings.catch_warnings(), library_limits(limits):
        warnings.simplefilter("ignore", RuntimeWarning)
        chain = fit_chain(beam, args.n_bodies, match=args.match)
    progress("done")
    data = {"beam": _beam_dict(beam), "source": source, "match": args.match,
            "n_bodies": args.n_bodies, "chain": _describe(chain),
            "beam_frequencies": _natural_frequencies(beam, args.n_bodies - 1)}
    if args.json:
        print(to_json(data))
        return 0
    c = data["chain"]
    print(f"chain of {args.n_bodies} bodies fitted to the {_beam_dict(beam).get('kind', 'beam')}"
          f" ({source}) by match = {args.match!r}")
    print(f"{'body':>4}  {'length [m]':>12}  {'mass [kg]':>12}  {'inertia [kg m^2]':>16}  "
          f"{'com offset [m]':>14}")
    for k in range(args.n_bodies):
        print(f"{k + 1:>4}  {c['lengths'][k]:>12.6g}  {c['masses'][k]:>12.6g}  "
              f"{c['inertias'][k]:>16.6g}  {c['com_offsets'][k]:>14.6g}")
    print("hinge stiffnesses [N m/rad]: " + ", ".join(f"{v:.6g}" for v in c["hinge_stiffnesses"]))
    print("natural frequencies [rad/s]: chain " + ", ".join(
        f"{v:.5g}" for v in c["natural_frequencies"]) + "; beam " + ", ".join(
        f"{v:.5g}" for v in data["beam_frequencies"]))
    return 0


def _cmd_scenes(args) -> int:
    from ..scene.read import example_scenes, load_scene, scene_path

    scenes = [{"name": name, "title": load_scene(scene_path(name)).title,
               "path": str(scene_path(name))} for name in example_scenes()]
    if getattr(args, "json", False):
        import json

        print(json.dumps(scenes, indent=2))
        return 0
    width = max(len(s["name"]) for s in scenes)
    for s in scenes:
        print(f"{s['name']:{width}s}  {s['title']}")
    return 0


def _dispatch(args) -> int:
    if args.command == "run":
        return _cmd_run(args)
    if args.command == "export":
        return _cmd_run(args, export_only=True)
    if args.command == "table":
        return _cmd_table(args)
    if args.command == "fit":
        return _cmd_fit(args)
    if args.command == "sweep":
        from .sweep import run_command

        return run_command(args)
    return _cmd_scenes(args)


def _classify(exc: BaseException) -> tuple[int, str]:
    """Exit code and message line of an exception: 2 for user and environment errors, 1 for
    a bug of flexsat."""
    from appendages.interface import FlexsatError
    from fmu import FMUError

    from ..report.output import is_environment_error

    if isinstance(exc, (FlexsatError, _UserError)):
        return 2, f"flexsat: error: {exc}"
    if isinstance(exc, FMUError):
        # the fmu package's messages say what to do; one that declares itself a bug of ours
        # (a compiler error on code we generated) is one
        if "bug" in str(exc).lower():
            return 1, f"flexsat: internal error: FMU export failed: {exc}"
        return 2, f"flexsat: error: FMU export failed: {exc}"
    if is_environment_error(exc):
        where = f": {exc.filename}" if getattr(exc, "filename", None) else ""
        return 2, (f"flexsat: error: {exc.strerror}{where} ({errno.errorcode.get(exc.errno, '')}"
                   "); free some space, check the permissions or choose another --out")
    if isinstance(exc, MemoryError):
        return 2, ("flexsat: error: out of memory: this machine has less memory than the scene "
                   "needs; ask for less (fewer modes, bodies, samples or controllers) or lower "
                   "--limit memory=BYTES to what the machine has")
    return 1, (f"flexsat: internal error: {type(exc).__name__}: {exc} (a bug in flexsat; run "
               "with --debug for the traceback and please report it)")


def main(argv=None) -> int:
    """Entry point of the ``flexsat`` console script; returns the exit code (see the module
    docstring for each)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(sweep_arguments="sweep" in argv)
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    debug = args.debug
    with _terminate_by_exception(), warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        try:
            code = _dispatch(args)
        except BrokenPipeError:
            # stdout closed early (e.g. piped into head): not an error of flexsat
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 0
        except KeyboardInterrupt:
            print("flexsat: interrupted; nothing half-written was kept", file=sys.stderr)
            return 130
        except Terminated as exc:
            name = signal.Signals(exc.signum).name
            print(f"flexsat: terminated by {name}; nothing half-written was kept",
                  file=sys.stderr)
            return 128 + exc.signum
        except Exception as exc:
            if debug:
                traceback.print_exc()
            code, line = _classify(exc)
            print(_one_line(line), file=sys.stderr)
            return code
    # warnings outside a scene run (those of a run are in its report and printed with it)
    from ..design.loop import warning_lines

    for line in warning_lines(caught):
        print(f"flexsat: warning: {_one_line(line)}", file=sys.stderr)
    return code


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
