"""Closed-loop analysis of attitude controllers (re-exports, by concept).

The analysis lives in one module per concept: :mod:`controllers.signals` (signal conventions),
:mod:`controllers.modes` (rigid-body inertia, flexible modes), :mod:`controllers.loop` (closing
the loop, loop transfer function), :mod:`controllers.margins` (margins, spillover verdict) and
:mod:`controllers.timeresp` (time responses, metrics). This module keeps the names importable
from ``controllers.analysis``.
"""
from .loop import close_loop, loop_frequency_response
from .margins import Margins, SpilloverVerdict, margins, spillover
from .modes import FlexibleMode, flexible_modes, rigid_body_inertia
from .timeresp import (METRIC_UNITS, disturbance_response, metrics, slew, slew_profile,
                       step_response)

__all__ = [
    "FlexibleMode",
    "Margins",
    "SpilloverVerdict",
    "METRIC_UNITS",
    "rigid_body_inertia",
    "flexible_modes",
    "close_loop",
    "loop_frequency_response",
    "slew_profile",
    "slew",
    "step_response",
    "disturbance_response",
    "metrics",
    "margins",
    "spillover",
]
