"""Systems and exported FMUs shared by the FMI 3.0, sampled-FMU, FMU-state, derivative,
portability and SSP tests.

Every FMU is exported once per test session (:func:`exported` caches by name, FMI version and
options in a temporary folder removed at exit), so the test files can share them.

Systems
-------
- ``hub``: rigid hub J = 10 kg m^2 with one flexible mode (3 rad/s, damping 0.01,
  participation 0.5), theta = q + eta, omega = q_dot + eta_dot; input ``torque``.
- ``pd``: torque = 20 (theta_ref - theta) - 30 omega: no states, D != 0.
- ``plant`` and ``lqr``: the digital-LQR loop of the issue: a hub (J = 10 kg m^2) with two
  collocated modes (3 and 12 rad/s, damping 0.01) from :func:`plants.modal_plant`, and
  ``controllers.lqr(..., sample_time=T)`` with T = 0.05 s: a discrete LQR + predictor
  Kalman filter (6 states), inputs theta_ref, theta, omega, output torque, D = [g, 0, 0].
- ``sampled``: a sampled double integrator with feedthrough, x[k+1] = A x[k] + B u[k],
  y = C x + D u, T = 0.1 s (states q, q_dot; D = [0.5, 0]^T), simple enough for closed forms.
"""

from __future__ import annotations

import atexit
import functools
import shutil
import tempfile
from pathlib import Path

import control
import numpy as np

import controllers
import fmu
from plants import modal_plant

__all__ = ["J", "SAMPLE_TIME", "hub", "pd", "loop_plant", "lqr", "sampled", "SYSTEMS",
           "exported", "monolithic_sampled_loop", "jacobi_controller"]

J = 10.0  # hub inertia [kg m^2]
#: Sample period of the digital LQR [s]
SAMPLE_TIME = 0.05


def hub() -> control.StateSpace:
    w, z = 3.0, 0.01
    A = [[0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1], [0, 0, -w * w, -2 * z * w]]
    B = [[0], [1 / J], [0], [0.5 / J]]
    C = [[1, 0, 1, 0], [0, 1, 0, 1]]
    return control.ss(A, B, C, 0, inputs=["torque"], outputs=["theta", "omega"],
                      states=["q", "q_dot", "eta", "eta_dot"], name="hub")


def pd() -> control.StateSpace:
    return control.ss(np.zeros((0, 0)), np.zeros((0, 3)), np.zeros((1, 0)), [[20.0, -20.0, -30.0]],
                      inputs=["theta_ref", "theta", "omega"], outputs=["torque"], name="pd")


@functools.lru_cache(maxsize=None)
def _loop_plant() -> control.StateSpace:
    plant = modal_plant(J, [(3.0, 0.01, 0.05, 0.05), (12.0, 0.01, 0.03, 0.03)], disturbance=False)
    return control.ss(plant.A, plant.B, plant.C, plant.D, inputs=plant.input_labels,
                      outputs=plant.output_labels,
                      states=["q", "q_dot", "eta1", "eta1_dot", "eta2", "eta2_dot"], name="plant")


def loop_plant() -> control.StateSpace:
    return _loop_plant()


@functools.lru_cache(maxsize=None)
def _lqr() -> control.StateSpace:
    K = controllers.lqr(loop_plant(), attitude_weight=100.0, rate_weight=10.0, torque_weight=1.0,
                        sample_time=SAMPLE_TIME)
    return control.ss(K.A, K.B, K.C, K.D, K.dt, inputs=K.input_labels, outputs=K.output_labels,
                      states=[f"xhat{i}" for i in range(K.nstates)], name="lqr")


def lqr() -> control.StateSpace:
    return _lqr()


def sampled() -> control.StateSpace:
    T = 0.1
    A = [[1.0, T], [0.0, 1.0]]
    B = [[T * T / 2 / J], [T / J]]
    return control.ss(A, B, np.eye(2), [[0.5], [0.0]], T, inputs=["torque"],
                      outputs=["theta", "omega"], states=["q", "q_dot"], name="sampled")


SYSTEMS = {"hub": hub, "pd": pd, "plant": loop_plant, "lqr": lqr, "sampled": sampled}

_folder = Path(tempfile.mkdtemp(prefix="flexsat-test-fmus-"))
atexit.register(shutil.rmtree, _folder, True)


@functools.lru_cache(maxsize=None)
def exported(name: str, version: str, **options) -> Path:
    """The system ``name`` exported as an FMI ``version`` FMU (cached for the session)."""
    suffix = "_".join(f"{k}{v}" for k, v in sorted(options.items()))
    path = _folder / f"{name}_{version[0]}{'_' + suffix if suffix else ''}.fmu"
    defaults = {"step": SAMPLE_TIME} if name == "plant" else {}
    defaults.update(options)
    return fmu.export(SYSTEMS[name](), path, fmi_version=version, model_name=name, **defaults)


def monolithic_sampled_loop(t_end: float, h: float, reference: float) -> dict[str, np.ndarray]:
    """The digital-LQR loop sampled exactly, on the grid t_k = k h (h = T / N, N whole).

    The plant is discretised with a zero-order hold at h; the controller samples every
    N = T / h grid points (from t = 0): u = C_c x_c + D_c [r; theta; omega] is held until
    its next sample, x_c <- A_c x_c + B_c [r; theta; omega]. For h = T this is
    ``control.interconnect([c2d(plant, T), K])`` (checked in the tests); for h < T it is
    the multirate loop that an FMU sampling every T shows to a master stepping every h.

    Returns
    -------
    dict of str to numpy.ndarray
        ``time``, ``theta``, ``omega``, ``torque`` on the grid (torque: the value held at
        t_k, as the controller FMU outputs it then).
    """
    N = int(round(SAMPLE_TIME / h))
    plant, K = loop_plant(), lqr()
    discrete = control.c2d(plant, h, "zoh")
    Phi, Gamma, C = (np.asarray(M) for M in (discrete.A, discrete.B, discrete.C))
    Ac, Bc, Cc, Dc = (np.asarray(M) for M in (K.A, K.B, K.C, K.D))
    n_steps = int(round(t_end / h))
    x, xc = np.zeros(Phi.shape[0]), np.zeros(Ac.shape[0])
    out = {name: np.zeros(n_steps + 1) for name in ("theta", "omega", "torque")}
    u = np.zeros(1)
    for k in range(n_steps + 1):
        y = C @ x
        if k % N == 0:
            v = np.array([reference, y[0], y[1]])
            u = Cc @ xc + Dc @ v
            xc = Ac @ xc + Bc @ v
        out["theta"][k], out["omega"][k], out["torque"][k] = y[0], y[1], u[0]
        x = Phi @ x + Gamma @ u
    out["time"] = np.arange(n_steps + 1) * h
    return out


def jacobi_controller(controller_d):
    """Discrete controller whose feedthrough acts through a one-step delay state z."""
    Phi, Gamma = np.asarray(controller_d.A), np.asarray(controller_d.B)
    C, D = np.asarray(controller_d.C), np.asarray(controller_d.D)
    n, m = Gamma.shape
    A = np.block([[Phi, np.zeros((n, m))], [np.zeros((m, n)), np.zeros((m, m))]])
    B = np.vstack([Gamma, np.eye(m)])
    return control.ss(A, B, np.hstack([C, D]), np.zeros_like(D), controller_d.dt,
                      inputs=controller_d.input_labels, outputs=controller_d.output_labels)
