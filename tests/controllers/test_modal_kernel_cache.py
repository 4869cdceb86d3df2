"""Where the compiled modal loop is cached (controllers._modal_kernel).

An installed flexsat may sit in a read-only site-packages and run for a user whose home is
not writable: numba then finds no cache location and refuses ``cache=True`` at decoration.
The loop must still be compiled, cached in a private temporary directory, and loaded from
there by the next process (the one-time compile costs seconds, the load a fraction of one).
"""

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

numba = pytest.importorskip("numba")

ROOT = Path(__file__).resolve().parents[2]

# numba's locators other than the user-provided one (NUMBA_CACHE_DIR) are switched off, as
# if site-packages and the home directory were read-only; NUMBA_CACHE_DIR stays unset.
CHILD = r"""
import json, warnings
warnings.simplefilter("error")          # the chunked fallback's warning would fail here
import numpy as np, control
from controllers.simulate import Simulator
from controllers import _modal_kernel
system = control.ss([[0.0, 1.0], [-4.0, -0.1]], [[0.0], [1.0]], [[1.0, 0.0]], 0.0)
T = np.arange(200_000) * 0.01
simulator = Simulator(system, 0.01)
y = simulator.outputs(T, np.ones((1, T.size)))
stats = _modal_kernel.modal_recursion.stats
print(json.dumps({"method": simulator.method_for(T.size), "cache_path": stats.cache_path,
                  "hits": sum(stats.cache_hits.values()),
                  "misses": sum(stats.cache_misses.values()),
                  "finite": bool(np.isfinite(y).all())}))
"""


def run_child(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(NUMBA_CACHE_LOCATOR_CLASSES="UserProvidedCacheLocator", TMPDIR=str(tmp_path),
               PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", CHILD], cwd=tmp_path, env=env, check=True,
                         capture_output=True, text=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.slow
def test_no_writable_cache_location_caches_in_a_private_temporary_directory(tmp_path):
    """First process: compiled (a cache miss) into <TMPDIR>/flexsat-numba-<uid>, the modal
    method used, no warning; second process: loaded from there (a hit)."""
    first = run_child(tmp_path)
    assert first["method"] == "modal" and first["finite"]
    assert Path(first["cache_path"]).is_relative_to(tmp_path)
    assert first["misses"] == 1 and first["hits"] == 0
    second = run_child(tmp_path)
    assert second["cache_path"] == first["cache_path"]
    assert second["hits"] == 1 and second["misses"] == 0


@pytest.mark.skipif(not hasattr(os, "getuid"), reason="ownership checks need POSIX uids")
def test_private_directory_refuses_one_that_others_can_write(tmp_path, monkeypatch):
    """Compiled code loaded from a directory another user can write would run as ours: a
    group- or world-writable directory at the private path is not used."""
    from controllers import _modal_kernel

    monkeypatch.setattr(_modal_kernel.tempfile, "tempdir", str(tmp_path))
    path = tmp_path / f"flexsat-numba-{os.getuid()}"
    assert _modal_kernel._private_directory() == str(path)
    assert (path.stat().st_mode & 0o777) == 0o700
    path.chmod(0o777)
    assert _modal_kernel._private_directory() is None
