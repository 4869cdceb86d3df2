"""Fast frequency response of a state-space model (modal partial fractions), and FRDs.

Cost. A plant in modal form (the spacecraft's plants: A = [[0, I], [-diag(w^2), -C_modal]]
with modal damping, or any A whose sparsity graph falls apart into small decoupled parts) is
set up in O(n): each decoupled part is diagonalised on its own (2 x 2 modal blocks all at
once), so no O(n^3) decomposition of the whole A is made. A dense A costs one Schur
decomposition, O(n^3), once. Either way each frequency then costs O(n) (a sum of partial
fractions), and a sweep is evaluated in chunks of frequencies so that its temporaries stay
below CHUNK_BYTES whatever the number of frequencies and modes.
"""
from __future__ import annotations

import math
import weakref
from typing import Sequence

import control
import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.csgraph

from .arguments import frequency_grid

__all__ = ["CHUNK_BYTES", "ModalEvaluator", "decoupled_parts", "frequency_response_data",
           "modal_evaluator", "siso_zeros"]

#: Largest temporary of one chunk of a frequency sweep [bytes]: the (frequencies x poles)
#: complex matrix of 1 / (s - lambda). 16 MiB: a 400-mode plant (802 poles) is evaluated
#: 1300 frequencies at a time, whatever the length of the sweep.
CHUNK_BYTES = 1 << 24

# components of A's sparsity graph up to this size are diagonalised in one batched call
_SMALL = 2
# eigenvector matrices with a condition number above this are not used (defective blocks):
# partial fractions lose about cond x eps. A small part is solved densely at no real cost, so
# its limit is low (1e6: 1e-10 relative; an exactly defective 2 x 2 block, a critically damped
# mode, computes with cond ~ eps^-1/2 = 7e7); a large part solved densely would cost O(n^3) per
# frequency, so it keeps partial fractions up to 1e10 (1e-6 relative).
_COND_LIMIT_SMALL = 1e6
_COND_LIMIT = 1e10


class ModalEvaluator:
    """Evaluate C (sI - A)^-1 B + D at many complex points in O(n) per point.

    A is balanced, then split into its decoupled parts (connected components of its sparsity
    graph). Parts of one or two states (the modes of a modal realisation) are diagonalised
    together in one batched eigen-decomposition. A larger part, or one holding near-zero
    eigenvalues (the rigid-body Jordan block of a free-floating plant, which is defective and
    cannot be diagonalised), is brought to complex Schur form with its near-zero eigenvalues
    first, T = [[T11, T12], [0, T22]]; the Sylvester equation T11 X - X T22 = -T12
    block-diagonalises it with S = [[I, X], [0, I]]: S^-1 T S = diag(T11, T22). T22 (well
    separated, non-defective eigenvalues) is diagonalised; the small block T11 is solved
    directly. A part whose eigenvectors are ill-conditioned (a defective flexible block) is
    kept as it is and solved densely at each point (cheap for the small parts where it occurs).

    A discrete-time system is evaluated at z with ``center=1``: its rigid-body block sits at
    z = 1, so A - I takes the place of A and z - 1 that of s (the same partial fractions).

    Parameters
    ----------
    A, B, C, D : array_like
        The state-space matrices, (n, n), (n, m), (p, n) and (p, m), in the system's units.
    center : float
        0 for a continuous system (evaluated at s [rad/s]), 1 for a discrete one (at z).

    Attributes
    ----------
    modal : bool
        True when every part was diagonalised or block-diagonalised (no dense solve per point).
    rigid_tol : float
        |eigenvalue| below which an eigenvalue counts as rigid-body (after balancing).

    Notes
    -----
    Calling the evaluator, ``ev(s)``, gives G at each point; :meth:`poles` the eigenvalues of A
    and :meth:`characteristic_frequencies` the undamped frequencies of the non-rigid ones.

    References
    ----------
    G. H. Golub and C. F. Van Loan, Matrix Computations, 4th ed., 2013, sec. 7.6.3
    (block diagonalisation by a Sylvester equation); B. N. Parlett, C. Reinsch, "Balancing a
    matrix for calculation of eigenvalues and eigenvectors", Numer. Math. 13, 1969.
    """

    def __init__(self, A, B, C, D, *, center: float = 0.0):
        self.center = float(center)
        A = np.asarray(A, dtype=float) - self.center * np.eye(np.shape(A)[0])
        self.B = np.asarray(B, dtype=float)
        self.C = np.asarray(C, dtype=float)
        self.D = np.asarray(D, dtype=float)
        self.A = A
        n = A.shape[0]
        p, m = self.C.shape[0], self.B.shape[1]
        self.n = n
        self.dense: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
        self.k = 0
        self.T11 = np.zeros((0, 0), dtype=complex)
        self.C1 = np.zeros((p, 0), dtype=complex)
        self.B1 = np.zeros((0, m), dtype=complex)
        self.lam = np.zeros(0, dtype=complex)
        self.Cm = np.zeros((p, 0), dtype=complex)
        self.Bm = np.zeros((0, m), dtype=complex)
        self.rigid_tol = 0.0
        if n:
            self._decompose(A)
        self.modal = not self.dense
        # a rigid-body block with exactly zero eigenvalues (T11 strictly upper triangular,
        # nilpotent: T11^q = 0) is the finite sum C1 (sI - T11)^-1 B1 = sum_j C1 T11^j B1 /
        # s^(j+1), j < q: its Markov parameters once, then a product per point
        self.rigid_markov = None
        if self.k and not np.any(np.diag(self.T11)):
            power, markov = np.eye(self.k, dtype=complex), []
            while np.any(power) and len(markov) < self.k:
                markov.append((self.C1 @ power @ self.B1).reshape(-1))
                power = power @ self.T11
            self.rigid_markov = np.array(markov)                       # (q, p m)
        # residues R_i = Cm[:, i] Bm[i, :] of the partial fractions, one row per pole:
        # G(s) = D + C1 (sI - T11)^-1 B1 + sum_i R_i / (s - lam_i) is then one matrix product
        self.residues = (self.Cm.T[:, :, None] * self.Bm[:, None, :]).reshape(self.lam.size,
                                                                              p * m)

    def _decompose(self, A: np.ndarray) -> None:
        # balancing (an exact diagonal similarity, powers of 2, and a permutation) brings a
        # modal block [[0, 1], [-w^2, -2 zeta w]] to norm ~w; the rigid-body Jordan block's
        # eigenvalues are then perturbed by ~sqrt(eps |A|), far below this tolerance
        Ab, (scale, perm) = scipy.linalg.matrix_balance(A, separate=True)
        self.rigid_tol = 1e-6 * math.sqrt(max(np.linalg.norm(Ab, 1), 1.0))
        # A = Tb Ab Tb^-1 with Tb[perm[j], j] = scale[j]
        Cb = self.C[:, perm] * scale[None, :]
        Bb = self.B[perm] / scale[:, None]
        n_parts, part_of = decoupled_parts(Ab != 0.0)
        sizes = np.bincount(part_of, minlength=n_parts)
        order = np.argsort(part_of, kind="stable")
        starts = np.concatenate([[0], np.cumsum(sizes)])
        parts = [order[starts[i]:starts[i + 1]] for i in range(n_parts)]
        general = [idx for idx in parts if idx.size > _SMALL]
        lam, Cm, Bm = [], [], []
        for size in range(1, _SMALL + 1):
            group = [idx for idx in parts if idx.size == size]
            if not group:
                continue
            idx = np.array(group)                                   # (g, size)
            M = Ab[idx[:, :, None], idx[:, None, :]]                # (g, size, size)
            w, V = np.linalg.eig(M)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                cond = np.linalg.cond(V) if size > 1 else np.ones(len(group))
            ok = (np.all(np.abs(w) > self.rigid_tol, axis=1) & np.isfinite(cond)
                  & (cond <= _COND_LIMIT_SMALL))
            general += [group[i] for i in np.nonzero(~ok)[0]]
            if not ok.any():
                continue
            idx, w, V = idx[ok], w[ok], V[ok]
            lam.append(w.reshape(-1))
            Cm.append(np.einsum("gpi,gij->gpj", np.moveaxis(Cb[:, idx], 1, 0), V)
                      .transpose(1, 0, 2).reshape(Cb.shape[0], w.size))
            Bm.append(np.linalg.solve(V, Bb[idx].astype(complex)).reshape(w.size, Bb.shape[1]))
        T11s, C1s, B1s = [], [], []
        for idx in general:
            Ap = Ab[np.ix_(idx, idx)]
            T, Z, k = scipy.linalg.schur(Ap.astype(complex), output="complex",
                                         sort=lambda x: abs(x) <= self.rigid_tol)
            T11, T12, T22 = T[:k, :k], T[:k, k:], T[k:, k:]
            if 0 < k < idx.size:
                # T11 and T22 are triangular already: LAPACK's triangular Sylvester solver
                # (solve_sylvester would bring both to Schur form again)
                X, scale, info = scipy.linalg.lapack.ztrsyl(T11, T22, -T12, isgn=-1)
                if info == 0 and scale > 0:
                    X = X / scale
                else:  # close eigenvalues of T11 and T22 (perturbed): the general solver
                    X = scipy.linalg.solve_sylvester(T11, -T22, -T12)
            else:
                X = np.zeros((k, idx.size - k), dtype=complex)
            CZ = Cb[:, idx] @ Z
            ZB = Z.conj().T @ Bb[idx]
            # C Z S and S^-1 Z^H B with S = [[I, X], [0, I]], S^-1 = [[I, -X], [0, I]]
            if k:
                T11s.append(T11)
                C1s.append(CZ[:, :k])
                B1s.append(ZB[:k] - X @ ZB[k:])
            if k == idx.size:
                continue
            C2, B2 = CZ[:, k:] + CZ[:, :k] @ X, ZB[k:]
            w, V = np.linalg.eig(T22)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                cond = np.linalg.cond(V)
            limit = _COND_LIMIT_SMALL if idx.size - k <= _SMALL else _COND_LIMIT
            if not np.isfinite(cond) or cond > limit:
                self.dense.append((T22, B2, C2))
            else:
                lam.append(w)
                Cm.append(C2 @ V)
                Bm.append(np.linalg.solve(V, B2))
        if T11s:
            self.T11 = scipy.linalg.block_diag(*T11s)
            self.C1 = np.hstack(C1s)
            self.B1 = np.vstack(B1s)
            self.k = self.T11.shape[0]
        if lam:
            self.lam = np.concatenate(lam)
            self.Cm = np.hstack(Cm)
            self.Bm = np.vstack(Bm)

    def __call__(self, s: np.ndarray) -> np.ndarray:
        """Return G(s), shape (len(s), n_outputs, n_inputs), complex128; inf at a pole."""
        s = np.asarray(s, dtype=complex).reshape(-1) - self.center
        p, m = self.C.shape[0], self.B.shape[1]
        step = max(1, CHUNK_BYTES // (16 * max(self.lam.size, self.n, 1)))
        if 0 < s.size <= step:
            return self._chunk(s)
        G = np.empty((s.size, p, m), dtype=complex)
        for start in range(0, s.size, step):
            G[start:start + step] = self._chunk(s[start:start + step])
        return G

    def _chunk(self, s: np.ndarray) -> np.ndarray:
        p, m = self.C.shape[0], self.B.shape[1]
        G = (1.0 / (s[:, None] - self.lam)) @ self.residues + self.D.reshape(1, p * m)
        G = G.reshape(s.size, p, m)
        if self.rigid_markov is not None:
            inverse = np.repeat((1.0 / s)[:, None], self.rigid_markov.shape[0], axis=1)
            G += (np.cumprod(inverse, axis=1) @ self.rigid_markov).reshape(s.size, p, m)
        elif self.k:
            # (sI - T11) X = B1 by back substitution (T11 upper triangular), all s at once; X
            # held as (k, f m) so that each step is one matrix-vector product
            T11, k, f = self.T11, self.k, s.size
            X = np.empty((k, f, m), dtype=complex)
            for i in range(k - 1, -1, -1):
                X[i] = self.B1[i]
                if i + 1 < k:
                    X[i] += (T11[i, i + 1:] @ X[i + 1:].reshape(k - i - 1, f * m)).reshape(f, m)
                X[i] /= (s - T11[i, i])[:, None]
            G += (self.C1 @ X.reshape(k, f * m)).reshape(p, f, m).transpose(1, 0, 2)
        for Ad, Bd, Cd in self.dense:
            G += _dense_response(Ad, Bd, Cd, s)
        return G

    def modal_sums(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None:
        """G as sums alone, ``(poles, residues, feedthrough, markov)``, or None.

        G(s) = D + sum_i R_i / (s - lam_i) + sum_j M_j / s^(j+1) (s taken from ``center``),
        the residues R_i one row (p m,) per pole, M_j the Markov parameters of a rigid-body
        block with exactly zero eigenvalues (shape (0, p m): none): the form a compiled
        evaluation sums without per-call overhead (:mod:`controllers.loop`). None when the
        evaluator also needs a triangular solve (a rigid-body block with non-zero
        eigenvalues) or dense solves (ill-conditioned parts) at each point.
        """
        if self.dense or (self.k and self.rigid_markov is None):
            return None
        pm = self.residues.shape[1]
        markov = (self.rigid_markov if self.rigid_markov is not None
                  else np.zeros((0, pm), dtype=complex))
        return (np.ascontiguousarray(self.lam, dtype=complex),
                np.ascontiguousarray(self.residues, dtype=complex),
                np.ascontiguousarray(self.D.reshape(-1), dtype=complex),
                np.ascontiguousarray(markov, dtype=complex))

    def poles(self) -> np.ndarray:
        """Eigenvalues of A (shifted back by ``center``), complex128."""
        dense = [np.linalg.eigvals(Ad) for Ad, _, _ in self.dense]
        return np.concatenate([np.diag(self.T11), self.lam] + dense).astype(complex) \
            + self.center

    def characteristic_frequencies(self) -> np.ndarray:
        """Undamped natural frequencies |lambda| of the non-rigid eigenvalues [rad/s]."""
        if self.n == 0:
            return np.zeros(0)
        w = np.abs(self.poles())
        return w[w > self.rigid_tol]


def decoupled_parts(pattern: np.ndarray) -> tuple[int, np.ndarray]:
    """Weakly connected components of the directed graph with adjacency ``pattern`` (n, n)
    (bool): (number of parts, part of each node); with ``pattern = A != 0`` the decoupled
    parts of a state matrix A (the modes of a modal realisation). Small graphs by the
    transitive closure of the symmetrised pattern (repeated boolean squaring, a few small
    products: a fraction of the cost of building scipy's sparse graph), large ones by scipy's
    sparse graph search; the labels number the parts in the order of their first node either
    way (scipy's own numbering)."""
    n = pattern.shape[0]
    if n > _DENSE_PARTS:
        n_parts, labels = scipy.sparse.csgraph.connected_components(
            scipy.sparse.csr_matrix(pattern), directed=True, connection="weak")
    else:
        reach = (pattern | pattern.T | np.eye(n, dtype=bool)).astype(np.float64)
        for _ in range(max(1, int(math.ceil(math.log2(max(n, 2)))))):
            grown = (reach @ reach) > 0
            if np.array_equal(grown, reach > 0):
                break
            reach = grown.astype(np.float64)
        first = np.argmax(reach > 0, axis=1)          # each node's lowest reachable node
        _, labels = np.unique(first, return_inverse=True)
        n_parts = int(labels.max()) + 1 if n else 0
        return n_parts, labels
    # renumber by first node, as above
    _, order = np.unique(labels, return_index=True)
    rank = np.empty(n_parts, dtype=int)
    rank[np.argsort(order)] = np.arange(n_parts)
    return n_parts, rank[labels]


# graphs up to this many nodes are split into parts densely (decoupled_parts)
_DENSE_PARTS = 256


def _dense_response(A, B, C, s) -> np.ndarray:
    """C (sI - A)^-1 B at each s by a dense solve; inf where sI - A is singular."""
    n = A.shape[0]
    M = s[:, None, None] * np.eye(n) - A
    try:
        return C @ np.linalg.solve(M, np.broadcast_to(B, (s.size,) + B.shape))
    except np.linalg.LinAlgError:
        # a point exactly on a pole (an undamped mode of a sampled plant on the unit circle):
        # G is infinite there, the other points are solved one by one
        G = np.empty((s.size, C.shape[0], B.shape[1]), dtype=complex)
        for f in range(s.size):
            try:
                G[f] = C @ np.linalg.solve(M[f], B)
            except np.linalg.LinAlgError:
                G[f] = complex(np.inf)
        return G


def modal_evaluator(system, inputs: Sequence[str], outputs: Sequence[str]) -> ModalEvaluator:
    """A :class:`ModalEvaluator` of one block of a system's transfer matrix.

    Parameters
    ----------
    system : control.StateSpace
        Continuous (evaluated at s [rad/s]) or discrete (evaluated at z).
    inputs, outputs : sequence of str
        Names of the block's inputs and outputs, in the order of its columns and rows.

    Returns
    -------
    ModalEvaluator
        ``ev(s)`` has shape ``(len(s), len(outputs), len(inputs))``.

    Notes
    -----
    The evaluator of a system is kept while the system lives and given again for the same
    block of the same matrices (compared entry by entry, so a system changed in place gets a
    new one): a controller judged on many plants (a sweep's nominal controller, one per
    sample) is decomposed once.
    """
    inputs, outputs = tuple(inputs), tuple(outputs)
    i_in = [list(system.input_labels).index(n) for n in inputs]
    i_out = [list(system.output_labels).index(n) for n in outputs]
    matrices = (np.asarray(system.A, dtype=float), np.asarray(system.B, dtype=float)[:, i_in],
                np.asarray(system.C, dtype=float)[i_out, :],
                np.asarray(system.D, dtype=float)[np.ix_(i_out, i_in)])
    center = 1.0 if system.isdtime(strict=True) else 0.0
    try:
        kept = _EVALUATORS.setdefault(system, {})
    except TypeError:  # a system that cannot be weakly referenced: no reuse
        kept = {}
    key = (inputs, outputs, center)
    if key in kept:
        known, ev = kept[key]
        if all(np.array_equal(a, b) for a, b in zip(known, matrices)):
            return ev
    ev = ModalEvaluator(*matrices, center=center)
    if len(kept) < _KEPT_BLOCKS:
        kept[key] = (tuple(m.copy() for m in matrices), ev)
    return ev


# a system's evaluators by block, while the system lives (modal_evaluator)
_EVALUATORS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
_KEPT_BLOCKS = 8


def siso_zeros(A, b, c, d) -> np.ndarray:
    """Finite zeros of the SISO system d + c (sI - A)^-1 b, by a standard eigenproblem.

    ``A`` (n, n), ``b`` and ``c`` n-vectors and ``d`` a scalar, real; the zeros come back as a
    complex128 array (empty when there is none), in the units of A's eigenvalues (rad/s, or z
    for a discrete system).

    With d != 0 the zeros are the eigenvalues of A - b c / d. With d = 0 an orthogonal
    (Householder) change of state coordinates x = H z puts the output on the last coordinate,
    c H = gamma e_n^T; on a zero, y = gamma z_n = 0 for all t, hence
    z_n' = A21 z_1 + b_2 u = 0: the zeros are those of the smaller system
    (A11, b1, A21, b2), to which the same applies. Each step removes one state (one unit of
    relative degree) at O(n^2); the final eigenproblem is real and of size n minus the relative
    degree, several times cheaper than the QZ of the (n + 1) pencil [[A, b], [c, d]].

    References
    ----------
    A. Emami-Naeini, P. Van Dooren, "Computation of zeros of linear multivariable systems",
    Automatica 18(4), 1982 (the reduction, here for one input and one output).
    """
    A = np.asarray(A, dtype=float)
    b = np.asarray(b, dtype=float).reshape(-1)
    c = np.asarray(c, dtype=float).reshape(-1)
    d = float(np.asarray(d, dtype=float).reshape(()))
    scale = max(np.linalg.norm(A, 1), np.finfo(float).tiny)
    while A.shape[0]:
        nb, nc = np.linalg.norm(b), np.linalg.norm(c)
        if nb == 0.0 or nc == 0.0:
            return np.zeros(0, dtype=complex)  # G = d: no finite zero
        # d is negligible against the first Markov parameter's size at the system's scale:
        # a zero at |s| ~ |c b| / |d| beyond eps^-1 times the system's scale is at infinity
        if abs(d) * scale > 1e-14 * nb * nc:
            with np.errstate(all="ignore"):
                return np.linalg.eigvals(A - np.outer(b, c) / d).astype(complex)
        n = A.shape[0]
        # Householder H = I - 2 v v^T / (v^T v) with c H = +-|c| e_n^T
        v = c.copy()
        v[-1] += math.copysign(nc, c[-1] if c[-1] != 0 else 1.0)
        beta = 2.0 / (v @ v)
        AH = A - beta * np.outer(A @ v, v)           # A H
        HAH = AH - beta * np.outer(v, v @ AH)        # H A H
        Hb = b - beta * v * (v @ b)
        A, c, b, d = HAH[:n - 1, :n - 1], HAH[n - 1, :n - 1], Hb[:n - 1], Hb[n - 1]
    return np.zeros(0, dtype=complex)


def frequency_response_data(system: control.StateSpace, omega, *, name: str | None = None
                            ) -> control.FrequencyResponseData:
    """``control.FrequencyResponseData`` of a state-space system, O(n) per frequency.

    The same response as ``control.frd(system, omega)`` (which solves an n x n system at each
    frequency), through the modal partial fractions of :class:`ModalEvaluator`: a modal plant
    costs O(n) to set up and O(n) per frequency, any other system one Schur decomposition;
    frequencies are evaluated in chunks, so the memory beyond the result stays below
    CHUNK_BYTES.

    Parameters
    ----------
    system : control.StateSpace
        Continuous (evaluated at s = j omega) or discrete (at z = exp(j omega dt)).
    omega : array of float, rad/s
        Positive finite frequencies (sorted on output).
    name : str, optional
        Name of the result (default the system's).

    Returns
    -------
    control.FrequencyResponseData
        The system's signal names; ``frdata`` of shape (outputs, inputs, frequencies); inf at
        a frequency that falls exactly on an undamped pole.
    """
    if not isinstance(system, control.StateSpace):
        raise TypeError(f"system must be a control.StateSpace; got {type(system).__name__}")
    omega = np.sort(frequency_grid(omega))
    if name is not None and not isinstance(name, str):
        raise TypeError(f"name must be a string or None; got {type(name).__name__}")
    ev = modal_evaluator(system, list(system.input_labels), list(system.output_labels))
    point = np.exp(1j * omega * float(system.dt)) if system.isdtime(strict=True) else 1j * omega
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        G = ev(point)
    return control.frd(np.moveaxis(G, 0, 2), omega, inputs=list(system.input_labels),
                       outputs=list(system.output_labels),
                       name=system.name if name is None else name)
