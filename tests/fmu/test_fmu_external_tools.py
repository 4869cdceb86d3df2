"""The FMUs through FMI tools flexsat did not write, where they are installed: the
Modelica Association's Reference-FMUs ``fmusim`` (FMI 2.0 and 3.0; XSD validation, the
standard calling sequences, serialised FMU states) and the FMU Compliance Checker
``fmuCheck`` (FMI 2.0 only).

The tools are looked up in ``$FMI_TOOLS_BIN`` (default ``/work/tools/bin``), then on PATH;
each test is skipped, saying which tool is missing, where it is not there. The core checks
of the repository (validation, simulation, rollback, derivatives) rely on fmpy and run
everywhere; these add the independent importers.

References compared with: the FMUs' own cross-check files (``fmu.export(...,
reference=True)``: ``control.c2d`` + ``forced_response`` at the communication points) and,
for ME, the same at the solver's tolerance.
"""

from pathlib import Path

import numpy as np
import pytest

import fmu
from fmi_tools import (assert_matches_reference, early_events, first_per_time, last_per_time,
                       read_table, run, tool)
from fmu_cases import SAMPLE_TIME, SYSTEMS


@pytest.fixture(scope="module")
def cases(tmp_path_factory):
    """hub (continuous) and the digital LQR (sampled), both versions, with reference files."""
    folder = tmp_path_factory.mktemp("tools")
    out = {}
    for name, step, stop in (("hub", 0.01, 4.0), ("lqr", SAMPLE_TIME, 2.0)):
        for version in ("2.0", "3.0"):
            path = fmu.export(SYSTEMS[name](), folder / f"{name}{version[0]}.fmu",
                              fmi_version=version, step=step, stop_time=stop, reference=True)
            out[name, version] = path
    return out


@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("name", ["hub", "lqr"])
def test_fmusim_co_simulation(cases, name, version, tmp_path):
    """fmusim CS at the reference step: exact to round-off (1e-12 relative, as in the
    fmpy tests), for the sampled controller too (left limits at input steps, see
    first_per_time); for the sampled FMI 3.0 controller with --event-mode-used (an
    importer that uses Event Mode but does not activate clocks) the same result. (The
    continuous FMI 3.0 FMU declares hasEventMode="false" and refuses eventModeUsed.)"""
    fmusim = tool("fmusim")
    path = cases[name, version]
    stem = path.with_suffix("")
    options = dict(line.split(",") for line in Path(f"{stem}_ref.opt").read_text().splitlines())
    command = [fmusim, "--interface-type", "cs", "--input-file", f"{stem}_in.csv",
               "--stop-time", options["StopTime"].strip(),
               "--output-interval", options["StepSize"].strip()]
    result = run(command + ["--output-file", str(tmp_path / "cs.csv"), str(path)])
    assert result.returncode == 0, result.stdout + result.stderr
    assert_matches_reference(tmp_path / "cs.csv", Path(f"{stem}_ref.csv"), 1e-12, first_per_time)
    if version == "3.0" and name == "lqr":
        result = run(command + ["--event-mode-used", "--output-file", str(tmp_path / "ev.csv"),
                                str(path)])
        assert result.returncode == 0, result.stdout + result.stderr
        assert_matches_reference(tmp_path / "ev.csv", tmp_path / "cs.csv", 0.0, first_per_time)


@pytest.mark.parametrize("version", ["2.0", "3.0"])
def test_fmusim_model_exchange(cases, version, tmp_path):
    """fmusim's CVODE (with the local input-event fix, fmusim-ir: plain fmusim's CVODE
    keeps integrating over input steps, a bug of the tool) at rtol 1e-8: the solver's error
    against the exact response, bounded at 1e-5 relative (observed ~1e-7)."""
    fmusim = tool("fmusim-ir")
    path = cases["hub", version]
    stem = path.with_suffix("")
    result = run([fmusim, "--interface-type", "me", "--solver", "cvode", "--tolerance", "1e-8",
                  "--input-file", f"{stem}_in.csv", "--stop-time", "4", "--output-interval",
                  "0.01", "--output-file", str(tmp_path / "me.csv"), str(path)])
    assert result.returncode == 0, result.stdout + result.stderr
    assert_matches_reference(tmp_path / "me.csv", Path(f"{stem}_ref.csv"), 1e-5)


@pytest.mark.parametrize("version", ["2.0", "3.0"])
@pytest.mark.parametrize("name", ["hub", "lqr"])
def test_fmusim_resumes_from_a_serialised_state(cases, name, version, tmp_path):
    """fmusim saves the serialised FMU state at the end of a run and restores it in a fresh
    instance (without initialising it) for a second run: the second half equals the
    second half of one whole run, bit for bit."""
    fmusim = tool("fmusim")
    path = cases[name, version]
    stem = path.with_suffix("")
    h = "0.01" if name == "hub" else str(SAMPLE_TIME)
    base = [fmusim, "--interface-type", "cs", "--input-file", f"{stem}_in.csv",
            "--output-interval", h]
    whole = run(base + ["--stop-time", "2", "--output-file", str(tmp_path / "whole.csv"), str(path)])
    first = run(base + ["--stop-time", "1", "--output-file", str(tmp_path / "first.csv"),
                        "--final-fmu-state-file", str(tmp_path / "state.bin"), str(path)])
    second = run(base + ["--start-time", "1", "--stop-time", "2", "--output-file",
                         str(tmp_path / "second.csv"), "--initial-fmu-state-file",
                         str(tmp_path / "state.bin"), str(path)])
    for result in (whole, first, second):
        assert result.returncode == 0, result.stdout + result.stderr
    a, b = last_per_time(read_table(tmp_path / "whole.csv")), last_per_time(read_table(tmp_path / "second.csv"))
    tail = a["time"] >= 1.0 + 1e-9
    for column in b:
        if column != "time":
            np.testing.assert_array_equal(b[column][b["time"] >= 1.0 + 1e-9], a[column][tail])


@pytest.mark.parametrize("name", ["hub", "lqr"])
def test_fmu_compliance_checker(cases, name, tmp_path):
    """fmuCheck (FMI 2.0 only): XML, CS and (continuous) ME through its own C importer:
    no warnings and no errors in its summary (it exits 0 even with errors, so the summary
    is read), and its CS result equals the reference to round-off (1e-12 relative)."""
    checker = tool("fmuCheck.linux64")
    path = cases[name, "2.0"]
    stem = path.with_suffix("")
    h = 0.01 if name == "hub" else SAMPLE_TIME
    stop = "4" if name == "hub" else "2"
    inputs = early_events(Path(f"{stem}_in.csv"), tmp_path / "in.csv", h)
    for kind in ("xml", "cs", "me"):
        if kind == "me" and name == "lqr":
            continue  # a sampled FMU is Co-Simulation only
        log = tmp_path / f"{kind}.log"
        command = [checker, "-l", "3", "-k", kind, "-o", str(tmp_path / f"{kind}.csv"),
                   "-e", str(log)]
        if kind != "xml":
            command += ["-i", str(inputs), "-s", stop, "-h", repr(h) if kind == "cs" else "1e-4",
                        "-n", "0" if kind == "cs" else "400"]
        result = run(command + [str(path)])
        text = log.read_text(errors="replace") + result.stdout + result.stderr
        assert "0 Warning(s)" in text and "0 Error(s)" in text, text[-2000:]
    assert_matches_reference(tmp_path / "cs.csv", Path(f"{stem}_ref.csv"), 1e-12, first_per_time)
