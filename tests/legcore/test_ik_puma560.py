"""PUMA 560 closed-form IK: all 8 branches, FK round trip, distinctness, branch geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest

from legcore import kinematics as K
from legcore.ik.dispatch import ik
from legcore.ik.puma560 import BRANCH_NAMES, puma560_geometry, puma560_ik
from legcore.manipulability import manipulability_split
from legcore.robots import build_robot, catalog
from legcore.robots.catalog import puma560 as puma_module


def dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0, sa, ca, d],
            [0, 0, 0, 1],
        ]
    )


def dh_fk(spec, q: np.ndarray) -> np.ndarray:
    """Independent tool pose: base · Π A_i(q_i + offset_i) · tool."""
    T = np.asarray(spec.base, float) if spec.base is not None else np.eye(4)
    for qi, j in zip(q, spec.joints, strict=True):
        T = T @ dh(qi + j.offset, j.d, j.a, j.alpha)
    return T @ (np.asarray(spec.tool, float) if spec.tool is not None else np.eye(4))


def angdiff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.abs(np.angle(np.exp(1j * (a - b))))


@pytest.fixture(scope="module")
def robot():
    return catalog.get("puma560")


@pytest.fixture(scope="module")
def random_case(robot):
    rng = np.random.default_rng(100)
    q = rng.uniform(robot.q_min, robot.q_max, (300, 6))
    # keep away from the exact singularities so that all 8 branches are distinct
    w, w_A, w_W = manipulability_split(robot, q)
    q = q[(w_W > 0.05) & (w_A > 1e-3)]
    return q, K.fk(robot, q)


def test_all_eight_branches_round_trip_and_are_distinct(robot, random_case):
    q, T = random_case
    sol = puma560_ik(T, puma560_geometry(robot.spec), robot.q_min, robot.q_max)
    assert sol.q.shape == (q.shape[0], 8, 6)
    assert sol.reachable.all()
    for s in range(q.shape[0]):
        for b in range(8):
            np.testing.assert_allclose(dh_fk(robot.spec, sol.q[s, b]), T[s], atol=1e-9, rtol=0)
    # batched FK agrees too
    np.testing.assert_allclose(
        K.fk(robot, sol.q), np.broadcast_to(T[:, None], sol.q.shape[:2] + (4, 4)), atol=1e-9
    )
    # distinct: every pair of branches differs by > 1e-3 rad in some joint (mod 2π)
    d = angdiff(sol.q[:, :, None, :], sol.q[:, None, :, :]).max(axis=-1)
    off_diag = d[:, ~np.eye(8, dtype=bool)]
    assert off_diag.min() > 1e-3
    # the configuration the pose came from is one of the 8 (mod 2π)
    assert angdiff(sol.q, q[:, None, :]).max(axis=-1).min(axis=-1).max() < 1e-9


def test_branch_names_match_the_geometry(robot, random_case):
    """left ⇔ wrist centre in front of the shoulder along x1 (X > 0, Corke's 'l');
    up ⇔ elbow (origin of DH frame 2) above the shoulder→wrist line in the arm plane;
    noflip ⇔ sin θ5 ≥ 0. Checked on the DH frames of each branch."""
    q, T = random_case
    sol = puma560_ik(T, puma560_geometry(robot.spec))
    F = K.frames(robot, sol.q)  # (B, 8, 7, 4, 4)
    S = F[..., 1, :3, 3]  # frame 1 origin (shoulder, on axis 2)
    x1 = F[..., 1, :3, 0]
    E = F[..., 2, :3, 3]
    W = F[..., 4, :3, 3]  # wrist centre
    X = np.sum((W - S) * x1, axis=-1)
    # the arm moves in the vertical plane (x1, ẑ) (z1 is horizontal); the line S→W projected on
    # it has height (W − S)_z · t at radial distance t·X; the elbow is above it or not
    elbow_above = (E[..., 2] - S[..., 2]) > (W[..., 2] - S[..., 2]) * np.sum(
        (E - S) * x1, axis=-1
    ) / X
    for b, name in enumerate(BRANCH_NAMES):
        shoulder, elbow, wrist = name.split("-")
        assert np.all((X[:, b] > 0) == (shoulder == "left")), name
        assert np.all(elbow_above[:, b] == (elbow == "up")), name
        assert np.all((np.sin(sol.q[:, b, 4]) >= 0) == (wrist == "noflip")), name


def test_ik_dispatch_picks_branch_and_reports(robot, random_case):
    q, T = random_case
    res = ik(robot, T)
    assert res.method == "puma560" and res.branch_names == BRANCH_NAMES
    assert res.reachable.all() and res.within_limits.all()
    assert np.all(res.error < 1e-9)
    np.testing.assert_allclose(K.fk(robot, res.q), T, atol=1e-9)
    # nearest to the configuration itself → recovers it
    res_ref = ik(robot, T, q_ref=q)
    np.testing.assert_allclose(res_ref.q, q, atol=1e-9)
    # an explicit branch, by name or index
    res_b = ik(robot, T, branch="right-down-flip")
    assert np.all(res_b.branch == BRANCH_NAMES.index("right-down-flip"))
    np.testing.assert_allclose(K.fk(robot, res_b.q), T, atol=1e-9)
    with pytest.raises(ValueError, match="branch"):
        ik(robot, T, branch="sideways")
    with pytest.raises(ValueError, match="branch"):
        ik(robot, T, branch=8)


def test_unreachable_poses_are_reported_not_clipped(robot):
    T = np.tile(np.eye(4), (3, 1, 1))
    T[0, :3, 3] = (2.0, 0.0, 0.7)  # beyond full reach (~0.86 m + tool)
    # wrist centre inside the shoulder-offset cylinder (ρ < d3 = 0.15 m) above the shoulder
    T[1, :3, 3] = (0.05, 0.0, 1.0 - 0.2)
    T[1, :3, :3] = np.diag([1.0, -1.0, -1.0])  # tool pointing down → wrist 0.2 m above
    T[2, :3, 3] = (0.5, 0.2, 0.3)  # reachable control
    sol = puma560_ik(T, puma560_geometry(robot.spec))
    assert not sol.reachable[0].any() and not sol.reachable[1].any()
    assert sol.reachable[2].all()
    assert np.isnan(sol.q[:2]).all()
    res = ik(robot, T)
    assert res.reachable.tolist() == [False, False, True]
    assert np.isnan(res.q[:2]).all() and res.branch[:2].tolist() == [-1, -1]
    assert np.isnan(res.error[:2]).all()


def test_wrist_singularity_still_round_trips(robot):
    q = np.array(
        [
            [0.1, 0.5, -1.0, 0.3, 0.0, 0.2],
            [-0.4, 1.2, -2.0, 1.0, 0.0, -1.0],
            [0.3, 0.2, 0.1, 0, math.pi, 0.5],
        ]
    )
    T = K.fk(robot, q)
    sol = puma560_ik(T, puma560_geometry(robot.spec))
    assert sol.reachable.all()
    np.testing.assert_allclose(
        K.fk(robot, sol.q), np.broadcast_to(T[:, None], (3, 8, 4, 4)), atol=1e-9
    )


def test_bare_arm_batch_shapes_and_limits():
    bare = puma_module.build(tool=False)
    rng = np.random.default_rng(101)
    q = rng.uniform(bare.q_min, bare.q_max, (4, 5, 6))
    T = K.fk(bare, q)
    sol = puma560_ik(T, puma560_geometry(bare.spec), bare.q_min, bare.q_max)
    assert sol.q.shape == (4, 5, 8, 6) and sol.within_limits.shape == (4, 5, 8)
    inside = np.all((sol.q >= bare.q_min - 1e-12) & (sol.q <= bare.q_max + 1e-12), axis=-1)
    np.testing.assert_array_equal(sol.within_limits, inside & sol.reachable)
    assert sol.within_limits.any(axis=-1).all()  # the source configuration is inside
    res = ik(bare, T)
    assert res.q.shape == (4, 5, 6) and res.within_limits.all()


def test_base_offset_and_shoulder_d2_are_honoured():
    spec = catalog.get("puma560").spec
    base = np.eye(4)
    c, s = math.cos(0.4), math.sin(0.4)
    base[:3, :3] = [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    base[:3, 3] = (0.3, -0.1, 0.05)
    joints = list(spec.joints)
    joints[1] = joints[1].model_copy(update={"d": 0.03})  # split the shoulder offset d2 + d3
    joints[2] = joints[2].model_copy(update={"d": 0.15005 - 0.03, "offset": 0.2})
    robot = build_robot(spec.model_copy(update={"base": base.tolist(), "joints": joints}))
    q = np.random.default_rng(102).uniform(robot.q_min, robot.q_max, (50, 6))
    T = K.fk(robot, q)
    sol = puma560_ik(T, puma560_geometry(robot.spec))
    assert sol.reachable.all()
    np.testing.assert_allclose(
        K.fk(robot, sol.q), np.broadcast_to(T[:, None], (50, 8, 4, 4)), atol=1e-9
    )


def test_geometry_rejects_other_arms():
    with pytest.raises(ValueError, match="6 revolute"):
        puma560_geometry(catalog.get("articulated_5dof").spec)
    spec = catalog.get("puma560").spec
    joints = list(spec.joints)
    joints[3] = joints[3].model_copy(update={"a": 0.05})
    with pytest.raises(ValueError, match="spherical wrist"):
        puma560_geometry(spec.model_copy(update={"joints": joints}))
