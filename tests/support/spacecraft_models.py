"""Spacecraft the tests build in Python (not from a scene)."""
from __future__ import annotations

import math

import numpy as np

from appendages import Beam
from spacecraft import Hub, Mount, Spacecraft
from spacecraft.dynamics.kinematics import euler_orientation, orientation_from_axis

__all__ = ["twin_wings"]

CANT = math.radians(20.0)


def twin_wings(n_modes: int, youngs_right: float = 7e8) -> Spacecraft:
    """The shipped three-axis example's layout: two canted rectangular wings along +-y (twins:
    the right one's Young's modulus ``youngs_right`` [Pa]) and a tube boom off every principal
    axis, each beam truncated to its ``n_modes`` lowest Craig-Bampton modes and at least 5 of
    torsion and 2 of x-z bending (as the shipped three-axis scene's tip outputs ask)."""
    motions = {"xy": 1, "xz": 2, "torsion": 5}
    wing = Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8, damping_ratio=0.005).truncated(
        n_modes, modes_per_motion=motions)
    right = Beam.rectangular(6.0, 2.0, 0.04, 40.0, youngs_right, damping_ratio=0.005).truncated(
        n_modes, modes_per_motion=motions)
    boom = Beam.tube(4.0, 0.05, 0.001, 1600.0, 1.2e11, damping_ratio=0.005).truncated(
        n_modes, modes_per_motion=motions)
    inertia = np.array([[950.0, 12.0, -8.0], [12.0, 780.0, 15.0], [-8.0, 15.0, 640.0]])
    return Spacecraft(Hub(820.0, inertia), [
        Mount(wing, (0.0, 1.1, 0.0), orientation=euler_orientation("ZYX", (math.pi / 2, 0.0, CANT)),
              name="wing_left"),
        Mount(right, (0.0, -1.1, 0.0),
              orientation=euler_orientation("ZYX", (-math.pi / 2, 0.0, CANT)), name="wing_right"),
        Mount(boom, (0.6, 0.3, -0.9), orientation=orientation_from_axis((1.0, -0.5, -1.2)),
              name="boom")])
