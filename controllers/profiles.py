"""Rest-to-rest slew profiles: reference attitude, rate, acceleration and feedforward torque.

A profile turns the spacecraft from rest at 0 to rest at ``angle`` [rad] about one fixed axis
along a path s(t) (s(0) = 0, s(t_end) = angle, s' = s'' = 0 at both ends): for a planar plant
theta_ref = s, omega_ref = s', alpha_ref = s''; for a three-axis plant the eigen-axis slew about
the unit vector e (hub axes) of the small-angle kinematics of flexsat's plants,
theta_ref = e s, omega_ref = e s', alpha_ref = e s''. The feedforward torque is the rigid body's
torque along the reference: J alpha_ref (planar), J alpha_ref + omega_ref x J omega_ref (three
axes, Euler's equation; the gyroscopic term (e x J e) s'^2 vanishes about a principal axis and is
absent from flexsat's linear plants, which are linearised about rest).

Kinds (``PROFILE_KINDS``)
-------------------------
``"step"`` (:func:`step_reference`)
    The reference of flexsat's first designs: the cycloid of :func:`controllers.slew_profile`
    fed to theta_ref alone, omega_ref = 0 and no feedforward; the loop's own lag then sets the
    attitude error during the slew.
``"bang-coast-bang"`` (:func:`bang_coast_bang`)
    Constant acceleration a, coast at rate w, constant deceleration -a: the time-optimal
    rest-to-rest profile under an acceleration (torque) and a rate limit.
``"smooth"`` (:func:`jerk_limited`)
    The jerk-limited 7-segment ("double S") profile: jerk +-j or 0 on seven segments, the
    acceleration a continuous trapezoid, under jerk, acceleration (torque) and rate limits.
``"shaped"`` (:func:`shaped`)
    A base profile convolved with an input shaper (:class:`Shaper`): zero residual vibration of
    the shaper's modes (ZV), robustly to a frequency error (ZVD).

Every profile other than "step" is piecewise polynomial in t (degree <= 3, ``breakpoints`` and
``coefficients``); its peaks are exact.

Duration and limits
-------------------
Without ``duration`` a profile is the shortest the limits allow (closed form). With a
``duration`` T it completes in exactly T: bang-coast-bang with the least acceleration (hence
feedforward torque) the rate limit allows, the jerk-limited profile with the least jerk that the
acceleration and rate limits allow. A duration shorter than the limits allow raises a ValueError
that gives the shortest time they allow. In three axes the torque limit bounds each hub-axis
component of the rigid-body torque J e s'', so the acceleration limit is
torque_limit / max_i |(J e)_i|; the gyroscopic torque is reported apart
(:meth:`Profile.peak_torque`).

Derivation (given T, bang-coast-bang). With accelerating time t_a and coast, angle
theta = w (T - t_a) and a = w / t_a, so a = theta / (t_a (T - t_a)): the least a takes the
largest t_a allowed, t_a = min(T/2, T - theta / w_max) (w = theta / (T - t_a) <= w_max). For the
7-segment profile with jerk time t_j, constant-acceleration time t_c, accelerating phase
S = 2 t_j + t_c and u = t_j + t_c: w = theta / (T - S), a = w / u, j = a / t_j =
theta / ((T - S) u t_j); (T - S) u t_j grows with S (both while u = S/2 and where the
acceleration limit u >= theta / (a_max (T - S)) binds), so S = min(T/2, T - theta / w_max) and
u = max(S/2, theta / (a_max (T - S))). Without active limits this is the triangular-acceleration
profile of peak jerk 32 theta / T^3 (the cycloid needs 4 pi^2 theta / T^3 = 39.5 theta / T^3,
the quintic 60 theta / T^3).

Sampling for the simulators
---------------------------
:func:`controllers.simulate` interpolates its inputs linearly between samples (or holds them,
``hold="zero"``). :meth:`Profile.references` samples the references; :meth:`Profile.hold_error`
bounds, per signal, the difference between the profile and what the simulator sees, in the sup
norm and in the L1 norm (which bounds the effect on a stable loop's response: the output error is
at most the peak of the loop's impulse response from that input times the L1 error). Exact
alternatives: a grid through every breakpoint for the piecewise-linear parts, or the profile's
generator (:meth:`Profile.generator`): its highest derivative is piecewise constant, so a
zero-order hold on a grid through the breakpoints realises the profile exactly.

References
----------
B. Wie, Space Vehicle Dynamics and Control, 2nd ed., AIAA 2008, sec. 7.3 (rest-to-rest slews,
bang-coast-bang, feedforward); L. Biagiotti, C. Melchiorri, Trajectory Planning for Automatic
Machines and Robots, Springer 2008, sec. 3.4 (the double-S trajectory); N. C. Singer,
W. P. Seering, "Preshaping command inputs to reduce system vibration", J. Dyn. Sys. Meas.
Control 112(1), 1990 (ZV, ZVD shapers); W. Singhose, "Command shaping for flexible systems: a
review of the first 50 years", Int. J. Precision Eng. and Manufacturing 10(4), 2009.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Sequence

import control
import numpy as np

from .signals import AXES, OMEGA_REF, THETA_REF, TORQUE_FF
from .timeresp import slew_profile

__all__ = ["PROFILE_KINDS", "SHAPER_KINDS", "Profile", "Shaper",
           "step_reference", "bang_coast_bang", "jerk_limited", "shaped", "zv_shaper",
           "zvd_shaper", "mode_shaper", "reference_profile", "minimum_time"]

#: Profile kinds (see the module docstring).
PROFILE_KINDS = ("step", "bang-coast-bang", "smooth", "shaped")
#: Input shapers (see :func:`mode_shaper`).
SHAPER_KINDS = ("zv", "zvd")

# a duration within this relative distance of the shortest one counts as that one
_TIME_RTOL = 1e-12


# --------------------------------------------------------------------------------------------
# argument checks
# --------------------------------------------------------------------------------------------
def _number(value, name: str, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise TypeError(f"{name} must be a real number [{unit}]; got {type(value).__name__}")
    return float(value)


def _positive(value, name: str, unit: str) -> float:
    value = _number(value, name, unit)
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be positive and finite [{unit}]; got {value:.6g}")
    return value


def _limit(value, name: str, unit: str) -> float:
    """A positive finite limit, or inf for None (no limit)."""
    return math.inf if value is None else _positive(value, name, unit)


#: A rate limit above this [rad/s] (57 deg/s) is accepted with a warning: a spacecraft slew
#: rate in degrees per second given as radians per second, most likely.
PLAUSIBLE_RATE = 1.0


def _rate_limit(value) -> float:
    W = _limit(value, "rate_limit", "rad/s")
    if math.isfinite(W) and W > PLAUSIBLE_RATE:
        warnings.warn(f"rate_limit {W:.4g} rad/s is {math.degrees(W):.4g} deg/s, fast for a "
                      "spacecraft slew: degrees per second given as rad/s?", UserWarning,
                      stacklevel=3)
    return W


def _flag(value, name: str) -> bool:
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False; got {type(value).__name__}")
    return bool(value)


def _times(t, name: str = "t") -> np.ndarray:
    """Finite real times [s] as a float array."""
    if t is None or isinstance(t, (str, bytes)) or np.iscomplexobj(t):
        raise TypeError(f"{name} must be real numbers [s]; got {type(t).__name__}")
    try:
        t = np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be real numbers [s]; got {type(t).__name__}") from None
    if not np.all(np.isfinite(t)):
        raise ValueError(f"{name} must be finite [s]; got NaN or inf")
    return t


def _angle(value) -> float:
    value = _number(value, "angle", "rad")
    if not (math.isfinite(value) and value != 0):
        raise ValueError(f"angle must be non-zero and finite [rad]; got {value:.6g}")
    if abs(value) > 2 * math.pi:
        raise ValueError(f"angle must be at most 2 pi rad in magnitude (a slew, in radians); got "
                         f"{value:.6g} (degrees given as radians?)")
    return value


def _unit_axis(axis) -> np.ndarray | None:
    """None (planar), or the unit vector of 'x', 'y', 'z' or a non-zero 3-vector."""
    if axis is None:
        return None
    if isinstance(axis, str):
        if axis not in AXES:
            raise ValueError(f"axis must be 'x', 'y', 'z' or a 3-vector (hub axes); got "
                             f"{axis[:20]!r}")
        return np.eye(3)[AXES.index(axis)]
    try:
        e = np.asarray(axis, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"axis must be 'x', 'y', 'z' or a 3-vector (hub axes); got "
                        f"{type(axis).__name__}") from None
    if e.shape != (3,) or not np.all(np.isfinite(e)) or not np.any(e):
        raise ValueError(f"axis must be a non-zero finite 3-vector (hub axes); got shape "
                         f"{e.shape}")
    e = e / np.max(np.abs(e))  # scaled first: the norm of 1e-300 or 1e200 entries stays normal
    return e / np.linalg.norm(e)


def _inertia(inertia, e: np.ndarray | None):
    """A positive inertia [kg*m^2] (planar) or a symmetric positive-definite 3 x 3 one (three
    axes, with an axis)."""
    if e is None:
        if np.ndim(inertia) != 0:
            raise ValueError("inertia must be a positive number [kg*m^2] for a planar profile "
                             f"(axis=None); got an array of shape {np.shape(inertia)}: give "
                             "axis= for a three-axis slew")
        return _positive(inertia, "inertia", "kg*m^2")
    try:
        J = np.asarray(inertia, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"inertia must be a 3 x 3 array [kg*m^2]; got "
                        f"{type(inertia).__name__}") from None
    if J.shape != (3, 3) or not np.all(np.isfinite(J)):
        raise ValueError(f"inertia must be a finite 3 x 3 array [kg*m^2] for a three-axis "
                         f"profile; got shape {J.shape}")
    if not np.allclose(J, J.T, rtol=1e-10, atol=0.0) or np.linalg.eigvalsh(0.5 * (J + J.T)).min() <= 0:
        raise ValueError("inertia must be symmetric positive definite [kg*m^2]; got eigenvalues "
                         f"{np.array2string(np.linalg.eigvals(J).real, precision=4)}")
    return 0.5 * (J + J.T)


def _acceleration_limit(torque_limit, inertia, e) -> tuple[float, object]:
    """(acceleration limit [rad/s^2], checked inertia or None) from a torque limit."""
    if torque_limit is None:
        return math.inf, (None if inertia is None else _inertia(inertia, e))
    tau = _positive(torque_limit, "torque_limit", "N*m")
    if inertia is None:
        raise ValueError("inertia [kg*m^2] must be given with torque_limit (the acceleration "
                         "limit is torque_limit / inertia)")
    J = _inertia(inertia, e)
    if e is None:
        return tau / J, J
    return tau / float(np.max(np.abs(J @ e))), J


# --------------------------------------------------------------------------------------------
# input shapers
# --------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Shaper:
    """An input shaper: a unit-sum sequence of impulses A_i at times t_i (t_0 = 0).

    Convolving a command with it (:func:`shaped`) delays it by ``duration`` at most and cancels
    the residual vibration of the modes it was designed for.

    Attributes
    ----------
    amplitudes : ndarray, shape (n,)
        Positive impulse amplitudes, sum 1.
    times : ndarray, shape (n,), s
        Increasing impulse times, the first 0.
    modes : tuple of (float, float)
        (frequency [rad/s], damping ratio) of each mode the shaper was designed for.
    kind : str
        ``"zv"``, ``"zvd"`` or ``"convolved"`` (several modes).
    """

    amplitudes: np.ndarray
    times: np.ndarray
    modes: tuple = ()
    kind: str = "zv"

    def __post_init__(self):
        try:
            A = np.asarray(self.amplitudes, dtype=float).reshape(-1)
            t = np.asarray(self.times, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise TypeError("amplitudes and times must be real arrays") from None
        if A.size == 0 or A.shape != t.shape:
            raise ValueError(f"amplitudes and times must be non-empty and of one length; got "
                             f"{A.size} amplitudes and {t.size} times")
        if not (np.all(np.isfinite(A)) and np.all(A > 0)
                and abs(A.sum() - 1.0) <= 1e-12 * A.size):
            raise ValueError("amplitudes must be positive and sum to 1 (a unit-gain shaper); got "
                             f"{np.array2string(A[:6], precision=6)}")
        if not (np.all(np.isfinite(t)) and t[0] == 0.0 and np.all(np.diff(t) >= 0)):
            raise ValueError("times must be finite and non-decreasing from 0 [s]; got "
                             f"{np.array2string(t[:6], precision=6)}")
        for name, value in (("amplitudes", A), ("times", t)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @property
    def duration(self) -> float:
        """Time of the last impulse [s]: what the shaper adds to a profile's duration."""
        return float(self.times[-1])

    def convolve(self, other: "Shaper") -> "Shaper":
        """The shaper of both (their impulse sequences convolved): cancels both's modes."""
        if not isinstance(other, Shaper):
            raise TypeError(f"other must be a Shaper; got {type(other).__name__}")
        A = np.outer(self.amplitudes, other.amplitudes).reshape(-1)
        t = np.add.outer(self.times, other.times).reshape(-1)
        order = np.argsort(t, kind="stable")
        return Shaper(A[order], t[order], self.modes + other.modes, "convolved")

    def residual_vibration(self, frequency, damping: float = 0.0) -> np.ndarray:
        """Residual vibration of a mode after the shaper, as a fraction of an unshaped impulse's.

        V = e^(-zeta w t_n) |sum_i A_i e^(zeta w t_i) e^(j w_d t_i)|, w_d = w sqrt(1 - zeta^2)
        (Singer & Seering 1990), computed as |sum_i A_i e^(-zeta w (t_n - t_i)) e^(j w_d t_i)|
        (no overflow). The residual vibration of a shaped profile is that of its base times V.

        Parameters
        ----------
        frequency : float or array, rad/s
            Natural frequency w of the mode (positive).
        damping : float
            Damping ratio zeta in [0, 1).

        Returns
        -------
        ndarray, shape np.shape(frequency)
        """
        if isinstance(frequency, (str, bytes, bool)) or np.iscomplexobj(frequency):
            raise TypeError(f"frequency must be real [rad/s]; got {type(frequency).__name__}")
        try:
            w = np.asarray(frequency, dtype=float)
        except (TypeError, ValueError):
            raise TypeError(f"frequency must be real [rad/s]; got "
                            f"{type(frequency).__name__}") from None
        if not (np.all(np.isfinite(w)) and np.all(w > 0)):
            raise ValueError("frequency must be positive and finite [rad/s]")
        zeta = _damping(damping)
        if np.max(w, initial=0.0) > 1e15 / max(self.duration, 1e-300):
            raise ValueError(f"frequency up to {np.max(w):.3g} rad/s over the shaper's "
                             f"{self.duration:.3g} s is beyond 1e15 rad of phase (lost to "
                             "round-off)")
        wd = w * math.sqrt(1.0 - zeta * zeta)
        t = self.times
        decay = np.exp(-zeta * w[..., None] * (t[-1] - t))
        phase = np.exp(1j * wd[..., None] * t)
        return np.abs(np.sum(self.amplitudes * decay * phase, axis=-1))

    def insensitivity(self, frequency: float, damping: float = 0.0, *,
                      tolerance: float = 0.05) -> tuple[float, float]:
        """Frequency band around ``frequency`` in which the residual vibration stays at or below
        ``tolerance``: (lower, upper) as ratios w / frequency, found by bisection on
        :meth:`residual_vibration` from the nominal frequency outwards (to 1e-12).

        For an undamped ZVD shaper V = cos^2(pi w / (2 w_n)), so the band is
        1 -+ (2 / pi) asin(sqrt(tolerance)): +-14.4 % at 5 %; for ZV, V = |cos(pi w / (2 w_n))|,
        +-3.2 % at 5 %.
        """
        w0 = _positive(frequency, "frequency", "rad/s")
        tol = _number(tolerance, "tolerance", "1")
        if not 0 < tol < 1:
            raise ValueError(f"tolerance must be in (0, 1) [fraction of the unshaped vibration]; "
                             f"got {tol:.6g}")
        zeta = _damping(damping)
        if w0 * self.duration > 1e14:
            raise ValueError(f"frequency {w0:.3g} rad/s over the shaper's {self.duration:.3g} s "
                             "is beyond 1e14 rad of phase (lost to round-off)")

        def excess(ratio):
            return float(self.residual_vibration(w0 * ratio, zeta)) - tol

        if excess(1.0) > 0:
            return 1.0, 1.0
        out = []
        for step in (-1.0, 1.0):
            inner, outer = 1.0, 1.0
            # march outwards by 1 % until the tolerance is exceeded, then bisect
            for _ in range(10_000):
                nxt = outer + step * 0.01
                if nxt <= 0 or excess(nxt) > 0:
                    break
                inner = outer = nxt
            outer = max(outer + step * 0.01, 1e-12)
            for _ in range(200):
                mid = 0.5 * (inner + outer)
                if excess(mid) > 0:
                    outer = mid
                else:
                    inner = mid
                if abs(outer - inner) <= 1e-12:
                    break
            out.append(inner)
        return out[0], out[1]


def _damping(value) -> float:
    zeta = _number(value, "damping", "1")
    if not (math.isfinite(zeta) and 0 <= zeta < 1):
        raise ValueError(f"damping must be a damping ratio in [0, 1); got {zeta:.6g}")
    return zeta


def zv_shaper(frequency: float, damping: float = 0.0) -> Shaper:
    """Zero-vibration (ZV) shaper of a mode: amplitudes [1, K] / (1 + K) at [0, pi / w_d],
    K = exp(-zeta pi / sqrt(1 - zeta^2)), w_d = w sqrt(1 - zeta^2).

    Cancels the mode's residual vibration exactly at its frequency; sensitive to frequency error
    (5 % residual at +-3.2 % error, undamped).

    Parameters
    ----------
    frequency : float, rad/s
        Natural frequency of the mode.
    damping : float
        Its damping ratio, in [0, 1).

    References
    ----------
    N. C. Singer, W. P. Seering, J. Dyn. Sys. Meas. Control 112(1), 1990.
    """
    w = _positive(frequency, "frequency", "rad/s")
    zeta = _damping(damping)
    root = math.sqrt(1.0 - zeta * zeta)
    K = math.exp(-zeta * math.pi / root)
    half = math.pi / (w * root)
    if not (math.isfinite(half) and half > 0):
        raise ValueError(f"frequency {w:.6g} rad/s gives a half period of {half:.6g} s, outside "
                         "the floating-point range")
    return Shaper(np.array([1.0, K]) / (1.0 + K), np.array([0.0, half]), ((w, zeta),), "zv")


def zvd_shaper(frequency: float, damping: float = 0.0) -> Shaper:
    """Zero-vibration-and-derivative (ZVD) shaper: amplitudes [1, 2K, K^2] / (1 + K)^2 at
    [0, pi / w_d, 2 pi / w_d] (the ZV shaper convolved with itself).

    Zero residual vibration and zero slope of it in frequency at the mode: residual at most 5 %
    for a frequency error of +-14.4 % (undamped, V = cos^2(pi w / (2 w_n))), at the price of one
    more half period of delay. Parameters as :func:`zv_shaper`.

    References
    ----------
    N. C. Singer, W. P. Seering, J. Dyn. Sys. Meas. Control 112(1), 1990.
    """
    zv = zv_shaper(frequency, damping)
    out = zv.convolve(zv)
    # the convolution's two middle impulses coincide: merge them (times 0, T/2, T)
    return Shaper(np.array([out.amplitudes[0], out.amplitudes[1] + out.amplitudes[2],
                            out.amplitudes[3]]),
                  np.array([0.0, zv.times[1], 2.0 * zv.times[1]]), zv.modes, "zvd")


def mode_shaper(modes, *, kind: str = "zvd") -> Shaper:
    """A shaper for several modes: the convolution of one shaper per mode.

    Parameters
    ----------
    modes : sequence of FlexibleMode or of (frequency [rad/s], damping ratio)
        The modes to cancel, e.g. ``controllers.flexible_modes(design_plant)[:2]``.
    kind : {"zv", "zvd"}
        The shaper of each mode.
    """
    if not isinstance(kind, str) or kind not in SHAPER_KINDS:
        raise ValueError(f"kind must be one of {SHAPER_KINDS}; got {str(kind)[:40]!r}")
    if isinstance(modes, (str, bytes)) or not isinstance(modes, Sequence) or not modes:
        raise ValueError("modes must be a non-empty sequence of FlexibleMode or (frequency "
                         "[rad/s], damping ratio) pairs")
    build = zv_shaper if kind == "zv" else zvd_shaper
    shaper = None
    for i, mode in enumerate(modes):
        if hasattr(mode, "frequency") and hasattr(mode, "damping_ratio"):
            w, zeta = mode.frequency, mode.damping_ratio
        else:
            try:
                w, zeta = mode
            except (TypeError, ValueError):
                raise ValueError(f"modes[{i}] must be a FlexibleMode or a (frequency [rad/s], "
                                 f"damping ratio) pair; got {str(mode)[:60]}") from None
        one = build(w, zeta)
        shaper = one if shaper is None else shaper.convolve(one)
    if len(modes) == 1:
        return shaper
    return Shaper(shaper.amplitudes, shaper.times, shaper.modes, "convolved")


# --------------------------------------------------------------------------------------------
# the profile
# --------------------------------------------------------------------------------------------
def _poly(c: np.ndarray, x: np.ndarray, derivative: int) -> np.ndarray:
    """d-th derivative of c0 + c1 x + c2 x^2 + c3 x^3 (rows of c) at x, by Horner."""
    if derivative == 0:
        return c[:, 0] + x * (c[:, 1] + x * (c[:, 2] + x * c[:, 3]))
    if derivative == 1:
        return c[:, 1] + x * (2.0 * c[:, 2] + x * 3.0 * c[:, 3])
    if derivative == 2:
        return 2.0 * c[:, 2] + 6.0 * x * c[:, 3]
    if derivative == 3:
        return 6.0 * c[:, 3]
    return np.zeros_like(x)


def _derivative_coefficients(c: np.ndarray, d: int) -> np.ndarray:
    """Coefficients (K, 4) of the d-th derivative of the cubic pieces c (K, 4)."""
    out = c.copy()
    for _ in range(d):
        out = np.column_stack([out[:, 1], 2.0 * out[:, 2], 3.0 * out[:, 3],
                               np.zeros(out.shape[0])])
    return out


def _piece_max_abs(c: np.ndarray, lengths: np.ndarray) -> float:
    """max over every piece k of max_{0 <= x <= lengths[k]} |c_k(x)| (cubics): the ends and the
    real critical points inside."""
    best = 0.0
    if c.size == 0:
        return best
    ends = np.concatenate([np.abs(c[:, 0]), np.abs(_poly(c, lengths, 0))])
    best = float(ends.max())
    for k in range(c.shape[0]):
        # critical points: c1 + 2 c2 x + 3 c3 x^2 = 0
        roots = np.roots([3.0 * c[k, 3], 2.0 * c[k, 2], c[k, 1]]) if np.any(c[k, 1:]) else []
        for r in np.atleast_1d(roots):
            if abs(r.imag) <= 1e-12 * max(1.0, abs(r.real)) and 0 < r.real < lengths[k]:
                x = np.array([r.real])
                best = max(best, float(abs(_poly(c[k:k + 1], x, 0)[0])))
    return best


class Profile:
    """A rest-to-rest slew reference (see the module docstring); build one with
    :func:`step_reference`, :func:`bang_coast_bang`, :func:`jerk_limited`, :func:`shaped` or
    :func:`reference_profile`.

    The path s(t) [rad] is piecewise cubic: on [breakpoints[k], breakpoints[k + 1]),
    s = c0 + c1 x + c2 x^2 + c3 x^3 with x = t - breakpoints[k] and c = coefficients[k];
    s = 0 before 0 and s = angle from ``end_time`` on.

    Attributes
    ----------
    kind : str
        One of PROFILE_KINDS.
    angle : float, rad
        Slew angle (signed).
    axis : ndarray (3,) or None
        Unit slew axis (hub axes) of a three-axis profile; None for a planar one.
    end_time : float, s
        End of the manoeuvre: rest at the target from then on.
    breakpoints : ndarray, shape (K + 1,), s
    coefficients : ndarray, shape (K, 4)
    shaper : Shaper or None
        The shaper of a "shaped" profile.
    base : Profile or None
        The profile a "shaped" one was made from.
    """

    def __init__(self, kind: str, angle: float, breakpoints, coefficients, *, axis=None,
                 shaper: Shaper | None = None, base: "Profile | None" = None):
        if not isinstance(kind, str) or kind not in PROFILE_KINDS:
            raise ValueError(f"kind must be one of {PROFILE_KINDS}; got {str(kind)[:40]!r}")
        self.kind = kind
        self.angle = _angle(angle)
        self.axis = _unit_axis(axis)
        self.breakpoints = _times(breakpoints, "breakpoints").reshape(-1)
        try:
            self.coefficients = np.asarray(coefficients, dtype=float).reshape(-1, 4)
        except (TypeError, ValueError):
            raise ValueError("coefficients must be real, shape (K, 4) (cubic pieces)") from None
        if (self.breakpoints.size != self.coefficients.shape[0] + 1
                or self.breakpoints[0] != 0.0 or np.any(np.diff(self.breakpoints) <= 0)
                or not np.all(np.isfinite(self.coefficients))):
            raise ValueError("breakpoints must increase from 0 [s], one more than the finite "
                             f"rows of coefficients (K, 4); got {self.breakpoints.size} "
                             f"breakpoints and {self.coefficients.shape[0]} rows")
        if shaper is not None and not isinstance(shaper, Shaper):
            raise TypeError(f"shaper must be a Shaper; got {type(shaper).__name__}")
        if base is not None and not isinstance(base, Profile):
            raise TypeError(f"base must be a Profile; got {type(base).__name__}")
        for array in (self.breakpoints, self.coefficients):
            array.setflags(write=False)
        if self.axis is not None:
            self.axis.setflags(write=False)
        self.shaper = shaper
        self.base = base

    # -- the path --------------------------------------------------------------------------
    @property
    def end_time(self) -> float:
        """End of the manoeuvre [s]."""
        return float(self.breakpoints[-1])

    @property
    def three_axis(self) -> bool:
        """True for a three-axis profile (an axis was given)."""
        return self.axis is not None

    def path(self, t, derivative: int = 0) -> np.ndarray:
        """s^(d)(t): the angle [rad] (d = 0) along the axis, its rate [rad/s] (1), acceleration
        [rad/s^2] (2) or jerk [rad/s^3] (3; 0 where the acceleration jumps), same shape as t."""
        t = _times(t)
        if isinstance(derivative, bool) or derivative not in (0, 1, 2, 3):
            raise ValueError(f"derivative must be 0, 1, 2 or 3; got {str(derivative)[:20]}")
        flat = t.reshape(-1)
        k = np.searchsorted(self.breakpoints, flat, side="right") - 1
        inside = (k >= 0) & (k < self.coefficients.shape[0])
        out = np.zeros(flat.size)
        if derivative == 0:
            out[k >= self.coefficients.shape[0]] = self.angle
        ki = k[inside]
        out[inside] = _poly(self.coefficients[ki], flat[inside] - self.breakpoints[ki],
                            derivative)
        return out.reshape(t.shape)

    def _vector(self, values: np.ndarray) -> np.ndarray:
        return values if self.axis is None else np.multiply.outer(self.axis, values)

    def theta_ref(self, t) -> np.ndarray:
        """Attitude reference [rad]: shape of t (planar), (3,) + shape of t (three axes)."""
        return self._vector(self.path(t, 0))

    def omega_ref(self, t) -> np.ndarray:
        """Rate reference [rad/s], shaped as :meth:`theta_ref`."""
        return self._vector(self.path(t, 1))

    def alpha_ref(self, t) -> np.ndarray:
        """Acceleration reference [rad/s^2], shaped as :meth:`theta_ref`."""
        return self._vector(self.path(t, 2))

    def torque_ff(self, t, inertia, *, gyroscopic: bool = True) -> np.ndarray:
        """Feedforward torque [N*m]: J alpha_ref (planar), J alpha_ref + omega_ref x J omega_ref
        (three axes; without the second term if ``gyroscopic`` is False), shaped as
        :meth:`theta_ref`."""
        J = _inertia(inertia, self.axis)
        gyroscopic = _flag(gyroscopic, "gyroscopic")
        if self.axis is None:
            return J * self.path(t, 2)
        e = self.axis
        out = np.multiply.outer(J @ e, self.path(t, 2))
        if gyroscopic:
            out = out + np.multiply.outer(np.cross(e, J @ e), self.path(t, 1) ** 2)
        return out

    def references(self, t, inertia=None, *, gyroscopic: bool = True) -> dict[str, np.ndarray]:
        """The controller's reference inputs sampled at t, by signal name.

        Returns
        -------
        dict of str to ndarray
            ``theta_ref``, ``omega_ref`` and, with an inertia, ``torque_ff`` (three axes:
            ``theta_ref_x`` ... ``torque_ff_z``), each of the shape of t.
        """
        t = _times(t)
        _flag(gyroscopic, "gyroscopic")
        signals = [(THETA_REF, self.theta_ref(t)), (OMEGA_REF, self.omega_ref(t))]
        if inertia is not None:
            signals.append((TORQUE_FF, self.torque_ff(t, inertia, gyroscopic=gyroscopic)))
        out = {}
        for name, values in signals:
            if self.axis is None:
                out[name] = values
            else:
                out.update({f"{name}_{a}": values[i] for i, a in enumerate(AXES)})
        return out

    # -- peaks -----------------------------------------------------------------------------
    def _lengths(self) -> np.ndarray:
        return np.diff(self.breakpoints)

    def _peak(self, d: int) -> float:
        return _piece_max_abs(_derivative_coefficients(self.coefficients, d), self._lengths())

    def _jumps(self, d: int) -> np.ndarray:
        """|jump| of s^(d) at each breakpoint (the first and last included: from/to rest)."""
        c = _derivative_coefficients(self.coefficients, d)
        left = np.concatenate([[0.0], _poly(c, self._lengths(), 0)])
        right = np.concatenate([c[:, 0], [0.0 if d > 0 else self.angle]])
        if d == 0:
            left[0] = 0.0
        return np.abs(right - left)

    @property
    def peak_rate(self) -> float:
        """max |s'| [rad/s] (exact)."""
        return self._peak(1)

    @property
    def peak_acceleration(self) -> float:
        """max |s''| [rad/s^2] (exact)."""
        return self._peak(2)

    @property
    def peak_jerk(self) -> float:
        """max |s'''| [rad/s^3] (exact); inf for a piecewise-constant acceleration (order 2:
        bang-coast-bang, shaped or not), whose jumps are impulses of jerk."""
        if self.order == 2 and self.peak_acceleration > 0:
            return math.inf
        return self._peak(3)

    def peak_torque(self, inertia, *, gyroscopic: bool = True) -> float:
        """max over t (and hub axes) of |torque_ff| [N*m], exact for the piecewise-polynomial
        path (planar: J max |s''|)."""
        J = _inertia(inertia, self.axis)
        gyroscopic = _flag(gyroscopic, "gyroscopic")
        if self.axis is None:
            return J * self.peak_acceleration
        b, g = J @ self.axis, np.cross(self.axis, J @ self.axis)
        c2 = _derivative_coefficients(self.coefficients, 2)
        c1 = _derivative_coefficients(self.coefficients, 1)
        best = 0.0
        for i in range(3):
            # b_i s'' + g_i s'^2: s'' cubic-free (degree <= 1), s'^2 degree <= 4; sampled at the
            # ends and the critical points of each piece
            for k in range(c1.shape[0]):
                L = self._lengths()[k]
                p1 = np.polynomial.Polynomial(c1[k])
                p = b[i] * np.polynomial.Polynomial(c2[k]) + (g[i] * p1 * p1 if gyroscopic
                                                              else 0.0)
                xs = [0.0, L] + [r.real for r in np.atleast_1d(p.deriv().roots())
                                 if abs(r.imag) <= 1e-12 * max(1.0, abs(r)) and 0 < r.real < L]
                best = max(best, float(np.max(np.abs(p(np.array(xs))))))
        return best

    # -- sampling --------------------------------------------------------------------------
    def hold_error(self, dt: float, *, hold: str = "linear", inertia=None,
                   norm: str = "sup") -> dict[str, float]:
        """Bound on the difference between each reference signal and what a simulator sees of
        its samples on the grid 0, dt, 2 dt, ...

        Per signal f (theta_ref, omega_ref, torque_ff: s, s', s'' scaled by |e_i|, J or
        |(J e)_i|; the gyroscopic torque is not included):

        hold="linear" (linear interpolation between samples)
            sup: dt^2 / 8 max |f''| + max over breakpoints of (|jump of f| + dt / 4 |jump of
            f'|, the latter only off the grid); L1: dt^2 / 12 max |f''| end_time + sum of
            dt / 2 |jump of f| + dt^2 / 8 |jump of f'| (off the grid).
        hold="zero" (held from each sample)
            sup: dt max |f'| + max |jump of f| off the grid; L1: dt / 2 max |f'| end_time + sum
            of dt |jump of f| off the grid.

        A breakpoint counts as on the grid within 1e-9 dt. The "step" profile's cycloid has no
        breakpoint inside and max |s''| = 2 pi angle / T^2.

        Parameters
        ----------
        dt : float, s
        hold : {"linear", "zero"}
        inertia : float or (3, 3) array, kg*m^2, optional
            Adds ``torque_ff``.
        norm : {"sup", "integral"}
            sup [signal unit] or L1 [signal unit * s].

        Returns
        -------
        dict of str to float
            By signal name, as :meth:`references` names them.
        """
        dt = _positive(dt, "dt", "s")
        if not isinstance(hold, str) or hold not in ("linear", "zero"):
            raise ValueError(f"hold must be 'linear' or 'zero'; got {str(hold)[:40]!r}")
        if norm not in ("sup", "integral"):
            raise ValueError(f"norm must be 'sup' or 'integral'; got {str(norm)[:40]!r}")
        if dt > self.end_time:
            raise ValueError(f"dt must be at most the profile's end time {self.end_time:.6g} s; "
                             f"got {dt:.6g}")
        with np.errstate(over="ignore", invalid="ignore"):
            position = self.breakpoints / dt
            # beyond 1e15 steps the grid cannot be told apart: off it (the larger bound)
            off_grid = ~(np.abs(position - np.round(position)) <= 1e-9) | (position > 1e15)
        errors = [self._path_hold_error(d, dt, hold, norm, off_grid) for d in range(3)]
        scales = [np.ones(1) if self.axis is None else np.abs(self.axis)] * 2
        names = [THETA_REF, OMEGA_REF]
        if inertia is not None:
            J = _inertia(inertia, self.axis)
            scales.append(np.array([J]) if self.axis is None else np.abs(J @ self.axis))
            names.append(TORQUE_FF)
        out = {}
        for name, scale, error in zip(names, scales, errors):
            if self.axis is None:
                out[name] = float(scale[0] * error)
            else:
                out.update({f"{name}_{a}": float(scale[i] * error) for i, a in enumerate(AXES)})
        return out

    def _path_hold_error(self, d: int, dt: float, hold: str, norm: str, off_grid) -> float:
        jump = self._jumps(d)
        kink = self._jumps(d + 1)
        second = self._peak(d + 2) if d + 2 <= 3 else 0.0
        first = self._peak(d + 1) if d + 1 <= 3 else 0.0
        T = self.end_time
        if hold == "linear":
            if norm == "sup":
                return (dt * dt / 8.0 * second
                        + float(np.max(jump + np.where(off_grid, dt / 4.0 * kink, 0.0))))
            return (dt * dt / 12.0 * second * T + float(np.sum(dt / 2.0 * jump))
                    + float(np.sum(np.where(off_grid, dt * dt / 8.0 * kink, 0.0))))
        if norm == "sup":
            return dt * first + float(np.max(np.where(off_grid, jump, 0.0)))
        return dt / 2.0 * first * T + float(np.sum(np.where(off_grid, dt * jump, 0.0)))

    # -- exact generator ---------------------------------------------------------------------
    @property
    def order(self) -> int:
        """Degree of the path's pieces: 2 (piecewise-constant acceleration) or 3
        (piecewise-constant jerk)."""
        return 3 if np.any(self.coefficients[:, 3] != 0.0) else 2

    def generator(self, inertia=None) -> control.StateSpace:
        """The reference generator: a chain of ``order`` integrators driven by the path's
        highest derivative, with the reference signals as outputs.

        Input ``'profile_input'``: s'' [rad/s^2] (order 2) or s''' [rad/s^3] (order 3), piecewise
        constant (:meth:`generator_input`). States s, s' (, s''). Outputs as
        :meth:`references` (theta_ref..., omega_ref..., and with an inertia torque_ff... = J e
        s'', the gyroscopic term left out: it is not linear in the state). Driven with a
        zero-order hold on a grid through every breakpoint it reproduces the profile exactly.
        """
        n = self.order
        A = np.diag(np.ones(n - 1), 1)
        B = np.zeros((n, 1))
        B[-1, 0] = 1.0
        rows, D_rows, names = [], [], []
        e = np.ones(1) if self.axis is None else self.axis
        blocks = [(THETA_REF, np.eye(n)[0], 0.0), (OMEGA_REF, np.eye(n)[1], 0.0)]
        if inertia is not None:
            J = _inertia(inertia, self.axis)
            b = np.array([J]) if self.axis is None else J @ self.axis
            accel = (np.eye(n)[2], 0.0) if n == 3 else (np.zeros(n), 1.0)
            blocks.append((TORQUE_FF, accel[0], accel[1]))
        for name, row, feed in blocks:
            scale = b if name == TORQUE_FF else e
            for i in range(scale.size):
                rows.append(scale[i] * row)
                D_rows.append([scale[i] * feed])
                names.append(name if self.axis is None else f"{name}_{AXES[i]}")
        return control.ss(A, B, np.array(rows), np.array(D_rows), 0, inputs=["profile_input"],
                          outputs=names, states=[f"profile_s{i}" for i in range(n)],
                          name="profile")

    def driving(self, closed_loop: control.StateSpace, inertia=None) -> control.StateSpace:
        """The closed loop driven by this profile's :meth:`generator`: the generator's outputs
        feed the loop's inputs of the same names (theta_ref...; omega_ref... and torque_ff...
        where the loop has them), the loop's other inputs stay inputs.

        Returns
        -------
        control.StateSpace
            Inputs ``['profile_input']`` then the loop's non-reference inputs; the loop's
            outputs; states: the generator's, then the loop's. Simulate it with
            ``hold="zero"`` and :meth:`generator_input` (continuous loop): exact on a grid
            through every breakpoint.
        """
        if not isinstance(closed_loop, control.StateSpace) or closed_loop.isdtime(strict=True):
            raise TypeError("closed_loop must be a continuous control.StateSpace (from "
                            f"close_loop); got {type(closed_loop).__name__}")
        labels = list(closed_loop.input_labels)
        wants_ff = any(n.startswith(TORQUE_FF) for n in labels)
        if wants_ff and inertia is None:
            raise ValueError("inertia [kg*m^2] must be given: the closed loop has feedforward "
                             "torque inputs")
        gen = self.generator(inertia if wants_ff else None)
        fed = [n for n in gen.output_labels if n in labels]
        names = (THETA_REF,) if self.axis is None else tuple(f"{THETA_REF}_{a}" for a in AXES)
        missing = [n for n in names if n not in labels]
        if missing:
            raise ValueError(f"closed_loop must have the reference inputs {list(names)}; "
                             f"missing {missing}")
        others = [n for n in labels if n not in fed]
        i_fed = [labels.index(n) for n in fed]
        i_other = [labels.index(n) for n in others]
        rows = [list(gen.output_labels).index(n) for n in fed]
        Ag, Bg, Cg, Dg = gen.A, gen.B, gen.C[rows], gen.D[rows]
        Al, Bl, Cl, Dl = (np.asarray(M, dtype=float) for M in (closed_loop.A, closed_loop.B,
                                                               closed_loop.C, closed_loop.D))
        ng, nl = Ag.shape[0], Al.shape[0]
        A = np.block([[Ag, np.zeros((ng, nl))], [Bl[:, i_fed] @ Cg, Al]])
        B = np.block([[Bg, np.zeros((ng, len(i_other)))],
                      [Bl[:, i_fed] @ Dg, Bl[:, i_other]]])
        C = np.hstack([Dl[:, i_fed] @ Cg, Cl])
        D = np.hstack([Dl[:, i_fed] @ Dg, Dl[:, i_other]])
        return control.ss(A, B, C, D, 0, inputs=["profile_input"] + others,
                          outputs=list(closed_loop.output_labels),
                          states=list(gen.state_labels) + list(closed_loop.state_labels),
                          name="driven_loop")

    def generator_input(self, t) -> np.ndarray:
        """The generator's input for a zero-order hold on the grid t (evenly spaced): on each
        step [t_k, t_k+1) the mean of the piecewise-constant highest derivative over the step
        (the value itself where no breakpoint falls inside), the last sample's value held
        after. Exact when every breakpoint lies on the grid."""
        t = _times(t).reshape(-1)
        if t.size < 2 or np.any(np.diff(t) <= 0):
            raise ValueError("t must hold at least 2 increasing samples [s]")
        n = self.order
        # the integral of the top derivative: s^(n-1), continuous, evaluated exactly
        F = self.path(t, n - 1)
        mean = np.empty(t.size)
        mean[:-1] = np.diff(F) / np.diff(t)
        mean[-1] = self.path(t[-1:], n)[0]
        return mean


class _StepProfile(Profile):
    """The "step" reference: the cycloid fed to theta_ref alone (see :func:`step_reference`)."""

    def __init__(self, angle: float, duration: float, axis=None):
        super().__init__("step", angle, [0.0, duration], np.zeros((1, 4)), axis=axis)
        self.duration = duration

    def path(self, t, derivative: int = 0) -> np.ndarray:
        t = _times(t)
        if isinstance(derivative, bool) or derivative not in (0, 1, 2, 3):
            raise ValueError(f"derivative must be 0, 1, 2 or 3; got {str(derivative)[:20]}")
        if derivative == 0:
            return slew_profile(t, self.angle, self.duration)
        return np.zeros(t.shape)  # the reference feeds no rate or acceleration

    @property
    def order(self) -> int:
        return 0

    def generator(self, inertia=None):
        raise ValueError("the 'step' profile (a cycloid) has no polynomial generator; sample it "
                         "with references()")

    def generator_input(self, t):
        raise ValueError("the 'step' profile (a cycloid) has no polynomial generator; sample it "
                         "with references()")

    @property
    def peak_rate(self) -> float:
        """0: the reference feeds no rate (the cycloid's own rate peaks at 2 angle / T)."""
        return 0.0

    @property
    def peak_acceleration(self) -> float:
        return 0.0

    @property
    def peak_jerk(self) -> float:
        return 0.0

    def peak_torque(self, inertia, *, gyroscopic: bool = True) -> float:
        _inertia(inertia, self.axis)
        _flag(gyroscopic, "gyroscopic")
        return 0.0

    def _path_hold_error(self, d, dt, hold, norm, off_grid) -> float:
        if d > 0:
            return 0.0
        a, T = abs(self.angle), self.duration
        second, first = 2.0 * math.pi * a / T ** 2, 2.0 * a / T
        if hold == "linear":
            return dt * dt / 8.0 * second if norm == "sup" else dt * dt / 12.0 * second * T
        return dt * first if norm == "sup" else dt / 2.0 * first * T


# --------------------------------------------------------------------------------------------
# constructors
# --------------------------------------------------------------------------------------------
def _from_segments(kind: str, angle: float, segments, axis) -> Profile:
    """Profile of the sign of ``angle`` from segments (duration [s], acceleration at the start
    [rad/s^2], jerk [rad/s^3]) of a unit-signed path starting at rest; zero-length segments are
    dropped."""
    sign = math.copysign(1.0, angle)
    breaks, coefficients = [0.0], []
    s = v = 0.0
    for duration, a0, j in segments:
        if not duration > 0:
            continue
        coefficients.append([sign * s, sign * v, sign * a0 / 2.0, sign * j / 6.0])
        s += duration * (v + duration * (a0 / 2.0 + duration * j / 6.0))
        v += duration * (a0 + duration * j / 2.0)
        breaks.append(breaks[-1] + duration)
    return Profile(kind, angle, breaks, coefficients, axis=axis)


def step_reference(angle: float, duration: float, *, axis=None) -> Profile:
    """The "step" reference of flexsat's first designs: theta_ref = the cycloid of
    :func:`controllers.slew_profile` from 0 to ``angle`` in ``duration``, with omega_ref = 0
    and no feedforward torque (the controller sees the attitude reference only).

    Parameters
    ----------
    angle : float, rad
    duration : float, s
    axis : {'x', 'y', 'z'} or 3-vector, optional
        Three-axis slew axis (hub axes); None for a planar profile.
    """
    angle = _angle(angle)
    duration = _positive(duration, "duration", "s")
    return _StepProfile(angle, duration, _unit_axis(axis))


def _bcb_minimum_time(theta: float, A: float, W: float) -> float:
    """Shortest bang-coast-bang time [s] for |angle| theta under acceleration A and rate W."""
    if not math.isfinite(A):
        return 0.0 if not math.isfinite(W) else theta / W
    if not math.isfinite(W) or W * W >= theta * A:
        return 2.0 * math.sqrt(theta / A)          # bang-bang, peak rate sqrt(theta A)
    return theta / W + W / A                        # accelerate W/A, coast, decelerate


def _jerk_minimum_time(theta: float, A: float, W: float, Jm: float) -> float:
    """Shortest 7-segment time [s] for |angle| theta under acceleration A, rate W, jerk Jm
    (Biagiotti & Melchiorri 2008, sec. 3.4, rest to rest)."""
    if not math.isfinite(Jm):
        return _bcb_minimum_time(theta, A, W)
    if math.isfinite(W):
        if math.isfinite(A) and W * Jm >= A * A:
            tj, tc = A / Jm, W / A - A / Jm        # acceleration limit reached
        else:
            tj, tc = math.sqrt(W / Jm), 0.0
        S = 2.0 * tj + tc
        if theta >= W * S:                          # the rate limit is reached: coast
            return 2.0 * S + (theta / W - S)
    if math.isfinite(A):
        tj = A / Jm
        # w (w / A + A / Jm) = theta, in the form without cancellation
        w = 2.0 * theta / (A / Jm + math.hypot(A / Jm, math.sqrt(4.0 * theta / A)))
        tc = w / A - tj
        if tc >= 0.0:
            return 4.0 * tj + 2.0 * tc
    return 4.0 * (theta / (2.0 * Jm)) ** (1.0 / 3.0)  # triangular acceleration


def _limits_text(A, W, Jm, torque_limit, inertia) -> str:
    parts = []
    if torque_limit is not None:
        parts.append(f"torque_limit {torque_limit:.4g} N*m with inertia "
                     f"{inertia if np.ndim(inertia) == 0 else 'J'} kg*m^2 (acceleration "
                     f"{A:.4g} rad/s^2)")
    if math.isfinite(W):
        parts.append(f"rate_limit {W:.4g} rad/s")
    if math.isfinite(Jm):
        parts.append(f"jerk_limit {Jm:.4g} rad/s^3")
    return " and ".join(parts) if parts else "no limits"


def minimum_time(kind: str, angle: float, *, inertia=None, torque_limit=None, rate_limit=None,
                 jerk_limit=None, axis=None) -> float:
    """Shortest duration [s] of a "bang-coast-bang" or "smooth" (jerk-limited) profile under
    the limits (closed form; see :func:`bang_coast_bang`, :func:`jerk_limited`)."""
    if not isinstance(kind, str) or kind not in ("bang-coast-bang", "smooth"):
        raise ValueError(f"kind must be 'bang-coast-bang' or 'smooth'; got {str(kind)[:40]!r}")
    theta = abs(_angle(angle))
    e = _unit_axis(axis)
    A, _ = _acceleration_limit(torque_limit, inertia, e)
    W = _rate_limit(rate_limit)
    if kind == "bang-coast-bang":
        return _bcb_minimum_time(theta, A, W)
    return _jerk_minimum_time(theta, A, W, _limit(jerk_limit, "jerk_limit", "rad/s^3"))


def bang_coast_bang(angle: float, duration: float | None = None, *, inertia=None,
                    torque_limit: float | None = None, rate_limit: float | None = None,
                    axis=None) -> Profile:
    """Bang-coast-bang profile: acceleration a for t_a, coast at w = a t_a, deceleration -a.

    Parameters
    ----------
    angle : float, rad
        Slew angle (signed, non-zero, at most 2 pi).
    duration : float, s, optional
        Duration of the manoeuvre. Given: the profile ends at exactly ``duration`` with the least
        acceleration the rate limit allows, t_a = min(T/2, T - |angle| / rate_limit),
        a = |angle| / (t_a (T - t_a)). Omitted: the shortest profile under the limits, a = the
        acceleration limit, t_a = min(rate_limit / a, sqrt(|angle| / a)) (needs torque_limit).
    inertia : float or (3, 3) array, kg*m^2, optional
        The spacecraft's inertia (``controllers.rigid_body_inertia(plant)``): needed with
        torque_limit.
    torque_limit : float, N*m, optional
        Largest feedforward torque: planar |J a| <= torque_limit; three axes each component of
        J e a (the acceleration limit torque_limit / max_i |(J e)_i|).
    rate_limit : float, rad/s, optional
        Largest rate |w|.
    axis : {'x', 'y', 'z'} or 3-vector, optional
        Three-axis slew axis (hub axes); None for a planar profile.

    Raises
    ------
    ValueError
        Bad arguments (named), no duration and no torque_limit, or a duration shorter than the
        limits allow (the message gives the shortest time they allow).

    References
    ----------
    B. Wie, Space Vehicle Dynamics and Control, 2nd ed., AIAA 2008, sec. 7.3.
    """
    angle = _angle(angle)
    e = _unit_axis(axis)
    A, J = _acceleration_limit(torque_limit, inertia, e)
    W = _rate_limit(rate_limit)
    theta = abs(angle)
    t_min = _bcb_minimum_time(theta, A, W)
    if duration is None:
        if not math.isfinite(A):
            raise ValueError("bang_coast_bang needs a duration [s] or a torque_limit [N*m] (the "
                             "shortest profile accelerates at the limit)")
        T = t_min
    else:
        T = _positive(duration, "duration", "s")
        if T < t_min * (1.0 - _TIME_RTOL) or (not math.isfinite(A) and T <= t_min):
            raise ValueError(
                f"bang_coast_bang: {_limits_text(A, W, math.inf, torque_limit, J)} cannot "
                f"complete the slew of {angle:.6g} rad in duration {T:.6g} s; the shortest time "
                f"they allow is {t_min:.6g} s" + (" (not reached: the rate limit alone needs "
                                                  "more than that)" if not math.isfinite(A)
                                                  else ""))
    ta = 0.5 * T if not math.isfinite(W) else min(0.5 * T, T - theta / W)
    with np.errstate(over="ignore"):
        a = theta / (ta * (T - ta)) if ta * (T - ta) > 0 else math.inf
    if not math.isfinite(a):
        raise ValueError(f"bang_coast_bang: duration {T:.6g} s is too short for the slew of "
                         f"{angle:.6g} rad: its acceleration leaves the floating-point range")
    if duration is None or T <= t_min:
        a = min(a, A)  # at the shortest time the limit itself (no round-off above it)
    coast = max(T - 2.0 * ta, 0.0)
    return _from_segments("bang-coast-bang", angle,
                          [(ta, a, 0.0), (coast, 0.0, 0.0), (ta, -a, 0.0)], e)


def jerk_limited(angle: float, duration: float | None = None, *, inertia=None,
                 torque_limit: float | None = None, rate_limit: float | None = None,
                 jerk_limit: float | None = None, axis=None) -> Profile:
    """The "smooth" profile: jerk-limited 7-segment ("double S") rest-to-rest profile.

    Jerk +j for t_j, 0 for t_c, -j for t_j (acceleration a = j t_j reached and left), coast,
    then the mirror image: a continuous trapezoidal acceleration, bounded jerk.

    Parameters
    ----------
    angle : float, rad
    duration : float, s, optional
        Given: the profile ends at exactly ``duration`` with the least peak jerk that the
        acceleration and rate limits allow (module docstring: accelerating phase
        S = min(T/2, T - |angle| / rate_limit), u = t_j + t_c = max(S/2, |angle| /
        (a_max (T - S))), j = |angle| / ((T - S) u t_j)); without active limits the
        triangular-acceleration profile, j = 32 |angle| / T^3. Omitted: the shortest profile
        under the limits (closed form; needs jerk_limit).
    inertia, torque_limit, rate_limit, axis
        As :func:`bang_coast_bang`.
    jerk_limit : float, rad/s^3, optional
        Largest |s'''|.

    Raises
    ------
    ValueError
        Bad arguments (named), no duration and no jerk_limit, or a duration shorter than the
        limits allow (the message gives the shortest time they allow).

    References
    ----------
    L. Biagiotti, C. Melchiorri, Trajectory Planning for Automatic Machines and Robots, Springer
    2008, sec. 3.4 (double-S trajectory).
    """
    angle = _angle(angle)
    e = _unit_axis(axis)
    A, J = _acceleration_limit(torque_limit, inertia, e)
    W = _rate_limit(rate_limit)
    Jm = _limit(jerk_limit, "jerk_limit", "rad/s^3")
    theta = abs(angle)
    t_min = _jerk_minimum_time(theta, A, W, Jm)
    if duration is None:
        if not math.isfinite(Jm):
            raise ValueError("jerk_limited needs a duration [s] or a jerk_limit [rad/s^3] (the "
                             "shortest profile runs at the limits)")
        T = t_min * (1.0 + 4.0 * _TIME_RTOL)
    else:
        T = _positive(duration, "duration", "s")

    def infeasible():
        return ValueError(
            f"jerk_limited: {_limits_text(A, W, Jm, torque_limit, J)} cannot complete the slew "
            f"of {angle:.6g} rad in duration {T:.6g} s; the shortest time they allow is "
            f"{t_min:.6g} s")

    if T < t_min * (1.0 - _TIME_RTOL):
        raise infeasible()
    S = 0.5 * T if not math.isfinite(W) else min(0.5 * T, T - theta / W)
    if not S > 0:
        raise infeasible()
    u = 0.5 * S if not math.isfinite(A) else max(0.5 * S, theta / (A * (T - S)))
    tj = S - u
    if not tj > 0:
        raise infeasible()
    j = theta / ((T - S) * u * tj)
    if j > Jm * (1.0 + 1e-9):
        raise infeasible()
    tc = max(u - tj, 0.0)
    coast = max(T - 2.0 * S, 0.0)
    a = j * tj
    segments = [(tj, 0.0, j), (tc, a, 0.0), (tj, a, -j), (coast, 0.0, 0.0),
                (tj, 0.0, -j), (tc, -a, 0.0), (tj, -a, j)]
    return _from_segments("smooth", angle, segments, e)


def shaped(base: Profile, shaper: Shaper) -> Profile:
    """A profile convolved with an input shaper: sum_i A_i base(t - t_i).

    The shaped path ends ``shaper.duration`` after the base; with positive amplitudes summing
    to 1 its peak rate, acceleration and jerk stay at or below the base's (every limit the base
    meets, the shaped profile meets). The residual vibration of a mode after the shaped
    profile is that after the base times :meth:`Shaper.residual_vibration`: zero at the
    shaper's modes.

    Parameters
    ----------
    base : Profile
        A piecewise-polynomial profile (not "step", whose cycloid is fed without rate).
    shaper : Shaper
    """
    if not isinstance(base, Profile):
        raise TypeError(f"base must be a Profile; got {type(base).__name__}")
    if not isinstance(shaper, Shaper):
        raise TypeError(f"shaper must be a Shaper; got {type(shaper).__name__}")
    if base.kind == "step":
        raise ValueError("base must be a 'bang-coast-bang', 'smooth' or 'shaped' profile; the "
                         "'step' reference feeds no rate or feedforward to shape")
    b, c = base.breakpoints, base.coefficients
    times = np.unique(np.concatenate([b + t for t in shaper.times]))
    # sums that coincide in exact arithmetic (a base breakpoint plus one impulse time, another
    # plus another) differ by round-off: one breakpoint for them, not a piece of length ~eps
    keep = np.concatenate([[True], np.diff(times) > 1e-12 * max(times[-1], 1.0)])
    times = times[keep]
    K = times.size - 1
    out = np.zeros((K, 4))
    starts = times[:-1]
    for A_i, t_i in zip(shaper.amplitudes, shaper.times):
        local = starts - t_i                      # base time at each new piece's start
        k = np.searchsorted(b, local, side="right") - 1
        # round-off of the union: a start within 1e-12 of a base breakpoint belongs to it
        near = np.searchsorted(b, local + 1e-12 * max(b[-1], 1.0), side="right") - 1
        k = np.where(near > k, near, k)
        after = k >= c.shape[0]
        inside = (k >= 0) & ~after
        ki = k[inside]
        d = local[inside] - b[ki]
        c0, c1, c2, c3 = (c[ki, i] for i in range(4))
        shifted = np.column_stack([c0 + d * (c1 + d * (c2 + d * c3)),
                                   c1 + d * (2.0 * c2 + 3.0 * d * c3),
                                   c2 + 3.0 * d * c3, c3])
        out[inside] += A_i * shifted
        out[after, 0] += A_i * base.angle
    return Profile("shaped", base.angle, times, out, axis=base.axis, shaper=shaper, base=base)


def reference_profile(kind: str, angle: float, duration: float | None = None, *,
                      inertia=None, torque_limit: float | None = None,
                      rate_limit: float | None = None, jerk_limit: float | None = None,
                      shaper: Shaper | None = None, base: str = "bang-coast-bang",
                      axis=None) -> Profile:
    """One profile by kind, for a scene's manoeuvre.

    Parameters
    ----------
    kind : {"step", "bang-coast-bang", "smooth", "shaped"}
    angle : float, rad
    duration : float, s, optional
        End of the manoeuvre (required for "step"); for "shaped" the whole shaped profile's
        (the base gets ``duration - shaper.duration``).
    inertia, torque_limit, rate_limit, jerk_limit, axis
        As :func:`bang_coast_bang` / :func:`jerk_limited`.
    shaper : Shaper
        Required for "shaped" (e.g. ``mode_shaper(flexible_modes(design_plant)[:1])``).
    base : {"bang-coast-bang", "smooth"}
        The shaped profile's base.
    """
    if not isinstance(kind, str) or kind not in PROFILE_KINDS:
        raise ValueError(f"kind must be one of {PROFILE_KINDS}; got {str(kind)[:40]!r}")
    if kind == "step":
        if duration is None:
            raise ValueError("duration [s] must be given for the 'step' profile")
        if any(v is not None for v in (torque_limit, rate_limit, jerk_limit, shaper)):
            raise ValueError("the 'step' profile takes no torque_limit, rate_limit, jerk_limit "
                             "or shaper (it is the cycloid of theta_ref alone)")
        return step_reference(angle, duration, axis=axis)
    if kind != "shaped" and shaper is not None:
        raise ValueError(f"shaper is for kind='shaped'; got kind={kind!r}")
    if kind == "bang-coast-bang" and jerk_limit is not None:
        raise ValueError("jerk_limit is for the 'smooth' profile (bang-coast-bang has "
                         "unbounded jerk)")
    if kind == "shaped":
        if not isinstance(shaper, Shaper):
            raise ValueError(f"shaper must be a Shaper for kind='shaped'; got "
                             f"{type(shaper).__name__}")
        if not isinstance(base, str) or base not in ("bang-coast-bang", "smooth"):
            raise ValueError(f"base must be 'bang-coast-bang' or 'smooth'; got "
                             f"{str(base)[:40]!r}")
        if base == "bang-coast-bang" and jerk_limit is not None:
            raise ValueError("jerk_limit is for base='smooth'")
        base_duration = None
        if duration is not None:
            T = _positive(duration, "duration", "s")
            base_duration = T - shaper.duration
            if not base_duration > 0:
                raise ValueError(f"duration {T:.6g} s is shorter than the shaper alone "
                                 f"({shaper.duration:.6g} s)")
        inner = reference_profile(base, angle, base_duration, inertia=inertia,
                                  torque_limit=torque_limit, rate_limit=rate_limit,
                                  jerk_limit=jerk_limit, axis=axis)
        return shaped(inner, shaper)
    if kind == "bang-coast-bang":
        return bang_coast_bang(angle, duration, inertia=inertia, torque_limit=torque_limit,
                               rate_limit=rate_limit, axis=axis)
    return jerk_limited(angle, duration, inertia=inertia, torque_limit=torque_limit,
                        rate_limit=rate_limit, jerk_limit=jerk_limit, axis=axis)
