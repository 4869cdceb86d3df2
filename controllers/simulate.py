"""Fast, exact time responses of continuous-time LTI state-space systems.

The system ``x' = A x + B u``, ``y = C x + D u`` is discretised exactly on an
evenly spaced time grid (inputs held constant or linear between samples) with
one matrix exponential (Van Loan), giving the recursion
``x[k+1] = Ad x[k] + Bd0 u[k] + Bd1 u[k+1]``.

Propagation exploits the structure of ``Ad``:

1. Set-up, O(n^3) once: the block-diagonal Schur form of ``Ad`` (Bavely and
   Stewart): the real Schur form is split by Sylvester equations into
   clusters of eigenvalues whose decoupling transformation stays well
   conditioned.  A cluster is diagonalised when its eigenvectors are well
   conditioned (lightly damped modes: one complex coordinate per conjugate
   pair) and otherwise (defective rigid-body modes: eigenvalue 1 in a
   Jordan block) kept in its triangular Schur form.
2. The time grid is cut into chunks of ``L`` samples.  The modal coordinates
   at the chunk starts obey ``z[c+1] = Lambda^L z[c] + e[c]``: one scalar
   first-order recursion per mode (triangular back substitution in a
   cluster), O(n) per chunk, run over all chunks at once by
   :func:`scipy.signal.lfilter`.  The forcing ``e[c]`` is a fixed linear
   map of the chunk's inputs.
3. Inside a chunk, ``x[s+t] = P Lambda^t z[s] + sum_j Gamma[t, j] u[s+j]``
   for all chunks at once is one matrix product (BLAS), and the outputs
   likewise with ``C`` folded in.  The outputs alone cost
   O(p (n + L m)) per sample; the states O(n (n + L m)) per sample, which
   any method that returns the n states in the original coordinates pays.

With ``hold="linear"`` (the default) the input is interpreted exactly as
:func:`control.forced_response` and :func:`scipy.signal.lsim` interpret it
(same block exponential, same discrete matrices), so the results agree with
theirs to round-off.

References
----------
.. [1] C. F. Van Loan, "Computing integrals involving the matrix
   exponential", IEEE Trans. Automatic Control 23(3), 395-404, 1978.
.. [2] G. F. Franklin, J. D. Powell, M. L. Workman, *Digital Control of
   Dynamic Systems*, 3rd ed., Addison-Wesley, 1998, sec. 6.3 (zero- and
   first-order hold equivalents).
.. [3] C. A. Bavely, G. W. Stewart, "An algorithm for computing reducing
   subspaces by block diagonalization", SIAM J. Numer. Anal. 16(2),
   359-367, 1979.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg
import scipy.linalg.lapack
import scipy.signal

__all__ = ["HOLDS", "Simulator", "simulate"]

#: Accepted input interpolations between samples.
HOLDS = ("linear", "zero")

# Largest Frobenius norm of a Sylvester solution accepted when splitting a
# cluster of eigenvalues off the rest of the Schur form.  Each split's shear
# [[I, X], [0, I]] then has a condition number below ~(1 + 1e3)^2, so
# round-off in the modal coordinates is amplified by little.
_MAX_SPLIT_NORM = 1e3

# Largest eigenvector condition number for which a cluster is propagated in
# diagonal coordinates; above it the cluster is propagated in triangular
# Schur form (a unitary, perfectly conditioned basis).
_MAX_EIGVEC_COND = 1e3

# Largest 1-norm condition number of the eigenvector matrix of the whole
# transition matrix for which it is used directly (no block-Schur split);
# round-off in the modal coordinates is amplified by at most this factor.
_MAX_DIRECT_EIGVEC_COND = 1e4

# Eigenvalues closer than this (relative to 1 + |lambda|) are put in one
# cluster before any split is tried: numerically equal eigenvalues, such as
# the round-off split of a Jordan block of size <= 3 (eps**(1/3) ~ 6e-6).
_NEAR_EIGENVALUES = 1e-5

# Relative tolerance on the spacing of the time vector.
_SPACING_RTOL = 1e-6

# Memory budget (float64 entries) of the per-chunk state map.
_CHUNK_MAP_ENTRIES = 4_000_000


@dataclass(frozen=True)
class _Cluster:
    """Modes kept together: ``z[k+1] = R z[k] + h[k]``, R upper triangular.

    ``z = left @ x`` for the cluster's coordinates, state contribution
    ``Re(right @ z)``; real clusters have real R, left and right.
    """

    R: np.ndarray
    left: np.ndarray
    right: np.ndarray
    is_real: bool

    @property
    def n_coords(self) -> int:
        """Number of stacked real coordinates (k or 2k)."""
        k = self.R.shape[0]
        return k if self.is_real else 2 * k


@dataclass(frozen=True)
class _Modes:
    """``Ad`` as independent recursions on complex modal coordinates.

    Real modes ``z = real_left @ x`` (contribution ``real_right @ z``),
    complex modes, one per conjugate pair (contribution
    ``Re(cplx_right @ z)``, the factor 2 of the pair is in ``cplx_right``),
    and triangular clusters.  ``Re(right @ z)`` summed over all groups is x.

    The stacked real coordinates ``Zr`` are: the real modes, the real parts
    of the complex modes, their imaginary parts, then per cluster its
    coordinates (real cluster) or their real and imaginary parts.
    """

    real_lam: np.ndarray      # (n_real,) float
    real_left: np.ndarray     # (n_real, n) float
    real_right: np.ndarray    # (n, n_real) float
    cplx_lam: np.ndarray      # (n_cplx,) complex
    cplx_left: np.ndarray     # (n_cplx, n) complex
    cplx_right: np.ndarray    # (n, n_cplx) complex
    clusters: tuple           # of _Cluster

    @property
    def n_coords(self) -> int:
        """Number of stacked real coordinates."""
        return (self.real_lam.size + 2 * self.cplx_lam.size
                + sum(c.n_coords for c in self.clusters))

    def power_list(self, q_max: int) -> list:
        """``[Lambda^q for q = 0..q_max]`` per group, by repeated products.

        Each entry is (real factors, complex factors, [R_c^q per cluster]).
        """
        lr = np.ones_like(self.real_lam)
        lc = np.ones_like(self.cplx_lam)
        lk = [np.eye(c.R.shape[0], dtype=c.R.dtype) for c in self.clusters]
        out = []
        for _ in range(q_max + 1):
            out.append((lr, lc, lk))
            lr, lc = lr * self.real_lam, lc * self.cplx_lam
            lk = [Rq @ c.R for Rq, c in zip(lk, self.clusters)]
        return out

    def project(self, M: np.ndarray) -> tuple:
        """Modal coordinates ``left @ M`` per group of a real (n, k) M."""
        return (self.real_left @ M, self.cplx_left @ M,
                [c.left @ M for c in self.clusters])

    def stacked_rows(self, projected: tuple, power: tuple) -> np.ndarray:
        """Stacked real rows of ``Lambda^q @ projected`` (see project)."""
        pr, pc, pk = projected
        lr, lc, lk = power
        rows = [lr[:, None] * pr]
        c = lc[:, None] * pc
        rows += [c.real, c.imag]
        for clu, Rq, Mk in zip(self.clusters, lk, pk):
            c = Rq @ Mk
            rows += [c.real] if clu.is_real else [c.real, c.imag]
        return np.vstack(rows)

    def stacked_cols(self, power: tuple) -> np.ndarray:
        """Real (n, n_coords) map of the stacked coordinates to
        ``x = Re(right @ Lambda^q z)``, using Re(w z) = Re w Re z - Im w Im z.
        """
        lr, lc, lk = power
        cols = [self.real_right * lr]
        w = self.cplx_right * lc
        cols += [w.real, -w.imag]
        for clu, Rq in zip(self.clusters, lk):
            w = clu.right @ Rq
            cols += [w.real] if clu.is_real else [w.real, -w.imag]
        return np.hstack(cols)


class Simulator:
    """Exact simulator of one continuous-time StateSpace on a fixed step.

    The discretisation, the modal decomposition and the chunk maps (O(n^3))
    are computed once on construction; :meth:`run` then costs O(n) per
    sample for the modal recursions plus matrix products (BLAS) that fill
    in the states and outputs, so design loops that simulate the same system
    many times pay the set-up once.

    Parameters
    ----------
    system : control.StateSpace
        Continuous-time system (``system.dt == 0``) with real, finite
        matrices.  Time in s; states, inputs and outputs in the system's units.
    dt : float, s
        Sample step, positive and finite.
    hold : {"linear", "zero"}
        Input interpolation between samples: ``"linear"`` (first-order hold,
        as :func:`control.forced_response` and :func:`scipy.signal.lsim`) or
        ``"zero"`` (zero-order hold, as ``control.c2d(system, dt, "zoh")``).

    Attributes
    ----------
    system : control.StateSpace
        The simulated system.
    dt : float, s
        Sample step.
    hold : str
        Input interpolation.
    Ad, Bd0, Bd1 : numpy.ndarray
        Exact discrete matrices, ``x[k+1] = Ad x[k] + Bd0 u[k] + Bd1 u[k+1]``
        (``Bd1`` is zero for ``hold="zero"``).
    chunk_length : int
        Samples per chunk of the propagation (see the module docstring).

    Examples
    --------
    >>> sim = Simulator(plant, 0.01)                      # doctest: +SKIP
    >>> T = np.arange(10001) * 0.01
    >>> for gain in gains:                                # doctest: +SKIP
    ...     resp = sim.run(T, gain * np.sin(T))

    References
    ----------
    .. [1] C. F. Van Loan, "Computing integrals involving the matrix
       exponential", IEEE Trans. Automatic Control 23(3), 1978.
    .. [2] C. A. Bavely, G. W. Stewart, "An algorithm for computing reducing
       subspaces by block diagonalization", SIAM J. Numer. Anal. 16(2), 1979.
    """

    def __init__(self, system: control.StateSpace, dt: float, *,
                 hold: str = "linear") -> None:
        _check_system(system)
        dt = _check_dt(dt)
        if hold not in HOLDS:
            raise ValueError(f"hold must be one of {HOLDS}; got {hold!r}")
        self.system = system
        self.dt = dt
        self.hold = hold
        A, B, C, D = (np.array(M, dtype=float) for M in
                      (system.A, system.B, system.C, system.D))
        self._D = D
        n, m = B.shape
        self.Ad, self.Bd0, self.Bd1 = _discretise(A, B, dt, hold)
        modes = self._modes = _modal_form(self.Ad)
        self._C = C
        L = _chunk_length(n, modes.n_coords, m)
        with np.errstate(over="ignore", invalid="ignore"):
            self._build_chunk_maps(L)
            if L > 1 and not all(np.all(np.isfinite(M)) for M in
                                 (self._Fx, self._Fy, self._K)):
                # Modes growing past the float range within one chunk
                # (absurdly unstable): fall back to one sample per chunk.
                self._build_chunk_maps(1)

    def _build_chunk_maps(self, L: int) -> None:
        """Chunk-start recursion and fill-in maps for chunks of L samples."""
        modes, hold = self._modes, self.hold
        C, D = self._C, self._D
        n, m, p = self.n_states, self.n_inputs, self.n_outputs
        n_z = modes.n_coords
        self.chunk_length = L
        powers = modes.power_list(L)
        self._left = modes.stacked_rows(modes.project(np.eye(n)), powers[0])

        # Chunk-start recursion z[c+1] = Lambda^L z[c] + K @ [u[s..s+L]]:
        # x[s+L] = Ad^L x[s] + sum_{j<L} Ad^{L-1-j} (Bd0 u[s+j]
        # + Bd1 u[s+j+1]), so the input u[s+j] enters through
        # [j < L] Lambda^{L-1-j} G0 + [j >= 1] Lambda^{L-j} G1 (G = left Bd).
        lr, lc, lk = powers[L]
        self._carry = (lr, lc, [(RL, clu.is_real) for RL, clu
                                in zip(lk, modes.clusters)])
        G0, G1 = modes.project(self.Bd0), modes.project(self.Bd1)
        K = np.zeros((n_z, (L + 1) * m))
        for j in range(L + 1):
            block = K[:, j * m:(j + 1) * m]
            if j < L:
                block += modes.stacked_rows(G0, powers[L - 1 - j])
            if j >= 1 and hold == "linear":
                block += modes.stacked_rows(G1, powers[L - j])
        self._K = K

        # Inside a chunk: x[s+t] = P_t z[s] + sum_{j<=t} Gamma[t, j] u[s+j]
        # with P_t = P Lambda^t and (a Toeplitz pattern in d = t - j)
        # Gamma[t, j] = [d >= 1] Ad^{d-1} Bd0 + [j >= 1] Ad^d Bd1;
        # y[s+t] = C x[s+t] + D u[s+t].  Stored transposed so that one
        # product [z[s]^T, u-chunk^T] @ F gives all chunks sample-major
        # (rows: chunks; columns: (t, state)).
        Fx = np.zeros((n_z + L * m, L * n))
        Fy = np.zeros((n_z + L * m, L * p))
        for t in range(L):
            P_t = modes.stacked_cols(powers[t])
            Fx[:n_z, t * n:(t + 1) * n] = P_t.T
            Fy[:n_z, t * p:(t + 1) * p] = (C @ P_t).T
        Fx_u = Fx[n_z:].reshape(L, m, L, n)          # [j, input, t, state]
        Fy_u = Fy[n_z:].reshape(L, m, L, p)
        Psi0 = np.zeros((n, m))                      # Ad^{d-1} Bd0
        Psi1 = self.Bd1.copy()                       # Ad^d Bd1
        for d in range(L):
            feedthrough = D if d == 0 else 0.0
            Fx_u[0, :, d, :] = Psi0.T
            Fy_u[0, :, d, :] = (C @ Psi0 + feedthrough).T
            j = np.arange(1, L - d)
            Fx_u[j, :, j + d, :] = (Psi0 + Psi1).T
            Fy_u[j, :, j + d, :] = (C @ (Psi0 + Psi1) + feedthrough).T
            Psi0 = self.Bd0 if d == 0 else self.Ad @ Psi0
            Psi1 = self.Ad @ Psi1
        self._Fx, self._Fy = Fx, Fy

    @property
    def n_states(self) -> int:
        """Number of states."""
        return self.Ad.shape[0]

    @property
    def n_inputs(self) -> int:
        """Number of inputs."""
        return self._D.shape[1]

    @property
    def n_outputs(self) -> int:
        """Number of outputs."""
        return self._D.shape[0]

    def run(self, T, U=None, X0=None, *, squeeze: bool | None = None
            ) -> control.TimeResponseData:
        """Simulate on the time grid ``T`` (step ``self.dt``).

        Parameters
        ----------
        T : array_like, shape (n_samples,), s
            Evenly spaced increasing sample times with step ``self.dt``
            (relative tolerance 1e-6); at least 2 samples.
        U : array_like or float, optional
            Inputs at the samples, shape ``(n_inputs, n_samples)``
            (``(n_samples,)`` allowed for one input); a scalar is held
            constant.  Default 0.
        X0 : array_like or float, optional
            Initial state at ``T[0]``, shape ``(n_states,)``; a scalar fills
            it.  Default 0.
        squeeze : bool, optional
            As in :func:`control.forced_response` (default: 1-D outputs for
            a SISO system, 2-D otherwise).

        Returns
        -------
        control.TimeResponseData
            ``time`` (n_samples,), ``outputs``, ``states`` (n_states,
            n_samples) and ``inputs`` with the system's signal names; the
            shapes are those :func:`control.forced_response` returns.
        """
        T, U, X0 = self._check_run_arguments(T, U, X0)
        X, Y = self._propagate(U, X0, with_states=True)
        sys = self.system
        return control.TimeResponseData(
            T, Y, X, U, issiso=sys.issiso(),
            output_labels=sys.output_labels, state_labels=sys.state_labels,
            input_labels=sys.input_labels, sysname=sys.name,
            title="Simulated response for " + sys.name,
            trace_types=["forced"], plot_inputs=True,
            return_x=control.config.defaults["forced_response.return_x"],
            squeeze=squeeze)

    def outputs(self, T, U=None, X0=None) -> np.ndarray:
        """Outputs only, shape (n_outputs, n_samples): the design-loop path.

        Same arguments and results as :meth:`run` (``run(...).y``), without
        the state trajectory, whose fill-in costs O(n^2) per sample; the
        outputs alone cost O(p (n + L m)) per sample.

        Parameters
        ----------
        T, U, X0
            As in :meth:`run`.

        Returns
        -------
        numpy.ndarray, shape (n_outputs, n_samples)
            Outputs in the system's units.
        """
        T, U, X0 = self._check_run_arguments(T, U, X0)
        return self._propagate(U, X0, with_states=False)[1]

    def _check_run_arguments(self, T, U, X0):
        T = _check_time(T)
        dt = (T[-1] - T[0]) / (T.size - 1)
        if abs(dt - self.dt) > _SPACING_RTOL * self.dt:
            raise ValueError(
                f"T must have the simulator's step dt = {self.dt!r} s; got "
                f"a step of {dt!r} s (build a Simulator for this step)")
        U = _check_inputs(U, self.n_inputs, T.size)
        X0 = _check_initial_state(X0, self.n_states)
        return T, U, X0

    def _propagate(self, U, X0, *, with_states: bool):
        """States (n, N) or None, and outputs (p, N), from checked U, X0."""
        n, m, p = self.n_states, self.n_inputs, self.n_outputs
        L = self.chunk_length
        n_samples = U.shape[1]
        n_chunks = -(-n_samples // L)
        n_padded = n_chunks * L
        with_input = m > 0 and bool(np.any(U))
        # Zero padding past the end changes nothing before it (causality).
        U_pad = np.zeros((m, n_padded + 1))
        U_pad[:, :n_samples] = U
        # Chunk inputs, one row per chunk: [u[s]; u[s+1]; ...; u[s+L-1]].
        U_chunks = (U_pad[:, :n_padded].reshape(m, n_chunks, L)
                    .transpose(1, 2, 0).reshape(n_chunks, L * m))
        n_z = self._left.shape[0]
        Zs = np.empty((n_z, n_chunks))
        Zs[:, 0] = self._left @ X0
        E = None
        if with_input and n_chunks > 1:
            # Chunk c's forcing needs u[s..s+L]: its own inputs plus the
            # first input of the next chunk.
            U_plus = np.hstack([U_chunks[:-1],
                                U_pad[:, L:n_padded:L].T])
            E = self._K @ U_plus.T
        with np.errstate(over="ignore", invalid="ignore"):
            _run_recursions(*self._carry, Zs, E)
        # The fill-in maps are bounded (|Lambda^t| for t < L), so finite
        # chunk-start coordinates well inside the float range give finite
        # states and outputs.
        if not (np.all(np.isfinite(Zs))
                and (Zs.size == 0 or np.abs(Zs).max() < 1e250)):
            raise FloatingPointError(
                "simulation overflowed: the response of this (unstable) "
                "system exceeds the float64 range on this time grid")
        M = np.hstack([Zs.T, U_chunks]) if with_input else Zs.T
        rows = slice(None) if with_input else slice(0, n_z)
        YT = M @ self._Fy[rows]
        Y = np.ascontiguousarray(YT.reshape(n_padded, p)[:n_samples].T)
        if not np.all(np.isfinite(Y)):
            raise FloatingPointError(
                "simulation overflowed: the outputs of this (unstable) "
                "system exceed the float64 range on this time grid")
        X = None
        if with_states:
            XT = M @ self._Fx[rows]
            X = XT.reshape(n_padded, n)[:n_samples].T
        return X, Y


def simulate(system: control.StateSpace, T, U=None, X0=None, *,
             hold: str = "linear", squeeze: bool | None = None
             ) -> control.TimeResponseData:
    """Exact time response of a continuous-time StateSpace.

    A drop-in replacement for :func:`control.forced_response` on
    continuous-time state-space systems: same arguments ``T, U, X0``, same
    interpretation of the input (``hold="linear"``), same returned shapes and
    signal names, results equal to round-off; much faster for large systems
    and long grids (``benchmarks/bench_simulate.py``).

    Parameters
    ----------
    system : control.StateSpace
        Continuous-time system (``system.dt == 0``), real finite matrices.
    T : array_like, shape (n_samples,), s
        Evenly spaced increasing sample times (at least 2).  Uneven grids
        are rejected, as :func:`control.forced_response` rejects them:
        resample the input on an even grid or run a :class:`Simulator` per
        segment (passing the last state on as ``X0``).
    U : array_like or float, optional
        Inputs, shape ``(n_inputs, n_samples)`` (``(n_samples,)`` allowed
        for one input); a scalar is held constant.  Default 0.
    X0 : array_like or float, optional
        Initial state at ``T[0]``, shape ``(n_states,)``.  Default 0.
    hold : {"linear", "zero"}
        ``"linear"``: inputs vary linearly between samples (first-order
        hold, as forced_response and scipy.signal.lsim).  ``"zero"``: inputs
        held constant over each step (zero-order hold, as
        ``control.c2d(system, dt, "zoh")``).
    squeeze : bool, optional
        As in :func:`control.forced_response` (default: 1-D outputs for a
        SISO system, 2-D otherwise).

    Returns
    -------
    control.TimeResponseData
        ``time``, ``outputs``, ``states``, ``inputs`` with the system's
        signal names.

    Raises
    ------
    TypeError
        ``system`` is not a ``control.StateSpace``.
    ValueError
        Discrete-time system, non-finite or badly shaped ``T``, ``U`` or
        ``X0``, uneven ``T``, unknown ``hold``.
    FloatingPointError
        The response of an unstable system overflows float64.

    See Also
    --------
    Simulator : the reusable object (set-up once, many runs).

    References
    ----------
    .. [1] C. F. Van Loan, "Computing integrals involving the matrix
       exponential", IEEE Trans. Automatic Control 23(3), 1978.
    """
    _check_system(system)
    T = _check_time(T)
    dt = (T[-1] - T[0]) / (T.size - 1)
    return Simulator(system, dt, hold=hold).run(T, U, X0, squeeze=squeeze)


# --------------------------------------------------------------------------
# Discretisation
# --------------------------------------------------------------------------

def _discretise(A, B, dt, hold):
    """Exact discrete matrices from ONE matrix exponential (Van Loan).

    Zero-order hold (u constant on [0, dt]): the augmented state [x; u]
    obeys d/dt [x; u] = [[A, B], [0, 0]] [x; u], hence

        expm([[A dt, B dt], [0, 0]]) = [[Ad, Bd], [0, I]],
        Ad = e^{A dt},  Bd = int_0^dt e^{A s} ds B,
        x[k+1] = Ad x[k] + Bd u[k].

    First-order hold (u(t) = u0 + (u1 - u0) t/dt on [0, dt]): with the
    step's input change v = u1 - u0 (constant) the state [x; u; v] obeys
    dx/dt = A x + B u,  du/dt = v / dt,  dv/dt = 0;  in the scaled time
    t/dt the generator is [[A dt, B dt, 0], [0, 0, I], [0, 0, 0]], so

        expm([[A dt, B dt, 0], [0, 0, I], [0, 0, 0]])
            = [[Ad, G1, G2], [0, I, I], [0, 0, I]],
        x(dt) = Ad x0 + G1 u0 + G2 (u1 - u0)
              = Ad x0 + (G1 - G2) u0 + G2 u1,
        G1 = int_0^dt e^{A s} ds B,
        G2 = int_0^dt e^{A (dt - s)} (s / dt) ds B.

    This is the block matrix of control.forced_response and
    scipy.signal.lsim, so Ad, Bd0 = G1 - G2 and Bd1 = G2 are identical to
    theirs.
    """
    n, m = B.shape
    if hold == "zero":
        M = np.zeros((n + m, n + m))
        M[:n, :n] = A * dt
        M[:n, n:] = B * dt
        E = scipy.linalg.expm(M)
        return E[:n, :n], E[:n, n:], np.zeros((n, m))
    M = np.block([[A * dt, B * dt, np.zeros((n, m))],
                  [np.zeros((m, n + m)), np.identity(m)],
                  [np.zeros((m, n + 2 * m))]])
    E = scipy.linalg.expm(M)
    Ad = E[:n, :n]
    Bd1 = E[:n, n + m:]
    Bd0 = E[:n, n:n + m] - Bd1
    return Ad, Bd0, Bd1

def _chunk_length(n: int, n_coords: int, n_inputs: int) -> int:
    """Samples per chunk.

    A chunk costs the recursions O(n) once and the fill-in product
    O((n_coords + L m) n) per sample: L ~ 16/sqrt(m) balances the scalar
    recursions (compiled, ~10 ns per mode and chunk) against the extra
    L m columns of the product (BLAS, ~0.03 ns per multiply-add); the map
    F of size (n_coords + L m) x L n is kept within a memory budget.
    """
    if n_inputs == 0:
        L = 32
    else:
        L = int(np.clip(round(16.0 / np.sqrt(n_inputs)), 4, 32))
    while L > 1 and (n_coords + L * n_inputs) * L * max(n, 1) \
            > _CHUNK_MAP_ENTRIES:
        L //= 2
    return L


# --------------------------------------------------------------------------
# Block-modal form of the transition matrix
# --------------------------------------------------------------------------

def _schur_blocks(T):
    """Rows, sizes and eigenvalues (Im >= 0) of the diagonal blocks of T."""
    n = T.shape[0]
    starts_pair = np.zeros(n, dtype=bool)
    starts_pair[:-1] = np.diag(T, -1) != 0.0
    second = np.zeros(n, dtype=bool)
    second[1:] = starts_pair[:-1]
    rows = np.flatnonzero(~second)
    sizes = np.where(starts_pair[rows], 2, 1)
    lam = T[rows, rows].astype(complex)
    pair = sizes == 2
    if np.any(pair):
        r = rows[pair]
        a, b = T[r, r], T[r, r + 1]
        c, d = T[r + 1, r], T[r + 1, r + 1]
        # Eigenvalues of [[a, b], [c, d]]: (a+d)/2 +- sqrt(((a-d)/2)^2 + bc).
        disc = ((a - d) / 2) ** 2 + b * c
        lam[pair] = (a + d) / 2 + 1j * np.sqrt(np.maximum(-disc, 0.0))
    return rows, sizes, lam


def _block_diagonal_schur(Ad):
    """Block-diagonal real Schur form ``Ad = S diag(T_1, ..., T_r) S^-1``.

    Bavely-Stewart: walking down the real Schur form, a cluster of leading
    blocks ``T11`` is split off the trailing ``T22`` by the shear
    ``[[I, X], [0, I]]`` with ``T11 X - X T22 = -T12`` (which zeroes the
    coupling ``T12``) when ``||X||_F <= _MAX_SPLIT_NORM``; otherwise the
    trailing eigenvalue nearest to the cluster is moved next to it
    (LAPACK dtrexc, orthogonal swaps) and joins it.  Returns ``T`` (block
    diagonal), ``S`` and the list of cluster ranges ``(start, stop)``.
    """
    T, S = scipy.linalg.schur(Ad, output="real")
    T, S = np.asfortranarray(T), np.asfortranarray(S)
    n = T.shape[0]
    rows, sizes, lams = _schur_blocks(T)
    ranges = []
    start = 0
    while start < n:
        first = int(np.searchsorted(rows, start))
        stop = start + int(sizes[first])
        members = [lams[first]]
        nxt = first + 1                 # first trailing block
        gather_near = True
        while stop < n:
            cluster = np.array(members)
            dist = np.min(np.abs(lams[nxt:, None] - cluster[None, :]), axis=1)
            if gather_near:
                # Numerically equal eigenvalues join without a split try.
                scale = 1.0 + np.abs(cluster).max()
                near = np.flatnonzero(dist <= _NEAR_EIGENVALUES * scale)
                if near.size == 0:
                    gather_near = False
                    continue
                j = int(near[0])
            else:
                X, scale_x, info = scipy.linalg.lapack.dtrsyl(
                    T[start:stop, start:stop], T[stop:, stop:],
                    -T[start:stop, stop:], isgn=-1)
                if (info == 0 and scale_x == 1.0 and np.all(np.isfinite(X))
                        and np.linalg.norm(X) <= _MAX_SPLIT_NORM):
                    # Shear: S <- S [[I, X], [0, I]] zeroes T12.
                    S[:, stop:] += S[:, start:stop] @ X
                    T[start:stop, stop:] = 0.0
                    break
                j = int(np.argmin(dist))
                gather_near = True      # its near twins come along
            row = int(rows[nxt + j])
            if row != stop:
                T2, S2, info = scipy.linalg.lapack.dtrexc(T, S, row + 1,
                                                          stop + 1)
                if info != 0:
                    # Swap refused (eigenvalues too close to reorder
                    # stably): take every block up to that one instead.
                    members += list(lams[nxt:nxt + j + 1])
                    stop = row + int(sizes[nxt + j])
                    nxt += j + 1
                    continue
                T, S = np.asfortranarray(T2), np.asfortranarray(S2)
                rows, sizes, lams = _schur_blocks(T)
                nxt = int(np.searchsorted(rows, stop))
            members.append(lams[nxt])
            stop += int(sizes[nxt])
            nxt += 1
        ranges.append((start, stop))
        start = stop
    return T, S, ranges


def _modal_form(Ad: np.ndarray) -> _Modes:
    """Split ``Ad`` into independent recursions (see _Modes)."""
    n = Ad.shape[0]
    real_lam, real_left, real_right = [np.zeros(0)], [np.zeros((0, n))], \
        [np.zeros((n, 0))]
    cplx_lam, cplx_left, cplx_right = [np.zeros(0, complex)], \
        [np.zeros((0, n), complex)], [np.zeros((n, 0), complex)]
    clusters = []
    if n == 0:
        return _Modes(np.zeros(0), np.zeros((0, 0)), np.zeros((0, 0)),
                      np.zeros(0, complex), np.zeros((0, 0), complex),
                      np.zeros((0, 0), complex), ())
    # Distinct, well separated eigenvalues (the common case): one
    # eigendecomposition.  Its basis is accepted if well conditioned
    # (1-norm condition number); otherwise, e.g. for a Jordan block, the
    # block-diagonal Schur form below.
    lam, V = scipy.linalg.eig(Ad)
    try:
        W = np.linalg.inv(V)
    except np.linalg.LinAlgError:
        W = None
    if W is not None and np.all(np.isfinite(W)) and (
            np.linalg.norm(V, 1) * np.linalg.norm(W, 1)
            <= _MAX_DIRECT_EIGVEC_COND):
        # LAPACK returns exactly real eigenvectors for real eigenvalues and
        # conjugate pairs as adjacent conjugate columns (Im > 0 first).
        real, upper = lam.imag == 0.0, lam.imag > 0.0
        return _Modes(lam.real[real], W[real].real, V[:, real].real,
                      lam[upper], W[upper], 2.0 * V[:, upper], ())
    T, S, ranges = _block_diagonal_schur(Ad)
    S_inv = np.linalg.inv(S)
    bounds = np.array(ranges)
    size = bounds[:, 1] - bounds[:, 0]
    # 1x1 clusters: real modes.
    r1 = bounds[size == 1, 0]
    real_lam.append(T[r1, r1])
    real_left.append(S_inv[r1])
    real_right.append(S[:, r1])
    # 2x2 clusters: a complex pair or two real eigenvalues, diagonalised
    # together (vectorised) when the eigenvectors are well conditioned.
    r2 = bounds[size == 2, 0]
    generic = [tuple(b) for b in bounds[size > 2]]
    if r2.size:
        idx = r2[:, None] + np.arange(2)
        blocks = T[idx[:, :, None], idx[:, None, :]]          # (K, 2, 2)
        lam, V = np.linalg.eig(blocks.astype(complex))
        with np.errstate(all="ignore"):
            cond = np.linalg.cond(V)
        is_pair = np.abs(lam[:, 0].imag) > 0.0
        good = np.isfinite(cond) & (cond <= _MAX_EIGVEC_COND) & is_pair
        generic += [(int(r), int(r) + 2) for r in r2[~good]]
        if np.any(good):
            lam, V, idx = lam[good], V[good], idx[good]
            W = np.linalg.inv(V)
            # Keep the member of each conjugate pair with Im > 0; its
            # contribution to the state is 2 Re(v z).
            pick = np.where(lam[:, 0].imag > 0.0, 0, 1)
            k = np.arange(lam.shape[0])
            cplx_lam.append(lam[k, pick])
            w = W[k, pick, :]                                   # (K, 2)
            v = V[k, :, pick]                                   # (K, 2)
            cplx_left.append(np.einsum("kj,kjn->kn", w, S_inv[idx]))
            cplx_right.append(2.0 * np.einsum("nkj,kj->nk", S[:, idx], v))
    for start, stop in generic:
        B = T[start:stop, start:stop]
        Sl, Sr = S_inv[start:stop], S[:, start:stop]
        lam, V = scipy.linalg.eig(B)
        with np.errstate(all="ignore"):
            cond = np.linalg.cond(V)
        if np.isfinite(cond) and cond <= _MAX_EIGVEC_COND:
            W = np.linalg.inv(V)
            # LAPACK returns exactly real eigenvectors for real eigenvalues
            # and conjugate pairs as adjacent conjugate columns.
            real = lam.imag == 0.0
            upper = lam.imag > 0.0
            real_lam.append(lam.real[real])
            real_left.append((W[real] @ Sl).real)
            real_right.append((Sr @ V[:, real]).real)
            cplx_lam.append(lam[upper])
            cplx_left.append(W[upper] @ Sl)
            cplx_right.append(2.0 * (Sr @ V[:, upper]))
        elif np.all(np.diag(B, -1) == 0.0):
            # Only real eigenvalues: B is already upper triangular.
            clusters.append(_Cluster(B.copy(), Sl, Sr, True))
        else:
            R, U = scipy.linalg.schur(B.astype(complex), output="complex")
            clusters.append(_Cluster(R, U.conj().T @ Sl, Sr @ U, False))
    return _Modes(np.concatenate(real_lam), np.vstack(real_left),
                  np.hstack(real_right), np.concatenate(cplx_lam),
                  np.vstack(cplx_left), np.hstack(cplx_right),
                  tuple(clusters))


# --------------------------------------------------------------------------
# Recursions
# --------------------------------------------------------------------------

def _recursion(lam, z0, h):
    """z[1..N-1] of z[k+1] = lam z[k] + h[k] (h has N-1 samples).

    lfilter with b = [1], a = [1, -lam] and initial condition zi = lam z0
    computes y[j] = lam y[j-1] + h[j] with y[-1] = z0, i.e. y[j] = z[j+1].
    It runs the recursion sequentially in compiled code, exactly as stable
    as the recursion itself (prefix products lam^-k would overflow for
    decaying modes).
    """
    return scipy.signal.lfilter([1.0], [1.0, -lam], h, zi=[lam * z0])[0]


def _run_recursions(real_mu, cplx_mu, clusters, Zr, H) -> None:
    """Fill Zr[:, 1:] from Zr[:, 0] and the forcing H (None = 0).

    Zr holds stacked real coordinates (see _Modes); real_mu and cplx_mu
    are the per-step factors of the real and complex modes, clusters the
    per-step triangular matrices with their is_real flags.
    """
    n_steps = Zr.shape[1] - 1
    if n_steps == 0:
        return
    zeros = np.zeros(n_steps)

    def forcing(row):
        return zeros if H is None else H[row]

    n_real, n_cplx = real_mu.size, cplx_mu.size
    for i, mu in enumerate(real_mu):
        Zr[i, 1:] = _recursion(mu, Zr[i, 0], forcing(i))
    re, im = n_real, n_real + n_cplx
    for i, mu in enumerate(cplx_mu):
        h = forcing(re + i) + 1j * forcing(im + i)
        z = _recursion(mu, complex(Zr[re + i, 0], Zr[im + i, 0]), h)
        Zr[re + i, 1:] = z.real
        Zr[im + i, 1:] = z.imag
    row = n_real + 2 * n_cplx
    for R, is_real in clusters:
        k = R.shape[0]
        if is_real:
            h = np.array([forcing(row + i) for i in range(k)])
            Z = _triangular_recursion(R, Zr[row:row + k, 0], h)
            Zr[row:row + k, 1:] = Z[:, 1:]
            row += k
        else:
            z0 = Zr[row:row + k, 0] + 1j * Zr[row + k:row + 2 * k, 0]
            h = np.array([forcing(row + i) + 1j * forcing(row + k + i)
                          for i in range(k)])
            Z = _triangular_recursion(R, z0, h)
            Zr[row:row + k, 1:] = Z[:, 1:].real
            Zr[row + k:row + 2 * k, 1:] = Z[:, 1:].imag
            row += 2 * k


def _triangular_recursion(R, z0, h):
    """z[k+1] = R z[k] + h[k] for upper triangular R, by back substitution.

    Row i depends on the rows j > i only through R[i, j] z_j[k], which are
    known once the rows below have been propagated; each row is then a
    scalar recursion.  Returns z at all samples, shape (k, n_steps + 1).
    """
    k, n_steps = h.shape
    Z = np.empty((k, n_steps + 1), dtype=np.result_type(R, z0, h))
    Z[:, 0] = z0
    for i in range(k - 1, -1, -1):
        hi = h[i]
        if i < k - 1:
            hi = hi + R[i, i + 1:] @ Z[i + 1:, :-1]
        Z[i, 1:] = _recursion(R[i, i], z0[i], hi)
    return Z


# --------------------------------------------------------------------------
# Validation at the public boundary
# --------------------------------------------------------------------------

def _check_system(system) -> None:
    if not isinstance(system, control.StateSpace):
        raise TypeError(
            "system must be a control.StateSpace (convert a transfer "
            f"function with control.ss); got {type(system).__name__}")
    # dt = None ("unspecified") is accepted only for static gains, where
    # continuous and discrete time coincide; forced_response simulates a
    # dynamic system with dt = None as a discrete-time one.
    static = system.nstates == 0
    if not (system.dt == 0 or (system.dt is None and static)):
        raise ValueError(
            "system must be continuous-time (system.dt == 0); got "
            f"dt = {system.dt!r} (use control.forced_response for "
            "discrete-time systems)")
    for name in ("A", "B", "C", "D"):
        M = np.asarray(getattr(system, name))
        if np.iscomplexobj(M):
            raise ValueError(f"system.{name} must be real; got complex")
        if not np.all(np.isfinite(M)):
            raise ValueError(f"system.{name} must be finite; got NaN or inf")


def _check_dt(dt) -> float:
    if isinstance(dt, bool) or not np.isscalar(dt) or not np.isreal(dt):
        raise TypeError(f"dt must be a real number [s]; got {dt!r}")
    dt = float(dt)
    if not (np.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be positive and finite [s]; got {dt!r}")
    return dt


def _as_real_array(value, name) -> np.ndarray:
    value = np.asarray(value)
    if (np.iscomplexobj(value) or value.dtype == bool
            or not np.issubdtype(value.dtype, np.number)):
        raise ValueError(
            f"{name} must be real numbers; got dtype {value.dtype}")
    return value.astype(float)


def _check_time(T) -> np.ndarray:
    if T is None:
        raise ValueError("T must be given for a continuous-time system "
                         "(sample times [s]); got None")
    T = _as_real_array(T, "T")
    if T.ndim == 2 and T.shape[0] == 1:
        T = T[0]
    if T.ndim != 1:
        raise ValueError(
            f"T must be 1-D, shape (n_samples,) [s]; got shape {T.shape}")
    if T.size < 2:
        raise ValueError(f"T must have at least 2 samples [s]; got {T.size}")
    if not np.all(np.isfinite(T)):
        raise ValueError("T must be finite [s]; got NaN or inf")
    dt = (T[-1] - T[0]) / (T.size - 1)
    if not dt > 0:
        raise ValueError(
            f"T must be increasing [s]; got T[0] = {T[0]!r}, "
            f"T[-1] = {T[-1]!r}")
    steps = np.diff(T)
    # Stored sample times carry round-off of ~eps*|T|; allow for it.
    tol = _SPACING_RTOL * dt + 8 * np.finfo(float).eps * np.max(np.abs(T))
    if np.max(np.abs(steps - dt)) > tol:
        raise ValueError(
            "T must be evenly spaced [s] (uneven grids are not supported: "
            "resample the input on an even grid or simulate each segment "
            f"with its own Simulator); got steps from {steps.min()!r} to "
            f"{steps.max()!r} s")
    return T


def _check_inputs(U, n_inputs, n_samples) -> np.ndarray:
    if U is None:
        return np.zeros((n_inputs, n_samples))
    U = _as_real_array(U, "U")
    if U.ndim == 0:
        U = np.full((n_inputs, n_samples), float(U))
    elif U.ndim == 1 and n_inputs == 1 and U.shape[0] == n_samples:
        U = U.reshape(1, n_samples)
    if U.shape != (n_inputs, n_samples):
        raise ValueError(
            f"U must have shape (n_inputs, n_samples) = ({n_inputs}, "
            f"{n_samples})" + (" or (n_samples,)" if n_inputs == 1 else "")
            + f"; got shape {U.shape}")
    if not np.all(np.isfinite(U)):
        raise ValueError("U must be finite; got NaN or inf")
    return U


def _check_initial_state(X0, n_states) -> np.ndarray:
    if X0 is None:
        return np.zeros(n_states)
    X0 = _as_real_array(X0, "X0")
    if X0.ndim == 0:
        X0 = np.full(n_states, float(X0))
    elif X0.shape == (n_states, 1):
        X0 = X0[:, 0]
    if X0.shape != (n_states,):
        raise ValueError(
            f"X0 must have shape (n_states,) = ({n_states},); got shape "
            f"{X0.shape}")
    if not np.all(np.isfinite(X0)):
        raise ValueError("X0 must be finite; got NaN or inf")
    return X0
