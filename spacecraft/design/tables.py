"""Tables of models: the paper's equivalence table against the exact beam, model parameters.

:func:`equivalence_table` tabulates the paper's quantities (m, J, L, gains k_r, zeros n_r1,
n_r2, natural frequencies w1, w2) of the paper's two-mode free-free beam and of each chain
fitted to a beam, with their relative errors against the exact distributed beam and the largest
|ln(W_r / W_r,exact)| over the band (:func:`appendages.equivalence.criterion`).
:func:`describe_model` gives an appendage model's parameters, JSON-ready.
"""

from __future__ import annotations

import warnings

import numpy as np

from .naming import FIT_LABELS

__all__ = ["equivalence_table", "describe_model"]


def equivalence_table(beam, fits: dict, *, stats=None) -> dict:
    """The paper's equivalence table against the exact beam, JSON-ready.

    Parameters
    ----------
    beam : appendages.Beam
        The distributed beam (reference: its exact W, poles and zeros).
    fits : dict
        ``match -> HingedChain`` (keys of :data:`FIT_LABELS`) or ``label -> model``.
    stats : RunStats, optional
        Counts one exact-reference evaluation per column.

    Returns
    -------
    dict
        ``quantities``, ``units``, ``exact`` (the exact beam's values, None where not defined)
        and ``columns``: for the paper's 2-mode free-free beam and each chain, ``name``,
        ``values``, ``relative_error`` against the exact beam and ``max_log_error`` of
        W1..W4 over the band (see :func:`appendages.equivalence.criterion`).
    """
    from appendages.equivalence import criterion

    candidates = [("beam, 2 modes (paper)", beam.truncated(2, method="free-free"))]
    candidates += [(FIT_LABELS.get(k, k), model) for k, model in fits.items()]
    columns, reference, units = [], None, None
    for label, model in candidates:
        if stats is not None:
            stats.exact_reference_evaluations += 1
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            result = criterion(beam, model, names=("beam (exact)", label))
        rows = result.rows()
        if reference is None:
            reference = [r[2] for r in rows]
            units = [(r[0], r[1]) for r in rows]
        column = {"name": label, "values": [r[3] for r in rows],
                  "relative_error": [r[4] for r in rows],
                  "max_log_error": result.max_log_error.tolist(), "band": list(result.band)}
        if hasattr(model, "hinge_stiffnesses"):
            column["parameters"] = describe_model(model)
        columns.append(column)
    return {"quantities": [u[0] for u in units], "units": [u[1] for u in units],
            "exact": reference, "columns": columns}


def describe_model(model) -> dict:
    """Parameters of an appendage model, JSON-ready."""
    out = {"type": type(model).__name__, "length": float(model.length),
           "mass": float(model.mass), "inertia": float(model.inertia)}
    if hasattr(model, "lengths"):
        out.update(root=model.root, lengths=model.lengths.tolist(), masses=model.masses.tolist(),
                   inertias=model.inertias.tolist(),
                   hinge_stiffnesses=model.hinge_stiffnesses.tolist(),
                   hinge_dampings=(None if model.hinge_dampings is None
                                   else np.asarray(model.hinge_dampings).tolist()),
                   com_offsets=model.com_offsets.tolist())
    if hasattr(model, "n_modes"):
        out.update(n_modes=int(model.n_modes), method=getattr(model, "method", None))
    if hasattr(model, "poles"):
        try:
            out["natural_frequencies"] = np.asarray(model.poles())[:6].tolist()
        except ValueError:
            pass
    return out

