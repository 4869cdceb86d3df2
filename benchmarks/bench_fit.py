"""Speed and accuracy of fit_chain (issue 10): cold and memoised fits, BLAS threads unset and one.

For n = 3 .. ``--max-bodies`` (the ``fit_bodies`` limit of appendages.limits) the paper's rod is
fitted with ``fit_chain(rod, n)`` (match="poles-and-zeros", the default), and for the cold
timings also the unit beam (L = EJ = rho = 1).

Timings run in one subprocess per BLAS setting: OPENBLAS/OMP/MKL_NUM_THREADS unset (as a user has
them; the machine has 2 cores) and all set to 1. In each subprocess:

- the first fit of the process (3 bodies; it also imports threadpoolctl and finds the BLAS
  libraries, once per process);
- per n and beam, *cold*: ``appendages.fitting.clear_memo()`` then ``fit_chain(beam, n)``,
  median of ``--repeats`` (three times as many up to 6 bodies, whose short fits are noisier),
  measured in rounds over every n and beam (a burst of load stretches several n alike);
  *memoised*: ``fit_chain(other_beam, n)`` served from the memo (a steel tube of
  another size: the memo is per options, not per beam), median of at least 50 calls;
- wall time (perf_counter) and the process's CPU time (process_time), and the lowest and
  highest 1-min load average seen before the rounds' fits of each n: wall time on a shared
  machine is CPU time stretched by the load.

Whether the cold CPU time increases with n (issue 10: the cost monotonic in the number of
bodies; appendages.fitting, "The work schedule") is printed and recorded, with the smallest step
ratio between consecutive n and whether every step is at least +10 % (a margin that survives
the noise of a shared machine).

Accuracy, in the main process, per n: the fit's own objective (the weighted least-squares cost,
``appendages.fitting``: it is the same for every beam), the largest relative error of the first
two poles ("p2"), of the first two zeros of W1, W2, W4 ("z2"), of every pole and zero the chain has
("all"), and the band error of ``criterion`` ("band"), beside today's fit: ``fit_chain`` of
commit f575039 on the same rod (``TODAY``, measured with ``--today DIR`` where DIR holds that
commit's ``appendages``: ``git archive f575039 appendages | tar -x -C DIR``), and the relative
change of each against the fit before its work schedule (fit version 3, ``BEFORE``). Beyond the
limit (``--beyond``), one cold fit each shows why the limit stops where it does.

Run: python benchmarks/bench_fit.py [--repeats 5] [--max-bodies 14] [--beyond 16]
                                    [--today DIR] [--quick]
Writes benchmarks/results/fit.json and fit.md (full mode: about 5 minutes on a quiet machine),
or with ``--quick`` (3 to 7 bodies, 3 repeats, nothing beyond the limit: about 1 minute)
fit_quick.json and fit_quick.md.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import _common  # noqa: E402  (sets the BLAS threads of this process before numpy)
import numpy as np  # noqa: E402

from appendages import fitting, limits  # noqa: E402
from appendages.beam import Beam  # noqa: E402
from appendages.chain import HingedChain  # noqa: E402
from appendages.equivalence import criterion, fit_chain, spectral_errors  # noqa: E402

THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")

# Today's fit (commit f575039, appendages.equivalence.fit_chain) on the paper's rod, measured
# with --today on 2026-11-22 10:52 UTC (OPENBLAS_NUM_THREADS=1, load average 14-15): the cost of
# the fit's objective, the error measures of this script, and the CPU time of one fit [s].
TODAY = {
    3: {"cost": 3.600042e-04, "p2": 5.726e-05, "z2": 1.708e-02, "all": 1.708e-02,
        "band": 1.566e+00, "cpu_s": 1.25},
    4: {"cost": 2.268441e-04, "p2": 1.852e-07, "z2": 7.096e-03, "all": 1.270e-02,
        "band": 3.581e-01, "cpu_s": 3.74},
    5: {"cost": 1.567917e-04, "p2": 4.057e-07, "z2": 3.891e-03, "all": 1.062e-02,
        "band": 1.960e-01, "cpu_s": 2.22},
    6: {"cost": 1.153188e-04, "p2": 1.098e-07, "z2": 2.435e-03, "all": 9.154e-03,
        "band": 1.224e-01, "cpu_s": 5.36},
    7: {"cost": 9.040029e-05, "p2": 2.094e-06, "z2": 1.653e-03, "all": 7.840e-03,
        "band": 8.304e-02, "cpu_s": 2.30},
    8: {"cost": 7.434134e-05, "p2": 3.481e-06, "z2": 1.179e-03, "all": 6.761e-03,
        "band": 5.917e-02, "cpu_s": 2.16},
    9: {"cost": 6.351099e-05, "p2": 6.556e-06, "z2": 8.863e-04, "all": 5.792e-03,
        "band": 4.446e-02, "cpu_s": 2.63},
    10: {"cost": 4.770060e-05, "p2": 1.004e-07, "z2": 6.873e-04, "all": 5.977e-03,
        "band": 3.446e-02, "cpu_s": 12.27},
    11: {"cost": 4.033787e-05, "p2": 1.113e-07, "z2": 5.452e-04, "all": 5.510e-03,
        "band": 2.733e-02, "cpu_s": 13.23},
    12: {"cost": 3.459191e-05, "p2": 6.865e-08, "z2": 4.418e-04, "all": 5.114e-03,
        "band": 2.214e-02, "cpu_s": 17.96},
}

# The fit before its work schedule (FIT_VERSION 3, commit e513dca) on the paper's rod:
# benchmarks/results/fit.json of that commit (2026-11-22 12:22 UTC), full precision. The
# accuracy columns of this script; "bound" the modal bound there.
BEFORE = {
    3: {"cost": 0.0003600042046783274, "p2": 5.7413861241917274e-05,
        "z2": 0.017079622571755104, "all": 0.017079622571755104,
        "band": 1.5660147787251002, "bound": 0.00036000420379936647},
    4: {"cost": 0.00022684407154242975, "p2": 1.6562299354205834e-07,
        "z2": 0.007096030016213617, "all": 0.012703323343255746,
        "band": 0.3580709079347346, "bound": 0.0002268440714874071},
    5: {"cost": 0.00015679168121607968, "p2": 3.716886822768828e-07,
        "z2": 0.003890984261844088, "all": 0.010624913876574382,
        "band": 0.195980695468315, "bound": 0.00015679168020698545},
    6: {"cost": 0.00011531830503696168, "p2": 1.6050527618105548e-07,
        "z2": 0.0024347289268216166, "all": 0.009156467441754579,
        "band": 0.1224265462556318, "bound": 0.00011531810070894603},
    7: {"cost": 9.038251092105213e-05, "p2": 1.3433458081468785e-06,
        "z2": 0.0016549998714054936, "all": 0.00782053537749694,
        "band": 0.08311917311819621, "bound": 8.862770716076777e-05},
    8: {"cost": 7.434075823661093e-05, "p2": 3.9344651419082055e-06,
        "z2": 0.0011893652600669657, "all": 0.006731050679171124,
        "band": 0.05968801633770113, "bound": 7.039168202777555e-05},
    9: {"cost": 6.364554381939553e-05, "p2": 5.5199184565424275e-06,
        "z2": 0.0008905953720895754, "all": 0.005773253954486135,
        "band": 0.044671822385806456, "bound": 5.7353387250577055e-05},
    10: {"cost": 4.769596720042224e-05, "p2": 3.9318871492000085e-08,
        "z2": 0.0006872393321071257, "all": 0.005976933384891137,
        "band": 0.03446019433595437, "bound": 4.769299890119515e-05},
    11: {"cost": 4.033131114900258e-05, "p2": 6.199649993376966e-08,
        "z2": 0.000545169775243437, "all": 0.0055107653285544345,
        "band": 0.027330007649106237, "bound": 4.0326578054644746e-05},
    12: {"cost": 3.458375019865121e-05, "p2": 1.1110444964046451e-07,
        "z2": 0.0004416342570511267, "all": 0.0051151518517735806,
        "band": 0.022135923034156364, "bound": 3.4574741495202076e-05},
    13: {"cost": 3.0008217192080352e-05, "p2": 1.6637839705957447e-07,
        "z2": 0.000363998915685948, "all": 0.004775278522650028,
        "band": 0.01824236860107962, "bound": 2.9993531620386383e-05},
    14: {"cost": 2.6295206107819286e-05, "p2": 1.1685351619661333e-07,
        "z2": 0.0003045415041751376, "all": 0.004477848186054345,
        "band": 0.015261142273484431, "bound": 2.6282560657771718e-05},
    15: {"cost": 0.00011289370171536128, "p2": 1.1646111930829761e-05,
        "z2": 0.0008378060209458527, "all": 0.00825994243082806,
        "band": 0.041915270131437754, "bound": 2.3232499379465674e-05},
    16: {"cost": 0.008129725405723907, "p2": 2.578832611010995e-06,
        "z2": 0.001144638298429923, "all": 0.09416252516544754,
        "band": 0.057317886552340484, "bound": 2.069373410522177e-05},
}

_WORKER = r"""
import json, os, statistics, sys, time
sys.path.insert(0, {root!r})
from appendages import fitting, limits
from appendages.beam import Beam
from appendages.equivalence import fit_chain
beams = {{"rod": Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11), "unit": Beam(1.0, 1.0, 1.0)}}
other = Beam.tube(3.0, 0.05, 0.002, 2700.0, 7.0e10)
repeats = {repeats}

def timed(function):
    wall, cpu = time.perf_counter(), time.process_time()
    function()
    return time.perf_counter() - wall, time.process_time() - cpu

out = {{"first_fit": None, "rows": []}}
with limits.raised(fit_bodies=max({bodies})):
    out["first_fit"] = timed(lambda: fit_chain(beams["rod"], 3))
    # rounds over every n and beam, so that a burst of load on the shared machine stretches
    # several n alike instead of all the repeats of one n
    cold = {{(n, name): [] for n in {bodies} for name in beams}}
    loads = {{n: [] for n in {bodies}}}
    for round_ in range(3 * repeats):
        for n in {bodies}:
            if round_ >= repeats and n > 6:  # short fits (<= 6 bodies): three times as many
                continue
            loads[n].append(os.getloadavg()[0])
            for name, beam in beams.items():
                fitting.clear_memo()
                cold[n, name].append(timed(lambda: fit_chain(beam, n)))
    for n in {bodies}:
        row = {{"n_bodies": n}}
        for name in beams:
            prefix = "" if name == "rod" else name + "_"
            row[prefix + "cold_wall_s"] = statistics.median(w for w, _ in cold[n, name])
            row[prefix + "cold_cpu_s"] = statistics.median(c for _, c in cold[n, name])
            row[prefix + "cold_cpu_all_s"] = [c for _, c in cold[n, name]]
        memo = [timed(lambda: fit_chain(other, n)) for _ in range(max(50, repeats))]
        row.update(memo_wall_s=statistics.median(w for w, _ in memo),
                   nfev=fitting.fit_poles_and_zeros(n).nfev, load_min=min(loads[n]),
                   load_max=max(loads[n]))
        out["rows"].append(row)
print(json.dumps(out))
"""


def _today_literal(today: dict) -> str:
    """``today`` as the literal of TODAY (to paste above)."""
    lines = ["TODAY = {"]
    for n, row in sorted(today.items()):
        lines.append(f'    {n}: {{"cost": {row["cost"]:.6e}, "p2": {row["p2"]:.3e}, '
                     f'"z2": {row["z2"]:.3e}, "all": {row["all"]:.3e},')
        lines.append(f'        "band": {row["band"]:.3e}, "cpu_s": {row["cpu_s"]:.2f}}},')
    return "\n".join(lines) + "\n}"


def run_worker(bodies: list[int], repeats: int, threads: str | None) -> dict:
    """Timings of a subprocess with the BLAS thread variables unset (None) or set."""
    environment = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    if threads is None:
        environment["FLEXSAT_BENCH_BLAS_THREADS"] = "default"
    else:
        for name in THREAD_VARIABLES:
            environment[name] = threads
    code = _WORKER.format(root=str(_common.ROOT), repeats=repeats, bodies=list(bodies))
    done = subprocess.run([sys.executable, "-c", code], env=environment, capture_output=True,
                          text=True)
    if done.returncode != 0:
        raise RuntimeError(f"timing subprocess failed:\n{done.stderr}")
    return json.loads(done.stdout)


def accuracy(rod, chain) -> dict:
    """The fit's objective and the error measures of the module docstring."""
    n = chain.n_bodies
    L, EJ, rho = rod.length, rod.bending_stiffness, rod.linear_density
    arrays = (chain.lengths / L, chain.masses / (rho * L), chain.inertias / (rho * L**3),
              chain.com_offsets / L, chain.hinge_stiffnesses / (EJ / L))
    weights = np.concatenate([np.full(n - 1, 10.0), np.ones(3 * (n - 1))])
    problem = fitting._Problem(fitting._Layout(n), weights)
    residual = weights * (np.log(fitting._spectrum(arrays, n - 1)) - problem.log_target)
    every = spectral_errors(rod, chain)
    first_two = spectral_errors(rod, chain, 2)
    return {"cost": 0.5 * float(residual @ residual),
            "p2": float(np.abs(first_two["poles"]).max()),
            "z2": float(max(np.abs(first_two[k]).max() for k in ("W1", "W2", "W4"))),
            "all": float(max(np.abs(e).max() for e in every.values())),
            "band": float(criterion(rod, chain).max_log_error.max())}


def modal_bound(n: int, pole_weight: float = 10.0) -> float:
    """The fit's objective minimised over modal models instead of chains.

    Every pole and zero of a chain depends on its W(s) = R/s**2 + sum_k phi_k phi_k^T /
    (s**2 + w_k**2) only: R (the rigid part, fixed by m, J and the centre of mass) and, per mode,
    w_k and the root participations phi_k = (delta, phi) entries of the mass-normalised mode,
    3 (n - 1) numbers. This fits those numbers directly (logs of w_k**2 and of the squared
    participations, the signs of their products kept from the RFEM chain): a well-conditioned
    problem with a local minimum no chain of the fit's family can undercut near it. Zeros: the
    finite eigenvalues of the Rosenbrock pencil of the modal realisation. Units L = EJ = rho = 1.
    """
    import scipy.linalg
    import scipy.optimize

    from appendages.chain import chain_matrices

    k = n - 1
    M, _, K, _ = chain_matrices(*fitting._rfem_arrays(n), None, False)
    lam, modes = scipy.linalg.eigh(K, M)
    rigid = modes[:2, :2] @ modes[:2, :2].T  # R: the rigid modes' participations
    root = np.linalg.cholesky(rigid)
    signs = np.sign(modes[0, 2:] * modes[1, 2:])
    log_target = np.log(fitting._targets(k))

    def zeros(squares, inputs, output, into):
        size = squares.size + 2
        A, E = np.zeros((size + 1, size + 1)), np.zeros((size + 1, size + 1))
        A[:size, :size] = np.diag(np.concatenate([[0.0, 0.0], squares]))
        E[:size, :size] = np.eye(size)
        A[:size, size], A[size, :size] = inputs[:, into], inputs[:, output]
        values = scipy.linalg.eigvals(A, E)
        values = np.sort(values[np.isfinite(values)].real)
        return values[values > 1e-9 * squares.max()]

    def residual(p, weights):
        squares, delta, phi = np.exp(p[:k]), np.exp(p[k:2 * k] / 2), signs * np.exp(p[2 * k:] / 2)
        inputs = np.vstack([root.T, np.stack([delta, phi], axis=1)])
        values = [squares]
        for output, into in ((0, 0), (0, 1), (1, 1)):
            z = zeros(squares, inputs, output, into)
            if z.size < k:
                return np.full(4 * k, 10.0)
            values.append(z[:k])
        return weights * (0.5 * np.log(np.concatenate(values)) - log_target)

    p = np.concatenate([np.log(lam[2:]), np.log(modes[0, 2:] ** 2), np.log(modes[1, 2:] ** 2)])
    for weight in (1.0, pole_weight):
        weights = np.concatenate([np.full(k, weight), np.ones(3 * k)])
        result = scipy.optimize.least_squares(residual, p, args=(weights,), xtol=1e-12,
                                              ftol=1e-12, gtol=1e-12)
        p = result.x
    return float(result.cost)


def measure_today(source: Path, bodies: list[int]) -> dict:
    """Today's fits (the appendages package in ``source``) on the rod, one subprocess."""
    code = (f"import json, sys, time\nsys.path.insert(0, {str(source)!r})\n"
            "from appendages.beam import Beam\nfrom appendages.equivalence import fit_chain\n"
            "rod = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)\nout = {}\n"
            f"for n in {list(bodies)}:\n"
            "    t = time.process_time(); c = fit_chain(rod, n)\n"
            "    out[n] = dict(cpu_s=time.process_time() - t, arrays=[a.tolist() for a in "
            "(c.lengths, c.masses, c.inertias, c.hinge_stiffnesses, c.com_offsets)])\n"
            "print(json.dumps(out))\n")
    environment = dict(os.environ, **{name: "1" for name in THREAD_VARIABLES})
    done = subprocess.run([sys.executable, "-c", code], env=environment, capture_output=True,
                          text=True, check=True, cwd=str(source))
    rod = _common.paper_rod()
    today = {}
    for n, entry in json.loads(done.stdout).items():
        lengths, masses, inertias, stiffnesses, offsets = entry["arrays"]
        chain = HingedChain(lengths, masses, inertias, stiffnesses, com_offsets=offsets)
        today[int(n)] = dict(accuracy(rod, chain), cpu_s=round(entry["cpu_s"], 2))
    return today


def main(argv=None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5, help="cold fits per n (median)")
    parser.add_argument("--max-bodies", type=int, default=limits.current("fit_bodies"))
    parser.add_argument("--beyond", type=int, default=16,
                        help="also one cold fit each up to this many bodies")
    parser.add_argument("--today", type=Path, default=None,
                        help="directory with today's appendages package: re-measure TODAY")
    parser.add_argument("--quick", action="store_true",
                        help="3 to 7 bodies, 3 repeats, nothing beyond the limit; writes "
                             "fit_quick.{json,md} (a smoke run, about 1 min)")
    args = parser.parse_args(argv)
    if args.quick:
        args.repeats, args.max_bodies, args.beyond = 3, min(args.max_bodies, 7), 0
    bodies = list(range(3, args.max_bodies + 1))
    info = _common.machine_info()
    today = TODAY
    if args.today is not None:
        today = measure_today(args.today, [n for n in bodies if n <= 12])
        print(_today_literal(today))

    timings = {}
    for label, threads in (("threads unset", None), ("OPENBLAS_NUM_THREADS=1", "1")):
        timings[label] = run_worker(bodies, args.repeats, threads)
        rows = timings[label]["rows"]
        print(f"{label}: first fit {timings[label]['first_fit'][0]:.3f} s; cold CPU " + ", ".join(
            f"{r['n_bodies']}: {r['cold_cpu_s']:.3f} s" for r in rows), flush=True)
        for key, beam in (("cold_cpu_s", "rod"), ("unit_cold_cpu_s", "unit beam")):
            print(f"  {beam}: " + _monotonic_text(steps([r[key] for r in rows])), flush=True)

    rod = _common.paper_rod()
    rows = []
    with limits.raised(fit_bodies=max(args.max_bodies, args.beyond)):
        for n in range(3, max(args.max_bodies, args.beyond) + 1):
            fitting.clear_memo()
            wall, cpu = time.perf_counter(), time.process_time()
            chain = fit_chain(rod, n)
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
            row = {"n_bodies": n, "within_limit": n <= args.max_bodies,
                   "one_fit_wall_s": wall, "one_fit_cpu_s": cpu,
                   "load_average": os.getloadavg()[0], **accuracy(rod, chain),
                   "modal_bound": modal_bound(n)}
            if n in today:
                row["today"] = today[n]
            if n in BEFORE:
                row["before"] = BEFORE[n]
            rows.append(row)
            print(f"{n} bodies: cost {row['cost']:.4e}"
                  + (f" (today {today[n]['cost']:.4e})" if n in today else ""), flush=True)

    out = {"machine": info, "repeats": args.repeats, "fit_bodies_limit": args.max_bodies,
           "quick": args.quick, "timings": timings, "accuracy": rows,
           "fit_version": fitting.FIT_VERSION, "load_average_end": list(os.getloadavg())}
    for data in timings.values():
        for key in ("cold_cpu", "unit_cold_cpu", "cold_wall"):
            data[key + "_steps"] = steps([r[key + "_s"] for r in data["rows"]])
    stem = "fit_quick" if args.quick else "fit"
    _common.write_json(f"{stem}.json", out)
    markdown = to_markdown(out)
    (_common.RESULTS / f"{stem}.md").write_text(markdown)
    print(markdown)
    return out


def steps(values) -> dict:
    """Whether ``values`` (one per n, n increasing) increase, and their smallest step ratio."""
    ratios = [b / a for a, b in zip(values, values[1:])]
    if not ratios:
        return {"increasing": True, "smallest_ratio": None, "at": None}
    at = min(range(len(ratios)), key=ratios.__getitem__)
    return {"increasing": all(r > 1.0 for r in ratios), "smallest_ratio": ratios[at], "at": at}


def _monotonic_text(step: dict, first_n: int = 3) -> str:
    if step["smallest_ratio"] is None:
        return "one n only"
    n = first_n + step["at"]
    return (f"increasing in n: {'yes' if step['increasing'] else 'no'}; smallest step "
            f"{step['smallest_ratio'] - 1:+.0%} ({n} -> {n + 1} bodies), each step >= +10 %: "
            f"{'yes' if step['smallest_ratio'] >= 1.1 else 'no'}")


def to_markdown(out: dict) -> str:
    info = out["machine"]
    lines = ["# fit_chain: speed and accuracy (issue 10)", "",
             "Generated by `benchmarks/bench_fit.py`"
             + (" --quick" if out.get("quick") else "") + ": the paper's rod, "
             "`fit_chain(rod, n)` (match=\"poles-and-zeros\", fit version "
             f"{out['fit_version']}), and the unit beam (L = EJ = rho = 1). "
             f"{info['date_utc']} UTC, {info['cpu']}, {info['nproc']} cores (shared), numpy "
             f"{info['numpy']}, scipy {info['scipy']}; load average (1 min) per row.", "",
             "## Time per fit", "",
             f"Cold: memo cleared, median of {out['repeats']}; memoised: a fit of another beam "
             "with the same options (median of 50). Wall and CPU time of the process [s]; "
             "evaluations: residual evaluations of one fit (`evaluation_budget`); step: cold "
             "CPU time over the previous row's. The fit's work does not depend on the beam "
             "(appendages.fitting, scale invariance): the unit beam's column measures the "
             "same work again.", ""]
    for label, data in out["timings"].items():
        first = data["first_fit"]
        rows = data["rows"]
        lines += [f"### {label}", "",
                  f"First fit of a process (3 bodies, imports threadpoolctl): {first[0]:.3f} s "
                  f"wall, {first[1]:.3f} s CPU.", ""]
        header = ["bodies", "evaluations", "cold wall [s]", "cold CPU [s]", "step",
                  "unit beam: cold CPU [s]", "step", "memoised [ms]", "load min / max"]
        body = []
        for i, r in enumerate(rows):
            cells = [r["n_bodies"], r["nfev"], f"{r['cold_wall_s']:.3f}"]
            for key in ("cold_cpu_s", "unit_cold_cpu_s"):
                cells += [f"{r[key]:.3f}",
                          "-" if i == 0 else f"{r[key] / rows[i - 1][key] - 1:+.0%}"]
            cells += [f"{1e3 * r['memo_wall_s']:.3f}",
                      f"{r['load_min']:.1f} / {r['load_max']:.1f}"]
            body.append(cells)
        lines += [_common.markdown_table(header, body), "",
                  "Cold CPU time, rod: " + _monotonic_text(data["cold_cpu_steps"])
                  + ". Unit beam: " + _monotonic_text(data["unit_cold_cpu_steps"])
                  + ". Cold wall time: " + _monotonic_text(data["cold_wall_steps"]) + ".", ""]
    lines += ["## Accuracy against the exact beam, beside today's fit", "",
              "cost: the fit's objective (weighted least squares in log-frequency, the same for "
              "every beam); bound: the same objective minimised over modal models (the "
              "3 (n - 1) numbers a chain's W(s) depends on, `modal_bound`), and how far each "
              "fit's cost lies above it; p2, z2: largest relative error of the first two "
              "poles, of the first two zeros of W1, W2, W4; all: of every pole and zero of the "
              "chain; band: max |ln(W_r^chain / W_r^beam)| on the criterion's default band. "
              "Today: commit f575039 on the same rod (CPU time of one fit there, "
              "single-threaded BLAS). A star: not worse than today.", ""]
    header = ["bodies", "cost", "today", "bound", "above bound: new / today", "p2", "today",
              "z2", "today", "all", "today", "band", "today", "one fit CPU [s]", "today"]
    body = []
    for r in out["accuracy"]:
        t = r.get("today")
        cells = [f"{r['n_bodies']}" + ("" if r["within_limit"] else " (beyond limit)")]
        for key in ("cost", "p2", "z2", "all", "band"):
            star = "*" if t is not None and r[key] <= t[key] * (1 + 1e-6) else ""
            cells += [f"{r[key]:.4g}{star}", "-" if t is None else f"{t[key]:.4g}"]
            if key == "cost":
                bound = r["modal_bound"]
                cells += [f"{bound:.4g}", f"{r['cost'] / bound - 1:+.1%} / "
                          + ("-" if t is None else f"{t['cost'] / bound - 1:+.1%}")]
        cells += [f"{r['one_fit_cpu_s']:.2f}", "-" if t is None else f"{t['cpu_s']:.2f}"]
        body.append(cells)
    lines += [_common.markdown_table(header, body), ""]
    lines += ["## Against the fit before its work schedule", "",
              "Relative change of each accuracy column against fit version 3 (commit e513dca, "
              "`BEFORE`: the previous fit.json), negative = better; \"=\" within 1e-6. "
              "above bound: before -> now.", ""]
    header = ["bodies", "above bound", "cost", "p2", "z2", "all", "band"]
    body = []
    for r in out["accuracy"]:
        b = r.get("before")
        if b is None:
            continue
        cells = [f"{r['n_bodies']}" + ("" if r["within_limit"] else " (beyond limit)"),
                 f"{b['cost'] / b['bound'] - 1:+.2%} -> {r['cost'] / r['modal_bound'] - 1:+.2%}"]
        for key in ("cost", "p2", "z2", "all", "band"):
            change = r[key] / b[key] - 1
            cells.append("=" if abs(change) <= 1e-6 else f"{change:+.2%}")
        body.append(cells)
    lines += [_common.markdown_table(header, body), ""]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
