"""The stability guarantee of a designed loop: its margin, and the modes it leaves out.

Stability margin of a design
    Every controller this package designs (:func:`controllers.pd`, :func:`controllers.lqr`)
    comes with a guarantee on its design plant: every closed-loop pole the loop can influence
    has Re(s) <= -alpha, alpha = MARGIN * omega_s, where omega_s [rad/s] is the spectral scale
    of the loop (the largest |s| of its poles, of the plant's modes and of the design's
    rigid-body bandwidth); a digital loop's poles z satisfy |z| <= exp(-alpha T). MARGIN = 1e-13
    is about 450 eps: the computed eigenvalues of a loop carry round-off of about
    kappa eps ||A|| (kappa the eigenvalue's condition number, ||A|| ~ omega_s for the balanced
    modal matrices used here), so a pole at Re <= -alpha is resolved as stable whatever the
    order of the floating-point sums (the BLAS threads), while an undamped flexible mode whose
    damping by the loop is at round-off (Re ~ +-1e-13 rad/s on hub + 40-mode beam plants) is not
    mistaken for a stable one. alpha is a numerical margin, not a robustness margin: the
    damping the loop really adds is what the design (weights, natural frequency) asks for.
    ||A|| ~ omega_s fails for high-gain loops (estimator gains ~ w_e^2 = 4e10 at w_e = 1e5
    rad/s): there a regulator and an estimator pole nearly coincide on a transmission zero
    and the loop's computed pair moves by ~1e-7 1/s, far above alpha. The designs therefore
    check the loop's own poles, and :func:`controllers.lqr` raises its degree of stability
    above the round-off it measures there (or refuses, naming the mode).

References
----------
J. H. Wilkinson, The Algebraic Eigenvalue Problem, 1965, ch. 2 (eigenvalue condition numbers:
round-off perturbs a simple eigenvalue by about kappa eps ||A||); B. D. O. Anderson, J. B.
Moore, Optimal Control: Linear Quadratic Methods, 1990, sec. 3.5 (prescribed degree of
stability, used by :func:`controllers.lqr` to reach the margin).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from .arguments import user_stacklevel

__all__ = ["MARGIN", "MAX_SCALE_RATIO", "RemovedMode", "RemovedModesWarning", "continuous_poles",
           "stability_margin", "warn_removed_modes"]

#: Relative stability margin of a designed loop: Re(s) <= -MARGIN * omega_s (module docstring).
MARGIN = 1e-13
#: A loop's spectral scale may exceed the plant's lowest flexible frequency (and a design's
#: rigid-body bandwidth) at most this many times: beyond, alpha = MARGIN * scale passes 1e-3 of
#: that frequency and the loop's poles there cannot be resolved against the margin.
MAX_SCALE_RATIO = 1e10


def stability_margin(scale: float) -> float:
    """alpha = MARGIN * scale [1/s]: the margin of a loop whose spectral scale is ``scale``."""
    return MARGIN * float(scale)


@dataclass(frozen=True)
class RemovedMode:
    """A mode of a design plant that the attitude loop cannot influence.

    Attributes
    ----------
    frequency : float, rad/s
        |lambda| of the mode.
    damping_ratio : float
        -Re(lambda) / |lambda| (0 for an undamped mode).
    participation : float
        Fraction of the inertia taking part in the mode as seen from torque to theta/omega
        (see the module docstring); <= INFLUENCE_TOL.
    multiplicity : int
        Number of modes at this eigenvalue (repeated modes of symmetric appendages).
    reason : str
        Why the loop cannot influence it.
    """

    frequency: float
    damping_ratio: float
    participation: float
    multiplicity: int
    reason: str

    def __str__(self) -> str:
        if self.frequency == 0.0:
            return (f"rigid-body motion, {self.multiplicity} states (participation "
                    f"{self.participation:.2g})")
        times = f" (x{self.multiplicity})" if self.multiplicity > 1 else ""
        return (f"{self.frequency:.6g} rad/s{times} (damping ratio "
                f"{0.0 + self.damping_ratio:.3g}, participation {self.participation:.2g})")


class RemovedModesWarning(UserWarning):
    """A design left modes out of its guarantee: the loop cannot influence them."""


def _describe_modes(modes, limit: int = 6) -> str:
    """'0.467 rad/s (...), 2.86 rad/s (...) and 3 more' (short enough for a message)."""
    text = ", ".join(str(m) for m in modes[:limit])
    return text + (f" and {len(modes) - limit} more" if len(modes) > limit else "")


def warn_removed_modes(what: str, modes, detail: str) -> None:
    """Warn that a design left modes out of its guarantee (:class:`RemovedModesWarning`).

    The warning points at the user's line (the first outside the controllers package); nothing
    is said when ``modes`` is empty.

    Parameters
    ----------
    what : str
        The design that removed them ("pd", "lqr"), the message's start.
    modes : sequence of RemovedMode
        The modes left out, by frequency (the first six are listed).
    detail : str
        Why and with what consequence, for the message.
    """
    if not modes:
        return
    warnings.warn(f"{what}: {len(modes)} mode(s) out of the loop's reach {detail}: "
                  f"{_describe_modes(modes)}", RemovedModesWarning,
                  stacklevel=user_stacklevel())


def continuous_poles(system) -> np.ndarray:
    """The poles of a system in the s-plane [rad/s], a digital one's mapped from the z-plane.

    A digital system's poles z are mapped by ``s = log(z) / T`` (the principal branch: a pole
    in the left half of the z-plane comes back at the Nyquist frequency pi/T); poles at z = 0,
    infinitely fast and deadbeat, are left out.

    Parameters
    ----------
    system : control.StateSpace
        Continuous, or digital with sample time ``T = system.dt`` [s].

    Returns
    -------
    ndarray of complex128
        The eigenvalues of ``system.A`` [rad/s], mapped as above when digital.
    """
    lam = np.linalg.eigvals(system.A) if system.nstates else np.zeros(0, dtype=complex)
    lam = lam.astype(complex)
    if system.isdtime(strict=True):
        lam = np.log(lam[np.abs(lam) > 1e-300]) / float(system.dt)
    return lam
