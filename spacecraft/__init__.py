"""The spacecraft: a rigid hub coupled to appendages through the W-matrix interface, scenes,
the scene runner, its report and the ``flexsat`` command.

The names below are imported on first use (PEP 562): ``import spacecraft`` costs nothing, so
that ``flexsat --help`` does not load numpy, scipy, python-control, matplotlib or Dask.
"""

import importlib

#: Public name -> the module that defines it.
_WHERE = {
    "SecondOrderModel": "coupling", "Spacecraft": "coupling",
    "Hub": "hub", "Mount": "hub",
    "Limits": "limits",
    "OutputError": "output", "OutputFolder": "output",
    "output_folder": "report", "write_report": "report",
    "RunResult": "runner", "RunStats": "runner", "run": "runner",
    "Scene": "scene", "SceneError": "scene", "default_scene": "scene",
    "example_scenes": "scene", "load_scene": "scene", "scene_path": "scene",
}

__all__ = [
    "Hub", "Limits", "Mount", "OutputError", "OutputFolder", "RunResult", "RunStats", "Scene",
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
