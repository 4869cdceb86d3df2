"""The FMUs a scene asks for, and the SSP files that connect them.

For each FMI version of ``export.fmi_version`` (``"2.0"``, ``"3.0"``): the truth plant, every
controller tuned on the first design model and its loop closed on the truth plant
(:func:`fmu.export`, with FMI cross-check files unless ``export.reference_files = false``;
C sources only with ``export.sources_only``). A digital controller is a sampled Co-Simulation
FMU at its sample time T, its closed loop a discrete system at T
(:func:`controllers.close_loop`), and the plant FMU's communication step is T, so that plant
and controller FMUs co-simulate the sampled-data loop. With ``export.ssp`` an SSP file per
controller and version connects the plant FMU and the controller FMU (:func:`fmu.write_ssp`),
written once both FMUs exist.

File names: ``plant.fmu``, ``<controller>.fmu``, ``closed_loop_<controller>.fmu``,
``loop_<controller>.ssp``; when both versions are asked for, the FMI 3.0 files carry the suffix
``_fmi3``.
"""

from __future__ import annotations

import concurrent.futures
import os
from collections.abc import Callable
from pathlib import Path

from ..design.naming import controller_label, design_label, plural

__all__ = ["fmu_jobs", "start_exports", "finish_exports", "write_ssps", "write_exports"]


def _suffix(version: str, versions) -> str:
    return "_fmi3" if version == "3.0" and len(versions) > 1 else ""


def fmu_jobs(result) -> list:
    """``(name, system, description, version, role)`` of every FMU the scene asks for; role is
    ``"plant"``, ``"controller"`` or ``"closed_loop"`` with the controller kind."""
    scene = result.scene
    primary = next(iter(result.designs))
    versions = scene.export.fmi_versions
    jobs = []
    for version in versions:
        tail = _suffix(version, versions)
        label = f" (FMI {version})"
        if "plant" in scene.export.systems:
            jobs.append((f"plant{tail}", result.truth["sim"],
                         "truth plant (hub + appendages)" + label, version, ("plant", None)))
        for kind, K in result.designs[primary]["controllers"].items():
            what = controller_label(kind)
            digital = f", digital at {K.dt:g} s" if K.isdtime(strict=True) else ""
            if "controller" in scene.export.systems:
                jobs.append((f"{kind}{tail}", K, f"{what} controller tuned on "
                             f"{design_label(primary)}{digital}{label}", version,
                             ("controller", kind)))
            if "closed_loop" in scene.export.systems:
                loop = result.loops.get((primary, kind, "truth"))
                if loop is None:
                    import controllers

                    loop = controllers.close_loop(result.truth["sim"], K)
                jobs.append((f"closed_loop_{kind}{tail}", loop,
                             f"{what} loop closed on the truth plant{digital}{label}", version,
                             ("closed_loop", kind)))
    return jobs


def _steps(result) -> tuple[float, float]:
    """Communication step [s] of continuous FMUs and the stop time [s]."""
    scene = result.scene
    step = scene.export.step or (scene.manoeuvre.step if scene.manoeuvre else None)
    sample_time = scene.controller.sample_time
    if sample_time is not None:
        # the plant FMU steps at the controller's sample time: with the sampled controller
        # FMU it co-simulates the sampled-data loop
        step = sample_time
    stop = scene.manoeuvre.duration if scene.manoeuvre else 100.0 * step
    return step, stop


def start_exports(result, folder: Path, pool) -> list:
    """Submit the FMU builds to a thread pool; returns ``[(job, future)]``."""
    import fmu

    scene = result.scene
    step, stop = _steps(result)

    def build(job):
        name, system, description, version, _ = job
        options = {}
        if version != "2.0" or scene.export.sources_only:
            options = {"fmi_version": version, "sources_only": scene.export.sources_only}
        return fmu.export(system, folder / f"{name}.fmu", model_name=name,
                          step=None if system.isdtime(strict=True) else step,
                          stop_time=stop, reference=scene.export.reference_files,
                          description=f"flexsat: {description}", **options)

    return [(job, pool.submit(build, job)) for job in fmu_jobs(result)]


def finish_exports(started: list, stats) -> list:
    """Wait for the builds; returns the FMU entries of results.json."""
    out = []
    for (name, system, description, version, role), future in started:
        path = future.result()
        stats.fmu_builds += 1
        out.append({"path": f"fmu/{path.name}", "description": description,
                    "fmi_version": version, "role": role[0], "controller": role[1],
                    "inputs": list(system.input_labels), "outputs": list(system.output_labels),
                    "n_states": int(system.nstates),
                    "sample_time": float(system.dt) if system.isdtime(strict=True) else None})
    return out


def write_ssps(result, folder: Path, fmus: list) -> list:
    """One SSP per controller and FMI version connecting the plant and controller FMUs."""
    import fmu

    scene = result.scene
    if not scene.export.ssp:
        return []
    _, stop = _steps(result)
    by_role = {(f["role"], f["controller"], f["fmi_version"]): f for f in fmus}
    out = []
    for version in scene.export.fmi_versions:
        plant = by_role.get(("plant", None, version))
        for kind in result.designs[next(iter(result.designs))]["controllers"]:
            controller = by_role.get(("controller", kind, version))
            if plant is None or controller is None:
                continue
            name = f"loop_{kind}{_suffix(version, scene.export.fmi_versions)}.ssp"
            path = fmu.write_ssp(folder / name, folder.parent / plant["path"],
                                 folder.parent / controller["path"], stop_time=stop,
                                 name=f"loop_{kind}")
            out.append({"path": f"fmu/{Path(path).name}", "fmi_version": version,
                        "controller": kind,
                        "description": f"{controller_label(kind)} controller FMU and plant FMU "
                                       f"connected by signal name (SSP, FMI {version})"})
    return out


def write_exports(result, folder: str | os.PathLike, *, progress=None,
                  meanwhile: Callable[[], object] | None = None) -> tuple[dict, object]:
    """Build the FMUs and SSP files a run's scene asks for (``export.fmu``) into
    ``folder/fmu``.

    The C compiler runs in subprocesses, two builds at a time (both cores): ``meanwhile()``
    runs while they build (the report's plots).

    Parameters
    ----------
    result : spacecraft.design.loop.RunResult
    folder : path
        An existing folder.
    progress : callable, optional
        Called with a short message per step.
    meanwhile : callable, optional
        Work to do while the FMUs build; its value is returned.

    Returns
    -------
    files : dict
        ``fmu`` and ``ssp``: the entries of results.json (empty without ``export.fmu``).
    value
        What ``meanwhile()`` returned (None without it).
    """
    scene = result.scene
    progress = progress or (lambda message: None)
    folder = Path(folder)
    files: dict = {"fmu": [], "ssp": []}
    pool = (concurrent.futures.ThreadPoolExecutor(max_workers=2) if scene.export.fmu
            else None)
    try:
        started = []
        if pool is not None:
            (folder / "fmu").mkdir(exist_ok=True)
            started = start_exports(result, folder / "fmu", pool)
            progress(f"exporting {plural(len(started), 'FMU')}")
        value = meanwhile() if meanwhile is not None else None
        if started:
            progress("waiting for the FMU builds")
        files["fmu"] = finish_exports(started, result.stats)
        if pool is not None and scene.export.ssp:
            files["ssp"] = write_ssps(result, folder / "fmu", files["fmu"])
    finally:
        # on an error or a signal the builds not yet started are dropped; running ones (a few
        # tenths of a second of gcc) finish before the folder is removed
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
    return files, value
