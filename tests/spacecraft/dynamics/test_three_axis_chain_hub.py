"""Three-axis chains on a free-floating hub against the independent Lagrangian model
(issue 11, item 6): coupled frequencies of chains mounted anywhere in any orientation, and the
limiting cases, a huge hub (each chain clamped at its root, every motion) and a tiny hub (the
chain free-free).

Reference: tests/test_three_axis_chain.lagrangian_matrices (maximal coordinates, joints as
constraints, nothing shared with appendages.chain) assembled here with a rigid hub of six
coordinates (u_h, theta_h) about its centre of mass: the root frame of the chain on a mount at
p with orientation R moves with the hub, u_root = R^T (u_h + theta_h x p), theta_root =
R^T theta_h (small rotations), imposed as constraints. flexsat's frequencies come from the
Wittrick-Williams count on the 6 x 6 hub dynamic stiffness through each chain's W6 (exact=True)
and from its assembled eigenvalues (exact=False).
"""

import math

import numpy as np
import pytest
import scipy.linalg

from appendages import Beam, fit_chain_3d
from spacecraft import Hub, Mount, Spacecraft
from spacecraft.dynamics.kinematics import euler_orientation, orientation_from_axis
from chain3d_reference import cross, lagrangian_matrices, random_chain

RNG = np.random.default_rng(2024)
CHAIN = random_chain(RNG, 4, "rigid")
HINGED = random_chain(RNG, 3, "hinged")
R1 = euler_orientation("ZYX", (0.7, -0.4, 1.1))
R2 = orientation_from_axis((1.0, -0.5, -1.2))
P1, P2 = np.array([0.3, -0.2, 0.1]), np.array([-0.5, 0.4, -0.3])


def _undamped_frequencies(M, K, T, n_rigid):
    """Natural frequencies of (M, K) on the motions q = T z, the n_rigid zero ones left out.
    QZ of the reduced pencil: a massless coordinate (the root frame of a hinged chain that
    nothing holds) has an infinite eigenvalue, dropped; the problems here are small and well
    scaled."""
    lam = scipy.linalg.eigvals(T.T @ K @ T, T.T @ M @ T)
    lam = np.sort(np.abs(lam[np.isfinite(lam)]))
    return np.sqrt(lam[n_rigid:])


def lagrangian_spacecraft(hub_mass, hub_inertia, mounts):
    """Frequencies of a hub carrying chains, from the Lagrangian chain models: coordinates
    (u_h, theta_h), then each chain's maximal coordinates; its root frame tied to the hub."""
    blocks = [lagrangian_matrices(chain) for chain, _, _ in mounts]
    sizes = [M.shape[0] for M, _, _, _ in blocks]
    N = 6 + sum(sizes)
    M = np.zeros((N, N))
    K = np.zeros((N, N))
    M[:3, :3] = hub_mass * np.eye(3)
    M[3:6, 3:6] = hub_inertia
    constraints = []
    start = 6
    for (Mc, Kc, _, Tc), (chain, p, R), size in zip(blocks, mounts, sizes):
        block = slice(start, start + size)
        M[block, block] = Mc
        K[block, block] = Kc
        # the chain's own joints: q_c in the range of Tc, i.e. orthogonal to its complement
        complement = scipy.linalg.null_space(Tc.T)
        rows = np.zeros((complement.shape[1], N))
        rows[:, block] = complement.T
        constraints.append(rows)
        # root frame (its first six coordinates) = mount motion of the hub
        tie = np.zeros((6, N))
        tie[:, start:start + 6] = np.eye(6)
        tie[:3, :3] -= R.T
        tie[:3, 3:6] -= R.T @ (-cross(p))   # theta_h x p = -[p]x theta_h
        tie[3:, 3:6] -= R.T
        constraints.append(tie)
        start += size
    T = scipy.linalg.null_space(np.vstack(constraints))
    return _undamped_frequencies(M, K, T, 6)


def clamped_and_free(chain):
    """The chain's frequencies with its root frame held (clamped) and free (free-floating,
    six rigid modes out; a hinged root's joint then holds nothing), from the Lagrangian
    model."""
    M, K, _, T = lagrangian_matrices(chain)
    held = T @ scipy.linalg.null_space(T[:6])
    return _undamped_frequencies(M, K, held, 0), _undamped_frequencies(M, K, T, 6)


J_HUB = np.array([[9.5, 0.4, -0.3], [0.4, 7.8, 0.2], [-0.3, 0.2, 6.4]])


@pytest.mark.parametrize("exact", [True, False])
def test_chains_on_a_hub_against_the_lagrangian_spacecraft(exact):
    """Two chains (rigid and hinged root, every motion sprung) on a hub of comparable size,
    off its centre and turned off its axes: every coupled frequency to 1e-9 relative (the
    count's bisection and the eigensolvers, on matrices with condition ~1e4)."""
    mounts = [(CHAIN, P1, R1), (HINGED, P2, R2)]
    craft = Spacecraft(Hub(5.0, J_HUB), [Mount(c, p, orientation=R) for c, p, R in mounts])
    reference = lagrangian_spacecraft(5.0, J_HUB, mounts)
    n = reference.size
    # four sprung motions per joint (bending in two planes, torsion, axial)
    assert n == 4 * (CHAIN.n_bodies - 1) + 4 * HINGED.n_bodies
    np.testing.assert_allclose(craft.natural_frequencies(n, exact=exact), reference, rtol=1e-9)


def test_huge_hub_gives_each_motions_clamped_chain_frequencies():
    """Hub 1e12 kg and kg m^2 (chains of a few kg): the root does not move; the coupled
    frequencies are the union of both chains' clamped ones (bending in both planes, torsion,
    axial), to ~m_chain/m_hub = 1e-12 (1e-9 for the count)."""
    mounts = [(CHAIN, P1, R1), (HINGED, P2, R2)]
    craft = Spacecraft(Hub(1e12, 1e12 * np.eye(3)),
                       [Mount(c, p, orientation=R) for c, p, R in mounts])
    clamped = np.sort(np.concatenate([clamped_and_free(c)[0] for c, _, _ in mounts]))
    np.testing.assert_allclose(craft.natural_frequencies(clamped.size), clamped, rtol=1e-9)


@pytest.mark.parametrize("chain", [CHAIN, HINGED], ids=["rigid_root", "hinged_root"])
def test_tiny_hub_gives_the_chains_free_free_frequencies(chain):
    """Hub 1e-12 kg and kg m^2 carrying one chain off its centre: the chain floats free; the
    coupled frequencies are its free-free ones (six rigid modes out), to ~1e-12 (1e-9)."""
    craft = Spacecraft(Hub(1e-12, 1e-12 * np.eye(3)), [Mount(chain, P1, orientation=R1)])
    free = clamped_and_free(chain)[1]
    np.testing.assert_allclose(craft.natural_frequencies(free.size), free, rtol=1e-9)


def test_fitted_wing_chains_on_the_example_hub():
    """The 3-D chains fitted to the example's rectangular wing, on its 820 kg hub at a cant
    angle: coupled frequencies equal to the Lagrangian spacecraft's, 1e-9."""
    wing = fit_chain_3d(Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8), 3)
    J = np.array([[950.0, 12.0, -8.0], [12.0, 780.0, 15.0], [-8.0, 15.0, 640.0]])
    mounts = [(wing, np.array([0.0, 1.1, 0.0]),
               euler_orientation("ZYX", (math.pi / 2, 0.0, math.radians(20.0)))),
              (wing, np.array([0.0, -1.1, 0.0]),
               euler_orientation("ZYX", (-math.pi / 2, 0.0, math.radians(20.0))))]
    craft = Spacecraft(Hub(820.0, J), [Mount(c, p, orientation=R) for c, p, R in mounts])
    reference = lagrangian_spacecraft(820.0, J, mounts)
    np.testing.assert_allclose(craft.natural_frequencies(reference.size), reference, rtol=1e-9)
