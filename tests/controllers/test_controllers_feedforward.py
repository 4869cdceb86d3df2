"""PD and LQR with a rate reference and a feedforward torque, the flown profile and its metrics.

On a rigid body the rest-to-rest profile with its feedforward torque J s'' is followed exactly:
theta = theta_ref is a solution of J theta'' = torque_ff + feedback with zero feedback, and with
zero initial state it is the solution. The profile is fed through its generator with a
zero-order hold on a grid through every breakpoint (exact), so the tracking error is round-off:
~1e-13 relative to the slew angle over 1e4 steps (the simulator's error budget,
benchmarks/results/simulate_error_budget.json); 1e-10 is asserted.
"""
import math

import control
import numpy as np
import pytest

import controllers
from controllers import profiles as P
from controllers.lqr import lqr_design
from plants import modal_plant, three_axis_plant

J = 250.0
RIGID = modal_plant(J, [])
FLEX = modal_plant(J, [(1.2, 0.005, 0.05, 0.05), (6.0, 0.005, 0.02, 0.02)],
                   tips=[("wing_tip_deflection", [0.8, -0.3])])
LQR_WEIGHTS = dict(attitude_weight=1e3, rate_weight=1e4, torque_weight=1.0)


def test_pd_feedforward_law_and_unchanged_feedback():
    """torque = Kp (theta_ref - theta) + Kd (omega_ref - omega) + torque_ff; the feedback part
    and every existing column are the controller without feedforward, bit for bit."""
    K0 = controllers.pd(FLEX, natural_frequency=0.2, roll_off=3.0)
    K1 = controllers.pd(FLEX, natural_frequency=0.2, roll_off=3.0, feedforward=True)
    assert list(K1.input_labels) == ["theta_ref", "omega_ref", "torque_ff", "theta", "omega"]
    keep = [0, 3, 4]
    np.testing.assert_array_equal(K1.A, K0.A)
    np.testing.assert_array_equal(K1.B[:, keep], K0.B)
    np.testing.assert_array_equal(K1.D[:, keep], K0.D)
    # the static law
    Kp, Kd = controllers.pd_gains(J, 0.2, 0.7)
    static = controllers.pd(FLEX, natural_frequency=0.2, feedforward=True)
    x = np.array([0.3, -0.02, 0.7, 0.1, 0.05])
    assert (static.D @ x)[0] == pytest.approx(Kp * (0.3 - 0.1) + Kd * (-0.02 - 0.05) + 0.7,
                                              rel=1e-15)


def test_lqr_feedforward_keeps_the_design():
    d0 = lqr_design(FLEX, **LQR_WEIGHTS)
    d1 = lqr_design(FLEX, **LQR_WEIGHTS, feedforward=True)
    K0, K1 = d0.controller, d1.controller
    assert list(K1.input_labels) == ["theta_ref", "omega_ref", "torque_ff", "theta", "omega"]
    keep = [0, 3, 4]
    np.testing.assert_array_equal(K1.A, K0.A)
    np.testing.assert_array_equal(K1.B[:, keep], K0.B)
    np.testing.assert_array_equal(K1.D[:, keep], K0.D)
    # x_rate: a unit rigid rate, A x_rate = x_ref, theta = 0, omega = 1
    plant = d1.design_plant
    np.testing.assert_allclose(plant.A @ d1.x_rate, d1.x_ref, rtol=0, atol=1e-14)
    assert (plant.C[0] @ d1.x_rate, plant.C[1] @ d1.x_rate) == pytest.approx((0.0, 1.0),
                                                                            abs=1e-14)
    # torque_ff reaches the torque directly and the estimator through B u
    np.testing.assert_array_equal(K1.D[:, 2], [1.0])
    np.testing.assert_allclose(K1.B[:, 2], (d1.design_plant.B[:, 0] - d1.L @ plant.D[:2, 0]),
                               rtol=1e-15, atol=0)


def driven_tracking_error(plant, controller, profile, inertia, dt):
    """max |theta - theta_ref| / |angle| of the loop driven exactly by the profile."""
    loop = controllers.close_loop(plant, controller)
    response = controllers.profile_response(loop, profile, inertia=inertia, dt=dt,
                                            t_final=profile.end_time * 1.5, hold="generator")
    labels = list(loop.output_labels)
    thetas = [n for n in labels if n.startswith("theta")]
    refs = profile.references(response.t, None)
    error = max(np.max(np.abs(response.y[labels.index(n)] - refs[n.replace("theta", "theta_ref")]))
                for n in thetas)
    return error / abs(profile.angle), response


# the digital loop reads the references at its samples, and its held torque is J s'' exactly
# only where s'' is constant between samples: bang-coast-bang and shaped on the 0.5 s grid
@pytest.mark.parametrize("design, kind", [
    (d, k) for d in ("pd", "lqr") for k in ("bang-coast-bang", "smooth", "shaped")]
    + [("pd-digital", "bang-coast-bang"), ("pd-digital", "shaped")])
def test_rigid_body_follows_the_profile_exactly(design, kind):
    profile = P.reference_profile(kind, 0.2, 40.0, inertia=J, torque_limit=0.2,
                                  rate_limit=0.01, shaper=P.zv_shaper(math.pi / 2.5)
                                  if kind == "shaped" else None)
    if design == "pd":
        K = controllers.pd(RIGID, natural_frequency=0.2, feedforward=True)
    elif design == "lqr":
        K = controllers.lqr(RIGID, **LQR_WEIGHTS, feedforward=True)
    else:
        K = controllers.pd(RIGID, natural_frequency=0.2, sample_time=0.5, feedforward=True)
    if design == "pd-digital":
        loop = controllers.close_loop(RIGID, K)
        response = controllers.profile_response(loop, profile, inertia=J,
                                                t_final=profile.end_time * 1.5)
        error = np.max(np.abs(response.y[0] - profile.theta_ref(response.t))) / 0.2
    else:
        error, _ = driven_tracking_error(RIGID, K, profile, J, 0.01)
    assert error <= 1e-10


@pytest.mark.parametrize("design", ["pd", "lqr"])
def test_three_axis_rigid_body_follows_the_profile_exactly(design):
    Jm = np.array([[300.0, 15.0, -4.0], [15.0, 250.0, 8.0], [-4.0, 8.0, 420.0]])
    plant = three_axis_plant(Jm)
    profile = P.jerk_limited(0.15, 60.0, inertia=Jm, torque_limit=0.3, axis=[1.0, -2.0, 0.5])
    if design == "pd":
        K = controllers.pd(plant, natural_frequency=0.25, feedforward=True)
    else:
        K = controllers.lqr(plant, **LQR_WEIGHTS, feedforward=True)
    error, _ = driven_tracking_error(plant, K, profile, Jm, 0.02)
    assert error <= 1e-10


def test_feedforward_profile_removes_the_lag_of_the_step_reference():
    """The default scene's observation: the step-like reference (cycloid on theta_ref alone)
    leaves an attitude error of the order of the loop's lag during the slew; the same loop with
    the profile's rate and torque feedforward follows it within the flexible response."""
    K0 = controllers.pd(FLEX, natural_frequency=0.2, roll_off=3.0)
    K1 = controllers.pd(FLEX, natural_frequency=0.2, roll_off=3.0, feedforward=True)
    step = P.step_reference(0.2, 60.0)
    smooth = P.jerk_limited(0.2, 60.0)
    r0 = controllers.profile_response(controllers.close_loop(FLEX, K0), step, dt=0.05,
                                      t_final=150.0)
    r1 = controllers.profile_response(controllers.close_loop(FLEX, K1), smooth, inertia=J,
                                      dt=0.05, t_final=150.0)
    m0 = controllers.manoeuvre_metrics(r0)
    m1 = controllers.manoeuvre_metrics(r1)
    assert m1["peak_attitude_error_during"] < 0.05 * m0["peak_attitude_error_during"]
    assert m1["residual_attitude_error"] < 0.1 * m0["residual_attitude_error"]
    # the feedforward torque is about J s'' during the slew
    assert m1["peak_torque_during"] == pytest.approx(J * smooth.peak_acceleration, rel=0.1)


def test_manoeuvre_metrics_by_hand():
    """A crafted response: error 0.3 during (t <= 2), 0.01 at t = 2.5 and 0.005 after, tip 0.2
    at t = 3, torque peak 4 at t = 1 and 9 after the end."""
    t = np.linspace(0.0, 5.0, 11)
    ref = np.where(t < 2.0, t / 2.0, 1.0)
    theta = ref.copy()
    theta[2] += 0.3                  # t = 1.0
    theta[5] += 0.01                 # t = 2.5
    theta[6:] += 0.005
    torque = np.zeros_like(t)
    torque[2], torque[7] = 4.0, -9.0
    tip = np.zeros_like(t)
    tip[6] = -0.2
    response = control.TimeResponseData(t, np.vstack([theta, np.zeros_like(t), tip, torque]),
                                        None, ref[None, :], output_labels=["theta", "omega",
                                                                           "a_tip_deflection",
                                                                           "torque"],
                                        input_labels=["theta_ref"], issiso=False)
    m = controllers.manoeuvre_metrics(response, 2.0, settling_band=0.008)
    assert m["peak_attitude_error_during"] == pytest.approx(0.3, rel=1e-15)
    assert m["peak_torque_during"] == 4.0
    assert m["residual_attitude_error"] == pytest.approx(0.01, rel=1e-12)
    assert m["residual_tip_deflection"] == 0.2
    assert m["settling_time_after_end"] == pytest.approx(1.0, rel=1e-15)   # from t = 3.0
    assert m["profile_end"] == 2.0 and m["diverged"] is False
    for name in m:
        if name != "diverged":
            assert name in controllers.METRIC_UNITS
    with pytest.raises(ValueError, match="end_time"):
        controllers.manoeuvre_metrics(response, 7.0)
    with pytest.raises(ValueError, match="end_time"):
        controllers.manoeuvre_metrics(response)


def test_profile_response_needs_the_inertia_for_feedforward():
    K = controllers.pd(RIGID, natural_frequency=0.2, feedforward=True)
    loop = controllers.close_loop(RIGID, K)
    with pytest.raises(ValueError, match="inertia"):
        controllers.profile_response(loop, P.jerk_limited(0.1, 20.0))
    with pytest.raises(ValueError, match="profile"):
        controllers.profile_response(loop, P.jerk_limited(0.1, 20.0, axis="x"), inertia=J)
    with pytest.raises(TypeError, match="feedforward"):
        controllers.pd(RIGID, natural_frequency=0.2, feedforward="yes")
    with pytest.raises(TypeError, match="feedforward"):
        controllers.lqr(RIGID, **LQR_WEIGHTS, feedforward=1)
