"""Issue 9 "Must show", arm kinds: real robots' files (example-robot-data) × ``path_tracking``
and ``path_placement``, each a short ``legcore.run`` of the arm presets
(``examples/presets/path_*.yaml``; the Z1 with its default, robot-derived task) checked
physically — not just "it ran" (every matrix robot with DEFAULT task settings:
tests/studies/test_defaults_arms.py):

- the tool follows the path: Pinocchio FK of the decoded joints is on the path to 1e-6 m
  (tracking: the path at σ(t); placement: every placed target), with the tool orientation kept;
- the joints stay inside their position, speed, acceleration (tracking) and torque limits, and
  q̇ is the derivative of q (one consistent motion);
- the torques are Pinocchio's RNEA of the motion, and the mechanical energy Σ∫|τ_i q̇_i| dt is
  at least the variation of the chain's kinetic + potential energy by the same quadrature (its
  gravity/inertia bound, :mod:`tests.studies.checks`);
- every other matrix robot is refused, naming the missing capability.

The checks live in :mod:`tests.studies.checks`. One robot per arm kind also runs through the
real service (API + a worker process): the stored optimum and seed law, decoded again, pass the
same checks; a refused robot is a 422 located at ``robot``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import legcore
from legcore.runner import prepare
from legcore.studies.path_placement.problem import PathPlacementProblem
from legcore.studies.path_tracking.problem import PathTrackingProblem
from services.client import ApiError
from tests.robot_files import ERD_URDF, erd_robots_dir
from tests.studies.checks import (
    check_placement,
    check_tracking,
    stored_baselines,
    stored_best,
    stored_solution,
)
from tests.studies.conftest import refusal_message

SpecOf = Callable[[str], dict[str, Any]]

NSGA2 = {"kind": "nsga2", "params": {"pop_size": 30}}
HKA = {"kind": "hka", "params": {"n_samples": 12, "n_best": 4, "init": "survey",
                                 "survey_size": 27, "survey_best": 3, "penalty": 1000.0}}


def short(spec: dict[str, Any], generations: int) -> dict[str, Any]:
    """A preset with a test-sized budget (NSGA-II 30 or HKA 12 per generation)."""
    opt = NSGA2 if spec["problem"]["kind"] == "path_tracking" else HKA
    return {**spec, "optimizer": opt, "budget": {"generations": generations}, "record": False}


def z1_capsule() -> dict[str, Any]:
    """Unitree Z1 (gripper locked) with its default task: seed 004's capsule scaled to its
    reach, where it is well conditioned, with a tool orientation it holds (derived)."""
    root = erd_robots_dir()
    assert root is not None
    robot = {"kind": "urdf", "name": "z1", "urdf": (root / ERD_URDF["z1"]).read_text(),
             "locked_joints": {"jointGripper": None}}
    return {"robot": robot, "problem": {"kind": "path_tracking"}, "seed": 1}


@pytest.mark.parametrize("name", ["ur5", "panda", "z1"])
def test_path_tracking_on_real_arms(name: str, preset: SpecOf) -> None:
    spec = short(z1_capsule() if name == "z1" else preset(f"path_tracking_{name}"), 15)
    problem = prepare(spec).problem
    assert isinstance(problem, PathTrackingProblem)
    if name == "panda":  # the robot's own limits (MoveIt's), given in its spec by joint name
        np.testing.assert_array_equal(problem.qdd_max, [3.75, 1.875, 2.5, 3.125, 3.75, 5, 5])
    res = legcore.run(spec)
    for sol in (res.best, res.baselines["seed"]):
        check_tracking(problem, sol)
    assert res.best.objectives["time"] < res.baselines["seed"].objectives["time"]


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_path_placement_on_real_arms(name: str, preset: SpecOf) -> None:
    spec = short(preset(f"path_placement_{name}"), 4)
    problem = prepare(spec).problem
    assert isinstance(problem, PathPlacementProblem) and not problem.closed_form
    check_placement(problem, legcore.run(spec).best)


@pytest.mark.parametrize(
    ("name", "kind", "why"),
    [
        ("solo12_leg", "path_tracking", "path_tracking needs ≥ 5 actuated joints; robot "
                                        "solo12_leg.FL has 3"),
        ("solo12_leg", "path_placement", "path_placement needs ≥ 6 actuated joints; robot "
                                         "solo12_leg.FL has 3"),
        # every whole legged robot × every arm kind
        *[(robot, kind, "needs a serial")
          for robot in ("solo12", "anymal", "go1")
          for kind in ("path_tracking", "path_placement")],
    ],
)
def test_arm_kinds_refuse_what_is_not_an_arm(name: str, kind: str, why: str,
                                             robot_spec: SpecOf) -> None:
    msg = refusal_message({"robot": robot_spec(name), "problem": {"kind": kind}})
    assert msg.startswith("robot:") and why in msg and name in msg


def test_a_5_joint_arm_tracks_but_does_not_place(robot_spec: SpecOf) -> None:
    """The UR5 with its last joint locked: 5 joints, enough to track a path (its default task:
    a path a 5-joint arm can follow, derived), not to place one."""
    ur5_5 = robot_spec("ur5") | {"locked_joints": {"wrist_3_joint": None}}
    msg = refusal_message({"robot": ur5_5, "problem": {"kind": "path_placement"}})
    assert msg == "robot: path_placement needs ≥ 6 actuated joints; robot ur5 has 5"
    ur5_4 = robot_spec("ur5") | {"locked_joints": {"wrist_3_joint": None, "wrist_2_joint": None}}
    msg = refusal_message({"robot": ur5_4, "problem": {"kind": "path_tracking"}})
    assert msg == "robot: path_tracking needs ≥ 5 actuated joints; robot ur5 has 4"
    spec = {"robot": ur5_5, "problem": {"kind": "path_tracking", "n_samples": 40}}
    problem = prepare(spec).problem
    assert problem.robot.nq == 5 and problem.task is not None and problem.task.rules


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
    stored results (optimum, and the tracking's seed law) decoded again from their decision
    vectors reproduce the stored metrics and pass the matrix's physical checks: the tool on the
    path / on every placed target to 1e-6 m by Pinocchio, limits, energy ≥ the gravity bound.
    A 4-joint arm is a 422 at body.robot."""
    specs = {"path_tracking": short(preset("path_tracking_ur5"), 15),
             "path_placement": short(preset("path_placement_panda"), 3)}
    with service.client() as c:
        jobs = {kind: c.submit(spec)["id"] for kind, spec in specs.items()}
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
            problem = prepare(specs[kind]).problem
            best = stored_solution(problem, stored_best(result))
            if kind == "path_tracking":
                assert extra["path_error"] < 1e-6 and extra["orientation_error"] < 1e-6
                for use in ("qd_use_max", "qdd_use_max", "tau_use_max"):
                    assert metrics[use] <= 1.0 + 1e-9
                seed = stored_solution(problem, stored_baselines(result)["seed"])
                for sol in (best, seed):
                    check_tracking(problem, sol)
                assert metrics["time"] < seed.metrics["time"]
            else:
                assert extra["energy_kind"] == "mechanical"
                assert not math.isnan(metrics["mean_manipulability"])
                check_placement(problem, best)
