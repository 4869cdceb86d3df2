"""The flexsat command: exit codes, files written, JSON content, nothing half-written."""
import json
import subprocess
import sys

import numpy as np
import pytest

from appendages import Beam
from appendages.equivalence import fit_chain
from spacecraft import cli
from spacecraft.design.loop import run

from command import flexsat
from scenes import BASE_TOML, edited


def test_run_writes_the_report_folder(scene_file, tmp_path, capsys):
    out = tmp_path / "report"
    assert flexsat("run", scene_file, "--out", out, "--quiet") == 0
    stdout = capsys.readouterr().out
    assert f"to {out}" in stdout and "PD tuned on chain, paper's fit: stable" in stdout
    for name in ("report.md", "report.html", "results.json", ".flexsat-complete"):
        assert (out / name).is_file(), name
    assert not (out / "fmu").exists() and not (out / "plots").exists()
    data = json.loads((out / "results.json").read_text())
    # every number of the report is in the JSON, equal to what the library gives directly
    direct = run(scene_file)
    row = data["closed_loops"][0]
    assert row["controller"] == "pd" and row["design"] == "frequencies"
    for which in ("design", "truth"):
        for name, value in direct.data["closed_loops"][0]["metrics"][which].items():
            assert row["metrics"][which][name] == pytest.approx(value, rel=1e-12), name
    assert row["verdict"]["stable"] is True
    assert data["fidelity"]["n_modes"] == 3 and data["truth"]["n_states"] > 0
    assert data["stats"]["fmu_builds"] == 0 and data["stats"]["plots"] == 0
    # report.md and report.html carry the same numbers
    md, page = (out / "report.md").read_text(), (out / "report.html").read_text()
    overshoot = f"{row['metrics']['truth']['overshoot']:.5g}"
    assert overshoot in md and overshoot in page
    assert "Verdicts" in md and "Verdicts" in page


def test_run_json_on_stdout(scene_file, tmp_path, capsys):
    assert flexsat("run", scene_file, "--out", tmp_path / "o", "--json", "--quiet") == 0
    data = json.loads(capsys.readouterr().out)
    assert data["closed_loops"][0]["metrics"]["truth"]["peak_tip_deflection"] > 0
    assert data == json.loads((tmp_path / "o" / "results.json").read_text())


def test_progress_goes_to_stderr(scene_file, tmp_path, capsys):
    assert flexsat("run", scene_file, "--out", tmp_path / "o") == 0
    captured = capsys.readouterr()
    assert "closing the loops" in captured.err and "closing the loops" not in captured.out


@pytest.mark.slow
def test_no_plots_flag_and_plots_when_asked(scene_file, tmp_path):
    text = edited(BASE_TOML, ("equivalence = false",
                              "equivalence = false\nplots = [\"slew\", \"poles\"]"))
    scene_file.write_text(text)
    assert flexsat("run", scene_file, "--out", tmp_path / "a", "--quiet") == 0
    assert sorted(p.name for p in (tmp_path / "a" / "plots").iterdir()) == [
        "poles.png", "slew.png"]
    assert json.loads((tmp_path / "a" / "results.json").read_text())["stats"]["plots"] == 2
    assert flexsat("run", scene_file, "--out", tmp_path / "b", "--quiet", "--no-plots") == 0
    assert not (tmp_path / "b" / "plots").exists()
    assert json.loads((tmp_path / "b" / "results.json").read_text())["stats"]["plots"] == 0


@pytest.mark.parametrize("edit, message", [
    (("diameter = 0.01", "diameter = -0.01"),
     r"boom\.toml: appendages\[0\]\.beam\.diameter: must be positive \[m\]; got -0\.01"),
    (("[hub]", "colour = 'red'\n[hub]"), r"boom\.toml: colour: unknown key"),
    (("mass = 100.0", "mass = 'heavy'"), r"boom\.toml: hub\.mass: must be a number"),
])
def test_user_errors_exit_2_with_one_line(scene_file, tmp_path, capsys, edit, message):
    scene_file.write_text(edited(BASE_TOML, edit))
    out = tmp_path / "o"
    assert flexsat("run", scene_file, "--out", out, "--quiet") == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    import re
    assert re.search(message, err)
    assert not out.exists()
    assert not list(tmp_path.glob(".o.partial*"))


def test_missing_scene_file_and_bad_option(tmp_path, capsys):
    assert flexsat("run", tmp_path / "nope.toml", "--out", tmp_path / "o") == 2
    assert "nope.toml: no such scene file" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        flexsat("run", "--frobnicate")
    assert exc.value.code == 2


def test_output_folder_taken_is_a_user_error(scene_file, tmp_path, capsys):
    out = tmp_path / "taken"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    assert flexsat("run", scene_file, "--out", out, "--quiet") == 2
    assert "exists and is not empty" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt"]


def test_failure_leaves_no_half_written_folder(scene_file, tmp_path, capsys, monkeypatch):
    import spacecraft.report.write

    def broken(*args, **kwargs):
        folder = args[1]
        (folder / "report.md").write_text("half")
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(spacecraft.report.write, "write_report", broken)
    out = tmp_path / "o"
    assert flexsat("run", scene_file, "--out", out, "--quiet") == 1
    err = capsys.readouterr().err
    assert "internal error: RuntimeError: disk on fire" in err and "Traceback" not in err
    assert not out.exists()
    assert [p.name for p in tmp_path.iterdir()] == ["boom.toml"]


def test_fit_json_reproduces_the_papers_chain(capsys):
    assert flexsat("fit", "--match", "frequencies", "--json") == 0
    data = json.loads(capsys.readouterr().out)
    lengths = np.array(data["chain"]["lengths"])
    # PAPER.md: k_L = 0.26989, c = 37.134 N*m (printed to 5 digits) from the printed
    # frequencies; the exact Blevins frequencies give 0.26988 and 37.137 (fit_chain docstring)
    assert lengths[1] / lengths.sum() == pytest.approx(0.26989, abs=2e-5)
    assert data["chain"]["hinge_stiffnesses"] == pytest.approx([37.134, 37.134], abs=5e-3)
    assert data["chain"]["mass"] == pytest.approx(6.1261, abs=5e-5)


def test_table_json_matches_the_library(capsys):
    assert flexsat("table", "--json") == 0
    data = json.loads(capsys.readouterr().out)
    beam = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)
    names = [c["name"] for c in data["columns"]]
    assert names == ["beam, 2 modes (paper)", "chain, flexsat fit", "chain, paper's fit"]
    q = data["quantities"]
    # exact beam: w1, w2 and the zeros of W1 (pinned-free frequencies), closed forms
    assert data["exact"][q.index("w1")] == pytest.approx(beam.natural_frequencies(1)[0],
                                                         rel=1e-12)
    assert data["exact"][q.index("n11")] == pytest.approx(beam.zeros(1, 1)[0], rel=1e-12)
    # the paper's two-mode beam column: its printed k1 = 1.9588, n41 = 0.8793
    two_mode = data["columns"][0]["values"]
    assert two_mode[q.index("k1")] == pytest.approx(1.9588, abs=5e-5)
    assert two_mode[q.index("n41")] == pytest.approx(0.8793, abs=5e-5)
    # the paper's chain column: its printed k1 = 1.5814
    paper = data["columns"][2]["values"]
    assert paper[q.index("k1")] == pytest.approx(fit_chain(beam, 3, match="frequencies")
                                                 .gains()[0], rel=1e-9)
    assert paper[q.index("k1")] == pytest.approx(1.5814, abs=5e-4)


def test_table_prints_the_papers_layout(capsys):
    assert flexsat("table", "--length", "10", "--diameter", "0.01") == 0
    out = capsys.readouterr().out
    for label in ("k2 = k3", "n21 = n31", "w2", "chain, paper's fit", "beam (exact)"):
        assert label in out


def test_table_bad_beam_option_is_a_user_error(capsys):
    assert flexsat("table", "--diameter", "-1") == 2
    assert "beam.diameter: must be positive [m]" in capsys.readouterr().err


def test_help_everywhere(capsys):
    for command in ([], ["run"], ["table"], ["fit"], ["export"], ["scenes"]):
        with pytest.raises(SystemExit) as exc:
            flexsat(*command, "--help")
        assert exc.value.code == 0
        assert "usage: flexsat" in capsys.readouterr().out


@pytest.mark.slow
def test_console_entry_point_runs_as_a_module():
    done = subprocess.run([sys.executable, "-m", "spacecraft.cli", "scenes"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0
    assert "two_wings" in done.stdout and "hinged_wing" in done.stdout


def test_export_writes_fmus_and_cross_check_files(scene_file, tmp_path, capsys):
    """The one test that compiles FMUs (about 0.3 s each)."""
    out = tmp_path / "fmus"
    assert flexsat("export", scene_file, "--out", out, "--quiet") == 0
    names = sorted(p.name for p in (out / "fmu").iterdir())
    for model in ("plant", "pd", "closed_loop_pd"):
        for suffix in (".fmu", "_in.csv", "_ref.csv", "_ref.opt"):
            assert model + suffix in names
    assert not (out / "report.md").exists()
    from fmpy import simulate_fmu
    from fmpy.util import read_csv
    from fmpy.validation import validate_fmu

    folder = out / "fmu"
    assert validate_fmu(str(folder / "closed_loop_pd.fmu")) == []
    # the FMU reproduces its own cross-check reference (computed by python-control) when driven
    # by the cross-check input file: co-simulation with zero-order hold is exact at the grid
    reference = read_csv(str(folder / "closed_loop_pd_ref.csv"))
    inputs = read_csv(str(folder / "closed_loop_pd_in.csv"))
    options = dict(line.split(",") for line in
                   (folder / "closed_loop_pd_ref.opt").read_text().split("\n") if line)
    result = simulate_fmu(str(folder / "closed_loop_pd.fmu"), fmi_type="CoSimulation",
                          stop_time=float(options["StopTime"]),
                          output_interval=float(options["StepSize"]), input=inputs)
    t_ref = reference["time"]
    grid = np.concatenate([t_ref[:-1][np.diff(t_ref) > 0], t_ref[-1:]])  # right limits
    theta_ref = np.array([reference["theta"][np.flatnonzero(t_ref == t)[-1]] for t in grid])
    theta = np.interp(grid, result["time"], result["theta"])
    # 1e-9 of the signal's size: ZOH stepping is exact, the rest is round-off
    np.testing.assert_allclose(theta, theta_ref, rtol=0, atol=1e-9 * np.abs(theta_ref).max())
    assert "closed_loop_pd.fmu" in capsys.readouterr().out


@pytest.mark.slow
@pytest.mark.parametrize("name", ["single_boom", "two_wings", "hinged_wing"])
def test_example_scenes_run(name, tmp_path, capsys):
    out = tmp_path / name
    assert flexsat("run", name, "--out", out, "--no-fmu", "--no-plots", "--quiet") == 0
    data = json.loads((out / "results.json").read_text())
    assert data["closed_loops"] and all(r["verdict"]["stable"] for r in data["closed_loops"])
    assert f"to {out}" in capsys.readouterr().out


# ---------------------------------------------------------------------------------------------
# issue 14, command line: --version, --debug anywhere, scenes --json, did-you-mean, progress
# ---------------------------------------------------------------------------------------------
def test_version_prints_the_project_version(capsys):
    import tomllib
    from pathlib import Path

    # the project these tests belong to (an installed flexsat has no pyproject.toml beside it)
    pyproject = Path(__file__).resolve().parents[3] / "pyproject.toml"
    expected = tomllib.loads(pyproject.read_text())["project"]["version"]
    with pytest.raises(SystemExit) as exc:
        flexsat("--version")
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"flexsat {expected}"


@pytest.mark.parametrize("command", [["run"], ["table"], ["fit"], ["export"], ["scenes"]])
def test_debug_is_accepted_after_the_subcommand(command):
    parser = cli.build_parser()
    assert parser.parse_args(command + ["--debug"]).debug is True
    assert parser.parse_args(["--debug"] + command).debug is True
    assert parser.parse_args(command).debug is False


def test_debug_after_the_subcommand_shows_the_traceback(scene_file, tmp_path, capsys,
                                                       monkeypatch):
    import spacecraft.design.loop

    def broken(*args, **kwargs):
        raise ZeroDivisionError("x")
    monkeypatch.setattr(spacecraft.design.loop, "run", broken)
    assert flexsat("run", scene_file, "--out", tmp_path / "o", "--quiet", "--debug") == 1
    assert "Traceback" in capsys.readouterr().err


@pytest.mark.slow
def test_scenes_json_lists_name_title_and_a_loadable_path(capsys):
    from spacecraft.scene.read import example_scenes, load_scene

    assert flexsat("scenes", "--json") == 0
    scenes = json.loads(capsys.readouterr().out)
    assert [s["name"] for s in scenes] == example_scenes()
    for s in scenes:
        assert load_scene(s["path"]).title == s["title"]


def test_a_misspelt_scene_name_suggests_the_embedded_one(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)   # no file of that name here
    assert flexsat("run", "two_wing", "--out", tmp_path / "o") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "two_wing: no such scene file or embedded scene" in err
    assert "did you mean 'two_wings'?" in err


def test_fit_shows_progress_on_stderr_unless_quiet(capsys):
    assert flexsat("fit", "--n-bodies", "3", "--json") == 0
    captured = capsys.readouterr()
    assert "fitting a chain of 3 bodies (match = 'poles-and-zeros')" in captured.err
    json.loads(captured.out)   # stdout stays pure JSON
    assert flexsat("table", "--quiet") == 0
    assert capsys.readouterr().err == ""


# ---------------------------------------------------------------------------------------------
# issue 15 wired into the command: FMI 2.0 and 3.0, SSP, digital controllers
# ---------------------------------------------------------------------------------------------
DIGITAL_LQR = edited(
    BASE_TOML, ('types = ["pd"]', 'types = ["lqr"]\nsample_rate = 5.0'),
    ("[controller.pd]\nnatural_frequency = 0.1",
     "[controller.lqr]\nattitude_weight = 7.6\ntorque_weight = 1.0"),
    ("step = 0.5\n", ""), ('match = "frequencies"', 'match = "poles-and-zeros"'),
    ("n_modes = 3", "n_modes = 2"), ("duration = 120.0", "duration = 30.0"))


@pytest.mark.slow
def test_a_digital_lqr_exports_fmi2_fmi3_and_ssp_through_run(tmp_path, capsys):
    """Acceptance of issue 15 at the command line: plant, controller and loop as FMI 2.0 and
    3.0 FMUs, valid for fmpy, and an SSP per version whose co-simulation (plant FMU stepped
    at the sample time T with the sampled controller FMU) is the sampled loop of the run."""
    import fmpy
    from fmpy.validation import validate_fmu

    from fmu import cosimulate_ssp

    scene = tmp_path / "dlqr.toml"
    scene.write_text(DIGITAL_LQR)
    out = tmp_path / "o"
    assert flexsat("run", scene, "--fmi-version", "both", "--ssp", "--no-plots", "--quiet",
                   "--out", out) == 0
    data = json.loads((out / "results.json").read_text())
    fmus = {f["path"]: f for f in data["files"]["fmu"]}
    for name in ("plant", "lqr", "closed_loop_lqr"):
        for suffix, version in (("", "2.0"), ("_fmi3", "3.0")):
            path = out / "fmu" / f"{name}{suffix}.fmu"
            assert fmus[f"fmu/{path.name}"]["fmi_version"] == version
            assert validate_fmu(str(path)) == []
            assert fmpy.read_model_description(str(path)).fmiVersion == version
    assert fmus["fmu/lqr.fmu"]["sample_time"] == pytest.approx(0.2)
    ssps = [f["path"] for f in data["files"]["ssp"]]
    assert ssps == ["fmu/loop_lqr.ssp", "fmu/loop_lqr_fmi3.ssp"]
    # the run's sampled loop on the truth plant, at the sample times
    result = run(str(scene))
    reference = result.responses[("poles-and-zeros", "lqr", "truth")]
    t = np.asarray(reference.t).reshape(-1)
    theta = np.asarray(reference.y)[list(reference.output_labels).index("theta")].reshape(-1)
    ref_input = np.asarray(reference.u)[list(reference.input_labels).index("theta_ref")]
    for ssp in ssps:
        table = cosimulate_ssp(out / ssp, 30.0, 0.2,
                               inputs={"theta_ref": (t, ref_input.reshape(-1))})
        got = np.interp(t, table["time"], table["theta"])
        # both are the exactly discretised sampled-data loop; the FMUs' C arithmetic and
        # python-control's differ by round-off growing with the steps: 1e-9 of the range
        np.testing.assert_allclose(got, theta, rtol=0, atol=1e-9 * np.abs(theta).max())


def test_export_options_refuse_contradictions(scene_file, tmp_path, capsys):
    assert flexsat("run", scene_file, "--ssp", "--no-fmu", "--out", tmp_path / "o") == 2
    assert "--no-fmu contradicts" in capsys.readouterr().err
    scene_file.write_text(BASE_TOML + '\n[export]\nfmu = true\nsystems = ["plant"]\n')
    assert flexsat("run", scene_file, "--ssp", "--out", tmp_path / "p") == 2
    # the scene reader checks the option's key with the scene's, and says which option set it
    err = capsys.readouterr().err
    assert "export.ssp: needs both 'plant' and 'controller' in export.systems" in err
    assert err.rstrip().endswith("(set by --ssp)")


# ---------------------------------------------------------------------------------------------
# issue 12, items 3-4: flexsat run --simulator basilisk
# ---------------------------------------------------------------------------------------------
@pytest.mark.slow
@pytest.mark.basilisk
def test_simulator_basilisk_adds_basilisks_run_to_report_json_and_time_series(scene_file,
                                                                              tmp_path, capsys):
    out = tmp_path / "o"
    assert flexsat("run", scene_file, "--simulator", "basilisk", "--no-fmu", "--quiet",
                   "--out", out) == 0
    said = capsys.readouterr().out
    assert "Basilisk, PD: theta [rad] differs from the distributed beam (truth) by" in said
    data = json.loads((out / "results.json").read_text())
    entry = data["basilisk"]["pd"]
    assert entry["design"] == "frequencies" and entry["sample_time"] > 0
    d = entry["differences"]
    for name in ("theta", "rod_tip_deflection"):
        b_truth = d["basilisk_vs_truth"][name]["peak_difference"]
        b_chain = d["basilisk_vs_chain"][name]["peak_difference"]
        c_truth = d["chain_vs_truth"][name]["peak_difference"]
        # peaks of |difference| on the same instants obey the triangle inequality
        assert abs(b_truth - c_truth) <= b_chain * (1 + 1e-9) + 1e-15
        # a 10 deg slew: the nonlinearity is small against the chain's modelling error
        assert b_chain < 0.1 * b_truth
    assert data["stats"]["basilisk_runs"] == 1
    md = (out / "report.md").read_text()
    assert "## Basilisk: the manoeuvre in a nonlinear multibody simulator" in md
    files = [f["path"] for f in data["files"]["timeseries"] if f["model"] == "basilisk"]
    assert files == ["timeseries/pd_basilisk.csv"] and (out / files[0]).is_file()


def test_simulator_basilisk_without_bsk_is_one_line_exit_2(scene_file, tmp_path, capsys,
                                                          monkeypatch):
    import spacecraft.basilisk
    from spacecraft.basilisk import INSTALL_HINT, BasiliskNotInstalled

    def missing():
        raise BasiliskNotInstalled(INSTALL_HINT)
    monkeypatch.setattr(spacecraft.basilisk, "require_basilisk", missing)
    out = tmp_path / "o"
    assert flexsat("run", scene_file, "--simulator", "basilisk", "--out", out) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"flexsat: error: {INSTALL_HINT}"
    assert not out.exists()   # refused before any work


def test_simulator_basilisk_refuses_a_scene_it_cannot_run(scene_file, tmp_path, capsys):
    scene_file.write_text(edited(BASE_TOML, ("step = 0.5\n", 'step = 0.5\n\n'
                                             '[manoeuvre.disturbance]\n'
                                             'input = "rod_tip_force"\namplitude = 1.0\n')))
    assert flexsat("run", scene_file, "--simulator", "basilisk", "--out", tmp_path / "o") == 2
    assert "manoeuvre.disturbance.input: a tip force is not applied by the Basilisk model" \
        in capsys.readouterr().err


def test_help_imports_no_numerical_library():
    """flexsat --help must stay fast (issue 10): neither the package nor the parser import
    numpy, scipy, python-control, matplotlib, fmpy, numba or Dask."""
    code = ("import sys; from spacecraft import cli; cli.build_parser(sweep_arguments=False); "
            "print(' '.join(m for m in ('numpy', 'scipy', 'control', 'matplotlib', 'fmpy', "
            "'numba', 'dask') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=120, check=True)
    assert done.stdout.strip() == ""


def test_package_names_resolve_on_first_use():
    import spacecraft
    import spacecraft.design.loop

    assert spacecraft.run is spacecraft.design.loop.run
    assert callable(spacecraft.sweep) and spacecraft.sweep.__name__ == "spacecraft.sweep"
    assert set(spacecraft.__all__) <= set(dir(spacecraft))
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        spacecraft.nope


def test_the_last_line_counts_in_words(scene_file, tmp_path, capsys):
    """Before: 'wrote report.md, report.html, results.json, 1 plots to ...'."""
    scene_file.write_text(edited(BASE_TOML, ("equivalence = false",
                                             'equivalence = false\nplots = ["slew"]')))
    assert flexsat("run", scene_file, "--out", tmp_path / "o", "--quiet") == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last == f"wrote report.md, report.html, results.json, 1 plot to {tmp_path / 'o'}"


def test_basilisk_table_keeps_small_relative_differences_visible():
    from spacecraft.report.write import _basilisk

    entry = {"design": "frequencies", "bsk_version": "2.12.1", "sample_time": 0.05,
             "dt": 0.05, "summary": "s",
             "differences": {"basilisk_vs_chain": {"theta": {
                 "peak": 0.17, "peak_difference": 1.9e-8, "relative": 1.1e-7}}}}
    blocks = _basilisk({"basilisk": {"pd": entry}})
    table = [b for b in blocks if b[0] == "table"][0]
    # before: "1.9e-08 (0.00 %)"
    assert table[2][0][3] == "1.9e-08 (1.1e-05 %)"
