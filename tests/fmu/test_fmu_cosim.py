"""Co-simulation of a plant FMU with a controller FMU against the monolithic sampled loop.

Reference (python-control): the plant and the controller discretised with c2d(..., "zoh")
at the communication step, connected by signal name with control.interconnect, simulated
with forced_response. That is exactly what the master does:
- Gauss-Seidel: u_k = C_c x_c,k + D_c [r_k; y_k], y_k = C_p x_p,k (plant D = 0): the plain
  interconnection of the two discrete systems;
- Jacobi: the controller's feedthrough acts one step late, u_k = C_c x_c,k + D_c v_k-1 with
  v = [r; y], while its state integrates v_k: a controller with a one-step delay state z,
  z_k+1 = v_k, and output C_c x_c + D_c z (start value z_0 = 0, the FMUs' input starts).
"""

import control
import numpy as np
import pytest

from fmu import CosimulationError, cosimulate, export

from fmu_cases import jacobi_controller

J = 10.0  # hub inertia [kg m^2]
KP, KD, FILTER = 20.0, 30.0, 40.0  # [N m/rad], [N m s/rad], derivative filter [rad/s]


def hub_with_flexible_mode():
    """theta = q + eta: rigid angle q (J q'' = torque) plus a 3 rad/s mode (damping 0.01)."""
    w, z = 3.0, 0.01
    A = [[0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1], [0, 0, -w * w, -2 * z * w]]
    B = [[0], [1 / J], [0], [0.5 / J]]
    C = [[1, 0, 1, 0], [0, 1, 0, 1]]
    return control.ss(A, B, C, 0, inputs=["torque"], outputs=["theta", "omega"],
                      states=["q", "q_dot", "eta", "eta_dot"], name="hub")


def pd_controller():
    """torque = KP (theta_ref - theta) - KD omega: 0 states, D != 0."""
    return control.ss(np.zeros((0, 0)), np.zeros((0, 3)), np.zeros((1, 0)), [[KP, -KP, -KD]],
                      inputs=["theta_ref", "theta", "omega"], outputs=["torque"], name="pd")


def filtered_pd_controller():
    """torque = KP (theta_ref - theta) - KD omega_f, omega_f' = FILTER (omega - omega_f)."""
    return control.ss([[-FILTER]], [[0.0, 0.0, FILTER]], [[-KD]], [[KP, -KP, 0.0]],
                      inputs=["theta_ref", "theta", "omega"], outputs=["torque"],
                      states=["omega_f"], name="fpd")


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cosim")
    return {
        "plant": export(hub_with_flexible_mode(), folder / "plant.fmu", step=0.01),
        "pd": export(pd_controller(), folder / "pd.fmu", step=0.01),
        "fpd": export(filtered_pd_controller(), folder / "fpd.fmu", step=0.01),
        "plant_me": export(hub_with_flexible_mode(), folder / "plant_me.fmu", interfaces="me"),
    }


def monolithic(controller, h, t_end, reference, method, x0_plant=None):
    plant_d = control.c2d(hub_with_flexible_mode(), h, "zoh")
    controller_d = control.c2d(controller, h, "zoh")
    if method == "jacobi":
        controller_d = jacobi_controller(controller_d)
    loop = control.interconnect([plant_d, controller_d], inplist=["theta_ref"],
                                outlist=["theta", "omega", "torque"])
    t = np.arange(int(round(t_end / h)) + 1) * h
    x0 = np.zeros(loop.nstates)
    if x0_plant is not None:
        x0[:4] = x0_plant  # interconnect keeps the subsystems' state order: plant first
    response = control.forced_response(loop, T=t, U=reference(t), X0=x0)
    return t, dict(zip(["theta", "omega", "torque"], np.asarray(response.outputs)))


def assert_equal_to_monolithic(result, t, expected):
    np.testing.assert_allclose(result["time"], t, rtol=0, atol=1e-12)
    for name, values in expected.items():
        # 1e-12 relative to the signal's size (the bound); both sides use the
        # same zero-order-hold matrices, so only round-off differs (observed ~1e-15)
        np.testing.assert_allclose(result[name], values, rtol=0,
                                   atol=1e-12 * np.max(np.abs(values)))


@pytest.mark.slow
@pytest.mark.parametrize("method", ["gauss-seidel", "jacobi"])
@pytest.mark.parametrize("controller", ["pd", "fpd"])
def test_equals_monolithic_closed_loop(fmus, method, controller):
    h, t_end = 0.01, 3.0
    result = cosimulate(fmus["plant"], fmus[controller], t_end, h, method=method,
                        inputs={"theta_ref": 0.1})
    system = pd_controller() if controller == "pd" else filtered_pd_controller()
    t, expected = monolithic(system, h, t_end, lambda t: np.full_like(t, 0.1), method)
    assert result.dtype.names == ("time", "theta", "omega", "torque", "theta_ref")
    assert_equal_to_monolithic(result, t, expected)
    np.testing.assert_array_equal(result["theta_ref"], 0.1)


def test_methods_differ_only_by_the_feedthrough_delay(fmus):
    """Jacobi's controller sees y one step late: at t_0 the PD torque is KP * 0 (inputs at
    their start values) in Jacobi and KP * theta_ref in Gauss-Seidel."""
    gs = cosimulate(fmus["plant"], fmus["pd"], 0.1, 0.01, inputs={"theta_ref": 0.1})
    jacobi = cosimulate(fmus["plant"], fmus["pd"], 0.1, 0.01, method="jacobi",
                        inputs={"theta_ref": 0.1})
    assert gs["torque"][0] == KP * 0.1
    assert jacobi["torque"][0] == 0.0
    assert jacobi["torque"][1] == KP * 0.1  # theta_1 = 0: nothing applied yet


def test_other_step_and_initial_state(fmus):
    """A communication step (0.02 s) unlike the FMUs' default step: transition matrices
    computed in C. Start values set the plant's initial state."""
    h, t_end, x0 = 0.02, 2.0, [0.05, -0.01, 0.02, 0.0]
    result = cosimulate(fmus["plant"], fmus["fpd"], t_end, h, inputs={"theta_ref": 0.0},
                        plant_start_values=dict(zip(["q", "q_dot", "eta", "eta_dot"], x0)))
    t, expected = monolithic(filtered_pd_controller(), h, t_end, lambda t: np.zeros_like(t),
                             "gauss-seidel", x0_plant=x0)
    assert_equal_to_monolithic(result, t, expected)


def test_reference_as_function_and_table(fmus):
    h, t_end = 0.01, 1.0

    def ramp(t):
        return np.minimum(t, 0.5) * 0.2  # a ramp to 0.1 rad over 0.5 s

    by_function = cosimulate(fmus["plant"], fmus["pd"], t_end, h, inputs={"theta_ref": ramp})
    by_table = cosimulate(fmus["plant"], fmus["pd"], t_end, h,
                          inputs={"theta_ref": ([0.0, 0.5, 2.0], [0.0, 0.1, 0.1])})
    t, expected = monolithic(pd_controller(), h, t_end, ramp, "gauss-seidel")
    assert_equal_to_monolithic(by_function, t, expected)
    # linear interpolation of the table reproduces the ramp up to rounding of t_k * 0.2
    np.testing.assert_allclose(by_table["theta"], by_function["theta"], rtol=0, atol=1e-15)


def test_step_table_is_right_continuous(fmus):
    """A repeated time row is a step: from t = 0.2 s on the reference is 0.1 rad."""
    result = cosimulate(fmus["plant"], fmus["pd"], 0.5, 0.01,
                        inputs={"theta_ref": ([0.0, 0.2, 0.2], [0.0, 0.0, 0.1])})
    t = result["time"]
    np.testing.assert_array_equal(result["theta_ref"], np.where(t >= 0.2 - 1e-12, 0.1, 0.0))


def test_unconnected_input_keeps_its_start_value(fmus):
    result = cosimulate(fmus["plant"], fmus["pd"], 0.2, 0.01)
    np.testing.assert_array_equal(result["theta_ref"], 0.0)
    np.testing.assert_array_equal(result["theta"], 0.0)  # at rest and no reference


def test_errors(fmus, tmp_path):
    with pytest.raises(ValueError, match="method must be one of"):
        cosimulate(fmus["plant"], fmus["pd"], 1.0, 0.01, method="newton")
    with pytest.raises(ValueError, match="whole number of steps"):
        cosimulate(fmus["plant"], fmus["pd"], 1.005, 0.01)
    with pytest.raises(ValueError, match=r"step must be positive \[s\]"):
        cosimulate(fmus["plant"], fmus["pd"], 1.0, -0.01)
    with pytest.raises(ValueError, match="inputs names 'theta'"):
        cosimulate(fmus["plant"], fmus["pd"], 1.0, 0.01, inputs={"theta": 1.0})
    with pytest.raises(ValueError, match=r"inputs\['theta_ref'\] must be finite"):
        cosimulate(fmus["plant"], fmus["pd"], 1.0, 0.01, inputs={"theta_ref": lambda t: np.nan})
    with pytest.raises(FileNotFoundError, match="plant_fmu must be an existing .fmu file"):
        cosimulate(tmp_path / "none.fmu", fmus["pd"], 1.0, 0.01)
    with pytest.raises(CosimulationError, match="must provide Co-Simulation; got FMI 2.0 without"):
        cosimulate(fmus["plant_me"], fmus["pd"], 1.0, 0.01)
    with pytest.raises(CosimulationError, match="connected both ways"):
        cosimulate(fmus["plant"], fmus["plant"], 1.0, 0.01)
    with pytest.raises(ValueError, match="plant_start_values names 'nope'"):
        cosimulate(fmus["plant"], fmus["pd"], 1.0, 0.01, plant_start_values={"nope": 1.0})


def test_fmu_failure_becomes_cosimulation_error(fmus):
    """A NaN start value is refused by the FMU (fmi2Error): the master names FMU and call."""
    with pytest.raises(CosimulationError, match="plant FMU plant: fmi2SetReal failed at t = 0.0 s"):
        cosimulate(fmus["plant"], fmus["pd"], 1.0, 0.01, plant_start_values={"q": float("nan")})
