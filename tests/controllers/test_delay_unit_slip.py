"""A loop delay that looks like a unit slip (controllers.delay): every public function that
takes a delay warns once about one above PLAUSIBLE_DELAY (LongDelayWarning, naming the
parameter, its value and the likely slip, at the caller's line) and uses it as given; none
warns at a plausible delay; the scene reader warns by key with the same rule, and a scene's run
does not warn a second time about the same value.

The rule (attitude loops have milliseconds to a few hundred milliseconds of delay, so above
1 s milliseconds given as seconds is likelier) is the module docstring's; the loops here are
slow enough (PD at 0.05 rad/s, delay margin ~13 s) to be stable with the 1.5 s used.
"""
import math
import warnings

import numpy as np
import pytest

import controllers
from controllers.delay import (PLAUSIBLE_DELAY, DelayedSampledPlant, LongDelayWarning,
                               delayed_closed_loop, delayed_discretisation, long_delay,
                               split_delay, warns_long_delay)
from controllers.loop import LoopTransfer
from controllers.margins import loop_verdict, multiloop_margins
from plants import modal_plant

J = 100.0
PLANT = modal_plant(J, [(2.0, 0.01, 0.04, 0.04)], disturbance=False)
PD = controllers.pd(PLANT, natural_frequency=0.05, damping=0.7)
DIGITAL = controllers.pd(PLANT, natural_frequency=0.05, damping=0.7, sample_time=0.5)
NOISE = controllers.SensorNoise(attitude_density=1e-5)
WHEELS = controllers.WheelSet(controllers.ReactionWheel(torque_limit=1.0, momentum_limit=None,
                                                        spin_inertia=0.05))
OMEGA = np.logspace(-3, 1, 200)
LONG = 1.5  # s: above PLAUSIBLE_DELAY


def rigid_loop(w):
    """The PD's loop on the rigid hub, -K(j w) / (J (j w)^2), as a function of omega [rad/s]."""
    s = 1j * np.asarray(w, dtype=float)
    k_p, k_d = J * 0.05**2, 2 * 0.7 * 0.05 * J
    return (k_p + k_d * s) / (J * s**2)


# every public entry that takes a delay, called with it (keyword, or positional where the
# entry takes it so)
ENTRIES = {
    "close_loop": lambda d: controllers.close_loop(PLANT, PD, delay=d, dt=0.25),
    "close_loop digital": lambda d: controllers.close_loop(PLANT, DIGITAL, delay=d),
    "close_loop with computation_delay": lambda d: controllers.close_loop(
        PLANT, DIGITAL, delay=d, computation_delay=True),
    "loop_frequency_response": lambda d: controllers.loop_frequency_response(
        PLANT, PD, OMEGA, delay=d),
    "LoopTransfer": lambda d: LoopTransfer(PLANT, PD, d),
    "margins": lambda d: controllers.margins(PLANT, PD, delay=d),
    "spillover": lambda d: controllers.spillover(PLANT, PD, delay=d),
    "loop_margins": lambda d: controllers.loop_margins(rigid_loop, OMEGA, delay=d),
    "multiloop_margins": lambda d: multiloop_margins(
        lambda w: rigid_loop(w)[:, None, None], OMEGA, delay=d),
    "loop_verdict": lambda d: loop_verdict(rigid_loop, OMEGA, delay=d),
    "close_loop_with_sensors": lambda d: controllers.close_loop_with_sensors(
        PLANT, DIGITAL, delay=d),
    "pointing continuous": lambda d: controllers.pointing(PLANT, PD, NOISE, window=10.0,
                                                          delay=d),
    "pointing digital": lambda d: controllers.pointing(PLANT, DIGITAL, NOISE, window=10.0,
                                                       delay=d),
    "WheelLoop": lambda d: controllers.WheelLoop(PLANT, DIGITAL, WHEELS, delay=d),
    "simulate_wheels": lambda d: controllers.simulate_wheels(
        PLANT, DIGITAL, WHEELS, np.arange(5) * 0.5, delay=d),
    "delayed_closed_loop": lambda d: delayed_closed_loop(PLANT, PD, d, dt=0.25),
    "DelayedSampledPlant": lambda d: DelayedSampledPlant(PLANT, 0.5, d, ["torque"], ["theta"]),
    "delayed_discretisation": lambda d: delayed_discretisation(PLANT.A, PLANT.B, 0.5, d),
    "split_delay": lambda d: split_delay(d, 0.5),
}


def caught(call, delay):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        call(delay)
    return [w for w in seen if issubclass(w.category, LongDelayWarning)]


@pytest.mark.parametrize("entry", list(ENTRIES))
def test_each_entry_warns_once_about_a_long_delay_at_the_callers_line(entry):
    seen = caught(ENTRIES[entry], LONG)
    # once, however many of the entries the call goes through (pointing -> close_loop ->
    # LoopTransfer ...), naming the parameter, the value with its unit and the likely slip
    assert len(seen) == 1, [str(w.message) for w in seen]
    assert str(seen[0].message) == ("delay = 1.5 s: a loop delay of 1.5 s is long for an "
                                    "attitude loop (milliseconds to a few hundred): did you "
                                    "give milliseconds? 1.5 ms = 0.0015 s")
    assert seen[0].filename == __file__      # the line that gave the delay


@pytest.mark.parametrize("entry", list(ENTRIES))
@pytest.mark.parametrize("delay", [0.2, PLAUSIBLE_DELAY])
def test_no_entry_warns_at_a_plausible_delay(entry, delay):
    assert caught(ENTRIES[entry], delay) == []


def test_a_long_delay_is_used_as_given():
    # the warning changes nothing: the margins' delay is the one given, and the delay margin
    # shrinks by exactly it (tests/controllers/test_controllers_delay.py: to 1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", LongDelayWarning)
        delayed = controllers.margins(PLANT, PD, delay=LONG)
    undelayed = controllers.margins(PLANT, PD)
    assert delayed.delay == LONG
    assert delayed.delay_margin == pytest.approx(undelayed.delay_margin - LONG, rel=1e-9)


def test_the_warning_can_be_filtered_and_made_an_error():
    assert issubclass(LongDelayWarning, UserWarning)
    assert controllers.LongDelayWarning is LongDelayWarning
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        warnings.simplefilter("ignore", LongDelayWarning)
        controllers.margins(PLANT, PD, delay=LONG)
    assert not [w for w in seen if issubclass(w.category, LongDelayWarning)]
    with warnings.catch_warnings():
        warnings.simplefilter("error", LongDelayWarning)
        with pytest.raises(LongDelayWarning, match=r"delay = 20 s: .*did you give "
                                                   r"milliseconds\? 20 ms = 0\.02 s"):
            controllers.margins(PLANT, PD, delay=20)


def test_one_sample_of_computation_delay_is_not_a_unit_slip():
    # computation_delay adds the controller's own sample time: a 2 s sample is what it is,
    # not a delay typed in the wrong unit
    slow = controllers.pd(PLANT, natural_frequency=0.05, damping=0.7, sample_time=2.0)
    assert caught(lambda d: controllers.margins(PLANT, slow, delay=d, computation_delay=True),
                  0.0) == []


def test_bad_delays_get_their_error_and_no_warning():
    # a delay that is not a number, negative or beyond MAX_DELAY: the check's error only
    for bad, error in (("1500 ms", TypeError), (-2.0, ValueError), (math.inf, ValueError),
                       (1e101, ValueError), (True, TypeError)):
        with warnings.catch_warnings():
            warnings.simplefilter("error", LongDelayWarning)
            with pytest.raises(error, match="delay"):
                controllers.margins(PLANT, PD, delay=bad)


def test_the_rule():
    # above PLAUSIBLE_DELAY (1 s) only, finite numbers only
    assert PLAUSIBLE_DELAY == 1.0
    assert long_delay(1.0) is None and long_delay(0.5) is None and long_delay(0) is None
    assert long_delay(np.float32(50.0)) == ("a loop delay of 50 s is long for an attitude "
                                            "loop (milliseconds to a few hundred): did you "
                                            "give milliseconds? 50 ms = 0.05 s")
    assert long_delay(np.int64(2)).endswith("2 ms = 0.002 s")
    for odd in (math.nan, math.inf, "20", None, True, [20.0]):
        assert long_delay(odd) is None


def test_the_decorator_needs_a_delay_parameter():
    with pytest.raises(TypeError, match="has no parameter 'delay'"):
        warns_long_delay(lambda plant, tau: None)

    @warns_long_delay
    def positional(plant, delay=0.0):
        return delay

    for call in (lambda: positional(None, 3.0), lambda: positional(None, delay=3.0)):
        with pytest.warns(LongDelayWarning, match="delay = 3 s"):
            assert call() == 3.0
    assert caught(lambda d: positional(None), 0.0) == []


def test_the_scene_reader_uses_the_same_rule():
    from spacecraft.scene import flown

    assert flown.PLAUSIBLE_DELAY is PLAUSIBLE_DELAY
