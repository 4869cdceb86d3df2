"""The report of a flown manoeuvre (spacecraft/report/flown.py, the profile and wheel plots):
every figure of the run in words and tables, results.json in numbers and words, the plots
drawn only where they have something to show."""
import json

import pytest

import spacecraft
from spacecraft.report.write import write_report
from spacecraft.scene.read import SceneError, load_scene

from scenes import BASE, flown_damped, scene_with


@pytest.fixture(scope="module")
def written(tmp_path_factory):
    folder = tmp_path_factory.mktemp("flown")
    data = flown_damped(**{"wheels": {"torque_limit": 0.07, "momentum_limit": 4.0,
                                      "spin_inertia": 0.02},
                           "controller.delay": 0.1, "report": {"plots": True},
                           "manoeuvre.disturbance": {"input": "disturbance_torque",
                                                     "amplitude": 0.005, "start": 100.0,
                                                     "length": 5.0}})
    result = spacecraft.run(data)
    write_report(result, folder)
    return result, folder


@pytest.mark.slow
def test_the_report_shows_the_profile_the_delay_the_wheels_and_the_pointing(written):
    result, folder = written
    text = (folder / "report.md").read_text()
    for heading in ("## The manoeuvre as flown", "### Reference profile for the controllers "
                    "tuned on chain, flexsat fit", "### Delay margins",
                    "### Measured against the end of the profile", "### Reaction wheels",
                    "### Pointing under the sensors' noise"):
        assert heading in text, heading
    assert "ZVD shaper convolved with a bang-coast-bang profile" in text
    assert "the wheels SATURATED from t = " in text
    assert "ECSS-E-ST-60-10C" in text and "integrals over the noise spectrum" in text
    # the summary says it too
    summary = spacecraft.report.write.summary_lines(json.loads(
        (folder / "results.json").read_text()))
    assert any("delay margin" in line and "pointing APE" in line for line in summary)
    html = (folder / "report.html").read_text()
    assert "The manoeuvre as flown" in html


def test_results_json_says_in_words_when_a_wheel_saturated(written):
    result, folder = written
    data = json.loads((folder / "results.json").read_text())
    rows = {r["controller"]: r for r in data["closed_loops"]}
    words = rows["pd"]["wheels"]["truth"]["words"]
    assert words.startswith("the wheels SATURATED from t = ")
    assert rows["pd"]["wheels"]["truth"]["time_saturated"] > 0
    assert rows["lqr"]["wheels"]["truth"]["words"].startswith("no wheel reached a limit")
    assert any(w["code"] == "wheel_saturation" for w in data["design_warnings"])
    facts = data["manoeuvre"]
    assert facts["delay"]["total"] == 0.1
    assert facts["profiles"]["poles-and-zeros"]["shaper"]["kind"] == "zvd"
    assert rows["pd"]["verdict"]["delay"] == 0.1 and rows["pd"]["verdict"]["delay_margin"] > 0
    assert set(rows["pd"]["pointing"]["truth"]["ape"]) == {"theta"}


def test_the_profile_and_wheel_plots_are_drawn(written):
    result, folder = written
    for name in ("profile.png", "wheels.png", "slew.png"):
        png = (folder / "plots" / name).read_bytes()
        assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000, name
    files = json.loads((folder / "results.json").read_text())["files"]["plots"]
    assert "plots/profile.png" in files and "plots/wheels.png" in files


def test_the_time_series_carry_the_wheels_with_units(written):
    result, folder = written
    path = next((folder / "timeseries").glob("*truth*.csv"))
    header = path.read_text().splitlines()[0]
    for column in ("wheel_momentum [N*m*s]", "wheel_torque [N*m]",
                   "wheel_torque_command [N*m]", "wheel_speed [rad/s]", "torque_ff [N*m]",
                   "omega_ref [rad/s]"):
        assert column in header, (column, header)


def test_plots_true_draws_the_flown_plots_only_where_they_show_something():
    assert set(load_scene(None).report.plots) == {"slew", "loop", "poles", "W"}
    flown = load_scene(flown_damped(**{"report": {"plots": True}}))
    assert set(flown.report.plots) == {"slew", "loop", "poles", "W", "profile", "wheels"}
    with pytest.raises(SceneError, match=r"report\.plots: asks for 'wheels' but the scene has "
                                         r"none"):
        load_scene(scene_with(**{"report": {"plots": ["wheels"]}}))
    with pytest.raises(SceneError, match=r"report\.plots: asks for 'profile' but the scene has "
                                         r"no manoeuvre table"):
        load_scene(scene_with(**{"report": {"plots": ["profile"]}, "manoeuvre": None}))
    # the step reference drawn when asked by name
    assert load_scene(dict(BASE, report={"plots": ["profile"]})).report.plots == ("profile",)


def test_pointing_figures_not_computed_are_said_in_words():
    from spacecraft.report.flown import flown_blocks
    why = ("the spectral pointing integrals did not reach their relative accuracy 1e-09 "
           "within 100000 quadrature panels")
    row = {"controller": "pd", "design": "poles-and-zeros", "verdict": {"stable": True},
           "pointing": {"design": {"error": why, "not_computed": True, "window": 10.0,
                                   "placement": "random"},
                        "truth": {"error": "the closed loop must be asymptotically stable",
                                  "window": 10.0, "placement": "random"}}}
    blocks = flown_blocks({"manoeuvre": {"flown": True, "delay": {"total": 0.1}},
                           "closed_loops": [row],
                           "scene_resolved": {"sensors": {"attitude_density": 1e-5}}})
    table = [b for b in blocks if b[0] == "table" and "APE (1 sigma)" in b[1]][0][2]
    said = {r[1]: r[3] for r in table}
    assert str(said["design"]) == "not computed: " + why and said["design"].tone == "warn"
    assert said["truth"].tone == "bad"
