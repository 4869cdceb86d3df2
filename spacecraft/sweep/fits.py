r"""Equivalent chains of uniform beams by scaling one dimensionless fit.

A uniform free-free Euler-Bernoulli beam is fixed by its length L [m], bending stiffness EJ
[N m^2] and linear density rho [kg/m]. In the units L, m = rho L and t0 = sqrt(rho L^4 / EJ)
every such beam is the same beam (length 1, mass 1, EJ = 1), so a fitted chain of any of them is
the unit beam's fitted chain in those units: body lengths and centre-of-mass offsets scale with
L, masses with rho L, inertias with rho L^3 (= m L^2), hinge stiffnesses with EJ / L, and every
frequency (poles, zeros of W_r) with 1/t0 = sqrt(EJ / (rho L^4)). The fits of
:func:`appendages.equivalence.fit_chain` solve equations stated in these dimensionless terms
(log-frequency ratios to the beam's own targets, length fractions, mass fractions), so the
scaled unit fit solves the fit's equations for every beam.

A sweep therefore fits each ``(n_bodies, match)`` once, on the unit beam, and scales it per
sample (microseconds instead of 0.03 s for ``"frequencies"`` and 0.5-2 s for
``"poles-and-zeros"``). How close the scaled chain is to a fresh fit of the sample's beam
(``tests/test_sweep_fits.py``):

* ``match="frequencies"``: the fit's unknowns are determined (n - 1 equations in n - 1
  unknowns), and the two chains agree to round-off (1e-14 measured; tested to 1e-10);
* ``match="poles-and-zeros"``: least squares over 5 n - 5 parameters whose minimum lies in a
  flat valley; a fresh fit at another scale stops elsewhere in that valley (body masses and
  lengths up to 1.2 % apart, measured for three and four bodies) with the same poles and zeros
  to 3e-7 and the same cost to 1e-7: the fitted quantities agree to the fit's tolerance, the
  parametrisation does not. The scaled chain is as good a fit (its errors against the beam are
  the unit fit's, exactly, at every scale).

The hinge damping of a damped beam (modal damping ratio zeta) is the runner's:
``2 zeta c_k / w_1`` with w_1 the chain's first frequency (stiffness-proportional damping with
ratio zeta at the first mode).
"""

from __future__ import annotations

import math
import warnings

__all__ = ["unit_fit", "scaled_chain", "with_beam_damping", "FitTemplates"]


def unit_fit(n_bodies: int, match: str):
    """The chain fitted to the unit beam (L = 1 m, EJ = 1 N m^2, rho = 1 kg/m), undamped."""
    from appendages import Beam
    from appendages.equivalence import fit_chain

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return fit_chain(Beam(1.0, 1.0, 1.0), n_bodies, match=match)


def scaled_chain(unit, beam):
    """The unit fit scaled to a uniform beam (undamped; see the module docstring).

    Parameters
    ----------
    unit : appendages.HingedChain
        A chain of the unit beam (:func:`unit_fit`), rigid root.
    beam : appendages.Beam
        Uniform beam: ``length`` [m], ``bending_stiffness`` [N m^2], ``linear_density`` [kg/m].

    Returns
    -------
    appendages.HingedChain
    """
    from appendages.chain import HingedChain

    L, EJ, rho = float(beam.length), float(beam.bending_stiffness), float(beam.linear_density)
    return HingedChain(unit.lengths * L, unit.masses * (rho * L), unit.inertias * (rho * L**3),
                       unit.hinge_stiffnesses * (EJ / L), com_offsets=unit.com_offsets * L,
                       root=unit.root)


def with_beam_damping(chain, damping_ratio: float):
    """The chain with hinge dampings ``2 zeta c_k / w_1`` (the runner's rule; zeta = 0: as is).

    Parameters
    ----------
    chain : appendages.HingedChain
        Undamped chain.
    damping_ratio : float
        The beam's modal damping ratio zeta [-].
    """
    from appendages.chain import HingedChain

    if damping_ratio == 0.0:
        return chain
    w1 = float(chain.poles()[0])
    return HingedChain(chain.lengths, chain.masses, chain.inertias, chain.hinge_stiffnesses,
                       hinge_dampings=2.0 * damping_ratio * chain.hinge_stiffnesses / w1,
                       com_offsets=chain.com_offsets, root=chain.root)


class FitTemplates:
    """Unit fits per ``(n_bodies, match)``, computed on first use and kept (picklable).

    Built once on the client and shipped to the workers, so that no worker fits a chain.
    """

    def __init__(self):
        self._fits: dict = {}

    def prepare(self, n_bodies: int, match: str) -> None:
        """Fit ``(n_bodies, match)`` now if it is not yet known."""
        key = (int(n_bodies), match)
        if key not in self._fits:
            self._fits[key] = unit_fit(*key)

    def chain(self, beam, n_bodies: int, match: str):
        """The damped chain of ``beam`` (a fresh unit fit the first time a key is asked)."""
        self.prepare(n_bodies, match)
        chain = scaled_chain(self._fits[(int(n_bodies), match)], beam)
        return with_beam_damping(chain, float(beam.damping_ratio))

    def keys(self) -> list:
        """The ``(n_bodies, match)`` pairs fitted so far."""
        return sorted(self._fits)

    @staticmethod
    def frequency_scale(beam) -> float:
        """1/t0 = sqrt(EJ / (rho L^4)) [rad/s]: the unit fit's frequencies times this."""
        return math.sqrt(beam.bending_stiffness / (beam.linear_density * beam.length**4))

    def __repr__(self) -> str:
        return f"FitTemplates({self.keys()})"

