"""Every documented scene key is honoured or refused by name, in a planar and a three-axis scene.

The keys are those of the scene reference (the table in :mod:`spacecraft.scene.read`, which the
README points to) and every key the embedded scenes use. For each key and each kind of scene a
case gives a context (keys set in both runs) and a change (the key itself, with whatever it
needs beside it); the run with the change must differ from the run without it (its results,
and for report and export keys the files written), or the scene must be refused with a
SceneError that names the key, its table or a key of the case. A key read and then ignored
fails here: that is the bug this test is for.
"""
from __future__ import annotations

import copy
import functools
import json
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from spacecraft import SceneError, load_scene, run, write_report
from spacecraft.scene import read as scene_read
from spacecraft.scene.read import example_scenes, scene_path
from scenes import rod_chain, rod_scene

DATA = Path(scene_path("real_appendages")).parent / "data"

# -- the two base scenes: small and fast (tests/support/scenes.py) ------------------------------
PLANAR = rod_scene()
THREE_AXIS = rod_scene(three_axis=True)
BASES = {"planar": PLANAR, "three_axis": THREE_AXIS}

A = "appendages[0]"
M = "manoeuvre"
# the rod's rigid finite elements by hand (three axes: with its torsion and axial springs)
CHAIN = {**rod_chain(), "root": "rigid"}
RFEM = {"from_beam": "rfem", "n_bodies": 3}
CHAIN_3 = {**rod_chain(three_axis=True), "root": "rigid"}
TUBE = {"section": "tube", "diameter": None, "outer_diameter": 0.02, "wall_thickness": 0.002}
RECTANGLE = {"section": "rectangular", "diameter": None, "width": 0.05, "thickness": 0.01}
UNIFORM = {"section": "uniform", "diameter": None, "density": None, "youngs_modulus": None,
           "bending_stiffness": 101.1, "linear_density": 0.6126}
SEGMENTS = [{"section": "rod", "length": 5.0, "diameter": 0.012, "density": 7800.0,
             "youngs_modulus": 2.06e11},
            {"section": "rod", "length": 5.0, "diameter": 0.008, "density": 7800.0,
             "youngs_modulus": 2.06e11}]
# structures whose chain fits are costly: the controllers tuned on the truth model itself
TRUTH_DESIGN = {f"{A}.design": "truth", f"{A}.fit": None}
STEPPED = {**TRUTH_DESIGN, f"{A}.beam": None, f"{A}.stepped_beam": {"segments": SEGMENTS,
                                                    "damping_ratio": 0.005}}
TAPERED = {**TRUTH_DESIGN, f"{A}.beam": None, f"{A}.tapered_beam": {
    "section": "rod", "length": 10.0, "root_dimensions": {"diameter": 0.012},
    "tip_dimensions": {"diameter": 0.008}, "density": 7800.0, "youngs_modulus": 2.06e11,
    "n_segments": 2, "damping_ratio": 0.005}}
NASTRAN = {"nastran": str(DATA / "boom_modes.npz"), "root": 1, "units": ["in", "slinch"],
           "mass_matrix": str(DATA / "boom_mass.npy"), "tip_grid": 11, "damping": 0.003}
LQR = {"controller.types": ["lqr"],
       "controller.lqr": {"attitude_weight": 7.6, "torque_weight": 1.0, "rate_weight": 0.0}}
DISTURBANCE = {f"{M}.disturbance": {"input": "disturbance_torque", "amplitude": 0.01,
                                    "start": 35.0, "length": 2.0}}
DISTURBANCE_3 = {f"{M}.disturbance": {**DISTURBANCE[f"{M}.disturbance"], "axis": "z"}}
FMU = {"export.fmu": True, "export.systems": ["controller"], "export.sources_only": True}
# limits that fly the slew in its time (bang-coast-bang: 26 s of the 30 s; the shaped profile
# adds the ZVD shaper's period of the rod's first mode, about 14 s, in a 60 s slew)
FLOWN = {f"{M}.profile": "bang-coast-bang", f"{M}.torque_limit": 0.3, f"{M}.rate_limit": 1.0}
SHAPED = {f"{M}.profile": "shaped", f"{M}.torque_limit": 0.3, f"{M}.rate_limit": 1.0,
          f"{M}.shaper": {"kind": "zvd"}, f"{M}.slew_time": 60.0, f"{M}.duration": 80.0}
# wheels that can fly the 30 s slew (the shortest 25 s planar, 17 s with the pyramid)
WHEELS = {"wheels": {"torque_limit": 0.3, "momentum_limit": 4.0, "spin_inertia": 0.02}}
# three axes: a four-wheel pyramid about +z (the default cant angle)
WHEELS_3 = {"wheels": {**WHEELS["wheels"], "pyramid": {}}}
SENSORS = {"sensors": {"attitude_density": 1e-5, "rpe_window": 2.0}}
TIP = {f"{A}.tip": {"mass": 1.0}}
CHAIN_DESIGN = {f"{A}.design": "chain", f"{A}.fit": None}


@functools.lru_cache(maxsize=None)
def _modal_numbers(three_axis: bool) -> dict:
    """The NASTRAN boom's modal data as numbers in the scene (SI)."""
    from appendages import read_nastran

    boom = read_nastran(DATA / "boom_modes.npz", root=1, units=("in", "slinch"),
                        mass_matrix=np.load(DATA / "boom_mass.npy"), tip=11, damping=0.003)
    if not three_axis:
        boom = boom.planar_view("xy")
    return {"frequencies": boom.frequencies.tolist(),
            "participation": boom.participation.tolist(),
            "rigid_mass": boom.rigid_mass.tolist(), "tip_motion": boom.tip_motion.tolist(),
            "damping": 0.003, "length": float(boom.length)}


def _cases(kind: str) -> dict:
    """key -> (context, change): key paths (``a.b[0].c``) to values, None removes a key."""
    three = kind == "three_axis"
    numbers = copy.deepcopy(_modal_numbers(three))
    modal = {f"{A}.beam": None, f"{A}.modal": numbers}
    given = ({"kind": "pd", "D": [[1.0 * (j % 3 == i) * (-1.0 if j > 2 else 1.0)
                                   for j in range(9)] for i in range(3)]}
             if three else {"kind": "pd", "D": [[1.0, -1.0, -1.0]]})
    second = copy.deepcopy(BASES[kind]["appendages"][0])
    second["name"] = "rod2"
    if three:
        second["orientation"] = [180.0, 0.0, 0.0]
    else:
        second["direction"] = 180.0
    vector = (lambda *v: list(v)) if three else (lambda *v: list(v[:2]))
    wheels = WHEELS_3 if three else WHEELS
    # an explicit chain as the design model (three axes: with its torsion and axial springs)
    explicit = {**CHAIN_DESIGN, f"{A}.chain": CHAIN_3 if three else CHAIN}
    return {
        "title": ({}, {"title": "another title"}),
        "hub.mass": ({}, {"hub.mass": 120.0}),
        "hub.inertia": ({}, {"hub.inertia": ([[70.0, 2.0, 0.0], [2.0, 50.0, 1.0],
                                              [0.0, 1.0, 40.0]] if three else 60.0)}),
        "appendages": ({}, {"appendages": BASES[kind]["appendages"] + [second]}),
        f"{A}.name": ({}, {f"{A}.name": "boom"}),
        f"{A}.position": ({}, {f"{A}.position": vector(0.6, 0.1, 0.2)}),
        f"{A}.direction": ({}, {f"{A}.direction": 90.0}),
        f"{A}.truth": ({f"{A}.chain": RFEM}, {f"{A}.truth": "chain"}),
        f"{A}.design": ({}, {f"{A}.design": "truth"}),
        f"{A}.beam.section": ({}, {f"{A}.beam.{k}": v for k, v in TUBE.items()}),
        f"{A}.beam.length": ({}, {f"{A}.beam.length": 9.0}),
        f"{A}.beam.diameter": ({}, {f"{A}.beam.diameter": 0.012}),
        f"{A}.beam.outer_diameter": ({f"{A}.beam.{k}": v for k, v in TUBE.items()},
                                     {f"{A}.beam.outer_diameter": 0.025}),
        f"{A}.beam.wall_thickness": ({f"{A}.beam.{k}": v for k, v in TUBE.items()},
                                     {f"{A}.beam.wall_thickness": 0.003}),
        f"{A}.beam.width": ({f"{A}.beam.{k}": v for k, v in RECTANGLE.items()},
                            {f"{A}.beam.width": 0.06}),
        f"{A}.beam.thickness": ({f"{A}.beam.{k}": v for k, v in RECTANGLE.items()},
                                {f"{A}.beam.thickness": 0.012}),
        f"{A}.beam.density": ({}, {f"{A}.beam.density": 7000.0}),
        f"{A}.beam.youngs_modulus": ({}, {f"{A}.beam.youngs_modulus": 1.9e11}),
        f"{A}.beam.bending_stiffness": ({f"{A}.beam.{k}": v for k, v in UNIFORM.items()},
                                        {f"{A}.beam.bending_stiffness": 120.0}),
        f"{A}.beam.linear_density": ({f"{A}.beam.{k}": v for k, v in UNIFORM.items()},
                                     {f"{A}.beam.linear_density": 0.7}),
        f"{A}.beam.damping_ratio": ({}, {f"{A}.beam.damping_ratio": 0.01}),
        f"{A}.beam.poisson_ratio": ({}, {f"{A}.beam.poisson_ratio": 0.2}),
        f"{A}.tip.mass": ({}, TIP),
        f"{A}.tip.inertia": (TIP, {f"{A}.tip.inertia": (np.diag([0.5, 0.4, 0.3]).tolist()
                                                       if three else 0.5)}),
        # three axes: an offset across the axis, which no chain holds (fit_chain_3d refuses
        # it by name): the controllers tuned on the truth model
        f"{A}.tip.offset": ({**TIP, **TRUTH_DESIGN} if three else TIP,
                            {f"{A}.tip.offset": [0.2, 0.0, 0.1] if three else 0.2}),
        f"{A}.stepped_beam.segments": (STEPPED, {f"{A}.stepped_beam.segments": SEGMENTS[::-1]}),
        f"{A}.stepped_beam.damping_ratio": (STEPPED, {f"{A}.stepped_beam.damping_ratio": 0.01}),
        f"{A}.tapered_beam.section": (TAPERED, {
            f"{A}.tapered_beam.section": "tube",
            f"{A}.tapered_beam.root_dimensions": {"outer_diameter": 0.03,
                                                  "wall_thickness": 0.002},
            f"{A}.tapered_beam.tip_dimensions": {"outer_diameter": 0.02,
                                                 "wall_thickness": 0.001}}),
        f"{A}.tapered_beam.length": (TAPERED, {f"{A}.tapered_beam.length": 9.0}),
        f"{A}.tapered_beam.root_dimensions": (TAPERED, {
            f"{A}.tapered_beam.root_dimensions": {"diameter": 0.014}}),
        f"{A}.tapered_beam.tip_dimensions": (TAPERED, {
            f"{A}.tapered_beam.tip_dimensions": {"diameter": 0.006}}),
        f"{A}.tapered_beam.n_segments": (TAPERED, {f"{A}.tapered_beam.n_segments": 3}),
        f"{A}.tapered_beam.density": (TAPERED, {f"{A}.tapered_beam.density": 7000.0}),
        f"{A}.modal": ({}, modal),
        f"{A}.modal.file": (modal, {f"{A}.modal": {"file": "MODAL_FILE"}}),
        f"{A}.modal.nastran": (modal, {f"{A}.modal": NASTRAN}),
        f"{A}.modal.root": ({f"{A}.beam": None, f"{A}.modal": NASTRAN},
                            {f"{A}.modal.root": 2}),
        f"{A}.modal.units": ({f"{A}.beam": None, f"{A}.modal": NASTRAN},
                             {f"{A}.modal.units": ["in", "lbm"]}),
        f"{A}.modal.mass_matrix": ({f"{A}.beam": None, f"{A}.modal": NASTRAN},
                                   {f"{A}.modal.mass_matrix": None}),
        f"{A}.modal.tip_grid": ({f"{A}.beam": None, f"{A}.modal": NASTRAN,
                                 "outputs.tip_deflection": True}, {f"{A}.modal.tip_grid": 6}),
        f"{A}.modal.axes": ({f"{A}.beam": None, f"{A}.modal": NASTRAN},
                            {f"{A}.modal.axes": [[0.0, 1.0, 0.0], [1.0, 0.0, 0.0],
                                                 [0.0, 0.0, -1.0]]}),
        f"{A}.modal.subcase": ({f"{A}.beam": None, f"{A}.modal": NASTRAN},
                               {f"{A}.modal.subcase": 2}),
        f"{A}.modal.frequencies": (modal, {f"{A}.modal.frequencies": [
            1.05 * w for w in numbers["frequencies"]]}),
        f"{A}.modal.participation": (modal, {f"{A}.modal.participation": [
            [0.95 * g for g in row] for row in numbers["participation"]]}),
        f"{A}.modal.rigid_mass": (modal, {f"{A}.modal.rigid_mass": [
            [1.05 * v for v in row] for row in numbers["rigid_mass"]]}),
        f"{A}.modal.tip_motion": ({**modal, "outputs.tip_deflection": True},
                                  {f"{A}.modal.tip_motion": None}),
        f"{A}.modal.damping": (modal, {f"{A}.modal.damping": 0.01}),
        f"{A}.modal.length": ({**modal, "outputs.tip_deflection": True},
                              {f"{A}.modal.length": 1.1 * numbers["length"]}),
        f"{A}.modal.n_modes": ({**modal, f"{A}.design": "truth", f"{A}.fit": None},
                               {f"{A}.modal.n_modes": 2}),
        f"{A}.truth_chain": ({**CHAIN_DESIGN, f"{A}.chain": RFEM},
                             {f"{A}.truth": "chain",
                              f"{A}.truth_chain": {"from_beam": "rfem", "n_bodies": 6}}),
        f"{A}.fit.n_bodies": ({}, {f"{A}.fit.n_bodies": 4}),
        f"{A}.fit.match": ({}, {f"{A}.fit.match": ["poles-and-zeros", "frequencies"]}),
        f"{A}.chain": ({}, {**CHAIN_DESIGN, f"{A}.chain": RFEM}),
        f"{A}.chain.lengths": (explicit,
                               {f"{A}.chain.lengths": [2.4, 5.2, 2.4]}),
        f"{A}.chain.masses": (explicit,
                              {f"{A}.chain.masses": [1.6, 3.0, 1.6]}),
        f"{A}.chain.inertias": (explicit,
                                {f"{A}.chain.inertias": [0.9, 6.0, 0.9]}),
        f"{A}.chain.hinge_stiffnesses": (explicit,
                                         {f"{A}.chain.hinge_stiffnesses": [25.0, 25.0]}),
        f"{A}.chain.hinge_dampings": (explicit,
                                      {f"{A}.chain.hinge_dampings": [0.5, 0.5]}),
        f"{A}.chain.com_offsets": (explicit,
                                   {f"{A}.chain.com_offsets": [1.0, 2.5, 1.0]}),
        # a hinged root: every per-joint array one entry longer (three axes: a soft drive
        # hinge in x-y bending, the root joint as stiff as the next in the other motions)
        f"{A}.chain.root": (explicit,
                            {f"{A}.chain.root": "hinged",
                             f"{A}.chain.hinge_stiffnesses": [5.0, 20.2, 20.2],
                             f"{A}.chain.hinge_dampings": None,
                             **({f"{A}.chain.torsion_stiffnesses": [20.7] * 3,
                                 f"{A}.chain.axial_stiffnesses": [4.3e6] * 3}
                                if three else {})}),
        f"{A}.chain.inertias_y": (explicit, {f"{A}.chain.inertias_y": [0.9, 6.0, 0.9]}),
        f"{A}.chain.hinge_stiffnesses_y": (explicit,
                                           {f"{A}.chain.hinge_stiffnesses_y": [25.0, 25.0]}),
        f"{A}.chain.hinge_dampings_y": (explicit, {f"{A}.chain.hinge_dampings_y": [0.5, 0.5]}),
        f"{A}.chain.torsional_inertias": (explicit, {f"{A}.chain.torsional_inertias": [
            1.9e-5, 5.0e-5, 1.9e-5]}),
        f"{A}.chain.torsion_stiffnesses": (explicit,
                                           {f"{A}.chain.torsion_stiffnesses": [30.0, 30.0]}),
        f"{A}.chain.torsion_dampings": (explicit, {f"{A}.chain.torsion_dampings": [1e-3, 1e-3]}),
        f"{A}.chain.axial_stiffnesses": (explicit,
                                         {f"{A}.chain.axial_stiffnesses": [5e6, 5e6]}),
        f"{A}.chain.axial_dampings": (explicit, {f"{A}.chain.axial_dampings": [10.0, 10.0]}),
        f"{A}.chain.from_beam": (explicit,
                                 {f"{A}.chain": RFEM}),
        f"{A}.chain.n_bodies": ({**CHAIN_DESIGN, f"{A}.chain": RFEM},
                                {f"{A}.chain.n_bodies": 5}),
        f"{A}.chain.root_stiffness": (
            {**CHAIN_DESIGN, f"{A}.chain": {**RFEM, "root": "hinged",
                                                    "root_stiffness": 5.0}},
            {f"{A}.chain.root_stiffness": 8.0}),
        f"{A}.chain.root_damping": (
            {**CHAIN_DESIGN, f"{A}.chain": {**RFEM, "root": "hinged",
                                                    "root_stiffness": 5.0}},
            {f"{A}.chain.root_damping": 0.5}),
        f"{A}.orientation": ({}, {f"{A}.orientation": [10.0, 20.0, 0.0]}),
        f"{A}.orientation_sequence": ({f"{A}.orientation": [10.0, 20.0, 30.0]},
                                      {f"{A}.orientation_sequence": "XYZ"}),
        "fidelity.n_modes": ({}, {"fidelity.n_modes": 3}),
        "fidelity.tolerance": ({}, {"fidelity.n_modes": None, "fidelity.tolerance": 1e-2}),
        "fidelity.method": ({}, {"fidelity.method": "residual"}),
        "fidelity.bandwidth_factor": ({"fidelity.n_modes": None, "fidelity.tolerance": 1e-3},
                                      {"fidelity.bandwidth_factor": 2.0}),
        "fidelity.prune": ({}, {"fidelity.prune": False}),
        # an empty table keeps a mode of each motion a tip output sees (three axes only)
        "fidelity.modes_per_motion": ({"outputs.tip_deflection": True},
                                      {"fidelity.modes_per_motion": {}}),
        "fidelity.modes_per_motion.<name>.bending": (
            {}, {"fidelity.modes_per_motion.rod.bending": 1}),
        "fidelity.modes_per_motion.<name>.<motion>": (
            {}, {"fidelity.modes_per_motion.rod.torsion": 2}),
        "controller": ({}, {"controller": {"lqr": LQR["controller.lqr"]}}),
        "controller.types": ({"controller.lqr": LQR["controller.lqr"]},
                             {"controller.types": ["pd", "lqr"]}),
        "controller.sample_rate": ({}, {"controller.sample_rate": 5.0}),
        "controller.pd.natural_frequency": ({}, {"controller.pd.natural_frequency": 0.12}),
        "controller.pd.bandwidth": ({}, {"controller.pd.natural_frequency": None,
                                         "controller.pd.bandwidth": 0.15}),
        "controller.pd.damping": ({}, {"controller.pd.damping": 0.8}),
        "controller.pd.roll_off": ({}, {"controller.pd.roll_off": 2.0}),
        "controller.pd.notch": ({}, {"controller.pd.notch": "first_mode"}),
        "controller.lqr.attitude_weight": (LQR, {"controller.lqr.attitude_weight": 10.0}),
        "controller.lqr.rate_weight": (LQR, {"controller.lqr.rate_weight": 5.0}),
        "controller.lqr.torque_weight": (LQR, {"controller.lqr.torque_weight": 2.0}),
        "controller.lqr.deflection_weight": ({**LQR, "outputs.tip_deflection": True},
                                             {"controller.lqr.deflection_weight": 1e4}),
        "controller.lqr.estimator_speed": (LQR, {"controller.lqr.estimator_speed": 5.0}),
        "controller.delay": ({}, {"controller.delay": 0.15}),     # the step at most 2 x it
        "controller.computation_delay": ({"controller.sample_rate": 4.0},   # 1 / step
                                         {"controller.computation_delay": True}),
        "controller.given": ({}, {"controller.given": given}),
        f"{M}.slew_angle": ({}, {f"{M}.slew_angle": 12.0}),
        f"{M}.slew_time": ({}, {f"{M}.slew_time": 25.0}),
        f"{M}.duration": ({}, {f"{M}.duration": 50.0}),
        f"{M}.step": ({}, {f"{M}.step": 0.2}),
        f"{M}.profile": ({}, FLOWN),
        f"{M}.feedforward": (FLOWN, {f"{M}.feedforward": True}),
        f"{M}.torque_limit": (FLOWN, {f"{M}.torque_limit": 0.25}),
        f"{M}.rate_limit": (FLOWN, {f"{M}.rate_limit": 0.8}),
        f"{M}.jerk_limit": ({**FLOWN, f"{M}.profile": "smooth", f"{M}.jerk_limit": 0.5},
                            {f"{M}.jerk_limit": 0.4}),
        f"{M}.shaper.kind": (SHAPED, {f"{M}.shaper.kind": "zv"}),
        f"{M}.shaper.modes": (SHAPED, {f"{M}.shaper.modes": 2}),
        f"{M}.shaper.base": (SHAPED, {f"{M}.shaper.base": "smooth"}),
        f"{M}.shaper.frequency_error": (SHAPED, {f"{M}.shaper.frequency_error": 0.1}),
        f"{M}.shaper.tolerance": ({**SHAPED, f"{M}.shaper.frequency_error": 0.1},
                                  {f"{M}.shaper.tolerance": 0.03}),
        f"{M}.slew_axis": ({}, {f"{M}.slew_axis": [1.0, 1.0, 0.0]}),
        f"{M}.disturbance.input": ({}, DISTURBANCE_3 if three else DISTURBANCE),
        f"{M}.disturbance.amplitude": (DISTURBANCE_3 if three else DISTURBANCE,
                                       {f"{M}.disturbance.amplitude": 0.02}),
        f"{M}.disturbance.start": (DISTURBANCE_3 if three else DISTURBANCE,
                                   {f"{M}.disturbance.start": 30.0}),
        f"{M}.disturbance.length": (DISTURBANCE_3 if three else DISTURBANCE,
                                    {f"{M}.disturbance.length": 4.0}),
        f"{M}.disturbance.axis": (DISTURBANCE_3 if three else DISTURBANCE,
                                  {f"{M}.disturbance.axis": "x"}),
        "outputs.tip_deflection": ({}, {"outputs.tip_deflection": True}),
        "outputs.root_loads": ({}, {"outputs.root_loads": True}),
        "outputs.exact_reference": ({}, {"outputs.exact_reference": True}),
        "export.fmu": ({k: v for k, v in FMU.items() if k != "export.fmu"},
                       {"export.fmu": True}),
        "export.systems": (FMU, {"export.systems": ["controller", "plant"]}),
        "export.reference_files": (FMU, {"export.reference_files": False}),
        "export.step": (FMU, {"export.step": 0.5}),
        "export.fmi_version": (FMU, {"export.fmi_version": "3.0"}),
        "export.sources_only": (FMU, {"export.sources_only": False}),
        "export.ssp": ({**FMU, "export.systems": ["plant", "controller"]},
                       {"export.ssp": True}),
        "report.plots": ({}, {"report.plots": ["poles"]}),
        "report.equivalence": ({}, {"report.equivalence": False}),
        "report.timeseries": ({}, {"report.timeseries": False}),
        "simulator.name": ({}, {"simulator.name": "basilisk"}),
        "simulator.sample_rate": ({"simulator.name": "basilisk"},
                                  {"simulator.sample_rate": 20.0}),
        "simulator.dt": ({"simulator.name": "basilisk"}, {"simulator.dt": 0.01}),
        "simulator.reaction_wheel.spin_inertia": (
            {"simulator.name": "basilisk"}, {"simulator.reaction_wheel.spin_inertia": 0.02}),
        "simulator.reaction_wheel.max_torque": (
            {"simulator.name": "basilisk", "simulator.reaction_wheel.spin_inertia": 0.02},
            {"simulator.reaction_wheel.max_torque": 0.05}),
        "simulator.reaction_wheel.max_speed": (
            {"simulator.name": "basilisk", "simulator.reaction_wheel.spin_inertia": 0.02},
            {"simulator.reaction_wheel.max_speed": 10.0}),
        "wheels.torque_limit": ({}, wheels),
        "wheels.momentum_limit": (wheels, {"wheels.momentum_limit": 3.0}),
        "wheels.spin_inertia": (wheels, {"wheels.spin_inertia": 0.03}),
        "wheels.viscous_friction": (wheels, {"wheels.viscous_friction": 1e-4}),
        "wheels.coulomb_friction": (wheels, {"wheels.coulomb_friction": 1e-3}),
        # limits that allow the slew (bang-coast-bang) and that the cycloid's PD loop exceeds
        "wheels.saturation": ({**wheels, "wheels.torque_limit": 0.12 if three else 0.25},
                              {"wheels.saturation": "clip"}),
        "wheels.spin_axes": (wheels, {"wheels.pyramid": None,
                                        "wheels.spin_axes": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0],
                                                             [0.0, 0.0, 1.0]]}),
        "wheels.pyramid.cant_angle": (wheels, {"wheels.pyramid.cant_angle": 45.0}),
        "wheels.pyramid.azimuth": (wheels, {"wheels.pyramid.azimuth": 10.0}),
        "sensors.attitude_density": (SENSORS, {"sensors.attitude_density": 2e-5}),
        "sensors.attitude_rms": (SENSORS, {"sensors.attitude_density": None,
                                           "sensors.attitude_rms": 1e-5,
                                           "sensors.attitude_rate": 4.0}),
        "sensors.attitude_rate": ({**SENSORS, "sensors.attitude_density": None,
                                   "sensors.attitude_rms": 1e-5, "sensors.attitude_rate": 4.0},
                                  {"sensors.attitude_rate": 8.0}),
        "sensors.angle_random_walk": (SENSORS, {"sensors.angle_random_walk": 1e-6}),
        "sensors.bias_instability": (SENSORS, {"sensors.bias_instability": 1e-6,
                                               "sensors.bias_correlation_time": 300.0}),
        "sensors.bias_correlation_time": ({**SENSORS, "sensors.bias_instability": 1e-6,
                                           "sensors.bias_correlation_time": 300.0},
                                          {"sensors.bias_correlation_time": 100.0}),
        "sensors.rpe_window": (SENSORS, {"sensors.rpe_window": 4.0}),
        "sensors.placement": (SENSORS, {"sensors.placement": "end"}),
        "sensors.probability": (SENSORS, {"sensors.probability": 0.95}),
        "limits.<name>": ({}, {"limits.states": 4}),
    }


# -- the documented keys -------------------------------------------------------------------------
def documented_keys() -> list[str]:
    """The keys of the scene reference (``appendages[i]`` as ``appendages[0]``)."""
    keys = []
    doc = scene_read.__doc__
    table = doc[doc.index("Keys (units"):doc.index("Ranges (")]
    for line in table.splitlines():
        found = re.match(r"``([a-z_]+(?:\[i\])?(?:\.[a-z_<>]+)*)``", line)
        if found:
            key = found.group(1).replace("[i]", "[0]")
            if key not in keys:
                keys.append(key)
    return keys


def _leaves(table, prefix=""):
    for key, value in table.items():
        path = f"{prefix}{key}"
        if isinstance(value, dict):
            yield path
            yield from _leaves(value, path + ".")
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            yield path
            for item in value[:1]:
                yield from _leaves(item, f"{path}[0].")
        else:
            yield path


def test_every_key_of_the_embedded_scenes_is_documented():
    documented = set(documented_keys())
    allowed = {re.sub(r"\.[a-z_]+$", "", k) for k in documented} | documented
    used = set()
    for name in example_scenes():
        raw = tomllib.loads(scene_path(name).read_text())
        used |= {re.sub(r"^limits\..*", "limits.<name>", k) for k in _leaves(raw)}
    # a truth chain has the keys of a chain (documented so)
    used = {k.replace(".truth_chain.", ".chain.") for k in used}
    # the key paths within a documented table (a stepped beam's segments, a tapered beam's
    # dimensions, a given controller's matrices) are documented with it
    inside = ("stepped_beam.segments[0].", "tapered_beam.root_dimensions.",
              "tapered_beam.tip_dimensions.", "controller.given.", "modal.frequencies_hz")
    missing = sorted(k for k in used - allowed if not any(p in k for p in inside))
    assert not missing, f"keys of the embedded scenes missing from the reference: {missing}"
    assert set(documented) <= set(_cases("planar")), sorted(set(documented) - set(_cases("planar")))


# -- the walk ------------------------------------------------------------------------------------
def _set(data: dict, path: str, value) -> None:
    parts = re.findall(r"[A-Za-z_<>]+|\[\d+\]", path)
    table = data
    for part in parts[:-1]:
        table = table[int(part[1:-1])] if part.startswith("[") else table.setdefault(part, {})
    last = parts[-1]
    if value is None:
        table.pop(last, None)
    else:
        table[last] = copy.deepcopy(value)


def _scene(kind: str, *edits: dict, modal_file: Path) -> dict:
    data = copy.deepcopy(BASES[kind])
    for edit in edits:
        for path, value in edit.items():
            if value == {"file": "MODAL_FILE"}:
                value = {"file": str(modal_file)}
            _set(data, path, value)
    return data


_VOLATILE = {"created", "version", "stats", "timing", "source", "files"}


def _fingerprint(data: dict, folder: Path | None) -> str:
    def clean(value):
        if isinstance(value, dict):
            return {k: clean(v) for k, v in value.items() if k not in _VOLATILE}
        if isinstance(value, list):
            return [clean(v) for v in value]
        return value
    text = json.dumps(clean(data), sort_keys=True, default=str)
    if folder is not None:
        files = sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())
        text += json.dumps(files) + (folder / "report.md").read_text().split("\n", 3)[-1]
    return text


_OUTCOMES: dict = {}


def _outcome(raw: dict, folder: Path | None):
    """The scene's result (a fingerprint) or the SceneError; a scene without files once (the
    cases share their contexts)."""
    if folder is None:
        key = json.dumps(raw, sort_keys=True, default=str)
        if key not in _OUTCOMES:
            _OUTCOMES[key] = _computed(raw, None)
        return _OUTCOMES[key]
    return _computed(raw, folder)


def _computed(raw: dict, folder: Path | None):
    try:
        scene = load_scene(raw, source="walk")
        if scene.simulator.name == "basilisk":
            pytest.importorskip("Basilisk", reason="simulator keys run Basilisk")
        result = run(scene)
        if folder is None:
            return _fingerprint(result.data, None)
        folder.mkdir()
        return _fingerprint(write_report(result, folder), folder)
    except SceneError as exc:
        return exc


@pytest.fixture(scope="module")
def modal_file(tmp_path_factory):
    from appendages import read_nastran, write_modal_data

    boom = read_nastran(DATA / "boom_modes.npz", root=1, units=("in", "slinch"),
                        mass_matrix=np.load(DATA / "boom_mass.npy"), tip=11, damping=0.01)
    path = tmp_path_factory.mktemp("modal") / "boom.toml"
    write_modal_data(boom, path)
    return path


#: The keys of the manoeuvre as flown: a three-axis scene flies them too (none is refused there).
FLOWN_KEYS = ("controller.delay", "controller.computation_delay", f"{M}.profile",
              f"{M}.feedforward", f"{M}.torque_limit", f"{M}.rate_limit", f"{M}.jerk_limit",
              f"{M}.shaper.", "wheels.", "sensors.")


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["planar", "three_axis"])
@pytest.mark.parametrize("key", documented_keys())
def test_a_documented_key_changes_the_result_or_is_refused_by_name(key, kind, tmp_path,
                                                                     modal_file):
    context, change = _cases(kind)[key]
    named = {re.sub(r"\.<name>$", "", n)
             for n in (key, key.rsplit(".", 1)[0], *change, *context)}
    files = key.split(".")[0] in ("export", "report", "title")
    before = _outcome(_scene(kind, context, modal_file=modal_file),
                      tmp_path / "before" if files else None)
    after = before if isinstance(before, SceneError) else _outcome(
        _scene(kind, context, change, modal_file=modal_file),
        tmp_path / "after" if files else None)
    if kind == "three_axis" and key.startswith(FLOWN_KEYS):
        assert not isinstance(before, SceneError), f"{key}: context refused: {before}"
        assert not isinstance(after, SceneError), f"{key} refused in a three-axis scene: {after}"
    if isinstance(after, SceneError):
        # refused (the key itself, or what it needs beside it): by name
        assert any(n in str(after) for n in named), f"{key} refused without its name: {after}"
        return
    assert after != before, f"{key} accepted and ignored in a {kind} scene"
