"""Fuzz of every public function of the flown manoeuvre (profiles, shapers,
feedforward, delay): one parameter at a time gets an awkward value (negative, zero, NaN, inf,
extremes, a string, a bool, an array, None) with the others valid, every combination; the call either succeeds with
finite results or raises TypeError/ValueError whose message names that parameter (or, for a
combination of limits that cannot complete the slew, says so with the limits by name); never a
numpy/scipy error, a NaN or a RuntimeWarning."""
import math
import re
import warnings

import numpy as np
import pytest

import controllers
from controllers import delay as D
from controllers import profiles as P
from plants import modal_plant

J = 250.0
PLANT = modal_plant(J, [(2.0, 0.005, 0.04, 0.04)])
K = controllers.pd(PLANT, natural_frequency=0.3, roll_off=3.0, feedforward=True)
KD = controllers.pd(PLANT, natural_frequency=0.3, sample_time=0.2)
LOOP = controllers.close_loop(PLANT, K)
BASE = P.bang_coast_bang(0.2, 80.0, inertia=J, torque_limit=0.05, rate_limit=0.005)
SHAPER = P.zv_shaper(1.0, 0.01)
RESPONSE = controllers.profile_response(LOOP, BASE, inertia=J, dt=0.5)

AWKWARD = [-1.0, 0.0, math.nan, math.inf, -math.inf, 1e308, 1e-308, 7.0, "1", None, True,
           [1.0, 2.0], np.array([math.nan]), 1j, 2 * math.pi + 1e-9]

# (name, callable taking keyword arguments, the valid keyword arguments)
CASES = [
    ("step_reference", P.step_reference, dict(angle=0.2, duration=60.0, axis=None)),
    ("bang_coast_bang", P.bang_coast_bang,
     dict(angle=0.2, duration=80.0, inertia=J, torque_limit=0.05, rate_limit=0.005, axis=None)),
    ("jerk_limited", P.jerk_limited,
     dict(angle=0.2, duration=80.0, inertia=J, torque_limit=0.05, rate_limit=0.005,
          jerk_limit=1e-4, axis=None)),
    ("minimum_time", P.minimum_time,
     dict(kind="smooth", angle=0.2, inertia=J, torque_limit=0.05, rate_limit=0.005,
          jerk_limit=1e-4, axis=None)),
    ("zv_shaper", P.zv_shaper, dict(frequency=1.0, damping=0.01)),
    ("zvd_shaper", P.zvd_shaper, dict(frequency=1.0, damping=0.01)),
    ("mode_shaper", P.mode_shaper, dict(modes=[(1.0, 0.01)], kind="zvd")),
    ("shaped", P.shaped, dict(base=BASE, shaper=SHAPER)),
    ("reference_profile", P.reference_profile,
     dict(kind="shaped", angle=0.2, duration=90.0, inertia=J, torque_limit=0.05,
          rate_limit=0.005, shaper=SHAPER, base="bang-coast-bang", axis=None)),
    ("Shaper", P.Shaper, dict(amplitudes=[0.5, 0.5], times=[0.0, 1.0])),
    ("residual_vibration", SHAPER.residual_vibration, dict(frequency=1.0, damping=0.01)),
    ("insensitivity", SHAPER.insensitivity, dict(frequency=1.0, damping=0.01, tolerance=0.05)),
    ("path", BASE.path, dict(t=np.linspace(0, 90, 7), derivative=1)),
    ("torque_ff", BASE.torque_ff, dict(t=np.linspace(0, 90, 7), inertia=J, gyroscopic=True)),
    ("references", BASE.references, dict(t=np.linspace(0, 90, 7), inertia=J,
                                         gyroscopic=True)),
    ("peak_torque", BASE.peak_torque, dict(inertia=J, gyroscopic=True)),
    ("hold_error", BASE.hold_error, dict(dt=0.3, hold="linear", inertia=J, norm="sup")),
    ("generator", BASE.generator, dict(inertia=J)),
    ("generator_input", BASE.generator_input, dict(t=np.linspace(0, 90, 7))),
    ("driving", BASE.driving, dict(closed_loop=LOOP, inertia=J)),
    ("profile_response", controllers.profile_response,
     dict(closed_loop=LOOP, profile=BASE, inertia=J, t_final=100.0, dt=0.5, hold="linear",
          gyroscopic=False, max_samples=None)),
    ("manoeuvre_metrics", controllers.manoeuvre_metrics,
     dict(response=RESPONSE, end_time=80.0, settling_band=0.02)),
    ("margins", controllers.margins,
     dict(plant=PLANT, controller=K, delay=0.1, computation_delay=False)),
    ("spillover", controllers.spillover,
     dict(truth_plant=PLANT, controller=K, delay=0.1, computation_delay=False)),
    ("close_loop", controllers.close_loop,
     dict(plant=PLANT, controller=K, delay=0.1, computation_delay=False, dt=0.05)),
    ("close_loop_digital", controllers.close_loop,
     dict(plant=PLANT, controller=KD, delay=0.1, computation_delay=True)),
    ("loop_frequency_response", controllers.loop_frequency_response,
     dict(plant=PLANT, controller=K, delay=0.1, computation_delay=False)),
    ("split_delay", D.split_delay, dict(delay=0.35, dt=0.1)),
    ("delayed_discretisation", D.delayed_discretisation,
     dict(A=PLANT.A, B=PLANT.B[:, :1], dt=0.1, delay=0.35)),
    ("check_delay", D.check_delay, dict(delay=0.1)),
    ("total_delay", D.total_delay, dict(controller=KD, delay=0.1, computation_delay=True)),
    ("pd", controllers.pd, dict(plant=PLANT, natural_frequency=0.3, feedforward=True)),
    ("lqr", controllers.lqr, dict(plant=PLANT, attitude_weight=1e3, rate_weight=1e3,
                                  torque_weight=1.0, feedforward=True)),
    ("rate_reference_state", controllers.rate_reference_state, dict(plant=PLANT)),
]
CASE_NAMES = [c[0] for c in CASES]


def finite(value) -> bool:
    """Every number reachable in a result is finite (profiles: their path sampled)."""
    if isinstance(value, P.Profile):
        return bool(np.all(np.isfinite(value.path(np.linspace(0, value.end_time, 50)))))
    if isinstance(value, dict):
        return all(finite(v) for v in value.values() if v is not None and not isinstance(
            v, bool))
    if isinstance(value, (tuple, list)):
        return all(finite(v) for v in value)
    if hasattr(value, "A") and hasattr(value, "D"):   # a StateSpace
        return all(np.all(np.isfinite(np.asarray(getattr(value, m))))
                   for m in ("A", "B", "C", "D"))
    if hasattr(value, "as_dict"):                     # margins: inf allowed, NaN not
        return not any(isinstance(v, float) and math.isnan(v) for v in vars(value).values())
    if isinstance(value, (float, int, np.floating, np.integer, np.ndarray)):
        array = np.asarray(value)
        return not np.any(np.isnan(array)) if array.dtype.kind in "fc" else True
    return True


@pytest.mark.parametrize("name", CASE_NAMES)
def test_flown_fuzz(name):
    """Every parameter of the function with every awkward value (exhaustive, deterministic)."""
    _, function, valid = CASES[CASE_NAMES.index(name)]
    for parameter in sorted(valid):
        for value in AWKWARD:
            check_call(name, function, valid, parameter, value)


def check_call(name, function, valid, parameter, value):
    kwargs = dict(valid)
    kwargs[parameter] = value
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            result = function(**kwargs)
        except (TypeError, ValueError) as error:
            message = str(error)
            named = re.search(rf"\b{re.escape(parameter)}\b", message)
            infeasible = "shortest time they allow" in message
            assert named or infeasible, (name, parameter, value, message)
            given_nan = isinstance(value, (float, np.ndarray)) and not np.all(np.isfinite(value))
            # "got nan" ("NaN or inf") only echoing a non-finite value that was given
            assert given_nan or "nan" not in message.lower().replace(";", " ").split(), message
            result = None
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], \
        (name, parameter, value, [str(w.message) for w in caught])
    if result is not None:
        assert finite(result), (name, parameter, value)


@pytest.mark.parametrize("name", CASE_NAMES)
def test_every_case_is_valid_as_given(name):
    """The fuzz's baseline: each function runs with its valid arguments."""
    _, function, valid = CASES[CASE_NAMES.index(name)]
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        assert finite(function(**valid))
