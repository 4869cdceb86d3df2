r"""Exact distributed rods: the axial and torsional motion of a uniform straight member.

Both motions obey the same wave equation. With ``S`` the stiffness (EA [N] for axial motion,
GJ [N*m**2] for torsion), ``mu`` the inertia per unit length (rho*A [kg/m], rho*I_p [kg*m])
and ``q(x, t)`` the motion (u [m], theta_x [rad]), ``S q'' = mu q_tt``. The member is free at
x = L and loaded at its attachment end x = 0 by ``P`` (F_x [N] or M_x [N*m]); the end's
equilibrium gives ``S q'(0) = -P`` (a positive load stretches or twists the member towards
-x), ``q'(L) = 0``.

Exact root compliance
---------------------
In Laplace form ``q'' = k**2 q`` with ``k = s sqrt(mu/S)``. The solution free at x = L is
``q = A cosh(k (L - x))``; ``S q'(0) = S A k sinh(k L) = P``. Writing ``tau = L sqrt(mu/S)``
(the travel time of a wave along the member), ``c = sqrt(S mu)`` (its impedance),
``m = mu L = tau c`` (the rigid inertia: mass or polar moment of inertia) and ``z = s tau``::

    W(s) = q(0)/P = coth(z)/(c s) = z coth(z)/(m s**2),      D(s) = 1/W = m s**2 tanh(z)/z.

Near s = 0, ``z coth z = 1 + z**2/3 - z**4/45 + ...``: W is the rigid ``1/(m s**2)`` plus the
static flexibility ``L/(3 S)`` of a member loaded by its own inertia. At ``s = i w``,
``W = -cot(w tau)/(c w)``: poles at the free-free frequencies ``k pi/tau`` and zeros at the
clamped-free ones ``(k - 1/2) pi/tau`` (k = 1, 2, ...).

Evaluation: with ``Re z >= 0`` (both ``z coth z`` and ``tanh(z)/z`` are even), ``t = exp(-2 z)``
has ``|t| <= 1`` and ``1 - t = -expm1(-2 z)`` keeps full relative accuracy near z = 0, so
``z coth z = z (1 + t)/(1 - t)`` and ``tanh(z)/z = (1 - t)/((1 + t) z)`` never overflow and
never cancel.

Modal damping
-------------
The free-free modes are ``phi_k = sqrt(2/m) cos(k pi x/L)`` (mass-normalised, root value
``b_k = sqrt(2/m)``, frequency ``w_k = k Omega``, ``Omega = pi/tau``). With every mode damped
at the ratio zeta, ``W = 1/(m s**2) + (2/m) sum_k 1/(s**2 + 2 zeta w_k s + w_k**2)``.
Factoring ``k**2 + 2 zeta k a + a**2 = (k - p)(k - q)`` with ``a = s/Omega``,
``p, q = a (-zeta +- i sqrt(1 - zeta**2))``, and summing the partial fractions with the
digamma function (``psi(1 + x) = -gamma + sum_k [1/k - 1/(k + x)]``)::

    W(s) = 1/(m s**2) + 2/(m Omega**2) [psi(1 - q) - psi(1 - p)]/(p - q),

exact at any s (zeta = 0 gives back the coth form). That is the free-free convention; by
default the ratio damps the cantilever modes (:mod:`appendages.damping`), and D(s) is their
modal sum (``Rod._cantilever_modal_stiffness``: the modes up to 10 |s| one by one, the rest by
Hurwitz zeta sums), the closed form with damping corrections beyond its cap on modes.

References
----------
.. [1] R. D. Blevins, "Formulas for Natural Frequency and Mode Shape", Van Nostrand, 1979,
   table 8-19 (uniform rods in axial and torsional vibration).
.. [2] K. F. Graff, "Wave Motion in Elastic Solids", Dover, 1991, ch. 2 (longitudinal and
   torsional waves in rods, impedance).
.. [3] NIST DLMF 5.7.6 (series of the digamma function), 5.15 (polygamma), 25.11 (Hurwitz
   zeta function).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.special

from . import limits
from .damping import (MAX_MODES, CantileverDamping, check_damping_convention,
                      check_damping_ratio, chebyshev_resonance_coefficients,
                      hurwitz_tail_coefficients, CantileverModalSums)
from .checks import as_frequency_array, check_range
from .errors import describe

__all__ = ["Rod", "MOTIONS"]

_TAIL_TERMS = 12    # terms of the series in s/w_k of the modal sum's tail

#: The two rod motions and the quantities (keys of RANGES) of their stiffness and inertia.
MOTIONS = {"axial": ("axial_stiffness", "linear_density"),
           "torsion": ("torsional_stiffness", "torsional_inertia")}

def zcoth_and_tanh_over_z(z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``z coth z`` and ``tanh(z)/z`` at complex z, stable at any |z| (module docstring).

    Both are even in z, so ``Re z >= 0`` is taken; with ``t = exp(-2 z)`` (``|t| <= 1``) and
    ``e = expm1(-2 z) = t - 1``, ``tanh(z)/z = -e/((1 + t) z)`` and ``z coth z =
    z (1 + t)/(-e)``: no overflow, and no cancellation near z = 0, where expm1 keeps full
    relative accuracy (both tend to 1; z = 0 is set exactly). Returns inf where
    ``sinh z = 0`` (z = i k pi, k != 0) or ``cosh z = 0`` respectively.
    """
    z = np.asarray(z, dtype=np.complex128)
    zz = np.where(z.real < 0.0, -z, z)
    t = np.exp(-2.0 * zz)
    e = np.expm1(-2.0 * zz)
    with np.errstate(divide="ignore", invalid="ignore"):
        zcoth = zz * (1.0 + t) / -e
        tanhz = -e / ((1.0 + t) * zz)
    zero = zz == 0
    if np.any(zero):
        zcoth[zero] = 1.0
        tanhz[zero] = 1.0
    return zcoth, tanhz


class Rod:
    """A uniform rod in axial or torsional motion, free at both ends (module docstring).

    Parameters
    ----------
    length : float, m
    stiffness : float
        EA [N] (``motion="axial"``) or GJ [N*m**2] (``motion="torsion"``).
    inertia : float
        rho*A [kg/m] (axial) or rho*I_p [kg*m] (torsion), per unit length.
    damping_ratio : float, optional
        Modal damping ratio, 0 <= zeta < 1, of every cantilever (fixed-root) mode by default.
    motion : {"axial", "torsion"}
    damping_convention : {"cantilever", "free-free"}, optional
        What damping_ratio damps (:class:`~appendages.beam.Beam`): the cantilever modes
        (default; :mod:`appendages.damping`) or every free-free mode (the digamma form above).

    Notes
    -----
    A three-axis :class:`~appendages.beam.Beam` builds its rods itself
    (``Beam.axial_rod()``, ``Beam.torsion_rod()``); the class is public for tests and for
    members that are only rods.
    """

    def __init__(self, length: float, stiffness: float, inertia: float, *,
                 damping_ratio: float = 0.0, motion: str = "axial",
                 damping_convention: str = "cantilever"):
        if not isinstance(motion, str) or motion not in MOTIONS:
            raise ValueError(f"motion must be 'axial' or 'torsion'; got {describe(motion)}")
        stiffness_quantity, inertia_quantity = MOTIONS[motion]
        self.motion = motion
        self.length = check_range("length", length, "length")
        self.stiffness = check_range(f"stiffness ({stiffness_quantity})", stiffness,
                                     stiffness_quantity)
        self.inertia = check_range(f"inertia ({inertia_quantity})", inertia, inertia_quantity)
        self.damping_ratio = check_damping_ratio(damping_ratio)
        self.damping_convention = check_damping_convention(damping_convention)
        self._cantilever = None
        self._modal: dict = {}     # N -> the modal sums (grid and few points alternate)

    def __repr__(self) -> str:
        return (f"Rod(length={self.length!r}, stiffness={self.stiffness!r}, "
                f"inertia={self.inertia!r}, damping_ratio={self.damping_ratio!r}, "
                f"motion={self.motion!r})")

    # -- scales -------------------------------------------------------------------------------
    @property
    def rigid_inertia(self) -> float:
        """mu L: the mass [kg] (axial) or polar moment of inertia [kg*m**2] (torsion)."""
        return self.inertia * self.length

    @property
    def travel_time(self) -> float:
        """tau = L sqrt(mu/S) [s]: free-free frequencies are k pi/tau."""
        return self.length * math.sqrt(self.inertia / self.stiffness)

    @property
    def impedance(self) -> float:
        """c = sqrt(S mu) [N*s/m or N*m*s]."""
        return math.sqrt(self.stiffness * self.inertia)

    # -- frequencies --------------------------------------------------------------------------
    def _check_n(self, n) -> int:
        if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)):
            raise TypeError(f"n must be an integer (number of frequencies); got "
                            f"{type(n).__name__} {describe(n)}")
        if n < 0:
            raise ValueError(f"n must be a non-negative integer; got {describe(n)}")
        limits.check("n", int(n), "roots", "frequencies of a rod at once")
        return int(n)

    def natural_frequencies(self, n: int) -> np.ndarray:
        """First n free-free frequencies ``k pi/tau`` [rad/s] (the rigid mode left out)."""
        return np.arange(1, self._check_n(n) + 1) * (math.pi / self.travel_time)

    def cantilever_frequencies(self, n: int) -> np.ndarray:
        """First n clamped-free frequencies ``(k - 1/2) pi/tau`` [rad/s] (zeros of W)."""
        return (np.arange(1, self._check_n(n) + 1) - 0.5) * (math.pi / self.travel_time)

    def cantilever_frequencies_below(self, omega_max: float) -> np.ndarray:
        """Every clamped-free frequency up to ``omega_max`` [rad/s], and the next one."""
        n = int(max(omega_max, 0.0) * self.travel_time / math.pi + 1.5) + 1
        return self.cantilever_frequencies(n)

    # -- exact W ------------------------------------------------------------------------------
    def W(self, s) -> np.ndarray:
        """Exact root compliance ``q(0)/P`` [m/N or rad/(N*m)], shape ``np.shape(s)``.

        Undamped: ``z coth(z)/(m s**2)``; damped: the digamma form (module docstring).
        """
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError("s = 0 is the rigid-body pole of W (W is infinite there) [rad/s]")
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            W = self._W(s)
        if not np.all(np.isfinite(W)):
            raise ValueError("s is a natural frequency of the undamped rod: W is infinite "
                             "there [rad/s]")
        return W

    def _W(self, s: np.ndarray) -> np.ndarray:
        m = self.rigid_inertia
        if self.damping_ratio > 0.0 and self.damping_convention == "cantilever":
            return 1.0 / self._D(s)
        if self.damping_ratio == 0.0:
            zcoth, _ = zcoth_and_tanh_over_z(s * self.travel_time)
            return zcoth / (m * s**2)
        zeta = self.damping_ratio
        Omega = math.pi / self.travel_time
        a = s / Omega
        root = math.sqrt(1.0 - zeta * zeta)
        p = a * complex(-zeta, root)
        q = a * complex(-zeta, -root)
        psi = scipy.special.psi
        return 1.0 / (m * s**2) + 2.0 / (m * Omega**2) * (psi(1.0 - q) - psi(1.0 - p)) / (p - q)

    def dynamic_stiffness(self, s, *, check: bool = True) -> np.ndarray:
        """Exact root dynamic stiffness ``D = 1/W`` [N/m or N*m/rad], shape ``np.shape(s)``.

        Undamped: ``m s**2 tanh(z)/z``, infinite exactly at a clamped-free frequency; damped
        (cantilever convention): the modal sum of the module docstring; s = 0 gives 0 (a free
        rod offers no static stiffness).

        Parameters
        ----------
        s : complex or array_like of complex, rad/s
        check : bool
            Check s (:func:`~appendages.checks.as_frequency_array`); False for a complex128
            array already checked (a beam's W6 evaluates its rods at the s it checked).
        """
        if check:
            s = as_frequency_array(s)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return self._D(s)

    def _D(self, s: np.ndarray) -> np.ndarray:
        if self.damping_ratio > 0.0 and self.damping_convention == "cantilever":
            flat = s.ravel()
            D = self._cantilever_modal_stiffness(flat)
            if D is None:       # |s| too high for the modal sum: the general evaluation
                D = self._cantilever_damping()(flat)[:, 0, 0]
            return D.reshape(s.shape)
        if self.damping_ratio == 0.0:
            _, tanhz = zcoth_and_tanh_over_z(s * self.travel_time)
            return self.rigid_inertia * s**2 * tanhz
        D = np.zeros(s.shape, dtype=np.complex128)
        nonzero = s != 0
        D[nonzero] = 1.0 / self._W(s[nonzero])
        return D

    def _undamped_D(self, s: np.ndarray) -> np.ndarray:
        _, tanhz = zcoth_and_tanh_over_z(s * self.travel_time)
        return self.rigid_inertia * s**2 * tanhz

    def _cantilever_damping(self) -> CantileverDamping:
        """The damped D of the cantilever convention (:mod:`appendages.damping`), built once."""
        if self._cantilever is None:
            def modes(n):
                l, _, w = self.cantilever_modes(n)
                return w, l[:, None]

            self._cantilever = CantileverDamping(
                self.damping_ratio, lambda s: self._undamped_D(s)[:, None, None], modes,
                np.array([[self.rigid_inertia]]), tail=self._cantilever_tail)
        return self._cantilever

    def _cantilever_modal_stiffness(self, s: np.ndarray) -> np.ndarray | None:
        r"""The damped D(s) of the cantilever convention by its modal sum, at flat complex s:
        shape (npts,), or None where it would need more than
        :data:`~appendages.damping.MAX_MODES` modes.

        With ``l_k**2 = 2 m/(b_k pi)**2``, ``w_k = b_k Omega`` (``b_k = k - 1/2``) and their
        completeness ``sum_k l_k**2 = m``, the modal form
        ``D = m s**2 - s**4 sum_k l_k**2/(s**2 + 2 zeta w_k s + w_k**2)`` is

            D(s) = s**2 sum_{k<=N} l_k**2 (w_k**2 + 2 zeta w_k s)/(s**2 + 2 zeta w_k s + w_k**2)
                   + s**2 R_N - s**4 sum_{k>N} l_k**2/w_k**2 h(s/w_k),

        ``R_N = (2 m/pi**2) zeta(2, N + 1/2)`` (Hurwitz) and ``h(u) = 1/(1 + 2 zeta u + u**2)
        = sum_j U_j(-zeta) u**j`` (:func:`~appendages.damping.chebyshev_resonance_coefficients`),
        so the last sum is ``Omega**2 (2 m/pi**2) sum_j U_j(-zeta) v**(4+j) zeta(4 + j,
        N + 1/2)``, ``v = s/Omega``. N (a power of two, at least 16) puts every mode up to
        10 max|s| in the explicit sum: |u| <= 1/10 in the tail, whose 12 terms leave below
        1e-11 of it (|U_j| <= j + 1). No term cancels another (a mode far below |s| gives
        about ``l**2 w_k**2``, one far above ``l**2 s**2``; the denominators are written
        ``(s - i w_k)(s + i w_k) + 2 zeta w_k s``, no difference of squares near a resonance).
        The same function as the closed form with damping corrections of
        :class:`~appendages.damping.CantileverDamping`, to rounding, at a fraction of its
        cost (no circle mean about the undamped poles); s = 0 gives 0.
        """
        N = self._modal_sum_size(float(np.abs(s).max()) if s.size else 0.0)
        if N is None:
            return None
        sums = self._modal.get(N)
        if sums is None:
            sums = self._modal[N] = CantileverModalSums([self._modal_motion(N)],
                                                        self.damping_ratio)
        return sums(s)[:, 0]

    def _modal_sum_size(self, top: float) -> int | None:
        """N of :meth:`_cantilever_modal_stiffness` at points up to ``top`` = max|s| [rad/s]:
        a power of two, at least 16, with every mode up to 10 top; None beyond
        :data:`~appendages.damping.MAX_MODES`."""
        Omega = math.pi / self.travel_time
        N = 16
        while (N + 0.5) * Omega < 10.0 * top:
            N *= 2
            if N > MAX_MODES:
                return None
        return N

    def _modal_motion(self, N: int) -> tuple:
        """The terms of :class:`~appendages.damping.CantileverModalSums` with N explicit modes
        (:meth:`_cantilever_modal_stiffness`): frequencies, weights l_k**2, R_N, the tail's
        coefficients, Omega."""
        Omega = math.pi / self.travel_time
        m, zeta = self.rigid_inertia, self.damping_ratio
        b = np.arange(1, N + 1) - 0.5
        j = np.arange(_TAIL_TERMS)
        scale = 2.0 * m / math.pi**2
        tail = (chebyshev_resonance_coefficients(zeta, _TAIL_TERMS) * Omega**2 * scale
                * scipy.special.zeta(4.0 + j, N + 0.5))
        return (b * Omega, (scale / b**2)[:, None],
                np.array([scale * float(scipy.special.zeta(2.0, N + 0.5))]), tail[:, None],
                Omega)

    def _cantilever_tail(self, s: np.ndarray, n: int) -> np.ndarray:
        """The damping of the cantilever modes k > n, exactly: ``l_k**2 = 2 m/(b_k pi)**2``,
        ``w_k = b_k Omega`` (``b_k = k - 1/2``), so with ``g(u) = sum_j c_j u**j`` the tail is
        ``sum_j c_j v**(4+j) Omega**2 (2 m/pi**2) zeta(4 + j, n + 1/2)``, ``v = s/Omega``
        (12 terms where ``|s| <= w_(n+1)/2``, else the leading one). Shape (npts, 1, 1)."""
        Omega = math.pi / self.travel_time
        w_next = (n + 0.5) * Omega
        n_terms = 12 if float(np.max(np.abs(s), initial=0.0)) <= 0.5 * w_next else 1
        c = hurwitz_tail_coefficients(self.damping_ratio, n_terms)
        j = np.arange(1, n_terms + 1)
        coefficients = (c * Omega**2 * 2.0 * self.rigid_inertia / math.pi**2
                        * scipy.special.zeta(4.0 + j, n + 0.5))
        v = s / Omega
        out = np.zeros(s.size, dtype=np.complex128)
        for t in range(n_terms - 1, -1, -1):
            out = (out + coefficients[t]) * v
        return (out * v**4)[:, None, None]

    # -- modal data ---------------------------------------------------------------------------
    def free_free_modes(self, n: int):
        """Root values b_k, tip values phi_k(L) and frequencies of the first n free-free modes.

        Mass-normalised ``phi_k = sqrt(2/m) cos(k pi x/L)``: ``b_k = sqrt(2/m)``,
        ``phi_k(L) = (-1)**k sqrt(2/m)``, ``w_k = k pi/tau``.
        """
        k = np.arange(1, n + 1)
        amplitude = math.sqrt(2.0 / self.rigid_inertia)
        return (np.full(n, amplitude), amplitude * (-1.0) ** k,
                k * (math.pi / self.travel_time))

    def free_free_tail(self, n: int, power: int) -> tuple[float, float]:
        """``sum_{k>n} b_k**2/w_k**power`` and ``sum_{k>n} phi_k(L) b_k/w_k**power``.

        ``(2/m) (tau/pi)**p`` times the Hurwitz zeta ``zeta(p, n + 1)`` and its alternating
        twin ``sum_{k>n} (-1)**k k**-p = (-1)**(n+1) 2**-p [zeta(p, (n+1)/2) - zeta(p,
        (n+2)/2)]``, exact, no cancellation.
        """
        f = 2.0 / self.rigid_inertia * (self.travel_time / math.pi) ** power
        zeta = scipy.special.zeta
        alternating = ((-1.0) ** (n + 1) * 2.0**-power
                       * (zeta(power, (n + 1) / 2.0) - zeta(power, (n + 2) / 2.0)))
        return f * float(zeta(power, n + 1.0)), f * float(alternating)

    def cantilever_modes(self, n: int):
        """Participation factors, tip values and frequencies of the first n cantilever modes.

        ``psi_k = sqrt(2/m) sin(b_k pi x/L)``, ``b_k = k - 1/2``: participation
        ``integral mu psi_k dx = sqrt(2 m)/(b_k pi)`` (their squares sum to m), tip value
        ``(-1)**(k+1) sqrt(2/m)``, frequency ``b_k pi/tau``.
        """
        b = np.arange(1, n + 1) - 0.5
        m = self.rigid_inertia
        return (math.sqrt(2.0 * m) / (b * math.pi), math.sqrt(2.0 / m) * (-1.0) ** (b - 0.5),
                b * (math.pi / self.travel_time))

    def cantilever_participation_tail(self, n: int) -> float:
        """``sum_{k>n}`` of the squared participation factors: ``(2 m/pi**2) zeta(2, n + 1/2)``,
        the mass the first n cantilever modes leave to the others."""
        return 2.0 * self.rigid_inertia / math.pi**2 * float(scipy.special.zeta(2.0, n + 0.5))

    def projected_damping(self, n: int) -> np.ndarray:
        r"""The rod's modal damping in its first n cantilever modes, shape (n, n) [1/s].

        ``C = sum_j 2 zeta w_j O_j O_j^T`` over every free-free mode j, with the overlaps
        ``O_ji = integral mu phi_j psi_i dx = (2/pi) b_i/(b_i**2 - j**2)`` (b_i = i - 1/2).
        Summed in closed form: with ``S(b, b') = sum_j j/((j**2 - b**2)(j**2 - b'**2))``,
        ``C_ii' = 2 zeta Omega (4/pi**2) b b' S(b, b')``, and from ``j/(j**2 - b**2) =
        [1/(j - b) + 1/(j + b)]/2`` and the digamma series,
        ``S(b, b') = [g(b') - g(b)]/(2 (b**2 - b'**2))``, ``g(b) = psi(1 - b) + psi(1 + b) =
        2 psi(b) + 1/b`` at half-integers, and on the diagonal
        ``S(b, b) = -g'(b)/(4 b) = (pi**2 + 1/b**2 - 2 psi'(b))/(4 b)`` (the reflection
        ``psi(1 - b) = psi(b) + pi cot(pi b)`` contributes ``-pi**2/sin(pi b)**2 = -pi**2`` to
        g'). Exact: no truncation of the sum over j.
        """
        b = np.arange(1, n + 1) - 0.5
        g = 2.0 * scipy.special.psi(b) + 1.0 / b
        with np.errstate(divide="ignore", invalid="ignore"):
            S = (g[None, :] - g[:, None]) / (2.0 * (b[:, None] ** 2 - b[None, :] ** 2))
        diagonal = (math.pi**2 + 1.0 / b**2 - 2.0 * scipy.special.polygamma(1, b)) / (4.0 * b)
        S[np.diag_indices(n)] = diagonal
        Omega = math.pi / self.travel_time
        C = 2.0 * self.damping_ratio * Omega * (4.0 / math.pi**2) * np.outer(b, b) * S
        return 0.5 * (C + C.T)
