"""The physics: a rigid hub, its mounts, and the spacecraft coupled through the W-matrix
interface.

:mod:`.hub` (the hub and the mounts), :mod:`.kinematics` (small-motion kinematics of the hub in
three axes and the checks of its inputs), :mod:`.coupling` (:class:`Spacecraft`: the coupled
second-order model, its modes and state-space plants) and :mod:`.exact` (the exact references
through W(s) of distributed appendages: coupled frequencies and frequency responses).
Nothing here knows about scenes, controllers' tuning, reports or the command line.
"""

from .coupling import HUB_COORDINATES, SecondOrderModel, Spacecraft
from .exact import ExactReference
from .hub import Hub, Mount

__all__ = ["Hub", "Mount", "Spacecraft", "SecondOrderModel", "ExactReference",
           "HUB_COORDINATES"]
