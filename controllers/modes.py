"""Modal properties of a plant: rigid-body inertia and flexible modes of a channel."""
from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np

from .frequency import _ModalEvaluator, _evaluator
from .signals import THETA, TORQUE, _check_plant, _require_signal

__all__ = ["FlexibleMode", "rigid_body_inertia", "flexible_modes"]


@dataclass(frozen=True)
class FlexibleMode:
    """One flexible mode of a plant channel.

    Attributes
    ----------
    frequency : float, rad/s
        Undamped natural frequency |lambda|.
    damping_ratio : float
        -Re(lambda) / |lambda|.
    residue : complex
        Residue r of the channel's transfer function at lambda (the term r / (s - lambda)),
        units of output / (input * s).
    participation : float
        2 |r| omega J: for a collocated modal form phi^2 / (s^2 + 2 zeta omega s + omega^2) this is
        phi^2 J, the fraction of the total inertia that takes part in the mode.
    """

    frequency: float
    damping_ratio: float
    residue: complex
    participation: float


def _rigid_gain(ev: _ModalEvaluator) -> tuple[complex, complex]:
    """Coefficients (a1, a2) of the singular part a1/s + a2/s^2 at s = 0 of a SISO evaluator.

    With the rigid block T11 nilpotent of index 2, (sI - T11)^-1 = I/s + T11/s^2, so
    a1 = C1 B1 and a2 = C1 T11 B1.
    """
    if ev.k == 0:
        return 0j, 0j
    a1 = (ev.C1 @ ev.B1)[0, 0]
    a2 = (ev.C1 @ ev.T11 @ ev.B1)[0, 0]
    return a1, a2


def rigid_body_inertia(plant: control.StateSpace) -> float:
    """Total inertia J [kg*m^2] seen by the torque: lim_{s->0} s^2 theta(s)/torque(s) = 1/J.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous-time free-floating plant with input ``'torque'`` and output ``'theta'``.

    Returns
    -------
    float
        J in kg*m^2 (about the system's centre of mass for a free-floating spacecraft).

    Raises
    ------
    ValueError
        If the channel torque -> theta has no rigid-body double integrator.

    References
    ----------
    Low-frequency limit of the free-floating plant theta/torque -> 1/(J s^2); e.g. P. C. Hughes,
    Spacecraft Attitude Dynamics, Wiley 1986, ch. 12 (hybrid coordinates).
    """
    _check_plant(plant)
    ev = _evaluator(plant, [TORQUE], [THETA])
    a1, a2 = _rigid_gain(ev)
    scale = abs(a2) if a2 else 1.0
    # a frequency scale to compare the 1/s and 1/s^2 coefficients: a1/a2 is in rad/s
    w_scale = math.sqrt(max(np.linalg.norm(ev.A, 1), 1e-300))
    nilpotent_ok = ev.k == 0 or np.linalg.norm(ev.T11 @ ev.T11) <= 1e-6 * max(
        np.linalg.norm(ev.T11), 1e-300)
    if (ev.k == 0 or not nilpotent_ok or abs(a2.imag) > 1e-8 * scale or a2.real <= 0
            or abs(a1) > 1e-6 * scale * w_scale):
        raise ValueError(
            "plant must be free-floating: the channel torque -> theta needs a rigid-body double "
            f"integrator 1/(J s^2) with J > 0 [kg*m^2]; got singular part {a1:.3g}/s + {a2:.3g}/s^2 "
            f"({ev.k} eigenvalue(s) of A near zero)")
    return float(1.0 / a2.real)


def flexible_modes(plant: control.StateSpace, *, input: str = TORQUE, output: str = THETA,
                   min_participation: float = 1e-9) -> list[FlexibleMode]:
    """Flexible (lightly damped, complex) modes visible in one channel of a plant.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous-time plant with named signals.
    input, output : str
        Channel (default torque -> theta).
    min_participation : float
        Modes whose participation (see :class:`FlexibleMode`) is below this are dropped
        (uncontrollable or unobservable in the channel, e.g. symmetric modes of two wings).

    Returns
    -------
    list of FlexibleMode
        Sorted by frequency, one entry per complex-conjugate pair.
    """
    _check_plant(plant)
    _require_signal(plant, input, "input", "plant")
    _require_signal(plant, output, "output", "plant")
    ev = _evaluator(plant, [input], [output])
    try:
        J = rigid_body_inertia(plant)
    except ValueError:
        J = 1.0
    if not ev.modal:
        lam, V = np.linalg.eig(plant.A)
        raise ValueError("plant A is defective outside its rigid-body block; cannot list modes "
                         f"(eigenvalues {lam[:6]}...)")
    modes = []
    for lam, c, b in zip(ev.lam, ev.Cm[0], ev.Bm[:, 0]):
        if lam.imag <= 0:
            continue
        w = abs(lam)
        r = complex(c * b)
        participation = 2.0 * abs(r) * w * J
        if participation < min_participation:
            continue
        modes.append(FlexibleMode(float(w), float(-lam.real / w), r, float(participation)))
    return sorted(modes, key=lambda m: m.frequency)
