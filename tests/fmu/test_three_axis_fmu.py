"""Three-axis plants, controllers and closed loops as FMUs (issue 11, item 4): FMI 2.0 and
3.0, Model Exchange and Co-Simulation, checked as the planar FMUs are.

Systems (built once per session): a free-floating spacecraft with a full inertia tensor, two
rectangular wings canted about their axes and a tube boom off the principal axes (the shape
of ``benchmarks/three_axis.py``, with 1 % modal damping so that fixed-step forward Euler, the
ME integrator of fmuCheck, is stable on it: h = 1e-4 s < 2 zeta / w_max); each beam is
truncated to 4 Craig-Bampton modes and the plant keeps the first 6 coupled elastic modes
(highest ~30 rad/s), with tip motions and root loads (D != 0). The design plant is the same
spacecraft with 3-body chains. Controllers on it: PD per principal axis with a roll-off
(continuous and digital), LQR + Kalman (continuous and digital); loops: the continuous LQR on
the beam plant, the digital LQR on it (a sampled-data loop).

References: python-control, as for the planar FMUs (tests/fmu/test_fmu_simulation.py,
test_fmu3_simulation.py, test_fmu_sampled.py): for inputs held over each step the zero-order-
hold discretisation ``control.c2d(sys, h, "zoh")`` is the exact response at the grid points,
so CS equals it to round-off (each step adds a few ulps of |x|; over N = 400 steps of
non-growing modes below N * 10 eps relative: 1e-12), ME to the solver's tolerance
(CVode at rtol 1e-10: 1e-6 relative, as for the planar FMU). A sampled controller is its own
recurrence (``forced_response`` of the discrete system).
"""

from __future__ import annotations

import atexit
import functools
import math
import shutil
import tempfile
from pathlib import Path

import control
import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

import controllers
import fmu
from appendages import Beam
from appendages.fit3d import fit_chain_3d
from spacecraft import Hub, Mount, Spacecraft
from spacecraft.dynamics.kinematics import euler_orientation, orientation_from_axis

AXES = ("x", "y", "z")
SAMPLE_TIME = 0.1  # s, digital controllers (>= 10 samples per rigid-body crossover)
STEP = 0.01        # s, communication step of the continuous FMUs
STOP = 4.0         # s
HUB_INERTIA = np.array([[950.0, 12.0, -8.0], [12.0, 780.0, 15.0], [-8.0, 15.0, 640.0]])


def _spacecraft(model, damping_ratio: float = 0.01) -> Spacecraft:
    cant = math.radians(20.0)
    wing = Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8, damping_ratio=damping_ratio)
    boom = Beam.tube(4.0, 0.05, 0.001, 1600.0, 1.2e11, damping_ratio=damping_ratio)
    return Spacecraft(Hub(820.0, HUB_INERTIA), [
        Mount(model(wing), (0.0, 1.1, 0.0), orientation=euler_orientation("ZYX", (math.pi / 2, 0.0, cant)),
              name="wing_left"),
        Mount(model(wing), (0.0, -1.1, 0.0),
              orientation=euler_orientation("ZYX", (-math.pi / 2, 0.0, cant)), name="wing_right"),
        Mount(model(boom), (0.6, 0.3, -0.9), orientation=orientation_from_axis((1.0, -0.5, -1.2)),
              name="boom")])


@functools.lru_cache(maxsize=None)
def system(name: str) -> control.StateSpace:
    """The systems of the module docstring, by name."""
    if name == "plant":
        return _spacecraft(lambda b: b.truncated(4)).plant(
            tip_deflection=True, root_loads=True, n_modes=6, prune=True, name="plant")
    if name == "chain":
        return _spacecraft(lambda b: fit_chain_3d(b, 3)).plant(n_modes=6, prune=True)
    design = system("chain")
    if name in ("pd", "pd_digital"):
        return controllers.pd(design, natural_frequency=0.1, damping=0.7, roll_off=1.0,
                              sample_time=SAMPLE_TIME if name == "pd_digital" else None)
    if name in ("lqr", "lqr_digital"):
        return controllers.lqr(design, attitude_weight=100.0, rate_weight=1000.0,
                               torque_weight=1.0,
                               sample_time=SAMPLE_TIME if name == "lqr_digital" else None)
    if name == "loop":
        return controllers.close_loop(system("plant"), system("lqr"))
    if name == "loop_digital":
        return controllers.close_loop(system("plant"), system("lqr_digital"))
    raise KeyError(name)


_folder = Path(tempfile.mkdtemp(prefix="flexsat-test-3ax-fmus-"))
atexit.register(shutil.rmtree, _folder, True)


@functools.lru_cache(maxsize=None)
def exported(name: str, version: str) -> Path:
    """``system(name)`` as an FMI ``version`` FMU with cross-check files (cached)."""
    sys_ = system(name)
    step = SAMPLE_TIME if sys_.dt else STEP
    return fmu.export(sys_, _folder / f"{name}_{version[0]}.fmu", fmi_version=version,
                      step=step, stop_time=STOP, reference=True)


def step_inputs(names, switch: dict[str, list[tuple[float, float]]]) -> np.ndarray:
    """fmpy input table: each input piecewise constant, switch[name] = [(t, value), ...] from
    t on; a step is two rows at the same time (before, after)."""
    times = sorted({t for steps in switch.values() for t, _ in steps} | {0.0})

    def value(name, t, after):
        v = 0.0
        for ts, vs in switch.get(name, []):
            if ts < t or (after and ts == t):
                v = vs
        return v

    rows = []
    for t in times:
        rows.append((t, *[value(n, t, False) for n in names]))
        rows.append((t, *[value(n, t, True) for n in names]))
    rows.append((1e3, *[value(n, 1e3, True) for n in names]))
    return np.array(rows[1:], dtype=[("time", np.float64)] + [(n, np.float64) for n in names])


def held(table: np.ndarray, names, t: np.ndarray) -> np.ndarray:
    """The right-continuous values of the table's inputs at the times t, shape (m, len(t))."""
    out = np.zeros((len(names), t.size))
    for k, tk in enumerate(t):
        row = max(np.count_nonzero(table["time"] <= tk + 1e-12) - 1, 0)
        out[:, k] = [table[n][row] for n in names]
    return out


def zoh_response(sys_: control.StateSpace, table: np.ndarray, h: float, t_end: float, *,
                 left: bool = True):
    """Outputs at t_k = k h: the state takes the input held from t_k on; with ``left`` the
    output is C x_k + D u(t_k-), with the input before a step at t_k, as fmpy's CS master
    records it (it reads the outputs before it sets the inputs of the instant: the left
    limit, which differs where D != 0); else the right limit (ME rows after an event)."""
    t = np.arange(int(round(t_end / h)) + 1) * h
    u = held(table, list(sys_.input_labels), t)
    u_left = held(table, list(sys_.input_labels), t - 1e-9)
    u_left[:, 0] = u[:, 0]
    discrete = sys_ if sys_.dt else control.c2d(sys_, h, "zoh")
    y = np.asarray(control.forced_response(discrete, T=t, U=u).outputs)
    return t, (y + np.asarray(sys_.D) @ (u_left - u)) if left else y


def _steps(system_: control.StateSpace) -> dict:
    """Steps on every input of the system at distinct grid times inside [0, STOP / 2]."""
    m = system_.ninputs
    return {name: [(round(0.2 + 0.3 * k, 2), 1.0 if k % 2 == 0 else -0.5),
                   (round(1.9 - 0.1 * k, 2), 0.3)]
            for k, name in enumerate(system_.input_labels) if k < m}


# ----- variables: names, causality, variability, units -----------------------------------------
EXPECTED_UNITS = {"torque": "N.m", "theta": "rad", "omega": "rad/s", "tip_deflection": "m",
                  "tip_twist": "rad", "root_force": "N", "root_moment": "N.m"}


def _expected_unit(name: str) -> str:
    for key, unit in EXPECTED_UNITS.items():
        if key in name:
            return unit
    raise AssertionError(f"no expected unit for {name}")


@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("name", ["plant", "lqr", "lqr_digital", "pd", "loop"])
def test_variables_have_the_three_axis_names_causality_and_units(name, version):
    sys_ = system(name)
    description = read_model_description(str(exported(name, version)))
    variables = {v.name: v for v in description.modelVariables}
    inputs = [v.name for v in description.modelVariables if v.causality == "input"
              and v.name != "sample_clock"]
    outputs = [v.name for v in description.modelVariables if v.causality == "output"]
    assert inputs == list(sys_.input_labels)
    assert outputs == list(sys_.output_labels)
    for signal in inputs + outputs:
        assert variables[signal].unit == _expected_unit(signal), signal
        discrete_output = sys_.dt and variables[signal].causality == "output"
        assert variables[signal].variability == ("discrete" if discrete_output else "continuous")
    assert (description.modelExchange is None) == bool(sys_.dt)
    assert description.coSimulation is not None
    if name == "plant":
        assert inputs == [f"torque_{a}" for a in AXES]
        assert outputs[:6] == [f"theta_{a}" for a in AXES] + [f"omega_{a}" for a in AXES]
        for label in ("wing_left", "wing_right", "boom"):
            for motion in ("tip_deflection_y", "tip_deflection_z", "tip_twist"):
                assert f"{label}_{motion}" in outputs
    if name in ("lqr", "lqr_digital", "pd"):
        assert inputs == ([f"theta_ref_{a}" for a in AXES] + [f"theta_{a}" for a in AXES]
                          + [f"omega_{a}" for a in AXES])
        assert outputs == [f"torque_{a}" for a in AXES]


# ----- Co-Simulation and Model Exchange against python-control ---------------------------------
@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("name", ["plant", "pd", "lqr", "loop", "pd_digital", "lqr_digital",
                                  "loop_digital"])
def test_co_simulation_equals_python_control(name, version):
    """Steps on every input (different times and signs, so every axis and every column of B
    and D is exercised); CS at the default step equals c2d(zoh) + forced_response (continuous)
    or the discrete recurrence (sampled), 1e-12 relative to each signal's size (module
    docstring)."""
    sys_ = system(name)
    h = SAMPLE_TIME if sys_.dt else STEP
    table = step_inputs(list(sys_.input_labels), _steps(sys_))
    result = simulate_fmu(str(exported(name, version)), fmi_type="CoSimulation", stop_time=STOP,
                          output_interval=h, input=table)
    t, y = zoh_response(sys_, table, h, STOP)
    np.testing.assert_allclose(result["time"], t, rtol=0, atol=1e-12)
    for i, signal in enumerate(sys_.output_labels):
        scale = np.max(np.abs(y[i]))
        if np.any(sys_.C[i]) or np.any(sys_.D[i]):
            assert scale > 0, signal  # every output the model can move is moved
        np.testing.assert_allclose(result[signal], y[i], rtol=0, atol=1e-12 * scale,
                                   err_msg=signal)


@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("name", ["plant", "pd", "lqr", "loop"])
def test_model_exchange_equals_the_continuous_response(name, version):
    """CVode at rtol 1e-10 against the exact response to inputs stepping on the output grid
    (the ZOH discretisation, exact there): the solver's error, 1e-6 relative to each signal's
    size as for the planar FMU (observed ~1e-8)."""
    sys_ = system(name)
    table = step_inputs(list(sys_.input_labels), _steps(sys_))
    result = simulate_fmu(str(exported(name, version)), fmi_type="ModelExchange", stop_time=STOP,
                          output_interval=STEP, relative_tolerance=1e-10, input=table)
    t, y = zoh_response(sys_, table, STEP, STOP, left=False)
    last = np.r_[np.diff(result["time"]) > 0, True]
    np.testing.assert_allclose(result["time"][last], t, rtol=0, atol=1e-9)
    for i, signal in enumerate(sys_.output_labels):
        scale = np.max(np.abs(y[i]))
        np.testing.assert_allclose(result[signal][last], y[i], rtol=0, atol=1e-6 * scale,
                                   err_msg=signal)


@pytest.mark.parametrize("versions", [("2.0", "2.0"), ("3.0", "3.0"), ("2.0", "3.0")])
def test_plant_and_digital_lqr_cosimulated_equal_the_sampled_loop(versions):
    """Plant FMU (continuous) + digital three-axis LQR FMU, Gauss-Seidel master at h = T:
    equal to controllers.close_loop(plant, K_digital) (the ZOH plant in the loop with the
    discrete controller), 1e-12 relative (same ZOH matrices, round-off only)."""
    t_end = 3.0
    reference = {"theta_ref_x": 0.01, "theta_ref_y": -0.02, "theta_ref_z": 0.015}
    result = fmu.cosimulate(exported("plant", versions[0]), exported("lqr_digital", versions[1]),
                            t_end, SAMPLE_TIME, inputs=reference)
    loop, plant = system("loop_digital"), system("plant")
    t = np.arange(int(round(t_end / SAMPLE_TIME)) + 1) * SAMPLE_TIME
    U = np.array([np.full(t.size, reference[n]) for n in loop.input_labels])
    y = np.asarray(control.forced_response(loop, T=t, U=U).outputs)
    # the master reads the plant's outputs before it sets the torques u_k: its root loads
    # (D != 0 from the torques) show D u_k-1 where the monolithic loop has D u_k
    torques = y[[list(loop.output_labels).index(f"torque_{a}") for a in AXES]]
    previous = np.hstack([np.zeros((3, 1)), torques[:, :-1]])
    y[:plant.noutputs] += np.asarray(plant.D) @ (previous - torques)
    assert set(loop.output_labels) <= set(result.dtype.names)
    for i, signal in enumerate(loop.output_labels):
        np.testing.assert_allclose(result[signal], y[i], rtol=0,
                                   atol=1e-12 * np.max(np.abs(y[i])), err_msg=signal)


# ----- a stiff plant: the benchmark's spacecraft, undamped, 10 modes per appendage --------------
def test_co_simulation_is_exact_on_the_stiff_undamped_plant(tmp_path):
    """10 Craig-Bampton modes per appendage, no damping (modes up to ~1900 rad/s: 19 rad per
    0.01 s step, where an explicit integrator diverges): the CS step is the exact ZOH map,
    equal to c2d + forced_response, 1e-12 relative, and bounded."""
    plant = _spacecraft(lambda b: b.truncated(10), damping_ratio=0.0).plant(
        tip_deflection=True, prune=True)
    assert np.abs(np.linalg.eigvals(plant.A)).max() * STEP > 10
    path = fmu.export(plant, tmp_path / "stiff.fmu", fmi_version="3.0", step=STEP)
    table = step_inputs(list(plant.input_labels), _steps(plant))
    result = simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=STOP,
                          output_interval=STEP, input=table)
    t, y = zoh_response(plant, table, STEP, STOP)
    for i, signal in enumerate(plant.output_labels):
        np.testing.assert_allclose(result[signal], y[i], rtol=0,
                                   atol=1e-12 * np.max(np.abs(y[i])), err_msg=signal)


# ----- the FMI tools flexsat did not write (skipped where not installed) ------------------------
@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("name", ["plant", "lqr_digital", "loop"])
def test_fmusim(name, version, tmp_path):
    """fmusim CS at the reference step equals the FMU's reference files (python-control) to
    round-off, 1e-12 relative (left limits at input steps, as fmpy); fmusim's CVODE (fmusim-ir,
    see test_fmu_external_tools) at rtol 1e-8 to the solver's error, 1e-5 relative."""
    from fmi_tools import assert_matches_reference, first_per_time, run, tool
    path = exported(name, version)
    stem = path.with_suffix("")
    h = repr(SAMPLE_TIME if system(name).dt else STEP)
    common = ["--input-file", f"{stem}_in.csv", "--stop-time", repr(STOP), "--output-interval", h]
    result = run([tool("fmusim"), "--interface-type", "cs", *common,
                  "--output-file", str(tmp_path / "cs.csv"), str(path)])
    assert result.returncode == 0, result.stdout + result.stderr
    assert_matches_reference(tmp_path / "cs.csv", Path(f"{stem}_ref.csv"), 1e-12, first_per_time)
    if not system(name).dt:
        result = run([tool("fmusim-ir"), "--interface-type", "me", "--solver", "cvode",
                      "--tolerance", "1e-8", *common, "--output-file", str(tmp_path / "me.csv"),
                      str(path)])
        assert result.returncode == 0, result.stdout + result.stderr
        assert_matches_reference(tmp_path / "me.csv", Path(f"{stem}_ref.csv"), 1e-5)


@pytest.mark.parametrize("name", ["plant", "lqr_digital", "loop"])
def test_fmu_compliance_checker(name, tmp_path):
    """fmuCheck (FMI 2.0): XML, CS and (continuous) ME with no warning and no error in its
    summary; its CS result equals the reference files to round-off (1e-12 relative). Its ME is
    forward Euler at h = 1e-4 s, stable here (1 % damping, modes below 40 rad/s: h < 2 zeta /
    w); its first-order error is not compared (test_fmu_external_tools compares none)."""
    from fmi_tools import (assert_matches_reference, early_events, first_per_time,
                                         run, tool)
    checker = tool("fmuCheck.linux64")
    path = exported(name, "2.0")
    stem = path.with_suffix("")
    h = SAMPLE_TIME if system(name).dt else STEP
    inputs = early_events(Path(f"{stem}_in.csv"), tmp_path / "in.csv", h)
    for kind in ("xml", "cs") if system(name).dt else ("xml", "cs", "me"):
        log = tmp_path / f"{kind}.log"
        command = [checker, "-l", "3", "-k", kind, "-o", str(tmp_path / f"{kind}.csv"),
                   "-e", str(log)]
        if kind != "xml":
            command += ["-i", str(inputs), "-s", repr(STOP), "-h", repr(h) if kind == "cs" else "1e-4",
                        "-n", "0" if kind == "cs" else "400"]
        result = run(command + [str(path)])
        text = log.read_text(errors="replace") + result.stdout + result.stderr
        assert "0 Warning(s)" in text and "0 Error(s)" in text, text[-2000:]
    assert_matches_reference(tmp_path / "cs.csv", Path(f"{stem}_ref.csv"), 1e-12, first_per_time)
