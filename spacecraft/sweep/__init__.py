"""Sweeps, Monte Carlo and worst cases of the design loop, on Dask.

A ``[sweep]`` table in a scene names scene numbers (key paths) and their distributions; every
sample is a full design-loop evaluation (design on the chain, truth on the beam, the exact beam's
verdict); the samples run in batches on Dask and stream to Parquet; a differential-evolution
search finds the worst stability margin over the box; a report shows histograms, margins against
parameters, a stability map, the probability of instability and the worst case.

Every sample counts: a slew that does not settle or diverges is a result (its time metrics
withheld as the run's report withholds them), a sample that fails is counted apart, as a bound
on the probability of instability; margins are signed (negative: unstable) everywhere; each
design's controller is recorded, and ``worst.toml`` runs that very controller again
(``[controller.given]``).

Planar and three-axis scenes are swept alike: a three-axis sample is the same design loop with
its multiloop verdict (each axis' loop at a time, the disk margin, the return difference I + L;
on the exact beams through W6), its parameters the inertia tensor's entries (kept symmetric),
mount positions and angles, section properties (:mod:`.parameters`); the embedded sweep scene
``three_axis`` is one.

Modules: :mod:`.parameters` (key paths, distributions, sampling), :mod:`.evaluate` (one
sample), :mod:`.execute` (Dask, batches, Parquet, resume, progress), :mod:`.worst` (worst-case
search, ``worst.toml``), :mod:`.report` (statistics, plots, files), :mod:`.runner` (the whole
sweep), :mod:`.command` (``flexsat sweep``). Chains of the samples' beams come from the
runner's fit, memoised per process in dimensionless form (:mod:`appendages.fitting`).

``spacecraft.sweep`` is this package and can be called as the function :func:`sweep`:
``spacecraft.sweep(scene, parameters=..., samples=...)`` returns a pyarrow Table.
"""

import sys
import types

from .parameters import MAX_SAMPLES, Parameter, SweepError, SweepSpec
from .runner import SweepResult, load_sweep, run_sweep, sweep, sweep_scene_path, sweep_scenes

__all__ = ["MAX_SAMPLES", "Parameter", "SweepError", "SweepResult", "SweepSpec", "load_sweep",
           "run_sweep", "sweep", "sweep_scene_path", "sweep_scenes"]


class _CallableModule(types.ModuleType):
    """This package, callable as :func:`sweep` (so ``spacecraft.sweep(...)`` works while
    ``spacecraft.sweep.report`` stays the module)."""

    def __call__(self, *args, **kwargs):
        return sweep(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
