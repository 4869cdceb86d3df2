"""Assertions for users' own closed-loop comparison tests.

Example (in a user's pytest suite)::

    from controllers import assert_closed_loops_close, close_loop, pd

    def test_chain_tuned_pd_meets_spec_on_beam():
        controller = pd(chain_plant, natural_frequency=0.5, roll_off=3.0)
        assert_closed_loops_close(close_loop(beam_plant, controller),
                                  close_loop(chain_plant, controller),
                                  angle=0.2, duration=30.0, rtol=0.05,
                                  atol={"final_attitude_error": 1e-4})

On failure the AssertionError message is a table of every compared metric: both values, the
absolute and relative difference, the tolerance and PASS/FAIL.
"""
from __future__ import annotations

import math
from typing import Mapping, Sequence

import control

from .timeresp import METRIC_UNITS, metrics as _metrics, slew
from .compare import difference_columns, metric_table

__all__ = ["assert_closed_loops_close", "compare_metrics", "DEFAULT_RTOL", "DEFAULT_ATOL"]

#: Default relative tolerance: 5 %, the usual spread allowed on a closed-loop specification.
DEFAULT_RTOL = 0.05
#: Default absolute tolerance (0: purely relative).
DEFAULT_ATOL = 0.0


def _tolerance(value, name: str, what: str, default: float) -> float:
    if isinstance(value, Mapping):
        value = value.get(name, default)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"{what} must be a float or a mapping metric -> float; got "
                        f"{type(value).__name__}")
    value = float(value)
    if not (math.isfinite(value) and value >= 0):
        raise ValueError(f"{what} for {name!r} must be non-negative and finite; got {value}")
    return value


def _as_metrics(item, what: str, angle, duration, t_final, axis=None) -> dict[str, float]:
    if isinstance(item, Mapping):
        out = {}
        for key, value in item.items():
            if value is None or isinstance(value, bool):
                out[str(key)] = value  # a flag, or a metric of a diverged response
                continue
            if not isinstance(value, (int, float)):
                raise TypeError(f"{what}[{key!r}] must be a number, a bool or None; got "
                                f"{type(value).__name__}")
            out[str(key)] = float(value)
        return out
    if isinstance(item, control.StateSpace):
        if angle is None or duration is None:
            raise ValueError(f"{what} is a closed loop: give angle [rad] and duration [s] of the "
                             "slew from which its metrics are computed")
        return _metrics(slew(item, angle, duration, t_final=t_final, axis=axis))
    raise TypeError(f"{what} must be a metrics mapping or a closed loop (control.StateSpace); "
                    f"got {type(item).__name__}")


def compare_metrics(actual: Mapping[str, float], expected: Mapping[str, float], *,
                    rtol: float | Mapping[str, float] = DEFAULT_RTOL,
                    atol: float | Mapping[str, float] = DEFAULT_ATOL,
                    metrics: Sequence[str] | None = None) -> tuple[bool, str]:
    """Compare metric dicts; return (all within tolerance, readable table).

    A metric passes if |actual - expected| <= atol + rtol |expected| (as numpy.isclose), or both
    are the same infinity; a flag (``diverged``) or a None (a metric of a diverged response, a
    loop that did not settle) passes only if equal on both sides; a metric missing on either side
    fails. ``metrics`` defaults to every key of ``expected``.
    """
    for value, what in ((actual, "actual"), (expected, "expected")):
        if not isinstance(value, Mapping):
            raise TypeError(f"{what} must be a mapping metric -> value (controllers.metrics); "
                            f"got {type(value).__name__}")
    if metrics is not None and (isinstance(metrics, str) or not isinstance(metrics, Sequence)
                                or not all(isinstance(m, str) for m in metrics)):
        raise TypeError(f"metrics must be a sequence of metric names or None; got "
                        f"{type(metrics).__name__} {str(metrics)[:100]}")
    names = list(expected) if metrics is None else list(metrics)
    if not names:
        raise ValueError("metrics to compare must not be empty")
    rows, ok = [], True
    for name in names:
        r = _tolerance(rtol, name, "rtol", DEFAULT_RTOL)
        a_tol = _tolerance(atol, name, "atol", DEFAULT_ATOL)
        if name not in actual or name not in expected:
            rows.append((name, METRIC_UNITS.get(name, ""), actual.get(name, "missing"),
                         expected.get(name, "missing"), None, None, None, "FAIL"))
            ok = False
            continue
        a, e = actual[name], expected[name]
        if any(v is None or isinstance(v, bool) for v in (a, e)):
            passed = a == e and type(a) is type(e)
            ok &= passed
            rows.append((name, METRIC_UNITS.get(name, ""), a, e, None, None, None,
                         "PASS" if passed else "FAIL"))
            continue
        diff, rel = difference_columns(a, e)
        tol = a_tol + r * abs(e) if math.isfinite(e) else 0.0
        passed = diff <= tol
        ok &= passed
        rows.append((name, METRIC_UNITS.get(name, ""), a, e, diff, rel, tol,
                     "PASS" if passed else "FAIL"))
    table = metric_table(rows, ("metric", "unit", "actual", "expected", "abs diff", "rel diff",
                                "tolerance", "status"))
    return ok, table


def assert_closed_loops_close(actual, expected, *,
                              rtol: float | Mapping[str, float] = DEFAULT_RTOL,
                              atol: float | Mapping[str, float] = DEFAULT_ATOL,
                              metrics: Sequence[str] | None = None,
                              angle: float | None = None, duration: float | None = None,
                              t_final: float | None = None, axis=None) -> None:
    """Assert that two closed loops (or one and stored reference metrics) agree.

    Parameters
    ----------
    actual, expected : mapping of str to float, or control.StateSpace
        Metric dicts (from :func:`controllers.metrics`, possibly with margins, or loaded from a
        stored JSON reference) or closed loops from :func:`controllers.close_loop`, whose metrics
        are then computed from a slew of ``angle`` in ``duration``.
    rtol, atol : float or mapping metric -> float
        Tolerance |actual - expected| <= atol + rtol |expected| per metric (defaults 5 % and 0;
        a mapping gives per-metric values, the defaults for the others).
    metrics : sequence of str, optional
        Metrics to compare; default every metric of ``expected``.
    angle : float, rad, optional
    duration, t_final : float, s, optional
        Slew used for closed loops (see :func:`controllers.slew`).
    axis : {'x', 'y', 'z'} or sequence of 3 floats, optional
        Three-axis closed loops: the eigen-axis of that slew. Their metrics are per output
        signal (``peak_attitude_error_x``, ``peak_torque_y``, ``peak_<tip output>``, ... beside
        the vector-norm metrics, :func:`controllers.metrics`), all compared by default.

    Raises
    ------
    AssertionError
        With a table of every compared metric: unit, actual, expected, abs and relative
        difference, tolerance, PASS/FAIL.
    """
    __tracebackhide__ = True  # pytest: report the failure at the caller's line
    a = _as_metrics(actual, "actual", angle, duration, t_final, axis)
    e = _as_metrics(expected, "expected", angle, duration, t_final, axis)
    ok, table = compare_metrics(a, e, rtol=rtol, atol=atol, metrics=metrics)
    if not ok:
        n_fail = sum(line.rstrip().endswith("FAIL") for line in table.splitlines()[2:])
        n_all = len(table.splitlines()) - 2
        raise AssertionError(f"closed loops differ in {n_fail} of {n_all} metrics "
                             f"(|actual - expected| <= atol + rtol |expected|):\n{table}")
