"""The runner's errors and non-errors: a call of our API made with a scene value that our API
refuses is a SceneError naming the scene key; trouble inside numpy stays an internal error; a
loop that diverges is a result (the report says where the simulation stopped); warnings are
collected into the results instead of reaching the terminal."""
import math
import re
import warnings

import control
import numpy as np
import pytest

import controllers
from spacecraft.report.write import summary_lines
from spacecraft.design.loop import run
from spacecraft.design.responses import diverged_at, outputs_until_overflow
from spacecraft.scene.read import SceneError

from scenes import scene_with

LQR = {"attitude_weight": 7.6, "torque_weight": 1.0}


def diverging_scene(duration: float):
    """The default scene's LQR tuned on the paper's chain: its loop on the damped truth beam is
    unstable (the report's verdict: UNSTABLE, 2 poles; growth rate 0.028 1/s), so over 40000 s
    its response leaves the float64 range (e^(0.028 t) > 1e250 for t > 2e4 s)."""
    return scene_with(**{"appendages.0.beam.damping_ratio": 0.005, "fidelity.n_modes": 2,
                         "controller.types": ["lqr"], "controller.pd": None,
                         "controller.lqr": LQR, "manoeuvre.duration": duration,
                         "manoeuvre.step": 0.5, "report.equivalence": False})


def test_an_unreachable_tolerance_is_a_scene_error_naming_the_key():
    # before: "internal error: ValueError: no truncation ... raise fidelity.tolerance", exit 1
    data = scene_with(**{"fidelity.n_modes": None, "fidelity.tolerance": 1e-12})
    with pytest.raises(SceneError, match=r"<dict>: fidelity\.tolerance: no truncation with up to "
                                         r"40 modes .* raise fidelity\.tolerance"):
        run(data)


def test_a_bandwidth_above_what_40_modes_reach_says_what_can_help():
    """Issue-9 review: pd.natural_frequency = 1e3 rad/s (inside its documented range) gave
    "best n_modes = 1 with frequency error inf and gain error inf; raise fidelity.tolerance":
    the 5000 rad/s band needs 64 coupled frequencies of the paper's rod, 40 modes give 40, so
    no tolerance can help. The message says so, with no inf, and names what can."""
    data = scene_with(**{"fidelity.n_modes": None, "fidelity.tolerance": 1e-3,
                         "controller.types": ["pd"], "controller.pd.natural_frequency": 1e3})
    with pytest.raises(SceneError) as error:
        run(data)
    message = str(error.value)
    assert "inf" not in message.split() and "raise fidelity.tolerance" not in message
    assert re.search(r"fidelity\.tolerance: no truncation with up to 40 modes .* can meet any "
                     r"tolerance: .* asks for the first 64 coupled frequencies .* give 40; "
                     r"lower the controller's bandwidth or fidelity\.bandwidth_factor, or give "
                     r"fidelity\.n_modes \(about 64 or more\)", message), message


def test_a_diverging_loop_is_reported_not_raised():
    # before: FloatingPointError "simulation overflowed", exit 1
    result = run(diverging_scene(40000.0))
    row = result.data["closed_loops"][0]
    assert row["verdict"]["stable"] is False
    at = row["diverged"]["truth"]
    assert row["diverged"]["design"] is None
    # e^(sigma t) passes the simulator's overflow guard 1e250 near t = ln(1e250)/sigma, sigma
    # the loop's largest growth rate; the prefix ends within a few chunks of it
    sigma = max(control.poles(result.loops[("frequencies", "lqr", "truth")]).real)
    assert 0.5 * math.log(1e250) / sigma < at < math.log(1e308) / sigma
    truth = result.responses[("frequencies", "lqr", "truth")]
    assert truth.diverged and truth.diverged_at == at
    assert np.all(np.isfinite(truth.y)) and truth.t[-1] == at
    # no settling metrics for a diverging loop: None, flagged "diverges" (issue 14)
    time_metrics = [k for k in row["metrics"]["truth"] if k != "diverged"]
    assert time_metrics and all(row["metrics"]["truth"][k] is None for k in time_metrics)
    assert all(row["metric_flags"]["truth"][k] == "diverges" for k in time_metrics)
    assert row["metrics"]["truth"]["diverged"] is True
    assert all(v is None for v in row["peak_difference"].values())
    assert set(row["peak_difference_flags"].values()) == {"diverges"}
    line = [s for s in summary_lines(result.data) if s.startswith("LQR")][0]
    assert f"UNSTABLE: diverges, simulation stopped at t = {at:.6g} s" in line


def test_a_short_run_of_the_same_loop_is_not_called_diverging():
    result = run(diverging_scene(200.0))
    row = result.data["closed_loops"][0]
    assert row["verdict"]["stable"] is False and row["diverged"] == {"design": None,
                                                                     "truth": None}
    # the response is still finite at 200 s, but the loop has growing poles: unstable, and its
    # settling metrics are withheld (issue 14: "settling time 91 s" for an UNSTABLE loop)
    assert row["status"]["truth"]["status"] == "unstable"
    assert row["status"]["truth"]["growth_rate"] > 0
    assert row["metrics"]["truth"]["settling_time"] is None
    assert row["metric_flags"]["truth"]["settling_time"] == "diverges"


def test_overflow_prefix_is_the_exact_response():
    """dx/dt = x + u, y = x, u = 1 from x(0) = 0: y = e^t - 1 until the simulator refuses the
    float range; the prefix it returns is that closed form (relative error of the exact
    discretisation: a few eps per step, growing like the number of steps)."""
    system = control.ss([[1.0]], [[1.0]], [[1.0]], [[0.0]], inputs=["u"], outputs=["y"])
    T = np.arange(2001) * 0.5
    U = np.ones((1, T.size))
    Y = outputs_until_overflow(controllers.Simulator(system, 0.5), T, U)
    finite = np.isfinite(Y[0])
    k = int(np.argmin(finite))
    assert 0 < k < T.size and not finite[k:].any()
    assert math.log(1e250) * 0.5 < T[k - 1] < math.log(1e308)
    np.testing.assert_allclose(Y[0, :k], np.expm1(T[:k]), rtol=1e-11, atol=0)


class _Flagged:
    """A response as the controllers package may return it: flagged, not truncated."""

    def __init__(self, diverged, at, t, y):
        self.diverged, self.diverged_at, self.t, self.y = diverged, at, t, y


def test_divergence_is_read_from_flags_or_from_the_samples():
    t = np.arange(5.0)
    assert diverged_at(_Flagged(True, 2.5, t, np.zeros((1, 5)))) == 2.5
    assert diverged_at(_Flagged(False, None, t, np.full((1, 5), np.inf))) is None
    # no flags: the last finite sample before the first non-finite one
    plain = control.TimeResponseData(t, np.array([[0.0, 1.0, 2.0, np.inf, np.nan]]), None,
                                     np.zeros((1, 5)))
    assert diverged_at(plain) == 2.0
    assert diverged_at(control.TimeResponseData(t, np.zeros((1, 5)), None,
                                                np.zeros((1, 5)))) is None


def test_our_api_refusing_a_scene_value_names_the_key(monkeypatch):
    import appendages
    import appendages.equivalence

    def refuse(beam, n_bodies, match):
        # our API's own check raises (in appendages/): as a fit refusing the beam would
        return appendages.Beam(-1.0, beam.bending_stiffness, beam.linear_density)

    monkeypatch.setattr(appendages.equivalence, "fit_chain", refuse)
    with pytest.raises(SceneError, match=r"<dict>: appendages\[0\]\.fit: cannot fit a chain "
                                         r"\(match = 'frequencies'\): length must be positive"):
        run(scene_with())


def test_numpy_trouble_inside_our_api_stays_an_internal_error(monkeypatch):
    import appendages.equivalence

    def broken(beam, n_bodies, match):
        return np.linalg.inv(np.zeros((2, 2)))   # raised inside numpy: a bug of ours

    monkeypatch.setattr(appendages.equivalence, "fit_chain", broken)
    with pytest.raises(np.linalg.LinAlgError):
        run(scene_with())


def test_warnings_are_collected_into_the_results(monkeypatch, recwarn):
    original = controllers.metrics

    def noisy(response, **kwargs):
        # the runner evaluates metrics under np.errstate (a diverging response's overflow is a
        # verdict, not a warning): raise the RuntimeWarning as numpy would outside it
        warnings.warn("divide by zero encountered in log", RuntimeWarning)
        warnings.warn("a\nmulti-line\nwarning", UserWarning)
        return original(response, **kwargs)

    monkeypatch.setattr(controllers, "metrics", noisy)
    result = run(scene_with(**{"report.equivalence": False}))
    lines = result.data["warnings"]
    assert len(lines) == 2   # each distinct warning once, though raised twice
    assert lines[0].startswith("RuntimeWarning: divide by zero encountered in log (")
    assert lines[1].startswith("UserWarning: a multi-line warning (")
    assert not [w for w in recwarn.list if w.category in (RuntimeWarning, UserWarning)]
