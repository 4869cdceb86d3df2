"""LQR (+ Kalman), closed-loop simulation and plant builds of the design loop: before and after.

The stages of one design-loop evaluation that are not the margins, for the two loops of
``benchmarks/three_axis.py`` (two wings and a boom; truth 56 states, design 46, loop 102) and
``benchmarks/design_loop.py`` (the paper's rod, 20 modes; a 3-body chain as design model):
``build_truth``, ``build_design``, ``lqr``, ``close_loop`` and ``simulate`` (the slew, 100 s at
100 Hz), and the simulation of one sample of the shipped sweep scene (a short run of a small
loop, where the simulator's choice of method decides), each timed on its own (CPU, ``time.process_time``, one BLAS thread) in a fresh
process per round, the rounds alternating between two checkouts of flexsat (``--before PATH``,
e.g. ``git worktree add /tmp/before <rev>``, and this one) so that both see the same load;
``uptime``'s load average beside every round. Medians over the repeats of a round, then the
median over the rounds.

Then the three-axis truth build with the default BLAS threads (no thread variables set),
CPU and wall, the same alternation.

Accuracy, in the same run: each checkout's gains K and L, closed-loop poles and simulated
outputs of both loops, compared (max |after - before| relative to max |before|).

Run::

    python benchmarks/lqr_simulate_speed.py --before /tmp/before [--rounds 5] [--repeats 15]

Writes ``benchmarks/results/lqr_simulate_speed.{json,md}``.
"""

from __future__ import annotations

import _common  # noqa: F401  (BLAS threads, sys.path)

import argparse
import json
import sys
import tempfile
import textwrap
from pathlib import Path

import numpy as np

from _common import (RESULTS, machine_info, markdown_table, revision, run_in_checkout,
                     write_json)

HERE = Path(__file__).resolve().parent.parent
STAGES = ("build_truth", "build_design", "lqr", "close_loop", "simulate")

# the child: put the checkout first on the path, time the stages, save the results
CHILD = textwrap.dedent("""
    import json, math, os, statistics, sys, time, warnings
    tree, n, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    sys.path[:0] = [tree, os.path.join(tree, "benchmarks")]
    warnings.simplefilter("ignore")
    import numpy as np
    import controllers
    import three_axis as T3
    import design_loop as P
    from appendages.chain import HingedChain

    chains = T3.design_chains()
    rod = P.paper_rod()
    chain = HingedChain.three_body(rod.length, rod.mass, 0.26989, 37.134)

    def three_axis_stages():
        state = {}
        def build_truth():
            state["truth"] = T3.example(lambda b: b.truncated(T3.N_MODES)).plant(
                tip_deflection=True, prune=True)
        def build_design():
            models = iter(chains)
            state["design"] = T3.example(lambda b: next(models)).plant(prune=True)
        def lqr():
            J = controllers.rigid_body_inertia(state["design"])
            j, _ = controllers.principal_axes(J)
            state["lqr"] = controllers.lqr_design(
                state["design"], attitude_weight=(j * 0.1 ** 2) ** 2, rate_weight=0.0,
                torque_weight=1.0)
        def close_loop():
            state["loop"] = controllers.close_loop(state["truth"], state["lqr"].controller)
        def simulate():
            loop = state["loop"]
            e = np.asarray(T3.SLEW_AXIS) / np.linalg.norm(T3.SLEW_AXIS)
            profile = controllers.slew_profile(T3.T, math.radians(10.0), 60.0)
            U = np.zeros((loop.ninputs, T3.T.size))
            for i, axis in enumerate("xyz"):
                U[list(loop.input_labels).index(f"theta_ref_{axis}")] = e[i] * profile
            state["y"] = controllers.simulate(loop, T3.T, U).y
        return state, [build_truth, build_design, lqr, close_loop, simulate]

    def planar_stages():
        state = {}
        def build_truth():
            state["truth"] = P.spacecraft_with(rod.truncated(P.N_MODES)).plant(
                tip_deflection=True)
        def build_design():
            state["design"] = P.spacecraft_with(chain).plant()
        def lqr():
            J = controllers.rigid_body_inertia(state["design"])
            state["lqr"] = controllers.lqr_design(
                state["design"], attitude_weight=(J * 0.1 ** 2) ** 2, rate_weight=0.0,
                torque_weight=1.0)
        def close_loop():
            state["loop"] = controllers.close_loop(state["truth"], state["lqr"].controller)
        def simulate():
            loop = state["loop"]
            state["y"] = controllers.simulate(loop, P.T, P.slew_inputs(loop, P.T)).y
        return state, [build_truth, build_design, lqr, close_loop, simulate]

    result, arrays = {}, {}
    for name, make in (("three_axis", three_axis_stages), ("planar", planar_stages)):
        state, stages = make()
        for stage in stages:          # warm-up (numba, caches)
            stage()
        cpu = {stage.__name__: [] for stage in stages}
        for _ in range(n):
            for stage in stages:
                c = time.process_time()
                stage()
                cpu[stage.__name__].append(time.process_time() - c)
        result[name] = {k: statistics.median(v) for k, v in cpu.items()}
        result[name]["total"] = statistics.median([sum(v[i] for v in cpu.values())
                                                   for i in range(n)])
        design = state["lqr"]
        arrays[name + "_K"], arrays[name + "_L"] = design.K, design.L
        arrays[name + "_poles"] = np.sort_complex(np.linalg.eigvals(state["loop"].A))
        arrays[name + "_y"] = state["y"]

    # a sweep sample's simulation (the shipped sweep scene: a short run of a small loop)
    import spacecraft.sweep as S
    from spacecraft.sweep.evaluate import evaluate, prepare
    CS = sys.modules["controllers.simulate"]
    raw, spec, source = S.load_sweep(None, samples=4)
    context = prepare(raw, spec, source)
    grabbed, propagate = [], CS.Simulator._propagate
    def grab(self, U, X0, **kwargs):
        grabbed.append((self.system, self.dt, self.hold, U.copy(), X0.copy()))
        return propagate(self, U, X0, **kwargs)
    CS.Simulator._propagate = grab
    evaluate(context, spec.values()[0])
    CS.Simulator._propagate = propagate
    system, dt, hold, U, X0 = grabbed[-1]
    T = np.arange(U.shape[1]) * dt
    def sweep_simulate():
        return CS.Simulator(system, dt, hold=hold).outputs(T, U, X0)
    y = sweep_simulate()
    cpu = []
    for _ in range(n):
        c = time.process_time()
        sweep_simulate()
        cpu.append(time.process_time() - c)
    result["sweep_sample"] = {"simulate": statistics.median(cpu),
                              "states": system.nstates, "samples": U.shape[1],
                              "method": CS.Simulator(system, dt, hold=hold).method_for(
                                  U.shape[1])}
    arrays["sweep_sample_y"] = y
    np.savez(out, **arrays)
    result["load"] = [round(x, 2) for x in os.getloadavg()]
    print(json.dumps(result))
""")


# the child of the default-threads check: the three-axis truth build with the user's BLAS
# threads (OpenBLAS: one per core), CPU and wall
CHILD_THREADS = textwrap.dedent("""
    import json, os, statistics, sys, time, warnings
    tree, n = sys.argv[1], int(sys.argv[2])
    sys.path[:0] = [tree, os.path.join(tree, "benchmarks")]
    warnings.simplefilter("ignore")
    import three_axis as T3
    def build():
        T3.example(lambda b: b.truncated(T3.N_MODES)).plant(tip_deflection=True, prune=True)
    build()
    cpu, wall = [], []
    for _ in range(n):
        c, w = time.process_time(), time.perf_counter()
        build()
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - w)
    print(json.dumps({"cpu": statistics.median(cpu), "wall": statistics.median(wall)}))
""")


def run_child(tree: Path, repeats: int, out: Path) -> dict:
    return run_in_checkout(tree, CHILD, tree, repeats, out, what="the stages", blas="one")


def run_threads_child(tree: Path, repeats: int) -> dict:
    return run_in_checkout(tree, CHILD_THREADS, tree, repeats, what="the build",
                           blas="default")


def differences(before: Path, after: Path) -> dict:
    """max |after - before| / max |before| per array (poles sorted, complex)."""
    a, b = np.load(before), np.load(after)
    out = {}
    for key in a.files:
        x, y = a[key], b[key]
        if x.shape != y.shape:
            out[key] = f"shapes differ: {x.shape} before, {y.shape} after"
            continue
        out[key] = float(np.abs(y - x).max() / max(np.abs(x).max(), np.finfo(float).tiny))
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, required=True,
                        help="a checkout of flexsat before the change")
    parser.add_argument("--rounds", type=int, default=5, help="rounds per checkout")
    parser.add_argument("--repeats", type=int, default=15, help="evaluations per round")
    args = parser.parse_args()
    trees = {"before": args.before.resolve(), "after": HERE}
    info = machine_info()
    runs: dict = {"before": [], "after": []}
    with tempfile.TemporaryDirectory() as scratch:
        files = {k: Path(scratch) / f"{k}.npz" for k in trees}
        for _ in range(args.rounds):
            for which, tree in trees.items():
                runs[which].append(run_child(tree, args.repeats, files[which]))
                print(which, json.dumps(runs[which][-1]), flush=True)
        accuracy = differences(files["before"], files["after"])
    threads: dict = {"before": [], "after": []}
    for _ in range(args.rounds):
        for which, tree in trees.items():
            threads[which].append(run_threads_child(tree, args.repeats))
    default_threads = {which: {k: float(np.median([r[k] for r in rounds]))
                               for k in ("cpu", "wall")} for which, rounds in threads.items()}
    medians = {which: {loop: {stage: float(np.median([r[loop][stage] for r in rounds]))
                              for stage in STAGES + ("total",)}
                       for loop in ("three_axis", "planar")}
               for which, rounds in runs.items()}
    results = {"machine": info, "revisions": {k: revision(t) for k, t in trees.items()},
               "rounds": args.rounds, "repeats": args.repeats, "blas_threads": 1,
               "cpu_median_s": medians, "runs": runs, "accuracy_relative": accuracy}
    sweep = {which: float(np.median([r["sweep_sample"]["simulate"] for r in rounds]))
             for which, rounds in runs.items()}
    results["sweep_sample_simulate_cpu_median_s"] = sweep
    results["sweep_sample_method"] = {which: rounds[-1]["sweep_sample"]["method"]
                                      for which, rounds in runs.items()}
    results["three_axis_build_truth_default_threads_s"] = default_threads
    results["default_threads_runs"] = threads
    write_json("lqr_simulate_speed.json", results)
    rows = []
    for loop in ("three_axis", "planar"):
        for stage in STAGES + ("total",):
            b, a = medians["before"][loop][stage], medians["after"][loop][stage]
            rows.append([loop, stage, f"{b * 1e3:.2f}", f"{a * 1e3:.2f}", f"{a / b:.2f}"])
    loads = [r["load_before"][0] for rs in runs.values() for r in rs]
    lines = ["# LQR, simulation and plant builds of the design loop: before and after", "",
             f"`python benchmarks/lqr_simulate_speed.py --before <checkout> --rounds "
             f"{args.rounds} --repeats {args.repeats}` on {info['date_utc']} UTC, {info['cpu']}, "
             f"{info['nproc']} cores; one BLAS thread; before {results['revisions']['before']}, "
             f"after {results['revisions']['after']}; {args.rounds} rounds per checkout, "
             f"alternating, each a fresh process timing {args.repeats} evaluations of every "
             f"stage; 1-minute load average {min(loads):.2f} to {max(loads):.2f} over the "
             "rounds (each round's in the JSON).", "",
             "CPU time (time.process_time), median over the rounds of each round's median [ms]:",
             "",
             markdown_table(["loop", "stage", "before", "after", "after / before"], rows), "",
             f"A sweep sample's simulation (the shipped sweep scene's loop, "
             f"{runs['after'][-1]['sweep_sample']['states']} states, "
             f"{runs['after'][-1]['sweep_sample']['samples']} samples): "
             f"{sweep['before'] * 1e3:.2f} ms ({results['sweep_sample_method']['before']}) -> "
             f"{sweep['after'] * 1e3:.2f} ms ({results['sweep_sample_method']['after']}), "
             f"{sweep['after'] / sweep['before']:.2f}.", "",
             "The three-axis truth build with the default BLAS threads (OpenBLAS, one per "
             "core; the same alternation, medians) [ms]: CPU "
             f"{default_threads['before']['cpu'] * 1e3:.2f} -> "
             f"{default_threads['after']['cpu'] * 1e3:.2f}, wall "
             f"{default_threads['before']['wall'] * 1e3:.2f} -> "
             f"{default_threads['after']['wall'] * 1e3:.2f}.", "",
             "Results, after against before (max |after - before| / max |before|): "
             + ", ".join(f"{k} {v:.1e}" if isinstance(v, float) else f"{k} {v}"
                         for k, v in accuracy.items()), ""]
    text = "\n".join(lines) + "\n"
    (RESULTS / "lqr_simulate_speed.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
