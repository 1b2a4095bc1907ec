"""Regression (issue 9): a Solo12 leg from its URDF in ``swing_energy`` had its foot path and
ground constraint computed at the knee — a URDF leg's last link frame sits at its knee joint —
instead of at the foot (the leg's end frame, FL_FOOT)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from legcore.kinematics import fk
from legcore.robots import build_robot
from legcore.studies import swing_energy


def test_solo12_leg_swings_its_foot_not_its_knee(erd_urdf: Callable[[str], str]) -> None:
    spec = {"kind": "urdf", "name": "solo12", "urdf": erd_urdf("solo12"), "legs": "auto"}
    leg = build_robot({**spec, "leg": "FL"})
    problem = swing_energy.STUDY.build(leg, swing_energy.Params())
    sol = problem.solution(problem.coordinated_x())
    assert sol.motion is not None and sol.motion.tool is not None
    foot = fk(leg, sol.motion.q)[:, :3, 3]  # the FL_FOOT frame (see test_urdf_robots)
    np.testing.assert_allclose(sol.motion.tool, foot, atol=1e-12)
    np.testing.assert_allclose(foot[[0, -1]], [problem.foot_start, problem.foot_end], atol=1e-9)
    assert sol.metrics["lift_height"] == pytest.approx(foot[:, 2].max() - problem.z_ground)
    # the ground constraint holds at the foot: every candidate whose foot dips more than 1 mm
    # under the ground is infeasible
    rng = np.random.default_rng(0)
    X = rng.uniform(problem.xl, problem.xu, (100, problem.n_var))
    _, G = problem.evaluate(X)
    (q,) = problem.trajectories(X, (0,))
    z_foot = fk(leg, q)[..., 2, 3].min(axis=1)
    below = z_foot < problem.z_ground - 1e-3
    assert below.sum() > 10
    assert np.all(G[below, 0] > 0)
