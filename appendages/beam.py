r"""The distributed-parameter appendage: a uniform free-free Euler-Bernoulli beam.

Exact transfer matrix
---------------------
Transverse motion w(x, t) of a uniform beam (bending stiffness EJ, mass per length rho*A) obeys
``EJ w'''' + rho*A w_tt = 0``. In Laplace form with zero initial conditions
``w'''' = beta**4 w`` where ``beta**4 = -s**2 rho*A/EJ``. The attachment end x = 0 carries the
force F_y and the moment M; virtual work gives the boundary conditions

    EJ w'''(0) = F_y,   EJ w''(0) = -M,   w''(L) = w'''(L) = 0.

Solving with ``w = a cosh(beta x) + b sinh(beta x) + c cos(beta x) + d sin(beta x)`` and writing
``x = beta L``, ``D(x) = 1 - cos x cosh x``:

    W1 = delta/F_y = L**3/EJ * (cos x sinh x - sin x cosh x) / (x**3 D(x))
    W2 = delta/M   = L**2/EJ *  sin x sinh x                  / (x**2 D(x))   (= W3)
    W4 = phi/M     = L/EJ    * -(cos x sinh x + sin x cosh x) / (x    D(x))

Every ratio is an even function of x and invariant under x -> i x, so it is a function of
``y = x**4 = -s**2 rho*A L**4/EJ`` alone and any fourth root may be taken. Two branches keep full
accuracy:

* |x| < 2: every numerator and denominator is a power series in y (derived from
  ``cos x cosh x = sum (-4)**k x**(4k)/(4k)!`` and its relatives), so the ratios are evaluated
  without the cancellation of the closed form near s = 0; the factor 1/y is the rigid-body 1/s**2.
* |x| >= 2: the principal root has ``Re x >= |Im x|``; with ``t = exp(-2x)``,
  ``u = exp(2i sigma x)`` (sigma = sign Im x) and ``g = 4 exp(-x + i sigma x)`` all of modulus
  at most 4, ``cos x cosh x = P (1+u)(1+t)/4`` etc. with the common factor
  ``P = exp(x - i sigma x)``, which cancels. The scaled forms never overflow.

Natural frequencies and zeros
-----------------------------
Free-free frequencies are ``w_k = x_k**2 sqrt(EJ/(rho*A L**4))`` with ``cos x cosh x = 1``; solved
as ``cos x = sech x`` (sech evaluated as 2 exp(-x)/(1 + exp(-2x))) by Newton's method from
(k + 1/2) pi, which does not lose the roots at any k (the textbook ``cos x cosh x - 1`` overflows
beyond k ~ 230 and loses all digits of the correction long before). Zeros of W_r: W1 vanishes
where ``tan x = tanh x`` (pinned-free frequencies), W2 where ``sin x = 0`` (x = k pi), W4 where
``tan x = -tanh x`` (sliding-free frequencies).

Mode shapes
-----------
Free-free ``phi = cosh bx + cos bx - sigma (sinh bx + sin bx)``, clamped-free
``psi = cosh bx - cos bx - sigma (sinh bx - sin bx)``, both with integral of the square = L, are
evaluated in the stable form of Goncalves et al. (2007): ``cosh bx - sigma sinh bx`` is rewritten
as ``[(1-sigma) e^{bx} + (1+sigma) e^{-bx}]/2`` with ``(1-sigma)`` and ``sigma`` computed from
exponentials scaled by ``e^{-bL}``. This removes the cancellation that ruins the textbook form
beyond about 12 modes (Tang 2003).

References
----------
.. [1] R. D. Blevins, "Formulas for Natural Frequency and Mode Shape", Van Nostrand, 1979,
   table 8-1 (uniform beams: frequencies, mode shapes, sigma_k).
.. [2] R. E. D. Bishop, D. C. Johnson, "The Mechanics of Vibration", Cambridge, 1960
   (receptances of free-free beams).
.. [3] Y. Tang, "Numerical evaluation of uniform beam modes", J. Eng. Mech. 129(12), 2003.
.. [4] P. J. P. Goncalves, M. J. Brennan, S. J. Elliott, "Numerical evaluation of high-order
   modes of vibration in uniform Euler-Bernoulli beams", J. Sound Vib. 301, 2007.
.. [5] Belonozhko et al. 2009 (the paper of PAPER.md): the rod and its two-mode reference.
"""

from __future__ import annotations

import math

import numpy as np
import scipy.special

from . import limits
from .interface import (as_frequency_array, check_derived, check_positive, check_range, describe,
                        inverse_2x2)

__all__ = ["Beam", "characteristic_roots"]

_SERIES_RADIUS = 2.0  # |x| below which the power series in y = x**4 are used
_N_SERIES = 18        # terms: 4**k |y|**k/(4k)! < 1e-30 at |x| = 2 for k = 18


def _series_coefficients():
    """Coefficients in y = x**4 of the four functions that make up W (see module docstring)."""
    f = math.factorial
    k = np.arange(_N_SERIES)
    # Q(y) = (1 - cos x cosh x)/y = -sum_{k>=1} (-4)^k y^(k-1)/(4k)!
    q = np.array([-((-4.0) ** (j + 1)) / f(4 * j + 4) for j in k])
    # (cos x sinh x - sin x cosh x)/x**3 = sum (-1)^(k+1) 2^(2k+2) y^k/(4k+3)!
    p1 = np.array([(-1.0) ** (j + 1) * 2.0 ** (2 * j + 2) / f(4 * j + 3) for j in k])
    # sin x sinh x / x**2 = sum (-1)^k 2^(2k+1) y^k/(4k+2)!
    p2 = np.array([(-1.0) ** j * 2.0 ** (2 * j + 1) / f(4 * j + 2) for j in k])
    # -(cos x sinh x + sin x cosh x)/x = -sum (-1)^k 2^(2k+1) y^k/(4k+1)!
    p4 = np.array([-((-1.0) ** j) * 2.0 ** (2 * j + 1) / f(4 * j + 1) for j in k])
    return q, p1, p2, p4


_Q, _P1, _P2, _P4 = _series_coefficients()


def _polyval(coefficients: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Horner evaluation of sum c_k y**k."""
    out = np.zeros_like(y)
    for c in coefficients[::-1]:
        out = out * y + c
    return out


def _scaled_terms(y: np.ndarray):
    """Scaled exponential forms at y = x**4 (|x| >= 2), all of modulus at most 4.

    With the principal root x (Re x >= |Im x|), sigma = sign Im x and the common factor
    ``P = exp(x - i sigma x)`` divided out (module docstring): returns ``x`` and

        a = 4 cos x sinh x / P,   b = 4 sin x cosh x / P,   c = 4 sin x sinh x / P,
        p = 4 cos x cosh x / P,   g = 4 / P.
    """
    x = y ** 0.25  # principal root: Re x >= |Im x|
    sigma = np.where(x.imag >= 0.0, 1.0, -1.0)
    t = np.exp(-2.0 * x)
    u = np.exp(2j * sigma * x)
    g = 4.0 * np.exp(-x + 1j * sigma * x)
    a = (1.0 + u) * (1.0 - t)
    b = 1j * sigma * (1.0 - u) * (1.0 + t)
    c = 1j * sigma * (1.0 - u) * (1.0 - t)
    return x, a, b, c, (1.0 + u) * (1.0 + t), g


def _two_branches(y: np.ndarray, series, scaled) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Three functions of y: ``series(y)`` for |x| < 2, ``scaled(*_scaled_terms(y))`` beyond."""
    out = tuple(np.empty_like(y) for _ in range(3))
    small = np.abs(y) < _SERIES_RADIUS**4
    for where, evaluate in ((small, series), (~small, lambda v: scaled(*_scaled_terms(v)))):
        if np.any(where):
            for target, value in zip(out, evaluate(y[where])):
                target[where] = value
    return out


def _dimensionless_W(y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """f1, f2, f4 with W1 = L^3/EJ f1, W2 = L^2/EJ f2, W4 = L/EJ f4, as functions of y = x**4."""
    def series(ys):
        denominator = ys * _polyval(_Q, ys)
        return (_polyval(_P1, ys) / denominator, _polyval(_P2, ys) / denominator,
                _polyval(_P4, ys) / denominator)

    def scaled(x, a, b, c, p, g):
        den = g - p  # 4 (1 - cos x cosh x)/P
        return (a - b) / (x**3 * den), c / (x**2 * den), -(a + b) / (x * den)

    return _two_branches(y, series, scaled)


def _dimensionless_D(y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """d1, d2, d4 with D = W^-1 = [[EJ/L^3 d1, EJ/L^2 d2], [EJ/L^2 d2, EJ/L d4]], of y = x**4.

    From the module docstring's W, ``det W = L**4/EJ**2 (1 + cos x cosh x)/(x**4 D(x))``
    (the numerators satisfy ``p1 p4 - p2**2 = (1 - cos x cosh x)(1 + cos x cosh x)``), so the
    adjugate gives

        d1 = -x**3 (cos x sinh x + sin x cosh x) / (1 + cos x cosh x)
        d2 = -x**2 sin x sinh x                  / (1 + cos x cosh x)
        d4 =  x    (cos x sinh x - sin x cosh x) / (1 + cos x cosh x),

    finite at the free-free frequencies (where W has its poles) and infinite at the clamped-free
    ones (``1 + cos x cosh x = 0``). Evaluated with the same two branches as W: the power series
    (``x**3 p4 = y P4(y)``, ``1 + cos x cosh x = 2 - y Q(y)``) and the scaled exponentials with
    ``4 (1 + cos x cosh x)/P = g + (1 + u)(1 + t)``. Near s = 0, D = s**2 [[m, m L/2],
    [m L/2, m L**2/3]] (the rigid beam's inertia about its root) with full relative accuracy.
    """
    def series(ys):
        denominator = 2.0 - ys * _polyval(_Q, ys)
        return (ys * _polyval(_P4, ys) / denominator, -ys * _polyval(_P2, ys) / denominator,
                ys * _polyval(_P1, ys) / denominator)

    def scaled(x, a, b, c, p, g):
        den = g + p  # 4 (1 + cos x cosh x)/P
        return -(x**3) * (a + b) / den, -(x**2) * c / den, x * (a - b) / den

    return _two_branches(y, series, scaled)


def _newton(function, derivative, x0: np.ndarray, n_iter: int = 50) -> np.ndarray:
    """Vectorised Newton iteration, stopped when every step is below 1e-15 relative."""
    x = np.array(x0, dtype=float)
    for _ in range(n_iter):
        step = function(x) / derivative(x)
        x = x - step
        if np.all(np.abs(step) <= 1e-15 * np.abs(x)):
            break
    return x


def _sech(x):
    e = np.exp(-np.abs(x))
    return 2.0 * e / (1.0 + e * e)


def characteristic_roots(kind: str, n: int) -> np.ndarray:
    """First n positive roots x_k of a uniform-beam characteristic equation (dimensionless).

    Parameters
    ----------
    kind : {"free-free", "clamped-free", "pinned-free", "sliding-free", "w2"}
        ``cos x cosh x = 1``, ``cos x cosh x = -1``, ``tan x = tanh x``, ``tan x = -tanh x``, and
        ``sin x = 0`` (zeros of W2) respectively. The trivial root x = 0 is not counted.
    n : int
        Number of roots.

    Returns
    -------
    ndarray, shape (n,)
        Frequencies follow as ``x_k**2 sqrt(EJ/(rho*A L**4))``.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n must be a positive integer (number of roots); got {describe(n)}")
    limits.check("n", int(n), "roots", "roots at once")
    k = np.arange(1, n + 1, dtype=float)
    if kind == "free-free":    # cos x = sech x
        return _newton(lambda x: np.cos(x) - _sech(x),
                       lambda x: -np.sin(x) + _sech(x) * np.tanh(x), (k + 0.5) * np.pi)
    if kind == "clamped-free":  # cos x = -sech x
        return _newton(lambda x: np.cos(x) + _sech(x),
                       lambda x: -np.sin(x) - _sech(x) * np.tanh(x), (k - 0.5) * np.pi)
    if kind == "pinned-free":  # sin x - cos x tanh x = 0
        return _newton(lambda x: np.sin(x) - np.cos(x) * np.tanh(x),
                       lambda x: np.cos(x) + np.sin(x) * np.tanh(x) - np.cos(x) * _sech(x) ** 2,
                       (k + 0.25) * np.pi)
    if kind == "sliding-free":  # sin x + cos x tanh x = 0
        return _newton(lambda x: np.sin(x) + np.cos(x) * np.tanh(x),
                       lambda x: np.cos(x) - np.sin(x) * np.tanh(x) + np.cos(x) * _sech(x) ** 2,
                       (k - 0.25) * np.pi)
    if kind == "w2":
        return k * np.pi
    raise ValueError(
        "kind must be 'free-free', 'clamped-free', 'pinned-free', 'sliding-free' or 'w2'; "
        f"got {describe(kind)}"
    )


def _shape_terms(kind: str, xk: np.ndarray):
    """sigma_k and (1 - sigma_k) e^{x_k} / 2 ... in scaled form (Goncalves et al. 2007).

    Returns (sigma, c_plus) where the mode shape on xi = x/L in [0, 1] is

        free-free:    cos(x xi) - sigma sin(x xi) + c_plus e^{x (xi-1)} + (1+sigma)/2 e^{-x xi}
        clamped-free: -cos(x xi) + sigma sin(x xi) + c_plus e^{x (xi-1)} + (1+sigma)/2 e^{-x xi}

    with ``c_plus = (1 - sigma) e^{x} / 2`` computed without overflow.
    """
    e = np.exp(-xk)
    if kind == "free-free":
        # sigma = (cosh - cos)/(sinh - sin)
        num = (1.0 + e * e) - 2.0 * np.cos(xk) * e
        den = (1.0 - e * e) - 2.0 * np.sin(xk) * e
        c_plus = (np.cos(xk) - np.sin(xk) - e) / den
    else:
        # sigma = (cosh + cos)/(sinh + sin)
        num = (1.0 + e * e) + 2.0 * np.cos(xk) * e
        den = (1.0 - e * e) + 2.0 * np.sin(xk) * e
        c_plus = (np.sin(xk) - np.cos(xk) - e) / den
    return num / den, c_plus


def _check_damping_ratio(damping_ratio) -> float:
    """The modal damping ratio as a float in [0, 1), or TypeError/ValueError naming it."""
    zeta = check_positive("damping_ratio", damping_ratio, "-", allow_zero=True)
    if zeta >= 1.0:
        raise ValueError(f"damping_ratio must be below 1 (underdamped modes) [-]; got "
                         f"{describe(damping_ratio)}")
    return zeta


def _check_section(bending_stiffness: float, linear_density: float, ej_formula: str,
                   rho_formula: str, ej_given, rho_given) -> None:
    """Check the beam properties a section constructor derived, blaming its own parameters."""
    check_derived(bending_stiffness, "bending_stiffness", ej_formula, ej_given)
    check_derived(linear_density, "linear_density", rho_formula, rho_given)


class Beam:
    """Uniform Euler-Bernoulli beam, free at both ends, loaded at its attachment end x = 0.

    Parameters
    ----------
    length : float, m
        Length L.
    bending_stiffness : float, N*m**2
        EJ (Young's modulus times the second moment of area of the section).
    linear_density : float, kg/m
        Mass per unit length rho*A.
    damping_ratio : float, optional
        Modal damping ratio, the same for every bending mode (dimensionless, 0 <= zeta < 1).
        The exact W(s) of a damped beam is the undamped closed form plus the exact damping
        correction of each mode, summed until the rest is below round-off.

    Raises
    ------
    TypeError
        A parameter that is not a real number.
    ValueError
        A parameter outside its documented range (:data:`appendages.interface.RANGES`):
        length 1e-6 to 1e6 m, bending_stiffness 1e-15 to 1e15 N*m**2, linear_density 1e-12 to
        1e6 kg/m, damping_ratio in [0, 1). Within them the frequency scale
        ``sqrt(EJ/(rho*A L**4))`` lies between 1e-23 and 1e26 rad/s and every derived scale
        (L**3/EJ, the residual tails ``rho*A L**7/EJ**2``) between 1e-90 and 1e90.

    Notes
    -----
    Rotary inertia and shear deformation are neglected (Euler-Bernoulli), so the moment of
    inertia about the centre of mass is ``m L**2/12``, as in the paper [5]_.

    References
    ----------
    See the module docstring.
    """

    def __init__(self, length: float, bending_stiffness: float, linear_density: float, *,
                 damping_ratio: float = 0.0):
        self.length = check_range("length", length, "length")
        self.bending_stiffness = check_range("bending_stiffness", bending_stiffness,
                                             "bending_stiffness")
        self.linear_density = check_range("linear_density", linear_density, "linear_density")
        self.damping_ratio = _check_damping_ratio(damping_ratio)
        self._cache: dict = {}

    # -- constructors -------------------------------------------------------------------------
    @classmethod
    def circular_rod(cls, length: float, diameter: float, density: float, youngs_modulus: float,
                     *, damping_ratio: float = 0.0) -> "Beam":
        """Solid circular rod (the paper's example: 10 m, 0.01 m, 7800 kg/m**3, 2.06e11 Pa).

        Parameters
        ----------
        length : float, m
        diameter : float, m
        density : float, kg/m**3
        youngs_modulus : float, Pa
        damping_ratio : float, optional
        """
        d = check_range("diameter", diameter, "length")
        rho = check_range("density", density, "density")
        E = check_range("youngs_modulus", youngs_modulus, "youngs_modulus")
        area = math.pi * d**2 / 4.0
        second_moment = math.pi * d**4 / 64.0
        _check_section(E * second_moment, rho * area,
                       "youngs_modulus*pi*diameter**4/64", "density*pi*diameter**2/4",
                       [("diameter", diameter, "m"), ("youngs_modulus", youngs_modulus, "Pa")],
                       [("diameter", diameter, "m"), ("density", density, "kg/m^3")])
        return cls(length, E * second_moment, rho * area, damping_ratio=damping_ratio)

    @classmethod
    def tube(cls, length: float, outer_diameter: float, wall_thickness: float, density: float,
             youngs_modulus: float, *, damping_ratio: float = 0.0) -> "Beam":
        """Thin- or thick-walled circular tube (a typical deployable boom).

        Parameters
        ----------
        length : float, m
        outer_diameter : float, m
        wall_thickness : float, m
            Must be at most half the outer diameter (a solid rod at equality).
        density : float, kg/m**3
        youngs_modulus : float, Pa
        damping_ratio : float, optional
        """
        D = check_range("outer_diameter", outer_diameter, "length")
        t = check_range("wall_thickness", wall_thickness, "length")
        if t > D / 2.0:
            raise ValueError(
                f"wall_thickness must be at most outer_diameter/2 = {D / 2.0!r} [m]; got {t!r}"
            )
        rho = check_range("density", density, "density")
        E = check_range("youngs_modulus", youngs_modulus, "youngs_modulus")
        d = D - 2.0 * t
        # D**4 - d**4 and D**2 - d**2 factored: no cancellation for a thin wall (t << D)
        area = math.pi * t * (D - t)
        second_moment = math.pi * 2.0 * t * (D - t) * (D * D + d * d) / 32.0
        _check_section(E * second_moment, rho * area,
                       "youngs_modulus*pi*(outer_diameter**4 - inner**4)/64",
                       "density*pi*(outer_diameter**2 - inner**2)/4",
                       [("outer_diameter", outer_diameter, "m"),
                        ("wall_thickness", wall_thickness, "m"),
                        ("youngs_modulus", youngs_modulus, "Pa")],
                       [("outer_diameter", outer_diameter, "m"),
                        ("wall_thickness", wall_thickness, "m"), ("density", density, "kg/m^3")])
        return cls(length, E * second_moment, rho * area, damping_ratio=damping_ratio)

    @classmethod
    def rectangular(cls, length: float, width: float, thickness: float, density: float,
                    youngs_modulus: float, *, damping_ratio: float = 0.0) -> "Beam":
        """Rectangular section bending about its thin direction (a panel strip or tape).

        Parameters
        ----------
        length, width, thickness : float, m
            ``thickness`` is the dimension in the bending plane.
        density : float, kg/m**3
        youngs_modulus : float, Pa
        """
        b = check_range("width", width, "length")
        h = check_range("thickness", thickness, "length")
        rho = check_range("density", density, "density")
        E = check_range("youngs_modulus", youngs_modulus, "youngs_modulus")
        _check_section(E * b * h**3 / 12.0, rho * b * h, "youngs_modulus*width*thickness**3/12",
                       "density*width*thickness",
                       [("width", width, "m"), ("thickness", thickness, "m"),
                        ("youngs_modulus", youngs_modulus, "Pa")],
                       [("width", width, "m"), ("thickness", thickness, "m"),
                        ("density", density, "kg/m^3")])
        return cls(length, E * b * h**3 / 12.0, rho * b * h, damping_ratio=damping_ratio)

    def __repr__(self) -> str:
        return (f"Beam(length={self.length!r}, bending_stiffness={self.bending_stiffness!r}, "
                f"linear_density={self.linear_density!r}, damping_ratio={self.damping_ratio!r})")

    def undamped(self) -> "Beam":
        """The same beam without damping (itself when already undamped)."""
        if self.damping_ratio == 0.0:
            return self
        return Beam(self.length, self.bending_stiffness, self.linear_density)

    # -- rigid properties ---------------------------------------------------------------------
    @property
    def mass(self) -> float:
        """Mass m = rho*A L [kg]."""
        return self.linear_density * self.length

    @property
    def inertia(self) -> float:
        """Moment of inertia about the centre of mass, undeformed: m L**2/12 [kg*m**2]."""
        return self.mass * self.length**2 / 12.0

    @property
    def frequency_scale(self) -> float:
        """sqrt(EJ/(rho*A L**4)) [rad/s]: a root x_k gives the frequency x_k**2 times this."""
        return math.sqrt(self.bending_stiffness / (self.linear_density * self.length**4))

    # -- frequencies --------------------------------------------------------------------------
    def _roots(self, kind: str, n: int) -> np.ndarray:
        if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)):
            raise TypeError(f"n must be an integer (number of frequencies); got "
                            f"{type(n).__name__} {describe(n)}")
        if n < 1:
            raise ValueError(f"n must be a positive integer (number of frequencies); got {describe(n)}")
        limits.check("n", int(n), "roots", "frequencies of a beam at once")
        cached = self._cache.get(kind)
        if cached is None or cached.size < n:
            cached = characteristic_roots(kind, max(n, 16))
            self._cache[kind] = cached
        return cached[:n]

    def natural_frequencies(self, n: int) -> np.ndarray:
        """First n free-free bending frequencies w_k [rad/s] (rigid-body modes excluded)."""
        return self._roots("free-free", n) ** 2 * self.frequency_scale

    def cantilever_frequencies(self, n: int) -> np.ndarray:
        """First n clamped-free frequencies [rad/s] (attachment end clamped)."""
        return self._roots("clamped-free", n) ** 2 * self.frequency_scale

    def zeros(self, r: int, n: int = 2) -> np.ndarray:
        """First n zero frequencies of the exact W_r [rad/s] (r = 1, 2, 3, 4).

        W1: pinned-free frequencies (``tan x = tanh x``); W2 = W3: ``x = k pi``;
        W4: sliding-free frequencies (``tan x = -tanh x``).
        """
        if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r not in (1, 2, 3, 4):
            raise ValueError(f"r must be 1, 2, 3 or 4 (W1, W2, W3, W4); got {describe(r)}")
        kind = {1: "pinned-free", 2: "w2", 3: "w2", 4: "sliding-free"}[r]
        return self._roots(kind, n) ** 2 * self.frequency_scale

    # -- mode shapes --------------------------------------------------------------------------
    def mode_shapes(self, x, n: int, *, boundary: str = "free-free") -> np.ndarray:
        """Mass-normalised bending mode shapes at positions x [m], shape (len(x), n) [1/sqrt(kg)].

        Normalised so that ``integral rho*A phi_j phi_k dx = delta_jk``. Accurate at any mode
        number (stable form of Goncalves et al. 2007, see the module docstring).

        Parameters
        ----------
        x : array_like, m
            Positions along the beam, 0 <= x <= L.
        n : int
            Number of modes.
        boundary : {"free-free", "clamped-free"}
            Free-free modes, or cantilever modes clamped at the attachment end.
        """
        if isinstance(x, (str, bytes)) or x is None:
            raise TypeError(f"x must be positions along the beam [m]; got {type(x).__name__}")
        x = np.atleast_1d(np.asarray(x))
        if x.dtype == bool or x.dtype.kind not in "iuf":
            raise TypeError(f"x must be real positions along the beam [m]; got dtype {x.dtype}")
        if isinstance(n, (int, np.integer)) and not isinstance(n, (bool, np.bool_)):
            limits.check("len(x) * n", x.size * max(int(n), 1), "elements",
                         "entries of the mode-shape array")
        xi = x.astype(float) / self.length
        if not np.all(np.isfinite(xi)) or np.any(xi < -1e-12) or np.any(xi > 1 + 1e-12):
            raise ValueError(f"x must lie in [0, length] = [0, {self.length!r}] [m]")
        if boundary not in ("free-free", "clamped-free"):
            raise ValueError(f"boundary must be 'free-free' or 'clamped-free'; got {describe(boundary)}")
        xk = self._roots(boundary, n)
        sigma, c_plus = _shape_terms(boundary, xk)
        arg = np.outer(xi, xk)
        trig = np.cos(arg) - sigma * np.sin(arg)
        if boundary == "clamped-free":
            trig = -trig
        shapes = trig + c_plus * np.exp(arg - xk) + 0.5 * (1.0 + sigma) * np.exp(-arg)
        return shapes / math.sqrt(self.mass)

    def _free_free_root_values(self, n: int):
        """Mass-normalised (phi_k(0), phi_k'(0)) and phi_k(L) of the first n free-free modes."""
        xk = self._roots("free-free", n)
        sigma, c_plus = _shape_terms("free-free", xk)
        root = np.column_stack([np.full(n, 2.0), -2.0 * sigma * xk / self.length])
        tip = np.cos(xk) - sigma * np.sin(xk) + c_plus + 0.5 * (1.0 + sigma) * np.exp(-xk)
        return root / math.sqrt(self.mass), tip / math.sqrt(self.mass)

    def _free_free_tail(self, n: int, power: int) -> tuple[np.ndarray, np.ndarray]:
        """Sums over the dropped free-free modes k > n, without cancellation.

        Returns ``(sum_{k>n} b_k b_k^T / w_k**power, sum_{k>n} phi_k(L) b_k / w_k**power)``,
        shapes (2, 2) and (2,), with ``b_k = (phi_k(0), phi_k'(0))`` mass-normalised. Modes
        n < k <= K = max(n, 16) are summed explicitly; beyond K the roots are ``x_k = (k + 1/2)
        pi`` and ``sigma_k = 1`` to below 1e-19 (their corrections are ~ e**-x_k), so
        ``b_k = (2, -2 x_k/L)/sqrt(m)``, ``phi_k(L) = 2 (-1)**(k+1)/sqrt(m)`` (exact by the
        mode's symmetry), ``w_k = x_k**2 c`` and the tails are Hurwitz zeta functions:
        ``sum_{k>K} x_k**-q = pi**-q zeta(q, K + 3/2)`` and
        ``sum_{k>K} (-1)**(k+1) x_k**-q = (-1)**K (2 pi)**-q [zeta(q, (K + 3/2)/2) -
        zeta(q, (K + 5/2)/2)]``. The textbook route, the static flexibility of the whole beam
        minus the kept modes', cancels like n**-3 (10 digits lost at n = 1000).

        References
        ----------
        .. [1] NIST DLMF 25.11 (Hurwitz zeta function).
        """
        K = max(n, 16)
        m, L, c = self.mass, self.length, self.frequency_scale
        b, tip = self._free_free_root_values(K)
        w = self._roots("free-free", K) ** 2 * c
        b, tip, w = b[n:], tip[n:], w[n:]
        scale = w**-power
        bb = (b.T * scale) @ b
        tb = (tip * scale) @ b
        zeta = scipy.special.zeta

        def plain(q):
            return math.pi**-q * zeta(q, K + 1.5)

        def alternating(q):
            return ((-1) ** K * (2.0 * math.pi) ** -q
                    * (zeta(q, (K + 1.5) / 2.0) - zeta(q, (K + 2.5) / 2.0)))

        f = 4.0 / (m * c**power)
        q = 2 * power
        bb += f * np.array([[plain(q), -plain(q - 1) / L], [-plain(q - 1) / L, plain(q - 2) / L**2]])
        tb += f * np.array([alternating(q), -alternating(q - 1) / L])
        return 0.5 * (bb + bb.T), tb

    def modal_participation(self, n: int) -> np.ndarray:
        """Participation factors of the first n cantilever modes, shape (n, 2).

        Row k is ``[integral rho*A psi_k dx, integral rho*A x psi_k dx]`` [sqrt(kg), sqrt(kg)*m]
        for mass-normalised cantilever modes psi_k: the coupling of mode k with a translation and
        a rotation of the clamped end. From the beam equation, ``integral psi = -psi'''(0)/b**4
        = 2 sigma_k/b_k`` and ``integral x psi = psi''(0)/b**4 = 2/b_k**2`` (unnormalised shapes
        with integral of the square L), exact at any k. Their squares summed over all modes
        give m and m L**2/3 (the effective masses), a check used in the tests.
        """
        xk = self._roots("clamped-free", n)
        sigma, _ = _shape_terms("clamped-free", xk)
        beta = xk / self.length
        scale = self.linear_density / math.sqrt(self.mass)
        return np.column_stack([2.0 * sigma / beta, 2.0 / beta**2]) * scale

    def free_cantilever_overlap(self, n_free: int, n_cantilever: int) -> np.ndarray:
        r"""Mass inner products of free-free and cantilever modes, shape (n_free, n_cantilever).

        ``O[k, i] = integral rho*A phi_k psi_i dx`` (mass-normalised shapes, dimensionless).
        From the beam equation and the boundary conditions (phi'' = phi''' = 0 at both ends,
        psi = psi' = 0 at x = 0, psi'' = psi''' = 0 at x = L),
        ``(b_k^4 - b_i^4) integral phi_k psi_i = phi_k(0) psi_i'''(0) - phi_k'(0) psi_i''(0)``,
        exact where the roots are well apart. Free-free root k and cantilever root k + 1 both
        tend to (k + 1/2) pi, where this form cancels; those pairs (k <= n_cantilever + 8) are
        integrated by Gauss-Legendre quadrature of the stable mode shapes instead.
        """
        L = self.length
        for name, value in (("n_free", n_free), ("n_cantilever", n_cantilever)):
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) \
                    or value < 1:
                raise ValueError(f"{name} must be a positive integer; got {describe(value)}")
        limits.check("n_free * n_cantilever", int(n_free) * int(n_cantilever), "elements",
                     "entries of the overlap matrix")
        xk = self._roots("free-free", n_free)
        xi = self._roots("clamped-free", n_cantilever)
        sk, _ = _shape_terms("free-free", xk)
        si, _ = _shape_terms("clamped-free", xi)
        # unnormalised shapes (integral of the square = L), in dimensionless roots x = b L:
        # phi(0) = 2, phi'(0) = -2 sigma_k x_k/L, psi''(0) = 2 x_i^2/L^2, psi'''(0) = -2 sigma_i x_i^3/L^3
        numerator = -4.0 * (si * xi**3)[None, :] + 4.0 * (sk * xk)[:, None] * (xi**2)[None, :]
        with np.errstate(divide="ignore", invalid="ignore"):  # rows below are replaced
            overlap = numerator / (xk[:, None] ** 4 - xi[None, :] ** 4)
        n_quad = min(n_free, n_cantilever + 8)
        # Gauss-Legendre nodes: scipy's asymptotic algorithm (numpy's leggauss solves a dense
        # eigenproblem, seconds at this size); ~6 nodes per unit of the highest root x resolve
        # the products of shapes to round-off
        n_nodes = int(200 + 6 * (n_quad + 1) * math.pi)
        nodes, weights = scipy.special.roots_legendre(n_nodes)
        x = 0.5 * (nodes + 1.0) * L
        phi = self.mode_shapes(x, n_quad)
        psi = self.mode_shapes(x, n_cantilever, boundary="clamped-free")
        overlap[:n_quad] = (phi * (0.5 * L * weights * self.linear_density)[:, None]).T @ psi
        return overlap

    def _cantilever_tip_values(self, n: int) -> np.ndarray:
        xk = self._roots("clamped-free", n)
        sigma, c_plus = _shape_terms("clamped-free", xk)
        tip = -(np.cos(xk) - sigma * np.sin(xk)) + c_plus + 0.5 * (1.0 + sigma) * np.exp(-xk)
        return tip / math.sqrt(self.mass)

    # -- exact W(s) ---------------------------------------------------------------------------
    def W(self, s) -> np.ndarray:
        """Exact transfer matrix W(s) of the free distributed beam (see the module docstring).

        Parameters
        ----------
        s : complex or array_like of complex, rad/s
            Laplace variable of magnitude 1e-80 to 1e80 rad/s
            (:data:`appendages.interface.S_RANGE`; tests/test_extremes.py sweeps it, against
            60-digit closed forms from 1e-8 to 1e8 in tests/test_stress.py). s = 0 is the
            rigid-body pole and is rejected.

        Returns
        -------
        ndarray of complex128, shape ``np.shape(s) + (2, 2)``
            ``[[W1, W2], [W2, W4]]`` in m/N, 1/N and 1/(N*m).
        """
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError("s = 0 is the rigid-body pole of W (W is infinite there) [rad/s]")
        W = np.zeros(s.shape + (2, 2), dtype=np.complex128)
        W[..., 0, 0], W[..., 0, 1], W[..., 1, 1] = self._undamped_entries(s)
        W[..., 1, 0] = W[..., 0, 1]
        if self.damping_ratio > 0.0:
            with np.errstate(divide="ignore", invalid="ignore"):  # undamped poles, repaired below
                corrections = self._damping_correction(s)
            for (i, j), d in zip(((0, 0), (0, 1), (1, 1)), corrections):
                W[..., i, j] += d
            self._repair_near_poles(s, W)
        elif not np.all(np.isfinite(W)):
            raise ValueError("s is a natural frequency of the undamped beam: W is infinite there "
                             "[rad/s]")
        W[..., 1, 0] = W[..., 0, 1]
        return W

    def dynamic_stiffness(self, s) -> np.ndarray:
        """Attachment-end dynamic stiffness D(s) = W(s)^-1 [N/m, N; N, N*m], exact.

        The loads at x = 0 that move the attachment end by (delta, phi) = (1, 0) or (0, 1) at
        the Laplace variable s. Undamped: the closed form of :func:`_dimensionless_D`, which
        stays accurate where W is singular or huge (at the clamped-free frequencies D has its
        poles, at the free-free ones W has them); the hub coupling uses it instead of
        inverting W. Damped: the 2x2 inverse of the exact damped W by its adjugate.

        Parameters
        ----------
        s : complex or array_like of complex, rad/s
            Laplace variable; s = 0 gives D = 0 (a free beam offers no static stiffness).

        Returns
        -------
        ndarray of complex128, shape ``np.shape(s) + (2, 2)``
            Infinite entries exactly at a clamped-free frequency (undamped).
        """
        s = as_frequency_array(s)
        D = np.zeros(s.shape + (2, 2), dtype=np.complex128)
        if self.damping_ratio > 0.0:
            nonzero = s != 0
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                D[nonzero] = inverse_2x2(self.W(s[nonzero]))
        else:
            EJ, L = self.bending_stiffness, self.length
            y = -(s**2) * (self.linear_density * L**4 / EJ)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                d1, d2, d4 = _dimensionless_D(y.ravel())
            D[..., 0, 0] = d1.reshape(s.shape) * (EJ / L**3)
            D[..., 0, 1] = d2.reshape(s.shape) * (EJ / L**2)
            D[..., 1, 1] = d4.reshape(s.shape) * (EJ / L)
        D[..., 1, 0] = D[..., 0, 1]
        return D

    def _undamped_entries(self, s: np.ndarray):
        """W1, W2, W4 of the undamped closed form (module docstring), each of shape s.shape."""
        EJ, L = self.bending_stiffness, self.length
        y = -(s**2) * (self.linear_density * L**4 / EJ)
        with np.errstate(divide="ignore", invalid="ignore"):
            f1, f2, f4 = _dimensionless_W(y.ravel())
        return (f1.reshape(s.shape) * (L**3 / EJ), f2.reshape(s.shape) * (L**2 / EJ),
                f4.reshape(s.shape) * (L / EJ))

    def _repair_near_poles(self, s: np.ndarray, W: np.ndarray, n_points: int = 32) -> None:
        """Re-evaluate damped W near an undamped pole +-i w_k without cancellation.

        There the undamped closed form is huge and the damping correction cancels it. Instead,
        ``g(s) = W_undamped(s) - b_k b_k^T/(s^2 + w_k^2)`` is analytic in a disc around i w_k and
        equals its mean over a circle of radius r (mean-value property; the trapezoidal rule
        with 32 points converges like (|s - i w_k|/r)^32 there). Then
        ``W = g(s) + b_k b_k^T/(s^2 + 2 zeta w_k s + w_k^2) + sum_{j != k} corrections``.
        """
        flat = s.ravel()
        W_flat = W.reshape(-1, 2, 2)
        x_est = np.sqrt(np.abs(flat) / self.frequency_scale)
        n = int(min(x_est.max() / math.pi + 3, 20000))
        w = self.natural_frequencies(n)
        gaps = np.diff(np.concatenate([[0.0], w, [w[-1] + (w[-1] - w[-2] if n > 1 else w[-1])]]))
        radius = 0.25 * np.minimum(gaps[:-1], gaps[1:])
        root, _ = self._free_free_root_values(n)
        zeta = self.damping_ratio
        theta = 2 * np.pi * (np.arange(n_points) + 0.5) / n_points
        for index, si in enumerate(flat):
            k = int(np.argmin(np.abs(np.abs(si) - w)))
            pole = 1j * w[k] if si.imag >= 0 else -1j * w[k]
            if abs(si - pole) > 0.1 * radius[k]:
                continue
            z = si + radius[k] * np.exp(1j * theta)
            u1, u2, u4 = self._undamped_entries(z)
            bb = np.outer(root[k], root[k])
            pole_term = 1.0 / (z**2 + w[k] ** 2)
            g = np.array([[np.mean(u1 - bb[0, 0] * pole_term), np.mean(u2 - bb[0, 1] * pole_term)],
                          [0.0, np.mean(u4 - bb[1, 1] * pole_term)]])
            damped = 1.0 / (si**2 + 2 * zeta * w[k] * si + w[k] ** 2)
            others = [d[0] for d in self._damping_correction(np.array([si]), exclude=k)]
            W_flat[index, 0, 0] = g[0, 0] + bb[0, 0] * damped + others[0]
            W_flat[index, 0, 1] = g[0, 1] + bb[0, 1] * damped + others[1]
            W_flat[index, 1, 1] = g[1, 1] + bb[1, 1] * damped + others[2]

    def _damping_correction(self, s: np.ndarray, exclude: int | None = None):
        """Sum over all modes of b_k b_k^T [1/(s^2 + 2 zeta w_k s + w_k^2) - 1/(s^2 + w_k^2)].

        The undamped closed form holds every mode without damping; this adds each mode's
        damping exactly. Modes are summed explicitly up to N, where w_N >= 1e3 |s| (at most
        20000 modes); beyond, the term is ``-2 zeta s b_k b_k^T/w_k^3 (1 + O(|s|/w_k))`` with
        the asymptotic ``b_k = (2, -2 x_k/L)/sqrt(m)``, ``x_k = (k + 1/2) pi``, and the sum of
        ``x_k^-p`` over k > N is replaced by its midpoint integral
        ``((N + 1) pi)^(1-p)/(pi (p - 1))`` (p = 6, 5, 4 for the three entries).
        Returns the three distinct entries, each of shape ``s.shape``. Mode ``exclude`` (an
        index from 0) is left out of the sum.
        """
        zeta, m, L, c0 = self.damping_ratio, self.mass, self.length, self.frequency_scale
        s_max = float(np.abs(s).max())
        x_needed = math.sqrt(1e3 * s_max / c0)
        n = int(min(max(64, x_needed / math.pi + 1, (exclude or 0) + 64), 20000))
        root, _ = self._free_free_root_values(n)
        w = self.natural_frequencies(n)
        flat = s.ravel()
        d = np.empty((3, flat.size), dtype=np.complex128)
        products = np.stack([root[:, 0] ** 2, root[:, 0] * root[:, 1], root[:, 1] ** 2], axis=1)
        if exclude is not None:
            products[exclude] = 0.0
            w = w.copy()
            w[exclude] = 1.0  # any finite value: its products are zero
        chunk = max(1, 2_000_000 // n)
        for start in range(0, flat.size, chunk):
            ss = flat[start:start + chunk, None]
            term = 1.0 / (ss**2 + 2.0 * zeta * w * ss + w**2) - 1.0 / (ss**2 + w**2)
            d[:, start:start + chunk] = (term @ products).T
        tail = [((n + 1) * math.pi) ** (1 - p) / (math.pi * (p - 1)) for p in (6, 5, 4)]
        coefficient = -2.0 * zeta * flat * 4.0 / (m * c0**3)
        d[0] += coefficient * tail[0]
        d[1] += coefficient * (-1.0 / L) * tail[1]
        d[2] += coefficient * tail[2] / L**2
        return tuple(row.reshape(s.shape) for row in d)

    # -- finite models ------------------------------------------------------------------------
    def truncated(self, n_modes: int, *, method: str = "craig-bampton"):
        """A finite modal model of this beam with ``n_modes`` bending modes.

        Parameters
        ----------
        n_modes : int
            Number of elastic modes kept (>= 1).
        method : {"craig-bampton", "residual", "free-free"}
            ``"free-free"``: the paper's truncation, rigid-body modes plus the first free-free
            bending modes. ``"residual"``: the same plus two residual attachment modes (the
            dropped modes' static flexibility at the attachment end with its inertia, a
            Rayleigh-Ritz model): exact first n poles, better zeros, no spurious coupled mode.
            ``"craig-bampton"`` (default, the most accurate): attachment-end
            motion (two constraint modes, exact rigid-body inertia) plus the first cantilever
            modes, i.e. the hybrid coordinates of flexible-spacecraft dynamics; the zeros of W
            and coupled frequencies converge much faster (see benchmarks/truncation_table.py).

        Returns
        -------
        ModalBeam
        """
        from .modal import ModalBeam

        return ModalBeam(self, n_modes, method=method)
