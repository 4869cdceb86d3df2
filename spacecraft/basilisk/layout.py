r"""A flexsat spacecraft laid out as Basilisk's hub and spinning bodies (no Basilisk needed).

Which Basilisk effector, and why
    Basilisk offers four hinged-body state effectors. ``hingedRigidBodyStateEffector`` is one
    panel on the hub; ``dualHingedRigidBodyStateEffector`` two; ``nHingedRigidBodyStateEffector``
    a chain of panels that must all have the same mass, inertia and half-length d (its
    ``HingedPanel`` list shares one geometry), and ``linearSpringMassDamper`` is a translating
    point mass. ``spinningBodyNDOFStateEffector`` is N rigid bodies in series, body i spinning
    about an axis fixed in body i-1 (the hub for i = 1), each with its own mass, inertia about its
    centre of mass, centre-of-mass offset ``r_ScS_S``, hinge position ``r_SP_P`` in its parent,
    hinge orientation ``dcm_S0P``, spring ``k`` and damper ``c`` acting on the relative angle
    (torque ``-k theta - c thetaDot``, Basilisk's ``computeCThetaStar``) [1]_. It is the only
    one that represents a flexsat chain with non-identical bodies exactly, so flexsat uses it:
    one effector per chain.

Coordinates and conventions (flexsat -> Basilisk)
    The Basilisk body frame B is the flexsat hub frame: origin at the hub's centre of mass,
    planar motion in its x-y plane, attitude theta about +z (``sigma_BN = (0, 0, tan(theta/4))``).
    A mount at position p along the angle a (``Mount.position``, ``Mount.angle``) puts the first
    spinning body's hinge at ``r_SP_P = (p_x, p_y, 0)`` with ``dcm_S0P = R3(a)`` (rows: the
    appendage's axes in hub axes), spin axis ``sHat_S = +z``; body i+1 hangs at
    ``r_SP_P = (l_i, 0, 0)`` in body i's frame with ``dcm_S0P = I``. Every body's S frame has
    its origin at its hinge, x along the body, and its centre of mass at ``r_ScS_S = (a_i, 0, 0)``
    (the chain's ``com_offsets``, from the body's start). Basilisk's spin angle of body i is its
    rotation relative to its parent, ``theta_i - theta_(i-1)`` in flexsat's absolute angles; the
    first body's is relative to the mount (the hub), which is how flexsat's hinge springs act
    (``c_h (theta_(k+1) - theta_k)**2 / 2``), so the hinge stiffnesses and dampings map one to one.

Root
    ``root="hinged"``: every body is a spinning body, the first spring is the mount's drive
    hinge. ``root="rigid"``: the first body is part of the hub, folded exactly into the hub's
    mass properties (below); bodies 2..n are spinning bodies, the first hinged at the end of
    body 1, ``r_SP_P = p + l_1 e``.

Folding rigid bodies into the hub
    With hub mass m_h (centre of mass at B's origin) and folded bodies of mass m_j, central
    inertia J_j and centre of mass r_j = p_j + a_j e_j, the hub Basilisk sees has

        m = m_h + sum_j m_j,    r_BcB_B = c = sum_j m_j r_j / m,
        I_Bc = I_h + m_h P(-c) + sum_j (I_j + m_j P(r_j - c)),   P(d) = |d|**2 E - d d^T,

    the parallel-axis theorem in three dimensions. Basilisk's ``r_BcB_B`` is the offset of this
    combined centre of mass from B, and ``IHubPntBc_B`` the inertia about it.

Out-of-plane inertia
    flexsat's planar hub and bodies define only the inertia about z. Basilisk needs positive
    definite 3x3 tensors: the hub gets ``J E`` and each body ``J_i E`` (E the identity). The
    out-of-plane components never act: every body lies in the plane z = 0 and spins about z, so
    the products of inertia I_xz, I_yz vanish and ``I omega`` is parallel to z for every
    angular velocity along z; planar motion stays planar (the adapter checks it after each run).

Tip deflection
    flexsat's ``<name>_tip_deflection`` is the transverse displacement of the free end relative
    to the mount's tangent line, ``w(L) - delta - L phi`` = ``sum_i l_i (theta_i - theta)``
    linearised. From Basilisk's relative angles the exact (nonlinear) quantity is the component
    of (tip - mount point) along the mount's normal, in hub axes,

        tip = sum_i l_i sin(beta_i),   beta_i = sum_(j <= i) (relative angle of body j),

    whose linearisation is flexsat's (a folded first body has beta = 0).

Three axes
    A three-axis spacecraft (hub with a 3x3 inertia tensor, chains with their three-axis
    parameters, :func:`appendages.fit_chain_3d`) is laid out the same way, with three spinning
    bodies per joint, all hinged at the joint: the first spins about the child body's local z
    (bending in its x-y plane: ``hinge_stiffnesses``, ``hinge_dampings``), the second about its
    local y (bending in the x-z plane: ``hinge_stiffnesses_y``, ``hinge_dampings_y``), the third
    about its local x (torsion: ``torsion_stiffnesses``, ``torsion_dampings``; left out for a
    torsionally rigid chain, ``torsion_stiffnesses=None``). Only the last carries the body: its
    mass, its centre of mass ``(a_i, 0, 0)`` and its inertia ``diag(J_x, J_y, J_z)``
    (``torsional_inertias``, ``inertias_y``, ``inertias``) in its own axes; the others are
    massless, with zero inertia, which Basilisk's N-DOF effector documents as several degrees of
    freedom of one body [1]_. The first spinning body of a chain has ``dcm_S0P = R^T`` (R the
    mount's ``orientation``, columns the appendage's axes in hub axes) and its hinge at the
    mount point p (``root="hinged"``) or at ``p + l_1 R e_x`` (``root="rigid"``, the first body
    folded into the hub with its inertia ``R diag(J_x, J_y, J_z) R^T``). Linearised about the
    straight chain the joint rotations add as small rotation vectors, so the order of the three
    (z, y, x) does not matter to first order; each spring acts on its relative angle, as
    flexsat's springs act on the differences of the bodies' absolute angles in each motion (the
    x-z plane's ``dw/dx`` is ``-theta_y``, which flips the sign of both angles of a spring and
    leaves its energy as it is).

    Axial motion: Basilisk's spinning bodies only rotate (its translating bodies,
    ``linearTranslationNDOFStateEffector``, are an effector of their own and cannot hang from a
    spinning body), so a chain's axial springs cannot be represented: the layout holds them
    rigid, and the flexsat model of the same spacecraft (:attr:`SpacecraftLayout.spacecraft`,
    the comparison's linear chain) holds them rigid too (:func:`inextensible`). What that
    leaves out is the axial modes, far above the bending ones for a slender appendage (a
    uniform cantilever's first axial to first bending frequency is ``(pi/2) L sqrt(EA/EI) /
    3.516``: 126 for a 5 m thin-walled tube of 5 cm diameter). :attr:`AppendageLayout.held`
    names the motion held and :attr:`AppendageLayout.axial_frequency` gives the chain's first
    axial frequency with its root held, the mode left out.

    Stiff torsion: a chain's torsion whose first frequency (root held) lies far above what the
    flight software can act on (``rigid_above``, e.g. its sampling frequency) can be held
    rigid, in Basilisk and in the linear chain compared alike (``torsion_stiffnesses=None``,
    which :class:`appendages.HingedChain` models exactly): a thin boom's torsion, thousands
    of rad/s, would otherwise set RK4's step for the whole run (:mod:`.simulation`) though
    no torque of the loop excites it. :attr:`AppendageLayout.held` names it and
    :attr:`AppendageLayout.torsion_frequency` gives the mode left out; what holding it costs
    is measured on flexsat's linear chains (:func:`.slew_comparison`). The bending planes
    are never held: a chain has no rigid bending joint, so the comparison could not hold it
    alike.

    Bodies: Basilisk accepts only the inertia tensor of a body, whose largest principal moment
    is at most the sum of the other two. A chain fitted to an Euler-Bernoulli beam need not
    give one: the beam has the section's torsional inertia (``torsional_inertia``, rho I_p)
    but no rotary inertia in bending, so a wide wing's bodies get J_x > J_y + J_z (the shipped
    three-axis scene's wings: 1.2 kg*m^2 short at the tip body). Such a body's deficit is
    added to the moment of the stiffer of its two other motions (the larger spring per
    inertia at its joint: for a wing, its in-plane bending, whose modes are far above the
    others), the least change to the modes that matter, physically the section's rotary
    inertia the beam model leaves out. Basilisk and the linear chain it is compared with
    (:attr:`SpacecraftLayout.spacecraft`) carry the same raised moment
    (:func:`basilisk_chain`); :attr:`AppendageLayout.raised_inertias` lists them and
    :func:`layout` warns (:class:`BasiliskModelWarning`).

    Tip motions: ``<name>_tip_deflection_y`` and ``_z`` are the components along the mount's
    local y and z axes of the tip's position from the mount point (hub axes);
    ``<name>_tip_twist`` is the x component of the rotation vector of the tip body's axes
    relative to the mount's. Their linearisations are flexsat's elastic tip motions (relative
    to the rigidly moving root section).

References
----------
.. [1] J. Vaz Carneiro, C. Allard, H. Schaub, "Effector Dynamics for Sequentially Rotating Rigid
   Body Spacecraft Components", AAS Astrodynamics Specialist Conference, Big Sky, MT, 2023 (the
   spinningBodyNDOFStateEffector); Basilisk source
   ``src/simulation/dynamics/spinningBodies/spinningBodiesNDOF/spinningBodyNDOFStateEffector.cpp``.
.. [2] H. Schaub, J. L. Junkins, "Analytical Mechanics of Space Systems", 4th ed., AIAA 2018
   (MRPs, parallel-axis theorem).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Mapping

import numpy as np
import scipy.linalg
from scipy.spatial.transform import Rotation

from appendages.chain import HingedChain, spring_chain_matrices
from appendages.interface import check_positive

from ..dynamics.coupling import Spacecraft
from ..dynamics.hub import Mount
from ..dynamics.kinematics import TRIANGLE_TOLERANCE
from .install import BasiliskModelError, BasiliskModelWarning

__all__ = ["BodyLayout", "AppendageLayout", "HubLayout", "SpacecraftLayout", "layout",
           "chain_spacecraft", "basilisk_chain", "inextensible", "torsion_held",
           "torsion_frequency", "SPIN_AXES"]

_CHAIN_ATTRIBUTES = ("lengths", "masses", "inertias", "hinge_stiffnesses", "com_offsets", "root")

#: Unit spin axis ``sHat_S`` of a spinning body by the local axis it turns about.
SPIN_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


@dataclasses.dataclass(frozen=True)
class BodyLayout:
    """One spinning body of a ``spinningBodyNDOFStateEffector`` (Basilisk's parameter names).

    Attributes
    ----------
    mass : float, kg
    ISPntSc_S : ndarray (3, 3), kg*m**2
        Inertia about the body's centre of mass, S axes.
    r_SP_P : ndarray (3,), m
        Hinge point from the parent frame's origin, parent axes.
    dcm_S0P : ndarray (3, 3)
        Parent axes -> S axes at zero spin angle.
    r_ScS_S : ndarray (3,), m
        Centre of mass from the hinge, S axes.
    k : float, N*m/rad
        Hinge spring on the angle relative to the parent.
    c : float, N*m*s/rad
        Hinge damper.
    length : float, m
        Hinge to the next hinge (or the free end); 0 for a massless body that only adds a
        degree of freedom to the joint (three axes).
    spin_axis : {"z", "y", "x"}
        The local axis it spins about (``sHat_S``, :data:`SPIN_AXES`): z, bending in the
        appendage's x-y plane (every planar body); y, bending in its x-z plane; x, torsion.
    """

    mass: float
    ISPntSc_S: np.ndarray
    r_SP_P: np.ndarray
    dcm_S0P: np.ndarray
    r_ScS_S: np.ndarray
    k: float
    c: float
    length: float
    spin_axis: str = "z"

    @property
    def sHat_S(self) -> np.ndarray:
        """Unit spin axis in S axes (3,)."""
        return np.array(SPIN_AXES[self.spin_axis])


@dataclasses.dataclass(frozen=True)
class AppendageLayout:
    """A flexsat chain as Basilisk spinning bodies.

    Attributes
    ----------
    name : str
        flexsat's mount name (signal prefix of ``<name>_tip_deflection``).
    mount : Mount
    chain : HingedChain
        The chain Basilisk models (three axes: held inextensible, :func:`inextensible`).
    bodies : tuple of BodyLayout
        The spinning bodies, root first (empty when a one-body chain is rigidly mounted).
    n_folded : int
        Bodies folded into the hub (1 for ``root="rigid"``, else 0).
    held : tuple of str
        Motions of the given chain held rigid, in Basilisk and in flexsat's comparison model
        alike: ``"axial"`` for a three-axis chain with axial springs (Basilisk's spinning
        bodies cannot represent them), ``"torsion"`` for a torsion stiffer than
        :func:`layout`'s ``rigid_above`` (module docstring, "Stiff torsion"), else empty.
    axial_frequency : float or None, rad/s
        With ``"axial"`` held: the first axial frequency of the given chain with its root
        held (the mode left out).
    raised_inertias : tuple of (int, str, float)
        Bodies whose moments were made a body's (module docstring, "Bodies"): the body's
        number (1 at the root), the axis whose moment was raised and by how much [kg*m**2].
    torsion_frequency : float or None, rad/s
        With ``"torsion"`` held: the chain's first torsion frequency with its root held (the
        mode left out).
    """

    name: str
    mount: Mount
    chain: object
    bodies: tuple
    n_folded: int
    held: tuple = ()
    axial_frequency: float | None = None
    raised_inertias: tuple = ()
    torsion_frequency: float | None = None

    @property
    def three_axis(self) -> bool:
        """True for a three-axis mount (tip motions in both planes and twist)."""
        return bool(self.mount.three_axis) or bool(getattr(self.chain, "three_axis", False))

    def _angles(self, angles) -> np.ndarray:
        angles = np.asarray(angles, dtype=float)
        if angles.ndim != 2 or angles.shape[1] != len(self.bodies):
            raise ValueError(f"angles must have shape (n_samples, {len(self.bodies)}) [rad]; "
                             f"got {angles.shape}")
        return angles

    def tip_deflection(self, angles) -> np.ndarray:
        """Transverse tip deflection [m] from Basilisk's relative spin angles (planar).

        Parameters
        ----------
        angles : array_like (n_samples, n_spinning_bodies), rad
            Spin angle of each body relative to its parent, root first.

        Returns
        -------
        ndarray (n_samples,), m
            ``sum_i l_i sin(beta_i)`` with ``beta`` the cumulative sum of the angles (see the
            module docstring); zeros when the chain has no spinning body.
        """
        if self.three_axis:
            raise ValueError(f"appendage {self.name!r} is three-axis: its tip moves in both "
                             "planes and twists; use tip_motions(angles)")
        angles = self._angles(angles)
        lengths = np.array([b.length for b in self.bodies])
        return np.sin(np.cumsum(angles, axis=1)) @ lengths

    def tip_motions(self, angles) -> np.ndarray:
        """Tip deflections along the mount's y and z axes [m] and tip twist [rad] (three
        axes) from Basilisk's relative spin angles, exact (module docstring).

        Parameters
        ----------
        angles : array_like (n_samples, n_spinning_bodies), rad
            Spin angle of each body relative to its parent, root first.

        Returns
        -------
        ndarray (n_samples, 3)
            Columns ``tip_deflection_y`` [m], ``tip_deflection_z`` [m], ``tip_twist`` [rad];
            zeros when the chain has no spinning body.
        """
        angles = self._angles(angles)
        n = angles.shape[0]
        R = self.mount.orientation
        if not self.bodies:
            return np.zeros((n, 3))
        # frames of the bodies in hub axes, sample by sample: dcm_BS(i) = dcm_BS(i-1)
        # dcm_S0P(i)^T dcm_S0S(theta_i), dcm_S0S the rotation by +theta_i about sHat (Basilisk's
        # computeAttitudeProperties); hinge positions r_SB(i) = r_SB(i-1) + dcm_BS(i-1) r_SP_P
        frame = np.broadcast_to(np.eye(3), (n, 3, 3))
        origin = np.zeros((n, 3))
        for k, body in enumerate(self.bodies):
            origin = origin + frame @ body.r_SP_P
            spin = Rotation.from_rotvec(angles[:, k, None] * body.sHat_S).as_matrix()
            frame = frame @ body.dcm_S0P.T @ spin
        # the last spinning body carries the chain's last body, from its hinge along its x axis
        d = origin + frame[:, :, 0] * self.bodies[-1].length - self.mount.point
        twist = Rotation.from_matrix(R.T @ frame).as_rotvec()[:, 0]
        return np.column_stack([d @ R[:, 1], d @ R[:, 2], twist])


@dataclasses.dataclass(frozen=True)
class HubLayout:
    """The hub Basilisk sees: flexsat's hub plus the rigidly mounted first bodies.

    Attributes
    ----------
    mHub : float, kg
    r_BcB_B : ndarray (3,), m
        Its centre of mass from B (flexsat's hub centre of mass), hub axes.
    IHubPntBc_B : ndarray (3, 3), kg*m**2
        Inertia about that centre of mass, hub axes.
    """

    mHub: float
    r_BcB_B: np.ndarray
    IHubPntBc_B: np.ndarray


@dataclasses.dataclass(frozen=True)
class SpacecraftLayout:
    """A flexsat spacecraft as Basilisk parameters.

    Attributes
    ----------
    hub : HubLayout
    appendages : tuple of AppendageLayout
    spacecraft : Spacecraft
        flexsat's linear model of the same hub and chains (the comparison's plant; three axes:
        chains held inextensible as in Basilisk).
    """

    hub: HubLayout
    appendages: tuple
    spacecraft: Spacecraft

    @property
    def n_bodies(self) -> int:
        """Spinning bodies in all effectors."""
        return sum(len(a.bodies) for a in self.appendages)

    @property
    def three_axis(self) -> bool:
        """True for a three-axis spacecraft (hub with an inertia tensor)."""
        return bool(self.spacecraft.three_axis)


def _parallel_axis(mass: float, d: np.ndarray) -> np.ndarray:
    """m (|d|^2 E - d d^T): inertia of a point mass m at d about the origin [kg*m^2]."""
    return mass * (float(d @ d) * np.eye(3) - np.outer(d, d))


def _planar_rotation(angle: float) -> np.ndarray:
    """dcm_S0P of a frame rotated by ``angle`` about +z: rows are its axes in parent axes."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def _is_chain(appendage) -> bool:
    return all(hasattr(appendage, a) for a in _CHAIN_ATTRIBUTES)


def _check_chain(chain) -> None:
    if not isinstance(chain, HingedChain):
        raise TypeError(f"chain must be an appendages.HingedChain; got {type(chain).__name__} "
                        f"{chain!r:.60}")


def inextensible(chain: HingedChain) -> HingedChain:
    """The chain with its axial springs held rigid (everything else as it is).

    Basilisk's spinning bodies only rotate: a three-axis chain runs there inextensible (module
    docstring, "Axial motion"). A chain without axial springs is returned as it is.
    """
    _check_chain(chain)
    if getattr(chain, "axial_stiffnesses", None) is None:
        return chain
    return _held(chain, "axial")


def torsion_held(chain: HingedChain) -> HingedChain:
    """The three-axis chain with its torsion joints held rigid (``torsion_stiffnesses=None``;
    everything else as it is). A chain without torsion springs is returned as it is."""
    _check_chain(chain)
    if getattr(chain, "torsion_stiffnesses", None) is None:
        return chain
    return _held(chain, "torsion")


def _held(chain: HingedChain, motion: str) -> HingedChain:
    """``chain`` rebuilt without the springs and dampers of ``motion`` ("axial", "torsion")."""
    joints = {f"{m}_{what}": getattr(chain, f"{m}_{what}")
              for m in ("torsion", "axial") if m != motion
              for what in ("stiffnesses", "dampings")}
    return HingedChain(chain.lengths, chain.masses, chain.inertias, chain.hinge_stiffnesses,
                       hinge_dampings=chain.hinge_dampings, com_offsets=chain.com_offsets,
                       root=chain.root, inertias_y=chain.inertias_y,
                       hinge_stiffnesses_y=chain.hinge_stiffnesses_y,
                       hinge_dampings_y=chain.hinge_dampings_y,
                       torsional_inertias=chain.torsional_inertias, **joints)


def torsion_frequency(chain: HingedChain) -> float | None:
    """First torsion frequency [rad/s] of a three-axis chain with its root held (its torsion
    spring chain); None without torsion springs."""
    _check_chain(chain)
    if getattr(chain, "torsion_stiffnesses", None) is None:
        return None
    return _spring_frequency(chain.torsional_inertias, chain.torsion_stiffnesses, chain.root)


def _body_inertias(chain) -> tuple[np.ndarray, list]:
    """Principal moments (n, 3) ``(J_x, J_y, J_z)`` of a three-axis chain's bodies as Basilisk
    takes them, and the raises [(body number, axis, added)] that made them a body's (module
    docstring, "Bodies"). The first body of a rigid root is folded into the hub and left as
    it is: only the hub's total must be a body's."""
    moments = np.column_stack([chain.torsional_inertias, chain.inertias_y,
                               chain.inertias]).astype(float)
    n_hinges = chain.n_bodies - 1 if chain.root == "rigid" else chain.n_bodies
    inf = np.full(n_hinges, np.inf)
    springs = np.column_stack([inf if chain.torsion_stiffnesses is None
                               else np.asarray(chain.torsion_stiffnesses, dtype=float),
                               np.asarray(chain.hinge_stiffnesses_y, dtype=float),
                               np.asarray(chain.hinge_stiffnesses, dtype=float)])
    first = 1 if chain.root == "rigid" else 0
    raised = []
    for i in range(first, chain.n_bodies):
        J = moments[i]
        if not np.all(J > 0.0):
            continue  # no body's at all: refused by name when laid out
        excess = 2.0 * J - J.sum()  # J_a - (J_b + J_c)
        a = int(np.argmax(excess))
        b, c = (k for k in range(3) if k != a)
        if not excess[a] > TRIANGLE_TOLERANCE * (J[b] + J[c]):
            continue
        # the stiffer motion (spring per inertia at the body's own joint) takes the deficit
        k = springs[i - first]
        if k[c] / J[c] > k[b] / J[b]:
            b, c = c, b
        added = J[a] - J[c] - J[b]
        J[b] = J[a] - J[c]
        raised.append((i + 1, "xyz"[b], float(added)))
    return moments, raised


def basilisk_chain(chain: HingedChain) -> HingedChain:
    """The three-axis chain as Basilisk holds it: inextensible (:func:`inextensible`), and
    every body's moments those of a body (module docstring, "Bodies"). A chain Basilisk holds
    as it is is returned as it is."""
    _check_chain(chain)
    chain = inextensible(chain)
    if not getattr(chain, "three_axis", False):
        return chain
    moments, raised = _body_inertias(chain)
    if not raised:
        return chain
    return HingedChain(chain.lengths, chain.masses, moments[:, 2], chain.hinge_stiffnesses,
                       hinge_dampings=chain.hinge_dampings, com_offsets=chain.com_offsets,
                       root=chain.root, inertias_y=moments[:, 1],
                       hinge_stiffnesses_y=chain.hinge_stiffnesses_y,
                       hinge_dampings_y=chain.hinge_dampings_y,
                       torsional_inertias=moments[:, 0],
                       torsion_stiffnesses=chain.torsion_stiffnesses,
                       torsion_dampings=chain.torsion_dampings)


def _spring_frequency(inertias, springs, root: str) -> float:
    """First frequency [rad/s] of a spring chain (masses or moments ``inertias`` joined by
    ``springs``) with its root held."""
    M, _, K, _ = spring_chain_matrices(np.asarray(inertias, dtype=float),
                                       np.asarray(springs, dtype=float), None, root == "hinged")
    return float(math.sqrt(max(scipy.linalg.eigvalsh(K[1:, 1:], M[1:, 1:])[0], 0.0)))


def _axial_frequency(chain) -> float:
    """First axial frequency [rad/s] of a chain's spring chain with its root held."""
    return _spring_frequency(chain.masses, chain.axial_stiffnesses, chain.root)


def chain_spacecraft(spacecraft: Spacecraft, chains: Mapping | None = None, *,
                     rigid_above: float | None = None) -> Spacecraft:
    """The spacecraft Basilisk models: appendages replaced by chains, by mount name.

    Parameters
    ----------
    spacecraft : Spacecraft
        Planar or three-axis.
    chains : mapping name -> HingedChain, optional
        Replacements (e.g. the chain a scene fits to a beam). Appendages not named must already
        be chains.
    rigid_above : float, rad/s, optional
        Three axes: hold rigid the torsion of every chain whose first torsion frequency (root
        held, :func:`torsion_frequency`) is above it (module docstring, "Stiff torsion");
        None holds no torsion.

    Returns
    -------
    Spacecraft
        ``spacecraft`` itself when nothing is replaced (its computed modes are reused). Three
        axes: each chain as Basilisk holds it (:func:`basilisk_chain`: inextensible, every
        body's inertia a body's; :func:`torsion_held` above ``rigid_above``).

    Raises
    ------
    BasiliskModelError
        An appendage that is not a chain and has no replacement, or an unknown name.
    """
    if not isinstance(spacecraft, Spacecraft):
        raise TypeError(f"spacecraft must be a flexsat Spacecraft; got {type(spacecraft).__name__}")
    if chains is not None and not isinstance(chains, Mapping):
        raise TypeError(f"chains must be a mapping mount name -> HingedChain or None; got "
                        f"{type(chains).__name__} {chains!r:.100}")
    if rigid_above is not None:
        rigid_above = check_positive("rigid_above", rigid_above, "rad/s")
    chains = {} if chains is None else dict(chains)
    unknown = sorted(set(chains) - set(spacecraft.names))
    if unknown:
        raise BasiliskModelError(f"chains names {unknown} are not mounts of the spacecraft; its "
                                 f"mounts are {spacecraft.names}")
    for name, chain in chains.items():
        if not _is_chain(chain):
            raise BasiliskModelError(f"chains[{name!r}] must be a HingedChain; got "
                                     f"{type(chain).__name__}")
    mounts, replaced = [], bool(chains)
    fit = ("appendages.fit_chain_3d(beam, n_bodies)" if spacecraft.three_axis
           else "appendages.equivalence.fit_chain(beam, n_bodies)")
    for name, mount in zip(spacecraft.names, spacecraft.mounts):
        appendage = chains.get(name, mount.appendage)
        if not _is_chain(appendage):
            raise BasiliskModelError(
                f"appendage {name!r} is a {type(appendage).__name__}: Basilisk models an "
                "appendage as hinged rigid bodies, so it needs a HingedChain; fit one "
                f"({fit}) and pass chains={{{name!r}: chain}}")
        if spacecraft.three_axis:
            held = basilisk_chain(appendage)
            if rigid_above is not None and (torsion_frequency(held) or 0.0) > rigid_above:
                held = torsion_held(held)
            replaced = replaced or held is not appendage
            mounts.append(mount.with_appendage(held))
        else:
            mounts.append(Mount(appendage, mount.position, mount.angle, name=name))
    if not replaced:
        return spacecraft
    return Spacecraft(spacecraft.hub, mounts)


def _appendage(name: str, mount: Mount) -> tuple[AppendageLayout, list]:
    """Spinning bodies of one planar chain, and the (mass, inertia, position) of a folded
    body."""
    chain = mount.appendage
    n = int(chain.n_bodies) if hasattr(chain, "n_bodies") else len(chain.lengths)
    lengths = np.asarray(chain.lengths, dtype=float)
    masses = np.asarray(chain.masses, dtype=float)
    inertias = np.asarray(chain.inertias, dtype=float)
    offsets = np.asarray(chain.com_offsets, dtype=float)
    stiffnesses = np.asarray(chain.hinge_stiffnesses, dtype=float)
    dampings = (np.zeros_like(stiffnesses) if getattr(chain, "hinge_dampings", None) is None
                else np.asarray(chain.hinge_dampings, dtype=float))
    if chain.root not in ("rigid", "hinged"):
        raise BasiliskModelError(f"chain {name!r}: root must be 'rigid' or 'hinged'; got "
                                 f"{chain.root!r}")
    folded = []
    first = 0
    p = np.array([mount.position[0], mount.position[1], 0.0])
    e = np.array([math.cos(mount.angle), math.sin(mount.angle), 0.0])
    hinge = p
    if chain.root == "rigid":
        folded.append((float(masses[0]), float(inertias[0]) * np.eye(3), p + offsets[0] * e))
        hinge = p + lengths[0] * e
        first = 1
    bodies = []
    for i in range(first, n):
        _check_body_inertia(name, i, inertias[i])
        h = i - first  # hinge index of this body (its hinge to the parent)
        parent_hinge = hinge if i == first else np.array([lengths[i - 1], 0.0, 0.0])
        bodies.append(BodyLayout(
            mass=float(masses[i]), ISPntSc_S=float(inertias[i]) * np.eye(3),
            r_SP_P=parent_hinge.copy(),
            dcm_S0P=_planar_rotation(mount.angle) if i == first else np.eye(3),
            r_ScS_S=np.array([offsets[i], 0.0, 0.0]),
            k=float(stiffnesses[h]), c=float(dampings[h]), length=float(lengths[i])))
    return AppendageLayout(name, mount, chain, tuple(bodies), len(folded)), folded


def _check_body_inertia(name: str, i: int, inertia: float, axis: str = "") -> None:
    if not inertia > 0.0:
        about = f" about its {axis} axis" if axis else ""
        raise BasiliskModelError(
            f"chain {name!r}: body {i + 1} has inertia {float(inertia)!r} [kg*m^2]{about} about "
            "its centre of mass; Basilisk's spinningBodyNDOFStateEffector needs a positive "
            "definite inertia tensor for every body with mass (a point-mass body cannot be "
            "represented): give it a positive inertia")


def _optional(values, size: int) -> np.ndarray:
    return np.zeros(size) if values is None else np.asarray(values, dtype=float)


def _appendage_3d(name: str, mount: Mount, given) -> tuple[AppendageLayout, list]:
    """Spinning bodies of one three-axis chain, three per joint (module docstring), and the
    (mass, inertia in hub axes, position) of a folded body. ``mount`` carries the chain held
    inextensible, ``given`` the chain as given."""
    chain = mount.appendage
    if not getattr(chain, "three_axis", False):
        raise BasiliskModelError(
            f"chain {name!r} on a three-axis spacecraft has no torsion (torsional_inertias "
            "None): fit a three-axis chain (appendages.fit_chain_3d)")
    n = int(chain.n_bodies)
    lengths = np.asarray(chain.lengths, dtype=float)
    masses = np.asarray(chain.masses, dtype=float)
    offsets = np.asarray(chain.com_offsets, dtype=float)
    principal = np.column_stack([chain.torsional_inertias, chain.inertias_y, chain.inertias])
    n_hinges = n - 1 if chain.root == "rigid" else n
    motions = [("z", np.asarray(chain.hinge_stiffnesses, dtype=float),
                _optional(chain.hinge_dampings, n_hinges)),
               ("y", np.asarray(chain.hinge_stiffnesses_y, dtype=float),
                _optional(chain.hinge_dampings_y, n_hinges))]
    if chain.torsion_stiffnesses is not None:
        motions.append(("x", np.asarray(chain.torsion_stiffnesses, dtype=float),
                        _optional(chain.torsion_dampings, n_hinges)))
    R, p = mount.orientation, mount.point
    folded, first, hinge = [], 0, p
    if chain.root == "rigid":
        folded.append((float(masses[0]), R @ np.diag(principal[0]) @ R.T,
                       p + offsets[0] * R[:, 0]))
        hinge = p + lengths[0] * R[:, 0]
        first = 1
    bodies = []
    for i in range(first, n):
        for axis, J in zip("xyz", principal[i]):
            _check_body_inertia(name, i, J, axis)
        h = i - first  # hinge index of this body (its hinge to the parent)
        for j, (axis, springs, dampers) in enumerate(motions):
            carrier = j == len(motions) - 1  # the last of the joint's bodies is the body
            if j > 0:
                r_SP_P, dcm_S0P = np.zeros(3), np.eye(3)
            elif i == first:
                r_SP_P, dcm_S0P = hinge.copy(), R.T.copy()
            else:
                r_SP_P, dcm_S0P = np.array([lengths[i - 1], 0.0, 0.0]), np.eye(3)
            bodies.append(BodyLayout(
                mass=float(masses[i]) if carrier else 0.0,
                ISPntSc_S=np.diag(principal[i]) if carrier else np.zeros((3, 3)),
                r_SP_P=r_SP_P, dcm_S0P=dcm_S0P,
                r_ScS_S=np.array([offsets[i] if carrier else 0.0, 0.0, 0.0]),
                k=float(springs[h]), c=float(dampers[h]),
                length=float(lengths[i]) if carrier else 0.0, spin_axis=axis))
    held = ()
    axial = torsion = None
    if getattr(given, "axial_stiffnesses", None) is not None:
        held, axial = ("axial",), _axial_frequency(given)
    if chain.torsion_stiffnesses is None and getattr(given, "torsion_stiffnesses",
                                                     None) is not None:
        held, torsion = held + ("torsion",), torsion_frequency(given)
    raised = tuple(_body_inertias(given)[1]) if getattr(given, "three_axis", False) else ()
    return (AppendageLayout(name, mount, chain, tuple(bodies), len(folded), held, axial,
                            raised, torsion), folded)


def _raised_message(entry: AppendageLayout) -> str:
    planes = {"x": "torsion", "y": "x-z bending", "z": "x-y bending"}
    what = ", ".join(f"body {i} J_{axis} + {added:.3g} kg*m^2 ({planes[axis]})"
                     for i, axis, added in entry.raised_inertias)
    return (f"chain {entry.name!r}: Basilisk accepts only a body's inertia (largest principal "
            f"moment at most the sum of the other two), which the chain's are not (a beam "
            f"model's torsional inertia without the section's rotary inertia in bending); "
            f"Basilisk and the linear chain it is compared with carry {what}, the stiffer "
            "motion of each body, whose modes it moves least")


def layout(spacecraft: Spacecraft, *, chains: Mapping | None = None,
           rigid_above: float | None = None) -> SpacecraftLayout:
    """Basilisk parameters of a flexsat spacecraft whose appendages are chains.

    Parameters
    ----------
    spacecraft : Spacecraft
        Planar, or three-axis (hub with an inertia tensor, three-axis chains), with mounted
        appendages.
    chains : mapping name -> HingedChain, optional
        Chains replacing appendages that are not chains (see :func:`chain_spacecraft`).
    rigid_above : float, rad/s, optional
        Three axes: hold rigid every chain's torsion whose first frequency (root held) is
        above it (module docstring, "Stiff torsion"); None holds none.

    Returns
    -------
    SpacecraftLayout

    Raises
    ------
    BasiliskModelError
        A non-chain appendage without replacement, a body Basilisk cannot represent (zero
        inertia), a planar hub with a mount that is not planar.

    Warns
    -----
    BasiliskModelWarning
        A three-axis chain whose bodies' moments had to be made a body's (module docstring,
        "Bodies").
    """
    if not isinstance(spacecraft, Spacecraft):
        raise TypeError(f"spacecraft must be a flexsat Spacecraft; got {type(spacecraft).__name__}")
    sc = chain_spacecraft(spacecraft, chains, rigid_above=rigid_above)
    hub = sc.hub
    appendages, folded = [], []
    if sc.three_axis:
        originals = {name: dict(chains or {}).get(name, mount.appendage)
                     for name, mount in zip(spacecraft.names, spacecraft.mounts)}
        for name, mount in zip(sc.names, sc.mounts):
            entry, rigid = _appendage_3d(name, mount, originals[name])
            appendages.append(entry)
            folded += rigid
            if entry.raised_inertias:
                warnings.warn(_raised_message(entry), BasiliskModelWarning, stacklevel=2)
        inertia_hub = np.asarray(hub.inertia, dtype=float)
    else:
        for name, mount in zip(sc.names, sc.mounts):
            if np.shape(mount.position) != (2,):
                raise BasiliskModelError(f"mount {name!r}: the Basilisk adapter is planar; the "
                                         f"mount position must be (x, y) [m]; got "
                                         f"{mount.position!r}")
            entry, rigid = _appendage(name, mount)
            appendages.append(entry)
            folded += rigid
        inertia_hub = hub.inertia * np.eye(3)
    mass = hub.mass + sum(m for m, _, _ in folded)
    centre = sum((m * r for m, _, r in folded), np.zeros(3)) / mass
    inertia = inertia_hub + _parallel_axis(hub.mass, -centre)
    for m, J, r in folded:
        inertia += J + _parallel_axis(m, r - centre)
    hub_layout = HubLayout(mHub=float(mass), r_BcB_B=centre,
                           IHubPntBc_B=0.5 * (inertia + inertia.T))
    return SpacecraftLayout(hub_layout, tuple(appendages), sc)
