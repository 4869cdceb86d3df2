"""Hub + appendages: limiting cases, exact reference, convergence of truncated plants."""

import math

import numpy as np
import pytest

from appendages import Beam
from spacecraft import Hub, Mount, Spacecraft

ROD = Beam.circular_rod(10.0, 0.01, 7800.0, 2.06e11)  # the paper's rod (PAPER.md)


def boom(appendage, hub=(50.0, 20.0), position=(0.5, 0.0), direction=0.0):
    return Spacecraft(Hub(*hub), [Mount(appendage, position, direction)])


def wings(appendage, hub=(100.0, 50.0)):
    return Spacecraft(Hub(*hub), [Mount(appendage, (1.0, 0.0), 0.0, name="left"),
                                  Mount(appendage, (-1.0, 0.0), math.pi, name="right")])


def test_infinitely_heavy_hub_gives_cantilever_frequencies():
    # Hub mass and inertia 1e12 (beam 6.1 kg): the attachment end is clamped; the coupled
    # frequencies tend to the clamped-free ones, beta L = 1.8751, 4.6941, ... (Blevins), with
    # a deviation of order m_beam/m_hub ~ 1e-11.
    craft = boom(ROD, hub=(1e12, 1e12))
    np.testing.assert_allclose(craft.natural_frequencies(5), ROD.cantilever_frequencies(5), rtol=1e-9)
    truncated = boom(ROD.truncated(12), hub=(1e12, 1e12))
    np.testing.assert_allclose(truncated.natural_frequencies(3, exact=False),
                               ROD.cantilever_frequencies(3), rtol=1e-9)


def test_massless_hub_at_the_root_gives_free_free_frequencies():
    # A hub of 1e-9 kg, 1e-12 kg m^2 with the beam's root at its centre adds nothing: the
    # coupled frequencies are the free-free ones (deviation ~ m_hub/m_beam).
    craft = boom(ROD, hub=(1e-9, 1e-12), position=(0.0, 0.0), direction=0.7)
    np.testing.assert_allclose(craft.natural_frequencies(5), ROD.natural_frequencies(5), rtol=1e-8)


def test_low_frequency_limit_is_total_inertia_about_system_centre():
    # theta/torque -> 1/(J_total s^2); the next term is O(s^0), so at w = 1e-5 rad/s the
    # relative deviation is ~ (w/w_1)^2 ~ 1e-9.
    craft = Spacecraft(Hub(80.0, 30.0), [Mount(ROD, (1.0, 0.4), 0.3, name="a"),
                                         Mount(ROD, (-0.5, -0.2), 2.0, name="b")])
    c = craft.center_of_mass
    # J_total by hand: hub about c, rods (m L^2/12) about their centres, parallel axes
    J = 30.0 + 80.0 * c @ c
    for p, angle in (((1.0, 0.4), 0.3), ((-0.5, -0.2), 2.0)):
        centre = np.array(p) + 5.0 * np.array([math.cos(angle), math.sin(angle)])
        J += ROD.inertia + ROD.mass * (centre - c) @ (centre - c)
    assert craft.inertia == pytest.approx(J, rel=1e-14)
    w = 1e-5
    G = craft.frequency_response([w]).frdata[0, 0, 0]
    assert G == pytest.approx(-1.0 / (J * w**2), rel=1e-8)
    P = Spacecraft(craft.hub, [Mount(ROD.truncated(6), m.position, m.angle, name=m.name)
                               for m in craft.mounts]).plant()
    assert P(1j * w)[0, 0] == pytest.approx(-1.0 / (J * w**2), rel=1e-8)


@pytest.mark.parametrize("method", ["craig-bampton", "residual", "free-free"])
def test_truncated_plant_poles_converge_to_exact_coupled_frequencies(method):
    exact = wings(ROD).natural_frequencies(4)
    errors = []
    for n in (2, 4, 8, 16):
        craft = wings(ROD.truncated(n, method=method))
        errors.append(np.abs(craft.natural_frequencies(4, exact=False) / exact - 1).max())
        poles = np.sort(np.abs(np.linalg.eigvals(craft.plant().A)))
        nonzero = poles[poles > 1e-6]
        # the plant's poles are the coupled frequencies (undamped: pairs +-i w)
        np.testing.assert_allclose(nonzero[0:8:2], craft.natural_frequencies(4, exact=False), rtol=1e-9)
    assert all(b < a for a, b in zip(errors, errors[1:]))
    # free-free truncation misses the rotational flexibility of the dropped modes,
    # sum_{k>n} phi_k'(0)^2/w_k^2 ~ 1/n: 16 modes still leave ~6 %
    limit = {"craig-bampton": 1e-6, "residual": 1e-6, "free-free": 0.1}[method]
    assert errors[-1] < limit


def test_craig_bampton_is_the_best_reduction_in_coupled_use():
    exact = boom(ROD).natural_frequencies(3)
    error = {m: np.abs(boom(ROD.truncated(6, method=m)).natural_frequencies(3, exact=False) / exact - 1).max()
             for m in ("craig-bampton", "residual", "free-free")}
    assert error["craig-bampton"] < error["residual"] < error["free-free"]


def test_exact_frequency_response_matches_truncated_plant():
    craft = wings(ROD)
    truncated = wings(ROD.truncated(20)).plant()
    w = np.logspace(-2, 0.5, 30)
    exact = craft.frequency_response(w).frdata[0, 0]
    np.testing.assert_allclose(truncated(1j * w)[0, 0], exact, rtol=1e-6)
    omega = craft.frequency_response(w, output="omega").frdata[0, 0]
    np.testing.assert_allclose(omega, 1j * w * exact, rtol=1e-14)


def test_plant_signals_and_pruning_of_symmetric_modes():
    craft = wings(ROD.truncated(8))
    P = craft.plant(tip_deflection=True, root_loads=True, disturbances=True)
    assert P.input_labels == ["torque", "disturbance_torque", "force_x", "force_y", "left_tip_force", "right_tip_force"]
    assert P.output_labels == ["theta", "omega", "left_tip_deflection", "left_root_force",
                               "left_root_moment", "right_tip_deflection", "right_root_force",
                               "right_root_moment"]
    full = craft.plant()
    pruned = craft.plant(prune=True)
    # symmetric bending of two identical wings is not excited by torque nor seen in theta:
    # half of the 16 elastic modes plus one rigid translation direction... are dropped
    assert pruned.nstates < full.nstates
    w = np.logspace(-2, 1.5, 50)
    np.testing.assert_allclose(pruned(1j * w), full(1j * w), rtol=1e-10)


def test_root_loads_and_tip_deflection_static_checks():
    # Hub torque on a single boom with its root at the hub centre: at low frequency the whole
    # craft spins rigidly; the root moment transmitted to the boom is J_boom_root/J_total times
    # the torque (the boom's share of angular acceleration), J_boom_root = m L^2/3 about the
    # root when the hub centre is the system centre only in the limit of a heavy hub.
    craft = boom(ROD.truncated(10), hub=(1e9, 1e9), position=(0.0, 0.0))
    P = craft.plant(root_loads=True, tip_deflection=True)
    w = 1e-4
    H = P(1j * w)
    J_root = ROD.mass * ROD.length**2 / 3.0
    theta = H[0, 0]
    moment = H[P.output_labels.index("appendage1_root_moment"), 0]
    assert moment / ((1j * w) ** 2 * theta) == pytest.approx(J_root, rel=1e-6)
    force = H[P.output_labels.index("appendage1_root_force"), 0]
    assert force / ((1j * w) ** 2 * theta) == pytest.approx(ROD.mass * ROD.length / 2, rel=1e-6)


def test_any_appendage_with_the_interface_couples():
    class Rigid:
        """A rigid rod offering only the W-matrix interface (no class of ours)."""
        length, mass = 2.0, 3.0
        inertia = 3.0 * 4.0 / 12

        def W(self, s):
            s = np.asarray(s, dtype=complex)[..., None, None]
            a = self.length / 2
            return np.array([[1 / self.mass + a**2 / self.inertia, -a / self.inertia],
                             [-a / self.inertia, 1 / self.inertia]]) / s**2

    craft = Spacecraft(Hub(10.0, 2.0), [Mount(Rigid(), (0.5, 0.0), 0.0)])
    w = 0.3
    G = craft.frequency_response([w]).frdata[0, 0, 0]
    assert G == pytest.approx(-1 / (craft.inertia * w**2), rel=1e-12)


def test_bad_input():
    with pytest.raises(ValueError, match="hub mass must be positive.*kg"):
        Hub(-1.0, 1.0)
    with pytest.raises(ValueError, match=r"hub inertia.*kg\*m\^2"):
        Hub(1.0, 0.0)
    with pytest.raises(TypeError, match="W-matrix interface"):
        Mount(object(), (0, 0), 0.0)
    with pytest.raises(ValueError, match="position"):
        Mount(ROD, (0, 0, 0), 0.0)
    with pytest.raises(TypeError, match="mounts\\[0\\] must be a Mount"):
        Spacecraft(Hub(1.0, 1.0), [ROD])
    with pytest.raises(TypeError, match="no finite realisation"):
        boom(ROD).plant()
    with pytest.raises(ValueError, match="unique"):
        Spacecraft(Hub(1.0, 1.0), [Mount(ROD, name="a"), Mount(ROD, name="a")])
