"""Appendage models: the exact distributed beam, its truncations, hinged chains, equivalence."""

from . import equivalence, limits
from .beam import Beam, characteristic_roots
from .chain import MOLENAAR_K, HingedChain
from .equivalence import (EquivalenceResult, FitWarning, ModelQuantities, criterion, fit_chain,
                          spectral_errors)
from .fit3d import fit_chain_3d
from .errors import ConvergenceError, FlexsatError
from .interface import Appendage, FiniteAppendage, RootModel, three_axis_root_model
from .limits import LimitError
from .modal import ModalBeam
from .modal_data import ModalAppendage
from .modal_file import read_modal_data, write_modal_data
from .nastran import read_nastran
from .rod import Rod
from .selection import ModelChoice, cheapest_model
from .stepped import SteppedBeam
from .tip import TipBody

__all__ = [
    "Appendage", "Beam", "ConvergenceError", "EquivalenceResult", "FiniteAppendage",
    "FitWarning", "FlexsatError", "HingedChain", "LimitError", "MOLENAAR_K", "ModalAppendage",
    "ModalBeam", "ModelChoice",
    "ModelQuantities", "Rod", "RootModel", "SteppedBeam", "TipBody", "characteristic_roots",
    "cheapest_model", "criterion",
    "equivalence", "fit_chain", "fit_chain_3d", "limits", "read_modal_data", "read_nastran",
    "spectral_errors", "three_axis_root_model", "write_modal_data",
]
