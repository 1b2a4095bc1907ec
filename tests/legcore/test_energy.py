"""Energy models on hand-checkable cases and the work–energy theorem on a PUMA 560 motion."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from legcore.dynamics import inverse_dynamics
from legcore.energy import (
    ENERGY_MODELS,
    electrical_energy,
    energy,
    integrate,
    joules_to_kwh,
    kwh_to_joules,
    mechanical_energy,
    mechanical_power,
    positive_work,
    torque_squared,
)
from legcore.robots import catalog

PUMA_G = np.array([-62.6111, 107.815, -53.7063, 76.0364, 71.923, 76.686])
KT = KE = 0.228  # N·m/A, V·s/rad (joints 1–3)
R = 1.6  # Ω


def test_constant_torque_constant_speed():
    t = np.linspace(0.0, 4.0, 9)
    tau = np.tile([3.0, -2.0], (9, 1))  # joint 2 brakes
    qd = np.tile([0.5, 0.25], (9, 1))
    mech = mechanical_energy(qd, tau, t)
    np.testing.assert_allclose(mech.per_joint, [3 * 0.5 * 4, 2 * 0.25 * 4], rtol=1e-14)
    assert mech.total == pytest.approx(8.0)
    assert mech.unit == "J"
    assert mech.power.shape == (9, 2)
    pos = positive_work(qd, tau, t)
    np.testing.assert_allclose(pos.per_joint, [6.0, 0.0], rtol=1e-14)
    np.testing.assert_allclose(mechanical_power(qd, tau)[0], [1.5, -0.5])
    tsq = torque_squared(tau, t)
    np.testing.assert_allclose(tsq.per_joint, [9 * 4, 4 * 4], rtol=1e-14)
    assert tsq.unit == "N^2*m^2*s"


def test_trapezoid_rule_exact_for_linear_and_known_error_for_quadratic():
    t = np.array([0.0, 0.1, 0.5, 0.6, 1.3, 2.0])  # non-uniform
    y = (3.0 * t - 1.0)[:, None]
    assert integrate(y, t)[0] == pytest.approx(1.5 * 4.0 - 2.0, rel=1e-14)
    K = 11
    h = 1.0 / (K - 1)
    t = np.linspace(0.0, 1.0, K)
    # trapezoid error of ∫0^1 t² dt is (b - a) h² f'' / 12 = h² / 6
    assert integrate((t**2)[:, None], t)[0] == pytest.approx(1 / 3 + h**2 / 6, rel=1e-13)


def test_per_trajectory_time_grids():
    # two trajectories of different durations in one batch: t (B, K)
    t = np.stack([np.linspace(0, 1, 5), np.linspace(0, 3, 5)])
    tau = np.full((2, 5, 1), 2.0)
    qd = np.full((2, 5, 1), 1.0)
    np.testing.assert_allclose(mechanical_energy(qd, tau, t).total, [2.0, 6.0])


def test_holding_torque_costs_electrical_not_mechanical_energy():
    robot = catalog.get("puma560")
    T = 5.0
    t = np.linspace(0.0, T, 51)
    tau = np.tile([10.0, -40.0, 15.0, 1.0, 1.0, 1.0], (51, 1))
    qd = np.zeros_like(tau)
    mech = mechanical_energy(qd, tau, t)
    np.testing.assert_array_equal(mech.per_joint, 0.0)
    el = electrical_energy(qd, tau, t, robot)
    expected = R * (tau[0, :3] / (PUMA_G[:3] * KT)) ** 2 * T
    np.testing.assert_allclose(el.per_joint[:3], expected, rtol=1e-13)
    assert np.all(np.isnan(el.per_joint[3:]))  # wrist motors: no electrical data
    assert el.joints.tolist() == [True, True, True, False, False, False]
    assert el.total == pytest.approx(expected.sum(), rel=1e-13)
    # joint 2: I = 40 / (107.815 · 0.228) = 1.62725 A -> P = 1.6 · I² = 4.23672 W
    assert el.current[0, 1] == pytest.approx(-40 / (107.815 * 0.228), rel=1e-12)
    assert el.per_joint[1] == pytest.approx(1.6 * (40 / (107.815 * 0.228)) ** 2 * 5.0, rel=1e-12)
    np.testing.assert_allclose(el.joule_energy[:3], el.per_joint[:3], rtol=1e-14)
    np.testing.assert_array_equal(el.back_emf[:, :3], 0.0)


def test_electrical_power_moving_motor_by_hand():
    robot = catalog.get("puma560")
    t = np.linspace(0.0, 2.0, 3)
    tau = np.zeros((3, 6))
    qd = np.zeros((3, 6))
    tau[:, 1], qd[:, 1] = 20.0, 1.0  # joint 2 drives: τ = 20 N·m at 1 rad/s for 2 s
    tau[:, 0], qd[:, 0] = 20.0, 1.0  # joint 1: same, but G1 < 0 (direction reversal)
    el = electrical_energy(qd, tau, t, robot)
    # motor side by hand, joint 2: τ_m = 20/107.815, ω_m = 107.815 rad/s
    I2 = (20.0 / 107.815) / 0.228
    V2 = 0.228 * 107.815
    assert el.current[0, 1] == pytest.approx(I2)
    assert el.back_emf[0, 1] == pytest.approx(V2)
    P2 = 1.6 * I2**2 + V2 * I2  # = 1.6 I² + 20 W (Ke = Kt: back-EMF power = mechanical power)
    assert V2 * I2 == pytest.approx(20.0, rel=1e-14)
    assert el.per_joint[1] == pytest.approx(P2 * 2.0, rel=1e-13)
    # joint 1: I and V_e both flip sign with G; the power does not depend on the sign of G
    I1 = (20.0 / -62.6111) / 0.228
    assert el.current[0, 0] == pytest.approx(I1)
    assert el.per_joint[0] == pytest.approx((1.6 * I1**2 + 20.0) * 2.0, rel=1e-13)


def test_regenerative_braking_option():
    robot = catalog.get("puma560")
    t = np.linspace(0.0, 1.0, 2)
    tau = np.zeros((2, 6))
    qd = np.zeros((2, 6))
    tau[:, 1], qd[:, 1] = -20.0, 2.0  # braking: mechanical power -40 W
    I = -20.0 / (107.815 * 0.228)
    P = 1.6 * I**2 - 40.0
    assert P < 0
    assert electrical_energy(qd, tau, t, robot).per_joint[1] == pytest.approx(P)
    assert electrical_energy(qd, tau, t, robot, regenerative=False).per_joint[1] == 0.0


def test_electrical_needs_motor_data():
    leg = catalog.get("calderon_leg")
    t = np.linspace(0, 1, 4)
    with pytest.raises(ValueError, match="motors: no joint has electrical data"):
        electrical_energy(np.zeros((4, 3)), np.ones((4, 3)), t, leg)
    with pytest.raises(ValueError, match="robot"):
        energy("electrical", 0, np.zeros((4, 3)), 0, np.ones((4, 3)), t)
    with pytest.raises(ValueError, match="model: unknown"):
        energy("nuclear", 0, np.zeros((4, 3)), 0, np.ones((4, 3)), t)


def test_time_grid_validation():
    with pytest.raises(ValueError, match="strictly increasing"):
        integrate(np.ones((3, 1)), [0.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="t: last axis"):
        integrate(np.ones((3, 1)), [0.0, 1.0])


def test_kwh():
    assert joules_to_kwh(3.6e6) == pytest.approx(1.0)
    assert kwh_to_joules(2.5e-3) == pytest.approx(9000.0)
    res = mechanical_energy(np.ones((2, 1)), np.full((2, 1), 3.6e6), [0.0, 1.0])
    assert res.total_kwh == pytest.approx(1.0)
    with pytest.raises(ValueError, match="total_kwh"):
        _ = torque_squared(np.ones((2, 1)), [0.0, 1.0]).total_kwh


def test_work_energy_theorem_on_puma_motion():
    """∫ τ·q̇ dt (signed mechanical power of the frictionless RNEA torques) equals the change of
    kinetic (incl. rotor) + potential energy computed by pinocchio from the states alone."""
    robot = catalog.get("puma560")
    K = 4001
    t = np.linspace(0.0, 2.0, K)
    q0 = np.array([0.2, 0.6, -1.8, 0.3, 0.5, -0.4])
    A = np.array([0.5, 0.4, 0.6, 1.0, 0.8, 1.2])
    w = np.array([1.3, 0.9, 1.7, 2.0, 2.5, 1.1])
    q = q0 + A * np.sin(w * t[:, None])
    qd = A * w * np.cos(w * t[:, None])
    qdd = -A * w**2 * np.sin(w * t[:, None])
    tau = inverse_dynamics(robot, q, qd, qdd)
    work = integrate(mechanical_power(qd, tau), t).sum()

    def total_energy(k: int) -> float:
        data = robot.data()
        M = pin.crba(robot.model, data, q[k])  # includes the armature Jm·G²
        return 0.5 * qd[k] @ M @ qd[k] + pin.computePotentialEnergy(robot.model, data, q[k])

    dE = total_energy(K - 1) - total_energy(0)
    assert abs(dE) > 1.0
    assert work == pytest.approx(dE, rel=1e-5)
    # every registered model runs through the uniform signature
    for name, f in ENERGY_MODELS.items():
        res = f(q, qd, qdd, tau, t, robot)
        assert res.per_joint.shape == (6,), name
        assert np.isfinite(res.total), name
