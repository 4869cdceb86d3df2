"""The small rod scenes the tests run in the plane and in three axes, held once.

:func:`rod_scene`: a hub of 100 kg carries the paper's rod (PAPER.md: steel, L = 10 m,
d = 10 mm, rho = 7800 kg/m^3, E = 2.06e11 Pa), lightly damped (damping ratio 0.005), clamped
0.5 m off the hub's centre along x (three axes: 0.1 m above it, the rod along x). The controller
is a PD of 0.1 rad/s tuned on the rod's three-body chain (poles-and-zeros fit); the truth keeps
two modes a beam (``fidelity.n_modes = 2``); the slew is 10 deg in 30 s, simulated for 45 s at
0.25 s; no plots and no FMUs. It is small so that a test can run it many times (the scene-key
walk runs it for every documented key, in the plane and in three axes): one rod, three bodies
and two modes a beam, a short coarse time grid, nothing written that a test does not ask for.

The scene readers' tests start from a slower variant of it, :data:`BASE` (the rod undamped,
three truth modes, a 60 s slew), edited by :func:`scene_with`; :data:`BASE_TOML` is the same
scene as a file's text for the command's tests. The same rod's rigid finite elements, worked
out by hand, are :func:`rod_chain`: an explicit chain as a scene gives it.

Beside them: the manoeuvre as flown (:data:`FLOWN`, :func:`flown`, :func:`flown_damped`),
the run with both controllers on twelve truth modes (:data:`LOOP_SCENE`), a three-axis boom
(:data:`THREE_AXIS_BOOM`), a three-axis wing Basilisk runs in seconds
(:func:`soft_three_axis_scene`) and the shipped default sweep scene (:func:`default_sweep_scene`).

Units are the scene file's: SI, angles in degrees.
"""
from __future__ import annotations

import copy
import tomllib

__all__ = ["BASE", "BASE_TOML", "FLOWN", "FLOWN_DAMPED", "LOOP_SCENE", "THREE_AXIS_BOOM",
           "default_sweep_scene", "flown", "flown_damped", "rod_chain", "rod_scene",
           "scene_with", "soft_three_axis_scene", "with_changes"]

_ROD = {"section": "rod", "length": 10.0, "diameter": 0.01, "density": 7800.0,
        "youngs_modulus": 2.06e11, "damping_ratio": 0.005}

_PLANAR = {
    "title": "small rod",
    "hub": {"mass": 100.0, "inertia": 50.0},
    "appendages": [{"name": "rod", "position": [0.5, 0.0], "direction": 0.0,
                    "beam": _ROD, "fit": {"n_bodies": 3, "match": "poles-and-zeros"}}],
    "fidelity": {"n_modes": 2},
    "controller": {"types": ["pd"], "pd": {"natural_frequency": 0.1, "damping": 0.7}},
    "manoeuvre": {"slew_angle": 10.0, "slew_time": 30.0, "duration": 45.0, "step": 0.25},
    "report": {"plots": False},
    "export": {"fmu": False},
}

_THREE_AXIS = {
    **_PLANAR,
    # a full tensor: products of inertia couple the axes
    "hub": {"mass": 100.0, "inertia": [[60.0, 2.0, 0.0], [2.0, 50.0, 1.0], [0.0, 1.0, 40.0]]},
    "appendages": [{"name": "rod", "position": [0.5, 0.0, 0.1], "orientation": [0.0, 0.0, 0.0],
                    "beam": _ROD, "fit": {"n_bodies": 3, "match": "poles-and-zeros"}}],
    "manoeuvre": {**_PLANAR["manoeuvre"], "slew_axis": "z"},
}

#: The scene readers' planar base (:func:`scene_with` edits a copy; never change it in place):
#: the same hub and rod, undamped (damped Craig-Bampton models project the beam's damping on
#: their modes, which costs seconds per model; the tests that need damping set it), its chain
#: fitted on the frequencies, three truth modes, a PD of 0.1 rad/s at its default damping, the
#: slew in 60 s simulated for 120 s at 0.5 s; no title, report or export table.
BASE = {
    "hub": {"mass": 100.0, "inertia": 50.0},
    "appendages": [{"name": "rod", "position": [0.5, 0.0], "beam": {**_ROD, "damping_ratio": 0.0},
                    "fit": {"match": "frequencies"}}],
    "fidelity": {"n_modes": 3},
    "controller": {"types": ["pd"], "pd": {"natural_frequency": 0.1}},
    "manoeuvre": {"slew_angle": 10.0, "slew_time": 60.0, "duration": 120.0, "step": 0.5},
}

#: :data:`BASE` as a scene file's text, titled, with tip outputs and no equivalence section (no
#: FMUs; plots only when asked): the command's tests write it to a file.
BASE_TOML = """\
title = "test boom"

[hub]
mass = 100.0
inertia = 50.0

[[appendages]]
name = "rod"
position = [0.5, 0.0]

[appendages.beam]
section = "rod"
length = 10.0
diameter = 0.01
density = 7800.0
youngs_modulus = 2.06e11

[appendages.fit]
match = "frequencies"

[fidelity]
n_modes = 3

[controller]
types = ["pd"]

[controller.pd]
natural_frequency = 0.1

[manoeuvre]
slew_angle = 10.0
slew_time = 60.0
duration = 120.0
step = 0.5

[outputs]
tip_deflection = true

[report]
equivalence = false
"""

#: The manoeuvre as flown, as changes to :data:`BASE` (dotted key paths): a shaped profile with
#: feedforward under torque and rate limits, a 0.2 s loop delay, a 0.1 s step, wheels that
#: saturate and attitude sensor noise.
FLOWN = {"manoeuvre.profile": "shaped", "manoeuvre.feedforward": True,
         "manoeuvre.torque_limit": 0.1, "manoeuvre.rate_limit": 0.5,
         "controller.delay": 0.2, "manoeuvre.step": 0.1,
         "wheels": {"torque_limit": 0.2, "momentum_limit": 4.0, "spin_inertia": 0.02},
         "sensors": {"attitude_density": 1e-5, "angle_random_walk": 1e-6, "rpe_window": 10.0}}

#: :data:`FLOWN`'s rod damped (0.5 %: the loops are stable, the delay margins finite), flexsat's
#: fit, tip outputs, PD and LQR.
FLOWN_DAMPED = {"appendages.0.beam.damping_ratio": 0.005,
                "appendages.0.fit": {"match": "poles-and-zeros"},
                "outputs": {"tip_deflection": True}, "controller.types": ["pd", "lqr"],
                "controller.lqr": {"attitude_weight": 7.6, "torque_weight": 1.0}}

#: A three-axis spacecraft: an 820 kg hub with a full inertia tensor [kg m^2] and a CFRP tube
#: boom (4 m, 50 mm, 1 mm wall) at a point off the hub's axes, flexsat's fit, three truth modes,
#: a PD of 0.1 rad/s, a 10 deg slew in 60 s about an axis off the principal ones.
THREE_AXIS_BOOM = {
    "hub": {"mass": 820.0, "inertia": [[950.0, 12.0, -8.0], [12.0, 780.0, 15.0],
                                       [-8.0, 15.0, 640.0]]},
    "appendages": [{"name": "boom", "position": [0.6, 0.3, -0.9],
                    "beam": {"section": "tube", "length": 4.0, "outer_diameter": 0.05,
                             "wall_thickness": 0.001, "density": 1600.0,
                             "youngs_modulus": 1.2e11},
                    "fit": {"match": "poles-and-zeros"}}],
    "fidelity": {"n_modes": 3},
    "controller": {"types": ["pd"], "pd": {"natural_frequency": 0.1}},
    "manoeuvre": {"slew_angle": 10.0, "slew_time": 60.0, "step": 0.5,
                  "slew_axis": [1.0, 1.0, 0.5]}}

#: The paper's rod, damped, on twelve truth modes with PD and LQR, tip outputs and the exact
#: reference: the design loop's end-to-end scene (a 150 s slew at 0.1 s).
LOOP_SCENE = {
    "hub": {"mass": 100.0, "inertia": 50.0},
    "appendages": [{"name": "rod", "position": [0.5, 0.0], "beam": dict(_ROD),
                    "fit": {"match": "poles-and-zeros"}}],
    "fidelity": {"n_modes": 12},
    "controller": {"types": ["pd", "lqr"], "pd": {"natural_frequency": 0.1},
                   "lqr": {"attitude_weight": 7.6, "torque_weight": 1.0}},
    "manoeuvre": {"slew_angle": 10.0, "slew_time": 60.0, "duration": 150.0, "step": 0.1},
    "outputs": {"tip_deflection": True, "exact_reference": True},
    "report": {"equivalence": False},
}

# The rod's rigid finite elements by hand: three bodies, the inner one twice the outer ones
# (lengths 2.5, 5, 2.5 m, masses rho A l, inertias m l^2 / 12), hinges of EJ / H with
# EJ = E pi d^4 / 64 = 101.1 N m^2 and H = 5 m. In three axes also torsion (GJ = 77.6 N m^2,
# rho I_p = 7.66e-6 kg m) and axial springs (EA = 1.62e7 N) by the lumped rule; x-z bending as
# x-y (the rod is round).
_CHAIN = {"lengths": [2.5, 5.0, 2.5], "masses": [1.53, 3.06, 1.53],
          "inertias": [0.797, 6.38, 0.797], "hinge_stiffnesses": [20.2, 20.2],
          "hinge_dampings": [0.1, 0.1], "com_offsets": [1.25, 2.5, 1.25]}
_CHAIN_3 = {"torsional_inertias": [1.9e-5, 3.8e-5, 1.9e-5],
            "torsion_stiffnesses": [20.7, 20.7], "axial_stiffnesses": [4.3e6, 4.3e6]}


def edited(text: str, *edits: tuple[str, str]) -> str:
    """A scene's TOML text with each ``(old, new)`` edit made in turn.

    Each ``old`` must occur exactly once in the text as edited so far: an edit that changes
    nothing (the base scene changed under the test) or could change the wrong line is a
    mistake in the test, not a scene to run.

    Raises
    ------
    AssertionError
        Naming the edit and how often its text occurs.
    """
    for old, new in edits:
        count = text.count(old)
        assert count == 1, f"the edit {old!r} -> {new!r:.60} finds {count} occurrences, not 1"
        text = text.replace(old, new)
    return text


def with_changes(data: dict, changes: dict) -> dict:
    """A deep copy of a scene with changes at dotted key paths.

    Parameters
    ----------
    data : dict
        A scene as the TOML reader gives it; left untouched.
    changes : dict
        Key path -> value. A path is table keys and list indices joined by dots
        (``"appendages.0.beam.diameter"``); a missing table on the way is created; the value
        is copied in, and None removes the key (which must be there: a removal that removes
        nothing is a mistake in the test).

    Returns
    -------
    dict
    """
    data = copy.deepcopy(data)
    for path, value in changes.items():
        keys = path.split(".")
        node = data
        for key in keys[:-1]:
            node = node[int(key)] if isinstance(node, list) else node.setdefault(key, {})
        last = int(keys[-1]) if isinstance(node, list) else keys[-1]
        if value is None:
            del node[last]
        else:
            node[last] = copy.deepcopy(value)
    return data


def rod_scene(three_axis: bool = False, **changes) -> dict:
    """The small rod scene (see the module), as a new dict.

    Parameters
    ----------
    three_axis : bool
        False: the planar scene (hub inertia 50 kg m^2, the rod's direction 0 deg). True: the
        three-axis scene (a full hub inertia tensor [kg m^2], the rod mounted at
        (0.5, 0, 0.1) m with orientation (0, 0, 0) deg, the slew about z).
    **changes
        Dotted key paths to values, as :func:`with_changes` takes them
        (``rod_scene(outputs={"exact_reference": True})``,
        ``rod_scene(True, **{"appendages.0.beam.diameter": 0.05})``); None removes a key.

    Returns
    -------
    dict
    """
    return with_changes(_THREE_AXIS if three_axis else _PLANAR, changes)


def scene_with(**changes) -> dict:
    """:data:`BASE` with changes at dotted key paths, as :func:`with_changes` takes them
    (``scene_with(**{"hub.mass": -1})``); None removes a key."""
    return with_changes(BASE, changes)


def rod_chain(three_axis: bool = False) -> dict:
    """The small rod's rigid finite elements as a scene's explicit ``chain`` table (SI units).

    Parameters
    ----------
    three_axis : bool
        Also the torsion and axial arrays a three-axis chain needs.

    Returns
    -------
    dict
        A new dict: lengths [m], masses [kg], inertias [kg m^2], hinge stiffnesses [N m/rad]
        and dampings [N m s/rad], centre-of-mass offsets [m]; three axes also torsional
        inertias [kg m^2], torsion [N m/rad] and axial [N/m] stiffnesses.
    """
    return copy.deepcopy({**_CHAIN, **_CHAIN_3} if three_axis else _CHAIN)


def flown(**changes) -> dict:
    """:data:`BASE` flown (:data:`FLOWN`), with changes at dotted key paths; None removes a key
    (one of FLOWN's: it is left out)."""
    merged = {**FLOWN, **changes}
    return scene_with(**{k: v for k, v in merged.items() if not (v is None and k in FLOWN)})


def flown_damped(**changes) -> dict:
    """:func:`flown` with :data:`FLOWN_DAMPED`, and changes at dotted key paths."""
    return flown(**{**FLOWN_DAMPED, **changes})


def default_sweep_scene() -> dict:
    """The shipped default sweep scene as a new dict, without its ``[sweep]`` table."""
    from spacecraft.sweep import sweep_scene_path

    raw = tomllib.loads(sweep_scene_path("default").read_text())
    raw.pop("sweep")
    return raw


def soft_three_axis_scene(**simulator) -> dict:
    """A three-axis scene whose 2-body wing chain Basilisk runs in seconds (highest mode 51
    rad/s): 200 kg hub with a full inertia tensor, a canted 4 m wing off the centre of mass, a
    0.1 deg eigen-axis slew about (1, 1, 0.5), run in Basilisk with ``simulator`` keys."""
    return {
        "hub": {"mass": 200.0, "inertia": [[120.0, 3.0, -2.0], [3.0, 100.0, 4.0],
                                           [-2.0, 4.0, 80.0]]},
        "appendages": [{"name": "wing", "position": [0.0, 0.6, 0.1],
                        "orientation": [90.0, 0.0, 20.0],
                        "beam": {"section": "rectangular", "length": 4.0, "width": 0.3,
                                 "thickness": 0.03, "density": 600.0, "youngs_modulus": 7e8,
                                 "poisson_ratio": 0.3, "damping_ratio": 0.005},
                        "fit": {"n_bodies": 2}}],
        "controller": {"types": ["pd"], "pd": {"natural_frequency": 0.2, "damping": 0.7}},
        "manoeuvre": {"slew_angle": 0.1, "slew_time": 15.0, "duration": 60.0, "step": 0.1,
                      "slew_axis": [1.0, 1.0, 0.5]},
        "outputs": {"tip_deflection": True}, "report": {"plots": False},
        "simulator": {"name": "basilisk", **simulator}}
