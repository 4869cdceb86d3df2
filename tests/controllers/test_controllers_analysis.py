"""Loop analysis: inertia, modes, close_loop, margins, spillover, responses, metrics, compare."""
import ast
import math
import pathlib

import control
import numpy as np
import pytest

import controllers
from plants import modal_plant
from controllers.pd import pd_gains


def two_inertia_plant(hub_inertia, appendage_inertia, stiffness, damping):
    """Hub J_h driven by the torque, appendage J_a on a torsion spring k and damper c.

    States [theta_h, omega_h, theta_a, omega_a]; outputs theta = theta_h, omega = omega_h and
    the appendage's relative rotation (as 'wing_tip_deflection' times a 1 m lever)."""
    Jh, Ja, k, c = hub_inertia, appendage_inertia, stiffness, damping
    A = np.array([[0, 1, 0, 0], [-k / Jh, -c / Jh, k / Jh, c / Jh], [0, 0, 0, 1],
                  [k / Ja, c / Ja, -k / Ja, -c / Ja]], dtype=float)
    B = np.array([[0], [1 / Jh], [0], [0]])
    C = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [-1, 0, 1, 0]], dtype=float)
    return control.ss(A, B, C, 0, inputs=["torque"],
                      outputs=["theta", "omega", "wing_tip_deflection"])


J = 250.0  # kg m^2
RIGID = modal_plant(J)
COLLOCATED = modal_plant(J, [(2.0, 0.005, 1.0, 0.002)])
NONCOLLOCATED = modal_plant(J, [(2.0, 0.005, 1.0, -0.002)])


# ----- plant properties ------------------------------------------------------------------------
def test_rigid_body_inertia_modal_and_two_inertia():
    plant = modal_plant(J, [(2.0, 0.005, 0.04, 0.04), (9.0, 0.01, 0.02, 0.02)])
    # the flexible terms vanish at s = 0 after multiplying by s^2: lim s^2 G = 1/J
    assert controllers.rigid_body_inertia(plant) == pytest.approx(J, rel=1e-10)
    two = two_inertia_plant(200.0, 50.0, 400.0, 2.0)
    # the total inertia of hub + appendage: 250 kg m^2
    assert controllers.rigid_body_inertia(two) == pytest.approx(250.0, rel=1e-10)


def test_flexible_modes_match_construction():
    plant = modal_plant(J, [(9.0, 0.01, 0.02, 0.02), (2.0, 0.005, 0.04, 0.04)])
    modes = controllers.flexible_modes(plant)
    assert [m.frequency for m in modes] == pytest.approx([2.0, 9.0], rel=1e-12)
    assert [m.damping_ratio for m in modes] == pytest.approx([0.005, 0.01], rel=1e-9)
    # residue of bc/(s^2 + 2 zeta w s + w^2) at its pole: bc / (2 j w sqrt(1 - zeta^2)),
    # so participation 2 |r| w J = bc J / sqrt(1 - zeta^2)
    assert modes[0].participation == pytest.approx(0.04 ** 2 * J / math.sqrt(1 - 0.005 ** 2),
                                                   rel=1e-9)
    two = two_inertia_plant(200.0, 50.0, 400.0, 0.0)
    # two-inertia antiresonance-free mode: w^2 = k (J_h + J_a) / (J_h J_a)
    (mode,) = controllers.flexible_modes(two)
    assert mode.frequency == pytest.approx(math.sqrt(400.0 * 250.0 / (200.0 * 50.0)), rel=1e-12)
    # a mode the torque cannot excite is not listed
    hidden = modal_plant(J, [(2.0, 0.005, 0.0, 0.04)])
    assert controllers.flexible_modes(hidden) == []


# ----- closing the loop ------------------------------------------------------------------------
def test_close_loop_signals():
    plant = two_inertia_plant(200.0, 50.0, 400.0, 2.0)
    K = controllers.pd(plant, natural_frequency=0.5, roll_off=5.0)
    loop = controllers.close_loop(plant, K)
    assert list(loop.input_labels) == ["theta_ref"]
    assert list(loop.output_labels) == ["theta", "omega", "wing_tip_deflection", "torque"]
    assert loop.nstates == plant.nstates + K.nstates
    loop = controllers.close_loop(COLLOCATED, K)
    assert list(loop.input_labels) == ["theta_ref", "disturbance_torque"]
    with pytest.raises(TypeError, match="plant must be a control.StateSpace"):
        controllers.close_loop(control.tf([1.0], [J, 0.0, 0.0]), K)
    digital = controllers.pd(COLLOCATED, natural_frequency=0.1, sample_time=0.1)
    with pytest.raises(ValueError, match="FrequencyResponseData plant needs a continuous"):
        controllers.close_loop(control.frd(COLLOCATED, [1.0, 2.0]), digital)
    bad = control.ss([], [], [], [[1.0, 1.0]], inputs=["theta", "gyro"], outputs=["torque"])
    with pytest.raises(ValueError, match=r"\['gyro'\] are neither plant outputs nor reference"):
        controllers.close_loop(COLLOCATED, bad)
    wrong_output = control.ss([], [], [], [[1.0]], inputs=["theta"], outputs=["u"])
    with pytest.raises(ValueError, match="exactly one output named 'torque'"):
        controllers.close_loop(COLLOCATED, wrong_output)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_close_loop_against_frequency_domain_algebra(seed):
    """close_loop's state-space algebra (with the algebraic loop through the plant's and the
    controller's feedthrough solved) against the loop closed at each s:
    y = P_t torque + P_d d, torque = K_r r + K_y y_m  =>
    torque = (K_r r + K_y P_md d) / (1 - K_y P_mt). Equal to round-off."""
    rng = np.random.default_rng(seed)
    plant = control.ss(rng.normal(size=(5, 5)), rng.normal(size=(5, 2)), rng.normal(size=(4, 5)),
                       rng.normal(size=(4, 2)), inputs=["disturbance_torque", "torque"],
                       outputs=["omega", "x", "theta", "a_tip_deflection"])
    controller = control.ss(rng.normal(size=(3, 3)), rng.normal(size=(3, 3)),
                            rng.normal(size=(1, 3)), 0.3 * rng.normal(size=(1, 3)),
                            inputs=["omega", "theta_ref", "theta"], outputs=["torque"])
    loop = controllers.close_loop(plant, controller)
    assert list(loop.input_labels) == ["theta_ref", "disturbance_torque"]
    assert list(loop.output_labels) == ["omega", "x", "theta", "a_tip_deflection", "torque"]
    for s in (0.3j, 1.7j, 5.0j, 2.0 + 1.0j):
        P, K = plant(s), controller(s)  # P: (4 outputs, [d, torque]); K: (1, [omega, ref, theta])
        m = [0, 2]  # plant rows of omega and theta
        Ky = K[0, [0, 2]]
        denominator = 1.0 - Ky @ P[m, 1]
        torque = np.array([K[0, 1], Ky @ P[m, 0]]) / denominator  # per unit r, per unit d
        y = np.outer(P[:, 1], torque) + np.hstack([np.zeros((4, 1)), P[:, [0]]])
        expected = np.vstack([y, torque])
        np.testing.assert_allclose(loop(s), expected, rtol=1e-10, atol=1e-12)


def test_close_loop_on_frequency_response_data():
    """The closed loop on an FRD plant equals the state-space closed loop's frequency response,
    also when the FRD has theta only (omega = j w theta), as the exact distributed model does."""
    plant = modal_plant(J, [(2.0, 0.005, 1.0, 0.004), (9.0, 0.005, 1.0, 0.002)])
    K = controllers.lqr(plant, attitude_weight=100.0, rate_weight=300.0, torque_weight=1.0)
    w = np.logspace(-2, 2, 200)
    reference = controllers.close_loop(plant, K)(1j * w)  # (outputs, inputs, f)
    both = controllers.close_loop(control.frd(plant, w), K)
    assert list(both.input_labels) == ["theta_ref", "disturbance_torque"]
    assert list(both.output_labels) == ["theta", "omega", "torque"]
    np.testing.assert_allclose(both.frdata, reference, rtol=1e-9, atol=1e-12)
    theta_only = control.ss(plant.A, plant.B, plant.C[:1], 0, inputs=list(plant.input_labels),
                            outputs=["theta"])
    alone = controllers.close_loop(control.frd(theta_only, w), K)
    assert list(alone.output_labels) == ["theta", "torque"]
    np.testing.assert_allclose(alone.frdata, reference[[0, 2]], rtol=1e-9, atol=1e-12)


def test_disturbance_step_closed_form():
    """theta/d = 1/(J s^2 + Kd s + Kp) under PD: final value d/Kp, peak d/Kp (1 + Mp) at
    t_p = pi / (wn sqrt(1 - zeta^2)), Mp = exp(-pi zeta / sqrt(1 - zeta^2))."""
    wn, zeta, d = 0.5, 0.4, 2.0
    K = controllers.pd(RIGID, natural_frequency=wn, damping=zeta)
    Kp, _ = pd_gains(J, wn, zeta)
    t_p = math.pi / (wn * math.sqrt(1 - zeta ** 2))
    dt = t_p / 400  # the peak lies on the grid
    response = controllers.disturbance_response(controllers.close_loop(RIGID, K), amplitude=d,
                                                t_final=4000 * dt, dt=dt)
    m = controllers.metrics(response)
    Mp = math.exp(-math.pi * zeta / math.sqrt(1 - zeta ** 2))
    assert m["peak_attitude_error"] == pytest.approx(d / Kp * (1 + Mp), rel=1e-9)
    # after 10 t_p the decay exp(-zeta wn t) = exp(-13.7) leaves a relative error ~1e-6
    assert m["final_attitude_error"] == pytest.approx(d / Kp, rel=1e-5)
    torque = response.y[list(response.output_labels).index("torque")]
    assert torque[-1] == pytest.approx(-d, rel=1e-5)  # the controller balances the disturbance
    assert "overshoot" not in m  # no reference to overshoot


def test_slew_profile():
    T, angle = 20.0, 0.3
    t = np.array([0.0, 5.0, 10.0, 15.0, 20.0, 30.0])
    # closed form at t = T/4: angle (1/4 - 1/(2 pi)); both sides a sine to 1 ulp and a few
    # products and sums of O(1) terms (no cancellation below 1/4): ~4 eps relative; rtol 45 eps
    np.testing.assert_allclose(controllers.slew_profile(t, angle, T),
                               angle * np.array([0.0, 0.25 - 1 / (2 * np.pi), 0.5,
                                                 0.75 + 1 / (2 * np.pi), 1.0, 1.0]),
                               rtol=1e-14, atol=1e-16)
    # zero rate at both ends: central differences of order h^2 (the profile is C^2 at 0 and T)
    h = 1e-4
    rate = lambda x: (controllers.slew_profile(x + h, angle, T)  # noqa: E731
                      - controllers.slew_profile(x - h, angle, T)) / (2 * h)
    assert abs(rate(0.0)) < 1e-8 and abs(rate(T)) < 1e-8
    assert rate(T / 2) == pytest.approx(2 * angle / T, rel=1e-7)


def test_slew_reaches_angle_and_metrics_keys():
    K = controllers.pd(COLLOCATED, natural_frequency=0.5)
    response = controllers.slew(controllers.close_loop(COLLOCATED, K), 0.2, 20.0, t_final=100.0)
    m = controllers.metrics(response)
    assert set(m) == {"peak_torque", "peak_attitude_error", "final_attitude_error", "overshoot",
                      "settling_time", "diverged"}
    assert m["diverged"] is False  # 'diverged_at' only when it did
    assert m["final_attitude_error"] < 1e-8  # 80 s after the slew, slowest decay e^-0.35 t
    assert 10.0 < m["settling_time"] < 100.0  # may settle before the end of the profile
    assert response.t[-1] == pytest.approx(100.0)
    np.testing.assert_allclose(response.u[0], controllers.slew_profile(response.t, 0.2, 20.0))


def test_metrics_on_hand_made_response():
    t = np.arange(6.0)
    theta = np.array([0.0, 0.5, 1.1, 1.03, 1.01, 1.0])
    torque = np.array([0.0, 3.0, -2.0, 0.5, 0.1, 0.0])
    tip = np.array([0.0, 0.01, -0.02, 0.0, 0.0, 0.0])
    response = control.TimeResponseData(t, np.vstack([theta, torque, tip]),
                                        inputs=np.ones((1, 6)), input_labels=["theta_ref"],
                                        output_labels=["theta", "torque", "boom_tip_deflection"])
    m = controllers.metrics(response)
    assert m["overshoot"] == pytest.approx(10.0, rel=1e-12)
    assert m["settling_time"] == 4.0  # last sample outside the 2 % band is t = 3 (1.03)
    assert m["peak_torque"] == 3.0 and m["peak_tip_deflection"] == 0.02
    assert m["final_attitude_error"] == 0.0
    unsettled = control.TimeResponseData(t, np.vstack([theta[::-1], torque]), inputs=np.ones((1, 6)),
                                         input_labels=["theta_ref"],
                                         output_labels=["theta", "torque"])
    # not settled by the end: None (no inf in a table), and the loop did not diverge
    assert controllers.metrics(unsettled)["settling_time"] is None
    assert controllers.metrics(unsettled)["diverged"] is False
    # non-finite samples: diverged at the first of them, every other metric None
    diverged = control.TimeResponseData(t, np.vstack([theta, np.where(t > 2, np.inf, torque)]),
                                        inputs=np.ones((1, 6)), input_labels=["theta_ref"],
                                        output_labels=["theta", "torque"])
    m = controllers.metrics(diverged)
    assert m["diverged"] is True and m["diverged_at"] == 3.0
    assert all(m[name] is None for name in ("peak_torque", "peak_attitude_error",
                                            "final_attitude_error", "overshoot",
                                            "settling_time"))
    with pytest.raises(ValueError, match="settling_band must be in"):
        controllers.metrics(response, settling_band=2.0)


# ----- margins ---------------------------------------------------------------------------------
@pytest.mark.parametrize("zeta", [0.3, 0.5, 0.7])
def test_margins_rigid_pd_closed_form(zeta):
    """L = (Kp + Kd s)/(J s^2) = (wn^2 + 2 zeta wn s)/s^2.

    |L| = 1 at wc^2 = wn^2 (2 zeta^2 + sqrt(4 zeta^4 + 1)); PM = atan(2 zeta wc / wn); the phase
    stays above -180 deg, GM = inf. S = 1/(1+L) = s^2/(s^2 + 2 zeta wn s + wn^2) peaks at
    1/(2 zeta sqrt(1 - zeta^2)) for zeta < 1/sqrt(2): modulus margin 2 zeta sqrt(1 - zeta^2)."""
    wn = 0.5
    K = controllers.pd(RIGID, natural_frequency=wn, damping=zeta)
    m = controllers.margins(RIGID, K)
    wc = wn * math.sqrt(2 * zeta ** 2 + math.sqrt(4 * zeta ** 4 + 1))
    assert m.gain_crossover_frequency == pytest.approx(wc, rel=1e-10)
    assert m.phase_margin == pytest.approx(math.degrees(math.atan(2 * zeta * wc / wn)), rel=1e-10)
    assert m.gain_margin == math.inf and m.phase_crossover_frequency == math.inf
    # minimum located by a bounded scalar search: accurate to ~1e-12 in |1 + L|
    assert m.modulus_margin == pytest.approx(2 * zeta * math.sqrt(1 - zeta ** 2), rel=1e-9)


def test_gain_margin_third_order_closed_form():
    """L = k / (s (s+1) (s+2)): phase -180 deg at w = sqrt(2), |L| = k/6 there, so
    GM = 20 log10(6/k) (Ogata, Modern Control Engineering, the classic example)."""
    k = 1.5
    plant = control.ss(control.tf([1.0], [1.0, 3.0, 2.0, 0.0]))
    plant = control.ss(plant.A, plant.B, np.vstack([plant.C, plant.C @ plant.A]), [[0], [0]],
                       inputs=["torque"], outputs=["theta", "omega"])
    controller = control.ss([], [], [], [[k, -k, 0.0]], inputs=["theta_ref", "theta", "omega"],
                            outputs=["torque"])
    m = controllers.margins(plant, controller)
    assert m.phase_crossover_frequency == pytest.approx(math.sqrt(2), rel=1e-12)
    assert m.gain_margin == pytest.approx(20 * math.log10(6 / k), rel=1e-12)


@pytest.mark.slow
def test_margins_flexible_loop_agree_with_python_control():
    plant = modal_plant(J, [(2.0, 0.002, 1.0, 0.004), (7.0, 0.002, 1.0, 0.002)])
    # tuned on the rigid hub (same J): the roll-off destabilises the 7 rad/s mode of this plant,
    # which pd() refuses on a design plant; the margins are compared all the same
    K = controllers.pd(RIGID, natural_frequency=0.5, roll_off=4.0)
    m = controllers.margins(plant, K)
    # independent reference: python-control on L = -K_theta P_theta - K_omega P_omega
    P = control.ss(plant.A, plant.B[:, :1], plant.C, 0)
    Kfb = control.ss(K.A, K.B[:, 1:], K.C, K.D[:, 1:])
    L = -(Kfb * P)
    gm, pm, _, _, wpc, wgc = control.stability_margins(L, returnall=True)
    assert m.phase_margin == pytest.approx(min(pm, key=abs), rel=1e-6)
    i = int(np.argmin(np.abs(np.log(gm))))
    assert m.gain_margin == pytest.approx(20 * np.log10(gm[i]), rel=1e-6)
    # modulus margin against brute force: a coarse grid, then a fine one around its minimum
    w = np.linspace(0.01, 20.0, 4001)
    w0 = w[np.argmin(np.abs(1 + np.ravel(L(1j * w))))]
    w = np.linspace(w0 - 0.005, w0 + 0.005, 10001)
    ref = np.min(np.abs(1 + np.ravel(L(1j * w))))
    assert m.modulus_margin <= ref + 1e-12 and m.modulus_margin == pytest.approx(ref, rel=1e-6)


@pytest.mark.slow
def test_margins_on_frequency_response_data():
    """On a dense FRD of the same plant the margins agree to the interpolation error."""
    plant = modal_plant(J, [(2.0, 0.005, 1.0, 0.004)])
    K = controllers.pd(plant, natural_frequency=0.5, roll_off=4.0)
    exact = controllers.margins(plant, K)
    frd = control.frd(plant, np.logspace(-3, 3, 30000))
    approx = controllers.margins(frd, K)
    assert approx.phase_margin == pytest.approx(exact.phase_margin, rel=1e-5)
    assert approx.gain_margin == pytest.approx(exact.gain_margin, rel=1e-4)
    assert approx.modulus_margin == pytest.approx(exact.modulus_margin, rel=1e-4)
    # an FRD of theta alone (as the exact distributed model gives): omega = j w theta
    theta_only = control.ss(plant.A, plant.B[:, :1], plant.C[:1], 0, inputs=["torque"],
                            outputs=["theta"])
    alone = controllers.margins(control.frd(theta_only, np.logspace(-3, 3, 30000)), K)
    assert alone.phase_margin == pytest.approx(approx.phase_margin, rel=1e-12)
    assert alone.modulus_margin == pytest.approx(approx.modulus_margin, rel=1e-12)
    with pytest.raises(ValueError, match="output named 'theta' or 'omega'"):
        controllers.margins(control.frd(control.ss(theta_only, outputs=["x"]), [1.0, 2.0]), K)


def test_frd_loop_resolves_the_controllers_own_resonances():
    """FRD grid refined only at the plant's mode (2.1 rad/s, 30 points per decade elsewhere,
    steps of 8 %) and a PD with a sharp notch at 6 rad/s (zeta_z = 0.02: the dip is ~0.24 rad/s
    wide, half an FRD step): the loop response adds points across the notch and evaluates the
    controller exactly there, the plant interpolated between FRD points."""
    truth = modal_plant(J, [(2.1, 0.005, 1.0, 0.004)])
    K = controllers.pd(truth, natural_frequency=0.3, notch=6.0)
    w = np.unique(np.concatenate([np.logspace(-3, 3, 181),
                                  2.1 * (1 + 0.005 * np.tan(np.linspace(-1.5, 1.5, 61)))]))
    frd = control.frd(truth, w)
    omega, L = controllers.loop_frequency_response(frd, K)
    assert omega.size > w.size
    _, L_exact = controllers.loop_frequency_response(truth, K, omega=omega)
    # plant interpolation error only (smooth away from 2.1 rad/s; exact for the 1/s^2 part)
    np.testing.assert_allclose(L, L_exact, rtol=2e-3)
    dense = np.linspace(5.5, 6.5, 20001)
    depth = np.min(np.abs(controllers.loop_frequency_response(truth, K, omega=dense)[1]))
    near = (omega > 5.5) & (omega < 6.5)
    assert np.min(np.abs(L[near])) == pytest.approx(depth, rel=1e-2)
    on_frd_grid = (w > 5.5) & (w < 6.5)
    coarse = np.min(np.abs(controllers.loop_frequency_response(truth, K, omega=w[on_frd_grid])[1]))
    assert coarse > 1.5 * depth  # the FRD's own points alone would miss the notch


def test_digital_margins_lose_phase_to_the_hold():
    """The ZOH costs about w T / 2 rad of phase at crossover (Franklin, Powell & Workman)."""
    K = controllers.pd(RIGID, natural_frequency=0.5, damping=0.5)
    T = 0.2
    Kd = controllers.pd(RIGID, natural_frequency=0.5, damping=0.5, sample_time=T)
    mc, md = controllers.margins(RIGID, K), controllers.margins(RIGID, Kd)
    expected_loss = math.degrees(mc.gain_crossover_frequency * T / 2)
    assert mc.phase_margin - md.phase_margin == pytest.approx(expected_loss, rel=0.05)


# ----- spillover -------------------------------------------------------------------------------
@pytest.mark.slow
def test_spillover_verdict_stable_and_unstable():
    """A PD on a collocated plant is stable at any gain (passive loop); the same PD on a plant
    whose mode is seen with the opposite sign (non-collocated) is destabilised."""
    K = controllers.pd(COLLOCATED, natural_frequency=1.0)
    good = controllers.spillover(COLLOCATED, K)
    assert good.stable and good.n_unstable_poles == 0 and good.method == "eigenvalues"
    assert 0 < good.least_damping_ratio < 1
    bad = controllers.spillover(NONCOLLOCATED, K)  # a verdict, not an exception
    assert not bad.stable and bad.n_unstable_poles == 2
    assert bad.least_damping_ratio < 0
    assert bad.least_damped_frequency == pytest.approx(2.0, rel=0.2)
    assert "UNSTABLE" in str(bad)
    # the same verdicts from the Nyquist criterion on frequency-response data
    w = np.logspace(-4, 4, 20000)
    assert controllers.spillover(control.frd(COLLOCATED, w), K).stable
    frd_bad = controllers.spillover(control.frd(NONCOLLOCATED, w), K)
    assert not frd_bad.stable and frd_bad.n_unstable_poles == 2 and frd_bad.method == "nyquist"
    with pytest.raises(ValueError, match="frequency grid too narrow"):
        controllers.spillover(control.frd(COLLOCATED, np.logspace(-1, 1, 100)), K)
    digital = controllers.pd(COLLOCATED, natural_frequency=0.1, sample_time=0.1)
    with pytest.raises(ValueError, match="needs a continuous controller"):
        controllers.spillover(control.frd(COLLOCATED, w), digital)


@pytest.mark.slow
def test_the_nyquist_count_alone_is_the_verdicts():
    """nyquist_count gives spillover's count on frequency-response data (the two unstable
    poles of the non-collocated loop, none of the collocated one), from the loop's response
    when it is given, and refuses what the criterion cannot take, by name."""
    K = controllers.pd(COLLOCATED, natural_frequency=1.0)
    w = np.logspace(-4, 4, 20000)
    for plant, expected in ((COLLOCATED, 0), (NONCOLLOCATED, 2)):
        frd = control.frd(plant, w)
        assert controllers.nyquist_count(frd, K) == expected
        assert controllers.spillover(frd, K).n_unstable_poles == expected
        response = controllers.loop_frequency_response(frd, K)
        assert controllers.nyquist_count(frd, K, response=response) == expected
    with pytest.raises(ValueError, match="frequency grid too narrow"):
        controllers.nyquist_count(control.frd(COLLOCATED, np.logspace(-1, 1, 100)), K)
    with pytest.raises(ValueError, match=r"response must be \(omega, L\)"):
        controllers.nyquist_count(control.frd(COLLOCATED, w), K, response=(w, w[:3]))
    with pytest.raises(TypeError, match="truth_plant must be a control.FrequencyResponseData"):
        controllers.nyquist_count(COLLOCATED, K)


def test_spillover_least_damped_pole_closed_form():
    """Rigid hub under PD: the closed-loop poles are those of s^2 + 2 zeta wn s + wn^2."""
    K = controllers.pd(RIGID, natural_frequency=0.7, damping=0.35)
    verdict = controllers.spillover(RIGID, K)
    assert verdict.stable
    assert verdict.least_damping_ratio == pytest.approx(0.35, rel=1e-10)
    assert verdict.least_damped_frequency == pytest.approx(0.7, rel=1e-10)


@pytest.mark.parametrize("seed", range(6))
def test_pd_without_roll_off_stable_on_any_collocated_plant(seed):
    """Property: torque and hub attitude/rate are collocated, the plant is passive from torque
    to omega and a PD is strictly passive, so the loop is stable whatever the modes and gains
    (Balas 1978; Wie 2008, collocated control). Seeded random modes, damping and gains."""
    rng = np.random.default_rng(seed)
    n_modes = int(rng.integers(1, 5))
    modes = [(float(w), float(z), float(c), float(c)) for w, z, c in
             zip(np.sort(10 ** rng.uniform(-0.5, 2, n_modes)), 10 ** rng.uniform(-3, -1, n_modes),
                 rng.uniform(0.01, 0.05, n_modes))]
    plant = modal_plant(float(10 ** rng.uniform(1, 3)), modes)
    K = controllers.pd(plant, natural_frequency=float(10 ** rng.uniform(-1.5, 0.5)),
                       damping=float(rng.uniform(0.3, 1.5)))
    verdict = controllers.spillover(plant, K)
    assert verdict.stable and verdict.least_damping_ratio > 0


# ----- compare ---------------------------------------------------------------------------------
def test_compare_design_vs_truth():
    design = modal_plant(J, [(2.0, 0.005, 1.0, 0.004)])
    truth = modal_plant(J, [(2.1, 0.005, 1.0, 0.0042), (12.0, 0.005, 1.0, 0.001)])
    K = controllers.lqr(design, attitude_weight=400.0, rate_weight=1000.0, torque_weight=1.0)
    result = controllers.compare(design, truth, K, angle=0.2, slew_time=20.0)
    assert result.verdict.stable
    names = [row[0] for row in result.rows]
    assert names[:2] == ["peak_torque", "peak_attitude_error"]
    assert {"overshoot", "settling_time", "gain_margin", "phase_margin",
            "modulus_margin"} <= set(names)
    np.testing.assert_allclose(result.difference["theta"],
                               result.truth_response.y[0] - result.design_response.y[0])
    assert 0 < result.peak_difference["theta"] < 0.01 * 0.2
    text = str(result)
    assert "design" in text and "truth" in text and "STABLE" in text
    fig = result.plot()
    assert len(fig.axes) == 6
    with pytest.raises(TypeError, match="truth_plant must be a control.StateSpace"):
        controllers.compare(design, control.frd(truth, [1.0]), K, angle=0.2, slew_time=20.0)


@pytest.mark.slow
def test_controllers_import_no_other_flexsat_package():
    """DESIGN.md: controllers works on any LTI plant and imports no other package of ours."""
    ours = {"appendages", "spacecraft", "fmu"}
    for path in pathlib.Path(controllers.__file__).parent.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module or ""]
            else:
                continue
            assert not {n.split(".")[0] for n in names} & ours, f"{path.name} imports {names}"


# ----- fast margins: vectorised root refinement, residue evaluator ------------------------------
def test_crossings_refines_all_brackets_together_and_drops_pole_passes():
    """f(x) = (x - 1)(x - 3)(x - 5) / (x - 2): roots 1, 3, 5 (exact), an undamped-pole-like
    sign change at 2 that is no root. All brackets share one vectorised evaluation per
    iteration, at most three points per bracket: the old scalar brentq loop made ~10 calls
    per bracket (~670 single-frequency evaluations per margins call, the bottleneck)."""
    from controllers.margins import zero_crossings

    calls = []

    def f(x):
        calls.append(np.size(x))
        return (x - 1.0) * (x - 3.0) * (x - 5.0) / (x - 2.0)

    grid = np.linspace(0.55, 5.45, 8)  # no grid point on a root or on the pole
    roots = np.sort(zero_crossings(f, grid, f(grid)))
    calls = calls[1:]  # the grid evaluation above
    np.testing.assert_allclose(roots, [1.0, 3.0, 5.0], rtol=1e-13)  # 1e-13 b stopping width
    assert len(calls) <= 40 and all(n <= 3 * 4 for n in calls)


def test_crossings_exact_grid_zero_and_no_sign_change():
    from controllers.margins import zero_crossings

    grid = np.array([0.5, 1.0, 1.5])
    values = np.array([-1.0, 0.0, 2.0])
    np.testing.assert_array_equal(zero_crossings(lambda x: x - 1.0, grid, values), [1.0])
    assert zero_crossings(np.cos, grid, np.ones(3)).size == 0


def test_modal_evaluator_matches_resolvent():
    """G(s) = C (sI - A)^-1 B + D from the residues and the triangular rigid block equals a
    direct solve on a free-floating plant (rigid Jordan block) with two outputs, round-off
    only (1e-12 relative to |G|)."""
    from controllers.frequency import modal_evaluator

    plant = modal_plant(J, [(2.0, 0.01, 0.05, 0.05), (9.0, 0.0, 0.02, -0.01)])
    ev = modal_evaluator(plant, ["torque", "disturbance_torque"], ["theta", "omega"])
    assert ev.modal and ev.k == 2
    s = 1j * np.array([0.013, 0.7, 2.05, 8.9, 40.0]) + np.array([0.0, 0.0, 0.0, 0.0, 0.3])
    G = ev(s)
    assert G.shape == (5, 2, 2) and G.dtype == np.complex128
    for k, sk in enumerate(s):
        ref = plant.C @ np.linalg.solve(sk * np.eye(plant.nstates) - plant.A, plant.B) + plant.D
        np.testing.assert_allclose(G[k], ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max())


def test_margins_evaluation_count_on_flexible_loop():
    """Regression for the cost of margins: the loop is evaluated in a few dozen vectorised calls
    (grid, one per refinement iteration, the modulus search), not once per brentq step; the
    margins themselves agree with python-control (see the test above)."""
    from controllers import loop as loop_module

    plant = modal_plant(J, [(2.0, 0.002, 1.0, 0.004), (7.0, 0.0, 1.0, 0.002),
                            (15.0, 0.0, 1.0, -0.001)])
    K = controllers.pd(RIGID, natural_frequency=0.5, roll_off=4.0)  # unstable on this plant
    counted = []
    original = loop_module.LoopTransfer.__call__

    def counting(self, omega):
        counted.append(np.size(omega))
        return original(self, omega)

    loop_module.LoopTransfer.__call__ = counting
    try:
        m = controllers.margins(plant, K)
    finally:
        loop_module.LoopTransfer.__call__ = original
    assert len(counted) < 80  # was ~10 per sign-change bracket plus ~25 for the modulus search
    assert math.isfinite(m.phase_margin) and m.modulus_margin > 0
