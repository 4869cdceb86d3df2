"""The design loop: from a scene's spacecraft to tuned controllers, closed loops and verdicts.

:mod:`.models` builds the models a scene needs once (beams, truth truncations, design chains,
spacecraft, plants, exact references), choosing the truth model's fidelity with
:mod:`.fidelity`; :mod:`.tuning` tunes the controllers on the design plant; :mod:`.responses`
simulates the manoeuvre; :mod:`.verdicts` judges each loop (stability, margins, warnings);
:mod:`.loop` is the design loop itself (:class:`DesignLoop`, the one evaluator; :func:`run`
runs a scene's); :mod:`.tables` gives the paper's
equivalence tables; :mod:`.naming` the one name and colour of each model and loop;
:mod:`.simulators` runs the manoeuvre in Basilisk beside flexsat's prediction.
"""

from .loop import ClosedLoops, DesignLoop, RunResult, RunStats, run

__all__ = ["DesignLoop", "ClosedLoops", "RunResult", "RunStats", "run"]
