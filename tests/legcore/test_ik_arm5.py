"""Seed 004's 5-DOF arm: closed-form IK with the tool pointing down, on the capsule path."""

from __future__ import annotations

import math

import numpy as np
import pytest

from legcore import kinematics as K
from legcore.ik.arm5 import BRANCH_NAMES, arm5_geometry, arm5_ik_down
from legcore.ik.dispatch import ik
from legcore.robots import build_robot, catalog


@pytest.fixture(scope="module")
def robot():
    return catalog.get("articulated_5dof")


def capsule_points_from_paper(K_per_segment: int = 200) -> np.ndarray:
    """Seed 004 section V, eqs (54)–(61), geometry only (m): arc about (20, 30) cm from
    β1 = −90° sweeping 180°, line (20, 40) → (−20, 40), arc about (−20, 30) from β3 = 90°
    sweeping 180°, line (−20, 20) → (20, 20); r = 10 cm; on the plane z = 50 cm."""
    s = np.linspace(0.0, 1.0, K_per_segment)
    r = 0.10
    seg1 = np.c_[
        r * np.cos(math.pi * s - math.pi / 2) + 0.20, r * np.sin(math.pi * s - math.pi / 2) + 0.30
    ]
    seg2 = np.c_[0.20 * (1 - s) - 0.20 * s, 0.40 * (1 - s) + 0.40 * s]
    seg3 = np.c_[
        r * np.cos(math.pi * s + math.pi / 2) - 0.20, r * np.sin(math.pi * s + math.pi / 2) + 0.30
    ]
    seg4 = np.c_[-0.20 * (1 - s) + 0.20 * s, 0.20 * (1 - s) + 0.20 * s]
    xy = np.concatenate([seg1, seg2, seg3, seg4])
    return np.c_[xy, np.full(len(xy), 0.50)]


def check_down_and_on_target(robot, q: np.ndarray, p: np.ndarray) -> None:
    T = K.fk(robot, q)
    np.testing.assert_allclose(T[..., :3, 2], np.broadcast_to([0.0, 0.0, -1.0], p.shape), atol=1e-9)
    assert np.linalg.norm(T[..., :3, 3] - p, axis=-1).max() < 1e-9


def test_home_pose_of_the_paper_points_the_tool_horizontally(robot):
    """Fig. 18's home (0, 90°, −90°, 90°, 0): link 2 up, link 3 forward, tool along +x at
    (a3 + d5, 0, d1 + a2) — so "tool down" needs θ2 + θ3 + θ4 = 0, not the home's 90°."""
    T = K.fk(robot, robot.home)
    np.testing.assert_allclose(T[:3, 3], [0.60, 0.0, 0.90], atol=1e-12)
    np.testing.assert_allclose(T[:3, 2], [1.0, 0.0, 0.0], atol=1e-12)


def test_capsule_from_the_paper_equations_is_tracked_pointing_down(robot):
    p = capsule_points_from_paper()
    res = ik(robot, p)
    assert res.method == "arm5_down"
    assert res.reachable.all() and res.within_limits.all()
    check_down_and_on_target(robot, res.q, p)
    assert np.all(res.branch == BRANCH_NAMES.index("front-up"))  # nearest to the home pose
    # base yaw is atan2(y, x) of the point (Fig. 20): 45° at the start (20, 20) cm
    np.testing.assert_allclose(res.q[:, 0], np.arctan2(p[:, 1], p[:, 0]), atol=1e-12)
    assert res.q[0, 0] == pytest.approx(math.pi / 4)
    # tool vertical: θ2 + θ3 + θ4 = 0; the joint trajectory is continuous along the path
    np.testing.assert_allclose(res.q[:, 1:4].sum(axis=1), 0.0, atol=1e-12)
    assert np.abs(np.diff(res.q, axis=0)).max() < 0.05


def test_capsule_from_legcore_trajectories_is_tracked_pointing_down(robot):
    from legcore.trajectories.paths import capsule_path

    path = capsule_path()
    assert path.T == pytest.approx(17.2832, abs=1e-4)
    sample = path.sample(0.01)
    p = sample.p
    # the builder's points lie on the paper's capsule at z = 0.50 m
    np.testing.assert_allclose(p[:, 2], 0.50, atol=1e-12)
    on_arc = np.abs(np.hypot(np.abs(p[:, 0]) - 0.20, p[:, 1] - 0.30) - 0.10) < 1e-9
    on_line = (np.abs(p[:, 0]) <= 0.20 + 1e-12) & (
        (np.abs(p[:, 1] - 0.40) < 1e-9) | (np.abs(p[:, 1] - 0.20) < 1e-9)
    )
    assert np.all(on_arc | on_line)
    yaw = np.full(len(p), 0.3)  # a fixed tool heading
    res = ik(robot, p, yaw=yaw)
    assert res.reachable.all() and res.within_limits.all()
    check_down_and_on_target(robot, res.q, p)
    T = K.fk(robot, res.q)
    np.testing.assert_allclose(np.arctan2(T[:, 1, 0], T[:, 0, 0]), 0.3, atol=1e-9)


def test_all_four_branches_round_trip(robot):
    rng = np.random.default_rng(200)
    p = np.c_[rng.uniform(-0.6, 0.6, (400, 2)), rng.uniform(-0.2, 1.0, 400)]
    yaw = rng.uniform(-math.pi, math.pi, 400)
    sol = arm5_ik_down(p, arm5_geometry(robot.spec), yaw)
    assert sol.q.shape == (400, 4, 5)
    # reachable ⇔ the wrist centre p + d5 ẑ is within a2 + a3 of the shoulder (0, 0, d1)
    w = p + [0.0, 0.0, 0.20]
    dist = np.linalg.norm(w - [0.0, 0.0, 0.50], axis=-1)
    np.testing.assert_array_equal(sol.reachable.all(axis=1), dist <= 0.80)
    np.testing.assert_array_equal(sol.reachable.any(axis=1), dist <= 0.80)
    ok = sol.reachable.all(axis=1)
    assert ok.sum() > 200
    check_down_and_on_target(robot, sol.q[ok], np.broadcast_to(p[ok, None], (ok.sum(), 4, 3)))
    T = K.fk(robot, sol.q[ok])
    np.testing.assert_allclose(
        np.angle(np.exp(1j * (np.arctan2(T[..., 1, 0], T[..., 0, 0]) - yaw[ok, None]))),
        0,
        atol=1e-9,
    )
    assert np.isnan(sol.q[~ok]).all()
    # branch geometry: "front" faces the point, "up" has the elbow above the shoulder→wrist line
    F = K.frames(robot, sol.q[ok])
    S, E, Wc = F[..., 1, :3, 3], F[..., 2, :3, 3], F[..., 3, :3, 3]
    heading = np.stack([np.cos(sol.q[ok, :, 0]), np.sin(sol.q[ok, :, 0])], axis=-1)
    radial_w = np.sum(Wc[..., :2] * heading, axis=-1)
    radial_e = np.sum(E[..., :2] * heading, axis=-1)
    above = (E[..., 2] - S[..., 2]) > (Wc[..., 2] - S[..., 2]) * radial_e / radial_w
    for b, name in enumerate(BRANCH_NAMES):
        reach, elbow = name.split("-")
        assert np.all((radial_w[:, b] > 0) == (reach == "front")), name
        assert np.all(above[:, b] == (elbow == "up")), name


def test_unreachable_and_tilted_targets_are_reported(robot):
    p = np.array([[1.2, 0.0, 0.5], [0.4, 0.1, 0.5], [0.0, 0.0, -0.6]])
    res = ik(robot, p)
    assert res.reachable.tolist() == [False, True, False]
    assert np.isnan(res.q[[0, 2]]).all() and res.branch[[0, 2]].tolist() == [-1, -1]
    # pose targets: pointing down (with a yaw) is solved, any other orientation is reported
    T = np.tile(np.eye(4), (2, 1, 1))
    c, s = math.cos(0.7), math.sin(0.7)
    T[0, :3, :3] = np.array([[c, s, 0], [s, -c, 0], [0, 0, -1.0]])  # x at 0.7 rad, z down
    T[1, :3, :3] = np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]])  # tool horizontal
    T[:, :3, 3] = (0.3, 0.3, 0.5)
    res_T = ik(robot, T)
    assert res_T.reachable.tolist() == [True, False]
    np.testing.assert_allclose(K.fk(robot, res_T.q[0]), T[0], atol=1e-9)
    assert res_T.error[0] < 1e-9


def test_tool_roll_base_and_offsets_are_honoured():
    spec = catalog.get("articulated_5dof").spec
    tool = np.eye(4)
    c, s = math.cos(0.5), math.sin(0.5)
    tool[:2, :2] = [[c, -s], [s, c]]
    tool[2, 3] = 0.05
    base = np.eye(4)
    base[:2, :2] = [[math.cos(-0.3), -math.sin(-0.3)], [math.sin(-0.3), math.cos(-0.3)]]
    base[:3, 3] = (0.1, 0.2, 0.05)
    joints = list(spec.joints)
    joints[1] = joints[1].model_copy(update={"offset": math.pi / 2})
    joints[4] = joints[4].model_copy(update={"offset": 0.2})
    robot = build_robot(
        spec.model_copy(update={"tool": tool.tolist(), "base": base.tolist(), "joints": joints})
    )
    rng = np.random.default_rng(201)
    p = np.c_[rng.uniform(-0.3, 0.5, (100, 2)), rng.uniform(0.2, 0.8, 100)]
    yaw = rng.uniform(-3, 3, 100)
    res = ik(robot, p, yaw=yaw)
    assert res.reachable.all()
    T = K.fk(robot, res.q)
    np.testing.assert_allclose(T[:, :3, 3], p, atol=1e-9)
    np.testing.assert_allclose(T[:, :3, 2], np.broadcast_to([0, 0, -1.0], (100, 3)), atol=1e-9)
    np.testing.assert_allclose(
        np.angle(np.exp(1j * (np.arctan2(T[:, 1, 0], T[:, 0, 0]) - yaw))), 0, atol=1e-9
    )
    flat = [j.model_copy(update={"alpha": 0.0}) for j in spec.joints]
    with pytest.raises(ValueError, match="alpha"):
        arm5_geometry(spec.model_copy(update={"joints": flat}))
    with pytest.raises(ValueError, match="5 revolute"):
        arm5_geometry(catalog.get("puma560").spec)
