"""Tests of appendages.fitting beyond the public fit_chain (tests/test_equivalence.py): how
close the poles-and-zeros fit gets to the lowest cost its objective can reach."""

import pytest

from appendages import fitting


@pytest.mark.slow
def test_twelve_bodies_reach_the_modal_bound():
    """The fit's objective minimised over modal models (the 3 (n - 1) numbers a chain's W(s)
    depends on; ``modal_bound`` of benchmarks/bench_fit.py) is 3.457e-05 at 12 bodies
    (benchmarks/results/fit.md, printed to 4 digits); no chain near the fit does better. The
    fit along the first path alone ended 42 % above it (4.896e-05); with the second path it
    ends at the bound.  rtol 0.1 %: the bound's printed precision (4 digits) and the creep
    that stage 2's budget ends (module docstring: 2.4 % per 5 evaluations per parameter
    at the old end point, far less at the bound)."""
    fitting.clear_memo()
    chain = fitting.fit_poles_and_zeros(12)
    assert chain.cost == pytest.approx(3.457e-05, rel=1e-3)
    assert not chain.stopped


@pytest.mark.parametrize("n_bodies", [3, 7])
def test_fit_does_not_depend_on_the_memo(n_bodies):
    """A memoised fit and a fresh one are the same chain (the two paths from 7 bodies on are
    deterministic)."""
    first = fitting.fit_poles_and_zeros(n_bodies)
    fitting.clear_memo()
    second = fitting.fit_poles_and_zeros(n_bodies)
    assert second is not first
    for name in ("lengths", "masses", "inertias", "com_offsets", "hinge_stiffnesses"):
        assert (getattr(first, name) == getattr(second, name)).all()
