"""The three-axis margins against a brute-force reference (tests/support/dense_margins.py): the
loop's functions on a grid of about 1.1e5 to 1.9e5 frequencies from the plain state-space
matrices, dense around every pole and zero that can make a narrow feature (the plant's, the
controller's, the closed loop's, and each loop-at-a-time function's poles and true zeros).

The reference's values are bounds in the safe direction (each a grid value: a minimum found on
a grid is at least the true minimum; a crossover's margin the larger of its bracket's two ends),
so a margin of flexsat above the reference's is above the truth: a miss, a verdict more
optimistic than the truth. flexsat refines on the exact function, so it must be at most the
reference's bound; the tolerance is the round-off of evaluating the loop (rtol 1e-6: L near a
lightly damped pole is evaluated to about cond eps, far below it here). The crossings' margins
(phase, gain, delay per axis; the three-axis delay margin from the unit-circle crossings of L's
eigenvalues) are compared with the reference's crossings bisected to 1e-13 relative on its own
evaluation of the loop (the cut loop's SISO system per axis, the count of L's eigenvalues
outside the unit circle), at the same tolerance; the phase margin also with its bracket bound.

Loops: the shipped three_axis scene's truth loop with its PD (notched) and LQR controllers, and
seeded random hubs (full inertia tensors, 2-5 collocated modes in random directions, damping
ratios 1e-4 to 2e-2, some modes in close pairs) under a PD designed on the rigid hub with its
natural frequency 5 % to 45 % of the first flexible mode's (small margins): plain, notched,
rolled off, and digital.
"""
import math
import warnings

import numpy as np
import pytest

import controllers
from dense_margins import AXES, dense_margins
from loops import random_pd
from plants import three_axis_plant

RTOL = 1e-6


def random_loop(seed: int):
    """A seeded random three-axis plant and a PD designed on its rigid hub."""
    rng = np.random.default_rng(seed)
    d = rng.uniform(600.0, 1500.0, 3)
    off = rng.uniform(-0.1, 0.1, 3) * np.sqrt(d[[0, 0, 1]] * d[[1, 2, 2]])
    J = np.diag(d)
    J[0, 1] = J[1, 0] = off[0]
    J[0, 2] = J[2, 0] = off[1]
    J[1, 2] = J[2, 1] = off[2]
    n = rng.integers(2, 6)
    w1 = rng.uniform(0.5, 5.0)
    ws = [w1]
    for _ in range(n - 1):
        ws.append(ws[-1] * (rng.uniform(1.002, 1.05) if rng.random() < 0.3
                            else rng.uniform(1.1, 3.0)))
    modes = []
    for w in ws:
        zeta = 10.0 ** rng.uniform(-4.0, math.log10(2e-2))
        u = rng.standard_normal(3)
        u /= np.linalg.norm(u)
        b = u * math.sqrt(rng.uniform(0.05, 0.6) / np.mean(d))
        modes.append((w, zeta, b, b))
    plant = three_axis_plant(J, modes)
    rigid = three_axis_plant(J, [])
    kind = rng.integers(0, 4)
    wn = w1 * rng.uniform(0.05, 0.45)
    damping = rng.uniform(0.5, 0.9)
    K = random_pd(rng, rigid, w1, kind, wn, damping)
    return plant, K


def excesses(plant, controller, **density) -> dict:
    """(flexsat - reference) / reference for every margin (positive: flexsat is larger)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m = controllers.margins(plant, controller)
    with np.errstate(all="ignore"):
        ref = dense_margins(plant, controller, **density)
    pairs = {}
    for a in AXES:
        f, r = m.loop_at_a_time[a], ref["axes"][a]
        pairs.update({f"modulus_margin_{a}": (f.modulus_margin, r["modulus_margin"]),
                      f"phase_margin_{a}": (abs(f.phase_margin), r["phase_margin"]),
                      f"phase_margin_bisected_{a}": (abs(f.phase_margin),
                                                     r["phase_margin_bisected"]),
                      f"gain_margin_{a}": (abs(f.gain_margin), r["gain_margin_bisected"]),
                      f"delay_margin_{a}": (f.delay_margin, r["delay_margin_bisected"])})
    pairs.update(min_singular_value=(m.min_singular_value, ref["min_singular_value"]),
                 disk_margin=(m.disk_margin, ref["disk_margin"]),
                 delay_margin=(m.delay_margin, ref["delay_margin_bisected"]))
    out = {}
    for name, (mine, theirs) in pairs.items():
        if math.isinf(theirs):
            out[name] = 0.0 if math.isinf(mine) else -1.0   # flexsat found one: smaller
        else:
            out[name] = (mine - theirs) / abs(theirs)
    # the reference's own resolution of the phase across a crossover bracket: a few degrees at
    # most (the phase margin's bracket bound is then within that of the bisected value)
    assert ref["accuracy"]["phase_bracket_deg"] < 2.0
    return out


def misses(plant, controller, **density) -> dict:
    return {k: v for k, v in excesses(plant, controller, **density).items() if not v <= RTOL}


# seeds 53 and 58 are loops whose three-axis delay margin (the unit-circle crossings of L's
# eigenvalues) the count on the grid used to miss: 53 an eigenvalue grazing the unit circle
# between two grid points (two crossings 4e-4 rad/s apart at 9.38 rad/s: 0.247 s reported,
# 0.057 s true), 58 two eigenvalues crossing between the same two grid points 9e-5 rad/s apart
# (the second crossing dropped once the first was bisected: 2e-4 too large; the shipped
# three_axis scene's PD loop likewise, three crossings at 0.1542 rad/s: 7.18185 s reported,
# 7.17989 s true); 229 a loop whose largest singular value of S - I/2 peaks twice, at 1.19 and
# 2.27 rad/s, the second sampled coarser: its grid value 1.7e-4 below the first's, its true
# peak 2e-4 above (disk margin 0.288981 reported, 0.288924 true)
SEEDS = [0, 2, 5, 12, 20, 39, 53, 58, 229]


@pytest.mark.slow
@pytest.mark.parametrize("seed", SEEDS)
def test_random_three_axis_loops_miss_nothing_the_dense_reference_finds(seed):
    found = misses(*random_loop(seed))
    assert not found, f"flexsat's margins above the dense reference's: {found}"


@pytest.mark.slow
def test_the_shipped_three_axis_scenes_truth_loops_miss_nothing():
    import spacecraft
    from spacecraft.design.loop import DesignLoop

    scene = spacecraft.load_scene("three_axis", overrides={
        "export.fmu": False, "report.plots": False, "outputs.exact_reference": False})
    design = DesignLoop(scene)
    n_modes = design.n_modes
    truth = design.truth_plant(n_modes)
    for kind in scene.controller.types:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            K = design.tuned(design.variants[0], kind, n_modes).controller
        # (a coarser reference on these 54-state truth loops: 3e4 log points, 201 per root)
        found = misses(truth, K, n_log=30_000, n_window=201)
        assert not found, f"{kind}: flexsat's margins above the dense reference's: {found}"
