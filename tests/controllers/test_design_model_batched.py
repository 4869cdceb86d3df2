"""The design model's batched check of a modal plant (controllers.modes): it decides "nothing
to remove" only where the per-part analysis does, and the LQR designed through it is the one
designed through the per-part analysis, to the last bit."""
import warnings

import control
import numpy as np
import pytest
import scipy.linalg
import scipy.sparse.csgraph

import controllers
from controllers import modes
from controllers.lqr import lqr_design
from plants import modal_plant

J = 250.0  # kg m^2
WEIGHTS = dict(attitude_weight=400.0, rate_weight=1000.0, torque_weight=1.0)


def _per_part(monkeypatch):
    """Disable the batched check: design_model analyses every part on its own."""
    monkeypatch.setattr(modes, "_nothing_to_remove", lambda *args: False)


def _three_axis_modal(rng, n_modes, *, stuck=()):
    """A three-axis hub (full inertia tensor) with n_modes modal 2 x 2 blocks; the modes in
    ``stuck`` are undamped and not reached by any torque (participation 0)."""
    Jt = np.array([[950.0, 12.0, -8.0], [12.0, 780.0, 15.0], [-8.0, 15.0, 640.0]])
    Ji = np.linalg.inv(Jt)
    n = 6 + 2 * n_modes
    A = np.zeros((n, n))
    B = np.zeros((n, 3))
    C = np.zeros((6, n))
    for i in range(3):
        A[i, 3 + i] = 1.0
        C[i, i] = C[3 + i, 3 + i] = 1.0
    B[3:6] = Ji
    w = np.sort(rng.uniform(2.0, 900.0, n_modes))
    for k in range(n_modes):
        i = 6 + 2 * k
        zeta = 0.0 if k in stuck else 0.005
        A[i, i + 1], A[i + 1, i], A[i + 1, i + 1] = 1.0, -w[k] ** 2, -2 * zeta * w[k]
        phi = 0.0 if k in stuck else 1.0
        B[i + 1] = phi * rng.standard_normal(3) * 1e-2
        C[:3, i] = rng.standard_normal(3) * 1e-2
        C[3:, i + 1] = C[:3, i]
    names = [f"torque_{a}" for a in "xyz"]
    outputs = [f"theta_{a}" for a in "xyz"] + [f"omega_{a}" for a in "xyz"]
    return control.ss(A, B, C, 0, inputs=names, outputs=outputs)


@pytest.mark.parametrize("plant", [
    modal_plant(J, [(2.1, 0.005, 0.041, 0.041), (12.0, 0.0, 0.015, 0.015),
                    (35.0, 0.005, 0.006, 0.006)]),
    modal_plant(J, [(2.0, 0.0, 0.04, 0.04), (30.0, 0.0, 0.0, 0.02), (45.0, 0.0, 0.03, 0.0)]),
    modal_plant(J, [(2.0, 0.0, 0.04, 0.04), (2.0, 0.0, 0.04, 0.04)]),   # a repeated mode
    _three_axis_modal(np.random.default_rng(3), 20),
    _three_axis_modal(np.random.default_rng(4), 20, stuck=(3, 11)),
], ids=["beam", "stuck", "repeated", "three_axis", "three_axis_stuck"])
def test_batched_check_agrees_with_the_per_part_analysis(plant, monkeypatch):
    """Same design plant, same removed modes (or the same refusal) either way; the batched
    check says "nothing to remove" only when the per-part analysis removes nothing."""
    Jp = controllers.rigid_body_inertia(plant)

    def run():
        try:
            return modes.design_model(plant, critical=1e-9, J=Jp, what="test")
        except ValueError as error:
            return str(error)

    batched = run()
    _per_part(monkeypatch)
    per_part = run()
    if isinstance(per_part, str):
        assert batched == per_part
        return
    design_b, removed_b, eigs_b = batched
    design_p, removed_p, eigs_p = per_part
    assert removed_b == removed_p
    np.testing.assert_array_equal(eigs_b, eigs_p)
    for name in "ABCD":
        np.testing.assert_array_equal(getattr(design_b, name), getattr(design_p, name))


def test_batched_check_declines_what_it_cannot_decide():
    """A removable mode (participation 0), a repeated undamped mode and a part larger than
    2 x 2 (a non-modal realisation) go to the per-part analysis."""
    def check(plant):
        A = np.asarray(plant.A, dtype=float)
        b, ct, co = modes._channel_rows(plant)
        Ab, (d, _) = scipy.linalg.matrix_balance(A, permute=False, separate=True)
        n_parts, part_of = scipy.sparse.csgraph.connected_components(
            A != 0.0, directed=True, connection="weak")
        norm = np.linalg.norm(Ab, 1)
        return modes._nothing_to_remove(
            Ab, d, part_of, n_parts, b, ct, co,
            modes._sqrt_inertia(controllers.rigid_body_inertia(plant)), 1e-9,
            1e-6 * np.sqrt(max(norm, 1.0)), modes._CLUSTER_RTOL * norm)

    assert check(modal_plant(J, [(2.1, 0.005, 0.041, 0.041), (12.0, 0.0, 0.015, 0.015)]))
    assert not check(modal_plant(J, [(2.0, 0.0, 0.04, 0.04), (30.0, 0.0, 0.0, 0.02)]))
    assert not check(modal_plant(J, [(2.0, 0.0, 0.04, 0.04), (2.0, 0.0, 0.03, 0.03)]))
    dense = modal_plant(J, [(2.0, 0.005, 0.04, 0.04), (7.0, 0.005, 0.03, 0.03)])
    S = np.random.default_rng(1).standard_normal((6, 6)) + 4 * np.eye(6)
    mixed = control.ss(S @ dense.A @ np.linalg.inv(S), S @ dense.B, dense.C @ np.linalg.inv(S),
                       dense.D, inputs=list(dense.input_labels),
                       outputs=list(dense.output_labels))
    assert not check(mixed)


def test_lqr_through_the_batched_check_is_bit_identical(monkeypatch):
    """The LQR on a three-axis modal plant: gains, estimator and controller matrices are those
    of the per-part analysis exactly (the batched check only skips work)."""
    plant = _three_axis_modal(np.random.default_rng(5), 12)
    weights = dict(attitude_weight=(1e3 * 0.1 ** 2) ** 2, rate_weight=0.0, torque_weight=1.0)
    decided = []
    batched = modes._nothing_to_remove
    monkeypatch.setattr(modes, "_nothing_to_remove",
                        lambda *args: decided.append(batched(*args)) or decided[-1])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fast = lqr_design(plant, **weights)
        assert decided == [True]     # the batched check decided
        _per_part(monkeypatch)
        slow = lqr_design(plant, **weights)
    np.testing.assert_array_equal(fast.K, slow.K)
    np.testing.assert_array_equal(fast.L, slow.L)
    for name in "ABCD":
        np.testing.assert_array_equal(getattr(fast.controller, name),
                                      getattr(slow.controller, name))
