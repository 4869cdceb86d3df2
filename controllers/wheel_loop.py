r"""A closed attitude loop whose torque goes through reaction wheels, and its simulation.

The wheels (:mod:`.wheels`) put two nonlinearities between the controller's torque command tau_c
and the hub: saturation (torque and momentum) and friction. Write the torque the wheels apply to
the hub as the command plus a deviation,

    tau = tau_c + G e,          e = w - G^+ tau_c  (one entry per wheel),

w the wheels' torques after limits and friction, G^+ tau_c their commands. Everything else is
linear: the plant and controller (the closed loop of :func:`.close_loop`) with e as an extra
input at the plant's torque, and the wheels' absolute momenta, h_abs' = -(G^+ tau_c + e). That
linear system S (:attr:`WheelLoop.system`: states the loop's, then one momentum per wheel;
inputs the loop's, then e) is exact; only e is nonlinear.

Method: exact between switching instants, the switches at the samples. The wheel logic is
piecewise affine: at each sample t_k it fixes every wheel's mode (following its command, clipped
at +-tau_i, held at its momentum limit; the sign of its speed for Coulomb friction), and within a
mode e is an affine function of S's state and the loop's inputs (:class:`_Modes`), so S with
that feedback is again LTI, evolved exactly over [t_k, t_k+1) with the loop's inputs linear
between samples (the first-order hold of :func:`.simulate`; :func:`.discretise`). A mode that
lasts many samples is one segment, computed in O(log L) matrix products (a doubling scan);
samples whose e is not affine (the "scale" rule with several wheels and one saturated) are
stepped with e held over the step. For a digital loop S is discrete and the torque command held,
so the modes are exact as they are. Until the first sample where a limit acts (or friction, with
a spinning wheel), e = 0 and the response is the linear loop's, from :class:`.Simulator`; a
wheel that never saturates gives the linear loop's response to round-off.

Error: only from deciding the switches at the samples (a limit crossed between two samples acts
from the next). Where the applied torque is continuous across the switch (entering or leaving
the torque limit) a switch late by delta < dt costs an impulse |tau_c'| delta^2 / 2: the error
is O(dt^2) (against a continuous-time integration of the same nonlinear loop: log-log slope 1.5
to 2 for dt from 0.4 to 0.025 s, 2e-6 rad of a 0.21 rad peak at 0.1 s on the test loop). Where
it jumps (reaching the momentum limit, a Coulomb friction reversal, a stepped "scale" sample)
the error is O(dt): at most one sample of motor torque, |h| <= momentum_limit + dt torque_limit
before the limit holds. Basilisk's wheel decides its torque and speed limits at its update
instants in the same way.

References
----------
.. [1] G. F. Franklin, J. D. Powell, M. L. Workman, *Digital Control of Dynamic Systems*, 3rd ed.,
   Addison-Wesley, 1998, sec. 6.3 (zero-order hold equivalents).
.. [2] C. F. Van Loan, "Computing integrals involving the matrix exponential", IEEE Trans.
   Automatic Control 23(3), 395-404, 1978.
.. [3] W. D. Hillis, G. L. Steele, "Data parallel algorithms", Comm. ACM 29(12), 1170-1183, 1986
   (prefix computations by doubling).
"""
from __future__ import annotations

import dataclasses
import math

import control
import numpy as np

from .arguments import describe, real_number
from .delay import warns_long_delay
from .discretise import discretise, discretise_blocks
from .loop import close_loop
from .signals import Channels, channels
from .chunked import OVERFLOW as _OVERFLOW
from .simulate import Simulator
from .threads import one_blas_thread
from .timeresp import MAX_SAMPLES
from .wheels import WheelSet

__all__ = ["WheelLoop", "WheelResponse", "simulate_wheels", "DEVIATION_SUFFIX"]

#: Suffix of the plant-level input through which the wheels' deviation enters (see module doc).
DEVIATION_SUFFIX = "_wheel_deviation"
# A segment of one mode is first tried over _FIRST_SEGMENT samples, after a switch over twice the
# last mode's length, doubled while the mode lasts, up to as many samples as _SEGMENT_WORK
# multiply-adds of its doubling scan allow (n^2 per sample and level), within
# [_SHORTEST_SEGMENT, _LONGEST_SEGMENT]: for small loops the scan's flops cost little beside a
# segment's fixed overhead. After a mode that lasted one sample, _CHATTER_STEPS samples are
# stepped singly (a Coulomb friction sign chattering about zero speed, or a wheel at its
# momentum limit, would otherwise cost a segment per sample).
_SEGMENT_WORK = 4_000_000
_FIRST_SEGMENT = 512
_SHORTEST_SEGMENT, _LONGEST_SEGMENT = 16, 4096
_CHATTER_STEPS = 8
# Loops of at most this many states are simulated by segments from the first sample (measured
# cheaper than the simulator's set-up and run up to ~40 states, benchmarks/wheels.py); larger
# ones run the linear loop through the Simulator, O(n) per sample, first.
_SEGMENTS_FROM_START = 32


@dataclasses.dataclass
class WheelResponse:
    """A simulated loop with reaction wheels.

    Attributes
    ----------
    response : control.TimeResponseData
        Outputs: the plant's outputs (``theta``, ``omega``, tip deflections...); ``torque``
        (three-axis ``torque_x``...) the torque the wheels apply to the hub [N*m];
        ``torque_command`` (``torque_command_x``...) the controller's command [N*m]; per wheel
        ``<name>_torque_command`` (its share G^+ tau_c) and ``<name>_torque`` (applied, with
        friction) [N*m], ``<name>_momentum`` J_s Omega [N*m*s], ``<name>_speed`` Omega [rad/s]
        (wheels with a spin inertia), ``<name>_torque_saturated`` and
        ``<name>_momentum_saturated`` (1.0 while that limit acts, else 0.0). Inputs: the loop's.
    wheels : WheelSet
    saturated : bool
        Whether any wheel reached a limit at any sample.
    first_saturation : float or None, s
        Time of the first sample at which a limit acted.
    time_saturated : float, s
        Time during which at least one limit of one wheel acted (each sample's state held until
        the next sample).
    time_torque_saturated, time_momentum_saturated : dict of str to float, s
        The same per wheel and limit.
    peak_momentum : dict of str to float, N*m*s
        max |h| per wheel.
    momentum_margin : dict of str to float, N*m*s
        momentum_limit - max |h| per wheel (inf if unlimited; <= 0: the limit was reached).
    momentum_margin_fraction : dict of str to float
        momentum_margin / momentum_limit.
    peak_torque : dict of str to float, N*m
        max |applied torque| per wheel.
    """

    response: control.TimeResponseData
    wheels: WheelSet
    saturated: bool
    first_saturation: float | None
    time_saturated: float
    time_torque_saturated: dict
    time_momentum_saturated: dict
    peak_momentum: dict
    momentum_margin: dict
    momentum_margin_fraction: dict
    peak_torque: dict

    def summary(self) -> dict:
        """The scalar fields as a JSON-ready dict (inf written as None)."""
        def clean(v):
            if isinstance(v, dict):
                return {k: clean(x) for k, x in v.items()}
            return None if isinstance(v, float) and not math.isfinite(v) else v
        return {f.name: clean(getattr(self, f.name)) for f in dataclasses.fields(self)
                if f.name not in ("response", "wheels")}


class WheelLoop:
    """A closed attitude loop with the controller's torque applied through reaction wheels.

    Parameters
    ----------
    plant : control.StateSpace
        Continuous-time plant with named signals (:mod:`.signals`: planar ``torque``,
        ``theta``, ``omega``; or three-axis).
    controller : control.StateSpace
        Controller (continuous or digital) as for :func:`.close_loop`.
    wheels : WheelSet
        Planar set (one wheel) for a planar plant, three-axis set for a three-axis plant.
    delay, computation_delay, dt
        A loop delay, as for :func:`.close_loop`: the wheels receive the command of ``delay``
        earlier (the delayed loop of a continuous controller is discretised on ``dt``, and the
        wheels act on that discrete loop).

    Attributes
    ----------
    linear_loop : control.StateSpace
        :func:`.close_loop` of the plant (with the deviation inputs ``torque_wheel_deviation``
        ...) and the controller.
    system : control.StateSpace
        S of the module docstring: inputs the loop's inputs, then ``<name>_torque_deviation``
        (e) per wheel; states the loop's, then ``<name>_absolute_momentum``; outputs the
        plant's, ``torque_command`` (``torque_command_x``...) and ``<name>_momentum`` (the
        response's other signals follow from these and e).
    inputs : list of str
        The loop's inputs (references, disturbances): what ``U`` of :meth:`simulate` holds.

    Raises
    ------
    TypeError
        ``wheels`` not a WheelSet, plant or controller not a StateSpace.
    ValueError
        A wheel set for the other convention (planar / three-axis), a plant whose measurements
        depend instantaneously on the torque (the wheel logic would be an implicit equation),
        any error of :func:`.close_loop`.
    """

    @warns_long_delay
    def __init__(self, plant: control.StateSpace, controller: control.StateSpace,
                 wheels: WheelSet, *, delay: float = 0.0, computation_delay: bool = False,
                 dt: float | None = None) -> None:
        if not isinstance(wheels, WheelSet):
            raise TypeError(f"wheels must be a controllers.WheelSet; got "
                            f"{type(wheels).__name__} {describe(wheels)}")
        if not isinstance(plant, control.StateSpace):
            raise TypeError(f"plant must be a control.StateSpace; got {type(plant).__name__}")
        ch = channels(plant)
        if wheels.n_axes != ch.n_axes:
            kind = "a planar" if ch.n_axes == 1 else "a three-axis"
            have = "planar (one wheel, no spin_axes)" if wheels.planar else "three-axis"
            raise ValueError(f"wheels must match {kind} plant; got a {have} WheelSet")
        self.wheels = wheels
        self.channels = ch
        deviations = [t + DEVIATION_SUFFIX for t in ch.torques]
        self.linear_loop = close_loop(_with_deviation_inputs(plant, ch, deviations), controller,
                                      delay=delay, computation_delay=computation_delay, dt=dt)
        self.system = self._wheel_system(plant, deviations)
        self._simulators: dict = {}
        self._mode_cache: dict = {}

    @property
    def inputs(self) -> list[str]:
        """The loop's inputs (what U of :meth:`simulate` holds, in this order)."""
        return list(self.system.input_labels)[: self._n_u]

    def _wheel_system(self, plant, deviations) -> control.StateSpace:
        lin, ch, wheels = self.linear_loop, self.channels, self.wheels
        A, B, C, D = (np.asarray(M, dtype=float) for M in (lin.A, lin.B, lin.C, lin.D))
        inputs, outputs = list(lin.input_labels), list(lin.output_labels)
        i_dev = [inputs.index(n) for n in deviations]
        i_u = [i for i in range(len(inputs)) if i not in i_dev]
        self._n_u = len(i_u)
        i_t = [outputs.index(n) for n in ch.torques]
        i_w = [outputs.index(n) for n in ch.omegas]
        n, nw = A.shape[0], wheels.n_wheels
        G, P = wheels.distribution, wheels.allocation
        Ct, Dtu, Dtd = C[i_t], D[np.ix_(i_t, i_u)], D[np.ix_(i_t, i_dev)]
        if np.any(Dtd != 0.0) or np.any(D[np.ix_(i_w, i_dev)] != 0.0):
            raise ValueError("plant must not feed the torque through to its measurements "
                             "('theta', 'omega') instantaneously: with wheels the applied "
                             "torque would depend on itself within a sample (an implicit "
                             "equation this simulation does not solve)")
        Bu, Be = B[:, i_u], B[:, i_dev] @ G
        # absolute momenta h: h' = -(P tau_c + e); discrete: h+ = h - T (P tau_c + e)
        if lin.isdtime(strict=True):
            scale, A_hh = float(lin.dt), np.eye(nw)
        else:
            scale, A_hh = 1.0, np.zeros((nw, nw))
        A_h = np.hstack([-scale * P @ Ct, A_hh])
        A_S = np.vstack([np.hstack([A, np.zeros((n, nw))]), A_h])
        B_S = np.vstack([np.hstack([Bu, Be]), np.hstack([-scale * P @ Dtu, -scale * np.eye(nw)])])
        # outputs: the plant's, the torque command, the wheels' momenta h = h_abs - J_s g . omega
        # (the response's other signals follow from these and e, see _result)
        J_s = wheels.spin_inertias
        g = np.ones((1, 1)) if wheels.planar else wheels.spin_axes   # (nw, n_axes)
        i_p = [outputs.index(name) for name in plant.output_labels]
        Cw, Dwu = C[i_w], D[np.ix_(i_w, i_u)]
        C_S = np.vstack([np.hstack([C[i_p], np.zeros((len(i_p), nw))]),
                         np.hstack([Ct, np.zeros((ch.n_axes, nw))]),
                         np.hstack([-J_s[:, None] * (g @ Cw), np.eye(nw)])])
        D_S = np.vstack([np.hstack([D[np.ix_(i_p, i_u)], D[np.ix_(i_p, i_dev)] @ G]),
                         np.hstack([Dtu, np.zeros((ch.n_axes, nw))]),
                         np.hstack([-J_s[:, None] * (g @ Dwu), np.zeros((nw, nw))])])
        labels = list(plant.output_labels) + [f"torque_command{ch.suffix(a)}"
                                              for a in range(ch.n_axes)]
        self._tc_rows = list(range(len(labels) - ch.n_axes, len(labels)))
        self._h_rows = list(range(len(labels), len(labels) + nw))
        labels += [f"{w}_momentum" for w in wheels.names]
        states = list(lin.state_labels) + [f"{w}_absolute_momentum" for w in wheels.names]
        return control.ss(A_S, B_S, C_S, D_S, lin.dt,
                          inputs=[inputs[i] for i in i_u]
                          + [f"{w}_torque_deviation" for w in wheels.names],
                          outputs=labels, states=states, name="wheel_loop")

    # ------------------------------------------------------------------------------------
    def _simulator(self, dt: float | None) -> Simulator:
        key = None if dt is None else round(dt, 15)
        if key not in self._simulators:
            self._simulators[key] = Simulator(self.system, dt)
        return self._simulators[key]

    def simulate(self, T, U=None, X0=None, *, max_samples: int | None = None) -> WheelResponse:
        """Simulate the loop with its wheels on the evenly spaced time grid ``T``.

        Parameters
        ----------
        T : array_like, shape (n_samples,), s
            Evenly spaced sample times (a digital loop's step), at least 2.
        U : array_like, optional
            The loop's inputs (:attr:`inputs`: references, disturbances) at the samples, shape
            (n_inputs, n_samples) ((n_samples,) for one input); linear between samples for a
            continuous loop. Default 0.
        X0 : array_like, optional
            Initial state of the linear loop (``linear_loop``'s states), default 0. The wheels
            start at their ``initial_momentum``.
        max_samples : int, optional
            Most samples allowed (default controllers.timeresp.MAX_SAMPLES); more are refused
            before any work.

        Returns
        -------
        WheelResponse

        Raises
        ------
        ValueError
            Bad T, U or X0 (shapes, finiteness, uneven T, a step other than a digital loop's),
            too many samples.
        FloatingPointError
            The response leaves the float64 range (an unstable loop).
        """
        T = _check_time(T)
        n_t = T.size
        limit = MAX_SAMPLES if max_samples is None else real_number(max_samples,
                                                                    "max_samples", "1")
        if not limit >= 2:
            raise ValueError(f"max_samples must be at least 2; got {describe(max_samples)}")
        if n_t > limit:
            raise ValueError(f"T has {n_t} samples, more than max_samples = {limit:.4g} "
                             "(controllers.timeresp.MAX_SAMPLES by default): use a larger step "
                             "or a shorter grid, or raise max_samples explicitly")
        S, wheels = self.system, self.wheels
        nw, n_u = wheels.n_wheels, self._n_u
        U = _check_inputs(U, n_u, n_t, self.inputs)
        n_lin = self.linear_loop.nstates
        X0 = _check_state(X0, n_lin)
        dt = None if S.isdtime(strict=True) else float((T[-1] - T[0]) / (n_t - 1))
        if dt is None and abs(float(T[1] - T[0]) - float(S.dt)) > 1e-6 * float(S.dt):
            raise ValueError(f"T must have the simulator's step dt = {float(S.dt)!r} s (the "
                             f"digital loop's); got a step of {float(T[1] - T[0])!r} s")
        if dt is not None:
            steps = np.diff(T)
            if np.max(np.abs(steps - dt)) > 1e-6 * dt + 8 * np.finfo(float).eps * np.max(
                    np.abs(T)):
                raise ValueError("T must be evenly spaced [s]; got steps from "
                                 f"{steps.min()!r} to {steps.max()!r} s")
        # initial absolute momenta: h_abs = h + J_s g . omega(0)
        C, D = np.asarray(S.C, dtype=float), np.asarray(S.D, dtype=float)
        X0_S = np.concatenate([X0, np.zeros(nw)])
        h_rows = self._h_rows
        h_start = C[h_rows] @ X0_S + D[h_rows, :n_u] @ U[:, 0]      # -J_s g . omega(0)
        X0_S[n_lin:] = np.array([w.initial_momentum for w in wheels.wheels]) - h_start
        shape = (nw, n_t)
        E, torque_sat, momentum_sat = np.zeros(shape), np.zeros(shape, bool), np.zeros(shape,
                                                                                       bool)
        if S.nstates <= _SEGMENTS_FROM_START:
            # small loops: every sample by segments, the first in the free mode
            Y = np.empty((S.noutputs, n_t))
            self._nonlinear_run(self._modes(dt), 0, U, X0_S, Y, E, torque_sat, momentum_sat)
            with np.errstate(invalid="ignore"):
                if not np.all(np.abs(Y) < _OVERFLOW):
                    raise FloatingPointError("simulation with wheels overflowed: the loop's "
                                             "response leaves the float64 range")
        else:
            # the linear loop by the simulator (O(n) per sample), segments from the first
            # sample where a wheel leaves it
            Y = self._simulator(dt).outputs(T, np.vstack([U, np.zeros(shape)]), X0_S)
            c_lin, h_lin = wheels.allocation @ Y[self._tc_rows], Y[h_rows]
            E, torque_sat, momentum_sat = _deviations(wheels, c_lin, h_lin)
            active = np.flatnonzero(np.any(E != 0.0, axis=0))
            if active.size:
                self._nonlinear_run(self._modes(dt), int(active[0]), U, X0_S, Y, E,
                                    torque_sat, momentum_sat)
        return self._result(T, U, Y, E, torque_sat, momentum_sat)

    def _nonlinear_run(self, modes: _Modes, k0, U, X0, Y, E, torque_sat, momentum_sat):
        """Overwrite the samples from k0 on (outputs Y, deviations E, flags) with the wheels'
        response (module docstring): runs of samples in which every wheel stays in one affine
        mode are one segment of S with that mode's feedback, evolved exactly; samples whose
        deviation is not affine (several wheels scaled together), or where modes chatter, are
        stepped one at a time (in their mode, or with the deviation held if it is not
        affine)."""
        n_t, nw = U.shape[1], self.wheels.n_wheels
        with one_blas_thread(), np.errstate(over="ignore", invalid="ignore"):
            x = X0
            for k in range(0, k0, modes.longest):      # the linear loop's state at k0
                stop = min(k + modes.longest, k0)
                x = modes.segment(modes.free, x, U[:, k:stop + 1])[:, -1]
            k, stepping, horizon, key = k0, 0, modes.first, None
            while k < n_t:
                if key is None:                         # the mode at sample k
                    c, h = modes.commands(x[:, None], U[:, k:k + 1])
                    key, ts, ms = modes.key(c, h)
                    key, ts, ms = key[:, 0], ts[:, 0], ms[:, 0]
                affine = modes.affine(key)
                if stepping or k == n_t - 1 or not affine:
                    if affine:                          # one sample in its mode
                        out = modes.outputs(key, x[:, None], U[:, k:k + 1])[:, 0]
                        e = out[2 * nw:3 * nw]
                        if k < n_t - 1:
                            x = modes.segment(key, x, U[:, k:k + 2])[:, -1]
                    else:                               # e held over the step
                        c, h = modes.commands(x[:, None], U[:, k:k + 1])
                        e = self.wheels.applied_torques(c[:, 0], h[:, 0])[0] - c[:, 0]
                        out = modes.held_outputs(x, U[:, k], e)
                        if k < n_t - 1:
                            x = modes.step(x, U[:, k], U[:, k + 1], e)
                    E[:, k], torque_sat[:, k], momentum_sat[:, k] = e, ts, ms
                    Y[:, k] = out[3 * nw:]
                    key = None
                    k, stepping = k + 1, max(stepping - 1, 0)
                    continue
                stop = min(k + horizon, n_t - 1)           # the segment's steps: k .. stop-1
                Z = modes.segment(key, x, U[:, k:stop + 1])           # x_k .. x_stop
                out = modes.outputs(key, Z, U[:, k:stop + 1])         # [c; h; e; y]
                keys, tss, mss = modes.key(out[:nw], out[nw:2 * nw])
                same = np.all(keys[:, :-1] == key[:, None], axis=0)
                # the first sample's mode is the one just chosen, whatever its round-off
                j = stop - k if same[1:].all() else 1 + int(np.argmin(same[1:]))
                E[:, k:k + j] = out[2 * nw:3 * nw, :j]
                torque_sat[:, k:k + j], momentum_sat[:, k:k + j] = tss[:, :j], mss[:, :j]
                torque_sat[:, k], momentum_sat[:, k] = ts, ms
                Y[:, k:k + j] = out[3 * nw:, :j]
                x = Z[:, j].copy()
                # the mode at k + j, from its exact state x_(k+j) (the old mode acted before)
                key, ts, ms = keys[:, j], tss[:, j], mss[:, j]
                switched = j < stop - k
                stepping = _CHATTER_STEPS if j == 1 and switched else 0
                # the next segment: twice this one's length (a mode that lasted j samples is
                # likely followed by one of similar length: limit cycles), doubled while it lasts
                horizon = min(max(2 * j, _SHORTEST_SEGMENT) if switched else 2 * horizon,
                              modes.longest)
                k += j
                if not np.all(np.abs(x) < _OVERFLOW):
                    raise FloatingPointError("simulation with wheels overflowed: the loop's "
                                             "response leaves the float64 range")

    def _modes(self, dt) -> _Modes:
        key = None if dt is None else round(dt, 15)
        if key not in self._mode_cache:
            simulator = self._simulators.get(key)
            if simulator is not None:       # its exact discrete matrices, if it has them
                free = (simulator.Ad, simulator.Bd0, simulator.Bd1)
            elif self.system.isdtime(strict=True):
                B = np.asarray(self.system.B, dtype=float)
                free = (np.asarray(self.system.A, dtype=float), B, np.zeros_like(B))
            else:
                with one_blas_thread():
                    free = discretise(np.asarray(self.system.A, dtype=float),
                                      np.asarray(self.system.B, dtype=float), dt, "linear")
            self._mode_cache[key] = _Modes(self, free, dt)
        return self._mode_cache[key]

    def _result(self, T, U, Y, E, torque_sat, momentum_sat) -> WheelResponse:
        """The response's signals (S's outputs, then those that follow from them and the
        deviation e) and the summary fields."""
        wheels, ch, S = self.wheels, self.channels, self.system
        dt = float((T[-1] - T[0]) / (T.size - 1))
        n_p = len(S.output_labels) - ch.n_axes - wheels.n_wheels
        command = Y[self._tc_rows]                             # the controller's torque
        h = Y[self._h_rows]
        wheel_command = wheels.allocation @ command
        wheel_torque = wheel_command + E
        rows = [Y[:n_p], command, command + wheels.distribution @ E]
        labels = list(S.output_labels)[:n_p] + list(S.output_labels)[n_p:n_p + ch.n_axes]
        labels += list(ch.torques)
        J_s = wheels.spin_inertias
        for j, name in enumerate(wheels.names):
            rows += [wheel_command[j:j + 1], wheel_torque[j:j + 1], h[j:j + 1]]
            labels += [name + "_torque_command", name + "_torque", name + "_momentum"]
            if J_s[j] > 0:
                rows.append(h[j:j + 1] / J_s[j])
                labels.append(name + "_speed")
            rows += [torque_sat[j:j + 1].astype(float), momentum_sat[j:j + 1].astype(float)]
            labels += [name + "_torque_saturated", name + "_momentum_saturated"]
        response = control.TimeResponseData(
            T, np.vstack(rows), None, U, issiso=False, output_labels=labels,
            input_labels=self.inputs, sysname="wheel_loop",
            title="Simulated response of wheel_loop", trace_types=["forced"],
            plot_inputs=True, squeeze=False)
        any_flag = np.any(torque_sat | momentum_sat, axis=0)
        held = slice(0, T.size - 1)          # each sample's state lasts until the next one
        limits = wheels.momentum_limits
        peak = np.max(np.abs(h), axis=1)
        names = wheels.names

        def per_wheel(values):
            return {name: float(v) for name, v in zip(names, values)}

        with np.errstate(invalid="ignore"):
            fraction = np.where(np.isinf(limits), math.inf, (limits - peak) / limits)
        first = np.flatnonzero(any_flag)
        return WheelResponse(
            response=response, wheels=wheels, saturated=bool(first.size),
            first_saturation=float(T[first[0]]) if first.size else None,
            time_saturated=float(np.count_nonzero(any_flag[held]) * dt),
            time_torque_saturated=per_wheel(np.count_nonzero(torque_sat[:, held], axis=1) * dt),
            time_momentum_saturated=per_wheel(np.count_nonzero(momentum_sat[:, held], axis=1)
                                              * dt),
            peak_momentum=per_wheel(peak), momentum_margin=per_wheel(limits - peak),
            momentum_margin_fraction=per_wheel(fraction),
            peak_torque=per_wheel(np.max(np.abs(wheel_torque), axis=1)))


class _Modes:
    """The wheels' affine modes, for the segments of :meth:`WheelLoop._nonlinear_run`.

    Per wheel i a mode is (a_i, b_i, s_i): a_i = 1 when the motor does not follow the command
    (torque-clipped or held at the momentum limit), b_i in {-1, 0, 1} the sign of a clipped
    motor torque +-tau_i, s_i = sign(h_i) for Coulomb friction (0 without it). The wheels'
    commands c = C_c x + D_c u and momenta h = C_h x + D_h u are outputs of S (state x, loop
    inputs u; no feedthrough of e), so in a mode the deviation is affine,

        e = K x + K_u u + g,   K = -diag(a) C_c + diag(c_v / J_s) C_h,
        K_u = -diag(a) D_c + diag(c_v / J_s) D_h,   g = b tau + c_c s,

    and S with it is LTI: x' = (A + B_e K) x + (B_u + B_e K_u) u + B_e g, discretised exactly
    with u linear between samples and g constant (:func:`.discretise`; a digital loop's S is
    discrete: x+ = (A + B_e K) x + (B_u + B_e K_u) u + B_e g). The free mode without viscous
    friction is S itself (the simulator's matrices). The "scale" rule with two or more wheels
    and one saturated is not affine (c / max_i |c_i| / tau_i): those samples are stepped with
    e held.
    """

    def __init__(self, loop: WheelLoop, free, dt: float | None):
        wheels, S = loop.wheels, loop.system
        nw, n_u = wheels.n_wheels, loop._n_u
        self.wheels, self.nw, self.n_u, self.dt = wheels, nw, n_u, dt
        A, B, C, D = (np.asarray(M, dtype=float) for M in (S.A, S.B, S.C, S.D))
        self.A, self.B_u, self.B_e, self.C = A, B[:, :n_u], B[:, n_u:], C
        self.Du, self.De = D[:, :n_u], D[:, n_u:]
        P = wheels.allocation
        self.Cc, self.Dc = P @ C[loop._tc_rows], P @ D[loop._tc_rows, :n_u]
        self.Ch, self.Dh = C[loop._h_rows], D[loop._h_rows, :n_u]
        self.discrete = S.isdtime(strict=True)
        # S's own exact discrete matrices (first-order hold): the free mode and the held-e step
        self.Ad, self.Bd0, self.Bd1 = free
        self.tau = wheels.torque_limits[:, None]
        self.hmax = wheels.momentum_limits[:, None]
        self.cc = np.array([w.coulomb_friction for w in wheels.wheels])[:, None]
        self.cv = np.array([w.viscous_friction / w.spin_inertia if w.viscous_friction else 0.0
                            for w in wheels.wheels])[:, None]
        self.scaled = wheels.saturation == "scale" and nw > 1
        self.has_coulomb = (self.cc != 0.0).astype(float)
        n = A.shape[0]
        levels = math.log2(_LONGEST_SEGMENT) + 1
        self.longest = int(np.clip(2 ** math.floor(math.log2(_SEGMENT_WORK / (levels * n * n))),
                                   _SHORTEST_SEGMENT, _LONGEST_SEGMENT))
        self.first = min(_FIRST_SEGMENT, self.longest)
        self.free = np.zeros(3 * nw + 1)
        self._cache: dict = {}
        self._constant_cache: dict = {}

    def commands(self, x: np.ndarray, u: np.ndarray):
        """The wheels' commands c and momenta h at states x (n, N) and inputs u (n_u, N)."""
        return self.Cc @ x + self.Dc @ u, self.Ch @ x + self.Dh @ u

    def step(self, x, u0, u1, e) -> np.ndarray:
        """One step with e held (zero-order hold) and u linear (first-order hold)."""
        nu = self.n_u
        x1 = self.Ad @ x + self.Bd0[:, :nu] @ u0 + self.Bd1[:, :nu] @ u1
        return x1 + (self.Bd0[:, nu:] + self.Bd1[:, nu:]) @ e

    def key(self, c: np.ndarray, h: np.ndarray):
        """Mode of each sample, shape (3 n_wheels + 1, n_samples): a, b, s, then 1 where the
        sample is not affine; and the flags torque_saturated, momentum_saturated (n_wheels,
        n_samples) of :meth:`WheelSet.applied_torques`."""
        nw = c.shape[0]
        over = np.abs(c) > self.tau
        # the motor torque m has the sign of c (c, or +-tau clipped), so m h <= 0 iff c h <= 0
        gated = (np.abs(h) >= self.hmax) & (c * h <= 0.0)
        key = np.empty((3 * nw + 1, c.shape[1]))
        np.logical_or(gated, over, out=key[:nw])
        np.multiply(np.sign(c), over > gated, out=key[nw:2 * nw])
        np.multiply(np.sign(h), self.has_coulomb, out=key[2 * nw:3 * nw])
        if self.scaled:
            key[-1] = over.any(axis=0)
        else:
            key[-1] = 0.0
        key += 0.0                     # -0.0 -> 0.0: one cache entry per mode
        return key, over, gated

    def affine(self, key: np.ndarray) -> bool:
        """Whether a sample's mode is affine."""
        return key[-1] == 0.0

    def segment(self, key: np.ndarray, x: np.ndarray, U: np.ndarray) -> np.ndarray:
        """States x_k, ..., x_k+L of a segment of one mode from x_k and the inputs u_k, ...,
        u_k+L (n_u, L + 1).

        x_(i+1) = Phi x_i + q_i, q_i = G0 v_i + G1 v_(i+1), v = [u; g] (the mode's exact
        discrete matrices), is an affine recursion; its prefix (scan) by doubling,
        Y_i <- Y_i + Phi^d Y_(i-d) for d = 1, 2, 4, ... <= L, from Y = [x_k, q_0, ..., q_(L-1)],
        gives Y_i = Phi^i x_k + sum_(j<i) Phi^(i-1-j) q_j in ceil(log2(L + 1)) matrix products
        over the whole segment [1]_ (the powers Phi^(2^l), formed by squaring, are kept per
        mode).

        References
        ----------
        .. [1] W. D. Hillis, G. L. Steele, "Data parallel algorithms", Comm. ACM 29(12),
           1170-1183, 1986 (the prefix computation by doubling).
        """
        mode = self._mode(key)
        q_g = self._constants(key)[1]
        L = U.shape[1] - 1
        # samples as rows: the shifted blocks Y[d:], Y[:-d] are contiguous (40 % faster for
        # short segments than columns); returned transposed, a view
        Y = np.empty((L + 1, x.size))
        Y[0] = x
        np.matmul(U[:, :-1].T, mode.G0u_T, out=Y[1:])
        if mode.G1u_T is not None:
            Y[1:] += U[:, 1:].T @ mode.G1u_T
        if q_g is not None:
            Y[1:] += q_g
        d, level = 1, 0
        while d <= L:
            Y[d:] += Y[:-d] @ mode.powers_T[level]
            d, level = 2 * d, level + 1
        return Y.T

    def outputs(self, key: np.ndarray, X: np.ndarray, U: np.ndarray) -> np.ndarray:
        """[c; h; e; y] at states X (n, N) and inputs U (n_u, N) in a mode: the wheels'
        commands and momenta, the deviation e = K x + K_u u + g and S's outputs
        y = C x + D_u u + D_e e, from one product with each of X and U."""
        mode = self._mode(key)
        out = mode.Mx @ X + mode.Mu @ U
        const = self._constants(key)[0]
        if const is not None:
            out += const
        return out

    def held_outputs(self, x: np.ndarray, u: np.ndarray, e: np.ndarray) -> np.ndarray:
        """[c; h; e; y] at one sample with a given e (a sample not in an affine mode)."""
        c, h = self.commands(x[:, None], u[:, None])
        y = self.C @ x + self.Du @ u + self.De @ e
        return np.concatenate([c[:, 0], h[:, 0], e, y])

    def _constants(self, key: np.ndarray):
        """(the outputs' constant [0; 0; g; D_e g], column; the scan's G g), None where g = 0,
        built once per key."""
        cache = key.tobytes()
        if cache not in self._constant_cache:
            nw = self.nw
            b, s = key[nw:2 * nw], key[2 * nw:3 * nw]
            g = np.where(b != 0.0, b * np.where(b != 0.0, self.tau[:, 0], 0.0), 0.0) \
                + self.cc[:, 0] * s
            if not g.any():
                self._constant_cache[cache] = (None, None)
            else:
                const = np.concatenate([np.zeros(2 * nw), g, self.De @ g])[:, None]
                self._constant_cache[cache] = (const, self._mode(key).Gg @ g)
        return self._constant_cache[cache]

    def _mode(self, key: np.ndarray) -> _Mode:
        """A mode's matrices (they depend on a only), built once."""
        nw, nu = self.nw, self.n_u
        a = key[:nw]
        cache = a.tobytes()
        if cache not in self._cache:
            K = -a[:, None] * self.Cc + self.cv * self.Ch
            Ku = -a[:, None] * self.Dc + self.cv * self.Dh
            if not K.any() and not Ku.any():
                Phi, G0, G1 = self.Ad, self.Bd0, None if self.discrete else self.Bd1
            else:
                A_M = self.A + self.B_e @ K
                B_M = np.hstack([self.B_u + self.B_e @ Ku, self.B_e])
                if self.discrete:
                    Phi, G0, G1 = A_M, B_M, None
                else:
                    Phi, G0, G1 = (M[0] for M in discretise_blocks(A_M[None], B_M[None],
                                                                    self.dt, "linear"))
            # g is constant over the step: its first-order hold is the zero-order hold
            Gg = G0[:, nu:] if G1 is None else G0[:, nu:] + G1[:, nu:]
            powers = [Phi]
            for _ in range(int(math.log2(self.longest))):
                powers.append(powers[-1] @ powers[-1])
            self._cache[cache] = _Mode(
                G0u_T=np.ascontiguousarray(G0[:, :nu].T),
                G1u_T=None if G1 is None else np.ascontiguousarray(G1[:, :nu].T), Gg=Gg,
                powers_T=[np.ascontiguousarray(M.T) for M in powers],
                Mx=np.vstack([self.Cc, self.Ch, K, self.C + self.De @ K]),
                Mu=np.vstack([self.Dc, self.Dh, Ku, self.Du + self.De @ Ku]))
        return self._cache[cache]


@dataclasses.dataclass(frozen=True)
class _Mode:
    """One mode's matrices (:class:`_Modes`): discrete input matrices of u, transposed (G1u_T
    None for a digital loop), and of the constant g, the powers Phi^(2^l), transposed, and the
    output maps [c; h; e; y] = Mx x + Mu u + [0; 0; g; D_e g]."""

    G0u_T: np.ndarray
    G1u_T: np.ndarray | None
    Gg: np.ndarray
    powers_T: list
    Mx: np.ndarray
    Mu: np.ndarray


def _deviations(wheels: WheelSet, c: np.ndarray, h: np.ndarray):
    """e = w - c for commands c and momenta h of shape (n_wheels, n_samples), with the limit
    flags (:meth:`WheelSet.applied_torques`, vectorised over the samples)."""
    w, torque_sat, momentum_sat = wheels.applied_torques(c, h)
    return w - c, torque_sat, momentum_sat


def _with_deviation_inputs(plant, ch: Channels, deviations) -> control.StateSpace:
    """The plant with inputs ``deviations`` entering exactly as its torques do."""
    inputs = list(plant.input_labels)
    clash = [n for n in deviations if n in inputs]
    if clash:
        raise ValueError(f"plant must not have inputs named {clash} (reserved for the wheels' "
                         "torque deviation)")
    i_t = [inputs.index(t) for t in ch.torques]
    B = np.asarray(plant.B, dtype=float)
    D = np.asarray(plant.D, dtype=float)
    return control.ss(plant.A, np.hstack([B, B[:, i_t]]), plant.C, np.hstack([D, D[:, i_t]]),
                      plant.dt, inputs=inputs + list(deviations),
                      outputs=list(plant.output_labels), states=list(plant.state_labels),
                      name=plant.name)


def _check_time(T) -> np.ndarray:
    try:
        T = np.asarray(T, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"T must be an array of sample times [s]; got {describe(T)}") from exc
    if T.ndim != 1 or T.size < 2:
        raise ValueError(f"T must be 1-D with at least 2 samples [s]; got shape {T.shape}")
    if not np.all(np.isfinite(T)):
        raise ValueError("T must be finite [s]; got NaN or inf")
    if not T[-1] > T[0]:
        raise ValueError(f"T must be increasing [s]; got T[0] = {T[0]!r}, T[-1] = {T[-1]!r}")
    return T


def _check_inputs(U, n_u: int, n_t: int, names) -> np.ndarray:
    if U is None:
        return np.zeros((n_u, n_t))
    try:
        U = np.asarray(U, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"U must be an array of the loop's inputs {names}; got "
                        f"{describe(U)}") from exc
    if U.ndim == 0:
        U = np.full((n_u, n_t), float(U))
    elif U.ndim == 1 and n_u == 1 and U.size == n_t:
        U = U[None, :]
    if U.shape != (n_u, n_t):
        raise ValueError(f"U must have shape (n_inputs, n_samples) = ({n_u}, {n_t}) for the "
                         f"loop's inputs {names}; got shape {U.shape}")
    if not np.all(np.isfinite(U)):
        raise ValueError("U must be finite; got NaN or inf")
    return U


def _check_state(X0, n: int) -> np.ndarray:
    if X0 is None:
        return np.zeros(n)
    try:
        X0 = np.asarray(X0, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TypeError(f"X0 must be an array of {n} states; got {describe(X0)}") from exc
    if X0.ndim == 0:
        X0 = np.full(n, float(X0))
    if X0.shape != (n,) or not np.all(np.isfinite(X0)):
        raise ValueError(f"X0 must be {n} finite states (the linear loop's); got shape "
                         f"{X0.shape}")
    return X0


@warns_long_delay
def simulate_wheels(plant: control.StateSpace, controller: control.StateSpace,
                    wheels: WheelSet, T, U=None, X0=None, *, delay: float = 0.0,
                    computation_delay: bool = False, dt: float | None = None,
                    max_samples: int | None = None) -> WheelResponse:
    """One simulation of the loop with wheels: ``WheelLoop(plant, controller, wheels, delay=...,
    computation_delay=..., dt=...).simulate(T, U, X0)`` (keep the WheelLoop to simulate it
    again without its set-up).

    See Also
    --------
    WheelLoop, WheelLoop.simulate
    """
    return WheelLoop(plant, controller, wheels, delay=delay, computation_delay=computation_delay,
                     dt=dt).simulate(T, U, X0, max_samples=max_samples)
