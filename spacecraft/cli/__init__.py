"""The ``flexsat`` command: ``run``, ``export``, ``scenes``, ``table``, ``fit`` and ``sweep``.

:mod:`.command` parses the command line and maps every outcome to an exit code (0 done, 2 a user or
environment error, 1 a bug, 128 + n a signal); it imports the rest of flexsat only when a
command needs it, so that ``flexsat --help`` starts at once.
"""

from .command import Terminated, build_parser, main

__all__ = ["main", "build_parser", "Terminated"]
