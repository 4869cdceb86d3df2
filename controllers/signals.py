"""Signal conventions and checks shared by the controllers package.

A plant is a continuous-time ``control.StateSpace`` (or, for the frequency-domain functions, a
``control.FrequencyResponseData``) with input ``'torque'`` [N*m] (possibly other inputs such as
``'disturbance_torque'``) and outputs ``'theta'`` [rad] and ``'omega'`` [rad/s], optionally
``'<appendage>.tip_deflection'`` [m] outputs (DESIGN.md). A controller is a
``control.StateSpace`` with output ``'torque'`` and inputs ``'theta_ref'``, ``'theta'``,
``'omega'`` (torque = controller(inputs), no hidden minus sign). A controller with ``dt`` set is
a digital controller: its loop with a continuous plant is the sampled-data loop (zero-order hold
on the torque, sampled measurements).
"""
from __future__ import annotations

from typing import Sequence

import control
import numpy as np

__all__ = ["TORQUE", "THETA", "OMEGA", "THETA_REF", "TIP_SUFFIX"]

#: Longest echo of a user's value in an error message [characters].
MESSAGE_VALUE_CHARS = 100

TORQUE = "torque"
THETA = "theta"
OMEGA = "omega"
THETA_REF = "theta_ref"
TIP_SUFFIX = "tip_deflection"


def _short(value, limit: int = MESSAGE_VALUE_CHARS) -> str:
    """repr of a value for an error message, cut to about ``limit`` characters."""
    if isinstance(value, float):
        text = f"{value:.6g}"
    else:
        try:
            with np.printoptions(threshold=20, edgeitems=3, precision=6):
                text = repr(value)
        except Exception:  # noqa: BLE001 - a repr that fails must not hide the real error
            text = f"<{type(value).__name__}>"
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _real_number(value, name: str, unit: str) -> float:
    """A real number (not a bool, not a string) as float, or TypeError naming it."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.floating, np.integer)):
        raise TypeError(f"{name} must be a real number [{unit}]; got {type(value).__name__} "
                        f"{_short(value)}")
    return float(value)


def _labels(system, kind: str) -> list[str]:
    return list(system.input_labels if kind == "input" else system.output_labels)


def _require_signal(system, name: str, kind: str, what: str) -> int:
    labels = _labels(system, kind)
    if name not in labels:
        raise ValueError(f"{what} must have an {kind} named {name!r}; got {kind}s "
                         f"{_short(labels)}")
    return labels.index(name)


def _check_plant(plant, what: str = "plant", *, allow_frd: bool = False) -> None:
    allowed = (control.StateSpace, control.FrequencyResponseData) if allow_frd else (
        control.StateSpace,)
    if not isinstance(plant, allowed):
        expected = " or ".join(t.__name__ for t in allowed)
        raise TypeError(f"{what} must be a control.{expected}; got {type(plant).__name__}")
    if isinstance(plant, control.StateSpace) and not plant.isctime(strict=True):
        raise ValueError(f"{what} must be continuous-time (dt=0); got dt={plant.dt}")
    _require_signal(plant, TORQUE, "input", what)
    if isinstance(plant, control.FrequencyResponseData):
        # an FRD needs one of theta, omega: the other follows from omega = j w theta
        if THETA not in plant.output_labels and OMEGA not in plant.output_labels:
            raise ValueError(f"{what} must have an output named 'theta' or 'omega'; got outputs "
                             f"{_short(list(plant.output_labels))}")
        return
    _require_signal(plant, THETA, "output", what)
    _require_signal(plant, OMEGA, "output", what)


def _check_controller(controller, what: str = "controller") -> None:
    if not isinstance(controller, control.StateSpace):
        raise TypeError(f"{what} must be a control.StateSpace; got {type(controller).__name__}")
    if controller.noutputs != 1 or controller.output_labels[0] != TORQUE:
        raise ValueError(f"{what} must have exactly one output named 'torque'; got outputs "
                         f"{_short(list(controller.output_labels))}")
    if controller.dt is True:  # None: a static gain, usable in either time base
        raise ValueError(f"{what} must be continuous (dt=0) or have a sample time dt > 0 [s]; "
                         f"got dt={controller.dt}")


def _measurements(plant, controller) -> list[str]:
    """Controller inputs that are plant outputs (the fed-back signals)."""
    outputs = _labels(plant, "output")
    measured = [name for name in controller.input_labels if name in outputs]
    if not measured:
        raise ValueError(f"controller inputs {_short(list(controller.input_labels))} contain "
                         f"none of the plant outputs {_short(outputs)}: nothing is fed back")
    return measured


def _reference_inputs(controller, plant_outputs: Sequence[str]) -> list[str]:
    others = [n for n in controller.input_labels if n not in plant_outputs]
    bad = [n for n in others if "ref" not in n]
    if bad:
        raise ValueError(f"controller inputs {_short(bad)} are neither plant outputs nor "
                         "reference inputs (names containing 'ref')")
    return others


def _is_digital(controller) -> bool:
    return bool(controller.isdtime(strict=True))
