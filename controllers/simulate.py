"""Fast, exact time responses of continuous-time LTI state-space systems.

The system ``x' = A x + B u``, ``y = C x + D u`` is discretised exactly on an
evenly spaced time grid (inputs held constant or linear between samples) with
one matrix exponential, and the recursion
``x[k+1] = Ad x[k] + Bd0 u[k] + Bd1 u[k+1]`` is propagated in block-modal
coordinates: after an O(n^3) set-up every sample costs O(n) work, one scalar
first-order recursion per mode, run over all samples at once by
:func:`scipy.signal.lfilter`; one matrix product maps the modal coordinates
back to the states and outputs.

The modal form is the block-diagonal Schur form of ``Ad`` (Bavely and
Stewart): the real Schur form is split by Sylvester equations into clusters
of eigenvalues whose decoupling transformation stays well conditioned;
each cluster is diagonalised when its eigenvectors are well conditioned
and otherwise (defective rigid-body modes: eigenvalue 1 in a Jordan block)
propagated in its own triangular Schur form by back substitution.

With ``hold="linear"`` (the default) the input is interpreted exactly as
:func:`control.forced_response` and :func:`scipy.signal.lsim` interpret it, so
the results agree with theirs to round-off.

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

# Largest norm of a Sylvester solution accepted when splitting a cluster of
# eigenvalues off the rest of the Schur form.  The block-diagonalising
# transformation then has a condition number of about this size at most per
# split, so round-off in the modal coordinates is amplified by little.
_MAX_SPLIT_NORM = 1e3

# Largest eigenvector condition number for which a cluster is propagated in
# diagonal coordinates; above it the cluster is propagated in triangular
# Schur form (a unitary, perfectly conditioned basis).
_MAX_EIGVEC_COND = 1e3

# Eigenvalues closer than this (relative to 1 + |lambda|) are put in one
# cluster before any split is tried: numerically equal eigenvalues, such as
# the round-off split of a Jordan block of size <= 3 (eps**(1/3) ~ 6e-6).
_NEAR_EIGENVALUES = 1e-5

# Relative tolerance on the spacing of the time vector.
_SPACING_RTOL = 1e-6


@dataclass(frozen=True)
class _Modes:
    """``Ad`` as independent recursions on stacked real modal coordinates.

    The real coordinate vector is ``Zr = left @ x`` and ``x = right @ Zr``.
    Rows of ``Zr``: ``n_real`` real modes, then the real parts and the
    imaginary parts of ``n_cplx`` complex modes (one per conjugate pair),
    then per triangular cluster its ``k`` real coordinates or the real and
    imaginary parts of its ``k`` complex ones.  A mode obeys
    ``z[k+1] = lam z[k] + h[k]``; a cluster ``z[k+1] = R z[k] + h[k]`` with
    ``R`` upper triangular.
    """

    real_lam: np.ndarray          # (n_real,) float
    cplx_lam: np.ndarray          # (n_cplx,) complex
    clusters: tuple               # ((R, is_real), ...)
    left: np.ndarray              # (n_coords, n) float
    right: np.ndarray             # (n, n_coords) float


class Simulator:
    """Exact simulator of one continuous-time StateSpace on a fixed step.

    The discretisation and the modal decomposition (O(n^3)) are computed once
    on construction; :meth:`run` then costs O(n) per sample for the modal
    recursions plus one matrix product back to states and outputs, so design
    loops that simulate the same system many times pay the set-up once.

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
        self._C, self._D = C, D
        self.Ad, self.Bd0, self.Bd1 = _discretise(A, B, dt, hold)
        self._modes = _modal_form(self.Ad)
        # Forcing of the modal coordinates by the stacked inputs
        # [u[k]; u[k+1]] (first-order hold) or u[k] (zero-order hold).
        Bd = (self.Bd0 if hold == "zero"
              else np.hstack([self.Bd0, self.Bd1]))
        self._G = self._modes.left @ Bd
        self._CP = C @ self._modes.right

    @property
    def n_states(self) -> int:
        """Number of states."""
        return self._C.shape[1]

    @property
    def n_inputs(self) -> int:
        """Number of inputs."""
        return self._D.shape[1]

    @property
    def n_outputs(self) -> int:
        """Number of outputs."""
        return self._C.shape[0]

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
        T = _check_time(T)
        dt = (T[-1] - T[0]) / (T.size - 1)
        if abs(dt - self.dt) > _SPACING_RTOL * self.dt:
            raise ValueError(
                f"T must have the simulator's step dt = {self.dt!r} s; got "
                f"a step of {dt!r} s (build a Simulator for this step)")
        U = _check_inputs(U, self.n_inputs, T.size)
        X0 = _check_initial_state(X0, self.n_states)
        Zr = self._propagate(U, X0)
        X = self._modes.right @ Zr
        Y = self._CP @ Zr
        if self.n_inputs:
            Y += self._D @ U
        if not (np.all(np.isfinite(X)) and np.all(np.isfinite(Y))):
            raise FloatingPointError(
                "simulation overflowed: the response of this (unstable) "
                "system exceeds the float64 range on this time grid")
        sys = self.system
        return control.TimeResponseData(
            T, Y, X, U, issiso=sys.issiso(),
            output_labels=sys.output_labels, state_labels=sys.state_labels,
            input_labels=sys.input_labels, sysname=sys.name,
            title="Simulated response for " + sys.name,
            trace_types=["forced"], plot_inputs=True,
            return_x=control.config.defaults["forced_response.return_x"],
            squeeze=squeeze)

    def _propagate(self, U, X0) -> np.ndarray:
        """Stacked real modal coordinates at every sample, (n_coords, N)."""
        modes = self._modes
        n_samples = U.shape[1]
        Zr = np.empty((modes.left.shape[0], n_samples))
        Zr[:, 0] = modes.left @ X0
        if self.n_inputs and np.any(U):
            # h[k] = Bd0 u[k] + Bd1 u[k+1] in modal coordinates, k < N-1.
            Ustack = (U[:, :-1] if self.hold == "zero"
                      else np.vstack([U[:, :-1], U[:, 1:]]))
            H = self._G @ Ustack
        else:
            H = None
        _run_modes(modes, Zr, H)
        return Zr


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


# --------------------------------------------------------------------------
# Block-modal form of the transition matrix
# --------------------------------------------------------------------------

def _schur_blocks(T, start):
    """Diagonal blocks of the quasi-triangular T from row ``start`` on.

    Returns a list of (row, size, eigenvalue with Im >= 0).
    """
    n = T.shape[0]
    blocks = []
    i = start
    while i < n:
        if i + 1 < n and T[i + 1, i] != 0.0:
            a, b, c, d = T[i, i], T[i, i + 1], T[i + 1, i], T[i + 1, i + 1]
            # 2x2 standard block [[a, b], [c, a]], b c < 0: a +- i sqrt(-bc).
            lam = complex(0.5 * (a + d), np.sqrt(max(-b * c, 0.0)))
            blocks.append((i, 2, lam))
            i += 2
        else:
            blocks.append((i, 1, complex(T[i, i])))
            i += 1
    return blocks


def _move_block(T, S, row, to):
    """Move the Schur block at ``row`` up to ``to`` (dtrexc); None if refused.

    dtrexc refuses a swap that would perturb the eigenvalues too much, which
    only happens for eigenvalues that belong in one cluster anyway.
    """
    T2, S2, info = scipy.linalg.lapack.dtrexc(T, S, row + 1, to + 1)
    if info != 0:
        return None
    return T2, S2


def _block_diagonal_schur(Ad):
    """Block-diagonal real Schur form ``Ad = S diag(T_1, ..., T_r) S^-1``.

    Bavely-Stewart: walking down the real Schur form, a cluster of leading
    blocks ``T11`` is split off the trailing ``T22`` by the shear
    ``[[I, X], [0, I]]`` with ``T11 X - X T22 = -T12`` (which zeroes the
    coupling ``T12``) when ``||X|| <= _MAX_SPLIT_NORM``; otherwise the
    trailing eigenvalue nearest to the cluster is moved next to it
    (dtrexc) and joins it.  Returns ``T`` (block diagonal), ``S`` and the
    list of cluster ranges ``(start, stop)``.
    """
    T, S = scipy.linalg.schur(Ad, output="real")
    T = np.asfortranarray(T)
    S = np.asfortranarray(S)
    n = T.shape[0]
    ranges = []
    start = 0
    while start < n:
        first = _schur_blocks(T[:start + 2, :start + 2], start)[0]
        stop = start + first[1]
        members = [first[2]]
        gather_near = True
        while stop < n:
            trailing = _schur_blocks(T, stop)
            cluster = np.array(members)
            dist = [np.min(np.abs(cluster - lam)) for (_, _, lam) in trailing]
            if gather_near:
                # Numerically equal eigenvalues join without trying a split.
                scale = 1.0 + np.abs(cluster).max()
                near = [j for j, d in enumerate(dist)
                        if d <= _NEAR_EIGENVALUES * scale]
                if near:
                    j = near[0]
                else:
                    gather_near = False
                    continue
            else:
                T11, T12 = T[start:stop, start:stop], T[start:stop, stop:]
                T22 = T[stop:, stop:]
                X, scale_x, info = scipy.linalg.lapack.dtrsyl(
                    T11, T22, -T12, isgn=-1)
                if (info == 0 and scale_x == 1.0 and np.all(np.isfinite(X))
                        and np.linalg.norm(X) <= _MAX_SPLIT_NORM):
                    # Shear: S <- S [[I, X], [0, I]] zeroes T12.
                    S[:, stop:] += S[:, start:stop] @ X
                    T[start:stop, stop:] = 0.0
                    break
                j = int(np.argmin(dist))
                gather_near = True    # its near twins come along
            row, size, lam = trailing[j]
            moved = _move_block(T, S, row, stop) if row != stop else (T, S)
            if moved is None:
                # Refused swap: take every block up to it instead.
                stop = row + size
                members += [b[2] for b in trailing[:j + 1]]
                continue
            T, S = (np.asfortranarray(M) for M in moved)
            size = _schur_blocks(T[:stop + 2, :stop + 2], stop)[0][1]
            stop += size
            members.append(lam)
        ranges.append((start, stop))
        start = stop
    return T, S, ranges


def _modal_form(Ad: np.ndarray) -> _Modes:
    """Split ``Ad`` into independent first-order recursions (see _Modes)."""
    n = Ad.shape[0]
    if n == 0:
        return _Modes(np.zeros(0), np.zeros(0, complex), (),
                      np.zeros((0, 0)), np.zeros((0, 0)))
    T, S, ranges = _block_diagonal_schur(Ad)
    S_inv = np.linalg.inv(S)
    real_lam, real_left, real_right = [], [], []
    cplx_lam, cplx_left, cplx_right = [], [], []
    clusters, clu_left, clu_right = [], [], []
    for start, stop in ranges:
        B = T[start:stop, start:stop]
        Sl, Sr = S_inv[start:stop], S[:, start:stop]
        if stop - start == 1:
            real_lam.append(B[0, 0])
            real_left.append(Sl)
            real_right.append(Sr)
            continue
        lam, V = scipy.linalg.eig(B)
        cond = np.linalg.cond(V)
        if np.isfinite(cond) and cond <= _MAX_EIGVEC_COND:
            W = np.linalg.inv(V)
            # LAPACK returns exactly real eigenvectors for real eigenvalues
            # and conjugate pairs as adjacent conjugate columns: keep the
            # member with Im > 0, its state contribution is 2 Re(v z).
            real = lam.imag == 0.0
            upper = lam.imag > 0.0
            real_lam += list(lam.real[real])
            real_left.append((W[real] @ Sl).real)
            real_right.append((Sr @ V[:, real]).real)
            cplx_lam += list(lam[upper])
            cplx_left.append(W[upper] @ Sl)
            cplx_right.append(2.0 * (Sr @ V[:, upper]))
            continue
        if np.all(np.diag(B, -1) == 0.0):
            # Only real eigenvalues: B is already upper triangular.
            clusters.append((B.copy(), True))
            clu_left.append(Sl)
            clu_right.append(Sr)
        else:
            R, U = scipy.linalg.schur(B.astype(complex), output="complex")
            clusters.append((R, False))
            clu_left.append(U.conj().T @ Sl)
            clu_right.append(Sr @ U)
    # Stack into real coordinates: Re(v z) = Re v Re z - Im v Im z.
    left = [np.zeros((0, n))] + real_left
    right = [np.zeros((n, 0))] + real_right
    cl = np.vstack([np.zeros((0, n), complex)] + cplx_left)
    cr = np.hstack([np.zeros((n, 0), complex)] + cplx_right)
    left += [cl.real, cl.imag]
    right += [cr.real, -cr.imag]
    for (R, is_real), Lc, Rc in zip(clusters, clu_left, clu_right):
        if is_real:
            left.append(Lc.real)
            right.append(Rc.real)
        else:
            left += [Lc.real, Lc.imag]
            right += [Rc.real, -Rc.imag]
    return _Modes(np.array(real_lam, dtype=float),
                  np.array(cplx_lam, dtype=complex), tuple(clusters),
                  np.ascontiguousarray(np.vstack(left)),
                  np.ascontiguousarray(np.hstack(right)))


# --------------------------------------------------------------------------
# Propagation
# --------------------------------------------------------------------------

def _recursion(lam, z0, h):
    """z[1..N-1] of z[k+1] = lam z[k] + h[k] (h has N-1 samples).

    lfilter with b = [1], a = [1, -lam] and initial condition zi = lam z0
    computes y[j] = lam y[j-1] + h[j] with y[-1] = z0, i.e. y[j] = z[j+1].
    It runs the recursion sequentially in compiled code, which is exactly as
    stable as the recursion itself (no prefix products, which lose accuracy
    for decaying modes).
    """
    return scipy.signal.lfilter([1.0], [1.0, -lam], h, zi=[lam * z0])[0]


def _run_modes(modes: _Modes, Zr: np.ndarray, H: np.ndarray | None) -> None:
    """Fill Zr[:, 1:] from Zr[:, 0] and the modal forcing H (None = 0)."""
    n_samples = Zr.shape[1]
    zeros = np.zeros(n_samples - 1)

    def forcing(row):
        return zeros if H is None else H[row]

    n_real, n_cplx = modes.real_lam.size, modes.cplx_lam.size
    for i, lam in enumerate(modes.real_lam):
        Zr[i, 1:] = _recursion(lam, Zr[i, 0], forcing(i))
    re, im = n_real, n_real + n_cplx
    for i, lam in enumerate(modes.cplx_lam):
        h = forcing(re + i) + 1j * forcing(im + i)
        z = _recursion(lam, complex(Zr[re + i, 0], Zr[im + i, 0]), h)
        Zr[re + i, 1:] = z.real
        Zr[im + i, 1:] = z.imag
    row = n_real + 2 * n_cplx
    for R, is_real in modes.clusters:
        k = R.shape[0]
        if is_real:
            z0 = Zr[row:row + k, 0]
            h = np.array([forcing(row + i) for i in range(k)])
            Z = _triangular_recursion(R, z0, h)
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
    scalar recursion.  Returns z at all N samples, shape (k, N).
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
    if system.dt is None or system.dt != 0:
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
