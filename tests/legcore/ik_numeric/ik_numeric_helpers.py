"""Robots, paths and checks shared by the numerical IK tests (``test_ik_numeric*.py``): a UR5
and a Panda given by their DH tables (so the tests run without extra data), a SCARA, smooth joint
paths inside the limits, and the FK check of an IK solution."""

from __future__ import annotations

import math

import numpy as np

from legcore.ik import IKSolution
from legcore.kinematics import fk
from legcore.robots import Robot, build_robot
from legcore.transforms import log3

TOL = 1e-9  # m and rad
HALF = math.pi / 2


def ur5_dh(q1_limits: tuple[float, float] = (-2 * math.pi, 2 * math.pi)) -> Robot:
    """UR5 (standard DH of the maker's table); joint 3 ±π, the others ±2π unless given."""
    d = [0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823]
    a = [0.0, -0.425, -0.39225, 0.0, 0.0, 0.0]
    alpha = [HALF, 0.0, 0.0, HALF, -HALF, 0.0]
    lim = [q1_limits] + [(-2 * math.pi, 2 * math.pi), (-math.pi, math.pi)] + [
        (-2 * math.pi, 2 * math.pi)
    ] * 3
    joints = [
        {"d": d[i], "a": a[i], "alpha": alpha[i], "q_min": lim[i][0], "q_max": lim[i][1]}
        for i in range(6)
    ]
    return build_robot({"kind": "dh", "name": "ur5_dh", "joints": joints})


def panda_dh() -> Robot:
    """Franka Panda (modified DH of the maker's table, its joint limits, tool at the hand TCP)."""
    a = [0.0, 0.0, 0.0, 0.0825, -0.0825, 0.0, 0.088]
    d = [0.333, 0.0, 0.316, 0.0, 0.384, 0.0, 0.0]
    alpha = [0.0, -HALF, HALF, HALF, -HALF, HALF, HALF]
    lo = [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973]
    hi = [2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973]
    joints = [
        {"d": d[i], "a": a[i], "alpha": alpha[i], "q_min": lo[i], "q_max": hi[i]}
        for i in range(7)
    ]
    c, s = math.cos(-math.pi / 4), math.sin(-math.pi / 4)
    tool = [[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0.2104], [0, 0, 0, 1]]
    home = [0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785]
    return build_robot(
        {"kind": "dh", "name": "panda_dh", "convention": "modified", "joints": joints,
         "tool": tool, "home": home}
    )


def smooth_path(
    robot: Robot, K: int, seed: int, center: list[float] | None = None, amp: float = 0.4
) -> np.ndarray:
    """A smooth joint trajectory (K, n): sums of sines of amplitude ≤ ``amp`` rad about
    ``center`` (default mid-range), inside the limits."""
    rng = np.random.default_rng(seed)
    lo, hi = np.maximum(robot.q_min, -math.pi), np.minimum(robot.q_max, math.pi)
    mid = 0.5 * (lo + hi) if center is None else np.asarray(center)
    t = np.linspace(0.0, 1.0, K)[:, None]
    c = rng.uniform(-amp / 3, amp / 3, (3, robot.nq))
    q = mid + c[0] * np.sin(2 * np.pi * t) + c[1] * np.sin(4 * np.pi * t + 1) + c[2] * np.cos(
        2 * np.pi * t
    )
    return np.clip(q, robot.q_min, robot.q_max)


UR5_AWAY = [0.3, -1.2, 1.5, -1.0, 1.2, 0.3]  # elbow bent, wrist not aligned: no singularity
PUMA_AWAY = [0.2, 0.5, -2.0, 0.3, 0.8, 0.2]


def targets_of(robot: Robot, q: np.ndarray, task: str) -> np.ndarray:
    T = fk(robot, q)
    if task == "position":
        return T[..., :3, 3]
    if task == "axis":
        return np.concatenate([T[..., :3, 3], T[..., :3, 2]], axis=-1)
    return T


def assert_on_target(robot: Robot, sol: IKSolution, targets: np.ndarray, task: str) -> None:
    """FK of the reachable solutions matches the targets to 1e-9 m / rad, inside the limits."""
    ok = sol.reachable
    q = sol.q[ok]
    assert np.all(np.isnan(sol.q[~ok]))
    assert np.all(robot.within_limits(q, tol=0.0))
    T = fk(robot, q)
    tg = targets[ok]
    p = tg[..., :3, 3] if task == "pose" else tg[..., :3]
    assert np.abs(np.linalg.norm(T[..., :3, 3] - p, axis=-1)).max(initial=0.0) <= TOL
    if task == "axis":
        a = tg[..., 3:] / np.linalg.norm(tg[..., 3:], axis=-1, keepdims=True)
        ang = np.arctan2(np.linalg.norm(np.cross(T[..., :3, 2], a), axis=-1),
                         np.sum(T[..., :3, 2] * a, axis=-1))
        assert ang.max(initial=0.0) <= TOL
    if task == "pose":
        ang = np.linalg.norm(log3(tg[..., :3, :3] @ np.swapaxes(T[..., :3, :3], -1, -2)), axis=-1)
        assert ang.max(initial=0.0) <= TOL


def scara() -> Robot:
    """A SCARA (R, R, P, R): the prismatic joint's path through the solver."""
    joints = [
        {"a": 0.4, "d": 0.3},
        {"a": 0.3, "alpha": math.pi},
        {"type": "prismatic", "q_min": 0.0, "q_max": 0.2},
        {"d": 0.05},
    ]
    return build_robot({"kind": "dh", "name": "scara", "joints": joints})
