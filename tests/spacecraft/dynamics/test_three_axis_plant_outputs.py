"""The plant's requested outputs in the order of their names, planar and three-axis.

``Spacecraft.plant(tip_deflection=True, root_loads=True)`` names its outputs appendage by
appendage (each appendage's tip motions, then its root loads); the rows of C and D must
follow the names. Reference: the same plant asked for one kind of output at a time, whose
rows are not interleaved (the modal realisation is the same, so the rows agree exactly).
"""

import math

import numpy as np
import pytest

from appendages import Beam
from spacecraft import Hub, Mount, Spacecraft
from spacecraft.dynamics.kinematics import euler_orientation, orientation_from_axis


def planar() -> Spacecraft:
    rod = Beam.circular_rod(2.0, 0.02, 2700.0, 7e10)
    return Spacecraft(Hub(100.0, 10.0), [
        Mount(rod.truncated(3), (0.5, 0.0), (1.0, 0.0), name="a"),
        Mount(Beam.circular_rod(1.5, 0.02, 2700.0, 7e10).truncated(3), (-0.5, 0.2), (-1.0, 0.3),
              name="b")])


def three_axis() -> Spacecraft:
    wing = Beam.rectangular(3.0, 1.0, 0.03, 40.0, 7e8)
    boom = Beam.tube(2.0, 0.05, 0.001, 1600.0, 1.2e11)
    J = np.array([[95.0, 1.2, -0.8], [1.2, 78.0, 1.5], [-0.8, 1.5, 64.0]])
    return Spacecraft(Hub(80.0, J), [
        Mount(wing.truncated(3), (0.0, 0.6, 0.0),
              orientation=euler_orientation("ZYX", (math.pi / 2, 0.0, 0.3)), name="wing"),
        Mount(boom.truncated(3), (0.3, 0.1, -0.4), orientation=orientation_from_axis((1.0, -0.5, -1.2)),
              name="boom")])


@pytest.mark.parametrize("build", [planar, three_axis])
def test_rows_follow_the_output_names_with_tips_and_root_loads(build):
    both = build().plant(tip_deflection=True, root_loads=True)
    tips = build().plant(tip_deflection=True)
    loads = build().plant(root_loads=True)
    np.testing.assert_array_equal(both.A, tips.A)
    names = list(both.output_labels)
    assert set(names) == set(tips.output_labels) | set(loads.output_labels)
    # names interleave: every appendage's tips come before its loads and after the previous
    # appendage's loads
    assert names.index("a_root_force" if build is planar else "wing_root_force_x") < \
        names.index("b_tip_deflection" if build is planar else "boom_tip_deflection_y")
    for single in (tips, loads):
        for k, name in enumerate(single.output_labels):
            row = names.index(name)
            # the same products of the same matrices: equal to the last bit
            np.testing.assert_array_equal(both.C[row], single.C[k], err_msg=name)
            np.testing.assert_array_equal(both.D[row], single.D[k], err_msg=name)
    # the root loads feed through from torque (D != 0) and the tip motions do not
    for k, name in enumerate(names):
        if "root" in name and "moment" in name:
            assert np.any(both.D[k] != 0), name
        if "tip" in name:
            assert not np.any(both.D[k]), name
