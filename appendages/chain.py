"""Chains of hinged rigid bodies: the lumped-parameter appendage model.

A :class:`HingedChain` is n rigid bodies in a line along the undeformed appendage axis x, joined by
torsional springs (and dampers) at hinges, moving in the plane xy, linearised about the straight
configuration. The attachment end (x = 0) is the start of the first body (``root="rigid"``) or,
with ``root="hinged"``, a massless mount joined to the first body by one more spring hinge (a
solar-array drive).

Generalised coordinates (the attachment-end coordinates of :class:`~appendages.interface.RootModel`)

- ``root="rigid"``: ``q = [delta, phi, theta_2, ..., theta_n]`` with ``phi = theta_1``;
- ``root="hinged"``: ``q = [delta, phi, theta_1, ..., theta_n]`` with ``phi`` the massless mount's
  rotation,

where ``delta`` [m] is the transverse displacement of the attachment end and ``theta_i`` [rad] the
absolute (small) rotation of body i about +z. Body i starts at ``x_i = l_1 + ... + l_(i-1)``; its
centre of mass lies at ``x_i + a_i`` (``a_i`` the com offset) and moves transversally by

    y_i = delta + sum_(j<i) l_j theta_j + a_i theta_i                                   (1)

so the kinetic energy ``T = 1/2 sum_i (m_i y_i'^2 + J_i theta_i'^2)`` gives the mass matrix
``M = sum_i m_i g_i g_i^T + diag(J)`` with ``g_i = dy_i/dq``. Writing ``S_k = m_(k+1) + ... + m_n``
(mass outboard of body k) and ``P_k = m_k a_k + l_k S_k`` (first moment of bodies k..n about the
start of body k, per unit rotation of body k), and ``l_0 = 1`` for the ``delta`` coordinate,

    M[j, k] = l_j P_k  (j < k),    M[0, 0] = m,    M[k, k] = J_k + m_k a_k**2 + l_k**2 S_k   (2)

a sum of positive terms (no cancellation), built in O(n**2). Absolute angles make the stiffness
and damping matrices tridiagonal: hinge h between bodies k and k+1 adds
``c_h (theta_(k+1) - theta_k)**2 / 2`` to the potential energy. Absolute angles also keep the mass
matrix well conditioned: after diagonal scaling its condition number grows like n**2, as a
finite-element mass matrix's (5e5 for a 200-body RFEM chain), against n**4 with relative hinge
angles (5e10), so chains of hundreds of bodies keep their accuracy (tests: 200 bodies agree with
an O(n) Newton-Euler recursion to 1e-9 and with Blevins' frequencies to their O(H**4)
discretisation error).

References
----------
.. [1] P. A. Belonozhko, P. P. Belonozhko, A. A. Fokov et al., "On the equivalence of mechanical
   design schemes with distributed and lumped parameters for spatially developed peripheral
   elements of spacecraft", Institute of Technical Mechanics, NAS of Ukraine, 2009 (the
   three-body chain and the static-equivalence rules).
.. [2] E. Wittbrodt, I. Adamiec-Wojcik, S. Wojciech, "Dynamics of Flexible Multibody Systems:
   Rigid Finite Element Method", Springer, 2006 (the rigid finite element chain, c = EJ/H).
.. [3] K. Molenaar, "Superelements", cited in [1]: three rods kL, (1-2k)L, kL and two hinges
   c = 6 EJ/L (1-2k)**2, k = (1 - 1/sqrt(3))/2.
"""

from __future__ import annotations

import contextlib
import numbers
from collections.abc import Sequence

import numpy as np
import scipy.linalg

from . import limits
from .checks import RANGES, as_frequency_array, check_range
from .errors import describe
from .interface import (FiniteAppendage, RootModel, inverse_2x2, place_bending_planes,
                        three_axis_root_model)

__all__ = ["HingedChain", "MOLENAAR_K", "chain_matrices", "proportional_hinge_dampings",
           "spring_chain_matrices"]

#: Molenaar's superelement end-rod fraction k = (1 - 1/sqrt(3))/2 [1]_.
MOLENAAR_K: float = 0.5 * (1.0 - 1.0 / np.sqrt(3.0))

_ROOTS = ("rigid", "hinged")


def _as_vector(name: str, values, quantity: str | None, unit: str, *, size: int | None = None,
               allow_zero: bool = False) -> np.ndarray:
    """Validate a 1-D sequence of finite reals, each positive (or zero when ``allow_zero``) and
    within the documented range of ``quantity`` (:data:`~appendages.interface.RANGES`, None:
    no range); return a read-only float64 copy."""
    if isinstance(values, (str, bytes)) or values is None:
        raise TypeError(f"{name} must be a sequence of real numbers [{unit}]; "
                        f"got {type(values).__name__}")
    if isinstance(values, numbers.Number) or np.ndim(values) == 0:
        raise TypeError(f"{name} must be a sequence of real numbers [{unit}], one per "
                        f"{'hinge' if 'hinge' in name else 'body'}; got the scalar "
                        f"{describe(values)}")
    try:
        arr = np.asarray(values)
    except (ValueError, TypeError) as exc:  # ragged nesting
        raise ValueError(f"{name} must be a flat sequence of real numbers [{unit}]; got "
                         f"{describe(values)}") from exc
    if arr.dtype == bool or arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must contain real numbers [{unit}]; got dtype {arr.dtype}")
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional [{unit}]; got shape {arr.shape}")
    if size is not None and arr.size != size:
        raise ValueError(f"{name} must have {size} entries [{unit}]; got {arr.size}")
    with np.errstate(over="ignore"):  # a huge int becomes inf, refused below
        arr = arr.astype(np.float64)
    low, high = (RANGES[quantity][:2] if quantity is not None else (0.0, np.inf))
    positive = (arr >= 0.0) if allow_zero else (arr > 0.0)
    in_range = (arr >= low) & (arr <= high) | (allow_zero & (arr == 0.0))
    bad = ~np.isfinite(arr) | ~positive | ~in_range
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        what = "non-negative" if allow_zero else "positive"
        value = float(arr[k])
        if np.isfinite(value) and positive[k]:  # finite and positive but out of range
            bounds = f"at most {high:g}" if low == 0.0 else f"within [{low:g}, {high:g}]"
            raise ValueError(f"{name} must be {bounds} [{unit}] (the range where flexsat's "
                             f"numerics are sound, appendages.interface.RANGES); got "
                             f"{value!r} at index {k}")
        raise ValueError(f"{name} must be {what} and finite [{unit}]; got {describe(value)} at index {k}")
    arr.flags.writeable = False
    return arr


def _check_count(name: str, value, *, minimum: int) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer; got {type(value).__name__} {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be at least {minimum}; got {value}")
    return int(value)


def _frozen_pieces(lengths: np.ndarray, linear_density: float):
    """Masses [kg] and central inertias [kg*m^2] of thin uniform rods cut from one rod."""
    masses = linear_density * lengths
    return masses, masses * lengths**2 / 12.0


class HingedChain(FiniteAppendage):
    """A chain of rigid bodies joined by torsional spring hinges (planar, linearised).

    Parameters
    ----------
    lengths : sequence of float, m
        Length of each body, from the attachment end outward (n >= 1 entries, positive).
    masses : sequence of float, kg
        Mass of each body (positive).
    inertias : sequence of float, kg*m^2
        Moment of inertia of each body about its own centre of mass (non-negative; 0 for a
        point mass, as long as the mass matrix stays nonsingular).
    hinge_stiffnesses : sequence of float, N*m/rad
        Torsional stiffness of each hinge: n - 1 entries for ``root="rigid"`` (hinge k between
        bodies k and k+1), n entries for ``root="hinged"`` (the first between mount and body 1).
    hinge_dampings : sequence of float, N*m*s/rad, optional
        Viscous damping of each hinge (same count; default zero).
    com_offsets : sequence of float, m, optional
        Distance of each body's centre of mass from the body's start, in [0, length]; the last
        body's may lie beyond its end (a body carrying a tip mass), >= 0 (default:
        mid-length).
    root : {"rigid", "hinged"}
        How the first body is attached to the mount.

    Raises
    ------
    TypeError
        Parameters that are not sequences of real numbers.
    ValueError
        Wrong counts, values outside the documented ranges of
        :data:`appendages.interface.RANGES` (lengths 1e-6 to 1e6 m, masses 1e-15 to 1e15 kg,
        inertias up to 1e20 kg*m**2, hinge stiffnesses 1e-15 to 1e15 N*m/rad, dampings up to
        1e15 N*m*s/rad), a singular mass matrix, or more bodies than the ``bodies`` limit of
        :mod:`appendages.limits` (500; a :class:`~appendages.limits.LimitError`).

    Attributes
    ----------
    lengths, masses, inertias, hinge_stiffnesses, hinge_dampings, com_offsets : ndarray
        The inputs as read-only float64 arrays.
    root : str
    n_bodies : int

    Notes
    -----
    Coordinates, mass and stiffness matrices: see :mod:`appendages.chain` (eq. (1), (2)). W(s),
    poles, zeros, gains and the state-space model come from
    :class:`~appendages.interface.FiniteAppendage`.

    References
    ----------
    .. [1] Belonozhko et al. 2009 (see :mod:`appendages.chain`).
    """

    def __init__(self, lengths: Sequence[float], masses: Sequence[float],
                 inertias: Sequence[float], hinge_stiffnesses: Sequence[float], *,
                 hinge_dampings: Sequence[float] | None = None,
                 com_offsets: Sequence[float] | None = None, root: str = "rigid",
                 inertias_y: Sequence[float] | None = None,
                 hinge_stiffnesses_y: Sequence[float] | None = None,
                 hinge_dampings_y: Sequence[float] | None = None,
                 torsional_inertias: Sequence[float] | None = None,
                 torsion_stiffnesses: Sequence[float] | None = None,
                 torsion_dampings: Sequence[float] | None = None,
                 axial_stiffnesses: Sequence[float] | None = None,
                 axial_dampings: Sequence[float] | None = None) -> None:
        if not isinstance(root, str) or root not in _ROOTS:
            raise ValueError(f"root must be 'rigid' or 'hinged'; got {describe(root)}")
        self.root = root
        self.lengths = _as_vector("lengths", lengths, "length", "m")
        n = self.lengths.size
        if n < 1:
            raise ValueError("lengths must have at least one entry [m]; got an empty sequence")
        limits.check("lengths (number of bodies)", n, "bodies", "bodies per chain")
        self.n_bodies = n
        self.masses = _as_vector("masses", masses, "mass", "kg", size=n)
        self.inertias = _as_vector("inertias", inertias, "body_inertia", "kg*m^2", size=n,
                                   allow_zero=True)
        n_hinges = n - 1 if root == "rigid" else n
        self.hinge_stiffnesses = _as_vector(
            f"hinge_stiffnesses (root={root!r}: one per hinge)", hinge_stiffnesses,
            "hinge_stiffness", "N*m/rad", size=n_hinges)
        if hinge_dampings is None:
            dampings = np.zeros(n_hinges)
            dampings.flags.writeable = False
            self.hinge_dampings = dampings
        else:
            self.hinge_dampings = _as_vector(
                f"hinge_dampings (root={root!r}: one per hinge)", hinge_dampings,
                "hinge_damping", "N*m*s/rad", size=n_hinges, allow_zero=True)
        if com_offsets is None:
            offsets = 0.5 * self.lengths
            offsets.flags.writeable = False
            self.com_offsets = offsets
        else:
            self.com_offsets = _as_vector("com_offsets", com_offsets, None, "m", size=n,
                                          allow_zero=True)
            over = self.com_offsets > self.lengths * (1.0 + 1e-12)
            over[-1] = False   # the last body's centre may lie beyond its end (a tip body)
            if np.any(over):
                k = int(np.flatnonzero(over)[0])
                raise ValueError(
                    f"com_offsets must lie in [0, length of the body] [m]; got "
                    f"{float(self.com_offsets[k])!r} for body {k} of length "
                    f"{float(self.lengths[k])!r}")
        self._check_mass_matrix()
        self._init_three_axis(n_hinges, inertias_y, hinge_stiffnesses_y, hinge_dampings_y,
                              torsional_inertias, torsion_stiffnesses, torsion_dampings,
                              axial_stiffnesses, axial_dampings)

    def _init_three_axis(self, n_hinges, inertias_y, hinge_stiffnesses_y, hinge_dampings_y,
                         torsional_inertias, torsion_stiffnesses, torsion_dampings,
                         axial_stiffnesses, axial_dampings) -> None:
        """Validate and store the three-axis parameters (class docstring)."""
        n, root = self.n_bodies, self.root
        per_hinge = f"(root={root!r}: one per hinge)"
        self.inertias_y = (self.inertias if inertias_y is None else _as_vector(
            "inertias_y", inertias_y, "body_inertia", "kg*m^2", size=n, allow_zero=True))
        self.hinge_stiffnesses_y = (self.hinge_stiffnesses if hinge_stiffnesses_y is None
                                    else _as_vector(f"hinge_stiffnesses_y {per_hinge}",
                                                    hinge_stiffnesses_y, "hinge_stiffness",
                                                    "N*m/rad", size=n_hinges))
        self.hinge_dampings_y = (self.hinge_dampings if hinge_dampings_y is None
                                 else _as_vector(f"hinge_dampings_y {per_hinge}",
                                                 hinge_dampings_y, "hinge_damping",
                                                 "N*m*s/rad", size=n_hinges, allow_zero=True))
        if inertias_y is not None:
            self._check_mass_matrix(self.inertias_y, "inertias_y")
        self.torsional_inertias = (None if torsional_inertias is None else _as_vector(
            "torsional_inertias", torsional_inertias, "body_inertia", "kg*m^2", size=n))
        if torsion_stiffnesses is not None and self.torsional_inertias is None:
            raise ValueError("torsional_inertias [kg*m^2] must be given with "
                             "torsion_stiffnesses; got None")
        self.torsion_stiffnesses = (None if torsion_stiffnesses is None else _as_vector(
            f"torsion_stiffnesses {per_hinge}", torsion_stiffnesses, "hinge_stiffness",
            "N*m/rad", size=n_hinges))
        self.axial_stiffnesses = (None if axial_stiffnesses is None else _as_vector(
            f"axial_stiffnesses {per_hinge}", axial_stiffnesses, "axial_spring", "N/m",
            size=n_hinges))
        for name, dampings, springs, unit in (
                ("torsion_dampings", torsion_dampings, self.torsion_stiffnesses, "N*m*s/rad"),
                ("axial_dampings", axial_dampings, self.axial_stiffnesses, "N*s/m")):
            if dampings is not None and springs is None:
                raise ValueError(f"{name} [{unit}] needs the springs they damp "
                                 f"({name.replace('dampings', 'stiffnesses')}); got None")
        self.torsion_dampings = (None if torsion_dampings is None else _as_vector(
            f"torsion_dampings {per_hinge}", torsion_dampings, "hinge_damping", "N*m*s/rad",
            size=n_hinges, allow_zero=True))
        self.axial_dampings = (None if axial_dampings is None else _as_vector(
            f"axial_dampings {per_hinge}", axial_dampings, None, "N*s/m", size=n_hinges,
            allow_zero=True))

    @property
    def three_axis(self) -> bool:
        """True when the chain has what a three-axis model needs (torsional inertias)."""
        return self.torsional_inertias is not None

    def _require_three_axis(self, what: str) -> None:
        if self.torsional_inertias is None:
            raise ValueError(
                f"{what} needs the chain's torsion: torsional_inertias [kg*m^2] (each body's "
                "moment of inertia about the chain's axis) and torsion_stiffnesses [N*m/rad] "
                "(None: torsionally rigid joints) are expected; got torsional_inertias = None "
                "(a planar chain). Give them, or fit the chain with "
                "appendages.fit_chain_3d")

    # -- constructors -------------------------------------------------------------------------
    @classmethod
    def three_body(cls, length: float, mass: float, k_L: float, stiffness: float) -> "HingedChain":
        """The paper's symmetric three-body chain [1]_.

        Rods of lengths ``(1 - k_L) L/2``, ``k_L L``, ``(1 - k_L) L/2``, cut as "frozen pieces"
        of a uniform thin rod of mass m (``m_i = m l_i / L``, ``J_i = m_i l_i**2 / 12``, so that
        the chain's inertia about its centre of mass equals the rod's ``m L**2 / 12``), joined
        by two hinges of equal stiffness.

        Parameters
        ----------
        length : float, m
        mass : float, kg
        k_L : float
            Fraction of the length taken by the middle rod, in (0, 1).
        stiffness : float, N*m/rad
            Stiffness c of both hinges.

        References
        ----------
        .. [1] Belonozhko et al. 2009, the worked example (see :mod:`appendages.chain`).
        """
        length = check_range("length", length, "length")
        mass = check_range("mass", mass, "mass")
        stiffness = check_range("stiffness", stiffness, "hinge_stiffness")
        if isinstance(k_L, (bool, np.bool_)) or not isinstance(k_L, numbers.Real):
            raise TypeError(f"k_L must be a real number [-]; got {type(k_L).__name__} {describe(k_L)}")
        k_L = float(k_L)
        if not (0.0 < k_L < 1.0):
            raise ValueError(f"k_L must lie in the open interval (0, 1) [-]; got {describe(k_L)}")
        lengths = np.array([(1.0 - k_L) / 2.0, k_L, (1.0 - k_L) / 2.0]) * length
        masses, inertias = _frozen_pieces(lengths, mass / length)
        with _derived_from(f"HingedChain.three_body(length={length!r}, mass={mass!r}, "
                           f"k_L={k_L!r})", None):
            return cls(lengths, masses, inertias, [stiffness, stiffness])

    @classmethod
    def rfem(cls, beam, n_bodies: int) -> "HingedChain":
        """Rigid-finite-element chain of a uniform beam [2]_.

        ``n_bodies`` rods: two end rods of length H/2 and ``n_bodies - 2`` inner rods of length
        H = L/(n_bodies - 1), frozen pieces of the beam, joined by hinges of stiffness
        ``c = EJ/H`` (pure bending of an arc of length H). If the beam has a modal damping ratio
        zeta, the hinges get stiffness-proportional damping ``2 zeta c / w_1`` (damping ratio
        zeta at the beam's first frequency w_1).

        A three-axis beam (``beam.three_axis``; with a tip body, one given its 3x3 inertia:
        a planar moment makes the x-y plane's chain) gives a three-axis chain by the same
        rule in every motion: hinges ``EJ_y/H`` in the x-z plane, torsion springs ``GJ/H`` and axial
        springs ``EA/H`` (None where the beam is torsionally rigid or inextensible), body
        inertias about y equal to those about z (``m l**2/12``, no rotary inertia of the
        section, as the beam) and about x ``rho*I_p l``; each motion damped at its own first
        free-free frequency.

        A stepped beam (:class:`~appendages.stepped.SteppedBeam`, uniform segments end to end)
        gets the same hinges at the same places, each the series flexibility of the arc of
        length H about it, ``1/c = integral dx/EJ(x)`` over ``[x_h - H/2, x_h + H/2]`` (pure
        bending of that arc; ``EJ/H`` where the arc is uniform), and bodies that are the
        frozen pieces of the stepped beam between the hinges (mass, centre and inertia of the
        segments' parts they hold). Torsion and axial springs follow the same rule; the
        torsion and axial damping is set at the stepped rod's first cantilever frequency
        (:meth:`~appendages.segmented.SegmentedBeam.rod_cantilever_frequencies`). As for a
        uniform beam, the chain converges to the beam as n_bodies grows.

        A tip body (``beam.tip``) joins the last body (its mass, moment and parallel-axis
        terms); the body must lie on the axis with its principal axes along the beam's (a
        chain's bodies do), else ValueError names it.

        Parameters
        ----------
        beam : Beam or SteppedBeam
            Uniform beam (``length``, ``bending_stiffness``, ``linear_density``) or stepped
            beam (``segment_properties``), with or without a tip body.
        n_bodies : int
            Number of rods, at least 2.

        Raises
        ------
        TypeError
            Anything else (finite-element modal data have no stiffness along their length to
            discretise: fit a chain with :func:`appendages.equivalence.fit_chain`).

        References
        ----------
        .. [2] Wittbrodt, Adamiec-Wojcik, Wojciech 2006; rule 1 of Belonozhko et al. 2009.
        """
        n_bodies = _check_count("n_bodies", n_bodies, minimum=2)
        limits.check("n_bodies", n_bodies, "bodies", "bodies per chain")
        segments = _stepped_segments(beam, "HingedChain.rfem")
        if segments is not None:
            return cls._stepped_rfem(beam, segments, n_bodies)
        L, EJ, rho = _beam_properties(beam)
        H = L / (n_bodies - 1)
        lengths = np.full(n_bodies, H)
        lengths[0] = lengths[-1] = H / 2.0
        masses, inertias = _frozen_pieces(lengths, rho)
        stiffnesses = np.full(n_bodies - 1, EJ / H)
        three_axis = _three_axis_rfem(beam, lengths, H) if _three_axis_chain(beam) else {}
        masses, inertias, offsets = _with_tip(beam, lengths, masses, inertias, three_axis)
        with _derived_from(f"HingedChain.rfem(beam, n_bodies={n_bodies})", beam):
            return cls(lengths, masses, inertias, stiffnesses, com_offsets=offsets,
                       hinge_dampings=proportional_hinge_dampings(beam, stiffnesses),
                       **three_axis)

    @classmethod
    def superelements(cls, beam, n: int) -> "HingedChain":
        """Chain of n Molenaar superelements [3]_.

        Each superelement of length l = L/n is three rods ``k l, (1 - 2k) l, k l`` with
        ``k = (1 - 1/sqrt(3))/2`` and two hinges ``c = 6 EJ/l (1 - 2k)**2`` (= 2 EJ/l), which
        give a cantilever's static tip deflection and rotation under an end force and moment.
        The rigidly joined end rods of neighbouring superelements form one body of length
        2kl, so the chain has 2n + 1 bodies and 2n hinges; frozen pieces of the beam.
        Damping as in :meth:`rfem`; a tip body as in :meth:`rfem`. A planar method: a
        three-axis beam gives its x-y plane's chain.

        A superelement is derived for a uniform piece. On a stepped beam
        (:class:`~appendages.stepped.SteppedBeam`) each superelement takes the section of the
        segment it lies in, which needs every step at a multiple of l = L/n (e.g. a 1 m and a
        6 m segment with n = 7 or 14); other n are refused by name (the superelement across a
        step is not defined; :meth:`rfem` or :func:`~appendages.equivalence.fit_chain` take
        any stepped beam). The end rods of neighbouring superelements form one body, of two
        sections where it spans a step.

        Parameters
        ----------
        beam : Beam or SteppedBeam
        n : int
            Number of superelements, at least 1.

        Raises
        ------
        ValueError
            A stepped beam whose steps are not at multiples of L/n (the message gives them).

        References
        ----------
        .. [3] Molenaar, cited as rule 2 in Belonozhko et al. 2009.
        """
        n = _check_count("n", n, minimum=1)
        limits.check("n (2 n + 1 bodies)", 2 * n + 1, "bodies", "bodies per chain")
        segments = _stepped_segments(beam, "HingedChain.superelements")
        if segments is not None:
            return cls._stepped_superelements(beam, segments, n)
        L, EJ, rho = _beam_properties(beam)
        ell = L / n
        k = MOLENAAR_K
        lengths = np.empty(2 * n + 1)
        lengths[0] = lengths[-1] = k * ell
        lengths[1::2] = (1.0 - 2.0 * k) * ell
        lengths[2:-1:2] = 2.0 * k * ell
        masses, inertias = _frozen_pieces(lengths, rho)
        stiffnesses = np.full(2 * n, 6.0 * EJ / ell * (1.0 - 2.0 * k) ** 2)
        masses, inertias, offsets = _with_tip(beam, lengths, masses, inertias, {})
        with _derived_from(f"HingedChain.superelements(beam, n={n})", beam):
            return cls(lengths, masses, inertias, stiffnesses, com_offsets=offsets,
                       hinge_dampings=proportional_hinge_dampings(beam, stiffnesses))

    @classmethod
    def _stepped_rfem(cls, beam, segments, n_bodies: int) -> "HingedChain":
        """:meth:`rfem` of a stepped beam (its docstring)."""
        L = float(sum(seg.length for seg in segments))
        H = L / (n_bodies - 1)
        hinges = H * (0.5 + np.arange(n_bodies - 1))
        hinges[-1] = L - 0.5 * H
        edges = np.concatenate([[0.0], hinges, [L]])
        lengths = np.diff(edges)
        masses, offsets, inertias, torsional = _frozen_stepped_pieces(segments, edges)
        arcs = [(x - 0.5 * H, x + 0.5 * H) for x in hinges]
        stiffnesses = _arc_stiffnesses(segments, arcs, "bending_stiffness")
        three_axis = {}
        if _three_axis_chain(beam):
            three_axis = {"inertias_y": inertias.copy(),
                          "hinge_stiffnesses_y": _arc_stiffnesses(segments, arcs,
                                                                  "bending_stiffness_y"),
                          "torsional_inertias": torsional}
            three_axis["hinge_dampings_y"] = proportional_hinge_dampings(
                beam.planar_view("xz"), three_axis["hinge_stiffnesses_y"])
            for name, attribute in (("torsion", "torsional_stiffness"),
                                    ("axial", "axial_stiffness")):
                if getattr(segments[0], attribute) is None:
                    continue
                springs = _arc_stiffnesses(segments, arcs, attribute)
                three_axis[f"{name}_stiffnesses"] = springs
                if beam.damping_ratio > 0.0:
                    w1 = float(beam.rod_cantilever_frequencies(name, 1)[0])
                    three_axis[f"{name}_dampings"] = 2.0 * beam.damping_ratio * springs / w1
        masses, inertias, offsets = _with_tip(beam, lengths, masses, inertias, three_axis,
                                              offsets)
        with _derived_from(f"HingedChain.rfem(beam, n_bodies={n_bodies})", beam):
            return cls(lengths, masses, inertias, stiffnesses, com_offsets=offsets,
                       hinge_dampings=proportional_hinge_dampings(beam, stiffnesses),
                       **three_axis)

    @classmethod
    def _stepped_superelements(cls, beam, segments, n: int) -> "HingedChain":
        """:meth:`superelements` of a stepped beam (its docstring)."""
        L = float(sum(seg.length for seg in segments))
        ell = L / n
        steps = np.cumsum([seg.length for seg in segments])[:-1]
        # a step within 1e-9 of a piece's length of a multiple of ell is on it (the lengths
        # were given to a few digits; the frozen pieces below integrate the exact lengths)
        off = [x for x in steps if abs(x / ell - round(x / ell)) > 1e-9]
        if off:
            raise ValueError(
                f"HingedChain.superelements(beam, n={n}): Molenaar's superelement is a uniform "
                f"piece, so every step of a stepped beam must lie at a multiple of L/n = "
                f"{ell:.6g} m; the steps at x = {describe([float(x) for x in off])} m do not "
                f"(choose n so that L/n divides every segment's length, or use "
                "HingedChain.rfem or appendages.equivalence.fit_chain, which take any stepped "
                "beam)")
        k = MOLENAAR_K
        starts = ell * np.arange(n)
        inner = np.sort(np.concatenate([starts + k * ell, starts + (1.0 - k) * ell]))
        edges = np.concatenate([[0.0], inner, [L]])
        lengths = np.diff(edges)
        masses, offsets, inertias, _ = _frozen_stepped_pieces(segments, edges)
        bounds = np.concatenate([[0.0], steps, [L]])
        owner = np.searchsorted(bounds, starts + 0.5 * ell, side="right") - 1
        EJ = np.array([segments[j].bending_stiffness for j in owner])
        stiffnesses = np.repeat(6.0 * EJ / ell * (1.0 - 2.0 * k) ** 2, 2)
        masses, inertias, offsets = _with_tip(beam, lengths, masses, inertias, {}, offsets)
        with _derived_from(f"HingedChain.superelements(beam, n={n})", beam):
            return cls(lengths, masses, inertias, stiffnesses, com_offsets=offsets,
                       hinge_dampings=proportional_hinge_dampings(beam, stiffnesses))

    # -- rigid properties ---------------------------------------------------------------------
    @property
    def length(self) -> float:
        """Total length [m]."""
        return float(np.sum(self.lengths))

    @property
    def mass(self) -> float:
        """Total mass [kg]."""
        return float(np.sum(self.masses))

    @property
    def body_starts(self) -> np.ndarray:
        """x coordinate of each body's start [m] (the first is 0)."""
        return np.concatenate([[0.0], np.cumsum(self.lengths)[:-1]])

    @property
    def center_of_mass(self) -> float:
        """x coordinate of the chain's centre of mass, undeformed [m]."""
        return float(np.dot(self.masses, self.body_starts + self.com_offsets) / self.mass)

    @property
    def inertia(self) -> float:
        """Moment of inertia about the chain's centre of mass, undeformed [kg*m^2].

        ``sum_i (J_i + m_i d_i**2)`` with d_i the distance of body i's centre of mass from the
        chain's (parallel-axis theorem).
        """
        d = self.body_starts + self.com_offsets - self.center_of_mass
        return float(np.sum(self.inertias) + np.dot(self.masses, d * d))

    def __repr__(self) -> str:
        return (f"HingedChain(n_bodies={self.n_bodies}, root={self.root!r}, "
                f"length={self.length:.6g} m, mass={self.mass:.6g} kg)")

    # -- matrices -----------------------------------------------------------------------------
    def _matrices(self):
        """Mass, damping, stiffness matrices and tip row in the coordinates of eq. (1)."""
        return chain_matrices(self.lengths, self.masses, self.inertias, self.com_offsets,
                              self.hinge_stiffnesses, self.hinge_dampings, self.root == "hinged")

    def _check_mass_matrix(self, inertias=None, name: str = "inertias") -> None:
        """Raise ValueError when the bodies' mass matrix is singular (e.g. massless last rod)."""
        M = chain_matrices(self.lengths, self.masses,
                           self.inertias if inertias is None else inertias, self.com_offsets,
                           self.hinge_stiffnesses, self.hinge_dampings, self.root == "hinged")[0]
        keep = np.flatnonzero(np.diag(M) != 0.0)
        Mk = M[np.ix_(keep, keep)]
        d = np.sqrt(np.diag(Mk))
        scaled = Mk / np.outer(d, d)
        try:
            chol = np.linalg.cholesky(scaled)
            smallest = np.min(np.abs(np.diag(chol))) ** 2
        except np.linalg.LinAlgError:
            smallest = 0.0
        if keep.size < M.shape[0] - (self.root == "hinged") or smallest < 1e-13:
            raise ValueError(
                f"{name} and com_offsets give a singular mass matrix: some body rotation "
                "carries no inertia (e.g. a point-mass last body with com_offset 0 and "
                "inertia 0 [kg*m^2]); give it a positive inertia or com offset")

    def _root_model(self) -> RootModel:
        M, C, K, tip = self._matrices()
        if self.root == "hinged":
            names = ("delta", "phi") + tuple(f"theta_{k + 1}" for k in range(self.n_bodies))
        else:
            names = ("delta", "phi") + tuple(f"theta_{k + 1}" for k in range(1, self.n_bodies))
        return RootModel(mass=M, damping=C, stiffness=K, tip=tip, coordinate_names=names)

    # -- W(s), poles and zeros ------------------------------------------------------------------
    def W(self, s) -> np.ndarray:
        """Transfer matrix W(s) [m/N, 1/N; 1/N, 1/(N*m)] by a tip-to-root recursion.

        Body k, started at (y, theta) and carrying loads (F, M) there, applies (F_out, M_out)
        to the outboard part at its end point, which moves by ``y_e = y + l theta``. If the
        outboard part's dynamic stiffness (loads at its start for a unit motion there) is D',
        the hinge (``kappa = c + d s``) gives, with ``g = 1/(D'_22 + kappa)``,

            [F_out, M_out] = E [y_e, theta],
            E = [[D'_11 - D'_12 D'_21 g, kappa g D'_12], [kappa g D'_21, kappa g D'_22]],

        and Newton-Euler for body k (``F = m s^2 (y + a theta) + F_out``,
        ``M = J s^2 theta + a F + M_out + (l - a) F_out``) gives its own D:

            D_11 = m s^2 + E_11,            D_12 = D_21 = m a s^2 + E_12 + l E_11,
            D_22 = (J + m a^2) s^2 + E_22 + 2 l E_12 + l^2 E_11.

        From the free tip (E = 0) to the root; ``W = D_1^-1``, plus ``1/kappa_0`` on the
        rotation for a hinged root (the drive spring is in series). Every term is a product:
        nothing cancels at small |s|, where W tends to its rigid-body part ~ 1/s^2 with full
        relative accuracy (the matrix condensation of :class:`FiniteAppendage` subtracts
        stiffness-sized terms there), and the cost is O(n) per frequency.

        Parameters
        ----------
        s : complex or array_like of complex, rad/s
            Laplace variable, not 0 (the rigid-body pole).

        Returns
        -------
        ndarray of complex128, shape ``np.shape(s) + (2, 2)``

        References
        ----------
        .. [1] E. C. Pestel, F. A. Leckie, "Matrix Methods in Elastomechanics", McGraw-Hill,
           1963 (transfer-matrix / Riccati recursion along a chain).
        """
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError("s = 0 is the rigid-body pole of W (W is infinite there) [rad/s]")
        W = _bending_recursion(s, self.lengths, self.masses, self.inertias, self.com_offsets,
                               self.hinge_stiffnesses, self.hinge_dampings, self.root == "hinged")
        if not np.all(np.isfinite(W)):
            raise ValueError("s is a natural frequency of the undamped chain: W is infinite "
                             "there [rad/s]")
        return W

    # -- three axes -----------------------------------------------------------------------------
    @property
    def inertia_tensor(self) -> np.ndarray:
        """Inertia about the chain's centre of mass in chain axes [kg*m**2], undeformed.

        ``diag(sum J_x, sum (J_y + m d**2), sum (J_z + m d**2))`` (d: distance of each body's
        centre of mass from the chain's, along x; the bodies' principal axes are the chain's).
        """
        self._require_three_axis("inertia_tensor")
        d = self.body_starts + self.com_offsets - self.center_of_mass
        parallel = float(np.dot(self.masses, d * d))
        return np.diag([float(np.sum(self.torsional_inertias)),
                        float(np.sum(self.inertias_y)) + parallel,
                        float(np.sum(self.inertias)) + parallel])

    def planar_view(self, plane: str = "xy") -> "HingedChain":
        """The planar chain of one bending plane (same bodies; that plane's inertias, hinges).

        "xz" is written in the planar convention (``phi = dw/dx = -theta_y``), as
        :meth:`Beam.planar_view`.
        """
        if plane not in ("xy", "xz"):
            raise ValueError(f"plane must be 'xy' or 'xz'; got {describe(plane)}")
        if plane == "xy":
            inertias, stiffnesses, dampings = (self.inertias, self.hinge_stiffnesses,
                                               self.hinge_dampings)
        else:
            inertias, stiffnesses, dampings = (self.inertias_y, self.hinge_stiffnesses_y,
                                               self.hinge_dampings_y)
        return HingedChain(self.lengths, self.masses, inertias, stiffnesses,
                           hinge_dampings=dampings, com_offsets=self.com_offsets, root=self.root)

    def W6(self, s) -> np.ndarray:
        """Three-axis transfer matrix W6(s) [SI] by O(n) recursions, shape ``(..., 6, 6)``.

        Root motions ``(u, v, w, theta_x, theta_y, theta_z)`` per root loads
        ``(F_x, F_y, F_z, M_x, M_y, M_z)``, chain axes. The bodies' principal axes are the
        chain's and their centres of mass lie on its axis, so to first order the four motions
        decouple: each bending plane is the planar recursion of :meth:`W` with that plane's
        inertias and hinges (the x-z plane's off-diagonal with the opposite sign, as
        :meth:`Beam.W6`); torsion and axial motion are spring chains, whose recursion from
        the free tip (``D = mu_n s**2``) is, across a joint ``kappa = k + c s`` and a body of
        inertia mu (mass or J_x),

            E = kappa D'/(D' + kappa),     D = mu s**2 + E,

        ``W = 1/D_1`` (plus ``1/kappa_0`` for a hinged root); rigid joints give
        ``1/(sum mu s**2)``.

        Parameters
        ----------
        s : complex or array_like of complex, rad/s
            Not 0 (the rigid-body pole).
        """
        self._require_three_axis("W6")
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError("s = 0 is the rigid-body pole of W6 (W6 is infinite there) [rad/s]")
        hinged = self.root == "hinged"
        W6 = np.zeros(s.shape + (6, 6), dtype=np.complex128)
        W_xz = _bending_recursion(s, self.lengths, self.masses, self.inertias_y,
                                  self.com_offsets, self.hinge_stiffnesses_y,
                                  self.hinge_dampings_y, hinged)
        place_bending_planes(W6, self.W(s), W_xz)
        W6[..., 0, 0] = _spring_recursion(s, self.masses, self.axial_stiffnesses,
                                          self.axial_dampings, hinged)
        W6[..., 3, 3] = _spring_recursion(s, self.torsional_inertias, self.torsion_stiffnesses,
                                          self.torsion_dampings, hinged)
        if not np.all(np.isfinite(W6)):
            raise ValueError("s is a natural frequency of the undamped chain: W6 is infinite "
                             "there [rad/s]")
        return W6

    def _three_axis_root_model(self) -> RootModel:
        """Both planes' planar models, torsion and axial spring chains (module docstring)."""
        self._require_three_axis("a three-axis root model")
        hinged = self.root == "hinged"
        parts = [self.planar_view("xy").root_model(), self.planar_view("xz").root_model()]
        for label, inertias, springs, dampings in (
                ("theta_x", self.torsional_inertias, self.torsion_stiffnesses,
                 self.torsion_dampings),
                ("u", self.masses, self.axial_stiffnesses, self.axial_dampings)):
            M, C, K, tip = spring_chain_matrices(inertias, springs, dampings, hinged)
            start = 1 if hinged else 2  # a rigid root's first body moves with the root
            names = ("q",) + tuple(f"{label}_{start + k}" for k in range(M.shape[0] - 1))
            parts.append(RootModel(M, C, K, tip, names, n_root=1))
        return three_axis_root_model(*parts)

    def _body_pencil(self):
        """(K, M) of the bodies alone: for a hinged root, the massless mount removed and
        its spring (held mount: the W4 configuration) kept on theta_1, flagged by a third
        item, the drive stiffness to subtract for the free chain."""
        rm = self.root_model()
        if self.root == "rigid":
            return rm.stiffness, rm.mass, 0.0
        keep = np.concatenate([[0], np.arange(2, rm.n)])
        return (rm.stiffness[np.ix_(keep, keep)], rm.mass[np.ix_(keep, keep)],
                float(self.hinge_stiffnesses[0]))

    @staticmethod
    def _elastic(K: np.ndarray, M: np.ndarray, n_rigid: int) -> np.ndarray:
        """Frequencies [rad/s] of (K, M) with M positive definite, the n_rigid lowest dropped.

        A free chain has exactly two rigid-body modes (translation, rotation), a pinned one
        (delta = 0) one, one with the root rotation held one (translation): dropping them by
        count, not by a threshold, keeps the lowest elastic mode at any spread of the spectrum.
        The QZ algorithm is used: it is more accurate than a Cholesky reduction for the
        lowest modes of long chains (1e-16 vs 3e-8 relative at 400 bodies).
        """
        if K.shape[0] <= n_rigid:
            return np.zeros(0)
        lam = np.sort(scipy.linalg.eigvals(K, M).real)[n_rigid:]
        return np.sqrt(np.maximum(lam, 0.0))

    def poles(self) -> np.ndarray:
        """Undamped natural frequencies of the free chain [rad/s], ascending (n - 1 of them).

        The massless mount of a hinged root carries no load in free vibration, so a hinged
        chain has the same poles as its bodies joined rigidly to the mount.
        """
        K, M, drive = self._body_pencil()
        if drive:
            K = K.copy()
            K[1, 1] -= drive
        return self._elastic(K, M, 2)

    def zeros(self, r: int) -> np.ndarray:
        """Undamped zero frequencies of W_r [rad/s], ascending (r = 1, 2, 3, 4).

        W1: the chain pinned at the root (delta = 0); W4: root rotation held (phi = 0; for a
        hinged root the mount held, its spring acting on body 1); W2 = W3: the transmission
        zeros of :meth:`FiniteAppendage.zeros`.
        """
        if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r not in (1, 2, 3, 4):
            raise ValueError(f"r must be 1, 2, 3 or 4 (W1, W2, W3, W4); got {describe(r)}")
        if r in (2, 3):
            return super().zeros(r)
        K, M, drive = self._body_pencil()
        if r == 1:
            if drive:
                K = K.copy()
                K[1, 1] -= drive
            keep = np.arange(1, K.shape[0])
        else:
            keep = (np.arange(K.shape[0]) if drive
                    else np.concatenate([[0], np.arange(2, K.shape[0])]))
        return self._elastic(K[np.ix_(keep, keep)], M[np.ix_(keep, keep)], 1)


@contextlib.contextmanager
def _derived_from(call: str, beam):
    """Re-raise a ValueError of the chain built by a constructor as one about its arguments.

    The bodies' lengths, masses and inertias and the hinge stiffnesses are derived from the
    constructor's arguments; one out of its documented range is the arguments' fault.
    """
    try:
        yield
    except ValueError as exc:
        of = "" if beam is None else f" of {describe(beam)}"
        raise ValueError(f"{call}{of}: the chain derived from these arguments is outside the "
                         f"documented ranges: {exc}") from None


def _beam_properties(beam) -> tuple[float, float, float]:
    """(length [m], bending_stiffness [N*m^2], linear_density [kg/m]) of a beam-like object."""
    try:
        return (float(beam.length), float(beam.bending_stiffness), float(beam.linear_density))
    except AttributeError as exc:
        raise TypeError(
            "beam must be a uniform beam with length [m], bending_stiffness [N*m^2] and "
            "linear_density [kg/m], or a stepped beam (segment_properties); got "
            f"{type(beam).__name__} (finite-element modal data or a chain carry no stiffness "
            "along their length to discretise: fit a chain with "
            "appendages.equivalence.fit_chain)") from exc


def _three_axis_chain(beam) -> bool:
    """Whether :meth:`HingedChain.rfem` builds a three-axis chain: a three-axis beam whose tip
    body, if any, has its 3x3 inertia (a planar moment, a float, describes the x-y plane
    only)."""
    if not getattr(beam, "three_axis", False):
        return False
    tip = getattr(beam, "tip", None)
    return tip is None or not isinstance(tip.inertia, float) or tip.inertia == 0.0


def _stepped_segments(beam, method: str):
    """The segments (:class:`~appendages.assembly.Segment`) of a stepped beam, or None for
    a uniform beam (which has ``bending_stiffness``)."""
    if hasattr(beam, "bending_stiffness"):
        return None
    segments = getattr(beam, "segment_properties", None)
    if segments is None:
        raise TypeError(
            f"beam must be a uniform beam (length [m], bending_stiffness [N*m^2], "
            f"linear_density [kg/m]) or a stepped beam (segment_properties) for {method}; got "
            f"{type(beam).__name__} (finite-element modal data or a chain carry no stiffness "
            "along their length to discretise: fit a chain with "
            "appendages.equivalence.fit_chain)")
    if not segments:
        raise ValueError(f"{method}: the stepped beam has no segment")
    return tuple(segments)


def _overlaps(segments, a: float, b: float):
    """(segment index, start, end) of each segment's part within [a, b] [m]."""
    x = 0.0
    out = []
    for j, seg in enumerate(segments):
        lo, hi = max(a, x), min(b, x + seg.length)
        if hi > lo:
            out.append((j, lo, hi))
        x += seg.length
    return out


def _frozen_stepped_pieces(segments, edges: np.ndarray):
    """Frozen pieces of a stepped beam between consecutive ``edges`` [m].

    Each piece holds parts of one or more uniform segments (thin rods): its mass
    ``sum m_j``, its centre ``c = sum m_j c_j / sum m_j`` and its inertia about z through
    that centre ``sum m_j (l_j**2/12 + (c_j - c)**2)`` (parallel-axis theorem), and its
    torsional inertia ``sum rho I_p,j l_j`` (None where a segment has none).

    Returns
    -------
    masses [kg], com_offsets from each piece's start [m], inertias [kg*m^2], torsional
    inertias [kg*m^2] or None : ndarray
    """
    n = edges.size - 1
    masses, offsets, inertias = np.empty(n), np.empty(n), np.empty(n)
    torsional = None if segments[0].torsional_inertia is None else np.empty(n)
    for i in range(n):
        parts = _overlaps(segments, edges[i], edges[i + 1])
        l = np.array([hi - lo for _, lo, hi in parts])
        m = np.array([segments[j].linear_density for j, _, _ in parts]) * l
        centres = np.array([0.5 * (lo + hi) for _, lo, hi in parts])
        M = float(np.sum(m))
        c = float(m @ centres) / M
        masses[i], offsets[i] = M, c - edges[i]
        inertias[i] = float(np.sum(m * (l**2 / 12.0 + (centres - c) ** 2)))
        if torsional is not None:
            torsional[i] = float(sum(segments[j].torsional_inertia * (hi - lo)
                                     for j, lo, hi in parts))
    return masses, offsets, inertias, torsional


def _arc_stiffnesses(segments, arcs, attribute: str) -> np.ndarray:
    """The spring of each arc ``(a, b)`` of a stepped beam: the series flexibility of its
    parts, ``1/c = sum l_j / S_j`` with S_j the segments' ``attribute`` (EJ, EJ_y, GJ, EA):
    ``S/(b - a)`` on a uniform arc."""
    return np.array([1.0 / sum((hi - lo) / getattr(segments[j], attribute)
                               for j, lo, hi in _overlaps(segments, a, b)) for a, b in arcs])


def _with_tip(beam, lengths: np.ndarray, masses: np.ndarray, inertias: np.ndarray,
              three_axis: dict, offsets: np.ndarray | None = None):
    """The beam's tip body added to the chain's last body: (masses, inertias, com_offsets).

    The body of mass m_t and inertia J_t (about its centre, at ``l_n + offset_x`` from the last
    body's start) and the last body (m_b, J_b, centre a_b) make one rigid body: mass
    ``m_b + m_t``, centre ``a = (m_b a_b + m_t p)/(m_b + m_t)`` and inertia
    ``J_b + m_b (a_b - a)**2 + J_t + m_t (p - a)**2`` about it (parallel-axis theorem), in each
    plane; the torsional inertia gains ``J_t,xx``. A chain's bodies lie on its axis with their
    principal axes along the chain's, so a tip body off the axis or with products of inertia
    in the appendage's axes is refused by name. Without a tip body: the inputs and the
    centres ``offsets`` (default mid-length).
    """
    offsets = 0.5 * lengths if offsets is None else offsets
    tip = getattr(beam, "tip", None)
    if tip is None or tip.is_null:
        return masses, inertias, offsets
    if np.any(tip.offset[1:] != 0.0):
        raise ValueError(f"a chain's bodies lie on its axis: the tip body's offset must be along "
                         f"x to be carried by HingedChain.rfem or superelements [m]; got "
                         f"offset={tip.offset.tolist()!r}")
    three = bool(three_axis)
    J_tip = tip.inertia_tensor if three else None
    if three and np.any(J_tip != np.diag(np.diag(J_tip))):
        raise ValueError("a chain's bodies have their principal axes along the chain's: the tip "
                         "body's inertia must be diagonal in the appendage's axes to be carried "
                         f"by HingedChain.rfem [kg*m^2]; got {J_tip.tolist()!r}")
    masses, inertias, offsets = masses.copy(), inertias.copy(), offsets.copy()
    m_b, a_b, m_t = masses[-1], offsets[-1], tip.mass
    p = lengths[-1] + tip.offset[0]
    M = m_b + m_t
    a = (m_b * a_b + m_t * p) / M
    shift = m_b * (a_b - a) ** 2 + m_t * (p - a) ** 2
    masses[-1], offsets[-1] = M, a
    inertias[-1] += shift + (tip.planar_inertia if not three else J_tip[2, 2])
    if three:
        inertias_y = np.array(three_axis["inertias_y"], dtype=float)
        inertias_y[-1] += shift + J_tip[1, 1]
        three_axis["inertias_y"] = inertias_y
        torsional = np.array(three_axis["torsional_inertias"], dtype=float)
        torsional[-1] += J_tip[0, 0]
        three_axis["torsional_inertias"] = torsional
    return masses, inertias, offsets


def _three_axis_rfem(beam, lengths: np.ndarray, H: float) -> dict:
    """The three-axis parameters of an RFEM chain (:meth:`HingedChain.rfem`)."""
    n_hinges = lengths.size - 1
    _, inertias = _frozen_pieces(lengths, beam.linear_density)
    out = {"inertias_y": inertias,
           "hinge_stiffnesses_y": np.full(n_hinges, beam.bending_stiffness_y / H),
           "torsional_inertias": beam.torsional_inertia * lengths}
    out["hinge_dampings_y"] = proportional_hinge_dampings(beam.planar_view("xz"),
                                                          out["hinge_stiffnesses_y"])
    for name, rod in (("torsion", beam.torsion_rod()), ("axial", beam.axial_rod())):
        if rod is not None:
            springs = np.full(n_hinges, rod.stiffness / H)
            out[f"{name}_stiffnesses"] = springs
            zeta = rod.damping_ratio
            if zeta > 0.0:
                # with a tip body the rod's first cantilever mode is the loaded one's
                w1 = (_first_damped_frequency(rod) if beam.tip is None or beam.tip.is_null
                      else float(beam.rod_cantilever_frequencies(name, 1)[0]))
                out[f"{name}_dampings"] = 2.0 * zeta * springs / w1
    return out


def _first_damped_frequency(model) -> float:
    """The frequency at which a stiffness-proportional damping reproduces the model's ratio:
    its first cantilever frequency (the ratio of the cantilever modes, the default convention)
    or its first free-free one (``damping_convention="free-free"``)."""
    if getattr(model, "damping_convention", "cantilever") == "cantilever":
        return float(model.cantilever_frequencies(1)[0])
    return float(model.natural_frequencies(1)[0])


def proportional_hinge_dampings(beam, stiffnesses: np.ndarray) -> np.ndarray | None:
    """Hinge dampings that give a chain a beam's damping ratio, stiffness-proportionally.

    ``C = (2 zeta/w_1) K``: each mode of the chain, root clamped or free, is damped at
    ``zeta w_k/w_1``, so the mode at ``w_1`` has the beam's ratio ``zeta``; ``w_1`` is the
    beam's first cantilever frequency (the mode whose ratio ``damping_ratio`` is) or, with
    ``damping_convention="free-free"``, its first free-free one.

    Parameters
    ----------
    beam : Beam or Rod
        The model whose ``damping_ratio`` (0 if it has none) the chain takes.
    stiffnesses : ndarray, N*m/rad (N/m for an axial spring)
        The chain's hinge (or joint spring) stiffnesses.

    Returns
    -------
    ndarray or None
        The hinge dampings ``2 zeta c_h/w_1`` [N*m*s/rad, N*s/m for an axial spring], or None
        when ``zeta = 0`` (an undamped chain).
    """
    zeta = float(getattr(beam, "damping_ratio", 0.0) or 0.0)
    if zeta == 0.0:
        return None
    return 2.0 * zeta * stiffnesses / _first_damped_frequency(beam)


def chain_matrices(lengths: np.ndarray, masses: np.ndarray, inertias: np.ndarray,
                   com_offsets: np.ndarray, stiffnesses: np.ndarray, dampings: np.ndarray | None,
                   hinged: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Mass, damping and stiffness matrices of a planar chain, eq. (2) of the module docstring.

    The matrices of :class:`HingedChain` from plain arrays, without its checks: for the fits,
    which assemble many candidate chains. The arrays must be float64 and of consistent sizes
    (not checked).

    Parameters
    ----------
    lengths, masses, inertias, com_offsets : ndarray, shape (n,)
        Per body: length [m], mass [kg], moment of inertia about its centre of mass
        [kg*m**2] and centre-of-mass offset from its start [m].
    stiffnesses : ndarray, shape (n - 1,) or (n,) with ``hinged``, N*m/rad
        Hinge stiffnesses from the root outwards (a hinged root's first).
    dampings : ndarray like ``stiffnesses`` [N*m*s/rad], or None
        Hinge dampings; None: undamped.
    hinged : bool
        ``root="hinged"`` (a massless mount joined to body 1 by the first hinge).

    Returns
    -------
    M, C, K : ndarray, shape (size, size)
        In the coordinates ``q`` of the module docstring (size n + 1, n + 2 with ``hinged``).
    tip : ndarray, shape (size,)
        The row giving the elastic tip deflection ``w(L) - delta - L*phi`` [m].
    """
    n = lengths.size
    ell, m, a, J = lengths, masses, com_offsets, inertias
    # Index of body k's rotation (k = 0..n-1): 1 + k for the rigid root (theta_1 = phi),
    # 2 + k for the hinged root (index 1 is the massless mount).
    first = 2 if hinged else 1
    size = n + first
    outboard = np.concatenate([np.cumsum(m[::-1])[::-1][1:], [0.0]])  # S_k
    moment = m * a + ell * outboard                                      # P_k
    M = np.zeros((size, size))
    idx = first + np.arange(n)
    # eq. (2): M[j, k] = l_j P_k for j < k (upper triangle over the bodies), l_0 = 1.
    M[first:, first:] = np.triu(np.outer(ell, moment), k=1)
    M[0, first:] = moment
    M = M + M.T
    M[0, 0] = np.sum(m)
    M[idx, idx] = J + m * a * a + ell * ell * outboard
    # Hinge h joins coordinates (left[h], left[h] + 1): the mount (1) and body 1 (2) first
    # for a hinged root, then body k and body k+1.
    left = np.arange(1, size - 1)
    K = np.zeros((size, size))
    K[left, left] += stiffnesses
    K[left + 1, left + 1] += stiffnesses
    K[left, left + 1] -= stiffnesses
    K[left + 1, left] -= stiffnesses
    C = np.zeros((size, size))
    if dampings is not None:
        C[left, left] += dampings
        C[left + 1, left + 1] += dampings
        C[left, left + 1] -= dampings
        C[left + 1, left] -= dampings
    tip = np.zeros(size)
    tip[idx] = ell
    tip[1] -= np.sum(ell)  # w(L) - delta - L*phi, with w(L) = delta + sum l_k theta_k
    return M, C, K, tip


def _bending_recursion(s: np.ndarray, lengths, masses, inertias, com_offsets, stiffnesses,
                       dampings, hinged: bool) -> np.ndarray:
    """W(s) of a planar chain by the tip-to-root recursion of :meth:`HingedChain.W`.

    Returns shape ``s.shape + (2, 2)``, with inf/NaN entries at an undamped pole (the caller
    decides). s must be nonzero.
    """
    s2 = s * s
    kappa = stiffnesses[:, None] + dampings[:, None] * s.ravel()
    s2 = s2.ravel()
    d11 = d12 = d22 = None
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        for k in range(lengths.size - 1, -1, -1):
            m, J = masses[k], inertias[k]
            a, l = com_offsets[k], lengths[k]
            if d11 is None:
                e11 = e12 = e22 = 0.0
            else:
                kap = kappa[k + 1 if hinged else k]
                g = 1.0 / (d22 + kap)
                e11 = d11 - d12 * (d12 * g)  # grouped: no overflow of d12**2 at large |s|
                e12 = (kap * g) * d12
                e22 = (kap * g) * d22
            d11 = m * s2 + e11
            d12 = m * a * s2 + e12 + l * e11
            d22 = (J + m * a * a) * s2 + e22 + 2.0 * l * e12 + l * l * e11
        D = np.empty(s2.shape + (2, 2), dtype=np.complex128)
        D[:, 0, 0], D[:, 1, 1] = d11, d22
        D[:, 0, 1] = D[:, 1, 0] = d12
        W = inverse_2x2(D)
        if hinged:
            W[:, 1, 1] += 1.0 / kappa[0]
    return W.reshape(s.shape + (2, 2))


def _spring_recursion(s: np.ndarray, inertias, stiffnesses, dampings, hinged: bool) -> np.ndarray:
    """Root compliance of a spring chain (torsion or axial motion), shape ``s.shape``.

    ``stiffnesses`` None: rigid joints, ``1/(sum inertias s**2)``. Otherwise the recursion
    of :meth:`HingedChain.W6`; every step is a product or a sum of terms of one sign at
    small |s|, so the rigid-body part keeps full relative accuracy.
    """
    s2 = (s * s).ravel()
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        if stiffnesses is None:
            return (1.0 / (float(np.sum(inertias)) * s2)).reshape(s.shape)
        damping = np.zeros(stiffnesses.size) if dampings is None else dampings
        kappa = stiffnesses[:, None] + damping[:, None] * s.ravel()
        D = None
        for k in range(inertias.size - 1, -1, -1):
            if D is None:
                E = 0.0
            else:
                kap = kappa[k + 1 if hinged else k]
                E = kap * (D / (D + kap))
            D = inertias[k] * s2 + E
        W = 1.0 / D
        if hinged:
            W = W + 1.0 / kappa[0]
    return W.reshape(s.shape)


def spring_chain_matrices(inertias: np.ndarray, stiffnesses: np.ndarray | None,
                          dampings: np.ndarray | None, hinged: bool
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Mass, damping and stiffness matrices of a spring chain (a chain's torsion or axial motion).

    Coordinates: rigid root ``[q_1 (the root, body 1), q_2, ..., q_n]``; hinged root
    ``[q_mount (massless), q_1, ..., q_n]``; joint springs between neighbours. No checks (the
    arrays are float64 of consistent sizes), as :func:`chain_matrices`.

    Parameters
    ----------
    inertias : ndarray, shape (n,)
        Per body: moment of inertia about the chain's axis [kg*m**2] (torsion) or mass [kg]
        (axial motion).
    stiffnesses : ndarray, shape (n - 1,) or (n,) with ``hinged``, or None
        Joint springs [N*m/rad, or N/m axially] from the root outwards; None: rigid joints, one
        coordinate carrying every inertia.
    dampings : ndarray like ``stiffnesses`` [N*m*s/rad, or N*s/m], or None
        Joint dampers; None: undamped.
    hinged : bool
        A massless mount joined to body 1 by the first spring.

    Returns
    -------
    M, C, K : ndarray, shape (size, size)
        size n, n + 1 with ``hinged``, 1 with rigid joints.
    tip : ndarray, shape (size,)
        The row giving the tip's motion relative to the root, ``q_n - q_root`` [rad or m].
    """
    if stiffnesses is None:
        return (np.array([[float(np.sum(inertias))]]), np.zeros((1, 1)), np.zeros((1, 1)),
                np.zeros(1))
    n = inertias.size
    first = 1 if hinged else 0
    size = n + first
    M = np.zeros((size, size))
    M[np.arange(first, size), np.arange(first, size)] = inertias
    left = np.arange(size - 1)
    K = np.zeros((size, size))
    C = np.zeros((size, size))
    damping = np.zeros(stiffnesses.size) if dampings is None else dampings
    for A, values in ((K, stiffnesses), (C, damping)):
        A[left, left] += values
        A[left + 1, left + 1] += values
        A[left, left + 1] -= values
        A[left + 1, left] -= values
    tip = np.zeros(size)
    tip[-1] += 1.0
    tip[0] -= 1.0
    return M, C, K, tip
