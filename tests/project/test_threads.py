"""Tests of controllers.threads: BLAS threads sized to the problem.

The thread counts are read back through threadpoolctl, the library the limiter uses; the
simulator's results must not depend on the caller's BLAS settings.
"""

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

from controllers import threads
from controllers.simulate import Simulator


def blas_threads():
    """Thread counts of every loaded BLAS library."""
    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


@pytest.fixture
def two_threads():
    """The caller's setting: two BLAS threads (as a 2-core machine's default)."""
    np.ones((2, 2)) @ np.ones((2, 2))            # BLAS loaded
    with threadpool_limits(limits=2, user_api="blas"):
        yield


def test_small_problems_run_single_threaded(two_threads):
    assert set(blas_threads()) == {2}
    with threads.blas_threads_for(10):
        assert set(blas_threads()) == {1}
    assert set(blas_threads()) == {2}            # the caller's setting restored


def test_large_problems_keep_the_callers_setting(two_threads):
    with threads.blas_threads_for(threads.SINGLE_THREAD_BELOW):
        assert set(blas_threads()) == {2}


def test_a_400_mode_design_loop_runs_single_threaded(two_threads):
    """400 bending modes on a hub: 802 plant states plus the controller's (an LQR + Kalman
    controller of the three-body chain: 8) run with one thread, so that the loop's results
    do not depend on the caller's setting (and a busy machine does not make it 3-6 times
    slower: controllers/threads.py)."""
    with threads.blas_threads_for(802 + 8):
        assert set(blas_threads()) == {1}


def test_limits_nest(two_threads):
    """An inner region neither re-limits nor restores early."""
    with threads.blas_threads_for(5):
        with threads.blas_threads_for(50):
            assert set(blas_threads()) == {1}
        assert set(blas_threads()) == {1}
    assert set(blas_threads()) == {2}


def test_limit_restored_after_an_error(two_threads):
    with pytest.raises(ZeroDivisionError):
        with threads.blas_threads_for(5):
            1 / 0
    assert set(blas_threads()) == {2}


def test_decorator(two_threads):
    @threads.limits_blas_threads(lambda matrix: matrix.shape[0])
    def threads_inside(matrix):
        return blas_threads()

    assert set(threads_inside(np.eye(3))) == {1}
    # Only the size is read: an empty (SINGLE_THREAD_BELOW, 0) array, no n x n memory.
    assert set(threads_inside(np.empty((threads.SINGLE_THREAD_BELOW, 0)))) == {2}
    assert threads_inside.__name__ == "threads_inside"


@pytest.mark.slow
@pytest.mark.parametrize("n_states, n_samples", [(60, 5000), (500, 400)])
def test_simulation_does_not_depend_on_the_callers_threads(n_states, n_samples):
    """Same results, bit for bit, whatever the caller's BLAS threads: a simulation runs
    every product on one thread, whatever its size (a two-thread product of 1e5 x 400 by
    400 x 400 matrices differs from the one-thread product in the last bits)."""
    rng = np.random.default_rng(2)
    import control

    n = n_states
    A = rng.standard_normal((n, n)) / np.sqrt(n)
    A -= (np.abs(np.linalg.eigvals(A).real).max() + 0.5) * np.eye(n)
    sys = control.ss(A, rng.standard_normal((n, 2)), rng.standard_normal((3, n)), 0)
    T = np.arange(n_samples) * 0.01
    U = rng.standard_normal((2, T.size))
    results = []
    for n_threads in (1, 2):
        with threadpool_limits(limits=n_threads, user_api="blas"):
            response = Simulator(sys, 0.01).run(T, U)
            results.append((response.y, response.x))
    np.testing.assert_array_equal(results[0][0], results[1][0])
    np.testing.assert_array_equal(results[0][1], results[1][1])


def test_total_states_counts_every_system():
    import control

    plant = control.ss(np.eye(3), np.ones((3, 1)), np.ones((1, 3)), 0)
    controller = control.ss(np.eye(2), np.ones((2, 1)), np.ones((1, 2)), 0)
    assert threads.total_states(plant, controller, omega=np.ones(4)) == 5
    assert threads.total_states(plant, controller=controller) == 5


@pytest.mark.parametrize("name", ["lqr", "lqr_design", "pd", "margins", "spillover",
                                  "loop_frequency_response"])
def test_design_entry_points_limit_threads(name):
    """The design-loop entry points run inside limits_blas_threads (functools.wraps keeps
    the function as __wrapped__, its name and its docstring)."""
    import controllers

    entry = getattr(controllers, name)
    assert hasattr(entry, "__wrapped__") and entry.__name__ == name
    assert entry.__doc__ == entry.__wrapped__.__doc__


def test_a_small_scene_runs_single_threaded_outside_the_controllers_too(two_threads,
                                                                         monkeypatch):
    """spacecraft.run sizes the whole run like its largest loop: the models' and tables' own
    products (appendages, plant assembly, tuning, tables) run on one thread as the
    controllers' entry points do, so a run's numbers and CPU time do not depend on the
    caller's setting."""
    import spacecraft.design.loop as runner
    import spacecraft.design.tuning as tuning

    seen = []
    original = tuning.tune

    def recording(*args, **kwargs):
        seen.append(set(blas_threads()))
        return original(*args, **kwargs)

    # the run tunes through its model builder (spacecraft.design.models.ModelBuilder.tuned)
    monkeypatch.setattr(tuning, "tune", recording)
    runner.run(None, time_responses=False)
    assert seen and all(s == {1} for s in seen)
    assert set(blas_threads()) == {2}            # the caller's setting restored
