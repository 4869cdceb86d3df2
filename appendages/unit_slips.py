"""Values that look like a unit slip: legal, but more likely a mistake than meant.

flexsat works in SI units (angles in rad in Python, in deg in scene files). A value inside its
documented range can still be the right number in the wrong unit: a slew of 0.1745 deg in a
scene (10 deg typed in radians), a Young's modulus of 200,000 Pa (steel's in MPa), a damping
ratio of 0.5 (half a per cent typed as a percentage), a mount direction of 180 rad (degrees
given to the Python API). Each function here returns the likely mistake as a phrase
(``"did you give radians? 0.1745 rad = 10 deg"``), or None when the value looks meant; the
callers (the scene reader, the Python constructors) warn with :class:`UnitWarning`, naming the
parameter or key.

Rules (each a bound far from every value of the kind a spacecraft has, so a warning is rare
when the value is meant):

- an angle in degrees typed with at least three significant digits that is, to within one
  unit of its last digit, a round angle in radians (1 to 10 deg, or a multiple of 5 deg up to
  360): 0.1745 is 10 deg (0.174533 rad) rounded, 0.0873 is 5 deg; small whole numbers and
  halves (1, 2.5) have too few digits to say;
- an angle in radians larger than a turn, 2 pi: no mount direction or slew needs one;
- a Young's modulus whose bar wave speed sqrt(E / rho) is below 300 m/s: metals and fibre
  composites have 3,000 to 12,000 m/s, engineering plastics above 900, and a metal's modulus in
  MPa gives 3 to 12 m/s (in GPa 0.1 to 0.4): only rubbers and foams lie between;
- a structural damping ratio above :data:`DAMPING_WARNING` (0.2): structures have 1e-4 to 0.05
  (Blevins, Table 1.3 [1]_), 0.2 already needs added dampers; a value from 0.2 to 100 is what a
  ratio in per cent would be.

References
----------
.. [1] R. D. Blevins, "Formulas for Natural Frequency and Mode Shape", Krieger 2001, Table 1.3
   (damping of structures).
.. [2] M. F. Ashby, "Materials Selection in Mechanical Design", 4th ed., Butterworth-Heinemann
   2011, ch. 4 (modulus-density chart: sqrt(E/rho) of metals, composites, polymers, elastomers).
"""

from __future__ import annotations

import decimal
import math
import warnings

__all__ = ["UnitWarning", "DAMPING_WARNING", "WAVE_SPEED_WARNING", "ROUND_ANGLE_DIGITS",
           "ROUND_ANGLES",
           "radians_in_degrees", "degrees_in_radians", "modulus_in_megapascals",
           "damping_in_percent", "warn_angle_in_degrees", "warn_unit_slip"]


class UnitWarning(UserWarning):
    """A value that looks like a unit mistake (the message names the likely one)."""


#: Damping ratio above which a structural damping ratio is warned about [-].
DAMPING_WARNING = 0.2
#: Bar wave speed sqrt(E / rho) [m/s] below which a Young's modulus is warned about.
WAVE_SPEED_WARNING = 300.0
#: Fewest significant digits of an angle [deg] read as a round angle in radians.
ROUND_ANGLE_DIGITS = 3
#: The round angles [deg] an angle typed in radians is compared with.
ROUND_ANGLES = tuple(range(1, 10)) + tuple(range(10, 361, 5))


def _typed_digits(value: float) -> tuple[int, float]:
    """Significant digits of ``value`` as typed (its shortest repr) and one unit of its last
    digit."""
    sign, digits, exponent = decimal.Decimal(repr(abs(value))).normalize().as_tuple()
    return len(digits), 10.0 ** exponent


def radians_in_degrees(value: float) -> str | None:
    """The likely mistake of an angle given in degrees that is a round angle in radians.

    Parameters
    ----------
    value : float, deg
        The angle as given (a scene's ``slew_angle``, ``direction``...).

    Returns
    -------
    str or None
        ``"did you give radians? 0.1745 rad = 10 deg"``, or None.
    """
    if not math.isfinite(value) or value == 0.0 or abs(value) > 2.0 * math.pi + 0.01:
        return None
    n_digits, unit = _typed_digits(value)
    if n_digits < ROUND_ANGLE_DIGITS:
        return None
    for degrees in ROUND_ANGLES:
        if abs(abs(value) - math.radians(degrees)) <= unit * (1.0 + 1e-9):
            return (f"did you give radians? {value:g} rad = "
                    f"{math.copysign(degrees, value):g} deg")
    return None


def degrees_in_radians(value: float) -> str | None:
    """The likely mistake of an angle given in radians that is larger than a turn.

    Parameters
    ----------
    value : float, rad

    Returns
    -------
    str or None
        ``"more than a turn (2 pi rad); did you give degrees? 180 deg = 3.14159 rad"``, or
        None when |value| <= 2 pi.
    """
    if not math.isfinite(value) or abs(value) <= 2.0 * math.pi:
        return None
    return (f"more than a turn (2 pi rad); did you give degrees? {value:g} deg = "
            f"{math.radians(value):.6g} rad")


def warn_angle_in_degrees(name: str, value: float, *, stacklevel: int = 3) -> None:
    """Warn (:class:`UnitWarning`) about an angle [rad] of the Python API larger than a turn,
    naming the parameter ``name`` (:func:`degrees_in_radians`)."""
    said = degrees_in_radians(value)
    if said is not None:
        warnings.warn(f"{name} = {value:g} rad is {said}", UnitWarning, stacklevel=stacklevel)


def warn_unit_slip(name: str, value: float, unit: str, said: str | None, *,
                   stacklevel: int = 3) -> None:
    """Warn (:class:`UnitWarning`) about a value of the Python API that looks like a unit slip,
    naming the parameter: ``"damping_ratio = 0.5: above 0.2, ...; did you give per cent?"``.

    Parameters
    ----------
    name : str
        The parameter as the caller named it.
    value : float
        Its value, in ``unit`` (``""`` for a ratio).
    said : str or None
        The likely mistake (:func:`modulus_in_megapascals`, :func:`damping_in_percent`...);
        None: nothing to warn about.
    stacklevel : int
        As :func:`warnings.warn`, counted from the function that calls this one (3: its
        caller's line).
    """
    if said is not None:
        shown = f"{value:g} {unit}" if unit else f"{value:g}"
        warnings.warn(f"{name} = {shown}: {said}", UnitWarning, stacklevel=stacklevel)


def modulus_in_megapascals(youngs_modulus: float, density: float) -> str | None:
    """The likely mistake of a Young's modulus far too low for any structural material.

    Parameters
    ----------
    youngs_modulus : float, Pa
    density : float, kg/m**3

    Returns
    -------
    str or None
        ``"a bar wave speed sqrt(E/rho) of 5.1 m/s (metals and composites: 3,000-12,000 m/s);
        did you give MPa? 200000 MPa = 2e+11 Pa"`` (or GPa, whichever gives a structural
        material), or None.
    """
    if not (youngs_modulus > 0 and density > 0):
        return None
    speed = math.sqrt(youngs_modulus / density)
    if speed >= WAVE_SPEED_WARNING:
        return None
    factor, unit = 1e6, "MPa"
    if math.sqrt(youngs_modulus * 1e6 / density) < WAVE_SPEED_WARNING:
        factor, unit = 1e9, "GPa"
    return (f"a bar wave speed sqrt(E/rho) of {speed:.3g} m/s (metals and fibre composites: "
            f"3,000-12,000 m/s; rubbers below {WAVE_SPEED_WARNING:g}); did you give {unit}? "
            f"{youngs_modulus:g} {unit} = {youngs_modulus * factor:g} Pa")


def damping_in_percent(damping_ratio: float) -> str | None:
    """The likely mistake of a structural damping ratio above :data:`DAMPING_WARNING`.

    Parameters
    ----------
    damping_ratio : float, -

    Returns
    -------
    str or None
        ``"above 0.2, more than structures have (1e-4 to 0.05); did you give per cent?
        0.5 % = 0.005"``, or None.
    """
    if not (math.isfinite(damping_ratio) and damping_ratio > DAMPING_WARNING):
        return None
    hint = (f"; did you give per cent? {damping_ratio:g} % = {damping_ratio / 100:g}"
            if damping_ratio <= 100.0 else "")
    return (f"above {DAMPING_WARNING:g}, more than structures have (1e-4 to 0.05 without added "
            f"dampers){hint}")
