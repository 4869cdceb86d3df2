"""Closing the attitude loop by signal names, and the loop transfer function.

The loop transfer function is taken with the loop broken at the plant's torque input and the
negative-feedback convention, L(s) = -sum_i K_i(s) P_i(s), where P_i is the transfer from torque to
the i-th measured plant output and K_i the controller's transfer from that measurement to torque.
For a PD controller on a rigid hub, L(s) = (Kp + Kd s) / (J s^2).

A loop delay tau (the torque the plant receives is the command of tau earlier,
:mod:`controllers.delay`) multiplies L by e^(-j omega tau) exactly; for a digital controller on a
state-space plant the sampled plant with the delayed hold is used instead (the modified
z-transform, exact at the samples).
"""
from __future__ import annotations

import math
import warnings

import control
import numpy as np

from .delay import DelayedSampledPlant, delayed_closed_loop, total_delay, warns_long_delay
from .frequency import ModalEvaluator, modal_evaluator, siso_zeros
from .arguments import describe, frequency_grid
from .signals import (OMEGA, THETA, TORQUE, check_controller, check_pair, check_plant,
                      fed_back_signals, is_digital, reference_inputs, signal_names)
from .threads import limits_blas_threads, total_states

__all__ = ["LoopTransfer", "close_loop", "loop_frequency_response", "controller_roots",
           "resonance_points", "window_angle_steps", "UNDAMPED_LADDER", "loops_at_a_time",
           "sensitivity", "compiled_kernel"]

#: Relative offsets from an undamped pole at which :func:`resonance_points` adds points (on both
#: sides): between the innermost point of its half-power window (3.7e-9) and round-off.
UNDAMPED_LADDER = 10.0 ** -np.arange(9.0, 13.01, 0.5)

_kernel = None


def _compiled():
    """The compiled loop evaluation (:mod:`controllers._loop_kernel`), imported (compiled, or
    loaded from the disk cache) on first use; None when numba is not installed: the
    evaluators' numpy path runs instead."""
    global _kernel
    if _kernel is None:
        try:
            from . import _loop_kernel
        except ImportError:              # numba not installed
            _kernel = False
        except Exception as error:       # numba installed but unusable (a broken install)
            warnings.warn(f"flexsat: the compiled loop evaluation could not be loaded "
                          f"({error!s:.200}); evaluating loops with numpy instead",
                          RuntimeWarning, stacklevel=3)
            _kernel = False
        else:
            _kernel = _loop_kernel
    return _kernel or None


def compiled_kernel():
    """The module of compiled loop functions (:mod:`controllers._loop_kernel`), or None when
    numba is not available: loops are then evaluated by the numpy path, to the same values
    within round-off."""
    return _compiled()


def sensitivity(L: np.ndarray) -> np.ndarray:
    """The sensitivity at the loop's inputs, S = (I + L)^-1, at each frequency.

    Parameters
    ----------
    L : ndarray, shape (f, m, m), complex
        The loop broken at its m inputs at f frequencies (negative-feedback convention).

    Returns
    -------
    ndarray, shape (f, m, m), complex
        From an LU factorisation with partial pivoting either way: compiled, one frequency at
        a time, when numba is available, else numpy's batched inverse (the same arithmetic, to
        round-off); inf or NaN where I + L is singular or L is not finite (the compiled path;
        numpy's raises LinAlgError on an exactly singular I + L).
    """
    L = np.asarray(L)
    m = L.shape[1]
    kernel = _compiled()
    if kernel is not None:
        S = np.empty(L.shape, dtype=complex)
        kernel.sensitivity(np.ascontiguousarray(L, dtype=complex), S)
        return S
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return np.linalg.inv(np.eye(m) + L)  # LU with the identity as right-hand side


def loops_at_a_time(L: np.ndarray) -> np.ndarray:
    """Every loop-at-a-time function of loop values, L_i = 1 / S_ii - 1 (:func:`sensitivity`).

    Parameters
    ----------
    L : ndarray, shape (f, m, m), complex
        The loop broken at its m inputs at f frequencies (negative-feedback convention).

    Returns
    -------
    ndarray, shape (f, m), complex
        L_i: the loop broken at input i with the other loops closed (an injection at input i
        returns through 1 / (1 + L_i) = S_ii; Skogestad & Postlethwaite, Multivariable
        Feedback Control, 2nd ed., sec. 9.3).
    """
    S = sensitivity(L)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return 1.0 / np.diagonal(S, axis1=1, axis2=2) - 1.0


@warns_long_delay
def close_loop(plant, controller: control.StateSpace, *, delay: float = 0.0,
               computation_delay: bool = False, dt: float | None = None):
    """Close the attitude loop by signal names.

    Parameters
    ----------
    plant : control.StateSpace or control.FrequencyResponseData
        Continuous-time plant (input ``'torque'``, outputs ``'theta'``, ``'omega'``, ...; or the
        three-axis signals ``'torque_x'``, ..., ``'omega_z'``, :mod:`controllers.signals`). An
        FRD plant (e.g. the exact distributed model) gives the closed loop's frequency response
        on its grid; it needs ``'theta'`` or ``'omega'`` (the other is j w times / divided by
        it; planar FRDs only).
    controller : control.StateSpace
        Controller with output ``'torque'`` (three-axis: ``'torque_x'``, ``'torque_y'``,
        ``'torque_z'``); its inputs are plant outputs (measurements) and
        reference inputs (names containing ``'ref'`` or ``'ff'``). If the controller is discrete-time
        (``dt`` > 0), the plant is discretised with a zero-order hold at that ``dt`` and the
        result is the exact sampled-data loop at the sampling instants (every plant input,
        including disturbances, is then held constant over a sample). FRD plants need a
        continuous controller.
    delay : float, s
        Loop delay: the plant receives the torque commanded ``delay`` earlier (0: none). A
        digital controller gives the exact delayed sampled-data loop (delay-line states; see
        :func:`controllers.delay.delayed_closed_loop`); a continuous one needs ``dt``: its
        delayed loop is infinite-dimensional and is returned discretised on the step dt, the
        command held and delayed by delay - dt/2 (error O(dt^2), dt <= 2 delay). An FRD plant
        gets the factor e^(-j omega delay) exactly.
    computation_delay : bool
        Add one sample of a digital controller to the delay (its command applied one sample
        after the measurements it is computed from).
    dt : float, s, optional
        Step of the delayed loop of a continuous controller (only then).

    Returns
    -------
    control.StateSpace or control.FrequencyResponseData
        Inputs: the controller's reference inputs, then the plant's inputs other than the
        torques. Outputs: every plant output, then the torque(s). States: plant states,
        controller states. With u the torque(s), y_m the measurements and d the other plant
        inputs: u = (I - K_y D_mt)^-1 (K_r r + K_y (C_m x + D_md d)), the algebraic loop through
        the feedthroughs solved exactly (an error if I - K_y D_mt is singular). With a delay the
        torque outputs are the torques the plant receives (the delayed commands) and the
        states end with the delay line.
    """
    frd = isinstance(plant, control.FrequencyResponseData)
    if frd:
        check_plant(plant, allow_frd=True)
        check_controller(controller)
    else:
        ch = check_pair(plant, controller)
    tau = total_delay(controller, delay, computation_delay)
    if dt is not None and (tau == 0.0 or is_digital(controller) or frd):
        raise ValueError("dt [s] is the step of the delayed loop of a continuous controller on a "
                         "state-space plant; got dt with "
                         + ("no delay" if tau == 0.0 else "a digital controller or an FRD plant"))
    if frd:
        return _close_loop_frd(plant, controller, tau)
    if tau > 0.0:
        return delayed_closed_loop(plant, controller, tau, dt=dt)
    measured = fed_back_signals(plant, controller)
    refs = reference_inputs(controller, signal_names(plant, "output"))
    p_in, p_out = signal_names(plant, "input"), signal_names(plant, "output")
    disturbances = [n for n in p_in if n not in ch.torques]
    if is_digital(controller):
        plant = control.c2d(plant, controller.dt, method="zoh")
    A, B, C, D = _closed_loop_matrices(plant, controller, ch.torques, measured, refs,
                                      disturbances)
    n_p, n_c = plant.nstates, controller.nstates
    inputs = refs + disturbances
    outputs = p_out + list(ch.torques)
    states = [f"plant_x{i}" for i in range(n_p)] + [f"controller_x{i}" for i in range(n_c)]
    return control.ss(A, B, C, D, plant.dt, inputs=inputs, outputs=outputs, states=states,
                      name="closed_loop")


def _closed_loop_matrices(plant: control.StateSpace, controller: control.StateSpace, torques,
                         measured, refs=(), disturbances=(), *, cut: int | None = None
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The state-space matrices (A, B, C, D) of :func:`close_loop`'s undelayed loop, as plain
    arrays (no signal names checked or attached).

    Parameters
    ----------
    plant : control.StateSpace
        The plant, already sampled where the controller is digital.
    controller : control.StateSpace
    torques, measured, refs, disturbances : sequence of str
        The plant's torque inputs, the measurements fed back, the controller's reference
        inputs and the plant's other inputs (the closed loop's inputs: refs, then
        disturbances).
    cut : int, optional
        A torque output of the controller (its index) not fed back: the loop with that
        torque's loop open and the others closed (its poles are those of the loop-at-a-time
        function of that torque that L does not have).

    Returns
    -------
    A, B, C, D : ndarray
        As :func:`close_loop` returns them (states: plant, then controller).
    """
    p_in, p_out = list(plant.input_labels), list(plant.output_labels)
    c_in = list(controller.input_labels)
    Ap, Bp, Cp, Dp = (np.asarray(M, dtype=float) for M in (plant.A, plant.B, plant.C, plant.D))
    Ac, Bc, Cc, Dc = (np.asarray(M, dtype=float)
                      for M in (controller.A, controller.B, controller.C, controller.D))
    if cut is not None:
        Cc, Dc = Cc.copy(), Dc.copy()
        Cc[cut], Dc[cut] = 0.0, 0.0
    i_t = [p_in.index(n) for n in torques]
    i_d = [p_in.index(n) for n in disturbances]
    i_m = [p_out.index(n) for n in measured]
    j_m = [c_in.index(n) for n in measured]
    j_r = [c_in.index(n) for n in refs]
    m = len(i_t)
    # u = Cc xc + Dr r + Dy y_m,  y_m = Cm xp + Dmt u + Dmd d: solve the algebraic loop
    # (I - Dy Dmt) u = Cc xc + Dr r + Dy (Cm xp + Dmd d)
    Dy = Dc[:, j_m]
    gain = np.eye(m) - Dy @ Dp[np.ix_(i_m, i_t)]
    if abs(np.linalg.det(gain)) < 1e-12:
        raise ValueError("algebraic loop: the controller's direct feedthrough times the plant's "
                         "feedthrough from torque to the measurements makes I - Dc Dp singular")
    # u = F [xp; xc; r; d]
    F = np.linalg.solve(gain, np.hstack([Dy @ Cp[i_m], Cc, Dc[:, j_r],
                                         Dy @ Dp[np.ix_(i_m, i_d)]]))
    n_p, n_c = Ap.shape[0], Ac.shape[0]
    n_r = len(j_r)
    # the plant with the torque substituted, then the controller driven by r and y_m
    Fx, Fr, Fd = F[:, : n_p + n_c], F[:, n_p + n_c: n_p + n_c + n_r], F[:, n_p + n_c + n_r:]
    bt = Bp[:, i_t]
    A_top = np.hstack([Ap, np.zeros((n_p, n_c))]) + bt @ Fx
    ym_x = np.hstack([Cp[i_m], np.zeros((len(i_m), n_c))]) + Dp[np.ix_(i_m, i_t)] @ Fx
    A_bot = np.hstack([np.zeros((n_c, n_p)), Ac]) + Bc[:, j_m] @ ym_x
    B_top = np.hstack([bt @ Fr, Bp[:, i_d] + bt @ Fd])
    ym_r = Dp[np.ix_(i_m, i_t)] @ Fr
    ym_d = Dp[np.ix_(i_m, i_d)] + Dp[np.ix_(i_m, i_t)] @ Fd
    B_bot = np.hstack([Bc[:, j_r] + Bc[:, j_m] @ ym_r, Bc[:, j_m] @ ym_d])
    C = np.vstack([np.hstack([Cp, np.zeros((Cp.shape[0], n_c))]) + Dp[:, i_t] @ Fx, Fx])
    D = np.vstack([np.hstack([Dp[:, i_t] @ Fr, Dp[:, i_d] + Dp[:, i_t] @ Fd]),
                   np.hstack([Fr, Fd])])
    return np.vstack([A_top, A_bot]), np.vstack([B_top, B_bot]), C, D


def _close_loop_frd(plant: control.FrequencyResponseData, controller: control.StateSpace,
                    delay: float = 0.0) -> control.FrequencyResponseData:
    """Closed-loop frequency response on an FRD plant's grid (see :func:`close_loop`)."""
    check_plant(plant, allow_frd=True)
    check_controller(controller)
    if is_digital(controller):
        raise ValueError("close_loop on a FrequencyResponseData plant needs a continuous "
                         f"controller; got dt={controller.dt}")
    if delay > 0.0:
        # the plant receives the delayed torque: its torque column times e^(-j omega delay)
        # (the torque outputs below are then the received torques, delayed likewise)
        data = np.array(plant.frdata, dtype=complex)
        i_t = list(plant.input_labels).index(TORQUE)
        data[:, i_t, :] *= np.exp(-1j * np.asarray(plant.omega, dtype=float) * delay)
        plant = control.frd(data, plant.omega, inputs=list(plant.input_labels),
                            outputs=list(plant.output_labels), name=plant.name)
    loop = LoopTransfer(plant, controller)  # measured rows of the plant (theta/omega derived)
    p_in, p_out = signal_names(plant, "input"), signal_names(plant, "output")
    refs = reference_inputs(controller, sorted(set(p_out) | set(loop.measured)))
    disturbances = [n for n in p_in if n != TORQUE]
    omega = loop.omega
    jw = 1j * omega
    data = np.asarray(plant.frdata)[:, :, : omega.size]  # (p, m, f)
    K = modal_evaluator(controller, list(controller.input_labels), [TORQUE])(jw)[:, 0, :]  # (f, c)
    c_in = list(controller.input_labels)
    Ky = K[:, [c_in.index(n) for n in loop.measured]]  # (f, n_meas)
    Kr = K[:, [c_in.index(n) for n in refs]]  # (f, n_ref)

    def measured_rows(column: int) -> np.ndarray:  # (f, n_meas) response of y_m to one input
        rows = []
        for name in loop.measured:
            if name in p_out:
                rows.append(data[p_out.index(name), column])
            elif name == OMEGA:
                rows.append(jw * data[p_out.index(THETA), column])
            else:
                rows.append(data[p_out.index(OMEGA), column] / jw)
        return np.array(rows).T

    i_t = p_in.index(TORQUE)
    denominator = 1.0 - np.sum(Ky * measured_rows(i_t), axis=1)  # (f,)
    torque_r = Kr / denominator[:, None]  # (f, n_ref)
    torque_d = np.stack([np.sum(Ky * measured_rows(p_in.index(n)), axis=1) for n in disturbances],
                        axis=1).reshape(omega.size, len(disturbances)) / denominator[:, None]
    Pt = data[:, i_t, :].T  # (f, p)
    Pd = np.stack([data[:, p_in.index(n), :].T for n in disturbances], axis=2).reshape(
        omega.size, len(p_out), len(disturbances))
    y_r = Pt[:, :, None] * torque_r[:, None, :]
    y_d = Pt[:, :, None] * torque_d[:, None, :] + Pd
    received = np.exp(-1j * omega * delay)[:, None] if delay > 0.0 else 1.0
    response = np.concatenate([np.concatenate([y_r, y_d], axis=2),
                               (np.concatenate([torque_r, torque_d], axis=1)
                                * received)[:, None, :]], axis=1)
    return control.frd(np.moveaxis(response, 0, 2), omega, inputs=refs + disturbances,
                       outputs=p_out + [TORQUE], name="closed_loop")


class LoopTransfer:
    """The loop transfer function L(omega) = -sum_i K_i P_i at real frequencies omega [rad/s].

    The loop is broken at the plant's torque inputs, negative-feedback convention (module
    docstring); a digital controller is evaluated at z = exp(j omega T), a delay multiplies L by
    exp(-j omega tau) (or, digital on a state-space plant, gives the exact sampled plant with
    the delayed hold). The margins (:mod:`controllers.margins`) are computed on it.

    Parameters
    ----------
    plant : control.StateSpace or control.FrequencyResponseData
        The plant (an FRD for the planar loop only, interpolated between its frequencies).
    controller : control.StateSpace
        Continuous or digital, of the plant's convention.
    delay : float, s
        Loop delay tau >= 0.

    Attributes
    ----------
    ch : Channels
        The loop's signal convention.
    measured : list of str
        The fed-back measurements.
    digital : bool
        A digital controller (sample time ``dt`` [s]).

    Notes
    -----
    ``loop(omega)`` gives L, shape (f,) planar or (f, m, m); :meth:`matrix` always (f, m, m);
    :meth:`broken` and :meth:`broken_all` the loop-at-a-time functions; :meth:`grid` a
    frequency grid refined around the lightly damped poles and zeros of L; :meth:`zeros` the
    zeros of one channel's loop; :meth:`loop_at_a_time_poles` the poles the loop-at-a-time
    functions have and L has not.
    """

    @warns_long_delay
    def __init__(self, plant, controller, delay: float = 0.0):
        self.ch = ch = check_pair(plant, controller, allow_frd=True)
        self.delay = float(delay)
        if ch.mimo and isinstance(plant, control.FrequencyResponseData):
            raise ValueError("three-axis loops need a StateSpace plant (a FrequencyResponseData "
                             "plant is supported for the planar loop only)")
        self.digital = is_digital(controller)
        self.dt = float(controller.dt) if self.digital else 0.0
        self.frd = isinstance(plant, control.FrequencyResponseData)
        if self.frd:
            outputs = list(plant.output_labels)
            # theta or omega alone is enough: omega(jw) = jw theta(jw)
            derivable = {THETA, OMEGA} if (THETA in outputs or OMEGA in outputs) else set()
            self.measured = [n for n in controller.input_labels
                             if n in outputs or n in derivable]
            if not self.measured:
                raise ValueError(f"controller inputs {describe(list(controller.input_labels))} "
                                 f"contain none of the plant outputs {describe(outputs)}: nothing "
                                 "is fed back")
            i_t = list(plant.input_labels).index(TORQUE)
            self.omega = np.asarray(plant.omega, dtype=float)
            if self.digital:
                self.omega = self.omega[self.omega < math.pi / self.dt]
            data = np.asarray(plant.frdata)[:, i_t, : self.omega.size]
            jw = 1j * self.omega
            rows = []
            for name in self.measured:
                if name in outputs:
                    rows.append(data[outputs.index(name)])
                elif name == OMEGA:
                    rows.append(jw * data[outputs.index(THETA)])
                else:
                    rows.append(data[outputs.index(OMEGA)] / jw)
            self.plant_data = np.array(rows, dtype=complex).reshape(len(rows), self.omega.size)
        else:
            self.measured = fed_back_signals(plant, controller)
        self.controller_ev = modal_evaluator(controller, self.measured, list(ch.torques))
        if not self.frd:
            p = control.c2d(plant, self.dt, method="zoh") if self.digital else plant
            if self.digital and self.delay > 0.0:
                # the exact sampled plant with the delayed hold (its zeros for the grid are
                # taken without the delay)
                self.plant_ev = DelayedSampledPlant(plant, self.dt, self.delay,
                                                    list(ch.torques), self.measured)
            else:
                self.plant_ev = modal_evaluator(p, list(ch.torques), self.measured)
            self._plant_discretised = p
        self.plant = plant
        self.controller = controller
        # plant and controller as modal sums: L evaluated by the compiled kernel
        self._sums = None
        if (not self.frd and isinstance(self.plant_ev, ModalEvaluator)
                and _compiled() is not None):
            plant_sums, controller_sums = (self.plant_ev.modal_sums(),
                                           self.controller_ev.modal_sums())
            if plant_sums is not None and controller_sums is not None:
                self._sums = tuple(
                    part for poles, residues, d, markov in (plant_sums, controller_sums)
                    for part in (poles, np.ascontiguousarray(residues.real),
                                 np.ascontiguousarray(residues.imag), d, markov))

    def _point(self, omega: np.ndarray) -> np.ndarray:
        omega = np.asarray(omega, dtype=float)
        if self.digital:
            return np.exp(1j * omega * self.dt)
        return 1j * omega

    def matrix(self, omega) -> np.ndarray:
        """L(j omega) = -K P, shape (f, m, m) for m torque channels (loop broken at the plant's
        torque inputs, negative-feedback convention)."""
        omega = np.atleast_1d(np.asarray(omega, dtype=float))
        if self.delay > 0.0 and not np.max(np.abs(omega), initial=0.0) <= 1e15 / self.delay:
            raise ValueError(f"delay {self.delay:.4g} s at {np.max(omega):.4g} rad/s turns the phase "
                             "by more than 1e15 rad, lost to round-off: check the delay's unit "
                             "[s]")
        z = self._point(omega)
        if self.frd:
            K = self.controller_ev(z)  # (f, m, n_meas)
            P = self._interpolated_plant(omega)  # (f, n_meas)
            if self.digital:
                # zero-order hold seen from continuous time, aliasing neglected:
                # H(jw) = (1 - exp(-jwT)) / (jwT) (Franklin, Powell & Workman, sec. 6.3)
                wT = omega * self.dt
                P = P * ((1 - np.exp(-1j * wT)) / (1j * wT))[:, None]
            if self.delay > 0.0:
                P = P * np.exp(-1j * omega * self.delay)[:, None]
            return -np.sum(K[:, 0, :] * P, axis=1)[:, None, None]
        if self._sums is not None:
            m = len(self.ch.torques)
            L = np.empty((z.size, m, m), dtype=complex)
            with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
                _compiled().loop_matrix(z - self.plant_ev.center, z - self.controller_ev.center,
                                        *self._sums, L)
        else:
            L = -(self.controller_ev(z) @ self.plant_ev(z))
        if self.delay > 0.0 and not self.digital:
            L = L * np.exp(-1j * omega * self.delay)[:, None, None]
        return L

    def __call__(self, omega) -> np.ndarray:
        """L(j omega): shape (f,) for the planar loop, (f, m, m) for a three-axis one."""
        L = self.matrix(omega)
        return L[:, 0, 0] if not self.ch.mimo else L

    def broken(self, omega, i: int) -> np.ndarray:
        """Loop-at-a-time L_i(j omega), shape (f,): the loop broken at torque input i, the other
        loops closed. With S = (I + L)^-1 the sensitivity at the plant input, an injection at
        input i returns through 1 / (1 + L_i) = S_ii, so L_i = 1 / S_ii - 1 (Skogestad &
        Postlethwaite, Multivariable Feedback Control, 2nd ed., sec. 9.3)."""
        return self.broken_all(omega)[:, i]

    def broken_all(self, omega) -> np.ndarray:
        """Every loop-at-a-time L_i(j omega) (see :meth:`broken`), shape (f, m)."""
        L = self.matrix(omega)
        if L.shape[1] == 1:
            return L[:, :, 0]
        return loops_at_a_time(L)

    def _interpolated_plant(self, omega: np.ndarray) -> np.ndarray:
        """FRD plant rows at omega: exact on its grid, in between linear in log frequency for
        log|P| and arg P (P_i (P_i+1 / P_i)^t), so the grid must resolve the plant's resonances;
        the controller is always evaluated exactly."""
        grid = self.omega
        lo, hi = grid[0] * (1 - 1e-12), grid[-1] * (1 + 1e-12)
        if np.any(omega < lo) or np.any(omega > hi):
            raise ValueError(f"frequencies must lie within the FrequencyResponseData grid "
                             f"[{grid[0]:.4g}, {grid[-1]:.4g}] rad/s; got [{omega.min():.4g}, "
                             f"{omega.max():.4g}]")
        i = np.clip(np.searchsorted(grid, omega), 1, grid.size - 1)
        t = (np.log(omega) - np.log(grid[i - 1])) / (np.log(grid[i]) - np.log(grid[i - 1]))
        P0, P1 = self.plant_data[:, i - 1], self.plant_data[:, i]
        with np.errstate(divide="ignore", invalid="ignore"):
            P = P0 * (P1 / P0) ** t
        exact = np.isclose(t, 1.0, rtol=0, atol=1e-15)
        P[:, exact] = P1[:, exact]
        return P.T

    def _controller_roots(self) -> np.ndarray:
        """Poles of the controller and zeros of each of its measurement channels."""
        return controller_roots(self.controller, self.measured, self.ch.torques[:1])

    def zeros(self, channel: int = 0) -> np.ndarray:
        """Zeros of the loop of one torque channel alone, -K_ii P_ii (z-plane for a digital
        loop; the planar loop's L): the zeros of the series connection plant -> controller
        from torque input ``channel`` to torque output ``channel``, by
        :func:`~controllers.frequency.siso_zeros` (a real eigenproblem of the loop's order,
        not the QZ of its pencil)."""
        p, c = self._plant_discretised, self.controller
        i_t = list(p.input_labels).index(self.ch.torques[channel])
        i_m = [list(p.output_labels).index(n) for n in self.measured]
        j_m = [list(c.input_labels).index(n) for n in self.measured]
        Ap, Bt, Cm, Dmt = p.A, p.B[:, [i_t]], p.C[i_m], p.D[np.ix_(i_m, [i_t])]
        Ac, Bcm = c.A, c.B[:, j_m]
        Cc, Dcm = c.C[[channel]], c.D[np.ix_([channel], j_m)]
        n_p, n_c = Ap.shape[0], Ac.shape[0]
        A = np.block([[Ap, np.zeros((n_p, n_c))], [Bcm @ Cm, Ac]])
        B = np.vstack([Bt, Bcm @ Dmt])
        C = -np.hstack([Dcm @ Cm, Cc])
        D = -Dcm @ Dmt
        z = siso_zeros(A, B, C, D)
        return z[np.isfinite(z) & (np.abs(z) < 1e12)]

    def loop_at_a_time_poles(self) -> np.ndarray:
        """Poles of each loop-at-a-time L_i that the open loop does not have: those of the loop
        with torque i not fed back (the other loops closed); none for a planar loop."""
        if not self.ch.mimo:
            return np.zeros(0, dtype=complex)
        if getattr(self, "_loop_at_a_time_poles", None) is not None:
            return self._loop_at_a_time_poles.copy()
        # the closed loop's state matrix with torque i's loop open, as plain arrays (the
        # plant sampled once for a digital controller, as close_loop samples it)
        roots = [np.linalg.eigvals(_closed_loop_matrices(
            self._plant_discretised, self.controller, self.ch.torques, self.measured,
            cut=i)[0]) for i in range(self.ch.n_axes)]
        # computed once per loop (the grid and the poles both need them)
        self._loop_at_a_time_poles = np.concatenate(roots).astype(complex)
        return self._loop_at_a_time_poles.copy()

    def poles(self) -> np.ndarray:
        """The poles of L and of its loop-at-a-time functions (s-plane, rad/s; a digital
        loop's mapped from the z-plane by s = log(z) / T), computed once: for an FRD plant the
        controller's only."""
        if getattr(self, "_poles", None) is None:
            if self.frd:
                poles = self.controller_ev.poles()
            else:
                poles = np.concatenate([self.plant_ev.poles(), self.controller_ev.poles(),
                                        self.loop_at_a_time_poles()]).astype(complex)
            if self.digital:
                # z = 0 is infinitely fast: dropped
                poles = np.log(poles[np.abs(poles) > 1e-12]) / self.dt
            self._poles = np.asarray(poles, dtype=complex)
        return self._poles

    def undamped_frequencies(self) -> np.ndarray:
        """Frequencies [rad/s] of the undamped (or nearly: damping ratio below 1e-7) poles
        among :meth:`poles`, increasing, each once (to 1e-13 relative)."""
        poles = self.poles()
        w = np.sort(poles.imag[(poles.imag > 0) & (np.abs(poles.real) < 1e-7 * np.abs(poles))])
        return w[np.concatenate([[True], np.diff(w) > 1e-13 * w[1:]])] if w.size else w

    def grid(self, n_points: int = 600) -> np.ndarray:
        """Frequency grid [rad/s] refined around every lightly damped pole and zero of L."""
        poles = self.poles()
        if self.frd:
            # the FRD's own grid (it must resolve the plant) plus the controller's resonances
            roots = self._controller_roots()
        else:
            roots = np.concatenate([self.plant_ev.poles(), self.controller_ev.poles(),
                                    self.loop_at_a_time_poles()]
                                   + [self.zeros(i) for i in range(self.ch.n_axes)]
                                   ).astype(complex)
        if self.digital:
            # z-plane roots: map back with s = log(z) / T (z = 0 is infinitely fast: drop it)
            roots = np.log(roots[np.abs(roots) > 1e-12]) / self.dt
        w_all = np.abs(roots)
        w_all = w_all[w_all > 1e-5 * max(w_all.max(initial=0.0), 1e-300)]
        if w_all.size == 0:
            w_all = np.array([1.0])
        w_lo, w_hi = 1e-3 * w_all.min(), 1e3 * w_all.max()
        if self.digital:
            w_hi = min(w_hi, math.pi / self.dt * (1 - 1e-9))
            w_lo = min(w_lo, 1e-3 * math.pi / self.dt)
        grid = [np.logspace(math.log10(w_lo), math.log10(w_hi), n_points),
                resonance_points(roots, w_lo, w_hi, poles=poles)]
        if self.frd:
            inside = grid[1][(grid[1] >= self.omega[0]) & (grid[1] <= self.omega[-1])]
            return np.unique(np.concatenate([self.omega, inside]))
        return np.unique(np.concatenate(grid))


def controller_roots(controller: control.StateSpace, measured, torques) -> np.ndarray:
    """Poles of a controller and the zeros of each of its channels from a measurement to a
    torque (z-plane for a digital controller), finite and below 1e12: the roots whose lightly
    damped ones a frequency grid of its loop must resolve (:func:`resonance_points`).

    Parameters
    ----------
    controller : control.StateSpace
    measured, torques : sequence of str
        Its fed-back inputs and its torque outputs.
    """
    c = controller
    inputs, outputs = list(c.input_labels), list(c.output_labels)
    roots = [modal_evaluator(c, list(measured), list(torques)).poles()]
    for torque in torques:
        i = outputs.index(torque)
        for name in measured:
            j = inputs.index(name)
            roots.append(siso_zeros(c.A, c.B[:, j], c.C[i], c.D[i, j]))
    roots = np.concatenate(roots).astype(complex)
    return roots[np.isfinite(roots) & (np.abs(roots) < 1e12)]


# a lightly damped root's window: _WINDOW_POINTS points Im(root) + zeta w tan(t), t evenly in
# [-_THETA, _THETA]
_THETA = 1.45
_WINDOW_POINTS = 40
_STEP = 2.0 * _THETA / (_WINDOW_POINTS - 1)
# roots whose windows are merged: centres within this many of the narrowest half-width of the
# group, half-widths within this ratio (beyond, a merged window needs about as many points)
_MERGE_SPREAD = 1.0
_MERGE_WIDTHS = 1.25
# a merged window's ends may fall short of a root's own by round-off of the frequencies: this
# fraction of a step
_ENDS = 1e-6


def window_angle_steps(points: np.ndarray, centre: float, width: float) -> np.ndarray:
    """The angle t = arctan((x - centre) / width) that each gap between neighbouring increasing
    ``points`` spans, for the gaps that meet the root's own window |t| < 1.45 (the phase that a
    factor 1 / (j omega - root) of the root -width + j centre turns across the gap) [rad]: at
    most 2.9 / 39 in the root's own window (:func:`resonance_points`)."""
    t = np.arctan((np.asarray(points, dtype=float) - centre) / width)
    # (a gap that only touches the window's end, to round-off, is not in it)
    meets = (t[1:] > -_THETA + _ENDS * _STEP) & (t[:-1] < _THETA - _ENDS * _STEP)
    return np.diff(t)[meets]


def _groups(centres: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """Group number of each root (centres increasing): consecutive roots within _MERGE_SPREAD
    of the group's narrowest half-width from its first, half-widths within _MERGE_WIDTHS."""
    group = np.zeros(centres.size, dtype=int)
    k, first, narrowest, widest = 0, 0, math.inf, 0.0
    c, w = centres.tolist(), widths.tolist()
    for i in range(len(c)):
        narrowest_i, widest_i = min(narrowest, w[i]), max(widest, w[i])
        if i > first and (c[i] - c[first] > _MERGE_SPREAD * narrowest_i
                          or widest_i > _MERGE_WIDTHS * narrowest_i):
            k, first, narrowest_i, widest_i = k + 1, i, w[i], w[i]
        narrowest, widest = narrowest_i, widest_i
        group[i] = k
    return group


def _ragged_windows(centre, width, theta, n) -> np.ndarray:
    """The points of windows centre_k + width_k tan(t), t in n_k even steps over
    [-theta_k, theta_k], concatenated."""
    offsets = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
    t = np.repeat(-theta, n) + offsets * np.repeat(2.0 * theta / (n - 1), n)
    return np.repeat(centre, n) + np.repeat(width, n) * np.tan(t)


def _windows(centres: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """The window points of lightly damped roots (centres increasing, half-widths zeta |root|),
    close ones merged (:func:`resonance_points`)."""
    if centres.size == 0:
        return np.zeros(0)
    group = _groups(centres, widths)
    starts = np.flatnonzero(np.concatenate([[True], group[1:] != group[:-1]]))
    size = np.diff(np.concatenate([starts, [group.size]]))
    # the merged window: centre c between the extreme centres, half-width w the narrowest,
    # steps s0 / R, R = max_i kappa_i (1 + d_i + d_i^2), d_i = |c - c_i| / w_i,
    # kappa_i = w_i / w; its ends reach tan(t_max) = max_i (w_i tan(1.45) + |c - c_i|) / w
    centre = 0.5 * (np.minimum.reduceat(centres, starts) + np.maximum.reduceat(centres, starts))
    width = np.minimum.reduceat(widths, starts)
    apart = np.abs(centres - centre[group])
    d = apart / widths
    # (a relative 1e-12 beyond, for round-off)
    ratio = np.maximum.reduceat(widths / width[group] * (1.0 + d + d * d), starts) * (1 + 1e-12)
    theta = np.arctan(np.maximum.reduceat(widths * math.tan(_THETA) + apart, starts)
                      * (1 + 1e-12) / width)
    n = np.ceil(2.0 * theta * ratio / _STEP).astype(int) + 1
    merge = (size > 1) & (n < _WINDOW_POINTS * size)
    merged = np.flatnonzero(merge)
    points = _ragged_windows(centre[merged], width[merged], theta[merged], n[merged])
    if merged.size:
        # checked on the points: every gap spans at most s0 of every member's angle, and the
        # window covers every member's own (a group where round-off breaks it is not merged)
        members = np.flatnonzero(merge[group])
        k = np.searchsorted(merged, group[members])       # the member's merged window
        ends = np.cumsum(n[merged])
        first = ends - n[merged]
        count = n[merged][k]
        which = np.repeat(np.arange(members.size), count)
        at = np.repeat(first[k], count) + (np.arange(int(count.sum()))
                                           - np.repeat(np.cumsum(count) - count, count))
        t = np.arctan((points[at] - centres[members][which]) / widths[members][which])
        step = np.diff(t)
        same = which[1:] == which[:-1]
        meets = same & (t[1:] > -_THETA + _ENDS * _STEP) & (t[:-1] < _THETA - _ENDS * _STEP)
        bad_step = np.zeros(members.size, dtype=bool)
        np.logical_or.at(bad_step, which[1:][meets], step[meets] > _STEP)
        # (to the round-off of the frequencies themselves, 1e-6 of a step at 1e-7 |root|)
        covered = ((t[np.cumsum(count) - count] <= -_THETA + _ENDS * _STEP)
                   & (t[np.cumsum(count) - 1] >= _THETA - _ENDS * _STEP))
        broken = np.zeros(merged.size, dtype=bool)
        np.logical_or.at(broken, k, bad_step | ~covered)
        if broken.any():
            merge[merged[broken]] = False
            keep = np.repeat(~broken, n[merged])
            points = points[keep]
    single = ~merge[group]
    theta40 = np.linspace(-_THETA, _THETA, _WINDOW_POINTS)
    own = centres[single, None] + widths[single, None] * np.tan(theta40)
    return np.concatenate([points, own.ravel()])


def resonance_points(roots, w_lo: float, w_hi: float, *, poles=None) -> np.ndarray:
    """Frequencies [rad/s] across the half-power band of every lightly damped root, in
    (w_lo, w_hi), increasing.

    A root -zeta w + j w sqrt(1 - zeta^2) (a pole: a resonance; a zero: an antiresonance) with
    zeta <= 0.3 gets 40 points ``Im(root) + zeta w tan(t)``, t evenly in [-1.45, 1.45] (steps
    s0 = 2.9 / 39): the response falls to 1/sqrt(2) of its peak at about w (1 +/- zeta), so
    steps of a fraction of zeta w resolve the peak and its 180 deg phase swing; t is the phase
    the root's factor 1 / (j omega - root) turns. An even count puts no point on the peak
    itself, where an undamped pole (zeta = 0, taken as 1e-7) makes the response infinite.

    Roots whose centres c_i lie within one half-width w_i = zeta_i |root_i| of each other
    (half-widths within a ratio 1.25) share one window wherever it needs fewer points than
    their own windows together: a plant's mode that a loop leaves where it is comes back as a
    pole of every loop-at-a-time function and as zeros, several copies of one root computed a
    little apart. The shared window is c + w tan(t), c the middle of the centres, w the
    narrowest half-width, t in steps s0 / R. Its local spacing, s0 / R (w + (x - c)^2 / w), is
    at most s0 / R kappa_i (w_i + (x - c)^2 / w_i) (kappa_i = w_i / w >= 1), and
    (w_i + (x - c)^2 / w_i) / (w_i + (x - c_i)^2 / w_i) <= 1 + d_i + d_i^2
    (d_i = |c - c_i| / w_i), so with R = max_i kappa_i (1 + d_i + d_i^2) the angle
    t_i = arctan((x - c_i) / w_i) of every root turns by at most s0 across any of its gaps, as
    in the root's own window, nowhere a coarser spacing; its ends, tan(t_max) =
    max_i (w_i tan(1.45) + |c - c_i|) / w, lie beyond every root's own window (both checked
    on the points, :func:`window_angle_steps`; a group where round-off breaks them keeps its
    roots' own windows).

    A pole of the loop that is undamped or nearly so (zeta below the floor 1e-7) also gets
    points w (1 +- 10^-k), k = 9, 9.5, ..., 13 (UNDAMPED_LADDER), beside the pole: |L| grows
    without bound towards it, so |L| = 1 is crossed on both sides, as close to it as the
    mode's residue is small (a mode the loop barely feels), and these crossings, with their
    phase margins, are bracketed down to 1e-13 of the frequency (closer than that a double
    cannot tell them from the pole).

    Parameters
    ----------
    roots : array of complex, rad/s
        s-plane roots (only those with Im > 0 are used).
    w_lo, w_hi : float, rad/s
        The band the points are kept in.
    poles : array of complex, rad/s, optional
        The poles among them (of the loop, or of its loop-at-a-time functions): the undamped
        ones get the ladder of points above.
    """
    roots = np.asarray(roots, dtype=complex).reshape(-1)
    upper = roots[(roots.imag > 0) & (np.abs(roots) > 0)]
    upper = upper[np.argsort(upper.imag, kind="stable")]
    w_all = np.abs(upper)
    zeta = np.maximum(np.abs(upper.real) / w_all, 1e-7)
    light = zeta <= 0.3
    pts = _windows(upper.imag[light], (zeta * w_all)[light])
    points = [pts[(pts > w_lo) & (pts < w_hi)]]
    if poles is not None:
        poles = np.asarray(poles, dtype=complex).reshape(-1)
        poles = poles[(poles.imag > 0) & (np.abs(poles.real) < 1e-7 * np.abs(poles))]
        # one ladder per pole frequency (the loop's modes come back as poles of every
        # loop-at-a-time function, to round-off)
        w_poles = np.sort(poles.imag)
        if w_poles.size:
            w_poles = w_poles[np.concatenate([[True], np.diff(w_poles) > 1e-13 * w_poles[1:]])]
            offsets = np.concatenate([-UNDAMPED_LADDER, UNDAMPED_LADDER])
            pts = (w_poles[:, None] * (1.0 + offsets)).ravel()
            points.append(pts[(pts > w_lo) & (pts < w_hi)])
    return np.unique(np.concatenate(points))


@warns_long_delay
@limits_blas_threads(total_states)
def loop_frequency_response(plant, controller, omega: np.ndarray | None = None, *,
                            delay: float = 0.0, computation_delay: bool = False
                            ) -> tuple[np.ndarray, np.ndarray]:
    """Open-loop transfer L(j omega) with the loop broken at the torque input.

    Parameters
    ----------
    plant : control.StateSpace or control.FrequencyResponseData
        Plant with named signals (FRD: frequencies within its grid, interpolated as in
        :func:`margins`).
    controller : control.StateSpace
        Continuous or digital controller.
    omega : array of float, rad/s, optional
        Frequencies; default a logarithmic grid refined around the lightly damped poles and
        zeros (for an FRD plant its own grid plus the controller's resonances).
    delay : float, s
        Loop delay: L e^(-j omega delay) (a digital controller on a state-space plant: the
        sampled plant with the delayed hold, exact).
    computation_delay : bool
        Add one sample of a digital controller to the delay.

    Returns
    -------
    omega : ndarray, shape (n,), rad/s
    L : ndarray, shape (n,) (planar) or (n, 3, 3) (three-axis), complex128
        L = -sum_i K_i P_i (negative-feedback convention: the loop is unstable at L = -1);
        three axes: L = -K P broken at the three torque inputs (row: torque output, column:
        torque input).
    """
    check_controller(controller)
    loop = LoopTransfer(plant, controller, total_delay(controller, delay, computation_delay))
    if omega is None:
        omega = loop.grid()
    omega = frequency_grid(omega)
    return omega, loop(omega)
