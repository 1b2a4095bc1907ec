"""A running job, live (issue 21, items 2 and 3): its current front while it runs, and a
Server-Sent Events stream that pushes each new generation and ends with the job."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from api_helpers import fresh_app, listen_events

from services.api.deps import ApiContext
from services.store.lifecycle import claim_job, fail_job
from services.store.progress import record_generation

API = "/api/v1"
SPEC: dict[str, Any] = {
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 8}},
    "budget": {"generations": 5},
    "seed": 1,
}


@pytest.fixture
def env(tmp_path: Any) -> Iterator[dict[str, Any]]:
    with fresh_app(tmp_path, "alice", "bob") as app:
        r = app.client.post(f"{API}/jobs", json=SPEC, headers=app.keys["alice"])
        assert r.status_code == 202, r.text
        job_id = r.json()["id"]
        with app.ctx.write() as s:
            assert claim_job(s, job_id, "w1", 60.0) is not None
        yield {"client": app.client, "ctx": app.ctx, "job": job_id, **app.keys}


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
    events = listen_events(client, f"{API}/jobs/{job}/events", alice)
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


def test_events_of_another_key_are_404(env: dict[str, Any]) -> None:
    r = env["client"].get(f"{API}/jobs/{env['job']}/events", headers=env["bob"])
    assert r.status_code == 404
