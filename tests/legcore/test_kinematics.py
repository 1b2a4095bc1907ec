"""Batched FK / frames / Jacobian / manipulability / DLS IK against independent formulations.

Independent references written here: a plain numpy standard-DH product from the spec's table
(``dh``), the geometric Jacobian built from those DH frames (``z_{i-1} × (p_tool − p_{i-1})``),
central finite differences of that FK, and Pinocchio per sample (``*_reference``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from legcore import kinematics as K
from legcore.ik.dispatch import ik
from legcore.ik.dls import ik_dls
from legcore.joint_angles import wrap_to_limits
from legcore.kinematics_reference import fk_reference, frames_reference, jacobian_reference
from legcore.manipulability import manipulability, manipulability_split
from legcore.robots import LeggedRobot, Robot, build_robot, catalog
from legcore.transforms import log3

URDF = """<?xml version="1.0"?>
<robot name="test6">
  <link name="base"/>
  <link name="l1"><inertial><mass value="1.0"/><origin xyz="0 0 0.1"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="l2"><inertial><mass value="1.0"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="l3"><inertial><mass value="0.8"/><origin xyz="0.1 0 0"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <link name="l4"><inertial><mass value="0.5"/><origin xyz="0 0 0.05"/>
    <inertia ixx="0.005" ixy="0" ixz="0" iyy="0.005" iyz="0" izz="0.005"/></inertial></link>
  <link name="l5"><inertial><mass value="0.3"/><origin xyz="0 0 0.03"/>
    <inertia ixx="0.002" ixy="0" ixz="0" iyy="0.002" iyz="0" izz="0.002"/></inertial></link>
  <link name="l6"><inertial><mass value="0.2"/><origin xyz="0 0 0.02"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
  <link name="slider"><inertial><mass value="0.1"/><origin xyz="0 0 0.01"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.001" iyz="0" izz="0.001"/></inertial></link>
  <link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="50" velocity="2"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.05 0.02 0.1" rpy="1.5707963 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-2.5" upper="2.5" effort="50" velocity="2"/></joint>
  <joint name="j3" type="revolute"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.35 0 0.03" rpy="0 0.1 0"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-2.5" upper="2.5" effort="30" velocity="2"/></joint>
  <joint name="j4" type="continuous"><parent link="l3"/><child link="l4"/>
    <origin xyz="0.3 0 0" rpy="0 1.5707963 0"/><axis xyz="0 0 1"/>
    <limit effort="10" velocity="3"/></joint>
  <joint name="j5" type="revolute"><parent link="l4"/><child link="l5"/>
    <origin xyz="0 0 0.08" rpy="0.3 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-2" upper="2" effort="10" velocity="3"/></joint>
  <joint name="j6" type="revolute"><parent link="l5"/><child link="l6"/>
    <origin xyz="0 0.01 0.06" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="5" velocity="3"/></joint>
  <joint name="j7" type="prismatic"><parent link="l6"/><child link="slider"/>
    <origin xyz="0 0 0.02" rpy="0 0.2 0"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.1" effort="5" velocity="0.5"/></joint>
  <joint name="tipj" type="fixed"><parent link="slider"/><child link="tip"/>
    <origin xyz="0.02 0 0.1" rpy="0 0.4 0"/></joint>
</robot>
"""


def urdf_robot() -> Robot:
    return build_robot({"kind": "urdf", "name": "test7", "urdf": URDF})


def dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def dh_frames(robot: Robot, q: np.ndarray) -> list[np.ndarray]:
    """Frames 0..n and the tool (n+2 poses) by the plain standard-DH product of the spec."""
    spec = robot.spec
    T = np.asarray(spec.base, float) if spec.base is not None else np.eye(4)
    out = [T]
    for qi, j in zip(q, spec.joints, strict=True):
        T = T @ dh(qi + j.offset, j.d, j.a, j.alpha)
        out.append(T)
    tool = np.asarray(spec.tool, float) if spec.tool is not None else np.eye(4)
    out.append(T @ tool)
    return out


def dh_jacobian(robot: Robot, q: np.ndarray) -> np.ndarray:
    """Geometric Jacobian [v; ω] at the tool point from the DH frames (revolute joints)."""
    F = dh_frames(robot, q)
    p_tool = F[-1][:3, 3]
    cols = []
    for i in range(robot.nq):
        z = F[i][:3, 2]
        cols.append(np.concatenate([np.cross(z, p_tool - F[i][:3, 3]), z]))
    return np.array(cols).T


def serial_robots() -> list[tuple[str, Robot]]:
    out: list[tuple[str, Robot]] = []
    for name in catalog.names():
        r = catalog.get(name)
        if isinstance(r, LeggedRobot):
            out.extend((f"{name}/{leg.name}", leg.robot) for leg in r.legs)
        else:
            out.append((name, r))
    out.append(("urdf_test7", urdf_robot()))
    return out


# ---------------------------------------------------------------------------------------------
# forward kinematics and Jacobian
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["puma560", "articulated_5dof", "calderon_leg"])
def test_fk_and_frames_match_independent_dh_product(name):
    robot = catalog.get(name)
    rng = np.random.default_rng(10)
    q = rng.uniform(robot.q_min, robot.q_max, (25, robot.nq))
    T = K.fk(robot, q)
    F = K.frames(robot, q)
    for s in range(q.shape[0]):
        ref = dh_frames(robot, q[s])
        np.testing.assert_allclose(T[s], ref[-1], atol=1e-9, rtol=0)
        np.testing.assert_allclose(F[s], np.array(ref[:-1]), atol=1e-9, rtol=0)


@pytest.mark.parametrize("name", ["puma560", "articulated_5dof"])
def test_jacobian_matches_dh_cross_products_and_finite_differences(name):
    """J = [z_{i-1} × (p_tool − p_{i-1}); z_{i-1}] to 1e-9; central differences of the
    independent DH FK give the same linear rows and angular rows (vee(Ṙ Rᵀ)) to 1e-8."""
    robot = catalog.get(name)
    rng = np.random.default_rng(11)
    q = rng.uniform(robot.q_min, robot.q_max, (10, robot.nq))
    J = K.jacobian(robot, q)
    h = 1e-6
    for s in range(q.shape[0]):
        np.testing.assert_allclose(J[s], dh_jacobian(robot, q[s]), atol=1e-9, rtol=0)
        R0 = dh_frames(robot, q[s])[-1][:3, :3]
        for i in range(robot.nq):
            dq = np.zeros(robot.nq)
            dq[i] = h
            Tp = dh_frames(robot, q[s] + dq)[-1]
            Tm = dh_frames(robot, q[s] - dq)[-1]
            v = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
            W = (Tp[:3, :3] - Tm[:3, :3]) / (2 * h) @ R0.T
            w = np.array([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]]) / 2
            np.testing.assert_allclose(J[s, :3, i], v, atol=1e-8)
            np.testing.assert_allclose(J[s, 3:, i], w, atol=1e-8)


@pytest.mark.parametrize(
    "label,robot", serial_robots(), ids=lambda x: x if isinstance(x, str) else ""
)
def test_numba_path_equals_pinocchio_per_sample(label, robot):
    rng = np.random.default_rng(12)
    q = rng.uniform(robot.q_min, robot.q_max, (40, robot.nq))
    np.testing.assert_allclose(K.fk(robot, q), fk_reference(robot, q), atol=1e-12, rtol=0)
    np.testing.assert_allclose(
        K.jacobian(robot, q), jacobian_reference(robot, q), atol=1e-12, rtol=0
    )
    np.testing.assert_allclose(K.frames(robot, q), frames_reference(robot, q), atol=1e-12, rtol=0)
    T, J = K.fk_jacobian(robot, q)
    np.testing.assert_array_equal(T, K.fk(robot, q))
    np.testing.assert_array_equal(J, K.jacobian(robot, q))


def test_urdf_robot_has_prismatic_joint_column():
    robot = urdf_robot()
    assert robot.chain.prismatic.tolist() == [False] * 6 + [True]
    q = np.random.default_rng(13).uniform(robot.q_min, robot.q_max, (5, 7))
    J = K.jacobian(robot, q)
    np.testing.assert_allclose(J[:, 3:, 6], 0.0, atol=1e-15)  # no rotation from the slider
    np.testing.assert_allclose(np.linalg.norm(J[:, :3, 6], axis=-1), 1.0, atol=1e-12)


def test_batch_shapes_are_kept_and_bad_shapes_rejected():
    robot = catalog.get("puma560")
    q = np.random.default_rng(14).uniform(robot.q_min, robot.q_max, (3, 4, 6))
    assert K.fk(robot, q[0, 0]).shape == (4, 4)
    assert K.fk(robot, q).shape == (3, 4, 4, 4)
    assert K.jacobian(robot, q).shape == (3, 4, 6, 6)
    assert K.frames(robot, q).shape == (3, 4, 7, 4, 4)
    np.testing.assert_array_equal(K.fk(robot, q)[1, 2], K.fk(robot, q[1, 2]))
    with pytest.raises(ValueError, match="q: last axis must have length nq = 6"):
        K.fk(robot, np.zeros((2, 5)))
    nan_q = np.full(6, np.nan)
    assert np.isnan(K.fk(robot, nan_q)[:3]).all()  # NaN (an unreachable IK sample) propagates


# ---------------------------------------------------------------------------------------------
# manipulability
# ---------------------------------------------------------------------------------------------


def test_manipulability_split_seed001_matches_yoshikawa():
    """Verified (PUMA 560, seed 001 eqs 6–8, random q inside the limits):

    1. ``w = w_A · |sin θ5|`` exactly (eq 6 with eq 8);
    2. ``w_A`` (eq 7) equals |det| of the 3×3 Jacobian of the wrist-centre position (origin of DH
       frame 4) with respect to θ1, θ2, θ3, computed here by central differences of the plain DH
       product — the paper's translational ("arm") manipulability;
    3. ``w`` equals Yoshikawa's ``sqrt(det(J Jᵀ))`` of the full 6×6 tool Jacobian (which is
       what the paper's "manipulabilidad" is), to 1e-10 relative.
    """
    robot = catalog.get("puma560")
    rng = np.random.default_rng(20)
    q = rng.uniform(robot.q_min, robot.q_max, (30, 6))
    w, w_A, w_W = manipulability_split(robot, q)
    np.testing.assert_allclose(w_W, np.abs(np.sin(q[:, 4])), rtol=0, atol=1e-15)
    np.testing.assert_allclose(w, w_A * np.abs(np.sin(q[:, 4])), rtol=1e-15, atol=0)
    J = K.jacobian(robot, q)
    yoshikawa = np.sqrt(np.linalg.det(J @ np.swapaxes(J, -1, -2)))
    np.testing.assert_allclose(w, yoshikawa, rtol=1e-10)
    np.testing.assert_allclose(manipulability(robot, q), yoshikawa, rtol=1e-12)
    h = 1e-6
    for s in range(5):
        cols = []
        for i in range(3):
            dq = np.zeros(6)
            dq[i] = h
            pp = dh_frames(robot, q[s] + dq)[4][:3, 3]
            pm = dh_frames(robot, q[s] - dq)[4][:3, 3]
            cols.append((pp - pm) / (2 * h))
        np.testing.assert_allclose(w_A[s], abs(np.linalg.det(np.array(cols).T)), rtol=1e-7)
    # the PUMA's seed-001 arm term vanishes at the elbow singularity d4 cos θ3 + a3 sin θ3 = 0
    a3, d4 = robot.spec.joints[2].a, robot.spec.joints[3].d
    q_sing = np.array([0.3, 0.4, math.atan2(-d4, a3), 0.2, 0.7, 0.1])
    assert manipulability_split(robot, q_sing)[0] < 1e-15
    assert manipulability(robot, q_sing) < 1e-12


def test_manipulability_of_robots_with_fewer_than_six_joints():
    arm = catalog.get("articulated_5dof")
    q = np.random.default_rng(21).uniform(arm.q_min, arm.q_max, (8, 5))
    Jv = K.jacobian(arm, q)[:, :3, :]
    np.testing.assert_allclose(
        manipulability(arm, q), np.sqrt(np.linalg.det(Jv @ np.swapaxes(Jv, -1, -2))), rtol=1e-12
    )
    # all six rows, n = 5 < 6: the product of the 5 singular values (det(J Jᵀ) itself is 0)
    sv6 = np.linalg.svd(K.jacobian(arm, q), compute_uv=False)
    np.testing.assert_allclose(manipulability(arm, q, rows="all"), sv6.prod(-1), rtol=1e-10)
    leg = catalog.get("animatronic_quadruped").legs[0].robot  # planar 2-DOF: 3 rows × 2 joints
    ql = np.random.default_rng(22).uniform(leg.q_min, leg.q_max, (8, 2))
    sv = np.linalg.svd(K.jacobian(leg, ql)[:, :3, :], compute_uv=False)
    np.testing.assert_allclose(manipulability(leg, ql), sv.prod(axis=-1), rtol=1e-12)
    # the 2R leg: |det| = l1 l2 |sin q4|
    l1, l2 = (j.a for j in leg.spec.joints)
    np.testing.assert_allclose(manipulability(leg, ql), l1 * l2 * np.abs(np.sin(ql[:, 1])))
    with pytest.raises(ValueError, match="rows"):
        manipulability(leg, ql, rows="linear")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="6R"):
        manipulability_split(arm, q)


# ---------------------------------------------------------------------------------------------
# rotations, wrapping
# ---------------------------------------------------------------------------------------------


def _exp3(w: np.ndarray) -> np.ndarray:
    th = np.linalg.norm(w)
    if th == 0:
        return np.eye(3)
    k = w / th
    Kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(th) * Kx + (1 - math.cos(th)) * Kx @ Kx


def test_log3_round_trips_including_near_pi():
    rng = np.random.default_rng(30)
    axes = rng.normal(size=(50, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = np.concatenate(
        [[0.0, 1e-10, 1e-5, math.pi - 1e-6, math.pi - 1e-9], rng.uniform(0, math.pi, 45)]
    )
    w = axes * angles[:, None]
    R = np.array([_exp3(x) for x in w])
    w_back = log3(R)
    R_back = np.array([_exp3(x) for x in w_back])
    np.testing.assert_allclose(R_back, R, atol=1e-9)
    np.testing.assert_allclose(w_back[5:], w[5:], atol=1e-9)


def test_wrap_to_limits_prefers_angles_inside_limits():
    lo = np.array([-0.5, -math.pi, -4.0, 0.0])
    hi = np.array([4.0, math.pi, 4.0, 1.0])
    q = np.array([-3.0, 3.5, 3.0, 0.5])
    out = wrap_to_limits(q, lo, hi, revolute=[True, True, True, False])
    np.testing.assert_allclose(out, [-3.0 + 2 * math.pi, 3.5 - 2 * math.pi, 3.0, 0.5])
    out_ref = wrap_to_limits(q, lo, hi, q_ref=[0, 0, -3.0, 0], revolute=[True] * 3 + [False])
    assert out_ref[2] == pytest.approx(3.0 - 2 * math.pi)
    # no equivalent inside → principal value, left outside (never clipped)
    assert wrap_to_limits(np.array([2.0]), [-1.0], [1.0])[0] == 2.0


# ---------------------------------------------------------------------------------------------
# damped least squares
# ---------------------------------------------------------------------------------------------


def test_dls_converges_on_urdf_robot_and_flags_unreachable():
    robot = urdf_robot()
    assert robot.ik_family is None
    rng = np.random.default_rng(40)
    q_true = rng.uniform(robot.q_min, robot.q_max, (60, 7))
    q_true[:, 6] = 0.05  # the slider mid-travel
    T = K.fk(robot, q_true)
    T[:5, 0, 3] += 5.0  # 5 m away: out of reach
    res = ik(robot, T, q_ref=q_true + rng.normal(0.0, 0.2, q_true.shape), tol=1e-12)
    assert res.method == "dls"
    assert not res.reachable[:5].any()
    assert np.isnan(res.q[:5]).all() and np.isnan(res.error[:5]).all()
    assert res.reachable[5:].all()
    np.testing.assert_allclose(K.fk(robot, res.q[5:]), T[5:], atol=1e-9)
    assert np.all(res.error[5:] < 1e-11)


def test_dls_on_modified_puma_reports_limits_instead_of_clipping():
    """A PUMA with a 5 cm wrist offset a4 (no closed form): DLS from the home pose reaches
    random poses; a pose whose only nearby solution has θ2 beyond its limit converges and is
    reported out of limits with that θ2 (not clipped)."""
    spec = catalog.get("puma560").spec
    joints = list(spec.joints)
    joints[3] = joints[3].model_copy(update={"a": 0.05})
    robot = build_robot(spec.model_copy(update={"joints": joints, "ik": "dls", "name": "p5"}))
    rng = np.random.default_rng(41)
    q_true = rng.uniform(robot.q_min + 0.3, robot.q_max - 0.3, (40, 6))
    T = K.fk(robot, q_true)
    res = ik(robot, T, q_ref=q_true + rng.normal(0.0, 0.1, q_true.shape), tol=1e-12)
    assert res.reachable.all() and res.within_limits.all()
    np.testing.assert_allclose(K.fk(robot, res.q), T, atol=1e-9)
    q_out = robot.home.copy()
    q_out[1] = robot.q_min[1] - 0.2  # shoulder 0.2 rad below its limit
    res_out = ik_dls(robot, K.fk(robot, q_out), q_out + 0.01, tol=1e-12)
    assert res_out.reachable[()] and not res_out.within_limits[()]
    assert res_out.q[1] == pytest.approx(q_out[1], abs=1e-8)
    # position-only targets (…, 3)
    p = T[:, :3, 3]
    res_p = ik_dls(robot, p, robot.home)
    assert res_p.reachable.all()
    np.testing.assert_allclose(K.fk(robot, res_p.q)[:, :3, 3], p, atol=1e-9)


def test_ik_argument_errors():
    robot = catalog.get("puma560")
    with pytest.raises(ValueError, match="target"):
        ik(robot, np.zeros((2, 5)))
    with pytest.raises(ValueError, match="positions"):
        ik(robot, np.zeros((2, 3)))
    with pytest.raises(ValueError, match="ik_dls"):
        ik(robot, np.eye(4), tol=1e-3)
    with pytest.raises(ValueError, match="damping"):
        ik_dls(robot, np.eye(4), robot.home, damping=-1.0)
    with pytest.raises(ValueError, match="q0"):
        ik_dls(robot, np.eye(4), np.zeros(5))


@pytest.mark.parametrize(
    "name,leg",
    [
        ("calderon_leg", None),
        ("citedi_hexapod", 0),
        ("animatronic_quadruped", 0),
        ("animatronic_quadruped", 2),
    ],
)
def test_ik_dispatches_leg_families_to_their_closed_forms(name, leg):
    robot = catalog.get(name)
    if leg is not None:
        robot = robot.legs[leg].robot
    assert robot.ik_family in ("leg3", "leg2")
    rng = np.random.default_rng(50)
    q = rng.uniform(robot.q_min, robot.q_max, (100, robot.nq))
    p = K.fk(robot, q)[:, :3, 3]
    res = ik(robot, p)
    assert res.method == robot.ik_family and len(res.branch_names) == 2
    assert res.reachable.all() and res.within_limits.all()
    np.testing.assert_allclose(K.fk(robot, res.q)[:, :3, 3], p, atol=1e-12)
    far = ik(robot, p[:3] * 100.0)
    assert not far.reachable.any() and np.isnan(far.q).all()
