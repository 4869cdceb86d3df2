"""An elastic mode's sign is the spacecraft's, not the eigensolver's: its first coordinate
above 1e-3 of its largest is positive. A solver returns each eigenvector up to its sign, which
another CPU's rounding can flip; the modal plant's states, and the LQR and Kalman gains on them
printed in the report, then flipped sign from one machine to another (found comparing OpenBLAS
kernels on the real_appendages scenes)."""

from __future__ import annotations

import numpy as np
import scipy.linalg

from spacecraft.dynamics import coupling
from spacecraft_models import twin_wings


def test_modes_are_the_same_whatever_signs_the_solver_returns(monkeypatch):
    reference = twin_wings(2)
    w0, V0 = reference.modes()
    rng = np.random.default_rng(7)
    original = scipy.linalg.eigh

    def flipped(*args, **kwargs):
        lam, V = original(*args, **kwargs)
        return lam, V * rng.choice([-1.0, 1.0], V.shape[1])

    monkeypatch.setattr(coupling.scipy.linalg, "eigh", flipped)
    for _ in range(3):
        w, V = twin_wings(2).modes()
        np.testing.assert_array_equal(w, w0)
        np.testing.assert_array_equal(V, V0)
    r = reference.n_rigid
    E = V0[:, r:]
    first = np.argmax(np.abs(E) > 1e-3 * np.abs(E).max(axis=0), axis=0)
    assert np.all(E[first, np.arange(E.shape[1])] > 0)
