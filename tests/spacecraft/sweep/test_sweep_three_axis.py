"""Sweeps of three-axis scenes: inertia-tensor entries (kept symmetric, a tensor that is no rigid
body's a failed sample), mount angles and section properties swept by key path; each sample the
one design loop's multiloop verdict, equal to the design loop's run of the scene with the
sampled values; the worst case's scene reruns the very controller the sweep judged; the same
on a Dask LocalCluster; the shipped three-axis sweep scene."""
import json
import math
import tomllib

import numpy as np
import pytest

from spacecraft.design.loop import DesignLoop, run
from spacecraft.scene.read import SceneError, load_scene
from spacecraft.sweep import SweepError, run_sweep, sweep_scene_path
from spacecraft.sweep.evaluate import (THREE_AXIS_METRICS, evaluate, prepare, signed_margin,
                                       summary_margins)
from spacecraft.sweep.parameters import apply_values, mirror_path, read_sweep
from spacecraft.sweep.report import metric_label
from spacecraft.sweep.worst import worst_scene
from scenes import rod_scene

PARAMETERS = {
    "hub.inertia[0][0]": {"distribution": "uniform", "low": 55.0, "high": 65.0},
    "hub.inertia[0][1]": {"distribution": "uniform", "low": -4.0, "high": 4.0},
    "appendages.rod.orientation[1]": {"distribution": "uniform", "low": -10.0, "high": 10.0},
    "appendages.rod.beam.diameter": {"distribution": "normal", "mean": 0.01, "std": 0.0005},
}
MARGINS = ("gain_margin", "phase_margin", "modulus_margin")


def scene():
    """The small three-axis rod scene (tests/support/scenes.py): a steel rod on a hub with a
    full inertia tensor, PD tuned on the fitted 3-D chain, two modes a beam, a short slew about
    z; every loop judged on W6 too."""
    return rod_scene(three_axis=True, outputs={"exact_reference": True})


# -- key paths -----------------------------------------------------------------------------------
def test_an_off_diagonal_inertia_entry_moves_both_and_keeps_the_tensor_symmetric():
    raw = scene()
    spec = read_sweep({"parameters": {"hub.inertia[0][1]": PARAMETERS["hub.inertia[0][1]"]},
                       "samples": 3}, raw, "test")
    (p,) = spec.parameters
    assert p.path == ("hub", "inertia", 0, 1)
    assert mirror_path(p.path, raw) == ("hub", "inertia", 1, 0)
    out = apply_values(raw, spec.parameters, [-3.5])
    J = np.array(out["hub"]["inertia"])
    assert J[0, 1] == J[1, 0] == -3.5
    assert np.array_equal(J, J.T)
    assert raw["hub"]["inertia"][1][0] == 2.0    # the scene itself untouched
    # a diagonal entry, a planar inertia and a mount position have no partner
    assert mirror_path(("hub", "inertia", 1, 1), raw) is None
    assert mirror_path(("appendages", 0, "position", 1), raw) is None
    assert mirror_path(("hub", "inertia"), {"hub": {"inertia": 50.0}}) is None


def test_both_entries_of_one_product_of_inertia_are_refused_by_name():
    with pytest.raises(SweepError, match=r"'hub\.inertia\[0\]\[1\]' and 'hub\.inertia\[1\]\[0\]'"
                                         r": the inertia tensor is symmetric"):
        read_sweep({"parameters": {"hub.inertia[0][1]": PARAMETERS["hub.inertia[0][1]"],
                                   "hub.inertia[1][0]": PARAMETERS["hub.inertia[0][1]"]}},
                   scene(), "test")


@pytest.mark.parametrize("tensor, match", [
    # principal moments 10, 10, 30: 10 + 10 < 30, no rigid body has them
    ([[10.0, 0.0, 0.0], [0.0, 10.0, 0.0], [0.0, 0.0, 30.0]], r"hub\.inertia: must be the "
     r"inertia of a body .*triangle inequality.*30 > 10 \+ 10"),
    ([[10.0, 20.0, 0.0], [20.0, 10.0, 0.0], [0.0, 0.0, 30.0]], r"hub\.inertia.*positive"),
])
def test_an_inertia_tensor_that_is_no_rigid_bodys_is_refused_by_name(tensor, match):
    raw = scene()
    raw["hub"]["inertia"] = tensor
    with pytest.raises(SceneError, match=match):
        load_scene(raw)


def test_a_flat_body_is_the_limit_of_the_triangle_inequality():
    """A thin plate in the xy plane: J_zz = J_xx + J_yy exactly (rotated off its principal
    axes, so the eigenvalues carry round-off): accepted."""
    c, s = math.cos(0.3), math.sin(0.3)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.array(
        [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    J = R @ np.diag([30.0, 50.0, 80.0]) @ R.T
    raw = scene()
    raw["hub"]["inertia"] = (0.5 * (J + J.T)).tolist()
    assert load_scene(raw).three_axis


def test_three_axis_columns_are_named_in_words():
    assert metric_label("exact_modulus_margin_x") == "modulus margin about x, exact beam (signed)"
    assert metric_label("truth_disk_phase_margin") == \
        "disk phase margin, truth model (signed) [deg]"
    assert metric_label("truth_modulus_margin", three_axis=True) == \
        "modulus margin, least of the axes and I + L, truth model (signed)"
    assert metric_label("peak_torque_y") == "peak torque about y [N*m]"
    assert metric_label("pd_kd_z") == "PD derivative gain about z [N*m*s/rad]"
    assert all(unit and meaning for _, unit, meaning in THREE_AXIS_METRICS.values())


def test_summary_margins_are_never_above_any_loop():
    m = {"gain_margin_x": 12.0, "gain_margin_y": math.inf, "gain_margin_z": 8.0,
         "phase_margin_x": 60.0, "phase_margin_y": 45.0, "phase_margin_z": 70.0,
         "modulus_margin_x": 0.9, "modulus_margin_y": 0.8, "modulus_margin_z": 0.95,
         "disk_margin": 1.1, "disk_gain_margin": 10.0, "disk_phase_margin": 55.0,
         "min_singular_value": 0.7}
    out = summary_margins(m)
    assert (out["gain_margin"], out["phase_margin"], out["modulus_margin"]) == (8.0, 45.0, 0.7)
    m["min_singular_value"] = 0.85
    assert summary_margins(m)["modulus_margin"] == 0.8
    assert summary_margins({"gain_margin": 6.0, "phase_margin": 40.0,
                            "modulus_margin": 0.5}) == {"gain_margin": 6.0,
                                                        "phase_margin": 40.0,
                                                        "modulus_margin": 0.5}


# -- samples -------------------------------------------------------------------------------------
def loop_margins(raw, time_responses=False):
    """The design loop's own run of a sample's scene: the PD tuned on its chain, its verdict
    on the truth model and on the exact beams, margins signed as the sweep signs them (and the
    slew's status and metrics on the truth model)."""
    result = run(load_scene(raw), time_responses=time_responses)
    row = result.data["closed_loops"][0]
    out = {}
    if time_responses:
        out["status"] = row["status"]["truth"]["status"]
        out.update(row["metrics"]["truth"])
    for prefix, verdict in (("truth", row["verdict"]), ("exact", row["exact_verdict"])):
        stable = verdict["stable"]
        out[f"{prefix}_stable"] = stable
        for k, v in summary_margins(verdict).items():
            out[f"{prefix}_{k}"] = signed_margin(v, stable)
    return out


@pytest.mark.slow
def test_each_sample_is_the_design_loops_run_of_the_sampled_scene():
    """Per-sample design, in this process: each sample's multiloop margins (every axis' loop
    at a time, the disk margin, I + L; truth model and exact beam) equal those of
    spacecraft.run on the sweep's scene with the sampled numbers put in. The same models and
    the same controller (bit for bit), so the truth model's margins agree to round-off
    (1e-9 relative: the margins are refined to 1e-12 in frequency); the exact beam's margins
    are found on the exact loop function from brackets of two different grids (the sample's
    coarser one), so they agree to the refinement's tolerance, 1e-6 relative."""
    result = run_sweep(scene(), parameters=PARAMETERS, samples=3, seed=4, design="per-sample",
                       worst_case=False, workers=1, progress=False)
    table = result.table.to_pydict()
    assert result.summary["samples"]["failed"] == 0
    assert result.summary["loop"]["three_axis"] is True
    keys = list(PARAMETERS)
    context = result.context
    for i in range(3):
        values = [table[k][i] for k in keys]
        raw = apply_values(context.base, context.parameters, values)
        assert raw["hub"]["inertia"][1][0] == raw["hub"]["inertia"][0][1] == values[1]
        ref = loop_margins(raw, time_responses=True)
        for prefix, rtol in (("truth", 1e-9), ("exact", 1e-6)):
            assert table[f"{prefix}_stable"][i] is ref[f"{prefix}_stable"] is True
            names = [f"{prefix}_{k}" for k in MARGINS] + [
                k for k in THREE_AXIS_METRICS if k.startswith(prefix + "_")]
            for name in names:
                assert table[name][i] == pytest.approx(ref[name], rel=rtol, abs=1e-12), \
                    (i, name)
        # the slew (no disturbance: the sweep's whole manoeuvre is the run's slew)
        assert table["status"][i] == ref["status"]
        for name in ("overshoot", "peak_torque", "peak_attitude_error", "final_attitude_error",
                     *(f"{k}_{a}" for k in ("peak_torque", "peak_attitude_error",
                                           "final_attitude_error") for a in "xyz")):
            assert table[name][i] == pytest.approx(ref[name], rel=1e-9, abs=1e-15), (i, name)
        assert all(table[f"peak_torque_{a}"][i] > 0 for a in "xyz")


@pytest.mark.slow
def test_a_tensor_that_is_no_rigid_bodys_is_a_failed_sample_counted_apart():
    """A grid over two principal moments whose low ends are each valid but break the triangle
    inequality together (J_xx + J_yy >= J_zz: 42 + 42 < 90, while 42 + 60 and 60 + 42 are not):
    that one sample fails with the reason, has no verdict, and is counted apart from the
    stable and unstable ones."""
    raw = scene()
    raw["hub"]["inertia"] = [[50.0, 0.0, 0.0], [0.0, 50.0, 0.0], [0.0, 0.0, 90.0]]
    raw["outputs"]["exact_reference"] = False
    result = run_sweep(raw, parameters={
        "hub.inertia[0][0]": {"distribution": "uniform", "low": 42.0, "high": 60.0},
        "hub.inertia[1][1]": {"distribution": "uniform", "low": 42.0, "high": 60.0}},
        method="grid", levels=2, design="nominal", worst_case=False, workers=1,
        progress=False)
    table = result.table.to_pydict()
    failed = [i for i, s in enumerate(table["status"]) if s == "failed"]
    assert [(table["hub.inertia[0][0]"][i], table["hub.inertia[1][1]"][i])
            for i in failed] == [(42.0, 42.0)]
    (i,) = failed
    assert "hub.inertia: must be the inertia of a body" in table["error"][i]
    assert "triangle inequality" in table["error"][i]
    assert table["stable"][i] is None and math.isnan(table["truth_modulus_margin"][i])
    s = result.summary
    assert s["samples"]["failed"] == 1 and s["samples"]["evaluated"] == 3
    assert (s["instability"]["of"], s["instability"]["failed"]) == (3, 1)
    assert s["instability"]["bound"]["unstable"] == 1    # the failed one, counted as unstable
    assert all(table["stable"][k] is True for k in range(4) if k != i)


def test_the_worst_scene_reruns_the_very_controller_the_sweep_judged():
    """worst.toml of a three-axis sample: its scene with the sample's controller given as
    numbers ([controller.given], 3 torques from 9 signals); the design loop's run of it closes
    that controller and its multiloop margins equal the sample's (1e-9 relative on the truth
    model, the same matrices and models; 1e-6 on the exact beam, whose margins the run finds
    from its own denser grid's brackets)."""
    raw = scene()
    raw["controller"]["pd"]["notch"] = "first_mode"
    spec = read_sweep({"parameters": PARAMETERS, "samples": 1, "seed": 2,
                       "design": "per-sample"}, raw, "test")
    context = prepare(raw, spec, "test")
    values = spec.values()[0]
    row = evaluate(context, values)
    assert row["error"] == "" and row["exact_stable"] is True
    record = json.loads(row["controller"])
    assert np.shape(record["D"]) == (3, 9) and len(record["A"]) > 0
    again = worst_scene(context, {p.key: v for p, v in zip(spec.parameters, values)}, row)
    assert again["controller"]["given"]["B"] == record["B"]
    result = run(load_scene(again), time_responses=False)
    K = result.designs[context.variant]["controllers"]["pd"]
    assert np.array_equal(K.D, np.array(record["D"]))
    rerun = loop_margins(again)
    for prefix, rtol in (("truth", 1e-9), ("exact", 1e-6)):
        for name in [f"{prefix}_{k}" for k in MARGINS] + [
                k for k in THREE_AXIS_METRICS if k.startswith(prefix + "_")]:
            assert rerun[name] == pytest.approx(row[name], rel=rtol, abs=1e-12), name


@pytest.mark.slow
def test_a_sample_runs_on_the_truth_the_nominal_run_chose_from_its_tolerance():
    """A scene whose fidelity comes from its tolerance, with tip outputs: the sweep pins the
    nominal run's choice (n_modes and the modes per motion, ``fidelity.modes_per_motion``), so
    the sample at the nominal point has the nominal run's truth model, mode for mode of each
    motion, and its multiloop margins are spacecraft.run's of the nominal scene (1e-9 relative
    on the truth model, the same matrices; 1e-6 on the exact beam, brackets of two grids).
    A sample's worst-case scene carries the pins and reruns to the sample's margins."""
    raw = scene()
    raw["fidelity"] = {"tolerance": 1e-3}
    raw["outputs"]["tip_deflection"] = True
    spec = read_sweep({"parameters": PARAMETERS, "samples": 1, "seed": 2,
                       "design": "per-sample"}, raw, "test")
    context = prepare(raw, spec, "test")
    nominal_raw = apply_values(raw, spec.parameters, spec.nominal)
    nominal = DesignLoop(load_scene(nominal_raw))
    expected = nominal.truth_modes_per_motion(nominal.n_modes)
    assert expected["rod"]["torsion"] >= 1
    at_nominal = apply_values(context.base, spec.parameters, spec.nominal)
    sample = DesignLoop(load_scene(at_nominal))
    assert context.n_modes == nominal.n_modes
    assert sample.truth_modes_per_motion(context.n_modes) == expected
    row = evaluate(context, spec.nominal)
    ref = loop_margins(nominal_raw)
    for prefix, rtol in (("truth", 1e-9), ("exact", 1e-6)):
        for name in [f"{prefix}_{k}" for k in MARGINS] + [
                k for k in THREE_AXIS_METRICS if k.startswith(prefix + "_")]:
            assert row[name] == pytest.approx(ref[name], rel=rtol, abs=1e-12), name
    values = spec.values()[0]
    row = evaluate(context, values)
    again = worst_scene(context, {p.key: v for p, v in zip(spec.parameters, values)}, row)
    assert again["fidelity"]["modes_per_motion"] == context.base["fidelity"]["modes_per_motion"]
    rerun = loop_margins(again)
    for name in [f"truth_{k}" for k in MARGINS]:
        assert rerun[name] == pytest.approx(row[name], rel=1e-9, abs=1e-12), name


@pytest.mark.slow
def test_the_shipped_three_axis_sweeps_samples_keep_the_nominal_runs_modes_per_motion():
    """The shipped three-axis sweep (fidelity from the tolerance, tip outputs on): a sample's
    truth keeps as many modes of each motion as the nominal run's (its wings' and boom's
    torsion modes included, which the tip-output rule adds)."""
    from spacecraft.sweep import load_sweep

    raw, spec, source = load_sweep("three_axis", samples=4)
    context = prepare(raw, spec, source)
    nominal = DesignLoop(load_scene(apply_values(raw, spec.parameters, spec.nominal)))
    expected = nominal.truth_modes_per_motion(nominal.n_modes)
    sample = DesignLoop(load_scene(apply_values(context.base, spec.parameters,
                                                spec.values()[1])))
    assert sample.truth_modes_per_motion(context.n_modes) == expected
    assert all(m["torsion"] >= 1 and m["xz"] >= 1 for m in expected.values())
    # the summary and the report say so (not n_modes alone)
    assert context.truth_modes == expected
    from spacecraft.sweep.report import _truth_words
    words = _truth_words({"n_modes": context.n_modes, "truth_modes": context.truth_modes})
    assert words.startswith("truth modes per beam: ")
    for name, c in expected.items():
        assert f"{name} xy {c['xy']}, xz {c['xz']}, torsion {c['torsion']}" in words


@pytest.mark.slow
def test_a_three_axis_sweep_on_a_local_cluster_equals_the_serial_one():
    """Two worker processes (single-threaded BLAS) against this process: the same samples to
    rounding (1e-9 relative, 1e-12 absolute: margins refined to 1e-12 in frequency, a slew of
    some tens of states), verdicts, statuses and controllers' shapes exactly."""
    import logging

    from distributed import Client, LocalCluster

    raw = scene()
    settings = dict(parameters=PARAMETERS, samples=4, seed=7, design="nominal",
                    worst_case=False, progress=False)
    serial = run_sweep(raw, workers=1, **settings).table.to_pydict()
    cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                           dashboard_address=":0", silence_logs=logging.ERROR)
    client = Client(cluster, set_as_default=False)
    try:
        result = run_sweep(raw, client=client, **settings)
    finally:
        client.close()
        cluster.close()
    assert result.summary["executor"] == "client, 2 workers"
    parallel = result.table.to_pydict()
    assert list(serial) == list(parallel)
    assert "truth_disk_margin" in parallel and "exact_modulus_margin_z" in parallel
    for name in serial:
        if name == "seconds":
            continue
        for x, y in zip(serial[name], parallel[name]):
            if isinstance(x, float) and not math.isnan(x):
                assert y == pytest.approx(x, rel=1e-9, abs=1e-12), name
            elif not isinstance(x, float):
                assert x == y, name


def test_the_shipped_three_axis_sweep_scene_reads_and_its_box_is_physical():
    """The embedded sweep scene: a three-axis spacecraft, its parameters an inertia tensor's
    moments and product of inertia, a wing's cant, a section and a modulus; every end of the
    box valid alone (check_box), the tensor symmetric at every sampled point."""
    from spacecraft.sweep import load_sweep
    from spacecraft.sweep.parameters import check_box

    raw, spec, source = load_sweep("three_axis")
    assert load_scene(raw).three_axis
    keys = spec.keys
    assert "hub.inertia[0][1]" in keys and "appendages.wing_left.orientation[2]" in keys
    assert any(".beam." in k for k in keys)
    values = spec.values(np.arange(50))
    check_box(spec, raw, source, values)
    for v in values[:5]:
        J = np.array(apply_values(raw, spec.parameters, v)["hub"]["inertia"])
        assert np.array_equal(J, J.T)
        assert np.all(np.linalg.eigvalsh(J) > 0)
    assert sweep_scene_path("three_axis").name == "three_axis.toml"


def test_the_controller_columns_are_per_axis():
    """A PD tuned per sample records its gains about each hub axis (the diagonals of its 3 x 3
    matrices), as a planar sweep records its PD's two gains; a held (nominal) controller and an
    LQR have none (their matrices are in the controller column or summary.json)."""
    from spacecraft.sweep.evaluate import columns

    gains = [f"pd_k{g}_{a}" for a in "xyz" for g in "pd"]
    three = columns(False, True, per_sample=True, controller="pd", three_axis=True)
    assert set(gains) <= set(three) and "pd_kp" not in three and "controller" in three
    assert {"pd_kp", "pd_kd"} <= set(columns(False, True, per_sample=True, controller="pd"))
    for kwargs in ({"per_sample": False, "controller": "pd"},
                   {"per_sample": True, "controller": "lqr"}):
        assert not set(gains + ["pd_kp", "pd_kd"]) & set(
            columns(True, True, three_axis=True, **kwargs))


@pytest.mark.slow
def test_a_three_axis_pd_sweep_records_each_samples_gains_per_axis():
    """Each sample's Kp = wn^2 J and Kd = 2 zeta wn J (J the sample's spacecraft inertia, wn
    swept too): its columns about x, y, z equal the diagonals of the gains the design loop
    tunes on that sample's scene (the same formula: 1e-12)."""
    raw = scene()
    raw["outputs"] = {"exact_reference": False}
    parameters = {"hub.inertia[0][0]": PARAMETERS["hub.inertia[0][0]"],
                  "controller.pd.natural_frequency": {"distribution": "uniform",
                                                      "low": 0.08, "high": 0.12}}
    result = run_sweep(raw, parameters=parameters, samples=2, seed=4, design="per-sample",
                       worst_case=False, workers=1, progress=False)
    t = result.table.to_pydict()
    assert t["pd_kp_x"][0] != t["pd_kp_x"][1]
    context = result.context
    for i in range(2):
        sample = apply_values(context.base, context.parameters,
                              [t[k][i] for k in parameters])
        c = run(load_scene(sample), time_responses=False).data["controllers"]
        (pd,) = [kinds["pd"] for kinds in c.values()]
        for j, a in enumerate("xyz"):
            assert t[f"pd_kp_{a}"][i] == pytest.approx(pd["Kp"][j][j], rel=1e-12)
            assert t[f"pd_kd_{a}"][i] == pytest.approx(pd["Kd"][j][j], rel=1e-12)
        wn = t["controller.pd.natural_frequency"][i]
        assert t["pd_kd_z"][i] / t["pd_kp_z"][i] == pytest.approx(2 * 0.7 / wn, rel=1e-12)
