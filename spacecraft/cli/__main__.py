"""``python -m spacecraft.cli``: the ``flexsat`` command."""

import sys

from .command import main

__all__ = []  # a script, nothing to import

if __name__ == "__main__":
    sys.exit(main())
