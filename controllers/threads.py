"""BLAS threads sized to the problem: small problems single-threaded, whatever the caller set.

OpenBLAS starts as many threads as there are cores unless ``OPENBLAS_NUM_THREADS`` (or
``OMP_NUM_THREADS``) says otherwise.  For the matrices of a design loop (tens to a few hundred
states) the threads cost more than they save: waking and synchronising them for each small
product or factorisation dominates, and on a machine busy with other work a threaded call
waits for a core (measured in ``benchmarks/issue10.py``: a design-loop evaluation 6.8x slower
with two default threads than with one under load).  So that flexsat's speed and results do
not depend on the caller's settings, its entry points run problems below
:data:`SINGLE_THREAD_BELOW` states with one BLAS thread (threadpoolctl [1]_), and leave larger
ones to the caller's setting.

Use :func:`blas_threads_for` around an entry point's work, or the decorator
:func:`limits_blas_threads`.  Limits nest: inside a limited region, further limits cost
nothing (no call into the BLAS library), so library code may limit at every entry point.

References
----------
.. [1] threadpoolctl: Python helpers to limit the number of threads used in native libraries
   that handle their own internal threadpool (BLAS and OpenMP implementations),
   https://github.com/joblib/threadpoolctl.
"""

from __future__ import annotations

import contextlib
import functools
import threading
from typing import Callable, Iterator

__all__ = ["SINGLE_THREAD_BELOW", "blas_threads_for", "limits_blas_threads", "one_blas_thread",
           "total_states"]

#: Problems with fewer states than this run with one BLAS thread: every design loop up to
#: 400 bending modes (802 plant states and the controller's), whose results then never
#: depend on the caller's thread count.  Measured on a 2-core x86-64 (benchmarks/issue10.py,
#: "threads", "analysis"): up to ~400 states one thread is as fast or faster for every stage
#: of a design loop on a quiet machine; at 802 states on a busy one (load 7) two default
#: threads made LQR + Kalman 37 s of CPU and 58 s of wall time against 7.5 s and 17 s with
#: one, margins 4.0 s and 8.4 s against 0.63 s and 1.5 s (their O(n) work per frequency
#: gains nothing from threads).  Only dense products and factorisations of order well above
#: 1000 can gain from a second thread; they keep the caller's setting.
SINGLE_THREAD_BELOW = 1024

_lock = threading.Lock()
_depth = 0                     # nesting depth of active single-thread regions
_limiter = None                # the active threadpoolctl limiter (outermost region)
_controller = None             # threadpoolctl.ThreadpoolController, created on first use


def _get_controller():
    """threadpoolctl's controller (it inspects the loaded libraries once: ~ms), or False
    when threadpoolctl is not installed."""
    global _controller
    if _controller is None:
        try:
            from threadpoolctl import ThreadpoolController
        except ImportError:
            _controller = False
        else:
            _controller = ThreadpoolController()
    return _controller


@contextlib.contextmanager
def blas_threads_for(n_states: int) -> Iterator[None]:
    """Run the body with one BLAS thread if ``n_states < SINGLE_THREAD_BELOW``.

    Parameters
    ----------
    n_states : int
        Size of the problem (states of the system, order of the matrices).

    Notes
    -----
    Above the threshold the caller's setting applies, and results may then differ in the
    last bits with the number of threads (a threaded matrix product blocks its sums
    differently); below it they never do.  See :func:`one_blas_thread`.
    """
    if n_states >= SINGLE_THREAD_BELOW:
        yield
        return
    with one_blas_thread():
        yield


@contextlib.contextmanager
def one_blas_thread() -> Iterator[None]:
    """Run the body with one BLAS thread, whatever the caller's setting.

    Notes
    -----
    BLAS thread counts are process-wide: while one Python thread is inside a limited
    region, BLAS calls of other Python threads also run single-threaded.  The limit is
    restored when the outermost region exits; inner regions cost no call into BLAS.
    """
    global _depth, _limiter
    with _lock:
        if _depth == 0:
            controller = _get_controller()
            if controller:
                _limiter = controller.limit(limits=1, user_api="blas")
        _depth += 1
    try:
        yield
    finally:
        with _lock:
            _depth -= 1
            if _depth == 0 and _limiter is not None:
                _limiter.restore_original_limits()
                _limiter = None


def limits_blas_threads(size: Callable[..., int]) -> Callable:
    """Decorator: run the function inside ``blas_threads_for(size(*args, **kwargs))``.

    Parameters
    ----------
    size : callable
        Called with the function's arguments; returns the problem size (states).

    Examples
    --------
    >>> @limits_blas_threads(total_states)                       # doctest: +SKIP
    ... def margins(plant, controller): ...
    """
    def decorate(function: Callable) -> Callable:
        @functools.wraps(function)
        def wrapper(*args, **kwargs):
            try:
                n = int(size(*args, **kwargs))
            except Exception:          # a bad argument: let the function itself report it
                n = 0
            with blas_threads_for(n):
                return function(*args, **kwargs)
        return wrapper
    return decorate


def total_states(*args, **kwargs) -> int:
    """The states of every system among the arguments (objects with ``nstates``): the
    problem size of an entry point such as ``margins(plant, controller)``."""
    return sum(int(getattr(a, "nstates", 0) or 0) for a in (*args, *kwargs.values()))
