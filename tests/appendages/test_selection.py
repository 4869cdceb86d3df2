"""The model-selection rule: appendages.selection.cheapest_model."""

import math

import numpy as np
import pytest

from appendages import Beam
from appendages.selection import FAMILIES, QUANTITIES, candidates, cheapest_model

# A beam unlike the paper's rod (aluminium tube, 3 m): the table is dimensionless, so the
# choices made on the rod's measurements must hold here too.
TUBE = Beam.tube(3.0, 0.05, 0.002, 2700.0, 7.0e10)


def relative_errors(model, beam):
    """(poles, zeros) relative errors as in benchmarks/selection_table.py (first two each)."""
    def worst(values, exact):
        if values.size < exact.size:
            return math.inf
        return float(np.max(np.abs(values[: exact.size] / exact - 1.0)))

    e_p = worst(model.poles(), beam.natural_frequencies(2))
    e_z = max(worst(model.zeros(r), beam.zeros(r, 2)) for r in (1, 2, 4))
    return {"poles": e_p, "zeros": e_z, "poles-and-zeros": max(e_p, e_z)}


@pytest.mark.parametrize("quantity", QUANTITIES)
@pytest.mark.parametrize("tolerance", [1e-2, 1e-3, 1e-5])
def test_choice_meets_tolerance_on_another_beam(quantity, tolerance):
    """The cheapest choice, built for the tube, has its error below the tolerance."""
    choice = cheapest_model(tolerance, quantity=quantity)
    assert choice.guaranteed <= tolerance
    model = choice.build(TUBE)
    assert model.state_space().nstates == 2 * choice.n_dof
    assert relative_errors(model, TUBE)[quantity] < tolerance


@pytest.mark.parametrize("family", ["craig-bampton", "rfem", "superelements"])
def test_every_candidate_meets_and_one_size_less_does_not(family):
    """For families whose errors fall monotonically, the size is the smallest that works."""
    (choice,) = candidates(1e-3, quantity="zeros", families=[family])
    assert relative_errors(choice.build(TUBE), TUBE)["zeros"] < 1e-3
    smaller = type(choice)(family, choice.size - 1, 0, "zeros", 1e-3, 1e-3)
    if choice.size - 1 >= (2 if family == "rfem" else 1):
        assert relative_errors(smaller.build(TUBE), TUBE)["zeros"] >= 1e-3


def test_candidates_sorted_by_cost_and_cheapest_is_first():
    found = candidates(1e-3)
    assert [c.n_dof for c in found] == sorted(c.n_dof for c in found)
    assert cheapest_model(1e-3) == found[0]
    assert {c.family for c in found} <= set(FAMILIES)


def test_family_restriction_to_lumped_models():
    choice = cheapest_model(1e-2, quantity="poles", families=("rfem", "superelements"))
    assert choice.family in ("rfem", "superelements")
    assert relative_errors(choice.build(TUBE), TUBE)["poles"] < 1e-2


def test_tighter_tolerance_never_cheaper():
    costs = [cheapest_model(t, quantity="zeros").n_dof for t in (1e-1, 1e-2, 1e-3, 1e-4, 1e-6)]
    assert costs == sorted(costs)


def test_unreachable_tolerance_is_a_clear_error():
    with pytest.raises(ValueError, match="no model .* meets tolerance 1e-12"):
        cheapest_model(1e-12)
    with pytest.raises(ValueError, match="rfem"):
        cheapest_model(1e-8, families=["rfem"])


@pytest.mark.parametrize("tolerance, error, match", [
    (0.0, ValueError, "tolerance must lie in"), (1.0, ValueError, "tolerance"),
    (math.nan, ValueError, "tolerance"), (-1e-3, ValueError, "tolerance"),
    ("1e-3", TypeError, "tolerance must be a real"), (True, TypeError, "tolerance")])
def test_bad_tolerance(tolerance, error, match):
    with pytest.raises(error, match=match):
        cheapest_model(tolerance)


def test_bad_quantity_and_families():
    with pytest.raises(ValueError, match="quantity must be one of"):
        cheapest_model(1e-3, quantity="gains")
    with pytest.raises(ValueError, match="families must be a non-empty selection"):
        cheapest_model(1e-3, families=["fem"])
    with pytest.raises(ValueError, match="families"):
        cheapest_model(1e-3, families=[])
    with pytest.raises(TypeError, match="families must be a sequence"):
        cheapest_model(1e-3, families="rfem")
