"""Non-uniform beams: SteppedBeam (uniform segments from the root), its tapered constructor, and
the verification of issue 21 against independent finite-element models.

References: the uniform beam's closed forms (equal segments, split segments), the rigid bodies'
mass properties, and two finite-element models that share no code with flexsat: tests/support/fe3d.py
(Hermite elements with C1 bubbles, rods with Legendre bubbles; its stepped beams and tip bodies)
and the planar model below (fe3d's bending element, a rigid hub, rigid axial motion).
"""

import math

import numpy as np
import pytest
import scipy.sparse

import fe3d
from appendages import Beam, SteppedBeam, TipBody
from spacecraft import Hub, Mount, Spacecraft


def _tube(length, outer, wall, density=2700.0, E=7e10, **kw):
    return Beam.tube(length, outer, wall, density, E, **kw)


def _segments():
    return [_tube(1.2, 0.06, 0.003), _tube(0.8, 0.04, 0.002),
            _tube(1.5, 0.03, 0.001, 1600.0, 1.2e11)]


def assert_matrices_close(A, B, rtol):
    """Each matrix of A within rtol of the largest entry of B's matrix at that point (entries
    of W span many orders: a coupling of 1e-10 beside a diagonal of 1)."""
    scale = np.abs(B).max(axis=(-2, -1), keepdims=True)
    assert np.all(np.abs(A - B) <= rtol * scale), np.max(np.abs(A - B) / scale)


J_TIP = np.array([[0.02, 0.001, 0.0], [0.001, 0.03, 0.002], [0.0, 0.002, 0.04]])


# -- limiting cases -----------------------------------------------------------------------------
@pytest.mark.slow
def test_equal_segments_are_the_uniform_beam():
    """Three equal segments of the uniform beam: W to 1e-13, its free-free, cantilever and zero
    frequencies to 1e-12 (the closed forms of appendages.beam; measured 2e-13)."""
    beam = Beam(2.0, 3.0, 0.5)
    stepped = SteppedBeam([Beam(0.5, 3.0, 0.5), Beam(0.9, 3.0, 0.5), Beam(0.6, 3.0, 0.5)])
    s = np.array([1e-6j, 0.3 + 2j, 20j, 1 + 300j, 1e6 * (1 + 1j)])
    assert_matrices_close(stepped.W(s), beam.W(s), 1e-13)
    np.testing.assert_allclose(stepped.natural_frequencies(6), beam.natural_frequencies(6),
                               rtol=1e-12)
    np.testing.assert_allclose(stepped.cantilever_frequencies(6),
                               beam.cantilever_frequencies(6), rtol=1e-12)
    for r in (1, 2, 4):
        np.testing.assert_allclose(stepped.zeros(r, 3), beam.zeros(r, 3), rtol=1e-12)
    assert stepped.mass == pytest.approx(beam.mass, rel=1e-15)
    assert stepped.inertia == pytest.approx(beam.inertia, rel=1e-14)


def test_a_segment_split_in_two_equal_halves_gives_the_same_W():
    """W and W6 of [A, B] and [A, B/2, B/2] agree to 1e-13, with a tip body."""
    a, b = _tube(1.2, 0.06, 0.003), _tube(1.6, 0.04, 0.002)
    half = _tube(0.8, 0.04, 0.002)
    tip = TipBody(1.5, J_TIP, (0.1, 0.0, -0.03))
    s = np.array([0.4j, 2 + 15j, 300j, 1e4 * (1 + 1j)])
    one, two = SteppedBeam([a, b], tip=tip), SteppedBeam([a, half, half], tip=tip)
    assert_matrices_close(two.W6(s), one.W6(s), 1e-13)
    planar = TipBody(1.5, 0.04, 0.1)
    assert_matrices_close(SteppedBeam([a, half, half], tip=planar).W(s),
                          SteppedBeam([a, b], tip=planar).W(s), 1e-13)


def test_rigid_limit_symmetry_and_no_overflow():
    """s^2 W(s) -> M_rr^-1 (the segments' and body's rigid mass about the root, from their
    closed-form sums) to 1e-12 at s = 1e-7 j, planar and three-axis; W symmetric and
    W(conj s) = conj W(s); finite at |s| = 1e8 (no transfer matrix is multiplied)."""
    segments = _segments()
    tip = TipBody(1.5, J_TIP, (0.1, 0.05, -0.03))
    beam = SteppedBeam(segments, tip=tip)
    m = sum(seg.mass for seg in segments) + 1.5
    x = np.cumsum([0.0] + [seg.length for seg in segments])
    S = sum(seg.mass * (x[k] + seg.length / 2) for k, seg in enumerate(segments))
    S += 1.5 * (x[-1] + 0.1)
    assert beam.mass == pytest.approx(m, rel=1e-15)
    assert beam.first_moment == pytest.approx(S, rel=1e-14)
    s = 1e-7j
    np.testing.assert_allclose(s**2 * beam.W6(s), np.linalg.inv(beam.rigid_mass_matrix6),
                               rtol=1e-12, atol=1e-12 * np.abs(np.linalg.inv(
                                   beam.rigid_mass_matrix6)).max())
    planar = SteppedBeam(segments, tip=TipBody(1.5, 0.04, 0.1))
    np.testing.assert_allclose(s**2 * planar.W(s), np.linalg.inv(planar.rigid_mass_matrix),
                               rtol=1e-12, atol=0)
    s = np.array([0.3 + 2j, 5j + 1, 40j, 2 - 300j])
    for W, W_conj in ((beam.W6(s), beam.W6(np.conj(s))), (planar.W(s), planar.W(np.conj(s)))):
        np.testing.assert_array_equal(W, np.swapaxes(W, -1, -2))
        np.testing.assert_allclose(W_conj, np.conj(W), rtol=1e-13, atol=0)
    for W in (beam.W6(np.array([1e8j, 1e8 * (1 + 1j)])),
              planar.W(np.array([1e8j, 1e8 * (1 + 1j)]))):
        assert np.all(np.isfinite(W))


@pytest.mark.parametrize("change, name", [
    (lambda segs: segs + [Beam(1.0, 1.0, 1.0)], "segments\\[3\\].torsional_inertia"),
    (lambda segs: [Beam(1.0, 1.0, 1.0, torsional_inertia=1e-3)] + segs,
     "segments\\[1\\].torsional_stiffness"),
    (lambda segs: segs[:1] + [Beam.tube(1.0, 0.05, 0.002, 2700.0, 7e10,
                                        damping_ratio=0.01)], "segments\\[1\\].damping_ratio"),
    (lambda segs: segs[:1] + [Beam(1.0, 1.0, 1.0, tip=TipBody(1.0, 0.0))], "segments\\[1\\].tip"),
    (lambda segs: [], "at least one"),
])
def test_bad_segments_are_refused_by_name(change, name):
    with pytest.raises(ValueError, match=name):
        SteppedBeam(change(_segments()))


def test_segments_must_be_beams():
    with pytest.raises(TypeError, match="segments"):
        SteppedBeam(Beam(1.0, 1.0, 1.0))
    with pytest.raises(TypeError, match=r"segments\[1\]"):
        SteppedBeam([Beam(1.0, 1.0, 1.0), (1.0, 1.0, 1.0)])
    with pytest.raises(TypeError, match="tip"):
        SteppedBeam([Beam(1.0, 1.0, 1.0)], tip=3.0)


@pytest.mark.parametrize("kwargs, name", [
    ({"section": "square"}, "section"),
    ({"root_dimensions": {"diameter": 0.1}}, "root_dimensions"),
    ({"tip_dimensions": {"outer_diameter": -0.1, "wall_thickness": 0.001}},
     "tip_dimensions\\['outer_diameter'\\]"),
    ({"n_segments": 0}, "n_segments"),
])
def test_bad_tapered_arguments_are_refused_by_name(kwargs, name):
    args = dict(section="tube", root_dimensions={"outer_diameter": 0.1, "wall_thickness": 0.002},
                tip_dimensions={"outer_diameter": 0.05, "wall_thickness": 0.001},
                density=2700.0, youngs_modulus=7e10)
    n = kwargs.pop("n_segments", 8)
    args.update(kwargs)
    with pytest.raises((TypeError, ValueError), match=name):
        SteppedBeam.tapered(3.0, n, **args)


@pytest.mark.slow
def test_tapered_beam_converges_like_n_squared():
    """A linearly tapered tube as n midpoint segments: the first three free-free frequencies
    converge like n^-2 (midpoint rule of a smooth variation): the differences between n and 2n
    fall by 4 to within 10 % (measured 3.99-4.01 from n = 8 to 64)."""
    def freqs(n):
        return SteppedBeam.tapered(
            3.0, n, section="tube",
            root_dimensions={"outer_diameter": 0.1, "wall_thickness": 0.003},
            tip_dimensions={"outer_diameter": 0.04, "wall_thickness": 0.001},
            density=2700.0, youngs_modulus=7e10).natural_frequencies(3)
    w = [freqs(n) for n in (8, 16, 32)]
    ratio = np.abs(w[0] - w[1]) / np.abs(w[1] - w[2])
    assert np.all((3.6 < ratio) & (ratio < 4.4))


@pytest.mark.slow
@pytest.mark.parametrize("method, bound", [("craig-bampton", 1e-6), ("residual", 1e-8),
                                           ("free-free", 5e-3)])
def test_truncations_converge_to_the_stepped_beam(method, bound):
    """W of 4 and 24 modes against the exact W over the first modes' band: the error falls and
    the larger model is within the bound (measured 2e-7, 4e-10, 1e-3)."""
    beam = SteppedBeam(_segments(), tip=TipBody(1.5, 0.04, 0.1))
    w1 = beam.natural_frequencies(1)[0]
    s = 1j * np.linspace(0.05, 3.0, 7) * w1 + 0.01 * w1
    exact = beam.W(s)
    errors = [np.abs(beam.truncated(n, method=method).W(s) - exact).max() / np.abs(exact).max()
              for n in (4, 24)]
    assert errors[1] < errors[0] and errors[1] < bound


@pytest.mark.slow
def test_three_axis_truncation_converges_to_W6():
    beam = SteppedBeam(_segments(), tip=TipBody(1.5, J_TIP, (0.1, 0.05, -0.03)))
    w1 = beam.natural_frequencies6(1)[0]
    s = 1j * np.linspace(0.05, 3.0, 5) * w1 + 0.01 * w1
    exact = beam.W6(s)
    errors = [np.abs(beam.truncated(n).W6(s) - exact).max() / np.abs(exact).max()
              for n in (6, 36)]
    assert errors[1] < errors[0] and errors[1] < 1e-5


# -- the independent finite-element references --------------------------------------------------
def test_W6_against_the_3d_finite_element_model():
    """fe3d's stepped beam with the tip body's mass matrix at its last node (its own
    derivation): W6 converges to flexsat's, the differences falling by ~2^8 per halving of
    the elements (degree-5 elements); 8 elements per segment agree to 1e-10 up to 800 rad/s
    (measured 9e-12)."""
    segments = _segments()
    tip = TipBody(1.5, J_TIP, (0.1, 0.05, -0.03))
    spec = fe3d.TipSpec(1.5, J_TIP, np.array([0.1, 0.05, -0.03]))
    s = np.array([0.5j, 3 + 10j, 40j, 150j + 2, 800j])
    W6 = SteppedBeam(segments, tip=tip).W6(s)
    errors = []
    for n in (2, 8):
        Wfe = fe3d.appendage_root_compliance(segments, n, s, spec)
        errors.append(np.max(np.abs(Wfe - W6).max(axis=(1, 2)) / np.abs(W6).max(axis=(1, 2))))
    assert errors[1] < 1e-10 < errors[0]


def _planar_fe(hub_mass, hub_inertia, booms, n_elements):
    """Planar finite-element model of a rigid hub carrying stepped booms with tip bodies.

    Hub coordinates (X, Y, theta) of its centre of mass. A boom mounted at p (hub axes) along
    the unit vector e = (cos a, sin a), n = (-sin a, cos a): its root moves by
    u0 = e . (X - theta p_y, Y + theta p_x) along the boom (rigidly: the boom is inextensible,
    its whole mass, tip body included, moves axially with the root), v0 = n . (...) across it,
    and turns by theta. Bending: fe3d's degree-5 element per element (nodal (v, dv/dx), then
    bubbles); the tip body adds [[m, m a], [m a, J + m a^2]] at the last node (a its offset
    along the boom). Returns K, M with the hub's coordinates first.
    """
    blocks = []
    for segments, (m_t, J_t, a_t), p, angle in booms:
        counts = [n_elements] * len(segments)
        n_el = sum(counts)
        nb = 2
        n = 2 * (n_el + 1) + nb * n_el
        K, M = np.zeros((n, n)), np.zeros((n, n))
        e = 0
        for seg, count in zip(segments, counts):
            Ke, Me = fe3d.bending_matrices(seg.length / count, seg.bending_stiffness,
                                           seg.linear_density, order=5)
            for _ in range(count):
                dofs = np.concatenate([2 * e + np.arange(4),
                                       2 * (n_el + 1) + nb * e + np.arange(nb)])
                K[np.ix_(dofs, dofs)] += Ke
                M[np.ix_(dofs, dofs)] += Me
                e += 1
        last = 2 * n_el + np.arange(2)
        M[np.ix_(last, last)] += np.array([[m_t, m_t * a_t], [m_t * a_t, J_t + m_t * a_t**2]])
        mass = sum(seg.mass for seg in segments) + m_t
        c, s_ = math.cos(angle), math.sin(angle)
        root = np.array([[-s_, c, -s_ * -p[1] + c * p[0]], [0.0, 0.0, 1.0]])  # (v0, phi0)
        axial = np.array([c, s_, c * -p[1] + s_ * p[0]])                        # u0
        blocks.append((K, M, root, axial, mass))
    n = 3 + sum(K.shape[0] - 2 for K, *_ in blocks)
    K_all, M_all = np.zeros((n, n)), np.zeros((n, n))
    M_all[:3, :3] = np.diag([hub_mass, hub_mass, hub_inertia])
    start = 3
    for K, M, root, axial, mass in blocks:
        nb = K.shape[0]
        P = np.zeros((nb, n))
        P[:2, :3] = root
        P[2:, start:start + nb - 2] = np.eye(nb - 2)
        K_all += P.T @ K @ P
        M_all += P.T @ M @ P + mass * np.outer(np.pad(axial, (0, n - 3)), np.pad(axial, (0, n - 3)))
        start += nb - 2
    return scipy.sparse.csr_array(K_all), scipy.sparse.csr_array(M_all)


@pytest.mark.slow
def test_planar_coupled_frequencies_against_a_finite_element_model():
    """A 40 kg hub with two stepped booms carrying tip bodies (opposite sides, one tilted):
    flexsat's exact coupled frequencies (Wittrick-Williams on the exact W of each boom) against
    the planar finite-element model: the differences fall by ~2^8 per halving of the elements
    and are below 1e-9 with 8 elements per segment."""
    segs_a = [Beam(1.0, 400.0, 1.2), Beam(1.5, 150.0, 0.7), Beam(0.8, 60.0, 0.4)]
    segs_b = [Beam(2.0, 300.0, 1.0), Beam(1.0, 90.0, 0.5)]
    tips = [(2.0, 0.05, 0.1), (0.8, 0.01, 0.0)]
    mounts = [((0.4, 0.1), 0.0), ((-0.3, -0.2), math.pi - 0.3)]
    sc = Spacecraft(Hub(40.0, 6.0), [
        Mount(SteppedBeam(segs, tip=TipBody(*tip)), p, a)
        for segs, tip, (p, a) in zip((segs_a, segs_b), tips, mounts)])
    exact = sc.natural_frequencies(6)
    errors = []
    for n in (2, 8):
        K, M = _planar_fe(40.0, 6.0, [(segs, tip, p, a) for segs, tip, (p, a)
                                      in zip((segs_a, segs_b), tips, mounts)], n)
        fe = fe3d.natural_frequencies(K, M, 6, n_rigid=3)
        errors.append(np.abs(fe / exact - 1).max())
    assert errors[1] < 1e-9 < errors[0]


@pytest.mark.slow
def test_three_axis_coupled_frequencies_against_the_3d_finite_element_model():
    """A three-axis hub with two stepped tubes carrying off-axis tip bodies: flexsat's exact
    coupled frequencies against fe3d's spacecraft, 8 elements per segment: 1e-9."""
    hub_inertia = np.array([[8.0, 0.2, 0.0], [0.2, 10.0, 0.1], [0.0, 0.1, 12.0]])
    booms = []
    for k, (R, position) in enumerate(((np.eye(3), (0.5, 0.0, 0.1)),
                                       (np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0],
                                                  [0.0, 0.0, 1.0]]), (0.0, 0.6, -0.1)))):
        segments = _segments()[k:]
        J = J_TIP * (1 + k)
        offset = np.array([0.1, 0.05 * k, -0.03])
        booms.append((segments, TipBody(1.5 - k, J, offset), fe3d.TipSpec(1.5 - k, J, offset),
                      position, R))
    sc = Spacecraft(Hub(60.0, hub_inertia), [
        Mount(SteppedBeam(segs, tip=tip), pos, orientation=R) for segs, tip, _, pos, R in booms])
    exact = sc.natural_frequencies(8)
    K, M = fe3d.appendage_spacecraft_matrices(
        60.0, hub_inertia, [(segs, spec, pos, R) for segs, _, spec, pos, R in booms], 8)
    fe = fe3d.natural_frequencies(K, M, 8)
    np.testing.assert_allclose(fe, exact, rtol=1e-9)


# -- the member matrices ----------------------------------------------------------------------
def _member_mpmath(x, dps=50):
    """The Bernoulli-Euler member's six entries (EJ = L = 1) by solving the boundary-value
    problem in 50 digits: the end motions of ``a cosh + b sinh + c cos + d sin`` and the end
    loads ``(EJ w'''(0), -EJ w''(0), -EJ w'''(L), EJ w''(L))``, K = loads (motions)^-1."""
    import mpmath as mp

    with mp.workdps(dps):
        x = mp.mpc(x)

        def row(t, d):
            c, s, C, S = mp.cos(x * t), mp.sin(x * t), mp.cosh(x * t), mp.sinh(x * t)
            hyper = (C, S) if d % 2 == 0 else (S, C)
            trig = [(c, s), (-s, c), (-c, -s), (s, -c)][d % 4]
            return [x**d * v for v in (*hyper, *trig)]

        A = mp.matrix([row(0, 0), row(0, 1), row(1, 0), row(1, 1)])
        B = mp.matrix([row(0, 3), [-v for v in row(0, 2)], [-v for v in row(1, 3)], row(1, 2)])
        K = B * A**-1
        return np.array([[complex(K[i, j]) for j in range(4)] for i in range(4)])


@pytest.mark.parametrize("s", [1e-3j, 0.3 + 2j, 5j, 17 + 40j, 100j, 1e3 * (1 + 1j), 2.9j])
def test_member_matrix_against_50_digits(s):
    """appendages.members' scaled closed form and series (|x| < 2) against the boundary-value
    problem: 1e-14 of the matrix, except where x is real and large (rounding of x itself,
    ~ x eps: 1e-13 at x = 13)."""
    from appendages import members

    EJ, L, rho = 2.3, 1.7, 0.9
    K = members.bending_member(L, EJ, rho, np.array([s]))[0]
    x = (-(s**2) * rho * L**4 / EJ + 0j) ** 0.25
    scale = np.array([1.0, L, 1.0, L])     # K_vv ~ EJ/L^3, K_v theta ~ EJ/L^2, ...
    reference = _member_mpmath(x) * EJ / L**3 * np.outer(scale, scale)
    assert np.abs(K - reference).max() <= 1e-13 * np.abs(reference).max()


def test_member_dynamic_part_is_the_consistent_mass_at_rest():
    """(K(s) - K0)/s^2 -> the Hermite consistent mass matrix (Przemieniecki eq. 11.31) and
    the rods' mu L [[1/3, 1/6], [1/6, 1/3]], to 1e-15, at s = 1e-9 j."""
    from appendages import members

    L, rho = 1.7, 0.9
    M = members.bending_member(L, 2.3, rho, np.array([1e-9j]), part="dynamic")[0].real
    hermite = rho * L / 420 * np.array([[156, 22 * L, 54, -13 * L], [22 * L, 4 * L * L, 13 * L,
                                                                      -3 * L * L],
                                        [54, 13 * L, 156, -22 * L],
                                        [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    np.testing.assert_allclose(M, hermite, rtol=1e-15, atol=1e-15 * np.abs(hermite).max())
    R = members.rod_member(1.3, 2.0, 0.7, np.array([1e-9j]), part="dynamic")[0].real
    np.testing.assert_allclose(R, 0.7 * 1.3 * np.array([[1 / 3, 1 / 6], [1 / 6, 1 / 3]]),
                               rtol=1e-15)


def test_member_counts_are_the_clamped_clamped_frequencies():
    """A member's clamped-clamped frequencies are the roots of cos x cosh x = 1 (the free-free
    beam's, appendages.characteristic_roots) and k pi/tau for a rod: the counts step there."""
    from appendages import characteristic_roots, members

    x = characteristic_roots("free-free", 40)
    w = x**2                                          # EJ = rho A = L = 1
    below, above = w * (1 - 1e-12), w * (1 + 1e-12)
    np.testing.assert_array_equal(members.bending_clamped_count(1.0, 1.0, 1.0, below),
                                  np.arange(40))
    np.testing.assert_array_equal(members.bending_clamped_count(1.0, 1.0, 1.0, above),
                                  np.arange(1, 41))
    k = np.arange(1, 11) * math.pi
    np.testing.assert_array_equal(members.rod_clamped_count(1.0, 1.0, 1.0, k * (1 + 1e-12)),
                                  np.arange(1, 11))
