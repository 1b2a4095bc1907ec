"""services.recording.merge, blueprint and replay: merged .rrd files read back with the Rerun
SDK's own reader, the blueprint's views, the web viewer."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import time
from pathlib import Path

import httpx
import pytest
from rerun.chunk import RrdReader

from legcore import recording as R
from services.recording import blueprint as B
from services.recording import merge as M
from services.recording import replay as RP
from services.recording import writer as W
from tests.patience import Patience
from tests.recording_fixtures import arm_motion, fake_result
from tests.rrd_reading import column, read_back, signal

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
