"""FMI cross-check style reference files computed by python-control.

Next to ``<Model>.fmu`` the exporter can write

- ``<Model>_in.csv``: the input signals, one step per input (amplitude 1 in the input's
  unit) at distinct instants on the communication grid; a step is written as two rows with
  the same time (before and after), as the cross-check rules and fmpy expect;
- ``<Model>_ref.csv``: the outputs on the grid ``t_k = k h``, with two rows at every input
  step instant (left and right limits, which differ when D != 0);
- ``<Model>_ref.opt``: StartTime, StopTime, StepSize (the communication step h) and RelTol.

The inputs are piecewise constant between grid points, so the zero-order-hold
discretisation ``control.c2d(sys, h, "zoh")`` gives the exact continuous response at the
grid points: the same file checks Model Exchange (to the solver's tolerance) and
Co-Simulation (to round-off).  A sampled system (sample period h) is simulated as it is;
at a sample instant its output is ``C x_k + D u`` with the input before (left row) and
after (right row) the step, as the FMU shows it.

References
----------
Modelica Association, "FMI Cross-Check rules" (fmi-cross-check repository, README), for the
file names and the .opt keys.
"""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np

from .codegen import c_double
from .files import write_text_atomically
from .system import LinearModel

__all__ = ["reference_inputs", "reference_response", "write_reference_files"]


def _grid(step: float, stop_time: float) -> np.ndarray:
    n_steps = int(round(stop_time / step))
    return np.arange(n_steps + 1, dtype=np.float64) * step


def reference_inputs(model: LinearModel, step: float, stop_time: float) -> tuple[np.ndarray, np.ndarray]:
    """Step instants and the rows of the input table.

    Input ``k`` (of m) steps from 0 to 1 at the grid point nearest to
    ``(k + 1) / (m + 1) * stop_time / 2``, so every step happens inside the first half and
    the free response is visible in the second.

    Returns
    -------
    step_indices : numpy.ndarray of int, shape (m,)
        Grid index of each input's step.
    table : numpy.ndarray of float64, shape (rows, 1 + m)
        Columns time, inputs; two rows at each step instant.
    """
    t = _grid(step, stop_time)
    n_grid = t.size
    m = model.n_inputs
    step_indices = np.array([max(1, min(n_grid - 2, int(round((k + 1) / (m + 1) * (n_grid - 1) / 2))))
                             for k in range(m)], dtype=int)
    rows = [[t[0]] + [0.0] * m]
    for index in sorted(set(step_indices.tolist())):
        before = [1.0 if step_indices[k] < index else 0.0 for k in range(m)]
        after = [1.0 if step_indices[k] <= index else 0.0 for k in range(m)]
        rows.append([t[index]] + before)
        rows.append([t[index]] + after)
    rows.append([t[-1]] + [1.0] * m)
    return step_indices, np.array(rows, dtype=np.float64)


def reference_response(model: LinearModel, step: float, stop_time: float) -> np.ndarray:
    """Outputs for :func:`reference_inputs`, exact at the grid points.

    Returns
    -------
    numpy.ndarray of float64, shape (rows, 1 + p)
        Columns time, outputs. At an input step instant two rows: ``C x + D u(t-)`` and
        ``C x + D u(t+)``.
    """
    t = _grid(step, stop_time)
    step_indices, _ = reference_inputs(model, step, stop_time)
    # u_k = u(t_k+), held over [t_k, t_k+1): right-continuous steps
    U = (np.arange(t.size)[None, :] >= step_indices[:, None]).astype(np.float64)
    U_left = (np.arange(t.size)[None, :] > step_indices[:, None]).astype(np.float64)
    if model.discrete:
        return _sampled_response(model, t, step, step_indices, U, U_left)
    sampled = control.c2d(model.statespace(), step, method="zoh")
    response = control.forced_response(sampled, T=t, U=U, X0=model.x0)
    X = np.asarray(response.states, dtype=np.float64).reshape(model.n_states, t.size)
    Y = np.asarray(response.outputs, dtype=np.float64).reshape(model.n_outputs, t.size)
    rows = []
    events = set(step_indices.tolist())
    for k in range(t.size):
        if k in events:
            left = model.C @ X[:, k] + model.D @ U_left[:, k]
            rows.append(np.concatenate(([t[k]], left)))
        rows.append(np.concatenate(([t[k]], Y[:, k])))
    return np.array(rows, dtype=np.float64)


#: Sample instants this close to a communication point, relative to the sample period,
#: count as at it (LI_SAMPLE_TOLERANCE of fmu/c/lti_instance.h).
SAMPLE_TOLERANCE = 1e-6


def _sampled_response(model: LinearModel, t: np.ndarray, h: float, step_indices: np.ndarray,
                      U: np.ndarray, U_left: np.ndarray) -> np.ndarray:
    """Outputs of a sampled system on the communication grid t, as its FMU shows them.

    The FMU samples at s_j = j T with the inputs the master set at the last communication
    point at or before s_j (it holds them over the step): u_k(j) with k(j) the grid index of
    that point. Sample j gives y_j = C x_j + D u_k(j) and x_j+1 = A x_j + B u_k(j). At a grid
    point t_k the output is the last sample's y_j, except where a sample instant falls on
    t_k: there the sample is still to be taken and the output is C x_j + D u with the input
    before (left row) and after (right row) the input step at t_k.
    """
    T = model.sample_period
    tolerance = SAMPLE_TOLERANCE * T
    n_samples = int(np.floor((t[-1] + tolerance) / T)) + 1
    s = np.arange(n_samples) * T
    k_of_sample = np.minimum(np.floor((s + tolerance) / h).astype(int), t.size - 1)
    response = control.forced_response(model.statespace(), T=s, U=U[:, k_of_sample], X0=model.x0)
    X = np.asarray(response.states, dtype=np.float64).reshape(model.n_states, n_samples)
    Y = np.asarray(response.outputs, dtype=np.float64).reshape(model.n_outputs, n_samples)
    rows = []
    events = set(step_indices.tolist())
    for k in range(t.size):
        j = min(int(np.floor((t[k] + tolerance) / T)), n_samples - 1)
        pending = abs(s[j] - t[k]) <= tolerance
        if k in events:  # the row before the input step: held, or C x + D u(t-) if pending
            left = model.C @ X[:, j] + model.D @ U_left[:, k] if pending else Y[:, j]
            rows.append(np.concatenate(([t[k]], left)))
        right = model.C @ X[:, j] + model.D @ U[:, k] if pending else Y[:, j]
        rows.append(np.concatenate(([t[k]], right)))
    return np.array(rows, dtype=np.float64)


def _write_csv(path: Path, names: list[str], table: np.ndarray) -> None:
    header = ",".join(f'"{name}"' for name in names)
    body = "\n".join(",".join(c_double(v) for v in row) for row in table.tolist())
    write_text_atomically(path, header + "\n" + body + "\n")


def write_reference_files(model: LinearModel, model_identifier: str, directory: Path,
                          step: float, stop_time: float) -> list[Path]:
    """Write ``<Model>_in.csv``, ``<Model>_ref.csv`` and ``<Model>_ref.opt`` into ``directory``.

    Parameters
    ----------
    model : LinearModel
    model_identifier : str
        The ``<Model>`` part of the file names.
    directory : pathlib.Path
    step : float, s
        Communication step (StepSize) and output grid spacing.
    stop_time : float, s

    Returns
    -------
    list of pathlib.Path
        The three files written.
    """
    _, inputs = reference_inputs(model, step, stop_time)
    outputs = reference_response(model, step, stop_time)
    in_path = directory / f"{model_identifier}_in.csv"
    ref_path = directory / f"{model_identifier}_ref.csv"
    opt_path = directory / f"{model_identifier}_ref.opt"
    _write_csv(in_path, ["time", *model.input_names], inputs)
    _write_csv(ref_path, ["time", *model.output_names], outputs)
    write_text_atomically(opt_path, f"StartTime, 0.0\nStopTime, "
                          f"{c_double(float(_grid(step, stop_time)[-1]))}\n"
                          f"StepSize, {c_double(step)}\nRelTol, 1e-06\n")
    return [in_path, ref_path, opt_path]
