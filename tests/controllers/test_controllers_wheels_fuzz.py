"""The methods of the wheels' and the pointing API (the functions and classes are fuzzed by
tests/project/test_public_api_fuzz.py) refuse a bad argument by the parameter's name.

Each parameter of each method gets each value of the fuzz tests' BAD list (tests/support/fuzzing.py), the others
their valid values; a call passes if it returns without a NaN in its numeric result, or raises
ValueError or TypeError naming the parameter, or FloatingPointError saying that the response
leaves the float64 range (inputs near 1e308); a RuntimeWarning fails it.
"""
from __future__ import annotations

import math
import re
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import controllers


from plants import modal_plant  # noqa: E402
from fuzzing import BAD  # noqa: E402

PLANT = modal_plant(50.0, [(2.0, 0.005, 0.04, 0.04)], tips=[("wing_tip_deflection", [0.5])],
                    disturbance=False)
PD = controllers.pd(PLANT, natural_frequency=0.5)
WHEEL = controllers.ReactionWheel(torque_limit=0.05, momentum_limit=0.5, spin_inertia=0.01)
PLANAR = controllers.WheelSet(WHEEL)
PYRAMID = controllers.WheelSet.pyramid(WHEEL, 0.9)
LOOP = controllers.WheelLoop(PLANT, PD, PLANAR)
T = np.linspace(0.0, 20.0, 201)
BUDGET = controllers.pointing(PLANT, PD, controllers.SensorNoise(attitude_density=1e-5),
                              window=1.0)

#: (name, function, valid keyword arguments)
METHODS = [
    ("WheelSet.pyramid", controllers.WheelSet.pyramid,
     dict(wheel=WHEEL, cant_angle=0.9, azimuth=0.0, saturation="scale", names=None)),
    ("WheelSet.torque_capacity", PYRAMID.torque_capacity, dict(direction=[1.0, 0.0, 0.0])),
    ("WheelSet.momentum_capacity", PYRAMID.momentum_capacity, dict(direction=[0.0, 1.0, 0.0])),
    ("WheelSet.applied_torques", PLANAR.applied_torques,
     dict(command=np.array([0.1]), momentum=np.array([0.4]))),
    ("WheelSet.friction_torques", PLANAR.friction_torques, dict(momentum=np.array([0.4]))),
    ("WheelLoop.simulate", LOOP.simulate,
     dict(T=T, U=0.01 * np.ones(T.size), X0=None, max_samples=None)),
    ("SensorNoise.from_rms", controllers.SensorNoise.from_rms,
     dict(attitude_rms=1e-5, sample_rate=10.0)),
    ("SensorNoise.per_axis", controllers.SensorNoise(attitude_density=1e-5).per_axis,
     dict(n_axes=1)),
    ("PointingBudget.at", BUDGET.at, dict(probability=0.99)),
]
CASES = [(name, parameter, i) for name, _, valid in METHODS for parameter in valid
         for i in range(len(BAD))]


def _has_nan(value) -> bool:
    if isinstance(value, (float, np.floating)):
        return math.isnan(value)
    if isinstance(value, np.ndarray) and value.dtype.kind in "fc":
        return bool(np.isnan(value).any())
    if isinstance(value, (tuple, list)):
        return any(_has_nan(v) for v in value)
    if isinstance(value, dict):
        return any(_has_nan(v) for v in value.values())
    if hasattr(value, "response"):
        return _has_nan(np.asarray(value.response.outputs))
    return False


@pytest.mark.parametrize("name, parameter, i", CASES)
def test_methods_refuse_bad_arguments_by_name(name, parameter, i):
    function, valid = next((f, v) for n, f, v in METHODS if n == name)
    kwargs = dict(valid, **{parameter: BAD[i]})
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        warnings.simplefilter("ignore", UserWarning)      # unit-slip warnings are legal
        try:
            result = function(**kwargs)
        except (ValueError, TypeError) as error:
            assert re.search(rf"\b{re.escape(parameter)}\b", str(error)), (parameter, error)
            return
        except FloatingPointError as error:
            assert "float64 range" in str(error), error
            return
    assert not _has_nan(result), (name, parameter, BAD[i])
