"""Appendage models: the exact distributed beam, its truncations, hinged chains, equivalence."""

from .beam import Beam, characteristic_roots
from .interface import (Appendage, ConvergenceError, FiniteAppendage, FlexsatError, RootModel)
from .modal import ModalBeam

__all__ = [
    "Appendage", "Beam", "ConvergenceError", "FiniteAppendage", "FlexsatError", "ModalBeam",
    "RootModel", "characteristic_roots",
]
