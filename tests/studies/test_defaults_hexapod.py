"""Issue 25, ``hexapod_workspace`` with DEFAULT task settings on robots that are not seed 002's:
a verdict up front, and a feasible answer whose physics holds.

- Every matrix robot (:data:`tests.studies.conftest.MATRIX_ROBOTS`: arms, one leg, quadrupeds —
  none has six legs) is refused up front, and ``legcore.studies.fit.fit`` (every listing) says
  exactly what ``legcore.runner.prepare`` (the submission) raises.
- Two URDF hexapods written by ``hexapod_urdf`` (``legs: auto``, numerical FK/IK): a medium one
  (3 / 8 / 12 cm legs on a 16 × 20 cm body) and the same ×5; and the parametric hexapod
  (``problem.hexapod``, closed-form legs) of the medium geometry. Each runs with
  ``{"problem": {"kind": "hexapod_workspace"}}`` (a short MOEA/D) to a feasible optimum whose
  motions keep the stance feet put (Pinocchio FK, 1e-6 m) and whose claimed stability holds
  (body pose inside the fixed feet's triangle) — :func:`tests.studies.checks.check_hexapod`.
- The derived values are the robot's: the stance foot is 45° below its hip (Pinocchio FK), the
  ×5 robot has the same angles and five times the lengths, and the DH and URDF forms of one
  robot get the same task. A task that cannot stand is refused naming the field.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from functools import cache
from typing import Any

import numpy as np
import pytest

import legcore
from legcore.runner import RunResult, prepare
from legcore.studies.fit import fit
from legcore.studies.hexapod_workspace.robot import HexapodGeometry, hexapod_urdf
from tests.studies.checks import check_hexapod
from tests.studies.conftest import MATRIX_ROBOTS
from tests.studies.physics import tool_positions

KIND = "hexapod_workspace"
#: A medium hexapod: 3 / 8 / 12 cm legs, hips 8 cm out and 10 cm apart (seed 002's frame).
MEDIUM: dict[str, Any] = {
    "link_lengths": (0.03, 0.08, 0.12),
    "hips": {"L1": (0.08, 0.1, 0.0), "L2": (0.08, 0.0, 0.0), "L3": (0.08, -0.1, 0.0),
             "L4": (-0.08, 0.1, math.pi), "L5": (-0.08, 0.0, math.pi),
             "L6": (-0.08, -0.1, math.pi)},
    "body_size": (0.16, 0.2, 0.04),
    "body_mass": 1.5,
}
#: A short MOEA/D (the task settings stay the defaults).
SHORT = {"optimizer": {"kind": "moead", "params": {"n_subproblems": 40}},
         "budget": {"generations": 10}, "seed": 1, "record": False}


def geometry(scale: float = 1.0) -> HexapodGeometry:
    """The medium hexapod with every length × ``scale`` (masses × scale³)."""
    return HexapodGeometry(
        link_lengths=tuple(scale * v for v in MEDIUM["link_lengths"]),
        hips={k: (scale * x, scale * y, yaw) for k, (x, y, yaw) in MEDIUM["hips"].items()},
        body_size=tuple(scale * v for v in MEDIUM["body_size"]),
        link_masses=(0.010 * scale**3, 0.012 * scale**3, 0.008 * scale**3),
        body_mass=MEDIUM["body_mass"] * scale**3,
    )


def urdf_spec(scale: float) -> dict[str, Any]:
    return {"robot": {"kind": "urdf", "name": f"hexapod_x{scale:g}", "legs": "auto",
                      "urdf": hexapod_urdf(geometry(scale))},
            "problem": {"kind": KIND}}


def parametric_spec() -> dict[str, Any]:
    return {"problem": {"kind": KIND, "hexapod": json.loads(geometry().model_dump_json())}}


SPECS: dict[str, Callable[[], dict[str, Any]]] = {
    "urdf_x1": lambda: urdf_spec(1.0),
    "urdf_x5": lambda: urdf_spec(5.0),
    "parametric": parametric_spec,
}


@cache
def _run(name: str) -> tuple[RunResult, Any]:
    """The short default-task run of ``name`` and its prepared problem."""
    spec = {**SPECS[name](), **SHORT}
    return legcore.run(spec), prepare(spec).problem


# ------------------------------------------------------------------------------ refusals


@pytest.mark.parametrize("name", sorted(MATRIX_ROBOTS))
def test_matrix_robots_are_refused_up_front(
    name: str, robot_spec: Callable[[str], dict[str, Any]], built_robot: Callable[[str], Any]
) -> None:
    verdict = fit(built_robot(name), KIND)
    assert not verdict.accepted and verdict.field == "robot"
    assert ("needs a legged robot" in verdict.reason
            or "needs 6 legs of 3 joints" in verdict.reason), verdict.reason
    with pytest.raises(ValueError) as exc:
        prepare({"robot": robot_spec(name), "problem": {"kind": KIND}})
    assert str(exc.value) == verdict.message


def test_a_hexapod_that_cannot_stand_is_refused_by_field() -> None:
    """Pre-flight: a body thicker than the legs can lift, feet above the hips."""
    thick = geometry().model_copy(update={"body_size": (0.16, 0.2, 0.4)})
    spec = {"problem": {"kind": KIND, "hexapod": json.loads(thick.model_dump_json())}}
    with pytest.raises(ValueError, match=r"^theta2: .* below its hip, but the body is 0\.4 m "
                                         "high: it would rest on the ground"):
        prepare(spec)
    up = {**urdf_spec(1.0), "problem": {"kind": KIND, "theta2": 0.8, "theta3": 0.5}}
    with pytest.raises(ValueError, match=r"^theta2: at the stance posture the foot of leg L1 is -"):
        prepare(up)


# ------------------------------------------------------------------------------ derived values


def test_derived_task_is_the_robots() -> None:
    t1 = prepare({**urdf_spec(1.0), **SHORT}).problem.task
    t5 = prepare({**urdf_spec(5.0), **SHORT}).problem.task
    tp = prepare({**parametric_spec(), **SHORT}).problem.task
    assert t1.preset is None and set(t1.rules) >= {"theta2", "theta3", "theta1_min",
                                                   "pose_x_extent", "hv_ref_point"}
    p1, p5, pp = t1.params, t5.params, tp.params
    angles = ("theta1_min", "theta1_max", "theta2", "theta3", "pose_yaw_extent", "pose_yaw_step")
    lengths = ("pose_x_extent", "pose_y_extent", "pose_xy_step")
    for f in angles:  # scale-free, and the same for the DH and the URDF form of one robot
        assert getattr(p5, f) == getattr(p1, f) == getattr(pp, f), f
    for f in lengths:  # five times larger, to the rounding: the step to 2 digits, the extents
        assert getattr(pp, f) == getattr(p1, f), f  # to a whole number of steps
    assert p5.pose_xy_step == pytest.approx(5 * p1.pose_xy_step, rel=0.05)
    for f in ("pose_x_extent", "pose_y_extent"):
        assert abs(getattr(p5, f) - 5 * getattr(p1, f)) <= 1.01 * p5.pose_xy_step, f
    assert p5.hv_ref_point[2] == pytest.approx(5 * p1.hv_ref_point[2], rel=0.01)
    assert p1.stability == "constraint" and not p1.paper_baselines
    assert -math.pi / 6 <= p1.theta1_min < 0.0 < p1.theta1_max <= math.pi / 6


@pytest.mark.parametrize("scale", [1.0, 5.0])
def test_stance_foot_is_45_degrees_below_its_hip(scale: float) -> None:
    problem = prepare({**urdf_spec(scale), **SHORT}).problem
    q = problem.q_stance
    for k, leg in enumerate(problem.tripod.legs):
        foot = tool_positions(problem.robot.leg(leg).robot, q[k:k + 1])[0]  # hip frame
        out, below = float(np.hypot(foot[0], foot[1])), -float(foot[2])
        assert below == pytest.approx(out, rel=2e-3), (leg, out, below)
        # halfway between the 3 cm coxa (the tibia folded back at its limit) and the stretched
        # leg on that line: within the legs' reach, 0.136 m for the medium robot
        assert math.hypot(out, below) == pytest.approx(0.192 * scale, rel=5e-3)


# ------------------------------------------------------------------------------ runs


@pytest.mark.parametrize("name", sorted(SPECS))
def test_default_task_runs_to_a_feasible_physical_answer(name: str) -> None:
    r, problem = _run(name)
    doc = json.loads(json.dumps(r.to_dict(), allow_nan=False))
    assert r.feasible and doc["feasible"] is True and doc["violations"] == []
    assert doc["task"]["rules"]["theta2"].startswith(f"{problem.theta2:.4f} rad: foot 45°")
    # stability is a constraint: the whole front is stable, the knee point too
    split = r.extras["stability_split"]
    assert split["mode"] == "constraint" and split["n_unstable"] == 0 and split["n_front"] > 0
    assert r.best.metrics["stable"] == 1.0
    # the physics: stance feet put (Pinocchio FK, 1e-6 m), claimed stability inside the triangle
    checked = [check_hexapod(problem, sol) for sol in (r.best, *r.baselines.values())]
    assert set(r.baselines) == {"start", "straight_walk"} and all(checked)
    # the pose grid holds the workspace (the start pose in it, no reachable pose on its edge)
    pw = r.extras["pose_workspace"]
    i0 = len(pw["yaw"]) // 2
    assert not pw["touches_grid_edge"] and pw["masks"][i0][len(pw["y"]) // 2][len(pw["x"]) // 2]
    assert len(pw["x"]) <= 41 and len(pw["y"]) <= 41 and len(pw["yaw"]) == 13


def test_an_unstable_stance_is_reported_infeasible() -> None:
    """Feasible means statically stable, whatever ``stability`` says: with ``classify`` (the
    paper's post-hoc split, its preset) the optimiser may keep an unstable stance, and
    ``violations`` names it — so a run cannot claim feasible with one (``RunResult.feasible``
    and each baseline's ``feasible`` come from it)."""
    _, problem = _run("urdf_x1")
    X = np.random.default_rng(0).uniform(-1.2, 1.2, (400, 3))  # beyond the bounds: any stance
    S = problem.objectives(X)[1]
    ok = (S[:, 0] > 0) & (S[:, 1] > 0)
    assert (~ok).any() and ok.any()
    for x in X[~ok][:20]:
        v = problem.violations(x)
        assert v and {e.constraint for e in v} <= {"S_f", "S_b"}
        assert all(e.amount >= 0 and e.unit == "m" and "unstable" in e.text for e in v)
    assert all(problem.violations(x) == () for x in X[ok][:20])
    # seed 002's own run (its preset: classify): Table 2's solution b is the unstable one of
    # Fig. 9b, and the result says so
    r = legcore.run({"problem": {"kind": KIND, "pose_xy_step": 0.004}, **SHORT})
    b = r.baselines["paper_b"]
    assert b.metrics["stable"] == 0.0 and b.feasible is False
    assert [e.constraint for e in b.violations or ()] == ["S_f"]
    assert all(r.baselines[k].feasible for k in ("start", "paper_a", "paper_c", "paper_d"))
