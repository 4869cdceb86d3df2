r"""The paper's dynamic-equivalence criterion and equivalent-chain fits.

Two appendage models are dynamically equivalent at their attachment end when they have

* (3) equal frozen mass m, moment of inertia J about the centre of mass, and length L, and
* (4)/(5) equal transfer matrices W(s): in the two-mode form
  ``W_r = k_r (s**2 + n_r1**2)(s**2 + n_r2**2) / (s**2 (s**2 + w1**2)(s**2 + w2**2))``
  equal gains k_r, zeros n_r1, n_r2 (r = 1..4, W2 = W3) and poles w1, w2 [1]_.

:func:`criterion` tabulates these quantities for a reference and a candidate model and their
relative differences, plus a frequency-domain error of each W_r over a band. :func:`fit_chain`
builds a :class:`~appendages.chain.HingedChain` equivalent to a beam: the paper's fit
(``match="frequencies"``) or flexsat's (``match="poles-and-zeros"``), which also redistributes the
mass among the bodies (keeping m, J, L and the centre of mass) so that the zeros of every W_r come
close to those of the exact distributed beam.

Any appendage
-------------
Both work from the W-matrix interface, so they take any appendage that gives W: a uniform
:class:`~appendages.beam.Beam`, a beam with a tip body, a stepped beam, a
:class:`~appendages.modal_data.ModalAppendage` from finite-element data, a truncation or a
chain. The poles-and-zeros fit of an appendage other than a uniform beam
(:func:`fit_targets`) keeps its mass m, centre of mass c (its first moment) and central inertia
J exactly (tip body included) and fits the same 4 (n - 1) log-frequency targets, the
appendage's own first natural frequencies and zeros of W1, W2, W4, by the same schedule
(:func:`appendages.fitting.fit_poles_and_zeros_to`) in units of its length, its mass and a
frequency unit that puts its first pole where the uniform beam's is; the result is memoised by
those dimensionless targets. The paper's frequency fit (frozen pieces of a uniform rod) stays
the uniform beam's.

Frequency-domain error
----------------------
On the imaginary axis the error of W_r is infinite at every pole or zero that the two models do
not share, so it is measured on the ray ``s = omega (zeta_e + i)`` slightly to the right of the
axis (``zeta_e``, the *evaluation damping*, default 0.02): an undamped mode term
``1/(s**2 + w**2)`` evaluated there equals ``1/(w**2 - (1 - zeta_e**2) omega**2 + 2 i zeta_e
omega**2)``, the response of that mode with damping ratio about zeta_e. The error is the complex
logarithm of the ratio,

    e_r(omega) = | ln( W_r^cand(s) / W_r^ref(s) ) |,    s = omega (zeta_e + i),

which combines the gain error (its real part, ln of the magnitude ratio: 0.1 ~ 10 %, 1.15 ~ 10 dB)
and the phase error (its imaginary part, rad). :class:`EquivalenceResult` holds its maximum and its
root mean square over log-spaced omega in the band (by default from w1/10 of the reference up to
1.5 w2, or up to just below the reference's third pole or zero, see :func:`criterion`).

References
----------
.. [1] P. A. Belonozhko, P. P. Belonozhko, A. A. Fokov et al., "On the equivalence of mechanical
   design schemes with distributed and lumped parameters for spatially developed peripheral
   elements of spacecraft", Institute of Technical Mechanics, NAS of Ukraine, 2009
   (conditions (3)-(5), the worked example and its table).
.. [2] R. D. Blevins, "Formulas for Natural Frequency and Mode Shape", Van Nostrand, 1979,
   table 8-1 (free-free, pinned-free and sliding-free beam frequencies: the exact poles and zeros).
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import warnings
from collections.abc import Sequence

import numpy as np
import scipy.linalg

from . import fitting, limits
from .beam import Beam, characteristic_roots
from .chain import HingedChain
from .fitting import FitWarning
from .checks import as_frequency_array
from .errors import describe
from .interface import FiniteAppendage, equilibrate

__all__ = [
    "ANY_APPENDAGE_BUDGET",
    "EquivalenceResult",
    "FitWarning",
    "ModelQuantities",
    "criterion",
    "damping_frequency_of",
    "damping_ratio_of",
    "fit_chain",
    "fit_targets",
    "is_uniform_beam",
    "spectral_errors",
]

MATCHES = ("poles-and-zeros", "frequencies")

#: The poles-and-zeros fit of an appendage other than a uniform beam spends this many times the
#: uniform beam's budget (:func:`appendages.fitting.evaluation_budget`): its RFEM start lies
#: farther from the fit (a stepped boom with a tip body: start cost 150, against 6.2 for the
#: uniform beam at 4 bodies), and its first path needed 181 to 540 evaluations where the
#: uniform budget is 180 (benchmarks/results/modal_appendage.md); not memoised across
#: appendages, so each fit pays it.
ANY_APPENDAGE_BUDGET = 3

# (label, unit) of the rows of the paper's table, in the paper's order.
_ROWS = (
    ("m", "kg"),
    ("J", "kg*m^2"),
    ("L", "m"),
    ("k1", "m/(N*s^2)"),
    ("k2 = k3", "1/(N*s^2)"),
    ("k4", "1/(m*N*s^2)"),
    ("n11", "rad/s"),
    ("n21 = n31", "rad/s"),
    ("n41", "rad/s"),
    ("n12", "rad/s"),
    ("n22 = n32", "rad/s"),
    ("n42", "rad/s"),
    ("w1", "rad/s"),
    ("w2", "rad/s"),
)


# ---------------------------------------------------------------------------------------------
# quantities of one model
# ---------------------------------------------------------------------------------------------
def _is_distributed(model) -> bool:
    return (not isinstance(model, FiniteAppendage)) and hasattr(model, "natural_frequencies") \
        and hasattr(model, "zeros") and hasattr(model, "W")


def _check_model(name: str, model) -> None:
    """TypeError unless ``model`` is a finite appendage or a distributed beam."""
    is_model = isinstance(model, FiniteAppendage) or _is_distributed(model)
    if is_model and all(hasattr(model, a) for a in ("mass", "inertia", "length")):
        return
    raise TypeError(f"{name} must be an appendage model (Beam, ModalBeam, HingedChain); "
                    f"got {type(model).__name__}")


def _first(values: np.ndarray, n: int) -> tuple:
    """The first n entries as floats, None where the model has fewer."""
    return tuple(float(values[k]) if k < values.size else None for k in range(n))


def _model_frequencies(model, what, n: int) -> np.ndarray:
    """First (up to) n poles (what = 0) or zeros of W_what [rad/s] of any appendage model."""
    if _is_distributed(model):
        values = model.natural_frequencies(n) if what == 0 else model.zeros(what, n)
    else:
        values = model.poles() if what == 0 else model.zeros(what)
    return np.asarray(values, dtype=np.float64)[:n]


@dataclasses.dataclass(frozen=True)
class ModelQuantities:
    """The paper's quantities (3) and (5) of one appendage model.

    Attributes
    ----------
    name : str
    mass : float, kg
    inertia : float, kg*m^2
        About the centre of mass, undeformed.
    length : float, m
    gains : tuple of 4 float, or None
        k_1..k_4 = lim s**2 W_r(s) [m/(N s^2), 1/(N s^2), 1/(N s^2), 1/(m N s^2)]; None for a
        model without finite gains (the distributed beam, a chain with a spring at the mount).
    zeros : dict
        ``zeros[r] = (n_r1, n_r2)`` [rad/s] for r = 1..4; None where the model has fewer zeros.
    poles : tuple of 2 float
        ``(w1, w2)`` [rad/s]; None where the model has fewer modes.
    """

    name: str
    mass: float
    inertia: float
    length: float
    gains: tuple | None
    zeros: dict
    poles: tuple

    @classmethod
    def of(cls, model, name: str | None = None) -> "ModelQuantities":
        """Collect the quantities of ``model`` (a FiniteAppendage or a distributed Beam)."""
        _check_model("model", model)
        gains = None
        if not _is_distributed(model):
            try:
                gains = tuple(float(g) for g in model.gains())
            except ValueError:
                gains = None
        zeros = {r: _first(_model_frequencies(model, r, 2), 2) for r in (1, 2, 3, 4)}
        return cls(
            name=name or type(model).__name__,
            mass=float(model.mass),
            inertia=float(model.inertia),
            length=float(model.length),
            gains=gains,
            zeros=zeros,
            poles=_first(_model_frequencies(model, 0, 2), 2),
        )

    def values(self) -> tuple:
        """The 14 values in the order of the paper's table rows (None: not applicable)."""
        g = self.gains if self.gains is not None else (None,) * 4
        z = self.zeros
        return (self.mass, self.inertia, self.length, g[0], g[1], g[3],
                z[1][0], z[2][0], z[4][0], z[1][1], z[2][1], z[4][1],
                self.poles[0], self.poles[1])


def _relative(candidate, reference):
    if candidate is None or reference is None or reference == 0.0:
        return None
    return (candidate - reference) / abs(reference)


def _fmt(value, digits: int = 5) -> str:
    if value is None:
        return "n/a"
    return f"{value:.{digits}g}"


@dataclasses.dataclass(frozen=True)
class EquivalenceResult:
    """Outcome of :func:`criterion`: both models' quantities, differences and band errors.

    Attributes
    ----------
    reference, candidate : ModelQuantities
    relative_differences : dict
        Row label (``"m"``, ``"k2 = k3"``, ``"n11"``, ``"w1"``...) -> ``(cand - ref)/|ref|``
        [-], None where either value is not applicable.
    band : tuple of float
        ``(omega_min, omega_max)`` [rad/s] of the frequency-domain comparison.
    evaluation_damping : float
        zeta_e of the ray ``s = omega (zeta_e + i)`` on which W is compared [-].
    max_log_error, rms_log_error : ndarray, shape (4,)
        Maximum and root mean square over the band of ``|ln(W_r^cand/W_r^ref)|`` for
        r = 1..4 [-] (module docstring).
    exact : ModelQuantities or None
        The exact (distributed) model's quantities, when :func:`criterion` was given one.
    exact_differences : dict or None
        ``{"reference": {label: rel}, "candidate": {label: rel}}``: each model's relative
        differences from the exact model.
    exact_max_log_error : ndarray, shape (2, 4), or None
        Band error (maximum) of the reference (row 0) and the candidate (row 1) against the
        exact model.
    """

    reference: ModelQuantities
    candidate: ModelQuantities
    relative_differences: dict
    band: tuple
    evaluation_damping: float
    max_log_error: np.ndarray
    rms_log_error: np.ndarray
    exact: ModelQuantities | None = None
    exact_differences: dict | None = None
    exact_max_log_error: np.ndarray | None = None

    def rows(self) -> list:
        """``(label, unit, reference, candidate, relative difference)`` per table row."""
        ref, cand = self.reference.values(), self.candidate.values()
        return [(label, unit, r, c, self.relative_differences[label])
                for (label, unit), r, c in zip(_ROWS, ref, cand)]

    def _table(self, digits: int) -> tuple[list, list]:
        """Header and rows of strings (shared by the text and Markdown forms)."""
        head = ["quantity", self.reference.name, self.candidate.name, "rel. diff."]
        if self.exact is not None:
            head += [self.exact.name, f"{self.reference.name} vs exact",
                     f"{self.candidate.name} vs exact"]
        body = []
        exact_values = self.exact.values() if self.exact is not None else None
        for k, (label, unit, r, c, d) in enumerate(self.rows()):
            row = [f"{label} [{unit}]", _fmt(r, digits), _fmt(c, digits), _diff(d)]
            if exact_values is not None:
                row += [_fmt(exact_values[k], digits),
                        _diff(self.exact_differences["reference"][label]),
                        _diff(self.exact_differences["candidate"][label])]
            body.append(row)
        return head, body

    def _band_lines(self) -> list:
        return [f"Frequency-domain error |ln(W_r^cand / W_r^ref)| on s = omega "
                f"({self.evaluation_damping:g} + i), omega in [{self.band[0]:.4g}, "
                f"{self.band[1]:.4g}] rad/s (log-spaced):"]

    def to_markdown(self, digits: int = 5) -> str:
        """The paper's table (plus m, J, L and the band errors) as a Markdown string."""
        head, body = self._table(digits)
        lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
        lines += ["| " + " | ".join(row) + " |" for row in body]
        lines += [""] + self._band_lines()
        lines += ["", "| | W1 | W2 | W3 | W4 |", "|---|---|---|---|---|"]
        lines.append("| max | " + " | ".join(f"{e:.3g}" for e in self.max_log_error) + " |")
        lines.append("| rms | " + " | ".join(f"{e:.3g}" for e in self.rms_log_error) + " |")
        if self.exact_max_log_error is not None:
            for name, errors in zip((self.reference.name, self.candidate.name),
                                    self.exact_max_log_error):
                lines.append(f"| max, {name} vs exact | "
                             + " | ".join(f"{e:.3g}" for e in errors) + " |")
        return "\n".join(lines)

    def __str__(self) -> str:
        head, body = self._table(5)
        widths = [max(len(row[k]) for row in [head] + body) for k in range(len(head))]
        def line(row):
            return "  ".join(cell.ljust(w) if k == 0 else cell.rjust(w)
                             for k, (cell, w) in enumerate(zip(row, widths)))
        lines = [line(head), "-" * len(line(head))] + [line(row) for row in body]
        lines += [""] + self._band_lines()
        lines.append("  max: " + ", ".join(f"W{r} {e:.3g}" for r, e in
                                            zip((1, 2, 3, 4), self.max_log_error)))
        if self.exact_max_log_error is not None:
            for name, errors in zip((self.reference.name, self.candidate.name),
                                    self.exact_max_log_error):
                lines.append(f"  max, {name} vs exact: " + ", ".join(
                    f"W{r} {e:.3g}" for r, e in zip((1, 2, 3, 4), errors)))
        return "\n".join(lines)

    def to_dict(self) -> dict:
        """JSON-serialisable form."""
        def quantities(q: ModelQuantities) -> dict:
            return {"name": q.name, "values": dict(zip([r[0] for r in _ROWS], q.values()))}
        out = {
            "reference": quantities(self.reference),
            "candidate": quantities(self.candidate),
            "relative_differences": dict(self.relative_differences),
            "band": list(self.band),
            "evaluation_damping": self.evaluation_damping,
            "max_log_error": self.max_log_error.tolist(),
            "rms_log_error": self.rms_log_error.tolist(),
        }
        if self.exact is not None:
            out["exact"] = quantities(self.exact)
            out["exact_differences"] = {k: dict(v) for k, v in self.exact_differences.items()}
            out["exact_max_log_error"] = self.exact_max_log_error.tolist()
        return out


def _diff(value) -> str:
    return "n/a" if value is None else f"{value:+.2e}"


def _check_real(name: str, value, unit: str, *, low=None, high=None) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number [{unit}]; got {type(value).__name__} "
                        f"{value!r}")
    value = float(value)
    if not math.isfinite(value) or (low is not None and value <= low) or \
            (high is not None and value >= high):
        expected = f"in ({low}, {high})" if high is not None else f"greater than {low}"
        raise ValueError(f"{name} must be finite and {expected} [{unit}]; got {describe(value)}")
    return value


def _default_band(reference, quantities: ModelQuantities) -> tuple:
    """``[w1/10, upper]`` [rad/s]: upper = 1.5 w2, or less so as to stop before the reference's
    next pole or zero beyond the paper's quantities (which no two-mode model can match)."""
    w = [p for p in quantities.poles if p is not None]
    if len(w) < 2:
        raise ValueError("band must be given [rad/s] when the reference has fewer than two "
                         "natural frequencies")
    covered = max([w[1]] + [z for r in (1, 2, 4) for z in quantities.zeros[r] if z is not None])
    upper = 1.5 * w[1]
    third = [v[2] for v in (_model_frequencies(reference, what, 3) for what in (0, 1, 2, 4))
             if v.size > 2]
    if third and min(third) > covered:
        upper = min(upper, math.sqrt(covered * min(third)))
    return (w[0] / 10.0, upper)


def _log_errors(W_cand: np.ndarray, W_ref: np.ndarray) -> np.ndarray:
    """|ln(W_cand/W_ref)| per entry r = 1..4, shape (4, n_points)."""
    entries = [(0, 0), (0, 1), (1, 0), (1, 1)]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        err = np.stack([np.abs(np.log(W_cand[:, i, j] / W_ref[:, i, j])) for i, j in entries])
    if not np.all(np.isfinite(err)):
        raise FloatingPointError("W of a model vanished or overflowed on the comparison ray; "
                                 "choose another band [rad/s] or evaluation_damping")
    return err


def criterion(reference, candidate, *, exact=None, band: Sequence[float] | None = None,
              n_points: int = 2000, evaluation_damping: float = 0.02,
              names: Sequence[str] | None = None) -> EquivalenceResult:
    """The paper's equivalence criterion: quantities (3), (5) of two models and their differences.

    Parameters
    ----------
    reference : Beam or FiniteAppendage
        The model to compare against: the exact distributed beam (no finite gains: its k_r
        rows show n/a) or a finite model such as ``beam.truncated(2, method="free-free")``.
    candidate : Beam or FiniteAppendage
        Typically a :class:`~appendages.chain.HingedChain`.
    exact : Beam, optional
        A third, exact model (the distributed beam) against which both are also measured
        (extra columns and band errors), e.g. to see how far the paper's 2-mode reference and
        its chain are from the real beam.
    band : (float, float), rad/s, optional
        Frequency band of the W_r comparison. Default ``[w1/10, w_top]`` of the reference, with
        ``w_top = 1.5 w2`` or, if the reference has a third pole or zero f3 below that, the
        geometric mean of f3 and the largest of its w2, n_r2 (so the band holds the paper's
        quantities and no feature that a two-mode model lacks: for the exact beam, whose third
        W4 zero is 1.21 w2, w_top = 1.10 w2).
    n_points : int
        Number of log-spaced frequencies in the band (>= 10). The error peaks have a relative
        width of about ``evaluation_damping``; the default resolves them.
    evaluation_damping : float
        zeta_e in (0, 1) of the comparison ray ``s = omega (zeta_e + i)`` (module docstring).
    names : (str, str), optional
        Column names; default the class names.

    Returns
    -------
    EquivalenceResult

    References
    ----------
    .. [1] Belonozhko et al. 2009, conditions (3)-(5) (see :mod:`appendages.equivalence`).
    """
    _check_model("reference", reference)
    _check_model("candidate", candidate)
    if exact is not None:
        _check_model("exact", exact)
    if isinstance(n_points, (bool, np.bool_)) or not isinstance(n_points, (int, np.integer)):
        raise TypeError(f"n_points must be an integer; got {type(n_points).__name__}")
    if n_points < 10:
        raise ValueError(f"n_points must be at least 10; got {n_points}")
    limits.check("n_points", int(n_points), "points", "points at once")
    zeta = _check_real("evaluation_damping", evaluation_damping, "-", low=0.0, high=1.0)
    if names is None:
        names = (type(reference).__name__, type(candidate).__name__)
    elif (isinstance(names, str) or not isinstance(names, Sequence) or len(names) != 2
          or not all(isinstance(n, str) for n in names)):
        raise ValueError(f"names must be two strings (reference, candidate); got {describe(names)}")
    ref_q = ModelQuantities.of(reference, names[0])
    cand_q = ModelQuantities.of(candidate, names[1])
    differences = {label: _relative(c, r) for (label, _), r, c in
                   zip(_ROWS, ref_q.values(), cand_q.values())}
    if band is None:
        band = _default_band(reference, ref_q)
    try:
        band = np.asarray(band, dtype=np.float64) if not isinstance(band, (str, bytes)) else None
    except (TypeError, ValueError):  # complex numbers, objects: not a band
        band = None
    if band is None or band.shape != (2,) or not np.all(np.isfinite(band)) or \
            not 0.0 < band[0] < band[1]:
        raise ValueError(f"band must be (omega_min, omega_max) with 0 < omega_min < omega_max "
                         f"[rad/s]; got {describe(band)}")
    omega = np.geomspace(band[0], band[1], int(n_points))
    s = as_frequency_array(omega * (zeta + 1j))
    W_ref, W_cand = reference.W(s), candidate.W(s)
    err = _log_errors(W_cand, W_ref)
    extra = {}
    if exact is not None:
        exact_q = ModelQuantities.of(exact, "exact")
        W_exact = exact.W(s)
        extra = dict(
            exact=exact_q,
            exact_differences={
                key: {label: _relative(v, e) for (label, _), v, e in
                      zip(_ROWS, q.values(), exact_q.values())}
                for key, q in (("reference", ref_q), ("candidate", cand_q))},
            exact_max_log_error=np.stack([_log_errors(W_ref, W_exact).max(axis=1),
                                          _log_errors(W_cand, W_exact).max(axis=1)]),
        )
    return EquivalenceResult(
        reference=ref_q, candidate=cand_q, relative_differences=differences,
        band=(float(band[0]), float(band[1])), evaluation_damping=zeta,
        max_log_error=err.max(axis=1), rms_log_error=np.sqrt(np.mean(err**2, axis=1)),
        **extra,
    )


def spectral_errors(reference, candidate, n: int | None = None) -> dict:
    """Relative errors of the candidate's first poles and zeros against the reference's.

    Parameters
    ----------
    reference : Beam or FiniteAppendage
        E.g. the exact distributed beam.
    candidate : FiniteAppendage or Beam
    n : int, optional
        How many of each to compare; default: as many as the candidate has natural
        frequencies (a chain of n bodies: n - 1).

    Returns
    -------
    dict
        ``{"poles": e, "W1": e, "W2": e, "W4": e}`` with ``e = cand/ref - 1`` [-], arrays of
        length n (W3 = W2). A missing candidate value raises ValueError.
    """
    _check_model("reference", reference)
    _check_model("candidate", candidate)
    if n is None:
        n = _model_frequencies(candidate, 0, 10**6).size
    if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n must be a positive integer; got {describe(n)}")
    out = {}
    for key, what in (("poles", 0), ("W1", 1), ("W2", 2), ("W4", 4)):
        ref = _model_frequencies(reference, what, n)
        cand = _model_frequencies(candidate, what, n)
        if ref.size < n or cand.size < n:
            raise ValueError(f"{key}: a model has fewer than n = {n} values "
                             f"(reference {ref.size}, candidate {cand.size})")
        out[key] = cand / ref - 1.0
    return out


# ---------------------------------------------------------------------------------------------
# fits
# ---------------------------------------------------------------------------------------------
def is_uniform_beam(model) -> bool:
    """A uniform beam (no tip body, or one of zero mass; one section): the fits'
    scale-invariant, memoised path."""
    tip = getattr(model, "tip", None)
    return isinstance(model, Beam) and (tip is None or bool(getattr(tip, "is_null", False)))


def _beam_data(beam):
    try:
        L, EJ, rho = float(beam.length), float(beam.bending_stiffness), float(beam.linear_density)
    except AttributeError as exc:
        raise TypeError("beam must be a uniform Beam (length [m], bending_stiffness [N*m^2], "
                        f"linear_density [kg/m]); got {type(beam).__name__}") from exc
    return L, EJ, rho


def damping_ratio_of(appendage) -> float:
    """The damping ratio [-] a chain fitted to ``appendage`` gives its first mode.

    ``damping_ratio`` (beams: one ratio for every mode) or the first of ``damping_ratios``
    (modal data: the first cantilever mode's); 0 when the appendage has neither.
    """
    zeta = getattr(appendage, "damping_ratio", None)
    if zeta is None:
        ratios = getattr(appendage, "damping_ratios", None)
        zeta = ratios[0] if ratios is not None and len(ratios) else 0.0
    return float(zeta)


def damping_frequency_of(appendage) -> float:
    """The frequency [rad/s] at which a fitted chain's stiffness-proportional hinge damping
    (``2 zeta c_h / w``) gives the appendage's damping ratio.

    Its first cantilever (fixed-root) frequency, the mode whose ratio the damping ratio is
    (:func:`damping_ratio_of`; as the beams' chains match it), or its first free-free one for
    an appendage with ``damping_convention = "free-free"``.
    """
    if getattr(appendage, "damping_convention", "cantilever") == "free-free":
        return float(_model_frequencies(appendage, 0, 1)[0])
    if hasattr(appendage, "cantilever_frequencies"):
        return float(appendage.cantilever_frequencies(1)[0])
    frequencies = getattr(appendage, "frequencies", None)  # modal data: the cantilever modes
    if frequencies is not None:
        return float(np.min(frequencies))
    rm = appendage.root_model()
    r = rm.n_root
    Kii, Mii = rm.stiffness[r:, r:], rm.mass[r:, r:]
    d = equilibrate(Kii, Mii)
    lam = scipy.linalg.eigvalsh(Kii * np.outer(d, d), Mii * np.outer(d, d))
    return float(np.sqrt(np.min(lam)))


def fit_targets(appendage, n_bodies: int):
    """What the poles-and-zeros fit needs of any appendage that gives W (module docstring).

    Returns
    -------
    dict
        ``targets`` (4, n - 1): the first n - 1 natural frequencies and zeros of W1, W2, W4
        [rad/s]; ``mass`` [kg], ``length`` [m], ``center`` (centre of mass from the root over
        the length), ``inertia`` (central inertia over m L**2) [-].

    Raises
    ------
    ValueError
        Fewer than n - 1 poles or zeros of some kind (a modal appendage with too few modes), or
        rigid properties that no chain of the appendage's length can hold (a centre of mass
        outside it, an inertia above m c (L - c)).
    """
    _check_model("appendage", appendage)
    n = int(n_bodies)
    rows = []
    for what, label in ((0, "natural frequencies"), (1, "zeros of W1"), (2, "zeros of W2"),
                        (4, "zeros of W4")):
        values = _model_frequencies(appendage, what, n - 1)
        if values.size < n - 1:
            raise ValueError(
                f"fit_chain(n_bodies={n}) needs the appendage's first {n - 1} {label}; "
                f"{describe(appendage)} has {values.size}: fit fewer bodies (or give more "
                "modes)")
        rows.append(values)
    m, L = float(appendage.mass), float(appendage.length)
    center = getattr(appendage, "center_of_mass", None)
    center = 0.5 * L if center is None else float(center)
    c = center / L
    J = float(appendage.inertia) / (m * L**2)
    if not 0.0 < c < 1.0:
        raise ValueError(f"the appendage's centre of mass lies at {center:.6g} m from the root, "
                         f"outside (0, length = {L:.6g} m): no chain of that length holds it")
    if not 0.0 < J < c * (1.0 - c):
        raise ValueError(
            f"the appendage's central inertia {appendage.inertia:.6g} kg*m^2 exceeds m c (L - c) "
            f"= {m * c * (1.0 - c) * L**2:.6g} kg*m^2, the most a chain of length L = {L:.6g} m "
            "with its centre of mass at c can have: is length the appendage's extent [m]?")
    return {"targets": np.vstack(rows), "mass": m, "length": L, "center": c, "inertia": J}


def fit_chain(beam, n_bodies: int = 3, *, match: str = "poles-and-zeros",
              frequencies: Sequence[float] | None = None, pole_weight: float = 10.0,
              max_nfev: int | None = None) -> HingedChain:
    """A hinged chain dynamically equivalent to a beam or any other appendage that gives W.

    Parameters
    ----------
    beam : Beam or any appendage model
        The uniform beam (``length``, ``bending_stiffness``, ``linear_density``, and
        optionally ``damping_ratio``), or any appendage with W, its poles and zeros, ``mass``,
        ``length``, ``inertia`` and ``center_of_mass`` (a beam with a tip body, a stepped beam,
        a :class:`~appendages.modal_data.ModalAppendage`...): flexsat's fit only (module
        docstring, "Any appendage"), with hinge dampings ``2 zeta c_h / w`` for the damping
        ratio of the appendage's first mode (:func:`damping_ratio_of`) at its first cantilever
        frequency w (:func:`damping_frequency_of`).
    n_bodies : int
        Number of rigid bodies (>= 2); the chain has n_bodies - 1 hinges and
        n_bodies + 1 degrees of freedom.
    match : {"poles-and-zeros", "frequencies"}
        ``"frequencies"``: the paper's fit. A symmetric chain of frozen pieces of the beam
        (``m_i = rho l_i``, ``J_i = m_i l_i**2/12``, so m, J and L are the beam's) whose
        symmetric body lengths and hinge stiffnesses (ceil(n/2) - 1 + ceil((n-1)/2) = n - 1
        unknowns) are solved so that its n - 1 natural frequencies equal the beam's first n - 1.
        For n_bodies = 3 the unknowns are the paper's k_L (middle rod ``k_L L``) and c.
        ``"poles-and-zeros"`` (default): flexsat's fit. Any body lengths, masses, centre-of-mass
        offsets, inertias and hinge stiffnesses (5 n - 5 parameters) with m, J, L and the
        centre of mass (L/2) kept exactly equal to the beam's; least squares in log-frequency
        of the first n - 1 natural frequencies and the first n - 1 zeros of W1, W2 (= W3) and
        W4 against the *exact* distributed beam (4 n - 4 targets, the poles weighted by
        ``pole_weight``), from the RFEM chain and other uniform chains, within bounds that
        keep the chain physical (:func:`appendages.fitting.fit_poles_and_zeros`: exact
        Jacobian, a fixed budget of 15 n (n - 1) residual evaluations, so the cost grows with
        n).
    frequencies : sequence of float, rad/s, optional
        ``match="frequencies"`` only: the n - 1 target frequencies instead of the beam's exact
        ones (e.g. the paper's printed 2.8744, 7.9231, which give its k_L = 0.26989 and
        c = 37.134 N*m; the exact Blevins frequencies 2.87446, 7.92356 give 0.26988, 37.137).
    pole_weight : float
        ``match="poles-and-zeros"`` only: weight of the natural frequencies relative to the
        zeros in the least squares (> 0). The default 10 matches the poles to ~1e-4 while the
        zeros lose almost nothing (three bodies: poles 6e-5, zeros 1.7 %; with weight 1:
        0.56 % and 1.6 %).
    max_nfev : int, optional
        ``match="poles-and-zeros"`` only: budget of residual evaluations of the whole fit
        (default :func:`appendages.fitting.evaluation_budget`, 15 n (n - 1): 90 for 3 bodies,
        1350 for 10).

    Returns
    -------
    HingedChain
        With hinge dampings ``2 zeta c_h / w_1`` (damping ratio zeta at the first mode, as
        :meth:`HingedChain.rfem <appendages.chain.HingedChain.rfem>`) if the beam has a modal
        damping ratio zeta > 0.

    Raises
    ------
    ConvergenceError
        If the frequencies cannot be matched, or the poles-and-zeros fit ends no better than its
        start or outside the physical layout.

    Warns
    -----
    FitWarning
        If the evaluation budget of the poles-and-zeros fit cuts its first path (from the RFEM
        chain) short (the best chain found is returned).

    Notes
    -----
    The fit of a uniform beam depends on its size and material only through units
    (:mod:`appendages.fitting`): it is solved once per ``(n_bodies, match, pole_weight,
    max_nfev)`` for L = EJ = rho = 1, memoised in the process, and scaled to each beam; a
    second fit with the same options, of any beam, costs a scaling (about 0.1 ms).
    :func:`appendages.fitting.clear_memo` forgets the memo.

    References
    ----------
    .. [1] Belonozhko et al. 2009 (the frequency fit; the suggestion to redistribute mass).
    .. [2] Blevins 1979, table 8-1 (exact targets).
    """
    if isinstance(n_bodies, (bool, np.bool_)) or not isinstance(n_bodies, (int, np.integer)):
        raise TypeError(f"n_bodies must be an integer; got {type(n_bodies).__name__} {describe(n_bodies)}")
    if n_bodies < 2:
        raise ValueError(f"n_bodies must be at least 2 (a chain needs a hinge); got {n_bodies}")
    if not isinstance(match, str) or match not in MATCHES:
        raise ValueError(f"match must be one of {MATCHES}; got {describe(match)}")
    if not is_uniform_beam(beam):
        _check_model("beam", beam)
        return _fit_any(beam, int(n_bodies), match, frequencies, pole_weight, max_nfev)
    L, EJ, rho = _beam_data(beam)
    n = int(n_bodies)
    if match == "frequencies":
        limits.check("n_bodies", n, "bodies", "bodies per chain")
        targets = None
        if frequencies is not None:
            targets = np.asarray(frequencies, dtype=np.float64)
            if targets.shape != (n - 1,) or not np.all(np.isfinite(targets)) or \
                    np.any(targets <= 0) or np.any(np.diff(targets) <= 0):
                raise ValueError(f"frequencies must be {n - 1} increasing positive values "
                                 f"[rad/s] (one per hinge); got {describe(frequencies)}")
            targets = targets / math.sqrt(EJ / (rho * L**4))  # in the beam's frequency unit
        fit = fitting.fit_frequencies(n, targets)
    else:
        limits.check("n_bodies", n, "fit_bodies", "bodies of a chain fitted to poles and zeros")
        if frequencies is not None:
            raise ValueError("frequencies [rad/s] applies to match='frequencies' only")
        pole_weight = _check_real("pole_weight", pole_weight, "-", low=0.0)
        if max_nfev is not None and (isinstance(max_nfev, bool) or not isinstance(max_nfev, int)
                                     or max_nfev < 1):
            raise ValueError(f"max_nfev must be a positive integer; got {describe(max_nfev)}")
        fit = fitting.fit_poles_and_zeros(n, pole_weight=pole_weight, max_nfev=max_nfev)
        if fit.stopped:
            warnings.warn(
                f"fit_chain(match='poles-and-zeros', n_bodies={n}) stopped at max_nfev="
                f"{max_nfev if max_nfev is not None else fit.nfev} evaluations before its "
                f"first path (from the RFEM chain) met its tolerances; returning the best chain "
                f"found (cost {fit.cost:.3e}, RFEM start {fit.start_cost:.3e})", FitWarning,
                stacklevel=2)
    try:
        return fit.to_chain(beam)
    except ValueError as exc:
        # the fitted chain, scaled to the beam, left the documented ranges: the beam's and
        # n_bodies' fault, said so
        raise ValueError(f"fit_chain(beam, n_bodies={n}, match={match!r}) of {describe(beam)}: "
                         f"a chain built from these arguments is outside the documented "
                         f"ranges: {exc}") from None


def _check_fit_options(n: int, pole_weight, max_nfev) -> float:
    limits.check("n_bodies", n, "fit_bodies", "bodies of a chain fitted to poles and zeros")
    pole_weight = _check_real("pole_weight", pole_weight, "-", low=0.0)
    if max_nfev is not None and (isinstance(max_nfev, bool) or not isinstance(max_nfev, int)
                                 or max_nfev < 1):
        raise ValueError(f"max_nfev must be a positive integer; got {describe(max_nfev)}")
    return pole_weight


def _fit_any(appendage, n: int, match: str, frequencies, pole_weight, max_nfev) -> HingedChain:
    """flexsat's fit of any appendage that gives W (:func:`fit_chain`, "Any appendage")."""
    if match == "frequencies":
        raise ValueError(
            "match='frequencies' (the paper's fit: a symmetric chain of frozen pieces of a "
            f"uniform rod) needs a uniform Beam; got {describe(appendage)}: use "
            "match='poles-and-zeros'")
    if frequencies is not None:
        raise ValueError("frequencies [rad/s] applies to match='frequencies' only")
    pole_weight = _check_fit_options(n, pole_weight, max_nfev)
    data = fit_targets(appendage, n)
    # the frequency unit in which the appendage's first pole is the uniform beam's (the starts
    # are uniform chains): a unit of the problem, not an approximation
    unit = float(data["targets"][0, 0]) / float(characteristic_roots("free-free", 1)[0]) ** 2
    budget = max_nfev if max_nfev is not None else \
        ANY_APPENDAGE_BUDGET * fitting.evaluation_budget(n)
    fit = fitting.fit_poles_and_zeros_to(data["targets"] / unit, n, inertia=data["inertia"],
                                         center=data["center"], pole_weight=pole_weight,
                                         max_nfev=budget)
    if fit.stopped:
        warnings.warn(
            f"fit_chain(match='poles-and-zeros', n_bodies={n}) stopped at max_nfev={budget} "
            f"evaluations before its first path met its tolerances; returning the best chain "
            f"found (cost {fit.cost:.3e}, RFEM start {fit.start_cost:.3e})", FitWarning,
            stacklevel=3)
    try:
        return fit.scaled(data["length"], data["mass"], unit,
                          damping_ratio=damping_ratio_of(appendage),
                          first_frequency=damping_frequency_of(appendage))
    except ValueError as exc:
        raise ValueError(f"fit_chain(n_bodies={n}) of {describe(appendage)}: the fitted chain is "
                         f"outside the documented ranges: {exc}") from None
