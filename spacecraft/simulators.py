"""The scene's manoeuvre in another simulator: Basilisk (``simulator.name = "basilisk"`` or
``flexsat run --simulator basilisk``).

For each controller tuned on the first design model, :func:`basilisk_runs` runs the scene's
slew (and disturbance) in Basilisk through :func:`spacecraft.basilisk.slew_comparison`: the
design chains as hinged bodies on the hub, the controller as flight software at the simulator's
sample time (the controller's own when digital), and beside it flexsat's two linear predictions
of the same sampled-data loop: on the linear hub + chains and on the scene's truth plant (the
distributed beams, truncated to the modes the scene's tolerance needs). The differences answer:

- Basilisk - truth: what modelling the appendage as a hinged chain costs a Basilisk user (the
  chain against the distributed beam);
- Basilisk - linear chain: the nonlinearity of the manoeuvre (large hinge angles, the hub's
  finite rotation), plus RK4's error.

Basilisk's results are JSON-ready in ``data["basilisk"]`` (results.json), its responses beside
flexsat's in the report, the slew plot and the time series.
"""

from __future__ import annotations

import numpy as np

__all__ = ["basilisk_runs", "basilisk_disturbances", "summary", "SIGNALS"]

#: Signals compared, in the report's order (those both responses have).
SIGNALS = ("theta", "omega", "torque")


def basilisk_disturbances(manoeuvre) -> dict | None:
    """The scene's disturbance pulse as Basilisk inputs: name -> f(t) (None without one)."""
    d = manoeuvre.disturbance
    if d is None:
        return None
    end = np.inf if d.length is None else d.start + d.length

    def pulse(t, start=d.start, end=end, amplitude=d.amplitude):
        t = np.asarray(t, dtype=float)
        return np.where((t >= start) & (t < end), amplitude, 0.0)
    return {d.input: pulse}


def _differences(comparison) -> dict:
    out = {}
    for which, table in comparison.differences.items():
        out[which] = {name: dict(values) for name, values in table.items()}
    return out


def basilisk_runs(runner, designs: dict, truth_sim) -> tuple[dict, dict]:
    """Run the manoeuvre in Basilisk for every controller of the first design model.

    Parameters
    ----------
    runner : spacecraft.runner._Runner
    designs : dict
        The runner's designs (variant -> ``spacecraft``, ``controllers``...).
    truth_sim : control.StateSpace
        The truth plant (tip deflections when the scene asks for them).

    Returns
    -------
    comparisons : dict
        Controller kind -> :class:`spacecraft.basilisk.SlewComparison`.
    data : dict
        JSON-ready, per controller kind: ``design`` (the variant simulated), ``bsk_version``,
        ``sample_time`` [s], ``dt`` [s], ``seconds`` (Basilisk's build and run wall time),
        ``out_of_plane``, ``differences`` (``basilisk_vs_truth``, ``basilisk_vs_chain``,
        ``chain_vs_truth``: per signal ``peak``, ``peak_difference``, ``relative``) and
        ``summary`` (:func:`summary`).

    Raises
    ------
    spacecraft.basilisk.BasiliskNotInstalled
        Without the ``bsk`` package (one line: how to install the extra).
    """
    from .basilisk import (ReactionWheel, default_sample_time, require_basilisk,
                           slew_comparison)

    version = require_basilisk()
    scene = runner.scene
    m, sim = scene.manoeuvre, scene.simulator
    variant = next(iter(designs))
    d = designs[variant]
    wheel = None
    if sim.reaction_wheel is not None:
        w = sim.reaction_wheel
        wheel = ReactionWheel(w.spin_inertia, max_torque=w.max_torque, max_speed=w.max_speed)
    comparisons, data = {}, {}
    for kind, K in d["controllers"].items():
        runner.stats.basilisk_runs += 1
        # the scene's rate, else the controller's own (digital), else 30 samples per period
        # of the loop's fastest crossover or the controller's fastest pole
        sample_time = sim.sample_time or default_sample_time(d["plant"], K)
        comparison = slew_comparison(
            d["spacecraft"], K, m.slew_angle, m.slew_time, duration=m.duration,
            sample_time=sample_time, dt=sim.dt, truth_plant=truth_sim,
            disturbances=basilisk_disturbances(m), reaction_wheel=wheel)
        comparisons[kind] = comparison
        b = comparison.basilisk
        differences = _differences(comparison)
        data[kind] = {"design": variant, "bsk_version": version, "sample_time": b.sample_time,
                      "dt": b.dt, "seconds": dict(b.seconds), "out_of_plane": b.out_of_plane,
                      "differences": differences, "summary": summary(differences)}
    return comparisons, data


def _part(entry) -> str:
    if entry is None:
        return "n/a"
    if entry["relative"] is None:
        return f"{entry['peak_difference']:.3g}"
    return f"{entry['peak_difference']:.3g} ({100.0 * entry['relative']:.3g} % of its peak)"


def summary(differences: dict) -> str:
    """One sentence: how far Basilisk's nonlinear chain is from flexsat's beam (truth) and
    from flexsat's linear chain, in theta and the tip deflections."""
    truth = differences.get("basilisk_vs_truth", {})
    chain = differences.get("basilisk_vs_chain", {})
    names = ["theta"] + sorted(n for n in chain if n.endswith("_tip_deflection"))
    parts = []
    for name in names:
        if name not in chain:
            continue
        unit = "rad" if name == "theta" else "m"
        parts.append(f"{name} [{unit}] differs from the distributed beam (truth) by "
                     f"{_part(truth.get(name))} and from the linear chain by "
                     f"{_part(chain.get(name))}")
    return "; ".join(parts) if parts else "no common signals"
