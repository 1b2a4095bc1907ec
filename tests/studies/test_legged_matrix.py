"""Issue 9 "Must show": real robots × the legged study kinds, each a short ``legcore.run`` with
physical checks, or the refusal naming the missing capability.

- ``swing_energy``: the foot starts and ends at the requested positions (1e-6 m, by Pinocchio
  FK of the decoded joints), the torques are Pinocchio's RNEA, and the mechanical energy is at
  least the variation of the leg's mechanical energy by the same quadrature (its
  gravity/inertia bound); a legged robot without ``leg`` swings its first front leg. The
  default task (a step derived from the leg) on every matrix robot:
  tests/studies/test_defaults_swing_energy.py.
- ``quadruped_gait``: every foot follows its target (1e-6 m) with the stance feet on the
  ground, and each leg's energy is at least the variation of its mechanical energy (the
  ground reactions are vertical on feet that move horizontally: they do no work).
- ``hexapod_workspace``: no robot here has six legs — each is refused by name; a URDF hexapod
  runs here with the feet-fixed check, the parametric one in
  tests/legcore/studies/hexapod_workspace/test_hexapod_workspace.py.

The checks live in :mod:`tests.studies.checks`; tests/studies/test_service_studies.py applies
them to the same kinds run through the real service.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import pytest

import legcore
from legcore.robots import LeggedRobot
from legcore.runner import prepare
from tests.studies.checks import check_gait, check_hexapod, check_swing
from tests.studies.conftest import refusal_message

SpecOf = Callable[[str], dict[str, Any]]

#: swing_energy rows: robot -> (leg or None, foot start, foot end) in the leg's base frame, m.
SWINGS: dict[str, tuple[str | None, list[float], list[float]]] = {
    "ur5": (None, [0.34, 0.2, 0.1], [0.46, 0.2, 0.1]),
    "solo12_leg": (None, [-0.06, 0.0594, -0.22], [0.06, 0.0594, -0.22]),
    "solo12": ("HL", [-0.06, 0.0594, -0.22], [0.06, 0.0594, -0.22]),
    "anymal": ("LF", [0.10, 0.13, -0.45], [0.22, 0.13, -0.45]),
    "go1": ("FL", [-0.06, 0.08, -0.28], [0.06, 0.08, -0.28]),
}
GA = {"kind": "ga", "params": {"pop_size": 16, "fitness": "window", "penalty": None}}


@pytest.mark.parametrize("name", sorted(SWINGS))
def test_swing_energy_on_real_legs(name: str, robot_spec: SpecOf, built_robot: Any) -> None:
    leg, start, end = SWINGS[name]
    problem: dict[str, Any] = {
        "kind": "swing_energy", "foot_start": start, "foot_end": end, "exact_ends": True,
        "T": 1.0, "dt": 0.02, "step_height": 0.03, "baselines": ["calderon2008_parabolic"],
    }
    if leg is not None:
        problem["leg"] = leg
    r = legcore.run({"robot": robot_spec(name), "problem": problem, "optimizer": GA,
                     "budget": {"generations": 3}, "seed": 2})
    json.dumps(r.to_dict(), allow_nan=False)
    robot = built_robot(name)
    assert isinstance(robot, LeggedRobot) == (leg is not None)
    for sol in (r.best, r.baselines["calderon2008_parabolic"]):
        check_swing(robot, leg, sol, start, end)
    assert r.best.metrics["on_grid"] == 1.0


def test_swing_energy_refuses_a_seven_joint_arm(robot_spec: SpecOf) -> None:
    msg = refusal_message({"robot": robot_spec("panda"), "problem": {"kind": "swing_energy"}})
    assert msg == "robot: swing_energy needs 2–6 actuated joints; robot panda has 7"


def test_swing_energy_on_a_legged_robot_takes_its_first_front_leg(robot_spec: SpecOf) -> None:
    """Without ``leg`` a legged robot swings its first front leg, and the task says so (the runs
    with the default task: tests/studies/test_defaults_swing_energy.py)."""
    task = prepare({"robot": robot_spec("go1"), "problem": {"kind": "swing_energy"}}).problem.task
    assert task is not None and task.params.leg == "FL"
    assert task.rules["leg"].startswith("the first front leg: the hips of ['FL', 'FR'] lie ")


HKA = {"kind": "hka", "params": {"n_samples": 8, "n_best": 3}}


@pytest.mark.parametrize("name", ["solo12", "anymal", "go1"])
def test_quadruped_gait_on_real_quadrupeds(name: str, preset: SpecOf, built_robot: Any) -> None:
    spec = preset(f"quadruped_gait_{name}")
    spec.update(optimizer=HKA, budget={"generations": 2}, record=False)
    spec["problem"]["samples_per_cycle"] = 32
    r = legcore.run(spec)
    json.dumps(r.to_dict(), allow_nan=False)
    sol = r.baselines["default_step"]
    check_gait(built_robot(name), sol)
    assert set(sol.extra["ik"].values()) == {"numerical (legcore.ik.solve)"}
    # the preset's default step (its unset fields derived from the leg length) is feasible
    assert sol.feasible, [v.text for v in sol.violations or ()]


@pytest.mark.parametrize("name", ["ur5", "panda", "solo12_leg"])
def test_quadruped_gait_refuses_serial_chains(name: str, robot_spec: SpecOf) -> None:
    msg = refusal_message({"robot": robot_spec(name), "problem": {"kind": "quadruped_gait"}})
    assert msg.startswith("robot:") and "needs a legged robot" in msg and name in msg


@pytest.mark.parametrize(
    ("name", "why"),
    [
        ("ur5", "needs a legged robot"),
        ("panda", "needs a legged robot"),
        ("solo12_leg", "needs a legged robot"),
        ("solo12", "hexapod_workspace needs 6 legs of 3 joints; robot solo12 has 4 legs"),
        ("anymal", "hexapod_workspace needs 6 legs of 3 joints; robot anymal has 4 legs"),
        ("go1", "hexapod_workspace needs 6 legs of 3 joints; robot go1 has 4 legs"),
    ],
)
def test_hexapod_workspace_refuses_what_is_not_a_hexapod(
    name: str, why: str, robot_spec: SpecOf
) -> None:
    msg = refusal_message({"robot": robot_spec(name), "problem": {"kind": "hexapod_workspace"}})
    assert msg.startswith("robot:") and why in msg


def test_hexapod_workspace_on_a_urdf_hexapod() -> None:
    """A parametric hexapod written as URDF (numerical FK/IK), its pose grid given by hand
    (used as given; the rest of the task derived from the robot — tests/studies/
    test_defaults_hexapod.py runs hexapods with every default): the optimum is feasible (stable)
    and its and the baselines' motions keep the stance feet where they started (Pinocchio FK,
    1e-6 m)."""
    from legcore.studies.hexapod_workspace.robot import HexapodGeometry, hexapod_urdf

    spec = {"robot": {"kind": "urdf", "name": "hexapod", "legs": "auto",
                      "urdf": hexapod_urdf(HexapodGeometry(link_lengths=(0.03, 0.08, 0.12)))},
            "problem": {"kind": "hexapod_workspace", "paper_baselines": False,
                        "pose_x_extent": 0.04, "pose_xy_step": 0.004, "pose_y_extent": 0.04,
                        "pose_yaw_step": 0.2617993877991494},
            "optimizer": {"kind": "moead", "params": {"n_subproblems": 30}},
            "budget": {"generations": 3}, "seed": 1, "record": False}
    problem = prepare(spec).problem
    r = legcore.run(spec)
    checked = [check_hexapod(problem, sol) for sol in (r.best, *r.baselines.values())]
    assert set(r.baselines) == {"start", "straight_walk"} and all(checked)
    assert problem.task is not None and problem.task.params.pose_x_extent == 0.04
    assert "pose_x_extent" not in problem.task.rules and "theta2" in problem.task.rules
    assert r.feasible and r.best.metrics["stable"] == 1.0
