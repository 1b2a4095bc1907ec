"""legcore.ik.solve / solve_numeric: batched numerical IK of any chain, checked by FK.

Robots: a UR5, a Panda and a SCARA given by their DH tables (``ik_numeric_helpers.py``: the
tests run without extra data) and the catalog's robots. Here: the per-sample kinematics the
solver uses, random reachable targets, prismatic joints, joint limits, unreachable targets and
input errors; along paths, closed forms and robot files: ``test_ik_numeric_paths.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from legcore.ik import solve, solve_numeric
from legcore.ik.sample_kinematics import fk_z, jac_z, z_chain
from legcore.kinematics import fk, fk_jacobian
from legcore.robots import Robot, catalog
from tests.legcore.ik_numeric.ik_numeric_helpers import (
    TOL,
    assert_on_target,
    scara,
    targets_of,
    ur5_dh,
)


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
