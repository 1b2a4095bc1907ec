"""DH / modified DH / URDF building against an independent DH product written here."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from legcore.robots import build_robot, catalog


def dh(theta, d, a, alpha):
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def fk_tool(robot, q):
    data = robot.data()
    pin.framesForwardKinematics(robot.model, data, q)
    return data.oMf[robot.tool_frame].homogeneous


@pytest.mark.parametrize("name", ["puma560", "articulated_5dof", "calderon_leg"])
def test_standard_dh_matches_independent_product(name):
    robot = catalog.get(name)
    spec = robot.spec
    rng = np.random.default_rng(1)
    tool = np.asarray(spec.tool) if spec.tool is not None else np.eye(4)
    for _ in range(20):
        q = rng.uniform(robot.q_min, robot.q_max)
        T = np.eye(4)
        frames = []
        for qi, j in zip(q, spec.joints, strict=True):
            T = T @ dh(qi + j.offset, j.d, j.a, j.alpha)
            frames.append(T)
        np.testing.assert_allclose(fk_tool(robot, q), T @ tool, atol=1e-12)
        data = robot.data()
        pin.framesForwardKinematics(robot.model, data, q)
        for fid, Ti in zip(robot.link_frames, frames, strict=True):
            np.testing.assert_allclose(data.oMf[fid].homogeneous, Ti, atol=1e-12)


def test_modified_dh_equals_standard_dh_shifted():
    std = catalog.get("puma560").spec
    joints = []
    prev_a, prev_alpha = 0.0, 0.0
    for j in std.joints:
        joints.append(j.model_copy(update={"a": prev_a, "alpha": prev_alpha}))
        prev_a, prev_alpha = j.a, j.alpha
    last = std.joints[-1]
    tool = (dh(0.0, 0.0, last.a, last.alpha) @ np.asarray(std.tool)).tolist()
    mod = std.model_copy(update={"convention": "modified", "joints": joints, "tool": tool})
    r_std, r_mod = build_robot(std), build_robot(mod)
    rng = np.random.default_rng(2)
    for _ in range(10):
        q = rng.uniform(r_std.q_min, r_std.q_max)
        np.testing.assert_allclose(fk_tool(r_mod, q), fk_tool(r_std, q), atol=1e-12)


def test_prismatic_joint_moves_along_z():
    robot = build_robot(
        {
            "kind": "dh",
            "name": "rp",
            "joints": [
                {"type": "revolute", "a": 0.2, "q_min": -3, "q_max": 3},
                {"type": "prismatic", "d": 0.1, "alpha": 0.0, "q_min": 0.0, "q_max": 0.5},
            ],
        }
    )
    T = fk_tool(robot, np.array([math.pi / 2, 0.3]))
    np.testing.assert_allclose(T[:3, 3], [0.0, 0.2, 0.4], atol=1e-12)
    assert robot.chain.prismatic.tolist() == [False, True]


URDF_2R = """<robot name="planar2r">
  <link name="base"/>
  <link name="l1"><inertial><origin xyz="0.15 0 0"/><mass value="1.0"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.008" iyz="0" izz="0.008"/></inertial></link>
  <link name="l2"><inertial><origin xyz="0.1 0 0"/><mass value="0.5"/>
    <inertia ixx="0.0005" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.002"/></inertial></link>
  <link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="20" velocity="3"/></joint>
  <joint name="j2" type="continuous"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.3 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="tipj" type="fixed"><parent link="l2"/><child link="tip"/>
    <origin xyz="0.2 0 0"/></joint>
</robot>"""


def test_urdf_matches_equivalent_dh():
    r_urdf = build_robot({"kind": "urdf", "name": "u", "urdf": URDF_2R, "tool_frame": "tip"})
    r_dh = build_robot(
        {
            "kind": "dh",
            "name": "d",
            "joints": [
                {"a": 0.3, "q_min": -3, "q_max": 3, "mass": 1.0, "com": [-0.15, 0, 0],
                 "inertia": [[0.001, 0, 0], [0, 0.008, 0], [0, 0, 0.008]]},
                {"a": 0.2, "q_min": -6.3, "q_max": 6.3, "mass": 0.5, "com": [-0.1, 0, 0],
                 "inertia": [[0.0005, 0, 0], [0, 0.002, 0], [0, 0, 0.002]]},
            ],
        }
    )
    assert r_urdf.nq == 2
    q, qd, qdd = np.array([0.4, -1.1]), np.array([0.3, 0.7]), np.array([-1.0, 2.0])
    np.testing.assert_allclose(fk_tool(r_urdf, q), fk_tool(r_dh, q), atol=1e-12)
    tau_u = pin.rnea(r_urdf.model, r_urdf.data(), q, qd, qdd)
    tau_d = pin.rnea(r_dh.model, r_dh.data(), q, qd, qdd)
    np.testing.assert_allclose(tau_u, tau_d, atol=1e-12)
    assert r_urdf.q_max[1] == pytest.approx(2 * math.pi)  # continuous -> ±2π


def test_acceleration_limits_from_the_spec():
    """URDF has no acceleration limits: the spec gives them by joint name (inf where not);
    a DH joint carries its own; unknown names and non-positive values are refused."""
    spec = {"kind": "urdf", "name": "u", "urdf": URDF_2R, "tool_frame": "tip"}
    r = build_robot({**spec, "qdd_max": {"j2": 4.5}})
    np.testing.assert_array_equal(r.qdd_max, [np.inf, 4.5])
    assert np.all(np.isinf(build_robot(spec).qdd_max))
    with pytest.raises(ValueError, match="qdd_max: unknown joint"):
        build_robot({**spec, "qdd_max": {"nope": 1.0}})
    with pytest.raises(ValueError, match="qdd_max"):
        build_robot({**spec, "qdd_max": {"j1": 0.0}})
    d = build_robot({"kind": "dh", "name": "d", "joints": [{"a": 0.3, "qdd_max": 2.0}, {"a": 0.2}]})
    np.testing.assert_array_equal(d.qdd_max, [2.0, np.inf])


def test_puma_armature_and_motors():
    robot = catalog.get("puma560")
    ref = catalog.get("puma560").spec
    for i, j in enumerate(ref.joints):
        assert robot.model.armature[i] == pytest.approx(j.motor.Jm * j.motor.G**2)
    assert robot.motors.electrical.tolist() == [True, True, True, False, False, False]
    assert robot.motors.Kt[0] == pytest.approx(0.228)


def test_catalog_names_and_sources():
    assert set(catalog.names()) == {
        "animatronic_quadruped", "articulated_5dof", "calderon_leg", "citedi_hexapod", "puma560",
    }
    assert "seed 000" in catalog.source("calderon_leg")
    with pytest.raises(KeyError, match="unknown catalog robot 'r2d2'"):
        catalog.get("r2d2")


def test_calderon_leg_table1_masses():
    robot = catalog.get("calderon_leg")
    np.testing.assert_allclose(robot.chain.mass, [0.175, 0.13, 0.11])
    # thigh COM 0.0242 m from the hip-pitch joint, i.e. -0.0508 m in the distal DH frame 2
    assert robot.spec.joints[1].com[0] == pytest.approx(0.0242 - 0.075)
