"""Seed 002 ``hexapod_workspace``: objectives (eqs 11–14), Table 2, stability split, the
left/right mirror, exact body-pose workspace, errors and options. MOEA/D (N = 300, T = 20, 100
generations) end to end and the hypervolume against pymoo's MOEA/D:
``test_hexapod_workspace_run.py``; other hexapods: ``test_hexapod_workspace_any.py``."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from pydantic import ValidationError

import legcore
from legcore.jobspec import parse_job_spec
from legcore.kinematics import fk
from legcore.robots import catalog
from legcore.studies.hexapod_workspace.geometry import (
    fit_body_motion,
    mirror_left_right,
    pose_workspace,
    tripod_from_robot,
)
from legcore.studies.hexapod_workspace.problem import (
    HV_REF,
    PAPER_TABLE2,
    HexapodWorkspaceProblem,
    Params,
)
from legcore.studies.hexapod_workspace.study import STUDY, build
from legcore.studies.registry import get_study

ROOT = Path(__file__).resolve().parents[4]
ROBOT = catalog.get("citedi_hexapod")


def _angle(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Interior angle at a of triangle abc by the law of cosines (independent of legcore)."""
    ab, ac, bc = (np.linalg.norm(u[..., :2] - v[..., :2], axis=-1)
                  for u, v in ((a, b), (a, c), (b, c)))
    return np.arccos((ab**2 + ac**2 - bc**2) / (2 * ab * ac))


# ------------------------------------------------------------------------------ set-up / paper


def test_registered_with_the_seed_settings() -> None:
    study = get_study("hexapod_workspace")
    assert study is STUDY and study.seed_paper == "002" and study.robot_kinds == ("legged",)
    assert study.default_robot == "citedi_hexapod"
    assert study.default_optimizer == {"kind": "moead",
                                       "params": {"n_subproblems": 300, "n_neighbors": 20}}
    assert study.default_generations == 100
    # the paper's settings are its preset on its robot, not Params defaults (issue 25)
    assert Params().theta2 is None and Params().stability == "constraint"
    task = study.task(ROBOT, Params())
    p = task.params
    assert task.preset is not None and task.preset.startswith("seed 002")
    assert (p.theta1_min, p.theta1_max) == (-math.pi / 6, math.pi / 6)
    assert (p.theta2, p.theta3, p.theta1_start) == (-math.pi / 8, -math.pi / 4, (0.0, 0.0, 0.0))
    assert p.stability == "classify"  # the paper classifies after optimising (Fig. 9b)
    assert (p.pose_x_extent, p.pose_xy_step, p.pose_yaw_step) == (0.04, 0.001, math.pi / 36)
    assert p.hv_ref_point == HV_REF and p.paper_baselines


def test_start_stance(problem: HexapodWorkspaceProblem) -> None:
    assert problem.tripod.legs == ("L1", "L3", "L5")
    np.testing.assert_allclose(problem.feet_start[:, 2], -0.068827, atol=5e-7)  # z = −6.8827 cm
    R = 0.01 + 0.035 * math.cos(math.pi / 8) + 0.06 * math.cos(3 * math.pi / 8)
    np.testing.assert_allclose(problem.feet_start[:, :2],
                               [[0.035 + R, 0.05], [0.035 + R, -0.05], [-0.035 - R, 0.0]],
                               atol=1e-12)
    F, G = problem.evaluate(np.zeros(3))
    np.testing.assert_allclose(F, 0.0, atol=1e-15)
    assert G.shape == (1, 0)
    assert np.all(problem.S_start > 0)


def test_objectives_vectorised_and_by_hand(problem: HexapodWorkspaceProblem) -> None:
    rng = np.random.default_rng(0)
    X = rng.uniform(-math.pi / 6, math.pi / 6, (64, 3))
    F, _ = problem.evaluate(X)
    assert F.shape == (64, 3)
    rows = np.vstack([problem.evaluate(x)[0] for x in X])
    np.testing.assert_array_equal(F, rows)
    # independent: feet by eqs (5)-(7) and the hip layout, angles by the law of cosines
    R = 0.01 + 0.035 * math.cos(-math.pi / 8) + 0.06 * math.cos(-3 * math.pi / 8)
    hips = np.array([[0.035, 0.05, 0.0], [0.035, -0.05, 0.0], [-0.035, 0.0, math.pi]])

    def feet(th: np.ndarray) -> np.ndarray:
        a = th + hips[:, 2]
        return np.stack((hips[:, 0] + R * np.cos(a), hips[:, 1] + R * np.sin(a)), -1)

    P0, P = feet(np.zeros(3)), feet(X)
    per0 = sum(np.linalg.norm(P0[i] - P0[j]) for i, j in ((0, 1), (1, 2), (0, 2)))
    per = sum(np.linalg.norm(P[:, i] - P[:, j], axis=-1) for i, j in ((0, 1), (1, 2), (0, 2)))
    f1 = np.abs(_angle(P0[0], P0[1], P0[2]) - _angle(P[:, 0], P[:, 1], P[:, 2]))
    f2 = np.abs(_angle(P0[2], P0[0], P0[1]) - _angle(P[:, 2], P[:, 0], P[:, 1]))
    np.testing.assert_allclose(F, np.column_stack((f1, f2, np.abs(per - per0))), atol=1e-12)


def test_table2_feet_and_stability_split(problem: HexapodWorkspaceProblem) -> None:
    base = problem.baseline_solutions()
    assert set(base) == {"start", "straight_walk", "paper_a", "paper_b", "paper_c", "paper_d"}
    for key, row in PAPER_TABLE2.items():
        sol = base[f"paper_{key}"]
        feet = np.asarray(sol.extra["feet_t1_body"])
        # the 24 printed foot coordinates (cm, 3-4 significant digits) from their θ1
        np.testing.assert_allclose(feet[:, 0], np.array(row["x_cm"]) / 100, atol=1.2e-5)
        np.testing.assert_allclose(feet[:, 1], np.array(row["y_cm"]) / 100, atol=1.2e-5)
        assert sol.extra["paper"]["f"] == list(row["f"])
    # Fig. 9b: solution b puts the body centre outside the support triangle (S_f < 0)
    assert base["paper_b"].metrics["S_f"] < 0 and base["paper_b"].metrics["stable"] == 0.0
    for key in ("a", "c", "d"):
        assert base[f"paper_{key}"].metrics["stable"] == 1.0
    # the printed f's are not those of the printed feet (docs): a's perimeter changes by 1.8 cm
    assert base["paper_a"].objectives["f3_perimeter"] == pytest.approx(0.017971, abs=1e-5)
    assert base["start"].metrics["foot_slip_max"] == pytest.approx(0.0, abs=1e-15)
    # §3's straight walk (−Δθ1, −Δθ1, +Δθ1) moves the body forward; with θ2, θ3 fixed the
    # triangle narrows by 2R(1 − cos Δθ1): the feet slip (second order), exact IK fixes it
    sw = base["straight_walk"]
    assert sw.metrics["body_dy"] > 0.005 and abs(sw.metrics["body_dyaw"]) < 1e-12
    assert 1e-5 < sw.metrics["foot_slip_max"] < 1e-3 and sw.metrics["exact_reachable"] == 1.0
    # a, c, d need a 13° body yaw that the legs cannot reach with the feet fixed: their motion
    # falls back to the paper's (θ1 interpolated, θ2 and θ3 fixed) and says so
    a = base["paper_a"]
    assert a.metrics["exact_reachable"] == 0.0 and a.metrics["motion_feet_fixed"] == 0.0
    assert "theta2_exact_max_dev" not in a.metrics
    json.dumps(build(ROBOT, Params()).decode(a.x), allow_nan=False)  # strict JSON
    assert a.motion is not None
    np.testing.assert_allclose(a.motion.q[:, 1::3], -math.pi / 8)
    np.testing.assert_allclose(a.motion.q[-1, 0::3], PAPER_TABLE2["a"]["theta1"])


def test_fit_body_motion_recovers_a_rigid_motion() -> None:
    rng = np.random.default_rng(1)
    P = rng.normal(size=(5, 3, 3)) * 0.1
    yaw = rng.uniform(-1, 1, 5)
    d = rng.normal(size=(5, 2)) * 0.02
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    # Q = body-frame feet after the body moved by (d, yaw): Q = R^T (P - d)
    dx, dy = P[..., 0] - d[:, :1], P[..., 1] - d[:, 1:]
    Q = np.stack((c * dx + s * dy, -s * dx + c * dy), -1)
    d_fit, yaw_fit, slip = fit_body_motion(P, Q)
    np.testing.assert_allclose(d_fit, d, atol=1e-12)
    np.testing.assert_allclose(yaw_fit, yaw, atol=1e-12)
    np.testing.assert_allclose(slip, 0.0, atol=1e-12)
    # a mirrored triangle is not a rigid motion: it must leave slip
    assert fit_body_motion(P, Q * np.array([1.0, -1.0]))[2].max() > 1e-3


# ------------------------------------------------------------------------------ mirrors


def test_left_right_mirror_is_the_other_tripod_with_equal_objectives(problem) -> None:  # type: ignore[no-untyped-def]
    p246 = build(ROBOT, Params(stance="246"))
    assert p246.tripod.legs == ("L4", "L6", "L2")
    X = np.random.default_rng(2).uniform(-0.5, 0.5, (40, 3))
    F, _ = problem.evaluate(X)
    F2, _ = p246.evaluate(mirror_left_right(X))
    np.testing.assert_allclose(F2, F, atol=1e-12)
    pose, _ = problem.body_motion(X)
    pose2, _ = p246.body_motion(mirror_left_right(X))
    np.testing.assert_allclose(pose2, pose * [-1, 1, -1], atol=1e-12)


# ------------------------------------------------------------------------------ exact workspace


def test_pose_workspace_by_construction_and_ik_round_trip() -> None:
    tri = tripod_from_robot(ROBOT, "135")
    # by construction: a body pose and joint angles inside the limits; feet = where they land
    pose = np.array([0.006, -0.004, math.radians(5.0)])
    q = np.array([[0.2, -0.5, -0.9], [-0.3, -0.3, -0.6], [0.1, -0.2, -1.0]])
    c, s = math.cos(pose[2]), math.sin(pose[2])
    body = np.array([[c, -s, 0, pose[0]], [s, c, 0, pose[1]], [0, 0, 1, 0], [0, 0, 0, 1]])
    feet = np.stack([(body @ ROBOT.leg(n).hip @ fk(ROBOT.leg(n).robot, q[k]))[:3, 3]
                     for k, n in enumerate(tri.legs)])
    x = np.arange(-20, 21) * 0.001
    yaw = np.radians(np.arange(-30, 31, 5.0))
    ws = pose_workspace(tri, feet, x, x, yaw)
    iy, ix, iyaw = 16, 26, 7  # y = -0.004, x = 0.006, yaw = 5°
    assert (x[ix], x[iy], yaw[iyaw]) == pytest.approx(tuple(pose))
    assert ws.reachable[iyaw, iy, ix]
    np.testing.assert_allclose(ws.q[iyaw, iy, ix], q, atol=1e-9)  # IK round trip
    # far away: out of reach
    far = pose_workspace(tri, feet, [0.2], [0.0], [0.0])
    assert not far.reachable.any()


# ------------------------------------------------------------------------------ errors, options


def test_clear_errors() -> None:
    with pytest.raises(ValidationError, match="theta1_min"):
        Params(theta1_min=0.3, theta1_max=0.1)
    with pytest.raises(ValidationError, match="extra"):
        parse_job_spec({"problem": {"kind": "hexapod_workspace", "bogus": 1}})
    with pytest.raises(ValueError, match="^theta1_max: 1.0000 rad is outside the coxa limits"):
        build(ROBOT, Params(theta1_max=1.0))
    with pytest.raises(ValueError, match="^theta3: -2.0000 rad is outside the joint limits"):
        build(ROBOT, Params(theta3=-2.0))
    with pytest.raises(ValueError, match="robot"):
        legcore.run({"robot": "puma560", "problem": {"kind": "hexapod_workspace"}})
    with pytest.raises(ValueError, match="robot"):
        build(catalog.get("animatronic_quadruped"), Params())
    with pytest.raises(ValidationError, match="pose_xy_step"):
        Params(pose_xy_step=1e-5, pose_x_extent=0.04, pose_y_extent=0.04, pose_yaw_extent=0.5,
               pose_yaw_step=0.1)
    # with the extents left to the robot, the same step is refused at the task, naming it
    with pytest.raises(ValueError, match="^pose_xy_step: 1e-05 m makes a pose grid of"):
        build(ROBOT, Params(pose_xy_step=1e-5))


def test_paper_formula_option_and_determinism() -> None:
    p = build(ROBOT, Params(triangle_formula="paper"))
    X = np.random.default_rng(4).uniform(-math.pi / 6, math.pi / 6, (200, 3))
    F, _ = p.evaluate(X)
    assert np.all(np.isfinite(F)) and np.allclose(p.evaluate(np.zeros(3))[0], 0.0)
    algo = {"kind": "moead", "params": {"n_subproblems": 50}}
    spec = {"problem": {"kind": "hexapod_workspace", "pose_xy_step": 0.004},
            "optimizer": algo, "seed": 7, "budget": {"generations": 10}}
    a, b = legcore.run(spec).to_dict(), legcore.run(spec).to_dict()
    assert a["pareto"] == b["pareto"] and a["best"] == b["best"]


def test_example_spec_loads_and_runs() -> None:
    path = ROOT / "examples" / "002_hexapod_workspace.yaml"
    data = yaml.safe_load(path.read_text())
    spec = parse_job_spec(data)
    assert spec.problem.kind == "hexapod_workspace" and spec.robot == "citedi_hexapod"
    assert spec.optimizer.kind == "moead" and spec.optimizer.params["n_subproblems"] == 300
    assert spec.optimizer.params["n_neighbors"] == 20 and spec.budget.generations == 100
    r = legcore.run(spec)
    json.dumps(r.to_dict(), allow_nan=False)
