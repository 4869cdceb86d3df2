"""Tests of controllers.modal_form: block-diagonal form with a bounded transformation.

References: the eigenvalues of the blocks are those of A (similarity), closed-form spectra of
the test matrices (a damped oscillator's s = -zeta w +- i w sqrt(1 - zeta^2), a Jordan block's
single eigenvalue), and the defining identity A = V diag(A_j) V^-1 checked to round-off.
"""

import numpy as np
import pytest

from controllers.modal_form import DEFAULT_MAX_COUPLING, block_diagonal_form

EPS = np.finfo(float).eps


def assemble(form):
    """blockdiag(A_j) as a dense matrix."""
    n = form.V.shape[0]
    M = np.zeros((n, n))
    for a, b, block in zip(form.starts[:-1], form.starts[1:], form.blocks):
        M[a:b, a:b] = block
    return M


def oscillators(rng, omegas, zetas, n_rigid=0, condition=4.0):
    """Damped oscillators (normal 2 x 2 blocks) and double integrators, in a random basis
    of condition number ``condition``."""
    n = 2 * (len(omegas) + n_rigid)
    A = np.zeros((n, n))
    for i, (w, z) in enumerate(zip(omegas, zetas)):
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[-z * w, w * np.sqrt(1 - z * z)],
                                               [-w * np.sqrt(1 - z * z), -z * w]]
    for i in range(len(omegas), len(omegas) + n_rigid):
        A[2 * i, 2 * i + 1] = 1.0
    Q1, _ = np.linalg.qr(rng.standard_normal((n, n)))
    Q2, _ = np.linalg.qr(rng.standard_normal((n, n)))
    S = Q1 @ np.diag(np.geomspace(1.0, condition, n)) @ Q2
    return S @ A @ np.linalg.inv(S)


def check_factorisation(A, form):
    """A = V blockdiag V^-1 to round-off: the backward error of the Schur form (~n eps |A|)
    times the condition number of V (each Sylvester step is backward stable)."""
    n = A.shape[0]
    error = np.abs(form.V @ assemble(form) @ form.V_inv - A).max()
    assert error <= 10 * n * EPS * form.condition * np.abs(A).max()
    np.testing.assert_allclose(form.V @ form.V_inv, np.eye(n), rtol=0,
                               atol=10 * n * EPS * form.condition)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_separated_modes_decouple_into_2x2_blocks(seed):
    """Distinct lightly damped modes (0.1 to 1000 rad/s) split into one 2 x 2 block each,
    with the modes' eigenvalues, through a transformation of moderate condition (the hidden
    basis has condition 4; the 2 x 2 blocks of the Schur form add their own non-normality)."""
    rng = np.random.default_rng(seed)
    w = np.sort(np.exp(rng.uniform(np.log(0.1), np.log(1000.0), 12)))
    zeta = np.exp(rng.uniform(np.log(1e-3), np.log(0.05), 12))
    A = oscillators(rng, w, zeta)
    form = block_diagonal_form(A)
    assert list(form.sizes) == [2] * 12
    check_factorisation(A, form)
    assert form.condition < 1e4
    found = np.sort_complex(np.concatenate([np.linalg.eigvals(b) for b in form.blocks]))
    exact = np.sort_complex(np.concatenate([-zeta * w + 1j * w * np.sqrt(1 - zeta ** 2),
                                            -zeta * w - 1j * w * np.sqrt(1 - zeta ** 2)]))
    # Eigenvalues of a similarity: ~cond(S) eps |A| apart.
    np.testing.assert_allclose(found, exact, rtol=0, atol=1e3 * EPS * np.abs(A).max())


def test_rigid_bodies_stay_whole():
    """Two free rigid bodies (double integrators: two 2 x 2 Jordan blocks at s = 0) cannot
    be split from each other by a bounded transformation: their four states end in blocks
    whose eigenvalues are all ~0 (perturbed by round-off, ~sqrt(eps |A|)), and the
    factorisation holds."""
    rng = np.random.default_rng(7)
    A = oscillators(rng, [0.5, 3.0, 40.0], [0.01, 0.02, 0.005], n_rigid=2)
    form = block_diagonal_form(A)
    check_factorisation(A, form)
    near_zero = [b for b in form.blocks if np.abs(np.linalg.eigvals(b)).max() < 1e-4]
    assert sum(b.shape[0] for b in near_zero) == 4
    assert form.condition < 1e4


def test_close_coupled_eigenvalues_form_a_cluster():
    """Two oscillators 1e-9 rad/s apart and coupled (nearly defective): decoupling them
    would need max|X| ~ 1e9, so they share one 4 x 4 block; the transformation stays
    bounded."""
    rng = np.random.default_rng(21)
    A = np.zeros((6, 6))
    A[0:2, 0:2] = [[0, 1], [-9.0, -0.01]]
    A[2:4, 2:4] = [[0, 1], [-(3.0 + 1e-9) ** 2, -0.01]]
    A[4:6, 4:6] = [[0, 1], [-0.25, -0.02]]
    A[1, 2] = 1.0
    S = rng.standard_normal((6, 6))
    A = S @ A @ np.linalg.inv(S)
    form = block_diagonal_form(A)
    assert sorted(form.sizes) == [2, 4]
    check_factorisation(A, form)
    assert form.condition < 1e6


def test_exactly_repeated_decoupled_eigenvalues_split():
    """A = diag(1, 1, 1): the Sylvester equations are singular but their right-hand sides
    are zero; the blocks split and V stays orthogonal."""
    form = block_diagonal_form(np.eye(3))
    assert list(form.sizes) == [1, 1, 1]
    np.testing.assert_allclose(form.V @ form.V.T, np.eye(3), rtol=0, atol=1e-15)


def test_jordan_block_stays_one_block():
    """A single 5 x 5 Jordan block: one eigenvalue of multiplicity 5 with one eigenvector;
    no bounded transformation splits it."""
    A = -np.eye(5) + np.eye(5, k=1)
    form = block_diagonal_form(A)
    assert list(form.sizes) == [5]
    check_factorisation(A, form)


def test_bound_trades_block_size_for_condition():
    """A smaller bound on the elementary transformations gives larger blocks and a
    better-conditioned V (Bavely and Stewart's trade-off)."""
    rng = np.random.default_rng(5)
    A = oscillators(rng, np.geomspace(1.0, 1.3, 8), np.full(8, 0.01), condition=30.0)
    loose = block_diagonal_form(A, max_coupling=DEFAULT_MAX_COUPLING)
    tight = block_diagonal_form(A, max_coupling=2.0)
    assert max(tight.sizes) > max(loose.sizes)
    assert tight.condition < loose.condition
    check_factorisation(A, loose)
    check_factorisation(A, tight)


def test_empty_and_scalar():
    assert block_diagonal_form(np.zeros((0, 0))).blocks == []
    form = block_diagonal_form([[2.5]])
    assert form.blocks[0][0, 0] == 2.5 and form.condition == 1.0


@pytest.mark.parametrize("A, match", [
    (np.ones((2, 3)), "square"),
    ([[np.nan]], "finite"),
])
def test_errors(A, match):
    with pytest.raises(ValueError, match=match):
        block_diagonal_form(A)
    with pytest.raises(ValueError, match="max_coupling must be positive"):
        block_diagonal_form(np.eye(2), max_coupling=-1.0)


# --------------------------------------------------------------------------
# Accurate products and the refined cluster blocks (against exact arithmetic)
# --------------------------------------------------------------------------

def exact_product(X, Y):
    """X @ Y in exact rational arithmetic, rounded once to float64."""
    from fractions import Fraction
    Xf = [[Fraction(float(v)) for v in row] for row in X]
    Yf = [[Fraction(float(v)) for v in col] for col in np.asarray(Y).T]
    return np.array([[float(sum(a * b for a, b in zip(row, col))) for col in Yf]
                     for row in Xf])


@pytest.mark.parametrize("k", [3, 50, 400])
def test_accurate_product_first_part_is_exact(k):
    """P1 of the error-free splitting is X1 @ Y1 exactly (every product and partial sum
    representable), and P1 + P2 is X @ Y to ~2 k eps 2^-bits |X| |Y| (the remainder's
    float64 products), far below one float64 product's k eps |X| |Y|: checked on a product
    that cancels (rows of X orthogonal to columns of Y up to 1e-12) with entries over 12
    decades."""
    from controllers.modal_form import _accurate_product, _split
    rng = np.random.default_rng(k)
    X = rng.standard_normal((4, k)) * 10.0 ** rng.uniform(-6, 6, (4, 1))
    Y = rng.standard_normal((k, 3)) * 10.0 ** rng.uniform(-6, 6, (1, 3))
    Y -= X.T @ np.linalg.lstsq(X.T, Y, rcond=None)[0]    # X @ Y ~ 1e-12 |X| |Y|
    P1, P2 = _accurate_product(X, Y)
    bits = (53 - int(np.ceil(np.log2(k)))) // 2
    X1, X2 = _split(X, 1, bits)
    Y1, Y2 = _split(Y, 0, bits)
    assert np.array_equal(X1 + X2, X) and np.array_equal(Y1 + Y2, Y)
    np.testing.assert_array_equal(P1, exact_product(X1, Y1))
    bound = 4 * k * EPS * 2.0 ** -bits * (np.abs(X) @ np.abs(Y))
    assert np.all(np.abs(P1 + P2 - exact_product(X, Y)) <= bound + EPS * np.abs(P1 + P2))


def stiff_system_with_rigid_bodies(seed):
    """Two free rigid bodies, modes from 0.3 to 1000 rad/s: ||A|| ~ 1e3, the rigid bodies'
    blocks ~1."""
    rng = np.random.default_rng(seed)
    return oscillators(rng, [0.3, 2.0, 40.0, 1000.0], [0.01, 0.02, 0.005, 0.001], n_rigid=2)


def exact_diagonal_block(A, V, a, b):
    """(V^-1 A V)[a:b, a:b] for the float64 A and V, in 60-digit arithmetic."""
    import mpmath
    with mpmath.workdps(60):
        Vm = mpmath.matrix(V.tolist())
        M = mpmath.inverse(Vm) * mpmath.matrix(A.tolist()) * Vm
        return np.array([[float(M[i, j]) for j in range(a, b)] for i in range(a, b)])


@pytest.mark.parametrize("seed", [0, 3])
def test_rigid_blocks_are_the_exact_blocks_of_the_transformation(monkeypatch, seed):
    """The Schur form keeps the two rigid bodies in one 4 x 4 cluster, or splits them into two
    near-defective 2 x 2 blocks (eigenvalues ~1e-7 next to entries ~1), too close to
    decouple to first order, which the refinement merges into one 4 x 4 block (seed 3 on
    most BLAS kernels; the merge itself is tested on constructed blocks below).
    The rigid bodies' block equals the diagonal block of V^-1 A V (the exact similarity of
    the float64 V) to ~eps |T_c|: its rounding (eps) plus the rounding of the correction
    through V^-1 (cond(V) eps times the correction ~ n eps ||A|| cond(V)).  Without the
    refinement the rigid blocks carry the Schur form's backward error ~eps ||A|| cond(V),
    ~1e3 times more here: checked too, so that this test can fail."""
    import controllers.modal_form as modal_form
    A = stiff_system_with_rigid_bodies(seed)
    n = A.shape[0]
    form = block_diagonal_form(A)
    monkeypatch.setattr(modal_form, "_refine_blocks",
                        lambda A, V, inverse, starts, blocks, T:
                        (starts, blocks, None, np.zeros(0, dtype=int), None, None))
    raw = block_diagonal_form(A)

    def rigid(f):
        return [j for j, block in enumerate(f.blocks)
                if np.abs(np.linalg.eigvals(block)).max() < 1e-4]
    # Which of the two the Schur form gives is decided by rounding (by the BLAS kernel: seed
    # 3 gave a 4 x 4 cluster on some); either way the refined form has one 4 x 4 block.
    assert sorted(raw.sizes[j] for j in rigid(raw)) in ([4], [2, 2])
    assert [form.sizes[j] for j in rigid(form)] == [4]
    (j,) = rigid(form)
    a, b = form.starts[j], form.starts[j + 1]
    exact = exact_diagonal_block(A, form.V, a, b)
    correction = n * EPS * np.abs(A).max() * form.condition
    tolerance = 4 * EPS * np.abs(exact).max() + 4 * form.condition * EPS * correction
    assert np.abs(form.blocks[j] - exact).max() <= tolerance
    for j in rigid(raw):
        a, b = raw.starts[j], raw.starts[j + 1]
        exact = exact_diagonal_block(A, raw.V, a, b)
        assert np.abs(raw.blocks[j] - exact).max() > 10 * tolerance
    check_factorisation(A, form)


def exact_similarity(A, V, Z_right, Z_left):
    """(I - Z) V^-1 A V (I + Z) in 60-digit arithmetic, Z given by its products (the
    form's ``left`` and ``right``)."""
    import mpmath
    with mpmath.workdps(60):
        Vm = mpmath.matrix(V.tolist())
        M = mpmath.inverse(Vm) * mpmath.matrix(A.tolist()) * Vm
        n = A.shape[0]
        M = mpmath.matrix(Z_left.tolist()) * M * mpmath.matrix(Z_right.tolist())
        return np.array([[float(M[i, j]) for j in range(n)] for i in range(n)])


@pytest.mark.parametrize("seed", [0, 3])
def test_refined_blocks_are_decoupled_from_the_others(seed):
    """The off-diagonal couplings of the refined blocks (the rigid bodies'): ~eps ||A||
    cond(V) in the exact V^-1 A V of
    the float64 V (the Schur form's round-off, which the rigid bodies integrate), removed to
    first order by the corrected transformation V (I + Z): in the exact
    (I - Z) V^-1 A V (I + Z) they are O(|E| |Z|) plus the rounding of Z's entries (eps |Z|
    ||A|| ~ 1e-24 here); required below 1e-3 of the uncorrected ones, which must be there
    (so that this test can fail).  Seed 3 splits the two rigid bodies into blocks of their
    own, ~1e-7 apart: their mutual coupling would need |Z| ~ |E| / 1e-7, not a first-order
    correction, and stays (excluded here)."""
    A = stiff_system_with_rigid_bodies(seed)
    n = A.shape[0]
    form = block_diagonal_form(A)
    rigid = [j for j, block in enumerate(form.blocks)
             if np.abs(np.linalg.eigvals(block)).max() < 1e-4]
    rigid_states = np.concatenate([np.arange(form.starts[j], form.starts[j + 1])
                                   for j in rigid])
    assert set(rigid_states) <= set(form.coupled)
    eye = np.eye(n)
    before = exact_similarity(A, form.V, eye, eye)
    after = exact_similarity(A, form.V, form.right(eye), form.left(eye))
    mask = np.zeros((n, n), bool)
    mask[form.coupled, :] = mask[:, form.coupled] = True
    for a, b in zip(form.starts[:-1], form.starts[1:]):
        mask[a:b, a:b] = False
    mask[np.ix_(rigid_states, rigid_states)] = False    # seed 3: see the docstring
    coupling_before = np.abs(before[mask]).max()
    coupling_after = np.abs(after[mask]).max()
    assert coupling_before > 10 * EPS          # present: eps ||A|| cond(V) ~ 1e-12
    assert coupling_after <= 1e-3 * coupling_before


def test_blocks_too_close_to_decouple_are_merged_and_made_contiguous():
    """Two near-defective rigid blocks (eigenvalues +-1e-7, +-2e-7) coupled by 1e-10, with
    an oscillator between them: decoupling them would need |Z| ~ 1e-10 / 1e-7 = 1e-3, not a
    first-order correction, so _refine_blocks merges them into one 4 x 4 block placed first
    (V's columns permuted to [0, 1, 4, 5, 2, 3]); the merged block is the exact
    (V^-1 A V) block of the permuted V (to ~eps |T| plus cond(V) eps times the correction),
    and the corrected form reproduces A (check_factorisation's bound)."""
    import scipy.linalg
    from controllers.modal_form import BlockDiagonalForm, _Inverse, _refine_blocks
    T0 = np.zeros((6, 6))
    T0[0:2, 0:2] = [[1e-7, 1.0], [0.0, -1e-7]]
    T0[2:4, 2:4] = [[-0.01, 5.0], [-5.0, -0.01]]
    T0[4:6, 4:6] = [[2e-7, 0.8], [0.0, -2e-7]]
    T0[0:2, 4:6] = 1e-10
    rng = np.random.default_rng(11)
    V = np.eye(6) + 0.3 * rng.standard_normal((6, 6))
    A = V @ T0 @ np.linalg.inv(V)
    blocks = [T0[0:2, 0:2].copy(), T0[2:4, 2:4].copy(), T0[4:6, 4:6].copy()]
    lu = scipy.linalg.lu_factor(V)
    starts, blocks, perm, *coupling = _refine_blocks(
        A, V, _Inverse(lu, np.ones(6), None), np.array([0, 2, 4, 6]), blocks,
        scipy.linalg.block_diag(*blocks))
    assert list(np.diff(starts)) == [4, 2]
    np.testing.assert_array_equal(perm, [0, 1, 4, 5, 2, 3])
    form = BlockDiagonalForm(starts, blocks, V[:, perm], float(np.linalg.cond(V, 1)),
                             *coupling, _inverse=_Inverse(lu, np.ones(6), perm))
    exact = exact_diagonal_block(A, form.V, 0, 4)
    correction = 6 * EPS * np.abs(A).max() * form.condition
    tolerance = 4 * EPS * np.abs(exact).max() + 4 * form.condition * EPS * correction
    assert np.abs(form.blocks[0] - exact).max() <= tolerance
    assert abs(form.blocks[0][0, 2] - 1e-10) < 1e-14          # the coupling is kept
    check_factorisation(A, form)


@pytest.mark.parametrize("m, n", [(130, 70), (70, 130), (20, 30)])
def test_recursive_sylvester_solves_like_trsyl(m, n):
    """The recursive blocked solver (splits at 2 x 2 block boundaries, trsyl on the leaves)
    solves T11 X - X T22 = C with a residual of a backward-stable solve,
    <= 4 (m + n) eps (|T11| |X| + |X| |T22| + |C|) (max norms), and agrees with one trsyl
    call to the equation's conditioning times that (the two eliminate in different
    orders).  Schur forms of random matrices: many 2 x 2 blocks, so splits must avoid
    cutting them."""
    import scipy.linalg
    import scipy.linalg.lapack
    from controllers.modal_form import _sylvester_triangular
    rng = np.random.default_rng(m + n)
    T11 = scipy.linalg.schur(rng.standard_normal((m, m)), output="real")[0]
    T22 = scipy.linalg.schur(rng.standard_normal((n, n)) + 6 * np.eye(n), output="real")[0]
    C = rng.standard_normal((m, n))
    X, info = _sylvester_triangular(T11, T22, C)
    assert info == 0
    size = np.abs(T11).max() * np.abs(X).max() + np.abs(X).max() * np.abs(T22).max()
    residual = np.abs(T11 @ X - X @ T22 - C).max()
    assert residual <= 4 * (m + n) * EPS * (size + np.abs(C).max())
    X_lapack = scipy.linalg.lapack.dtrsyl(T11, T22, C, isgn=-1)[0]
    # sep(T11, T22) >= min |lambda_i - mu_j| / (departure); bound the difference by the
    # residuals over the smallest eigenvalue gap (both are ~eps-sized).
    gap = np.abs(np.linalg.eigvals(T11)[:, None] - np.linalg.eigvals(T22)[None, :]).min()
    assert np.abs(X - X_lapack).max() <= 1e3 * (m + n) * EPS * (size + 1) / gap


def test_times_block_triangular_is_the_product():
    """Q @ Y through trmm plus the columns with entries below the diagonal equals the plain
    product to round-off (n eps |Q| |Y| per entry), for an upper triangular Y with a few
    rotated columns, a full one and a strictly triangular one."""
    from controllers.modal_form import _times_block_triangular
    rng = np.random.default_rng(2)
    n = 60
    Q = rng.standard_normal((n, n))
    upper = np.triu(rng.standard_normal((n, n)))
    rotated = upper.copy()
    rotated[:, [7, 30, 31]] = rng.standard_normal((n, 3))
    for Y in (upper, rotated, rng.standard_normal((n, n))):
        bound = n * EPS * (np.abs(Q) @ np.abs(Y))
        assert np.all(np.abs(_times_block_triangular(Q, Y) - Q @ Y) <= bound)


def test_bartels_stewart_solves_large_pairs_like_the_kronecker_system():
    """Pairs of units with s t > _KRONECKER_MAX (here 20 x 12 = 240 states) are solved by
    Bartels-Stewart, whatever sizes the Schur form gives a particular matrix: a defective
    20-state cluster near s = 0 (nilpotent part 0.3) against a 12-state one at s = -1, and
    the same pair transposed (the form's column couplings). Z solves T1 Z - Z T2 = -E with
    the residual of a backward-stable solve, 4 (s + t) eps (|T1| + |T2|) |Z| (max norms),
    and equals the Kronecker system's solution to cond(I (x) T1 - T2^T (x) I) times that
    (measured: residuals 0.3 eps, differences 2 eps |Z|, cond 63). A pair whose eigenvalues
    overlap (sep ~1e-18: |Z| ~ 1e10) is no first-order correction for either solver: flagged,
    and zero."""
    import controllers.modal_form as modal_form
    from controllers.modal_form import _sylvester, _sylvester_kronecker
    rng = np.random.default_rng(4)
    s, t = 20, 12
    assert s * t > modal_form._KRONECKER_MAX
    T1 = np.triu(0.3 * rng.standard_normal((s, s)), 1) + np.diag(rng.uniform(-1e-3, 1e-3, s))
    T2 = -np.eye(t) + np.triu(0.3 * rng.standard_normal((t, t)), 1)
    near = np.diag(rng.uniform(-1e-3, 1e-3, t)) + np.triu(0.3 * rng.standard_normal((t, t)), 1)
    E = 1e-13 * rng.standard_normal((s, t))
    T1s, T2s, Es = np.stack([T1, T1.T, T1]), np.stack([T2, T2.T, near]), np.stack([E, -E, E])
    Z, ok = _sylvester(T1s, T2s, Es)
    Z_kronecker = _sylvester_kronecker(T1s, T2s, Es)
    np.testing.assert_array_equal(ok, [True, True, False])
    assert not np.any(Z[2])
    for k in range(2):
        size = (np.abs(T1s[k]).max() + np.abs(T2s[k]).max()) * np.abs(Z[k]).max()
        residual = np.abs(T1s[k] @ Z[k] - Z[k] @ T2s[k] + Es[k]).max()
        assert 0 < residual <= 4 * (s + t) * EPS * size
        kron = np.kron(np.eye(t), T1s[k]) - np.kron(T2s[k].T, np.eye(s))
        assert (np.abs(Z[k] - Z_kronecker[k]).max()
                <= np.linalg.cond(kron) * 4 * (s + t) * EPS * np.abs(Z[k]).max())
    assert np.abs(Z_kronecker[2]).max() > 1e6          # the overlapping pair: |Z| ~ 1e10


@pytest.mark.parametrize("kronecker_max", [None, 0, 10 ** 6])
def test_clusters_are_decoupled_from_other_eigenvalues_by_either_solver(monkeypatch,
                                                                        kronecker_max):
    """Five rigid bodies and five double poles at -1 (two defective groups of ten states) and
    an oscillator in a random basis; the Schur form splits each group into units of sizes
    that rounding decides (measured, by BLAS kernel: 10 + 10, 8 + 2 + 8 + 2), and the units'
    couplings are solved by Bartels-Stewart (every pair with _KRONECKER_MAX = 0), by the
    Kronecker system (every pair, 10^6) or as shipped (None). Either way the couplings of the
    refined blocks to the blocks of other eigenvalues, ~eps ||A|| cond(V) in the exact
    V^-1 A V of the float64 V (measured 1e-15 to 1e-14), are removed to first order: in the
    exact (I - Z) V^-1 A V (I + Z) they are O(|E| |Z|) (measured 3e-23 to 2e-22); required
    below 1e-3 of the uncorrected ones, which must be there (so that this test can fail: a
    Bartels-Stewart solve with a sign error leaves 2e-14). Couplings within one group (a
    unit beyond 8 states is not merged) are not first-order corrections and stay. The form
    reproduces A."""
    import scipy.linalg
    import controllers.modal_form as modal_form
    if kronecker_max is not None:
        monkeypatch.setattr(modal_form, "_KRONECKER_MAX", kronecker_max)
    rng = np.random.default_rng(1)
    blocks = ([np.array([[0.0, 1.0], [0.0, 0.0]])] * 5
              + [np.array([[-1.0, 1.0], [0.0, -1.0]])] * 5
              + [np.array([[-0.01, 3.0], [-3.0, -0.01]])])
    A = scipy.linalg.block_diag(*blocks)
    n = A.shape[0]
    S = np.linalg.qr(rng.standard_normal((n, n)))[0] @ np.diag(np.geomspace(1.0, 4.0, n))
    A = S @ A @ np.linalg.inv(S)
    form = block_diagonal_form(A)
    check_factorisation(A, form)
    group = np.empty(n)                       # 0: rigid bodies, -1: double poles, else 1 + j
    for j, (a, b) in enumerate(zip(form.starts[:-1], form.starts[1:])):
        eigenvalues = np.linalg.eigvals(form.blocks[j])
        group[a:b] = next((g for g in (0.0, -1.0) if np.abs(eigenvalues - g).max() < 1e-4),
                          1.0 + j)
    assert np.sum(group == 0.0) == 10 and np.sum(group == -1.0) == 10
    assert {0.0, -1.0} <= set(group[form.coupled])      # both groups refined
    eye = np.eye(n)
    before = exact_similarity(A, form.V, eye, eye)
    after = exact_similarity(A, form.V, form.right(eye), form.left(eye))
    mask = np.zeros((n, n), bool)
    mask[form.coupled, :] = mask[:, form.coupled] = True
    mask &= group[:, None] != group[None, :]
    coupling_before = np.abs(before[mask]).max()
    assert coupling_before > 4 * EPS
    assert np.abs(after[mask]).max() <= 1e-3 * coupling_before


def test_many_integrators_stay_apart(monkeypatch):
    """Forty integrators (eigenvalue 0, forty 1 x 1 blocks after the decoupling) and twenty
    oscillators in a random basis: the integrators' mutual couplings are not first-order
    corrections (they share s = 0), but merging them would make one 40-state block whose
    k^2 work a sample the recursion pays; a group beyond 8 states stays apart
    (their blocks refined, the couplings to the oscillators corrected): no block beyond 8
    states or the Schur form's own largest (which rounding decides: 2 x 2 here on every
    BLAS kernel tried, X <= 7 against the bound 100), and the form still reproduces A."""
    import scipy.linalg
    import controllers.modal_form as modal_form
    rng = np.random.default_rng(0)
    blocks = [np.zeros((40, 40))] + [np.array([[-0.01, w], [-w, -0.01]])
                                     for w in np.geomspace(1.0, 100.0, 20)]
    A = scipy.linalg.block_diag(*blocks)
    S = rng.standard_normal(A.shape)
    A = S @ A @ np.linalg.inv(S)
    form = block_diagonal_form(A)
    monkeypatch.setattr(modal_form, "_refine_blocks",
                        lambda A, V, inverse, starts, blocks, T:
                        (starts, blocks, None, np.zeros(0, dtype=int), None, None))
    schur = block_diagonal_form(A)
    assert max(form.sizes) <= max(8, max(schur.sizes))
    assert form.coupled.size >= 40
    check_factorisation(A, form)


def test_sequential_decoupling_moves_the_nearest_block_within_a_range(capfd):
    """Bavely and Stewart's step inside a range that the divide and conquer left (rows 0:3 of
    6): eigenvalues 0 and 1e-9, coupled by 1 (decoupling them would need |X| ~ 1e9), with 3
    between them; the block at 1e-9 is moved next to 0 by trexc and the two form a 2 x 2
    cluster, 3 stays alone. (trexc was given Y's rows above the range only, an illegal
    leading dimension: LAPACK printed an error, the swap was skipped and the cluster took
    all the rest, [3, 1, 1, 1].) An upper triangular T is its own Schur form, so the blocks
    do not depend on rounding."""
    rng = np.random.default_rng(3)
    T = np.triu(0.3 * rng.standard_normal((6, 6)), 1) + np.diag([0, 3, 1e-9, 10, 20, 30])
    T[0, 2] = 1.0
    form = block_diagonal_form(T)
    assert list(form.sizes) == [2, 1, 1, 1, 1]
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(form.blocks[0]).real), [0, 1e-9],
                               rtol=0, atol=1e-15)
    check_factorisation(T, form)
    captured = capfd.readouterr()
    assert "DTREXC" not in captured.out + captured.err


def test_a_pair_that_cannot_be_decoupled_forms_a_cluster():
    """Two coupled oscillators 1e-11 rad/s apart and nothing else: the Schur form has two
    blocks, the division's one range; its Sylvester solution is unbounded (max|X| ~ 1e11),
    so Bavely and Stewart take the range and the pair stays one 4 x 4 block, the
    factorisation exact to round-off."""
    rng = np.random.default_rng(4)
    close = np.array([[0.0, 1.0, 1.0, 0.0], [-49.0, -0.02, 0.0, 0.0],
                      [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, -(7.0 + 1e-11) ** 2, -0.02]])
    S = rng.standard_normal((4, 4))
    A = S @ close @ np.linalg.inv(S)
    form = block_diagonal_form(A)
    assert list(form.sizes) == [4]
    check_factorisation(A, form)
