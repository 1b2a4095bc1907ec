"""legcore.ik.solve / solve_numeric: batched numerical IK of any chain, checked by FK.

Robots: a UR5 and a Panda given by their DH tables here (so the tests run without extra data),
the catalog's closed-form robots (the numerical solver must agree with each closed form), and
the UR5 / Panda URDFs of ``example-robot-data`` when that package is installed.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from typing import Any

import numpy as np
import pytest

from legcore.ik import IKSolution, solve, solve_numeric
from legcore.ik.sample_kinematics import fk_z, jac_z, z_chain
from legcore.kinematics import fk, fk_jacobian, jacobian, log3, manipulability
from legcore.robots import Robot, build_robot, catalog

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


@pytest.fixture(scope="module")
def ur5() -> Robot:
    return ur5_dh()


@pytest.fixture(scope="module")
def panda() -> Robot:
    return panda_dh()


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


def fk_jac_one(  # the reference: plain Python, per sample
    q: np.ndarray,
    R: np.ndarray,
    p: np.ndarray,
    axis: np.ndarray,
    prismatic: np.ndarray,
    tool_R: np.ndarray,
    tool_p: np.ndarray,
    Rw: np.ndarray,
    pw: np.ndarray,
    T: np.ndarray,
    J: np.ndarray,
) -> None:
    """Tool pose ``T`` (4, 4) and Jacobian ``J`` (6, n) of ``q`` (n,) on chain arrays.

    ``Rw`` (n, 3, 3) and ``pw`` (n, 3) are scratch: the joint frames in the world.
    """
    n = q.shape[0]
    for i in range(n):
        r = R[i]
        if i == 0:
            for a in range(3):
                pw[0, a] = p[0, a]
                for c in range(3):
                    Rw[0, a, c] = r[a, c]
        else:
            for a in range(3):
                g0, g1, g2 = Rw[i - 1, a, 0], Rw[i - 1, a, 1], Rw[i - 1, a, 2]
                pw[i, a] = pw[i - 1, a] + g0 * p[i, 0] + g1 * p[i, 1] + g2 * p[i, 2]
                for c in range(3):
                    Rw[i, a, c] = g0 * r[0, c] + g1 * r[1, c] + g2 * r[2, c]
        ax, ay, az = axis[i, 0], axis[i, 1], axis[i, 2]
        qi = q[i]
        if prismatic[i]:
            for a in range(3):
                pw[i, a] += (Rw[i, a, 0] * ax + Rw[i, a, 1] * ay + Rw[i, a, 2] * az) * qi
        else:  # Rodrigues: Rw[i] ← Rw[i] · exp([a]× q)
            cq, sq = math.cos(qi), math.sin(qi)
            vq = 1.0 - cq
            e00 = cq + ax * ax * vq
            e01 = ax * ay * vq - az * sq
            e02 = ax * az * vq + ay * sq
            e10 = ay * ax * vq + az * sq
            e11 = cq + ay * ay * vq
            e12 = ay * az * vq - ax * sq
            e20 = az * ax * vq - ay * sq
            e21 = az * ay * vq + ax * sq
            e22 = cq + az * az * vq
            for a in range(3):
                b0, b1, b2 = Rw[i, a, 0], Rw[i, a, 1], Rw[i, a, 2]
                Rw[i, a, 0] = b0 * e00 + b1 * e10 + b2 * e20
                Rw[i, a, 1] = b0 * e01 + b1 * e11 + b2 * e21
                Rw[i, a, 2] = b0 * e02 + b1 * e12 + b2 * e22
    L = Rw[n - 1]
    for a in range(3):
        for c in range(3):
            T[a, c] = L[a, 0] * tool_R[0, c] + L[a, 1] * tool_R[1, c] + L[a, 2] * tool_R[2, c]
        T[a, 3] = pw[n - 1, a] + L[a, 0] * tool_p[0] + L[a, 1] * tool_p[1] + L[a, 2] * tool_p[2]
    T[3, 0] = 0.0
    T[3, 1] = 0.0
    T[3, 2] = 0.0
    T[3, 3] = 1.0
    ox, oy, oz = T[0, 3], T[1, 3], T[2, 3]
    for i in range(n):
        ax, ay, az = axis[i, 0], axis[i, 1], axis[i, 2]
        wx = Rw[i, 0, 0] * ax + Rw[i, 0, 1] * ay + Rw[i, 0, 2] * az
        wy = Rw[i, 1, 0] * ax + Rw[i, 1, 1] * ay + Rw[i, 1, 2] * az
        wz = Rw[i, 2, 0] * ax + Rw[i, 2, 1] * ay + Rw[i, 2, 2] * az
        if prismatic[i]:
            J[0, i], J[1, i], J[2, i] = wx, wy, wz
            J[3, i], J[4, i], J[5, i] = 0.0, 0.0, 0.0
        else:
            dx, dy, dz = ox - pw[i, 0], oy - pw[i, 1], oz - pw[i, 2]
            J[0, i] = wy * dz - wz * dy
            J[1, i] = wz * dx - wx * dz
            J[2, i] = wx * dy - wy * dx
            J[3, i], J[4, i], J[5, i] = wx, wy, wz


def test_per_sample_kinematics_equals_the_batched_kernel(ur5: Robot, panda: Robot) -> None:
    for robot in (ur5, panda, scara(), catalog.get("puma560"), catalog.get("calderon_leg")):
        c, n = robot.chain, robot.nq
        q = np.random.default_rng(0).uniform(robot.q_min, robot.q_max, (20, n))
        T_ref, J_ref = fk_jacobian(robot, q)
        Rw, pw, T, J = np.empty((n, 3, 3)), np.empty((n, 3)), np.empty((4, 4)), np.empty((6, n))
        for s in range(20):
            fk_jac_one(q[s], c.R, c.p, c.axis, c.prismatic, c.tool_R, c.tool_p, Rw, pw, T, J)
            np.testing.assert_allclose(T, T_ref[s], atol=1e-14)
            np.testing.assert_allclose(J, J_ref[s], atol=1e-14)


def test_z_aligned_chain_has_the_same_kinematics(ur5: Robot, panda: Robot) -> None:
    # the solver's chain (every joint turning about its frame's z axis): same FK and Jacobian,
    # also for axes along −z and in general directions (a random chain)
    rng = np.random.default_rng(20)
    n = 6
    axes = rng.normal(size=(n, 3))
    axes[1] = [0.0, 0.0, -1.0]
    axes[2] = [0.0, 1.0, 0.0]
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    rots = np.stack([np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(n + 1)])
    rots *= np.sign(np.linalg.det(rots))[:, None, None]
    prismatic = np.array([False, False, True, False, False, False])
    puma = catalog.get("puma560")
    assert isinstance(puma, Robot)
    chains = [(robot.chain.R, robot.chain.p, robot.chain.axis, robot.chain.prismatic,
               robot.chain.tool_R, robot.chain.tool_p)
              for robot in (ur5, panda, scara(), puma)]
    chains.append((rots[:n], rng.normal(size=(n, 3)), axes, prismatic, rots[n], rng.normal(size=3)))
    for R, p, axis, pris, tool_R, tool_p in chains:
        m = R.shape[0]
        zR, zp, ztR, ztp = z_chain(R, p, axis, tool_R, tool_p)
        Rw, pw, T, J = np.empty((m, 3, 3)), np.empty((m, 3)), np.empty((4, 4)), np.empty((6, m))
        T_z, J_z = np.empty((4, 4)), np.empty((6, m))
        for q in rng.uniform(-3.0, 3.0, (20, m)):
            fk_jac_one(q, R, p, axis, pris, tool_R, tool_p, Rw, pw, T, J)
            fk_z(q, zR, zp, pris, ztR, ztp, Rw, pw, T_z)
            jac_z(Rw, pw, T_z, pris, J_z)
            np.testing.assert_allclose(T_z, T, atol=1e-13)
            np.testing.assert_allclose(J_z, J, atol=1e-13)


def _pinocchio_dls(robot: Robot, T: np.ndarray, q0: np.ndarray) -> np.ndarray:
    """Reference: a per-sample Python loop of Pinocchio damped least squares (as in
    ``benchmarks/bench_ik.py``), warm-started from the previous solution."""
    import pinocchio as pin

    model, data, fid = robot.model, robot.data(), robot.tool_frame
    q = np.array(q0, dtype=float)
    out = np.empty((T.shape[0], robot.nq))
    e = np.empty(6)
    for k in range(T.shape[0]):
        for _ in range(100):
            pin.framesForwardKinematics(model, data, q)
            M = data.oMf[fid]
            e[:3] = T[k, :3, 3] - M.translation
            e[3:] = pin.log3(T[k, :3, :3] @ M.rotation.T)
            if np.abs(e).max() <= 1e-12:
                break
            rf = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
            J = pin.computeFrameJacobian(model, data, q, fid, rf)
            q = q + J.T @ np.linalg.solve(J @ J.T + 1e-18 * np.eye(6), e)
        out[k] = q
    return out


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_fast_path_step_equals_the_reference_solvers(name: str, request) -> None:
    # along a path each sample takes the one-step fast path (newton.track: an LU step, the
    # check by FK); it must give what the reference gives: for the 6-DOF arm the Pinocchio
    # DLS loop's solution, for the 7-DOF arm the full newton iteration from the same start
    robot = request.getfixturevalue(name)
    center = UR5_AWAY if name == "ur5" else [0.0, -0.5, 0.0, -2.0, 0.0, 1.6, 0.8]
    q = smooth_path(robot, 400, seed=21, center=center, amp=0.3)
    T = fk(robot, q)
    sol = solve(robot, T, "pose", q0=q[0], path=True)
    assert sol.reachable.all() and not sol.flip.any()
    assert_on_target(robot, sol, T, "pose")
    assert (sol.iterations[3:] == 1).mean() > 0.5  # mostly one step per sample: the fast path
    if name == "ur5":
        np.testing.assert_allclose(sol.q, _pinocchio_dls(robot, T, q[0]), atol=1e-8)
        return
    # each path sample solved alone by the full newton from the path's previous solution
    alone = solve(robot, T[1:], "pose", q0=sol.q[:-1])
    assert alone.reachable.all()
    np.testing.assert_allclose(sol.q[1:], alone.q, atol=1e-6)
    J = jacobian(robot, sol.q)
    N = np.eye(7) - np.linalg.pinv(J) @ J
    pull = np.abs(np.einsum("kij,kj->ki", N, robot.home - sol.q)).max()
    assert pull <= 1.5e-7  # |N (q_rest − q)| ≤ null_tol (1e-7) up to the pinv's rounding


@pytest.mark.parametrize("task", ["position", "axis", "pose"])
@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_random_reachable_targets_are_solved_to_1e9(name: str, task: str, request) -> None:
    robot = request.getfixturevalue(name)
    q = np.random.default_rng(1).uniform(robot.q_min, robot.q_max, (60, robot.nq))
    tg = targets_of(robot, q, task)
    sol = solve(robot, tg, task)
    assert sol.method == "numeric" and sol.task == task
    assert sol.q.shape == q.shape and sol.reachable.shape == (60,)
    assert sol.reachable.all()
    assert not sol.flip.any()
    assert_on_target(robot, sol, tg, task)
    assert np.all(sol.position_error <= TOL) and np.all(sol.rotation_error <= TOL)


def test_prismatic_joints_are_solved_inside_their_travel() -> None:
    robot = scara()
    q = np.random.default_rng(2).uniform(robot.q_min, robot.q_max, (40, 4))
    tg = targets_of(robot, q, "axis")
    sol = solve(robot, tg, "axis")
    assert sol.reachable.all()
    assert_on_target(robot, sol, tg, "axis")
    below = tg[:3].copy()
    below[:, 2] -= 0.5  # past the end of the vertical travel
    assert not solve(robot, below, "axis").reachable.any()


def test_path_keeps_its_branch_and_equals_the_generating_motion(ur5: Robot) -> None:
    q = smooth_path(ur5, 600, seed=3, center=UR5_AWAY)
    sol = solve(ur5, fk(ur5, q), "pose", q0=q[0], path=True)
    assert sol.reachable.all() and not sol.flip.any()
    # a 6-DOF pose has isolated solutions: continuation from q(0) tracks q(t) itself
    assert np.abs(sol.q - q).max() < 1e-6
    # the same path from a far start lands on one branch and stays on it
    sol2 = solve(ur5, fk(ur5, q), "pose", path=True)
    assert sol2.reachable.all()
    assert not sol2.flip[1:].any()
    assert np.abs(np.diff(sol2.q, axis=0)).max() < 0.1


@pytest.mark.parametrize("task", ["position", "axis", "pose"])
def test_redundant_path_is_continuous(panda: Robot, task: str) -> None:
    q = smooth_path(panda, 500, seed=4)
    tg = targets_of(panda, q, task)
    sol = solve(panda, tg, task, q0=q[0], path=True)
    assert sol.reachable.all() and not sol.flip.any()
    assert_on_target(panda, sol, tg, task)
    assert np.abs(np.diff(sol.q, axis=0)).max() < 0.05  # target steps move joints by ≲ 0.01


def test_batch_of_paths_equals_each_path_alone(ur5: Robot) -> None:
    qs = np.stack([smooth_path(ur5, 120, seed=s, center=UR5_AWAY) for s in (5, 6, 7)])
    T = fk(ur5, qs)
    sol = solve(ur5, T, "pose", q0=qs[:, 0], path=True)
    assert sol.q.shape == (3, 120, 6) and sol.flip.shape == (3, 120)
    for b in range(3):
        alone = solve(ur5, T[b], "pose", q0=qs[b, 0], path=True)
        np.testing.assert_array_equal(alone.q, sol.q[b])


def test_joint_limits_are_never_left() -> None:
    tight = ur5_dh(q1_limits=(-0.4, 0.4))
    rng = np.random.default_rng(8)
    q = rng.uniform(tight.q_min, tight.q_max, (40, 6))
    q_any = rng.uniform(-math.pi, math.pi, (40, 6))  # many of these need q1 outside ±0.4
    for task in ("position", "pose"):
        tg = targets_of(tight, np.concatenate([q, q_any]), task)
        sol = solve(tight, tg, task)
        assert sol.reachable[:40].all()  # generated inside the limits: reachable
        assert_on_target(tight, sol, tg, task)
        assert np.all(sol.within_limits == sol.reachable)


def test_unreachable_targets_are_flagged_not_clipped(ur5: Robot) -> None:
    q = np.random.default_rng(9).uniform(-2.0, 2.0, (4, 6))
    T = fk(ur5, q)
    far = T.copy()
    far[:, :3, 3] *= 5.0  # beyond the reach (~1 m)
    sol = solve(ur5, np.concatenate([T, far]), "pose")
    np.testing.assert_array_equal(sol.reachable, [True] * 4 + [False] * 4)
    assert np.all(np.isnan(sol.q[4:])) and np.all(sol.branch[4:] == -1)
    assert np.all(np.isnan(sol.error[4:]))
    # inside the workspace but only reachable with the base turned: unreachable when q1 ∈ ±0.3
    p = np.array([[0.0, 0.6, 0.3], [0.0, -0.5, 0.2]])
    assert solve(ur5, p, "position").reachable.all()
    limited = solve(ur5_dh(q1_limits=(-0.3, 0.3)), p, "position")
    assert not limited.reachable.any() and np.all(np.isnan(limited.q))


def test_redundancy_is_resolved_toward_the_rest_posture(panda: Robot) -> None:
    q_true = np.array([0.3, -0.4, 0.2, -2.0, 0.1, 1.8, 0.5])
    T = fk(panda, q_true)
    rests = [q_true + np.array([0, 0, 0.5, 0, 0, 0, 0]), q_true - np.array([0, 0, 0.5, 0, 0, 0, 0])]
    sols = [solve(panda, T, "pose", rest=r, q0=q_true) for r in rests]
    q_a, q_b = sols[0].q, sols[1].q
    assert sols[0].reachable and sols[1].reachable
    assert np.abs(q_a - q_b).max() > 0.1  # different rest postures, different elbows
    assert np.linalg.norm(q_a - rests[0]) < np.linalg.norm(q_b - rests[0])
    assert np.linalg.norm(q_b - rests[1]) < np.linalg.norm(q_a - rests[1])
    for q, r in ((q_a, rests[0]), (q_b, rests[1])):
        # first-order optimality: (q − rest) has no component along the self-motion (null space)
        J = jacobian(panda, q)
        N = np.eye(7) - np.linalg.pinv(J) @ J
        assert np.abs(N @ (q - r)).max() < 1e-6


def _closed_form_cases():
    rng = np.random.default_rng(10)
    puma = catalog.get("puma560")
    T = fk(puma, rng.uniform(puma.q_min, puma.q_max, (60, 6)))
    far = T[:5].copy()
    far[:, :3, 3] *= 4.0
    yield "puma560", puma, "pose", np.concatenate([T, far])
    arm5 = catalog.get("articulated_5dof")
    p = fk(arm5, rng.uniform(arm5.q_min, arm5.q_max, (80, 5)))[:, :3, 3]
    down = np.tile([0.0, 0.0, -1.0], (80, 1))
    yield "articulated_5dof", arm5, "axis", np.concatenate([p, down], axis=1)
    for leg in (catalog.get("calderon_leg"), catalog.get("citedi_hexapod").legs[0].robot,
                catalog.get("animatronic_quadruped").legs[0].robot):
        p = fk(leg, rng.uniform(leg.q_min, leg.q_max, (40, leg.nq)))[:, :3, 3]
        box = rng.uniform(-1.0, 1.0, (120, 3)) * np.abs(p).max(axis=0)  # many limited / out
        yield leg.name, leg, "position", np.concatenate([p, box])


@pytest.mark.parametrize(
    "name,robot,task,targets", list(_closed_form_cases()), ids=lambda v: v if isinstance(v, str)
    else None
)
def test_every_closed_form_agrees_with_the_numerical_solver(name, robot, task, targets) -> None:
    closed = solve(robot, targets, task)
    assert closed.method == robot.ik_family
    numeric = solve(robot, targets, task, method="numeric", restarts=64)
    np.testing.assert_array_equal(closed.reachable, numeric.reachable)
    assert closed.reachable.sum() >= 30
    assert_on_target(robot, closed, targets, task)
    assert_on_target(robot, numeric, targets, task)
    # same branch: the numerical solver started next to the closed-form solution returns it
    ok = closed.reachable
    near = solve(robot, targets[ok], task, method="numeric", q0=closed.q[ok] + 1e-4, restarts=0)
    assert near.reachable.all()
    rows = "all" if task == "pose" else "translational"
    well = manipulability(robot, closed.q[ok], rows=rows) > 1e-3  # isolated solutions
    if robot.nq > {"position": 3, "axis": 5, "pose": 6}[task]:
        well[:] = False  # pragma: no cover - every catalog closed form is square
    if task == "axis":  # the tool spin is free (joint 5): compare the joints that place it
        np.testing.assert_allclose(near.q[well][:, :4], closed.q[ok][well][:, :4], atol=1e-7)
    else:
        np.testing.assert_allclose(near.q[well], closed.q[ok][well], atol=1e-7)


def test_closed_form_path_tracks_the_branch_of_the_motion() -> None:
    puma = catalog.get("puma560")
    q = smooth_path(puma, 400, seed=11, center=PUMA_AWAY)
    T = fk(puma, q)
    closed = solve(puma, T, "pose", q0=q[0], path=True)
    numeric = solve(puma, T, "pose", q0=q[0], path=True, method="numeric")
    for sol in (closed, numeric):
        assert sol.reachable.all() and not sol.flip.any()
        assert np.abs(sol.q - q).max() < 1e-6
    assert len(set(closed.branch.tolist())) == 1


@pytest.mark.parametrize("task", ["position", "axis", "pose"])
def test_a_jump_along_a_path_is_reported_as_a_flip(ur5: Robot, task: str) -> None:
    qa = np.array([0.0, -1.0, 1.0, -0.5, 0.5, 0.0])
    qb = qa + np.array([2.0, 0.0, 0.0, 0.0, 0.0, 0.0])  # the base turns by 2 rad in one sample
    tg = targets_of(ur5, np.stack([qa, qa, qb, qb]), task)
    sol = solve(ur5, tg, task, q0=qa, path=True)
    assert sol.reachable.all()
    assert_on_target(ur5, sol, tg, task)
    np.testing.assert_array_equal(sol.flip, [False, False, True, False])


def test_input_errors_name_the_field(ur5: Robot) -> None:
    T = fk(ur5, np.zeros(6))
    with pytest.raises(ValueError, match="task"):
        solve(ur5, T, "orientation")
    with pytest.raises(ValueError, match="targets"):
        solve(ur5, np.zeros((5, 4)), "position")
    with pytest.raises(ValueError, match="targets"):
        solve(ur5, np.zeros((2, 6)), "axis")  # zero axis
    bad = T.copy()
    bad[:3, :3] *= 2.0
    with pytest.raises(ValueError, match="targets"):
        solve(ur5, bad, "pose")
    with pytest.raises(ValueError, match="method"):
        solve(ur5, T, "pose", method="closed_form")
    with pytest.raises(ValueError, match="q0"):
        solve(ur5, T, "pose", q0=np.zeros(5))
    with pytest.raises(ValueError, match="path"):
        solve_numeric(ur5, T, "pose", path=True)


# ---- real robot files (example-robot-data), when installed ---------------------------------


def erd_robot(subpath: str, name: str, tool_frame: str | None = None) -> Robot:
    """Build a robot from an example-robot-data URDF; gripper fingers locked."""
    from tests.robot_files import require_erd

    root_dir = require_erd()
    text = (root_dir / subpath).read_text(encoding="utf-8")
    fingers = [j.get("name", "") for j in ET.fromstring(text).iter("joint")
               if "finger" in j.get("name", "") and j.get("type") != "fixed"]  # fmt: skip
    spec: dict[str, Any] = {"kind": "urdf", "name": name, "urdf": text,
                            "locked_joints": dict.fromkeys(fingers)}  # fmt: skip
    if tool_frame:
        spec["tool_frame"] = tool_frame
    return build_robot(spec)


@pytest.mark.parametrize(
    "subpath,name,tool",
    [
        ("ur_description/urdf/ur5_robot.urdf", "ur5", None),
        ("panda_description/urdf/panda.urdf", "panda", "panda_hand_tcp"),
    ],
)
def test_urdf_robots_from_example_robot_data(subpath: str, name: str, tool) -> None:
    robot = erd_robot(subpath, name, tool)
    q = smooth_path(robot, 300, seed=12)
    T = fk(robot, q)
    sol = solve(robot, T, "pose", q0=q[0], path=True)
    assert sol.reachable.all() and not sol.flip.any()
    assert_on_target(robot, sol, T, "pose")
    rnd = solve(robot, fk(robot, np.random.default_rng(13).uniform(
        robot.q_min, robot.q_max, (30, robot.nq))), "pose")
    assert rnd.reachable.mean() > 0.95
