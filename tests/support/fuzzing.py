"""The bad values the fuzz tests feed every public parameter."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["BAD"]


class _Opaque:
    def __repr__(self):
        return "<opaque object>"


#: The 16 bad values every parameter gets.
BAD = (math.nan, math.inf, -math.inf, -1.0, 0.0, 1e308, -1e308, 5e-324, 1.0 + 1.0j, True, "x",
       None, [], [math.nan], np.array([]), _Opaque())
