"""Hand-built test plants with the controllers' signal conventions (shared by the test files)."""

import control
import numpy as np
import scipy.linalg

__all__ = ["modal_plant", "three_axis_plant", "embedded_planar_plant"]


def modal_plant(inertia, modes=(), *, tips=(), disturbance=True):
    """Hub + flexible modes in modal form, with named signals.

    theta/torque = 1/(J s^2) + sum_k b_k c_k / (s^2 + 2 zeta_k w_k s + w_k^2), omega = s theta.

    Parameters
    ----------
    inertia : float, kg*m**2
    modes : sequence of (w_k [rad/s], zeta_k, b_k, c_k)
        b_k = c_k is a collocated (hub-measured) mode.
    tips : sequence of (name, [d_k per mode])
        Tip-deflection outputs sum_k d_k q_k [m].
    disturbance : bool
        Also an input 'disturbance_torque' acting like 'torque'.
    """
    n = 2 + 2 * len(modes)
    A = np.zeros((n, n))
    B = np.zeros((n, 1))
    C = np.zeros((2 + len(tips), n))
    A[0, 1] = 1.0
    B[1, 0] = 1.0 / inertia
    C[0, 0] = C[1, 1] = 1.0
    for k, (w, zeta, b, c) in enumerate(modes):
        i = 2 + 2 * k
        A[i, i + 1] = 1.0
        A[i + 1, i] = -w * w
        A[i + 1, i + 1] = -2.0 * zeta * w
        B[i + 1, 0] = b
        C[0, i] = c
        C[1, i + 1] = c
        for j, (_, d) in enumerate(tips):
            C[2 + j, i] = d[k]
    inputs = ["torque", "disturbance_torque"] if disturbance else ["torque"]
    return control.ss(A, np.hstack([B, B]) if disturbance else B, C, 0.0, inputs=inputs,
                      outputs=["theta", "omega"] + [name for name, _ in tips])


AXES = ("x", "y", "z")


def three_axis_plant(inertia, modes=(), *, tips=(), disturbance=False):
    """Rigid hub with a full 3 x 3 inertia plus flexible modes, in modal form, with the
    three-axis signal names (inputs torque_x, torque_y, torque_z; outputs theta_x..z,
    omega_x..z, then the tips).

    theta/torque = J^-1 / s^2 + sum_k b_k c_k^T / (s^2 + 2 zeta_k w_k s + w_k^2), omega = s theta
    (3 x 3). The rigid block is written in principal coordinates, J = R diag(j) R^T:
    theta = R eta, eta_i'' = (R^T torque)_i / j_i, a well-scaled modal realisation.

    Parameters
    ----------
    inertia : (3, 3) array, kg*m**2
        Symmetric positive definite.
    modes : sequence of (w_k [rad/s], zeta_k, b_k (3,), c_k (3,))
        b_k = c_k is a collocated mode participating in several axes.
    tips : sequence of (name, [d_k per mode])
    disturbance : bool
        Also inputs 'disturbance_torque_x..z' acting like the torques.
    """
    J = np.asarray(inertia, dtype=float)
    j, R = np.linalg.eigh(J)
    n = 6 + 2 * len(modes)
    A = np.zeros((n, n))
    B = np.zeros((n, 3))
    C = np.zeros((6 + len(tips), n))
    for i in range(3):
        A[2 * i, 2 * i + 1] = 1.0
        B[2 * i + 1] = R[:, i] / j[i]
        C[:3, 2 * i] = R[:, i]
        C[3:6, 2 * i + 1] = R[:, i]
    for k, (w, zeta, b, c) in enumerate(modes):
        i = 6 + 2 * k
        A[i, i + 1] = 1.0
        A[i + 1, i] = -w * w
        A[i + 1, i + 1] = -2.0 * zeta * w
        B[i + 1] = b
        C[:3, i] = c
        C[3:6, i + 1] = c
        for t, (_, d) in enumerate(tips):
            C[6 + t, i] = d[k]
    inputs = [f"torque_{a}" for a in AXES]
    if disturbance:
        inputs += [f"disturbance_torque_{a}" for a in AXES]
        B = np.hstack([B, B])
    return control.ss(A, B, C, 0.0, inputs=inputs,
                      outputs=[f"theta_{a}" for a in AXES] + [f"omega_{a}" for a in AXES]
                      + [name for name, _ in tips])


def embedded_planar_plant(planar, inertia_x, inertia_y):
    """A planar plant (input torque, outputs theta, omega, ...) embedded in three axes as its z
    axis, with rigid x and y axes of the given inertias: block-diagonal, the planar model
    exactly in the z rows and columns (inputs torque_x, torque_y, torque_z; outputs theta_x..z,
    omega_x..z, then the planar plant's other outputs)."""
    n = planar.nstates
    A = scipy.linalg.block_diag(np.array([[0.0, 1.0], [0.0, 0.0]]),
                                np.array([[0.0, 1.0], [0.0, 0.0]]), planar.A)
    i_t = list(planar.input_labels).index("torque")
    B = np.zeros((n + 4, 3))
    B[1, 0], B[3, 1] = 1.0 / inertia_x, 1.0 / inertia_y
    B[4:, 2] = planar.B[:, i_t]
    outs = list(planar.output_labels)
    others = [o for o in outs if o not in ("theta", "omega")]
    C = np.zeros((6 + len(others), n + 4))
    C[0, 0], C[1, 2], C[3, 1], C[4, 3] = 1.0, 1.0, 1.0, 1.0
    C[2, 4:] = planar.C[outs.index("theta")]
    C[5, 4:] = planar.C[outs.index("omega")]
    for r, name in enumerate(others):
        C[6 + r, 4:] = planar.C[outs.index(name)]
    return control.ss(A, B, C, 0.0, inputs=[f"torque_{a}" for a in AXES],
                      outputs=[f"theta_{a}" for a in AXES] + [f"omega_{a}" for a in AXES]
                      + others)
