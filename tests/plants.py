"""Hand-built test plants with the controllers' signal conventions (shared by the test files)."""

import control
import numpy as np

__all__ = ["modal_plant"]


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
