"""The embedded scene real_appendages: a hub, two stepped wings with tip bodies and a boom given as
a NASTRAN normal-modes solution, through the whole design loop (planar).

Chains are fitted to all three appendages, the controllers tuned on them and judged on the
truth model (the wings' truncations, the boom's modes: all of them); the exact reference goes
through each appendage's W (the wings' exact, the boom's own: FE-exact). Independent check: a
planar finite-element model of the same spacecraft (tests/support/fe_planar.py: Hermite elements per
segment, the tip bodies at the last nodes; the boom as its modes' Craig-Bampton realisation, the
data themselves) converges to the exact coupled frequencies.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import scipy.sparse

import fe3d
import fe_planar
from spacecraft import load_scene, output_folder, run, write_report


def fe_coupled_frequencies(scene, boom_root_model, boom_mass: float, n_elements: int,
                           n: int = 8) -> np.ndarray:
    """The first n elastic frequencies [rad/s] of the scene's spacecraft as a planar FE model:
    the hub's (X, Y, theta); each wing a stepped Hermite boom with its tip body, root motion
    ``v = n . (X - theta y_p, Y + theta x_p)``, ``theta_root = theta`` and its mass moving
    rigidly along its axis e (inextensible); the boom's Craig-Bampton model likewise."""
    blocks = []
    for a in scene.appendages:
        if a.beam is not None:
            segments = []
            for s in a.beam.segments:
                d = dict(s.dimensions)
                segments.append((s.length, s.youngs_modulus * d["width"] * d["thickness"]**3 / 12,
                                 s.density * d["width"] * d["thickness"], n_elements))
            t = a.beam.tip
            K, M = fe_planar.boom_matrices(segments, (t.mass, t.inertia, t.offset))
            mass = sum(length * rho_a for length, _, rho_a, _ in segments) + t.mass
        else:
            K, M, mass = boom_root_model.stiffness, boom_root_model.mass, boom_mass
        blocks.append((K, M, a.position, a.direction, mass))
    size = 3 + sum(K.shape[0] - 2 for K, *_ in blocks)
    K_all, M_all = np.zeros((size, size)), np.zeros((size, size))
    M_all[0, 0] = M_all[1, 1] = scene.hub.mass
    M_all[2, 2] = scene.hub.inertia
    offset = 3
    for K, M, (x_p, y_p), angle, mass in blocks:
        e = np.array([math.cos(angle), math.sin(angle)])
        normal = np.array([-math.sin(angle), math.cos(angle)])
        point = np.array([[1.0, 0.0, -y_p], [0.0, 1.0, x_p]])  # root point from (X, Y, theta)
        T = np.zeros((K.shape[0], size))
        T[0, :3] = normal @ point
        T[1, 2] = 1.0
        T[2:, offset:offset + K.shape[0] - 2] = np.eye(K.shape[0] - 2)
        K_all += T.T @ K @ T
        M_all += T.T @ M @ T
        g = np.zeros(size)
        g[:3] = e @ point
        M_all += mass * np.outer(g, g)
        offset += K.shape[0] - 2
    # fe3d's subspace iteration removes the three rigid modes exactly and keeps the low modes'
    # digits (a dense generalized eigensolver loses eps (w_max/w_1)**2 of them: 1e-6 at 32
    # elements per segment)
    return fe3d.natural_frequencies(scipy.sparse.csr_array(K_all),
                                    scipy.sparse.csr_array(M_all), n, n_rigid=3)


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    folder = tmp_path_factory.mktemp("real") / "out"
    result = run(load_scene("real_appendages",
                            overrides={"export.fmu": False, "report.plots": False}))
    with output_folder(folder) as out:
        write_report(result, out)
    return result, folder


@pytest.mark.slow
def test_chains_are_fitted_to_all_three_and_the_loops_verified_on_the_truth(result):
    result, _ = result
    scene = result.scene
    assert [a.truth for a in scene.appendages] == ["beam", "beam", "modal"]
    for a in scene.appendages:
        chain = result.models[a.name]["fits"]["poles-and-zeros"]
        structure = result.models[a.name]["truth"]
        # a chain keeps its appendage's mass and inertia (exactly, by construction)
        assert chain.mass == pytest.approx(structure.mass, rel=1e-12)
        assert chain.inertia == pytest.approx(structure.inertia, rel=1e-10)
    # the boom's truth is its modal data, all the modes of its x-y plane
    assert result.models["boom"]["truth"].n_modes == 4
    for row in result.data["closed_loops"]:
        assert row["verdict"]["stable"] and row["exact_verdict"]["stable"]
        assert row["status"]["truth"]["status"] == "settles"
    assert not [w for w in result.data["warnings"] if "tip motion" in w]


@pytest.mark.slow
def test_the_exact_reference_agrees_with_an_independent_finite_element_model(result):
    """Hermite elements converge like h**4 in frequency, every mode: measured 16x from 8 to
    16 elements per segment (to 7.8e-5 largest, 6.4e-8 on the first two), and on to 1.8e-10
    on the first at 64: the exact frequencies are located far below these differences."""
    result, _ = result
    scene = result.scene
    exact = np.array(result.data["exact"]["coupled_frequencies"])
    boom = result.models["boom"]["truth"]
    errors = {n: np.abs(fe_coupled_frequencies(scene, boom.root_model(), boom.mass, n)
                        / exact - 1.0) for n in (8, 16)}
    assert np.all(errors[16] < 1e-4)
    assert np.all(errors[16][:2] < 3e-7)
    # h**4: a factor 16 per halving
    assert np.all(errors[16] < errors[8] / 10.0)


@pytest.mark.slow
def test_the_report_gives_the_modal_table_and_the_tables_of_each_appendage(result):
    result, folder = result
    modes = result.data["truth"]["modes"]
    # the wings' modes (the truth's one mode per wing and those the tip deflections need) and
    # the boom's four
    tip = result.data["fidelity"]["choice"].get("tip") or {"floors": {}}
    per_wing = 1 + tip["floors"].get("wing_px", {}).get("bending", 0)
    assert len(modes) == 2 * per_wing + 4
    boom = [m for m in modes if m["strain_energy"]["boom"] > 0.99]
    assert len(boom) == 4
    assert all(m["strain_energy"]["boom"] < 0.01 for m in modes if m not in boom)
    # the boom's coupled modes have the damping entered for its cantilever modes (a stiff boom
    # on a heavy hub: to 1e-2 relative)
    for m in boom:
        assert m["damping_ratio"] == pytest.approx(0.003, rel=1e-2)
    assert modes[0]["torque_participation"][0] < 1e-12  # the wings' symmetric mode
    tables = {t["appendage"]: t for t in result.data["equivalence"]}
    assert set(tables) == {"wing_px", "boom"}   # the two wings are one structure
    assert tables["boom"]["reference"] == "modal data (FE-exact)"
    assert tables["wing_px"]["reference"] == "stepped beam with tip body (exact)"
    report = (folder / "report.md").read_text()
    assert "### Modes of the open-loop spacecraft (truth model)" in report
    assert ("Damping ratios entered: wing_px: 0.005 (its cantilever modes); wing_mx: 0.005 (its "
            "cantilever modes); boom: 0.003 (its cantilever modes).") in report
    assert "NASTRAN solution " in report and "4 cantilever modes" in report
    back = json.loads((folder / "results.json").read_text())
    k = modes.index(boom[0])
    assert back["truth"]["modes"][k]["frequency_hz"] == pytest.approx(
        modes[k]["frequency"] / (2 * math.pi), rel=1e-15)


@pytest.mark.slow
def test_the_scene_reads_without_warnings():
    scene = load_scene("real_appendages")
    assert scene.input_warnings == ()
    boom = scene.appendages[2].modal
    assert boom.source == "nastran" and boom.has_tip_motion and boom.units == ("in", "slinch")
