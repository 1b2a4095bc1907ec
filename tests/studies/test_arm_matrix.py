"""Issue 9 "Must show", arm kinds: real robots' files (example-robot-data) × ``path_tracking``
and ``path_placement``, each a short ``legcore.run`` of the arm presets
(``examples/presets/path_*.yaml``) checked physically — not just "it ran":

- the tool follows the path: Pinocchio FK of the decoded joints is on the path to 1e-6 m
  (tracking: the path at σ(t); placement: every placed target), with the tool orientation kept;
- the joints stay inside their position, speed, acceleration (tracking) and torque limits, and
  q̇ is the derivative of q (one consistent motion);
- the mechanical energy Σ∫|τ_i q̇_i| dt is at least the total variation of the chain's
  kinetic + potential energy (its gravity/inertia bound, :mod:`tests.studies.physics`);
- every other matrix robot is refused, naming the missing capability.

One robot per arm kind also runs through the real service (API + a worker process), and a
refused robot is a 422 located at ``robot``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import legcore
from legcore.kinematics import fk
from legcore.problems.path_placement import PathPlacementProblem
from legcore.problems.path_tracking import PathTrackingProblem
from legcore.robots import Robot
from legcore.runner import prepare
from services.client import ApiError
from tests.robot_files import ERD_URDF, erd_robots_dir
from tests.studies.conftest import refusal_message
from tests.studies.physics import energy_variation, tool_positions

SpecOf = Callable[[str], dict[str, Any]]

NSGA2 = {"kind": "nsga2", "params": {"pop_size": 20}}
HKA = {"kind": "hka", "params": {"n_samples": 12, "n_best": 4, "init": "survey",
                                 "survey_size": 27, "survey_best": 3, "penalty": 1000.0}}


def short(spec: dict[str, Any], generations: int) -> dict[str, Any]:
    """A preset with a test-sized budget (NSGA-II 20 or HKA 12 per generation)."""
    opt = NSGA2 if spec["problem"]["kind"] == "path_tracking" else HKA
    return {**spec, "optimizer": opt, "budget": {"generations": generations}, "record": False}


def z1_capsule() -> dict[str, Any]:
    """Unitree Z1 (gripper locked): the seed's capsule at z = 0.20 m, orientation free."""
    root = erd_robots_dir()
    assert root is not None
    robot = {"kind": "urdf", "name": "z1", "urdf": (root / ERD_URDF["z1"]).read_text(),
             "locked_joints": {"jointGripper": None}}
    return {"robot": robot, "problem": {"kind": "path_tracking", "orientation": "free",
                                        "plane_origin": [0.0, 0.0, 0.2]}, "seed": 1}


def check_limits(robot: Robot, mo: Any, qdd_max: np.ndarray | None = None) -> None:
    assert robot.within_limits(mo.q, tol=1e-9).all()
    assert np.all(np.abs(mo.qd) <= robot.qd_max * (1 + 1e-9))
    assert np.all(np.abs(mo.tau) <= robot.tau_max * (1 + 1e-9))
    if qdd_max is not None:
        assert np.all(np.abs(mo.qdd) <= qdd_max * (1 + 1e-9))


@pytest.mark.parametrize("name", ["ur5", "panda", "z1"])
def test_path_tracking_on_real_arms(name: str, preset: SpecOf) -> None:
    spec = short(z1_capsule() if name == "z1" else preset(f"path_tracking_{name}"), 8)
    problem = prepare(spec).problem
    assert isinstance(problem, PathTrackingProblem)
    robot = problem.robot
    if name == "panda":  # the robot's own limits (MoveIt's), given in its spec by joint name
        np.testing.assert_array_equal(problem.qdd_max, [3.75, 1.875, 2.5, 3.125, 3.75, 5, 5])
    res = legcore.run(spec)
    for sol in (res.best, res.baselines["seed"]):
        assert sol.metrics["feasible"] == 1.0
        mo = sol.motion
        sigma = problem.time_law(np.asarray(sol.x)[None, :]).evaluate(mo.t[None, :])[0, 0]
        path = problem.path.derivatives(sigma)[0]
        assert np.abs(tool_positions(robot, mo.q) - path).max() < 1e-6  # on the path
        assert problem.tool.errors(fk(robot, mo.q), path)[1].max() < 1e-6  # orientation kept
        check_limits(robot, mo, problem.qdd_max)
        np.testing.assert_allclose(np.gradient(mo.q, mo.t, axis=0)[1:-1], mo.qd[1:-1],
                                   atol=0.02 * np.abs(mo.qd).max() + 1e-9)
        assert sol.metrics["energy"] >= 0.98 * energy_variation(robot, mo.q, mo.qd) - 1e-9
    assert res.best.objectives["time"] < res.baselines["seed"].objectives["time"]


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_path_placement_on_real_arms(name: str, preset: SpecOf) -> None:
    spec = short(preset(f"path_placement_{name}"), 4)
    problem = prepare(spec).problem
    assert isinstance(problem, PathPlacementProblem) and not problem.closed_form
    robot = problem.robot
    best = legcore.run(spec).best
    assert best.metrics["feasible"] == 1.0 and best.metrics["unreachable_fraction"] == 0.0
    assert best.extra["energy_kind"] == "mechanical" and best.motion.power_kind == "mechanical"
    mo = best.motion
    placed = problem.placed_poses(best.x)[0]
    assert np.abs(tool_positions(robot, mo.q) - placed[:, :3, 3]).max() < 1e-6
    assert np.abs(fk(robot, mo.q)[:, :3, :3] - placed[:, :3, :3]).max() < 1e-6
    check_limits(robot, mo)
    assert best.metrics["energy_J"] >= 0.98 * energy_variation(robot, mo.q, mo.qd) - 1e-9
    assert 0.0 < best.metrics["mean_manipulability_ratio"] <= 1.0 + 1e-9


@pytest.mark.parametrize(
    ("name", "kind", "why"),
    [
        ("solo12_leg", "path_tracking", "path_tracking needs ≥ 5 actuated joints; robot "
                                        "solo12_leg.FL has 3"),
        ("solo12_leg", "path_placement", "path_placement needs ≥ 6 actuated joints; robot "
                                         "solo12_leg.FL has 3"),
        ("solo12", "path_tracking", "needs a serial"),
        ("anymal", "path_placement", "needs a serial"),
        ("go1", "path_tracking", "needs a serial"),
    ],
)
def test_arm_kinds_refuse_what_is_not_an_arm(name: str, kind: str, why: str,
                                             robot_spec: SpecOf) -> None:
    msg = refusal_message({"robot": robot_spec(name), "problem": {"kind": kind}})
    assert msg.startswith("robot:") and why in msg and name in msg


def test_a_5_joint_arm_tracks_but_does_not_place(robot_spec: SpecOf) -> None:
    """The UR5 with its last joint locked: 5 joints, enough to track a path, not to place one."""
    ur5_5 = robot_spec("ur5") | {"locked_joints": {"wrist_3_joint": None}}
    msg = refusal_message({"robot": ur5_5, "problem": {"kind": "path_placement"}})
    assert msg == "robot: path_placement needs ≥ 6 actuated joints; robot ur5 has 5"
    ur5_4 = robot_spec("ur5") | {"locked_joints": {"wrist_3_joint": None, "wrist_2_joint": None}}
    msg = refusal_message({"robot": ur5_4, "problem": {"kind": "path_tracking"}})
    assert msg == "robot: path_tracking needs ≥ 5 actuated joints; robot ur5 has 4"
    spec = {"robot": ur5_5, "problem": {"kind": "path_tracking", "orientation": "free",
                                        "plane_origin": [0.1, 0.0, 0.2], "n_samples": 40}}
    assert prepare(spec).problem.robot.nq == 5


# --------------------------------------------------------------------------- the real service


@pytest.fixture(scope="module")
def service(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Any]:
    from tests.integration.stack import embedded_stack

    tmp: Path = tmp_path_factory.mktemp("arm-matrix")
    with embedded_stack(tmp) as st:
        yield st


@pytest.mark.integration
def test_one_robot_per_arm_kind_through_the_service(service: Any, preset: SpecOf,
                                                    robot_spec: SpecOf) -> None:
    """UR5 tracking and Panda placement submitted over HTTP and run by a worker process; the
    stored results carry the physical checks' numbers. A 4-joint arm is a 422 at body.robot."""
    with service.client() as c:
        jobs = {"path_tracking": c.submit(short(preset("path_tracking_ur5"), 6))["id"],
                "path_placement": c.submit(short(preset("path_placement_panda"), 3))["id"]}
        ur5_4 = robot_spec("ur5") | {"locked_joints": {"wrist_3_joint": None,
                                                       "wrist_2_joint": None}}
        with pytest.raises(ApiError) as err:
            c.submit({"robot": ur5_4, "problem": {"kind": "path_tracking"}})
        assert err.value.status == 422
        assert err.value.detail[0]["loc"] == ["body", "robot"]
        assert err.value.detail[0]["msg"] == "path_tracking needs ≥ 5 actuated joints; " \
                                             "robot ur5 has 4"
        for kind, job_id in jobs.items():
            job = c.wait(job_id, poll_s=0.2, timeout_s=120)
            assert job["status"] == "succeeded", (job, service.log_tail())
            result = c.result(job_id)
            metrics, extra = result["metrics"], result["summary"]["extra"]
            assert metrics["feasible"] == 1.0
            if kind == "path_tracking":
                assert extra["path_error"] < 1e-6 and extra["orientation_error"] < 1e-6
                for use in ("qd_use_max", "qdd_use_max", "tau_use_max"):
                    assert metrics[use] <= 1.0 + 1e-9
            else:
                assert extra["energy_kind"] == "mechanical"
                assert metrics["unreachable_fraction"] == 0.0 and metrics["energy_J"] > 0.0
                assert not math.isnan(metrics["mean_manipulability"])
