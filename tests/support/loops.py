"""Loop helpers the margin tests share: a controller given an unstable pole, margins compared
field by field, and the random PD variants of the dense-reference tests."""
from __future__ import annotations

import math
import warnings

import control
import numpy as np

import controllers

__all__ = ["assert_same_margins", "with_unstable_pole", "random_pd"]


def with_unstable_pole(K, a, c):
    """The controller with, per axis, a state x' = a x + theta (a > 0: unstable) feeding
    torque -c x. On a rigid axis of inertia J with PD gains kp, kd the loop's characteristic
    polynomial is J s^3 + (kd - a J) s^2 + (kp - a kd) s + (c - a kp): by Routh stable for
    a kp < c < a kp + (kd - a J)(kp - a kd)/J, unstable outside."""
    A0, B0, C0, D0 = (np.asarray(x, dtype=float) for x in (K.A, K.B, K.C, K.D))
    n0 = A0.shape[0]
    inputs = list(K.input_labels)
    A = np.block([[A0, np.zeros((n0, 3))], [np.zeros((3, n0)), a * np.eye(3)]])
    B = np.vstack([B0, np.zeros((3, len(inputs)))])
    B[n0 + np.arange(3), [inputs.index(f"theta_{x}") for x in "xyz"]] = 1.0
    C = np.hstack([C0, -c * np.eye(3)])
    return control.ss(A, B, C, D0, inputs=inputs, outputs=list(K.output_labels))


def assert_same_margins(a, b, tol=1e-9):
    da, db = a.as_dict(), b.as_dict()
    assert da.keys() == db.keys()
    for key in da:
        if math.isinf(da[key]):
            assert da[key] == db[key], key
        else:
            assert abs(da[key] - db[key]) <= tol * max(1.0, abs(da[key])), (key, da[key], db[key])
    assert abs(a.delay_margin - b.delay_margin) <= tol * max(1.0, abs(a.delay_margin))


def random_pd(rng, rigid, first_mode: float, kind: int, wn: float, damping: float):
    """A PD tuned on the rigid ``rigid`` plant (natural frequency ``wn`` [rad/s], ``damping``)
    of the variant ``kind``: 0 plain, 1 notched at 0.9-1.1 x ``first_mode`` [rad/s], 2 rolled
    off at 2.5-8 x ``wn``, 3 digital at 8-40 samples per pi / ``wn``; the variant's one
    random number drawn from the generator ``rng``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if kind == 0:
            return controllers.pd(rigid, natural_frequency=wn, damping=damping)
        if kind == 1:
            return controllers.pd(rigid, natural_frequency=wn, damping=damping,
                                  notch=first_mode * rng.uniform(0.9, 1.1))
        if kind == 2:
            return controllers.pd(rigid, natural_frequency=wn, damping=damping,
                                  roll_off=wn * rng.uniform(2.5, 8.0))
        return controllers.pd(rigid, natural_frequency=wn, damping=damping,
                              sample_time=math.pi / (wn * rng.uniform(8.0, 40.0)))
