"""Issue 25 "Must show", through the real service: one robot that is not a seed robot per study
kind, submitted over HTTP with DEFAULT task settings (only the kind given, and a test-sized
budget) and run by a worker process of the embedded stack.

Each job ends ``succeeded`` with ``feasible: true`` on the job, its list row and its result,
and the stored optimum — its decision vector decoded again here with the same spec, which must
reproduce the stored metrics (:func:`tests.studies.checks.stored_solution`) — passes the same
physical checks as the ``legcore.run`` matrix (tests/studies/test_defaults_*.py): the foot steps
forward in body axes and comes back to its start height, the gait keeps its margin with no
foot pulling on the ground, the tool follows the path to 1e-6 m inside its limits on a dense
resampling, the placed path is reached at every point, the hexapod's stance feet stay put; and
every energy is at least its gravity bound. The task the job ran with (``task`` of the result:
the robot-derived parameters and their rules) is the one ``legcore`` derives.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from legcore.robots import LeggedRobot
from legcore.runner import prepare
from legcore.studies.hexapod_workspace.robot import HexapodGeometry, hexapod_urdf
from tests.integration.stack import Stack, embedded_stack
from tests.studies.checks import (
    check_gait,
    check_hexapod,
    check_placement,
    check_tracking,
    stored_best,
    stored_solution,
)
from tests.studies.test_defaults_arms import SHORT as ARM_SHORT
from tests.studies.test_defaults_arms import _dense_limits
from tests.studies.test_defaults_quadruped_gait import HKA as GAIT_HKA
from tests.studies.test_defaults_swing_energy import check_step

pytestmark = pytest.mark.integration

SpecOf = Callable[[str], dict[str, Any]]


def _specs(robot_spec: SpecOf) -> dict[str, dict[str, Any]]:
    """Kind -> a job spec with the default task on a robot that is not a seed robot."""
    hexapod = {"kind": "urdf", "name": "hexapod", "legs": "auto",
               "urdf": hexapod_urdf(HexapodGeometry(link_lengths=(0.03, 0.08, 0.12)))}
    short = {"seed": 1, "record": False}
    return {
        "swing_energy": {"robot": robot_spec("solo12"), "problem": {"kind": "swing_energy"},
                         "budget": {"generations": 10}, **short},
        "quadruped_gait": {"robot": robot_spec("go1"), "problem": {"kind": "quadruped_gait"},
                           "optimizer": GAIT_HKA, "budget": {"generations": 3}, **short},
        "path_tracking": {"robot": robot_spec("so100"), "problem": {"kind": "path_tracking"},
                          **ARM_SHORT["path_tracking"], **short},
        "path_placement": {"robot": robot_spec("kinova"), "problem": {"kind": "path_placement"},
                           **ARM_SHORT["path_placement"], **short},
        "hexapod_workspace": {"robot": hexapod, "problem": {"kind": "hexapod_workspace"},
                              "optimizer": {"kind": "moead", "params": {"n_subproblems": 40}},
                              "budget": {"generations": 10}, **short},
    }


@pytest.fixture(scope="module")
def stack(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Stack]:
    tmp: Path = tmp_path_factory.mktemp("service-defaults")
    with embedded_stack(tmp) as st:
        yield st


def test_default_tasks_through_the_service_are_feasible_and_physical(
    stack: Stack, robot_spec: SpecOf, built_robot: Callable[[str], Any]
) -> None:
    specs = _specs(robot_spec)
    with stack.client() as c:
        ids = {kind: c.submit(spec)["id"] for kind, spec in specs.items()}
        done = {kind: c.wait(job_id, poll_s=0.2, timeout_s=600) for kind, job_id in ids.items()}
        rows = {row["id"]: row for row in c.jobs(limit=100)["items"]}
        results = {kind: c.result(job_id) for kind, job_id in ids.items()}
    for kind, job in done.items():
        assert job["status"] == "succeeded", (kind, job, stack.log_tail())
        assert job["feasible"] is True and job["violations"] == [], (kind, job["violations"])
        assert rows[job["id"]]["feasible"] is True, kind
        res = results[kind]
        assert res["feasible"] is True and res["violations"] == [], kind
        prepared = prepare(specs[kind])
        problem = prepared.problem
        assert problem.task is not None and res["task"]["rules"] == dict(problem.task.rules)
        assert res["task"]["preset"] is None and res["task"]["rules"], kind  # robot-derived
        best = stored_solution(problem, stored_best(res))
        if kind == "swing_energy":
            leg = problem.task.params.leg
            assert leg == "FL"  # Solo12's first front leg, said in the rules
            assert "FL" in res["task"]["rules"]["leg"]
            run = SimpleNamespace(best=best, spec=prepared.spec)
            step = check_step(built_robot("solo12"), leg, run)
            assert step[0] > 0.1  # forward along the body's x axis, m
        elif kind == "quadruped_gait":
            robot = built_robot("go1")
            assert isinstance(robot, LeggedRobot)
            check_gait(robot, best)
            scene = best.motion.scene
            assert np.all(scene["stability_margin"] >= problem.task.params.stability_margin
                          - 1e-12)
            loads = scene["foot_loads_N"]
            assert loads.min() >= -1e-9 * loads.max()  # no foot pulls on the ground
        elif kind == "path_tracking":
            check_tracking(problem, best)
            _dense_limits(problem, np.asarray(best.x))
        elif kind == "path_placement":
            check_placement(problem, best)
        else:
            assert check_hexapod(problem, best) and best.metrics["stable"] == 1.0
