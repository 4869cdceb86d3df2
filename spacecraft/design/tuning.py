"""The scene's controllers tuned on a design plant, with what an engineer needs to know of them.

:func:`tune` calls :func:`controllers.pd` or :func:`controllers.lqr_design` with the scene's
specification and returns the controller with its description (:class:`Tuned`): the control
law's structure, its gains (PD: Kp = J wn^2, Kd = 2 zeta wn J with the design plant's inertia J;
LQR: the state-feedback gain K and the estimator gain L, the regulator and estimator poles),
its filters (roll-off, notch), its sample time, and the modes the design leaves out because the
loop cannot influence them (announced by controllers with a
:class:`controllers.RemovedModesWarning`; an LQR lists them in ``LQRDesign.removed_modes``).
"""

from __future__ import annotations

import dataclasses
import math
import warnings

import control
import numpy as np

import controllers

from .verdicts import s_plane_poles

__all__ = ["Tuned", "tune", "controller_arguments", "digital_facts", "rigid_crossover"]


@dataclasses.dataclass
class Tuned:
    """A controller tuned on a design plant.

    Attributes
    ----------
    controller : control.StateSpace
        Inputs ``theta_ref``, ``theta``, ``omega``; output ``torque``; continuous (dt = 0) or
        digital (dt = sample time).
    description : dict
        JSON-ready: ``kind``, ``structure`` (the control law in words), gains and filters,
        ``sample_time`` [s] (None: continuous), ``n_states``.
    removed_modes : list of str
        The modes the design leaves out, one line each, with the reason.
    """

    controller: control.StateSpace
    description: dict
    removed_modes: list


def _poles(values, sample_time: float | None = None) -> list:
    """Poles as ``{"re", "im"}`` [1/s], a digital design's mapped from the z-plane
    (:func:`spacecraft.design.verdicts.s_plane_poles`)."""
    return [{"re": float(z.real), "im": float(z.imag)}
            for z in s_plane_poles(values, sample_time)]


def tune(kind: str, plant: control.StateSpace, spec, *, feedforward: bool = False) -> Tuned:
    """Tune the controller ``kind`` ("pd" or "lqr") of a scene's controller table on a plant
    (or take it as given: ``spec.given`` of that kind, :mod:`spacecraft.scene.given`).

    Parameters
    ----------
    kind : str
    plant : control.StateSpace
        Design plant (inputs ``torque``; outputs ``theta``, ``omega``).
    spec : spacecraft.scene.read.ControllerSpec
    feedforward : bool
        Tune the controller to take a profile's rate reference ``omega_ref`` [rad/s] and
        feedforward torque ``torque_ff`` [N m] besides theta_ref (the same gains:
        :func:`controllers.pd`, :func:`controllers.lqr`).

    Returns
    -------
    Tuned

    Raises
    ------
    ValueError, TypeError
        From controllers (the runner turns them into a SceneError naming the key).
    """
    given = getattr(spec, "given", None)
    if given is not None and given.kind == kind:
        return _given(given, spec.sample_time)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", controllers.RemovedModesWarning)
        if kind == "pd":
            tuned = _pd(plant, spec, feedforward)
        else:
            with np.errstate(all="ignore"), warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                tuned = _lqr(plant, spec, feedforward)
    removed = [" ".join(str(w.message).split()) for w in caught
               if issubclass(w.category, controllers.RemovedModesWarning)]
    for w in caught:  # anything else goes on to the caller's record
        if not issubclass(w.category, controllers.RemovedModesWarning):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if not tuned.removed_modes:
        tuned.removed_modes = removed
    K = tuned.controller
    if K.dt is None:
        # a static-gain StateSpace gets dt=None from python-control; it is a continuous-time
        # controller
        K = control.ss(K.A, K.B, K.C, K.D, 0, inputs=list(K.input_labels),
                       outputs=list(K.output_labels), name=K.name)
        tuned.controller = K
    tuned.description["n_states"] = int(K.nstates)
    tuned.description["sample_time"] = spec.sample_time
    return tuned


def _given(given, sample_time: float | None) -> Tuned:
    """The scene's given controller (:mod:`spacecraft.scene.given`): not tuned."""
    from ..scene.given import given_state_space

    K = given_state_space(given, sample_time)
    description = {"kind": given.kind, "given": True,
                   "structure": (f"given in the scene (controller.given): {K.nstates} states, "
                                 + ("torques about x, y, z from theta_ref, theta and omega "
                                    "about x, y, z" if given.three_axis else
                                    "torque from theta_ref, theta and omega") + "; not tuned"),
                   "A": [list(r) for r in given.A], "B": [list(r) for r in given.B],
                   "C": [list(r) for r in given.C], "D": [list(r) for r in given.D],
                   "n_states": int(K.nstates), "sample_time": sample_time}
    return Tuned(K, description, [])


def controller_arguments(kind: str, spec, plant, feedforward: bool = False) -> dict:
    """The keyword arguments of :func:`controllers.pd` or :func:`controllers.lqr_design` for
    a scene's controller table (:class:`~spacecraft.scene.specs.ControllerSpec`) on a design
    plant: the one mapping from the scene's settings to the controllers' arguments.

    A three-axis plant's LQR weighs the tip deflections in both planes by
    ``deflection_weight`` [1/m^2] (its twists [rad] are not deflections)."""
    if kind == "pd":
        p = spec.pd
        return dict(natural_frequency=p.natural_frequency, bandwidth=p.bandwidth,
                    damping=p.damping, roll_off=p.roll_off, notch=p.notch,
                    sample_time=spec.sample_time, feedforward=feedforward)
    q = spec.lqr
    weight = q.deflection_weight
    if weight is not None and "torque" not in plant.input_labels:
        weight = {name: weight for name in plant.output_labels
                  if name.endswith(("_tip_deflection_y", "_tip_deflection_z"))}
    return dict(attitude_weight=q.attitude_weight, rate_weight=q.rate_weight,
                torque_weight=q.torque_weight, deflection_weight=weight,
                estimator_speed=q.estimator_speed, sample_time=spec.sample_time,
                feedforward=feedforward)


def _pd(plant, spec, feedforward: bool = False) -> Tuned:
    p = spec.pd
    K = controllers.pd(plant, **controller_arguments("pd", spec, plant, feedforward))
    J = controllers.rigid_body_inertia(plant)
    wn = (p.natural_frequency if p.natural_frequency is not None
          else controllers.natural_frequency_from_bandwidth(p.bandwidth, p.damping))
    Kp, Kd = controllers.pd_gains(J, wn, p.damping)
    notch = p.notch
    if notch == "first_mode":
        notch = float(controllers.flexible_modes(plant)[0].frequency)
    filters = (["N(s) notch"] if notch is not None else []) + (
        ["F(s) roll-off"] if p.roll_off is not None else [])
    law = ("Kp (theta_ref - theta) + Kd (omega_ref - omega)" if feedforward
           else "Kp (theta_ref - theta) - Kd omega")
    structure = (f"torque = {' '.join(f.split()[0] for f in filters)} [{law}]" if filters
                 else f"torque = {law}") + (" + torque_ff" if feedforward else "")
    description = {
        "kind": "pd", "structure": structure, "inertia": J, "natural_frequency": wn,
        "damping": p.damping, "Kp": Kp, "Kd": Kd, "roll_off": p.roll_off, "notch": notch,
        "notch_spec": p.notch if isinstance(p.notch, str) else None,
        "feedforward": feedforward,
    }
    if np.ndim(J) == 2:
        # three axes: the gains about each principal axis of the design inertia
        description["principal_moments"] = controllers.principal_axes(J)[0]
    return Tuned(K, description, [])


def _lqr(plant, spec, feedforward: bool = False) -> Tuned:
    q = spec.lqr
    design = controllers.lqr_design(plant, **controller_arguments("lqr", spec, plant,
                                                                   feedforward))
    n = design.controller.nstates
    J = controllers.rigid_body_inertia(plant)
    # rigid-body regulator frequency (q / (r J^2))^(1/4) about each principal axis
    moments = controllers.principal_axes(J)[0] if np.ndim(J) == 2 else np.array([J])
    frequencies = (q.attitude_weight / q.torque_weight) ** 0.25 / np.sqrt(moments)
    K = np.asarray(design.K, dtype=float)
    description = {
        "kind": "lqr",
        "structure": (("torque = -K (x_hat - x_ref theta_ref - x_rate omega_ref) + torque_ff"
                       if feedforward else "torque = -K (x_hat - x_ref theta_ref)")
                      + ", x_hat from a Kalman filter on theta and omega (output feedback; "
                      "x_hat: the design model's states)"),
        "feedforward": feedforward,
        "attitude_weight": q.attitude_weight, "rate_weight": q.rate_weight,
        "torque_weight": q.torque_weight, "deflection_weight": q.deflection_weight,
        "estimator_speed": q.estimator_speed,
        "rigid_body_frequency": float(frequencies.max()),
        # K: one row of gains per torque (planar: the row itself)
        "K": K.reshape(-1).tolist() if K.shape[0] == 1 else K.tolist(),
        "L": np.asarray(design.L, dtype=float).tolist(),
        "states": list(design.design_plant.state_labels) if design.design_plant is not None
        else [f"x{i}" for i in range(n)],
        # [1/s]: a digital design's z-plane poles mapped by s = ln(z) / T
        "regulator_poles": _poles(design.regulator_poles, spec.sample_time),
        "estimator_poles": _poles(design.estimator_poles, spec.sample_time),
    }
    if np.ndim(J) == 2:
        description["principal_moments"] = moments
        description["rigid_body_frequencies"] = frequencies
    # the reason says "<=": words read the same in the Markdown, HTML and the terminal
    removed = [f"{m}: left out ({m.reason.replace('<=', 'at most')})"
               for m in design.removed_modes]
    return Tuned(design.controller, description, removed)


def rigid_crossover(plant, controller) -> float | None:
    """The loop's rigid-body gain crossover [rad/s]: the lowest frequency where |L(j omega)|
    (three axes: its largest singular value) falls through 1 (interpolated linearly in log |L|
    against log omega between grid points), None if |L| never does.

    Where a lightly damped mode lifts |L| above 1 again, :func:`controllers.margins` may report
    that resonance crossing (the worst phase margin); the bandwidth a sample rate must support
    is this one (Franklin, Powell & Workman, Digital Control of Dynamic Systems, 3rd ed.,
    ch. 11, sample-rate selection).
    """
    with np.errstate(all="ignore"):
        omega, L = controllers.loop_frequency_response(plant, controller)
        L = np.asarray(L).reshape(omega.size, -1)
        # three axes: the largest gain sigma_max(L), the fastest direction's crossover
        g = np.log(np.abs(L[:, 0]) if L.shape[1] == 1 else
                   np.linalg.svd(L.reshape(omega.size, 3, 3), compute_uv=False)[:, 0])
    finite = np.isfinite(g)
    omega, g = omega[finite], g[finite]
    down = np.nonzero((g[:-1] > 0.0) & (g[1:] <= 0.0))[0]
    if down.size == 0:
        return None
    k = int(down[0])
    t = g[k] / (g[k] - g[k + 1])
    return float(math.exp(math.log(omega[k]) + t * (math.log(omega[k + 1]) -
                                                    math.log(omega[k]))))


def digital_facts(sample_time: float | None, crossover: float | None) -> dict | None:
    """Sample rate [Hz], Nyquist frequency [rad/s] and the zero-order hold's phase lag
    omega_c T / 2 [deg] at the loop's rigid-body crossover omega_c [rad/s]
    (:func:`rigid_crossover`; Franklin, Powell & Workman,
    Digital Control of Dynamic Systems, 3rd ed., sec. 6.3); None for a continuous loop."""
    if sample_time is None:
        return None
    out = {"sample_time": sample_time, "sample_rate": 1.0 / sample_time,
           "nyquist_frequency": math.pi / sample_time}
    if crossover is not None and math.isfinite(crossover) and crossover > 0:
        out["crossover_frequency"] = crossover
        out["hold_phase_lag_at_crossover"] = math.degrees(crossover * sample_time / 2.0)
    return out
