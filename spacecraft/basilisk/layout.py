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
from collections.abc import Mapping

import numpy as np

from ..dynamics.coupling import Spacecraft
from ..dynamics.hub import Mount
from .install import BasiliskModelError

__all__ = ["BodyLayout", "AppendageLayout", "HubLayout", "SpacecraftLayout", "layout",
           "chain_spacecraft"]

_CHAIN_ATTRIBUTES = ("lengths", "masses", "inertias", "hinge_stiffnesses", "com_offsets", "root")


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
        Hinge to the next hinge (or the free end).
    """

    mass: float
    ISPntSc_S: np.ndarray
    r_SP_P: np.ndarray
    dcm_S0P: np.ndarray
    r_ScS_S: np.ndarray
    k: float
    c: float
    length: float


@dataclasses.dataclass(frozen=True)
class AppendageLayout:
    """A flexsat chain as Basilisk spinning bodies.

    Attributes
    ----------
    name : str
        flexsat's mount name (signal prefix of ``<name>_tip_deflection``).
    mount : Mount
    chain : HingedChain
    bodies : tuple of BodyLayout
        The spinning bodies, root first (empty when a one-body chain is rigidly mounted).
    n_folded : int
        Bodies folded into the hub (1 for ``root="rigid"``, else 0).
    """

    name: str
    mount: Mount
    chain: object
    bodies: tuple
    n_folded: int

    def tip_deflection(self, angles) -> np.ndarray:
        """Transverse tip deflection [m] from Basilisk's relative spin angles.

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
        angles = np.asarray(angles, dtype=float)
        lengths = np.array([b.length for b in self.bodies])
        if angles.ndim != 2 or angles.shape[1] != lengths.size:
            raise ValueError(f"angles must have shape (n_samples, {lengths.size}) [rad]; got "
                             f"{angles.shape}")
        return np.sin(np.cumsum(angles, axis=1)) @ lengths


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
        flexsat's linear model of the same hub and chains (the comparison's plant).
    """

    hub: HubLayout
    appendages: tuple
    spacecraft: Spacecraft

    @property
    def n_bodies(self) -> int:
        """Spinning bodies in all effectors."""
        return sum(len(a.bodies) for a in self.appendages)


def _parallel_axis(mass: float, d: np.ndarray) -> np.ndarray:
    """m (|d|^2 E - d d^T): inertia of a point mass m at d about the origin [kg*m^2]."""
    return mass * (float(d @ d) * np.eye(3) - np.outer(d, d))


def _planar_rotation(angle: float) -> np.ndarray:
    """dcm_S0P of a frame rotated by ``angle`` about +z: rows are its axes in parent axes."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def _is_chain(appendage) -> bool:
    return all(hasattr(appendage, a) for a in _CHAIN_ATTRIBUTES)


def chain_spacecraft(spacecraft: Spacecraft, chains: Mapping | None = None) -> Spacecraft:
    """The spacecraft with appendages replaced by chains, by mount name.

    Parameters
    ----------
    spacecraft : Spacecraft
    chains : mapping name -> HingedChain, optional
        Replacements (e.g. the chain a scene fits to a beam). Appendages not named must already
        be chains.

    Returns
    -------
    Spacecraft
        ``spacecraft`` itself when nothing is replaced (its computed modes are reused).

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
    chains = {} if chains is None else dict(chains)
    unknown = sorted(set(chains) - set(spacecraft.names))
    if unknown:
        raise BasiliskModelError(f"chains names {unknown} are not mounts of the spacecraft; its "
                                 f"mounts are {spacecraft.names}")
    for name, chain in chains.items():
        if not _is_chain(chain):
            raise BasiliskModelError(f"chains[{name!r}] must be a HingedChain; got "
                                     f"{type(chain).__name__}")
    mounts = []
    for name, mount in zip(spacecraft.names, spacecraft.mounts):
        appendage = chains.get(name, mount.appendage)
        if not _is_chain(appendage):
            raise BasiliskModelError(
                f"appendage {name!r} is a {type(appendage).__name__}: Basilisk models an "
                "appendage as hinged rigid bodies, so it needs a HingedChain; fit one "
                "(appendages.equivalence.fit_chain(beam, n_bodies)) and pass "
                f"chains={{{name!r}: chain}}")
        mounts.append(Mount(appendage, mount.position, mount.angle, name=name))
    if not chains:
        return spacecraft
    return Spacecraft(spacecraft.hub, mounts)


def _appendage(name: str, mount: Mount) -> tuple[AppendageLayout, list]:
    """Spinning bodies of one chain, and the (mass, inertia, position) of a folded body."""
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
        folded.append((float(masses[0]), float(inertias[0]), p + offsets[0] * e))
        hinge = p + lengths[0] * e
        first = 1
    bodies = []
    for i in range(first, n):
        if not inertias[i] > 0.0:
            raise BasiliskModelError(
                f"chain {name!r}: body {i + 1} has inertia {float(inertias[i])!r} [kg*m^2] about "
                "its centre of mass; Basilisk's spinningBodyNDOFStateEffector needs a positive "
                "definite inertia tensor for every body with mass (a point-mass body cannot be "
                "represented): give it a positive inertia")
        h = i - first  # hinge index of this body (its hinge to the parent)
        parent_hinge = hinge if i == first else np.array([lengths[i - 1], 0.0, 0.0])
        bodies.append(BodyLayout(
            mass=float(masses[i]), ISPntSc_S=float(inertias[i]) * np.eye(3),
            r_SP_P=parent_hinge.copy(),
            dcm_S0P=_planar_rotation(mount.angle) if i == first else np.eye(3),
            r_ScS_S=np.array([offsets[i], 0.0, 0.0]),
            k=float(stiffnesses[h]), c=float(dampings[h]), length=float(lengths[i])))
    return AppendageLayout(name, mount, chain, tuple(bodies), len(folded)), folded


def layout(spacecraft: Spacecraft, *, chains: Mapping | None = None) -> SpacecraftLayout:
    """Basilisk parameters of a flexsat spacecraft whose appendages are chains.

    Parameters
    ----------
    spacecraft : Spacecraft
        Planar hub with mounted appendages.
    chains : mapping name -> HingedChain, optional
        Chains replacing appendages that are not chains (see :func:`chain_spacecraft`).

    Returns
    -------
    SpacecraftLayout

    Raises
    ------
    BasiliskModelError
        A non-chain appendage without replacement, a body Basilisk cannot represent (zero
        inertia), a hub or mount that is not planar.
    """
    sc = chain_spacecraft(spacecraft, chains)
    hub = sc.hub
    if np.ndim(hub.inertia) != 0:
        raise BasiliskModelError("the Basilisk adapter is planar: the hub inertia must be the "
                                 f"scalar inertia about z [kg*m^2]; got shape {np.shape(hub.inertia)}")
    appendages, folded = [], []
    for name, mount in zip(sc.names, sc.mounts):
        if np.shape(mount.position) != (2,):
            raise BasiliskModelError(f"mount {name!r}: the Basilisk adapter is planar; the mount "
                                     f"position must be (x, y) [m]; got {mount.position!r}")
        entry, rigid = _appendage(name, mount)
        appendages.append(entry)
        folded += rigid
    mass = hub.mass + sum(m for m, _, _ in folded)
    centre = sum((m * r for m, _, r in folded), np.zeros(3)) / mass
    inertia = hub.inertia * np.eye(3) + _parallel_axis(hub.mass, -centre)
    for m, J, r in folded:
        inertia += J * np.eye(3) + _parallel_axis(m, r - centre)
    hub_layout = HubLayout(mHub=float(mass), r_BcB_B=centre,
                           IHubPntBc_B=0.5 * (inertia + inertia.T))
    return SpacecraftLayout(hub_layout, tuple(appendages), sc)
