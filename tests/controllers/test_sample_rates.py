"""Sample-rate refusals give the real reason (issue 20, item 5).

A digital loop is refused for what really goes wrong, with numbers: a rate too slow for the
loop's crossover (the hold's lag), a mode sampled at a multiple of half its period
(pathological sampling, omega T = k pi with k >= 1), a rate too fast for double precision
(omega_c T below 1e-9); a fast rate that is none of these is designed, not refused.
"""
import math
import sys
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest

import controllers
from spacecraft.scene.read import scene_path


from plants import modal_plant  # noqa: E402

J = 50.0  # kg m^2
# a mode below 1 rad/s (at 1 MHz its omega T < 1e-6, which was taken for omega T = 0 pi) and one
# above
PLANT = modal_plant(J, [(0.9, 0.005, 0.04, 0.04), (15.0, 0.005, 0.02, 0.02)])


def test_fast_sampling_is_not_pathological():
    """PD at 1 MHz: was refused as "pathological sampling (omega T = 0 pi)". omega T -> 0 keeps
    the sampled pair 1 +- j omega T apart; the sampled loop tends to the continuous one, its
    phase margin within O(omega_c T) (here 1e-7 rad: 1e-5 deg, to spare)."""
    continuous = controllers.margins(PLANT, controllers.pd(PLANT, natural_frequency=0.1))
    with warnings.catch_warnings():
        warnings.simplefilter("error", controllers.RemovedModesWarning)
        K = controllers.pd(PLANT, natural_frequency=0.1, sample_time=1e-6)
    digital = controllers.margins(PLANT, K)
    assert digital.phase_margin == pytest.approx(continuous.phase_margin, rel=0, abs=1e-5)


def test_pathological_sampling_is_still_refused():
    """omega T = pi for the 15 rad/s mode: the sampled pair meets at z = -1 (Kalman, Ho and
    Narendra 1963); 2 pi / T = 30 rad/s is far above 10 x the 0.15 rad/s crossover."""
    T = math.pi / 15.0
    with pytest.raises(ValueError, match=r"samples the 15 rad/s mode at a multiple of half its "
                                         r"period \(omega T = 1 pi\): pathological sampling"):
        controllers.pd(PLANT, natural_frequency=0.1, sample_time=T)


@pytest.mark.parametrize("T", [1e-10, 1e-14])
def test_a_rate_too_fast_for_double_precision_says_so(T):
    """T = 1e-14 s was refused with "lower natural_frequency toward the plant's modes": the
    rigid-body poles were computed at z = 1 exactly. The reason is the precision of z near 1."""
    with pytest.raises(ValueError, match=r"sample_time .* s is too short for double precision: "
                                         r"the loop turns by omega_c T = .* rad per sample at "
                                         r"its rigid-body crossover 0\.15\d* rad/s.*eps / T = "
                                         r".* 1/s; use sample_time >= 6\.\d*e-09 s"):
        controllers.pd(PLANT, natural_frequency=0.1, sample_time=T)
    with pytest.raises(ValueError, match=r"too short for double precision"):
        controllers.lqr(PLANT, attitude_weight=J**2 * 1e-4, rate_weight=0.0, torque_weight=1.0,
                        sample_time=T)


def test_a_rate_too_slow_names_the_crossover():
    with pytest.raises(ValueError, match=r"sample_time 10 s is too long for the loop bandwidth: "
                                         r"the sampling frequency 2\*pi/T = 0\.6283 rad/s must be "
                                         r"at least 10 x the loop's rigid-body gain-crossover"):
        controllers.pd(PLANT, natural_frequency=0.1, sample_time=10.0)


def hinged_wing_lqr(rate):
    with open(scene_path("hinged_wing"), "rb") as stream:
        data = tomllib.load(stream)
    data.pop("manoeuvre")
    data["report"] = {"plots": False}
    data["outputs"] = {}
    data["controller"] = {"types": ["lqr"], "lqr": {"attitude_weight": 7.6, "rate_weight": 0.0,
                                                    "torque_weight": 1.0}}
    if rate is not None:
        data["controller"]["sample_rate"] = rate
    return data


def test_the_hinged_wing_lqr_at_10_khz_is_designed_like_at_1_and_100_khz():
    """At 10 kHz scipy's real QZ could not reorder the symplectic pencil (every eigenvalue near
    z = 1) and the design was refused with "choose weights", though the same weights work at
    1 and 100 kHz. The complex QZ solves it; the digital gains converge to the continuous
    design's at first order in T (the sampled cost Q T, R T is first order): from 1 to 10 kHz
    ten times closer (1.8e-5 -> 1.8e-6 of the largest gain); at 100 kHz the first-order term
    (1.8e-7) meets the round-off of the ill-conditioned sampled Riccati equation (its
    condition grows like 1/T; 4.6e-7 measured with OpenBLAS's Haswell kernels), bounded here by
    2e-6."""
    import spacecraft

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = spacecraft.run(hinged_wing_lqr(None), time_responses=False)
        plant = result.designs["design"]["plant"]
        kwargs = dict(attitude_weight=7.6, rate_weight=0.0, torque_weight=1.0)
        K_c = controllers.lqr_design(plant, **kwargs).K
        errors = [float(np.abs(controllers.lqr_design(plant, sample_time=T, **kwargs).K - K_c)
                        .max() / np.abs(K_c).max()) for T in (1e-3, 1e-4, 1e-5)]
        ran = spacecraft.run(hinged_wing_lqr(1e4), time_responses=False)
    assert ran.data["closed_loops"][0]["verdict"]["stable"]
    assert errors[1] < 0.2 * errors[0] and errors[2] < 2e-6, errors


def test_a_digital_lqr_failure_names_the_sampling_not_the_weights(monkeypatch):
    """When the continuous design at the same weights succeeds and the digital one cannot be
    computed, the message blames the sample time (it used to say "choose weights")."""
    import importlib

    def failing(*args, **kwargs):
        raise ValueError("digital regulator: the discrete Riccati equation has no stabilising "
                         "solution that can be computed (LAPACK)")

    monkeypatch.setattr(importlib.import_module("controllers.lqr"), "solve_dare", failing)
    with pytest.raises(ValueError, match=r"the digital design at sample_time 0\.01 s failed "
                                         r"numerically \(.*\) where the continuous design "
                                         r"with the same weights succeeded: the sampling is "
                                         r"the cause"):
        controllers.lqr(PLANT, attitude_weight=J**2 * 1e-4, rate_weight=0.0,
                        torque_weight=1.0, sample_time=0.01)
