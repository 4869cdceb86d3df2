"""Benchmark: FMI 2.0 vs FMI 3.0 FMUs of flexsat - accuracy table and timings.

Accuracy (the comparison table of issue 15): every FMU type (continuous plant, digital
controller, the sampled loop as one FMU, plant + controller co-simulated, the SSP of the
loop) in both FMI versions, through every importer at hand (fmpy CS and ME, flexsat's
master, fmpy's SSP master, and - where installed - the Reference-FMUs' fmusim and the FMU
Compliance Checker): the largest error relative to the signal's size against
python-control (``c2d`` + ``forced_response``, or the exact continuous response for ME) or
the monolithic sampled loop; and the rollback (restore + step again) and directional
derivative checks, whose differences must be exactly 0.

The scenario: a hub of 10 kg m^2 with two collocated modes (3 and 12 rad/s, damping 0.01),
a digital LQR + Kalman filter from ``controllers.lqr(..., sample_time=0.05)``, a 0.1 rad
attitude step from rest over 3 s.

Timings (medians of >= 5 runs, load average recorded): export of 2-, 50- and 200-state
modal plants in both versions (warm object cache), one co-simulation of plant + digital
LQR (steps per second; FMI 3.0 with the clock activated at every tick), one FMU state
save + restore, one serialise + deserialise, one directional derivative of all outputs.

Usage::

    python benchmarks/bench_fmu_fmi3.py [--runs 5] [--tools /work/tools/bin]

Writes ``benchmarks/results/fmu_fmi3.{json,md}``.
"""

from __future__ import annotations

import _common  # noqa: F401  (first: limits BLAS threads, puts the worktree on sys.path)

import argparse
import csv
import os
import subprocess
import tempfile
from pathlib import Path

import control
import numpy as np
import scipy.linalg
from fmpy import extract, read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave

import controllers
import fmu

T = 0.05  # sample period of the digital LQR [s]
T_END = 3.0
REFERENCE = 0.1  # attitude step [rad]
VERSIONS = ("2.0", "3.0")


def plant() -> control.StateSpace:
    """Hub J = 10 kg m^2 + modes (3 rad/s, 0.01, b = 0.05) and (12 rad/s, 0.01, b = 0.03)."""
    J, modes = 10.0, [(3.0, 0.01, 0.05), (12.0, 0.01, 0.03)]
    n = 2 + 2 * len(modes)
    A, B, C = np.zeros((n, n)), np.zeros((n, 1)), np.zeros((2, n))
    A[0, 1], B[1, 0], C[0, 0], C[1, 1] = 1.0, 1.0 / J, 1.0, 1.0
    for k, (w, zeta, b) in enumerate(modes):
        i = 2 + 2 * k
        A[i, i + 1], A[i + 1, i], A[i + 1, i + 1] = 1.0, -w * w, -2 * zeta * w
        B[i + 1, 0], C[0, i], C[1, i + 1] = b, b, b
    return control.ss(A, B, C, 0, inputs=["torque"], outputs=["theta", "omega"],
                      states=["q", "q_dot", "eta1", "eta1_dot", "eta2", "eta2_dot"], name="plant")


def digital_lqr(design_plant: control.StateSpace) -> control.StateSpace:
    K = controllers.lqr(design_plant, attitude_weight=100.0, rate_weight=10.0,
                        torque_weight=1.0, sample_time=T)
    return control.ss(K.A, K.B, K.C, K.D, K.dt, inputs=K.input_labels, outputs=K.output_labels,
                      states=[f"xhat{i}" for i in range(K.nstates)], name="lqr")


def monolithic(P: control.StateSpace, K: control.StateSpace, h: float) -> dict[str, np.ndarray]:
    """The sampled loop on the grid k h (h = T / N): ZOH plant at h, controller every N."""
    N = int(round(T / h))
    d = control.c2d(P, h, "zoh")
    Phi, Gamma, C = (np.asarray(M) for M in (d.A, d.B, d.C))
    Ac, Bc, Cc, Dc = (np.asarray(M) for M in (K.A, K.B, K.C, K.D))
    n_steps = int(round(T_END / h))
    x, xc, u = np.zeros(Phi.shape[0]), np.zeros(Ac.shape[0]), np.zeros(1)
    out = {name: np.zeros(n_steps + 1) for name in ("theta", "omega", "torque")}
    for k in range(n_steps + 1):
        y = C @ x
        if k % N == 0:
            v = np.array([REFERENCE, y[0], y[1]])
            u = Cc @ xc + Dc @ v
            xc = Ac @ xc + Bc @ v
        out["theta"][k], out["omega"][k], out["torque"][k] = y[0], y[1], u[0]
        x = Phi @ x + Gamma @ u
    return out


def relative_error(got, expected) -> float:
    got, expected = np.asarray(got, dtype=float), np.asarray(expected, dtype=float)
    return float(np.max(np.abs(got - expected)) / max(np.max(np.abs(expected)), 1e-300))


def worst(result, expected, names=("theta", "omega", "torque"), rows=slice(None)) -> float:
    return max(relative_error(result[n][rows], expected[n][rows]) for n in names if n in expected)


def read_table(path: Path) -> dict[str, np.ndarray]:
    with open(path, newline="") as handle:
        rows = list(csv.reader(handle))
    names = [n.strip().strip('"') for n in rows[0]]
    values = np.array([[float(v) for v in row] for row in rows[1:] if row])
    return {name: values[:, i] for i, name in enumerate(names)}


def accuracy(folder: Path, tools: Path | None) -> list[dict]:
    P, K = plant(), digital_lqr(plant())
    rows = []

    def add(fmu_type, version, importer, error, against):
        rows.append({"fmu": fmu_type, "fmi": version, "importer": importer,
                     "max_relative_error": error, "against": against})

    t = np.arange(int(round(T_END / 0.01)) + 1) * 0.01
    switch = np.where(t >= 0.5, 1.0, 0.0)
    exact = control.forced_response(control.c2d(P, 0.01, "zoh"), T=t, U=switch)
    exact = dict(zip(("theta", "omega"), np.asarray(exact.outputs)))
    table = np.array([(0.0, 0.0), (0.5, 0.0), (0.5, 1.0), (1e3, 1.0)],
                     dtype=[("time", np.float64), ("torque", np.float64)])
    K_alone = control.forced_response(K, T=np.arange(61) * T,
                                      U=np.vstack([np.full(61, 0.1), 0.01 * np.sin(np.arange(61) * T),
                                                   np.zeros(61)]))
    loop_fmu_reference = monolithic(P, K, T)
    for version in VERSIONS:
        plant_fmu = fmu.export(P, folder / f"plant{version[0]}.fmu", fmi_version=version, step=0.01,
                               stop_time=T_END, reference=True)
        lqr_fmu = fmu.export(K, folder / f"lqr{version[0]}.fmu", fmi_version=version,
                             stop_time=T_END, reference=True)
        for interface, label in (("CoSimulation", "fmpy CS"), ("ModelExchange", "fmpy ME (CVode 1e-10)")):
            result = simulate_fmu(str(plant_fmu), fmi_type=interface, stop_time=T_END,
                                  output_interval=0.01, input=table, relative_tolerance=1e-10)
            keep = np.r_[np.diff(result["time"]) > 0, True]
            add("plant (continuous)", version, label,
                worst({n: result[n][keep] for n in ("theta", "omega")}, exact),
                "c2d zoh + forced_response (exact at the grid)")
        inputs = np.array([(k * T, 0.1, 0.01 * np.sin(k * T), 0.0) for k in range(61)],
                          dtype=[("time", np.float64), ("theta_ref", np.float64),
                                 ("theta", np.float64), ("omega", np.float64)])
        result = simulate_fmu(str(lqr_fmu), fmi_type="CoSimulation", stop_time=60 * T,
                              output_interval=T, input=inputs)
        add("digital LQR (sampled)", version, "fmpy CS", relative_error(result["torque"],
                                                                       np.asarray(K_alone.outputs)[0]),
            "forced_response of the discrete controller")
        for divisions in (1, 5):
            h = T / divisions
            result = fmu.cosimulate(plant_fmu, lqr_fmu, T_END, h, inputs={"theta_ref": REFERENCE})
            add("plant + digital LQR", version, f"flexsat master, h = T/{divisions}"
                if divisions > 1 else "flexsat master, h = T", worst(result, monolithic(P, K, h)),
                "monolithic sampled loop")
        ssp = fmu.write_ssp(folder / f"loop{version[0]}.ssp", plant_fmu, lqr_fmu, stop_time=T_END)
        result = fmu.cosimulate_ssp(ssp, T_END, T, inputs={"theta_ref": REFERENCE})
        add("SSP of the loop", version, "flexsat master (SSD connections)",
            worst(result, monolithic(P, K, T)), "monolithic sampled loop")
        if version == "2.0":
            from fmpy.ssp.simulation import simulate_ssp

            fmpy_result = simulate_ssp(str(ssp), stop_time=T_END, step_size=T,
                                       input={"theta_ref": lambda t: REFERENCE})
            jacobi = jacobi_loop(P, K, fmpy_result.size + 1)
            add("SSP of the loop", version, "fmpy SSP master (Jacobi)",
                worst(fmpy_result, {k: v[1:] for k, v in jacobi.items()}),
                "monolithic loop with fmpy's exchange delays")
        loop = controllers.close_loop(P, K)
        loop_fmu = fmu.export(loop, folder / f"loop{version[0]}.fmu", fmi_version=version,
                              stop_time=T_END)
        result = simulate_fmu(str(loop_fmu), fmi_type="CoSimulation", stop_time=T_END,
                              output_interval=T, input=np.array([(0.0, REFERENCE)], dtype=[
                                  ("time", np.float64), ("theta_ref", np.float64)]))
        add("sampled loop as one FMU", version, "fmpy CS",
            worst(result, loop_fmu_reference, ("theta", "omega")), "monolithic sampled loop")
        add("plant (continuous)", version, "rollback: restore + 30 steps again",
            rollback_difference(plant_fmu, version), "the first 30 steps (bit-identical)")
        add("plant (continuous)", version, "directional derivatives, unit seeds",
            jacobian_difference(plant_fmu, version, P), "[[C, D], [A, B]] (exact)")
        if tools is not None:
            rows.extend(external_tools(tools, version, plant_fmu, lqr_fmu, folder))
    return rows


def jacobi_loop(P, K, n) -> dict[str, np.ndarray]:
    """The loop fmpy's SSP master computes: the controller's feedthrough one step late
    (a delay state), theta_ref reaching the controller one step late from 0."""
    Phi, Gamma, C, D = (np.asarray(M) for M in (K.A, K.B, K.C, K.D))
    nk, m = Gamma.shape
    A = np.block([[Phi, np.zeros((nk, m))], [np.zeros((m, nk)), np.zeros((m, m))]])
    delayed = control.ss(A, np.vstack([Gamma, np.eye(m)]), np.hstack([C, D]), np.zeros_like(D), T,
                         inputs=K.input_labels, outputs=K.output_labels)
    loop = control.interconnect([control.c2d(P, T, "zoh"), delayed], inplist=["theta_ref"],
                                outlist=["theta", "omega", "torque"])
    t = np.arange(n) * T
    response = control.forced_response(loop, T=t, U=np.where(np.arange(n) >= 1, REFERENCE, 0.0))
    return dict(zip(("theta", "omega", "torque"), np.asarray(response.outputs)))


def _slave(path: Path, version: str):
    description = read_model_description(str(path))
    kind = FMU3Slave if version == "3.0" else FMU2Slave
    slave = kind(guid=description.guid, unzipDirectory=extract(str(path)),
                 modelIdentifier=description.coSimulation.modelIdentifier, instanceName="b")
    slave.instantiate()
    if version == "3.0":
        slave.enterInitializationMode(startTime=0.0)
    else:
        slave.setupExperiment(startTime=0.0)
        slave.enterInitializationMode()
    slave.exitInitializationMode()
    vr = {v.name: v.valueReference for v in description.modelVariables}
    get = slave.getFloat64 if version == "3.0" else slave.getReal
    set_ = slave.setFloat64 if version == "3.0" else slave.setReal
    return slave, vr, get, set_


def rollback_difference(path: Path, version: str) -> float:
    slave, vr, get, set_ = _slave(path, version)
    try:
        def steps():
            out = []
            for k in range(30):
                set_([vr["torque"]], [np.sin(0.3 * k)])
                slave.doStep(0.2 + 0.01 * k, 0.01)
                out.append(get([vr["theta"], vr["omega"], vr["q"]]))
            return np.array(out)
        for k in range(20):
            slave.doStep(0.01 * k, 0.01)
        state = slave.getFMUState()
        first = steps()
        slave.setFMUState(state)
        return float(np.max(np.abs(steps() - first)))
    finally:
        slave.freeInstance()


def jacobian_difference(path: Path, version: str, P) -> float:
    slave, vr, _, _ = _slave(path, version)
    try:
        unknowns = [vr["theta"], vr["omega"]] + [vr[f"der({s})"] for s in P.state_labels]
        knowns = [vr[s] for s in P.state_labels] + [vr["torque"]]
        columns = [slave.getDirectionalDerivative(unknowns, knowns, list(np.eye(len(knowns))[k]))
                   for k in range(len(knowns))]
        A, B, C, D = (np.asarray(M) for M in (P.A, P.B, P.C, P.D))
        return float(np.max(np.abs(np.column_stack(columns) - np.block([[C, D], [A, B]]))))
    finally:
        slave.freeInstance()


def external_tools(tools: Path, version: str, plant_fmu: Path, lqr_fmu: Path, folder: Path) -> list[dict]:
    rows = []
    fmusim, fmusim_ir, checker = tools / "fmusim", tools / "fmusim-ir", tools / "fmuCheck.linux64"
    for path, label, h in ((plant_fmu, "plant (continuous)", "0.01"), (lqr_fmu, "digital LQR (sampled)", str(T))):
        stem = path.with_suffix("")
        reference = read_table(Path(f"{stem}_ref.csv"))
        first = np.r_[True, np.diff(reference["time"]) > 0]  # left limits (the tools record before inputs)
        last = np.r_[np.diff(reference["time"]) > 0, True]
        runs = [("fmusim CS", [str(fmusim), "--interface-type", "cs"], first)]
        if label.startswith("plant"):
            runs.append(("fmusim-ir ME (CVODE 1e-8)", [str(fmusim_ir), "--interface-type", "me",
                                                       "--solver", "cvode", "--tolerance", "1e-8"], last))
        for name, command, rows_of in runs:
            if not Path(command[0]).is_file():
                continue
            output = folder / f"{stem.name}_{name.split()[0]}.csv"
            done = subprocess.run(command + ["--input-file", f"{stem}_in.csv", "--stop-time", str(T_END),
                                             "--output-interval", h, "--output-file", str(output),
                                             str(path)], capture_output=True, text=True)
            if done.returncode != 0:
                rows.append({"fmu": label, "fmi": version, "importer": name, "max_relative_error": None,
                             "against": f"failed: {done.stderr.strip()[:200]}"})
                continue
            got = read_table(output)
            keep = np.r_[np.diff(got["time"]) > 0, True] if "ME" in name else np.r_[True, np.diff(got["time"]) > 0]
            error = max(relative_error(got[c][keep], reference[c][rows_of]) for c in reference if c != "time")
            rows.append({"fmu": label, "fmi": version, "importer": name, "max_relative_error": error,
                         "against": "the FMU's reference file (c2d zoh + forced_response)"})
        if version == "2.0" and checker.is_file():
            log = folder / f"{stem.name}_check.log"
            output = folder / f"{stem.name}_check.csv"
            subprocess.run([str(checker), "-l", "3", "-k", "xml", "-e", str(log), "-o", os.devnull,
                            str(path)], capture_output=True, text=True)
            text = log.read_text(errors="replace")
            clean = "0 Warning(s)" in text and "0 Error(s)" in text
            rows.append({"fmu": label, "fmi": version, "importer": "FMU Compliance Checker (XML)",
                         "max_relative_error": None,
                         "against": "0 warnings, 0 errors" if clean else "PROBLEMS: see its log"})
    return rows


def timings(folder: Path, runs: int) -> dict:
    out: dict = {"export_s": {}, "cosimulation_steps_per_s": {}, "fmu_state_us": {},
                 "serialise_round_trip_us": {}, "directional_derivative_us": {}}
    rng = np.random.default_rng(0)
    for n in (2, 50, 200):
        blocks = [np.array([[0.0, 1.0], [0.0, 0.0]])]
        blocks += [np.array([[0.0, 1.0], [-w * w, -0.01 * w]]) for w in np.linspace(1.0, 1000.0, (n - 2) // 2)]
        A = scipy.linalg.block_diag(*blocks)
        system = control.ss(A, rng.standard_normal((n, 1)) * 0.1, rng.standard_normal((2, n)), 0,
                            inputs=["torque"], outputs=["theta", "omega"], name=f"modal{n}")
        for version in VERSIONS:
            path = folder / f"modal{n}_{version[0]}.fmu"
            out["export_s"][f"{n} states, FMI {version}"] = _common.median_time(
                lambda: fmu.export(system, path, fmi_version=version), repeats=runs)
    P, K = plant(), digital_lqr(plant())
    for version in VERSIONS:
        plant_fmu = folder / f"plant{version[0]}.fmu"
        lqr_fmu = folder / f"lqr{version[0]}.fmu"
        seconds = _common.median_time(lambda: fmu.cosimulate(plant_fmu, lqr_fmu, T_END, T / 5,
                                                             inputs={"theta_ref": REFERENCE}),
                                      repeats=runs)
        out["cosimulation_steps_per_s"][f"FMI {version}, h = T/5"] = int(round(T_END / (T / 5))) / seconds
        slave, vr, _, _ = _slave(plant_fmu, version)
        try:
            state = slave.getFMUState()
            out["fmu_state_us"][f"FMI {version}: get + set"] = 1e6 * _common.median_time(
                lambda: (slave.getFMUState(), slave.setFMUState(state)), repeats=runs, min_total=0.2)
            serialize = slave.serializeFMUState if version == "3.0" else slave.serializeFMUstate
            deserialize = slave.deserializeFMUState if version == "3.0" else slave.deSerializeFMUstate
            holder = [deserialize(serialize(state))]
            out["serialise_round_trip_us"][f"FMI {version}: {len(serialize(state))} bytes"] = 1e6 * \
                _common.median_time(lambda: deserialize(serialize(state), holder[0]), repeats=runs,
                                    min_total=0.2)
            unknowns = [vr["theta"], vr["omega"]]
            knowns = [vr["torque"]]
            out["directional_derivative_us"][f"FMI {version}"] = 1e6 * _common.median_time(
                lambda: slave.getDirectionalDerivative(unknowns, knowns, [1.0]), repeats=runs,
                min_total=0.2)
        finally:
            slave.freeInstance()
    return out


def markdown(results: dict) -> str:
    lines = ["# FMI 2.0 vs FMI 3.0 FMUs: accuracy and timings", "",
             f"Machine: {results['machine']['cpu']}, {results['machine']['nproc']} cores, load "
             f"average {', '.join(f'{v:.1f}' for v in results['machine']['load_average_1_5_15min'])} "
             f"(1, 5, 15 min) at {results['machine']['date_utc']} UTC.", "",
             "## Accuracy (largest error relative to the signal's size)", "",
             "| FMU | FMI | importer / check | max error | against |", "|---|---|---|---|---|"]
    for row in results["accuracy"]:
        error = row["max_relative_error"]
        shown = "-" if error is None else ("0 (bit-identical)" if error == 0 else f"{error:.1e}")
        lines.append(f"| {row['fmu']} | {row['fmi']} | {row['importer']} | {shown} | {row['against']} |")
    lines += ["", "## Timings (medians)", ""]
    for group, values in results["timings"].items():
        for key, value in values.items():
            lines.append(f"- {group} {key}: {value:.4g}")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--tools", type=Path, default=Path(os.environ.get("FMI_TOOLS_BIN", "/work/tools/bin")))
    args = parser.parse_args()
    tools = args.tools if (args.tools / "fmusim").is_file() else None
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        os.environ.setdefault("FLEXSAT_CACHE_DIR", str(folder / "cache"))
        results = {"machine": _common.machine_info(),
                   "external_tools": str(tools) if tools else "not installed",
                   "accuracy": accuracy(folder, tools), "timings": timings(folder, args.runs)}
        results["machine"]["load_average_after"] = list(os.getloadavg())
    text = markdown(results)
    print(text)
    path = _common.write_json("fmu_fmi3.json", results)
    path.with_suffix(".md").write_text(text)


if __name__ == "__main__":
    main()
