"""Stability margins of a loop and the spillover verdict of a controller on a truth model.

Loop delay
----------
A delay tau [s] (computation plus transport, :mod:`controllers.delay`) multiplies the loop by
e^(-j omega tau): it leaves every |L| and so the gain crossovers where they are and lowers the
phase there by omega_c tau. The margins are first found on the grid as it is (they bound the
true ones from above: a crossing or dip between grid points can only lower them); the grid is
then refined until omega tau changes by at most pi/4 between points wherever |L| can still lower
them (:func:`harmless_gain`: a crossing of the negative real axis at |L| = g gives a gain margin
of 1/g, and |1 + L e^(-j omega tau)| >= 1 - |L|), so the crossings the delay adds there are all
bracketed, and nowhere else: the stiff lightly damped modes far above the crossover, where
|L| is small, need no phase resolution however long the delay.

Delay margin: the smallest extra delay Delta that puts L e^(-j omega Delta) through -1, i.e.
min over the gain crossovers omega_c of PM / omega_c with PM in [0, 360) deg (a negative margin
of a conditionally stable crossover taken as 360 deg + PM). For a loop that is stable with its
delay this is the delay that destabilises it: as the delay grows, closed-loop roots cross the
imaginary axis only at j omega_c where |L(j omega_c)| = 1, and only at the delays
tau_k = (PM_0 + 2 pi k) / omega_c (PM_0 the margin without delay); a root crosses to the right
where |L| falls through 1 and to the left where it rises (Cooke & van den Driessche), so the
first crossing of a stable loop destabilises it whether or not the open loop is stable. Three
axes (the same delay on each torque): the same with the eigenvalues lambda of L(j omega) on the
unit circle, det(I + e^(-j omega tau) L) = 0 <=> -e^(j omega tau) is an eigenvalue of L.
:func:`spillover` counts the closed-loop roots in the right half-plane at the loop's delay exactly
this way: those of the loop without delay (eigenvalues, or the Nyquist count of an FRD) plus two
per destabilising crossing below the delay, minus two per stabilising one.

References
----------
K. L. Cooke, P. van den Driessche, "On zeroes of some transcendental equations", Funkcialaj
Ekvacioj 29, 1986 (direction of the imaginary-axis crossings of the roots of
P(s) + Q(s) e^(-s tau)); K. Gu, V. L. Kharitonov, J. Chen, Stability of Time-Delay Systems,
Birkhauser 2003, sec. 2.3 (delay margin from the gain crossovers); S. Skogestad, I. Postlethwaite,
Multivariable Feedback Control, 2nd ed., sec. 2.4.3 (delay margin PM / omega_c).
"""
from __future__ import annotations

import cmath
import dataclasses
import math
from dataclasses import dataclass
from typing import Callable, Sequence

import control
import numpy as np

from .delay import check_delay, total_delay, warns_long_delay
from .refine import refine
from .loop import (LoopTransfer, close_loop, compiled_kernel, loop_frequency_response,
                   loops_at_a_time, sensitivity)
from .arguments import describe, frequency_grid
from .signals import AXES, check_controller, check_plant, is_digital
from .stability import continuous_poles
from .threads import limits_blas_threads, total_states

__all__ = ["Margins", "MultiLoopMargins", "ModeSpillover", "SpilloverVerdict", "margins",
           "spillover", "nyquist_count", "disk_margin_gain", "disk_margin_phase",
           "loop_margins", "MAX_DELAY_GRID", "zero_crossings", "multiloop_margins",
           "loop_nyquist_count", "loop_verdict", "unstable_poles", "harmless_gain"]

#: Most frequencies a delayed loop's grid may hold (omega tau resolved to pi/4 wherever |L| can
#: lower the margins): beyond, margins() refuses the delay by name (controller.delay) before
#: evaluating the refined grid.
MAX_DELAY_GRID = 2_000_000
# a unit-circle crossing's bracket is cut into this many sections per step (_unit_crossings):
# 2, bisection; more sections take fewer evaluations of L but count at more points, each an
# eigenvalue problem near the crossing (8 was no faster on benchmarks/three_axis.py's loop)
_SECTIONS = 2
# ... or, with fewer brackets, into as many sections as give about this many points per step
_BISECTION_POINTS = 64
# below this |L| a crossing of the negative real axis is no margin (as in _loops_margins)
_NEGLIGIBLE_GAIN = 1e-9


@dataclass(frozen=True)
class Margins:
    """Classical stability margins of a loop (see :func:`margins`).

    Attributes
    ----------
    gain_margin : float, dB
        -20 log10 |L| at the phase crossover (L real and negative) closest to 0 dB;
        positive: the gain may rise by that much; negative: it may fall by that much (a
        conditionally stable loop). +inf if L never crosses the negative real axis.
    phase_margin : float, deg
        180 deg + arg L at the gain crossover (|L| = 1) with the smallest |margin|, wrapped to
        (-180, 180]; +inf if |L| never crosses 1.
    modulus_margin : float
        min over omega of |1 + L(j omega)| (the distance from L to the critical point -1;
        1/max|S|).
    gain_crossover_frequency, phase_crossover_frequency, modulus_margin_frequency : float, rad/s
        Where those margins are attained (nan-free: +inf when there is no crossover).
    delay : float, s
        The loop delay included in L (0: none).
    delay_margin : float, s
        The smallest extra delay that puts L through -1: min over every gain crossover of
        PM / omega_c, PM in [0, 360) deg (module docstring); the delay margin of a loop that is
        stable with its delay (+inf without gain crossover). :func:`spillover` reports it
        against the loop's stability: 0 or negative (the delay beyond the margin) for a loop
        that its delay destabilised.
    """

    gain_margin: float
    phase_margin: float
    modulus_margin: float
    gain_crossover_frequency: float
    phase_crossover_frequency: float
    modulus_margin_frequency: float
    delay: float = 0.0
    delay_margin: float = math.inf

    def as_dict(self) -> dict[str, float]:
        """The three margins under their metric names (gain_margin, phase_margin, modulus_margin)."""
        return {"gain_margin": self.gain_margin, "phase_margin": self.phase_margin,
                "modulus_margin": self.modulus_margin}


def disk_margin_gain(alpha: float) -> float:
    """Gain margin [dB] guaranteed by a balanced disk margin alpha: the loop tolerates gains in
    [(1 - alpha/2) / (1 + alpha/2), (1 + alpha/2) / (1 - alpha/2)], +-20 log10 of the upper end
    (inf for alpha >= 2).

    References
    ----------
    P. Seiler, A. Packard, P. Gahinet, "An introduction to disk margins", IEEE Control Systems
    Magazine 40(5), 2020, sec. "Disk margins" (the balanced disk, sigma = 0).
    """
    if alpha >= 2.0:
        return math.inf
    return 20.0 * math.log10((1.0 + alpha / 2.0) / (1.0 - alpha / 2.0))


def disk_margin_phase(alpha: float) -> float:
    """Phase margin [deg] guaranteed by a balanced disk margin alpha: +-2 arctan(alpha / 2)
    (Seiler, Packard & Gahinet 2020; 90 deg at alpha = 2)."""
    return math.degrees(2.0 * math.atan(alpha / 2.0)) if math.isfinite(alpha) else 180.0


@dataclass(frozen=True)
class MultiLoopMargins:
    """Margins of a three-axis loop (see :func:`margins`).

    Attributes
    ----------
    loop_at_a_time : dict of str to Margins
        Per hub axis ('x', 'y', 'z'): the classical margins of L_i = 1/S_ii - 1, the loop
        broken at torque input i with the other loops closed.
    disk_margin : float
        Balanced multivariable disk margin alpha at the plant input, for an unstructured
        (full-block) perturbation: alpha = 1 / max over omega of sigma_max(S - I/2), S = (I + L)^-1
        (Seiler, Packard & Gahinet 2020). The loop stays stable for simultaneous, independent
        (and even coupled) gain and phase variations in all three torque channels within the
        disk: gains in [(1 - alpha/2)/(1 + alpha/2), (1 + alpha/2)/(1 - alpha/2)] with phases
        within +-2 arctan(alpha/2). It is a lower bound of the margin for independent
        (diagonal) perturbations, equal to it when L is diagonal.
    disk_gain_margin : float, dB
        :func:`disk_margin_gain` of disk_margin.
    disk_phase_margin : float, deg
        :func:`disk_margin_phase` of disk_margin.
    disk_margin_frequency : float, rad/s
        Where sigma_max(S - I/2) peaks.
    min_singular_value : float
        min over omega of sigma_min(I + L(j omega)) (the return difference at the plant input,
        1 / ||S||_inf); any multiplicative input perturbation I + Delta with
        sigma_max(Delta) < min_singular_value keeps the loop stable.
    min_singular_value_frequency : float, rad/s
    delay : float, s
        The loop delay (the same on each torque) included in L.
    delay_margin : float, s
        The smallest extra delay on all three torques that makes det(I + L e^(-j omega Delta))
        vanish: min over the frequencies where an eigenvalue lambda of L(j omega) has
        |lambda| = 1 of ((180 deg + arg lambda) mod 360 deg) / omega (module docstring); each
        loop-at-a-time entry has its own (an extra delay on that torque alone).
    """

    loop_at_a_time: dict
    disk_margin: float
    disk_gain_margin: float
    disk_phase_margin: float
    disk_margin_frequency: float
    min_singular_value: float
    min_singular_value_frequency: float
    delay: float = 0.0
    delay_margin: float = math.inf

    @property
    def gain_margin(self) -> float:
        """The smallest |gain margin| over the axes, dB."""
        return min((m.gain_margin for m in self.loop_at_a_time.values()), key=abs)

    @property
    def phase_margin(self) -> float:
        """The smallest |phase margin| over the axes, deg."""
        return min((m.phase_margin for m in self.loop_at_a_time.values()), key=abs)

    @property
    def modulus_margin(self) -> float:
        """The smallest modulus margin over the axes."""
        return min(m.modulus_margin for m in self.loop_at_a_time.values())

    def as_dict(self) -> dict[str, float]:
        """Per axis ``gain_margin_x``, ``phase_margin_x``, ``modulus_margin_x``, ...; then
        ``disk_margin``, ``disk_gain_margin``, ``disk_phase_margin``, ``min_singular_value``."""
        out = {}
        for axis, m in self.loop_at_a_time.items():
            out.update({f"{k}_{axis}": v for k, v in m.as_dict().items()})
        out.update(disk_margin=self.disk_margin, disk_gain_margin=self.disk_gain_margin,
                   disk_phase_margin=self.disk_phase_margin,
                   min_singular_value=self.min_singular_value)
        return out


def zero_crossings(f: Callable[[np.ndarray], np.ndarray], omega: np.ndarray, values: np.ndarray
                   ) -> np.ndarray:
    """Zeros of f: grid points where `values` is 0 and refined roots where it changes sign.

    ``f`` maps an array of frequencies [rad/s] to real values; ``values = f(omega)`` on the
    increasing grid ``omega``. Returns the zeros found [rad/s], increasing.

    Every sign-change bracket of the grid is refined at once, one vectorised evaluation of f
    at three points per bracket per iteration (safeguarded Newton steps with difference
    quotients, :func:`controllers.refine.refine`), to |b - a| <= 1e-13 b. A sign change may
    also be a pass through an undamped pole (f -> +-inf): the bracket then closes in on the
    pole, where f is huge or not finite; such a point is no root and is dropped (|f| must fall
    below 1e-6 of its size at the bracket's ends, or grow outside the converged bracket as
    about a root, not fall as about a pole: :func:`controllers.refine.refine`); its refinement
    stops once |f| at both ends exceeds 1e3 times that size.
    """
    return _crossings_of_many(lambda x, owner: f(x), [(omega, values)])[0]


def _crossings_of_many(f: Callable[[np.ndarray, np.ndarray], np.ndarray],
                       grids: list[tuple[np.ndarray, np.ndarray]]) -> list[np.ndarray]:
    """Zeros of several functions at once, as :func:`zero_crossings` finds those of one.

    ``grids[j] = (omega_j, values_j)``: function j on its grid. ``f(x, owner)`` evaluates, at
    each x[k], the function ``owner[k]``: one call refines the brackets of every function
    (the three loop-at-a-time functions of a three-axis loop come from one evaluation of
    L). Returns the zeros of each function, in the order of ``grids``.
    """
    exact, brackets, guesses = _sign_changes(grids)
    (root, found), _ = refine(f, roots=brackets, guesses=guesses)
    owner = brackets[0]
    return [np.concatenate([exact[j], root[found & (owner == j)]]) for j in range(len(grids))]


def _sign_changes(grids: list[tuple[np.ndarray, np.ndarray]]) -> tuple[list, tuple, Callable]:
    """Grid points where each function is 0, the brackets of its sign changes (owner, a, b,
    f(a), f(b)) for :func:`controllers.refine.refine`, and a function giving a first guess of
    each root with its error (NaN: none): the inverse cubic through the bracket and its grid
    neighbours where f is monotonic on them, its distance to regula falsi's point as the
    error."""
    exact = [omega[values == 0] for omega, values in grids]
    brackets, starts = [], []
    for j, (omega, values) in enumerate(grids):
        sign = np.sign(values)
        i = np.nonzero(sign[:-1] * sign[1:] < 0)[0]
        brackets.append((np.full(i.size, j), omega[i], omega[i + 1], values[i], values[i + 1]))
        starts.append(i)

    def guesses() -> tuple[np.ndarray, np.ndarray]:
        # the four grid points about each bracket that has them, of every function at once
        windows = [(omega, values, i[(i >= 1) & (i + 2 < omega.size)])
                   for (omega, values), i in zip(grids, starts)]
        offsets = np.arange(-1, 3)
        x = np.concatenate([omega[k[:, None] + offsets] for omega, _, k in windows])
        f = np.concatenate([values[k[:, None] + offsets] for _, values, k in windows])
        centre = np.full(sum(i.size for i in starts), np.nan)
        spacing = centre.copy()
        where = np.concatenate([np.flatnonzero((i >= 1) & (i + 2 < omega.size)) + first
                                for (omega, _), i, first in
                                zip(grids, starts, np.cumsum([0] + [i.size for i in starts]))])
        if where.size:
            centre[where], spacing[where] = _inverse_cubic_guess(x.astype(float),
                                                                 f.real.astype(float))
        return centre, spacing

    if not brackets:
        empty = np.zeros(0)
        return exact, (empty.astype(int),) + (empty,) * 4, lambda: (empty, empty)
    owner, a, b, fa, fb = (np.concatenate(parts) for parts in zip(*brackets))
    return exact, (owner.astype(int), a.astype(float), b.astype(float), fa.astype(float),
                   fb.astype(float)), guesses


def _inverse_cubic_guess(x: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(root estimate, its error) of sign changes between x[:, 1] and x[:, 2], from four
    neighbouring grid points x (n, 4) and the function's values f there: the inverse
    interpolation cubic x(f) through them at f = 0 (Lagrange form) where f is strictly
    monotonic on them, and its distance to the regula falsi point of the bracket; NaN where f
    is not monotonic or the estimate leaves the bracket."""
    d = f[:, 1:] - f[:, :-1]
    monotonic = np.all(d > 0, axis=1) | np.all(d < 0, axis=1)
    with np.errstate(all="ignore"):
        estimate = np.zeros(x.shape[0])
        for m in range(4):
            term = x[:, m].copy()
            for q in range(4):
                if q != m:
                    term *= (0.0 - f[:, q]) / (f[:, m] - f[:, q])
            estimate += term
        a, b, fa, fb = x[:, 1], x[:, 2], f[:, 1], f[:, 2]
        falsi = (a * fb - b * fa) / (fb - fa)
    good = monotonic & np.isfinite(estimate) & (estimate > a) & (estimate < b)
    return (np.where(good, estimate, np.nan), np.where(good, np.abs(estimate - falsi), np.nan))


@warns_long_delay
@limits_blas_threads(total_states)
def margins(plant, controller, *, omega: np.ndarray | None = None, delay: float = 0.0,
            computation_delay: bool = False) -> Margins:
    """Gain, phase and modulus margins of the loop plant-controller.

    Parameters
    ----------
    plant : control.StateSpace or control.FrequencyResponseData
        Plant with named signals. For a FrequencyResponseData plant the grid is the FRD's own
        plus the controller's resonances; between the FRD's points the plant is interpolated
        linearly in log frequency (log|P| and arg P), the controller is evaluated exactly, so the
        FRD grid must resolve the plant's resonances. It needs output 'theta' or 'omega' (the
        other is derived as omega = j w theta).
    controller : control.StateSpace
        Continuous or digital controller. For a digital controller and a StateSpace plant, L is
        the exact sampled-data loop gain L(e^{j omega T}) with the plant discretised by a
        zero-order hold; with an FRD plant, the hold is modelled as (1 - e^{-j omega T})/(j omega T)
        (aliasing neglected). Frequencies stop at the Nyquist frequency pi/T.
    omega : array of float, rad/s, optional
        Frequency grid; default: logarithmic, 1e-3 x the lowest to 1e3 x the highest
        characteristic frequency, refined with 41 points across the half-power band of every
        pole with damping ratio below 0.3 (lightly damped modes of plant and controller).
        Crossings (pairs between two grid points too) and the minima of |1 + L| are then
        refined on the exact L (:func:`loop_margins`). With a delay the
        default grid is refined so that omega delay changes by at most pi/4 between points
        where |L| can lower the margins (:func:`harmless_gain`; at most MAX_DELAY_GRID points);
        a given grid is used as it is.
    delay : float, s
        Loop delay: L e^(-j omega delay) exactly (a digital controller on a state-space plant:
        the sampled plant with the delayed hold, the modified z-transform). The margins then
        include it and ``delay_margin`` is the extra delay the loop tolerates (exact for a
        continuous loop; for a digital one exact in whole samples, a fractional extra delay
        taken as its phase -omega Delta).
    computation_delay : bool
        Add one sample of a digital controller to the delay.

    Returns
    -------
    Margins or MultiLoopMargins
        Margins for a planar loop. For a three-axis loop, :class:`MultiLoopMargins`: the
        classical margins of each loop-at-a-time L_i = 1/S_ii - 1 (axis i broken, the others
        closed) and the multivariable disk margin and return difference at the plant input. The
        disk margin is taken for an unstructured perturbation (sigma_max of S - I/2): it needs
        no mu computation, it is exact for decoupled (diagonal) loops and a guaranteed lower
        bound otherwise, and it reads directly as simultaneous gain and phase margins in all
        channels (:func:`disk_margin_gain`, :func:`disk_margin_phase`).

    References
    ----------
    G. F. Franklin, J. D. Powell, A. Emami-Naeini, Feedback Control of Dynamic Systems, 7th ed.,
    sec. 6.4 (gain and phase margins); S. Skogestad, I. Postlethwaite, Multivariable Feedback
    Control, 2nd ed., sec. 2.4.3 (modulus margin = 1/||S||_inf) and sec. 9.3 (loop-at-a-time
    margins); P. Seiler, A. Packard, P. Gahinet, "An introduction to disk margins", IEEE Control
    Systems Magazine 40(5), 2020 (disk margins, balanced sigma = 0, multiloop).
    """
    check_controller(controller)
    tau = total_delay(controller, delay, computation_delay)
    loop = LoopTransfer(plant, controller, tau)
    refine = omega is None
    if omega is None:
        omega = loop.grid()
    omega = np.unique(frequency_grid(omega, minimum=2))
    if omega.size < 2:
        raise ValueError("omega must hold at least two distinct frequencies [rad/s]")
    undamped = loop.undamped_frequencies()

    def on(grid: np.ndarray) -> Margins | MultiLoopMargins:
        if not loop.ch.mimo:
            return dataclasses.replace(loop_margins(loop, grid, undamped=undamped), delay=tau)
        return _multiloop_margins(loop.matrix, loop.ch.axes, grid, None, tau, undamped)

    if not (refine and tau > 0.0):
        return on(omega)
    # the margins on the grid as it is bound the true ones from above; only where |L| can
    # reach what would lower them is the delay's phase resolved (harmless_gain)
    first = on(omega)
    with np.errstate(all="ignore"):
        gains = _gain(loop.matrix(omega))
    refined = _delay_grid(None, omega, tau, gains,
                          harmless_gain(first, len(loop.ch.axes) if loop.ch.mimo else 1))
    return first if refined.size == omega.size else on(refined)


@warns_long_delay
def multiloop_margins(loop: Callable[[np.ndarray], np.ndarray], omega: np.ndarray,
                      L: np.ndarray | None = None, *, delay: float = 0.0,
                      axes: Sequence[str] | None = None,
                      undamped: np.ndarray | None = None) -> MultiLoopMargins:
    """Loop-at-a-time and disk margins of a matrix loop function, found on the function itself.

    The multivariable counterpart of :func:`loop_margins`, with the definitions of
    :func:`margins` for a three-axis state-space loop (:class:`MultiLoopMargins`: the classical
    margins of each L_i = 1/S_ii - 1, the balanced disk margin 1 / max sigma_max(S - I/2), the
    smallest singular value of I + L, the delay margin): the same code computes both, so a
    loop known only by its frequency response (the exact distributed spacecraft's, through
    W6) gets the margins a state-space model of it would. The grid only brackets: crossings are
    refined on ``loop`` to 1e-13 relative in frequency (pairs between two grid points
    included), the extrema of the singular values (every grid peak within 10 % of the
    largest) by a bounded scalar search between grid neighbours.

    Parameters
    ----------
    loop : callable
        ``loop(omega)`` -> L(j omega), complex array of shape (f, m, m) for the f frequencies
        of the 1-D ``omega`` [rad/s]: the loop broken at the m plant inputs, negative-feedback
        convention (the loop is unstable where det(I + L) = 0).
    omega : ndarray, rad/s
        Increasing grid that resolves L (every crossing and extremum between two of its
        points).
    L : ndarray, optional
        ``loop(omega)``, if already known.
    delay : float, s
        A loop delay not in ``loop`` (the same on every input): the margins are those of
        loop(omega) e^(-j omega delay), the grid refined for it as :func:`margins` refines its
        own.
    axes : sequence of str, optional
        Names of the m inputs, the keys of ``loop_at_a_time`` (default ``'x', 'y', 'z'`` for
        m = 3, else ``'1'``...).
    undamped : array of float, rad/s, optional
        Frequencies of the loop's undamped poles, if known (:meth:`LoopTransfer.
        undamped_frequencies`): beside each, L runs along a whole straight line and |1 + L|
        can dip far below its grid values in a band narrower than any grid; those dips are
        searched on ``loop``.

    Returns
    -------
    MultiLoopMargins
    """
    omega, delay, _, L = _loop_arguments(loop, omega, L, delay, ", shape (f, m, m)")
    undamped = _check_undamped(undamped)
    m = L.shape[1]
    if axes is None:
        axes = AXES if m == 3 else tuple(str(i + 1) for i in range(m))
    axes = tuple(axes)
    if len(axes) != m or not all(isinstance(a, str) for a in axes):
        raise ValueError(f"axes must name the loop's {m} inputs; got {describe(axes)}")
    if delay > 0.0:
        bare = loop

        def loop(w):
            w = np.asarray(w, dtype=float).reshape(-1)
            return bare(w) * np.exp(-1j * w * delay)[:, None, None]

        first = _multiloop_margins(loop, axes, omega,
                                   L * np.exp(-1j * omega * delay)[:, None, None], delay,
                                   undamped)
        refined = _delay_grid(None, omega, delay, _gain(L), harmless_gain(first, m))
        if refined.size == omega.size:
            return first
        new = ~np.isin(refined, omega)
        values = np.empty((refined.size, m, m), dtype=complex)
        values[~new] = L[np.searchsorted(omega, refined[~new])]
        if new.any():
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                values[new] = bare(refined[new])
        omega = refined
        L = values * np.exp(-1j * omega * delay)[:, None, None]
    return _multiloop_margins(loop, axes, omega, L, delay, undamped)


def _loop_arguments(loop, omega, L, delay, shape: str
                    ) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """The arguments of a loop known as a function (:func:`multiloop_margins`,
    :func:`loop_verdict`) checked: ``loop`` callable (``shape`` ends its message), ``omega`` an
    increasing grid [rad/s] of at least two points, ``delay`` [s]; returns (omega, delay, L as
    given or ``loop(omega)``, its values (f, m, m))."""
    if not callable(loop):
        raise TypeError(f"loop must be a function of omega [rad/s] giving L(j omega){shape}; got "
                        f"{type(loop).__name__}")
    omega = frequency_grid(omega, minimum=2)
    if np.any(np.diff(omega) <= 0):
        raise ValueError(f"omega must be increasing [rad/s]; got {describe(omega)}")
    delay = check_delay(delay)
    if L is None:
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            L = loop(omega)
    return omega, delay, L, _loop_matrix_values(L, omega.size)


def _check_undamped(undamped) -> np.ndarray | None:
    """``undamped`` of :func:`loop_margins` checked: None or positive finite frequencies
    [rad/s], as a 1-D float array."""
    if undamped is None:
        return None
    try:
        w = np.asarray(undamped, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise TypeError(f"undamped must be the frequencies of the loop's undamped poles [rad/s]; "
                        f"got {describe(undamped)}") from None
    if not np.all(np.isfinite(w) & (w > 0)):
        raise ValueError(f"undamped must be positive finite frequencies [rad/s]; got "
                         f"{describe(undamped)}")
    return w


def _loop_matrix_values(L, n: int) -> np.ndarray:
    """Loop values (f, m, m) (planar (f,) as m = 1) of n frequencies, or ValueError."""
    L = np.asarray(L)
    if L.dtype.kind not in "fc" or L.shape[:1] != (n,) or not (
            L.ndim == 1 or (L.ndim == 3 and L.shape[1] == L.shape[2] and L.shape[1] > 0)):
        raise ValueError(f"L must be the loop's values at the {n} frequencies, shape ({n},) or "
                         f"({n}, m, m); got {L.dtype} of shape {L.shape}")
    L = L.astype(complex)
    return L[:, None, None] if L.ndim == 1 else L


def _multiloop_margins(matrix: Callable[[np.ndarray], np.ndarray], axes: tuple, omega: np.ndarray,
                       L_grid: np.ndarray | None, tau: float,
                       undamped: np.ndarray | None = None) -> MultiLoopMargins:
    """:class:`MultiLoopMargins` of the loop ``matrix(w)`` -> (f, m, m) (the delay ``tau``
    [s] already in it) on the increasing grid ``omega`` (``L_grid`` its values, if known;
    ``undamped`` the frequencies of its undamped poles, if known)."""
    m = len(axes)

    def broken_all(w: np.ndarray) -> np.ndarray:
        """Every loop-at-a-time L_i = 1/S_ii - 1 (LoopTransfer.broken_all), (f, m)."""
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return loops_at_a_time(matrix(w))

    # L on the grid once: the loop-at-a-time functions and the singular values all follow from
    # S = (I + L)^-1 there; only the refinements evaluate L again
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if L_grid is None:
            L_grid = matrix(omega)
        S = sensitivity(L_grid)
        per_axis = dict(zip(axes, _loops_margins(
            lambda w, owner: _at_distinct(broken_all, w)[np.arange(w.size), owner], omega,
            1.0 / np.diagonal(S, axis1=1, axis2=2).T - 1.0, delay=tau, undamped=undamped)))

    def singular_values(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(sigma_max(S - I/2), sigma_min(I + L)) at each frequency."""
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            L = matrix(w)
            R = np.eye(m) + L
            S = sensitivity(L)
            return (np.linalg.svd(S - 0.5 * np.eye(m), compute_uv=False)[:, 0],
                    np.linalg.svd(R, compute_uv=False)[:, -1])

    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        finite = np.all(np.isfinite(L_grid), axis=(1, 2)) & np.all(np.isfinite(S), axis=(1, 2))
        peak = np.full(omega.size, np.nan)
        smallest = np.full(omega.size, np.nan)
        # the grid scan only locates the extrema (their values are recomputed by the SVD and
        # refined below): sigma_min(I + L) = 1 / sigma_max(S), and sigma_max of a 3 x 3 in
        # closed form, a tenth of the cost of a batched SVD over thousands of frequencies,
        # and only where the Frobenius norm says it may be the largest
        S_finite = S if finite.all() else S[finite]
        peak[finite] = _peak_singular_values(S_finite, 0.5)
        smallest[finite] = 1.0 / _peak_singular_values(S_finite)
    ok = np.isfinite(peak) & np.isfinite(smallest)
    disk_peak, w_disk = _refined_extremum(lambda w: singular_values(w)[0], omega[ok], peak[ok],
                                          maximum=True)
    sigma, w_sigma = _refined_extremum(lambda w: singular_values(w)[1], omega[ok], smallest[ok],
                                       maximum=False)
    alpha = 1.0 / disk_peak if disk_peak > 0 else math.inf
    # every loop at a time bounds both: S_ii = 1 / (1 + L_i) is an entry of S, so
    # sigma_min(I + L) = 1 / sigma_max(S) <= |1 + L_i| and sigma_max(S - I/2) >= |S_ii - 1/2|,
    # which is 1/(2 tan(PM/2)) at a gain crossover and at least 1/m - 1/2 where |1 + L_i| = m:
    # a dip of one of them narrower than the grid shows in its loop-at-a-time margins
    for mg in per_axis.values():
        if mg.modulus_margin < sigma:
            sigma, w_sigma = mg.modulus_margin, mg.modulus_margin_frequency
        bounds = [(2.0 * mg.modulus_margin / (2.0 - mg.modulus_margin)
                   if mg.modulus_margin < 2.0 else math.inf, mg.modulus_margin_frequency)]
        if math.isfinite(mg.phase_margin):
            bounds.append((2.0 * math.tan(math.radians(min(abs(mg.phase_margin), 179.0)) / 2.0),
                           mg.gain_crossover_frequency))
        for bound, w in bounds:
            if bound < alpha:
                alpha, w_disk = bound, w
    crossings = _unit_crossings(matrix, omega, L_grid)
    return MultiLoopMargins(per_axis, alpha, disk_margin_gain(alpha), disk_margin_phase(alpha),
                            w_disk, sigma, w_sigma, tau, _first_event(crossings, 0.0))


def _at_distinct(function: Callable[[np.ndarray], np.ndarray], w: np.ndarray) -> np.ndarray:
    """``function(w)`` (rows per frequency) with ``function`` called once per distinct
    frequency of ``w``: the refinements ask for the loop at one frequency for several of its
    functions (the loops at a time, their phase and gain crossovers and dips)."""
    w = np.asarray(w, dtype=float).reshape(-1)
    ordered = np.sort(w)
    if not (ordered[1:] == ordered[:-1]).any():   # a sort: a quarter of np.unique's cost
        return function(w)
    distinct, where = np.unique(w, return_inverse=True)
    return function(distinct)[where.reshape(-1)]


# a grid point whose Frobenius norm is below (1 - this) times a known largest singular value of
# the grid cannot hold the grid's largest one nor a peak within this of it: every peak within
# this of the largest is refined (_peak_singular_values, _refined_extremum; the closed form is
# accurate to about sqrt(eps) relative at worst)
_PEAK_SLACK = 0.1


def _peak_singular_values(A: np.ndarray, shift: float = 0.0) -> np.ndarray:
    """sigma_max of each matrix of a stack (f, m, m) minus ``shift`` times the identity
    wherever it may lie within 10 % (_PEAK_SLACK) of the largest of the stack, and at those
    points' neighbours (:func:`_largest_singular_values`); elsewhere the lower bound
    ||A||_F / sqrt(m), which lies below 0.9 times the largest.

    sigma_max <= ||A||_F, so a point whose Frobenius norm is below 0.9 times a known
    sigma_max of the stack lies more than 10 % below its maximum: the stack's largest value,
    every peak within 10 % of it (those :func:`_refined_extremum` refines) and their
    neighbours are those of :func:`_largest_singular_values` on the whole stack, at the cost
    of some of its points (the largest singular value peaks at the loop's few sharp
    resonances). The shifted matrices are formed at those points only."""
    f, m = A.shape[0], A.shape[1] if A.ndim == 3 else 0
    if f == 0:
        return np.zeros(0)

    def shifted(index: np.ndarray) -> np.ndarray:
        return A[index] - shift * np.eye(m) if shift else A[index]

    kernel = compiled_kernel()
    with np.errstate(over="ignore", invalid="ignore"):
        if kernel is not None and A.dtype == complex:
            frobenius = np.empty(f)
            kernel.shifted_frobenius(np.ascontiguousarray(A), float(shift), frobenius)
        else:
            B = A - shift * np.eye(m) if shift else A
            frobenius = np.sqrt(np.einsum("fij,fij->f", B.real, B.real)
                                + np.einsum("fij,fij->f", B.imag, B.imag))
    out = frobenius / math.sqrt(m)
    top = np.argsort(frobenius)[-4:]
    known = max(float(np.max(out)), float(np.max(_largest_singular_values(shifted(top)))))
    candidate = np.flatnonzero(~(frobenius < (1.0 - _PEAK_SLACK) * known))
    near = np.unique(np.clip(np.concatenate([candidate - 1, candidate, candidate + 1]), 0, f - 1))
    out[near] = _largest_singular_values(shifted(near))
    return out


def _largest_singular_values(A: np.ndarray) -> np.ndarray:
    """sigma_max of each matrix of a stack, shape (f, m, m) -> (f,).

    For m = 3, the largest eigenvalue of the Hermitian G = A^H A in closed form (Smith's
    trigonometric solution of the characteristic cubic, B = G - q I, q = tr G / 3,
    p^2 = ||B||_F^2 / 6: lambda_max = q + 2 p cos(acos(det B / (2 p^3)) / 3)); the largest
    eigenvalue is computed so to a relative error of a few eps, or about sqrt(eps) where the
    two largest eigenvalues coincide (acos is ill-conditioned at -1): good enough to locate an
    extremum on a grid (:func:`_refined_extremum` takes the values from the SVD). Other sizes:
    numpy's SVD.

    References
    ----------
    O. K. Smith, "Eigenvalues of a symmetric 3 x 3 matrix", Communications of the ACM 4(4),
    1961, p. 168; J. Kopp, "Efficient numerical diagonalization of hermitian 3x3 matrices",
    Int. J. Mod. Phys. C 19(3), 2008 (accuracy of the analytical method).
    """
    if A.shape[1:] != (3, 3):
        return np.linalg.svd(A, compute_uv=False)[:, 0]
    # scaled by the largest |entry| first: G and det B square and cube it
    scale = np.abs(A).max(axis=(1, 2))
    scale = np.where(scale > 0, scale, 1.0)
    A = A / scale[:, None, None]
    G = np.einsum("fki,fkj->fij", A.conj(), A)
    q = np.einsum("fii->f", G).real / 3.0
    B = G - q[:, None, None] * np.eye(3)
    p = np.sqrt(np.einsum("fij,fij->f", B.real, B.real)
                + np.einsum("fij,fij->f", B.imag, B.imag)) / math.sqrt(6.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        # det B by cofactors along the first row (B Hermitian: real up to round-off)
        det = (B[:, 0, 0] * (B[:, 1, 1] * B[:, 2, 2] - B[:, 1, 2] * B[:, 2, 1])
               - B[:, 0, 1] * (B[:, 1, 0] * B[:, 2, 2] - B[:, 1, 2] * B[:, 2, 0])
               + B[:, 0, 2] * (B[:, 1, 0] * B[:, 2, 1] - B[:, 1, 1] * B[:, 2, 0])).real
        r = np.clip(det / (2.0 * p ** 3), -1.0, 1.0)
    r = np.where(p > 0, r, 1.0)
    lam = q + 2.0 * p * np.cos(np.arccos(r) / 3.0)
    return scale * np.sqrt(np.maximum(lam, 0.0))


def _extremum_candidates(omega: np.ndarray, values: np.ndarray,
                         window: float = math.inf) -> np.ndarray:
    """Indices of the grid points whose minimum of a function (``values`` on the increasing
    grid ``omega``) is refined: the grid's least value, every point within 1e-6 of it, and
    every local minimum of the grid within ``window`` times the least value's modulus of it
    (default: every local minimum).

    A resonance sampled coarser than another, or a broad minimum on the grid's logarithmic
    stretch (about 3 % between points), can hide a lower minimum behind a higher grid value:
    a grid value says little of how far the true minimum beside it lies below it."""
    i = int(np.argmin(values))
    best = values[i]
    keep = values <= best + 1e-6 * abs(best)
    if values.size >= 3:
        g = values[1:-1]
        limit = best + window * abs(best) if math.isfinite(window) else math.inf
        keep[1:-1] |= (g <= values[:-2]) & (g <= values[2:]) & (g <= limit)
    keep[i] = True
    return np.flatnonzero(keep)


def _refined_extremum(f, omega: np.ndarray, values: np.ndarray, *, maximum: bool
                      ) -> tuple[float, float]:
    """Grid extremum of f refined between the grid neighbours
    (:func:`controllers.refine.refine`). ``values`` (to 1e-6 relative) only locate it: f itself
    gives the values at the candidates of :func:`_extremum_candidates` (every local extremum
    within _PEAK_SLACK of the grid's, where ``values`` are exact:
    :func:`_peak_singular_values`), and the best of them
    and every local extremum among them are refined together."""
    sign = -1.0 if maximum else 1.0
    near = _extremum_candidates(omega, sign * values, _PEAK_SLACK)
    exact = sign * np.asarray(f(omega[near]), dtype=float)
    i = int(near[np.argmin(exact)])
    best, w_best = float(exact[near == i][0]), float(omega[i])
    # the best candidate, and each interior one that is a local minimum of the exact values
    # among its neighbours' grid values
    n = omega.size
    inner = (near > 0) & (near < n - 1)
    k = near[inner]
    local = (exact[inner] <= sign * values[np.maximum(k - 1, 0)]) & (
        exact[inner] <= sign * values[np.minimum(k + 1, n - 1)])
    start = np.unique(np.concatenate([k[local], [i] if 0 < i < n - 1 else []]).astype(int))
    if start.size:
        fx = exact[np.searchsorted(near, start)]
        _, (x, fmin) = refine(lambda w, task: sign * np.asarray(f(w), dtype=float),
                              minima=(np.zeros(start.size, dtype=int), omega[start - 1],
                                      omega[start], omega[start + 1],
                                      sign * values[start - 1], fx,
                                      sign * values[start + 1]))
        j = int(np.argmin(fmin))
        if fmin[j] < best:
            best, w_best = float(fmin[j]), float(x[j])
    return sign * best, w_best


@warns_long_delay
def loop_margins(loop: Callable[[np.ndarray], np.ndarray], omega: np.ndarray,
                 L: np.ndarray | None = None, *, delay: float = 0.0,
                 undamped: np.ndarray | None = None) -> Margins:
    """Gain, phase and modulus margins of a scalar loop function, found on the function itself.

    The grid only brackets them: every crossing of |L| = 1 and of the negative real axis is
    refined on ``loop`` to 1e-13 relative in frequency (:func:`zero_crossings`), the
    minima of |1 + L| between the grid neighbours of each of its grid minima, all together
    (:func:`controllers.refine.refine`); the margins are the values of ``loop`` there. Two
    crossings between the same two grid points (|L| peaking just above 1 at a lightly damped
    mode, L touching the negative real axis) leave no sign change on the grid: every grid
    point where log|L| or Im L (Re L < 0) is nearer zero than both its neighbours, with their
    sign, has the extremum between them refined too, and where it has the other sign both
    crossings are refined on either side of it. A loop known exactly (the exact distributed
    beam's response through W(s)) gives its margins to the accuracy of its evaluation, not of
    a grid.

    Parameters
    ----------
    loop : callable
        ``loop(omega)`` -> L(j omega), complex array of the shape of ``omega`` (1-D, rad/s),
        negative-feedback convention (the loop is unstable at L = -1).
    omega : ndarray, rad/s
        Increasing grid that resolves L: every crossing, or the extremum of a pair of them,
        and the minimum of |1 + L| between two of its points.
    L : ndarray, optional
        ``loop(omega)``, if already known.
    delay : float, s
        A loop delay not in ``loop``: the margins are those of loop(omega) e^(-j omega delay),
        the grid refined for it as :func:`margins` refines its own.
    undamped : array of float, rad/s, optional
        Frequencies of the loop's undamped poles, if known (:meth:`LoopTransfer.
        undamped_frequencies`): beside each, L runs along a whole straight line and |1 + L|
        can dip far below its grid values in a band narrower than any grid; those dips are
        searched on ``loop``.

    Returns
    -------
    Margins
        With ``delay_margin``, the extra delay it tolerates (see :class:`Margins`).
    """
    if not callable(loop):
        raise TypeError(f"loop must be a function of omega [rad/s] giving L(j omega); got "
                        f"{type(loop).__name__}")
    omega = frequency_grid(omega, minimum=2)
    if L is not None and not (isinstance(L, np.ndarray) and L.shape == omega.shape
                              and L.dtype.kind in "fc"):
        raise ValueError(f"L must be loop(omega), an array of {omega.size} numbers; got "
                         f"{type(L).__name__} of shape {np.shape(L)}")
    delay = check_delay(delay)
    undamped = _check_undamped(undamped)
    if delay > 0.0:
        bare, given = loop, L

        def loop(w):
            w = np.asarray(w, dtype=float).reshape(-1)
            return bare(w) * np.exp(-1j * w * delay)

        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            values = bare(omega) if given is None else np.asarray(given).reshape(-1)
        first = _loops_margins(lambda w, owner: loop(w), omega,
                               (values * np.exp(-1j * omega * delay))[None, :], delay=delay,
                               undamped=undamped)[0]
        refined = _delay_grid(None, omega, delay, np.abs(values), harmless_gain(first, 1))
        if refined.size == omega.size:
            return first
        new = ~np.isin(refined, omega)
        L = np.empty(refined.size, dtype=complex)
        L[~new] = values[np.searchsorted(omega, refined[~new])]
        if new.any():
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                L[new] = bare(refined[new])
        omega = refined
        L = L * np.exp(-1j * omega * delay)
        out = _loops_margins(lambda w, owner: loop(w), omega, L[None, :], delay=delay,
                             undamped=undamped)[0]
        return out
    if L is None:
        with np.errstate(divide="ignore", invalid="ignore"):
            L = loop(omega)
    return _loops_margins(lambda w, owner: loop(w), omega, L[None, :], undamped=undamped)[0]


def _loops_margins(evaluate: Callable[[np.ndarray, np.ndarray], np.ndarray], omega: np.ndarray,
                   L: np.ndarray, *, delay: float = 0.0,
                   undamped: np.ndarray | None = None) -> list[Margins]:
    """Margins of m scalar loop functions L_j at once (the loop-at-a-time functions of a
    three-axis loop), each as :func:`loop_margins` finds them: ``L`` (m, f) on the grid,
    ``evaluate(w, owner)`` the value of L_owner[k] at w[k] (one evaluation of the loop serves
    every function, so the crossings of all of them are refined together); ``undamped``: the
    frequencies [rad/s] of the loop's undamped poles, whose dips of |1 + L| are searched
    (:func:`_undamped_dips`)."""
    grids = []
    for row in L:
        finite = np.isfinite(row)  # a grid point exactly on an undamped pole: L is infinite
        grids.append((omega[finite], row[finite]))

    m = len(grids)
    # the refinement's evaluations (frequencies, functions, values): every refined root is
    # one of its probes (or a grid point), so the loop is not evaluated there again
    evaluated: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []

    def values_at(roots: list[np.ndarray]) -> list[np.ndarray]:
        owner = np.concatenate([np.full(r.size, j) for j, r in enumerate(roots)]).astype(int)
        if owner.size == 0:
            return [np.zeros(0, dtype=complex) for _ in roots]
        w, function = np.concatenate(roots), owner % m
        values = np.empty(w.size, dtype=complex)
        missing = np.ones(w.size, dtype=bool)
        if evaluated:
            w_all, function_all, values_all = (np.concatenate(v) for v in zip(*evaluated))
            for j in range(m):
                mine, asked = function_all == j, np.flatnonzero(function == j)
                if not (asked.size and mine.any()):
                    continue
                order = np.argsort(w_all[mine])
                w_j, values_j = w_all[mine][order], values_all[mine][order]
                i = np.minimum(np.searchsorted(w_j, w[asked]), w_j.size - 1)
                hit = w_j[i] == w[asked]
                values[asked[hit]] = values_j[i[hit]]
                missing[asked[hit]] = False
        if missing.any():
            values[missing] = evaluate(w[missing], function[missing])
        return [values[owner == j] for j in range(len(roots))]

    def crossing(w: np.ndarray, owner: np.ndarray) -> np.ndarray:
        """Im L_j for owner j < m, log|L_j| for owner m + j, |1 + L_j| for owner 2 m + j, and
        minus the first two for owner 3 m + j and 4 m + j: one evaluation of the loop per step
        refines the phase and the gain crossovers, the minima of |1 + L| and the extrema of
        the crossings' functions (:func:`_grazes`) together."""
        values = evaluate(w, owner % m)
        evaluated.append((w, owner % m, np.array(values)))   # (a loop may reuse its buffer)
        kind = np.where(owner < 3 * m, owner, owner - 3 * m) // m
        with np.errstate(divide="ignore", invalid="ignore"):
            out = np.where(kind == 0, values.imag,
                           np.where(kind == 1, np.log(np.abs(values)), np.abs(1.0 + values)))
        return np.where(owner < 3 * m, out, -out)

    # phase crossovers: L real and negative (Im L changes sign where Re L < 0). Crossings where
    # |L| < 1e-9 (a gain margin above 180 dB) are round-off in Im L, not a margin.
    # gain crossovers: |L| = 1
    with np.errstate(divide="ignore"):
        exact, brackets, guesses = _sign_changes([(w, row.imag) for w, row in grids]
                                                 + [(w, np.log(np.abs(row))) for w, row in grids])
    # modulus margin: min |1 + L|, refined between the neighbours of the grid's least value
    # (and every other local minimum of the grid, but those whose neighbours hold an undamped
    # pole between them or lie within 1e-6 of one: there |1 + L| is the distance of L's line
    # to -1, whose dip _undamped_dips searches)
    poles = np.sort(np.asarray(undamped, dtype=float)) if undamped is not None else np.zeros(0)
    grid_minima, minima = [], []
    for j, (w_grid, row) in enumerate(grids):
        dist = np.abs(1.0 + row)
        best_i = int(np.argmin(dist))
        grid_minima.append((float(dist[best_i]), float(w_grid[best_i])))
        for i in _extremum_candidates(w_grid, dist).tolist():
            if not (0 < i < w_grid.size - 1 and dist[i] <= dist[i - 1]
                    and dist[i] <= dist[i + 1]):
                continue
            w_lo, w_hi = w_grid[i - 1] * (1.0 - 1e-6), w_grid[i + 1] * (1.0 + 1e-6)
            beside = np.searchsorted(poles, w_hi, side="right") > np.searchsorted(poles, w_lo)
            if i == best_i or not beside:
                minima.append((2 * m + j, w_grid[i - 1], w_grid[i], w_grid[i + 1],
                               dist[i - 1], dist[i], dist[i + 1]))
    # a pair of crossings between two grid points (|L| peaking just above 1, L touching the
    # negative real axis) leaves no sign change on the grid: the extremum of the function
    # between such neighbours is refined with the minima of |1 + L| (the same evaluations)
    # (L touching the negative real axis where |L| is above the 1e-9 below which Im L is
    # round-off)
    with np.errstate(divide="ignore", invalid="ignore"):
        functions = ([(w, row.imag, (row.real < 0.0) & (np.abs(row) > 1e-9)) for w, row in grids]
                     + [(w, np.log(np.abs(row)), None) for w, row in grids])
        grazes = _grazes(functions, 3 * m)
    tasks = minima + grazes
    (root, found), (w_min, dist_min) = refine(
        crossing, roots=brackets, guesses=guesses,
        minima=tuple(np.array(v) for v in zip(*tasks)) if tasks else None,
        sign_only=np.arange(len(tasks)) >= len(minima))
    # where the function's extremum has the other sign, it crosses zero on either side of it
    pairs, touches = [], []
    for (task, lo, _, hi, f_lo, _, f_hi), x, fx in zip(grazes, w_min[len(minima):],
                                                        dist_min[len(minima):]):
        sign, j = (1.0, task) if task < 3 * m else (-1.0, task - 3 * m)
        if fx == 0.0:
            touches.append((j, x))
        elif fx < 0.0:
            pairs += [(j, lo, x, sign * f_lo, sign * fx), (j, x, hi, sign * fx, sign * f_hi)]
    for j, x in touches:
        exact[j] = np.append(exact[j], x)
    if pairs:
        more = tuple(np.array(v) for v in zip(*pairs))
        (root_more, found_more), _ = refine(crossing, roots=more)
        brackets = tuple(np.concatenate([old, new]) for old, new in zip(brackets, more))
        root, found = np.concatenate([root, root_more]), np.concatenate([found, found_more])
    owner = brackets[0]
    roots = [np.concatenate([exact[j], root[found & (owner == j)]]) for j in range(2 * m)]
    refined: dict[int, tuple] = {}
    for (task, *_), d, w in zip(minima, dist_min, w_min):
        refined[task - 2 * m] = min(refined.get(task - 2 * m, (math.inf, math.nan)),
                                    (float(d), float(w)))
    phase_roots, gain_roots = roots[:m], roots[m:]
    values = values_at(roots)
    L_phase, L_gain = values[:m], values[m:]
    # |1 + L| dips where L passes close to -1, at a gain crossover with a small phase margin:
    # beside a lightly damped pole such a dip can be far narrower than the grid's spacing, so
    # the grid minimum may miss it. Each crossover whose |1 + L| is below the best found so far
    # starts a minimum search between the grid points that bracketed it.
    best = [min((grid_minima[j],) + ((refined[j],) if j in refined else ()))
            for j in range(m)]
    dips = []
    for j in range(m):
        w_grid, row = grids[j]
        mine = np.flatnonzero(found & (owner == m + j))
        if mine.size == 0:
            continue
        # L there is known: the gain crossovers' values, after those exactly on the grid
        at = np.abs(1.0 + L_gain[j][exact[m + j].size:])
        for k, d in zip(mine, at):
            if not d < best[j][0]:
                continue
            best[j] = (float(d), float(root[k]))
            lo, hi = brackets[1][k], brackets[2][k]
            if lo < root[k] < hi:
                i_lo, i_hi = np.searchsorted(w_grid, [lo, hi])
                dips.append((2 * m + j, lo, root[k], hi, abs(1.0 + row[i_lo]), d,
                             abs(1.0 + row[i_hi])))
    if undamped is not None and len(undamped):
        more, floors = _undamped_dips(evaluate, m, np.asarray(undamped, dtype=float), best,
                                      omega[0], omega[-1])
        dips += [(2 * m + j, *rest) for j, *rest in more]
        for j, d, w in floors:
            best[j] = min(best[j], (d, w))
    if dips:
        _, (w_dip, dist_dip) = refine(crossing, minima=tuple(np.array(v) for v in zip(*dips)))
        for (task, *_), d, w in zip(dips, dist_dip, w_dip):
            best[task - 2 * m] = min(best[task - 2 * m], (float(d), float(w)))
    out = []
    for j in range(m):
        gain_margin, w_pc = math.inf, math.inf
        for w, Lw in zip(phase_roots[j], L_phase[j]):
            if Lw.real < 0 and abs(Lw) > 1e-9:
                gm = -20.0 * math.log10(abs(Lw))
                if abs(gm) < abs(gain_margin):
                    gain_margin, w_pc = gm, float(w)
        phase_margin, w_gc = math.inf, math.inf
        delay_margin = math.inf
        for w, Lw in zip(gain_roots[j], L_gain[j]):
            pm = 180.0 + math.degrees(cmath.phase(Lw))  # in (0, 360]
            # the extra delay that turns this crossover onto -1: PM in [0, 2 pi) over omega_c
            delay_margin = min(delay_margin, (math.pi + cmath.phase(Lw)) % (2.0 * math.pi) / w)
            pm = pm - 360.0 if pm > 180.0 else pm
            if abs(pm) < abs(phase_margin):
                phase_margin, w_gc = pm, float(w)
        mm, w_mm = best[j]
        # at a gain crossover |1 + L| = 2 sin(PM / 2) exactly; beside an undamped pole the
        # crossover and its dip can lie closer to the pole than L is evaluated to the accuracy
        # of that small value, but the phase there is well conditioned: it bounds the margin
        at_crossover = 2.0 * math.sin(math.radians(min(abs(phase_margin), 180.0)) / 2.0)
        if at_crossover < mm:
            mm, w_mm = at_crossover, w_gc
        out.append(Margins(float(gain_margin), float(phase_margin), mm, float(w_gc), float(w_pc),
                           w_mm, float(delay), float(delay_margin)))
    return out


def _grazes(functions: list[tuple[np.ndarray, np.ndarray, np.ndarray | None]],
            negated: int) -> list[tuple]:
    """Minimum brackets (task, lo, x, hi, f(lo), f(x), f(hi)) for
    :func:`controllers.refine.refine` of the extrema where a function may cross zero twice
    between two grid points, its sign the same at both.

    ``functions[t] = (omega, values, relevant)``: function t on its grid, and where its zeros
    matter (None: everywhere). A grid point where the function has the sign of both its
    neighbours and is nearer zero than either (a local minimum of s f, s its sign there) is
    such an extremum: the task is t (s = +1) or ``negated`` + t (s = -1, the function's
    negative), and the values are those of s f. Where the refined minimum of s f is negative,
    the function crosses zero on either side of it."""
    out = []
    for t, (omega, values, relevant) in enumerate(functions):
        if values.size < 3:
            continue
        sign = np.sign(values)
        size = np.abs(values)
        middle = ((sign[1:-1] != 0) & (sign[:-2] == sign[1:-1]) & (sign[2:] == sign[1:-1])
                  & (size[1:-1] < size[:-2]) & (size[1:-1] <= size[2:]))
        if relevant is not None:
            middle &= relevant[1:-1]
        i = np.flatnonzero(middle) + 1
        for k, s in zip(i.tolist(), sign[i].tolist()):
            out.append((t if s > 0 else negated + t, omega[k - 1], omega[k], omega[k + 1],
                        s * values[k - 1], s * values[k], s * values[k + 1]))
    return out


def _undamped_dips(evaluate: Callable[[np.ndarray, np.ndarray], np.ndarray], m: int,
                   undamped: np.ndarray, best: list, w_lo: float, w_hi: float
                   ) -> tuple[list, list]:
    """The dips of |1 + L_j| beside undamped poles that may lie below ``best[j]`` (value,
    frequency): (minimum brackets (j, lo, x, hi, f(lo), f(x), f(hi)) for
    :func:`controllers.refine.refine`, [(j, value, frequency)] of dips too close to their pole
    to be evaluated).

    Near an undamped pole w0, L(w0 + x) = c + r / x + O(x): as x runs through 0, L runs along
    the whole straight line c + t r (t = 1/x real), which passes -1 at the distance
    |Im((1 + c) conj(r))| / |r|, at t* = -Re((1 + c) conj(r)) / |r|^2. That dip can be far
    narrower than a grid's spacing, and away from any crossing of |L| = 1: c and r are taken
    from L at w0 (1 +- 1e-9) (c the mean, r from the difference), and the dip, where it may
    be lower than the best found, is searched on L about w0 + 1/t*, or, closer to the pole
    than 1e-13 w0 (beyond what L can be evaluated to there), taken from the line itself (to
    about 1 % of its value: the smooth part of L varies over 2e-9 w0, and L is evaluated
    there to about eps / 1e-9 of the pole's term)."""
    undamped = undamped[(undamped > w_lo) & (undamped < w_hi)]
    brackets, floors = [], []
    if undamped.size == 0:
        return brackets, floors
    x = 1e-9 * undamped
    w = np.concatenate([undamped - x, undamped + x])
    owner = np.repeat(np.arange(m), w.size)
    with np.errstate(all="ignore"):
        values = np.asarray(evaluate(np.tile(w, m), owner)).reshape(m, 2, -1)
        below, above = values[:, 0], values[:, 1]
        c = 0.5 * (below + above)
        r = 0.5 * (above - below) * x
        # a pole of this function: L changes across it by more than its smooth part could
        # over 2e-9 of the frequency (the pole's own term |r| / x may still be small next to c:
        # a mode the loop barely feels, its dip within 1e-9 of it)
        pole = (np.isfinite(c) & np.isfinite(r)
                & (np.abs(above - below) > 2e-6 * (1.0 + np.abs(c))))
        t = -((1.0 + c) * r.conj()).real / np.abs(r) ** 2
        depth = np.abs(((1.0 + c) * r.conj()).imag) / np.abs(r)
        offset = 1.0 / t
    for j in range(m):
        for k in np.flatnonzero(pole[j] & (depth[j] < best[j][0]) & np.isfinite(offset[j])):
            w0, dx = undamped[k], offset[j, k]
            if abs(dx) < 1e-13 * w0:
                floors.append((j, float(depth[j, k]), float(w0)))
                continue
            ends = sorted([w0 + 0.5 * dx, w0 + 2.0 * dx])
            line = [abs(1.0 + c[j, k] + r[j, k] / (e - w0)) for e in (ends[0], w0 + dx, ends[1])]
            brackets.append((j, ends[0], w0 + dx, ends[1], *line))
    return brackets, floors


def _gain(L: np.ndarray) -> np.ndarray:
    """Largest |entry| of L(j omega) at each frequency, (f,) (non-finite: inf)."""
    L = np.asarray(L)
    with np.errstate(invalid="ignore"):
        g = np.abs(L.reshape(L.shape[0], -1)).max(axis=1)
    return np.where(np.isfinite(g), g, np.inf)


def harmless_gain(bound: Margins | MultiLoopMargins, m: int = 1) -> float:
    """The largest |L| entry at which a loop's delay cannot lower the margins ``bound``.

    Margins found on a grid bound the true ones from above (a crossing or dip between grid
    points can only lower them), and the delay e^(-j omega tau) leaves |L| as it is. Where every
    entry of L (m x m) has modulus at most the returned g, no margin can fall below ``bound``:
    with a = m g >= sigma_max(L) (Frobenius bound) and e = a / (1 - a) >= ||S - I||,
    S = (I + L)^-1, a loop-at-a-time L_i = 1/S_ii - 1 has |L_i| <= e / (1 - e); a crossing of the
    negative real axis there gives a gain margin of at least 1/|L_i| and |1 + L_i| >=
    1 - |L_i|, sigma_max(S - I/2) <= 1/2 + e and sigma_min(I + L) >= 1 - a. For a single loop
    (m = 1) L_i = L. A phase crossover matters only where |L| >= 1/GM and the modulus dips only
    where |L| >= 1 - modulus margin; the gain crossovers (|L| = 1) do not depend on the delay.

    Parameters
    ----------
    bound : Margins or MultiLoopMargins
        Margins of the loop (delay included) on a grid.
    m : int
        The loop's size (1: a single loop).

    Returns
    -------
    float
        g >= 0 (0: everywhere matters).
    """
    if isinstance(bound, MultiLoopMargins):
        loops = list(bound.loop_at_a_time.values())
        # |L_i| <= t <=> e <= t / (1 + t) <=> a <= e / (1 + e)
        limits = [1.0 / bound.disk_margin - 0.5 if bound.disk_margin > 0 else math.inf]
    else:
        loops, limits = [bound], []
    for mg in loops:
        t = min(10.0 ** (-abs(mg.gain_margin) / 20.0), 1.0 - mg.modulus_margin)
        limits.append(t / (1.0 + t) if m > 1 and t > 0.0 else t)
    e = min(limits)
    if not e > 0.0:
        return 0.0
    if m == 1:
        return e
    a = min(e / (1.0 + e), 1.0 - bound.min_singular_value)
    return max(a, 0.0) / m


def _delay_grid(gain: Callable[[np.ndarray], np.ndarray] | None, omega: np.ndarray,
                delay: float, values: np.ndarray | None = None,
                harmless: float = 0.0) -> np.ndarray:
    """``omega`` with points added where omega delay changes by more than pi/4 between two grid
    points at which |L| (``gain(omega)`` or ``values``) reaches half of ``harmless`` (a
    :func:`harmless_gain`; margin against the growth of |L| between grid points, which resolve
    every lightly damped mode) or 1e-9: the phase -omega delay is then resolved wherever a
    crossing of the negative real axis or a dip of |1 + L| can lower the margins."""
    if values is None:
        with np.errstate(all="ignore"):
            values = gain(omega)
    values = np.where(np.isfinite(values), values, np.inf)
    step = 0.25 * math.pi / delay
    width = np.diff(omega)
    threshold = max(0.5 * harmless, _NEGLIGIBLE_GAIN)
    relevant = np.maximum(values[:-1], values[1:]) >= threshold
    with np.errstate(over="ignore", invalid="ignore"):
        needed = np.where(relevant, np.ceil(width / step) - 1.0, 0.0)
    total = float(np.sum(np.maximum(needed, 0.0))) + omega.size
    if not total <= MAX_DELAY_GRID:
        top = float(omega[1:][relevant].max())
        raise ValueError(
            f"controller.delay = {delay:.4g} s needs {total:.3g} frequencies to resolve its phase "
            f"omega delay (pi/4 per step) where the loop gain can still lower the margins, up "
            f"to {top:.4g} rad/s: more than MAX_DELAY_GRID = {MAX_DELAY_GRID:.3g}; a delay "
            f"below about {MAX_DELAY_GRID * 0.25 * math.pi / top:.3g} s would do (check its unit: "
            "seconds)")
    if total == omega.size:
        return omega
    counts = np.maximum(needed, 0.0).astype(np.int64)
    starts = np.repeat(omega[:-1], counts)
    steps = np.repeat(width / (counts + 1), counts)
    offsets = np.arange(starts.size) - np.repeat(np.cumsum(counts) - counts, counts) + 1
    return np.unique(np.concatenate([omega, starts + steps * offsets]))


def _unit_crossings(matrix: Callable[[np.ndarray], np.ndarray], omega: np.ndarray,
                    L: np.ndarray | None = None) -> list[tuple[float, complex, int]]:
    """Where an eigenvalue of L(j omega) crosses the unit circle: (omega_c [rad/s], lambda_c,
    direction), direction +1 where |lambda| falls through 1 (a closed-loop root then crosses
    to the right as the delay grows), -1 where it rises.

    Found from the number of eigenvalues outside the unit circle on the grid (no tracking of
    eigenvalues needed), each change located to 1e-13 relative in frequency. Where the count
    changes by one between two grid points (one eigenvalue crosses), the crossing is a sign
    change of the product of (|lambda_k| - 1) over the eigenvalues, a function of omega as
    continuous as they are (symmetric in them, so again no tracking), refined as a root
    (:func:`controllers.refine.refine`, superlinear); other brackets, and any such root the
    refinement does not confirm, are bisected on the count, at _SECTIONS - 1 points of every
    bracket per step. ``matrix(w)`` gives L, shape (f, m, m) (``L``: its values on ``omega``,
    if known); a planar loop is the m = 1 case (|L| = 1: the gain crossovers). The count needs
    no eigenvalues where ||L||_F < 1 (every |lambda| < 1), nor, for m = 2 or 3, where one
    coefficient of the characteristic polynomial dominates on the unit circle
    (:func:`_outside_unit_circle`, Rouche's theorem: beside resonances too), else where
    ||L^-1||_F < 1 (every |lambda| > 1): the eigenvalues are computed at a few points of a
    grid only.
    """
    kernel = compiled_kernel()

    def count_at(w, L=None):
        with np.errstate(all="ignore"):
            L = matrix(w) if L is None else L
            m = L.shape[1]
            if kernel is not None and m in (2, 3):
                # the same decisions compiled, eigenvalues where they decide nothing
                count = np.empty(L.shape[0], dtype=np.int64)
                kernel.unit_circle_count(np.ascontiguousarray(L, dtype=complex),
                                         _COEFFICIENT_ERROR, count)
                finite = count != -2
                lam = np.full(L.shape[:2], np.nan, dtype=complex)
                hard = np.flatnonzero(count == -1)
                count[~finite] = 0
                if hard.size:
                    lam[hard] = _eigenvalues(L[hard])
                    count[hard] = np.sum(np.abs(lam[hard]) > 1.0, axis=1)
                return count, lam, finite
            finite = np.all(np.isfinite(L), axis=(1, 2))
            count = np.zeros(L.shape[0], dtype=int)
            lam = np.full(L.shape[:2], np.nan, dtype=complex)
            small = finite & (np.sqrt(np.sum(np.abs(L) ** 2, axis=(1, 2))) < 1.0)
            rest = finite & ~small
            if rest.any():
                idx = np.nonzero(rest)[0]
                if m in (2, 3):
                    decided = _outside_unit_circle(L[rest])
                    count[idx] = decided
                    hard = idx[decided < 0]
                else:
                    inverse = np.linalg.inv(L[rest]) if m > 1 else 1.0 / L[rest]
                    large = np.sqrt(np.sum(np.abs(inverse) ** 2, axis=(1, 2))) < 1.0
                    count[idx[large]] = m
                    hard = idx[~large]
                if hard.size:
                    lam[hard] = np.linalg.eigvals(L[hard])
                    count[hard] = np.sum(np.abs(lam[hard]) > 1.0, axis=1)
        return count, lam, finite

    def eigenvalues_at(w):
        with np.errstate(all="ignore"):
            L = matrix(w)
        finite = np.all(np.isfinite(L), axis=(1, 2))
        lam = np.full(L.shape[:2], np.inf, dtype=complex)
        if finite.any():
            lam[finite] = _eigenvalues(L[finite])
        return lam, finite

    def product_at(w, task=None):
        """prod_k (|lambda_k| - 1) at each frequency (NaN on a pole)."""
        lam, ok = eigenvalues_at(w)
        with np.errstate(all="ignore"):
            return np.where(ok, np.prod(np.abs(lam) - 1.0, axis=1).real, np.nan)

    count, lam, finite = count_at(omega, L)
    m = lam.shape[1]
    grid, count = omega[finite], count[finite]
    i = np.nonzero(count[:-1] != count[1:])[0]
    a, b, ca, cb = grid[i].astype(float), grid[i + 1].astype(float), count[i], count[i + 1]
    # an eigenvalue that grazes the unit circle between two grid points crosses it twice
    # there, the count the same at both: found as a minimum of its distance to the circle (a
    # planar loop's |L| peaking just above 1 between two grid points, or dipping just below)
    pairs = _grazing_pairs(eigenvalues_at, count_at, grid, count,
                           None if L is None else L[finite])
    if pairs[0].size:
        a, b = np.concatenate([a, pairs[0]]), np.concatenate([b, pairs[1]])
        ca, cb = np.concatenate([ca, pairs[2]]), np.concatenate([cb, pairs[3]])
        order = np.argsort(a, kind="stable")
        a, b, ca, cb = a[order], b[order], ca[order], cb[order]
    if a.size == 0:
        return []
    out = []
    single = np.abs(cb - ca) == 1
    if single.any():
        ends = product_at(np.concatenate([a[single], b[single]])).reshape(2, -1)
        # the product's sign is (-1)^(eigenvalues inside): it changes across the bracket
        sign_change = np.isfinite(ends).all(axis=0) & (ends[0] * ends[1] < 0)
        usable, ends = np.flatnonzero(single)[sign_change], ends[:, sign_change]
        if usable.size:
            (root, found), _ = refine(product_at, roots=(np.zeros(usable.size, dtype=int),
                                                         a[usable], b[usable], ends[0], ends[1]))
            lam, ok = eigenvalues_at(root)
            # the count across the root (a few 1e-13 about it, beyond the refined bracket)
            # changes as across the grid's bracket: one eigenvalue crossing in that direction
            # (else, several crossings between two grid points, the count is bisected)
            lo, hi = root * (1.0 - 2e-13), root * (1.0 + 2e-13)
            c_ends, _, ok_ends = count_at(np.concatenate([lo, hi]))
            c_lo, c_hi = c_ends[:usable.size], c_ends[usable.size:]
            done = (found & ok & ok_ends[:usable.size] & ok_ends[usable.size:]
                    & (c_hi - c_lo == cb[usable] - ca[usable]))
            for k in np.flatnonzero(done):
                j = int(np.argmin(np.abs(np.abs(lam[k]) - 1.0)))
                change = int(cb[usable[k]]) - int(ca[usable[k]])
                out.append((float(root[k]), complex(lam[k, j]), -1 if change > 0 else 1))
            keep = np.ones(a.size, dtype=bool)
            keep[usable[done]] = False
            # a root not confirmed (a pass through an undamped pole, where the count may change
            # too, or several crossings): the count is bisected from the few 1e-13 about
            # where the refinement closed in if it changes there, else from the grid's bracket
            left = np.flatnonzero(~done)
            near = (ok_ends[:usable.size] & ok_ends[usable.size:] & (c_lo != c_hi)
                    & (lo > a[usable]) & (hi < b[usable]))[left]
            k = usable[left[near]]
            a[k], b[k] = lo[left[near]], hi[left[near]]
            ca[k], cb[k] = c_lo[left[near]], c_hi[left[near]]
            a, b, ca, cb = a[keep], b[keep], ca[keep], cb[keep]
    # each step counts at sections - 1 points inside every bracket at once (one evaluation of
    # L for all): the bracket shrinks sections-fold per call instead of two-fold; the few
    # brackets left once the others are refined as roots are cut into more sections, the
    # evaluations' cost then being their calls, not their points. A bracket whose count
    # changes by more than at the change it closes in on (several crossings between two grid
    # points, apart) leaves the rest of its change to a bracket from there to its end, bisected
    # in turn (at most m - 1 times: each takes one crossing at least)
    for _ in range(m):
        end, end_count = b.copy(), cb.copy()
        for _ in range(100):
            active = (b - a) > 1e-13 * b
            if not active.any():
                break
            idx = np.nonzero(active)[0]
            sections = max(_SECTIONS, _BISECTION_POINTS // idx.size)
            fractions = np.arange(1, sections) / sections
            points = a[idx, None] + (b[idx] - a[idx])[:, None] * fractions  # (k, sections - 1)
            cm, _, ok = count_at(points.ravel())
            # a point on an undamped pole (non-finite L): counted as the bracket's start
            cm = np.where(ok, cm, np.repeat(ca[idx], fractions.size)).reshape(points.shape)
            moved = cm != ca[idx, None]
            first = np.where(moved.any(axis=1), np.argmax(moved, axis=1), fractions.size)
            rows = np.arange(idx.size)
            inside = first < fractions.size
            # the count changes between the last point that keeps the start's count and the
            # first that does not (or the bracket's end)
            a[idx[first > 0]] = points[rows, first - 1][first > 0]
            b[idx[inside]] = points[rows[inside], first[inside]]
            cb[idx[inside]] = cm[rows[inside], first[inside]]
        w = 0.5 * (a + b)
        lam, ok = eigenvalues_at(w)
        for k in range(w.size):
            if not ok[k]:
                continue
            change = int(cb[k]) - int(ca[k])
            closest = np.argsort(np.abs(np.abs(lam[k]) - 1.0))[:abs(change)]
            for j in closest:
                out.append((float(w[k]), complex(lam[k, j]), -1 if change > 0 else 1))
        rest = np.flatnonzero((cb != end_count) & (b < end))
        if rest.size == 0:
            break
        a, b, ca, cb = b[rest], end[rest], cb[rest], end_count[rest]
    out.sort(key=lambda crossing: crossing[0])
    return out


def _grazing_pairs(eigenvalues_at, count_at, grid: np.ndarray, count: np.ndarray,
                   L: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Brackets (a, b, count at a, count at b) of the unit-circle crossings that come in pairs
    between two grid points: an eigenvalue of L that leaves the circle and comes back (or
    enters and leaves) between them, the count of eigenvalues outside the same at both.

    With the moduli of the eigenvalues sorted, rho_1 >= ... >= rho_m (continuous in omega),
    and c eigenvalues outside at three neighbouring grid points, such a pair makes
    f_out = 1 - rho_(c+1) (c < m) or f_in = rho_c - 1 (c > 0), positive at the points, negative
    in between. Each local minimum of f_out or f_in on the grid whose two neighbours have the
    same count is refined between them (:func:`controllers.refine.refine`); where the refined
    minimum is negative, the count there differs, and the two crossings are bracketed on
    either side of it (then bisected on the count with the grid's brackets)."""
    empty = np.zeros(0)
    if grid.size < 3:
        return empty, empty, empty.astype(int), empty.astype(int)
    lam, ok = (eigenvalues_at(grid) if L is None else
               (_eigenvalues(L), np.ones(grid.size, dtype=bool)))
    m = lam.shape[1]
    rho = -np.sort(-np.abs(lam), axis=1)                        # (f, m), decreasing
    rows = np.arange(grid.size)
    with np.errstate(invalid="ignore"):
        f_out = np.where(count < m, 1.0 - rho[rows, np.minimum(count, m - 1)], np.inf)
        f_in = np.where(count > 0, rho[rows, np.maximum(count - 1, 0)] - 1.0, np.inf)
    same = ok[1:-1] & ok[:-2] & ok[2:] & (count[:-2] == count[1:-1]) & (count[2:] == count[1:-1])
    tasks, lo, x, hi, f_lo, f_x, f_hi = [], [], [], [], [], [], []
    for task, f in ((0, f_out), (1, f_in)):
        mid = f[1:-1]
        local = np.flatnonzero(same & np.isfinite(mid) & (mid < f[:-2]) & (mid <= f[2:])) + 1
        tasks.append(np.full(local.size, task) * grid.size + local)
        lo.append(grid[local - 1])
        x.append(grid[local])
        hi.append(grid[local + 1])
        f_lo.append(f[local - 1])
        f_x.append(f[local])
        f_hi.append(f[local + 1])
    tasks = np.concatenate(tasks).astype(int)
    if tasks.size == 0:
        return empty, empty, empty.astype(int), empty.astype(int)
    # task t: function t // grid.size (0: f_out, 1: f_in) with the count of grid point
    # t % grid.size
    base = count[tasks % grid.size]

    def distance(w, task):
        lam_w, ok_w = eigenvalues_at(w)
        r = -np.sort(-np.abs(lam_w), axis=1)
        c = count[task % grid.size]
        k = task // grid.size
        with np.errstate(invalid="ignore"):
            value = np.where(k == 0, 1.0 - r[np.arange(w.size), np.minimum(c, m - 1)],
                             r[np.arange(w.size), np.maximum(c - 1, 0)] - 1.0)
        return np.where(ok_w, value, np.nan)

    index = np.arange(tasks.size)
    _, (w_min, f_min) = refine(lambda w, k: distance(w, tasks[k]),
                               minima=(index, *(np.concatenate(v) for v in
                                                (lo, x, hi, f_lo, f_x, f_hi))),
                               sign_only=np.ones(index.size, dtype=bool))
    crossed = np.flatnonzero(f_min < 0.0)
    # (one pair per grid interval: f_out's and f_in's minima at one grid point would bracket
    # the same crossings twice)
    crossed = crossed[np.unique(tasks[crossed] % grid.size, return_index=True)[1]]
    if crossed.size == 0:
        return empty, empty, empty.astype(int), empty.astype(int)
    c_at, _, ok_at = count_at(w_min[crossed])
    keep = ok_at & (c_at != base[crossed])
    crossed, c_at = crossed[keep], c_at[keep]
    lo_all, hi_all = np.concatenate(lo)[crossed], np.concatenate(hi)[crossed]
    at = w_min[crossed]
    c0 = base[crossed]
    return (np.concatenate([lo_all, at]), np.concatenate([at, hi_all]),
            np.concatenate([c0, c_at]), np.concatenate([c_at, c0]))


def _eigenvalues(L: np.ndarray) -> np.ndarray:
    """The eigenvalues (f, m) of each finite matrix of a stack (f, m, m): for m = 1 the
    entries, for m = 2, 3 compiled (:func:`controllers._loop_kernel.eigenvalues`, zgeev's steps
    for eigenvalues alone, without numpy's per-matrix cost of several microseconds), numpy's
    otherwise and for any matrix whose QR steps did not converge."""
    if L.shape[1] == 1:
        return L[:, 0, :].astype(complex)      # a planar loop: L itself (no kernel to compile)
    kernel = compiled_kernel()
    if kernel is None or L.shape[1] > 3 or L.shape[0] == 0:
        return np.linalg.eigvals(L)
    L = np.ascontiguousarray(L, dtype=complex)
    lam = np.empty(L.shape[:2], dtype=complex)
    converged = np.empty(L.shape[0], dtype=np.bool_)
    kernel.eigenvalues(L, lam, converged)
    if not converged.all():
        lam[~converged] = np.linalg.eigvals(L[~converged])
    return lam


# a characteristic polynomial coefficient's rounding error, relative to the sum of the moduli
# of the products it is made of (a few unit round-offs for a 3 x 3's minors and determinant)
_COEFFICIENT_ERROR = 1e-12


def _outside_unit_circle(L: np.ndarray) -> np.ndarray:
    """Number of eigenvalues outside the unit circle of each matrix of a stack (f, m, m),
    m = 2 or 3, where Rouche's theorem decides it from the characteristic polynomial; -1
    elsewhere.

    det(z I - L) = z^m + c_(m-1) z^(m-1) + ... + c_0, with c_(m-1) = -tr L, c_(m-2) the sum of
    the principal 2 x 2 minors and c_0 = (-1)^m det L. Where one term dominates on the unit
    circle, |c_k| > sum over j != k of |c_j| (c_m = 1), the polynomial has as many zeros
    inside the circle as z^k, k, and none on it: m - k eigenvalues lie outside. Each |c_j| is
    taken with a bound of its rounding error (_COEFFICIENT_ERROR times the sum of the moduli
    of the products it is made of), so that the count is that of the matrix as given. Near a
    loop's resonance one eigenvalue is large and the others small, where the Frobenius norms of
    L and of L^-1 decide nothing: there the term z^(m-1) dominates.

    References
    ----------
    L. V. Ahlfors, Complex Analysis, 3rd ed., McGraw-Hill 1979, ch. 4 (the argument principle,
    Rouche's theorem).
    """
    m = L.shape[1]
    A = np.abs(L)
    d = [L[:, i, i] for i in range(m)]
    if m == 2:
        c = [L[:, 0, 0] * L[:, 1, 1] - L[:, 0, 1] * L[:, 1, 0], -(d[0] + d[1])]
        e = [A[:, 0, 0] * A[:, 1, 1] + A[:, 0, 1] * A[:, 1, 0], A[:, 0, 0] + A[:, 1, 1]]
    elif m == 3:
        def minor(i, j, k, q):   # l_ik l_jq - l_iq l_jk and the sum of the moduli
            return (L[:, i, k] * L[:, j, q] - L[:, i, q] * L[:, j, k],
                    A[:, i, k] * A[:, j, q] + A[:, i, q] * A[:, j, k])
        m12, a12 = minor(1, 2, 1, 2)
        m02, a02 = minor(0, 2, 0, 2)
        m01, a01 = minor(0, 1, 0, 1)
        n12, b12 = minor(1, 2, 0, 2)
        n11, b11 = minor(1, 2, 0, 1)
        det = L[:, 0, 0] * m12 - L[:, 0, 1] * n12 + L[:, 0, 2] * n11
        c = [-det, m01 + m02 + m12, -(d[0] + d[1] + d[2])]
        e = [A[:, 0, 0] * a12 + A[:, 0, 1] * b12 + A[:, 0, 2] * b11, a01 + a02 + a12,
             A[:, 0, 0] + A[:, 1, 1] + A[:, 2, 2]]
    else:
        raise ValueError(f"stack of 2 x 2 or 3 x 3 matrices expected; got {m} x {m}")
    size = np.stack([np.abs(ck) for ck in c] + [np.ones(L.shape[0])])          # (m + 1, f)
    error = _COEFFICIENT_ERROR * np.stack(e + [np.zeros(L.shape[0])])
    total = np.sum(size + error, axis=0)
    count = np.full(L.shape[0], -1)
    for k in range(m + 1):
        # |c_k| - its error > the others with theirs
        dominant = (size[k] - error[k]) > total - (size[k] + error[k])
        count[dominant] = m - k
    return count


def _event_delays(crossing: tuple[float, complex, int], delay: float) -> tuple[float, float]:
    """(first delay at which the crossing puts a root on the imaginary axis, its period 2 pi /
    omega_c) for a crossing found on a loop that already includes ``delay``: the events are at
    delay + (pi + arg lambda_c mod 2 pi) / omega_c + k 2 pi / omega_c, k an integer (those below
    delay at negative k)."""
    w, lam, _ = crossing
    return delay + ((math.pi + cmath.phase(lam)) % (2.0 * math.pi)) / w, 2.0 * math.pi / w


def _first_event(crossings, delay: float) -> float:
    """The smallest extra delay [s] at which a crossing puts a root on the imaginary axis
    (+inf without crossings)."""
    return min((_event_delays(c, delay)[0] - delay for c in crossings), default=math.inf)


def _roots_at_delay(n_unstable_0: int, crossings, delay: float) -> tuple[int, float]:
    """(closed-loop roots in the closed right half-plane at ``delay``, delay margin [s]) from
    those without delay and the crossings of the loop without delay: two roots per event below
    or at the delay, in the crossing's direction. The margin: the extra delay to the next event
    for a stable loop; for an unstable one, minus how far the delay is beyond the smallest delay
    of the current unstable run (0 if the loop is unstable without delay)."""
    events = []
    for c in crossings:
        first, period = _event_delays(c, 0.0)
        k = 0
        while first + k * period <= delay:
            events.append((first + k * period, c[2]))
            k += 1
    events.sort()
    count = n_unstable_0
    start = 0.0 if count > 0 else None
    for at, direction in events:
        before = count
        count = max(count + 2 * direction, 0)
        if before == 0 and count > 0:
            start = at
        elif count == 0:
            start = None
    if count > 0:
        return count, start - delay
    following = math.inf
    for c in crossings:
        first, period = _event_delays(c, 0.0)
        k = 0 if first > delay else math.floor((delay - first) / period) + 1
        following = min(following, first + k * period)
    return 0, following - delay


@dataclass(frozen=True)
class ModeSpillover:
    """What the loop did to one flexible mode of the truth plant (see :func:`spillover`).

    Attributes
    ----------
    frequency : float, rad/s
        |lambda| of the open-loop mode.
    open_loop_damping : float
        -Re(lambda) / |lambda|.
    closed_loop_frequency : float, rad/s
        |s| of the closed-loop pole nearest the mode.
    closed_loop_damping : float
        -Re(s) / |s| of that pole (negative: the loop destabilised the mode).
    """

    frequency: float
    open_loop_damping: float
    closed_loop_frequency: float
    closed_loop_damping: float

    @property
    def stable(self) -> bool:
        """True if the closed-loop pole has Re(s) < 0."""
        return self.closed_loop_damping > 0


@dataclass(frozen=True)
class SpilloverVerdict:
    """Is a controller (designed on one model) stable on a truth model, and by how much.

    Attributes
    ----------
    stable : bool
        True if the closed loop is asymptotically stable (every pole strictly in the open left
        half-plane, inside the unit circle for a digital loop).
    n_unstable_poles : int
        Closed-loop poles in the closed right half-plane (outside or on the unit circle).
    least_damping_ratio : float or None
        Damping ratio of the least-damped closed-loop pole (negative when unstable);
        None for a FrequencyResponseData truth plant (no poles available).
    least_damped_frequency : float or None, rad/s
        Natural frequency of that pole.
    margins : Margins or MultiLoopMargins
        Margins of the loop on the truth plant (:func:`margins`).
    method : str
        ``'eigenvalues'`` (StateSpace truth) or ``'nyquist'`` (FrequencyResponseData truth).
    modes : tuple of ModeSpillover
        Per flexible mode of a StateSpace truth plant (complex eigenvalues, by frequency): its
        open-loop damping and that of the nearest closed-loop pole (the spillover of the loop
        into each mode); empty for an FRD truth plant.
    """

    stable: bool
    n_unstable_poles: int
    least_damping_ratio: float | None
    least_damped_frequency: float | None
    margins: Margins
    method: str
    modes: tuple = ()

    def __str__(self) -> str:
        state = "STABLE" if self.stable else f"UNSTABLE ({self.n_unstable_poles} unstable poles)"
        lines = [f"spillover verdict: {state} ({self.method})"]
        if self.least_damping_ratio is not None:
            lines.append(f"  least-damped pole: zeta = {self.least_damping_ratio:.4g} at "
                         f"{self.least_damped_frequency:.6g} rad/s")
        m = self.margins
        lines.append(f"  gain margin {m.gain_margin:.4g} dB, phase margin {m.phase_margin:.4g} deg,"
                     f" modulus margin {m.modulus_margin:.4g}")
        return "\n".join(lines)


def _mode_spillover(plant, closed_poles: np.ndarray) -> tuple[ModeSpillover, ...]:
    """Each flexible mode of the plant and the closed-loop pole nearest it."""
    lam = continuous_poles(plant)
    w_max = max(np.abs(lam).max(initial=0.0), 1.0)
    flexible = np.sort_complex(lam[(lam.imag > 1e-6 * math.sqrt(w_max))])
    upper = closed_poles[closed_poles.imag >= 0]
    out = []
    if not upper.size:
        return ()
    for x in flexible:
        p = upper[int(np.argmin(np.abs(upper - x)))]
        out.append(ModeSpillover(float(abs(x)), float(-x.real / abs(x)), float(abs(p)),
                                 float(-p.real / abs(p)) if abs(p) else 0.0))
    return tuple(sorted(out, key=lambda m: m.frequency))


@warns_long_delay
@limits_blas_threads(total_states)
def spillover(truth_plant, controller, *, delay: float = 0.0,
              computation_delay: bool = False) -> SpilloverVerdict:
    """Stability verdict of a controller on a truth model (never raises for an unstable loop).

    Parameters
    ----------
    truth_plant : control.StateSpace or control.FrequencyResponseData
        The high-fidelity plant (e.g. hub + beam with many modes, or the exact distributed
        model as FRD).
    controller : control.StateSpace
        Controller designed on another model.

    Returns
    -------
    SpilloverVerdict
        For a StateSpace truth plant, from the closed-loop eigenvalues (a pole counts as
        unstable if Re(s) >= -1e-10 max(1, |s|): undamped, uncontrolled modes make the loop
        only marginally stable, reported as not stable). For an FRD truth plant, from the Nyquist
        criterion: the plant is assumed to have no poles in the open right half-plane and
        n0 poles at s = 0 (n0 from the low-frequency slope of |L|, 2 for a free-floating plant);
        the contour is indented to the right around s = 0, so
        Z = P - (2 Delta - n0 pi) / (2 pi), where Delta is the phase change of 1 + L(j omega) over
        the FRD grid and P the controller's open right-half-plane poles. This needs |L| > 10 at the
        lowest and < 0.1 at the highest grid frequency, and a continuous controller.

        With a delay (a result, never an error: a delay at or beyond the delay margin gives an
        unstable verdict): a digital loop's poles are those of the exact delayed sampled-data
        loop (:func:`close_loop` with the delay). A continuous loop has infinitely many roots;
        those in the closed right half-plane are counted exactly from the loop without delay
        (its eigenvalues, or the Nyquist count of an FRD) and the imaginary-axis crossings the
        delay causes (module docstring), ``method`` then ``'eigenvalues+delay'`` (no pole
        damping or mode list: the roots are not all computed) or ``'nyquist+delay'``. The
        margins include the delay; their ``delay_margin`` is the extra delay the loop
        tolerates, or for a loop the delay destabilised minus how far the delay lies beyond
        the smallest destabilising one (0 for a digital loop).
    delay : float, s
        Loop delay (see :func:`margins`).
    computation_delay : bool
        Add one sample of a digital controller to the delay.

    References
    ----------
    M. J. Balas, "Feedback control of flexible systems", IEEE Trans. Automatic Control 23(4),
    1978 (control and observation spillover); Skogestad & Postlethwaite, Multivariable Feedback
    Control, 2nd ed., sec. 4.9 (Nyquist criterion with poles on the imaginary axis).
    """
    check_plant(truth_plant, "truth_plant", allow_frd=True)
    check_controller(controller)
    tau = total_delay(controller, delay, computation_delay)
    mg = margins(truth_plant, controller, delay=tau)
    continuous_delay = tau > 0.0 and not is_digital(controller)
    if isinstance(truth_plant, control.StateSpace):
        loop = close_loop(truth_plant, controller, delay=0.0 if continuous_delay else tau)
        s = continuous_poles(loop)
        w = np.abs(s)
        unstable = s.real >= -1e-10 * np.maximum(1.0, w)
        if continuous_delay:
            n_unstable, margin = _roots_at_delay(int(unstable.sum()),
                                                 _delay_free_crossings(truth_plant, controller),
                                                 tau)
            return SpilloverVerdict(
                stable=n_unstable == 0, n_unstable_poles=n_unstable, least_damping_ratio=None,
                least_damped_frequency=None, margins=dataclasses.replace(mg, delay_margin=margin),
                method="eigenvalues+delay")
        if tau > 0.0 and unstable.any():
            mg = dataclasses.replace(mg, delay_margin=min(mg.delay_margin, 0.0))
        zeta = np.where(w > 0, -s.real / np.where(w > 0, w, 1.0), 0.0)  # a pole at 0: zeta 0
        i = int(np.argmin(zeta)) if s.size else None
        return SpilloverVerdict(
            stable=bool(not unstable.any()), n_unstable_poles=int(unstable.sum()),
            least_damping_ratio=None if i is None else float(zeta[i]),
            least_damped_frequency=None if i is None else float(w[i]),
            margins=mg, method="eigenvalues", modes=_mode_spillover(truth_plant, s))
    n_unstable = nyquist_count(truth_plant, controller)
    if continuous_delay:
        n_unstable, margin = _roots_at_delay(max(n_unstable, 0), _delay_free_crossings(
            truth_plant, controller), tau)
        return SpilloverVerdict(stable=n_unstable == 0, n_unstable_poles=n_unstable,
                                least_damping_ratio=None, least_damped_frequency=None,
                                margins=dataclasses.replace(mg, delay_margin=margin),
                                method="nyquist+delay")
    return SpilloverVerdict(stable=n_unstable == 0, n_unstable_poles=max(n_unstable, 0),
                            least_damping_ratio=None, least_damped_frequency=None,
                            margins=mg, method="nyquist")


def nyquist_count(truth_plant: control.FrequencyResponseData, controller, *,
                  response: tuple | None = None) -> int:
    """Closed-loop poles in the right half-plane of a controller on a frequency-response plant,
    by the Nyquist criterion: the count :func:`spillover` gives an FRD truth plant, without
    its margins.

    Parameters
    ----------
    truth_plant : control.FrequencyResponseData
        A planar plant with no poles in the open right half-plane and n0 poles at s = 0 (n0
        from the low-frequency slope of |L|, 2 for a free-floating plant), on a grid that
        resolves every mode the loop feels, with |L| > 10 at its lowest and < 0.1 at its
        highest frequency.
    controller : control.StateSpace
        Continuous controller.
    response : (ndarray, ndarray), optional
        ``loop_frequency_response(truth_plant, controller)``, if already computed.

    Returns
    -------
    int
        Z = P - (2 Delta - n0 pi) / (2 pi) (the contour indented to the right around s = 0):
        Delta the phase change of 1 + L(j omega) over the grid, P the controller's open
        right-half-plane poles; 0 for a stable loop. May be negative for a grid that does not
        resolve the loop (then the count is not to be trusted).

    Raises
    ------
    ValueError
        A digital controller, or a grid too narrow for the criterion (named with |L| at its
        ends).

    References
    ----------
    Skogestad & Postlethwaite, Multivariable Feedback Control, 2nd ed., sec. 4.9 (Nyquist
    criterion with poles on the imaginary axis).
    """
    check_plant(truth_plant, "truth_plant", allow_frd=True)
    check_controller(controller)
    if not isinstance(truth_plant, control.FrequencyResponseData):
        raise TypeError(f"truth_plant must be a control.FrequencyResponseData; got "
                        f"{type(truth_plant).__name__}")
    if is_digital(controller):
        raise ValueError("spillover on a FrequencyResponseData truth_plant needs a continuous "
                         "controller (the sampled-data Nyquist count would need the aliased "
                         f"plant response); got dt={controller.dt}: use a StateSpace truth_plant")
    if response is None:
        omega, L = loop_frequency_response(truth_plant, controller)
    else:
        omega, L = _loop_response(response)
    return _nyquist_count(omega, L[:, None, None], unstable_poles(controller), "truth_plant ")


def unstable_poles(system) -> int:
    """Poles of a system in the open right half-plane (a digital one's mapped from the z-plane,
    :func:`~controllers.stability.continuous_poles`): Re(s) > 1e-10 max(1, |s|) [rad/s], the P
    of the Nyquist criterion for a controller (a pole on the imaginary axis, an integrator,
    counts as stable: the contour is indented to its right)."""
    lam = continuous_poles(system)
    return int(np.sum(lam.real > 1e-10 * np.maximum(1.0, np.abs(lam))))


def loop_nyquist_count(omega: np.ndarray, L: np.ndarray, *, open_loop_unstable: int = 0) -> int:
    """Closed-loop poles in the right half-plane of a loop known by its frequency response, by
    the (multivariable) Nyquist criterion on det(I + L(j omega)).

    With the Nyquist contour indented to the right around s = 0 (and around nothing else: the
    loop has no other pole on the imaginary axis), the clockwise encirclements of the origin by
    det(I + L) are N = Z - P, P the open loop's poles in the open right half-plane and Z the
    closed loop's. Along the contour det(I + L) turns by 2 Delta on the imaginary axis (Delta
    from 0+ to +inf, the other half its mirror image), by -n0 pi around the n0-fold pole of det
    L at s = 0 and by nothing on the large arc (L strictly proper), so

        Z = P - (2 Delta - n0 pi) / (2 pi).

    Delta is the unwrapped phase change of det(I + L) over the grid, n0 the low-frequency
    slope of log|det L| against log omega (2 per free-floating axis), which needs the grid to
    start where every singular value of L exceeds 10 (det(I + L) turns there as det L, whose
    phase has reached its asymptote) and to end where every one is below 0.1 (det(I + L) near
    1). For a planar loop (m = 1) this is :func:`nyquist_count`'s count.

    Parameters
    ----------
    omega : ndarray, rad/s
        Increasing grid that resolves the phase of det(I + L) (every lightly damped mode of
        plant and controller).
    L : ndarray, complex
        L(j omega): shape (f,) for a planar loop, (f, m, m) for m loops, negative-feedback
        convention.
    open_loop_unstable : int
        P: the open loop's poles in the open right half-plane (a controller's,
        :func:`unstable_poles`; a free-floating spacecraft has none).

    Returns
    -------
    int
        Z (0 for a stable loop). May be negative for a grid that does not resolve the loop
        (then the count is not to be trusted, and a verdict says unstable).

    Raises
    ------
    ValueError
        A grid too narrow for the criterion (named with the singular values of L at its
        ends), a bad grid or L of the wrong shape.

    References
    ----------
    Skogestad & Postlethwaite, Multivariable Feedback Control, 2nd ed., sec. 4.9.3 (the
    generalised Nyquist theorem, det(I + L)); C. A. Desoer, Y.-T. Wang, "On the generalized
    Nyquist stability criterion", IEEE Trans. Automatic Control 25(2), 1980.
    """
    omega = frequency_grid(omega, minimum=2)
    if np.any(np.diff(omega) <= 0):
        raise ValueError(f"omega must be increasing [rad/s]; got {describe(omega)}")
    L = _loop_matrix_values(L, omega.size)
    if isinstance(open_loop_unstable, (bool, np.bool_)) or not isinstance(
            open_loop_unstable, (int, np.integer)) or open_loop_unstable < 0:
        raise ValueError(f"open_loop_unstable must be a non-negative integer (poles in the "
                         f"open right half-plane); got {describe(open_loop_unstable)}")
    return _nyquist_count(omega, L, int(open_loop_unstable), "")


def _nyquist_count(omega: np.ndarray, L: np.ndarray, p_rhp: int, what: str) -> int:
    """Z of :func:`loop_nyquist_count` for L (f, m, m) on an increasing grid; ``what`` starts
    the message of a grid too narrow."""
    m = L.shape[1]
    with np.errstate(all="ignore"):
        ends = np.linalg.svd(L[[0, -1]], compute_uv=False) if m > 1 else np.abs(L[[0, -1], 0])
    low, high = float(np.min(ends[0])), float(np.max(ends[1]))
    if not (low >= 10 and high <= 0.1):
        name = "|L|" if m == 1 else "every singular value of L"
        raise ValueError(
            f"{what}frequency grid too narrow for the Nyquist criterion: need {name} > 10 at the "
            f"lowest and < 0.1 at the highest frequency; got {low:.3g} at {omega[0]:.3g} rad/s "
            f"and {high:.3g} at {omega[-1]:.3g} rad/s")
    with np.errstate(all="ignore"):
        if m == 1:
            det_L, det_R = L[:2, 0, 0], 1.0 + L[:, 0, 0]
        else:
            det_L, det_R = np.linalg.det(L[:2]), np.linalg.det(np.eye(m) + L)
    slope = ((math.log(abs(det_L[1])) - math.log(abs(det_L[0])))
             / (math.log(omega[1]) - math.log(omega[0])))
    n0 = int(round(-slope))
    phase = np.unwrap(np.angle(det_R))
    delta = phase[-1] - phase[0]
    z = p_rhp - (2.0 * delta - n0 * math.pi) / (2.0 * math.pi)
    return int(round(z))


@warns_long_delay
def loop_verdict(loop: Callable[[np.ndarray], np.ndarray], omega: np.ndarray,
                 L: np.ndarray | None = None, *, open_loop_unstable: int = 0,
                 delay: float = 0.0, axes: Sequence[str] | None = None) -> SpilloverVerdict:
    """Stability and margins of a loop known as a function L(j omega), planar or m x m.

    What :func:`spillover` gives a state-space truth plant, for a loop whose plant is known
    only by its frequency response but exactly, wherever asked (the exact distributed
    spacecraft through W or W6):

    - stability by the Nyquist criterion on det(I + L) over ``omega``
      (:func:`loop_nyquist_count`, the open loop's ``open_loop_unstable`` poles counted);
    - margins found on ``loop`` itself: :func:`loop_margins` (planar) or
      :func:`multiloop_margins` (loop-at-a-time, disk margin, smallest singular value of
      I + L), the definitions of :func:`margins`;
    - with a delay tau (the same on every input): the roots in the closed right half-plane
      are those without delay plus two per imaginary-axis crossing the delay causes below tau
      (module docstring: the unit-circle crossings of the eigenvalues of L, found on ``loop``
      and refined to 1e-13), as :func:`spillover` counts them; the margins include the delay
      and their ``delay_margin`` is the extra delay tolerated, or for a loop the delay
      destabilised minus how far tau lies beyond the smallest destabilising delay.

    Parameters
    ----------
    loop : callable
        ``loop(omega)`` -> L(j omega) at the 1-D frequencies omega [rad/s]: shape (f,) for a
        planar loop, (f, m, m) for m loops (the loop broken at the plant's inputs,
        negative-feedback convention), without the delay.
    omega : ndarray, rad/s
        Increasing grid that resolves det(I + L) (every lightly damped mode of plant and
        controller) from where every singular value of L exceeds 10 to where each is below
        0.1; it brackets the margins, which are then found on ``loop``.
    L : ndarray, optional
        ``loop(omega)``, if already known.
    open_loop_unstable : int
        The open loop's poles in the open right half-plane (:func:`unstable_poles` of the
        controller when the plant has none).
    delay : float, s
        Loop delay.
    axes : sequence of str, optional
        Names of the m inputs (:func:`multiloop_margins`).

    Returns
    -------
    SpilloverVerdict
        ``method`` ``'nyquist'`` (``'nyquist+delay'`` with a delay); no poles or mode list (a
        frequency response has none); ``margins`` :class:`Margins` or
        :class:`MultiLoopMargins`.

    Raises
    ------
    ValueError
        A grid too narrow for the Nyquist criterion, or a bad argument.
    """
    omega, delay, L, values = _loop_arguments(loop, omega, L, delay, "")
    planar = np.ndim(L) == 1
    n = loop_nyquist_count(omega, values, open_loop_unstable=open_loop_unstable)

    def matrix(w: np.ndarray) -> np.ndarray:
        out = np.asarray(loop(np.asarray(w, dtype=float).reshape(-1)))
        return out[:, None, None] if planar else out

    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        margins_ = (loop_margins(loop, omega, np.asarray(L).astype(complex), delay=delay)
                    if planar else multiloop_margins(loop, omega, values, delay=delay,
                                                     axes=axes))
    if delay == 0.0:
        return SpilloverVerdict(stable=n == 0, n_unstable_poles=max(n, 0),
                                least_damping_ratio=None, least_damped_frequency=None,
                                margins=margins_, method="nyquist")
    n_delayed, margin = _roots_at_delay(max(n, 0), _unit_crossings(matrix, omega, values), delay)
    return SpilloverVerdict(stable=n_delayed == 0 and n >= 0, n_unstable_poles=n_delayed,
                            least_damping_ratio=None, least_damped_frequency=None,
                            margins=dataclasses.replace(margins_, delay_margin=margin),
                            method="nyquist+delay")


def _loop_response(response) -> tuple[np.ndarray, np.ndarray]:
    """``(omega, L)`` of :func:`loop_frequency_response`, checked: increasing positive finite
    frequencies [rad/s] and as many complex values, at least two."""
    expected = ("response must be (omega, L) of loop_frequency_response: increasing positive "
                "frequencies [rad/s] and the loop's values there, at least two")
    if not isinstance(response, (tuple, list)) or len(response) != 2:
        raise TypeError(f"{expected}; got {describe(response)}")
    try:
        omega = np.asarray(response[0], dtype=float).reshape(-1)
        L = np.asarray(response[1], dtype=complex).reshape(-1)
    except (TypeError, ValueError):
        raise TypeError(f"{expected}; got {describe(response)}") from None
    if (omega.size < 2 or L.size != omega.size or not np.all(np.isfinite(omega))
            or np.any(omega <= 0) or np.any(np.diff(omega) <= 0)):
        raise ValueError(f"{expected}; got {omega.size} frequencies and {L.size} values "
                         f"{describe(response)}")
    return omega, L


def _delay_free_crossings(plant, controller) -> list[tuple[float, complex, int]]:
    """The unit-circle crossings of the loop's eigenvalues without delay (see
    :func:`_unit_crossings`), on the loop's default grid. ValueError if |L| does not fall
    below 1 at the grid's top: the delayed loop would then be of neutral type, whose roots the
    crossings do not account for."""
    loop = LoopTransfer(plant, controller)
    omega = loop.grid()
    with np.errstate(all="ignore"):
        top = _gain(loop.matrix(omega[-1:]))[0]
    if not top < 1.0:
        raise ValueError(f"delay: the loop gain |L| = {top:.3g} at {omega[-1]:.4g} rad/s does not "
                         "fall below 1 at high frequency (a controller and plant feedthrough); "
                         "with a delay such a loop is of neutral type and its stability is not "
                         "decided here")
    return _unit_crossings(loop.matrix, omega)
