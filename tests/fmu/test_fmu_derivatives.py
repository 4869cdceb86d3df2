"""Directional derivatives (FMI 2.0 and 3.0) and adjoint derivatives (FMI 3.0) against
python-control's matrices and against finite differences of the FMU's own outputs.

The partial derivatives of the linear model are the entries of [[C, D], [A, B]] (rows:
outputs, state derivatives; columns: states, inputs). With unit seeds the FMU returns single
entries times 1.0 plus exact zeros, so they must equal the matrices bit for bit. For a
random seed the sum has k = n + m terms: |error| <= 2 k eps sum |J_ij s_j| (Higham 2002,
eq. (3.5)). Finite differences of a linear map are exact up to the round-off of the two
evaluations, ~ eps |f| / delta: with delta = 1e-3 and |f| of order 1, 1e-9 is generous.

A sampled system's only partial derivatives are those of its outputs by its inputs: D at a
sample instant still to be taken, 0 between samples (the outputs are held).
"""

import ctypes

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model, FMU2Slave
from fmpy.fmi3 import FMU3Model, FMU3Slave

from fmu_cases import SAMPLE_TIME, exported, hub, lqr

VERSIONS = ["2.0", "3.0"]
EPS = np.finfo(np.float64).eps
STATES = ("q", "q_dot", "eta", "eta_dot")


def open_instance(name, version, interface):
    path = exported(name, version)
    description = read_model_description(str(path))
    if interface == "me":
        kind = FMU3Model if version == "3.0" else FMU2Model
        identifier = description.modelExchange.modelIdentifier
    else:
        kind = FMU3Slave if version == "3.0" else FMU2Slave
        identifier = description.coSimulation.modelIdentifier
    instance = kind(guid=description.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=identifier, instanceName="d")
    instance.instantiate()
    if version == "3.0":
        instance.enterInitializationMode(startTime=0.0)
    else:
        instance.setupExperiment(startTime=0.0)
        instance.enterInitializationMode()
    instance.exitInitializationMode()
    if interface == "me":
        if version == "3.0":
            instance.updateDiscreteStates()
        else:
            instance.newDiscreteStates()
        instance.enterContinuousTimeMode()
    return instance, {v.name: v.valueReference for v in description.modelVariables}


def directional(instance, version, unknowns, knowns, seed):
    """fmi2GetDirectionalDerivative / fmi3GetDirectionalDerivative (fmpy names both alike)."""
    return np.array(instance.getDirectionalDerivative(unknowns, knowns, list(seed)))


def reference_jacobian():
    system = hub()
    A, B, C, D = (np.asarray(M, dtype=float) for M in (system.A, system.B, system.C, system.D))
    return np.block([[C, D], [A, B]])


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("interface", ["me", "cs"])
def test_unit_seeds_give_the_matrices_exactly(version, interface):
    instance, vr = open_instance("hub", version, interface)
    try:
        unknowns = [vr[n] for n in ("theta", "omega")] + [vr[f"der({s})"] for s in STATES]
        knowns = [vr[s] for s in STATES] + [vr["torque"]]
        columns = [directional(instance, version, unknowns, knowns, np.eye(len(knowns))[k])
                   for k in range(len(knowns))]
        np.testing.assert_array_equal(np.column_stack(columns), reference_jacobian())
        # a random seed: J s to the rounding bound of a 5-term dot product
        seed = np.random.default_rng(0).standard_normal(len(knowns))
        J = reference_jacobian()
        got = directional(instance, version, unknowns, knowns, seed)
        bound = 2 * (len(knowns) + 1) * EPS * (np.abs(J) @ np.abs(seed))
        assert np.all(np.abs(got - J @ seed) <= bound)
    finally:
        instance.freeInstance()


@pytest.mark.parametrize("interface", ["me", "cs"])
def test_adjoint_is_the_transpose(interface):
    """FMI 3.0 fmi3GetAdjointDerivative: sensitivity = J^T seed; unit seeds over the
    unknowns give the rows of J exactly."""
    instance, vr = open_instance("hub", "3.0", interface)
    try:
        unknowns = [vr[n] for n in ("theta", "omega")] + [vr[f"der({s})"] for s in STATES]
        knowns = [vr[s] for s in STATES] + [vr["torque"]]
        rows = [np.array(instance.getAdjointDerivative(unknowns, knowns, list(np.eye(6)[i]),
                                                       nSensitivity=len(knowns)))
                for i in range(len(unknowns))]
        np.testing.assert_array_equal(np.vstack(rows), reference_jacobian())
    finally:
        instance.freeInstance()


@pytest.mark.parametrize("version", VERSIONS)
def test_directional_derivatives_agree_with_finite_differences(version):
    """Model Exchange: central differences of the derivatives and outputs the FMU computes
    (states through SetContinuousStates, the input through Set), at a random point."""
    instance, vr = open_instance("hub", version, "me")
    get = instance.getFloat64 if version == "3.0" else instance.getReal
    set_ = instance.setFloat64 if version == "3.0" else instance.setReal
    rng = np.random.default_rng(1)
    x0, u0 = rng.standard_normal(4), rng.standard_normal()
    unknown_names = ("theta", "omega") + tuple(f"der({s})" for s in STATES)
    unknowns = [vr[n] for n in unknown_names]
    knowns = [vr[s] for s in STATES] + [vr["torque"]]

    def evaluate(x, u):
        instance.setContinuousStates((ctypes.c_double * 4)(*x), 4)
        set_([vr["torque"]], [u])
        return np.array(get(unknowns))

    try:
        delta = 1e-3
        columns = []
        for k in range(5):
            step = np.eye(5)[k] * delta
            plus = evaluate(x0 + step[:4], u0 + step[4])
            minus = evaluate(x0 - step[:4], u0 - step[4])
            columns.append((plus - minus) / (2 * delta))
        finite = np.column_stack(columns)
        evaluate(x0, u0)
        analytic = np.column_stack([directional(instance, version, unknowns, knowns, np.eye(5)[k])
                                    for k in range(5)])
        np.testing.assert_allclose(analytic, finite, rtol=0, atol=1e-9)
    finally:
        instance.freeInstance()


@pytest.mark.parametrize("version", VERSIONS)
def test_sampled_controller_feeds_through_at_samples_only(version):
    """The digital LQR: d torque / d (theta_ref, theta, omega) = D = [g, 0, 0] at a sample
    instant, 0 between samples; and finite differences of its torque say the same."""
    instance, vr = open_instance("lqr", version, "cs")
    get = instance.getFloat64 if version == "3.0" else instance.getReal
    set_ = instance.setFloat64 if version == "3.0" else instance.setReal
    knowns = [vr["theta_ref"], vr["theta"], vr["omega"]]
    D = np.asarray(lqr().D)[0]
    try:
        at_sample = directional(instance, version, [vr["torque"]], knowns, [1.0, 0.0, 0.0])
        assert at_sample[0] == D[0] != 0.0
        set_(knowns, [0.1, 0.0, 0.0])
        first = get([vr["torque"]])[0]
        set_(knowns, [0.2, 0.0, 0.0])
        assert get([vr["torque"]])[0] - first == pytest.approx(0.1 * D[0], rel=1e-12)
        instance.doStep(0.0, SAMPLE_TIME / 2)  # takes the sample at 0; holds until T
        between = directional(instance, version, [vr["torque"]], knowns, [1.0, 1.0, 1.0])
        assert between[0] == 0.0
        held = get([vr["torque"]])[0]
        set_(knowns, [5.0, 1.0, 1.0])
        assert get([vr["torque"]])[0] == held
    finally:
        instance.freeInstance()
