"""FMU export: modelDescription.xml, validation by fmpy, binary contents, units, bad input.

Systems are built here with control.ss and named signals:
- a rigid hub with one flexible mode (inputs ['torque'], outputs ['theta', 'omega']);
- a PD controller with 0 states and D != 0 (inputs ['theta_ref', 'theta', 'omega'],
  output ['torque']);
- a 2-state rigid body and a 200-state modal plant (the size range the issue asks for).
"""

import os
import shutil
import subprocess
import zipfile

import control
import numpy as np
import pytest
import scipy.linalg
from fmpy import read_model_description
from fmpy.validation import validate_fmu

import fmu
from fmu import FMUBuildError, FMUError, export
from fmu.codegen import c_double
from fmu.units import guess_unit

HUB_INERTIA = 10.0  # J [kg m^2]
MODE_FREQUENCY = 3.0  # [rad/s]
MODE_DAMPING = 0.01
MODE_PARTICIPATION = 0.5


def hub_with_flexible_mode():
    """theta = q + eta: rigid angle q (J q'' = torque) plus one modal coordinate eta."""
    w, z, J = MODE_FREQUENCY, MODE_DAMPING, HUB_INERTIA
    A = [[0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1], [0, 0, -w * w, -2 * z * w]]
    B = [[0], [1 / J], [0], [MODE_PARTICIPATION / J]]
    C = [[1, 0, 1, 0], [0, 1, 0, 1]]
    return control.ss(A, B, C, 0, inputs=["torque"], outputs=["theta", "omega"],
                      states=["q", "q_dot", "eta", "eta_dot"], name="hub")


def pd_controller(kp=20.0, kd=30.0):
    """torque = kp (theta_ref - theta) - kd omega: no states, D = [kp, -kp, -kd]."""
    return control.ss(np.zeros((0, 0)), np.zeros((0, 3)), np.zeros((1, 0)), [[kp, -kp, -kd]],
                      inputs=["theta_ref", "theta", "omega"], outputs=["torque"], name="pd")


def rigid_body():
    return control.ss([[0, 1], [0, 0]], [[0], [1 / HUB_INERTIA]], [[1, 0]], 0,
                      inputs=["torque"], outputs=["theta"], states=["theta_s", "omega_s"])


def modal_plant(n_modes=99, seed=0):
    """Rigid body plus n_modes lightly damped modes up to 1000 rad/s: 2 + 2 n_modes states."""
    rng = np.random.default_rng(seed)
    blocks = [np.array([[0.0, 1.0], [0.0, 0.0]])]
    blocks += [np.array([[0.0, 1.0], [-w * w, -2 * 0.005 * w]]) for w in np.linspace(1.0, 1000.0, n_modes)]
    A = scipy.linalg.block_diag(*blocks)
    n = A.shape[0]
    B = rng.standard_normal((n, 1))
    C = rng.standard_normal((2, n))
    return control.ss(A, B, C, 0, inputs=["torque"], outputs=["theta", "omega"], name="modal")


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    folder = tmp_path_factory.mktemp("fmus")
    return {
        "hub": export(hub_with_flexible_mode(), folder / "hub.fmu", x0=[0.1, 0.0, 0.0, 0.0],
                      reference=True, stop_time=2.0),
        "pd": export(pd_controller(), folder / "pd.fmu"),
        "rigid": export(rigid_body(), folder / "rigid.fmu", interfaces=("cs",)),
        "rigid_me": export(rigid_body(), folder / "rigid_me.fmu", interfaces=("me",)),
        "modal": export(modal_plant(), folder / "modal.fmu"),
    }


@pytest.mark.slow
@pytest.mark.parametrize("name", ["hub", "pd", "rigid", "rigid_me", "modal"])
def test_validate_fmu_finds_no_problems(fmus, name):
    assert validate_fmu(str(fmus[name])) == []


def test_archive_layout(fmus):
    with zipfile.ZipFile(fmus["hub"]) as archive:
        names = set(archive.namelist())
    assert {"modelDescription.xml", "binaries/linux64/hub.so", "sources/model.c",
            "sources/fmi2Functions.c", "sources/linear_model.c", "sources/linear_model.h",
            "sources/fmi2Functions.h", "sources/LICENSE_fmi2_headers.txt"} <= names


def test_variables_names_units_and_start_values(fmus):
    description = read_model_description(str(fmus["hub"]))
    variables = {v.name: v for v in description.modelVariables}
    assert [v.name for v in description.modelVariables] == [
        "torque", "theta", "omega", "q", "q_dot", "eta", "eta_dot",
        "der(q)", "der(q_dot)", "der(eta)", "der(eta_dot)"]
    assert variables["torque"].causality == "input"
    assert variables["theta"].causality == "output"
    assert variables["theta"].initial == "calculated"
    assert variables["torque"].unit == "N.m"
    assert variables["theta"].unit == "rad"
    assert variables["omega"].unit == "rad/s"
    assert variables["q"].start == "0.1"
    assert variables["q"].initial == "exact"
    assert variables["der(q_dot)"].derivative is variables["q_dot"]
    assert description.coSimulation.canHandleVariableCommunicationStepSize
    assert description.modelExchange is not None
    assert float(description.defaultExperiment.stepSize) == fmu.DEFAULT_STEP
    units = {u.name: u.baseUnit for u in description.unitDefinitions}
    # N.m = kg m^2 s^-2
    assert [units["N.m"].kg, units["N.m"].m, units["N.m"].s] == [1, 2, -2]
    assert [units["rad/s"].rad, units["rad/s"].s] == [1, -1]


def test_model_structure_follows_sparsity(fmus):
    """theta = q + eta depends on states q (index 4) and eta (6); der(q_dot) = torque / J
    depends on the input only (index 1): read off C and B of hub_with_flexible_mode."""
    description = read_model_description(str(fmus["hub"]))
    outputs = {u.variable.name: sorted(d.name for d in u.dependencies) for u in description.outputs}
    assert outputs == {"theta": ["eta", "q"], "omega": ["eta_dot", "q_dot"]}
    derivatives = {u.variable.name: sorted(d.name for d in u.dependencies)
                   for u in description.derivatives}
    assert derivatives["der(q_dot)"] == ["torque"]
    assert derivatives["der(eta_dot)"] == ["eta", "eta_dot", "torque"]
    pd = read_model_description(str(fmus["pd"]))
    assert [sorted(d.name for d in u.dependencies) for u in pd.outputs] == [["omega", "theta", "theta_ref"]]
    assert pd.derivatives == []


def test_only_the_interfaces_asked_for(fmus):
    description = read_model_description(str(fmus["rigid"]))
    assert description.modelExchange is None and description.coSimulation is not None
    description = read_model_description(str(fmus["rigid_me"]))
    assert description.modelExchange is not None and description.coSimulation is None


def test_binary_exports_only_fmi2_symbols(fmus, tmp_path):
    # nm comes with binutils, which gcc needs (as, ld): a machine that compiled the FMU has it
    nm = shutil.which("nm")
    assert nm is not None, "nm not found although gcc built the FMU (binutils missing?)"
    with zipfile.ZipFile(fmus["hub"]) as archive:
        archive.extract("binaries/linux64/hub.so", tmp_path)
    listing = subprocess.run([nm, "-D", "--defined-only", str(tmp_path / "binaries/linux64/hub.so")],
                             capture_output=True, text=True, check=True).stdout
    symbols = [line.split()[-1] for line in listing.splitlines() if line.strip()]
    assert len(symbols) > 40  # the FMI 2.0 API has 44 functions
    assert all(s.startswith("fmi2") for s in symbols), [s for s in symbols if not s.startswith("fmi2")]


def test_matrices_are_written_exactly(fmus):
    """Every literal in model.c reads back as the same double."""
    with zipfile.ZipFile(fmus["modal"]) as archive:
        source = archive.read("sources/model.c").decode()
    A = np.asarray(modal_plant().A)
    body = source.split("static const double A[")[1].split("{", 1)[1].split("}", 1)[0]
    values = np.array([float(v) for v in body.replace("\n", " ").split(",")])
    np.testing.assert_array_equal(values, A.ravel())  # exact: repr round-trips
    assert c_double(0.1) == "0.1" and float(c_double(1 / 3)) == 1 / 3 and c_double(2.0) == "2.0"


def test_export_into_folder_uses_system_name(tmp_path):
    path = export(rigid_body().copy(name="my body"), tmp_path, interfaces="cs")
    assert path == tmp_path / "my_body.fmu"
    assert read_model_description(str(path)).coSimulation.modelIdentifier == "my_body"


@pytest.mark.slow
def test_guid_is_deterministic_and_content_dependent(tmp_path):
    a = read_model_description(str(export(rigid_body(), tmp_path / "a.fmu", model_name="body"))).guid
    b = read_model_description(str(export(rigid_body(), tmp_path / "b.fmu", model_name="body"))).guid
    c = read_model_description(str(export(rigid_body(), tmp_path / "c.fmu", model_name="body",
                                          x0=[1.0, 0.0]))).guid
    assert a == b and a != c


def test_reference_files(fmus):
    folder = fmus["hub"].parent
    opt = (folder / "hub_ref.opt").read_text()
    assert "StartTime, 0.0" in opt and "StopTime, 2.0" in opt and "StepSize, 0.01" in opt
    inputs = np.genfromtxt(folder / "hub_in.csv", delimiter=",", names=True)
    reference = np.genfromtxt(folder / "hub_ref.csv", delimiter=",", names=True)
    assert inputs.dtype.names == ("time", "torque")
    assert reference.dtype.names == ("time", "theta", "omega")
    # one unit step of torque, written as two rows at the same time
    step_rows = np.flatnonzero(np.diff(inputs["time"]) == 0)
    assert step_rows.size == 1
    t_step = inputs["time"][step_rows[0]]
    assert inputs["torque"][step_rows[0]] == 0.0 and inputs["torque"][step_rows[0] + 1] == 1.0
    # free response before the step from x0 = [0.1, 0, 0, 0]: theta = 0.1 exactly (rigid
    # angle at rest, mode at rest)
    before = reference["time"] < t_step
    np.testing.assert_allclose(reference["theta"][before], 0.1, rtol=0, atol=1e-15)
    # after the step: rigid part theta_q = 0.1 + (t - t_step)^2 / (2 J) plus the mode's
    # eta = (b/J)(1 - cos w t)/w^2 (damping 0.01 changes it by < 1e-2 relative); check the
    # closed form at the final time to 2e-2 relative (damping neglected)
    t_end = reference["time"][-1] - t_step
    rigid = 0.1 + t_end**2 / (2 * HUB_INERTIA)
    mode = MODE_PARTICIPATION / HUB_INERTIA * (1 - np.cos(MODE_FREQUENCY * t_end)) / MODE_FREQUENCY**2
    np.testing.assert_allclose(reference["theta"][-1], rigid + mode, rtol=2e-2)


def test_reference_files_match_python_control(fmus):
    """The ref file equals c2d(zoh) + forced_response of the same steps (to print precision)."""
    folder = fmus["hub"].parent
    reference = np.genfromtxt(folder / "hub_ref.csv", delimiter=",", names=True)
    t = reference["time"]
    keep = np.r_[np.diff(t) != 0, True]  # right limits at the step instant
    t_grid = t[keep]
    inputs = np.genfromtxt(folder / "hub_in.csv", delimiter=",", names=True)
    t_step = inputs["time"][np.flatnonzero(np.diff(inputs["time"]) == 0)[0]]
    u = (t_grid >= t_step - 1e-12).astype(float)
    response = control.forced_response(control.c2d(hub_with_flexible_mode(), 0.01, "zoh"),
                                       T=t_grid, U=u, X0=[0.1, 0, 0, 0])
    # the CSV holds shortest-repr doubles: exact; rtol for round-off of forced_response
    np.testing.assert_allclose(reference["theta"][keep], response.outputs[0], rtol=1e-13, atol=1e-15)


# ---------------------------------------------------------------- units


@pytest.mark.parametrize("name, unit", [
    ("theta", "rad"), ("phi", "rad"), ("theta_ref", "rad"), ("omega", "rad/s"),
    ("torque", "N.m"), ("M", "N.m"), ("F_y", "N"), ("force", "N"), ("delta", "m"),
    ("tip_deflection", "m"), ("theta_dot", "rad/s"), ("x[0]", None), ("u", None)])
def test_guess_unit(name, unit):
    assert guess_unit(name) == unit


def test_units_override(tmp_path):
    path = export(rigid_body(), tmp_path / "u.fmu", units={"theta": None, "theta_s": "rad"})
    variables = {v.name: v for v in read_model_description(str(path)).modelVariables}
    assert variables["theta"].unit is None
    assert variables["theta_s"].unit == "rad"
    assert variables["der(theta_s)"].unit == "rad/s"
    with pytest.raises(ValueError, match="units names the signal 'nope'"):
        export(rigid_body(), tmp_path / "u.fmu", units={"nope": "rad"})
    with pytest.raises(ValueError, match=r"units\['theta'\] must be one of"):
        export(rigid_body(), tmp_path / "u.fmu", units={"theta": "furlong"})


# ---------------------------------------------------------------- bad input


def test_errors_share_a_base_class():
    assert issubclass(FMUBuildError, FMUError) and issubclass(fmu.CosimulationError, FMUError)


def test_discrete_time_system_needs_a_sample_period_and_co_simulation(tmp_path):
    """A sampled system is exported (tests/test_fmu3_sampled.py), but only with a sample
    period (dt = True has none) and as Co-Simulation."""
    sampled = control.c2d(rigid_body(), 0.1)
    unspecified = control.ss(sampled.A, sampled.B, sampled.C, sampled.D, True)
    with pytest.raises(FMUBuildError, match=r"discrete-time without a sample period \(dt = True\)"):
        export(unspecified, tmp_path / "d.fmu")
    with pytest.raises(ValueError, match=r"interfaces must be 'cs' for a discrete-time system "
                                         r"\(sampled every 0.1 s"):
        export(sampled, tmp_path / "d.fmu", interfaces=("me", "cs"))


def test_non_lti_system_is_refused(tmp_path):
    nonlinear = control.nlsys(lambda t, x, u, params: -x, lambda t, x, u, params: x,
                              states=1, inputs=1, outputs=1)
    with pytest.raises(FMUBuildError, match="linear time-invariant control.StateSpace"):
        export(nonlinear, tmp_path / "n.fmu")
    with pytest.raises(FMUBuildError, match="TransferFunction.*control.ss"):
        export(control.tf([1], [1, 1]), tmp_path / "t.fmu")


def test_nan_matrix_is_refused(tmp_path):
    bad = rigid_body()
    bad.A[1, 0] = np.nan
    with pytest.raises(FMUBuildError, match=r"matrix A must be finite; got nan at index \(1, 0\)"):
        export(bad, tmp_path / "nan.fmu")


def test_duplicate_names_are_refused(tmp_path):
    system = control.ss([[0.0]], [[1.0]], [[1.0]], 0, inputs=["theta"], outputs=["theta"], states=["x"])
    with pytest.raises(FMUBuildError, match="'theta' is used twice .*input.*output"):
        export(system, tmp_path / "dup.fmu")


@pytest.mark.parametrize("bad_name", ["theta ref", "1theta", "thé", "a-b"])
def test_invalid_names_are_refused(tmp_path, bad_name):
    system = control.ss([[0.0]], [[1.0]], [[1.0]], 0, inputs=[bad_name], outputs=["y"], states=["x"])
    with pytest.raises(FMUBuildError, match="not a legal FMI variable name"):
        export(system, tmp_path / "bad.fmu")


def test_missing_compiler_says_what_to_do(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))
    monkeypatch.delenv("CC", raising=False)
    with pytest.raises(FMUBuildError, match="no C compiler found.*apt-get install gcc"):
        export(rigid_body(), tmp_path / "cc.fmu")
    monkeypatch.undo()
    with pytest.raises(FMUBuildError, match="no C compiler found"):
        export(rigid_body(), tmp_path / "cc.fmu", compiler=os.fspath(tmp_path / "no-such-cc"))
    assert not (tmp_path / "cc.fmu").exists()


@pytest.mark.parametrize("kwargs, message", [
    ({"step": 0.0}, r"step must be positive and finite \[s\]; got 0.0"),
    ({"step": float("nan")}, "step must be positive and finite"),
    ({"stop_time": -1.0}, "stop_time must be positive"),
    ({"interfaces": ("me", "fmi3")}, "interfaces must be"),
    ({"model_name": "2fast"}, "model_name must be a C identifier"),
    ({"x0": [1.0]}, r"x0 must have shape \(2,\)"),
    ({"x0": [np.inf, 0.0]}, "x0 must be finite"),
])
def test_bad_arguments(tmp_path, kwargs, message):
    with pytest.raises(ValueError, match=message):
        export(rigid_body(), tmp_path / "bad.fmu", **kwargs)


def test_path_must_be_fmu(tmp_path):
    with pytest.raises(ValueError, match="path must be a .fmu file"):
        export(rigid_body(), tmp_path / "x.zip")
