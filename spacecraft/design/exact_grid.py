"""The frequency grid of the exact reference: every coupled mode of a spacecraft with
distributed appendages resolved, planar or three-axis, located on a finite model of it.

The exact frequency response through W (W6) is evaluated on this grid, and the exact-beam
verdict (:func:`spacecraft.design.verdicts.exact_loop_verdict`) counts the encirclements of
det(I + L) on it and brackets the margins there; both need every lightly damped resonance
resolved, so the modes are located first, on :func:`locating_spacecraft`, each distributed
beam replaced by its undamped Craig-Bampton truncation (:func:`locator_model`).

References
----------
.. [1] R. R. Craig, M. C. C. Bampton, "Coupling of substructures for dynamic analyses", AIAA J.
   6(7), 1968: a truncation to n fixed-interface modes represents the appendage up to about its
   n-th clamped frequency.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..dynamics.coupling import Spacecraft
from .fidelity import clamped_frequencies

__all__ = ["POINTS_PER_DECADE", "POINTS_PER_MODE", "EXTRA_LOCATOR_MODES", "exact_grid",
           "locating_spacecraft", "locator_model"]

#: The exact reference's frequency grid (:func:`exact_grid`): points per decade,
#: points across each coupled mode's half-power band, and clamped modes beyond the top of the
#: grid in the truncation that locates the modes.
POINTS_PER_DECADE = 100
POINTS_PER_MODE = 60
EXTRA_LOCATOR_MODES = 2


def exact_grid(spacecraft: Spacecraft, bandwidth: float, *,
               points_per_decade: int = POINTS_PER_DECADE, points_per_mode: int = POINTS_PER_MODE,
               locating: Spacecraft | None = None) -> np.ndarray:
    """Frequencies [rad/s] of the exact reference of a spacecraft, every coupled mode resolved,
    planar or three-axis.

    Logarithmic from 1e-3 to 1e3 times the design bandwidth wb (``points_per_decade``), plus
    ``points_per_mode`` points ``w_k (1 + zeta tan(t))``, t evenly in [-1.5, 1.5] (an even
    count: no point exactly on an undamped mode), across every coupled mode w_k below 1e3 wb,
    zeta the largest modal damping ratio of the appendages (at least 1e-4): the Nyquist count
    of a loop needs the phase of det(I + L) through each resonance, and the margins' crossings
    bracketed (they are then found on the exact loop function itself,
    :func:`spacecraft.design.verdicts.exact_loop_verdict`). The modes are located on the
    spacecraft with every distributed beam replaced by its undamped Craig-Bampton truncation
    with :data:`EXTRA_LOCATOR_MODES` modes more than its clamped modes below 1e3 wb
    (:func:`locator_model`; three axes: of every motion, both bending planes, torsion and
    axial, as a three-axis truncation ranks them): two clamped modes beyond the top put the
    located frequencies within a small fraction of the half-power band 2 zeta of the exact
    coupled ones (the tests check it), at a fraction of the cost of the exact
    Wittrick-Williams roots.

    Parameters
    ----------
    spacecraft : Spacecraft
        Hub with its distributed appendages (finite ones are used as they are).
    bandwidth : float, rad/s
        The design bandwidth wb (the fastest rigid-body closed-loop natural frequency).
    points_per_decade, points_per_mode : int
    locating : Spacecraft, optional
        The finite spacecraft that locates the modes, :func:`locating_spacecraft` up to 1e3 wb
        (built here if not given; a run keeps it for its verdicts).
    """
    w_lo, w_hi = bandwidth * 1e-3, bandwidth * 1e3
    located = locating if locating is not None else locating_spacecraft(spacecraft, w_hi)
    modes = located.frequencies()[located.n_rigid:]    # the shapes are not needed
    modes = modes[modes < w_hi]
    # a beam's damping ratio, or modal data's largest
    zeta = max([getattr(m.appendage, "damping_ratio", 0.0) for m in spacecraft.mounts]
               + [float(np.max(m.appendage.damping_ratios)) for m in spacecraft.mounts
                  if hasattr(m.appendage, "damping_ratios")] + [1e-4])
    n_log = int(round(points_per_decade * math.log10(w_hi / w_lo)))
    spread = np.tan(np.linspace(-1.5, 1.5, points_per_mode))
    omega = np.unique(np.concatenate([np.geomspace(w_lo, w_hi, n_log), modes]
                                     + [w * (1.0 + zeta * spread) for w in modes]))
    return omega[(omega > 0) & (omega <= w_hi)]


def locating_spacecraft(spacecraft: Spacecraft, w_hi: float, *,
                        locator: Callable | None = None) -> Spacecraft:
    """The finite spacecraft that locates the coupled modes (and a loop's resonances) of one
    with distributed appendages below w_hi [rad/s]: each appendage replaced by its
    :func:`locator_model` (``locator(appendage, w_hi, three_axis)``, default that)."""
    locator = locator or locator_model
    three_axis = bool(spacecraft.three_axis)
    return Spacecraft(spacecraft.hub, [m.with_appendage(locator(m.appendage, w_hi, three_axis))
                                       for m in spacecraft.mounts])


def locator_model(appendage, w_hi: float, three_axis: bool = False):
    """An appendage's model that locates its coupled modes below w_hi [rad/s]: a distributed
    beam's undamped Craig-Bampton truncation (its clamped modes below w_hi, of every motion in
    three axes, and EXTRA_LOCATOR_MODES more), any other model as it is."""
    if not hasattr(appendage, "cantilever_frequencies") or not hasattr(appendage, "truncated"):
        return appendage
    beam = appendage.undamped() if hasattr(appendage, "undamped") else appendage
    n = clamped_frequencies(beam, w_hi, three_axis=three_axis).size
    n += EXTRA_LOCATOR_MODES - 1        # the list ends with the first mode above w_hi
    return beam.truncated(n, method="craig-bampton")
