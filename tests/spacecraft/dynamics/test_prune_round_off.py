"""Which modes a plant keeps, and where its unreached poles sit, do not depend on rounding.

Two exact zeros that round-off used to blur, so that another CPU's BLAS kernel could decide a
model's size and a loop's status:

- twin solar-array wings: the antisymmetric torsion modes are not driven by a hub torque, by
  symmetry, yet the computed modes give them a drive of about 1e-11 of their twins' (the
  eigenvector round-off eps ||K|| / gap). ``plant(prune=True)`` kept or dropped them depending on
  the kernel, so the tolerance-driven fidelity compared closed loops with and without their
  poles and stopped at another number of modes on another CPU. The decision is now taken
  against the round-off bound (:func:`spacecraft.dynamics.coupling._mode_mixing` x
  ``PRUNE_SAFETY``): checked here by mixing the computed modes at that level and rebuilding.
- a translation of the free spacecraft has no rotation of the hub: exactly (the hub block of
  the rigid modes is the identity), so a translation, an undriven double integrator of the
  attitude loop when the scene has force disturbances, keeps its poles exactly at 0; a coupling
  of 1e-20 split them into +-1e-8 1/s, a growing pole that the loop's status read as unstable.
"""

from __future__ import annotations

import numpy as np
import pytest

import controllers
from appendages import Beam
from spacecraft import Mount, Spacecraft
from spacecraft.dynamics.coupling import PRUNE_SAFETY

from spacecraft_models import twin_wings

EPS = np.finfo(float).eps


def mixed_modes(craft: Spacecraft, level: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The craft's modes with each elastic one mixed with the others at ``level`` x the round-off
    bound eps ||K|| / |lam_i - lam_j| (random signs), as another kernel's solver might return
    them; the rigid modes (exact by construction) as they are."""
    w, V = craft.modes()
    lam = w ** 2
    r = craft.n_rigid
    gap = np.abs(lam[:, None] - lam[None, :])
    with np.errstate(divide="ignore"):
        theta = np.where(gap > 1e4 * EPS * lam.max(), EPS * lam.max() / np.where(gap > 0, gap, 1), 0)
    rng = np.random.default_rng(seed)
    theta = level * theta * rng.uniform(-1.0, 1.0, theta.shape)
    theta = 0.5 * (theta - theta.T)          # a rotation to first order: V stays M-orthonormal
    theta[:r, :] = 0.0
    theta[:, :r] = 0.0
    return w, V @ (np.eye(w.size) + theta)


@pytest.mark.parametrize("n_modes", [1, 2, 3])
def test_twin_wings_keep_the_same_modes_whatever_the_round_off(n_modes):
    """Mixing the computed modes at up to the round-off bound (both directions, five draws)
    leaves the pruned plant's modes as they are, and the twins' antisymmetric torsion modes
    (tip twist of the wings, undriven by symmetry) are never kept: the drive they get from
    round-off is below PRUNE_SAFETY times the bound."""
    craft = twin_wings(n_modes)
    signals = dict(tip_deflection=True, prune=True)
    kept = list(craft.plant(**signals).state_labels)
    for seed in range(5):
        other = twin_wings(n_modes)
        other._cache["modes"] = mixed_modes(craft, 1.0, seed)
        assert list(other.plant(**signals).state_labels) == kept, seed
    # the modes left out are exactly those no torque drives (by symmetry) or no output sees:
    # the input-output behaviour of the pruned plant is the full one's
    full, pruned = craft.plant(tip_deflection=True), craft.plant(**signals)
    assert pruned.nstates < full.nstates
    omega = np.geomspace(0.05, 500.0, 400)
    H_full = full(1j * omega)
    H_pruned = pruned(1j * omega)
    scale = np.abs(H_full).max(axis=-1, keepdims=True)
    # round-off of the left-out modes' contributions: their drive is below PRUNE_SAFETY x the
    # bound (~1e-8 of the largest here) times their sight, amplified at most 1/(2 zeta) = 100
    np.testing.assert_allclose(H_pruned, H_full, rtol=0, atol=1e-9 * scale.max())


def test_a_mode_driven_well_above_round_off_is_kept():
    """The bound is a floor, not a filter of weak modes: with the right wing 1 % stiffer than
    the left (its antisymmetric modes now driven for real, at about 1e-3 of the symmetric
    ones') the pruned plant keeps more modes than with twins, and has the full plant's
    input-output behaviour."""
    twins, uneven = twin_wings(2), twin_wings(2, youngs_right=7.07e8)
    assert uneven.plant(prune=True).nstates > twins.plant(prune=True).nstates
    omega = np.geomspace(0.05, 500.0, 400)
    H_full, H_pruned = uneven.plant()(1j * omega), uneven.plant(prune=True)(1j * omega)
    np.testing.assert_allclose(H_pruned, H_full, rtol=0, atol=1e-9 * np.abs(H_full).max())
    assert PRUNE_SAFETY <= 100.0   # a drive within it of round-off has under two true digits


@pytest.fixture(scope="module")
def chains_with_translations():
    """The example layout's left wing and boom (no twins: every elastic mode is driven), each a
    3-body 3-D chain fitted on poles and zeros, and its plant with force disturbances, not
    pruned (so with the translations)."""
    from appendages.fit3d import fit_chain_3d

    left, _, boom = twin_wings(1).mounts
    craft = Spacecraft(twin_wings(1).hub, [
        Mount(fit_chain_3d(Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8), 3), left.position,
              orientation=left.orientation, name=left.name),
        Mount(fit_chain_3d(Beam.tube(4.0, 0.05, 0.001, 1600.0, 1.2e11), 3), boom.position,
              orientation=boom.orientation, name=boom.name)])
    return craft, craft.plant(disturbances=True)


@pytest.mark.parametrize("sample_time", [None, 0.1])
def test_translations_keep_their_poles_at_zero_in_the_attitude_loop(chains_with_translations,
                                                                   sample_time):
    """With force disturbances the unpruned plant keeps the translations: double integrators
    no torque drives and no output sees (pruning leaves them out: checked too). The hub block of the rigid modes is the identity
    exactly (the chains' modes gave it 2e-19 off the diagonal), so the loop leaves them exactly
    alone: their six poles stay at s = 0 (within 1e-12), never a round-off pair of about
    +-sqrt(eps) / T that a 10 Hz LQR loop's status read as a growing mode."""
    craft, plant = chains_with_translations
    _, V = craft.modes()
    assert np.all(V[3:6, :3] == 0.0)       # hub rotation of each translation
    assert {"mode[0]", "mode[1]", "mode[2]"} <= set(plant.state_labels)
    assert not {"mode[0]", "mode[1]", "mode[2]"} & set(
        craft.plant(disturbances=True, prune=True).state_labels)
    J = controllers.rigid_body_inertia(plant)
    j, _ = controllers.principal_axes(J)
    K = controllers.lqr(plant, attitude_weight=(j * 0.1 ** 2) ** 2, rate_weight=0.0,
                        torque_weight=1.0, sample_time=sample_time)
    poles = controllers.stability.continuous_poles(controllers.close_loop(plant, K))
    slow = np.sort(np.abs(poles))[:6]
    assert np.all(slow <= 1e-12), slow
    assert np.all(poles.real <= 1e-10 * np.maximum(1.0, np.abs(poles)))
