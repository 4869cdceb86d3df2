"""A truth model's tip output that no kept mode moves is said, not reported as a silent 0.

A three-axis truncation to a given n_modes keeps the lowest modes of all motions of a beam
together; a stiff motion (a wing's in-plane bending, a boom's torsion) may keep none, and its
tip output's row of the plant is then zero by construction."""
import control
import numpy as np
import pytest

import spacecraft
from spacecraft.design.loop import DesignLoop, unmodelled_outputs


def _plant(C, D, names):
    A = -np.eye(2)
    B = np.ones((2, 1))
    return control.ss(A, B, np.asarray(C, float), np.asarray(D, float), inputs=["torque"],
                      outputs=names)


def test_zero_rows_of_tip_outputs_are_named():
    names = ["theta", "wing_tip_deflection_y", "wing_tip_deflection_z", "boom_tip_twist"]
    C = [[1, 0], [0, 1e-30], [0, 0], [0, 0]]
    D = [[0], [0], [0], [1e-3]]
    (warning,) = unmodelled_outputs(_plant(C, D, names))
    assert warning["code"] == "truth_output_unmodelled"
    # a row with any entry, however small, is modelled; theta is no tip output
    assert "wing_tip_deflection_z" in warning["message"]
    for name in ("wing_tip_deflection_y", "boom_tip_twist", "theta"):
        assert name not in warning["message"]


def test_every_tip_output_modelled_gives_no_warning():
    names = ["theta", "rod_tip_deflection"]
    assert unmodelled_outputs(_plant([[1, 0], [0, 1]], [[0], [0]], names)) == []


@pytest.mark.slow
def test_the_shipped_flown_three_axis_scene_says_which_tips_its_truth_cannot_move():
    # a given n_modes keeps the 3 lowest of all motions (a tolerance-driven choice keeps a
    # mode of every motion a tip output sees: test_truth_motions.py)
    scene = spacecraft.load_scene("three_axis_flown", overrides={"export.fmu": False,
                                                                 "fidelity.n_modes": 3,
                                                                 "fidelity.tolerance": None})
    result = DesignLoop(scene).run()
    (warning,) = [w for w in result.data["design_warnings"]
                  if w["code"] == "truth_output_unmodelled"]
    peaks = result.data["closed_loops"][0]["appendages"]["truth"]
    # every output it names reads exactly 0 on the truth model, and every other tip does not
    for name, motions in peaks.items():
        for key, value in motions.items():
            motion = key.replace("peak_", "")
            named = f"{name}_{motion}" in warning["message"]
            assert (value == 0.0) is named, f"{name} {key}: {value}"
