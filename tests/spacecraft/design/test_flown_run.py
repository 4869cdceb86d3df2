"""A scene's manoeuvre as flown through the design loop (spacecraft/design/manoeuvre.py): the
profile and its feedforward, the loop delay in every verdict, the wheels, the metrics from the
end of the profile and the pointing figures, each against the library's own answer or a
property that holds exactly."""
import math

import numpy as np
import pytest

import controllers
import spacecraft
from spacecraft.design.responses import trace
from spacecraft.scene.read import SceneError, load_scene

from scenes import flown_damped, scene_with

def rows(result):
    return {row["controller"]: row for row in result.data["closed_loops"]}


@pytest.fixture(scope="module")
def ideal():
    """The shaped feedforward slew without delay or wheels."""
    return spacecraft.run(flown_damped(**{"controller.delay": None, "wheels": None,
                                                 "sensors": None}))


def test_the_flown_slew_is_the_librarys_profile_response(ideal):
    # the runner's glue (profile per design model, its shaper, the references by name, the
    # feedforward torque's inertia, the grid) against controllers.profile_response on the same
    # loop: the same simulation, to round-off
    result = ideal
    m = result.scene.manoeuvre
    variant = "poles-and-zeros"
    design = result.designs[variant]["plant"]
    J = controllers.rigid_body_inertia(design)
    shaper = controllers.mode_shaper(controllers.flexible_modes(design)[:1], kind="zvd")
    profile = controllers.reference_profile("shaped", m.slew_angle, m.slew_time, inertia=J,
                                            torque_limit=m.torque_limit,
                                            rate_limit=m.rate_limit, shaper=shaper)
    for kind in ("pd", "lqr"):
        K = result.designs[variant]["controllers"][kind]
        assert {"theta_ref", "omega_ref", "torque_ff"} <= set(K.input_labels)
        loop = controllers.close_loop(result.truth["sim"], K)
        expected = controllers.profile_response(loop, profile, inertia=J, t_final=m.duration,
                                                dt=m.step)
        got = result.responses[(variant, kind, "truth")]
        for name in ("theta", "torque", "rod_tip_deflection"):
            a, b = trace(got, name), trace(expected, name)
            assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(b)), (kind, name)
    facts = result.data["manoeuvre"]["profiles"][variant]
    assert facts["end_time"] == pytest.approx(m.slew_time, rel=1e-12)
    assert facts["shaper"]["duration"] == pytest.approx(shaper.duration, rel=1e-15)
    # the profile keeps its limits (exact peaks)
    assert facts["peak_torque"] <= m.torque_limit * (1 + 1e-12)
    assert facts["peak_rate"] <= m.rate_limit * (1 + 1e-12)


def test_metrics_from_the_end_of_the_profile(ideal):
    for row in ideal.data["closed_loops"]:
        for which in ("design", "truth"):
            today, flown_ = row["metrics"][which], row["manoeuvre_metrics"][which]
            assert flown_["profile_end"] == 60.0
            # during + after cover the response: the larger is today's peak (from t = 0)
            assert max(flown_["peak_attitude_error_during"],
                       flown_["residual_attitude_error"]) == today["peak_attitude_error"]
            assert flown_["peak_torque_during"] <= today["peak_torque"]
            settled = today["settling_time"]
            assert flown_["settling_time_after_end"] == pytest.approx(
                max(settled - 60.0, 0.0), abs=1e-9)


def test_todays_step_slew_gets_the_metrics_from_its_end_too():
    result = spacecraft.run(scene_with())
    row = result.data["closed_loops"][0]
    today, after = row["metrics"]["truth"], row["manoeuvre_metrics"]["truth"]
    assert after["profile_end"] == 60.0
    assert after["settling_time_after_end"] == pytest.approx(today["settling_time"] - 60.0,
                                                             abs=1e-9)


def test_wheels_that_never_saturate_give_the_linear_flight(ideal):
    free = spacecraft.run(flown_damped(**{"controller.delay": None, "sensors": None,
                                          "wheels": {"torque_limit": 100.0, "momentum_limit": 1e4,
                                                     "spin_inertia": 0.05}}))
    for key, response in ideal.responses.items():
        wheeled = free.responses[key]
        for name in ("theta", "torque", "rod_tip_deflection"):
            a, b = trace(wheeled, name), trace(response, name)
            assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(b)), (key, name)
    for row in free.data["closed_loops"]:
        summary = row["wheels"]["truth"]
        assert not summary["saturated"] and summary["time_saturated"] == 0.0
        assert summary["words"].startswith("no wheel reached a limit; momentum margin")
        # the wheel stores what the spacecraft turned with: its peak momentum is at least the
        # rigid body's J x peak rate of the profile
        J = row_inertia = free.data["manoeuvre"]["profiles"][row["design"]]["inertia"]
        peak = free.data["manoeuvre"]["profiles"][row["design"]]["peak_rate"]
        assert summary["peak_momentum"]["wheel"] >= 0.99 * J * peak, row_inertia
    assert not any(w["code"] == "wheel_saturation" for w in free.data["design_warnings"])


def test_a_saturating_wheel_is_said_in_words_and_warned_about():
    # the profile needs 0.062 N m, feedback adds to it during the slew (0.076 N m): a wheel of
    # 0.07 N m can fly the slew (its shortest time 34 s) but saturates on the way
    result = spacecraft.run(flown_damped(**{"controller.delay": None, "sensors": None,
                                            "wheels": {"torque_limit": 0.07,
                                                       "momentum_limit": 4.0}}))
    saturated = [row for row in result.data["closed_loops"] if row["wheels"]["truth"]["saturated"]]
    assert saturated
    for row in saturated:
        summary = row["wheels"]["truth"]
        assert summary["time_torque_saturated"]["wheel"] > 0.0
        assert "the wheels SATURATED from t = " in summary["words"]
        assert "torque limit for" in summary["words"]
        response = result.responses[(row["design"], row["controller"], "truth")]
        # the hub receives at most the limit; the controller asked for more
        assert np.max(np.abs(trace(response, "torque"))) <= 0.07 * (1 + 1e-12)
        assert np.max(np.abs(trace(response, "torque_command"))) > 0.07
    codes = [w["code"] for w in result.data["design_warnings"]]
    assert "wheel_saturation" in codes


@pytest.fixture(scope="module")
def delayed_pair():
    """The same loops without and with a delay of 0.1 s (the step reference: the delay alone),
    judged also on the exact beam."""
    base = {"manoeuvre.profile": None, "manoeuvre.feedforward": None,
            "manoeuvre.torque_limit": None, "manoeuvre.rate_limit": None, "wheels": None,
            "sensors": None, "outputs": {"tip_deflection": True, "exact_reference": True}}
    without = spacecraft.run(flown_damped(**{**base, "controller.delay": None}))
    with_delay = spacecraft.run(flown_damped(**{**base, "controller.delay": 0.1}))
    return without, with_delay


@pytest.mark.parametrize("verdict", ["design_margins", "verdict", "exact_verdict"])
def test_a_delay_takes_omega_c_tau_off_the_phase_margin_everywhere(delayed_pair, verdict):
    # e^(-j omega tau) leaves |L| and so every gain crossover where it is, and turns the phase
    # there by omega_c tau: PM(tau) = PM(0) - omega_c tau [deg] at the same crossover, and the
    # delay margin (min over crossovers of PM / omega_c) falls by tau exactly
    without, with_delay = (rows(r) for r in delayed_pair)
    checked = 0
    for kind in ("pd", "lqr"):
        a, b = without[kind][verdict], with_delay[kind][verdict]
        if not with_delay[kind]["verdict"]["stable"] or not without[kind]["verdict"]["stable"]:
            continue
        assert a["delay"] == 0.0 and b["delay"] == 0.1
        assert b["delay_margin"] == pytest.approx(a["delay_margin"] - 0.1, rel=1e-7)
        if b["gain_crossover_frequency"] == pytest.approx(a["gain_crossover_frequency"],
                                                          rel=1e-9):
            wc = a["gain_crossover_frequency"]
            assert b["phase_margin"] == pytest.approx(
                a["phase_margin"] - math.degrees(wc * 0.1), abs=1e-7)
        checked += 1
    assert checked >= 1


def test_the_delay_is_in_the_flown_loops_and_their_poles(delayed_pair):
    without, with_delay = delayed_pair
    for key, loop in with_delay.loops.items():
        # the continuous controller's delayed loop, held every step: discrete, with the delay
        # line (0.1 s / 0.1 s step: one command held, one delayed)
        assert loop.isdtime(strict=True) and loop.dt == pytest.approx(0.1)
        assert loop.nstates > without.loops[key].nstates


def test_a_delay_beyond_the_margin_is_a_result():
    probe = spacecraft.run(flown_damped(**{"wheels": None, "sensors": None,
                                           "controller.delay": 0.05}), time_responses=False)
    margin = rows(probe)["pd"]["verdict"]["delay_margin"] + 0.05
    result = spacecraft.run(flown_damped(**{"wheels": None, "controller.delay": 1.2 * margin,
                                            "manoeuvre.step": min(0.1, 2.4 * margin)}))
    row = rows(result)["pd"]
    assert not row["verdict"]["stable"] and row["undelayed_stable"]
    assert row["status"]["truth"]["status"] in ("unstable", "diverges")
    assert row["metrics"]["truth"]["peak_attitude_error"] is None
    assert row["metric_flags"]["truth"]["peak_attitude_error"] == "diverges"
    assert row["manoeuvre_metrics"]["truth"]["residual_attitude_error"] is None
    assert "must be asymptotically stable" in row["pointing"]["truth"]["error"]
    codes = [w["code"] for w in result.data["design_warnings"] if w.get("controller") == "pd"]
    assert "delay_destabilises" in codes and "unstable" in codes


def test_pointing_figures_are_the_librarys(ideal):
    result = spacecraft.run(flown_damped(**{"wheels": None}))
    s = result.scene.sensors
    for row in result.data["closed_loops"]:
        K = result.designs[row["design"]]["controllers"][row["controller"]]
        budget = controllers.pointing(result.truth["sim"], K, s.noise(), window=s.rpe_window,
                                      delay=0.2)
        figures = row["pointing"]["truth"]
        if not row["verdict"]["stable"]:
            assert "error" in figures
            continue
        for name in ("ape", "mpe", "rpe", "jitter", "jitter_rpe"):
            assert figures[name] == pytest.approx(getattr(budget, name), rel=1e-12)
        assert figures["at"]["factor"] == pytest.approx(3.0, rel=1e-3)   # 99.73 %: 3 sigma
        assert "ECSS-E-ST-60-10C" in figures["definitions"]
    assert result.data["stats"]["pointing_analyses"] == 2 * len(result.data["closed_loops"])


def test_a_digital_controllers_computation_delay_is_one_sample():
    result = spacecraft.run(flown_damped(**{"controller.delay": None,
                                                   "controller.sample_rate": 10.0,
                                                   "controller.computation_delay": True,
                                                   "wheels": None}))
    for row in result.data["closed_loops"]:
        assert row["verdict"]["delay"] == pytest.approx(0.1, rel=1e-12)
        assert row["design_margins"]["delay"] == pytest.approx(0.1, rel=1e-12)
        assert row["pointing"]["truth"].get("sampled", True)


@pytest.mark.parametrize("changes, match", [
    # 10 deg under 0.02 N m (the spacecraft's 275.67 kg m^2) and 0.5 deg/s: the rate limit
    # is not reached (w^2 > theta a), the shortest time is bang-bang's 2 sqrt(theta / a)
    ({"manoeuvre.torque_limit": 0.02},
     r"manoeuvre\.slew_time: 60 s is too short for a bang-coast-bang slew of 10 deg under "
     r"manoeuvre\.torque_limit = 0\.02 N m and manoeuvre\.rate_limit = 0\.5 deg/s .* the "
     r"shortest time they allow is (?P<t>[0-9.]+) s"),
    ({"wheels": {"torque_limit": 0.2, "momentum_limit": 0.5}},
     r"manoeuvre\.slew_time: 60 s is too short for the wheels: .* in no less than "
     r"(?P<t>[0-9.]+) s"),
    ({"manoeuvre.shaper": {"modes": 3}},
     r"manoeuvre\.shaper\.modes: asks for 3 modes, and the design model \(poles-and-zeros\) "
     r"has 2 flexible modes"),
])
def test_what_cannot_fly_the_slew_is_refused_by_key(changes, match):
    with pytest.raises(SceneError, match=match) as info:
        spacecraft.run(flown_damped(**changes))
    import re

    found = re.search(match, str(info.value))
    if "t" in found.groupdict():
        inertia = 275.668          # the spacecraft's, as the message gives it
        theta, w = math.radians(10.0), math.radians(0.5)
        if "wheels" in changes:
            wheels = load_scene(flown_damped(**changes)).wheels.build()
            shortest = controllers.shortest_slew_time(wheels, theta, inertia)
        else:
            a = 0.02 / inertia
            assert w * w > theta * a
            shortest = 2.0 * math.sqrt(theta / a)
        assert float(found["t"]) == pytest.approx(shortest, rel=1e-4)


def test_a_sweep_refuses_a_flown_scene_by_key():
    from spacecraft.sweep.evaluate import prepare
    from spacecraft.sweep.parameters import SweepError, read_sweep

    raw = flown_damped()
    spec = read_sweep({"parameters": {"hub.inertia": {"distribution": "uniform", "low": 40.0,
                                                      "high": 60.0}}}, raw, "test")
    with pytest.raises(SweepError, match=r"test: controller\.delay: a sweep's sample is the "
                                         r"ideal slew"):
        prepare(raw, spec, "test")


@pytest.mark.slow
def test_a_delayed_continuous_loop_converges_at_second_order_in_the_step():
    # the delayed continuous loop is simulated with the command held every step and delayed by
    # delay - step / 2 (controllers.delay); the references read at the samples (the feedforward
    # torque, which jumps between samples, as its mean over the step centred there), the
    # disturbance pulse, whose edges fall between samples, as its mean over each step: O(dt^2).
    # Halving the step from 0.1 to 0.05 s takes the difference from the 0.025 s run down by
    # (1 - 1/16) / (1/4 - 1/16) = 5 at second order (2 at first order; the references at the
    # step midpoints gave 3 and 2e-4 rad)
    theta = {}
    for step in (0.1, 0.05, 0.025):
        result = spacecraft.run(flown_damped(**{
            "wheels": None, "sensors": None, "controller.delay": 0.1, "manoeuvre.step": step,
            "manoeuvre.disturbance": {"input": "disturbance_torque", "amplitude": 0.01,
                                      "start": 70.33, "length": 10.0}}))
        every = int(round(0.1 / step))
        key = ("poles-and-zeros", "pd", "truth")
        theta[step] = [trace(responses[key], "theta")[::every]
                       for responses in (result.responses, result.disturbance_responses)]
    for k in range(2):   # the slew, the disturbance
        e1 = np.max(np.abs(theta[0.1][k] - theta[0.025][k]))
        e2 = np.max(np.abs(theta[0.05][k] - theta[0.025][k]))
        assert e1 / e2 > 4.0, (k, e1, e2)
        assert e1 < 5e-4 * np.max(np.abs(theta[0.025][k]))


@pytest.mark.slow
def test_the_embedded_default_flown_scene_flies_its_slew():
    """default_flown: the default scene's models and controllers, the slew shaped and fed
    forward, through a wheel with friction, with a 0.1 s delay and sensor noise."""
    result = spacecraft.run("default_flown")
    scene = result.scene
    assert scene.manoeuvre.profile == "shaped" and scene.manoeuvre.feedforward
    assert scene.controller.delay == 0.1 and scene.wheels is not None and scene.sensors
    default = load_scene("default")
    assert (scene.hub, scene.appendages, scene.fidelity) == (
        default.hub, default.appendages, default.fidelity)
    facts = result.data["manoeuvre"]
    for variant, profile in facts["profiles"].items():
        assert profile["kind"] == "shaped" and profile["end_time"] == pytest.approx(60.0)
        assert profile["peak_torque"] <= 0.08 * (1 + 1e-12)
    for row in result.data["closed_loops"]:
        assert row["verdict"]["delay"] == 0.1
        assert {"design", "truth"} == set(row["wheels"]) == set(row["pointing"])
        assert "words" in row["wheels"]["truth"]
        if row["verdict"]["stable"]:
            # stable with the delay: some margin left, and pointing figures
            assert row["verdict"]["delay_margin"] > 0
            assert 0 < row["pointing"]["truth"]["rpe"]["theta"] < row["pointing"]["truth"][
                "ape"]["theta"]
            assert row["exact_verdict"]["delay_margin"] == pytest.approx(
                row["verdict"]["delay_margin"], rel=1e-3)
        else:
            assert "error" in row["pointing"]["truth"]
    # flexsat's fit flies the slew stably with both controllers
    pz = {r["controller"]: r for r in result.data["closed_loops"]
          if r["design"] == "poles-and-zeros"}
    assert all(r["verdict"]["stable"] for r in pz.values())
