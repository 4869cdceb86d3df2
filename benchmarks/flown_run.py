"""Benchmark: the default scene's flown slew against today's, end to end as a user runs them.

``flexsat run default`` (the cycloid of theta_ref alone, an ideal loop) against ``flexsat run
default_flown`` (the same models and controllers; the shaped bang-coast-bang profile with
feedforward, one reaction wheel with friction, a 0.1 s loop delay in every verdict and the
simulation, sensor noise and the pointing figures), with the same options: ``--no-fmu`` (the
flown scene exports no closed-loop FMU: it has no delay) with and without ``--no-plots``. Each
case is a fresh ``python -m spacecraft.cli run`` process from the repository root; its wall
time and CPU time (user + system of the child, ``resource.getrusage(RUSAGE_CHILDREN)``: the
ratio that holds on a loaded machine), the load average before it. The cases take turns so the
machine's load hits them alike; medians of the repetitions.

Not a test. Writes ``benchmarks/results/flown_run.json`` and ``.md``.

``--three-axis``: ``flexsat run three_axis`` against ``flexsat run three_axis_flown`` (the
three-axis spacecraft's eigen-axis slew shaped and fed forward through a four-wheel pyramid,
with the delay and the sensor noise), ``--no-fmu --no-plots``; its section of flown_run.md
(``## Three axes``) is replaced, the planar table kept, and the figures go to
``flown_run_three_axis.json``.

    python benchmarks/flown_run.py [--quick]    # quick: 3 repetitions, full: 7
    python benchmarks/flown_run.py --three-axis [--repeats N]
"""
from __future__ import annotations

import _common  # noqa: F401  (BLAS settings before numpy)

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

from _common import ROOT, machine_info, markdown_table, write_json, RESULTS

CASES = [("default", ["--no-fmu"]), ("default_flown", ["--no-fmu"]),
         ("default", ["--no-fmu", "--no-plots"]), ("default_flown", ["--no-fmu", "--no-plots"])]
CASES_3 = [("three_axis", ["--no-fmu", "--no-plots"]),
           ("three_axis_flown", ["--no-fmu", "--no-plots"])]
SECTION_3 = "## Three axes"


def run_case(scene: str, options: list, folder: str) -> tuple[float, float]:
    """Wall and CPU time [s] of one ``flexsat run`` in a fresh process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "spacecraft.cli", "run", scene, "--quiet", "--out",
                    os.path.join(folder, f"{scene}-{len(os.listdir(folder))}"), *options],
                   cwd=ROOT, check=True, stdout=subprocess.DEVNULL,
                   env={**os.environ, "PYTHONPATH": str(ROOT)})
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--three-axis", action="store_true")
    parser.add_argument("--repeats", type=int, default=None)
    args = parser.parse_args()
    repeats = args.repeats or (3 if args.quick else 7)
    if args.three_axis:
        return three_axis(repeats)
    times = {i: {"wall": [], "cpu": [], "load": []} for i in range(len(CASES))}
    with tempfile.TemporaryDirectory() as folder:
        run_case("default", ["--no-fmu", "--no-plots"], folder)       # warm-up (bytecode)
        for _ in range(repeats):
            for i, (scene, options) in enumerate(CASES):
                times[i]["load"].append(os.getloadavg()[0])
                wall, cpu = run_case(scene, options, folder)
                times[i]["wall"].append(wall)
                times[i]["cpu"].append(cpu)
                print(scene, options, f"{wall:.2f} s wall, {cpu:.2f} s CPU", flush=True)
    cases = []
    for i, (scene, options) in enumerate(CASES):
        t = times[i]
        cases.append({"scene": scene, "options": options,
                      "wall_s_median": statistics.median(t["wall"]),
                      "cpu_s_median": statistics.median(t["cpu"]),
                      "wall_s": t["wall"], "cpu_s": t["cpu"], "load_average_1min": t["load"]})
    ratios = {" ".join(CASES[i + 1][1]): {
        "cpu": cases[i + 1]["cpu_s_median"] / cases[i]["cpu_s_median"],
        "wall": cases[i + 1]["wall_s_median"] / cases[i]["wall_s_median"]}
        for i in (0, 2)}
    info = machine_info()
    write_json("flown_run.json", {"machine": info, "repeats": repeats, "cases": cases,
                                  "ratio_flown_to_today": ratios})
    rows = [[c["scene"], " ".join(c["options"]), f"{c['wall_s_median']:.2f}",
             f"{c['cpu_s_median']:.2f}",
             f"{min(c['load_average_1min']):.1f}-{max(c['load_average_1min']):.1f}"]
            for c in cases]
    text = (f"# The default scene flown against today's, end to end\n\n{info['date_utc']} UTC, "
            f"{info['cpu']}, {info['nproc']} CPUs; medians of {repeats} runs, the cases "
            "taking turns.\n\n"
            + markdown_table(["scene", "options", "wall [s]", "CPU [s]", "load (1 min)"], rows)
            + "\n\nFlown / today: " + "; ".join(
                f"{options}: CPU {r['cpu']:.2f}x, wall {r['wall']:.2f}x"
                for options, r in ratios.items()) + "\n")
    (RESULTS / "flown_run.md").write_text(text)
    print(text)


def three_axis(repeats: int) -> None:
    """The three-axis scene flown against today's (module docstring)."""
    times = {i: {"wall": [], "cpu": [], "load": []} for i in range(len(CASES_3))}
    with tempfile.TemporaryDirectory() as folder:
        for _ in range(repeats):
            for i, (scene, options) in enumerate(CASES_3):
                times[i]["load"].append(os.getloadavg()[0])
                wall, cpu = run_case(scene, options, folder)
                times[i]["wall"].append(wall)
                times[i]["cpu"].append(cpu)
                print(scene, options, f"{wall:.2f} s wall, {cpu:.2f} s CPU", flush=True)
    cases = [{"scene": scene, "options": options,
              "wall_s_median": statistics.median(times[i]["wall"]),
              "cpu_s_median": statistics.median(times[i]["cpu"]), "wall_s": times[i]["wall"],
              "cpu_s": times[i]["cpu"], "load_average_1min": times[i]["load"]}
             for i, (scene, options) in enumerate(CASES_3)]
    ratio = {"cpu": cases[1]["cpu_s_median"] / cases[0]["cpu_s_median"],
             "wall": cases[1]["wall_s_median"] / cases[0]["wall_s_median"]}
    info = machine_info()
    write_json("flown_run_three_axis.json", {"machine": info, "repeats": repeats,
                                             "cases": cases, "ratio_flown_to_today": ratio})
    rows = [[c["scene"], " ".join(c["options"]), f"{c['wall_s_median']:.1f}",
             f"{c['cpu_s_median']:.1f}",
             f"{min(c['load_average_1min']):.1f}-{max(c['load_average_1min']):.1f}"]
            for c in cases]
    section = (f"{SECTION_3}\n\n{info['date_utc']} UTC, {info['cpu']}, {info['nproc']} CPUs; "
               f"medians of {repeats} run{'s' * (repeats != 1)}, the cases taking turns.\n\n"
               + markdown_table(["scene", "options", "wall [s]", "CPU [s]", "load (1 min)"],
                                rows)
               + f"\n\nFlown / today: CPU {ratio['cpu']:.2f}x, wall {ratio['wall']:.2f}x\n")
    path = RESULTS / "flown_run.md"
    text = path.read_text() if path.exists() else ""
    if SECTION_3 in text:
        text = text[:text.index(SECTION_3)]
    path.write_text(text.rstrip("\n") + "\n\n" + section)
    print(section)


if __name__ == "__main__":
    main()
