"""``flexsat sweep``: the command-line face of :func:`spacecraft.sweep.run_sweep`.

``flexsat sweep [SCENE] [--samples N] [--out DIR] [--scheduler ADDRESS] [--workers N]
[--resume] [--seed S] [--method M] [--design D] [--no-worst-case]
[--worst-case-evaluations N] [--max-samples N]
[--no-plots] [--quiet] [--json]``

SCENE is a scene file with a ``[sweep]`` table or an embedded sweep scene's name (default: the
embedded ``default`` sweep). Options override the ``[sweep]`` table. Errors of the user or the
environment (bad scene or sweep, unreachable scheduler, output folder in the way) are one line on
stderr with exit code 2 (:func:`spacecraft.cli.main` handles them).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

__all__ = ["add_arguments", "run_command", "summary_lines", "main"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the options of ``flexsat sweep`` to a (sub)parser."""
    parser.add_argument("scene", nargs="?", help="scene file with a [sweep] table, or an "
                                                 "embedded sweep scene (default: 'default')")
    parser.add_argument("--samples", type=int, help="Monte Carlo / Latin-hypercube samples")
    parser.add_argument("--out", type=Path, help="output folder (default: a new "
                                                 "flexsat-<timestamp> folder here)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="run on a running Dask cluster (tcp://host:8786)")
    parser.add_argument("--workers", type=int, help="local worker processes (default: one per "
                                                    "core; 1 runs in this process)")
    parser.add_argument("--resume", action="store_true",
                        help="continue the interrupted sweep in --out")
    parser.add_argument("--seed", type=int, help="random seed")
    parser.add_argument("--method", choices=("monte-carlo", "latin-hypercube", "grid"))
    parser.add_argument("--design", choices=("per-sample", "nominal"),
                        help="tune per sample, or hold the nominal controller")
    parser.add_argument("--no-worst-case", action="store_true", help="skip the worst-case "
                                                                     "search")
    parser.add_argument("--worst-case-evaluations", type=int, metavar="N",
                        help="evaluations per worst-case search (default 600)")
    parser.add_argument("--max-samples", type=int, help="raise the sample limit (1000000)")
    parser.add_argument("--no-plots", action="store_true", help="skip plots")
    parser.add_argument("--quiet", action="store_true", help="no progress display")
    parser.add_argument("--json", action="store_true", help="print summary.json to stdout")


def summary_lines(summary: dict) -> list[str]:
    """Short summary of a sweep (printed by the command)."""
    from ..sweep.report import format_number as _fmt, instability_text

    s = summary
    inst = s["instability"]
    failed = s["samples"]["failed"]
    lines = [f"{s['samples']['total']} samples ({failed} failed) on "
             f"{s['executor']}, {_fmt(s['timings'].get('samples'), 3)} s; "
             f"{_fmt(1e3 * (s['timings'].get('per_sample_median') or math.nan), 3)} ms per "
             "sample (median)",
             f"probability of instability ({inst['verdict']} verdict): " + instability_text(s)]
    statuses = s["samples"].get("status") or {}
    if statuses:
        lines.append("slews on the truth model: " + ", ".join(f"{k} {v}"
                                                             for k, v in statuses.items()))
    ranking = s["sensitivity"]["ranking"]
    if ranking:
        lines.append("most influential: " + ", ".join(
            f"{r['parameter']} ({_fmt(r['spearman'], 2)})" for r in ranking[:3]))
    for w in s["worst_case"]:
        ver = w.get("verification") or {}
        exact = ver.get("exact_reference", {})
        check = (f"; exact beam: {_fmt(exact.get(w['metric']))}, "
                 f"{'stable' if exact.get('stable') else 'UNSTABLE'}" if "stable" in exact
                 else "")
        verdict = "stable" if w["row"].get("stable") else "UNSTABLE"
        lines.append(f"worst {w['metric'].replace('_', ' ')}: {_fmt(w['objective'])} (signed; "
                     f"{verdict}) at " + ", ".join(f"{k} = {_fmt(v, 6)}"
                                                   for k, v in w["values"].items())
                     + f"{check} [{ver.get('scene') or ver.get('note', '')}]")
    if s.get("worst_case_skipped"):
        lines.append(f"worst case: not searched ({s['worst_case_skipped']})")
    return lines


def run_command(args) -> int:
    """Run ``flexsat sweep`` with parsed arguments; returns the exit code."""
    from .progress import Progress
    from ..report.write import default_output_folder, to_json
    from ..sweep.runner import run_sweep

    log = Progress(args.quiet)
    out = args.out if args.out is not None else (None if args.resume else default_output_folder())
    settings = {"samples": args.samples, "seed": args.seed, "method": args.method,
                "design": args.design, "worst_case_evaluations": args.worst_case_evaluations}
    if args.no_worst_case:
        settings["worst_case"] = False
    result = run_sweep(args.scene, out=out, scheduler=args.scheduler, workers=args.workers,
                       resume=args.resume, progress=not args.quiet, plots=not args.no_plots,
                       max_samples=args.max_samples, log=log, **settings)
    log(f"done in {time.perf_counter() - log.t0:.1f} s")
    if args.json:
        print(to_json(result.summary))
        return _all_failed(result.summary, out)
    for line in summary_lines(result.summary):
        print(line)
    print(f"wrote summary.json, report.md, report.html and samples/*.parquet to {out}")
    return _all_failed(result.summary, out)


def _all_failed(summary: dict, out) -> int:
    """0, or a SweepError when no sample could be evaluated (the report says why)."""
    from ..sweep.parameters import SweepError

    if summary["instability"]["of"]:
        return 0
    first = summary["failures"][0]["error"] if summary["failures"] else "?"
    raise SweepError(f"every one of the {summary['samples']['total']} samples failed, so the "
                     f"sweep has no verdict (most common error: {first[:200]}); "
                     f"{out}/report.md lists the errors")


def main(argv=None) -> int:
    """``python -m spacecraft.cli.sweep``: the sweep without the ``flexsat`` front end
    (the same options; user errors exit 2 with one line)."""
    from appendages.interface import FlexsatError

    parser = argparse.ArgumentParser(prog="python -m spacecraft.cli.sweep",
                                     description=__doc__.splitlines()[0])
    add_arguments(parser)
    args = parser.parse_args(argv)
    try:
        return run_command(args)
    except FlexsatError as exc:
        print(f"flexsat: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("flexsat: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
