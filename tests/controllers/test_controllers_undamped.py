"""Loop analysis on undamped flexible plants (free beams without damping)."""

import warnings

import numpy as np
import pytest

import controllers
from appendages import Beam
from spacecraft import Hub, Mount, Spacecraft


@pytest.fixture(scope="module")
def undamped_plant():
    rod = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)  # the paper's rod, no damping
    return Spacecraft(Hub(100.0, 50.0), [Mount(rod.truncated(8), (0.5, 0.0), 0.0)]).plant()


def test_margins_of_collocated_pd_on_undamped_modes(undamped_plant):
    # A PD on collocated theta/torque of an undamped structure is passive: the loop phase
    # stays within (-180, 0) deg, so no phase crossover exists (gain margin infinite); |1 + L|
    # stays finite and positive, its minimum near the rigid-body crossover. No grid point may
    # fall on an undamped pole (where L is infinite) and produce NaN.
    pd = controllers.pd(undamped_plant, natural_frequency=0.1, damping=0.7)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = controllers.margins(undamped_plant, pd)
    assert m.gain_margin == np.inf
    assert 0.5 < m.modulus_margin < 1.0
    # Rigid-body closed form: L = -(wn^2 + 2 j zeta wn w)/w^2 has |L| = 1 at
    # wc^2 = wn^2 (2 zeta^2 + sqrt(4 zeta^4 + 1)) and PM = atan(2 zeta wc/wn) = 65.16 deg for
    # zeta = 0.7; the flexible boom lowers it by about 1.5 deg (3 deg allowed).
    zeta = 0.7
    wc = np.sqrt(2 * zeta**2 + np.sqrt(4 * zeta**4 + 1))
    pm_rigid = np.degrees(np.arctan(2 * zeta * wc))
    assert pm_rigid == pytest.approx(65.16, abs=0.01)
    assert pm_rigid - 3.0 < m.phase_margin < pm_rigid
