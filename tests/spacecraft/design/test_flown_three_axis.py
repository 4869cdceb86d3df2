"""The three-axis manoeuvre as flown through the design loop (spacecraft/design/manoeuvre.py):
the eigen-axis profile and its feedforward, a wheel pyramid, the loop delay in every verdict
(loop at a time, disk margins, the exact beam) and the pointing per axis, each against the
library's own answer, a closed form or a property that holds exactly."""
import copy
import math

import numpy as np
import pytest

import controllers
import spacecraft
from spacecraft.design.responses import trace
from spacecraft.scene.read import SceneError, load_scene

from scenes import THREE_AXIS_BOOM, rod_scene

AXES = "xyz"
# the 820 kg hub with its full inertia tensor and the CFRP boom off every principal axis; a
# 10 deg eigen-axis slew about (1, 1, 0.5) in 60 s, bang-coast-bang with feedforward
BASE = copy.deepcopy(THREE_AXIS_BOOM)
BASE["manoeuvre"].update(duration=90.0, step=0.1, profile="bang-coast-bang", feedforward=True,
                         torque_limit=0.5, rate_limit=0.5)
BASE["appendages"][0]["beam"]["damping_ratio"] = 0.005   # damped: finite delay margins
BASE["outputs"] = {"tip_deflection": True}
BASE["fidelity"] = {"n_modes": 2}
BASE["report"] = {"plots": False}
BASE["export"] = {"fmu": False}
PYRAMID = {"torque_limit": 0.2, "momentum_limit": 10.0, "spin_inertia": 0.05,
           "pyramid": {"azimuth": 45.0}}
SENSORS = {"attitude_density": [1e-5, 2e-5, 1e-5], "angle_random_walk": 1.5e-6,
           "rpe_window": 10.0}


def scene(**changes):
    data = copy.deepcopy(BASE)
    for path, value in changes.items():
        *head, last = path.split(".")
        table = data
        for part in head:
            table = table.setdefault(part, {})
        if value is None:
            table.pop(last, None)
        else:
            table[last] = copy.deepcopy(value)
    return data


def unit(axis):
    e = np.asarray(axis, dtype=float)
    return e / np.linalg.norm(e)


@pytest.fixture(scope="module")
def ideal():
    """The feedforward bang-coast-bang slew without delay, wheels or noise."""
    return spacecraft.run(scene())


def test_the_feedforward_is_j_alpha_by_hand_and_the_gyroscopic_term_is_reported(ideal):
    # duration T = 60 s, theta = 10 deg: the rate limit (0.5 deg/s) does not bind
    # (t_a = min(T/2, T - theta/w_max) = 30 s), so s'' = a on [0, 30), -a on (30, 60] with
    # a = theta / (t_a (T - t_a)) (Wie 2008, sec. 7.3); s' = a t, then a (T - t)
    m = ideal.scene.manoeuvre
    theta, T = math.radians(10.0), 60.0
    ta = min(T / 2, T - theta / m.rate_limit)
    assert ta == 30.0
    a = theta / (ta * (T - ta))
    e = unit([1.0, 1.0, 0.5])
    facts = ideal.data["manoeuvre"]["profiles"]["poles-and-zeros"]
    J = np.asarray(facts["inertia"])
    assert facts["axis"] == pytest.approx(e.tolist(), rel=1e-15)
    assert facts["peak_acceleration"] == pytest.approx(a, rel=1e-12)
    assert facts["peak_rate"] == pytest.approx(a * ta, rel=1e-12)
    # the torque limit bounds each hub-axis component of J e s''
    assert facts["peak_torque"] == pytest.approx(np.max(np.abs(J @ e)) * a, rel=1e-12)
    assert facts["peak_torque"] <= m.torque_limit
    # the gyroscopic torque (e x J e) s'^2 is reported apart: at the peak rate
    gyro = np.cross(e, J @ e)
    assert facts["gyroscopic_peak_torque"] == pytest.approx(np.max(np.abs(gyro))
                                                            * (a * ta) ** 2, rel=1e-12)
    # the profile's whole feedforward is Euler's J alpha + omega x J omega, by hand
    profile = controllers.reference_profile("bang-coast-bang", theta, T, inertia=J,
                                            torque_limit=m.torque_limit,
                                            rate_limit=m.rate_limit, axis=e)
    t = np.array([5.0, 17.5, 29.0, 31.0, 44.0, 59.5])
    rate = np.where(t < ta, a * t, a * (T - t))
    alpha = np.where(t < ta, a, -a)
    omega = np.outer(e, rate)
    by_hand = (J @ np.outer(e, alpha)
               + np.cross(omega.T, (J @ omega).T).T)
    assert profile.torque_ff(t, J) == pytest.approx(by_hand, rel=1e-12, abs=1e-15)
    # the loop reads the part its linear plant has, J e s'', at the samples
    for kind in ("pd",):
        response = ideal.responses[("poles-and-zeros", kind, "truth")]
        ts = np.asarray(response.t).reshape(-1)
        inside = (np.abs(ts - ta) > 1e-6) & (ts < T - 1e-6)
        fed = np.array([trace(response, f"torque_ff_{x}", "input") for x in AXES])
        expected = np.outer(J @ e, np.where(ts < ta, a, -a))
        assert fed[:, inside] == pytest.approx(expected[:, inside], rel=1e-12, abs=1e-15)
        assert np.all(fed[:, ts > T + 1e-6] == 0.0)
        omega_ref = np.array([trace(response, f"omega_ref_{x}", "input") for x in AXES])
        s1 = np.where(ts < ta, a * ts, np.clip(a * (T - ts), 0.0, None))
        assert omega_ref == pytest.approx(np.outer(e, s1), rel=1e-12, abs=1e-15)


def test_the_flown_slew_is_the_librarys_profile_response(ideal):
    m = ideal.scene.manoeuvre
    design = ideal.designs["poles-and-zeros"]["plant"]
    J = controllers.rigid_body_inertia(design)
    profile = controllers.reference_profile("bang-coast-bang", m.slew_angle, m.slew_time,
                                            inertia=J, torque_limit=m.torque_limit,
                                            rate_limit=m.rate_limit, axis=m.slew_axis)
    K = ideal.designs["poles-and-zeros"]["controllers"]["pd"]
    assert {f"{s}_{x}" for s in ("theta_ref", "omega_ref", "torque_ff") for x in AXES} <= set(
        K.input_labels)
    loop = controllers.close_loop(ideal.truth["sim"], K)
    expected = controllers.profile_response(loop, profile, inertia=J, t_final=m.duration,
                                            dt=m.step)
    got = ideal.responses[("poles-and-zeros", "pd", "truth")]
    for name in [f"theta_{x}" for x in AXES] + [f"torque_{x}" for x in AXES]:
        a, b = trace(got, name), trace(expected, name)
        assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(b)), name
    # feedforward on the rigid body: the attitude error during the slew is a fraction of the
    # slew (the flexible boom and the loop's own lag only)
    metrics = ideal.data["closed_loops"][0]["manoeuvre_metrics"]["truth"]
    assert metrics["peak_attitude_error_during"] < 0.02 * m.slew_angle


def test_a_wheel_pyramid_that_never_saturates_gives_the_linear_flight(ideal):
    # limits far beyond the slew's, no friction: the wheels pass the command through, and the
    # flight is the linear loop's to round-off (the wheel loop integrates the same linear
    # loop between switching instants, of which there are none)
    free = spacecraft.run(scene(wheels={"torque_limit": 100.0, "momentum_limit": 1e4,
                                        "spin_inertia": 0.05, "pyramid": {}}))
    for key, response in ideal.responses.items():
        wheeled = free.responses[key]
        for name in [f"theta_{x}" for x in AXES] + [f"torque_{x}" for x in AXES] + [
                "boom_tip_deflection_y"]:
            a, b = trace(wheeled, name), trace(response, name)
            if b is None:
                continue
            assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(b)), (key, name)
    for row in free.data["closed_loops"]:
        summary = row["wheels"]["truth"]
        assert not summary["saturated"] and summary["time_saturated"] == 0.0
        assert set(summary["peak_torque"]) == {f"wheel_{k}" for k in range(1, 5)}
        assert summary["words"].startswith("no wheel reached a limit; momentum margin")
    assert not any(w["code"] == "wheel_saturation" for w in free.data["design_warnings"])


def test_a_saturating_pyramid_is_said_in_words_and_warned_about():
    # the step reference (the cycloid, no feedforward): wheels of 0.12 N m allow the slew in
    # 59.4 s of its 60 s (bang-bang at the pyramid's capacity along J e), the cycloid's PD
    # loop asks for more (0.1 N m wheels: 65 s, refused)
    wheels = {**PYRAMID, "torque_limit": 0.12}
    probe = load_scene(scene(wheels=wheels, **{"manoeuvre.profile": None,
                                               "manoeuvre.feedforward": None,
                                               "manoeuvre.torque_limit": None,
                                               "manoeuvre.rate_limit": None}))
    result = spacecraft.run(probe)
    J = result.data["manoeuvre"]["profiles"]["poles-and-zeros"]["inertia"]
    shortest = controllers.shortest_slew_time(probe.wheels.build(), probe.manoeuvre.slew_angle,
                                              J, axis=unit(probe.manoeuvre.slew_axis))
    assert shortest < 60.0
    row = result.data["closed_loops"][0]
    summary = row["wheels"]["truth"]
    assert summary["saturated"], summary["words"]
    assert "the wheels SATURATED from t = " in summary["words"]
    response = result.responses[("poles-and-zeros", "pd", "truth")]
    for k in range(1, 5):
        assert np.max(np.abs(trace(response, f"wheel_{k}_torque"))) <= 0.12 * (1 + 1e-12)
    assert "wheel_saturation" in [w["code"] for w in result.data["design_warnings"]]


@pytest.fixture(scope="module")
def delayed_pair():
    """The step reference without and with a loop delay of 0.1 s, judged on the design and
    truth models and the exact beam."""
    base = {"manoeuvre.profile": None, "manoeuvre.feedforward": None,
            "manoeuvre.torque_limit": None, "manoeuvre.rate_limit": None,
            "outputs.exact_reference": True, "manoeuvre.duration": 60.0}
    without = spacecraft.run(scene(**base), time_responses=False)
    with_delay = spacecraft.run(scene(**base, **{"controller.delay": 0.1}),
                                time_responses=False)
    return without, with_delay


@pytest.mark.slow
@pytest.mark.parametrize("verdict", ["design_margins", "verdict", "exact_verdict"])
def test_a_delay_takes_omega_c_tau_off_each_axis_phase_margin(delayed_pair, verdict):
    # e^(-j omega tau) I on the loop broken at the plant input: each loop at a time keeps |L|
    # and so its gain crossover, and turns the phase there by omega_c tau; the delay margin
    # (min over the loops and their crossovers of PM / omega_c) falls by tau exactly
    without, with_delay = (r.data["closed_loops"][0] for r in delayed_pair)
    a, b = without[verdict], with_delay[verdict]
    assert with_delay["verdict"]["stable"] and without["verdict"]["stable"]
    assert a["delay"] == 0.0 and b["delay"] == 0.1
    assert b["delay_margin"] == pytest.approx(a["delay_margin"] - 0.1, rel=1e-7)
    checked = 0
    for x in AXES:
        wc = a[f"gain_crossover_frequency_{x}"]
        if b[f"gain_crossover_frequency_{x}"] != pytest.approx(wc, rel=1e-9):
            continue
        assert b[f"phase_margin_{x}"] == pytest.approx(
            a[f"phase_margin_{x}"] - math.degrees(wc * 0.1), abs=1e-7), x
        checked += 1
    assert checked >= 1
    # the disk margin takes the delay too (it can only shrink with a pure phase lag at the
    # crossovers of a loop this slow: 0.1 s is 0.6 deg at 0.1 rad/s)
    assert b["disk_margin"] < a["disk_margin"]


@pytest.mark.slow
def test_a_delay_beyond_the_margin_is_a_result():
    # the small rod scene (tests/support/scenes.py: the 10 m rod, damped, on the three-axis
    # hub), a PD of 1 rad/s: a delay margin of a tenth of a second (the margins resolve the
    # delay's phase up to the loop's highest frequency, 2e6 rad/s here, on at most 2e6
    # frequencies)
    rod = rod_scene(three_axis=True, **{
        "appendages.0.beam.damping_ratio": 0.005, "manoeuvre.slew_axis": [1.0, 1.0, 0.5],
        "manoeuvre.step": 0.02, "controller.pd.natural_frequency": 1.0, "controller.delay": 0.01})
    probe = spacecraft.run(rod, time_responses=False)
    margin = probe.data["closed_loops"][0]["verdict"]["delay_margin"] + 0.01
    rod["controller"]["delay"] = 1.2 * margin
    rod["sensors"] = SENSORS
    result = spacecraft.run(rod)
    row = result.data["closed_loops"][0]
    assert not row["verdict"]["stable"] and row["undelayed_stable"]
    assert row["verdict"]["delay_margin"] <= 0.0
    assert row["status"]["truth"]["status"] in ("unstable", "diverges")
    assert row["manoeuvre_metrics"]["truth"]["residual_attitude_error"] is None
    assert "error" in row["pointing"]["truth"]
    codes = [w["code"] for w in result.data["design_warnings"]]
    assert "delay_destabilises" in codes


@pytest.mark.slow
def test_pointing_per_axis_is_the_librarys():
    result = spacecraft.run(scene(sensors=SENSORS, **{"controller.delay": 0.1}))
    s = result.scene.sensors
    row = result.data["closed_loops"][0]
    K = result.designs["poles-and-zeros"]["controllers"]["pd"]
    budget = controllers.pointing(result.truth["sim"], K, s.noise(), window=s.rpe_window,
                                  delay=0.1)
    figures = row["pointing"]["truth"]
    assert set(figures["ape"]) == {f"theta_{x}" for x in AXES}
    for name in ("ape", "mpe", "rpe", "jitter", "jitter_rpe"):
        assert figures[name] == pytest.approx(getattr(budget, name), rel=1e-12)
    # the noisier attitude sensor about y gives the larger pointing error there
    assert figures["ape"]["theta_y"] > figures["ape"]["theta_x"]


@pytest.mark.parametrize("changes, match", [
    ({"manoeuvre.torque_limit": 0.05},
     r"manoeuvre\.slew_time: 60 s is too short for a bang-coast-bang slew of 10 deg under "
     r"manoeuvre\.torque_limit = 0\.05 N m and manoeuvre\.rate_limit = 0\.5 deg/s \(the "
     r"spacecraft's inertia [0-9.]+ kg m\^2 about the slew axis\): the shortest time they "
     r"allow is (?P<t>[0-9.]+) s"),
    ({"wheels": {**PYRAMID, "torque_limit": 0.01}},
     r"manoeuvre\.slew_time: 60 s is too short for the wheels: .* about the slew axis\) in no "
     r"less than (?P<t>[0-9.]+) s"),
])
def test_limits_that_cannot_fly_the_slew_are_refused_with_the_shortest_time(changes, match):
    with pytest.raises(SceneError, match=match) as info:
        spacecraft.run(scene(**changes))
    import re

    found = re.search(match, str(info.value))
    sc = load_scene(scene(**changes))
    from spacecraft.design.loop import DesignLoop

    J = DesignLoop(sc).rigid_inertia()
    e = unit(sc.manoeuvre.slew_axis)
    if "wheels" in changes:
        shortest = controllers.shortest_slew_time(sc.wheels.build(), sc.manoeuvre.slew_angle,
                                                  J, axis=e)
    else:
        shortest = controllers.minimum_time("bang-coast-bang", sc.manoeuvre.slew_angle,
                                            inertia=J, torque_limit=0.05,
                                            rate_limit=sc.manoeuvre.rate_limit, axis=e)
    assert float(found["t"]) == pytest.approx(shortest, rel=1e-5)


def test_three_axis_noise_with_a_wrong_sign_is_refused_by_key():
    with pytest.raises(SceneError, match=r"sensors\.attitude_density\[1\]: must be "
                                         r"non-negative \[rad/sqrt\(Hz\)\]"):
        load_scene(scene(sensors={**SENSORS, "attitude_density": [1e-5, -1e-5, 1e-5]}))


@pytest.mark.slow
def test_the_embedded_three_axis_flown_scene_flies_its_slew():
    """three_axis_flown: the three_axis spacecraft, its slew shaped and fed forward through a
    four-wheel pyramid, with a 0.1 s delay and sensor noise."""
    result = spacecraft.run("three_axis_flown")
    scene_ = result.scene
    plain = load_scene("three_axis")
    assert (scene_.hub, scene_.appendages, scene_.fidelity) == (
        plain.hub, plain.appendages, plain.fidelity)
    assert scene_.manoeuvre.profile == "shaped" and scene_.manoeuvre.feedforward
    assert scene_.wheels.build().n_wheels == 4 and scene_.sensors is not None
    for variant, profile in result.data["manoeuvre"]["profiles"].items():
        assert profile["end_time"] == pytest.approx(60.0)
        assert profile["peak_torque"] <= 0.3 * (1 + 1e-12)
    for row in result.data["closed_loops"]:
        assert row["verdict"]["delay"] == 0.1
        assert {"design", "truth"} == set(row["wheels"]) == set(row["pointing"])
        assert row["verdict"]["stable"], row["controller"]
        assert row["verdict"]["delay_margin"] > 0
        assert row["exact_verdict"]["delay_margin"] == pytest.approx(
            row["verdict"]["delay_margin"], rel=1e-3)
        p = row["pointing"]["truth"]
        for x in AXES:
            assert 0 < p["rpe"][f"theta_{x}"] < p["ape"][f"theta_{x}"]
