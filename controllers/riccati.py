"""Numerical solvers of the LQR design: the Riccati equations and a modal pole correction.

References
----------
A. J. Laub, "A Schur method for solving algebraic Riccati equations", IEEE TAC 24(6), 1979;
B. Porter, T. R. Crossley, Modal Control: Theory and Applications, Taylor & Francis, 1972.
"""
from __future__ import annotations

import numpy as np
import scipy.linalg

from .arguments import describe

__all__ = ["modal_correction", "solve_care", "solve_dare"]


def solve_care(A, B, Q, R, N, what: str) -> np.ndarray:
    """Stabilising solution X of A^T X + X A - (X B + N) R^-1 (B^T X + N^T) + Q = 0.

    The stable invariant subspace [U_11; U_21] of the balanced Hamiltonian from an ordered
    complex Schur form (swaps of 1x1 blocks do not fail), X = U_21 U_11^-1 (Laub's method, R is
    invertible here); scipy's generalized-Schur solver if that fails. The Hamiltonian's
    eigenvalues come in pairs (lambda, -conj(lambda)); with the prescribed degree of stability
    they lie >= sigma from the imaginary axis, but a mode the cost barely moves can still have
    its pair within round-off of it, where the sign of the computed real part is noise: such
    pairs are matched explicitly and the member with the smaller real part taken. The complex
    Schur form of the 2n Hamiltonian costs a fifteenth of scipy's QZ of the (2n + m) pencil
    (measured: 0.6 s against 9 s for n = 398, one BLAS thread), which matters for chains of
    hundreds of bodies.

    Parameters
    ----------
    A, B : ndarray, (n, n) and (n, m)
        The system (the state-space matrices of the design, shifted by the degree of stability).
    Q, R, N : ndarray, (n, n), (m, m) and (n, m)
        State, input and cross weights (R invertible).
    what : str
        The design step for the message ("regulator", "Kalman filter").

    Returns
    -------
    ndarray, (n, n)
        X.

    Raises
    ------
    ValueError
        No stabilising solution can be computed (the message starts with ``what``).

    References
    ----------
    A. J. Laub, "A Schur method for solving algebraic Riccati equations", IEEE TAC 24(6), 1979.
    """
    try:
        X = _laub(A, B, Q, R, N)
        if np.all(np.isfinite(X)):
            return X
    except (np.linalg.LinAlgError, ValueError):
        pass
    try:
        X = scipy.linalg.solve_continuous_are(A, B, Q, R, s=N)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(f"{what}: the Riccati equation has no stabilising solution that can be "
                         f"computed ({describe(str(exc))})") from None
    return X


def solve_dare(A, B, Q, R, S, what: str) -> np.ndarray:
    """Stabilising solution X of the discrete Riccati equation (cross term S, or None), as
    :func:`scipy.linalg.solve_discrete_are` gives it from the ordered real generalized Schur
    form of the symplectic pencil; if LAPACK cannot reorder that form (it refuses to swap two
    2 x 2 blocks whose exchange would leave the pencil too far from Schur form, which happens at
    fast sampling, where every eigenvalue exp(+-lambda T) lies near z = 1: the hinged wing's
    LQR at 10 kHz, though 1 and 100 kHz passed), the same in complex arithmetic, where swaps of
    1 x 1 blocks do not fail, and its real part (the solution is real).

    Parameters
    ----------
    A, B : ndarray, (n, n) and (n, m)
        The sampled system.
    Q, R : ndarray, (n, n) and (m, m)
        State and input weights.
    S : ndarray, (n, m), or None
        Cross weight.
    what : str
        The design step for the message ("digital regulator", "digital Kalman filter").

    Returns
    -------
    ndarray, (n, n)
        X, symmetric.

    Raises
    ------
    ValueError
        No stabilising solution can be computed, or it is not finite.

    References
    ----------
    P. van Dooren, "A generalized eigenvalue approach for solving Riccati equations", SIAM J.
    Sci. Stat. Comput. 2(2), 1981 (the pencil and its ordered QZ form).
    """
    try:
        X = scipy.linalg.solve_discrete_are(A, B, Q, R, s=S)
        if np.all(np.isfinite(X)):
            return X
    except (np.linalg.LinAlgError, ValueError):
        pass
    try:
        complex_ = [np.asarray(M, dtype=complex) for M in (A, B, Q, R)]
        X = scipy.linalg.solve_discrete_are(
            *complex_, s=None if S is None else np.asarray(S, dtype=complex))
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ValueError(f"{what}: the discrete Riccati equation has no stabilising solution "
                         f"that can be computed ({describe(str(exc))})") from None
    X = np.real(X)
    if not np.all(np.isfinite(X)):
        raise ValueError(f"{what}: the discrete Riccati equation's solution is not finite")
    return 0.5 * (X + X.T)


def _laub(A, B, Q, R, N) -> np.ndarray:
    """Laub's Schur method (see solve_care); ValueError if the stable subspace is not n-dim.

    The real Schur form first (a third of the complex one's cost: 2.7x measured on the
    1604-state Hamiltonian of a 400-mode plant); if its reordering fails (LAPACK cannot swap
    two 2 x 2 blocks whose eigenvalues are too close), the complex Schur form, where swaps of
    1 x 1 blocks do not fail.
    """
    n = A.shape[0]
    Ri = np.linalg.inv(R)
    F = A - B @ Ri @ N.T
    H = np.block([[F, -B @ Ri @ B.T], [-(Q - N @ Ri @ N.T), -F.T]])
    Hb, (d, _) = scipy.linalg.matrix_balance(H, permute=False, separate=True)
    try:
        U = _stable_subspace_real(Hb, n)
    except ValueError:
        U = _stable_subspace_complex(Hb, n)
    U = U * d[:, None]
    X = np.linalg.solve(U[:n].T, U[n:].T).T
    return np.real(0.5 * (X + X.conj().T))


def _select_stable(ev: np.ndarray, n: int) -> np.ndarray:
    """0/1 selection of the n stable eigenvalues of a Hamiltonian among ``ev``.

    Eigenvalues come in pairs (lambda, -conj(lambda)). A pair within round-off of the imaginary
    axis (|Re| <= 1e-9 |ev|_max) has a noise sign: its members share their imaginary part, so
    sorted by it they are neighbours (distinct modes have distinct frequencies; else they are
    matched greedily), and the member with the smaller real part is taken.
    """
    select = (ev.real < 0).astype(np.int32)
    near = np.nonzero(np.abs(ev.real) <= 1e-9 * max(np.abs(ev).max(), 1.0))[0]
    select[near] = 0
    order = near[np.argsort(ev[near].imag, kind="stable")]
    pairs = order[: order.size // 2 * 2].reshape(-1, 2)
    spread = np.abs(ev[pairs[:, 0]] + np.conj(ev[pairs[:, 1]]))
    gaps = np.diff(ev[order].imag)
    if order.size % 2 == 0 and (pairs.size == 0 or np.all(
            spread < 0.5 * np.concatenate([gaps[1::2], [np.inf]]))):
        for i, j in pairs:
            select[i if ev[i].real <= ev[j].real else j] = 1
        free = []
    else:
        free = list(near)
        while len(free) > 1:
            i = free.pop(0)
            j = min(free, key=lambda k: abs(ev[k] + np.conj(ev[i])))
            free.remove(j)
            select[i if ev[i].real <= ev[j].real else j] = 1
    if free or select.sum() != n:
        raise ValueError(f"the Hamiltonian has {int(np.sum(ev.real < 0))} of {ev.size} "
                         f"eigenvalues in the open left half-plane, {n} needed")
    return select


def _quasi_triangular_eigenvalues(T: np.ndarray) -> np.ndarray:
    """Eigenvalues of a real quasi-triangular (real Schur) matrix, in diagonal order."""
    ev = np.diag(T).astype(complex)
    sub = np.nonzero(np.diag(T, -1) != 0.0)[0]  # 2 x 2 blocks start at these rows
    a, b, c, e = T[sub, sub], T[sub, sub + 1], T[sub + 1, sub], T[sub + 1, sub + 1]
    # LAPACK's standardised 2 x 2 blocks have a = e and b c < 0: a +- j sqrt(-b c)
    mid, root = 0.5 * (a + e), np.sqrt((0.5 * (a - e)) ** 2 + b * c + 0j)
    ev[sub], ev[sub + 1] = mid + root, mid - root
    return ev


def _stable_subspace_real(Hb: np.ndarray, n: int) -> np.ndarray:
    """Orthonormal basis (2n, n) of the stable invariant subspace from the real Schur form."""
    T, Z = scipy.linalg.schur(Hb, output="real")
    ev = _quasi_triangular_eigenvalues(T)
    select = _select_stable(ev, n)
    # a 2 x 2 block is selected whole: its conjugate pair has one real part
    sub = np.nonzero(np.diag(T, -1) != 0.0)[0]
    if np.any(select[sub] != select[sub + 1]):
        raise ValueError("a complex-conjugate pair split by the selection")
    _, U, *_, info = scipy.linalg.lapack.dtrsen(select, T, Z, job="N")
    if info != 0:
        raise ValueError(f"reordering the Hamiltonian's real Schur form failed (info={info})")
    return U[:, :n]


def _stable_subspace_complex(Hb: np.ndarray, n: int) -> np.ndarray:
    """As _stable_subspace_real, from the complex Schur form (swaps of 1 x 1 blocks)."""
    T, Z = scipy.linalg.schur(Hb.astype(complex), output="complex")
    select = _select_stable(np.diag(T), n)
    _, U, _, _, _, _, info = scipy.linalg.lapack.ztrsen(select, T, Z, job="N")
    if info != 0:
        raise ValueError(f"reordering the Hamiltonian's Schur form failed (info={info})")
    return U[:, :n]


def modal_correction(M, G, flagged, target) -> tuple[np.ndarray, np.ndarray]:
    """Gain dK that moves each flagged eigenvalue of M to target(eigenvalue) in M - G dK and
    leaves every other eigenvalue exactly where it is (modal control); returns dK and the
    eigenvalues of M - G dK (computed on the way: no second eigen-decomposition).

    The Riccati equations cannot resolve a mode whose Hamiltonian eigenvalue pair lies within
    round-off of each other (a high beam mode the cost barely sees, measured at Re = -2e-15
    instead of < -sigma on a hub 1e6 times the beam's inertia): its pole is left where the
    Riccati solution put it. Such a pole lambda = a + j b with left eigenvector x + j y spans
    the left invariant subspace W2 = [x, y], W2^T M = Lambda2 W2^T, Lambda2 = [[a, b], [-b, a]].
    A feedback on that mode's own coordinates, dK = F W2^T, keeps the subspace:
    W2^T (M - G dK) = (Lambda2 - g F) W2^T with g = W2^T G u (u the input direction reaching
    the mode best), so the pair moves to the roots placed by F (Ackermann's formula,
    F = [0, 1] [g, Lambda2 g]^-1 p(Lambda2)), while the right eigenvectors of the other
    eigenvalues, orthogonal to W2, stay eigenvectors with their eigenvalues. Real eigenvalues
    are moved alike with a one-dimensional W2. The correction costs gains of about
    |lambda - target| / |g|, the least that moves the mode.

    Parameters
    ----------
    M : ndarray, (n, n)
        The closed-loop matrix (continuous A - B K, or a sampled Phi - Gamma K).
    G : ndarray, (n, m)
        The input matrix through which the correction acts.
    flagged : callable (complex) -> bool
        True for an eigenvalue to be moved.
    target : callable (complex) -> complex
        Where a flagged eigenvalue goes.

    Returns
    -------
    (ndarray, ndarray)
        dK, shape (m, n), and the eigenvalues of M - G dK (complex).

    References
    ----------
    B. Porter, T. R. Crossley, Modal Control: Theory and Applications, Taylor & Francis, 1972;
    J. Ackermann, "Der Entwurf linearer Regelungssysteme im Zustandsraum", Regelungstechnik 20,
    1972 (pole placement formula).
    """
    n, m = G.shape
    dK = np.zeros((m, n))
    done: list[complex] = []
    for iteration in range(n):
        Mk = M - G @ dK
        if iteration == 0:
            # usually nothing is flagged: eigenvalues alone cost a third of eig with left
            # eigenvectors (0.3 s against 1 s for n = 802)
            lam = np.linalg.eigvals(Mk)
            if not any(flagged(x) for x in lam):
                return dK, lam
        lam, Wl = scipy.linalg.eig(Mk, left=True, right=False)
        todo = [i for i in range(n) if flagged(lam[i]) and lam[i].imag >= 0
                and all(abs(lam[i] - x) > 1e-12 * max(1.0, abs(x)) for x in done)]
        if not todo:
            return dK, lam
        i = max(todo, key=lambda k: lam[k].real)
        a, b = lam[i].real, lam[i].imag
        w = Wl[:, i]
        new = target(lam[i])
        if abs(b) <= 1e-14 * max(1.0, abs(lam[i])):
            W2 = np.real(w)[:, None] / np.linalg.norm(np.real(w))
            g_all = W2.T @ G
            u = g_all[0] / max(np.linalg.norm(g_all[0]), np.finfo(float).tiny)
            g = float(g_all[0] @ u)
            if g == 0.0:
                done.append(lam[i])
                continue
            F = np.array([[(a - new.real) / g]])
        else:
            W2 = np.column_stack([np.real(w), np.imag(w)])
            W2 /= np.linalg.norm(W2)
            Lam2 = np.array([[a, b], [-b, a]])
            g_all = W2.T @ G                                    # (2, m)
            _, _, vh = np.linalg.svd(g_all)
            u = vh[0]
            g = g_all @ u                                       # (2,)
            ctrb = np.column_stack([g, Lam2 @ g])
            if abs(np.linalg.det(ctrb)) <= 1e-300:
                done.append(lam[i])
                continue
            c1, c0 = -2.0 * new.real, abs(new) ** 2             # s^2 + c1 s + c0
            p = Lam2 @ Lam2 + c1 * Lam2 + c0 * np.eye(2)
            F = (np.array([0.0, 1.0]) @ np.linalg.solve(ctrb, p))[None, :]
        dK = dK + np.outer(u, F @ W2.T)
        done.append(new)
    return dK, np.linalg.eigvals(M - G @ dK)
