"""Every problem with a Dask scheduler given by address is one line within the stated timeout
(spacecraft/sweep/execute.py: connect), with no Dask traceback or leaked warning."""
import os
import socket
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from spacecraft.sweep import SweepError
from spacecraft.sweep.execute import connect

ROOT = Path(__file__).resolve().parents[3]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.mark.parametrize("address, match", [
    ("garbage://x", r"unknown scheme 'garbage'; Dask knows .*tcp"),
    ("tcp://127.0.0.1", r"expected tcp://host:port"),
    ("tcp://127.0.0.1:99999", r"expected tcp://host:port"),
])
def test_addresses_dask_cannot_use_are_refused(address, match):
    with pytest.raises(SweepError, match=match):
        connect(address)


def test_a_refused_connection_is_reported_without_waiting_for_the_timeout():
    """The port is probed first: a refusal is the answer (Dask's own client retried for its
    whole timeout); a timeout of an hour shows that nothing waits for it."""
    with pytest.raises(SweepError, match=r"cannot reach a Dask scheduler there \(Connection "
                                         r"refused\)"):
        within(600.0, connect, f"tcp://127.0.0.1:{free_port()}", timeout=3600.0)


def within(bound: float, function, *args, **kwargs):
    """Call ``function`` in a thread; fail if it has not returned after ``bound`` [s] (a
    hang, not a slow machine: the bound is 100 times the expected time), else its result or
    exception."""
    box = {}

    def call():
        try:
            box["value"] = function(*args, **kwargs)
        except BaseException as exc:
            box["error"] = exc

    thread = threading.Thread(target=call, daemon=True)
    thread.start()
    thread.join(bound)
    assert not thread.is_alive(), f"{function.__name__} hung"
    if "error" in box:
        raise box["error"]
    return box["value"]


@pytest.mark.slow
def test_an_address_that_accepts_but_never_answers_times_out():
    """A listener that accepts connections and says nothing (not a scheduler, or a hung one):
    refused after the timeout (1 s here), not hung (it once waited past 150 s)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    accepted = []

    def accept():
        while True:
            try:
                accepted.append(server.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    try:
        with pytest.raises(SweepError, match=r"no answer from a Dask scheduler within 1 s"):
            within(100.0, connect, f"tcp://127.0.0.1:{server.getsockname()[1]}", timeout=1.0)
    finally:
        server.close()
        for c in accepted:
            c.close()


@pytest.mark.slow
@pytest.mark.parametrize("address", ["garbage://x", "tcp://127.0.0.1:9"])
def test_the_command_says_one_line_and_leaves_nothing(tmp_path, address):
    """In a process of its own with every warning shown (-X dev): one line, exit 2, no
    traceback (Dask's Client.__del__ once printed one), no ResourceWarning, no folder."""
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT),
                                                       os.environ.get("PYTHONPATH", "")]))
    done = subprocess.run([sys.executable, "-X", "dev", "-m", "spacecraft.cli", "sweep",
                           "--scheduler", address, "--out", str(out), "--quiet"],
                          cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("flexsat: error: --scheduler"), done.stderr
    assert not out.exists()
