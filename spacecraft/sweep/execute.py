"""Running a sweep's samples on Dask: batches, Parquet streaming, resume, progress.

Where the samples run
    * a Dask cluster you give: ``client=`` (a ``distributed.Client``) or ``scheduler=ADDRESS``
      (``--scheduler tcp://host:8786``); its workers need flexsat installed. An address is
      reached before any work or file (:func:`connect`): a wrong one, a refused connection or a
      service that does not answer as a Dask scheduler within :data:`SCHEDULER_TIMEOUT` is
      one line naming the problem. Its workers run as its nannies start them: with Dask's
      default ``MALLOC_TRIM_THRESHOLD_`` a sample spends more system time
      (:data:`LOCAL_CLUSTER_CONFIG`; start the workers with
      ``distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_`` set to null in their Dask
      configuration to avoid it);
    * otherwise a ``LocalCluster`` of worker processes, one single-threaded worker per core
      (``workers=`` / ``--workers`` to choose; Dask gives each worker process one BLAS thread);
    * a tiny sweep (one worker asked, or less than :data:`LOCAL_CLUSTER_SECONDS` of work) runs
      in this process with Dask's synchronous scheduler, where a cluster's start-up would cost
      more than it saves.

Batches
    Each Dask task evaluates a batch of samples (:func:`.evaluate.evaluate_batch`). The batch
    size is chosen from the time of one evaluation of the nominal scene, measured before the
    sweep, so that a task takes about :data:`TASK_SECONDS` (Dask's per-task cost, some tens of
    milliseconds of a worker's time, stays a small fraction of the work;
    ``benchmarks/bench_sweep.py`` measures it; each task is also one
    Parquet part, so 2 s keeps a 10,000-sample sweep to about a hundred files), and at most a
    quarter of the samples per worker (the load stays balanced). Besides, an idle LocalCluster
    takes a few per cent of a core (scheduler, client, heartbeats:
    :data:`LOCAL_CLUSTER_CONFIG`). At most
    ``2 x workers + 1`` tasks are in flight; a finished batch is written before another is sent.
    A worker lost mid-task (killed, out of memory) costs its batch's time: each task carries
    its context and is run again elsewhere (:meth:`Executor.run`).

Output folder (``out``)
    ``sweep.json``: the sweep's settings, the trimmed scene's fingerprint and the nominal
    controller (a resume must match them);
    ``samples/part-<first>-<last>.parquet``: one file per finished batch, columns ``sample``,
    the parameters' key paths (file units), then the metrics (:data:`.evaluate.METRICS`).
    Each part is written to a temporary name and renamed, so a killed sweep leaves only whole
    parts, and carries the SHA-256 of its content. Read them all with
    ``pyarrow.parquet.read_table(out / "samples")``. While a sweep writes the folder it holds
    its lock (:class:`SampleStore`): another sweep on the same folder is refused, naming it.

Resume
    ``resume=True`` (``--resume``) on a folder of the same sweep skips every sample of its
    parts and runs the rest: nothing finished is lost or repeated. Samples are decided by their
    index alone (:mod:`.parameters`), so the resumed results are those of an uninterrupted run.
    A damaged part (truncated, bit-flipped, empty) is set aside as ``<name>.damaged`` and its
    samples are run again; the report lists it.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import re
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from .evaluate import METRICS, Context, evaluate, evaluate_batch
from .parameters import SweepError, SweepSpec

__all__ = ["TASK_SECONDS", "LOCAL_CLUSTER_SECONDS", "SCHEDULER_TIMEOUT", "TASK_RETRIES",
           "LOCAL_CLUSTER_CONFIG", "Progress", "Executor", "open_executor", "connect",
           "check_workers", "SampleStore",
           "table_from_columns", "schema", "run_samples", "batch_size", "batch_bounds"]

#: Target duration of one Dask task [s].
TASK_SECONDS = 2.0
#: Below this much estimated work [s] a sweep runs in-process (synchronous scheduler).
LOCAL_CLUSTER_SECONDS = 10.0
#: Time [s] a scheduler given by address has to answer (:func:`connect`).
SCHEDULER_TIMEOUT = 10.0
#: Times Dask runs a batch again whose run failed (the task raised: its worker lost its
#: connection mid-task); a worker that dies under a task is the scheduler's matter (it
#: re-runs the task elsewhere, up to ``distributed.scheduler.allowed-failures`` times).
TASK_RETRIES = 2
#: Dask settings of the LocalCluster a sweep starts (not of a cluster given to it): no
#: statistical profiler in the workers (it samples the running task's stack every 10 ms), a
#: system monitor every 5 s instead of 0.5 s, the event loops' responsiveness check every 1 s
#: instead of 20 ms and the nannies' memory check every 1 s instead of 0.1 s. What the
#: cluster's processes do between tasks is CPU time taken from the samples on a machine with
#: as many workers as cores: an idle cluster of 2 workers takes about a fifth of the CPU it
#: takes with Dask's defaults (``benchmarks/bench_sweep.py --idle``). A worker's memory limit
#: is still enforced, within a second; a task that blocks an event loop is still reported.
#: And the workers' C library allocator as a process alone has it: Dask's nannies set
#: ``MALLOC_TRIM_THRESHOLD_ = 65536`` (memory returned to the system as soon as 64 KiB are
#: free at the top of the heap), which also fixes glibc's threshold for serving an allocation
#: by its own mapping at 128 KiB: every array of a sample's frequency grids is then mapped,
#: touched page by page and unmapped again, system time for memory that the workers of a
#: sweep, a few hundred MB, do not need back (``benchmarks/results/sweep_10000.md``). A value
#: in this process's environment is kept: the user's, or one that the nannies of an earlier
#: Dask cluster in this process left there (they write it into ``os.environ``).
LOCAL_CLUSTER_CONFIG = {"distributed.worker.profile.enabled": False,
                         "distributed.admin.system-monitor.interval": "5s",
                         "distributed.admin.tick.interval": "1s",
                         "distributed.worker.memory.monitor-interval": "1s",
                         "distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}
_PARTS = "samples"
_SETTINGS = "sweep.json"
#: Key of a part's Parquet metadata holding the SHA-256 of its content (:func:`_digest`).
DIGEST_KEY = b"flexsat.sha256"


# ---------------------------------------------------------------------------------------------
# tables
# ---------------------------------------------------------------------------------------------
def schema(context: Context):
    """The pyarrow schema of a sweep's table."""
    import pyarrow as pa

    kinds = {"float": pa.float64(), "int": pa.int64(), "bool": pa.bool_(), "str": pa.string()}
    fields = [pa.field("sample", pa.int64(), nullable=False)]
    fields += [pa.field(p.key, pa.float64(), nullable=False) for p in context.parameters]
    # each metric's unit and meaning in words travel with its column (the field's metadata)
    fields += [pa.field(name, kinds[METRICS[name][0]],
                        metadata={"unit": METRICS[name][1], "meaning": METRICS[name][2]})
               for name in context.columns()]
    return pa.schema(fields)


def table_from_columns(context: Context, columns: dict):
    """A pyarrow Table of evaluated samples (:func:`.evaluate.evaluate_batch`'s columns)."""
    import pyarrow as pa

    s = schema(context)
    return pa.table({f.name: pa.array(columns[f.name], type=f.type) for f in s}, schema=s)


# ---------------------------------------------------------------------------------------------
# progress
# ---------------------------------------------------------------------------------------------
class Progress:
    """A progress bar on stderr: samples done, failed, elapsed, remaining.

    On a terminal one line redrawn at most five times a second; otherwise (a log file) a line
    at every tenth of the sweep.
    """

    def __init__(self, total: int, done: int = 0, *, enabled: bool = True, stream=None,
                 label: str = "sweep"):
        self.total, self.done, self.failed = int(total), int(done), 0
        self.start_done = int(done)
        self.enabled = enabled and total > 0
        self.stream = sys.stderr if stream is None else stream
        self.label = label
        self.t0 = time.perf_counter()
        self._last = -math.inf
        self._tenth = -1
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())

    def update(self, n: int, failed: int = 0) -> None:
        """Count n more samples, ``failed`` of them failed."""
        self.done += n
        self.failed += failed
        if not self.enabled:
            return
        now = time.perf_counter()
        tenth = int(10 * self.done / self.total)
        if self.tty and (now - self._last > 0.2 or self.done >= self.total):
            self._last = now
            print("\r" + self.line(), end="", file=self.stream, flush=True)
        elif not self.tty and tenth != self._tenth:
            self._tenth = tenth
            print(self.line(), file=self.stream, flush=True)

    def line(self) -> str:
        """The current progress text."""
        elapsed = time.perf_counter() - self.t0
        new = self.done - self.start_done
        rate = new / elapsed if elapsed > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        width = 24
        filled = int(width * self.done / self.total) if self.total else width
        eta = f"{left:.0f} s left" if math.isfinite(left) else "..."
        failed = f", {self.failed} failed" if self.failed else ""
        return (f"{self.label} [{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total}"
                f"{failed}, {elapsed:.1f} s, {eta}")

    def close(self) -> None:
        """End the line."""
        if self.enabled and self.tty:
            print(file=self.stream, flush=True)


# ---------------------------------------------------------------------------------------------
# executors
# ---------------------------------------------------------------------------------------------
@dataclasses.dataclass
class Executor:
    """Where batches run: Dask's synchronous scheduler in this process, or a distributed client.

    Attributes
    ----------
    kind : str
        ``"synchronous"`` (in-process), ``"local-cluster"``, ``"scheduler"`` (an address) or
        ``"client"`` (a client given by the caller).
    client : distributed.Client or None
    n_workers : int
        Worker threads available (1 in-process).
    owned : list
        Objects to close (a LocalCluster and its client made here).
    """

    kind: str
    client: object = None
    n_workers: int = 1
    owned: list = dataclasses.field(default_factory=list)

    def describe(self) -> str:
        """Short text for reports: ``local-cluster, 2 workers``."""
        return f"{self.kind}, {self.n_workers} worker{'s' if self.n_workers != 1 else ''}"

    def run(self, context: Context, batches: list) -> Iterator[tuple[list, dict]]:
        """Evaluate batches ``[(indices, values), ...]``; yield ``(indices, columns)`` as each
        finishes (in-process: in order).

        On a cluster each task carries the context itself (a few kB), not a reference to data
        held by the workers, and may be run again (:data:`TASK_RETRIES`): a worker lost
        mid-task (killed, out of memory) costs its batch's time, and its nanny's new worker
        or the others take the batch again. A batch lost for good (every attempt's worker
        died) stops the sweep with a :class:`SweepError` saying so; the parts written stay
        for ``--resume``.
        """
        if self.client is None:
            import dask

            for indices, values in batches:
                task = dask.delayed(evaluate_batch, pure=False)(context, indices, values)
                (columns,) = dask.compute(task, scheduler="synchronous")
                yield indices, columns
            return
        from distributed import as_completed

        pending = list(batches)
        window = 2 * self.n_workers + 1
        futures = {}

        def submit():
            indices, values = pending.pop(0)
            future = self.client.submit(evaluate_batch, context, indices, values, pure=False,
                                        retries=TASK_RETRIES)
            futures[future.key] = indices
            return future

        running = as_completed([submit() for _ in range(min(window, len(pending)))],
                               loop=self.client.loop)
        for future in running:
            indices = futures.pop(future.key)
            try:
                columns = future.result()
            except Exception as exc:
                raise _lost(exc, indices) from None
            future.release()
            if pending:
                running.add(submit())
            yield indices, columns

    def evaluate_rows(self, context: Context, values: np.ndarray, size: int) -> list[dict]:
        """Evaluate parameter rows (no sample index), in order; used by the worst-case search."""
        values = np.asarray(values, dtype=float)
        n = values.shape[0]
        if self.client is None:
            return [evaluate(context, v) for v in values]
        size = max(1, min(size, math.ceil(n / self.n_workers)))
        batches = [(list(range(k, min(k + size, n))), values[k:k + size])
                   for k in range(0, n, size)]
        rows: list = [None] * n
        for indices, columns in self.run(context, batches):
            names = [c for c in columns if c != "sample"]
            for j, i in enumerate(indices):
                rows[i] = {name: columns[name][j] for name in names}
        return rows

    def close(self) -> None:
        """Close what this executor started (not a client given by the caller)."""
        import logging

        # a cluster whose workers were killed logs their loss while it closes: not news
        quiet = [logging.getLogger(name) for name in ("distributed", "tornado", "asyncio")]
        levels = [q.level for q in quiet]
        for q in quiet:
            q.setLevel(logging.CRITICAL)
        try:
            for thing in reversed(self.owned):
                try:
                    thing.close()
                except Exception:  # closing a cluster that is already gone
                    pass
        finally:
            for q, level in zip(quiet, levels):
                q.setLevel(level)
        self.owned.clear()


def _lost(exc: BaseException, indices) -> SweepError:
    """The error of a batch that did not come back from the cluster."""
    what = f"samples {indices[0]} to {indices[-1]}" if len(indices) > 1 else \
        f"sample {indices[0]}"
    name = type(exc).__name__
    if name == "KilledWorker":
        why = ("the workers running it died every time Dask tried it (killed, out of memory; "
               "distributed.scheduler.allowed-failures)")
    elif "Cancelled" in name or "cancelled" in str(exc).lower():
        why = "the cluster cancelled it (its workers or scheduler went away)"
    else:
        why = f"{name}: {' '.join(str(exc).split())[:200]}"
    return SweepError(f"the Dask cluster lost the batch of {what}: {why}; the finished "
                      "batches are kept: run again with --resume to finish the sweep")


def check_workers(workers) -> None:
    """Refuse a bad worker count (before anything is started or written)."""
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers < 1):
        raise SweepError(f"workers must be a positive integer (local worker processes; 1 "
                         f"runs in this process); got {workers!r}")


def connect(scheduler: str, timeout: float = SCHEDULER_TIMEOUT):
    """A client of the Dask scheduler at ``scheduler``, or a :class:`SweepError` within
    ``timeout`` [s] naming what is wrong.

    The address is checked first (a scheme Dask knows, a host and a port), then the scheduler
    is asked who it is through Dask's own protocol with a deadline: an address that refuses
    the connection fails at once, one that accepts but never answers (not a Dask scheduler, or
    a hung one) after ``timeout``, never later; only then is the client made.
    """
    import asyncio
    import socket

    from distributed.comm import parse_address
    from distributed.comm.registry import backends

    text = " ".join(str(scheduler).split())[:200]
    where = f"--scheduler {text}"
    try:
        scheme, location = parse_address(str(scheduler))
    except (ValueError, TypeError) as exc:
        raise SweepError(f"{where}: not a Dask scheduler address ({exc}); expected e.g. "
                         "tcp://host:8786") from None
    if scheme not in backends:
        raise SweepError(f"{where}: unknown scheme {scheme!r}; Dask knows "
                         f"{', '.join(sorted(backends))} (e.g. tcp://host:8786)")
    if scheme in ("tcp", "tls"):
        host, _, port = location.rpartition(":")
        host = host.strip("[]")
        if not host or not port.isdigit() or not 0 < int(port) < 65536:
            raise SweepError(f"{where}: expected {scheme}://host:port (e.g. tcp://host:8786); "
                             f"got {location!r}")
        try:
            with socket.create_connection((host, int(port)), timeout=timeout):
                pass
        except OSError as exc:
            reason = exc.strerror or type(exc).__name__
            raise SweepError(f"{where}: cannot reach a Dask scheduler there ({reason})"
                             ) from None

    async def identity():
        from distributed.comm import connect as dask_connect

        comm = await dask_connect(str(scheduler), timeout=timeout)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    try:
        reply = asyncio.run(asyncio.wait_for(identity(), timeout))
    except (TimeoutError, asyncio.TimeoutError):
        raise SweepError(f"{where}: no answer from a Dask scheduler within {timeout:g} s (the "
                         "address accepts connections but does not speak Dask's protocol, or "
                         "the scheduler is hung)") from None
    except (OSError, ValueError, TypeError, EOFError) as exc:
        raise SweepError(f"{where}: cannot reach a Dask scheduler there "
                         f"({type(exc).__name__}: {' '.join(str(exc).split())[:120]})"
                         ) from None
    kind = reply.get("type") if isinstance(reply, dict) else None
    if not isinstance(kind, str) or "Scheduler" not in kind:
        raise SweepError(f"{where}: the service there is not a Dask scheduler"
                         + (f" (it is a {kind})" if isinstance(kind, str) else ""))
    from distributed import Client

    try:
        return Client(str(scheduler), timeout=f"{timeout}s", set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SweepError(f"{where}: cannot reach a Dask scheduler there "
                         f"({type(exc).__name__}: {' '.join(str(exc).split())[:120]})"
                         ) from None


def open_executor(*, client=None, scheduler: str | None = None, workers: int | None = None,
                  estimated_seconds: float = math.inf) -> Executor:
    """Choose and start where the samples run (module docstring).

    Parameters
    ----------
    client : distributed.Client, optional
        A client of a running cluster (the caller keeps and closes it).
    scheduler : str, optional
        Address of a running Dask scheduler (``tcp://host:8786``), reached within
        :data:`SCHEDULER_TIMEOUT` (:func:`connect`).
    workers : int, optional
        Local worker processes (default: the machine's cores); 1 runs in-process.
    estimated_seconds : float
        Estimated work [s] (single core); below :data:`LOCAL_CLUSTER_SECONDS` the sweep runs
        in-process.

    Raises
    ------
    SweepError
        An unreachable scheduler, or a bad worker count.
    """
    if client is not None and scheduler is not None:
        raise SweepError("give a client or a scheduler address, not both")
    check_workers(workers)
    if client is not None:
        return Executor("client", client, max(1, sum(client.nthreads().values())))
    if scheduler is not None:
        client = connect(scheduler)
        n = sum(client.nthreads().values())
        if n == 0:
            client.close()
            raise SweepError(f"--scheduler {scheduler}: the cluster has no workers")
        return Executor("scheduler", client, n, [client])
    n = workers if workers is not None else (os.cpu_count() or 1)
    if n == 1 or estimated_seconds < LOCAL_CLUSTER_SECONDS:
        return Executor("synchronous")
    import logging

    import dask
    from distributed import Client, LocalCluster

    with dask.config.set(LOCAL_CLUSTER_CONFIG):
        # the scheduler's HTTP server (its dashboard and health routes; dashboard_address
        # None still binds the default 8787) on a free port: no "Port 8787 is already in use"
        # beside another cluster
        cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                               dashboard_address=":0", silence_logs=logging.ERROR)
        client = Client(cluster, set_as_default=False)
    return Executor("local-cluster", client, n, [cluster, client])


def batch_size(seconds_per_sample: float, n_todo: int, n_workers: int) -> int:
    """Samples per task: about :data:`TASK_SECONDS` of work, at most a quarter of a worker's
    share of the samples, at least one."""
    by_time = max(1, int(round(TASK_SECONDS / max(seconds_per_sample, 1e-6))))
    by_balance = max(1, math.ceil(n_todo / (4 * max(n_workers, 1))))
    return min(by_time, by_balance)


def batch_bounds(n_todo: int, size: int, n_workers: int, *, tail: bool = True) -> list[int]:
    """Where the batches of ``n_todo`` samples start and end: ``[0, b1, ..., n_todo]``.

    Batches of ``size`` samples, but (``tail``, several workers) the last ``n_workers x size``
    samples in batches of a quarter of that: the workers run their last tasks side by side,
    and a worker that finishes first waits for the others by at most a quarter task's time
    instead of a whole one's (the samples and their order are the same).
    """
    size = max(1, int(size))
    start = n_todo
    if tail and n_workers > 1 and size > 1:
        start = max(0, n_todo - n_workers * size)
    bounds = list(range(0, start, size))
    small = max(1, math.ceil(size / 4))
    bounds += list(range(start, n_todo, small)) if start < n_todo else []
    return bounds + [n_todo] if n_todo else [0]


# ---------------------------------------------------------------------------------------------
# the output folder
# ---------------------------------------------------------------------------------------------
class SampleStore:
    """The Parquet parts of a sweep's output folder (module docstring); a context manager that
    holds the folder's lock while the sweep writes it.

    Parameters
    ----------
    folder : path
    resume : bool
        Continue the sweep in ``folder`` (its settings must match: :meth:`start`).

    Raises
    ------
    SweepError, OutputError
        On entering: a non-empty folder without ``resume``, a folder without a sweep with
        ``resume``, a folder another flexsat process is writing (named).

    Notes
    -----
    Locking: entering takes the folder's lock (:class:`spacecraft.report.output.FolderLock`, the
    claim of run folders: one atomic ``mkdir`` with the owner's process recorded; the lock of
    a process that is gone is taken over), so a second sweep, or a ``--resume`` of it, started
    on a folder another sweep is writing stops at once naming that sweep's process. A fresh
    sweep that stops before its first part leaves no folder behind (nor files in an empty
    folder it was given), so the corrected run needs no ``--resume``.

    Integrity: a part carries the SHA-256 of its content in its metadata
    (:data:`DIGEST_KEY`) and Parquet's page checksums. On resume every part is read whole and
    checked (readable, the sweep's columns, the samples its name says, the digest); a damaged
    one (truncated, bit-flipped, empty) is renamed ``<name>.damaged`` and its samples are run
    again, and the report says so. Reading the finished sweep checks every part the same way
    and refuses a damaged one naming it.
    """

    def __init__(self, folder, *, resume: bool):
        self.folder = Path(folder)
        self.parts = self.folder / _PARTS
        self.resume = resume
        self.settings: dict | None = None
        self.schema = None
        self.recomputed: list[str] = []
        self._lock = None
        self._created: list[Path] = []
        self._written = False
        self._verified: dict[str, tuple] = {}

    # -- entering and leaving --------------------------------------------------------------
    def __enter__(self) -> "SampleStore":
        """Check the folder and lock it (before the sweep does any work)."""
        from ..report.output import LOCK, FolderLock

        if self.resume:
            if not (self.folder / _SETTINGS).is_file():
                raise SweepError(f"{self.folder}: --resume needs the folder of an earlier sweep "
                                 f"(no {_SETTINGS} there)")
        else:
            if self.folder.exists() and (not self.folder.is_dir() or any(self.folder.iterdir())):
                raise SweepError(f"{self.folder}: output folder exists and is not empty; use "
                                 "--resume to continue its sweep, or choose another --out")
            missing = [p for p in [self.folder, *self.folder.parents] if not p.exists()]
            try:
                self.folder.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise SweepError(f"{self.folder}: cannot create the output folder "
                                 f"({exc.strerror or type(exc).__name__}); give another --out"
                                 ) from None
            self._created = missing
        lock = FolderLock(self.folder, "flexsat sweep")
        try:
            lock.__enter__()     # refused: another process's lock, left alone
            self._lock = lock
            # another process may have written here between the check and the lock
            if not self.resume and any(p.name != LOCK for p in self.folder.iterdir()):
                raise SweepError(f"{self.folder}: output folder exists and is not empty; use "
                                 "--resume to continue its sweep, or choose another --out")
        except BaseException:
            self.__exit__(*sys.exc_info())
            raise
        return self

    def start(self, settings: dict, schema) -> None:
        """Record the sweep's settings (fresh) or compare them and check every part (resume).

        Parameters
        ----------
        settings : dict
            The sweep's settings (``sweep.json``).
        schema : pyarrow.Schema
            The columns every part must have.

        Raises
        ------
        SweepError
            ``resume`` on a folder of another sweep.
        """
        from fmu.files import write_text_atomically

        self.settings, self.schema = settings, schema
        record = self.folder / _SETTINGS
        if self.resume:
            try:
                old = json.loads(record.read_text())
            except (OSError, ValueError) as exc:
                raise SweepError(f"{record}: cannot read it ({exc})") from None
            differs = _differences(old, settings)
            if differs:
                raise SweepError(f"{self.folder}: --resume: this folder holds another sweep "
                                 f"(its {', '.join(differs[:3])} differ"
                                 f"{'s' if len(differs) == 1 else ''}); run the same scene and "
                                 "settings, or choose another --out")
            self.parts.mkdir(parents=True, exist_ok=True)
            for stale in self.parts.glob("*.tmp"):
                stale.unlink()
            for path in self._part_paths():
                try:
                    self._check(path)
                except SweepError:
                    path.rename(path.with_name(path.name + ".damaged"))
                    self.recomputed.append(path.name)
        else:
            write_text_atomically(record, json.dumps(settings, indent=2, allow_nan=False)
                                  + "\n")
            self.parts.mkdir(parents=True, exist_ok=True)

    def __exit__(self, kind, exc, tb) -> bool:
        # a fresh sweep that stops before its first part takes back what it made (only if
        # it held the lock: never another process's files)
        undo = exc is not None and self._lock is not None and not self.resume \
            and not self._written
        if undo:
            self._discard()
        if self._lock is not None:
            self._lock.__exit__(None, None, None)
            self._lock = None
        if undo:
            for path in self._created:   # the folders it made, the deepest first, if empty
                try:
                    path.rmdir()
                except OSError:
                    break
        return False

    def _discard(self) -> None:
        """Remove what a fresh sweep wrote before its first part."""
        (self.folder / _SETTINGS).unlink(missing_ok=True)
        try:
            self.parts.rmdir()
        except OSError:
            pass

    # -- parts -------------------------------------------------------------------------------
    def _part_paths(self) -> list[Path]:
        return sorted(self.parts.glob("part-*.parquet"))

    def _check(self, path: Path):
        """The table of a part, or a SweepError naming it and what is wrong."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        def damaged(why: str) -> SweepError:
            return SweepError(f"{path}: damaged Parquet part of the sweep ({why}); run the "
                              "sweep with --resume to compute its samples again")

        try:
            table = pq.read_table(path, page_checksum_verification=True)
        except (OSError, pa.ArrowException, ValueError) as exc:
            raise damaged(" ".join(str(exc).split())[:160] or type(exc).__name__) from None
        meta = dict(table.schema.metadata or {})
        stored = meta.pop(DIGEST_KEY, None)
        table = table.replace_schema_metadata(meta or None)
        if self.schema is not None and not table.schema.equals(self.schema):
            raise damaged("its columns are not this sweep's")
        if stored is None or stored.decode("ascii", "replace") != _digest(table):
            raise damaged("its content does not match its checksum")
        samples = table.column("sample").to_numpy()
        m = re.fullmatch(r"part-(\d+)-(\d+)\.parquet", path.name)
        if (not samples.size or m is None or samples.min() != int(m.group(1))
                or samples.max() != int(m.group(2))):
            raise damaged("its samples are not those its name says")
        return table

    def completed(self) -> np.ndarray:
        """Sample indices already in the folder (sorted); each part is checked whole once
        (then, unchanged, only its sample column is read)."""
        import pyarrow.parquet as pq

        done = []
        for path in self._part_paths():
            if self._verified.get(path.name) != _stamp(path):
                self._check(path)
                self._verified[path.name] = _stamp(path)
            done.append(pq.read_table(path, columns=["sample"]).column("sample").to_numpy())
        return np.sort(np.concatenate(done)) if done else np.zeros(0, dtype=np.int64)

    def write(self, table) -> Path:
        """Write one batch's table as a part (atomically, with its digest)."""
        import pyarrow.parquet as pq
        from fmu.files import write_atomically

        samples = table.column("sample").to_numpy()
        path = self.parts / f"part-{samples.min():09d}-{samples.max():09d}.parquet"
        meta = dict(table.schema.metadata or {})
        meta[DIGEST_KEY] = _digest(table).encode("ascii")
        stamped = table.replace_schema_metadata(meta)
        write_atomically(path, lambda handle: pq.write_table(stamped, handle,
                                                              write_page_checksum=True))
        self._verified[path.name] = _stamp(path)
        self._written = True
        return path

    def read(self):
        """Every sample of the folder as one table, sorted by sample (every part checked;
        a sample in two parts refused)."""
        import pyarrow as pa

        tables, seen = [], {}
        for path in self._part_paths():
            table = self._check(path)
            for i in table.column("sample").to_pylist():
                if i in seen:
                    raise SweepError(f"{path}: sample {i} is also in {seen[i]}: two sweeps "
                                     "wrote this folder; run the sweep again in a new folder")
                seen[i] = path.name
            tables.append(table)
        if not tables:
            return None
        table = pa.concat_tables(tables)
        return table.take(np.argsort(table.column("sample").to_numpy(), kind="stable"))


def _stamp(path: Path) -> tuple:
    """A part's size and modification time (a part rewritten since its check is checked
    again)."""
    info = path.stat()
    return info.st_size, info.st_mtime_ns


def _digest(table) -> str:
    """SHA-256 of a table's content: its column names, types and values (not its layout)."""
    import hashlib

    h = hashlib.sha256()
    for field, column in zip(table.schema, table.columns):
        h.update(json.dumps([field.name, str(field.type), column.to_pylist()],
                            allow_nan=True).encode())
    return h.hexdigest()


def _differences(old, new, prefix: str = "") -> list[str]:
    """Dotted keys whose values differ between two settings records."""
    if isinstance(old, dict) and isinstance(new, dict):
        out = []
        for k in sorted(set(old) | set(new), key=str):
            # when it started, and the name the scene was given by (the fingerprint of its
            # content is compared), may differ
            if k not in ("started", "scene"):
                out += _differences(old.get(k), new.get(k), f"{prefix}.{k}" if prefix else k)
        return out
    if isinstance(old, list) and isinstance(new, list) and len(old) == len(new):
        return [d for k, (a, b) in enumerate(zip(old, new))
                for d in _differences(a, b, f"{prefix}[{k}]")]
    return [] if old == new else [prefix]


# ---------------------------------------------------------------------------------------------
# the samples
# ---------------------------------------------------------------------------------------------
def run_samples(context: Context, spec: SweepSpec, executor: Executor, *,
                store: SampleStore | None = None, values: np.ndarray | None = None,
                seconds_per_sample: float = 0.03, progress: bool = True,
                batch: int | None = None) -> tuple:
    """Evaluate every sample of the plan not yet in the store.

    Parameters
    ----------
    context : Context
    spec : SweepSpec
    executor : Executor
    store : SampleStore, optional
        Stream each finished batch to it (and skip its samples); None: in memory only.
    values : ndarray (n_samples, d), optional
        Every sample's values (default: ``spec.values()``).
    seconds_per_sample : float
        Measured cost of one evaluation [s] (for the batch size).
    progress : bool
        Progress bar on stderr.
    batch : int, optional
        Samples per task (default :func:`batch_size`, the last round of tasks on a cluster
        in smaller batches: :func:`batch_bounds`).

    Returns
    -------
    table : pyarrow.Table
        Every sample of the plan, sorted by index.
    info : dict
        ``evaluated`` (samples run now), ``skipped`` (found in the store), ``batch``,
        ``tasks``, ``seconds`` (wall time).
    """
    import pyarrow as pa

    n = spec.n_samples
    done = store.completed() if store is not None else np.zeros(0, dtype=np.int64)
    todo = np.setdiff1d(np.arange(n, dtype=np.int64), done)
    size = batch or batch_size(seconds_per_sample, todo.size, executor.n_workers)
    values = spec.values() if values is None else np.asarray(values, dtype=float)
    values = values[todo]
    bounds = batch_bounds(todo.size, size, executor.n_workers,
                          tail=batch is None and executor.client is not None)
    batches = [(todo[a:b].tolist(), values[a:b]) for a, b in zip(bounds[:-1], bounds[1:])]
    bar = Progress(n, done.size, enabled=progress)
    tables = []
    t0 = time.perf_counter()
    try:
        for _, columns in executor.run(context, batches):
            table = table_from_columns(context, columns)
            if store is not None:
                store.write(table)
            else:
                tables.append(table)
            bar.update(table.num_rows, sum(1 for e in columns["error"] if e))
    finally:
        bar.close()
    seconds = time.perf_counter() - t0
    if store is not None:
        table = store.read()
    else:
        table = pa.concat_tables(tables) if tables else schema(context).empty_table()
        table = table.take(np.argsort(table.column("sample").to_numpy(), kind="stable"))
    info = {"evaluated": int(todo.size), "skipped": int(done.size), "batch": int(size),
            "tasks": len(batches), "seconds": seconds}
    return table, info
