"""An independent Lagrangian model of a three-axis hinged chain, the reference of the 3-D
chain tests.

It shares nothing with appendages.chain: every body has six coordinates (centre-of-mass
translation and small rotation vector, 3-D), joints are linear constraints between the bodies'
points (``p = r + theta x d``) and springs on the relative rotations (and axial separations),
and the root motions come from the null space of the constraints. No decoupling of the motions
is assumed; the theta_y = -dw/dx sign comes out of the cross products.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

from appendages import HingedChain

__all__ = ["cross", "lagrangian_matrices", "random_chain"]


def cross(v):
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def lagrangian_matrices(chain):
    """Mass, stiffness and damping matrices of a linear 3-D chain in maximal coordinates, and
    an orthonormal basis T of the motions its joints allow (q = T z).

    Coordinates: root frame (u0, theta0), then each body's (r_k, theta_k); body k's point at
    distance d from its start is ``r_k + theta_k x ((d - a_k) e_x)``. Joint h (between the
    root frame and body 1 for a hinged root, else between bodies) holds the transverse
    separation of the two points at zero, springs (or holds) the axial separation and the
    relative rotation about x, and springs the relative rotations about y and z.
    """
    n = chain.n_bodies
    N = 6 + 6 * n
    M = np.zeros((N, N))
    K = np.zeros((N, N))
    C = np.zeros((N, N))
    ex = np.array([1.0, 0.0, 0.0])
    for k in range(n):
        r, th = 6 + 6 * k, 9 + 6 * k
        M[r:r + 3, r:r + 3] = chain.masses[k] * np.eye(3)
        M[th:th + 3, th:th + 3] = np.diag([chain.torsional_inertias[k], chain.inertias_y[k],
                                           chain.inertias[k]])

    def point(k, d):
        """3 x N map to the displacement of body k's point at d from its start."""
        P = np.zeros((3, N))
        P[:, 6 + 6 * k: 9 + 6 * k] = np.eye(3)
        P[:, 9 + 6 * k: 12 + 6 * k] = -cross((d - chain.com_offsets[k]) * ex)
        return P

    def rotation(k):
        R = np.zeros((3, N))
        R[:, 9 + 6 * k: 12 + 6 * k] = np.eye(3) if k >= 0 else 0.0
        return R

    root_u = np.zeros((3, N))
    root_u[:, 0:3] = np.eye(3)
    root_t = np.zeros((3, N))
    root_t[:, 3:6] = np.eye(3)
    constraints = []

    def joint(separation, relative, h):
        """Add joint h: separation (3 x N), relative rotation (3 x N)."""
        constraints.extend([separation[1], separation[2]])
        springs = [(None if chain.torsion_stiffnesses is None else chain.torsion_stiffnesses[h],
                    None if chain.torsion_dampings is None else chain.torsion_dampings[h],
                    relative[0]),
                   (chain.hinge_stiffnesses_y[h], chain.hinge_dampings_y[h], relative[1]),
                   (chain.hinge_stiffnesses[h], chain.hinge_dampings[h], relative[2]),
                   (None if chain.axial_stiffnesses is None else chain.axial_stiffnesses[h],
                    None if chain.axial_dampings is None else chain.axial_dampings[h],
                    separation[0])]
        for stiffness, damping, row in springs:
            if stiffness is None:
                constraints.append(row)
            else:
                K[:] += stiffness * np.outer(row, row)
                C[:] += (damping or 0.0) * np.outer(row, row)

    hinged = chain.root == "hinged"
    if hinged:
        joint(point(0, 0.0) - root_u, rotation(0) - root_t, 0)
    else:
        constraints.extend(list(point(0, 0.0) - root_u) + list(rotation(0) - root_t))
    for k in range(n - 1):
        joint(point(k, chain.lengths[k]) - point(k + 1, 0.0), rotation(k + 1) - rotation(k),
              k + 1 if hinged else k)
    return M, K, C, scipy.linalg.null_space(np.array(constraints))


def random_chain(rng, n, root, *, axial=True, torsion=True, damped=False):
    h = n - 1 if root == "rigid" else n
    dampings = (lambda: rng.uniform(0.0, 0.3, h)) if damped else (lambda: None)
    return HingedChain(rng.uniform(0.3, 1.5, n), rng.uniform(0.5, 2.0, n),
                       rng.uniform(0.05, 0.3, n), rng.uniform(10.0, 40.0, h),
                       hinge_dampings=dampings(), com_offsets=None, root=root,
                       inertias_y=rng.uniform(0.05, 0.3, n),
                       hinge_stiffnesses_y=rng.uniform(20.0, 80.0, h),
                       hinge_dampings_y=dampings(),
                       torsional_inertias=rng.uniform(0.01, 0.05, n),
                       torsion_stiffnesses=rng.uniform(3.0, 9.0, h) if torsion else None,
                       torsion_dampings=dampings() if torsion else None,
                       axial_stiffnesses=rng.uniform(500.0, 900.0, h) if axial else None,
                       axial_dampings=dampings() if axial else None)
