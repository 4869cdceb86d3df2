"""Chains of any uniform beam from one dimensionless fit (spacecraft/sweep/fits.py)."""
import math
import warnings

import numpy as np
import pytest

from appendages import Beam
from appendages.equivalence import fit_chain
from spacecraft.runner import RunStats, _Runner
from spacecraft.scene import load_scene
from spacecraft.sweep.fits import FitTemplates, scaled_chain, unit_fit, with_beam_damping

from test_sweep_parameters import scene

# (L [m], EJ [N m^2], rho [kg/m]): the paper's rod and two beams far from it
BEAMS = [(10.0, 2.06e11 * math.pi * 0.01**4 / 64, 7800.0 * math.pi * 0.01**2 / 4),
         (3.3, 1.0e5, 0.2), (25.0, 7.0e3, 1.7)]


def fresh(beam, n, match):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return fit_chain(beam, n, match=match)


def quantities(chain):
    """Poles and zeros of W1, W2, W4 (the two lowest of each) [rad/s]."""
    return np.concatenate([chain.poles()[:2]] + [chain.zeros(r)[:2] for r in (1, 2, 4)])


@pytest.mark.parametrize("n_bodies", [3, 4])
def test_scaled_unit_fit_obeys_the_scaling_law_exactly(n_bodies):
    unit = unit_fit(n_bodies, "frequencies")
    for L, EJ, rho in BEAMS:
        beam = Beam(L, EJ, rho)
        chain = scaled_chain(unit, beam)
        # m, J and L scale as rho L, rho L^3, L; frequencies as sqrt(EJ/(rho L^4)); only
        # the rounding of the scaled arrays and of the eigenvalue solver: 1e-12
        assert chain.mass == pytest.approx(unit.mass * rho * L, rel=1e-13)
        assert chain.inertia == pytest.approx(unit.inertia * rho * L**3, rel=1e-12)
        np.testing.assert_allclose(quantities(chain),
                                   quantities(unit) * math.sqrt(EJ / (rho * L**4)), rtol=1e-10)


@pytest.mark.parametrize("n_bodies", [3, 4])
def test_scaled_frequency_fit_equals_a_fresh_fit(n_bodies):
    """The paper's fit is determined (n - 1 equations, n - 1 unknowns): same chain to 1e-10
    (measured 1e-14: the solver's path differs by rounding only)."""
    unit = unit_fit(n_bodies, "frequencies")
    for L, EJ, rho in BEAMS:
        beam = Beam(L, EJ, rho)
        a, b = scaled_chain(unit, beam), fresh(beam, n_bodies, "frequencies")
        for name in ("lengths", "masses", "inertias", "hinge_stiffnesses", "com_offsets"):
            np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-10,
                                       err_msg=name)


@pytest.mark.slow
def test_scaled_poles_and_zeros_fit_matches_a_fresh_fit_in_what_it_fits():
    """flexsat's fit ends in a flat valley of its least squares: a fresh fit at another scale
    stops at other body masses (up to 1.2 % apart) with the same poles and zeros to the fit's
    tolerance (xtol = ftol = 1e-7 on log-frequency residuals: 1e-6 allowed), and the scaled
    chain's errors against the beam are the unit fit's exactly."""
    unit = unit_fit(3, "poles-and-zeros")
    errors = []
    for L, EJ, rho in BEAMS:
        beam = Beam(L, EJ, rho)
        a, b = scaled_chain(unit, beam), fresh(beam, 3, "poles-and-zeros")
        np.testing.assert_allclose(quantities(a), quantities(b), rtol=1e-6)
        assert a.mass == pytest.approx(b.mass, rel=1e-13)
        assert a.inertia == pytest.approx(b.inertia, rel=1e-12)
        targets = np.concatenate([beam.natural_frequencies(2)]
                                 + [beam.zeros(r, 2) for r in (1, 2, 4)])
        errors.append(quantities(a) / targets - 1.0)
    np.testing.assert_allclose(errors[1:], [errors[0]] * 2, rtol=0, atol=1e-12)


def test_templates_give_the_runners_damped_chain():
    """The damped chain of a scene's rod is the runner's (frequency fit: same to 1e-10)."""
    raw = scene()
    raw["appendages"][0]["fit"]["match"] = "frequencies"
    s = load_scene(raw)
    runner = _Runner(s, None, RunStats())
    expected = runner.fit(s.appendages[0], "frequencies")
    templates = FitTemplates()
    got = templates.chain(s.appendages[0].beam.build(), 3, "frequencies")
    for name in ("lengths", "masses", "inertias", "hinge_stiffnesses", "hinge_dampings"):
        np.testing.assert_allclose(getattr(got, name), getattr(expected, name), rtol=1e-10,
                                   err_msg=name)
    assert templates.keys() == [(3, "frequencies")]
    # the damping rule: hinge damping 2 zeta c / w1 gives the chain's first mode ratio ~ zeta
    undamped = with_beam_damping(got, 0.0)
    assert undamped is got
