"""flexsat.fmu: FMI 2.0 and FMI 3.0 export of python-control StateSpace systems,
co-simulation and SSP system descriptions.

Public API
----------
export
    Write an FMU (FMI 2.0 or 3.0; Model Exchange + Co-Simulation for a continuous-time
    system, Co-Simulation for a sampled one; compiled for this platform or sources only).
cosimulate
    Fixed-step co-simulation of a plant FMU with a controller FMU.
write_ssp, cosimulate_ssp
    An SSP file connecting a plant FMU and a controller FMU, and its co-simulation.
FMUError, FMUBuildError, CosimulationError
    Exceptions.
limits
    The documented limits on the work of an export or a co-simulation (module constants).

Object files of the fixed C templates are cached on disk (``$FLEXSAT_CACHE_DIR``, else
``$XDG_CACHE_HOME/flexsat``, else ``~/.cache/flexsat``; see :mod:`fmu.cache`).
"""

from . import limits
from .cosim import Signal, cosimulate
from .errors import CosimulationError, FMUBuildError, FMUCompilerError, FMUError
from .export import DEFAULT_STEP, DEFAULT_STOP_TIME, FMI_VERSIONS, export
from .ssp import cosimulate_ssp, write_ssp
from .units import SI_UNITS, guess_unit

__all__ = ["export", "cosimulate", "write_ssp", "cosimulate_ssp", "Signal", "FMUError", "FMUCompilerError",
           "FMUBuildError", "CosimulationError", "DEFAULT_STEP", "DEFAULT_STOP_TIME",
           "FMI_VERSIONS", "SI_UNITS", "guess_unit", "limits"]
