"""Seed 002 ``hexapod_workspace``: objectives (eqs 11–14), Table 2, stability split, mirrored
workspace, exact body-pose workspace, MOEA/D (N = 300, T = 20, 100 generations) end to end, and
the hypervolume against pymoo's MOEA/D."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from pydantic import ValidationError

import legcore
from legcore.gaits import tripod_stability
from legcore.jobspec import parse_job_spec
from legcore.kinematics import fk
from legcore.optimizers import MaxGenerations, get_algorithm, minimize
from legcore.robots import catalog
from legcore.runner import RunResult
from legcore.studies.hexapod_workspace.geometry import (
    fit_body_motion,
    mirror_front_back,
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

ROOT = Path(__file__).resolve().parents[3]
ROBOT = catalog.get("citedi_hexapod")


@pytest.fixture(scope="module")
def problem() -> HexapodWorkspaceProblem:
    return build(ROBOT, Params())


@pytest.fixture(scope="module")
def default_run() -> RunResult:
    # the seed's own settings: MOEA/D, N = 300, T = 20, 100 generations (~0.3 s + extras)
    return legcore.run({"problem": {"kind": "hexapod_workspace"}, "seed": 1})


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


# ------------------------------------------------------------------------------ end to end


def test_moead_300_20_100_end_to_end(default_run) -> None:  # type: ignore[no-untyped-def]
    r = default_run
    opt = r.optimizer
    assert opt["kind"] == "moead" and opt["n_gen"] == 100 and opt["n_evals"] == 300 * 100
    assert opt["params"]["n_subproblems"] == 300 and opt["params"]["n_neighbors"] == 20
    json.dumps(r.to_dict(), allow_nan=False)
    F = np.array([p["objectives"] for p in r.pareto])
    assert 50 <= F.shape[0] <= 300 and F.shape[1] == 3
    # the front is near-congruent: angle errors < 3°, perimeter error < 1 mm, and nearly all
    # points inside the HV box (1°, 1°, 1 mm)
    assert np.all(F < np.array([math.radians(3), math.radians(3), 1e-3]))
    ex = r.extras
    assert ex["hypervolume"]["n_points"] >= 0.9 * F.shape[0]
    assert ex["hypervolume"]["normalised"] > 0.98
    # best = knee point, decoded: its objectives are those of the front point
    best = r.best
    assert list(best.objectives) == list(STUDY.build(ROBOT, Params()).objective_names)
    assert min(np.abs(F - np.array(list(best.objectives.values()))).sum(axis=1)) < 1e-15
    assert set(r.baselines) >= {"paper_a", "paper_b", "paper_c", "paper_d"}
    decoded = build(ROBOT, Params()).decode(best.x)
    json.dumps(decoded, allow_nan=False)
    assert decoded["objectives"] == best.summary()["objectives"]


def test_stable_unstable_split(default_run, problem) -> None:  # type: ignore[no-untyped-def]
    ex = default_run.extras
    split, front = ex["stability_split"], ex["front"]
    assert split["mode"] == "classify"
    assert split["n_stable"] + split["n_unstable"] == split["n_front"] == front["n"]
    X = np.asarray(front["theta1"])
    feet = problem.feet(X)
    S_f, S_b = tripod_stability(feet[:, 0], feet[:, 2], feet[:, 1])
    expected = (S_f > 0) & (S_b > 0)
    np.testing.assert_array_equal(front["stable"], expected)
    assert split["n_stable"] == int(expected.sum())


def test_stability_as_constraint_keeps_only_stable_points() -> None:
    p = build(ROBOT, Params(stability="constraint"))
    assert p.n_constr == 2
    _, G = p.evaluate(np.array([PAPER_TABLE2["b"]["theta1"], PAPER_TABLE2["a"]["theta1"]]))
    assert G[0].max() > 0 and G[1].max() <= 0  # b infeasible (unstable), a feasible
    res = minimize(p, get_algorithm("moead", n_subproblems=100), MaxGenerations(20), seed=3)
    assert res.front_X.shape[0] > 0
    rep = p.front_report(res.front_X)
    assert rep["stable"].all()


def test_motion_keeps_the_feet_fixed(default_run, problem) -> None:  # type: ignore[no-untyped-def]
    best = default_run.best
    m = best.motion
    assert m is not None and best.metrics["motion_feet_fixed"] == 1.0
    assert m.q.shape == (51, 9) and m.joint_names[:3] == ("L1.q1", "L1.q2", "L1.q3")
    assert m.legs == ("L1", "L3", "L5")
    # IK round trip with an independent FK (numba DH chain of the leg robot) and the body poses
    body_T = np.asarray(m.scene["body_T"])
    for k, leg in enumerate(m.legs):
        T = fk(ROBOT.leg(leg).robot, m.q[:, 3 * k:3 * k + 3])
        p_world = body_T @ ROBOT.leg(leg).hip @ T
        np.testing.assert_allclose(p_world[:, :3, 3], np.broadcast_to(problem.feet_start[k],
                                                                      (m.n_samples, 3)), atol=1e-9)
    # ends at the fitted body pose, which is in the exact workspace
    np.testing.assert_allclose(m.tool[-1, :2], best.extra["body_pose"][:2], atol=1e-12)
    np.testing.assert_allclose(m.tool[0], 0.0, atol=1e-15)
    assert np.asarray(m.scene["support_polygon"]).shape == (3, 3)


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


def test_mirrored_full_workspace(default_run, problem) -> None:  # type: ignore[no-untyped-def]
    ws = default_run.extras["workspace"]
    front = np.asarray(ws["front"]["body_pose"])
    mirrored = np.asarray(ws["mirrored"]["body_pose"])
    # the front/back mirror of each solution moves the body to (x, -y, -yaw)
    np.testing.assert_allclose(mirrored, front * [1, -1, -1], atol=1e-12)
    np.testing.assert_allclose(ws["mirrored"]["theta1"],
                               mirror_front_back(np.asarray(ws["front"]["theta1"])), atol=0)
    full = np.asarray(ws["full"]["body_pose"])
    assert full.shape[0] == 2 * front.shape[0]
    # Fig. 8a (seed 1: the body only moves forward) completed to Fig. 8b: both ways along the
    # walking axis, symmetric
    assert front[:, 1].min() > 0
    assert full[:, 1].min() < 0  # symmetric to round-off (the mirror is evaluated, not negated)
    assert full[:, 1].min() == pytest.approx(-full[:, 1].max(), abs=1e-12)
    assert ws["full"]["y_range"] == [full[:, 1].min(), full[:, 1].max()]
    assert ws["other_tripod"]["legs"] == ["L4", "L6", "L2"]


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


def test_pose_workspace_of_the_study(default_run, problem) -> None:  # type: ignore[no-untyped-def]
    pw = default_run.extras["pose_workspace"]
    yaw = np.asarray(pw["yaw"])
    area = np.asarray(pw["area_m2"])
    i0 = int(np.argmin(np.abs(yaw)))
    assert area[i0] > 5e-4 and not pw["touches_grid_edge"]  # > 5 cm² at yaw 0
    np.testing.assert_allclose(area, area[::-1])  # front/back symmetry: A(yaw) = A(-yaw)
    # the start pose is in it with the start joint angles; 10 cm away is not
    nx = len(pw["x"])
    mask0 = pw["masks"][i0]
    assert mask0[len(pw["y"]) // 2][nx // 2] == "1"
    q, ok = problem.exact_ik(np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]))
    assert ok[0].all() and not ok[1].all()
    np.testing.assert_allclose(q[0], [[0, -math.pi / 8, -math.pi / 4]] * 3, atol=1e-12)
    # mask, area and count agree
    n = sum(row.count("1") for row in mask0)
    assert n == pw["n_reachable"][i0]
    assert area[i0] == pytest.approx(n * 1e-6)
    # every near-congruent front pose is inside the exact workspace
    assert pw["front_poses_reachable"] == default_run.extras["front"]["n"]


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


# ------------------------------------------------------------------------------ vs pymoo


@pytest.mark.slow
def test_moead_hypervolume_matches_pymoo_reduced() -> None:
    """Reduced form of benchmarks/bench_hexapod.py, like for like (issue 11): N = 105 (H = 13),
    30 generations, seeds 0-9, the same problem, weights, operators, neighbourhood and reference
    point; both fronts are the non-dominated part of the *final population* (ours with
    ``archive_size=0``: no external archive). The problem's true front is a single point, so the
    per-seed HV spread is large (HV/box sd ~0.10 ours, ~0.15 pymoo's); the honest check is a rank
    test, not a ratio of means: ours must not be significantly below pymoo's (one-sided
    Mann-Whitney U, p >= 0.05), and its mean not below pymoo's by more than one of pymoo's
    seed sd. 2026-11-27: ours 0.915 +- 0.102, pymoo 0.882 +- 0.150, two-sided
    p = 0.85. (Our archive, the earlier comparison, gave 0.955 +- 0.055: not like for like.)"""
    import sys

    from scipy.stats import mannwhitneyu

    from legcore.metrics import hypervolume

    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from bench_hexapod import REF, make_problem, run_pymoo
    finally:
        sys.path.pop(0)
    seeds, pop, gen = range(10), 100, 30
    ours, theirs = [], []
    for s in seeds:
        algo = get_algorithm("moead", n_subproblems=pop, n_neighbors=20, archive_size=0)
        res = minimize(make_problem(), algo, MaxGenerations(gen), seed=s)
        assert algo.pop_size == 105 and len(res.front_F) <= algo.pop_size
        ours.append(hypervolume(np.asarray(res.front_F), REF).value)
        theirs.append(hypervolume(run_pymoo("moead", s, pop, gen)[1], REF).value)
    p = mannwhitneyu(ours, theirs, alternative="less").pvalue
    assert p >= 0.05, (p, ours, theirs)
    assert np.mean(ours) >= np.mean(theirs) - np.std(theirs, ddof=1), (ours, theirs)
    # the speed is measured by benchmarks/bench_hexapod.py, not asserted here


# ------------------------------------------------------------------------------ any hexapod

GEOMETRY = {
    "link_lengths": (0.03, 0.08, 0.12),
    "hips": {"L1": (0.06, 0.1, 0.0), "L2": (0.08, 0.0, 0.0), "L3": (0.06, -0.1, 0.0),
             "L4": (-0.06, 0.1, math.pi), "L5": (-0.08, 0.0, math.pi),
             "L6": (-0.06, -0.1, math.pi)},
}
GRID = {"pose_x_extent": 0.06, "pose_y_extent": 0.06, "pose_xy_step": 0.004,
        "pose_yaw_step": math.pi / 18}


def test_parametric_defaults_are_the_seed_robot() -> None:
    from legcore.studies.hexapod_workspace.robot import HexapodGeometry

    p = build(ROBOT, Params(hexapod=HexapodGeometry()))
    ref = build(ROBOT, Params())
    X = np.random.default_rng(1).uniform(-0.5, 0.5, (20, 3))
    np.testing.assert_array_equal(p.evaluate(X)[0], ref.evaluate(X)[0])
    assert p.tripod.closed_form and p.robot.name == "parametric_hexapod"


def test_urdf_hexapod_numerical_path_equals_the_closed_form() -> None:
    """The same parametric hexapod as DH legs (leg3 closed forms) and as generated URDF text
    (x forward; numerical FK/IK): same tripod, objectives, motion and pose workspace."""
    from legcore.robots import build_any_robot
    from legcore.studies.hexapod_workspace.robot import (
        HexapodGeometry,
        hexapod_urdf,
        parametric_hexapod,
    )

    g = HexapodGeometry.model_validate(GEOMETRY)
    dh = build(parametric_hexapod(g), Params(**GRID))
    urdf = build(build_any_robot({"kind": "urdf", "name": "hx", "urdf": hexapod_urdf(g),
                                  "legs": "auto"}), Params(**GRID))
    assert dh.tripod.closed_form and not urdf.tripod.closed_form
    assert urdf.tripod.legs == ("L1", "L3", "L5") and urdf.symmetry == dh.symmetry
    np.testing.assert_allclose(urdf.feet_start, dh.feet_start, atol=1e-12)
    X = np.random.default_rng(0).uniform(-0.5, 0.5, (50, 3))
    np.testing.assert_allclose(urdf.evaluate(X)[0], dh.evaluate(X)[0], atol=1e-12)
    a, b = dh.pose_workspace(), urdf.pose_workspace()
    assert a.reachable.sum() > 100 and np.array_equal(a.reachable, b.reachable)
    np.testing.assert_allclose(b.q, a.q, atol=1e-6, equal_nan=True)
    sa, sb = dh.solution(X[3]), urdf.solution(X[3])
    for k in ("beta1", "perimeter", "S_f", "body_dx", "body_dyaw", "exact_reachable"):
        assert sb.metrics[k] == pytest.approx(sa.metrics[k], abs=1e-9), k
    np.testing.assert_allclose(sb.motion.q, sa.motion.q, atol=1e-6)


def test_urdf_hexapod_runs_and_others_are_refused_by_name() -> None:
    from legcore.studies.hexapod_workspace.robot import HexapodGeometry, hexapod_urdf

    text = hexapod_urdf(HexapodGeometry.model_validate(GEOMETRY))
    spec = {"robot": {"kind": "urdf", "name": "hx", "urdf": text, "legs": "auto"},
            "problem": {"kind": "hexapod_workspace", "paper_baselines": False, **GRID},
            "optimizer": {"kind": "moead", "params": {"n_subproblems": 30}},
            "budget": {"generations": 5}, "seed": 3}
    r = legcore.run(spec)
    json.dumps(r.to_dict(), allow_nan=False)
    assert set(r.baselines) == {"start", "straight_walk"}
    assert r.extras["pose_workspace"]["n_reachable"][len(r.extras["pose_workspace"]["yaw"]) // 2]
    from legcore.runner import prepare

    with pytest.raises(ValueError, match="^robot: hexapod_workspace needs 6 legs of 3 joints; "
                                         "robot animatronic_quadruped has 4 legs$"):
        prepare({"robot": "animatronic_quadruped", "problem": {"kind": "hexapod_workspace"}})
