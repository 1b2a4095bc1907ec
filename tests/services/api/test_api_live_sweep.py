"""A sweep, live (issue 21, item 3): ``GET /sweeps/{id}/events`` pushes the sweep's job counts
per status and its progress whenever they change, and ends when the sweep is finished; another
key's sweep is a 404, and beyond the shared limit of open streams the answer is a 429 (the
page polls)."""

from __future__ import annotations

import queue
from collections.abc import Iterator
from typing import Any

import pytest
from api_helpers import fresh_app, listen_events

from services.api.routes import live
from services.store.lifecycle import claim_job, fail_job, request_cancel
from services.store.progress import record_generation

API = "/api/v1"
BASE: dict[str, Any] = {
    "problem": {"kind": "path_tracking", "objective": "energy_time"},
    "optimizer": {"kind": "nsga2", "params": {"pop_size": 8}},
    "budget": {"generations": 4},
}


@pytest.fixture
def env(tmp_path: Any) -> Iterator[dict[str, Any]]:
    with fresh_app(tmp_path, "alice", "bob") as fa:
        r = fa.client.post(
            f"{API}/sweeps", json={"base": BASE, "seeds": [1, 2]}, headers=fa.keys["alice"]
        )
        assert r.status_code == 202, r.text
        yield {"client": fa.client, "ctx": fa.ctx, "sweep": r.json()["id"],
               "jobs": r.json()["job_ids"], **fa.keys}  # fmt: skip


def _until(events: queue.Queue[Any], pred: Any) -> dict[str, Any]:
    """The first progress event that satisfies ``pred`` (the state may be read twice)."""
    while True:
        name, data = events.get(timeout=60)
        assert name == "progress", (name, data)
        if pred(data):
            return dict(data)


def test_sweep_events_push_counts_and_progress_and_end_with_the_sweep(
    env: dict[str, Any],
) -> None:
    client, alice, ctx, sweep = env["client"], env["alice"], env["ctx"], env["sweep"]
    first_job, second_job = env["jobs"]
    events = listen_events(client, f"{API}/sweeps/{sweep}/events", alice)
    first = _until(events, lambda d: True)  # the state when the stream opens
    assert first["state"] == "queued" and first["n_jobs"] == 2 and first["terminal"] is False
    assert first["counts"]["queued"] == 2 and first["progress"] == 0.0
    assert first["total_generations"] == 8 and first["generation"] == 0

    with ctx.write() as s:
        assert claim_job(s, first_job, "w1", 60.0) is not None
    running = _until(events, lambda d: d["counts"]["running"] == 1)
    assert running["state"] == "running" and running["counts"]["queued"] == 1
    for g in (1, 2):  # each generation of a member job is pushed
        with ctx.write() as s:
            record_generation(s, first_job, "w1", generation=g, n_evals=8 * g,
                              best=[1.0 / g, g], wall_time_s=0.01)  # fmt: skip
        pushed = _until(events, lambda d, g=g: d["generation"] == g)
        assert pushed["progress"] == pytest.approx(g / 4 / 2)

    with ctx.write() as s:
        fail_job(s, first_job, "w1", "stopped by the test")
        request_cancel(s, second_job)  # queued: cancelled at once
    last = _until(events, lambda d: d["terminal"])
    assert last["state"] == "finished"
    assert last["counts"]["failed"] == 1 and last["counts"]["cancelled"] == 1
    assert events.get(timeout=60) == ("closed", None)  # the stream ends with the sweep


def test_a_finished_sweep_answers_one_event_and_ends(env: dict[str, Any]) -> None:
    client, alice, ctx, sweep = env["client"], env["alice"], env["ctx"], env["sweep"]
    with ctx.write() as s:
        for job in env["jobs"]:
            request_cancel(s, job)
    events = listen_events(client, f"{API}/sweeps/{sweep}/events", alice)
    name, data = events.get(timeout=60)
    assert name == "progress" and data["state"] == "finished" and data["terminal"] is True
    assert events.get(timeout=60) == ("closed", None)


def test_sweep_events_of_another_key_or_no_sweep_are_404(env: dict[str, Any]) -> None:
    client, sweep = env["client"], env["sweep"]
    bobs = client.get(f"{API}/sweeps/{sweep}/events", headers=env["bob"])
    nobody = client.get(f"{API}/sweeps/no-such-sweep/events", headers=env["bob"])
    assert bobs.status_code == nobody.status_code == 404
    assert bobs.json()["detail"].replace(sweep, "<id>") == nobody.json()["detail"].replace(
        "no-such-sweep", "<id>"
    )


def test_beyond_the_open_streams_limit_the_answer_is_429(
    env: dict[str, Any], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(live._open, "n", live.MAX_STREAMS)
    r = env["client"].get(f"{API}/sweeps/{env['sweep']}/events", headers=env["alice"])
    assert r.status_code == 429 and r.headers["Retry-After"] == "5"
    assert f"/sweeps/{env['sweep']}" in r.json()["detail"]
