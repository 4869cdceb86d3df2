"""Tests of controllers.simulate: the exact LTI simulator.

Reference values are closed forms derived in each test's docstring, the
responses of python-control's forced_response (same first-order-hold input
interpretation) and of control.c2d(..., "zoh") + a discrete-time response, or
an extended-precision (long double) solution.  Every comparison runs with both
methods of the simulator: the modal recursion (compiled; needs numba) and the
chunked recursion.
"""

import importlib

import control
import numpy as np
import pytest
import scipy.linalg

from controllers.modal_recursion import kernel_available
from controllers.simulate import Simulator, simulate

simulate_module = importlib.import_module("controllers.simulate")
EPS = np.finfo(float).eps

needs_numba = pytest.mark.skipif(not kernel_available(),
                                 reason="the modal recursion needs numba")
#: Both methods; "modal" needs numba (a dependency of flexsat).
METHODS = [pytest.param("modal", marks=needs_numba), "chunked"]


def modal_system(rng, n_modes, *, n_inputs=1, n_outputs=2, zeta=(0.001, 0.05),
                 omega=(0.2, 30.0), n_rigid=0, mix=True):
    """Random lightly damped system in a random (well-conditioned) basis.

    n_modes oscillators x'' + 2 zeta w x' + w^2 x = b u plus n_rigid double
    integrators (rigid-body modes: a 2x2 Jordan block at s = 0 each).
    """
    w = np.sort(rng.uniform(*omega, n_modes))
    z = rng.uniform(*zeta, n_modes)
    n = 2 * (n_modes + n_rigid)
    A = np.zeros((n, n))
    for i in range(n_modes):
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, 1], [-w[i] ** 2,
                                                      -2 * z[i] * w[i]]]
    for i in range(n_modes, n_modes + n_rigid):
        A[2 * i, 2 * i + 1] = 1.0
    if mix:
        # Orthogonal change of basis: same eigenvalues, dense matrices.
        Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
        A = Q @ A @ Q.T
    B = rng.standard_normal((n, n_inputs))
    C = rng.standard_normal((n_outputs, n))
    D = rng.standard_normal((n_outputs, n_inputs))
    return control.ss(A, B, C, D)


def signal_range(y):
    """Peak-to-peak range per signal (rows), at least tiny to avoid 0/0."""
    return np.maximum(np.ptp(y, axis=-1), 1e-300)


# --------------------------------------------------------------------------
# Closed forms
# --------------------------------------------------------------------------

@pytest.mark.parametrize("hold", ["linear", "zero"])
@pytest.mark.parametrize("method", METHODS)
def test_double_integrator_step_is_exact_parabola(hold, method):
    """x'' = u, u = 1 for t >= 0 (constant: both holds are exact).

    Closed form: x(t) = x0 + v0 t + t^2/2, v(t) = v0 + t.
    """
    sys = control.ss([[0, 1], [0, 0]], [[0], [1]], np.eye(2), 0)
    T = np.linspace(0.0, 20.0, 2001)
    x0, v0 = 0.3, -1.2
    resp = simulate(sys, T, np.ones_like(T), [x0, v0], hold=hold, method=method)
    expected = np.array([x0 + v0 * T + T ** 2 / 2, v0 + T])
    # Exact discretisation: only round-off, O(eps * |x| * steps).
    np.testing.assert_allclose(resp.states, expected, rtol=1e-12, atol=1e-11)
    np.testing.assert_allclose(resp.outputs, expected, rtol=1e-12,
                               atol=1e-11)


@pytest.mark.parametrize("method", METHODS)
def test_double_integrator_ramp_is_exact_cubic(method):
    """x'' = u with u = t (linear: the first-order hold is exact).

    Closed form: x(t) = t^3 / 6, v(t) = t^2 / 2.
    """
    sys = control.ss([[0, 1], [0, 0]], [[0], [1]], [[1, 0]], 0)
    T = np.linspace(0.0, 10.0, 1001)
    resp = simulate(sys, T, T, method=method)
    np.testing.assert_allclose(resp.states[0], T ** 3 / 6, rtol=1e-12,
                               atol=1e-11)
    np.testing.assert_allclose(resp.states[1], T ** 2 / 2, rtol=1e-12,
                               atol=1e-11)


@pytest.mark.parametrize("method", METHODS)
def test_undamped_oscillator_is_exact_cos_sin(method):
    """x'' + w^2 x = 0, x(0) = x0, x'(0) = v0.

    Closed form: x = x0 cos(w t) + v0/w sin(w t), x' = -x0 w sin + v0 cos.
    """
    w = 2.7
    sys = control.ss([[0, 1], [-w ** 2, 0]], [[0], [1]], [[1, 0]], 0)
    T = np.arange(5000) * 0.013
    x0, v0 = 0.8, -0.4
    resp = simulate(sys, T, X0=[x0, v0], method=method)
    x = x0 * np.cos(w * T) + v0 / w * np.sin(w * T)
    v = -x0 * w * np.sin(w * T) + v0 * np.cos(w * T)
    # expm is accurate to ~eps per step; 5000 steps -> ~1e-12.
    np.testing.assert_allclose(resp.states[0], x, rtol=0, atol=1e-11)
    np.testing.assert_allclose(resp.states[1], v, rtol=0, atol=1e-11)


@pytest.mark.parametrize("hold", ["linear", "zero"])
@pytest.mark.parametrize("method", METHODS)
def test_first_order_system_under_linear_input(hold, method):
    """x' = -a x + b u, u(t) = c0 + c1 t, x(0) = x0.

    Closed form (variation of constants):
      x(t) = x0 e^{-a t} + b [ c0/a (1 - e^{-a t})
                               + c1 (t/a - (1 - e^{-a t})/a^2) ].
    With hold="linear" this is exact at every sample; with hold="zero" the
    input is held at u[k] over [t_k, t_k + dt), whose closed form is the
    ZOH recursion x[k+1] = e^{-a dt} x[k] + b (1 - e^{-a dt})/a u[k].
    """
    a, b, c0, c1, x0 = 1.7, 0.6, 0.5, -0.3, 2.0
    sys = control.ss([[-a]], [[b]], [[1.0]], [[0.0]])
    T = np.linspace(0.0, 8.0, 801)
    U = c0 + c1 * T
    resp = simulate(sys, T, U, [x0], hold=hold, method=method)
    if hold == "linear":
        e = np.exp(-a * T)
        x = x0 * e + b * (c0 / a * (1 - e) + c1 * (T / a - (1 - e) / a ** 2))
    else:
        dt = T[1] - T[0]
        ad, bd = np.exp(-a * dt), b * (1 - np.exp(-a * dt)) / a
        x = np.empty_like(T)
        x[0] = x0
        for k in range(T.size - 1):
            x[k + 1] = ad * x[k] + bd * U[k]
    # each step adds ~4 eps |x| of round-off (the exact ad, bd to ~2 eps, then ad x + bd u),
    # which the stable recursion damps by ad = e^(-a dt) = 0.983 per step: in all at most
    # 4 eps |x| / (1 - ad) ~ 240 eps |x| = 5e-14 |x|, inside rtol 1e-12; atol 1e-13 where x
    # crosses 0
    np.testing.assert_allclose(resp.states[0], x, rtol=1e-12, atol=1e-13)


@pytest.mark.parametrize("method", METHODS)
def test_slow_modes_keep_their_steady_state(method):
    """Slow real mode (a = 1e-3 1/s, |lambda| = 1 - 1e-5 per step) and a
    slow lightly damped mode (w = 0.05 rad/s, zeta = 0.01), step input.

    Closed forms: x1(t) = (b/a)(1 - e^{-a t});  for x'' + 2 zeta w x' + w^2 x
    = u, x(t) = (1 - e^{-zeta w t} (cos(wd t) + zeta w / wd sin(wd t))) / w^2.
    A steady state (I - Ad)^-1 Bd u amplifies round-off in the transition
    matrix by 1 / (1 - |lambda|) = 1e5; the chunked recursion applies
    I - Ad^L as the product (I - Ad) S_L to avoid it.  Required: 1e-10
    relative to the final value (seen: 3e-13 and 1e-12; forced_response
    7e-13 and 2e-12).
    """
    a, b, w, zeta = 1e-3, 2.0, 0.05, 0.01
    A = np.zeros((3, 3))
    A[0, 0] = -a
    A[1, 2] = 1.0
    A[2, 1], A[2, 2] = -w ** 2, -2 * zeta * w
    sys = control.ss(A, [[b], [0.0], [1.0]], np.eye(3), 0)
    T = np.arange(200_001) * 0.01
    resp = simulate(sys, T, np.ones_like(T), method=method)
    x1 = b / a * (1 - np.exp(-a * T))
    wd = w * np.sqrt(1 - zeta ** 2)
    x2 = (1 - np.exp(-zeta * w * T) * (np.cos(wd * T)
                                       + zeta * w / wd * np.sin(wd * T))) / w ** 2
    np.testing.assert_allclose(resp.states[0], x1, rtol=0,
                               atol=1e-10 * abs(x1[-1]))
    np.testing.assert_allclose(resp.states[1], x2, rtol=0,
                               atol=1e-10 * np.abs(x2).max())


# --------------------------------------------------------------------------
# Against python-control
# --------------------------------------------------------------------------

@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("method", METHODS)
def test_matches_forced_response_lightly_damped(seed, method):
    """Same first-order-hold interpretation: agree to round-off."""
    rng = np.random.default_rng(seed)
    sys = modal_system(rng, 20, n_inputs=2, n_outputs=3)
    T = np.arange(3000) * 0.01
    U = np.vstack([np.sin(0.9 * T), rng.standard_normal(T.size)])
    X0 = rng.standard_normal(sys.nstates)
    ref = control.forced_response(sys, T, U, X0)
    resp = simulate(sys, T, U, X0, method=method)
    # Round-off of two different propagations of the same exact discrete
    # system: ~1e-12 of the signal range; 1e-9 leaves a wide margin.
    scale = signal_range(ref.y)[:, None]
    assert np.max(np.abs(resp.y - ref.y) / scale) < 1e-9
    np.testing.assert_allclose(resp.x, ref.x, rtol=0,
                               atol=1e-9 * np.abs(ref.x).max())


@pytest.mark.parametrize("seed", [3, 4])
@pytest.mark.parametrize("method", METHODS)
def test_matches_forced_response_with_rigid_body_modes(seed, method):
    """Defective eigenvalues (double integrators, Jordan blocks at s = 0)."""
    rng = np.random.default_rng(seed)
    sys = modal_system(rng, 10, n_rigid=2, n_inputs=1, n_outputs=2)
    T = np.arange(2000) * 0.01
    U = np.cos(0.5 * T) + 0.1 * rng.standard_normal(T.size)
    X0 = rng.standard_normal(sys.nstates)
    ref = control.forced_response(sys, T, U, X0)
    resp = simulate(sys, T, U, X0, method=method)
    scale = signal_range(ref.y)[:, None]
    # Round-off only (see test above).
    assert np.max(np.abs(resp.y - ref.y) / scale) < 1e-9


@pytest.mark.parametrize("method", METHODS)
def test_matches_forced_response_stiff_modes(method):
    """Stiff modes: poles from -0.1 to -1e4 rad/s (e^{-100} per step)."""
    rng = np.random.default_rng(7)
    poles = -np.logspace(-1, 4, 12)
    Q, _ = np.linalg.qr(rng.standard_normal((12, 12)))
    sys = control.ss(Q @ np.diag(poles) @ Q.T, rng.standard_normal((12, 2)),
                     rng.standard_normal((2, 12)), 0)
    T = np.arange(1500) * 0.01
    U = rng.standard_normal((2, T.size))
    ref = control.forced_response(sys, T, U, 0.0)
    resp = simulate(sys, T, U, 0.0, method=method)
    scale = signal_range(ref.y)[:, None]
    # Round-off only.
    assert np.max(np.abs(resp.y - ref.y) / scale) < 1e-9


def non_normal_system(rng, n, decades):
    """Stable A = S diag(poles) S^-1 with cond(S) up to 10^(2 decades).

    Strongly non-normal: transient growth, ||Ad|| far above its spectral
    radius (what control.rss can produce too).
    """
    Q1, _ = np.linalg.qr(rng.standard_normal((n, n)))
    Q2, _ = np.linalg.qr(rng.standard_normal((n, n)))
    S = Q1 @ np.diag(10.0 ** rng.uniform(-decades, decades, n)) @ Q2
    A = S @ np.diag(-rng.uniform(0.1, 5.0, n)) @ np.linalg.inv(S)
    return control.ss(A, rng.standard_normal((n, 1)),
                      rng.standard_normal((2, n)), 0)


@pytest.mark.parametrize("decades", [2, 3])
@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("method", METHODS)
def test_non_normal_systems_against_extended_precision(seed, decades, method):
    """Formed powers Ad^L lose accuracy against stepping when Ad is strongly non-normal; the
    chunk length is then cut (down to 1) by the accuracy probe.  Against the long-double
    solution: a step's round-off, ~eps |Ad| |x| with |Ad| up to the eigenvector condition
    kappa, is amplified by the transient growth of the powers of Ad (up to kappa again), so
    the bound is eps kappa^2 of the output range (kappa 1.5e3 to 4e3 at 2 decades, 6e4 to
    2.5e5 at 3).  Measured over four BLAS kernels: chunked up to 1/6 of the bound (1.4e-6 at
    kappa 2e5), modal 1e-11 to 1e-8 of it; forced_response, which this test compared with
    before, is itself off by 3e-8 to 1.1e-6 at 3 decades, by kernel, so agreement with it
    was decided by rounding."""
    rng = np.random.default_rng(seed)
    sys = non_normal_system(rng, 12, decades)
    T = np.arange(2000) * 0.01
    U = np.sin(T) + rng.standard_normal(T.size)
    y_exact = extended_precision_outputs(sys, 0.01, U[None, :])
    scale = signal_range(y_exact)[:, None]
    kappa = np.linalg.cond(np.linalg.eig(sys.A)[1])
    assert 10 ** (2 * decades - 2) < kappa < 10 ** (2 * decades)
    bound = EPS * kappa ** 2
    sim = Simulator(sys, 0.01, method=method)
    assert np.max(np.abs(sim.run(T, U).y - y_exact) / scale) < bound
    assert np.max(np.abs(sim.outputs(T, U) - y_exact) / scale) < bound


@pytest.mark.parametrize("method", METHODS)
def test_zero_order_hold_matches_c2d_zoh(method):
    """hold="zero" is control.c2d(sys, dt, "zoh") simulated in discrete time."""
    rng = np.random.default_rng(11)
    sys = modal_system(rng, 8, n_inputs=2, n_outputs=2, n_rigid=1)
    dt = 0.02
    T = np.arange(1500) * dt
    U = rng.standard_normal((2, T.size))
    X0 = rng.standard_normal(sys.nstates)
    ref = control.forced_response(control.c2d(sys, dt, "zoh"), T, U, X0)
    resp = simulate(sys, T, U, X0, hold="zero", method=method)
    scale = signal_range(ref.y)[:, None]
    # Same exact ZOH discretisation (both via expm): round-off only.
    assert np.max(np.abs(resp.y - ref.y) / scale) < 1e-9


@pytest.mark.parametrize("method", METHODS)
def test_simulator_reuse_matches_simulate(method):
    """One set-up, several runs: identical to fresh simulate() calls."""
    rng = np.random.default_rng(5)
    sys = modal_system(rng, 6)
    T = np.arange(500) * 0.05
    sim = Simulator(sys, 0.05, method=method)
    for gain in (0.5, 2.0):
        U = gain * np.sin(T)
        np.testing.assert_array_equal(sim.run(T, U).y,
                                      simulate(sys, T, U, method=method).y)
    # A grid that starts later with the same step is fine too.
    resp = sim.run(T + 3.0, np.ones_like(T))
    np.testing.assert_array_equal(resp.time, T + 3.0)
    # Runs of other lengths reuse the scratch space; earlier results keep
    # their values.
    long_run = sim.run(np.arange(2000) * 0.05, 1.0)
    kept = long_run.x.copy()
    short = sim.run(T[:37], np.sin(T[:37]))
    np.testing.assert_array_equal(short.x, simulate(sys, T[:37],
                                                    np.sin(T[:37]), method=method).x)
    np.testing.assert_array_equal(long_run.x, kept)


@pytest.mark.parametrize("case", ["repeated", "nearly_defective"])
@pytest.mark.parametrize("method", METHODS)
def test_close_and_repeated_eigenvalues_match_forced_response(case, method):
    """Two identical decoupled oscillators (repeated, non-defective
    eigenvalues) and a pair 1e-9 apart (nearly defective) in a dense basis."""
    rng = np.random.default_rng(21)
    w1, w2 = (3.0, 3.0) if case == "repeated" else (3.0, 3.0 + 1e-9)
    A = np.zeros((6, 6))
    A[0:2, 0:2] = [[0, 1], [-w1 ** 2, -0.01]]
    A[2:4, 2:4] = [[0, 1], [-w2 ** 2, -0.01]]
    A[4:6, 4:6] = [[0, 1], [-0.25, -0.02]]
    if case == "nearly_defective":
        A[1, 2] = 1.0                   # couples the two close modes
    S = rng.standard_normal((6, 6))
    sys = control.ss(S @ A @ np.linalg.inv(S), rng.standard_normal((6, 1)),
                     rng.standard_normal((2, 6)), 0)
    T = np.arange(2500) * 0.02
    U = np.sin(1.3 * T)
    ref = control.forced_response(sys, T, U, np.ones(6))
    resp = simulate(sys, T, U, np.ones(6), method=method)
    scale = signal_range(ref.y)[:, None]
    # Round-off only; the random basis S has cond ~ 1e2.
    assert np.max(np.abs(resp.y - ref.y) / scale) < 1e-9


@pytest.mark.parametrize("n_samples", [2, 3, 17, 1001])
@pytest.mark.parametrize("method", METHODS)
def test_short_and_odd_lengths_match_forced_response(n_samples, method):
    """Grids shorter than, and not a multiple of, the chunk length."""
    rng = np.random.default_rng(n_samples)
    sys = modal_system(rng, 4, n_inputs=2, n_rigid=1)
    T = 0.5 + np.arange(n_samples) * 0.03
    U = rng.standard_normal((2, n_samples))
    X0 = rng.standard_normal(sys.nstates)
    ref = control.forced_response(sys, T, U, X0)
    resp = simulate(sys, T, U, X0, method=method)
    # Round-off only.
    np.testing.assert_allclose(resp.y, ref.y, rtol=1e-10,
                               atol=1e-10 * np.abs(ref.y).max())
    np.testing.assert_allclose(resp.x, ref.x, rtol=1e-10,
                               atol=1e-10 * np.abs(ref.x).max())


@pytest.mark.parametrize("method", METHODS)
def test_outputs_only_path_equals_run(method):
    rng = np.random.default_rng(8)
    sys = modal_system(rng, 10, n_inputs=2, n_outputs=3, n_rigid=1)
    T = np.arange(1234) * 0.01
    U = rng.standard_normal((2, T.size))
    sim = Simulator(sys, 0.01, method=method)
    Y = sim.outputs(T, U, 0.1)
    assert Y.shape == (3, T.size) and Y.dtype == np.float64
    # outputs() may use other chunks than run(): other round-off, same
    # exact system.
    np.testing.assert_allclose(Y, sim.run(T, U, 0.1).y, rtol=1e-11,
                               atol=1e-11 * np.abs(Y).max())
    ref = control.forced_response(sys, T, U, 0.1)
    scale = signal_range(ref.y)[:, None]
    # Round-off only.
    assert np.max(np.abs(Y - ref.y) / scale) < 1e-9


def test_chunk_lengths():
    """A lightly damped modal loop keeps long chunks (outputs() longer than
    run()); a strongly non-normal system is cut to short ones by the
    accuracy probe."""
    w = np.geomspace(1.0, 30.0, 10)
    A = np.zeros((20, 20))
    for i, wi in enumerate(w):
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, 1], [-wi ** 2, -0.01 * wi]]
    modal = Simulator(control.ss(A, np.ones((20, 1)), np.ones((2, 20)), 0),
                      0.01)
    assert modal.chunk_length(with_states=True) >= 16
    assert (modal.chunk_length(with_states=False)
            > modal.chunk_length(with_states=True))
    rng = np.random.default_rng(0)
    nasty = Simulator(non_normal_system(rng, 12, 4), 0.01)
    assert nasty.chunk_length(with_states=True) <= 2


# --------------------------------------------------------------------------
# Discrete-time systems
# --------------------------------------------------------------------------

@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("step", [0.05, True])
def test_discrete_time_matches_forced_response(step, method):
    """A discrete-time system is its own recursion x[k+1] = A x[k] + B u[k]: the same
    arithmetic as forced_response's, other round-off (modal coordinates)."""
    rng = np.random.default_rng(31)
    continuous = modal_system(rng, 8, n_inputs=2, n_outputs=3, n_rigid=1)
    sys = control.c2d(continuous, 0.05, "zoh")
    if step is True:
        sys = control.ss(sys.A, sys.B, sys.C, sys.D, True)
    T = np.arange(3000) * (1.0 if step is True else step)
    U = rng.standard_normal((2, T.size))
    X0 = rng.standard_normal(sys.nstates)
    ref = control.forced_response(sys, T, U, X0)
    resp = simulate(sys, T, U, X0, method=method)
    scale = signal_range(ref.y)[:, None]
    # Round-off of two propagations of the same recursion (see the tests above).
    assert np.max(np.abs(resp.y - ref.y) / scale) < 1e-9
    np.testing.assert_allclose(resp.x, ref.x, rtol=0, atol=1e-9 * np.abs(ref.x).max())
    np.testing.assert_array_equal(resp.time, T)


# --------------------------------------------------------------------------
# Against an extended-precision solution; the choice of method
# --------------------------------------------------------------------------

def long_double_expm(M):
    """expm(M) in numpy.longdouble (64-bit mantissa on x86-64): scaling and squaring with
    a degree-24 Taylor polynomial of M / 2^s, ||M / 2^s|| <= 1/2: truncation error
    0.5^25 / 25! ~ 2e-33, far below the long-double round-off (~1e-19 per operation)."""
    M = np.asarray(M, dtype=np.longdouble)
    s = max(0, int(np.ceil(np.log2(max(float(np.abs(M).sum(axis=1).max()), 1e-300) / 0.5))))
    X = M / np.longdouble(2.0) ** s
    eye = np.eye(M.shape[0], dtype=np.longdouble)
    E = eye.copy()
    for k in range(24, 0, -1):
        E = eye + (X @ E) / k
    for _ in range(s):
        E = E @ E
    return E


def extended_precision_outputs(sys, dt, U):
    """Outputs from x(0) = 0 under linear-between-samples inputs, with the Van Loan block
    exponential and the recursion in long double: the exact solution to ~1e-16."""
    ld = np.longdouble
    A, B, C, D = (np.asarray(M, dtype=ld) for M in (sys.A, sys.B, sys.C, sys.D))
    n, m = B.shape
    M = np.zeros((n + 2 * m, n + 2 * m), dtype=ld)
    M[:n, :n], M[:n, n:n + m] = A * ld(dt), B * ld(dt)
    M[n:n + m, n + m:] = np.eye(m, dtype=ld)
    E = long_double_expm(M)
    Ad, Bd1 = E[:n, :n], E[:n, n + m:]
    Bd0 = E[:n, n:n + m] - Bd1
    U = U.astype(ld)
    W = Bd0 @ U[:, :-1] + Bd1 @ U[:, 1:]
    X = np.zeros((n, U.shape[1]), dtype=ld)
    for k in range(U.shape[1] - 1):
        X[:, k + 1] = Ad @ X[:, k] + W[:, k]
    return (C @ X + D @ U).astype(float)


def hidden_modal_system(rng, n_modes, n_rigid, condition=4.0):
    """The general system of issue 10: lightly damped modes (0.1 to 1000 rad/s, damping
    1e-3 to 0.05, as normal 2 x 2 blocks) and free rigid bodies (double integrators),
    hidden by a similarity transform S with cond(S) = condition."""
    w = np.exp(rng.uniform(np.log(0.1), np.log(1000.0), n_modes))
    zeta = np.exp(rng.uniform(np.log(1e-3), np.log(0.05), n_modes))
    n = 2 * (n_modes + n_rigid)
    A = np.zeros((n, n))
    for i in range(n_modes):
        sigma, wd = -zeta[i] * w[i], w[i] * np.sqrt(1 - zeta[i] ** 2)
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[sigma, wd], [-wd, sigma]]
    for i in range(n_modes, n_modes + n_rigid):
        A[2 * i, 2 * i + 1] = 1.0
    Q1, _ = np.linalg.qr(rng.standard_normal((n, n)))
    Q2, _ = np.linalg.qr(rng.standard_normal((n, n)))
    S = Q1 @ np.diag(np.geomspace(1.0, condition, n)) @ Q2
    return control.ss(S @ A @ np.linalg.inv(S), S @ rng.standard_normal((n, 2)),
                      rng.standard_normal((3, n)) @ np.linalg.inv(S), 0)


def general_system_run(rng, n_samples):
    """Issue 10's general system with 20 states (two rigid bodies), random inputs at
    dt = 0.01 s, and the error of outputs against its extended-precision solution:
    ``(sys, T, U, error)``, error(y) = max |y - y_exact| / range(y_exact) over the outputs."""
    sys = hidden_modal_system(rng, 8, 2)
    dt = 0.01
    U = rng.standard_normal((2, n_samples))
    T = np.arange(n_samples) * dt
    y_exact = extended_precision_outputs(sys, dt, U)
    scale = signal_range(y_exact)[:, None]
    return sys, T, U, lambda y: float(np.max(np.abs(y - y_exact) / scale))


@pytest.mark.parametrize("method", METHODS)
def test_general_system_against_extended_precision(method):
    """Issue 10's general system (20 states, two rigid bodies) over 3000 samples, inputs
    random (linear between samples).  Both methods and forced_response carry round-off
    only: each step adds ~eps relative, N eps = 7e-13 after N = 3000 steps, amplified by
    the transformation's condition (V: 30 here) and by the rigid bodies, which integrate
    their rate errors.  Seen: modal 1.3e-12, chunked 1.2e-12, forced_response 1.3e-12 of
    the output range; required: 1e-10 (a margin of 100)."""
    sys, T, U, error = general_system_run(np.random.default_rng(44), 3000)
    assert error(simulate(sys, T, U, method=method).y) < 1e-10


@needs_numba
@pytest.mark.parametrize("seed", [0, 1])
def test_rigid_bodies_drift_without_the_schur_forms_round_off(seed):
    """Issue 10's general system (20 states, two rigid bodies, modes up to 1000 rad/s) over
    1e4 samples: the rigid bodies' position drifts ~t^1.5 and integrates any error in their
    dynamics.  The Schur form's round-off (~eps ||A|| cond(V) ~ 1e-12 in the rigid blocks
    and in their couplings to the modes) gave the modal recursion 1.6e-11 (seed 0) and
    6.8e-11 (seed 1, where the Schur form splits the rigid bodies into two blocks) of the
    output range; with the blocks refined and decoupled from an accurate residual
    (controllers.modal_form._refine_blocks) what remains is the other blocks' round-off:
    seen 2.2e-13 and 6.6e-13, against 2.8e-12 and 3.4e-11 for forced_response.  Required:
    2e-12 (a margin of 3 over the worse seed; the unrefined form fails it by 8x or more),
    and no worse than forced_response (issue 10's criterion) on the same inputs."""
    sys, T, U, error = general_system_run(np.random.default_rng(seed), 10_000)
    modal = error(simulate(sys, T, U, method="modal").y)
    assert modal < 2e-12
    assert modal <= error(control.forced_response(sys, T, U).y)


@needs_numba
def test_three_rigid_bodies_and_integrators_in_a_cluster():
    """Three free rigid bodies and three integrators with five oscillators (0.34 to 98
    rad/s) in a random basis (cond 1.4), 5000 samples. The nine states at s = 0 end in
    blocks whose sizes rounding decides (measured, by BLAS kernel: one cluster of 9; 6 + 1 +
    1 + 1; 4 + 5; 4 + 2 + 2 + 1), clusters whose transition matrix is ~I + A dt, kept as
    Phi - I (test_cluster_transition_is_phi_minus_identity_to_its_own_precision) with the
    state added after the small terms in the loop.  Measured over those kernels: 8e-14 to
    9.5e-13 of the output range, forced_response 2.5e-12 to 5.5e-12 (stored as Phi, the
    rounding of its entries near 1 integrated by the drift gave up to 6.3e-12).  Required: no
    worse than forced_response, and 1.5e-12."""
    rng = np.random.default_rng(122)       # a random structure that draws this mix
    blocks = [np.array([[0.0, 1.0], [0.0, 0.0]])] * int(rng.integers(0, 4))
    blocks += [np.zeros((1, 1))] * int(rng.integers(0, 4))
    for w in np.exp(rng.uniform(np.log(0.05), np.log(500), rng.integers(3, 20))):
        zeta = np.exp(rng.uniform(np.log(1e-4), np.log(0.3)))
        wd = w * np.sqrt(1 - zeta * zeta)
        blocks.append(np.array([[-zeta * w, wd], [-wd, -zeta * w]]))
    blocks += [np.array([[-rng.uniform(0.1, 10)]]) for _ in range(rng.integers(0, 4))]
    A = scipy.linalg.block_diag(*blocks)
    n = A.shape[0]
    Q1, _ = np.linalg.qr(rng.standard_normal((n, n)))
    Q2, _ = np.linalg.qr(rng.standard_normal((n, n)))
    S = Q1 @ np.diag(np.geomspace(1, 10 ** rng.uniform(0, 2), n)) @ Q2
    assert n == 19                         # 3 rigid bodies, 3 integrators, 5 modes
    sys = control.ss(S @ A @ np.linalg.inv(S), S @ rng.standard_normal((n, 2)),
                     rng.standard_normal((2, n)) @ np.linalg.inv(S), 0)
    T = np.arange(5000) * 0.01
    U = rng.standard_normal((2, T.size))
    y_exact = extended_precision_outputs(sys, 0.01, U)
    scale = signal_range(y_exact)[:, None]

    def error(y):
        return np.max(np.abs(y - y_exact) / scale)
    simulator = Simulator(sys, 0.01, method="modal")
    modal = error(simulator.outputs(T, U))
    assert modal <= error(control.forced_response(sys, T, U).y)
    assert modal < 1.5e-12


def test_cluster_transition_is_phi_minus_identity_to_its_own_precision():
    """A cluster's transition matrix is kept as Phi - I = e^(A dt) - I (the recursion adds the
    state exactly), computed as (A dt) phi1(A dt) without cancellation against I: right to
    a few eps relative to |Phi - I| itself, against the exponential of the float64 A dt in
    40 digits. Clusters as the refined form gives them: three rigid bodies (three 2 x 2
    Jordan blocks at 0) and a Jordan chain of 6 at -0.5, in random bases, dt = 1e-3, so
    |Phi - I| ~ 1e-3: Phi rounded near 1 and I subtracted (e^(A dt) - I by cancellation)
    leaves ~eps / |Phi - I| relative (measured: 360 eps for the rigid bodies, 50 for the
    chain); required: 4 s eps (24 eps; measured 0.8 eps on every BLAS kernel tried)."""
    import mpmath
    from controllers.modal_recursion import _transition_minus_identity
    rng = np.random.default_rng(5)
    s, dt = 6, 1e-3
    rigid = scipy.linalg.block_diag(*[np.array([[0.0, 1.0], [0.0, 0.0]])] * 3)
    chain = -0.5 * np.eye(s) + np.eye(s, k=1)
    blocks = []
    for J in (rigid, chain):
        S = rng.standard_normal((s, s)) + 3 * np.eye(s)
        blocks.append(S @ J @ np.linalg.inv(S))
    blocks = np.array(blocks)
    computed = _transition_minus_identity(blocks, dt)
    for block, result in zip(blocks, computed):
        with mpmath.workdps(40):
            exact = mpmath.expm(mpmath.matrix((block * dt).tolist())) - mpmath.eye(s)
            exact = np.array(exact.tolist(), dtype=float)
        size = np.abs(exact).max()
        assert size < 1e-2
        assert np.abs(result - exact).max() <= 4 * s * EPS * size


def attitude_loop(n_modes, *, inertia=50.0, zeta=0.005, bandwidth=0.5):
    """PD attitude loop around a hub with n_modes bending modes in mechanical modal
    coordinates (q, q'), x'' + 2 zeta w x' + w^2 x = b torque, w from 0.5 to 200 rad/s:
    ||A|| ~ w_max^2 = 4e4, far above the slow closed-loop poles (~0.5 rad/s)."""
    rng = np.random.default_rng(9)
    w = np.geomspace(0.5, 200.0, n_modes)
    b = rng.uniform(0.2, 1.0, n_modes) / np.sqrt(inertia)
    n = 2 + 2 * n_modes
    A = np.zeros((n, n))
    A[0, 1] = 1.0
    B = np.zeros((n, 1))
    B[1, 0] = 1.0 / inertia
    C = np.zeros((2, n))
    C[0, 0] = C[1, 1] = 1.0
    for i in range(n_modes):
        k = 2 + 2 * i
        A[k, k + 1] = 1.0
        A[k + 1, k], A[k + 1, k + 1] = -w[i] ** 2, -2 * zeta * w[i]
        B[k + 1, 0] = b[i]
        C[0, k], C[1, k + 1] = 0.05 * b[i], 0.05 * b[i]
    K = np.array([[inertia * bandwidth ** 2, inertia * 2 * 0.7 * bandwidth]])
    return control.ss(A - B @ K @ C, B * K[0, 0], C, 0)


@pytest.mark.parametrize("method", METHODS)
def test_stiff_attitude_loop_against_extended_precision(method):
    """Attitude loop with modes up to 200 rad/s in mechanical coordinates: the Schur form's
    backward error ~eps ||A|| (||A|| ~ 4e4) perturbs the slow closed-loop poles by ~1e-11
    relative unless A is balanced first (its modes then scale like w, not w^2).  Seen:
    modal 8e-14, chunked 4e-14, forced_response 1.5e-13 of the output range; unbalanced,
    the modal recursion gave 2.5e-12.  Required: 1e-12."""
    sys = attitude_loop(20)
    dt = 0.01
    T = np.arange(4000) * dt
    tau = np.clip(T / 30.0, 0.0, 1.0)
    U = (0.17 * (tau - np.sin(2 * np.pi * tau) / (2 * np.pi)))[None, :]
    y_exact = extended_precision_outputs(sys, dt, U)
    scale = signal_range(y_exact)[:, None]
    y = simulate(sys, T, U, method=method).y
    assert np.max(np.abs(y - y_exact) / scale) < 1e-12


@needs_numba
def test_auto_method_choice():
    """Runs of at least as many samples as states go modal (a sweep's short runs too),
    shorter ones chunked (its set-up is the cheaper one there).  A system whose eigenvalues
    cannot be decoupled into small blocks (one Jordan block of 70 states: the modal
    recursion would step a dense 70 x 70 block, O(n^2) per sample) stays chunked, whatever
    the length."""
    rng = np.random.default_rng(3)
    sim = Simulator(modal_system(rng, 10, n_rigid=1), 0.01)
    assert sim.method_for(100_000) == "modal"
    assert sim.method_for(sim.n_states) == "modal"
    assert sim.method_for(sim.n_states - 1) == "chunked"
    jordan = control.ss(-np.eye(70) + np.eye(70, k=1), np.ones((70, 1)), np.ones((1, 70)), 0)
    assert Simulator(jordan, 0.01).method_for(10**6) == "chunked"


@needs_numba
def test_short_runs_go_modal_to_the_same_accuracy():
    """A run as short as a sweep sample's (2000 samples; before, runs below 2e5 states x
    samples went chunked): "auto" takes the modal recursion, as accurate as on long runs.
    Issue 10's general system (20 states, two rigid bodies) against its extended-precision
    solution: round-off only, ~N eps = 4e-13 amplified by V's condition (30) and the rigid
    bodies' drift; required: 1e-10 of the output range, as for 3000 samples above."""
    sys, T, U, error = general_system_run(np.random.default_rng(45), 2000)
    assert Simulator(sys, 0.01).method_for(T.size) == "modal"
    assert error(simulate(sys, T, U).y) < 1e-10


def test_static_gain_and_inputless_system():
    """y = D u for a static gain; free oscillation x = (cos t, -sin t)."""
    gain = control.ss([], [], [], [[2.0]])
    T = np.linspace(0, 1, 5)
    np.testing.assert_array_equal(simulate(gain, T, T).outputs, 2 * T)
    free = control.ss([[0, 1], [-1, 0]], np.zeros((2, 0)), np.eye(2),
                      np.zeros((2, 0)))
    T = np.linspace(0, np.pi, 9)
    resp = simulate(free, T, X0=[1.0, 0.0])
    # Closed form; expm accurate to ~eps.
    np.testing.assert_allclose(resp.y, [np.cos(T), -np.sin(T)], rtol=0,
                               atol=1e-14)


# --------------------------------------------------------------------------
# Long undamped simulation: conservation
# --------------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("method", METHODS)
def test_long_undamped_simulation_conserves_energy_and_rigid_motion(method):
    """1e5 s, 1e5 samples: oscillator w = 1.3 rad/s plus a free rigid body.

    Free motion of the undamped oscillator keeps E = (v^2 + w^2 x^2)/2
    constant; the free rigid body moves as p(t) = p0 + v0 t exactly.  The
    exact discretisation keeps E to ~eps per step (1e5 steps -> ~1e-11
    relative); required: 1e-9 relative.  The rigid body may deviate only
    by round-off: each of the N steps adds p + q dt with a rounding error
    of at most eps |p| / 2, so |p - exact| <= N eps max|p| (~2e-7 here);
    a systematic drift (a wrong discrete rigid-body block) would show as
    an error growing like t and far larger.  Seen: energy 4e-12, rigid body
    3e-10 (forced_response: 1e-11 and 2e-8).
    """
    w = 1.3
    A = np.zeros((4, 4))
    A[0, 1] = 1.0
    A[1, 0] = -w ** 2
    A[2, 3] = 1.0
    sys = control.ss(A, np.zeros((4, 1)), np.eye(4), 0)
    T = np.arange(100_001) * 1.0
    x0, v0, p0, q0 = 0.7, -0.2, 1.5, 0.1
    resp = simulate(sys, T, X0=[x0, v0, p0, q0], method=method)
    x, v, p, q = resp.states
    energy = 0.5 * (v ** 2 + w ** 2 * x ** 2)
    e0 = 0.5 * (v0 ** 2 + w ** 2 * x0 ** 2)
    assert np.max(np.abs(energy / e0 - 1.0)) < 1e-9
    bound = T.size * np.finfo(float).eps * np.abs(p).max()
    np.testing.assert_allclose(p, p0 + q0 * T, rtol=0, atol=bound)
    # q is propagated by multiplications with exactly 1: ~eps per step.
    np.testing.assert_allclose(q, q0, rtol=T.size * np.finfo(float).eps,
                               atol=0)


@pytest.mark.parametrize("method", METHODS)
def test_aliased_undamped_modes_conserve_energy(method):
    """Modal plant: a free rigid body and 8 undamped modes up to 71 rad/s,
    sampled every 1 s (w dt up to 71 rad: heavily aliased), 1e5 steps.

    Energy (|q'|^2 + sum w^2 q^2)/2 of the free modes is constant.  expm of
    the whole A dt misses |lambda| = 1 by ~6e-14 per step here (2e-9 after
    1e5 steps); the per-block closed-form exponential keeps it to ~1e-16
    per step.  Required: 1e-9 relative (the issue's figure); seen ~1e-13.
    """
    w = np.geomspace(2.0, 71.0, 8)
    n = 1 + w.size
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n + 1:, 1:n] = -np.diag(w ** 2)
    sys = control.ss(A, np.zeros((2 * n, 1)), np.eye(2 * n), 0)
    rng = np.random.default_rng(5)
    x0 = rng.standard_normal(2 * n) / np.concatenate([[1.0], w, np.ones(n)])
    T = np.arange(100_001) * 1.0
    X = simulate(sys, T, X0=x0, method=method).states
    q, rate = X[1:n], X[n + 1:]
    energy = 0.5 * (np.sum(rate ** 2, axis=0) + (w ** 2) @ q ** 2)
    np.testing.assert_allclose(energy, energy[0], rtol=1e-9, atol=0)
    # Rigid body: p0 + v0 t to round-off (N eps max|p|, see the test above).
    p = X[0]
    np.testing.assert_allclose(p, x0[0] + x0[n] * T, rtol=0,
                               atol=T.size * np.finfo(float).eps
                               * np.abs(p).max())


# --------------------------------------------------------------------------
# Shapes and signal names
# --------------------------------------------------------------------------

def test_shapes_and_names_match_forced_response():
    sys = control.ss(np.diag([-1.0, -2.0, -3.0]), np.ones((3, 2)),
                     np.ones((4, 3)), np.zeros((4, 2)),
                     inputs=["torque", "force"],
                     outputs=["theta", "omega", "a", "b"],
                     states=["s1", "s2", "s3"], name="plant")
    T = np.linspace(0, 1, 11)
    U = np.ones((2, 11))
    ref = control.forced_response(sys, T, U)
    resp = simulate(sys, T, U)
    assert isinstance(resp, control.TimeResponseData)
    for attr in ("time", "outputs", "states", "inputs"):
        assert getattr(resp, attr).shape == getattr(ref, attr).shape, attr
    assert resp.output_labels == ["theta", "omega", "a", "b"]
    assert resp.input_labels == ["torque", "force"]
    assert resp.state_labels == ["s1", "s2", "s3"]
    assert resp.states.dtype == np.float64


@pytest.mark.parametrize("method", METHODS)
def test_states_are_filled_in_on_first_use(method):
    """run() returns the outputs at once and the states when read; both
    equal forced_response's; the states are computed once; pickling keeps
    them."""
    import pickle

    rng = np.random.default_rng(12)
    sys = modal_system(rng, 5, n_inputs=2, n_outputs=2)
    T = np.arange(700) * 0.01
    U = rng.standard_normal((2, T.size))
    resp = Simulator(sys, 0.01, method=method).run(T, U)
    assert resp._states is None               # nothing filled in yet
    assert resp.nstates == sys.nstates
    assert resp.state_labels == sys.state_labels
    ref = control.forced_response(sys, T, U)
    states = resp.states
    assert states.shape == (sys.nstates, T.size)
    assert resp.x is resp.x                   # computed once
    # Round-off only.
    np.testing.assert_allclose(states, ref.states, rtol=0,
                               atol=1e-10 * np.abs(ref.x).max())
    again = pickle.loads(pickle.dumps(Simulator(sys, 0.01, method=method).run(T, U)))
    np.testing.assert_array_equal(again.x, resp.x)


def test_siso_squeeze_like_forced_response():
    sys = control.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]])
    T = np.linspace(0, 1, 5)
    for squeeze in (None, False, True):
        ref = control.forced_response(sys, T, 1.0, squeeze=squeeze)
        resp = simulate(sys, T, 1.0, squeeze=squeeze)
        assert resp.outputs.shape == ref.outputs.shape
        assert resp.inputs.shape == ref.inputs.shape
    # Default: 1-D outputs for SISO, like forced_response.
    assert simulate(sys, T).outputs.shape == (5,)
    t, y = simulate(sys, T, 1.0)
    assert t.shape == (5,) and y.shape == (5,)


def test_linspace_grid_with_round_off_is_accepted():
    """np.linspace steps differ by ~eps * |T|; that is still even."""
    sys = control.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]])
    T = np.linspace(0.0, 1000.0, 100_001)
    assert np.ptp(np.diff(T)) > 0          # not exactly even
    y = simulate(sys, T, np.ones_like(T)).outputs
    # Closed form 1 - e^-t; expm and propagation round-off only.
    np.testing.assert_allclose(y, 1 - np.exp(-T), rtol=0, atol=1e-12)


# --------------------------------------------------------------------------
# Errors
# --------------------------------------------------------------------------

@pytest.fixture
def sys2():
    return control.ss(np.diag([-1.0, -2.0]), [[1.0], [1.0]], [[1.0, 1.0]], 0)


def test_error_not_state_space(sys2):
    with pytest.raises(TypeError, match="system must be a control.StateSpace"):
        simulate(control.tf([1], [1, 1]), np.linspace(0, 1, 5))
    with pytest.raises(TypeError, match="system"):
        Simulator(np.eye(2), 0.1)


def test_error_discrete_time_step(sys2):
    dsys = control.c2d(sys2, 0.1)
    with pytest.raises(ValueError, match=r"dt must equal the discrete-time system's step"):
        Simulator(dsys, 0.2)
    with pytest.raises(ValueError, match="simulator's step"):
        simulate(dsys, np.arange(5) * 0.2)


def test_error_unspecified_timebase():
    sys = control.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]], None)
    with pytest.raises(ValueError, match="timebase"):
        simulate(sys, np.arange(5) * 0.1)


def test_error_unknown_method(sys2, monkeypatch):
    with pytest.raises(ValueError, match="method must be one of"):
        simulate(sys2, np.linspace(0, 1, 5), method="fast")
    # Without numba, "modal" is refused by name and "auto" falls back to the chunked
    # recursion.
    monkeypatch.setattr(simulate_module, "kernel_available", lambda: False)
    with pytest.raises(RuntimeError, match="numba"):
        Simulator(sys2, 0.1, method="modal")
    assert Simulator(sys2, 0.001).method_for(10**6) == "chunked"


@pytest.mark.parametrize("T, match", [
    (None, "T must be given"),
    ([0.0, 0.1, np.nan], "T must be finite"),
    ([0.0], "at least 2 samples"),
    ([0.0, 0.1, 0.3], "evenly spaced"),
    ([1.0, 0.5, 0.0], "increasing"),
    (np.zeros((2, 3)), "1-D"),
    (["a", "b"], "T must be real"),
])
def test_error_bad_time(sys2, T, match):
    with pytest.raises(ValueError, match=match):
        simulate(sys2, T)


def test_error_bad_inputs(sys2):
    T = np.linspace(0, 1, 5)
    with pytest.raises(ValueError, match=r"U must have shape \(n_inputs, "):
        simulate(sys2, T, np.ones(4))
    with pytest.raises(ValueError, match="U must be finite"):
        simulate(sys2, T, [0, 1, np.inf, 0, 0])
    with pytest.raises(ValueError, match="U must be real"):
        simulate(sys2, T, np.ones(5) * 1j)


def test_error_bad_initial_state(sys2):
    T = np.linspace(0, 1, 5)
    with pytest.raises(ValueError, match=r"X0 must have shape \(n_states,\)"):
        simulate(sys2, T, X0=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="X0 must be finite"):
        simulate(sys2, T, X0=[np.nan, 0.0])


def test_error_bad_hold_and_step(sys2):
    with pytest.raises(ValueError, match="hold must be one of"):
        simulate(sys2, np.linspace(0, 1, 5), hold="cubic")
    with pytest.raises(ValueError, match=r"dt must be positive and finite \[s\]"):
        Simulator(sys2, -0.1)
    sim = Simulator(sys2, 0.1)
    with pytest.raises(ValueError, match="simulator's step"):
        sim.run(np.linspace(0, 1, 5))


def test_error_nan_in_system():
    sys = control.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]])
    sys.A[0, 0] = np.nan
    with pytest.raises(ValueError, match="system.A must be finite"):
        simulate(sys, np.linspace(0, 1, 5))


def test_unstable_overflow_is_an_error_not_inf():
    sys = control.ss([[50.0]], [[1.0]], [[1.0]], [[0.0]])
    with pytest.raises(FloatingPointError, match="overflowed"):
        simulate(sys, np.linspace(0, 100, 1001), X0=[1.0])


@pytest.mark.parametrize("n_states", [1, 20])
@pytest.mark.parametrize("method", METHODS)
def test_overflow_stops_the_response_at_the_last_sample_in_range(n_states, method):
    """on_overflow="stop": x' = x from x(0) = 1 is e^t, which passes 1e250 (the overflow
    threshold) at t = 250 ln 10 = 575.646 s: with a 1 s step the response keeps t = 0..575 and
    diverged_at = 576 s; the samples kept are the exact ones (e^t to round-off, ~1e-13
    relative after 575 steps of eps). Chunk lengths differ with n (1 and 20 states)."""
    A = np.eye(n_states)
    sys = control.ss(A, np.ones((n_states, 1)), np.eye(n_states)[:1], 0.0)
    T = np.arange(1001.0)
    response = simulate(sys, T, X0=np.ones(n_states), on_overflow="stop", method=method)
    assert response.diverged_at == 576.0
    t = np.asarray(response.t)
    np.testing.assert_array_equal(t, np.arange(576.0))
    y = np.asarray(response.y).reshape(-1)
    np.testing.assert_allclose(y, np.exp(t), rtol=1e-12)
    assert np.asarray(response.u).shape[-1] == 576
    assert np.asarray(response.x).shape == (n_states, 576)
    # a response inside the range is whole, with diverged_at None
    assert simulate(sys, np.arange(100.0), X0=np.ones(n_states),
                    on_overflow="stop", method=method).diverged_at is None
    with pytest.raises(ValueError, match="on_overflow must be one of"):
        simulate(sys, T, on_overflow="ignore", method=method)


@needs_numba
def test_refined_modal_form_does_not_depend_on_the_callers_threads():
    """Issue 10's general system with 200 states and two rigid bodies (refined blocks and
    their decoupling: error-free products whose remainders round in float64, Sylvester and
    LU solves): the same outputs and states, bit for bit, with one or two BLAS threads
    allowed by the caller (the simulator runs every product on one thread)."""
    from threadpoolctl import threadpool_limits
    rng = np.random.default_rng(8)
    sys = hidden_modal_system(rng, 98, 2)
    T = np.arange(2000) * 0.01
    U = rng.standard_normal((2, T.size))
    results = []
    for n_threads in (1, 2):
        with threadpool_limits(limits=n_threads, user_api="blas"):
            simulator = Simulator(sys, 0.01, method="modal")
            response = simulator.run(T, U)
            results.append((response.y, response.x, simulator._modal.form.coupled.size))
    assert results[0][2] >= 4                  # the rigid bodies' blocks were refined
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1], results[1][1])
