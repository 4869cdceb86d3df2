"""A loop delay tau [s] (computation plus transport) between the controller and the torque.

The torque the plant receives at t is the controller's command at t - tau. In the frequency
domain that is exactly the factor e^(-j omega tau) on the loop (:func:`controllers.margins`,
:func:`controllers.spillover`, :func:`controllers.loop_frequency_response`); in sampled time
this module realises it exactly.

Zero-order hold with a delay (exact)
------------------------------------
A command u_j held over [t_j, t_j+1) (t_j = j T) and delayed by tau = (k + f) T, k an integer and
0 <= f < 1, reaches the plant as u_{n-k-1} over [t_n, t_n + f T) and as u_{n-k} over
[t_n + f T, t_n+1). Integrating x' = A x + B v over the step (the modified z-transform):

    x_{n+1} = Phi x_n + Gamma0 u_{n-k} + Gamma1 u_{n-k-1},
    Phi = e^(A T),  Gamma0 = int_0^((1-f) T) e^(A s) ds B,
    Gamma1 = e^(A (1-f) T) int_0^(f T) e^(A s) ds B,

and the plant's feedthrough sees v(t_n) = u_{n-k-1} (f > 0) or u_{n-k} (f = 0). The past
commands are states of a delay line, so the delayed sampled-data loop is a finite discrete
system, exact at the samples (:func:`delayed_closed_loop`); both integrals come from the exact
Van Loan exponential of :func:`controllers.discretise.discretise`.

A continuous controller with a delay
------------------------------------
The delayed continuous loop is infinite-dimensional. In time it is simulated on a step dt
(:func:`delayed_closed_loop` with ``dt``): the controller's command is sampled every dt and held,
and delayed by tau - dt/2, the hold's own mean delay taken out; plant and controller states are
integrated exactly between the samples. A zero-order hold is e^(-j omega dt/2) sinc(omega dt/2):
its phase is exactly that of a delay dt/2 and its gain 1 - (omega dt)^2 / 24 + ..., and the
sampled command's error has zero mean over each step, so the simulated loop differs from the
delayed continuous loop by O(dt^2) (verified in the tests: halving dt quarters the error). The
loop's other inputs (references, disturbances) are held over each step like any
zero-order-hold input: sampled at the step midpoints t_n + dt/2, their error is O(dt^2) as well.
This needs dt <= 2 tau.

A delay that looks like a unit slip
-----------------------------------
Attitude loops have milliseconds to a few hundred milliseconds of computation and transport
delay. A delay above :data:`PLAUSIBLE_DELAY` (1 s) is legal and used as given, but more likely
milliseconds given as seconds (``delay=20`` for 20 ms): every public function that takes a
loop delay warns about it (:class:`LongDelayWarning`, naming the parameter, its value and the
likely slip; :func:`warns_long_delay`), once per call, and the scene reader about
``controller.delay`` by key with the same rule (:func:`long_delay`).

References
----------
G. F. Franklin, J. D. Powell, M. L. Workman, Digital Control of Dynamic Systems, 3rd ed.,
Addison-Wesley 1998, sec. 4.3.4 and 6.3 (the modified z-transform of a fractional delay, the
zero-order hold); K. J. Astrom, B. Wittenmark, Computer-Controlled Systems, 3rd ed., 1997,
sec. 2.3 (sampling a system with a time delay).
"""
from __future__ import annotations

import contextvars
import functools
import inspect
import math
import warnings

import control
import numpy as np

from .arguments import user_stacklevel
from .discretise import DiscretisationOverflowWarning, discretise
from .frequency import ModalEvaluator
from .signals import check_pair, fed_back_signals, is_digital, reference_inputs, signal_names
from .threads import limits_blas_threads, total_states

__all__ = ["split_delay", "delayed_discretisation", "DelayedSampledPlant",
           "delayed_closed_loop", "check_delay", "total_delay", "DELAY_SNAP",
           "MAX_DELAY_STATES", "MAX_DELAY", "PLAUSIBLE_DELAY", "LongDelayWarning", "long_delay",
           "warns_long_delay"]

#: A fractional part of the delay within this many samples of 0 or 1 is taken as 0 (the
#: delay a whole number of samples: round-off of tau / T).
DELAY_SNAP = 1e-9
#: Most delay-line states a delayed loop may hold ((delay / dt + 1) x the torques): beyond, the
#: loop is refused by name before it is built.
MAX_DELAY_STATES = 10_000


#: Longest delay [s] accepted: omega * delay stays finite up to 1e200 rad/s.
MAX_DELAY = 1e100
#: A loop delay above this [s] is warned about as a likely unit slip: attitude loops have
#: milliseconds to a few hundred milliseconds of computation and transport delay; above,
#: milliseconds given as seconds is likelier (:class:`LongDelayWarning`; the scene reader's
#: ``controller.delay`` by the same rule).
PLAUSIBLE_DELAY = 1.0


class LongDelayWarning(UserWarning):
    """A loop delay above :data:`PLAUSIBLE_DELAY` [s] given to a public function: legal, and
    used as given, but more likely milliseconds given as seconds (the message names the
    parameter, its value and the likely slip)."""


# True while a call of a function decorated by warns_long_delay runs in this context: the
# delay it was given has been looked at, and the functions it calls with it say nothing more
_DELAY_SEEN = contextvars.ContextVar("controllers_delay_seen", default=False)


def long_delay(delay: float) -> str | None:
    """The likely mistake of a loop delay above :data:`PLAUSIBLE_DELAY`.

    Parameters
    ----------
    delay : float, s

    Returns
    -------
    str or None
        ``"a loop delay of 20 s is long for an attitude loop (milliseconds to a few hundred):
        did you give milliseconds? 20 ms = 0.02 s"``, or None for a delay of at most
        :data:`PLAUSIBLE_DELAY` (or one that is not a finite number: its check says why).
    """
    if not (isinstance(delay, (int, float, np.integer, np.floating))
            and not isinstance(delay, (bool, np.bool_))
            and PLAUSIBLE_DELAY < float(delay) <= MAX_DELAY):
        return None
    delay = float(delay)
    return (f"a loop delay of {delay:g} s is long for an attitude loop (milliseconds to a few "
            f"hundred): did you give milliseconds? {delay:g} ms = {delay / 1e3:g} s")


def warns_long_delay(function):
    """Decorator of a public function that takes a loop delay as its parameter ``delay`` [s]:
    a delay above :data:`PLAUSIBLE_DELAY` is warned about (:class:`LongDelayWarning` at the
    caller's line: ``"delay = 20 s: a loop delay of 20 s is long ..."``, :func:`long_delay`)
    and then used as given.

    Once per call: the functions such a function calls with the delay (close_loop inside
    pointing, a LoopTransfer inside margins) say nothing more. A caller that has reported the
    value itself (the scene reader, by key) silences the class with :mod:`warnings` filters.
    """
    parameters = list(inspect.signature(function).parameters.values())
    names = [p.name for p in parameters]
    if "delay" not in names:
        raise TypeError(f"{function.__qualname__} has no parameter 'delay' to check")
    position = names.index("delay")
    if parameters[position].kind not in (inspect.Parameter.POSITIONAL_ONLY,
                                         inspect.Parameter.POSITIONAL_OR_KEYWORD):
        position = None     # keyword-only

    @functools.wraps(function)
    def checked(*args, **kwargs):
        if _DELAY_SEEN.get():
            return function(*args, **kwargs)
        if "delay" in kwargs:
            delay = kwargs["delay"]
        elif position is not None and len(args) > position:
            delay = args[position]
        else:
            delay = None    # the default: no delay
        said = long_delay(delay)
        if said is not None:
            warnings.warn(f"delay = {float(delay):g} s: {said}", LongDelayWarning,
                          stacklevel=user_stacklevel())
        token = _DELAY_SEEN.set(True)
        try:
            return function(*args, **kwargs)
        finally:
            _DELAY_SEEN.reset(token)

    return checked


def check_delay(delay, name: str = "delay") -> float:
    """A delay [s]: a real number >= 0 and finite (0 for none); TypeError or ValueError naming
    it otherwise. (A long one is legal: the public functions warn about it,
    :func:`warns_long_delay`.)"""
    if isinstance(delay, bool) or not isinstance(delay, (int, float, np.floating, np.integer)):
        raise TypeError(f"{name} must be a real number [s]; got {type(delay).__name__}")
    delay = float(delay)
    if not (math.isfinite(delay) and delay >= 0):
        raise ValueError(f"{name} must be non-negative and finite [s]; got {delay:.6g}")
    if delay > MAX_DELAY:
        raise ValueError(f"{name} must be at most {MAX_DELAY:g} [s] (omega * delay, the phase "
                         f"it adds, stays finite); got {delay:.6g}")
    return delay


def total_delay(controller, delay, computation_delay) -> float:
    """The loop's delay [s]: ``delay`` plus, with ``computation_delay``, one sample of a digital
    controller (its command computed from the samples at t_n and applied at t_n+1)."""
    if not isinstance(controller, control.StateSpace):
        raise TypeError(f"controller must be a control.StateSpace; got "
                        f"{type(controller).__name__}")
    delay = check_delay(delay)
    if not isinstance(computation_delay, (bool, np.bool_)):
        raise TypeError(f"computation_delay must be True or False; got "
                        f"{type(computation_delay).__name__}")
    if computation_delay:
        if not is_digital(controller):
            raise ValueError("computation_delay is one sample of a digital controller; this "
                             "controller is continuous (give its delay as delay [s])")
        delay += float(controller.dt)
    return delay


@warns_long_delay
def split_delay(delay: float, dt: float) -> tuple[int, float]:
    """tau = (k + f) dt with k a non-negative integer and 0 <= f < 1 (f within DELAY_SNAP of 0
    or 1 taken as 0)."""
    ratio = check_delay(delay) / _check_dt(dt)
    if not ratio <= 1e15:
        raise ValueError(f"delay / dt = {ratio:.3g} steps is beyond 1e15 (the fraction of a step "
                         "is lost to round-off): check the delay's unit [s] and dt [s]")
    k = math.floor(ratio)
    f = ratio - k
    if f > 1.0 - DELAY_SNAP:
        k, f = k + 1, 0.0
    elif f < DELAY_SNAP:
        f = 0.0
    return int(k), float(f)


@warns_long_delay
def delayed_discretisation(A, B, dt: float, delay: float):
    """Exact zero-order-hold discretisation of x' = A x + B u(t - delay).

    Returns
    -------
    Phi, Gamma0, Gamma1 : ndarray
        x_{n+1} = Phi x_n + Gamma0 u_{n-k} + Gamma1 u_{n-k-1} (module docstring); Gamma1 = 0 when
        the delay is a whole number of steps.
    k : int
    f : float
        delay = (k + f) dt.
    """
    try:
        A = np.asarray(A, dtype=float)
        B = np.asarray(B, dtype=float)
    except (TypeError, ValueError):
        raise TypeError("A and B must be real arrays") from None
    if A.ndim != 2 or A.shape[0] != A.shape[1] or B.ndim != 2 or B.shape[0] != A.shape[0]:
        raise ValueError(f"A must be square (n, n) and B (n, m); got A {A.shape}, B {B.shape}")
    if not (np.all(np.isfinite(A)) and np.all(np.isfinite(B))):
        raise ValueError("A and B must be finite; got NaN or inf")
    k, f = split_delay(delay, dt)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DiscretisationOverflowWarning)
        with np.errstate(all="ignore"):
            if f == 0.0:
                Phi, Gamma0, _ = discretise(A, B, dt, "zero")
                Gamma1 = np.zeros_like(Gamma0)
            else:
                # the late part of the step [f T, T) and the early part [0, f T) (Van Loan)
                Phi_late, Gamma0, _ = discretise(A, B, (1.0 - f) * dt, "zero")
                Phi_early, G_early, _ = discretise(A, B, f * dt, "zero")
                Phi, Gamma1 = Phi_late @ Phi_early, Phi_late @ G_early
    if not all(np.all(np.isfinite(M)) for M in (Phi, Gamma0, Gamma1)):
        raise ValueError(f"dt {float(dt):.4g} s: the exact discretisation over one step leaves the "
                         "floating-point range (the system grows too much in a step, or the step "
                         "is far too long); shorten dt")
    return Phi, Gamma0, Gamma1, k, f


class DelayedSampledPlant:
    """Frequency response of a zero-order-hold-sampled plant with a delayed input, at z.

    P(z) = z^-k [C (zI - Phi)^-1 (Gamma0 + Gamma1 z^-1)] + D z^-l, l = k + 1 if f > 0 else k
    (module docstring), from one modal evaluator of (Phi, [Gamma0, Gamma1], C): O(n) per point,
    the delay line never realised as states.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous plant.
    dt : float, s
        Sample time.
    delay : float, s
    inputs, outputs : list of str
        The delayed inputs and the outputs of the response.
    """

    @warns_long_delay
    def __init__(self, plant: control.StateSpace, dt: float, delay: float, inputs, outputs):
        if not isinstance(plant, control.StateSpace) or not plant.isctime(strict=True):
            raise TypeError("plant must be a continuous control.StateSpace; got "
                            f"{type(plant).__name__}")
        for kind, names, labels in (("inputs", inputs, plant.input_labels),
                                    ("outputs", outputs, plant.output_labels)):
            unknown = [n for n in names if n not in labels]
            if unknown or not list(names):
                raise ValueError(f"{kind} must name the plant's signals {list(labels)[:8]}; got "
                                 f"{list(names)[:8]}")
        i_in = [list(plant.input_labels).index(n) for n in inputs]
        i_out = [list(plant.output_labels).index(n) for n in outputs]
        Phi, G0, G1, k, f = delayed_discretisation(plant.A, plant.B[:, i_in], dt, delay)
        self.k, self.f, self.m = k, f, len(i_in)
        self.lag = k + 1 if f > 0 else k
        self.D = np.asarray(plant.D, dtype=float)[np.ix_(i_out, i_in)]
        C = np.asarray(plant.C, dtype=float)[i_out]
        self.ev = ModalEvaluator(Phi, np.hstack([G0, G1]), C, np.zeros((len(i_out), 2 * self.m)),
                                 center=1.0)

    def __call__(self, z) -> np.ndarray:
        """P(z), shape (len(z), n_outputs, n_inputs), complex128."""
        z = np.asarray(z, dtype=complex).reshape(-1)
        G = self.ev(z)
        m = self.m
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            P = (G[:, :, :m] + G[:, :, m:] / z[:, None, None]) * (z ** -self.k)[:, None, None]
            return P + self.D[None] * (z ** -self.lag)[:, None, None]

    def poles(self) -> np.ndarray:
        """Eigenvalues of Phi (the delay line's poles at z = 0 left out)."""
        return self.ev.poles()


def _check_dt(dt) -> float:
    if isinstance(dt, bool) or not isinstance(dt, (int, float, np.floating, np.integer)):
        raise TypeError(f"dt must be a real number [s]; got {type(dt).__name__}")
    dt = float(dt)
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be positive and finite [s]; got {dt:.6g}")
    return dt


@warns_long_delay
@limits_blas_threads(total_states)
def delayed_closed_loop(plant: control.StateSpace, controller: control.StateSpace,
                        delay: float, *, dt: float | None = None) -> control.StateSpace:
    """The attitude loop with the torque delayed by ``delay``, as a discrete system.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous plant with named signals (as :func:`controllers.close_loop`).
    controller : control.StateSpace
        Digital controller: the exact sampled-data loop with the delayed zero-order hold at its
        sample time (module docstring), ``dt`` omitted or equal to it. Continuous controller:
        ``dt`` required, the command sampled every dt and held, delayed by delay - dt/2
        (module docstring: error O(dt^2); dt <= 2 delay).
    delay : float, s
        Total loop delay (> 0).
    dt : float, s, optional

    Returns
    -------
    control.StateSpace
        Discrete with step dt (the controller's for a digital one). Inputs: the controller's
        reference inputs, then the plant's other inputs (held over each step). Outputs: every
        plant output, then the torque(s) the plant receives (the delayed command; at a sample
        t_n the value held from then on). States: the plant's (and a continuous controller's)
        ``plant_x*``, the controller's ``controller_x*``, and the delay line ``delay_u*``
        (past commands).
    """
    ch = check_pair(plant, controller)
    delay = check_delay(delay)
    if delay <= 0:
        raise ValueError("delay must be positive [s] for a delayed loop (use close_loop without "
                         "a delay)")
    digital = is_digital(controller)
    if digital:
        T = float(controller.dt)
        if dt is not None and not math.isclose(_check_dt(dt), T, rel_tol=1e-9):
            raise ValueError(f"dt must equal the digital controller's sample time {T:.6g} s (or "
                             f"be omitted); got {float(dt):.6g}")
        shift = delay
    else:
        if dt is None:
            raise ValueError("dt [s] must be given for a continuous controller with a delay: its "
                             "delayed loop is simulated with the command held every dt (see "
                             "controllers.delay)")
        T = _check_dt(dt)
        if T > 2.0 * delay * (1.0 + 1e-12):
            raise ValueError(f"dt must be at most 2 x delay = {2 * delay:.6g} s for a continuous "
                             f"controller (the hold's mean delay dt/2 is taken out of the loop's "
                             f"delay); got {T:.6g} s")
        shift = max(delay - 0.5 * T, 0.0)
    measured = fed_back_signals(plant, controller)
    refs = reference_inputs(controller, signal_names(plant, "output"))
    p_in, p_out = signal_names(plant, "input"), signal_names(plant, "output")
    c_in = list(controller.input_labels)
    disturbances = [n for n in p_in if n not in ch.torques]
    Ap, Bp, Cp, Dp = (np.asarray(M, dtype=float) for M in (plant.A, plant.B, plant.C, plant.D))
    Ac, Bc, Cc, Dc = (np.asarray(M, dtype=float).reshape(shape) for M, shape in zip(
        (controller.A, controller.B, controller.C, controller.D),
        ((controller.nstates,) * 2, (controller.nstates, controller.ninputs),
         (ch.n_axes, controller.nstates), (ch.n_axes, controller.ninputs))))
    i_t = [p_in.index(n) for n in ch.torques]
    i_d = [p_in.index(n) for n in disturbances]
    i_m = [p_out.index(n) for n in measured]
    j_m = [c_in.index(n) for n in measured]
    j_r = [c_in.index(n) for n in refs]
    n_p, n_c, m = Ap.shape[0], Ac.shape[0], len(i_t)
    Cm, Dmt, Dmd = Cp[i_m], Dp[np.ix_(i_m, i_t)], Dp[np.ix_(i_m, i_d)]
    Bcm, Bcr, Dcm, Dcr = Bc[:, j_m], Bc[:, j_r], Dc[:, j_m], Dc[:, j_r]
    n_r, n_d = len(j_r), len(i_d)
    if (shift / T + 2.0) * ch.n_axes > MAX_DELAY_STATES:
        raise ValueError(f"delay / dt = {shift / T:.4g} steps of {ch.n_axes} torque(s) would need "
                         f"more than MAX_DELAY_STATES = {MAX_DELAY_STATES} delay-line states: use "
                         f"a longer dt (now {T:.4g} s) or check the delay's unit (s; got "
                         f"{delay:.4g})")
    k, f = split_delay(shift, T)
    lag_v = k + 1 if f > 0 else k  # the command the plant receives at a sample
    # "lag form": x_{n+1} = Phi x + sum_l Gam[l] u_{n-l} + Gw w, u_n = Cu x + sum_l Du[l]
    # u_{n-l} + Duw w, outputs = Co x + sum_l Do[l] u_{n-l} + Dow w, with w = [r; d]
    n = n_p + n_c
    Gam: dict[int, np.ndarray] = {}
    Du: dict[int, np.ndarray] = {}
    Do: dict[int, np.ndarray] = {}

    def add(table, lag, value):
        table[lag] = table.get(lag, 0.0) + value

    if digital:
        Phi_p, G0, G1, _, _ = delayed_discretisation(Ap, Bp[:, i_t], T, shift)
        Phi_d, Gd, _ = discretise(Ap, Bp[:, i_d], T, "zero") if n_d else (None, np.zeros(
            (n_p, 0)), None)
        Phi = np.block([[Phi_p, np.zeros((n_p, n_c))], [Bcm @ Cm, Ac]])
        add(Gam, k, np.vstack([G0, np.zeros((n_c, m))]))
        if f > 0:
            add(Gam, k + 1, np.vstack([G1, np.zeros((n_c, m))]))
        add(Gam, lag_v, np.vstack([np.zeros((n_p, m)), Bcm @ Dmt]))
        Gw = np.block([[np.zeros((n_p, n_r)), Gd], [Bcr, Bcm @ Dmd]])
    else:
        # plant and controller together, continuous, driven by the delayed held command v
        AG = np.block([[Ap, np.zeros((n_p, n_c))], [Bcm @ Cm, Ac]])
        Bv = np.vstack([Bp[:, i_t], Bcm @ Dmt])
        Bw = np.block([[np.zeros((n_p, n_r)), Bp[:, i_d]], [Bcr, Bcm @ Dmd]])
        Phi, G0, G1, _, _ = delayed_discretisation(AG, Bv, T, shift)
        _, Gw, _ = discretise(AG, Bw, T, "zero") if Bw.shape[1] else (None, np.zeros((n, 0)),
                                                                       None)
        add(Gam, k, G0)
        if f > 0:
            add(Gam, k + 1, G1)
    Cu = np.hstack([Dcm @ Cm, Cc])
    add(Du, lag_v, Dcm @ Dmt)
    Duw = np.hstack([Dcr, Dcm @ Dmd])
    Co = np.vstack([np.hstack([Cp, np.zeros((Cp.shape[0], n_c))]), np.zeros((m, n))])
    add(Do, lag_v, np.vstack([Dp[:, i_t], np.eye(m)]))
    Dow = np.vstack([np.hstack([np.zeros((Cp.shape[0], n_r)), Dp[:, i_d]]),
                     np.zeros((m, n_r + n_d))])
    A, B, C, D = _lag_form(Phi, Gam, Gw, Cu, Du, Duw, Co, Do, Dow)
    q = max([lag for lag in list(Gam) + list(Du) + list(Do)] + [0])
    states = ([f"plant_x{i}" for i in range(n_p)] + [f"controller_x{i}" for i in range(n_c)]
              + [f"delay_u{lag}_{a}" for lag in range(1, q + 1) for a in range(m)])
    return control.ss(A, B, C, D, T, inputs=refs + disturbances,
                      outputs=p_out + list(ch.torques), states=states, name="closed_loop")


def _lag_form(Phi, Gam, Gw, Cu, Du, Duw, Co, Do, Dow):
    """Discrete closed loop of the lag form (see delayed_closed_loop) with the delay line
    z_l = u_{n-l}, l = 1..q, as states: (A, B, C, D) on [x; z_1; ...; z_q]."""
    n, m = Phi.shape[0], Cu.shape[0]
    q = max([lag for lag in list(Gam) + list(Du) + list(Do)] + [0])
    N = n + q * m

    def z_block(lag):  # selector of z_lag in the state vector, (m, N)
        S = np.zeros((m, N))
        S[:, n + (lag - 1) * m: n + lag * m] = np.eye(m)
        return S

    X = np.hstack([np.eye(n), np.zeros((n, q * m))])  # selector of x
    # u_n = F [x; z] + Fw w, solving the algebraic loop of a lag-0 feedthrough
    gain = np.eye(m) - Du.get(0, np.zeros((m, m)))
    if abs(np.linalg.det(gain)) < 1e-12:
        raise ValueError("algebraic loop: the controller's feedthrough times the plant's "
                         "feedthrough makes I - Dc Dp singular")
    rhs = Cu @ X + sum((Du[lag] @ z_block(lag) for lag in Du if lag > 0), np.zeros((m, N)))
    F = np.linalg.solve(gain, rhs)
    Fw = np.linalg.solve(gain, Duw)

    def lagged(lag):  # u_{n-lag} as (state map, input map)
        if lag == 0:
            return F, Fw
        return z_block(lag), np.zeros((m, Fw.shape[1]))

    A = np.zeros((N, N))
    B = np.zeros((N, Fw.shape[1]))
    A[:n] = Phi @ X
    B[:n] = Gw
    for lag, G in Gam.items():
        S, W = lagged(lag)
        A[:n] += G @ S
        B[:n] += G @ W
    if q:
        A[n:n + m], B[n:n + m] = F, Fw            # z_1 <- u_n
        for lag in range(2, q + 1):               # z_lag <- z_(lag-1)
            A[n + (lag - 1) * m: n + lag * m] = z_block(lag - 1)
    C = Co @ X
    D = Dow.copy()
    for lag, G in Do.items():
        S, W = lagged(lag)
        C = C + G @ S
        D = D + G @ W
    return A, B, C, D
