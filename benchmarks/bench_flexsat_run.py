"""Wall time of `flexsat run` on the default scene, by stage, and of its skips.

Prints medians over several repetitions and writes benchmarks/results/flexsat_run.json.
Not a test: timings depend on the machine (and on whatever else runs on it).

    python benchmarks/bench_flexsat_run.py [repetitions]
"""
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

from spacecraft.report import output_folder, write_report
from spacecraft.runner import run
from spacecraft.scene import load_scene


def once(scene, *, fmus: bool, plots: bool) -> dict:
    t0 = time.perf_counter()
    result = run(scene)
    t1 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp, output_folder(Path(tmp) / "out") as folder:
        write_report(result, folder, fmus=fmus, plots=plots)
    t2 = time.perf_counter()
    return {"run": t1 - t0, "report": t2 - t1, "total": t2 - t0,
            **{f"stage: {k}": v for k, v in result.stats.seconds.items()}}


def main(repetitions: int = 3) -> None:
    scene = load_scene(None)
    once(scene, fmus=False, plots=True)  # warm-up: imports (matplotlib, fmpy) and caches
    table = {}
    for label, fmus, plots in (("full default run", True, True),
                               ("--no-fmu", False, True),
                               ("--no-fmu --no-plots", False, False)):
        samples = [once(scene, fmus=fmus, plots=plots) for _ in range(repetitions)]
        table[label] = {key: statistics.median(s[key] for s in samples) for key in samples[0]}
        print(f"{label}: median of {repetitions}")
        for key, value in table[label].items():
            print(f"  {key:45s} {value:7.3f} s")
    out = Path(__file__).parent / "results" / "flexsat_run.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps({"repetitions": repetitions, "seconds": table}, indent=2))
    print(f"wrote {out}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)
