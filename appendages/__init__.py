"""Appendage models: the exact distributed beam, its truncations, hinged chains, equivalence."""

from . import equivalence
from .beam import Beam, characteristic_roots
from .chain import HingedChain
from .equivalence import EquivalenceResult, criterion, fit_chain
from .interface import (Appendage, ConvergenceError, FiniteAppendage, FlexsatError, RootModel)
from .modal import ModalBeam

__all__ = [
    "Appendage", "Beam", "ConvergenceError", "EquivalenceResult", "FiniteAppendage",
    "FlexsatError", "HingedChain", "ModalBeam", "RootModel", "characteristic_roots", "criterion",
    "equivalence", "fit_chain",
]
