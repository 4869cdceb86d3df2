"""NASTRAN modal solutions as modal appendages (appendages.nastran), on a real solver's output.

Data: tests/data/nastran (README there: origin in pyNastran's repository, BSD licence). The
conversion runs everywhere on the .npz extracts; reading the OP2 files themselves needs pyNastran
and is skipped without it.

The independent check: the participation factors from the eigenvectors and the mass matrix
(G = Phi^T M D) against the solver's own internal forces of the root element in each mode.
The root holds the vibrating cantilever: the reaction R_i satisfies D^T R_i = -w_i^2 D^T M Phi_i,
and the root element's end-A forces are minus that reaction: w_i^2 G_i (unnormalised modes).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from appendages import nastran
from appendages.nastran import NastranError, NastranModes

from nastran_deck import lumped_mass_matrix

DATA = Path(__file__).parent.parent / "data" / "nastran"
SLINCH = 0.45359237 * 9.80665 / 0.0254  # kg per lbf s^2/in
INCH = 0.0254

@pytest.fixture(scope="module")
def beam_modes() -> NastranModes:
    return NastranModes.load(DATA / "beam_modes.npz")


@pytest.fixture(scope="module")
def boom(beam_modes):
    return nastran.modal_appendage(beam_modes, root=1, units=("in", "slinch"),
                                   mass_matrix=lumped_mass_matrix(), tip=11)


def _without_marker(modes: NastranModes) -> NastranModes:
    """beam_modes without grid 12, the deck's unconnected centre-of-gravity marker."""
    return dataclasses.replace(modes, node_ids=modes.node_ids[:11],
                               eigenvectors=modes.eigenvectors[:, :11],
                               positions=modes.positions[:11],
                               output_systems=modes.output_systems[:11])


# -- the real solution ------------------------------------------------------------------------------
def test_rebuilt_mass_matrix_gives_the_solvers_generalized_masses_and_gpwg(beam_modes):
    # The OP2 data are single precision: agreement to a few 1e-8 says the deck's mass matrix
    # is the one the solver used (a wrong split of the beam's torsional inertia would move the
    # torsion mode's generalized mass by several percent).
    M = lumped_mass_matrix()
    Phi = beam_modes.eigenvectors.reshape(10, 72).T
    own = np.einsum("ij,ij->j", Phi, M @ Phi)
    np.testing.assert_allclose(own, beam_modes.generalized_masses, rtol=2e-7)
    D = np.concatenate([nastran._rigid_motion(p) for p in beam_modes.positions])
    np.testing.assert_allclose(D.T @ M @ D, beam_modes.gpwg_mass, rtol=2e-7, atol=1e-9)


def test_participation_agrees_with_the_root_elements_forces(beam_modes, boom):
    # Independent of the mass matrix: the solver's internal forces of CBAR 1 at the root are
    # w^2 G of the unnormalised mode (module docstring), in the element axes (= basic: x along
    # the bar, plane 1 = x-y), with NASTRAN's sense of plane 2's moment opposite to +theta_y.
    with np.load(DATA / "beam_modes_root_element.npz") as data:
        forces, headers = data["forces"], list(data["headers"])
    column = {name: headers.index(name) for name in headers}
    from_element = np.column_stack([
        forces[:, column["axial"]], forces[:, column["shear1"]], forces[:, column["shear2"]],
        forces[:, column["torque"]], -forces[:, column["bending_moment_a2"]],
        forces[:, column["bending_moment_a1"]]])
    w = beam_modes.frequencies
    norm = np.sqrt(beam_modes.generalized_masses)
    # the appendage's G in model units (in, slinch), basic axes = the appendage's axes here
    to_model = np.sqrt(SLINCH) * np.array([1, 1, 1, INCH, INCH, INCH])
    G_model = boom.participation / to_model
    expected = (w**2 * norm)[:, None] * G_model
    # single-precision data: each mode to 2e-6 of its largest component
    scale = np.max(np.abs(expected), axis=1, keepdims=True)
    assert np.max(np.abs(from_element - expected) / scale) < 2e-6
    # the modes: 1-4, 7-10 bending in pairs, 5 torsion, 6 axial
    dominant = np.argmax(np.abs(boom.effective_mass_fractions[:, :4]), axis=1)
    assert list(dominant[[4, 5]]) == [3, 0]


def test_units_rigid_properties_and_frequencies(beam_modes, boom):
    assert boom.mass == pytest.approx(0.02610514 * SLINCH, rel=1e-6)  # GPWG's printed mass
    assert boom.center_of_mass == pytest.approx(5.496071 * INCH, rel=1e-6)
    assert boom.length == pytest.approx(10.0 * INCH, rel=1e-15)  # the farthest grid with mass
    np.testing.assert_allclose(boom.frequencies, beam_modes.frequencies, rtol=1e-15)
    assert boom.frequencies[0] == pytest.approx(2.869282e3, rel=1e-6)  # LAMA, printed in f06
    # the tip grid's motion: each mode's elastic deflection along y, z and twist, normalised
    assert boom.tip_motion.shape == (10, 3)
    phi_tip = beam_modes.eigenvectors[:, 10] / np.sqrt(beam_modes.generalized_masses)[:, None]
    # (normalised by the mass matrix's generalized masses, the file's to 6e-8: rtol 2e-7)
    np.testing.assert_allclose(boom.tip_motion[:, 0] * np.sqrt(SLINCH) / INCH, phi_tip[:, 1],
                               rtol=2e-7)


def test_spc_force_and_meffmass_routes_give_the_same_appendage(beam_modes, boom):
    # Two other sources of the participation factors, built from the real solution: the
    # reactions at the root (SPCFORCES: minus the root element's end-A forces) and MEFFMASS's
    # factors per unit generalized mass (about the GPWG point, the root here).
    modes = _without_marker(beam_modes)
    with np.load(DATA / "beam_modes_root_element.npz") as data:
        forces, headers = data["forces"], list(data["headers"])
    c = {name: headers.index(name) for name in headers}
    reaction = -np.column_stack([forces[:, c["axial"]], forces[:, c["shear1"]],
                                 forces[:, c["shear2"]], forces[:, c["torque"]],
                                 -forces[:, c["bending_moment_a2"]],
                                 forces[:, c["bending_moment_a1"]]])
    spc = dataclasses.replace(modes, spc_node_ids=np.array([1]), spc_forces=reaction[:, None, :])
    from_spc = nastran.modal_appendage(spc, root=1, units=("in", "slinch"))
    scale = np.max(np.abs(boom.participation), axis=1, keepdims=True)
    assert np.max(np.abs(from_spc.participation - boom.participation) / scale) < 2e-6
    np.testing.assert_allclose(from_spc.rigid_mass, boom.rigid_mass, rtol=2e-7,
                               atol=1e-12 * np.abs(boom.rigid_mass).max())
    to_model = np.sqrt(SLINCH) * np.array([1, 1, 1, INCH, INCH, INCH])
    gamma = boom.participation / to_model / np.sqrt(modes.generalized_masses)[:, None]
    meff = dataclasses.replace(modes, participation_factors=gamma)
    from_meff = nastran.modal_appendage(meff, root=1, units=("in", "slinch"))
    np.testing.assert_allclose(from_meff.participation, boom.participation, rtol=1e-12,
                               atol=1e-12 * scale.max())


def test_axes_turn_the_data(beam_modes, boom):
    # The same boom described in appendage axes turned 90 degrees about x: y -> z, z -> -y.
    A = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    turned = nastran.modal_appendage(beam_modes, root=1, units=("in", "slinch"),
                                     mass_matrix=lumped_mass_matrix(), axes=A)
    np.testing.assert_allclose(turned.participation[:, [0, 2, 1, 3, 5, 4]]
                               * [1, -1, 1, 1, -1, 1], boom.participation, rtol=1e-12,
                               atol=1e-14)


def test_on_a_heavy_hub_the_first_coupled_modes_are_the_cantilever_ones(boom):
    from spacecraft import Hub, Mount, Spacecraft

    spacecraft = Spacecraft(Hub(1e8, 1e8 * np.eye(3)),
                            [Mount(boom, (0.1, 0.0, 0.0), orientation=np.eye(3))])
    coupled = spacecraft.natural_frequencies(4, exact=False)
    np.testing.assert_allclose(coupled, boom.frequencies[:4], rtol=1e-7)


# -- refused, by name ------------------------------------------------------------------------------
def test_root_that_is_not_clamped(beam_modes):
    with pytest.raises(NastranError, match=r"root grid 2 moves in mode 1 .*not clamped"):
        nastran.modal_appendage(beam_modes, root=2, units=("in", "slinch"),
                                mass_matrix=lumped_mass_matrix())
    with pytest.raises(NastranError, match=r"root must be a grid id.*got 99"):
        nastran.modal_appendage(beam_modes, root=99, units=("in", "slinch"))


def test_a_solution_clamped_at_several_grids():
    modes = NastranModes.load(DATA / "mode_solid_shell_bar.npz")
    with pytest.raises(NastranError, match=r"hold grid\(s\) \[23, 24, 25\] fixed besides the "
                                           r"root grid 22.*interface alone"):
        nastran.modal_appendage(modes, root=22, units=("m", "kg"))


def test_held_grid_with_and_without_a_mass_matrix(beam_modes):
    with pytest.raises(NastranError, match=r"grid\(s\) \[12\].*give mass_matrix="):
        nastran.modal_appendage(beam_modes, root=1, units=("in", "slinch"))
    M = lumped_mass_matrix()
    M[66, 66] = 1e-3  # now grid 12 carries mass but is held: clamped elsewhere
    with pytest.raises(NastranError, match=r"grid\(s\) \[12\] fixed besides the root"):
        nastran.modal_appendage(beam_modes, root=1, units=("in", "slinch"), mass_matrix=M)


def test_no_participation_source_and_wrong_mass_matrix(beam_modes):
    with pytest.raises(NastranError, match=r"no participation factors: give mass_matrix="):
        nastran.modal_appendage(_without_marker(beam_modes), root=1, units=("in", "slinch"))
    M = lumped_mass_matrix()
    order = (np.arange(0, 72, 6)[:, None] + [3, 1, 2, 0, 4, 5]).ravel()  # T1, R1 swapped
    with pytest.raises(NastranError, match=r"generalized mass.*not the solution's mass matrix"):
        nastran.modal_appendage(beam_modes, root=1, units=("in", "slinch"),
                                mass_matrix=M[np.ix_(order, order)])
    with pytest.raises(ValueError, match=r"mass_matrix must be 72 x 72"):
        nastran.modal_appendage(beam_modes, root=1, units=("in", "slinch"),
                                mass_matrix=np.eye(6))


def test_rigid_body_modes_other_analyses_and_coordinate_systems(beam_modes):
    free = dataclasses.replace(beam_modes, frequencies=np.concatenate(
        [[0.0], beam_modes.frequencies[1:]]))
    with pytest.raises(NastranError, match=r"rigid-body modes.*not held at the root"):
        nastran.modal_appendage(free, root=1, units=("in", "slinch"))
    buckling = dataclasses.replace(beam_modes, analysis_code=8)
    with pytest.raises(NastranError, match=r"not of a normal-modes solution"):
        nastran.modal_appendage(buckling, root=1, units=("in", "slinch"))
    systems = beam_modes.output_systems.copy()
    systems[4] = 3
    local = dataclasses.replace(beam_modes, output_systems=systems)
    with pytest.raises(NastranError, match=r"grids \[5\].*CD != 0"):
        nastran.modal_appendage(local, root=1, units=("in", "slinch"))


def test_units_are_required_and_checked(beam_modes):
    with pytest.raises(ValueError, match=r"length unit must be one of"):
        nastran.modal_appendage(beam_modes, root=1, units=("inch", "slinch"))
    with pytest.raises(TypeError, match=r"units must be \(length, mass\)"):
        nastran.modal_appendage(beam_modes, root=1, units="SI")


def test_npz_without_modes(tmp_path):
    path = tmp_path / "empty.npz"
    np.savez(path, format=np.array("flexsat-nastran-modes-1"), source=np.array("x.op2"),
             wtmass=np.array(1.0), analysis_code=np.array(2))
    with pytest.raises(NastranError, match=r"no modal solution"):
        nastran.read_nastran(path, root=1, units=("m", "kg"))


# -- pyNastran itself --------------------------------------------------------------------------------
def _pynastran_works() -> bool:
    try:
        nastran._import_read_op2()
    except ImportError:
        return False
    return True


needs_pynastran = pytest.mark.skipif(not _pynastran_works(),
                                     reason="pyNastran missing or not importable")


@needs_pynastran
def test_extracts_equal_a_fresh_read():
    for name in ("beam_modes", "mode_solid_shell_bar"):
        fresh = nastran.read_op2(DATA / f"{name}.op2")
        stored = NastranModes.load(DATA / f"{name}.npz")
        for field in NastranModes._ARRAYS:
            a, b = getattr(fresh, field), getattr(stored, field)
            assert (a is None) == (b is None), field
            if a is not None:
                np.testing.assert_array_equal(a, b)


@needs_pynastran
def test_op2_reader_end_to_end_and_a_file_without_modes():
    boom = nastran.read_nastran(DATA / "beam_modes.op2", root=1, units=("in", "slinch"),
                                mass_matrix=lumped_mass_matrix(), damping=0.003)
    assert boom.n_modes == 10 and np.all(boom.damping_ratios == 0.003)
    with pytest.raises(NastranError, match=r"no modal solution.*'displacements', "
                                           r"'spc_forces'"):
        nastran.read_op2(DATA / "cantilever_2014.1.op2")
    with pytest.raises(NastranError, match=r"not readable as a NASTRAN OP2 file"):
        nastran.read_op2(DATA / "beam_modes.dat")


def test_a_missing_pynastran_is_named(monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_pynastran(name, *args, **kwargs):
        if name.startswith("pyNastran"):
            raise ModuleNotFoundError("No module named 'pyNastran'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_pynastran)
    with pytest.raises(ImportError, match=r"needs pyNastran \(pip install \"flexsat\[nastran\]\""):
        nastran.read_nastran(DATA / "beam_modes.op2", root=1, units=("in", "slinch"))


def test_planar_views_of_twin_modes(boom):
    # The round rod's bending modes come in equal-frequency twins that the solver mixes
    # (mode 1 moves along y and z). A plane's view turns each twin so that one mode carries the
    # plane: 4 bending modes per plane, no spurious pole-zero pair at a cantilever frequency,
    # and W unchanged (the view's W is the inverse of D6's block of the plane).
    for plane, index in (("xy", [1, 5]), ("xz", [2, 4])):
        view = boom.planar_view(plane)
        np.testing.assert_array_equal(view.frequencies, boom.frequencies[[0, 2, 6, 8]])
        poles, zeros = view.poles(), view.zeros(1)
        assert poles.size == 4 and zeros.size == 4
        assert np.all(zeros < poles)  # pinned below free, interlaced
        assert np.all(poles[:-1] < zeros[1:])
        s = np.array([500.0j, 3e3 + 2e4j])
        block = np.linalg.inv(boom.dynamic_stiffness6(s)[:, index][:, :, index])
        flip = np.diag([1.0, 1.0 if plane == "xy" else -1.0])
        np.testing.assert_allclose(view.W(s), flip @ block @ flip, rtol=1e-9)
    # torsion and axial motion, each with the other root motions held: their first clamped
    # frequencies are modes 5 and 6 (found from D6 by appendages.fit3d.motion_frequencies)
    from appendages.fit3d import motion_frequencies

    scale = boom.planar_view("xy").poles()[0]
    torsion = motion_frequencies(boom, 3, scale, 1.0)
    axial = motion_frequencies(boom, 0, scale, 1.0)
    assert torsion.clamped == pytest.approx(boom.frequencies[4], rel=1e-13)
    assert axial.clamped == pytest.approx(boom.frequencies[5], rel=1e-13)
    # free torsion: the tip's CONM2 inertia, far out on a light rod, sets its frequency high;
    # the root's torsional dynamic mass vanishes there (M(s) of the module docstring)
    assert torsion.free > 10.0 * torsion.clamped
    assert abs(boom.dynamic_mass(1j * torsion.free)[3, 3]) < 1e-10 * boom.rigid_mass[3, 3]
