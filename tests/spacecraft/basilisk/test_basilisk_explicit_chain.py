"""The Basilisk run of a three-axis scene whose design model is an explicit chain
(``design = "chain"`` with its bodies and hinges), not one fitted to the beam, on a rigid root
or a hinged one (a sprung joint between mount and body 1 in every motion).

What the comparison can expect: as for the fitted chains of
tests/spacecraft/basilisk/test_basilisk_three_axis.py (its module docstring): Basilisk's run
differs from flexsat's linear chain by RK4's error (below 1e-7 of the peaks) and by the terms
the linear model drops, second order in the amplitude: relative to the first-order response the
slew angle [rad] times factors of order one. Hence "relative difference <= angle in rad" for
every signal at 0.1 deg, and halving the angle halves every relative difference (2 +- 2 %: a
convention error, a body or hinge misplaced, would leave a first-order difference that does not
scale).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from appendages import HingedChain
from appendages.fit3d import rod_chain_frequencies
from spacecraft import Spacecraft, load_scene, run
from spacecraft.basilisk import default_sample_time
from spacecraft.design.models import ModelBuilder, RunStats

from scenes import soft_three_axis_scene

#: the scene's slew [rad]
SMALL = math.radians(soft_three_axis_scene()["manoeuvre"]["slew_angle"])

# runs Basilisk: skipped with the install hint where bsk is not installed (tests/conftest.py)
needs_bsk = pytest.mark.basilisk

# a 4 m, 21.6 kg three-body chain (the beam's length and mass) whose motions all differ: x-z
# inertias 1.2 times the x-y ones, torsion inertias 0.25 J_z + 0.02 m (every body's moments
# obey the triangle inequality: nothing raised), stiffer x-z hinges, torsion springs, and
# undamped axial springs (which Basilisk holds rigid)
MASSES = [7.0, 7.5, 7.1]
INERTIAS = [0.9, 1.3, 1.2]
AXIAL = [1e6, 1e6]
CHAIN = {"lengths": [1.2, 1.4, 1.4], "masses": MASSES, "inertias": INERTIAS,
         "hinge_stiffnesses": [250.0, 200.0], "hinge_dampings": [0.2, 0.15],
         "com_offsets": [0.6, 0.7, 0.72], "inertias_y": [1.2 * j for j in INERTIAS],
         "hinge_stiffnesses_y": [700.0, 500.0], "hinge_dampings_y": [0.4, 0.3],
         "torsional_inertias": [0.25 * j + 0.02 * m for j, m in zip(INERTIAS, MASSES)],
         "torsion_stiffnesses": [250.0, 200.0], "torsion_dampings": [0.025, 0.02],
         "axial_stiffnesses": AXIAL}


# the same chain on a hinged root: a joint between mount and body 1 first in every per-joint
# array, stiffer than the next in each motion
HINGED = {**CHAIN, "root": "hinged",
          "hinge_stiffnesses": [400.0, 250.0, 200.0], "hinge_dampings": [0.3, 0.2, 0.15],
          "hinge_stiffnesses_y": [900.0, 700.0, 500.0], "hinge_dampings_y": [0.5, 0.4, 0.3],
          "torsion_stiffnesses": [300.0, 250.0, 200.0],
          "torsion_dampings": [0.03, 0.025, 0.02], "axial_stiffnesses": [1e6] + AXIAL}


def explicit_chain_scene(angle_deg: float = 0.1, chain: dict = CHAIN) -> dict:
    """The soft three-axis scene of the fitted-chain tests with the wing's design model the
    explicit ``chain`` (its truth still the beam), slewing ``angle_deg``."""
    data = soft_three_axis_scene()
    wing = data["appendages"][0]
    del wing["fit"]
    wing.update(design="chain", chain=dict(chain))
    data["manoeuvre"]["slew_angle"] = angle_deg
    return data


def _held_axial_frequency(chain: dict) -> float:
    """First axial frequency [rad/s] of ``chain`` with its root held: the bodies' masses on
    the axial springs (a hinged root's first between the held mount and body 1), from the
    3 x 3 eigenproblem written out here."""
    m, k = np.array(chain["masses"]), np.array(chain["axial_stiffnesses"], dtype=float)
    n = m.size
    K = np.zeros((n, n))
    springs = k if chain.get("root") == "hinged" else np.concatenate([[np.inf], k])
    for j in range(1, n):                       # spring j between bodies j - 1 and j
        K[j - 1:j + 1, j - 1:j + 1] += springs[j] * np.array([[1.0, -1.0], [-1.0, 1.0]])
    if chain.get("root") == "hinged":
        K[0, 0] += springs[0]
        return float(np.sqrt(np.linalg.eigvalsh(K / np.sqrt(np.outer(m, m)))[0]))
    # a rigid root: body 1 is the mount's, held
    return float(np.sqrt(np.linalg.eigvalsh(K[1:, 1:] / np.sqrt(np.outer(m[1:], m[1:])))[0]))


@pytest.mark.slow
@needs_bsk
@pytest.mark.parametrize("given", [CHAIN, HINGED], ids=["rigid_root", "hinged_root"])
def test_an_explicit_three_axis_chain_flies_in_basilisk_as_flexsats_linear_chain(given):
    full = run(explicit_chain_scene(0.1, given))
    half = run(explicit_chain_scene(0.05, given))
    entry = full.data["basilisk"]["pd"]
    chain = entry["differences"]["basilisk_vs_chain"]
    names = ({f"{q}_{a}" for q in ("theta", "omega", "torque") for a in "xyz"}
             | {f"wing_{m}" for m in ("tip_deflection_y", "tip_deflection_z", "tip_twist")})
    assert names <= set(chain)
    halved = half.data["basilisk"]["pd"]["differences"]["basilisk_vs_chain"]
    for name in names:
        assert chain[name]["relative"] <= SMALL, name       # second order: the angle x O(1)
        assert chain[name]["relative"] / halved[name]["relative"] == pytest.approx(
            2.0, rel=0.02), name
    # Basilisk flew the explicit chain: its axial springs held rigid (and said so), the mode
    # they drop the chain's own first axial frequency with the root held
    held = entry["chains_as_held"]["wing"]
    assert held["held"] == ["axial"]
    assert held["axial_frequency"] == pytest.approx(_held_axial_frequency(given), rel=1e-12)
    if given is CHAIN:
        _, clamped = rod_chain_frequencies(np.array(MASSES), np.array(AXIAL))
        assert held["axial_frequency"] == pytest.approx(clamped, rel=1e-12)
    assert not [w for w in full.data["warnings"] if "BasiliskModelWarning" in w]
    assert "wing_tip_twist [rad] differs from" in entry["summary"]
    # The flight-software rate is chosen on the loop Basilisk flies: the inextensible chain's,
    # as if it had no axial springs. On the design plant the undamped axial mode (230 rad/s)
    # has a loop gain of 1 or more and would ask for a rate ten times or more higher.
    scene = load_scene(explicit_chain_scene(0.1, given))
    builder = ModelBuilder(scene, None, RunStats())
    variant = builder.variants[0]
    design = builder.design_spacecraft(variant, None)
    K = builder.tuned(variant, "pd", None).controller
    rigid = dict(given)
    del rigid["axial_stiffnesses"]
    inextensible = HingedChain(rigid.pop("lengths"), rigid.pop("masses"), rigid.pop("inertias"),
                               rigid.pop("hinge_stiffnesses"), **rigid)
    flown = Spacecraft(design.hub, [design.mounts[0].with_appendage(inextensible)])
    expected = default_sample_time(flown.plant(prune=True), K)
    assert entry["sample_time"] == expected
    assert default_sample_time(design.plant(prune=True), K) < expected / 10

