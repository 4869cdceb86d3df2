r"""The modal survey of a free-floating spacecraft: what each coupled mode is and who takes part.

For the assembled finite model ``M q'' + C q' + K q = F u`` of :class:`Spacecraft` (hub and
finite appendages, :meth:`Spacecraft.second_order_model`), with its undamped modes ``v_k``
(mass-normalised, ``K v_k = w_k**2 M v_k``), each coupled elastic mode k is described by:

* its damped pole ``lambda_k`` of the state-space model in modal coordinates,
  ``A = [[0, I], [-Omega**2, -V^T C V]]`` (the plant's own realisation): the frequency
  ``|lambda_k|`` [rad/s, Hz] and the damping ratio ``-Re(lambda_k)/|lambda_k|``. Each damped
  pole is paired with the undamped mode that dominates its eigenvector (an assignment over all
  of them, so that two close modes never claim one pole);
* its torque participation ``J v_k,theta**2`` [-]: its residue in the attitude response
  ``theta/torque = 1/(J s**2) + sum_k v_k,theta**2/(s**2 + 2 zeta_k w_k s + w_k**2)`` (rigid
  part first, J the spacecraft's inertia about its centre of mass) relative to the rigid body's
  1/J: how strongly a torque drives the mode and theta sees it (0 for a mode that pure torque
  cannot excite, such as the symmetric bending of two mirror-image wings). In three axes one per
  axis, relative to that axis' diagonal entry of the inertia tensor;
* each appendage's share of its strain energy, ``v_k^T K_i v_k / w_k**2`` [-] with K_i the
  appendage's part of K (the hub is rigid: the shares sum to 1): which appendage deforms in the
  mode.

The modal damping matrix of a spacecraft whose appendages are damped in their own cantilever
modes is not diagonal in the coupled modes, so the damping ratios of the coupled modes are not
those entered; this table shows what the spacecraft has, beside what was entered.

References
----------
.. [1] P. W. Likins, "Dynamics and control of flexible space vehicles", JPL TR 32-1329, 1970.
.. [2] R. R. Craig, A. J. Kurdila, "Fundamentals of Structural Dynamics", 2nd ed., Wiley, 2006,
   ch. 11 (modal participation) and ch. 17 (component-mode synthesis).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import scipy.linalg
import scipy.optimize

from appendages.interface import describe

__all__ = ["CoupledMode", "modal_survey"]


@dataclasses.dataclass(frozen=True)
class CoupledMode:
    """One elastic mode of the coupled spacecraft (module docstring).

    Attributes
    ----------
    frequency : float, rad/s
        ``|lambda|`` of its damped pole (the undamped one for an undamped spacecraft).
    damping_ratio : float
        ``-Re(lambda)/|lambda|``.
    undamped_frequency : float, rad/s
        Of the undamped mode it is paired with.
    torque_participation : tuple of float
        ``J v_theta**2`` per rotation axis (one planar; x, y, z in three axes) [-].
    strain_energy : dict
        Appendage name -> its share of the mode's strain energy [-].
    """

    frequency: float
    damping_ratio: float
    undamped_frequency: float
    torque_participation: tuple
    strain_energy: dict

    @property
    def hertz(self) -> float:
        """The frequency in Hz."""
        return self.frequency / (2.0 * math.pi)

    def as_dict(self) -> dict:
        """JSON-ready: ``frequency`` [rad/s], ``frequency_hz``, ``damping_ratio``,
        ``undamped_frequency`` [rad/s], ``torque_participation`` (a list), ``strain_energy``."""
        return {"frequency": self.frequency, "frequency_hz": self.hertz,
                "damping_ratio": self.damping_ratio,
                "undamped_frequency": self.undamped_frequency,
                "torque_participation": list(self.torque_participation),
                "strain_energy": dict(self.strain_energy)}


def modal_survey(spacecraft, n_modes: int | None = None) -> list[CoupledMode]:
    """The first ``n_modes`` coupled elastic modes of a spacecraft (module docstring).

    Parameters
    ----------
    spacecraft : Spacecraft
        With finite appendages (truncated beams, modal data, chains).
    n_modes : int, optional
        How many, from the lowest; default all.

    Returns
    -------
    list of CoupledMode
        Ascending in undamped frequency.

    Raises
    ------
    TypeError
        A spacecraft with an appendage that has no finite realisation (a distributed beam).
    ValueError
        n_modes not a positive integer.
    """
    if n_modes is not None and (isinstance(n_modes, (bool, np.bool_)) or
                                not isinstance(n_modes, (int, np.integer)) or n_modes < 1):
        raise ValueError(f"n_modes must be a positive integer or None; got {describe(n_modes)}")
    model = spacecraft.second_order_model()
    w, V = spacecraft.modes()
    r = spacecraft.n_rigid
    n = w.size - r
    if n_modes is not None:
        n = min(n, int(n_modes))
    if n == 0:
        return []
    Ve = V[:, r:]          # every elastic mode: the damping couples the kept ones to the rest
    m = Ve.shape[1]
    Ce = Ve.T @ model.damping @ Ve
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-np.diag(w[r:] ** 2), -Ce]])
    lam, X = scipy.linalg.eig(A)
    # the poles of a pair in the upper half plane, the real ones of an overdamped mode
    scale = max(float(np.max(np.abs(lam), initial=0.0)), 1e-300)
    pick = lam.imag > 1e-12 * scale
    pick |= np.abs(lam.imag) <= 1e-12 * scale
    lam, X = lam[pick], X[:, pick]
    shapes = np.abs(X[:m]) ** 2
    shapes /= np.maximum(shapes.sum(axis=0, keepdims=True), 1e-300)
    modes, poles = scipy.optimize.linear_sum_assignment(-shapes.T)
    pole_of = np.empty(m, dtype=int)
    pole_of[poles] = modes
    # torque participation: J v_theta**2 per rotation axis
    rotation = [3, 4, 5] if spacecraft.three_axis else [2]
    inertia = spacecraft.inertia
    inertias = (np.diag(np.asarray(inertia)) if spacecraft.three_axis
                else np.array([float(inertia)]))
    # each appendage's stiffness, in the assembled coordinates
    n_root = 6 if spacecraft.three_axis else 2
    stiffness = []
    for (mount, T), name in zip(model.blocks, spacecraft.names):
        rm = (mount.appendage.root_model(6) if n_root == 6
              else mount.appendage.root_model())
        stiffness.append((name, T.T @ rm.stiffness @ T))
    out = []
    for k in range(n):
        pole = lam[pole_of[k]]
        v = Ve[:, k]
        size = abs(pole)
        zeta = float(-pole.real / size) if size > 0 else 1.0
        energy = {name: float(v @ K @ v) for name, K in stiffness}
        total = sum(energy.values())
        shares = {name: (e / total if total > 0 else 0.0) for name, e in energy.items()}
        participation = tuple(float(J * v[i] ** 2) for J, i in zip(inertias, rotation))
        out.append(CoupledMode(float(size), zeta, float(w[r + k]), participation, shares))
    return out
