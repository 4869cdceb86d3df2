"""RFEM and Molenaar superelement chains of stepped beams and beams with tip bodies."""

import numpy as np
import pytest

from appendages import Beam, HingedChain, ModalAppendage, SteppedBeam, TipBody

ARRAYS = ("lengths", "masses", "inertias", "com_offsets", "hinge_stiffnesses", "hinge_dampings",
          "inertias_y", "hinge_stiffnesses_y", "hinge_dampings_y", "torsional_inertias",
          "torsion_stiffnesses", "torsion_dampings", "axial_stiffnesses", "axial_dampings")

TIP3 = TipBody(3.0, np.diag([0.1, 0.2, 0.3]), 0.2)


def tube(length, damping_ratio=0.005):
    return Beam.tube(length, 0.1, 0.002, 2700.0, 70e9, damping_ratio=damping_ratio)


def wing(tip=TipBody(5.0, 0.5, 0.1)):
    """A 1 m yoke and a 6 m panel (the shape of a solar-array wing) with a tip body."""
    return SteppedBeam([Beam.rectangular(1.0, 0.05, 0.02, 1600.0, 1.2e11),
                        Beam.rectangular(6.0, 1.0, 0.02, 200.0, 2e10)], tip=tip)


def assert_same_chain(a, b, rtol):
    for name in ARRAYS:
        x, y = getattr(a, name, None), getattr(b, name, None)
        assert (x is None) == (y is None), name
        if x is not None:
            np.testing.assert_allclose(y, x, rtol=rtol, atol=0, err_msg=name)


@pytest.mark.slow
@pytest.mark.parametrize("n_bodies", [2, 5, 8])
def test_rfem_of_a_stepped_beam_of_equal_segments_is_the_uniform_beams(n_bodies):
    # One segment, or the same tube as two equal halves, with the same three-axis tip body:
    # the uniform beam's RFEM chain in every motion. The pieces are integrated from the parts
    # of the segments (sums of a few terms: 1e-15); the hinge dampings divide by the first
    # cantilever frequency, the uniform beam's closed form against the stepped beam's count
    # located to ~1e-14 (appendages.assembly): rtol 1e-12.
    uniform = Beam.tube(4.0, 0.1, 0.002, 2700.0, 70e9, damping_ratio=0.005, tip=TIP3)
    reference = HingedChain.rfem(uniform, n_bodies)
    assert reference.torsional_inertias is not None and reference.torsion_dampings is not None
    for segments in ([tube(4.0)], [tube(2.0), tube(2.0)]):
        assert_same_chain(reference, HingedChain.rfem(SteppedBeam(segments, tip=TIP3),
                                                      n_bodies), rtol=1e-12)


@pytest.mark.parametrize("n", [2, 4])
def test_superelements_of_a_stepped_beam_of_equal_segments_are_the_uniform_beams(n):
    uniform = Beam.tube(4.0, 0.1, 0.002, 2700.0, 70e9, damping_ratio=0.005,
                        tip=TipBody(3.0, 0.3, 0.2))
    stepped = SteppedBeam([tube(2.0), tube(2.0)], tip=uniform.tip)
    assert_same_chain(HingedChain.superelements(uniform, n),
                      HingedChain.superelements(stepped, n), rtol=1e-12)


@pytest.mark.slow
def test_rfem_and_superelements_converge_to_a_stepped_beam_with_a_tip_body():
    # The chains' first three frequencies against the stepped beam's exact free-free ones
    # (Wittrick-Williams, ~1e-14). Superelements are uniform pieces (the step at 1 m on a
    # multiple of 7/n m) and converge like l^4 (measured 16-19x per doubling); RFEM hinges
    # integrate the flexibility across the step and converge like H^2 on average, unevenly as
    # the step moves along the hinges' arcs (measured 1.4-17x per doubling from 8 to 128
    # bodies, 2.5e-6 to 3.9e-5 at 128).
    beam = wing()
    exact = beam.natural_frequencies(3)

    def error(chain):
        return np.abs(chain.poles()[:3] / exact - 1.0).max()

    rfem = [error(HingedChain.rfem(beam, n)) for n in (16, 128)]
    assert rfem[1] < 1e-4 and rfem[1] < rfem[0] / 10.0, rfem
    superelements = [error(HingedChain.superelements(beam, n)) for n in (14, 28)]
    assert superelements[1] < 3e-6 and superelements[1] < superelements[0] / 8.0, superelements
    # both carry the whole mass, first moment and inertia (tip body included)
    for chain in (HingedChain.rfem(beam, 9), HingedChain.superelements(beam, 7)):
        assert chain.mass == pytest.approx(beam.mass, rel=1e-14)
        assert chain.center_of_mass == pytest.approx(beam.center_of_mass, rel=1e-14)
        assert chain.inertia == pytest.approx(beam.inertia, rel=1e-13)


@pytest.mark.slow
def test_three_axis_rfem_of_a_stepped_beam_converges_to_its_W6():
    # Every motion (two bending planes, torsion, axial) of a stepped tube with a tip body:
    # the relative error of W6 at four points falls 4x per doubling (H^2; measured 4.0-4.5
    # from 16 to 64 bodies).
    beam = SteppedBeam([Beam.tube(1.0, 0.08, 0.003, 1600.0, 1e11),
                        Beam.tube(3.0, 0.05, 0.001, 1600.0, 1e11)],
                       tip=TipBody(2.0, np.diag([0.3, 0.2, 0.5]), 0.1))
    w1 = beam.natural_frequencies6(1)[0]
    s = (0.05 + 1j * np.array([0.3, 0.7, 1.5, 3.1])) * w1
    exact = beam.W6(s)
    errors = [(np.abs(HingedChain.rfem(beam, n).W6(s) - exact).max(axis=(1, 2))
               / np.abs(exact).max(axis=(1, 2))).max() for n in (16, 32, 64)]
    assert errors[1] < errors[0] / 3.5 and errors[2] < errors[1] / 3.5, errors


@pytest.mark.slow
def test_rod_dampings_of_a_tip_loaded_beam_are_set_at_its_loaded_first_mode():
    # The torsion springs' damping 2 zeta c / w_1 with w_1 the first cantilever torsion
    # frequency of the rod carrying the tip body's moment about the axis (here 4.0x below the
    # bare rod's): the chain's first clamped torsion mode then has the entered ratio (to the
    # chain's discretisation error in that frequency).
    beam = Beam.tube(4.0, 0.1, 0.002, 2700.0, 70e9, damping_ratio=0.005, tip=TIP3)
    chain = HingedChain.rfem(beam, 6)
    w1 = beam.rod_cantilever_frequencies("torsion", 1)[0]
    assert w1 < beam.torsion_rod().cantilever_frequencies(1)[0] / 2.0
    np.testing.assert_allclose(chain.torsion_dampings,
                               2.0 * 0.005 * chain.torsion_stiffnesses / w1, rtol=1e-14)


def test_superelements_across_a_step_and_modal_data_are_refused_by_name():
    with pytest.raises(ValueError, match=r"superelements\(beam, n=3\).*multiple of L/n = 2\.33333"
                                         r" m; the steps at x = \[1\.0\] m"):
        HingedChain.superelements(wing(), 3)
    modal = ModalAppendage([10.0], [[1.0, 1.0]], [[5.0, 2.0], [2.0, 4.0]])
    for method in (HingedChain.rfem, HingedChain.superelements):
        with pytest.raises(TypeError, match="ModalAppendage.*fit_chain"):
            method(modal, 3)


def test_a_planar_tip_moment_on_a_section_beam_gives_the_planar_chain():
    # A tip body given its moment about z alone describes the x-y plane: the chain of that
    # plane (its other motions' inertias are unknown), for a uniform and a stepped beam
    for beam in (Beam.rectangular(6.0, 1.0, 0.02, 200.0, 2e10, tip=TipBody(5.0, 0.5, 0.1)),
                 wing()):
        chain = HingedChain.rfem(beam, 6)
        assert chain.torsional_inertias is None
        assert chain.inertia == pytest.approx(beam.inertia, rel=1e-13)
