"""Bounded scenes: the work a scene asks for is estimated when it is read and refused, by key
and limit, beyond the documented limits; values outside their documented ranges, non-ASCII
names, deep nesting and oversized files are refused with one line naming the key."""
import dataclasses
import math
import re

import pytest

import spacecraft.scene.read
from spacecraft.scene.limits import Limits, estimate_cost
from spacecraft.design.loop import run
from spacecraft.scene.read import RANGES, SceneError, load_scene, read_limits

from scenes import scene_with


def refused(data, match, **kwargs):
    with pytest.raises(SceneError, match=match) as info:
        load_scene(data, **kwargs)
    message = str(info.value)
    assert "\n" not in message and len(message) < 600
    return message


# ---------------------------------------------------------------------------------------------
# work limits
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("changes, key, limit", [
    # the findings: each ran for minutes or tried to allocate 75 GiB to 7 TiB
    ({"fidelity.n_modes": 5000}, r"fidelity\.n_modes", "modes"),
    ({"fidelity.n_modes": 1000}, r"fidelity\.n_modes", "modes"),
    ({"appendages.0.fit.n_bodies": 1000}, r"appendages\[0\]\.fit\.n_bodies", "fit_bodies"),
    ({"appendages.0.design": "chain", "appendages.0.fit": None,
      "appendages.0.chain": {"from_beam": "rfem", "n_bodies": 100000}},
     r"appendages\[0\]\.chain\.n_bodies", "bodies"),
    ({"manoeuvre.duration": 1e9, "manoeuvre.step": 0.1}, r"manoeuvre\.step", "samples"),
    # a digital loop: 1e6 samples count 2e7
    ({"manoeuvre.duration": 1e5, "manoeuvre.step": 0.1, "controller.sample_rate": 10.0},
     r"manoeuvre\.step: 1e\+06 samples per simulation of a digital loop.*", "samples"),
    ({"title": "x" * 100_000}, r"title", "string_length"),
])
def test_work_beyond_a_limit_is_refused_by_key_and_limit(changes, key, limit):
    message = refused(scene_with(**changes), rf"<dict>: {key}: .*over the limit")
    assert f"limits.{limit}" in message and f"--limit {limit}=N" in message


def test_the_estimated_loop_size_is_refused_by_the_key_that_drives_it():
    # 12 bodies per fit (within fit_bodies) but an LQR on a 550-mode truth design model: the
    # loop (plant + estimator) would have ~2200 states
    data = scene_with(**{"fidelity.n_modes": 500, "appendages.0.design": "truth",
                         "appendages.0.fit": None, "controller.types": ["lqr"],
                         "controller.pd": None,
                         "controller.lqr": {"attitude_weight": 7.6, "torque_weight": 1.0}})
    refused(data, r"fidelity\.n_modes: the largest closed loop would have up to \d+ states: "
                  r"over the limit 1200 \(limits\.states")


def test_memory_estimate_refuses_many_long_simulations():
    # 5e6 samples x 2 simulations x (time, input, 4 outputs) = 480 MB kept: under 2 GiB; with
    # both controllers and both fits (8 simulations) and a lower limit it is refused
    data = scene_with(**{"manoeuvre.duration": 5e5, "manoeuvre.step": 0.1})
    assert estimate_cost(load_scene(data)).memory < 2 * 1024**3
    refused(data, r"manoeuvre\.step: the time responses would take up to .* GiB .*limits\.memory",
            limits={"memory": 1e8})


def test_a_limit_is_raised_by_the_scene_or_the_command_line():
    data = scene_with(**{"fidelity.n_modes": 520})
    refused(data, r"fidelity\.n_modes: 520: over the limit 500")
    assert load_scene(dict(data, limits={"modes": 520})).fidelity.n_modes == 520
    assert load_scene(data, limits={"modes": 520}).limits.modes == 520
    # the command line (load_scene's limits) wins over the scene's table
    refused(dict(data, limits={"modes": 520}), r"over the limit 510", limits={"modes": 510})
    # TOML writes large numbers as floats: a whole float is accepted
    assert load_scene(dict(data, limits={"modes": 520.0})).limits.modes == 520


@pytest.mark.parametrize("limits, match", [
    ({"modez": 3}, r"limits\.modez: unknown key; expected one of .*modes"),
    ({"modes": 0}, r"limits\.modes: must be a finite number >= 1"),
    ({"modes": 2.5}, r"limits\.modes: must be a whole number"),
    ({"memory": "lots"}, r"limits\.memory: must be a positive number \[bytes\]; got string"),
    ({"samples": math.inf}, r"limits\.samples: must be a finite number"),
])
def test_bad_limits_are_refused(limits, match):
    refused(dict(scene_with(), limits=limits), match)
    with pytest.raises(SceneError, match=match):
        read_limits(limits)


def test_the_docstring_table_states_the_default_limits():
    doc = spacecraft.scene.read.__doc__
    table = doc[doc.index("Limits (work a scene may ask for"):]
    units = {"GiB": 1024**3, "MiB": 1024**2}
    for field in dataclasses.fields(Limits):
        row = re.search(rf"^{field.name}\s+(\S+)(?: (GiB|MiB))?\s", table, re.M)
        assert row, f"{field.name} is missing from the Limits table"
        value = float(row.group(1)) * units.get(row.group(2), 1)
        assert value == getattr(Limits(), field.name), field.name


def test_estimated_sizes_bound_the_sizes_a_run_builds():
    """The estimate is an upper bound: states of every closed loop and bytes of every response
    (a bound that is not one would let a scene past its limits)."""
    data = scene_with(**{"controller.types": ["pd", "lqr"],
                         "controller.lqr": {"attitude_weight": 7.6, "torque_weight": 1.0},
                         "controller.pd.roll_off": 50.0, "outputs.tip_deflection": True,
                         "appendages.0.fit.match": ["poles-and-zeros", "frequencies"],
                         "manoeuvre.disturbance": {"input": "rod_tip_force", "amplitude": 1.0},
                         "report.equivalence": False})
    scene = load_scene(data)
    cost = estimate_cost(scene)
    result = run(scene)
    assert len(result.responses) == cost.simulations
    assert max(loop.nstates for loop in result.loops.values()) <= cost.loop_states
    kept = sum(r.t.nbytes + r.y.nbytes + r.u.nbytes for r in result.responses.values())
    assert kept <= cost.memory
    assert all(r.t.size == cost.samples for r in result.responses.values())


def test_the_tolerance_search_stops_within_the_limits():
    # limits.states = 20: a one-beam scene with a PD (2 states at most) has 2 (3 + n) + 2
    # states, so at most 6 modes fit; 1e-9 needs more, and the search says it stopped at 6
    data = scene_with(**{"fidelity.n_modes": None, "fidelity.tolerance": 1e-9})
    with pytest.raises(SceneError, match=r"fidelity\.tolerance: no truncation with up to 6 modes"):
        run(load_scene(data, limits={"states": 20}))


# ---------------------------------------------------------------------------------------------
# ranges
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("changes, match", [
    # the extreme values (LinAlgError, OverflowError, ZeroDivisionError before)
    ({"appendages.0.beam.length": 1e-9},
     r"appendages\[0\]\.beam\.length: must lie between 0\.01 and 1000 \[m\]; got 1e-09"),
    ({"controller.pd.natural_frequency": 1e9},
     r"controller\.pd\.natural_frequency: must lie between 1e-05 and 1000 \[rad/s\]"),
    ({"hub.inertia": 1e300}, r"hub\.inertia: must lie between 1e-06 and 1e\+10 \[kg\*m\^2\]"),
    ({"hub.mass": 1e-300}, r"hub\.mass: must lie between"),
    ({"appendages.0.beam.youngs_modulus": 1e300}, r"youngs_modulus: must lie between"),
    ({"appendages.0.beam.diameter": 1e300}, r"diameter: must lie between"),
    ({"appendages.0.beam.diameter": 5.0, "appendages.0.beam.length": 1.0},
     r"diameter: must not exceed the beam's length 1 \[m\]"),
    ({"appendages.0.position": [1e12, 0.0]},
     r"position\[0\]: must be at most 1000 in magnitude \[m\]"),
    ({"fidelity.bandwidth_factor": 1e9}, r"fidelity\.bandwidth_factor: must lie between"),
    ({"controller.pd.damping": 1e300}, r"controller\.pd\.damping: must lie between"),
    ({"manoeuvre.slew_angle": 1e5}, r"manoeuvre\.slew_angle: must lie between 1e-06 and 360 "
                                     r"in magnitude \[deg\]"),
    ({"manoeuvre.disturbance": {"input": "force_x", "amplitude": 1.0, "start": 500.0}},
     r"manoeuvre\.disturbance\.start: must fall inside the simulated time"),
    # a TOML integer beyond the float range
    ({"hub.mass": 10**400}, r"hub\.mass: must be finite \[kg\]; got 1000000.*characters\)"),
    # a derived quantity: the beam's first bending frequency
    ({"appendages.0.beam.youngs_modulus": 1e5, "appendages.0.beam.density": 1e5,
      "appendages.0.beam.length": 1000.0, "appendages.0.beam.diameter": 1e-5},
     r"appendages\[0\]\.beam: first bending frequency .* rad/s .* outside \[0\.0001, 100000\]"),
])
def test_values_outside_their_range_name_key_unit_and_value(changes, match):
    refused(scene_with(**changes), match)


def test_lqr_weights_outside_the_range_of_a_rigid_body_frequency():
    data = scene_with(**{"controller.types": ["lqr"], "controller.pd": None,
                         "controller.lqr": {"attitude_weight": 1e12, "torque_weight": 1e-12}})
    with pytest.raises(SceneError, match=r"controller\.lqr: the weights give a rigid-body "
                                         r"closed-loop frequency .* outside \[1e-05, 1000\]"):
        run(data)


def test_every_range_has_a_unit_and_an_order():
    for key, rng in RANGES.items():
        assert rng.unit and 0 <= rng.lo < rng.hi, key
        assert rng.sign in ("positive", "non-negative", "signed", "non-zero"), key


# ---------------------------------------------------------------------------------------------
# names, strings, files
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["bööm", "boom\n", "1boom", "a" * 65, "", "x-y"])
def test_appendage_names_are_ascii_identifiers(name):
    # "bööm" passed str.isidentifier() and was refused only at FMU export
    refused(scene_with(**{"appendages.0.name": name}),
            r"appendages\[0\]\.name: must be an ASCII identifier of at most 64 characters")


def test_a_64_character_name_is_accepted():
    assert load_scene(scene_with(**{"appendages.0.name": "a" * 64})).appendages[0].name == "a" * 64


@pytest.mark.parametrize("title", ["two\nlines", "tab\there", "bell\x07", "sep\u2028"])
def test_titles_are_one_line(title):
    refused(scene_with(title=title), r"title: must be one line of text without control")


def test_long_values_are_shortened_in_messages():
    message = refused(scene_with(**{"appendages.0.beam.section": "h" * 200_000}),
                      r"section: must be one of .*got 'hhh.*\.\.\. \(200002 characters\)")
    assert len(message) < 400
    message = refused(scene_with(**{"hub.mass": [1.0] * 200_000}), r"hub\.mass: must be a number")
    assert len(message) < 200


def test_unknown_keys_of_any_type_are_named_short():
    data = scene_with()
    data["hub"][("x" * 500)] = 1.0
    message = refused(data, r"hub\.'xxx.*\(502 characters\): unknown key")
    data = scene_with()
    data["hub"][3] = 1.0   # a non-string key (from Python) sorts with the others
    refused(data, r"hub\.3: unknown key")


def test_deeply_nested_toml_is_a_scene_error(tmp_path):
    path = tmp_path / "deep.toml"
    path.write_text("title = " + "[" * 500 + "]" * 500 + "\n")
    with pytest.raises(SceneError, match=r"deep\.toml: tables or arrays nested too deeply"):
        load_scene(path)


def test_scene_files_larger_than_the_limit_are_refused_before_parsing(tmp_path):
    path = tmp_path / "big.toml"
    path.write_text(f'title = "{"x" * (2 * 1024**2)}"\n')
    with pytest.raises(SceneError, match=r"big\.toml: the scene file is larger than the limit "
                                         r"1048576 bytes \(limits\.file_size\)"):
        load_scene(path)
    # raised, the file is read and its title refused by the next limit
    with pytest.raises(SceneError, match=r"title: a text of 2097152 characters: over the limit"):
        load_scene(path, limits={"file_size": 4 * 1024**2})


def test_a_folder_is_not_a_scene_file(tmp_path):
    with pytest.raises(SceneError, match="is a folder, not a scene file"):
        load_scene(tmp_path)


def test_the_limits_docs_state_the_cap_of_the_tolerance_search():
    """Issue-9 review: the tables said limits.modes is "also the cap of the search from
    fidelity.tolerance", but the search stops at fidelity.MAX_MODES = 40 whatever the limit.
    Both tables now state that number."""
    from spacecraft.scene import limits as limits_module
    from spacecraft.design.fidelity import MAX_MODES

    for doc in (spacecraft.scene.read.__doc__, limits_module.__doc__):
        table = " ".join(doc[doc.index("\nmodes "):].split("\nbodies ")[0].split())
        assert f"tries at most {MAX_MODES}" in table, table


def test_fit_bodies_is_appendages_limit_and_raising_it_raises_appendages():
    """Before: the scene allowed 12 bodies and appendages 14, and a scene or --limit that
    raised fit_bodies past 14 still met appendages' LimitError."""
    from appendages import limits as library
    from spacecraft.scene.limits import Limits, library_limits

    assert Limits().fit_bodies == library.DEFAULTS["fit_bodies"]
    with library_limits(Limits(fit_bodies=20, modes=10)):
        assert library.current("fit_bodies") == 20
        # never lowered: the scene's own check came first
        assert library.current("modes") == library.DEFAULTS["modes"]
    assert library.current("fit_bodies") == library.DEFAULTS["fit_bodies"]


@pytest.mark.parametrize("value, error, match", [
    (None, TypeError, r"limit {name} must be a number >= 1 \[{unit}\]; got NoneType None"),
    ("x", TypeError, r"limit {name} must be a number >= 1 \[{unit}\]; got str 'x'"),
    (True, TypeError, r"limit {name} must be a number >= 1 \[{unit}\]; got bool True"),
    (math.nan, ValueError, r"limit {name} must be a finite number >= 1 \[{unit}\]; got nan"),
    (math.inf, ValueError, r"limit {name} must be a finite number >= 1 \[{unit}\]; got inf"),
    (0, ValueError, r"limit {name} must be a finite number >= 1 \[{unit}\]; got 0"),
    (-5, ValueError, r"limit {name} must be a finite number >= 1 \[{unit}\]; got -5"),
    (10**400, ValueError, r"limit {name} must be a finite number >= 1"),
])
@pytest.mark.parametrize("name", [f.name for f in dataclasses.fields(Limits)])
def test_limits_refuse_what_is_not_a_limit_by_name(name, value, error, match):
    """Limits accepted None, "x" and NaN for every field (and compared them later)."""
    from spacecraft.scene.limits import LIMIT_UNITS

    unit = re.escape(LIMIT_UNITS[name][0])
    with pytest.raises(error, match=match.format(name=name, unit=unit)):
        Limits(**{name: value})
    with pytest.raises(error, match=match.format(name=name, unit=unit)):
        Limits().replace(**{name: value})


def test_limits_are_whole_numbers_except_memory_and_basilisk_seconds():
    from spacecraft.scene.limits import REAL_LIMITS

    for f in dataclasses.fields(Limits):
        if f.name in REAL_LIMITS:
            assert Limits(**{f.name: 2.5}).__getattribute__(f.name) == 2.5
        else:
            with pytest.raises(ValueError, match=rf"limit {f.name} must be a whole number"):
                Limits(**{f.name: 2.5})
            assert type(getattr(Limits(**{f.name: 7.0}), f.name)) is int


@pytest.mark.parametrize("tip, root_loads, floor", [(True, False, 3), (False, True, 4),
                                                    (False, False, 0)])
def test_the_estimate_counts_the_modes_a_three_axis_truncation_keeps_per_motion(tip, root_loads,
                                                                               floor):
    """A three-axis truth chosen from the tolerance keeps the lowest mode of every motion a
    reported output sees (both bending planes and torsion; axial with root loads) beyond n:
    the estimate counts them (the hub's three rotations the rigid states). A rectangular wing (no twin
    modes) designed on its truth: the smallest truth plant the search builds (n = 1) has
    exactly the estimated states."""
    from spacecraft.design.loop import DesignLoop

    wing = {"section": "rectangular", "length": 6.0, "width": 2.0, "thickness": 0.04,
            "density": 40.0, "youngs_modulus": 7e8, "poisson_ratio": 0.3}
    raw = {"hub": {"mass": 800.0, "inertia": [[900.0, 0.0, 0.0], [0.0, 700.0, 0.0],
                                              [0.0, 0.0, 600.0]]},
           "appendages": [{"name": "wing", "position": [0.0, 1.0, 0.0],
                           "orientation": [90.0, 0.0, 0.0], "beam": wing, "design": "truth"}],
           "controller": {"types": ["pd"], "pd": {"natural_frequency": 0.1}},
           "outputs": {"tip_deflection": tip, "root_loads": root_loads}}
    scene = load_scene(raw, source="wing")
    cost = estimate_cost(scene)
    assert cost.plant_states == 2 * (3 + 1 + floor)
    loop = DesignLoop(scene)
    counts = loop.truth_model(scene.appendages[0], 1).modes_per_motion
    assert sum(counts.values()) == 1 + floor
    plant = loop.truth_spacecraft(1).plant(tip_deflection=tip, root_loads=root_loads)
    assert plant.nstates == cost.plant_states
    # a given n_modes is the lowest n of all motions: no floor
    given = load_scene({**raw, "fidelity": {"n_modes": 5}}, source="wing")
    assert estimate_cost(given).plant_states == 2 * (3 + 5)
