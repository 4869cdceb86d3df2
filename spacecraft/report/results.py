"""results.json and the time series beside it: numbers only, nothing a program must guess.

:func:`to_json` writes strict JSON: numpy scalars and arrays become numbers and lists, complex
numbers ``{"re": .., "im": ..}``; a value that is not a finite number is never written as a
string or a non-standard literal: it is ``null``, and the key ``<name>_flag`` beside it says why
(``"inf"``, ``"-inf"``, ``"nan"``; lists with such entries get ``<name>_flag`` =
``"non-finite entries are null"``). A metric withheld by a verdict (a diverging loop's settling
time) is ``null`` with its flag in the ``metric_flags`` table of its loop (``"diverges"``,
``"slew unfinished"``, ``"not settled"``).

:func:`write_timeseries` writes every response of a run as a CSV file under ``timeseries/``
(one per loop: time [s] and every input and output in SI units, with a header naming them and
their units), listed in results.json under ``files.timeseries``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

__all__ = ["clean", "to_json", "write_timeseries", "SIGNAL_UNITS", "signal_unit"]

#: Units of the signals of flexsat's loops (by name or suffix; a three-axis signal's axis
#: ``_x``, ``_y``, ``_z`` aside).
SIGNAL_UNITS = {"time": "s", "theta": "rad", "theta_ref": "rad", "omega": "rad/s",
                "torque": "N*m", "disturbance_torque": "N*m", "force": "N", "force_x": "N",
                "force_y": "N", "_tip_deflection": "m", "_tip_twist": "rad", "_tip_force": "N",
                "_root_force": "N", "_root_moment": "N*m", "wheel_speed": "rad/s",
                "omega_ref": "rad/s", "torque_ff": "N*m", "torque_command": "N*m",
                "_torque_command": "N*m", "_torque": "N*m", "_momentum": "N*m*s",
                "_speed": "rad/s", "_saturated": "-"}


def signal_unit(name: str) -> str:
    """The SI unit of a loop signal (``"-"`` if unknown): planar names, and three-axis ones
    with an axis suffix (``theta_x``, ``wing_tip_deflection_z``, ``boom_root_moment_y``)."""
    names = [name] + ([name[:-2]] if name[-2:] in ("_x", "_y", "_z") else [])
    for n in names:
        if n in SIGNAL_UNITS:
            return SIGNAL_UNITS[n]
    for n in names:
        for suffix, unit in SIGNAL_UNITS.items():
            if suffix.startswith("_") and n.endswith(suffix):
                return unit
    return "-"


def _flag(value: float) -> str | None:
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return None


def _scalar(value):
    """A JSON-ready scalar and its flag (None when it is a finite number or not a number)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value), None
    if isinstance(value, (int, np.integer)):
        return int(value), None
    if isinstance(value, (float, np.floating)):
        value = float(value)
        flag = _flag(value)
        return (None, flag) if flag else (value, None)
    return value, None


def clean(value):
    """JSON-ready copy of results: numbers only, null plus a ``<key>_flag`` for non-finite
    values (see the module docstring)."""
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            key = str(k)
            if isinstance(v, (dict, list, tuple, np.ndarray, complex, np.complexfloating)):
                cleaned = clean(v)
                out[key] = cleaned
                if isinstance(v, (list, tuple, np.ndarray)) and _has_non_finite(v):
                    out.setdefault(f"{key}_flag", "non-finite entries are null")
                continue
            scalar, flag = _scalar(v)
            out[key] = scalar
            if flag is not None:
                out[f"{key}_flag"] = flag
        return out
    if isinstance(value, np.ndarray):
        return [clean(v) for v in value.tolist()]
    if isinstance(value, (list, tuple)):
        return [clean(v) for v in value]
    if isinstance(value, (complex, np.complexfloating)):
        return {"re": clean(float(value.real)), "im": clean(float(value.imag))}
    return _scalar(value)[0]


def _has_non_finite(values) -> bool:
    for v in (values.tolist() if isinstance(values, np.ndarray) else values):
        if isinstance(v, (float, np.floating)) and not math.isfinite(v):
            return True
        if isinstance(v, (list, tuple, np.ndarray)) and _has_non_finite(v):
            return True
    return False


def to_json(data: dict) -> str:
    """Strict JSON text of a results dict (numbers only; no NaN or Infinity literals)."""
    return json.dumps(clean(data), indent=2, allow_nan=False)


def _csv(path: Path, columns: list, names: list) -> None:
    header = ",".join(f"{n} [{signal_unit(n)}]" for n in names)
    data = np.column_stack(columns) if columns else np.zeros((0, 0))
    with open(path, "w", encoding="utf-8", newline="\n") as stream:
        stream.write(header + "\n")
        np.savetxt(stream, data, delimiter=",", fmt="%.10g")


def _columns(response) -> tuple[list, list]:
    t = np.asarray(response.t, dtype=float).reshape(-1)
    names, columns = ["time"], [t]
    for kind, labels, values in (("input", response.input_labels, response.u),
                                 ("output", response.output_labels, response.y)):
        if values is None:
            continue
        data = np.asarray(values, dtype=float).reshape(len(labels), -1)
        for name, row in zip(labels, data):
            if name in names:
                continue
            names.append(name)
            columns.append(row[: t.size])
    return names, columns


def write_timeseries(result, folder: Path) -> list:
    """Write every response of a run as CSV under ``folder`` (created).

    Returns
    -------
    list of dict
        One per file: ``path`` (relative to the report folder: ``timeseries/<file>``),
        ``design``, ``controller``, ``model`` (``"design"``, ``"truth"`` or ``"basilisk"``),
        ``input`` (``"slew"`` or ``"disturbance"``), ``columns`` and their ``units``,
        ``samples``.
    """
    folder.mkdir(exist_ok=True)
    out = []
    sources = [(result.responses, "slew"), (result.disturbance_responses, "disturbance")]
    for responses, what in sources:
        for (variant, kind, which), response in responses.items():
            name = f"{kind}_{variant}_{which}" + ("" if what == "slew" else "_disturbance")
            out.append(_write(folder, name, response, variant, kind, which, what))
    for kind, comparison in result.basilisk.items():
        response = comparison.basilisk.response
        out.append(_write(folder, f"{kind}_basilisk", response, result.data.get(
            "basilisk", {}).get(kind, {}).get("design"), kind, "basilisk", "slew"))
    return out


def _write(folder, name, response, variant, kind, which, what) -> dict:
    names, columns = _columns(response)
    path = folder / f"{name}.csv"
    _csv(path, columns, names)
    return {"path": f"{folder.name}/{path.name}", "design": variant, "controller": kind,
            "model": which, "input": what, "columns": names,
            "units": [signal_unit(n) for n in names], "samples": int(columns[0].size)}
