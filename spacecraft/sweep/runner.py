"""Run a sweep: read it, prepare the shared design data, run the samples, search the worst case,
write the report.

:func:`run_sweep` is the whole sweep (the ``flexsat sweep`` command calls it);
:func:`sweep` is its Python face and returns the table of samples.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import datetime
import hashlib
import json
import os
import time
import tomllib
from collections.abc import Mapping
from pathlib import Path

from fmu.files import write_text_atomically

from ..scene.read import SceneError
from .evaluate import Context, evaluate, prepare
from .execute import SampleStore, check_workers, open_executor, run_samples, schema
from .parameters import SweepError, SweepSpec, check_box, read_sweep
from .report import summarise, write_report
from .worst import search, to_toml, verify, worst_scene

__all__ = ["SweepResult", "load_sweep", "run_sweep", "sweep", "sweep_scene_path",
           "sweep_scenes"]


@dataclasses.dataclass
class SweepResult:
    """Everything a sweep produced.

    Attributes
    ----------
    table : pyarrow.Table
        One row per sample: ``sample``, the parameters (file units), the metrics.
    summary : dict
        Every figure of the report (``summary.json``).
    worst : list of WorstCase
    context : Context
    spec : SweepSpec
    folder : Path or None
    """

    table: object
    summary: dict
    worst: list
    context: Context
    spec: SweepSpec
    folder: Path | None = None


def _folder() -> Path:
    import importlib.resources

    return Path(str(importlib.resources.files("spacecraft.scene").joinpath("embedded", "sweeps")))


def sweep_scenes() -> list[str]:
    """Names of the embedded sweep scenes."""
    return sorted(p.stem for p in _folder().glob("*.toml"))


def sweep_scene_path(name: str) -> Path:
    """Path of an embedded sweep scene (``"default"``)."""
    if not isinstance(name, str):
        raise TypeError(f"name must be the name of an embedded sweep scene (a string); got "
                        f"{type(name).__name__} {name!r:.100}")
    path = _folder() / f"{name}.toml"
    if not path.is_file():
        raise SweepError(f"name: no embedded sweep scene {name!r}; available: "
                         + ", ".join(sweep_scenes()))
    return path


def _read(scene) -> tuple[dict, str]:
    """The scene mapping and its name: a file, an embedded sweep scene, an embedded scene
    (``flexsat scenes``: its ``[sweep]`` table, if any, or the parameters given), a dict."""
    from ..scene.read import example_scenes, scene_path

    if scene is None:
        return _read_file(sweep_scene_path("default"), "default sweep scene")
    if isinstance(scene, Mapping):
        return copy.deepcopy(dict(scene)), "<dict>"
    if isinstance(scene, (str, os.PathLike)):
        path = Path(scene)
        if not path.exists() and isinstance(scene, str):
            if scene in sweep_scenes():
                return _read_file(sweep_scene_path(scene), f"{scene} (embedded sweep scene)")
            if scene in example_scenes():
                return _read_file(scene_path(scene), f"{scene} (embedded scene)")
            if path.suffix == "" and path.parent == Path("."):
                raise SweepError(f"{' '.join(scene.split())[:100]}: no such scene file or "
                                 f"embedded scene (sweep scenes: {', '.join(sweep_scenes())}; "
                                 f"scenes: {', '.join(example_scenes())})")
        return _read_file(path, str(path))
    raise SweepError(f"scene must be a TOML file path, an embedded scene name or a dict; got "
                     f"{type(scene).__name__}")


def _read_file(path: Path, source: str) -> tuple[dict, str]:
    try:
        text = path.read_bytes()
    except FileNotFoundError:
        raise SweepError(f"{path}: no such scene file") from None
    except OSError as exc:
        raise SweepError(f"{path}: cannot read the scene file ({exc.strerror})") from None
    try:
        return tomllib.loads(text.decode("utf-8")), source
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise SweepError(f"{path}: invalid TOML ({exc})") from None


def load_sweep(scene=None, *, parameters: Mapping | None = None, max_samples: int | None = None,
               **settings) -> tuple[dict, SweepSpec, str]:
    """Read a sweep scene; keyword settings override its ``[sweep]`` table.

    Parameters
    ----------
    scene : path, str, dict or None
        A TOML scene file with a ``[sweep]`` table, an embedded sweep scene's name, a dict of
        the same structure, or None for the embedded default sweep.
    parameters : mapping, optional
        Key path -> distribution table, replacing the scene's ``[sweep.parameters]``.
    max_samples : int, optional
        Raise the sample limit.
    **settings
        Any other key of ``[sweep]`` (``samples``, ``seed``, ``method``, ``design``,
        ``worst_case``...), replacing the scene's.

    Returns
    -------
    raw : dict
        The scene mapping without ``sweep`` (file units).
    spec : SweepSpec
    source : str
    """
    raw, source = _read(scene)
    table = raw.pop("sweep", None)
    if table is not None and not isinstance(table, Mapping):
        raise SweepError(f"{source}: sweep: must be a table ([sweep] with parameters, samples, "
                         f"method...); got {type(table).__name__} {table!r:.60}")
    table = dict(table or {})
    if not table and parameters is None:
        raise SweepError(f"{source}: no [sweep] table and no parameters given: nothing to "
                         "sweep (add a [sweep] table: see the embedded sweep scene 'default')")
    if parameters is not None:
        if not isinstance(parameters, Mapping):
            raise SweepError(f"parameters must be a mapping key path -> distribution table; got "
                             f"{type(parameters).__name__}")
        table["parameters"] = dict(parameters)
    if max_samples is not None and (isinstance(max_samples, bool) or not isinstance(
            max_samples, int) or max_samples < 1):
        raise SweepError(f"max_samples must be a positive whole number or None; got "
                         f"{max_samples!r:.100}")
    table.update({k: v for k, v in settings.items() if v is not None})
    return raw, read_sweep(table, raw, source, max_samples=max_samples), source


def _fingerprint(context: Context) -> str:
    text = json.dumps(context.base, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def run_sweep(scene=None, *, out=None, client=None, scheduler: str | None = None,
              workers: int | None = None, resume: bool = False, progress: bool = True,
              plots: bool = True, batch: int | None = None, parameters: Mapping | None = None,
              max_samples: int | None = None, log=None, **settings) -> SweepResult:
    """Run a sweep end to end.

    Parameters
    ----------
    scene : path, str, dict or None
        See :func:`load_sweep`.
    out : path, optional
        Output folder: Parquet parts, ``sweep.json``, the report, ``worst.toml``. None: keep
        everything in memory, no files.
    client : distributed.Client, optional
        Run on this cluster.
    scheduler : str, optional
        Address of a running Dask scheduler.
    workers : int, optional
        Local worker processes (default: one per core).
    resume : bool
        Continue the sweep in ``out`` (needs ``out``).
    progress : bool
        Progress bar on stderr.
    plots : bool
        Write the plots (with ``out``).
    batch : int, optional
        Samples per Dask task (default: about :data:`.execute.TASK_SECONDS` of work).
    parameters, max_samples, **settings
        See :func:`load_sweep`.
    log : callable, optional
        Called with a short message at the start of each stage.

    Returns
    -------
    SweepResult

    Raises
    ------
    SweepError, SceneError
        Bad sweep or scene (naming the key), a box reaching non-physical values, an output
        folder in the way, an unreachable scheduler, a nominal scene whose design loop fails.
    """
    say = log or (lambda message: None)
    timings: dict = {}
    t = time.perf_counter()
    raw, spec, source = load_sweep(scene, parameters=parameters, max_samples=max_samples,
                                   **settings)
    if resume and out is None:
        raise SweepError("--resume needs the output folder of the interrupted sweep (--out)")
    check_workers(workers)
    if out is not None and not resume:
        folder = Path(out)
        if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
            raise SweepError(f"{folder}: output folder exists and is not empty; use --resume "
                             "to continue its sweep, or choose another --out")
    executor = None
    if scheduler is not None or client is not None:
        # before any work or file: an unreachable scheduler is reported at once
        say(f"connecting to the Dask scheduler{'' if scheduler is None else ' ' + scheduler}")
        executor = open_executor(client=client, scheduler=scheduler, workers=workers)
    try:
        # the folder is claimed (locked) before the work: another sweep writing it is named
        # at once
        with (SampleStore(out, resume=resume) if out is not None
              else contextlib.nullcontext()) as store:
            return _run(raw, spec, source, store, executor, workers, progress, plots, batch,
                        say, timings, t)
    finally:
        if executor is not None:
            executor.close()


def _run(raw, spec, source, store, executor, workers, progress, plots, batch, say,
         timings, t) -> SweepResult:
    say(f"{spec.n_samples} samples of {len(spec.parameters)} parameters ({spec.method})")
    values = spec.values()
    check_box(spec, raw, source, values)
    say("preparing: fidelity, chain fits, nominal design")
    context = prepare(raw, spec, source)
    timings["prepare"] = time.perf_counter() - t
    # the nominal scene, twice: the first pays for imports and caches, the second is timed
    nominal = evaluate(context, spec.nominal)
    t = time.perf_counter()
    nominal = evaluate(context, spec.nominal)
    timings["nominal_evaluation"] = time.perf_counter() - t
    if nominal["error"]:
        raise SceneError(f"{source}: the nominal scene's design loop fails: {nominal['error']}")
    if store is not None:
        store.start({"scene": source, "sweep": spec.as_dict(),
                     "scene_fingerprint": _fingerprint(context), "n_modes": context.n_modes,
                     "nominal_controller": context.nominal_record,
                     "started": datetime.datetime.now().isoformat(timespec="seconds")},
                    schema(context))
        if store.recomputed:
            say(f"damaged parts set aside (renamed *.damaged), their samples computed again: "
                f"{', '.join(store.recomputed)}")
    return _samples_and_report(context, spec, source, store, executor, workers, values,
                               nominal, progress, plots, batch, say, timings)


def _samples_and_report(context, spec, source, store, executor, workers, values, nominal,
                        progress, plots, batch, say, timings) -> SweepResult:
    out = None if store is None else store.folder
    n_todo = spec.n_samples - (store.completed().size if store is not None else 0)
    owned = executor is None
    if owned:
        executor = open_executor(workers=workers,
                                 estimated_seconds=n_todo * timings["nominal_evaluation"])
    worst = []
    skipped = None
    try:
        say(f"running {n_todo} samples on {executor.describe()}")
        t = time.perf_counter()
        table, info = run_samples(context, spec, executor, store=store, values=values,
                                  seconds_per_sample=timings["nominal_evaluation"],
                                  progress=progress, batch=batch)
        info["recomputed"] = [] if store is None else list(store.recomputed)
        timings["samples"] = time.perf_counter() - t
        evaluated = sum(1 for e in table.column("error").to_pylist() if not e)
        if spec.worst_case and not evaluated:
            skipped = "every sample failed: no margin to start the worst-case search from"
        for metric in spec.worst_case if evaluated else ():
            say(f"worst case of the {metric.replace('_', ' ')}")
            t = time.perf_counter()
            w = search(context, spec, executor, table, metric, batch=info["batch"])
            timings[f"worst_{metric}"] = time.perf_counter() - t
            worst.append(w)
    finally:
        if owned:
            executor.close()
    for w in worst:
        t = time.perf_counter()
        name = "worst.toml" if w.metric == "modulus_margin" else f"worst_{w.metric}.toml"
        try:
            scene_raw = worst_scene(context, w.values, w.row)
        except ValueError as exc:
            w.verification = {"scene": None, "note": str(exc)}
            continue
        say(f"verifying the worst {w.metric.replace('_', ' ')} on the exact beam")
        w.verification = verify(context, w.values, scene_raw, f"{name} of {source}")
        w.verification["scene"] = name
        timings[f"verify_{w.metric}"] = time.perf_counter() - t
        if out is not None:
            header = (f"Worst {w.metric.replace('_', ' ')} of the sweep of {source}: signed margin "
                      f"{w.objective:.6g}\n"
                      + "\n".join(f"{k} = {v!r}" for k, v in w.values.items())
                      + "\nThe controller the sweep closed there is given as numbers "
                        "([controller.given]).\nRun it with: flexsat run " + name)
            write_text_atomically(Path(out) / name, to_toml(scene_raw, header))
    summary = summarise(table, context, spec, nominal=nominal, worst=worst, timings=timings,
                        executor=executor.describe(), info=info)
    if skipped:
        summary["worst_case_skipped"] = skipped
    if out is not None:
        say("writing the report")
        summary = write_report(out, table, context, spec, summary, plots=plots)
    return SweepResult(table, summary, worst, context, spec, None if out is None else Path(out))


def sweep(scene=None, *, parameters: Mapping | None = None, samples: int | None = None,
          client=None, **options):
    """Sweep a scene and return the table of samples.

    Parameters
    ----------
    scene : path, str, dict or None
        A scene (TOML file, embedded sweep scene name, dict; None: the default sweep scene).
        Its ``[sweep]`` table gives the settings; the arguments override them.
    parameters : mapping, optional
        Key path -> distribution, e.g. ``{"hub.inertia": {"distribution": "uniform",
        "low": 40.0, "high": 60.0}}``.
    samples : int, optional
        Monte Carlo / Latin-hypercube samples.
    client : distributed.Client, optional
        Run on this Dask cluster (default: a local cluster sized to the machine, or in-process
        for a tiny sweep).
    **options
        Any other argument of :func:`run_sweep` (``out``, ``seed``, ``method``, ``design``,
        ``worst_case``, ``workers``, ``progress``...).

    Returns
    -------
    pyarrow.Table
        One row per sample: ``sample``, the parameters, the metrics
        (:data:`spacecraft.sweep.evaluate.METRICS`). The summary (probability of instability,
        sensitivities, worst case) is in ``table.schema.metadata[b"flexsat.summary"]`` (JSON).
        A pyarrow Table rather than a pandas DataFrame: typed columns (booleans and integers
        stay so where samples failed), the Parquet files' own format, no further dependency;
        ``table.to_pandas()`` gives a DataFrame where pandas is installed.
    """
    from ..report.write import to_json

    result = run_sweep(scene, parameters=parameters, samples=samples, client=client, **options)
    meta = dict(result.table.schema.metadata or {})
    meta[b"flexsat.summary"] = to_json(result.summary).encode()
    return result.table.replace_schema_metadata(meta)

