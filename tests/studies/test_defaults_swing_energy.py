"""``swing_energy`` with the DEFAULT task on every matrix robot (issue 25): the task is a step
derived from the robot (:mod:`legcore.studies.swing_energy.defaults`).

Each robot is either refused up front — the listing's verdict (:func:`legcore.studies.fit.fit`)
and the submission's (:func:`legcore.runner.prepare`) are the same message, naming the field to
give — or runs (the study's default optimiser, 10 generations) to a FEASIBLE optimum whose
motion passes physical checks, independent of legcore's kinematics (Pinocchio):

- the foot starts and ends at the derived positions: half a step behind and ahead of the
  nominal stance, which lies under the hip's pitch joint along the body's forward axis, at the
  foot's home lateral offset (at most 45° out from under it) and 0.7 L from that joint (L the
  stretched leg below it: no sampled posture reaches further); it moves forward along the
  body's x axis by the step length 0.5 L, its lateral and vertical end−start difference 0 to
  1e-6 m;
- the knee is on the leg's own branch (behind the hip–foot line at both ends);
- the foot stays above the ground (its start height, less the 1 mm tolerance) during the swing;
- the mechanical energy is at least the motion's gravity/inertia bound (``check_energy``).

And a value the user gives (``leg``, ``foot_start``) is used as given, the rest derived from it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin
import pytest

import legcore
from legcore.robots import LeggedRobot, Robot, build_robot, catalog
from legcore.runner import prepare
from legcore.studies.fit import fit
from legcore.studies.swing_energy.defaults import FRACTIONS, leg_length_of
from tests.studies.checks import POS_TOL, check_energy, swing_chain
from tests.studies.conftest import MATRIX_ROBOTS, refusal_message
from tests.studies.physics import tool_positions

SpecOf = Callable[[str], dict[str, Any]]

#: robot -> the field its refusal names (None: it runs)
REFUSED = {"ur5": "foot_start", "panda": "robot", "kinova": "foot_start", "z1": "foot_start",
           "so100": "foot_start"}
#: robot -> the leg it swings by default (None: a serial chain, the leg itself)
LEGS = {"solo12_leg": None, "solo12": "FL", "anymal": "LF", "go1": "FL"}
SHORT = {"budget": {"generations": 10}, "seed": 1, "record": False}
STEP = 0.5  # × L
RULES = {"q_start", "q_end", "exact_ends", "step_height", "w_d", "w_a", "search_range", "tube",
         "lift_only"}


def _forward(robot: Robot | LeggedRobot, leg: str | None) -> np.ndarray:
    """The body's forward axis in the swinging leg's base frame (x of a serial chain)."""
    if not isinstance(robot, LeggedRobot):
        return np.array([1.0, 0.0, 0.0])
    f = np.asarray((robot.meta or {}).get("forward", (1.0, 0.0, 0.0)), dtype=float)
    assert leg is not None
    return robot.leg(leg).hip[:3, :3].T @ f


def _hip(chain: Robot, q: np.ndarray) -> np.ndarray:
    """The hip's pitch joint (the second joint) at ``q``: Pinocchio's joint placement."""
    model, data = chain.model, chain.data()
    pin.forwardKinematics(model, data, q)
    return np.array(data.oMi[2].translation)


def _knee_behind(chain: Robot, q: np.ndarray, forward: np.ndarray) -> bool:
    """The last joint (the knee) lies behind the line from the second joint to the foot, in the
    forward–up plane (Pinocchio's joint placements)."""
    model, data = chain.model, chain.data()
    pin.forwardKinematics(model, data, q)
    hip, knee = data.oMi[2].translation, data.oMi[3].translation
    foot = tool_positions(chain, q[None])[0]
    u = lambda p: float(p @ forward)  # noqa: E731
    x_line = u(hip) + (u(foot) - u(hip)) * (knee[2] - hip[2]) / (foot[2] - hip[2])
    return u(knee) < x_line


def check_step(robot: Robot | LeggedRobot, leg: str | None, run: Any, *,
               fraction: float = 0.7, knee_behind: bool = True) -> np.ndarray:
    """The physical checks of the module docstring on a run's optimum; returns the foot's
    displacement (3,) m in the leg's base frame."""
    chain = swing_chain(robot, leg)
    forward = _forward(robot, leg)
    up = np.array([0.0, 0.0, 1.0])
    lateral = np.cross(up, forward)
    mo = run.best.motion
    feet = tool_positions(chain, mo.q)
    p0, p1 = feet[0], feet[-1]
    L = leg_length_of(chain)
    Q = np.random.default_rng(0).uniform(-np.pi, np.pi, (400, chain.nq))
    reach = max(np.linalg.norm(tool_positions(chain, q[None])[0] - _hip(chain, q)) for q in Q)
    assert 0.9 * L < reach <= L + 1e-9  # L: the stretched leg below the hip, none reaches further
    step = p1 - p0
    np.testing.assert_allclose(step, STEP * L * forward, atol=POS_TOL)  # a step along body x
    mid = 0.5 * (p0 + p1)  # the stance: under the hip's pitch joint, at the home lateral offset
    home = np.clip(chain.home, chain.q_min, chain.q_max)
    hip = _hip(chain, home)
    assert (mid - hip) @ forward == pytest.approx(0.0, abs=POS_TOL)
    home_side = float((tool_positions(chain, home[None])[0] - hip) @ lateral)
    side = math.copysign(min(abs(home_side), fraction * L * math.sqrt(0.5)), home_side)
    assert mid @ lateral == pytest.approx(hip @ lateral + side, abs=POS_TOL)  # ≤ 45° out
    assert np.linalg.norm(mid - hip) / L == pytest.approx(fraction, abs=1e-9)
    assert fraction in FRACTIONS and mid[2] < hip[2]
    if knee_behind:
        assert _knee_behind(chain, mo.q[0], forward) and _knee_behind(chain, mo.q[-1], forward)
    tol = run.spec.problem.ground_tolerance
    assert feet[:, 2].min() >= p0[2] - tol - 1e-9  # above the ground during the swing
    check_energy(chain, mo.t, mo.q, mo.qd, mo.qdd, mo.tau, run.best.metrics["energy_total"])
    if isinstance(robot, LeggedRobot):
        assert leg is not None and mo.legs == (leg,)
        np.testing.assert_allclose(mo.tool[[0, -1]] - robot.leg(leg).hip[:3, 3], [p0, p1],
                                   atol=POS_TOL)
    return step


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(MATRIX_ROBOTS))
def test_default_task_is_refused_up_front_or_a_feasible_step(
    name: str, robot_spec: SpecOf, built_robot: Any
) -> None:
    spec = {"robot": robot_spec(name), "problem": {"kind": "swing_energy"}}
    robot = built_robot(name)
    verdict = fit(robot, "swing_energy")
    if name in REFUSED:
        assert not verdict.accepted and verdict.field == REFUSED[name]
        assert refusal_message(spec) == verdict.message
        if verdict.field == "foot_start":  # an arm: no stance to step from
            assert "not a leg" in str(verdict.reason) and "foot_end" in str(verdict.reason)
        return
    assert verdict.accepted and verdict.task is not None
    leg = LEGS[name]
    task = prepare(spec).problem.task
    assert task is not None and task.params.leg == leg
    assert set(task.rules) == RULES | ({"leg"} if leg else set())
    assert task.params.exact_ends is True and task.params.tube == "shortest"
    r = legcore.run({**spec, **SHORT})
    assert r.feasible, r.best.violations
    check_step(robot, leg, r)


@pytest.mark.slow
def test_catalog_hexapod_steps_forward_along_its_y_axis() -> None:
    """The catalog hexapod walks along +y (``meta["forward"]``): its first front leg L1 yaws its
    foot along y from a stance 0.75 L from the hip (0.7 L is out of reach inside its joint
    limits: the fallback); the catalog quadruped's x-down legs are refused as the listing
    says."""
    hexapod = catalog.get("citedi_hexapod")
    r = legcore.run({"robot": "citedi_hexapod", "problem": {"kind": "swing_energy"}, **SHORT})
    assert r.feasible and r.task is not None and r.task.params.leg == "L1"
    assert "0.75 × L" in r.task.rules["q_start"]
    step = check_step(hexapod, "L1", r, fraction=0.75, knee_behind=False)
    assert step[1] == pytest.approx(0.5 * 0.095, abs=1e-6)  # L: femur 3.5 cm + tibia 6 cm
    quad = catalog.get("animatronic_quadruped")
    verdict = fit(quad, "swing_energy")
    assert not verdict.accepted and verdict.field == "robot"
    assert refusal_message({"robot": "animatronic_quadruped",
                            "problem": {"kind": "swing_energy"}}) == verdict.message


@pytest.mark.slow
def test_a_leg_mounted_sideways_steps_across_its_reach() -> None:
    """Seed 000's leg with a longer shank (0.16 m instead of 0.15: other kinematics, so not the
    paper's preset) reaches out along its base x at home, as a leg on the side of a hexapod
    (its masses alone changed, it would keep the paper's task): its derived step goes
    across that reach (+y), from a stance 45° below and out from the hip's pitch joint, and the
    run is feasible — the foot moves 0.5 L along y, ends at its start height, stays above the
    ground, and the energy is at least its gravity bound (Pinocchio)."""
    spec = catalog.get("calderon_leg").spec.model_dump(mode="json")
    heavier = {**spec, "joints": [*spec["joints"][:1], {**spec["joints"][1], "mass": 0.16},
                                  *spec["joints"][2:]]}
    assert fit(build_robot(heavier), "swing_energy").task.preset is not None  # the paper's task
    spec["joints"][2]["a"] = 0.16
    r = legcore.run({"robot": spec, "problem": {"kind": "swing_energy"}, **SHORT})
    assert r.feasible and r.task is not None and r.task.preset is None
    built = prepare({"robot": spec, "problem": {"kind": "swing_energy"}}).problem.robot
    L = leg_length_of(built)
    mo = r.best.motion
    feet = tool_positions(built, mo.q)
    np.testing.assert_allclose(feet[-1] - feet[0], [0.0, 0.5 * L, 0.0], atol=POS_TOL)
    hip = _hip(built, np.clip(built.home, built.q_min, built.q_max))
    mid = 0.5 * (feet[0] + feet[-1])
    out, down = mid[0] - hip[0], hip[2] - mid[2]
    assert out == pytest.approx(down, abs=POS_TOL) and out > 0.0  # 45° below and out
    assert feet[:, 2].min() >= feet[0, 2] - r.spec.problem.ground_tolerance - 1e-9
    check_energy(built, mo.t, mo.q, mo.qd, mo.qdd, mo.tau, r.best.metrics["energy_total"])


def test_the_coordinated_step_dips_and_says_by_how_much(robot_spec: SpecOf) -> None:
    """Why the search is centred on the shortest foot path: the joints' straight line between
    the derived ends dips the foot below the ground, and the violation says so in metres."""
    problem = prepare({"robot": robot_spec("go1"), "problem": {"kind": "swing_energy"}}).problem
    (v,) = problem.violations(problem.coordinated_x())
    assert v.constraint == "ground" and v.unit == "m" and 0.01 < v.amount < 0.03
    assert v.as_dict()["text"] == (f"the leg dips {v.amount + 0.001:.3g} m below the ground (z "
                                   f"= {problem.z_ground:.4g} m): {v.amount:.3g} m more than "
                                   "its 0.001 m tolerance")
    assert problem.violations(np.zeros(problem.n_var)) == ()  # the shortest path: the free start
    assert problem.task is not None
    assert problem.task.rules["tube"].startswith("shortest: the coordinated motion (the joints' "
                                                 "straight line) dips 18.4 mm below the ground")


def test_given_values_are_used_as_given(robot_spec: SpecOf, built_robot: Any) -> None:
    """Solo12's hind-right leg, its foot starting where the user says: the end is derived one
    step ahead of it; neither the leg nor the start has a rule."""
    start = (-0.05, -0.0594, -0.24)
    spec = {"robot": robot_spec("solo12"),
            "problem": {"kind": "swing_energy", "leg": "HR", "foot_start": start,
                        "baselines": ["calderon2008_parabolic"]}}
    task = prepare(spec).problem.task
    assert task is not None and task.params.leg == "HR" and task.params.foot_start == start
    assert not {"leg", "foot_start", "q_start"} & set(task.rules)
    assert task.rules["q_end"].startswith("foot at (0.1116, -0.0594, -0.24) m, one step")
    r = legcore.run({**spec, **SHORT})
    assert r.feasible
    robot = built_robot("solo12")
    chain = swing_chain(robot, "HR")
    feet = tool_positions(chain, r.best.motion.q[[0, -1]])
    np.testing.assert_allclose(feet[0], start, atol=POS_TOL)
    np.testing.assert_allclose(feet[1] - feet[0], [STEP * leg_length_of(chain), 0.0, 0.0],
                               atol=POS_TOL)
    check_energy(chain, r.best.motion.t, r.best.motion.q, r.best.motion.qd,
                 r.best.motion.qdd, r.best.motion.tau, r.best.metrics["energy_total"])
