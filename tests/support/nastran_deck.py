"""The NASTRAN deck of tests/data/nastran/beam_modes (a cantilevered rod of ten bar and beam
elements with a CONM2 at its tip, in inch-slinch units): its lumped mass matrix, worked out by
hand as NASTRAN's default mass, for the tests that convert its modal solution."""
from __future__ import annotations

import math

import numpy as np

__all__ = ["CONM2", "RADIUS", "RHO", "lumped_mass_matrix"]

# beam_modes' deck (beam_modes.dat, cbar_cbeam.blk): MAT1 rho = 7.4851e-4 lbf s^2/in^4, ROD
# sections of radius 1 in, unit-length elements joining grids k, k+1 (k = 1..10), CBEAM 10 the
# last, CONM2 at grid 11 of mass 2.59e-3 with I11 = I22 = I33 = 2.59e-3.
RHO, RADIUS, CONM2 = 7.4851e-4, 1.0, 2.59e-3


def lumped_mass_matrix() -> np.ndarray:
    """NASTRAN's default (lumped) mass of beam_modes over its 12 grids x (T1..R3).

    Bar and beam elements put half their translational mass rho*A*l at each end (no rotary
    inertia); the CBEAM adds half its torsional inertia rho*J*l at each end. The tests check this
    against the file's generalized masses (each mode) and its GPWG.
    """
    area, polar = math.pi * RADIUS**2, math.pi / 2.0 * RADIUS**4
    M = np.zeros((72, 72))
    for element in range(10):
        for grid in (element, element + 1):
            M[6 * grid:6 * grid + 3, 6 * grid:6 * grid + 3] += 0.5 * RHO * area * np.eye(3)
            if element == 9:  # the CBEAM
                M[6 * grid + 3, 6 * grid + 3] += 0.5 * RHO * polar
    M[60:66, 60:66] += CONM2 * np.eye(6)
    return M
