"""Three-axis (MIMO) controllers and analysis: closed forms, the planar case embedded, margins."""
import math

import control
import numpy as np
import pytest

import controllers
from controllers.lqr import lqr_design
from controllers.pd import pd_gains, principal_axes
from plants import embedded_planar_plant, modal_plant, three_axis_plant

# a full, non-diagonal inertia tensor (principal axes tilted by ~5-15 deg from the hub's)
J3 = np.array([[1200.0, 80.0, -40.0], [80.0, 900.0, 30.0], [-40.0, 30.0, 1500.0]])
RIGID3 = three_axis_plant(J3)
# flexible modes with participation in several axes (collocated: b = c)
PHI1, PHI2 = np.array([0.010, 0.020, 0.0]), np.array([0.0, 0.010, 0.015])
FLEX3 = three_axis_plant(J3, [(2.0, 0.005, PHI1, PHI1), (5.0, 0.005, PHI2, PHI2)],
                         tips=[("wing_tip_deflection_y", [0.5, -0.2]),
                               ("wing_tip_deflection_z", [0.1, 0.3])])
PHI3 = np.array([0.004, 0.0, 0.006])
TRUTH3 = three_axis_plant(J3, [(2.1, 0.005, PHI1, PHI1), (5.2, 0.005, PHI2, PHI2),
                               (17.0, 0.005, PHI3, PHI3)],
                          tips=[("wing_tip_deflection_y", [0.5, -0.2, 0.05]),
                                ("wing_tip_deflection_z", [0.1, 0.3, -0.1])])
RATE = 0.1  # rad/s, rigid-body bandwidth of the designs below


def _rigid_poles(loop):
    return np.sort_complex(np.linalg.eigvals(loop.A))


# ----- rigid body: inertia tensor, PD closed forms -----------------------------------------------
def test_rigid_body_inertia_is_the_full_tensor():
    """lim s^2 theta/torque = J^-1 (3 x 3): the flexible terms vanish at s = 0. The modal
    realisation is built from J's eigen-decomposition, so J comes back to round-off of it and of
    one 3 x 3 inverse (cond(J) ~ 1.8: 1e-12 relative)."""
    for plant in (RIGID3, FLEX3, TRUTH3):
        np.testing.assert_allclose(controllers.rigid_body_inertia(plant), J3, rtol=0,
                                   atol=1e-12 * np.abs(J3).max())


@pytest.mark.parametrize("axes", ["principal", "hub"])
def test_pd_rigid_closed_loop_poles_per_axis(axes):
    """Rigid body J theta'' = Kp (theta_ref - theta) - Kd omega with wn_i, zeta_i per axis:
    principal axes (Kp = R diag(j wn^2) R^T, Kd = R diag(2 j zeta wn) R^T) decouple it into
    j_i (s^2 + 2 zeta_i wn_i s + wn_i^2) along each principal axis; hub axes (Kp = J Wn^2,
    Kd = 2 J Z Wn) into s^2 + 2 zeta_i wn_i s + wn_i^2 along each hub axis. Either way the six
    closed-loop poles are the roots of the three specified polynomials (eigenvalues of a 6 x 6
    well-conditioned matrix: 1e-10 relative)."""
    wn, zeta = np.array([0.1, 0.2, 0.15]), np.array([0.7, 0.5, 0.9])
    K = controllers.pd(RIGID3, natural_frequency=wn, damping=zeta, axes=axes)
    assert list(K.input_labels) == ["theta_ref_x", "theta_ref_y", "theta_ref_z", "theta_x",
                                    "theta_y", "theta_z", "omega_x", "omega_y", "omega_z"]
    assert list(K.output_labels) == ["torque_x", "torque_y", "torque_z"]
    expected = np.sort_complex(np.concatenate([np.roots([1, 2 * z * w, w * w])
                                               for w, z in zip(wn, zeta)]))
    got = _rigid_poles(controllers.close_loop(RIGID3, K))
    np.testing.assert_allclose(got, expected, rtol=1e-10)
    Kp, Kd = K.D[:, :3], -K.D[:, 6:]
    if axes == "principal":
        j, R = principal_axes(J3)
        # eigh is backward stable: R diag(j) R^T = J3 + E, ||E||_2 <= p(n) eps ||J3||_2 with
        # p(n) a modest multiple of n (LAPACK Users' Guide, 3rd ed., sec. 4.7.1), plus
        # gamma_3 of the product here; 8 n eps ||J3|| (measured: 1.4 eps ||J3||)
        np.testing.assert_allclose(R @ np.diag(j) @ R.T, J3, rtol=0,
                                   atol=8 * 3 * np.finfo(float).eps * np.linalg.norm(J3, 2))
        # R matched to the hub axes: the largest entry of each column on the diagonal
        assert np.all(np.argmax(np.abs(R), axis=0) == [0, 1, 2]) and np.all(np.diag(R) > 0)
        np.testing.assert_allclose(Kp, Kp.T, rtol=1e-14)  # symmetric positive definite
        assert np.linalg.eigvalsh(Kd).min() > 0
    else:
        # J from the plant: J3 to round-off of one 3 x 3 inverse (1e-13)
        np.testing.assert_allclose(Kp, J3 @ np.diag(wn ** 2), rtol=1e-13)
        np.testing.assert_allclose(Kd, J3 @ np.diag(2 * zeta * wn), rtol=1e-13)


def test_pd_uniform_spec_is_wn2_J_in_either_axes():
    """One wn and zeta for every axis: Kp = wn^2 J, Kd = 2 zeta wn J in principal and hub axes
    alike (the rotation R diag(j) R^T = J: round-off of eigh, 1e-12 relative)."""
    for axes in ("principal", "hub"):
        Kp, Kd = pd_gains(J3, 0.3, 0.7, axes=axes)
        np.testing.assert_allclose(Kp, 0.09 * J3, rtol=0, atol=1e-12 * 0.09 * np.abs(J3).max())
        np.testing.assert_allclose(Kd, 0.42 * J3, rtol=0, atol=1e-12 * 0.42 * np.abs(J3).max())


def test_pd_on_flexible_three_axis_plant_is_stable_with_filters_and_sampling():
    """Symmetric positive definite gains on collocated theta, omega damp every mode; the roll-off
    and a digital implementation keep the guarantee (checked by pd itself); the loop's poles
    are in the open left half-plane / unit disk."""
    for kwargs in (dict(), dict(roll_off=1.5), dict(sample_time=0.5)):
        K = controllers.pd(FLEX3, natural_frequency=RATE, **kwargs)
        loop = controllers.close_loop(FLEX3, K)
        poles = np.linalg.eigvals(loop.A)
        assert (np.abs(poles).max() < 1 if K.isdtime(strict=True) else poles.real.max() < 0)


# ----- the planar case embedded in three axes ---------------------------------------------------
PLANAR = modal_plant(250.0, [(2.0, 0.02, 0.04, 0.04), (9.0, 0.02, 0.02, 0.02)],
                     tips=[("wing_tip_deflection", [0.5, -0.2])], disturbance=False)
EMBEDDED = embedded_planar_plant(PLANAR, 300.0, 400.0)


def _response(system, inputs, outputs, s):
    ev = controllers.frequency.modal_evaluator(system, inputs, outputs)
    return ev(np.asarray(s))


def test_embedded_planar_pd_is_the_planar_pd_on_z():
    """diag(300, 400, J) with the planar plant on z: the three-axis PD's z row restricted to the
    z signals is the planar PD (same roll-off and notch), and it has no coupling to x, y. Both
    gains come from the same floating-point formula (J wn^2, 2 zeta wn J: bit-equal), the
    filters' state-space realisations differ only by the block order, so their responses agree
    to round-off: each evaluation of C (sI - A)^-1 B + D is within about kappa(sI - A) eps of
    the exact value (a backward-stable solve; Higham 2002, sec. 7.1), kappa <= 460 on this
    grid, so the bound is 2 x 2 kappa eps (measured: bit-equal)."""
    kwargs = dict(natural_frequency=0.3, damping=0.6, roll_off=6.0, notch=15.0)
    planar = controllers.pd(PLANAR, **kwargs)
    three = controllers.pd(EMBEDDED, **kwargs)
    s = 1j * np.array([0.01, 0.3, 1.2, 4.0, 20.0])
    ref = _response(planar, ["theta_ref", "theta", "omega"], ["torque"], s)[:, 0, :]
    got = _response(three, ["theta_ref_z", "theta_z", "omega_z"],
                    ["torque_x", "torque_y", "torque_z"], s)
    A = np.asarray(planar.A)
    kappa = max(np.linalg.cond(x * np.eye(A.shape[0]) - A) for x in s)
    np.testing.assert_allclose(got[:, 2, :], ref, rtol=4 * kappa * np.finfo(float).eps)
    assert np.abs(got[:, :2, :]).max() == 0.0
    static_planar = controllers.pd(PLANAR, natural_frequency=0.3, damping=0.6)
    static_three = controllers.pd(EMBEDDED, natural_frequency=0.3, damping=0.6)
    np.testing.assert_array_equal(static_three.D[2, [2, 5, 8]], static_planar.D[0])


def test_embedded_planar_lqr_is_the_planar_lqr_on_z():
    """The LQR + Kalman of the embedded plant with the planar weights on z (any weights on x, y)
    decouples: the Riccati equations are block diagonal (cost, input and noises per axis), so
    its z block is the planar design. The two designs differ only by their prescribed degree of
    stability sigma (from each loop's spectral scale, ~1e-13 rad/s) and the scaling of the
    Hamiltonians: 1e-9 relative on the controller's response."""
    weights = dict(attitude_weight=400.0, rate_weight=1000.0, torque_weight=1.0)
    planar = controllers.lqr(PLANAR, **weights)
    three = controllers.lqr(EMBEDDED, attitude_weight=[900.0, 1600.0, 400.0],
                            rate_weight=[0.0, 0.0, 1000.0], torque_weight=[2.0, 1.0, 1.0])
    s = 1j * np.array([0.01, 0.3, 1.2, 4.0, 20.0])
    ref = _response(planar, ["theta_ref", "theta", "omega"], ["torque"], s)[:, 0, :]
    got = _response(three, ["theta_ref_z", "theta_z", "omega_z"],
                    ["torque_x", "torque_y", "torque_z"], s)
    np.testing.assert_allclose(got[:, 2, :], ref, rtol=1e-9)
    np.testing.assert_allclose(got[:, :2, :], 0.0, atol=1e-9 * np.abs(ref).max())
    pm = controllers.margins(PLANAR, planar)
    mm = controllers.margins(EMBEDDED, three)
    # the x, y loops are closed and decoupled: L_z alone is the planar L (1e-7: refined margins)
    assert mm.loop_at_a_time["z"].phase_margin == pytest.approx(pm.phase_margin, rel=1e-7)
    assert mm.loop_at_a_time["z"].gain_margin == pytest.approx(pm.gain_margin, rel=1e-7)


# ----- LQR on three axes --------------------------------------------------------------------------
def test_lqr_rigid_three_axis_closed_form_in_principal_axes():
    """Isotropic weights q|theta|^2 + q_w|omega|^2 + r|torque|^2 are invariant under the rotation
    to principal axes, theta = R eta, torque = R v: the problem decouples into planar double
    integrators j_i eta_i'' = v_i, whose gains are K_i = [sqrt(q/r), sqrt((2 j_i sqrt(q r) +
    q_w)/r)] (test_rigid_hub_lqr_gain_closed_form). RIGID3's states are (eta_i, eta_i') per
    principal axis, so K[:, 2i:2i+2] = R[:, i] K_i (ARE solver: 1e-10)."""
    q, qw, r = 400.0, 1000.0, 2.0
    design = lqr_design(RIGID3, attitude_weight=q, rate_weight=qw, torque_weight=r)
    j, R = np.linalg.eigh(J3)  # the plant's own principal coordinates (tests/support/plants.py)
    for i in range(3):
        Ki = np.array([math.sqrt(q / r), math.sqrt((2 * j[i] * math.sqrt(q * r) + qw) / r)])
        np.testing.assert_allclose(design.K[:, 2 * i:2 * i + 2], np.outer(R[:, i], Ki),
                                   rtol=0, atol=1e-10 * Ki.max())


def test_lqr_three_axis_tracks_every_axis_and_is_stable_on_truth():
    """Chain-like design plant (2 modes), truth with 3: stable on both, DC gain theta_ref ->
    theta = I exactly (a rigid rotation about each axis is an equilibrium), every flexible mode
    of the truth damped (spillover per mode)."""
    Jd = np.diag(J3)
    design = lqr_design(FLEX3, attitude_weight=(Jd * RATE ** 2) ** 2, rate_weight=0.0,
                        torque_weight=1.0, deflection_weight=1e3)
    K = design.controller
    assert design.K.shape == (3, FLEX3.nstates) and design.L.shape == (FLEX3.nstates, 6)
    assert design.x_ref.shape == (FLEX3.nstates, 3)
    # the guarantee of controllers.stability, by construction (prescribed degree of stability)
    assert design.margin > 0
    assert max(design.regulator_poles.real.max(), design.estimator_poles.real.max()) <= \
        -design.margin
    for plant in (FLEX3, TRUTH3):
        loop = controllers.close_loop(plant, K)
        assert np.linalg.eigvals(loop.A).real.max() < 0
        dc = loop.D - loop.C @ np.linalg.solve(loop.A, loop.B)
        # a linear solve of a well-conditioned loop: round-off only
        np.testing.assert_allclose(dc[:3, :3], np.eye(3), rtol=0, atol=1e-9)
    verdict = controllers.spillover(TRUTH3, K)
    assert verdict.stable and len(verdict.modes) == 3
    assert [round(m.frequency, 6) for m in verdict.modes] == pytest.approx([2.1, 5.2, 17.0],
                                                                          rel=1e-4)
    assert all(m.stable and m.closed_loop_damping > 0 for m in verdict.modes)
    assert isinstance(verdict.margins, controllers.MultiLoopMargins)
    assert "gain margin" in str(verdict)


def test_repeated_modes_in_two_axes_are_controllable_with_three_torques():
    """Two undamped modes at one frequency: one torque reaches one combination only (the planar
    design refuses them), three torques reach both when their participation vectors are
    independent (multi-input PBH: rank 2), but not when they are parallel (rank 1)."""
    a, b = np.array([0.02, 0.0, 0.0]), np.array([0.0, 0.0, 0.02])
    weights = dict(attitude_weight=(1000 * RATE ** 2) ** 2, rate_weight=0.0, torque_weight=1.0)
    both = three_axis_plant(J3, [(3.0, 0.0, a, a), (3.0, 0.0, b, b)])
    design = lqr_design(both, **weights)
    assert not design.removed_modes
    assert np.linalg.eigvals(controllers.close_loop(both, design.controller).A).real.max() < 0
    parallel = three_axis_plant(J3, [(3.0, 0.0, a, a), (3.0, 0.0, 0.5 * a, 0.5 * a)])
    with pytest.raises(ValueError, match="nearly\\) repeated and undamped: the torques reach"):
        lqr_design(parallel, **weights)
    planar = modal_plant(1000.0, [(3.0, 0.0, 0.02, 0.02), (3.0, 0.0, 0.01, 0.01)])
    with pytest.raises(ValueError, match="a single torque reaches only one combination"):
        controllers.lqr(planar, **weights)


def test_digital_three_axis_lqr():
    K = controllers.lqr(FLEX3, attitude_weight=(900 * RATE ** 2) ** 2, rate_weight=0.0,
                        torque_weight=1.0, sample_time=0.5)
    assert K.dt == 0.5 and K.noutputs == 3
    loop = controllers.close_loop(TRUTH3, K)
    assert np.abs(np.linalg.eigvals(loop.A)).max() < 1


# ----- margins --------------------------------------------------------------------------------
def _rate_controller(gains, tau, R=np.eye(3)):
    """torque = -R diag(k_i / (tau s + 1)) R^T omega: with the plant I/s^2 in theta (J = I),
    L = R diag(k_i / (s (tau s + 1))) R^T."""
    A = -np.eye(3) / tau
    B = R.T / tau
    C = -R @ np.diag(gains)
    return control.ss(A, B, C, np.zeros((3, 3)), inputs=["omega_x", "omega_y", "omega_z"],
                      outputs=["torque_x", "torque_y", "torque_z"])


@pytest.mark.parametrize("coupled", [False, True])
def test_disk_margin_closed_form_and_brute_force(coupled):
    """L = k/(s (tau s + 1)) on each channel (coupled: rotated by an orthogonal R, which
    changes no singular value). The balanced disk margin is alpha = 2 min_w |1 + L| / |1 - L|
    (Seiler et al. 2020: f = -1/L on the boundary of the disk (1 + d alpha/2)/(1 - d alpha/2));
    with x = w^2, |1 - L|^2 / |1 + L|^2 = 1 + 4 tau k x / ((k - tau x)^2 + x), largest at
    x = k / tau, so alpha = 2 / sqrt(1 + 4 k tau) at w = sqrt(k / tau). The loop with the
    smallest alpha sets the multivariable margin. Checked against the closed form (refined
    extremum: 1e-9) and against the definition on a brute-force sweep of 200,000 frequencies
    (grid resolution: 1e-6)."""
    gains, tau = np.array([0.5, 2.0, 1.0]), 0.8
    R = (np.linalg.qr(np.random.default_rng(5).standard_normal((3, 3)))[0] if coupled
         else np.eye(3))
    plant = three_axis_plant(np.eye(3))
    m = controllers.margins(plant, _rate_controller(gains, tau, R))
    k = gains.max()
    alpha = 2 / math.sqrt(1 + 4 * k * tau)
    assert m.disk_margin == pytest.approx(alpha, rel=1e-9)
    assert m.disk_margin_frequency == pytest.approx(math.sqrt(k / tau), rel=1e-4)
    assert m.disk_gain_margin == pytest.approx(20 * math.log10((1 + alpha / 2) / (1 - alpha / 2)),
                                               rel=1e-9)
    assert m.disk_phase_margin == pytest.approx(math.degrees(2 * math.atan(alpha / 2)), rel=1e-9)
    w = np.logspace(-3, 3, 200_000)
    s = 1j * w
    brute = min(2 * np.min(np.abs(1 + ki / (s * (tau * s + 1))) / np.abs(1 - ki / (s * (tau * s
                                                                                       + 1))))
                for ki in gains)
    assert m.disk_margin == pytest.approx(brute, rel=1e-6)
    # min sigma(I + L) = min over channels of min |1 + L_i|
    sigma = min(np.min(np.abs(1 + ki / (s * (tau * s + 1)))) for ki in gains)
    assert m.min_singular_value == pytest.approx(sigma, rel=1e-6)


def test_loop_at_a_time_phase_margin_closed_form():
    """Decoupled loops: L_i = 1/S_ii - 1 is the channel's own k_i / (s (tau s + 1)); its
    crossover solves k = w sqrt(1 + tau^2 w^2), i.e. tau^2 w^4 + w^2 - k^2 = 0, and
    PM = 90 deg - atan(tau w_c); no phase crossover (GM infinite). Refined crossings: 1e-9."""
    gains, tau = np.array([0.5, 2.0, 1.0]), 0.8
    m = controllers.margins(three_axis_plant(np.eye(3)), _rate_controller(gains, tau))
    for axis, k in zip("xyz", gains):
        wc = math.sqrt((-1 + math.sqrt(1 + 4 * tau ** 2 * k ** 2)) / (2 * tau ** 2))
        pm = 90.0 - math.degrees(math.atan(tau * wc))
        assert m.loop_at_a_time[axis].phase_margin == pytest.approx(pm, rel=1e-9)
        assert m.loop_at_a_time[axis].gain_margin == math.inf
    names = m.as_dict()
    assert {"gain_margin_x", "phase_margin_z", "disk_margin", "min_singular_value"} <= set(names)
    assert m.phase_margin == min((m.loop_at_a_time[a].phase_margin for a in "xyz"), key=abs)


# ----- slews about any axis, metrics, comparison --------------------------------------------------
def test_eigen_axis_slew_stays_on_its_axis():
    """Hub-axes PD with one wn, zeta: Kp = wn^2 J, Kd = 2 zeta wn J, so the rigid loop is
    theta'' + 2 zeta wn theta' + wn^2 theta = wn^2 theta_ref whatever J: the response to
    theta_ref = e phi(t) is e times the planar one. Per-axis peaks are |e_i| times the norm
    (exact simulation of a 12-state loop: 1e-9 relative)."""
    e = np.array([1.0, -2.0, 0.5]) / math.sqrt(5.25)
    K = controllers.pd(RIGID3, natural_frequency=0.2, damping=0.7, axes="hub")
    loop = controllers.close_loop(RIGID3, K)
    response = controllers.slew(loop, 0.3, 40.0, axis=[1.0, -2.0, 0.5], t_final=100.0)
    theta = np.asarray(response.y)[:3]
    cross = np.cross(theta.T, e)
    assert np.abs(cross).max() < 1e-9 * np.abs(theta).max()
    m = controllers.metrics(response)
    for i, a in enumerate("xyz"):
        assert m[f"peak_attitude_error_{a}"] == pytest.approx(abs(e[i]) * m["peak_attitude_error"],
                                                              rel=1e-9)
    # planar closed form of the same loop: the SISO PD on a unit inertia
    planar = controllers.close_loop(modal_plant(1.0), controllers.pd(
        modal_plant(1.0), natural_frequency=0.2, damping=0.7))
    ref = controllers.metrics(controllers.slew(planar, 0.3, 40.0, t_final=100.0))
    for name in ("overshoot", "settling_time", "peak_attitude_error", "final_attitude_error"):
        assert m[name] == pytest.approx(ref[name], rel=1e-8, abs=1e-15)


def test_compare_and_assert_closed_loops_close_on_three_axes():
    """Chain-tuned (FLEX3) LQR on a truth with one more mode: the comparison holds three-axis
    metrics and margins; assert_closed_loops_close passes for the loop against itself and fails
    with a table naming per-axis metrics against a slower loop."""
    Jd = np.diag(J3)
    K = controllers.lqr(FLEX3, attitude_weight=(Jd * RATE ** 2) ** 2, rate_weight=0.0,
                        torque_weight=1.0)
    comparison = controllers.compare(FLEX3, TRUTH3, K, angle=0.1, slew_time=60.0, axis="y")
    assert comparison.verdict.stable
    assert {"peak_torque_y", "peak_wing_tip_deflection_z", "disk_margin",
            "phase_margin_x"} <= set(comparison.truth_metrics)
    assert "disk_margin" in comparison.table()
    design_loop = controllers.close_loop(FLEX3, K)
    controllers.assert_closed_loops_close(design_loop, design_loop, angle=0.1, duration=60.0,
                                          axis=[0, 1, 1], rtol=1e-12)
    slower = controllers.lqr(FLEX3, attitude_weight=(Jd * (0.5 * RATE) ** 2) ** 2,
                             rate_weight=0.0, torque_weight=1.0)
    with pytest.raises(AssertionError, match="peak_torque_y"):
        controllers.assert_closed_loops_close(controllers.close_loop(FLEX3, slower), design_loop,
                                              angle=0.1, duration=60.0, axis=[0, 1, 1])
    fig = comparison.plot()
    assert len(fig.axes) == 6


# ----- errors --------------------------------------------------------------------------------
def test_three_axis_errors_name_the_parameter():
    K = controllers.pd(RIGID3, natural_frequency=0.1)
    loop = controllers.close_loop(RIGID3, K)
    with pytest.raises(ValueError, match="axis must be given for a three-axis loop"):
        controllers.slew(loop, 0.1, 10.0)
    with pytest.raises(ValueError, match="axis must be a non-zero finite 3-vector"):
        controllers.slew(loop, 0.1, 10.0, axis=[0, 0, 0])
    planar_loop = controllers.close_loop(PLANAR, controllers.pd(PLANAR, natural_frequency=0.1))
    with pytest.raises(ValueError, match="axis is for three-axis loops"):
        controllers.slew(planar_loop, 0.1, 10.0, axis="x")
    with pytest.raises(ValueError, match=r"natural_frequency must be a real number or 3 of them"):
        controllers.pd(RIGID3, natural_frequency=[0.1, 0.2])
    with pytest.raises(ValueError, match=r"damping\[1\] must be positive and finite \[1\]"):
        controllers.pd(RIGID3, natural_frequency=0.1, damping=[0.7, -1.0, 0.7])
    with pytest.raises(ValueError, match="axes must be 'principal' or 'hub'"):
        controllers.pd(RIGID3, natural_frequency=0.1, axes="body")
    with pytest.raises(ValueError, match=r"attitude_weight must be a real number or 3 of them"):
        controllers.lqr(RIGID3, attitude_weight=[1.0, 2.0], rate_weight=0.0, torque_weight=1.0)
    with pytest.raises(ValueError, match=r"torque_weight\[2\] R must be positive definite"):
        controllers.lqr(RIGID3, attitude_weight=1.0, rate_weight=0.0,
                        torque_weight=[1.0, 1.0, 0.0])
    two = control.ss(RIGID3.A, RIGID3.B[:, :2], RIGID3.C, 0,
                     inputs=["torque_x", "torque_y"], outputs=list(RIGID3.output_labels))
    with pytest.raises(ValueError, match=r"inputs 'torque_x', 'torque_y', 'torque_z'"):
        controllers.pd(two, natural_frequency=0.1)
    with pytest.raises(ValueError, match="do not drive the plant's torque inputs"):
        controllers.close_loop(PLANAR, K)
    with pytest.raises(ValueError, match="three-axis loops need a StateSpace plant"):
        controllers.margins(control.frd(RIGID3, [0.1, 1.0]), K)
    bad_J = three_axis_plant(np.diag([1.0, 2.0, 3.0]))
    bad = control.ss(bad_J.A, bad_J.B @ np.array([[1, 0, 0], [0, 1, 0], [1, 0, 0.0]]), bad_J.C,
                     0, inputs=list(bad_J.input_labels), outputs=list(bad_J.output_labels))
    with pytest.raises(ValueError, match="J symmetric positive definite"):
        controllers.rigid_body_inertia(bad)


def test_no_runtime_warning_leaks_from_three_axis_designs_and_analysis():
    """Continuous and digital three-axis PD and LQR, their margins (undamped poles on the grid
    edges, loop-at-a-time inverses), spillover, a comparison: no numpy RuntimeWarning escapes."""
    import warnings

    Jd = np.diag(J3)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        for K in (controllers.pd(FLEX3, natural_frequency=RATE, roll_off=1.5),
                  controllers.pd(FLEX3, natural_frequency=RATE, sample_time=0.5),
                  controllers.lqr(FLEX3, attitude_weight=(Jd * RATE ** 2) ** 2, rate_weight=0.0,
                                  torque_weight=1.0)):
            m = controllers.margins(TRUTH3, K)
            assert m.disk_margin > 0 and all(np.isfinite(v.modulus_margin)
                                             for v in m.loop_at_a_time.values())
            controllers.spillover(TRUTH3, K)
        controllers.compare(FLEX3, TRUTH3, K, angle=0.05, slew_time=30.0, axis="z",
                            t_final=60.0)
