"""Margins of a delayed loop with the delay's phase resolved only where |L| can lower them
(controllers.margins.harmless_gain): the same margins as resolving it everywhere, never above an
independent dense scan, and a delay far beyond the delay margin is a result.

Tolerances. The full resolution (the delay's phase resolved wherever |L| >= 1e-9) and the
restricted one find the same crossings and dips, each refined on the exact L to ~1e-13 relative
in frequency: margins agree to 1e-9 relative (1e-9 dB / deg absolute where they vanish). The
dense scan steps omega tau by pi/32 and 1/200 of each mode's half-power band, so its minimum of
|1 + L| is above the refined one by at most the curvature over half a step (< 1e-3 relative);
the margins must not exceed it by more than 1e-9 relative (a margin above a sampled value would be
optimistic).
"""
import importlib
import math

import numpy as np
import pytest

import controllers
from plants import modal_plant

# delays of seconds on purpose (the slow loops' delay margins): not the unit slip they are
# warned about as (tests/controllers/test_delay_unit_slip.py)
pytestmark = pytest.mark.filterwarnings("ignore::controllers.LongDelayWarning")

margins_module = importlib.import_module("controllers.margins")

J = 250.0


def random_loop(seed):
    """A rigid hub with 2..4 lightly damped collocated and non-collocated modes and a PD."""
    rng = np.random.default_rng(seed)
    modes = []
    for k in range(rng.integers(2, 5)):
        w = float(rng.uniform(1.0, 60.0))
        zeta = float(10 ** rng.uniform(-3.5, -2.0))
        b = float(rng.uniform(0.005, 0.05))
        c = b * float(rng.choice([1.0, -0.5]))
        modes.append((w, zeta, b, c))
    plant = modal_plant(J, modes)
    design = modal_plant(J, modes[:1])
    pd = controllers.pd(design, natural_frequency=float(rng.uniform(0.2, 0.6)), roll_off=3.0)
    return plant, pd, modes


def dense_scan(plant, controller, tau, modes, top):
    """min |1 + L| and the |L| at every sign change of Im L with Re L < 0, by a dense scan."""
    parts = [np.geomspace(1e-4, top, 20001), np.arange(1e-4, top, 0.125 * math.pi / tau / 4)]
    for w, zeta, _, _ in modes:
        parts.append(w + np.linspace(-20, 20, 8001) * zeta * w)
    omega = np.unique(np.concatenate(parts))
    omega = omega[(omega > 0) & (omega <= top)]
    _, L = controllers.loop_frequency_response(plant, controller, omega, delay=tau)
    change = np.flatnonzero((np.sign(L.imag[:-1]) != np.sign(L.imag[1:]))
                            & (L.real[:-1] < 0) & (L.real[1:] < 0))
    gains = np.maximum(np.abs(L[change]), np.abs(L[change + 1]))
    return np.min(np.abs(1 + L)), gains


@pytest.mark.parametrize("seed", range(6))
def test_delayed_margins_are_never_above_a_dense_scan(seed):
    plant, pd, modes = random_loop(seed)
    tau = float(np.random.default_rng(100 + seed).uniform(0.02, 0.5))
    m = controllers.margins(plant, pd, delay=tau)
    top = 3.0 * max(w for w, *_ in modes)
    scan_min, gains = dense_scan(plant, pd, tau, modes, top)
    assert m.modulus_margin <= scan_min * (1 + 1e-9)
    # a sampled phase crossover at |L| = g (to within the scan's step) gives a margin of
    # 20 log10(1/g) dB: the reported one, the closest to 0 dB, is no farther from 0 dB
    relevant = gains[gains > 1e-6]
    if relevant.size:
        sampled = np.min(np.abs(20 * np.log10(relevant)))
        assert abs(m.gain_margin) <= sampled + 0.02   # the scan's |L| between two samples


@pytest.mark.parametrize("seed", range(3))
@pytest.mark.parametrize("tau", [0.05, 0.4])
def test_restricted_resolution_equals_the_full_one(seed, tau, monkeypatch):
    plant, pd, _ = random_loop(seed)
    fast = controllers.margins(plant, pd, delay=tau)
    monkeypatch.setattr(margins_module, "harmless_gain", lambda *args: 0.0)
    full = controllers.margins(plant, pd, delay=tau)
    for key in ("gain_margin", "phase_margin", "modulus_margin", "delay_margin"):
        a, b = getattr(fast, key), getattr(full, key)
        if math.isinf(b):
            assert a == b, key
        else:
            assert a == pytest.approx(b, rel=1e-9, abs=1e-9), key


def test_stiff_lightly_damped_modes_with_a_long_delay_are_a_result():
    # stiff modes far above the crossover (3e3..3e4 rad/s): resolving e^(-j omega tau) up to
    # the grid's top would take millions of frequencies; the margins need it nowhere there
    modes = [(3e3, 0.001, 0.02, 0.02), (9e3, 0.001, 0.01, 0.01), (2.8e4, 0.0005, 0.01, 0.01)]
    plant = modal_plant(J, modes)
    pd = controllers.pd(modal_plant(J), natural_frequency=0.3, roll_off=3.0)
    for tau in (0.1, 0.3, 3.0):
        m = controllers.margins(plant, pd, delay=tau)
        free = controllers.margins(plant, pd)
        # one gain crossover: PM(tau) = PM(0) - omega_c tau, wrapped to (-180, 180]
        assert m.gain_crossover_frequency == pytest.approx(free.gain_crossover_frequency,
                                                           rel=1e-9)
        expected = (free.phase_margin - math.degrees(free.gain_crossover_frequency * tau)
                    + 180.0) % 360.0 - 180.0
        assert m.phase_margin == pytest.approx(expected, abs=1e-6)
        assert math.isfinite(m.modulus_margin) and m.modulus_margin <= 1.0


def test_a_delay_far_beyond_the_margin_is_a_result():
    plant, pd, _ = random_loop(0)
    v = controllers.spillover(plant, pd, delay=1e3)
    assert not v.stable and v.margins.delay_margin < 0
    m = controllers.margins(plant, pd, delay=1e3)
    assert m.delay == 1e3 and math.isfinite(m.modulus_margin)


def test_harmless_gain_bounds():
    planar = controllers.Margins(gain_margin=20.0, phase_margin=40.0, modulus_margin=0.6,
                                 gain_crossover_frequency=1.0, phase_crossover_frequency=2.0,
                                 modulus_margin_frequency=1.5)
    # a phase crossover below |L| = 0.1 (GM 20 dB) or a dip where |L| < 0.4 changes nothing
    assert margins_module.harmless_gain(planar) == pytest.approx(0.1, rel=1e-12)
    assert margins_module.harmless_gain(
        controllers.Margins(math.inf, 40.0, 1.0, 1.0, math.inf, 1.0)) == 0.0
    multi = controllers.MultiLoopMargins({a: planar for a in "xyz"}, 0.5, 1.0, 1.0, 1.0, 0.6, 1.0)
    g = margins_module.harmless_gain(multi, 3)
    # the bound's chain: a = 3 g >= sigma_max(L), e = a/(1 - a), |L_i| <= e/(1 - e) <= 0.1
    a = 3 * g
    e = a / (1 - a)
    assert e / (1 - e) <= 0.1 * (1 + 1e-12) and 0.5 + e <= 1 / 0.5 and 1 - a >= 0.6
    assert g > 0


def test_a_grid_too_large_names_the_delay_and_what_would_do():
    # |L| = 0.5 up to 1e9 rad/s: the delay's phase matters everywhere, 1 s of it would need
    # ~4e8 points
    def flat(w):
        return np.full(np.size(w), -0.5 + 0j)

    with pytest.raises(ValueError, match=r"controller\.delay = 1 s .* below about [0-9.e+-]+ s"):
        controllers.loop_margins(flat, np.array([1.0, 1e9]), delay=1.0)
