"""The scene's manoeuvre on a closed loop: the slew and the disturbance, and what they measure.

A manoeuvre is a cycloidal slew of theta_ref (:func:`controllers.slew_profile`) and, if the
scene asks, a rectangular disturbance pulse. The loop is linear, so the two are simulated apart
(:func:`simulate_manoeuvre`): the slew's metrics (overshoot, settling time...) are the slew's
alone, and the disturbance's (peak attitude error, peak torque...) the disturbance's alone; what
the spacecraft does under both is their sum.

Divergence is a result: a response that leaves the float64 range stops at the last sample that
could be computed (attributes ``diverged`` and ``diverged_at`` [s], :func:`diverged_at`).

Per appendage (:func:`appendage_peaks`): the peak tip deflection and, when the plant has them,
the peak root force and root moment, from the outputs ``<name>_tip_deflection`` [m],
``<name>_root_force`` [N] and ``<name>_root_moment`` [N m] of :meth:`Spacecraft.plant`; three
axes: the tip deflections in both planes [m] and the twist [rad], the root loads per axis.
"""

from __future__ import annotations

import math
import warnings

import control
import numpy as np

import controllers

__all__ = ["simulate_manoeuvre", "diverged_at", "time_grid", "trace", "appendage_peaks",
           "outputs_until_overflow", "slew_and_disturbance_inputs", "disturbance_inputs",
           "discrete_outputs", "response_data", "disturbance_weights", "APPENDAGE_SIGNALS"]


def time_grid(manoeuvre) -> np.ndarray:
    """Sample times 0, step, ... <= duration [s] of a manoeuvre."""
    n = int(math.floor(manoeuvre.duration / manoeuvre.step + 1e-9)) + 1
    return np.arange(n) * manoeuvre.step


def slew_and_disturbance_inputs(loop, manoeuvre, T: np.ndarray):
    """Input arrays (ninputs, n) of the slew alone and of the disturbance alone (None without
    a disturbance). A three-axis loop slews about the manoeuvre's eigen-axis e:
    ``theta_ref_i = e_i profile`` (small angles), as :func:`controllers.slew` does."""
    labels = list(loop.input_labels)
    U = np.zeros((loop.ninputs, T.size))
    profile = controllers.slew_profile(T, manoeuvre.slew_angle, manoeuvre.slew_time)
    if "theta_ref" in labels:
        U[labels.index("theta_ref")] = profile
    else:
        for axis, e in zip("xyz", manoeuvre.slew_axis):
            U[labels.index(f"theta_ref_{axis}")] = e * profile
    return U, disturbance_inputs(labels, manoeuvre, T)


def disturbance_inputs(labels, manoeuvre, T: np.ndarray) -> np.ndarray | None:
    """Input array (len(labels), n) of the manoeuvre's disturbance pulse alone at the times T
    (None without a disturbance)."""
    if manoeuvre.disturbance is None:
        return None
    labels = list(labels)
    d = manoeuvre.disturbance
    end = math.inf if d.length is None else d.start + d.length
    D = np.zeros((len(labels), T.size))
    pulse = np.where((T >= d.start) & (T < end), d.amplitude, 0.0)
    for name, weight in disturbance_weights(d).items():
        D[labels.index(name)] = weight * pulse
    return D


def disturbance_weights(disturbance) -> dict[str, float]:
    """The plant inputs a scene's disturbance acts on and its share of the amplitude in each:
    the one input it names, or (three axes, ``disturbance_torque`` or ``force`` with an
    ``axis``) the three inputs ``<input>_x``, ``_y``, ``_z`` with the axis' components."""
    d = disturbance
    if getattr(d, "axis", None) is None:
        return {d.input: 1.0}
    return {f"{d.input}_{a}": float(e) for a, e in zip("xyz", d.axis) if e != 0.0}


def simulate_manoeuvre(loop, manoeuvre, *, simulator=None, together: bool = False) -> dict:
    """The slew and (if any) the disturbance response of a closed loop.

    Parameters
    ----------
    loop : control.StateSpace
        Closed loop from :func:`controllers.close_loop` (input ``theta_ref``, disturbances).
    manoeuvre : spacecraft.scene.read.ManoeuvreSpec
    simulator : controllers.Simulator, optional
        A simulator of ``loop`` at ``manoeuvre.step`` to reuse (continuous loops).
    together : bool
        Simulate slew and disturbance at once (``"slew"`` is then the whole manoeuvre's
        response, ``"disturbance"`` None): what the spacecraft does under both.

    Returns
    -------
    dict
        ``"slew"`` and ``"disturbance"`` (None without one): control.TimeResponseData with
        outputs only, ``diverged`` (bool) and ``diverged_at`` [s] or None.
    """
    T = time_grid(manoeuvre)
    U, D = slew_and_disturbance_inputs(loop, manoeuvre, T)
    if together and D is not None:
        U, D = U + D, None
    if loop.isdtime(strict=True):
        outputs = discrete_outputs
    else:
        if simulator is None:
            simulator = controllers.Simulator(loop, manoeuvre.step)

        def outputs(loop, T, U):
            return outputs_until_overflow(simulator, T, U)
    out = {"slew": response_data(loop, T, U, outputs(loop, T, U), "slew"), "disturbance": None}
    if D is not None:
        out["disturbance"] = response_data(loop, T, D, outputs(loop, T, D), "disturbance")
    return out


def discrete_outputs(loop, T, U) -> np.ndarray:
    """Outputs (noutputs, n) of a discrete loop driven by U at its samples T (non-finite
    where its response leaves the float range)."""
    with np.errstate(over="ignore", invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        response = control.forced_response(loop, T, U, squeeze=False)
    return np.asarray(response.y).reshape(loop.noutputs, -1)


def response_data(loop, T, U, Y, what: str) -> control.TimeResponseData:
    """The response of ``loop`` (outputs Y, inputs U at the times T) up to its first sample
    outside the float range, with ``diverged`` and ``diverged_at`` [s] (None)."""
    n = T.size
    with np.errstate(invalid="ignore"):
        finite = np.all(np.isfinite(Y), axis=0)
    k = n if finite.all() else max(int(np.argmin(finite)), 1)
    out = control.TimeResponseData(
        T[:k], Y[:, :k], None, U[:, :k], issiso=loop.issiso(),
        output_labels=list(loop.output_labels), input_labels=list(loop.input_labels),
        sysname=loop.name, title=f"{what} of {loop.name}", trace_types=["forced"],
        plot_inputs=True, squeeze=False)
    out.diverged = k < n
    out.diverged_at = float(T[k - 1]) if k < n else None
    return out


def outputs_until_overflow(simulator, T: np.ndarray, U: np.ndarray) -> np.ndarray:
    """Outputs on ``T``; where the response overflows float64, those of the longest prefix of
    ``T`` that does not (found by bisection; the simulator's set-up is reused), padded with inf.

    ``controllers.Simulator`` raises FloatingPointError when an unstable loop's response leaves
    the float64 range; the prefix shows how it diverged up to then.
    """
    n = T.size
    try:
        return simulator.outputs(T, U)
    except FloatingPointError:
        pass
    good, bad, Y = 1, n, None       # prefixes of `good` samples compute, of `bad` overflow
    while bad - good > 1:
        mid = (good + bad) // 2
        try:
            Y = simulator.outputs(T[:mid], U[:, :mid])
            good = mid
        except FloatingPointError:
            bad = mid
    out = np.full((simulator.n_outputs, n), np.inf)
    if good >= 2:
        out[:, :good] = Y if Y is not None and Y.shape[1] == good else \
            simulator.outputs(T[:good], U[:, :good])
    else:
        # X0 = 0: the first output is the feedthrough
        D = np.asarray(simulator.system.D, dtype=float)
        out[:, 0] = D @ U[:, 0]
    return out


def diverged_at(response) -> float | None:
    """Time [s] at which a response's simulation stopped because it diverged, or None.

    Reads the attributes ``diverged`` and ``diverged_at`` that :func:`simulate_manoeuvre` (and
    controllers' responses, where they provide them) set; a response without them diverged if
    it has a non-finite output sample (at the last finite sample before it).
    """
    if hasattr(response, "diverged"):
        if not response.diverged:
            return None
        at = getattr(response, "diverged_at", None)
        return float(at) if at is not None else float(np.asarray(response.t).reshape(-1)[-1])
    y = np.asarray(response.y)
    y = y.reshape(-1, y.shape[-1])
    finite = np.all(np.isfinite(y), axis=0)
    if finite.all():
        return None
    k = int(np.argmin(finite))
    t = np.asarray(response.t).reshape(-1)
    return float(t[max(k - 1, 0)])


def trace(response, name: str, kind: str = "output") -> np.ndarray | None:
    """One output (or input) of a response as a 1-D array, None if it has no such signal."""
    labels = list(response.output_labels if kind == "output" else response.input_labels)
    if name not in labels:
        return None
    data = np.asarray(response.y if kind == "output" else response.u)
    return data.reshape(len(labels), -1)[labels.index(name)]


#: Per-appendage outputs and the peak each gives: (suffix, metric name, unit). Planar: the tip
#: deflection, the root force and moment; three axes: the tip deflections in the appendage's
#: x-y and x-z planes and its twist, the root loads along and about each appendage axis.
APPENDAGE_SIGNALS = (("_tip_deflection", "peak_tip_deflection", "m"),
                     ("_root_force", "peak_root_force", "N"),
                     ("_root_moment", "peak_root_moment", "N m"),
                     ("_tip_deflection_y", "peak_tip_deflection_y", "m"),
                     ("_tip_deflection_z", "peak_tip_deflection_z", "m"),
                     ("_tip_twist", "peak_tip_twist", "rad"),
                     *((f"_root_force_{a}", f"peak_root_force_{a}", "N") for a in "xyz"),
                     *((f"_root_moment_{a}", f"peak_root_moment_{a}", "N m") for a in "xyz"))


def appendage_peaks(response, names) -> dict:
    """``{name: {"peak_tip_deflection": m, "peak_root_force": N, "peak_root_moment": N m}}``
    over the response, for the signals it has (empty dicts otherwise)."""
    out = {}
    for name in names:
        peaks = {}
        for suffix, metric, _ in APPENDAGE_SIGNALS:
            y = trace(response, name + suffix)
            if y is not None and y.size:
                peaks[metric] = float(np.max(np.abs(y)))
        out[name] = peaks
    return out
