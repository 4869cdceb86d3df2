"""Reaction wheels (controllers.wheels) and the closed loop through them (controllers.wheel_loop).

References of the checks: the pyramid's distribution matrix in closed form (Markley & Crassidis
2014, sec. 7.2.1), the time-optimal rest-to-rest slew in closed form (Wie 2008, sec. 7.3), the
linear loop (controllers.simulate) where no limit acts, an independent full-state per-sample
implementation of the same method, and a continuous-time integration of the nonlinear loop.
"""
import math
import warnings

import control
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import controllers
from controllers.discretise import discretise
from plants import modal_plant, three_axis_plant

J = 250.0                                   # kg m^2
PLANT = modal_plant(J, [(2.0, 0.005, 0.04, 0.04)], tips=[("wing_tip_deflection", [0.5])],
                    disturbance=False)
PD = controllers.pd(PLANT, natural_frequency=0.1, damping=0.7)
DT = 0.1                                    # s
T = np.arange(2001) * DT
ANGLE, SLEW_TIME = math.radians(10.0), 60.0
SLEW = controllers.slew_profile(T, ANGLE, SLEW_TIME)
MAGIC = math.acos(1.0 / math.sqrt(3.0))     # rad: the isotropic pyramid


def wheel(**kwargs):
    values = dict(torque_limit=0.03, momentum_limit=None, spin_inertia=0.01)
    values.update(kwargs)
    return controllers.ReactionWheel(**values)


def planar(**kwargs):
    return controllers.WheelSet(wheel(**kwargs))


def peak_relative(a, b):
    """max |a - b| / max |b| per row."""
    return np.max(np.abs(a - b), axis=-1) / np.maximum(np.max(np.abs(b), axis=-1), 1e-300)


def signals(response, names):
    labels = list(response.output_labels)
    y = np.asarray(response.outputs).reshape(len(labels), -1)
    return np.array([y[labels.index(n)] for n in names])


# -- one wheel -------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, match, error", [
    (dict(torque_limit=-1.0), r"torque_limit must be positive and finite \[N\*m\]", ValueError),
    (dict(torque_limit=0.0), r"torque_limit must be positive", ValueError),
    (dict(torque_limit=math.nan), r"torque_limit must be positive", ValueError),
    (dict(torque_limit="0.03 N m"), r"torque_limit must be a real number \[N\*m\]", TypeError),
    (dict(torque_limit=True), r"torque_limit must be a real number", TypeError),
    (dict(momentum_limit=-2.0), r"momentum_limit must be positive and finite \[N\*m\*s\]",
     ValueError),
    (dict(momentum_limit=math.inf), r"momentum_limit must be positive and finite", ValueError),
    (dict(spin_inertia=0.0), r"spin_inertia must be positive and finite \[kg\*m\^2\]",
     ValueError),
    (dict(viscous_friction=-1e-3), r"viscous_friction must be non-negative", ValueError),
    (dict(coulomb_friction=-1e-3), r"coulomb_friction must be non-negative and finite \[N\*m\]",
     ValueError),
    (dict(spin_inertia=None, viscous_friction=1e-3), r"viscous_friction needs spin_inertia",
     ValueError),
    (dict(momentum_limit=1.0, initial_momentum=1.5), r"initial_momentum must lie within",
     ValueError),
    (dict(initial_momentum=math.inf), r"initial_momentum must be finite", ValueError),
])
def test_wheel_parameters_are_checked(kwargs, match, error):
    with pytest.raises(error, match=match):
        wheel(**kwargs)


def test_wheel_torque_limit_that_looks_like_mN_m_warns():
    with pytest.warns(UserWarning, match=r"mN\*m"):
        wheel(torque_limit=30.0)


def test_wheel_limits_may_be_absent_and_give_its_speed_limit():
    w = wheel(torque_limit=None, momentum_limit=2.0, spin_inertia=0.05)
    assert w.torque_limit is None and w.speed_limit == pytest.approx(40.0, rel=1e-15)
    assert wheel(spin_inertia=None).speed_limit is None


# -- wheel sets ------------------------------------------------------------------------------
@pytest.mark.parametrize("beta", [0.3, MAGIC, 1.2])
def test_pyramid_distribution_in_closed_form(beta):
    # G G^T = diag(2 sin^2 b, 2 sin^2 b, 4 cos^2 b); the allocation is G^T (G G^T)^-1 and
    # G G^+ = I (Markley & Crassidis 2014, sec. 7.2.1)
    ws = controllers.WheelSet.pyramid(wheel(torque_limit=0.1), beta, azimuth=0.2)
    G = ws.distribution
    s2, c2 = math.sin(beta) ** 2, math.cos(beta) ** 2
    np.testing.assert_allclose(G @ G.T, np.diag([2 * s2, 2 * s2, 4 * c2]), rtol=0, atol=1e-15)
    np.testing.assert_allclose(ws.allocation, G.T @ np.linalg.inv(G @ G.T), rtol=0, atol=1e-14)
    np.testing.assert_allclose(G @ ws.allocation, np.eye(3), rtol=0, atol=1e-14)
    # capacities 2 tau sin(beta) / max_i |cos a_i| about x (a_i = 0.2 + i pi/2: the first
    # wheel's azimuth), 4 tau cos(beta) about z
    assert ws.torque_capacity([1, 0, 0]) == pytest.approx(0.2 * math.sin(beta) / math.cos(0.2),
                                                          rel=1e-13)
    assert ws.torque_capacity([0, 0, 2.0]) == pytest.approx(0.4 * math.cos(beta), rel=1e-13)
    assert ws.momentum_capacity([0, 0, 1]) == math.inf


def test_isotropic_pyramid_needs_the_same_wheel_torque_about_every_axis():
    ws = controllers.WheelSet.pyramid(wheel(), MAGIC)
    rng = np.random.default_rng(1)
    for e in rng.normal(size=(20, 3)):
        e /= np.linalg.norm(e)
        assert np.linalg.norm(ws.allocation @ e) == pytest.approx(math.sqrt(3) / 2, rel=1e-13)


def test_the_planar_set_is_one_wheel_about_z():
    ws = planar()
    assert ws.planar and ws.n_axes == 1 and ws.names == ("wheel",)
    np.testing.assert_array_equal(ws.distribution, [[1.0]])
    assert ws.torque_capacity() == 0.03
    with pytest.raises(ValueError, match="spin_axes must be given for 2 wheels"):
        controllers.WheelSet([wheel(), wheel()])


@pytest.mark.parametrize("axes", [
    [[1, 0, 0], [0, 1, 0], [1, 1, 0]],                    # coplanar
    [[1, 0, 0], [0, 1, 0]],                               # two wheels
    [[0, 0, 1], [0, 0, 2], [0, 0, -1], [0, 0, 1]],        # one axis
])
def test_axes_that_do_not_span_are_refused(axes):
    with pytest.raises(ValueError, match=r"spin_axes do not span the controlled axes"):
        controllers.WheelSet([wheel()] * len(axes), axes)


def test_the_message_names_the_missing_direction():
    with pytest.raises(ValueError, match=r"about the direction \[ ?-?0\. +-?0\. +-?1\.\]"):
        controllers.WheelSet([wheel()] * 3, [[1, 0, 0], [0, 1, 0], [1, 1, 0]])


def test_weakly_spanning_axes_warn():
    with pytest.warns(UserWarning, match="span the hub axes weakly"):
        controllers.WheelSet([wheel()] * 3, [[1, 0, 0], [0, 1, 0], [1, 1, 0.05]])


@pytest.mark.parametrize("kwargs, match", [
    (dict(cant_angle=0.0), r"cant_angle must lie in \(0, pi/2\) \[rad\]"),
    (dict(cant_angle=math.pi / 2), r"cant_angle must lie in"),
    (dict(cant_angle=54.7), r"degrees\? give radians"),
    (dict(cant_angle=MAGIC, azimuth=math.nan), r"azimuth must be finite and within"),
])
def test_pyramid_parameters_are_checked(kwargs, match):
    with pytest.raises(ValueError, match=match):
        controllers.WheelSet.pyramid(wheel(), **kwargs)


@pytest.mark.parametrize("args, kwargs, match, error", [
    (([],), {}, "at least one ReactionWheel", ValueError),
    (("wheel",), {}, "wheels must be a ReactionWheel", TypeError),
    (([1.0],), {}, r"wheels\[0\] must be a controllers.ReactionWheel", TypeError),
    ((wheel(),), dict(saturation="cut"), "saturation must be one of", ValueError),
    (([wheel()] * 3, np.eye(3)[:2]), {}, r"spin_axes must have shape \(n_wheels, 3\)",
     ValueError),
    (([wheel()] * 3, [[1, 0, 0], [0, 0, 0], [0, 0, 1]]), {}, r"spin_axes\[1\] must be a non-zero",
     ValueError),
    (([wheel()] * 3, np.eye(3)), dict(names=["a", "a", "b"]), "names must be distinct",
     ValueError),
    (([wheel()] * 3, np.eye(3)), dict(names=["a", "b c", "d"]), "names must be 3 identifiers",
     ValueError),
])
def test_wheel_set_parameters_are_checked(args, kwargs, match, error):
    with pytest.raises(error, match=match):
        controllers.WheelSet(*args, **kwargs)


def test_torque_saturation_scales_or_clips():
    ws_scale = controllers.WheelSet([wheel(torque_limit=1.0)] * 3, np.eye(3))
    ws_clip = controllers.WheelSet([wheel(torque_limit=1.0)] * 3, np.eye(3), saturation="clip")
    c, h = np.array([2.0, -0.5, 1.0]), np.zeros(3)
    w, ts, ms = ws_scale.applied_torques(c, h)
    np.testing.assert_allclose(w, c / 2.0, rtol=0, atol=0)          # direction kept
    np.testing.assert_array_equal(ts, [True, False, False])
    w, ts, ms = ws_clip.applied_torques(c, h)
    np.testing.assert_allclose(w, [1.0, -0.5, 1.0], rtol=0, atol=0)
    assert not ms.any()


def test_momentum_limit_stops_the_motor_only_when_it_would_spin_the_wheel_further():
    # h' = -w: a wheel at +limit is spun further by a negative hub torque (m h < 0), not by a
    # positive one (Basilisk's rule Omega u_s >= 0 with u_s = -m)
    ws = planar(momentum_limit=1.0)
    # three samples of the one wheel (columns)
    w, ts, ms = ws.applied_torques(np.array([[-0.02, 0.02, -0.02]]), np.array([[1.0, 1.0,
                                                                                 0.99]]))
    np.testing.assert_array_equal(ms[0], [True, False, False])
    np.testing.assert_allclose(w[0], [0.0, 0.02, -0.02], rtol=0, atol=0)
    # one sample
    w1, _, ms1 = ws.applied_torques(np.array([-0.02]), np.array([1.0]))
    assert w1[0] == 0.0 and ms1[0]


def test_friction_drags_the_hub_along_with_the_rotor():
    ws = planar(spin_inertia=0.02, viscous_friction=1e-3, coulomb_friction=2e-4)
    h = np.array([[0.1, -0.1, 0.0]])                        # Omega = 5, -5, 0 rad/s
    np.testing.assert_allclose(ws.friction_torques(h)[0], [5e-3 + 2e-4, -5e-3 - 2e-4, 0.0],
                               rtol=1e-15, atol=0)
    w, _, _ = ws.applied_torques(np.zeros((1, 3)), h)
    np.testing.assert_allclose(w, ws.friction_torques(h), rtol=0, atol=0)


# -- the shortest slew -----------------------------------------------------------------------
def test_shortest_slew_time_in_closed_form():
    # Wie (2008), sec. 7.3: bang-bang when omega_m is not reached, bang-coast-bang otherwise
    Jz, tau, H = 300.0, 0.03, 1.0
    ws = planar(torque_limit=tau, momentum_limit=H)
    small = 0.01                       # rad: J omega_m^2 / tau = 0.111 rad > small
    assert controllers.shortest_slew_time(ws, small, Jz) == pytest.approx(
        2 * math.sqrt(small * Jz / tau), rel=1e-14)
    big = 0.5
    omega_m = H / Jz
    assert controllers.shortest_slew_time(ws, -big, Jz) == pytest.approx(
        big / omega_m + Jz * omega_m / tau, rel=1e-14)
    assert controllers.shortest_slew_time(planar(torque_limit=None), big, Jz) == 0.0


def test_initial_momentum_leaves_less_room_one_way():
    Jz, H = 300.0, 1.0
    ws = planar(torque_limit=0.03, momentum_limit=H, initial_momentum=-0.5)
    # a positive slew drives the wheel's momentum negative (h = h0 - J omega): room 0.5
    one_way = controllers.shortest_slew_time(ws, 0.5, Jz)
    other_way = controllers.shortest_slew_time(ws, -0.5, Jz)
    omega = 0.5 / Jz
    assert one_way == pytest.approx(0.5 / omega + Jz * omega / 0.03, rel=1e-14)
    assert other_way < one_way


def test_a_slew_the_wheels_cannot_make_names_the_shortest_time():
    ws = planar(torque_limit=0.03, momentum_limit=1.0)
    shortest = controllers.shortest_slew_time(ws, ANGLE, 275.0)
    with pytest.raises(ValueError, match=rf"allow it in no less than {shortest:.4g} s"):
        controllers.check_slew_time(ws, ANGLE, 0.9 * shortest, 275.0)
    assert controllers.check_slew_time(ws, ANGLE, 1.1 * shortest, 275.0) == shortest


def test_three_axis_shortest_slew_needs_the_axis_and_a_tensor():
    ws = controllers.WheelSet.pyramid(wheel(momentum_limit=1.0), MAGIC)
    inertia = np.diag([300.0, 200.0, 100.0])
    t_x = controllers.shortest_slew_time(ws, 0.5, inertia, axis=[1, 0, 0])
    tau_x = ws.torque_capacity([1, 0, 0])
    H_x = ws.momentum_capacity([1, 0, 0])
    omega = H_x / 300.0
    assert 0.5 > 300.0 * omega ** 2 / tau_x                 # the coasting branch
    assert t_x == pytest.approx(0.5 / omega + 300.0 * omega / tau_x, rel=1e-13)
    with pytest.raises(ValueError, match="direction must be given"):
        controllers.shortest_slew_time(ws, 0.1, inertia)
    with pytest.raises(ValueError, match="inertia must be symmetric positive definite"):
        controllers.shortest_slew_time(ws, 0.1, -inertia, axis=[1, 0, 0])
    # off a principal axis the torque J e a and momentum J e omega point along J e, not e
    # (J_zz 150, not 100: principal moments 186, 314 and 100 break the triangle inequality of a
    # body, 314 > 186 + 100, and are refused; J e is the same)
    full = np.array([[300.0, 40.0, 0.0], [40.0, 200.0, 0.0], [0.0, 0.0, 150.0]])
    e = np.array([1.0, 0.0, 0.0])
    Je = full @ e
    u = Je / np.linalg.norm(Je)
    A = ws.torque_capacity(u) / np.linalg.norm(Je)
    W = ws.momentum_capacity(u) / np.linalg.norm(Je)
    assert 0.5 > W * W / A
    assert controllers.shortest_slew_time(ws, 0.5, full, axis=e) == pytest.approx(
        0.5 / W + W / A, rel=1e-13)


# -- the loop: where no limit acts, the linear loop ---------------------------------------
def linear_response(plant, controller, T, U):
    loop = controllers.close_loop(plant, controller)
    return loop, np.asarray(controllers.simulate(loop, T, U).outputs).reshape(loop.noutputs, -1)


@pytest.mark.parametrize("kind", ["pd", "lqr", "digital"])
def test_a_wheel_that_never_saturates_gives_the_linear_response(kind):
    # Both are exact simulations of the same linear loop (the wheels' system adds integrators
    # for the momenta and an input that stays zero): they differ by round-off accumulated over
    # 2000 steps, ~1e-14 of each signal's peak; 1e-11 leaves a wide margin.
    if kind == "lqr":
        K = controllers.lqr(PLANT, attitude_weight=7.6, rate_weight=0.0, torque_weight=1.0)
    elif kind == "digital":
        K = controllers.pd(PLANT, natural_frequency=0.1, damping=0.7, sample_time=DT)
    else:
        K = PD
    loop, y_lin = linear_response(PLANT, K, T, SLEW)
    result = controllers.simulate_wheels(PLANT, K, planar(torque_limit=1.0, momentum_limit=10.0),
                                         T, SLEW)
    y = signals(result.response, loop.output_labels)
    assert np.all(peak_relative(y, y_lin) <= 1e-11), peak_relative(y, y_lin)
    # the applied torque is the command
    np.testing.assert_array_equal(*signals(result.response, ["torque", "torque_command"]))
    assert not result.saturated and result.time_saturated == 0.0
    assert result.first_saturation is None
    assert result.momentum_margin["wheel"] == pytest.approx(
        10.0 - result.peak_momentum["wheel"], rel=1e-15)


def test_a_delayed_loop_through_a_wheel_that_never_saturates_is_the_delayed_loop():
    # the wheel receives the command of `delay` earlier: with no limit reached, the delayed
    # loop of close_loop (exact for a digital controller), to round-off
    K = controllers.pd(PLANT, natural_frequency=0.1, damping=0.7, sample_time=DT)
    loop = controllers.close_loop(PLANT, K, delay=0.25)
    y_lin = np.asarray(controllers.simulate(loop, T, SLEW).outputs).reshape(loop.noutputs, -1)
    result = controllers.simulate_wheels(PLANT, K, planar(torque_limit=1.0), T, SLEW,
                                         delay=0.25)
    y = signals(result.response, loop.output_labels)
    assert np.all(peak_relative(y, y_lin) <= 1e-11), peak_relative(y, y_lin)
    assert controllers.simulate_wheels(PLANT, K, planar(torque_limit=0.03), T, SLEW,
                                       delay=0.25).saturated


def test_three_axis_wheels_that_never_saturate_give_the_linear_response():
    inertia = np.array([[300.0, 5.0, -3.0], [5.0, 200.0, 2.0], [-3.0, 2.0, 150.0]])
    plant = three_axis_plant(inertia, [(1.5, 0.01, np.array([0.02, 0.01, 0.0]),
                                        np.array([0.02, 0.01, 0.0]))])
    K = controllers.pd(plant, natural_frequency=0.1, damping=0.7)
    U = np.outer([0.6, -0.3, 0.74], SLEW)
    loop, y_lin = linear_response(plant, K, T, U)
    ws = controllers.WheelSet.pyramid(wheel(torque_limit=1.0, momentum_limit=10.0), MAGIC)
    result = controllers.simulate_wheels(plant, K, ws, T, U)
    y = signals(result.response, loop.output_labels)
    assert np.all(peak_relative(y, y_lin) <= 1e-11), peak_relative(y, y_lin)
    assert not result.saturated


def test_wheel_momentum_is_minus_the_impulse_on_the_hub():
    # digital loop: the torque is held, so the absolute momentum J_s (Omega + omega) is
    # exactly h0 - dt sum of the torques before (round-off)
    K = controllers.pd(PLANT, natural_frequency=0.1, damping=0.7, sample_time=DT)
    Js, h0 = 0.02, 0.3
    result = controllers.simulate_wheels(PLANT, K, planar(torque_limit=None, spin_inertia=Js,
                                                          initial_momentum=h0), T, SLEW)
    h, omega, torque, speed = signals(result.response, ["wheel_momentum", "omega", "torque",
                                                        "wheel_speed"])
    impulse = np.concatenate([[0.0], np.cumsum(torque[:-1]) * DT])
    np.testing.assert_allclose(h + Js * omega, h0 - impulse, rtol=0, atol=1e-13)
    np.testing.assert_allclose(speed, h / Js, rtol=1e-15, atol=0)


# -- the loop: saturation --------------------------------------------------------------------
def full_state_reference(wl, T, U, dt):
    """An independent implementation of the method: the full state of the wheels' system S,
    each sample's mode from WheelSet.applied_torques' rules, the mode's exact discretisation
    with the loop's input and the deviation's forcing linear between samples (constants held),
    or, where the deviation is not affine (scale rule, several wheels), e held over the step."""
    ws = wl.wheels
    S = wl.system
    A, B, C, D = (np.asarray(M, dtype=float) for M in (S.A, S.B, S.C, S.D))
    n_u, nw = U.shape[0], ws.n_wheels
    labels = list(S.output_labels)
    tc = [labels.index(n) for n in labels if n.startswith("torque_command")]
    hr = [labels.index(f"{w}_momentum") for w in ws.names]
    P = ws.allocation
    Cc, Dc = P @ C[tc], P @ D[tc, :n_u]
    Ch, Dh = C[hr], D[hr, :n_u]
    Bu, Be = B[:, :n_u], B[:, n_u:]
    tau, hmax = ws.torque_limits, ws.momentum_limits
    cv = np.array([w.viscous_friction / w.spin_inertia if w.viscous_friction else 0.0
                   for w in ws.wheels])
    cc = np.array([w.coulomb_friction for w in ws.wheels])
    x = np.zeros(A.shape[0])
    x[-nw:] = [w.initial_momentum for w in ws.wheels]
    matrices = {}

    def exact(A_M, B_M, key):
        if key not in matrices:
            matrices[key] = (A_M, B_M, None) if discrete else discretise(A_M, B_M, dt, "linear")
        return matrices[key]
    Y = np.zeros((C.shape[0], T.size))
    E = np.zeros((nw, T.size))
    discrete = S.isdtime(strict=True)
    for k in range(T.size):
        c, h = Cc @ x + Dc @ U[:, k], Ch @ x + Dh @ U[:, k]
        w, ts, ms = ws.applied_torques(c, h)
        E[:, k] = w - c
        Y[:, k] = C @ x + D @ np.concatenate([U[:, k], E[:, k]])
        if k == T.size - 1:
            break
        affine = not (ws.saturation == "scale" and nw > 1 and ts.any())
        if not affine:                                   # e held over the step
            Ad, G0, G1 = exact(A, B, "held")
            if discrete:
                x = Ad @ x + G0 @ np.concatenate([U[:, k], E[:, k]])
            else:
                x = Ad @ x + G0 @ np.concatenate([U[:, k], E[:, k]]) + G1 @ np.concatenate(
                    [U[:, k + 1], E[:, k]])
            continue
        a = (ms | ts).astype(float)
        b = np.where(ms, 0.0, np.sign(c) * ts)
        # e = -a c + b tau + cc sign(h) + cv h, with c, h affine in x and u
        K = -a[:, None] * Cc + cv[:, None] * Ch
        Ku = -a[:, None] * Dc + cv[:, None] * Dh
        g = np.where(b != 0, b * tau, 0.0) + cc * np.sign(h)
        Ad, G0, G1 = exact(A + Be @ K, np.hstack([Bu + Be @ Ku, Be]), tuple(a))
        if discrete:
            x = Ad @ x + G0 @ np.concatenate([U[:, k], g])
        else:
            x = Ad @ x + G0 @ np.concatenate([U[:, k], g]) + G1 @ np.concatenate(
                [U[:, k + 1], g])
    return Y, E, labels


@pytest.mark.parametrize("limits", [
    dict(torque_limit=0.03),
    dict(torque_limit=0.02, momentum_limit=0.5, coulomb_friction=3e-3),
    dict(torque_limit=0.03, momentum_limit=0.8, viscous_friction=1e-3, coulomb_friction=2e-3,
         initial_momentum=0.2),
])
@pytest.mark.parametrize("digital", [False, True])
def test_saturated_loop_matches_an_independent_implementation(limits, digital):
    # The same method computed two ways (segments by a doubling scan on the deviation's
    # response vs the full state stepped sample by sample with each mode's matrices): equal to
    # round-off, ~1e-13 of the peaks over 2000 samples; 1e-9 allows for the scan's powers.
    K = controllers.pd(PLANT, natural_frequency=0.1, damping=0.7,
                       sample_time=DT if digital else None)
    wl = controllers.WheelLoop(PLANT, K, planar(**limits))
    result = wl.simulate(T, SLEW)
    assert result.saturated
    Y, E, labels = full_state_reference(wl, T, SLEW[None, :], DT)
    y = signals(result.response, labels)
    assert np.all(peak_relative(y, Y) <= 1e-9), peak_relative(y, Y)
    e = signals(result.response, ["wheel_torque"])[0] - signals(result.response,
                                                                ["wheel_torque_command"])[0]
    assert np.max(np.abs(e - E[0])) <= 1e-9 * np.max(np.abs(E[0]))


def test_a_large_loop_matches_the_independent_implementation():
    # 39 states: the linear loop runs through controllers.Simulator, the segments from the first
    # sample where a wheel leaves it (the small loops above run by segments throughout)
    modes = [(1.0 + 0.7 * i, 0.01, 0.02 / (1 + i), 0.02 / (1 + i)) for i in range(18)]
    plant = modal_plant(J, modes, tips=[("wing_tip_deflection", [0.5 / (1 + i)
                                                                 for i in range(18)])],
                        disturbance=False)
    K = controllers.pd(plant, natural_frequency=0.1, damping=0.7)
    wl = controllers.WheelLoop(plant, K, planar(torque_limit=0.02, momentum_limit=0.5,
                                                coulomb_friction=3e-3))
    assert wl.system.nstates > 32
    result = wl.simulate(T, SLEW)
    assert result.saturated
    Y, _, labels = full_state_reference(wl, T, SLEW[None, :], DT)
    y = signals(result.response, labels)
    assert np.all(peak_relative(y, Y) <= 1e-9), peak_relative(y, Y)


def test_applied_torque_stays_within_the_limit_and_the_times_add_up():
    result = controllers.simulate_wheels(PLANT, PD, planar(torque_limit=0.03), T, SLEW)
    torque, command, flag = signals(result.response, ["torque", "torque_command",
                                                      "wheel_torque_saturated"])
    assert np.max(np.abs(torque)) == pytest.approx(0.03, rel=1e-12)
    over = np.abs(command) > 0.03
    np.testing.assert_array_equal(flag, over.astype(float))
    assert result.time_torque_saturated["wheel"] == pytest.approx(
        DT * np.count_nonzero(over[:-1]), rel=1e-15)
    assert result.time_saturated == result.time_torque_saturated["wheel"]
    assert result.first_saturation == pytest.approx(T[np.argmax(over)], rel=1e-15)
    assert result.peak_torque["wheel"] == pytest.approx(0.03, rel=1e-12)
    # the saturated slew overshoots more than the linear one (the 10 deg slew needs 0.054 N m)
    linear = controllers.metrics(controllers.simulate(controllers.close_loop(PLANT, PD), T,
                                                      SLEW))
    assert controllers.metrics(result.response)["overshoot"] > 1.5 * linear["overshoot"]


def test_momentum_limit_holds_within_one_sample_of_motor_torque():
    limit, tau = 0.8, 0.05
    result = controllers.simulate_wheels(PLANT, PD, planar(torque_limit=tau,
                                                           momentum_limit=limit), T, SLEW)
    h, held = signals(result.response, ["wheel_momentum", "wheel_momentum_saturated"])
    assert result.saturated and result.time_momentum_saturated["wheel"] > 0
    assert np.max(np.abs(h)) <= limit + DT * tau
    assert result.momentum_margin["wheel"] == pytest.approx(limit - np.max(np.abs(h)),
                                                            rel=1e-15)
    assert result.momentum_margin["wheel"] <= 0.0           # the limit was reached
    # while held, the motor gives no torque (no friction): the absolute momentum is constant
    k = np.flatnonzero(held[:-1])
    h_abs = h + 0.01 * signals(result.response, ["omega"])[0]
    np.testing.assert_allclose(h_abs[k + 1], h_abs[k], rtol=0, atol=1e-14)


def continuous_reference(wl, t_out):
    """The nonlinear loop in continuous time (the wheel logic at every instant), integrated by
    DOP853 to rtol 1e-10, for the cycloidal slew evaluated exactly."""
    ws, S = wl.wheels, wl.system
    A, B, C, D = (np.asarray(M, dtype=float) for M in (S.A, S.B, S.C, S.D))
    labels = list(S.output_labels)
    tc = labels.index("torque_command")
    hr = labels.index("wheel_momentum")

    def rhs(t, x):
        u = float(controllers.slew_profile(t, ANGLE, SLEW_TIME))
        c = ws.allocation @ (C[[tc]] @ x + D[[tc], 0] * u)
        h = C[[hr]] @ x + D[[hr], 0] * u
        e = ws.applied_torques(c, h)[0] - c
        return A @ x + B[:, 0] * u + B[:, 1:] @ e

    sol = solve_ivp(rhs, (0.0, t_out[-1]), np.zeros(S.nstates), method="DOP853", rtol=1e-10,
                    atol=1e-13, t_eval=t_out, max_step=0.5)
    assert sol.status == 0
    return C[labels.index("theta")] @ sol.y


@pytest.mark.slow
def test_torque_saturation_converges_at_second_order_to_the_continuous_loop():
    # Within a mode the evolution is exact; a torque-limit switch decided up to dt late costs an
    # impulse |tau_c'| delta^2 / 2, so the error is O(dt^2), with a constant that depends on
    # where the switches fall between samples (measured log-log slope 1.5 to 2 over this range;
    # the first-order zero-order hold of the deviation gives 1, and 100x these errors at 0.1 s).
    wl = controllers.WheelLoop(PLANT, PD, planar(torque_limit=0.03, viscous_friction=1e-3))
    t_out = np.arange(0.0, 200.0 + 1e-9, 0.4)
    theta_ref = continuous_reference(wl, t_out)
    steps = [0.4, 0.2, 0.1, 0.05, 0.025]
    errors = []
    for dt in steps:
        T_dt = np.arange(int(round(200.0 / dt)) + 1) * dt
        theta = signals(wl.simulate(T_dt, controllers.slew_profile(T_dt, ANGLE,
                                                                   SLEW_TIME)).response,
                        ["theta"])[0]
        errors.append(np.max(np.abs(theta[:: int(round(0.4 / dt))] - theta_ref)))
    slope = np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert slope >= 1.4, (slope, errors)
    # at the default step the error is a small fraction of the peak (measured 2e-6 / 0.21)
    assert errors[2] <= 1e-4 * np.max(np.abs(theta_ref)), errors


def test_momentum_limit_converges_at_first_order():
    # the momentum limit acts at the samples: one sample of motor torque too many at most,
    # an O(dt) error; successive halvings of dt shrink the differences at least linearly
    wl = controllers.WheelLoop(PLANT, PD, planar(torque_limit=0.05, momentum_limit=0.6))
    theta = {}
    for dt in (0.2, 0.1, 0.05, 0.025, 0.0125):
        T_dt = np.arange(int(round(200.0 / dt)) + 1) * dt
        y = signals(wl.simulate(T_dt, controllers.slew_profile(T_dt, ANGLE,
                                                               SLEW_TIME)).response, ["theta"])
        theta[dt] = y[0][:: int(round(0.2 / dt))]
    differences = [np.max(np.abs(theta[dt] - theta[dt / 2])) for dt in (0.2, 0.1, 0.05, 0.025)]
    slope = np.polyfit(np.log([0.2, 0.1, 0.05, 0.025]), np.log(differences), 1)[0]
    assert slope >= 0.8, (slope, differences)
    assert differences[1] <= 1e-2 * np.max(np.abs(theta[0.0125]))


@pytest.mark.slow
def test_scale_rule_keeps_the_hub_torque_direction():
    inertia = np.diag([300.0, 200.0, 150.0])
    plant = three_axis_plant(inertia)
    K = controllers.pd(plant, natural_frequency=0.1, damping=0.7)
    U = np.outer([0.6, -0.3, 0.74], SLEW)
    for saturation in ("scale", "clip"):
        ws = controllers.WheelSet.pyramid(wheel(torque_limit=0.01), MAGIC, saturation=saturation)
        wl = controllers.WheelLoop(plant, K, ws)
        result = wl.simulate(T, U)
        assert result.saturated
        tau = signals(result.response, ["torque_x", "torque_y", "torque_z"])
        cmd = signals(result.response, ["torque_command_x", "torque_command_y",
                                        "torque_command_z"])
        sat = np.any(signals(result.response, [f"{w}_torque_saturated" for w in ws.names]),
                     axis=0)
        cross = np.linalg.norm(np.cross(tau[:, sat].T, cmd[:, sat].T), axis=1)
        scale = np.linalg.norm(tau[:, sat], axis=0) * np.linalg.norm(cmd[:, sat], axis=0)
        if saturation == "scale":
            assert np.all(cross <= 1e-12 * scale)
            assert np.all(np.einsum("ik,ik->k", tau[:, sat], cmd[:, sat]) > 0)
        else:
            assert np.max(cross / scale) > 1e-3
        assert np.max(np.abs(signals(result.response, [f"{w}_torque" for w in ws.names]))) \
            <= 0.01 * (1 + 1e-12)
        Y, _, labels = full_state_reference(wl, T, U, DT)
        assert np.all(peak_relative(signals(result.response, labels), Y) <= 1e-9)


# -- bad input -------------------------------------------------------------------------------
def test_wheels_of_the_other_convention_are_refused():
    inertia = np.diag([300.0, 200.0, 150.0])
    plant = three_axis_plant(inertia)
    K = controllers.pd(plant, natural_frequency=0.1, damping=0.7)
    with pytest.raises(ValueError, match="wheels must match a three-axis plant; got a planar"):
        controllers.WheelLoop(plant, K, planar())
    with pytest.raises(ValueError, match="wheels must match a planar plant"):
        controllers.WheelLoop(PLANT, PD, controllers.WheelSet.pyramid(wheel(), MAGIC))
    with pytest.raises(TypeError, match="wheels must be a controllers.WheelSet"):
        controllers.WheelLoop(PLANT, PD, wheel())


def test_a_plant_that_feeds_torque_to_its_rate_is_refused():
    plant = control.ss(PLANT.A, PLANT.B, PLANT.C, [[0.0], [1e-3], [0.0]],
                       inputs=["torque"], outputs=list(PLANT.output_labels))
    with pytest.raises(ValueError, match="plant must not feed the torque through"):
        controllers.WheelLoop(plant, PD, planar())


@pytest.mark.parametrize("T_, U, X0, kwargs, match", [
    (T, SLEW[:-1], None, {}, r"U must have shape \(n_inputs, n_samples\) = \(1, 2001\)"),
    (T, np.full(T.size, math.nan), None, {}, "U must be finite"),
    (T[:1], None, None, {}, "T must be 1-D with at least 2 samples"),
    (np.r_[T[:10], T[11:]], SLEW[:-1], None, {}, "T must be evenly spaced"),
    (T, SLEW, np.ones(3), {}, "X0 must be"),
    (T, SLEW, None, dict(max_samples=100), "more than max_samples = 100"),
])
def test_bad_simulation_arguments_are_refused(T_, U, X0, kwargs, match):
    wl = controllers.WheelLoop(PLANT, PD, planar())
    with pytest.raises(ValueError, match=match):
        wl.simulate(T_, U, X0, **kwargs)


def test_a_digital_loop_needs_its_own_step():
    K = controllers.pd(PLANT, natural_frequency=0.1, damping=0.7, sample_time=DT)
    wl = controllers.WheelLoop(PLANT, K, planar())
    with pytest.raises(ValueError, match="T must have the simulator's step"):
        wl.simulate(T / 2, SLEW)


def test_summary_is_json_ready():
    import json
    result = controllers.simulate_wheels(PLANT, PD, planar(torque_limit=0.03), T, SLEW)
    summary = result.summary()
    json.dumps(summary, allow_nan=False)
    assert summary["momentum_margin"] == {"wheel": None}     # unlimited: no margin to give
    assert summary["saturated"] is True
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        controllers.metrics(result.response)
