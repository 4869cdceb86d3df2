"""Sweep folders (spacecraft/sweep/execute.py): locked like run folders, damaged parts named or
recomputed, nothing left behind by a sweep that could not start, files written atomically."""
import json
import os
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from spacecraft import cli
from spacecraft.report.output import LOCK, OWNER, FolderLock, OutputError
from spacecraft.sweep import SweepError, run_sweep
from spacecraft.sweep.execute import SampleStore

ROOT = Path(__file__).resolve().parents[3]
INERTIA = {"hub.inertia": {"distribution": "uniform", "low": 40.0, "high": 60.0}}


def small_sweep(out, **options):
    settings = dict(parameters=INERTIA, samples=4, seed=2, worst_case=False, workers=1,
                    progress=False, plots=False, batch=1, out=out)
    settings.update(options)
    return run_sweep(None, **settings)


def samples_of(folder):
    return sorted(i for p in (folder / "samples").glob("part-*.parquet")
                  for i in pq.read_table(p).column("sample").to_pylist())


def test_a_folder_being_written_is_refused_naming_the_writer(tmp_path, monkeypatch):
    """The lock of a live process (this one, standing in for a running sweep): a second
    sweep, fresh or resumed, is refused before any work, naming that process."""
    import spacecraft.sweep.runner as runner

    def no_work(*args, **kwargs):
        raise AssertionError("the sweep started its work on a locked folder")

    monkeypatch.setattr(runner, "prepare", no_work)
    folder = tmp_path / "sweep"
    folder.mkdir()
    (folder / "sweep.json").write_text("{}")
    with FolderLock(folder, "flexsat sweep"):
        owner = json.loads((folder / LOCK / OWNER).read_text())
        assert owner["pid"] == os.getpid() and owner["command"] == "flexsat sweep"
        with pytest.raises(OutputError, match=rf"another flexsat sweep \(pid {os.getpid()} on "):
            small_sweep(folder, resume=True)
        assert cli.main(["sweep", "--resume", "--out", str(folder), "--quiet"]) == 2
    assert not (folder / LOCK).exists()


def test_the_lock_of_a_dead_sweep_is_taken_over(tmp_path):
    """A sweep killed with SIGKILL leaves its lock; its process is gone, so the next sweep
    takes the folder."""
    folder = tmp_path / "sweep"
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    (folder / LOCK).mkdir(parents=True)
    (folder / LOCK / OWNER).write_text(json.dumps({
        "program": "flexsat", "command": "flexsat sweep", "pid": int(dead.stdout),
        "host": os.uname().nodename, "start": "0", "since": "then"}))
    (folder / "sweep.json").write_text("{}")
    with SampleStore(folder, resume=True) as store:
        owner = json.loads((folder / LOCK / OWNER).read_text())
        assert owner["pid"] == os.getpid() and store.folder == folder
    assert not (folder / LOCK).exists()


def test_a_sweep_that_cannot_start_leaves_no_folder(tmp_path, capsys):
    out = tmp_path / "a" / "b"
    assert cli.main(["sweep", "--workers", "0", "--out", str(out), "--quiet"]) == 2
    assert "workers must be a positive integer" in capsys.readouterr().err
    assert cli.main(["sweep", "--samples", "2", "--scheduler", "tcp://127.0.0.1:9", "--out",
                     str(out), "--quiet"]) == 2
    assert "cannot reach a Dask scheduler" in capsys.readouterr().err
    assert not (tmp_path / "a").exists()
    # a failure after the folder was claimed (here: a bad box, found while preparing) takes
    # back what the sweep made
    assert cli.main(["sweep", "--samples", "2", "--workers", "1", "--out", str(out),
                     "--quiet", "--seed", "-1"]) == 2
    capsys.readouterr()
    assert not (tmp_path / "a").exists()


def test_the_same_empty_folder_stays_empty_after_a_refusal(tmp_path):
    out = tmp_path / "given"
    out.mkdir()
    with pytest.raises(SweepError, match="workers must be a positive integer"):
        small_sweep(out, workers=0)
    assert out.is_dir() and not any(out.iterdir())


def _flip_a_value(path: Path, value: float) -> None:
    """Flip one mantissa bit of a double stored in a Parquet part (its data page)."""
    data = bytearray(path.read_bytes())
    at = data.find(struct.pack("<d", value))
    assert at >= 0
    data[at + 2] ^= 0x10
    path.write_bytes(bytes(data))


@pytest.mark.slow
def test_damaged_parts_are_recomputed_on_resume_and_named(tmp_path, capsys):
    """A truncated, a bit-flipped and an empty part: the resume sets each aside
    (``<name>.damaged``), computes its samples again and says so; the table is that of the
    undamaged sweep (samples are decided by their index alone)."""
    out = tmp_path / "sweep"
    first = small_sweep(out)
    parts = sorted((out / "samples").glob("part-*.parquet"))
    assert len(parts) == 4
    parts[0].write_bytes(parts[0].read_bytes()[:-40])                  # truncated
    _flip_a_value(parts[1], first.table.column("hub.inertia")[1].as_py())  # one bit flipped
    parts[2].write_bytes(b"")                                          # empty
    # reading the folder as it is names the first damaged part
    with SampleStore(out, resume=True) as store:
        with pytest.raises(SweepError, match=rf"{parts[0].name}: damaged Parquet part"):
            store.read()
    again = small_sweep(out, resume=True)
    damaged = sorted(p.name for p in (out / "samples").glob("*.damaged"))
    assert damaged == sorted(p.name + ".damaged" for p in parts[:3])
    assert again.summary["samples"]["recomputed_parts"] == [p.name for p in parts[:3]]
    assert again.summary["samples"]["evaluated_now"] == 3
    assert samples_of(out) == [0, 1, 2, 3]
    for name in ("hub.inertia", "exact_modulus_margin", "stable"):
        assert again.table.column(name).to_pylist() == first.table.column(name).to_pylist()
    assert "recomputed on resume" in (out / "report.md").read_text()


@pytest.mark.slow
def test_a_resume_started_beside_a_running_sweep_is_refused(tmp_path, capsys):
    """Issue 20's reproducer: a second ``flexsat sweep --resume`` on a folder a first sweep is
    writing. It is refused naming the first; after the first is killed, a resume takes the
    folder over and finishes it: every sample once."""
    out = tmp_path / "sweep"
    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    env["OPENBLAS_NUM_THREADS"] = "1"
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    first = subprocess.Popen(
        [sys.executable, "-m", "spacecraft.cli.sweep", "--samples", "40", "--seed", "5",
         "--no-worst-case", "--no-plots", "--quiet", "--workers", "1", "--out", str(out)],
        cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120
        while not (out / LOCK / OWNER).is_file() or not (out / "sweep.json").is_file():
            assert first.poll() is None, first.stderr.read().decode()
            assert time.monotonic() < deadline
            time.sleep(0.02)
        assert cli.main(["sweep", "--samples", "40", "--seed", "5", "--no-worst-case",
                         "--no-plots", "--quiet", "--workers", "1", "--out", str(out),
                         "--resume"]) == 2
        err = capsys.readouterr().err
        assert f"another flexsat sweep (pid {first.pid} on" in err and err.count("\n") == 1
    finally:
        first.send_signal(signal.SIGKILL)
        first.wait()
        first.stderr.close()
    done = samples_of(out)
    assert len(done) == len(set(done)) < 40
    resumed = run_sweep(None, samples=40, seed=5, worst_case=False, workers=1, out=out,
                        resume=True, progress=False, plots=False)
    assert resumed.summary["samples"]["resumed_from_folder"] == len(done)
    assert samples_of(out) == list(range(40))


def test_summary_and_report_are_written_atomically(tmp_path, monkeypatch):
    """A report whose writing fails (the disk fills at the last step, the rename) leaves the
    previous summary.json and report.md whole and no temporary file behind: each file is
    written to a temporary name and renamed."""
    import errno

    import fmu.files
    import spacecraft.sweep.report as report

    summary = {"title": "t", "settings": {"method": "monte-carlo", "seed": 0, "parameters": []},
               "samples": {"total": 0, "failed": 0}, "loop": {
                   "controller": "lqr", "design_model": "x", "design": "nominal",
                   "n_modes": 2, "exact_reference": False},
               "executor": "synchronous",
               "instability": {**report.instability(0, 0, 0), "verdict": "truth"},
               "sensitivity": {"measure": "", "ranking": []}, "worst_case": [], "metrics": {},
               "failures": [], "timings": {}}
    report.write_report(tmp_path, None, None, None, summary, plots=False)
    before = {name: (tmp_path / name).read_bytes() for name in ("summary.json", "report.md")}

    def full(source, destination):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(fmu.files.os, "replace", full)
    with pytest.raises(OSError):
        report.write_report(tmp_path, None, None, None, {**summary, "title": "new"},
                            plots=False)
    for name, data in before.items():
        assert (tmp_path / name).read_bytes() == data, name
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.html", "report.md",
                                                          "summary.json"]
