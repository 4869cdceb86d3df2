r"""Reaction wheels: one wheel's limits and friction, a wheel set's torque distribution.

A reaction wheel is a rotor of spin inertia J_s spinning about a fixed axis g of the hub (a unit
vector in hub axes) at a speed Omega relative to the hub. Its motor torque spins the rotor and
reacts on the hub; friction between rotor and hub does the same. With the wheel torque w defined
as the torque the wheel applies to the hub about g (the sign of the hub torque it produces),

    w = m + c_v Omega + c_c sign(Omega),        J_s (Omega' + g . omega') = -w,

m the motor's share (the reaction of its torque on the rotor), c_v the viscous and c_c the
Coulomb friction coefficients (friction drags the hub along with the rotor). The wheel's
momentum is h = J_s Omega (relative to the hub, the quantity a wheel's momentum capacity
refers to); its absolute momentum along g, J_s (Omega + g . omega), changes at -w [1]_.

Limits (what :meth:`WheelSet.applied_torques` does, in this order, as Basilisk's
``reactionWheelStateEffector`` does [2]_):

1. torque: |m_i| <= torque_limit_i. ``saturation="scale"`` (the default) scales the whole vector
   of commanded wheel torques by the largest ratio |c_i| / torque_limit_i when it exceeds 1, so
   the hub torque keeps the commanded direction (shorter); ``"clip"`` clips each wheel alone
   (Basilisk's rule; the direction changes when several wheels saturate).
2. momentum (speed): a wheel at |h_i| >= momentum_limit_i whose motor torque would spin it
   further (m_i h_i <= 0) gets m_i = 0. Its speed limit is momentum_limit / spin_inertia.
3. friction: w_i = m_i + c_v Omega_i + c_c sign(Omega_i) (no stiction: sign(0) = 0).

Distribution: the hub torque command tau (per controlled axis) becomes the wheel torque commands
c = G^+ tau, G = [g_1 ... g_n] (3 x n, or 1 x 1 for the planar wheel), the minimum-norm
allocation (the Moore-Penrose pseudo-inverse): G c = tau exactly when the axes span the
controlled axes, with the least sum of squared wheel torques. A set whose axes do not span
(rank G < 3) is refused; a nearly coplanar set gets a warning (its torque about the weak axis
costs 1 / sigma_min(G) times more wheel torque). The redundant wheels' null-space momentum is
not managed (no momentum unloading, no speed biasing).

Neglected: the gyroscopic torque omega x h of the stored momentum on the hub (second order in
the small rates of the linear plant when the wheels start at rest; a bias momentum h_0 makes it
first order, omega x h_0, and it is not in the linear plant), motor dynamics, torque noise,
imbalance (jitter), power limits.

References
----------
.. [1] H. Schaub, J. L. Junkins, *Analytical Mechanics of Space Systems*, 4th ed., AIAA, 2018,
   sec. 4.5 (spacecraft with reaction wheels).
.. [2] Basilisk 2.12, ``reactionWheelStateEffector`` (``ConfigureRWRequests``: torque
   saturation u_max, speed saturation Omega_max when Omega u_cmd >= 0; friction
   f_C sign(Omega) + c_v Omega in the dynamics).
.. [3] F. L. Markley, J. L. Crassidis, *Fundamentals of Spacecraft Attitude Determination and
   Control*, Springer, 2014, sec. 7.2.1 (reaction wheel arrays, pseudo-inverse distribution).
"""
from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Sequence

import numpy as np

from .arguments import (check_inertia, describe, finite_vector, non_negative, optional_positive,
                        real_number)
from .profiles import minimum_time

__all__ = ["ReactionWheel", "WheelSet", "SATURATION_MODES", "MIN_SPAN_RATIO",
           "WEAK_SPAN_RATIO", "PLAUSIBLE_TORQUE_LIMIT", "shortest_slew_time",
           "check_slew_time"]

#: How a torque command beyond a wheel's limit is reduced (see the module docstring).
SATURATION_MODES = ("scale", "clip")
#: Spin axes span the controlled axes when sigma_min(G) / sigma_max(G) exceeds this.
MIN_SPAN_RATIO = 1e-6
#: Below this ratio sigma_min / sigma_max the set spans badly: a warning.
WEAK_SPAN_RATIO = 0.1
#: A torque limit above this [N m] is an unusual reaction wheel (a warning: mN m given?).
PLAUSIBLE_TORQUE_LIMIT = 10.0


@dataclasses.dataclass(frozen=True)
class ReactionWheel:
    """One reaction wheel: its limits, spin inertia and friction.

    Parameters
    ----------
    torque_limit : float or None, N*m
        Largest motor torque (positive); None: unlimited.
    momentum_limit : float or None, N*m*s
        Largest |h| = J_s |Omega| (positive); None: unlimited. With ``spin_inertia``, the
        speed limit is momentum_limit / spin_inertia [rad/s].
    spin_inertia : float or None, kg*m**2
        Rotor inertia J_s about its spin axis (not part of the plant's hub inertia). Needed for
        the wheel's speed and for viscous friction; without it the wheel's momentum is taken
        as its absolute momentum along its axis (J_s -> 0 at fixed momentum: the hub rate's
        share J_s g . omega left out).
    viscous_friction : float, N*m*s/rad
        c_v >= 0: friction torque c_v Omega (needs ``spin_inertia``).
    coulomb_friction : float, N*m
        c_c >= 0: friction torque c_c sign(Omega).
    initial_momentum : float, N*m*s
        h = J_s Omega at the start of a simulation (within the momentum limit).

    Raises
    ------
    TypeError
        A parameter that is not a real number.
    ValueError
        A limit or inertia that is not positive and finite, negative friction, viscous friction
        without a spin inertia, an initial momentum beyond the momentum limit.
    """

    torque_limit: float | None
    momentum_limit: float | None
    spin_inertia: float | None = None
    viscous_friction: float = 0.0
    coulomb_friction: float = 0.0
    initial_momentum: float = 0.0

    def __post_init__(self):
        checked = {
            "torque_limit": optional_positive(self.torque_limit, "torque_limit", "N*m"),
            "momentum_limit": optional_positive(self.momentum_limit, "momentum_limit",
                                                "N*m*s"),
            "spin_inertia": optional_positive(self.spin_inertia, "spin_inertia", "kg*m^2"),
            "viscous_friction": non_negative(self.viscous_friction, "viscous_friction",
                                             "N*m*s/rad"),
            "coulomb_friction": non_negative(self.coulomb_friction, "coulomb_friction", "N*m"),
            "initial_momentum": real_number(self.initial_momentum, "initial_momentum",
                                            "N*m*s"),
        }
        for name, value in checked.items():
            object.__setattr__(self, name, value)
        if not math.isfinite(self.initial_momentum):
            raise ValueError(f"initial_momentum must be finite [N*m*s]; got "
                             f"{describe(self.initial_momentum)}")
        if self.viscous_friction > 0 and self.spin_inertia is None:
            raise ValueError("viscous_friction needs spin_inertia [kg*m^2] (the friction is "
                             "c_v Omega, Omega = momentum / spin_inertia); got viscous_friction "
                             f"= {self.viscous_friction:.6g} N*m*s/rad and spin_inertia = None")
        if self.momentum_limit is not None and abs(self.initial_momentum) > self.momentum_limit:
            raise ValueError(f"initial_momentum must lie within the momentum limit +-"
                             f"{self.momentum_limit:.6g} [N*m*s]; got "
                             f"{self.initial_momentum:.6g}")
        if self.torque_limit is not None and self.torque_limit > PLAUSIBLE_TORQUE_LIMIT:
            warnings.warn(f"torque_limit = {self.torque_limit:.6g} N*m is large for a reaction "
                          f"wheel (they give 1e-4 to ~1 N*m): was it given in mN*m? The value "
                          "is used as N*m", UserWarning, stacklevel=3)

    @property
    def speed_limit(self) -> float | None:
        """momentum_limit / spin_inertia [rad/s] (None if either is None)."""
        if self.momentum_limit is None or self.spin_inertia is None:
            return None
        return self.momentum_limit / self.spin_inertia

    @property
    def has_friction(self) -> bool:
        """Whether any friction coefficient is non-zero."""
        return self.viscous_friction > 0 or self.coulomb_friction > 0


def _check_wheel(wheel, name: str) -> ReactionWheel:
    if not isinstance(wheel, ReactionWheel):
        raise TypeError(f"{name} must be a controllers.ReactionWheel; got "
                        f"{type(wheel).__name__} {describe(wheel)}")
    return wheel


class WheelSet:
    """Reaction wheels that produce the hub torque: their axes, limits and distribution.

    Parameters
    ----------
    wheels : ReactionWheel or sequence of ReactionWheel
        One wheel (planar loops) or several (three-axis loops).
    spin_axes : array_like, shape (n_wheels, 3), optional
        Spin axis of each wheel in hub axes (non-zero; normalised here). Omit for the planar
        set: one wheel about the plane's normal (+z), the axis the planar plant turns about.
    saturation : {"scale", "clip"}
        Torque saturation rule (see the module docstring): ``"scale"`` keeps the direction of
        the hub torque, ``"clip"`` clips each wheel alone.
    names : sequence of str, optional
        Wheel names for signal names (``<name>_torque``...). Default ``"wheel"`` for the planar
        wheel, ``"wheel_1"``, ``"wheel_2"``, ... otherwise.

    Attributes
    ----------
    wheels : tuple of ReactionWheel
    spin_axes : numpy.ndarray, shape (n_wheels, 3) or None (planar)
    distribution : numpy.ndarray, shape (n_axes, n_wheels)
        G: hub torque = G @ wheel torques (planar: [[1.0]]).
    allocation : numpy.ndarray, shape (n_wheels, n_axes)
        G^+, the minimum-norm distribution of a hub torque command to the wheels.
    saturation : str
    names : tuple of str

    Raises
    ------
    ValueError
        Spin axes that do not span the three hub axes (the message names the direction no wheel
        can produce torque about), a planar set of more than one wheel, bad shapes, unknown
        ``saturation``, names that are not distinct identifiers.

    Warns
    -----
    UserWarning
        Axes that span only weakly (sigma_min / sigma_max of G below WEAK_SPAN_RATIO).

    Examples
    --------
    >>> wheel = ReactionWheel(torque_limit=0.03, momentum_limit=1.0, spin_inertia=0.01)
    >>> planar = WheelSet(wheel)
    >>> pyramid = WheelSet.pyramid(wheel, math.radians(54.7356))
    """

    def __init__(self, wheels, spin_axes=None, *, saturation: str = "scale",
                 names: Sequence[str] | None = None) -> None:
        if isinstance(wheels, ReactionWheel):
            wheels = (wheels,)
        if isinstance(wheels, (str, bytes)) or not isinstance(wheels, Sequence):
            raise TypeError(f"wheels must be a ReactionWheel or a sequence of them; got "
                            f"{type(wheels).__name__} {describe(wheels)}")
        wheels = tuple(_check_wheel(w, f"wheels[{i}]") for i, w in enumerate(wheels))
        if not wheels:
            raise ValueError("wheels must hold at least one ReactionWheel; got none")
        if not isinstance(saturation, str) or saturation not in SATURATION_MODES:
            raise ValueError(f"saturation must be one of {SATURATION_MODES}; got "
                             f"{describe(saturation)}")
        n = len(wheels)
        if spin_axes is None:
            if n != 1:
                raise ValueError(f"spin_axes must be given for {n} wheels (shape ({n}, 3), hub "
                                 "axes); omit them only for the planar set of one wheel")
            G = np.ones((1, 1))
            axes = None
        else:
            axes = _unit_axes(spin_axes, n)
            G = axes.T.copy()
            _check_span(G)
        if names is None:
            names = ("wheel",) if axes is None else tuple(f"wheel_{i + 1}" for i in range(n))
        names = _check_names(names, n)
        self.wheels = wheels
        self.spin_axes = axes
        self.distribution = G
        self.allocation = np.linalg.pinv(G)
        self.saturation = saturation
        self.names = names
        self._torque_limits = np.array([math.inf if w.torque_limit is None else w.torque_limit
                                        for w in wheels])
        self._momentum_limits = np.array([math.inf if w.momentum_limit is None
                                          else w.momentum_limit for w in wheels])

    @classmethod
    def pyramid(cls, wheel: ReactionWheel, cant_angle: float, *, azimuth: float = 0.0,
                saturation: str = "scale", names: Sequence[str] | None = None) -> WheelSet:
        r"""Four identical wheels in a pyramid about the hub's +z axis.

        Wheel i (i = 0..3) spins about
        g_i = (sin(beta) cos(a_i), sin(beta) sin(a_i), cos(beta)), a_i = azimuth + i pi/2:
        ``cant_angle`` beta is the angle between each spin axis and the pyramid axis +z; then
        G G^T = diag(2 sin^2 beta, 2 sin^2 beta, 4 cos^2 beta). With beta = arccos(1/sqrt(3))
        = 54.7356 deg, G G^T = 4/3 I: the minimum-norm distribution needs the same wheel-torque
        norm, sqrt(3)/2, per unit hub torque about any axis. Per-wheel limits tau give the
        torque capacities 2 tau sin(beta) about x and y and 4 tau cos(beta) about z
        (:meth:`torque_capacity`), equal at tan(beta) = 2. beta = 0 or pi/2 puts every axis on
        z or in the xy plane, which does not span (refused).

        Parameters
        ----------
        wheel : ReactionWheel
            The wheel, used four times.
        cant_angle : float, rad
            beta, in (0, pi/2).
        azimuth : float, rad
            Azimuth of the first wheel from +x about +z.
        saturation, names
            As for :class:`WheelSet`.

        References
        ----------
        Markley & Crassidis (2014), sec. 7.2.1 (four-wheel pyramid).
        """
        _check_wheel(wheel, "wheel")
        beta = real_number(cant_angle, "cant_angle", "rad")
        if not (math.isfinite(beta) and 0.0 < beta < 0.5 * math.pi):
            raise ValueError(f"cant_angle must lie in (0, pi/2) [rad] (angle between each spin "
                             f"axis and the pyramid axis +z); got {describe(cant_angle)}"
                             + (" (degrees? give radians)" if math.isfinite(beta)
                                and 1.0 < beta < 90.0 else ""))
        a0 = real_number(azimuth, "azimuth", "rad")
        if not (math.isfinite(a0) and abs(a0) <= 2.0 * math.pi):
            raise ValueError(f"azimuth must be finite and within [-2 pi, 2 pi] [rad]; got "
                             f"{describe(azimuth)}")
        a = a0 + 0.5 * math.pi * np.arange(4)
        axes = np.column_stack([math.sin(beta) * np.cos(a), math.sin(beta) * np.sin(a),
                                np.full(4, math.cos(beta))])
        try:
            return cls((wheel,) * 4, axes, saturation=saturation, names=names)
        except ValueError as exc:
            if "spin_axes" not in str(exc):
                raise
            raise ValueError(f"cant_angle = {beta:.6g} rad puts the four spin axes too close to "
                             f"the pyramid axis or to its base plane: {exc}") from None

    @property
    def n_wheels(self) -> int:
        """Number of wheels."""
        return len(self.wheels)

    @property
    def n_axes(self) -> int:
        """Controlled axes: 1 (planar set) or 3."""
        return self.distribution.shape[0]

    @property
    def planar(self) -> bool:
        """True for the planar set (one wheel about the plane's normal)."""
        return self.spin_axes is None

    @property
    def torque_limits(self) -> np.ndarray:
        """Torque limit of each wheel [N*m] (inf: unlimited)."""
        return self._torque_limits.copy()

    @property
    def momentum_limits(self) -> np.ndarray:
        """Momentum limit of each wheel [N*m*s] (inf: unlimited)."""
        return self._momentum_limits.copy()

    @property
    def spin_inertias(self) -> np.ndarray:
        """Spin inertia of each wheel [kg*m**2] (0 where not given)."""
        return np.array([0.0 if w.spin_inertia is None else w.spin_inertia
                         for w in self.wheels])

    @property
    def has_friction(self) -> bool:
        """Whether any wheel has friction."""
        return any(w.has_friction for w in self.wheels)

    def _unit_direction(self, direction) -> np.ndarray:
        if self.planar:
            if direction is not None:
                raise ValueError(f"direction is for three-axis wheel sets; the planar wheel "
                                 f"acts about its one axis; got {describe(direction)}")
            return np.ones(1)
        if direction is None:
            raise ValueError("direction must be given for a three-axis wheel set: a non-zero "
                             "3-vector in hub axes")
        e = finite_vector(direction, "direction", "hub axes", 3)
        norm = float(np.linalg.norm(e))
        if norm == 0.0:
            raise ValueError("direction must be a non-zero 3-vector (hub axes); got zeros")
        return e / norm

    def torque_capacity(self, direction=None) -> float:
        """Largest hub torque [N*m] along a unit ``direction`` with every wheel within its
        torque limit, for the minimum-norm distribution: 1 / max_i |(G^+ e)_i| / limit_i
        (inf if unlimited). Planar: the wheel's limit (``direction`` omitted)."""
        a = self.allocation @ self._unit_direction(direction)
        return _capacity(a, self._torque_limits)

    def momentum_capacity(self, direction=None) -> float:
        """Largest momentum [N*m*s] the set stores along a unit ``direction`` from rest with
        every wheel within its momentum limit (minimum-norm distribution); planar: the
        wheel's limit."""
        a = self.allocation @ self._unit_direction(direction)
        return _capacity(a, self._momentum_limits)

    def applied_torques(self, command, momentum) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The wheels' torques on the hub for commanded wheel torques, at given momenta.

        Parameters
        ----------
        command : array_like, shape (n_wheels,) or (n_wheels, n_samples), N*m
            Commanded wheel torques c (the allocation G^+ tau of a hub torque command), one
            column per sample.
        momentum : array_like, same shape, N*m*s
            Each wheel's momentum h = J_s Omega.

        Returns
        -------
        applied : numpy.ndarray, N*m
            w = m + c_v Omega + c_c sign(Omega) (module docstring, steps 1-3).
        torque_saturated, momentum_saturated : numpy.ndarray of bool
            Wheels whose command exceeded their torque limit; wheels held at their momentum
            limit (motor torque set to zero).
        """
        c = _finite_array(command, "command", "N*m")
        h = _finite_array(momentum, "momentum", "N*m*s")
        if c.shape[:1] != (self.n_wheels,) or c.ndim > 2 or h.shape != c.shape:
            raise ValueError(f"command and momentum must have shape (n_wheels,) or (n_wheels, "
                             f"n_samples) with n_wheels = {self.n_wheels}; got {c.shape} and "
                             f"{h.shape}")
        column = (slice(None),) + (None,) * (c.ndim - 1)
        tau, hmax = self._torque_limits[column], self._momentum_limits[column]
        ratio = np.abs(c) / tau
        torque_saturated = ratio > 1.0
        if self.saturation == "scale":
            worst = np.maximum(ratio.max(axis=0), 1.0)
            m = c / worst
        else:
            m = np.clip(c, -tau, tau)
        momentum_saturated = (np.abs(h) >= hmax) & (m * h <= 0.0)
        m = np.where(momentum_saturated, 0.0, m)
        return m + self.friction_torques(h), torque_saturated, momentum_saturated

    def friction_torques(self, momentum) -> np.ndarray:
        """Friction torque of each wheel on the hub [N*m], c_v Omega + c_c sign(Omega), at
        momenta h = J_s Omega [N*m*s] (shape (n_wheels,) or (n_wheels, n_samples))."""
        h = _finite_array(momentum, "momentum", "N*m*s")
        if h.shape[:1] != (self.n_wheels,) or h.ndim > 2:
            raise ValueError(f"momentum must have shape (n_wheels,) or (n_wheels, n_samples) "
                             f"with n_wheels = {self.n_wheels} [N*m*s]; got {h.shape}")
        column = (slice(None),) + (None,) * (h.ndim - 1)
        cc = np.array([w.coulomb_friction for w in self.wheels])[column]
        cv = np.array([w.viscous_friction / w.spin_inertia if w.viscous_friction else 0.0
                       for w in self.wheels])[column]
        return cc * np.sign(h) + cv * h

    def __repr__(self) -> str:
        kind = "planar" if self.planar else f"{self.n_wheels} wheels"
        return f"WheelSet({kind}, saturation={self.saturation!r}, names={self.names})"


def _finite_array(value, name: str, unit: str) -> np.ndarray:
    """A float64 array of finite real numbers, or an error naming ``name``."""
    array = np.asarray(value) if not isinstance(value, np.ndarray) else value
    if array.dtype == object or array.dtype.kind not in "iuf" or array.dtype == bool:
        raise TypeError(f"{name} must be an array of real numbers [{unit}]; got "
                        f"{describe(value)}")
    array = array.astype(float, copy=False)
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite [{unit}]; got {describe(value)}")
    return array


def _capacity(a: np.ndarray, limits: np.ndarray) -> float:
    with np.errstate(divide="ignore"):
        worst = float(np.max(np.abs(a) / limits))
    return math.inf if worst == 0.0 else 1.0 / worst


def _unit_axes(spin_axes, n: int) -> np.ndarray:
    try:
        axes = np.asarray(spin_axes, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"spin_axes must be an array of real numbers, shape ({n}, 3) (hub "
                        f"axes); got {describe(spin_axes)}") from exc
    if axes.shape != (n, 3):
        raise ValueError(f"spin_axes must have shape (n_wheels, 3) = ({n}, 3) (one unit vector "
                         f"per wheel, hub axes); got shape {axes.shape}")
    if not np.all(np.isfinite(axes)):
        raise ValueError(f"spin_axes must be finite; got {describe(spin_axes)}")
    norms = np.linalg.norm(axes, axis=1)
    if np.any(norms == 0.0):
        i = int(np.argmin(norms))
        raise ValueError(f"spin_axes[{i}] must be a non-zero vector (hub axes); got zeros")
    return axes / norms[:, None]


def _check_span(G: np.ndarray) -> None:
    """Refuse axes that do not span 3-D; warn when they span weakly."""
    U, s, _ = np.linalg.svd(G)
    ratio = s[-1] / s[0] if s.size == 3 else 0.0
    if s.size < 3 or ratio < MIN_SPAN_RATIO:
        weak = U[:, -1]
        raise ValueError(
            f"spin_axes do not span the controlled axes (hub x, y, z): no wheel produces torque "
            f"about the direction {np.array2string(weak, precision=4)} (sigma_min / sigma_max "
            f"of the distribution matrix = {ratio:.3g}, need > {MIN_SPAN_RATIO:g}); give at "
            "least three wheels whose axes are not coplanar")
    if ratio < WEAK_SPAN_RATIO:
        warnings.warn(f"spin_axes span the hub axes weakly (sigma_min / sigma_max = "
                      f"{ratio:.3g}): a torque about {np.array2string(U[:, -1], precision=4)} "
                      f"needs {1.0 / s[-1]:.3g} times its size in wheel torque",
                      UserWarning, stacklevel=4)


def _check_names(names, n: int) -> tuple[str, ...]:
    if isinstance(names, str) or not isinstance(names, Sequence):
        raise TypeError(f"names must be a sequence of {n} strings; got {describe(names)}")
    names = tuple(names)
    if len(names) != n or not all(isinstance(s, str) and s.isidentifier() for s in names):
        raise ValueError(f"names must be {n} identifiers (letters, digits, '_'), one per wheel; "
                         f"got {describe(names)}")
    if len(set(names)) != n:
        raise ValueError(f"names must be distinct; got {describe(names)}")
    return names


def shortest_slew_time(wheels: WheelSet, angle: float, inertia, *, axis=None) -> float:
    r"""Shortest rest-to-rest slew time [s] the wheels' torque and momentum limits allow.

    An eigen-axis slew by ``angle`` about the unit axis e of a rigid body of inertia J needs the
    hub torque J e a for an acceleration a, and leaves the body with the momentum J e omega,
    which the wheels take from their initial momenta h_0 (minimum-norm distribution: each wheel
    h_0 - (G^+ J e)_i omega). With u = J e / |J e|, the wheels' limits bound the acceleration by
    a_m = (torque capacity along u) / |J e| (:meth:`WheelSet.torque_capacity`) and the rate by
    omega_m = (momentum room along u) / |J e|; the least time under both is the bang-coast-bang
    one [1]_ (:func:`.profiles.minimum_time`):

        t = 2 sqrt(|angle| / a_m)                   if |angle| <= omega_m^2 / a_m,
        t = |angle| / omega_m + omega_m / a_m        otherwise.

    Every profile under the same limits takes at least this long (a lower bound for the
    flexible spacecraft, whose appendages store part of the momentum on the way; friction,
    which the motor must also overcome, is left out).

    Parameters
    ----------
    wheels : WheelSet
    angle : float, rad
        Slew angle (non-zero).
    inertia : float or array_like (3, 3), kg*m**2
        The whole spacecraft's rigid-body inertia (``controllers.rigid_body_inertia(plant)``):
        about the planar axis, or the 3 x 3 tensor (hub axes) for a three-axis set.
    axis : array_like (3,), optional
        Three-axis sets: the slew's eigen-axis (hub axes), required.

    Returns
    -------
    float, s
        0 without limits; inf if the wheels can store no momentum in the needed direction.

    References
    ----------
    .. [1] B. Wie, *Space Vehicle Dynamics and Control*, 2nd ed., AIAA, 2008, sec. 7.3
       (rest-to-rest time-optimal manoeuvres with rate limits).
    """
    limits = _slew_limits(wheels, angle, inertia, axis)
    if limits["momentum_room"] <= 0.0:
        return math.inf
    A, W = limits["acceleration"], limits["rate"]
    # the bang-coast-bang time for acceleration A and rate W: a unit inertia makes the torque
    # limit the acceleration limit
    return minimum_time("bang-coast-bang", limits["angle"], inertia=1.0,
                        torque_limit=A if math.isfinite(A) else None,
                        rate_limit=W if math.isfinite(W) else None)


def check_slew_time(wheels: WheelSet, angle: float, duration: float, inertia, *,
                    axis=None) -> float:
    """Refuse a slew the wheels cannot complete in ``duration`` [s]; return the shortest time.

    Raises
    ------
    ValueError
        ``duration`` below :func:`shortest_slew_time`; the message gives the limits and the
        shortest time they allow.
    """
    duration_s = real_number(duration, "duration", "s")
    if not (math.isfinite(duration_s) and duration_s > 0):
        raise ValueError(f"duration must be positive and finite [s]; got {describe(duration)}")
    shortest = shortest_slew_time(wheels, angle, inertia, axis=axis)
    if duration_s < shortest:
        limits = _slew_limits(wheels, angle, inertia, axis)
        about = "" if wheels.planar else f" about {np.array2string(limits['axis'], precision=4)}"
        raise ValueError(
            f"duration {duration_s:.6g} s is too short for the slew of angle {angle:.6g} rad "
            f"({math.degrees(angle):.6g} deg){about} with these wheels: their torque capacity {limits['torque']:.4g} N*m "
            f"and momentum room {limits['momentum_room']:.4g} N*m*s (for the inertia "
            f"{limits['inertia']:.6g} kg*m^2 about the slew axis) allow it in no less than "
            f"{shortest:.4g} s")
    return shortest


def _slew_limits(wheels: WheelSet, angle, inertia, axis) -> dict:
    """The wheels' torque and momentum capacities for an eigen-axis slew, and the acceleration
    and rate limits they set (see :func:`shortest_slew_time`)."""
    if not isinstance(wheels, WheelSet):
        raise TypeError(f"wheels must be a controllers.WheelSet; got {type(wheels).__name__}")
    angle = real_number(angle, "angle", "rad")
    if not (math.isfinite(angle) and angle != 0.0):
        raise ValueError(f"angle must be non-zero and finite [rad]; got {describe(angle)}")
    e = wheels._unit_direction(axis)
    Je = np.atleast_1d(_inertia_times(inertia, e, wheels.planar))
    size = float(np.linalg.norm(Je))
    u = Je / size
    a = wheels.allocation @ u * math.copysign(1.0, angle)   # wheel momentum per unit of H
    tau_m = _capacity(a, wheels._torque_limits)
    h0 = np.array([w.initial_momentum for w in wheels.wheels])
    # wheel momenta during the slew: h0 - a H, H from 0 to |J e| omega_m (>= 0 along the slew)
    with np.errstate(divide="ignore", invalid="ignore"):
        room = np.where(a > 0, (h0 + wheels._momentum_limits) / a,
                        np.where(a < 0, (wheels._momentum_limits - h0) / -a, math.inf))
    H_m = float(np.min(room))
    return {"angle": angle, "axis": e, "inertia": float(e @ Je) if e.size == 3 else size,
            "torque": tau_m, "momentum_room": H_m, "acceleration": tau_m / size,
            "rate": H_m / size}


def _inertia_times(inertia, e: np.ndarray, planar: bool):
    """J e for the checked inertia (a float J for the planar set)."""
    if planar:
        J = real_number(inertia, "inertia", "kg*m^2")
        if not (math.isfinite(J) and J > 0):
            raise ValueError(f"inertia must be positive and finite [kg*m^2]; got "
                             f"{describe(inertia)}")
        if not 1e-20 <= J <= 1e20:  # flexsat's inertia range: J, 1/J and their products finite
            raise ValueError(f"inertia must lie in [1e-20, 1e20] [kg*m^2]; got "
                             f"{describe(inertia)}")
        return J
    try:
        M = np.asarray(inertia, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"inertia must be a 3 x 3 array of real numbers [kg*m^2]; got "
                        f"{describe(inertia)}") from exc
    if M.shape != (3, 3) or not np.all(np.isfinite(M)):
        raise ValueError(f"inertia must be a finite 3 x 3 tensor [kg*m^2] (hub axes); got "
                         f"{describe(inertia)}")
    symmetric = np.allclose(M, M.T, rtol=1e-9, atol=0.0)
    if not (symmetric and np.all(np.linalg.eigvalsh(0.5 * (M + M.T)) > 0)):
        raise ValueError(f"inertia must be symmetric positive definite [kg*m^2]; got "
                         f"{describe(inertia)}")
    return check_inertia(M) @ e  # and a body's (triangle inequality)
