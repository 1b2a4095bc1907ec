"""``quadruped_gait`` with DEFAULT task settings on every matrix robot (issue 25, item 1): the
gait is derived from the robot's leg length (legcore/studies/quadruped_gait/defaults.py), so a
quadruped that can stand gets a statically feasible default walk and a feasible optimum; what
cannot work is refused up front, with the same message by the listing (``fit``) and the
submission (``prepare``).

Physical checks of every run, none of them by the study's own code: every foot on its target
by Pinocchio FK and the stance feet on the ground, each leg's energy at least its
gravity/inertia bound (:func:`tests.studies.checks.check_gait`); the COM inside the support
polygon of the stance feet at every sample (a margin ≥ the required one), no foot pulling on
the ground (vertical loads ≥ 0, summing to the weight); the standing postures by Pinocchio FK
(the foot H below the hip, the knee on its side, inside the joint limits). Runtime ≈ 15 s.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import legcore
from legcore.robots import LeggedRobot
from legcore.runner import prepare
from legcore.studies.fit import fit
from legcore.studies.registry import get_study
from tests.studies.checks import check_gait
from tests.studies.conftest import MATRIX_ROBOTS, refusal_message
from tests.studies.physics import tool_positions

SpecOf = Callable[[str], dict[str, Any]]

KIND = "quadruped_gait"
#: the quadrupeds that must walk with the defaults; every other matrix robot is refused
WALKERS = ("solo12", "anymal", "go1")
#: a short budget: HKA on a 30-point survey of the search box, 3 generations of 10
HKA = {"kind": "hka", "params": {"n_samples": 10, "n_best": 3, "survey_size": 30,
                                 "survey_best": 3}}


def _default(spec_of: SpecOf, name: str, **problem: Any) -> dict[str, Any]:
    return {"robot": spec_of(name), "problem": {"kind": KIND, **problem}, "optimizer": HKA,
            "budget": {"generations": 3}, "seed": 1, "record": False}


@pytest.mark.parametrize("name", sorted(MATRIX_ROBOTS))
def test_default_task_is_refused_up_front_or_walks_feasibly(
    name: str, robot_spec: SpecOf, built_robot: Any
) -> None:
    robot = built_robot(name)
    verdict = fit(robot, KIND)
    spec = _default(robot_spec, name)
    if name not in WALKERS:
        assert not verdict.accepted and verdict.field == "robot"
        assert refusal_message(spec) == verdict.message
        return
    assert verdict.accepted and verdict.task is not None, verdict.message
    r = legcore.run(spec)
    weight = prepare(spec).problem.mass * 9.81  # body + legs, N
    assert r.feasible, [v.text for v in r.best.violations or ()]
    base = r.baselines["default_step"]
    assert base.feasible, [v.text for v in base.violations or ()]  # the rules' default step
    assert isinstance(robot, LeggedRobot)
    p = r.task.params if r.task is not None else None
    assert p is not None and p == verdict.task.params
    for sol in (r.best, base):
        check_gait(robot, sol)
        scene = sol.motion.scene
        assert np.all(scene["stability_margin"] >= p.stability_margin - 1e-12)
        assert p.stability_margin > 0.0
        loads = scene["foot_loads_N"]  # (K+1, 4) vertical ground reactions, N
        assert loads.min() >= -1e-9 * loads.max()  # no foot pulls on the ground
        np.testing.assert_allclose(loads.sum(-1), weight, rtol=1e-9)  # they carry the robot
        assert sol.metrics["max_joint_speed_ratio"] <= 1.0
        assert sol.metrics["max_torque_ratio"] <= 1.0
    assert r.best.objectives["energy_per_metre"] <= base.objectives["energy_per_metre"] + 1e-9


@pytest.mark.parametrize("name", WALKERS)
def test_default_gait_scales_with_the_leg(name: str, built_robot: Any) -> None:
    """The rules: depth 0.75 L, step 0.4 L high 0.1 L, Froude number v²/(g L) = 0.01 (or slower
    for the joints), margin 0.25 % of L; each leg stands there (Pinocchio FK) inside its
    limits, its knee toward the body centre unless its limits forbid it."""
    robot = built_robot(name)
    task = get_study(KIND).task(robot, get_study(KIND).params(kind=KIND))
    p = task.params
    L = p.depth / 0.75
    assert p.step_length == pytest.approx(0.4 * L) and p.step_height == pytest.approx(0.1 * L)
    assert p.step_length_bounds == pytest.approx((0.1 * L, 0.6 * L))
    assert p.stability_margin == pytest.approx(0.0025 * L)
    assert p.speed**2 / (9.81 * L) <= 0.01 * (1 + 1e-9)
    assert set(task.rules) >= {"depth", "speed", "step_length", "stroke_center", "q_ref"}
    assert f"{L:.4g} m" in task.rules["depth"] and "Froude" in task.rules["speed"]
    hips = np.array([leg.hip[:3, 3] for leg in robot.legs])
    for leg, hip in zip(robot.legs, hips, strict=True):
        q = np.asarray(p.q_ref[leg.name])
        assert leg.robot.within_limits(q[None], tol=0.0).all()
        foot = leg.foot_in_body(tool_positions(leg.robot, q[None]))[0]
        assert foot[2] - hip[2] == pytest.approx(-p.depth, abs=1e-6)
        assert foot[0] - hip[0] == pytest.approx(p.stroke_center, abs=1e-6)
        # the knee (the last joint's origin, Pinocchio) ahead of or behind the hip-foot line
        model, data = leg.robot.model, leg.robot.data()
        pin.forwardKinematics(model, data, q)
        knee = leg.foot_in_body(data.oMi[model.njoints - 1].translation)
        t = (knee[2] - hip[2]) / (foot[2] - hip[2])
        ahead = knee[0] > hip[0] + t * (foot[0] - hip[0])
        toward_centre = ahead == (hip[0] < 0.0)  # rear knees ahead, front knees behind
        words = task.rules["q_ref"].split(f"{leg.name}: ", 1)[1].split(";")[0]
        assert ("ahead of" if ahead else "behind") in words
        if name == "go1":  # its knee limits allow only knees behind the feet
            assert not ahead and leg.robot.q_max[2] < 0.0
        else:
            assert toward_centre, (leg.name, q)
    assert (name == "go1") == ("allow no other" in task.rules["q_ref"])  # Go1's rear knees


def test_a_given_value_is_used_as_given(robot_spec: SpecOf) -> None:
    prepared = prepare(_default(robot_spec, "go1", speed=0.15, step_length=0.12))
    problem = prepared.problem
    task = problem.task
    assert task is not None
    assert task.params.speed == 0.15 and task.params.step_length == 0.12
    assert "speed" not in task.rules and "step_length" not in task.rules
    assert "step_height" in task.rules  # the rest still derived
    sol = problem.baseline_solutions()["default_step"]
    assert sol.x is not None and sol.x[0] == 0.12 and sol.metrics["speed_m_s"] == 0.15
    assert sol.metrics["cycle_time_s"] == pytest.approx(0.12 / (0.8 * 0.15))


@pytest.mark.parametrize(
    ("problem", "field", "words"),
    [
        ({"step_length": 0.9}, "step_length", "longer than any stroke"),
        ({"depth": 0.5}, "depth", "cannot stand"),
        ({"depth": 0.05}, "depth", "cannot stand"),
        ({"step_length": 0.6, "step_length_bounds": [0.1, 0.6]}, "step_length", "out of reach"),
    ],
)
def test_an_impossible_given_task_is_refused_naming_the_field(
    problem: dict[str, Any], field: str, words: str, robot_spec: SpecOf, built_robot: Any
) -> None:
    spec = _default(robot_spec, "go1", **problem)
    msg = refusal_message(spec)
    assert msg.startswith(f"{field}: ") and words in msg, msg
    verdict = get_study(KIND).fit(built_robot("go1"), get_study(KIND).params(kind=KIND,
                                                                            **problem))
    assert not verdict.accepted and verdict.field == field and verdict.message == msg
    assert "give" in msg  # says what to change


def test_the_seed_robot_keeps_its_paper_values() -> None:
    """On seed 003's own robot the preset, not the rules, fills the defaults; the rules there
    would give a speed near the paper's (its servos are slow)."""
    from legcore.robots import catalog

    study = get_study(KIND)
    robot = catalog.get("animatronic_quadruped")
    task = study.task(robot, study.params(kind=KIND))
    assert task.preset is not None and task.params.speed == 0.03
    assert (task.params.step_length, task.params.depth) == (0.119, 0.1648)
    derived = study.derive(robot, study.params(kind=KIND)) if study.derive else None
    assert derived is not None
    assert derived.params.depth == pytest.approx(0.75 * 0.1775)
    assert math.isclose(derived.params.speed, 0.03, rel_tol=0.1)  # 0.029 m/s by the rule
    assert "lowered" in derived.rules["speed"]
