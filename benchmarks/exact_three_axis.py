"""The exact-beam verdict of a three-axis loop: its cost per evaluation, against the planar one.

The example spacecraft of ``benchmarks/three_axis.py`` (an 820 kg hub with a full inertia
tensor, two canted rectangular-section wings and an off-axis CFRP boom), its beams with a
modal damping ratio of 0.5 %, and two controllers tuned on the hub with each beam's 3-body 3-D
chain: a PD (0.1 rad/s per principal axis, damping 0.7) and the benchmark's LQR + Kalman. The
exact verdict (spacecraft.design.verdicts.exact_loop_verdict: the exact 3x3 attitude response
through each beam's W6, the MIMO Nyquist count of det(I + L), loop-at-a-time and disk margins
found on the exact loop function) is measured in its parts:

- once per run: the exact grid (modes located on the undamped Craig-Bampton truncations of
  every motion, spacecraft.design.exact_grid), and the exact response on it (one 6x6 solve per
  frequency through the three W6);
- per evaluation (each controller, each sweep sample): the verdict given the grid and the
  response, with the locating spacecraft kept for the run (as ModelBuilder.exact_verdict does);
- beside it, the planar default scene's exact verdict (the paper's rod on a hub, PD).

The state-space verdict on a 10-mode truncation (controllers.spillover) is timed beside it, and
the exact verdict's margins are compared with it (they differ by the truncation's error).

Run: ``python benchmarks/exact_three_axis.py`` (about a minute on 2 cores). Output:
``results/exact_three_axis.{json,md}``. CPU and wall medians, the load average beside them.
"""

from __future__ import annotations

import _common  # noqa: F401  (BLAS threads, sys.path)

import os
import time
import warnings

import numpy as np

from _common import RESULTS, machine_info, markdown_table, write_json
import controllers
from appendages import Beam
from appendages.fit3d import fit_chain_3d
from spacecraft import DesignLoop, Hub, Mount, Spacecraft
from spacecraft.design.exact_grid import exact_grid, locating_spacecraft
from spacecraft.design.verdicts import exact_loop_verdict
from three_axis import HUB_INERTIA, HUB_MASS, placements

ZETA = 0.005
BANDWIDTH = 0.1   # rad/s: the controllers' rigid-body natural frequency
COLD: list = []


def beams() -> list:
    """The example's wings and boom, damped (0.5 % per mode)."""
    wing = Beam.rectangular(6.0, 2.0, 0.04, 40.0, 7e8, damping_ratio=ZETA)
    boom = Beam.tube(4.0, 0.05, 0.001, 1600.0, 1.2e11, damping_ratio=ZETA)
    return [wing, wing, boom]


def example(models) -> Spacecraft:
    return Spacecraft(Hub(HUB_MASS, HUB_INERTIA),
                      [Mount(m, p, orientation=R, name=n) for m, (p, R), n
                       in zip(models, placements(), ["wing_left", "wing_right", "boom"])])


def timed(function, repeats: int = 5) -> tuple[float, float, object]:
    """(median CPU [s], median wall [s], result) of ``repeats`` calls after a warm-up (the
    warm-up's CPU time in ``COLD``: caches of the appendages filled)."""
    c = time.process_time()
    out = function()
    COLD.append(time.process_time() - c)
    cpu, wall = [], []
    for _ in range(repeats):
        c, w = time.process_time(), time.perf_counter()
        function()
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - w)
    return float(np.median(cpu)), float(np.median(wall)), out


def main() -> None:
    warnings.simplefilter("ignore")
    exact = example(beams())
    design = example([fit_chain_3d(b, 3) for b in beams()]).plant(prune=True)
    truth = example([b.truncated(10) for b in beams()]).plant(prune=True)
    J = controllers.rigid_body_inertia(design)
    j, _ = controllers.principal_axes(J)
    ks = {"pd": controllers.pd(design, natural_frequency=BANDWIDTH, damping=0.7),
          "lqr": controllers.lqr(design, attitude_weight=(j * BANDWIDTH ** 2) ** 2,
                                 rate_weight=0.0, torque_weight=1.0)}
    rows, data = [], {"machine": machine_info(), "load_before": list(os.getloadavg())}

    c, w, grid = timed(lambda: exact_grid(exact, BANDWIDTH), 3)
    data["grid"] = {"cpu": c, "wall": w, "points": int(grid.size), "cold_cpu": COLD[-1]}
    rows.append(["three-axis: exact grid (once per run)",
                 f"{grid.size} points; first call {COLD[-1]:.3f} s CPU", c, w])
    locating = locating_spacecraft(exact, float(grid[-1]))
    c, w, P = timed(lambda: exact.exact.attitude_compliance(grid), 3)
    data["response"] = {"cpu": c, "wall": w, "cold_cpu": COLD[-1]}
    rows.append(["three-axis: exact 3x3 response on the grid (once per run)",
                 f"first call {COLD[-1]:.3f} s CPU", c, w])
    for name, K in ks.items():
        c, w, verdict = timed(lambda: exact_loop_verdict(exact, K, grid, theta=P,
                                                         locating=locating))
        cs, ws, reference = timed(lambda: controllers.spillover(truth, K), 3)
        a, b = verdict.margins.as_dict(), reference.margins.as_dict()
        difference = max(abs(a[k] - b[k]) / max(1.0, abs(b[k])) for k in a
                         if np.isfinite(b[k]))
        data[name] = {"exact_verdict_cpu": c, "exact_verdict_wall": w,
                      "stable": bool(verdict.stable), "margins": a,
                      "truncated_10_verdict_cpu": cs, "truncated_10_verdict_wall": ws,
                      "largest_margin_difference_to_10_modes": difference}
        rows.append([f"three-axis {name}: exact verdict (per evaluation)",
                     f"stable {verdict.stable}, disk margin {a['disk_margin']:.4f}", c, w])
        rows.append([f"three-axis {name}: state-space verdict, 10 modes a beam",
                     f"margins within {difference:.1e} of the exact", cs, ws])

    loop = DesignLoop("default", time_responses=False)
    frd = loop.exact_reference_frd()
    K = loop.tuned("poles-and-zeros", "pd", loop.n_modes).controller
    c, w, verdict = timed(lambda: loop.exact_verdict(K, frd))
    data["planar_pd"] = {"exact_verdict_cpu": c, "exact_verdict_wall": w,
                         "points": int(frd.omega.size)}
    rows.append(["planar default scene pd: exact verdict (per evaluation)",
                 f"{frd.omega.size} points", c, w])
    data["load_after"] = list(os.getloadavg())

    write_json("exact_three_axis.json", data)
    table = markdown_table(["what", "notes", "CPU [s]", "wall [s]"],
                           [[r[0], r[1], f"{r[2]:.3f}", f"{r[3]:.3f}"] for r in rows])
    text = (f"# The exact-beam verdict of a three-axis loop: cost per evaluation\n\n"
            f"{data['machine']['date_utc']} UTC, {data['machine']['cpu']}, "
            f"load {data['load_before']} before, {data['load_after']} after "
            f"(1, 5, 15 min).\n\n{table}\n")
    (RESULTS / "exact_three_axis.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
