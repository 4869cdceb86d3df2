"""The exported system: a validated LTI model with named signals.

:class:`LinearModel` is what the rest of the package works from: float64 matrices of fixed
shapes, signal names that are legal FMI variable names, units, the initial state, the
states' nominal magnitudes and, for a discrete-time (sampled) system, its sample period.
It is built once, at the public boundary, by :func:`linear_model_from`, which raises
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

__all__ = ["LinearModel", "linear_model_from", "zoh_matrices", "is_legal_name",
           "state_nominals", "NOMINAL_POINTS"]

#: Points of the default experiment at which :func:`state_nominals` looks at the states.
NOMINAL_POINTS = 200

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
    """An LTI system ready for export: continuous time ``dx/dt = A x + B u, y = C x + D u``
    or, with ``sample_period`` T > 0, discrete time ``x[k+1] = A x[k] + B u[k], y[k] = C
    x[k] + D u[k]`` sampled at ``t_k = t_0 + k T``.

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
    sample_period : float, s
        0.0 for continuous time, else the sample period T.
    nominals : numpy.ndarray of float64, shape (n,), optional
        Positive nominal magnitude of each state, in its unit (None until
        :func:`state_nominals` or the user fills it in).
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
    sample_period: float = 0.0
    nominals: np.ndarray | None = None

    @property
    def discrete(self) -> bool:
        """True for a discrete-time (sampled) system."""
        return self.sample_period > 0.0

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
        """The model as a named python-control StateSpace (discrete with dt = T if sampled)."""
        return control.ss(self.A, self.B, self.C, self.D, self.sample_period,
                          inputs=list(self.input_names), outputs=list(self.output_names),
                          states=list(self.state_names))


def linear_model_from(system: object, *, x0: object = None,
                      units: Mapping[str, str | None] | None = None,
                      nominals: object = None) -> LinearModel:
    """Validate a python-control system and turn it into a :class:`LinearModel`.

    Parameters
    ----------
    system : control.StateSpace
        Continuous-time (``dt == 0``) or discrete-time with a sample period (``dt > 0``),
        finite matrices, legal and distinct signal names.
    x0 : array_like of float, shape (n_states,), optional
        Initial state in the units of the states; zeros by default.
    units : mapping of str to str or None, optional
        Unit overrides, see :func:`fmu.units.resolve_units`.
    nominals : array_like of float, shape (n_states,), optional
        Positive finite nominal magnitude of each state; left None otherwise (see
        :func:`state_nominals`).

    Returns
    -------
    LinearModel

    Raises
    ------
    FMUBuildError
        For a system that is not a StateSpace, is discrete-time without a sample period,
        has non-finite matrices, or has missing, illegal or duplicate signal names.
    ValueError
        For an ``x0`` or ``nominals`` of the wrong shape or with bad entries, bad
        ``units``, or a system beyond the limits of :mod:`fmu.limits` (states, signals).
    TypeError
        For an ``x0`` or ``nominals`` that is not an array of numbers or ``units`` that is
        not a mapping.
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
    sample_period = 0.0
    if dt is True:
        raise FMUBuildError(
            "system is discrete-time without a sample period (dt = True); a sampled FMU "
            "needs it: build the StateSpace with dt = <sample period in s>.")
    if dt is not None and dt is not False and dt != 0:
        if isinstance(dt, (bool, np.bool_)) or not isinstance(dt, (int, float, np.integer, np.floating)) \
                or not (np.isfinite(dt) and dt > 0):
            raise FMUBuildError(f"system.dt must be 0 (continuous time) or a positive finite "
                                f"sample period [s]; got {shorten(dt)}")
        sample_period = float(dt)

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

    x0_array = np.zeros(n) if x0 is None else _state_vector("x0", x0, n, positive=False)
    nominal_array = None if nominals is None else _state_vector("nominals", nominals, n, positive=True)

    return LinearModel(
        A=matrices["A"], B=matrices["B"], C=matrices["C"], D=matrices["D"],
        input_names=inputs, output_names=outputs, state_names=states, x0=x0_array,
        units=resolve_units(list(inputs + outputs + states), units), name=str(system.name),
        sample_period=sample_period, nominals=nominal_array)


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


def _state_vector(label: str, value: object, n: int, *, positive: bool) -> np.ndarray:
    """``value`` as a float64 vector of one finite (and if asked, positive) number per state."""
    what = "positive numbers" if positive else "real numbers"
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise TypeError(f"{label} must be an array of {n} {what} (in the states' units); got "
                        f"{type(value).__name__} {shorten(value)}") from error
    if array.shape != (n,):
        raise ValueError(f"{label} must have shape ({n},) (one value per state, in the states' "
                         f"units); got shape {array.shape}")
    good = np.isfinite(array) & (array > 0 if positive else True)
    if not np.all(good):
        bad = int(np.flatnonzero(~good)[0])
        raise ValueError(f"{label} must be {'positive and ' if positive else ''}finite (in the "
                         f"states' units); got {array[bad]} at index {bad}")
    return array


def _round_nominal(value: float) -> float:
    """Two significant digits: a nominal is a scale, not a measurement."""
    return float(f"{value:.1e}")


def state_nominals(model: LinearModel, stop_time: float) -> np.ndarray:
    """Nominal magnitude of each state from the model's own scaling.

    The nominal of state i is the largest ``|x_i(t)|`` over the default experiment
    ``[0, stop_time]`` of (a) the free response from ``x0`` and (b) the responses to a unit
    step of each input (1 in the input's unit) from rest, looked at on
    :data:`NOMINAL_POINTS` equally spaced instants, rounded to two significant digits; 1.0
    for a state that none of them moves (or that overflows). A deflection state that a
    unit torque moves by millimetres thus gets a nominal of about 1e-3 m, and an
    integrator that tolerances are applied to relative to its nominal (FMI 2.0.1, section
    3.2.2; FMI 3.0, ``nominal``) is neither over- nor under-resolved.

    The responses are exact at the sampled instants: zero-order-hold transition matrices
    (:func:`zoh_matrices`) for a continuous-time model, powers of ``[[A, B], [0, I]]`` for
    a discrete-time one.

    Parameters
    ----------
    model : LinearModel
    stop_time : float, s
        Positive and finite.

    Returns
    -------
    numpy.ndarray of float64, shape (n_states,)
    """
    n, m = model.n_states, model.n_inputs
    if n == 0:
        return np.zeros(0)
    if model.discrete:
        samples = max(1, int(min(stop_time / model.sample_period, 2.0**52)))
        stride = max(1, samples // NOMINAL_POINTS)
        augmented = np.zeros((n + m, n + m))
        augmented[:n, :n], augmented[:n, n:] = model.A, model.B
        augmented[n:, n:] = np.eye(m)
        points = min(NOMINAL_POINTS, samples)
        with np.errstate(all="ignore"):
            transition = np.linalg.matrix_power(augmented, stride)
    else:
        points = NOMINAL_POINTS
        Phi, Gamma = zoh_matrices(model.A, model.B, stop_time / points)
        transition = np.block([[Phi, Gamma], [np.zeros((m, n)), np.eye(m)]])
    # columns: [x; u] of the free response and of each unit input step
    columns = np.zeros((n + m, 1 + m))
    columns[:n, 0] = model.x0
    columns[n:, 1:] = np.eye(m)
    peak = np.abs(columns[:n]).max(axis=1)
    with np.errstate(all="ignore"):
        for _ in range(points):
            columns = transition @ columns
            peak = np.fmax(peak, np.abs(columns[:n]).max(axis=1))
    return np.array([_round_nominal(v) if np.isfinite(v) and v > 0 else 1.0 for v in peak])
