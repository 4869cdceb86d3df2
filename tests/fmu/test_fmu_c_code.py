"""The C code of the FMUs: the FMI 2.0 headers as published, several FMUs' sources in one
program, memory safety of fmi2FreeInstance, bounded time for any step, overflow checks.

C harnesses are compiled here with gcc against the sources/ folder of exported FMUs, as an
importing tool would do with a source-code FMU.
"""

import hashlib
import json
import subprocess
import sys
import textwrap
import zipfile
from ctypes import c_double
from pathlib import Path

import control
import numpy as np
import pytest
from fmpy import read_model_description

from fmu import export
from fmu.codegen import template_dir

from fmi_binary import CO_SIMULATION, DISCARD, ERROR, MODEL_EXCHANGE, OK, Binary

J = 10.0  # hub inertia [kg m^2]


def body():
    """J theta'' = torque; outputs theta, omega."""
    return control.ss([[0, 1], [0, 0]], [[0], [1 / J]], np.eye(2), 0, inputs=["torque"],
                      outputs=["theta", "omega"], states=["angle", "rate"], name="body")


def pd_controller():
    """torque = 20 (theta_ref - theta) - 30 omega."""
    return control.ss(np.zeros((0, 0)), np.zeros((0, 3)), np.zeros((1, 0)), [[20.0, -20.0, -30.0]],
                      inputs=["theta_ref", "theta", "omega"], outputs=["torque"], name="pd")


def hub_with_flexible_mode():
    """Rigid hub plus a 3 rad/s mode, damping 0.01 (as in test_fmu_export)."""
    w, z = 3.0, 0.01
    A = [[0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1], [0, 0, -w * w, -2 * z * w]]
    return control.ss(A, [[0], [1 / J], [0], [0.5 / J]], [[1, 0, 1, 0], [0, 1, 0, 1]], 0,
                      inputs=["torque"], outputs=["theta", "omega"],
                      states=["q", "q_dot", "eta", "eta_dot"], name="hub")


def unpack(path: Path, folder: Path) -> tuple[Path, str]:
    """Extract an FMU; returns its sources/ folder and its GUID."""
    with zipfile.ZipFile(path) as archive:
        archive.extractall(folder)
    return folder / "sources", read_model_description(str(path)).guid


def compile_and_run(command: list[str], executable: Path) -> subprocess.CompletedProcess:
    subprocess.run(command + ["-o", str(executable), "-lm", "-pthread"], check=True,
                   capture_output=True, text=True)
    return subprocess.run([str(executable)], capture_output=True, text=True, timeout=60)


# ---------------------------------------------------------------- the standard headers


# SHA-256 of headers/<name> at tag v2.0.1 of github.com/modelica/fmi-standard (the FMI
# 2.0.1 release), with its CRLF line endings turned into LF.
FMI_2_0_1_HEADERS = {
    "fmi2Functions.h": "5315e320046c976b3977bc14eb7e2cb58711fa296e4bdf88ddd2c9c82e2a9958",
    "fmi2FunctionTypes.h": "756da446057a5a6dec47a5938e099ba3a9b1882326672b393c6f7dd8571e3456",
    "fmi2TypesPlatform.h": "50a180641623f47f2e48fc445707549ce4ec2e27358e2451a2dad5b6dfc55287",
}


@pytest.mark.parametrize("name", sorted(FMI_2_0_1_HEADERS))
def test_fmi_headers_are_the_published_ones(name):
    data = (template_dir() / "fmi2" / name).read_bytes()
    assert hashlib.sha256(data.replace(b"\r\n", b"\n")).hexdigest() == FMI_2_0_1_HEADERS[name]


HARNESS_TWO_FMUS = r"""
#include <stdio.h>
#include <stdlib.h>
#include "fmi2FunctionTypes.h"

/* the functions of both FMUs, as FMI2_FUNCTION_PREFIX names them */
fmi2InstantiateTYPE body_fmi2Instantiate, pd_fmi2Instantiate;
fmi2SetupExperimentTYPE body_fmi2SetupExperiment, pd_fmi2SetupExperiment;
fmi2EnterInitializationModeTYPE body_fmi2EnterInitializationMode, pd_fmi2EnterInitializationMode;
fmi2ExitInitializationModeTYPE body_fmi2ExitInitializationMode, pd_fmi2ExitInitializationMode;
fmi2SetRealTYPE body_fmi2SetReal, pd_fmi2SetReal;
fmi2GetRealTYPE body_fmi2GetReal, pd_fmi2GetReal;
fmi2DoStepTYPE body_fmi2DoStep;
fmi2FreeInstanceTYPE body_fmi2FreeInstance, pd_fmi2FreeInstance;

static void logger(fmi2ComponentEnvironment e, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)e; (void)category;
    printf("log %s %d: %s\n", name, (int)status, message);
}

int main(void)
{
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component b = body_fmi2Instantiate("body", fmi2CoSimulation, BODY_GUID, "", &callbacks,
                                           fmi2False, fmi2False);
    fmi2Component p = pd_fmi2Instantiate("pd", fmi2CoSimulation, PD_GUID, "", &callbacks,
                                         fmi2False, fmi2False);
    if (!b || !p) return 2;
    int bad = 0;
    bad |= body_fmi2SetupExperiment(b, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    bad |= pd_fmi2SetupExperiment(p, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    bad |= body_fmi2EnterInitializationMode(b) | body_fmi2ExitInitializationMode(b);
    bad |= pd_fmi2EnterInitializationMode(p) | pd_fmi2ExitInitializationMode(p);
    const fmi2ValueReference pd_in[3] = {0, 1, 2}, pd_out[1] = {3};  /* theta_ref, theta, omega; torque */
    const fmi2ValueReference body_in[1] = {0}, body_out[2] = {1, 2};  /* torque; theta, omega */
    const fmi2Real measured[3] = {0.5, 0.1, 0.2};
    fmi2Real torque, motion[2];
    bad |= pd_fmi2SetReal(p, pd_in, 3, measured) | pd_fmi2GetReal(p, pd_out, 1, &torque);
    bad |= body_fmi2SetReal(b, body_in, 1, &torque) | body_fmi2DoStep(b, 0.0, 0.1, fmi2True);
    bad |= body_fmi2GetReal(b, body_out, 2, motion);
    printf("%.17g %.17g %.17g\n", torque, motion[0], motion[1]);
    body_fmi2FreeInstance(b);
    pd_fmi2FreeInstance(p);
    return bad;
}
"""


@pytest.mark.slow
def test_two_fmus_sources_link_into_one_program(tmp_path):
    """FMI 2.0.1, section 2.1.1: with FMI2_FUNCTION_PREFIX set per FMU, the sources of
    several FMUs compile into one program. Every other symbol must be static or take the
    prefix too, or the link fails with duplicate definitions."""
    objects = []
    defines = []
    for name, system in (("body", body()), ("pd", pd_controller())):
        sources, guid = unpack(export(system, tmp_path / f"{name}.fmu"), tmp_path / name)
        defines.append(f'-D{name.upper()}_GUID="{guid}"')
        for source in ("model.c", "fmi2Functions.c", "lti_instance.c", "linear_model.c"):
            obj = tmp_path / f"{name}_{source}.o"
            subprocess.run(["gcc", "-c", "-std=c99", "-O2", "-pthread", f"-DFMI2_FUNCTION_PREFIX={name}_",
                            f"-I{sources}", "-o", str(obj), str(sources / source)], check=True)
            objects.append(str(obj))
    (tmp_path / "main.c").write_text(HARNESS_TWO_FMUS)
    result = compile_and_run(["gcc", "-std=c99", *defines, f"-I{tmp_path / 'body' / 'sources'}",
                              str(tmp_path / "main.c"), *objects], tmp_path / "both")
    assert result.returncode == 0, result.stdout + result.stderr
    torque, theta, omega = (float(v) for v in result.stdout.split())
    assert torque == 20.0 * (0.5 - 0.1) - 30.0 * 0.2  # 2.0, exact in binary
    # one exact zero-order-hold step of J theta'' = 2 N m from rest: theta = 2/J h^2/2,
    # omega = 2/J h; round-off of a few operations
    assert theta == pytest.approx(2.0 / J * 0.1**2 / 2, rel=1e-14)
    assert omega == pytest.approx(2.0 / J * 0.1, rel=1e-14)


HARNESS_DOUBLE_FREE = r"""
#include <stdio.h>
#include <stdlib.h>
#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment e, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)e; (void)name; (void)status; (void)category; (void)message;
}

int main(void)
{
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component first = fmi2Instantiate("first", fmi2CoSimulation, GUID, "", &callbacks,
                                          fmi2False, fmi2False);
    fmi2Component second = fmi2Instantiate("second", fmi2CoSimulation, GUID, "", &callbacks,
                                           fmi2False, fmi2False);
    if (!first || !second) return 2;
    fmi2FreeInstance(first);
    fmi2FreeInstance(first);                       /* undefined by the standard */
    if (fmi2DoStep(first, 0.0, 0.1, fmi2True) != fmi2Error) return 3;  /* a stale handle */
    if (fmi2SetupExperiment(second, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK) return 4;
    fmi2FreeInstance(second);
    printf("done\n");
    return 0;
}
"""


@pytest.mark.slow
def test_double_free_reads_no_freed_memory(tmp_path):
    """Under AddressSanitizer, a second fmi2FreeInstance and a call on the freed handle
    neither read nor free freed memory, and the other instance is unharmed."""
    sources, guid = unpack(export(body(), tmp_path / "body.fmu"), tmp_path / "body")
    (tmp_path / "main.c").write_text(HARNESS_DOUBLE_FREE)
    files = [str(sources / f) for f in ("model.c", "fmi2Functions.c", "lti_instance.c", "linear_model.c")]
    result = compile_and_run(["gcc", "-std=c99", "-g", "-fsanitize=address", "-fno-omit-frame-pointer",
                              f'-DGUID="{guid}"', f"-I{sources}", str(tmp_path / "main.c"), *files],
                             tmp_path / "double_free")
    assert "AddressSanitizer" not in result.stderr, result.stderr[:2000]
    assert result.returncode == 0 and result.stdout == "done\n", result.stdout + result.stderr


# ---------------------------------------------------------------- steps and overflow


HUGE_STEPS = """
import json, sys
sys.path[:0] = [{support!r}, {root!r}]
from fmi_binary import Binary
from pathlib import Path
binary = Binary(Path({fmu!r}), Path({folder!r}))
results = []
for h in {steps!r}:
    c = binary.initialised()
    status = binary.DoStep(c, 0.0, h, 1)
    results.append([h, status, binary.get(c, *{states!r})[1], binary.last_message()])
    binary.FreeInstance(c)
print(json.dumps(results))
"""

STEPS = [1e50, 1e100, 1e150, 1e155, 1e200, 1e300, 1e307, 3e307, 5e307, 1e308, 1.7976931348623157e308]


def run_steps(tmp_path, system, steps, states):
    path = export(system, tmp_path / "plant.fmu")
    here = Path(__file__).resolve()
    script = HUGE_STEPS.format(support=str(here.parents[1] / "support"),
                               root=str(here.parents[2]), fmu=str(path),
                               folder=str(tmp_path / "plant"), steps=steps, states=states)
    # a step that hangs would hang this test: a separate process with a time limit (each
    # step takes microseconds to milliseconds)
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                            timeout=120)
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout)


@pytest.mark.slow
def test_any_finite_step_returns_at_once(tmp_path):
    """Hub with a rigid body and a flexible mode: steps up to the largest double. The rigid
    body's Gamma grows like h^2 / (2 J), finite up to h ~ 1.8e154 and infinite beyond:
    those steps are discarded with a message and leave the state as it was. (Steps near
    the threshold are left out: there intermediate products may overflow first.)"""
    results = run_steps(tmp_path, hub_with_flexible_mode(), STEPS, ["q", "q_dot", "eta", "eta_dot"])
    for h, status, states, message in results:
        if h <= 1e150:  # Gamma = h^2 / 20 <= 5e298: finite; a step from rest stays at rest
            assert status == OK and states == [0.0, 0.0, 0.0, 0.0]
        else:
            assert status == DISCARD, (h, status)
            assert "not finite" in message and states == [0.0, 0.0, 0.0, 0.0]


def test_huge_step_of_a_stable_system_reaches_its_steady_state(tmp_path):
    """x' = -x + u, y = x: after any step h, x = e^-h x0 + (1 - e^-h) u; for h >= 40,
    e^-h < 1e-17, so x = u to round-off. Thousands of squarings would be needed for
    h = 1e300: the early exit at the fixed point must give the same result."""
    lag = control.ss([[-1.0]], [[1.0]], [[1.0]], 0, inputs=["u"], outputs=["y"], states=["x"])
    path = export(lag, tmp_path / "lag.fmu", x0=[3.0])
    binary = Binary(path, tmp_path / "lag")
    for h in (50.0, 1e10, 1e100, 1e300, 1.7976931348623157e308):
        c = binary.initialised()
        assert binary.set(c, u=2.0) == OK
        assert binary.DoStep(c, 0.0, h, 1) == OK
        status, (x,) = binary.get(c, "x")
        # |x - u| <= a few eps |u| from the Pade approximant and the squarings
        assert status == OK and x == pytest.approx(2.0, rel=1e-14, abs=0), h
        binary.FreeInstance(c)


def huge_gain():
    """x' = 1e308 u, y = 1e308 x: finite matrices whose products overflow."""
    return control.ss([[0.0]], [[1e308]], [[1e308]], 0, inputs=["u"], outputs=["y"], states=["x"])


def test_output_overflow_discards_the_step(tmp_path):
    binary = Binary(export(huge_gain(), tmp_path / "gain.fmu"), tmp_path / "gain")
    c = binary.initialised()
    try:
        assert binary.set(c, u=1e-300) == OK
        # x = Gamma u = 1e306 * 1e-300 = 1e6 is finite, y = 1e308 * 1e6 is not
        assert binary.DoStep(c, 0.0, 0.01, 1) == DISCARD
        assert "output y overflowed" in binary.last_message()
        assert binary.get(c, "x") == (OK, [0.0])  # the state was not changed
    finally:
        binary.FreeInstance(c)


def test_output_and_derivative_overflow_when_read(tmp_path):
    """Model Exchange: fmi2Discard (the integrator may retry with a smaller step);
    Co-Simulation: fmi2Error (only inputs set after a checked step can cause it)."""
    binary = Binary(export(huge_gain(), tmp_path / "gain.fmu"), tmp_path / "gain")
    c = binary.initialised(MODEL_EXCHANGE)
    try:
        assert binary.set(c, u=10.0) == OK  # der(x) = 1e309
        derivatives = (c_double * 1)()
        assert binary.GetDerivatives(c, derivatives, 1) == DISCARD
        assert "derivative of state x is not finite" in binary.last_message()
        assert binary.get(c, "der(x)")[0] == DISCARD
        assert binary.set(c, u=0.0) == OK
        assert binary.get(c, "y", "der(x)") == (OK, [0.0, 0.0])
    finally:
        binary.FreeInstance(c)
    c = binary.instantiate(CO_SIMULATION)
    try:
        assert binary.set(c, x=10.0) == OK  # a start value: y = 1e309
        assert binary.SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == OK
        assert binary.EnterInitializationMode(c) == OK
        assert binary.get(c, "y")[0] == ERROR
        assert "output y is not finite" in binary.last_message()
        assert binary.get(c, "x") == (OK, [10.0])
    finally:
        binary.FreeInstance(c)
