"""An independent 3-D finite-element model of a free-floating hub carrying uniform beams.

This module is the test suite's reference for flexsat's three-axis model: it imports nothing from
flexsat and shares no code with it, so that agreement between the two is evidence, not an echo.
Only numpy and scipy are used.

Model
-----
Each appendage is a straight uniform beam of length L along its local x axis, x = 0 at the
attachment (root) end. Every node carries six degrees of freedom in local axes, in this order::

    u, v, w, theta_x, theta_y, theta_z

u along x (axial), v along y, w along z, and the small rotation vector of the cross-section. The
section is symmetric (shear centre = centroid), so the four motions decouple in the local frame:

* bending in the x-y plane: v(x) with theta_z = dv/dx, stiffness EI_z (``bending_stiffness``);
* bending in the x-z plane: w(x) with theta_y = -dw/dx, stiffness EI_y (``bending_stiffness_y``);
* torsion: theta_x(x), St-Venant stiffness GJ, polar mass moment rho*I_p per unit length;
* axial: u(x), stiffness EA.

Bending is Euler-Bernoulli (no shear deformation, no rotary inertia of the section), with the
Hermite cubic element (``bending_order=3``), optionally enriched with C1 bubble functions
(``bending_order=5``, the default: the nodal values and slopes are still the Hermite ones, the
bubbles' amplitudes are internal degrees of freedom); the mass per unit length rho*A moves with
v and w. Torsion and axial motion use C0 rod elements of polynomial order ``rod_order`` (1: the
linear element; 2, 3, ...: enriched with integrated-Legendre bubbles; 5 by default). Internal
degrees of freedom come after the nodal ones. All mass matrices are consistent (the stiffness's
shape functions).

Frequencies converge as h^4 with the Hermite cubic and h^8 with bending_order=5 (measured, see
tests/support/test_fe3d_reference.py); 20 elements of the default kind give the first three bending
modes of each plane to 2e-11 or better, 200 plain Hermite elements to 1e-9.

Numerics
--------
A beam's stiffness matrix has a condition number of order N^4, and the plain recipes lose that
many digits in the low modes: a shift-invert Lanczos on K + tau M formed in double gave the first
cantilever frequency about 1e-7 off with 160 Hermite elements and 5e-6 off with 640 (measured;
the mesh error is 1e-11 and 5e-14 there). Here
(i) every solve is a sparse LU refined with residuals formed in long double from the unshifted
terms (:class:`_RefinedLU`), (ii) the rigid-body motion of a free structure is removed exactly,
in closed form at the reference point, and the flexible part solved from a bordered system that
stays regular at s = 0 (:class:`_FreeStructure`), (iii) eigenvalues come from block subspace
iteration on K^+ M, which never multiplies a vector by K and finds repeated frequencies
(:func:`natural_frequencies`). Frequencies are then good to about 1e-13 relative, W6 at any
|s| > 0 to about 1e-12 (measured against closed forms).

The sign of theta_y
-------------------
In the x-y plane a positive rotation about +z turns +x towards +y, so theta_z = +dv/dx. In the
x-z plane a positive rotation about +y turns +z towards +x, i.e. +x towards -z, so a section that
rotates by theta_y > 0 makes the beam's axis dip towards -z: theta_y = -dw/dx. The Hermite
interpolation of w uses its slopes, w(xi) = N1 w1 + N2 w1' + N3 w2 + N4 w2', and w' = -theta_y,
so in the element's (w1, theta_y1, w2, theta_y2) the shape vector is D (N1, N2, N3, N4) with
D = diag(1, -1, 1, -1), and its matrices are D K_h D and D M_h D where K_h, M_h are the usual
(v1, theta_z1, v2, theta_z2) Hermite matrices: the w-theta_y couplings change sign, the rest do
not. The same rule gives the opposite sign of the F_z/theta_y coupling in the root compliance
(see :func:`rigid_root_compliance`).

Units are SI throughout: m, kg, s, N, N*m, rad; frequencies in rad/s.

References
----------
.. [1] J. S. Przemieniecki, Theory of Matrix Structural Analysis, McGraw-Hill, 1968, ch. 5 and 11
   (Hermite beam and rod stiffness and consistent mass matrices).
.. [2] B. Szabo and I. Babuska, Finite Element Analysis, Wiley, 1991, ch. 3 (hierarchic
   integrated-Legendre shape functions).
.. [3] R. D. Blevins, Formulas for Natural Frequency and Mode Shape, Van Nostrand Reinhold, 1979,
   tables 8-1 and 8-19 (beam and rod frequencies).
.. [4] G. Strang and G. J. Fix, An Analysis of the Finite Element Method, Prentice-Hall, 1973,
   sec. 6.3 (eigenvalue errors of order h^(2(k-m)) for elements of degree k, energy of order m).
.. [5] N. J. Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed., SIAM, 2002,
   ch. 12 (iterative refinement with residuals in extra precision).
.. [6] M. Geradin and D. Rixen, Mechanical Vibrations: Theory and Application to Structural
   Dynamics, 3rd ed., Wiley, 2015, sec. 2.6 (free structures: rigid modes, inertia relief,
   flexibility with the rigid-body modes removed) and sec. 8.3 (subspace iteration).
.. [7] K.-J. Bathe, Finite Element Procedures, Prentice Hall, 1996, sec. 11.6 (the subspace
   iteration method, block size 2n or n + 8).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.csgraph
import scipy.sparse.linalg

__all__ = [
    "BeamParameters",
    "hermite_bending_matrices",
    "bending_matrices",
    "rod_matrices",
    "element_matrices",
    "beam_matrices",
    "beam_dof_motions",
    "root_compliance",
    "rigid_root_compliance",
    "mount_transformation",
    "spacecraft_matrices",
    "rigid_body_modes",
    "natural_frequencies",
    "hub_compliance",
    "attitude_compliance",
    "SingularMatrixError",
    "TipSpec",
    "tip_mass_matrix",
    "stepped_beam_matrices",
    "appendage_root_compliance",
    "appendage_spacecraft_matrices",
]

_FIELDS = ("length", "bending_stiffness", "bending_stiffness_y", "torsional_stiffness",
           "torsional_inertia", "axial_stiffness", "linear_density")
_UNITS = {"length": "m", "bending_stiffness": "N m^2", "bending_stiffness_y": "N m^2",
          "torsional_stiffness": "N m^2", "torsional_inertia": "kg m",
          "axial_stiffness": "N", "linear_density": "kg/m"}


class BeamParameters(NamedTuple):
    """A uniform beam, with flexsat's three-axis parameter names (DESIGN.md, "Three axes").

    Attributes
    ----------
    length : float, m
    bending_stiffness : float, N m^2
        EI_z, bending in the local x-y plane (v, theta_z = dv/dx).
    bending_stiffness_y : float, N m^2
        EI_y, bending in the local x-z plane (w, theta_y = -dw/dx).
    torsional_stiffness : float, N m^2
        GJ.
    torsional_inertia : float, kg m
        rho*I_p, polar mass moment of inertia per unit length.
    axial_stiffness : float, N
        EA.
    linear_density : float, kg/m
        rho*A.
    """

    length: float
    bending_stiffness: float
    bending_stiffness_y: float
    torsional_stiffness: float
    torsional_inertia: float
    axial_stiffness: float
    linear_density: float

    @property
    def mass(self) -> float:
        """Mass rho*A*L [kg]."""
        return self.linear_density * self.length


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 100 else text[:97] + "..."


def _positive(name: str, value, unit: str) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer,
                                                                     np.floating)):
        raise TypeError(f"{name} must be a real number [{unit}]; got {_short(value)}")
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be positive and finite [{unit}]; got {_short(value)}")
    return value


def _count(name: str, value, minimum: int = 1) -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name} must be an integer; got {_short(value)}")
    if value < minimum:
        raise ValueError(f"{name} must be at least {minimum}; got {int(value)}")
    return int(value)


def _as_params(params) -> BeamParameters:
    """A BeamParameters from a BeamParameters, a mapping, or any object with the attributes.

    The last lets the tests pass a flexsat ``Beam`` directly, without this module importing it.
    """
    if isinstance(params, Mapping):
        missing = [f for f in _FIELDS if f not in params]
        if missing:
            raise ValueError(f"beam parameters lack {missing}")
        values = [params[f] for f in _FIELDS]
    else:
        missing = [f for f in _FIELDS if not hasattr(params, f)]
        if missing:
            raise TypeError(f"beam parameters must have {list(_FIELDS)}; "
                            f"{type(params).__name__} lacks {missing}")
        values = [getattr(params, f) for f in _FIELDS]
    return BeamParameters(*(_positive(f, v, _UNITS[f]) for f, v in zip(_FIELDS, values)))


# ---------------------------------------------------------------------------------------------
# Element matrices
# ---------------------------------------------------------------------------------------------

def hermite_bending_matrices(h: float, bending_stiffness: float, linear_density: float):
    """Stiffness and consistent mass of the Hermite cubic Euler-Bernoulli element.

    Degrees of freedom (v1, dv/dx(0), v2, dv/dx(h)) of an element of length h; with
    t = x/h the shape functions are N1 = 1 - 3 t^2 + 2 t^3, N2 = h (t - 2 t^2 + t^3),
    N3 = 3 t^2 - 2 t^3, N4 = h (t^3 - t^2), and K = EI int N''N''^T dx,
    M = rho*A int N N^T dx ([1]_, eqs. 5.118 and 11.31).

    For the x-y plane these are (v1, theta_z1, v2, theta_z2); for the x-z plane use
    D K D and D M D with D = diag(1, -1, 1, -1) (module docstring).

    Parameters
    ----------
    h : float, m
        Element length.
    bending_stiffness : float, N m^2
    linear_density : float, kg/m

    Returns
    -------
    K : ndarray, shape (4, 4)
    M : ndarray, shape (4, 4)
    """
    K = bending_stiffness / h**3 * np.array([
        [12.0, 6.0 * h, -12.0, 6.0 * h],
        [6.0 * h, 4.0 * h**2, -6.0 * h, 2.0 * h**2],
        [-12.0, -6.0 * h, 12.0, -6.0 * h],
        [6.0 * h, 2.0 * h**2, -6.0 * h, 4.0 * h**2]])
    M = linear_density * h / 420.0 * np.array([
        [156.0, 22.0 * h, 54.0, -13.0 * h],
        [22.0 * h, 4.0 * h**2, 13.0 * h, -3.0 * h**2],
        [54.0, 13.0 * h, 156.0, -22.0 * h],
        [-13.0 * h, -3.0 * h**2, -22.0 * h, 4.0 * h**2]])
    return K, M


def _hermite_values(xi: np.ndarray, h: float) -> np.ndarray:
    t = (1.0 + xi) / 2.0
    return np.array([1.0 - 3.0 * t**2 + 2.0 * t**3, h * (t - 2.0 * t**2 + t**3),
                     3.0 * t**2 - 2.0 * t**3, h * (t**3 - t**2)])


def bending_matrices(h: float, bending_stiffness: float, linear_density: float, order: int = 3):
    """The Hermite cubic bending element, optionally enriched with C1 bubbles to degree p.

    The nodal part is :func:`hermite_bending_matrices`. For p > 3 the element adds the bubbles
    b_k(xi), k = 4..p, on xi in [-1, 1] (x = h (1 + xi)/2), defined by
    d^2 b_k/dxi^2 = sqrt((2n + 1)/2) P_n(xi), n = k - 2, and b_k(-1) = b_k'(-1) = 0. Since
    int P_n = 0 and int xi P_n = 0 for n >= 2, they also vanish with their slope at xi = 1: they
    leave the nodal values and slopes alone (the element stays C1 and conforming). Their
    curvatures are orthogonal to the linear curvatures of the cubics and to each other, so the
    stiffness is block diagonal: the cubic block, then EI (2/h)^3 I. The mass is integrated by
    (p + 1)-point Gauss-Legendre quadrature, exact for degree 2p ([2]_).

    Eigenvalue errors are of order h^(2(p - 1)) ([4]_): h^4 for the cubic, h^8 for p = 5.

    Parameters
    ----------
    h : float, m
    bending_stiffness : float, N m^2
    linear_density : float, kg/m
    order : int
        Polynomial degree p >= 3.

    Returns
    -------
    K, M : ndarray, shape (p + 1, p + 1)
        Degrees of freedom (v1, dv/dx(0), v2, dv/dx(h), bubble amplitudes [m]).
    """
    order = _count("bending_order", order, minimum=3)
    Kc, Mc = hermite_bending_matrices(h, bending_stiffness, linear_density)
    if order == 3:
        return Kc, Mc
    xi, weights = np.polynomial.legendre.leggauss(order + 1)
    values = list(_hermite_values(xi, h))
    for k in range(4, order + 1):
        n = k - 2
        bubble = np.polynomial.legendre.Legendre.basis(n).integ(2, lbnd=-1)
        values.append(math.sqrt((2 * n + 1) / 2.0) * bubble(xi))
    N = np.array(values)
    M = linear_density * (N * weights) @ N.T * (h / 2.0)
    M = 0.5 * (M + M.T)                   # exactly symmetric, whatever the summation order
    K = np.zeros_like(M)
    K[:4, :4] = Kc
    K[4:, 4:] = bending_stiffness * (2.0 / h) ** 3 * np.eye(order - 3)
    return K, M


def rod_matrices(h: float, stiffness: float, inertia: float, order: int = 1):
    """Stiffness and consistent mass of a C0 rod element (axial or torsion) of order p.

    Shape functions on xi in [-1, 1] (x = h (1 + xi)/2): the two linear ones
    (1 - xi)/2, (1 + xi)/2 (end values), then the integrated-Legendre bubbles
    phi_k = (P_k - P_(k-2)) / sqrt(2 (2k - 1)), k = 2..p, which vanish at both ends ([2]_).
    Since d phi_k/dxi = sqrt((2k - 1)/2) P_(k-1), the stiffness is the linear element's
    (stiffness/h) [[1, -1], [-1, 1]] and (2 stiffness/h) I for the bubbles; the mass
    inertia int N N^T dx is integrated exactly by (p + 1)-point Gauss-Legendre quadrature.

    Eigenvalue errors are of order h^(2p) ([4]_): h^2 for the linear element, h^6 for p = 3.

    Parameters
    ----------
    h : float, m
        Element length.
    stiffness : float
        EA [N] for axial motion, GJ [N m^2] for torsion.
    inertia : float
        rho*A [kg/m] for axial motion, rho*I_p [kg m] for torsion.
    order : int
        Polynomial order p >= 1.

    Returns
    -------
    K, M : ndarray, shape (p + 1, p + 1)
        Degrees of freedom: end 1, end 2, bubble amplitudes 2..p.
    """
    order = _count("rod_order", order)
    xi, weights = np.polynomial.legendre.leggauss(order + 1)
    values = [(1.0 - xi) / 2.0, (1.0 + xi) / 2.0]
    for k in range(2, order + 1):
        Pk = np.polynomial.legendre.Legendre.basis(k)(xi)
        Pk2 = np.polynomial.legendre.Legendre.basis(k - 2)(xi)
        values.append((Pk - Pk2) / math.sqrt(2.0 * (2 * k - 1)))
    N = np.array(values)
    M = inertia * (N * weights) @ N.T * (h / 2.0)
    M = 0.5 * (M + M.T)                   # exactly symmetric, whatever the summation order
    K = np.zeros_like(M)
    K[:2, :2] = stiffness / h * np.array([[1.0, -1.0], [-1.0, 1.0]])
    K[2:, 2:] = 2.0 * stiffness / h * np.eye(order - 1)
    return K, M


def _orders(rod_order, bending_order):
    return _count("rod_order", rod_order), _count("bending_order", bending_order, minimum=3)


def _n_bubbles(rod_order: int, bending_order: int) -> int:
    return 2 * (rod_order - 1) + 2 * (bending_order - 3)


def element_matrices(params, h: float, rod_order: int = 5, bending_order: int = 5):
    """The 3-D beam element in local axes.

    Parameters
    ----------
    params : BeamParameters or mapping or object with its attributes
    h : float, m
        Element length.
    rod_order : int
        Polynomial order of the axial and torsion interpolation (:func:`rod_matrices`).
    bending_order : int
        Polynomial degree of the bending interpolation (:func:`bending_matrices`).

    Returns
    -------
    K, M : ndarray, shape (12 + nb, 12 + nb)
        Degrees of freedom (u, v, w, theta_x, theta_y, theta_z) at end 1, the same at end 2,
        then nb = 2 (rod_order - 1) + 2 (bending_order - 3) bubble amplitudes: axial, torsion,
        x-y bending (v), x-z bending (w).
    """
    b = _as_params(params)
    pr, pb = _orders(rod_order, bending_order)
    n = 12 + _n_bubbles(pr, pb)
    K = np.zeros((n, n))
    M = np.zeros((n, n))
    bubbles = iter(range(12, n))
    axial = [0, 6] + [next(bubbles) for _ in range(pr - 1)]
    torsion = [3, 9] + [next(bubbles) for _ in range(pr - 1)]
    xy = [1, 5, 7, 11] + [next(bubbles) for _ in range(pb - 3)]   # v1, theta_z1, v2, theta_z2
    xz = [2, 4, 8, 10] + [next(bubbles) for _ in range(pb - 3)]   # w1, theta_y1, w2, theta_y2
    Ka, Ma = rod_matrices(h, b.axial_stiffness, b.linear_density, pr)
    Kt, Mt = rod_matrices(h, b.torsional_stiffness, b.torsional_inertia, pr)
    Kz, Mz = bending_matrices(h, b.bending_stiffness, b.linear_density, pb)
    Ky, My = bending_matrices(h, b.bending_stiffness_y, b.linear_density, pb)
    D = np.ones(pb + 1)
    D[[1, 3]] = -1.0                          # theta_y = -dw/dx (module docstring)
    Ky, My = D[:, None] * Ky * D, D[:, None] * My * D
    for dofs, Ke, Me in ((axial, Ka, Ma), (torsion, Kt, Mt), (xy, Kz, Mz), (xz, Ky, My)):
        K[np.ix_(dofs, dofs)] += Ke
        M[np.ix_(dofs, dofs)] += Me
    return K, M


# ---------------------------------------------------------------------------------------------
# One beam
# ---------------------------------------------------------------------------------------------

def _beam_dof_map(n_elements: int, rod_order: int, bending_order: int) -> np.ndarray:
    """Global degree of freedom of each element's local one, shape (n_elements, n_element_dofs)."""
    nb = _n_bubbles(rod_order, bending_order)
    e = np.arange(n_elements)[:, None]
    nodal = np.concatenate([6 * e + np.arange(6), 6 * (e + 1) + np.arange(6)], axis=1)
    bubbles = 6 * (n_elements + 1) + nb * e + np.arange(nb)
    return np.concatenate([nodal, bubbles], axis=1)


def _n_beam_dofs(n_elements: int, rod_order: int, bending_order: int) -> int:
    return 6 * (n_elements + 1) + _n_bubbles(rod_order, bending_order) * n_elements


def _assemble(Ke: np.ndarray, dof_map: np.ndarray, n: int) -> scipy.sparse.csr_array:
    rows = np.repeat(dof_map, Ke.shape[0], axis=1).ravel()
    cols = np.tile(dof_map, (1, Ke.shape[0])).ravel()
    data = np.tile(Ke.ravel(), dof_map.shape[0])
    return scipy.sparse.csr_array(scipy.sparse.coo_array((data, (rows, cols)), shape=(n, n)))


def beam_matrices(L: float, EIz: float, EIy: float, GJ: float, rhoIp: float, EA: float,
                  rhoA: float, n_elements: int, *, rod_order: int = 5, bending_order: int = 5):
    """Stiffness and mass of a free uniform beam in local axes, n_elements equal elements.

    Parameters
    ----------
    L : float, m
    EIz, EIy : float, N m^2
        Bending stiffness in the x-y and x-z planes.
    GJ : float, N m^2
    rhoIp : float, kg m
    EA : float, N
    rhoA : float, kg/m
    n_elements : int
    rod_order : int
        Order of the axial and torsion interpolation (:func:`rod_matrices`).
    bending_order : int
        Degree of the bending interpolation (:func:`bending_matrices`); 3 is the plain Hermite
        cubic.

    Returns
    -------
    K, M : scipy.sparse.csr_array, shape (n, n), n = 6 (N + 1) + nb N
        Degree of freedom 6 i + j is motion j of node i (x = i L / N; node 0 is the root), j in
        (u, v, w, theta_x, theta_y, theta_z); the nb bubble amplitudes of element e follow from
        6 (N + 1) + nb e, in the order of :func:`element_matrices`.
    """
    params = _as_params(BeamParameters(L, EIz, EIy, GJ, rhoIp, EA, rhoA))
    return _beam_matrices(params, n_elements, rod_order, bending_order)


def beam_dof_motions(n_elements: int, *, rod_order: int = 5,
                     bending_order: int = 5) -> np.ndarray:
    """The motion each degree of freedom of :func:`beam_matrices` belongs to.

    Parameters
    ----------
    n_elements : int
    rod_order, bending_order : int

    Returns
    -------
    ndarray of str, shape (n,)
        One of "u", "v", "w", "theta_x", "theta_y", "theta_z": the nodal motion, or for a
        bubble the motion it enriches ("u" axial, "theta_x" torsion, "v" and "w" bending).
    """
    n_elements = _count("n_elements", n_elements)
    pr, pb = _orders(rod_order, bending_order)
    nodal = ["u", "v", "w", "theta_x", "theta_y", "theta_z"] * (n_elements + 1)
    bubbles = (["u"] * (pr - 1) + ["theta_x"] * (pr - 1) + ["v"] * (pb - 3)
               + ["w"] * (pb - 3)) * n_elements
    return np.array(nodal + bubbles)


def _beam_matrices(params: BeamParameters, n_elements, rod_order, bending_order):
    n_elements = _count("n_elements", n_elements)
    pr, pb = _orders(rod_order, bending_order)
    Ke, Me = element_matrices(params, params.length / n_elements, pr, pb)
    dof_map = _beam_dof_map(n_elements, pr, pb)
    n = _n_beam_dofs(n_elements, pr, pb)
    return _assemble(Ke, dof_map, n), _assemble(Me, dof_map, n)


def _complex_s(s) -> np.ndarray:
    try:
        s = np.asarray(s, dtype=complex)
    except (TypeError, ValueError):
        raise TypeError(f"s must be a complex number or array [rad/s]; got {_short(s)}") from None
    if not np.all(np.isfinite(s)):
        raise ValueError(f"s must be finite [rad/s]; got {_short(s)}")
    if np.any(s == 0):
        raise ValueError("s must be nonzero [rad/s]: a free body has a 1/s^2 pole at s = 0")
    return s


class SingularMatrixError(RuntimeError):
    """A matrix to be factorised is singular: the structure is a mechanism, or more free than
    the caller said (more zero-frequency modes than n_rigid), or s sits on a pole."""


def _factor(A, **options):
    try:
        return scipy.sparse.linalg.splu(scipy.sparse.csc_array(A), **options)
    except RuntimeError as error:                     # SuperLU: "Factor is exactly singular"
        raise SingularMatrixError(
            f"singular matrix ({error}): a mechanism, more zero-frequency modes than n_rigid "
            f"(the first n_rigid degrees of freedom must carry all rigid motions), or s on a "
            f"pole") from None


class _RefinedLU:
    """Solves of (sum_i c_i A_i) x = b: sparse LU, refined with residuals in extended precision.

    A beam's stiffness matrix has a condition number of order N^4 (N elements), and a plain LU
    solve loses about that many digits in the smooth, low-frequency directions. Worse, forming
    K + c M in double rounds every entry of K anew: each element's entries are rounded alike,
    the rigid motions stop being exact null vectors, and the lowest eigenvalues shift by about
    eps kappa(K): with 160 Hermite elements the first cantilever frequency came out 5e-8 off
    (measured), with 320 elements 3e-7. So the terms are kept apart: the LU factors of the
    rounded sum serve only to solve for corrections, and the residual
    r = b - sum_i c_i A_i x is formed in long double (80-bit on x86-64, eps = 1.1e-19) from the
    stored terms, whose own rounding shifts the eigenvalues by only about eps N^2. Each step of
    this mixed-precision iterative refinement gains about -log10(eps kappa) digits ([5]_), so
    it stops when the corrections stop shrinking. Where long double is plain double, the
    refinement is harmless and gains nothing.
    """

    def __init__(self, terms, max_steps: int = 10, n_dense_last: int = 0):
        self.terms = [(c, scipy.sparse.csr_array(A)) for c, A in terms]
        total = scipy.sparse.csr_array(sum(c * A for c, A in self.terms))
        complex_ = np.iscomplexobj(total.data)
        self.wide = np.clongdouble if complex_ else np.longdouble
        self.terms_wide = [(self.wide(c), A.astype(np.longdouble)) for c, A in self.terms]
        # A band-limiting order (reverse Cuthill-McKee) with the n_dense_last dense rows and
        # columns of a border kept last: the factors then fill only the band and the border.
        # Without a border, SuperLU's own column order (COLAMD) is the fastest measured.
        n = total.shape[0]
        body = n - n_dense_last
        if n_dense_last:
            order = scipy.sparse.csgraph.reverse_cuthill_mckee(
                scipy.sparse.csr_array(total[:body][:, :body]), symmetric_mode=True)
            self.order = np.concatenate([order, np.arange(body, n)])
            permuted = total[self.order][:, self.order]
            self.lu = _factor(permuted, permc_spec="NATURAL")
        else:
            self.order = np.arange(n)
            self.lu = _factor(total)
        self.max_steps = max_steps
        self.size = float(np.max(np.abs(total.data), initial=0.0))

    def _lu_solve(self, b):
        x = np.empty_like(b, dtype=np.result_type(b.dtype, self.lu.L.dtype))
        x[self.order] = self.lu.solve(b[self.order])
        return x

    def solve(self, b, refine: bool = True):
        b = np.asarray(b)
        x = self._lu_solve(b)
        self._check_regular(b, x)
        b_wide = b.astype(self.wide)
        previous = np.inf
        for _ in range(self.max_steps if refine else 0):
            x_wide = x.astype(self.wide)
            r = b_wide.copy()
            for c, A in self.terms_wide:
                r -= c * (A @ x_wide)
            dx = self._lu_solve(r.astype(x.dtype))
            x = x + dx
            # Stop when the corrections stop shrinking: they then only reflect the rounding of
            # x to double, amplified by the condition number (measured: about 1e-11 relative
            # for 80 elements, reached after one or two steps).
            size = np.max(np.abs(dx))
            if size > 0.5 * previous or size == 0.0:
                break
            previous = size
        return x


    def _check_regular(self, b, x):
        """Raise SingularMatrixError if x = A^-1 b shows A singular to working precision.

        SuperLU reports a singular matrix only when a pivot comes out exactly zero, and
        whether it does is decided by rounding (by the BLAS kernel of the machine, measured:
        a free beam held at five of its six rigid degrees of freedom factored without
        complaint on one CPU and as exactly singular on others). Otherwise the pivot of the
        null direction is ~eps |A| and the solve returns |x| ~ |b| / (eps |A|). For any
        matrix, max|A| max|x| / max|b| <= kappa_inf(A), so a ratio above 1 / (64 eps)
        (7e13) means eps kappa > 1/64: beyond what the refinement can correct. Measured: up
        to 1.7e11 in the solves of the tests' meshes (kappa ~ N^4 for N elements), 1e18 to
        1e19 for the singular matrices.
        """
        top = float(np.max(np.abs(b), initial=0.0))
        if self.size * float(np.max(np.abs(x), initial=0.0)) > top / (64 * np.finfo(float).eps):
            raise SingularMatrixError(
                "singular matrix (to working precision: a solve grew the loads by more than "
                "1 / (64 eps)): a mechanism, more zero-frequency modes than n_rigid (the first "
                "n_rigid degrees of freedom must carry all rigid motions), or s on a pole")


def _scaled(K, M):
    """D K D, D M D and d = diag(D): each degree of freedom scaled to unit mass.

    d is diag(M)^(-1/2) rounded to a power of two, so that the scaling is exact: every element
    of a uniform beam has the same matrices, and an inexact scaling would round them all alike,
    a coherent error that does not average out (it shifts the lowest eigenvalues by about
    eps kappa(K)).
    """
    K = scipy.sparse.csc_array(K, dtype=float)
    M = scipy.sparse.csc_array(M, dtype=float)
    diagonal = M.diagonal()
    if not np.all(diagonal > 0.0):
        raise ValueError("M must have a positive diagonal (every degree of freedom has mass)")
    d = np.exp2(np.round(-0.5 * np.log2(diagonal)))
    Dg = scipy.sparse.diags_array(d)
    return (Dg @ K @ Dg).tocsc(), (Dg @ M @ Dg).tocsc(), d


class _FreeStructure:
    """A structure whose first n_rigid degrees of freedom carry its rigid-body motions.

    The matrices are scaled to unit mass first (:func:`_scaled`). Phi holds the rigid modes
    normalised to unit motion of the reference degrees of freedom r = 0..n_rigid-1 (the hub, or
    a beam's root node): Phi_r = I and K Phi = 0, so Phi_f = -K_ff^-1 K_fr, a solve with the
    structure held at r (a regular matrix: held there, it is no mechanism). G = Phi^T M Phi is
    the rigid body's mass matrix at r.

    The flexible response to loads b is found from the bordered system ([6]_, inertia
    relief)::

        [[K + s^2 M, M Phi], [Phi^T M, 0]] [y; mu] = [b - M Phi G^-1 Phi^T b; 0]

    whose solution y = sum_k phi_k phi_k^T b / (omega_k^2 + s^2) over the flexible modes is
    M-orthogonal to the rigid ones; the bordered matrix stays regular at s = 0, so no solve
    meets the 1/s^2 of the rigid motion or the singularity of K.
    """

    def __init__(self, K, M, n_rigid: int):
        self.Ks, self.Ms, self.d = _scaled(K, M)
        n = self.Ks.shape[0]
        self.n_rigid = n_rigid
        r, f = np.arange(n_rigid), np.arange(n_rigid, n)
        self.Phi = np.zeros((n, n_rigid))
        if n_rigid:
            self.Phi[r] = np.eye(n_rigid)
            self.Phi[f] = -_RefinedLU([(1.0, self.Ks[f][:, f])]).solve(
                self.Ks[f][:, r].toarray())
        self.MPhi = self.Ms @ self.Phi
        G = _tdot(self.Phi, self.MPhi)
        self.G = 0.5 * (G + G.T)
        pad = scipy.sparse.csr_array((n_rigid, n_rigid))
        self.K_border = scipy.sparse.block_diag([self.Ks, pad], format="csr")
        self.M_border = scipy.sparse.block_diag([self.Ms, pad], format="csr")
        self.border = scipy.sparse.bmat([[None, scipy.sparse.csr_array(self.MPhi)],
                                         [scipy.sparse.csr_array(self.MPhi.T), None]],
                                        format="csr") if n_rigid else None

    def rigid_part(self, b):
        """G^-1 Phi^T b: the rigid-body accelerations of the reference point per unit s^2."""
        return np.linalg.solve(self.G, _tdot(self.Phi, b))

    def relieve(self, b):
        """b - M Phi G^-1 Phi^T b: the loads less those that accelerate the rigid body."""
        return b - _dot(self.MPhi, self.rigid_part(b)) if self.n_rigid else b

    def flexible_solver(self, s2):
        """A solver y = flexible_solver(s2)(b) for relieved loads b at s^2 = s2."""
        n = self.Ks.shape[0]
        if not self.n_rigid:
            lu = _RefinedLU([(1.0, self.Ks), (s2, self.Ms)] if s2 else [(1.0, self.Ks)])
            return lu.solve
        terms = [(1.0, self.K_border), (1.0, self.border)]
        if s2:
            terms.insert(1, (s2, self.M_border))
        lu = _RefinedLU(terms, n_dense_last=self.n_rigid)

        def solve(b, refine=True):
            padded = np.vstack([b, np.zeros((self.n_rigid,) + b.shape[1:], dtype=b.dtype)])
            return lu.solve(padded, refine)[:n]
        return solve


def _free_compliance(K, M, s) -> np.ndarray:
    """Motions of degrees of freedom 0..5 per loads on them, for a free structure.

    For each s, rows and columns 0..5 of (K + s^2 M)^-1, where degrees of freedom 0..5 (a
    beam's root node, or the hub) carry the six rigid-body motions. With the rigid part
    taken out exactly (:class:`_FreeStructure`)::

        x = Phi G^-1 Phi^T f / s^2 + y(s)

    and only the flexible y is solved for, by a refined sparse LU for each s.
    """
    s = _complex_s(s)
    free = _FreeStructure(K, M, 6)
    r = np.arange(6)
    loads = np.zeros((free.Ks.shape[0], 6))
    loads[r, r] = free.d[r]                      # unit loads, in scaled coordinates
    rigid = free.rigid_part(loads)
    relieved = free.relieve(loads).astype(complex)
    out = np.empty(s.shape + (6, 6), dtype=complex)
    for index in np.ndindex(s.shape):
        s2 = complex(s[index]) ** 2
        try:
            with np.errstate(all="raise"):
                y = free.flexible_solver(s2)(relieved)
        except FloatingPointError:
            raise SingularMatrixError(f"s = {_short(complex(s[index]))} [rad/s] is on or too "
                                      f"near a pole") from None
        out[index] = free.d[r, None] * (free.Phi[r] @ rigid / s2 + y[r])
    return out


def root_compliance(params, s, n_elements: int, *, rod_order: int = 5,
                    bending_order: int = 5) -> np.ndarray:
    """W6(s) of the free-free beam from the finite-element model.

    Root motions (u, v, w, theta_x, theta_y, theta_z) at x = 0 caused by root loads
    (F_x, F_y, F_z, M_x, M_y, M_z) at x = 0, beam axes: the root-node block of
    (K + s^2 M)^-1, by a sparse solve for each s.

    Parameters
    ----------
    params : BeamParameters or mapping or object with its attributes
    s : complex or array of complex, rad/s
        Nonzero, away from the free-free poles.
    n_elements : int
    rod_order, bending_order : int
        As in :func:`beam_matrices`.

    Returns
    -------
    ndarray of complex, shape np.shape(s) + (6, 6)
    """
    K, M = _beam_matrices(_as_params(params), n_elements, rod_order, bending_order)
    return _free_compliance(K, M, s)


def rigid_root_compliance(params) -> np.ndarray:
    """The limit s^2 W6(s) as s -> 0: the rigid beam's root accelerations per root load.

    A free rigid uniform beam of mass m = rho*A*L has its centre G at x = L/2, so the root P is
    at r = P - G = (-L/2, 0, 0). Its inertia about G in beam axes is
    J = diag(rho*I_p L, m L^2/12, m L^2/12) (no rotary inertia of the section: Euler-Bernoulli).
    Loads F, M at P give (linearised, at rest)::

        a_G = F/m,   alpha = J^-1 (M + r x F),   a_P = a_G + alpha x r,

    with r x F = (0, L F_z/2, -L F_y/2) and alpha x r = (0, -L alpha_z/2, L alpha_y/2). Hence

    ============  ======  ======  ======  ==============  ========  =========
    (a_P, alpha)  F_x     F_y     F_z     M_x             M_y       M_z
    ============  ======  ======  ======  ==============  ========  =========
    u             1/m
    v                     4/m                                       -6/(mL)
    w                             4/m                     6/(mL)
    theta_x                                1/(rho I_p L)
    theta_y                       6/(mL)                  12/(mL^2)
    theta_z               -6/(mL)                                   12/(mL^2)
    ============  ======  ======  ======  ==============  ========  =========

    e.g. v: F_y (1/m + (L/2)^2 / (m L^2/12)) = 4 F_y/m. The x-z plane couplings have the sign
    opposite to the x-y plane's because theta_y = -dw/dx. In W6, the rigid body's motion is this
    matrix over s^2 (u = a/s^2); the flexible part adds a finite term as s -> 0.

    Parameters
    ----------
    params : BeamParameters or mapping or object with its attributes

    Returns
    -------
    ndarray, shape (6, 6), units 1/kg, 1/(kg m), 1/(kg m^2)
    """
    b = _as_params(params)
    m, L = b.mass, b.length
    A = np.zeros((6, 6))
    A[0, 0] = 1.0 / m
    A[1, 1] = A[2, 2] = 4.0 / m
    A[3, 3] = 1.0 / (b.torsional_inertia * L)
    A[4, 4] = A[5, 5] = 12.0 / (m * L**2)
    A[1, 5] = A[5, 1] = -6.0 / (m * L)
    A[2, 4] = A[4, 2] = 6.0 / (m * L)
    return A


# ---------------------------------------------------------------------------------------------
# Spacecraft
# ---------------------------------------------------------------------------------------------

def _cross_matrix(r: np.ndarray) -> np.ndarray:
    """[r]x with [r]x a = r x a."""
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _vector3(name: str, value, unit: str) -> np.ndarray:
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be 3 real numbers [{unit}]; got {_short(value)}") from None
    if v.shape != (3,):
        raise ValueError(f"{name} must have shape (3,) [{unit}]; got shape {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be finite [{unit}]; got {_short(v.tolist())}")
    return v


def _rotation(name: str, value) -> np.ndarray:
    try:
        R = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be a 3x3 real rotation matrix; got {_short(value)}") from None
    if R.shape != (3, 3):
        raise ValueError(f"{name} must have shape (3, 3); got shape {R.shape}")
    # Orthonormality to 1e-9: a matrix typed with 10 digits passes, a scaled one does not.
    if (not np.all(np.isfinite(R)) or np.max(np.abs(R.T @ R - np.eye(3))) > 1e-9
            or np.linalg.det(R) < 0):
        raise ValueError(f"{name} must be a proper rotation (R^T R = I, det R = +1); "
                         f"got {_short(R.tolist())}")
    return R


def mount_transformation(position, orientation) -> np.ndarray:
    """T with (root motions in beam axes) = T (hub motions), for a rigid attachment.

    The hub's motions are the translation u_G of its centre of mass and its small rotation
    vector phi, hub axes. A point of the hub at r (from the centre of mass, hub axes) moves by
    u_P = u_G + phi x r = u_G - [r]x phi, and every line through it turns by phi. The beam's
    root moves with that point; its local axes are the columns of R (orientation), so a hub-axes
    vector a has local components R^T a::

        T = [[R^T, 0], [0, R^T]] [[I, -[r]x], [0, I]]

    Parameters
    ----------
    position : array_like, shape (3,), m
        Attachment point r, hub axes, from the hub's centre of mass.
    orientation : array_like, shape (3, 3)
        Rotation whose columns are the beam's local x, y, z axes in hub axes.

    Returns
    -------
    ndarray, shape (6, 6)
    """
    r = _vector3("position", position, "m")
    R = _rotation("orientation", orientation)
    rigid = np.eye(6)
    rigid[:3, 3:] = -_cross_matrix(r)
    return np.kron(np.eye(2), R.T) @ rigid


def _hub_inertia(value) -> np.ndarray:
    try:
        J = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"hub_inertia must be a 3x3 real matrix [kg m^2]; "
                        f"got {_short(value)}") from None
    if J.shape != (3, 3):
        raise ValueError(f"hub_inertia must have shape (3, 3) [kg m^2]; got shape {J.shape}")
    if not np.all(np.isfinite(J)) or np.max(np.abs(J - J.T)) > 1e-12 * np.max(np.abs(J)):
        raise ValueError(f"hub_inertia must be finite and symmetric [kg m^2]; "
                         f"got {_short(J.tolist())}")
    if np.min(np.linalg.eigvalsh(J)) <= 0.0:
        raise ValueError(f"hub_inertia must be positive definite [kg m^2]; "
                         f"got {_short(J.tolist())}")
    return 0.5 * (J + J.T)


def _mounts(mounts):
    if isinstance(mounts, (str, bytes)) or not isinstance(mounts, Sequence):
        raise TypeError(f"mounts must be a sequence of (params, position, orientation); "
                        f"got {_short(mounts)}")
    out = []
    for i, mount in enumerate(mounts):
        if not isinstance(mount, Sequence) or len(mount) != 3:
            raise ValueError(f"mounts[{i}] must be (params, position, orientation); "
                             f"got {_short(mount)}")
        params, position, orientation = mount
        out.append((_as_params(params), _vector3(f"mounts[{i}] position", position, "m"),
                    _rotation(f"mounts[{i}] orientation", orientation)))
    return out


def _layout(mounts, n_elements, rod_order, bending_order):
    """Start of each beam's free degrees of freedom in the spacecraft vector, and the total."""
    n_beam = _n_beam_dofs(n_elements, rod_order, bending_order)
    starts = [6 + i * (n_beam - 6) for i in range(len(mounts))]
    return starts, 6 + len(mounts) * (n_beam - 6)


def spacecraft_matrices(hub_mass: float, hub_inertia, mounts, n_elements: int, *,
                        rod_order: int = 5, bending_order: int = 5):
    """Stiffness and mass of a free-floating rigid hub carrying beams rigidly attached.

    Degrees of freedom: the hub's six first (translation of its centre of mass u_G along hub
    x, y, z [m], then its small rotation vector phi [rad]), then for each mount in turn all of
    its beam's degrees of freedom (:func:`beam_matrices`) except the root node's six, which are
    slaved to the hub: u_root = T q_hub (:func:`mount_transformation`). With P_b the map from
    the spacecraft's degrees of freedom to beam b's, K = sum_b P_b^T K_b P_b + 0 and
    M = diag(m I, J) + sum_b P_b^T M_b P_b.

    Parameters
    ----------
    hub_mass : float, kg
    hub_inertia : array_like, shape (3, 3), kg m^2
        About the hub's centre of mass, hub axes; symmetric positive definite.
    mounts : sequence of (params, position, orientation)
        params: BeamParameters (or mapping or object with its attributes); position (3,) [m]
        from the hub's centre of mass, hub axes; orientation (3, 3), columns the beam's local
        x, y, z axes in hub axes.
    n_elements : int
        Elements per beam.
    rod_order, bending_order : int
        As in :func:`beam_matrices`.

    Returns
    -------
    K, M : scipy.sparse.csr_array
    """
    hub_mass = _positive("hub_mass", hub_mass, "kg")
    J = _hub_inertia(hub_inertia)
    mounts = _mounts(mounts)
    n_elements = _count("n_elements", n_elements)
    rod_order, bending_order = _orders(rod_order, bending_order)
    starts, n = _layout(mounts, n_elements, rod_order, bending_order)
    hub = np.zeros((6, 6))
    hub[:3, :3] = hub_mass * np.eye(3)
    hub[3:, 3:] = J
    K = scipy.sparse.csr_array((n, n))
    M = scipy.sparse.csr_array(scipy.sparse.coo_array(
        (hub.ravel(), np.divmod(np.arange(36), 6)), shape=(n, n)))
    for (params, position, R), start in zip(mounts, starts):
        Kb, Mb = _beam_matrices(params, n_elements, rod_order, bending_order)
        P = _beam_gather(mount_transformation(position, R), start, Kb.shape[0], n)
        K = K + P.T @ Kb @ P
        M = M + P.T @ Mb @ P
    # Symmetric by construction; the symmetrisation removes round-off asymmetry of P^T A P.
    return (0.5 * (K + K.T)).tocsr(), (0.5 * (M + M.T)).tocsr()


def _beam_gather(T, start, n_beam, n):
    """P with (beam b's degrees of freedom) = P (spacecraft's)."""
    rows = np.concatenate([np.repeat(np.arange(6), 6), np.arange(6, n_beam)])
    cols = np.concatenate([np.tile(np.arange(6), 6), start + np.arange(n_beam - 6)])
    data = np.concatenate([T.ravel(), np.ones(n_beam - 6)])
    return scipy.sparse.csr_array(scipy.sparse.coo_array((data, (rows, cols)),
                                                         shape=(n_beam, n)))


def rigid_body_modes(mounts, n_elements: int, *, rod_order: int = 5,
                     bending_order: int = 5) -> np.ndarray:
    """The six rigid-body motions of the spacecraft, columns for unit hub motions.

    Column j moves the hub by unit motion j (u_G x, y, z, phi x, y, z) and every beam node at
    x along beam b rigidly with it: in beam axes, R^T (u_G + phi x (r_b + x R e_x)) and the
    rotation R^T phi; the bubbles stay zero (a rigid motion is linear in x).

    Parameters
    ----------
    mounts : sequence of (params, position, orientation)
    n_elements : int
    rod_order, bending_order : int
        As in :func:`beam_matrices`.

    Returns
    -------
    ndarray, shape (n, 6)
    """
    mounts = _mounts(mounts)
    n_elements = _count("n_elements", n_elements)
    rod_order, bending_order = _orders(rod_order, bending_order)
    starts, n = _layout(mounts, n_elements, rod_order, bending_order)
    Phi = np.zeros((n, 6))
    Phi[:6] = np.eye(6)
    for (params, position, R), start in zip(mounts, starts):
        for node in range(1, n_elements + 1):
            x = params.length * node / n_elements
            T = mount_transformation(position + x * R[:, 0], R)
            Phi[start + 6 * (node - 1): start + 6 * node] = T
    return Phi


# ---------------------------------------------------------------------------------------------
# Frequencies and frequency responses
# ---------------------------------------------------------------------------------------------

def _tdot(A, B):
    """A^T B for tall thin A, B, without BLAS.

    einsum's own loops: a threaded BLAS product of tall thin matrices costs up to hundreds of
    milliseconds on an oversubscribed machine (measured: 430 ms for 5000 x 20 with 2 BLAS
    threads on 2 busy cores, against 0.8 ms here).
    """
    return np.einsum("ij,ik->jk", A, B)


def _dot(A, B):
    """A B for tall thin A and small B, without BLAS (see :func:`_tdot`)."""
    return np.einsum("ij,jk->ik", A, B)


def _orthonormal(X):
    """An orthonormal basis of span(X) (X of full column rank, p << rows).

    Cholesky QR of the column-normalised X (one small Gram matrix, one p x p triangle): a
    Householder QR of a tall thin matrix makes many small BLAS calls, which cost tens of
    milliseconds each on an oversubscribed machine (measured: 27 ms a call with 4 BLAS threads
    on 2 busy cores). Householder QR is the fallback when X is too ill-conditioned for
    Cholesky QR (diagonal of R below 1e-4: orthogonality lost would exceed 1e-8, which the
    generalised Ritz problem would absorb, but no reason to go there).
    """
    X = X / np.linalg.norm(X, axis=0)
    try:
        R = scipy.linalg.cholesky(_tdot(X, X))
    except np.linalg.LinAlgError:
        R = None
    if R is None or np.min(np.abs(np.diagonal(R))) < 1e-4:
        return np.linalg.qr(X)[0]
    return _dot(X, scipy.linalg.solve_triangular(R, np.eye(R.shape[0])))


def natural_frequencies(K, M, n: int, *, n_rigid: int = 6) -> np.ndarray:
    """The first n nonzero natural frequencies [rad/s] of K x = omega^2 M x.

    The rigid-body modes are removed exactly (:class:`_FreeStructure`; the first n_rigid
    degrees of freedom must carry them, as the hub's do in :func:`spacecraft_matrices` and the
    root node's in :func:`beam_matrices`), and the flexible ones found by block inverse
    (subspace) iteration with Rayleigh-Ritz on a block of p = n + 10 vectors ([6]_, [7]_),
    for the operator T = K^+ M (K^+ by the bordered solve, flexible part only), whose largest
    eigenvalues 1/lambda are the wanted ones: they come out with relative errors of about
    eps lambda/lambda_1. K is never multiplied by a vector: a product with K would cancel away
    about log10(kappa(K)) digits in the smooth low modes. A block method,
    unlike single-vector Lanczos, finds every copy of a repeated frequency (symmetric
    spacecraft). The eigenvalues converge like (lambda_i/lambda_(p+1))^(2k) after k steps; the
    iteration stops when the first n change by less than 1e-12 relative, or stop shrinking
    below 1e-10 (rounding).

    Parameters
    ----------
    K, M : sparse or dense, shape (N, N)
        Symmetric; M positive definite, K positive semi-definite with exactly n_rigid zero
        modes, carried by degrees of freedom 0..n_rigid-1.
    n : int
        Number of frequencies.
    n_rigid : int
        Number of zero-frequency modes: 6 for a free-floating spacecraft or a free beam, 0 for
        a constrained structure (K positive definite).

    Returns
    -------
    ndarray, shape (n,), rad/s, ascending

    Raises
    ------
    SingularMatrixError
        (a RuntimeError) If K held at degrees of freedom 0..n_rigid-1 is singular to working
        precision (:meth:`_RefinedLU.solve`), or a mode found has zero frequency: more zero
        modes than n_rigid, or rigid modes not carried by those degrees of freedom.
    RuntimeError
        If the iteration does not converge in 500 steps.
    """
    n = _count("n", n)
    n_rigid = _count("n_rigid", n_rigid, minimum=0)
    if K.shape != M.shape or K.shape[0] != K.shape[1]:
        raise ValueError(f"K and M must be square and of one shape; got {K.shape}, {M.shape}")
    n_flexible = K.shape[0] - n_rigid
    if n > n_flexible:
        raise ValueError(f"n must be at most the number of flexible modes ({n_flexible}); "
                         f"got {n}")
    free = _FreeStructure(K, M, n_rigid)
    solve = free.flexible_solver(0.0)
    p = min(n + 10, n_flexible)
    # A fixed seed: the same start, hence the same result, on every run and thread count.
    Q = _orthonormal(np.random.default_rng(20260611).standard_normal((K.shape[0], p)))
    previous, last_change = np.full(n, np.inf), np.inf
    refine, n_refined = False, 0
    for _ in range(500):
        MQ = free.Ms @ Q
        Y = solve(MQ, refine)                            # K^+ M Q
        n_refined += refine
        # Rayleigh-Ritz for T = K^+ M (self-adjoint in the M inner product) on span(Q):
        # (Q^T M T Q) w = nu (Q^T M Q) w, nu = 1/lambda. Q is orthonormal and M well
        # conditioned, so the small problem is too; products with K never occur.
        H = _tdot(MQ, Y)
        B = _tdot(MQ, Q)
        nu, W = scipy.linalg.eigh(0.5 * (H + H.T), 0.5 * (B + B.T))
        nu, W = nu[::-1], W[:, ::-1]                     # largest nu = lowest lambda first
        lam = 1.0 / nu[:n]
        # Converged: changes below 1e-12, or below 1e-10 and no longer shrinking (they then
        # only reflect rounding; measured: about 1e-13 relative, reached in about ten steps).
        # Refined solves only once the subspace has settled to 1e-8 (they cost two to three
        # times a plain solve); the answer comes from two refined steps at least.
        change = np.max(np.abs(lam - previous) / np.abs(lam))
        refine = refine or change <= 1e-8
        if n_refined >= 2 and (change <= 1e-12 or (change <= 1e-10
                                                   and change > 0.5 * last_change)):
            break
        previous, last_change = lam, change
        Q = _orthonormal(_dot(Y, W))                          # T applied to the Ritz vectors
    else:
        raise RuntimeError(f"natural_frequencies: the subspace iteration did not converge in "
                           f"500 steps (eigenvalues {_short(lam.tolist())} [rad^2/s^2])")
    if not np.all(nu[:n] > 0) or lam[0] <= 1e-10 * lam[-1]:
        raise SingularMatrixError(f"more than n_rigid = {n_rigid} zero-frequency modes: eigenvalues "
                           f"{_short(lam.tolist())} [rad^2/s^2]")
    return np.sqrt(lam)


def hub_compliance(K, M, s) -> np.ndarray:
    """The hub's motions caused by loads on the hub: rows/columns 0..5 of (K + s^2 M)^-1.

    Motions (u_G x, y, z, phi x, y, z) per loads (F x, y, z at the centre of mass, torque x, y,
    z), hub axes, for the matrices of :func:`spacecraft_matrices`. For s = j omega this is
    (K - omega^2 M)^-1, the frequency response.

    Parameters
    ----------
    K, M : sparse or dense
    s : complex or array of complex, rad/s
        Nonzero, away from the coupled poles.

    Returns
    -------
    ndarray of complex, shape np.shape(s) + (6, 6)
    """
    return _free_compliance(K, M, s)


def attitude_compliance(K, M, s) -> np.ndarray:
    """theta(s)/torque(s): the hub's rotation caused by a torque on the hub, hub axes.

    The 3x3 block phi/torque of :func:`hub_compliance`; the hub's translation is free, so the
    low-frequency limit is the (phi, phi) block of the rigid spacecraft's inverse 6x6 mass
    matrix over s^2.

    Parameters
    ----------
    K, M : sparse or dense
    s : complex or array of complex, rad/s

    Returns
    -------
    ndarray of complex, shape np.shape(s) + (3, 3)
    """
    return hub_compliance(K, M, s)[..., 3:, 3:]


# ---------------------------------------------------------------------------------------------
# Stepped beams with a tip body (issue 21): segments of uniform elements, a rigid body at the end
# ---------------------------------------------------------------------------------------------

class TipSpec(NamedTuple):
    """A rigid body fixed to the free end of a beam.

    Attributes
    ----------
    mass : float, kg
    inertia : array_like (3, 3), kg m^2
        About the body's centre of mass, beam axes.
    offset : array_like (3,), m
        The centre of mass from the free end, beam axes.
    """

    mass: float
    inertia: np.ndarray
    offset: np.ndarray


def tip_mass_matrix(tip: TipSpec) -> np.ndarray:
    """The tip body's 6x6 mass matrix about the free-end node, in (u, v, w, theta_x, theta_y,
    theta_z).

    A point of the body at r from the node moves by u + theta x r. The kinetic energy of the body
    (mass m, centre at c, inertia J about the centre) is m/2 |u' + theta' x c|^2 +
    1/2 theta'^T J theta'; with theta x c = -[c]x theta, the velocity of the centre is
    [I, -[c]x] q', so M = m [I, -[c]x]^T [I, -[c]x] + diag(0, J) ([6]_, sec. 2.6 / Goldstein).
    """
    m = float(tip.mass)
    c = _vector3("tip offset", tip.offset, "m")
    J = np.asarray(tip.inertia, dtype=float).reshape(3, 3)
    A = np.hstack([np.eye(3), -_cross_matrix(c)])
    M = m * A.T @ A
    M[3:, 3:] += J
    return 0.5 * (M + M.T)


def _stepped_layout(segments, n_elements, rod_order, bending_order):
    segments = [_as_params(p) for p in segments]
    if isinstance(n_elements, (int, np.integer)) and not isinstance(n_elements, bool):
        counts = [int(n_elements)] * len(segments)
    else:
        counts = [_count("n_elements", c) for c in n_elements]
    if len(counts) != len(segments):
        raise ValueError("n_elements must be one count or one per segment")
    return segments, counts


def stepped_beam_matrices(segments, n_elements, tip: TipSpec | None = None, *,
                          rod_order: int = 5, bending_order: int = 5):
    """Stiffness and mass of a free beam of uniform segments with a tip body, beam axes.

    Each segment (BeamParameters or mapping or object with the attributes; its length its own)
    is cut into ``n_elements`` equal elements (:func:`element_matrices`); the segments follow
    each other from the root; the tip body's :func:`tip_mass_matrix` is added at the last node.

    Returns
    -------
    K, M : scipy.sparse.csr_array
        Degrees of freedom as :func:`beam_matrices`: node i's six from 6 i (node 0 the root),
        then every element's bubble amplitudes.
    """
    pr, pb = _orders(rod_order, bending_order)
    segments, counts = _stepped_layout(segments, n_elements, pr, pb)
    n_el = sum(counts)
    nb = _n_bubbles(pr, pb)
    n = 6 * (n_el + 1) + nb * n_el
    rows, cols, k_data, m_data = [], [], [], []
    e = 0
    for params, count in zip(segments, counts):
        Ke, Me = element_matrices(params, params.length / count, pr, pb)
        for _ in range(count):
            dofs = np.concatenate([6 * e + np.arange(6), 6 * (e + 1) + np.arange(6),
                                   6 * (n_el + 1) + nb * e + np.arange(nb)])
            rows.append(np.repeat(dofs, dofs.size))
            cols.append(np.tile(dofs, dofs.size))
            k_data.append(Ke.ravel())
            m_data.append(Me.ravel())
            e += 1
    if tip is not None:
        dofs = 6 * n_el + np.arange(6)
        rows.append(np.repeat(dofs, 6))
        cols.append(np.tile(dofs, 6))
        k_data.append(np.zeros(36))
        m_data.append(tip_mass_matrix(tip).ravel())
    rows, cols = np.concatenate(rows), np.concatenate(cols)
    K = scipy.sparse.csr_array(scipy.sparse.coo_array((np.concatenate(k_data), (rows, cols)),
                                                      shape=(n, n)))
    M = scipy.sparse.csr_array(scipy.sparse.coo_array((np.concatenate(m_data), (rows, cols)),
                                                      shape=(n, n)))
    return K, M


def appendage_root_compliance(segments, n_elements, s, tip: TipSpec | None = None, *,
                              rod_order: int = 5, bending_order: int = 5) -> np.ndarray:
    """W6(s) of a free stepped beam with a tip body from the finite-element model (the root
    node's block of (K + s^2 M)^-1, rigid part in closed form: :func:`root_compliance`)."""
    K, M = stepped_beam_matrices(segments, n_elements, tip, rod_order=rod_order,
                                 bending_order=bending_order)
    return _free_compliance(K, M, s)


def appendage_spacecraft_matrices(hub_mass: float, hub_inertia, mounts, n_elements, *,
                                  rod_order: int = 5, bending_order: int = 5):
    """Stiffness and mass of a rigid hub carrying stepped beams with tip bodies.

    As :func:`spacecraft_matrices`, each mount being ``(segments, tip, position, orientation)``
    (tip a :class:`TipSpec` or None), its beam from :func:`stepped_beam_matrices`.

    Returns
    -------
    K, M : scipy.sparse.csr_array
        The hub's six degrees of freedom first, then each beam's but its root node's.
    """
    hub_mass = _positive("hub_mass", hub_mass, "kg")
    J = _hub_inertia(hub_inertia)
    beams = []
    for i, mount in enumerate(mounts):
        segments, tip, position, orientation = mount
        Kb, Mb = stepped_beam_matrices(segments, n_elements, tip, rod_order=rod_order,
                                       bending_order=bending_order)
        T = mount_transformation(_vector3(f"mounts[{i}] position", position, "m"),
                                 _rotation(f"mounts[{i}] orientation", orientation))
        beams.append((Kb, Mb, T))
    n = 6 + sum(Kb.shape[0] - 6 for Kb, _, _ in beams)
    hub = np.zeros((6, 6))
    hub[:3, :3] = hub_mass * np.eye(3)
    hub[3:, 3:] = J
    K = scipy.sparse.csr_array((n, n))
    M = scipy.sparse.csr_array(scipy.sparse.coo_array(
        (hub.ravel(), np.divmod(np.arange(36), 6)), shape=(n, n)))
    start = 6
    for Kb, Mb, T in beams:
        P = _beam_gather(T, start, Kb.shape[0], n)
        K = K + P.T @ Kb @ P
        M = M + P.T @ Mb @ P
        start += Kb.shape[0] - 6
    return (0.5 * (K + K.T)).tocsr(), (0.5 * (M + M.T)).tocsr()
