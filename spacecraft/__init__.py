"""The spacecraft: a rigid hub coupled to appendages through the W-matrix interface."""

from .coupling import SecondOrderModel, Spacecraft
from .hub import Hub, Mount

__all__ = ["Hub", "Mount", "SecondOrderModel", "Spacecraft"]
