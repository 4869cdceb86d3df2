r"""Exact two-end dynamic stiffness of uniform members: Euler-Bernoulli bending and rods.

A member of length L joins two nodes; its exact (distributed-mass) dynamic stiffness relates the
end loads to the end motions at the Laplace variable s. Non-uniform appendages (stepped beams,
beams carrying a tip body: :mod:`appendages.assembly`) are assembled from these matrices and
condensed to their root, so that no transfer matrix with growing hyperbolic terms is ever
multiplied.

Bending
-------
End motions ``(w1, theta1, w2, theta2)`` with ``theta = dw/dx``, loads ``(F1, M1, F2, M2)``
applied to the member at its ends (virtual work ``F1 dw1 + M1 dtheta1 + ...``), so that
``F1 = EJ w'''(0)``, ``M1 = -EJ w''(0)``, ``F2 = -EJ w'''(L)``, ``M2 = EJ w''(L)``. With
``x = beta L``, ``beta**4 = -s**2 rho*A/EJ``, ``c, s_, C, S = cos x, sin x, cosh x, sinh x`` and
``delta = 1 - c C`` (solving ``w = a C(beta x) + b S(beta x) + ...``, checked against a 40-digit
solution of the boundary-value problem in the tests)::

    K11 = K33 =  EJ/L**3 x**3 (c S + s_ C)/delta     K12 = -K34 = EJ/L**2 x**2 s_ S/delta
    K22 = K44 =  EJ/L    x    (s_ C - c S)/delta     K13 =        -EJ/L**3 x**3 (S + s_)/delta
    K14 = -K23 = EJ/L**2 x**2 (C - c)/delta           K24 =         EJ/L x (S - s_)/delta

Every entry is even in x and invariant under ``x -> i x``: a function of ``y = x**4`` alone.
Two branches keep full accuracy, as :mod:`appendages.beam` does for the free beam:

* ``|x| < 2``: each numerator is ``y`` times a power series in y (``x**3 (c S + s_ C) =
  y sum (-1)**k 2**(2k+1) y**k/(4k+1)!``, ``-x**3 (S + s_) = -2 y sum y**k/(4k+1)!``, ...), and
  ``delta = y Q(y)`` with ``Q = -sum_{k>=1} (-4)**k y**(k-1)/(4k)!``; the ratios are power series
  in y (divided once, exactly, in rational arithmetic), convergent for ``|y| < 4.73**4`` (the
  first zero of ``delta``). Their constant terms are the static stiffness (12, 6 L, 4 L**2...)
  and their next ones the consistent (Hermite) mass matrix: K(s) = K0 + s**2 M(s).
* ``|x| >= 2``: with the principal root (``Re x >= |Im x|``), ``sigma = sign Im x``,
  ``t = e**(-2x)``, ``u = e**(2 i sigma x)``, ``q = e**(-x)``, ``h = e**(i sigma x)`` (all of
  modulus at most 1) and the common factor ``P/4 = e**(x - i sigma x)/4`` divided out of
  numerators and denominator: ``4 c C/P = (1 + u)(1 + t)``, ``4 c S/P = (1 + u)(1 - t)``,
  ``4 s_ C/P = i sigma (1 - u)(1 + t)``, ``4 s_ S/P = i sigma (1 - u)(1 - t)``,
  ``4 C/P = 2 h (1 + t)``, ``4 S/P = 2 h (1 - t)``, ``4 c/P = 2 q (1 + u)``,
  ``4 s_/P = 2 i sigma q (1 - u)``, ``4/P = 4 q h``. Nothing overflows at any |s|.

The dynamic part ``M(s) = (K(s) - K0)/s**2`` (the member's "dynamic mass", the consistent mass
matrix at s = 0) comes from the shifted series below |x| = 2 and from the closed form beyond,
where ``|K - K0|`` is not small against ``K0``.

Rods
----
Axial or torsional motion (stiffness S = EA or GJ, inertia mu = rho*A or rho*I_p per length),
end motions ``(q1, q2)``: with ``z = s L sqrt(mu/S)``,
``K = S/L [[z coth z, -z/sinh z], [-z/sinh z, z coth z]]``, stable for any z through
``t = e**(-2z)`` (``Re z >= 0``; both functions are even), and
``M(s) = mu L [[(z coth z - 1)/z**2, (1 - z/sinh z)/z**2], [...]]`` from their Bernoulli
series below |z| = 1.

Clamped-clamped frequencies
---------------------------
The Wittrick-Williams count of an assembly needs, per member, the number of its natural
frequencies with both ends clamped below w: bending ``cos x cosh x = 1`` (the roots of the
free-free beam, x_k -> (k + 1/2) pi), rods ``z = i k pi``.

References
----------
.. [1] W. H. Wittrick, F. W. Williams, "A general algorithm for computing natural frequencies of
   elastic structures", Q. J. Mech. Appl. Math. 24(3), 1971.
.. [2] J. R. Banerjee, "Dynamic stiffness formulation for structural elements: a general
   approach", Computers & Structures 63(1), 1997 (the Bernoulli-Euler member matrix).
.. [3] J. S. Przemieniecki, "Theory of Matrix Structural Analysis", McGraw-Hill, 1968, ch. 11
   (consistent mass matrices: the first terms of the series).
.. [4] NIST DLMF 4.19 (series of z coth z and z/sinh z: Bernoulli numbers).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from .checks import check_positive
from .errors import describe

__all__ = ["bending_member", "bending_static_stiffness", "bending_clamped_count",
           "bending_mass_series", "rod_mass_series",
           "rod_member", "rod_static_stiffness", "rod_clamped_count", "BENDING_ENTRIES"]

_SERIES_RADIUS = 2.0   # |x| below which the series in y = x**4 are used
_N_TERMS = 24          # terms of the series of the ratios: (16/500)**24 < 1e-35 at |x| = 2
_ROD_RADIUS = 1.0      # |z| below which the rod's dynamic part comes from its series

#: The six distinct entries of the bending member matrix, (row, column), in the order of
#: the series and scaled forms below; the others follow by symmetry and the mirror rule.
BENDING_ENTRIES = ((0, 0), (0, 1), (1, 1), (0, 2), (0, 3), (1, 3))


def _f(n: int) -> Fraction:
    return Fraction(math.factorial(n))


def _ratio_series() -> np.ndarray:
    """Series in y of the six dimensionless entries k_ij = N_ij(y)/Q(y), shape (6, terms).

    Numerators (module docstring, each divided by y): k11: sum (-1)^k 2^(2k+1) y^k/(4k+1)!,
    k12: sum (-1)^k 2^(2k+1) y^k/(4k+2)!, k22: sum (-1)^k 2^(2k+2) y^k/(4k+3)!, k13:
    -2 sum y^k/(4k+1)!, k14: 2 sum y^k/(4k+2)!, k24: 2 sum y^k/(4k+3)!. Divided by Q in exact
    rational arithmetic, then rounded once to float.
    """
    n = _N_TERMS + 2
    numerators = [
        [Fraction((-1) ** k * 2 ** (2 * k + 1)) / _f(4 * k + 1) for k in range(n)],
        [Fraction((-1) ** k * 2 ** (2 * k + 1)) / _f(4 * k + 2) for k in range(n)],
        [Fraction((-1) ** k * 2 ** (2 * k + 2)) / _f(4 * k + 3) for k in range(n)],
        [Fraction(-2) / _f(4 * k + 1) for k in range(n)],
        [Fraction(2) / _f(4 * k + 2) for k in range(n)],
        [Fraction(2) / _f(4 * k + 3) for k in range(n)],
    ]
    Q = [-Fraction((-4) ** (k + 1)) / _f(4 * k + 4) for k in range(n)]
    out = np.empty((6, _N_TERMS))
    for row, N in enumerate(numerators):
        ratio = []
        for k in range(_N_TERMS):  # N = Q * ratio, solved term by term
            ratio.append((N[k] - sum(Q[k - j] * ratio[j] for j in range(k))) / Q[0])
        out[row] = [float(r) for r in ratio]
    return out


_RATIOS = _ratio_series()
#: Static stiffness (constant terms): 12, 6, 4, -12, 6, 2.
_STATIC = _RATIOS[:, 0].copy()
#: Largest |y| for which the first K terms of the shifted series are enough (terms bounded
#: by about 6 (|y|/500)**k; below 1e-19 of the first).
_TERMS_RADIUS = np.array([500.0 * (1e-19 / 6.0) ** (1.0 / K) for K in range(1, _N_TERMS + 1)])


def _check_member(length, stiffness, inertia, stiffness_name: str, inertia_name: str,
                  part: str | None = None):
    """The member's properties as positive finite floats (a building block: the ranges of
    :data:`~appendages.interface.RANGES` are checked where the beams are made)."""
    units = {"bending_stiffness": "N*m^2", "linear_density": "kg/m",
             "stiffness": "N or N*m^2", "inertia": "kg/m or kg*m"}
    values = (check_positive("length", length, "m"),
              check_positive(stiffness_name, stiffness, units[stiffness_name]),
              None if inertia is None else check_positive(inertia_name, inertia,
                                                          units[inertia_name]))
    if part is not None and part not in ("full", "dynamic"):
        raise ValueError(f"part must be 'full' or 'dynamic'; got {describe(part)}")
    return values


def _horner(coefficients: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Rows of ``coefficients`` (ascending powers) evaluated at y, shape (rows,) + y.shape,
    with only the terms the largest |y| needs."""
    top = float(np.max(np.abs(y), initial=0.0))
    n_terms = int(np.searchsorted(_TERMS_RADIUS, top)) + 1 if top > 0 else 1
    n_terms = min(n_terms, coefficients.shape[1])
    out = np.zeros((coefficients.shape[0],) + y.shape, dtype=np.complex128)
    for k in range(n_terms - 1, -1, -1):
        out = out * y + coefficients[:, k].reshape((-1,) + (1,) * y.ndim)
    return out


def _scaled_entries(y: np.ndarray) -> np.ndarray:
    """The six dimensionless entries at |x| >= 2 from the scaled exponentials, (6,) + y.shape."""
    x = y ** 0.25  # principal root: Re x >= |Im x|
    sigma = np.where(x.imag >= 0.0, 1.0, -1.0)
    t = np.exp(-2.0 * x)
    u = np.exp(2j * sigma * x)
    q = np.exp(-x)
    h = np.exp(1j * sigma * x)
    a = (1.0 + u) * (1.0 - t)                    # 4 cos x sinh x / P
    b = 1j * sigma * (1.0 - u) * (1.0 + t)       # 4 sin x cosh x / P
    c = 1j * sigma * (1.0 - u) * (1.0 - t)       # 4 sin x sinh x / P
    p = (1.0 + u) * (1.0 + t)                    # 4 cos x cosh x / P
    den = 4.0 * q * h - p                        # 4 (1 - cos x cosh x) / P
    sinh_sum = 2.0 * h * (1.0 - t) + 2j * sigma * q * (1.0 - u)    # 4 (sinh x + sin x)/P
    cosh_diff = 2.0 * h * (1.0 + t) - 2.0 * q * (1.0 + u)          # 4 (cosh x - cos x)/P
    sinh_diff = 2.0 * h * (1.0 - t) - 2j * sigma * q * (1.0 - u)   # 4 (sinh x - sin x)/P
    x2, x3 = x * x, x * x * x
    return np.stack([x3 * (a + b), x2 * c, x * (b - a), -x3 * sinh_sum, x2 * cosh_diff,
                     x * sinh_diff]) / den


def _dimensionless(y: np.ndarray, part: str) -> np.ndarray:
    """The six entries k_ij(y) (``part="full"``) or m_ij(y) = -(k_ij(y) - k_ij(0))/y
    (``"dynamic"``), shape (6,) + y.shape."""
    out = np.empty((6,) + y.shape, dtype=np.complex128)
    small = np.abs(y) < _SERIES_RADIUS**4
    if np.any(small):
        ys = y[small]
        if part == "full":
            out[:, small] = _horner(_RATIOS, ys)
        else:
            out[:, small] = -_horner(_RATIOS[:, 1:], ys)
    if np.any(~small):
        yl = y[~small]
        full = _scaled_entries(yl)
        out[:, ~small] = full if part == "full" else -(full - _STATIC[:, None]) / yl
    return out


def _place_bending(entries: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """4x4 matrices from the six entries (last axis first), with the unit scales of each."""
    k11, k12, k22, k13, k14, k24 = (e * f for e, f in zip(entries, scale))
    K = np.empty(k11.shape + (4, 4), dtype=np.complex128)
    K[..., 0, 0] = K[..., 2, 2] = k11
    K[..., 1, 1] = K[..., 3, 3] = k22
    K[..., 0, 1] = K[..., 1, 0] = k12
    K[..., 2, 3] = K[..., 3, 2] = -k12
    K[..., 0, 2] = K[..., 2, 0] = k13
    K[..., 0, 3] = K[..., 3, 0] = k14
    K[..., 1, 2] = K[..., 2, 1] = -k14
    K[..., 1, 3] = K[..., 3, 1] = k24
    return K


def bending_member(length: float, bending_stiffness: float, linear_density: float, s,
                   part: str = "full") -> np.ndarray:
    """Exact dynamic stiffness of a uniform Euler-Bernoulli member (module docstring).

    Parameters
    ----------
    length : float, m
    bending_stiffness : float, N*m**2
    linear_density : float, kg/m
    s : ndarray of complex, rad/s
    part : {"full", "dynamic"}
        ``"full"``: K(s) [N/m, N, N*m]; ``"dynamic"``: ``M(s) = (K(s) - K0)/s**2``
        [kg, kg*m, kg*m**2], accurate down to s = 0 (the consistent mass matrix there).

    Returns
    -------
    ndarray of complex128, shape ``s.shape + (4, 4)``
        End motions ``(w1, theta1, w2, theta2)``, ``theta = dw/dx``.
    """
    L, EJ, rho = _check_member(length, bending_stiffness, linear_density, "bending_stiffness",
                               "linear_density", part)
    s = np.asarray(s, dtype=np.complex128)
    y = -(s**2) * (rho * L**4 / EJ)
    entries = _dimensionless(y.ravel(), part).reshape((6,) + s.shape)
    if part == "full":
        scale = np.array([EJ / L**3, EJ / L**2, EJ / L, EJ / L**3, EJ / L**2, EJ / L])
    else:
        scale = rho * L * np.array([1.0, L, L * L, 1.0, L, L * L])
    return _place_bending(entries, scale)


def bending_static_stiffness(length: float, bending_stiffness: float) -> np.ndarray:
    """K0 = K(0) of a bending member [N/m, N, N*m]: the textbook 12, 6 L, 4 L**2 matrix."""
    L, bending_stiffness, _ = _check_member(length, bending_stiffness, None,
                                            "bending_stiffness", "linear_density")
    scale = np.array([1.0 / L**3, 1.0 / L**2, 1.0 / L, 1.0 / L**3, 1.0 / L**2, 1.0 / L])
    return _place_bending(_STATIC.astype(complex), scale * bending_stiffness).real


def _rod_series():
    """Series in w = z**2 of (z coth z - 1)/z**2 and (1 - z/sinh z)/z**2 (DLMF 4.19)."""
    n = 20
    # Bernoulli numbers B_2k in exact rational arithmetic (Akiyama-Tanigawa)
    B = []
    a = [Fraction(0)] * (2 * n + 3)
    for m in range(2 * n + 3):
        a[m] = Fraction(1, m + 1)
        for j in range(m, 0, -1):
            a[j - 1] = j * (a[j - 1] - a[j])
        B.append(a[0])
    coth, csch = [], []
    for k in range(1, n + 1):
        # z coth z = sum 2^(2k) B_2k z^(2k)/(2k)!; z/sinh z = sum (2 - 2^(2k)) B_2k z^(2k)/(2k)!
        coth.append(float(Fraction(2 ** (2 * k)) * B[2 * k] / _f(2 * k)))
        csch.append(float(-Fraction(2 - 2 ** (2 * k)) * B[2 * k] / _f(2 * k)))
    return np.array([coth, csch])


_ROD_SERIES = _rod_series()


def rod_member(length: float, stiffness: float, inertia: float, s,
               part: str = "full") -> np.ndarray:
    """Exact dynamic stiffness of a uniform rod in axial or torsional motion.

    Parameters
    ----------
    length : float, m
    stiffness : float
        EA [N] or GJ [N*m**2].
    inertia : float
        rho*A [kg/m] or rho*I_p [kg*m].
    s : ndarray of complex, rad/s
    part : {"full", "dynamic"}
        K(s), or ``M(s) = (K(s) - K0)/s**2`` (``mu L [[1/3, 1/6], [1/6, 1/3]]`` at s = 0).

    Returns
    -------
    ndarray of complex128, shape ``s.shape + (2, 2)``
    """
    length, stiffness, inertia = _check_member(length, stiffness, inertia, "stiffness", "inertia", part)
    s = np.asarray(s, dtype=np.complex128)
    z = s * (length * math.sqrt(inertia / stiffness))
    zz = np.where(z.real < 0.0, -z, z)          # both functions are even
    diagonal = np.empty(z.shape, dtype=np.complex128)
    off = np.empty(z.shape, dtype=np.complex128)
    small = np.abs(zz) < _ROD_RADIUS
    t = np.exp(-2.0 * zz)
    e = np.expm1(-2.0 * zz)
    with np.errstate(divide="ignore", invalid="ignore"):
        zcoth = zz * (1.0 + t) / -e
        zcsch = 2.0 * zz * np.exp(-zz) / -e
    if part == "full":
        zcoth[zz == 0] = 1.0
        zcsch[zz == 0] = 1.0
        diagonal, off = zcoth, -zcsch
        scale = stiffness / length
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            diagonal = (zcoth - 1.0) / (zz * zz)
            off = (1.0 - zcsch) / (zz * zz)
        if np.any(small):
            w = zz[small] ** 2
            series = np.zeros((2,) + w.shape, dtype=np.complex128)
            for k in range(_ROD_SERIES.shape[1] - 1, -1, -1):
                series = series * w + _ROD_SERIES[:, k:k + 1]
            diagonal[small], off[small] = series[0], series[1]
        scale = inertia * length
    K = np.empty(z.shape + (2, 2), dtype=np.complex128)
    K[..., 0, 0] = K[..., 1, 1] = scale * diagonal
    K[..., 0, 1] = K[..., 1, 0] = scale * off
    return K


def rod_static_stiffness(length: float, stiffness: float) -> np.ndarray:
    """K0 of a rod member: ``S/L [[1, -1], [-1, 1]]``."""
    length, stiffness, _ = _check_member(length, stiffness, None, "stiffness", "inertia")
    return stiffness / length * np.array([[1.0, -1.0], [-1.0, 1.0]])


def _clamped_roots(k: np.ndarray) -> np.ndarray:
    """Roots x_k of cos x cosh x = 1 (k >= 1) by Newton on cos x = sech x from (k + 1/2) pi."""
    x = (k + 0.5) * math.pi
    for _ in range(8):
        e = np.exp(-x)
        sech = 2.0 * e / (1.0 + e * e)
        x = x - (np.cos(x) - sech) / (-np.sin(x) + sech * (1.0 - e * e) / (1.0 + e * e))
    return x


_ROOT_TABLE = {"roots": _clamped_roots(np.arange(1.0, 65.0))}


def _clamped_root_table(x_max: float) -> np.ndarray:
    """The roots of cos x cosh x = 1 up to beyond x_max (computed once, extended by doubling)."""
    roots = _ROOT_TABLE["roots"]
    while roots[-1] <= x_max:
        roots = _clamped_roots(np.arange(1.0, 2.0 * roots.size + 1.0))
        _ROOT_TABLE["roots"] = roots
    return roots


def bending_clamped_count(length: float, bending_stiffness: float, linear_density: float,
                          omega: np.ndarray) -> np.ndarray:
    """Clamped-clamped frequencies of a bending member strictly below each omega [rad/s]:
    the roots of ``cos x cosh x = 1`` below ``x = (omega**2 rho*A L**4/EJ)**(1/4)``."""
    x = np.sqrt(np.abs(omega)) * (linear_density * length**4 / bending_stiffness) ** 0.25
    table = _clamped_root_table(float(np.max(x, initial=0.0)))
    return np.searchsorted(table, x, side="left").astype(np.int64)


def rod_clamped_count(length: float, stiffness: float, inertia: float,
                      omega: np.ndarray) -> np.ndarray:
    """Clamped-clamped frequencies ``k pi/tau`` of a rod strictly below each omega."""
    ratio = np.abs(omega) * length * math.sqrt(inertia / stiffness) / math.pi
    return np.maximum(np.ceil(ratio) - 1.0, 0.0).astype(np.int64)


def bending_mass_series(length: float, bending_stiffness: float, linear_density: float,
                        n_terms: int = 3) -> np.ndarray:
    """Coefficients of ``M(s) = sum_k M_k s**(2k)`` of a bending member, shape (n_terms, 4, 4).

    ``M_0`` is the consistent (Hermite) mass matrix; the next ones are the terms of the exact
    member's expansion (``y = -s**2 rho*A L**4/EJ``), for static expansions of assemblies.
    """
    L, EJ, rho = _check_member(length, bending_stiffness, linear_density, "bending_stiffness",
                               "linear_density")
    c = -rho * L**4 / EJ                       # y = c s**2
    scale = rho * L * np.array([1.0, L, L * L, 1.0, L, L * L])
    entries = np.array([-_RATIOS[:, k + 1] * c**k for k in range(n_terms)])  # (n_terms, 6)
    return _place_bending(entries.T.astype(complex), scale).real


def rod_mass_series(length: float, stiffness: float, inertia: float,
                    n_terms: int = 3) -> np.ndarray:
    """Coefficients of ``M(s) = sum_k M_k s**(2k)`` of a rod member, shape (n_terms, 2, 2)."""
    length, stiffness, inertia = _check_member(length, stiffness, inertia, "stiffness", "inertia")
    tau2 = length**2 * inertia / stiffness     # z**2 = tau**2 s**2
    out = np.empty((n_terms, 2, 2))
    for k in range(n_terms):
        out[k, 0, 0] = out[k, 1, 1] = inertia * length * _ROD_SERIES[0, k] * tau2**k
        out[k, 0, 1] = out[k, 1, 0] = inertia * length * _ROD_SERIES[1, k] * tau2**k
    return out
