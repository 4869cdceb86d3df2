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

References
----------
.. [1] C. A. Bavely and G. W. Stewart, "An algorithm for computing reducing subspaces by
   block diagonalization", SIAM J. Numer. Anal. 16(2), 359-367, 1979.
.. [2] G. H. Golub and C. F. Van Loan, *Matrix Computations*, 4th ed., Johns Hopkins, 2013,
   sec. 7.6.3 (block diagonalization and its conditioning).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
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
        The diagonal blocks ``A_j`` (real; in real Schur form, except the clusters (larger
        than 2 x 2) and the blocks of small eigenvalues, which are the accurately computed
        diagonal blocks of ``V^-1 A V``, dense: see ``_refine_blocks``).
    V, V_inv : numpy.ndarray, shape (n, n)
        The transformation and its inverse (columns of V span the blocks' invariant
        subspaces).
    condition : float
        The 1-norm condition number of V without its diagonal balancing (V = D W with D
        diagonal, an exact scaling by powers of two: cond(W) is what round-off sees).
    """

    starts: np.ndarray
    blocks: list
    V: np.ndarray
    V_inv: np.ndarray
    condition: float

    @property
    def sizes(self) -> np.ndarray:
        """Block sizes, shape (r,)."""
        return np.diff(self.starts)


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
        empty = np.zeros((0, 0))
        return BlockDiagonalForm(np.zeros(1, dtype=int), [], empty, empty, 1.0)
    # Balancing first (a diagonal similarity, exact in binary floating point): the Schur
    # form's backward error is ~eps ||A||, and for a mechanical mode [[0, 1], [-w^2, .]]
    # ||A|| ~ w^2 of the stiffest mode where the balanced ||A|| ~ w: slow modes then keep
    # their eigenvalues w_max times more accurately.
    A_balanced, scaling = scipy.linalg.matrix_balance(A, permute=False, separate=True)
    scaling = scaling[0]
    T, Q = scipy.linalg.schur(A_balanced, output="real")
    form = _Decoupling(np.asfortranarray(T), max_coupling)
    form.split(0, n)
    starts = np.array(sorted(form.starts) + [n])
    # The condition number that matters for round-off is that of V without its (exact)
    # diagonal scaling: W = Q Y (one product, used for both).
    W = Q @ form.Y
    V = np.ascontiguousarray(scaling[:, None] * W)
    T = form.T
    V_inv = np.linalg.inv(V)
    W_inv = V_inv * scaling[None, :]
    condition = float(np.abs(W).sum(axis=0).max() * np.abs(W_inv).sum(axis=0).max())
    blocks = [np.array(T[a:b, a:b]) for a, b in zip(starts[:-1], starts[1:])]
    _refine_blocks(A, V, V_inv, starts, blocks)
    return BlockDiagonalForm(starts, blocks, V, V_inv, condition)


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
    scale = np.abs(X).max(axis=axis, keepdims=True)
    exponent = np.maximum(np.frexp(scale)[1], -400)
    sigma = np.ldexp(1.5, exponent + 52 - bits)
    X1 = (X + sigma) - sigma
    return X1, X - X1


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
    k = X.shape[1]
    bits = (53 - int(np.ceil(np.log2(max(k, 2))))) // 2
    X1, X2 = _split(X, 1, bits)
    Y1, Y2 = _split(Y, 0, bits)
    return X1 @ Y1, X1 @ Y2 + X2 @ Y


# Blocks whose spectral radius is below this fraction of max |A| (or of their own max |A_j|)
# are refined by _refine_blocks, as are all blocks larger than 2 x 2.
_REFINE_BELOW = 1e-3


def _refined(block: np.ndarray, norm_A: float) -> bool:
    """Whether a diagonal block is refined (see :func:`_refine_blocks`): a cluster (larger
    than 2 x 2), or a block whose eigenvalues are small next to max |A| or to its own
    entries (a near-defective 2 x 2 block: a free rigid body split off on its own)."""
    if block.shape[0] > 2:
        return True
    radius = np.sqrt(abs(np.linalg.det(block))) if block.shape[0] == 2 else abs(block[0, 0])
    return radius < _REFINE_BELOW * max(norm_A, np.finfo(float).tiny) or (
        block.shape[0] == 2 and radius < _REFINE_BELOW * np.abs(block).max())


def _refine_blocks(A, V, V_inv, starts, blocks) -> None:
    """Replace the diagonal blocks that need it (:func:`_refined`) by the diagonal blocks of
    ``V^-1 A V`` for the float64 V, computed accurately (in place).

    The Schur form leaves every block with a backward error ~eps ||A||: for a cluster of
    defective or close eigenvalues (a free rigid body's double integrator, ||T_c|| ~ 1 in a
    system whose ||A|| is its stiffest mode's frequency) or a slow block that is an error of
    ~eps ||A|| / ||T_c|| relative, and the polynomially growing motion of a defective block
    (a rigid body's position drifts ~t^1.5 under random inputs) carries it into the outputs
    over a long run.  With ``R_c = A V_c - V_c T_c`` computed accurately (error-free
    products, :func:`_accurate_product`), ``T_c + (V^-1)_c R_c`` is the block of the exact
    ``V^-1 A V`` up to ~eps ||T_c|| (its rounding) plus cond(V) eps |(V^-1)_c R_c| (the
    rounding of the small correction): the error a block of its own norm would have.

    Measured on issue 10's general systems (``benchmarks/issue10.py``: 20 to 400 states,
    two rigid bodies in a 4 x 4 cluster): the outputs' error against an extended-precision
    solution fell 2 to 40 times (e.g. 3.7e-11 to 1.0e-12 at 20 states over 1e4 samples),
    at a cost of O(n^2 k) for k refined states.  The other blocks are left alone: refining
    all of them (O(n^3), three more products of order n) changed the errors by under 20 %
    (their round-off does not grow polynomially).
    """
    norm_A = np.abs(A).max()
    chosen = [(j, a, b) for j, (a, b) in enumerate(zip(starts[:-1], starts[1:]))
              if _refined(blocks[j], norm_A)]
    # Far beyond any physical system; sigma of _split would overflow near 2^970.
    if not chosen or max(norm_A, np.abs(V).max()) > 2.0 ** 900:
        return
    columns = np.concatenate([np.arange(a, b) for _, a, b in chosen])
    P1, P2 = _accurate_product(A, V[:, columns])
    first = 0
    for j, a, b in chosen:
        cols = slice(first, first + b - a)
        first += b - a
        Q1, Q2 = _accurate_product(V[:, a:b], blocks[j])
        # P1 - Q1: two exact values of one product that nearly cancel, one rounding.
        residual = (P1[:, cols] - Q1) + (P2[:, cols] - Q2)
        blocks[j] = blocks[j] + V_inv[a:b] @ residual


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

    def _solve(self, k: int, m: int, b: int) -> np.ndarray | None:
        """X with T11 X - X T22 = -T12 for the ranges k:m and m:b, or None if it is
        unbounded or not a solution."""
        T = self.T
        T11, T22, T12 = T[k:m, k:m], T[m:b, m:b], T[k:m, m:b]
        if not np.any(T12):
            return np.zeros_like(T12)
        # trsyl: T11 X + isgn X T22 = scale C, here isgn = -1 and C = -T12.
        X, scale, info = scipy.linalg.lapack.dtrsyl(T11, T22, -T12, isgn=-1)
        if not (info >= 0 and scale == 1.0 and np.all(np.isfinite(X))):
            return None
        if np.abs(X).max() > self.max_coupling:
            return None
        if info != 0 and not _solves(T11, T22, T12, X, self.norm_T):
            return None
        return X

    def _apply(self, k: int, m: int, b: int, X: np.ndarray) -> None:
        self.Y[:b, m:b] += self.Y[:b, k:m] @ X
        self.T[k:m, m:b] = 0.0

    def split(self, a: int, b: int) -> None:
        blocks = _schur_blocks(self.T, a, b)
        if len(blocks) == 1:
            self.starts.append(a)
            return
        m = blocks[len(blocks) // 2][0]
        X = self._solve(a, m, b)
        if X is None:
            self.sequential(a, b)
            return
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
                    # trexc rotates the columns of its "q" argument: Y's rows above b.
                    Yb = np.asfortranarray(self.Y[:b])
                    T, Yb, info = scipy.linalg.lapack.dtrexc(T, Yb, i + 1, k + size + 1,
                                                             overwrite_a=1, overwrite_q=1)
                    self.T = T
                    self.Y[:b] = Yb
                    if info != 0:      # swap refused (ill-conditioned): take all the rest
                        size = b - k
                        break
                # The moved block may have changed size in the swap (re-read it).
                moved = 2 if k + size + 1 < b and T[k + size + 1, k + size] != 0.0 else 1
                cluster.extend(_block_eigenvalues(T, k + size, moved))
                size += moved
            self.starts.append(k)
            k += size
