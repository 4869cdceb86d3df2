"""Sweeps on a real Dask LocalCluster (distributed scheduler, two worker processes): results
equal to a serial run, resume after a killed run, failing samples recorded, the worst case of a
case with a known answer, the command line."""
import json
import math
import os
import signal
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

import spacecraft.sweep
from spacecraft.design.loop import run
from spacecraft.sweep import run_sweep, sweep_scene_path
from spacecraft.cli.sweep import main
from scenes import edited

ROOT = Path(__file__).resolve().parents[3]
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def client():
    import logging

    from distributed import Client, LocalCluster

    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=":0", silence_logs=logging.ERROR)
    client = Client(cluster, set_as_default=False)
    yield client
    client.close()
    cluster.close()


def assert_same_samples(a, b):
    """Equal sample by sample. The two runs differ only in BLAS threads (this process vs
    single-threaded workers), i.e. in rounding: the margins (refined to 1e-12 in frequency) and
    the slew (20 states, signals of 0.17 rad) agree to 1e-9 relative or 1e-12 absolute;
    verdicts, counts and texts exactly."""
    a, b = a.to_pydict(), b.to_pydict()
    assert list(a) == list(b)
    for name in a:
        if name == "seconds":
            continue
        for x, y in zip(a[name], b[name]):
            if isinstance(x, float) and not (math.isnan(x) and math.isnan(y)):
                assert x == pytest.approx(y, rel=1e-9, abs=1e-12), name
            elif not isinstance(x, float):
                assert x == y, name


def test_distributed_results_equal_a_serial_run(client):
    serial = run_sweep(None, samples=10, seed=11, worst_case=False, workers=1, progress=False)
    parallel = run_sweep(None, samples=10, seed=11, worst_case=False, client=client,
                         progress=False, batch=2)
    assert serial.summary["executor"].startswith("synchronous")
    assert parallel.summary["executor"] == "client, 2 workers"
    assert parallel.summary["samples"]["tasks"] == 5
    assert parallel.table.column("sample").to_pylist() == list(range(10))
    assert_same_samples(serial.table, parallel.table)


def test_resume_after_a_killed_run_loses_and_repeats_nothing(client, tmp_path):
    out = tmp_path / "sweep"
    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    env["OPENBLAS_NUM_THREADS"] = "1"
    process = subprocess.Popen(
        [sys.executable, "-m", "spacecraft.cli.sweep", "--samples", "24", "--seed", "5",
         "--no-worst-case", "--no-plots", "--quiet", "--workers", "1", "--out", str(out)],
        cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    parts = out / "samples"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(list(parts.glob("part-*.parquet"))) < 2:
        assert process.poll() is None, process.stderr.read().decode()
        time.sleep(0.02)
    process.send_signal(signal.SIGKILL)
    process.wait()
    process.stderr.close()
    before = {p.name: p.read_bytes() for p in parts.glob("part-*.parquet")}
    done = sorted(i for p in parts.glob("part-*.parquet")
                  for i in pq.read_table(p).column("sample").to_pylist())
    assert 2 <= len(before) and len(done) < 24, "the run finished before it was killed"
    resumed = run_sweep(None, samples=24, seed=5, worst_case=False, client=client,
                        out=out, resume=True, progress=False, plots=False)
    s = resumed.summary["samples"]
    assert s["resumed_from_folder"] == len(done)
    assert s["evaluated_now"] == 24 - len(done)        # nothing repeated
    for name, data in before.items():                  # nothing lost or rewritten
        assert (parts / name).read_bytes() == data
    samples = [i for p in parts.glob("part-*.parquet")
               for i in pq.read_table(p).column("sample").to_pylist()]
    assert sorted(samples) == list(range(24))          # each sample once
    reference = run_sweep(None, samples=24, seed=5, worst_case=False, client=client,
                          progress=False)
    assert_same_samples(reference.table, resumed.table)
    # a resume of another sweep in that folder is refused
    with pytest.raises(spacecraft.sweep.SweepError, match="holds another sweep.*sweep.seed"):
        run_sweep(None, samples=24, seed=6, worst_case=False, out=out, resume=True,
                  progress=False)


def test_a_failing_sample_is_recorded_on_the_cluster(client):
    raw = tomllib.loads(sweep_scene_path("default").read_text())
    raw["appendages"][0]["beam"] = {"section": "tube", "length": 10.0, "outer_diameter": 0.03,
                                    "wall_thickness": 0.004, "density": 2700.0,
                                    "youngs_modulus": 7.0e10, "damping_ratio": 0.005}
    # each value alone is a tube; 0.02 m outer with 0.011 m wall is not (wall > diameter / 2)
    parameters = {
        "appendages.rod.beam.outer_diameter": {"distribution": "discrete",
                                               "values": [0.02, 0.04]},
        "appendages.rod.beam.wall_thickness": {"distribution": "discrete",
                                               "values": [0.004, 0.011]}}
    result = run_sweep(raw, parameters=parameters, method="grid", worst_case=False,
                       design="per-sample", client=client, progress=False, batch=1)
    t = result.table.to_pydict()
    errors = dict(zip(t["sample"], t["error"]))
    assert "wall_thickness: must be at most outer_diameter/2" in errors[1]
    assert errors[0] == errors[2] == errors[3] == ""
    assert t["stable"][1] is None and all(isinstance(t["stable"][i], bool) for i in (0, 2, 3))
    assert result.summary["samples"]["failed"] == 1
    assert result.summary["instability"]["of"] == 3
    assert result.summary["failures"][0]["count"] == 1


def test_worst_case_of_a_monotonic_margin_lies_on_the_box_edge(client, tmp_path):
    """With the nominal controller held, more modal damping only adds damping to every mode:
    the modulus margin rises monotonically with the damping ratio (a 7-point scan: 0.067,
    0.55, 0.71, 0.737, ... from 0.001 to 0.02), so the worst case is the box's lower edge, and
    nothing in the box beats the edge sample the search is seeded with."""
    out = tmp_path / "worst"
    result = run_sweep(None, parameters={"appendages.rod.beam.damping_ratio": {
        "distribution": "uniform", "low": 0.001, "high": 0.02}}, method="grid", levels=5,
        worst_case=["modulus_margin"], worst_case_evaluations=30, client=client,
        progress=False, out=out)
    t = result.table.to_pydict()
    margin = t["exact_modulus_margin"]
    assert all(x < y for x, y in zip(margin, margin[1:]))       # monotonic on the grid
    (w,) = result.worst
    assert w.values == {"appendages.rod.beam.damping_ratio": 0.001}
    assert w.evaluations >= 15
    # the same point evaluated on a worker and in this process: rounding only
    assert w.objective == pytest.approx(margin[0], rel=1e-9)
    assert w.best_sample == {"sample": 0, "objective": pytest.approx(margin[0], rel=1e-15)}
    # verified on the exact beam with the runner's grid (its interpolation error: 5e-3)
    check = w.verification["exact_reference"]
    assert check["stable"] is True
    assert check["modulus_margin"] == pytest.approx(margin[0], rel=5e-3)
    # worst.toml is a scene the runner runs: the damping is the worst one
    data = tomllib.loads((out / "worst.toml").read_text())
    assert data["appendages"][0]["beam"]["damping_ratio"] == 0.001
    assert "sweep" not in data
    assert run(out / "worst.toml").data["closed_loops"][0]["exact_verdict"]["stable"] is True
    summary = json.loads((out / "summary.json").read_text())
    assert summary["worst_case"][0]["values"] == w.values
    assert {p["path"] for p in summary["files"]["plots"]} == {
        "plots/histograms.png", "plots/margins.png"}    # one parameter: no 2-D map


def test_the_command_writes_the_report_and_refuses_bad_input(tmp_path, capsys):
    out = tmp_path / "cli"
    assert main(["--samples", "6", "--workers", "1", "--out", str(out), "--quiet",
                 "--worst-case-evaluations", "20"]) == 0
    printed = capsys.readouterr().out
    assert "probability of instability (exact verdict)" in printed
    assert "worst modulus margin" in printed and "worst.toml" in printed
    for name in ("summary.json", "report.md", "report.html", "worst.toml",
                 "worst_phase_margin.toml", "sweep.json", "plots/stability_map.png"):
        assert (out / name).is_file(), name
    summary = json.loads((out / "summary.json").read_text())
    assert summary["samples"]["total"] == 6
    lo, hi = summary["instability"]["interval"]
    assert 0.0 <= lo <= hi <= 1.0
    # bad input: one line on stderr, exit 2
    scene = tmp_path / "bad.toml"
    raw = edited(sweep_scene_path("default").read_text(), ('"hub.inertia"', '"hub.inertai"'))
    scene.write_text(raw)
    assert main([str(scene), "--out", str(tmp_path / "bad"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "did you mean 'hub.inertia'" in err
    assert main(["--out", str(out), "--quiet"]) == 2                 # folder taken
    assert "exists and is not empty" in capsys.readouterr().err
    assert main(["--samples", "2000000", "--out", str(tmp_path / "big"), "--quiet"]) == 2
    assert "exceed the limit of 1000000" in capsys.readouterr().err
    assert main(["--samples", "20", "--scheduler", "tcp://127.0.0.1:9", "--out",
                 str(tmp_path / "far"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "cannot reach a Dask scheduler" in err


def test_the_package_is_callable_and_returns_a_table(client):
    table = spacecraft.sweep(None, parameters={"hub.inertia": {
        "distribution": "uniform", "low": 45.0, "high": 55.0}}, samples=3, worst_case=False,
        client=client, progress=False)
    assert table.num_rows == 3 and table.column_names[:2] == ["sample", "hub.inertia"]
    summary = json.loads(table.schema.metadata[b"flexsat.summary"])
    assert summary["samples"]["total"] == 3
    assert np.all(np.diff(table.column("sample").to_numpy()) == 1)


def test_a_scheduler_given_by_address_runs_the_sweep(client):
    """--scheduler ADDRESS: the scheduler is asked who it is (a deadline on the answer), then
    the sweep runs on its workers."""
    result = run_sweep(None, samples=2, seed=11, worst_case=False,
                       scheduler=client.scheduler.address, progress=False)
    assert result.summary["executor"] == "scheduler, 2 workers"
    assert result.summary["samples"]["evaluated"] == 2


def test_a_sweep_survives_its_workers_being_killed(client, tmp_path):
    """Both worker processes killed (SIGKILL) while the sweep runs: their nannies start new
    ones and Dask runs the lost batches again (each task carries its context: nothing the
    dead workers held is needed). Every sample comes back once, none failed."""
    import threading

    out = tmp_path / "sweep"
    box = {}

    def sweep():
        box["result"] = run_sweep(None, samples=8, seed=7, worst_case=False, client=client,
                                  out=out, batch=1, progress=False, plots=False)

    thread = threading.Thread(target=sweep)
    thread.start()
    deadline = time.monotonic() + 180
    while not list((out / "samples").glob("part-*.parquet")):
        assert thread.is_alive() and time.monotonic() < deadline
        time.sleep(0.02)
    for pid in client.run(os.getpid).values():
        os.kill(pid, signal.SIGKILL)
    thread.join(300)
    assert not thread.is_alive()
    summary = box["result"].summary
    assert summary["samples"]["failed"] == 0
    samples = [i for p in (out / "samples").glob("part-*.parquet")
               for i in pq.read_table(p).column("sample").to_pylist()]
    assert sorted(samples) == list(range(8))
    client.wait_for_workers(2, timeout=120)


def test_a_local_cluster_beside_another_warns_nothing():
    """The sweep's LocalCluster while port 8787 is taken (another cluster's dashboard): no
    "Port 8787 is already in use" warning (the scheduler's HTTP server binds a free port), and
    nothing else warned while it starts and closes."""
    import socket
    import warnings

    from spacecraft.sweep.execute import open_executor

    taken = socket.socket()
    try:
        taken.bind(("0.0.0.0", 8787))
        taken.listen(1)
    except OSError:
        taken.close()          # taken already: by another cluster, as the test wants
        taken = None
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            executor = open_executor(workers=2)
            try:
                assert executor.kind == "local-cluster" and executor.n_workers == 2
            finally:
                executor.close()
        assert [str(w.message) for w in caught] == []
    finally:
        if taken is not None:
            taken.close()


def test_local_cluster_workers_keep_the_allocator_of_a_process_alone(monkeypatch):
    """The sweep's LocalCluster workers: no MALLOC_TRIM_THRESHOLD_ (Dask's nannies set 65536,
    which makes glibc map and unmap every array of a frequency grid; spacecraft.sweep.execute,
    LOCAL_CLUSTER_CONFIG), Dask's other settings as before; Dask's configuration as it was
    after.
    (A value already in this process's environment is the user's, or one that an earlier
    cluster's nannies left there, as the other tests' clusters here do: it is kept, so the
    test starts without one.)"""
    import os

    monkeypatch.delenv("MALLOC_TRIM_THRESHOLD_", raising=False)

    import dask
    import distributed  # noqa: F401  (its configuration's defaults)

    from spacecraft.sweep.execute import open_executor

    before = dask.config.get("distributed.nanny.pre-spawn-environ")
    executor = open_executor(workers=2)
    try:
        environ = executor.client.run(lambda: {k: os.environ.get(k) for k in (
            "MALLOC_TRIM_THRESHOLD_", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")})
    finally:
        executor.close()
    assert len(environ) == 2
    for worker in environ.values():
        assert worker["MALLOC_TRIM_THRESHOLD_"] is None
        # Dask's other settings still reach the workers (one BLAS thread, unless this
        # process's environment says otherwise: Dask keeps a value set there)
        for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
            assert worker[name] == os.environ.get(name, "1")
    assert dask.config.get("distributed.nanny.pre-spawn-environ") == before
