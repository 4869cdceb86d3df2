r"""A rigid hub coupled to appendages through their W-matrix interface.

Planar motion: the hub has coordinates ``h = (X, Y, theta)`` (its centre of mass and attitude).
Each appendage i is mounted at point p_i along the unit vector e_i (normal n_i); its attachment
end follows the hub rigidly,

    (axial_i, delta_i, phi_i) = G_i h        (Mount.kinematics)

Finite appendages (realisation in attachment-end coordinates, RootModel)
    The appendage's first two coordinates are replaced by ``G_i h``, its internal ones kept:
    ``q_i = T_i [h; z_i]``. Its axial motion is rigid (Euler-Bernoulli members are inextensible),
    a point mass m_i moving with ``axial_i``. The coupled second-order system is

        M = M_hub + sum_i (T_i^T M_i T_i + m_i g_i g_i^T),  C, K likewise,

    in coordinates ``[h, z_1, z_2, ...]``, and the state-space plant is built from its
    undamped modes (mass-normalised, ``K V = M V Lambda``): states ``[eta, eta_dot]`` with
    ``A = [[0, I], [-Lambda, -V^T C V]]``, a well-scaled realisation of any size.

Distributed appendages (exact reference)
    Eliminating the appendage gives the hub's dynamic stiffness, with ``D_i = W_i^-1``,

        Z(s) = M_hub s**2 + sum_i ( G_r,i^T D_i(s) G_r,i + m_i s**2 g_i g_i^T ),

    and ``theta/torque = [Z(s)^-1]_{theta theta}``: the exact frequency response. The coupled
    natural frequencies are counted with the Wittrick-Williams algorithm: the number of
    frequencies below w is ``J(w) = sum_i J0_i(w) + s{Z(i w)}``, where J0_i counts the
    appendage's frequencies with its attachment end clamped (the cantilever frequencies of a
    beam) and s{.} the negative eigenvalues of the real symmetric Z(iw). Bisection on J finds
    every frequency without missing one.

References
----------
.. [1] P. W. Likins, "Dynamics and control of flexible space vehicles", JPL TR 32-1329, 1970.
.. [2] W. H. Wittrick, F. W. Williams, "A general algorithm for computing natural frequencies of
   elastic structures", Q. J. Mech. Appl. Math. 24(3), 1971.
.. [3] Belonozhko et al. 2009 (PAPER.md), the W-matrix interface.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg

from appendages import limits
from appendages.interface import S_RANGE, describe, equilibrate, inverse_2x2

from .hub import Hub, Mount

__all__ = ["Spacecraft", "SecondOrderModel"]

_HUB_NAMES = ("X", "Y", "theta")


@dataclasses.dataclass(frozen=True)
class SecondOrderModel:
    """Assembled ``M z'' + C z' + K z = F u`` of hub and finite appendages.

    Attributes
    ----------
    mass, damping, stiffness : ndarray (n, n)
    coordinate_names : tuple of str
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
    """Rigid hub with appendages mounted on it.

    Parameters
    ----------
    hub : Hub
    mounts : sequence of Mount
        Any number (zero for a rigid spacecraft) of appendages of any model that offers the
        W-matrix interface.
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
        self.hub = hub
        self.mounts = mounts
        self.names = names
        self._cache: dict = {}

    def __repr__(self) -> str:
        return f"Spacecraft({self.hub!r}, {self.mounts!r})"

    # -- rigid properties ---------------------------------------------------------------------
    def _appendage_centres(self) -> list:
        return [m.position + 0.5 * m.appendage.length * m.axis for m in self.mounts]

    @property
    def mass(self) -> float:
        """Total mass [kg]."""
        return self.hub.mass + sum(m.appendage.mass for m in self.mounts)

    @property
    def center_of_mass(self) -> np.ndarray:
        """Centre of mass of the undeformed spacecraft in hub axes [m].

        Appendage centres are taken at mid-length, exact for uniform beams; for chains the
        chain's own centre of mass is used when it offers ``center_of_mass`` (from its root).
        """
        moment = np.zeros(2)
        for mount in self.mounts:
            moment += mount.appendage.mass * self._centre(mount)
        return moment / self.mass

    @staticmethod
    def _centre(mount: Mount) -> np.ndarray:
        a = mount.appendage
        distance = getattr(a, "center_of_mass", None)
        if distance is None:
            distance = 0.5 * a.length
        return mount.position + float(distance) * mount.axis

    @property
    def inertia(self) -> float:
        """Moment of inertia of the undeformed spacecraft about its centre of mass [kg*m**2]."""
        c = self.center_of_mass
        J = self.hub.inertia + self.hub.mass * float(c @ c)
        for mount in self.mounts:
            d = self._centre(mount) - c
            J += mount.appendage.inertia + mount.appendage.mass * float(d @ d)
        return J

    # -- finite assembly ----------------------------------------------------------------------
    def second_order_model(self) -> SecondOrderModel:
        """Assemble M, C, K of hub and appendages (all appendages must be finite models)."""
        cached = self._cache.get("second_order")
        if cached is not None:
            return cached
        models = []
        for name, mount in zip(self.names, self.mounts):
            if not hasattr(mount.appendage, "root_model"):
                raise TypeError(
                    f"appendage '{name}' ({type(mount.appendage).__name__}) has no finite "
                    "realisation (root_model); use a truncated model, e.g. beam.truncated(n_modes), "
                    "or the exact frequency-domain methods"
                )
            models.append(mount.appendage.root_model())
        n = 3 + sum(rm.n - 2 for rm in models)
        limits.check("the appendages' coordinates (3 + their internal ones)", n, "coordinates",
                     "coordinates of the assembled model")
        M = np.zeros((n, n))
        M[:2, :2] = np.eye(2) * self.hub.mass
        M[2, 2] = self.hub.inertia
        C = np.zeros((n, n))
        K = np.zeros((n, n))
        names = list(_HUB_NAMES)
        blocks = []
        offset = 3
        for name, mount, rm in zip(self.names, self.mounts, models):
            G = mount.kinematics()
            T = np.zeros((rm.n, n))
            T[:2, :3] = G[1:]
            T[2:, offset:offset + rm.n - 2] = np.eye(rm.n - 2)
            M += T.T @ rm.mass @ T
            g = np.zeros(n)  # axial rigid motion of the appendage

            g[:3] = G[0]
            M += mount.appendage.mass * np.outer(g, g)
            C += T.T @ rm.damping @ T
            K += T.T @ rm.stiffness @ T
            names += [f"{name}.{c}" for c in rm.coordinate_names[2:]]
            blocks.append((mount, T))
            offset += rm.n - 2
        model = SecondOrderModel(0.5 * (M + M.T), 0.5 * (C + C.T), 0.5 * (K + K.T), tuple(names), blocks)
        self._cache["second_order"] = model
        return model

    # -- modes and the state-space plant ------------------------------------------------------
    def modes(self):
        """Undamped modes of the assembled finite model (computed once).

        Returns
        -------
        frequencies : ndarray (n,), rad/s
            Ascending; the three rigid-body modes (X, Y, theta) are exactly 0.
        shapes : ndarray (n, n)
            Mass-normalised mode shapes in the assembled coordinates (columns).
        """
        cached = self._cache.get("modes")
        if cached is None:
            model = self.second_order_model()
            # equilibrated (unit-free) pencil: hub coordinates in m and rad, appendage ones in
            # their own units; eigenvalues unchanged, eigenvectors scaled back by d
            d = equilibrate(model.stiffness, model.mass)
            lam, V = scipy.linalg.eigh(model.stiffness * np.outer(d, d),
                                       model.mass * np.outer(d, d))
            V = V * d[:, None]
            # A free-floating planar spacecraft has exactly three rigid-body modes; every
            # hinge/bending stiffness is positive, so the rest are elastic.
            lam[:3] = 0.0
            if np.any(lam[3:] <= 0.0):
                raise ValueError(
                    "the assembled stiffness matrix has more than three zero or negative "
                    "eigenvalues: the stiffness range is too wide for double precision "
                    f"(smallest elastic eigenvalue {lam[3]!r}, largest {lam[-1]!r} [rad^2/s^2])"
                )
            V = V.copy()
            V[:, :3] = self._rigid_modes(V[:, :3], model.mass)
            cached = (np.sqrt(lam), V)
            self._cache["modes"] = cached
        return cached[0].copy(), cached[1]

    @staticmethod
    def _rigid_modes(R: np.ndarray, M: np.ndarray) -> np.ndarray:
        """Physical rigid-body modes from any basis R of the null space of K.

        Within span(R), the motions with hub displacement (1, 0, 0), (0, 1, 0) and (0, 0, 1)
        are unique (the hub block of R is invertible); the two translations are M-orthogonal
        to each other (a rigid translation carries the total mass), and the rotation is made
        M-orthogonal to them by Gram-Schmidt, which turns it into the rotation about the
        system's centre of mass. Returned mass-normalised: [x translation, y translation,
        rotation]; torque excites only the last, and theta sees only the last.
        """
        physical = R @ np.linalg.solve(R[:3, :3], np.eye(3))
        tx, ty, rot = physical.T
        for t in (tx, ty):
            rot = rot - (t @ M @ rot) / (t @ M @ t) * t
        modes = np.column_stack([tx, ty, rot])
        return modes / np.sqrt(np.einsum("ij,ik,kj->j", modes, M, modes))

    def natural_frequencies(self, n: int, *, exact: bool | None = None) -> np.ndarray:
        """First n coupled elastic natural frequencies [rad/s] (rigid-body modes left out).

        Parameters
        ----------
        n : int
            Number of frequencies.
        exact : bool, optional
            True: roots of the coupled characteristic equation through each appendage's exact
            W(s) (Wittrick-Williams count and bisection); the accuracy reference for truncated
            models of a distributed beam. False: eigenvalues of the assembled finite model.
            Default: exact when some appendage has no finite realisation.

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
            if w.size - 3 < n:
                raise ValueError(f"n = {n} exceeds the {w.size - 3} elastic modes of the finite "
                             "model; ask for fewer or use exact=True")
            return w[3:3 + n]
        return self._wittrick_williams(n)

    def plant(self, *, tip_deflection: bool = False, root_loads: bool = False,
              disturbances: bool = False, n_modes: int | None = None, prune: bool = False,
              name: str = "spacecraft"):
        """Linear state-space model of the free-floating spacecraft.

        Parameters
        ----------
        tip_deflection : bool
            Add outputs ``<name>_tip_deflection`` [m] (elastic, relative to the mount's tangent).
        root_loads : bool
            Add outputs ``<name>_root_force`` [N] and ``<name>_root_moment`` [N*m], the load
            the hub applies to each appendage at its attachment end (F_y, M of PAPER.md).
        disturbances : bool
            Add inputs ``disturbance_torque`` [N*m] (on the hub, apart from the actuator's
            ``torque``), ``force_x``, ``force_y`` [N] (at the hub's centre of mass, hub axes) and
            ``<name>_tip_force`` [N] (transverse, at each appendage's free end).
        n_modes : int, optional
            Keep only the rigid-body modes and the first ``n_modes`` coupled elastic modes.
        prune : bool
            Drop modes that no input excites and no output sees (e.g. the symmetric bending of
            two symmetric wings under pure torque); the input-output behaviour is unchanged.

        Returns
        -------
        control.StateSpace
            Inputs ``torque`` [N*m] (+ disturbances), outputs ``theta`` [rad], ``omega``
            [rad/s] (+ requested), states ``mode[k]``, ``mode_rate[k]`` (modal coordinates).
        """
        import control

        model = self.second_order_model()
        w, V = self.modes()
        n = w.size
        index_theta = 2
        inputs = ["torque"]
        load_columns = [np.eye(n)[:, index_theta]]
        if disturbances:
            inputs += ["disturbance_torque", "force_x", "force_y"]
            load_columns += [np.eye(n)[:, index_theta], np.eye(n)[:, 0], np.eye(n)[:, 1]]
        e_theta = np.eye(n)[index_theta]
        outputs = ["theta", "omega"]
        out_pos = [e_theta, np.zeros(n)]  # rows on displacements z
        out_vel = [np.zeros(n), e_theta]  # rows on velocities z'
        load_rows = []  # (root model, T, row) of each root-load output
        for name, (mount, T) in zip(self.names, model.blocks):
            rm = mount.appendage.root_model()
            if disturbances:
                tip_abs = rm.tip.copy()
                tip_abs[0] += 1.0
                tip_abs[1] += mount.appendage.length
                inputs.append(f"{name}_tip_force")
                load_columns.append(T.T @ tip_abs)
            if tip_deflection:
                outputs.append(f"{name}_tip_deflection")
                out_pos.append(rm.tip @ T)
                out_vel.append(np.zeros(n))
            if root_loads:
                for row, label in ((0, "root_force"), (1, "root_moment")):
                    outputs.append(f"{name}_{label}")
                    load_rows.append((rm, T, row))
        F = np.column_stack(load_columns)
        keep = np.arange(n)
        if n_modes is not None:
            if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 0:
                raise ValueError(f"n_modes must be a non-negative integer; got {describe(n_modes)}")
            keep = keep[: 3 + n_modes]
        modal_damping = V.T @ model.damping @ V
        # damping forces vanish for rigid-body motion (C r = 0 exactly); keep round-off of
        # ~1e-17 out of the rigid rows, where it would couple the rigid-body Jordan block to
        # the elastic modes (and defeat balancing-based tests downstream)
        modal_damping[:3, :] = 0.0
        modal_damping[:, :3] = 0.0
        if not disturbances:
            # the centre of mass cannot translate without an external force: leave out the two
            # translation modes (zero load from torque, unseen by theta and tip deflections)
            keep = keep[keep >= 2]
        Vk, lam = V[:, keep], w[keep] ** 2
        Ck = modal_damping[np.ix_(keep, keep)]
        if prune:
            # Keep a mode only if some input excites it and some output sees it, directly or
            # through damping coupling (closure of each set over the coupling graph): the
            # input-output behaviour from rest is unchanged.
            Bq = Vk.T @ F
            Cq, Cv, _ = self._output_rows(out_pos, out_vel, load_rows, Vk, lam, Ck, Bq)
            tol = 1e-12 * (np.abs(Vk).max(axis=0))
            driven = np.abs(Bq).max(axis=1, initial=0) > tol * np.abs(F).max()
            out_scale = max(np.abs(Cq).max(initial=0), np.abs(Cv).max(initial=0), 1e-300)
            seen = (np.abs(Cq).max(axis=0, initial=0) + np.abs(Cv).max(axis=0, initial=0)) > 1e-12 * out_scale
            # damping couples two modes when C_jk is more than round-off of the damping scale
            # (symmetric wings leave ~1e-16 between symmetric and antisymmetric modes)
            coupled = np.abs(Ck - np.diag(np.diag(Ck))) > 1e-12 * max(np.abs(Ck).max(initial=0), 1e-300)
            driven, seen = _closure(driven, coupled), _closure(seen, coupled)
            active = driven & seen
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
        states = [f"mode[{k}]" for k in keep] + [f"mode_rate[{k}]" for k in keep]
        return control.ss(A, B, Cmat, D, inputs=inputs, outputs=outputs, states=states, name=name)

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
        """Z(s) of the hub with every appendage eliminated through D_i(s) = W_i(s)^-1.

        Shape ``s.shape + (3, 3)``. D_i comes from the appendage's own dynamic stiffness when
        it offers one (exact closed form of a beam, static condensation of a finite model),
        which stays accurate where W_i is singular (W_i -> 0 at its clamped frequencies) or
        huge (at its free poles), where inverting W_i loses every digit.
        """
        s = np.asarray(s, dtype=complex)
        Z = np.zeros(s.shape + (3, 3), dtype=complex)
        M_hub = np.diag([self.hub.mass, self.hub.mass, self.hub.inertia])
        Z += M_hub * (s**2)[..., None, None]
        for mount in self.mounts:
            G = mount.kinematics()
            D = _dynamic_stiffness_of(mount.appendage, s, undamped=undamped)
            Z += G[1:].T @ D @ G[1:]
            Z += mount.appendage.mass * np.outer(G[0], G[0]) * (s**2)[..., None, None]
        return Z

    def frequency_response(self, omega, *, output: str = "theta"):
        """Exact frequency response from ``torque`` through every appendage's W(s).

        Parameters
        ----------
        omega : array_like, rad/s
            Positive frequencies.
        output : {"theta", "omega"}
            theta/torque [rad/(N*m)] or omega/torque [rad/(s*N*m)].

        Returns
        -------
        control.FrequencyResponseData
            With input ``torque`` and the requested output name.
        """
        import control

        omega = _frequency_vector(omega)
        if output not in ("theta", "omega"):
            raise ValueError(f"output must be 'theta' or 'omega'; got {describe(output)}")
        s = 1j * omega
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            Z = self._hub_dynamic_stiffness(s)
            e_theta = np.broadcast_to(np.array([[0.0], [0.0], [1.0]]), Z.shape[:-1] + (1,))
            try:
                response = np.linalg.solve(Z, e_theta)[..., 2, 0]
            except np.linalg.LinAlgError:
                response = np.full(omega.shape, np.nan, dtype=complex)
        if not np.all(np.isfinite(response)):
            bad = omega[~np.isfinite(response)]
            raise ValueError(
                "omega hits a natural frequency of the undamped spacecraft, where the response "
                f"is infinite [rad/s]: {describe(bad)}; give the appendages damping or move "
                "omega off the resonance")
        if output == "omega":
            response = response * s
        return control.frd(response.reshape(1, 1, -1), omega, inputs=["torque"], outputs=[output])

    def _count(self, omega: np.ndarray) -> np.ndarray:
        """Wittrick-Williams count: coupled frequencies (the 3 rigid-body ones included) < omega.

        ``J(w) = sum_i J0_i(w) + s{Z(iw)}`` (module docstring). Exactly at an appendage's clamped
        frequency D_i is infinite; the count there is its limit from below (a natural frequency
        is counted only above it), taken by evaluating Z one rounding step lower.
        """
        omega = np.asarray(omega, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            Z = self._hub_dynamic_stiffness(1j * omega, undamped=True).real
            bad = ~np.all(np.isfinite(Z), axis=(-2, -1))
            step = 0
            while np.any(bad) and step < 8:
                step += 1
                lower = omega[bad] * (1.0 - 2.0 * step * np.finfo(float).eps)
                Z[bad] = self._hub_dynamic_stiffness(1j * lower, undamped=True).real
                bad[bad] = ~np.all(np.isfinite(Z[bad]), axis=(-2, -1))
        if np.any(bad):  # pragma: no cover - needs a pole on 8 consecutive doubles
            raise FloatingPointError("the dynamic stiffness of an appendage is not finite near "
                                     f"omega = {describe(omega[bad])} [rad/s]")
        Z = 0.5 * (Z + np.swapaxes(Z, -1, -2))
        # Sylvester's law of inertia: negative eigenvalues of the symmetric 3x3 Z. eigvalsh
        # is backward stable, so the count is exact unless an eigenvalue is within round-off
        # of zero, i.e. omega within round-off of a coupled frequency: what bisection needs.
        negative = (np.linalg.eigvalsh(Z) < 0).sum(axis=-1)
        top = float(np.max(omega, initial=0.0))
        clamped = sum(np.searchsorted(self._clamped(k, top), omega)
                      for k in range(len(self.mounts)))
        return negative + clamped

    def _clamped(self, k: int, omega_max: float) -> np.ndarray:
        """Clamped frequencies of appendage k [rad/s], at least up to omega_max (cached)."""
        cache = self._cache.setdefault("clamped", {})
        wc = cache.get(k)
        if wc is None or (wc.size and wc[-1] <= omega_max and
                          hasattr(self.mounts[k].appendage, "cantilever_frequencies")):
            wc = _clamped_frequencies(self.mounts[k].appendage, omega_max)
            cache[k] = wc
        return wc

    def _wittrick_williams(self, n: int) -> np.ndarray:
        """First n elastic coupled frequencies by the Wittrick-Williams count and bisection.

        Bracket: with the hub held, the spacecraft falls apart into the clamped appendages; by
        Rayleigh's interlacing (3 constraints) the k-th elastic coupled frequency is at least
        the k-th clamped frequency of them all, so half the lowest clamped frequency is below
        every elastic one. The upper end doubles until the count reaches n + 3.
        """
        n_total = n + 3  # the three rigid-body modes count as frequencies <= any omega > 0
        lowest = min((float(wc[0]) if wc.size else np.inf)
                     for wc in (self._clamped(k, 0.0) for k in range(len(self.mounts))))
        if not np.isfinite(lowest):
            raise ValueError("the spacecraft has no elastic mode: no appendage has a clamped "
                             "natural frequency")
        lo = np.full(n, 0.5 * lowest)
        hi = np.full(1, lowest)
        while self._count(hi)[0] < n_total:
            hi = hi * 2.0
            if not np.isfinite(hi[0]) or hi[0] > 1e12 * lowest:
                raise ValueError(
                    f"the spacecraft has fewer than n = {n} elastic natural frequencies "
                    f"below {hi[0]:.3g} rad/s (a finite appendage has a finite number)")
        hi = np.full(n, hi[0])
        target = np.arange(4, n_total + 1)  # frequency k is where the count reaches k
        active = np.arange(n)
        for _ in range(200):
            mid = 0.5 * (lo[active] + hi[active])
            above = self._count(mid) >= target[active]
            hi[active] = np.where(above, mid, hi[active])
            lo[active] = np.where(above, lo[active], mid)
            active = active[hi[active] - lo[active] > 4e-16 * hi[active]]
            if active.size == 0:
                break
        return 0.5 * (lo + hi)


def _closure(active: np.ndarray, coupled: np.ndarray) -> np.ndarray:
    """Grow a set of modes by every mode coupled to it (boolean adjacency), to a fixed point."""
    active = active.copy()
    while True:
        grown = active | coupled[:, active].any(axis=1)
        if np.array_equal(grown, active):
            return active
        active = grown


def _frequency_vector(omega) -> np.ndarray:
    """omega as a 1-D float64 array of positive finite frequencies [rad/s], or an error."""
    if isinstance(omega, (str, bytes)) or omega is None:
        raise TypeError(f"omega must be an array of frequencies [rad/s]; got "
                        f"{type(omega).__name__}")
    arr = np.asarray(omega)
    if arr.dtype.kind not in "iuf" or arr.dtype == bool:
        raise TypeError(f"omega must be real frequencies [rad/s]; got dtype {arr.dtype} "
                        f"{describe(omega)}")
    limits.check("omega (number of frequencies)", arr.size, "points", "points at once")
    arr = arr.astype(float)
    if arr.ndim != 1 or arr.size == 0 or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError("omega must be a 1-D array of positive finite frequencies [rad/s]; "
                         f"got {describe(omega)}")
    if np.any(arr < S_RANGE[0]) or np.any(arr > S_RANGE[1]):
        raise ValueError(f"omega must lie between {S_RANGE[0]:g} and {S_RANGE[1]:g} [rad/s] "
                         "(appendages.interface.S_RANGE); got "
                         f"{describe(arr[(arr < S_RANGE[0]) | (arr > S_RANGE[1])][0])}")
    return arr


def _dynamic_stiffness_of(appendage, s: np.ndarray, *, undamped: bool) -> np.ndarray:
    """D(s) = W(s)^-1 of an appendage [N/m, N; N, N*m], shape ``s.shape + (2, 2)``.

    Through the interface only. Undamped (the natural-frequency count): a finite appendage
    (``root_model()``) by static condensation of its realisation with the damping removed,
    which carries the poles of D at its clamped frequencies natively (inverting W there,
    where W is singular, loses every digit); an appendage offering ``undamped()`` (the
    distributed beam) through its undamped twin. Otherwise an appendage offering
    ``dynamic_stiffness(s)`` (the beam's closed form) by it, any other by the scaled 2x2
    inverse of its own W(s), which is the accurate one at small |s| (a chain's recursion, a
    truncation's modal sum; the condensation subtracts stiffness-sized terms there).
    """
    if undamped and hasattr(appendage, "undamped"):
        appendage = appendage.undamped()
    if undamped and hasattr(appendage, "root_model"):
        rm = appendage.root_model()
        if np.any(rm.damping):
            rm = dataclasses.replace(rm, damping=np.zeros_like(rm.damping))
        return rm.dynamic_stiffness(s)
    if hasattr(appendage, "dynamic_stiffness"):
        return np.asarray(appendage.dynamic_stiffness(s), dtype=complex)
    return inverse_2x2(np.asarray(appendage.W(s), dtype=complex))


def _clamped_frequencies(appendage, omega_max: float) -> np.ndarray:
    """Natural frequencies [rad/s] of the appendage with its attachment end clamped, ascending:
    at least every one up to omega_max (all of them for a finite model)."""
    if hasattr(appendage, "cantilever_frequencies"):
        n = 8
        while True:
            wc = appendage.cantilever_frequencies(n)
            if wc[-1] > omega_max:
                return wc
            n *= 2
    if not hasattr(appendage, "root_model"):
        raise TypeError(
            f"exact natural frequencies need each appendage's clamped frequencies "
            f"(cantilever_frequencies(n) or a finite root_model()); "
            f"{type(appendage).__name__} offers neither")
    rm = appendage.root_model()
    Kii, Mii = rm.stiffness[2:, 2:], rm.mass[2:, 2:]
    if Kii.shape[0] == 0:
        return np.zeros(0)
    d = equilibrate(Kii, Mii)
    lam = scipy.linalg.eigvalsh(Kii * np.outer(d, d), Mii * np.outer(d, d))
    return np.sqrt(np.clip(lam, 0.0, None))
