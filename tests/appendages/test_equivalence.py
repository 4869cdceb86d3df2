"""Tests of appendages.equivalence: the paper's table, the criterion, and the chain fits.

The paper (PAPER.md) prints its numbers to 5 significant digits. Its inputs are printed to the
same precision (w1 = 2.8744, w2 = 7.9231 1/s; k_L = 0.26989, c = 37.134 N*m), and its w2 is not
the exact free-free frequency of its rod: Blevins' beta_2 L = 7.853204624 gives 7.92356 (the
ratio w2/w1 = (7.853204624/4.730040745)^2 = 2.756499 vs the paper's 7.9231/2.8744 = 2.756436,
independent of the rod's data). The table's zeros were evidently computed with the paper's
printed frequencies, so the reproduction below feeds them in; with them every number agrees
to within 0.55 of a unit in its last printed digit except n22 = n32 (one unit; no consistent set of
the paper's printed inputs reproduces its n22 to half a unit: the inputs' rounding alone moves
it by up to 1.2 units, computed in test_paper_table_chain_column).
"""

import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

from appendages import fitting
from appendages.beam import Beam
from appendages.chain import HingedChain
from appendages.equivalence import (EquivalenceResult, FitWarning, ModelQuantities, criterion,
                                    fit_chain, spectral_errors)
from appendages.interface import ConvergenceError, FiniteAppendage, RootModel

PAPER_FREQUENCIES = (2.8744, 7.9231)  # [1/s], as printed (PAPER.md)

# The paper's table, rows in its order: k1, k2 = k3, k4, n11, n21 = n31, n41, n12, n22 = n32, n42.
ROWS = ("k1", "k2 = k3", "k4", "n11", "n21 = n31", "n41", "n12", "n22 = n32", "n42")
PAPER_BEAM = (1.9588, -0.9145, 0.5639, 1.9965, 1.3322, 0.8793, 6.5858, 5.5945, 4.8272)
PAPER_CHAIN = (1.5814, -0.5647, 0.2627, 2.0583, 1.4653, 1.0524, 7.1097, 6.4729, 5.9092)
UNIT = 1e-4  # one unit in the last printed digit of every row above


@pytest.fixture(scope="module")
def rod():
    """The paper's rod: L = 10 m, d = 0.01 m, rho = 7800 kg/m^3, E = 2.06e11 N/m^2."""
    return Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)


@pytest.fixture(scope="module")
def fitted3(rod):
    return fit_chain(rod, 3)


class _Realisation(FiniteAppendage):
    """A FiniteAppendage around a given RootModel (to substitute modal frequencies)."""

    def __init__(self, root_model, like):
        self._rm, self.length, self.mass, self.inertia = (root_model, like.length, like.mass,
                                                          like.inertia)

    def _root_model(self):
        return self._rm


def two_mode_beam(rod, frequencies=None):
    """The paper's 2-mode free-free truncation, optionally with other modal frequencies
    (its root model has the modal stiffness diag(w^2) in the last two coordinates)."""
    model = rod.truncated(2, method="free-free")
    if frequencies is None:
        return model
    rm = model.root_model()
    K = rm.stiffness.copy()
    K[2:, 2:] = np.diag(np.square(frequencies))
    return _Realisation(RootModel(rm.mass, rm.damping, K, rm.tip, rm.coordinate_names), model)


def table_values(result: EquivalenceResult, column: str) -> np.ndarray:
    rows = {label: (ref, cand) for label, _, ref, cand, _ in result.rows()}
    index = 0 if column == "reference" else 1
    return np.array([rows[label][index] for label in ROWS])


# -- the paper's fit and table ------------------------------------------------------------------
def test_frequency_fit_reproduces_paper_parameters(rod):
    """k_L = 0.26989 and c = 37.134 N*m (PAPER.md), at half a unit of the printed digit."""
    chain = fit_chain(rod, 3, match="frequencies", frequencies=PAPER_FREQUENCIES)
    k_L = chain.lengths[1] / chain.length
    np.testing.assert_allclose(k_L, 0.26989, rtol=0, atol=0.5e-5)
    np.testing.assert_allclose(chain.hinge_stiffnesses, [37.134, 37.134], rtol=0, atol=0.5e-3)
    np.testing.assert_allclose(chain.poles(), PAPER_FREQUENCIES, rtol=1e-10)
    np.testing.assert_allclose(chain.lengths[0], chain.lengths[2], rtol=1e-14)


def test_frequency_fit_to_exact_beam(rod):
    """Against the exact frequencies 2.874459, 7.923556 the same fit gives k_L = 0.269877 and
    c = 37.1368 N*m: 2.7 and 5.5 half-units from the paper's, the effect of its low w2.
    The poles are matched to 1e-10; m, J, L are the rod's to round-off."""
    chain = fit_chain(rod, 3, match="frequencies")
    np.testing.assert_allclose(chain.poles(), rod.natural_frequencies(2), rtol=1e-10)
    np.testing.assert_allclose(chain.lengths[1] / 10.0, 0.269877, rtol=0, atol=1e-6)
    np.testing.assert_allclose(chain.hinge_stiffnesses[0], 37.1368, rtol=0, atol=1e-4)
    np.testing.assert_allclose([chain.mass, chain.inertia, chain.length],
                               [rod.mass, rod.inertia, rod.length], rtol=1e-13)


def test_paper_table_chain_column(rod):
    """The chain column, from the chain fitted to the paper's frequencies.

    Tolerance per number: half a unit in its last printed digit plus the change caused by
    rounding the paper's printed inputs w1, w2 (half a unit of 1e-4 each), computed here by
    refitting; that allowance is largest for the second zeros (0.4-1.2 units).
    """
    def values(frequencies):
        chain = fit_chain(rod, 3, match="frequencies", frequencies=frequencies)
        return table_values(criterion(two_mode_beam(rod), chain), "candidate")

    base = values(PAPER_FREQUENCIES)
    spread = np.zeros_like(base)
    for k in range(2):
        bumped = np.array(PAPER_FREQUENCIES)
        bumped[k] += 0.5e-4
        spread += np.abs(values(tuple(bumped)) - base)
    np.testing.assert_array_less(np.abs(base - PAPER_CHAIN), 0.5 * UNIT + spread)
    # and all but n22 = n32 at 0.55 units without any allowance
    close = np.abs(base - PAPER_CHAIN) < 0.55 * UNIT
    assert [label for label, ok in zip(ROWS, close) if not ok] in ([], ["n22 = n32"])


def test_paper_table_beam_column(rod):
    """The 2-mode beam column, from beam.truncated(2, "free-free") with the paper's printed
    frequencies: every number within 0.55 units of its last digit but n22 = n32, within 1.1
    (the module docstring explains the one-unit discrepancy)."""
    result = criterion(two_mode_beam(rod, PAPER_FREQUENCIES),
                       fit_chain(rod, 3, match="frequencies", frequencies=PAPER_FREQUENCIES))
    beam = table_values(result, "reference")
    deviation = np.abs(beam - PAPER_BEAM) / UNIT
    assert np.all(deviation < 1.1), dict(zip(ROWS, deviation))
    assert np.all(np.delete(deviation, ROWS.index("n22 = n32")) < 0.55), dict(zip(ROWS, deviation))


def test_paper_table_with_exact_frequencies(rod):
    """With the exact frequencies (the truncation as it is, the chain fitted to them) the
    gains and first zeros still agree within 0.8 units; the second zeros move by up to 4.2
    units, the effect of the paper's w2 being 4.6 units below the exact 7.92356 1/s."""
    result = criterion(two_mode_beam(rod), fit_chain(rod, 3, match="frequencies"))
    for column, paper in (("reference", PAPER_BEAM), ("candidate", PAPER_CHAIN)):
        deviation = np.abs(table_values(result, column) - paper) / UNIT
        assert np.all(deviation[:6] < 0.8) and np.all(deviation < 4.5), deviation


def test_paper_signs_and_condition_3(rod):
    """k1 > 0, k2 = k3 < 0, k4 > 0 for both models (DESIGN.md); m, J, L equal (condition (3)),
    relative differences of the frequencies below 1e-9 (they are matched)."""
    result = criterion(two_mode_beam(rod), fit_chain(rod, 3, match="frequencies"))
    for q in (result.reference, result.candidate):
        k1, k2, k3, k4 = q.gains
        assert k1 > 0 and k2 < 0 and k4 > 0 and k2 == k3
    for label in ("m", "J", "L"):
        # both models are built to the rod's m, J, L: sums of <= 4 positive terms of a few
        # products each, ~10 eps of exact; 450 eps leaves room for the fit's own rounding
        assert abs(result.relative_differences[label]) < 1e-13
    for label in ("w1", "w2"):
        assert abs(result.relative_differences[label]) < 1e-9


# -- criterion ----------------------------------------------------------------------------------
def test_criterion_against_exact_beam(rod):
    """With the distributed beam as reference the gains are not applicable and the zeros are the
    exact ones: pinned-free (tan x = tanh x), x = k pi and sliding-free (tan x = -tanh x) roots,
    n11 = 3.9266023120^2 s0, n21 = pi^2 s0, n41 = 2.3650203724^2 s0 with
    s0 = sqrt(EJ/(rho A L^4)) (roots from mpmath.findroot at 20 digits; rtol 1e-9)."""
    chain = HingedChain.rfem(rod, 5)
    result = criterion(rod, chain, names=("exact beam", "RFEM 5"))
    assert result.reference.gains is None and result.candidate.gains is not None
    s0 = np.sqrt(rod.bending_stiffness / (rod.linear_density * rod.length**4))
    np.testing.assert_allclose(result.reference.zeros[1][0], 3.9266023120**2 * s0, rtol=1e-9)
    np.testing.assert_allclose(result.reference.zeros[2][0], np.pi**2 * s0, rtol=1e-9)
    np.testing.assert_allclose(result.reference.zeros[4][0], 2.3650203724**2 * s0, rtol=1e-9)
    assert result.relative_differences["k1"] is None
    text = str(result)
    assert "exact beam" in text and "n/a" in text and "n22 = n32" in text
    markdown = result.to_markdown()
    assert "| k2 = k3 [1/(N*s^2)] | n/a |" in markdown
    json.dumps(result.to_dict())  # serialisable


def test_criterion_with_exact_column(rod):
    """exact=beam adds both models' differences from the exact beam: the same numbers as
    spectral_errors, zero for the truncation's poles, and the band errors. The differences
    are relative differences of frequencies, (w_chain - w_beam) / w_beam, each frequency
    right to ~1e-15 relative: they agree to that absolutely (atol 1e-14), not relative to
    themselves (rtol 1e-12 alone failed on one BLAS kernel for a difference of 2e-5 whose
    two computations were 3.6e-17 apart)."""
    chain = HingedChain.three_body(10.0, rod.mass, 0.26989, 37.134)
    result = criterion(two_mode_beam(rod), chain, exact=rod)
    errors = spectral_errors(rod, chain, 2)
    np.testing.assert_allclose([result.exact_differences["candidate"][label]
                                for label in ("n41", "n42", "w1", "w2")],
                               [*errors["W4"], *errors["poles"]], rtol=1e-12, atol=1e-14)
    assert abs(result.exact_differences["reference"]["w2"]) < 1e-12
    assert result.exact_differences["reference"]["k1"] is None
    assert result.exact_max_log_error.shape == (2, 4)
    assert "vs exact" in str(result) and "vs exact" in result.to_markdown()
    assert "exact_differences" in json.loads(json.dumps(result.to_dict()))
    with pytest.raises(TypeError, match="exact must be an appendage model"):
        criterion(rod, chain, exact="beam")


def test_criterion_of_a_model_with_itself_is_zero(rod):
    """Identical models: every relative difference is zero and the band errors are round-off
    (W is evaluated twice; threaded BLAS may sum in another order: 1e-15)."""
    chain = HingedChain.rfem(rod, 4)
    result = criterion(chain, chain)
    assert all(d == 0.0 for d in result.relative_differences.values())
    np.testing.assert_allclose(result.max_log_error, np.zeros(4), rtol=0, atol=1e-15)


def test_band_error_definition(rod):
    """max_log_error is max |ln(W_cand/W_ref)| on s = omega (zeta_e + i): recomputed by hand on
    the same grid (rtol 1e-12), W2 and W3 identical, and the default band stops below the exact
    beam's third W4 zero (1.21 w2): geometric mean of w2 and that zero."""
    chain = HingedChain.rfem(rod, 6)
    result = criterion(rod, chain, n_points=50, evaluation_damping=0.05)
    w = rod.natural_frequencies(2)
    third_w4_zero = rod.zeros(4, 3)[2]
    np.testing.assert_allclose(result.band, (w[0] / 10, np.sqrt(w[1] * third_w4_zero)),
                               rtol=1e-12)
    s = np.geomspace(*result.band, 50) * (0.05 + 1j)
    by_hand = np.abs(np.log(chain.W(s)[:, 0, 0] / rod.W(s)[:, 0, 0])).max()
    np.testing.assert_allclose(result.max_log_error[0], by_hand, rtol=1e-12)
    assert result.max_log_error[1] == result.max_log_error[2]
    assert np.all(result.rms_log_error <= result.max_log_error)


def test_band_error_decreases_with_rfem_refinement(rod):
    """RFEM chains converge to the beam, so their W_r error over a fixed band falls."""
    band = (0.3, 8.0)
    errors = [criterion(rod, HingedChain.rfem(rod, n), band=band).max_log_error
              for n in (4, 8, 16, 32)]
    assert np.all(np.diff(np.array(errors), axis=0) < 0)
    assert np.all(errors[-1] < 0.05)


def test_spectral_errors(rod):
    """Relative pole and zero errors: length n - 1 for a chain of n bodies; zero for the
    2-mode free-free truncation's poles (they are the exact ones, 1e-12)."""
    errors = spectral_errors(rod, HingedChain.rfem(rod, 5))
    assert set(errors) == {"poles", "W1", "W2", "W4"}
    assert all(e.shape == (4,) for e in errors.values())
    np.testing.assert_allclose(spectral_errors(rod, two_mode_beam(rod))["poles"], 0.0, atol=1e-12)
    with pytest.raises(ValueError, match="fewer than n = 6"):
        spectral_errors(rod, HingedChain.rfem(rod, 5), n=6)


# -- flexsat's fit ------------------------------------------------------------------------------
def max_error(rod, chain, n=None):
    return max(np.abs(e).max() for e in spectral_errors(rod, chain, n).values())


def test_fitted_chain_keeps_condition_3(rod, fitted3):
    """m, J, L and the centre of mass of the fitted chain equal the rod's (rtol 1e-13)."""
    np.testing.assert_allclose([fitted3.mass, fitted3.inertia, fitted3.length,
                                fitted3.center_of_mass],
                               [rod.mass, rod.inertia, rod.length, rod.length / 2], rtol=1e-13)
    assert fitted3.n_bodies == 3 and np.all(fitted3.masses > 0) and np.all(fitted3.inertias >= 0)


def test_fitted_three_body_chain_beats_the_paper_on_every_zero(rod, fitted3):
    """Against the exact beam, each of the six zeros n_r1, n_r2 (r = 1, 2, 4) of the fitted chain
    is closer than the paper's chain's; all its zeros are within 2 % (measured 1.7 %; the
    paper's chain is off by up to 52 %) and, with the default pole weight, its poles within
    2e-4 (measured 6e-5)."""
    paper = spectral_errors(rod, HingedChain.three_body(10.0, rod.mass, 0.26989, 37.134))
    ours = spectral_errors(rod, fitted3)
    for key in ("W1", "W2", "W4"):
        assert np.all(np.abs(ours[key]) < np.abs(paper[key])), key
    assert max_error(rod, fitted3) < 0.02
    assert np.abs(ours["poles"]).max() < 2e-4
    criterion_result = criterion(rod, fitted3)
    assert criterion_result.max_log_error.max() < criterion(
        rod, HingedChain.three_body(10.0, rod.mass, 0.26989, 37.134)).max_log_error.max()


@pytest.mark.parametrize("n_bodies", [4, 5])
def test_fitted_chains_beat_rfem_and_superelements(rod, n_bodies):
    """Fitted chains have smaller pole and zero errors than RFEM chains of the same size, both
    over all their n - 1 poles and zeros and over the paper's first two (and than superelement
    chains where the size matches: 2n + 1 bodies)."""
    fitted, rfem = fit_chain(rod, n_bodies), HingedChain.rfem(rod, n_bodies)
    assert max_error(rod, fitted) < max_error(rod, rfem)
    assert max_error(rod, fitted, 2) < max_error(rod, rfem, 2)
    if n_bodies % 2 == 1:
        superelements = HingedChain.superelements(rod, (n_bodies - 1) // 2)
        assert max_error(rod, fitted) < max_error(rod, superelements)


@pytest.mark.slow
@pytest.mark.parametrize("n_bodies", [7, 9])
def test_larger_fitted_chains_beat_rfem_and_superelements(rod, n_bodies):
    """As above for 8 and 10 degrees of freedom; the fitted errors also fall with size."""
    fitted, rfem = fit_chain(rod, n_bodies), HingedChain.rfem(rod, n_bodies)
    superelements = HingedChain.superelements(rod, (n_bodies - 1) // 2)
    for n in (None, 2):
        assert max_error(rod, fitted, n) < min(max_error(rod, rfem, n),
                                               max_error(rod, superelements, n))
    assert max_error(rod, fitted) < 0.01


def test_frequency_fit_for_more_bodies(rod):
    """match="frequencies" with n bodies matches n - 1 frequencies with a symmetric
    frozen-piece chain (rtol 1e-9)."""
    for n in (2, 4, 5):
        chain = fit_chain(rod, n, match="frequencies")
        np.testing.assert_allclose(chain.poles()[: n - 1], rod.natural_frequencies(n - 1),
                                   rtol=1e-9)
        np.testing.assert_allclose(chain.lengths, chain.lengths[::-1], rtol=1e-12)
        np.testing.assert_allclose(chain.inertia, rod.inertia, rtol=1e-13)


def test_fit_that_cannot_match_says_so(rod):
    """Two frequencies 0.1 % apart are out of reach of a symmetric three-body chain."""
    with pytest.raises(ConvergenceError, match="did not match the frequencies"):
        fit_chain(rod, 3, match="frequencies", frequencies=(1.0, 1.001))


def test_fit_budget_warns(rod):
    """A fit stopped by its evaluation budget warns and returns the best chain found, every
    time (also when the chain comes from the memo)."""
    for _ in range(2):
        with pytest.warns(FitWarning, match="stopped at max_nfev=3"):
            chain = fit_chain(rod, 4, max_nfev=3)
    # even an unfinished fit keeps condition (3) and the centre of mass (rtol 1e-13)
    np.testing.assert_allclose([chain.mass, chain.inertia, chain.length, chain.center_of_mass],
                               [rod.mass, rod.inertia, rod.length, 5.0], rtol=1e-13)


# -- the fit's machinery: exact Jacobian, scale invariance, memo, threads --------------------
# Beams of other sizes and materials (within the documented ranges): a 0.5 m light strip and a
# 40 m heavy boom, against the paper's 10 m steel rod.
OTHER_BEAMS = (Beam(0.5, 3.0e3, 0.02), Beam(40.0, 2.0e5, 8.0))


def in_beam_units(chain, beam) -> np.ndarray:
    """The chain's arrays in units of its beam: L, rho L, rho L**3, L and EJ/L."""
    L, EJ, rho = beam.length, beam.bending_stiffness, beam.linear_density
    return np.concatenate([chain.lengths / L, chain.masses / (rho * L),
                           chain.inertias / (rho * L**3), chain.com_offsets / L,
                           chain.hinge_stiffnesses / (EJ / L)])


@pytest.mark.parametrize("n_bodies", [3, 6])
def test_exact_jacobian_matches_central_differences(n_bodies):
    """The fit's Jacobian (eigenvalue perturbation through the mass layout, appendages.fitting)
    against central differences of its residuals, at the RFEM start and two seeded random
    points inside the bounds (no layout penalty). Step 1e-5: the truncation error
    h**2 |r'''|/6 and the round-off ~1e-13 |r|/h (eigenvalues of pencils conditioned O(10))
    are both near 1e-8 of the largest entry (measured: 2e-8 at most); a wrong term would be
    O(1e-2) or more."""
    layout = fitting._Layout(n_bodies)
    weights = np.concatenate([np.full(n_bodies - 1, 10.0), np.ones(3 * (n_bodies - 1))])
    problem = fitting._Problem(layout, weights)
    lo, hi = layout.bounds()
    rng = np.random.default_rng(7)
    points = [layout.from_arrays(*fitting._rfem_arrays(n_bodies))]
    while len(points) < 3:
        x = lo + (hi - lo) * (0.3 + 0.4 * rng.random(layout.size))
        if layout.arrays(x)[5] == 0.0 and \
                fitting._spectrum(layout.arrays(x), n_bodies - 1) is not None:
            points.append(x)
    h = 1e-5
    for x in points:
        J = problem.jacobian(x)
        differences = np.stack([(problem.residual(x + h * e) - problem.residual(x - h * e))
                                / (2 * h) for e in np.eye(x.size)], axis=1)
        np.testing.assert_allclose(J, differences, rtol=0, atol=1e-6 * np.abs(J).max())


@pytest.mark.parametrize("match", ["poles-and-zeros", "frequencies"])
def test_fits_of_different_beams_are_one_dimensionless_chain(rod, match):
    """Every length scales with L, mass with rho L, inertia with rho L**3, stiffness with EJ/L
    (appendages.fitting: the fit depends on the beam only through these units), so the chains
    of three different beams are one chain in beam units. Each value is one product and here
    one quotient by the same unit: two roundings, rtol 1e-15."""
    reference = in_beam_units(fit_chain(rod, 4, match=match), rod)
    for beam in OTHER_BEAMS:
        np.testing.assert_allclose(in_beam_units(fit_chain(beam, 4, match=match), beam),
                                   reference, rtol=1e-15, atol=0)


@pytest.mark.slow
def test_memoised_fit_equals_a_fresh_fit(rod):
    """The memo holds the dimensionless chain of (n_bodies, options): a fit of another beam
    served from it is bit for bit the chain that a fresh, unmemoised fit of that beam gives
    (the fresh fit computes the same dimensionless chain, deterministically on one BLAS
    thread, then the same products)."""
    beam = OTHER_BEAMS[1]
    fit_chain(rod, 5)
    hits = fitting._fit_poles_and_zeros.cache_info().hits
    memoised = fit_chain(beam, 5)
    assert fitting._fit_poles_and_zeros.cache_info().hits == hits + 1
    fitting.clear_memo()
    fresh = fit_chain(beam, 5)
    for name in ("lengths", "masses", "inertias", "com_offsets", "hinge_stiffnesses"):
        np.testing.assert_array_equal(getattr(memoised, name), getattr(fresh, name))
    # the options are part of the key: another pole weight is another fit
    assert not np.allclose(fit_chain(beam, 5, pole_weight=1.0).masses, fresh.masses)


@pytest.mark.slow
def test_scaled_chain_fits_its_own_beam(rod):
    """Why scaling is right: the rod's fitted chain has the rod's m, J, L and centre of mass
    (rtol 1e-13: sums of n products), and its poles and zeros divided by the rod's frequency
    scale sqrt(EJ/(rho L**4)) are those of the chain fitted to the unit beam
    (L = EJ = rho = 1), both from HingedChain's own eigen-solvers: rtol 1e-12 (each scaled
    entry of M and K is a few roundings off; the pencils' condition is below 1e3)."""
    unit = Beam(1.0, 1.0, 1.0)
    chain, unit_chain = fit_chain(rod, 6), fit_chain(unit, 6)
    np.testing.assert_allclose([chain.mass, chain.inertia, chain.length, chain.center_of_mass],
                               [rod.mass, rod.inertia, rod.length, rod.length / 2], rtol=1e-13)

    def spectrum(c):
        return np.concatenate([c.poles()] + [c.zeros(r) for r in (1, 2, 4)])

    np.testing.assert_allclose(spectrum(chain) / rod.frequency_scale, spectrum(unit_chain),
                               rtol=1e-12)


@pytest.mark.parametrize("match", ["poles-and-zeros", "frequencies"])
def test_fitted_chain_of_a_damped_beam_is_damped(rod, match):
    """A beam with modal damping ratio zeta (of its cantilever modes) gives hinge dampings
    2 zeta c_h / w_c1 as HingedChain.rfem does, w_c1 its first cantilever frequency:
    stiffness-proportional, so each mode of the chain has the damping ratio zeta w/w_c1 (zeta at
    the first cantilever mode); the free chain's first mode zeta w_1^chain/w_c1, with w_1^chain
    the beam's w_1 to the pole match (2e-4). The rest of the chain is the undamped beam's.
    (Before issue 10 the fitted chain of a damped beam was undamped; before issue 21 the ratio
    was matched at the first free-free frequency.)"""
    zeta = 0.01
    damped = Beam(rod.length, rod.bending_stiffness, rod.linear_density, damping_ratio=zeta)
    chain = fit_chain(damped, 4, match=match)
    w1, wc1 = rod.natural_frequencies(1)[0], rod.cantilever_frequencies(1)[0]
    np.testing.assert_allclose(chain.hinge_dampings, 2 * zeta * chain.hinge_stiffnesses / wc1,
                               rtol=1e-15)
    poles = np.linalg.eigvals(np.asarray(chain.state_space().A))
    oscillating = poles[poles.imag > 1e-9]
    first = oscillating[np.argmin(np.abs(oscillating))]
    np.testing.assert_allclose(-first.real / abs(first), zeta * w1 / wc1, rtol=2e-4)
    np.testing.assert_array_equal(in_beam_units(chain, damped),
                                  in_beam_units(fit_chain(rod, 4, match=match), rod))


_THREADS_WORKER = """
import hashlib, numpy as np
from appendages.beam import Beam
from appendages.equivalence import fit_chain
c = fit_chain(Beam(10.0, 101.12, 0.6126), 10)
print(hashlib.sha256(np.concatenate([c.lengths, c.masses, c.inertias, c.com_offsets,
                                     c.hinge_stiffnesses]).tobytes()).hexdigest())
"""


@pytest.mark.slow
def test_fitted_chain_independent_of_blas_threads():
    """The fit runs on one BLAS thread whatever the environment asks: the same chain, bit for
    bit, with OPENBLAS_NUM_THREADS unset, 1 and 4 (before issue 10 a 10-body fit with threads
    followed another path: 1401 against 1143 evaluations, another chain)."""
    root = pathlib.Path(__file__).resolve().parents[2]
    digests = set()
    for threads in (None, "1", "4"):
        environment = {key: value for key, value in os.environ.items()
                       if key not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS",
                                      "MKL_NUM_THREADS")}
        if threads is not None:
            environment["OPENBLAS_NUM_THREADS"] = environment["OMP_NUM_THREADS"] = threads
        environment["PYTHONPATH"] = str(root)
        done = subprocess.run([sys.executable, "-c", _THREADS_WORKER], cwd=root,
                              env=environment, capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr
        digests.add(done.stdout.strip())
    assert len(digests) == 1, digests


# -- bad input ----------------------------------------------------------------------------------
def test_bad_input(rod):
    chain = HingedChain.rfem(rod, 3)
    with pytest.raises(ValueError, match="match must be one of"):
        fit_chain(rod, 3, match="zeros")
    with pytest.raises(ValueError, match="n_bodies must be at least 2"):
        fit_chain(rod, 1)
    with pytest.raises(TypeError, match="n_bodies must be an integer"):
        fit_chain(rod, 3.0)
    with pytest.raises(ValueError, match=r"match='frequencies' .*needs a uniform Beam"):
        fit_chain(chain, 3, match="frequencies")  # any appendage: flexsat's fit only
    with pytest.raises(TypeError, match="beam must be an appendage model"):
        fit_chain("rod", 3)
    with pytest.raises(ValueError, match=r"frequencies must be 2 increasing positive values "
                                         r"\[rad/s\]"):
        fit_chain(rod, 3, match="frequencies", frequencies=(7.9, 2.8))
    with pytest.raises(ValueError, match=r"frequencies \[rad/s\] applies to match='frequencies'"):
        fit_chain(rod, 3, frequencies=(2.8, 7.9))
    with pytest.raises(ValueError, match=r"pole_weight must be finite and greater than 0.0"):
        fit_chain(rod, 3, pole_weight=-1.0)
    with pytest.raises(ValueError, match="max_nfev must be a positive integer"):
        fit_chain(rod, 3, max_nfev=0)
    with pytest.raises(TypeError, match="reference must be an appendage model"):
        criterion("beam", chain)
    with pytest.raises(TypeError, match="candidate must be an appendage model"):
        criterion(rod, 3.0)
    with pytest.raises(ValueError, match=r"band must be \(omega_min, omega_max\)"):
        criterion(rod, chain, band=(5.0, 1.0))
    with pytest.raises(ValueError, match="n_points must be at least 10"):
        criterion(rod, chain, n_points=3)
    with pytest.raises(ValueError, match=r"evaluation_damping must be finite and in \(0.0, 1.0\)"):
        criterion(rod, chain, evaluation_damping=0.0)
    with pytest.raises(ValueError, match="band must be given"):
        criterion(HingedChain.rfem(rod, 2), chain)


def test_model_quantities_of_hinged_root(rod):
    """A chain with a drive spring has no finite gains: ModelQuantities says so (None)."""
    rigid = HingedChain.rfem(rod, 3)
    hinged = HingedChain(rigid.lengths, rigid.masses, rigid.inertias,
                         np.concatenate([[100.0], rigid.hinge_stiffnesses]), root="hinged")
    q = ModelQuantities.of(hinged, "hinged")
    assert q.gains is None and q.poles[1] is not None


def test_fit_of_a_beam_whose_chains_leave_the_ranges_names_the_beam():
    """A 1 mm beam with EJ = 1e14 N m^2 is in range, but a chain of it needs hinges of
    EJ/H ~ 2e17 N*m/rad, beyond the documented range: the fit says so, naming fit_chain's
    arguments (before issue 9 it built the chain whatever the values)."""
    beam = Beam(1e-3, 1e14, 1e-8)
    for match in ("frequencies", "poles-and-zeros"):
        with pytest.raises(ValueError, match=r"fit_chain\(beam, n_bodies=3.*Beam\(length=0\.001.*"
                                             r"outside the documented ranges.*hinge"):
            fit_chain(beam, 3, match=match)
