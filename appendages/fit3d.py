r"""Three-axis equivalent chains: one body layout, the four motions each matched to the beam.

A three-axis hinged chain (:class:`~appendages.chain.HingedChain` with its three-axis
parameters) has one set of bodies, shared by every motion: lengths, masses and centres of mass
are physical and cannot differ between the bending planes. What may differ per motion is what
each motion alone sees: the bodies' inertias about local z (x-y bending), about local y (x-z
bending) and about x (torsion), and the joints' springs in each motion.

Bending: one fit serves both planes
    The planar fit (:func:`appendages.equivalence.fit_chain`) is run once, on the x-y plane
    (EJ = ``bending_stiffness``). An Euler-Bernoulli beam's x-z plane differs from its x-y
    plane only by its bending stiffness, ``EJ_y = lambda EJ``, with the same mass
    distribution (no rotary inertia of the section in either plane), so every free-free,
    pinned, sliding and clamped frequency of the x-z plane is ``sqrt(lambda)`` times the x-y
    plane's, and so is every pole and zero of its W. A chain with the same bodies and inertias
    and hinges ``lambda c`` scales the same way (its eigenproblems are ``(lambda K, M)``). The
    fit's criterion (log-frequency errors of poles and zeros, rigid properties m, J, L and the
    centre of mass held) is therefore invariant: the x-y fit with its hinges scaled by lambda
    *is* the fit of the x-z plane, with the same relative errors, and the shared body layout
    costs nothing. (tests/appendages/test_three_axis_chain.py runs fit_chain on both planar views and
    finds the same layout and hinges in the ratio lambda.) The bodies' inertias about y and z
    are then equal, as the Euler-Bernoulli beam's are.

Torsion and axial motion: their own criterion
    Each is a spring chain on the same bodies, joined by springs at the joints, fitted to the
    exact rod's first free-free frequency ``pi/tau`` (the first pole of its W) and its first
    clamped-free frequency ``pi/(2 tau)`` (the first zero of W): the rod's version of the
    paper's criterion. Both frequencies scale with the springs, so a common factor beta
    matches the pole exactly once one shape parameter has set their ratio to 2, found by a
    bracketing root search:

    * torsion: the bodies' torsional inertias enter no other motion, so they are free:
      ``J_x,k`` proportional to ``m_k exp(gamma zeta_k)`` (zeta_k the body centre's position
      over L minus 1/2), their sum the beam's ``rho*I_p L`` (a rigid property, like m and J
      in bending); springs ``beta GJ/h_h`` (h_h the distance between the centres of the two
      bodies the joint connects, the lumped-mass rule). Inertia towards the tip raises the
      ratio without bound, towards the root lowers it to 1, so gamma always exists;
    * axial motion: the inertias are the bodies' masses, fixed by the bending fit, and the
      springs ``beta EA/h_h exp(alpha xi_h)`` are tilted (xi_h the joint's position over L
      minus 1/2). Where no alpha in [-8, 8] gives the ratio (two bodies: one spring), the
      pole is matched and the zero is as close as alpha allows; :func:`rod_chain_errors`
      reports both.

Any appendage
    A three-axis appendage other than a uniform beam (a
    :class:`~appendages.modal_data.ModalAppendage`, a beam with a tip body) gives its planes
    as planar appendages (``planar_view("xy")``, ``planar_view("xz")``, the root's other
    motions held); its torsion and axial motion are read from its undamped root dynamic
    stiffness D6 (:func:`motion_frequencies`: the first clamped and free frequencies of one
    root motion with the others held; none when that motion is rigid). The
    x-y plane is fitted by flexsat's fit of any appendage (mass, centre of mass and inertia
    exact); the x-z plane need not be a scaled copy of it, so its bodies' inertias about y and
    its hinges are refitted on the same bodies to the x-z plane's own poles and zeros, with
    its inertia held (:func:`appendages.fitting.fit_plane_on_layout`); torsion and axial
    motion by the rod criterion above with the motion's own first pole and zero (their ratio
    is 2 only for a uniform rod), the torsional inertias summing to the inertia about
    the appendage's axis. Couplings between the motions (an off-axis tip body) are outside
    what a straight chain holds: each motion is fitted with the others held.

Damping
    A damped beam (modal damping ratio zeta) gives every joint stiffness-proportional damping
    ``2 zeta k/w_1`` with w_1 that motion's first free-free chain frequency: ratio zeta at the
    chain's first mode of each motion, the rule of ``HingedChain.rfem`` and of the runner.
    Any other appendage: ``2 zeta k/w`` with w its first cantilever frequency of that plane
    or motion (:func:`appendages.equivalence.damping_frequency_of`, the motion's first clamped
    frequency), the modes whose ratio zeta is.

References
----------
.. [1] Belonozhko et al. 2009 (PAPER.md): the equivalence criterion (poles, zeros, rigid
   properties).
.. [2] R. D. Blevins, "Formulas for Natural Frequency and Mode Shape", 1979, table 8-19 (rods).
.. [3] E. Wittbrodt, I. Adamiec-Wojcik, S. Wojciech, "Dynamics of Flexible Multibody Systems:
   Rigid Finite Element Method", Springer, 2006 (spring-chain discretisation of rods).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import scipy.linalg
import scipy.optimize

from . import fitting
from .fitting import FitWarning
from .chain import HingedChain, spring_chain_matrices
from .equivalence import (damping_frequency_of, damping_ratio_of, fit_chain, fit_targets,
                          is_uniform_beam)
from .errors import ConvergenceError, describe

__all__ = ["MotionRod", "fit_chain_3d", "motion_frequencies", "rod_chain_errors",
           "rod_chain_frequencies"]

_ALPHA_BOUND = 8.0


def rod_chain_frequencies(inertias: np.ndarray, stiffnesses: np.ndarray) -> tuple[float, float]:
    """First free-free and first clamped (body 1 held) frequencies [rad/s] of a spring chain
    with a rigid root (bodies 1..n, springs between neighbours)."""
    M, _, K, _ = spring_chain_matrices(np.asarray(inertias, float),
                                       np.asarray(stiffnesses, float), None, False)
    free = np.sort(scipy.linalg.eigvalsh(K, M))
    clamped = scipy.linalg.eigvalsh(K[1:, 1:], M[1:, 1:])
    return math.sqrt(max(free[1], 0.0)), math.sqrt(max(np.min(clamped), 0.0))


def rod_chain_errors(chain: HingedChain, rod, motion: str) -> dict:
    """Relative errors of a chain's first pole and zero in torsion or axial motion.

    Parameters
    ----------
    chain : HingedChain
        A rigid-root three-axis chain with that motion's springs.
    rod : Rod
        The exact rod (``Beam.torsion_rod()`` or ``axial_rod()``).
    motion : {"torsion", "axial"}

    Returns
    -------
    dict
        ``{"pole": (chain, exact, relative error), "zero": (...)}`` [rad/s].
    """
    if motion == "torsion":
        inertias, springs = chain.torsional_inertias, chain.torsion_stiffnesses
    else:
        inertias, springs = chain.masses, chain.axial_stiffnesses
    pole, zero = rod_chain_frequencies(inertias, springs)
    exact_pole = float(rod.natural_frequencies(1)[0])
    exact_zero = float(rod.cantilever_frequencies(1)[0])
    return {"pole": (pole, exact_pole, pole / exact_pole - 1.0),
            "zero": (zero, exact_zero, zero / exact_zero - 1.0)}


def _ratio_root(log_ratio) -> tuple[float, bool]:
    """The tilt in [-bound, bound] where ``log_ratio`` (the log of the pole/zero ratio less
    the target's) vanishes (brentq), or, when no tilt reaches it, the tilt that comes closest
    (bounded minimisation); and whether it is exact."""
    low, high = log_ratio(-_ALPHA_BOUND), log_ratio(_ALPHA_BOUND)
    if low * high <= 0.0:
        return scipy.optimize.brentq(log_ratio, -_ALPHA_BOUND, _ALPHA_BOUND, xtol=1e-14,
                                     rtol=1e-15), True
    result = scipy.optimize.minimize_scalar(lambda a: abs(log_ratio(a)),
                                            bounds=(-_ALPHA_BOUND, _ALPHA_BOUND),
                                            method="bounded", options={"xatol": 1e-10})
    return float(result.x), False


def _fit_rod_chain(masses: np.ndarray, total_inertia: float | None, centres: np.ndarray,
                   joints: np.ndarray, length: float, rod):
    """(inertias, springs) of a spring chain matched to the rod's first pole and zero.

    Axial motion (``total_inertia`` None): the inertias are the bodies' masses, and the
    springs ``beta S/h exp(alpha xi)`` are tilted. Torsion: the bodies' torsional inertias
    are free (they enter no other motion), ``J_k`` proportional to ``m_k exp(gamma zeta_k)``
    (zeta_k the body's centre over L minus 1/2) with their sum the beam's, and the springs
    ``beta S/h``: tilting the inertia reaches any ratio (all at the tip: unbounded; all at the
    root: 1), tilting springs not always (module docstring).
    """
    spacing = np.diff(centres)
    # any positive scale (beta rescales the springs to the pole); a Rod's own keeps its bits
    base = getattr(rod, "stiffness", 1.0) / spacing
    xi = joints / length - 0.5
    zeta = centres / length - 0.5

    def layout(tilt):
        if total_inertia is None:
            return masses, base * np.exp(tilt * xi)
        weights = masses * np.exp(tilt * (zeta - zeta.max()))  # no overflow at any tilt
        return total_inertia * weights / weights.sum(), base

    # the uniform rod's pole/zero ratio is 2 exactly; any other appendage's motion its own
    target = (math.log(rod.free / rod.clamped) if isinstance(rod, MotionRod)
              else math.log(2.0))

    def log_ratio(tilt):
        pole, zero = rod_chain_frequencies(*layout(tilt))
        return math.log(pole / zero) - target

    tilt, exact = (_ratio_root(log_ratio) if spacing.size >= 2 or total_inertia is not None
                   else (0.0, False))
    if not exact and isinstance(rod, MotionRod):
        # Any other appendage's ratio out of reach: the closest tilt lies on the bound, where
        # the inertias or springs spread over e**8 and the chain's highest mode of this motion
        # rises with them (a design model stiff for nothing: an LQR design on it failed). The
        # untilted layout, the lumped rule, keeps the pole; the zero's error is said.
        tilt = 0.0
    inertias, springs = layout(tilt)
    pole, zero = rod_chain_frequencies(inertias, springs)
    if not exact and isinstance(rod, MotionRod):
        warnings.warn(
            f"fit_chain_3d: the {'axial' if total_inertia is None else 'torsion'} chain of "
            f"{masses.size} bodies cannot reach the appendage's first pole/zero ratio "
            f"{rod.free / rod.clamped:.4g} within its bounded tilt: the untilted chain (ratio "
            f"{pole / zero:.4g}) matches its first pole, its first zero is off by "
            f"{abs(rod.free / rod.clamped * zero / pole - 1):.3g} relative", FitWarning,
            stacklevel=4)
    return inertias, springs * (float(rod.natural_frequencies(1)[0]) / pole) ** 2


def fit_chain_3d(beam, n_bodies: int = 3, *, match: str = "poles-and-zeros",
                 **fit_options) -> HingedChain:
    """A three-axis hinged chain equivalent to a three-axis uniform beam (module docstring).

    Parameters
    ----------
    beam : Beam
        A three-axis beam (``torsional_inertia`` given; ``torsional_stiffness`` None:
        torsionally rigid joints; ``axial_stiffness`` None: inextensible joints).
    n_bodies : int
        Number of rigid bodies (>= 2), as :func:`~appendages.equivalence.fit_chain`.
    match : {"poles-and-zeros", "frequencies"}
        The bending fit (:func:`~appendages.equivalence.fit_chain`).
    **fit_options
        Passed to :func:`~appendages.equivalence.fit_chain` (``pole_weight``, ``max_nfev``).

    Returns
    -------
    HingedChain
        Rigid root; ``hinge_stiffnesses`` the x-y fit's, ``hinge_stiffnesses_y`` those times
        ``bending_stiffness_y/bending_stiffness``, ``inertias_y = inertias``,
        ``torsional_inertias``, ``torsion_stiffnesses`` and ``axial_stiffnesses`` from the rod
        criterion; dampings when the beam is damped.

    Raises
    ------
    ValueError
        A planar beam (no torsional_inertia), a tip body off the axis or with products of
        inertia in the appendage's axes (a chain cannot carry it), or what fit_chain raises.
    ConvergenceError
        If the rod criterion gives non-finite springs.
    """
    if not is_uniform_beam(beam):
        return _fit_any_3d(beam, n_bodies, match, fit_options)
    if not getattr(beam, "three_axis", False):
        raise ValueError(
            "fit_chain_3d needs a three-axis beam: torsional_inertia [kg*m] (rho*I_p per unit "
            f"length) is expected; got {describe(getattr(beam, 'torsional_inertia', None))} "
            "(build the beam with a section constructor or give its torsion)")
    planar = fit_chain(beam.planar_view("xy"), n_bodies, match=match, **fit_options)
    ratio = beam.bending_stiffness_y / beam.bending_stiffness
    masses = np.asarray(planar.masses)
    centres = planar.body_starts + planar.com_offsets
    joints = np.cumsum(planar.lengths)[:-1]
    total_torsional_inertia = beam.torsional_inertia * beam.length
    torsional_inertias = masses * (total_torsional_inertia / beam.mass)
    springs = {}
    for motion, rod, total in (("torsion", beam.torsion_rod(), total_torsional_inertia),
                               ("axial", beam.axial_rod(), None)):
        if rod is None:
            springs[motion] = None
            continue
        inertias, values = _fit_rod_chain(masses, total, centres, joints, beam.length, rod)
        if not np.all(np.isfinite(values)) or np.any(values <= 0) \
                or not np.all(np.isfinite(inertias)) or np.any(inertias <= 0):
            raise ConvergenceError(f"fit_chain_3d: the {motion} chain of {describe(beam)} "
                                   f"came out non-finite or non-positive: springs "
                                   f"{describe(values)}, inertias {describe(inertias)}")
        springs[motion] = values
        if motion == "torsion":
            torsional_inertias = inertias
    stiffnesses_y = ratio * np.asarray(planar.hinge_stiffnesses)
    dampings = {}
    zeta = beam.damping_ratio
    if zeta > 0.0:
        w_xy = float(planar.poles()[0])
        dampings = {"hinge_dampings": 2.0 * zeta * np.asarray(planar.hinge_stiffnesses) / w_xy,
                    "hinge_dampings_y": 2.0 * zeta * stiffnesses_y / (math.sqrt(ratio) * w_xy)}
        for motion, inertias in (("torsion", torsional_inertias), ("axial", masses)):
            if springs[motion] is not None:
                w1, _ = rod_chain_frequencies(inertias, springs[motion])
                dampings[f"{motion}_dampings"] = 2.0 * zeta * springs[motion] / w1
    return HingedChain(planar.lengths, planar.masses, planar.inertias, planar.hinge_stiffnesses,
                       com_offsets=planar.com_offsets, inertias_y=planar.inertias,
                       hinge_stiffnesses_y=stiffnesses_y,
                       torsional_inertias=torsional_inertias,
                       torsion_stiffnesses=springs["torsion"],
                       axial_stiffnesses=springs["axial"], **dampings)


def _fit_any_3d(appendage, n_bodies: int, match: str, fit_options: dict) -> HingedChain:
    """:func:`fit_chain_3d` of a three-axis appendage other than a uniform beam (module
    docstring, "Any appendage")."""
    for attribute in ("planar_view", "inertia_tensor", "dynamic_stiffness6"):
        if not hasattr(appendage, attribute):
            raise TypeError(f"fit_chain_3d needs a three-axis appendage as its beam "
                            f"(planar_view, inertia_tensor, dynamic_stiffness6); got "
                            f"{type(appendage).__name__} without '{attribute}'")
    if not getattr(appendage, "three_axis", False):
        raise ValueError(f"fit_chain_3d needs three-axis data; {describe(appendage)} is planar")
    _check_tip_on_axis(getattr(appendage, "tip", None))
    xy, xz = appendage.planar_view("xy"), appendage.planar_view("xz")
    planar = fit_chain(xy, n_bodies, match=match, **fit_options)
    n = planar.n_bodies
    masses = np.asarray(planar.masses)
    centres = planar.body_starts + planar.com_offsets
    joints = np.cumsum(planar.lengths)[:-1]
    pole_weight = fit_options.get("pole_weight", 10.0)
    data_xz = fit_targets(xz, n)
    inertias_y, stiffnesses_y = fitting.fit_plane_on_layout(
        planar.lengths, masses, planar.com_offsets, planar.inertias, planar.hinge_stiffnesses,
        data_xz["targets"], float(xz.inertia), pole_weight=pole_weight)
    # the inertia about the appendage's x axis (the chain lies on it)
    center = np.asarray(getattr(appendage, "center_of_mass_vector", np.zeros(3)), dtype=float)
    about_axis = float(appendage.inertia_tensor[0, 0]) + appendage.mass * float(
        center[1] ** 2 + center[2] ** 2)
    torsional_inertias = masses * (about_axis / appendage.mass)
    scale = float(planar.poles()[0])  # the first bending frequency (fitted to 1e-4)
    zeta = damping_ratio_of(appendage)
    springs, rods = {}, {motion: motion_frequencies(appendage, index, scale, rigid, zeta)
                         for motion, index, rigid in (("torsion", 3, about_axis),
                                                      ("axial", 0, appendage.mass))}
    for motion, total in (("torsion", about_axis), ("axial", None)):
        rod = rods[motion]
        if rod is None:
            springs[motion] = None
            continue
        inertias, values = _fit_rod_chain(masses, total, centres, joints, planar.length, rod)
        if not np.all(np.isfinite(values)) or np.any(values <= 0) \
                or not np.all(np.isfinite(inertias)) or np.any(inertias <= 0):
            raise ConvergenceError(f"fit_chain_3d: the {motion} chain of {describe(appendage)} "
                                   f"came out non-finite or non-positive: springs "
                                   f"{describe(values)}, inertias {describe(inertias)}")
        springs[motion] = values
        if motion == "torsion":
            torsional_inertias = inertias
    dampings = {}
    zeta_xz = damping_ratio_of(xz)
    if zeta_xz > 0.0:
        dampings["hinge_dampings_y"] = 2.0 * zeta_xz * stiffnesses_y / damping_frequency_of(xz)
    for motion in ("torsion", "axial"):
        rod = rods[motion]
        if springs[motion] is not None and rod.damping_ratio > 0.0:
            # the ratio at the motion's first clamped frequency, as in bending
            dampings[f"{motion}_dampings"] = (2.0 * rod.damping_ratio * springs[motion]
                                              / rod.clamped)
    return HingedChain(planar.lengths, planar.masses, planar.inertias, planar.hinge_stiffnesses,
                       hinge_dampings=planar.hinge_dampings, com_offsets=planar.com_offsets,
                       inertias_y=inertias_y, hinge_stiffnesses_y=stiffnesses_y,
                       torsional_inertias=torsional_inertias,
                       torsion_stiffnesses=springs["torsion"],
                       axial_stiffnesses=springs["axial"], **dampings)


def _check_tip_on_axis(tip) -> None:
    """ValueError for a tip body that no chain can carry: a chain's bodies lie on its axis
    with their principal axes along it, so a body whose centre lies off the axis (a first
    moment across it) or whose inertia has products in the appendage's axes would be lost."""
    if tip is None or tip.is_null:
        return
    offset = [float(v) for v in tip.offset]
    if offset[1] != 0.0 or offset[2] != 0.0:
        raise ValueError(
            f"fit_chain_3d: the tip body's centre lies off the appendage's axis (offset "
            f"{offset} m): a chain's bodies lie on its axis, so no chain keeps the first moment "
            "across it; give the body's offset along x alone (or design on the appendage's "
            "truncation instead of a chain)")
    if not isinstance(tip.inertia, float):
        J = np.asarray(tip.inertia, dtype=float)
        if np.any(J != np.diag(np.diag(J))):
            raise ValueError(
                "fit_chain_3d: the tip body's inertia has products in the appendage's axes "
                f"({J.tolist()} kg*m^2): a chain's bodies have their principal axes along the "
                "chain's; give it diagonal in the appendage's axes")


class MotionRod:
    """One root motion of a three-axis appendage, the others held, seen as a rod: what the rod
    criterion of :func:`fit_chain_3d` needs (as a uniform beam's :class:`~appendages.rod.Rod`).

    Attributes
    ----------
    free, clamped : float
        Its first free (pole of W) and clamped (zero of W) frequency [rad/s].
    rigid_inertia : float
        Its rigid mass [kg] or moment of inertia about the axis [kg*m^2].
    damping_ratio : float
        The appendage's (its first mode's) [-].
    """

    def __init__(self, free: float, clamped: float, rigid_inertia: float, damping_ratio: float):
        self.free, self.clamped = float(free), float(clamped)
        self.rigid_inertia, self.damping_ratio = float(rigid_inertia), float(damping_ratio)

    def __repr__(self) -> str:
        return (f"MotionRod(free={self.free!r}, clamped={self.clamped!r}, "
                f"rigid_inertia={self.rigid_inertia!r})")

    def natural_frequencies(self, n: int) -> np.ndarray:
        """[free] (n = 1 only)."""
        if n != 1:
            raise ValueError(f"a MotionRod holds the first frequency only; got n = {n!r}")
        return np.array([self.free])

    def cantilever_frequencies(self, n: int) -> np.ndarray:
        """[clamped] (n = 1 only)."""
        if n != 1:
            raise ValueError(f"a MotionRod holds the first frequency only; got n = {n!r}")
        return np.array([self.clamped])


#: The scan of :func:`motion_frequencies`: points per decade and decades above and below the
#: appendage's first bending frequency.
_SCAN_PER_DECADE, _SCAN_BELOW, _SCAN_ABOVE = 100, 3, 8


def motion_frequencies(appendage, index: int, scale: float, rigid_inertia: float,
                       damping_ratio: float = 0.0) -> MotionRod | None:
    """The first clamped and free frequencies of root motion ``index`` (0 axial, 3 torsion)
    with the root's other motions held, from the undamped root dynamic stiffness.

    On the imaginary axis ``f(omega) = D6[index, index](i omega)`` of an undamped structure is
    real and decreasing between its poles (its derivative in omega**2 is minus a kinetic
    energy), from ``f(0) = 0``: it first falls to a pole at the first clamped frequency (the
    zero of this motion's W), comes back from plus infinity and crosses zero at the first free
    frequency (its pole). They are bracketed on a logarithmic scan (100 points per decade from
    ``1e-3 scale`` to ``1e8 scale``) and refined by Brent's method on ``1/f`` and ``f``. A pole
    and zero closer than the scan's step (a mode of another motion coupled very weakly) are
    passed over, as W barely shows them.

    Parameters
    ----------
    appendage
        Offers ``dynamic_stiffness6(s)`` (and ``undamped()`` when damped).
    index : {0, 3}
    scale : float, rad/s
        A frequency of the appendage (its first bending one).
    rigid_inertia : float
        The motion's rigid inertia [kg or kg*m^2], kept with the result.
    damping_ratio : float

    Returns
    -------
    MotionRod or None
        None when f has no pole in the scan: the motion is rigid (an inextensible or
        torsionally rigid appendage).
    """
    model = appendage.undamped() if hasattr(appendage, "undamped") else appendage

    def f(omega):
        value = model.dynamic_stiffness6(np.atleast_1d(1j * omega))[..., index, index].real
        return value if np.ndim(omega) else float(value[0])

    edges = scale * np.logspace(-_SCAN_BELOW, _SCAN_ABOVE,
                                (_SCAN_BELOW + _SCAN_ABOVE) * _SCAN_PER_DECADE + 1)
    with np.errstate(all="ignore"):
        values = f(edges)
    finite = np.isfinite(values)
    sign = np.sign(np.where(finite, values, np.nan))
    up = np.flatnonzero((sign[:-1] < 0) & (sign[1:] > 0))  # through a pole: - to +
    if up.size == 0:
        return None
    k = int(up[0])
    def inverse(w):  # continuous through the pole; at the pole itself D is not finite
        value = f(w)
        return 1.0 / value if math.isfinite(value) else 0.0

    with np.errstate(all="ignore"):
        clamped = scipy.optimize.brentq(inverse, edges[k], edges[k + 1],
                                        xtol=1e-14 * edges[k], rtol=1e-15)
    down = np.flatnonzero((sign[k + 1:-1] > 0) & (sign[k + 2:] < 0))
    if down.size == 0:
        return None
    j = k + 1 + int(down[0])
    with np.errstate(all="ignore"):
        free = scipy.optimize.brentq(f, edges[j], edges[j + 1], xtol=1e-14 * edges[j],
                                     rtol=1e-15)
    return MotionRod(free, clamped, rigid_inertia, damping_ratio)
