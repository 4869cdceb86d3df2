"""Bounded work at the API (issue 9): requests beyond the documented limits of
appendages.limits are refused at once and by name; appendages.limits.raised() lifts them
explicitly, for one block and one thread only.

Each refusal is checked to come before the work: the refused call is made with arguments whose
work would take minutes or tens of GiB (truncated(5000) of a damped beam projects 20,400
free-free modes on 5000 cantilever ones; rfem(beam, 100000) would assemble a 100,001**2 mass
matrix, 80 GB), so a test that passes did not do it.
"""

import threading

import numpy as np
import pytest

from appendages import Beam, FlexsatError, HingedChain, limits
from appendages.equivalence import fit_chain
from spacecraft import Hub, Mount, Spacecraft

ROD = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)  # the paper's rod (PAPER.md)
DAMPED = Beam(ROD.length, ROD.bending_stiffness, ROD.linear_density, damping_ratio=0.005)


def refused(limit_name, parameter):
    """pytest.raises for a LimitError naming the parameter, the limit and how to raise it."""
    return pytest.raises(limits.LimitError,
                         match=rf"{parameter}.*'{limit_name}'.*limits\.raised\({limit_name}=")


def test_limit_error_is_a_value_error_of_ours_with_its_facts():
    with pytest.raises(ValueError) as info:
        DAMPED.truncated(5000)
    error = info.value
    assert isinstance(error, FlexsatError) and isinstance(error, limits.LimitError)
    assert (error.parameter, error.value, error.limit_name, error.limit) == (
        "n_modes", 5000, "modes", limits.DEFAULTS["modes"])


def test_truncation_beyond_1000_modes_is_refused_and_can_be_allowed():
    with refused("modes", "n_modes"):
        DAMPED.truncated(5000, method="craig-bampton")
    assert DAMPED.truncated(1000).n_modes == 1000  # the limit itself is allowed (lazy)
    with limits.raised(modes=5000):
        assert DAMPED.truncated(5000).n_modes == 5000
    with refused("modes", "n_modes"):  # and the limit is back after the block
        DAMPED.truncated(1001)


def test_chains_beyond_500_bodies_are_refused():
    with refused("bodies", "n_bodies"):
        HingedChain.rfem(ROD, 100_000)
    with refused("bodies", "n"):
        HingedChain.superelements(ROD, 250)  # 501 bodies
    n = 501
    with refused("bodies", "lengths"):
        HingedChain(np.full(n, 0.02), np.full(n, 0.01), np.zeros(n), np.ones(n - 1))
    assert HingedChain.rfem(ROD, 500).n_bodies == 500


def test_fit_chain_limits():
    """Poles-and-zeros fits: the least squares grows like n_bodies**4 (measured 35 s at 20
    bodies on a loaded 2-core machine, see appendages.limits); the paper's frequency fit has
    n - 1 unknowns and is bounded by the chain limit."""
    with refused("fit_bodies", "n_bodies"):
        fit_chain(ROD, n_bodies=1000)
    with refused("bodies", "n_bodies"):
        fit_chain(ROD, n_bodies=1000, match="frequencies")


def test_exact_frequencies_and_assembled_models_are_bounded():
    craft = Spacecraft(Hub(100.0, 50.0), [Mount(ROD, (0.5, 0.0), 0.0)])
    with refused("frequencies", "n"):
        craft.natural_frequencies(10**6)
    # three 1000-mode wings: 3003 coordinates, beyond the 2500 of a dense eigen-decomposition
    wings = Spacecraft(Hub(100.0, 50.0), [Mount(ROD.truncated(1000), (0.0, 0.0), a)
                                          for a in (0.0, 2.0, 4.0)])
    with refused("coordinates", "coordinates"):
        wings.plant()
    with refused("appendages", "mounts"):
        Spacecraft(Hub(100.0, 50.0), [Mount(ROD)] * 101)


def test_beam_root_lists_and_shape_arrays_are_bounded():
    with refused("roots", "n"):
        ROD.natural_frequencies(10**8)
    with refused("elements", r"len\(x\) \* n"):
        ROD.mode_shapes(np.linspace(0.0, ROD.length, 100_000), 1000)


def test_raised_checks_its_arguments_and_is_undone_on_error():
    with pytest.raises(TypeError, match="unknown limit 'mode'"):
        with limits.raised(mode=10):
            pass
    with pytest.raises(ValueError, match="limit modes must be positive"):
        with limits.raised(modes=0):
            pass
    with pytest.raises(RuntimeError):
        with limits.raised(modes=10**6):
            raise RuntimeError("inside")
    assert limits.current("modes") == limits.DEFAULTS["modes"]


def test_raised_applies_to_the_current_thread_only():
    seen = {}

    def other():
        seen["modes"] = limits.current("modes")

    with limits.raised(modes=10**6):
        thread = threading.Thread(target=other)
        thread.start()
        thread.join()
        assert limits.current("modes") == 10**6
    assert seen["modes"] == limits.DEFAULTS["modes"]


def test_evaluation_points_are_bounded():
    """W(s), frequency responses and the criterion's band: at most 1e6 points at once (a W
    of 2e7 points would hold ~20 GiB of temporaries)."""
    from appendages.equivalence import criterion

    s = np.zeros(20_000_000, dtype=complex)  # 320 MB, never processed
    with refused("points", r"s \(number of points\)"):
        ROD.W(s)
    with refused("points", r"s \(number of points\)"):
        ROD.truncated(3).W(s)
    with refused("points", r"omega \(number of frequencies\)"):
        Spacecraft(Hub(100.0, 50.0), [Mount(ROD)]).frequency_response(np.ones(2_000_000))
    with refused("points", "n_points"):
        criterion(ROD, HingedChain.rfem(ROD, 3), n_points=10**9)
