"""Issue 25 item 1 (arm part): every matrix robot × {``path_tracking``, ``path_placement``}
submitted with DEFAULT task settings (``{"robot": …, "problem": {"kind": K}}``) is either
refused up front — the listing's verdict (:func:`legcore.studies.fit.fit`) and the submission
(:func:`legcore.runner.prepare`) give the same message — or runs to a FEASIBLE optimum that
passes the physical checks of :mod:`tests.studies.checks` (the tool on the path to 1e-6 m by
Pinocchio FK, its orientation kept, joint limits, energy ≥ the gravity bound), and for the
tracking motion the joint speed, acceleration and torque limits also hold on a resampling at
10 × the optimiser's samples.

Every arm of ≥ 6 joints (UR5, Panda with its fingers locked, Kinova, Z1 with its gripper
locked) runs both kinds; the 5-joint SO-100 tracks a path and is refused a placement; the
legged robots and the single leg are refused both. Short budgets: the whole file takes about
half a minute on one core with warm numba caches.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import legcore
from legcore.robots import Robot
from legcore.runner import prepare
from legcore.studies.fit import fit
from legcore.studies.path_placement.problem import PathPlacementProblem
from legcore.studies.path_tracking.problem import PathTrackingProblem
from legcore.studies.registry import get_study
from tests.studies.checks import check_placement, check_tracking
from tests.studies.conftest import MATRIX_ROBOTS, refusal_message

SpecOf = Callable[[str], dict[str, Any]]

ARM_KINDS = ("path_tracking", "path_placement")
#: What must run feasibly (issue 25): every arm of ≥ 6 joints both kinds, SO-100 tracking.
MUST_RUN = {(arm, kind) for arm in ("ur5", "panda", "kinova", "z1") for kind in ARM_KINDS} | {
    ("so100", "path_tracking")}
SHORT = {
    "path_tracking": {"optimizer": {"kind": "nsga2", "params": {"pop_size": 30}},
                      "budget": {"generations": 15}},
    "path_placement": {"optimizer": {"kind": "hka", "params": {
        "n_samples": 12, "n_best": 4, "init": "survey", "survey_size": 27, "survey_best": 3,
        "penalty": 1000.0}}, "budget": {"generations": 3}},
}
DENSE = 10  # the tracking motion's limits are checked again on 10 × its samples


def _dense_limits(problem: PathTrackingProblem, x: np.ndarray) -> None:
    """The decoded motion resampled at ``DENSE`` × ``n_samples``: every joint inside its
    speed, acceleration and torque limits (the same task, the same joint path)."""
    params = problem.params.model_copy(update={"n_samples": DENSE * problem.n_samples})
    dense = PathTrackingProblem(problem.robot, params)
    sim = dense.simulate(np.asarray(x, dtype=float)[None, :])
    r = problem.robot
    for key, lim in (("qd", r.qd_max), ("qdd", problem.qdd_max), ("tau", r.tau_max)):
        peak = np.abs(sim[key][0]).max(axis=0)
        assert np.all(peak <= lim * (1.0 + 1e-9)), (key, peak / lim)


@pytest.mark.parametrize("kind", ARM_KINDS)
@pytest.mark.parametrize("name", list(MATRIX_ROBOTS))
def test_default_arm_task_is_refused_or_feasible(name: str, kind: str, robot_spec: SpecOf,
                                                 built_robot: Callable[[str], Any]) -> None:
    spec = {"robot": robot_spec(name), "problem": {"kind": kind}}
    verdict = fit(built_robot(name), kind)
    if not verdict.accepted:
        assert (name, kind) not in MUST_RUN, verdict.message
        assert refusal_message(spec) == verdict.message
        return
    assert (name, kind) in MUST_RUN
    assert verdict.task is not None and verdict.task.preset is None and verdict.task.rules
    run_spec = {**spec, **SHORT[kind], "seed": 1, "record": False}
    problem = prepare(run_spec).problem
    res = legcore.run(run_spec)
    assert res.feasible and res.best.violations == (), res.best.violations
    assert res.to_dict()["feasible"] is True
    if kind == "path_tracking":
        assert isinstance(problem, PathTrackingProblem)
        check_tracking(problem, res.best)
        _dense_limits(problem, np.asarray(res.best.x))
        seed = res.baselines["seed"]
        assert seed.feasible  # the % reference is feasible: the % changes are given
        check_tracking(problem, seed)
        assert res.extras["seed_feasible"] is True
        assert res.best.objectives["time"] < seed.objectives["time"]
        assert all(row["time_change_pct"] is not None for row in res.extras["front"])
        if "seed_max_V" in res.baselines:
            assert res.baselines["seed_max_V"].feasible
        # issue 19: the physical minimum (TOPP-RA) of every arm's path, feasible, below ours
        physical = problem.time_optimal
        assert physical is not None and res.baselines["time_optimal"].feasible
        check_tracking(problem, res.baselines["time_optimal"], physical.law)
        assert physical.T <= res.best.objectives["time"]
        assert res.gap is not None and res.gap["pct"] >= 0.0
    else:
        assert isinstance(problem, PathPlacementProblem)
        check_placement(problem, res.best)
        original = res.baselines["original"]
        assert original.feasible  # the % reference: reachable, every constraint held
        check_placement(problem, original)
        assert math.isfinite(res.best.metrics["energy_change_pct"])
        assert res.best.objectives["J"] <= original.objectives["J"] + 1e-12


def test_derived_tasks_are_relative_to_the_arm(built_robot: Callable[[str], Any]) -> None:
    """The derived numbers scale with the arm: the capsule is 0.4 × the reach across (the seed
    0.6 m on its 1 m arm), the placement's pan radius 0.08 m × reach / the PUMA's; the path's
    plane passes through the tool of a posture inside the arm's reach; the nominal power is
    Σ τ_max q̇_max."""
    from legcore.studies.arm_workspace import arm_workspace
    from legcore.studies.path_placement.defaults import puma560_reach

    for name in ("ur5", "so100"):
        robot = built_robot(name)
        assert isinstance(robot, Robot)
        ws = arm_workspace(robot)
        p = fit(robot, "path_tracking").task.params  # type: ignore[union-attr]
        across = p.segments[0].center[0] - p.segments[2].center[0] + 2 * p.segments[0].r
        assert across == pytest.approx(round(0.4 * ws.reach, 3), rel=1e-12)
        assert np.linalg.norm(np.subtract(p.plane_origin, ws.shoulder)) < ws.reach
    ur5 = built_robot("ur5")
    pp = fit(ur5, "path_placement").task.params  # type: ignore[union-attr]
    assert pp.nominal_power_kw == pytest.approx(
        float(np.sum(ur5.tau_max * ur5.qd_max)) / 1000.0, rel=1e-3)
    assert pp.path_scale == pytest.approx(arm_workspace(ur5).reach / puma560_reach(), rel=2e-3)


def test_violations_say_what_with_units(built_robot: Callable[[str], Any]) -> None:
    """An infeasible candidate is reported with which constraint, by how much, in its units:
    a time law far too fast for the UR5's joints; a placement out of the UR5's reach (% of the
    path unreachable) — and against an infeasible original no % change is given (NaN, with
    the reason)."""
    ur5 = built_robot("ur5")
    tr = get_study("path_tracking").build(ur5, None)
    x = tr.xu.copy()
    x[tr.n_seg:] = tr.xl[tr.n_seg:]  # top speeds, the shortest ramps
    v = tr.violations(x)
    assert v and any(u.unit == "rad/s²" and u.text.startswith("joint ") for u in v)
    assert all(u.amount > 0.0 for u in v)
    params = fit(ur5, "path_placement").task.params  # type: ignore[union-attr]
    far = params.model_copy(update={"original": (3.0, 0.0, 0.0)})
    pl = PathPlacementProblem(ur5, far)
    broken = pl.violations(pl.x_original)
    assert broken[0].constraint == "unreachable" and broken[0].unit == "%"
    assert broken[0].amount == pytest.approx(100.0)
    sol = pl.solution(np.asarray(params.original))
    assert math.isnan(sol.metrics["energy_change_pct"])
    assert "(the original placement) is infeasible" in sol.extra["change_pct_reason"]
