"""Compiled loop of the modal recursion (numba; imported on first use by modal_recursion).

One call propagates ``z[k+1] = Phi z[k] + G0^T u[k] + G1^T u[k+1]`` for block-diagonal Phi
and writes ``y[k] = H^T z[k] + D u[k]`` (and, on request, the states ``x[k] = V z[k]``),
time block by time block: per block of ``n_block`` samples the input and output maps are
small matrix products through BLAS (np.dot) on data that stays in cache, the
recursion in between a loop over the modes that the compiler vectorises (the 2 x 2 blocks are
stored as structure of arrays: first components of all pairs, then second components).

Compiled code is cached on disk, so that a process loads it (~0.3 s) instead of compiling
it (~2.5 s of CPU): where numba puts it (``NUMBA_CACHE_DIR`` if set, else ``__pycache__``
beside this file when writable, else the user's cache directory), and when none of those is
writable (a read-only installation run by a user without a writable home) in a private
directory under the system's temporary directory (:func:`cached_njit`); only if that fails too
is the loop compiled in every process, uncached.
"""

from __future__ import annotations

import os
import stat
import tempfile

import numba
import numpy as np
from numba import njit

__all__ = ["cached_njit", "modal_recursion"]


def _private_directory() -> str | None:
    """``<tmp>/flexsat-numba-<uid>``, created with mode 0700; None unless it is a directory
    owned by this user that nobody else can write (compiled code loaded from a directory that
    another user controls would run as ours)."""
    uid = os.getuid() if hasattr(os, "getuid") else None
    name = f"flexsat-numba-{uid if uid is not None else 'user'}"
    path = os.path.join(tempfile.gettempdir(), name)
    try:
        os.makedirs(path, mode=0o700, exist_ok=True)
        info = os.lstat(path)
    except OSError:
        return None
    if not stat.S_ISDIR(info.st_mode) or info.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
        return None
    if uid is not None and info.st_uid != uid:
        return None
    return path


def cached_njit(function=None, /, **options):
    """``njit(cache=True, nogil=True, **options)(function)``, with the fallbacks of the module
    docstring (every compiled kernel of the package is decorated so); ``@cached_njit(**options)``
    passes further options to numba (e.g. ``error_model="numpy"``).

    numba raises RuntimeError ("no locator available") at decoration when no cache location
    is writable; its user-provided locator reads ``numba.config.CACHE_DIR`` at that moment
    and keeps the path, so the private directory is set for this decoration only.
    """
    if function is None:
        return lambda f: cached_njit(f, **options)
    try:
        return njit(cache=True, nogil=True, **options)(function)
    except RuntimeError:
        pass
    directory = _private_directory()
    if directory is not None:
        previous = numba.config.CACHE_DIR
        numba.config.CACHE_DIR = directory
        try:
            return njit(cache=True, nogil=True, **options)(function)
        except RuntimeError:
            pass
        finally:
            numba.config.CACHE_DIR = previous
    return njit(nogil=True, **options)(function)


@cached_njit
def modal_recursion(f00, f01, f10, f11, cl_starts, cl_offsets, cl_phi, G0, G1, use_G1,
                    HD, weights, U, z0, Y, Z, store, n_block, limit):
    """Propagate the modal recursion; return the number of samples kept (see below).

    Parameters (all float64 C-contiguous unless stated)
    ---------------------------------------------------
    f00, f01, f10, f11 : (n_pairs,)
        2 x 2 blocks [[f00, f01], [f10, f11]] acting on (z[j], z[n_pairs + j]).
    cl_starts : int64 (n_clusters + 1,)
        Dense blocks ("clusters") occupy z[cl_starts[c]:cl_starts[c + 1]] (after the pairs).
    cl_offsets : int64 (n_clusters + 1,)
        cl_phi[cl_offsets[c]:cl_offsets[c + 1]] is cluster c's ``Phi - I``, row-major (the
        identity is added exactly: a rigid body's Phi ~ I + A dt keeps its small part to
        round-off, see modal_recursion._transition_minus_identity).
    G0, G1 : (m, nz)
        Input maps (G1 used only if use_G1).
    HD : (nz + m, p)
        Output map [H; D^T]: y[k] = [z[k]; u[k]] @ HD.
    weights : (nz,)
        max_i |V[i, j]|: |x[k]| <= sum_j weights[j] |z[k, j]| (the overflow check).
    U : (N + 1, m)
        Inputs, one row per sample, plus one row of zeros.
    z0 : (nz,)
        Initial modal state.
    Y : (N, p)
        Outputs, written in place.
    Z : (N, nz + m)
        Rows [z[k], u[k]], written in place if ``store`` (the states are then Z @ [V^T; 0]).
    n_block : int
        Samples per time block.
    limit : float
        |x| or |y| beyond this ends the run (overflow).

    Returns
    -------
    int
        N, or the number of samples before the first one whose outputs, or whose states
        at a block's end (bound through ``weights``), left the range.
    """
    n_pairs = f00.shape[0]
    nz = z0.shape[0]
    m = U.shape[1]
    p = Y.shape[1]
    N = Y.shape[0]
    n_clusters = cl_starts.shape[0] - 1
    Zb = np.zeros((n_block, nz + m))      # [z[k], u[k]] for the block's samples
    W = np.empty((n_block, nz))
    W1 = np.empty((n_block, nz))
    z = z0.copy()
    for s in range(0, N, n_block):
        e = min(s + n_block, N)
        nb = e - s
        Zv = Z[s:e] if store else Zb[:nb]
        Wv = W[:nb]
        # w[k] = G0^T u[k] + G1^T u[k+1] for the block's steps.
        if m > 0:
            np.dot(U[s:e], G0, Wv)
            if use_G1:
                W1v = W1[:nb]
                np.dot(U[s + 1:e + 1], G1, W1v)
                for t in range(nb):
                    for j in range(nz):
                        Wv[t, j] += W1v[t, j]
            for t in range(nb):
                for i in range(m):
                    Zv[t, nz + i] = U[s + t, i]
        else:
            Wv[:, :] = 0.0
        # The recursion: row t of Zv holds z[s + t]; z carries z[e] to the next block.
        for j in range(nz):
            Zv[0, j] = z[j]
        for t in range(nb):
            last = t + 1 == nb
            for j in range(n_pairs):
                a = Zv[t, j]
                b = Zv[t, n_pairs + j]
                na = f00[j] * a + f01[j] * b + Wv[t, j]
                nb_ = f10[j] * a + f11[j] * b + Wv[t, n_pairs + j]
                if last:
                    z[j] = na
                    z[n_pairs + j] = nb_
                else:
                    Zv[t + 1, j] = na
                    Zv[t + 1, n_pairs + j] = nb_
            for c in range(n_clusters):
                i0 = cl_starts[c]
                size = cl_starts[c + 1] - i0
                off = cl_offsets[c]
                for i in range(size):
                    # cl_phi holds Phi - I: the small increment first, then the state (one
                    # rounding at the state's magnitude a step, not one a term)
                    acc = Wv[t, i0 + i]
                    for l in range(size):
                        acc += cl_phi[off + i * size + l] * Zv[t, i0 + l]
                    acc += Zv[t, i0 + i]
                    if last:
                        z[i0 + i] = acc
                    else:
                        Zv[t + 1, i0 + i] = acc
        Yv = Y[s:e]
        np.dot(Zv, HD, Yv)
        for t in range(nb):
            for i in range(p):
                v = Yv[t, i]
                if not (abs(v) < limit):        # also catches NaN
                    return s + t
        bound = 0.0
        for j in range(nz):
            bound += weights[j] * abs(z[j])
        if not (bound < limit) and e < N:
            return e
    return N
