"""The spacecraft: a rigid hub coupled to appendages through the W-matrix interface, scenes,
the scene runner, its report and the ``flexsat`` command."""

from .coupling import SecondOrderModel, Spacecraft
from .hub import Hub, Mount
from .limits import Limits
from .output import OutputError, OutputFolder
from .report import output_folder, write_report
from .runner import RunResult, RunStats, run
from .scene import Scene, SceneError, default_scene, example_scenes, load_scene, scene_path
from . import sweep  # noqa: E402  (after the runner it uses; callable: spacecraft.sweep(...))

__all__ = [
    "Hub", "Limits", "Mount", "OutputError", "OutputFolder", "RunResult", "RunStats", "Scene",
    "SceneError", "SecondOrderModel", "Spacecraft", "default_scene", "example_scenes",
    "load_scene", "output_folder", "run", "scene_path", "sweep", "write_report",
]
