"""Peer benchmark: the same closed-loop slew in Exudyn (optional; PyPI ``exudyn``).

Two Exudyn models of the rod:

1. The distributed beam itself, as an Exudyn user models a slender elastic rod: ``n``
   ``ObjectANCFCable2D`` elements (bending stiffness EJ, axial stiffness EA of the steel rod,
   mass per length rho*A), its first node clamped to the hub (``ObjectJointRevolute2D`` between
   the hub's and the cable's ``MarkerBodyRigid`` plus an ``ObjectConnectorTorsionalSpringDamper``
   of 1e8 N*m/rad, 1e7 times the rod's EJ/L, as a penalty on the relative rotation: an error of
   ~1e-7). Newton's absolute tolerance is set to 1e-6 (with the default, Exudyn's solver stalls on
   this slender free beam: minutes per simulated second). Free-free frequencies from
   ``ComputeODE2Eigenvalues`` on the unconstrained cable.
2. The rod as of identical panels as in the Basilisk peer
(:func:`peer_basilisk.panel_chain`: n panels of length L/n, root hinge 2 EJ/h, the others EJ/h),
built the way an Exudyn user builds a planar chain: ``ObjectRigidBody2D`` bodies (the hub, free
in the plane, and the panels), ``ObjectJointRevolute2D`` hinges and
``ObjectConnectorTorsionalSpringDamper`` springs. The PD torque on the hub
(``LoadTorqueVector`` with a Python user function reading the hub's rotation and angular velocity)
is evaluated at the solver's current state, i.e. continuous in time like flexsat's reference.
Integration: Exudyn's default implicit generalized-alpha solver with 100 steps per second.

Outputs sampled at 10 Hz (sensors): the hub angle and the elastic tip deflection (the free end's
position in hub axes minus the undeformed one). Errors against the same reference as flexsat's
models; ``agreement``: against flexsat's exact simulation of the same panel chain with the
continuous PD (the integration error of Exudyn alone).
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import time

import numpy as np

import controllers

from _common import (SLEW_ANGLE, SLEW_DURATION, paper_rod, pd_closed_loop, slew_errors,
                     slew_response)
from peer_basilisk import _pd_gains, panel_chain

__all__ = ["run", "simulate_exudyn", "simulate_exudyn_ancf", "ancf_free_frequencies"]

STEPS_PER_SECOND = 100


def _add_hub_pd(exu, mbs, hub_node, hub_marker, Kp, Kd):
    """The slew PD as a torque load on the hub (Python user function) and a hub sensor."""
    from exudyn.itemInterface import LoadTorqueVector, SensorNode

    rotation = exu.OutputVariableType.Rotation
    angular_velocity = exu.OutputVariableType.AngularVelocity

    def pd_torque(mbs, t, load):
        theta = mbs.GetNodeOutput(hub_node, rotation)[2]
        omega = mbs.GetNodeOutput(hub_node, angular_velocity)[2]
        ref = float(controllers.slew_profile(np.array([t]), SLEW_ANGLE, SLEW_DURATION)[0])
        return [0.0, 0.0, Kp * (ref - theta) - Kd * omega]

    mbs.AddLoad(LoadTorqueVector(markerNumber=hub_marker, loadVector=[0.0, 0.0, 0.0],
                                 loadVectorUserFunction=pd_torque))
    return mbs.AddSensor(SensorNode(nodeNumber=hub_node, storeInternal=True,
                                    outputVariableType=exu.OutputVariableType.Coordinates))


def simulate_exudyn(chain, *, t_final: float, record_dt: float):
    """Run the Exudyn model of a root-hinged chain of panels on the default hub.

    Returns (t, theta, tip, build_seconds, simulate_seconds).
    """
    import exudyn as exu
    from exudyn.itemInterface import (MarkerBodyRigid, MarkerNodeRigid, NodeRigidBody2D,
                                      ObjectConnectorTorsionalSpringDamper,
                                      ObjectJointRevolute2D, ObjectRigidBody2D, SensorBody)

    Kp, Kd = _pd_gains(chain)
    t0 = time.perf_counter()
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    hub_node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0.0, 0.0, 0.0]))
    hub = mbs.AddObject(ObjectRigidBody2D(nodeNumber=hub_node, mass=100.0, inertia=50.0))
    hub_marker = mbs.AddMarker(MarkerNodeRigid(nodeNumber=hub_node))
    previous, joint_position = hub, [0.5, 0.0, 0.0]
    x = 0.5
    last = hub
    for k in range(chain.n_bodies):
        h = float(chain.lengths[k])
        node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[x + h / 2.0, 0.0, 0.0]))
        body = mbs.AddObject(ObjectRigidBody2D(nodeNumber=node, mass=float(chain.masses[k]),
                                               inertia=float(chain.inertias[k])))
        a = mbs.AddMarker(MarkerBodyRigid(bodyNumber=previous, localPosition=joint_position))
        b = mbs.AddMarker(MarkerBodyRigid(bodyNumber=body, localPosition=[-h / 2.0, 0.0, 0.0]))
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[a, b]))
        mbs.AddObject(ObjectConnectorTorsionalSpringDamper(
            markerNumbers=[a, b], stiffness=float(chain.hinge_stiffnesses[k]), damping=0.0))
        previous, joint_position, last = body, [h / 2.0, 0.0, 0.0], body
        x += h
    length = x - 0.5
    hub_sensor = _add_hub_pd(exu, mbs, hub_node, hub_marker, Kp, Kd)
    tip_sensor = mbs.AddSensor(SensorBody(bodyNumber=last, localPosition=[joint_position[0], 0, 0],
                                          storeInternal=True,
                                          outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = int(round(t_final * STEPS_PER_SECOND))
    settings.timeIntegration.endTime = t_final
    settings.timeIntegration.verboseMode = 0
    settings.solutionSettings.sensorsWritePeriod = record_dt
    settings.solutionSettings.writeSolutionToFile = False
    settings.displayStatistics = False
    t1 = time.perf_counter()
    mbs.SolveDynamic(settings)
    t2 = time.perf_counter()
    hub_data = mbs.GetSensorStoredData(hub_sensor)
    tip_data = mbs.GetSensorStoredData(tip_sensor)
    t = hub_data[:, 0]
    X, Y, theta = hub_data[:, 1], hub_data[:, 2], hub_data[:, 3]
    px, py = tip_data[:, 1] - X, tip_data[:, 2] - Y
    # free end in hub axes; its undeformed position is (0.5 + L, 0)
    tip = -np.sin(theta) * px + np.cos(theta) * py
    del length
    return t, theta, tip, t1 - t0, t2 - t1


ROD_AXIAL_STIFFNESS = 2.06e11 * 3.141592653589793 * 0.01**2 / 4.0  # E A of the paper's rod [N]


def _ancf_cable(mbs, beam, n_elements: int, x0: float):
    from exudyn.itemInterface import NodePoint2DSlope1, ObjectANCFCable2D

    h = beam.length / n_elements
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[x0 + i * h, 0.0, 1.0, 0.0]))
             for i in range(n_elements + 1)]
    return [mbs.AddObject(ObjectANCFCable2D(
        nodeNumbers=[nodes[i], nodes[i + 1]], physicsLength=h,
        physicsMassPerLength=beam.linear_density, physicsBendingStiffness=beam.bending_stiffness,
        physicsAxialStiffness=ROD_AXIAL_STIFFNESS)) for i in range(n_elements)], h


def ancf_free_frequencies(beam, n_elements: int, n: int = 2):
    """First n free-free bending frequencies [rad/s] of the ANCF cable, and the seconds spent."""
    import exudyn as exu

    t0 = time.perf_counter()
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    _ancf_cable(mbs, beam, n_elements, 0.0)
    mbs.Assemble()
    values, _ = mbs.ComputeODE2Eigenvalues()
    w = np.sort(np.sqrt(np.abs(np.asarray(values))))
    # three rigid-body modes come out at ~1e-4 rad/s (round-off); the first bending is 2.87
    elastic = w[w > 1e-2 * beam.natural_frequencies(1)[0]]
    return elastic[:n], time.perf_counter() - t0


def simulate_exudyn_ancf(beam, n_elements: int, *, t_final: float, record_dt: float):
    """Hub + ANCF cable beam + PD in Exudyn. Returns (t, theta, tip, build_s, simulate_s)."""
    import exudyn as exu
    from exudyn.itemInterface import (MarkerBodyRigid, MarkerNodeRigid, NodeRigidBody2D,
                                      ObjectConnectorTorsionalSpringDamper,
                                      ObjectJointRevolute2D, ObjectRigidBody2D, SensorBody)

    Kp, Kd = _pd_gains(beam.truncated(8))  # the PD depends only on the total inertia
    t0 = time.perf_counter()
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    hub_node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0.0, 0.0, 0.0]))
    hub = mbs.AddObject(ObjectRigidBody2D(nodeNumber=hub_node, mass=100.0, inertia=50.0))
    hub_marker = mbs.AddMarker(MarkerNodeRigid(nodeNumber=hub_node))
    elements, h = _ancf_cable(mbs, beam, n_elements, 0.5)
    a = mbs.AddMarker(MarkerBodyRigid(bodyNumber=hub, localPosition=[0.5, 0.0, 0.0]))
    b = mbs.AddMarker(MarkerBodyRigid(bodyNumber=elements[0], localPosition=[0.0, 0.0, 0.0]))
    mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[a, b]))
    mbs.AddObject(ObjectConnectorTorsionalSpringDamper(markerNumbers=[a, b], stiffness=1e8,
                                                       damping=0.0))
    hub_sensor = _add_hub_pd(exu, mbs, hub_node, hub_marker, Kp, Kd)
    tip_sensor = mbs.AddSensor(SensorBody(bodyNumber=elements[-1], localPosition=[h, 0.0, 0.0],
                                          storeInternal=True,
                                          outputVariableType=exu.OutputVariableType.Position))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps = int(round(t_final * STEPS_PER_SECOND))
    settings.timeIntegration.endTime = t_final
    settings.timeIntegration.verboseMode = 0
    settings.timeIntegration.newton.absoluteTolerance = 1e-6
    settings.solutionSettings.sensorsWritePeriod = record_dt
    settings.solutionSettings.writeSolutionToFile = False
    settings.displayStatistics = False
    t1 = time.perf_counter()
    mbs.SolveDynamic(settings)
    t2 = time.perf_counter()
    hub_data = mbs.GetSensorStoredData(hub_sensor)
    tip_data = mbs.GetSensorStoredData(tip_sensor)
    t = hub_data[:, 0]
    X, Y, theta = hub_data[:, 1], hub_data[:, 2], hub_data[:, 3]
    px, py = tip_data[:, 1] - X, tip_data[:, 2] - Y
    tip = -np.sin(theta) * px + np.cos(theta) * py
    return t, theta, tip, t1 - t0, t2 - t1


def _ancf_rows(quick: bool, reference: dict, exact: dict) -> list:
    import warnings

    beam = paper_rod()
    rows = []
    for n in ([2, 4] if quick else [2, 4, 8, 16]):
        row = {"model": "Exudyn ANCF beam (gen.-alpha)", "n_elements": n}
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", DeprecationWarning)
                w, eig_time = ancf_free_frequencies(beam, n)
                row["poles"] = float(np.max(np.abs(w / exact["poles"][: w.size] - 1.0)))
                row["time_eigen"] = eig_time
                t, theta, tip, build, _ = simulate_exudyn_ancf(beam, n, t_final=200.0,
                                                               record_dt=0.1)
            grid = min(t.size, reference["t"].size)
            if not np.allclose(t[:grid], reference["t"][:grid], atol=1e-6):
                raise RuntimeError("Exudyn's sensor times do not match the 10 Hz grid")
            errors = slew_errors({"theta": theta[:grid], "tip": tip[:grid],
                                  "torque": np.zeros(grid)},
                                 {k: reference[k][:grid] for k in ("theta", "tip", "torque")})
            row["slew_theta"], row["slew_tip"] = errors["theta"], errors["tip"]
            times = []
            for _ in range(3):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", DeprecationWarning)
                    _, _, _, b, s = simulate_exudyn_ancf(beam, n, t_final=100.0, record_dt=0.01)
                times.append((b, s))
            row["time_build"] = float(np.median([b for b, _ in times]))
            row["time_sim"] = float(np.median([s for _, s in times]))
        except Exception as exc:
            row["failure"] = f"{type(exc).__name__}: {exc}"
        rows.append(row)
        print(f"  Exudyn ANCF n={n}: " + ", ".join(
            f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()),
            flush=True)
    return rows


def run(*, quick: bool, reference: dict, exact: dict) -> dict:
    """Benchmark Exudyn on panel chains of several sizes (see the module docstring)."""
    import importlib.metadata
    import warnings

    import exudyn  # noqa: F401  (ImportError -> "not installed")

    beam = paper_rod()
    sizes = [1, 2, 4] if quick else [1, 2, 3, 4, 6, 8]
    rows = []
    notes = [f"exudyn {importlib.metadata.version('exudyn')}; default implicit "
             "generalized-alpha solver, 100 steps/s; ANCF: Newton absolute tolerance 1e-6"]
    for n in sizes:
        chain = panel_chain(beam, n)
        row = {"model": "Exudyn panels (gen.-alpha)", "n_panels": n}
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", DeprecationWarning)
                t, theta, tip, build, sim_200 = simulate_exudyn(chain, t_final=200.0,
                                                                record_dt=0.1)
            grid = min(t.size, reference["t"].size)
            if not np.allclose(t[:grid], reference["t"][:grid], atol=1e-6):
                raise RuntimeError("Exudyn's sensor times do not match the 10 Hz grid")
            response = {"theta": theta[:grid], "tip": tip[:grid], "torque": np.zeros(grid)}
            ref = {k: reference[k][:grid] for k in ("theta", "tip", "torque")}
            errors = slew_errors(response, ref)
            row["slew_theta"], row["slew_tip"] = errors["theta"], errors["tip"]
            same = slew_response(pd_closed_loop(chain)[2])
            same = {k: v[:grid] for k, v in same.items()}
            agree = slew_errors(response, same)
            row["agreement_theta"], row["agreement_tip"] = agree["theta"], agree["tip"]
            row["flexsat_same_chain_slew_tip"] = slew_errors(same, ref)["tip"]
            # first free-free pole of the panel chain (one panel behind a root hinge has none)
            row["poles"] = (float(abs(chain.poles()[0] / exact["poles"][0] - 1.0))
                            if n >= 2 else None)
            times = []
            for _ in range(3):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", DeprecationWarning)
                    _, _, _, b, s = simulate_exudyn(chain, t_final=100.0, record_dt=0.01)
                times.append((b, s))
            row["time_build"] = float(np.median([b for b, _ in times]))
            row["time_sim"] = float(np.median([s for _, s in times]))
        except Exception as exc:
            row["failure"] = f"{type(exc).__name__}: {exc}"
        rows.append(row)
        print(f"  Exudyn n={n}: " + ", ".join(f"{k}={v:.3g}" if isinstance(v, float) else
                                              f"{k}={v}" for k, v in row.items()), flush=True)
    rows += _ancf_rows(quick, reference, exact)
    failed = [r for r in rows if "failure" in r]
    return {"status": "ok" if len(failed) < len(rows) else "failed", "rows": rows,
            "notes": notes, "reason": "; ".join(r["failure"] for r in failed)}
