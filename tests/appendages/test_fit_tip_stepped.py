"""Equivalent chains of beams with tip bodies and stepped beams (appendages.equivalence, fit3d).

The exact distributed models (TipBody, SteppedBeam) go through flexsat's fit of any appendage;
the independent reference is the planar FE boom of tests/support/fe_planar.py as modal data.
"""

from __future__ import annotations

import numpy as np
import pytest

import fe_planar
from appendages import Beam, ModalAppendage, SteppedBeam, TipBody, fit_chain, fit_chain_3d
from appendages.equivalence import criterion, fit_targets, is_uniform_beam, spectral_errors
from appendages.fit3d import motion_frequencies, rod_chain_frequencies

TIP = TipBody(5.0, 0.8, 0.3)  # kg, kg m^2, m beyond the end
SEGMENTS = [(3.0, 2.0e4, 4.0), (4.0, 6.0e3, 2.0)]  # length, EJ, rho*A from the root


def _stepped() -> SteppedBeam:
    return SteppedBeam([Beam(*s) for s in SEGMENTS], tip=TIP)


def _largest(errors: dict) -> dict:
    return {key: float(np.max(np.abs(value))) for key, value in errors.items()}


@pytest.mark.slow
def test_a_tip_body_is_kept_by_the_chain():
    beam = Beam(7.0, 6.0e3, 2.0, tip=TIP)
    assert not is_uniform_beam(beam)
    chain = fit_chain(beam, 3)
    assert chain.mass == pytest.approx(19.0, rel=1e-13)
    assert chain.center_of_mass == pytest.approx((14.0 * 3.5 + 5.0 * 7.3) / 19.0, rel=1e-12)
    assert chain.inertia == pytest.approx(beam.inertia, rel=1e-12)
    errors = _largest(spectral_errors(beam, chain))
    assert errors["poles"] < 2e-4 and max(errors["W1"], errors["W2"], errors["W4"]) < 0.03
    assert criterion(beam, chain).relative_differences["m"] == pytest.approx(0.0, abs=1e-13)


def test_a_zero_tip_body_keeps_the_uniform_fit():
    # A tip body of zero mass is the uniform beam: the same memoised fit, bit for bit.
    bare = Beam(7.0, 6.0e3, 2.0)
    null = Beam(7.0, 6.0e3, 2.0, tip=TipBody(0.0, 0.0))
    assert is_uniform_beam(null)
    a, b = fit_chain(bare, 3), fit_chain(null, 3)
    for name in ("lengths", "masses", "inertias", "hinge_stiffnesses", "com_offsets"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


@pytest.mark.slow
def test_stepped_beam_and_its_finite_element_modes_give_the_same_fit():
    # The exact stepped boom and its independent FE model (28 Hermite elements, every mode, as
    # modal data) have the same first poles and zeros to the FE's discretisation error (h^4 of
    # the Hermite cubic: 7e-6 on the third ones, 2e-7 on the first), so the fits' criteria are
    # the same and so are the chains' errors.
    stepped = _stepped()
    w, G, rigid, _ = fe_planar.cantilever_modal_data([s + (n,) for s, n in
                                                      zip(SEGMENTS, (12, 16))],
                                                     (TIP.mass, 0.8, 0.3))
    data = ModalAppendage(w, G, rigid, length=7.0)
    exact = fit_targets(stepped, 4)
    fe = fit_targets(data, 4)
    np.testing.assert_allclose(fe["targets"], exact["targets"], rtol=2e-5)
    for key in ("mass", "center", "inertia"):
        assert fe[key] == pytest.approx(exact[key], rel=1e-12)
    ours = _largest(spectral_errors(stepped, fit_chain(stepped, 4)))
    theirs = _largest(spectral_errors(data, fit_chain(data, 4)))
    for key in ours:
        assert ours[key] == pytest.approx(theirs[key], rel=1e-3, abs=1e-6)


@pytest.mark.slow
def test_three_axis_tube_with_a_tip_body():
    tip = TipBody(0.5, np.diag([0.002, 0.003, 0.004]), 0.05)
    tube = Beam.tube(4.0, 0.1, 0.002, 2700.0, 70e9, tip=tip)
    chain = fit_chain_3d(tube, 3)
    np.testing.assert_allclose(chain.inertia_tensor, tube.inertia_tensor, rtol=1e-9)
    assert chain.mass == pytest.approx(tube.mass, rel=1e-12)
    for plane in ("xy", "xz"):
        errors = _largest(spectral_errors(tube.planar_view(plane), chain.planar_view(plane)))
        assert errors["poles"] < 2e-4
    scale = float(tube.natural_frequencies(1)[0])
    rod = motion_frequencies(tube, 3, scale, 1.0)
    pole, _ = rod_chain_frequencies(chain.torsional_inertias, chain.torsion_stiffnesses)
    assert pole == pytest.approx(rod.free, rel=1e-10)
