"""Run time against error of every appendage model family, and of the tools a user would pick
instead (issue 6, "Benchmarks: run time against error").

One command runs everything::

    python benchmarks/run_time_vs_error.py            # full run (~10-20 min on 2 cores)
    python benchmarks/run_time_vs_error.py --quick    # short run (~1-2 min)
    python benchmarks/run_time_vs_error.py --no-peers # flexsat, python-control and scipy only
    python benchmarks/run_time_vs_error.py --only-peers  # Basilisk and Exudyn into the results

Model families (each against the exact distributed reference):

- beam truncations ``Beam.truncated(n_modes, method=...)`` for "free-free" (the paper's),
  "residual" and "craig-bampton", n_modes from 1 to 64;
- hinged chains ``HingedChain.rfem(beam, n_bodies)`` (2..32 bodies),
  ``HingedChain.superelements(beam, n)`` (3..31 bodies), the paper's three-body chain and,
  when ``appendages.equivalence`` exists, ``fit_chain(beam, n_bodies)`` (2..32 bodies).

Errors (relative, dimensionless):

- ``poles``: max over the first two free-free bending frequencies, |model/exact - 1|;
- ``zeros``: max over the first two zeros of W1, W2 (= W3) and W4;
- ``coupled``: max over the first two coupled frequencies with the default hub (exact:
  Wittrick-Williams roots of the coupled characteristic equation through the exact W);
- ``W_band``: max over r = 1, 2, 4 and 200 log-spaced omega in [0.05, 20] rad/s of
  |W_r,model - W_r,exact| / |W_r,exact| at ``s = omega (-0.05 + i sqrt(1 - 0.05**2))`` (a ray
  at 5 % damping, so that the comparison is finite at the undamped poles and zeros);
- ``slew_theta``, ``slew_tip``, ``slew_torque``: peak error of the closed-loop slew (default
  hub, PD 0.1 rad/s / 0.7 designed on the model, 10 deg in 60 s, 200 s sampled at 10 Hz)
  against the reference: hub + Craig-Bampton beam with N_REF modes, whose own convergence is
  verified against N_CHECK modes and written to the results. theta error relative to the slew
  angle, tip and torque errors relative to the reference's peak values.

Run times (medians of several runs, wall clock, one process):

- ``build``: the appendage model and the hub + appendage plant (``Spacecraft.plant``);
- ``freq``: torque -> theta frequency response at 1000 points through W(s)
  (``Spacecraft.frequency_response``); peer ``freq_control``: python-control's
  ``plant.frequency_response`` on the state-space plant;
- ``sim``: the closed-loop slew, 100 s at 100 Hz (10001 samples), ``controllers.simulate``;
  peers ``sim_forced_response`` (``control.forced_response``) and ``sim_lsim``
  (``scipy.signal.lsim``) on the same closed loop (same linear input interpolation);
- ``lqr``: ``controllers.lqr`` (LQR + Kalman filter) on the hub + model plant.

Optional peers (benchmarks/requirements-peers.txt): Basilisk (``bsk``) and Exudyn
(``exudyn``), run by benchmarks/peer_basilisk.py and benchmarks/peer_exudyn.py on the same
scenario; if one is missing or fails, the results say precisely why.

Writes benchmarks/results/run_time_vs_error.json, .md and .png (``_quick`` suffix with --quick).
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads before numpy is imported)

import argparse
import math
import sys
import time
import traceback
import warnings

import numpy as np

from _common import (RESULTS, fmt, machine_info, markdown_table, median_time,
                     paper_rod, pd_closed_loop, slew_errors, slew_inputs, slew_response,
                     spacecraft_with, write_json)

import control
import scipy.signal

import controllers
from appendages.chain import HingedChain

N_REF = 64          # modes of the Craig-Bampton reference for the closed-loop slew
N_CHECK = 48        # its convergence check
BAND = np.geomspace(0.05, 20.0, 200)       # rad/s
BAND_DAMPING = 0.05
FREQ_POINTS = np.geomspace(0.01, 100.0, 1000)  # rad/s
SIM_DT = 0.01       # s (100 Hz)
SIM_T_FINAL = 100.0  # s

FULL_SIZES = {
    "free-free": [1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64],
    "residual": [1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64],
    "craig-bampton": [1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64],
    "rfem": [2, 3, 4, 6, 8, 12, 16, 24, 32],
    "superelements": [1, 2, 3, 5, 7, 11, 15],
    "fitted": [2, 3, 4, 5, 6],
    "paper-chain": [3],
}
QUICK_SIZES = {
    "free-free": [1, 2, 4, 8, 16],
    "residual": [1, 2, 4, 8, 16],
    "craig-bampton": [1, 2, 4, 8, 16],
    "rfem": [2, 4, 8, 16],
    "superelements": [1, 3, 7],
    "fitted": [2, 3],
    "paper-chain": [3],
}


def _fit_chain():
    """``appendages.equivalence.fit_chain`` if it exists, else None."""
    try:
        from appendages.equivalence import fit_chain
    except ImportError:
        return None
    return fit_chain


def builder(family: str, beam):
    """Function size -> appendage model of the family, and the name of the size parameter."""
    if family in ("free-free", "residual", "craig-bampton"):
        return (lambda n: beam.truncated(n, method=family)), "n_modes"
    if family == "rfem":
        return (lambda n: HingedChain.rfem(beam, n)), "n_bodies"
    if family == "superelements":
        return (lambda n: HingedChain.superelements(beam, n)), "n_superelements"
    if family == "paper-chain":
        # the paper's fit: k_L = 0.26989, c = 37.134 N*m (PAPER.md)
        return (lambda n: HingedChain.three_body(beam.length, beam.mass, 0.26989, 37.134)), "n_bodies"
    if family == "fitted":
        fit_chain = _fit_chain()
        if fit_chain is None:
            return None, "n_bodies"
        return (lambda n: fit_chain(beam, n)), "n_bodies"
    raise ValueError(family)


# -- errors ------------------------------------------------------------------------------------
def _max_relative(values: np.ndarray, exact: np.ndarray) -> float:
    """max_k |values_k/exact_k - 1| over the exact entries; inf if the model has fewer."""
    if values.size < exact.size:
        return math.inf
    return float(np.max(np.abs(values[: exact.size] / exact - 1.0)))


def exact_reference(beam) -> dict:
    s = BAND * (-BAND_DAMPING + 1j * math.sqrt(1.0 - BAND_DAMPING**2))
    return {
        "poles": beam.natural_frequencies(2),
        "zeros": {r: beam.zeros(r, 2) for r in (1, 2, 4)},
        "coupled": spacecraft_with(beam).natural_frequencies(2, exact=True),
        "s_band": s,
        "W_band": beam.W(s),
    }


def model_errors(model, reference: dict) -> dict:
    poles = _max_relative(model.poles(), reference["poles"])
    zeros = max(_max_relative(model.zeros(r), reference["zeros"][r]) for r in (1, 2, 4))
    craft = spacecraft_with(model)
    n_elastic = craft.modes()[0].size - 3
    coupled = (_max_relative(craft.natural_frequencies(min(2, n_elastic), exact=False),
                             reference["coupled"]) if n_elastic else math.inf)
    W = model.W(reference["s_band"])
    We = reference["W_band"]
    band = max(float(np.max(np.abs(W[:, i, j] - We[:, i, j]) / np.abs(We[:, i, j])))
               for i, j in ((0, 0), (0, 1), (1, 1)))
    return {"poles": poles, "zeros": zeros, "coupled": coupled, "W_band": band}


# -- run times ---------------------------------------------------------------------------------
def timings(make, *, repeats: int, peers: bool) -> dict:
    """Median run times [s] of the stages for one model (see the module docstring)."""
    out = {}
    out["build"] = median_time(lambda: spacecraft_with(make()).plant(tip_deflection=True),
                               repeats=repeats, min_total=0.05)
    model = make()
    plant, _, loop = pd_closed_loop(model)
    out["n_states_plant"] = plant.nstates
    out["freq"] = median_time(lambda: spacecraft_with(model).frequency_response(FREQ_POINTS),
                              repeats=repeats, min_total=0.05)
    T = np.arange(int(round(SIM_T_FINAL / SIM_DT)) + 1) * SIM_DT
    U = slew_inputs(loop, T)
    out["sim"] = median_time(lambda: controllers.simulate(loop, T, U), repeats=repeats,
                             min_total=0.05)
    J = controllers.rigid_body_inertia(plant)
    wn = 0.1
    # rigid double integrator J s^2: q_theta = (J wn^2)^2, q_omega = 0, r = 1 give
    # closed-loop poles of natural frequency wn and damping 1/sqrt(2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            out["lqr"] = median_time(lambda: controllers.lqr(
                plant, attitude_weight=(J * wn**2) ** 2, rate_weight=0.0, torque_weight=1.0),
                repeats=repeats, max_total=20.0)
        except Exception as exc:  # record, do not stop the benchmark
            out["lqr"] = None
            out["lqr_error"] = f"{type(exc).__name__}: {exc}"
    if peers:
        p_repeats = max(3, repeats // 2)
        out["freq_control"] = median_time(lambda: plant.frequency_response(FREQ_POINTS),
                                          repeats=p_repeats, max_total=20.0)
        out["sim_forced_response"] = median_time(
            lambda: control.forced_response(loop, T, U), repeats=p_repeats, max_total=30.0)
        A, B, C, D = (np.asarray(M) for M in (loop.A, loop.B, loop.C, loop.D))
        out["sim_lsim"] = median_time(
            lambda: scipy.signal.lsim((A, B, C, D), U.T, T), repeats=p_repeats, max_total=30.0)
        # agreement of the three simulators on this closed loop (same input interpolation)
        y0 = np.asarray(controllers.simulate(loop, T, U, squeeze=False).outputs)
        y1 = np.asarray(control.forced_response(loop, T, U, squeeze=False).outputs)
        _, y2, _ = scipy.signal.lsim((A, B, C, D), U.T, T)
        scale = np.max(np.abs(y0), axis=1, keepdims=True)
        out["agreement_forced_response"] = float(np.max(np.abs(y0 - y1) / scale))
        out["agreement_lsim"] = float(np.max(np.abs(y0 - np.asarray(y2).T) / scale))
    return out


def run(quick: bool, peers: bool, repeats: int) -> dict:
    beam = paper_rod()
    t_start = time.perf_counter()
    print("exact reference ...", flush=True)
    reference = exact_reference(beam)
    exact_times = {
        "coupled_wittrick_williams": median_time(
            lambda: spacecraft_with(beam).natural_frequencies(2, exact=True), repeats=3),
        "freq_exact_W": median_time(
            lambda: spacecraft_with(beam).frequency_response(FREQ_POINTS), repeats=repeats),
        "W_exact_1000": median_time(lambda: beam.W(1j * FREQ_POINTS), repeats=repeats,
                                    min_total=0.05),
    }
    print(f"closed-loop reference: craig-bampton, {N_REF} modes ...", flush=True)
    ref_response = slew_response(pd_closed_loop(beam.truncated(N_REF))[2])
    check = slew_errors(slew_response(pd_closed_loop(beam.truncated(N_CHECK))[2]), ref_response)
    sizes = QUICK_SIZES if quick else FULL_SIZES
    rows = []
    notes = []
    for family, family_sizes in sizes.items():
        make_of, size_name = builder(family, beam)
        if make_of is None:
            notes.append(f"family '{family}' skipped: appendages.equivalence.fit_chain is not "
                         "available in this checkout")
            print(notes[-1], flush=True)
            continue
        for size in family_sizes:
            row = {"family": family, size_name: size, "size": size}
            try:
                model = make_of(size)
                row["n_dof"] = model.root_model().n
                row["errors"] = model_errors(model, reference)
                row["errors"].update(
                    {f"slew_{k}": v for k, v in
                     slew_errors(slew_response(pd_closed_loop(model)[2]), ref_response).items()})
                # a fit costs seconds: time its build once (after the warm-up run)
                row["times"] = timings(lambda: make_of(size),
                                       repeats=1 if family == "fitted" else repeats,
                                       peers=peers)
            except Exception as exc:
                row["failure"] = f"{type(exc).__name__}: {exc}"
                traceback.print_exc()
            rows.append(row)
            e = row.get("errors", {})
            t = row.get("times", {})
            print(f"{family:14s} {size:3d}  slew_theta {fmt(e.get('slew_theta'))}  zeros "
                  f"{fmt(e.get('zeros'))}  build {fmt(t.get('build'))} s  sim "
                  f"{fmt(t.get('sim'))} s  forced_response {fmt(t.get('sim_forced_response'))} s"
                  + (f"  FAILED {row['failure']}" if 'failure' in row else ""), flush=True)
    peer_results = {}
    if peers:
        for name in ("peer_basilisk", "peer_exudyn"):
            print(f"{name} ...", flush=True)
            peer_results[name] = run_peer(name, quick=quick, reference=ref_response,
                                          exact=reference)
    return {
        "machine": machine_info(),
        "quick": quick,
        "repeats": repeats,
        "scenario": {
            "beam": repr(beam), "hub": "Hub(mass=100.0, inertia=50.0)",
            "mount": "position (0.5, 0.0) m, direction +x",
            "controller": "PD natural frequency 0.1 rad/s, damping 0.7, designed on the model",
            "slew": "cycloidal 10 deg in 60 s; errors on 200 s at 10 Hz; timings 100 s at 100 Hz",
        },
        "reference": {
            "closed_loop": f"hub + Beam.truncated({N_REF}, method='craig-bampton')",
            "convergence_check_vs_n_modes_" + str(N_CHECK): check,
            "exact_times_s": exact_times,
            "poles_rad_s": reference["poles"], "coupled_rad_s": reference["coupled"],
            "zeros_rad_s": {f"W{r}": reference["zeros"][r] for r in (1, 2, 4)},
        },
        "rows": rows,
        "peers": peer_results,
        "notes": notes,
        "seconds": time.perf_counter() - t_start,
    }


def run_peer(module_name: str, *, quick: bool, reference: dict, exact: dict) -> dict:
    """Run an optional peer benchmark module; a missing package or a failure is recorded."""
    try:
        module = __import__(module_name)
    except Exception as exc:
        return {"status": "failed", "reason": f"cannot import {module_name}: {exc!r}"}
    try:
        return module.run(quick=quick, reference=reference, exact=exact)
    except ImportError as exc:
        return {"status": "not installed", "reason": repr(exc)}
    except Exception as exc:
        return {"status": "failed", "reason": f"{type(exc).__name__}: {exc}",
                "traceback": traceback.format_exc()}


# -- outputs ---------------------------------------------------------------------------------
TIME_KEYS = ("build", "freq", "freq_control", "sim", "sim_forced_response", "sim_lsim", "lqr")
ERROR_KEYS = ("poles", "zeros", "coupled", "W_band", "slew_theta", "slew_tip", "slew_torque")


def ratios(result: dict) -> dict:
    """Medians over the models of the peers' time / flexsat's time, measured in one run."""
    out = {}
    for peer, ours in (("sim_forced_response", "sim"), ("sim_lsim", "sim"),
                       ("freq_control", "freq")):
        values = [row["times"][peer] / row["times"][ours] for row in result["rows"]
                  if "times" in row and row["times"].get(peer) and row["times"].get(ours)]
        if values:
            out[f"{peer}/{ours}"] = {"median": float(np.median(values)),
                                     "min": float(np.min(values)), "max": float(np.max(values)),
                                     "n_models": len(values)}
    return out


def markdown(result: dict) -> str:
    m = result["machine"]
    lines = [
        "# Run time against error",
        "",
        f"`python benchmarks/run_time_vs_error.py{' --quick' if result['quick'] else ''}` on "
        f"{m['date_utc']} UTC; {m['cpu']}, {m['nproc']} cores; Python {m['python']}, numpy "
        f"{m['numpy']}, scipy {m['scipy']}, python-control {m['control']}. Medians of "
        f"{result['repeats']} runs (peers: at least 3); BLAS threads: "
        f"{m.get('blas_threads')}; load average (1, 5, 15 min) at the end: "
        f"{m.get('load_average_1_5_15min')}.",
        "",
        "Scenario: " + "; ".join(f"{k}: {v}" for k, v in result["scenario"].items()) + ".",
        "Times: t_build = model + plant, t_freq = torque->theta frequency response at 1000 "
        "points through W (t_freq_control: python-control on the plant), t_sim = closed-loop "
        "slew 100 s at 100 Hz with controllers.simulate (t_sim_forced_response, t_sim_lsim: the "
        "peers on the same loop), t_lqr = controllers.lqr on the plant. 'fitted' build times "
        "include fit_chain. Errors: see the script's docstring; '-' = the model has fewer "
        "poles/zeros than compared.",
        "",
        f"Closed-loop reference: {result['reference']['closed_loop']}; its own convergence "
        f"(vs {N_CHECK} modes): " + ", ".join(
            f"{k} {fmt(v)}" for k, v in
            result["reference"][f"convergence_check_vs_n_modes_{N_CHECK}"].items()) + ".",
        "Exact-reference costs [s]: " + ", ".join(
            f"{k} {fmt(v)}" for k, v in result["reference"]["exact_times_s"].items()) + ".",
        "",
        "## Time ratios (peer / flexsat, median over models, measured side by side)",
        "",
    ]
    r = ratios(result)
    lines += [markdown_table(["ratio", "median", "min", "max", "models"],
                             [[k, f"{v['median']:.3g}", f"{v['min']:.3g}", f"{v['max']:.3g}",
                               v["n_models"]] for k, v in r.items()]), ""]
    lines += ["## Errors (relative) and run times [s]", ""]
    header = ["family", "size", "dof"] + list(ERROR_KEYS) + [f"t_{k}" for k in TIME_KEYS]
    body = []
    for row in result["rows"]:
        if "failure" in row:
            body.append([row["family"], row["size"], "-", f"FAILED: {row['failure']}"]
                        + [""] * (len(header) - 4))
            continue
        e, t = row["errors"], row["times"]
        body.append([row["family"], row["size"], row["n_dof"]]
                    + [fmt(e.get(k), 1) for k in ERROR_KEYS]
                    + [fmt(t.get(k), 1) for k in TIME_KEYS])
    lines += [markdown_table(header, body), ""]
    lqr_failures = {}
    for row in result["rows"]:
        message = row.get("times", {}).get("lqr_error")
        if message:
            lqr_failures.setdefault(message.split(";")[0], []).append(
                f"{row['family']} {row['size']}")
    for message, models in lqr_failures.items():
        lines += [f"t_lqr '-': controllers.lqr raised \"{message}\" for {', '.join(models)}.", ""]
    for name, peer in result["peers"].items():
        lines += [f"## {name}", ""]
        if peer.get("status") != "ok":
            lines += [f"status: {peer.get('status')}; {peer.get('reason', '')}", ""]
        if peer.get("rows"):
            keys = sorted({k for row in peer["rows"] for k in row if k != "notes"})
            lines += [markdown_table(keys, [[fmt(row.get(k), 2) if isinstance(row.get(k), float)
                                             else row.get(k, "-") for k in keys]
                                            for row in peer["rows"]]), ""]
        for note in peer.get("notes", []):
            lines.append(f"- {note}")
        lines.append("")
    for note in result["notes"]:
        lines.append(f"- {note}")
    return "\n".join(lines)


def _num(value) -> float:
    """A JSON error value: null (infinite: the model lacks the quantity) becomes inf."""
    return math.inf if value is None else float(value)


def plot(result: dict, path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(13, 7.5))
    families = []
    for row in result["rows"]:
        if row["family"] not in families and "errors" in row:
            families.append(row["family"])
    floor = 1e-16

    peer_colors = {"Basilisk panels (RK4)": "black", "Exudyn panels (gen.-alpha)": "teal",
                   "Exudyn ANCF beam (gen.-alpha)": "darkgoldenrod"}

    def curve(ax, rows, x_of, y_of, label, style, color=None):
        pts = [(x_of(r), _num(y_of(r))) for r in rows]
        # y == 0: the reference model itself (Craig-Bampton N_REF) -- not a measurement
        pts = [(x, max(y, floor)) for x, y in pts
               if x is not None and y is not None and math.isfinite(y) and math.isfinite(x)
               and y > 0]
        if pts:
            xs, ys = zip(*pts)
            ax.loglog(xs, ys, style, label=label, color=color)

    ok = [r for r in result["rows"] if "errors" in r]
    for family in families:
        rows = [r for r in ok if r["family"] == family]
        curve(axes[0], rows, lambda r: r["times"]["build"] + r["times"]["sim"],
              lambda r: r["errors"]["slew_tip"], f"{family} (controllers.simulate)", "o-")
        curve(axes[1], rows, lambda r: r["times"]["build"],
              lambda r: max(_num(r["errors"]["poles"]), _num(r["errors"]["zeros"])), family,
              "o-")
    for family in ("craig-bampton", "rfem"):
        rows = [r for r in ok if r["family"] == family]
        for peer, style in (("sim_forced_response", "s:"), ("sim_lsim", "^:")):
            curve(axes[0], rows, lambda r: (r["times"]["build"] + r["times"][peer])
                  if r["times"].get(peer) else None,
                  lambda r: r["errors"]["slew_tip"],
                  f"{family} + {'control.forced_response' if 'forced' in peer else 'scipy lsim'}",
                  style)
    for name, peer in result["peers"].items():
        rows = [r for r in peer.get("rows", []) if r.get("slew_tip") is not None]
        for label in sorted({r["model"] for r in rows}):
            sub = [r for r in rows if r["model"] == label]
            curve(axes[0], sub, lambda r: r["time_build"] + r["time_sim"],
                  lambda r: r["slew_tip"], label, "D--", peer_colors.get(label))
        rows = [r for r in peer.get("rows", []) if r.get("time_eigen") is not None
                and r.get("poles") is not None]
        for label in sorted({r["model"] for r in rows}):
            sub = [r for r in rows if r["model"] == label]
            curve(axes[1], sub, lambda r: r["time_eigen"], lambda r: r["poles"],
                  label + " (poles only)", "D--", peer_colors.get(label))
    axes[0].set_xlabel("run time: build + simulate 100 s at 100 Hz [s]")
    axes[0].set_ylabel("closed-loop slew: peak tip-deflection error (relative)")
    axes[0].set_title("Closed-loop slew of the default hub")
    axes[1].set_xlabel("run time: build model + plant [s]")
    axes[1].set_ylabel("max relative error, first 2 poles and zeros of W")
    axes[1].set_title("Appendage poles and zeros vs exact beam")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        # below the panel: inside it, the legend hid the peers' curves
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2,
                  frameon=False)
    fig.suptitle(f"flexsat run time vs error ({result['machine']['date_utc']} UTC, "
                 f"{result['machine']['cpu']}, {result['machine']['nproc']} cores)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer model sizes, fewer repeats")
    parser.add_argument("--no-peers", action="store_true",
                        help="skip python-control/scipy/Basilisk/Exudyn peers")
    parser.add_argument("--repeats", type=int, default=None,
                        help="timing repetitions (default 5, quick 3)")
    parser.add_argument("--only-peers", action="store_true",
                        help="rerun Basilisk and Exudyn only, into the existing JSON results")
    parser.add_argument("--replot", action="store_true",
                        help="only rewrite the markdown and the plot from the JSON results")
    args = parser.parse_args(argv)
    suffix = "_quick" if args.quick else ""
    if args.replot:
        import json

        result = json.loads((RESULTS / f"run_time_vs_error{suffix}.json").read_text())
        (RESULTS / f"run_time_vs_error{suffix}.md").write_text(markdown(result) + "\n")
        plot(result, RESULTS / f"run_time_vs_error{suffix}.png")
        return 0
    repeats = args.repeats or (3 if args.quick else 5)
    if args.only_peers:
        import json

        result = json.loads((RESULTS / f"run_time_vs_error{suffix}.json").read_text())
        beam = paper_rod()
        reference = exact_reference(beam)
        ref_response = slew_response(pd_closed_loop(beam.truncated(N_REF))[2])
        for name in ("peer_basilisk", "peer_exudyn"):
            print(f"{name} ...", flush=True)
            result["peers"][name] = run_peer(name, quick=args.quick, reference=ref_response,
                                             exact=reference)
        result["peers_machine"] = machine_info()
    else:
        result = run(args.quick, not args.no_peers, repeats)
    result["ratios"] = ratios(result)
    write_json(f"run_time_vs_error{suffix}.json", result)
    text = markdown(result)
    (RESULTS / f"run_time_vs_error{suffix}.md").write_text(text + "\n")
    plot(result, RESULTS / f"run_time_vs_error{suffix}.png")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
