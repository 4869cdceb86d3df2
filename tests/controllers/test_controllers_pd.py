"""PD controller: rigid-hub closed form, filters, digital implementation, errors."""
import math

import control
import numpy as np
import pytest

import controllers
from plants import modal_plant
from controllers.pd import (MIN_SAMPLES_PER_CROSSOVER, NOTCH_POLE_DAMPING, NOTCH_ZERO_DAMPING,
                            check_sample_time, natural_frequency_from_bandwidth, pd_gains)


J = 250.0  # kg m^2
RIGID = modal_plant(J)
FLEX = modal_plant(J, [(2.0, 0.005, 0.04, 0.04), (11.0, 0.005, 0.02, 0.02)])


@pytest.mark.parametrize("wn, zeta", [(0.3, 0.7), (1.0, 0.5), (0.05, 1.2)])
def test_rigid_hub_closed_loop_matches_spec(wn, zeta):
    """Closed loop on 1/(J s^2) is J s^2 + Kd s + Kp: poles -zeta wn +/- wn sqrt(zeta^2 - 1)."""
    K = controllers.pd(RIGID, natural_frequency=wn, damping=zeta)
    loop = controllers.close_loop(RIGID, K)
    poles = np.sort_complex(loop.poles())
    expected = np.sort_complex(np.roots([1.0, 2.0 * zeta * wn, wn * wn]).astype(complex))
    # closed form vs a 2x2 eigenvalue problem: round-off only (1e-10 relative to wn);
    # a repeated root (zeta = 1) would be sqrt(eps)-sensitive, hence zeta != 1 here
    np.testing.assert_allclose(poles, expected, rtol=0, atol=1e-10 * wn)
    # Vieta: product of the poles = wn^2, sum = -2 zeta wn
    np.testing.assert_allclose(np.prod(poles).real, wn * wn, rtol=1e-10)
    np.testing.assert_allclose(np.sum(poles).real, -2 * zeta * wn, rtol=1e-10)
    if zeta < 1:
        np.testing.assert_allclose(np.abs(poles), wn, rtol=1e-10)
        np.testing.assert_allclose(-poles.real / np.abs(poles), zeta, rtol=1e-10)
    Kp, Kd = pd_gains(J, wn, zeta)
    np.testing.assert_allclose(K.D, [[Kp, -Kp, -Kd]], rtol=1e-13)
    assert list(K.input_labels) == ["theta_ref", "theta", "omega"]
    assert list(K.output_labels) == ["torque"]


def test_inertia_taken_from_flexible_plant():
    """The PD gains use the total inertia J (rigid-body gain), not the hub's alone."""
    K = controllers.pd(FLEX, natural_frequency=0.4, damping=0.7)
    Kp, Kd = pd_gains(J, 0.4, 0.7)
    np.testing.assert_allclose(K.D, [[Kp, -Kp, -Kd]], rtol=1e-9)  # inertia from Schur: ~1e-12


def test_bandwidth_relation_of_second_order_prototype():
    """|wn^2 / (s^2 + 2 zeta wn s + wn^2)| = 1/sqrt(2) at s = j wb (definition of wb)."""
    for zeta in (0.3, 0.7, 1.0):
        wb = 2.0
        wn = natural_frequency_from_bandwidth(wb, zeta)
        T = wn ** 2 / ((1j * wb) ** 2 + 2 * zeta * wn * 1j * wb + wn ** 2)
        assert abs(abs(T) - 1 / math.sqrt(2)) < 1e-12
    # zeta = 1/sqrt(2): wb = wn exactly (Butterworth)
    assert natural_frequency_from_bandwidth(3.0, 1 / math.sqrt(2)) == pytest.approx(3.0, rel=1e-14)
    K = controllers.pd(RIGID, bandwidth=1.0, damping=0.7)
    wn = natural_frequency_from_bandwidth(1.0, 0.7)
    np.testing.assert_allclose(K.D[0, 0], J * wn ** 2, rtol=1e-13)


def test_roll_off_is_butterworth_at_the_corner():
    """F(s) = wr^2/(s^2 + sqrt(2) wr s + wr^2): |F(j wr)| = 1/sqrt(2), unity DC gain."""
    wn, wr = 0.4, 4.0
    K = controllers.pd(RIGID, natural_frequency=wn, roll_off=wr)
    Kp, Kd = pd_gains(J, wn, 0.7)
    dc = K(0.0)
    np.testing.assert_allclose(np.real(dc), [[Kp, -Kp, -Kd]], rtol=1e-12)
    np.testing.assert_allclose(abs(K(1j * wr)[0, 0]), Kp / math.sqrt(2), rtol=1e-12)
    assert K.nstates == 2


def test_notch_depth_at_its_frequency_and_first_mode_choice():
    """N(j wz) = zeta_z / zeta_p exactly (the s^2 + wz^2 terms cancel at s = j wz)."""
    wn = 0.3
    K = controllers.pd(FLEX, natural_frequency=wn, notch="first_mode")
    Kp, _ = pd_gains(J, wn, 0.7)
    # the first flexible mode of FLEX is built at 2.0 rad/s
    np.testing.assert_allclose(abs(K(2.0j)[0, 0]), Kp * NOTCH_ZERO_DAMPING / NOTCH_POLE_DAMPING,
                               rtol=1e-9)
    K5 = controllers.pd(FLEX, natural_frequency=wn, notch=5.0)
    np.testing.assert_allclose(abs(K5(5.0j)[0, 0]), Kp * NOTCH_ZERO_DAMPING / NOTCH_POLE_DAMPING,
                               rtol=1e-12)


def test_digital_pd_sampled_data_loop_closed_form():
    """ZOH double integrator: Phi = [[1, T], [0, 1]], Gamma = [T^2/(2J), T/J]; with
    u = -Kp theta - Kd omega the loop's characteristic polynomial is
    z^2 - (2 - a Kp - b Kd) z + (1 + a Kp - b Kd), a = T^2/(2J), b = T/J."""
    wn, T = 0.5, 0.05
    K = controllers.pd(RIGID, natural_frequency=wn, sample_time=T)
    assert K.dt == T
    Kp, Kd = pd_gains(J, wn, 0.7)
    loop = controllers.close_loop(RIGID, K)
    assert loop.dt == T
    a, b = T * T / (2 * J), T / J
    expected = np.roots([1.0, -(2 - a * Kp - b * Kd), 1 + a * Kp - b * Kd])
    np.testing.assert_allclose(np.sort_complex(loop.poles()), np.sort_complex(expected),
                               rtol=0, atol=1e-12)
    assert np.all(np.abs(loop.poles()) < 1)


def test_digital_pd_with_filters_is_zoh_of_continuous():
    wn, T = 0.3, 0.02
    Kc = controllers.pd(FLEX, natural_frequency=wn, roll_off=3.0)
    Kd = controllers.pd(FLEX, natural_frequency=wn, roll_off=3.0, sample_time=T)
    ref = control.c2d(Kc, T, method="zoh")
    # both are expm of the Van Loan block [[A T, B T], [0, 0]] with ||A T|| <= 0.1 (no
    # squaring: Pade error below eps), within ~10 eps ||e^{AT}|| = 2e-15 absolute of exact on
    # entries of size <= 1 (Higham, Functions of Matrices, 2008, sec. 10.3): atol 1e-14;
    # rtol 1e-12 for the small entries of B (~T)
    np.testing.assert_allclose(Kd.A, ref.A, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(Kd.B, ref.B, rtol=1e-12, atol=1e-14)
    assert controllers.spillover(FLEX, Kd).stable


def test_sample_time_too_long_for_bandwidth():
    # crossover of (Kp + Kd s)/(J s^2) with zeta = 0.7: wc = wn sqrt(2 zeta^2 + sqrt(4 zeta^4 + 1))
    wn = 1.0
    wc = wn * math.sqrt(2 * 0.49 + math.sqrt(4 * 0.49 ** 2 + 1))
    T_max = 2 * math.pi / (MIN_SAMPLES_PER_CROSSOVER * wc)
    controllers.pd(RIGID, natural_frequency=wn, sample_time=0.95 * T_max)
    with pytest.raises(ValueError, match=r"sample_time .* too long .* gain-crossover"):
        controllers.pd(RIGID, natural_frequency=wn, sample_time=1.1 * T_max)


def test_errors_name_the_parameter():
    with pytest.raises(ValueError, match="exactly one of natural_frequency"):
        controllers.pd(RIGID, natural_frequency=1.0, bandwidth=1.0)
    with pytest.raises(ValueError, match="exactly one of natural_frequency"):
        controllers.pd(RIGID)
    with pytest.raises(ValueError, match=r"damping must be positive and finite \[1\]; got -0.1"):
        controllers.pd(RIGID, natural_frequency=1.0, damping=-0.1)
    with pytest.raises(ValueError, match=r"natural_frequency must be positive .*rad/s"):
        controllers.pd(RIGID, natural_frequency=float("nan"))
    with pytest.raises(ValueError, match="roll_off corner must exceed"):
        controllers.pd(RIGID, natural_frequency=1.0, roll_off=1.5)
    with pytest.raises(ValueError, match="notch frequency must exceed"):
        controllers.pd(FLEX, natural_frequency=1.5, notch="first_mode")
    with pytest.raises(ValueError, match="no flexible mode"):
        controllers.pd(RIGID, natural_frequency=1.0, notch="first_mode")
    with pytest.raises(ValueError, match="notch must be a frequency"):
        controllers.pd(FLEX, natural_frequency=0.1, notch="second")
    with pytest.raises(TypeError, match="plant must be a control.StateSpace"):
        controllers.pd(control.tf([1], [J, 0, 0]), natural_frequency=1.0)
    no_omega = control.ss([[0, 1], [0, 0]], [[0], [1 / J]], [[1, 0]], 0, inputs=["torque"],
                          outputs=["theta"])
    with pytest.raises(ValueError, match="output named 'omega'"):
        controllers.pd(no_omega, natural_frequency=1.0)
    # hub on a torsion spring: no rigid-body mode, the design rule does not apply
    sprung = control.ss([[0, 1], [-4.0, 0]], [[0], [1 / J]], np.eye(2), 0, inputs=["torque"],
                        outputs=["theta", "omega"])
    with pytest.raises(ValueError, match="free-floating"):
        controllers.pd(sprung, natural_frequency=1.0)


# --------------------------------------------------------------------------------------------
# the stability guarantee on the design plant (issue 9)
# --------------------------------------------------------------------------------------------
def _spacecraft(*appendages):
    from spacecraft import Hub, Mount, Spacecraft

    mounts = [Mount(a, (0.5, 0.0), 0.0) if k == 0 else Mount(a, (-0.5, 0.0), math.pi)
              for k, a in enumerate(appendages)]
    return Spacecraft(Hub(100.0, 50.0), mounts)


def _rod():
    from appendages import Beam

    return Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)  # the paper's rod, undamped


def _assert_margin(plant, K, left_out=()):
    """Every pole at Re <= -alpha = -MARGIN x the loop's spectral scale, except the modes
    left out (undamped: within alpha of +-j w)."""
    poles = controllers.close_loop(plant, K).poles()
    lam = np.linalg.eigvals(plant.A)
    alpha = controllers.MARGIN * max(np.abs(poles).max(), np.abs(lam).max())
    # the open-loop eigenvalues of the left-out modes (frequencies given to 1e-4)
    kept = lam[[any(abs(abs(x) - w) <= 1e-4 * w for w in left_out) for x in lam]]
    for p in poles[poles.real > -alpha]:
        assert np.min(np.abs(kept - p), initial=np.inf) <= alpha, p


def test_pd_refuses_a_loop_unstable_on_its_design_plant():
    """A roll-off at 4 rad/s lags the 7 rad/s mode of this collocated plant by ~120 deg: the loop
    has a pole at +0.026 + 7.04j. pd() used to return that controller; now it refuses it and
    names the filter and the mode."""
    plant = modal_plant(J, [(2.0, 0.002, 1.0, 0.004), (7.0, 0.002, 1.0, 0.002)])
    with pytest.raises(ValueError, match=r"pd: .*7\.03\d* rad/s.*roll_off = 4 rad/s"):
        controllers.pd(plant, natural_frequency=0.5, roll_off=4.0)
    K = controllers.pd(plant, natural_frequency=0.5)  # without the filter: passive, stable
    _assert_margin(plant, K)


def test_pd_on_unpruned_symmetric_wings_names_the_modes_it_cannot_move():
    """The symmetric bending of two identical wings leaves theta/torque (participation
    ~1e-26): the loop leaves those 8 undamped modes where they are; pd() says so and
    guarantees the margin for every other pole."""
    rod = _rod()
    craft = _spacecraft(rod.truncated(8), rod.truncated(8))
    plant = craft.plant()
    with pytest.warns(controllers.RemovedModesWarning, match="pd: 8 mode") as record:
        K = controllers.pd(plant, natural_frequency=0.1)
    text = str(record[0].message)
    pruned = craft.plant(prune=True)
    symmetric = sorted(set(np.round(np.abs(np.linalg.eigvals(plant.A)), 4))
                       - set(np.round(np.abs(np.linalg.eigvals(pruned.A)), 4)))
    for w in symmetric[:6]:  # the message lists six, then 'and 2 more'
        assert f"{w:.4f}"[:5] in text
    _assert_margin(plant, K, symmetric)


def test_pd_on_25_body_chain_names_its_free_tip_mode():
    from appendages import HingedChain

    plant = _spacecraft(HingedChain.rfem(_rod(), 25)).plant()
    with pytest.warns(controllers.RemovedModesWarning, match=r"pd: 1 mode.*656\.25 rad/s"):
        K = controllers.pd(plant, natural_frequency=0.1)
    _assert_margin(plant, K, [656.25])


@pytest.mark.parametrize("wn, what", [(1e-300, "gives gains"), (1e-12, "rigid-body poles"),
                                      (1e9, "too high"), (1e100, "spectral scale"),
                                      (1e200, "gives gains")])
def test_pd_extreme_natural_frequency_is_refused_by_name(wn, what):
    """natural_frequency = 1e9 ended in LinAlgError, 1e200 in OverflowError: now a ValueError
    naming natural_frequency (gains outside float64, rigid-body poles inside the margin, a
    loop too stiff to damp the flexible modes, or a loop 1e10 times faster than them)."""
    flexible = modal_plant(J, [(2.0, 0.0, 0.04, 0.04), (11.0, 0.0, 0.02, 0.02)])
    with pytest.raises(ValueError, match=rf"natural_frequency.*|{what}") as info:
        controllers.pd(flexible, natural_frequency=wn)
    assert "natural_frequency" in str(info.value) and what in str(info.value)


# --------------------------------------------------------------------------------------------
# sample rate: judged on the rigid-body crossover and on the sampled loop itself (issue 9)
# --------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def default_scene_design_plant():
    """The default scene's design plant: hub 100 kg / 50 kg m^2, the paper's rod (0.5 %
    damping) fitted by a 3-body chain (flexsat's fit; its modes at 0.985 and 3.204 rad/s coupled
    to the hub, lightly damped), pruned. The rod keeps the free-free damping convention (hinge
    dampings matched at its first free-free frequency, 2.87 rad/s), the plant issue 9's findings
    were measured on: matched at its first cantilever frequency (0.45 rad/s, the default) the
    hinges damp 6.4 times more and the 1 Hz loop below is stable."""
    from appendages import Beam, fit_chain
    from spacecraft import Hub, Mount, Spacecraft

    rod = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11, damping_ratio=0.005,
                            damping_convention="free-free")
    chain = fit_chain(rod, 3)
    return Spacecraft(Hub(100.0, 50.0), [Mount(chain, (0.5, 0.0), 0.0)]).plant(prune=True)


def test_sample_rate_judged_on_the_rigid_body_crossover(default_scene_design_plant):
    """Finding of issue 9: the check took the highest |L| = 1 crossing (the chain's undamped
    3.2 rad/s resonance) as the crossover and refused 5 Hz for a 0.2 rad/s PD. The loop's
    crossover is the rigid-body one: for L = (Kp + Kd s)/(J s^2),
    w_c = wn sqrt(2 zeta^2 + sqrt(4 zeta^4 + 1)) = 0.30856 rad/s (zeta = 0.7), so any rate
    above 10 w_c / (2 pi) = 0.49 Hz passes that rule; 5 and 20 Hz give stable sampled loops."""
    plant = default_scene_design_plant
    wn, zeta = 0.2, 0.7
    continuous = controllers.pd(plant, natural_frequency=wn, damping=zeta)
    w_c = wn * math.sqrt(2 * zeta ** 2 + math.sqrt(4 * zeta ** 4 + 1))
    # crossings refined to 1e-13 relative; the plant's rigid gain 1/J from a Schur form ~1e-12
    assert check_sample_time(0.2, plant, continuous) == pytest.approx(w_c, rel=1e-9)
    for rate in (5.0, 20.0):
        K = controllers.pd(plant, natural_frequency=wn, damping=zeta, sample_time=1.0 / rate)
        assert controllers.spillover(plant, K).stable
        _assert_margin_digital(plant, K)


def test_sample_rate_that_destabilises_the_sampled_loop_is_refused_with_the_reason(
        default_scene_design_plant):
    """At 1 Hz the fitted chain's first mode (3.2-3.5 rad/s, depending on the fit) lies above
    the Nyquist frequency pi rad/s: the exact sampled loop (ZOH plant and controller) has an
    aliased pole near 2.98 rad/s with a positive real part (+0.005 with the current fit), a real
    instability of the design loop; pd() refuses 1 Hz and says why. The instability itself is
    checked below on the loop built by hand, so the test does not hang on the fit's digits."""
    plant = default_scene_design_plant
    with pytest.raises(ValueError, match=r"pd: .*pole at .*sample_time = 1 s.*Nyquist.*"
                                         r"modes above the Nyquist frequency, 3.2\d* rad/s, alias"):
        controllers.pd(plant, natural_frequency=0.2, sample_time=1.0)
    # the same sampled loop, built by hand, is analysed, not crashed on (it raised
    # LinAlgError: a refinement point fell on the unit-circle pole of the sampled chain mode)
    Kc = controllers.pd(plant, natural_frequency=0.2)
    Kd = control.c2d(Kc, 1.0, method="zoh")
    Kd = control.ss(Kd.A, Kd.B, Kd.C, Kd.D, 1.0, inputs=list(Kc.input_labels),
                    outputs=["torque"])
    m = controllers.margins(plant, Kd)
    assert math.isfinite(m.phase_margin) and m.modulus_margin < 0.2  # near -1 at 2.98 rad/s
    assert not controllers.spillover(plant, Kd).stable


def _assert_margin_digital(plant, K):
    z = controllers.close_loop(plant, K).poles()
    s = np.log(z) / K.dt
    alpha = controllers.MARGIN * np.abs(s).max()
    assert s.real.max() <= -alpha


def test_pathological_sample_time_is_refused():
    """omega T = k pi puts exp(+-j omega T) on one point of the unit circle and the sampled
    plant cannot control the mode (pathological sampling; Kalman, Ho and Narendra 1963). Found
    by the design fuzz: natural_frequency 1e-4 rad/s and sample_time 2 pi / 1e-2 s put the
    modes of 2 and 30 rad/s (omega T = 400 pi, 6000 pi) on z = 1, and pd returned a loop with
    poles at -6e-16 and no warning. A sample time 0.37 % longer (omega T = 401.48 pi and
    6022.2 pi) is not pathological: the sampled loop's own check judges it (here the aliased
    2 rad/s mode is destabilised, and named)."""
    plant = modal_plant(250.0, [(2.0, 0.0, 0.04, 0.04), (30.0, 0.0, 0.0, 0.02)])
    T = 2.0 * math.pi / 1e-2
    with pytest.raises(ValueError, match=r"sample_time 628\.3\d* s samples the 2 rad/s mode .*"
                                         r"omega T = 400 pi.*pathological"):
        controllers.pd(plant, natural_frequency=1e-4, damping=1.0, sample_time=T)
    with pytest.raises(ValueError, match=r"pole at .*modes above the Nyquist frequency, 2 rad/s"
                       ) as refusal:
        controllers.pd(plant, natural_frequency=1e-4, damping=1.0, sample_time=1.0037 * T)
    assert "pathological" not in str(refusal.value)
