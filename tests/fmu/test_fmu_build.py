"""Building FMU binaries: the persistent object cache under concurrency, its failure modes,
the verification of every FMU before it is written, and the clean-up of build folders.

The concurrency tests use a deliberately slow compiler: a shell script that waits, then
runs gcc. It also refuses to run when another compiler process is writing the same output
file at that moment: two compilers writing one object file is how the exporter produced
libraries without fmi2 symbols (or "file not recognized" link errors) when it built on two
threads. Every FMU produced is then checked independently of the exporter's own check:
``nm -D`` lists exactly the 44 fmi2 functions, and fmpy's Co-Simulation equals
``control.c2d`` + ``forced_response``.
"""

import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
import zipfile
from pathlib import Path

import control
import numpy as np
import pytest
from fmpy import simulate_fmu

import fmu
import fmu.build
from fmu import FMUBuildError, export
from fmu.codegen import template_sources
from fmu.cache import ObjectCache, compiler_identity, object_cache_dir
from fmu.verify import FMI2_COMMON, FMI2_CO_SIMULATION, elf_exported_symbols

ROOT = Path(__file__).resolve().parents[2]
J = 10.0  # hub inertia [kg m^2]
#: Fixed C templates of an FMI 2.0 FMU, each one cache entry
N_TEMPLATES = len(template_sources("2.0"))

SLOW_COMPILER = """#!/bin/sh
# A slow C compiler: waits {delay} s, then runs gcc. It fails if another compiler process
# writes the same output file at the same time.
out=""
prev=""
for arg in "$@"; do
  [ "$prev" = "-o" ] && out="$arg"
  prev="$arg"
done
if [ -n "$out" ]; then
  if ! mkdir "$out.writing" 2>/dev/null; then
    echo "two compilers write $out at once" >&2
    exit 1
  fi
  sleep {delay}
fi
gcc "$@"
status=$?
[ -n "$out" ] && rmdir "$out.writing"
exit $status
"""


def slow_compiler(folder: Path, delay: float = 0.5, version_note: str = "") -> Path:
    script = folder / "slow-cc"
    text = SLOW_COMPILER.format(delay=delay)
    if version_note:  # a compiler that reports another version
        text = text.replace('gcc "$@"\n', f'[ "$1" = "--version" ] && echo "{version_note}"\ngcc "$@"\n')
    script.write_text(text)
    script.chmod(0o755)
    return script


def rigid_body(gain=1.0):
    """J theta'' = gain * torque; outputs theta, omega."""
    return control.ss([[0, 1], [0, 0]], [[0], [gain / J]], np.eye(2), 0, inputs=["torque"],
                      outputs=["theta", "omega"], states=["angle", "rate"], name="body")


def assert_fmu_works(path: Path, system: control.StateSpace, h: float = 0.01):
    """nm -D lists exactly the 44 fmi2 functions; fmpy CS equals c2d(zoh) for a unit step."""
    with zipfile.ZipFile(path) as archive:
        binary = [n for n in archive.namelist() if n.startswith("binaries/")][0]
        data = archive.read(binary)
    library = path.with_suffix(".so.check")
    library.write_bytes(data)
    listing = subprocess.run(["nm", "-D", "--defined-only", str(library)], capture_output=True,
                             text=True, check=True).stdout
    symbols = {line.split()[-1] for line in listing.splitlines() if line.strip()}
    assert len(symbols) == 44 and all(s.startswith("fmi2") for s in symbols), sorted(symbols)
    table = np.array([(0.0, 1.0), (1.0, 1.0)], dtype=[("time", np.float64), ("torque", np.float64)])
    result = simulate_fmu(str(path), fmi_type="CoSimulation", stop_time=0.1, output_interval=h,
                          input=table)
    t = np.arange(11) * h
    expected = control.forced_response(control.c2d(system, h, "zoh"), T=t, U=np.ones_like(t))
    # exact discretisation on both sides: round-off only (outputs ~1e-3, errors ~1e-18)
    np.testing.assert_allclose(result["theta"], expected.outputs[0], rtol=1e-12, atol=1e-18)


@pytest.fixture
def cache_dir(tmp_path, monkeypatch):
    folder = tmp_path / "cache"
    monkeypatch.setenv("FLEXSAT_CACHE_DIR", str(folder))
    return folder / "fmu-objects"


# ---------------------------------------------------------------- concurrency


@pytest.mark.slow
def test_threads_exporting_at_once_share_the_cache_safely(tmp_path, cache_dir):
    """Four threads start exporting together with a cold cache and a slow compiler: no
    two compilers ever write one object, and every FMU works."""
    cc = slow_compiler(tmp_path)
    n_threads, per_thread = 4, 2
    barrier = threading.Barrier(n_threads)
    results, errors = {}, []

    def work(worker):
        barrier.wait()
        for k in range(per_thread):
            name = f"m{worker}_{k}"
            try:
                results[name] = export(rigid_body(1.0 + worker + k / 10), tmp_path / f"{name}.fmu",
                                       compiler=str(cc))
            except Exception as error:  # collected and reported below
                errors.append(f"{name}: {error}")

    threads = [threading.Thread(target=work, args=(w,)) for w in range(n_threads)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    for worker in range(n_threads):
        for k in range(per_thread):
            assert_fmu_works(results[f"m{worker}_{k}"], rigid_body(1.0 + worker + k / 10))
    # each template compiled once: two objects with their sidecars and locks, no leftovers
    assert sorted(p.suffix for p in cache_dir.iterdir()) == ([".json"] * N_TEMPLATES + [".lock"] * N_TEMPLATES
                                                             + [".o"] * N_TEMPLATES)


WORKER = """
import sys, threading
sys.path.insert(0, {root!r})
import control, numpy as np
from fmu import export
def body(gain):
    return control.ss([[0, 1], [0, 0]], [[0], [gain / 10.0]], np.eye(2), 0, inputs=["torque"],
                      outputs=["theta", "omega"], states=["angle", "rate"])
def work(k):
    export(body({gain} + k / 10), {folder!r} + "/p{index}_" + str(k) + ".fmu", compiler={cc!r})
threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
[t.start() for t in threads]
[t.join() for t in threads]
"""


@pytest.mark.slow
def test_processes_and_threads_exporting_at_once(tmp_path, cache_dir):
    """Three processes of two threads each, one cold persistent cache, a slow compiler."""
    cc = slow_compiler(tmp_path)
    processes = [subprocess.Popen([sys.executable, "-c", WORKER.format(
        root=str(ROOT), gain=1.0 + i, folder=str(tmp_path), index=i, cc=str(cc))],
        stderr=subprocess.PIPE, text=True) for i in range(3)]
    for process in processes:
        _, stderr = process.communicate(timeout=600)
        assert process.returncode == 0, stderr
    for i in range(3):
        for k in range(2):
            assert_fmu_works(tmp_path / f"p{i}_{k}.fmu", rigid_body(1.0 + i + k / 10))
    assert len(list(cache_dir.glob("*.o"))) == N_TEMPLATES and not list(cache_dir.glob("*.tmp-*"))


# ---------------------------------------------------------------- the persistent cache


@pytest.mark.slow
def test_cold_cache_is_created_and_then_reused(tmp_path, cache_dir):
    """A missing cache folder is created; the second export compiles only model.c."""
    assert not cache_dir.exists()
    export(rigid_body(), tmp_path / "a.fmu")
    objects = {p.name: p.stat().st_mtime_ns for p in cache_dir.glob("*.o")}
    assert len(objects) == N_TEMPLATES  # fmi2Functions.o, lti_instance.o, linear_model.o
    calls = []
    original = fmu.build.SharedLibraryBuild._compile_now
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(fmu.build.SharedLibraryBuild, "_compile_now",
                      lambda self, source, obj: calls.append(source.name) or original(self, source, obj))
        path = export(rigid_body(2.0), tmp_path / "b.fmu")
    assert calls == []  # both templates from the cache
    assert {p.name: p.stat().st_mtime_ns for p in cache_dir.glob("*.o")} == objects
    assert_fmu_works(path, rigid_body(2.0))


@pytest.mark.slow
@pytest.mark.parametrize("damage", ["truncated", "garbage", "no sidecar"])
def test_damaged_cache_entry_is_detected_and_rebuilt(tmp_path, cache_dir, damage):
    export(rigid_body(), tmp_path / "a.fmu")
    victim = sorted(cache_dir.glob("*.o"))[0]
    good = victim.read_bytes()
    if damage == "truncated":
        victim.write_bytes(good[:len(good) // 2])
    elif damage == "garbage":
        victim.write_bytes(b"\x7fELF" + bytes(len(good) - 4))
    else:
        victim.with_suffix(".json").unlink()
    path = export(rigid_body(3.0), tmp_path / "b.fmu")
    assert_fmu_works(path, rigid_body(3.0))
    assert ObjectCache(cache_dir).read(victim.stem) is not None  # rebuilt and intact again


@pytest.mark.slow
def test_entry_that_passes_its_checks_but_does_not_link_is_rebuilt(tmp_path, cache_dir):
    """An object with a matching sidecar but wrong content (an object of another source)
    makes the link fail once; the entry is evicted, rebuilt, and the export succeeds."""
    export(rigid_body(), tmp_path / "a.fmu")
    first, second, *_ = sorted(cache_dir.glob("*.o"))
    first.write_bytes(second.read_bytes())  # duplicate symbols at link time
    first.with_suffix(".json").write_bytes(second.with_suffix(".json").read_bytes())
    path = export(rigid_body(4.0), tmp_path / "b.fmu")
    assert_fmu_works(path, rigid_body(4.0))
    assert first.read_bytes() != second.read_bytes()


@pytest.mark.slow
def test_unwritable_cache_falls_back_to_a_process_folder(tmp_path, monkeypatch):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("a file where the cache folder would go")
    monkeypatch.setenv("FLEXSAT_CACHE_DIR", str(blocker / "cache"))
    folder = object_cache_dir()
    assert folder.is_dir() and folder.name.startswith(f"flexsat-fmu-cache-{os.getpid()}-")
    assert_fmu_works(export(rigid_body(), tmp_path / "a.fmu"), rigid_body())


@pytest.mark.slow
def test_without_working_file_locks_nothing_is_cached(tmp_path, cache_dir, monkeypatch):
    """flock fails with ENOLCK on some network file systems: compile privately instead."""
    import errno
    import fcntl

    def no_locks(descriptor, operation):
        raise OSError(errno.ENOLCK, "No locks available")

    monkeypatch.setattr(fcntl, "flock", no_locks)
    assert_fmu_works(export(rigid_body(), tmp_path / "a.fmu"), rigid_body())
    assert list(cache_dir.glob("*.o")) == []


def test_cache_location_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.delenv("FLEXSAT_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert object_cache_dir() == tmp_path / "xdg" / "flexsat" / "fmu-objects"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert object_cache_dir() == tmp_path / "home" / ".cache" / "flexsat" / "fmu-objects"
    monkeypatch.setenv("FLEXSAT_CACHE_DIR", str(tmp_path / "mine"))
    assert object_cache_dir() == tmp_path / "mine" / "fmu-objects"


@pytest.mark.slow
def test_another_compiler_version_gets_its_own_objects(tmp_path, cache_dir):
    """The key holds the compiler's --version output: a wrapper that reports another
    version compiles its own templates instead of using gcc's."""
    export(rigid_body(), tmp_path / "a.fmu")
    assert len(list(cache_dir.glob("*.o"))) == N_TEMPLATES
    other = tmp_path / "other"
    other.mkdir()
    cc = slow_compiler(other, delay=0.0, version_note="gcc (patched) 99.1")
    assert "99.1" in compiler_identity(str(cc))
    assert_fmu_works(export(rigid_body(), tmp_path / "b.fmu", compiler=cc), rigid_body())
    assert len(list(cache_dir.glob("*.o"))) == 2 * N_TEMPLATES


# ---------------------------------------------------------------- verification


@pytest.mark.slow
def test_every_fmu_is_verified_before_it_is_written(tmp_path, cache_dir, monkeypatch):
    """A library that computes other numbers than the model (here: model.c written for
    twice the input gain) fails the check: FMUBuildError, and no file."""
    export_module = sys.modules["fmu.export"]  # the name fmu.export is the function
    original = export_module.model_c_source

    def wrong_model_c(model, *args):
        return original(model.__class__(**{**model.__dict__, "B": 2 * model.B}), *args)

    monkeypatch.setattr(export_module, "model_c_source", wrong_model_c)
    with pytest.raises(FMUBuildError, match="failed its check"):
        export(rigid_body(), tmp_path / "wrong.fmu")
    assert list(tmp_path.glob("wrong*")) == [] and list(tmp_path.glob(".wrong*")) == []


@pytest.mark.slow
def test_a_library_without_the_declared_functions_is_refused(tmp_path, cache_dir, monkeypatch):
    """Compiled for Model Exchange only while the description declares both interfaces:
    the Co-Simulation functions are missing."""
    export_module = sys.modules["fmu.export"]
    original = export_module.interfaces_header
    monkeypatch.setattr(export_module, "interfaces_header",
                        lambda interfaces: original(("me",)))
    with pytest.raises(FMUBuildError, match=r"exactly the 44 FMI 2.0 functions .*9 missing "
                                            r"\['fmi2CancelStep'"):
        export(rigid_body(), tmp_path / "half.fmu")
    assert not (tmp_path / "half.fmu").exists()


def test_elf_reader_lists_what_the_loader_can_bind(tmp_path):
    """Exported: global and weak definitions of default or protected visibility. Not:
    static, hidden, undefined (puts) symbols. Checked against nm -D."""
    source = tmp_path / "lib.c"
    source.write_text(textwrap.dedent("""
        #include <stdio.h>
        int exported_function(void) { return puts("x"); }
        int exported_data = 1;
        __attribute__((weak)) int weak_function(void) { return 2; }
        __attribute__((visibility("protected"))) int protected_function(void) { return 3; }
        __attribute__((visibility("hidden"))) int hidden_function(void) { return 4; }
        static int static_function(void) { return 5; }
        int use_static(void) { return static_function(); }
    """))
    library = tmp_path / "lib.so"
    subprocess.run(["gcc", "-shared", "-fPIC", "-O0", "-o", str(library), str(source)], check=True)
    symbols = elf_exported_symbols(library.read_bytes())
    assert symbols == {"exported_function", "exported_data", "weak_function",
                       "protected_function", "use_static"}
    listing = subprocess.run(["nm", "-D", "--defined-only", str(library)], capture_output=True,
                             text=True, check=True).stdout
    assert symbols == {line.split()[-1] for line in listing.splitlines() if line.strip()}
    with pytest.raises(ValueError, match="not an ELF file"):
        elf_exported_symbols(b"garbage" * 20)


@pytest.mark.slow
def test_cs_only_fmu_exports_exactly_the_cs_functions(tmp_path, cache_dir):
    path = export(rigid_body(), tmp_path / "cs.fmu", interfaces="cs")
    with zipfile.ZipFile(path) as archive:
        symbols = elf_exported_symbols(archive.read("binaries/linux64/cs.so"))
    assert symbols == FMI2_COMMON | FMI2_CO_SIMULATION  # 25 + 9 functions, FMI 2.0.1


# ---------------------------------------------------------------- build folders


def dead_pid() -> int:
    process = subprocess.Popen([sys.executable, "-c", "pass"])
    process.wait()
    return process.pid


def test_stale_build_folders_of_dead_processes_are_removed(tmp_path):
    day = fmu.build.STALE_BUILD_AGE
    old = time.time() - 2 * day
    dead = dead_pid()
    folders = {
        "dead_old": tmp_path / f"flexsat-fmu-{dead}-abc",
        "dead_old_cache": tmp_path / f"flexsat-fmu-cache-{dead}-xyz",
        "old_style": tmp_path / "flexsat-fmu-obj-k2j3h4",
        "dead_recent": tmp_path / f"flexsat-fmu-{dead}-new",
        "alive_old": tmp_path / f"flexsat-fmu-{os.getppid()}-abc",
        "mine_old": tmp_path / f"flexsat-fmu-{os.getpid()}-abc",
        "unrelated": tmp_path / "flexsat-other-1-abc",
    }
    for name, folder in folders.items():
        (folder / "sources").mkdir(parents=True)
        if name != "dead_recent":
            os.utime(folder, (old, old))
    removed = fmu.build.remove_stale_build_dirs(tmp_path)
    assert sorted(removed) == sorted([folders["dead_old"], folders["dead_old_cache"],
                                      folders["old_style"]])
    assert all(folder.exists() == (folder not in removed) for folder in folders.values())


KILLED_EXPORT = """
import sys, signal
sys.path.insert(0, {root!r})
import control, numpy as np
from fmu import export
if {handler}:  # what the CLI does: SIGTERM becomes an exception
    signal.signal(signal.SIGTERM, lambda *args: sys.exit(143))
body = control.ss([[0, 1], [0, 0]], [[0], [0.1]], np.eye(2), 0, inputs=["torque"],
                  outputs=["theta", "omega"], states=["angle", "rate"])
export(body, {target!r}, compiler={cc!r})
"""


def kill_group(process):
    try:
        os.killpg(process.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass


def start_slow_export(tmp_path, handler):
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    cc = slow_compiler(tmp_path, delay=30.0)
    environment = {**os.environ, "TMPDIR": str(temporary),
                   "FLEXSAT_CACHE_DIR": str(tmp_path / "cache")}
    # a session of its own, so that the whole process group can be killed at once, as a
    # job control or service manager does
    process = subprocess.Popen([sys.executable, "-c", KILLED_EXPORT.format(
        root=str(ROOT), handler=handler, target=str(tmp_path / "out" / "body.fmu"), cc=str(cc))],
        env=environment, start_new_session=True)
    deadline = time.monotonic() + 60
    while not list(temporary.glob(f"flexsat-fmu-{process.pid}-*/objects/*.writing")):
        assert time.monotonic() < deadline and process.poll() is None
        time.sleep(0.05)
    return process, temporary


@pytest.mark.slow
def test_sigterm_as_exception_removes_the_build_folder(tmp_path):
    process, temporary = start_slow_export(tmp_path, handler=True)
    process.send_signal(signal.SIGTERM)
    try:
        assert process.wait(timeout=60) == 143
    finally:
        kill_group(process)  # the slow compiler's sleep, orphaned by the killed wrapper
    assert list(temporary.glob("flexsat-fmu-*")) == []
    assert not (tmp_path / "out" / "body.fmu").exists()


@pytest.mark.slow
def test_sigkill_leaves_a_folder_that_a_later_export_removes(tmp_path, monkeypatch):
    process, temporary = start_slow_export(tmp_path, handler=False)
    kill_group(process)
    process.wait(timeout=60)
    left = list(temporary.glob(f"flexsat-fmu-{process.pid}-*"))
    assert len(left) == 1
    old = time.time() - 2 * fmu.build.STALE_BUILD_AGE
    os.utime(left[0], (old, old))
    # the killed export held the cache lock and left a temporary object: a new export in
    # a new process neither waits for the lock nor trips over the leftovers
    monkeypatch.setenv("TMPDIR", str(temporary))
    monkeypatch.setenv("FLEXSAT_CACHE_DIR", str(tmp_path / "cache"))
    run = subprocess.run([sys.executable, "-c", textwrap.dedent(f"""
        import sys; sys.path.insert(0, {str(ROOT)!r})
        import control, numpy as np
        from fmu import export
        export(control.ss([[0.0]], [[1.0]], [[1.0]], 0, inputs=["u"], outputs=["y"], states=["x"]),
               {str(tmp_path / "later.fmu")!r})
    """)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert not left[0].exists()
    # (the slow compiler's own marker folders may stay; no temporary object file does)
    assert [p for p in (tmp_path / "cache").rglob("*.tmp-*") if p.is_file()] == []
