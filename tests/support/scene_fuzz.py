"""The scene fuzz tests' tools: a mutation of a scene dict at a key path, and the check that a
load gives a Scene or a one-line SceneError naming the source and a key."""
from __future__ import annotations

import copy
import math
import re

from spacecraft.scene.read import Scene, SceneError

__all__ = ["DELETE", "check", "mutate"]


TOP = {"title", "hub", "appendages", "fidelity", "controller", "manoeuvre", "outputs", "export",
       "report", "limits", "wheels", "sensors"}


DELETE = object()


# one key of a key path in a message: a plain key, or the repr of an odd one (shortened to
# about 100 characters, then without its closing quote)
SEGMENT = (r"""(?:[\w-]+|'(?:[^'\\]|\\.)*'|"(?:[^"\\]|\\.)*"|['"].*?\.\.\. \(\d+ """
           r"""characters\))""")


def mutate(data, path, value):
    node = data
    for key in path[:-1]:
        if isinstance(node, dict):
            node = node.setdefault(key, {})
        elif isinstance(node, list) and isinstance(key, int) and key < len(node):
            node = node[key]
        else:
            return
    last = path[-1]
    if isinstance(node, dict):
        if value is DELETE:
            node.pop(last, None)
        else:
            node[last] = copy.deepcopy(value)
    elif isinstance(node, list) and isinstance(last, int) and last < len(node):
        if value is not DELETE:
            node[last] = copy.deepcopy(value)


def check(load, source: str, unknown: set):
    """load() gives a Scene or a one-line SceneError naming ``source`` and a key."""
    try:
        scene = load()
    except SceneError as exc:
        message = str(exc)
        assert "\n" not in message and "\r" not in message, message
        assert len(message) < 1200, len(message)
        assert message.startswith(source + ": "), message
        rest = message[len(source) + 2:]
        if rest.startswith(("tables or arrays nested too deeply", "invalid TOML")):
            return
        match = re.match(rf"({SEGMENT})((?:\.{SEGMENT}|\[\d+\])*): ", rest)
        assert match, message
        first = match.group(1)
        assert first in TOP or first in unknown or first[0] in "'\"", message
        return
    assert isinstance(scene, Scene)
    assert math.isfinite(scene.hub.mass) and scene.hub.mass > 0
