"""The spacecraft: a rigid hub coupled to appendages through the W-matrix interface, and the
application around it.

The subpackages, from the physics up (each imports only those listed before it):
:mod:`.dynamics` (hub, mounts, the coupled spacecraft, exact references), :mod:`.scene` (a
user's question, read and validated), :mod:`.basilisk` (the adapter to Basilisk),
:mod:`.design` (the design loop: models, fidelity, tuning, responses, verdicts), :mod:`.report`
(output folder, pages, plots, results, FMUs), :mod:`.sweep` (sweeps on Dask) and :mod:`.cli`
(the ``flexsat`` command). :mod:`.walkthrough` is a worked example of the public API.

The names below are imported on first use (PEP 562): ``import spacecraft`` costs nothing, so
that ``flexsat --help`` does not load numpy, scipy, python-control, matplotlib or Dask.
"""

import importlib

#: Public name -> the subpackage that exports it.
_WHERE = {
    "SecondOrderModel": "dynamics", "Spacecraft": "dynamics", "Hub": "dynamics",
    "Mount": "dynamics",
    "Limits": "scene", "Scene": "scene", "SceneError": "scene", "default_scene": "scene",
    "example_scenes": "scene", "load_scene": "scene", "scene_path": "scene",
    "DesignLoop": "design", "RunResult": "design", "RunStats": "design", "run": "design",
    "OutputError": "report", "OutputFolder": "report", "output_folder": "report",
    "write_report": "report",
}

__all__ = [
    "DesignLoop", "Hub", "Limits", "Mount", "OutputError", "OutputFolder", "RunResult", "RunStats", "Scene",
    "SceneError", "SecondOrderModel", "Spacecraft", "default_scene", "example_scenes",
    "load_scene", "output_folder", "run", "scene_path", "sweep", "write_report",
]


def __getattr__(name: str):
    if name == "sweep":
        # the package itself (callable: spacecraft.sweep(...))
        return importlib.import_module(".sweep", __name__)
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module 'spacecraft' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value   # later look-ups skip this function
    return value


def __dir__():
    return sorted(set(globals()) | set(__all__))
