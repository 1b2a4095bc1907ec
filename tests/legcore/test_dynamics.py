"""Batched RNEA against (1) an independent numpy Newton–Euler on the DH table written here and
(2) pinocchio.rnea per sample; friction by hand from the PUMA 560 reference values."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from legcore.dynamics import (
    COULOMB_DEAD_BAND,
    inverse_dynamics,
    inverse_dynamics_reference,
    joint_friction,
)
from legcore.robots import build_robot, catalog

# ---------------------------------------------------------------------------------------------
# Independent formulation: Corke's standard-DH recursive Newton–Euler (Robotics Toolbox rne_dh),
# link quantities in DH frame i (distal), rotor inertia added as Jm·G²·q̈.
# ---------------------------------------------------------------------------------------------


def _rne_dh(spec, q, qd, qdd, gravity):
    n = len(spec.joints)
    z0 = np.array([0.0, 0.0, 1.0])
    w = np.zeros(3)
    wd = np.zeros(3)
    vd = -np.asarray(gravity, float)  # base accelerates upwards: gravity for free
    Rs, pstars, Fs, Ns = [], [], [], []
    for i, j in enumerate(spec.joints):
        th = q[i] + j.offset
        ct, st, ca, sa = math.cos(th), math.sin(th), math.cos(j.alpha), math.sin(j.alpha)
        R = np.array([[ct, -st * ca, st * sa], [st, ct * ca, -ct * sa], [0.0, sa, ca]])
        pstar = np.array([j.a, j.d * sa, j.d * ca])  # origin i from origin i-1, in frame i
        wd = R.T @ (wd + z0 * qdd[i] + np.cross(w, z0 * qd[i]))
        w = R.T @ (w + z0 * qd[i])
        vd = np.cross(wd, pstar) + np.cross(w, np.cross(w, pstar)) + R.T @ vd
        r = np.asarray(j.com, float)
        I = np.asarray(j.inertia, float)
        vc = np.cross(wd, r) + np.cross(w, np.cross(w, r)) + vd
        Fs.append(j.mass * vc)
        Ns.append(I @ wd + np.cross(w, I @ w))
        Rs.append(R)
        pstars.append(pstar)
    tau = np.zeros(n)
    f = np.zeros(3)
    nn = np.zeros(3)
    for i in range(n - 1, -1, -1):
        pstar = pstars[i]
        r = np.asarray(spec.joints[i].com, float)
        if i < n - 1:
            Rn = Rs[i + 1]
            nn = Rn @ (nn + np.cross(Rn.T @ pstar, f)) + np.cross(pstar + r, Fs[i]) + Ns[i]
            f = Rn @ f + Fs[i]
        else:
            nn = np.cross(pstar + r, Fs[i]) + Ns[i]
            f = Fs[i]
        motor = spec.joints[i].motor
        arm = motor.Jm * motor.G**2 if motor is not None else 0.0
        tau[i] = nn @ (Rs[i].T @ z0) + arm * qdd[i]
    return tau


def _motion(robot, shape, seed=0, scale=1.5):
    rng = np.random.default_rng(seed)
    q = rng.uniform(robot.q_min, robot.q_max, (*shape, robot.nq))
    qd = rng.uniform(-scale, scale, q.shape)
    qdd = rng.uniform(-2 * scale, 2 * scale, q.shape)
    return q, qd, qdd


def test_puma560_matches_independent_dh_newton_euler():
    robot = catalog.get("puma560")
    spec = robot.spec
    assert spec.base is None or np.allclose(spec.base, np.eye(4))
    q, qd, qdd = _motion(robot, (4, 25), seed=3)
    tau = inverse_dynamics(robot, q, qd, qdd)
    ref = np.array(
        [
            _rne_dh(spec, a, b, c, spec.gravity)
            for a, b, c in zip(
                q.reshape(-1, 6), qd.reshape(-1, 6), qdd.reshape(-1, 6), strict=True
            )
        ]
    ).reshape(tau.shape)
    np.testing.assert_allclose(tau, ref, rtol=0, atol=1e-9)
    # non-trivial magnitudes (gravity on joint 2 of the PUMA is tens of N·m)
    assert np.abs(ref[..., 1]).max() > 20.0


def test_puma560_static_gravity_value():
    """Arm stretched horizontally (qs = (0, 0, -π/2, 0, 0, 0)), at rest: joint 2 holds all links
    2..6 + gun; the value comes from the independent formulation, cross-checked by moments."""
    robot = catalog.get("puma560")
    q = np.array([0.0, 0.0, -math.pi / 2, 0.0, 0.0, 0.0])
    tau = inverse_dynamics(robot, q, np.zeros(6), np.zeros(6))
    # Moment of gravity about joint 2 by summing m·g·x of each COM (frames from pinocchio FK)
    data = robot.data()
    pin.forwardKinematics(robot.model, data, q)
    z2 = data.oMi[2].rotation[:, 2]
    o2 = data.oMi[2].translation
    moment = 0.0
    for jid in range(2, 7):
        inert = robot.model.inertias[jid]
        c = data.oMi[jid].act(inert.lever)
        moment += float(np.cross(c - o2, inert.mass * np.array([0, 0, -9.81])) @ z2)
    assert tau[1] == pytest.approx(-moment, abs=1e-9)


URDF_3 = """<?xml version="1.0"?>
<robot name="mixed">
  <link name="base"/>
  <link name="l1">
    <inertial><origin xyz="0.05 0.01 0.1" rpy="0.1 0.2 0.3"/><mass value="2.0"/>
      <inertia ixx="0.02" ixy="0.001" ixz="0.0" iyy="0.03" iyz="0.002" izz="0.025"/></inertial>
  </link>
  <link name="l2">
    <inertial><origin xyz="0.2 0.0 -0.02" rpy="0 0.4 0"/><mass value="1.5"/>
      <inertia ixx="0.01" ixy="0.0" ixz="0.001" iyy="0.015" iyz="0.0" izz="0.012"/></inertial>
  </link>
  <link name="l3">
    <inertial><origin xyz="0.0 0.03 0.05" rpy="0 0 0"/><mass value="0.8"/>
      <inertia ixx="0.004" ixy="0.0" ixz="0.0" iyy="0.004" iyz="0.0" izz="0.002"/></inertial>
  </link>
  <link name="l4">
    <inertial><origin xyz="0.01 0.0 0.02" rpy="0 0 0"/><mass value="0.3"/>
      <inertia ixx="0.001" ixy="0.0" ixz="0.0" iyy="0.0012" iyz="0.0" izz="0.0009"/></inertial>
  </link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0.1 0.0 0.3" rpy="0.2 0.0 0.5"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-2" upper="2" effort="100" velocity="3"/></joint>
  <joint name="j2" type="prismatic"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.0 0.1 0.2" rpy="0.0 0.3 0.0"/><axis xyz="1 0 0"/>
    <limit lower="-0.3" upper="0.3" effort="100" velocity="1"/></joint>
  <joint name="j3" type="continuous"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.3 0.0 0.0" rpy="0.0 0.0 -0.7"/><axis xyz="1 0 0"/></joint>
  <joint name="j4" type="revolute"><parent link="l3"/><child link="l4"/>
    <origin xyz="0.0 0.05 0.1" rpy="1.0 0.0 0.0"/><axis xyz="0 1 0"/>
    <limit lower="-2" upper="2" effort="10" velocity="3"/></joint>
</robot>
"""


def _urdf_robot():
    return build_robot(
        {
            "kind": "urdf",
            "name": "mixed",
            "urdf": URDF_3,
            "motors": {"j1": {"G": 50.0, "Jm": 1e-4}, "j3": {"G": -30.0, "Jm": 2e-4}},
            "gravity": [0.3, -0.2, -9.81],
        }
    )


@pytest.mark.parametrize("name", ["puma560", "calderon_leg", "articulated_5dof", "urdf"])
def test_fast_path_matches_pinocchio_rnea(name):
    robot = _urdf_robot() if name == "urdf" else catalog.get(name)
    if name == "urdf":
        assert robot.chain.prismatic.tolist() == [False, True, False, False]
        assert robot.chain.armature[0] == pytest.approx(50.0**2 * 1e-4)
    q, qd, qdd = _motion(robot, (3, 40), seed=7)
    tau = inverse_dynamics(robot, q, qd, qdd)
    model, data = robot.model, robot.data()
    for idx in np.ndindex(q.shape[:-1]):
        ref = pin.rnea(model, data, q[idx], qd[idx], qdd[idx])
        np.testing.assert_allclose(tau[idx], ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(
        inverse_dynamics_reference(robot, q, qd, qdd), tau, rtol=0, atol=1e-12
    )


def test_shapes_and_parallel_kernel_identical():
    robot = catalog.get("puma560")
    q, qd, qdd = _motion(robot, (3, 3000), seed=11)  # 9000 samples: several parallel chunks
    serial = inverse_dynamics(robot, q, qd, qdd, parallel=False)
    par = inverse_dynamics(robot, q, qd, qdd, parallel=True)
    assert par.shape == q.shape
    assert np.array_equal(serial, par)
    # one trajectory (K, n) and one sample (n,) give the same numbers as inside the batch
    assert np.array_equal(inverse_dynamics(robot, q[1], qd[1], qdd[1]), serial[1])
    assert np.array_equal(inverse_dynamics(robot, q[2, 5], qd[2, 5], qdd[2, 5]), serial[2, 5])


def test_friction_by_hand_puma_joint1():
    robot = catalog.get("puma560")
    ref = catalog.get("puma560").motors
    G, B = -62.6111, 0.00148  # joint 1, motor side (puma560.json)
    assert ref.G[0] == G and ref.B[0] == B
    qd = np.zeros((3, 6))
    qd[:, 0] = [0.5, -0.5, 0.0]
    tf = joint_friction(robot, qd)
    # derived_link_side in puma560.json: G²B = 5.8018217679508, |G|Tc = 24.7313845 / -27.2358285
    assert tf[0, 0] == pytest.approx(5.8018217679508 * 0.5 + 24.7313845, rel=1e-12)
    assert tf[1, 0] == pytest.approx(-5.8018217679508 * 0.5 - 27.2358285, rel=1e-12)
    assert tf[2, 0] == 0.0
    np.testing.assert_array_equal(tf[:, 1:], 0.0)
    # inverse dynamics adds exactly this term
    q = np.tile(robot.home, (3, 1))
    qdd = np.zeros((3, 6))
    diff = inverse_dynamics(robot, q, qd, qdd, friction=True) - inverse_dynamics(robot, q, qd, qdd)
    np.testing.assert_allclose(diff, tf, rtol=0, atol=1e-12)
    # a robot without motors has no friction
    leg = catalog.get("calderon_leg")
    np.testing.assert_array_equal(joint_friction(leg, np.ones((2, 3))), 0.0)


def test_coulomb_friction_is_off_for_round_off_speeds():
    """A joint that stops has a speed of round-off size: no Coulomb torque switching on and
    off with its sign (only the viscous part), while any real motion gets it in full."""
    robot = catalog.get("puma560")
    qd = np.zeros((4, 6))
    qd[:, 0] = [1e-15, -3e-12, COULOMB_DEAD_BAND * 2, -COULOMB_DEAD_BAND * 2]
    tf = joint_friction(robot, qd)[:, 0]
    viscous = 5.8018217679508 * qd[:, 0]
    np.testing.assert_allclose(tf[:2], viscous[:2], rtol=1e-12, atol=0)
    assert tf[2] == pytest.approx(viscous[2] + 24.7313845, rel=1e-12)
    assert tf[3] == pytest.approx(viscous[3] - 27.2358285, rel=1e-12)


def test_armature_counted_once():
    robot = catalog.get("puma560")
    q = np.tile(robot.home, (2, 1))
    qd = np.zeros((2, 6))
    qdd = np.zeros((2, 6))
    qdd[1, 3] = 1.0  # joint 4: reflected rotor inertia Jm·G² = 3.3e-5·76.0364²
    d = inverse_dynamics(robot, q, qd, qdd)
    link_only = pin.crba(robot.model, robot.data(), q[0])[3, 3] - robot.model.armature[3]
    assert d[1, 3] - d[0, 3] == pytest.approx(link_only + 3.3e-5 * 76.0364**2, rel=1e-12)


def test_bad_input_names_argument():
    robot = catalog.get("calderon_leg")
    with pytest.raises(ValueError, match="qd"):
        inverse_dynamics(robot, np.zeros((5, 3)), np.zeros((5, 4)), np.zeros((5, 3)))
    with pytest.raises(ValueError, match="shapes must be equal"):
        inverse_dynamics(robot, np.zeros((5, 3)), np.zeros((4, 3)), np.zeros((5, 3)))


def test_block_sincos_matches_libm():
    from legcore.sincos import _sincos

    rng = np.random.default_rng(5)
    x = np.concatenate(
        [
            rng.uniform(-20.0, 20.0, 5000),
            rng.uniform(-1e5, 1e5, 500),
            np.arange(-64, 65) * (math.pi / 4),  # octant boundaries of the reduction
            [0.0, -0.0, 1e-300, 2e5, -3e7, np.inf, np.nan],
        ]
    )
    c = np.empty_like(x)
    s = np.empty_like(x)
    _sincos(x, 0, x.size, c, s)
    fin = np.isfinite(x)
    np.testing.assert_allclose(c[fin], np.cos(x[fin]), rtol=0, atol=3e-16)
    np.testing.assert_allclose(s[fin], np.sin(x[fin]), rtol=0, atol=3e-16)
    assert np.isnan(c[~fin]).all() and np.isnan(s[~fin]).all()


def test_large_angles_use_libm_fallback():
    robot = catalog.get("articulated_5dof")
    q, qd, qdd = _motion(robot, (200,), seed=9)
    q[::3, 1] += 2e5 * math.pi  # whole turns beyond the fast reduction range
    tau = inverse_dynamics(robot, q, qd, qdd)
    ref = inverse_dynamics_reference(robot, q, qd, qdd)
    np.testing.assert_allclose(tau, ref, rtol=0, atol=1e-12)
