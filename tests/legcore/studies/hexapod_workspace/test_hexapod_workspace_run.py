"""Seed 002 ``hexapod_workspace`` end to end: MOEA/D (N = 300, T = 20, 100 generations) with the
seed's settings, its stable / unstable split, the motion with the feet fixed, the mirrored
workspace and the exact body-pose workspace of the run, stability as a constraint, and (slow)
the hypervolume against pymoo's MOEA/D. The problem itself: ``test_hexapod_workspace.py``;
other hexapods: ``test_hexapod_workspace_any.py``."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

import legcore
from legcore.kinematics import fk
from legcore.optimizers import MaxGenerations, get_algorithm, minimize
from legcore.robots import catalog
from legcore.runner import RunResult
from legcore.studies.hexapod_workspace.geometry import mirror_front_back
from legcore.studies.hexapod_workspace.problem import (
    PAPER_TABLE2,
    Params,
)
from legcore.studies.hexapod_workspace.study import STUDY, build
from legcore.tripod_stability import tripod_stability

ROOT = Path(__file__).resolve().parents[4]
ROBOT = catalog.get("citedi_hexapod")


@pytest.fixture(scope="module")
def default_run() -> RunResult:
    # the seed's own settings: MOEA/D, N = 300, T = 20, 100 generations (~0.3 s + extras)
    return legcore.run({"problem": {"kind": "hexapod_workspace"}, "seed": 1})


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
