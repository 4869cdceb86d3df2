"""Modal recursion: an LTI system simulated in block-diagonal coordinates, compiled loop.

With ``A = V diag(A_j) V^-1`` (:func:`.modal_form.block_diagonal_form`, a bounded V), the
modal state ``z = V^-1 x`` obeys ``z' = diag(A_j) z + V^-1 B u``, ``y = C V z + D u``: every
block evolves on its own.  Each block is discretised exactly (:mod:`.discretise`: the Van Loan
exponential of the block, the closed form for undamped 2 x 2 blocks; rigid-body and other
defective blocks exactly too, since nothing here uses eigenvectors), so that

    z[k+1] = Phi z[k] + Gamma0 u[k] + Gamma1 u[k+1],  Phi = diag(Phi_j),

and the recursion costs O(n) per sample (2 x 2 blocks; O(k^2) for a cluster of k close
eigenvalues), run in a compiled loop (:mod:`._modal_kernel`).  Outputs cost O(n p) per sample,
states O(n^2) (``x = V z``, one matrix product per block of samples).

Accuracy: round-off enters through V (relative ~cond(V) eps, once), through the blocks (the
Schur form's backward error ~eps ||A||, removed from the rigid-body, clustered and slow
blocks and from their couplings by :mod:`.modal_form`'s refinement: the maps below go
through its corrected transformation ``V (I + Z)``) and through the recursion (~eps per
step per block, as in any recursion); a 2 x 2 block keeps its eigenvalues to round-off,
where a dense n x n transition matrix perturbs them by ~eps ||Ad||.  Measured against an
extended-precision solution this is 1.4 to 50 times more accurate than stepping the dense
discrete system (forced_response) on issue 10's general systems (``benchmarks/issue10.py``).
"""

from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg

from .discretise import discretise_blocks
from .modal_form import BlockDiagonalForm, block_diagonal_form

__all__ = ["ModalRecursion", "kernel_available"]

# Samples per time block of the compiled loop: its scratch arrays (n_block x (nz + m) each)
# then hold ~16k entries (128 kB), so that the block's products stay in cache.
_BLOCK_ENTRIES = 16384

_kernel = None


def kernel_available() -> bool:
    """Whether the compiled loop (numba) can be loaded."""
    return _load_kernel() is not None


def _load_kernel():
    """The compiled loop, imported (and compiled or loaded from the disk cache) on first use;
    None when numba is not installed."""
    global _kernel
    if _kernel is None:
        try:
            from ._modal_kernel import modal_recursion
        except ImportError:              # numba not installed: the chunked recursion runs
            _kernel = False
        except Exception as error:       # numba installed but unusable (a broken install)
            warnings.warn(f"flexsat: the compiled simulator could not be loaded ({error!s:.200}); "
                          "simulating with the chunked recursion instead", RuntimeWarning,
                          stacklevel=3)
            _kernel = False
        else:
            _kernel = modal_recursion
    return _kernel or None


def _transition_minus_identity(A: np.ndarray, dt: float | None) -> np.ndarray:
    """``Phi - I`` for a stack of blocks (K, s, s): ``e^(A dt) - I`` to round-off relative
    to itself (``A - I`` for a discrete-time recursion, dt None).

    A cluster of defective eigenvalues (free rigid bodies) has Phi ~ I + (A dt): stored as
    Phi, the rounding of its entries near 1 (~1e-16) acts like a growth rate of 1e-16 per
    step, which the bodies' drift integrates (measured: 6.3e-12 of the output range over 5000
    steps on three rigid bodies and three integrators in a random basis, forced_response
    2.5e-12; with Phi - I kept, and the compiled loop adding the state after the small
    terms, 7.3e-13).
    ``e^X - I = X phi1(X)``, ``phi1(X) = sum X^k / (k + 1)!`` read off the exponential of
    ``[[X, I], [0, 0]]`` (Van Loan), so no cancellation against I."""
    if dt is None:
        return A - np.eye(A.shape[1])
    K, s, _ = A.shape
    M = np.zeros((K, 2 * s, 2 * s))
    M[:, :s, :s] = A * dt
    M[:, :s, s:] = np.eye(s)
    with np.errstate(over="ignore", invalid="ignore"):
        phi1 = scipy.linalg.expm(M)[:, :s, s:]
        return (A * dt) @ phi1


class ModalRecursion:
    """Exact discrete recursion of ``x' = A x + B u, y = C x + D u`` in modal coordinates.

    Parameters
    ----------
    A, B, C, D : numpy.ndarray
        Real state-space matrices (continuous time, or the discrete-time recursion itself
        when ``dt`` is None).
    dt : float or None, s
        Sample step; None: A, B are already discrete (``x[k+1] = A x[k] + B u[k]``).
    hold : {"linear", "zero"}
        Input interpolation between samples (continuous time).
    form : BlockDiagonalForm, optional
        The block-diagonal form of A (computed if not given).

    Attributes
    ----------
    form : BlockDiagonalForm
    n_pairs : int
        2 x 2 blocks (pairs of 1 x 1 blocks count as one).
    cluster_sizes : list of int
        Sizes of the larger blocks (clusters of close or defective eigenvalues).
    """

    def __init__(self, A, B, C, D, dt, hold, *, form: BlockDiagonalForm | None = None):
        self.form = form if form is not None else block_diagonal_form(A)
        V = self.form.V
        n, m = B.shape
        p = C.shape[0]
        sizes = self.form.sizes
        starts = self.form.starts[:-1]
        singles = starts[sizes == 1]
        doubles = starts[sizes == 2]
        clusters = [(int(i), int(s)) for i, s in zip(starts, sizes) if s > 2]
        # Pairs: the 2 x 2 blocks, then the 1 x 1 blocks two by two (the last one with a
        # zero dummy state if their number is odd).
        n_pairs = doubles.size + (singles.size + 1) // 2
        nz = 2 * n_pairs + sum(s for _, s in clusters)
        position = np.empty(n, dtype=np.int64)       # modal index -> position in z
        position[doubles] = np.arange(doubles.size)
        position[doubles + 1] = n_pairs + np.arange(doubles.size)
        pair_of_single = doubles.size + np.arange(singles.size) // 2
        position[singles[0::2]] = pair_of_single[0::2]
        position[singles[1::2]] = n_pairs + pair_of_single[1::2]
        cl_starts = [2 * n_pairs]
        for i, s in clusters:
            position[i:i + s] = cl_starts[-1] + np.arange(s)
            cl_starts.append(cl_starts[-1] + s)

        # Exact discretisation, block by block (stacked by size).
        # Through the corrected transformation V (I + Z) (modal_form's refined blocks).
        # z = V^-1 x by the form's LU solve, not an explicit inverse: backward stable, so
        # that the inputs and the initial state seen in x (V z) are B and x0 to ~eps, where
        # the explicit inverse leaves ~cond(V) eps.
        Bz = self.form.left(self.form.solve(B))
        G0z = np.zeros((n, m))
        G1z = np.zeros((n, m))
        f = np.zeros((4, n_pairs))
        cl_Phi = {}
        for s in np.unique(sizes):
            bs = np.flatnonzero(sizes == s)                               # in order of start
            rows = starts[bs][:, None] + np.arange(s)                     # (K, s)
            Ablk = np.array([self.form.blocks[b] for b in bs])
            if dt is None:
                Ad, Bd0, Bd1 = Ablk, Bz[rows], np.zeros((bs.size, s, m))
            else:
                Ad, Bd0, Bd1 = discretise_blocks(Ablk, Bz[rows], dt, hold)
            G0z[rows] = Bd0
            G1z[rows] = Bd1
            if s == 2:
                f[:, :doubles.size] = Ad.reshape(-1, 4).T
            elif s == 1:
                f[0, pair_of_single[0::2]] = Ad[0::2, 0, 0]
                f[3, pair_of_single[1::2]] = Ad[1::2, 0, 0]
            else:
                cl_Phi.update(zip(starts[bs].tolist(), _transition_minus_identity(Ablk, dt)))
        self._f = [np.ascontiguousarray(r) for r in f]
        cl_phi = [cl_Phi[i].ravel() for i, _ in clusters]
        self._cl_starts = np.array(cl_starts, dtype=np.int64)
        self._cl_offsets = np.concatenate([[0], np.cumsum([s * s for _, s in clusters])]
                                          ).astype(np.int64)
        self._cl_phi = np.concatenate(cl_phi) if cl_phi else np.zeros(0)

        # Maps into z's order (dummy states: zero rows and columns).
        self._G0 = np.zeros((m, nz))
        self._G1 = np.zeros((m, nz))
        self._G0[:, position] = G0z.T
        self._G1[:, position] = G1z.T
        self._use_G1 = bool(np.any(self._G1))
        self._HD = np.zeros((nz + m, p))
        self._HD[position] = self.form.right(C @ V).T
        self._HD[nz:] = D.T
        V_corrected = self.form.right(V)
        self._VT = np.zeros((nz + m, n))
        self._VT[position] = V_corrected.T
        self._weights = np.zeros(nz)
        self._weights[position] = np.abs(V_corrected).max(axis=0)
        self._position = position
        self.n_pairs = n_pairs
        self.cluster_sizes = [s for _, s in clusters]
        self._n, self._m, self._p, self._nz = n, m, p, nz
        self._n_block = int(np.clip(_BLOCK_ENTRIES // (nz + m + 1), 16, 4096))

    def flops_per_sample(self, with_states: bool) -> int:
        """Multiply-adds per sample of :meth:`run` (recursion, inputs, outputs, states)."""
        nz, m, p, n = self._nz, self._m, self._p, self._n
        cost = 2 * nz + sum(s * s for s in self.cluster_sizes)
        cost += nz * m * (2 if self._use_G1 else 1) + (nz + m) * p
        return cost + ((nz + m) * n if with_states else 0)

    def run(self, U: np.ndarray, x0: np.ndarray, *, store: bool,
            limit: float) -> tuple[np.ndarray, np.ndarray | None, int]:
        """Outputs (p, N), the modal record or None, and the number of samples kept.

        Parameters
        ----------
        U : numpy.ndarray, shape (m, N)
            Inputs at the samples.
        x0 : numpy.ndarray, shape (n,)
            Initial state (original coordinates).
        store : bool
            Whether to keep the modal states (for :meth:`states`; N (n + m) floats).
        limit : float
            Outputs or (block-end) states beyond this magnitude end the run: the samples
            kept are those before (see :func:`._modal_kernel.modal_recursion`).
        """
        kernel = _load_kernel()
        m, p, nz = self._m, self._p, self._nz
        N = U.shape[1]
        U_rows = np.zeros((N + 1, m))
        U_rows[:N] = U.T
        z0 = np.zeros(nz)
        z0[self._position] = self.form.left(self.form.solve(x0))
        Y = np.empty((N, p))
        Z = np.empty((N, nz + m)) if store else np.empty((0, nz + m))
        f00, f01, f10, f11 = self._f
        kept = kernel(f00, f01, f10, f11, self._cl_starts, self._cl_offsets, self._cl_phi,
                      self._G0, self._G1, self._use_G1, self._HD, self._weights,
                      U_rows, z0, Y, Z, store, self._n_block, limit)
        Y = np.ascontiguousarray(Y[:kept].T)
        return Y, (Z[:kept] if store else None), int(kept)

    def states(self, record: np.ndarray) -> np.ndarray:
        """States (n, N) from the modal record of :meth:`run`: x = V z, one matrix product
        (an F-ordered view of the sample-major result)."""
        return (record @ self._VT).T
