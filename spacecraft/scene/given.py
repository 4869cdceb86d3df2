"""A controller given as numbers: what a sweep records of each design, and the scene's
``[controller.given]`` table that runs exactly that controller again instead of tuning one.

A controller is the state-space system (continuous: dx/dt = A x + B u, torque = C x + D u;
digital, sample time T = 1 / ``controller.sample_rate``: x[k+1] = A x[k] + B u[k])

* inputs u = (theta_ref [rad], theta [rad], omega [rad/s]), in this order;
* output torque [N m];
* its own states x (none for a PD without filters: ``D = [[Kp, -Kp, -Kd]]``, Kp [N m/rad],
  Kd [N m s/rad]; an LQR's are the estimate of the design model's states).

So A is [1/s] (digital: dimensionless), B [1/s per input unit], C [N m per state unit] and D
[N m/rad, N m/rad, N m s/rad]. The numbers are written in full (the shortest text that reads
back to the same double), so a recorded controller is the tuned one to the last bit.

Scene keys (a planar scene; the entry replaces the tuning of one of ``controller.types``)

===========================  ==========================================================
key                          meaning
===========================  ==========================================================
``controller.given.kind`` *  ``"pd"`` or ``"lqr"``: the controller of ``controller.types``
                             that is given instead of tuned (its ``pd``/``lqr`` table stays:
                             it says how the controller was designed, and sets the frequency
                             band of the models, as for a tuned one)
``controller.given.A``       n x n array (``[]`` for n = 0)
``controller.given.B``       n x 3 array (``[]`` for n = 0)
``controller.given.C``       1 x n array (``[[]]`` or ``[]`` for n = 0)
``controller.given.D`` *     1 x 3 array
===========================  ==========================================================
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import numpy as np

__all__ = ["GivenController", "INPUTS", "OUTPUTS", "controller_record", "read_given",
           "given_state_space"]

#: Inputs of a given controller, in the order of the columns of B and D.
INPUTS = ("theta_ref", "theta", "omega")
#: Its output (the row of C and D).
OUTPUTS = ("torque",)
_KEYS = ("kind", "A", "B", "C", "D")


@dataclasses.dataclass(frozen=True)
class GivenController:
    """A controller given in a scene (module docstring): which type it replaces and its
    matrices (tuples of rows of floats)."""

    kind: str
    A: tuple
    B: tuple
    C: tuple
    D: tuple

    @property
    def n_states(self) -> int:
        """Number of controller states."""
        return len(self.A)


def controller_record(K, kind: str) -> dict:
    """A tuned controller as the numbers of a ``[controller.given]`` table (JSON-ready).

    Parameters
    ----------
    K : control.StateSpace
        Inputs ``theta_ref``, ``theta``, ``omega`` (any order), output ``torque``.
    kind : str
        ``"pd"`` or ``"lqr"``.

    Returns
    -------
    dict
        ``kind``, ``A``, ``B``, ``C``, ``D`` (lists of rows, inputs in :data:`INPUTS` order).
    """
    labels = list(K.input_labels)
    if sorted(labels) != sorted(INPUTS) or list(K.output_labels) != list(OUTPUTS):
        raise ValueError(f"controller_record: needs inputs {list(INPUTS)} and output "
                         f"{list(OUTPUTS)}; got {labels} -> {list(K.output_labels)}")
    order = [labels.index(name) for name in INPUTS]
    n = K.nstates

    def rows(M, shape):
        return np.asarray(M, dtype=float).reshape(shape).tolist()

    return {"kind": kind, "A": rows(K.A, (n, n)), "B": rows(np.asarray(K.B)[:, order], (n, 3)),
            "C": rows(K.C, (1, n)), "D": rows(np.asarray(K.D)[:, order], (1, 3))}


def read_given(data, path: str, types, error, *, three_axis: bool = False,
               max_states: int | None = None) -> GivenController:
    """Validate a ``[controller.given]`` table.

    Parameters
    ----------
    data : mapping
        The table as read from TOML.
    path : str
        Its key path (``"controller.given"``).
    types : sequence of str
        The scene's ``controller.types``.
    error : callable
        ``error(key_path, problem)`` returns the exception to raise (the scene reader's: a
        SceneError naming the file).
    three_axis : bool
        The scene is three-axis (refused: a given controller is planar for now).
    max_states : int, optional
        Most controller states accepted (the scene's ``limits.states``).

    Raises
    ------
    SceneError
        Naming the key: unknown keys, a kind not among ``types``, arrays of the wrong shape,
        numbers that are not finite.
    """
    if three_axis:
        raise error(path, "a given controller is planar for now (torque about z from "
                         "theta and omega); this scene is three-axis")
    if not isinstance(data, Mapping):
        raise error(path, f"must be a table with kind, A, B, C, D; got {type(data).__name__}")
    unknown = sorted(set(data) - set(_KEYS), key=str)
    if unknown:
        raise error(f"{path}.{unknown[0]}", f"unknown key; expected one of {', '.join(_KEYS)}")
    kind = data.get("kind")
    if kind not in types:
        raise error(f"{path}.kind", f"must name one of controller.types "
                    f"({', '.join(map(repr, types))}); got {kind!r}")

    def matrix(name, rows, cols):
        value = data.get(name, [] if name != "D" else None)
        full = f"{path}.{name}"
        if value is None:
            raise error(full, "missing required value (1 x 3: the torque per theta_ref "
                        "[N m/rad], theta [N m/rad], omega [N m s/rad])")
        if not isinstance(value, (list, tuple)) or any(not isinstance(r, (list, tuple))
                                                       for r in value):
            raise error(full, "must be an array of rows (arrays of numbers); got "
                        f"{type(value).__name__}")
        value = [list(r) for r in value]
        if value == [[]]:
            value = []
        got = (len(value), len(value[0]) if value else 0)
        if (len(value) != rows or any(len(r) != cols for r in value)) and not (
                rows * cols == 0 and not value):
            raise error(full, f"must be {rows} x {cols} (the controller has {n} states, "
                        f"{len(INPUTS)} inputs and 1 output); got {got[0]} x {got[1]}")
        out = []
        for i, r in enumerate(value):
            for j, x in enumerate(r):
                if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
                    raise error(f"{full}[{i}][{j}]", f"must be a finite number; got {x!r}")
            out.append(tuple(float(x) for x in r))
        return tuple(out)

    A_raw = data.get("A", [])
    if not isinstance(A_raw, (list, tuple)):
        raise error(f"{path}.A", "must be an array of rows (arrays of numbers); got "
                    f"{type(A_raw).__name__}")
    n = len(A_raw)
    if max_states is not None and n > max_states:
        raise error(f"{path}.A", f"{n} controller states exceed limits.states = {max_states}")
    return GivenController(kind, matrix("A", n, n), matrix("B", n, 3), matrix("C", 1, n),
                           matrix("D", 1, 3))


def given_state_space(given: GivenController, sample_time: float | None):
    """The controller of a :class:`GivenController` as a ``control.StateSpace`` (dt = 0, or the
    sample time [s] of a digital controller), inputs :data:`INPUTS`, output ``torque``."""
    import control

    n = given.n_states
    A = np.array(given.A, dtype=float).reshape(n, n)
    B = np.array(given.B, dtype=float).reshape(n, 3)
    C = np.array(given.C, dtype=float).reshape(1, n)
    D = np.array(given.D, dtype=float).reshape(1, 3)
    return control.ss(A, B, C, D, 0 if sample_time is None else sample_time,
                      inputs=list(INPUTS), outputs=list(OUTPUTS), name=f"{given.kind}_given")
