"""Bounded work, divergence as a result, and messages (issue 9, findings 4 and 5)."""
import math
import warnings

import control
import numpy as np
import pytest

import controllers
from controllers.timeresp import MAX_SAMPLES
from plants import modal_plant

J = 250.0  # kg m^2
RIGID = modal_plant(J)
# a roll-off at 4 rad/s tuned on the rigid hub lags this plant's 7 rad/s mode into instability:
# closed-loop pole +0.0261 + 7.04j (continuous), growth e^(0.0261 t)
FLEXIBLE = modal_plant(J, [(2.0, 0.002, 1.0, 0.004), (7.0, 0.002, 1.0, 0.002)])


@pytest.fixture(scope="module")
def unstable_on_truth():
    return controllers.pd(RIGID, natural_frequency=0.5, roll_off=4.0)


def test_compare_refuses_a_huge_sample_count_before_allocating(unstable_on_truth):
    """compare(dt=1e-9, t_final=1e3) tried to allocate 1e12 samples (MemoryError after a long
    wait); now a ValueError names the estimate and the limit, and max_samples raises it."""
    with pytest.raises(ValueError, match=r"1e\+12 samples .*max_samples = 1e\+07"):
        controllers.compare(RIGID, RIGID, unstable_on_truth, angle=0.1, slew_time=20.0,
                            t_final=1e3, dt=1e-9)
    assert MAX_SAMPLES == 10_000_000
    with pytest.raises(ValueError, match=r"1001 samples .*max_samples = 100\b"):
        controllers.slew(controllers.close_loop(RIGID, unstable_on_truth), 0.1, 20.0,
                         t_final=100.0, dt=0.1, max_samples=100)
    response = controllers.slew(controllers.close_loop(RIGID, unstable_on_truth), 0.1, 20.0,
                                t_final=100.0, dt=0.1, max_samples=1001)
    assert np.asarray(response.t).size == 1001


@pytest.mark.slow
@pytest.mark.parametrize("sample_time, t_final, growth", [(None, 40000.0, 0.0261),
                                                          (0.2, 8000.0, 0.166)])
def test_a_diverging_loop_is_a_result_not_a_crash(unstable_on_truth, sample_time, t_final,
                                                   growth):
    """A loop unstable on the truth plant, run for 40000 s, raised 'simulation overflowed'
    from controllers/simulate.py. Its response now stops at the last sample inside the float64
    range; the metrics say it diverged and when, and give no settling time or peak (None).
    Digital: the PD sampled at 5 Hz with its roll-off at 2 rad/s, growth e^(0.166 t)."""
    K = unstable_on_truth if sample_time is None else controllers.pd(
        RIGID, natural_frequency=0.5, roll_off=2.0, sample_time=sample_time)
    step = 0.5 if sample_time is None else sample_time
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning from the overflow either
        result = controllers.compare(RIGID, FLEXIBLE, K, angle=0.1, slew_time=20.0,
                                     t_final=t_final, dt=step)
    truth = result.truth_metrics
    assert result.diverged and not result.verdict.stable
    assert truth["diverged"] is True
    # |x| ~ e^(growth t) reaches 1e250 (ln 1e250 = 575.6) after ~575.6 / growth s, later by
    # the time the unstable mode takes to grow from its small initial excitation
    assert 575.6 / growth < truth["diverged_at"] < t_final
    response = result.truth_response
    assert response.diverged_at == truth["diverged_at"]
    t = np.asarray(response.t)
    assert t[-1] < truth["diverged_at"] <= t[-1] + step * (1 + 1e-9)
    assert np.all(np.isfinite(np.asarray(response.y)))
    for name in ("peak_torque", "peak_attitude_error", "final_attitude_error", "overshoot",
                 "settling_time"):
        assert truth[name] is None
    assert result.design_metrics["diverged"] is False
    assert result.design_metrics["settling_time"] is not None
    text = str(result)
    assert "DIVERGED at" in text and "inf" not in text and "nan" not in text
    assert result.t.size == t.size  # differences over the time both responses cover


def test_metrics_of_a_loop_that_never_settles_are_none_not_inf(unstable_on_truth):
    loop = controllers.close_loop(FLEXIBLE, unstable_on_truth)
    # e^(0.0261 x 1500) ~ 1e17: the oscillation has left the 2 % band, inside the float range
    m = controllers.metrics(controllers.slew(loop, 0.1, 20.0, t_final=1500.0))
    assert m["diverged"] is False and m["settling_time"] is None
    assert all(v is None or isinstance(v, bool) or math.isfinite(v) for v in m.values())


def test_type_errors_name_the_parameter_and_unit(unstable_on_truth):
    with pytest.raises(TypeError, match=r"angle must be a real number \[rad\] \(give the "
                       r"number in SI units, without a unit string\); got str '1'"):
        controllers.compare(RIGID, RIGID, unstable_on_truth, angle="1", slew_time=20.0)
    with pytest.raises(TypeError, match=r"slew_time must be a real number \[s\]"):
        controllers.compare(RIGID, RIGID, unstable_on_truth, angle=0.1, slew_time=[20.0])
    loop = controllers.close_loop(RIGID, unstable_on_truth)
    with pytest.raises(TypeError, match=r"t_final must be a real number \[s\]"):
        controllers.step_response(loop, t_final="10")
    with pytest.raises(TypeError, match=r"amplitude must be a real number"):
        controllers.disturbance_response(loop, amplitude=None)


def test_values_in_messages_are_cut_to_about_100_characters():
    long = "x" * 100_000
    with pytest.raises(ValueError, match="notch must be a frequency") as info:
        controllers.pd(FLEXIBLE, natural_frequency=0.1, notch=long)
    assert len(str(info.value)) < 250
    with pytest.raises(ValueError, match="estimator must be 'kalman'") as info:
        controllers.lqr(RIGID, attitude_weight=1.0, rate_weight=0.0, torque_weight=1.0,
                        estimator=long)
    assert len(str(info.value)) < 250
    with pytest.raises(TypeError, match="natural_frequency must be a real number") as info:
        controllers.pd(FLEXIBLE, natural_frequency=np.ones(200_000), damping=0.7)
    assert len(str(info.value)) < 250


def test_extreme_lqr_weights_are_refused_by_name():
    """Weights 1e300 / 1e-300 ended in 'estimator is not stable' naming no weight; now the
    message names the weights and the rigid-body bandwidth they set."""
    for q, r in ((1e300, 1e-300), (1e300, 1.0), (1.0, 1e300), (1e-300, 1.0)):
        with pytest.raises(ValueError, match=r"attitude_weight.*torque_weight") as info:
            controllers.lqr(FLEXIBLE, attitude_weight=q, rate_weight=0.0, torque_weight=r)
        assert "bandwidth" in str(info.value)


@pytest.mark.slow
def test_no_runtime_warning_leaks_from_designs_and_analysis():
    """Undamped modes (L infinite on the grid), a diverging loop, a digital loop on an undamped
    plant, extreme but accepted specifications: RuntimeWarnings are turned into results or
    errors of ours, never printed."""
    undamped = modal_plant(J, [(2.0, 0.0, 0.04, 0.04), (11.0, 0.0, 0.02, 0.02)])
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        for plant in (FLEXIBLE, undamped):
            for K in (controllers.pd(RIGID, natural_frequency=0.5, roll_off=4.0),
                      controllers.pd(plant, natural_frequency=1e-6),
                      controllers.pd(plant, natural_frequency=0.3, sample_time=0.2),
                      controllers.lqr(plant, attitude_weight=1e20, rate_weight=0.0,
                                      torque_weight=1.0),
                      controllers.lqr(plant, attitude_weight=1e-20, rate_weight=1e-30,
                                      torque_weight=1.0, sample_time=50.0)):
                controllers.margins(plant, K)
                controllers.spillover(plant, K)
                controllers.compare(RIGID, plant, K, angle=0.1, slew_time=20.0,
                                    t_final=3000.0)


@pytest.mark.parametrize("hold", ["zero", "linear"])
def test_a_step_whose_transition_matrix_overflows_warns_in_our_words(hold):
    """Finding of the issue-9 review: simulate() of x' = [[0.02, 1], [-1, 0.02]] x on a 2e5 s
    grid printed scipy's "RuntimeWarning: overflow encountered in matmul" from expm: the
    growth over one step is e^(0.02 x 2e5) = e^4000, beyond float64 (e^709.8). Now no numpy
    or scipy warning: a DiscretisationOverflowWarning names dt and the growth rate, and the
    response is a result (on_overflow="stop": it ends at t = 0, diverged at the first step) or
    our FloatingPointError."""
    growing = control.ss([[0.02, 1.0], [-1.0, 0.02]], [[0.0], [1.0]], [[1.0, 0.0]], 0.0,
                         inputs=["u"], outputs=["y"])
    T = np.array([0.0, 2e5, 4e5])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        response = controllers.simulate(growing, T, np.ones((1, T.size)), hold=hold,
                                        on_overflow="stop")
        with pytest.raises(FloatingPointError, match="overflowed"):
            controllers.simulate(growing, T, np.ones((1, T.size)), hold=hold)
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], \
        [str(w.message) for w in caught]
    ours = [w for w in caught
            if issubclass(w.category, controllers.DiscretisationOverflowWarning)]
    assert ours and all("dt = 2e+05 s" in str(w.message) and "0.02 1/s" in str(w.message)
                        for w in ours)
    assert response.diverged_at == 2e5 and np.asarray(response.t).tolist() == [0.0]
