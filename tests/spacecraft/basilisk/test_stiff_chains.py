"""Stiff chains in Basilisk: RK4's step from the modes the flight software acts on, stiff
torsion held rigid, and the flight-software rate from where the loop has gain.

The shipped three_axis scene's 3-body chains reach 5.7e3 rad/s (the boom's torsion) and 1.3e3
rad/s (the wings' in-plane bending), while its loops cross over near 6 rad/s and the flight
software samples at 50 Hz. What is asserted here is each rule's defining property, against
values computed independently (RK4's stability limit 2 sqrt(2) on the imaginary axis, Hairer
& Wanner, Solving ODEs II, sec. IV.2; a two-body spring chain's first frequency by hand), not
what rounding decides.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import controllers
from appendages import fit_chain_3d
from spacecraft import Hub, Mount, Spacecraft
from spacecraft import basilisk as sb
from spacecraft.basilisk.simulation import (DEFAULT_STEP_FACTOR, RK4_STABILITY_LIMIT,
                                            STABLE_STEP_FACTOR)

needs_bsk = pytest.mark.basilisk


def shipped_spacecraft():
    """The shipped three_axis scene's hub, mounts and 3-body chains (as the design loop fits
    them: fit_chain_3d of each beam)."""
    import warnings

    from spacecraft import load_scene

    scene = load_scene("three_axis")
    hub = Hub(scene.hub.mass, np.array(scene.hub.inertia))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the boom's torsion zero (a FitWarning)
        return Spacecraft(hub, [Mount(fit_chain_3d(a.beam.build(), a.fit.n_bodies),
                                      a.position, orientation=np.array(a.orientation),
                                      name=a.name)
                                for a in scene.appendages])


# -- RK4's step --------------------------------------------------------------------------------
@pytest.mark.parametrize("w_max, resolved", [(5655.0, 157.0), (1344.0, 157.0), (300.0, 157.0),
                                             (100.0, 157.0), (1e4, 10.0)])
def test_the_default_step_resolves_up_to_a_frequency_and_is_stable_above(w_max, resolved):
    T = 0.02
    dt = sb.dynamics_step(w_max, T, accurate_up_to=resolved)
    k = round(T / dt)
    assert k * dt == pytest.approx(T, rel=1e-12)
    # accurate on every mode up to the resolved frequency, stable with a margin on the highest
    assert min(w_max, resolved) * dt <= DEFAULT_STEP_FACTOR * (1 + 1e-12)
    assert w_max * dt <= STABLE_STEP_FACTOR * (1 + 1e-12) < RK4_STABILITY_LIMIT
    # the longest such step: no longer step T/k' (k' < k, whole nanoseconds) keeps both
    for shorter_k in (j for j in range(1, k) if round(T * 1e9) % j == 0):
        longer = T / shorter_k
        assert (min(w_max, resolved) * longer > DEFAULT_STEP_FACTOR
                or w_max * longer > STABLE_STEP_FACTOR)
    # every mode below the resolved frequency: the accurate default as before
    if w_max <= resolved:
        assert dt == sb.dynamics_step(w_max, T)


def test_rk4_is_stable_at_the_stable_factor_and_not_beyond_the_limit():
    # |R(i y)| of RK4's stability function (Hairer & Wanner, sec. IV.2) at the factors used
    def amplification(y):
        z = 1j * y
        return abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)
    assert amplification(STABLE_STEP_FACTOR) == pytest.approx(0.745, abs=1e-3)
    assert amplification(RK4_STABILITY_LIMIT) == pytest.approx(1.0, abs=1e-12)
    assert amplification(RK4_STABILITY_LIMIT * 1.01) > 1.0
    assert 1 - amplification(DEFAULT_STEP_FACTOR) < DEFAULT_STEP_FACTOR**6 / 144 * 1.01


def test_a_step_beyond_the_stability_limit_names_the_largest_stable_one():
    w, T = 5655.0, 0.02
    with pytest.raises(ValueError) as caught:
        sb.dynamics_step(w, T, 1e-3)
    message = str(caught.value)
    stable = sb.largest_stable_step(w, T)
    assert "dt = 0.001 s is beyond RK4's stability limit" in message
    assert f"the largest stable step dividing the sample time 0.02 s is {stable:.9g} s" in message
    # it is stable, divides T, and the next longer divisor of T is not stable
    assert w * stable <= RK4_STABILITY_LIMIT
    assert sb.dynamics_step(w, T, stable) == stable
    k = round(T / stable)
    longer = [T / j for j in range(1, k) if round(T * 1e9) % j == 0]
    assert all(w * step > RK4_STABILITY_LIMIT for step in longer)


# -- stiff torsion held rigid ------------------------------------------------------------------
def test_torsion_above_the_limit_is_held_rigid_in_basilisk_and_the_chain_compared():
    sc = shipped_spacecraft()
    boom = sc.mounts[sc.names.index("boom")].appendage
    wing = sc.mounts[sc.names.index("wing_left")].appendage
    # the boom's first torsion frequency (root body held): the 2-DOF spring chain by hand
    J, k = boom.torsional_inertias, boom.torsion_stiffnesses
    M = np.diag(J[1:])
    K = np.array([[k[0] + k[1], -k[1]], [-k[1], k[1]]])
    expected = math.sqrt(min(np.linalg.eigvals(np.linalg.solve(M, K)).real))
    assert sb.torsion_frequency(boom) == pytest.approx(expected, rel=1e-12)
    limit = 2 * math.pi / 0.02  # a 50 Hz flight software's sampling frequency
    assert sb.torsion_frequency(wing) < limit < sb.torsion_frequency(boom)
    with pytest.warns(sb.BasiliskModelWarning):  # the wings' raised moments, as before
        free = sb.layout(sc)
    with pytest.warns(sb.BasiliskModelWarning):
        held = sb.layout(sc, rigid_above=limit)
    by_name = {a.name: a for a in held.appendages}
    assert by_name["boom"].held == ("axial", "torsion")
    assert by_name["boom"].torsion_frequency == pytest.approx(expected, rel=1e-12)
    assert by_name["wing_left"].held == ("axial",)
    assert by_name["wing_left"].torsion_frequency is None
    # Basilisk: the boom's torsion hinges gone (two joints), nothing else changed
    assert held.n_bodies == free.n_bodies - 2
    assert all(b.spin_axis != "x" for b in by_name["boom"].bodies)
    # the linear chain compared holds it too: its two torsion modes gone, the rest unchanged
    modes_free = np.sort(free.spacecraft.modes()[0])
    modes_held = np.sort(held.spacecraft.modes()[0])
    assert modes_held.size == modes_free.size - 2
    assert modes_free[-1] == pytest.approx(5655, rel=1e-3)
    assert modes_held[-1] < 0.3 * modes_free[-1]
    assert held.spacecraft.mounts[sc.names.index("boom")].appendage.torsion_stiffnesses is None
    # a chain without torsion springs is as it is
    rigid = sb.torsion_held(boom)
    assert sb.torsion_held(rigid) is rigid and sb.torsion_frequency(rigid) is None
    with pytest.raises(ValueError, match=r"rigid_above must be positive .*rad/s"):
        sb.layout(sc, rigid_above=-1.0)


# -- the flight-software rate ------------------------------------------------------------------
def test_an_estimators_poles_where_the_loop_has_no_gain_do_not_set_the_rate():
    plant = shipped_spacecraft().plant(prune=True)  # the design model, as the loop tunes on
    K = controllers.lqr(plant, attitude_weight=1e3, rate_weight=1e5, torque_weight=1.0)
    T = sb.default_sample_time(plant, K)
    omega, L = controllers.loop_frequency_response(plant, K)
    gain = np.linalg.norm(L, ord=2, axis=(1, 2))
    crossover = float(omega[np.nonzero(gain >= 1.0)[0][-1]])
    acting = float(omega[np.nonzero(gain >= sb.LOOP_GAIN_FLOOR)[0][-1]])
    poles = np.abs(np.linalg.eigvals(K.A))
    counted = max([crossover] + [p for p in poles if p <= acting])
    assert 2 * math.pi / T >= sb.SAMPLES_PER_CROSSOVER * counted
    assert 2 * math.pi / (2.5 * T) < sb.SAMPLES_PER_CROSSOVER * counted  # the longest such
    # the estimator's copies of the stiff modes are there, where the loop has no gain
    assert poles.max() > 1e3 > 100 * acting


# -- the shipped scene ---------------------------------------------------------------------------
@pytest.mark.slow
@needs_bsk
def test_a_given_step_beyond_stability_is_refused_by_key_with_the_largest_stable_one():
    import re

    from spacecraft import SceneError, load_scene, run

    scene = load_scene("three_axis", overrides={"simulator.name": "basilisk",
                                                "simulator.dt": 1e-3})
    with pytest.raises(SceneError) as refused:
        run(scene)
    message = str(refused.value)
    assert message.startswith("three_axis (embedded scene): simulator.dt: dt = 0.001 s is "
                              "beyond RK4's stability limit"), message
    # a given step runs every torsion free: the boom's 5.7e3 rad/s torsion sets the limit
    w = float(re.search(r"highest mode ([\d.e+]+) rad/s", message).group(1))
    stable = float(re.search(r"the largest stable step dividing the sample time [\d.e+-]+ s "
                             r"is ([\d.e+-]+) s", message).group(1))
    assert w == pytest.approx(5655, rel=1e-3)
    assert w * stable <= RK4_STABILITY_LIMIT * (1 + 1e-6)


@pytest.mark.slow
@needs_bsk
def test_the_shipped_three_axis_scene_runs_in_basilisk(tmp_path):
    # the done-when line: a notch, a disturbance, a tolerance, SSP, Basilisk and every plot;
    # exit 0, Basilisk's runs per axis and tip motion in results.json and the report, the
    # step and the torsion held said, with what holding it costs measured
    import json
    import subprocess
    import sys
    import tomllib

    from spacecraft.scene.read import scene_path

    raw = tomllib.loads(scene_path("three_axis").read_text())
    assert raw["controller"]["pd"]["notch"] and raw["manoeuvre"]["disturbance"]
    assert raw["fidelity"]["tolerance"] and raw["report"]["plots"] is True
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "spacecraft.cli", "run", "three_axis",
                           "--simulator", "basilisk", "--ssp", "--quiet", "--out", str(out)],
                          capture_output=True, text=True, timeout=1800)
    assert done.returncode == 0, done.stderr
    data = json.loads((out / "results.json").read_text())
    for kind in ("pd", "lqr"):
        entry = data["basilisk"][kind]
        T, dt, w = entry["sample_time"], entry["dt"], entry["highest_frequency"]
        assert w * dt <= STABLE_STEP_FACTOR * (1 + 1e-9)
        assert round(T / dt) * dt == pytest.approx(T, rel=1e-12)
        # every mode the flight software acts on resolved (w dt <= 1/2 up to pi / T)
        assert math.pi / T * dt <= DEFAULT_STEP_FACTOR
        d = entry["differences"]
        names = {f"{q}_{a}" for q in ("theta", "omega", "torque") for a in "xyz"} | {
            f"{n}_{m}" for n in ("wing_left", "wing_right", "boom")
            for m in ("tip_deflection_y", "tip_deflection_z", "tip_twist")}
        assert names <= set(d["basilisk_vs_chain"]) and names <= set(d["basilisk_vs_truth"])
        # a 10 deg slew: the nonlinearity is second order, the attitude within the angle [rad]
        # of its peak (test_basilisk_three_axis.py's bound), far from a blown-up run
        for a in "xyz":
            assert d["basilisk_vs_chain"][f"theta_{a}"]["relative"] <= math.radians(10.0)
        # the boom's torsion held, said, and its cost measured on the linear chains: its
        # quasi-static share (w_loop / w_torsion)**2, far below 1e-3 of any other signal
        held = entry["chains_as_held"]["boom"]
        assert "torsion" in held["held"] and held["torsion_frequency"] > 2 * math.pi / T
        cost = d["held_vs_chain"]
        assert all(e["relative"] < 1e-3 for n, e in cost.items()
                   if n != "boom_tip_twist" and e["relative"] is not None)
        assert any("Torsion held rigid" in note for note in entry["notes"])
    report = (out / "report.md").read_text()
    assert "## Basilisk: the manoeuvre in a nonlinear multibody simulator" in report
    assert "RK4 step" in report and "boom (first torsion mode" in report
    assert list((out / "fmu").glob("*.ssp"))
    for plot in ("slew_pd", "slew_lqr", "loop", "poles", "W"):
        assert (out / "plots" / f"{plot}.png").exists(), plot
