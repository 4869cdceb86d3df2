r"""Run a flexsat spacecraft and controller in Basilisk, and flexsat's prediction of the same run.

:func:`simulate_slew` is the entry point: it lays the spacecraft out as Basilisk's hub and
``spinningBodyNDOFStateEffector`` chains (:mod:`.layout`), runs the controller as flight software
(:mod:`.flight_software`) on the scene's cycloidal slew, and returns theta, omega, every tip
deflection and the torque as flexsat's plant defines them, at the flight-software sample
instants. flexsat's prediction of the same sampled-data loop and the differences are in
:mod:`.comparison`.

Tasks and time
    One Basilisk process with two tasks: ``dynamics`` (priority 100, step dt) holds the spacecraft;
    ``flight_software`` (priority 50, step T = sample time, dt divides T) holds, in this order,
    the disturbance schedule, the controller, the actuator that reads its command
    (``extForceTorque`` or a reaction wheel, :mod:`.actuators`), and the recorders. At a common
    instant the higher-priority dynamics task runs first, so the flight software sees the state
    at t_k and its torque drives [t_k, t_(k+1)): the zero-order hold of
    :func:`controllers.close_loop` with a digital controller.

Integrator and step
    Basilisk's fixed-step RK4 (its default). On an undamped mode of frequency w, RK4 is stable for
    w dt <= 2 sqrt(2) (its stability region on the imaginary axis [1]_); its amplitude error per
    step is 1 - |R(i w dt)| ~ (w dt)**6 / 144 (a numerical damping ratio (w dt)**5 / 144) and its
    phase error ~ (w dt)**5 / 120, so the error of a run falls as dt**4. The default dt is the
    largest T/k with w_max dt <= 1/2 (w_max the chain spacecraft's highest linear mode): a factor
    5.7 inside the stability limit, room for the stiffening of large motions, and accurate even
    when a torque step excites every mode (a 1e-3 N*m pulse on a 3-body chain: 7e-5 of the peak
    tip deflection at w_max dt = 0.54, 4e-6 at 0.27; smooth slews excite the top modes far
    less, 1e-7). A chain whose w_max dt exceeds 2 sqrt(2) diverges: ``peer_basilisk.py``'s
    equal-panel chains of the paper's rod at its dt = 0.01 s give NaN from 20 panels (w_max dt =
    3.5) but run at 10 (0.86) and 16 (2.24) (``benchmarks/basilisk_vs_flexsat.py``); the
    adapter refuses such a dt before the run, naming the largest stable step.

    Stiff chains (``accurate_up_to``): a three-axis chain's stiffest motions (a wide wing's
    in-plane bending, a thin boom's torsion) have modes of thousands of rad/s that the
    flight software, sampling at 2 pi / T, neither sees nor drives except through the small
    steps of its held torque. Resolving them takes w_max / 0.5 steps per second for motions
    that answer quasi-statically. Given ``accurate_up_to`` (the design loop passes the flight
    software's Nyquist frequency pi / T), the default step is accurate (w dt <= 1/2) on the
    modes up to it and stable with a margin on the highest, w_max dt <= :data:`STABLE_STEP_FACTOR`
    = 2 (70 % of the limit: RK4's amplification there is |R(2i)| = 0.75 a step, so a mode
    above the accurate range is damped numerically and its ringing after each torque step
    lost, while its quasi-static response, which follows the slow loads, is kept). What that
    costs is measured against the accurate step (``benchmarks/basilisk_three_axis.py``).

Three axes
    A three-axis spacecraft runs the same way: the hub's full inertia tensor, three spinning
    bodies per joint (:mod:`.layout`), a three-axis law commanding torques about x, y and z
    (:mod:`.flight_software`), the eigen-axis slew ``theta_ref = e * profile(t)``, and the
    outputs of flexsat's three-axis plant: ``theta_x/_y/_z`` (the rotation vector of the hub's
    MRP), ``omega_x/_y/_z``, per appendage ``<name>_tip_deflection_y``, ``_z`` and
    ``<name>_tip_twist``, ``torque_x/_y/_z``. A reaction wheel becomes a triad, one such wheel
    on each hub axis (:mod:`.actuators`). :func:`linearised` gives Basilisk's own equations of
    motion linearised about rest, by central differences, for checking a layout against
    flexsat's linear model.

References
----------
.. [1] E. Hairer, G. Wanner, "Solving Ordinary Differential Equations II", 2nd ed., Springer
   1996, sec. IV.2 (stability function of RK4, R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24).
.. [2] Basilisk 2.12 documentation: ``spacecraft``, ``extForceTorque``,
   ``spinningBodyNDOFStateEffector``, "Creating Python Modules" (SysModel subclasses), task
   priorities (higher value runs first).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Callable, Mapping

import control
import numpy as np

from appendages.interface import check_positive

from ..dynamics.coupling import Spacecraft
from ..scene.limits import Limits
from .actuators import (WHEEL_ACCELERATION_GUARD, ReactionWheel, rotor_inertia,
                        triad_inertia, wheel_config)
from .flight_software import (TORQUES_3, FlightSoftwareLaw, flight_software_class,
                              flight_software_law, rotation_vector)
from .install import (BasiliskIntegrationError, BasiliskModelError, BasiliskRunTooLong,
                      require_basilisk)
from .layout import SpacecraftLayout, layout

__all__ = ["BasiliskResult", "simulate", "simulate_slew", "dynamics_step", "estimated_seconds",
           "largest_stable_step", "RK4_STABILITY_LIMIT", "DEFAULT_STEP_FACTOR",
           "STABLE_STEP_FACTOR", "DISTURBANCES", "DISTURBANCES_3",
           "MAX_SECONDS", "MAX_SAMPLES", "nanoseconds", "disturbance_values", "sample_count",
           "default_duration", "linearised", "LinearisedModel", "slew_reference"]

#: RK4 is stable on the imaginary axis for |w dt| <= 2 sqrt(2) [1]_.
RK4_STABILITY_LIMIT = 2.0 * math.sqrt(2.0)
#: Default w_max * dt of the dynamics step (see the module docstring).
DEFAULT_STEP_FACTOR = 0.5
#: w_max * dt of the default step when only the modes up to ``accurate_up_to`` are resolved
#: (module docstring, "Stiff chains"): 70 % of :data:`RK4_STABILITY_LIMIT`.
STABLE_STEP_FACTOR = 2.0
#: Disturbance inputs the Basilisk model applies (hub torque; force at the hub's centre of mass).
DISTURBANCES = ("disturbance_torque", "force_x", "force_y")
#: The same in three axes (hub axes).
DISTURBANCES_3 = ("disturbance_torque_x", "disturbance_torque_y", "disturbance_torque_z",
                  "force_x", "force_y", "force_z")
#: Work model of a run [s]: per RK4 step STEP_SECONDS + BODY_SECONDS * N**3 (the N-DOF effector
#: builds and inverts its N x N mass matrix in O(N**3) per derivative evaluation), per
#: flight-software sample SAMPLE_SECONDS (the Python law). Measured with bsk 2.12.1 on a shared
#: 2-core AMD EPYC (load 5-6): 110 us/step at 3 bodies, 350 at 10, 1.3 ms at 20, 12 ms at 40.
STEP_SECONDS, BODY_SECONDS, SAMPLE_SECONDS = 1.0e-4, 1.8e-7, 1.0e-4
#: Default limit on the estimated run time [s] (``max_seconds``; a scene's
#: ``limits.basilisk_seconds``).
MAX_SECONDS = Limits().basilisk_seconds

_NANO = 1e-9
#: Most flight-software samples of one run (a run's outputs are kept per sample).
MAX_SAMPLES = 1e8
#: Most RK4 steps per flight-software sample a run may need (the search for a step dividing
#: the sample time stays short; a run that stiff would take days anyway).
MAX_STEPS_PER_SAMPLE = 1e6


@dataclasses.dataclass
class BasiliskResult:
    """A Basilisk run of a flexsat spacecraft.

    Attributes
    ----------
    response : control.TimeResponseData
        At the flight-software sample instants k T: outputs ``theta`` [rad], ``omega`` [rad/s],
        ``<name>_tip_deflection`` [m] per appendage, ``torque`` [N*m] (the names of flexsat's
        closed loops), with a reaction wheel ``wheel_speed`` [rad/s] (relative to the hub);
        inputs ``theta_ref`` [rad] and any disturbance. Three axes: ``theta_x/_y/_z``,
        ``omega_x/_y/_z``, ``<name>_tip_deflection_y``, ``_z`` [m], ``<name>_tip_twist`` [rad],
        ``torque_x/_y/_z``, with wheels ``wheel_speed_x/_y/_z``; inputs ``theta_ref_x/_y/_z``.
    sample_time : float, s
        Flight-software (and output) step.
    dt : float, s
        Dynamics (RK4) step.
    highest_frequency : float, rad/s
        Highest linear mode of the chain spacecraft (what dt was sized from).
    layout : SpacecraftLayout
    law : FlightSoftwareLaw or None
    bsk_version : str
    seconds : dict
        Wall time [s] of ``build`` (Python objects and InitializeSimulation) and ``run``.
    out_of_plane : float
        Largest |sigma_BN_x|, |sigma_BN_y|, |omega_BN_B_x|, |omega_BN_B_y| seen (0 for planar
        motion; a three-axis run moves in every direction and reports NaN).
    conservation : dict or None
        When asked: ``time`` [s], ``rotational_energy`` [J] (kinetic + hinge springs, Basilisk's
        ``totRotEnergy``), ``angular_momentum`` [N*m*s] (n, 3), about the system's centre of mass
        in inertial axes (``totRotAngMomPntC_N``), ``orbital_energy`` [J] (``totOrbEnergy``).
    """

    response: control.TimeResponseData
    sample_time: float
    dt: float
    highest_frequency: float
    layout: SpacecraftLayout
    law: FlightSoftwareLaw | None
    bsk_version: str
    seconds: dict
    out_of_plane: float
    conservation: dict | None = None


def nanoseconds(seconds: float, name: str) -> int:
    """Basilisk's clock is integer nanoseconds: the step in ns, checked to be representable."""
    if not seconds * 1e9 < 2.0**63:  # Basilisk's clock is a uint64 of nanoseconds
        raise ValueError(f"{name} must be at most {2.0**63 * _NANO:.6g} s (Basilisk's clock); "
                         f"got {seconds!r}")
    nanos = round(seconds * 1e9)
    if nanos < 1 or abs(nanos * _NANO - seconds) > 1e-9 * seconds:
        raise ValueError(f"{name} must be a whole number of nanoseconds (Basilisk's clock) [s]; "
                         f"got {seconds!r}")
    return nanos


def _divided(period: int, k: int) -> float | None:
    """The step T/k' [s] for the least k' in [k, 4k] dividing ``period`` [ns]; None if none."""
    for candidate in range(k, 4 * k + 1):
        if period % candidate == 0:
            return period // candidate * _NANO
    return None


def largest_stable_step(highest_frequency: float, sample_time: float) -> float | None:
    """The largest RK4 step [s] dividing the sample time into whole nanoseconds that is
    stable on the highest mode (w_max dt <= 2 sqrt(2) [1]_); None if no such step is found."""
    w = check_positive("highest_frequency", highest_frequency, "rad/s", allow_zero=True)
    T = check_positive("sample_time", sample_time, "s")
    period = nanoseconds(T, "sample_time")
    ratio = w * T / RK4_STABILITY_LIMIT
    if not ratio <= MAX_STEPS_PER_SAMPLE:
        return None
    return _divided(period, max(1, math.ceil(ratio - 1e-12)))


def dynamics_step(highest_frequency: float, sample_time: float, dt: float | None = None, *,
                  accurate_up_to: float | None = None) -> float:
    """RK4 step [s] for the dynamics: T/k, k integer, sized from the highest mode.

    Parameters
    ----------
    highest_frequency : float, rad/s
        w_max of the linearised spacecraft (0: rigid).
    sample_time : float, s
        Flight-software step T; the dynamics step must divide it.
    dt : float, s, optional
        Asked step, checked: T/dt an integer, w_max dt <= 2 sqrt(2). Default: the largest T/k
        with w_max dt <= :data:`DEFAULT_STEP_FACTOR` and k dividing T in whole nanoseconds.
    accurate_up_to : float, rad/s, optional
        For the default step: resolve accurately (w dt <= :data:`DEFAULT_STEP_FACTOR`) only the
        modes up to this frequency, and keep the highest stable with a margin (w_max dt <=
        :data:`STABLE_STEP_FACTOR`; module docstring, "Stiff chains"). None: every mode.

    Raises
    ------
    ValueError
        A step that does not divide T, or one beyond RK4's stability limit for w_max (the
        message names the largest stable step).
    """
    w = check_positive("highest_frequency", highest_frequency, "rad/s", allow_zero=True)
    T = check_positive("sample_time", sample_time, "s")
    period = nanoseconds(T, "sample_time")
    if w * T / DEFAULT_STEP_FACTOR > MAX_STEPS_PER_SAMPLE:
        raise ValueError(f"highest_frequency {w:.6g} rad/s needs more than "
                         f"{MAX_STEPS_PER_SAMPLE:g} RK4 steps per flight-software sample of "
                         f"{T:.6g} s (w*dt <= {DEFAULT_STEP_FACTOR:g}); use a softer or shorter "
                         "chain, or a shorter sample time")
    highest_frequency = w
    if dt is not None:
        dt = check_positive("dt", dt, "s")
        if not T / dt <= MAX_STEPS_PER_SAMPLE:
            raise ValueError(f"dt must be at least the sample time / {MAX_STEPS_PER_SAMPLE:g} "
                             f"= {T / MAX_STEPS_PER_SAMPLE:.6g} [s]; got {dt!r}")
        k = round(T / dt)
        if k < 1 or period % k or abs(k * dt - T) > 1e-9 * T:
            raise ValueError(f"dt must divide the flight-software sample time {T!r} s into a whole "
                             f"number of whole-nanosecond steps [s]; got {dt!r} (T / dt = "
                             f"{T / dt:.6g}){_dividing_steps(period, dt)}")
        if highest_frequency * dt > RK4_STABILITY_LIMIT:
            stable = largest_stable_step(highest_frequency, T)
            largest = ("" if stable is None else
                       f"; the largest stable step dividing the sample time {T:.6g} s is "
                       f"{stable:.9g} s (w*dt = {highest_frequency * stable:.3g})")
            raise ValueError(
                f"dt = {dt!r} s is beyond RK4's stability limit for the chain's highest mode "
                f"{highest_frequency:.6g} rad/s (w*dt = {highest_frequency * dt:.3g} > 2*sqrt(2) "
                f"= 2.83: the run would blow up){largest}; the accurate step has w*dt <= "
                f"{DEFAULT_STEP_FACTOR:g}, dt <= {DEFAULT_STEP_FACTOR / highest_frequency:.3g} s")
        return period // k * _NANO
    factor = DEFAULT_STEP_FACTOR
    if accurate_up_to is not None:
        resolved = check_positive("accurate_up_to", accurate_up_to, "rad/s")
        if highest_frequency > resolved:
            # accurate up to ``resolved``, stable with a margin above (module docstring)
            factor = min(STABLE_STEP_FACTOR, DEFAULT_STEP_FACTOR * highest_frequency / resolved)
    k = max(1, math.ceil(highest_frequency * T / factor - 1e-12))
    step = _divided(period, k)
    if step is not None:
        return step
    raise ValueError(f"no dynamics step divides the sample time {T!r} s into between {k} and "
                     f"{4 * k} whole-nanosecond steps; choose a rounder sample time [s]")


def _dividing_steps(period: int, dt: float) -> str:
    """``"; the nearest that do: ..."``: the steps T/k (whole nanoseconds) next to ``dt``."""
    k = period * _NANO / dt
    found = []
    for candidates in (range(max(1, math.floor(k)), 0, -1),
                       range(max(1, math.ceil(k)), 4 * max(1, math.ceil(k)) + 2)):
        for n in candidates:
            if period % n == 0:
                found.append(period // n * _NANO)
                break
    steps = sorted(set(found))
    return ("; the nearest that do: " + " or ".join(f"{step:.9g}" for step in steps)
            if steps else "")


def estimated_seconds(n_bodies: int, duration: float, dt: float, sample_time: float) -> float:
    """Estimated wall time [s] of a Basilisk run (see :data:`STEP_SECONDS`).

    Parameters
    ----------
    n_bodies : int
        Spinning bodies (>= 0).
    duration, dt, sample_time : float, s
        Simulated time, RK4 step and flight-software step (positive, finite).

    Returns
    -------
    float, s
        inf for a run beyond the float range (refused by any limit).
    """
    if isinstance(n_bodies, bool) or not isinstance(n_bodies, (int, np.integer)) or n_bodies < 0:
        raise ValueError(f"n_bodies must be a non-negative integer; got {n_bodies!r:.100}")
    duration = check_positive("duration", duration, "s")
    dt = check_positive("dt", dt, "s")
    sample_time = check_positive("sample_time", sample_time, "s")
    if n_bodies > 1e6:
        return math.inf
    steps = duration / dt
    return (steps * (STEP_SECONDS + BODY_SECONDS * n_bodies**3)
            + duration / sample_time * SAMPLE_SECONDS)


def _initial_rate(value, three_axis: bool):
    """The initial hub rate: a finite float (about z), three axes a finite (3,) array."""
    if not three_axis:
        return _finite(value, "initial_rate", "rad/s")
    if isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool) \
            and value == 0:
        return np.zeros(3)
    try:
        rate = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        rate = None
    if rate is None or rate.shape != (3,) or not np.all(np.isfinite(rate)):
        raise ValueError(f"initial_rate must be three finite rates (x, y, z) [rad/s] on a "
                         f"three-axis spacecraft; got {value!r:.100}")
    return rate


def _finite(value, name: str, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a real number [{unit}]; got {type(value).__name__}")
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite [{unit}]; got {value!r}")
    return value


def default_duration(slew_time: float, duration) -> float:
    """``duration`` [s], or 3 x slew_time when None (named in the error if that overflows)."""
    if duration is not None:
        return check_positive("duration", duration, "s")
    if not math.isfinite(3.0 * slew_time):
        raise ValueError(f"slew_time must be at most {1e300:g} [s] (the default duration is "
                         f"3 x slew_time); got {slew_time!r}")
    return 3.0 * slew_time


def sample_count(duration: float, sample_time: float) -> int:
    """Flight-software samples of a run, floor(duration / T) + 1: refused (ValueError naming
    both) above :data:`MAX_SAMPLES`."""
    ratio = duration / sample_time
    if not ratio <= MAX_SAMPLES:
        raise ValueError(f"duration / sample_time = {duration!r} s / {sample_time!r} s is more "
                         f"than {MAX_SAMPLES:g} flight-software samples; lengthen sample_time "
                         "or shorten duration")
    return int(math.floor(ratio + 1e-9)) + 1


def _initial_angles(lay: SpacecraftLayout, initial_angles: Mapping | None) -> dict:
    if initial_angles is not None and not isinstance(initial_angles, Mapping):
        raise TypeError(f"initial_angles must be a mapping mount name -> hinge angles [rad]; "
                        f"got {type(initial_angles).__name__}")
    angles = {}
    initial_angles = {} if initial_angles is None else dict(initial_angles)
    names = [a.name for a in lay.appendages]
    unknown = sorted(set(initial_angles) - set(names))
    if unknown:
        raise ValueError(f"initial_angles names {unknown} are not mounts; the mounts are {names}")
    for a in lay.appendages:
        values = np.asarray(initial_angles.get(a.name, np.zeros(len(a.bodies))), dtype=float)
        if values.shape != (len(a.bodies),) or not np.all(np.isfinite(values)):
            raise ValueError(f"initial_angles[{a.name!r}] must be {len(a.bodies)} finite hinge "
                             f"angles [rad] (one per hinge); got {values!r}"[:200])
        angles[a.name] = values
    return angles


def disturbance_values(disturbances: Mapping | None, times: np.ndarray,
                       three_axis: bool = False) -> dict:
    """name -> the disturbance's value at each sample instant (checked: names the Basilisk
    model applies, :data:`DISTURBANCES` or :data:`DISTURBANCES_3`, one finite value each)."""
    if disturbances is not None and not isinstance(disturbances, Mapping):
        raise TypeError(f"disturbances must be a mapping name -> function of time or array; got "
                        f"{type(disturbances).__name__}")
    applied = DISTURBANCES_3 if three_axis else DISTURBANCES
    values = {}
    for name, profile in ({} if disturbances is None else dict(disturbances)).items():
        if name not in applied:
            raise BasiliskModelError(
                f"disturbance {name!r} is not applied by the Basilisk model: it applies "
                f"{list(applied)} (a tip force would need a force effector on a spinning "
                "body)")
        v = np.asarray(profile(times) if callable(profile) else profile, dtype=float)
        if v.shape != times.shape or not np.all(np.isfinite(v)):
            raise ValueError(f"disturbance {name!r} must give one finite value per sample "
                             f"({times.size}); got shape {v.shape}")
        values[name] = v
    return values


def simulate(spacecraft: Spacecraft, controller: control.StateSpace | None = None, *,
             duration: float, reference: Callable[[np.ndarray], np.ndarray] | None = None,
             sample_time: float | None = None, dt: float | None = None,
             chains: Mapping | None = None, disturbances: Mapping | None = None,
             initial_rate=0.0, initial_angles: Mapping | None = None,
             conservation: bool = False, reaction_wheel: ReactionWheel | None = None,
             max_seconds: float = MAX_SECONDS, rigid_above: float | None = None,
             accurate_up_to: float | None = None) -> BasiliskResult:
    """Simulate a flexsat spacecraft (chains) and controller in Basilisk.

    Parameters
    ----------
    spacecraft : Spacecraft
        Planar or three-axis hub with appendages that are chains (or replaced through
        ``chains``; three axes: chains from :func:`appendages.fit_chain_3d`, held
        inextensible, :mod:`.layout`).
    controller : control.StateSpace, optional
        Any flexsat controller (see :func:`.flight_software_law`); None: no control torque.
    duration : float, s
        Simulated time (from 0).
    reference : callable, optional
        theta_ref(t) [rad] for an array of times [s] (three axes: an array (n, 3) of
        theta_ref_x, _y, _z, e.g. :func:`slew_reference`); default 0.
    sample_time : float, s, optional
        Flight-software and output step; default the digital controller's dt. Required for a
        continuous controller and without controller.
    dt : float, s, optional
        Dynamics (RK4) step; default from the highest mode (:func:`dynamics_step`).
    chains : mapping name -> HingedChain, optional
        Chains replacing non-chain appendages (e.g. the scene's fit of a beam).
    disturbances : mapping name -> callable or array, optional
        ``disturbance_torque`` [N*m], ``force_x``, ``force_y`` [N] (hub axes, at the hub's centre
        of mass) as functions of time, held over each sample (as flexsat's sampled loop holds
        them); three axes :data:`DISTURBANCES_3`.
    initial_rate : float or (3,) array, rad/s
        Initial hub rate about z (three axes: the rate vector, hub axes).
    initial_angles : mapping name -> array, optional
        Initial hinge angles [rad] of each chain, relative rotation at each hinge from the root
        (one per spinning body: three axes, z, y and x at each joint, :mod:`.layout`).
    conservation : bool
        Record Basilisk's energy and angular momentum (:attr:`BasiliskResult.conservation`).
    reaction_wheel : ReactionWheel, optional
        Apply the torque through a reaction wheel about z instead of an external torque
        (:mod:`.actuators`); the response gains the output ``wheel_speed`` [rad/s]. Three axes:
        one such wheel on each hub axis, outputs ``wheel_speed_x/_y/_z``; it must start at rest
        relative to the hub (``initial_speed`` 0, see :mod:`.actuators`).
    max_seconds : float, s
        Refuse a run whose estimated wall time (:func:`estimated_seconds`) exceeds this.
    rigid_above : float, rad/s, optional
        Three axes: hold rigid the torsion of every chain whose first torsion frequency (root
        held) is above it (:func:`.layout`; its ``held`` and ``torsion_frequency`` say which).
    accurate_up_to : float, rad/s, optional
        The default step resolves the modes up to this frequency and is only stable above
        (:func:`dynamics_step`); ignored with ``dt``.

    Returns
    -------
    BasiliskResult

    Raises
    ------
    BasiliskNotInstalled
        Without the ``bsk`` package (message: how to install the extra).
    BasiliskModelError
        A spacecraft or controller Basilisk cannot represent (the message names it and why).
    BasiliskRunTooLong
        A run estimated to take longer than ``max_seconds`` (a BasiliskModelError).
    BasiliskIntegrationError
        Non-finite states during the run.
    """
    version = require_basilisk()
    t_build = time.perf_counter()
    lay = layout(spacecraft, chains=chains, rigid_above=rigid_above)
    law = None if controller is None else flight_software_law(controller, sample_time)
    if law is not None and law.three_axis != lay.three_axis:
        which = "three-axis" if lay.three_axis else "planar"
        raise BasiliskModelError(
            f"the spacecraft is {which} but the controller's outputs are "
            f"{list(law.outputs)}: a {which} spacecraft needs "
            f"{TORQUES_3 if lay.three_axis else ('torque',)}")
    if law is not None:
        T = law.sample_time
    elif sample_time is None:
        raise ValueError("without a controller, give sample_time [s] (the output step)")
    else:
        T = check_positive("sample_time", sample_time, "s")
    duration = check_positive("duration", duration, "s")
    n_samples = sample_count(duration, T)
    if reference is not None and not callable(reference):
        raise TypeError(f"reference must be None or a function of the times [s]; got "
                        f"{type(reference).__name__}")
    if not isinstance(conservation, (bool, np.bool_)):
        raise TypeError(f"conservation must be True or False; got {type(conservation).__name__}")
    if n_samples < 2:
        raise ValueError(f"duration {duration!r} s must be at least one sample_time {T!r} s "
                         "(a slew's duration is 3 x slew_time by default)")
    frequencies = lay.spacecraft.modes()[0] if lay.n_bodies else np.zeros(1)
    w_max = float(np.max(frequencies))
    step = dynamics_step(w_max, T, dt, accurate_up_to=None if dt is not None else accurate_up_to)
    max_seconds = check_positive("max_seconds", max_seconds, "s")
    estimate = estimated_seconds(lay.n_bodies, duration, step, T)
    if estimate > max_seconds:
        work = (f"the Basilisk run would take about {estimate:.3g} s ({lay.n_bodies} spinning "
                f"bodies, {duration / step:.3g} RK4 steps of {step:.3g} s for the highest mode "
                f"{w_max:.4g} rad/s)")
        raise BasiliskRunTooLong(
            f"{work}, above max_seconds = {max_seconds:g} s: use a chain with fewer or softer "
            "bodies, a shorter duration, or raise max_seconds", work=work, estimate=estimate,
            limit=max_seconds, highest_frequency=w_max, step=step)
    initial_rate = _initial_rate(initial_rate, lay.three_axis)
    angles = _initial_angles(lay, initial_angles)
    times = np.arange(n_samples) * (nanoseconds(T, "sample_time") * _NANO)
    shape = times.shape + ((3,) if lay.three_axis else ())
    ref = np.zeros(shape) if reference is None else np.asarray(reference(times), dtype=float)
    if ref.shape != shape or not np.all(np.isfinite(ref)):
        what = "three finite angles [rad] (x, y, z)" if lay.three_axis else "one finite angle [rad]"
        raise ValueError(f"reference must give {what} per sample ({n_samples}); "
                         f"got shape {ref.shape}")
    pushes = disturbance_values(disturbances, times, lay.three_axis)
    if reaction_wheel is not None:
        if not isinstance(reaction_wheel, ReactionWheel):
            raise TypeError("reaction_wheel must be a spacecraft.basilisk.ReactionWheel; got "
                            f"{type(reaction_wheel).__name__}")
        if law is None:
            raise ValueError("a reaction wheel needs a controller to command it")
        if lay.three_axis and reaction_wheel.initial_speed != 0.0:
            raise BasiliskModelError(
                f"reaction_wheel.initial_speed must be 0 [rad/s] on a three-axis spacecraft; "
                f"got {reaction_wheel.initial_speed!r}: a spinning wheel's momentum h turns the "
                "hub's rates into torques omega x h, first order in the motion, which flexsat's "
                "linear plant (no wheel momentum) leaves out, so the comparison would not hold")

    run = _BasiliskRun(lay, law, ref, pushes, T, step, initial_rate, angles,
                       conservation, reaction_wheel)
    seconds = {"build": time.perf_counter() - t_build}
    t_run = time.perf_counter()
    run.execute(times[-1])
    seconds["run"] = time.perf_counter() - t_run
    response, out_of_plane, energy = run.collect(times, ref, pushes)
    return BasiliskResult(response, T, step, w_max, lay, law, version, seconds, out_of_plane,
                          energy)


class _BasiliskRun:
    """The Basilisk objects of one run, kept referenced for the run's life (SWIG ownership)."""

    def __init__(self, lay, law, ref, pushes, T, step, initial_rate, angles, conservation,
                 wheel):
        from Basilisk.simulation import (extForceTorque, reactionWheelStateEffector, spacecraft,
                                         spinningBodyNDOFStateEffector)
        from Basilisk.utilities import SimulationBaseClass

        self.lay, self.law = lay, law
        period, step_nanos = round(T * 1e9), round(step * 1e9)
        sim = SimulationBaseClass.SimBaseClass()
        process = sim.CreateNewProcess("flexsat")
        process.addTask(sim.CreateNewTask("dynamics", step_nanos), 100)
        process.addTask(sim.CreateNewTask("flight_software", period), 50)
        craft = spacecraft.Spacecraft()
        craft.ModelTag = "flexsat_hub"
        hub = lay.hub
        craft.hub.mHub = hub.mHub
        craft.hub.r_BcB_B = hub.r_BcB_B.reshape(3, 1).tolist()
        inertia = hub.IHubPntBc_B.copy()
        axes = ("x", "y", "z") if lay.three_axis else ("z",)
        if wheel is not None:
            # Basilisk's balanced wheel expects its rotor's spin inertia inside the hub's and
            # removes J_s g g^T itself (matrixD -= Js gsHat gsHat^T): add the rotor, a disc
            # (planar), or each wheel's J_s g g^T (three axes; see .actuators)
            inertia += triad_inertia(wheel) if lay.three_axis else rotor_inertia(wheel)
        craft.hub.IHubPntBc_B = inertia.tolist()
        rate = (np.asarray(initial_rate, dtype=float) if lay.three_axis
                else np.array([0.0, 0.0, initial_rate]))
        craft.hub.omega_BN_BInit = rate.reshape(3, 1).tolist()
        self.effectors, self.bodies = [], []
        for a in lay.appendages:
            if not a.bodies:
                self.effectors.append(None)
                continue
            effector = spinningBodyNDOFStateEffector.SpinningBodyNDOFStateEffector()
            effector.ModelTag = f"flexsat_{a.name}"
            for body, angle in zip(a.bodies, angles[a.name]):
                b = spinningBodyNDOFStateEffector.SpinningBody()
                b.setMass(body.mass)
                b.setISPntSc_S(body.ISPntSc_S.tolist())
                b.setDCM_S0P(body.dcm_S0P.tolist())
                b.setR_ScS_S(body.r_ScS_S.reshape(3, 1).tolist())
                b.setR_SP_P(body.r_SP_P.reshape(3, 1).tolist())
                b.setSHat_S(body.sHat_S.reshape(3, 1).tolist())
                b.setK(body.k)
                b.setC(body.c)
                b.setThetaInit(float(angle))
                effector.addSpinningBody(b)
                self.bodies.append(b)
            craft.addStateEffector(effector)
            self.effectors.append(effector)
        sim.AddModelToTask("dynamics", craft, 100)

        self.torque = self.wheel = None
        if law is not None:
            self.fsw = flight_software_class()(law, ref)
            self.fsw.ModelTag = "flexsat_flight_software"
            self.fsw.stateInMsg.subscribeTo(craft.scStateOutMsg)
            sim.AddModelToTask("flight_software", self.fsw, 30)
            # the actuator reads the command in the same task, after the law (see the docstring)
            if wheel is None:
                self.torque = extForceTorque.ExtForceTorque()
                self.torque.ModelTag = "flexsat_control_torque"
                craft.addDynamicEffector(self.torque)
                self.torque.cmdTorqueInMsg.subscribeTo(self.fsw.torqueOutMsg)
                sim.AddModelToTask("flight_software", self.torque, 20)
            else:
                self.wheel_configs = [wheel_config(wheel, axis) for axis in axes]
                self.wheel = reactionWheelStateEffector.ReactionWheelStateEffector()
                self.wheel.ModelTag = "flexsat_reaction_wheel"
                for config in self.wheel_configs:
                    self.wheel.addReactionWheel(config)
                if hasattr(self.wheel, "setMaxWheelAcceleration"):
                    self.wheel.setMaxWheelAcceleration(WHEEL_ACCELERATION_GUARD)
                craft.addStateEffector(self.wheel)
                self.wheel.rwMotorCmdInMsg.subscribeTo(self.fsw.motorTorqueOutMsg)
                sim.AddModelToTask("flight_software", self.wheel, 20)
        self.push = None
        if pushes:
            self.push = extForceTorque.ExtForceTorque()
            self.push.ModelTag = "flexsat_disturbance"
            craft.addDynamicEffector(self.push)
            self.schedule = _disturbance_class()(self.push, pushes, period, lay.three_axis)
            self.schedule.ModelTag = "flexsat_disturbance_schedule"
            sim.AddModelToTask("flight_software", self.schedule, 40)

        self.recorders = {"state": craft.scStateOutMsg.recorder(period)}
        if law is not None:
            self.recorders["torque"] = self.fsw.torqueOutMsg.recorder(period)
        if self.wheel is not None:
            self.recorders["wheel"] = self.wheel.rwSpeedOutMsg.recorder(period)
        for a, effector in zip(lay.appendages, self.effectors):
            if effector is not None:
                self.recorders[a.name] = [effector.spinningBodyOutMsgs[k].recorder(period)
                                          for k in range(len(a.bodies))]
        self.energy = None
        if conservation:
            self.energy = craft.logger(["totRotEnergy", "totRotAngMomPntC_N", "totOrbEnergy"],
                                       period)
        for value in self.recorders.values():
            for recorder in (value if isinstance(value, list) else [value]):
                sim.AddModelToTask("flight_software", recorder, 10)
        if self.energy is not None:
            sim.AddModelToTask("flight_software", self.energy, 10)
        self.sim, self.craft = sim, craft
        self._call(sim.InitializeSimulation)

    def _call(self, function, *args):
        """Run a Basilisk call; its BasiliskError (a model it rejects) becomes ours."""
        try:
            function(*args)
        except Exception as exc:
            if type(exc).__name__ != "BasiliskError":
                raise
            raise BasiliskModelError(f"Basilisk rejected the model: {exc}") from None

    def linearise(self, step: float) -> tuple[np.ndarray, list]:
        """Central differences of Basilisk's equations of motion about the initial state.

        States: hub position and velocity (of B, inertial axes), MRP and rate, then per
        effector the spin angles and rates. Returns (A, state names)."""
        dyn = self.craft.dynManager
        hub = self.craft.hub
        names = [(hub.nameOfHubPosition, "r_BN_N"), (hub.nameOfHubVelocity, "v_BN_N"),
                 (hub.nameOfHubSigma, "sigma_BN"), (hub.nameOfHubOmega, "omega_BN_B")]
        for a, effector in zip(self.lay.appendages, self.effectors):
            if effector is not None:
                names += [(effector.getNameOfThetaState(), f"{a.name}.theta"),
                          (effector.getNameOfThetaDotState(), f"{a.name}.thetaDot")]
        states = [dyn.getStateObject(name) for name, _ in names]
        base = [np.asarray(state.getState(), dtype=float) for state in states]
        sizes = [b.size for b in base]
        labels = []
        for (_, label), size in zip(names, sizes):
            labels += [f"{label}[{k}]" for k in range(size)]

        def derivative(x: np.ndarray) -> np.ndarray:
            offset = 0
            for state, b, size in zip(states, base, sizes):
                state.setState(x[offset:offset + size].reshape(b.shape).tolist())
                offset += size
            self._call(self.craft.equationsOfMotion, 0.0, 1.0)
            return np.concatenate([np.asarray(state.getStateDeriv(), dtype=float).ravel()
                                   for state in states])

        x0 = np.concatenate([b.ravel() for b in base])
        A = np.zeros((x0.size, x0.size))
        for k in range(x0.size):
            e = np.zeros(x0.size)
            e[k] = step
            A[:, k] = (derivative(x0 + e) - derivative(x0 - e)) / (2.0 * step)
        derivative(x0)
        return A, labels

    def execute(self, t_final: float) -> None:
        self.sim.ConfigureStopTime(round(t_final * 1e9))
        self._call(self.sim.ExecuteSimulation)

    def collect(self, times, ref, pushes):
        state = self.recorders["state"]
        n = times.size
        recorded = state.times()
        if recorded.size != n or np.any(recorded != np.round(times * 1e9).astype(recorded.dtype)):
            raise RuntimeError(f"Basilisk recorded {recorded.size} samples, expected {n} at the "
                               "flight-software instants")
        sigma = np.asarray(state.sigma_BN, dtype=float).reshape(n, 3)
        rate = np.asarray(state.omega_BN_B, dtype=float).reshape(n, 3)
        if self.lay.three_axis:
            return self._collect_three_axis(times, ref, pushes, sigma, rate)
        rows, labels = [], []
        theta = np.unwrap(4.0 * np.arctan(sigma[:, 2]))
        rows += [theta, rate[:, 2]]
        labels += ["theta", "omega"]
        for a in self.lay.appendages:
            if a.bodies:
                rows.append(a.tip_deflection(self._angles(a, n)))
            else:
                rows.append(np.zeros(n))
            labels.append(f"{a.name}_tip_deflection")
        if self.law is not None:
            torque = np.asarray(self.recorders["torque"].torqueRequestBody, dtype=float)
            rows.append(torque.reshape(n, 3)[:, 2])
            labels.append("torque")
        if self.wheel is not None:
            speeds = np.asarray(self.recorders["wheel"].wheelSpeeds, dtype=float)
            rows.append(speeds.reshape(n, -1)[:, 0])
            labels.append("wheel_speed")
        outputs = np.vstack(rows)
        self._check_finite(outputs, times)
        out_of_plane = float(max(np.abs(sigma[:, :2]).max(), np.abs(rate[:, :2]).max()))
        inputs = np.vstack([ref] + [pushes[name] for name in pushes])
        response = control.TimeResponseData(
            times, outputs, inputs=inputs, output_labels=labels,
            input_labels=["theta_ref"] + list(pushes), issiso=False, sysname="basilisk")
        return response, out_of_plane, self._energy()

    def _angles(self, appendage, n: int) -> np.ndarray:
        """The recorded spin angles of an appendage's bodies (n, n_bodies) [rad]."""
        return np.column_stack([np.asarray(r.theta, dtype=float).reshape(n)
                                for r in self.recorders[appendage.name]])

    @staticmethod
    def _check_finite(outputs: np.ndarray, times: np.ndarray) -> None:
        bad = ~np.all(np.isfinite(outputs), axis=0)
        if np.any(bad):
            k = int(np.flatnonzero(bad)[0])
            raise BasiliskIntegrationError(
                f"Basilisk's integration diverged: non-finite states at t = {times[k]:.6g} s "
                "(an RK4 step too long for the chain's highest mode, or an unstable loop)")

    def _collect_three_axis(self, times, ref, pushes, sigma, rate):
        """The three-axis outputs (module docstring) from the recorded states."""
        n = times.size
        if not (np.all(np.isfinite(sigma)) and np.all(np.isfinite(rate))):
            self._check_finite(np.vstack([sigma.T, rate.T]), times)
        theta = np.zeros((n, 3))
        previous = np.zeros(3)
        for k in range(n):  # unwrapped sample by sample, as the flight software does
            theta[k] = previous = rotation_vector(sigma[k], previous)
        rows = [theta.T, rate.T]
        labels = [f"theta_{a}" for a in "xyz"] + [f"omega_{a}" for a in "xyz"]
        for a in self.lay.appendages:
            motions = (a.tip_motions(self._angles(a, n)) if a.bodies else np.zeros((n, 3)))
            rows.append(motions.T)
            labels += [f"{a.name}_tip_deflection_y", f"{a.name}_tip_deflection_z",
                       f"{a.name}_tip_twist"]
        if self.law is not None:
            torque = np.asarray(self.recorders["torque"].torqueRequestBody, dtype=float)
            rows.append(torque.reshape(n, 3).T)
            labels += list(TORQUES_3)
        if self.wheel is not None:
            speeds = np.asarray(self.recorders["wheel"].wheelSpeeds, dtype=float)
            rows.append(speeds.reshape(n, -1)[:, :3].T)
            labels += [f"wheel_speed_{a}" for a in "xyz"]
        outputs = np.vstack(rows)
        self._check_finite(outputs, times)
        inputs = np.vstack([ref.T] + [pushes[name] for name in pushes])
        response = control.TimeResponseData(
            times, outputs, inputs=inputs, output_labels=labels,
            input_labels=[f"theta_ref_{a}" for a in "xyz"] + list(pushes), issiso=False,
            sysname="basilisk")
        return response, math.nan, self._energy()

    def _energy(self) -> dict | None:
        if self.energy is None:
            return None
        return {"time": self.energy.times() * _NANO,
                "rotational_energy": np.asarray(self.energy.totRotEnergy, dtype=float),
                "angular_momentum": np.asarray(self.energy.totRotAngMomPntC_N,
                                               dtype=float).reshape(-1, 3),
                "orbital_energy": np.asarray(self.energy.totOrbEnergy, dtype=float)}


@functools.cache
def _disturbance_class():
    """SysModel that sets the disturbance effector's torque and force at each sample."""
    from Basilisk.architecture import sysModel

    class DisturbanceSchedule(sysModel.SysModel):
        def __init__(self, effector, values: dict, period: int, three_axis: bool = False):
            super().__init__()
            self.effector, self.values, self.period = effector, values, period
            self.three_axis = three_axis

        def UpdateState(self, CurrentSimNanos):
            k = CurrentSimNanos // self.period
            get = {name: float(v[min(k, v.size - 1)]) for name, v in self.values.items()}
            if self.three_axis:
                self.effector.extTorquePntB_B = [[get.get(f"disturbance_torque_{a}", 0.0)]
                                                 for a in "xyz"]
                self.effector.extForce_B = [[get.get(f"force_{a}", 0.0)] for a in "xyz"]
                return
            self.effector.extTorquePntB_B = [[0.0], [0.0], [get.get("disturbance_torque", 0.0)]]
            self.effector.extForce_B = [[get.get("force_x", 0.0)], [get.get("force_y", 0.0)],
                                        [0.0]]

    return DisturbanceSchedule


@dataclasses.dataclass
class LinearisedModel:
    """Basilisk's equations of motion of a spacecraft linearised about rest.

    Attributes
    ----------
    A : ndarray (n, n)
        ``x' = A x`` with x the Basilisk states in :attr:`states` (SI, MRPs for the attitude).
    states : list of str
        ``r_BN_N[k]``, ``v_BN_N[k]`` [m, m/s], ``sigma_BN[k]`` [-], ``omega_BN_B[k]`` [rad/s],
        then per chain ``<name>.theta[k]`` [rad] and ``<name>.thetaDot[k]`` [rad/s].
    layout : SpacecraftLayout
    bsk_version : str
    """

    A: np.ndarray
    states: list
    layout: SpacecraftLayout
    bsk_version: str

    def elastic_eigenvalues(self) -> np.ndarray:
        """The eigenvalues of A [rad/s] without the free-floating rigid-body ones (two zeros for
        each of the 6 rigid motions: 12, of a planar spacecraft too, whose Basilisk model
        moves in three dimensions), sorted by imaginary part."""
        lam = np.linalg.eigvals(self.A)
        lam = lam[np.argsort(np.abs(lam))][12:]
        return lam[np.lexsort((lam.real, lam.imag))]


#: Central-difference step of :func:`linearised` (rad, m, rad/s, m/s and MRP alike): the
#: truncation error is step**2 times the third derivatives (1e-12 relative), the rounding error
#: eps times |A| (the equations are evaluated at states of size step).
LINEARISATION_STEP = 1e-6


def linearised(spacecraft: Spacecraft, *, chains: Mapping | None = None,
               step: float = LINEARISATION_STEP) -> LinearisedModel:
    """Basilisk's own model of a spacecraft, linearised about rest by central differences.

    The spacecraft is laid out (:func:`.layout`) and built in Basilisk as :func:`simulate`
    builds it (no controller), then its equations of motion (``Spacecraft.equationsOfMotion``:
    the hub and every spinning body, back-substituted) are evaluated at the undeformed state
    plus and minus ``step`` in each state: ``A[:, k] = (f(x + h e_k) - f(x - h e_k)) / 2h``,
    exact for the linear part up to the third-order terms (the equations are smooth; the
    second-order ones cancel). Its eigenvalues are the modes Basilisk integrates, to be set
    against flexsat's linear model of the same chains (:attr:`SpacecraftLayout.spacecraft`).

    Parameters
    ----------
    spacecraft : Spacecraft
    chains : mapping name -> HingedChain, optional
        As for :func:`simulate`.
    step : float
        Difference step (positive; default :data:`LINEARISATION_STEP`).

    Returns
    -------
    LinearisedModel
    """
    version = require_basilisk()
    lay = layout(spacecraft, chains=chains)
    step = check_positive("step", step, "-")
    angles = _initial_angles(lay, None)
    rate = np.zeros(3) if lay.three_axis else 0.0
    run = _BasiliskRun(lay, None, np.zeros(2), {}, 1.0, 1.0, rate, angles, False, None)
    A, states = run.linearise(step)
    return LinearisedModel(A, states, lay, version)


def slew_reference(angle: float, slew_time: float, axis=None
                   ) -> Callable[[np.ndarray], np.ndarray]:
    """theta_ref(t) of a cycloidal slew (:func:`controllers.slew_profile`) for
    :func:`simulate`: planar (``axis`` None) the profile, three axes the eigen-axis slew
    ``e * profile(t)``, an (n, 3) array (e the unit ``axis``, hub axes)."""
    import controllers

    if isinstance(angle, bool) or not isinstance(angle, (int, float, np.integer, np.floating)) \
            or not math.isfinite(angle) or angle == 0:
        raise ValueError(f"angle must be non-zero and finite [rad]; got {angle!r}")
    slew_time = check_positive("slew_time", slew_time, "s")
    if axis is None:
        return lambda t: controllers.slew_profile(t, float(angle), slew_time)
    e = _unit_axis(axis)
    return lambda t: np.outer(controllers.slew_profile(t, float(angle), slew_time), e)


def _unit_axis(axis) -> np.ndarray:
    """The unit vector of a slew axis: 'x', 'y', 'z' or three finite numbers, not zero."""
    if isinstance(axis, str):
        if axis not in ("x", "y", "z"):
            raise ValueError(f"axis must be 'x', 'y', 'z' or three numbers (hub axes); got "
                             f"{axis!r:.60}")
        return np.eye(3)["xyz".index(axis)]
    try:
        e = np.asarray(axis, dtype=float)
    except (TypeError, ValueError):
        e = None
    if e is None or e.shape != (3,) or not np.all(np.isfinite(e)) or not np.any(e):
        raise ValueError(f"axis must be 'x', 'y', 'z' or three finite numbers, not all zero "
                         f"(the slew's eigen-axis, hub axes); got {axis!r:.100}")
    return e / np.linalg.norm(e)


def simulate_slew(spacecraft: Spacecraft, controller: control.StateSpace, angle: float,
                  slew_time: float, *, duration: float | None = None,
                  sample_time: float | None = None, dt: float | None = None,
                  chains: Mapping | None = None, disturbances: Mapping | None = None,
                  reaction_wheel: ReactionWheel | None = None,
                  max_seconds: float = MAX_SECONDS, axis=None, rigid_above: float | None = None,
                  accurate_up_to: float | None = None) -> BasiliskResult:
    """A cycloidal slew (:func:`controllers.slew_profile`) of the spacecraft in Basilisk.

    Parameters
    ----------
    spacecraft, controller, sample_time, dt, chains, disturbances, reaction_wheel, max_seconds,
    rigid_above, accurate_up_to
        As for :func:`simulate`.
    angle : float, rad
        Slew angle (non-zero, finite).
    slew_time : float, s
        Duration of the reference profile.
    duration : float, s, optional
        Simulated time; default 3 * slew_time (as :func:`controllers.slew`).
    axis : {'x', 'y', 'z'} or sequence of 3 floats, optional
        Three-axis spacecraft only (and required there): the slew's eigen-axis e, hub axes
        (as :func:`controllers.slew`).

    Returns
    -------
    BasiliskResult
        ``response`` has the closed-loop signal names of flexsat (``theta``, ``omega``,
        ``<name>_tip_deflection``, ``torque``; three axes per axis) at the flight-software
        instants.
    """
    if isinstance(angle, bool) or not isinstance(angle, (int, float, np.integer, np.floating)) \
            or not math.isfinite(angle) or angle == 0:
        raise ValueError(f"angle must be non-zero and finite [rad]; got {angle!r}")
    slew_time = check_positive("slew_time", slew_time, "s")
    duration = default_duration(slew_time, duration)
    _check_axis(spacecraft, axis)
    return simulate(spacecraft, controller, duration=duration, sample_time=sample_time, dt=dt,
                    chains=chains, disturbances=disturbances, reaction_wheel=reaction_wheel,
                    max_seconds=max_seconds, rigid_above=rigid_above,
                    accurate_up_to=accurate_up_to,
                    reference=slew_reference(angle, slew_time, axis))


def _check_axis(spacecraft, axis) -> None:
    """A slew axis is given for a three-axis spacecraft and only there."""
    three_axis = bool(getattr(spacecraft, "three_axis", False))
    if three_axis and axis is None:
        raise ValueError("axis is required for a three-axis spacecraft: the slew's eigen-axis "
                         "('x', 'y', 'z' or three numbers, hub axes)")
    if not three_axis and axis is not None:
        raise ValueError(f"axis is for three-axis spacecraft; a planar one slews about z (got "
                         f"axis {axis!r:.60})")
