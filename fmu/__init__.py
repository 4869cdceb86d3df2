"""flexsat.fmu: FMI 2.0 export of python-control StateSpace systems and co-simulation.

Public API
----------
export
    Write an FMU (Model Exchange + Co-Simulation, compiled for this platform).
cosimulate
    Fixed-step co-simulation of a plant FMU with a controller FMU.
FMUError, FMUBuildError, CosimulationError
    Exceptions.
limits
    The documented limits on the work of an export or a co-simulation (module constants).

Object files of the fixed C templates are cached on disk (``$FLEXSAT_CACHE_DIR``, else
``$XDG_CACHE_HOME/flexsat``, else ``~/.cache/flexsat``; see :mod:`fmu.cache`).
"""

from . import limits
from .cosim import Signal, cosimulate
from .errors import CosimulationError, FMUBuildError, FMUError
from .export import DEFAULT_STEP, DEFAULT_STOP_TIME, export
from .units import SI_UNITS, guess_unit

__all__ = ["export", "cosimulate", "Signal", "FMUError", "FMUBuildError", "CosimulationError",
           "DEFAULT_STEP", "DEFAULT_STOP_TIME", "SI_UNITS", "guess_unit", "limits"]
