"""Checks of user arguments at the public boundary of the fmu package, and their messages.

Every message names the parameter, says what was expected and shows what was got, the
value's ``repr`` cut to :data:`MAX_SHOWN` characters (a 200,000-element array or a
megabyte-long string is never echoed).

Names that go into C source or XML are matched whole (:meth:`re.Pattern.fullmatch`): with
``re.match`` and ``$``, a trailing newline slips through (``$`` also matches before a final
``"\\n"``).  Text that goes into XML must consist of characters XML 1.0 allows
(section 2.2 of the XML 1.0 specification): a control character other than tab, newline
and carriage return cannot be written at all, not even as a character reference, and an
FMU containing one does not load.

References
----------
W3C, "Extensible Markup Language (XML) 1.0 (Fifth Edition)", 2008, section 2.2
"Characters", production [2] Char.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping

import numpy as np

from .limits import check_cosimulation_steps

__all__ = ["MAX_SHOWN", "COSIMULATION_METHODS", "shorten", "real_number", "positive_finite",
           "c_identifier", "is_c_identifier", "xml_text", "first_xml_illegal",
           "check_cosimulation_run"]

#: Longest excerpt of a value shown in an error message [characters].
MAX_SHOWN = 100

#: The master algorithms of a co-simulation (:func:`fmu.cosimulate`).
COSIMULATION_METHODS = ("gauss-seidel", "jacobi")

_C_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
# characters XML 1.0 forbids (the complement of production [2] Char)
_XML_ILLEGAL = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


def shorten(value: object, limit: int = MAX_SHOWN) -> str:
    """``repr(value)``, cut to ``limit`` characters with "..." where something was left out."""
    text = repr(value)
    if len(text) <= limit:
        return text
    return text[:limit - 3] + "..."


def real_number(name: str, value: object, unit: str) -> float:
    """``value`` as a float; TypeError naming ``name`` if it is not a real number."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(
            value, (int, float, np.integer, np.floating)):
        raise TypeError(f"{name} must be a real number [{unit}]; got {type(value).__name__} "
                        f"{shorten(value)}")
    return float(value)


def positive_finite(name: str, value: object, unit: str = "s") -> float:
    """``value`` as a positive finite float, else TypeError/ValueError naming ``name``."""
    number = real_number(name, value, unit)
    if not (math.isfinite(number) and number > 0.0):
        raise ValueError(f"{name} must be positive and finite [{unit}]; got {number!r}")
    return number


def is_c_identifier(text: object) -> bool:
    """True if ``text`` is a whole C identifier (letters, digits, "_", no leading digit)."""
    return isinstance(text, str) and _C_IDENTIFIER.fullmatch(text) is not None


def c_identifier(name: str, value: object) -> str:
    """``value`` if it is a C identifier, else TypeError/ValueError naming ``name``."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a str (a C identifier); got {type(value).__name__} "
                        f"{shorten(value)}")
    if not is_c_identifier(value):
        raise ValueError(f"{name} must be a C identifier (letters, digits and '_', not starting "
                         f"with a digit, nothing else); got {shorten(value)}")
    return value


def first_xml_illegal(text: str) -> int | None:
    """Position of the first character XML 1.0 does not allow in ``text``, or None."""
    found = _XML_ILLEGAL.search(text)
    return None if found is None else found.start()


def xml_text(name: str, value: object) -> str:
    """``value`` if it is a str that XML 1.0 can hold, else TypeError/ValueError naming ``name``.

    Raises
    ------
    TypeError
        If ``value`` is not a str.
    ValueError
        If it holds a character XML 1.0 forbids; the message gives its code point and
        position.
    """
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a str; got {type(value).__name__} {shorten(value)}")
    position = first_xml_illegal(value)
    if position is not None:
        raise ValueError(
            f"{name} must be text that XML 1.0 can hold (no control characters other than "
            f"tab, newline and carriage return); got U+{ord(value[position]):04X} at position "
            f"{position} of {shorten(value)}")
    return value


def check_cosimulation_run(method: object, step: object, stop_time: object,
                           start_time: object, inputs: object, start_values: tuple) -> int:
    """Check the arguments of a fixed-step co-simulation run; return its number of steps.

    Parameters
    ----------
    method : str
        One of :data:`COSIMULATION_METHODS`.
    step, stop_time, start_time : float, s
        The communication step (positive) and the interval, a whole number of steps long and
        at most ``fmu.limits.MAX_COSIMULATION_STEPS`` of them.
    inputs : mapping or None
        The external inputs by name.
    start_values : tuple of (name, mapping or None)
        Further mappings to check, with their parameter names.

    Raises
    ------
    TypeError, ValueError
        Naming the parameter, its unit, what was expected and what was got.
    """
    if not isinstance(method, str) or method not in COSIMULATION_METHODS:
        raise ValueError(f"method must be one of {COSIMULATION_METHODS}; got {shorten(method)}")
    for label, value in (("step", step), ("stop_time", stop_time), ("start_time", start_time)):
        if not math.isfinite(real_number(label, value, "s")):
            raise ValueError(f"{label} must be finite [s]; got {value!r}")
    if not step > 0:
        raise ValueError(f"step must be positive [s]; got {step!r}")
    for label, value in (("inputs", inputs), *start_values):
        if value is not None and not isinstance(value, Mapping):
            raise TypeError(f"{label} must be a mapping {{name: value}}; got "
                            f"{type(value).__name__} {shorten(value)}")
    duration = float(stop_time) - float(start_time)
    if not (math.isfinite(duration) and duration > 0):
        raise ValueError(f"stop_time must be after start_time, by a finite time [s]; got "
                         f"stop_time {stop_time!r}, start_time {start_time!r}")
    check_cosimulation_steps(duration / step, step, duration)
    n_steps = int(round(duration / step))
    if n_steps < 1 or abs(n_steps * step - duration) > 1e-9 * max(duration, step):
        raise ValueError(f"stop_time - start_time must be a positive whole number of steps "
                         f"(step = {step!r} s) [s]; got {duration!r} s")
    return n_steps
