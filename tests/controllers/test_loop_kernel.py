"""The compiled loop evaluation (controllers._loop_kernel) gives what the numpy path gives.

- L = -K P from the modal sums of plant and controller, planar and three-axis, continuous,
  digital and delayed, equals the evaluators' numpy path to round-off: |L - L_ref| <= 1e-12
  times the sums of the moduli of the terms (|D| + sum |R_k| / |s - lambda_k| + the Markov
  terms, for K and for P; their product bounds the product's error), also beside undamped
  poles where both are huge;
- S = (I + L)^-1 and the loops at a time from the pivoted LU equal numpy's inverse to the
  condition number of I + L times round-off, also for the nearly rank-one huge L beside an
  undamped pole, and are not finite (no exception) where I + L is singular;
- the compiled count of eigenvalues outside the unit circle decides as the numpy one;
- the margins with the numpy path (numba missing) equal those with the kernel to round-off.
"""
import dataclasses
import math

import numpy as np
import pytest

import controllers
from controllers import loop as loop_module
from controllers.loop import LoopTransfer, loops_at_a_time, sensitivity
from plants import modal_plant, three_axis_plant

pytest.importorskip("numba")


def _planar(sample_time=None):
    plant = modal_plant(50.0, [(0.8, 0.0, 0.05, 0.05), (3.1, 0.002, 0.02, 0.02),
                               (17.0, 0.0, 0.01, 0.01)], disturbance=False)
    return plant, controllers.pd(plant, natural_frequency=0.1, damping=0.7,
                                 sample_time=sample_time)


def _three_axis():
    J = np.array([[1200.0, 30.0, -10.0], [30.0, 900.0, 20.0], [-10.0, 20.0, 1500.0]])
    modes = [(0.9, 0.0, np.array([0.02, 0.01, 0.0]), np.array([0.02, 0.01, 0.0])),
             (2.3, 0.003, np.array([0.0, 0.015, 0.01]), np.array([0.0, 0.015, 0.01])),
             (11.0, 0.0, np.array([0.01, -0.01, 0.02]), np.array([0.01, -0.01, 0.02]))]
    plant = three_axis_plant(J, modes)
    j, _ = controllers.principal_axes(J)
    K = controllers.lqr(plant, attitude_weight=(j * 0.1 ** 2) ** 2, rate_weight=0.0,
                        torque_weight=1.0)
    return plant, K


def _moduli(ev, z):
    """Sum of the moduli of the terms of an evaluator's modal sums at z, (f, p, m)."""
    poles, residues, d, markov = ev.modal_sums()
    s = np.asarray(z, dtype=complex) - ev.center
    p, m = ev.C.shape[0], ev.B.shape[1]
    total = (np.abs(1.0 / (s[:, None] - poles)) @ np.abs(residues) + np.abs(d)[None, :])
    if markov.shape[0]:
        powers = np.abs(1.0 / s)[:, None] ** np.arange(1, markov.shape[0] + 1)
        total += powers @ np.abs(markov)
    return total.reshape(s.size, p, m)


def _points(loop):
    """The loop's grid and points 1e-9 and 1e-12 beside its undamped poles."""
    grid = loop.grid()
    w = loop.undamped_frequencies()
    if loop.digital:
        w = w[w < math.pi / loop.dt]
    near = np.concatenate([w * (1 + e) for e in (-1e-9, 1e-9, -1e-12, 1e-12)])
    return np.concatenate([grid, near])


@pytest.mark.parametrize("case", ["planar", "three_axis", "digital", "delayed"])
def test_compiled_loop_equals_the_numpy_path_to_round_off(case):
    plant, K = (_three_axis() if case in ("three_axis", "delayed")
                else _planar(0.5 if case == "digital" else None))
    delay = 0.05 if case == "delayed" else 0.0
    loop = LoopTransfer(plant, K, delay)
    assert loop._sums is not None
    omega = _points(loop)
    L = loop.matrix(omega)
    z = loop._point(omega)
    with np.errstate(all="ignore"):
        reference = -(loop.controller_ev(z) @ loop.plant_ev(z))
        if delay:
            reference = reference * np.exp(-1j * omega * delay)[:, None, None]
        bound = _moduli(loop.controller_ev, z) @ _moduli(loop.plant_ev, z)
    assert np.all(np.isfinite(L))
    assert np.all(np.abs(L - reference) <= 1e-12 * bound)
    # beside the undamped poles L is huge: the bound is the conditioning there, not |L|
    assert np.abs(L).max() > 1e6


def test_sensitivity_equals_numpys_inverse_to_its_conditioning():
    """Random loops over ten decades, and the resonance form (a huge rank-one term over a
    small matrix, L beside an undamped pole): S to cond(I + L) eps, the loops at a time
    1 / S_ii - 1 likewise against numpy's."""
    rng = np.random.default_rng(3)
    n = 3000
    L = ((rng.normal(size=(n, 3, 3)) + 1j * rng.normal(size=(n, 3, 3)))
         * 10.0 ** rng.uniform(-5, 5, size=(n, 1, 1)))
    u = rng.normal(size=(n, 3)) + 1j * rng.normal(size=(n, 3))
    v = rng.normal(size=(n, 3)) + 1j * rng.normal(size=(n, 3))
    resonance = (10.0 ** rng.uniform(3, 10, size=(n, 1, 1)) * u[:, :, None] * v[:, None, :]
                 + 0.3 * (rng.normal(size=(n, 3, 3)) + 1j * rng.normal(size=(n, 3, 3))))
    for stack in (L, resonance):
        R = np.eye(3) + stack
        reference = np.linalg.inv(R)
        S = sensitivity(stack)
        cond = np.linalg.cond(R)
        error = np.linalg.norm(S - reference, axis=(1, 2)) / np.linalg.norm(reference,
                                                                           axis=(1, 2))
        assert np.all(error <= 1e-14 * cond)
        broken = loops_at_a_time(stack)
        exact = 1.0 / np.diagonal(reference, axis1=1, axis2=2) - 1.0
        # 1 / S_ii: relative error cond eps of S_ii's; then - 1: absolute
        scale = 1.0 + np.abs(exact)
        assert np.all(np.abs(broken - exact) <= 1e-14 * cond[:, None] * scale)
    singular = np.array([-np.eye(3), np.full((3, 3), np.nan)], dtype=complex)
    with np.errstate(all="ignore"):
        assert not np.isfinite(sensitivity(singular)).all(axis=(1, 2)).any()


def test_a_point_on_an_undamped_pole_is_not_finite_and_raises_nothing():
    plant, K = _planar()
    loop = LoopTransfer(plant, K)
    L = loop.matrix(np.array([0.8, 1.0]))
    assert not np.isfinite(L[0]).all() and np.isfinite(L[1]).all()


def _flat(m):
    out = {}
    for key, value in vars(m).items():
        if isinstance(value, dict):
            for axis, one in value.items():
                out.update({f"{k}_{axis}": v for k, v in vars(one).items()})
        else:
            out[key] = value
    return out


@pytest.mark.parametrize("case", ["planar", "three_axis"])
def test_margins_without_numba_equal_those_with_the_kernel(case, monkeypatch):
    """The numpy path (numba missing) and the kernel give the same margins to round-off
    (1e-9 relative: a margin is a value at a refined crossing, its frequency found to
    1e-13 relative, its value to the conditioning of L there)."""
    plant, K = _planar() if case == "planar" else _three_axis()
    compiled = _flat(controllers.margins(plant, K))
    monkeypatch.setattr(loop_module, "_kernel", False)
    assert loop_module.compiled_kernel() is None
    plain = _flat(controllers.margins(plant, K))
    assert compiled.keys() == plain.keys()
    for key, value in plain.items():
        if math.isfinite(value):
            assert compiled[key] == pytest.approx(value, rel=1e-9, abs=1e-12), key
        else:
            assert compiled[key] == value, key


@pytest.mark.parametrize("m", [2, 3])
def test_compiled_unit_circle_count_decides_as_the_numpy_one(m):
    """Random stacks over six decades and the resonance form: 0 below a unit Frobenius norm,
    elsewhere the numpy path's Rouche decision (the same arithmetic: equal but where a
    rounding bound is met to the last bit, none here), -2 where L is not finite; every count
    given is the number of eigenvalues outside the circle."""
    from controllers import _loop_kernel
    from controllers.margins import _COEFFICIENT_ERROR, _outside_unit_circle

    rng = np.random.default_rng(5)
    n = 4000
    L = ((rng.normal(size=(n, m, m)) + 1j * rng.normal(size=(n, m, m)))
         * 10.0 ** rng.uniform(-3, 3, size=(n, 1, 1)))
    u = rng.normal(size=(n, m)) + 1j * rng.normal(size=(n, m))
    L[: n // 2] = (10.0 ** rng.uniform(1, 8, size=(n // 2, 1, 1)) * u[: n // 2, :, None]
                   * u[: n // 2, None, :].conj() + 1e-2 * L[: n // 2])
    L[7, 1, 0] = np.nan
    L[9, 0, 0] = np.inf
    count = np.empty(n, dtype=np.int64)
    _loop_kernel.unit_circle_count(L, _COEFFICIENT_ERROR, count)
    finite = np.all(np.isfinite(L), axis=(1, 2))
    assert np.array_equal(count == -2, ~finite)
    with np.errstate(invalid="ignore"):
        small = finite & (np.linalg.norm(L, axis=(1, 2)) < 1.0)
    assert np.all(count[small] == 0)
    rest = finite & ~small
    np.testing.assert_array_equal(count[rest], _outside_unit_circle(L[rest]))
    decided = count >= 0
    exact = np.sum(np.abs(np.linalg.eigvals(L[decided])) > 1.0, axis=1)
    np.testing.assert_array_equal(count[decided], exact)
    assert decided.mean() > 0.5


@pytest.mark.parametrize("m", [1, 2, 3])
def test_compiled_eigenvalues_are_backward_stable_and_numpys(m):
    """The compiled small-matrix eigenvalues (balancing, Householder, shifted complex QR):
    random stacks over six decades and the resonance form (huge, nearly rank one) plus
    matrices with repeated eigenvalues, a Jordan block, a permutation and zero.
    - backward stable: sigma_min(L - lambda I) <= 50 eps ||L||_F for each eigenvalue (an exact
      eigenvalue of a matrix within that of L; measured up to ~8 eps), and the sum of the
      eigenvalues is the trace to 50 eps ||L||_F (so no eigenvalue is counted twice);
    - the random ones (well-conditioned eigenvalues) equal numpy's to 1e-12 ||L||_F (two
      backward stable algorithms differ by the condition number times round-off; measured
      ~3e-15), and their counts outside the unit circle agree wherever no eigenvalue is within
      1e-9 of the circle."""
    from controllers import _loop_kernel

    rng = np.random.default_rng(11)
    n = 3000
    L = ((rng.normal(size=(n, m, m)) + 1j * rng.normal(size=(n, m, m)))
         * 10.0 ** rng.uniform(-3, 3, size=(n, 1, 1)))
    u = rng.normal(size=(n, m)) + 1j * rng.normal(size=(n, m))
    L[: n // 2] = (10.0 ** rng.uniform(1, 9, size=(n // 2, 1, 1)) * u[: n // 2, :, None]
                   * u[: n // 2, None, :].conj() + 1e-2 * L[: n // 2])
    special = [np.zeros((m, m)), np.eye(m), np.eye(m, k=1) + np.eye(m),
               np.roll(np.eye(m), 1, axis=0), np.diag(10.0 ** np.linspace(-9, 9, m))]
    L = np.concatenate([L, np.array(special, dtype=complex)])
    lam = np.empty(L.shape[:2], dtype=complex)
    converged = np.empty(L.shape[0], dtype=np.bool_)
    _loop_kernel.eigenvalues(L, lam, converged)
    assert converged.all()
    eps = np.finfo(float).eps
    norm = np.linalg.norm(L, axis=(1, 2))
    residual = np.linalg.svd(L[:, None] - lam[:, :, None, None] * np.eye(m),
                             compute_uv=False)[..., -1]
    np.testing.assert_array_less(residual, np.broadcast_to(50 * eps * norm[:, None] + 1e-300,
                                                          residual.shape))
    np.testing.assert_array_less(np.abs(lam.sum(axis=1) - np.trace(L, axis1=1, axis2=2)),
                                 50 * eps * norm + 1e-300)
    random = slice(0, n)
    reference = np.linalg.eigvals(L[random])
    apart = np.abs(lam[random, :, None] - reference[:, None, :]).min(axis=2)
    np.testing.assert_array_less(apart, np.broadcast_to(1e-12 * norm[random, None], apart.shape))
    clear = np.all(np.abs(np.abs(reference) - 1.0) > 1e-9, axis=1)
    np.testing.assert_array_equal(np.sum(np.abs(lam[random][clear]) > 1.0, axis=1),
                                  np.sum(np.abs(reference[clear]) > 1.0, axis=1))


def test_shifted_frobenius_and_shifted_peaks_are_numpys():
    """||S - c I||_F compiled equals numpy's norm of the formed difference to 1e-14 relative
    (sums of squares in another order; measured ~2e-16), is not finite where S is not, and the
    shifted peak singular values equal those of the formed difference (the same points'
    closed forms: 1e-12 relative, the closed form's own accuracy)."""
    from controllers import _loop_kernel
    from controllers.margins import _peak_singular_values

    rng = np.random.default_rng(8)
    S = (rng.normal(size=(500, 3, 3)) + 1j * rng.normal(size=(500, 3, 3))) * 10.0 ** rng.uniform(
        -3, 3, size=(500, 1, 1))
    out = np.empty(500)
    _loop_kernel.shifted_frobenius(S, 0.5, out)
    np.testing.assert_allclose(out, np.linalg.norm(S - 0.5 * np.eye(3), axis=(1, 2)),
                               rtol=1e-14, atol=0)
    S[3, 1, 2] = np.nan
    _loop_kernel.shifted_frobenius(S[:5], 0.5, out[:5])
    assert not np.isfinite(out[3]) and np.isfinite(out[[0, 1, 2, 4]]).all()
    S = S[4:]
    np.testing.assert_allclose(_peak_singular_values(S, 0.5),
                               _peak_singular_values(S - 0.5 * np.eye(3)), rtol=1e-12, atol=0)
