"""Seed 001 ``path_placement``: workspace (eqs 1–5), paths, cost (eq 15), constraints, HKA runs.

"Must show": on both built-in paths with the PUMA 560, HKA cuts the electrical energy by at least
30 % and raises the mean manipulability against the original placement with all 13 constraints
satisfied; the convergence history is non-empty and improving; plain vs modified initialisation
over several seeds are both reported. Here: workspace, paths, cost and constraints on the
catalog's PUMA 560; the HKA runs and other arms: ``test_path_placement_any_arm.py``.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np
import pytest

from legcore.energy import electrical_energy
from legcore.jobspec import parse_job_spec
from legcore.kinematics import fk
from legcore.manipulability import manipulability, manipulability_split
from legcore.runner import run
from legcore.studies.path_placement.paths import (
    JAR_DURATION,
    PAN_DURATION,
    jar_path,
    pan_path,
    parse_path_csv,
    rpy_to_matrix,
)
from legcore.studies.path_placement.problem import (
    CONSTRAINT_NAMES,
    Params,
    max_manipulability,
    simplified_workspace,
)
from legcore.studies.path_placement.study import build


@pytest.fixture(scope="module")
def jar(robot: Any) -> Any:
    return build(robot, Params(path="jar"))


# ------------------------------------------------------------------------------ workspace


def test_simplified_workspace_matches_the_dh_geometry(robot: Any) -> None:
    ws = simplified_workspace(robot)
    j = robot.spec.joints
    a2, a3, d4, d1 = j[1].a, j[2].a, j[3].d, j[0].d
    L3, psi = math.hypot(a3, d4), math.atan2(d4, a3)

    def reach(q3: float) -> float:  # shoulder–wrist distance in the arm plane
        beta = q3 + psi
        return math.sqrt(a2**2 + L3**2 + 2 * a2 * L3 * math.cos(beta))

    # eq 1 at the stretched elbow θ3 = (θ3S + θ3I)/2 = −90°, eq 2 at θ3 = θ3S = 45°
    assert ws.R_max == pytest.approx(reach(-math.pi / 2), abs=1e-12)
    assert ws.R_min == pytest.approx(reach(math.radians(45.0)), abs=1e-12)
    assert ws.R_max == pytest.approx(0.86384, abs=1e-5)
    assert ws.R_min == pytest.approx(0.34933, abs=1e-5)
    # eq 3 at θ2 = −45° (the stretched arm pointing lowest in front of the robot)
    t2, t23 = -math.pi / 4, -3 * math.pi / 4
    X = a2 * math.cos(t2) + a3 * math.cos(t23) - d4 * math.sin(t23)
    assert ws.gamma_low == pytest.approx(math.acos(X / ws.R_max), abs=1e-12)
    assert ws.gamma_up == -math.pi / 2
    assert (ws.phi_low, ws.phi_up) == pytest.approx((-math.radians(160), math.radians(160)))
    assert ws.origin == pytest.approx([0.0, 0.0, d1])
    # eq 5 and its inverse
    x = np.array([[0.6, 0.3, -1.0], [0.4, -1.2, 2.5]])
    p = ws.point(x)
    assert p[:, 2] == pytest.approx(-x[:, 0] * np.sin(x[:, 1]) + d1)
    assert np.hypot(p[:, 0], p[:, 1]) == pytest.approx(x[:, 0] * np.cos(x[:, 1]))
    assert ws.coords(p) == pytest.approx(x)


def test_max_manipulability_is_the_joint_space_maximum(robot: Any) -> None:
    w_M, q = max_manipulability(robot)
    assert w_M == pytest.approx(0.124158, abs=1e-5)
    # eq 6 = Yoshikawa's |det J| of the full arm at that configuration
    assert manipulability(robot, q) == pytest.approx(w_M, rel=1e-9)
    rng = np.random.default_rng(0)
    qs = robot.q_min + rng.random((20000, 6)) * (robot.q_max - robot.q_min)
    assert manipulability_split(robot, qs)[0].max() <= w_M + 1e-12


# ------------------------------------------------------------------------------ paths


def test_builtin_paths_have_the_papers_points_and_times() -> None:
    p, j = pan_path(), jar_path()
    assert (p.n_points, j.n_points) == (225, 413)
    assert p.duration == pytest.approx(PAN_DURATION) and j.duration == pytest.approx(JAR_DURATION)
    assert p.p[0] == pytest.approx(p.p[-1])  # closed seam
    # pan: every point on the r = 0.08 m circle, torch 10° off the vertical
    r = np.linalg.norm(p.p[:, :2] - np.array([0.25, 0.0]), axis=1)
    assert r == pytest.approx(0.08) and p.p[:, 2] == pytest.approx(0.80)
    assert np.degrees(np.arccos(-p.T[:, 2, 2])) == pytest.approx(10.0)
    for path in (p, j):
        R = path.T[:, :3, :3]
        assert np.abs(R @ np.swapaxes(R, 1, 2) - np.eye(3)).max() < 1e-12
        v = np.linalg.norm(np.diff(path.p, axis=0), axis=1) / np.diff(path.t)
        assert v[0] < 0.1 * v.max() and v[-1] < 0.1 * v.max()  # from rest to rest


def test_csv_paths_rpy_matrix_and_validation() -> None:
    rng = np.random.default_rng(1)
    xyz = rng.random((5, 3))
    rpy = rng.uniform(-1, 1, (5, 3))
    R = rpy_to_matrix(rpy[:, 0], rpy[:, 1], rpy[:, 2])
    # R = Rz(yaw) Ry(pitch) Rx(roll)
    r0, p0, y0 = rpy[0]
    Rz = np.array([[math.cos(y0), -math.sin(y0), 0], [math.sin(y0), math.cos(y0), 0], [0, 0, 1]])
    Ry = np.array([[math.cos(p0), 0, math.sin(p0)], [0, 1, 0], [-math.sin(p0), 0, math.cos(p0)]])
    Rx = np.array([[1, 0, 0], [0, math.cos(r0), -math.sin(r0)], [0, math.sin(r0), math.cos(r0)]])
    assert R[0] == pytest.approx(Rz @ Ry @ Rx)
    text_rpy = "\n".join(",".join(f"{v:.17g}" for v in row) for row in np.hstack([xyz, rpy]))
    text_rot = "# rotation matrices\n" + "\n".join(
        ",".join(f"{v:.17g}" for v in row) for row in np.hstack([xyz, R.reshape(5, 9)]))
    a = parse_path_csv(text_rpy, duration=2.0)
    b = parse_path_csv(text_rot, duration=2.0)
    assert a.T == pytest.approx(b.T) and a.t == pytest.approx(np.linspace(0, 2, 5))
    header = "t, x, y, z, roll, pitch, yaw\n" + "\n".join(
        f"{0.1 * k}," + ",".join(f"{v:.17g}" for v in row)
        for k, row in enumerate(np.hstack([xyz, rpy])))
    assert parse_path_csv(header).t == pytest.approx(0.1 * np.arange(5))
    bad = {
        "0,0,0,0,0,0": "at least 2 points",
        "0,0,0,0,0\n1,1,1,0,0": "columns",
        "0,0,0,0,0,inf\n1,1,1,0,0,0": "non-finite",
        "0,0,0,0,0,x\n1,1,1,0,0,0": "non-numeric",
        "0,0,0,0,0,0\n1,1,1,0,0,0": "duration",
        "t,x,y,z,roll,pitch,yaw\n0,0,0,0,0,0,0\n0,1,1,1,0,0,0": "increasing",
        "0,0,0,2,0,0,0,1,0,0,0,1\n1,1,1,1,0,0,0,1,0,0,0,1": "rotation",
    }
    for text, reason in bad.items():
        with pytest.raises(ValueError, match=reason):
            parse_path_csv(text)
    with pytest.raises(ValueError, match="at most"):
        parse_path_csv("\n".join("0,0,0,0,0,0" for _ in range(5001)), duration=1.0)


def test_params_reject_bad_input_with_the_field_named() -> None:
    for bad, field in (
        ({"path": "csv"}, "csv"),
        ({"path": "pan", "csv": "0,0,0,0,0,0\n1,1,1,0,0,0"}, "csv"),
        ({"path": "csv", "csv": "1,2,3\n4,5,6"}, "csv"),
        ({"original": (0.0, 0.0, 0.0)}, "original"),
        ({"energy_weight": 1.5}, "energy_weight"),
        ({"nominal_power_kw": 0.0}, "nominal_power_kw"),
        ({"branch": "left"}, "branch"),
        ({"unknown": 1}, "unknown"),
    ):
        with pytest.raises(ValueError, match=field):
            parse_job_spec({"problem": {"kind": "path_placement", **bad}})
    with pytest.raises(ValueError, match="^robot: path_placement needs ≥ 6 actuated joints; "
                                         "robot articulated_5dof has 5$"):
        run({"robot": "articulated_5dof", "problem": {"kind": "path_placement"}})


# ------------------------------------------------------------------------------ evaluation


def test_evaluation_is_batched_and_matches_eq_15(robot: Any, pan: Any) -> None:
    assert pan.n_var == 3 and pan.n_constr == 13 == len(CONSTRAINT_NAMES)
    assert pan.xl == pytest.approx(simplified_workspace(robot).xl)
    rng = np.random.default_rng(2)
    X = pan.xl + rng.random((7, 3)) * (pan.xu - pan.xl)
    X[0] = pan.x_original
    F, G = pan.evaluate(X)
    assert F.shape == (7, 1) and G.shape == (7, 13)
    F1, G1 = pan.evaluate(X[3:4])
    assert F1 == pytest.approx(F[3:4], rel=1e-12) and G1 == pytest.approx(G[3:4], rel=1e-12)
    # eq 15 rebuilt from the decoded motion of the original placement
    s = pan.solution(pan.x_original)
    m = s.motion
    el = electrical_energy(m.qd, m.tau, m.t, robot)
    w = manipulability_split(robot, m.q)[0]
    T = m.t[-1]
    J = 0.5 * el.total / (400.0 * T) + 0.5 * (1.0 - w.mean() / pan.w_max)
    assert s.objectives["J"] == pytest.approx(J, rel=1e-9) == pytest.approx(F[0, 0], rel=1e-9)
    assert s.metrics["energy_J"] == pytest.approx(el.total, rel=1e-9)
    assert s.metrics["energy_kWh"] == pytest.approx(el.total / 3.6e6, rel=1e-9)
    assert m.energy[-1] == pytest.approx(el.total, rel=1e-9)
    # the IK branch reaches the placed path: FK of q is the target pose
    T_fk = fk(robot, m.q)
    assert np.abs(T_fk[:, :3, 3] - m.tool).max() < 1e-9
    placed = pan.placed_poses(pan.x_original)[0]
    assert np.abs(T_fk[:, :3, :3] - placed[:, :3, :3]).max() < 1e-9
    # constraints of a feasible placement: joint limits, speeds and power inside
    g = s.extra["constraints"]
    assert max(g.values()) <= 0.0 and s.metrics["feasible"] == 1.0
    assert np.all(np.abs(m.qd).max(axis=0) <= robot.qd_max)
    assert np.all(m.q >= robot.q_min) and np.all(m.q <= robot.q_max)


def test_unreachable_placements_are_penalised_not_crashing(pan: Any) -> None:
    X = np.array([[5.0, 0.0, 0.0], [1e-3, 0.0, 0.0], [pan.xu[0], pan.xl[1], pan.xl[2]]])
    F, G = pan.evaluate(X)
    assert np.all(np.isfinite(F)) and np.all(np.isfinite(G))
    assert np.all(G[:2, :6] >= 1.0)  # unreachable points violate the position constraints
    s = pan.solution(X[0])
    assert s.metrics["unreachable_fraction"] == 1.0 and s.metrics["feasible"] == 0.0
    json.dumps(s.summary(), allow_nan=False)


def test_fixed_branch_and_joint_limited_timing(robot: Any, pan: Any) -> None:
    x = pan.x_original
    best = pan.evaluate(x)
    branch = pan.solution(x).extra["branch"]
    other = build(robot, Params(path="pan", branch=branch))
    assert other.n_samples == pan.n_samples // 8
    assert other.evaluate(x)[0] == pytest.approx(best[0])
    # slowing down where a joint would exceed its speed limit: time grows, speeds stay inside
    slow = build(robot, Params(path="pan", timing="joint_limited", speed_fraction=0.3))
    s = slow.solution(x)
    assert s.metrics["time_s"] > PAN_DURATION * 1.5
    assert np.all(np.abs(s.motion.qd) <= 0.3 * robot.qd_max + 1e-12)
    # the centroid as the anchor: the placed path's centroid is p(x)
    cen = build(robot, Params(path="pan", anchor="centroid"))
    xc = np.array([0.6, 0.2, 1.0])
    assert cen.placed_poses(xc)[0, :, :3, 3].mean(axis=0) == pytest.approx(
        cen.workspace.point(xc))
    assert cen.x_original == pytest.approx(cen.workspace.coords(pan_path().p.mean(axis=0)))
    # the original against itself: no change
    for key in ("energy_change_pct", "manipulability_change_pct", "time_change_pct"):
        assert s.metrics[key] == pytest.approx(0.0, abs=1e-9)
