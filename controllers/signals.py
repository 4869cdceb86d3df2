"""Signal conventions and checks shared by the controllers package.

A plant is a continuous-time ``control.StateSpace`` (or, for the frequency-domain functions, a
``control.FrequencyResponseData``) with named signals (DESIGN.md), in one of two conventions:

planar (single axis)
    input ``'torque'`` [N*m], outputs ``'theta'`` [rad] and ``'omega'`` [rad/s]; a controller
    has output ``'torque'`` and inputs ``'theta_ref'``, ``'theta'``, ``'omega'``.
three-axis
    inputs ``'torque_x'``, ``'torque_y'``, ``'torque_z'`` [N*m] (hub axes), outputs
    ``'theta_x'``, ``'theta_y'``, ``'theta_z'`` [rad] (small angles) and ``'omega_x'``,
    ``'omega_y'``, ``'omega_z'`` [rad/s]; a controller has outputs ``'torque_x'``,
    ``'torque_y'``, ``'torque_z'`` and inputs ``'theta_ref_x'``, ``'theta_ref_y'``,
    ``'theta_ref_z'``, ``'theta_x'``, ..., ``'omega_z'``.

Either may have other inputs (``'disturbance_torque'``, forces) and outputs (tip deflections,
``'*tip_deflection'`` [m], or any other tip motion). torque = controller(inputs): no hidden minus
sign. Reference inputs are the controller inputs whose names contain ``'ref'`` or ``'ff'``
(``'theta_ref'``; with feedforward also ``'omega_ref'`` [rad/s] and ``'torque_ff'`` [N*m]). A
controller with ``dt`` set is a digital controller: its loop with a continuous plant is the
sampled-data loop (zero-order hold on the torque, sampled measurements).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import control

# MESSAGE_VALUE_CHARS was defined here before it moved to controllers.arguments: still importable
from .arguments import MESSAGE_VALUE_CHARS, describe  # noqa: F401

__all__ = ["TORQUE", "THETA", "OMEGA", "THETA_REF", "OMEGA_REF", "TORQUE_FF", "TIP_SUFFIX",
           "AXES", "Channels", "PLANAR", "THREE_AXIS", "channels", "check_controller",
           "check_pair", "check_plant", "fed_back_signals", "is_digital", "reference_inputs",
           "require_signal", "signal_names", "tip_outputs"]

TORQUE = "torque"
THETA = "theta"
OMEGA = "omega"
THETA_REF = "theta_ref"
#: Rate reference input of a controller with feedforward (three axes: ``omega_ref_x`` ...).
OMEGA_REF = "omega_ref"
#: Feedforward torque input of a controller with feedforward (three axes: ``torque_ff_x`` ...).
TORQUE_FF = "torque_ff"
TIP_SUFFIX = "tip_deflection"
#: Hub axes of a three-axis plant, in the order of its signals.
AXES = ("x", "y", "z")


@dataclass(frozen=True)
class Channels:
    """The attitude signals of one convention (see the module docstring).

    Attributes
    ----------
    torques, thetas, omegas, refs : tuple of str
        Actuator torques, attitude and rate measurements, attitude references, one per axis.
    axes : tuple of str
        Axis names (``('',)`` for the planar plant, ``('x', 'y', 'z')``).
    """

    torques: tuple[str, ...]
    thetas: tuple[str, ...]
    omegas: tuple[str, ...]
    refs: tuple[str, ...]
    axes: tuple[str, ...]

    @property
    def n_axes(self) -> int:
        """1 (planar) or 3."""
        return len(self.torques)

    @property
    def mimo(self) -> bool:
        """True for the three-axis convention."""
        return len(self.torques) > 1

    @property
    def measurements(self) -> tuple[str, ...]:
        """The thetas, then the omegas."""
        return self.thetas + self.omegas

    @property
    def omega_refs(self) -> tuple[str, ...]:
        """Rate references, one per axis (``'omega_ref'`` or ``'omega_ref_x'``...)."""
        return tuple(OMEGA_REF + self.suffix(i) for i in range(self.n_axes))

    @property
    def feedforwards(self) -> tuple[str, ...]:
        """Feedforward torques, one per axis (``'torque_ff'`` or ``'torque_ff_x'``...)."""
        return tuple(TORQUE_FF + self.suffix(i) for i in range(self.n_axes))

    def suffix(self, i: int) -> str:
        """'' (planar) or '_x', '_y', '_z': the ending of axis i's metric names."""
        return f"_{self.axes[i]}" if self.mimo else ""


PLANAR = Channels((TORQUE,), (THETA,), (OMEGA,), (THETA_REF,), ("",))
THREE_AXIS = Channels(tuple(f"{TORQUE}_{a}" for a in AXES), tuple(f"{THETA}_{a}" for a in AXES),
                      tuple(f"{OMEGA}_{a}" for a in AXES), tuple(f"{THETA_REF}_{a}" for a in AXES),
                      AXES)


def tip_outputs(labels) -> list[str]:
    """The tip-motion outputs among ``labels``: names ending in ``'tip_deflection'`` (planar)
    or holding ``'tip_'`` (three-axis tip motions such as ``'wing_tip_deflection_z'`` or
    ``'wing_tip_twist'``)."""
    return [n for n in labels if n.endswith(TIP_SUFFIX) or "tip_" in n]


def channels(system, kind: str = "plant") -> Channels:
    """The convention of a plant (by its inputs) or a controller (by its outputs).

    Raises
    ------
    ValueError
        Neither ``'torque'`` nor all of ``'torque_x'``, ``'torque_y'``, ``'torque_z'``.
    """
    names = list(system.input_labels if kind == "plant" else system.output_labels)
    signal = "input" if kind == "plant" else "output"
    if TORQUE in names:
        return PLANAR
    if all(name in names for name in THREE_AXIS.torques):
        return THREE_AXIS
    raise ValueError(f"{kind} must have an {signal} named 'torque' (planar) or {signal}s "
                     f"'torque_x', 'torque_y', 'torque_z' (three-axis); got {signal}s "
                     f"{describe(names)}")


def signal_names(system, kind: str) -> list[str]:
    """The names of a system's inputs (``kind="input"``) or outputs (any other ``kind``)."""
    return list(system.input_labels if kind == "input" else system.output_labels)


def require_signal(system, name: str, kind: str, what: str) -> int:
    """The index of the ``kind`` ("input" or "output") signal ``name`` of ``system``.

    Raises
    ------
    ValueError
        It has no such signal (the message calls the system ``what`` and lists its signals).
    """
    labels = signal_names(system, kind)
    if name not in labels:
        raise ValueError(f"{what} must have an {kind} named {name!r}; got {kind}s "
                         f"{describe(labels)}")
    return labels.index(name)


def check_plant(plant, what: str = "plant", *, allow_frd: bool = False) -> Channels:
    """Check a plant's type, time base and signals (module docstring); return its convention.

    Parameters
    ----------
    plant : control.StateSpace or control.FrequencyResponseData
        Continuous-time, with the torque inputs and the attitude and rate outputs of its
        convention (an FRD needs one of theta and omega per axis).
    what : str
        Its name in the messages (the caller's parameter).
    allow_frd : bool
        Accept a ``control.FrequencyResponseData`` (frequency-domain functions).

    Raises
    ------
    TypeError
        Not a StateSpace (or FrequencyResponseData when allowed).
    ValueError
        Discrete-time, or a signal of the convention missing.
    """
    allowed = (control.StateSpace, control.FrequencyResponseData) if allow_frd else (
        control.StateSpace,)
    if not isinstance(plant, allowed):
        expected = " or ".join(t.__name__ for t in allowed)
        raise TypeError(f"{what} must be a control.{expected}; got {type(plant).__name__}")
    if isinstance(plant, control.StateSpace) and not plant.isctime(strict=True):
        raise ValueError(f"{what} must be continuous-time (dt=0); got dt={plant.dt}")
    labels = signal_names(plant, "input")
    if TORQUE not in labels and not all(n in labels for n in THREE_AXIS.torques):
        raise ValueError(f"{what} must have an input named 'torque' (or inputs 'torque_x', "
                         f"'torque_y', 'torque_z' for three axes); got inputs {describe(labels)}")
    ch = channels(plant)
    if isinstance(plant, control.FrequencyResponseData):
        # an FRD needs one of theta, omega per axis: the other follows from omega = j w theta
        outputs = list(plant.output_labels)
        for theta, omega in zip(ch.thetas, ch.omegas):
            if theta not in outputs and omega not in outputs:
                raise ValueError(f"{what} must have an output named {theta!r} or {omega!r}; "
                                 f"got outputs {describe(outputs)}")
        return ch
    for name in ch.measurements:
        require_signal(plant, name, "output", what)
    return ch


def check_controller(controller, what: str = "controller") -> Channels:
    """Check a controller's type, outputs and time base; return its convention.

    Parameters
    ----------
    controller : control.StateSpace
        Output ``'torque'`` (planar) or ``'torque_x'``, ``'torque_y'``, ``'torque_z'``;
        continuous (dt = 0), digital (dt > 0 [s]) or a static gain (dt None).
    what : str
        Its name in the messages.

    Raises
    ------
    TypeError
        Not a StateSpace.
    ValueError
        Other outputs, or an unspecified time base (dt True).
    """
    if not isinstance(controller, control.StateSpace):
        raise TypeError(f"{what} must be a control.StateSpace; got {type(controller).__name__}")
    outputs = list(controller.output_labels)
    if outputs == [TORQUE]:
        ch = PLANAR
    elif outputs == list(THREE_AXIS.torques):
        ch = THREE_AXIS
    else:
        raise ValueError(f"{what} must have exactly one output named 'torque' (planar) or the "
                         "outputs 'torque_x', 'torque_y', 'torque_z' (three-axis); got outputs "
                         f"{describe(outputs)}")
    if controller.dt is True:  # None: a static gain, usable in either time base
        raise ValueError(f"{what} must be continuous (dt=0) or have a sample time dt > 0 [s]; "
                         f"got dt={controller.dt}")
    return ch


def check_pair(plant, controller, *, allow_frd: bool = False) -> Channels:
    """Check a plant and a controller (:func:`check_plant`, :func:`check_controller`) and
    that the controller's torques drive the plant's; return their convention.

    Raises
    ------
    ValueError
        A planar controller on a three-axis plant or the reverse, or what the two checks raise.
    """
    ch = check_plant(plant, allow_frd=allow_frd)
    if check_controller(controller) is not ch:
        raise ValueError(f"controller outputs {describe(list(controller.output_labels))} do not "
                         f"drive the plant's torque inputs {describe(list(ch.torques))}")
    return ch


def fed_back_signals(plant, controller) -> list[str]:
    """The controller's inputs that are plant outputs (the fed-back measurements), in the
    controller's order.

    Raises
    ------
    ValueError
        There are none: nothing is fed back.
    """
    outputs = signal_names(plant, "output")
    measured = [name for name in controller.input_labels if name in outputs]
    if not measured:
        raise ValueError(f"controller inputs {describe(list(controller.input_labels))} contain "
                         f"none of the plant outputs {describe(outputs)}: nothing is fed back")
    return measured


def reference_inputs(controller, plant_outputs: Sequence[str]) -> list[str]:
    """The controller's inputs that are not among ``plant_outputs``: its references.

    Raises
    ------
    ValueError
        One of them is no reference (a name holding neither 'ref' nor 'ff'): it would be an
        input the loop leaves unconnected.
    """
    others = [n for n in controller.input_labels if n not in plant_outputs]
    bad = [n for n in others if "ref" not in n and "ff" not in n]
    if bad:
        raise ValueError(f"controller inputs {describe(bad)} are neither plant outputs nor "
                         "reference inputs (names containing 'ref' or 'ff')")
    return others


def is_digital(controller) -> bool:
    """True for a discrete-time system (``dt > 0`` [s]); False for a continuous one or a
    static gain (dt None)."""
    return bool(controller.isdtime(strict=True))
