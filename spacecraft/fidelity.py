"""Model fidelity: how many beam modes a scene needs, and which states its signals cannot reach.

Choosing n_modes
    A truncated beam (``beam.truncated(n, method)``) coupled to the hub is accurate enough when,
    for the controller's bandwidth wb and a requested relative tolerance tol,

    1. every coupled natural frequency up to ``bandwidth_factor * wb``, and the first one above
       it (the mode the loop rolls off against, where spillover starts), agrees with the exact
       coupled frequency within tol (exact: Wittrick-Williams on the exact W(s),
       :meth:`Spacecraft.natural_frequencies` with ``exact=True``); and
    2. the gain |theta/torque| agrees with the exact one within tol (relative) on
       the closed-loop-relevant low band ``[wb/10, min(bandwidth_factor*wb, w_1/2, z_1/2)]``,
       w_1 the first exact coupled frequency and z_1 the first anti-resonance of theta/torque
       (the lowest clamped-root frequency of the appendages): below the first resonance and
       anti-resonance a relative error is meaningful whatever the (modelled) damping.

    :func:`choose_n_modes` returns the smallest n that meets both, with the errors of every n
    it tried (a short, monotone search: Craig-Bampton frequencies converge like n**-4).

Dropping what the signals cannot reach
    :meth:`Spacecraft.plant` with ``prune=True`` drops the modes that no input excites or no
    output sees (e.g. the symmetric bending of two symmetric wings under a pure torque); the
    input-output behaviour is unchanged. The runner prunes the truth and design plants of every
    scene unless ``fidelity.prune = false``.

References
----------
.. [1] W. H. Wittrick, F. W. Williams, Q. J. Mech. Appl. Math. 24(3), 1971 (exact frequencies).
.. [2] R. R. Craig, M. C. C. Bampton, AIAA J. 6(7), 1968 (the truncation converging fastest).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import control
import numpy as np

from appendages import limits
from appendages.interface import describe

__all__ = ["FidelityChoice", "choose_n_modes", "low_band", "transfer_theta_torque"]

#: Largest number of modes per beam the search from a tolerance tries (also within the scene's
#: limits.modes), whatever limits.modes allows: Craig-Bampton frequency errors fall like n**-4,
#: so a tolerance that 40 modes miss needs ten times the modes for 1e-4 of it, beyond a search
#: that builds one plant per n (about a second for all 40); give fidelity.n_modes for more.
MAX_MODES = 40


@dataclasses.dataclass(frozen=True)
class FidelityChoice:
    """Outcome of :func:`choose_n_modes`.

    Attributes
    ----------
    n_modes : int
        Bending modes per truncated beam.
    method : str
        Truncation method.
    tolerance : float
        Requested relative accuracy.
    band : tuple of float, rad/s
        Low band where the frequency response had to match (:func:`low_band`).
    reference_frequencies : ndarray, rad/s
        Exact coupled frequencies that had to match.
    trials : list of dict
        For each n tried: ``n_modes``, ``frequency_error`` (max relative), ``gain_error`` (max
        relative on the low band).
    """

    n_modes: int
    method: str
    tolerance: float
    band: tuple
    reference_frequencies: np.ndarray
    trials: list

    def as_dict(self) -> dict:
        """JSON-ready form."""
        return {"n_modes": self.n_modes, "method": self.method, "tolerance": self.tolerance,
                "band": list(self.band),
                "reference_frequencies": self.reference_frequencies.tolist(),
                "trials": self.trials}


def low_band(bandwidth: float, factor: float, first_frequency: float,
             first_zero: float = math.inf) -> tuple[float, float]:
    """``(wb/10, min(factor*wb, w_1/2, z_1/2))`` [rad/s]: where the low-frequency gain must match.

    The upper end never falls below ``wb/5`` (two octaves of band at least).
    """
    top = min(factor * bandwidth, 0.5 * first_frequency, 0.5 * first_zero)
    return bandwidth / 10.0, max(top, bandwidth / 5.0)


def transfer_theta_torque(plant: control.StateSpace, omega: np.ndarray) -> np.ndarray:
    """theta/torque [rad/(N m)] of a state-space plant at j*omega (complex, shape omega.shape)."""
    i_in = list(plant.input_labels).index("torque")
    i_out = list(plant.output_labels).index("theta")
    A = np.asarray(plant.A, dtype=float)
    b = np.asarray(plant.B, dtype=float)[:, i_in]
    c = np.asarray(plant.C, dtype=float)[i_out]
    d = float(np.asarray(plant.D)[i_out, i_in])
    n = A.shape[0]
    s = 1j * np.asarray(omega, dtype=float)
    M = s[:, None, None] * np.eye(n) - A
    return np.linalg.solve(M, np.broadcast_to(b, (s.size, n))[..., None])[..., 0] @ c + d


def choose_n_modes(truncated_plant: Callable[[int], tuple], exact_frequencies: Callable[[int], np.ndarray],
                   exact_response: Callable[[np.ndarray], np.ndarray], *, bandwidth: float,
                   tolerance: float, bandwidth_factor: float = 5.0, method: str = "craig-bampton",
                   first_zero: float = math.inf, n_min: int = 1,
                   n_max: int = MAX_MODES) -> FidelityChoice:
    """The smallest number of beam modes meeting the tolerance near the controller bandwidth.

    Parameters
    ----------
    truncated_plant : callable n -> (coupled frequencies [rad/s], plant StateSpace)
        Hub with every beam truncated to n modes: its first coupled elastic frequencies (as many
        as it has) and its torque-to-theta plant.
    exact_frequencies : callable k -> ndarray
        First k exact coupled elastic frequencies [rad/s].
    exact_response : callable omega -> ndarray
        Exact theta/torque at j*omega [rad/(N m)].
    bandwidth : float, rad/s
        Controller bandwidth (rigid-body closed-loop natural frequency).
    tolerance : float
        Relative accuracy (0 < tolerance < 1).
    bandwidth_factor : float
        Frequencies up to ``bandwidth_factor * bandwidth`` (and the first one above) must match.
    method : str
        Recorded in the result.
    first_zero : float, rad/s
        First anti-resonance of theta/torque (lowest clamped-root appendage frequency).
    n_min, n_max : int
        Search range.

    Returns
    -------
    FidelityChoice

    Raises
    ------
    TypeError, ValueError
        Bad arguments (named); n_max above the ``modes`` limit of :mod:`appendages.limits`
        (a :class:`~appendages.limits.LimitError`); no n up to n_max meeting the tolerance
        (the message names the best error reached).
    """
    for name, value in (("bandwidth", bandwidth), ("tolerance", tolerance),
                        ("bandwidth_factor", bandwidth_factor)):
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
            raise TypeError(f"{name} must be a real number; got {type(value).__name__} "
                            f"{describe(value)}")
    if not (math.isfinite(bandwidth) and bandwidth > 0):
        raise ValueError(f"bandwidth must be positive and finite [rad/s]; got {describe(bandwidth)}")
    if not (0 < tolerance < 1):
        raise ValueError(f"tolerance must lie in (0, 1) [-]; got {describe(tolerance)}")
    if not (math.isfinite(bandwidth_factor) and bandwidth_factor > 0):
        raise ValueError(f"bandwidth_factor must be positive and finite [-]; got "
                         f"{describe(bandwidth_factor)}")
    for name, value in (("n_min", n_min), ("n_max", n_max)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise ValueError(f"{name} must be a positive integer (modes per beam); got "
                             f"{describe(value)}")
    if n_min > n_max:
        raise ValueError(f"n_min must not exceed n_max; got {n_min} > {n_max}")
    limits.check("n_max", int(n_max), "modes", "bending modes per beam")
    w_top = bandwidth_factor * bandwidth
    # exact frequencies up to w_top and the first one above it
    k = 4
    reference = exact_frequencies(k)
    while reference[-1] <= w_top:
        k *= 2
        reference = exact_frequencies(k)
    n_ref = int(np.searchsorted(reference, w_top, side="right")) + 1
    reference = reference[:n_ref]
    band = low_band(bandwidth, bandwidth_factor, float(reference[0]), first_zero)
    omega = np.geomspace(band[0], band[1], 40)
    exact = exact_response(omega)
    trials = []
    n_have = 0
    for n in range(n_min, n_max + 1):
        frequencies, plant = truncated_plant(n)
        n_have = frequencies.size
        if frequencies.size < n_ref:
            trials.append({"n_modes": n, "frequency_error": math.inf, "gain_error": math.inf})
            continue
        f_err = float(np.max(np.abs(frequencies[:n_ref] / reference - 1.0)))
        # gain (magnitude) error: below the first resonance damping changes the phase at
        # first order in zeta but the gain only at second order, so the gain is compared
        g_err = float(np.max(np.abs(np.abs(transfer_theta_torque(plant, omega) / exact) - 1.0)))
        trials.append({"n_modes": n, "frequency_error": f_err, "gain_error": g_err})
        if f_err <= tolerance and g_err <= tolerance:
            return FidelityChoice(n, method, float(tolerance), band, reference, trials)
    if n_have < n_ref:
        # no truncation had the frequencies to compare: a looser tolerance cannot help
        needed = math.ceil(n_ref * n_max / max(n_have, 1))
        raise ValueError(
            f"no truncation with up to {n_max} modes per beam ({method}) can meet any tolerance: "
            f"the bandwidth {bandwidth:.4g} rad/s x fidelity.bandwidth_factor "
            f"{bandwidth_factor:g} asks for the first {n_ref} coupled frequencies (up to "
            f"{w_top:.4g} rad/s and the first above it), and {n_max} modes per beam give "
            f"{n_have}; lower the controller's bandwidth or fidelity.bandwidth_factor, or give "
            f"fidelity.n_modes (about {needed} or more)")
    best = min(trials, key=lambda t: max(t["frequency_error"], t["gain_error"]))
    raise ValueError(
        f"no truncation with up to {n_max} modes per beam ({method}) meets the tolerance "
        f"{tolerance:g}: best n_modes = {best['n_modes']} with frequency error "
        f"{best['frequency_error']:.3g} and gain error {best['gain_error']:.3g}; raise "
        "fidelity.tolerance or give fidelity.n_modes")
