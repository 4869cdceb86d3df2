"""Independent finite-element models of a scene's three-axis spacecraft.

The reference of the real-appendage scenes in three axes: the hub rigid (six degrees of
freedom), each stepped beam with its tip body a finite-element beam of tests/support/fe3d.py
(high-order elements per segment, the body's 6x6 mass matrix at the last node), each modal
appendage its own Craig-Bampton realisation (``root_model(6)``: the finite-element data
themselves, six root motions and the cantilever modes), all joined at their roots by the mounts' rigid kinematics
(:func:`fe3d.mount_transformation`). Nothing of flexsat's W6 or exact coupling is used.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse

import fe3d

__all__ = ["spacecraft_matrices", "coupled_frequencies"]


def spacecraft_matrices(scene, models, n_elements: int):
    """Stiffness and mass [SI] of a three-axis scene's spacecraft.

    Parameters
    ----------
    scene : spacecraft.scene.Scene
        Three-axis: a 3x3 hub inertia, every appendage a stepped (or uniform) beam with its
        tip body or modal data, mounted with an orientation.
    models : sequence
        Each appendage's structure as built (``a.structure.build()``): a SteppedBeam (its
        ``segments``) or a ModalAppendage (its ``root_model(6)``).
    n_elements : int
        Elements per beam segment.

    Returns
    -------
    K, M : scipy.sparse.csr_array
        The hub's six degrees of freedom first.
    """
    beams, modal = [], []
    for a, model in zip(scene.appendages, models):
        R = np.array(a.orientation, dtype=float)
        if a.beam is not None:
            segments = getattr(model, "segments", (model,))
            t = a.beam.tip
            tip = None if t is None else fe3d.TipSpec(
                t.mass, np.array(t.inertia, dtype=float).reshape(3, 3),
                np.array(t.offset, dtype=float))
            beams.append((segments, tip, a.position, R))
        else:
            modal.append((model.root_model(6), a.position, R))
    K, M = fe3d.appendage_spacecraft_matrices(scene.hub.mass, np.array(scene.hub.inertia),
                                              beams, n_elements)
    K, M = K.toarray(), M.toarray()
    for root_model, position, R in modal:
        n_old, n_new = K.shape[0], root_model.n - 6
        T = np.zeros((root_model.n, n_old + n_new))
        T[:6, :6] = fe3d.mount_transformation(np.array(position, dtype=float), R)
        T[6:, n_old:] = np.eye(n_new)
        K = np.pad(K, (0, n_new)) + T.T @ root_model.stiffness @ T
        M = np.pad(M, (0, n_new)) + T.T @ root_model.mass @ T
    return (scipy.sparse.csr_array(0.5 * (K + K.T)), scipy.sparse.csr_array(0.5 * (M + M.T)))


def coupled_frequencies(scene, models, n_elements: int, n: int) -> np.ndarray:
    """The first n elastic frequencies [rad/s] of :func:`spacecraft_matrices` (fe3d's
    subspace iteration, six rigid modes removed exactly)."""
    K, M = spacecraft_matrices(scene, models, n_elements)
    return fe3d.natural_frequencies(K, M, n)
