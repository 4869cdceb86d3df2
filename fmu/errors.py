"""Exceptions of the fmu package.

The package defines its own small hierarchy rather than importing one from another flexsat
package (the fmu package imports no other package of ours).
"""

__all__ = ["FMUError", "FMUBuildError", "FMUCompilerError", "CosimulationError"]


class FMUError(Exception):
    """Base class of every error raised by the fmu package."""


class FMUBuildError(FMUError):
    """The system cannot be exported as an FMU, or the FMU could not be built.

    Raised for input the FMU cannot represent (a non-LTI or discrete-time system, NaN or
    infinite matrices, duplicate or invalid signal names) and for a failed build (no C
    compiler, a compiler error, a binary that fails the check every FMU undergoes before it
    is written, see :mod:`fmu.verify`). The message says what to do.
    """


class FMUCompilerError(FMUBuildError):
    """The C compiler does not work: it fails on a trivial C file too (an error of the
    environment, not of the exported code). The message names the compiler and where it came
    from (``compiler=``, ``$CC`` or PATH)."""


class CosimulationError(FMUError):
    """An FMU call failed during co-simulation, or the FMUs cannot be connected."""
