"""Reading a scene's values: one check per value at the boundary, one line per problem.

:class:`SceneReader` pops keys off the tables of a scene file, checks their types and ranges
(:data:`RANGES`) and the work limits, and raises :class:`SceneError` naming the file, the key
path (``appendages[1].beam.diameter``), the unit, the value (shortened to about 100 characters)
and what to do. An unknown key, or a missing required key beside an unknown one that looks like
it, is answered with the closest known key ("did you mean 'youngs_modulus'?"): the closest by
:func:`difflib.get_close_matches` (Ratcliff-Obershelp similarity >= 0.6).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import numbers
import re
import unicodedata
from collections.abc import Mapping

import numpy as np

from appendages.interface import FlexsatError

from .limits import LIMIT_UNITS, Limits

__all__ = ["SceneError", "SceneReader", "RANGES", "BEAM_FREQUENCY_RANGE", "BETA1_L",
           "NAME_LENGTH", "NAME_PATTERN", "SHOWN", "suggestion", "closest", "shorten",
           "shown_value", "value_kind", "quoted_choices"]


class SceneError(FlexsatError, ValueError):
    """A scene that cannot be run: names the file, the key path and the problem."""


def closest(word: str, candidates) -> str | None:
    """The candidate most like ``word`` (similarity >= 0.6), or None."""
    if not isinstance(word, str):
        return None
    found = difflib.get_close_matches(word, [c for c in candidates if isinstance(c, str)], n=1)
    return found[0] if found else None


def suggestion(word: str, candidates) -> str:
    """``"; did you mean 'x'?"`` for the closest candidate, or ''."""
    match = closest(word, candidates)
    return f"; did you mean {match!r}?" if match is not None and match != word else ""


# ---------------------------------------------------------------------------------------------
# ranges of the values (SI units inside; the file's units where they differ)
# ---------------------------------------------------------------------------------------------
# ---------------------------------------------------------------------------------------------
# ranges of the values (SI units inside; the file's units where they differ)
# ---------------------------------------------------------------------------------------------
@dataclasses.dataclass(frozen=True)
class _Range:
    """Accepted values of one kind of key: ``lo <= |value| <= hi`` in ``unit``.

    sign: ``"positive"`` (value > 0), ``"non-negative"`` (0 allowed besides the range),
    ``"signed"`` (either sign, 0 allowed), ``"non-zero"`` (either sign, not 0).
    ``below``: the upper end is excluded.
    """

    unit: str
    lo: float
    hi: float
    sign: str = "positive"
    below: bool = False


#: Accepted values per key (without the appendage index). Values outside are refused by name:
#: they are outside what flexsat's models and numerics are verified for (see the module table).
RANGES = {
    "hub.mass": _Range("kg", 1e-3, 1e7),
    "hub.inertia": _Range("kg*m^2", 1e-6, 1e10),
    "hub.inertia tensor": _Range("kg*m^2", 0.0, 1e10, "signed"),
    "orientation": _Range("deg", 0.0, 360.0, "signed"),
    "beam.poisson_ratio": _Range("-", 0.0, 0.5, "non-negative", below=True),
    "manoeuvre.slew_axis": _Range("-", 0.0, 1e6, "signed"),
    "disturbance.axis": _Range("-", 0.0, 1e6, "signed"),
    "position": _Range("m", 0.0, 1e3, "signed"),
    "direction": _Range("deg", 0.0, 360.0, "signed"),
    "direction vector": _Range("-", 0.0, 1e6, "signed"),
    "beam.length": _Range("m", 1e-2, 1e3),
    "beam.section": _Range("m", 1e-5, 10.0),
    "beam.wall_thickness": _Range("m", 1e-6, 5.0),
    "beam.density": _Range("kg/m^3", 1.0, 1e5),
    "beam.youngs_modulus": _Range("Pa", 1e5, 1e13),
    "beam.bending_stiffness": _Range("N*m^2", 1e-6, 1e12),
    "beam.linear_density": _Range("kg/m", 1e-6, 1e5),
    "beam.damping_ratio": _Range("-", 0.0, 1.0, "non-negative", below=True),
    "tip.mass": _Range("kg", 1e-6, 1e7, "non-negative"),
    "tip.inertia": _Range("kg*m^2", 1e-12, 1e10, "non-negative"),
    "tip.inertia tensor": _Range("kg*m^2", 0.0, 1e10, "signed"),
    "tip.offset": _Range("m", 0.0, 1e3, "signed"),
    "modal.frequencies": _Range("rad/s", 1e-4, 1e7),
    "modal.frequencies_hz": _Range("Hz", 1e-5, 2e6),
    "modal.participation": _Range("sqrt(kg), sqrt(kg)*m", 0.0, 1e8, "signed"),
    "modal.rigid_mass": _Range("kg, kg*m, kg*m^2", 0.0, 1e10, "signed"),
    "modal.tip_motion": _Range("m/sqrt(kg), rad/sqrt(kg)", 0.0, 1e8, "signed"),
    "modal.axes": _Range("-", 0.0, 1.0, "signed"),
    "chain.lengths": _Range("m", 1e-3, 1e3),
    "chain.masses": _Range("kg", 1e-6, 1e7),
    "chain.inertias": _Range("kg*m^2", 1e-12, 1e10, "non-negative"),
    "chain.hinge_stiffnesses": _Range("N*m/rad", 1e-6, 1e12),
    "chain.hinge_dampings": _Range("N*m*s/rad", 1e-12, 1e12, "non-negative"),
    "chain.com_offsets": _Range("m", 1e-12, 1e3, "non-negative"),
    "chain.torsional_inertias": _Range("kg*m^2", 1e-12, 1e10),
    "chain.axial_stiffnesses": _Range("N/m", 1e-6, 1e15),
    "chain.axial_dampings": _Range("N*s/m", 1e-12, 1e12, "non-negative"),
    "chain.root_stiffness": _Range("N*m/rad", 1e-6, 1e12),
    "chain.root_damping": _Range("N*m*s/rad", 1e-12, 1e12, "non-negative"),
    "fidelity.tolerance": _Range("-", 1e-12, 0.5),
    "fidelity.bandwidth_factor": _Range("-", 1.0, 1e3),
    "controller.sample_rate": _Range("Hz", 1e-3, 1e6),
    "pd.frequency": _Range("rad/s", 1e-5, 1e3),
    "pd.damping": _Range("-", 1e-3, 10.0),
    "pd.filter": _Range("rad/s", 1e-5, 1e6),
    "lqr.attitude_weight": _Range("1/rad^2", 1e-12, 1e12),
    "lqr.rate_weight": _Range("s^2/rad^2", 1e-12, 1e12, "non-negative"),
    "lqr.torque_weight": _Range("1/(N*m)^2", 1e-12, 1e12),
    "lqr.deflection_weight": _Range("1/m^2", 1e-12, 1e12, "non-negative"),
    "lqr.estimator_speed": _Range("-", 0.1, 100.0),
    "manoeuvre.slew_angle": _Range("deg", 1e-6, 360.0, "non-zero"),
    "manoeuvre.slew_time": _Range("s", 1e-3, 1e8),
    "manoeuvre.duration": _Range("s", 1e-3, 1e10),
    "manoeuvre.step": _Range("s", 1e-9, 1e6),
    "disturbance.amplitude": _Range("N, N*m", 1e-12, 1e9, "non-zero"),
    "disturbance.start": _Range("s", 1e-12, 1e10, "non-negative"),
    "disturbance.length": _Range("s", 1e-9, 1e10),
    "export.step": _Range("s", 1e-9, 1e6),
    "simulator.sample_rate": _Range("Hz", 1e-3, 1e6),
    "simulator.dt": _Range("s", 1e-9, 1e3),
    "reaction_wheel.spin_inertia": _Range("kg*m^2", 1e-9, 1e6),
    "reaction_wheel.max_torque": _Range("N*m", 1e-9, 1e6),
    "reaction_wheel.max_speed": _Range("rad/s", 1e-3, 1e6),
    # the manoeuvre as flown (spacecraft.scene.flown)
    "controller.delay": _Range("s", 1e-9, 1e3, "non-negative"),
    "manoeuvre.torque_limit": _Range("N*m", 1e-9, 1e6),
    "manoeuvre.rate_limit": _Range("deg/s", 1e-6, 1e3),
    "manoeuvre.jerk_limit": _Range("deg/s^3", 1e-9, 1e6),
    "shaper.frequency_error": _Range("-", 1e-6, 1.0, below=True),
    "shaper.tolerance": _Range("-", 1e-6, 1.0, below=True),
    "wheels.torque_limit": _Range("N*m", 1e-9, 1e6),
    "wheels.momentum_limit": _Range("N*m*s", 1e-9, 1e9),
    "wheels.spin_inertia": _Range("kg*m^2", 1e-9, 1e6),
    "wheels.viscous_friction": _Range("N*m*s/rad", 1e-12, 1e6, "non-negative"),
    "wheels.coulomb_friction": _Range("N*m", 1e-12, 1e6, "non-negative"),
    "wheels.spin_axes": _Range("-", 0.0, 1e6, "signed"),
    "wheels.cant_angle": _Range("deg", 1e-3, 90.0, below=True),
    "wheels.azimuth": _Range("deg", 0.0, 360.0, "signed"),
    "sensors.attitude_density": _Range("rad/sqrt(Hz)", 1e-15, 1.0, "non-negative"),
    "sensors.attitude_rms": _Range("rad", 1e-15, 1.0, "non-negative"),
    "sensors.attitude_rate": _Range("Hz", 1e-3, 1e6),
    "sensors.angle_random_walk": _Range("rad/sqrt(s)", 1e-15, 1.0, "non-negative"),
    "sensors.bias_instability": _Range("rad/s", 1e-15, 1.0, "non-negative"),
    "sensors.bias_correlation_time": _Range("s", 1e-6, 1e9),
    "sensors.rpe_window": _Range("s", 1e-6, 1e8),
    "sensors.probability": _Range("-", 1e-6, 1.0, below=True),
}

#: First free-free bending frequency of a beam [rad/s]: a beam outside is refused (its
#: frequencies would be far from any attitude-control band and the coupled plant ill-scaled).
BEAM_FREQUENCY_RANGE = (1e-4, 1e5)
#: beta_1 L of the first free-free bending mode (Blevins, Formulas for Natural Frequency and
#: Mode Shape, table 8-1): omega_1 = (beta_1 L)^2 sqrt(EJ / (rho A L^4)).
BETA1_L = 4.730040745

#: Longest appendage name [characters]: names become FMI variable names and C identifiers.
NAME_LENGTH = 64
#: A name in a scene (appendage names, key path parts): a C identifier.
NAME_PATTERN = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")

#: Longest value shown in a message [characters].
SHOWN = 100

# ---------------------------------------------------------------------------------------------
# the reader
# ---------------------------------------------------------------------------------------------
_MISSING = object()


def shorten(text: str, limit: int = SHOWN, *, one_line: bool = False) -> str:
    """A text for a message: cut to ``limit`` characters, saying how long it was; with
    ``one_line`` its white space (newlines included) folded to single spaces first."""
    text = str(text)
    if one_line:
        text = " ".join(text.split())
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text)} characters)"


def shown_value(value) -> str:
    """A value for a message: repr (control characters escaped), at most about 100 characters."""
    try:
        text = repr(value)
    except Exception:  # a foreign object whose repr fails: its type is enough
        text = f"<{type(value).__name__}>"
    return shorten(text)


def _key(key) -> str:
    """A key of the user's file for a key path: as is if plain, else quoted and shortened."""
    if isinstance(key, str) and re.fullmatch(r"[A-Za-z0-9_-]{1,100}", key):
        return key
    return shown_value(key)


class SceneReader:
    """Pops keys off a table, checking types and ranges, and reports problems with file and key
    path; ``limits`` bound the sizes (modes, bodies, appendages, strings)."""

    def __init__(self, source: str, limits: Limits | None = None):
        self.source = source
        self.limits = Limits() if limits is None else limits
        self.warnings: list[str] = []

    def warn(self, path: str, problem: str | None) -> None:
        """Record a value that looks like a unit slip (``problem`` from
        :mod:`appendages.unit_slips`; None: nothing to say) for :attr:`Scene.input_warnings`."""
        if problem is not None:
            where = f"{self.source}: " if self.source else ""
            self.warnings.append(f"{where}{path}: {problem}")

    def error(self, path: str, problem: str) -> SceneError:
        where = f"{self.source}: " if self.source else ""
        return SceneError(f"{where}{path}: {problem}" if path else f"{where}{problem}")

    def table(self, data, path: str) -> dict:
        if not isinstance(data, Mapping):
            raise self.error(path, f"must be a table; got {value_kind(data)}")
        return dict(data)

    def done(self, table: dict, path: str, allowed) -> None:
        if table:
            key = _key(sorted(table, key=str)[0])
            full = f"{path}.{key}" if path else key
            raise self.error(full, "unknown key; expected one of " + ", ".join(sorted(allowed))
                             + suggestion(sorted(table, key=str)[0], allowed))

    def take(self, table: dict, key: str, path: str, default=_MISSING):
        full = f"{path}.{key}" if path else key
        if key not in table:
            if default is _MISSING:
                typo = closest(key, [k for k in table if k != key])
                hint = (f" (is {shown_value(typo)} a misspelling of {key!r}?)"
                        if typo is not None else "")
                raise self.error(full, f"missing required value{hint}")
            return default, full
        return table.pop(key), full

    def number(self, table: dict, key: str, path: str, kind: str, *, default=_MISSING):
        """A number of the range ``RANGES[kind]`` (or ``default`` when absent)."""
        value, full = self.take(table, key, path, default)
        if value is default and default is not _MISSING:
            return value
        return self.check_number(value, full, kind)

    def check_number(self, value, full: str, kind: str) -> float:
        rng = RANGES[kind]
        unit = rng.unit
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
            raise self.error(full, f"must be a number [{unit}]; got {value_kind(value)}")
        try:
            value = float(value)
        except (OverflowError, ValueError):  # an integer beyond the float range
            raise self.error(full, f"must be finite [{unit}]; got {shown_value(value)}") from None
        if not math.isfinite(value):
            raise self.error(full, f"must be finite [{unit}]; got {value!r}")
        size = abs(value)
        if rng.sign in ("positive", "non-negative") and value < 0:
            what = "positive" if rng.sign == "positive" else "non-negative"
            raise self.error(full, f"must be {what} [{unit}]; got {value!r}")
        if value == 0 and rng.sign in ("positive", "non-zero"):
            what = "positive" if rng.sign == "positive" else "non-zero"
            raise self.error(full, f"must be {what} [{unit}]; got 0")
        if value == 0:
            return 0.0
        too_big = size >= rng.hi if rng.below else size > rng.hi
        if too_big or size < rng.lo:
            magnitude = "" if rng.sign in ("positive", "non-negative") else " in magnitude"
            if rng.below and rng.lo == 0:
                limit = f"must be below {rng.hi:g}{magnitude}"
            elif rng.lo == 0:
                limit = f"must be at most {rng.hi:g}{magnitude}"
            else:
                limit = f"must lie between {rng.lo:g} and {rng.hi:g}{magnitude}"
            zero = " (or be 0)" if rng.sign in ("non-negative", "signed") and rng.lo > 0 else ""
            raise self.error(full, f"{limit} [{unit}]{zero}; got {value!r}")
        return value

    def integer(self, table: dict, key: str, path: str, *, minimum: int, limit: str | None = None,
                default=_MISSING):
        """An integer >= minimum, at most the limit ``limit`` (a :class:`Limits` field)."""
        value, full = self.take(table, key, path, default)
        if value is default and default is not _MISSING:
            if limit is not None and value is not None:
                self.check_limit(full, value, limit)   # a lowered limit applies to defaults
            return value
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
            raise self.error(full, f"must be an integer; got {value_kind(value)}")
        value = int(value)
        if value < minimum:
            raise self.error(full, f"must be at least {minimum}; got {value}")
        if limit is not None:
            self.check_limit(full, value, limit)
        return value

    def check_limit(self, full: str, value: int, limit: str, what: str = "") -> None:
        """Refuse ``value`` above the work limit ``limit``, saying how to raise it."""
        bound = getattr(self.limits, limit)
        if value > bound:
            raise self.error(full, f"{what or shown_value(value)}: over the limit {bound:g} "
                             f"(limits.{limit}, {LIMIT_UNITS[limit][1]}); ask for less, or if "
                             f"you really want more raise it: [limits] {limit} = N in the "
                             f"scene, or --limit {limit}=N")

    def boolean(self, table: dict, key: str, path: str, default: bool) -> bool:
        value, full = self.take(table, key, path, default)
        if not isinstance(value, bool):
            raise self.error(full, f"must be true or false; got {value_kind(value)}")
        return value

    def text(self, table: dict, key: str, path: str, default: str) -> str:
        """A free-text string: at most limits.string_length characters, one line."""
        value, full = self.take(table, key, path, default)
        if not isinstance(value, str):
            raise self.error(full, f"must be a string; got {value_kind(value)}")
        self.check_limit(full, len(value), "string_length", f"a text of {len(value)} characters")
        bad = [c for c in value if unicodedata.category(c) in ("Cc", "Cs", "Zl", "Zp")]
        if bad:
            raise self.error(full, f"must be one line of text without control characters; got "
                             f"{shown_value(bad[0])} in {shown_value(value)}")
        return value

    def choice(self, table: dict, key: str, path: str, choices, default=_MISSING):
        value, full = self.take(table, key, path, default)
        if value is None and default is None:
            return None
        if not isinstance(value, str):
            raise self.error(full, f"must be a string, one of {quoted_choices(choices)}; got {value_kind(value)}")
        if value not in choices:
            raise self.error(full, f"must be one of {quoted_choices(choices)}; got {shown_value(value)}")
        return value

    def choices(self, table: dict, key: str, path: str, choices, default) -> tuple:
        """A string or a list of strings from ``choices`` (no duplicates)."""
        value, full = self.take(table, key, path, default)
        if isinstance(value, str):
            value = [value]
        if not isinstance(value, (list, tuple)):
            raise self.error(full, f"must be a string or a list of strings from "
                                   f"{quoted_choices(choices)}; got {value_kind(value)}")
        if len(value) > len(choices):
            raise self.error(full, f"must list each of {quoted_choices(choices)} at most once; got "
                             f"{len(value)} entries")
        out = []
        for k, item in enumerate(value):
            if not isinstance(item, str) or item not in choices:
                raise self.error(f"{full}[{k}]", f"must be one of {quoted_choices(choices)}; got "
                                 f"{shown_value(item)}")
            if item in out:
                raise self.error(f"{full}[{k}]", f"{item!r} is listed twice")
            out.append(item)
        return tuple(out)

    def vector(self, table: dict, key: str, path: str, kind: str, *, default=_MISSING,
               size: int | None = None, limit: str | None = None):
        """An array of numbers of the range ``RANGES[kind]``; its length at most ``limit``."""
        value, full = self.take(table, key, path, default)
        if value is default and default is not _MISSING:
            return value
        unit = RANGES[kind].unit
        if not isinstance(value, (list, tuple)):
            raise self.error(full, f"must be an array of numbers [{unit}]; got {value_kind(value)}")
        if size is not None and len(value) != size:
            raise self.error(full, f"must have {size} entries [{unit}]; got {len(value)}")
        if not value:
            raise self.error(full, f"must not be empty [{unit}]")
        if limit is not None:
            self.check_limit(full, len(value), limit, f"an array of {len(value)} entries")
        return tuple(self.check_number(v, f"{full}[{k}]", kind) for k, v in enumerate(value))


def value_kind(value) -> str:
    """What a value of the user's file is, for a message: ``"number 1.5"``, ``"a table"``,
    ``"string 'x'"``, ``"an array of 3"``..."""
    if isinstance(value, (bool, np.bool_)):
        return f"boolean {str(bool(value)).lower()}"
    if isinstance(value, numbers.Real):
        return f"number {shown_value(value)}"
    if isinstance(value, numbers.Number):
        return f"{shorten(type(value).__name__)} {shown_value(value)}"
    if isinstance(value, str):
        return f"string {shown_value(value)}"
    if isinstance(value, Mapping):
        return "a table"
    if isinstance(value, (list, tuple)):
        return f"an array of {len(value)}"
    return shorten(type(value).__name__)


def quoted_choices(choices) -> str:
    """The allowed values of a choice for a message: ``'a', 'b', 'c'``."""
    return ", ".join(repr(c) for c in choices)

