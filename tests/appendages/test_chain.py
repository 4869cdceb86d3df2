"""Tests of appendages.chain.HingedChain: closed forms, limits, convergence, large n, bad input.

Sign conventions (DESIGN.md): delta along +y, phi about +z, F_y along +y and M about +z at the
attachment end x = 0; the chain extends along +x.
"""

import numpy as np
import pytest

from appendages.beam import Beam
from appendages.chain import MOLENAAR_K, HingedChain
from appendages.interface import FiniteAppendage

# Free-free Euler-Bernoulli roots beta_k L (Blevins 1979, table 8-1).
BLEVINS_FREE_FREE = np.array([4.730040745, 7.853204624, 10.99560784, 14.13716549, 17.27875966])

S_POINTS = np.array([0.37 + 0.0j, 1.3j, 0.2 + 2.9j, -0.05 + 7.1j, 3.0 - 11.0j])


def paper_rod():
    """The paper's rod: L = 10 m, d = 0.01 m, steel (PAPER.md)."""
    return Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)


def rigid_body_W(s, mass, inertia, a):
    """W of one free rigid body whose centre of mass is a distance a along +x from the root.

    Newton-Euler: m y_c'' = F, J theta'' = M - a F (F at x = 0 has lever -a about the centre),
    delta = y_c - a theta, so W = [[1/m + a^2/J, -a/J], [-a/J, 1/J]] / s^2.
    """
    s = np.asarray(s, dtype=complex)[..., None, None]
    return np.array([[1.0 / mass + a * a / inertia, -a / inertia],
                     [-a / inertia, 1.0 / inertia]]) / s**2


def recursive_W(chain, s):
    """W(s) by an independent O(n) Newton-Euler recursion from the free tip to the root.

    For body k (start displacement y, rotation theta, loads F, M applied at its start), with
    (F_out, M_out) the loads it applies to the outboard part at its end (displacement
    y + l theta): F = m s^2 (y + a theta) + F_out, M = J s^2 theta + M_out + a F + (l - a) F_out.
    Through the hinge (stiffness c + d s), M_out = (c + d s)(theta - theta_next), and the outboard
    part's dynamic stiffness D gives [F_out, M_out] = D [y + l theta, theta_next]; eliminating
    theta_next gives D of body k and everything outboard. W = D_1^-1 (plus 1/(c_0 + d_0 s) on
    the rotation for a hinged root: the drive spring is in series).
    """
    s = complex(s)
    n = chain.n_bodies
    hinged = chain.root == "hinged"
    k_springs = chain.hinge_stiffnesses + s * chain.hinge_dampings
    outer_springs = k_springs[1:] if hinged else k_springs
    D = None
    for k in range(n - 1, -1, -1):
        m, J, a, l = chain.masses[k], chain.inertias[k], chain.com_offsets[k], chain.lengths[k]
        # loads [F_out, M_out] as a matrix acting on [y, theta] of body k
        if D is None:
            out = np.zeros((2, 2), dtype=complex)
        else:
            c = outer_springs[k]
            end = np.array([[1.0, l], [0.0, 1.0]], dtype=complex)          # [y_e, theta]
            # theta_next = (c theta - D21 y_e) / (D22 + c)
            next_row = np.array([-D[1, 0], c]) / (D[1, 1] + c)              # on [y_e, theta]
            F_out = D[0, 0] * np.array([1.0, 0.0]) + D[0, 1] * next_row
            M_out = c * (np.array([0.0, 1.0]) - next_row)
            out = np.vstack([F_out, M_out]) @ end
        F = m * s**2 * np.array([1.0, a]) + out[0]
        M = J * s**2 * np.array([0.0, 1.0]) + out[1] + a * F + (l - a) * out[0]
        D = np.vstack([F, M])
    W = np.linalg.inv(D)
    if hinged:
        W[1, 1] += 1.0 / k_springs[0]
    return W


def random_chain(rng, n, root="rigid", damped=True):
    lengths = rng.uniform(0.2, 2.0, n)
    masses = rng.uniform(0.5, 5.0, n)
    inertias = masses * lengths**2 * rng.uniform(0.02, 0.2, n)
    n_hinges = n - 1 if root == "rigid" else n
    stiffness = rng.uniform(5.0, 200.0, n_hinges)
    dampings = rng.uniform(0.0, 2.0, n_hinges) if damped else None
    offsets = lengths * rng.uniform(0.1, 0.9, n)
    return HingedChain(lengths, masses, inertias, stiffness, hinge_dampings=dampings,
                       com_offsets=offsets, root=root)


# -- closed forms ---------------------------------------------------------------------------------
@pytest.mark.parametrize("offset", [None, 0.7, 0.0, 2.0])
def test_one_rigid_body_matches_closed_form(offset):
    """W of a single body equals the rigid-body closed form (rtol 1e-12: a 2x2 inverse)."""
    chain = HingedChain([2.0], [3.0], [0.5], [],
                        com_offsets=None if offset is None else [offset])
    a = 1.0 if offset is None else offset
    np.testing.assert_allclose(chain.W(S_POINTS), rigid_body_W(S_POINTS, 3.0, 0.5, a),
                               rtol=1e-12, atol=0.0)
    assert chain.poles().size == 0
    np.testing.assert_allclose(chain.gains(), [1 / 3 + a * a / 0.5, -a / 0.5, -a / 0.5, 1 / 0.5],
                               rtol=1e-12)


def test_rigid_body_sign_convention():
    """A body extending along +x: a force along +y makes it rotate negatively, W2 < 0."""
    chain = HingedChain([2.0], [3.0], [0.5], [])
    W = chain.W(1.0j)  # s^2 = -1: W = -s^2 W, so signs flip
    assert W[0, 1].real > 0.0 and chain.gains()[1] < 0.0


def test_hinged_single_body_is_rigid_body_plus_series_spring():
    """A hinged root puts the drive spring in series with the body's rotation:
    W = W_body + [[0, 0], [0, 1/(c + d s)]] (rtol 1e-12)."""
    c, d = 10.0, 0.3
    chain = HingedChain([2.0], [3.0], [0.5], [c], hinge_dampings=[d], com_offsets=[0.7],
                        root="hinged")
    expected = rigid_body_W(S_POINTS, 3.0, 0.5, 0.7)
    expected[:, 1, 1] += 1.0 / (c + d * S_POINTS)
    np.testing.assert_allclose(chain.W(S_POINTS), expected, rtol=1e-12, atol=0.0)


def two_body_chain():
    return HingedChain([1.5, 2.5], [2.0, 3.5], [0.3, 1.1], [40.0], com_offsets=[0.6, 1.4])


def test_two_body_frequency_closed_form():
    """Two bodies joined by a spring c, r1 = l1 - a1, r2 = a2 from the hinge, mu = m1 m2/m.

    Eliminating the hinge translation by momentum conservation leaves the mass matrix
    [[J1 + mu r1^2, mu r1 r2], [mu r1 r2, J2 + mu r2^2]] on (theta1, theta2) and K = c e e^T,
    e = [1, -1], so w^2 = c (M11 + M22 + 2 M12) / det M. Closed form, rtol 1e-12.
    """
    m1, m2, J1, J2, a1, a2, l1, c = 2.0, 3.5, 0.3, 1.1, 0.6, 1.4, 1.5, 40.0
    r1, r2, mu = l1 - a1, a2, m1 * m2 / (m1 + m2)
    M11, M22, M12 = J1 + mu * r1**2, J2 + mu * r2**2, mu * r1 * r2
    w2 = c * (M11 + M22 + 2 * M12) / (M11 * M22 - M12**2)
    np.testing.assert_allclose(two_body_chain().poles(), [np.sqrt(w2)], rtol=1e-12)


def test_two_body_zero_closed_forms():
    """Zeros of W1 (root pinned) and W4 (root rotation held), closed forms, rtol 1e-12.

    Pinned: coordinates (theta1, theta2), y_c1 = a1 theta1, y_c2 = l1 theta1 + a2 theta2:
    M = [[J1 + m1 a1^2 + m2 l1^2, m2 l1 a2], [m2 l1 a2, J2 + m2 a2^2]], K = c e e^T.
    Rotation held: coordinates (delta, theta2): M = [[m, m2 a2], [m2 a2, J2 + m2 a2^2]],
    K = diag(0, c), so n^2 = c m / det M.
    """
    m1, m2, J1, J2, a1, a2, l1, c = 2.0, 3.5, 0.3, 1.1, 0.6, 1.4, 1.5, 40.0
    M11, M22, M12 = J1 + m1 * a1**2 + m2 * l1**2, J2 + m2 * a2**2, m2 * l1 * a2
    # K = c e e^T with e = [1, -1]: the nonzero eigenvalue is c e^T adj(M) e / det M
    n1 = np.sqrt(c * (M22 + M11 + 2 * M12) / (M11 * M22 - M12**2))
    m = m1 + m2
    n4 = np.sqrt(c * m / (m * (J2 + m2 * a2**2) - (m2 * a2) ** 2))
    chain = two_body_chain()
    np.testing.assert_allclose(chain.zeros(1), [n1], rtol=1e-12)
    np.testing.assert_allclose(chain.zeros(4), [n4], rtol=1e-12)
    # W2 vanishes at its zero (checked through W itself, |W2| relative to |W1|)
    z2 = chain.zeros(2)
    assert z2.size == 1
    W = chain.W(1j * z2[0])
    assert abs(W[0, 1]) < 1e-9 * abs(W[0, 0])


def test_paper_three_body_chain():
    """The paper's chain: J = m L^2/12 exactly (frozen pieces), k1 > 0, k2 = k3 < 0, k4 > 0."""
    rod = paper_rod()
    chain = HingedChain.three_body(10.0, rod.mass, 0.26989, 37.134)
    np.testing.assert_allclose(chain.lengths, [3.650550, 2.6989, 3.650550], rtol=1e-12)
    # closed forms of a few flops on 3 bodies (no BLAS): masses m L_i / L, centre of mass
    # sum m_i x_i / m and inertia sum m_i (L_i^2 / 12 + (x_i - x_c)^2) are sums of 3 positive
    # terms of <= 6 roundings each, within ~10 eps of exact (Higham 2002, sec. 3.1-3.3);
    # 1e-14 = 45 eps and 1e-13 (the inertia's longer chain of products) leave room
    np.testing.assert_allclose(chain.inertia, rod.mass * 100.0 / 12.0, rtol=1e-13)
    np.testing.assert_allclose(chain.center_of_mass, 5.0, rtol=1e-14)
    k = chain.gains()
    assert k[0] > 0 and k[1] < 0 and k[3] > 0 and k[1] == k[2]
    np.testing.assert_allclose(chain.masses.sum(), rod.mass, rtol=1e-14)


# -- properties -----------------------------------------------------------------------------------
@pytest.mark.parametrize("root", ["rigid", "hinged"])
@pytest.mark.parametrize("n", [1, 2, 5, 12])
def test_W_symmetric_and_real(n, root):
    """W(s) = W(s)^T (reciprocity) and W(conj s) = conj W(s) (real system); rtol 1e-12."""
    chain = random_chain(np.random.default_rng(n), n, root)
    W = chain.W(S_POINTS)
    np.testing.assert_allclose(W, np.swapaxes(W, -1, -2), rtol=1e-12, atol=0.0)
    np.testing.assert_allclose(chain.W(np.conj(S_POINTS)), np.conj(W), rtol=1e-12, atol=0.0)


@pytest.mark.parametrize("root", ["rigid", "hinged"])
@pytest.mark.parametrize("n", [1, 3, 8])
def test_W_matches_lagrangian_realisation_and_recursion(n, root):
    """HingedChain.W (a D-recursion), the Lagrangian realisation condensed by FiniteAppendage.W
    and the test's own Newton-Euler recursion agree (rtol 1e-11)."""
    chain = random_chain(np.random.default_rng(10 + n), n, root)
    for s in S_POINTS:
        lagrangian = FiniteAppendage.W(chain, s)
        np.testing.assert_allclose(chain.W(s), lagrangian, rtol=1e-11, atol=0.0)
        np.testing.assert_allclose(recursive_W(chain, s), lagrangian, rtol=1e-11, atol=0.0)


@pytest.mark.parametrize("n_bodies", [3, 10, 200])
def test_W_keeps_the_rigid_body_limit_at_small_s(n_bodies):
    """s^2 W(s) tends to the rigid-body flexibility of the whole chain; at |s| = 1e-6 rad/s the
    elastic correction is ~ (|s|/w_1)^2 ~ 1e-13, so rtol 1e-10 (the matrix condensation of
    FiniteAppendage.W loses 4e-2 here at 200 bodies: it subtracts stiffness-sized terms)."""
    chain = HingedChain.rfem(paper_rod(), n_bodies)
    s = np.array([1e-6j, 1e-6 + 2e-7j])
    expected = rigid_body_W(s, chain.mass, chain.inertia, chain.center_of_mass)
    np.testing.assert_allclose(chain.W(s), expected, rtol=1e-10, atol=0.0)


def test_W_rejects_the_rigid_body_pole():
    with pytest.raises(ValueError, match="s = 0 is the rigid-body pole"):
        HingedChain.rfem(paper_rod(), 3).W(np.array([1j, 0.0]))


def test_poles_and_zeros_by_count_at_any_spectrum_spread():
    """Rigid-body modes are dropped by count: a one-body hinged chain has no pole (not a
    round-off one), and a 400-body chain keeps its first mode (Blevins, rtol 1e-9 + its
    O(H^4) discretisation error ~ 2e-11)."""
    one = HingedChain([10.0], [6.0], [50.0], [20.0], root="hinged")
    assert one.poles().size == 0 and one.zeros(1).size == 0
    np.testing.assert_allclose(one.zeros(4), [np.sqrt(20.0 / 50.0)], rtol=1e-12)
    rod = paper_rod()
    exact = BLEVINS_FREE_FREE[0] ** 2 * np.sqrt(rod.bending_stiffness / (rod.linear_density * 1e4))
    np.testing.assert_allclose(HingedChain.rfem(rod, 400).poles()[0], exact, rtol=1e-9)


@pytest.mark.parametrize("root", ["rigid", "hinged"])
def test_state_space_reproduces_W(root):
    """state_space() evaluated at s equals W(s) (undamped: modal realisation exact, rtol 1e-9)."""
    chain = random_chain(np.random.default_rng(3), 4, root, damped=False)
    sys = chain.state_space()
    assert list(sys.input_labels) == ["F_y", "M"] and list(sys.output_labels) == ["delta", "phi"]
    for s in S_POINTS[1:]:
        np.testing.assert_allclose(sys(s), chain.W(s), rtol=1e-9, atol=0.0)


def test_stiff_hinges_tend_to_one_rigid_body():
    """Five bodies with c -> infinity behave as one body with the chain's m, J and centre of mass.

    At |s| = 1 rad/s the flexible correction is of order m L^2 |s|^2 / c ~ 1e-7 for c = 1e9."""
    rng = np.random.default_rng(7)
    chain = random_chain(rng, 5, damped=False)
    stiff = HingedChain(chain.lengths, chain.masses, chain.inertias, np.full(4, 1e9),
                        com_offsets=chain.com_offsets)
    s = np.array([1.0j, 0.5 + 0.5j])
    np.testing.assert_allclose(stiff.W(s), rigid_body_W(s, stiff.mass, stiff.inertia,
                                                        stiff.center_of_mass),
                               rtol=1e-6, atol=0.0)
    assert stiff.poles()[0] > 1e3  # the elastic modes leave for high frequency


def test_hinged_root_properties():
    """A massless mount: the free chain's poles and pinned (W1) zeros do not depend on the drive
    spring, and a soft drive spring c0 gives a W4 zero sqrt(c0/J) (the chain rocking about its
    centre of mass on the spring, translation free), rtol 1e-3 for c0 = 1e-4 of the hinges'."""
    rod = paper_rod()
    rigid = HingedChain.rfem(rod, 6)
    c0 = 1e-4 * rigid.hinge_stiffnesses[0]
    hinged = HingedChain(rigid.lengths, rigid.masses, rigid.inertias,
                         np.concatenate([[c0], rigid.hinge_stiffnesses]), root="hinged")
    np.testing.assert_allclose(hinged.poles(), rigid.poles(), rtol=1e-10)
    np.testing.assert_allclose(hinged.zeros(1), rigid.zeros(1), rtol=1e-10)
    np.testing.assert_allclose(hinged.zeros(4)[0], np.sqrt(c0 / rigid.inertia), rtol=1e-3)
    with pytest.raises(ValueError, match="gains are undefined"):
        hinged.gains()


# -- static equivalence of the classical chains ---------------------------------------------------
def clamped_tip_compliance(chain):
    """Tip deflection and rotation of the chain clamped at the root under a tip force F and
    a tip moment M: returns the 2x2 matrix [[w/F, w/M], [theta/F, theta/M]]."""
    rm = chain.root_model()
    K = rm.stiffness[2:, 2:]
    # absolute tip displacement row w(L) = tip + delta + L phi; with delta = phi = 0: tip row
    w_row = rm.tip[2:]
    theta_row = np.zeros(K.shape[0])
    theta_row[-1] = 1.0  # rotation of the last body
    Q = np.column_stack([w_row, theta_row])  # generalised forces of F and M
    q = np.linalg.solve(K, Q)
    return np.vstack([w_row @ q, theta_row @ q])


def test_superelement_static_equivalence():
    """Molenaar's superelement gives the cantilever's exact tip compliance (Euler-Bernoulli:
    [[L^3/3, L^2/2], [L^2/2, L]] / EJ) for any number of superelements (rtol 1e-12)."""
    rod = paper_rod()
    L, EJ = rod.length, rod.bending_stiffness
    exact = np.array([[L**3 / 3, L**2 / 2], [L**2 / 2, L]]) / EJ
    for n in (1, 2, 5):
        chain = HingedChain.superelements(rod, n)
        assert chain.n_bodies == 2 * n + 1
        np.testing.assert_allclose(clamped_tip_compliance(chain), exact, rtol=1e-12)
    np.testing.assert_allclose(MOLENAAR_K, (1 - 1 / np.sqrt(3)) / 2, rtol=1e-15)


def test_rfem_static_moment_response():
    """RFEM (c = EJ/H, hinges at the mid-points of H-long segments) is exact under a tip moment:
    rotation M L/EJ, deflection M L^2/(2 EJ) (midpoint rule, exact for a linear integrand);
    under a tip force its deflection is L^3/(3EJ) (1 - 1/(4 N^2)), N = n - 1 segments."""
    rod = paper_rod()
    L, EJ = rod.length, rod.bending_stiffness
    for n in (2, 5, 20):
        C = clamped_tip_compliance(HingedChain.rfem(rod, n))
        np.testing.assert_allclose(C[:, 1], [L**2 / (2 * EJ), L / EJ], rtol=1e-12)
        N = n - 1
        np.testing.assert_allclose(C[0, 0], L**3 / (3 * EJ) * (1 - 1 / (4 * N**2)), rtol=1e-12)


# -- convergence to the beam ----------------------------------------------------------------------
def test_rfem_converges_to_blevins_frequencies_at_fourth_order():
    """RFEM chains' first five frequencies tend to Blevins' free-free ones with an error
    O(H^4) (measured order 3.9-4.1 between 40 and 80 segments; the frozen rotary inertia and
    the half end rods cancel the H^2 term)."""
    rod = paper_rod()
    exact = BLEVINS_FREE_FREE**2 * np.sqrt(rod.bending_stiffness / (rod.linear_density * 1e4))
    errors = [np.abs(HingedChain.rfem(rod, N + 1).poles()[:5] / exact - 1) for N in (40, 80)]
    order = np.log2(errors[0] / errors[1])
    assert np.all((order > 3.8) & (order < 4.2)), order
    assert np.all(errors[1] < 2e-6)


def test_superelements_converge_to_blevins_frequencies():
    """Superelement chains converge too; error O(l^4) asymptotically (measured 4.0-4.6
    between 8 and 16 superelements for the first 3 modes)."""
    rod = paper_rod()
    exact = BLEVINS_FREE_FREE**2 * np.sqrt(rod.bending_stiffness / (rod.linear_density * 1e4))
    errors = [np.abs(HingedChain.superelements(rod, n).poles()[:3] / exact[:3] - 1)
              for n in (8, 16)]
    order = np.log2(errors[0] / errors[1])
    assert np.all((order > 3.8) & (order < 5.0)), order
    assert np.all(errors[1] < 3e-5)


@pytest.mark.slow
def test_two_hundred_bodies_keep_their_accuracy():
    """A 200-body RFEM chain: poles within 1e-8 of Blevins' (its O(H^4) discretisation error is
    2e-10 .. 7e-9 for modes 1-3), W equal to the O(n) recursion to 1e-9 (relative; the
    condensation of a 199x199 block costs a few digits), and W symmetric."""
    rod = paper_rod()
    chain = HingedChain.rfem(rod, 200)
    exact = BLEVINS_FREE_FREE**2 * np.sqrt(rod.bending_stiffness / (rod.linear_density * 1e4))
    np.testing.assert_allclose(chain.poles()[:5], exact, rtol=5e-8)
    np.testing.assert_allclose(chain.poles()[:3], exact[:3], rtol=1e-8)
    for s in (0.3j, 1.0 + 2.0j, 5.0j):
        W = chain.W(s)
        np.testing.assert_allclose(W, recursive_W(chain, s), rtol=1e-9, atol=0.0)
        np.testing.assert_allclose(W, W.T, rtol=1e-12, atol=0.0)
    # pinned-free zeros (tan x = tanh x roots 3.9266023120, 7.0685827456, mpmath.findroot)
    pinned = np.array([3.9266023120, 7.0685827456]) ** 2 * exact[0] / BLEVINS_FREE_FREE[0] ** 2
    np.testing.assert_allclose(chain.zeros(1)[:2], pinned, rtol=1e-8)


# -- rigid properties -----------------------------------------------------------------------------
def test_rigid_properties_parallel_axis():
    """length, mass and inertia about the centre of mass (parallel-axis theorem), rtol 1e-14."""
    chain = HingedChain([1.0, 3.0], [2.0, 4.0], [0.5, 1.5], [10.0], com_offsets=[0.25, 1.0])
    centres = np.array([0.25, 2.0])
    xc = (2.0 * 0.25 + 4.0 * 2.0) / 6.0
    assert chain.length == 4.0 and chain.mass == 6.0
    np.testing.assert_allclose(chain.center_of_mass, xc, rtol=1e-14)
    np.testing.assert_allclose(chain.inertia,
                               2.0 + np.dot([2.0, 4.0], (centres - xc) ** 2), rtol=1e-14)
    assert chain.n_bodies == 2 and chain.root == "rigid"
    np.testing.assert_array_equal(chain.hinge_dampings, [0.0])


def test_point_masses_allowed_when_mass_matrix_regular():
    """A zero inertia is allowed (a point mass) if every coordinate still carries inertia.

    Body 1: point mass 1 kg at 0.5 m of its 1 m; body 2: 1 kg, J = 0.2 kg*m^2, centre at 0.5 m.
    Pinned root, coordinates (theta1, theta2): y1 = 0.5 theta1, y2 = theta1 + 0.5 theta2, so
    M = [[0.25 + 1, 0.5], [0.5, 0.2 + 0.25]]; n1^2 = c (M11 + M22 + 2 M12)/det M (rtol 1e-12).
    """
    chain = HingedChain([1.0, 1.0], [1.0, 1.0], [0.0, 0.2], [5.0], com_offsets=[0.5, 0.5])
    M11, M22, M12 = 1.25, 0.45, 0.5
    np.testing.assert_allclose(chain.zeros(1), [np.sqrt(5.0 * (M11 + M22 + 2 * M12)
                                                        / (M11 * M22 - M12**2))], rtol=1e-12)
    # two point masses cannot carry three coordinates (delta, theta1, theta2)
    with pytest.raises(ValueError, match="singular mass matrix"):
        HingedChain([1.0, 1.0], [1.0, 1.0], [0.0, 0.0], [5.0], com_offsets=[1.0, 1.0])


# -- bad input ------------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, error, match", [
    (dict(lengths=[1.0, -1.0]), ValueError, r"lengths must be positive and finite \[m\]"),
    (dict(lengths=[1.0, np.nan]), ValueError, r"lengths .*\[m\]; got nan"),
    (dict(lengths=[]), ValueError, r"lengths"),
    (dict(lengths=[[1.0, 1.0]]), ValueError, r"lengths must be one-dimensional"),
    (dict(lengths=2.0), TypeError, r"lengths must be a sequence"),
    (dict(lengths=["a", "b"]), TypeError, r"lengths must contain real numbers"),
    (dict(masses=[1.0, 0.0]), ValueError, r"masses must be positive and finite \[kg\]"),
    (dict(masses=[1.0]), ValueError, r"masses must have 2 entries \[kg\]; got 1"),
    (dict(inertias=[1.0, -0.1]), ValueError, r"inertias must be non-negative .*\[kg\*m\^2\]"),
    (dict(hinge_stiffnesses=[0.0]), ValueError, r"hinge_stiffnesses .*positive .*\[N\*m/rad\]"),
    (dict(hinge_stiffnesses=[1.0, 1.0]), ValueError, r"hinge_stiffnesses .*1 entries"),
    (dict(hinge_stiffnesses=[np.inf]), ValueError, r"hinge_stiffnesses .*got inf"),
    (dict(hinge_dampings=[-1.0]), ValueError, r"hinge_dampings .*\[N\*m\*s/rad\]"),
    # the first body's centre beyond its end (the last body's may lie beyond: a tip body)
    (dict(com_offsets=[1.5, 0.5]), ValueError, r"com_offsets must lie in \[0, length"),
    (dict(com_offsets=[0.5, -0.1]), ValueError, r"com_offsets .*\[m\]"),
    (dict(root="clamped"), ValueError, r"root must be 'rigid' or 'hinged'"),
    (dict(root="hinged"), ValueError, r"hinge_stiffnesses \(root='hinged'.*2 entries"),
    (dict(inertias=[0.0, 0.0], com_offsets=[0.5, 0.0]), ValueError, r"singular mass matrix"),
])
def test_bad_input(kwargs, error, match):
    args = dict(lengths=[1.0, 1.0], masses=[1.0, 1.0], inertias=[0.1, 0.1],
                hinge_stiffnesses=[10.0])
    args.update(kwargs)
    with pytest.raises(error, match=match):
        HingedChain(**args)


def test_bad_constructor_input():
    rod = paper_rod()
    with pytest.raises(ValueError, match=r"k_L must lie in the open interval \(0, 1\)"):
        HingedChain.three_body(10.0, 6.0, 1.0, 37.0)
    with pytest.raises(TypeError, match="k_L must be a real number"):
        HingedChain.three_body(10.0, 6.0, "0.3", 37.0)
    with pytest.raises(ValueError, match=r"stiffness must be positive and finite \[N\*m/rad\]"):
        HingedChain.three_body(10.0, 6.0, 0.3, -37.0)
    with pytest.raises(ValueError, match=r"length must be positive and finite \[m\]"):
        HingedChain.three_body(-10.0, 6.0, 0.3, 37.0)
    with pytest.raises(ValueError, match="n_bodies must be at least 2"):
        HingedChain.rfem(rod, 1)
    with pytest.raises(TypeError, match="n_bodies must be an integer"):
        HingedChain.rfem(rod, 3.0)
    with pytest.raises(ValueError, match="n must be at least 1"):
        HingedChain.superelements(rod, 0)
    with pytest.raises(TypeError, match="beam must be a uniform beam"):
        HingedChain.rfem(object(), 3)
    with pytest.raises(TypeError, match="s must be a complex number"):
        HingedChain.rfem(rod, 3).W("1j")
