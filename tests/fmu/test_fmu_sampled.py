"""Sampled (discrete-time) systems as Co-Simulation FMUs, FMI 2.0 and 3.0: a digital
controller updates every T whatever the master's step, holds its outputs between samples,
and the digital-LQR loop co-simulated with the plant FMU equals the monolithic sampled loop.

References for the sampled FMU (``fmu_cases.sampled``: x[k+1] = A x[k] + B u[k],
y = C x + D u, T = 0.1 s): the recurrence itself, evaluated here with numpy; the FMU
evaluates the same products in the same order of samples, so the two agree to a few ulps
per sample (tolerances below are 1e-12 relative for up to 100 samples).

Reference for the loop (``fmu_cases.monolithic_sampled_loop``): the plant discretised by
``control.c2d(..., "zoh")`` at the master's step and the controller sampled every T; for a
master step h = T it equals ``control.interconnect`` of the two discrete systems (checked).
The issue's bound is 1e-12 relative to each signal's size: both sides use the same
zero-order-hold matrices, so only round-off differs (observed ~1e-15).
"""

import control
import numpy as np
import pytest
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
from fmpy.validation import validate_fmu

import controllers
import fmu.cosim
from fmu import cosimulate, export

from fmu_cases import SAMPLE_TIME, exported, lqr, loop_plant, monolithic_sampled_loop, sampled
from fmu_cases import jacobi_controller

VERSIONS = ["2.0", "3.0"]
T = 0.1  # sample period of fmu_cases.sampled [s]


def held_reference(t: np.ndarray, torque: float) -> np.ndarray:
    """Outputs of the sampled system at the times t for a constant torque from rest: the
    output of sample k = floor(t / T) (a sample instant shows its own sample)."""
    system = sampled()
    A, B, C, D = (np.asarray(M) for M in (system.A, system.B, system.C, system.D))
    k_max = int(np.floor(t[-1] / T + 1e-6))
    x = np.zeros(2)
    outputs = []
    for _ in range(k_max + 1):
        outputs.append(C @ x + D[:, 0] * torque)
        x = A @ x + B[:, 0] * torque
    k = np.floor(t / T + 1e-6).astype(int)
    return np.array(outputs)[k].T


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("h", [T, T / 4, 3 * T, 0.07])
def test_samples_every_T_whatever_the_step(version, h):
    """fmpy's CS master with steps equal to, shorter than, longer than and not aligned with
    the sample period: the outputs at every communication point are those of the last
    sample (and the FMU's own samples fall at k T, not at the master's points)."""
    stop = 2.1
    table = np.array([(0.0, 1.0)], dtype=[("time", np.float64), ("torque", np.float64)])
    result = simulate_fmu(str(exported("sampled", version)), fmi_type="CoSimulation",
                          stop_time=stop, output_interval=h, input=table)
    expected = held_reference(result["time"], 1.0)
    for i, name in enumerate(("theta", "omega")):
        np.testing.assert_allclose(result[name], expected[i], rtol=1e-12, atol=1e-15)


def _slave(version: str, name: str):
    path = exported(name, version)
    description = read_model_description(str(path))
    kind = FMU3Slave if version == "3.0" else FMU2Slave
    slave = kind(guid=description.guid, unzipDirectory=extract(str(path)),
                 modelIdentifier=description.coSimulation.modelIdentifier, instanceName=name)
    slave.instantiate()
    if version == "3.0":
        slave.enterInitializationMode(startTime=0.0)
        get, set_ = slave.getFloat64, slave.setFloat64
    else:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
        get, set_ = slave.getReal, slave.setReal
    slave.exitInitializationMode()
    return slave, {v.name: v.valueReference for v in description.modelVariables}, get, set_


@pytest.mark.parametrize("version", VERSIONS)
def test_outputs_hold_between_samples_and_feed_through_at_them(version):
    """y = C x + D u with D = [0.5, 0]^T: at a sample instant the output follows the input
    as set now; between samples it holds the sample's value whatever the input does."""
    slave, vr, get, set_ = _slave(version, "sampled")
    try:
        set_([vr["torque"]], [1.0])
        assert get([vr["theta"]]) == [0.5]          # t = 0: pending sample, 0.5 * 1
        slave.doStep(0.0, T / 2)                    # takes the sample at 0 with torque 1
        set_([vr["torque"]], [3.0])
        assert get([vr["theta"]]) == [0.5]          # held until T
        slave.doStep(T / 2, T / 2)
        # t = T: pending sample, x1 = B * 1, theta = x1[0] + 0.5 * 3
        assert get([vr["theta"]]) == [pytest.approx(T * T / 2 / 10.0 + 1.5, rel=1e-15)]
    finally:
        slave.terminate()
        slave.freeInstance()


@pytest.mark.parametrize("version", VERSIONS)
def test_a_very_long_step_takes_its_samples_by_powering(version):
    """A step of 2000 T (more than the 1000 samples taken one by one) takes its samples by
    binary powering of [[A, B], [0, I]]: 22 products instead of 2000 steps; the two
    round differently, by a few ulps per product of these matrices with entries up to
    ~2000 T (so 1e-12 relative)."""
    slave, vr, get, set_ = _slave(version, "sampled")
    try:
        set_([vr["torque"]], [1.0])
        slave.doStep(0.0, 2000 * T)
        got = np.array(get([vr["q"], vr["q_dot"], vr["theta"]]))
    finally:
        slave.terminate()
        slave.freeInstance()
    # closed form of the double integrator: q_N = (N T)^2 / (2 J), q_dot_N = N T / J
    N, J = 2000, 10.0
    expected_states = [(N * T) ** 2 / (2 * J), N * T / J]
    np.testing.assert_allclose(got[:2], expected_states, rtol=1e-12)
    assert got[2] == pytest.approx(expected_states[0] + 0.5, rel=1e-12)  # pending sample at 200 s


@pytest.mark.parametrize("version", VERSIONS)
def test_model_exchange_is_refused_for_a_sampled_system(version, tmp_path):
    with pytest.raises(ValueError, match="interfaces must be 'cs' for a discrete-time system"):
        export(sampled(), tmp_path / "s.fmu", fmi_version=version, interfaces="me")


# ---------------------------------------------------------------- the digital LQR loop


def test_monolithic_reference_is_the_interconnected_sampled_loop():
    """The test's multirate reference at h = T equals python-control's interconnection of
    the ZOH plant and the discrete controller (1e-13 relative: same products, other order)."""
    t_end = 3.0
    ours = monolithic_sampled_loop(t_end, SAMPLE_TIME, 0.1)
    loop = control.interconnect([control.c2d(loop_plant(), SAMPLE_TIME, "zoh"), lqr()],
                                inplist=["theta_ref"], outlist=["theta", "omega", "torque"])
    response = control.forced_response(loop, T=ours["time"], U=np.full(ours["time"].size, 0.1))
    # the same recursion of the loop with its products in other orders: each step adds at most
    # gamma_n |Phi| |x| ~ n eps max|x| (Higham 2002, sec. 3.5; n the loop's states), which
    # this stable loop carries along without growth, so after N steps: N n eps max|y|
    # (61 samples x 12 states: 1.6e-13 relative; measured: 6 eps)
    bound = ours["time"].size * loop.nstates * np.finfo(float).eps
    for name, values in zip(("theta", "omega", "torque"), np.asarray(response.outputs)):
        np.testing.assert_allclose(ours[name], values, rtol=0,
                                   atol=bound * np.max(np.abs(values)))


def assert_equal_to(result, expected, decimate=1):
    for name in ("theta", "omega", "torque"):
        reference = expected[name][::decimate] if decimate > 1 else expected[name]
        got = result[name][::decimate] if decimate > 1 else result[name]
        np.testing.assert_allclose(got, reference, rtol=0, atol=1e-12 * np.max(np.abs(reference)))


@pytest.mark.parametrize("plant_version,controller_version",
                         [("2.0", "2.0"), ("3.0", "3.0"), ("2.0", "3.0")])
@pytest.mark.parametrize("divisions", [1, 5])
@pytest.mark.slow
def test_digital_lqr_loop_equals_the_monolithic_sampled_loop(plant_version, controller_version,
                                                             divisions):
    """Plant FMU (continuous) + digital LQR FMU (sampled every T), Gauss-Seidel master with
    h = T and h = T / 5: equal to the monolithic sampled loop on the master's grid. With
    FMI 3.0 the master activates the controller's clock in Event Mode at its ticks."""
    h, t_end = SAMPLE_TIME / divisions, 3.0
    result = cosimulate(exported("plant", plant_version), exported("lqr", controller_version),
                        t_end, h, inputs={"theta_ref": 0.1})
    assert_equal_to(result, monolithic_sampled_loop(t_end, h, 0.1))


@pytest.mark.parametrize("version", VERSIONS)
def test_digital_lqr_loop_jacobi(version):
    """Jacobi exchange: the controller's feedthrough (D = [g, 0, 0], from theta_ref) acts
    one sample late while its state takes the fresh inputs: the monolithic loop with the
    delay state of test_fmu_cosim.jacobi_controller."""
    t_end = 3.0
    result = cosimulate(exported("plant", version), exported("lqr", version), t_end,
                        SAMPLE_TIME, inputs={"theta_ref": 0.1}, method="jacobi")
    loop = control.interconnect([control.c2d(loop_plant(), SAMPLE_TIME, "zoh"),
                                 jacobi_controller(lqr())],
                                inplist=["theta_ref"], outlist=["theta", "omega", "torque"])
    t = np.arange(int(round(t_end / SAMPLE_TIME)) + 1) * SAMPLE_TIME
    response = control.forced_response(loop, T=t, U=np.full(t.size, 0.1))
    assert_equal_to(result, dict(zip(("theta", "omega", "torque"), np.asarray(response.outputs))))


def test_clock_activation_and_fmu_sampling_give_the_same_loop(monkeypatch):
    """The master activates the FMI 3.0 controller's clock at every tick (counted); without
    activation (an importer that does not handle clocks) fmi3DoStep takes the samples
    itself: bit-identical results."""
    ticks = []
    original = fmu.cosim.FMUSlave.tick

    def counting(self, time):
        if self.ticks_at(time):
            ticks.append(time)
        return original(self, time)

    with monkeypatch.context() as patch:
        patch.setattr(fmu.cosim.FMUSlave, "tick", counting)
        clocked = cosimulate(exported("plant", "3.0"), exported("lqr", "3.0"), 1.0, SAMPLE_TIME / 2,
                             inputs={"theta_ref": 0.1})
    assert len(ticks) == 21  # 0, 0.05, ..., 1.0: every other point of the h = T/2 grid
    with monkeypatch.context() as patch:
        patch.setattr(fmu.cosim.FMUSlave, "tick", lambda self, time: None)
        unclocked = cosimulate(exported("plant", "3.0"), exported("lqr", "3.0"), 1.0,
                               SAMPLE_TIME / 2, inputs={"theta_ref": 0.1})
    for name in clocked.dtype.names:
        np.testing.assert_array_equal(clocked[name], unclocked[name])


@pytest.mark.parametrize("version", VERSIONS)
def test_sampled_loop_fmu(version, tmp_path):
    """The loop itself as an FMU: controllers.close_loop of the plant and the digital LQR is
    the discrete sampled loop (dt = T); exported, validated, and simulated by fmpy with
    h = T, it equals the monolithic sampled loop."""
    loop = controllers.close_loop(loop_plant(), lqr())
    assert loop.dt == SAMPLE_TIME
    path = export(loop, tmp_path / "loop.fmu", fmi_version=version, stop_time=3.0)
    assert validate_fmu(str(path)) == []
    table = np.array([(0.0, 0.1)], dtype=[("time", np.float64), ("theta_ref", np.float64)])
    result = simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=3.0,
                          output_interval=SAMPLE_TIME, input=table)
    expected = monolithic_sampled_loop(3.0, SAMPLE_TIME, 0.1)
    for name in ("theta", "omega"):
        np.testing.assert_allclose(result[name], expected[name], rtol=0,
                                   atol=1e-12 * np.max(np.abs(expected[name])))


@pytest.mark.parametrize("version", VERSIONS)
@pytest.mark.parametrize("h", [T, 0.02, 2 * T])
def test_reference_files_of_a_sampled_fmu(version, h, tmp_path):
    """The cross-check files of a sampled FMU for communication steps equal to, finer and
    coarser than its period (fmu.reference simulates it on its own sample grid with the
    inputs the master holds): fmpy, fed with <Model>_in.csv, reproduces <Model>_ref.csv
    to round-off. fmpy records the outputs at the end of each step, before it sets the inputs
    of that instant: at an input step it shows the left limit (the first of the two rows)."""
    from fmpy.util import read_csv

    path = export(sampled(), tmp_path / "s.fmu", fmi_version=version, step=h, stop_time=2.0,
                  reference=True)
    result = simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=2.0, output_interval=h,
                          input=read_csv(str(tmp_path / "s_in.csv")))
    reference = read_csv(str(tmp_path / "s_ref.csv"))
    first = np.r_[True, np.diff(reference["time"]) > 0]
    np.testing.assert_allclose(result["time"], reference["time"][first], rtol=0, atol=1e-12)
    for name in ("theta", "omega"):
        expected = reference[name][first]
        np.testing.assert_allclose(result[name], expected, rtol=0, atol=1e-12 * np.max(np.abs(expected)))
    # the input step falls on a sample instant in every case here (0.5 s, 0.5 s, 0.4 s): the
    # sample is still to be taken, so the two rows differ by the feedthrough D = 0.5
    steps = np.flatnonzero(np.diff(reference["time"]) == 0)
    assert reference["theta"][steps[0] + 1] - reference["theta"][steps[0]] == pytest.approx(0.5)
