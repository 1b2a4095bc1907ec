"""``POST /sweeps/{id}/cancel`` (issue 22, item 6): one request cancels every queued job of a
sweep and asks its running ones to stop, leaves its finished ones, and is idempotent; another
key gets 404; ``legopt cancel SWEEP`` makes that one request."""

from __future__ import annotations

from api_helpers import finish_like_a_worker
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from legcore.studies.registry import studies
from services.api.deps import ApiContext
from services.cli import app as cli_app
from services.store import repository as repo
from services.store.events import list_events
from services.store.lifecycle import claim_job
from services.store.states import JobEventKind, JobStatus

API = "/api/v1"
KIND = sorted(studies())[0]


def _sweep(client: TestClient, headers: dict[str, str], seeds: list[int]) -> tuple[str, list[str]]:
    body = {"base": {"problem": {"kind": KIND}, "record": False}, "seeds": seeds}
    r = client.post(f"{API}/sweeps", json=body, headers=headers)
    assert r.status_code == 202, r.text
    return r.json()["id"], r.json()["job_ids"]


def _statuses(ctx: ApiContext, job_ids: list[str]) -> list[tuple[JobStatus, bool]]:
    with ctx.read() as s:
        jobs = [repo.get_job(s, j) for j in job_ids]
    return [(j.status, j.cancel_requested) for j in jobs if j is not None]


def test_one_request_cancels_every_queued_job_and_is_idempotent(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], bob: dict[str, str]
) -> None:
    sweep_id, job_ids = _sweep(client, alice, [1, 2, 3, 4, 5])
    other_id, other_jobs = _sweep(client, alice, [7])  # another sweep: untouched
    assert client.post(f"{API}/sweeps/{sweep_id}/cancel", headers=bob).status_code == 404
    assert _statuses(ctx, job_ids) == [(JobStatus.QUEUED, False)] * 5

    r = client.post(f"{API}/sweeps/{sweep_id}/cancel", headers=alice)
    assert r.status_code == 202, r.text
    answer = r.json()
    assert (answer["cancelled"], answer["stopping"], answer["already_finished"]) == (5, 0, 0)
    assert answer["id"] == sweep_id and answer["n_jobs"] == 5 and answer["state"] == "finished"
    assert answer["counts"]["cancelled"] == 5 and answer["counts"]["queued"] == 0
    assert _statuses(ctx, job_ids) == [(JobStatus.CANCELLED, True)] * 5
    with ctx.read() as s:  # the job cancellation's own path: its event per job
        events = [e.kind for j in job_ids for e in list_events(s, j)]
    assert events.count(JobEventKind.CANCELLED) == 5
    assert _statuses(ctx, other_jobs) == [(JobStatus.QUEUED, False)]

    again = client.post(f"{API}/sweeps/{sweep_id}/cancel", headers=alice)
    assert again.status_code == 202
    assert (again.json()["cancelled"], again.json()["already_finished"]) == (0, 5)
    assert again.json()["counts"] == answer["counts"]
    assert client.get(f"{API}/sweeps/{other_id}", headers=alice).json()["counts"]["queued"] == 1
    assert client.post(f"{API}/sweeps/nope/cancel", headers=alice).status_code == 404


def test_running_jobs_are_asked_to_stop_and_finished_ones_are_left(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    sweep_id, job_ids = _sweep(client, alice, [1, 2, 3, 4])
    done, running, *queued = job_ids
    finish_like_a_worker(ctx, done, generations=1, n_pareto=2, recording=None)
    with ctx.write() as s:
        assert claim_job(s, running, "w2", 60.0) is not None

    r = client.post(f"{API}/sweeps/{sweep_id}/cancel", headers=alice)
    assert r.status_code == 202, r.text
    answer = r.json()
    assert (answer["cancelled"], answer["stopping"], answer["already_finished"]) == (2, 1, 1)
    assert answer["state"] == "running"
    assert _statuses(ctx, job_ids) == [
        (JobStatus.SUCCEEDED, False), (JobStatus.RUNNING, True),
        (JobStatus.CANCELLED, True), (JobStatus.CANCELLED, True),
    ]  # fmt: skip
    again = client.post(f"{API}/sweeps/{sweep_id}/cancel", headers=alice).json()
    assert (again["cancelled"], again["stopping"], again["already_finished"]) == (0, 1, 3)


def test_the_cli_cancels_a_sweep_in_one_request(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], cli_calls: list[str]
) -> None:
    sweep_id, job_ids = _sweep(client, alice, [1, 2, 3])
    res = CliRunner().invoke(cli_app, ["cancel", sweep_id[:8]])
    assert res.exit_code == 0, res.output
    assert f"sweep {sweep_id[:8]}: 3 cancelled, 0 already finished" in res.output
    assert [c for c in cli_calls if c.startswith("POST")] == [
        f"POST {API}/sweeps/{sweep_id}/cancel"
    ]
    assert _statuses(ctx, job_ids) == [(JobStatus.CANCELLED, True)] * 3
    res = CliRunner().invoke(cli_app, ["cancel", sweep_id])
    assert res.exit_code == 0 and "0 cancelled, 3 already finished" in res.output, res.output
