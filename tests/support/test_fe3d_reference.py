"""Verification of the independent 3-D finite-element reference model (tests/support/fe3d.py).

fe3d is the yardstick for flexsat's three-axis model, so it is checked here on its own, against
closed forms and limiting cases that share nothing with flexsat: textbook roots of the beam
characteristic equations (recomputed with mpmath to 25 digits and compared with Blevins'
printed values), the rod closed forms, the free-free W of an Euler-Bernoulli beam derived below,
rigid-body mass properties computed by hand, and the exact coupled frequencies of a hub carrying
one beam along a principal axis, where the three-axis problem splits into four planar ones.

Convergence measured on BEAM below (cantilever, relative frequency errors against the
mpmath roots):

=========================  =======  =======  =======  ========  ======================
bending element            N = 10   N = 20   N = 40   N = 80    order observed
=========================  =======  =======  =======  ========  ======================
Hermite cubic, mode 1      8.6e-7   5.4e-8   3.4e-9   2.1e-10   h^4 (ratios 16, 16, 16)
Hermite cubic, mode 3      2.5e-4   1.6e-5   1.0e-6   6.4e-8    h^4
=========================  =======  =======  =======  ========  ======================

=========================  =======  =======  =======  ======================
bending_order=5            N = 4    N = 8    N = 16   order observed
=========================  =======  =======  =======  ======================
mode 1                     4.5e-11  1.8e-13  1.1e-15  h^8
mode 3                     3.3e-6   1.6e-8   6.6e-11  h^8 (ratios 206, 242)
=========================  =======  =======  =======  ======================

Rods: linear elements converge as h^2, cubic (p = 3) as h^6, p = 5 reach 1e-14 with 20
elements. 250 plain Hermite cubic elements put the first three cantilever bending modes within
1e-9 (the issue's "hundreds of elements"); 20 elements of the default kind give 1e-11, which
is why it is fe3d's default. The floor is round-off, about 1e-13 (fe3d's module docstring, on
why plain shift-invert solvers stop at 1e-8 with hundreds of elements).
"""

import math

import mpmath as mp
import numpy as np
import pytest
import scipy.optimize
from scipy.spatial.transform import Rotation

import fe3d

# A beam with every stiffness different, so that no two motions share a frequency by accident.
BEAM = fe3d.BeamParameters(length=2.0, bending_stiffness=3.0, bending_stiffness_y=7.0,
                           torsional_stiffness=1.5, torsional_inertia=0.02,
                           axial_stiffness=900.0, linear_density=0.5)
OTHER = fe3d.BeamParameters(length=1.3, bending_stiffness=5.0, bending_stiffness_y=2.0,
                            torsional_stiffness=4.0, torsional_inertia=0.01,
                            axial_stiffness=2000.0, linear_density=0.7)
# The paper's rod (PAPER.md): L = 10 m, d = 0.01 m, rho = 7800 kg/m^3, E = 2.06e11 Pa; a
# steel G = E/(2 (1 + 0.3)) for torsion. Circular section: I = pi d^4/64, I_p = 2 I.
_D, _RHO, _E = 0.01, 7800.0, 2.06e11
_AREA, _I = math.pi * _D**2 / 4, math.pi * _D**4 / 64
PAPER_ROD = fe3d.BeamParameters(10.0, _E * _I, _E * _I, _E / 2.6 * 2 * _I, _RHO * 2 * _I,
                                _E * _AREA, _RHO * _AREA)

# Blevins, Formulas for Natural Frequency and Mode Shape (1979), table 8-1: beta_k L.
BLEVINS_CANTILEVER = (1.8751040687, 4.6940911330, 7.8547574382)
BLEVINS_FREE_FREE = (4.7300407449, 7.8532046241)


def _roots(equation, guesses):
    with mp.workdps(30):
        return np.array([float(mp.findroot(equation, g)) for g in guesses])


# cos(x) cosh(x) = -1 (clamped-free), = +1 (free-free, flexible roots); 25+ correct digits.
CANTILEVER_BETA_L = _roots(lambda x: mp.cos(x) * mp.cosh(x) + 1,
                           [(2 * k - 1) * math.pi / 2 for k in range(1, 8)])
FREE_BETA_L = _roots(lambda x: mp.cos(x) * mp.cosh(x) - 1,
                     [(2 * k + 1) * math.pi / 2 for k in range(1, 8)])


def bending(beta_L, EI, beam):
    """omega = (beta L)^2 sqrt(EI / (rho A L^4)) [rad/s]."""
    return beta_L**2 * np.sqrt(EI / (beam.linear_density * beam.length**4))


def rod(multiples, stiffness, inertia, beam):
    """omega = c pi / L sqrt(stiffness/inertia), c = k (free-free) or k - 1/2 (cantilever)."""
    return np.asarray(multiples) * math.pi / beam.length * math.sqrt(stiffness / inertia)


def cantilever_frequencies(beam, n_per_motion=6):
    """Every motion's clamped-free frequencies, as a dict."""
    k = np.arange(1, n_per_motion + 1)
    return {"v": bending(CANTILEVER_BETA_L[:n_per_motion], beam.bending_stiffness, beam),
            "w": bending(CANTILEVER_BETA_L[:n_per_motion], beam.bending_stiffness_y, beam),
            "theta_x": rod(k - 0.5, beam.torsional_stiffness, beam.torsional_inertia, beam),
            "u": rod(k - 0.5, beam.axial_stiffness, beam.linear_density, beam)}


def free_free_frequencies(beam, n_per_motion=6):
    k = np.arange(1, n_per_motion + 1)
    return {"v": bending(FREE_BETA_L[:n_per_motion], beam.bending_stiffness, beam),
            "w": bending(FREE_BETA_L[:n_per_motion], beam.bending_stiffness_y, beam),
            "theta_x": rod(k, beam.torsional_stiffness, beam.torsional_inertia, beam),
            "u": rod(k, beam.axial_stiffness, beam.linear_density, beam)}


def lowest(frequencies, n):
    return np.sort(np.concatenate(list(frequencies.values())))[:n]


def clamped(K, M):
    """Remove the root node's six degrees of freedom: the cantilever."""
    keep = np.arange(6, K.shape[0])
    return K[keep][:, keep], M[keep][:, keep]


MOTION_DOFS = {"v": ("v", "theta_z"), "w": ("w", "theta_y"), "theta_x": ("theta_x",),
               "u": ("u",)}


def cantilever_of_one_motion(motion, n, n_elements, **orders):
    """The n lowest cantilever frequencies of one motion alone (the motions decouple)."""
    K, M = fe3d.beam_matrices(*BEAM, n_elements, **orders)
    labels = fe3d.beam_dof_motions(n_elements, **orders)
    keep = np.flatnonzero(np.isin(labels, MOTION_DOFS[motion]))
    keep = keep[keep >= 6]                                   # root clamped
    return fe3d.natural_frequencies(K[keep][:, keep], M[keep][:, keep], n, n_rigid=0)


def cross(r):
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def Rz(angle):
    return Rotation.from_rotvec([0.0, 0.0, angle]).as_matrix()


# ---------------------------------------------------------------------------------------------
# Element matrices
# ---------------------------------------------------------------------------------------------

def test_hermite_matrices_equal_quadrature_of_the_shape_functions():
    # The closed-form matrices (Przemieniecki) against Gauss quadrature of the cubic Hermite
    # shape functions written out here; 4 points are exact for the degree-6 mass integrand.
    h, EI, rhoA = 0.37, 2.5, 1.7
    xi, weights = np.polynomial.legendre.leggauss(4)
    t = (1 + xi) / 2
    N = np.array([1 - 3 * t**2 + 2 * t**3, h * (t - 2 * t**2 + t**3), 3 * t**2 - 2 * t**3,
                  h * (t**3 - t**2)])
    N2 = np.array([-6 + 12 * t, h * (-4 + 6 * t), 6 - 12 * t, h * (6 * t - 2)]) / h**2
    K_ref = EI * (N2 * weights) @ N2.T * h / 2
    M_ref = rhoA * (N * weights) @ N.T * h / 2
    K, M = fe3d.hermite_bending_matrices(h, EI, rhoA)
    # Entries are sums of a few terms of one sign or exact cancellations: 1e-13 of the largest.
    np.testing.assert_allclose(K, K_ref, rtol=0, atol=1e-13 * np.abs(K_ref).max())
    np.testing.assert_allclose(M, M_ref, rtol=0, atol=1e-13 * np.abs(M_ref).max())


def test_bending_bubbles_by_quadrature():
    # The p = 5 element from its definition, integrated here: shape functions = the Hermite
    # cubics and b_k with b_k'' = sqrt((2n+1)/2) P_n(xi), n = k - 2, b_k(-1) = b_k'(-1) = 0.
    # Checks the closed-form stiffness (cubic block, zero coupling, EI (2/h)^3 I) and the
    # quadrature mass; and that the bubbles leave the nodal values and slopes alone (C1).
    h, EI, rhoA = 0.5, 3.0, 2.0
    xi, weights = np.polynomial.legendre.leggauss(8)
    t = (1 + xi) / 2
    Leg = np.polynomial.legendre.Legendre
    N = [1 - 3 * t**2 + 2 * t**3, h * (t - 2 * t**2 + t**3), 3 * t**2 - 2 * t**3,
         h * (t**3 - t**2)]
    N2 = [(-6 + 12 * t) / h**2, (-4 + 6 * t) / h, (6 - 12 * t) / h**2, (6 * t - 2) / h]
    for n in (2, 3):
        c = math.sqrt((2 * n + 1) / 2)
        b = Leg.basis(n).integ(2, lbnd=-1)
        N.append(c * b(xi))
        N2.append(c * Leg.basis(n)(xi) * (2 / h) ** 2)
        for end in (-1.0, 1.0):
            assert abs(b(end)) < 1e-15 and abs(b.deriv()(end)) < 1e-15
    N, N2 = np.array(N), np.array(N2)
    K_ref = EI * (N2 * weights) @ N2.T * h / 2
    M_ref = rhoA * (N * weights) @ N.T * h / 2
    K, M = fe3d.bending_matrices(h, EI, rhoA, order=5)
    np.testing.assert_allclose(K, K_ref, rtol=0, atol=1e-13 * np.abs(K_ref).max())
    np.testing.assert_allclose(M, M_ref, rtol=0, atol=1e-14 * np.abs(M_ref).max())
    # The bubbles' mass does couple to the nodes (else they would change nothing).
    assert np.abs(M[:4, 4:]).max() > 1e-3 * np.abs(M).max()


def test_rod_element_is_the_textbook_linear_element_plus_bubbles():
    h, EA, rhoA = 0.25, 8.0, 3.0
    K, M = fe3d.rod_matrices(h, EA, rhoA, order=1)
    np.testing.assert_allclose(K, EA / h * np.array([[1, -1], [-1, 1]]), rtol=1e-15)
    np.testing.assert_allclose(M, rhoA * h / 6 * np.array([[2, 1], [1, 2]]), rtol=1e-14)
    K3, M3 = fe3d.rod_matrices(h, EA, rhoA, order=3)
    np.testing.assert_allclose(M3[:2, :2], M, rtol=1e-14)
    np.testing.assert_allclose(K3[2:, 2:], 2 * EA / h * np.eye(2), rtol=1e-15)
    # Total mass: a uniform unit translation has nodal values 1 and zero bubbles.
    assert M3[:2, :2].sum() == pytest.approx(rhoA * h, rel=1e-14)


def test_element_annihilates_the_six_rigid_motions_with_the_theta_y_sign():
    # Rigid motion of the element's points: u(x) = a + phi x (x e_x); e_x rotated by phi about
    # y gives -phi_y x along z: w = -phi_y x with theta_y = phi_y, the module's convention.
    # The opposite sign (w = +phi_y x) must cost strain energy.
    h = 0.3
    K, _ = fe3d.element_matrices(BEAM, h, rod_order=3, bending_order=5)
    scale = np.abs(K).max()
    for j in range(6):
        a, phi = np.zeros(3), np.zeros(3)
        (a if j < 3 else phi)[j % 3] = 1.0
        q = np.zeros(K.shape[0])
        for node, x in enumerate((0.0, h)):
            q[6 * node: 6 * node + 3] = a + np.cross(phi, [x, 0.0, 0.0])
            q[6 * node + 3: 6 * node + 6] = phi
        # Exact cancellations of O(scale h) terms: 1e-14 of scale.
        assert np.abs(K @ q).max() <= 1e-14 * scale * max(h, 1.0), j
    wrong = np.zeros(K.shape[0])
    wrong[[4, 10]] = 1.0                         # theta_y = 1 at both ends
    wrong[8] = +h                                # but w = +theta_y x
    assert wrong @ K @ wrong > 1e-3 * BEAM.bending_stiffness_y / h


def test_x_z_couplings_have_the_opposite_sign_of_the_x_y_ones():
    K, M = fe3d.element_matrices(BEAM._replace(bending_stiffness_y=BEAM.bending_stiffness),
                                 0.4, rod_order=1, bending_order=3)
    v, tz, w, ty = 1, 5, 2, 4
    for A in (K, M):
        assert A[w, w] == A[v, v] and A[ty, ty] == A[tz, tz]
        assert A[w, ty] == -A[v, tz] != 0 and A[w, 6 + ty] == -A[v, 6 + tz] != 0
        assert A[ty, 6 + ty] == A[tz, 6 + tz]


def test_beam_matrices_layout_and_labels():
    K, M = fe3d.beam_matrices(*BEAM, 7, rod_order=3, bending_order=5)
    motions = fe3d.beam_dof_motions(7, rod_order=3, bending_order=5)
    assert K.shape == M.shape == (6 * 8 + 8 * 7, 6 * 8 + 8 * 7) == (len(motions),) * 2
    assert list(motions[:6]) == ["u", "v", "w", "theta_x", "theta_y", "theta_z"]
    assert (abs(K - K.T)).max() == 0 and (abs(M - M.T)).max() == 0
    # Motions decouple in the local frame (symmetric section), except v/theta_z and w/theta_y.
    group = {"u": 0, "theta_x": 1, "v": 2, "theta_z": 2, "w": 3, "theta_y": 3}
    g = np.array([group[m] for m in motions])
    for A in (K, M):
        rows, cols = A.nonzero()
        assert np.all(g[rows] == g[cols])


def test_rigid_mass_of_the_beam_at_its_root():
    # Phi^T M Phi for the six rigid motions about the root equals the continuous beam's
    # rigid mass matrix at x = 0: m, first moment m L/2 along x, inertia diag(rho I_p L,
    # m L^2/3, m L^2/3) (consistent mass is exact for linear displacement fields).
    N = 5
    K, M = fe3d.beam_matrices(*BEAM, N)
    Phi = np.zeros((K.shape[0], 6))
    for node in range(N + 1):
        x = BEAM.length * node / N
        Phi[6 * node: 6 * node + 6] = np.block([[np.eye(3), -cross([x, 0, 0])],
                                               [np.zeros((3, 3)), np.eye(3)]])
    m, L = BEAM.mass, BEAM.length
    c = np.array([L / 2, 0, 0])
    G_ref = np.block([[m * np.eye(3), -m * cross(c)],
                      [m * cross(c), np.diag([BEAM.torsional_inertia * L, m * L**2 / 3,
                                              m * L**2 / 3])]])
    np.testing.assert_allclose(Phi.T @ M @ Phi, G_ref, rtol=0, atol=1e-13 * np.abs(G_ref).max())
    assert np.abs(K @ Phi).max() <= 1e-12 * abs(K).max()


# ---------------------------------------------------------------------------------------------
# Cantilever and free-free frequencies
# ---------------------------------------------------------------------------------------------

def test_mpmath_roots_agree_with_blevins_table():
    # Blevins prints 10 decimals: agreement to 0.6e-10.
    np.testing.assert_allclose(CANTILEVER_BETA_L[:3], BLEVINS_CANTILEVER, rtol=0, atol=6e-11)
    np.testing.assert_allclose(FREE_BETA_L[:2], BLEVINS_FREE_FREE, rtol=0, atol=6e-11)


def test_cantilever_frequencies_of_every_motion():
    """Clamped root: three modes of each motion against the closed forms.

    Default element (bending p = 5, rods p = 5), 20 elements: measured errors <= 2e-11 for the
    bending modes (limited by round-off, not by the mesh), <= 1e-14 for the rods; the
    tolerance 1e-10 leaves a margin of five.
    """
    K, M = clamped(*fe3d.beam_matrices(*BEAM, 20))
    omega = fe3d.natural_frequencies(K, M, 12, n_rigid=0)
    np.testing.assert_allclose(omega, lowest(cantilever_frequencies(BEAM), 12), rtol=1e-10)
    exact = cantilever_frequencies(BEAM, 3)
    for motion in MOTION_DOFS:                    # three modes of each motion, alone
        np.testing.assert_allclose(cantilever_of_one_motion(motion, 3, 20), exact[motion],
                                   rtol=1e-10)
    # The first bending frequencies in Blevins' printed precision: 10 decimals of beta L give
    # omega to 2 * 0.5e-10 / beta L relative.
    np.testing.assert_allclose(omega[[0, 1]], bending(np.array(BLEVINS_CANTILEVER[0]),
                                                      np.array([BEAM.bending_stiffness,
                                                                BEAM.bending_stiffness_y]),
                                                      BEAM), rtol=6e-11)


def test_hundreds_of_hermite_cubic_elements_reach_1e9():
    """Plain Hermite cubic bending, 250 elements: first three modes of each plane to 1e-9.

    Measured errors of modes 1..3: 8.4e-11, 3.4e-9, 2.6e-8 with 100 elements; 8e-13, 2.1e-10,
    1.65e-9 with 200 (the h^4 law: 16-fold per halving of h); so 250 elements for mode 3 below
    1e-9 (h^4 estimate 6.8e-10).
    """
    exact = cantilever_frequencies(BEAM, 3)
    for plane in ("v", "w"):
        omega = cantilever_of_one_motion(plane, 3, 250, rod_order=3, bending_order=3)
        errors = np.abs(omega / exact[plane] - 1)
        assert np.all(errors < 1e-9), (plane, errors)


@pytest.mark.parametrize("rod_order, bending_order, expected_bending, expected_rod",
                         [(1, 3, 4, 2), (3, 5, 8, 6)])
def test_observed_convergence_orders(rod_order, bending_order, expected_bending, expected_rod):
    """h^(2(p-1)) for bending of degree p, h^(2p) for rods of order p (Strang and Fix).

    Third cantilever mode of each (errors far above round-off on these meshes). Orders
    measured: 4.0 and 2.0 (cubic, linear rods), 8.0 and 6.0 (p = 5 bending, p = 3 rods).
    """
    exact = cantilever_frequencies(BEAM, 3)
    errors = {"v": [], "theta_x": []}
    meshes = (4, 8) if bending_order == 5 else (8, 16)
    for N in meshes:
        for motion in errors:
            omega = cantilever_of_one_motion(motion, 3, N, rod_order=rod_order,
                                             bending_order=bending_order)
            errors[motion].append(abs(omega[2] / exact[motion][2] - 1))
    order_v = math.log2(errors["v"][0] / errors["v"][1])
    order_t = math.log2(errors["theta_x"][0] / errors["theta_x"][1])
    # Asymptotic orders within 0.5: the meshes are coarse enough to stay above round-off and
    # fine enough to be near the asymptote (the next term is O(h^2) smaller).
    assert abs(order_v - expected_bending) < 0.5, order_v
    assert abs(order_t - expected_rod) < 0.5, order_t


def test_free_free_frequencies_of_every_motion():
    """Free beam: the six rigid modes are removed, then 12 flexible frequencies.

    Measured errors <= 6e-13 with 40 elements (bending p = 5), <= 1e-11 with 30; tolerance
    1e-10.
    """
    K, M = fe3d.beam_matrices(*BEAM, 30)
    omega = fe3d.natural_frequencies(K, M, 12)
    np.testing.assert_allclose(omega, lowest(free_free_frequencies(BEAM), 12), rtol=1e-10)


def test_paper_rod_free_free_frequencies():
    # PAPER.md: w1 = 2.8744, w2 = 7.9231 1/s, truncated and slightly low (exact 7.92356):
    # 1e-4 relative, the printed precision; our closed form to 1e-10.
    K, M = fe3d.beam_matrices(*PAPER_ROD, 20)
    omega = fe3d.natural_frequencies(K, M, 4)
    # A round rod bends alike in both planes: each frequency twice. Torsion and axial motion
    # are far higher for a thin rod.
    np.testing.assert_allclose(omega[0::2], omega[1::2], rtol=1e-12)
    bending_modes = omega[0::2]
    np.testing.assert_allclose(bending_modes, [2.8744, 7.9231], rtol=1e-4)
    np.testing.assert_allclose(bending_modes,
                               bending(FREE_BETA_L[:2], PAPER_ROD.bending_stiffness, PAPER_ROD),
                               rtol=1e-10)
    assert PAPER_ROD.mass == pytest.approx(6.1261, abs=1e-4)


# ---------------------------------------------------------------------------------------------
# Root compliance W6 of the free-free beam
# ---------------------------------------------------------------------------------------------

def planar_W(s, EI, rhoA, L):
    """Exact 2x2 W of a free-free Euler-Bernoulli beam, (v, dv/dx)(0) per (F, M)(0), mpmath.

    v = a cosh(bx) + b sinh(bx) + c cos(bx) + d sin(bx), b^4 = -s^2 rhoA/EI. Virtual work
    with the loads at x = 0 gives EI v'''(0) = F, EI v''(0) = -M, v''(L) = v'''(L) = 0.
    Solving the four equations (lambda = b L, Delta = 1 - cos(lambda) cosh(lambda)):

        v(0)/F  = (cos sinh - sin cosh) / (EI b^3 Delta)
        v(0)/M  = v'(0)/F = sin sinh / (EI b^2 Delta)
        v'(0)/M = -(cos sinh + sin cosh) / (EI b Delta)

    Small lambda: Delta ~ lambda^4/6, so s^2 W -> [[4/m, -6/(mL)], [-6/(mL), 12/(mL^2)]]
    (tested below). Evaluated in 40 digits: at small lambda the numerators cancel.
    """
    with mp.workdps(40):
        s, EI, rhoA, L = mp.mpc(s), mp.mpf(EI), mp.mpf(rhoA), mp.mpf(L)
        b = mp.root(-s**2 * rhoA / EI, 4)
        lam = b * L
        c, sn, ch, sh = mp.cos(lam), mp.sin(lam), mp.cosh(lam), mp.sinh(lam)
        delta = 1 - c * ch
        W = [[(c * sh - sn * ch) / (EI * b**3 * delta), sn * sh / (EI * b**2 * delta)],
             [sn * sh / (EI * b**2 * delta), -(c * sh + sn * ch) / (EI * b * delta)]]
        return np.array([[complex(x) for x in row] for row in W])


def rod_W(s, stiffness, inertia, L):
    """Free-free rod, end motion per end load: coth(g L)/(stiffness g), g = s sqrt(i/k).

    From stiffness u'' = inertia s^2 u, stiffness u'(0) = -F, u'(L) = 0; as s -> 0 it tends
    to 1/(inertia L s^2).
    """
    with mp.workdps(40):
        g = mp.mpc(s) * mp.sqrt(mp.mpf(inertia) / mp.mpf(stiffness))
        return complex(mp.coth(g * L) / (stiffness * g))


def exact_W6(beam, s):
    """The 6x6 W of the free-free beam assembled from the four decoupled closed forms.

    x-z plane: (w, theta_y) = D (w, w') with D = diag(1, -1) and (F_z, M_y) loads enter the
    same way, so its block is D W_planar(EI_y) D.
    """
    W = np.zeros((6, 6), dtype=complex)
    W[0, 0] = rod_W(s, beam.axial_stiffness, beam.linear_density, beam.length)
    W[3, 3] = rod_W(s, beam.torsional_stiffness, beam.torsional_inertia, beam.length)
    D = np.diag([1.0, -1.0])
    W[np.ix_([1, 5], [1, 5])] = planar_W(s, beam.bending_stiffness, beam.linear_density,
                                         beam.length)
    W[np.ix_([2, 4], [2, 4])] = D @ planar_W(s, beam.bending_stiffness_y,
                                             beam.linear_density, beam.length) @ D
    return W


def entry_scale(W):
    """sqrt(|W_ii W_jj|): the natural scale of entry ij (units differ between entries)."""
    d = np.sqrt(np.abs(np.diagonal(W, axis1=-2, axis2=-1)))
    return d[..., :, None] * d[..., None, :]


def test_rigid_root_compliance_inverts_the_rigid_mass_at_the_root():
    # The docstring's table (free rigid body, loads at the root) is the inverse of the rigid
    # mass matrix at the root written independently: G = [[m I, -m [c]x], [m [c]x, J_root]].
    m, L = BEAM.mass, BEAM.length
    c = np.array([L / 2, 0, 0])
    G = np.block([[m * np.eye(3), -m * cross(c)],
                  [m * cross(c), np.diag([BEAM.torsional_inertia * L, m * L**2 / 3,
                                          m * L**2 / 3])]])
    np.testing.assert_allclose(fe3d.rigid_root_compliance(BEAM) @ G, np.eye(6), atol=1e-14)


def test_closed_forms_tend_to_the_rigid_root_compliance():
    # Independent check of the planar and rod closed forms: s^2 W -> A with error O(s^2).
    A = fe3d.rigid_root_compliance(BEAM)
    for s in (1e-6j, 1e-7 * (1 + 1j)):
        np.testing.assert_allclose(s**2 * exact_W6(BEAM, s), A, rtol=0,
                                   atol=1e-10 * np.abs(A).max())


def test_W6_low_frequency_limit_is_the_rigid_body():
    """s^2 W6(s) -> A (rigid_root_compliance), the remainder O(s^2) (the flexible part).

    The remainder must shrink 100-fold when s shrinks 10-fold: a rigid part wrong by any
    amount would leave an s-independent error. Down to |s| = 1e-6 omega_1 the rigid part is
    exact (taken out analytically); measured |s^2 W - A| / |A| = 1.9e-8, 1.9e-10, 1.9e-12 at
    s = 1e-2, 1e-3, 1e-4 j.
    """
    A = fe3d.rigid_root_compliance(BEAM)
    s = np.array([1e-2j, 1e-3j, 1e-4j, 1e-6j])
    W = fe3d.root_compliance(BEAM, s, 20)
    remainder = np.abs(s[:, None, None] ** 2 * W - A).max(axis=(1, 2)) / np.abs(A).max()
    ratios = remainder[:-2] / remainder[1:-1]
    np.testing.assert_allclose(ratios, 100.0, rtol=1e-3)
    # At 1e-6 j the remainder is the rounding of G^-1 (kappa(G) ~ 1e2 times eps): 1e-12.
    assert remainder[-1] < 1e-12


@pytest.mark.parametrize("s", [0.05j, 1.0j, 5.0j, 17.0j, 40.0j, 2.0 + 3.0j, 0.3 - 8.0j])
def test_W6_matches_the_closed_forms(s):
    """FE W6 against the exact W6 at s on and off the imaginary axis, between the poles.

    Measured entry errors <= 1.5e-11 of sqrt(|W_ii W_jj|) with 40 elements (p = 5); 1e-9
    allows for s nearer a pole, where the error grows like 1/distance.
    """
    W = fe3d.root_compliance(BEAM, s, 40)
    W_exact = exact_W6(BEAM, s)
    scale = entry_scale(W_exact)
    assert np.all(np.abs(W - W_exact) <= 1e-9 * scale)


def test_W6_of_the_paper_rod_planar_block():
    # The (v, theta_z)/(F_y, M_z) block of the paper's rod at frequencies below, between and
    # above its first two free-free modes (2.8745, 7.9236 rad/s).
    s = 1j * np.array([0.5, 2.0, 5.0, 10.0])
    W = fe3d.root_compliance(PAPER_ROD, s, 20)[..., [1, 5], :][..., :, [1, 5]]
    for k, sk in enumerate(s):
        W_exact = planar_W(sk, PAPER_ROD.bending_stiffness, PAPER_ROD.linear_density,
                           PAPER_ROD.length)
        assert np.all(np.abs(W[k] - W_exact) <= 1e-9 * entry_scale(W_exact)), k


def test_W6_symmetry_decoupling_and_theta_y_sign():
    s = np.array([0.7j, 3.0 + 2.0j])
    W = fe3d.root_compliance(BEAM, s, 20)
    assert W.shape == (2, 6, 6) and W.dtype == np.complex128
    scale = entry_scale(W)
    # Reciprocity and real coefficients: W = W^T, W(conj s) = conj W(s); 1e-12 of the scale
    # (solves accurate to ~1e-13).
    assert np.all(np.abs(W - np.swapaxes(W, -1, -2)) <= 1e-12 * scale)
    W_conj = fe3d.root_compliance(BEAM, np.conj(s), 20)
    assert np.all(np.abs(W_conj - np.conj(W)) <= 1e-12 * scale)
    # Axial, torsion and the two bending planes do not couple.
    blocks = {0: 0, 3: 1, 1: 2, 5: 2, 2: 3, 4: 3}
    for i in range(6):
        for j in range(6):
            if blocks[i] != blocks[j]:
                assert np.all(np.abs(W[:, i, j]) <= 1e-14 * scale[:, i, j])
    # With equal bending stiffnesses the x-z block is the x-y block with the couplings negated.
    Ws = fe3d.root_compliance(BEAM._replace(bending_stiffness_y=BEAM.bending_stiffness), s, 20)
    np.testing.assert_allclose(Ws[:, 2, 2], Ws[:, 1, 1], rtol=1e-12)
    np.testing.assert_allclose(Ws[:, 4, 4], Ws[:, 5, 5], rtol=1e-12)
    np.testing.assert_allclose(Ws[:, 2, 4], -Ws[:, 1, 5], rtol=1e-12)


def test_W6_scalar_s_shape():
    assert fe3d.root_compliance(BEAM, 1j, 4).shape == (6, 6)
    assert fe3d.root_compliance(BEAM, np.ones((2, 3)) * 1j, 4).shape == (2, 3, 6, 6)


# ---------------------------------------------------------------------------------------------
# Spacecraft
# ---------------------------------------------------------------------------------------------

HUB_MASS = 7.0
HUB_INERTIA = np.array([[3.0, 0.1, -0.2], [0.1, 4.0, 0.3], [-0.2, 0.3, 5.0]])
R1 = Rotation.from_euler("zyx", [0.3, -0.4, 0.7]).as_matrix()
R2 = Rotation.from_euler("zyx", [2.3, 0.2, -0.5]).as_matrix()
MOUNTS = [(BEAM, [0.4, 0.1, -0.2], R1), (OTHER, [-0.3, 0.5, 0.25], R2)]


def rigid_mass_by_hand(hub_mass, hub_inertia, mounts):
    """6x6 rigid mass matrix about the hub's centre of mass, hub axes, from first principles.

    Each beam: mass m = rho A L at its centre c = p + R e_x L/2; inertia about c in local axes
    diag(rho I_p L, m L^2/12, m L^2/12), in hub axes R J R^T, moved to the hub's centre by
    m (|c|^2 I - c c^T). Kinetic energy of a rigid motion (u, phi): the velocity of a point at
    r is u + phi x r, so M = [[m_tot I, -[S]x], [[S]x, J_tot]] with S the first moment.
    """
    m, S, J = hub_mass, np.zeros(3), np.array(hub_inertia, dtype=float)
    for beam, position, R in mounts:
        mb = beam.linear_density * beam.length
        c = np.asarray(position) + R[:, 0] * beam.length / 2
        local = np.diag([beam.torsional_inertia * beam.length, mb * beam.length**2 / 12,
                         mb * beam.length**2 / 12])
        m += mb
        S += mb * c
        J += R @ local @ R.T + mb * (c @ c * np.eye(3) - np.outer(c, c))
    return np.block([[m * np.eye(3), -cross(S)], [cross(S), J]])


def test_mount_transformation_is_the_small_rotation_of_the_hub():
    # Independent kinematics: turn the hub by the rotation vector +-eps phi (scipy's exact
    # rotation) and move it by +-eps u; the central difference of the attachment point's
    # motion is u + phi x r, of the section's attitude phi, both seen in the beam's axes
    # through R^T. Truncation O(eps^2 |phi|^3 |r|) ~ 1e-10 and rounding 1e-16/eps ~ 1e-11
    # with eps = 1e-5: 1e-9.
    r = np.array([0.4, -0.3, 0.25])
    R = R1
    T = fe3d.mount_transformation(r, R)
    rng = np.random.default_rng(3)
    eps = 1e-5
    for _ in range(3):
        u, phi = rng.standard_normal(3), rng.standard_normal(3)
        moved = [Rotation.from_rotvec(e * phi).apply(r) + e * u for e in (eps, -eps)]
        rotation = [Rotation.from_rotvec(e * phi).as_rotvec() for e in (eps, -eps)]
        expected = np.concatenate([R.T @ (moved[0] - moved[1]),
                                   R.T @ (rotation[0] - rotation[1])]) / (2 * eps)
        np.testing.assert_allclose(T @ np.concatenate([u, phi]), expected, rtol=0, atol=1e-9)


def test_rigid_body_block_equals_hand_computed_mass_properties():
    N = 10
    K, M = fe3d.spacecraft_matrices(HUB_MASS, HUB_INERTIA, MOUNTS, N)
    Phi = fe3d.rigid_body_modes(MOUNTS, N)
    # Six independent zero-energy motions: K Phi = 0 to round-off of the largest entries.
    assert np.linalg.matrix_rank(Phi) == 6
    assert np.abs(K @ Phi).max() <= 1e-13 * abs(K).max()
    G = rigid_mass_by_hand(HUB_MASS, HUB_INERTIA, MOUNTS)
    np.testing.assert_allclose(Phi.T @ M @ Phi, G, rtol=0, atol=1e-13 * np.abs(G).max())
    # The hub compliance's low-frequency limit is the rigid body's: s^2 H(s) -> G^-1, the
    # remainder O(s^2) (1e-6 rad/s: 1e-12 relative).
    H = fe3d.hub_compliance(K, M, 1e-6j)
    np.testing.assert_allclose((1e-6j) ** 2 * H, np.linalg.inv(G), rtol=0,
                               atol=1e-11 * np.abs(np.linalg.inv(G)).max())
    # Reciprocity: the hub compliance is symmetric at any s (solves good to ~1e-13).
    H = fe3d.hub_compliance(K, M, [2.0j, 1.0 + 5.0j])
    assert np.all(np.abs(H - np.swapaxes(H, -1, -2)) <= 1e-11 * entry_scale(H))
    theta = fe3d.attitude_compliance(K, M, [1e-6j])
    assert theta.shape == (1, 3, 3)
    np.testing.assert_allclose((1e-6j) ** 2 * theta[0], np.linalg.inv(G)[3:, 3:], rtol=0,
                               atol=1e-11 * np.abs(np.linalg.inv(G)).max())


def test_huge_hub_gives_every_beams_cantilever_frequencies():
    """Hub of 1e12 kg and 1e12 kg m^2: the beams are clamped (shift ~ m_beam/m_hub = 1e-12).

    Both beams, all motions: the 14 lowest against the union of their cantilever closed
    forms; measured <= 2e-11 with 20 elements (p = 5), 1.5e-12 with 40.
    """
    K, M = fe3d.spacecraft_matrices(1e12, 1e12 * np.eye(3), MOUNTS, 20)
    omega = fe3d.natural_frequencies(K, M, 14)
    exact = np.sort(np.concatenate([lowest(cantilever_frequencies(b), 14)
                                    for b in (BEAM, OTHER)]))[:14]
    np.testing.assert_allclose(omega, exact, rtol=1e-9)


def test_tiny_hub_gives_the_free_free_frequencies():
    # Hub of 1e-12 kg: the beam floats free (its root at the offset attachment point).
    K, M = fe3d.spacecraft_matrices(1e-12, 1e-12 * np.eye(3), [(BEAM, [0.3, -0.2, 0.1], R1)],
                                    40)
    omega = fe3d.natural_frequencies(K, M, 10)
    np.testing.assert_allclose(omega, lowest(free_free_frequencies(BEAM), 10), rtol=1e-9)


def _entire_planar(omega, beam, EI, hub_mass, hub_inertia, offset, D):
    """Characteristic function of a hub (mass, inertia) with one beam, one bending plane.

    Hub coordinates q = (translation, rotation) with root motion T q, T = [[1, offset],
    [0, 1]]; with loads F = W^-1 T q on the beam and -T^T F on the hub, the free vibration
    satisfies det(I + W G) = 0, G = -omega^2 T^-T diag(m, J) T^-1. Writing W = D N D / Delta
    (planar_W's numerators N; D = diag(1, -1) for the x-z plane) and using det N =
    Delta (1 + cos cosh) / (EI^2 b^4), Delta det(I + W G) = Delta + tr(D N D G)
    + (1 + cos cosh) det G/(EI^2 b^4), an entire function; divided by cosh to stay finite.
    """
    b = (omega**2 * beam.linear_density / EI) ** 0.25
    lam = b * beam.length
    c, sn, th, sech = math.cos(lam), math.sin(lam), math.tanh(lam), 1 / math.cosh(lam)
    N = np.array([[(c * th - sn) / (EI * b**3), sn * th / (EI * b**2)],
                  [sn * th / (EI * b**2), -(c * th + sn) / (EI * b)]])
    T_inv = np.linalg.inv(np.array([[1.0, offset], [0.0, 1.0]]))
    G = -omega**2 * T_inv.T @ np.diag([hub_mass, hub_inertia]) @ T_inv
    return (sech - c) + np.trace(D @ N @ D @ G) + (sech + c) * np.linalg.det(G) / (EI * b**2) ** 2


def _entire_rod(omega, stiffness, inertia, L, hub):
    """Hub on a rod: hub s^2 + 1/W_rod(s) = 0 at s = j omega, with W_rod = -cot(kL)/(EA k),
    k = omega sqrt(inertia/stiffness); times -cos(kL), an entire function:
    hub omega^2 cos(kL) + stiffness k sin(kL). Huge hub: cos(kL) = 0 (cantilever); no hub:
    sin(kL) = 0 (free-free)."""
    k = omega * math.sqrt(inertia / stiffness)
    return hub * omega**2 * math.cos(k * L) + stiffness * k * math.sin(k * L)


def test_single_beam_spacecraft_exact_coupled_frequencies():
    """A hub with one beam along its x axis, at (a, 0, 0): four exact planar problems.

    With a diagonal hub inertia, hub x couples only to axial motion, rotation about x only to
    torsion, (y, rotation z) to x-y bending with v = y + a phi_z, and (z, rotation y) to x-z
    bending with w = z - a phi_y (the theta_y convention shows here). The exact coupled
    frequencies are the roots of the characteristic functions above; each FE frequency must
    sit on one of them (found by brentq in +-1e-7 of it), and none may be missing (their sign
    changes counted on a fine grid). Measured agreement <= 2e-12 (40 elements).
    """
    m, J, a = 3.0, np.array([0.05, 2.0, 1.5]), 0.4
    beam = BEAM
    K, M = fe3d.spacecraft_matrices(m, np.diag(J), [(beam, [a, 0, 0], np.eye(3))], 40)
    omega = fe3d.natural_frequencies(K, M, 14)
    functions = [
        lambda w: _entire_rod(w, beam.axial_stiffness, beam.linear_density, beam.length, m),
        lambda w: _entire_rod(w, beam.torsional_stiffness, beam.torsional_inertia, beam.length,
                              J[0]),
        lambda w: _entire_planar(w, beam, beam.bending_stiffness, m, J[2], a, np.eye(2)),
        lambda w: _entire_planar(w, beam, beam.bending_stiffness_y, m, J[1], -a,
                                 np.diag([1.0, -1.0])),
    ]
    for w in omega:
        lo, hi = w * (1 - 1e-7), w * (1 + 1e-7)
        hits = [f for f in functions if np.sign(f(lo)) != np.sign(f(hi))]
        assert len(hits) == 1, w
        root = scipy.optimize.brentq(hits[0], lo, hi, xtol=1e-15 * w, rtol=1e-15)
        assert abs(w / root - 1) < 1e-10, (w, root)
    # The sign of the offset in w = z - a phi_y matters: with +a, some x-z frequency of the FE
    # model would sit on no characteristic function.
    wrong = functions[:3] + [lambda w: _entire_planar(w, beam, beam.bending_stiffness_y, m,
                                                      J[1], +a, np.diag([1.0, -1.0]))]
    assert any(all(np.sign(f(w * (1 - 1e-7))) == np.sign(f(w * (1 + 1e-7))) for f in wrong)
               for w in omega)
    # Completeness: every exact root below the 14th FE frequency is among the FE ones.
    grid = np.linspace(1e-3, omega[-1] * (1 + 1e-7), 4001)   # step 0.015 rad/s << root spacing
    n_roots = sum(int(np.sum(np.diff(np.sign([f(w) for w in grid])) != 0)) for f in functions)
    assert n_roots == 14


def test_planar_layout_decouples_in_plane_from_out_of_plane():
    """Beams in the hub's x-y plane, turned about z: in-plane and out-of-plane motions split.

    In-plane: hub (x, y, phi_z) with each beam's u, v, theta_z; out-of-plane: hub
    (z, phi_x, phi_y) with w, theta_x, theta_y. The coupling blocks of K and M vanish exactly
    and the frequencies are the union of the two halves' (each with three rigid modes).
    """
    mounts = [(BEAM, [0.5, 0.1, 0.0], Rz(0.2)), (OTHER, [-0.4, 0.3, 0.0], Rz(2.5)),
              (BEAM, [0.1, -0.6, 0.0], Rz(-1.4))]
    J = np.array([[3.0, 0.2, 0.0], [0.2, 4.0, 0.0], [0.0, 0.0, 5.0]])
    N = 10          # a self-comparison: the mesh need not be fine
    K, M = fe3d.spacecraft_matrices(HUB_MASS, J, mounts, N)
    hub = np.array(["u", "v", "w", "theta_x", "theta_y", "theta_z"])   # x, y, z, phi_x, ...
    beam = fe3d.beam_dof_motions(N)[6:]
    motions = np.concatenate([hub] + [beam] * len(mounts))
    in_plane = np.isin(motions, ["u", "v", "theta_z"])
    for A in (K, M):
        assert abs(A[in_plane][:, ~in_plane]).max() == 0.0
    # Hub degrees of freedom come first in both halves, as natural_frequencies requires.
    halves = [fe3d.natural_frequencies(K[mask][:, mask], M[mask][:, mask], 12, n_rigid=3)
              for mask in (in_plane, ~in_plane)]
    omega = fe3d.natural_frequencies(K, M, 12)
    np.testing.assert_allclose(omega, np.sort(np.concatenate(halves))[:12], rtol=1e-11)


def test_symmetric_pair_gives_double_frequencies():
    """Two equal round beams on opposite sides along x, hub axisymmetric about x.

    The spacecraft is then symmetric under rotation about x: every bending mode in the x-y
    plane has a twin in the x-z plane (double frequency), while torsion and axial modes
    (placed above the first eight by making those stiff) stay single. The block solver must
    find both copies.
    """
    beam = BEAM._replace(bending_stiffness_y=BEAM.bending_stiffness, torsional_stiffness=150.0)
    mounts = [(beam, [0.5, 0, 0], np.eye(3)), (beam, [-0.5, 0, 0], Rz(math.pi))]
    K, M = fe3d.spacecraft_matrices(HUB_MASS, np.diag([2.0, 3.0, 3.0]), mounts, 20)
    omega = fe3d.natural_frequencies(K, M, 8)
    pairs = omega.reshape(4, 2)
    # Copies equal to the solver's accuracy (1e-12 measured); distinct pairs well apart.
    np.testing.assert_allclose(pairs[:, 0], pairs[:, 1], rtol=1e-10)
    assert np.all(np.diff(pairs[:, 0]) > 1e-3 * pairs[1:, 0])


def test_rotating_the_whole_spacecraft_leaves_the_frequencies():
    # Hub inertia Q J Q^T, positions Q p, orientations Q R: the same spacecraft seen in other
    # axes. Round-off only (both solves accurate to ~1e-13): 1e-10.
    Q = Rotation.from_euler("xyz", [0.9, -1.1, 0.4]).as_matrix()
    turned = [(b, Q @ np.asarray(p), Q @ R) for b, p, R in MOUNTS]
    omega = fe3d.natural_frequencies(*fe3d.spacecraft_matrices(HUB_MASS, HUB_INERTIA,
                                                               MOUNTS, 20), 10)
    omega_turned = fe3d.natural_frequencies(*fe3d.spacecraft_matrices(
        HUB_MASS, Q @ HUB_INERTIA @ Q.T, turned, 20), 10)
    np.testing.assert_allclose(omega_turned, omega, rtol=1e-10)
    # And the attitude response turns as a tensor: theta' = Q theta Q^T.
    s = 1.3j
    H = fe3d.attitude_compliance(*fe3d.spacecraft_matrices(HUB_MASS, HUB_INERTIA, MOUNTS, 20), s)
    H_turned = fe3d.attitude_compliance(*fe3d.spacecraft_matrices(
        HUB_MASS, Q @ HUB_INERTIA @ Q.T, turned, 20), s)
    np.testing.assert_allclose(H_turned, Q @ H @ Q.T, rtol=0, atol=1e-10 * np.abs(H).max())


def test_attitude_compliance_of_a_planar_hub_and_beam():
    """theta_z/torque_z of a hub with one beam along x at (a, 0, 0) against the exact planar
    coupling: (diag(m, J) s^2 + T^T W^-1 T) q = (0, torque), T = [[1, a], [0, 1]], with the
    closed-form W. Measured <= 1e-12 relative (40 elements).
    """
    m, J, a = 3.0, np.diag([0.05, 2.0, 1.5]), 0.4
    K, M = fe3d.spacecraft_matrices(m, J, [(BEAM, [a, 0, 0], np.eye(3))], 40)
    s = 1j * np.array([0.3, 1.7, 6.0, 11.0])
    H = fe3d.attitude_compliance(K, M, s)
    T = np.array([[1.0, a], [0.0, 1.0]])
    for k, sk in enumerate(s):
        W = planar_W(sk, BEAM.bending_stiffness, BEAM.linear_density, BEAM.length)
        Z = np.diag([m, J[2, 2]]) * sk**2 + T.T @ np.linalg.solve(W, T)
        exact = np.linalg.solve(Z, [0.0, 1.0])[1]
        assert abs(H[k, 2, 2] / exact - 1) < 1e-9, k
        # theta_x/torque_x is the hub on the torsion rod; theta_x does not respond to torque_z.
        assert abs(H[k, 0, 2]) <= 1e-14 * abs(H[k, 2, 2])


# ---------------------------------------------------------------------------------------------
# Input checks
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("call, error, match", [
    (lambda: fe3d.beam_matrices(-1.0, 1, 1, 1, 1, 1, 1, 4), ValueError, r"length.*\[m\].*-1"),
    (lambda: fe3d.beam_matrices(1.0, 1, 1, 1, 0.0, 1, 1, 4), ValueError, "torsional_inertia"),
    (lambda: fe3d.beam_matrices(1.0, 1, 1, 1, 1, 1, 1, 0), ValueError, "n_elements"),
    (lambda: fe3d.beam_matrices(1.0, 1, 1, 1, 1, 1, 1, 2.5), TypeError, "n_elements"),
    (lambda: fe3d.beam_matrices(1.0, 1, 1, 1, 1, 1, 1, 4, bending_order=2), ValueError,
     "bending_order"),
    (lambda: fe3d.root_compliance(BEAM, 0.0, 4), ValueError, "s must be nonzero"),
    (lambda: fe3d.root_compliance(BEAM, np.nan, 4), ValueError, "finite"),
    (lambda: fe3d.root_compliance({"length": 1.0}, 1j, 4), ValueError, "lack"),
    (lambda: fe3d.root_compliance(object(), 1j, 4), TypeError, "lacks"),
    (lambda: fe3d.spacecraft_matrices(1.0, np.eye(3), [(BEAM, [0, 0], np.eye(3))], 4),
     ValueError, r"position.*shape \(3,\)"),
    (lambda: fe3d.spacecraft_matrices(1.0, np.eye(3), [(BEAM, [0, 0, 0], 2 * np.eye(3))], 4),
     ValueError, "orientation must be a proper rotation"),
    (lambda: fe3d.spacecraft_matrices(1.0, np.eye(3), [(BEAM, [0, 0, 0], -np.eye(3))], 4),
     ValueError, "proper rotation"),
    (lambda: fe3d.spacecraft_matrices(1.0, -np.eye(3), [], 4), ValueError, "positive definite"),
    (lambda: fe3d.spacecraft_matrices(1.0, [[1, 2, 0], [0, 1, 0], [0, 0, 1]], [], 4),
     ValueError, "symmetric"),
    (lambda: fe3d.spacecraft_matrices(0.0, np.eye(3), [], 4), ValueError, r"hub_mass.*\[kg\]"),
    (lambda: fe3d.natural_frequencies(np.eye(3), np.eye(2), 1), ValueError, "one shape"),
    (lambda: fe3d.natural_frequencies(np.eye(8), np.eye(8), 3), ValueError, "at most"),
])
def test_bad_input_is_named(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_more_zero_modes_than_declared_is_an_error():
    # A free beam declared constrained (n_rigid=0), or with five rigid modes: K held at the
    # declared degrees of freedom is singular, and the solver says so instead of returning
    # zero or garbage frequencies.
    K, M = fe3d.beam_matrices(*BEAM, 4)
    for n_rigid in (0, 5):
        with pytest.raises(fe3d.SingularMatrixError, match="more zero-frequency modes"):
            fe3d.natural_frequencies(K, M, 3, n_rigid=n_rigid)


def test_a_matrix_singular_to_working_precision_is_refused_without_a_zero_pivot():
    # Whether SuperLU finds an exactly zero pivot in a singular matrix is decided by rounding
    # (the BLAS kernel), so the refined solve checks its result: max|A| max|x| / max|b| is a
    # lower bound of kappa_inf(A), and above 1 / (64 eps) = 7e13 the matrix is singular to
    # working precision. diag(1, 1e-17) has nonzero pivots (no SuperLU error) and kappa 1e17:
    # refused; diag(1, 1e-12) (kappa 1e12, a fine mesh's order) is solved exactly.
    b = np.ones((2, 1))
    with pytest.raises(fe3d.SingularMatrixError, match="working precision"):
        fe3d._RefinedLU([(1.0, np.diag([1.0, 1e-17]))]).solve(b)
    x = fe3d._RefinedLU([(1.0, np.diag([1.0, 1e-12]))]).solve(b)
    np.testing.assert_allclose(x, [[1.0], [1e12]], rtol=4 * np.finfo(float).eps, atol=0)
