"""Peer benchmark: the same closed-loop slew in Basilisk (optional; PyPI ``bsk``).

A Basilisk user models the rod as panels on hinges: one panel
(``hingedRigidBodyStateEffector``) or a chain of identical panels
(``nHingedRigidBodyStateEffector``, which accepts only panels of the same mass and
half-length d). The discretisation used here: n panels of length h = L/n, frozen pieces of the rod
(mass m/n, inertia (m/n) h**2/12 about the panel's centre), hinges at x = 0, h, ..., (n-1) h.
Each hinge gets the bending stiffness of the beam segment it replaces, EJ/h, and the root
hinge, which replaces only the half segment [0, h/2], gets 2 EJ/h (the rule of the rigid finite
element method, Wittbrodt et al. 2006). The hub (100 kg, 50 kg*m^2 about z) moves freely in
6 DOF (no gravity body, so no gravity); the panels hang at (0.5, 0, 0) m along +x with
``dcm_HB = [[-1, 0, 0], [0, 0, 1], [0, 1, 0]]`` (hinge axis = body z).

The PD law (the same gains as flexsat's, designed on the same panel chain: Kp = J wn**2,
Kd = 2 zeta wn J) runs as a Python module every 0.01 s and commands ``extForceTorque``; the
dynamics are integrated by Basilisk's fixed-step RK4 with the largest step <= 0.01 s that keeps
RK4 stable and accurate for the chain's top mode (omega_max dt <= 1).

Outputs: the hub angle theta = 4 atan(sigma_z) and the elastic tip deflection
sum_i h sin(theta_1 + ... + theta_i) (panel angles relative to the previous panel), sampled
at 10 Hz for 200 s. Errors against the same reference as flexsat's models (hub + Craig-Bampton
beam, continuous PD); ``agreement`` compares Basilisk with flexsat's exact simulation of the
*same* panel chain with the same digital PD (controllers.pd(..., sample_time=0.01)), i.e. the
integration error of Basilisk alone.
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import math
import time

import numpy as np

from _common import (PD_DAMPING, PD_NATURAL_FREQUENCY, SLEW_ANGLE, SLEW_DURATION, paper_rod,
                     slew_errors, slew_response, spacecraft_with)

__all__ = ["run", "panel_chain", "simulate_basilisk"]

DT_CONTROL = 0.01


def panel_chain(beam, n_panels: int):
    """The flexsat HingedChain with the same panels as the Basilisk model."""
    from appendages.chain import HingedChain

    h = beam.length / n_panels
    m = beam.mass / n_panels
    stiffness = np.full(n_panels, beam.bending_stiffness / h)
    stiffness[0] = 2.0 * beam.bending_stiffness / h
    return HingedChain([h] * n_panels, [m] * n_panels, [m * h * h / 12.0] * n_panels, stiffness,
                       root="hinged")


def _pd_gains(chain):
    import controllers

    plant = spacecraft_with(chain).plant()
    J = controllers.rigid_body_inertia(plant)
    return controllers.pd_gains(J, PD_NATURAL_FREQUENCY, PD_DAMPING)


def simulate_basilisk(chain, *, t_final: float, record_dt: float, dt_dynamics: float):
    """Run the Basilisk model of ``chain`` (a root-hinged chain of identical panels).

    Returns (t, theta, tip, build_seconds, simulate_seconds).
    """
    from Basilisk.architecture import messaging, sysModel
    from Basilisk.simulation import (extForceTorque, hingedRigidBodyStateEffector,
                                     nHingedRigidBodyStateEffector, spacecraft)
    from Basilisk.utilities import SimulationBaseClass, macros

    import controllers

    Kp, Kd = _pd_gains(chain)
    t0 = time.perf_counter()
    n = chain.n_bodies
    h = float(chain.lengths[0])
    m = float(chain.masses[0])
    J = float(chain.inertias[0])
    sim = SimulationBaseClass.SimBaseClass()
    process = sim.CreateNewProcess("process")
    # higher priority runs first at a common time: the PD reads the state just integrated
    process.addTask(sim.CreateNewTask("dynamics", macros.sec2nano(dt_dynamics)), 100)
    process.addTask(sim.CreateNewTask("control", macros.sec2nano(DT_CONTROL)), 50)

    craft = spacecraft.Spacecraft()
    craft.ModelTag = "hub"
    craft.hub.mHub = 100.0
    craft.hub.r_BcB_B = [[0.0], [0.0], [0.0]]
    craft.hub.IHubPntBc_B = [[50.0, 0.0, 0.0], [0.0, 50.0, 0.0], [0.0, 0.0, 50.0]]
    dcm_HB = [[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]
    inertia = [[J, 0.0, 0.0], [0.0, J, 0.0], [0.0, 0.0, J]]
    if n == 1:
        panel = hingedRigidBodyStateEffector.HingedRigidBodyStateEffector()
        panel.mass, panel.d = m, h / 2.0
        panel.k, panel.c = float(chain.hinge_stiffnesses[0]), 0.0
        panel.IPntS_S = inertia
        panel.r_HB_B = [[0.5], [0.0], [0.0]]
        panel.dcm_HB = dcm_HB
        panel.thetaInit, panel.thetaDotInit = 0.0, 0.0
        panel_messages = [panel.hingedRigidBodyOutMsg]
    else:
        panel = nHingedRigidBodyStateEffector.NHingedRigidBodyStateEffector()
        panel.r_HB_B = [[0.5], [0.0], [0.0]]
        panel.dcm_HB = dcm_HB
        for k in range(n):
            piece = nHingedRigidBodyStateEffector.HingedPanel()
            piece.mass, piece.d = m, h / 2.0
            piece.k, piece.c = float(chain.hinge_stiffnesses[k]), 0.0
            piece.IPntS_S = inertia
            piece.thetaInit, piece.thetaDotInit = 0.0, 0.0
            panel.addHingedPanel(piece)
        panel_messages = None
    craft.addStateEffector(panel)
    torque = extForceTorque.ExtForceTorque()
    torque.ModelTag = "torque"
    craft.addDynamicEffector(torque)

    class PD(sysModel.SysModel):
        """torque_z = Kp (theta_ref - theta) - Kd omega_z, from the hub's state message."""

        def __init__(self):
            super().__init__()
            self.stateInMsg = messaging.SCStatesMsgReader()
            self.torqueOutMsg = messaging.CmdTorqueBodyMsg()

        def Reset(self, CurrentSimNanos):
            self.torqueOutMsg.write(messaging.CmdTorqueBodyMsgPayload(), CurrentSimNanos,
                                    self.moduleID)

        def UpdateState(self, CurrentSimNanos):
            state = self.stateInMsg()
            theta = 4.0 * math.atan(state.sigma_BN[2])
            omega = state.omega_BN_B[2]
            t = CurrentSimNanos * 1e-9
            ref = float(controllers.slew_profile(np.array([t]), SLEW_ANGLE, SLEW_DURATION)[0])
            payload = messaging.CmdTorqueBodyMsgPayload()
            payload.torqueRequestBody = [0.0, 0.0, Kp * (ref - theta) - Kd * omega]
            self.torqueOutMsg.write(payload, CurrentSimNanos, self.moduleID)

    pd = PD()
    pd.ModelTag = "pd"
    pd.stateInMsg.subscribeTo(craft.scStateOutMsg)
    torque.cmdTorqueInMsg.subscribeTo(pd.torqueOutMsg)
    sim.AddModelToTask("dynamics", craft)
    sim.AddModelToTask("dynamics", torque)
    sim.AddModelToTask("control", pd)
    recorders = [craft.scStateOutMsg.recorder(macros.sec2nano(record_dt))]
    if panel_messages is None:
        panel_messages = [panel.nHingedRigidBodyOutMsgs[k] for k in range(n)]
    recorders += [msg.recorder(macros.sec2nano(record_dt)) for msg in panel_messages]
    for recorder in recorders:
        sim.AddModelToTask("dynamics", recorder)
    sim.InitializeSimulation()
    t1 = time.perf_counter()
    sim.ConfigureStopTime(macros.sec2nano(t_final))
    sim.ExecuteSimulation()
    t2 = time.perf_counter()
    t = recorders[0].times() * 1e-9
    sigma = np.asarray(recorders[0].sigma_BN)
    theta = 4.0 * np.arctan(sigma[:, 2])
    angles = np.column_stack([np.asarray(r.theta).reshape(-1) for r in recorders[1:]])
    tip = np.sum(h * np.sin(np.cumsum(angles, axis=1)), axis=1)
    return t, theta, tip, t1 - t0, t2 - t1


def _dynamics_step(chain) -> float:
    """Largest step <= 0.01 s dividing 0.01 s with omega_max dt <= 1 (RK4 accurate, stable)."""
    w_max = float(spacecraft_with(chain).modes()[0].max())
    k = max(1, math.ceil(w_max * DT_CONTROL / 1.0))
    return DT_CONTROL / k


def run(*, quick: bool, reference: dict, exact: dict) -> dict:
    """Benchmark Basilisk on panel chains of several sizes (see the module docstring)."""
    import Basilisk  # noqa: F401  (ImportError -> "not installed")
    import importlib.metadata

    import controllers

    beam = paper_rod()
    sizes = [1, 2, 4] if quick else [1, 2, 3, 4, 6, 8]
    rows = []
    notes = [f"bsk {importlib.metadata.version('bsk')}"]
    for n in sizes:
        chain = panel_chain(beam, n)
        dt_dyn = _dynamics_step(chain)
        row = {"model": "Basilisk panels (RK4)", "n_panels": n, "dt_dynamics": dt_dyn}
        try:
            t, theta, tip, build, sim_200 = simulate_basilisk(
                chain, t_final=200.0, record_dt=0.1, dt_dynamics=dt_dyn)
            grid = min(t.size, reference["t"].size)
            if not np.allclose(t[:grid], reference["t"][:grid], atol=1e-9):
                raise RuntimeError("Basilisk's recorder times do not match the 10 Hz grid")
            response = {"theta": theta[:grid], "tip": tip[:grid],
                        "torque": np.zeros(grid)}
            ref = {k: reference[k][:grid] for k in ("theta", "tip", "torque")}
            errors = slew_errors(response, ref)
            row["slew_theta"], row["slew_tip"] = errors["theta"], errors["tip"]
            # flexsat's exact simulation of the same panel chain with the same digital PD
            plant = spacecraft_with(chain).plant(tip_deflection=True)
            pd = controllers.pd(plant, natural_frequency=PD_NATURAL_FREQUENCY,
                                damping=PD_DAMPING, sample_time=DT_CONTROL)
            loop = controllers.close_loop(plant, pd)
            same = slew_response(loop, dt=DT_CONTROL)
            stride = int(round(0.1 / DT_CONTROL))
            same = {k: v[::stride][:grid] for k, v in same.items()}
            agree = slew_errors(response, {**same, "torque": np.ones(grid)})
            row["agreement_theta"], row["agreement_tip"] = agree["theta"], agree["tip"]
            continuous = controllers.pd(plant, natural_frequency=PD_NATURAL_FREQUENCY,
                                        damping=PD_DAMPING)
            chain_errors = slew_errors(slew_response(controllers.close_loop(plant, continuous)),
                                       reference)
            row["flexsat_same_chain_slew_tip"] = chain_errors["tip"]
            # first free-free pole of the panel chain (one panel behind a root hinge has none)
            row["poles"] = (float(abs(chain.poles()[0] / exact["poles"][0] - 1.0))
                            if n >= 2 else None)
            # timing: build and 100 s at 100 Hz control rate
            times = []
            for _ in range(3):
                _, _, _, b, s = simulate_basilisk(chain, t_final=100.0, record_dt=0.01,
                                                  dt_dynamics=dt_dyn)
                times.append((b, s))
            row["time_build"] = float(np.median([b for b, _ in times]))
            row["time_sim"] = float(np.median([s for _, s in times]))
        except Exception as exc:
            row["failure"] = f"{type(exc).__name__}: {exc}"
        rows.append(row)
        print(f"  Basilisk n={n}: " + ", ".join(f"{k}={v:.3g}" if isinstance(v, float) else
                                                f"{k}={v}" for k, v in row.items()), flush=True)
    failed = [r for r in rows if "failure" in r]
    return {"status": "ok" if len(failed) < len(rows) else "failed", "rows": rows,
            "notes": notes, "reason": "; ".join(r["failure"] for r in failed)}
