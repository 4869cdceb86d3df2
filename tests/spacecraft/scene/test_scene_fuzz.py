"""Fuzz of the scene reader: whatever a scene holds, load_scene returns a Scene or raises a
SceneError of one line that names the source and a key; never another exception.

The examples are derandomised (the same every run, as CI needs). An opt-in longer run:
``FLEXSAT_FUZZ_EXAMPLES=20000 python -m pytest tests/spacecraft/scene/test_scene_fuzz.py`` (each strategy then
draws that many examples; derandomised too, so a longer run explores further along the same
sequence).

Two strategies: (1) mutations of a valid scene dict at the documented keys (the table of
spacecraft/scene/read.py), with wild values (NaN, inf, huge and tiny floats, integers beyond the
float range, unicode and control characters, long strings, booleans, nested arrays and
tables, None), deleted keys, unknown keys and extra appendages; (2) TOML text: the small test
scene with lines replaced or inserted, read from a file (tomllib's errors included).
"""
import copy
import math
import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from spacecraft.scene.read import Scene, load_scene

from scene_fuzz import DELETE, check, mutate
from scenes import BASE, BASE_TOML

EXAMPLES = int(os.environ.get("FLEXSAT_FUZZ_EXAMPLES", "150"))
FUZZ = settings(max_examples=EXAMPLES, derandomize=True, deadline=None,
                suppress_health_check=list(HealthCheck), database=None)

# documented key paths (spacecraft/scene/read.py), as paths into the dict; 0 is the first appendage
A = ("appendages", 0)
KEYS = [
    ("title",), ("hub",), ("hub", "mass"), ("hub", "inertia"), ("appendages",), A,
    A + ("name",), A + ("position",), A + ("direction",), A + ("truth",), A + ("design",),
    A + ("beam",), A + ("beam", "section"), A + ("beam", "length"), A + ("beam", "diameter"),
    A + ("beam", "outer_diameter"), A + ("beam", "wall_thickness"), A + ("beam", "width"),
    A + ("beam", "thickness"), A + ("beam", "density"), A + ("beam", "youngs_modulus"),
    A + ("beam", "bending_stiffness"), A + ("beam", "linear_density"),
    A + ("beam", "damping_ratio"), A + ("truth_chain",), A + ("fit",), A + ("fit", "n_bodies"),
    A + ("fit", "match"), A + ("chain",), A + ("chain", "lengths"), A + ("chain", "masses"),
    A + ("chain", "inertias"), A + ("chain", "hinge_stiffnesses"),
    A + ("chain", "hinge_dampings"), A + ("chain", "com_offsets"), A + ("chain", "root"),
    A + ("chain", "from_beam"), A + ("chain", "n_bodies"), A + ("chain", "root_stiffness"),
    A + ("chain", "root_damping"), ("fidelity",), ("fidelity", "n_modes"),
    ("fidelity", "tolerance"), ("fidelity", "method"), ("fidelity", "bandwidth_factor"),
    ("fidelity", "prune"), ("controller",), ("controller", "types"),
    ("controller", "sample_rate"), ("controller", "pd"), ("controller", "pd", "natural_frequency"),
    ("controller", "pd", "bandwidth"), ("controller", "pd", "damping"),
    ("controller", "pd", "roll_off"), ("controller", "pd", "notch"), ("controller", "lqr"),
    ("controller", "lqr", "attitude_weight"), ("controller", "lqr", "rate_weight"),
    ("controller", "lqr", "torque_weight"), ("controller", "lqr", "deflection_weight"),
    ("controller", "lqr", "estimator_speed"), ("manoeuvre",), ("manoeuvre", "slew_angle"),
    ("manoeuvre", "slew_time"), ("manoeuvre", "duration"), ("manoeuvre", "step"),
    ("manoeuvre", "disturbance"), ("manoeuvre", "disturbance", "input"),
    ("manoeuvre", "disturbance", "amplitude"), ("manoeuvre", "disturbance", "start"),
    ("manoeuvre", "disturbance", "length"), ("outputs", "tip_deflection"),
    ("outputs", "root_loads"), ("outputs", "exact_reference"), ("export", "fmu"),
    ("export", "systems"), ("export", "reference_files"), ("export", "step"),
    ("report", "plots"), ("report", "equivalence"), ("limits",), ("limits", "modes"),
    ("limits", "samples"), ("limits", "memory"), ("limits", "states"),
]

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-300, -1e-300, 1e300, 5e-324, 1e-9, 1e9, 0.5, 3.0, 600.0]),
    st.integers(min_value=-10**5, max_value=10**5),
    st.sampled_from([10**400, -10**400, 2**63, 0, 1, 2, 3, 1000, 5000, 100000]),
)
texts = st.one_of(
    st.text(max_size=20),
    st.sampled_from(["rod", "tube", "beam", "chain", "fit", "truth", "pd", "lqr", "rfem",
                     "frequencies", "poles-and-zeros", "first_mode", "bööm", "a\nb", "\x00",
                     "slew", "plant", "hinged", "rigid", "force_x", "rod_tip_force", "x" * 5000,
                     "\u202e", "\ud800"]),
)
leaves = st.one_of(numbers, texts, st.booleans(), st.none())
values = st.one_of(
    leaves,
    st.lists(leaves, max_size=6),
    st.dictionaries(st.one_of(texts, st.integers()), leaves, max_size=3),
    st.recursive(leaves, lambda inner: st.one_of(st.lists(inner, max_size=3),
                                                 st.dictionaries(texts, inner, max_size=2)),
                 max_leaves=12),
)
unknown_keys = st.tuples(st.sampled_from([(), ("hub",), A, A + ("beam",), ("controller",),
                                          ("controller", "pd"), ("manoeuvre",)]),
                         st.one_of(texts, st.sampled_from(["colour", "diamter", "n_mode"])))
mutation = st.one_of(
    st.tuples(st.sampled_from(KEYS), st.one_of(values, st.just(DELETE))),
    unknown_keys.map(lambda t: (t[0] + (t[1],), 1.0)),
)


@pytest.mark.slow
@FUZZ
@given(st.lists(mutation, min_size=1, max_size=4), st.integers(min_value=1, max_value=70))
def test_mutated_scene_dicts_give_a_scene_or_one_line_naming_a_key(mutations, n_appendages):
    data = copy.deepcopy(BASE)
    if n_appendages > 1 and n_appendages % 7 == 0:   # now and then many appendages
        data["appendages"] = [dict(copy.deepcopy(data["appendages"][0]), name=f"a{k}")
                              for k in range(n_appendages)]
    unknown = set()
    for path, value in mutations:
        mutate(data, path, value)
        if len(path) == 1:
            unknown.add(str(path[0])[:100])
    check(lambda: load_scene(data), "<dict>", unknown)


LINES = BASE_TOML.splitlines()
toml_fragments = st.one_of(
    st.text(max_size=40),
    st.sampled_from(["mass = nan", "mass = inf", "inertia = -1", "[hub]", "[[appendages]]",
                     "x = [[[[[[1]]]]]]", "a = " + "[" * 600 + "]" * 600, "title = 1979-05-27",
                     "n_modes = 99999999999999999999999", 'name = "bööm"', "[limits]",
                     "modes = 1e400", "step = 1e-300", "duration = 1e300", "= 1", "[[x]]",
                     'title = """\nmulti\n"""', "diameter = 0x10", "diameter = 1_000",
                     "[appendages.beam]", "section = 3", "types = []", "samples = 1.5"]),
)


@FUZZ
@given(st.lists(st.tuples(st.integers(min_value=0, max_value=len(LINES)), toml_fragments,
                          st.booleans()), min_size=1, max_size=3))
def test_mutated_toml_files_give_a_scene_or_one_line(tmp_path_factory, edits):
    lines = list(LINES)
    for index, fragment, replace in edits:
        if replace and index < len(lines):
            lines[index] = fragment
        else:
            lines.insert(index, fragment)
    path = tmp_path_factory.mktemp("fuzz") / "scene.toml"
    path.write_text("\n".join(lines), encoding="utf-8", errors="surrogatepass")
    keys = {line.split("=")[0].strip().strip("[]").split(".")[0] for line in lines}
    check(lambda: load_scene(path), str(path), keys)


def test_the_fuzz_base_scene_is_valid():
    # the mutations start from scenes that load: each failure is the mutation's
    assert isinstance(load_scene(copy.deepcopy(BASE)), Scene)


@pytest.mark.parametrize("value", [math.nan, 10**400, "x" * 10_000, [[[[1.0]]]], {"a": 1},
                                   None, b"bytes", object(), 1 + 2j])
def test_wild_values_at_every_documented_key(value):
    """Every documented key with each wild value: a Scene or a one-line SceneError."""
    for path in KEYS:
        data = copy.deepcopy(BASE)
        mutate(data, path, value)
        check(lambda: load_scene(data), "<dict>", set())
