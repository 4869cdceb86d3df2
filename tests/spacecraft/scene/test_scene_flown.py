"""The manoeuvre as flown in a scene (spacecraft/scene/flown.py): the delay, the profile and
its feedforward, the [wheels] and [sensors] tables read into SI units, and every bad value
refused by its key (or warned about where it looks like a unit slip)."""
import copy
import math

import numpy as np
import pytest

from spacecraft.scene.flown import shaper_band
from spacecraft.scene.read import SceneError, load_scene

from scenes import BASE, THREE_AXIS_BOOM, flown


def test_the_default_keys_keep_todays_scene():
    scene = load_scene(BASE)
    m, c = scene.manoeuvre, scene.controller
    assert (m.profile, m.feedforward, m.shaper, m.flown) == ("step", False, None, False)
    assert (c.delay, c.computation_delay, c.total_delay) == (0.0, False, 0.0)
    assert scene.wheels is None and scene.sensors is None


def test_a_flown_scene_in_si_units():
    scene = load_scene(flown())
    m = scene.manoeuvre
    assert (m.profile, m.feedforward, m.flown) == ("shaped", True, True)
    assert m.torque_limit == 0.1
    # the file's deg/s and deg/s^3 are rad/s and rad/s^3 inside
    assert m.rate_limit == pytest.approx(math.radians(0.5), rel=1e-15)
    assert m.shaper.kind == "zvd" and m.shaper.modes == 1 and m.shaper.base == "bang-coast-bang"
    assert scene.controller.delay == 0.2
    w = scene.wheels
    assert (w.torque_limit, w.momentum_limit, w.spin_inertia, w.n_wheels) == (0.2, 4.0, 0.02, 1)
    wheels = w.build()
    assert wheels.planar and wheels.torque_limits.tolist() == [0.2]
    s = scene.sensors
    assert (s.attitude_density, s.angle_random_walk, s.rpe_window) == (1e-5, 1e-6, 10.0)
    assert s.placement == "random" and s.probability == 0.9973
    assert s.noise().attitude_density == 1e-5


def test_jerk_limit_in_degrees_per_second_cubed():
    scene = load_scene(flown(**{"manoeuvre.profile": "smooth", "manoeuvre.jerk_limit": 0.01}))
    assert scene.manoeuvre.jerk_limit == pytest.approx(math.radians(0.01), rel=1e-15)


def test_attitude_rms_at_a_rate_is_a_density():
    # q = sigma / sqrt(f_s): controllers.SensorNoise.from_rms
    scene = load_scene(flown(sensors={"attitude_rms": 4e-5, "attitude_rate": 4.0,
                                      "rpe_window": 10.0}))
    assert scene.sensors.attitude_density == pytest.approx(2e-5, rel=1e-15)


def test_the_default_step_of_a_delayed_continuous_loop_fits_the_delay():
    # slew_time / 500 = 0.12 s > 2 x 0.05 s: the default step becomes 0.1 s
    data = flown(**{"controller.delay": 0.05})
    del data["manoeuvre"]["step"]
    assert load_scene(data).manoeuvre.step == pytest.approx(0.1, rel=1e-15)


@pytest.mark.parametrize("kind, tolerance, band", [
    # Singer & Seering 1990: undamped ZV +-3.2 %, ZVD +-14.4 % at 5 % residual vibration
    ("zv", 0.05, 0.0318), ("zvd", 0.05, 0.1436)])
def test_shaper_bands_against_the_closed_form(kind, tolerance, band):
    assert shaper_band(kind, tolerance) == pytest.approx(band, abs=5e-5)


def test_the_shortest_shaper_that_holds_the_frequency_error_is_chosen():
    zv = load_scene(flown(**{"manoeuvre.shaper": {"frequency_error": 0.02}}))
    zvd = load_scene(flown(**{"manoeuvre.shaper": {"frequency_error": 0.1}}))
    assert (zv.manoeuvre.shaper.kind, zvd.manoeuvre.shaper.kind) == ("zv", "zvd")


def test_a_three_axis_scene_reads_per_wheel_limits_pyramid_and_per_axis_noise():
    data = copy.deepcopy(THREE_AXIS_BOOM)
    data["wheels"] = {"torque_limit": [0.1, 0.1, 0.2, 0.2], "momentum_limit": 4.0,
                      "pyramid": {"cant_angle": 54.7356}}
    data["sensors"] = {"attitude_density": [1e-5, 1e-5, 3e-5], "rpe_window": 10.0}
    scene = load_scene(data)
    w = scene.wheels
    assert (w.torque_limit, w.momentum_limit, w.n_wheels) == ((0.1, 0.1, 0.2, 0.2), 4.0, 4)
    wheels = w.build()
    assert wheels.torque_limits.tolist() == [0.1, 0.1, 0.2, 0.2]
    # the pyramid's spin axes: unit vectors at the cant angle from +z
    assert np.linalg.norm(wheels.spin_axes, axis=1) == pytest.approx(np.ones(4), rel=1e-12)
    assert wheels.spin_axes[:, 2] == pytest.approx(
        np.full(4, math.cos(math.radians(54.7356))), rel=1e-12)
    assert scene.sensors.attitude_density == (1e-5, 1e-5, 3e-5)
    data["wheels"] = {"torque_limit": 0.1, "momentum_limit": 4.0,
                      "spin_axes": [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1]]}
    wheels = load_scene(data).wheels.build()
    assert wheels.spin_axes[3] == pytest.approx(np.full(3, 3 ** -0.5), rel=1e-15)


@pytest.mark.parametrize("changes, match", [
    # the delay
    ({"controller.delay": -0.1}, r"controller\.delay: must be non-negative \[s\]; got -0\.1"),
    ({"controller.delay": "10 ms"}, r"controller\.delay: must be a number \[s\]"),
    ({"controller.computation_delay": True}, r"controller\.computation_delay: is one sample of a "
                                             r"digital controller"),
    ({"manoeuvre.step": 0.5}, r"manoeuvre\.step: must be at most 2 x controller\.delay = 0\.4 s"),
    # the profile
    ({"manoeuvre.profile": "trapezoid"}, r"manoeuvre\.profile: must be one of 'step'"),
    ({"manoeuvre.profile": "step"}, r"manoeuvre\.torque_limit: applies to the profiles"),
    ({"manoeuvre.profile": "step", "manoeuvre.torque_limit": None,
      "manoeuvre.rate_limit": None}, r"manoeuvre\.feedforward: needs a profile with a rate"),
    ({"manoeuvre.feedforward": "yes"}, r"manoeuvre\.feedforward: must be true or false"),
    ({"manoeuvre.torque_limit": 0.0}, r"manoeuvre\.torque_limit: must be positive \[N\*m\]"),
    ({"manoeuvre.rate_limit": -1.0}, r"manoeuvre\.rate_limit: must be positive \[deg/s\]"),
    ({"manoeuvre.profile": "bang-coast-bang", "manoeuvre.jerk_limit": 1.0},
     r"manoeuvre\.jerk_limit: applies to the 'smooth' profile"),
    ({"manoeuvre.jerk_limit": 1.0}, r"manoeuvre\.jerk_limit: applies to a 'smooth' profile or "
                                    r"base"),
    ({"manoeuvre.profile": "smooth", "manoeuvre.shaper": {"kind": "zv"}},
     r"manoeuvre\.shaper: applies to manoeuvre\.profile = 'shaped'"),
    ({"manoeuvre.shaper": {"kind": "ei"}}, r"manoeuvre\.shaper\.kind: must be one of 'zv', 'zvd'"),
    ({"manoeuvre.shaper": {"modes": 0}}, r"manoeuvre\.shaper\.modes: must be at least 1"),
    ({"manoeuvre.shaper": {"modes": 9}}, r"manoeuvre\.shaper\.modes: must be at most 8"),
    ({"manoeuvre.shaper": {"frequency_error": 0.3}},
     r"manoeuvre\.shaper\.frequency_error: \+-30 % is beyond what the shapers hold"),
    ({"manoeuvre.shaper": {"kind": "zv", "frequency_error": 0.1}},
     r"manoeuvre\.shaper\.frequency_error: \+-10 % is beyond what a ZV shaper holds .* choose "
     r"kind = 'zvd' \(\+-14\.4 %\)"),
    ({"manoeuvre.shaper": {"tolerance": 1.0}}, r"manoeuvre\.shaper\.tolerance: must lie between"),
    ({"manoeuvre.shaper": {"order": 2}}, r"manoeuvre\.shaper\.order: unknown key"),
    # the wheels
    ({"wheels": {"torque_limit": 0.1}}, r"wheels\.momentum_limit: missing required value"),
    ({"wheels": {"torque_limit": -0.1, "momentum_limit": 1.0}},
     r"wheels\.torque_limit: must be positive \[N\*m\]; got -0\.1"),
    ({"wheels": {"torque_limit": [0.1, 0.1], "momentum_limit": 1.0}},
     r"wheels\.torque_limit: must be one number \(every wheel\) or one per wheel: 1 for the one "
     r"wheel of a planar scene; got 2"),
    ({"wheels": {"torque_limit": 0.1, "momentum_limit": 1.0, "viscous_friction": 1e-4}},
     r"wheels\.viscous_friction: needs the wheel's speed: give wheels\.spin_inertia"),
    ({"wheels": {"torque_limit": 0.1, "momentum_limit": 1.0, "spin_axes": [[0, 0, 1]]}},
     r"wheels\.spin_axes: applies to three-axis scenes"),
    ({"wheels": {"torque_limit": 0.1, "momentum_limit": 1.0, "saturation": "soft"}},
     r"wheels\.saturation: must be one of 'scale', 'clip'"),
    ({"wheels": {"torque_limit": 0.1, "momentum_limit": 1.0, "speed_limit": 600.0}},
     r"wheels\.speed_limit: unknown key"),
    ({"manoeuvre": None, "report": {"plots": False}},
     r"wheels: the wheels fly the manoeuvre: the scene needs a manoeuvre table"),
    # the sensors
    ({"sensors": {"attitude_density": -1e-5, "rpe_window": 10.0}},
     r"sensors\.attitude_density: must be non-negative \[rad/sqrt\(Hz\)\] .* got -1e-05: a sign "
     r"slip\?"),
    ({"sensors": {"angle_random_walk": -1e-6, "rpe_window": 10.0}},
     r"sensors\.angle_random_walk: must be non-negative \[rad/sqrt\(s\)\]"),
    ({"sensors": {"attitude_density": [1e-5, 1e-5, 1e-5], "rpe_window": 10.0}},
     r"sensors\.attitude_density: must be one number \[rad/sqrt\(Hz\)\] in a planar scene"),
    ({"sensors": {"bias_instability": 1e-7, "rpe_window": 10.0}},
     r"sensors\.bias_correlation_time: missing"),
    ({"sensors": {"attitude_density": 1e-5, "bias_correlation_time": 100.0, "rpe_window": 1.0}},
     r"sensors\.bias_correlation_time: is given without a bias_instability"),
    ({"sensors": {"attitude_density": 1e-5}}, r"sensors\.rpe_window: missing required value"),
    ({"sensors": {"attitude_density": 1e-5, "rpe_window": 0.0}},
     r"sensors\.rpe_window: must be positive \[s\]"),
    ({"sensors": {"attitude_density": 1e-5, "attitude_rms": 1e-5, "rpe_window": 1.0}},
     r"sensors\.attitude_rms: give the attitude sensor's noise as attitude_density"),
    ({"sensors": {"attitude_rms": 1e-5, "rpe_window": 1.0}},
     r"sensors\.attitude_rate: missing required value"),
    ({"sensors": {"rpe_window": 1.0}}, r"sensors: gives no noise"),
    ({"sensors": {"attitude_density": 1e-5, "rpe_window": 1.0, "probability": 99.73}},
     r"sensors\.probability: must lie between 1e-06 and 1"),
    ({"sensors": {"attitude_density": 1e-5, "rpe_window": 1.0, "placement": "middle"}},
     r"sensors\.placement: must be one of 'random', 'end'"),
    # with the rest of the scene
    ({"controller.given": {"kind": "pd", "A": [], "B": [], "C": [], "D": [[1.0, -1.0, -1.0]]}},
     r"manoeuvre\.feedforward: needs controllers tuned"),
    ({"simulator.name": "basilisk"}, r"manoeuvre\.profile: Basilisk's flight software runs the "
                                     r"step reference"),
    ({"export.fmu": True}, r"export\.systems: a closed-loop FMU has no loop delay"),
])
def test_bad_flown_keys_are_refused_by_key(changes, match):
    with pytest.raises(SceneError, match=match):
        load_scene(flown(**changes))


def test_a_digital_rpe_window_is_whole_samples():
    data = flown(**{"controller.sample_rate": 10.0, "controller.delay": 0.0})
    data["sensors"]["rpe_window"] = 1.05
    with pytest.raises(SceneError, match=r"sensors\.rpe_window: must be a whole number of the "
                                         r"digital controller's samples \(1/sample_rate = 0\.1 s"
                                         r"\) \[s\]; got 1\.05 \(10\.5 samples\)"):
        load_scene(data)
    data["sensors"]["rpe_window"] = 1.0
    data["controller"]["computation_delay"] = True
    scene = load_scene(data)
    assert scene.controller.total_delay == pytest.approx(0.1, rel=1e-15)


def test_three_axis_wheel_axes_that_do_not_span_are_refused():
    data = copy.deepcopy(THREE_AXIS_BOOM)
    data["wheels"] = {"torque_limit": 0.1, "momentum_limit": 4.0,
                      "spin_axes": [[1, 0, 0], [0, 1, 0], [1, 1, 0]]}
    with pytest.raises(SceneError, match=r"wheels\.spin_axes: spin_axes do not span the "
                                         r"controlled axes .* no wheel produces torque about "
                                         r"the direction \[ ?-?0\. +-?0\. +-?1\.\]"):
        load_scene(data)
    data["wheels"] = {"torque_limit": 0.1, "momentum_limit": 4.0}
    with pytest.raises(SceneError, match=r"wheels: a three-axis scene needs the wheels' spin "
                                         r"axes"):
        load_scene(data)
    data["wheels"] = {"torque_limit": 0.1, "momentum_limit": 4.0, "spin_axes": [[0, 0, 0]]}
    with pytest.raises(SceneError, match=r"wheels\.spin_axes\[0\]: must be a non-zero vector"):
        load_scene(data)
    data["wheels"] = {"torque_limit": 0.1, "momentum_limit": 4.0,
                      "pyramid": {"cant_angle": 90.0}}
    with pytest.raises(SceneError, match=r"wheels\.pyramid\.cant_angle: must lie between"):
        load_scene(data)
    data["sensors"] = {"attitude_density": [1e-5, 1e-5], "rpe_window": 10.0}
    data.pop("wheels")
    with pytest.raises(SceneError, match=r"sensors\.attitude_density: must be one number or "
                                         r"three \(x, y, z\)"):
        load_scene(data)


@pytest.mark.parametrize("changes, key, says", [
    ({"controller.delay": 50.0, "manoeuvre.step": 0.1}, "controller.delay",
     "did you give milliseconds? 50 ms = 0.05 s"),
    ({"manoeuvre.rate_limit": 0.0175}, "manoeuvre.rate_limit",
     "did you give rad/s? 0.0175 rad/s = 1.003 deg/s"),
    ({"wheels": {"torque_limit": 30.0, "momentum_limit": 4.0}}, "wheels.torque_limit",
     "was it given in mN*m?"),
    ({"sensors": {"attitude_density": 5.0e-2, "rpe_window": 1.0}}, "sensors.attitude_density",
     "was it given in arcsec/sqrt(Hz) or deg/sqrt(Hz)?"),
    ({"sensors": {"bias_instability": 0.01, "bias_correlation_time": 100.0, "rpe_window": 1.0}},
     "sensors.bias_instability", "was it given in deg/h or deg/s?"),
])
def test_unit_slips_are_warned_about_by_key(changes, key, says):
    scene = load_scene(flown(**changes))
    lines = [w for w in scene.input_warnings if f": {key}" in w]
    assert lines and says in lines[0], scene.input_warnings


def test_plausible_values_are_not_warned_about():
    assert load_scene(flown()).input_warnings == ()


# the fuzz of the scene reader (tests/spacecraft/scene/test_scene_fuzz.py) on the flown keys
FLOWN_KEYS = [
    ("controller", "delay"), ("controller", "computation_delay"), ("controller", "sample_rate"),
    ("manoeuvre", "profile"), ("manoeuvre", "feedforward"), ("manoeuvre", "torque_limit"),
    ("manoeuvre", "rate_limit"), ("manoeuvre", "jerk_limit"), ("manoeuvre", "shaper"),
    ("manoeuvre", "shaper", "kind"), ("manoeuvre", "shaper", "modes"),
    ("manoeuvre", "shaper", "base"), ("manoeuvre", "shaper", "frequency_error"),
    ("manoeuvre", "shaper", "tolerance"), ("manoeuvre", "step"), ("wheels",),
    ("wheels", "torque_limit"), ("wheels", "momentum_limit"), ("wheels", "spin_inertia"),
    ("wheels", "viscous_friction"), ("wheels", "coulomb_friction"), ("wheels", "saturation"),
    ("wheels", "spin_axes"), ("wheels", "pyramid"), ("wheels", "pyramid", "cant_angle"),
    ("sensors",), ("sensors", "attitude_density"), ("sensors", "attitude_rms"),
    ("sensors", "attitude_rate"), ("sensors", "angle_random_walk"),
    ("sensors", "bias_instability"), ("sensors", "bias_correlation_time"),
    ("sensors", "rpe_window"), ("sensors", "placement"), ("sensors", "probability"),
]


@pytest.mark.slow
def test_wild_values_at_every_flown_key():
    """Every flown key with each wild value, in a planar and a three-axis scene: a Scene or a
    one-line SceneError naming a key."""
    from scene_fuzz import check, mutate

    bases = [flown(), {**copy.deepcopy(THREE_AXIS_BOOM), "wheels": {"torque_limit": 0.1,
                                                          "momentum_limit": 4.0,
                                                          "pyramid": {}}}]
    for value in (math.nan, -1.0, 0.0, 1e300, 10**400, "x" * 10_000, [[[[1.0]]]], {"a": 1},
                  [1.0, 2.0, 3.0], [[1, 0, 0]], True, None, 1 + 2j):
        for base in bases:
            for path in FLOWN_KEYS:
                data = copy.deepcopy(base)
                mutate(data, path, value)
                check(lambda: load_scene(data), "<dict>", set())
