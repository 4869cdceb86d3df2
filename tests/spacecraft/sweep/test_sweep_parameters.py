"""Sweep parameters: key paths into a scene, distributions, sampling plans, bad input."""
import math

import numpy as np
import pytest

from spacecraft.sweep import SweepError, load_sweep
from spacecraft.sweep.parameters import (MAX_SAMPLES, apply_values, check_box, read_sweep,
                                         resolve_key)

from scenes import default_sweep_scene


def spec_of(parameters, **settings):
    return read_sweep({"parameters": parameters, **settings}, default_sweep_scene(), "test")


UNIFORM = {"distribution": "uniform", "low": 40.0, "high": 60.0}


def test_key_paths_resolve_appendages_by_name_and_array_indices():
    raw = default_sweep_scene()
    assert resolve_key("hub.inertia", raw) == ("hub", "inertia")
    assert resolve_key("appendages.rod.beam.youngs_modulus", raw) == \
        ("appendages", 0, "beam", "youngs_modulus")
    assert resolve_key("appendages.rod.position[1]", raw) == ("appendages", 0, "position", 1)
    # a key the scene leaves at its default is allowed (the scene reader judges the value)
    raw["appendages"][0]["beam"].pop("damping_ratio")
    assert resolve_key("appendages.rod.beam.damping_ratio", raw)[-1] == "damping_ratio"


@pytest.mark.parametrize("key, message", [
    ("appendages.rod.beam.youngs_modulos", "did you mean 'appendages.rod.beam.youngs_modulus'"),
    ("hub.inertai", "did you mean 'hub.inertia'"),
    ("appendages.rdo.beam.length", "no appendage named 'rdo'.*did you mean 'rod'"),
    ("appendages.rod.position[2]", "index 2 out of range"),
    ("appendages.rod.beam", "names a table, not a number"),
    ("fidelity.tolerance", "fidelity settings cannot be swept"),
    ("controler.lqr.attitude_weight", "the scene has no controler"),
])
def test_unknown_key_paths_name_the_key(key, message):
    with pytest.raises(SweepError, match=message) as info:
        spec_of({key: UNIFORM})
    assert key in str(info.value) and "\n" not in str(info.value)


@pytest.mark.parametrize("table, message", [
    ({"distribution": "uniform", "low": 2.0, "high": 1.0}, "low must be below high"),
    ({"distribution": "loguniform", "low": 0.0, "high": 1.0}, "loguniform needs 0 < low"),
    ({"distribution": "normal", "mean": 50.0, "std": -1.0}, "std must be positive"),
    ({"distribution": "normal", "mean": 50.0, "std": 1.0, "low": 60.0}, "holds a probability"),
    ({"distribution": "gauss", "mean": 50.0, "std": 1.0}, "distribution must be one of"),
    ({"distribution": "uniform", "low": 40.0}, "missing 'high'"),
    ({"distribution": "uniform", "low": 40.0, "high": math.inf}, "high must be a finite"),
    ({"distribution": "uniform", "low": 40.0, "high": 60.0, "mean": 1.0}, "unknown key 'mean'"),
    ({"distribution": "discrete", "values": []}, "non-empty array"),
    ({"distribution": "discrete", "values": [1.0, 1.0]}, "distinct"),
])
def test_invalid_distributions_are_refused(table, message):
    with pytest.raises(SweepError, match=message) as info:
        spec_of({"hub.inertia": table})
    assert "'hub.inertia'" in str(info.value)


def test_a_box_reaching_non_physical_values_names_the_key():
    # Young's modulus 2.06e11 +- 3 x 1e11: the box reaches negative stiffness
    spec = spec_of({"appendages.rod.beam.youngs_modulus":
                    {"distribution": "normal", "mean": 2.06e11, "std": 1.0e11}})
    with pytest.raises(SweepError, match=r"'appendages.rod.beam.youngs_modulus'.*reaches "
                                         r"-9.4e\+10.*must be positive"):
        check_box(spec, default_sweep_scene(), "test")
    # truncating it makes it physical
    spec = spec_of({"appendages.rod.beam.youngs_modulus":
                    {"distribution": "normal", "mean": 2.06e11, "std": 1.0e11, "low": 1e10}})
    check_box(spec, default_sweep_scene(), "test", spec.values())


def test_sample_counts_above_the_limit_are_refused_unless_raised():
    with pytest.raises(SweepError, match=f"exceed the limit of {MAX_SAMPLES}.*max_samples"):
        spec_of({"hub.inertia": UNIFORM}, samples=MAX_SAMPLES + 1)
    spec = read_sweep({"parameters": {"hub.inertia": UNIFORM}, "samples": MAX_SAMPLES + 1},
                      default_sweep_scene(), "test", max_samples=MAX_SAMPLES + 1)
    assert spec.n_samples == MAX_SAMPLES + 1
    # a grid counts its product
    with pytest.raises(SweepError, match="36 samples exceed the limit of 30"):
        spec_of({"hub.inertia": UNIFORM, "hub.mass": {**UNIFORM, "levels": 6}}, method="grid",
                levels=6, max_samples=30)


def test_controller_parameters_need_per_sample_design():
    table = {"controller.lqr.attitude_weight": {"distribution": "uniform", "low": 5.0,
                                                "high": 10.0}}
    with pytest.raises(SweepError, match="no effect with design = \"nominal\""):
        spec_of(table, design="nominal")
    assert spec_of(table, design="per-sample").parameters[0].path[0] == "controller"


def test_unknown_sweep_keys_and_missing_parameters():
    with pytest.raises(SweepError, match=r"sweep.sample: unknown key"):
        read_sweep({"sample": 3, "parameters": {"hub.inertia": UNIFORM}}, default_sweep_scene(),
                   "test")
    with pytest.raises(SweepError, match="sweep.parameters: missing"):
        read_sweep({"samples": 3}, default_sweep_scene(), "test")
    with pytest.raises(SweepError, match="sweep.method: must be one of"):
        spec_of({"hub.inertia": UNIFORM}, method="sobol")


def test_inverse_distribution_functions_against_closed_forms():
    p = spec_of({"hub.inertia": UNIFORM}).parameters[0]
    u = np.array([0.0, 0.25, 0.5])
    np.testing.assert_array_equal(p.ppf(u), [40.0, 45.0, 50.0])
    p = spec_of({"hub.inertia": {"distribution": "loguniform", "low": 1.0, "high": 100.0}}
                ).parameters[0]
    # log-uniform on [1, 100]: the median is the geometric mean 10 (rounding of exp, log: 1e-15)
    np.testing.assert_allclose(p.ppf(np.array([0.5])), [10.0], rtol=1e-14)
    p = spec_of({"hub.inertia": {"distribution": "normal", "mean": 50.0, "std": 2.0}}
                ).parameters[0]
    # Phi^-1(0.975) = 1.959963984540054 (Abramowitz & Stegun 26.2; to double precision)
    np.testing.assert_allclose(p.ppf(np.array([0.975])), [50.0 + 2.0 * 1.959963984540054],
                               rtol=1e-14)
    assert p.box() == (44.0, 56.0)
    p = spec_of({"hub.inertia": {"distribution": "discrete", "values": [40, 45, 60]}}
                ).parameters[0]
    np.testing.assert_array_equal(p.ppf(np.array([0.0, 0.34, 0.99])), [40.0, 45.0, 60.0])


def test_monte_carlo_samples_are_decided_by_their_index():
    params = {"hub.inertia": UNIFORM,
              "appendages.rod.beam.damping_ratio": {"distribution": "loguniform",
                                                    "low": 0.001, "high": 0.02}}
    short = spec_of(params, samples=10, seed=3).values()
    long = spec_of(params, samples=50, seed=3)
    # a longer sweep extends a shorter one; any subset of indices gives the same rows
    np.testing.assert_array_equal(long.values()[:10], short)
    np.testing.assert_array_equal(long.values(np.array([42, 7])), long.values()[[42, 7]])
    assert not np.array_equal(spec_of(params, samples=10, seed=4).values(), short)
    assert np.all((short[:, 0] >= 40.0) & (short[:, 0] < 60.0))


def test_latin_hypercube_puts_one_point_in_each_stratum():
    n = 16
    spec = spec_of({"hub.inertia": UNIFORM, "hub.mass": {"distribution": "uniform",
                                                         "low": 0.0 + 90.0, "high": 110.0}},
                   method="latin-hypercube", samples=n, seed=5)
    u = spec.unit_points()
    for k in range(2):
        assert sorted(np.floor(u[:, k] * n).astype(int)) == list(range(n))
    np.testing.assert_array_equal(spec.values(np.array([3])), spec.values()[[3]])


def test_grid_is_the_cartesian_product_last_parameter_fastest():
    spec = spec_of({"hub.inertia": {**UNIFORM, "levels": 3},
                    "appendages.rod.beam.damping_ratio": {"distribution": "discrete",
                                                          "values": [0.001, 0.01]}},
                   method="grid")
    assert spec.n_samples == 6
    np.testing.assert_array_equal(spec.values(), [[40, 0.001], [40, 0.01], [50, 0.001],
                                                  [50, 0.01], [60, 0.001], [60, 0.01]])


def test_values_go_into_a_copy_of_the_scene_in_file_units():
    raw = default_sweep_scene()
    spec = spec_of({"hub.inertia": UNIFORM, "appendages.rod.direction":
                    {"distribution": "uniform", "low": -5.0, "high": 5.0}})
    out = apply_values(raw, spec.parameters, [45.0, 2.5])
    assert out["hub"]["inertia"] == 45.0 and out["appendages"][0]["direction"] == 2.5
    assert raw["hub"]["inertia"] == 50.0        # the original is untouched


def test_values_shared_copy_sets_the_same_values_and_leaves_the_scene_untouched():
    import copy

    raw = default_sweep_scene()
    before = copy.deepcopy(raw)
    spec = spec_of({"hub.inertia": UNIFORM, "appendages.rod.direction":
                    {"distribution": "uniform", "low": -5.0, "high": 5.0},
                    "appendages.rod.beam.length": {"distribution": "uniform", "low": 9.0,
                                                   "high": 11.0}})
    values = [45.0, 2.5, 10.5]
    out = apply_values(raw, spec.parameters, values, shared=True)
    assert out == apply_values(raw, spec.parameters, values)
    assert raw == before                         # nothing of the scene changed
    # the tables on the paths are new, the others the scene's own
    assert out["appendages"] is not raw["appendages"]
    assert out["appendages"][0]["beam"] is not raw["appendages"][0]["beam"]
    assert out["manoeuvre"] is raw["manoeuvre"]


def test_load_sweep_overrides_the_scene_table():
    raw, spec, source = load_sweep(None, samples=7, seed=9, parameters={"hub.inertia": UNIFORM})
    assert spec.n_samples == 7 and spec.seed == 9 and spec.keys == ["hub.inertia"]
    assert "sweep" not in raw and "default" in source
    with pytest.raises(SweepError, match="nothing to sweep"):
        load_sweep(default_sweep_scene())
