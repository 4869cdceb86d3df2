"""Block-diagonal (modal) form of a real square matrix with a bounded transformation.

``A = V diag(A_1, ..., A_r) V^-1`` with real blocks ``A_j``: one per real eigenvalue or
complex-conjugate pair (1 x 1 or 2 x 2) where the eigenvalues are well separated, one larger
block per cluster of close (or defective, as a rigid body's double integrator) eigenvalues.
Decoupling a cluster from the rest costs a transformation whose norm grows as their
separation shrinks; the norm of every elementary transformation is bounded here, and a
cluster whose decoupling would exceed the bound grows instead, so that the condition number
of ``V`` stays moderate and the modal coordinates carry no more round-off than the original
ones (up to that condition number).

The method is Bavely and Stewart's [1]_ (the one of SLICOT's MB03RD, behind python-control's
``bdschur``): a real Schur form ``A = Q T Q^T``; then, from the top left, the leading block
``T11`` is decoupled from the trailing part ``T22`` by the Sylvester equation
``T11 X - X T22 = -T12``, which makes ``[[I, X], [0, I]]^-1 T [[I, X], [0, I]]`` block
diagonal; if ``max |X_ij|`` exceeds the bound (or the equation is singular), the eigenvalue
block of ``T22`` nearest to the eigenvalues of ``T11`` is moved next to it by an orthogonal
swap (LAPACK ``trexc``) and the enlarged block is tried again.

Last, the blocks whose round-off matters most (clusters, rigid bodies, integrators:
defective blocks and eigenvalues zero to the Schur form's accuracy) are refined to the exact
diagonal blocks of ``V^-1 A V`` for the float64 V and decoupled from the other blocks to
first order, from residuals computed with error-free products (``_refine_blocks``): the
Schur form's backward error ~eps ||A|| would otherwise accumulate in a rigid body's drift.

References
----------
.. [1] C. A. Bavely and G. W. Stewart, "An algorithm for computing reducing subspaces by
   block diagonalization", SIAM J. Numer. Anal. 16(2), 359-367, 1979.
.. [2] G. H. Golub and C. F. Van Loan, *Matrix Computations*, 4th ed., Johns Hopkins, 2013,
   sec. 7.6.3 (block diagonalization and its conditioning).
.. [3] N. J. Higham, "FORTRAN codes for estimating the one-norm of a real or complex
   matrix, with applications to condition estimation", ACM Trans. Math. Softw. 14(4),
   381-396, 1988 (LAPACK's gecon).
"""

from __future__ import annotations

import bisect
import functools
import warnings
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.linalg.blas
import scipy.linalg.lapack

__all__ = ["BlockDiagonalForm", "block_diagonal_form", "DEFAULT_MAX_COUPLING"]

#: Default bound on max |X_ij| of each elementary decoupling transformation.  The condition
#: number of V grows with it; 100 keeps V's condition at ~1e2-1e3 on lightly damped modal
#: systems, whose modes then decouple into 2 x 2 blocks (a smaller bound only merges more).
DEFAULT_MAX_COUPLING = 100.0


@dataclass(frozen=True)
class BlockDiagonalForm:
    """``A = V @ blockdiag(blocks) @ V_inv``.

    Attributes
    ----------
    starts : numpy.ndarray of int, shape (r + 1,)
        Block j occupies rows and columns ``starts[j]:starts[j + 1]``.
    blocks : list of numpy.ndarray
        The diagonal blocks ``A_j`` (real; in real Schur form, except the refined ones
        (clusters larger than 2 x 2, near-defective and zero-eigenvalue blocks), which are
        the accurately computed diagonal blocks of ``V^-1 A V``, dense: see
        ``_refine_blocks``).
    V : numpy.ndarray, shape (n, n)
        The transformation (columns of V span the blocks' invariant subspaces).  Its
        inverse is applied by :meth:`solve` (an LU factorisation) and formed on request
        (``V_inv``).
    condition : float
        The 1-norm condition number of V without its diagonal balancing (V = D W with D
        diagonal, an exact scaling by powers of two: cond(W) is what round-off sees), as
        LAPACK's estimator (``gecon``, Higham's 1-norm estimator [3]_) gives it from the LU
        factors: a lower bound, measured within 20 % of the exact value on issue 10's
        systems, at O(n^2) instead of an O(n^3) inverse.
    coupled : numpy.ndarray of int
        The states of the refined blocks (``_refine_blocks``), whose coupling to the other
        blocks through the float64 V is removed to first order: the exact similarity is
        then ``V (I + Z)``, ``Z`` nonzero only in the rows ``Z_rows`` (shape (k, n)) and
        the columns ``Z_cols`` (shape (n, k), zero in the rows ``coupled``) of these
        states; ``A = V (I + Z) blockdiag(blocks) (I - Z) V^-1`` to second order in Z
        (|Z| ~ eps cond(V), so the remainder ~eps^2).  Empty with ``Z_rows`` None when no
        block is refined.
    """

    starts: np.ndarray
    blocks: list
    V: np.ndarray
    condition: float
    coupled: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    Z_rows: np.ndarray | None = None
    Z_cols: np.ndarray | None = None
    _inverse: "_Inverse | None" = field(default=None, repr=False, compare=False)

    @property
    def sizes(self) -> np.ndarray:
        """Block sizes, shape (r,)."""
        return np.diff(self.starts)

    def solve(self, M: np.ndarray) -> np.ndarray:
        """``V^-1 M`` (backward stable: through the LU factors of V's unscaled part)."""
        return self._inverse.solve(M)

    @functools.cached_property
    def V_inv(self) -> np.ndarray:
        """The inverse of V, shape (n, n) (formed on first use: O(n^3))."""
        return self.solve(np.eye(self.V.shape[0]))

    def right(self, M: np.ndarray) -> np.ndarray:
        """``M (I + Z)``: with ``M = V`` the columns of the corrected transformation, with
        ``M = C V`` the output map of the modal coordinates (see ``coupled``)."""
        if self.Z_rows is None:
            return M
        out = M + M[:, self.coupled] @ self.Z_rows
        out[:, self.coupled] += M @ self.Z_cols
        return out

    def left(self, M: np.ndarray) -> np.ndarray:
        """``(I - Z) M``: with ``M = V^-1 B`` the input map of the modal coordinates, the
        inverse of :meth:`right`'s transformation to first order (``Z^2`` ~ eps^2)."""
        if self.Z_rows is None:
            return M
        out = M - self.Z_cols @ M[self.coupled]
        out[self.coupled] -= self.Z_rows @ M
        return out


def _schur_blocks(T: np.ndarray, start: int, stop: int) -> list[tuple[int, int]]:
    """(first row, size) of the 1 x 1 and 2 x 2 diagonal blocks of quasi-triangular T in
    rows ``start:stop``."""
    out = []
    i = start
    while i < stop:
        size = 2 if i + 1 < stop and T[i + 1, i] != 0.0 else 1
        out.append((i, size))
        i += size
    return out


def _block_eigenvalues(T: np.ndarray, i: int, size: int) -> list[complex]:
    """Eigenvalues of the diagonal block of T at row i (1 x 1, or 2 x 2 in LAPACK's
    standard form [[a, b], [c, a]] with b c < 0: a +- i sqrt(-b c))."""
    if size == 1:
        return [complex(T[i, i])]
    a, b, c, d = T[i, i], T[i, i + 1], T[i + 1, i], T[i + 1, i + 1]
    mean, half = 0.5 * (a + d), 0.5 * (a - d)
    root = np.sqrt(complex(half * half + b * c))
    return [mean + root, mean - root]


def _solves(T11, T22, T12, X, norm_T) -> bool:
    """Whether X solves T11 X - X T22 = -T12 to round-off (for LAPACK's perturbed solutions):
    the residual of a backward-stable solve is ~eps (|T11| + |T22|) |X| + eps |T12|."""
    residual = np.abs(T11 @ X - X @ T22 + T12).max()
    size = T11.shape[0]
    return residual <= 64 * size * np.finfo(float).eps * norm_T * max(np.abs(X).max(), 1.0)


def block_diagonal_form(A, *, max_coupling: float = DEFAULT_MAX_COUPLING
                        ) -> BlockDiagonalForm:
    """Real block-diagonal form of A with every elementary transformation bounded.

    Parameters
    ----------
    A : array_like, shape (n, n)
        Real, finite square matrix.
    max_coupling : float
        Bound on ``max |X_ij|`` of each decoupling transformation (see the module
        docstring); larger values give smaller blocks and a worse-conditioned V.

    Returns
    -------
    BlockDiagonalForm

    Notes
    -----
    Cost O(n^3) (the Schur form and one Sylvester solve per block), plus O(k n^2) per
    eigenvalue block moved into a cluster of size k.  A Sylvester solve is accepted when its
    solution is bounded and it solves the equation to round-off (LAPACK's ``trsyl`` returns
    the solution of a perturbed equation when the two blocks share an eigenvalue: it is kept
    only if it also solves the true one, as for an exactly decoupled repeated eigenvalue).

    References
    ----------
    .. [1] C. A. Bavely and G. W. Stewart, SIAM J. Numer. Anal. 16(2), 1979.
    """
    A = np.array(A, dtype=float)
    if A.ndim != 2 or A.shape[0] != A.shape[1]:
        raise ValueError(f"A must be a square matrix; got shape {A.shape}")
    if not np.all(np.isfinite(A)):
        raise ValueError("A must be finite; got NaN or inf")
    if not (np.isfinite(max_coupling) and max_coupling > 0):
        raise ValueError(f"max_coupling must be positive and finite; got {max_coupling!r}")
    n = A.shape[0]
    if n == 0:
        return BlockDiagonalForm(np.zeros(1, dtype=int), [], np.zeros((0, 0)), 1.0,
                                 _inverse=_Inverse(None, np.ones(0), None))
    # Balancing first (a diagonal similarity, exact in binary floating point): the Schur
    # form's backward error is ~eps ||A||, and for a mechanical mode [[0, 1], [-w^2, .]]
    # ||A|| ~ w^2 of the stiffest mode where the balanced ||A|| ~ w: slow modes then keep
    # their eigenvalues w_max times more accurately.
    A_balanced, scaling = scipy.linalg.matrix_balance(A, permute=False, separate=True)
    scaling = scaling[0]
    T, Q = scipy.linalg.schur(A_balanced, output="real", overwrite_a=True, check_finite=False)
    form = _Decoupling(np.asfortranarray(T), max_coupling)
    form.split(0, n)
    starts = np.array(sorted(form.starts) + [n])
    # The condition number that matters for round-off is that of V without its (exact)
    # diagonal scaling: W = Q Y (one product, used for both).
    W = _times_block_triangular(Q, form.Y)
    V = np.ascontiguousarray(scaling[:, None] * W)
    T = form.T
    lu = scipy.linalg.lu_factor(W, check_finite=False)
    rcond, _ = scipy.linalg.lapack.dgecon(lu[0], np.abs(W).sum(axis=0).max(), norm="1")
    condition = float(1.0 / rcond) if rcond > 0 else np.inf
    inverse = _Inverse(lu, scaling, None)
    blocks = [np.array(T[a:b, a:b]) for a, b in zip(starts[:-1], starts[1:])]
    starts, blocks, perm, *coupling = _refine_blocks(A, V, inverse, starts, blocks, T)
    if perm is not None:
        V = np.ascontiguousarray(V[:, perm])
        inverse = _Inverse(lu, scaling, perm)
    return BlockDiagonalForm(starts, blocks, V, condition, *coupling, _inverse=inverse)


def _times_block_triangular(Q: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """``Q @ Y`` for the decoupling's Y: upper triangular (identity plus the Sylvester
    steps' blocks above the diagonal) but for the few columns that the swaps of diagonal
    blocks rotated: one triangular product (BLAS trmm, half a general product's work) plus
    the columns with entries below the diagonal (any Y gives Q @ Y)."""
    lower = np.tril(Y, -1)
    W = scipy.linalg.blas.dtrmm(1.0, Y, Q, side=1, lower=0)
    columns = np.flatnonzero(np.any(lower, axis=0))
    if columns.size:
        W[:, columns] += Q @ lower[:, columns]
    return W


class _Inverse:
    """Applies ``V^-1`` for ``V = D W P`` (D the balancing's diagonal scaling by powers of
    two, P a permutation of columns, ``perm`` or None) from the LU factors of W."""

    def __init__(self, lu, scaling: np.ndarray, perm: np.ndarray | None):
        self.lu, self.scaling, self.perm = lu, scaling, perm

    def solve(self, M: np.ndarray) -> np.ndarray:
        """``V^-1 M``."""
        M = np.asarray(M, dtype=float)
        if self.lu is None:
            return np.zeros((0,) + M.shape[1:])
        scale = self.scaling.reshape((-1,) + (1,) * (M.ndim - 1))
        out = scipy.linalg.lu_solve(self.lu, M / scale, check_finite=False)
        return out if self.perm is None else out[self.perm]

    def rows(self, index: np.ndarray) -> np.ndarray:
        """``V^-1[index, :]`` (one transposed solve per row; before any permutation)."""
        E = np.zeros((self.scaling.size, index.size))
        E[index, np.arange(index.size)] = 1.0
        return (scipy.linalg.lu_solve(self.lu, E, trans=1, check_finite=False)
                / self.scaling[:, None]).T


def _split(X: np.ndarray, axis: int, bits: int) -> tuple[np.ndarray, np.ndarray]:
    """``X = X1 + X2`` exactly, with X1 on the grid ``2^(e - bits)`` where ``2^e`` bounds
    ``|X|`` along ``axis`` (per row for axis=1, per column for axis=0).

    Rump, Ogita and Oishi's extraction [1]_: with ``sigma = 1.5 * 2^(e + 52 - bits)`` the
    unit in the last place of ``sigma + x`` is ``2^(e - bits)`` for every ``|x| <= 2^e``,
    so ``(sigma + x) - sigma`` rounds x to that grid and both subtractions are exact.  The
    exponent is bounded below (-400) so that products of two parts never reach the subnormal
    range; a smaller row then has X1 = 0 (exact all the same, without the gain).

    References
    ----------
    .. [1] S. M. Rump, T. Ogita, S. Oishi, "Accurate floating-point summation part I:
       faithful rounding", SIAM J. Sci. Comput. 31(1), 189-224, 2008 (ExtractScalar).
    """
    scale = np.abs(X).max(axis=axis, keepdims=axis is not None)
    exponent = np.maximum(np.frexp(scale)[1], -400)
    sigma = np.ldexp(1.5, exponent + 52 - bits)
    X1 = (X + sigma) - sigma
    return X1, X - X1


def _parts(X: np.ndarray, bits: int, axis=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(X1, X2, X)`` of :func:`_split` (axis None: one grid for the whole matrix, from
    max |X|: exact products all the same, each row or column split no finer than the
    largest one needs)."""
    return (*_split(X, axis, bits), X)


def _pair(Xs, Ys) -> tuple[np.ndarray, np.ndarray]:
    """``X @ Y`` as ``(P1, P2)`` from the parts of X (rows or whole) and of Y (columns or
    whole) split for the same ``bits`` (see :func:`_accurate_product`)."""
    X1, X2, X = Xs
    Y1, Y2, Y = Ys
    return X1 @ Y1, X1 @ Y2 + X2 @ Y


def _accurate_product(X: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``X @ Y = P1 + P2`` with P1 exact and P2 to ~k eps 2^-bits |X| |Y| (k = inner size).

    Ozaki's error-free splitting [1]_: X1 (per row) and Y1 (per column) carry
    ``bits = floor((53 - ceil(log2 k)) / 2)`` significant bits each, so every product of
    their entries is exact and so is every partial sum of k of them, in any order (a BLAS
    product, threaded or not, with or without FMA, returns P1 exactly).  The remainder
    ``X1 Y2 + X2 Y`` is 2^-bits times smaller than the product and rounds in float64: the
    pair carries ~2 bits + 53 - log2 k bits of the product (about 75 at k = 400), where one
    float64 product carries 53 minus its cancellation.

    References
    ----------
    .. [1] K. Ozaki, T. Ogita, S. Oishi, S. M. Rump, "Error-free transformations of matrix
       multiplication by using fast routines of matrix multiplication and its
       applications", Numer. Algorithms 59(1), 95-118, 2012.
    """
    bits = _bits(X.shape[1])
    return _pair(_parts(X, bits, 1), _parts(Y, bits, 0))


def _bits(k: int) -> int:
    """Bits of each part for exact products summed over k terms: 2 bits + log2 k <= 53."""
    return (53 - int(np.ceil(np.log2(max(k, 2))))) // 2


# A 2 x 2 block whose spectral radius is below this fraction of its largest entry is
# near-defective (a free rigid body split off on its own) and is refined by _refine_blocks.
_NEAR_DEFECTIVE = 1e-3


def _refined(T: np.ndarray, starts: np.ndarray, norm_A: float) -> np.ndarray:
    """Which diagonal blocks of the block-diagonal T (rows ``starts[j]:starts[j + 1]``) are
    refined (see :func:`_refine_blocks`): a cluster (larger than 2 x 2: defective or close
    eigenvalues), a block whose eigenvalues are zero to the Schur form's accuracy (spectral
    radius below sqrt(eps) max |A|: integrators, rigid bodies split apart), or a
    near-defective 2 x 2 block (radius below 1e-3 of its largest entry).  Slow but
    well-separated modes are not refined: measured on issue 10's systems, refining those
    too (eigenvalues below 1e-3 max |A|) cut the remaining error by up to 4x at 50 states
    but cost 0.6 to 1.5 ms of set-up at 20 to 200 states, for errors already 10 to 30
    times below forced_response's."""
    first, sizes = starts[:-1], np.diff(starts)
    second = np.minimum(first + 1, T.shape[0] - 1)
    a, b = T[first, first], np.where(sizes == 2, T[first, second], 0.0)
    c, d = np.where(sizes == 2, T[second, first], 0.0), np.where(sizes == 2, T[second, second], 0.0)
    radius = np.where(sizes == 2, np.sqrt(np.abs(a * d - b * c)), np.abs(a))
    largest = np.maximum(np.maximum(np.abs(a), np.abs(b)), np.maximum(np.abs(c), np.abs(d)))
    zero = np.sqrt(np.finfo(float).eps) * max(norm_A, np.finfo(float).tiny)
    return (sizes > 2) | (radius < zero) | ((sizes == 2) & (radius < _NEAR_DEFECTIVE * largest))


def _refine_blocks(A, V, inverse, starts, blocks, T):
    """Refine the diagonal blocks that need it (:func:`_refined`) to the diagonal blocks of
    ``V^-1 A V`` for the float64 V, computed accurately, and decouple them from the others
    to first order.

    Returns ``(starts, blocks, perm, coupled, Z_rows, Z_cols)``: the form (its blocks
    refined; refined blocks that cannot be decoupled from each other merged into one block,
    the blocks permuted so that each merged block is contiguous: V's columns permuted by
    ``perm``, None if none is), and the correction as :class:`BlockDiagonalForm` holds it,
    in the permuted order (``coupled`` empty and Z None when nothing is refined).
    ``inverse`` applies V^-1 (:class:`_Inverse`, before the permutation); T is the
    block-diagonal matrix of the blocks (updated in place).

    The Schur form leaves every block with a backward error ~eps ||A||: for a cluster of
    defective or close eigenvalues (a free rigid body's double integrator, ||T_c|| ~ 1 in a
    system whose ||A|| is its stiffest mode's frequency) that is an error of
    ~eps ||A|| / ||T_c|| relative, and the polynomially growing motion of a defective block
    (a rigid body's position drifts ~t^1.5 under random inputs) carries it into the outputs
    over a long run.  With ``R_c = A V_c - V_c T_c`` computed accurately (error-free
    products, :func:`_accurate_product`), ``T_c + (V^-1)_c R_c`` is the block of the exact
    ``V^-1 A V`` up to ~eps ||T_c|| (its rounding) plus cond(V) eps |(V^-1)_c R_c| (the
    rounding of the small correction): the error a block of its own norm would have.

    The same round-off leaves ``E = V^-1 A V - blockdiag`` ~eps ||A|| cond(V) off the
    diagonal blocks: couplings between blocks, which a drifting rigid body integrates too.
    Rounding a corrected V to float64 would bring them back, so the correction is kept
    apart: ``V' = V (I + Z)`` with ``T_c Z_cj - Z_cj T_j = -E_cj`` (and likewise ``Z_jc``)
    for each refined block c and every other block j, E's rows and columns of the refined
    blocks computed accurately (``E[c, :] = (L_c A) V - (L_c V) T`` with ``L = V^-1``,
    error-free products; ``E[:, c] = L R_c``): ``V'^-1 A V'`` is block diagonal in these
    rows and columns up to O(|E| |Z|), and the simulator maps inputs and outputs through
    V' (:meth:`BlockDiagonalForm.left`, :meth:`~BlockDiagonalForm.right`).  Two refined
    blocks too close for a first-order correction (two rigid bodies split into blocks of
    their own, ~sqrt(eps ||A||) apart) become one block, their exact coupling E included
    (up to _MAX_MERGED states).

    Measured on issue 10's general systems (``benchmarks/issue10.py``: 20 to 400 states,
    two rigid bodies): the outputs' error against an extended-precision solution fell 2.4
    to 90 times (3.7e-11 to 4.2e-13 at 20 states over 1e4 samples; 9.0e-13 to 3.7e-13 at
    400 states over 2000), to 0.04 to 0.7 times forced_response's, at a cost of O(n^2 k)
    for k refined states (0.3 to 6 ms of set-up at 20 to 400 states).  The other blocks
    are left alone (see :func:`_refined`): refining all of them (O(n^3), three more
    products of order n) changed the errors by under 20 % (their round-off does not grow
    polynomially).
    """
    n = A.shape[0]
    nothing = (starts, blocks, None, np.zeros(0, dtype=int), None, None)
    norm_A = np.abs(A).max()
    chosen = np.flatnonzero(_refined(T, starts, norm_A)).tolist()
    # Far beyond any physical system; sigma of _split would overflow near 2^970.
    if not chosen or max(norm_A, np.abs(V).max()) > 2.0 ** 900:
        return nothing
    n = A.shape[0]
    spans = [slice(a, b) for a, b in zip(starts[:-1], starts[1:])]
    columns = np.concatenate([np.arange(starts[j], starts[j + 1]) for j in chosen])
    row_of = np.full(n, -1)
    row_of[columns] = np.arange(columns.size)     # state -> its row of E_rows, Z_rows
    rows = {j: slice(row_of[starts[j]], row_of[starts[j]] + starts[j + 1] - starts[j])
            for j in chosen}
    # A and V split once (one grid each: the residuals are needed to ~1e-6 of
    # eps ||A|| |V|, not row by row), for every product below.
    bits = _bits(n)
    A_parts, V_parts = _parts(A, bits), _parts(V, bits)
    P1, P2 = _pair(A_parts, tuple(part[:, columns] for part in V_parts))
    T_chosen = np.zeros((columns.size, columns.size))
    for j in chosen:
        T_chosen[rows[j], rows[j]] = blocks[j]
    Q1, Q2 = _accurate_product(V[:, columns], T_chosen)
    # P1 - Q1: two exact values of one product that nearly cancel, one rounding.
    residual = (P1 - Q1) + (P2 - Q2)
    # E's columns of the refined blocks (their diagonal blocks refine the blocks), and its
    # rows: L_c (A V - V T) for the float64 L_c = V^-1[c, :].
    E_cols = inverse.solve(residual)
    blocks = list(blocks)
    for j in chosen:
        blocks[j] = T[spans[j], spans[j]] = blocks[j] + E_cols[spans[j], rows[j]]
    # E[c, :] = (L_c A) V - (L_c V) T; L_c V = J + delta (J selects the states c, delta
    # ~cond(V) eps), so (L_c V) T = T[c, :] + delta T, delta T to eps |delta| |T|.
    L_parts = _parts(inverse.rows(columns), bits, 1)
    G1, G2 = _pair(L_parts, A_parts)
    H1, H2 = _pair(_parts(G1, bits, 1), V_parts)
    K1, K2 = _pair(L_parts, V_parts)
    K1[np.arange(columns.size), columns] -= 1.0      # exact: those entries are ~1
    E_rows = (H1 - T[columns]) + ((H2 + G2 @ V) - (K1 + K2) @ T)

    # Units: (states, block, refined).  First each block on its own; refined blocks that
    # cannot be decoupled from each other to first order then become one unit (merged at
    # the place of the first) and the couplings are solved again.
    units = [(np.arange(starts[j], starts[j + 1]), blocks[j], j in rows)
             for j in range(len(blocks))]
    Z_rows, Z_cols, failed = _couplings(units, E_rows, E_cols, row_of)
    if failed:
        group = {j: j for j in chosen}

        def root(j):
            while group[j] != j:
                j = group[j]
            return j
        for c, d in failed:
            group[root(d)] = root(c)
        members: dict[int, list[int]] = {}
        for j in chosen:
            members.setdefault(root(j), []).append(j)
        merged_units = []
        for j, unit in enumerate(units):
            parts = members.get(root(j), []) if j in group else []
            if len(parts) <= 1 or sum(units[k][0].size for k in parts) > _MAX_MERGED:
                merged_units.append(unit)
            elif parts[0] == j:
                idx = np.concatenate([units[k][0] for k in members[root(j)]])
                merged = T[np.ix_(idx, idx)] + E_rows[np.ix_(row_of[idx], idx)]
                merged_units.append((idx, merged, True))
        if len(merged_units) < len(units):
            units = merged_units
            Z_rows, Z_cols, _ = _couplings(units, E_rows, E_cols, row_of)
    blocks = [u[1] for u in units]
    new_starts = np.concatenate([[0], np.cumsum([u[0].size for u in units])])
    perm = np.concatenate([u[0] for u in units])
    if np.array_equal(perm, np.arange(n)):
        return new_starts, blocks, None, columns, Z_rows, Z_cols
    position = np.empty(n, dtype=int)
    position[perm] = np.arange(n)
    return (new_starts, blocks, perm, position[columns],
            np.ascontiguousarray(Z_rows[:, perm]), np.ascontiguousarray(Z_cols[perm]))


def _couplings(units, E_rows, E_cols, row_of):
    """Z_rows, Z_cols of :func:`_refine_blocks` for the units (states, block, refined), and
    the pairs of refined units (indices) whose coupling is not a first-order correction.

    For each refined unit c and every other unit j: ``T_c Z_cj - Z_cj T_j = -E_cj``; for
    each unit j not refined: ``T_j Z_jc - Z_jc T_c = -E_jc``, solved transposed as
    ``T_c^T Y - Y T_j^T = E_jc^T`` (``Y = Z_jc^T``) so that both kinds share one batched
    solve per pair of unit sizes."""
    n = row_of.size
    Z_rows = np.zeros((E_rows.shape[0], n))
    Z_cols = np.zeros((n, E_rows.shape[0]))
    sizes = np.array([u[0].size for u in units])
    refined = np.array([u[2] for u in units])
    by_size = {}
    for size in np.unique(sizes):
        ids = np.flatnonzero(sizes == size)
        by_size[int(size)] = (ids, np.array([units[j][0] for j in ids]),
                              np.array([units[j][1] for j in ids]))
    failed = []
    for s_c, (ids_c, states_c, blocks_c) in by_size.items():
        mine = refined[ids_c]
        if not np.any(mine):
            continue
        ids_c, states_c, blocks_c = ids_c[mine], states_c[mine], blocks_c[mine]
        rows_c = row_of[states_c]                                          # (C, s)
        for ids_j, states_j, blocks_j in by_size.values():
            ci, jj = np.nonzero(ids_c[:, None] != ids_j[None, :])
            if ci.size == 0:
                continue
            column = ~refined[ids_j[jj]]
            cc, jc = ci[column], jj[column]
            T1 = np.concatenate([blocks_c[ci], blocks_c[cc].transpose(0, 2, 1)])
            T2 = np.concatenate([blocks_j[jj], blocks_j[jc].transpose(0, 2, 1)])
            E = np.concatenate([
                E_rows[rows_c[ci][:, :, None], states_j[jj][:, None, :]],
                -E_cols[states_j[jc][:, :, None], rows_c[cc][:, None, :]].transpose(0, 2, 1)])
            Z, ok = _sylvester(T1, T2, E)
            Z_rows[rows_c[ci][:, :, None], states_j[jj][:, None, :]] = Z[:ci.size]
            Z_cols[states_j[jc][:, :, None], rows_c[cc][:, None, :]] = (
                Z[ci.size:].transpose(0, 2, 1))
            bad = ~ok[:ci.size] & refined[ids_j[jj]] & (ids_c[ci] < ids_j[jj])
            failed.extend(zip(ids_c[ci][bad].tolist(), ids_j[jj][bad].tolist()))
    return Z_rows, Z_cols, failed


# Refined blocks that cannot be decoupled from each other merge into one block up to this
# many states (three free rigid bodies: 6); a larger group (dozens of integrators, all at
# s = 0) stays apart, its mutual couplings uncorrected: one block of k states costs the
# recursion k^2 multiply-adds a sample (measured: 40 integrators merged, 8x the run time
# for 1.7x less error, already below forced_response's without).
_MAX_MERGED = 8


# Largest entry of a first-order decoupling correction kept (its square is below eps).
_FIRST_ORDER = float(np.sqrt(np.finfo(float).eps))


def _sylvester(T1: np.ndarray, T2: np.ndarray, E: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """Z with ``T1 Z - Z T2 = -E`` for stacks T1 (K, s, s), T2 (K, t, t), E (K, s, t): the
    Kronecker form ``(I_t (x) T1 - T2^T (x) I_s) vec(Z) = -vec(E)`` (column-major vec), one
    batched solve of (s t) x (s t) systems (Bartels-Stewart per pair beyond
    s t = _KRONECKER_MAX).  Returns Z and, per pair, whether its solution
    is a small first-order correction (entries below sqrt(eps)); Z is zero where not."""
    K, s, t = E.shape
    if s * t > _KRONECKER_MAX:
        # Two large units (clusters): Bartels-Stewart per pair, O(s^3 + t^3 + s t (s + t))
        # instead of the Kronecker system's O(s^3 t^3).
        Z = np.empty((K, s, t))
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            for k in range(K):
                try:
                    Z[k] = scipy.linalg.solve_sylvester(T1[k], -T2[k], -E[k])
                except (np.linalg.LinAlgError, ValueError):
                    Z[k] = np.inf
    else:
        Z = _sylvester_kronecker(T1, T2, E)
    # A first-order correction is kept where its square is below round-off (|Z| ~ |E| /
    # sep, ~1e-12 between well-separated blocks); a pair too close for it (two rigid bodies
    # split into blocks of their own: sep ~ sqrt(eps ||A||)) keeps its coupling.
    ok = np.abs(Z).max(axis=(1, 2), initial=0.0) < _FIRST_ORDER      # False for NaN too
    Z[~ok] = 0.0
    return Z, ok


# Pairs of units with more than this product of sizes are solved by Bartels-Stewart.
_KRONECKER_MAX = 64


def _sylvester_kronecker(T1: np.ndarray, T2: np.ndarray, E: np.ndarray) -> np.ndarray:
    """The Kronecker solve of :func:`_sylvester` (small units)."""
    K, s, t = E.shape
    # kron[b, i, k, j, l] = delta_ij T1[b, k, l] - T2[b, j, i] delta_kl, assigned block by
    # block (a five-index einsum of the identities cost more than the batched solve)
    kron = np.zeros((K, t, s, t, s))
    for i in range(t):
        kron[:, i, :, i, :] = T1
    T2t = T2.transpose(0, 2, 1)
    for k in range(s):
        kron[:, :, k, :, k] -= T2t
    kron = kron.reshape(K, s * t, s * t)
    rhs = -E.transpose(0, 2, 1).reshape(K, s * t)
    with np.errstate(all="ignore"):
        try:
            x = np.linalg.solve(kron, rhs[..., None])[..., 0]
        except np.linalg.LinAlgError:        # an exactly singular pair: solve one by one
            x = np.array([np.linalg.lstsq(k, r, rcond=None)[0] for k, r in zip(kron, rhs)])
    return x.reshape(K, t, s).transpose(0, 2, 1)


# Leaves of the recursive Sylvester solver: LAPACK's trsyl on at most this many rows and
# columns (its level-2 loops run at ~1 GFLOP/s; the recursion moves the rest into matrix
# products, ~20 GFLOP/s on one core).
_TRSYL_LEAF = 48


def _quasi_split(T: np.ndarray) -> int:
    """A split point near the middle of quasi-triangular T that cuts no 2 x 2 block."""
    m = T.shape[0] // 2
    return m + 1 if T[m, m - 1] != 0.0 else m


def _sylvester_triangular(T11: np.ndarray, T22: np.ndarray, C: np.ndarray
                          ) -> tuple[np.ndarray | None, int]:
    """X with ``T11 X - X T22 = C`` for quasi-upper-triangular T11, T22 (real Schur form),
    and LAPACK's info (1: the equation was perturbed, the blocks sharing an eigenvalue);
    X None where trsyl had to scale the solution to avoid overflow.

    Recursive blocking [1]_: split T11 = [[A11, A12], [0, A22]] (rows of X) or T22 =
    [[B11, B12], [0, B22]] (columns), whichever side is larger, at a boundary between
    diagonal blocks; then ``A22 X2 - X2 T22 = C2``, ``A11 X1 - X1 T22 = C1 - A12 X2``
    (or ``T11 Xa - Xa B11 = Ca``, ``T11 Xb - Xb B22 = Cb + Xa B12``), down to trsyl on
    leaves of at most _TRSYL_LEAF rows and columns.  The same equations as one trsyl call,
    eliminated in another order: at 200 x 200, 3.1 ms against trsyl's 4.6 (one core).

    References
    ----------
    .. [1] I. Jonsson and B. Kagstrom, "Recursive blocked algorithms for solving triangular
       systems - Part I: one-sided and coupled Sylvester-type matrix equations", ACM Trans.
       Math. Softw. 28(4), 392-415, 2002.
    """
    m, n = C.shape
    if max(m, n) <= _TRSYL_LEAF or min(m, n) == 0:
        X, scale, info = scipy.linalg.lapack.dtrsyl(T11, T22, C, isgn=-1)
        return (X if info >= 0 and scale == 1.0 else None), max(info, 0)
    if m >= n:
        k = _quasi_split(T11)
        X2, info2 = _sylvester_triangular(T11[k:, k:], T22, C[k:])
        if X2 is None:
            return None, info2
        X1, info1 = _sylvester_triangular(T11[:k, :k], T22, C[:k] - T11[:k, k:] @ X2)
        if X1 is None:
            return None, info1
        return np.vstack([X1, X2]), max(info1, info2)
    k = _quasi_split(T22)
    Xa, info_a = _sylvester_triangular(T11, T22[:k, :k], C[:, :k])
    if Xa is None:
        return None, info_a
    Xb, info_b = _sylvester_triangular(T11, T22[k:, k:], C[:, k:] + Xa @ T22[:k, k:])
    if Xb is None:
        return None, info_b
    return np.hstack([Xa, Xb]), max(info_a, info_b)


class _Decoupling:
    """The decoupling of a quasi-triangular T (in place), recording Y with T_original =
    Y diag(blocks) Y^-1.

    ``split(a, b)`` decouples the diagonal range a:b (already decoupled from the rest):
    divide and conquer first (one Sylvester equation between the two halves; a few large
    LAPACK solves cost far less than one per block: 11 ms against 80 ms at 400 states),
    then, where two halves cannot be decoupled within the bound, Bavely and Stewart's
    sequential method on that range, which grows clusters.

    A step [[I, X], [0, I]] changes Y's columns of the trailing part (Y[:, m:b] +=
    Y[:, a:m] X); a swap of diagonal blocks by trexc's rotation G changes Y's columns of
    the range (Y[:, a:b] G).  Y's rows from b on vanish in the columns a:b throughout.
    """

    def __init__(self, T: np.ndarray, max_coupling: float):
        self.T = T
        self.n = T.shape[0]
        self.Y = np.eye(self.n, order="F")
        self.max_coupling = max_coupling
        self.norm_T = max(np.abs(T).max(), np.finfo(float).tiny)
        self.starts: list[int] = []
        # The diagonal blocks' first rows, read once: ``split`` cuts only between blocks and
        # never enters a range that ``sequential`` has reordered, so the 1 x 1 / 2 x 2
        # structure it sees is this one (a scan per range cost O(n log n) Python steps).
        self._block_starts = [i for i, _ in _schur_blocks(T, 0, self.n)]

    def _solve(self, k: int, m: int, b: int) -> np.ndarray | None:
        """X with T11 X - X T22 = -T12 for the ranges k:m and m:b, or None if it is
        unbounded or not a solution."""
        T = self.T
        T11, T22, T12 = T[k:m, k:m], T[m:b, m:b], T[k:m, m:b]
        if not T12.any():
            return np.zeros_like(T12)
        X, info = _sylvester_triangular(T11, T22, -T12)
        # (array methods, one comparison that NaN and inf fail too: most of the solves are
        # of 1 x 1 and 2 x 2 blocks, where numpy's function wrappers cost more than LAPACK)
        if X is None or not abs(X).max() <= self.max_coupling:
            return None
        if info != 0 and not _solves(T11, T22, T12, X, self.norm_T):
            return None
        return X

    def _apply(self, k: int, m: int, b: int, X: np.ndarray) -> None:
        self.Y[:b, m:b] += self.Y[:b, k:m] @ X
        self.T[k:m, m:b] = 0.0

    def split(self, a: int, b: int) -> None:
        first = bisect.bisect_left(self._block_starts, a)
        count = bisect.bisect_left(self._block_starts, b, first) - first
        if count == 1:
            self.starts.append(a)
            return
        m = self._block_starts[first + count // 2]
        X = self._solve(a, m, b)
        if X is None:
            self.sequential(a, b)
            return
        if X.any():                     # T12 = 0: the halves are decoupled already
            self._apply(a, m, b, X)
        self.split(a, m)
        self.split(m, b)

    def sequential(self, a: int, b: int) -> None:
        """Bavely and Stewart on the range a:b: the leading block is decoupled from the
        rest, or grows by the nearest eigenvalue block until it can be."""
        T = self.T
        k = a
        while k < b:
            size = 2 if k + 1 < b and T[k + 1, k] != 0.0 else 1
            cluster = list(_block_eigenvalues(T, k, size))
            while k + size < b:
                X = self._solve(k, k + size, b)
                if X is not None:
                    self._apply(k, k + size, b, X)
                    break
                # Move the eigenvalue block of T22 nearest to the cluster next to it.
                candidates = _schur_blocks(T, k + size, b)
                distances = [min(abs(mu - lam) for mu in _block_eigenvalues(T, i, s)
                                 for lam in cluster) for i, s in candidates]
                i, s = candidates[int(np.argmin(distances))]
                if i != k + size:
                    # trexc rotates the columns of its "q" argument, all n rows of it (LAPACK
                    # requires ldq >= n: Y's rows above b alone, ldq = b, were refused as an
                    # illegal argument, info = -6, and the cluster took all the rest).
                    T, Y, info = scipy.linalg.lapack.dtrexc(T, self.Y, i + 1, k + size + 1,
                                                            overwrite_a=1, overwrite_q=1)
                    self.T, self.Y = T, Y
                    if info != 0:      # swap refused (ill-conditioned): take all the rest
                        size = b - k
                        break
                # The moved block may have changed size in the swap (re-read it).
                moved = 2 if k + size + 1 < b and T[k + size + 1, k + size] != 0.0 else 1
                cluster.extend(_block_eigenvalues(T, k + size, moved))
                size += moved
            self.starts.append(k)
            k += size
