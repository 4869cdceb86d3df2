"""FMI tools flexsat did not write, where they are installed, and how their results are read.

The Modelica Association's Reference-FMUs ``fmusim`` and the FMU Compliance Checker ``fmuCheck``
are looked up in ``$FMI_TOOLS_BIN`` (default ``/work/tools/bin``), then on PATH; a test that
needs one is skipped, saying which, where it is not there."""
from __future__ import annotations

import csv
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

__all__ = ["TOOLS", "assert_matches_reference", "early_events", "first_per_time", "last_per_time",
           "read_table", "run", "tool"]


TOOLS = Path(os.environ.get("FMI_TOOLS_BIN", "/work/tools/bin"))


def tool(name: str) -> str:
    candidate = TOOLS / name
    if candidate.is_file() and os.access(candidate, os.X_OK):
        return str(candidate)
    found = shutil.which(name)
    if found is None:
        pytest.skip(f"{name} is not installed (looked in {TOOLS} and on PATH): the independent "
                    "check is not possible here")
    return found


def read_table(path: Path) -> dict[str, np.ndarray]:
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    names = [n.strip().strip('"') for n in rows[0]]
    values = np.array([[float(v) for v in row] for row in rows[1:] if row], dtype=np.float64)
    return {name: values[:, i] for i, name in enumerate(names)}


def last_per_time(table: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """One row per time: the right limit at event instants (two rows of the same time)."""
    keep = np.r_[np.diff(table["time"]) > 0, True]
    return {name: values[keep] for name, values in table.items()}


def first_per_time(table: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """One row per time: the left limit at event instants. fmusim and fmuCheck record a
    Co-Simulation FMU's outputs right after each step, before the inputs of that instant
    are set: where D != 0 they show the left limit at an input step."""
    keep = np.r_[True, np.diff(table["time"]) > 0]
    return {name: values[keep] for name, values in table.items()}


def run(command: list[str]) -> subprocess.CompletedProcess:
    return subprocess.run(command, capture_output=True, text=True, timeout=300)


def assert_matches_reference(result: Path, reference: Path, rtol: float,
                             limit=last_per_time) -> None:
    got, expected = limit(read_table(result)), limit(read_table(reference))
    np.testing.assert_allclose(got["time"], expected["time"], rtol=0, atol=1e-9)
    for name in expected:
        if name != "time":
            scale = max(np.max(np.abs(expected[name])), 1e-300)
            np.testing.assert_allclose(got[name], expected[name], rtol=0, atol=rtol * scale)


def early_events(source: Path, target: Path, h: float) -> Path:
    """The input table with every step moved h / 1000 earlier: fmuCheck advances its time
    by t += h, which after a few hundred steps lies a few ulps short of the grid point, so
    a step exactly at a grid point would be applied one step late (the briefing's "known
    tool problems"); a step just before it is applied at that grid point, as intended."""
    table = read_table(source)
    names = list(table)
    times = table["time"].copy()
    repeated = np.r_[False, np.diff(times) == 0]
    times[np.r_[repeated[1:], False]] -= h / 1000  # the row before the step
    times[repeated] -= h / 1000
    lines = [",".join(f'"{n}"' for n in names)]
    lines += [",".join(repr(float(v)) for v in row)
              for row in np.column_stack([times] + [table[n] for n in names[1:]])]
    target.write_text("\n".join(lines) + "\n")
    return target
