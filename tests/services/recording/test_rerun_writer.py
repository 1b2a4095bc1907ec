"""services.recording.writer: .rrd files read back with the Rerun SDK's own reader."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import time
from collections import defaultdict
from pathlib import Path
from types import SimpleNamespace

import httpx
import numpy as np
import pyarrow as pa
import pytest
import yaml
from rerun.chunk import RrdReader

from legcore import recording as R
from legcore.kinematics import frames
from legcore.robots import catalog
from legcore.studies.study import Box, Motion
from services.recording import blueprint as B
from services.recording import merge as M
from services.recording import replay as RP
from services.recording import writer as W
from tests.patience import Patience
from tests.recording_fixtures import arm_motion, fake_result

SCENE = {
    "targets": np.array([[0.5, 0.0, 0.5], [0.6, 0.0, 0.5]]),
    "obstacles": [Box((0.3, 0.0, 0.5), (0.03, 0.02, 0.013))],
    "support_polygon": np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]),
}
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


def read_back(path: Path) -> dict[str, list[pa.RecordBatch]]:
    """Entity path (no leading /) → record batches of its chunks, via rerun.chunk.RrdReader."""
    out: dict[str, list[pa.RecordBatch]] = defaultdict(list)
    for chunk in RrdReader(path).stream():
        out[chunk.entity_path.lstrip("/")].append(chunk.to_record_batch())
    return dict(out)


def column(batches: list[pa.RecordBatch], name: str, index: str) -> tuple[np.ndarray, list]:
    """(index values — s for a duration timeline —, component values) of the rows of
    ``batches`` that carry ``name``, sorted by index."""
    idx: list[np.ndarray] = []
    vals: list = []
    for b in batches:
        if name in b.schema.names and index in b.schema.names:
            col = b.column(index)
            scale = 1e-9 if pa.types.is_duration(col.type) else 1.0
            idx.append(col.cast(pa.int64()).to_numpy() * scale)
            vals.extend(b.column(name).to_pylist())
    i = np.concatenate(idx) if idx else np.zeros(0)
    order = np.argsort(i, kind="stable")
    return i[order], [vals[k] for k in order]


def signal(batches: list[pa.RecordBatch], j: int, index: str = "time") -> tuple[np.ndarray, list]:
    """(index, [[value]] rows) of joint ``j`` of a signal logged as one entity (a ``Scalars``
    batch of one value per joint at each sample)."""
    t, vals = column(batches, "Scalars:scalars", index)
    return t, [[v[j]] for v in vals]


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


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, SimpleNamespace, dict]:
    """One recording of a 3-objective run with per-generation fronts and two baselines."""
    path = tmp_path_factory.mktemp("rec") / "job.rrd"
    res = fake_result(
        arm_motion(K=5000, **SCENE),
        generations=20,
        baselines={"parabolic": arm_motion(K=600), "min energy": arm_motion(K=300)},
    )
    rng = np.random.default_rng(3)
    fronts = {g: rng.random((40 + g, 3)) for g in range(1, 21)}
    W.write_recording(res, path, recording_id="job-123", fronts=fronts)
    return path, res, fronts


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
# merge
# ---------------------------------------------------------------------------------------------


def test_merge_recordings(tmp_path: Path) -> None:
    a, b = tmp_path / "a.rrd", tmp_path / "b.rrd"
    W.write_recording(fake_result(arm_motion(K=300), generations=4), a, recording_id="job-a")
    W.write_recording(fake_result(arm_motion(K=700), generations=6), b, recording_id="job-b")
    out = tmp_path / "sweep" / "merged.rrd"
    M.merge_recordings([a, b], out, ["seed 1", "seed-2"], recording_id="sweep-1")
    reader = RrdReader(out)
    (store,) = reader.recordings()
    assert store.recording_id == "sweep-1" and len(reader.blueprints()) == 1
    ents = read_back(out)
    assert "jobs/seed_1/signals/q" in ents and "jobs/seed-2/signals/q" in ents
    assert "jobs/seed_1/world/robot/links" in ents
    assert not any(e.startswith(("signals", "world", "jobs/seed_1/__")) for e in ents)
    t1, _ = signal(ents["jobs/seed_1/signals/q"], 0)
    t2, _ = signal(ents["jobs/seed-2/signals/q"], 0)
    assert (len(t1), len(t2)) == (300, 700)
    g, _ = column(ents["jobs/seed-2/optimization/front"], "Points3D:positions", "generation")
    assert list(g) == [6]
    with pytest.raises(ValueError, match="names"):
        M.merge_recordings([a, b], out, ["only one"])


@pytest.mark.slow
def test_merged_recording_is_made_in_a_child_once_and_cached(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from services.api import merged_recordings as M

    a, b = tmp_path / "a.rrd", tmp_path / "b.rrd"
    W.write_recording(fake_result(arm_motion(K=100), generations=2), a, recording_id="job-a")
    W.write_recording(fake_result(arm_motion(K=120), generations=2), b, recording_id="job-b")
    cache = tmp_path / "cache"
    out = M.merged_recording([a, b], ["1_a", "2_b"], ["da", "db"], cache)
    assert out.parent == cache / "merged" and "jobs/2_b/signals/q" in read_back(out)
    calls: list[object] = []
    monkeypatch.setattr(M.subprocess, "run", lambda *a, **k: calls.append(a))
    assert M.merged_recording([a, b], ["1_a", "2_b"], ["da", "db"], cache) == out
    assert not calls  # the second download reads the cached file
    monkeypatch.undo()
    with pytest.raises(RuntimeError, match="not found"):
        M.merged_recording([a, tmp_path / "gone.rrd"], ["1_a", "2_b"], ["da", "dx"], cache)
    (cache / "merged" / "old.rrd").write_bytes(b"x")
    os.utime(cache / "merged" / "old.rrd", (1, 1))
    M._prune(cache / "merged", keep_bytes=0)
    assert list((cache / "merged").glob("*.rrd")) == [out]  # the newest always stays


def test_merges_run_bounded_shared_and_refused_beyond_the_queue(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """12 parallel merge requests (10 distinct, 2 repeats): at most MERGE_WORKERS children at
    once, the repeats share a child, distinct merges beyond MAX_PENDING get 429 + Retry-After
    at once, and every accepted one ends with its file."""
    import threading

    from fastapi import HTTPException

    from services.api import merged_recordings as M

    release = threading.Event()
    lock = threading.Lock()
    running, peak, children = [0], [0], [0]

    def fake_child(cmd: list[str], **_: object) -> object:
        with lock:
            running[0] += 1
            children[0] += 1
            peak[0] = max(peak[0], running[0])
        assert release.wait(60)
        Path(json.loads(cmd[-1])["out"]).write_bytes(b"merged")
        with lock:
            running[0] -= 1
        return M.subprocess.CompletedProcess(cmd, 0, "", "")

    monkeypatch.setattr(M.subprocess, "run", fake_child)
    cache, a = tmp_path / "cache", tmp_path / "a.rrd"
    outcomes: list[tuple[int, object]] = []

    def request(i: int) -> None:
        try:
            outcomes.append((i, M.merged_recording([a], [f"1_{i}"], [f"d{i}"], cache)))
        except HTTPException as exc:
            outcomes.append((i, exc))

    def refused() -> list[tuple[int, HTTPException]]:
        return [(i, o) for i, o in outcomes if isinstance(o, HTTPException)]

    threads = [threading.Thread(target=request, args=(i,)) for i in range(10)]
    for t in threads:
        t.start()
    patience = Patience(60)
    while len(refused()) < 10 - M.MAX_PENDING or M._work.pending < M.MAX_PENDING:
        assert not patience.expired(), (outcomes, M._work.pending)
        release.wait(0.01)
    admitted = sorted(set(range(10)) - {i for i, _ in refused()})
    repeats = [threading.Thread(target=request, args=(i,)) for i in admitted[:2]]
    for t in repeats:
        t.start()  # the same merges: they join the pending ones (no new child, no 429)
    release.set()
    for t in threads + repeats:
        t.join(60)
    assert len(refused()) == 10 - M.MAX_PENDING
    assert all(e.status_code == 429 and (e.headers or {})["Retry-After"] for _, e in refused())
    files = [o for _, o in outcomes if isinstance(o, Path)]
    assert len(files) == M.MAX_PENDING + 2 and all(f.read_bytes() == b"merged" for f in files)
    assert children[0] == M.MAX_PENDING and peak[0] <= M.MERGE_WORKERS


def views(container: object) -> list[tuple[str, str, str]]:
    """(view class, origin, name) of every view under a blueprint container, depth first."""
    out: list[tuple[str, str, str]] = []
    for c in getattr(container, "contents", []):
        if hasattr(c, "origin"):
            out.append((type(c).__name__, str(c.origin), str(c.name)))
        else:
            out.extend(views(c))
    return out


def test_blueprint_views() -> None:
    res = fake_result(arm_motion(K=50), baselines={"p": arm_motion(K=50)})
    bp = B.blueprint_for(R.record_run(res))
    v = views(bp.root_container)
    assert ("Spatial3DView", "world", "robot, path and scene") in v
    assert ("Spatial3DView", "optimization", "Pareto front") in v
    origins = {o for kind, o, _ in v if kind == "TimeSeriesView"}
    assert {"signals/q", "signals/qd", "signals/tau", "signals/power", "signals/energy"} <= origins
    assert {"optimization/best", "baselines"} <= origins  # one view for every baseline's q
    # a merged recording: one set of views per job plus the overlays
    ents = {f"jobs/{j}/{e}": set() for j in ("a", "b") for e in R.record_run(res).entity_paths()}
    ents["jobs/a/optimization/front"] = ents["jobs/b/optimization/front"] = {
        "rerun.archetypes.Points3D"
    }
    v = views(B.blueprint_for(ents, jobs=["a", "b"]).root_container)
    names = {n for _, _, n in v}
    assert {"Pareto fronts, all jobs", "energy (J), all jobs", "a: q (rad)", "b: q (rad)"} <= names


# ---------------------------------------------------------------------------------------------
# replay
# ---------------------------------------------------------------------------------------------


@pytest.mark.filterwarnings("ignore:RRD file has no footer")  # the saved copy of the live stream
def test_serve_web_answers_200_on_localhost_and_serves_the_data(
    written: tuple, tmp_path: Path
) -> None:
    path, _, _ = written
    with RP.serve_web(path, None, timeout=20) as viewer:
        assert viewer.url is not None and viewer.url.startswith("http://127.0.0.1:")
        r = httpx.get(viewer.url, timeout=5)
        assert r.status_code == 200
        assert "text/html" in r.headers["content-type"] and "rerun" in r.text.lower()
        # a late client receives the pushed recording from the server
        grpc = httpx.URL(viewer.url).params["url"]
        got = tmp_path / "got.rrd"
        saver = subprocess.Popen(
            [RP.rerun_binary(), "--connect", grpc, "--save", str(got)],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            deadline, last = time.monotonic() + 15, -1
            while time.monotonic() < deadline:
                time.sleep(0.5)
                size = got.stat().st_size if got.exists() else 0
                if size > 0 and size == last:
                    break
                last = size
        finally:
            saver.terminate()
            saver.wait(10)
        assert "signals/q" in B.read_entities(got)
    assert viewer.process.poll() is not None  # stopped


def test_serve_web_on_a_busy_port_fails_clearly(written: tuple) -> None:
    path, _, _ = written
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        with pytest.raises(RuntimeError, match="already in use"):
            RP.serve_web(path, busy.getsockname()[1], timeout=10)


def test_open_viewer_without_display_uses_the_web_viewer(
    written: tuple, monkeypatch: pytest.MonkeyPatch
) -> None:
    path, _, _ = written
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    monkeypatch.setattr(RP.sys, "platform", "linux")
    assert not RP.has_display()
    port = RP._free_port()
    with RP.open_viewer(path, port=port) as viewer:
        assert viewer.url is not None and f":{port}/" in viewer.url
        assert httpx.get(viewer.url, timeout=5).status_code == 200
    with pytest.raises(FileNotFoundError):
        RP.open_viewer(path.with_name("missing.rrd"))


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
