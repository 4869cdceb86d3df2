"""Chunked (block-processing) recursion of an exact discrete LTI system.

The fallback of :mod:`.simulate` for systems whose modal form is ill-conditioned (and for
runs of fewer samples than states, where its set-up is the cheaper one): it works with the dense
discrete matrices ``x[k+1] = Ad x[k] + Bd0 u[k] + Bd1 u[k+1]``, the ones
:func:`control.forced_response` steps through, and needs no eigen- or Schur decomposition.

Propagation exploits the block-Toeplitz structure of an LTI recursion (block
processing).  The grid is cut into chunks of ``L`` samples.  With
``s`` the first sample of a chunk,

    x[s+L] = x[s] - Delta x[s] + K [u[s]; ...; u[s+L]],  Delta = I - Ad^L,
    x[s+t] = Ad^t x[s] + sum_{j<=t} Gamma[t, j] u[s+j],  0 <= t < L,

where ``Gamma`` holds the Markov parameters ``Ad^d Bd``.  Only the chunk
starts are propagated sequentially (one n x n product per chunk, O(n^2 / L)
per sample); every sample inside every chunk then follows from one matrix
product [x[s]^T, u[s]^T, ..., u[s+L-1]^T] @ F over all chunks at once
(BLAS): O(n (n + L m)) per sample for the states, O(p (n + L m)) for the
outputs alone.  For outputs only (:meth:`Simulator.outputs`, the design-loop
path) the chunk is long, L proportional to n / sqrt(p m) up to 256, so a
sample costs O(n sqrt(p m)), i.e. O(n), after an O(n^3) set-up; the states,
which any method returning n states per sample must write, cost one O(n^2)
product per sample.  L is chosen from a simple cost model (chunk-start step
versus fill-in columns; see _best_chunk_length) and cut, down to 1 (plain
stepping), when a set-up probe finds that formed powers of Ad are less
accurate than stepping: strongly non-normal systems (see _chunk_maps).

References
----------
.. [0] C. F. Van Loan, "Computing integrals involving the matrix
   exponential", IEEE Trans. Automatic Control 23(3), 395-404, 1978.
.. [2] G. F. Franklin, J. D. Powell, M. L. Workman, *Digital Control of
   Dynamic Systems*, 3rd ed., Addison-Wesley, 1998, sec. 6.3 (zero- and
   first-order hold equivalents).
.. [3] C. S. Burrus, "Block realization of digital filters", IEEE Trans.
   Audio and Electroacoustics 20(4), 230-235, 1972 (block processing of
   recursions).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ChunkedRecursion", "OVERFLOW"]

# Memory budget (float64 entries) of a chunk fill-in map.
_CHUNK_MAP_ENTRIES = 6_000_000

#: Chunk-start states (and outputs) beyond this magnitude are treated as overflow: the
#: fill-in maps (Ad^t, t < L) would carry them past the float64 range.
OVERFLOW = 1e250
_OVERFLOW = OVERFLOW


@dataclass(frozen=True)
class _ChunkMaps:
    """Maps of the chunked recursion for chunks of ``L`` samples.

    Chunk starts: ``x[s+L] = x[s] - Delta x[s] + K u_plus`` with
    ``u_plus = [u[s]; ...; u[s+L]]`` and ``Delta = I - Ad^L``.  Inside the
    chunks, with rows of ``M = [x[s]^T, u[s]^T, ..., u[s+L-1]^T]`` (one per
    chunk):
    ``M @ Fy`` gives ``y[s+t]^T`` in columns ``t p .. (t+1) p`` and
    ``M @ Fx`` (None if not built) the states.
    """

    L: int
    DeltaT: np.ndarray          # (I - Ad^L)^T = ((I - Ad) S_L)^T, (n, n)
    KT: np.ndarray              # K^T, ((L+1) m, n)
    Fy: np.ndarray              # (n + L m, L p)
    Fx: np.ndarray | None       # (n + L m, L n)
    accurate_length: int        # longest chunk passing the accuracy probe


def _chunk_maps(Ad, Bd0, Bd1, C, D, L: int, with_states: bool) -> _ChunkMaps:
    """Build the chunk maps (see _ChunkMaps).

    From x[k+1] = Ad x[k] + Bd0 u[k] + Bd1 u[k+1]:

        x[s+t] = Ad^t x[s] + sum_{j=0}^{t} Gamma[t, j] u[s+j],
        Gamma[t, j] = [d >= 1] Ad^(d-1) Bd0 + [j >= 1] Ad^d Bd1,  d = t - j,

    a Toeplitz pattern in d except for the chunk's first input (j = 0),
    which enters only through Bd0.  y[s+t] = C x[s+t] + D u[s+t].

    The chunk-start transition is applied as x - Delta x with
    Delta = I - Ad^L = (I - Ad) S_L, S_L = I + Ad + ... + Ad^(L-1).  For
    slow modes (eigenvalue lambda ~ 1) I - Ad has no cancellation error
    (its diagonal is exact by Sterbenz's lemma) and S_L ~ L I none either,
    so Delta carries relative round-off only.  Forming Ad^L and
    subtracting it from I would leave an absolute error ~ L eps, which the
    steady state (I - Ad^L)^-1 K u of a slow mode amplifies by
    1 / (1 - |lambda|^L).  For other modes both forms carry ~ L eps.

    L is a power of two: every sequence of powers is built by doubling,
    ``[Ad^t]_{t<2k} = [[Ad^t]_{t<k}, Ad^k [Ad^t]_{t<k}]``, so the set-up
    makes O(log L) BLAS calls (each call can wake BLAS threads, which is
    costly on a busy machine).  Cost O(n^3 log L + (n + p) n m L) without
    states; the states' map holds the powers Ad^t, t < L: O(L n^3).
    """
    n, m = Bd0.shape
    p = C.shape[0]
    # Wide and tall arrays of power sequences, filled by doubling:
    # MB = [Ad^t [Bd0, Bd1]]_{t<=L} (column blocks), CA = [C Ad^t]_{t<L}
    # (row blocks), At = [Ad^t]_{t<L} (column blocks, states only).
    MB = np.empty((n, (L + 1) * 2 * m))
    MB[:, :2 * m] = np.hstack([Bd0, Bd1])
    CA = np.empty((L * p, n))
    CA[:p] = C
    At = None
    if with_states:
        At = np.empty((n, L * n))
        At[:, :n] = np.eye(n)
    S = np.eye(n)                      # S_k = I + Ad + ... + Ad^(k-1)
    Ak = Ad.copy()                     # Ad^k
    # Accuracy probe.  A formed power Ad^k applied to x carries the
    # round-off of the product, eps |Ad|^k |x| entrywise, where stepping
    # carries eps |Ad| |Ad^j x| per step.  For strongly non-normal Ad
    # (transient growth, ||Ad|| >> spectral radius) the first is far larger,
    # and outputs that cancel states amplify it.  Two fixed pseudo-random
    # vectors stepped k times are compared with x - Delta_k x; chunks
    # longer than the last k agreeing within 10 k eps are refused.
    # Lightly damped modal loops agree to ~1e-16 k; a random state space
    # with eigenvector condition 1e6 fails at k = 2.
    V = np.random.default_rng(20260523).standard_normal((n, 2))
    W = Ad @ V                         # Ad^k V by steps
    eps = np.finfo(float).eps
    k = 1
    while k < L:
        for _ in range(k):
            W = Ad @ W
        S = S + Ak @ S
        MB[:, 2 * m * k:2 * m * 2 * k] = Ak @ MB[:, :2 * m * k]
        CA[p * k:p * 2 * k] = CA[:p * k] @ Ak
        if At is not None:
            At[:, n * k:n * 2 * k] = Ak @ At[:, :n * k]
        Ak = Ak @ Ak
        k *= 2
        if n:
            SV = S @ V
            error = np.linalg.norm(V - (SV - Ad @ SV) - W) / max(
                np.linalg.norm(W), 1e-3 * np.linalg.norm(V))
            if not (np.isfinite(error) and error <= 3 * k * eps):
                # Refused: the caller rebuilds with chunks of k / 2.
                empty = np.zeros((0, 0))
                return _ChunkMaps(L, empty, empty, empty, None, k // 2)
    Delta = (np.eye(n) - Ad) @ S
    MB[:, 2 * m * L:] = Ak @ MB[:, :2 * m]            # t = L
    MB = MB.reshape(n, L + 1, 2 * m).transpose(1, 0, 2)    # (t, n, 2m)
    CA = CA.reshape(L, p, n)
    # Markov parameters by d = t - j: Psi0[d] = Ad^(d-1) Bd0 (0 for d = 0),
    # Psi1[d] = Ad^d Bd1, d = 0..L.
    Psi0 = np.concatenate([np.zeros((1, n, m)), MB[:L, :, :m]])
    Psi1 = MB[:, :, m:]
    # K[:, j] = Gamma[L, j]: d = L - j.
    K = np.concatenate([Psi0[L][None], Psi0[L - 1::-1][:L] + Psi1[L - 1::-1]
                        [:L]]) if m else np.zeros((L + 1, n, 0))
    KT = K.transpose(0, 2, 1).reshape((L + 1) * m, n)

    Fy = np.zeros((n + L * m, L * p))
    Fy[:n] = CA.transpose(2, 0, 1).reshape(n, L * p)  # [state, (t, output)]
    Fx = None
    if with_states:
        Fx = np.zeros((n + L * m, L * n))
        for t in range(L):        # block by block: cache-friendly
            Fx[:n, t * n:(t + 1) * n] = At[:, t * n:(t + 1) * n].T
    if m:
        CPsi0 = C @ Psi0[:L]                          # (L, p, m)
        CG = CPsi0 + C @ Psi1[:L]
        CPsi0[0] += D
        CG[0] += D
        Fy_u = Fy[n:].reshape(L, m, L, p)            # [j, input, t, output]
        Fx_u = None if Fx is None else Fx[n:].reshape(L, m, L, n)
        G = Psi0[:L] + Psi1[:L]
        for d in range(L):
            j = np.arange(1, L - d)                  # chunk inputs j >= 1
            Fy_u[0, :, d, :] = CPsi0[d].T
            Fy_u[j, :, j + d, :] = CG[d].T
            if Fx_u is not None:
                Fx_u[0, :, d, :] = Psi0[d].T
                Fx_u[j, :, j + d, :] = G[d].T
    return _ChunkMaps(L, np.ascontiguousarray(Delta.T),
                      np.ascontiguousarray(KT), Fy, Fx, L)


# Cost model of the chunk length choice (orders of magnitude measured on a
# 2-core x86-64 with OpenBLAS): a chunk start costs a Python-level step of
# ~3 us plus an n x n matrix-vector product at ~0.3 ns per multiply-add
# (memory bound); the fill-in product runs at ~0.05 ns per multiply-add.
_CHUNK_STEP_NS = 3000.0
_GEMV_NS = 0.3
_GEMM_NS = 0.05


def _best_chunk_length(n: int, m: int, rows: int, low: int,
                       high: int) -> int:
    """Chunk length minimising the time per sample.

    Per sample the chunk starts cost (step + n^2 gemv) / L and the extra
    input columns of the fill-in product rows L m gemm, where rows = n
    (states) or p (outputs only):  L = sqrt((step + n^2 gemv)
    / (rows m gemm)), as a power of two within [low, high].
    """
    start = _CHUNK_STEP_NS + n * n * _GEMV_NS
    per_column = max(rows, 1) * max(m, 1) * _GEMM_NS
    return _power_of_two(np.sqrt(start / per_column), low, high)


def _states_chunk_length(n: int, m: int) -> int:
    """Chunk length for runs with states (see _best_chunk_length); the
    fill-in map, (n + L m) x L n entries, stays within a memory budget.
    """
    L = _best_chunk_length(n, m, n, 4, 64)
    while L > 1 and (n + L * m) * L * n > _CHUNK_MAP_ENTRIES:
        L //= 2
    return L


def _outputs_chunk_length(n: int, m: int, p: int) -> int:
    """Chunk length for outputs only (see _best_chunk_length).

    For large n, L ~ n sqrt(gemv / (p m gemm)), so a sample costs
    O(n sqrt(p m)): O(n) per sample.
    """
    return _best_chunk_length(n, m, p, 16, 256)


def _power_of_two(x: float, low: int, high: int) -> int:
    """The power of two nearest to x (in log scale), within [low, high]."""
    return int(np.clip(2 ** round(np.log2(max(x, 1.0))), low, high))


class ChunkedRecursion:
    """The chunked recursion of ``x[k+1] = Ad x[k] + Bd0 u[k] + Bd1 u[k+1]``,
    ``y = C x + D u`` (see the module docstring).

    The chunk maps of runs with states are built on first use (O(n^3 log L)), the states'
    fill-in map when states are first read (O(L n^3)), the maps of outputs-only runs on
    their first use (O(n^3 log L)).
    """

    def __init__(self, Ad, Bd0, Bd1, C, D):
        self.Ad, self.Bd0, self.Bd1 = Ad, Bd0, Bd1
        self._C, self._D = C, D
        self._maps: dict[bool, _ChunkMaps] = {}
        self._Fx: np.ndarray | None = None

    @property
    def n_states(self) -> int:
        return self.Ad.shape[0]

    @property
    def n_inputs(self) -> int:
        return self._D.shape[1]

    @property
    def n_outputs(self) -> int:
        return self._D.shape[0]

    def chunk_length(self, with_states: bool) -> int:
        """Samples per chunk (from the cost model, shortened by the accuracy probe or the
        float range)."""
        return self._chunk_maps(with_states).L

    def _planned_chunk_length(self, with_states: bool) -> int:
        n, m, p = self.n_states, self.n_inputs, self.n_outputs
        return (_states_chunk_length(n, m) if with_states
                else _outputs_chunk_length(n, m, p))

    def _chunk_maps(self, with_states: bool) -> _ChunkMaps:
        """Chunk maps of run() (with_states) or outputs(); the states' fill-in
        map of run() is built only when states are first read
        (_state_fill_map)."""
        if with_states not in self._maps:
            L = self._planned_chunk_length(with_states)
            with np.errstate(over="ignore", invalid="ignore"):
                while True:
                    maps = _chunk_maps(self.Ad, self.Bd0, self.Bd1, self._C,
                                       self._D, L, False)
                    if maps.accurate_length < L:
                        # Strongly non-normal Ad: shorter chunks.
                        L = maps.accurate_length
                        continue
                    if L == 1 or all(np.all(np.isfinite(M)) for M in
                                     (maps.DeltaT, maps.KT, maps.Fy, maps.Fx)
                                     if M is not None):
                        break
                    # Modes growing past the float range within one chunk
                    # (strongly unstable): shorter chunks.
                    L //= 2
            self._maps[with_states] = maps
        return self._maps[with_states]

    def _state_fill_map(self) -> np.ndarray:
        """Fill-in map of the states for run()'s chunks, built once."""
        if self._Fx is None:
            L = self._maps[True].L
            with np.errstate(over="ignore", invalid="ignore"):
                Fx = _chunk_maps(self.Ad, self.Bd0, self.Bd1, self._C,
                                 self._D, L, True).Fx
            if not np.all(np.isfinite(Fx)):
                raise FloatingPointError(
                    "simulation overflowed: states of this (unstable) system "
                    f"grow past the float64 range within {L} samples")
            self._Fx = Fx
        return self._Fx

    def propagate(self, U, X0, *, with_states: bool, stop: bool = False):
        """Outputs (p, N) from checked U, X0, and a function that computes
        the states (n, N) when called (None if with_states is False).

        With ``stop`` a response that leaves the float range (|x| or |y| >=
        1e250, or not finite) ends at the last sample before (N is then
        smaller than the number of inputs' samples); without, that raises
        FloatingPointError.
        """
        maps = self._chunk_maps(with_states)
        n, m, p = self.n_states, self.n_inputs, self.n_outputs
        L = maps.L
        n_samples = U.shape[1]
        n_chunks = -(-n_samples // L)
        n_padded = n_chunks * L
        with_input = m > 0 and bool(np.any(U))
        # Zero padding past the end changes nothing before it (causality).
        U_pad = np.zeros((m, n_padded + 1))
        U_pad[:, :n_samples] = U
        # One row per chunk: [u[s]^T, u[s+1]^T, ..., u[s+L-1]^T].
        U_chunks = (U_pad[:, :n_padded].reshape(m, n_chunks, L)
                    .transpose(1, 2, 0).reshape(n_chunks, L * m))
        # Chunk-start states, one row per chunk (sequential recursion).
        XsT = np.empty((n_chunks, n))
        XsT[0] = X0
        with np.errstate(over="ignore", invalid="ignore"):
            if with_input and n_chunks > 1:
                # Chunk c needs u[s..s+L]: its inputs and the next chunk's
                # first one.
                U_plus = np.hstack([U_chunks[:-1],
                                    U_pad[:, L:n_padded:L].T])
                ET = U_plus @ maps.KT
                for c in range(n_chunks - 1):
                    np.subtract(XsT[c], XsT[c] @ maps.DeltaT, out=XsT[c + 1])
                    XsT[c + 1] += ET[c]
            else:
                for c in range(n_chunks - 1):
                    np.subtract(XsT[c], XsT[c] @ maps.DeltaT, out=XsT[c + 1])
        # The fill-in maps are bounded (Ad^t, t < L), so finite chunk starts
        # well inside the float range give finite states and outputs.
        with np.errstate(invalid="ignore"):
            bad_start = ~(np.isfinite(XsT).all(axis=1)
                          & (np.abs(XsT).max(axis=1, initial=0.0) < _OVERFLOW))
        n_good = int(np.argmax(bad_start)) if bad_start.any() else n_chunks
        if n_good < n_chunks and not stop:
            raise FloatingPointError(
                "simulation overflowed: the response of this (unstable) "
                "system exceeds the float64 range on this time grid")
        n_kept = min(n_samples, n_good * L)
        M = np.hstack([XsT[:n_good], U_chunks[:n_good]]) if with_input else XsT[:n_good]
        rows = slice(None) if with_input else slice(0, n)
        with np.errstate(over="ignore", invalid="ignore"):
            YT = M @ maps.Fy[rows]
        Y = np.ascontiguousarray(YT.reshape(n_good * L, p)[:n_kept].T)
        with np.errstate(invalid="ignore"):
            bad_y = ~(np.isfinite(Y).all(axis=0) & (np.abs(Y).max(axis=0, initial=0.0) < _OVERFLOW))
        if bad_y.any():
            if not stop:
                raise FloatingPointError(
                    "simulation overflowed: the outputs of this (unstable) "
                    "system exceed the float64 range on this time grid")
            n_kept = int(np.argmax(bad_y))
            Y = Y[:, :n_kept]
        if n_kept == 0:
            raise FloatingPointError("simulation overflowed at the first sample: the "
                                     "initial state or input exceeds the float64 range")
        if not with_states:
            return None, Y

        def fill_states():
            # (n, N), an F-ordered view of the sample-major product.
            XT = M @ self._state_fill_map()[rows]
            return XT.reshape(n_good * L, n)[:n_kept].T
        return fill_states, Y
