"""One sweep sample: the runner's design loop reduced to numbers (spacecraft/sweep/evaluate.py)."""
import json
import math

import numpy as np
import pytest

import controllers

from spacecraft.design.loop import run
from spacecraft.scene.read import load_scene
from spacecraft.sweep.evaluate import METRICS, evaluate, evaluate_batch, prepare
from spacecraft.sweep.parameters import apply_values, read_sweep

from scenes import default_sweep_scene

PARAMETERS = {"hub.inertia": {"distribution": "uniform", "low": 40.0, "high": 60.0},
              "appendages.rod.beam.damping_ratio": {"distribution": "loguniform",
                                                    "low": 0.001, "high": 0.02}}


def frequency_fit_scene():
    """The default sweep scene with the paper's fit."""
    raw = default_sweep_scene()
    raw["appendages"][0]["fit"]["match"] = "frequencies"
    return raw


def context_of(raw, **settings):
    spec = read_sweep({"parameters": PARAMETERS, **settings}, raw, "test")
    return prepare(raw, spec, "test"), spec


@pytest.mark.slow
def test_a_sample_is_the_runners_design_loop():
    """A sample is one evaluation of the design loop: its truth-model margins, slew metrics
    and exact-beam verdict equal those of flexsat run on the same one-loop scene (flexsat's
    poles-and-zeros fit: the sample's chain is the run's, from the same memoised
    dimensionless fit); the exact-beam margins, found on the exact loop function, do not
    depend on the grid (a grid four times as dense gives them to 1e-9)."""
    raw = default_sweep_scene()
    context, spec = context_of(raw, design="per-sample")
    values = [45.0, 0.003]
    row = evaluate(context, values)
    assert row["error"] == "" and row["warning"] == ""
    sample_scene = load_scene(apply_values(context.base, context.parameters, values))
    result = run(sample_scene)
    loop = result.data["closed_loops"][0]
    truth, exact = loop["verdict"], loop["exact_verdict"]
    # the sweep withholds the time metrics as the report does (None where the report has
    # None); the others are those of the run's own response to the whole manoeuvre
    key = (loop["design"], loop["controller"], "truth")
    with np.errstate(all="ignore"):
        metrics = controllers.metrics(result.responses[key])
    assert row["truth_stable"] == truth["stable"]
    # same models and controller: margins refined to 1e-12 relative in frequency (the sweep's
    # signed by the verdict); the simulations agree to round-off
    sign = 1.0 if truth["stable"] else -1.0
    for name in ("gain_margin", "phase_margin", "modulus_margin"):
        assert row[f"truth_{name}"] == pytest.approx(sign * abs(truth[name]), rel=1e-9), name
    reported = loop["metrics"]["truth"]
    for name in ("overshoot", "settling_time", "peak_tip_deflection", "peak_torque",
                 "peak_attitude_error"):
        if reported[name] is None or not row["stable"]:
            assert row[name] is None, name
        else:
            assert row[name] == pytest.approx(metrics[name], rel=1e-9, abs=1e-15), name
    assert row["exact_stable"] == exact["stable"]
    sign = 1.0 if exact["stable"] else -1.0
    for name in ("modulus_margin", "phase_margin", "gain_margin"):
        assert row[f"exact_{name}"] == pytest.approx(sign * abs(exact[name]), rel=1e-9), name
    # a grid four times as dense: the same verdict, the same margins (found on the exact L)
    from spacecraft import DesignLoop
    from spacecraft.design.verdicts import exact_loop_verdict
    from spacecraft.sweep.evaluate import SAMPLE_GRID
    from spacecraft.sweep.worst import DENSE_GRID

    dense_loop = DesignLoop(sample_scene)
    frd = dense_loop.exact_reference_frd(**DENSE_GRID)
    assert frd.omega.size > 3 * dense_loop.exact_grid(**SAMPLE_GRID).size
    K = result.designs[loop["design"]]["controllers"][loop["controller"]]
    dense = exact_loop_verdict(dense_loop.exact_spacecraft(), K, frd.omega,
                               theta=np.asarray(frd.frdata)[0, 0])
    assert dense.stable == row["exact_stable"]
    for name in ("modulus_margin", "phase_margin", "gain_margin"):
        assert getattr(dense.margins, name) == pytest.approx(exact[name], rel=1e-9), name
    assert row["n_modes"] == result.data["fidelity"]["n_modes"]


def test_nominal_and_per_sample_designs_coincide_at_the_nominal_point():
    raw = frequency_fit_scene()
    per_sample, spec = context_of(raw, design="per-sample")
    nominal, _ = context_of(raw, design="nominal")
    a = evaluate(per_sample, spec.nominal)
    b = evaluate(nominal, spec.nominal)
    for name in nominal.columns():
        if name != "seconds":
            assert a[name] == b[name], name
    # the per-sample row records its controller: at the nominal point the nominal one
    assert "controller" in per_sample.columns() and "controller" not in nominal.columns()
    record = json.loads(a["controller"])
    assert record == {k: nominal.nominal_record[k] for k in ("kind", "A", "B", "C", "D")}
    # away from it they differ: the held controller does not follow the hub
    c = evaluate(per_sample, [58.0, 0.004])
    d = evaluate(nominal, [58.0, 0.004])
    assert c["truth_modulus_margin"] != d["truth_modulus_margin"]


def test_a_failing_sample_is_recorded_and_the_batch_goes_on():
    raw = frequency_fit_scene()
    context, spec = context_of(raw)
    # an inertia of zero is refused by the scene reader: that sample fails, its neighbours not
    columns = evaluate_batch(context, [0, 1, 2], np.array([[45.0, 0.003], [0.0, 0.003],
                                                            [55.0, 0.003]]))
    assert columns["sample"] == [0, 1, 2]
    assert columns["error"][0] == "" and columns["error"][2] == ""
    assert "hub.inertia" in columns["error"][1] and "must be positive" in columns["error"][1]
    assert columns["stable"][1] is None and math.isnan(columns["exact_modulus_margin"][1])
    assert columns["truth_n_unstable_poles"][1] == -1
    assert isinstance(columns["stable"][0], bool) and isinstance(columns["stable"][2], bool)
    assert set(columns) == {"sample", *spec.keys, *context.columns()}
    assert set(context.columns()) <= set(METRICS)


def test_exact_frequencies_of_a_sample_that_once_failed():
    """A sample of the default sweep's box (hub inertia 45.66 kg m^2, E = 2.0017e11 Pa) on
    which the exact coupled frequencies once raised "Singular matrix" (the Wittrick-Williams
    count; not reproducible on main since). Against a 40-mode Craig-Bampton truncation
    (converged: 20 modes are within 1.5e-9, 40 and 80 within 1e-10 of each other): 1e-8."""
    from appendages import Beam
    from spacecraft import Hub, Mount, Spacecraft

    beam = Beam.circular_rod(10.0, 0.01, 7800.0, 200168544101.7793)
    hub = Hub(100.0, 45.65950110682256)
    exact = Spacecraft(hub, [Mount(beam, (0.5, 0.0), 0.0)]).natural_frequencies(3, exact=True)
    truncated = Spacecraft(hub, [Mount(beam.truncated(40), (0.5, 0.0), 0.0)])
    np.testing.assert_allclose(exact, truncated.natural_frequencies(3), rtol=1e-8)


def test_exact_margins_by_the_modal_sum_of_the_damped_rod_are_the_closed_forms(monkeypatch):
    """The exact-beam verdict of a sample through the damped rod's modal sum (the beam's
    dynamic stiffness as the sweeps evaluate it) equals the verdict through the closed form
    with damping corrections (appendages.damping), sample by sample over the shipped sweep's
    box: the two D(s) agree to 1e-12 of the matrix (tests/appendages/
    test_cantilever_damping.py), the margins, refined on the exact loop function to 1e-12 in
    frequency, to rtol 1e-9 (measured: 1e-13 on 100 samples); every other column is the
    same number (the truth model does not use the exact beam)."""
    from appendages.beam import Beam
    import spacecraft.sweep as S

    raw, spec, source = S.load_sweep(None, samples=6)
    context = prepare(raw, spec, source)
    values = spec.values()
    modal = [evaluate(context, v) for v in values]
    monkeypatch.setattr(Beam, "_cantilever_modal_stiffness", lambda self, s: None)
    closed = [evaluate(context, v) for v in values]
    for a, b in zip(modal, closed):
        assert a["error"] == b["error"] == ""
        for name in context.columns():
            if name in ("seconds", "warning"):
                continue
            if name.startswith("exact_") and isinstance(a[name], float):
                assert a[name] == pytest.approx(b[name], rel=1e-9, abs=0), name
            else:
                assert a[name] == b[name] or (isinstance(a[name], float)
                                              and math.isnan(a[name]) and math.isnan(b[name])), name
