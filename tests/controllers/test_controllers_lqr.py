"""LQR + estimator: rigid-body closed form, output feedback, tracking, digital design, errors."""
import math
import warnings

import control
import numpy as np
import pytest
import scipy.linalg

import controllers
from plants import modal_plant
from controllers.lqr import KalmanNoise, lqr_design, reference_state


J = 250.0  # kg m^2
RIGID = modal_plant(J)
CHAIN = modal_plant(J, [(2.0, 0.005, 0.04, 0.04)],
                    tips=[("wing_tip_deflection", [0.5])])
BEAM = modal_plant(J, [(2.1, 0.005, 0.041, 0.041), (12.0, 0.005, 0.015, 0.015),
                       (35.0, 0.005, 0.006, 0.006)], tips=[("wing_tip_deflection", [0.5, -0.2, 0.1])])
WEIGHTS = dict(attitude_weight=400.0, rate_weight=1000.0, torque_weight=1.0)


def test_rigid_hub_lqr_gain_closed_form():
    """Double integrator J theta'' = torque, cost q theta^2 + q_w omega^2 + r torque^2.

    The Riccati equation in P = [[p1, p2], [p2, p3]] gives p2 = J sqrt(q r),
    p3 = J sqrt(r (2 p2 + q_w)), so K = [sqrt(q/r), sqrt((2 J sqrt(q r) + q_w)/r)]
    (Anderson & Moore, Optimal Control, ex. 3.3-type derivation)."""
    q, qw, r = 400.0, 1000.0, 2.0
    design = lqr_design(RIGID, attitude_weight=q, rate_weight=qw, torque_weight=r)
    K_exact = [math.sqrt(q / r), math.sqrt((2 * J * math.sqrt(q * r) + qw) / r)]
    np.testing.assert_allclose(design.K, [K_exact], rtol=1e-10)  # ARE solver: ~1e-13
    np.testing.assert_allclose(design.Q, np.diag([q, qw]), rtol=1e-15)
    np.testing.assert_allclose(design.R, [[r]], rtol=1e-15)


def test_output_feedback_controller_signals_and_separation():
    design = lqr_design(CHAIN, **WEIGHTS)
    K = design.controller
    assert list(K.input_labels) == ["theta_ref", "theta", "omega"]
    assert list(K.output_labels) == ["torque"]
    assert K.nstates == CHAIN.nstates  # the estimate of the chain's states, nothing else
    loop = controllers.close_loop(CHAIN, K)
    # separation principle: closed-loop poles = regulator poles + estimator poles
    expected = np.concatenate([design.regulator_poles, design.estimator_poles])
    got = loop.poles()
    for p in expected:
        assert np.min(np.abs(got - p)) < 1e-7 * max(1.0, abs(p))
    assert got.real.max() < 0


def test_closed_loop_stable_on_design_and_truth_for_several_weights():
    rng = np.random.default_rng(3)
    for _ in range(5):
        q, qw, r = 10 ** rng.uniform(0, 3), 10 ** rng.uniform(0, 3), 10 ** rng.uniform(-1, 1)
        K = controllers.lqr(CHAIN, attitude_weight=q, rate_weight=qw, torque_weight=r)
        assert controllers.close_loop(CHAIN, K).poles().real.max() < 0
        assert controllers.spillover(BEAM, K).stable


def test_reference_tracking_zero_steady_state_error():
    """DC gain theta_ref -> theta of the closed loop is exactly 1, on the design plant and on a
    different free-floating truth plant (a rigid rotation is an equilibrium of both)."""
    K = controllers.lqr(CHAIN, **WEIGHTS)
    for plant in (CHAIN, BEAM):
        loop = controllers.close_loop(plant, K)
        dc = loop.D - loop.C @ np.linalg.solve(loop.A, loop.B)
        i_theta = list(loop.output_labels).index("theta")
        i_tip = list(loop.output_labels).index("wing_tip_deflection")
        assert dc[i_theta, 0] == pytest.approx(1.0, rel=1e-9)  # linear solve: round-off only
        assert abs(dc[i_tip, 0]) < 1e-9  # a rigid rotation does not bend the wing
    response = controllers.slew(controllers.close_loop(BEAM, K), 0.3, 30.0, t_final=120.0)
    m = controllers.metrics(response)
    assert m["final_attitude_error"] < 1e-6 * 0.3  # slowest pole decays ~e^-0.2t over 90 s


def test_reference_state_is_unit_rigid_rotation():
    """x_ref solves M x = [0; 1; 0], M = [A; C_theta; C_omega], by an SVD least-squares solve,
    which is backward stable: the residual is at most c eps ||M|| ||x|| with c a modest
    multiple of the dimension (N. J. Higham, Accuracy and Stability of Numerical Algorithms, 2nd
    ed., SIAM 2002, ch. 20).
    ||M|| ~ w_max^2 = 1225 here, so the bound is ~3e-12 with c = 10, while the exact residual is
    0; the order of the BLAS threads' sums moves the computed one within that bound (1.09e-14
    was measured with 2 threads, against a former bare atol of 1e-14)."""
    x_ref = reference_state(BEAM)
    M = np.vstack([BEAM.A, BEAM.C[:2]])
    tol = 10 * np.finfo(float).eps * np.linalg.norm(M, 2) * np.linalg.norm(x_ref)
    np.testing.assert_allclose(BEAM.A @ x_ref, 0.0, atol=tol)
    np.testing.assert_allclose(BEAM.C @ x_ref, [1.0, 0.0, 0.0], atol=tol)


def test_deflection_weight_enters_Q():
    d = lqr_design(CHAIN, **WEIGHTS, deflection_weight=1e4)
    Cw = CHAIN.C  # rows theta, omega, tip
    W = np.diag([WEIGHTS["attitude_weight"], WEIGHTS["rate_weight"], 1e4])
    # each entry of Cw^T W Cw is a sum of 3 nonnegative products (C >= 0: no cancellation);
    # both sides are within gamma_3 ~ 3 eps of it per product sum (Higham, Accuracy and
    # Stability of Numerical Algorithms, 2nd ed., sec. 3.5), the design's side with 3 more
    # roundings (W / r0, x r0, the symmetrisation): their difference <= ~10 eps relative
    assert np.all(Cw >= 0)
    np.testing.assert_allclose(d.Q, Cw.T @ W @ Cw, rtol=32 * np.finfo(float).eps, atol=0)
    d2 = lqr_design(CHAIN, **WEIGHTS, deflection_weight={"wing_tip_deflection": 1e4})
    np.testing.assert_allclose(d2.K, d.K, rtol=1e-12)
    base = lqr_design(CHAIN, **WEIGHTS)
    # weighting the deflection adds damping to the flexible mode (regulator pole at ~2 rad/s)
    zeta = lambda p: np.min(-p.real / np.abs(p))  # noqa: E731
    assert zeta(d.regulator_poles) > zeta(base.regulator_poles)


def test_kalman_and_luenberger_estimators():
    base = lqr_design(CHAIN, **WEIGHTS)
    assert base.L.shape == (CHAIN.nstates, 2)
    assert base.estimator_poles.real.max() < 0
    noise = KalmanNoise.default(J, WEIGHTS["attitude_weight"], WEIGHTS["torque_weight"])
    explicit = lqr_design(CHAIN, **WEIGHTS, estimator=noise)
    np.testing.assert_allclose(explicit.L, base.L, rtol=1e-12)
    luenberger = lqr_design(CHAIN, **WEIGHTS, estimator=base.L)
    np.testing.assert_allclose(luenberger.controller.A, base.controller.A, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("speed", [1.0, 3.0, 6.0])
def test_default_kalman_filter_rigid_body_closed_form(speed):
    """Rigid hub, default noises V_theta = 1/q, W = k^4/r, V_omega = V_theta w_e^2 with
    w_e = k (q/(r J^2))^(1/4). The filter Riccati equation (dual LQR on A^T with C^T = I,
    scaled by V_theta) is solved by P = [[a w_e, b w_e^2], [b w_e^2, c w_e^3]] with b = 1/2,
    a = c = sqrt(3)/2, so the estimator poles are the roots of s^2 + sqrt(3) w_e s + w_e^2."""
    q, r = WEIGHTS["attitude_weight"], WEIGHTS["torque_weight"]
    design = lqr_design(RIGID, **WEIGHTS, estimator_speed=speed)
    w_e = speed * (q / (r * J * J)) ** 0.25
    expected = np.roots([1.0, math.sqrt(3.0) * w_e, w_e * w_e])
    np.testing.assert_allclose(np.sort_complex(design.estimator_poles), np.sort_complex(expected),
                               rtol=1e-9)  # Riccati solver round-off, ~1e-13


def test_digital_lqr():
    T = 0.05
    design = lqr_design(CHAIN, **WEIGHTS, sample_time=T)
    K = design.controller
    assert K.dt == T
    assert list(K.input_labels) == ["theta_ref", "theta", "omega"]
    assert np.abs(design.regulator_poles).max() < 1 and np.abs(design.estimator_poles).max() < 1
    loop = controllers.close_loop(CHAIN, K)
    assert np.abs(loop.poles()).max() < 1
    dc = loop.D - loop.C @ np.linalg.solve(loop.A - np.eye(loop.nstates), loop.B)
    assert dc[0, 0] == pytest.approx(1.0, rel=1e-9)
    verdict = controllers.spillover(BEAM, K)
    assert verdict.stable
    # the digital design approaches the continuous one as T -> 0 (first-order cost sampling)
    fine = lqr_design(CHAIN, **WEIGHTS, sample_time=1e-4)
    cont = lqr_design(CHAIN, **WEIGHTS)
    np.testing.assert_allclose(fine.K, cont.K, rtol=2e-3)


def test_errors():
    with pytest.raises(ValueError, match=r"torque_weight R must be positive definite"):
        controllers.lqr(CHAIN, attitude_weight=1.0, rate_weight=1.0, torque_weight=0.0)
    with pytest.raises(ValueError, match=r"rate_weight must be non-negative"):
        controllers.lqr(CHAIN, attitude_weight=1.0, rate_weight=-1.0, torque_weight=1.0)
    with pytest.raises(ValueError, match=r"attitude_weight must be positive .*undetectable"):
        controllers.lqr(CHAIN, attitude_weight=0.0, rate_weight=1.0, torque_weight=1.0)
    with pytest.raises(TypeError, match="torque_weight must be a real number"):
        controllers.lqr(CHAIN, attitude_weight=1.0, rate_weight=1.0, torque_weight="1")
    with pytest.raises(ValueError, match="positive semidefinite"):
        controllers.lqr(CHAIN, **WEIGHTS, deflection_weight=np.array([[-1.0]]))
    with pytest.raises(ValueError, match="no '\\*tip_deflection' output"):
        controllers.lqr(RIGID, **WEIGHTS, deflection_weight=1.0)
    with pytest.raises(ValueError, match="not tip-deflection outputs"):
        controllers.lqr(CHAIN, **WEIGHTS, deflection_weight={"boom_tip_deflection": 1.0})
    # torque has no effect at all: no rigid-body double integrator from torque to theta
    dead = control.ss(RIGID.A, np.zeros((2, 1)), RIGID.C, 0, inputs=["torque"],
                      outputs=["theta", "omega"])
    with pytest.raises(ValueError, match="free-floating"):
        controllers.lqr(dead, **WEIGHTS)
    with pytest.raises(ValueError, match="Luenberger estimator gain must have shape"):
        controllers.lqr(CHAIN, **WEIGHTS, estimator=np.zeros((3, 2)))
    with pytest.raises(ValueError, match=r"estimator: .*estimator is not stable"):
        controllers.lqr(CHAIN, **WEIGHTS, estimator=np.zeros((CHAIN.nstates, 2)))
    with pytest.raises(ValueError, match="Luenberger gain array is a continuous-time estimator"):
        controllers.lqr(CHAIN, **WEIGHTS, estimator=np.zeros((CHAIN.nstates, 2)),
                        sample_time=0.01)
    with pytest.raises(ValueError, match="estimator must be 'kalman'"):
        controllers.lqr(CHAIN, **WEIGHTS, estimator="luenberger")
    # rigid-body crossover of this design 0.366 rad/s: T <= 2 pi / (10 x 0.366) = 1.72 s
    with pytest.raises(ValueError, match="sample_time .* too long"):
        controllers.lqr(CHAIN, **WEIGHTS, sample_time=2.0)
    with pytest.raises(ValueError, match="attitude_noise must be positive"):
        KalmanNoise(torque_noise=1.0, attitude_noise=0.0, rate_noise=1.0)


# --------------------------------------------------------------------------------------------
# undamped hub + beam plants: scale-invariant stabilisability / detectability tests
# --------------------------------------------------------------------------------------------
def _rod():
    from appendages import Beam

    return Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)  # the paper's rod, no damping


def _craft(*appendages):
    from spacecraft import Hub, Mount, Spacecraft

    mounts = [Mount(a, (0.5, 0.0), 0.0) if k == 0 else Mount(a, (-0.5, 0.0), math.pi)
              for k, a in enumerate(appendages)]
    return Spacecraft(Hub(100.0, 50.0), mounts)


def _design_at_0p1(craft):
    """The craft's plant and its LQR design with q = (0.01 J)^2, r = 1: rigid-body bandwidth
    (q / (r J^2))^(1/4) = 0.1 rad/s."""
    plant = craft.plant()
    J = craft.inertia
    return plant, lqr_design(plant, attitude_weight=(J * 0.01) ** 2, rate_weight=0.0,
                             torque_weight=1.0)


def _loop_poles_outside_removed(plant, design):
    """Closed-loop poles of the design's controller on the whole plant, without those that
    stay within the margin of a removed mode's open-loop eigenvalue (+-j w, undamped)."""
    poles = controllers.close_loop(plant, design.controller).poles()
    keep = np.ones(poles.size, dtype=bool)
    for mode in design.removed_modes:
        for sign in (1.0, -1.0):
            near = np.abs(poles - sign * 1j * mode.frequency) <= design.margin
            keep &= ~near
    return poles[keep]


def _assert_guarantee(plant, design):
    """Every pole the loop influences at Re <= -margin: the regulator's and estimator's (the
    separation principle) and the whole loop's on the plant, the removed modes aside."""
    assert design.margin > 0
    assert design.regulator_poles.real.max() <= -design.margin
    assert design.estimator_poles.real.max() <= -design.margin
    assert _loop_poles_outside_removed(plant, design).real.max() <= -design.margin


@pytest.mark.parametrize("n_modes", [12, 16, pytest.param(40, marks=pytest.mark.slow)])
def test_lqr_on_undamped_beam_with_many_modes(n_modes):
    """Regression: the PBH test compared sigma_min([A - lambda I, B]) with 1e-9 sigma_max, and
    sigma_max grows like the highest w^2, so hub + beam plants with >= 12 undamped modes were
    refused as 'uncontrollable' although every beam mode is excited by the torque. With 40
    modes the plain LQR left the highest modes at Re ~ -1e-10, and with 2 BLAS threads one at
    +2.9e-13: the prescribed degree of stability puts every pole at Re <= -margin (2e-10 1/s
    here, 1e-13 x the highest mode 1978 rad/s), whatever the thread count."""
    craft = _craft(_rod().truncated(n_modes))
    plant, design = _design_at_0p1(craft)
    assert design.removed_modes == ()
    _assert_guarantee(plant, design)
    poles = controllers.close_loop(plant, design.controller).poles()
    # separation: the closed loop is exactly regulator + estimator poles (round-off ~1e-9 |p|)
    for p in np.concatenate([design.regulator_poles, design.estimator_poles]):
        assert np.min(np.abs(poles - p)) < 1e-6 * max(1.0, abs(p))


def test_lqr_on_25_body_chain_leaves_its_free_tip_mode_out():
    """Finding of issue 9: HingedChain.rfem(rod, 25) on a hub failed with 'estimator is not
    stable' (an estimator pole at +1e-13 + 656j): the chain's top mode, localised at its free
    tip, takes part in theta/torque with 1e-16 of the inertia (the input reaches it by 3e-9 in
    energy coordinates, theta sees it by 6e-12), so neither the Kalman filter nor any loop can
    move it. It is left out of the design model, named, and stays undamped in the loop; every
    other pole has Re <= -margin."""
    from appendages import HingedChain

    craft = _craft(HingedChain.rfem(_rod(), 25))
    with pytest.warns(controllers.RemovedModesWarning, match=r"lqr: 1 mode.* 656\.25 rad/s"):
        plant, design = _design_at_0p1(craft)
    (mode,) = design.removed_modes
    assert mode.frequency == pytest.approx(656.25, abs=0.01) and mode.damping_ratio == 0.0
    assert mode.participation < controllers.INFLUENCE_TOL
    assert design.design_plant.nstates == plant.nstates - 2
    assert design.controller.nstates == plant.nstates - 2
    _assert_guarantee(plant, design)
    # the removed mode keeps its open-loop place (undamped) in the loop on the whole plant
    poles = controllers.close_loop(plant, design.controller).poles()
    assert np.min(np.abs(poles - 1j * mode.frequency)) <= design.margin


@pytest.mark.parametrize("ratio", [1e4, 1e5, 1e6])
def test_lqr_on_undamped_plants_with_large_hub_ratios(ratio):
    """Finding of issue 9: with hub inertia / appendage inertia = 1e4..1e6 the beam modes take
    part with 1e-6..1e-12 of the inertia; the plain LQR left them at Re = +1e-13..+3e-10 (at
    round-off, the Riccati solution could not resolve them). Now every pole has Re <= -margin;
    the modes are kept (their participation is above INFLUENCE_TOL)."""
    from spacecraft import Hub, Mount, Spacecraft

    rod = _rod()
    craft = Spacecraft(Hub(100.0 * ratio, ratio * rod.inertia),
                       [Mount(rod.truncated(8), (0.5, 0.0), 0.0)])
    plant, design = _design_at_0p1(craft)
    assert design.removed_modes == ()
    _assert_guarantee(plant, design)


def test_modal_correction_moves_one_mode_and_no_other():
    """M - G dK: the flagged pair moves to the target exactly (to round-off of the 2 x 2
    placement, 1e-12 relative), the other eigenvalues stay (left invariant subspace)."""
    from controllers.riccati import modal_correction

    rng = np.random.default_rng(11)
    lam = [complex(-1.0, 2.0), complex(1e-14, 7.0), complex(-3.0, 0.5)]
    blocks = [np.array([[x.real, x.imag], [-x.imag, x.real]]) for x in lam]
    S = rng.standard_normal((6, 6))
    M = S @ scipy.linalg.block_diag(*blocks) @ np.linalg.inv(S)
    G = rng.standard_normal((6, 1))
    dK, reported = modal_correction(M, G, lambda x: x.real > -1e-3,
                                    lambda x: complex(-0.5, x.imag))
    got = np.sort_complex(np.linalg.eigvals(M - G @ dK))
    # the eigenvalues it reports are those of the corrected matrix (same round-off)
    np.testing.assert_allclose(np.sort_complex(reported), got, rtol=0, atol=1e-10)
    want = np.sort_complex(np.array([-1 + 2j, -1 - 2j, -0.5 + 7j, -0.5 - 7j, -3 + 0.5j,
                                     -3 - 0.5j]))
    # eigenvalues of a random 6 x 6 similarity (condition ~1e2): round-off ~1e-13
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-10)


def test_removed_modes_invariant_to_state_and_input_scaling():
    """x = T z with T diagonal (random decades on displacement and rate coordinates alike) and a
    torque in another unit leave the removed modes and their participation unchanged: the
    participation is a residue of theta/torque, independent of the state coordinates, and
    relative to the rigid-body gain 1/J of the same channel."""
    from controllers.modes import design_model

    stuck = modal_plant(J, [(2.0, 0.0, 0.04, 0.04), (30.0, 0.0, 0.0, 0.02),
                            (45.0, 0.0, 0.03, 0.0)])
    rng = np.random.default_rng(7)
    T = 10.0 ** rng.uniform(-3, 3, stuck.nstates)
    scaled = control.ss(stuck.A * T[None, :] / T[:, None], 1e-4 * stuck.B / T[:, None],
                        stuck.C * T[None, :], 0, inputs=list(stuck.input_labels),
                        outputs=list(stuck.output_labels))
    for plant in (stuck, scaled):
        Jp = controllers.rigid_body_inertia(plant)
        design, removed, _ = design_model(plant, critical=1e-9, J=Jp, what="test")
        # exactly the 30 rad/s mode the torque cannot reach and the 45 rad/s one theta and
        # omega cannot see
        assert [m.frequency for m in removed] == pytest.approx([30.0, 45.0], rel=1e-12)
        assert design.nstates == plant.nstates - 4
        np.testing.assert_allclose(controllers.rigid_body_inertia(design), Jp, rtol=1e-12)


def test_symmetric_wings_designed_without_their_symmetric_modes():
    """Finding of issue 9: two identical wings at opposite sides, unpruned, were refused as
    uncontrollable. Their symmetric bending leaves the hub at rest (participation ~1e-26,
    round-off): the design leaves those 8 modes out, announces them and designs on the rest;
    the controller is the one designed on the pruned plant (same transfer function)."""
    rod = _rod()
    craft = _craft(rod.truncated(8), rod.truncated(8))
    J = craft.inertia
    weights = dict(attitude_weight=(J * 0.01) ** 2, rate_weight=0.0, torque_weight=1.0)
    plant = craft.plant()
    with pytest.warns(controllers.RemovedModesWarning, match="lqr: 8 mode"):
        design = lqr_design(plant, **weights)
    pruned = craft.plant(prune=True)
    assert pruned.nstates == plant.nstates - 16
    removed = sorted(m.frequency for m in design.removed_modes)
    symmetric = sorted(set(np.round(np.abs(np.linalg.eigvals(plant.A)), 6))
                       - set(np.round(np.abs(np.linalg.eigvals(pruned.A)), 6)))
    np.testing.assert_allclose(removed, symmetric, rtol=1e-6)  # 6 decimals compared above
    _assert_guarantee(plant, design)
    reference = lqr_design(pruned, **weights)
    w = np.array([0.01, 0.3, 1.0, 3.0, 30.0])
    np.testing.assert_allclose(design.controller(1j * w), reference.controller(1j * w),
                               rtol=1e-6)


@pytest.mark.slow
def test_200_body_chain_tip_mode_is_the_only_removed_one():
    """HingedChain.rfem(rod, 200): every mode but one takes part in theta/torque (>= 6e-10 of
    the inertia, up to 35245 rad/s); the top mode at 45118 rad/s is localised at the free tip,
    its participation decays ~0.5 per link and is round-off at 200 (7e-34). Exactly that pair
    is left out."""
    from appendages.chain import HingedChain

    craft = _craft(HingedChain.rfem(_rod(), 200))
    with pytest.warns(controllers.RemovedModesWarning):
        plant, design = _design_at_0p1(craft)
    (mode,) = design.removed_modes
    assert mode.frequency == pytest.approx(45118.33, abs=0.01)
    assert design.design_plant.nstates == plant.nstates - 2
    assert design.regulator_poles.real.max() <= -design.margin
    assert design.estimator_poles.real.max() <= -design.margin


# undamped, collocated: the two modes' antiresonances (transmission zeros) lie at 1.69 and
# 10.63 rad/s, where high-gain regulator and estimator poles both converge
UNDAMPED = modal_plant(J, [(2.0, 0.0, 0.04, 0.04), (11.0, 0.0, 0.02, 0.02)],
                       tips=[("wing_tip_deflection", [0.5, -0.2])])
# as UNDAMPED's first mode, plus a 30 rad/s mode the torque cannot reach (removed)
STUCK = modal_plant(J, [(2.0, 0.0, 0.04, 0.04), (30.0, 0.0, 0.0, 0.02)])


@pytest.mark.parametrize("plant, bandwidth, speed", [
    (UNDAMPED, 100.0, 1000.0), (UNDAMPED, 300.0, 100.0), (UNDAMPED, 300.0, 1000.0),
    (UNDAMPED, 1000.0, 1000.0), (STUCK, 100.0, 1000.0), (STUCK, 1000.0, 100.0)])
def test_high_gain_loops_meet_the_margin_on_the_loop_itself(plant, bandwidth, speed):
    """Finding of the issue-9 review: at a 100 rad/s bandwidth with estimator_speed = 1000 the
    regulator and estimator spectra each met Re <= -margin (the estimator's poles near the
    1.69 rad/s antiresonance at -sigma = -4e-8, put there by the modal correction), but the
    loop's own computed poles had +1.47e-7 + 1.69j against a margin of 1e-8, with no error.
    High-gain regulator and estimator poles converge on the same transmission zero, and the
    nearly coincident pair in a loop whose matrices hold gains of 4e10 (L ~ 4 w_e^2) is
    computed with an error of ~2e-7 (~0.03 eps ||L||); on the STUCK plant the same showed as
    an error naming no parameter. Now the design checks the loop and raises its degree of
    stability above that round-off; every pole meets the margin, or the error names
    estimator_speed."""
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            design = lqr_design(plant, attitude_weight=J ** 2 * bandwidth ** 4, rate_weight=0.0,
                                torque_weight=1.0, estimator_speed=speed)
    except ValueError as error:
        assert "estimator_speed" in str(error) and "attitude_weight" in str(error)
        return
    removed = [str(w.message) for w in caught
               if issubclass(w.category, controllers.RemovedModesWarning)]
    assert len(removed) == (0 if plant is UNDAMPED else 1), removed
    assert plant is UNDAMPED or "30 rad/s" in removed[0]
    _assert_guarantee(plant, design)
