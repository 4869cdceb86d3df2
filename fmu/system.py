"""The exported system: a validated continuous-time LTI model with named signals.

:class:`LinearModel` is what the rest of the package works from: float64 matrices of fixed
shapes, signal names that are legal FMI variable names, units and the initial state.  It is
built once, at the public boundary, by :func:`linear_model_from`, which raises
:class:`~fmu.errors.FMUBuildError` for anything an FMU cannot represent.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field

import control
import numpy as np
import scipy.linalg

from .checks import shorten
from .errors import FMUBuildError
from .limits import check_model_size
from .units import resolve_units

__all__ = ["LinearModel", "linear_model_from", "zoh_matrices", "is_legal_name"]

# FMI 2.0 "structured" variable names without quoted names (FMI 2.0.1, section 2.2.9):
# identifiers with optional array subscripts, joined by dots: omega, x[0], wing.tip[2,1].
# Matched whole (fullmatch): "$" would also accept a trailing newline, which then breaks
# the C string literals of model.c.
_BNAME = r"[A-Za-z_][A-Za-z0-9_]*(\[[0-9]+(,[0-9]+)*\])?"
_STRUCTURED_NAME = re.compile(rf"{_BNAME}(\.{_BNAME})*")


def is_legal_name(name: object) -> bool:
    """True if ``name`` is a legal FMI 2.0 structured variable name (no quoted parts)."""
    return isinstance(name, str) and _STRUCTURED_NAME.fullmatch(name) is not None


@dataclass(frozen=True)
class LinearModel:
    """A continuous-time LTI system ``dx/dt = A x + B u, y = C x + D u`` ready for export.

    Attributes
    ----------
    A, B, C, D : numpy.ndarray of float64
        Shapes (n, n), (n, m), (p, n), (p, m); finite.
    input_names, output_names, state_names : tuple of str
        Legal FMI structured names, all distinct.
    x0 : numpy.ndarray of float64, shape (n,)
        Initial state (start values of the state variables).
    units : dict of str to str or None
        Unit of every signal (see :mod:`fmu.units`).
    name : str
        The StateSpace's name, used in descriptions.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]
    state_names: tuple[str, ...]
    x0: np.ndarray
    units: dict[str, str | None] = field(default_factory=dict)
    name: str = ""

    @property
    def n_states(self) -> int:
        return self.A.shape[0]

    @property
    def n_inputs(self) -> int:
        return self.B.shape[1]

    @property
    def n_outputs(self) -> int:
        return self.C.shape[0]

    def statespace(self) -> control.StateSpace:
        """The model as a named python-control StateSpace."""
        return control.ss(self.A, self.B, self.C, self.D, inputs=list(self.input_names),
                          outputs=list(self.output_names), states=list(self.state_names))


def linear_model_from(system: object, *, x0: object = None,
                      units: Mapping[str, str | None] | None = None) -> LinearModel:
    """Validate a python-control system and turn it into a :class:`LinearModel`.

    Parameters
    ----------
    system : control.StateSpace
        Continuous-time (``dt == 0``), finite matrices, legal and distinct signal names.
    x0 : array_like of float, shape (n_states,), optional
        Initial state in the units of the states; zeros by default.
    units : mapping of str to str or None, optional
        Unit overrides, see :func:`fmu.units.resolve_units`.

    Returns
    -------
    LinearModel

    Raises
    ------
    FMUBuildError
        For a system that is not a StateSpace, is discrete-time, has non-finite matrices, or
        has missing, illegal or duplicate signal names.
    ValueError
        For an ``x0`` of the wrong shape or with non-finite entries, bad ``units``, or a
        system beyond the limits of :mod:`fmu.limits` (states, signals).
    TypeError
        For an ``x0`` that is not an array of numbers or ``units`` that is not a mapping.
    """
    if isinstance(system, control.TransferFunction):
        raise FMUBuildError(
            "system must be a control.StateSpace; got a TransferFunction. Convert it with "
            "control.ss(tf) and name its signals (inputs=..., outputs=..., states=...).")
    if not isinstance(system, control.StateSpace):
        raise FMUBuildError(
            "system must be a linear time-invariant control.StateSpace; got "
            f"{type(system).__name__}. Nonlinear or time-varying systems cannot be exported: "
            "linearise them first (e.g. control.linearize).")
    dt = system.dt
    if dt is not None and dt is not False and dt != 0:
        raise FMUBuildError(
            f"system must be continuous-time (dt = 0); got a discrete-time system with dt = {shorten(dt)}. "
            "Export the continuous-time model (the FMU discretises it exactly for any "
            "communication step), e.g. control.d2c if you only have the sampled one.")

    check_model_size(system.nstates, system.ninputs, system.noutputs)
    matrices = {}
    for label in ("A", "B", "C", "D"):
        value = np.array(getattr(system, label), dtype=np.float64)
        if not np.all(np.isfinite(value)):
            bad = np.argwhere(~np.isfinite(value))[0]
            raise FMUBuildError(
                f"system matrix {label} must be finite; got {value[tuple(bad)]} at index "
                f"{tuple(int(i) for i in bad)}. Fix the model before exporting.")
        matrices[label] = value
    n, m, p = system.nstates, system.ninputs, system.noutputs
    matrices["A"] = matrices["A"].reshape(n, n)
    matrices["B"] = matrices["B"].reshape(n, m)
    matrices["C"] = matrices["C"].reshape(p, n)
    matrices["D"] = matrices["D"].reshape(p, m)

    inputs = tuple(system.input_labels)
    outputs = tuple(system.output_labels)
    states = tuple(system.state_labels)
    seen: dict[str, str] = {}
    for kind, names in (("input", inputs), ("output", outputs), ("state", states)):
        for name in names:
            if not is_legal_name(name):
                raise FMUBuildError(
                    f"{kind} name {shorten(name)} is not a legal FMI variable name: expected "
                    "letters, digits and '_' starting with a letter or '_', optionally with "
                    "[index] and '.'-separated parts, and nothing else (e.g. 'theta', 'x[0]', "
                    "'wing.tip'). Rename the signal in the StateSpace (inputs=..., "
                    "outputs=..., states=...).")
            if name in seen:
                raise FMUBuildError(
                    f"signal name {shorten(name)} is used twice (as {seen[name]} and as {kind}); "
                    "FMU variable names must be unique. Rename one of them in the StateSpace.")
            seen[name] = kind

    if x0 is None:
        x0_array = np.zeros(n, dtype=np.float64)
    else:
        try:
            x0_array = np.array(x0, dtype=np.float64)
        except (TypeError, ValueError) as error:
            raise TypeError(f"x0 must be an array of {n} real numbers (in the states' units); "
                            f"got {type(x0).__name__} {shorten(x0)}") from error
        if x0_array.shape != (n,):
            raise ValueError(f"x0 must have shape ({n},) (one value per state, in the states' "
                             f"units); got shape {x0_array.shape}")
        if not np.all(np.isfinite(x0_array)):
            bad = int(np.flatnonzero(~np.isfinite(x0_array))[0])
            raise ValueError(f"x0 must be finite (in the states' units); got {x0_array[bad]} "
                             f"at index {bad}")

    return LinearModel(
        A=matrices["A"], B=matrices["B"], C=matrices["C"], D=matrices["D"],
        input_names=inputs, output_names=outputs, state_names=states, x0=x0_array,
        units=resolve_units(list(inputs + outputs + states), units), name=str(system.name))


def zoh_matrices(A: np.ndarray, B: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact zero-order-hold transition matrices of ``dx/dt = A x + B u`` for one step.

    Parameters
    ----------
    A : numpy.ndarray, shape (n, n)
    B : numpy.ndarray, shape (n, m)
    step : float, s
        Positive and finite.

    Returns
    -------
    Phi : numpy.ndarray, shape (n, n)
        ``expm(A h)``.
    Gamma : numpy.ndarray, shape (n, m)
        ``int_0^h expm(A s) ds B``.

    Notes
    -----
    With ``u`` constant over the step, ``x(t + h) = Phi x(t) + Gamma u``, and both blocks come
    from one exponential of the augmented matrix (Van Loan 1978)::

        expm([[A, B], [0, 0]] h) = [[Phi, Gamma], [0, I]]

    which needs no inverse of A (singular A, e.g. rigid-body modes, is fine). The augmented
    matrix is balanced first by an exact diagonal power-of-2 similarity
    (``scipy.linalg.matrix_balance``): a lightly damped mode ``[[0, 1], [-w^2, -2 z w]]``
    becomes nearly normal, and the exponential loses less to scaling and squaring.

    References
    ----------
    C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE Trans.
    Automatic Control 23(3), 395-404, 1978.
    """
    n, m = B.shape
    augmented = np.zeros((n + m, n + m), dtype=np.float64)
    augmented[:n, :n] = A * step
    augmented[:n, n:] = B * step
    balanced, scaling = scipy.linalg.matrix_balance(augmented, permute=False, separate=True)
    factors = scaling[0]
    # expm(M) = D expm(D^-1 M D) D^-1 with D = diag(factors), powers of 2 (exact)
    exponential = scipy.linalg.expm(balanced) * factors[:, None] / factors[None, :]
    return exponential[:n, :n].copy(), exponential[:n, n:].copy()
