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

Damping and tip bodies
----------------------
The modal damping ratio is that of every cantilever (fixed-root) mode by default
(:mod:`appendages.damping`: the damped root dynamic stiffness is the undamped closed form plus
each cantilever mode's damping, the tail in Hurwitz zeta sums; W its inverse);
``damping_convention="free-free"`` keeps the former meaning, every free-free mode damped (the
correction and repair below). A beam carrying a rigid body at its free end (``tip=``) has no
closed form: it is the exact assembled model of :mod:`appendages.segmented`.

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

import functools
import math

import numpy as np
import scipy.special

from . import limits
from .assembly import Segment
from .damping import (CantileverDamping, check_damping_convention, check_damping_ratio,
                      chebyshev_resonance_coefficients, hurwitz_tail_coefficients,
                      CantileverModalSums)
from .checks import as_frequency_array, check_derived, check_range
from .errors import describe
from .interface import inverse_2x2, place_bending_planes
from .modal import ModalBeam
from .rod import Rod
from .segmented import SegmentedBeam
from .tip import TipBody, check_tip
from .unit_slips import damping_in_percent, modulus_in_megapascals, warn_unit_slip

__all__ = ["Beam", "characteristic_roots", "rectangle_torsion_constant"]

_SERIES_RADIUS = 2.0  # |x| below which the power series in y = x**4 are used
_MAX_CORRECTION_MODES = 20000  # free-free modes summed explicitly in a damping correction
_TAIL_TERMS = 12      # terms of the series in s/w_k of the damping correction's tail
#: Most cantilever modes of the modal sum of the damped root dynamic stiffness (beyond, the
#: closed form with damping corrections of :mod:`appendages.damping`).
_MODAL_MAX_MODES = 1024
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


_SERIES = np.stack([_Q, _P1, _P2, _P4])[:, ::-1, None].copy()  # (4, terms, 1), highest first
# Largest |y| for which the first K terms suffice: every dropped term, bounded by
# 4**(k+1) |y|**k/(4k+1)!, below 1e-20 (the sums are O(1) for |y| <= 16, so far below the
# rounding of the kept ones); K = 18 covers the series' whole range |y| < 16.
_TERMS_RADIUS = np.array([(1e-20 * math.factorial(4 * K + 1) / 4.0 ** (K + 1)) ** (1.0 / K)
                          for K in range(1, _N_SERIES + 1)])


def _polyvals(y: np.ndarray):
    """Q, P1, P2, P4 at y by one Horner scheme on the stacked coefficients (a quarter of the
    array operations of four separate ones), with only the terms that the largest |y| of the
    call needs (:data:`_TERMS_RADIUS`): 9 at |y| = 16, 4 at |y| = 1e-3 (the exact count of a
    three-axis spacecraft evaluates them often)."""
    top = float(np.max(np.abs(y), initial=0.0))
    n_terms = int(np.searchsorted(_TERMS_RADIUS, top)) + 1 if top > 0 else 1
    out = np.zeros((4,) + y.shape, dtype=y.dtype)
    for c in _SERIES[:, _N_SERIES - min(n_terms, _N_SERIES):].transpose(1, 0, 2):
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
        q, p1, p2, p4 = _polyvals(ys)
        denominator = ys * q
        return p1 / denominator, p2 / denominator, p4 / denominator

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
        q, p1, p2, p4 = _polyvals(ys)
        denominator = 2.0 - ys * q
        return ys * p4 / denominator, -ys * p2 / denominator, ys * p1 / denominator

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
    if not isinstance(kind, str):
        raise TypeError(f"kind must be a string, e.g. 'free-free'; got {type(kind).__name__} "
                        f"{describe(kind)}")
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


@functools.lru_cache(maxsize=64)
def _shared_roots(kind: str, n: int) -> np.ndarray:
    """:func:`characteristic_roots` (dimensionless: the same for every beam), computed once
    per process for each (kind, n) and shared read-only; a beam asks for the same n as it
    would compute, so its roots are those :func:`characteristic_roots` gives, to the bit."""
    roots = characteristic_roots(kind, n)
    roots.flags.writeable = False
    return roots


@functools.lru_cache(maxsize=64)
def _clamped_free_sigma(n: int) -> np.ndarray:
    """sigma_k of the first n clamped-free roots (:func:`_shape_terms`; dimensionless, the
    same for every beam), computed once per process for each n and shared read-only."""
    sigma, _ = _shape_terms("clamped-free", _shared_roots("clamped-free", max(n, 16))[:n])
    sigma.flags.writeable = False
    return sigma


@functools.lru_cache(maxsize=64)
def _participation_tail_sums(n: int) -> tuple[float, float, float]:
    """The dimensionless sums of :meth:`Beam.cantilever_participation_tail` over the
    clamped-free roots x_k, k > n: ``sum sigma**2/x**2``, ``sum sigma/x**3``, ``sum 1/x**4``
    (the roots up to max(n, 16) one by one, the rest ``pi**-q zeta(q, K + 1/2)``, Hurwitz),
    the same for every beam: computed once per process for each n."""
    K = max(n, 16)
    x = _shared_roots("clamped-free", K)[n:]
    sigma, _ = _shape_terms("clamped-free", x)
    zeta = scipy.special.zeta
    plain = [math.pi**-q * float(zeta(q, K + 0.5)) for q in (2, 3, 4)]
    return (math.fsum(sigma**2 / x**2) + plain[0], math.fsum(sigma / x**3) + plain[1],
            math.fsum(1.0 / x**4) + plain[2])


@functools.lru_cache(maxsize=64)
def _modal_sum_constants(n: int, zeta: float) -> tuple[np.ndarray, np.ndarray]:
    """The beam-independent factors of the tail of :meth:`Beam._cantilever_modal_stiffness`
    beyond n modes: the Chebyshev coefficients ``U_m(-zeta)``, m < _TAIL_TERMS, and
    ``pi**-q zeta(q, n + 1/2)`` (Hurwitz) for q = 6 + 2m, 7 + 2m, 8 + 2m, shape
    (3, _TAIL_TERMS); computed once per process for each (n, zeta), shared read-only."""
    cheb = chebyshev_resonance_coefficients(zeta, _TAIL_TERMS)
    m = np.arange(_TAIL_TERMS)
    orders = 2 * m[None, :] + np.array([[6], [7], [8]])
    Z = math.pi ** (-orders.astype(float)) * scipy.special.zeta(orders, n + 0.5)
    cheb.flags.writeable = False
    Z.flags.writeable = False
    return cheb, Z


def _joint_modal_sums(motions: list, rods: list, zeta: float) -> tuple:
    """For :meth:`Beam._modal_stiffness6`: the :class:`~appendages.damping.CantileverModalSums`
    of a beam's motions, the entries of the flattened 6 x 6 D6 they fill and the column of the
    sums that fills each.

    ``motions`` are the terms of the x-y plane (columns D11, D12, D22), of the x-z plane if it
    differs, then of the elastic rods, whose motions (``"axial"``, ``"torsion"``) ``rods``
    names. The x-z plane's coupling enters D6 negated
    (:func:`~appendages.interface.place_bending_planes`), so its terms are negated (exactly);
    with equal planes the x-y plane's terms get that negated column as a fourth.
    """
    def picked(motion, picks):
        w, weights, rest, coefficients, scale = motion
        index = [column for column, _ in picks]
        sign = np.array([factor for _, factor in picks])
        return w, weights[:, index] * sign, rest[index] * sign, coefficients[:, index] * sign, \
            scale

    n_planes = len(motions) - len(rods)
    xy = [[(1, 1)], [(1, 5), (5, 1)], [(5, 5)]]
    xz = [[(2, 2)], [(2, 4), (4, 2)], [(4, 4)]]
    if n_planes == 1:
        terms = [picked(motions[0], [(0, 1.0), (1, 1.0), (2, 1.0), (1, -1.0)])]
        places = [xy[0] + xz[0], xy[1], xy[2] + xz[2], xz[1]]
    else:
        terms = [motions[0], picked(motions[1], [(0, 1.0), (1, -1.0), (2, 1.0)])]
        places = xy + xz
    terms += motions[n_planes:]
    places += [[(0, 0)] if motion == "axial" else [(3, 3)] for motion in rods]
    entries = [6 * row + col for targets in places for row, col in targets]
    columns = [column for column, targets in enumerate(places) for _ in targets]
    return CantileverModalSums(terms, zeta), np.array(entries), np.array(columns)


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


def _shape_coefficients(x: np.ndarray, kind: str):
    """(A, B, C, D) of ``A cos(x xi) + B sin(x xi) + C e^{x (xi-1)} + D e^{-x xi}`` (xi = x/L),
    the unnormalised shapes of :func:`_shape_terms` (mean square over [0, 1] equal to 1)."""
    sigma, c_plus = _shape_terms(kind, x)
    sign = 1.0 if kind == "free-free" else -1.0
    return sign, -sign * sigma, c_plus, 0.5 * (1.0 + sigma)


def _sin_over(c):
    """sin(c)/c, 1 at c = 0."""
    return np.sinc(c / math.pi)


def _one_minus_cos_over(c):
    """(1 - cos c)/c = 2 sin(c/2)**2/c, 0 at c = 0, without cancellation."""
    with np.errstate(invalid="ignore", divide="ignore"):
        out = 2.0 * np.sin(0.5 * c) ** 2 / c
    return np.where(c == 0.0, 0.0, out)


def _expm1_over(c):
    """expm1(c)/c, 1 at c = 0."""
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        out = np.expm1(c) / c
    return np.where(c == 0.0, 1.0, out)


def _shape_products(x1: np.ndarray, kind1: str, x2: np.ndarray, kind2: str) -> np.ndarray:
    """``integral_0^1 f(xi) g(xi) dxi`` of two unnormalised stable shapes, elementwise.

    f has roots x1 (kind1), g roots x2 (kind2); both are sums of cos, sin and the two
    decaying exponentials (:func:`_shape_coefficients`). With a = x1, b = x2 and
    ``S(c) = sin c/c``, ``C(c) = (1 - cos c)/c``, ``E(c) = expm1(c)/c``::

        int cos a cos b = [S(a-b) + S(a+b)]/2      int sin a sin b = [S(a-b) - S(a+b)]/2
        int sin a cos b = [C(a+b) + C(a-b)]/2      int cos a sin b = [C(a+b) - C(a-b)]/2
        int e^{a(xi-1)} e^{b(xi-1)} = int e^{-a xi} e^{-b xi} = (1 - e^{-(a+b)})/(a+b)
        int e^{a(xi-1)} e^{-b xi} = e^{-a} E(a - b)
        int e^{i a xi} e^{b(xi-1)} = (e^{i a} - e^{-b})/(b + i a)
        int e^{i a xi} e^{-b xi}   = (1 - e^{-b} e^{i a})/(b - i a)

    (cos and sin from the real and imaginary parts of the last two). Every term is O(1) or
    smaller and none is a difference of nearly equal numbers; the result is good to a few
    ulps of 1. For |a - b| large the first forms still hold (``e^{-a} E(a - b)`` then
    overflows beyond a - b ~ 700: use it for near roots). Divided by sqrt(m) each, the
    shapes are mass-normalised and this is ``integral rho*A f g dx``.
    """
    A1, B1, C1, D1 = _shape_coefficients(x1, kind1)
    A2, B2, C2, D2 = _shape_coefficients(x2, kind2)
    a, b = x1, x2
    total = (A1 * A2 * 0.5 * (_sin_over(a - b) + _sin_over(a + b))
             + B1 * B2 * 0.5 * (_sin_over(a - b) - _sin_over(a + b))
             + B1 * A2 * 0.5 * (_one_minus_cos_over(a + b) + _one_minus_cos_over(a - b))
             + A1 * B2 * 0.5 * (_one_minus_cos_over(a + b) - _one_minus_cos_over(a - b)))
    same = -np.expm1(-(a + b)) / (a + b)
    total = total + (C1 * C2 + D1 * D2) * same
    total = (total + C1 * D2 * np.exp(-a) * _expm1_over(a - b)
             + D1 * C2 * np.exp(-b) * _expm1_over(b - a))

    def trig_exp(root, cos_coefficient, sin_coefficient, exp_root, rising_coefficient,
                 falling_coefficient):
        e_i = np.exp(1j * root)
        rising = (e_i - np.exp(-exp_root)) / (exp_root + 1j * root)            # e^{r(xi-1)}
        falling = (1.0 - np.exp(-exp_root) * e_i) / (exp_root - 1j * root)     # e^{-r xi}
        mixed = rising_coefficient * rising + falling_coefficient * falling
        return cos_coefficient * mixed.real + sin_coefficient * mixed.imag

    return total + trig_exp(a, A1, B1, b, C2, D2) + trig_exp(b, A2, B2, a, C1, D1)


def _check_section(bending_stiffness: float, linear_density: float, ej_formula: str,
                   rho_formula: str, ej_given, rho_given) -> None:
    """Check the beam properties a section constructor derived, blaming its own parameters."""
    check_derived(bending_stiffness, "bending_stiffness", ej_formula, ej_given)
    check_derived(linear_density, "linear_density", rho_formula, rho_given)


def _check_poisson_ratio(poisson_ratio) -> float:
    """Poisson's ratio of an isotropic material, in (-1, 1/2) [-]."""
    if isinstance(poisson_ratio, (bool, np.bool_)) or not isinstance(
            poisson_ratio, (int, float, np.integer, np.floating)):
        raise TypeError(f"poisson_ratio must be a real number [-]; got "
                        f"{type(poisson_ratio).__name__} {describe(poisson_ratio)}")
    nu = float(poisson_ratio)
    if not (-1.0 < nu < 0.5):
        raise ValueError(f"poisson_ratio must lie in (-1, 0.5) for an isotropic material [-]; "
                         f"got {describe(poisson_ratio)}")
    return nu


def _warn_material(youngs_modulus: float, density: float, damping_ratio) -> None:
    """Warn at a section constructor's caller about a modulus that looks like MPa or GPa and a
    damping ratio that looks like per cent (:mod:`appendages.unit_slips`), once the values
    are checked."""
    zeta = check_damping_ratio(damping_ratio)
    warn_unit_slip("youngs_modulus", youngs_modulus, "Pa",
                   modulus_in_megapascals(youngs_modulus, density), stacklevel=4)
    warn_unit_slip("damping_ratio", zeta, "", damping_in_percent(zeta), stacklevel=4)


def rectangle_torsion_constant(side_a: float, side_b: float) -> float:
    """Saint-Venant torsion constant J_t [m**4] of a solid a x b rectangle.

    With ``a >= b`` the long and short sides (Timoshenko & Goodier, sec. 109)::

        J_t = a b**3 [1/3 - (64/pi**5) (b/a) sum_{n odd} tanh(n pi a/(2 b))/n**5],

    the sum written as ``(31/32) zeta(5) - sum_{n odd} (1 - tanh(n pi a/(2 b)))/n**5``, whose
    terms decay like ``exp(-n pi)`` (20 terms reach round-off). A square gives
    ``0.1406 a**4``, a thin strip ``a b**3/3``.

    References
    ----------
    .. [1] S. P. Timoshenko, J. N. Goodier, "Theory of Elasticity", 3rd ed., McGraw-Hill, 1970,
       sec. 109 (torsion of a rectangular bar).
    """
    a, b = max(side_a, side_b), min(side_a, side_b)
    n = np.arange(1, 41, 2, dtype=float)
    x = n * math.pi * a / (2.0 * b)
    e = np.exp(-2.0 * x)
    deficit = float(np.sum(2.0 * e / (1.0 + e) / n**5))  # 1 - tanh x = 2 e^-2x/(1 + e^-2x)
    total = (31.0 / 32.0) * float(scipy.special.zeta(5.0)) - deficit
    return a * b**3 * (1.0 / 3.0 - 64.0 / math.pi**5 * (b / a) * total)


#: The beam's three-axis parameters: (name, key of RANGES, unit).
_THREE_AXIS_PARAMETERS = (("bending_stiffness_y", "bending_stiffness", "N*m^2"),
                          ("torsional_stiffness", "torsional_stiffness", "N*m^2"),
                          ("torsional_inertia", "torsional_inertia", "kg*m"),
                          ("axial_stiffness", "axial_stiffness", "N"))


class Beam:
    """Uniform Euler-Bernoulli beam, free at both ends, loaded at its attachment end x = 0.

    Parameters
    ----------
    length : float, m
        Length L.
    bending_stiffness : float, N*m**2
        EJ for bending in the local x-y plane (deflection v along y, ``theta_z = dv/dx``):
        the planar beam.
    linear_density : float, kg/m
        Mass per unit length rho*A.
    bending_stiffness_y : float, N*m**2, optional
        EJ for bending in the local x-z plane (deflection w along z, ``theta_y = -dw/dx``);
        default equal to ``bending_stiffness``.
    torsional_stiffness : float, N*m**2, optional
        Saint-Venant torsional stiffness GJ. None with ``torsional_inertia`` given: torsionally
        rigid (the limit GJ -> inf).
    torsional_inertia : float, kg*m, optional
        Polar mass moment of inertia per unit length rho*I_p. Needed for three-axis use
        (:meth:`W6`, a three-axis spacecraft): without it a root torque would meet no inertia.
    axial_stiffness : float, N, optional
        EA. None: inextensible (the limit EA -> inf), the assumption the planar model makes.
    damping_ratio : float, optional
        Modal damping ratio, the same for every elastic mode (dimensionless, 0 <= zeta < 1):
        by default of every cantilever (fixed-root) mode, as finite-element data carries it,
        bending in both planes, torsion and axial motion; a hub much heavier than the beam
        then sees its first modes damped at zeta. The exact W(s) of a damped beam is the
        inverse of its exact damped root dynamic stiffness: the undamped closed form plus the
        damping of each cantilever mode, the tail summed in closed form
        (:mod:`appendages.damping`).
    damping_convention : {"cantilever", "free-free"}, optional
        What damping_ratio damps: "cantilever" (default) the cantilever modes; "free-free"
        every free-free mode (flexsat's meaning before, kept by name; the bare uniform beam
        only): then W(s) is the undamped closed form plus each free-free mode's damping, and
        a rod's W the digamma form of :mod:`appendages.rod`.
    tip : TipBody, optional
        A rigid body fixed to the free end (:class:`appendages.TipBody`): W(s), W6(s), the
        mass properties, the frequencies and the truncations include it exactly, through the
        assembled model of :mod:`appendages.segmented` (a body of zero mass and inertia gives
        the bare beam bit for bit).

    Raises
    ------
    TypeError
        A parameter that is not a real number, a tip that is not a TipBody.
    ValueError
        A parameter outside its documented range (:data:`appendages.interface.RANGES`):
        length 1e-6 to 1e6 m, bending_stiffness(_y) 1e-15 to 1e15 N*m**2, linear_density 1e-12 to
        1e6 kg/m, torsional_stiffness 1e-15 to 1e15 N*m**2, torsional_inertia 1e-30 to 1e12 kg*m,
        axial_stiffness 1e-9 to 1e20 N, damping_ratio in [0, 1); or a torsional_stiffness
        without a torsional_inertia. Within them the frequency scale
        ``sqrt(EJ/(rho*A L**4))`` lies between 1e-23 and 1e26 rad/s and every derived scale
        (L**3/EJ, the residual tails ``rho*A L**7/EJ**2``) between 1e-90 and 1e90.

    Notes
    -----
    Rotary inertia and shear deformation are neglected in bending (Euler-Bernoulli), so the
    moment of inertia about the centre of mass is ``m L**2/12`` about local y and z, as in the
    paper [5]_; about the axis it is ``rho*I_p L``. The section is symmetric (shear centre on
    the axis, principal axes along local y and z), so the four motions decouple and W6 is
    made of the planar W of each bending plane and the exact W of two rods
    (:meth:`W6`). A planar beam (no torsional_inertia) works in every planar model and is
    refused by name in three-axis ones.

    References
    ----------
    See the module docstring; :mod:`appendages.rod` for torsion and axial motion.
    """

    def __init__(self, length: float, bending_stiffness: float, linear_density: float, *,
                 bending_stiffness_y: float | None = None,
                 torsional_stiffness: float | None = None,
                 torsional_inertia: float | None = None,
                 axial_stiffness: float | None = None, damping_ratio: float = 0.0,
                 damping_convention: str = "cantilever", tip: TipBody | None = None):
        self._initialise(length, bending_stiffness, linear_density,
                         bending_stiffness_y=bending_stiffness_y,
                         torsional_stiffness=torsional_stiffness,
                         torsional_inertia=torsional_inertia, axial_stiffness=axial_stiffness,
                         damping_ratio=damping_ratio, damping_convention=damping_convention,
                         tip=tip)
        warn_unit_slip("damping_ratio", self.damping_ratio, "",
                       damping_in_percent(self.damping_ratio))

    @classmethod
    def _quiet(cls, *args, **kwargs) -> "Beam":
        """A beam built from values already warned about (a view, a section constructor's
        beam): ``Beam(*args, **kwargs)`` without the unit-slip warnings."""
        beam = cls.__new__(cls)
        beam._initialise(*args, **kwargs)
        return beam

    def _initialise(self, length, bending_stiffness, linear_density, *,
                    bending_stiffness_y=None, torsional_stiffness=None, torsional_inertia=None,
                    axial_stiffness=None, damping_ratio=0.0, damping_convention="cantilever",
                    tip=None) -> None:
        """The constructor's checks and attributes (:class:`Beam`)."""
        self.length = check_range("length", length, "length")
        self.bending_stiffness = check_range("bending_stiffness", bending_stiffness,
                                             "bending_stiffness")
        self.linear_density = check_range("linear_density", linear_density, "linear_density")
        self.damping_ratio = check_damping_ratio(damping_ratio)
        self.damping_convention = check_damping_convention(damping_convention)
        given = {"bending_stiffness_y": bending_stiffness_y,
                 "torsional_stiffness": torsional_stiffness,
                 "torsional_inertia": torsional_inertia, "axial_stiffness": axial_stiffness}
        for name, quantity, _ in _THREE_AXIS_PARAMETERS:
            value = given[name]
            given[name] = None if value is None else check_range(name, value, quantity)
        if given["torsional_stiffness"] is not None and given["torsional_inertia"] is None:
            raise ValueError(
                "torsional_inertia [kg*m] (rho*I_p per unit length) must be given with "
                f"torsional_stiffness = {describe(torsional_stiffness)} N*m^2; got None")
        self._bending_stiffness_y = given["bending_stiffness_y"]
        self.torsional_stiffness = given["torsional_stiffness"]
        self.torsional_inertia = given["torsional_inertia"]
        self.axial_stiffness = given["axial_stiffness"]
        self.tip = check_tip(tip)
        if self.damping_convention == "free-free" and self.tip is not None \
                and not self.tip.is_null:
            raise ValueError("damping_convention='free-free' is the bare uniform beam's only; a "
                             "beam with a tip body is damped in its cantilever modes "
                             "(damping_convention='cantilever'); got 'free-free' with "
                             f"tip={self.tip!r}")
        self._cache: dict = {}
        # with a tip body: the exact assembled model (appendages.segmented); a body of zero
        # mass and inertia leaves the bare beam, bit for bit
        self._segmented = None if self.tip is None or self.tip.is_null else SegmentedBeam(
            [Segment(self.length, self.bending_stiffness, self.linear_density,
                     self.bending_stiffness_y if self.three_axis else None,
                     self.torsional_stiffness, self.torsional_inertia, self.axial_stiffness)],
            self.tip, self.damping_ratio)

    @property
    def bending_stiffness_y(self) -> float:
        """EJ for bending in the local x-z plane [N*m**2] (default: ``bending_stiffness``)."""
        if self._bending_stiffness_y is None:
            return self.bending_stiffness
        return self._bending_stiffness_y

    @property
    def three_axis(self) -> bool:
        """True when the beam has the properties of a three-axis model (a torsional inertia)."""
        return self.torsional_inertia is not None

    @property
    def is_uniform(self) -> bool:
        """True for the bare uniform beam (no tip body), whose closed forms apply."""
        return self._segmented is None

    def require_three_axis(self, what: str) -> None:
        """ValueError unless the beam has the three-axis properties (a torsional inertia).

        Parameters
        ----------
        what : str
            What needs them, the message's subject (e.g. ``"W6"``).
        """
        if self.torsional_inertia is None:
            raise ValueError(
                f"{what} needs the beam's torsion: torsional_inertia [kg*m] (rho*I_p per unit "
                "length) and torsional_stiffness [N*m^2] (GJ; None for a torsionally rigid "
                "beam) are expected; got torsional_inertia = None (a planar beam). Give them, "
                "or build the beam with a section constructor (Beam.circular_rod, tube, "
                "rectangular), which fills every property")

    # -- constructors -------------------------------------------------------------------------
    @classmethod
    def circular_rod(cls, length: float, diameter: float, density: float, youngs_modulus: float,
                     *, poisson_ratio: float = 0.3, damping_ratio: float = 0.0,
                     damping_convention: str = "cantilever",
                     tip: TipBody | None = None) -> "Beam":
        """Solid circular rod (the paper's example: 10 m, 0.01 m, 7800 kg/m**3, 2.06e11 Pa).

        Every property is filled: ``EJ = E pi d**4/64`` in both planes, ``EA = E pi d**2/4``,
        ``GJ = G pi d**4/32`` with ``G = E/(2 (1 + nu))`` (the polar moment is the torsion
        constant of a circle), ``rho*I_p = rho pi d**4/32``.

        Parameters
        ----------
        length : float, m
        diameter : float, m
        density : float, kg/m**3
        youngs_modulus : float, Pa
        poisson_ratio : float, optional
            nu, in (-1, 0.5) [-], for the shear modulus; default 0.3 (steel; aluminium
            alloys 0.33). It enters only torsion.
        damping_ratio, damping_convention : optional
            As :class:`Beam`.
        tip : TipBody, optional
            A rigid body at the free end (:class:`Beam`).
        """
        d = check_range("diameter", diameter, "length")
        rho = check_range("density", density, "density")
        E = check_range("youngs_modulus", youngs_modulus, "youngs_modulus")
        nu = _check_poisson_ratio(poisson_ratio)
        _warn_material(E, rho, damping_ratio)
        area = math.pi * d**2 / 4.0
        second_moment = math.pi * d**4 / 64.0
        _check_section(E * second_moment, rho * area,
                       "youngs_modulus*pi*diameter**4/64", "density*pi*diameter**2/4",
                       [("diameter", diameter, "m"), ("youngs_modulus", youngs_modulus, "Pa")],
                       [("diameter", diameter, "m"), ("density", density, "kg/m^3")])
        return cls._section(length, E, nu, rho, area, second_moment, second_moment,
                            2.0 * second_moment, 2.0 * second_moment, damping_ratio,
                            [("diameter", diameter, "m")], tip, damping_convention)

    @classmethod
    def tube(cls, length: float, outer_diameter: float, wall_thickness: float, density: float,
             youngs_modulus: float, *, poisson_ratio: float = 0.3,
             damping_ratio: float = 0.0, damping_convention: str = "cantilever",
             tip: TipBody | None = None) -> "Beam":
        """Thin- or thick-walled circular tube (a typical deployable boom).

        ``EJ = E pi (D**4 - d**4)/64`` in both planes, ``EA``, ``GJ = G pi (D**4 - d**4)/32``
        (a closed circular tube's torsion constant is its polar moment) and
        ``rho*I_p = rho pi (D**4 - d**4)/32``.

        Parameters
        ----------
        length : float, m
        outer_diameter : float, m
        wall_thickness : float, m
            Must be at most half the outer diameter (a solid rod at equality).
        density : float, kg/m**3
        youngs_modulus : float, Pa
        poisson_ratio : float, optional
            nu in (-1, 0.5) [-], default 0.3.
        damping_ratio, damping_convention : optional
            As :class:`Beam`.
        tip : TipBody, optional
            A rigid body at the free end (:class:`Beam`).
        """
        D = check_range("outer_diameter", outer_diameter, "length")
        t = check_range("wall_thickness", wall_thickness, "length")
        if t > D / 2.0:
            raise ValueError(
                f"wall_thickness must be at most outer_diameter/2 = {D / 2.0!r} [m]; got {t!r}"
            )
        rho = check_range("density", density, "density")
        E = check_range("youngs_modulus", youngs_modulus, "youngs_modulus")
        nu = _check_poisson_ratio(poisson_ratio)
        _warn_material(E, rho, damping_ratio)
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
        return cls._section(length, E, nu, rho, area, second_moment, second_moment,
                            2.0 * second_moment, 2.0 * second_moment, damping_ratio,
                            [("outer_diameter", outer_diameter, "m"),
                             ("wall_thickness", wall_thickness, "m")], tip, damping_convention)

    @classmethod
    def rectangular(cls, length: float, width: float, thickness: float, density: float,
                    youngs_modulus: float, *, poisson_ratio: float = 0.3,
                    damping_ratio: float = 0.0, damping_convention: str = "cantilever",
                    tip: TipBody | None = None) -> "Beam":
        """Solid rectangular section: thickness along local y, width along local z.

        The planar beam (x-y plane) bends about its thin direction (a panel strip or tape,
        a solar-array wing out of its plane): ``EJ = E width thickness**3/12``; the x-z plane
        bends about the wide direction: ``EJ_y = E thickness width**3/12``. ``EA = E width
        thickness``, ``GJ = G J_t`` with the Saint-Venant constant
        (:func:`rectangle_torsion_constant`), ``rho*I_p = rho width thickness (width**2 +
        thickness**2)/12``.

        Parameters
        ----------
        length, width, thickness : float, m
            ``thickness`` is the dimension in the x-y bending plane (along local y).
        density : float, kg/m**3
        youngs_modulus : float, Pa
        poisson_ratio : float, optional
            nu in (-1, 0.5) [-], default 0.3.
        damping_ratio, damping_convention : optional
            As :class:`Beam`.
        tip : TipBody, optional
            A rigid body at the free end (:class:`Beam`).
        """
        b = check_range("width", width, "length")
        h = check_range("thickness", thickness, "length")
        rho = check_range("density", density, "density")
        E = check_range("youngs_modulus", youngs_modulus, "youngs_modulus")
        nu = _check_poisson_ratio(poisson_ratio)
        _warn_material(E, rho, damping_ratio)
        _check_section(E * b * h**3 / 12.0, rho * b * h, "youngs_modulus*width*thickness**3/12",
                       "density*width*thickness",
                       [("width", width, "m"), ("thickness", thickness, "m"),
                        ("youngs_modulus", youngs_modulus, "Pa")],
                       [("width", width, "m"), ("thickness", thickness, "m"),
                        ("density", density, "kg/m^3")])
        return cls._section(length, E, nu, rho, b * h, b * h**3 / 12.0, h * b**3 / 12.0,
                            rectangle_torsion_constant(b, h), b * h * (b * b + h * h) / 12.0,
                            damping_ratio, [("width", width, "m"), ("thickness", thickness, "m")],
                            tip, damping_convention)

    @classmethod
    def _section(cls, length, E, nu, rho, area, I_z, I_y, torsion_constant, polar_moment,
                 damping_ratio, dimensions, tip=None,
                 damping_convention="cantilever") -> "Beam":
        """A beam from section properties, every derived one checked against RANGES."""
        given_E = dimensions + [("youngs_modulus", E, "Pa")]
        values = {
            "bending_stiffness_y": check_derived(E * I_y, "bending_stiffness",
                                                 "youngs_modulus*I_y", given_E),
            "axial_stiffness": check_derived(E * area, "axial_stiffness",
                                             "youngs_modulus*area", given_E),
            "torsional_stiffness": check_derived(
                E / (2.0 * (1.0 + nu)) * torsion_constant, "torsional_stiffness",
                "youngs_modulus/(2 (1 + poisson_ratio))*J_t",
                given_E + [("poisson_ratio", nu, "-")]),
            "torsional_inertia": check_derived(rho * polar_moment, "torsional_inertia",
                                               "density*I_p",
                                               dimensions + [("density", rho, "kg/m^3")]),
        }
        # the section constructor warned about the material and the damping at its caller
        return cls._quiet(length, E * I_z, rho * area, damping_ratio=damping_ratio,
                          damping_convention=damping_convention, tip=tip, **values)

    def __repr__(self) -> str:
        extra = "".join(f", {name}={value!r}" for name, value in (
            ("bending_stiffness_y", self._bending_stiffness_y),
            ("torsional_stiffness", self.torsional_stiffness),
            ("torsional_inertia", self.torsional_inertia),
            ("axial_stiffness", self.axial_stiffness)) if value is not None)
        tip = "" if self.tip is None else f", tip={self.tip!r}"
        convention = ("" if self.damping_convention == "cantilever"
                      else f", damping_convention={self.damping_convention!r}")
        return (f"Beam(length={self.length!r}, bending_stiffness={self.bending_stiffness!r}, "
                f"linear_density={self.linear_density!r}{extra}, "
                f"damping_ratio={self.damping_ratio!r}{convention}{tip})")

    def _three_axis_properties(self) -> dict:
        return {"bending_stiffness_y": self._bending_stiffness_y,
                "torsional_stiffness": self.torsional_stiffness,
                "torsional_inertia": self.torsional_inertia,
                "axial_stiffness": self.axial_stiffness}

    def undamped(self) -> "Beam":
        """The same beam without damping (itself when already undamped)."""
        if self.damping_ratio == 0.0:
            return self
        cached = self._cache.get("undamped")
        if cached is None:
            cached = Beam(self.length, self.bending_stiffness, self.linear_density,
                          tip=self.tip, **self._three_axis_properties())
            self._cache["undamped"] = cached
        return cached

    # -- the four motions ---------------------------------------------------------------------
    def planar_view(self, plane: str = "xy") -> "Beam":
        """The planar beam of one bending plane (same length, density and damping).

        Parameters
        ----------
        plane : {"xy", "xz"}
            "xy": EJ = ``bending_stiffness`` (deflection v, ``theta_z = dv/dx``); "xz":
            EJ = ``bending_stiffness_y``, in the planar convention (``delta = w(0)``,
            ``phi = dw/dx(0) = -theta_y``, loads F_z and ``-M_y``).
        """
        if plane not in ("xy", "xz"):
            raise ValueError(f"plane must be 'xy' or 'xz'; got {describe(plane)}")
        key = f"plane_{plane}"
        cached = self._cache.get(key)
        if cached is None:
            EJ = self.bending_stiffness if plane == "xy" else self.bending_stiffness_y
            if plane == "xy" and all(v is None for v in self._three_axis_properties().values()):
                cached = self
            else:
                cached = Beam._quiet(self.length, EJ, self.linear_density,
                                     damping_ratio=self.damping_ratio,
                                     damping_convention=self.damping_convention,
                                     tip=self._planar_tip(plane))
            self._cache[key] = cached
        return cached

    def _planar_tip(self, plane: str) -> TipBody | None:
        """The tip body as a planar model of one plane sees it: its moment about z (x-y) or y
        (x-z), its offset along x and across the axis in that plane."""
        tip = self.tip
        if tip is None:
            return None
        if plane == "xy":
            return TipBody(tip.mass, tip.planar_inertia, tip.offset[:2])
        return TipBody(tip.mass, float(tip.inertia_tensor[1, 1]), tip.offset[[0, 2]])

    def torsion_rod(self) -> Rod | None:
        """The beam's torsion as an exact rod (GJ, rho*I_p), or None when torsionally rigid
        (the beam's own, without a tip body).

        Raises ValueError naming the missing property for a planar beam.
        """
        self.require_three_axis("torsion_rod()")
        if self.torsional_stiffness is None:
            return None
        if "torsion" not in self._cache:
            self._cache["torsion"] = Rod(self.length, self.torsional_stiffness,
                                         self.torsional_inertia,
                                         damping_ratio=self.damping_ratio, motion="torsion",
                                         damping_convention=self.damping_convention)
        return self._cache["torsion"]

    def rod_cantilever_frequencies(self, motion: str, n: int) -> np.ndarray:
        """First n frequencies of the beam's torsion or axial motion alone with the root
        clamped, the tip body's moment about the axis or its mass included [rad/s]
        (:meth:`SegmentedBeam.rod_cantilever_frequencies
        <appendages.segmented.SegmentedBeam.rod_cantilever_frequencies>`; without a tip body
        the exact rod's, :meth:`torsion_rod`, :meth:`axial_rod`). Empty where the beam is
        rigid in that motion."""
        if self._segmented is not None:
            return self._segmented.rod_cantilever_frequencies(motion, n)
        if motion not in ("torsion", "axial"):
            raise ValueError(f"motion must be 'torsion' or 'axial'; got {describe(motion)}")
        rod = self.torsion_rod() if motion == "torsion" else self.axial_rod()
        return np.zeros(0) if rod is None else rod.cantilever_frequencies(n)

    def axial_rod(self) -> Rod | None:
        """The beam's axial motion as an exact rod (EA, rho*A), or None when inextensible (the
        beam's own, without a tip body)."""
        if self.axial_stiffness is None:
            return None
        if "axial" not in self._cache:
            self._cache["axial"] = Rod(self.length, self.axial_stiffness, self.linear_density,
                                       damping_ratio=self.damping_ratio, motion="axial",
                                       damping_convention=self.damping_convention)
        return self._cache["axial"]

    # -- rigid properties ---------------------------------------------------------------------
    @property
    def mass(self) -> float:
        """Mass m = rho*A L [kg], the tip body's included."""
        if self._segmented is not None:
            return self._segmented.mass
        return self.linear_density * self.length

    @property
    def inertia(self) -> float:
        """Moment of inertia about z through the centre of mass, undeformed: m L**2/12
        [kg*m**2] (with a tip body: its moment and the parallel-axis terms added)."""
        if self._segmented is not None:
            return self._segmented.inertia
        return self.mass * self.length**2 / 12.0

    @property
    def first_moment(self) -> float:
        """First moment of the mass about the root along x [kg*m]: m L/2 for the bare beam."""
        if self._segmented is not None:
            return self._segmented.first_moment
        return 0.5 * self.mass * self.length

    @property
    def center_of_mass_vector(self) -> np.ndarray:
        """Centre of mass from the root, beam axes [m], shape (3,) (off the axis only with a
        tip body offset across it)."""
        if self._segmented is not None:
            return self._segmented.center_of_mass_vector
        return np.array([0.5 * self.length, 0.0, 0.0])

    @property
    def rigid_mass_matrix(self) -> np.ndarray:
        """Rigid mass matrix about the root in (delta, phi) [kg, kg*m; kg*m, kg*m**2]:
        ``rho*A [[L, L**2/2], [L**2/2, L**3/3]]`` for the bare beam."""
        if self._segmented is not None:
            return self._segmented.rigid_mass_matrix
        L = self.length
        return self.linear_density * np.array([[L, L**2 / 2.0], [L**2 / 2.0, L**3 / 3.0]])

    @property
    def rigid_mass_matrix6(self) -> np.ndarray:
        """Rigid mass matrix about the root in (u, v, w, theta_x, theta_y, theta_z)."""
        if self._segmented is not None:
            return self._segmented.rigid_mass_matrix6
        self.require_three_axis("rigid_mass_matrix6")
        m, L = self.mass, self.length
        M = np.zeros((6, 6))
        M[0, 0] = M[1, 1] = M[2, 2] = m
        M[3, 3] = self.torsional_inertia * L
        M[4, 4] = M[5, 5] = m * L**2 / 3.0
        M[1, 5] = M[5, 1] = m * L / 2.0
        M[2, 4] = M[4, 2] = -m * L / 2.0
        return M

    @property
    def frequency_scale(self) -> float:
        """sqrt(EJ/(rho*A L**4)) [rad/s]: a root x_k gives the frequency x_k**2 times this."""
        return math.sqrt(self.bending_stiffness / (self.linear_density * self.length**4))

    @property
    def center_of_mass(self) -> float:
        """Distance of the centre of mass from the attachment end along x [m]: L/2 for the
        bare beam."""
        if self._segmented is not None:
            return self._segmented.center_of_mass
        return 0.5 * self.length

    @property
    def inertia_tensor(self) -> np.ndarray:
        """Inertia about the centre of mass in beam axes [kg*m**2], undeformed (three axes).

        ``diag(rho*I_p L, m L**2/12, m L**2/12)``: no rotary inertia of the section in bending
        (Euler-Bernoulli, as :attr:`inertia`).
        """
        self.require_three_axis("inertia_tensor")
        if self._segmented is not None:
            return self._segmented.inertia_tensor
        return np.diag([self.torsional_inertia * self.length, self.inertia, self.inertia])

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
            cached = _shared_roots(kind, max(n, 16))
            self._cache[kind] = cached
        return cached[:n]

    def natural_frequencies(self, n: int) -> np.ndarray:
        """First n free-free bending frequencies w_k [rad/s] (rigid-body modes excluded)."""
        if self._segmented is not None:
            return self._segmented.natural_frequencies(n)
        return self._roots("free-free", n) ** 2 * self.frequency_scale

    def cantilever_frequencies(self, n: int) -> np.ndarray:
        """First n clamped-free frequencies [rad/s] (attachment end clamped)."""
        if self._segmented is not None:
            return self._segmented.cantilever_frequencies(n)
        return self._roots("clamped-free", n) ** 2 * self.frequency_scale

    def zeros(self, r: int, n: int = 2) -> np.ndarray:
        """First n zero frequencies of the exact W_r [rad/s] (r = 1, 2, 3, 4).

        W1: pinned-free frequencies (``tan x = tanh x``); W2 = W3: ``x = k pi``;
        W4: sliding-free frequencies (``tan x = -tanh x``).
        """
        if isinstance(r, bool) or not isinstance(r, (int, np.integer)) or r not in (1, 2, 3, 4):
            raise ValueError(f"r must be 1, 2, 3 or 4 (W1, W2, W3, W4); got {describe(r)}")
        if self._segmented is not None:
            return self._segmented.zeros(r, n)
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
        self._uniform_only("mode_shapes")
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

    def _uniform_only(self, what: str) -> None:
        """ValueError for the closed forms of the bare uniform beam asked of a tip beam."""
        if self._segmented is not None:
            raise ValueError(f"{what} is a closed form of the bare uniform beam; a beam with a "
                             "tip body has no such closed form (its modal data: "
                             "free_free_modes, cantilever_modes)")

    # -- modal data (the truncations' input; closed forms, or the assembled model's) ----------
    def free_free_modes(self, n: int, *, n_root: int = 2):
        """The first n free-free bending modes: (frequencies (n,) [rad/s], root values
        ``b_k = (phi_k(0), phi_k'(0))`` (n, 2) [1/sqrt(kg), 1/(sqrt(kg) m)], tip values
        ``phi_k(L)`` (n, 1)), mass-normalised. ``n_root=6``: the three-axis modes of a beam
        with a tip body (root values (n, 6), tip rows v, w, theta_x)."""
        if self._segmented is not None:
            return self._segmented.free_free_modes(n, n_root=n_root)
        self._planar_data(n_root)
        root, tip = self._free_free_root_values(n)
        return self.natural_frequencies(n), root, tip[:, None]

    def cantilever_modes(self, n: int, *, n_root: int = 2):
        """The first n cantilever modes: (frequencies (n,) [rad/s], participation factors
        ``l_k = [integral rho*A psi_k, integral rho*A x psi_k]`` (n, 2) [sqrt(kg),
        sqrt(kg)*m], tip values ``psi_k(L)`` (n, 1)), mass-normalised (``n_root=6``: as
        :meth:`free_free_modes`)."""
        if self._segmented is not None:
            return self._segmented.cantilever_modes(n, n_root=n_root)
        self._planar_data(n_root)
        return (self.cantilever_frequencies(n), self.modal_participation(n),
                self._cantilever_tip_values(n)[:, None])

    def free_free_tail(self, n: int, power: int, *, n_root: int = 2):
        """``(sum_{k>n} b_k b_k^T/w_k**power (2, 2), sum_{k>n} phi_k(L) b_k/w_k**power (1, 2))``
        over the dropped free-free modes, without cancellation (power 2, 3, 4; with a tip
        body 2 and 4)."""
        if self._segmented is not None:
            return self._segmented.free_free_tail(n, power, n_root=n_root)
        self._planar_data(n_root)
        if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 0:
            raise ValueError(f"n must be a non-negative integer (modes kept); got {describe(n)}")
        if isinstance(power, (bool, np.bool_)) or power not in (2, 3, 4):
            raise ValueError(f"power must be 2, 3 or 4; got {describe(power)}")
        bb, tb = self._free_free_tail(n, power)
        return bb, tb[None, :]

    def _planar_data(self, n_root) -> None:
        if n_root != 2:
            raise ValueError("the bare uniform beam's modal data are planar (n_root=2): its "
                             "motions are separate (planar_view, torsion_rod, axial_rod); "
                             f"got n_root={describe(n_root)}")

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
        give m and m L**2/3 (the effective masses), a check used in the tests. With a tip
        body: the assembled model's (:meth:`cantilever_modes`).
        """
        if self._segmented is not None:
            return self._segmented.cantilever_modes(n)[1]
        xk = self._roots("clamped-free", n)
        sigma = _clamped_free_sigma(n)
        beta = xk / self.length
        scale = self.linear_density / math.sqrt(self.mass)
        return np.column_stack([2.0 * sigma / beta, 2.0 / beta**2]) * scale

    def cantilever_participation_tail(self, n: int, *, n_root: int = 2) -> np.ndarray:
        """``sum_{k>n} l_k l_k^T`` of the participation factors, shape (2, 2) [kg, kg*m; ...].

        The rigid mass the first n cantilever modes leave to the others: with
        ``l_k = rho*A/sqrt(m) (2 sigma_k/beta_k, 2/beta_k**2)`` (:meth:`modal_participation`),
        ``l_k l_k^T = 4 rho*A/L [[sigma**2/b**2, sigma/b**3], [., 1/b**4]]`` with b = beta_k
        (in 1/m). Modes n < k <= max(n, 16) are summed explicitly; beyond, ``sigma_k = 1`` and
        ``beta_k L = (k - 1/2) pi`` to below 1e-19, and ``sum_{k>K} (beta_k L)**-q =
        pi**-q zeta(q, K + 1/2)`` (Hurwitz). No cancellation, unlike ``M_rr - L^T L``
        (which a beam with a tip body uses: :class:`~appendages.segmented.SegmentedBeam`).
        """
        if self._segmented is not None:
            return self._segmented.cantilever_participation_tail(n, n_root=n_root)
        self._planar_data(n_root)
        if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 0:
            raise ValueError(f"n must be a non-negative integer (modes kept); got {describe(n)}")
        L = self.length
        self._roots("clamped-free", max(n, 16))      # checks the number of roots
        sums = _participation_tail_sums(int(n))
        f = 4.0 * self.linear_density * L
        return f * np.array([[sums[0], sums[1] * L], [sums[1] * L, sums[2] * L**2]])

    def free_cantilever_overlap(self, n_free: int, n_cantilever: int) -> np.ndarray:
        r"""Mass inner products of free-free and cantilever modes, shape (n_free, n_cantilever).

        ``O[k, i] = integral rho*A phi_k psi_i dx`` (mass-normalised shapes, dimensionless).
        From the beam equation and the boundary conditions (phi'' = phi''' = 0 at both ends,
        psi = psi' = 0 at x = 0, psi'' = psi''' = 0 at x = L),
        ``(b_k^4 - b_i^4) integral phi_k psi_i = phi_k(0) psi_i'''(0) - phi_k'(0) psi_i''(0)``,
        exact where the roots are well apart: its rounding is about ``eps x/|x_k - x_i|``
        relative (x the roots, themselves rounded to eps x), so it is used where
        ``|x_k - x_i| >= 1``. Free-free root k and cantilever root k + 1 both tend to
        (k + 1/2) pi, where it cancels; those pairs are integrated in closed form instead
        (:func:`_shape_products`, good to a few ulps of their size, about 1):
        each shape is, on ``xi = x/L``, ``A cos(x xi) + B sin(x xi) + C e^{x (xi - 1)} +
        D e^{-x xi}``, and the 16 integrals of the products over [0, 1] are elementary and
        written without cancellation. O(n_free n_cantilever), no quadrature (issue 10: the
        Gauss-Legendre quadrature this replaces took 100 s in a 1000-mode damped
        Craig-Bampton model).
        """
        self._uniform_only("free_cantilever_overlap")
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
        # phi(0) = 2, phi'(0) = -2 sigma_k x_k/L, psi''(0) = 2 x_i^2/L^2,
        # psi'''(0) = -2 sigma_i x_i^3/L^3
        numerator = -4.0 * (si * xi**3)[None, :] + 4.0 * (sk * xk)[:, None] * (xi**2)[None, :]
        with np.errstate(divide="ignore", invalid="ignore"):  # near pairs are replaced below
            overlap = numerator / (xk[:, None] ** 4 - xi[None, :] ** 4)
        rows, cols = np.nonzero(np.abs(xk[:, None] - xi[None, :]) < 1.0)
        overlap[rows, cols] = _shape_products(xk[rows], "free-free", xi[cols], "clamped-free")
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
            (:data:`appendages.interface.S_RANGE`; tests/project/test_extremes.py sweeps it, against
            60-digit closed forms from 1e-8 to 1e8 in tests/project/test_stress.py). s = 0 is the
            rigid-body pole and is rejected.

        Returns
        -------
        ndarray of complex128, shape ``np.shape(s) + (2, 2)``
            ``[[W1, W2], [W2, W4]]`` in m/N, 1/N and 1/(N*m).
        """
        if self._segmented is not None:
            return self._segmented.W(s)
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError("s = 0 is the rigid-body pole of W (W is infinite there) [rad/s]")
        if self.damping_ratio > 0.0 and self.damping_convention == "cantilever":
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                W = inverse_2x2(self._cantilever_damping()(s.ravel())).reshape(s.shape + (2, 2))
            if not np.all(np.isfinite(W)):  # pragma: no cover - damped W is finite
                raise ValueError("W is not finite at s (damped beam) [rad/s]")
            return W
        W = np.zeros(s.shape + (2, 2), dtype=np.complex128)
        W[..., 0, 0], W[..., 0, 1], W[..., 1, 1] = self._undamped_entries(s)
        W[..., 1, 0] = W[..., 0, 1]
        if self.damping_ratio > 0.0:
            # the closed form plus each mode's damping; near an undamped pole, where the two
            # cancel, the circle mean of _repair_near_poles instead
            flat, W_flat = s.reshape(-1), W.reshape(-1, 2, 2)
            near, k = self._near_poles(flat)
            far = np.nonzero(~near)[0]
            with np.errstate(divide="ignore", invalid="ignore"):  # a pole's own point is near
                corrections = self._damping_correction(flat[far])
            for (i, j), d in zip(((0, 0), (0, 1), (1, 1)), corrections):
                W_flat[far, i, j] += d
            if near.any():
                for (i, j), d in zip(((0, 0), (0, 1), (1, 1)),
                                     self._repair_near_poles(flat[near], k[near])):
                    W_flat[near, i, j] = d
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
        inverting W. Damped, cantilever convention: the modal sum of
        :meth:`_cantilever_modal_stiffness` (beyond its cap on modes, the closed form with
        the damping corrections of :mod:`appendages.damping`); free-free convention: the
        2x2 inverse of the exact damped W by its adjugate.

        Parameters
        ----------
        s : complex or array_like of complex, rad/s
            Laplace variable; s = 0 gives D = 0 (a free beam offers no static stiffness).

        Returns
        -------
        ndarray of complex128, shape ``np.shape(s) + (2, 2)``
            Infinite entries exactly at a clamped-free frequency (undamped).
        """
        return self._dynamic_stiffness(as_frequency_array(s))

    def _dynamic_stiffness(self, s: np.ndarray) -> np.ndarray:
        """:meth:`dynamic_stiffness` of a checked complex array s."""
        if self._segmented is not None:
            return self._segmented.dynamic_stiffness(s)
        if self.damping_ratio > 0.0 and self.damping_convention == "cantilever":
            flat = s.ravel()
            D = self._cantilever_modal_stiffness(flat)
            if D is None:       # |s| too high for the modal sum: the general evaluation
                D = self._cantilever_damping()(flat)
            return D.reshape(s.shape + (2, 2))
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

    # -- three axes ---------------------------------------------------------------------------
    def _planes_equal(self) -> bool:
        return self.bending_stiffness_y == self.bending_stiffness

    def W6(self, s) -> np.ndarray:
        """Exact three-axis transfer matrix W6(s) of the free beam [SI], beam axes.

        Root motions ``(u, v, w, theta_x, theta_y, theta_z)`` caused by root loads
        ``(F_x, F_y, F_z, M_x, M_y, M_z)`` at x = 0. The motions decouple (symmetric
        section), so W6 is made of

        * x-y bending: :meth:`W` (``[[W1, W2], [W2, W4]]``) in rows/columns (v, theta_z);
        * x-z bending: the planar W of :meth:`planar_view` ("xz"), whose coordinates are
          ``(w, dw/dx = -theta_y)`` under ``(F_z, -M_y)``: in (w, theta_y) it is
          ``S W S`` with ``S = diag(1, -1)``, i.e. ``[[W1, -W2], [-W2, W4]]`` (the rigid part
          ``theta_y/F_z = +6/(m L s**2)``, opposite to ``theta_z/F_y``);
        * torsion and axial motion: the exact rods of :mod:`appendages.rod`,
          ``z coth(z)/(m_r s**2)``; a torsionally rigid or inextensible beam has the rigid
          ``1/(m_r s**2)`` (m_r = rho*I_p L or m).

        Every part is exact and stable at any |s| in :data:`~appendages.interface.S_RANGE`
        (damped too), so W6 is.

        Parameters
        ----------
        s : complex or array_like of complex, rad/s
            Not 0 (the rigid-body pole).

        Returns
        -------
        ndarray of complex128, shape ``np.shape(s) + (6, 6)``

        Raises
        ------
        ValueError
            A planar beam (no ``torsional_inertia``), s = 0, or s at an undamped natural
            frequency.
        """
        self.require_three_axis("W6")
        if self._segmented is not None:
            return self._segmented.W6(s)
        s = as_frequency_array(s)
        if np.any(s == 0):
            raise ValueError("s = 0 is the rigid-body pole of W6 (W6 is infinite there) [rad/s]")
        W_xy = self.W(s)
        W_xz = W_xy if self._planes_equal() else self.planar_view("xz").W(s)
        W6 = np.zeros(s.shape + (6, 6), dtype=np.complex128)
        place_bending_planes(W6, W_xy, W_xz)
        W6[..., 0, 0] = self._rod_entry(self.axial_rod(), self.mass, s, "W")
        W6[..., 3, 3] = self._rod_entry(self.torsion_rod(),
                                        self.torsional_inertia * self.length, s, "W")
        return W6

    def dynamic_stiffness6(self, s) -> np.ndarray:
        """Exact three-axis root dynamic stiffness D6(s) = W6(s)^-1 [SI], beam axes.

        Assembled like :meth:`W6` from each plane's :meth:`dynamic_stiffness` (the x-z
        plane's off-diagonal with the opposite sign) and the rods' ``m_r s**2 tanh(z)/z``
        (rigid: ``m_r s**2``). Undamped, it stays accurate where W6 is singular and is
        infinite exactly at a clamped frequency of some motion; s = 0 gives 0.

        Returns
        -------
        ndarray of complex128, shape ``np.shape(s) + (6, 6)``
        """
        self.require_three_axis("dynamic_stiffness6")
        if self._segmented is not None:
            return self._segmented.dynamic_stiffness6(s)
        s = as_frequency_array(s)
        D6 = np.zeros(s.shape + (6, 6), dtype=np.complex128)
        if self._modal_stiffness6(s.ravel(), D6.reshape(-1, 6, 6)):
            return D6
        D_xy = self._dynamic_stiffness(s)
        D_xz = D_xy if self._planes_equal() else self.planar_view("xz")._dynamic_stiffness(s)
        place_bending_planes(D6, D_xy, D_xz)
        D6[..., 0, 0] = self._rod_entry(self.axial_rod(), self.mass, s, "D")
        D6[..., 3, 3] = self._rod_entry(self.torsion_rod(),
                                        self.torsional_inertia * self.length, s, "D")
        return D6

    def _modal_stiffness6(self, s: np.ndarray, D6: np.ndarray) -> bool:
        """D6 at flat s into ``D6`` (npts, 6, 6), zero on entry, by the cantilever modal sums
        of every motion together (:class:`~appendages.damping.CantileverModalSums`; the beam's
        damping ratio is every motion's), each motion's sum the one :meth:`dynamic_stiffness`
        and the rods give; False (nothing written) where they do not apply: undamped, the
        free-free convention, or beyond a motion's cap on modes."""
        if not (self.damping_ratio > 0.0 and self.damping_convention == "cantilever"):
            return False
        top = float(np.abs(s).max()) if s.size else 0.0
        planes = [self] if self._planes_equal() else [self, self.planar_view("xz")]
        rods = [(0, self.axial_rod(), self.mass),
                (3, self.torsion_rod(), self.torsional_inertia * self.length)]
        members = planes + [rod for _, rod, _ in rods if rod is not None]
        sizes = tuple(member._modal_sum_size(top) for member in members)
        if None in sizes:
            return False
        key = ("cantilever_modal_sums6", sizes)
        cached = self._cache.get(key)
        if cached is None:
            motions = [member._modal_motion(n) for member, n in zip(members, sizes)]
            cached = self._cache[key] = _joint_modal_sums(
                motions, [rod.motion for rod in members[len(planes):]], self.damping_ratio)
        sums, entries, columns = cached
        D6.reshape(s.size, 36)[:, entries] = sums(s)[:, columns]
        for index, rod, inertia in rods:
            if rod is None:
                D6[:, index, index] = inertia * s**2
        return True

    @staticmethod
    def _rod_entry(rod, rigid_inertia: float, s: np.ndarray, which: str) -> np.ndarray:
        if rod is not None:
            if which == "W":
                return rod.W(s)
            return rod.dynamic_stiffness(s, check=False)      # s checked by the caller
        with np.errstate(divide="ignore"):
            return 1.0 / (rigid_inertia * s**2) if which == "W" else rigid_inertia * s**2

    def clamped_frequencies6(self, omega_max: float) -> np.ndarray:
        """Every natural frequency with the attachment end clamped, all motions [rad/s].

        The cantilever frequencies of both bending planes, torsion and axial motion (rigid
        motions have none), ascending: every one up to the last returned, which is above
        ``omega_max`` (the Wittrick-Williams count of a three-axis spacecraft needs them;
        it takes the last as the bound of completeness). Each motion's list is extended
        beyond omega_max and the union cut at the smallest of their ends.
        """
        self.require_three_axis("clamped_frequencies6")
        if self._segmented is not None:
            return self._segmented.clamped_frequencies6(omega_max)
        parts = []
        for plane in (("xy",) if self._planes_equal() else ("xy", "xz")):
            beam = self.planar_view(plane)
            n = 8
            while True:
                wc = beam.cantilever_frequencies(n)
                if wc[-1] > omega_max:
                    break
                n *= 2
            parts += [wc, wc] if self._planes_equal() else [wc]
        for rod in (self.torsion_rod(), self.axial_rod()):
            if rod is not None:
                parts.append(rod.cantilever_frequencies_below(omega_max))
        complete = min(part[-1] for part in parts)
        merged = np.sort(np.concatenate(parts))
        return merged[merged <= complete]

    def _cantilever_damping(self) -> CantileverDamping:
        """The damped root dynamic stiffness of the cantilever convention (built once)."""
        cached = self._cache.get("cantilever_damping")
        if cached is None:
            bare = self.undamped()
            cached = CantileverDamping(
                self.damping_ratio, lambda s: bare._dynamic_stiffness(s),
                lambda n: (self.cantilever_frequencies(n), self.modal_participation(n)),
                self.rigid_mass_matrix, tail=self._cantilever_tail)
            self._cache["cantilever_damping"] = cached
        return cached

    def _cantilever_modal_stiffness(self, s: np.ndarray) -> np.ndarray | None:
        r"""The damped root dynamic stiffness of the cantilever convention by its modal sum,
        at flat complex s: shape (npts, 2, 2), or None where it would need more than
        :data:`_MODAL_MAX_MODES` modes.

        With the completeness of the cantilever modes, ``M_rr = sum_k l_k l_k^T``
        (:mod:`appendages.damping`), the modal form
        ``D = s**2 M_rr - s**4 sum_k l_k l_k^T/(s**2 + 2 zeta w_k s + w_k**2)`` is

            D(s) = s**2 sum_{k<=N} l_k l_k^T (w_k**2 + 2 zeta w_k s)/(s**2 + 2 zeta w_k s + w_k**2)
                   + s**2 R_N - s**4 sum_{k>N} l_k l_k^T/w_k**2 h(s/w_k),

        ``R_N = sum_{k>N} l_k l_k^T`` (:meth:`cantilever_participation_tail`, Hurwitz sums, no
        cancellation) and ``h(u) = 1/(1 + 2 zeta u + u**2) = sum_m U_m(-zeta) u**m``
        (Chebyshev), summed like :meth:`_cantilever_tail` over the asymptotic modes k > N:
        ``sum_m U_m(-zeta) v**(4+m) c0**2 (4 rho*A/L) [L**2 Z(6+2m), L**3 Z(7+2m),
        L**4 Z(8+2m)]`` (v = s/c0, Z of :meth:`_cantilever_tail`). N (a power of two, at
        least 16) puts every mode up to 10 max|s| in the explicit sum, so that |u| <= 1/10 in
        the tail and its 12 terms leave below 1e-12 of it. No term cancels another: a mode
        far below |s| contributes about ``-l l^T w_k**2`` (the rod's stiffness it carries),
        one far above ``s**2 l l^T``, and the denominators are written as
        ``(s - i w_k)(s + i w_k) + 2 zeta w_k s`` (no difference of squares near a
        resonance). It equals the closed form with the damping corrections of
        :class:`~appendages.damping.CantileverDamping` to rounding, at a fraction of the cost
        (no repair about the undamped poles, one pass over the points); s = 0 gives 0.
        """
        N = self._modal_sum_size(float(np.abs(s).max()) if s.size else 0.0)
        if N is None:
            return None
        key = ("cantilever_modal_sums", N)
        sums = self._cache.get(key)
        if sums is None:
            sums = self._cache[key] = CantileverModalSums([self._modal_motion(N)],
                                                          self.damping_ratio)
        entries = sums(s)
        # [[D11, D12], [D12, D22]] from the entries (D11, D12, D22) of each point
        return entries[:, [0, 1, 1, 2]].reshape(s.size, 2, 2)

    def _modal_sum_size(self, top: float) -> int | None:
        """N of :meth:`_cantilever_modal_stiffness` at points up to ``top`` = max|s| [rad/s]:
        a power of two, at least 16, with every mode up to 10 top; None beyond
        :data:`_MODAL_MAX_MODES`."""
        c0 = self.frequency_scale
        N = 16
        while ((N + 0.5) * math.pi) ** 2 * c0 < 10.0 * top:
            N *= 2
            if N > _MODAL_MAX_MODES:
                return None
        return N

    def _modal_motion(self, N: int) -> tuple:
        """This plane's terms of :class:`~appendages.damping.CantileverModalSums` with N
        explicit modes (:meth:`_cantilever_modal_stiffness`), worked out once: the entries
        (D11, D12, D22) of the products l_k l_k^T, of R_N and of the tail's coefficients."""
        key = ("cantilever_modal", N)
        motion = self._cache.get(key)
        if motion is None:
            c0 = self.frequency_scale
            w = self.cantilever_frequencies(N)
            l = self.modal_participation(N)
            products = np.stack([l[:, 0] ** 2, l[:, 0] * l[:, 1], l[:, 1] ** 2], axis=1)
            R = self.cantilever_participation_tail(N)
            L = self.length
            cheb, Z = _modal_sum_constants(N, self.damping_ratio)
            scale = 4.0 * self.linear_density / L * c0**2 * np.array([L**2, L**3, L**4])[:, None]
            motion = self._cache[key] = (w, products, np.array([R[0, 0], R[0, 1], R[1, 1]]),
                                         (scale * cheb[None, :] * Z).T, c0)
        return motion

    def _cantilever_tail(self, s: np.ndarray, n: int) -> np.ndarray:
        r"""The damping of the cantilever modes k > n (:mod:`appendages.damping`), exactly.

        Beyond n >= 16 the roots are ``x_k = (k - 1/2) pi`` and ``sigma_k = 1`` to below
        1e-19, so ``l_k l_k^T = (4 rho*A/L) [[L**2/x**2, L**3/x**3], [., L**4/x**4]]``,
        ``w_k = x_k**2 c0``; with ``g(u) = sum_j c_j u**j``
        (:func:`~appendages.damping.hurwitz_tail_coefficients`, |u| <= 1/10 where it is
        used, 12 terms: the rest below 1e-10 of the first) the tail is
        ``sum_j c_j v**(4+j) c0**2 (4 rho*A/L) [L**2 Z(6+2j), L**3 Z(7+2j), L**4 Z(8+2j)]``
        with ``v = s/c0`` and ``Z(q) = pi**-q zeta(q, n + 1/2)`` (Hurwitz). Where the mode cap
        of :mod:`appendages.damping` binds and ``|s|/w_(n+1) > 1/2`` only the leading term is
        kept. Returns shape (npts, 2, 2).
        """
        c0, L = self.frequency_scale, self.length
        w_next = ((n + 0.5) * math.pi) ** 2 * c0
        n_terms = _TAIL_TERMS if float(np.max(np.abs(s), initial=0.0)) <= 0.5 * w_next else 1
        key = ("cantilever_tail", n, n_terms)
        coefficients = self._cache.get(key)
        if coefficients is None:
            c = hurwitz_tail_coefficients(self.damping_ratio, n_terms)
            j = np.arange(1, n_terms + 1)
            orders = 2 * j[None, :] + np.array([[6], [7], [8]])
            Z = math.pi ** (-orders.astype(float)) * scipy.special.zeta(orders, n + 0.5)
            scale = 4.0 * self.linear_density / L * c0**2 * np.array([L**2, L**3, L**4])[:, None]
            coefficients = self._cache[key] = scale * c[None, :] * Z      # (3, J)
        v = s / c0
        out = np.zeros((3, s.size), dtype=np.complex128)
        for t in range(n_terms - 1, -1, -1):
            out = (out + coefficients[:, t:t + 1]) * v
        out = out * v**4
        D = np.empty((s.size, 2, 2), dtype=np.complex128)
        D[:, 0, 0], D[:, 0, 1], D[:, 1, 1] = out
        D[:, 1, 0] = D[:, 0, 1]
        return D

    def _undamped_entries(self, s: np.ndarray):
        """W1, W2, W4 of the undamped closed form (module docstring), each of shape s.shape."""
        EJ, L = self.bending_stiffness, self.length
        y = -(s**2) * (self.linear_density * L**4 / EJ)
        with np.errstate(divide="ignore", invalid="ignore"):
            f1, f2, f4 = _dimensionless_W(y.ravel())
        return (f1.reshape(s.shape) * (L**3 / EJ), f2.reshape(s.shape) * (L**2 / EJ),
                f4.reshape(s.shape) * (L / EJ))

    def _repair_near_poles(self, s: np.ndarray, k: np.ndarray, n_points: int = 32):
        """Damped W at points s near an undamped pole +-i w_k, without cancellation.

        There the undamped closed form is huge and the damping correction cancels it. Instead,
        ``g(s) = W_undamped(s) - b_k b_k^T/(s^2 + w_k^2)`` is analytic in a disc around i w_k and
        equals its mean over a circle of radius r (mean-value property; the trapezoidal rule
        with 32 points converges like (|s - i w_k|/r)^32 there). Then
        ``W = g(s) + b_k b_k^T/(s^2 + 2 zeta w_k s + w_k^2) + sum_{j != k} corrections``.
        The points are those of :meth:`_near_poles`, ``|s -+ i w_k| <= r/10`` with r a quarter
        of the smaller gap to the neighbouring frequencies, so the rule's error is below
        1e-32 relative to g. All points at once: one evaluation of the closed form on all the
        circles, one damping correction leaving each point's own mode out.

        Parameters
        ----------
        s : ndarray of complex, shape (n,)
        k : ndarray of int, shape (n,)
            The mode (index from 0) each point is near.

        Returns
        -------
        tuple of 3 ndarrays of complex, shape (n,)
            The entries (1,1), (1,2), (2,2) of W.
        """
        w = self.natural_frequencies(int(k.max()) + 2)
        gaps = np.diff(np.concatenate([[0.0], w]))
        radius = 0.25 * np.minimum(gaps[k], gaps[k + 1])
        root, _ = self._free_free_root_values(int(k.max()) + 1)
        bb = (root[k, 0] ** 2, root[k, 0] * root[k, 1], root[k, 1] ** 2)
        theta = 2 * np.pi * (np.arange(n_points) + 0.5) / n_points
        z = s[:, None] + radius[:, None] * np.exp(1j * theta)
        wk = w[k]
        pole_term = 1.0 / (z**2 + (wk**2)[:, None])
        undamped = self._undamped_entries(z)
        damped = 1.0 / (s**2 + 2.0 * self.damping_ratio * wk * s + wk**2)
        others = self._damping_correction(s, exclude=k)
        return tuple(np.mean(u - b[:, None] * pole_term, axis=1) + b * damped + d
                     for u, b, d in zip(undamped, bb, others))

    def _near_poles(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Which points of a flat s lie within a tenth of the repair radius of an undamped pole
        +-i w_k (:meth:`_repair_near_poles`), and that k (index from 0; -1 elsewhere)."""
        c0 = self.frequency_scale
        # the nearest free-free frequency: root k (from 0) lies within 0.02 of (k + 3/2) pi, so
        # the one nearest x = sqrt(|s|/c0) is among the three from floor(x/pi - 3/2) up
        # (beyond 20000 modes, where W is not repaired, every point has k = 19999: not near)
        x = np.minimum(np.sqrt(np.abs(s) / c0), (_MAX_CORRECTION_MODES + 2) * math.pi)
        guess = np.clip(np.floor(x / math.pi - 0.5).astype(np.int64) - 1, 0, None)
        k_max = min(int(guess.max(initial=0)) + 3, _MAX_CORRECTION_MODES)
        w = self.natural_frequencies(k_max + 1)
        gaps = np.diff(np.concatenate([[0.0], w]))
        candidates = np.clip(guess[:, None] + np.arange(3)[None, :], 0, k_max - 1)
        distance = np.abs(np.abs(s)[:, None] - w[candidates])
        k = candidates[np.arange(s.size), np.argmin(distance, axis=1)]
        pole = np.where(s.imag >= 0, 1j, -1j) * w[k]
        radius = 0.25 * np.minimum(gaps[k], gaps[k + 1])
        near = np.abs(s - pole) <= 0.1 * radius
        return near, np.where(near, k, -1)

    def _damping_correction(self, s: np.ndarray, exclude: np.ndarray | None = None):
        r"""Sum over all modes of b_k b_k^T [1/(s^2 + 2 zeta w_k s + w_k^2) - 1/(s^2 + w_k^2)].

        The undamped closed form holds every mode without damping; this adds each mode's
        damping exactly. Each term is ``b_k b_k^T/w_k^2 f(s/w_k)`` with

            f(u) = -2 zeta u / ((1 + u^2)(1 + 2 zeta u + u^2)) = sum_{j>=1} c_j u^j,  |u| < 1,

        written as a product (no difference of the two nearly equal fractions). Modes are
        summed explicitly up to N (per point, N >= 16 and ``w_{N+1} >= 10 |s|``, rounded up to
        a power of two so that points share their sums; at most 20000 modes); beyond, the
        asymptotic ``b_k = (2, -2 x_k/L)/sqrt(m)``, ``x_k = (k + 1/2) pi`` (exact to
        ``e^-x_k``, below 1e-20 for k > 16) turn the tail into Hurwitz zeta sums,

            sum_{k>N} b_k b_k^T/w_k^2 f(s/w_k)
                = 4/m sum_j c_j s^j / c0^(j+2) [[Z(2j+4), -Z(2j+3)/L], [., Z(2j+2)/L^2]],
            Z(q) = sum_{k>N} x_k^-q = pi^-q zeta(q, N + 3/2),

        with the series cut after ``J = 12`` terms (c_j from the Chebyshev series of
        1/(1 + 2 zeta u + u^2), whose |U_n| <= n + 1, give |c_j| <= zeta (j + 1)^2/2): with
        |u| <= 1/10 the terms left out are below 1e-10 of the first (the tail itself is
        O(zeta |s|/w_N^3)).
        Where the 20000-mode cap binds and |s|/w_{N+1} > 1/2 only the leading term is kept.

        Parameters
        ----------
        s : ndarray of complex
        exclude : ndarray of int, optional
            Per point (shape ``s.shape``), a mode (index from 0) left out of the sum, -1 for
            none (:meth:`_repair_near_poles`).

        Returns
        -------
        tuple of 3 ndarrays of complex
            The three distinct entries (1,1), (1,2), (2,2), each of shape ``s.shape``.
        """
        zeta, c0 = self.damping_ratio, self.frequency_scale
        flat = s.ravel()
        skip = np.full(flat.size, -1, dtype=np.int64) if exclude is None \
            else np.asarray(exclude, dtype=np.int64).ravel()
        # N: w_{N+1} = ((N + 3/2) pi)^2 c0 >= 10 |s|, N >= 16, N > the excluded mode
        needed = np.sqrt(10.0 * np.abs(flat) / c0) / math.pi - 1.5
        needed = np.maximum(np.maximum(needed, 16.0), skip + 1.0)
        bucket = np.minimum(2.0 ** np.ceil(np.log2(needed)), _MAX_CORRECTION_MODES).astype(int)
        d = np.empty((3, flat.size), dtype=np.complex128)
        n_all = int(bucket.max(initial=16))
        w_all, products = self._damping_products(n_all)
        for n in np.unique(bucket):
            where = np.nonzero(bucket == n)[0]
            w, w2 = w_all[:n], w_all[:n] ** 2
            chunk = max(1, 1_000_000 // n)
            for start in range(0, where.size, chunk):
                idx = where[start:start + chunk]
                ss = flat[idx, None]
                undamped = ss**2 + w2
                # infinite only at a point's own excluded mode (exactly on its pole), zeroed
                with np.errstate(divide="ignore", invalid="ignore"):
                    inverse = 1.0 / (undamped * (undamped + (2.0 * zeta) * w * ss))
                rows = np.nonzero(skip[idx] >= 0)[0]
                inverse[rows, skip[idx][rows]] = 0.0
                d[:, idx] = (-2.0 * zeta) * flat[idx] * (inverse @ products[:n]).T
            d[:, where] += self._damping_tail(flat[where], n)
        return tuple(row.reshape(s.shape) for row in d)

    def _damping_products(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(w_k, b_k b_k^T w_k as rows (11, 12, 22)) of the first n modes, kept per beam: the
        numerators of the damping correction's terms divided by -2 zeta s."""
        cached = self._cache.get("damping_products")
        if cached is None or cached[0].size < n:
            root, _ = self._free_free_root_values(n)
            w = self.natural_frequencies(n)
            products = np.stack([root[:, 0] ** 2, root[:, 0] * root[:, 1], root[:, 1] ** 2],
                                axis=1) * w[:, None]
            cached = (w, products)
            self._cache["damping_products"] = cached
        return cached[0][:n], cached[1][:n]

    def _damping_tail(self, s: np.ndarray, n: int) -> np.ndarray:
        """The damping correction of the modes k > n (:meth:`_damping_correction`), shape
        (3, s.size)."""
        c0 = self.frequency_scale
        ratio = np.abs(s) / (((n + 1.5) * math.pi) ** 2 * c0)  # |u| at the first tail mode
        n_terms = _TAIL_TERMS if float(ratio.max(initial=0.0)) <= 0.5 else 1
        coefficients = self._cache.get(("damping_tail", n, n_terms))
        if coefficients is None:
            coefficients = self._damping_tail_coefficients(n, n_terms)
            self._cache[("damping_tail", n, n_terms)] = coefficients
        # sum_j c_j (s/c0)^j / c0^2 Z: a polynomial in v = s/c0 (|v| small where it is used)
        v = s / c0
        out = np.zeros((3, s.size), dtype=np.complex128)
        for t in range(n_terms - 1, -1, -1):
            out = (out + coefficients[:, t:t + 1]) * v
        return out

    def _damping_tail_coefficients(self, n: int, n_terms: int) -> np.ndarray:
        """Coefficients of v^1 .. v^J (v = s/c0) of the tail after n modes, shape (3, J)."""
        zeta, m, L, c0 = self.damping_ratio, self.mass, self.length, self.frequency_scale
        # f(u)/(-2 zeta u) = 1/((1 + u^2)(1 + 2 zeta u + u^2)): the product of the series
        # sum (-1)^i u^(2i) and the Chebyshev series sum U_j(-zeta) u^j
        cheb = np.empty(n_terms)
        cheb[0] = 1.0
        if n_terms > 1:
            cheb[1] = -2.0 * zeta
        for j in range(2, n_terms):
            cheb[j] = -2.0 * zeta * cheb[j - 1] - cheb[j - 2]
        alternating = np.zeros(n_terms)
        alternating[::2] = (-1.0) ** np.arange((n_terms + 1) // 2)
        c = -2.0 * zeta * np.convolve(alternating, cheb)[:n_terms]  # c_{j+1}, j = 0..J-1
        j = np.arange(1, n_terms + 1)
        orders = 2 * j[None, :] + np.array([[4], [3], [2]])  # (3, J): q of Z(q)
        Z = math.pi ** (-orders.astype(float)) * scipy.special.zeta(orders, n + 1.5)
        scale = np.array([4.0 / m, -4.0 / (m * L), 4.0 / (m * L * L)])[:, None]
        return scale * c[None, :] * Z / c0**2

    # -- finite models ------------------------------------------------------------------------
    def truncated(self, n_modes: int, *, method: str = "craig-bampton",
                  modes_per_motion: dict | None = None):
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

        modes_per_motion : dict, optional
            Three-axis model only: modes per motion (``"xy"``, ``"xz"``, ``"torsion"``,
            ``"axial"``) instead of the ``n_modes`` lowest of all (:class:`ModalBeam`).

        Returns
        -------
        ModalBeam
        """
        return ModalBeam(self, n_modes, method=method, modes_per_motion=modes_per_motion)
