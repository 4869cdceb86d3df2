"""Frequency responses that scale: modal set-up, chunked sweeps, loop zeros, FRDs, Riccati."""
import tracemalloc

import control
import numpy as np
import pytest
import scipy.linalg

import controllers
from controllers import frequency as frequency_module
from controllers.frequency import ModalEvaluator, modal_evaluator, siso_zeros
from plants import modal_plant

J = 250.0  # kg m^2


def _many_modes(n_modes, zeta=0.002):
    rng = np.random.default_rng(n_modes)
    w = np.sort(rng.uniform(1.0, 500.0, n_modes))
    phi = rng.uniform(0.005, 0.05, n_modes)
    return modal_plant(J, [(wk, zeta, pk, pk) for wk, pk in zip(w, phi)],
                       tips=[("wing_tip_deflection", list(rng.uniform(-1, 1, n_modes)))])


def _resolvent(plant, s):
    return np.array([plant.C @ np.linalg.solve(sk * np.eye(plant.nstates) - plant.A, plant.B)
                     + plant.D for sk in s])


def test_modal_plant_is_set_up_without_a_schur_form_of_its_whole_A(monkeypatch):
    """The decoupled 2 x 2 modal blocks are diagonalised together; the only Schur form taken is
    the rigid-body block's (2 states): the set-up is O(n), not O(n^3). The response agrees with
    the resolvent to round-off (modes of condition ~1: 1e-12 relative to max |G|)."""
    sizes = []
    original = scipy.linalg.schur

    def recording(a, *args, **kwargs):
        sizes.append(np.shape(a)[0])
        return original(a, *args, **kwargs)

    monkeypatch.setattr(frequency_module.scipy.linalg, "schur", recording)
    plant = _many_modes(60)
    ev = modal_evaluator(plant, ["torque", "disturbance_torque"], ["theta", "omega",
                                                                   "wing_tip_deflection"])
    assert sizes == [2] and ev.modal and ev.k == 2 and ev.lam.size == 120
    s = 1j * np.array([0.01, 0.9, 3.3, 47.0, 212.0, 1e4]) + 0.05
    G, ref = ev(s), _resolvent(plant, s)
    for Gk, rk in zip(G, ref):
        np.testing.assert_allclose(Gk, rk, rtol=1e-12, atol=1e-12 * np.abs(rk).max())


def test_defective_flexible_block_is_solved_densely():
    """A critically damped mode (zeta = 1: a double real eigenvalue -w with one eigenvector)
    cannot be diagonalised: its part is kept as it is and solved at each point, the rest of the
    plant stays modal. Closed form of the part: b c / (s + w)^2."""
    plant = modal_plant(J, [(2.0, 1.0, 0.3, 0.3), (7.0, 0.01, 0.1, 0.1)], disturbance=False)
    ev = modal_evaluator(plant, ["torque"], ["theta"])
    assert not ev.modal and len(ev.dense) == 1 and ev.lam.size == 2
    s = np.array([0.5j, 2.0j, 6.9j, 30.0j])
    expected = 1 / (J * s ** 2) + 0.09 / (s + 2.0) ** 2 + 0.01 / (s ** 2 + 0.14 * s + 49.0)
    # the 2 x 2 solve and the partial fractions: round-off relative to the largest term
    np.testing.assert_allclose(ev(s)[:, 0, 0], expected, rtol=1e-12)
    assert sorted(np.round(np.abs(ev.poles()), 9)) == [0.0, 0.0, 2.0, 2.0, 7.0, 7.0]


def test_sweep_memory_is_bounded_by_chunking(monkeypatch):
    """20,000 frequencies of a 100-mode plant: unchunked, 1 / (s - lambda) alone would take
    20,000 x 202 x 16 B = 65 MB; in chunks of CHUNK_BYTES = 1 MB the traced peak stays below
    the result (20,000 x 3 x 2 x 16 B = 1.9 MB) plus a few chunks. The chunks change nothing
    but the BLAS blocking of the sum over the poles (its order, with several threads): round-off
    of 202 terms, 1e-12 relative to the largest response."""
    plant = _many_modes(100)
    ev = modal_evaluator(plant, ["torque", "disturbance_torque"], ["theta", "omega",
                                                                   "wing_tip_deflection"])
    s = 1j * np.logspace(-2, 3, 20_000)
    monkeypatch.setattr(frequency_module, "CHUNK_BYTES", 1 << 20)
    tracemalloc.start()
    G = ev(s)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 10e6
    monkeypatch.setattr(frequency_module, "CHUNK_BYTES", 1 << 40)
    np.testing.assert_allclose(ev(s[:3000]), G[:3000], rtol=1e-12,
                               atol=1e-12 * np.abs(G).max())


@pytest.mark.parametrize("seed", range(8))
def test_siso_zeros_against_the_numerator(seed):
    """Zeros from the Householder reduction equal the roots of the transfer function's
    numerator (scipy.signal.ss2tf), for d != 0 and for relative degrees 1 to 3 (c A^k b = 0,
    k < r - 1, made by construction): n - r of them. For these random 7-state systems the
    numerator's roots are conditioned to ~1e-10 relative (checked against a long-double
    evaluation when the test was written), hence 1e-7."""
    import scipy.signal

    rng = np.random.default_rng(seed)
    n = 7
    A = rng.standard_normal((n, n))
    b = rng.standard_normal(n)
    c = rng.standard_normal(n)
    degree = seed % 4  # 0: d != 0
    d = rng.standard_normal() if degree == 0 else 0.0
    if degree > 1:  # c orthogonal to b, A b, ..., A^(degree-2) b
        basis = np.linalg.qr(np.column_stack([np.linalg.matrix_power(A, j) @ b
                                              for j in range(degree - 1)]))[0]
        c = c - basis @ (basis.T @ c)
    num, _ = scipy.signal.ss2tf(A, b[:, None], c[None, :], [[d]])
    num = np.trim_zeros(np.where(np.abs(num[0]) > 1e-10 * np.abs(num[0]).max(), num[0], 0.0),
                        "f")
    ref = np.roots(num)
    z = siso_zeros(A, b, c, d)
    assert z.size == ref.size == n - degree
    for x in ref:
        assert np.min(np.abs(z - x)) < 1e-7 * max(1.0, abs(x))


def test_siso_zeros_closed_forms():
    """PD on a rigid hub: L = (Kp + Kd s) / (J s^2) has one zero, -Kp / Kd; a double integrator
    has none; a lightly damped mode's antiresonance of 1/(J s^2) + p^2/(s^2 + w^2) sits at
    w / sqrt(1 + p^2 J) (collocated: the zero of J s^2 + ... below the pole)."""
    Kp, Kd = 25.0, 70.0
    A = np.array([[0.0, 1.0], [0.0, 0.0]])
    b = np.array([0.0, 1.0 / J])
    # one backward-stable Householder step and a 1 x 1 eigenproblem (Higham 2002, sec. 19.3)
    # for a well-conditioned zero (||c|| / Kd = 1.06): a few eps relative; rtol 45 eps
    np.testing.assert_allclose(siso_zeros(A, b, np.array([Kp, Kd]), 0.0), [-Kp / Kd],
                               rtol=1e-14)
    assert siso_zeros(A, b, np.array([1.0, 0.0]), 0.0).size == 0
    w, p = 3.0, 0.04
    plant = modal_plant(J, [(w, 0.0, p, p)], disturbance=False)
    z = siso_zeros(plant.A, plant.B[:, 0], plant.C[0], 0.0)
    # zeros of (s^2 + w^2) + p^2 J s^2 = 0: s = +- j w / sqrt(1 + p^2 J)
    np.testing.assert_allclose(np.sort(z.imag), [-w / np.sqrt(1 + p * p * J),
                                                 w / np.sqrt(1 + p * p * J)], rtol=1e-12)
    np.testing.assert_allclose(z.real, 0.0, atol=1e-12 * w)


def test_frequency_response_data_matches_python_control():
    """The FRD equals control.frd's (an n x n solve per frequency) to round-off, continuous and
    discrete (z = exp(j w dt)), with the system's signal names."""
    plant = _many_modes(12)
    omega = np.logspace(-1, 3, 300)
    ours = controllers.frequency_response_data(plant, omega)
    ref = control.frd(plant, omega)
    assert list(ours.input_labels) == list(plant.input_labels)
    assert list(ours.output_labels) == list(plant.output_labels)
    np.testing.assert_allclose(ours.frdata, ref.frdata, rtol=1e-10, atol=1e-12 * np.abs(
        ref.frdata).max())
    digital = control.c2d(plant, 0.01)
    ours = controllers.frequency_response_data(digital, omega[omega < np.pi / 0.01])
    ref = control.frd(digital, omega[omega < np.pi / 0.01])
    # the sampled plant's modal form is well conditioned too: 1e-9 relative
    np.testing.assert_allclose(ours.frdata, ref.frdata, rtol=1e-9, atol=1e-9 * np.abs(
        ref.frdata).max())
    with pytest.raises(ValueError, match=r"omega must be positive finite frequencies \[rad/s\]"):
        controllers.frequency_response_data(plant, [1.0, -2.0])
    with pytest.raises(TypeError, match="system must be a control.StateSpace"):
        controllers.frequency_response_data(control.tf([1], [1, 0]), [1.0])


def test_margins_of_a_many_mode_loop_unchanged_by_the_modal_evaluator():
    """Margins of one loop through the modal evaluator (decoupled parts) and through a dense
    realisation of the same plant (an orthogonal similarity destroys the block structure: one
    Schur form of the whole A): equal to the refinement's tolerance (1e-9 relative)."""
    plant = _many_modes(30)
    Qo = np.linalg.qr(np.random.default_rng(1).standard_normal((plant.nstates,) * 2))[0]
    dense = control.ss(Qo.T @ plant.A @ Qo, Qo.T @ plant.B, plant.C @ Qo, plant.D,
                       inputs=list(plant.input_labels), outputs=list(plant.output_labels))
    K = controllers.pd(modal_plant(J), natural_frequency=0.5, roll_off=5.0)
    a, b = controllers.margins(plant, K), controllers.margins(dense, K)
    for name in ("gain_margin", "phase_margin", "modulus_margin"):
        assert getattr(a, name) == pytest.approx(getattr(b, name), rel=1e-9)


def test_real_schur_riccati_equals_complex_and_eigenvalue_parser():
    """Laub's method from the real Schur form and from the complex one solve the same Riccati
    equation as scipy's solver: a well-damped (zeta = 0.2), well-weighted plant, whose
    Riccati equation is well conditioned, so the three agree to 1e-9 relative; the eigenvalues
    read off the real quasi-triangular form equal numpy's."""
    from controllers.riccati import (_quasi_triangular_eigenvalues, _stable_subspace_complex,
                                     _stable_subspace_real)

    plant = modal_plant(1.0, [(1.5, 0.2, 0.5, 0.5), (4.0, 0.2, 0.3, 0.3)], disturbance=False)
    A, B = plant.A, plant.B
    Q = plant.C.T @ plant.C
    n = A.shape[0]
    H = np.block([[A, -B @ B.T], [-Q, -A.T]])
    X_ref = scipy.linalg.solve_continuous_are(A, B, Q, np.eye(1))
    for subspace in (_stable_subspace_real, _stable_subspace_complex):
        U = subspace(H, n)
        X = np.real(np.linalg.solve(U[:n].T, U[n:].T).T)
        np.testing.assert_allclose(X, X_ref, rtol=0, atol=1e-9 * np.abs(X_ref).max())
    T, _ = scipy.linalg.schur(H, output="real")
    got = np.sort_complex(_quasi_triangular_eigenvalues(T))
    np.testing.assert_allclose(got, np.sort_complex(np.linalg.eigvals(T)), rtol=0,
                               atol=1e-12 * np.abs(got).max())


def test_a_systems_evaluator_is_reused_until_the_system_changes():
    """modal_evaluator gives the evaluator it built for the same block of the same system again
    (a sweep's nominal controller is decomposed once, not once per sample), a new one for
    another block or after the system's matrices changed in place, and the same response
    either way (bit for bit: the same computation)."""
    plant = _many_modes(5)
    s = 1j * np.geomspace(0.1, 100.0, 50)
    first = modal_evaluator(plant, ["torque"], ["theta"])
    assert modal_evaluator(plant, ["torque"], ["theta"]) is first
    assert modal_evaluator(plant, ["torque"], ["omega"]) is not first
    before = first(s)
    plant.A[3, 2] *= 2.25   # the first mode 1.5 times as fast, in place
    changed = modal_evaluator(plant, ["torque"], ["theta"])
    assert changed is not first
    np.testing.assert_array_equal(changed(s), ModalEvaluator(plant.A, plant.B[:, [0]],
                                                             plant.C[[0]], plant.D[[0]][:, [0]])(s))
    assert not np.allclose(changed(s), before, rtol=1e-2)
