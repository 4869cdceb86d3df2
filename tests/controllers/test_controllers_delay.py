"""Loop delay: exact e^(-j omega tau) in the margins and verdicts, the delay margin, and the
delayed loop in sampled time (controllers.delay).

Tolerances. A delay leaves |L| and so the gain crossover unchanged and lowers the phase there by
omega_c tau exactly; both margins are refined on L to 1e-13 relative in frequency, where the
phase varies by at most a few degrees per relative unit of frequency, so the identity holds to
~1e-9 deg (asserted 1e-7 deg). Stability verdicts are checked 1 % on either side of the delay
margin against an independent realisation of the delay: the delayed loop discretised on a fine
step (its error O(dt^2) ~ 1e-7 of the loop's rates, far inside the 1 % of margin).
"""
import math

import control
import numpy as np
import pytest

import controllers
from controllers.delay import delayed_discretisation, split_delay
from controllers.margins import MAX_DELAY_GRID
from plants import modal_plant, three_axis_plant

# delays of seconds on purpose (the slow loops' delay margins): not the unit slip they are
# warned about as (tests/controllers/test_delay_unit_slip.py)
pytestmark = pytest.mark.filterwarnings("ignore::controllers.LongDelayWarning")

J = 250.0
DESIGN = modal_plant(J, [(2.0, 0.005, 0.04, 0.04), (7.0, 0.002, 0.02, 0.02)])
TRUTH = modal_plant(J, [(1.9, 0.005, 0.041, 0.041), (6.6, 0.002, 0.021, 0.021),
                        (14.0, 0.002, 0.01, 0.01), (25.0, 0.002, 0.006, 0.006),
                        (41.0, 0.002, 0.004, 0.004)])
PD = controllers.pd(DESIGN, natural_frequency=0.3, roll_off=3.0)


def delayed_loop_eigenvalues(plant, controller, delay, dt=None):
    """Eigenvalues of the delayed loop discretised on a step delay / 20 (its gain error
    (omega dt)^2 / 24 < 1e-5 at the loops' crossovers, far inside a 1 % change of delay)."""
    dt = delay / 20 if dt is None else dt
    return np.linalg.eigvals(controllers.close_loop(plant, controller, delay=delay, dt=dt).A)


def spectral_radius_of_delayed_loop(plant, controller, delay, dt=None):
    return float(np.abs(delayed_loop_eigenvalues(plant, controller, delay, dt)).max())


# ---------------------------------------------------------------------------------------------
# phase margin minus omega_c tau
# ---------------------------------------------------------------------------------------------
def assert_delay_lowers_the_phase(m0, m1, tau):
    assert m1.gain_crossover_frequency == pytest.approx(m0.gain_crossover_frequency, rel=1e-10)
    expected = m0.phase_margin - math.degrees(m0.gain_crossover_frequency * tau)
    assert m1.phase_margin == pytest.approx(expected, abs=1e-7)
    assert m1.delay == tau


@pytest.mark.parametrize("plant", ["design", "truth", "frd"])
def test_phase_margin_with_delay_is_the_margin_minus_omega_c_tau(plant):
    P = {"design": DESIGN, "truth": TRUTH,
         "frd": controllers.frequency_response_data(TRUTH, np.logspace(-3, 3, 6000))}[plant]
    m0 = controllers.margins(P, PD)
    tau = 0.2 * m0.delay_margin
    m1 = controllers.margins(P, PD, delay=tau)
    assert_delay_lowers_the_phase(m0, m1, tau)
    # the delay margin: the extra delay shrinks by exactly the delay added
    assert m1.delay_margin == pytest.approx(m0.delay_margin - tau, rel=1e-9)


def test_delay_on_the_exact_beam_loop_function():
    """The runner's exact-beam verdict evaluates L through W(s) of the distributed beam
    (spacecraft.design.verdicts.exact_loop_verdict: loop_margins on a callable, spillover on an FRD):
    the same identity holds on that callable, and the FRD verdict with the delay agrees with
    the callable's delay margin."""
    from appendages import Beam
    from spacecraft import Hub, Mount, Spacecraft
    rod = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=0.005)
    craft = Spacecraft(Hub(50.0, 20.0), [Mount(rod, (0.5, 0.0), 0.0)])
    design = Spacecraft(Hub(50.0, 20.0), [Mount(rod.truncated(3), (0.5, 0.0), 0.0)]).plant()
    K = controllers.pd(design, natural_frequency=0.5)
    omega = np.logspace(-3, 3.5, 5000)

    def theta(w):
        return craft.exact.attitude_compliance(np.asarray(w, dtype=float))[:, 0, 0]

    def loop(w):
        w = np.asarray(w, dtype=float).reshape(-1)
        k = controllers.frequency_response_data(K, w)
        c = list(K.input_labels)
        kk = np.asarray(k.frdata)[0]
        return -(kk[c.index("theta")] + 1j * w * kk[c.index("omega")]) * theta(w)

    m0 = controllers.loop_margins(loop, omega)
    tau = 0.3 * m0.delay_margin
    m1 = controllers.loop_margins(loop, omega, delay=tau)
    assert_delay_lowers_the_phase(m0, m1, tau)
    frd = control.frd(np.stack([theta(omega), 1j * omega * theta(omega)]).reshape(2, 1, -1),
                      omega, inputs=["torque"], outputs=["theta", "omega"])
    assert controllers.spillover(frd, K, delay=0.99 * m0.delay_margin).stable
    assert not controllers.spillover(frd, K, delay=1.01 * m0.delay_margin).stable


# ---------------------------------------------------------------------------------------------
# the delay margin and the verdict at the delay
# ---------------------------------------------------------------------------------------------
def test_delay_margin_is_the_smallest_over_several_crossovers():
    """This loop crosses |L| = 1 at its bandwidth and again at its first flexible mode; the
    mode's crossover, with the smaller PM / omega_c, sets the margin."""
    m = controllers.margins(DESIGN, PD)
    omega = np.logspace(-2, 2, 20001)
    _, L = controllers.loop_frequency_response(DESIGN, PD, omega)
    g = np.log(np.abs(L))
    crossings = np.nonzero(np.sign(g[:-1]) != np.sign(g[1:]))[0]
    assert crossings.size >= 3
    candidates = [((math.pi + np.angle(L[i])) % (2 * math.pi)) / omega[i] for i in crossings]
    # the grid's points lie 4.6e-4 apart (relative), where the phase turns fast near the mode
    assert m.delay_margin == pytest.approx(min(candidates), rel=1e-2)
    assert m.delay_margin < candidates[0]                               # not the bandwidth's


@pytest.mark.parametrize("plant", ["design", "truth", "frd"])
def test_verdict_around_the_delay_margin(plant):
    P = {"design": DESIGN, "truth": TRUTH,
         "frd": controllers.frequency_response_data(TRUTH, np.logspace(-3, 3, 6000))}[plant]
    margin = controllers.margins(P, PD).delay_margin
    below = controllers.spillover(P, PD, delay=0.99 * margin)
    beyond = controllers.spillover(P, PD, delay=1.01 * margin)
    assert below.stable and below.margins.delay_margin == pytest.approx(0.01 * margin, rel=1e-6)
    assert not beyond.stable and beyond.n_unstable_poles == 2
    assert beyond.margins.delay_margin == pytest.approx(-0.01 * margin, rel=1e-6)
    # independently: the delayed loop on a fine step (error O(dt^2))
    S = TRUTH if plant != "design" else DESIGN
    assert spectral_radius_of_delayed_loop(S, PD, 0.99 * margin) < 1.0
    assert spectral_radius_of_delayed_loop(S, PD, 1.01 * margin) > 1.0


def test_unstable_roots_counted_through_stability_windows():
    """The roots the delay drives across: this loop loses stability at 0.22 s (the mode's
    crossover), regains it between about 1.8 and 2.0 s (where the rising side of the mode's
    |L| = 1 crossing sends the pair back) and loses it again; at 3.3 s two pairs are out. The
    count of spillover agrees with the discretised delayed loop's eigenvalues outside the unit
    circle at every delay of the sweep."""
    for tau in (0.1, 0.3, 0.9, 1.5, 1.9, 2.1, 2.9, 3.3):
        v = controllers.spillover(DESIGN, PD, delay=tau)
        outside = int(np.sum(np.abs(delayed_loop_eigenvalues(DESIGN, PD, tau, 0.05)) > 1.0))
        assert v.n_unstable_poles == outside, tau
        assert v.stable == (outside == 0)
    assert controllers.spillover(DESIGN, PD, delay=1.9).stable
    assert controllers.spillover(DESIGN, PD, delay=3.3).n_unstable_poles == 4


def test_delay_margin_of_an_unstable_open_loop():
    """An inverted-pendulum-like plant (theta'' = torque / J + a^2 theta) stabilised by a PD:
    the open loop has a pole at +a, the closed loop is stable up to the delay margin."""
    a = 0.2
    plant = control.ss([[0, 1], [a * a, 0]], [[0], [1 / J]], [[1, 0], [0, 1]], 0,
                       inputs=["torque"], outputs=["theta", "omega"])
    Kp, Kd = controllers.pd_gains(J, 0.6, 0.7)
    K = control.ss([], [], [], [[Kp, -Kp, -Kd]], inputs=["theta_ref", "theta", "omega"],
                   outputs=["torque"])
    m = controllers.margins(plant, K)
    assert 0 < m.delay_margin < math.inf
    assert controllers.spillover(plant, K, delay=0.99 * m.delay_margin).stable
    assert not controllers.spillover(plant, K, delay=1.01 * m.delay_margin).stable
    assert spectral_radius_of_delayed_loop(plant, K, 0.99 * m.delay_margin) < 1.0
    assert spectral_radius_of_delayed_loop(plant, K, 1.01 * m.delay_margin) > 1.0


def test_three_axis_delay_margin():
    Jm = np.array([[300.0, 15.0, -4.0], [15.0, 250.0, 8.0], [-4.0, 8.0, 420.0]])
    plant = three_axis_plant(Jm, [(2.0, 0.005, np.array([0.03, 0.01, 0.0]),
                                   np.array([0.03, 0.01, 0.0])),
                                  (5.0, 0.002, np.array([0.0, 0.01, 0.02]),
                                   np.array([0.0, 0.01, 0.02]))])
    K = controllers.pd(plant, natural_frequency=0.3, roll_off=3.0)
    m = controllers.margins(plant, K)
    margin = m.delay_margin
    assert 0 < margin <= min(x.delay_margin for x in m.loop_at_a_time.values()) * (1 + 1e-9)
    # det(I + L e^(-j w margin)) = 0 at the crossing: some eigenvalue of L e^(-j w tau) is -1
    tau = 0.5 * margin
    m1 = controllers.margins(plant, K, delay=tau)
    assert m1.delay_margin == pytest.approx(margin - tau, rel=1e-9)
    assert controllers.spillover(plant, K, delay=0.99 * margin).stable
    assert not controllers.spillover(plant, K, delay=1.01 * margin).stable
    assert spectral_radius_of_delayed_loop(plant, K, 0.99 * margin) < 1.0
    assert spectral_radius_of_delayed_loop(plant, K, 1.01 * margin) > 1.0


def test_digital_loop_delay_in_whole_samples_is_exact():
    """A delay of k samples is z^-k: the sampled loop's phase margin drops by omega_c k T
    exactly, and computation_delay is one sample."""
    T = 0.1
    K = controllers.pd(DESIGN, natural_frequency=0.3, roll_off=3.0, sample_time=T)
    m0 = controllers.margins(DESIGN, K)
    m1 = controllers.margins(DESIGN, K, delay=T)
    assert_delay_lowers_the_phase(m0, m1, T)
    mc = controllers.margins(DESIGN, K, computation_delay=True)
    assert mc.phase_margin == pytest.approx(m1.phase_margin, abs=1e-9)
    # the verdict from the exact delayed sampled-data loop's poles
    v = controllers.spillover(TRUTH, K, delay=0.1)
    loop = controllers.close_loop(TRUTH, K, delay=0.1)
    assert v.stable == bool(np.abs(np.linalg.eigvals(loop.A)).max() < 1)


# ---------------------------------------------------------------------------------------------
# sampled time
# ---------------------------------------------------------------------------------------------
def test_split_delay():
    assert split_delay(0.35, 0.1) == (3, pytest.approx(0.5, abs=1e-12))
    assert split_delay(0.3, 0.1) == (3, 0.0)          # 2.9999999999999996 snapped
    assert split_delay(0.0, 0.1) == (0, 0.0)


def test_delayed_discretisation_against_a_fine_step():
    """x' = A x + B u(t - tau) with u held over steps T: Phi, Gamma0, Gamma1 against the same
    input applied on a step T / 20 (the delay 3.35 T = 67 fine steps), exact both ways."""
    A = np.array([[0.0, 1.0], [-4.0, -0.1]])
    B = np.array([[0.0], [1.0]])
    T, tau = 0.2, 3.35 * 0.2
    Phi, G0, G1, k, f = delayed_discretisation(A, B, T, tau)
    assert (k, f) == (3, pytest.approx(0.35, abs=1e-12))
    u = np.random.default_rng(0).normal(size=40)
    x = np.zeros(2)
    coarse = [x]
    for n in range(30):
        late = u[n - k] if n - k >= 0 else 0.0
        early = u[n - k - 1] if n - k - 1 >= 0 else 0.0
        x = Phi @ x + G0[:, 0] * late + G1[:, 0] * early
        coarse.append(x)
    fine_Phi, fine_G, _ = controllers.discretise.discretise(A, B, T / 20, "zero")
    x = np.zeros(2)
    for i in range(30 * 20):
        j = i - 67                    # the fine step's input, 67 fine steps late
        v = u[j // 20] if j >= 0 else 0.0
        x = fine_Phi @ x + fine_G[:, 0] * v
        if (i + 1) % 20 == 0:
            np.testing.assert_allclose(x, coarse[(i + 1) // 20], rtol=1e-11, atol=1e-14)


def test_delayed_zoh_loop_against_a_fine_step_realisation():
    """The digital PD with a delay of 1.3 samples: the exact delayed sampled-data loop
    (delay-line states) against the same loop run on a step T / 10, the plant's torque the
    command 13 fine steps late, the controller updated every 10 fine steps."""
    T, tau = 0.1, 0.13
    K = controllers.pd(DESIGN, natural_frequency=0.3, roll_off=3.0, sample_time=T)
    loop = controllers.close_loop(DESIGN, K, delay=tau)
    n = 200
    U = np.zeros((loop.ninputs, n))
    U[0] = 0.1                                            # theta_ref step
    y = controllers.simulate(loop, np.arange(n) * T, U).y
    h = T / 10
    Pd = control.c2d(control.ss(DESIGN.A, DESIGN.B[:, :1], DESIGN.C, 0), h, "zoh")
    x = np.zeros(DESIGN.nstates)
    xc = np.zeros(K.nstates)
    commands = []
    theta = []
    for i in range(n * 10):
        if i % 10 == 0:
            meas = DESIGN.C @ x                          # theta, omega at the sample
            theta.append(meas[0])
            inp = np.array([0.1, meas[0], meas[1]])
            u = float((K.C @ xc + K.D @ inp).item())
            xc = K.A @ xc + K.B @ inp
            commands.append(u)
        j = i - 13                                      # 1.3 samples = 13 fine steps late
        v = commands[j // 10] if j >= 0 else 0.0
        x = Pd.A @ x + Pd.B[:, 0] * v
    np.testing.assert_allclose(y[0], theta, rtol=0, atol=1e-11 * 0.1)


@pytest.mark.slow
def test_continuous_delayed_loop_converges_at_second_order():
    """The continuous PD with a 0.1 s delay, simulated on steps dt (command held, delayed by
    0.1 - dt/2): against dt / 64, halving dt divides the error by about 4 (O(dt^2))."""
    tau = 0.1

    def run(h, t_end=20.0):
        cl = controllers.close_loop(DESIGN, PD, delay=tau, dt=h)
        steps = int(round(t_end / h)) + 1
        U = np.zeros((cl.ninputs, steps))
        U[0] = 0.1
        return controllers.simulate(cl, np.arange(steps) * h, U).y[0]

    h0 = tau / 4
    reference = run(h0 / 64)
    errors = []
    for h in (h0, h0 / 2, h0 / 4):
        y = run(h)
        errors.append(np.max(np.abs(y - reference[::int(round(h / (h0 / 64)))])))
    for coarse, fine in zip(errors, errors[1:]):
        assert 3.0 < coarse / fine < 5.0


# ---------------------------------------------------------------------------------------------
# bad input
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("call, name", [
    (lambda: controllers.margins(DESIGN, PD, delay=-0.1), "delay"),
    (lambda: controllers.margins(DESIGN, PD, delay=float("nan")), "delay"),
    (lambda: controllers.margins(DESIGN, PD, delay="0.1"), "delay"),
    (lambda: controllers.margins(DESIGN, PD, computation_delay=True), "computation_delay"),
    (lambda: controllers.spillover(DESIGN, PD, delay=-1.0), "delay"),
    (lambda: controllers.close_loop(DESIGN, PD, delay=0.1), "dt"),
    (lambda: controllers.close_loop(DESIGN, PD, delay=0.1, dt=0.3), "dt"),
    (lambda: controllers.close_loop(DESIGN, PD, dt=0.01), "dt"),
    (lambda: controllers.loop_frequency_response(DESIGN, PD, delay=-2.0), "delay"),
])
def test_bad_delay_arguments_name_the_parameter(call, name):
    with pytest.raises((ValueError, TypeError), match=name):
        call()


def test_a_delay_beyond_the_margin_is_a_result():
    v = controllers.spillover(DESIGN, PD, delay=1.0)
    assert not v.stable and v.margins.delay_margin < 0
    assert MAX_DELAY_GRID >= 1e5
