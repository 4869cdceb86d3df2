r"""The actuator that applies the flight software's torque in Basilisk.

Default: an ``extForceTorque`` effector, the torque applied to the hub as commanded. Option: a
reaction wheel on the hub's z axis (:class:`ReactionWheel`), Basilisk's
``reactionWheelStateEffector`` with the balanced-wheel model. Its motor torque u_s spins the
wheel, J_s (Omega' + omega') = u_s, and reacts on the hub with -u_s about the spin axis; the
flight software commands u_s = -torque, so the hub receives the commanded torque, and for a spin
axis along z the gyroscopic term omega x (J_s Omega g) vanishes: the planar loop is the one
flexsat predicts, with the wheel's speed as an extra output.

Inertia bookkeeping: with the rotor spinning freely about g, the hub obeys J_B omega' = -u_s,
J_B the spacecraft's inertia without the rotor's spin inertia J_s (its mass and transverse
inertia included). That is flexsat's hub inertia. Basilisk's balanced-wheel model adds no wheel
mass or inertia to the spacecraft (``updateEffectorMassProps`` does so for the jitter models
only) and subtracts J_s g g^T in its back-substitution (``matrixD -= Js gsHat gsHat^T``): it
expects the rotor's spin inertia inside the hub's ``IHubPntBc_B``. The adapter therefore adds
J_s about z to the hub it gives Basilisk; the hub's equation is then flexsat's. Torque
(``u_max``) and speed (``Omega_max``) limits are Basilisk's.

Three axes: a triad
    On a three-axis spacecraft the wheel becomes three such wheels, spinning about the hub's
    x, y and z axes, each commanded ``u_s = -torque`` of its axis; the adapter adds
    ``sum_k J_s g_k g_k^T = J_s E`` to the hub's inertia (:func:`triad_inertia`), which
    Basilisk takes out again. The hub then obeys

        J_B omega' + omega x (J_B omega + h) = torque,    h = J_s (Omega + omega),

    with h the wheels' momentum. Started at rest relative to the hub (``initial_speed`` 0) the
    wheels hold only the momentum the commands gave them, first order in the motion, so the
    gyroscopic torque ``omega x h`` is second order, as the other terms flexsat's linear plant
    drops: the loop is flexsat's to second order. A wheel spinning at the start (a momentum
    bias) makes ``omega x h`` first order, a gyroscopic stiffness flexsat's plant does not
    have: the adapter refuses it on a three-axis spacecraft.

References
----------
.. [1] H. Schaub, J. L. Junkins, "Analytical Mechanics of Space Systems", 4th ed., AIAA 2018,
   sec. 4.5 (spacecraft with reaction wheels).
.. [2] Basilisk documentation, ``reactionWheelStateEffector`` (balanced wheels, u_max,
   Omega_max).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from appendages.interface import check_positive

__all__ = ["ReactionWheel", "WHEEL_ACCELERATION_GUARD", "rotor_inertia", "triad_inertia",
           "wheel_config"]

#: Basilisk's ``maxWheelAcceleration`` [rad/s**2] set by the adapter: no clipping (module
#: docstring, "Basilisk's wheel-acceleration guard").
WHEEL_ACCELERATION_GUARD = math.inf


def _optional(value, name: str, unit: str) -> float | None:
    return None if value is None else check_positive(name, value, unit)


@dataclasses.dataclass(frozen=True)
class ReactionWheel:
    """A reaction wheel spinning about the hub's +z axis (Basilisk's balanced-wheel model).

    Parameters
    ----------
    spin_inertia : float, kg*m**2
        Rotor inertia J_s about the spin axis (not part of flexsat's hub inertia).
    max_torque : float, N*m, optional
        Motor torque limit (Basilisk's ``u_max``); default unlimited.
    max_speed : float, rad/s, optional
        Wheel speed beyond which the motor no longer accelerates it (``Omega_max``); default
        unlimited.
    initial_speed : float, rad/s
        Wheel speed relative to the hub at t = 0.
    """

    spin_inertia: float
    max_torque: float | None = None
    max_speed: float | None = None
    initial_speed: float = 0.0

    def __post_init__(self):
        speed = self.initial_speed
        if isinstance(speed, bool) or not isinstance(speed, (int, float)) or not math.isfinite(speed):
            raise ValueError(f"initial_speed must be a finite speed [rad/s]; got {speed!r}")
        for name, value in (("spin_inertia", check_positive("spin_inertia", self.spin_inertia,
                                                            "kg*m^2")),
                            ("max_torque", _optional(self.max_torque, "max_torque", "N*m")),
                            ("max_speed", _optional(self.max_speed, "max_speed", "rad/s")),
                            ("initial_speed", float(speed))):
            object.__setattr__(self, name, value)


def rotor_inertia(wheel: ReactionWheel) -> np.ndarray:
    """The rotor as a thin disc about its centre [kg*m**2] (3, 3), hub axes: J_s about the
    spin axis z, J_s / 2 about x and y (``Jt = Jg`` of :func:`wheel_config`)."""
    return np.diag([0.5, 0.5, 1.0]) * wheel.spin_inertia


def triad_inertia(wheel: ReactionWheel) -> np.ndarray:
    """The spin inertias of three such wheels on the hub's x, y and z axes, ``J_s E``
    [kg*m**2] (3, 3): what Basilisk's balanced wheels take out of the hub's inertia."""
    return np.eye(3) * wheel.spin_inertia


#: A wheel's spin axis and the two transverse axes Basilisk asks for, by hub axis.
_WHEEL_AXES = {"z": ((0.0, 0.0, 1.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)),
               "x": ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
               "y": ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (1.0, 0.0, 0.0))}


def wheel_config(wheel: ReactionWheel, axis: str = "z"):
    """Basilisk's ``RWConfigPayload`` for the wheel spinning about the hub's ``axis`` (needs
    Basilisk)."""
    from Basilisk.architecture import messaging
    from Basilisk.simulation import reactionWheelStateEffector

    spin, w2, w3 = _WHEEL_AXES[axis]
    config = reactionWheelStateEffector.RWConfigPayload()
    config.RWModel = messaging.BalancedWheels
    config.gsHat_B = [[v] for v in spin]
    config.w2Hat0_B = [[v] for v in w2]
    config.w3Hat0_B = [[v] for v in w3]
    config.rWB_B = [[0.0], [0.0], [0.0]]
    config.Js = wheel.spin_inertia
    config.Jt = config.Jg = 0.5 * wheel.spin_inertia  # unused by the balanced model
    config.mass = 1.0       # unused by the balanced model; nonzero so Basilisk's d = U_s/mass = 0
    config.U_s = config.U_d = 0.0
    config.Omega = wheel.initial_speed
    config.u_max = -1.0 if wheel.max_torque is None else wheel.max_torque
    config.u_min = 0.0
    config.Omega_max = -1.0 if wheel.max_speed is None else wheel.max_speed
    config.fCoulomb = config.fStatic = config.cViscous = 0.0
    config.betaStatic = -1.0
    config.P_max = -1.0
    config.label = f"RW_{axis}"
    return config
