"""Scenes: one question a user asks flexsat, read from TOML or a dict and validated.

:mod:`.read` reads every section of a scene (the documented keys, their units and ranges) into
the validated :class:`Scene` of :mod:`.specs`; :mod:`.reader` holds the value checks shared by
the section readers and :class:`SceneError`; :mod:`.limits` estimates a scene's work before
anything is built and refuses what exceeds its limits; :mod:`.given` reads a controller given
as numbers. The shipped scenes are the TOML files in ``embedded/``.
"""

from .given import GivenController
from .limits import Limits, estimate_cost
from .read import (Scene, SceneError, default_scene, example_scenes, load_scene, scene_dict,
                   scene_path)

__all__ = ["Scene", "SceneError", "Limits", "GivenController", "default_scene",
           "example_scenes", "load_scene", "scene_dict", "scene_path", "estimate_cost"]
