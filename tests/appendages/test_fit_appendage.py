"""Equivalent chains of any appendage that gives W (appendages.equivalence, fitting, fit3d).

References: the planar FE boom of tests/support/fe_planar.py (stepped, tip body), the 3-D FE beam of
tests/support/fe3d.py, pyNastran's beam_modes solution (tests/data/nastran), each as a ModalAppendage;
the uniform beam's own fit for comparison.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

import fe3d
import fe_planar
from nastran_deck import lumped_mass_matrix
from appendages import Beam, FitWarning, ModalAppendage, fit_chain, fit_chain_3d, nastran
from appendages.equivalence import criterion, fit_targets, spectral_errors
from appendages.fit3d import motion_frequencies, rod_chain_frequencies
from appendages.nastran import NastranModes

SEGMENTS = [(3.0, 2.0e4, 4.0, 12), (4.0, 6.0e3, 2.0, 16)]
TIP = (5.0, 0.8, 0.3)


@pytest.fixture(scope="module")
def boom() -> ModalAppendage:
    """The stepped boom with its tip body, 30 of its cantilever modes, damped 0.5 %."""
    w, G, rigid, _ = fe_planar.cantilever_modal_data(SEGMENTS, TIP)
    return ModalAppendage(w[:30], G[:30], rigid, damping=0.005, length=7.0)


def _largest(errors: dict) -> dict:
    return {key: float(np.max(np.abs(value))) for key, value in errors.items()}


@pytest.mark.slow
def test_chain_keeps_mass_first_moment_and_inertia_tip_included(boom):
    for n in (3, 6):
        chain = fit_chain(boom, n)
        assert chain.mass == pytest.approx(25.0, rel=1e-13)
        assert chain.center_of_mass == pytest.approx(boom.center_of_mass, rel=1e-12)
        assert chain.inertia == pytest.approx(boom.inertia, rel=1e-12)
        assert chain.length == pytest.approx(7.0, rel=1e-14)


@pytest.mark.slow
def test_accuracy_on_the_same_poles_and_zeros_as_the_uniform_beam(boom):
    # The fit's criterion on the boom's own poles and zeros: the poles to 1e-4 (weighted), the
    # zeros to a few percent with 3 bodies, better with more (measured: 1.7 %, 1.3 %, 1.0 %,
    # 0.57 % largest zero error at 3, 4, 6, 10 bodies), as for the uniform beam (1.7 % at 3).
    largest = []
    for n in (3, 6):
        errors = _largest(spectral_errors(boom, fit_chain(boom, n)))
        assert errors["poles"] < 2e-4
        largest.append(max(errors["W1"], errors["W2"], errors["W4"]))
    assert largest[0] < 0.03
    assert largest[1] < 0.75 * largest[0]
    result = criterion(boom, fit_chain(boom, 3))
    assert result.relative_differences["m"] == pytest.approx(0.0, abs=1e-13)
    assert abs(result.relative_differences["w1"]) < 2e-4


@pytest.mark.slow
def test_modal_data_of_a_uniform_beam_fit_like_the_beam():
    # The uniform beam's cantilever modes as modal data: the same targets to the modes'
    # truncation error (60 modes: 1e-7 on the first poles and zeros), the same criterion, so
    # the fits' errors agree (the chains themselves may differ along the fit's valley).
    beam = Beam(2.0, 30.0, 1.5)
    L = beam.length
    rigid = beam.linear_density * np.array([[L, L**2 / 2.0], [L**2 / 2.0, L**3 / 3.0]])
    data = ModalAppendage(beam.cantilever_frequencies(60), beam.modal_participation(60), rigid,
                          length=L)
    targets = fit_targets(data, 4)["targets"]
    exact = np.vstack([beam.natural_frequencies(3)] + [beam.zeros(r, 3) for r in (1, 2, 4)])
    np.testing.assert_allclose(targets, exact, rtol=1e-6)
    ours = _largest(spectral_errors(beam, fit_chain(data, 4)))
    theirs = _largest(spectral_errors(beam, fit_chain(beam, 4)))
    for key in ours:
        assert ours[key] == pytest.approx(theirs[key], rel=0.05, abs=2e-5)


def test_damping_of_the_first_mode(boom):
    # Stiffness-proportional hinge damping C = (2 zeta/w) K with w the boom's first cantilever
    # frequency, whose ratio the data give: every mode of the chain, free or clamped, gets
    # zeta times its frequency over w; clamped at its root (on a very heavy hub), its first
    # mode has the entered ratio up to the chain's clamped frequency over the boom's.
    chain = fit_chain(boom, 3)
    w_c = boom.frequencies[0]
    np.testing.assert_allclose(chain.hinge_dampings, 2.0 * 0.005 * chain.hinge_stiffnesses / w_c,
                               rtol=1e-14)
    rm = chain.root_model()
    inner = slice(2, None)
    lam, V = scipy.linalg.eigh(rm.stiffness[inner, inner], rm.mass[inner, inner])
    clamped = np.sqrt(lam[0])
    modal_damping = V[:, 0] @ rm.damping[inner, inner] @ V[:, 0]
    assert modal_damping / (2.0 * clamped) == pytest.approx(0.005 * clamped / w_c, rel=1e-10)
    assert abs(clamped / w_c - 1.0) < 0.05


def test_bad_fits_of_modal_data(boom):
    few = boom.truncated(2)
    with pytest.raises(ValueError, match=r"needs the appendage's first 4 natural frequencies.*"
                                         r"has 2"):
        fit_chain(few, 5)
    w, G, rigid = boom.frequencies, boom.participation, boom.rigid_mass
    with pytest.warns(UserWarning, match="outside"):
        short = ModalAppendage(w, G, rigid, length=3.0)  # the centre of mass is at 3.78 m
    with pytest.raises(ValueError, match=r"centre of mass lies at 3.78 m from the root, outside"):
        fit_chain(short, 3)
    tight = ModalAppendage(w, G, rigid, length=4.0)
    with pytest.raises(ValueError, match=r"exceeds m c \(L - c\).*is length the appendage's "
                                         r"extent"):
        fit_chain(tight, 3)
    with pytest.raises(ValueError, match=r"match='frequencies'.*needs a uniform Beam"):
        fit_chain(boom, 3, match="frequencies")
    with pytest.raises(ValueError, match=r"no length \[m\]"):
        fit_chain(ModalAppendage(w, G, rigid), 3)


# -- three axes ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def nastran_boom() -> ModalAppendage:
    modes = NastranModes.load(fe_data("beam_modes.npz"))
    return nastran.modal_appendage(modes, root=1, units=("in", "slinch"),
                                   mass_matrix=lumped_mass_matrix(), damping=0.004)


def fe_data(name):
    from pathlib import Path

    return Path(__file__).parent.parent / "data" / "nastran" / name


def test_three_axis_chain_of_nastran_data(nastran_boom):
    # A round rod with a tip mass: its planes are equal (each its twin modes), so both planes'
    # chains have the same errors; torsion and axial motion match their first pole exactly,
    # the axial motion its first zero too (its own pole/zero ratio, 2.28); the torsion's ratio
    # (31: the tip mass's moment on a short rod) is beyond three bodies, which is warned.
    with pytest.warns(FitWarning, match="torsion chain of 3 bodies cannot reach"):
        chain = fit_chain_3d(nastran_boom, 3)
    xy = _largest(spectral_errors(nastran_boom.planar_view("xy"), chain.planar_view("xy")))
    xz = _largest(spectral_errors(nastran_boom.planar_view("xz"), chain.planar_view("xz")))
    for key in xy:
        assert xz[key] == pytest.approx(xy[key], rel=1e-3, abs=1e-6)
    assert xy["poles"] < 2e-4 and max(xy["W1"], xy["W2"], xy["W4"]) < 0.05
    assert chain.mass == pytest.approx(nastran_boom.mass, rel=1e-12)
    np.testing.assert_allclose(chain.inertia_tensor, nastran_boom.inertia_tensor, rtol=1e-9)
    for motion, inertias, springs in (("torsion", chain.torsional_inertias,
                                       chain.torsion_stiffnesses),
                                      ("axial", chain.masses, chain.axial_stiffnesses)):
        rod = motion_frequencies(nastran_boom, 3 if motion == "torsion" else 0,
                                 nastran_boom.planar_view("xy").poles()[0], 1.0)
        pole, zero = rod_chain_frequencies(inertias, springs)
        assert pole == pytest.approx(rod.free, rel=1e-10)
        if motion == "axial":
            assert zero == pytest.approx(rod.clamped, rel=1e-10)


@pytest.mark.slow
def test_three_axis_chain_with_unequal_planes():
    # A 3-D FE beam with EI_y = 0.625 EI_z and a tip mass on its axis: the x-z plane is not a
    # scaled copy of the x-y plane once the tip body's inertias differ (0.8 about y, 0.6 about
    # z), so its inertias and hinges are refitted on the x-y bodies; it reaches the x-y plane's
    # accuracy.
    L, EIz, EIy, GJ, rhoIp, EA, rhoA, ne = 6.0, 4.0e4, 2.5e4, 1.5e4, 0.05, 3.0e7, 3.0, 8
    K, M = (A.toarray() for A in fe3d.beam_matrices(L, EIz, EIy, GJ, rhoIp, EA, rhoA, ne,
                                                    rod_order=1, bending_order=3))
    last = np.arange(6 * ne, 6 * ne + 6)
    M[np.ix_(last, last)] += np.diag([4.0, 4.0, 4.0, 0.5, 0.8, 0.6])
    D = np.zeros((K.shape[0], 6))
    for i in range(ne + 1):
        D[6 * i:6 * i + 6] = fe3d.mount_transformation([L * i / ne, 0.0, 0.0], np.eye(3))
    inner = np.arange(6, K.shape[0])
    lam, Phi = scipy.linalg.eigh(K[np.ix_(inner, inner)], M[np.ix_(inner, inner)])
    data = ModalAppendage(np.sqrt(lam), Phi.T @ (M @ D)[inner], D.T @ M @ D, length=L,
                          damping=0.002)
    chain = fit_chain_3d(data, 4)
    xy = _largest(spectral_errors(data.planar_view("xy"), chain.planar_view("xy")))
    xz = _largest(spectral_errors(data.planar_view("xz"), chain.planar_view("xz")))
    assert xz["poles"] < 3e-4
    assert max(xz["W1"], xz["W2"], xz["W4"]) < 1.5 * max(xy["W1"], xy["W2"], xy["W4"]) + 0.005
    assert chain.planar_view("xz").inertia == pytest.approx(data.planar_view("xz").inertia,
                                                            rel=1e-9)
    assert chain.hinge_dampings_y is not None
