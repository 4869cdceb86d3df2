r"""An appendage given by finite-element modal data: its cantilever modes seen from the root.

A structures team describes an appendage by the modes of its finite-element model with the
attachment point (the *root*) clamped: the frequencies w_i [rad/s], the damping ratios zeta_i
of those modes, the participation factors of the modes at the root and the rigid mass
properties about the root. :class:`ModalAppendage` turns these into the W-matrix interface.

Data
----
Let u be the model's nodal displacements, M and K its mass and stiffness, D the rigid motion
of every degree of freedom for a unit motion of the root (K D = 0) and Phi the cantilever modes,
mass-normalised (``Phi^T M Phi = I``, ``Phi^T K Phi = Omega**2 = diag(w_i**2)``). Then

* ``rigid_mass = D^T M D`` (r x r), the rigid mass matrix about the root point;
* ``participation = G = Phi^T M D`` (n x r), row i the participation factors of mode i.

Planar (r = 2): the root motions are ``(delta, phi)``, translation along the appendage's y axis
[m] and rotation about z [rad], so ``rigid_mass = [[m, S], [S, I_root]]`` with the first moment
``S = m x_c`` [kg*m] and the moment of inertia about the root ``I_root`` [kg*m**2]; G has the
units ``[sqrt(kg), sqrt(kg)*m]``. Three axes (r = 6): ``(u, v, w, theta_x, theta_y, theta_z)``
in the appendage's axes at the root point (x along the appendage), so
``rigid_mass = [[m I, -m [c]x], [m [c]x, I_root]]`` with c the centre of mass from the root
and ``[c]x`` its cross-product matrix; the planar data are its rows and columns (1, 5).

The root's dynamic mass
-----------------------
With ``u = D q_r + Phi eta`` (q_r the root motions, eta the modal coordinates: the
Craig-Bampton coordinates [1]_), the kinetic energy is
``1/2 (q_r'^T M_rr q_r' + 2 eta'^T G q_r' + eta'^T eta')`` (``M_rr = rigid_mass``) and the strain
energy ``1/2 eta^T Omega**2 eta`` (the cross terms vanish since K D = 0); each mode is damped
by ``2 zeta_i w_i eta_i'``. The root loads f (``F_y``, ``M``, or the six loads) do work on q_r
only (the cantilever modes vanish at the root), so Lagrange's equations are

    M_rr q_r'' + G^T eta''                                   = f
    G q_r''    + eta'' + diag(2 zeta_i w_i) eta' + Omega**2 eta = 0.

In Laplace form (zero initial state) the second row gives
``eta_i = -s**2 G_i q_r/(s**2 + 2 zeta_i w_i s + w_i**2)`` (G_i the i-th row), and the first

    f = s**2 M(s) q_r,   M(s) = M_rr - sum_i G_i^T G_i s**2/(s**2 + 2 zeta_i w_i s + w_i**2).

The minus sign: as s passes w_i, mode i's mass stops following the root (its modal
coordinate moves against it), so the root sees less mass; ``M(0) = M_rr`` (the whole rigid
mass: the rigid-body motion, exact) and ``M(inf) = M_rr - G^T G``, the *residual mass* (the
mass that no kept mode carries, which moves rigidly with the root). W of the free appendage is
the inverse, ``W(s) = (s**2 M(s))^-1``: its 1/s**2 part is ``M_rr^-1`` exactly. It is evaluated
in the form

    M(s) = M_res + sum_i G_i^T G_i (2 zeta_i w_i s + w_i**2)/(s**2 + 2 zeta_i w_i s + w_i**2),

(:class:`~appendages.modal.ModalStiffness`, shared with the beams' Craig-Bampton truncations),
a sum that tends to M_res at large |s| and to M_rr at small |s| without cancellation; the
residual ``M_res = M_rr - G^T G`` is formed once, and carries the data's own precision: when the
kept modes hold all but a fraction f of the mass in some direction, M_res there has about
``eps/f`` relative error (it matters only above the last mode, where the truncation error is
of order one anyway). The modal effective masses are the diagonal entries ``G_ik**2`` [kg for
translations, kg*m**2 about the root for rotations]; summed over all the modes of a model whose
every degree of freedom carries mass they give ``diag(M_rr)``.

The realisation for truncated use (:meth:`ModalAppendage.root_model`) is the Craig-Bampton
model of these equations (:func:`~appendages.modal.fixed_root_model`), the form in which the
beams' truncations couple to a hub too.

References
----------
.. [1] R. R. Craig, M. C. C. Bampton, "Coupling of substructures for dynamic analyses", AIAA J.
   6(7), 1968.
.. [2] R. R. Craig, A. J. Kurdila, "Fundamentals of Structural Dynamics", 2nd ed., Wiley, 2006,
   ch. 17 (component-mode synthesis) and sec. 11.4 (modal effective mass).
.. [3] P. W. Likins, "Dynamics and control of flexible space vehicles", JPL TR 32-1329, 1970
   (cantilever modes of appendages in hybrid coordinates).
.. [4] MSC Nastran Dynamic Analysis User's Guide, "Modal effective mass" (MEFFMASS): the
   participation factors and effective masses that a finite-element solver prints.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Sequence

import numpy as np
import scipy.linalg

from . import limits
from .checks import as_frequency_array, check_range
from .errors import describe
from .interface import (ROOT_LOADS, ROOT_MOTIONS, FiniteAppendage, RootModel, equilibrate,
                        inverse_2x2, inverse_symmetric)
from .modal import ModalStiffness, fixed_root_model
from .unit_slips import damping_in_percent, warn_unit_slip

__all__ = ["ModalAppendage", "NEGLIGIBLE_FRACTION", "PLANES", "RESIDUAL_TOLERANCE"]

#: Planes of a three-axis appendage and their root coordinates in the planar convention:
#: (rows/columns of the 6x6 data, signs). The x-z plane's rotation is ``dw/dx = -theta_y``.
PLANES = {"xy": ((1, 5), (1.0, 1.0)), "xz": ((2, 4), (1.0, -1.0))}

#: Largest negative eigenvalue of the residual mass, scaled to unit diagonal by the rigid mass
#: (``d_i = 1/sqrt(M_rr,ii)``), that is taken for round-off of the data and set to zero: the
#: 6 to 8 digits that finite-element output files print leave ~1e-7 in a residual that a
#: complete set of modes makes zero.
RESIDUAL_TOLERANCE = 1e-6

#: Effective-mass fraction below which a mode is taken as not seen by a motion (a planar view):
#: the cross-talk that round-off leaves in a decoupled model's data is far below it (1e-28 and
#: less in tests/data/nastran's beam_modes), and a mode coupled that weakly makes a pole-zero
#: pair that W does not show.
NEGLIGIBLE_FRACTION = 1e-12

# Modes whose frequencies agree to this (relative) are one degenerate group (a round boom's two
# bending planes): a solver prints them equal, or mixes them.
_DEGENERATE_RTOL = 1e-9

# Relative tolerance of the structure checks of the rigid mass matrix (symmetry; in three axes
# the isotropic mass and skew first-moment blocks): printed data carry 6 to 8 digits.
_STRUCTURE_RTOL = 1e-6


def _real_array(name: str, value, unit: str, *, ndim: int) -> np.ndarray:
    """``value`` as a finite float64 array with ``ndim`` dimensions, or TypeError/ValueError."""
    if isinstance(value, (str, bytes)) or value is None:
        raise TypeError(f"{name} must be an array of real numbers [{unit}]; got "
                        f"{type(value).__name__}")
    try:
        arr = np.asarray(value)
    except (ValueError, TypeError) as exc:  # ragged nesting
        raise ValueError(f"{name} must be a rectangular array of real numbers [{unit}]; got "
                         f"{describe(value)}") from exc
    if arr.dtype == bool or arr.dtype.kind not in "iuf":
        raise TypeError(f"{name} must contain real numbers [{unit}]; got dtype {arr.dtype}")
    if arr.ndim != ndim:
        raise ValueError(f"{name} must be a {ndim}-D array [{unit}]; got shape {arr.shape}")
    with np.errstate(over="ignore"):
        arr = arr.astype(np.float64)
    bad = ~np.isfinite(arr)
    if np.any(bad):
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"{name} must be finite [{unit}]; got {arr[index]!r} at index "
                         f"{index if ndim > 1 else index[0]}")
    return arr


def _read_only(arr: np.ndarray) -> np.ndarray:
    arr = np.array(arr, dtype=np.float64)
    arr.flags.writeable = False
    return arr


def _cross(c: np.ndarray) -> np.ndarray:
    """The cross-product matrix [c]x (``[c]x v = c x v``)."""
    return np.array([[0.0, -c[2], c[1]], [c[2], 0.0, -c[0]], [-c[1], c[0], 0.0]])


def _check_frequencies(frequencies) -> np.ndarray:
    w = _real_array("frequencies", frequencies, "rad/s", ndim=1)
    if w.size < 1:
        raise ValueError("frequencies must hold at least one cantilever mode [rad/s]; got none")
    limits.check("frequencies (number of modes)", int(w.size), "modes",
                 "modes of a modal appendage")
    low, high = 1e-12, 1e12
    bad = (w <= 0.0) | (w < low) | (w > high)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"frequencies must be positive, within [{low:g}, {high:g}] [rad/s] (cantilever "
            f"modes: a clamped root leaves no rigid-body mode); got {w[k]!r} at index {k}")
    down = np.flatnonzero(np.diff(w) < 0.0)
    if down.size:
        k = int(down[0])
        raise ValueError(
            f"frequencies must be non-decreasing [rad/s] (the cantilever modes in ascending "
            f"order, participation rows in the same order); got {w[k + 1]!r} at index "
            f"{k + 1} after {w[k]!r} at index {k}")
    return w


def _check_damping(damping, n: int) -> np.ndarray:
    if isinstance(damping, (bool, np.bool_)):
        raise TypeError(f"damping must be a real number or one per mode (damping ratio) [-]; "
                        f"got {damping!r}")
    if np.ndim(damping) == 0:
        if not isinstance(damping, (int, float, np.integer, np.floating)):
            raise TypeError(f"damping must be a real number or one per mode (damping ratio) "
                            f"[-]; got {type(damping).__name__} {describe(damping)}")
        zeta = np.full(n, float(damping))
    else:
        zeta = _real_array("damping", damping, "-", ndim=1)
        if zeta.size != n:
            raise ValueError(f"damping must be one ratio or one per mode ({n}) [-]; got "
                             f"{zeta.size} values")
    bad = ~np.isfinite(zeta) | (zeta < 0.0) | (zeta >= 1.0)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"damping must lie in [0, 1) (modal damping ratio of each cantilever "
                         f"mode) [-]; got {zeta[k]!r}" + (f" at index {k}" if np.ndim(damping)
                                                           else ""))
    largest = float(zeta.max(initial=0.0))
    warn_unit_slip("damping" if np.ndim(damping) == 0 else "max(damping)", largest, "",
                   damping_in_percent(largest), stacklevel=4)
    return zeta


@dataclasses.dataclass(frozen=True)
class _RigidProperties:
    mass: float
    center: np.ndarray      # (3,) from the root, appendage axes [m]
    inertia: np.ndarray     # (3, 3) about the centre of mass [kg*m^2]


def _check_rigid_mass(rigid_mass) -> tuple[np.ndarray, _RigidProperties]:
    """The symmetrised rigid mass matrix and its mass, centre and central inertia."""
    M = _real_array("rigid_mass", rigid_mass, "kg, kg*m, kg*m^2", ndim=2)
    if M.shape not in ((2, 2), (6, 6)):
        raise ValueError(f"rigid_mass must be 2x2 (planar: y, rotation z) or 6x6 (x, y, z, "
                         f"rotations about x, y, z) [kg, kg*m, kg*m^2]; got shape {M.shape}")
    r = M.shape[0]
    m = float(M[0, 0]) if r == 2 else float(np.trace(M[:3, :3]) / 3.0)
    if not m > 0.0:
        what = "rigid_mass[0, 0]" if r == 2 else "the mass (trace(rigid_mass[:3, :3])/3)"
        raise ValueError(f"{what} must be positive [kg] (the appendage's mass); got {m!r}")
    check_range("the mass of rigid_mass", m, "mass")
    diag = np.abs(np.diag(M))
    scale = np.sqrt(np.outer(diag, diag))
    asym = np.abs(M - M.T) > _STRUCTURE_RTOL * np.maximum(scale, 1e-300)
    if np.any(asym):
        i, j = (int(v) for v in np.argwhere(asym)[0])
        raise ValueError(f"rigid_mass must be symmetric [kg, kg*m, kg*m^2] (D^T M D); got "
                         f"rigid_mass[{i}, {j}] = {M[i, j]!r} and rigid_mass[{j}, {i}] = "
                         f"{M[j, i]!r}")
    M = 0.5 * (M + M.T)
    if r == 2:
        x_c = M[0, 1] / m
        center = np.array([x_c, 0.0, 0.0])
        J = M[1, 1] - m * x_c**2
        inertia = np.diag([0.0, 0.0, J])  # planar: only about z is known
        central = np.array([J])
        about = "about z through the centre of mass, rigid_mass[1, 1] - rigid_mass[0, 1]**2/m"
    else:
        A, B = M[:3, :3], M[:3, 3:]
        if np.max(np.abs(A - m * np.eye(3))) > _STRUCTURE_RTOL * m:
            raise ValueError(
                f"rigid_mass[:3, :3] must be m*I [kg] (the same mass in every direction, as for "
                f"rigid motion of a body); got diagonal {describe(np.diag(A).tolist())}")
        first_moment = float(np.max(np.abs(B)))
        length_scale = math.sqrt(max(np.max(np.diag(M[3:, 3:])), 0.0) / m)
        if np.max(np.abs(B + B.T)) > _STRUCTURE_RTOL * max(first_moment, m * length_scale,
                                                           1e-300):
            raise ValueError(
                "rigid_mass[:3, 3:] must be -m [c]x [kg*m] (skew-symmetric: the first moment "
                f"of a body with centre of mass c); got {describe(B.tolist())}")
        B = 0.5 * (B - B.T)
        center = -np.array([B[2, 1], B[0, 2], B[1, 0]]) / m  # B = -m [c]x
        inertia = M[3:, 3:] - m * (float(center @ center) * np.eye(3) - np.outer(center, center))
        inertia = 0.5 * (inertia + inertia.T)
        central = scipy.linalg.eigvalsh(inertia)
        M = M.copy()
        M[:3, :3] = m * np.eye(3)
        M[:3, 3:] = B
        M[3:, :3] = B.T
        about = "about the centre of mass, rigid_mass[3:, 3:] - m (|c|^2 I - c c^T)"
    tol = 1e-12 * max(np.max(np.abs(M[-1, -1])), 1e-300)
    if np.min(central) < -tol:
        raise ValueError(
            f"the rigid inertia {about}, must be positive semi-definite [kg*m^2]; got "
            f"eigenvalue(s) {describe(np.round(central, 15).tolist())}: check that rigid_mass "
            "is about the root point, in the appendage's axes")
    if np.min(central) <= tol:
        raise ValueError(
            f"the rigid inertia {about}, is singular [kg*m^2] (eigenvalues "
            f"{describe(central.tolist())}): a root moment would meet no inertia; give the "
            "appendage's rotary (e.g. torsional) inertia")
    return M, _RigidProperties(m, center, inertia)


def _check_participation(participation, n: int, r: int) -> np.ndarray:
    G = _real_array("participation", participation, "sqrt(kg), sqrt(kg)*m", ndim=2)
    if G.shape != (n, r):
        raise ValueError(f"participation must have one row per mode and one column per root "
                         f"motion, shape ({n}, {r}) [sqrt(kg), sqrt(kg)*m]; got shape {G.shape}")
    return G


def _residual_mass(M_rr: np.ndarray, G: np.ndarray, tolerance: float) -> np.ndarray:
    """``M_rr - G^T G``, checked positive semi-definite (round-off set to zero)."""
    residual = M_rr - G.T @ G
    residual = 0.5 * (residual + residual.T)
    d = 1.0 / np.sqrt(np.diag(M_rr))
    lam, V = scipy.linalg.eigh(residual * np.outer(d, d))
    if lam[0] < -tolerance:
        direction = V[:, 0] / d
        direction /= np.max(np.abs(direction))
        labels = ("delta", "phi") if M_rr.shape[0] == 2 else ROOT_MOTIONS
        worst = labels[int(np.argmax(np.abs(direction)))]
        fractions = np.sum(G**2, axis=0) / np.diag(M_rr)
        raise ValueError(
            f"participation: the modes' effective masses exceed the rigid mass (the residual "
            f"mass rigid_mass - participation^T participation is not positive semi-definite: "
            f"eigenvalue {lam[0]:.3g} of rigid_mass scaled to unit diagonal, mostly in "
            f"{worst}; effective-mass fractions {describe(np.round(fractions, 6).tolist())}). "
            f"Expected participation factors of mass-normalised modes [sqrt(kg), sqrt(kg)*m] "
            f"and rigid_mass about the root in the same units and axes")
    if lam[0] < 0.0:
        lam = np.maximum(lam, 0.0)
        residual = (V * lam) @ V.T / np.outer(d, d)
        residual = 0.5 * (residual + residual.T)
    return residual


class ModalAppendage(FiniteAppendage):
    r"""An appendage given by the cantilever modes of a finite-element model (module docstring).

    Parameters
    ----------
    frequencies : array_like, shape (n,), rad/s
        Natural frequencies of the modes with the root clamped, non-decreasing (repeated
        frequencies, e.g. the two bending planes of a round boom, are allowed).
    participation : array_like, shape (n, 2) or (n, 6)
        Participation factors ``G = Phi^T M D`` of the mass-normalised modes at the root
        [sqrt(kg) for translations, sqrt(kg)*m for rotations]: planar (n, 2), translation y
        and rotation about z; three axes (n, 6), translations x, y, z then rotations about x,
        y, z, in the appendage's axes at the root point (x along the appendage).
    rigid_mass : array_like, shape (2, 2) or (6, 6)
        Rigid mass matrix about the root ``D^T M D`` in the same coordinates [kg, kg*m,
        kg*m^2]: planar ``[[m, m x_c], [m x_c, I_root]]``; three axes
        ``[[m I, -m [c]x], [m [c]x, I_root]]``.
    damping : float or array_like, shape (n,)
        Modal damping ratio of the cantilever modes [-], one for all or one per mode, in
        [0, 1) (a :class:`~appendages.unit_slips.UnitWarning` above 0.2: a percentage
        entered as a ratio?).
    length : float, m, optional
        The appendage's extent along x from the root (the paper's L): needed by the chain fits
        and the equivalence table, and by a spacecraft's tip outputs.
    tip_motion : array_like, shape (n,) or (n, 3), optional
        Each mode's elastic motion of the free end [m/sqrt(kg), rad/sqrt(kg)] (relative to the
        rigidly moving root): planar the deflection along y; three axes the deflections along
        y and z and the twist (:data:`~appendages.interface.TIP_MOTIONS`). Without it the tip
        outputs of the realisation are zero (:attr:`has_tip_motion` False).

    Raises
    ------
    TypeError
        Arguments that are not arrays of real numbers.
    ValueError
        Non-finite values; frequencies not positive or decreasing; shapes that do not match;
        a rigid mass that is not symmetric, has a non-positive mass or (three axes) is not
        ``[[m I, -m [c]x], [m [c]x, I]]``; an inertia about the centre of mass that is not
        positive definite; participation factors whose effective masses exceed the rigid mass
        (a residual mass with an eigenvalue below ``-RESIDUAL_TOLERANCE`` of the rigid mass
        scaled to unit diagonal; smaller negative ones are round-off and set to zero); a
        damping ratio outside [0, 1); more modes than the ``modes`` limit of
        :mod:`appendages.limits` (1000).

    Notes
    -----
    The planar interface of a three-axis appendage (:meth:`W`, ``root_model()``, the poles
    and zeros) is its x-y plane with the root's other motions held (:meth:`planar_view`):
    what a planar spacecraft, which moves only in its plane, imposes on it. For a straight
    appendage whose section is symmetric the motions are uncoupled and this is exact.

    :attr:`center_of_mass` is the centre's coordinate along x and
    :attr:`center_of_mass_vector` the centre itself (off the axis where the rigid mass matrix
    puts it there); a spacecraft's rigid properties (``Spacecraft.center_of_mass``,
    ``inertia``) and its three-axis dynamics use both exactly. A planar spacecraft moves the
    root's axial motion rigidly, without the coupling to rotation that a centre off the axis
    in the plane brings: it warns of such an appendage.

    References
    ----------
    See the module docstring.
    """

    def __init__(self, frequencies: Sequence[float], participation, rigid_mass, *,
                 damping: float | Sequence[float] = 0.0, length: float | None = None,
                 tip_motion=None) -> None:
        w = _check_frequencies(frequencies)
        n = w.size
        M_rr, rigid = _check_rigid_mass(rigid_mass)
        r = M_rr.shape[0]
        G = _check_participation(participation, n, r)
        zeta = _check_damping(damping, n)
        self._length = None if length is None else check_range("length", length, "length")
        if tip_motion is None:
            tip = None
        else:
            tip = _real_array("tip_motion", tip_motion, "m/sqrt(kg), rad/sqrt(kg)",
                              ndim=1 if r == 2 else 2)
            expected = (n,) if r == 2 else (n, 3)
            if tip.shape != expected:
                raise ValueError(f"tip_motion must have shape {expected} (one row per mode) "
                                 f"[m/sqrt(kg), rad/sqrt(kg)]; got {tip.shape}")
        residual = _residual_mass(M_rr, G, RESIDUAL_TOLERANCE)
        self._frequencies = _read_only(w)
        self._participation = _read_only(G)
        self._rigid_mass = _read_only(M_rr)
        self._damping = _read_only(zeta)
        self._residual = _read_only(residual)
        self._tip = None if tip is None else _read_only(tip)
        self._rigid = rigid
        if self._length is not None and not 0.0 <= rigid.center[0] <= self._length:
            warnings.warn(
                f"the centre of mass lies at x = {rigid.center[0]:.6g} m, outside [0, length = "
                f"{self._length:.6g} m]: length in other units than rigid_mass, or rigid_mass "
                "not about the root?", UserWarning, stacklevel=2)
        self._cache: dict = {}

    # -- the data -------------------------------------------------------------------------------
    def __repr__(self) -> str:
        kind = "planar" if self.n_root == 2 else "three-axis"
        return (f"ModalAppendage({self.n_modes} {kind} modes, {self._frequencies[0]:.6g} to "
                f"{self._frequencies[-1]:.6g} rad/s, mass {self.mass:.6g} kg)")

    @property
    def n_modes(self) -> int:
        """Number of cantilever modes."""
        return int(self._frequencies.size)

    @property
    def n_root(self) -> int:
        """Root motions of the data: 2 (planar) or 6 (three axes)."""
        return int(self._rigid_mass.shape[0])

    @property
    def three_axis(self) -> bool:
        """True when the data are three-axis (6 root motions)."""
        return self.n_root == 6

    @property
    def frequencies(self) -> np.ndarray:
        """Cantilever frequencies w_i [rad/s] (read-only)."""
        return self._frequencies

    @property
    def participation(self) -> np.ndarray:
        """Participation factors G (n, 2) or (n, 6) [sqrt(kg), sqrt(kg)*m] (read-only)."""
        return self._participation

    @property
    def rigid_mass(self) -> np.ndarray:
        """Rigid mass matrix about the root [kg, kg*m, kg*m^2] (symmetrised, read-only)."""
        return self._rigid_mass

    @property
    def damping_ratios(self) -> np.ndarray:
        """Damping ratio of each cantilever mode [-] (read-only)."""
        return self._damping

    @property
    def residual_mass(self) -> np.ndarray:
        """``rigid_mass - G^T G`` [kg, kg*m, kg*m^2]: the mass that no kept mode carries."""
        return self._residual

    @property
    def effective_masses(self) -> np.ndarray:
        """Modal effective masses ``G_ik**2``, shape (n, 2) or (n, 6) [kg; kg*m^2 about the
        root for rotations]."""
        return self._participation**2

    @property
    def effective_mass_fractions(self) -> np.ndarray:
        """:attr:`effective_masses` over the rigid mass's diagonal [-], shape (n, r)."""
        return self._participation**2 / np.diag(self._rigid_mass)

    @property
    def tip_motion(self) -> np.ndarray | None:
        """Each mode's elastic tip motion (n,) or (n, 3), or None when not given."""
        return self._tip

    @property
    def has_tip_motion(self) -> bool:
        """Whether the realisation's tip rows are data (True) or zeros (False)."""
        return self._tip is not None

    # -- rigid properties -----------------------------------------------------------------------
    @property
    def length(self) -> float:
        """Extent along x from the root [m] (the ``length`` given).

        Raises
        ------
        ValueError
            When it was not given: a spacecraft (its tip rows), the equivalence table and the
            chain fits need it.
        """
        if self._length is None:
            raise ValueError("this ModalAppendage has no length [m] (its extent along x from "
                             "the root): give ModalAppendage(..., length=...) to mount it on a "
                             "spacecraft or fit a chain to it")
        return self._length

    @property
    def mass(self) -> float:
        """Mass [kg]."""
        return self._rigid.mass

    @property
    def center_of_mass(self) -> float:
        """Distance of the centre of mass from the root along x [m]."""
        return float(self._rigid.center[0])

    @property
    def center_of_mass_vector(self) -> np.ndarray:
        """Centre of mass from the root in appendage axes [m], shape (3,) (planar: (x_c, 0, 0))."""
        return self._rigid.center.copy()

    @property
    def inertia(self) -> float:
        """Moment of inertia about z through the centre of mass [kg*m^2] (the planar one)."""
        return float(self._rigid.inertia[2, 2])

    @property
    def inertia_tensor(self) -> np.ndarray:
        """Inertia about the centre of mass in appendage axes [kg*m^2], 3x3 (three axes)."""
        self._require_three_axis("inertia_tensor")
        return self._rigid.inertia.copy()

    def _require_three_axis(self, what: str) -> None:
        if not self.three_axis:
            raise ValueError(
                f"{what} needs three-axis modal data: participation of shape (n, 6) and a 6x6 "
                "rigid_mass [kg, kg*m, kg*m^2] are expected; got planar data (n, 2), 2x2")

    # -- views ----------------------------------------------------------------------------------
    def _damping_matrix(self) -> np.ndarray | None:
        if not np.any(self._damping):
            return None
        return np.diag(2.0 * self._damping * self._frequencies)

    def _motion_modes(self, columns, signs, tip_column: int | None):
        """The modes one motion sees, the root's other motions held: (frequencies,
        participation (k, len(columns)), damping ratios, tip motion or None).

        Modes of equal frequency and damping span an invariant subspace, in which any
        orthonormal basis is as good: each such group is rotated (SVD of its participation
        block, the tip motion with it) so that the motion's participation sits in as few modes
        as possible; then the modes whose effective-mass fraction in every one of the columns
        is below :data:`NEGLIGIBLE_FRACTION` are left out. Without this, a round boom's twin
        (the other plane's mode at the same frequency, or a solver's mix of the two) or a mode
        of another motion would stay in the view as an uncoupled coordinate, a spurious pole
        and zero at its frequency.
        """
        columns = np.asarray(columns)
        G = self._participation[:, columns] * np.asarray(signs)
        w, zeta = self._frequencies, self._damping
        tip = None if self._tip is None or tip_column is None else (
            self._tip if self._tip.ndim == 1 else self._tip[:, tip_column])
        scale = np.diag(self._rigid_mass)[columns]
        keep_w, keep_G, keep_z, keep_tip = [], [], [], []
        start, n = 0, w.size
        while start < n:
            stop = start + 1
            while stop < n and w[stop] - w[start] <= _DEGENERATE_RTOL * w[start] \
                    and zeta[stop] == zeta[start]:
                stop += 1
            block = G[start:stop]
            tips = None if tip is None else tip[start:stop]
            if stop - start > 1:
                U = np.linalg.svd(block, full_matrices=True)[0]
                block = U.T @ block
                tips = None if tips is None else U.T @ tips
            seen = np.max(block**2 / scale, axis=1) >= NEGLIGIBLE_FRACTION
            keep_w.append(w[start:stop][seen])
            keep_G.append(block[seen])
            keep_z.append(zeta[start:stop][seen])
            if tips is not None:
                keep_tip.append(tips[seen])
            start = stop
        return (np.concatenate(keep_w), np.concatenate(keep_G), np.concatenate(keep_z),
                np.concatenate(keep_tip) if tip is not None else None)

    def planar_view(self, plane: str = "xy") -> "ModalAppendage":
        """The planar modal appendage of one plane of three-axis data, the root's other motions
        held (Notes of the class). ``"xy"``: (y, theta_z); ``"xz"``: (z, dw/dx = -theta_y)
        in the planar convention. Modes the plane does not see are left out
        (:meth:`_motion_modes`). A planar appendage's "xy" view is itself.

        Raises
        ------
        ValueError
            A plane that no mode moves (rigid in that plane: no planar view).
        """
        if plane not in PLANES:
            raise ValueError(f"plane must be one of {tuple(PLANES)}; got {describe(plane)}")
        if not self.three_axis:
            if plane == "xy":
                return self
            self._require_three_axis("planar_view('xz')")
        cached = self._cache.get(("planar", plane))
        if cached is None:
            index, sign = PLANES[plane]
            flip = np.asarray(sign)
            idx = np.asarray(index)
            w, G, zeta, tip = self._motion_modes(idx, flip, 0 if plane == "xy" else 1)
            if w.size == 0:
                raise ValueError(f"no mode of this appendage moves in the {plane} plane (it is "
                                 "rigid there): it has no planar view")
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the three-axis data were checked already
                cached = ModalAppendage(w, G, self._rigid_mass[np.ix_(idx, idx)]
                                        * np.outer(flip, flip), damping=zeta,
                                        length=self._length, tip_motion=tip)
            self._cache[("planar", plane)] = cached
        return cached

    def undamped(self) -> "ModalAppendage":
        """The same data without damping (itself when undamped)."""
        if not np.any(self._damping):
            return self
        cached = self._cache.get("undamped")
        if cached is None:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                cached = ModalAppendage(self._frequencies, self._participation, self._rigid_mass,
                                        length=self._length, tip_motion=self._tip)
            self._cache["undamped"] = cached
        return cached

    def truncated(self, n_modes: int) -> "ModalAppendage":
        """The first ``n_modes`` modes (the rest's mass joins the residual mass)."""
        if isinstance(n_modes, (bool, np.bool_)) or not isinstance(n_modes, (int, np.integer)):
            raise TypeError(f"n_modes must be an integer (number of modes); got "
                            f"{type(n_modes).__name__} {describe(n_modes)}")
        if not 1 <= n_modes <= self.n_modes:
            raise ValueError(f"n_modes must be between 1 and {self.n_modes} (the modes of the "
                             f"data); got {n_modes!r}")
        k = int(n_modes)
        tip = None if self._tip is None else self._tip[:k]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return ModalAppendage(self._frequencies[:k], self._participation[:k],
                                  self._rigid_mass, damping=self._damping[:k],
                                  length=self._length, tip_motion=tip)

    # -- W(s) -----------------------------------------------------------------------------------
    def _operator(self, n_root: int) -> ModalStiffness:
        data = self if n_root == self.n_root else self.planar_view("xy")
        key = ("operator", n_root)
        cached = self._cache.get(key)
        if cached is None:
            cached = ModalStiffness(data._rigid_mass, data._participation, data._frequencies,
                                    data._damping_matrix(), data._residual)
            self._cache[key] = cached
        return cached

    def dynamic_mass(self, s) -> np.ndarray:
        """The root's dynamic mass M(s) (module docstring), shape ``np.shape(s) + (r, r)``.

        ``M(s) = M_rr - sum_i G_i^T G_i s**2/(s**2 + 2 zeta_i w_i s + w_i**2)`` with r the
        data's root motions (2 or 6) [kg, kg*m, kg*m^2]; s = 0 gives ``rigid_mass``.
        """
        s = as_frequency_array(s)
        r = self.n_root
        out = np.empty(s.shape + (r, r), dtype=np.complex128)
        zero = s == 0
        out[zero] = self._rigid_mass
        if np.any(~zero):
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                out[~zero] = self._operator(r)(s[~zero]) / (s[~zero] ** 2)[:, None, None]
        return out

    def dynamic_stiffness(self, s) -> np.ndarray:
        """Planar root dynamic stiffness ``D(s) = s**2 M(s) = W(s)^-1`` [N/m, N; N, N*m].

        O(n) per frequency; infinite exactly at an undamped cantilever frequency; s = 0
        gives 0. Three-axis data: the x-y plane with the other root motions held.
        """
        s = as_frequency_array(s)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return self._operator(2)(s)

    def dynamic_stiffness6(self, s) -> np.ndarray:
        """Three-axis root dynamic stiffness ``D6(s) = s**2 M(s) = W6(s)^-1``, shape
        ``np.shape(s) + (6, 6)`` (loads :data:`~appendages.interface.ROOT_LOADS` per motions
        :data:`~appendages.interface.ROOT_MOTIONS`); s = 0 gives 0."""
        self._require_three_axis("dynamic_stiffness6")
        s = as_frequency_array(s)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            return self._operator(6)(s)

    def W(self, s) -> np.ndarray:
        """Transfer matrix W(s) = (s**2 M(s))^-1 of the free appendage, shape
        ``np.shape(s) + (2, 2)`` [m/N, 1/N; 1/N, 1/(N*m)], O(n) per frequency.

        Parameters
        ----------
        s : complex or array_like of complex, rad/s
            Laplace variable, not 0 (the rigid-body pole).
        """
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError("s = 0 is the rigid-body pole of W (W is infinite there) [rad/s]")
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            W = inverse_2x2(self._operator(2)(s))
        if not np.all(np.isfinite(W)):
            raise ValueError("s is a natural frequency of the undamped model: W is infinite "
                             "there [rad/s]")
        return W

    def W6(self, s) -> np.ndarray:
        """Three-axis transfer matrix W6(s) = (s**2 M(s))^-1, shape ``np.shape(s) + (6, 6)``:
        root motions (u, v, w, theta_x, theta_y, theta_z) per root loads (F_x, ..., M_z),
        appendage axes, rigid-body motion included; O(n) per frequency."""
        self._require_three_axis("W6")
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError("s = 0 is the rigid-body pole of W6 (W6 is infinite there) [rad/s]")
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            W = inverse_symmetric(self._operator(6)(s))
        if not np.all(np.isfinite(W)):
            raise ValueError("s is a natural frequency of the undamped model: W6 is infinite "
                             "there [rad/s]")
        return W

    # -- realisations ---------------------------------------------------------------------------
    def _names(self) -> tuple:
        root = ("delta", "phi") if self.n_root == 2 else ROOT_MOTIONS
        return tuple(root) + tuple(f"eta[{k + 1}]" for k in range(self.n_modes))

    def _root_model(self) -> RootModel:
        data = self.planar_view("xy")
        tip = np.zeros(data.n_modes) if data._tip is None else data._tip
        return fixed_root_model(data._rigid_mass, data._participation, data._frequencies,
                                data._damping_matrix(), tip, np.zeros(2), data._names(), 2)

    def _three_axis_root_model(self) -> RootModel:
        self._require_three_axis("a three-axis root model (root_model(n_root=6))")
        model = fixed_root_model(self._rigid_mass, self._participation, self._frequencies,
                                 self._damping_matrix(), np.zeros(self.n_modes), np.zeros(6),
                                 self._names(), 6)
        tip = np.zeros((3, model.n))
        if self._tip is not None:
            tip[:, 6:] = self._tip.T
        return dataclasses.replace(model, tip=tip)

    def state_space(self, *, tip: bool = False, name: str | None = None,
                    three_axis: bool = False):
        """python-control StateSpace of W (or W6) in free modal coordinates.

        Planar (default): inputs ``F_y``, ``M``; outputs ``delta``, ``phi`` (and
        ``tip_deflection`` with ``tip``), as every finite appendage
        (:meth:`FiniteAppendage.state_space <appendages.interface.FiniteAppendage.state_space>`).
        ``three_axis=True`` (three-axis data): inputs
        :data:`~appendages.interface.ROOT_LOADS`, outputs
        :data:`~appendages.interface.ROOT_MOTIONS` (and the
        :data:`~appendages.interface.TIP_MOTIONS` with ``tip``), built the same way:
        states ``[eta, eta_dot]`` of the free appendage's modes (six rigid-body modes at 0).

        Raises
        ------
        ValueError
            Tip outputs asked of data without :attr:`tip_motion`; a residual mass that is
            singular (all of a direction's mass in the kept modes: W then tends to a constant
            at high frequency, which this realisation of a mass matrix cannot give).
        """
        if tip and self._tip is None:
            raise ValueError("tip outputs need tip_motion [m/sqrt(kg)] (each mode's tip "
                             "motion); this ModalAppendage was built without it")
        if not three_axis:
            self.planar_view("xy")._check_residual_regular()
            return super().state_space(tip=tip, name=name)
        self._check_residual_regular()
        self._require_three_axis("state_space(three_axis=True)")
        import control

        rm = self.root_model(6)
        d = equilibrate(rm.stiffness, rm.mass)
        lam, V = scipy.linalg.eigh(rm.stiffness * np.outer(d, d), rm.mass * np.outer(d, d))
        V = V * d[:, None]
        # the six smallest are the free appendage's rigid-body modes (zero up to round-off)
        lam[:6] = np.where(np.abs(lam[:6]) <= 1e-6 * np.abs(lam).max(initial=0.0), 0.0, lam[:6])
        m = lam.size
        load = np.zeros((rm.n, 6))
        load[:6] = np.eye(6)
        rows = np.vstack([np.eye(rm.n)[:6], rm.tip_rows]) if tip else np.eye(rm.n)[:6]
        A = np.block([[np.zeros((m, m)), np.eye(m)], [-np.diag(lam), -(V.T @ rm.damping @ V)]])
        B = np.vstack([np.zeros((m, 6)), V.T @ load])
        C = np.hstack([rows @ V, np.zeros((rows.shape[0], m))])
        from .interface import TIP_MOTIONS

        outputs = list(ROOT_MOTIONS) + (list(TIP_MOTIONS) if tip else [])
        states = [f"eta[{k}]" for k in range(m)] + [f"eta_dot[{k}]" for k in range(m)]
        return control.ss(A, B, C, np.zeros((C.shape[0], 6)), inputs=list(ROOT_LOADS),
                          outputs=outputs, states=states, name=name)

    def _check_residual_regular(self) -> None:
        d = 1.0 / np.sqrt(np.diag(self._rigid_mass))
        smallest = float(scipy.linalg.eigvalsh(self._residual * np.outer(d, d))[0])
        if smallest <= 1e-12:
            raise ValueError(
                f"the residual mass is singular (smallest eigenvalue {smallest:.3g} of the "
                "rigid mass scaled to unit diagonal): the kept modes hold all of some "
                "direction's mass, and a free state-space model of this appendage has no "
                "mass matrix; couple it to a hub (root_model) or drop the last modes "
                "(truncated(n_modes))")

