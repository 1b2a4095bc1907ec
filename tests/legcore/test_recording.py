"""legcore.recording: run → time series to log (pure; no Rerun here)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from legcore import recording as R
from legcore.kinematics import fk, frames
from legcore.recording.helpers import _chain_scale
from legcore.robots import catalog
from legcore.studies.study import Box, Motion
from tests.recording_fixtures import arm_motion, fake_result

EXAMPLES = sorted((Path(__file__).resolve().parents[2] / "examples").glob("*.yaml"))


def hexapod_motion(K: int = 300) -> Motion:
    """Tripod legs L1, L3, L5 of the CITEDI hexapod with the body sliding along +y."""
    legs = ("L1", "L3", "L5")
    t = np.linspace(0.0, 1.0, K)
    th1 = 0.3 * np.sin(2 * np.pi * t)
    q1 = np.stack([th1, np.full(K, -np.pi / 8), np.full(K, -np.pi / 4)], axis=1)
    q = np.concatenate([q1, -q1 * [1, -1, -1], 0.5 * q1], axis=1)
    body = np.tile(np.eye(4), (K, 1, 1))
    body[:, 1, 3] = 0.02 * t
    return Motion(
        t=t,
        q=q,
        joint_names=tuple(f"{leg}.q{j + 1}" for leg in legs for j in range(3)),
        qd=np.gradient(q, t, axis=0),
        tool=body[:, :3, 3].copy(),
        robot="citedi_hexapod",
        legs=legs,
        scene={
            "body_T": body,
            "support_polygon": np.array([[0.1, 0.1, -0.07], [0.1, -0.1, -0.07], [-0.1, 0, -0.07]]),
            "feet": {"L1": np.zeros(3), "L3": np.ones(3), "L5": np.full(3, 2.0)},
            "ground_z": -0.07,
            "frame": "world = body frame at t",
        },
    )


def test_stride_indices_exact_count_and_endpoints() -> None:
    idx = R.stride_indices(100_000, 2000)
    assert idx.shape == (2000,)
    assert idx[0] == 0 and idx[-1] == 99_999
    assert np.all(np.diff(idx) > 0)
    assert np.array_equal(R.stride_indices(50, 2000), np.arange(50))
    with pytest.raises(ValueError, match="max_samples"):
        R.stride_indices(10, 1)


def test_minmax_indices_keeps_peaks_and_cap() -> None:
    K = 100_000
    y = np.sin(np.linspace(0, 20, K))
    y[12_345] = 50.0  # a spike a uniform stride would miss
    y[77_777] = -40.0
    idx = R.minmax_indices(y, 2000)
    assert idx.shape[0] <= 2000
    assert idx[0] == 0 and idx[-1] == K - 1
    assert np.all(np.diff(idx) > 0)
    assert 12_345 in idx and 77_777 in idx
    assert y[idx].max() == y.max() and y[idx].min() == y.min()
    assert np.array_equal(R.minmax_indices(y[:1500], 2000), np.arange(1500))


def test_entity_part_sanitises() -> None:
    assert R.entity_part("L1.q2") == "L1_q2"
    assert R.entity_part("θ") == "_"
    assert R.unique_parts(["a b", "a/b", "c"]) == ["a_b", "a_b_2", "c"]


# ---------------------------------------------------------------------------------------------
# one motion
# ---------------------------------------------------------------------------------------------


def test_record_motion_signals_downsampled_exact_samples() -> None:
    motion = arm_motion(K=5000)
    rec = R.record_motion(motion, max_samples=2000)
    for kind in ("q", "qd", "qdd", "jerk", "tau", "power", "energy"):
        for j in range(1, 6):
            s = rec.series_at(f"signals/{kind}/q{j}")
            assert s.timeline == "time"
            assert s.source_samples == 5000
            assert 1000 < s.n_samples <= 2000
    q2 = rec.series_at("signals/q/q2")
    k = np.searchsorted(motion.t, q2.index)
    assert np.array_equal(motion.t[k], q2.index)  # every kept value is an original sample
    assert np.array_equal(motion.q[k, 1], q2.values)
    total = rec.series_at("signals/energy/total")
    assert total.values[-1] == pytest.approx(motion.energy[-1])
    # per-joint cumulative ∫|P| dt adds up to the total here (energy built that way)
    last = sum(rec.series_at(f"signals/energy/q{j}").values[-1] for j in range(1, 6))
    assert last == pytest.approx(motion.energy[-1], rel=1e-12)


def test_record_motion_short_motion_keeps_every_sample() -> None:
    motion = arm_motion(K=300)
    rec = R.record_motion(motion)
    s = rec.series_at("signals/tau/q3")
    assert s.n_samples == 300 and np.array_equal(s.values, motion.tau[:, 2])


def test_record_motion_frames_links_and_tool_match_kinematics() -> None:
    robot = catalog.get("articulated_5dof")
    motion = arm_motion(K=3000)
    rec = R.record_motion(motion, robot, max_samples=500)
    poses = {p.path: p for p in rec.poses}
    idx = R.stride_indices(3000, 500)
    F = frames(robot, motion.q[idx])
    for k in range(robot.nq + 1):
        p = poses[f"world/robot/frames/{k}"]
        if p.t is None:  # the base does not move: logged once, static
            assert k == 0
            np.testing.assert_allclose(p.translation[0], F[0, 0, :3, 3], atol=1e-12)
            continue
        assert p.n_samples == 500 and p.source_samples == 3000
        np.testing.assert_array_equal(p.t, motion.t[idx])
        np.testing.assert_allclose(p.translation, F[:, k, :3, 3], atol=1e-12)
        np.testing.assert_allclose(p.rotation, F[:, k, :3, :3], atol=1e-12)
    # link k: a capsule in frame k from origin k-1 to origin k; static for a DH chain
    for k in range(1, robot.nq + 1):
        link = poses[f"world/robot/frames/{k}/link"]
        assert link.geometry == "capsule" and link.t is None
        frame = poses[f"world/robot/frames/{k}"]
        Rk = frame.rotation if frame.t is not None else frame.rotation[[0] * 500]
        pk = frame.translation if frame.t is not None else frame.translation[[0] * 500]
        start = np.einsum("nij,j->ni", Rk, link.translation[0]) + pk
        np.testing.assert_allclose(start, F[:, k - 1, :3, 3], atol=1e-12)
        end = link.translation[0] + link.length * link.rotation[0][:, 2]
        np.testing.assert_allclose(end, 0.0, atol=1e-12)
    assert poses["world/robot/frames/2/link"].length == pytest.approx(0.4)
    tool = next(p for p in rec.points if p.path == "world/robot/tool")
    np.testing.assert_allclose(tool.positions[:, 0], fk(robot, motion.q[idx])[:, :3, 3], atol=1e-12)
    path = next(p for p in rec.polylines if p.path == "world/path")
    assert path.points.shape == (500, 3) and path.source_samples == 3000
    assert R.link_radius(robot) == pytest.approx(0.035 * _chain_scale(robot))


def test_record_motion_tool_link_when_tool_is_offset() -> None:
    robot = catalog.get("puma560")  # tool 0.2 m beyond frame 6
    t = np.linspace(0, 1, 20)
    q = robot.home + 0.1 * np.outer(t, np.ones(6))
    motion = Motion(t=t, q=q, joint_names=tuple(f"j{i}" for i in range(6)), robot="puma560")
    rec = R.record_motion(motion)
    tool_link = next(p for p in rec.poses if p.path.endswith("/frames/6/tool_link"))
    T = fk(robot, q)
    F6 = frames(robot, q)[:, 6]
    assert tool_link.length == pytest.approx(np.linalg.norm(T[0, :3, 3] - F6[0, :3, 3]))
    assert tool_link.t is None  # rigidly attached to frame 6


def test_record_motion_scene_items() -> None:
    K = 200
    polys = np.full((K, 4, 3), np.nan)
    polys[:, :3] = [[0, 0, 0], [1, 0, 0], [0, 1, 0]]
    polys[K // 2 :, 3] = [1, 1, 0]  # a 4th vertex in the second half
    motion = arm_motion(
        K=K,
        targets=np.array([[0.5, 0, 0.5], [0.6, 0, 0.5]]),
        obstacles=[Box((0.3, 0.0, 0.5), (0.03, 0.02, 0.013))],
        support_polygon=polys,
        com=np.column_stack([np.linspace(0, 1, K), np.zeros(K), np.zeros(K)]),
        original_path=np.random.default_rng(1).random((40, 3)),
        target_approach=np.ones((K, 3)),  # directions: not drawn
        ground_z=0.0,
        note="text is ignored",
    )
    rec = R.record_motion(motion, max_samples=100)
    paths = set(rec.entity_paths())
    assert {
        "world/scene/targets",
        "world/scene/obstacles",
        "world/scene/support_polygon",
        "world/scene/com",
        "world/scene/original_path",
        "world/scene/ground",
    } <= paths
    assert "world/scene/target_approach" not in paths and "world/scene/note" not in paths
    box = next(b for b in rec.boxes if b.path == "world/scene/obstacles")
    np.testing.assert_array_equal(box.half_sizes, [[0.03, 0.02, 0.013]])
    track = rec.polyline_tracks[0]
    assert len(track.strips) == 100 and track.strips[0].shape == (4, 3)  # closed triangle
    assert track.strips[-1].shape == (5, 3)  # closed quad
    com = next(p for p in rec.points if p.path == "world/scene/com")
    assert com.positions.shape == (100, 1, 3)
    ground = next(b for b in rec.boxes if b.path == "world/scene/ground")
    assert ground.centers[0, 2] < 0.0 < ground.centers[0, 2] + 2 * ground.half_sizes[0, 2] + 1e-12
    assert rec.notes == []


def test_record_motion_legged_robot() -> None:
    robot = catalog.get("citedi_hexapod")
    motion = hexapod_motion(K=300)
    rec = R.record_motion(motion, max_samples=100)
    poses = {p.path: p for p in rec.poses}
    idx = R.stride_indices(300, 100)
    body = motion.scene["body_T"][idx]
    for n, leg in enumerate(("L1", "L3", "L5")):
        chain = robot.leg(leg)
        F = frames(chain.robot, motion.q[idx, 3 * n : 3 * n + 3])
        W = body[:, None] @ chain.hip @ F
        for k in (1, 3):
            np.testing.assert_allclose(
                poses[f"world/robot/{leg}/frames/{k}"].translation, W[:, k, :3, 3], atol=1e-12
            )
        assert f"world/robot/{leg}/frames/3/link" in poses
        foot = next(p for p in rec.polylines if p.path == f"world/robot/{leg}/foot_path")
        T = body @ chain.hip @ fk(chain.robot, motion.q[idx, 3 * n : 3 * n + 3])
        np.testing.assert_allclose(foot.points, T[:, :3, 3], atol=1e-12)
    assert "world/robot/L2/frames/1" not in poses  # legs not in the motion are not drawn
    b = poses["world/robot/body"]
    assert b.geometry == "box" and b.t is not None and b.n_samples == 100
    np.testing.assert_allclose(b.half_size, np.array(robot.body_size) / 2)
    assert "world/scene/feet" in rec.entity_paths()
    q = [s for s in rec.series if s.group == "signals/q"]  # the joints share their samples
    assert len(q) == 9 and all(np.array_equal(s.index, q[0].index) for s in q)
    assert 50 < rec.series_at("signals/q/L3_q1").n_samples <= 100
    const = rec.series_at("signals/q/L3_q2")  # a constant signal: one sample per bucket is enough
    assert const.n_samples <= 100 and np.all(const.values == motion.q[0, 4])


def test_record_motion_mismatched_robot_is_a_note_not_an_error() -> None:
    motion = arm_motion(K=50)
    rec = R.record_motion(motion, catalog.get("puma560"))
    assert any("nq = 6" in n for n in rec.notes)
    assert not rec.poses and rec.series


def test_record_motion_nan_configurations_are_held() -> None:
    motion = arm_motion(K=100)
    q = motion.q.copy()
    q[10:20] = np.nan  # e.g. unreachable IK samples
    m2 = Motion(t=motion.t, q=q, joint_names=motion.joint_names, robot=motion.robot)
    rec = R.record_motion(m2)
    assert any("NaN" in n for n in rec.notes)
    assert all(np.all(np.isfinite(p.translation)) for p in rec.poses)


# ---------------------------------------------------------------------------------------------
# one run
# ---------------------------------------------------------------------------------------------


def test_record_run_final_front_only_and_history() -> None:
    res = fake_result(
        arm_motion(K=400), m=3, generations=12, baselines={"parabolic": arm_motion(K=300)}
    )
    rec = R.record_run(res)
    assert rec.front is not None and rec.front.source == "final_only"
    assert list(rec.front.generations) == [12] and rec.front.dims == 3
    assert rec.front.points[0].shape == (50, 3)
    assert any("final front" in n for n in rec.notes)
    paths = {s.path: s for s in rec.optimization}
    assert paths["optimization/best/f2"].timeline == "generation"
    np.testing.assert_allclose(paths["optimization/best/f1"].values, 1.0 / np.arange(1, 13))
    assert {"optimization/ideal/f3", "optimization/nadir/f1", "optimization/front_size"} <= set(
        paths
    )
    assert rec.best_point is not None and rec.best_point.points[0].shape == (1, 3)
    base = rec.baselines["parabolic"]
    assert base.series_at("baselines/parabolic/signals/q/q1").n_samples == 300
    assert "world/baselines/parabolic/path" in base.entity_paths()
    assert not base.poses  # baselines: signals and path only
    assert rec.properties["front_source"] == "final_only"


def test_record_run_per_generation_fronts_capped() -> None:
    res = fake_result(None, m=2, generations=5)
    rng = np.random.default_rng(2)
    fronts = {g: rng.random((1000, 2)) for g in range(1, 6)}
    rec = R.record_run(res, fronts=fronts, max_front_points=300)
    assert rec.best is None
    f = rec.front
    assert f is not None and f.source == "per_generation" and f.dims == 2
    assert list(f.generations) == [1, 2, 3, 4, 5]
    assert all(p.shape == (300, 2) for p in f.points) and f.source_sizes == [1000] * 5
    # capped points are original front points, spread over the whole front
    assert f.points[0][:, 0].min() == fronts[1][:, 0].min()


def test_record_run_single_objective_has_no_front() -> None:
    res = fake_result(arm_motion(K=100), m=1, generations=4)
    rec = R.record_run(res)
    assert rec.front is None and rec.best_point is None
    assert [s.path for s in rec.optimization] == ["optimization/best/f1", "optimization/front_size"]


def test_record_run_size_budget() -> None:
    base = {f"b{i}": arm_motion(K=4000) for i in range(4)}
    res = fake_result(arm_motion(K=4000), m=2, generations=30, baselines=base)
    fronts = {g: np.random.default_rng(g).random((500, 2)) for g in range(1, 31)}
    # every signal of the baselines (by default only q and the total energy: see below)
    full = R.record_run(res, fronts=fronts, max_bytes=None, baseline_signals=None)
    assert R.estimate_bytes(full) == full.properties["estimated_bytes"]
    budget = int(0.6 * R.estimate_bytes(full))
    rec = R.record_run(res, fronts=fronts, max_bytes=budget, baseline_signals=None)
    assert R.estimate_bytes(rec) <= budget
    assert rec.properties["max_samples_baselines"] < 2000  # baselines lowered first
    assert rec.properties["max_samples_best"] == 2000
    assert rec.best is not None and rec.best.series_at("signals/q/q1").n_samples > 1000
    lean = R.record_run(res, fronts=fronts, max_bytes=None)  # the default baseline signals
    kinds = {s.path.split("/signals/")[1].rsplit("/", 1)[0] for s in lean.baselines["b0"].series}
    assert kinds == {"q", "energy"} and R.estimate_bytes(lean) < R.estimate_bytes(full)
    assert [s.path for s in lean.baselines["b0"].series if "/energy/" in s.path] == [
        "baselines/b0/signals/energy/total"
    ]
    # an impossible budget: every cap at its floor, and a note says it is over
    tiny = R.record_run(res, fronts=fronts, max_bytes=10_000)
    p = tiny.properties
    assert (p["max_samples_best"], p["max_samples_baselines"]) == (R.MIN_SAMPLES, R.MIN_SAMPLES)
    assert p["max_front_points"] == R.MIN_SAMPLES // 4
    assert any("over the" in n for n in tiny.notes)


@pytest.mark.slow
@pytest.mark.parametrize("spec_path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_record_run_of_example_specs(spec_path: Path) -> None:
    from legcore.runner import run

    spec = yaml.safe_load(spec_path.read_text())
    spec["budget"] = {"generations": 2}
    fronts: dict[int, np.ndarray] = {}
    res = run(spec, callback=lambda p: fronts.__setitem__(p.generation, p.front_F.copy()))
    rec = R.record_run(res, fronts=fronts)
    assert rec.best is not None and rec.best.series
    motion = res.best.motion
    q = rec.best.series_at(f"signals/q/{R.entity_part(motion.joint_names[0])}")
    assert q.source_samples == motion.n_samples
    k = np.searchsorted(motion.t, q.index)
    np.testing.assert_array_equal(q.values, motion.q[k, 0])
    assert any("/frames/" in p.path for p in rec.best.poses)
    assert [s for s in rec.optimization if s.path.startswith("optimization/best/")]
    if len(res.objective_names) > 1:
        assert rec.front is not None and rec.front.source == "per_generation"
    assert not rec.notes, rec.notes
