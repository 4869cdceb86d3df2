r"""The exact frequency-domain reference of a hub with appendages, through their W matrices.

Eliminating every appendage leaves the hub's dynamic stiffness. Planar (hub coordinates
``h = (X, Y, theta)``; appendage root motions ``(delta, phi) = G_r h``, its rigid axial motion
``g^T h``; ``D = W^-1``)::

    Z(s) = M_hub s**2 + sum_i ( G_r,i^T D_i(s) G_r,i + m_i s**2 g_i g_i^T ),

three axes (``h = (X, Y, Z, theta_x, theta_y, theta_z)``; root motions ``G_i h`` in the
appendage's axes, :mod:`spacecraft.kinematics`; ``D6 = W6^-1``, axial motion included)::

    Z(s) = M_hub s**2 + sum_i G_i^T D6_i(s) G_i.

The attitude response is the rotation block of ``Z(s)^-1`` (torques act on the hub's rotation
coordinates): ``theta/torque`` (1x1 planar, 3x3 in three axes). The coupled natural
frequencies are counted with the Wittrick-Williams algorithm: the number of frequencies below
w is ``J(w) = sum_i J0_i(w) + s{Z(i w)}``, where J0_i counts appendage i's frequencies with its
attachment end clamped (in three axes: the cantilever frequencies of every motion, both
bending planes, torsion and axial) and s{.} the negative eigenvalues of the real symmetric
Z(iw) (3x3 or 6x6). Bisection on J finds every frequency without missing one; the rigid-body
modes (3 planar, 6 in three axes) count as frequencies below any w > 0.

Each appendage is reached only through its interface (``W``/``W6``, ``dynamic_stiffness``/
``dynamic_stiffness6``, ``root_model``, clamped frequencies), never by class; appendages
shared by several mounts (two identical wings) are evaluated once per frequency.

References
----------
.. [1] W. H. Wittrick, F. W. Williams, "A general algorithm for computing natural frequencies
   of elastic structures", Q. J. Mech. Appl. Math. 24(3), 1971.
.. [2] F. W. Williams, W. H. Wittrick, "An automatic computational procedure for calculating
   natural frequencies of skeletal structures", Int. J. Mech. Sci. 12, 1970 (member
   stiffnesses of bars in axial and torsional vibration).
.. [3] P. W. Likins, "Dynamics and control of flexible space vehicles", JPL TR 32-1329, 1970.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg

from appendages import limits
from appendages.interface import S_RANGE, describe, equilibrate, inverse_symmetric

__all__ = ["ExactReference", "clamped_frequencies", "dynamic_stiffness_of", "frequency_vector"]


def frequency_vector(omega) -> np.ndarray:
    """omega as a 1-D float64 array of positive finite frequencies [rad/s], or an error."""
    if isinstance(omega, (str, bytes)) or omega is None:
        raise TypeError(f"omega must be an array of frequencies [rad/s]; got "
                        f"{type(omega).__name__}")
    arr = np.asarray(omega)
    if arr.dtype.kind not in "iuf" or arr.dtype == bool:
        raise TypeError(f"omega must be real frequencies [rad/s]; got dtype {arr.dtype} "
                        f"{describe(omega)}")
    limits.check("omega (number of frequencies)", arr.size, "points", "points at once")
    arr = arr.astype(float)
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError("omega must be a 1-D array of positive finite frequencies [rad/s]; "
                         f"got {describe(omega)}")
    if np.any(arr < S_RANGE[0]) or np.any(arr > S_RANGE[1]):
        raise ValueError(f"omega must lie between {S_RANGE[0]:g} and {S_RANGE[1]:g} [rad/s] "
                         "(appendages.interface.S_RANGE); got "
                         f"{describe(arr[(arr < S_RANGE[0]) | (arr > S_RANGE[1])][0])}")
    return arr


def dynamic_stiffness_of(appendage, s: np.ndarray, *, undamped: bool,
                         n_root: int = 2) -> np.ndarray:
    """D(s) = W(s)^-1 (``n_root = 2``) or D6(s) = W6(s)^-1 (6) of an appendage.

    Shape ``s.shape + (n_root, n_root)``, through the interface only. Undamped (the
    natural-frequency count): an appendage offering ``undamped()`` (a distributed or
    truncated beam) through its undamped twin and its own dynamic stiffness (closed form or
    O(n) modal form); any other finite appendage (``root_model()``) by static condensation
    of its realisation with the damping removed, which carries the poles of D at its clamped
    frequencies natively (inverting W there, where W is singular, loses every digit).
    Otherwise an appendage offering ``dynamic_stiffness(s)`` (``dynamic_stiffness6``) by it,
    any other by the scaled inverse of its own W(s) (W6), which is the accurate one at small
    |s| (a chain's recursion; the condensation subtracts stiffness-sized terms there).
    """
    method = "dynamic_stiffness" if n_root == 2 else "dynamic_stiffness6"
    if undamped and hasattr(appendage, "undamped"):
        appendage = appendage.undamped()
        if hasattr(appendage, "root_model") and hasattr(appendage, method) and n_root == 6:
            return np.asarray(getattr(appendage, method)(s), dtype=complex)
    if undamped and hasattr(appendage, "root_model"):
        rm = appendage.root_model() if n_root == 2 else appendage.root_model(6)
        if np.any(rm.damping):
            rm = dataclasses.replace(rm, damping=np.zeros_like(rm.damping))
        return rm.dynamic_stiffness(s)
    if hasattr(appendage, method):
        return np.asarray(getattr(appendage, method)(s), dtype=complex)
    W = appendage.W(s) if n_root == 2 else appendage.W6(s)
    return inverse_symmetric(np.asarray(W, dtype=complex))


def clamped_frequencies(appendage, omega_max: float, *, n_root: int = 2) -> np.ndarray:
    """Natural frequencies [rad/s] of the appendage with its attachment end clamped, ascending:
    at least every one up to omega_max (all of them for a finite model). Three axes: every
    motion's (``clamped_frequencies6``, or the internal block of ``root_model(6)``)."""
    if n_root == 2 and hasattr(appendage, "cantilever_frequencies"):
        n = 8
        while True:
            wc = appendage.cantilever_frequencies(n)
            if wc[-1] > omega_max:
                return wc
            n *= 2
    if n_root == 6 and hasattr(appendage, "clamped_frequencies6"):
        return np.asarray(appendage.clamped_frequencies6(omega_max), dtype=float)
    if not hasattr(appendage, "root_model"):
        raise TypeError(
            f"exact natural frequencies need each appendage's clamped frequencies "
            f"({'cantilever_frequencies(n)' if n_root == 2 else 'clamped_frequencies6'} or a "
            f"finite root_model()); {type(appendage).__name__} offers neither")
    rm = appendage.root_model() if n_root == 2 else appendage.root_model(6)
    r = rm.n_root
    Kii, Mii = rm.stiffness[r:, r:], rm.mass[r:, r:]
    if Kii.shape[0] == 0:
        return np.zeros(0)
    d = equilibrate(Kii, Mii)
    lam = scipy.linalg.eigvalsh(Kii * np.outer(d, d), Mii * np.outer(d, d))
    return np.sqrt(np.clip(lam, 0.0, None))


class ExactReference:
    """The exact reference of one spacecraft: Z(s), attitude response, count, frequencies.

    Parameters
    ----------
    hub : Hub
    mounts : list of Mount
        Planar mounts on a planar hub; any mounts on a three-axis hub (planar ones lie in
        its x-y plane).
    """

    def __init__(self, hub, mounts):
        self.hub, self.mounts = hub, list(mounts)
        self.three_axis = bool(hub.three_axis)
        self.n_hub = 6 if self.three_axis else 3
        self.n_root = 6 if self.three_axis else 2
        self._kinematics = []
        for mount in self.mounts:
            if self.three_axis:
                self._kinematics.append((mount.transformation(), None))
            else:
                G = mount.kinematics()
                self._kinematics.append((G[1:], G[0]))
        self._clamped: dict = {}

    # -- Z(s) -------------------------------------------------------------------------------------
    def hub_dynamic_stiffness(self, s: np.ndarray, *, undamped: bool = False) -> np.ndarray:
        """Z(s) of the hub with every appendage eliminated (module docstring).

        Shape ``s.shape + (n_hub, n_hub)``. D_i comes from the appendage's own dynamic
        stiffness when it offers one (exact closed form of a beam, static condensation of a
        finite model), which stays accurate where W_i is singular (W_i -> 0 at its clamped
        frequencies) or huge (at its free poles), where inverting W_i loses every digit.
        """
        s = np.asarray(s, dtype=complex)
        s2 = (s**2)[..., None, None]
        Z = self.hub.mass_matrix * s2
        evaluated: dict = {}
        for mount, (G, axial) in zip(self.mounts, self._kinematics):
            key = id(mount.appendage)
            D = evaluated.get(key)
            if D is None:
                D = dynamic_stiffness_of(mount.appendage, s, undamped=undamped,
                                         n_root=self.n_root)
                evaluated[key] = D
            Z = Z + G.T @ D @ G
            if axial is not None:
                Z = Z + mount.appendage.mass * np.outer(axial, axial) * s2
        return Z

    def attitude_compliance(self, omega: np.ndarray) -> np.ndarray:
        """theta/torque at s = i omega: shape ``omega.shape + (1, 1)`` planar, ``(3, 3)``.

        Raises ValueError where the undamped spacecraft has a natural frequency.
        """
        s = 1j * omega
        rotation = slice(2, 3) if not self.three_axis else slice(3, 6)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            Z = self.hub_dynamic_stiffness(s)
            unit = np.zeros((self.n_hub, rotation.stop - rotation.start))
            unit[rotation] = np.eye(rotation.stop - rotation.start)
            try:
                response = np.linalg.solve(Z, np.broadcast_to(unit, Z.shape[:-1] + unit.shape[-1:]))
                response = response[..., rotation, :]
            except np.linalg.LinAlgError:
                response = np.full(omega.shape + (unit.shape[1],) * 2, np.nan, dtype=complex)
        bad = ~np.all(np.isfinite(response), axis=(-2, -1))
        if np.any(bad):
            raise ValueError(
                "omega hits a natural frequency of the undamped spacecraft, where the response "
                f"is infinite [rad/s]: {describe(omega[bad])}; give the appendages damping or "
                "move omega off the resonance")
        return response

    # -- Wittrick-Williams ------------------------------------------------------------------------
    def clamped(self, k: int, omega_max: float) -> np.ndarray:
        """Clamped frequencies of appendage k [rad/s], at least up to omega_max (cached)."""
        wc = self._clamped.get(k)
        appendage = self.mounts[k].appendage
        distributed = hasattr(appendage, "cantilever_frequencies" if self.n_root == 2
                              else "clamped_frequencies6")
        if wc is None or (wc.size and wc[-1] <= omega_max and distributed):
            wc = clamped_frequencies(appendage, omega_max, n_root=self.n_root)
            self._clamped[k] = wc
        return wc

    def count(self, omega: np.ndarray) -> np.ndarray:
        """Wittrick-Williams count: coupled frequencies (rigid-body ones included) < omega.

        ``J(w) = sum_i J0_i(w) + s{Z(iw)}`` (module docstring). Exactly at an appendage's
        clamped frequency D_i is infinite; the count there is its limit from below (a natural
        frequency is counted only above it), taken by evaluating Z one rounding step lower.
        """
        omega = np.asarray(omega, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            Z = self.hub_dynamic_stiffness(1j * omega, undamped=True).real
            bad = ~np.all(np.isfinite(Z), axis=(-2, -1))
            step = 0
            while np.any(bad) and step < 8:
                step += 1
                lower = omega[bad] * (1.0 - 2.0 * step * np.finfo(float).eps)
                Z[bad] = self.hub_dynamic_stiffness(1j * lower, undamped=True).real
                bad[bad] = ~np.all(np.isfinite(Z[bad]), axis=(-2, -1))
        if np.any(bad):  # pragma: no cover - needs a pole on 8 consecutive doubles
            raise FloatingPointError("the dynamic stiffness of an appendage is not finite near "
                                     f"omega = {describe(omega[bad])} [rad/s]")
        Z = 0.5 * (Z + np.swapaxes(Z, -1, -2))
        # Sylvester's law of inertia: negative eigenvalues of the symmetric Z. eigvalsh is
        # backward stable, so the count is exact unless an eigenvalue is within round-off of
        # zero, i.e. omega within round-off of a coupled frequency: what bisection needs.
        # Z is equilibrated first (translations in N/m, rotations in N*m/rad).
        scale = np.sqrt(np.abs(np.diagonal(Z, axis1=-2, axis2=-1)))
        scale = np.where(scale > 0, 1.0 / np.where(scale > 0, scale, 1.0), 1.0)
        negative = (np.linalg.eigvalsh(Z * scale[..., :, None] * scale[..., None, :]) < 0
                    ).sum(axis=-1)
        top = float(np.max(omega, initial=0.0))
        clamped = sum(np.searchsorted(self.clamped(k, top), omega)
                      for k in range(len(self.mounts)))
        return negative + clamped

    def frequencies(self, n: int) -> np.ndarray:
        """First n elastic coupled frequencies by the Wittrick-Williams count and bisection.

        Bracket: with the hub held, the spacecraft falls apart into the clamped appendages; by
        Rayleigh's interlacing (n_hub constraints) the k-th elastic coupled frequency is at
        least the k-th clamped frequency of them all, so half the lowest clamped frequency is
        below every elastic one. The upper end doubles until the count reaches n + n_rigid.
        """
        n_rigid = self.n_hub
        n_total = n + n_rigid
        lowest = min((float(wc[0]) if wc.size else np.inf)
                     for wc in (self.clamped(k, 0.0) for k in range(len(self.mounts))))
        if not np.isfinite(lowest):
            raise ValueError("the spacecraft has no elastic mode: no appendage has a clamped "
                             "natural frequency")
        lo = np.full(n, 0.5 * lowest)
        hi = np.full(1, lowest)
        while self.count(hi)[0] < n_total:
            hi = hi * 2.0
            if not np.isfinite(hi[0]) or hi[0] > 1e12 * lowest:
                raise ValueError(
                    f"the spacecraft has fewer than n = {n} elastic natural frequencies "
                    f"below {hi[0]:.3g} rad/s (a finite appendage has a finite number)")
        hi = np.full(n, hi[0])
        target = np.arange(n_rigid + 1, n_total + 1)  # frequency k is where the count reaches k
        active = np.arange(n)
        for _ in range(200):
            mid = 0.5 * (lo[active] + hi[active])
            above = self.count(mid) >= target[active]
            hi[active] = np.where(above, mid, hi[active])
            lo[active] = np.where(above, lo[active], mid)
            active = active[hi[active] - lo[active] > 4e-16 * hi[active]]
            if active.size == 0:
                break
        return 0.5 * (lo + hi)
