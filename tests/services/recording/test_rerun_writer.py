"""services.recording.writer: .rrd files read back with the Rerun SDK's own reader (merge,
blueprint and replay: test_rerun_merge_replay.py)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pyarrow as pa
import pytest
import yaml
from rerun.chunk import RrdReader

from legcore import recording as R
from legcore.kinematics import frames
from legcore.robots import catalog
from legcore.studies.study import Motion
from services.recording import blueprint as B
from services.recording import writer as W
from tests.recording_fixtures import arm_motion, fake_result
from tests.rrd_reading import column, read_back, signal

EXAMPLES = sorted((Path(__file__).resolve().parents[3] / "examples").glob("*.yaml"))


# ---------------------------------------------------------------------------------------------
# fixtures and readers
# ---------------------------------------------------------------------------------------------


def hexapod_like_motion(K: int, phase: float = 0.0) -> Motion:
    """All six legs of the CITEDI hexapod (18 joints), body moving; ``phase`` shifts the legs'
    sines (baselines that differ: identical ones compress ~5× in a shared entity)."""
    robot = catalog.get("citedi_hexapod")
    legs = tuple(leg.name for leg in robot.legs)
    t = np.linspace(0.0, 2.0, K)
    base = np.array([0.0, -np.pi / 8, -np.pi / 4])
    q = np.concatenate(
        [base + 0.2 * np.sin(np.outer(t, [1, 2, 3]) + i + phase) for i in range(6)], axis=1
    )
    body = np.tile(np.eye(4), (K, 1, 1))
    body[:, 1, 3] = 0.03 * t
    d = np.gradient(q, t, axis=0)
    return Motion(
        t=t,
        q=q,
        joint_names=tuple(f"{leg}.q{j + 1}" for leg in legs for j in range(3)),
        qd=d,
        qdd=d,
        jerk=d,
        tau=d,
        power=d,
        energy=np.cumsum(np.abs(d).sum(axis=1)),
        tool=body[:, :3, 3].copy(),
        robot="citedi_hexapod",
        legs=legs,
        scene={"body_T": body, "ground_z": -0.07},
    )


def quat_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of unit quaternions (N, 4) given as x, y, z, w."""
    x, y, z, w = (q[:, i].astype(float) for i in range(4))
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


def static_components(batches: list[pa.RecordBatch]) -> set[str]:
    return {n for b in batches for n in b.schema.names if not n.startswith("rerun.") and ":" in n}


# ---------------------------------------------------------------------------------------------
# write
# ---------------------------------------------------------------------------------------------


def test_file_is_complete_with_ids_and_blueprint(written: tuple) -> None:
    path, _, _ = written
    reader = RrdReader(path)
    (store,) = reader.recordings()
    assert store.application_id == "legopt" and store.recording_id == "job-123"
    assert len(reader.blueprints()) == 1
    assert len(reader.store()) > 0  # the footer/manifest exists: the stream was closed
    assert not list(path.parent.glob("*.tmp"))


def test_entity_paths(written: tuple) -> None:
    path, _, _ = written
    ents = read_back(path)
    expected = (
        [f"signals/{k}" for k in ("q", "qd", "qdd", "jerk", "tau", "power", "energy")]
        + ["signals/energy/total"]
        + ["world/robot/links", "world/robot/tool", "world/path"]
        + ["world/scene/targets", "world/scene/obstacles", "world/scene/support_polygon"]
        + ["optimization/best", "optimization/front_size", "optimization/ideal"]
        + ["optimization/front", "optimization/best_point"]
        + ["baselines/parabolic/signals/q", "baselines/min_energy/signals/energy/total"]
        + ["world/baselines/paths"]
    )
    missing = [e for e in expected if e not in ents]
    assert not missing
    assert set(B.read_entities(path)) == set(ents) - {e for e in ents if e.startswith("__")}
    links = B.read_entities(path)["world/robot/links"]  # the whole robot: one entity
    assert {"rerun.archetypes.Capsules3D", "rerun.archetypes.Arrows3D"} <= links
    assert not any("/frames/" in e for e in ents)
    assert not any(e.startswith("signals/q/") for e in ents)  # the joints share one entity
    names = [
        b.column("SeriesLines:names").to_pylist()[0]
        for b in ents["signals/q"]
        if "SeriesLines:names" in b.schema.names
    ]
    assert names == [[f"joint position q{j} (rad)" for j in range(1, 6)]]


def test_joint_signals_sample_counts_and_values(written: tuple) -> None:
    path, res, _ = written
    ents = read_back(path)
    motion = res.best.motion
    rec = R.record_run(res)
    for kind in ("q", "qd", "tau", "power"):
        for j in range(1, 6):
            t, vals = signal(ents[f"signals/{kind}"], j - 1)
            s = rec.best.series_at(f"signals/{kind}/q{j}")
            assert len(t) == s.n_samples and s.group == f"signals/{kind}"
            assert 1000 < len(t) <= 2000
            np.testing.assert_array_equal([v[0] for v in vals], s.values)
    # q at several times equals the Motion's q (time stamps are the original samples' times)
    t, vals = signal(ents["signals/q"], 2)
    q3 = np.array([v[0] for v in vals])
    for k in (0, 1234, 2500, 4999):
        hit = np.flatnonzero(np.isclose(t, motion.t[k], rtol=0, atol=1e-9))
        if hit.size:
            assert q3[hit[0]] == motion.q[k, 2]
    k = np.searchsorted(motion.t, t - 1e-12)
    np.testing.assert_allclose(motion.t[k], t, atol=1e-9)
    np.testing.assert_array_equal(q3, motion.q[k, 2])
    assert t[0] == 0.0 and t[-1] == pytest.approx(motion.t[-1])
    # baselines: all their samples (fewer than the cap)
    tb, _ = signal(ents["baselines/parabolic/signals/q"], 1)
    assert len(tb) == 600
    assert "SeriesLines:names" in static_components(ents["signals/q"])


def test_link_frames_are_drawn_as_axes_over_time(written: tuple) -> None:
    """Every link frame: three arrows (x, y, z) from its origin in ``world/robot/links``."""
    path, res, _ = written
    ents = read_back(path)
    robot = catalog.get("articulated_5dof")
    motion = res.best.motion
    links = ents["world/robot/links"]
    t, origins = column(links, "Arrows3D:origins", "time")
    assert len(t) == 2000
    _, vectors = column(links, "Arrows3D:vectors", "time")
    k = np.searchsorted(motion.t, t - 1e-12)
    F = frames(robot, motion.q[k])  # (n, 6, 4, 4): frames 0..5
    O, V = np.array(origins), np.array(vectors)  # (n, 3 * 6, 3)
    assert O.shape == V.shape == (len(t), 18, 3)
    np.testing.assert_allclose(O[:, 9], F[:, 3, :3, 3], atol=1e-6)  # frame 3: arrows 9..11
    length = np.linalg.norm(V[0, 9])
    for i in range(3):  # arrow 9 + i: axis i of frame 3
        np.testing.assert_allclose(V[:, 9 + i] / length, F[:, 3, :3, i], atol=1e-5)
    colors = [c for b in links if "Arrows3D:colors" in b.schema.names
              for c in b.column("Arrows3D:colors").to_pylist()]  # fmt: skip
    assert len(colors) == 1 and len(colors[0]) == 18 and len(set(colors[0][:3])) == 3
    # the links: capsules posed in the world per sample, their sizes static
    _, caps = column(links, "Capsules3D:translations", "time")
    assert np.array(caps).shape == (len(t), 5, 3)
    assert {"Capsules3D:lengths", "Capsules3D:radii"} <= static_components(links)


def test_front_per_generation(written: tuple) -> None:
    path, _, fronts = written
    ents = read_back(path)
    g, pts = column(ents["optimization/front"], "Points3D:positions", "generation")
    assert list(g) == list(range(1, 21))
    assert [len(p) for p in pts] == [40 + i for i in range(1, 21)]
    got = np.array(pts[4])
    np.testing.assert_allclose(got, fronts[5], atol=1e-6)  # under the cap: every point, in order
    gb, best = signal(ents["optimization/best"], 0, "generation")  # f1 of the group
    np.testing.assert_allclose([b[0] for b in best], 1.0 / np.arange(1, 21))
    assert list(gb) == list(range(1, 21))


def test_two_objective_front_is_points2d(tmp_path: Path) -> None:
    path = tmp_path / "two.rrd"
    W.write_recording(fake_result(None, m=2, generations=3), path)
    ents = read_back(path)
    g, pts = column(ents["optimization/front"], "Points2D:positions", "generation")
    assert list(g) == [3] and len(pts[0]) == 50  # final front only, at the last generation
    assert not any(e.startswith("signals/") for e in ents)


def test_failed_write_leaves_no_partial_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "job.rrd"

    def boom(*a: object, **k: object) -> None:
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(W, "_log_front", boom)  # fails after the signals were logged
    with pytest.raises(RuntimeError, match="disk on fire"):
        W.write_recording(fake_result(arm_motion(K=500)), path)
    assert not path.exists()
    assert list(tmp_path.iterdir()) == []
    # an existing recording is left as it was
    path.write_bytes(b"previous")
    with pytest.raises(RuntimeError):
        W.write_recording(fake_result(arm_motion(K=500)), path)
    assert path.read_bytes() == b"previous"
    assert [p.name for p in tmp_path.iterdir()] == ["job.rrd"]


@pytest.mark.slow
def test_long_motion_is_capped(tmp_path: Path) -> None:
    path = tmp_path / "long.rrd"
    motion = arm_motion(K=200_000, T=200.0)
    W.write_recording(fake_result(motion, m=1), path, max_samples=1000)
    ents = read_back(path)
    t, _ = signal(ents["signals/qd"], 0)
    assert len(t) <= 1000
    t, _ = column(ents["world/robot/links"], "Arrows3D:origins", "time")
    assert len(t) == 1000
    assert path.stat().st_size < 5e6


@pytest.mark.slow
def test_hexapod_like_recording_stays_under_20_mb(tmp_path: Path) -> None:
    """18 joints × 20 000 samples, 6 baselines, a 300-point front over 100 generations."""
    path = tmp_path / "hexa.rrd"
    motion = hexapod_like_motion(K=20_000)
    res = fake_result(
        motion,
        generations=100,
        front_size=300,
        baselines={
            f"paper_{c}": hexapod_like_motion(K=20_000, phase=0.1 * j)
            for j, c in enumerate("abcdef", 1)
        },
    )
    rng = np.random.default_rng(4)
    fronts = {g: rng.random((300, 3)) for g in range(1, 101)}
    t0 = time.perf_counter()
    W.write_recording(res, path, fronts=fronts)
    elapsed = time.perf_counter() - t0
    size = path.stat().st_size
    assert size <= 20e6, f"{size / 1e6:.1f} MB"
    assert elapsed < 30
    rec = R.record_run(res, fronts=fronts)
    assert abs(rec.properties["estimated_bytes"] - size) < 0.25 * size
    assert rec.properties["estimated_bytes"] <= R.DEFAULT_MAX_BYTES
    # with every signal of the baselines (not only q and energy) the budget binds: the
    # baselines give way first, the best motion keeps its 2000 samples
    full = R.record_run(res, fronts=fronts, baseline_signals=None)
    assert full.properties["max_samples_best"] == 2000
    assert R.MIN_SAMPLES <= full.properties["max_samples_baselines"] < 2000
    assert any("display caps lowered" in n for n in full.notes)
    assert full.properties["estimated_bytes"] <= R.DEFAULT_MAX_BYTES
    ents = read_back(path)
    g, pts = column(ents["optimization/front"], "Points3D:positions", "generation")
    assert len(g) == 100 and all(len(p) == 300 for p in pts)
    t, _ = column(ents["world/robot/links"], "Arrows3D:origins", "time")
    assert len(t) == 2000
    _, body = column(ents["world/robot/links"], "Boxes3D:centers", "time")  # the body box
    assert len(body) == 2000 and "world/scene/ground" in ents


# ---------------------------------------------------------------------------------------------
# the example studies, end to end
# ---------------------------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("spec_path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_spec_recording(spec_path: Path, tmp_path: Path) -> None:
    from legcore.runner import run

    spec = yaml.safe_load(spec_path.read_text())
    spec["budget"] = {"generations": 2}
    fronts: dict[int, np.ndarray] = {}
    res = run(spec, callback=lambda p: fronts.__setitem__(p.generation, p.front_F.copy()))
    path = tmp_path / "rec.rrd"
    W.write_recording(res, path, recording_id="ex", fronts=fronts)
    assert path.stat().st_size < 20e6
    ents = read_back(path)
    motion = res.best.motion
    n_joints = len(motion.joint_names)
    t, vals = (
        signal(ents["signals/q"], n_joints - 1)
        if n_joints > 1
        else column(ents[f"signals/q/{R.entity_part(motion.joint_names[0])}"], "Scalars:scalars",
                    "time")
    )  # fmt: skip
    assert len(t) == min(motion.n_samples, len(t)) and 0 < len(t) <= 2000
    k = np.searchsorted(motion.t, t - 1e-12)
    np.testing.assert_array_equal([v[0] for v in vals], motion.q[k, -1])
    assert any(e.endswith("/robot/links") or "/frames/" in e for e in ents)
    assert "optimization/front_size" in ents
    if len(res.objective_names) > 1:
        comp = "Points3D:positions" if len(res.objective_names) > 2 else "Points2D:positions"
        g, pts = column(ents["optimization/front"], comp, "generation")
        assert list(g) == sorted(fronts)  # (an empty front is logged too: nothing feasible yet)
        assert [len(p) for p in pts] == [len(fronts[k]) for k in sorted(fronts)]
    for name in res.baselines:
        if res.baselines[name].motion is not None:
            part = R.entity_part(name)
            assert f"baselines/{part}/signals/q" in ents or "baselines/signals/q" in ents
