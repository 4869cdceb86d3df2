"""A controller given as numbers: what a sweep records of each design, and the scene's
``[controller.given]`` table that runs exactly that controller again instead of tuning one.

A controller is the state-space system (continuous: dx/dt = A x + B u, torque = C x + D u;
digital, sample time T = 1 / ``controller.sample_rate``: x[k+1] = A x[k] + B u[k])

* inputs u, in this order (:func:`channel_names`): planar (theta_ref [rad], theta [rad],
  omega [rad/s]); three-axis (theta_ref_x, theta_ref_y, theta_ref_z [rad], theta_x, theta_y,
  theta_z [rad], omega_x, omega_y, omega_z [rad/s]), hub axes, the signals the design loop's
  three-axis controllers take (:mod:`controllers.signals`);
* outputs: torque [N m] (planar); torque_x, torque_y, torque_z [N m] (three-axis);
* its own states x (none for a PD without filters: planar ``D = [[Kp, -Kp, -Kd]]``, Kp
  [N m/rad], Kd [N m s/rad]; three-axis ``D = [Kp, -Kp, -Kd]`` with 3 x 3 gain blocks; an
  LQR's states are the estimate of the design model's states).

So A is [1/s] (digital: dimensionless), B [1/s per input unit], C [N m per state unit] and D
[N m per input unit]. The numbers are written in full (the shortest text that reads back to the
same double), so a recorded controller is the tuned one to the last bit.

Scene keys (the entry replaces the tuning of one of ``controller.types``; m inputs and p
outputs: m = 3, p = 1 in a planar scene, m = 9, p = 3 in a three-axis one)

===========================  ==========================================================
key                          meaning
===========================  ==========================================================
``controller.given.kind`` *  ``"pd"`` or ``"lqr"``: the controller of ``controller.types``
                             that is given instead of tuned (its ``pd``/``lqr`` table stays:
                             it says how the controller was designed, and sets the frequency
                             band of the models, as for a tuned one)
``controller.given.A``       n x n array (``[]`` for n = 0)
``controller.given.B``       n x m array (``[]`` for n = 0)
``controller.given.C``       p x n array (``[[]]`` or ``[]`` for n = 0)
``controller.given.D`` *     p x m array
===========================  ==========================================================
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import numpy as np

__all__ = ["GivenController", "INPUTS", "OUTPUTS", "INPUTS_3D", "OUTPUTS_3D", "channel_names",
           "controller_record", "read_given", "given_state_space"]

#: Inputs of a planar given controller, in the order of the columns of B and D.
INPUTS = ("theta_ref", "theta", "omega")
#: Its output (the row of C and D).
OUTPUTS = ("torque",)
#: Inputs of a three-axis given controller, in the order of the columns of B and D: the
#: three-axis controller signals of :mod:`controllers.signals` (written out here so that
#: reading a scene does not import the control library).
INPUTS_3D = tuple(f"{name}_{axis}" for name in INPUTS for axis in "xyz")
#: Its outputs (the rows of C and D).
OUTPUTS_3D = tuple(f"torque_{axis}" for axis in "xyz")
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

    @property
    def three_axis(self) -> bool:
        """A three-axis controller (three torques)."""
        return len(self.D) == len(OUTPUTS_3D)


def channel_names(three_axis: bool) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """The inputs (columns of B and D) and outputs (rows of C and D) of a given controller,
    in order: :data:`INPUTS`, :data:`OUTPUTS` (planar) or :data:`INPUTS_3D`,
    :data:`OUTPUTS_3D` (three-axis)."""
    return (INPUTS_3D, OUTPUTS_3D) if three_axis else (INPUTS, OUTPUTS)


def controller_record(K, kind: str) -> dict:
    """A tuned controller as the numbers of a ``[controller.given]`` table (JSON-ready).

    Parameters
    ----------
    K : control.StateSpace
        Planar: inputs ``theta_ref``, ``theta``, ``omega`` (any order), output ``torque``;
        three-axis: inputs :data:`INPUTS_3D` (any order), outputs :data:`OUTPUTS_3D` (any
        order).
    kind : str
        ``"pd"`` or ``"lqr"``.

    Returns
    -------
    dict
        ``kind``, ``A``, ``B``, ``C``, ``D`` (lists of rows, inputs and outputs in the order
        of :func:`channel_names`).
    """
    labels, outputs = list(K.input_labels), list(K.output_labels)
    inputs, wanted = channel_names(len(outputs) == len(OUTPUTS_3D))
    if sorted(labels) != sorted(inputs) or sorted(outputs) != sorted(wanted):
        raise ValueError(f"controller_record: needs inputs {list(INPUTS)} and output "
                         f"{list(OUTPUTS)} (planar) or inputs {list(INPUTS_3D)} and outputs "
                         f"{list(OUTPUTS_3D)} (three-axis); got {labels} -> {outputs}")
    order = [labels.index(name) for name in inputs]
    rows_order = [outputs.index(name) for name in wanted]
    n, m, p = K.nstates, len(inputs), len(wanted)

    def rows(M, shape):
        return np.asarray(M, dtype=float).reshape(shape).tolist()

    B = np.asarray(K.B, dtype=float).reshape(n, m)[:, order]
    C = np.asarray(K.C, dtype=float).reshape(p, n)[rows_order, :]
    D = np.asarray(K.D, dtype=float).reshape(p, m)[np.ix_(rows_order, order)]
    return {"kind": kind, "A": rows(K.A, (n, n)), "B": rows(B, (n, m)), "C": rows(C, (p, n)),
            "D": rows(D, (p, m))}


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
        The scene is three-axis: the controller takes :data:`INPUTS_3D` and gives
        :data:`OUTPUTS_3D`.
    max_states : int, optional
        Most controller states accepted (the scene's ``limits.states``).

    Raises
    ------
    SceneError
        Naming the key: unknown keys, a kind not among ``types``, arrays of the wrong shape,
        numbers that are not finite.
    """
    inputs, outputs = channel_names(three_axis)
    n_in, n_out = len(inputs), len(outputs)
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
            if three_axis:
                raise error(full, "missing required value (3 x 9: torque_x, torque_y, torque_z "
                            "[N m] per theta_ref_x..z [rad], theta_x..z [rad], omega_x..z "
                            "[rad/s])")
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
                        f"{n_in} inputs and {n_out} output{'s' if n_out > 1 else ''}"
                        f"{' in a three-axis scene' if three_axis else ''}); got {got[0]} x "
                        f"{got[1]}")
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
    return GivenController(kind, matrix("A", n, n), matrix("B", n, n_in),
                           matrix("C", n_out, n), matrix("D", n_out, n_in))


def given_state_space(given: GivenController, sample_time: float | None):
    """The controller of a :class:`GivenController` as a ``control.StateSpace`` (dt = 0, or the
    sample time [s] of a digital controller), signals as :func:`channel_names` says."""
    import control

    inputs, outputs = channel_names(given.three_axis)
    n, m, p = given.n_states, len(inputs), len(outputs)
    A = np.array(given.A, dtype=float).reshape(n, n)
    B = np.array(given.B, dtype=float).reshape(n, m)
    C = np.array(given.C, dtype=float).reshape(p, n)
    D = np.array(given.D, dtype=float).reshape(p, m)
    return control.ss(A, B, C, D, 0 if sample_time is None else sample_time,
                      inputs=list(inputs), outputs=list(outputs), name=f"{given.kind}_given")
