"""Exported FMUs simulated by fmpy against python-control.

- Co-Simulation: exact for inputs held over each step, so it must equal
  ``control.c2d(sys, h, "zoh")`` + ``forced_response`` to round-off (1e-9 relative asked).
  fmpy applies inputs "after the event" at each communication point and interpolates
  linearly between table rows, so inputs are written as steps with repeated time rows.
- Model Exchange: the continuous response (``control.forced_response``, which interpolates
  inputs linearly between samples like fmpy) to the solver's tolerance.
- Steps other than the default one (computed in C) and a stiff lightly damped mode.
"""

import ctypes

import control
import numpy as np
import pytest
import scipy.linalg
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.util import read_csv
from fmpy.fmi2 import FMU2Model, FMU2Slave

from fmu import export

from fmu_references import augmented_exponential_mp, step_table, zoh_reference

J = 10.0  # hub inertia [kg m^2]


def hub_with_flexible_mode(frequency=3.0, damping=0.01):
    """theta = q + eta: rigid angle q (J q'' = torque) plus one modal coordinate eta."""
    w, z = frequency, damping
    A = [[0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1], [0, 0, -w * w, -2 * z * w]]
    B = [[0], [1 / J], [0], [0.5 / J]]
    C = [[1, 0, 1, 0], [0, 1, 0, 1]]
    return control.ss(A, B, C, 0, inputs=["torque"], outputs=["theta", "omega"],
                      states=["q", "q_dot", "eta", "eta_dot"], name="hub")


def stiff_plant():
    """Rigid hub plus a 1000 rad/s mode with damping ratio 1e-3 (|A h| = 100 for h = 0.1 s)."""
    return hub_with_flexible_mode(frequency=1000.0, damping=1e-3)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sim")
    return {
        "hub": export(hub_with_flexible_mode(), folder / "hub.fmu", step=0.01, stop_time=4.0,
                      reference=True),
        "stiff": export(stiff_plant(), folder / "stiff.fmu", step=0.01),
    }


def test_cs_equals_c2d_zoh(fmus):
    h = 0.01
    switch_times, values = [0.0, 0.5, 1.5, 2.5], [0.0, 1.0, -2.0, 0.5]
    result = simulate_fmu(str(fmus["hub"]), fmi_type="CoSimulation", stop_time=4.0,
                          output_interval=h, input=step_table(switch_times, values))
    t, y = zoh_reference(hub_with_flexible_mode(), h, 4.0, switch_times, values)
    np.testing.assert_allclose(result["time"], t, rtol=0, atol=1e-12)
    for i, name in enumerate(["theta", "omega"]):
        # 1e-9 relative to the signal's size (the bound); round-off is ~1e-14
        np.testing.assert_allclose(result[name], y[i], rtol=0, atol=1e-9 * np.max(np.abs(y[i])))


def test_cs_steps_shortened_at_input_events_stay_exact(fmus):
    """Input steps between grid points make fmpy shorten steps (0.005 s pieces): the FMU
    computes those transition matrices in C. The reference uses a 0.005 s grid, on which
    the same input is piecewise constant, and keeps every second sample."""
    h = 0.01
    switch_times, values = [0.0, 0.255, 1.105], [0.0, 1.0, -0.5]
    result = simulate_fmu(str(fmus["hub"]), fmi_type="CoSimulation", stop_time=2.0,
                          output_interval=h, input=step_table(switch_times, values))
    t_fine, y_fine = zoh_reference(hub_with_flexible_mode(), h / 2, 2.0, switch_times, values)
    on_grid = np.isclose(np.round(result["time"] / h) * h, result["time"], rtol=0, atol=1e-12)
    assert np.count_nonzero(~on_grid) >= 2  # the event instants were visited
    for i, name in enumerate(["theta", "omega"]):
        expected = np.interp(result["time"][on_grid], t_fine, y_fine[i])  # exact at grid points
        np.testing.assert_allclose(result[name][on_grid], expected, rtol=0,
                                   atol=1e-9 * np.max(np.abs(y_fine[i])))


def test_cs_start_values_set_the_initial_state(fmus):
    x0 = [0.2, -0.1, 0.05, 0.0]
    result = simulate_fmu(str(fmus["hub"]), fmi_type="CoSimulation", stop_time=1.0,
                          output_interval=0.01,
                          start_values={"q": x0[0], "q_dot": x0[1], "eta": x0[2]})
    t, y = zoh_reference(hub_with_flexible_mode(), 0.01, 1.0, [0.0], [0.0], x0=x0)
    np.testing.assert_allclose(result["theta"], y[0], rtol=0, atol=1e-12)
    assert result["theta"][0] == 0.2 + 0.05  # theta = q + eta at t = 0, exactly


def test_me_equals_continuous_response(fmus):
    """CVode (rtol 1e-10) against the exact continuous response to piecewise-constant input.

    fmpy's CVode wrapper sets the inputs at communication points and events only (its
    right-hand side does not re-interpolate them), so the test input is a step signal with
    steps on the output grid; for it the continuous response at the grid points is exactly
    the zero-order-hold discretisation (c2d "zoh"), the same reference as for CS."""
    h = 0.01
    switch_times, values = [0.0, 0.5, 1.5, 2.5], [0.0, 1.0, -2.0, 0.5]
    t, y = zoh_reference(hub_with_flexible_mode(), h, 4.0, switch_times, values)
    errors = {}
    for tolerance in (1e-8, 1e-10):
        result = simulate_fmu(str(fmus["hub"]), fmi_type="ModelExchange", stop_time=4.0,
                              output_interval=h, relative_tolerance=tolerance,
                              input=step_table(switch_times, values))
        # ME results repeat time rows at events: keep the last row of each time
        last = np.r_[np.diff(result["time"]) > 0, True]
        np.testing.assert_allclose(result["time"][last], t, rtol=0, atol=1e-9)
        errors[tolerance] = max(np.max(np.abs(result[name][last] - y[i])) / np.max(np.abs(y[i]))
                                for i, name in enumerate(["theta", "omega"]))
    # the error is the solver's: global error ~1e3 x rtol here (observed 6e-6 and 2e-7),
    # and it shrinks with the tolerance (observed 28x for 100x)
    assert errors[1e-10] < 1e-6
    assert errors[1e-10] < errors[1e-8] / 10


def test_stiff_mode_is_stable_with_a_long_step(fmus):
    """1000 rad/s mode, damping 1e-3, step 0.1 s (100 rad per step): explicit integrators
    diverge; the exact step matches c2d at the same step and stays bounded."""
    h = 0.1
    switch_times, values = [0.0, 0.3], [0.0, 1.0]
    result = simulate_fmu(str(fmus["stiff"]), fmi_type="CoSimulation", stop_time=3.0,
                          output_interval=h, input=step_table(switch_times, values))
    t, y = zoh_reference(stiff_plant(), h, 3.0, switch_times, values)
    np.testing.assert_allclose(result["theta"], y[0], rtol=0, atol=1e-9 * np.max(np.abs(y[0])))
    np.testing.assert_allclose(result["omega"], y[1], rtol=0, atol=1e-9 * np.max(np.abs(y[1])))
    # bounded: the rigid part gives omega = (t - 0.3)/J at most; the mode adds < 1e-4 rad/s
    assert np.max(np.abs(result["omega"])) < (3.0 - 0.3) / J + 1e-3


def _slave(path, name):
    description = read_model_description(str(path))
    unzipped = extract(str(path))
    slave = FMU2Slave(guid=description.guid, unzipDirectory=unzipped,
                      modelIdentifier=description.coSimulation.modelIdentifier, instanceName=name)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    return slave, {v.name: v.valueReference for v in description.modelVariables}


@pytest.mark.parametrize("h", [0.037, 1e-6, 2.5, 0.1])
def test_any_step_size_is_exact(fmus, h):
    """One fmi2DoStep of size h (not the default 0.01 s: computed in C by balancing and
    scaling-and-squaring Pade 13) from x = [1, 2, 3, 4] with torque = 0.7, against the
    augmented exponential in 40-digit arithmetic. 1e-12 relative to |x(h)|: round-off of a
    5x5 exponential whose stiff mode turns by up to 2500 rad (observed <= 1e-13)."""
    for key, system in (("hub", hub_with_flexible_mode()), ("stiff", stiff_plant())):
        slave, vr = _slave(fmus[key], f"step_{key}")
        states = [vr[s] for s in ("q", "q_dot", "eta", "eta_dot")]
        x = np.array([1.0, 2.0, 3.0, 4.0])
        try:
            slave.terminate()
            slave.reset()
            slave.setReal(states, list(x))  # states are settable before initialisation
            slave.setupExperiment(startTime=0.0)
            slave.enterInitializationMode()
            slave.exitInitializationMode()
            slave.setReal([vr["torque"]], [0.7])
            slave.doStep(0.0, h)
            got = np.array(slave.getReal(states))
        finally:
            slave.terminate()
            slave.freeInstance()
        expected = augmented_exponential_mp(system, h, x, 0.7)
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12 * np.max(np.abs(expected)))


def test_default_step_is_exact(fmus):
    """The default step uses the matrices precomputed in Python: same 40-digit check."""
    slave, vr = _slave(fmus["stiff"], "default")
    states = [vr[s] for s in ("q", "q_dot", "eta", "eta_dot")]
    try:
        slave.setReal([vr["torque"]], [0.7])
        slave.doStep(0.0, 0.01)
        got = np.array(slave.getReal(states))
    finally:
        slave.terminate()
        slave.freeInstance()
    expected = augmented_exponential_mp(stiff_plant(), 0.01, np.zeros(4), 0.7)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12 * np.max(np.abs(expected)))


def test_repeated_cs_steps_are_consistent(fmus):
    """Two half steps equal one full step (semigroup property) to round-off."""
    slave, vr = _slave(fmus["hub"], "halves")
    slave2, _ = _slave(fmus["hub"], "whole")
    try:
        for s in (slave, slave2):
            s.setReal([vr["torque"]], [1.0])
        slave.doStep(0.0, 0.005)
        slave.doStep(0.005, 0.005)
        slave2.doStep(0.0, 0.01)
        states = [vr[s] for s in ("q", "q_dot", "eta", "eta_dot")]
        # Phi(h/2) applied twice against Phi(h): each transition matrix within ~10 eps of
        # exact for ||A h|| << 1 (Higham, Functions of Matrices, sec. 10.3), and the two
        # products of 4 terms add gamma_4: ~30 eps relative to the state; rtol 450 eps
        np.testing.assert_allclose(slave.getReal(states), slave2.getReal(states), rtol=1e-13, atol=1e-18)
    finally:
        for s in (slave, slave2):
            s.terminate()
            s.freeInstance()


def test_reference_files_cross_check_in_fmpy(fmus):
    """What another tool would do with <Model>_in.csv, _ref.csv and _ref.opt."""
    folder = fmus["hub"].parent
    options = dict(line.split(",") for line in (folder / "hub_ref.opt").read_text().splitlines())
    result = simulate_fmu(str(fmus["hub"]), fmi_type="CoSimulation",
                          start_time=float(options["StartTime"]), stop_time=float(options["StopTime"]),
                          output_interval=float(options["StepSize"]),
                          input=read_csv(str(folder / "hub_in.csv")))
    reference = read_csv(str(folder / "hub_ref.csv"))
    last = np.r_[np.diff(reference["time"]) > 0, True]  # one row per time (D = 0: equal rows)
    np.testing.assert_allclose(result["time"], reference["time"][last], rtol=0, atol=1e-12)
    for name in ("theta", "omega"):
        expected = reference[name][last]
        np.testing.assert_allclose(result[name], expected, rtol=0, atol=1e-9 * np.max(np.abs(expected)))


@pytest.mark.slow
def test_200_states_any_step(tmp_path):
    """A 200-state modal plant (rigid body + 99 modes up to 1000 rad/s, damping 0.005):
    one step of 0.0123 s (computed in C, a 201 x 201 exponential) against scipy's augmented
    exponential; 1e-11 relative to |x(h)| allows for scipy's own round-off (~1e-13 here)."""
    rng = np.random.default_rng(1)
    blocks = [np.array([[0.0, 1.0], [0.0, 0.0]])]
    blocks += [np.array([[0.0, 1.0], [-w * w, -0.01 * w]]) for w in np.linspace(1.0, 1000.0, 99)]
    A = scipy.linalg.block_diag(*blocks)
    B = rng.standard_normal((200, 1))
    system = control.ss(A, B, rng.standard_normal((2, 200)), 0, inputs=["torque"],
                        outputs=["theta", "omega"])
    x0 = rng.standard_normal(200)
    path = export(system, tmp_path / "modal.fmu", x0=x0)
    slave, vr = _slave(path, "modal")
    states = [vr[f"x[{i}]"] for i in range(200)]
    try:
        slave.setReal([vr["torque"]], [0.3])
        slave.doStep(0.0, 0.0123)
        got = np.array(slave.getReal(states))
    finally:
        slave.terminate()
        slave.freeInstance()
    M = np.zeros((201, 201))
    M[:200, :200], M[:200, 200:] = A * 0.0123, B * 0.0123
    E = scipy.linalg.expm(M)
    expected = E[:200, :200] @ x0 + E[:200, 200] * 0.3
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-11 * np.max(np.abs(expected)))


def test_me_derivatives_and_outputs(fmus):
    """fmi2GetDerivatives = A x + B u and outputs C x + D u for states set by the
    integrator (fmi2SetContinuousStates): 1e-15 relative, one dot product of round-off."""
    path = fmus["hub"]
    description = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in description.modelVariables}
    model = FMU2Model(guid=description.guid, unzipDirectory=extract(str(path)),
                      modelIdentifier=description.modelExchange.modelIdentifier, instanceName="me")
    system = hub_with_flexible_mode()
    x, u = np.array([0.3, -1.0, 0.02, 0.5]), 2.5
    model.instantiate()
    try:
        model.setupExperiment(startTime=0.0)
        model.enterInitializationMode()
        model.exitInitializationMode()
        model.enterContinuousTimeMode()
        model.setTime(0.5)
        model.setContinuousStates((ctypes.c_double * 4)(*x), 4)
        model.setReal([vr["torque"]], [u])
        derivatives = (ctypes.c_double * 4)()
        model.getDerivatives(derivatives, 4)
        outputs = model.getReal([vr["theta"], vr["omega"]])
        model.terminate()
    finally:
        model.freeInstance()
    # the FMU's C loops and numpy's BLAS sum the n + 1 products in other orders: each result is
    # within gamma_{n+1} (|A| |x| + |B| |u|) of the exact sums, entry by entry (Higham,
    # Accuracy and Stability of Numerical Algorithms, 2nd ed., sec. 3.5), so their difference
    # is within twice that (cancellation in A x is allowed for; no bare rtol)
    A, B, C = (np.asarray(m, dtype=float) for m in (system.A, system.B, system.C))
    n, eps = x.size, np.finfo(float).eps
    gamma = (n + 1) * eps / 2 / (1 - (n + 1) * eps / 2)  # unit round-off eps / 2
    bound = 2 * gamma * (np.abs(A) @ np.abs(x) + np.abs(B[:, 0]) * abs(u))
    assert np.all(np.abs(np.array(list(derivatives)) - (A @ x + B[:, 0] * u)) <= bound)
    bound = 2 * gamma * (np.abs(C) @ np.abs(x))
    assert np.all(np.abs(np.array(outputs) - C @ x) <= bound)
