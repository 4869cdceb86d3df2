"""What the tip-output rule reports does not depend on a set's order or on which of two twins
round-off makes larger: the floors in the scene's order of appendages (motions sorted), and
every output within 1e-3 of the largest change named, in name order. Before, the floors came in
the order of a set of string tuples (it changes with PYTHONHASHSEED from one process to the
next) and the report named one of two twin wings whose changes agree to 6e-14 by the CPU's
rounding."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from spacecraft.report import write

ROOT = Path(__file__).resolve().parents[3]

CHILD = """
import json, warnings
warnings.simplefilter("ignore")
from spacecraft.design.loop import DesignLoop
loop = DesignLoop("two_wings")
loop.choose_fidelity()
print(json.dumps([[name, list(f)] for name, f in loop.tip_floors.items()]))
"""


@pytest.mark.slow
def test_the_floors_come_in_the_scenes_order_whatever_the_hash_seed():
    """Three processes with different hash seeds choose the same floors, in scene order."""
    out = set()
    for seed in ("1", "2", "3"):
        env = dict(os.environ, PYTHONHASHSEED=seed, PYTHONPATH=str(ROOT))
        run = subprocess.run([sys.executable, "-c", CHILD], env=env, capture_output=True,
                             text=True, check=True, cwd=ROOT)
        out.add(run.stdout.strip().splitlines()[-1])
    assert len(out) == 1, out
    from spacecraft.scene import load_scene
    names = [a.name for a in load_scene("two_wings").appendages]
    floors = json.loads(out.pop())
    assert [name for name, _ in floors] == [n for n in names if n in dict(floors)]


def test_twin_outputs_that_tie_are_both_named():
    changes = {"wing_px_tip_deflection": 0.0059005620928408616,
               "wing_mx_tip_deflection": 0.005900562092841226,
               "boom_tip_deflection": 0.004}
    assert write._largest_changes(changes) == "wing_mx_tip_deflection, wing_px_tip_deflection"
    assert write._largest_changes({"a": 1.0, "b": 0.99}) == "a"
    assert write._largest_changes({}) == "-"
