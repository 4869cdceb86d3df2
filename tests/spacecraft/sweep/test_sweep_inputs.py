"""What a sweep is given: its table, its keys, its grid, its scene (spacecraft/sweep), each
refused by name when it cannot be swept."""
import tomllib

import pytest

from spacecraft import cli
from spacecraft.scene.read import scene_path
from spacecraft.sweep import SweepError, load_sweep, run_sweep, sweep_scene_path
from spacecraft.sweep.parameters import MAX_SAMPLES, read_sweep, resolve_key

UNIFORM = {"distribution": "uniform", "low": 40.0, "high": 60.0}


def default_scene():
    raw = tomllib.loads(sweep_scene_path("default").read_text())
    raw.pop("sweep")
    return raw


def test_grid_levels_are_counted_before_their_product_overflows():
    """1128506 x 1500025 x 10897261 levels = 18446744073709551650 samples, 2^64 + 34: an
    int64 product wrapped to 34 samples (another to 0); counted in Python integers it is
    refused as beyond the limit."""
    raw = default_scene()
    levels = {"hub.inertia": 1128506, "appendages.rod.beam.youngs_modulus": 1500025,
              "appendages.rod.beam.damping_ratio": 10897261}
    parameters = {"hub.inertia": {**UNIFORM, "levels": levels["hub.inertia"]},
                  "appendages.rod.beam.youngs_modulus": {
                      "distribution": "normal", "mean": 2.06e11, "std": 1e10,
                      "levels": levels["appendages.rod.beam.youngs_modulus"]},
                  "appendages.rod.beam.damping_ratio": {
                      "distribution": "loguniform", "low": 1e-3, "high": 2e-2,
                      "levels": levels["appendages.rod.beam.damping_ratio"]}}
    product = 1128506 * 1500025 * 10897261
    assert product == 2**64 + 34
    with pytest.raises(SweepError, match=rf"sweep: {product} samples exceed the limit of "
                                         rf"{MAX_SAMPLES}"):
        read_sweep({"method": "grid", "parameters": parameters}, raw, "test")
    # 2^32 x 2^32 x 2 wrapped to 0 samples
    parameters = {"hub.inertia": {**UNIFORM, "levels": 2**32},
                  "hub.mass": {"distribution": "uniform", "low": 90.0, "high": 110.0,
                               "levels": 2**32},
                  "appendages.rod.beam.length": {"distribution": "uniform", "low": 9.0,
                                                 "high": 11.0, "levels": 2}}
    with pytest.raises(SweepError, match=rf"{2**65} samples exceed"):
        read_sweep({"method": "grid", "parameters": parameters}, raw, "test")


def test_a_sweep_that_is_not_a_table_is_refused_by_name(tmp_path, capsys):
    path = tmp_path / "five.toml"
    path.write_text("sweep = 5\n" + scene_path("default").read_text())
    assert cli.main(["sweep", str(path), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "sweep: must be a table" in err and "got int 5" in err and err.count("\n") == 1


def test_embedded_scenes_are_found_by_name(capsys, tmp_path):
    """``flexsat sweep single_boom``: the embedded scene, which has no [sweep] table (once:
    "no such scene file"); with parameters (the Python API) it sweeps."""
    assert cli.main(["sweep", "single_boom", "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "single_boom (embedded scene): no [sweep] table" in err
    raw, spec, source = load_sweep("single_boom", parameters={
        "hub.inertia": {"distribution": "uniform", "low": 7.0, "high": 9.0}}, samples=2)
    assert source == "single_boom (embedded scene)" and spec.n_samples == 2
    assert raw["title"].startswith("Single 4 m aluminium boom")
    assert cli.main(["sweep", "no_such_scene", "--quiet"]) == 2
    assert "no such scene file or embedded scene" in capsys.readouterr().err


@pytest.mark.slow
def test_a_three_axis_scene_sweeps_its_tensor_mounts_and_sections():
    """A three-axis scene is no longer refused: the shipped three_axis scene sweeps an
    inertia-tensor entry, a mount angle and a section property (2 samples, the PD held, no
    exact reference: the three-axis sweep's own tests, test_sweep_three_axis.py, check the
    numbers)."""
    raw = tomllib.loads(scene_path("three_axis").read_text())
    raw["controller"]["types"] = ["pd"]
    del raw["controller"]["lqr"]
    raw["outputs"]["exact_reference"] = False
    result = run_sweep(raw, parameters={
        "hub.inertia[1][2]": {"distribution": "uniform", "low": 10.0, "high": 20.0},
        "appendages.boom.orientation[1]": {"distribution": "uniform", "low": 40.0, "high": 50.0},
        "appendages.wing_right.beam.thickness": {"distribution": "uniform", "low": 0.035,
                                                 "high": 0.045}},
        samples=2, workers=1, progress=False, worst_case=False, design="nominal")
    table = result.table.to_pydict()
    assert table["status"] == ["settles", "settles"]
    assert all(m > 0 for m in table["truth_disk_margin"])


def test_the_key_offered_for_an_array_is_one_the_reader_accepts():
    """hub.inertia of a three-axis scene is a 3 x 3 array: ``hub.inertia[0]`` names a row; the
    key offered instead (once ``hub.inertia[2][0]``, which the reader then refused) is its
    first number, and the reader resolves it."""
    raw = tomllib.loads(scene_path("three_axis").read_text())
    with pytest.raises(SweepError, match=r"names an array of 3, not a number; its entries are "
                                         r"numbers: e\.g\. 'hub\.inertia\[0\]\[0\]'"):
        resolve_key("hub.inertia[0]", raw)
    assert resolve_key("hub.inertia[0][0]", raw) == ("hub", "inertia", 0, 0)
    assert resolve_key("hub.inertia[2][1]", raw) == ("hub", "inertia", 2, 1)


@pytest.mark.parametrize("key, spec, match", [
    ("appendages.rod.fit.n_bodies", {"distribution": "uniform", "low": 2.0, "high": 5.0},
     r"'appendages\.rod\.fit\.n_bodies' \(uniform \[2, 5\]\): at its nominal value 3 the "
     r"scene refuses it: .*must be an integer.*distribution = \"discrete\""),
    ("hub." + "x" * 120, {"distribution": "uniform", "low": 2.0, "high": 5.0},
     r"'hub\.x{120}': is not a key the scene knows"),
])
def test_a_key_that_cannot_be_swept_is_blamed_not_its_neighbour(key, spec, match):
    """Swept beside hub.inertia (listed first), a key the scene refuses at its nominal value,
    or does not know, is named; hub.inertia once took the blame."""
    with pytest.raises(SweepError, match=match) as info:
        read_sweep({"parameters": {"hub.inertia": UNIFORM, key: spec}}, default_scene(),
                   "test")
    assert "'hub.inertia'" not in str(info.value)
