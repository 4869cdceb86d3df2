r"""The exact frequency-domain reference of a hub with appendages, through their W matrices.

Eliminating every appendage leaves the hub's dynamic stiffness. Planar (hub coordinates
``h = (X, Y, theta)``; appendage root motions ``(delta, phi) = G_r h``, its rigid axial motion
``g^T h``; ``D = W^-1``)::

    Z(s) = M_hub s**2 + sum_i ( G_r,i^T D_i(s) G_r,i + m_i s**2 g_i g_i^T ),

three axes (``h = (X, Y, Z, theta_x, theta_y, theta_z)``; root motions ``G_i h`` in the
appendage's axes, :mod:`spacecraft.dynamics.kinematics`; ``D6 = W6^-1``, axial motion included)::

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

__all__ = ["ExactReference", "clamped_frequencies", "dynamic_stiffness_of", "frequency_vector",
           "planar_rotation_response"]

_CHUNK = 65536  # frequencies per evaluation of Z in the count


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


#: From this many frequencies on, a planar attitude response is solved by
#: :func:`planar_rotation_response` (a few array operations over all of them) instead of one
#: LAPACK solve per frequency, which costs more for a long grid and less for a few points.
_ELIMINATION_POINTS = 32


def planar_rotation_response(Z: np.ndarray) -> np.ndarray:
    """``(Z^-1)[2, 2]`` of a stack of 3x3 matrices, shape ``Z.shape[:-2]``: the third component
    of the solution of ``Z x = e_3``.

    Gaussian elimination with partial pivoting, as LAPACK's ``zgesv`` does it for each matrix
    (pivot: the largest ``|Re| + |Im|`` in the column), written over the whole stack at once:
    the same backward-stable algorithm, its results equal to a per-matrix solve to rounding. A
    singular matrix gives a non-finite entry (a zero pivot), the others are unaffected.
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return _eliminate(np.asarray(Z, dtype=complex))


def _eliminate(Z: np.ndarray) -> np.ndarray:
    n = Z.shape[:-2]
    A = Z.reshape(-1, 3, 3)

    def size(z):
        return np.abs(z.real) + np.abs(z.imag)

    # first column: the pivot row moves to the top (its rows in order p, then the other two)
    p = np.argmax(size(A[:, :, 0]), axis=1)
    order = np.array([[0, 1, 2], [1, 0, 2], [2, 1, 0]])[p]
    A = np.take_along_axis(A, order[:, :, None], axis=1)
    b = (order == 2).astype(complex)          # e_3, permuted with the rows
    l1 = A[:, 1, 0] / A[:, 0, 0]
    l2 = A[:, 2, 0] / A[:, 0, 0]
    a11 = A[:, 1, 1] - l1 * A[:, 0, 1]
    a12 = A[:, 1, 2] - l1 * A[:, 0, 2]
    a21 = A[:, 2, 1] - l2 * A[:, 0, 1]
    a22 = A[:, 2, 2] - l2 * A[:, 0, 2]
    b1 = b[:, 1] - l1 * b[:, 0]
    b2 = b[:, 2] - l2 * b[:, 0]
    # second column: rows 1 and 2 exchanged where the lower holds the larger pivot
    swap = size(a21) > size(a11)
    a11, a21 = np.where(swap, a21, a11), np.where(swap, a11, a21)
    a12, a22 = np.where(swap, a22, a12), np.where(swap, a12, a22)
    b1, b2 = np.where(swap, b2, b1), np.where(swap, b1, b2)
    m = a21 / a11
    return ((b2 - m * b1) / (a22 - m * a12)).reshape(n)


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
        # Z(s) = s**2 M + sum over distinct appendages of vec(D(s)) K (module docstring): the
        # congruences G^T D G of the mounts sharing an appendage as one constant matrix K,
        # ``K[a*r + b, i*n + j] = sum G_ai G_bj``, so that every frequency's sum is one matrix
        # product (n, r*r) @ (r*r, n*n), and the hub's and the axial rigid masses as one M
        self._mass = np.array(hub.mass_matrix, dtype=float)
        self._congruences: dict = {}
        for mount in self.mounts:
            if self.three_axis:
                G = mount.transformation()
            else:
                kinematics = mount.kinematics()
                G, axial = kinematics[1:], kinematics[0]
                self._mass = self._mass + mount.appendage.mass * np.outer(axial, axial)
            K = np.einsum("ai,bj->abij", G, G).reshape(G.shape[0] ** 2, self.n_hub ** 2)
            key = id(mount.appendage)
            if key in self._congruences:
                self._congruences[key] = (mount.appendage, self._congruences[key][1] + K)
            else:
                self._congruences[key] = (mount.appendage, K)
        # complex once here, not at every product with the complex D (the same numbers)
        self._congruences = {key: (appendage, K.astype(complex))
                             for key, (appendage, K) in self._congruences.items()}
        self._clamped: dict = {}
        # the attitude response's right-hand sides: the unit torques on the rotations
        self._rotation = slice(2, 3) if not self.three_axis else slice(3, 6)
        n_rotations = self._rotation.stop - self._rotation.start
        self._unit = np.zeros((self.n_hub, n_rotations))
        self._unit[self._rotation] = np.eye(n_rotations)

    # -- Z(s) -------------------------------------------------------------------------------------
    def hub_dynamic_stiffness(self, s: np.ndarray, *, undamped: bool = False) -> np.ndarray:
        """Z(s) of the hub with every appendage eliminated (module docstring).

        Shape ``s.shape + (n_hub, n_hub)``. D_i comes from the appendage's own dynamic
        stiffness when it offers one (exact closed form of a beam, static condensation of a
        finite model), which stays accurate where W_i is singular (W_i -> 0 at its clamped
        frequencies) or huge (at its free poles), where inverting W_i loses every digit.
        """
        s = np.asarray(s, dtype=complex)
        flat = s.reshape(-1)
        n = self.n_hub
        Z = (flat**2)[:, None] * self._mass.reshape(1, n * n)
        for appendage, K in self._congruences.values():
            D = dynamic_stiffness_of(appendage, flat, undamped=undamped, n_root=self.n_root)
            Z += D.reshape(flat.size, -1) @ K
        return Z.reshape(s.shape + (n, n))

    def attitude_compliance(self, omega: np.ndarray) -> np.ndarray:
        r"""theta/torque at s = i omega: shape ``omega.shape + (1, 1)`` planar, ``(3, 3)``.

        Derivation (three axes; the planar case is the same with h = (X, Y, theta), the
        appendages' root motions (delta, phi) and their rigid axial motion). The hub's small
        motion h = (u_G, theta) (centre of mass, rotation vector, hub axes) moves appendage i's
        root by ``q_i = G_i h`` in the appendage's axes (``G_i = Mount.transformation()``,
        :mod:`spacecraft.dynamics.kinematics`). The root loads F_i that the hub applies to the
        appendage give ``q_i = W6_i(s) F_i``, so ``F_i = D6_i(s) G_i h`` with ``D6_i = W6_i^-1``,
        and by virtual work (the power ``F_i . q_i' = (G_i^T F_i) . h'``) the appendage pushes
        back on the hub with ``-G_i^T F_i``. The hub's equations under the generalised load Q
        (forces at its centre of mass, torques) are then, in Laplace form from rest,

            M_hub s**2 h = Q - sum_i G_i^T D6_i(s) G_i h,   i.e.   Z(s) h = Q,

        with Z of the module docstring. The actuator torques tau act on the rotations,
        ``Q = E tau`` with ``E = [0; I3]``, and the attitude is ``theta = E^T h``: the attitude
        response is ``theta/tau = E^T Z(s)^-1 E``, the rotation block of Z^-1 (one linear
        solve per frequency, all frequencies at once), and the rate response is ``s`` times it.

        The rigid limit. A free appendage has no static stiffness at its root: its D6(s) =
        ``s**2 M_rr + O(s**4)`` (M_rr its rigid mass matrix about the root), and each
        appendage evaluates it without cancellation at small |s| (the beam's power series, the
        modal sums of finite models). So every entry of Z carries the factor s**2,
        ``Z(s) = s**2 (M_rigid + O(s**2))``, with M_rigid the whole spacecraft's rigid mass
        matrix about the hub's centre of mass, positive definite: Z is s**2 times a matrix as
        well conditioned as M_rigid, whatever |s|. The solve (LU with partial pivoting) is
        invariant under that scalar, so the 1/s**2 of the rigid body comes out of it exactly,
        ``theta/tau -> -J_c^-1 / omega**2`` (J_c the inertia about the spacecraft's centre of
        mass, the Schur complement of the translations in M_rigid), with the flexible part
        as a relative correction O(omega**2 / w_1**2) in full precision: no near-singular
        matrix is inverted, as in the planar case, which takes the same path.

        Raises ValueError where the undamped spacecraft has a natural frequency.
        """
        s = 1j * omega
        rotation, unit = self._rotation, self._unit
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            Z = self.hub_dynamic_stiffness(s)
            if not self.three_axis and omega.size >= _ELIMINATION_POINTS:
                response = planar_rotation_response(Z)[..., None, None]
            else:
                try:
                    response = np.linalg.solve(Z, unit)      # unit broadcast over Z
                    response = response[..., rotation, :]
                except np.linalg.LinAlgError:
                    response = np.full(omega.shape + (unit.shape[1],) * 2, np.nan,
                                       dtype=complex)
        if not np.isfinite(response).all():
            bad = ~np.all(np.isfinite(response), axis=(-2, -1))
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

    def _stiffness_at(self, omega: np.ndarray) -> np.ndarray:
        """Real symmetric Z(i omega) of the undamped spacecraft; at an appendage's clamped
        frequency (D infinite) its limit from below: evaluated lower by 2, 4, 8, ... ulps
        until finite (a finite model's condensation can meet an exactly zero pivot a few
        ulps around its pole, where the last pivot is a difference rounded to zero; at most
        2**24 ulps, 4e-9 relative, are tried). Evaluated in chunks of 65536 frequencies
        (bounded memory, within the ``points`` limit)."""
        omega = np.asarray(omega, dtype=float)
        if omega.size > _CHUNK:
            return np.concatenate([self._stiffness_at(omega[k:k + _CHUNK])
                                   for k in range(0, omega.size, _CHUNK)])
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            Z = self.hub_dynamic_stiffness(1j * omega, undamped=True).real
            bad = ~np.all(np.isfinite(Z), axis=(-2, -1))
            step = 0
            while np.any(bad) and step < 24:
                step += 1
                lower = omega[bad] * (1.0 - 2.0**step * np.finfo(float).eps)
                Z[bad] = self.hub_dynamic_stiffness(1j * lower, undamped=True).real
                bad[bad] = ~np.all(np.isfinite(Z[bad]), axis=(-2, -1))
        if np.any(bad):  # pragma: no cover - a pole 2**24 ulps wide
            raise FloatingPointError("the dynamic stiffness of an appendage is not finite near "
                                     f"omega = {describe(omega[bad])} [rad/s]")
        return 0.5 * (Z + np.swapaxes(Z, -1, -2))

    @staticmethod
    def _scaling(Z: np.ndarray) -> np.ndarray:
        """Diagonal equilibration 1/sqrt|Z_ii| (1 where Z_ii = 0): N/m against N*m/rad."""
        diagonal = np.abs(np.diagonal(Z, axis1=-2, axis2=-1))
        return np.where(diagonal > 0, 1.0 / np.sqrt(np.where(diagonal > 0, diagonal, 1.0)), 1.0)

    def _clamped_below(self, omega: np.ndarray) -> np.ndarray:
        """Clamped frequencies of all appendages below each omega (the J0 of the count)."""
        top = float(np.max(omega, initial=0.0))
        return sum(np.searchsorted(self.clamped(k, top), omega)
                   for k in range(len(self.mounts)))

    def _safe(self, omega: np.ndarray) -> np.ndarray:
        """omega, or, within 1e-13 of a clamped frequency, a point 2e-13 below the lowest
        clamped frequency of that cluster.

        Next to a pole of Z its decisive eigenvalues drown in the pole's rounding, and
        clamped frequencies of different appendages can coincide to an ulp (rods whose
        lengths are in odd ratios): there the count would not be monotone. Within such a
        window it is taken from below the whole cluster, so a coupled frequency inside it (a
        mode that leaves the hub still, at a clamped frequency) is found at the window's
        upper edge, 1e-13 relative from where it is.
        """
        omega = np.asarray(omega, dtype=float)
        top = float(np.max(omega, initial=0.0)) * (1.0 + 1e-12)
        poles = np.sort(np.concatenate([self.clamped(k, top)
                                        for k in range(len(self.mounts))] or [np.zeros(0)]))
        if poles.size == 0:
            return omega
        first = np.searchsorted(poles, omega * (1.0 - 1e-13))
        near = (first < poles.size) & (poles[np.minimum(first, poles.size - 1)]
                                       <= omega * (1.0 + 1e-13))
        if not np.any(near):
            return omega
        out = omega.copy()
        lowest = first[near]
        # walk down through a cluster of poles each within 1e-13 of the next
        while True:
            below = np.maximum(lowest - 1, 0)
            step = (lowest > 0) & (poles[below] >= poles[lowest] * (1.0 - 1e-13))
            if not np.any(step):
                break
            lowest = np.where(step, below, lowest)
        out[near] = poles[lowest] * (1.0 - 2e-13)
        return out

    def count(self, omega: np.ndarray) -> np.ndarray:
        """Wittrick-Williams count: coupled frequencies (rigid-body ones included) < omega.

        ``J(w) = sum_i J0_i(w) + s{Z(iw)}`` (module docstring). Exactly at an appendage's
        clamped frequency D_i is infinite; the count there is its limit from below (a natural
        frequency is counted only above it), taken below the cluster of clamped frequencies
        within 1e-13 (:meth:`_safe`).
        """
        omega = self._safe(np.asarray(omega, dtype=float))
        return self._count_from(self._stiffness_at(omega), omega)

    def _count_from(self, Z: np.ndarray, omega: np.ndarray) -> np.ndarray:
        """The count at omega from Z(i omega) (:meth:`_stiffness_at`)."""
        # Sylvester's law of inertia: negative eigenvalues of the symmetric Z, equilibrated
        # (a congruence: same inertia). eigvalsh is backward stable, so the count is exact
        # unless an eigenvalue is within round-off of zero, i.e. omega within round-off of a
        # coupled frequency: what bisection needs.
        S = self._scaling(Z)
        negative = (np.linalg.eigvalsh(Z * S[..., :, None] * S[..., None, :]) < 0).sum(axis=-1)
        return negative + self._clamped_below(omega)

    def frequencies(self, n: int) -> np.ndarray:
        """First n elastic coupled frequencies by the Wittrick-Williams count.

        Bracket: with the hub held, the spacecraft falls apart into the clamped appendages; by
        Rayleigh's interlacing (n_hub constraints) the k-th elastic coupled frequency is at
        least the k-th clamped frequency of them all, so half the lowest clamped frequency is
        below every elastic one. The upper end doubles until the count reaches n + n_rigid.

        Bisection on the count then isolates each frequency: a bracket [lo, hi] whose counts
        are k - 1 and k. Inside it, the function

            F(w) = det(S Z(i w) S) prod_p (1 - w**2/w_p**2)

        (S the diagonal equilibration at lo, w_p the clamped frequencies of all appendages
        in the bracket, with their multiplicity) is continuous, since each pole of Z is a
        rank-one pole of one appendage's D whose sign flip the factor cancels, and it changes
        sign exactly where the count does: at the frequency, and only there. A safeguarded
        secant method on F (:class:`_Secant`) converges superlinearly (a few evaluations
        instead of 40 bisections) and keeps the bracket, so the result is as safe as bisection and
        accurate to the same rounding (both are decided by the sign of the eigenvalue of Z
        that crosses zero). One Z evaluation per step serves every frequency at once,
        bisecting or refining. A multiple frequency (never isolated: a symmetric spacecraft)
        is finished by bisection.
        """
        n_rigid = self.n_hub
        n_total = n + n_rigid
        lowest = min((float(wc[0]) if wc.size else np.inf)
                     for wc in (self.clamped(k, 0.0) for k in range(len(self.mounts))))
        if not np.isfinite(lowest):
            raise ValueError("the spacecraft has no elastic mode: no appendage has a clamped "
                             "natural frequency")
        # the top of the search: the first of lowest * 2**k whose count reaches n + n_rigid,
        # twelve at a time
        ladder = lowest * 2.0 ** np.arange(12)
        while True:
            reached = np.flatnonzero(self.count(ladder) >= n_total)
            if reached.size:
                top = ladder[reached[0]]
                break
            if ladder[-1] > 1e12 * lowest or not np.isfinite(ladder[-1]):
                raise ValueError(
                    f"the spacecraft has fewer than n = {n} elastic natural frequencies "
                    f"below {ladder[-1]:.3g} rad/s (a finite appendage has a finite number)")
            ladder = ladder[-1] * 2.0 ** np.arange(1, 13)
        poles = np.sort(np.concatenate([self.clamped(k, float(top))
                                        for k in range(len(self.mounts))]))
        # First brackets from one evaluation at the eighths between consecutive clamped
        # frequencies below the top and beside each (1e-4 and 1e-2 relative): these interlace the
        # coupled frequencies (Rayleigh), and a coupled frequency next to a clamped one (a
        # mode that leaves the hub almost still) is split from its neighbours, so most
        # brackets hold one frequency at once, without bisection steps. (Not at the clamped
        # frequencies themselves: next to a pole of Z the eigenvalues that decide the count
        # are swamped by the pole's rounding.)
        dividers = np.unique(poles[(poles > 0.5 * lowest) & (poles < top)])
        edges = np.concatenate([[0.5 * lowest], dividers, [top]])
        # (eighths while they are few; midpoints for thousands of frequencies)
        fractions = np.arange(1, 8) / 8.0 if dividers.size <= 4096 else np.array([0.5])
        inner = edges[:-1, None] + np.diff(edges)[:, None] * fractions
        beside = dividers[:, None] * (1.0 + np.array([-1e-2, -1e-4, 1e-4, 1e-2]))
        samples = np.unique(np.concatenate([edges[[0, -1]], inner.ravel(), beside.ravel()]))
        # none within 1e-8 of a pole (clamped frequencies of different appendages a few ulps
        # apart put "midpoints" on them): the count is unreliable there
        if poles.size:
            nearest = np.searchsorted(poles, samples).clip(1, poles.size - 1)
            gap = np.minimum(np.abs(samples - poles[nearest - 1]), np.abs(samples - poles[nearest]))
            samples = samples[(gap > 1e-8 * samples) | (samples == edges[0]) | (samples == top)]
        Z_samples = self._stiffness_at(samples)
        counts = self.count(samples) if np.any(self._safe(samples) != samples) \
            else self._count_from(Z_samples, samples)
        target = np.arange(n_rigid + 1, n_total + 1)  # frequency k is where the count reaches k
        upper = np.searchsorted(counts, target, side="left")  # first sample counting >= k
        lo, hi = samples[upper - 1], samples[upper]
        Z_lo, Z_hi = Z_samples[upper - 1], Z_samples[upper]
        count_lo, count_hi = counts[upper - 1], counts[upper]
        refine = _Secant(n, self.n_hub)
        active = np.arange(n)
        for _ in range(300):
            active = active[(hi[active] - lo[active] > 4e-16 * hi[active])
                            & ~refine.done[active]]
            if active.size == 0:
                break
            isolated = ((count_lo[active] == target[active] - 1)
                        & (count_hi[active] == target[active]))
            start = active[isolated & ~refine.running[active]]
            if start.size:
                ok = start[~(np.isin(lo[start], poles) | np.isin(hi[start], poles))]
                if ok.size:
                    # the clamped frequencies strictly inside each bracket, inf-padded
                    first = np.searchsorted(poles, lo[ok], side="right")
                    count = np.searchsorted(poles, hi[ok], side="left") - first
                    offsets = np.arange(max(int(count.max()), 1))
                    index = np.minimum(first[:, None] + offsets, max(poles.size - 1, 0))
                    inner = np.where(offsets < count[:, None],
                                     poles[index] if poles.size else np.inf, np.inf)
                    refine.start(ok, lo, hi, Z_lo[ok], Z_hi[ok], inner)
            by_refine = active[refine.running[active]]
            by_bisection = active[~refine.running[active]]
            points = np.concatenate([refine.candidates(by_refine, lo, hi),
                                     0.5 * (lo[by_bisection] + hi[by_bisection])])
            Z = self._stiffness_at(points)
            m = by_refine.size
            if m:
                refine.update(by_refine, points[:m], Z[:m], lo, hi)
            if by_bisection.size:
                mid, Zb = points[m:], Z[m:]
                safe = self._safe(mid)
                moved = safe != mid
                counts = self._count_from(Zb, mid)
                if np.any(moved):
                    counts[moved] = self.count(safe[moved])
                above = counts >= target[by_bisection]
                up, down = by_bisection[above], by_bisection[~above]
                hi[up], count_hi[up], Z_hi[up] = mid[above], counts[above], Zb[above]
                lo[down], count_lo[down], Z_lo[down] = mid[~above], counts[~above], Zb[~above]
        return np.where(refine.done, refine.root, 0.5 * (lo + hi))


class _Secant:
    """Safeguarded secant (Dekker's method) on F of :meth:`ExactReference.frequencies`, for
    many roots at once.

    F is kept as a sign and a logarithm, ``log|F| = log|det(S Z S)| + sum log|1 -
    w**2/w_p**2|``, so that no value overflows and the secant uses only ratios of F at
    nearby points. Each root keeps a bracket [a, b] with F of opposite signs, b the end with
    the smaller |F|, and steps by the secant through b and the previous iterate when that
    lands between b and the midpoint, by bisection otherwise, and by bisection whenever the
    bracket has not halved in three steps (T. J. Dekker 1969; R. P. Brent, "Algorithms for
    Minimization without Derivatives", 1973, ch. 4). A step shorter than the tolerance is
    lengthened to it, so the bracket closes to ``4.4e-16 |b|`` once the secant has converged.
    """

    def __init__(self, n: int, n_hub: int):
        self.running = np.zeros(n, dtype=bool)
        self.done = np.zeros(n, dtype=bool)
        self.root = np.zeros(n)
        self.S = np.ones((n, n_hub))
        self.poles = np.full((n, 1), np.inf)  # clamped frequencies in each bracket, inf-padded
        self.a, self.b, self.previous = np.zeros(n), np.zeros(n), np.zeros(n)
        # F at a, b and the previous iterate: signs and log magnitudes
        self.sa, self.sb, self.sp = np.zeros(n), np.zeros(n), np.zeros(n)
        self.la, self.lb, self.lp = np.zeros(n), np.zeros(n), np.zeros(n)
        self.width = np.zeros(n)
        self.steps = np.zeros(n, dtype=int)

    def _F(self, rows, omega, Z):
        """(sign, log|F|) at omega; a point exactly on a pole is taken from below, as Z."""
        S = self.S[rows]
        sign, logdet = np.linalg.slogdet(Z * S[:, :, None] * S[:, None, :])
        factor = 1.0 - (omega[:, None] / self.poles[rows]) ** 2
        factor[factor == 0.0] = 4.4e-16
        return sign * np.prod(np.sign(factor), axis=1), logdet + np.sum(np.log(np.abs(factor)),
                                                                        axis=1)

    def start(self, rows, lo, hi, Z_lo, Z_hi, poles):
        diagonal = np.abs(np.diagonal(Z_lo, axis1=-2, axis2=-1))
        self.S[rows] = np.where(diagonal > 0, 1.0 / np.sqrt(np.where(diagonal > 0, diagonal,
                                                                     1.0)), 1.0)
        width = poles.shape[1]
        if width > self.poles.shape[1]:
            self.poles = np.hstack([self.poles, np.full((self.poles.shape[0],
                                                         width - self.poles.shape[1]), np.inf)])
        self.poles[rows] = np.inf
        self.poles[rows, :width] = poles
        sa, la = self._F(rows, lo[rows], Z_lo)
        sb, lb = self._F(rows, hi[rows], Z_hi)
        good = (sa * sb < 0) & np.isfinite(la) & np.isfinite(lb)
        rows = rows[good]
        self.a[rows], self.sa[rows], self.la[rows] = lo[rows], sa[good], la[good]
        self.b[rows], self.sb[rows], self.lb[rows] = hi[rows], sb[good], lb[good]
        self.previous[rows], self.sp[rows], self.lp[rows] = lo[rows], sa[good], la[good]
        self.width[rows] = hi[rows] - lo[rows]
        self.steps[rows] = 0
        self.running[rows] = True

    def candidates(self, rows, lo, hi):
        """Next point of each running root (class docstring)."""
        swap = rows[self.la[rows] < self.lb[rows]]
        for first, second in ((self.a, self.b), (self.sa, self.sb), (self.la, self.lb)):
            first[swap], second[swap] = second[swap], first[swap].copy()
        a, b, p = self.a[rows], self.b[rows], self.previous[rows]
        # the secant partner: the previous iterate, or the contrapoint when the swap has made
        # the previous iterate b itself (regula falsi then)
        own = p == b
        p = np.where(own, a, p)
        sp = np.where(own, self.sa[rows], self.sp[rows])
        lp = np.where(own, self.la[rows], self.lp[rows])
        middle = 0.5 * (a + b)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            ratio = sp * self.sb[rows] * np.exp(lp - self.lb[rows])
            secant = b - (b - p) / (1.0 - ratio)  # b - F(b) (b - p)/(F(b) - F(p))
        between = np.isfinite(secant) & ((secant - b) * (secant - middle) < 0)
        checkpoint = (self.steps[rows] > 0) & (self.steps[rows] % 3 == 0)
        slow = checkpoint & (np.abs(b - a) > 0.5 * self.width[rows])
        self.width[rows] = np.where(checkpoint, np.abs(b - a), self.width[rows])
        point = np.where(between & ~slow, secant, middle)
        # a secant step below the tolerance (or rounding to b itself) means b is the root to
        # rounding: step by the tolerance towards a, which closes the bracket
        tolerance = 2.2e-16 * np.abs(b)
        short = (np.abs(point - b) < tolerance) | (np.isfinite(secant) & ~slow
                                                    & (np.abs(secant - b) < tolerance))
        return np.where(short, b + np.sign(middle - b) * tolerance, point)

    def update(self, rows, points, Z, lo, hi):
        sc, lc = self._F(rows, points, Z)
        zero = (sc == 0.0) | np.isneginf(lc)
        self.previous[rows], self.sp[rows], self.lp[rows] = (self.b[rows], self.sb[rows],
                                                             self.lb[rows])
        same = rows[sc == self.sa[rows]]
        # the old b becomes the contrapoint when the new point is on a's side
        self.a[same], self.sa[same], self.la[same] = self.b[same], self.sb[same], self.lb[same]
        self.b[rows], self.sb[rows], self.lb[rows] = points, sc, lc
        self.steps[rows] += 1
        lo[rows] = np.minimum(self.a[rows], self.b[rows])
        hi[rows] = np.maximum(self.a[rows], self.b[rows])
        closed = zero | (hi[rows] - lo[rows] <= 4.5e-16 * hi[rows])
        finished = rows[closed]
        self.root[finished] = np.where(zero[closed], points[closed],
                                       0.5 * (lo[finished] + hi[finished]))
        self.done[finished] = True
        self.running[finished] = False
