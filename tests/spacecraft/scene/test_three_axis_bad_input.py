"""Bad three-axis input (issue 11, "Bad input"): each error names the parameter, its unit,
what was expected and what was got, and echoes no large array. Complements
tests/spacecraft/dynamics/test_three_axis_spacecraft.py::test_bad_three_axis_input_is_named."""

import math

import numpy as np
import pytest

from appendages import Beam, HingedChain
from spacecraft import Hub, Mount, Spacecraft
from spacecraft.dynamics.kinematics import euler_orientation

TUBE = Beam.tube(4.0, 0.05, 0.001, 1600.0, 1.2e11)
J3 = np.array([[950.0, 12.0, -8.0], [12.0, 780.0, 15.0], [-8.0, 15.0, 640.0]])


@pytest.mark.parametrize("inertia, match", [
    # non-symmetric: the largest asymmetry and the tolerance
    ([[950.0, 12.0, 0.0], [11.0, 780.0, 0.0], [0.0, 0.0, 640.0]],
     r"hub inertia must be a symmetric tensor \[kg\*m\^2\] \(J = J\^T to 1e-09 relative\); "
     r"got max \|J - J\^T\| = 1 of 950"),
    # positive diagonal, indefinite (|J_xy| > sqrt(J_xx J_yy)): the principal moments
    ([[950.0, 900.0, 0.0], [900.0, 780.0, 0.0], [0.0, 0.0, 640.0]],
     r"hub inertia must be positive definite \[kg\*m\^2\]; got principal moments \(-39\.0"),
    # positive semi-definite (a zero principal moment)
    ([[1.0, 1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
     r"hub inertia must be positive definite \[kg\*m\^2\]"),
    (np.diag([1.0, np.nan, 1.0]), r"hub inertia must be finite \[kg\*m\^2\]"),
    # positive definite but no body's: the largest principal moment exceeds the sum of the
    # other two (a body's j1 + j2 - j3 = 2 * integral of z^2 dm >= 0 in principal axes)
    (np.diag([1.0, 1.0, 100.0]),
     r"hub inertia must be the inertia of a body \[kg\*m\^2\].*triangle inequality.*got "
     r"principal moments \(1\.0, 1\.0, 100\.0\), 100 > 1 \+ 1"),
    # the same in rotated axes (the check is on the principal moments, not the diagonal)
    (euler_orientation("ZYX", (0.3, 0.2, 0.1)) @ np.diag([1.0, 2.0, 3.5])
     @ euler_orientation("ZYX", (0.3, 0.2, 0.1)).T,
     r"hub inertia must be the inertia of a body.*3\.5 > 1 \+ 2"),
])
def test_inertia_tensor(inertia, match):
    with pytest.raises(ValueError, match=match):
        Hub(820.0, inertia)


@pytest.mark.parametrize("moments", [(1.0, 1.0, 2.0), (1.0, 2.0, 3.0), (3.0, 2.0, 1.0)])
def test_flat_plate_inertia_is_accepted(moments):
    """Equality in the triangle inequality is a flat plate (j3 = j1 + j2), a real body."""
    R = euler_orientation("ZYX", (0.3, 0.2, 0.1))
    assert Hub(820.0, R @ np.diag(moments) @ R.T).three_axis


def test_inertia_of_no_body_in_a_scene_is_refused_by_key():
    from spacecraft import SceneError, load_scene
    from spacecraft.scene.read import scene_path
    import tomllib

    with open(scene_path("three_axis"), "rb") as stream:
        data = tomllib.load(stream)
    data["hub"]["inertia"] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 100.0]]
    with pytest.raises(SceneError, match=r"hub\.inertia: must be the inertia of a body "
                                         r"\[kg\*m\^2\].*100 > 1 \+ 1"):
        load_scene(data)


def test_inertia_of_a_wrong_shape_is_not_echoed_in_full():
    with pytest.raises(ValueError, match=r"hub inertia must have shape \(3, 3\) \[kg\*m\^2\]; "
                                         r"got shape \(300, 300\)") as info:
        Hub(820.0, np.ones((300, 300)))
    assert len(str(info.value)) < 300


@pytest.mark.parametrize("orientation, match", [
    # orthonormal columns, det = -1 (a reflection: two axes swapped)
    ([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
     r"orientation must be a rotation matrix \[-\] .*orthonormal to 1e-09, det = \+1\); "
     r"got max \|R\^T R - I\| = 0, det = -1"),
    # columns not orthonormal to 1e-9 (a column 2e-9 too long: R^T R - I = 4e-9)
    (np.eye(3) + np.diag([2e-9, 0.0, 0.0]),
     r"orientation must be a rotation matrix \[-\].*got max \|R\^T R - I\| = 4e-09"),
    # orthogonal but scaled
    (2.0 * euler_orientation("ZYX", (0.3, 0.2, 0.1)),
     r"orientation must be a rotation matrix \[-\].*got max \|R\^T R - I\| = 3, det = 8"),
    (np.full((3, 3), np.nan), r"orientation must be finite \[-\]"),
])
def test_orientation_that_is_not_a_rotation(orientation, match):
    with pytest.raises(ValueError, match=match):
        Mount(TUBE, (0.0, 0.0, 0.0), orientation=orientation)


def test_orientation_within_the_tolerance_is_accepted():
    """|R^T R - I| = 2e-10 (a column 1e-10 too long) is within 1e-9: accepted."""
    mount = Mount(TUBE, (0.0, 0.0, 0.0), orientation=np.eye(3) + np.diag([1e-10, 0.0, 0.0]))
    assert mount.three_axis


def test_orientation_of_a_wrong_shape_is_not_echoed_in_full():
    with pytest.raises(ValueError, match=r"orientation must have shape \(3, 3\) \[-\]") as info:
        Mount(TUBE, (0.0, 0.0, 0.0), orientation=np.ones((300, 300)))
    assert len(str(info.value)) < 300


def test_euler_sequence_with_a_repeated_consecutive_axis_is_named():
    """Before: scipy's own message ("Expected consecutive axes to be different"), which names
    neither the parameter nor what is allowed."""
    with pytest.raises(ValueError, match=r"sequence must be three axes from 'xyz' \(extrinsic\) "
                                         r"or 'XYZ' \(intrinsic\), no two consecutive alike.*"
                                         r"got 'ZZX'"):
        euler_orientation("ZZX", (0.1, 0.2, 0.3))
    # a proper Euler sequence (first and last alike) is fine
    R = euler_orientation("zxz", (0.1, 0.2, 0.3))
    np.testing.assert_allclose(R.T @ R, np.eye(3), rtol=0, atol=1e-15)


def test_three_axis_mount_of_a_planar_beam_names_the_mount_and_the_missing_property():
    """A beam without torsional properties cannot twist: a three-axis mount needs
    torsional_inertia [kg*m] (and GJ); the error names the mount."""
    with pytest.raises(ValueError, match=r"three-axis mount 'wing' \(orientation given\): .*"
                                         r"torsional_inertia \[kg\*m\] .*got torsional_inertia "
                                         r"= None"):
        Mount(Beam(6.0, 1e4, 3.2), (0.0, 1.0, 0.0), orientation=np.eye(3), name="wing")
    with pytest.raises(ValueError, match=r"three-axis mount 'wing' .*torsional_inertia \[kg\*m\]"):
        Mount(Beam(6.0, 1e4, 3.2).truncated(3), (0.0, 1.0, 0.0), orientation=np.eye(3),
              name="wing")


def test_three_axis_mount_of_a_planar_chain_names_the_missing_property():
    chain = HingedChain.three_body(6.0, 19.2, 0.27, 40.0)
    with pytest.raises(ValueError, match=r"three-axis mount 'wing' .*torsional_inertias "
                                         r"\[kg\*m\^2\].*got torsional_inertias = None"):
        Mount(chain, (0.0, 1.0, 0.0), orientation=np.eye(3), name="wing")


def test_torsional_stiffness_without_torsional_inertia():
    with pytest.raises(ValueError, match=r"torsional_inertia \[kg\*m\] .* must be given with "
                                         r"torsional_stiffness = 1000.0 N\*m\^2; got None"):
        Beam(6.0, 1e4, 3.2, torsional_stiffness=1e3)


def test_W6_of_a_planar_beam_names_the_missing_property():
    with pytest.raises(ValueError, match=r"W6 needs the beam's torsion: torsional_inertia \[kg\*m\]"):
        Beam(6.0, 1e4, 3.2, axial_stiffness=1e6).W6(1j)


def test_planar_mount_on_a_three_axis_hub_names_the_hub_and_the_mount():
    with pytest.raises(ValueError, match=r"mount 'boom' on a three-axis hub: .*torsional_inertia"):
        Spacecraft(Hub(820.0, J3), [Mount(Beam(4.0, 1e4, 1.0), (0.0, 0.0), math.pi / 4,
                                          name="boom")])
