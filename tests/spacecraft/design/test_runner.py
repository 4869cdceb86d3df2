"""The scene runner: each skip is proven by the runner's own work counters, and the results
that were asked for are unchanged by the skip (or by pruning, or by the chosen fidelity)."""
import math

import numpy as np
import pytest

import controllers
from appendages import Beam
from appendages.equivalence import fit_chain
from spacecraft import Hub, Mount, Spacecraft
from spacecraft.report.write import output_folder, write_report
from spacecraft.design.loop import run

from scenes import scene_with

WING = {"section": "rectangular", "length": 6.0, "width": 0.5, "thickness": 0.02,
        "density": 1600.0, "youngs_modulus": 7.0e10, "damping_ratio": 0.0}


def lean(**changes):
    """The small test scene with nothing optional: no equivalence table, outputs or exports."""
    return scene_with(**{"report.equivalence": False, **changes})


def two_wings(prune: bool, damping_ratio: float = 0.0):
    wing = dict(WING, damping_ratio=damping_ratio)
    return {
        "hub": {"mass": 500.0, "inertia": 400.0},
        "appendages": [
            {"name": "px", "position": [1.0, 0.0], "direction": 0.0, "beam": wing,
             "fit": {"match": "frequencies"}},
            {"name": "mx", "position": [-1.0, 0.0], "direction": 180.0, "beam": wing,
             "fit": {"match": "frequencies"}}],
        "fidelity": {"n_modes": 4, "prune": prune},
        "controller": {"types": ["pd"], "pd": {"natural_frequency": 0.2}},
        "manoeuvre": {"slew_angle": 5.0, "slew_time": 40.0, "duration": 80.0, "step": 0.2},
        "outputs": {"tip_deflection": True},
        "report": {"equivalence": False},
    }


def trace(response, name):
    labels = list(response.output_labels)
    return np.asarray(response.y).reshape(len(labels), -1)[labels.index(name)]


def test_lean_scene_builds_nothing_optional(tmp_path):
    result = run(lean())
    s = result.stats
    assert s.exact_reference_evaluations == 0      # n_modes given, no exact outputs, no table
    assert s.lqr_designs == 0 and s.pd_designs == 1
    assert s.tip_deflection_outputs == 0 and s.root_load_outputs == 0
    assert s.chain_fits == 1
    # one design variant x one controller x (design, truth): two loops, one setup each
    assert s.simulations == 2 and s.simulator_setups == 2
    # one eigen-decomposition per model set (truth, design), reused by every plant and loop
    assert s.eigendecompositions == 2
    assert not any(n.endswith("tip_deflection") for n in result.truth["sim"].output_labels)
    with output_folder(tmp_path / "out") as folder:
        data = write_report(result, folder)
    assert s.fmu_builds == 0 and s.plots == 0
    assert not (tmp_path / "out" / "fmu").exists()
    assert not list((tmp_path / "out").rglob("*.png"))
    assert data["stats"]["fmu_builds"] == 0


def test_tip_deflection_skip_leaves_attitude_unchanged():
    without = run(lean())
    with_tip = run(lean(**{"outputs.tip_deflection": True}))
    assert without.stats.tip_deflection_outputs == 0
    assert with_tip.stats.tip_deflection_outputs == 2   # one per plant: truth and design
    key = ("frequencies", "pd", "truth")
    assert "rod_tip_deflection" in with_tip.responses[key].output_labels
    for name in ("theta", "omega", "torque"):
        # same plant dynamics, extra output row only: identical to round-off
        np.testing.assert_allclose(trace(with_tip.responses[key], name),
                                   trace(without.responses[key], name), rtol=0, atol=1e-14)


def test_lqr_only_when_asked():
    assert run(lean()).stats.lqr_designs == 0
    both = run(lean(**{"controller.types": ["pd", "lqr"],
                       "controller.lqr": {"attitude_weight": 7.6, "torque_weight": 1.0}}))
    assert both.stats.lqr_designs == 1 and both.stats.pd_designs == 1
    assert {r["controller"] for r in both.data["closed_loops"]} == {"pd", "lqr"}
    # PD results do not depend on whether an LQR was also tuned
    pd_alone = run(lean()).data["closed_loops"][0]["metrics"]["truth"]
    pd_both = [r for r in both.data["closed_loops"] if r["controller"] == "pd"][0]
    for name, value in pd_alone.items():
        assert pd_both["metrics"]["truth"][name] == pytest.approx(value, rel=1e-12, abs=1e-15)


def test_exact_reference_only_when_asked():
    plain = run(lean())
    # damped: the exact reference's grid passes through the resonances
    exact = run(lean(**{"outputs.exact_reference": True, "appendages.0.beam.damping_ratio": 0.005}))
    assert plain.stats.exact_reference_evaluations == 0 and plain.exact_frd is None
    assert exact.stats.exact_reference_evaluations > 0
    assert exact.data["closed_loops"][0]["exact_verdict"]["stable"] is True
    # the exact frequency response tends to the rigid body 1/(J s^2), J about the system's
    # centre of mass (issue 3's low-frequency limit), at the lowest grid frequency
    frd = exact.exact_frd
    w0 = frd.omega[0]
    J = exact.data["exact"]["inertia"]
    theta0 = np.asarray(frd.frdata)[0, 0, 0]
    assert theta0 * (-J * w0**2) == pytest.approx(1.0, rel=1e-6)  # error ~ (w0/w1)^2 ~ 1e-8


def test_chain_fit_shared_by_identical_wings_and_plants_cached():
    result = run(two_wings(prune=True))
    assert result.stats.chain_fits == 1          # both wings: same beam, same criterion
    assert result.stats.cache_hits > 0
    assert result.stats.eigendecompositions == 2


def test_pruning_two_symmetric_wings_drops_symmetric_modes_results_unchanged():
    pruned, full = run(two_wings(prune=True)), run(two_wings(prune=False))
    # 4 modes per wing: 8 coupled elastic modes, half of them symmetric (hub translation, no
    # rotation): torque cannot excite them, so 1 rotation + 4 antisymmetric modes remain
    assert full.data["truth"]["modes_kept"] == 9
    assert pruned.data["truth"]["modes_kept"] == 5
    assert pruned.stats.modes_dropped == full.stats.modes_dropped + 4
    key = ("frequencies", "pd", "truth")
    for name in ("theta", "torque", "px_tip_deflection", "mx_tip_deflection"):
        a, b = trace(pruned.responses[key], name), trace(full.responses[key], name)
        # an exact reduction: only round-off of the two realisations differs
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * np.abs(b).max())
    for name, value in full.data["closed_loops"][0]["metrics"]["truth"].items():
        assert pruned.data["closed_loops"][0]["metrics"]["truth"][name] == pytest.approx(
            value, rel=1e-9, abs=1e-12)


def test_pruning_damped_symmetric_wings_results_unchanged():
    """With damping the modal damping matrix is full but couples symmetric and antisymmetric
    modes only by round-off: they are still dropped, the responses stay the same."""
    pruned = run(two_wings(prune=True, damping_ratio=0.005))
    full = run(two_wings(prune=False, damping_ratio=0.005))
    assert pruned.data["truth"]["modes_kept"] == 5 and full.data["truth"]["modes_kept"] == 9
    key = ("frequencies", "pd", "truth")
    for name in ("theta", "torque", "px_tip_deflection"):
        a, b = trace(pruned.responses[key], name), trace(full.responses[key], name)
        # the dropped coupling is round-off (1e-16 relative): the responses agree to 1e-9
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * np.abs(b).max())


def test_fidelity_from_tolerance_is_small_and_accurate():
    chosen = run(lean(**{"fidelity.n_modes": None, "fidelity.tolerance": 1e-3}))
    n = chosen.data["fidelity"]["n_modes"]
    choice = chosen.data["fidelity"]["choice"]
    n_open = choice["open_loop_n_modes"]
    assert 1 <= n_open <= 4                  # not a fixed large number
    last = choice["trials"][-1]
    assert last["n_modes"] == n_open and last["frequency_error"] <= 1e-3 \
        and last["gain_error"] <= 1e-3
    # every smaller n failed the tolerance (the smallest n is chosen)
    assert all(max(t["frequency_error"], t["gain_error"]) > 1e-3 for t in choice["trials"][:-1])
    # then the closed loops (spacecraft.design.fidelity): n is the first whose loops change by less
    # than the tolerance with one more mode (on this undamped rod the least damping ratio of
    # the PD's loop falls with every mode, ~n^-4, until it changes by less than 1e-3 x 1e-3)
    record = choice["closed_loop"]
    assert record["converged"] and record["trials"][0]["n_modes"] == n_open
    changes = [max(v for k, v in t.items() if k != "n_modes") for t in record["trials"]]
    assert record["trials"][-1]["n_modes"] == n and changes[-1] <= 1e-3
    assert all(c > 1e-3 for c in changes[:-1])
    # the slew on the chosen truth model agrees with a 12-mode one to well below the
    # tolerance relative to the slew angle (Craig-Bampton converges like n^-4 in frequency)
    fine = run(lean(**{"fidelity.n_modes": 12}))
    key = ("frequencies", "pd", "truth")
    theta_c, theta_f = trace(chosen.responses[key], "theta"), trace(fine.responses[key], "theta")
    assert np.max(np.abs(theta_c - theta_f)) < 1e-3 * math.radians(10.0)


def test_results_match_the_library_called_directly():
    result = run(lean(**{"outputs.tip_deflection": True}))
    # the same models built by hand
    beam = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)
    chain = fit_chain(beam, 3, match="frequencies")
    hub = Hub(100.0, 50.0)
    truth = Spacecraft(hub, [Mount(beam.truncated(3), (0.5, 0.0), 0.0, name="rod")])
    design = Spacecraft(hub, [Mount(chain, (0.5, 0.0), 0.0, name="rod")])
    np.testing.assert_allclose(result.data["truth"]["coupled_frequencies"],
                               truth.natural_frequencies(3), rtol=1e-12)
    P_design = design.plant(prune=True)
    K = controllers.pd(P_design, natural_frequency=0.1, damping=0.7)
    loop = controllers.close_loop(truth.plant(prune=True, tip_deflection=True), K)
    response = controllers.slew(loop, math.radians(10.0), 60.0, t_final=120.0, dt=0.5)
    expected = controllers.metrics(response)
    got = result.data["closed_loops"][0]["metrics"]["truth"]
    for name, value in expected.items():
        # forced_response vs the runner's exact simulator: the same interpretation of the
        # input (linear between samples), agreement to round-off
        assert got[name] == pytest.approx(value, rel=1e-8, abs=1e-12), name


def test_disturbance_pulse_reaches_the_truth_loop():
    result = run(lean(**{"manoeuvre.disturbance": {"input": "rod_tip_force", "amplitude": 0.01,
                                                   "start": 10.0, "length": 5.0}}))
    loop = result.loops[("frequencies", "pd", "truth")]
    assert "rod_tip_force" in loop.input_labels
    # the disturbance is simulated apart from the slew (issue 14: reported separately)
    response = result.disturbance_responses[("frequencies", "pd", "truth")]
    u = np.asarray(response.u).reshape(loop.ninputs, -1)[list(loop.input_labels).index(
        "rod_tip_force")]
    t = np.asarray(response.t).reshape(-1)
    assert u[(t >= 10.0) & (t < 15.0)] == pytest.approx(0.01)
    assert np.all(u[(t < 10.0) | (t >= 15.0)] == 0.0)


def test_hinged_root_chain_scene_runs():
    from spacecraft.scene.read import scene_path

    result = run(scene_path("hinged_wing"))
    assert result.stats.exact_reference_evaluations == 0 and result.stats.chain_fits == 0
    truth_chain = result.models["wing"]["truth"]
    assert truth_chain.root == "hinged" and truth_chain.n_bodies == 20
    assert {"wing_root_force", "wing_root_moment", "wing_tip_deflection"} <= set(
        result.truth["sim"].output_labels)
    assert result.data["closed_loops"][0]["verdict"]["stable"] is True


def test_digital_controller_is_closed_as_a_sampled_data_loop():
    continuous = run(lean())
    digital = run(lean(**{"controller.sample_rate": 20.0, "manoeuvre.step": 0.05}))
    loop = digital.loops[("frequencies", "pd", "truth")]
    assert loop.dt == pytest.approx(0.05, rel=1e-15)
    assert digital.stats.simulator_setups == 0   # discrete loops step their own matrices
    assert digital.data["closed_loops"][0]["verdict"]["stable"] is True
    # a 20 Hz zero-order hold adds a phase lag of w T / 2 = 0.0025 rad at the 0.1 rad/s
    # bandwidth: the overshoot moves by far less than 0.05 percentage points
    got = digital.data["closed_loops"][0]["metrics"]["truth"]["overshoot"]
    expected = continuous.data["closed_loops"][0]["metrics"]["truth"]["overshoot"]
    assert got == pytest.approx(expected, abs=0.05)


def _two_wings(**changes):
    """Two identical wings at +-1 m along x (mirror images) and a boom on y."""
    wing = {"section": "rectangular", "length": 6.0, "width": 0.5, "thickness": 0.02,
            "density": 1600.0, "youngs_modulus": 7.0e10, "damping_ratio": 0.005}
    data = scene_with(**{
        "appendages": [
            {"name": "wing_px", "position": [1.0, 0.0], "direction": 0.0, "beam": dict(wing),
             "fit": {"match": "poles-and-zeros"}},
            {"name": "wing_mx", "position": [-1.0, 0.0], "direction": 180.0,
             "beam": dict(wing), "fit": {"match": "poles-and-zeros"}},
            {"name": "boom", "position": [0.0, 1.0], "direction": 90.0,
             "beam": {"section": "tube", "length": 4.0, "outer_diameter": 0.05,
                      "wall_thickness": 0.002, "density": 2700.0, "youngs_modulus": 7.0e10},
             "fit": {"match": "poles-and-zeros"}}],
        "fidelity.n_modes": 2, "outputs.tip_deflection": True, "report.equivalence": False,
        **changes})
    return data


def test_root_load_outputs_do_not_shift_the_tip_deflections():
    """Before: with root_loads the plant's output labels were interleaved per appendage
    (tip, force, moment, tip, ...) while its rows were every motion first, then every load:
    wing_mx's 'tip deflection' was wing_px's root force (0.094 against 0.00015 m)."""
    wing = Beam(6.0, 7.0e10 * 0.5 * 0.02 ** 3 / 12.0, 1600.0 * 0.5 * 0.02, damping_ratio=0.005)
    boom = Beam(4.0, 1.0e4, 0.8, damping_ratio=0.005)
    sc = Spacecraft(Hub(500.0, 400.0), [
        Mount(wing.truncated(2), (1.0, 0.0), 0.0, name="wing_px"),
        Mount(wing.truncated(2), (-1.0, 0.0), math.pi, name="wing_mx"),
        Mount(boom.truncated(2), (0.0, 1.0), math.pi / 2, name="boom")])
    with_loads = sc.plant(tip_deflection=True, root_loads=True, prune=False)
    plain = sc.plant(tip_deflection=True, prune=False)
    s = 0.5j
    for P in (with_loads, plain):
        P.H = P.C @ np.linalg.solve(s * np.eye(P.nstates) - P.A, P.B) + P.D
    for name in plain.output_labels:
        # the same realisation with more rows: equal to round-off of one solve
        np.testing.assert_allclose(with_loads.H[list(with_loads.output_labels).index(name)],
                                   plain.H[list(plain.output_labels).index(name)],
                                   rtol=1e-12, atol=0)
    # mirror-image wings under torque: equal tip deflections in their own axes
    tips = [abs(with_loads.H[list(with_loads.output_labels).index(f"{n}_tip_deflection"),
                             list(with_loads.input_labels).index("torque")])
            for n in ("wing_px", "wing_mx")]
    assert tips[0] == pytest.approx(tips[1], rel=1e-9)


def test_report_peaks_of_mirror_image_wings_are_equal_with_root_loads():
    result = run(_two_wings(**{"outputs.root_loads": True}))
    peaks = result.data["closed_loops"][0]["appendages"]["truth"]
    # the mirror symmetry holds to the round-off of the simulation
    assert peaks["wing_px"]["peak_tip_deflection"] == pytest.approx(
        peaks["wing_mx"]["peak_tip_deflection"], rel=1e-8)
    assert peaks["wing_px"]["peak_root_moment"] == pytest.approx(
        peaks["wing_mx"]["peak_root_moment"], rel=1e-8)
    assert peaks["boom"]["peak_root_force"] > 0


@pytest.mark.slow
def test_a_run_without_fmus_loads_no_fmu_toolchain_nor_dask():
    """issue 10: fmpy and the FMU exporter only when FMUs are built, Dask only for sweeps."""
    import subprocess
    import sys
    from pathlib import Path

    # this file's folder and the project's root by their paths, not the working directory's
    here = Path(__file__).resolve()
    paths = [str(here.parents[2] / "support"), str(here.parents[3])]  # the tests' helpers, the root
    code = (f"import sys, json; sys.path[:0] = {paths!r}; from scenes import scene_with; "
            "import spacecraft; spacecraft.run(scene_with(**{'report.equivalence': False})); "
            "print(' '.join(m for m in ('fmu', 'fmpy', 'dask', 'distributed', 'pyarrow') "
            "if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=300, check=True)
    assert done.stdout.strip() == ""
