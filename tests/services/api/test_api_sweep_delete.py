"""``DELETE /sweeps/{id}`` (issue 21, item 5): deletes every job of a finished sweep with its
artifacts, as ``DELETE /jobs/{id}`` deletes one (its storage quota freed), then the sweep; a
409 saying how many jobs are unfinished while any is queued or running (nothing deleted);
another key's sweep is a 404; ``legopt delete ID`` deletes a sweep as it deletes a job. The
jobs are finished through the store as a worker finishes them."""

from __future__ import annotations

from pathlib import Path

from api_helpers import finish_like_a_worker
from fastapi.testclient import TestClient
from typer.testing import CliRunner

from legcore.studies.registry import studies
from services.api.deps import ApiContext
from services.cli import app as cli_app
from services.store.lifecycle import claim_job, fail_job
from services.store.settings import Settings

API = "/api/v1"
KIND = sorted(studies())[0]


def _sweep(client: TestClient, headers: dict[str, str], seeds: list[int]) -> tuple[str, list[str]]:
    body = {"base": {"problem": {"kind": KIND}, "record": False}, "seeds": seeds}
    r = client.post(f"{API}/sweeps", json=body, headers=headers)
    assert r.status_code == 202, r.text
    return r.json()["id"], r.json()["job_ids"]


def _files(settings: Settings, job_id: str) -> list[Path]:
    """The artifact files of ``job_id`` in the app's artifact directory."""
    root = Path(settings.artifact_dir)
    return [p for p in root.rglob("*") if p.is_file() and job_id in p.relative_to(root).as_posix()]


def _stored_bytes(client: TestClient, headers: dict[str, str]) -> int:
    return int(client.get(f"{API}/keys/me", headers=headers).json()["stored_bytes"])


def _finish(ctx: ApiContext, job_ids: list[str]) -> None:
    for job_id in job_ids:  # a result, a front and a recording file each
        finish_like_a_worker(ctx, job_id, generations=1, n_pareto=3)


def test_deleting_a_finished_sweep_deletes_every_job_and_artifact(
    client: TestClient, ctx: ApiContext, settings: Settings, alice: dict[str, str]
) -> None:
    sweep_id, job_ids = _sweep(client, alice, [1, 2, 3])
    other_sweep, other_jobs = _sweep(client, alice, [4])  # untouched
    _finish(ctx, [*job_ids, *other_jobs])
    assert all(_files(settings, j) for j in [*job_ids, *other_jobs])
    before = _stored_bytes(client, alice)

    r = client.delete(f"{API}/sweeps/{sweep_id}", headers=alice)
    assert r.status_code == 204, r.text
    assert r.content == b""
    assert client.get(f"{API}/sweeps/{sweep_id}", headers=alice).status_code == 404
    for job_id in job_ids:
        assert client.get(f"{API}/jobs/{job_id}", headers=alice).status_code == 404
        assert client.get(f"{API}/jobs/{job_id}/result", headers=alice).status_code == 404
        assert _files(settings, job_id) == []
    assert (
        client.get(f"{API}/jobs", params={"sweep_id": sweep_id}, headers=alice).json()["total"] == 0
    )
    after = _stored_bytes(client, alice)
    assert 0 < after < before  # the deleted jobs' bytes are freed, the other job's are not
    # the other sweep is whole
    assert client.get(f"{API}/sweeps/{other_sweep}", headers=alice).json()["n_jobs"] == 1
    assert client.get(f"{API}/jobs/{other_jobs[0]}", headers=alice).status_code == 200
    assert _files(settings, other_jobs[0])
    # once: a repeat is a 404
    assert client.delete(f"{API}/sweeps/{sweep_id}", headers=alice).status_code == 404
    # and deleting the other one too leaves nothing stored
    assert client.delete(f"{API}/sweeps/{other_sweep}", headers=alice).status_code == 204
    assert _stored_bytes(client, alice) == 0


def test_a_sweep_with_an_unfinished_job_is_a_409_and_nothing_is_deleted(
    client: TestClient, ctx: ApiContext, settings: Settings, alice: dict[str, str]
) -> None:
    sweep_id, job_ids = _sweep(client, alice, [1, 2, 3])
    done, running, queued = job_ids
    _finish(ctx, [done])
    with ctx.write() as s:
        assert claim_job(s, running, "w", 60.0) is not None

    r = client.delete(f"{API}/sweeps/{sweep_id}", headers=alice)
    assert r.status_code == 409, r.text
    detail = r.json()["detail"]
    assert "2 unfinished jobs" in detail and f"POST /sweeps/{sweep_id}/cancel" in detail
    assert "cancel it first" in detail
    for job_id in job_ids:
        assert client.get(f"{API}/jobs/{job_id}", headers=alice).status_code == 200
    assert _files(settings, done)

    client.post(f"{API}/sweeps/{sweep_id}/cancel", headers=alice)  # queued: cancelled now
    r = client.delete(f"{API}/sweeps/{sweep_id}", headers=alice)
    assert r.status_code == 409 and "1 unfinished job (queued or running)" in r.json()["detail"]
    with ctx.write() as s:  # the running job's worker stops
        fail_job(s, running, "w", "stopped")
    assert client.delete(f"{API}/sweeps/{sweep_id}", headers=alice).status_code == 204
    assert all(client.get(f"{API}/jobs/{j}", headers=alice).status_code == 404 for j in job_ids)
    assert _files(settings, done) == []


def test_another_keys_sweep_is_a_404(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], bob: dict[str, str]
) -> None:
    sweep_id, job_ids = _sweep(client, alice, [1, 2])
    _finish(ctx, job_ids)
    r = client.delete(f"{API}/sweeps/{sweep_id}", headers=bob)
    assert r.status_code == 404, r.text
    assert client.get(f"{API}/sweeps/{sweep_id}", headers=alice).json()["n_jobs"] == 2
    assert client.delete(f"{API}/sweeps/nope", headers=alice).status_code == 404
    # a sweep with no job of another key's in it either: bob's own jobs are not touched
    bob_sweep, bob_jobs = _sweep(client, bob, [1])
    _finish(ctx, bob_jobs)
    assert client.delete(f"{API}/sweeps/{bob_sweep}", headers=alice).status_code == 404
    assert client.get(f"{API}/jobs/{bob_jobs[0]}", headers=bob).status_code == 200


def test_the_job_delete_still_refuses_an_unfinished_job(
    client: TestClient, ctx: ApiContext, settings: Settings, alice: dict[str, str]
) -> None:
    """``DELETE /jobs/{id}`` goes through the same deletion: a 409 for a queued job, then 204
    with its files gone once it finished; a job of a sweep leaves the sweep with one job less."""
    sweep_id, (first, second) = _sweep(client, alice, [1, 2])
    r = client.delete(f"{API}/jobs/{first}", headers=alice)
    assert r.status_code == 409 and "cancel it first" in r.json()["detail"]
    _finish(ctx, [first])
    assert client.delete(f"{API}/jobs/{first}", headers=alice).status_code == 204
    assert _files(settings, first) == []
    assert client.get(f"{API}/sweeps/{sweep_id}", headers=alice).json()["n_jobs"] == 1


def test_the_cli_deletes_a_sweep_and_a_job_by_prefix(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], cli_calls: list[str]
) -> None:
    sweep_id, job_ids = _sweep(client, alice, [1, 2])
    lone = client.post(f"{API}/jobs", json={"problem": {"kind": KIND}, "record": False},
                       headers=alice).json()["id"]  # fmt: skip
    res = CliRunner().invoke(cli_app, ["delete", sweep_id[:8]])
    assert res.exit_code == 2, res.output  # the API's 409: cancel it first
    assert "2 unfinished jobs" in res.output and "cancel it first" in res.output
    _finish(ctx, [*job_ids, lone])

    cli_calls.clear()
    res = CliRunner().invoke(cli_app, ["delete", sweep_id[:8], lone[:8]])
    assert res.exit_code == 0, res.output
    assert f"sweep {sweep_id[:8]}: deleted with its jobs" in res.output
    assert f"job {lone[:8]}: deleted" in res.output
    assert [c for c in cli_calls if c.startswith("DELETE")] == [
        f"DELETE {API}/sweeps/{sweep_id}",
        f"DELETE {API}/jobs/{lone}",
    ]
    for job_id in [*job_ids, lone]:
        assert client.get(f"{API}/jobs/{job_id}", headers=alice).status_code == 404
    res = CliRunner().invoke(cli_app, ["delete", sweep_id[:8]])
    assert res.exit_code == 2 and "ID: no job or sweep id starts with" in res.output
