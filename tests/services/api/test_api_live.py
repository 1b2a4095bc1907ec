"""A running job, live (issue 21, items 2 and 3): its current front while it runs, and a
Server-Sent Events stream that pushes each new generation and ends with the job."""

from __future__ import annotations

import json
import queue
import threading
from collections.abc import Iterator
from typing import Any

import pytest
from fastapi.testclient import TestClient

from services.api.app import create_app
from services.api.deps import ApiContext
from services.store import repository as repo
from services.store.keys import generate_api_key
from services.store.lifecycle import claim_job, fail_job, record_generation
from services.store.migrate import upgrade
from services.store.session import reset_engine
from services.store.settings import get_settings

API = "/api/v1"
SPEC: dict[str, Any] = {
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 8}},
    "budget": {"generations": 5},
    "seed": 1,
}


@pytest.fixture
def env(tmp_path: Any) -> Iterator[dict[str, Any]]:
    mp = pytest.MonkeyPatch()
    url = f"sqlite:///{tmp_path / 'legopt.db'}"
    mp.setenv("LEGOPT_DATA_DIR", str(tmp_path))
    mp.setenv("LEGOPT_DATABASE_URL", url)
    get_settings.cache_clear()
    reset_engine()
    upgrade(url)
    app = create_app(get_settings(), enqueue=lambda _j: None)
    ctx: ApiContext = app.state.context
    keys = {}
    for name in ("alice", "bob"):
        raw, key_hash = generate_api_key()
        with ctx.write() as s:
            repo.create_api_key(s, name=name, key_hash=key_hash)
        keys[name] = {"X-API-Key": raw}
    with TestClient(app) as client:
        r = client.post(f"{API}/jobs", json=SPEC, headers=keys["alice"])
        assert r.status_code == 202, r.text
        job_id = r.json()["id"]
        with ctx.write() as s:
            assert claim_job(s, job_id, "w1", 60.0) is not None
        yield {"client": client, "ctx": ctx, "job": job_id, **keys}
    mp.undo()
    get_settings.cache_clear()
    reset_engine()


def _generation(ctx: ApiContext, job_id: str, g: int, front: Any = None) -> None:
    with ctx.write() as s:
        record_generation(s, job_id, "w1", generation=g, n_evals=8 * g, best=[1.0 / g, g],
                          wall_time_s=0.01, front=front)  # fmt: skip


def test_the_live_front_is_the_last_stored_generations(env: dict[str, Any]) -> None:
    client, alice, job, ctx = env["client"], env["alice"], env["job"], env["ctx"]
    empty = client.get(f"{API}/jobs/{job}/front/live", headers=alice).json()
    assert empty["generation"] is None and empty["points"] == []
    _generation(ctx, job, 1, [[1.0, 5.0], [2.0, 4.0]])
    _generation(ctx, job, 2, [[0.5, 4.0], [1.5, 3.0], [3.0, 1.0]])
    live = client.get(f"{API}/jobs/{job}/front/live", headers=alice).json()
    assert live["generation"] == 2 and live["points"] == [[0.5, 4.0], [1.5, 3.0], [3.0, 1.0]]
    assert sorted(q["name"] for q in live["objectives"]) == ["energy", "time"]
    assert client.get(f"{API}/jobs/{job}/front/live", headers=env["bob"]).status_code == 404


def test_events_push_each_generation_and_end_with_the_job(env: dict[str, Any]) -> None:
    client, alice, job, ctx = env["client"], env["alice"], env["job"], env["ctx"]
    events: queue.Queue[tuple[str, Any]] = queue.Queue()

    def listen() -> None:
        with client.stream("GET", f"{API}/jobs/{job}/events", headers=alice) as r:
            assert r.status_code == 200
            assert r.headers["content-type"].startswith("text/event-stream")
            name = None
            for line in r.iter_lines():
                if line.startswith("event:"):
                    name = line[6:].strip()
                elif line.startswith("data:") and name:
                    events.put((name, json.loads(line[5:])))
        events.put(("closed", None))

    t = threading.Thread(target=listen, daemon=True)
    t.start()
    first = events.get(timeout=60)  # the state when the stream opens
    assert first[0] == "progress" and first[1]["status"] == "running"
    for g in (1, 2, 3):
        _generation(ctx, job, g)
        while True:  # the push of generation g (the state may be read more than once)
            name, data = events.get(timeout=60)
            assert name == "progress"
            if data["generation"] == g:
                break
    with ctx.write() as s:
        fail_job(s, job, "w1", "stopped by the test")
    name, data = events.get(timeout=60)
    assert name == "progress" and data["status"] == "failed" and data["terminal"] is True
    assert events.get(timeout=60) == ("closed", None)  # the stream ends with the job
    t.join(60)


def test_events_of_another_key_are_404(env: dict[str, Any]) -> None:
    r = env["client"].get(f"{API}/jobs/{env['job']}/events", headers=env["bob"])
    assert r.status_code == 404
