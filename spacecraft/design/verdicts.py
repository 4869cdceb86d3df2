"""Verdicts on a closed loop that cannot be misread, and the design warnings of a run.

Status of a loop's response (:func:`loop_status`), from its closed-loop poles and its
simulation:

- ``"diverges"``: the response left the float64 range (it stops there);
- ``"unstable"``: a closed-loop pole has Re(s) > 0 (the response grows as exp(sigma t),
  sigma the largest real part, even if the simulated time shows little of it);
- ``"slew unfinished"``: the simulated time ends before the slew does (manoeuvre.duration <
  slew_time): overshoot and settling time are not defined;
- ``"not settled"``: stable, but still outside the 2 % band at the end of the simulated time;
- ``"settles"``.

For the first two, every time metric of the response is withheld (None, with the flag
``"diverges"``): the numbers of a growing response's first seconds read as those of a loop that
settles. A pole with |Re(s)| <= 1e-10 max(1, |s|) (an undamped mode the loop does not reach,
e.g. a symmetric mode of symmetric wings when pruning is off) is marginal: it neither grows nor
decays, and the status says so without withholding the metrics.

Warnings (:func:`design_warnings`, :func:`loop_warnings`): every one has a ``code``, the loop
it concerns and a message that says what to change. Thresholds (classical robustness targets,
Skogestad & Postlethwaite [1]_ sec. 2.4.3: "typically we require GM > 2 and PM > 30 deg", and a
peak sensitivity below 2, i.e. a modulus margin above 0.5):

==============================  ===========  ==================================================
check (code)                    threshold    on
==============================  ===========  ==================================================
gain margin (margins)           6 dB         GM < 6 dB on the truth model, signed: a negative
                                             GM (a conditionally stable loop, destabilised by a
                                             gain reduction, e.g. actuator saturation) is below
phase margin (margins)          30 deg       PM < 30 deg on the truth model, signed
modulus margin (margins)        0.5          min |1 + L| on the truth model
three axes (margins)            the same     each axis' loop-at-a-time margins; the disk
                                             margin's gain (6 dB, alpha = 2/3) and phase
                                             (30 deg); min sigma(I + L) (0.5)
unstable on the truth model     -            closed-loop poles with Re(s) > 0; its classical
(unstable)                                   "margins" are then no margins (the loop needs no
                                             perturbation to diverge): flagged, never shown as
                                             guarantees
damping lowered                 0.1 %        a flexible mode of the truth plant whose nearest
(damping_lowered)                            closed-loop pole has a damping ratio below
                                             (1 - 1e-3) x the mode's open-loop one: the loop
                                             takes damping from the structure (spillover)
lightly damped closed loop      zeta 1e-3    a closed-loop pole of a stable loop with damping
(light_damping)                              ratio below 1e-3: it rings for more than
                                             1/(2 pi zeta) = 160 cycles (the lower end of the
                                             structural damping, 0.1-0.5 %, that deployed
                                             appendages are credited with); a marginal
                                             (undamped) pole is below it
unstable on the exact beam      -            Nyquist count on W(s) of the distributed beam
manoeuvre ends before the slew  -            manoeuvre.duration < slew_time
not settled                     2 % band     still outside at the end of the simulated time
truth model misses modes        1 %          a coupled mode below bandwidth_factor x the loop's
                                             crossover that the truth model does not resolve
truth model not converged       tolerance    the closed-loop rule of :mod:`spacecraft.design.fidelity`
                                             stopped at its largest number of modes
==============================  ===========  ==================================================

:func:`margin_flags` marks each margin a report shows: ``"unstable"`` for every margin of an
unstable loop, ``"low"`` for a margin below its threshold; the report colours them and
results.json carries the flags beside the numbers.

References
----------
.. [1] S. Skogestad, I. Postlethwaite, Multivariable Feedback Control, 2nd ed., Wiley 2005,
   sec. 2.4.3 (gain, phase and modulus margins; typical requirements).
.. [2] Craig & Bampton, AIAA J. 6(7), 1968: a truncation to n fixed-interface modes represents
   the appendage up to about its n-th clamped (cantilever) frequency.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Mapping

import numpy as np

from controllers.stability import continuous_poles

__all__ = ["MIN_GAIN_MARGIN", "MIN_PHASE_MARGIN", "MIN_MODULUS_MARGIN", "MIN_DISK_MARGIN",
           "MIN_DAMPING", "DAMPING_DROP", "CAUTIONS", "MODE_ERROR", "MARGINAL", "STATUS_TEXT",
           "closed_loop_poles", "loop_status", "withheld_metrics", "design_warnings",
           "loop_warnings", "margin_flags", "verdict_dict", "margins_dict",
           "crossover_frequencies", "growing",
           "resolved_frequency", "TIME_METRICS", "exact_loop_verdict", "s_plane_poles"]

#: Smallest acceptable |gain margin| on the truth model [dB] (a factor of 2).
MIN_GAIN_MARGIN = 6.0
#: Smallest acceptable phase margin on the truth model [deg].
MIN_PHASE_MARGIN = 30.0
#: Smallest acceptable modulus margin min |1 + L| on the truth model [-] (peak |S| <= 2).
MIN_MODULUS_MARGIN = 0.5
#: Smallest acceptable balanced disk margin alpha of a three-axis loop (it guarantees the
#: 6 dB of MIN_GAIN_MARGIN in every channel at once: (1 + alpha/2)/(1 - alpha/2) = 2).
MIN_DISK_MARGIN = 2.0 / 3.0
#: Closed-loop damping ratio below which a pole of a stable loop is warned about [-].
MIN_DAMPING = 1e-3
#: Relative fall of a flexible mode's damping ratio, closed loop against open loop, above which
#: the loop is said to lower it (far above the eigenvalues' rounding, ~1e-10 here).
DAMPING_DROP = 1e-3
#: Warning codes that qualify a loop that does not diverge (the report and plots mark it).
CAUTIONS = {"margins": "low margins", "damping_lowered": "lowers a mode's damping",
            "light_damping": "lightly damped", "unstable_exact": "UNSTABLE on the exact beam"}
#: Relative frequency error above which a coupled mode counts as missed by the truth model.
MODE_ERROR = 0.01
#: |Re(s)| <= MARGINAL max(1, |s|) [1/s]: a pole on the imaginary axis (neither grows nor
#: decays; the eigenvalues of the loops are computed to ~1e-13 relative, see
#: controllers.stability).
MARGINAL = 1e-10

#: The time-domain metrics of a response (withheld for a diverging loop).
TIME_METRICS = ("overshoot", "settling_time", "peak_torque", "peak_tip_deflection",
                "peak_attitude_error", "final_attitude_error")

#: What each status means, for the report.
STATUS_TEXT = {
    "settles": "settles",
    "not settled": "does not settle within the simulated time",
    "slew unfinished": "the simulated time ends before the slew",
    "unstable": "UNSTABLE: diverges",
    "diverges": "UNSTABLE: diverges",
}


def s_plane_poles(poles, sample_time: float | None = None) -> np.ndarray:
    """Poles [1/s] in the s-plane: as given for a continuous system; a digital system's
    z-plane poles (``sample_time`` T [s]) mapped by s = log(z) / T, the poles at z = 0
    (deadbeat: no s-plane image) left out."""
    lam = np.asarray(poles, dtype=complex).reshape(-1)
    if sample_time is None:
        return lam
    lam = lam[np.abs(lam) > 1e-300]
    return np.log(lam) / float(sample_time)


def closed_loop_poles(loop) -> np.ndarray:
    """Poles of a closed loop in the s-plane [1/s], a digital loop's mapped from the z-plane
    (:func:`controllers.stability.continuous_poles`)."""
    return continuous_poles(loop)


def loop_status(poles: np.ndarray, response, manoeuvre, metrics: dict | None) -> dict:
    """Status of a loop's slew response (see the module docstring).

    Parameters
    ----------
    poles : ndarray, complex, 1/s
        Closed-loop poles (:func:`closed_loop_poles`).
    response : control.TimeResponseData or None
        The slew response (attributes ``diverged``, ``diverged_at``), None without a manoeuvre.
    manoeuvre : ManoeuvreSpec or None
    metrics : dict or None
        :func:`controllers.metrics` of the response.

    Returns
    -------
    dict
        ``status`` (a key of :data:`STATUS_TEXT`), ``text``, ``growth_rate`` [1/s] (largest
        Re(s) of a growing pole, else None), ``doubling_time`` [s] (ln 2 / growth_rate),
        ``diverged_at`` [s] or None, ``marginal_frequencies`` [rad/s] (undamped modes).
    """
    s = np.asarray(poles, dtype=complex)
    size = np.maximum(1.0, np.abs(s))
    growing = s.real > MARGINAL * size
    marginal = np.abs(s.real) <= MARGINAL * size
    growth = float(np.max(s.real[growing])) if growing.any() else None
    out = {"growth_rate": growth,
           "doubling_time": math.log(2.0) / growth if growth else None,
           "diverged_at": None,
           "marginal_frequencies": sorted({round(float(w), 12) for w in
                                           np.abs(s[marginal & (s.imag >= 0)])})}
    at = None if response is None else getattr(response, "diverged_at", None)
    if response is not None and getattr(response, "diverged", False):
        out.update(status="diverges", diverged_at=at)
        out["text"] = (f"UNSTABLE: diverges, simulation stopped at t = {at:.6g} s (the "
                       "response left the floating-point range)" if at is not None
                       else "UNSTABLE: diverges")
    elif growth is not None:
        at_w = sorted({float(f"{abs(z):.3g}") for z in s[growing & (s.imag >= 0)]})
        out["status"] = "unstable"
        out["growing_frequencies"] = at_w
        out["text"] = (f"UNSTABLE: diverges (growing mode{'s' if len(at_w) != 1 else ''} at "
                       + ", ".join(f"{w:.3g}" for w in at_w[:4]) + f" rad/s, sigma = "
                       f"{growth:.3g} 1/s: the amplitude doubles every "
                       f"{out['doubling_time']:.3g} s)")
    elif manoeuvre is not None and manoeuvre.duration < manoeuvre.slew_time:
        out["status"] = "slew unfinished"
        out["text"] = (f"the simulated time {manoeuvre.duration:g} s ends before the slew "
                       f"({manoeuvre.slew_time:g} s): no overshoot or settling time")
    elif metrics is not None and "settling_time" in metrics and metrics["settling_time"] is None:
        out["status"] = "not settled"
        out["text"] = (f"does not settle within the simulated time ({manoeuvre.duration:g} s): "
                       "lengthen manoeuvre.duration")
    else:
        out["status"] = "settles"
        out["text"] = "settles"
    if out["marginal_frequencies"] and out["status"] in ("settles", "not settled"):
        out["text"] += (" (marginally stable: undamped modes the loop does not reach at "
                        + ", ".join(f"{w:.4g}" for w in out["marginal_frequencies"][:4])
                        + " rad/s)")
    return out


def _time_metric(name: str, kinds) -> bool:
    """``name`` is one of ``kinds``, or one of them per hub axis (``peak_torque_x``), or a
    peak of an appendage's tip motion (``peak_boom_tip_twist``: three-axis runs name them so)."""
    base = name[:-2] if name[-2:] in ("_x", "_y", "_z") else name
    return name in kinds or base in kinds or (
        "peak_tip_deflection" in kinds and name.startswith("peak_")
        and ("_tip_deflection" in name or name.endswith("_tip_twist")))


def withheld_metrics(metrics: dict, status: dict) -> tuple[dict, dict]:
    """The metrics to report under a status, and the flags of those withheld.

    Returns
    -------
    values : dict
        ``metrics`` with None for every metric the status makes meaningless.
    flags : dict
        name -> ``"diverges"``, ``"slew unfinished"`` or ``"not settled"`` for each None.
    """
    values, flags = dict(metrics), {}
    kind = status["status"]
    if kind in ("diverges", "unstable"):
        for name in values:
            if _time_metric(name, TIME_METRICS):
                values[name] = None
                flags[name] = "diverges"
    elif kind == "slew unfinished":
        for name in values:
            if _time_metric(name, ("overshoot", "settling_time")):
                values[name] = None
                flags[name] = "slew unfinished"
    elif kind == "not settled" and "settling_time" in values:
        values["settling_time"] = None
        flags["settling_time"] = "not settled"
    values.pop("diverged_at", None)
    values["diverged"] = kind in ("diverges", "unstable")
    return values, flags


def exact_loop_verdict(spacecraft, controller, omega, *, theta=None, delay: float = 0.0,
                       locating=None):
    """The verdict and margins of a loop closed on the exact distributed spacecraft, planar or
    three-axis.

    The loop is broken at the torque inputs, L(j w) = -(K_theta(j w) + j w K_omega(j w))
    P(j w) (negative-feedback convention), P = theta/torque the exact attitude response
    through each appendage's W(s) (W6 in three axes, :mod:`spacecraft.dynamics.exact`): a
    number planar, the 3 x 3 matrix in three axes, where K_theta and K_omega are the
    controller's 3 x 3 transfers from the measured attitudes and rates to the torques.
    :func:`controllers.margins.loop_verdict` then judges it on the exact function itself:

    - stability by the Nyquist criterion on det(I + L) over ``omega`` with the controller's
      lightly damped roots added (:func:`controllers.loop.resonance_points`; P exact there
      too), the controller's own poles in the right half-plane counted
      (:func:`controllers.margins.loop_nyquist_count`). Three axes: also the lightly damped
      roots that the loop-at-a-time functions have and L has not (the poles of the loop with
      one axis open, which are no open-loop modes) and the zeros of each axis' loop, taken
      from the loop on the finite ``locating`` spacecraft, which has the exact one's modes
      below the grid's top to a small fraction of their half-power bands: the grid of
      :func:`controllers.margins` on a state-space plant resolves the same roots;
    - the margins found on L, evaluated through W (W6) wherever asked: the grid only brackets
      the crossings of |L| = 1 and of the negative real axis (three axes: of each
      loop-at-a-time L_i = 1/S_ii - 1) and the extrema of |1 + L| and of the singular values,
      which are then found on L to 1e-13 in frequency, so the margins are as accurate as the
      exact response (about 1e-13 relative), not as a grid interpolation. Three axes: the
      definitions of :func:`controllers.margins` (loop-at-a-time, balanced disk margin,
      smallest singular value of I + L), so they equal a state-space model's.

    Parameters
    ----------
    spacecraft : spacecraft.Spacecraft
        Hub with its distributed appendages (its ``exact`` reference is evaluated).
    controller : control.StateSpace
        Continuous controller with output ``torque`` and inputs ``theta`` and/or ``omega``
        (three axes: outputs ``torque_x/_y/_z``, inputs ``theta_x``... and/or ``omega_x``...;
        others, such as references, are not fed back).
    omega : array of float, rad/s
        Grid that resolves every coupled mode the loop feels (the Nyquist count is taken on
        it), e.g. :meth:`spacecraft.design.models.ModelBuilder.exact_grid`; with the
        controller's lightly damped roots it also brackets the margins.
    theta : array of complex, optional
        The exact theta/torque on ``omega``, if already known: shape (f,) planar [rad/(N m)],
        (f, 3, 3) in three axes (row: attitude axis, column: torque axis).
    delay : float, s
        A loop delay (computation plus transport), the same on every torque, in the count and
        the margins as :func:`controllers.spillover` takes it.
    locating : spacecraft.Spacecraft, optional
        Three axes: the finite spacecraft whose loop locates the exact loop's resonances
        (:func:`spacecraft.design.exact_grid.locating_spacecraft` up to the grid's top, built here
        if not given). Unused for a planar loop, whose L has only the plant's and the
        controller's poles and zeros.

    Returns
    -------
    controllers.SpilloverVerdict
        ``method`` ``'nyquist'`` (``'nyquist+delay'``); ``margins`` refined on the exact loop
        function: :class:`controllers.Margins` planar, :class:`controllers.MultiLoopMargins`
        in three axes.

    Raises
    ------
    ValueError
        A digital controller, or a grid too narrow for the Nyquist criterion.
    """
    from controllers.loop import LoopTransfer, resonance_points
    from controllers.margins import loop_verdict
    from controllers.signals import channels

    ch = channels(controller, "controller")
    if ch.mimo != bool(spacecraft.three_axis):
        raise ValueError(f"controller: a {'three-axis' if ch.mimo else 'planar'} controller "
                         f"(outputs {list(controller.output_labels)}) on a "
                         f"{'three-axis' if spacecraft.three_axis else 'planar'} spacecraft")
    m = ch.n_axes
    omega = np.asarray(omega, dtype=float).reshape(-1)
    order = np.argsort(omega)
    omega = omega[order]
    if theta is None:
        P = _exact_compliance(spacecraft, omega)
    else:
        P = np.asarray(theta)
        shapes = [(omega.size, m, m)] + ([(omega.size,)] if m == 1 else [])
        if P.shape not in shapes or P.dtype.kind not in "fc":
            raise ValueError(f"theta must be the exact attitude response on the {omega.size} "
                             f"frequencies of omega [rad/(N m)], shape "
                             f"{' or '.join(str(x) for x in shapes)}; got {P.dtype} of shape "
                             f"{P.shape}")
        P = P.astype(complex).reshape((-1, m, m))[order]
    gains, controller_root_list, open_loop_unstable = _controller_facts(controller, ch)
    # the exact grid and the controller's lightly damped roots inside it (P evaluated at the
    # points added: a controller's root may sit on a lightly damped mode, between whose grid
    # points an interpolated plant is no bracket); it counts the encirclements and brackets the
    # margins, which are then found on the exact loop function
    roots = [controller_root_list]
    if ch.mimo:
        if locating is None:
            from .exact_grid import locating_spacecraft

            locating = locating_spacecraft(spacecraft, float(omega[-1]))
        located = LoopTransfer(locating.plant(prune=True), controller)
        roots += [located.loop_at_a_time_poles()] + [located.zeros(i) for i in range(m)]
    extra = resonance_points(np.concatenate(roots), omega[0], omega[-1])
    grid = np.unique(np.concatenate([omega, extra]))
    added = ~np.isin(grid, omega)
    P_grid = np.empty((grid.size, m, m), dtype=complex)
    P_grid[~added] = P[np.searchsorted(omega, grid[~added])]
    if added.any():
        P_grid[added] = _exact_compliance(spacecraft, grid[added])

    def loop_of(w: np.ndarray, P: np.ndarray) -> np.ndarray:
        K = gains(w)
        L = -(K[:, :, :m] + 1j * w[:, None, None] * K[:, :, m:]) @ P
        return L[:, 0, 0] if m == 1 else L

    def loop(w: np.ndarray) -> np.ndarray:
        w = np.asarray(w, dtype=float).reshape(-1)
        return loop_of(w, _exact_compliance(spacecraft, w))

    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        L = loop_of(grid, P_grid)
    return loop_verdict(loop, grid, L, open_loop_unstable=open_loop_unstable,
                        delay=delay, axes=ch.axes if ch.mimo else None)


def _exact_compliance(spacecraft, omega: np.ndarray) -> np.ndarray:
    """Exact theta/torque at j omega, shape (f, m, m) [rad/(N m)]; inf where an undamped
    spacecraft has a natural frequency (a refinement step may land there; the margin search
    steps aside)."""
    try:
        return spacecraft.exact.attitude_compliance(omega)
    except ValueError:
        m = 3 if spacecraft.three_axis else 1
        out = np.full(omega.shape + (m, m), np.inf, dtype=complex)
        for k in range(omega.size):
            try:
                out[k] = spacecraft.exact.attitude_compliance(omega[k:k + 1])[0]
            except ValueError:
                pass
        return out


def _controller_facts(controller, ch):
    """What the exact-beam verdict needs of a controller alone: ``(gains, roots, unstable)``,
    its measurement gains (:func:`_measurement_gains`), its poles and channel zeros
    (:func:`controllers.loop.controller_roots`) and its poles in the right half-plane
    (:func:`controllers.margins.unstable_poles`).

    Kept while the controller lives and given again for the same matrices and signal names
    (compared entry by entry, so a controller changed in place is worked out anew): a
    controller judged on many spacecraft (a sweep's nominal controller, one per sample) is
    worked out once.
    """
    from controllers.loop import controller_roots
    from controllers.margins import unstable_poles

    inputs, outputs = tuple(controller.input_labels), tuple(controller.output_labels)
    matrices = tuple(np.asarray(x) for x in (controller.A, controller.B, controller.C,
                                            controller.D))
    key = (inputs, outputs, controller.dt)
    try:
        known = _CONTROLLER_FACTS.get(controller)
    except TypeError:  # a controller that cannot be weakly referenced: not kept
        known = None
    if known is not None and known[0] == key and all(
            a.shape == b.shape and a.dtype == b.dtype and np.array_equal(a, b)
            for a, b in zip(known[1], matrices)):
        return known[2]
    measured = [n for n in ch.measurements if n in inputs]
    roots = np.array(controller_roots(controller, measured, ch.torques))
    roots.setflags(write=False)
    facts = (_measurement_gains(controller, ch), roots, unstable_poles(controller))
    try:
        _CONTROLLER_FACTS[controller] = (key, tuple(m.copy() for m in matrices), facts)
    except TypeError:
        pass
    return facts


# a controller's facts for the exact-beam verdict, while the controller lives
# (_controller_facts)
_CONTROLLER_FACTS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _measurement_gains(controller, ch):
    """``gains(omega)`` -> K(j omega), shape (f, m, 2m): the controller's transfers from the
    measured attitudes, then rates (the channels ``ch``), to its m torques (zero for a signal
    it does not take), C (j omega I - A)^-1 B + D: in modal form where A's eigenvectors are
    well conditioned (condition number below 1e6: the modal sum then loses at most 1e-10
    relative), else by one linear solve per frequency (controllers have a few states)."""
    if controller.isdtime(strict=True):
        raise ValueError("the exact-beam verdict needs a continuous controller; got "
                         f"dt={controller.dt}")
    inputs, outputs = list(controller.input_labels), list(controller.output_labels)
    rows = [outputs.index(name) for name in ch.torques]
    A = np.asarray(controller.A, dtype=float)
    C = np.asarray(controller.C, dtype=float)[rows]
    columns = []
    for name in ch.thetas + ch.omegas:
        j = inputs.index(name) if name in inputs else None
        columns.append((np.zeros(A.shape[0]), np.zeros(len(rows))) if j is None else
                       (np.asarray(controller.B, dtype=float)[:, j],
                        np.asarray(controller.D, dtype=float)[rows, j]))
    B = np.stack([b for b, _ in columns], axis=1)
    D = np.stack([d for _, d in columns], axis=1)
    modal = None
    if A.shape[0]:
        # modal form when the eigenvectors are well conditioned: (C V) diag(1/(s - lambda))
        # (V^-1 B) = sum_n R_n/(s - lambda_n), the residue of pole n the outer product
        # R_n = (C V)_n (V^-1 B)_n of its column and row, worked out once: one matrix product
        # (f, n) @ (n, m*2m) per call instead of a solve per frequency (the margins' search
        # evaluates the loop at one or a few frequencies at a time, the verdict on thousands)
        lam, V = np.linalg.eig(A)
        if np.linalg.cond(V) < 1e6:
            residues = np.einsum("in,nk->nik", C @ V, np.linalg.solve(V, B.astype(complex)))
            modal = lam, residues.reshape(lam.size, -1)

    def gains(omega: np.ndarray) -> np.ndarray:
        if A.shape[0] == 0:
            return np.broadcast_to(D.astype(complex), (omega.size,) + D.shape)
        if modal is not None:
            lam, residues = modal
            return ((1.0 / (1j * omega[:, None] - lam)) @ residues).reshape(
                (omega.size,) + D.shape) + D
        M = 1j * omega[:, None, None] * np.eye(A.shape[0]) - A
        X = np.linalg.solve(M, np.broadcast_to(B, (omega.size,) + B.shape))
        return np.einsum("in,fnk->fik", C, X) + D
    return gains


#: Threshold of each margin a report shows, by name (a three-axis loop's per-axis margins
#: ``gain_margin_x``... by their stem): value < threshold is low.
_THRESHOLDS = {"gain_margin": MIN_GAIN_MARGIN, "phase_margin": MIN_PHASE_MARGIN,
               "modulus_margin": MIN_MODULUS_MARGIN, "disk_margin": MIN_DISK_MARGIN,
               "disk_gain_margin": MIN_GAIN_MARGIN, "disk_phase_margin": MIN_PHASE_MARGIN,
               "min_singular_value": MIN_MODULUS_MARGIN}


def _threshold(name: str) -> float | None:
    if name in _THRESHOLDS:
        return _THRESHOLDS[name]
    stem, _, axis = name.rpartition("_")
    return _THRESHOLDS.get(stem) if axis in ("x", "y", "z") else None


def margin_flags(margins: dict, stable: bool) -> dict:
    """The flag of each margin in ``margins`` (name -> value) that deserves one.

    Parameters
    ----------
    margins : dict
        Margins by name: ``gain_margin`` [dB], ``phase_margin`` [deg], ``modulus_margin``;
        three axes ``gain_margin_x``..., ``disk_margin``, ``disk_gain_margin``,
        ``disk_phase_margin``, ``min_singular_value``. Other keys (frequencies) are ignored.
    stable : bool
        The loop's verdict.

    Returns
    -------
    dict
        name -> ``"unstable"`` for every margin of an unstable loop (it guarantees nothing: the
        loop diverges unperturbed), else ``"low"`` for a finite margin below its threshold
        (module docstring; signed: a negative gain or phase margin is below).
    """
    out = {}
    for name, value in margins.items():
        threshold = _threshold(name)
        if threshold is None or isinstance(value, bool) or not isinstance(value, (int, float)):
            continue
        if not stable:
            out[name] = "unstable"
        elif math.isfinite(value) and value < threshold:
            out[name] = "low"
    return out


def margins_dict(margins) -> dict:
    """A loop's :func:`controllers.margins`, JSON-ready, with the frequencies where they are
    attained: planar ``gain_margin`` [dB], ``phase_margin`` [deg], ``modulus_margin`` and
    ``gain_crossover_frequency``, ``phase_crossover_frequency``,
    ``modulus_margin_frequency`` [rad/s]; three axes per axis (``gain_margin_x``... and
    ``gain_crossover_frequency_x``...) and the disk margin and smallest singular value of
    the return difference with their frequencies."""
    m = margins
    out = dict(m.as_dict())
    if hasattr(m, "gain_crossover_frequency"):
        out.update(gain_crossover_frequency=m.gain_crossover_frequency,
                   phase_crossover_frequency=m.phase_crossover_frequency,
                   modulus_margin_frequency=m.modulus_margin_frequency)
    else:
        for axis, a in m.loop_at_a_time.items():
            out.update({f"gain_crossover_frequency_{axis}": a.gain_crossover_frequency,
                        f"phase_crossover_frequency_{axis}": a.phase_crossover_frequency,
                        f"modulus_margin_frequency_{axis}": a.modulus_margin_frequency})
        out.update(disk_margin_frequency=m.disk_margin_frequency,
                   min_singular_value_frequency=m.min_singular_value_frequency)
    return out


def crossover_frequencies(margins) -> list[float]:
    """The positive finite gain crossovers [rad/s] of a loop's margins: a
    :func:`controllers.margins` result or its :func:`margins_dict` (a three-axis loop's, one
    per axis' loop at a time)."""
    if not isinstance(margins, dict):
        margins = margins_dict(margins)
    return [float(w) for k, w in margins.items() if k.startswith("gain_crossover_frequency")
            and w is not None and math.isfinite(w) and w > 0]


def verdict_dict(verdict) -> dict:
    """A :class:`controllers.SpilloverVerdict` as the JSON-ready ``verdict`` of a loop: stable,
    unstable poles, least-damped pole, method, the margins (planar: gain, phase, modulus and
    their frequencies; three axes: per axis and the disk margin), the flexible modes' open-
    and closed-loop damping (``modes``) and the margins' flags (:func:`margin_flags`)."""
    margins = margins_dict(verdict.margins)
    out = {"stable": bool(verdict.stable), "n_unstable_poles": int(verdict.n_unstable_poles),
           "least_damping_ratio": verdict.least_damping_ratio,
           "least_damped_frequency": verdict.least_damped_frequency,
           "method": verdict.method, **margins,
           "modes": [{"frequency": x.frequency, "open_loop_damping": x.open_loop_damping,
                      "closed_loop_frequency": x.closed_loop_frequency,
                      "closed_loop_damping": x.closed_loop_damping} for x in verdict.modes]}
    out["margin_flags"] = margin_flags(margins, not growing(out))
    return out


def resolved_frequency(beam, n_modes: int, method: str, *, three_axis: bool = False,
                       modes_per_motion: Mapping | None = None) -> float:
    """Highest frequency [rad/s] up to which a truncation of ``beam`` to ``n_modes`` modes
    represents it: its n-th clamped (cantilever) frequency for Craig-Bampton (fixed-interface
    modes [2]_), its n-th free-free bending frequency for the free-free and residual
    truncations; ``three_axis``: the n-th of all motions together (both bending planes,
    torsion, axial), as a three-axis truncation keeps the n lowest of them.

    ``modes_per_motion`` (``{"xy": .., "xz": .., "torsion": .., "axial": ..}``, a three-axis
    truncation that keeps modes per motion, e.g. the lowest of a stiff motion an output sees):
    the highest kept frequency below the lowest one left out, of any motion; every mode of the
    beam below it is in the model. For the n lowest of all motions this is the n-th."""
    if modes_per_motion is not None:
        kind = "cantilever_frequencies" if method == "craig-bampton" else "natural_frequencies"
        rods = {"torsion": beam.torsion_rod(), "axial": beam.axial_rod()}
        kept, first_out = [], math.inf
        for motion, count in modes_per_motion.items():
            model = beam.planar_view(motion) if motion in ("xy", "xz") else rods[motion]
            if model is None:
                continue
            w = np.asarray(getattr(model, kind)(int(count) + 1), dtype=float)
            kept.extend(w[:int(count)])
            first_out = min(first_out, float(w[int(count)]))
        below = [w for w in kept if w < first_out]
        return float(max(below)) if below else 0.0
    if not three_axis:
        if method == "craig-bampton":
            return float(beam.cantilever_frequencies(n_modes)[-1])
        return float(beam.natural_frequencies(n_modes)[-1])
    if method == "craig-bampton":
        # the x-y plane alone has n clamped frequencies up to its n-th: all motions at least n
        top = float(beam.cantilever_frequencies(n_modes)[-1])
        return float(beam.clamped_frequencies6(top)[n_modes - 1])
    parts = [beam.planar_view(plane).natural_frequencies(n_modes) for plane in ("xy", "xz")]
    parts += [rod.natural_frequencies(n_modes) for rod in (beam.torsion_rod(), beam.axial_rod())
              if rod is not None]
    return float(np.sort(np.concatenate(parts))[n_modes - 1])


def _who(row) -> str:
    from .naming import controller_label, design_label

    return f"{controller_label(row['controller'])} tuned on {design_label(row['design'])}"


def _warning(code: str, message: str, row=None) -> dict:
    out = {"code": code, "message": message}
    if row is not None:
        out["design"], out["controller"] = row["design"], row["controller"]
    return out


def growing(verdict: dict, status: dict | None = None) -> bool:
    """True if a loop diverges: its status (:func:`loop_status`) says so, or, without one, its
    verdict is not stable and its least-damped pole grows faster than a marginal one
    (-Re(s) = zeta |s| < -MARGINAL max(1, |s|)); a loop whose only poles on the boundary are
    undamped modes it does not reach is marginal, not growing. A verdict without poles (a
    Nyquist count) grows when it is not stable."""
    if status is not None:
        return status.get("status") in ("unstable", "diverges")
    if verdict.get("stable", True):
        return False
    zeta, w = verdict.get("least_damping_ratio"), verdict.get("least_damped_frequency")
    if zeta is None or w is None:
        return True
    return -zeta * w > MARGINAL * max(1.0, w)


#: How a margin reads in a warning: (label, unit) by name stem.
_MARGIN_TEXT = {"gain_margin": ("gain margin", " dB"), "phase_margin": ("phase margin", " deg"),
                "modulus_margin": ("modulus margin", ""), "disk_margin": ("disk margin", ""),
                "disk_gain_margin": ("disk gain margin", " dB"),
                "disk_phase_margin": ("disk phase margin", " deg"),
                "min_singular_value": ("min singular value of I + L", "")}


#: The margins an unstable loop's warning quotes (to say they are none).
_HEADLINE = ("gain_margin", "phase_margin", "modulus_margin", "disk_gain_margin",
             "disk_phase_margin")


def _margin_text(name: str, value: float, *, threshold: bool = False) -> str:
    """``gain margin (x) 4.2 dB``; with ``threshold``, `` (< 6 dB)`` after it."""
    stem, axis = name, ""
    if name not in _MARGIN_TEXT:
        stem, _, axis = name.rpartition("_")
    label, unit = _MARGIN_TEXT[stem]
    text = f"{label}{f' ({axis})' if axis else ''} {value:.3g}{unit}"
    return text + (f" (< {_threshold(name):.3g}{unit})" if threshold else "")


def loop_warnings(who: str, verdict: dict, *, status: dict | None = None, row=None
                  ) -> list[dict]:
    """The warnings of one loop on its truth model (module docstring: unstable, margins,
    damping lowered, lightly damped), planar or three-axis.

    Parameters
    ----------
    who : str
        The loop as the message names it ("LQR tuned on chain, flexsat fit").
    verdict : dict
        :func:`verdict_dict` of its truth verdict (margins under their names, ``modes``).
    status : dict, optional
        :func:`loop_status` of its slew on the truth model.
    row : dict, optional
        Its ``closed_loops`` row (``design``, ``controller`` recorded in the warnings).

    Returns
    -------
    list of dict
        ``code``, ``message`` (and ``design``, ``controller`` with a row).
    """
    out = []
    margins = {k: value for k, value in verdict.items() if _threshold(k) is not None
               and isinstance(value, (int, float)) and not isinstance(value, bool)}
    zeta, w = verdict.get("least_damping_ratio"), verdict.get("least_damped_frequency")
    if growing(verdict, status):
        where = (f": poles at {w:.4g} rad/s with damping ratio {zeta:.3g}"
                 if zeta is not None and w is not None else "")
        # the headline figures (planar margins, three axes' disk margin), not every axis'
        shown = ", ".join(_margin_text(k, value) for k, value in margins.items()
                          if math.isfinite(value) and k in _HEADLINE)
        out.append(_warning("unstable", f"{who} is UNSTABLE on the truth model{where}; "
                            + (f"its margin figures ({shown}) guarantee nothing: the loop diverges "
                               "unperturbed; " if shown else "")
                            + "retune it (lower bandwidth, a roll-off or notch at the mode) "
                            "or design on a better model", row))
        return out
    low = [_margin_text(k, margins[k], threshold=True)
           + (" (negative: a gain reduction by that much destabilises it)"
              if k.startswith("gain_margin") and margins[k] < 0 else "")
           for k in margin_flags(margins, True)]
    if low:
        out.append(_warning("margins", f"{who}: low robustness on the truth model: "
                            + ", ".join(low) + "; a small change of the plant can "
                            "destabilise it (lower the bandwidth, add damping or a "
                            "roll-off)", row))
    lowered = [m for m in verdict.get("modes", [])
               if m["closed_loop_damping"] < (1.0 - DAMPING_DROP) * m["open_loop_damping"]]
    if lowered:
        text = ", ".join(f"{m['frequency']:.4g} rad/s from {m['open_loop_damping']:.3g} to "
                         f"{m['closed_loop_damping']:.3g}" for m in lowered[:4])
        more = f" and {len(lowered) - 4} more" if len(lowered) > 4 else ""
        out.append(_warning("damping_lowered", f"{who} lowers the damping ratio of flexible "
                            f"modes below their open-loop values: {text}{more} (the loop "
                            "drives the structure: spillover); roll the controller off "
                            "below the mode, notch it, or design on a model that has it",
                            row))
    if zeta is not None and w is not None and zeta < MIN_DAMPING:
        out.append(_warning("light_damping", f"{who}: lightly damped closed loop on the truth "
                            f"model: a pole at {w:.4g} rad/s with damping ratio {zeta:.3g} "
                            f"(< {MIN_DAMPING:g}; it rings for about "
                            + (f"{1.0 / (zeta * w):.3g} s per e-fold" if zeta > 0
                               else "ever: undamped")
                            + "); add damping at that mode (rate feedback, a notch) or "
                            "check the structure's damping", row))
    return out


def design_warnings(data: dict, *, loop_band: float | None, resolved: dict) -> list[dict]:
    """The warnings of a run's results (see the module docstring's table).

    Parameters
    ----------
    data : dict
        The run's results (``closed_loops`` rows with ``verdict``, ``design_margins``,
        ``status``, ``exact_verdict``; ``truth``; ``exact``; ``fidelity``).
    loop_band : float or None, rad/s
        bandwidth_factor x the fastest loop's crossover (None: no check of the truth model).
    resolved : dict
        appendage name -> (frequency [rad/s] up to which its truth model is resolved,
        description, covers_loops), for the appendages whose truth is a truncated beam;
        ``covers_loops`` False (the frequency below the loops' band and no converged
        closed-loop check over it) gives the warning ``truth_resolution``.

    Returns
    -------
    list of dict
        ``code``, ``message``, and ``design``, ``controller`` for a loop's warning.
    """
    out = []
    for row in data.get("closed_loops", []):
        who = _who(row)
        v = row["verdict"]
        status = row.get("status", {}).get("truth")
        unstable = growing(v, status)
        out += loop_warnings(who, v, status=status, row=row)
        e = row.get("exact_verdict") or {}
        if "stable" in e and not e["stable"] and not unstable:
            out.append(_warning("unstable_exact", f"{who} is stable on the truncated truth model "
                                "but UNSTABLE on the exact distributed beam (Nyquist): the truth "
                                "model misses what destabilises it; raise fidelity.n_modes or "
                                "lower fidelity.tolerance", row))
        if status is not None and status["status"] in ("slew unfinished", "not settled"):
            out.append(_warning(status["status"].replace(" ", "_"), f"{who}: {status['text']}",
                                row))
    # one warning for the manoeuvre rather than one per loop
    unfinished = [w for w in out if w["code"] == "slew_unfinished"]
    if unfinished:
        out = [w for w in out if w["code"] != "slew_unfinished"]
        out.append(_warning("slew_unfinished", unfinished[0]["message"].split(": ", 1)[1]
                            + "; set manoeuvre.duration beyond manoeuvre.slew_time (3 x "
                            "slew_time is the default)"))
    if loop_band is not None:
        for name, (w_resolved, what, covers) in resolved.items():
            if not covers:
                out.append(_warning("truth_resolution", f"the truth model of {name!r} ({what}) "
                                    f"resolves the appendage up to about {w_resolved:.4g} rad/s, "
                                    f"but the loops act up to {loop_band:.4g} rad/s "
                                    "(bandwidth_factor x crossover): modes in that band are "
                                    "missing; raise fidelity.n_modes or use fidelity.tolerance"))
    record = ((data.get("fidelity") or {}).get("choice") or {}).get("closed_loop")
    if record is not None and not record["converged"]:
        last = record["trials"][-1] if record["trials"] else {}
        worst = max(((k, v) for k, v in last.items() if k != "n_modes"),
                    key=lambda item: item[1], default=None)
        out.append(_warning("truth_not_converged", "the truth model's closed loops have not "
                            f"converged at {data['fidelity']['n_modes']} modes per beam (the "
                            "most the search tries within limits.modes and limits.states)"
                            + (f": the {worst[0].replace('_', ' ')} still changes by "
                               f"{worst[1]:.3g} (relative) with one more mode" if worst else "")
                            + "; loosen fidelity.tolerance or give fidelity.n_modes"))
    exact = (data.get("exact") or {}).get("coupled_frequencies")
    truth = data.get("truth", {}).get("coupled_frequencies")
    if loop_band is not None and exact and truth is not None:
        missed = []
        for k, w in enumerate(exact):
            if w > loop_band:
                break
            if k >= len(truth) or abs(truth[k] / w - 1.0) > MODE_ERROR:
                missed.append((w, truth[k] if k < len(truth) else None))
        if missed:
            text = ", ".join(f"{w:.4g} rad/s (truth model: "
                             + (f"{t:.4g})" if t is not None else "missing)") for w, t in missed)
            out.append(_warning("missed_modes", f"the truth model misses exact coupled modes "
                                f"inside the loops' band (up to {loop_band:.4g} rad/s): {text}; "
                                "raise fidelity.n_modes or use fidelity.tolerance"))
    return out
