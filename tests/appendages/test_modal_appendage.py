"""ModalAppendage: finite-element cantilever modes as an appendage (appendages.modal_data).

References: the independent planar Hermite model of a stepped boom with a tip body
(tests/support/fe_planar.py) and the 3-D finite-element model (tests/support/fe3d.py), neither of which imports
flexsat; the uniform beam's closed forms (Beam.cantilever_frequencies, modal_participation).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse

import fe3d
import fe_planar
from appendages import Beam, ModalAppendage
from appendages.unit_slips import UnitWarning
from spacecraft import Hub, Mount, Spacecraft

# A stepped boom (a stiff inner segment, a lighter outer one) with a tip body off its end.
SEGMENTS = [(3.0, 2.0e4, 4.0, 12), (4.0, 6.0e3, 2.0, 16)]
TIP = (5.0, 0.8, 0.3)  # kg, kg m^2 about its centre, m beyond the end
HUB = (300.0, 150.0)   # kg, kg m^2
POSITION = 0.8         # m, the root on the hub's x axis


@pytest.fixture(scope="module")
def planar_data():
    return fe_planar.cantilever_modal_data(SEGMENTS, TIP)


@pytest.fixture(scope="module")
def planar_truth():
    return fe_planar.coupled_frequencies(SEGMENTS, TIP, *HUB, POSITION)


def _spacecraft(appendage):
    return Spacecraft(Hub(*HUB), [Mount(appendage, (POSITION, 0.0), 0.0)])


def _beam_data(beam: Beam, n: int):
    L = beam.length
    rigid = beam.linear_density * np.array([[L, L**2 / 2.0], [L**2 / 2.0, L**3 / 3.0]])
    return beam.cantilever_frequencies(n), beam.modal_participation(n), rigid


# -- the round trip ------------------------------------------------------------------------------
def test_all_modes_reproduce_the_models_coupled_frequencies(planar_data, planar_truth):
    # Every cantilever mode of the FE boom: the ModalAppendage is that FE model exactly, so a hub
    # carrying it has the FE model's coupled frequencies. The FE reference's dense eigen-solution
    # is good to ~4e-10 on the first coupled mode (measured against a 40-digit solution), the
    # modal data's cantilever solve to the same: rtol 2e-9.
    w, G, rigid, tip = planar_data
    app = ModalAppendage(w, G, rigid, length=7.0, tip_motion=tip)
    for exact in (False, True):
        coupled = _spacecraft(app).natural_frequencies(8, exact=exact)
        np.testing.assert_allclose(coupled, planar_truth[:8], rtol=2e-9, atol=0)


def test_truncated_modes_converge_from_above(planar_data, planar_truth):
    # A Craig-Bampton reduction is a Rayleigh-Ritz model of the coupled system: every coupled
    # frequency is an upper bound of the FE model's of the same rank, and they converge.
    w, G, rigid, _ = planar_data
    app = ModalAppendage(w, G, rigid, length=7.0)
    errors = []
    for n in (3, 6, 12, 24):
        coupled = _spacecraft(app.truncated(n)).natural_frequencies(3, exact=False)
        error = coupled / planar_truth[:3] - 1.0
        assert np.all(error > -2e-9)  # upper bounds, within the reference's accuracy
        errors.append(np.max(error))
    assert all(b < 0.2 * a for a, b in zip(errors, errors[1:]))
    assert errors[-1] < 1e-8


def test_effective_masses_add_up_to_the_rigid_mass(planar_data):
    # With every mode the effective masses plus the residual (the root node's own mass block,
    # which no cantilever mode moves) give the rigid mass exactly (completeness of the modes).
    w, G, rigid, _ = planar_data
    app = ModalAppendage(w, G, rigid)
    np.testing.assert_allclose(app.effective_masses.sum(axis=0) + np.diag(app.residual_mass),
                               np.diag(rigid), rtol=1e-12)
    assert app.mass == pytest.approx(3.0 * 4.0 + 4.0 * 2.0 + 5.0, rel=1e-13)
    # first moment: segments at their mid-points, the tip body at 7.3 m
    first = 12.0 * 1.5 + 8.0 * 5.0 + 5.0 * 7.3
    assert app.center_of_mass == pytest.approx(first / 25.0, rel=1e-13)
    assert np.all(app.effective_mass_fractions <= 1.0)


def test_heavy_hub_gives_the_entered_damping_to_the_first_coupled_mode(planar_data):
    # The damping ratio means the cantilever modes' (as finite-element data carry it): a hub so
    # heavy that it clamps the root leaves the first coupled mode at w_1 with zeta_1. The
    # coupled mode differs from the cantilever one by O(J_appendage/J_hub), ~7e-7 here about
    # the hub's centre (measured: 3e-7 on the ratio).
    w, G, rigid, _ = planar_data
    zeta = np.full(20, 0.002)
    zeta[0] = 0.005
    app = ModalAppendage(w[:20], G[:20], rigid, damping=zeta, length=7.0)
    plant = Spacecraft(Hub(1e9, 1e9), [Mount(app, (POSITION, 0.0), 0.0)]).plant()
    poles = np.linalg.eigvals(plant.A)
    poles = poles[np.abs(poles) > 1e-6]
    first = poles[np.argmin(np.abs(poles))]
    assert abs(first) == pytest.approx(w[0], rel=1e-6)
    assert -first.real / abs(first) == pytest.approx(0.005, rel=1e-5)
    # on a light hub the same data give another ratio: the entered one is the cantilever mode's
    light = _spacecraft(app).plant()
    p = np.linalg.eigvals(light.A)
    p = p[np.abs(p) > 1e-6]
    p = p[np.argmin(np.abs(p))]
    assert abs(-p.real / abs(p) / 0.005 - 1.0) > 0.1


# -- against the uniform beam ----------------------------------------------------------------------
def test_uniform_beam_modes_equal_the_craig_bampton_truncation():
    # The same model two ways: the beam's own truncation sums the residual mass in closed form,
    # the modal appendage subtracts it from the rigid mass. The residual rotary inertia is 2.4e-5
    # of the rigid one with 12 modes, so the subtraction leaves it ~1e-11 relative error, which
    # W carries (amplified by the 2x2 inversion) where the residual dominates, above the last
    # mode: rtol 1e-9.
    beam = Beam(2.0, 30.0, 1.5)
    app = ModalAppendage(*_beam_data(beam, 12), length=2.0)
    truncation = beam.truncated(12, method="craig-bampton")
    s = np.geomspace(0.1, 1e4, 200) * (0.02 + 1j)
    np.testing.assert_allclose(app.W(s), truncation.W(s), rtol=1e-9, atol=0)
    np.testing.assert_allclose(app.poles(), truncation.poles(), rtol=1e-11)
    for r in (1, 2, 4):
        np.testing.assert_allclose(app.zeros(r), truncation.zeros(r), rtol=1e-10)
    np.testing.assert_allclose(app.gains(), truncation.gains(), rtol=1e-11)
    assert app.mass == pytest.approx(beam.mass, rel=1e-15)
    assert app.inertia == pytest.approx(beam.inertia, rel=1e-14)
    assert app.center_of_mass == pytest.approx(1.0, rel=1e-15)


def test_uniform_beam_modes_converge_to_the_exact_W():
    # The dropped modes' mass rides rigidly on the root: the error of W below the second
    # free-free mode falls fast with the modes kept (measured 8, 16, 32, 64 modes: 5.3e-3,
    # 2.3e-4, 8.3e-6, 2.8e-7).
    beam = Beam(2.0, 30.0, 1.5)
    s = np.geomspace(0.1, 1.0, 300) * beam.natural_frequencies(2)[1] * (0.02 + 1j)
    exact = beam.W(s)
    errors = []
    for n in (8, 16, 32, 64):
        W = ModalAppendage(*_beam_data(beam, n)).W(s)
        errors.append(np.max(np.abs(W - exact) / np.abs(exact)))
    assert all(b < 0.2 * a for a, b in zip(errors, errors[1:]))
    assert errors[-1] < 1e-5


# -- properties of W -------------------------------------------------------------------------------
def test_W_rigid_limit_symmetry_and_conjugation(planar_data):
    w, G, rigid, _ = planar_data
    app = ModalAppendage(w[:10], G[:10], rigid, damping=0.01)
    # s -> 0: s^2 W -> rigid_mass^-1 exactly; the correction is O(s^2/w_1^2) = 1e-12 here
    s_small = 1e-6 * w[0] * 1j
    np.testing.assert_allclose(s_small**2 * app.W(s_small), np.linalg.inv(rigid), rtol=1e-11)
    np.testing.assert_array_equal(app.dynamic_mass(0.0), app.rigid_mass)
    np.testing.assert_allclose(app.rigid_mass, rigid, rtol=1e-15)
    s = np.geomspace(0.1, 1e4, 100) * (0.05 + 1j)
    W = app.W(s)
    np.testing.assert_array_equal(W[:, 0, 1], W[:, 1, 0])
    # the same rounding up to the order of sums; near the poles amplified by 1/(2 zeta) = 50
    np.testing.assert_allclose(app.W(np.conj(s)), np.conj(W), rtol=1e-12)
    # far above every mode, the root sees the residual mass only
    s_big = 1e12j  # the damped terms decay like 2 zeta w/s: 1e-8 here
    np.testing.assert_allclose(s_big**2 * app.W(s_big), np.linalg.inv(app.residual_mass),
                               rtol=1e-6)


def test_state_space_is_W(planar_data):
    w, G, rigid, tip = planar_data
    app = ModalAppendage(w[:8], G[:8], rigid, damping=0.02, tip_motion=tip[:8])
    sys = app.state_space(tip=True)
    assert sys.input_labels == ["F_y", "M"]
    assert sys.output_labels == ["delta", "phi", "tip_deflection"]
    for s in (0.7j, 3.0 + 40j, 500j):
        H = sys(s)
        np.testing.assert_allclose(H[:2], app.W(s), rtol=1e-9)


# -- three axes ------------------------------------------------------------------------------------
def _fe3d_boom(n_elements: int = 10):
    """A 3-D FE beam with a tip body off its axis (mass, inertia tensor, offset)."""
    L, EIz, EIy, GJ, rhoIp, EA, rhoA = 6.0, 4.0e4, 2.5e4, 1.5e4, 0.05, 3.0e7, 3.0
    K, M = fe3d.beam_matrices(L, EIz, EIy, GJ, rhoIp, EA, rhoA, n_elements)
    K, M = K.toarray(), M.toarray()
    m_t, offset = 4.0, np.array([0.4, 0.15, -0.1])
    J_t = np.array([[0.5, 0.05, 0.0], [0.05, 0.8, 0.02], [0.0, 0.02, 0.6]])
    T = fe3d.mount_transformation(offset, np.eye(3))
    last = np.arange(6 * n_elements, 6 * n_elements + 6)
    M[np.ix_(last, last)] += T.T @ scipy.linalg.block_diag(m_t * np.eye(3), J_t) @ T
    D = np.zeros((K.shape[0], 6))
    for i in range(n_elements + 1):
        D[6 * i:6 * i + 6] = fe3d.mount_transformation([L * i / n_elements, 0.0, 0.0],
                                                       np.eye(3))
    return L, K, M, D


def _cantilever_data(K, M, D):
    inner = np.arange(6, K.shape[0])
    Ki, Mi = K[np.ix_(inner, inner)], M[np.ix_(inner, inner)]
    d = 1.0 / np.sqrt(np.diag(Mi))  # equilibrated: the low modes keep their digits
    lam, V = scipy.linalg.eigh(Ki * np.outer(d, d), Mi * np.outer(d, d))
    Phi = V * d[:, None]
    return np.sqrt(lam), Phi.T @ (M @ D)[inner], D.T @ M @ D


@pytest.fixture(scope="module")
def three_axis_case():
    L, K, M, D = _fe3d_boom()
    w, G, rigid = _cantilever_data(K, M, D)
    hub_mass = 500.0
    hub_inertia = np.array([[300.0, 10.0, 0.0], [10.0, 250.0, 5.0], [0.0, 5.0, 400.0]])
    position = np.array([0.5, 0.3, -0.2])
    c1, s1, c2, s2 = np.cos(0.3), np.sin(0.3), np.cos(0.2), np.sin(0.2)
    R = np.array([[c1, -s1, 0.0], [s1, c1, 0.0], [0.0, 0.0, 1.0]]) @ \
        np.array([[c2, 0.0, s2], [0.0, 1.0, 0.0], [-s2, 0.0, c2]])
    n = K.shape[0]
    P = np.zeros((n, n))
    P[:6, :6] = fe3d.mount_transformation(position, R)
    P[6:, 6:] = np.eye(n - 6)
    Kc, Mc = P.T @ K @ P, P.T @ M @ P
    Mc[:3, :3] += hub_mass * np.eye(3)
    Mc[3:6, 3:6] += hub_inertia
    truth = fe3d.natural_frequencies(scipy.sparse.csr_array(Kc), scipy.sparse.csr_array(Mc), 8)
    return dict(L=L, w=w, G=G, rigid=rigid, hub=(hub_mass, hub_inertia), position=position,
                R=R, truth=truth)


def test_three_axis_round_trip_with_an_off_axis_tip_body(three_axis_case):
    # Bending in both planes, torsion and axial motion coupled by the tip body's offset: every
    # cantilever mode of the FE model as three-axis data on a hub reproduces the FE spacecraft's
    # coupled frequencies. fe3d's refined subspace iteration is good to ~1e-13; the cantilever
    # modes' dense solve here (a stiffness of condition ~1e10) to 5e-9 on the first (measured
    # against that iteration), which the data carry into the coupled modes: rtol 1e-8.
    c = three_axis_case
    app = ModalAppendage(c["w"], c["G"], c["rigid"], length=c["L"])
    spacecraft = Spacecraft(Hub(*c["hub"]), [Mount(app, c["position"], orientation=c["R"])])
    for exact in (False, True):
        np.testing.assert_allclose(spacecraft.natural_frequencies(8, exact=exact), c["truth"],
                                   rtol=1e-8)
    np.testing.assert_allclose(app.center_of_mass_vector,
                               [(18.0 * 3.0 + 4.0 * 6.4) / 22.0, 4.0 * 0.15 / 22.0,
                                -4.0 * 0.1 / 22.0], rtol=1e-12)
    # the spacecraft places the centre off the axis where the data put it (hub at the origin)
    centre = c["position"] + c["R"] @ app.center_of_mass_vector
    np.testing.assert_allclose(spacecraft.center_of_mass, 22.0 * centre / (22.0 + c["hub"][0]),
                               rtol=1e-12)
    # a planar spacecraft cannot couple the offset's axial motion to rotation: it says so
    with pytest.warns(UserWarning, match="off its axis in the plane"):
        Spacecraft(Hub(c["hub"][0], 300.0), [Mount(app, (0.5, 0.3), 0.2)])


def test_three_axis_W6_state_space_and_planar_view(three_axis_case):
    c = three_axis_case
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        app = ModalAppendage(c["w"][:30], c["G"][:30], c["rigid"], damping=0.01, length=6.0)
    s = np.array([0.5j, 2.0 + 30j, 400j])
    W6 = app.W6(s)
    np.testing.assert_allclose(W6, np.swapaxes(W6, -1, -2), rtol=1e-12, atol=0)
    sys = app.state_space(three_axis=True)
    assert sys.input_labels == ["F_x", "F_y", "F_z", "M_x", "M_y", "M_z"]
    for k, sk in enumerate(s):
        np.testing.assert_allclose(sys(sk), W6[k], rtol=1e-8, atol=1e-12 * np.abs(W6[k]).max())
    # the planar view holds the other root motions: its W is the inverse of D6's (v, theta_z)
    # block
    D6 = app.dynamic_stiffness6(s)
    np.testing.assert_allclose(app.W(s), np.linalg.inv(D6[:, [1, 5]][:, :, [1, 5]]),
                               rtol=1e-10)
    xz = app.planar_view("xz")
    flip = np.diag([1.0, -1.0])
    np.testing.assert_allclose(xz.W(s), flip @ np.linalg.inv(D6[:, [2, 4]][:, :, [2, 4]]) @ flip,
                               rtol=1e-10)


def test_decoupled_three_axis_data_of_a_uniform_beam_give_its_planar_W():
    beam = Beam.tube(4.0, 0.1, 0.002, 2700.0, 70e9)
    w, G, rigid = _beam_data(beam, 10)
    G6 = np.zeros((10, 6))
    G6[:, [1, 5]] = G
    M6 = np.zeros((6, 6))
    M6[:3, :3] = beam.mass * np.eye(3)
    M6[1, 5] = M6[5, 1] = rigid[0, 1]
    M6[2, 4] = M6[4, 2] = -rigid[0, 1]
    M6[3, 3] = beam.torsional_inertia * beam.length
    M6[4, 4] = M6[5, 5] = rigid[1, 1]
    app6 = ModalAppendage(w, G6, M6)
    app2 = ModalAppendage(w, G, rigid)
    s = np.geomspace(1.0, 1e4, 50) * (0.03 + 1j)
    np.testing.assert_allclose(app6.W(s), app2.W(s), rtol=1e-13)
    np.testing.assert_allclose(app6.W6(s)[:, [1, 5]][:, :, [1, 5]], app2.W(s), rtol=1e-12)
    np.testing.assert_allclose(app6.inertia_tensor,
                               np.diag([M6[3, 3], beam.inertia, beam.inertia]), rtol=1e-12)


# -- bad input -------------------------------------------------------------------------------------
@pytest.fixture
def good():
    beam = Beam(2.0, 30.0, 1.5)
    return _beam_data(beam, 5)


@pytest.mark.parametrize("frequencies, match", [
    ([4.0, 25.0, 70.0, 60.0, 200.0], r"non-decreasing \[rad/s\].*index 3"),
    ([4.0, 25.0, np.nan, 130.0, 200.0], r"finite \[rad/s\]"),
    ([-4.0, 25.0, 70.0, 130.0, 200.0], r"positive.*\[rad/s\]"),
    ([4.0, 25.0], r"shape \(2, 2\)"),
])
def test_bad_frequencies(good, frequencies, match):
    _, G, rigid = good
    with pytest.raises(ValueError, match=match):
        ModalAppendage(frequencies, G, rigid)


def test_bad_rigid_mass(good):
    w, G, rigid = good
    for bad, match in [
        (np.array([[-3.0, 3.0], [3.0, 4.0]]), r"positive \[kg\]"),
        (np.array([[np.inf, 3.0], [3.0, 4.0]]), r"finite"),
        (rigid + np.array([[0.0, 1e-3], [0.0, 0.0]]), r"symmetric"),
        (np.array([[3.0, 3.0], [3.0, 2.0]]), r"positive semi-definite \[kg\*m\^2\]"),
        (np.array([[3.0, 3.0], [3.0, 3.0]]), r"singular \[kg\*m\^2\]"),
        (np.eye(3), r"2x2 .* or 6x6"),
    ]:
        with pytest.raises(ValueError, match=match):
            ModalAppendage(w, G, bad)
    M6 = np.eye(6)
    M6[0, 0] = 2.0
    with pytest.raises(ValueError, match=r"m\*I \[kg\]"):
        ModalAppendage(w, np.zeros((5, 6)), M6)
    M6 = np.eye(6)
    M6[0, 4] = M6[4, 0] = 0.3  # a symmetric first-moment block, not -m [c]x
    with pytest.raises(ValueError, match=r"skew"):
        ModalAppendage(w, np.zeros((5, 6)), M6)


def test_participation_exceeding_the_rigid_mass(good):
    w, G, rigid = good
    with pytest.raises(ValueError, match=r"effective masses exceed the rigid mass.*"
                                         r"mass-normalised modes \[sqrt\(kg\)"):
        ModalAppendage(w, 3.0 * G, rigid)
    with pytest.raises(ValueError, match=r"participation must have one row per mode.*"
                                         r"shape \(5, 2\)"):
        ModalAppendage(w, G.T, rigid)


def test_bad_damping_and_length(good):
    w, G, rigid = good
    with pytest.raises(ValueError, match=r"damping must lie in \[0, 1\)"):
        ModalAppendage(w, G, rigid, damping=-0.01)
    with pytest.raises(ValueError, match=r"damping must be one ratio or one per mode \(5\)"):
        ModalAppendage(w, G, rigid, damping=[0.01, 0.02])
    with pytest.warns(UnitWarning, match=r"damping = 0\.7: above 0\.2.*did you give per cent\? "
                                         r"0\.7 % = 0\.007"):
        ModalAppendage(w, G, rigid, damping=0.7)
    with pytest.raises(ValueError, match=r"length must be positive and finite \[m\]"):
        ModalAppendage(w, G, rigid, length=-2.0)
    with pytest.warns(UserWarning, match="outside"):
        ModalAppendage(w, G, rigid, length=0.5)  # centre of mass at 1 m
    with pytest.raises(ValueError, match="tip outputs need tip_motion"):
        ModalAppendage(w, G, rigid).state_space(tip=True)
    with pytest.raises(ValueError, match="three-axis modal data"):
        ModalAppendage(w, G, rigid).W6(1j)


def test_modes_holding_all_the_mass():
    # Every degree of freedom's mass in the kept modes (a lumped model, all its modes): the
    # residual mass is zero; data that exceed it by round-off (1e-9 here, below
    # RESIDUAL_TOLERANCE) are taken as zero. W tends to a constant flexibility, which couples
    # to a hub but has no free state-space model of a mass matrix: that is refused by name.
    G = np.array([[1.2, 0.7], [-0.4, 0.9]])
    rigid = (G.T @ G) * (1.0 - 1e-9)
    app = ModalAppendage([2.0, 9.0], G, rigid, length=1.0)
    np.testing.assert_allclose(app.residual_mass, 0.0, atol=1e-8)
    s = np.array([1e6j])
    W_inf = np.linalg.inv(G.T @ np.diag([4.0, 81.0]) @ G)  # s^2 M(s) -> G^T Omega^2 G
    np.testing.assert_allclose(app.W(s)[0], W_inf, rtol=1e-6)
    with pytest.raises(ValueError, match="residual mass is singular"):
        app.state_space()
    coupled = Spacecraft(Hub(10.0, 5.0), [Mount(app, (0.2, 0.0), 0.0)])
    assert coupled.natural_frequencies(2, exact=False).size == 2
