r"""A beam of uniform segments carrying a tip body: the exact distributed model.

:class:`SegmentedBeam` gives everything the W-matrix interface asks of a distributed appendage
(W, W6, dynamic stiffness, mass properties, natural, cantilever and zero frequencies, modal data for
truncations) for a straight beam made of uniform Euler-Bernoulli segments with a rigid body at its
free end. Its exact root dynamics come from :mod:`appendages.assembly` (member dynamic stiffness
matrices condensed to the root, Wittrick-Williams counts, residues); its damping is the modal
damping of its cantilever modes (:mod:`appendages.damping`). :class:`appendages.Beam` uses it for a
beam with a tip body, :class:`appendages.SteppedBeam` for stepped and tapered beams.

Mass properties
---------------
About the root, appendage axes: segment i (mass m_i = rho*A_i L_i, from x_i to x_i + L_i) has its
centre at ``x_i + L_i/2`` and its own inertia ``diag(rho*I_p,i L_i, m_i L_i**2/12, m_i L_i**2/12)``
(no rotary inertia of the section in bending, as the Euler-Bernoulli model); the tip body adds its
mass at ``(L, 0, 0) + offset`` and its inertia. The totals (mass, first moment, inertia about the
centre of mass by the parallel-axis theorem) are sums of these terms.

Damping
-------
The modal damping of the cantilever modes (:class:`~appendages.damping.CantileverDamping`) sums
the exact modes of the assembly explicitly, up to the point where a bound on the rest is below
1e-9 of D (about 30 times |s|): without the closed-form asymptotic modes of a uniform member, the
rest has no exact tail. The undamped model is exact to rounding.

Zeros of W
----------
W1 vanishes at the frequencies of the beam with its root translation held (pinned), W4 with its
root rotation held (sliding): Wittrick-Williams counts with those root motions fixed. W2 = W3 =
-D12/det D vanishes where the undamped root dynamic stiffness's coupling term D12 does, between its
poles (the cantilever frequencies): sign changes on 64 points of each interval, refined by Brent's
method (two zeros closer than the sampling in one interval would be missed; the uniform beam has one
per interval).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from . import limits
from .assembly import BeamAssembly, Segment, check_segments
from .damping import CantileverDamping, check_damping_ratio
from .checks import as_frequency_array
from .errors import describe
from .interface import inverse_2x2, inverse_symmetric
from .tip import TipBody, check_tip

__all__ = ["SegmentedBeam"]


def _check_count(name: str, n) -> int:
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)):
        raise TypeError(f"{name} must be an integer (number of frequencies); got "
                        f"{type(n).__name__} {describe(n)}")
    if n < 1:
        raise ValueError(f"{name} must be a positive integer (number of frequencies); got "
                         f"{describe(n)}")
    return int(n)


#: Where each planar or rod part of a decoupled three-axis model goes: its root coordinates'
#: indices in (u, v, w, theta_x, theta_y, theta_z), their signs, and its tip row (TIP_MOTIONS).
_PARTS = {"xy": ((1, 5), (1.0, 1.0), 0), "xz": ((2, 4), (1.0, -1.0), 1),
          "torsion": ((3,), (1.0,), 2), "axial": ((0,), (1.0,), None)}


class _RodPart:
    """One rod motion (torsion or axial) of a decoupled three-axis beam: its exact assembly
    (``n_root = 1``) with the tip body's moment about the axis or its mass, and its damping."""

    def __init__(self, segments, motion: str, tip_inertia: float, zeta: float):
        tip = None if tip_inertia == 0.0 else np.array([[tip_inertia]])
        self.assembly = BeamAssembly(segments, tip, 1, rod_motion=motion)
        mu = "torsional_inertia" if motion == "torsion" else "linear_density"
        self.rigid = np.array([[sum(getattr(seg, mu) * seg.length for seg in segments)
                                + tip_inertia]])
        self.zeta = zeta
        self.damping = None if zeta == 0.0 else CantileverDamping(
            zeta, self.assembly.root_stiffness,
            lambda n: self.assembly.modes("clamped", n)[:2], self.rigid)

    def stiffness(self, s: np.ndarray) -> np.ndarray:
        """D(s), shape s.shape + (1, 1)."""
        if self.damping is None:
            return self.assembly.root_stiffness(s)
        return self.damping(s.ravel()).reshape(s.shape + (1, 1))

    def modes(self, kind: str, n: int):
        return self.assembly.modes(kind, n)

    def frequencies(self, kind: str, n: int) -> np.ndarray:
        return self.assembly.frequencies(kind, n)

    def free_free_tail(self, n: int, power: int):
        _, G, G2, G_tip = self.assembly.static_expansion()
        total, tip_total = (G, G_tip) if power == 2 else (G2, None)
        if n == 0:
            return total, tip_total
        w, b, tip = self.assembly.modes("free", n)
        scale = w**-power
        rest = total - (b.T * scale) @ b
        return rest, (None if tip_total is None else tip_total - (tip.T * scale) @ b)


def _check_tail_count(n) -> int:
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 0:
        raise ValueError(f"n must be a non-negative integer (modes kept); got {describe(n)}")
    return int(n)


class SegmentedBeam:
    """Uniform segments from the root and a tip body: the exact model (module docstring).

    Parameters
    ----------
    segments : sequence of :class:`~appendages.assembly.Segment`
        Checked by the caller; three-axis use needs every segment's torsional inertia.
    tip : TipBody or None
    damping_ratio : float
        Modal damping ratio of every cantilever mode, 0 <= zeta < 1 (checked by the caller).
    """

    def __init__(self, segments: Sequence[Segment], tip, damping_ratio: float):
        self.segment_properties = tuple(check_segments(segments))
        self.tip = check_tip(tip)
        self.damping_ratio = check_damping_ratio(damping_ratio)
        self._cache: dict = {}

    # -- structure ------------------------------------------------------------------------------
    @property
    def three_axis(self) -> bool:
        """True when every segment has the three-axis properties (a torsional inertia)."""
        return all(seg.torsional_inertia is not None for seg in self.segment_properties)

    def require_three_axis(self, what: str) -> None:
        """ValueError unless every segment has the three-axis properties (a torsional
        inertia), naming the first that has not and ``what`` needs them."""
        for k, seg in enumerate(self.segment_properties):
            if seg.torsional_inertia is None:
                raise ValueError(
                    f"{what} needs every segment's torsion: segment {k} has torsional_inertia "
                    "None [kg*m] (a planar beam); give it, or build the segments with a section "
                    "constructor (Beam.circular_rod, tube, rectangular)")

    def assembly(self, n_root: int = 2) -> BeamAssembly:
        """The exact assembly of the planar (2) or three-axis (6) model (built once)."""
        key = ("assembly", n_root)
        cached = self._cache.get(key)
        if cached is None:
            if n_root == 6:
                self.require_three_axis("a three-axis model")
            tip = None if self.tip is None else self.tip.mass_matrix(n_root)
            cached = self._cache[key] = BeamAssembly(self.segment_properties, tip, n_root)
        return cached

    def _parts(self) -> dict | None:
        """The four motions as separate exact models when the tip body couples none of them
        (no body, or one on the axis with its principal axes along the beam's): the planar
        x-y and x-z models with the body's mass and moment about z or y, the torsion and axial
        rods with its moment about x or its mass (None where the beam is rigid in that motion:
        then the rigid inertia). A three-axis evaluation then costs four planar ones (2x2 and
        1x1 pivots instead of 6x6), and each motion's modes are its own."""
        cached = self._cache.get("parts")
        if cached is not None:
            return cached or None
        self.require_three_axis("a three-axis model")
        tip = self.tip
        J = np.zeros((3, 3)) if tip is None else tip.inertia_tensor
        if tip is not None and (np.any(tip.offset[1:] != 0.0) or np.any(J != np.diag(np.diag(J)))):
            self._cache["parts"] = False
            return None
        m, offset = (0.0, 0.0) if tip is None else (tip.mass, float(tip.offset[0]))
        segs = self.segment_properties
        planar = {"bending_stiffness_y": None, "torsional_stiffness": None,
                  "torsional_inertia": None, "axial_stiffness": None}

        def plane_tip(moment):
            body = TipBody(m, float(moment), offset)
            return None if body.is_null else body

        parts = {
            "xy": SegmentedBeam([seg._replace(**planar) for seg in segs], plane_tip(J[2, 2]),
                                self.damping_ratio),
            "xz": SegmentedBeam([seg._replace(bending_stiffness=seg.bending_stiffness_y,
                                              **planar) for seg in segs],
                                plane_tip(J[1, 1]), self.damping_ratio)}
        for name, stiffness, mu, tip_inertia in (
                ("torsion", "torsional_stiffness", "torsional_inertia", J[0, 0]),
                ("axial", "axial_stiffness", "linear_density", m)):
            if getattr(segs[0], stiffness) is None:
                parts[name] = float(sum(getattr(seg, mu) * seg.length for seg in segs)
                                    + tip_inertia)
            else:
                parts[name] = _RodPart(segs, name, float(tip_inertia), self.damping_ratio)
        self._cache["parts"] = parts
        return parts

    def _part_stiffness(self, parts: dict, s: np.ndarray) -> np.ndarray:
        """D6(s) of a decoupled model from its parts (:meth:`_parts`)."""
        D6 = np.zeros(s.shape + (6, 6), dtype=np.complex128)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            for name, (index, signs, _) in _PARTS.items():
                part = parts[name]
                if isinstance(part, float):
                    D = (part * s**2)[..., None, None]
                elif isinstance(part, _RodPart):
                    D = part.stiffness(s)
                else:
                    D = part._stiffness(s, 2)
                sign = np.outer(signs, signs)
                for a, i in enumerate(index):
                    for b, j in enumerate(index):
                        D6[..., i, j] = sign[a, b] * D[..., a, b]
        return D6

    def _part_modes(self, parts: dict, kind: str, n: int):
        """The first n modes of all parts together, in three-axis form (frequencies (n,),
        root values or participation (n, 6), tip rows (n, 3)), and each part's count."""
        rows = []
        for name, (index, signs, tip_row) in _PARTS.items():
            part = parts[name]
            if isinstance(part, float):
                continue
            w, root, tip = (part.modes(kind, n) if isinstance(part, _RodPart)
                            else part.assembly(2).modes(kind, n))
            for k in range(w.size):
                rows.append((w[k], name, k, index, signs, tip_row, root[k], tip[k]))
        rows.sort(key=lambda row: row[0])
        rows = rows[:n]
        w = np.array([row[0] for row in rows])
        root6 = np.zeros((len(rows), 6))
        tip3 = np.zeros((len(rows), 3))
        counts = {name: 0 for name in _PARTS}
        for i, (_, name, _, index, signs, tip_row, root, tip) in enumerate(rows):
            root6[i, list(index)] = np.asarray(signs) * root
            if tip_row is not None:
                tip3[i, tip_row] = tip[0]
            counts[name] += 1
        return w, root6, tip3, counts

    @property
    def length(self) -> float:
        """Length L from the root to the free end [m] (the tip body's offset not included)."""
        return float(sum(seg.length for seg in self.segment_properties))

    # -- rigid properties -----------------------------------------------------------------------
    def _bodies(self, three_axis: bool):
        """(masses, centres (k, 3), own inertias (k, 3, 3)) of the segments and the tip body."""
        masses, centres, inertias = [], [], []
        x = 0.0
        for seg in self.segment_properties:
            m = seg.linear_density * seg.length
            masses.append(m)
            centres.append([x + 0.5 * seg.length, 0.0, 0.0])
            polar = (seg.torsional_inertia or 0.0) * seg.length
            inertias.append(np.diag([polar, m * seg.length**2 / 12.0, m * seg.length**2 / 12.0]))
            x += seg.length
        if self.tip is not None:
            masses.append(self.tip.mass)
            centres.append(np.array([x, 0.0, 0.0]) + self.tip.offset)
            if three_axis:
                inertias.append(self.tip.inertia_tensor)
            else:
                inertias.append(np.diag([0.0, 0.0, self.tip.planar_inertia]))
        return np.array(masses), np.array(centres, dtype=float), np.array(inertias)

    @property
    def mass(self) -> float:
        """Total mass, tip body included [kg]."""
        masses, _, _ = self._bodies(False)
        return float(math.fsum(masses))

    @property
    def first_moment(self) -> float:
        """First moment of the mass about the root along x [kg*m] (mass times centre)."""
        masses, centres, _ = self._bodies(False)
        return float(math.fsum(masses * centres[:, 0]))

    @property
    def center_of_mass_vector(self) -> np.ndarray:
        """Centre of mass from the root, appendage axes [m], shape (3,)."""
        masses, centres, _ = self._bodies(False)
        return (masses @ centres) / self.mass

    @property
    def center_of_mass(self) -> float:
        """Distance of the centre of mass from the root along x [m]."""
        return self.first_moment / self.mass

    def _inertia_about(self, three_axis: bool) -> np.ndarray:
        masses, centres, inertias = self._bodies(three_axis)
        c = (masses @ centres) / float(np.sum(masses))
        d = centres - c
        J = inertias.sum(axis=0) + np.einsum("k,kij->ij", masses,
                                             np.einsum("ki,ki->k", d, d)[:, None, None]
                                             * np.eye(3) - d[:, :, None] * d[:, None, :])
        return 0.5 * (J + J.T)

    @property
    def inertia(self) -> float:
        """Moment of inertia about z through the centre of mass, undeformed [kg*m**2]."""
        return float(self._inertia_about(False)[2, 2])

    @property
    def inertia_tensor(self) -> np.ndarray:
        """Inertia about the centre of mass in appendage axes [kg*m**2], three-axis models."""
        self.require_three_axis("inertia_tensor")
        return self._inertia_about(True)

    @property
    def rigid_mass_matrix(self) -> np.ndarray:
        """The rigid mass matrix about the root in (delta, phi) [kg, kg*m; kg*m, kg*m**2]."""
        masses, centres, _ = self._bodies(False)
        J_root = self.inertia + self.mass * float(np.sum(self.center_of_mass_vector[:2] ** 2))
        S = self.first_moment
        return np.array([[self.mass, S], [S, J_root]])

    @property
    def rigid_mass_matrix6(self) -> np.ndarray:
        """The rigid mass matrix about the root in (u, v, w, theta_x, theta_y, theta_z)."""
        self.require_three_axis("rigid_mass_matrix6")
        m, c = self.mass, self.center_of_mass_vector
        X = np.array([[0.0, -c[2], c[1]], [c[2], 0.0, -c[0]], [-c[1], c[0], 0.0]])
        M = np.zeros((6, 6))
        M[:3, :3] = m * np.eye(3)
        M[:3, 3:] = -m * X
        M[3:, :3] = m * X
        M[3:, 3:] = self.inertia_tensor + m * (float(c @ c) * np.eye(3) - np.outer(c, c))
        return 0.5 * (M + M.T)

    # -- exact root dynamics --------------------------------------------------------------------
    def _damping(self, n_root: int) -> CantileverDamping:
        key = ("damping", n_root)
        cached = self._cache.get(key)
        if cached is None:
            assembly = self.assembly(n_root)
            rigid = self.rigid_mass_matrix if n_root == 2 else self.rigid_mass_matrix6
            cached = self._cache[key] = CantileverDamping(
                self.damping_ratio, assembly.root_stiffness,
                lambda n: self.cantilever_modes(n, n_root=n_root)[:2], rigid)
        return cached

    def _stiffness(self, s: np.ndarray, n_root: int) -> np.ndarray:
        """D(s) (undamped or damped) of a checked complex array, shape s.shape + (d, d)."""
        parts = self._parts() if n_root == 6 else None
        if parts is not None:
            return self._part_stiffness(parts, s)
        if self.damping_ratio == 0.0:
            return self.assembly(n_root).root_stiffness(s)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            D = self._damping(n_root)(s.ravel())
        return D.reshape(s.shape + (n_root, n_root))

    def _compliance(self, s, n_root: int, name: str) -> np.ndarray:
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError(f"s = 0 is the rigid-body pole of {name} ({name} is infinite there) "
                             "[rad/s]")
        D = self._stiffness(s, n_root)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            W = inverse_2x2(D) if n_root == 2 else inverse_symmetric(D)
        if not np.all(np.isfinite(W)):
            raise ValueError(f"s is a natural frequency of the undamped beam: {name} is infinite "
                             "there [rad/s]")
        return W

    def W(self, s) -> np.ndarray:
        """Exact W(s) = D(s)^-1 of the free beam, shape ``np.shape(s) + (2, 2)``."""
        if self.tip is not None:
            self.tip.check_planar()
        return self._compliance(s, 2, "W")

    def dynamic_stiffness(self, s) -> np.ndarray:
        """Exact root dynamic stiffness D(s) [N/m, N; N, N*m]; s = 0 gives 0."""
        if self.tip is not None:
            self.tip.check_planar()
        return self._stiffness(as_frequency_array(s), 2)

    def W6(self, s) -> np.ndarray:
        """Exact three-axis W6(s), shape ``np.shape(s) + (6, 6)`` (root motions
        ``(u, v, w, theta_x, theta_y, theta_z)`` per root loads, appendage axes)."""
        self.require_three_axis("W6")
        return self._compliance(s, 6, "W6")

    def dynamic_stiffness6(self, s) -> np.ndarray:
        """Exact three-axis root dynamic stiffness D6(s) = W6(s)^-1; s = 0 gives 0."""
        self.require_three_axis("dynamic_stiffness6")
        return self._stiffness(as_frequency_array(s), 6)

    # -- frequencies ----------------------------------------------------------------------------
    def _frequencies(self, kind: str, n: int, n_root: int = 2) -> np.ndarray:
        n = _check_count("n", n)
        limits.check("n", n, "roots", "frequencies of a beam at once")
        return self.assembly(n_root).frequencies(kind, n).copy()

    def natural_frequencies(self, n: int) -> np.ndarray:
        """First n free-free bending frequencies of the planar (x-y) model [rad/s]."""
        if self.tip is not None:
            self.tip.check_planar()
        return self._frequencies("free", n)

    def cantilever_frequencies(self, n: int) -> np.ndarray:
        """First n frequencies with the root clamped, planar (x-y) model [rad/s]."""
        if self.tip is not None:
            self.tip.check_planar()
        return self._frequencies("clamped", n)

    def natural_frequencies6(self, n: int) -> np.ndarray:
        """First n free-free frequencies of the three-axis model, all motions [rad/s]."""
        self.require_three_axis("natural_frequencies6")
        parts = self._parts()
        if parts is not None:
            return self._part_modes(parts, "free", _check_count("n", n))[0]
        return self._frequencies("free", n, 6)

    def clamped_frequencies6(self, omega_max: float) -> np.ndarray:
        """Every frequency of the three-axis model with the root clamped up to omega_max, and
        the next one [rad/s] (the Wittrick-Williams count of a three-axis spacecraft)."""
        self.require_three_axis("clamped_frequencies6")
        parts = self._parts()
        if parts is None:
            assembly = self.assembly(6)
            n = 8
            while True:
                wc = assembly.frequencies("clamped", n)
                if wc[-1] > omega_max:
                    return wc.copy()
                n *= 2
        lists = []
        for part in parts.values():
            if isinstance(part, float):
                continue
            frequencies = (part.frequencies if isinstance(part, _RodPart)
                           else part.assembly(2).frequencies)
            n = 8
            while True:
                wc = frequencies("clamped", n)
                if wc[-1] > omega_max:
                    break
                n *= 2
            lists.append(wc)
        complete = min(wc[-1] for wc in lists)
        merged = np.sort(np.concatenate(lists))
        return merged[merged <= complete]

    def rod_cantilever_frequencies(self, motion: str, n: int) -> np.ndarray:
        """First n frequencies of the beam's torsion or axial motion alone with the root
        clamped [rad/s]: the exact stepped rod with the tip body's moment about the axis
        (about its centre plus ``m (r_y**2 + r_z**2)``) or its mass at the free end.

        Parameters
        ----------
        motion : {"torsion", "axial"}
        n : int
            At least 1.

        Returns
        -------
        ndarray, shape (n,), rad/s
            Empty when the beam is rigid in that motion (no ``torsional_stiffness`` or
            ``axial_stiffness``).
        """
        if motion not in ("torsion", "axial"):
            raise ValueError(f"motion must be 'torsion' or 'axial'; got {describe(motion)}")
        n = _check_count("n", n)
        self.require_three_axis(f"rod_cantilever_frequencies({motion!r})")
        stiffness = "torsional_stiffness" if motion == "torsion" else "axial_stiffness"
        if getattr(self.segment_properties[0], stiffness) is None:
            return np.zeros(0)
        key = ("rod", motion)
        assembly = self._cache.get(key)
        if assembly is None:
            tip = self.tip
            if tip is None:
                body = 0.0
            elif motion == "axial":
                body = tip.mass
            else:
                r = tip.offset
                body = float(tip.inertia_tensor[0, 0]) + tip.mass * float(r[1]**2 + r[2]**2)
            assembly = self._cache[key] = BeamAssembly(
                self.segment_properties, None if body == 0.0 else np.array([[body]]), 1,
                rod_motion=motion)
        return assembly.frequencies("clamped", n).copy()

    def zeros(self, r: int, n: int = 2) -> np.ndarray:
        """First n zero frequencies of the exact W_r [rad/s] (r = 1, 2, 3, 4; module
        docstring)."""
        if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r not in (1, 2, 3, 4):
            raise ValueError(f"r must be 1, 2, 3 or 4 (W1, W2, W3, W4); got {describe(r)}")
        if self.tip is not None:
            self.tip.check_planar()
        n = _check_count("n", n)
        if r == 1:
            return self._frequencies("pinned", n)
        if r == 4:
            return self._frequencies("sliding", n)
        return self._coupling_zeros(n)

    def _coupling_zeros(self, n: int) -> np.ndarray:
        cached = self._cache.get("w2")
        if cached is not None and cached.size >= n:
            return cached[:n].copy()
        assembly = self.assembly(2)

        def d12(w):
            return assembly.root_stiffness(1j * np.asarray(w, dtype=float))[..., 0, 1].real

        m = max(n, 8)
        while True:
            poles = assembly.frequencies("clamped", m + 1)
            edges = np.concatenate([[0.0], poles])
            # 64 points inside each interval between poles, denser towards the ends
            t = 0.5 * (1.0 - np.cos(math.pi * (np.arange(64) + 0.5) / 64))
            grid = edges[:-1, None] + (edges[1:] - edges[:-1])[:, None] * t[None, :]
            values = d12(grid)
            change = np.sign(values[:, :-1]) * np.sign(values[:, 1:]) < 0
            rows, cols = np.nonzero(change)
            if rows.size >= n or m > 4 * n + 64:
                break
            m *= 2
        lo, hi = grid[rows, cols], grid[rows, cols + 1]
        f_lo = values[rows, cols]
        for _ in range(200):  # bisection of every bracket at once, to the last bit
            active = (hi - lo) > 2.0 * np.finfo(float).eps * hi
            if not np.any(active):
                break
            mid = 0.5 * (lo + hi)
            f_mid = d12(mid)
            left = np.sign(f_mid) == np.sign(f_lo)
            lo = np.where(left, mid, lo)
            f_lo = np.where(left, f_mid, f_lo)
            hi = np.where(left, hi, mid)
        result = np.sort(0.5 * (lo + hi))
        self._cache["w2"] = result
        return result[:n].copy()

    # -- modal data for truncations -------------------------------------------------------------
    def _modes(self, kind: str, n: int, n_root: int):
        n = _check_count("n", n)
        parts = self._parts() if n_root == 6 else None
        if parts is not None:
            return self._part_modes(parts, kind, n)[:3]
        return self.assembly(n_root).modes(kind, n)

    def free_free_modes(self, n: int, *, n_root: int = 2):
        """(frequencies (n,) [rad/s], root values b_k (n, d), tip values (n, rows)) of the
        first n free-free modes, mass-normalised (:meth:`BeamAssembly.modes`)."""
        return self._modes("free", n, n_root)

    def cantilever_modes(self, n: int, *, n_root: int = 2):
        """(frequencies (n,) [rad/s], participation factors l_k (n, d), tip values (n, rows))
        of the first n cantilever modes."""
        return self._modes("clamped", n, n_root)

    def cantilever_participation_tail(self, n: int, *, n_root: int = 2) -> np.ndarray:
        """``sum_{k>n} l_k l_k^T = M_rr - sum_{k<=n} l_k l_k^T`` (d, d): the rigid mass the first
        n cantilever modes leave to the others (its rounding is eps M_rr, small against D)."""
        M = self.rigid_mass_matrix if n_root == 2 else self.rigid_mass_matrix6
        if _check_tail_count(n) == 0:
            return M.copy()
        _, l, _ = self.cantilever_modes(n, n_root=n_root)
        rest = M - l.T @ l
        return 0.5 * (rest + rest.T)

    def free_free_tail(self, n: int, power: int, *, n_root: int = 2):
        """``(sum_{k>n} b b^T/w**power, sum_{k>n} phi_tip b^T/w**power)`` for power 2 and 4:
        the static expansion's G and G2 minus the kept modes' (:mod:`appendages.assembly`)."""
        _check_tail_count(n)
        if isinstance(power, (bool, np.bool_)) or power not in (2, 4):
            raise ValueError(f"power must be 2 or 4 for a non-uniform beam; got {describe(power)}")
        parts = self._parts() if n_root == 6 else None
        if parts is not None:
            return self._part_tail(parts, n, power)
        _, G, G2, G_tip = self.assembly(n_root).static_expansion()
        total = G if power == 2 else G2
        tip_total = G_tip if power == 2 else None
        if n == 0:
            return total.copy(), (None if tip_total is None else tip_total.copy())
        w, b, tip = self.free_free_modes(n, n_root=n_root)
        scale = w**-power
        rest = total - (b.T * scale) @ b
        tip_rest = None if tip_total is None else tip_total - (tip.T * scale) @ b
        return 0.5 * (rest + rest.T), tip_rest

    def _part_tail(self, parts: dict, n: int, power: int):
        """:meth:`free_free_tail` of a decoupled three-axis model: each part's tail beyond its
        own modes among the first n, placed in (6, 6) and the tip rows (3, 6)."""
        counts = self._part_modes(parts, "free", n)[3] if n else {name: 0 for name in _PARTS}
        rest = np.zeros((6, 6))
        tip_rest = np.zeros((3, 6)) if power == 2 else None
        for name, (index, signs, tip_row) in _PARTS.items():
            part = parts[name]
            if isinstance(part, float):
                continue
            R, R_tip = part.free_free_tail(counts[name], power)
            sign = np.asarray(signs)
            rest[np.ix_(index, index)] = np.outer(sign, sign) * R
            if tip_rest is not None and tip_row is not None:
                tip_rest[tip_row, list(index)] = np.asarray(R_tip)[0] * sign
        return rest, tip_rest
