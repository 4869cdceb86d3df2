"""Appendage models: the exact distributed beam, its truncations, hinged chains, equivalence."""

from . import equivalence, limits
from .beam import Beam, characteristic_roots
from .chain import MOLENAAR_K, HingedChain
from .equivalence import (EquivalenceResult, FitWarning, ModelQuantities, criterion, fit_chain,
                          spectral_errors)
from .interface import (Appendage, ConvergenceError, FiniteAppendage, FlexsatError, RootModel)
from .limits import LimitError
from .modal import ModalBeam
from .selection import ModelChoice, cheapest_model

__all__ = [
    "Appendage", "Beam", "ConvergenceError", "EquivalenceResult", "FiniteAppendage",
    "FitWarning", "FlexsatError", "HingedChain", "LimitError", "MOLENAAR_K", "ModalBeam", "ModelChoice",
    "ModelQuantities", "RootModel", "characteristic_roots", "cheapest_model", "criterion",
    "equivalence", "fit_chain", "limits", "spectral_errors",
]
