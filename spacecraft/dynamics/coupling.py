r"""A rigid hub coupled to appendages through their W-matrix interface, planar or three-axis.

Planar motion: the hub has coordinates ``h = (X, Y, theta)`` (its centre of mass and attitude).
Each appendage i is mounted at point p_i along the unit vector e_i (normal n_i); its attachment
end follows the hub rigidly,

    (axial_i, delta_i, phi_i) = G_i h        (Mount.kinematics)

Three axes: the hub has ``h = (X, Y, Z, theta_x, theta_y, theta_z)`` (centre of mass, small
rotation vector, hub axes) and each appendage's root motions in its own axes are
``(u, v, w, theta_x, theta_y, theta_z)_i = G_i h`` with the 6x6 ``G_i = Mount.transformation()``
(:mod:`spacecraft.dynamics.kinematics`); the appendage's axial motion is one of its root coordinates.

Finite appendages (realisation in attachment-end coordinates, RootModel)
    The appendage's root coordinates (2 planar, 6 in three axes) are replaced by their
    kinematic images of h, its internal ones kept: ``q_i = T_i [h; z_i]``. Planar axial motion
    is rigid (Euler-Bernoulli members are inextensible), a point mass m_i moving with
    ``axial_i``. The coupled second-order system is

        M = M_hub + sum_i (T_i^T M_i T_i [+ m_i g_i g_i^T planar]),  C, K likewise,

    in coordinates ``[h, z_1, z_2, ...]``, and the state-space plant is built from its
    undamped modes (mass-normalised, ``K V = M V Lambda``): states ``[eta, eta_dot]`` with
    ``A = [[0, I], [-Lambda, -V^T C V]]``, a well-scaled realisation of any size.

Distributed appendages (exact reference)
    Eliminating the appendages through ``D_i = W_i^-1`` (``W6_i^-1``) gives the hub's dynamic
    stiffness Z(s), the exact attitude response and, by the Wittrick-Williams count, the exact
    coupled natural frequencies: :mod:`spacecraft.dynamics.exact`.

References
----------
.. [1] P. W. Likins, "Dynamics and control of flexible space vehicles", JPL TR 32-1329, 1970.
.. [2] W. H. Wittrick, F. W. Williams, "A general algorithm for computing natural frequencies of
   elastic structures", Q. J. Mech. Appl. Math. 24(3), 1971.
.. [3] Belonozhko et al. 2009 (PAPER.md), the W-matrix interface.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import scipy.linalg

from appendages import limits
from controllers.threads import SINGLE_THREAD_BELOW, one_blas_thread
from appendages.interface import ROOT_LOADS, TIP_MOTIONS, describe, equilibrate

from .exact import ExactReference, frequency_vector
from .hub import Hub, Mount

__all__ = ["Spacecraft", "SecondOrderModel", "HUB_COORDINATES", "PRUNE_SAFETY"]

#: Hub coordinates: planar and three-axis.
HUB_COORDINATES = {False: ("X", "Y", "theta"),
                   True: ("X", "Y", "Z", "theta_x", "theta_y", "theta_z")}
_HUB_NAMES = HUB_COORDINATES[False]
_AXES = ("x", "y", "z")

#: ``Spacecraft.plant(prune=True)`` keeps a mode whose drive by the inputs, sight by the
#: outputs or damping coupling to a kept mode is above this many times the round-off that the
#: computed modes give an exact zero (:func:`_mode_mixing`); below it the value is not told
#: from zero to one digit. Measured on twin solar-array wings (the three-axis example scene,
#: 1 to 10 modes a beam, two OpenBLAS kernels): exact zeros came out at 0.001 to 1.4 times the
#: estimate, true drives and couplings at 150 to 1e9 times it.
PRUNE_SAFETY = 10.0


@dataclasses.dataclass(frozen=True)
class SecondOrderModel:
    """Assembled ``M z'' + C z' + K z = F u`` of hub and finite appendages.

    Attributes
    ----------
    mass, damping, stiffness : ndarray (n, n)
    coordinate_names : tuple of str
        The hub's coordinates first (:data:`HUB_COORDINATES`), then each appendage's internal
        ones.
    blocks : list of (Mount, ndarray)
        For each mount the matrix T_i with ``q_i = T_i z`` (appendage coordinates from the
        global ones).
    """

    mass: np.ndarray
    damping: np.ndarray
    stiffness: np.ndarray
    coordinate_names: tuple
    blocks: list


class Spacecraft:
    """Rigid hub with appendages mounted on it, planar or three-axis.

    Parameters
    ----------
    hub : Hub
        A scalar inertia: the planar spacecraft; a 3x3 tensor: three axes.
    mounts : sequence of Mount
        Any number (zero for a rigid spacecraft) of appendages of any model that offers the
        W-matrix interface (three axes: ``W6``, finite models ``root_model(6)``). On a
        three-axis hub, planar mounts lie in its x-y plane.

    Attributes
    ----------
    three_axis : bool
    n_rigid : int
        Rigid-body modes of the free-floating spacecraft: 3 planar, 6 in three axes.
    """

    def __init__(self, hub: Hub, mounts=()):
        if not isinstance(hub, Hub):
            raise TypeError(f"hub must be a Hub; got {type(hub).__name__}")
        if isinstance(mounts, Mount):
            raise TypeError("mounts must be a sequence of Mount; got a single Mount (put it "
                            "in a list: [mount])")
        if mounts is None or isinstance(mounts, (str, bytes)) or not hasattr(mounts, "__iter__"):
            raise TypeError(f"mounts must be a sequence of Mount; got {type(mounts).__name__} "
                            f"{describe(mounts)}")
        if hasattr(mounts, "__len__"):
            limits.check("mounts (number of appendages)", len(mounts), "appendages",
                         "appendages per spacecraft")
        mounts = list(mounts)
        limits.check("mounts (number of appendages)", len(mounts), "appendages",
                     "appendages per spacecraft")
        for k, mount in enumerate(mounts):
            if not isinstance(mount, Mount):
                raise TypeError(f"mounts[{k}] must be a Mount; got {type(mount).__name__}")
        names = [m.name or f"appendage{k + 1}" for k, m in enumerate(mounts)]
        if len(set(names)) != len(names):
            raise ValueError(f"mount names must be unique; got {names}")
        self.three_axis = bool(hub.three_axis)
        for name, mount in zip(names, mounts):
            if mount.three_axis and not self.three_axis:
                raise ValueError(
                    f"mount '{name}' has an orientation (three axes) but the hub is planar "
                    f"(inertia {describe(hub.inertia)} kg*m^2, a scalar): give the hub a 3x3 "
                    "inertia tensor [kg*m^2] or the mount a planar direction")
            if self.three_axis and not mount.three_axis:
                self._check_three_axis_appendage(name, mount.appendage)
            if not self.three_axis:
                self._warn_off_axis_in_plane(name, mount.appendage)
        self.hub = hub
        self.mounts = mounts
        self.names = names
        self.n_rigid = 6 if self.three_axis else 3
        self._cache: dict = {}

    @staticmethod
    def _check_three_axis_appendage(name: str, appendage) -> None:
        if not hasattr(appendage, "W6"):
            raise TypeError(f"mount '{name}': a three-axis spacecraft needs appendages with "
                            f"W6(s); got {type(appendage).__name__} without 'W6'")
        try:
            appendage.inertia_tensor
        except ValueError as exc:
            raise ValueError(f"mount '{name}' on a three-axis hub: {exc}") from None

    @staticmethod
    def _warn_off_axis_in_plane(name: str, appendage) -> None:
        """Warn of an appendage whose centre of mass lies off its axis in the plane: the
        planar coupling moves its root's axial motion rigidly, without the coupling of that
        motion to rotation which the offset brings (exact in three axes)."""
        vector = getattr(appendage, "center_of_mass_vector", None)
        if vector is None:
            return
        try:
            c = np.asarray(vector, dtype=float)
        except ValueError:
            return
        if c.shape == (3,) and abs(c[1]) > 1e-6 * max(abs(c[0]), 1e-300):
            warnings.warn(
                f"mount '{name}': the appendage's centre of mass lies {c[1]:.3g} m off its "
                "axis in the plane (along its y); a planar spacecraft carries its axial motion "
                "as rigid, without the coupling to rotation this offset brings: the rigid "
                "properties are exact, the planar dynamics are not (use a three-axis hub)",
                UserWarning, stacklevel=3)

    def __repr__(self) -> str:
        return f"Spacecraft({self.hub!r}, {self.mounts!r})"

    @property
    def exact(self) -> ExactReference:
        """The exact frequency-domain reference (:mod:`spacecraft.dynamics.exact`), built once."""
        cached = self._cache.get("exact")
        if cached is None:
            cached = self._cache["exact"] = ExactReference(self.hub, self.mounts)
        return cached

    # -- rigid properties ---------------------------------------------------------------------
    @property
    def mass(self) -> float:
        """Total mass [kg]."""
        return self.hub.mass + sum(m.appendage.mass for m in self.mounts)

    @property
    def center_of_mass(self) -> np.ndarray:
        """Centre of mass of the undeformed spacecraft in hub axes [m] (2 or 3 coordinates).

        Each appendage's centre is its own ``center_of_mass_vector`` (from its root, in its
        axes: a tip body offset across the axis moves it off the axis), else its
        ``center_of_mass`` along its axis, else mid-length (a uniform body).
        """
        moment = np.zeros(3 if self.three_axis else 2)
        for mount in self.mounts:
            moment += mount.appendage.mass * self.appendage_center(mount)
        return moment / self.mass

    def appendage_center(self, mount: Mount) -> np.ndarray:
        """Centre of mass of the undeformed appendage on ``mount`` in hub axes [m].

        Parameters
        ----------
        mount : Mount
            One of this spacecraft's mounts.

        Returns
        -------
        ndarray, shape (2,) planar or (3,) three-axis, m
            ``p + R c``: the mount point ``p`` plus the appendage's centre ``c`` (appendage
            axes, from its root) turned into hub axes by the mount's orientation ``R``. In
            the plane the out-of-plane coordinate of ``c`` does not enter.
        """
        a = mount.appendage
        vector = getattr(a, "center_of_mass_vector", None)
        if vector is not None:
            c = np.asarray(vector, dtype=float)
        else:
            distance = getattr(a, "center_of_mass", None)
            c = np.array([0.5 * a.length if distance is None else float(distance), 0.0, 0.0])
        if self.three_axis:
            return mount.point + mount.orientation @ c
        return mount.position + c[0] * mount.axis + c[1] * mount.normal

    @property
    def inertia(self):
        """Inertia of the undeformed spacecraft about its centre of mass [kg*m**2].

        Planar: the moment of inertia about +z (a float). Three axes: the 3x3 tensor in hub
        axes, ``J_hub + sum R J_i R^T`` plus the parallel-axis terms
        ``m (|d|**2 I - d d^T)``, ``d`` from the spacecraft's centre of mass to each body's
        (:meth:`appendage_center`; each appendage's inertia is about its own centre).
        """
        c = self.center_of_mass
        if not self.three_axis:
            J = self.hub.inertia + self.hub.mass * float(c @ c)
            for mount in self.mounts:
                d = self.appendage_center(mount) - c
                J += mount.appendage.inertia + mount.appendage.mass * float(d @ d)
            return J

        def parallel(m, d):
            return m * (float(d @ d) * np.eye(3) - np.outer(d, d))

        J = self.hub.inertia + parallel(self.hub.mass, -c)
        for mount in self.mounts:
            R = mount.orientation
            J = J + R @ mount.appendage.inertia_tensor @ R.T
            J = J + parallel(mount.appendage.mass, self.appendage_center(mount) - c)
        return 0.5 * (J + J.T)

    # -- finite assembly ----------------------------------------------------------------------
    def _root_kinematics(self, mount: Mount):
        """(G_root, axial row or None): root coordinates of the appendage from hub motion."""
        if self.three_axis:
            return mount.transformation(), None
        G = mount.kinematics()
        return G[1:], G[0]

    def second_order_model(self) -> SecondOrderModel:
        """Assemble M, C, K of hub and appendages (all appendages must be finite models)."""
        cached = self._cache.get("second_order")
        if cached is not None:
            return cached
        n_root = 6 if self.three_axis else 2
        n_hub = 6 if self.three_axis else 3
        models = []
        for name, mount in zip(self.names, self.mounts):
            if not hasattr(mount.appendage, "root_model"):
                raise TypeError(
                    f"appendage '{name}' ({type(mount.appendage).__name__}) has no finite "
                    "realisation (root_model); use a truncated model, e.g. beam.truncated(n_modes), "
                    "or the exact frequency-domain methods"
                )
            try:
                models.append(mount.appendage.root_model() if n_root == 2
                              else mount.appendage.root_model(6))
            except ValueError as exc:
                raise ValueError(f"appendage '{name}': {exc}") from None
        n = n_hub + sum(rm.n - n_root for rm in models)
        limits.check(f"the appendages' coordinates ({n_hub} + their internal ones)", n,
                     "coordinates", "coordinates of the assembled model")
        M = np.zeros((n, n))
        M[:n_hub, :n_hub] = self.hub.mass_matrix
        C = np.zeros((n, n))
        K = np.zeros((n, n))
        names = list(HUB_COORDINATES[self.three_axis])
        blocks = []
        offset = n_hub
        for name, mount, rm in zip(self.names, self.mounts, models):
            G, axial = self._root_kinematics(mount)
            T = np.zeros((rm.n, n))
            T[:n_root, :n_hub] = G
            T[n_root:, offset:offset + rm.n - n_root] = np.eye(rm.n - n_root)
            M += T.T @ rm.mass @ T
            if axial is not None:  # planar: the appendage's rigid axial motion
                g = np.zeros(n)
                g[:n_hub] = axial
                M += mount.appendage.mass * np.outer(g, g)
            C += T.T @ rm.damping @ T
            K += T.T @ rm.stiffness @ T
            names += [f"{name}.{c}" for c in rm.coordinate_names[n_root:]]
            blocks.append((mount, T))
            offset += rm.n - n_root
        model = SecondOrderModel(0.5 * (M + M.T), 0.5 * (C + C.T), 0.5 * (K + K.T), tuple(names), blocks)
        self._cache["second_order"] = model
        return model

    # -- modes and the state-space plant ------------------------------------------------------
    def modes(self):
        """Undamped modes of the assembled finite model (computed once).

        Returns
        -------
        frequencies : ndarray (n,), rad/s
            Ascending; the rigid-body modes (3 planar: X, Y, theta; 6 in three axes) are
            exactly 0.
        shapes : ndarray (n, n)
            Mass-normalised mode shapes in the assembled coordinates (columns).

        See Also
        --------
        frequencies : the frequencies alone, without the shapes (cheaper).
        """
        cached = self._cache.get("modes")
        if cached is None:
            model = self.second_order_model()
            r = self.n_rigid
            K, M, d = self._equilibrated_pencil()
            lam, V = scipy.linalg.eigh(K, M)
            V = V * d[:, None]
            lam = self._elastic_eigenvalues(lam)
            V = V.copy()
            V[:, :r] = self._rigid_modes(V[:, :r], model.mass)
            # each elastic mode's sign fixed (the solver's is its rounding's: the states of a
            # modal plant, and the gains on them, would change sign from one CPU to another):
            # its first coordinate above 1e-3 of its largest is positive
            E = V[:, r:]
            if E.size:
                first = np.argmax(np.abs(E) > 1e-3 * np.abs(E).max(axis=0), axis=0)
                V[:, r:] = E * np.where(E[first, np.arange(E.shape[1])] < 0, -1.0, 1.0)
            cached = (np.sqrt(lam), V)
            self._cache["modes"] = cached
        return cached[0].copy(), cached[1]

    def frequencies(self) -> np.ndarray:
        """Undamped natural frequencies of the assembled finite model, without its mode shapes
        (computed once).

        The eigenvalues alone of the pencil that :meth:`modes` solves (LAPACK without the
        eigenvectors, and no rigid-body shapes or signs to fix: what a frequency grid needs,
        at a fraction of the cost). They agree with :meth:`modes` to rounding, not bit for
        bit (without the eigenvectors LAPACK finishes the tridiagonal problem another way),
        and are those of :meth:`modes` once it has been computed.

        Returns
        -------
        ndarray (n,), rad/s
            Ascending; the rigid-body modes (3 planar, 6 in three axes) exactly 0.

        Raises
        ------
        ValueError
            The stiffness matrix has more than the rigid-body zero or negative eigenvalues
            (as :meth:`modes`).
        """
        modes = self._cache.get("modes")
        if modes is not None:
            return modes[0].copy()
        cached = self._cache.get("frequencies")
        if cached is None:
            K, M, _ = self._equilibrated_pencil()
            lam = self._elastic_eigenvalues(scipy.linalg.eigh(K, M, eigvals_only=True))
            cached = self._cache["frequencies"] = np.sqrt(lam)
        return cached.copy()

    def _equilibrated_pencil(self):
        """(K', M', d): the assembled stiffness and mass, equilibrated (unit-free: hub
        coordinates in m and rad, appendage ones in their own units; K' = d K d, M' = d M d,
        eigenvalues unchanged, eigenvectors those of (K, M) divided by d)."""
        model = self.second_order_model()
        d = equilibrate(model.stiffness, model.mass)
        dd = np.outer(d, d)
        return model.stiffness * dd, model.mass * dd, d

    def _elastic_eigenvalues(self, lam: np.ndarray) -> np.ndarray:
        """The pencil's ascending eigenvalues [rad^2/s^2] with the rigid-body ones exactly 0,
        checked: every other one positive."""
        # A free-floating spacecraft has exactly n_rigid rigid-body modes (3 planar, 6 in
        # three axes); every hinge/bending stiffness is positive, so the rest are elastic.
        r = self.n_rigid
        lam[:r] = 0.0
        if np.any(lam[r:] <= 0.0):
            raise ValueError(
                f"the assembled stiffness matrix has more than {r} zero or negative "
                "eigenvalues: the stiffness range is too wide for double precision "
                f"(smallest elastic eigenvalue {lam[r]!r}, largest {lam[-1]!r} [rad^2/s^2])"
            )
        return lam

    @staticmethod
    def _rigid_modes(R: np.ndarray, M: np.ndarray) -> np.ndarray:
        """Physical rigid-body modes from any basis R of the null space of K.

        Within span(R), the motions with unit hub displacements (the hub block of R is
        invertible) are unique; the translations are M-orthogonal to each other (a rigid
        translation carries the total mass), and the rotations are made M-orthogonal to them
        by Gram-Schmidt, which turns them into rotations about the system's centre of mass.
        Planar (3 modes): [x translation, y translation, rotation], mass-normalised; torque
        excites only the last, and theta sees only the last. Three axes (6 modes): the three
        translations, then the rotations about the principal axes of the spacecraft's inertia
        at its centre of mass (the eigenvectors of the rotations' 3x3 mass matrix), each
        mass-normalised.
        """
        r = R.shape[1]
        physical = R @ np.linalg.solve(R[:r, :r], np.eye(r))
        # the hub block is the identity by construction: exactly, so that a translation has
        # no rotation of the hub at all (round-off there, ~1e-20, would couple an unreached
        # double integrator into the attitude loop and split its poles at 0 by ~sqrt of it)
        physical[:r] = np.eye(r)
        if r == 3:
            tx, ty, rot = physical.T
            for t in (tx, ty):
                rot = rot - (t @ M @ rot) / (t @ M @ t) * t
            modes = np.column_stack([tx, ty, rot])
            return modes / np.sqrt(np.einsum("ij,ik,kj->j", modes, M, modes))
        translations, rotations = physical[:, :3], physical[:, 3:].copy()
        for t in translations.T:
            rotations -= np.outer(t, (t @ M @ rotations) / (t @ M @ t))
        inertia = rotations.T @ M @ rotations
        _, principal = np.linalg.eigh(0.5 * (inertia + inertia.T))
        rotations = rotations @ principal
        modes = np.column_stack([translations, rotations])
        return modes / np.sqrt(np.einsum("ij,ik,kj->j", modes, M, modes))

    def natural_frequencies(self, n: int, *, exact: bool | None = None) -> np.ndarray:
        """First n coupled elastic natural frequencies [rad/s] (rigid-body modes left out).

        Parameters
        ----------
        n : int
            Number of frequencies.
        exact : bool, optional
            True: roots of the coupled characteristic equation through each appendage's exact
            W(s) (W6 in three axes; Wittrick-Williams count and bisection,
            :mod:`spacecraft.dynamics.exact`); the accuracy reference for truncated models of a
            distributed beam. False: eigenvalues of the assembled finite model. Default:
            exact when some appendage has no finite realisation.

        Raises
        ------
        LimitError
            ``exact`` and n above the ``frequencies`` limit of :mod:`appendages.limits` (100000:
            the bisection costs O(n) per appendage and step, 5 s for 1e5 on one rod, 26 s on
            eight; raise it with ``appendages.limits.raised(frequencies=...)``).
        ValueError
            n larger than the finite model's number of elastic modes.
        """
        if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)):
            raise TypeError(f"n must be an integer (number of frequencies); got "
                            f"{type(n).__name__} {describe(n)}")
        if n < 1:
            raise ValueError(f"n must be a positive integer (number of frequencies); got {describe(n)}")
        if exact is not None and not isinstance(exact, (bool, np.bool_)):
            raise TypeError(f"exact must be True, False or None; got {describe(exact)}")
        finite = all(hasattr(m.appendage, "root_model") for m in self.mounts)
        if exact is None:
            exact = not finite
        if not self.mounts:
            raise ValueError("a spacecraft without appendages has no elastic natural frequency")
        if exact:
            limits.check("n", int(n), "frequencies", "exact coupled frequencies at once")
        if not exact:
            w, _ = self.modes()
            r = self.n_rigid
            if w.size - r < n:
                raise ValueError(f"n = {n} exceeds the {w.size - r} elastic modes of the finite "
                                 "model; ask for fewer or use exact=True")
            return w[r:r + n]
        return self.exact.frequencies(n)

    def _signals(self, disturbances: bool):
        """Hub inputs and attitude outputs: names, hub load columns, rotation indices."""
        if not self.three_axis:
            inputs, columns = ["torque"], [2]
            if disturbances:
                inputs += ["disturbance_torque", "force_x", "force_y"]
                columns += [2, 0, 1]
            return inputs, columns, ["theta"], ["omega"], [2]
        inputs = [f"torque_{a}" for a in _AXES]
        columns = [3, 4, 5]
        if disturbances:
            inputs += [f"disturbance_torque_{a}" for a in _AXES] + [f"force_{a}" for a in _AXES]
            columns += [3, 4, 5, 0, 1, 2]
        return (inputs, columns, [f"theta_{a}" for a in _AXES], [f"omega_{a}" for a in _AXES],
                [3, 4, 5])

    def plant(self, *, tip_deflection: bool = False, root_loads: bool = False,
              disturbances: bool = False, n_modes: int | None = None, prune: bool = False,
              name: str = "spacecraft"):
        """Linear state-space model of the free-floating spacecraft.

        Parameters
        ----------
        tip_deflection : bool
            Planar: add outputs ``<name>_tip_deflection`` [m] (elastic, relative to the
            mount's tangent). Three axes: ``<name>_tip_deflection_y``,
            ``<name>_tip_deflection_z`` [m] and ``<name>_tip_twist`` [rad] (elastic, relative
            to the rigidly moving root section, the appendage's axes). Modal data without tip
            motion (``has_tip_motion`` False) give zero rows: a UserWarning says so.
        root_loads : bool
            Planar: add outputs ``<name>_root_force`` [N] and ``<name>_root_moment`` [N*m], the
            load the hub applies to each appendage at its attachment end (F_y, M of PAPER.md).
            Three axes: ``<name>_root_force_x/_y/_z`` [N] and ``<name>_root_moment_x/_y/_z``
            [N*m] in the appendage's axes.
        disturbances : bool
            Planar: add inputs ``disturbance_torque`` [N*m] (on the hub, apart from the
            actuator's ``torque``), ``force_x``, ``force_y`` [N] (at the hub's centre of mass,
            hub axes) and ``<name>_tip_force`` [N] (transverse, at each appendage's free end).
            Three axes: ``disturbance_torque_x/_y/_z``, ``force_x/_y/_z`` and
            ``<name>_tip_force_y``, ``<name>_tip_force_z`` (along the appendage's y and z axes).
        n_modes : int, optional
            Keep only the rigid-body modes and the first ``n_modes`` coupled elastic modes.
        prune : bool
            Drop modes that no input excites and no output sees (e.g. the symmetric bending of
            two symmetric wings under pure torque); the input-output behaviour is unchanged. A
            drive or sight within ``PRUNE_SAFETY`` times the round-off of the computed modes
            counts as none, so the modes kept do not depend on the CPU's rounding.

        Returns
        -------
        control.StateSpace
            Planar: inputs ``torque`` [N*m] (+ disturbances), outputs ``theta`` [rad],
            ``omega`` [rad/s] (+ requested). Three axes: inputs ``torque_x``, ``torque_y``,
            ``torque_z``, outputs ``theta_x/_y/_z`` [rad] (small-angle attitude, hub axes),
            ``omega_x/_y/_z`` [rad/s] (+ requested). States ``mode[k]``, ``mode_rate[k]``
            (modal coordinates).

        Notes
        -----
        Built with one BLAS thread up to ``controllers.threads.SINGLE_THREAD_BELOW``
        coordinates (the appendages' root models and their assembly always): for these small
        matrices OpenBLAS's threads cost more than they compute, and they keep spinning
        after the call, taking a core from what runs next (measured on the three-axis
        example of ``benchmarks/three_axis.py`` with the default two threads:
        ``benchmarks/results/lqr_simulate_speed.md``).
        """
        arguments = dict(tip_deflection=tip_deflection, root_loads=root_loads,
                         disturbances=disturbances, n_modes=n_modes, prune=prune, name=name)
        with one_blas_thread():
            if self.second_order_model().mass.shape[0] < SINGLE_THREAD_BELOW:
                return self._plant(**arguments)
        return self._plant(**arguments)        # a large model: the caller's BLAS threads

    def _plant(self, *, tip_deflection: bool, root_loads: bool, disturbances: bool,
               n_modes: int | None, prune: bool, name: str):
        """:meth:`plant`, within its BLAS-thread limit."""
        import control

        model = self.second_order_model()
        w, V = self.modes()
        n = w.size
        r = self.n_rigid
        n_translations = 3 if self.three_axis else 2
        inputs, columns, theta_names, omega_names, rotation = self._signals(disturbances)
        load_columns = [np.eye(n)[:, c] for c in columns]
        outputs = theta_names + omega_names
        out_pos = [np.eye(n)[i] for i in rotation] + [np.zeros(n)] * len(rotation)
        out_vel = [np.zeros(n)] * len(rotation) + [np.eye(n)[i] for i in rotation]
        load_rows = []  # (root model, T, row) of each root-load output
        # outputs are labelled per appendage (tip, root force, root moment, next appendage...)
        # but stacked as every motion row, then every root-load row: ("motion"|"load", index)
        sources = [("motion", k) for k in range(len(outputs))]
        for label, (mount, T) in zip(self.names, model.blocks):
            rm = (mount.appendage.root_model() if not self.three_axis
                  else mount.appendage.root_model(6))
            tips = self._tip_rows(rm, mount.appendage.length)
            if (tip_deflection or disturbances) and \
                    getattr(mount.appendage, "has_tip_motion", True) is False:
                warnings.warn(
                    f"appendage {label!r}: its modal data have no tip motion "
                    "(ModalAppendage(tip_motion=...); a NASTRAN solution's tip grid): its tip "
                    "deflection outputs are zero and a tip force moves it rigidly only, "
                    "whatever its modes do", UserWarning, stacklevel=2)
            if disturbances:
                for _, force, _, absolute in tips:
                    if force is not None:
                        inputs.append(f"{label}_{force}")
                        load_columns.append(T.T @ absolute)
            if tip_deflection:
                for motion, _, relative, _ in tips:
                    outputs.append(f"{label}_{motion}")
                    sources.append(("motion", len(out_pos)))
                    out_pos.append(relative @ T)
                    out_vel.append(np.zeros(n))
            if root_loads:
                if self.three_axis:
                    labels = [f"root_{'force' if q[0] == 'F' else 'moment'}_{q[-1].lower()}"
                              for q in ROOT_LOADS]
                else:
                    labels = ["root_force", "root_moment"]
                for row, load in enumerate(labels):
                    outputs.append(f"{label}_{load}")
                    sources.append(("load", len(load_rows)))
                    load_rows.append((rm, T, row))
        F = np.column_stack(load_columns)
        keep = np.arange(n)
        if n_modes is not None:
            if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 0:
                raise ValueError(f"n_modes must be a non-negative integer; got {describe(n_modes)}")
            keep = keep[: r + n_modes]
        modal_damping = V.T @ model.damping @ V
        # damping forces vanish for rigid-body motion (C r = 0 exactly); keep round-off of
        # ~1e-17 out of the rigid rows, where it would couple the rigid-body Jordan block to
        # the elastic modes (and defeat balancing-based tests downstream)
        modal_damping[:r, :] = 0.0
        modal_damping[:, :r] = 0.0
        if not disturbances:
            # the centre of mass cannot translate without an external force: leave out the
            # translation modes (zero load from torque, unseen by theta and tip deflections)
            keep = keep[keep >= n_translations]
        Vk, lam = V[:, keep], w[keep] ** 2
        Ck = modal_damping[np.ix_(keep, keep)]
        if prune:
            # Keep a mode only if some input excites it and some output sees it, directly or
            # through damping coupling (closure of each set over the coupling graph): the
            # input-output behaviour from rest is unchanged.
            Bq = Vk.T @ F
            Cq, Cv, _ = self._output_rows(out_pos, out_vel, load_rows, Vk, lam, Ck, Bq)
            # a drive, sight or damping coupling counts only above the round-off that the
            # computed modes give an exact zero (twin appendages: the antisymmetric modes' drive
            # is zero, computed as ~1e-11 of their twins'), by PRUNE_SAFETY: else which modes
            # are kept would depend on the CPU's rounding (_mode_mixing); and above the
            # products' own round-off, 1e-12 of the scale
            mixing = _mode_mixing(lam)
            drive = np.abs(Bq).max(axis=1, initial=0)
            driven = drive > np.maximum(1e-12 * np.abs(Vk).max(axis=0) * np.abs(F).max(),
                                        PRUNE_SAFETY * (mixing @ drive))
            out_scale = max(np.abs(Cq).max(initial=0), np.abs(Cv).max(initial=0), 1e-300)
            sight = np.abs(Cq).max(axis=0, initial=0) + np.abs(Cv).max(axis=0, initial=0)
            seen = sight > np.maximum(1e-12 * out_scale, PRUNE_SAFETY * (mixing @ sight))
            # damping couples two modes when C_jk is more than round-off (symmetric wings leave
            # ~1e-12 between symmetric and antisymmetric modes)
            size = np.abs(Ck)
            spread = mixing @ size      # mixing and Ck symmetric: size @ mixing.T is its transpose
            coupled = (size - np.diag(np.diag(size))) > np.maximum(
                1e-12 * max(size.max(initial=0), 1e-300), PRUNE_SAFETY * (spread + spread.T))
            driven, seen = _closure(driven, coupled), _closure(seen, coupled)
            # modes of one (numerically) repeated frequency are one eigenspace, in a basis the
            # solver picks: kept or dropped together
            active = _whole_clusters(driven & seen, lam)
            keep, Vk, lam, Ck = keep[active], Vk[:, active], lam[active], Ck[np.ix_(active, active)]
        Bq = Vk.T @ F
        Pq, Pv, D_rows = self._output_rows(out_pos, out_vel, load_rows, Vk, lam, Ck, Bq)
        m = keep.size
        A = np.block([[np.zeros((m, m)), np.eye(m)], [-np.diag(lam), -Ck]])
        B = np.vstack([np.zeros((m, len(inputs))), Bq])
        Cmat = np.hstack([Pq, Pv])
        D = np.zeros((len(outputs), len(inputs)))
        if load_rows:
            D[-len(load_rows):] = D_rows
        # rows into the order of the labels
        order = [k if kind == "motion" else len(out_pos) + k for kind, k in sources]
        Cmat, D = Cmat[order], D[order]
        states = [f"mode[{k}]" for k in keep] + [f"mode_rate[{k}]" for k in keep]
        return control.ss(A, B, Cmat, D, inputs=inputs, outputs=outputs, states=states, name=name)

    def _tip_rows(self, rm, length: float) -> list:
        """(output name, tip-force input name or None, elastic tip row, absolute row or None).

        Planar: the tip deflection and the transverse tip force, whose work is done on the
        absolute tip displacement ``delta + L phi + elastic``. Three axes
        (:data:`~appendages.interface.TIP_MOTIONS`): the deflections along local y
        (``v(L) = v(0) + L theta_z(0) + elastic``) and z (``w(L) = w(0) - L theta_y(0) +
        elastic``) with their tip forces, and the twist (no input).
        """
        if not self.three_axis:
            absolute = rm.tip.copy()
            absolute[0] += 1.0
            absolute[1] += length
            return [("tip_deflection", "tip_force", rm.tip, absolute)]
        tip = rm.tip_rows
        y_abs = tip[0].copy()
        y_abs[1] += 1.0
        y_abs[5] += length
        z_abs = tip[1].copy()
        z_abs[2] += 1.0
        z_abs[4] -= length
        return [(TIP_MOTIONS[0], "tip_force_y", tip[0], y_abs),
                (TIP_MOTIONS[1], "tip_force_z", tip[1], z_abs),
                (TIP_MOTIONS[2], None, tip[2], None)]

    @staticmethod
    def _output_rows(out_pos, out_vel, load_rows, Vk, lam, Ck, Bq):
        """Output matrices on modal displacements and velocities, and root-load feedthrough.

        A root load is ``e_r^T (M_i q_i'' + C_i q_i' + K_i q_i)`` with ``q_i = T_i V eta`` and
        ``eta'' = -Lambda eta - C_modal eta' + B_modal u``.
        """
        Pq = np.array(out_pos) @ Vk
        Pv = np.array(out_vel) @ Vk
        D_rows = np.zeros((len(load_rows), Bq.shape[1]))
        if load_rows:
            rows_q, rows_v = [], []
            for k, (rm, T, row) in enumerate(load_rows):
                mrow = rm.mass[row] @ T @ Vk
                rows_q.append(rm.stiffness[row] @ T @ Vk - mrow * lam)
                rows_v.append(rm.damping[row] @ T @ Vk - mrow @ Ck)
                D_rows[k] = mrow @ Bq
            Pq = np.vstack([Pq, rows_q])
            Pv = np.vstack([Pv, rows_v])
        return Pq, Pv, D_rows

    # -- exact frequency-domain reference -------------------------------------------------------
    def _hub_dynamic_stiffness(self, s: np.ndarray, *, undamped: bool = False) -> np.ndarray:
        """Z(s) of the hub with every appendage eliminated (:mod:`spacecraft.dynamics.exact`)."""
        return self.exact.hub_dynamic_stiffness(s, undamped=undamped)

    def frequency_response(self, omega, *, output: str = "theta"):
        """Exact frequency response from the hub torque(s) through every appendage's W (W6).

        The attitude response is the rotation block of the inverse of the hub's dynamic
        stiffness Z(s), every appendage eliminated through its W (W6): derived, with its rigid
        limit, in :meth:`spacecraft.dynamics.exact.ExactReference.attitude_compliance`.
        Vectorised over frequency.

        Parameters
        ----------
        omega : array_like, rad/s
            Positive frequencies.
        output : {"theta", "omega", "both"}
            Attitude per torque [rad/(N*m)], rate per torque [rad/(s*N*m)], or both (the
            attitudes first).

        Returns
        -------
        control.FrequencyResponseData
            Planar: input ``torque``, the requested output(s) (``theta`` and/or ``omega``).
            Three axes: the exact 3x3 matrix (6x3 for ``"both"``), inputs ``torque_x/_y/_z``,
            outputs ``theta_x/_y/_z`` and/or ``omega_x/_y/_z``, hub axes.
        """
        import control

        omega = frequency_vector(omega)
        if output not in ("theta", "omega", "both"):
            raise ValueError(f"output must be 'theta', 'omega' or 'both'; got {describe(output)}")
        theta = self.exact.attitude_compliance(omega)
        parts = {"theta": [("theta", theta)],
                 "omega": [("omega", theta * (1j * omega)[:, None, None])]}
        parts["both"] = parts["theta"] + parts["omega"]
        data = np.moveaxis(np.concatenate([r for _, r in parts[output]], axis=1), 0, -1)
        suffixes = [""] if not self.three_axis else [f"_{a}" for a in _AXES]
        return control.frd(data, omega, inputs=[f"torque{x}" for x in suffixes],
                           outputs=[f"{name}{x}" for name, _ in parts[output] for x in suffixes])


def _mode_mixing(lam: np.ndarray) -> np.ndarray:
    """First-order bound on the share of mode j that round-off mixes into computed mode i.

    A backward-stable solver of the symmetric-definite pencil (K, M) returns each mode
    with the others mixed in at |theta_ij| <~ eps ||K|| / |lam_i - lam_j| (the eigenvector
    perturbation bound, ||K|| the largest eigenvalue of the equilibrated, mass-normalised
    pencil), so a modal quantity q that is exactly zero for mode i (an input's drive by
    symmetry) is computed as up to sum_j theta_ij |q_j|: ``_mode_mixing(lam) @ |q|``. Modes
    whose eigenvalues agree to 1e4 eps ||K|| (one eigenspace as far as the solver can tell) get
    0 with each other: their basis is arbitrary, and :func:`_whole_clusters` decides for them
    together.

    Parameters
    ----------
    lam : ndarray (n,)
        Eigenvalues omega^2 [rad^2/s^2] of the modes.

    Returns
    -------
    ndarray (n, n)
        theta bounds, zero on the diagonal and within clusters.

    References
    ----------
    G. H. Golub, C. F. Van Loan, Matrix Computations, 4th ed., 2013, sec. 8.1.4 (eigenvector
    sensitivity, theorem 8.1.12); B. N. Parlett, The Symmetric Eigenvalue Problem, 1998, ch. 11.
    """
    scale = float(np.max(lam, initial=0.0))
    gap = np.abs(lam[:, None] - lam[None, :])
    with np.errstate(divide="ignore"):
        return np.where(gap <= 1e4 * np.finfo(float).eps * scale, 0.0,
                        np.finfo(float).eps * scale / np.where(gap > 0, gap, 1.0))


def _whole_clusters(active: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """``active`` with every elastic mode of a cluster of eigenvalues equal to 1e4 eps max(lam)
    (:func:`_mode_mixing`) active if one of them is. The rigid-body modes (lam = 0 exactly) are
    not a solver's arbitrary basis but the physical translations and principal rotations
    (:meth:`Spacecraft._rigid_modes`): each is decided on its own."""
    order = np.argsort(lam, kind="stable")
    tight = np.diff(lam[order]) <= 1e4 * np.finfo(float).eps * float(np.max(lam, initial=0.0))
    tight &= lam[order][1:] > 0.0
    cluster = np.empty(lam.size, dtype=int)
    cluster[order] = np.concatenate([[0], np.cumsum(~tight)])
    any_active = np.zeros(lam.size, dtype=bool)
    np.logical_or.at(any_active, cluster, active)
    return any_active[cluster]


def _closure(active: np.ndarray, coupled: np.ndarray) -> np.ndarray:
    """Grow a set of modes by every mode coupled to it (boolean adjacency), to a fixed point."""
    active = active.copy()
    while True:
        grown = active | coupled[:, active].any(axis=1)
        if np.array_equal(grown, active):
            return active
        active = grown
