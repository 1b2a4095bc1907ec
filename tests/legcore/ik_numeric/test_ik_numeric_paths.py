"""legcore.ik.solve along paths: the one-step fast path against the reference solvers, branch
continuity, flips, batches of paths, the rest posture of a redundant arm, agreement with every
closed form of the catalog, and the UR5 / Panda URDFs of ``example-robot-data`` when that
package is installed.

Robots, paths and the FK check: ``tests/legcore/ik_numeric_helpers.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from legcore.ik import solve
from legcore.kinematics import fk, jacobian
from legcore.manipulability import manipulability
from legcore.robots import Robot, build_robot, catalog
from tests.legcore.ik_numeric.ik_numeric_helpers import (
    PUMA_AWAY,
    UR5_AWAY,
    assert_on_target,
    smooth_path,
    targets_of,
)


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


# ---- real robot files (example-robot-data), when installed ---------------------------------


def erd_robot(subpath: str, name: str, tool_frame: str | None = None) -> Robot:
    """Build a robot from an example-robot-data URDF; gripper fingers locked."""
    from tests.robot_files import erd_arm_spec, require_erd

    text = (require_erd() / subpath).read_text(encoding="utf-8")
    return build_robot(erd_arm_spec(text, name, tool_frame))


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
