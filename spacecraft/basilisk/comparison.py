r"""flexsat's prediction of a Basilisk run, and the differences between them.

For a slew run in Basilisk (:func:`.simulate_slew`) flexsat predicts the same sampled-data loop
exactly at the sample instants: the digital law at T (:func:`.flight_software_law`) closed by
:func:`controllers.close_loop` around a linear plant, the linear hub + chains (the Basilisk
model linearised) or the scene's truth (hub + beam). Three differences answer what a Basilisk
user asks (:func:`slew_comparison`):

- Basilisk - truth: how far the Basilisk model (nonlinear chain) is from flexsat's distributed
  beam, i.e. what modelling the appendage as a chain costs;
- Basilisk - linear chain: the nonlinearity of the manoeuvre (plus RK4's error, below 1e-7 at
  the accurate default step; a step that resolves only the modes up to ``accurate_up_to``
  damps those above numerically, :mod:`.simulation`);
- linear chain - truth: flexsat's own chain-vs-beam figure for the same sampled loop.

Each as the peak absolute difference per signal and relative to the reference's peak. When
Basilisk holds a stiff torsion rigid (``rigid_above``, :mod:`.layout`), the linear chain
compared holds it too, and a fourth difference measures what that costs: the linear chain held
against the linear chain free (``held_vs_chain``), both exact at the samples.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping

import control
import numpy as np

from appendages.interface import check_positive

from ..dynamics.coupling import Spacecraft
from .actuators import ReactionWheel
from .flight_software import flight_software_law
from .layout import chain_spacecraft
from .simulation import (MAX_SECONDS, BasiliskResult, default_duration, disturbance_values,
                         nanoseconds, sample_count, simulate_slew, slew_reference)

__all__ = ["SlewComparison", "linear_slew", "compare", "slew_comparison"]

_NANO = 1e-9


def linear_slew(spacecraft: Spacecraft, controller: control.StateSpace, angle: float,
                slew_time: float, *, duration: float | None = None,
                sample_time: float | None = None, chains: Mapping | None = None,
                disturbances: Mapping | None = None, plant: control.StateSpace | None = None,
                axis=None) -> control.TimeResponseData:
    """flexsat's linear prediction of :func:`simulate_slew`: the same sampled-data loop.

    The plant is the linear hub + chains (``plant(tip_deflection=True)`` of the same chains as
    Basilisk models them, :func:`.chain_spacecraft`, or ``plant``: any flexsat plant, e.g. hub
    + beam for the beam's prediction), the controller the same digital law
    (:func:`.flight_software_law`), closed by :func:`controllers.close_loop` (zero-order hold,
    exact at the sample instants), driven by the same reference and disturbances sampled at
    k T. A three-axis spacecraft needs ``axis``, the slew's eigen-axis (hub axes): the reference
    is ``theta_ref = e * profile`` (:func:`.slew_reference`).

    Returns
    -------
    control.TimeResponseData
        Outputs of the closed loop (plant outputs, then ``torque``) at k T.
    """
    import controllers

    law = flight_software_law(controller, sample_time)
    T = law.sample_time
    if isinstance(angle, bool) or not isinstance(angle, (int, float, np.integer, np.floating)) \
            or not math.isfinite(angle):
        raise TypeError(f"angle must be a finite real number [rad]; got {angle!r:.60}")
    slew_time = check_positive("slew_time", slew_time, "s")
    duration = default_duration(slew_time, duration)
    if law.three_axis and axis is None:
        raise ValueError("axis is required for a three-axis controller: the slew's eigen-axis "
                         "('x', 'y', 'z' or three numbers, hub axes)")
    if not law.three_axis and axis is not None:
        raise ValueError(f"axis is for three-axis controllers; a planar one slews about z (got "
                         f"axis {axis!r:.60})")
    if disturbances is not None and not isinstance(disturbances, Mapping):
        raise TypeError(f"disturbances must be a mapping name -> function of time or array; "
                        f"got {type(disturbances).__name__}")
    if plant is None:
        plant = chain_spacecraft(spacecraft, chains).plant(
            tip_deflection=True, disturbances=bool(disturbances))
    loop = controllers.close_loop(plant, law.controller)
    n = sample_count(duration, T)
    if n < 2:
        raise ValueError(f"duration {duration!r} s must be at least one sample time {T!r} s "
                         "(3 x slew_time by default)")
    times = np.arange(n) * (nanoseconds(T, "sample_time") * _NANO)
    U = np.zeros((loop.ninputs, n))
    labels = list(loop.input_labels)
    reference = slew_reference(angle, slew_time, axis)(times)
    if law.three_axis:
        for k, a in enumerate("xyz"):
            U[labels.index(f"theta_ref_{a}")] = reference[:, k]
    else:
        U[labels.index("theta_ref")] = reference
    for name, value in disturbance_values(disturbances, times, law.three_axis).items():
        U[labels.index(name)] = value
    return control.forced_response(loop, times, U, squeeze=False)


def _trace(response, name: str) -> np.ndarray | None:
    labels = list(response.output_labels)
    if name not in labels:
        return None
    return np.asarray(response.outputs).reshape(len(labels), -1)[labels.index(name)]


def compare(response: control.TimeResponseData, reference: control.TimeResponseData,
            names=None) -> dict:
    """Peak differences of a response from a reference, signal by signal.

    Parameters
    ----------
    response, reference : control.TimeResponseData
        E.g. Basilisk's (:attr:`BasiliskResult.response`) and flexsat's linear chain or beam
        loop. Where the time grids differ the reference is interpolated linearly onto the
        response's times (within the reference's time span).
    names : sequence of str, optional
        Signals to compare; default every output the two have in common.

    Returns
    -------
    dict
        name -> ``{"peak": max |reference|, "peak_difference": max |response - reference|,
        "relative": peak_difference / peak}`` (relative is None where the peak is 0).
    """
    for value, what in ((response, "response"), (reference, "reference")):
        if not isinstance(value, control.TimeResponseData):
            raise TypeError(f"{what} must be a control.TimeResponseData; got "
                            f"{type(value).__name__}")
    if names is not None and (isinstance(names, str) or not all(
            isinstance(n, str) for n in np.atleast_1d(np.asarray(names, dtype=object)))):
        raise TypeError(f"names must be a sequence of signal names (str) or None; got "
                        f"{names!r:.100}")
    t = np.asarray(response.time, dtype=float)
    t_ref = np.asarray(reference.time, dtype=float)
    same = t.shape == t_ref.shape and np.allclose(t, t_ref, rtol=0.0, atol=1e-9)
    keep = np.ones(t.size, dtype=bool) if same else (t >= t_ref[0]) & (t <= t_ref[-1])
    if names is None:
        names = [n for n in response.output_labels if n in list(reference.output_labels)]
    out = {}
    for name in names:
        a, b = _trace(response, name), _trace(reference, name)
        if a is None or b is None:
            raise ValueError(f"signal {name!r} is not an output of both responses")
        if not same:
            b = np.interp(t[keep], t_ref, b)
        a = a[keep]
        peak = float(np.max(np.abs(b)))
        difference = float(np.max(np.abs(a - b)))
        out[name] = {"peak": peak, "peak_difference": difference,
                     "relative": difference / peak if peak > 0 else None}
    return out


@dataclasses.dataclass
class SlewComparison:
    """A slew in Basilisk beside flexsat's predictions of the same sampled-data loop.

    Attributes
    ----------
    basilisk : BasiliskResult
    chain : control.TimeResponseData
        flexsat's linear hub + chains, same digital law, same instants.
    truth : control.TimeResponseData or None
        flexsat's truth plant (e.g. hub + beam), same digital law, same instants.
    differences : dict
        ``"basilisk_vs_chain"``, and with a truth ``"basilisk_vs_truth"`` and
        ``"chain_vs_truth"``: each :func:`compare`'s dict over the common signals; with a
        torsion held rigid (``rigid_above``) ``"held_vs_chain"``, the linear chain held against
        the linear chain free (what holding costs).
    free_chain : control.TimeResponseData or None
        With a torsion held rigid: flexsat's linear hub + chains with every torsion free.
    """

    basilisk: BasiliskResult
    chain: control.TimeResponseData
    truth: control.TimeResponseData | None
    differences: dict
    free_chain: control.TimeResponseData | None = None


def slew_comparison(spacecraft: Spacecraft, controller: control.StateSpace, angle: float,
                    slew_time: float, *, duration: float | None = None,
                    sample_time: float | None = None, truth_plant: control.StateSpace | None = None,
                    dt: float | None = None, chains: Mapping | None = None,
                    disturbances: Mapping | None = None,
                    reaction_wheel: ReactionWheel | None = None,
                    max_seconds: float = MAX_SECONDS, axis=None,
                    rigid_above: float | None = None,
                    accurate_up_to: float | None = None) -> SlewComparison:
    """Run a slew in Basilisk and compare it with flexsat's chain and truth predictions.

    Parameters
    ----------
    spacecraft, controller, angle, slew_time, duration, sample_time, dt, chains, disturbances,
    reaction_wheel, max_seconds, axis, rigid_above, accurate_up_to
        As for :func:`.simulate_slew` (``spacecraft`` with its design chains; ``axis`` the
        eigen-axis of a three-axis slew; a torsion held rigid above ``rigid_above`` is held
        in the linear chain compared too, and what that costs measured, ``held_vs_chain``).
    truth_plant : control.StateSpace, optional
        flexsat's truth plant (e.g. ``Spacecraft(hub, [Mount(beam.truncated(...), ...)]).plant(
        tip_deflection=True)``, the runner's truth); its outputs are compared by name.

    Returns
    -------
    SlewComparison
    """
    if truth_plant is not None and not isinstance(truth_plant, control.StateSpace):
        raise TypeError(f"truth_plant must be a control.StateSpace or None; got "
                        f"{type(truth_plant).__name__}")
    basilisk = simulate_slew(spacecraft, controller, angle, slew_time, duration=duration,
                             sample_time=sample_time, dt=dt, chains=chains,
                             disturbances=disturbances, reaction_wheel=reaction_wheel,
                             max_seconds=max_seconds, axis=axis, rigid_above=rigid_above,
                             accurate_up_to=accurate_up_to)
    kwargs = dict(duration=duration, sample_time=basilisk.sample_time, disturbances=disturbances,
                  axis=axis)
    chain = linear_slew(basilisk.layout.spacecraft, controller, angle, slew_time, **kwargs)
    differences = {"basilisk_vs_chain": compare(basilisk.response, chain)}
    free = None
    if any("torsion" in a.held for a in basilisk.layout.appendages):
        free = linear_slew(chain_spacecraft(spacecraft, chains), controller, angle, slew_time,
                           **kwargs)
        differences["held_vs_chain"] = compare(chain, free)
    truth = None
    if truth_plant is not None:
        truth = linear_slew(spacecraft, controller, angle, slew_time, plant=truth_plant, **kwargs)
        differences["basilisk_vs_truth"] = compare(basilisk.response, truth)
        differences["chain_vs_truth"] = compare(chain, truth)
    return SlewComparison(basilisk, chain, truth, differences, free)
