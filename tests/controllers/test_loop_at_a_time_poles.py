"""The poles of the loops at a time (LoopTransfer.loop_at_a_time_poles, from plain arrays) are
those of the closed loop with one torque's loop open, built by close_loop with that torque's
controller row zeroed: continuous and digital, with and without a controller feedthrough."""
import control
import numpy as np
import pytest

import controllers
from controllers.loop import LoopTransfer
from plants import three_axis_plant

J = np.array([[1200.0, 80.0, -40.0], [80.0, 900.0, 30.0], [-40.0, 30.0, 1500.0]])
PHI1, PHI2, PHI3 = (np.array([0.010, 0.020, 0.0]), np.array([0.0, 0.010, 0.015]),
                    np.array([0.004, 0.0, 0.006]))
PLANT = three_axis_plant(J, [(2.1, 0.005, PHI1, PHI1), (5.2, 0.0, PHI2, PHI2),
                             (17.0, 0.005, PHI3, PHI3)])


def _cut(controller, i):
    """The controller with torque output i zeroed (its loop open), as a python-control system."""
    rows = np.arange(controller.noutputs)[:, None] == i
    return control.ss(controller.A, controller.B, np.where(rows, 0.0, controller.C),
                      np.where(rows, 0.0, controller.D), controller.dt,
                      inputs=list(controller.input_labels),
                      outputs=list(controller.output_labels))


def _controllers():
    pd = controllers.pd(PLANT, natural_frequency=0.1, damping=0.7)
    lqr = controllers.lqr(PLANT, attitude_weight=(900 * 0.01) ** 2, rate_weight=0.0,
                          torque_weight=1.0)
    digital = controllers.lqr(PLANT, attitude_weight=(900 * 0.01) ** 2, rate_weight=0.0,
                              torque_weight=1.0, sample_time=0.5)
    return {"pd": pd, "lqr": lqr, "digital lqr": digital}


@pytest.mark.parametrize("name", ["pd", "lqr", "digital lqr"])
def test_loop_at_a_time_poles_are_the_cut_closed_loops(name):
    """Each loop's poles equal the eigenvalues of close_loop(plant, cut).A (the same matrices,
    formed without the signal-name objects): every pole within 1e-9 of the largest pole's
    modulus of one of the other's (eigenvalues of the same matrix to round-off; the
    undamped mode's conjugate pair is well separated)."""
    controller = _controllers()[name]
    loop = LoopTransfer(PLANT, controller)
    poles = loop.loop_at_a_time_poles()
    reference = np.concatenate([np.linalg.eigvals(controllers.close_loop(PLANT, _cut(
        controller, i)).A) for i in range(3)])
    assert poles.shape == reference.shape
    scale = np.abs(reference).max()
    for got, want in ((poles, reference), (reference, poles)):
        distance = np.abs(got[:, None] - want[None, :]).min(axis=1)
        np.testing.assert_array_less(distance, 1e-9 * scale)

