r"""A flexsat controller as Basilisk flight software.

Any flexsat controller (a ``control.StateSpace`` with output ``torque`` and inputs among
``theta_ref``, ``theta``, ``omega``) runs in Basilisk as a digital law at the flight-software
sample time T,

    x[k+1] = A x[k] + B u[k],    torque[k] = C x[k] + D u[k],    u[k] = inputs at t_k = k T,

held constant over [t_k, t_(k+1)) (zero-order hold). A digital controller (``dt`` > 0) runs at
its own ``dt``; a continuous one is discretised exactly with a zero-order hold at T
(``control.c2d(..., method="zoh")``, what :func:`controllers.pd` does with ``sample_time``).
flexsat's prediction for the same loop is :func:`controllers.close_loop` of the plant with this
discrete controller: the exact sampled-data loop.

In Basilisk the law is a Python ``SysModel`` in the flight-software task. At each t_k it reads
the hub's ``SCStatesMsgPayload`` (written after the dynamics integrated up to t_k: the dynamics
task has the higher priority), forms flexsat's signals

    theta = 4 atan(sigma_BN[2]), unwrapped across MRP shadow-set switches (+-2 pi),
    omega = omega_BN_B[2],

(exact for a rotation about z, sigma = tan(theta/4) e_z [1]_), evaluates the law, and writes
``torqueRequestBody = (0, 0, torque)`` to a ``CmdTorqueBodyMsg``. The ``extForceTorque``
effector that applies it sits in the same task after the law, so the torque computed at t_k
drives the integration over [t_k, t_(k+1)) exactly as the sampled-data model assumes.

Three axes
    A three-axis controller (outputs ``torque_x``, ``torque_y``, ``torque_z``; inputs among
    ``theta_ref_x/_y/_z``, ``theta_x/_y/_z``, ``omega_x/_y/_z``, :data:`SIGNALS_3`) runs the same
    way. The attitude it reads is the rotation vector of the hub's MRP,

        theta = 4 atan(|sigma|) sigma / |sigma|,

    unwrapped along its axis across shadow-set switches (+-2 pi), the rate ``omega_BN_B``, and
    the reference the eigen-axis slew ``theta_ref = e * profile(t)``: for a rotation about a
    fixed axis e the rotation vector is exactly ``phi e``, so the law sees what flexsat's
    small-angle loop (``theta`` the small rotation vector in hub axes) sees, up to terms second
    order in the attitude. ``torqueRequestBody = (torque_x, torque_y, torque_z)``.

References
----------
.. [1] H. Schaub, J. L. Junkins, "Analytical Mechanics of Space Systems", 4th ed., AIAA 2018,
   sec. 3.7 (modified Rodrigues parameters and their shadow set).
.. [2] G. F. Franklin, J. D. Powell, M. L. Workman, "Digital Control of Dynamic Systems", 3rd ed.,
   Addison-Wesley 1998, sec. 4.3 (zero-order-hold equivalent), sec. 11.2 (sample rate: 10 to 30
   times the bandwidth).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import control
import numpy as np

from appendages.interface import check_positive

from .install import BasiliskModelError

__all__ = ["FlightSoftwareLaw", "flight_software_law", "default_sample_time",
           "SIGNALS", "SIGNALS_3", "TORQUES_3", "SAMPLES_PER_CROSSOVER", "LOOP_GAIN_FLOOR",
           "flight_software_class", "rotation_vector"]

#: The signals the flight software forms, in flexsat's names.
SIGNALS = ("theta_ref", "theta", "omega")
#: The signals a three-axis flight software forms (hub axes).
SIGNALS_3 = tuple(f"{name}_{axis}" for name in SIGNALS for axis in "xyz")
#: A three-axis controller's outputs (hub axes).
TORQUES_3 = ("torque_x", "torque_y", "torque_z")

#: Default flight-software rate for a continuous controller: this many samples per period of
#: the highest gain crossover or controller pole (the top of Franklin, Powell & Workman's 10-30
#: range [2]_), so the sampled loop stays close to the continuous loop the user designed.
SAMPLES_PER_CROSSOVER = 30.0
#: Loop gain (largest singular value of L(j omega)) below which a controller pole does not set
#: the default rate (-40 dB): where |L| < 0.01, even a sampled law 100 % off the continuous one
#: moves the return difference I + L by less than 1 %, so the closed loop barely notices (an
#: estimator's copies of stiff chain modes, thousands of rad/s, far above the loop's band).
LOOP_GAIN_FLOOR = 0.01


@dataclasses.dataclass(frozen=True)
class FlightSoftwareLaw:
    """A controller as the digital law Basilisk runs.

    Attributes
    ----------
    A, B, C, D : ndarray
        ``x[k+1] = A x + B u``, ``torque = C x + D u`` (C, D one row; three axes: three).
    inputs : tuple of str
        The meaning of each entry of u (names from :data:`SIGNALS`; three axes
        :data:`SIGNALS_3`).
    sample_time : float, s
    controller : control.StateSpace
        The same law as a discrete StateSpace with ``dt = sample_time`` (for
        :func:`controllers.close_loop`).
    outputs : tuple of str
        ``("torque",)``, or three axes the controller's order of :data:`TORQUES_3`.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    inputs: tuple
    sample_time: float
    controller: control.StateSpace
    outputs: tuple = ("torque",)

    @property
    def three_axis(self) -> bool:
        """True for a three-axis law (torques about x, y and z)."""
        return self.outputs != ("torque",)


def flight_software_law(controller: control.StateSpace, sample_time: float | None = None
                        ) -> FlightSoftwareLaw:
    """The digital law Basilisk runs for a flexsat controller.

    Parameters
    ----------
    controller : control.StateSpace
        Output ``torque`` [N*m]; inputs among ``theta_ref`` [rad], ``theta`` [rad], ``omega``
        [rad/s]. Three axes: outputs ``torque_x/_y/_z`` [N*m], inputs among
        ``theta_ref_x/_y/_z``, ``theta_x/_y/_z`` [rad], ``omega_x/_y/_z`` [rad/s] (hub axes).
        Continuous (dt = 0, or None for a static gain) or digital (dt > 0).
    sample_time : float, s, optional
        Flight-software sample time. Required for a continuous controller (it is discretised
        exactly, zero-order hold, at this rate); for a digital one it must equal its dt
        (default).

    Returns
    -------
    FlightSoftwareLaw

    Raises
    ------
    BasiliskModelError
        An input Basilisk's flight software does not form (e.g. a tip-deflection measurement),
        an output other than the single ``torque``.
    ValueError
        A missing or inconsistent sample time.
    """
    if not isinstance(controller, control.StateSpace):
        raise TypeError(f"controller must be a control.StateSpace; got {type(controller).__name__}")
    outputs = list(controller.output_labels)
    three_axis = sorted(outputs) == list(TORQUES_3)
    if outputs != ["torque"] and not three_axis:
        raise BasiliskModelError(f"controller must have the single output 'torque' [N*m] (the "
                                 f"hub torque Basilisk applies), or three axes the outputs "
                                 f"{list(TORQUES_3)}; got outputs {outputs}")
    signals = SIGNALS_3 if three_axis else SIGNALS
    inputs = list(controller.input_labels)
    unknown = [name for name in inputs if name not in signals]
    if unknown:
        raise BasiliskModelError(
            f"controller inputs {unknown} are not signals the Basilisk flight software forms: it "
            f"reads the hub's attitude and rate and the reference, {list(signals)}")
    dt = controller.dt
    if dt is True:
        raise ValueError("controller has an unspecified sample time (dt=True); give it dt > 0 [s]")
    if dt is not None and dt > 0:
        T = float(dt)
        if sample_time is not None and not math.isclose(check_positive("sample_time", sample_time, "s"), T,
                                                        rel_tol=1e-12):
            raise ValueError(f"sample_time must equal the digital controller's dt = {T!r} [s] "
                             f"(it runs at its own rate); got {sample_time!r}")
        digital = controller
    else:
        if sample_time is None:
            raise ValueError("a continuous controller needs sample_time [s], the flight-software "
                             "rate at which Basilisk runs it (see default_sample_time)")
        T = check_positive("sample_time", sample_time, "s")
        continuous = control.ss(controller.A, controller.B, controller.C, controller.D, 0)
        digital = control.c2d(continuous, T, method="zoh")
    A, B, C, D = (np.asarray(M, dtype=float) for M in (digital.A, digital.B, digital.C, digital.D))
    n = A.shape[0]
    A, B, C = A.reshape(n, n), B.reshape(n, len(inputs)), C.reshape(len(outputs), n)
    D = D.reshape(len(outputs), len(inputs))
    system = control.ss(A, B, C, D, T, inputs=inputs, outputs=outputs,
                        name=controller.name or "controller")
    return FlightSoftwareLaw(A, B, C, D, tuple(inputs), T, system, tuple(outputs))


def default_sample_time(plant: control.StateSpace, controller: control.StateSpace) -> float:
    """Flight-software sample time for a continuous controller [s].

    The largest of 1, 2, 5 x 10**k seconds with at least :data:`SAMPLES_PER_CROSSOVER` samples
    per period of the fastest of (a) the loop's highest gain crossover on ``plant`` (above it
    |L(j omega)| < 1 for good; three axes: the largest singular value of the 3x3 L, every
    loop's gain in every direction) and (b) the controller's own fastest pole (an estimator's copy of
    the chain modes, a roll-off filter): the sampled law then stays close to the continuous one
    the user designed wherever the loop acts. Poles above the band where the loop has gain
    (above the highest frequency with |L| >= :data:`LOOP_GAIN_FLOOR`) do not count: they are
    an estimator's copies of modes the loop does not act on (the stiff ones would ask for a
    rate no flight computer has), and a sampled law off the continuous one there changes the
    closed loop by less than the floor (flexsat's predictions are of the sampled law as
    flown, whatever the rate). A digital controller's own dt is returned as it is.

    Parameters
    ----------
    plant : control.StateSpace
        The design plant (hub + chain) with input ``torque`` and outputs ``theta``, ``omega``.
    controller : control.StateSpace

    Returns
    -------
    float, s
    """
    import controllers

    if not isinstance(controller, control.StateSpace):
        raise TypeError(f"controller must be a control.StateSpace; got "
                        f"{type(controller).__name__}")
    if controller.dt not in (None, 0) and controller.dt is not True:
        return float(controller.dt)
    omega, L = controllers.loop_frequency_response(plant, controller)
    gain = np.abs(L) if L.ndim == 1 else np.linalg.norm(L, ord=2, axis=(1, 2))
    above = np.nonzero(gain >= 1.0)[0]
    fastest = float(omega[above[-1]]) if above.size else 0.0
    if controller.nstates:
        poles = np.abs(np.linalg.eigvals(np.asarray(controller.A, dtype=float)))
        acting = np.nonzero(gain >= LOOP_GAIN_FLOOR)[0]
        if acting.size and acting[-1] < omega.size - 1:
            # poles above the band where the loop has gain do not count (docstring)
            poles = poles[poles <= omega[acting[-1]]]
        if poles.size:
            fastest = max(fastest, float(np.max(poles)))
    if fastest == 0.0:
        raise ValueError("the loop has no gain crossover and the controller no dynamics: cannot "
                         "choose a sample time; give sample_time [s]")
    return _one_two_five(2.0 * math.pi / (SAMPLES_PER_CROSSOVER * fastest))


def _one_two_five(limit: float) -> float:
    """The largest of 1, 2, 5 x 10**k at most ``limit`` [s]."""
    decade = 10.0 ** math.floor(math.log10(limit))
    return max(m * decade for m in (1.0, 2.0, 5.0) if m * decade <= limit * (1.0 + 1e-12))


def _unwrap(angle: float, previous: float) -> float:
    """``angle`` shifted by a multiple of 2 pi to lie within pi of ``previous``."""
    return angle + 2.0 * math.pi * round((previous - angle) / (2.0 * math.pi))


def _three_finite(value, name: str, unit: str) -> np.ndarray:
    """``value`` as three finite floats (3,), or a ValueError naming ``name``."""
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        v = None
    if v is None or v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be three finite numbers (x, y, z) [{unit}], hub axes; "
                         f"got {value!r:.100}")
    return v


def rotation_vector(sigma, previous=None) -> np.ndarray:
    """The rotation vector [rad] (3,) of an MRP ``sigma``, unwrapped towards ``previous``.

    ``theta = 4 atan(|sigma|) sigma / |sigma|`` [1]_, shifted along its axis by the multiple of
    2 pi that brings it closest to ``previous`` (a rotation vector [rad], e.g. the last
    sample's): continuous across the MRP's shadow-set switch at 180 deg, where sigma jumps to
    ``-sigma / |sigma|**2`` and the rotation vector by 2 pi along its axis.

    Parameters
    ----------
    sigma : array_like (3,)
        Modified Rodrigues parameters (dimensionless), finite.
    previous : array_like (3,), rad, optional
        The rotation vector to unwrap towards.

    Returns
    -------
    ndarray (3,), rad
    """
    sigma = _three_finite(sigma, "sigma", "-")
    if previous is not None:
        previous = _three_finite(previous, "previous", "rad")
    return _rotation_vector(sigma, previous)


def _rotation_vector(sigma: np.ndarray, previous: np.ndarray | None) -> np.ndarray:
    """:func:`rotation_vector` without its checks (the flight software's, every sample)."""
    s = math.sqrt(float(sigma @ sigma))
    if s == 0.0:
        return np.zeros(3)
    axis = sigma / s
    angle = 4.0 * math.atan(s)
    if previous is not None:
        angle = _unwrap(angle, float(axis @ previous))
    return angle * axis


@functools.cache
def flight_software_class():
    """The Basilisk ``SysModel`` subclass that runs a :class:`FlightSoftwareLaw` (built once).

    Instances take ``(law, reference_values)``: the law, and theta_ref [rad] at every sample
    instant k T (evaluated once, before the run; three axes: an (n, 3) array in hub axes).
    Attributes ``stateInMsg`` (``SCStatesMsgReader``), ``torqueOutMsg`` (``CmdTorqueBodyMsg``,
    the hub torque for ``extForceTorque``) and ``motorTorqueOutMsg`` (``ArrayMotorTorqueMsg``,
    -torque for a reaction wheel; three axes for wheels along x, y, z) are connected by the
    caller.
    """
    from Basilisk.architecture import messaging, sysModel

    class AttitudeFlightSoftware(sysModel.SysModel):
        """x[k+1] = A x + B u, torque = C x + D u with u from the hub's state message."""

        def __init__(self, law: FlightSoftwareLaw, reference_values: np.ndarray):
            super().__init__()
            self.stateInMsg = messaging.SCStatesMsgReader()
            self.torqueOutMsg = messaging.CmdTorqueBodyMsg()
            self.motorTorqueOutMsg = messaging.ArrayMotorTorqueMsg()  # for a reaction wheel
            self.law = law
            self.reference_values = np.asarray(reference_values, dtype=float)
            self.period_nanos = round(law.sample_time * 1e9)
            self.x = np.zeros(law.A.shape[0])
            if law.three_axis:
                self.theta = np.zeros(3)
                self._where = [SIGNALS_3.index(name) for name in law.inputs]
                # torque_x, _y, _z from the law's outputs, in whatever order it gives them
                self._axes = [law.outputs.index(name) for name in TORQUES_3]
            else:
                self.theta = 0.0
                self._where = [SIGNALS.index(name) for name in law.inputs]

        def Reset(self, CurrentSimNanos):
            self.x = np.zeros(self.law.A.shape[0])
            self.theta = np.zeros(3) if self.law.three_axis else 0.0
            self.torqueOutMsg.write(messaging.CmdTorqueBodyMsgPayload(), CurrentSimNanos,
                                    self.moduleID)
            self.motorTorqueOutMsg.write(messaging.ArrayMotorTorqueMsgPayload(), CurrentSimNanos,
                                         self.moduleID)

        def UpdateState(self, CurrentSimNanos):
            if self.law.three_axis:
                torque = self._three_axis(CurrentSimNanos)
            else:
                torque = (0.0, 0.0, self._planar(CurrentSimNanos))
            payload = messaging.CmdTorqueBodyMsgPayload()
            payload.torqueRequestBody = list(torque)
            self.torqueOutMsg.write(payload, CurrentSimNanos, self.moduleID)
            # a wheel's motor torque u_s reacts on the hub as -u_s: command u_s = -torque
            motor = messaging.ArrayMotorTorqueMsgPayload()
            motor.motorTorque = ([-t for t in torque] if self.law.three_axis
                                 else [-torque[2]])
            self.motorTorqueOutMsg.write(motor, CurrentSimNanos, self.moduleID)

        def _planar(self, nanos) -> float:
            state = self.stateInMsg()
            sigma, rate = state.sigma_BN[2], state.omega_BN_B[2]
            if not (math.isfinite(sigma) and math.isfinite(rate)):
                # diverged dynamics: command nothing (an exception here would only print a
                # traceback from inside Basilisk); the run's collection reports the divergence
                return 0.0
            self.theta = _unwrap(4.0 * math.atan(sigma), self.theta)
            k = min(nanos // self.period_nanos, self.reference_values.size - 1)
            signals = np.array([self.reference_values[k], self.theta, rate])
            return self._step(signals)[0]

        def _three_axis(self, nanos) -> tuple:
            state = self.stateInMsg()
            sigma, rate = np.array(state.sigma_BN, dtype=float), np.array(state.omega_BN_B,
                                                                          dtype=float)
            if not (np.all(np.isfinite(sigma)) and np.all(np.isfinite(rate))):
                return (0.0, 0.0, 0.0)  # diverged: as in _planar
            self.theta = _rotation_vector(sigma, self.theta)
            k = min(nanos // self.period_nanos, self.reference_values.shape[0] - 1)
            signals = np.concatenate([self.reference_values[k], self.theta, rate])
            torque = self._step(signals)
            return tuple(float(torque[i]) for i in self._axes)

        def _step(self, signals: np.ndarray) -> np.ndarray:
            u = signals[self._where]
            law = self.law
            torque = law.C @ self.x + law.D @ u
            self.x = law.A @ self.x + law.B @ u
            return torque

    return AttitudeFlightSoftware
