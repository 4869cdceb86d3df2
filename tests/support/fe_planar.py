"""An independent planar finite-element model of a stepped boom with a tip body, and its modal data.

The test suite's reference for finite-element modal data (``appendages.ModalAppendage``): it
imports nothing from flexsat, so agreement is evidence. Only numpy and scipy.

Model
-----
Euler-Bernoulli bending in the x-y plane, Hermite cubic elements with consistent mass [1]_,
nodal degrees of freedom ``(v, theta)`` with ``theta = dv/dx`` (rotation about +z). A boom is a
list of segments ``(length [m], EI [N m^2], rho*A [kg/m], n_elements)`` from the root (node 0,
x = 0) outward; a tip body (mass m_t [kg], inertia J_t [kg m^2] about its own centre of mass,
centre at a distance e [m] beyond the free end along x) is rigidly fixed to the last node:
its centre moves by ``v + e theta``, so it adds ``m_t [[1, e], [e, e**2]] + diag(0, J_t)``.

Modal data of the boom clamped at the root
------------------------------------------
With D the rigid motion of every degree of freedom for a unit root translation along y
(``v = 1``, ``theta = 0``) and a unit root rotation (``v = x``, ``theta = 1``), the modal data
of the cantilever modes Phi (root degrees of freedom removed, ``Phi^T M Phi = I``) are
``rigid_mass = D^T M D`` and ``participation = Phi^T (M D)``.

Coupled with a hub
------------------
A rigid hub (mass m_h, inertia J_h about its centre of mass, coordinates y_h, theta_h) carries
the boom's root at a distance p along the hub's x axis with the boom along x: the root's
``(v, theta) = (y_h + p theta_h, theta_h)``. The motion along x (hub and boom together,
inextensible) is a rigid translation apart from the rest and is left out.

References
----------
.. [1] J. S. Przemieniecki, Theory of Matrix Structural Analysis, McGraw-Hill, 1968, ch. 5 and
   11 (Hermite beam stiffness and consistent mass matrices).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

__all__ = ["boom_matrices", "cantilever_modal_data", "coupled_frequencies", "node_positions"]


def _element(h: float, EI: float, rhoA: float):
    """Hermite element stiffness and consistent mass, dofs (v1, theta1, v2, theta2)."""
    K = EI / h**3 * np.array([[12.0, 6 * h, -12.0, 6 * h],
                              [6 * h, 4 * h**2, -6 * h, 2 * h**2],
                              [-12.0, -6 * h, 12.0, -6 * h],
                              [6 * h, 2 * h**2, -6 * h, 4 * h**2]])
    M = rhoA * h / 420.0 * np.array([[156.0, 22 * h, 54.0, -13 * h],
                                     [22 * h, 4 * h**2, 13 * h, -3 * h**2],
                                     [54.0, 13 * h, 156.0, -22 * h],
                                     [-13 * h, -3 * h**2, -22 * h, 4 * h**2]])
    return K, M


def node_positions(segments) -> np.ndarray:
    """x of every node [m], root first."""
    x = [0.0]
    for length, _, _, n_el in segments:
        x += list(x[-1] + length * np.arange(1, n_el + 1) / n_el)
    return np.array(x)


def boom_matrices(segments, tip=(0.0, 0.0, 0.0)):
    """Free boom's K, M (dense), dofs ``2 i`` (v) and ``2 i + 1`` (theta) of node i.

    Parameters
    ----------
    segments : sequence of (length, EI, rhoA, n_elements)
    tip : (mass, inertia, offset)
        The tip body at the last node (kg, kg m^2 about its centre, m beyond the end).
    """
    n_nodes = 1 + sum(s[3] for s in segments)
    K = np.zeros((2 * n_nodes, 2 * n_nodes))
    M = np.zeros_like(K)
    node = 0
    for length, EI, rhoA, n_el in segments:
        Ke, Me = _element(length / n_el, EI, rhoA)
        for _ in range(n_el):
            dofs = np.arange(2 * node, 2 * node + 4)
            K[np.ix_(dofs, dofs)] += Ke
            M[np.ix_(dofs, dofs)] += Me
            node += 1
    m_t, J_t, e = tip
    last = np.array([2 * node, 2 * node + 1])
    M[np.ix_(last, last)] += m_t * np.array([[1.0, e], [e, e**2]]) + np.diag([0.0, J_t])
    return K, M


def _rigid(segments) -> np.ndarray:
    x = node_positions(segments)
    D = np.zeros((2 * x.size, 2))
    D[0::2, 0] = 1.0
    D[0::2, 1] = x
    D[1::2, 1] = 1.0
    return D


def cantilever_modal_data(segments, tip=(0.0, 0.0, 0.0)):
    """(frequencies [rad/s], participation (n, 2), rigid_mass (2, 2), tip motion (n,)) of every
    cantilever mode of the boom (root clamped), ascending."""
    K, M = boom_matrices(segments, tip)
    D = _rigid(segments)
    inner = np.arange(2, K.shape[0])
    lam, Phi = scipy.linalg.eigh(K[np.ix_(inner, inner)], M[np.ix_(inner, inner)])
    G = Phi.T @ (M @ D)[inner]
    tip_motion = Phi[-2]  # v of the last node (the root's rigid motion is not in Phi)
    return np.sqrt(lam), G, D.T @ M @ D, tip_motion


def coupled_frequencies(segments, tip, hub_mass: float, hub_inertia: float,
                        position: float) -> np.ndarray:
    """Elastic natural frequencies [rad/s] of the hub carrying the boom (module docstring)."""
    K_b, M_b = boom_matrices(segments, tip)
    n_b = K_b.shape[0]
    n = 2 + n_b - 2
    T = np.zeros((n_b, n))  # boom dofs from (y_h, theta_h, inner boom dofs)
    T[0, 0], T[0, 1], T[1, 1] = 1.0, position, 1.0
    T[2:, 2:] = np.eye(n_b - 2)
    K = T.T @ K_b @ T
    M = T.T @ M_b @ T
    M[0, 0] += hub_mass
    M[1, 1] += hub_inertia
    lam = scipy.linalg.eigh(K, M, eigvals_only=True)
    return np.sqrt(np.sort(lam)[2:])  # the two rigid-body modes (y, theta) left out
