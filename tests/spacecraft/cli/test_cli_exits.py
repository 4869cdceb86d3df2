"""Every exit path of the flexsat command, and its output folders.

Exit codes (spacecraft/cli/command.py): 0 success (also when stdout is closed early); 1 a bug of
flexsat; 2 a user or environment error, one line on stderr; 130 SIGINT; 128 + n signal n
(143 SIGTERM, 129 SIGHUP). Output folders are claimed before any computing, follow the umask,
are complete or absent, and simultaneous runs never collide.

Subprocess tests run ``python -m spacecraft.cli`` (or ``-c`` with a slowed runner) from the
repository root, as flexsat is not installed in the test environment.
"""
import errno
import json
import os
import signal
import stat
import subprocess
import sys
import time
import warnings
from pathlib import Path

import pytest

import spacecraft.report.write
import spacecraft.design.loop
from spacecraft.report.output import OWNER

from command import flexsat
from scenes import BASE_TOML, edited

ROOT = Path(__file__).resolve().parents[3]


def one_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


def no_computing(monkeypatch):
    """Make any scene run fail loudly: the checks under test must come before it."""
    def fail(*args, **kwargs):
        raise AssertionError("the run started although the output folder is unusable")
    monkeypatch.setattr(spacecraft.design.loop, "run", fail)


# ---------------------------------------------------------------------------------------------
# 0 and 1
# ---------------------------------------------------------------------------------------------
def test_success_exits_0_with_a_complete_folder(scene_file, tmp_path, capsys):
    out = tmp_path / "out"
    assert flexsat("run", scene_file, "--out", out, "--quiet", "--no-fmu") == 0
    assert (out / ".flexsat-complete").is_file() and not (out / OWNER).exists()
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("error", [ZeroDivisionError("float division by zero"),
                                   KeyError("theta"), RecursionError("deep")])
def test_a_bug_exits_1_with_one_line(scene_file, tmp_path, capsys, monkeypatch, error):
    def broken(*args, **kwargs):
        raise error
    monkeypatch.setattr(spacecraft.design.loop, "run", broken)
    out = tmp_path / "out"
    assert flexsat("run", scene_file, "--out", out, "--quiet") == 1
    line = one_line(capsys)
    assert line.startswith(f"flexsat: internal error: {type(error).__name__}: ")
    assert "a bug in flexsat" in line
    assert not out.exists() and not list(tmp_path.glob(".out.partial*"))


def test_debug_shows_the_traceback(scene_file, tmp_path, capsys, monkeypatch):
    def broken(*args, **kwargs):
        raise ZeroDivisionError("x")
    monkeypatch.setattr(spacecraft.design.loop, "run", broken)
    assert flexsat("--debug", "run", scene_file, "--out", tmp_path / "o", "--quiet") == 1
    assert "Traceback" in capsys.readouterr().err


@pytest.mark.slow
def test_a_diverging_loop_exits_0_and_the_report_says_where_it_stopped(scene_file, tmp_path,
                                                                       capsys):
    """The LQR on the paper's chain, UNSTABLE on the damped truth beam, for 40000 s: before, the
    run crashed with "simulation overflowed" (exit 1)."""
    scene_file.write_text(
        edited(BASE_TOML, ('types = ["pd"]', 'types = ["lqr"]'),
               ("[controller.pd]\nnatural_frequency = 0.1",
                "[controller.lqr]\nattitude_weight = 7.6\ntorque_weight = 1.0"),
               ("duration = 120.0", "duration = 40000.0"),
               ("youngs_modulus = 2.06e11", "youngs_modulus = 2.06e11\ndamping_ratio = 0.005"),
               ("n_modes = 3", "n_modes = 2")))
    out = tmp_path / "o"
    assert flexsat("run", scene_file, "--out", out, "--quiet", "--no-fmu") == 0
    said = "UNSTABLE: diverges, simulation stopped at t = "
    assert said in capsys.readouterr().out
    assert said in (out / "report.md").read_text() and said in (out / "report.html").read_text()
    row = json.loads((out / "results.json").read_text())["closed_loops"][0]
    assert row["diverged"]["truth"] > 0 and row["metrics"]["truth"]["peak_torque"] is None
    assert row["metric_flags"]["truth"]["peak_torque"] == "diverges"


# ---------------------------------------------------------------------------------------------
# 2: the scene and the options
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("edit, message", [
    (("length = 10.0", "length = 1e-9"),
     r"appendages\[0\]\.beam\.length: must lie between 0\.01 and 1000 \[m\]; got 1e-09"),
    (("name = \"rod\"", "name = \"bööm\""), r"appendages\[0\]\.name: must be an ASCII identifier"),
    (("n_modes = 3", "n_modes = 5000"), r"fidelity\.n_modes: 5000: over the limit 500"),
    (("n_modes = 3", "tolerance = 1e-12"), r"fidelity\.tolerance: no truncation with up to 40"),
    (("title = \"test boom\"", "title = " + "[" * 500 + "]" * 500),
     r"boom\.toml: tables or arrays nested too deeply"),
])
def test_scene_errors_exit_2_with_one_line(scene_file, tmp_path, capsys, edit, message):
    import re

    scene_file.write_text(edited(BASE_TOML, edit))
    out = tmp_path / "o"
    assert flexsat("run", scene_file, "--out", out, "--quiet", "--no-fmu") == 2
    line = one_line(capsys)
    assert line.startswith("flexsat: error: ") and re.search(message, line), line
    assert not out.exists() and not list(tmp_path.glob(".o.partial*"))


def test_limit_option_raises_and_lowers_limits(scene_file, tmp_path, capsys):
    assert flexsat("run", scene_file, "--out", tmp_path / "a", "--quiet", "--no-fmu",
                   "--limit", "fit_bodies=2") == 2
    assert "appendages[0].fit.n_bodies: 3: over the limit 2 (limits.fit_bodies" in one_line(capsys)
    assert flexsat("run", scene_file, "--out", tmp_path / "b", "--quiet", "--no-fmu",
                   "--limit", "samples=100") == 2
    assert "manoeuvre.step: 241 samples per simulation" in one_line(capsys)
    scene_file.write_text(edited(BASE_TOML, ("test boom", "t" * 5000)))
    assert flexsat("run", scene_file, "--out", tmp_path / "c", "--quiet", "--no-fmu") == 2
    assert "title: a text of 5000 characters: over the limit 4096" in one_line(capsys)
    assert flexsat("run", scene_file, "--out", tmp_path / "c", "--quiet", "--no-fmu",
                   "--limit", "string_length=5000") == 0
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:
        flexsat("run", scene_file, "--limit", "modes")
    assert exc.value.code == 2
    assert "expected NAME=VALUE" in one_line(capsys)
    assert flexsat("run", scene_file, "--limit", "modez=3") == 2
    assert "--limit: limits.modez: unknown key" in one_line(capsys)


@pytest.mark.parametrize("value, message", [
    ("modes=abc", "argument --limit: modes: expected a number; got 'abc'"),
    ("=3", "argument --limit: expected NAME=VALUE (e.g. modes=800); got '=3'"),
    ("modes=", "argument --limit: modes: expected a number; got ''")])
def test_bad_limit_values_are_one_line(scene_file, capsys, value, message):
    """Issue-9 review: `--limit modes=abc` printed argparse's usage (3 lines) before the
    error; now one line that says where the help is."""
    with pytest.raises(SystemExit) as exc:
        flexsat("run", scene_file, "--limit", value)
    assert exc.value.code == 2
    assert one_line(capsys) == (f"flexsat: error: {message} (see 'flexsat run --help')")


@pytest.mark.parametrize("command", ["table", "fit"])
def test_n_bodies_of_table_and_fit_is_bounded(command, capsys):
    assert flexsat(command, "--n-bodies", "1000") == 2
    assert "--n-bodies 1000: over the limit 14 (limits.fit_bodies" in one_line(capsys)


# ---------------------------------------------------------------------------------------------
# 2: the output folder, found before anything is computed
# ---------------------------------------------------------------------------------------------
def test_output_under_proc_exits_2_before_computing(scene_file, capsys, monkeypatch):
    no_computing(monkeypatch)
    assert flexsat("run", scene_file, "--out", "/proc/flexsat-out", "--quiet") == 2
    assert one_line(capsys).startswith("flexsat: error: /proc/flexsat-out: cannot create the "
                                       "output folder here (")


@pytest.mark.parametrize("problem", [errno.EROFS, errno.EACCES])
def test_unwritable_output_exits_2_before_computing(scene_file, tmp_path, capsys, monkeypatch,
                                                    problem):
    # root may write anywhere: the file system's refusal is simulated at the one mkdir
    import spacecraft.report.output

    def refuse(path, *args, **kwargs):
        raise OSError(problem, os.strerror(problem), str(path))
    monkeypatch.setattr(spacecraft.report.output.os, "mkdir", refuse)
    no_computing(monkeypatch)
    assert flexsat("run", scene_file, "--out", tmp_path / "o", "--quiet") == 2
    assert f"cannot create the output folder here ({os.strerror(problem)})" in one_line(capsys)


@pytest.mark.parametrize("make, message", [
    (lambda p: p.symlink_to(p.parent / "nowhere" / "x"), "a symbolic link to .*nowhere/x, "
                                                        "which does not exist"),
    (lambda p: p.write_text("a file"), "exists and is not a folder"),
    (lambda p: (p.mkdir(), (p / "keep.txt").write_text("mine")), "exists and is not empty"),
    (lambda p: (p.parent / "full").mkdir() or (p.parent / "full" / "x").write_text("")
     or p.symlink_to(p.parent / "full"), "full: output folder exists and is not empty"),
])
def test_unusable_output_exits_2_before_computing(scene_file, tmp_path, capsys, monkeypatch,
                                                  make, message):
    import re

    out = tmp_path / "o"
    make(out)
    no_computing(monkeypatch)
    assert flexsat("run", scene_file, "--out", out, "--quiet") == 2
    assert re.search(message, one_line(capsys))


def test_output_under_a_file_exits_2(scene_file, tmp_path, capsys, monkeypatch):
    (tmp_path / "afile").write_text("")
    no_computing(monkeypatch)
    assert flexsat("run", scene_file, "--out", tmp_path / "afile" / "o", "--quiet") == 2
    assert "is a file, not a folder" in one_line(capsys)


def test_a_link_to_an_empty_folder_is_followed(scene_file, tmp_path):
    target = tmp_path / "target"
    target.mkdir(mode=0o751)
    target.chmod(0o751)
    (tmp_path / "link").symlink_to(target)
    assert flexsat("run", scene_file, "--out", tmp_path / "link", "--quiet", "--no-fmu") == 0
    assert (target / "report.md").is_file() and (tmp_path / "link").is_symlink()
    assert stat.S_IMODE(target.stat().st_mode) == 0o751   # an existing folder keeps its mode


def test_disk_full_exits_2_and_removes_the_partial_folder(scene_file, tmp_path, capsys,
                                                          monkeypatch):
    original = Path.write_text

    def full(self, text, *args, **kwargs):
        if self.name == "report.html":
            original(self, text[:10], *args, **kwargs)   # a part was written, then no space
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return original(self, text, *args, **kwargs)
    monkeypatch.setattr(Path, "write_text", full)
    out = tmp_path / "o"
    assert flexsat("run", scene_file, "--out", out, "--quiet", "--no-fmu") == 2
    assert "cannot write the output (No space left on device); nothing was kept" in \
        one_line(capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["boom.toml"]


def test_a_full_tmpdir_is_blamed_on_tmpdir_not_on_out(scene_file, tmp_path, capsys,
                                                    monkeypatch):
    """Issue-9 review: with $TMPDIR on a full 16 KiB tmpfs, `flexsat export` said "<out>:
    cannot write the output (No space left on device: .../fmu/c/fmi2Functions.c) ... choose
    another --out": the FMU build folder in $TMPDIR was full, not --out. (shutil.copyfile
    names the source file in that error, as here.)"""
    import shutil
    import tempfile

    scratch = tmp_path / "scratch"
    scratch.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))
    original = shutil.copyfile

    def full(src, dst, *args, **kwargs):
        if str(dst).startswith(str(scratch)):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(src))
        return original(src, dst, *args, **kwargs)
    monkeypatch.setattr(shutil, "copyfile", full)
    out = tmp_path / "o"
    assert flexsat("export", scene_file, "--out", out, "--quiet") == 2
    line = one_line(capsys)
    assert (f"FMU export failed: cannot write the FMU build folder in {scratch} (No space left "
            "on device); free some space there or set TMPDIR to a folder with room") in line
    assert "--out" not in line
    assert not out.exists()


def test_out_of_memory_exits_2(scene_file, tmp_path, capsys, monkeypatch):
    def hungry(*args, **kwargs):
        raise MemoryError()
    monkeypatch.setattr(spacecraft.design.loop, "run", hungry)
    assert flexsat("run", scene_file, "--out", tmp_path / "o", "--quiet") == 2
    assert one_line(capsys).startswith("flexsat: error: out of memory")


@pytest.mark.parametrize("message, code", [
    ("no C compiler found (looked for cc, gcc); install one", 2),
    ("compiling the FMU binary failed (exit code 1): This is a bug in flexsat.fmu", 1),
])
def test_fmu_errors_are_classified(scene_file, tmp_path, capsys, monkeypatch, message, code):
    from fmu import FMUBuildError

    def no_compiler(*args, **kwargs):
        raise FMUBuildError(message)
    monkeypatch.setattr(spacecraft.report.write, "write_report", no_compiler)
    assert flexsat("run", scene_file, "--out", tmp_path / "o", "--quiet") == code
    assert "FMU export failed: " + message.split(":")[0] in one_line(capsys)


def test_a_broken_compiler_exits_2_naming_it_and_cc(scene_file, tmp_path, capsys,
                                                   monkeypatch):
    """Issue-9 review: CC=/bin/false gave "internal error ... This is a bug in flexsat.fmu if
    the compiler itself works", exit 1. A compiler that fails on a trivial C file is an
    environment error: exit 2, one line naming it and CC."""
    monkeypatch.setenv("CC", "/bin/false")
    assert flexsat("export", scene_file, "--out", tmp_path / "o", "--quiet") == 2
    line = one_line(capsys)
    assert line.startswith("flexsat: error: FMU export failed: the C compiler /bin/false "
                           "(from $CC) does not work"), line
    assert "bug" not in line and "set CC" in line
    assert not (tmp_path / "o").exists()


def test_a_folder_being_written_by_a_live_run_exits_2(scene_file, tmp_path, capsys,
                                                      monkeypatch):
    import socket

    partial = tmp_path / ".o.partial"
    partial.mkdir()
    (partial / OWNER).write_text(json.dumps({"program": "flexsat", "pid": os.getpid(),
                                             "host": socket.gethostname()}))
    no_computing(monkeypatch)
    assert flexsat("run", scene_file, "--out", tmp_path / "o", "--quiet") == 2
    assert f"another flexsat run (pid {os.getpid()} on" in one_line(capsys)
    assert partial.is_dir()   # a live run's folder is left alone


def dead_pid() -> int:
    done = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)
    return int(done.stdout)


def test_stale_partial_folders_of_dead_runs_are_removed(scene_file, tmp_path):
    import socket

    for name in (".o.partial", ".other.partial"):
        partial = tmp_path / name
        partial.mkdir()
        (partial / "report.md").write_text("half")
        (partial / OWNER).write_text(json.dumps({"program": "flexsat", "pid": dead_pid(),
                                                 "host": socket.gethostname()}))
    (tmp_path / ".mine.partial").mkdir()   # not flexsat's (no owner record): left alone
    assert flexsat("run", scene_file, "--out", tmp_path / "o", "--quiet", "--no-fmu") == 0
    assert (tmp_path / "o" / "report.md").read_text() != "half"
    assert sorted(p.name for p in tmp_path.iterdir()) == [".mine.partial", "boom.toml", "o"]


# ---------------------------------------------------------------------------------------------
# permissions
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("umask", [0o022, 0o027, 0o002])
def test_folders_and_files_follow_the_umask(scene_file, tmp_path, umask):
    previous = os.umask(umask)
    try:
        out = tmp_path / "o"
        assert flexsat("run", scene_file, "--out", out, "--quiet", "--no-fmu") == 0
    finally:
        os.umask(previous)
    # before: folders 0700 whatever the umask (tempfile.mkdtemp)
    assert stat.S_IMODE(out.stat().st_mode) == 0o777 & ~umask
    for name in ("report.md", "report.html", "results.json"):
        assert stat.S_IMODE((out / name).stat().st_mode) == 0o666 & ~umask


def test_an_existing_empty_folder_keeps_its_mode(scene_file, tmp_path):
    out = tmp_path / "o"
    out.mkdir()
    out.chmod(0o755)
    assert flexsat("run", scene_file, "--out", out, "--quiet", "--no-fmu") == 0
    assert stat.S_IMODE(out.stat().st_mode) == 0o755   # before: chmod-ed to 0700


# ---------------------------------------------------------------------------------------------
# report text
# ---------------------------------------------------------------------------------------------
EVIL = "<script>alert(1)</script> *bold* _it_ [x](http://e) `c` | ~~s~~ &amp;"


def test_title_is_escaped_in_markdown_and_html(scene_file, tmp_path):
    scene_file.write_text(edited(BASE_TOML, ('title = "test boom"', f"title = '{EVIL}'")))
    out = tmp_path / "o"
    assert flexsat("run", scene_file, "--out", out, "--quiet", "--no-fmu") == 0
    md, page = (out / "report.md").read_text(), (out / "report.html").read_text()
    assert md.splitlines()[0] == (r"# &lt;script&gt;alert(1)&lt;/script&gt; \*bold\* \_it\_ "
                                  r"\[x\](http://e) \`c\` \| \~\~s\~\~ &amp;amp;")
    assert "<script>" not in md and "<script>" not in page
    assert "<h1>&lt;script&gt;alert(1)&lt;/script&gt; *bold*" in page
    assert json.loads((out / "results.json").read_text())["title"] == EVIL


def test_markdown_text_renders_as_the_text():
    from spacecraft.report.write import markdown_text

    assert markdown_text("n_modes = 3, peak_tip") == "n_modes = 3, peak_tip"  # intraword _
    assert markdown_text("# 1. - x", line_start=True) == r"\# 1. - x"
    assert markdown_text("1. x", line_start=True) == r"1\. x"
    assert markdown_text("a\nb") == "a b"


# ---------------------------------------------------------------------------------------------
# warnings
# ---------------------------------------------------------------------------------------------
def test_numerical_warnings_are_one_formatted_line(scene_file, tmp_path, capsys, monkeypatch):
    import controllers
    import numpy as np

    original = controllers.metrics

    def noisy(response, **kwargs):
        # metrics run under np.errstate in the runner: warn as numpy would outside it
        warnings.warn("divide by zero encountered in log", RuntimeWarning)
        return original(response, **kwargs)
    monkeypatch.setattr(controllers, "metrics", noisy)
    out = tmp_path / "o"
    assert flexsat("run", scene_file, "--out", out, "--quiet", "--no-fmu") == 0
    line = one_line(capsys)
    assert line.startswith("flexsat: warning: RuntimeWarning: divide by zero encountered in "
                           "log (")
    assert "divide by zero encountered in log" in (out / "report.md").read_text()


# ---------------------------------------------------------------------------------------------
# subprocesses: signals, broken pipe, simultaneous runs
# ---------------------------------------------------------------------------------------------
SLOW_RUN = """\
import sys, time
sys.path.insert(0, {root!r})
import spacecraft.design.loop as runner
real = runner.DesignLoop.run
def slow(self):
    time.sleep({seconds})   # in the computation, after the output folder was claimed
    return real(self)
runner.DesignLoop.run = slow
from spacecraft.cli.command import main
sys.exit(main(sys.argv[1:]))
"""


def _sigint_as_in_a_terminal():
    """A command typed in a terminal starts with SIGINT at its default, which Python turns
    into KeyboardInterrupt. Tests run in the background of a script (nohup, a CI runner, `&`
    without job control) inherit SIGINT ignored, and a child that inherits that ignores it
    too, as POSIX asks: the child of these tests gets the terminal's disposition."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start(args, seconds, cwd=ROOT, **kwargs):
    code = SLOW_RUN.format(root=str(ROOT), seconds=seconds)
    return subprocess.Popen([sys.executable, "-c", code, *map(str, args)], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=_sigint_as_in_a_terminal, **kwargs)


def wait_for_partial(folder: Path, process, timeout: float = 120.0):
    """Wait until ``process`` has made its partial output folder in ``folder``."""
    t0 = time.monotonic()
    while not list(folder.glob(".o.partial*")):
        assert process.poll() is None, process.communicate()
        assert time.monotonic() - t0 < timeout, "the partial folder never appeared"
        time.sleep(0.05)
    time.sleep(0.2)   # its owner record is written right after the folder


@pytest.mark.slow
@pytest.mark.parametrize("signum, code, text", [
    (signal.SIGINT, 130, "flexsat: interrupted; nothing half-written was kept"),
    (signal.SIGTERM, 143, "flexsat: terminated by SIGTERM; nothing half-written was kept"),
    (signal.SIGHUP, 129, "flexsat: terminated by SIGHUP; nothing half-written was kept"),
])
def test_signals_clean_up_and_exit_128_plus_n(scene_file, tmp_path, signum, code, text):
    out = tmp_path / "o"
    process = start(["run", scene_file, "--out", out, "--quiet", "--no-fmu"], 120)
    wait_for_partial(tmp_path, process)
    process.send_signal(signum)
    stdout, stderr = process.communicate(timeout=60)
    assert process.returncode == code, stderr
    assert stderr.strip() == text
    # before: SIGTERM killed the process at once, leaving .o.partial-* behind
    assert sorted(p.name for p in tmp_path.iterdir()) == ["boom.toml"]


@pytest.mark.slow
def test_sigkill_leaves_a_partial_folder_that_the_next_run_takes_over(scene_file, tmp_path):
    out = tmp_path / "o"
    process = start(["run", scene_file, "--out", out, "--quiet", "--no-fmu"], 120)
    wait_for_partial(tmp_path, process)
    process.kill()
    process.communicate(timeout=60)
    assert (tmp_path / ".o.partial").is_dir()
    assert flexsat("run", scene_file, "--out", out, "--quiet", "--no-fmu") == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["boom.toml", "o"]


@pytest.mark.slow
def test_broken_pipe_exits_0_quietly(scene_file, tmp_path):
    out = tmp_path / "o"
    process = subprocess.Popen([sys.executable, "-m", "spacecraft.cli", "run", str(scene_file),
                                "--out", str(out), "--json", "--quiet", "--no-fmu"], cwd=ROOT,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    process.stdout.close()   # the reader (e.g. head) is gone before flexsat writes
    stderr = process.stderr.read().decode()
    process.wait(timeout=120)
    assert process.returncode == 0
    assert stderr == ""   # no traceback, no "Exception ignored ... BrokenPipeError"
    assert (out / ".flexsat-complete").is_file()


@pytest.mark.slow
def test_simultaneous_runs_to_one_new_folder_one_wins(scene_file, tmp_path):
    out = tmp_path / "o"
    processes = [start(["run", scene_file, "--out", out, "--quiet", "--no-fmu"], 3)
                 for _ in range(4)]
    results = [(p.wait(timeout=300), p.communicate()[1]) for p in processes]
    codes = sorted(code for code, _ in results)
    assert codes == [0, 2, 2, 2], results
    for code, stderr in results:
        if code == 2:
            assert len(stderr.strip().splitlines()) == 1, stderr
            # "(pid ... on host, since ...)" once the winner's owner record is written; a loser
            # that looks in the instant between the winner's mkdir and that write sees none
            assert ("another flexsat run" in stderr or "exists and is not empty" in stderr)
    assert (out / ".flexsat-complete").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["boom.toml", "o"]


@pytest.mark.slow
def test_simultaneous_runs_without_out_get_distinct_folders(scene_file, tmp_path):
    # before: the same flexsat-<second> name for all, then "Directory not empty" (exit 1)
    processes = [start(["run", scene_file, "--quiet", "--no-fmu"], 3, cwd=tmp_path)
                 for _ in range(4)]
    results = [(p.wait(timeout=300), p.communicate()) for p in processes]
    assert [code for code, _ in results] == [0, 0, 0, 0], results
    folders = sorted(p for p in tmp_path.iterdir() if p.name.startswith("flexsat-"))
    assert len(folders) == 4
    assert all((f / ".flexsat-complete").is_file() for f in folders)
    # each run names its own folder
    named = sorted(out.strip().splitlines()[-1].rsplit(" to ", 1)[1] for _, (out, _) in results)
    assert named == [str(f) for f in folders]
