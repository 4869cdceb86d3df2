"""Model fidelity: how many beam modes a scene needs, and which states its signals cannot reach.

Choosing n_modes
    A truncated beam (``beam.truncated(n, method)``) coupled to the hub is accurate enough when,
    for the controller's bandwidth wb and a requested relative tolerance tol,

    1. every coupled natural frequency up to ``bandwidth_factor * wb``, and the first one above
       it (the mode the loop rolls off against, where spillover starts), agrees with the exact
       coupled frequency within tol (exact: Wittrick-Williams on the exact W(s),
       :meth:`Spacecraft.natural_frequencies` with ``exact=True``); and
    2. the gain |theta/torque| (three axes: each singular value of the 3x3 attitude response)
       agrees with the exact one within tol (relative) on
       the closed-loop-relevant low band ``[wb/10, min(bandwidth_factor*wb, w_1/2, z_1/2)]``,
       w_1 the first exact coupled frequency and z_1 the first anti-resonance of theta/torque
       (the lowest clamped-root frequency of the appendages): below the first resonance and
       anti-resonance a relative error is meaningful whatever the (modelled) damping.

    :func:`choose_n_modes` returns the smallest n that meets both, with the errors of every n
    it tried (a short, monotone search: Craig-Bampton frequencies converge like n**-4).

Converging the closed loops
    Open-loop accuracy is not enough: the loops' verdicts also depend on modes above the band
    (a mode two octaves up sets a gain margin, the least-damped closed-loop pole can be the
    fourth mode). From that n, :func:`refine_for_closed_loop` adds one mode per beam at a time
    and closes every loop of the scene on the truth model with n and n + 1 modes; n is kept
    when, for every loop, between the two (:func:`closed_loop_change`, each a relative change,
    compared with the tolerance):

    * the stability verdict is the same;
    * every closed-loop pole up to the band that matters (``band``: bandwidth_factor x the
      fastest crossover, or the first exact coupled frequency above bandwidth_factor x the
      bandwidth if higher, as rule 1 above) has a counterpart within tol |s|;
    * the least damping ratio of all closed-loop poles agrees within tol relative, or within
      tol x 1e-3 (:data:`DAMPING_SCALE`) for damping ratios below 1e-3 (where a loop is warned
      about as lightly damped whatever the digits);
    * the gain margin (tol relative in gain, 20 log10(1 + tol) dB), phase margin and modulus
      margin agree within tol relative (both infinite: equal).

    The time metrics of the slew follow from the poles and residues, which these settle; they
    are not simulated per n. Each n costs one coupled eigen-decomposition of the truth model
    and the closed-loop eigenvalues and margins of each loop (a few milliseconds); every
    model, plant, controller and verdict is built once and reused by the run. The search stops
    at the largest n the scene's limits allow (reported as not converged).

Three axes: every motion an output sees
    A three-axis truncation ranks the modes of all a beam's motions together (bending in both
    planes, torsion, axial motion), so the n lowest may hold none of a stiff motion (a wing's
    in-plane bending, a boom's torsion) whose tip output would then read 0. When n is chosen
    from the tolerance and the scene reports tip outputs (or root loads), each beam keeps the
    lowest mode of every motion they see, however stiff, and n counts the modes beyond
    (:func:`motion_counts`; a beam whose modes are not split by motion, with a tip body or
    segments, keeps the fewest lowest modes that move every such tip motion and one more per
    n: :meth:`spacecraft.design.models.ModelBuilder.truncation`). Each n adds a mode, so the
    closed-loop rule never compares a model with itself. A stiff motion's one mode with the
    Craig-Bampton constraint modes does not give its quasi-static tip response: the static
    flexibility of its higher modes is missing (a uniform rod's tip twist under a uniform load
    from its first cantilever mode alone is 32/pi^3 = 1.032 of the exact one, whatever the
    mode's frequency); the tip-output rule below adds those modes.

Holding the tip outputs
    The tip figures a report prints (tip deflections, twists, root loads) are held by a rule of
    their own (:func:`refine_for_tip_outputs`), run at the open-loop rule's n before the
    closed-loop rule: each such output's response per hub torque on the open-loop rule's low
    band (below the first resonance and anti-resonance, where a slew's quasi-static tip figures
    are made and a relative change means something whatever the damping;
    :func:`output_changes`) is compared between the truncation and one with a mode more of the
    motion that moves it (a uniform three-axis beam: per appendage and motion,
    :data:`OUTPUT_MOTIONS`; a beam whose modes are ranked together, or a planar beam: its
    lowest modes), and modes of that motion are added until one more changes it by at most the
    tolerance. Each comparison costs one eigen-decomposition of an undamped truth model and its
    response on 40 frequencies; no time simulation. The motions' floors are kept as n grows
    (:func:`motion_counts` with ``floors``). The band does not see modes above it that a
    sharp-edged input (a torque pulse) rings: such figures hold to a few times the tolerance.

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

__all__ = ["FidelityChoice", "choose_n_modes", "motion_counts", "low_band", "transfer_theta_torque", "gain_error",
           "closed_loop_change", "refine_for_closed_loop", "DAMPING_SCALE",
           "clamped_frequencies", "transfer", "OUTPUT_MOTIONS", "NEGLIGIBLE", "output_changes",
           "refine_for_tip_outputs"]

#: Largest number of modes per beam the search from a tolerance tries (also within the scene's
#: limits.modes), whatever limits.modes allows: Craig-Bampton frequency errors fall like n**-4,
#: so a tolerance that 40 modes miss needs ten times the modes for 1e-4 of it, beyond a search
#: that builds one plant per n (about a second for all 40); give fidelity.n_modes for more.
MAX_MODES = 40


#: Damping ratios below this are compared absolutely (tolerance x DAMPING_SCALE) in the
#: closed-loop rule: the light-damping threshold of :mod:`spacecraft.design.verdicts`.
DAMPING_SCALE = 1e-3


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
    open_loop_n_modes : int or None
        The n the open-loop rule chose (``n_modes`` until the closed-loop rule refines it).
    closed_loop : dict or None
        The closed-loop rule's record (:func:`refine_for_closed_loop`): ``band`` [rad/s],
        ``trials`` (per n: the changes from n to n + 1), ``converged``.
    tip : dict or None
        The tip-output rule's record (:func:`refine_for_tip_outputs`; None without reported
        tip outputs or root loads): ``band`` [rad/s], ``n_modes`` (the n it held them at),
        ``trials``, ``floors`` (appendage -> motion -> modes kept at least), ``converged``.
    """

    n_modes: int
    method: str
    tolerance: float
    band: tuple
    reference_frequencies: np.ndarray
    trials: list
    open_loop_n_modes: int | None = None
    closed_loop: dict | None = None
    tip: dict | None = None

    def as_dict(self) -> dict:
        """JSON-ready form."""
        return {"n_modes": self.n_modes, "method": self.method, "tolerance": self.tolerance,
                "band": list(self.band),
                "reference_frequencies": self.reference_frequencies.tolist(),
                "trials": self.trials,
                "open_loop_n_modes": (self.n_modes if self.open_loop_n_modes is None
                                      else self.open_loop_n_modes),
                **({"closed_loop": self.closed_loop} if self.closed_loop is not None else {}),
                **({"tip": self.tip} if self.tip is not None else {})}


def clamped_frequencies(beam, omega_max: float, *, three_axis: bool = False) -> np.ndarray:
    """A beam's natural frequencies with its attachment end clamped [rad/s], ascending: every
    one up to ``omega_max`` and the first above it (the zeros of the coupled plant's attitude
    response, and what a Craig-Bampton truncation keeps). Planar: bending in the x-y plane;
    ``three_axis``: every motion (both bending planes, torsion, axial), as a three-axis
    truncation ranks them together (:meth:`appendages.Beam.clamped_frequencies6`)."""
    if three_axis:
        w = beam.clamped_frequencies6(omega_max)
    else:
        n = 8
        w = beam.cantilever_frequencies(n)
        while w[-1] <= omega_max:
            n *= 2
            w = beam.cantilever_frequencies(n)
    return w[:int(np.searchsorted(w, omega_max, side="right")) + 1]


def motion_counts(beam, n_modes: int, method: str, seen: tuple = (),
                  floors: dict | None = None) -> dict:
    """Modes per motion of a three-axis truncation that keeps, of a uniform beam, the lowest
    mode of every motion in ``seen`` that the beam has (the ``floors[motion]`` lowest where
    given) and, beyond those, the ``n_modes`` lowest of all its motions (and any tying with the
    last: a round section's twin).

    Parameters
    ----------
    beam : appendages.Beam
        A uniform three-axis beam (its four motions separate).
    n_modes : int
        Modes beyond the floor (>= 1).
    method : str
        Truncation method: Craig-Bampton ranks cantilever modes, the others free-free ones.
    seen : tuple of str
        Motions (``"xy"``, ``"xz"``, ``"torsion"``, ``"axial"``) whose lowest mode is kept
        whatever its frequency.
    floors : dict, optional
        motion -> the number of its lowest modes kept whatever their frequencies (at least one
        for a motion in ``seen``; capped at the modes the motion has): what the tip-output rule
        adds (:func:`refine_for_tip_outputs`).

    Returns
    -------
    dict
        ``{"xy": .., "xz": .., "torsion": .., "axial": ..}`` for
        ``beam.truncated(n, method=method, modes_per_motion=...)``. With ``seen``, beyond the
        floor the n lowest distinct frequencies are kept (twins count once), so each added n
        adds at least one mode and a search over n never compares a model with itself.
        Without ``seen``: the n lowest of all motions, as
        :attr:`appendages.ModalBeam.modes_per_motion`.
    """
    kind = "cantilever_frequencies" if method == "craig-bampton" else "natural_frequencies"
    floors = floors or {}
    k = max([int(n_modes)] + [int(v) for v in floors.values()]) + 1
    frequencies = {"xy": getattr(beam.planar_view("xy"), kind)(k),
                   "xz": getattr(beam.planar_view("xz"), kind)(k)}
    for name, rod in (("torsion", beam.torsion_rod()), ("axial", beam.axial_rod())):
        frequencies[name] = getattr(rod, kind)(k) if rod is not None else np.zeros(0)
    floor = {name: min(max(int(name in seen), int(floors.get(name, 0))), f.size)
             for name, f in frequencies.items()}
    rest = np.sort(np.concatenate([f[floor[name]:] for name, f in frequencies.items()]))
    if not seen and not any(floor.values()):
        cutoff = rest[int(n_modes) - 1] * (1.0 + 1e-12)
    else:
        # distinct frequencies: a round section's twins count once, so that n + 1 always adds
        levels = rest[np.concatenate([[True], np.diff(rest) > 1e-12 * rest[1:]])]
        cutoff = levels[min(int(n_modes), levels.size) - 1] * (1.0 + 1e-12)
    return {name: floor[name] + int(np.count_nonzero(f[floor[name]:] <= cutoff))
            for name, f in frequencies.items()}


def low_band(bandwidth: float, factor: float, first_frequency: float,
             first_zero: float = math.inf) -> tuple[float, float]:
    """``(wb/10, min(factor*wb, w_1/2, z_1/2))`` [rad/s]: where the low-frequency gain must match.

    The upper end never falls below ``wb/5`` (two octaves of band at least).
    """
    top = min(factor * bandwidth, 0.5 * first_frequency, 0.5 * first_zero)
    return bandwidth / 10.0, max(top, bandwidth / 5.0)


def transfer_theta_torque(plant: control.StateSpace, omega: np.ndarray) -> np.ndarray:
    """theta/torque [rad/(N m)] of a state-space plant at j*omega: complex, shape
    ``omega.shape + (m, m)``, m = 1 for a planar plant (torque to theta), 3 for a three-axis
    one (torque_x.._z to theta_x.._z, hub axes)."""
    inputs = list(plant.input_labels)
    if "torque" in inputs:
        return transfer(plant, omega, ["torque"], ["theta"])
    return transfer(plant, omega, [f"torque_{a}" for a in "xyz"],
                    [f"theta_{a}" for a in "xyz"])


def transfer(plant: control.StateSpace, omega: np.ndarray, inputs: list, outputs: list
             ) -> np.ndarray:
    """The frequency response of a state-space plant at j*omega from the named inputs to the
    named outputs (units of the signals): complex, shape ``omega.shape + (len(outputs),
    len(inputs))``."""
    labels_in, labels_out = list(plant.input_labels), list(plant.output_labels)
    i_in = [labels_in.index(name) for name in inputs]
    i_out = [labels_out.index(name) for name in outputs]
    A = np.asarray(plant.A, dtype=float)
    B = np.asarray(plant.B, dtype=float)[:, i_in]
    C = np.asarray(plant.C, dtype=float)[i_out]
    D = np.asarray(plant.D, dtype=float)[np.ix_(i_out, i_in)]
    n = A.shape[0]
    s = 1j * np.asarray(omega, dtype=float).reshape(-1)
    M = s[:, None, None] * np.eye(n) - A
    return C @ np.linalg.solve(M, np.broadcast_to(B, (s.size,) + B.shape)) + D


def gain_error(response: np.ndarray, exact: np.ndarray) -> float:
    """Largest relative error of the gains of an attitude response against the exact one:
    max over frequency of |sigma_i(P) / sigma_i(P_exact) - 1| over the singular values (a
    planar plant's |P| / |P_exact| - 1). The singular values are the gains in the principal
    directions; damping changes them, like the magnitude, only at second order below the
    first resonance, where a phase would change at first order."""
    sigma = np.linalg.svd(response, compute_uv=False)
    sigma_exact = np.linalg.svd(exact, compute_uv=False)
    return float(np.max(np.abs(sigma / sigma_exact - 1.0)))


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
        as it has) and its torque-to-theta plant (three axes: torques to attitudes).
    exact_frequencies : callable k -> ndarray
        First k exact coupled elastic frequencies [rad/s].
    exact_response : callable omega -> ndarray
        Exact theta/torque at j*omega [rad/(N m)], shape ``omega.shape + (m, m)`` as
        :func:`transfer_theta_torque` (three axes: the 3x3 attitude compliance).
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
        # gain error: below the first resonance damping changes the phase at first order in
        # zeta but the gains (singular values) only at second order, so the gains are compared
        g_err = gain_error(transfer_theta_torque(plant, omega), exact)
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


def _relative(a: float | None, b: float | None, *, scale: float = 0.0) -> float:
    """|a - b| / max(|b|, scale); 0 for two equal values (both infinite included), inf when
    only one is finite or missing."""
    if a is None or b is None:
        return 0.0 if a is None and b is None else math.inf
    if a == b:
        return 0.0
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.inf
    return abs(a - b) / max(abs(b), scale, 1e-300)


def _pole_change(before: np.ndarray, after: np.ndarray, band: float) -> float:
    """Largest distance, relative to |s|, from a pole of either set within the band (upper
    half-plane) to the nearest pole of the other set."""
    worst = 0.0
    for mine, other in ((after, before), (before, after)):
        mine = mine[(mine.imag >= 0) & (np.abs(mine) <= band)]
        if mine.size == 0:
            continue
        if other.size == 0:
            return math.inf
        distance = np.abs(mine[:, None] - other[None, :]).min(axis=1)
        worst = max(worst, float(np.max(distance / np.maximum(np.abs(mine), 1e-300))))
    return worst


def _pole_facts(poles: np.ndarray) -> tuple[bool, float | None]:
    """(stable, least damping ratio) of closed-loop poles [1/s]: stable when no pole grows
    faster than a marginal one, Re(s) <= 1e-10 max(1, |s|) (spacecraft.design.verdicts.MARGINAL);
    damping -Re(s)/|s| (0 at s = 0)."""
    s = np.asarray(poles, dtype=complex)
    if s.size == 0:
        return True, None
    w = np.abs(s)
    zeta = np.where(w > 0, -s.real / np.where(w > 0, w, 1.0), 0.0)
    return bool(not np.any(s.real > 1e-10 * np.maximum(1.0, w))), float(zeta.min())


def closed_loop_change(before: dict, after: dict, band: float, *,
                       margins: bool = True) -> dict:
    """How much the closed loops change from one truth model to a finer one.

    Parameters
    ----------
    before, after : dict
        loop -> an object with ``poles`` (closed-loop poles [1/s]) and ``verdict`` (its
        :class:`controllers.SpilloverVerdict`, read only for the margins) on the two truth
        models, the same loops in both.
    band : float, rad/s
        The poles compared are those up to it (module docstring).
    margins : bool
        Compare the margins too (False: only what the poles give, without computing a margin).

    Returns
    -------
    dict
        The largest relative change over the loops of: ``verdict`` (0, or inf when a loop's
        stability differs), ``poles``, ``least_damping`` (relative, absolute below
        :data:`DAMPING_SCALE` in units of it), and with ``margins`` ``gain_margin`` (in gain),
        ``phase_margin``, ``modulus_margin``.
    """
    names = ("verdict", "poles", "least_damping") + (
        ("gain_margin", "phase_margin", "modulus_margin") if margins else ())
    out = dict.fromkeys(names, 0.0)
    for key, b in after.items():
        a = before[key]
        (stable_a, zeta_a), (stable_b, zeta_b) = _pole_facts(a.poles), _pole_facts(b.poles)
        change = {
            "verdict": 0.0 if stable_a == stable_b else math.inf,
            "poles": _pole_change(np.asarray(a.poles, complex), np.asarray(b.poles, complex),
                                  band),
            "least_damping": _relative(zeta_a, zeta_b, scale=DAMPING_SCALE),
        }
        if margins:
            ma, mb = a.verdict.margins, b.verdict.margins
            # a gain margin in dB: the relative change of the gain, 10^(dGM/20) - 1
            change["gain_margin"] = (
                0.0 if ma.gain_margin == mb.gain_margin else
                abs(10.0 ** ((ma.gain_margin - mb.gain_margin) / 20.0) - 1.0)
                if math.isfinite(ma.gain_margin - mb.gain_margin) else math.inf)
            change["phase_margin"] = _relative(ma.phase_margin, mb.phase_margin)
            change["modulus_margin"] = _relative(ma.modulus_margin, mb.modulus_margin)
        for name, value in change.items():
            out[name] = max(out[name], value)
    return out


def refine_for_closed_loop(closed_loops: Callable[[int], dict], n_start: int, *,
                           tolerance: float, band: float, n_max: int
                           ) -> tuple[int, dict]:
    """The smallest n >= n_start at which the scene's closed loops have converged.

    Parameters
    ----------
    closed_loops : callable n -> dict
        loop -> an object with ``poles`` and ``verdict`` (:func:`closed_loop_change`) on the
        truth model with n modes per beam (each n evaluated once: the caller caches what it
        builds; the verdict is read only once the poles have converged).
    n_start : int
        The open-loop rule's n (:func:`choose_n_modes`).
    tolerance : float
        Relative tolerance (the scene's ``fidelity.tolerance``).
    band : float, rad/s
        Poles compared up to this frequency (module docstring).
    n_max : int
        Largest n to try.

    Returns
    -------
    n_modes : int
        The first n whose loops change by at most ``tolerance`` (:func:`closed_loop_change`)
        when a mode per beam is added; ``n_max`` if none up to it does.
    record : dict
        ``band``, ``trials`` (per n: ``n_modes`` and the changes to n + 1, the margins' only
        where the poles' were within the tolerance), ``converged``.
    """
    trials = []
    n, current = n_start, closed_loops(n_start)
    while n < n_max:
        finer = closed_loops(n + 1)
        # the poles first: the margins (the costly part) only once the poles have settled
        change = closed_loop_change(current, finer, band, margins=False)
        if max(change.values()) <= tolerance:
            change = closed_loop_change(current, finer, band)
        trials.append({"n_modes": n, **change})
        if max(change.values()) <= tolerance:
            return n, {"band": band, "trials": trials, "converged": True}
        n, current = n + 1, finer
    return n, {"band": band, "trials": trials, "converged": False}


#: Suffix of an appendage's reported output -> (the motion of a uniform three-axis beam that
#: moves it, its unit); planar outputs are moved by the bending (``"bending"``). Tip
#: deflections in the appendage's x-y and x-z planes, its twist, the root force along and
#: across it and the root moments about its axes (:mod:`spacecraft.dynamics.coupling`).
OUTPUT_MOTIONS = {
    "_tip_deflection": ("bending", "m"), "_root_force": ("bending", "N"),
    "_root_moment": ("bending", "N m"),
    "_tip_deflection_y": ("xy", "m"), "_tip_deflection_z": ("xz", "m"),
    "_tip_twist": ("torsion", "rad"),
    "_root_force_x": ("axial", "N"), "_root_force_y": ("xy", "N"), "_root_force_z": ("xz", "N"),
    "_root_moment_x": ("torsion", "N m"), "_root_moment_y": ("xz", "N m"),
    "_root_moment_z": ("xy", "N m"),
}

#: An output whose response on the band stays below this fraction of the largest response of
#: the outputs of its unit is not compared (its relative change is round-off: e.g. a motion a
#: symmetric load leaves still); such a figure is 1e-9 of its neighbours' in the report.
NEGLIGIBLE = 1e-9


def output_changes(before: control.StateSpace, after: control.StateSpace, omega: np.ndarray,
                   inputs: list, outputs: dict) -> dict:
    """How much each output's frequency response changes from one model to a finer one.

    Parameters
    ----------
    before, after : control.StateSpace
        The two plants (the same named inputs and outputs).
    omega : ndarray, rad/s
        Frequencies compared.
    inputs : list of str
        The inputs (the hub torques).
    outputs : dict
        Output name -> its unit (outputs of one unit are compared with one another's size,
        :data:`NEGLIGIBLE`).

    Returns
    -------
    dict
        Output name -> max over omega of |H_after(w) - H_before(w)| / max over omega of
        |H_after(w)|, |.| the 2-norm over the inputs (the output's row): a change relative to
        the largest response on the band, as a peak in the time domain sees it (a pointwise
        ratio would blow up at a zero of one input's response). 0 for a negligible output.
    """
    names = list(outputs)
    h_before = transfer(before, omega, inputs, names)
    h_after = transfer(after, omega, inputs, names)
    size = np.linalg.norm(h_after, axis=2).max(axis=0)            # per output
    change = np.linalg.norm(h_after - h_before, axis=2).max(axis=0)
    largest: dict = {}
    for name, value in zip(names, size):
        largest[outputs[name]] = max(largest.get(outputs[name], 0.0), float(value))
    out = {}
    for name, value, delta in zip(names, size, change):
        if not value > NEGLIGIBLE * largest[outputs[name]]:
            out[name] = 0.0
        else:
            out[name] = float(delta / value)
    return out


def refine_for_tip_outputs(compare: Callable[[dict, dict], dict], add: Callable[[dict, set], dict],
                           motion_of: Callable[[str], tuple], motions: set, *, tolerance: float,
                           max_rounds: int = 200) -> tuple[dict, dict]:
    """The fewest modes per appendage and motion that hold the reported tip outputs.

    From the truncation the other rules chose (``floors`` empty), a mode of every motion a
    reported output sees is added (``add``) and each output's frequency response is compared
    between the two models (``compare``, :func:`output_changes`); the modes of the motions whose
    outputs changed by more than ``tolerance`` are kept and the comparison repeated for those,
    until every output changes by at most the tolerance when one more mode of its motion is
    added (n against n + 1, as the closed-loop rule: an upper estimate of the error of n where
    the modal series converge monotonically or alternate, as a stiff motion's quasi-static
    tip response does).

    Parameters
    ----------
    compare : callable (floors, floors) -> dict
        Output -> relative change from the first model to the second.
    add : callable (floors, set of motions) -> floors
        The floors with one more mode of each of the motions (those at their cap left as they
        are).
    motion_of : callable output -> motion
        The (appendage, motion) whose modes move an output.
    motions : set
        Every (appendage, motion) an output sees.
    tolerance : float
        Relative tolerance (the scene's ``fidelity.tolerance``).
    max_rounds : int
        A guard: the search stops after this many comparisons.

    Returns
    -------
    floors : dict
        (appendage, motion) -> modes kept at least (``add``'s record).
    record : dict
        ``trials`` (per comparison: ``added`` motions, ``changes`` per output, ``largest``
        change), ``converged`` (False: a motion at its cap, or the guard, stopped the search).
    """
    floors: dict = {}
    trying = set(motions)
    capped: set = set()
    trials = []
    for _ in range(max_rounds):
        finer = add(floors, trying)
        added = {k for k in trying if finer.get(k) != floors.get(k)}
        capped |= trying - added
        if not added:
            break   # every motion that misses the tolerance is at its cap
        changes = compare(floors, finer)
        trials.append({"added": [list(k) for k in sorted(added)], "changes": changes,
                       "largest": max(changes.values(), default=0.0)})
        failing = {motion_of(o) for o, c in changes.items() if not c <= tolerance}
        if not failing - capped:
            return floors, {"trials": trials, "converged": not failing}
        keep = failing & added
        # the finer model as built when every motion it added misses, or none does (the
        # misses then come from other motions' modes: kept, so that each round adds a mode)
        floors = finer if keep in (added, set()) else add(floors, keep)
        trying = failing - capped
    return floors, {"trials": trials, "converged": False}
