"""How the analysis scales with the number of modes (issue 10, item 3).

For a hub carrying the paper's rod as a Craig-Bampton beam of n modes
(``Beam.circular_rod(10, 0.01, 7800, 2.06e11).truncated(n)``, ``Hub(100, 50)``), each stage
in a fresh process (so that its peak resident memory is its own):

- ``lqr_kalman``: ``controllers.lqr`` (LQR + Kalman filter) on the n-mode plant itself,
  weights for a 0.1 rad/s rigid-body regulator;
- ``margins``: ``controllers.margins`` of the chain-tuned LQR (the paper's three-body chain)
  on the n-mode plant;
- ``frd``: ``controllers.frequency_response_data`` of the n-mode plant on 1,000 frequencies
  (before it existed: ``control.frd``);
- ``design_loop``: the whole design loop: LQR on the chain, the loop on the n-mode beam,
  its margins, the slew (10 deg in 60 s) simulated for 100 s at 100 Hz.

Wall and CPU time (medians of ``--repeats``), the peak of traced Python/numpy allocations
(tracemalloc) and the process's peak resident set (ru_maxrss), the load average beside them.
``--controllers-from DIR`` measures another tree's ``controllers`` package (e.g. an export of
an older commit: ``git archive <commit> controllers | tar -x -C DIR``) against the same
appendages and spacecraft, for before/after tables. Slopes are least-squares fits of
log(time) against log(n).

Run::

    python benchmarks/analysis_scaling.py [--sizes 50 100 200 400] [--repeats 5]
        [--stages lqr_kalman margins frd design_loop] [--controllers-from DIR --label before]

Writes benchmarks/results/analysis_scaling[_<label>].json and .md.
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import argparse
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import time
import tracemalloc
import warnings

import numpy as np

from _common import RESULTS, machine_info, markdown_table, write_json

STAGES = ("lqr_kalman", "margins", "frd", "design_loop")
T = np.arange(10001) * 0.01  # 100 s at 100 Hz


def _setup(n_modes: int):
    from appendages import Beam
    from appendages.chain import HingedChain
    from spacecraft import Hub, Mount, Spacecraft

    beam = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)

    def spacecraft(appendage):
        return Spacecraft(Hub(mass=100.0, inertia=50.0), [Mount(appendage, (0.5, 0.0), 0.0)])

    truth = spacecraft(beam.truncated(n_modes)).plant(tip_deflection=True)
    chain = HingedChain.three_body(beam.length, beam.mass, 0.26989, 37.134)
    return truth, spacecraft(chain).plant()


def _weights(controllers, plant) -> dict:
    J = controllers.rigid_body_inertia(plant)
    return dict(attitude_weight=(J * 0.1 ** 2) ** 2, rate_weight=0.0, torque_weight=1.0)


def child(stage: str, n_modes: int, repeats: int) -> dict:
    """Run one stage ``repeats`` times in this process; return times and memory."""
    import controllers
    from _common import slew_inputs

    warnings.simplefilter("ignore")
    truth, design = _setup(n_modes)
    chain_controller = controllers.lqr(design, **_weights(controllers, design))
    omega = np.logspace(-2, 4, 1_000)

    def run():
        if stage == "lqr_kalman":
            controllers.lqr(truth, **_weights(controllers, truth))
        elif stage == "margins":
            controllers.margins(truth, chain_controller)
        elif stage == "frd":
            if hasattr(controllers, "frequency_response_data"):
                controllers.frequency_response_data(truth, omega)
            else:  # before it existed: python-control's FRD (a solve per frequency)
                import control

                control.frd(truth, omega)
        else:
            K = controllers.lqr(design, **_weights(controllers, design))
            loop = controllers.close_loop(truth, K)
            controllers.margins(truth, K)
            controllers.simulate(loop, T, slew_inputs(loop, T))

    walls, cpus, peaks = [], [], []
    for _ in range(repeats):
        tracemalloc.start()
        w0, c0 = time.perf_counter(), time.process_time()
        run()
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
        peaks.append(tracemalloc.get_traced_memory()[1] / 1e6)
        tracemalloc.stop()
    return {"stage": stage, "n_modes": n_modes, "n_states": truth.nstates,
            "wall_s": walls, "cpu_s": cpus, "traced_peak_MB": peaks,
            "maxrss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3,
            "load_average": os.getloadavg()}


def _slope(sizes, values) -> float:
    x, y = np.log(np.asarray(sizes, float)), np.log(np.asarray(values, float))
    return float(np.polyfit(x, y, 1)[0]) if len(sizes) > 1 else math.nan


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[50, 100, 200, 400])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--stages", nargs="+", default=list(STAGES), choices=STAGES)
    parser.add_argument("--controllers-from", default=None)
    parser.add_argument("--label", default="")
    parser.add_argument("--skip", nargs="*", default=[], metavar="STAGE:N",
                        help="stage:size pairs not to measure (e.g. frd:400 before "
                             "frequency_response_data existed: control.frd solves an 802 x 802 "
                             "system per frequency, minutes per run)")
    parser.add_argument("--child", nargs=3, metavar=("STAGE", "N", "REPEATS"),
                        help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.controllers_from:
        sys.path.insert(0, os.path.abspath(args.controllers_from))
    if args.child:
        stage, n, repeats = args.child
        print(json.dumps(child(stage, int(n), int(repeats))))
        return 0
    rows, results = [], []
    suffix = f"_{args.label}" if args.label else ""
    for stage in args.stages:
        for n in args.sizes:
            if f"{stage}:{n}" in args.skip:
                continue
            command = [sys.executable, os.path.abspath(__file__), "--child", stage, str(n),
                       str(args.repeats)]
            if args.controllers_from:
                command += ["--controllers-from", args.controllers_from]
            out = subprocess.run(command, capture_output=True, text=True, check=True)
            r = json.loads(out.stdout.strip().splitlines()[-1])
            results.append(r)
            med = {k: statistics.median(r[k]) for k in ("wall_s", "cpu_s", "traced_peak_MB")}
            print(f"{stage:12s} n={n:4d}: wall {med['wall_s']:8.3f} s, cpu {med['cpu_s']:8.3f} s,"
                  f" traced peak {med['traced_peak_MB']:7.1f} MB, maxrss {r['maxrss_MB']:7.1f} MB,"
                  f" load {r['load_average'][0]:.2f}", flush=True)
            rows.append([stage, n, r["n_states"], f"{med['wall_s']:.3f}", f"{med['cpu_s']:.3f}",
                         f"{med['traced_peak_MB']:.1f}", f"{r['maxrss_MB']:.0f}",
                         f"{r['load_average'][0]:.2f}"])
            _write(args, results, rows, suffix)  # after every measurement: nothing is lost
    print(_write(args, results, rows, suffix))
    return 0


def _write(args, results, rows, suffix) -> str:
    """JSON and Markdown of the results so far; returns the Markdown."""
    slopes = {}
    for stage in args.stages:
        mine = [r for r in results if r["stage"] == stage]
        if len(mine) > 1:
            slopes[stage] = {"cpu": _slope([r["n_modes"] for r in mine],
                                           [statistics.median(r["cpu_s"]) for r in mine]),
                             "wall": _slope([r["n_modes"] for r in mine],
                                            [statistics.median(r["wall_s"]) for r in mine])}
    write_json(f"analysis_scaling{suffix}.json",
               {"machine": machine_info(), "repeats": args.repeats,
                "controllers_from": args.controllers_from, "skipped": args.skip,
                "results": results, "slopes": slopes})
    m = machine_info()
    text = "\n".join([
        f"# Analysis cost against the number of modes{' (' + args.label + ')' if args.label else ''}",
        "", f"`python benchmarks/analysis_scaling.py` on {m['date_utc']} UTC ({m['cpu']}, "
        f"{m['nproc']} cores, single-threaded BLAS). Medians of {args.repeats}; each stage in "
        "its own process." + (f" Not measured: {', '.join(args.skip)}." if args.skip else ""),
        "",
        markdown_table(["stage", "modes", "states", "wall [s]", "cpu [s]", "traced peak [MB]",
                        "max RSS [MB]", "load (1 min)"], rows), "",
        markdown_table(["stage", "slope of cpu time in n", "slope of wall time in n"],
                       [[s, f"{v['cpu']:.2f}", f"{v['wall']:.2f}"] for s, v in slopes.items()]),
        ""])
    (RESULTS / f"analysis_scaling{suffix}.md").write_text(text + "\n")
    return text


if __name__ == "__main__":
    sys.exit(main())
