"""Fast frequency response of a state-space model (modal partial fractions)."""
from __future__ import annotations

import math
from typing import Sequence

import numpy as np
import scipy.linalg

__all__ = []  # private helpers of loop, margins and modes


class _ModalEvaluator:
    """Evaluate C (sI - A)^-1 B + D at many complex points in O(n) per point.

    A is brought to complex Schur form with its near-zero eigenvalues (the rigid-body Jordan
    block of a free-floating plant, which is defective and cannot be diagonalised) first,
    T = [[T11, T12], [0, T22]]. The Sylvester equation T11 X - X T22 = -T12 block-diagonalises
    T with S = [[I, X], [0, I]]: S^-1 T S = diag(T11, T22). T22 (well separated, non-defective
    eigenvalues) is diagonalised; the small block T11 is solved directly.

    References
    ----------
    G. H. Golub and C. F. Van Loan, Matrix Computations, 4th ed., 2013, sec. 7.6.3
    (block diagonalisation by a Sylvester equation).

    A discrete-time system is evaluated at z with ``center=1``: its rigid-body block sits at
    z = 1, so A - I takes the place of A and z - 1 that of s (the same partial fractions).
    """

    def __init__(self, A, B, C, D, *, center: float = 0.0):
        self.center = float(center)
        A = np.asarray(A, dtype=float) - self.center * np.eye(np.shape(A)[0])
        self.B = np.asarray(B, dtype=float)
        self.C = np.asarray(C, dtype=float)
        self.D = np.asarray(D, dtype=float)
        n = A.shape[0]
        self.n = n
        if n == 0:
            self.k = 0
            self.modal = True
            self.rigid_tol = 0.0
            return
        # balancing (an exact diagonal similarity, powers of 2) brings a modal block
        # [[0, 1], [-w^2, -2 zeta w]] to norm ~w; the rigid-body Jordan block's eigenvalues are
        # then perturbed by ~sqrt(eps |A|), far below this tolerance
        Ab, (scale, perm) = scipy.linalg.matrix_balance(A, separate=True)
        Tb = np.zeros((n, n))
        Tb[perm, np.arange(n)] = scale  # A = Tb Ab Tb^-1
        self.rigid_tol = 1e-6 * math.sqrt(max(np.linalg.norm(Ab, 1), 1.0))
        T, Z, k = scipy.linalg.schur(Ab.astype(complex), output="complex",
                                     sort=lambda x: abs(x) <= self.rigid_tol)
        self.k = int(k)
        T11, T12, T22 = T[:k, :k], T[:k, k:], T[k:, k:]
        if 0 < k < n:
            X = scipy.linalg.solve_sylvester(T11, -T22, -T12)
        else:
            X = np.zeros((k, n - k), dtype=complex)
        CZ = (self.C @ Tb) @ Z
        ZB = Z.conj().T @ np.linalg.solve(Tb, self.B)
        # C Z S and S^-1 Z^H B with S = [[I, X], [0, I]], S^-1 = [[I, -X], [0, I]]
        self.C1 = CZ[:, :k]
        C2 = CZ[:, k:] + CZ[:, :k] @ X
        self.B1 = ZB[:k] - X @ ZB[k:]
        B2 = ZB[k:]
        self.T11 = T11
        self.modal = True
        if n - k:
            lam, V = np.linalg.eig(T22)
            cond = np.linalg.cond(V)
            if not np.isfinite(cond) or cond > 1e10:
                self.modal = False
            else:
                self.lam = lam
                self.Cm = C2 @ V
                self.Bm = np.linalg.solve(V, B2)
        else:
            self.lam = np.zeros(0, dtype=complex)
            self.Cm = np.zeros((self.C.shape[0], 0), dtype=complex)
            self.Bm = np.zeros((0, self.B.shape[1]), dtype=complex)
        if self.modal:
            # residues R_i = Cm[:, i] Bm[i, :] of the partial fractions, one row per pole:
            # G(s) = D + C1 (sI - T11)^-1 B1 + sum_i R_i / (s - lam_i) is then one matrix product
            p, m = self.C.shape[0], self.B.shape[1]
            self.residues = (self.Cm.T[:, :, None] * self.Bm[:, None, :]).reshape(-1, p * m)
        self.A = A

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """Return G(s), shape (len(s), n_outputs, n_inputs), complex128; inf at a pole."""
        s = np.asarray(s, dtype=complex).reshape(-1) - self.center
        p, m = self.C.shape[0], self.B.shape[1]
        if self.n == 0:
            return np.broadcast_to(self.D.astype(complex), (s.size, p, m)).copy()
        if not self.modal:
            G = np.broadcast_to(self.D.astype(complex), (s.size, p, m)).copy()
            M = s[:, None, None] * np.eye(self.n) - self.A
            try:
                return G + self.C @ np.linalg.solve(M, np.broadcast_to(self.B, (s.size,)
                                                                       + self.B.shape))
            except np.linalg.LinAlgError:
                # a point exactly on a pole (an undamped mode of a sampled plant on the unit
                # circle): G is infinite there, the other points are solved one by one
                for f in range(s.size):
                    try:
                        G[f] += self.C @ np.linalg.solve(M[f], self.B)
                    except np.linalg.LinAlgError:
                        G[f] = complex(np.inf)
                return G
        G = (1.0 / (s[:, None] - self.lam)) @ self.residues + self.D.reshape(1, p * m)
        G = G.reshape(s.size, p, m)
        if self.k:
            # (sI - T11) X = B1 by back substitution (T11 upper triangular), all s at once
            T11, k = self.T11, self.k
            X = np.empty((s.size, k, m), dtype=complex)
            for i in range(k - 1, -1, -1):
                rhs = self.B1[i] + np.einsum("j,fjm->fm", T11[i, i + 1:], X[:, i + 1:])
                X[:, i] = rhs / (s - T11[i, i])[:, None]
            G += np.einsum("pk,fkm->fpm", self.C1, X)
        return G

    def characteristic_frequencies(self) -> np.ndarray:
        """Undamped natural frequencies |lambda| of the non-rigid eigenvalues [rad/s]."""
        if self.n == 0:
            return np.zeros(0)
        lam = (self.lam if self.modal else np.linalg.eigvals(self.A)) + self.center
        w = np.abs(lam)
        return w[w > self.rigid_tol]


def _evaluator(system, inputs: Sequence[str], outputs: Sequence[str]) -> _ModalEvaluator:
    """Evaluator of one block of a system's transfer matrix (at s, or at z if discrete)."""
    i_in = [list(system.input_labels).index(n) for n in inputs]
    i_out = [list(system.output_labels).index(n) for n in outputs]
    return _ModalEvaluator(system.A, system.B[:, i_in], system.C[i_out, :],
                           system.D[np.ix_(i_out, i_in)],
                           center=1.0 if system.isdtime(strict=True) else 0.0)


def _poles_of(ev: _ModalEvaluator) -> np.ndarray:
    """Poles of an evaluator's system (s-plane, or z-plane for a discrete one)."""
    if ev.n == 0:
        return np.zeros(0, dtype=complex)
    if ev.modal:
        return np.concatenate([np.diag(ev.T11), ev.lam]) + ev.center
    return np.linalg.eigvals(ev.A).astype(complex) + ev.center
