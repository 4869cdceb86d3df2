"""controllers.compare from Python (issue 14, "Python API"): the slew's length is slew_time as
in scenes (duration deprecated), and Comparison.plot saves or returns a figure whose frequency
range comes from the loop and whose phase is wrapped."""
import math
import warnings

import numpy as np
import pytest

import controllers
from appendages import Beam
from spacecraft import Hub, Mount, Spacecraft

ROD = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=0.005)


@pytest.fixture(scope="module")
def loops():
    hub = Hub(100.0, 50.0)
    design = Spacecraft(hub, [Mount(ROD.truncated(2), (0.5, 0.0), 0.0, name="rod")]).plant()
    truth = Spacecraft(hub, [Mount(ROD.truncated(4), (0.5, 0.0), 0.0, name="rod")]).plant()
    K = controllers.pd(design, natural_frequency=0.1, damping=0.7)
    return design, truth, K


def test_slew_time_is_the_keyword_and_duration_is_deprecated(loops):
    design, truth, K = loops
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        new = controllers.compare(design, truth, K, angle=0.1, slew_time=60.0, dt=0.5)
    with pytest.warns(DeprecationWarning, match=r"compare\(duration=\.\.\.\) is the slew "
                                                r"time: use slew_time="):
        old = controllers.compare(design, truth, K, angle=0.1, duration=60.0, dt=0.5)
    # the same slew: 3 x slew_time simulated either way
    assert new.truth_metrics["overshoot"] == old.truth_metrics["overshoot"]
    assert np.asarray(new.truth_response.t)[-1] == pytest.approx(180.0)
    with pytest.raises(TypeError, match="slew_time"):
        controllers.compare(design, truth, K, angle=0.1, slew_time=60.0, duration=60.0)
    with pytest.raises(TypeError, match="needs slew_time"):
        controllers.compare(design, truth, K, angle=0.1)


@pytest.mark.slow
def test_plot_saves_to_a_path_or_returns_the_figure(loops, tmp_path):
    design, truth, K = loops
    result = controllers.compare(design, truth, K, angle=0.1, slew_time=60.0, dt=0.5)
    fig = result.plot()
    phase = fig.axes[3]
    assert phase.get_ylabel() == "arg L [deg]"
    values = np.concatenate([np.asarray(line.get_ydata(), float) for line in phase.get_lines()])
    # wrapped into (-270, 90] deg; before: unwrapped to -6000 deg over 1e-4..1e6 rad/s
    assert np.nanmin(values) >= -270.0 and np.nanmax(values) <= 90.0
    lo, hi = phase.get_xlim()
    # a PD at 0.1 rad/s on the rod: crossover ~0.14 rad/s, the plant's modes up to ~16 rad/s
    assert 1e-3 < lo < 0.14 / 10 and 16.0 < hi < 1e3
    path = result.plot(tmp_path / "compare.png")
    assert path == tmp_path / "compare.png" and path.stat().st_size > 10_000
