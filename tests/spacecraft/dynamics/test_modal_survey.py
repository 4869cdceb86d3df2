"""The modal survey of the open-loop spacecraft (spacecraft.dynamics.survey) and the report's
modal table.

References: the damped poles are the eigenvalues of the plant's own state matrix (the same
realisation: agreement to the eigensolver's error); the torque participations sum to a closed
form (the attitude response's high-frequency limit); a hub far heavier than its appendage sees
the appendage's cantilever modes with their entered damping (the damping convention).
"""

from __future__ import annotations

import numpy as np
import pytest

from appendages import Beam, HingedChain, TipBody
from spacecraft import Hub, Mount, Spacecraft
from spacecraft.dynamics.survey import modal_survey

ROD = dict(length=10.0, diameter=0.01, density=7800.0, youngs_modulus=2.06e11)


def _rod(zeta=0.005, **kw):
    return Beam.circular_rod(ROD["length"], ROD["diameter"], ROD["density"],
                             ROD["youngs_modulus"], damping_ratio=zeta, **kw)


def test_the_damped_poles_are_the_plants():
    craft = Spacecraft(Hub(100.0, 50.0), [Mount(_rod(tip=TipBody(0.5, 0.01)).truncated(8),
                                                (0.5, 0.0), 0.0, name="rod")])
    modes = modal_survey(craft)
    assert len(modes) == 8
    A = craft.plant().A
    poles = np.linalg.eigvals(A)
    poles = poles[poles.imag > 0]
    # the eigensolver's error on a matrix of norm ~ w_max**2: relative 1e-12 of the largest
    got = np.sort([m.frequency * complex(-m.damping_ratio, np.sqrt(1 - m.damping_ratio**2))
                   for m in modes], kind="stable")
    want = np.sort(poles, kind="stable")
    np.testing.assert_allclose(np.sort(np.abs(got)), np.sort(np.abs(want)), rtol=1e-10)
    np.testing.assert_allclose(np.sort(got.real), np.sort(want.real), rtol=1e-8,
                               atol=1e-12 * np.abs(want).max())


def test_torque_participations_sum_to_the_high_frequency_limit():
    """theta/torque = sum_k v_k,theta**2/(s**2 + ...) over every mode, rigid ones included: its
    s**2 limit is (M^-1)_theta,theta, the rigid part 1/J, so sum_elastic J v_theta**2 =
    J (M^-1)_theta,theta - 1."""
    craft = Spacecraft(Hub(100.0, 50.0), [
        Mount(_rod().truncated(6), (0.5, 0.0), 0.3, name="a"),
        Mount(HingedChain.rfem(_rod(), 4), (-0.4, 0.2), 2.5, name="b")])
    modes = modal_survey(craft)
    M = craft.second_order_model().mass
    expected = craft.inertia * np.linalg.inv(M)[2, 2] - 1.0
    total = sum(m.torque_participation[0] for m in modes)
    assert total == pytest.approx(expected, rel=1e-10)
    for m in modes:
        assert sum(m.strain_energy.values()) == pytest.approx(1.0, rel=1e-12)


def test_on_a_heavy_hub_the_first_mode_has_the_entered_damping():
    """The convention: the damping ratio of an appendage is that of its cantilever modes; a hub
    far heavier than the rod clamps it. The first coupled mode then has the entered ratio to
    O(J_rod / J_hub) (J_rod ~ 203 kg m^2 about the root, J_hub 1e6: ~2e-4 relative; the
    survey gives 1.2e-4)."""
    rod = _rod(0.005)
    for hub in (1e6, 1e8):
        craft = Spacecraft(Hub(hub, hub), [Mount(rod.truncated(12), (0.5, 0.0), 0.0)])
        first = modal_survey(craft, 1)[0]
        bound = 3.0 * rod.mass * rod.length**2 / 3.0 / hub
        assert first.damping_ratio == pytest.approx(0.005, rel=bound)
        assert first.frequency == pytest.approx(rod.cantilever_frequencies(1)[0], rel=bound)


def test_mirror_image_wings():
    """The symmetric mode of two mirror-image wings: no torque participation, equal shares."""
    wing = Beam.rectangular(6.0, 0.5, 0.02, 1600.0, 7e10, damping_ratio=0.005).truncated(4)
    craft = Spacecraft(Hub(500.0, 400.0), [Mount(wing, (1.0, 0.0), 0.0, name="px"),
                                            Mount(wing, (-1.0, 0.0), np.pi, name="mx")])
    first, second = modal_survey(craft, 2)
    # round-off of a mode that torque cannot excite: ~eps relative to the antisymmetric one
    assert first.torque_participation[0] < 1e-14 * second.torque_participation[0]
    for m in (first, second):
        assert m.strain_energy["px"] == pytest.approx(0.5, rel=1e-12)
    assert modal_survey(craft, 1)[0].as_dict()["frequency_hz"] == pytest.approx(
        first.frequency / (2 * np.pi), rel=1e-15)


def test_an_undamped_spacecraft_and_bad_arguments():
    craft = Spacecraft(Hub(100.0, 50.0), [Mount(_rod(0.0).truncated(3), (0.5, 0.0), 0.0)])
    for m in modal_survey(craft):
        assert m.damping_ratio == 0.0 and m.frequency == pytest.approx(m.undamped_frequency,
                                                                       rel=1e-12)
    with pytest.raises(ValueError, match="n_modes must be a positive integer"):
        modal_survey(craft, 0)
    with pytest.raises(TypeError, match="has no finite realisation"):
        modal_survey(Spacecraft(Hub(100.0, 50.0), [Mount(_rod(), (0.5, 0.0), 0.0)]))
