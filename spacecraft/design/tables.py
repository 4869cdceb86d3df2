"""Tables of models: the paper's equivalence table against the exact beam, model parameters.

:func:`equivalence_table` tabulates the paper's quantities (m, J, L, gains k_r, zeros n_r1,
n_r2, natural frequencies w1, w2) of each chain fitted to an appendage (and, for a bare uniform
beam, of the paper's two-mode free-free beam), with their relative errors against the
appendage's exact model (a distributed beam's exact W; modal data's own W) and the largest
|ln(W_r / W_r,exact)| over the band (:func:`appendages.equivalence.criterion`).
:func:`describe_model` gives an appendage model's parameters, JSON-ready.
"""

from __future__ import annotations

import warnings

import numpy as np

from .naming import FIT_LABELS

__all__ = ["equivalence_table", "describe_model", "reference_name"]


def reference_name(model) -> str:
    """The name of an appendage model as the reference of an equivalence table: what kind of
    exact model it is (``"beam (exact)"``, ``"stepped beam (exact)"``, ``"modal data
    (FE-exact)"``...)."""
    if getattr(model, "is_uniform", False):
        return "beam (exact)"
    if hasattr(model, "segments"):
        return ("stepped beam with tip body (exact)" if getattr(model, "tip", None) is not None
                else "stepped beam (exact)")
    if hasattr(model, "participation"):
        return "modal data (FE-exact)"
    if hasattr(model, "tip"):
        return "beam with tip body (exact)"
    return f"{type(model).__name__} (exact)"


def equivalence_table(beam, fits: dict, *, stats=None) -> dict:
    """The paper's equivalence table against the appendage's exact model, JSON-ready.

    Parameters
    ----------
    beam : appendage model
        The reference: a distributed beam (uniform, with a tip body, stepped or tapered; its
        exact W, poles and zeros) or modal data (:class:`appendages.ModalAppendage`: its own
        W, "FE-exact": exact for the modes it holds).
    fits : dict
        ``match -> HingedChain`` (keys of :data:`FIT_LABELS`) or ``label -> model``.
    stats : RunStats, optional
        Counts one exact-reference evaluation per column.

    Returns
    -------
    dict
        ``reference`` (the reference's name, :func:`reference_name`), ``quantities``,
        ``units``, ``exact`` (the reference's values, None where not defined), ``columns``
        (for each model: ``name``, ``values``, ``relative_error`` against the reference and
        ``max_log_error`` of W1..W4 over the band, see
        :func:`appendages.equivalence.criterion`) and ``notes``. The paper's two-mode
        free-free beam is a column for a bare uniform beam only (the paper's model of the
        uniform rod): a note says so for any other appendage.
    """
    from appendages.equivalence import criterion

    reference_label = reference_name(beam)
    candidates, notes = [], []
    if getattr(beam, "is_uniform", False):
        candidates.append(("beam, 2 modes (paper)", beam.truncated(2, method="free-free")))
    else:
        kind = reference_label.split(" (")[0]
        how = ("its own W, exact for the modes it holds" if "FE-exact" in reference_label
               else "its exact W")
        notes.append(f"The paper's two-mode free-free beam and its frequency fit are models of "
                     f"a bare uniform beam; the reference here is the {kind} ({how}), so "
                     "neither is a column.")
        if "FE-exact" in reference_label:
            notes.append("The gains k_r of modal data, lim s^2 W_r, are the inverse of their "
                         "residual mass (the mass their modes do not carry): a property of "
                         "where the data were truncated, not of the structure (a distributed "
                         "beam has none); compare the chains' poles, zeros and W over the band.")
    candidates += [(FIT_LABELS.get(k, k), model) for k, model in fits.items()]
    columns, reference, units = [], None, None
    for label, model in candidates:
        if stats is not None:
            stats.exact_reference_evaluations += 1
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            result = criterion(beam, model, names=(reference_label, label))
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
    return {"reference": reference_label, "quantities": [u[0] for u in units],
            "units": [u[1] for u in units], "exact": reference, "columns": columns,
            "notes": notes}


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
        if getattr(model, "three_axis", False):   # a three-axis chain's other motions
            for name in ("inertias_y", "hinge_stiffnesses_y", "hinge_dampings_y",
                         "torsional_inertias", "torsion_stiffnesses", "torsion_dampings",
                         "axial_stiffnesses", "axial_dampings"):
                value = getattr(model, name)
                out[name] = None if value is None else np.asarray(value).tolist()
    if hasattr(model, "n_modes"):
        out.update(n_modes=int(model.n_modes), method=getattr(model, "method", None))
        try:
            out["modes_per_motion"] = dict(model.modes_per_motion)
        except (AttributeError, ValueError):
            pass   # planar, or a beam whose motions couple
    if hasattr(model, "poles"):
        try:
            out["natural_frequencies"] = np.asarray(model.poles())[:6].tolist()
        except ValueError:
            pass
    return out

