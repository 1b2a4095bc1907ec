"""path_tracking (seed 004): capsule on articulated_5dof, the seed's law, exact joint rates,
the evaluation and clear errors. Tool orientations, user paths, other arms:
``test_path_tracking_orientation.py``; optimised timing: ``test_path_tracking_optimum.py``."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from pydantic import ValidationError

import legcore
from legcore import kinematics
from legcore.ik.arm5 import arm5_geometry
from legcore.jobspec import parse_job_spec
from legcore.robots import catalog
from legcore.studies.path_tracking.kin import arm5_down_rates
from legcore.studies.path_tracking.problem import Params, PathTrackingProblem
from legcore.studies.path_tracking.study import STUDY
from legcore.studies.registry import get_study
from legcore.trajectories import capsule_path

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
SEED_T = (1.5 + math.pi, 4.0, math.pi, 5.5)  # seed 004 §V: 4.6416, 4, 3.1416, 5.5 s


@pytest.fixture(scope="module")
def arm():
    return catalog.get("articulated_5dof")


@pytest.fixture(scope="module")
def problem(arm) -> PathTrackingProblem:
    return STUDY.build(arm, Params())


@pytest.fixture(scope="module")
def seed(problem):
    return problem.solution(problem.seed_x(), "linear")


def test_defaults_are_the_seed(arm, problem):
    """On seed 004's own arm the preset fills every robot-relative field with the paper's
    values (Params leaves them None: derived from any other robot)."""
    assert Params().plane_origin is None and Params().V is None
    task = STUDY.task(arm, Params())
    p = task.params
    assert (p.V, p.t_a, p.t_d) == (0.10, 3.0, 3.0)
    assert p.plane_origin == (0.0, 0.0, 0.50)
    assert p.V_bounds == (0.01, 1.0) and p.ramp_bounds == (0.005, 5.0)
    assert p.orientation == "down" and p.rest is None and p.limit_check == 1
    assert task.preset is not None and "seed 004" in task.preset and task.rules == {}
    assert STUDY.preset is not None and STUDY.preset.robot == STUDY.default_robot
    ref = capsule_path()
    np.testing.assert_allclose(problem.path.lengths, ref.lengths, rtol=1e-15)
    sig = np.linspace(0.0, problem.path.length, 101)
    np.testing.assert_allclose(problem.path.joins, ref.evaluate(ref.t_breaks).p, atol=1e-15)
    assert problem.path.derivatives(sig).shape == (4, 101, 3)
    assert get_study("path_tracking") is STUDY
    assert STUDY.default_robot == "articulated_5dof" and STUDY.seed_paper == "004"
    assert problem.variable_names == ("V_1", "V_2", "V_3", "V_4", "t_a", "t_d", "t_b")


def test_acceleration_limits_default_to_the_robots(arm):
    """qdd_max "robot" (the default): the robot's own limits, 5 rad/s² (assumed) where it
    gives none — the seed arm gives none, so the seed's 5 rad/s² everywhere."""
    assert Params().qdd_max == "robot"
    np.testing.assert_array_equal(STUDY.build(arm, Params()).qdd_max, 5.0)
    limited = dataclasses.replace(arm, qdd_max=np.array([1.0, 2.0, np.inf, np.inf, 3.0]))
    np.testing.assert_array_equal(STUDY.build(limited, Params()).qdd_max, [1.0, 2.0, 5.0, 5.0, 3.0])
    np.testing.assert_array_equal(STUDY.build(limited, Params(qdd_max=7.0)).qdd_max, 7.0)
    assert np.all(np.isinf(STUDY.build(limited, Params(qdd_max=None)).qdd_max))


def test_speed_box_cuts_off_only_infeasible_speeds(problem):
    """Each cruise speed's upper bound: the fastest speed at which the joint speed limits hold
    at some point of its segment (+1 %). On the bottom line joint 1 limits it most loosely at
    the line's ends: 0.283 m from the base axis, the tool moving at 45° to the radius, so
    q̇1 = V sin 45° / 0.283 m ≤ 1.5 rad/s → V ≤ 0.60 m/s (0.30 m/s in the middle)."""
    cap = problem.V_max
    assert cap.shape == (4,) and np.all(cap <= 1.0)
    assert cap[3] == pytest.approx(1.01 * 1.5 * math.hypot(0.2, 0.2) / math.sin(math.pi / 4),
                                   rel=1e-6)
    x = problem.seed_x()
    x[3] = 1.02 * cap[3]  # faster than the cap on the bottom line: breaks joint 1's limit
    G = problem.evaluate(x)[1][0]
    assert G[problem.constraint_names.index("qd_max.q1")] > 0.0


def test_seed_segment_times_and_profiles(seed):
    m = seed.metrics
    got = [m[f"T_{k}"] for k in range(1, 5)]
    np.testing.assert_allclose(got, SEED_T, atol=1e-9)
    assert got == pytest.approx([4.6416, 4.0, 3.1416, 5.5], abs=1e-4)  # as printed
    assert m["time"] == pytest.approx(11.0 + 2.0 * math.pi, abs=1e-12)  # 17.2832 s
    assert m["tool_speed_max"] == pytest.approx(0.10, abs=1e-12)
    assert seed.extra["segment_profiles"] == [
        "accel + constant", "constant", "constant", "constant + decel"
    ]
    assert m["feasible"] == 1.0


def test_seed_normalised_laws_eqs_50_to_53(problem):
    """s1 = 0.0531 t² | 0.3183 t − 0.4775 (eq 50), s2 = t/4 (51), s3 = t/3.1416 (52),
    s4 = 0.25 t | −0.0417 t² + 0.4583 t − 0.2604 (53): the printed coefficients are the exact
    1/(6π), 1/π, 1.5/π, 1/24, 11/24, 25/96 rounded to 4 digits."""
    assert [round(c, 4) for c in (1 / (6 * math.pi), 1 / math.pi, 1.5 / math.pi)] == [
        0.0531, 0.3183, 0.4775]
    assert [round(c, 4) for c in (1 / 24, 11 / 24, 25 / 96)] == [0.0417, 0.4583, 0.2604]
    law = problem.time_law(problem.seed_x()[None, :], "linear")
    D = problem.path.lengths
    starts = np.concatenate([[0.0], np.cumsum(SEED_T)])
    sig0 = np.concatenate([[0.0], np.cumsum(D)])

    def s(k: int, tau: np.ndarray) -> np.ndarray:
        return (law.evaluate(starts[k] + tau[None, :])[0, 0] - sig0[k]) / D[k]

    t = np.linspace(0.0, SEED_T[0], 50)
    eq50 = np.where(t < 3.0, t**2 / (6 * math.pi), t / math.pi - 1.5 / math.pi)
    np.testing.assert_allclose(s(0, t), eq50, atol=1e-12)
    np.testing.assert_allclose(s(0, t), np.where(t < 3, 0.0531 * t**2, 0.3183 * t - 0.4775),
                               atol=5e-4)  # as printed (rounding: 0.5e-4 · 3²)
    t = np.linspace(0.0, 4.0, 20)
    np.testing.assert_allclose(s(1, t), t / 4.0, atol=1e-12)
    t = np.linspace(0.0, math.pi, 20)
    np.testing.assert_allclose(s(2, t), t / math.pi, atol=1e-12)
    t = np.linspace(0.0, 5.5, 50)
    eq53 = np.where(t < 2.5, 0.25 * t, -t**2 / 24 + 11 * t / 24 - 25 / 96)
    np.testing.assert_allclose(s(3, t), eq53, atol=1e-12)


def test_seed_motion_is_complete_and_on_the_capsule(arm, seed):
    mo = seed.motion
    K = mo.n_samples
    for name in ("qd", "qdd", "jerk", "tau", "power"):
        a = getattr(mo, name)
        assert a is not None and a.shape == (K, 5) and np.all(np.isfinite(a)), name
    assert mo.energy is not None and mo.tool is not None and mo.robot == "articulated_5dof"
    assert np.all(np.diff(mo.t) > 0.0) and mo.t[-1] == pytest.approx(17.283185307179586)
    # tool path = the capsule of legcore.trajectories, to 1e-9 m, on every sample
    ref = capsule_path().evaluate(mo.t)
    np.testing.assert_allclose(mo.tool, ref.p, atol=1e-9)
    # tool pointing down on every sample
    T = kinematics.fk(arm, mo.q)
    np.testing.assert_allclose(T[:, :3, 2], np.tile([0.0, 0.0, -1.0], (K, 1)), atol=1e-12)
    # energy: cumulative ∫Σ|τ q̇| dt ending at the objective; power = τ·q̇
    np.testing.assert_allclose(mo.power, mo.tau * mo.qd, rtol=1e-15)
    assert np.all(np.diff(mo.energy) >= 0.0)
    assert mo.energy[-1] == pytest.approx(seed.metrics["energy"], rel=1e-12)
    # our numbers for the seed's law (docs/studies.md (seed 004)): joint ranges, speeds
    q_deg = np.degrees([mo.q.min(axis=0), mo.q.max(axis=0)])
    np.testing.assert_allclose(q_deg[:, 0], [40.21, 139.79], atol=0.01)  # base (fig. 20)
    np.testing.assert_allclose(q_deg[:, 1], [74.60, 114.30], atol=0.01)  # shoulder (fig. 21)
    np.testing.assert_allclose(q_deg[:, 2], [-138.59, -102.25], atol=0.01)  # elbow (fig. 22)
    np.testing.assert_allclose(q_deg[:, 3], [24.30, 30.00], atol=0.01)  # pitch (fig. 23)
    assert np.abs(mo.qd[:, 0]).max() == pytest.approx(0.5, abs=1e-3)  # V / 0.20 m
    assert seed.metrics["energy"] == pytest.approx(14.16, abs=0.01)
    assert scene_ok(mo.scene)


def scene_ok(scene: dict) -> bool:
    return scene["targets"].shape == (5, 3) and scene["path"].shape[1] == 3


def test_joint_rates_equal_the_differentiated_closed_form(arm):
    """q̇, q̈, q⃛ of the interpolated joint path against the exact reference (seed 004's closed
    form differentiated, ``arm5_down_rates``), the Jacobian and finite differences."""
    pr = STUDY.build(arm, Params(n_samples=20_000, ramp="cubic"))
    x = np.array([0.45, 0.55, 0.5, 0.25, 0.4, 0.6, 0.5])
    sim = pr.simulate(x[None, :])
    t, q, qd, qdd, jerk = (sim[k][0] for k in ("t", "q", "qd", "qdd", "jerk"))
    ref = arm5_down_rates(arm5_geometry(arm.spec), q, sim["pd"][0], sim["pdd"][0], sim["pddd"][0])
    # quintic splines at 2 mm: q̇ to ~1e-8, q̈ to ~1e-6, q⃛ to ~1e-4 of their largest values
    for got, want, rel in zip((qd, qdd, jerk), ref, (1e-7, 1e-5, 1e-3), strict=True):
        np.testing.assert_allclose(got, want, atol=rel * np.abs(want).max())
    J = kinematics.jacobian(arm, q)
    v = np.einsum("kij,kj->ki", J, qd)
    np.testing.assert_allclose(v[:, :3], sim["pd"][0], atol=1e-8)  # tool velocity
    np.testing.assert_allclose(v[:, 3:5], 0.0, atol=1e-12)  # stays pointing down
    # finite differences inside pieces (the line/arc joins make q̈ jump)
    law = sim["law"]
    phase = law.phase_of(t[None, :])[0]
    seg = np.searchsorted(np.cumsum(pr.path.lengths)[:-1], pr.time_law(x).evaluate(
        t[None, :])[0, 0], side="right")
    same = (phase[1:-1] == phase[:-2]) & (phase[1:-1] == phase[2:])
    same &= (seg[1:-1] == seg[:-2]) & (seg[1:-1] == seg[2:])
    for lo, hi in ((q, qd), (qd, qdd), (qdd, jerk)):
        fd = np.gradient(lo, t, axis=0)[1:-1][same]
        scale = np.abs(hi).max()
        np.testing.assert_allclose(fd, hi[1:-1][same], atol=2e-4 * scale)


def test_bad_parameters_are_clear_errors(arm):
    line = {"type": "line", "start": (0.3, 0.2), "end": (0.3, 0.4)}
    gap = {"type": "line", "start": (0.3, 0.45), "end": (0.1, 0.45)}
    with pytest.raises(ValidationError, match=r"segments\.1: starts 0\.05 m away"):
        Params(segments=(line, gap))
    with pytest.raises(ValidationError, match="phi must be non-zero"):
        Params(segments=({"type": "arc", "center": (0, 0), "r": 0.1, "beta": 0, "phi": 0},))
    with pytest.raises(ValidationError, match="greater than 0"):
        Params(segments=({"type": "arc", "center": (0, 0), "r": -0.1, "beta": 0, "phi": 1},))
    with pytest.raises(ValidationError, match="V_bounds"):
        Params(V_bounds=(0.5, 0.1))
    with pytest.raises(ValidationError, match="plane_e1/plane_e2"):
        Params(plane_e2=(1.0, 1.0, 0.0))
    with pytest.raises(ValidationError, match="objective"):
        Params(objective="speed")
    with pytest.raises(ValueError, match=r"segments\.0: tool point .* out of reach"):
        STUDY.build(arm, Params(segments=({"type": "line", "start": (1.2, 0), "end": (1.3, 0)},)))
    with pytest.raises(ValueError, match=r"segments\.0: .* must jump 3\.14 rad to another IK"):
        STUDY.build(arm, Params(segments=({"type": "line", "start": (-0.2, 0), "end": (0.2, 0)},)))
    with pytest.raises(ValueError, match=r"segments\.0: .* out of reach of puma560"):
        STUDY.build(catalog.get("puma560"), Params.model_validate(STUDY.preset.params))
    with pytest.raises(ValueError, match="^robot: .*path_tracking.* needs a serial robot.* "
                                         "citedi_hexapod.* is legged"):
        legcore.run({"robot": "citedi_hexapod", "problem": {"kind": "path_tracking"}})
    with pytest.raises(ValueError, match="^robot: path_tracking needs ≥ 5 actuated joints; "
                                         "robot calderon_leg has 3$"):
        STUDY.build(catalog.get("calderon_leg"), Params())
    corner = ({"type": "line", "start": (0.3, 0.2), "end": (0.3, 0.4)},
              {"type": "line", "start": (0.3, 0.4), "end": (0.1, 0.4)})
    with pytest.raises(ValidationError, match=r"segments\.1: turns the path by 90°"):
        Params(segments=corner)
    with pytest.raises(ValidationError, match="tool_axis"):
        Params(orientation="axis")
    with pytest.raises(ValidationError, match="tool_yaw"):
        Params(orientation="free", tool_yaw=0.2)
    with pytest.raises(ValueError, match="^qdd_max: 2 values for the 5 joints"):
        STUDY.build(arm, Params(qdd_max=(1.0, 2.0)))
    with pytest.raises(ValueError, match="^rest: 3 values"):
        STUDY.build(arm, Params(rest=(0.0, 1.0, 2.0)))
    slow = {"type": "line", "start": (0.0, 0.02), "end": (0.2, 0.02)}
    with pytest.raises(ValueError, match=r"segments\.0: .* even at the slowest speed"):
        STUDY.build(arm, Params(segments=(slow,), V_bounds=(0.05, 1.0)))


def test_evaluate_is_vectorised_and_matches_the_decoded_solution(problem):
    rng = np.random.default_rng(4)
    X = rng.uniform(problem.xl, problem.xu, (6, problem.n_var))
    X[0] = [1.0, 1.0, 1.0, 1.0, 5.0, 5.0, 5.0]  # ramps far too long for the segments
    F, G = problem.evaluate(X)
    assert F.shape == (6, 1) and G.shape == (6, 16)
    assert np.all(np.isfinite(F)) and np.all(np.isfinite(G))
    assert G[0, problem.constraint_names.index("ramps_fit")] > 1.0  # reported, law repaired
    for i in (0, 3):
        Fi, Gi = problem.evaluate(X[i])
        np.testing.assert_allclose(Fi[0], F[i], rtol=1e-12)
        np.testing.assert_allclose(Gi[0], G[i], rtol=1e-12, atol=1e-12)
        sol = problem.solution(X[i])
        assert sol.objectives["time"] == pytest.approx(F[i, 0], rel=1e-12)
        got = [sol.extra["constraints"][n] for n in problem.constraint_names]
        np.testing.assert_allclose(got, G[i], rtol=1e-12, atol=1e-12)


def test_examples_load_and_name_this_study():
    files = sorted(EXAMPLES.glob("004_path_tracking*.yaml"))
    assert files, "examples/004_path_tracking*.yaml missing"
    for f in files:
        spec = parse_job_spec(yaml.safe_load(f.read_text()))
        assert spec.problem.kind == "path_tracking"
