"""Every physical parameter over many decades (issue 9): the result is either finite and
correct-looking, or a ValueError/TypeError that names the parameter; never LinAlgError,
ZeroDivisionError, OverflowError, RecursionError, NaN, inf or a numpy/scipy RuntimeWarning.

Each parameter of the public constructors (Beam and its sections, Hub, Mount, the chains) is
swept alone, the others at the paper's values, over (a) a fixed list of edge values: both ends
of double precision, the documented range's bounds and just beyond them (RANGES), zero,
negative, NaN, inf and wrong types; and (b) derandomised hypothesis draws of m * 10**e with e
from -320 to 308. A value that is accepted must then go through the whole pipeline of that
object: W(s) symmetric, finite and real (W(conj s) = conj W(s)); positive increasing natural
frequencies; truncations, chains and the coupled spacecraft with finite plant matrices.
Warnings are turned into errors, so a RuntimeWarning that leaks fails the test.
"""

import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from appendages import Beam, HingedChain
from appendages.interface import RANGES
from spacecraft import Hub, Mount, Spacecraft

SWEEP = settings(derandomize=True, database=None, max_examples=25, deadline=None,
                 suppress_health_check=[HealthCheck.too_slow])

ROD = dict(length=10.0, diameter=0.01, density=7800.0, youngs_modulus=2.06e11)
ROD_BEAM = Beam.circular_rod(**ROD)
PLAIN = dict(length=10.0, bending_stiffness=ROD_BEAM.bending_stiffness,
             linear_density=ROD_BEAM.linear_density)
TUBE = dict(length=3.0, outer_diameter=0.05, wall_thickness=0.002, density=2700.0,
            youngs_modulus=7.0e10)
STRIP = dict(length=2.0, width=0.1, thickness=0.001, density=2700.0, youngs_modulus=7.0e10)
CHAIN = dict(length=10.0, mass=6.1, k_L=0.27, stiffness=37.0)

# magnitudes: m * 10**e over the whole double range (and its subnormal end)
magnitudes = st.builds(lambda m, e: m * 10.0**e, st.floats(1.0, 9.99),
                       st.integers(-320, 308)).filter(math.isfinite)
EDGES = [0.0, -1.0, -1e300, 5e-324, 1e-300, 1e300, 1.7e308, math.nan, math.inf, -math.inf]
WRONG_TYPES = [None, "1", 1j, True, [1.0]]


def range_edges(quantity):
    low, high, _ = RANGES[quantity]
    out = [high, high * (1 + 1e-9)]
    if low > 0:
        out += [low, low * (1 - 1e-9)]
    return out


def run_clean(action):
    """Run ``action`` with every warning an error (but the deliberate unit-slip warning of an
    angle beyond a turn, appendages.unit_slips.UnitWarning); return its result."""
    from appendages.unit_slips import UnitWarning

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warnings.simplefilter("ignore", UnitWarning)
        return action()


def accepted_or_named(build, name, value):
    """Build with ``value``: the object, or None after a ValueError/TypeError naming ``name``."""
    try:
        return run_clean(lambda: build(value))
    except (ValueError, TypeError) as exc:
        assert not isinstance(exc, np.linalg.LinAlgError), f"{name}={value!r}: {exc!r}"
        assert name in str(exc), f"{name}={value!r}: message does not name it: {exc}"
        assert len(str(exc)) < 600, "message too long"
        return None


def check_W(model, scale):
    """W at s spread around the model's frequency scale: finite, symmetric, real system."""
    s = scale * np.array([0.01 + 0.1j, 0.3 + 3.0j, 5.0 + 1e3j, -2.0 + 40.0j])
    W = model.W(s)
    assert W.shape == (4, 2, 2) and np.all(np.isfinite(W))
    assert np.array_equal(W[:, 0, 1], W[:, 1, 0])
    np.testing.assert_allclose(model.W(np.conj(s)), np.conj(W), rtol=1e-12,
                               atol=1e-12 * np.abs(W).max())


def check_frequencies(w, n=None):
    w = np.asarray(w)
    assert np.all(np.isfinite(w)) and np.all(w > 0) and np.all(np.diff(w) >= 0)
    if n is not None:
        assert w.size == n


def check_plant(plant):
    for matrix in (plant.A, plant.B, plant.C, plant.D):
        assert np.all(np.isfinite(np.asarray(matrix)))


def exercise_beam(beam):
    """The whole pipeline of one beam; must succeed when the beam was accepted."""
    def run():
        c = beam.frequency_scale
        check_W(beam, c)
        check_frequencies(beam.natural_frequencies(3), 3)
        check_frequencies(beam.cantilever_frequencies(3), 3)
        for method in ("craig-bampton", "residual", "free-free"):
            model = beam.truncated(4, method=method)
            check_W(model, c)
            check_frequencies(model.poles())
            check_frequencies(model.zeros(2))
            check_plant(model.state_space(tip=True))
        # a hub like the beam (mass and inertia ratio 1), within the hub's own range
        hub = Hub(float(np.clip(beam.mass, *RANGES["mass"][:2])),
                  float(np.clip(beam.inertia, *RANGES["inertia"][:2])))
        exact = Spacecraft(hub, [Mount(beam, (0.05 * beam.length, 0.0), 0.3)])
        check_frequencies(exact.natural_frequencies(2), 2)
        finite = Spacecraft(hub, [Mount(beam.truncated(6), (0.05 * beam.length, 0.0), 0.3)])
        check_frequencies(finite.natural_frequencies(2), 2)
        check_plant(finite.plant(tip_deflection=True, root_loads=True))
    run_clean(run)


def exercise_chain(chain):
    def run():
        check_frequencies(chain.poles())
        scale = chain.poles()[0]
        check_W(chain, scale)
        for r in (1, 2, 4):
            check_frequencies(chain.zeros(r))
        check_plant(chain.state_space(tip=True))
        hub = Hub(float(np.clip(chain.mass, *RANGES["mass"][:2])),
                  float(np.clip(chain.inertia, *RANGES["inertia"][:2])))
        craft = Spacecraft(hub, [Mount(chain, (0.05 * chain.length, 0.0), 0.3)])
        check_frequencies(craft.natural_frequencies(2), 2)
        check_frequencies(craft.natural_frequencies(2, exact=True), 2)
        check_plant(craft.plant(tip_deflection=True))
    run_clean(run)


def exercise_spacecraft(craft, truncated):
    def run():
        check_frequencies(craft.natural_frequencies(3), 3)
        check_frequencies(truncated.natural_frequencies(3), 3)
        check_plant(truncated.plant(tip_deflection=True, root_loads=True, disturbances=True))
        response = craft.frequency_response([0.01, 1.5]).frdata
        assert np.all(np.isfinite(response))
    run_clean(run)


# -- the parameters ----------------------------------------------------------------------------
BEAM_PARAMETERS = {
    # name: (build from value, range key for the edges or None)
    "length": (lambda v: Beam(**{**PLAIN, "length": v}), "length"),
    "bending_stiffness": (lambda v: Beam(**{**PLAIN, "bending_stiffness": v}),
                          "bending_stiffness"),
    "linear_density": (lambda v: Beam(**{**PLAIN, "linear_density": v}), "linear_density"),
    "damping_ratio": (lambda v: Beam(**PLAIN, damping_ratio=v), None),
    "diameter": (lambda v: Beam.circular_rod(**{**ROD, "diameter": v}), "length"),
    "density": (lambda v: Beam.circular_rod(**{**ROD, "density": v}), "density"),
    "youngs_modulus": (lambda v: Beam.circular_rod(**{**ROD, "youngs_modulus": v}),
                       "youngs_modulus"),
    "outer_diameter": (lambda v: Beam.tube(**{**TUBE, "outer_diameter": v}), "length"),
    "wall_thickness": (lambda v: Beam.tube(**{**TUBE, "wall_thickness": v}), "length"),
    "width": (lambda v: Beam.rectangular(**{**STRIP, "width": v}), "length"),
    "thickness": (lambda v: Beam.rectangular(**{**STRIP, "thickness": v}), "length"),
}

CHAIN_PARAMETERS = {
    "length": (lambda v: HingedChain.three_body(**{**CHAIN, "length": v}), "length"),
    "mass": (lambda v: HingedChain.three_body(**{**CHAIN, "mass": v}), "mass"),
    "stiffness": (lambda v: HingedChain.three_body(**{**CHAIN, "stiffness": v}),
                  "hinge_stiffness"),
    "hinge_dampings": (lambda v: HingedChain(
        [3.0, 4.0, 3.0], [1.8, 2.4, 1.8], [1.35, 3.2, 1.35], [37.0, 37.0],
        hinge_dampings=[v, v]), "hinge_damping"),
    "hinge_stiffnesses": (lambda v: HingedChain(
        [3.0, 4.0, 3.0], [1.8, 2.4, 1.8], [1.35, 3.2, 1.35], [v, v], root="rigid"),
        "hinge_stiffness"),
}

HUB_PARAMETERS = {
    "hub mass": (lambda v: Hub(v, 50.0), "mass"),
    "hub inertia": (lambda v: Hub(100.0, v), "inertia"),
}

MOUNT_PARAMETERS = {
    "position": lambda v: Mount(ROD_BEAM, (v, 0.5), 0.0),
    "direction": lambda v: Mount(ROD_BEAM, (0.5, 0.0), v),
}


def sweep_values(quantity):
    values = EDGES + WRONG_TYPES
    if quantity is not None:
        values = values + range_edges(quantity)
    return values


def check_beam_value(name, value):
    build, _ = BEAM_PARAMETERS[name]
    beam = accepted_or_named(build, name, value)
    if beam is not None:
        exercise_beam(beam)


def check_chain_value(name, value):
    build, _ = CHAIN_PARAMETERS[name]
    chain = accepted_or_named(build, name, value)
    if chain is not None:
        exercise_chain(chain)


def check_hub_value(name, value):
    build, _ = HUB_PARAMETERS[name]
    hub = accepted_or_named(build, name, value)
    if hub is not None:
        exercise_spacecraft(Spacecraft(hub, [Mount(ROD_BEAM, (0.5, 0.0), 0.0)]),
                            Spacecraft(hub, [Mount(ROD_BEAM.truncated(6), (0.5, 0.0), 0.0)]))


def check_mount_value(name, value):
    mount = accepted_or_named(MOUNT_PARAMETERS[name], name, value)
    if mount is not None:
        truncated = Mount(ROD_BEAM.truncated(6), tuple(mount.position), mount.angle)
        exercise_spacecraft(Spacecraft(Hub(100.0, 50.0), [mount]),
                            Spacecraft(Hub(100.0, 50.0), [truncated]))


# (group, parameter) -> (check of one value, range key of its edges)
CASES = {
    **{("beam", name): (check_beam_value, key) for name, (_, key) in BEAM_PARAMETERS.items()},
    **{("chain", name): (check_chain_value, key) for name, (_, key) in CHAIN_PARAMETERS.items()},
    **{("hub", name): (check_hub_value, key) for name, (_, key) in HUB_PARAMETERS.items()},
    **{("mount", name): (check_mount_value, "length") for name in MOUNT_PARAMETERS},
}


@pytest.mark.parametrize("case", CASES, ids="-".join)
def test_parameter_edges(case):
    check, key = CASES[case]
    for value in sweep_values(key):
        check(case[1], value)


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES, ids="-".join)
@SWEEP
@given(value=magnitudes, negative=st.booleans())
def test_parameter_decades(case, value, negative):
    """Negative values only where a sign is meaningful (mount coordinates and angles)."""
    check, _ = CASES[case]
    check(case[1], -value if negative and case[0] == "mount" else value)


@SWEEP
@given(s=st.builds(lambda v, angle: v * complex(math.cos(angle), math.sin(angle)),
                   magnitudes, st.floats(-math.pi, math.pi)))
def test_laplace_variable_decades(s):
    """W(s) of every model at any |s|: finite and symmetric within S_RANGE, refused by name
    (s) beyond it."""
    models = [ROD_BEAM, Beam(**PLAIN, damping_ratio=0.01), ROD_BEAM.truncated(4),
              ROD_BEAM.truncated(4, method="residual"), ROD_BEAM.truncated(4, method="free-free"),
              HingedChain.rfem(ROD_BEAM, 5)]
    for model in models:
        W = accepted_or_named(model.W, "s", s)
        if W is not None:
            assert np.all(np.isfinite(W)) and W[0, 1] == W[1, 0]
