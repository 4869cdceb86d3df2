"""The manoeuvre as flown, read from a scene: the loop delay, the slew profile and its
feedforward, the reaction wheels and the sensor noise.

The keys (units in the file; the module table of :mod:`spacecraft.scene.read` lists them with
the others, table "Ranges" their accepted values):

- ``controller.delay`` [s], the loop delay (computation plus transport), and
  ``controller.computation_delay`` (true: one sample of a digital controller added to it);
- ``manoeuvre.profile`` (``"step"``, ``"bang-coast-bang"``, ``"smooth"``, ``"shaped"``) with
  ``manoeuvre.torque_limit`` [N m], ``rate_limit`` [deg/s], ``jerk_limit`` [deg/s^3], the
  ``[manoeuvre.shaper]`` table (``kind``, ``modes``, ``base``, ``frequency_error``,
  ``tolerance``) and ``manoeuvre.feedforward``;
- ``[wheels]``: ``torque_limit`` [N m], ``momentum_limit`` [N m s], ``spin_inertia``
  [kg m^2], ``viscous_friction`` [N m s/rad], ``coulomb_friction`` [N m] (a number for every
  wheel, or one per wheel), three axes ``spin_axes`` (hub axes) or ``[wheels.pyramid]``
  (``cant_angle``, ``azimuth`` [deg]), ``saturation``;
- ``[sensors]``: ``attitude_density`` [rad/sqrt(Hz)] (or ``attitude_rms`` [rad] at
  ``attitude_rate`` [Hz]), ``angle_random_walk`` [rad/sqrt(s)], ``bias_instability`` [rad/s]
  with ``bias_correlation_time`` [s] (a number for every axis, or three), ``rpe_window`` [s],
  ``placement``, ``probability``.

What needs the spacecraft's models is checked when the run builds them
(:mod:`spacecraft.design.manoeuvre`): a profile's limits against the slew time with the
spacecraft's inertia, the wheels' shortest slew time, the shaper's length. Everything else is
checked here, by key: a value outside its range, a key that does not apply to the profile or
controller given, wheel axes that do not span the hub's axes, noise levels with the wrong sign,
an RPE window that is not a whole number of a digital controller's samples; values that look
like unit slips (a delay of 50 s, a noise density in arcsec/sqrt(Hz)) are warned about.

The functions take the scene reader ``r`` of :mod:`spacecraft.scene.reader` (its ``number``,
``boolean``, ``choice``, ``table``, ``take``, ``done``, ``warn`` and ``error``).
"""

from __future__ import annotations

import math
import warnings

from appendages.unit_slips import radians_in_degrees
from controllers.delay import PLAUSIBLE_DELAY, long_delay
from controllers.noise import PLAUSIBLE as NOISE_PLAUSIBLE

from .specs import SensorsSpec, ShaperSpec, WheelsSpec

__all__ = ["PROFILES", "SHAPERS", "SHAPER_BASES", "SATURATIONS", "PLACEMENTS",
           "PLAUSIBLE_DELAY", "read_delay", "read_profile", "read_wheels", "read_sensors",
           "check_flown_scene", "flown_plots", "shaper_band", "MANOEUVRE_KEYS"]

#: Reference profiles (``manoeuvre.profile``; :data:`controllers.PROFILE_KINDS`).
PROFILES = ("step", "bang-coast-bang", "smooth", "shaped")
#: Input shapers (``manoeuvre.shaper.kind``): zero vibration, and zero vibration and
#: derivative (:func:`controllers.mode_shaper`).
SHAPERS = ("zv", "zvd")
#: Profiles a shaper is convolved with (``manoeuvre.shaper.base``).
SHAPER_BASES = ("bang-coast-bang", "smooth")
#: Torque saturation rules of a wheel set (``wheels.saturation``).
SATURATIONS = ("scale", "clip")
#: Where t lies in its RPE window (``sensors.placement``; :data:`controllers.pointing.PLACEMENTS`).
PLACEMENTS = ("random", "end")
#: The keys of the manoeuvre table this module reads.
MANOEUVRE_KEYS = ("profile", "feedforward", "torque_limit", "rate_limit", "jerk_limit",
                  "shaper")

# sensor levels above these look like a unit slip (controllers.noise.PLAUSIBLE; an rms per
# sample as the density)
_SENSOR_PLAUSIBLE = {**NOISE_PLAUSIBLE,
                     "attitude_rms": (NOISE_PLAUSIBLE["attitude_density"][0], "arcsec or deg")}
_SENSOR_UNITS = {"attitude_density": "rad/sqrt(Hz)", "attitude_rms": "rad",
                 "angle_random_walk": "rad/sqrt(s)", "bias_instability": "rad/s"}


# --------------------------------------------------------------------------------------------
# controller.delay
# --------------------------------------------------------------------------------------------
def read_delay(r, t: dict, path: str, sample_time: float | None) -> tuple[float, bool]:
    """``controller.delay`` [s] (default 0) and ``controller.computation_delay`` (default
    false; a digital controller's only)."""
    delay = r.number(t, "delay", path, "controller.delay", default=0.0)
    # the rule of the Python API's functions (above controllers.PLAUSIBLE_DELAY); the run
    # passes this value to them with their warning silenced (specs.quiet_unit_slips)
    r.warn(f"{path}.delay", long_delay(delay))
    computation = r.boolean(t, "computation_delay", path, False)
    if computation and sample_time is None:
        raise r.error(f"{path}.computation_delay", "is one sample of a digital controller, and "
                      "this one is continuous: give controller.sample_rate [Hz], or put the "
                      "delay in controller.delay [s]")
    return delay, computation


# --------------------------------------------------------------------------------------------
# manoeuvre.profile
# --------------------------------------------------------------------------------------------
def shaper_band(kind: str, tolerance: float) -> float:
    """Half-width of the frequency band, as a fraction of the mode's frequency, in which an
    undamped mode's residual vibration after the shaper stays at or below ``tolerance``:
    ZV: V = |cos(pi r / 2)|, so (2 / pi) asin(tolerance); ZVD: V = cos^2(pi r / 2), so
    (2 / pi) asin(sqrt(tolerance)) (r = w / w_n; Singer & Seering 1990; 3.2 % and 14.4 % at
    5 %)."""
    level = tolerance if kind == "zv" else math.sqrt(tolerance)
    return 2.0 / math.pi * math.asin(level)


def _read_shaper(r, data, path: str, jerk_limit) -> ShaperSpec:
    t = r.table(data, path)
    kind_given = "kind" in t
    kind = r.choice(t, "kind", path, SHAPERS, default="zvd")
    modes = r.integer(t, "modes", path, minimum=1, default=1)
    if modes > 8:
        raise r.error(f"{path}.modes", f"must be at most 8 (each mode's shaper lengthens the "
                      f"profile by half its period or more, and the shapers' impulses multiply: "
                      f"2^8 to 3^8 of them); got {modes}")
    base = r.choice(t, "base", path, SHAPER_BASES, default="bang-coast-bang")
    error = r.number(t, "frequency_error", path, "shaper.frequency_error", default=None)
    tolerance = r.number(t, "tolerance", path, "shaper.tolerance", default=0.05)
    r.done(t, path, {"kind", "modes", "base", "frequency_error", "tolerance"})
    if base == "bang-coast-bang" and jerk_limit is not None:
        raise r.error("manoeuvre.jerk_limit", "applies to a 'smooth' profile or base (a "
                      "bang-coast-bang profile's acceleration jumps): set manoeuvre.shaper.base "
                      "= 'smooth' or remove manoeuvre.jerk_limit")
    if error is not None:
        bands = {k: shaper_band(k, tolerance) for k in SHAPERS}
        if not kind_given:
            # the shortest shaper that holds the band: ZV (half a period) before ZVD (one)
            fits = [k for k in SHAPERS if bands[k] >= error]
            if not fits:
                raise r.error(f"{path}.frequency_error", f"+-{100 * error:.4g} % is beyond what "
                              f"the shapers hold at a residual vibration of "
                              f"{100 * tolerance:.4g} % (ZV +-{100 * bands['zv']:.3g} %, ZVD "
                              f"+-{100 * bands['zvd']:.3g} %, undamped mode): ask for less, or "
                              "allow more residual vibration (tolerance)")
            kind = fits[0]
        elif bands[kind] < error:
            raise r.error(f"{path}.frequency_error", f"+-{100 * error:.4g} % is beyond what a "
                          f"{kind.upper()} shaper holds at a residual vibration of "
                          f"{100 * tolerance:.4g} % (+-{100 * bands[kind]:.3g} %, undamped "
                          f"mode); choose kind = 'zvd' (+-{100 * bands['zvd']:.3g} %), or "
                          "allow more residual vibration (tolerance)")
    return ShaperSpec(kind, modes, base, error, tolerance)


def read_profile(r, t: dict, path: str) -> dict:
    """The profile keys of a manoeuvre table (:data:`MANOEUVRE_KEYS`) as ManoeuvreSpec fields
    (SI: the rate and jerk limits from deg/s and deg/s^3 to rad/s and rad/s^3)."""
    profile = r.choice(t, "profile", path, PROFILES, default="step")
    feedforward = r.boolean(t, "feedforward", path, False)
    torque_limit = r.number(t, "torque_limit", path, "manoeuvre.torque_limit", default=None)
    rate = r.number(t, "rate_limit", path, "manoeuvre.rate_limit", default=None)
    jerk = r.number(t, "jerk_limit", path, "manoeuvre.jerk_limit", default=None)
    if rate is not None and radians_in_degrees(rate) is not None:
        r.warn(f"{path}.rate_limit", f"did you give rad/s? {rate:g} rad/s = "
               f"{math.degrees(rate):.4g} deg/s (the key is in deg/s)")
    given = [k for k, v in (("torque_limit", torque_limit), ("rate_limit", rate),
                            ("jerk_limit", jerk)) if v is not None]
    shaper = None
    if profile == "step":
        if given or "shaper" in t:
            key = given[0] if given else "shaper"
            raise r.error(f"{path}.{key}", "applies to the profiles 'bang-coast-bang', "
                          "'smooth' and 'shaped'; the 'step' reference (the default "
                          "manoeuvre.profile) is the cycloid of slew_time: set "
                          "manoeuvre.profile")
        if feedforward:
            raise r.error(f"{path}.feedforward", "needs a profile with a rate and an "
                          "acceleration to feed ('bang-coast-bang', 'smooth' or 'shaped'); the "
                          "'step' reference (the default manoeuvre.profile) is theta_ref alone")
    elif profile == "shaped":
        shaper = _read_shaper(r, t.pop("shaper", {}), f"{path}.shaper", jerk)
    else:
        if "shaper" in t:
            raise r.error(f"{path}.shaper", f"applies to manoeuvre.profile = 'shaped'; got "
                          f"{profile!r}")
        if profile == "bang-coast-bang" and jerk is not None:
            raise r.error(f"{path}.jerk_limit", "applies to the 'smooth' profile (a "
                          "bang-coast-bang profile's acceleration jumps: unbounded jerk)")
    return {"profile": profile, "feedforward": feedforward, "torque_limit": torque_limit,
            "rate_limit": None if rate is None else math.radians(rate),
            "jerk_limit": None if jerk is None else math.radians(jerk), "shaper": shaper}


# --------------------------------------------------------------------------------------------
# [wheels]
# --------------------------------------------------------------------------------------------
def _per_wheel(r, t: dict, key: str, path: str, kind: str, default):
    """A number (every wheel) or an array of numbers (one per wheel) of ``RANGES[kind]``."""
    value, full = r.take(t, key, path, default)
    if value is default:
        return value
    if isinstance(value, (list, tuple)):
        return r.vector({key: value}, key, path, kind, limit="appendages")
    return r.check_number(value, full, kind)


def read_wheels(r, data, path: str, three_axis: bool) -> WheelsSpec:
    """The ``[wheels]`` table: built once here (:class:`controllers.WheelSet`) so that axes
    that do not span, or friction the wheel cannot have, are refused by key."""
    t = r.table(data, path)
    values = {}
    for key, kind, default in (("torque_limit", "wheels.torque_limit", None),
                               ("momentum_limit", "wheels.momentum_limit", None),
                               ("spin_inertia", "wheels.spin_inertia", None),
                               ("viscous_friction", "wheels.viscous_friction", 0.0),
                               ("coulomb_friction", "wheels.coulomb_friction", 0.0)):
        if default is None and key in ("torque_limit", "momentum_limit") and key not in t:
            r.take(t, key, path)     # missing required value, with a typo's hint
        values[key] = _per_wheel(r, t, key, path, kind, default)
    saturation = r.choice(t, "saturation", path, SATURATIONS, default="scale")
    spin_axes = pyramid = None
    if three_axis:
        if ("spin_axes" in t) == ("pyramid" in t):
            raise r.error(path, "a three-axis scene needs the wheels' spin axes: give "
                          "spin_axes (an array of [x, y, z], one per wheel, hub axes) or a "
                          "[wheels.pyramid] table (four wheels about +z), not both")
        if "spin_axes" in t:
            value, full = r.take(t, "spin_axes", path)
            if not isinstance(value, (list, tuple)) or not value:
                raise r.error(full, "must be an array of [x, y, z] spin axes, one per wheel "
                              "(hub axes)")
            r.check_limit(full, len(value), "appendages", f"{len(value)} wheels")
            spin_axes = tuple(_axis(r, axis, f"{full}[{k}]") for k, axis in enumerate(value))
        else:
            p = f"{path}.pyramid"
            pt = r.table(t.pop("pyramid"), p)
            beta = r.number(pt, "cant_angle", p, "wheels.cant_angle", default=math.degrees(
                math.acos(1.0 / math.sqrt(3.0))))
            r.warn(f"{p}.cant_angle", radians_in_degrees(beta))
            azimuth = r.number(pt, "azimuth", p, "wheels.azimuth", default=0.0)
            r.done(pt, p, {"cant_angle", "azimuth"})
            pyramid = (math.radians(beta), math.radians(azimuth))
    else:
        for key in ("spin_axes", "pyramid"):
            if key in t:
                raise r.error(f"{path}.{key}", "applies to three-axis scenes (hub.inertia a "
                              "3x3 tensor); a planar scene has one wheel about the hub's z axis")
    r.done(t, path, {"torque_limit", "momentum_limit", "spin_inertia", "viscous_friction",
                     "coulomb_friction", "saturation", "spin_axes", "pyramid"})
    spec = WheelsSpec(spin_axes=spin_axes, pyramid=pyramid, saturation=saturation, **values)
    n = spec.n_wheels
    for key in ("torque_limit", "momentum_limit", "spin_inertia", "viscous_friction",
                "coulomb_friction"):
        value = values[key]
        if isinstance(value, tuple) and len(value) != n:
            what = ("the one wheel of a planar scene" if n == 1 else
                    "the pyramid's four wheels" if pyramid is not None else
                    f"the {n} spin_axes")
            raise r.error(f"{path}.{key}", f"must be one number (every wheel) or one per wheel: "
                          f"{n} for {what}; got {len(value)}")
    for k in range(n):
        if spec.value("viscous_friction", k) > 0 and spec.value("spin_inertia", k) is None:
            raise r.error(f"{path}.viscous_friction", "needs the wheel's speed: give "
                          "wheels.spin_inertia [kg m^2] (viscous friction is c_v Omega, Omega = "
                          "h / J_s)")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            spec.build()
        except ValueError as exc:
            key = "spin_axes" if spin_axes is not None else "pyramid.cant_angle" \
                if pyramid is not None else ""
            raise r.error(f"{path}.{key}" if key else path, str(exc)) from None
    for w in caught:
        message = " ".join(str(w.message).split())
        key = ("torque_limit" if message.startswith("torque_limit") else
               "spin_axes" if spin_axes is not None else "pyramid.cant_angle")
        r.warn(f"{path}.{key}", message)
    return spec


def _axis(r, value, full: str) -> tuple:
    """One spin axis: three numbers, not all zero (normalised by WheelSet)."""
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise r.error(full, "must be an array of 3 numbers [x, y, z] (hub axes)")
    axis = tuple(r.check_number(v, f"{full}[{i}]", "wheels.spin_axes")
                 for i, v in enumerate(value))
    if not any(axis):
        raise r.error(full, "must be a non-zero vector (hub axes); got [0, 0, 0]")
    return axis


# --------------------------------------------------------------------------------------------
# [sensors]
# --------------------------------------------------------------------------------------------
def _level(r, t: dict, key: str, path: str, three_axis: bool, default=0.0):
    """A noise level: a number (every axis) or three (x, y, z; three-axis scenes), >= 0."""
    value, full = r.take(t, key, path, default)
    if value is default:
        return value
    unit = _SENSOR_UNITS.get(key, "s")
    items = value if isinstance(value, (list, tuple)) else None
    if items is not None:
        if not three_axis:
            raise r.error(full, f"must be one number [{unit}] in a planar scene (three values "
                          "are for the axes x, y, z of a three-axis scene)")
        if len(items) != 3:
            raise r.error(full, f"must be one number or three (x, y, z) [{unit}]; got "
                          f"{len(items)}")
    out = []
    for k, v in enumerate(items if items is not None else [value]):
        where = f"{full}[{k}]" if items is not None else full
        if (isinstance(v, (int, float)) and not isinstance(v, bool) and v < 0
                and key in _SENSOR_UNITS):
            raise r.error(where, f"must be non-negative [{unit}] (the square root of a noise "
                          f"intensity, or a standard deviation); got {v!r}: a sign slip?")
        number = r.check_number(v, where, f"sensors.{key}")
        if key in _SENSOR_PLAUSIBLE and number > _SENSOR_PLAUSIBLE[key][0]:
            r.warn(where, f"{number:g} {unit} is large for a spacecraft sensor: was it given in "
                   f"{_SENSOR_PLAUSIBLE[key][1]}? It is used as {unit}")
        out.append(number)
    return tuple(out) if items is not None else out[0]


def _positive_levels(value) -> bool:
    return any(v > 0 for v in (value if isinstance(value, tuple) else (value,)))


def read_sensors(r, data, path: str, three_axis: bool,
                 sample_time: float | None) -> SensorsSpec:
    """The ``[sensors]`` table; the attitude sensor as a density, or as an rms per sample at
    its rate (density = rms / sqrt(rate), :meth:`controllers.SensorNoise.from_rms`)."""
    t = r.table(data, path)
    if "attitude_density" in t and ("attitude_rms" in t or "attitude_rate" in t):
        raise r.error(f"{path}.attitude_rms", "give the attitude sensor's noise as "
                      "attitude_density [rad/sqrt(Hz)] or as attitude_rms [rad] with "
                      "attitude_rate [Hz], not both")
    if "attitude_rms" in t or "attitude_rate" in t:
        rms = _level(r, t, "attitude_rms", path, three_axis, default=None)
        if rms is None:
            r.take(t, "attitude_rms", path)       # missing, with a typo's hint
        rate = r.number(t, "attitude_rate", path, "sensors.attitude_rate")
        density = (tuple(v / math.sqrt(rate) for v in rms) if isinstance(rms, tuple)
                   else rms / math.sqrt(rate))
    else:
        density = _level(r, t, "attitude_density", path, three_axis)
    walk = _level(r, t, "angle_random_walk", path, three_axis)
    bias = _level(r, t, "bias_instability", path, three_axis)
    tau = None
    if "bias_correlation_time" in t:
        tau = _level(r, t, "bias_correlation_time", path, three_axis, default=None)
        if not _positive_levels(bias):
            raise r.error(f"{path}.bias_correlation_time", "is given without a "
                          "bias_instability [rad/s]: give both or neither")
        for v in (tau if isinstance(tau, tuple) else (tau,)):
            if v <= 0:
                raise r.error(f"{path}.bias_correlation_time", "must be positive [s]; got 0")
    elif _positive_levels(bias):
        raise r.error(f"{path}.bias_correlation_time", "missing: the gyro bias's correlation "
                      "time [s] (a first-order Gauss-Markov process) must be given with "
                      "bias_instability")
    window = r.number(t, "rpe_window", path, "sensors.rpe_window")
    placement = r.choice(t, "placement", path, PLACEMENTS, default="random")
    probability = r.number(t, "probability", path, "sensors.probability", default=0.9973)
    r.done(t, path, {"attitude_density", "attitude_rms", "attitude_rate", "angle_random_walk",
                     "bias_instability", "bias_correlation_time", "rpe_window", "placement",
                     "probability"})
    if sample_time is not None:
        n = window / sample_time
        if abs(n - round(n)) > 1e-9 * n or round(n) < 1:
            raise r.error(f"{path}.rpe_window", f"must be a whole number of the digital "
                          f"controller's samples (1/sample_rate = {sample_time:g} s) [s]; got "
                          f"{window:g} ({n:.6g} samples)")
    if not any(_positive_levels(v) for v in (density, walk, bias)):
        raise r.error(path, "gives no noise: set attitude_density (or attitude_rms), "
                      "angle_random_walk or bias_instability, or remove the table")
    return SensorsSpec(density, walk, bias, tau, window, placement, probability)


# --------------------------------------------------------------------------------------------
# the scene as a whole
# --------------------------------------------------------------------------------------------
def flown_plots(r, plots: tuple, all_plots: bool, *, manoeuvre, wheels, simulator) -> tuple:
    """``report.plots`` with the flown plots: ``plots = true`` draws ``"profile"`` only for a
    flown profile and ``"wheels"`` only with wheels (flexsat's or Basilisk's); asked by name
    without them, refused by key."""
    has_wheels = wheels is not None or simulator.reaction_wheel is not None
    flown = manoeuvre is not None and manoeuvre.flown
    if all_plots:
        return tuple(p for p in plots if (p != "profile" or flown)
                     and (p != "wheels" or has_wheels))
    if "profile" in plots and manoeuvre is None:
        raise r.error("report.plots", "asks for 'profile' but the scene has no manoeuvre table")
    if "wheels" in plots and not has_wheels:
        raise r.error("report.plots", "asks for 'wheels' but the scene has none: give a "
                      "[wheels] table (or simulator.reaction_wheel for Basilisk)")
    return plots


def check_flown_scene(r, *, controller, manoeuvre, wheels, sensors, simulator, export,
                      three_axis: bool) -> None:
    """Cross-checks of the flown keys against the rest of the scene, by key."""
    flown = manoeuvre is not None and manoeuvre.flown
    if manoeuvre is None:
        if wheels is not None:
            raise r.error("wheels", "the wheels fly the manoeuvre: the scene needs a "
                          "manoeuvre table")
    if flown and manoeuvre.feedforward and controller.given is not None:
        raise r.error("manoeuvre.feedforward", "needs controllers tuned to take the rate "
                      "reference and the feedforward torque; controller.given reads "
                      "theta_ref, theta and omega only: set feedforward = false or tune the "
                      "controller")
    if simulator.name == "basilisk":
        for key, asked in (("manoeuvre.profile", flown and manoeuvre.profile != "step"),
                           ("manoeuvre.feedforward", flown and manoeuvre.feedforward),
                           ("controller.delay", controller.total_delay > 0)):
            if asked:
                raise r.error(key, "Basilisk's flight software runs the step reference "
                              "without feedforward or delay; drop simulator.name = 'basilisk' "
                              "(flexsat flies this manoeuvre itself) or the key")
    if export.fmu and controller.total_delay > 0 and "closed_loop" in export.systems:
        raise r.error("export.systems", "a closed-loop FMU has no loop delay "
                      f"(controller.delay = {controller.delay:g} s): export 'plant' and "
                      "'controller' (a co-simulation applies the delay between them), or set "
                      "controller.delay = 0")
