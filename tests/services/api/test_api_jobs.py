"""Jobs: submission (every study kind, stored robots), every bad input -> 4xx with nothing
stored, the lifecycle read back through the API, cancel, ownership, listing."""

from __future__ import annotations

import copy
import time
from datetime import UTC, datetime, timedelta
from typing import Any

import pytest
from api_helpers import finish_like_a_worker, locs, new_key, row_counts
from fastapi.testclient import TestClient

from legcore.robots import Robot, catalog
from legcore.studies.registry import studies
from services.api.deps import ApiContext
from services.store.lifecycle import claim_job, fail_job

API = "/api/v1"
KINDS = sorted(studies())


def serial_study() -> tuple[str, dict[str, Any]]:
    """A study whose default robot is a serial catalog robot, and that robot's inline spec."""
    for kind in KINDS:
        robot = catalog.get(studies()[kind].default_robot)
        if isinstance(robot, Robot):
            return kind, robot.spec.model_dump(mode="json")
    raise AssertionError("no study with a serial default robot")


def submit(client: TestClient, headers: dict[str, str], spec: dict[str, Any]) -> dict[str, Any]:
    r = client.post(f"{API}/jobs", json=spec, headers=headers)
    assert r.status_code == 202, r.text
    return r.json()


@pytest.mark.slow
@pytest.mark.parametrize("kind", KINDS)
def test_submit_each_study_kind(
    client: TestClient, alice: dict[str, str], sent: list[str], kind: str
) -> None:
    r = client.post(f"{API}/jobs", json={"problem": {"kind": kind}}, headers=alice)
    assert r.status_code == 202, r.text
    job = r.json()
    assert job["status"] == "queued" and job["total_generations"] >= 1
    assert r.headers["location"] == f"{API}/jobs/{job['id']}"
    assert sent == [job["id"]]
    assert job["spec"] == {"problem": {"kind": kind}} and job["kind"] == kind


def test_what_submission_learns_is_stored_with_the_job(
    client: TestClient, alice: dict[str, str], sent: list[str]
) -> None:
    """Issue 24 (facts stored once): kind, the study's default robot and optimizer resolved,
    the objective names and n_var, as legcore.runner.prepare finds them, are stored with the
    job (and each job of a sweep) and read back without rebuilding the study."""
    from legcore.runner import prepare

    kind = "quadruped_gait"
    job = submit(client, alice, {"problem": {"kind": kind}, "budget": {"generations": 2}})
    prepared = prepare({"problem": {"kind": kind}})
    expected = {
        "kind": kind,
        "robot": prepared.robot.name,
        "optimizer": studies()[kind].default_optimizer["kind"],
        "objectives": list(prepared.problem.objective_names),
        "n_var": prepared.problem.n_var,
    }
    assert job["facts"] == expected
    assert client.get(f"{API}/jobs/{job['id']}", headers=alice).json()["facts"] == expected
    sweep = client.post(
        f"{API}/sweeps",
        json={"base": {"problem": {"kind": kind}, "budget": {"generations": 2}},
              "grid": {"optimizer.kind": ["ga", "nsga2"]}},
        headers=alice,
    )  # fmt: skip
    assert sweep.status_code == 202, sweep.text
    jobs = client.get(f"{API}/jobs?sweep_id={sweep.json()['id']}", headers=alice).json()["items"]
    assert sorted(j["facts"]["optimizer"] for j in jobs) == ["ga", "nsga2"]
    assert all(j["facts"]["objectives"] == expected["objectives"] for j in jobs)


def test_stored_robot_is_substituted(
    client: TestClient, alice: dict[str, str], sent: list[str]
) -> None:
    kind, spec = serial_study()
    robot = client.post(f"{API}/robots", json={"name": "mine", "spec": spec}, headers=alice)
    assert robot.status_code == 201, robot.text
    by_id = submit(client, alice, {"problem": {"kind": kind}, "robot": robot.json()["id"]})
    assert by_id["spec"]["robot"]["joints"] == spec["joints"]
    by_name = submit(client, alice, {"problem": {"kind": kind}, "robot": "mine"})
    assert by_name["spec"]["robot"] == by_id["spec"]["robot"]
    default = studies()[kind].default_robot
    cat = client.post(f"{API}/robots", json={"name": "cat", "catalog": default}, headers=alice)
    by_cat = submit(client, alice, {"problem": {"kind": kind}, "robot": cat.json()["id"]})
    assert by_cat["spec"]["robot"] == default
    assert len(sent) == 3


def bad_job_cases() -> list[tuple[str, Any, list[Any]]]:
    """(case id, body, expected loc) of bad job submissions."""
    kind, spec = serial_study()
    bad_inertia = copy.deepcopy(spec)
    bad_inertia["joints"][1]["inertia"] = [[1.0, 0, 0], [0, -1.0, 0], [0, 0, 1.0]]
    bad_mass = copy.deepcopy(spec)
    bad_mass["joints"][0]["mass"] = -2.0
    base = {"problem": {"kind": kind}}
    return [
        ("unknown-field", {**base, "bogus": 1}, ["body", "bogus"]),
        (
            "unknown-problem-field",
            {"problem": {"kind": kind, "bogus": 1}},
            ["body", "problem", "bogus"],
        ),
        ("unknown-kind", {"problem": {"kind": "nope"}}, ["body", "problem"]),
        ("missing-problem", {}, ["body", "problem"]),
        ("unknown-robot", {**base, "robot": "no_such_robot"}, ["body", "robot"]),
        ("robot-not-a-spec", {**base, "robot": 12}, ["body", "robot"]),
        (
            "non-physical-inertia",
            {**base, "robot": bad_inertia},
            ["body", "robot", "joints", 1, "inertia"],
        ),
        ("negative-mass", {**base, "robot": bad_mass}, ["body", "robot", "joints", 0, "mass"]),
        (
            "oversized-generations",
            {**base, "budget": {"generations": 90_000}},
            ["body", "budget", "generations"],
        ),
        (
            "budget-out-of-range",
            {**base, "budget": {"generations": 0}},
            ["body", "budget", "generations"],
        ),
        ("bad-seed", {**base, "seed": -1}, ["body", "seed"]),
        ("bad-optimizer", {**base, "optimizer": {"kind": "sgd"}}, ["body", "optimizer", "kind"]),
        ("not-an-object", [1, 2], ["body"]),
    ]


@pytest.mark.parametrize(
    ("body", "loc"), [c[1:] for c in bad_job_cases()], ids=[c[0] for c in bad_job_cases()]
)
def test_bad_job_is_422_naming_the_field_and_stores_nothing(
    client: TestClient,
    ctx: ApiContext,
    alice: dict[str, str],
    sent: list[str],
    body: Any,
    loc: list[Any],
) -> None:
    before = row_counts(ctx)
    r = client.post(f"{API}/jobs", json=body, headers=alice)
    assert loc in locs(r), r.json()
    assert row_counts(ctx) == before and sent == []


def test_oversized_population_names_the_parameter(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], sent: list[str]
) -> None:
    limit = ctx.settings.max_population
    for kind in KINDS:
        opt = studies()[kind].default_optimizer
        key = next(k for k in ("pop_size", "n_samples", "n_subproblems") if k in opt["params"])
        params = {**opt["params"], key: limit + 1}
        body = {"problem": {"kind": kind}, "optimizer": {"kind": opt["kind"], "params": params}}
        r = client.post(f"{API}/jobs", json=body, headers=alice)
        assert ["body", "optimizer", "params", key] in locs(r), r.json()
    assert sent == [] and row_counts(ctx)["jobs"] == 0


def test_malformed_json_names_the_position(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    r = client.post(
        f"{API}/jobs",
        content=b'{"problem": {"kind": }',
        headers={**alice, "content-type": "application/json"},
    )
    assert r.status_code == 422
    (err,) = r.json()["detail"]
    assert err["type"] == "json_invalid" and err["loc"] == ["body", 21]
    assert row_counts(ctx)["jobs"] == 0


def test_body_too_large_is_413(client: TestClient, ctx: ApiContext, alice: dict[str, str]) -> None:
    big = {"problem": {"kind": KINDS[0]}, "name": "x" * (3 * 1024 * 1024)}
    r = client.post(f"{API}/jobs", json=big, headers=alice)
    assert r.status_code == 413 and "limit" in r.json()["detail"]

    def chunks() -> Any:  # no Content-Length: counted while streaming
        for _ in range(40):
            yield b" " * 100_000

    r = client.post(
        f"{API}/jobs", content=chunks(), headers={**alice, "content-type": "application/json"}
    )
    assert r.status_code == 413
    assert row_counts(ctx)["jobs"] == 0


def test_auth_missing_or_invalid_key_is_401(client: TestClient, ctx: ApiContext) -> None:
    body = {"problem": {"kind": KINDS[0]}}
    for headers in ({}, {"X-API-Key": "lgo_not-a-key"}, {"X-API-Key": ""}):
        r = client.post(f"{API}/jobs", json=body, headers=headers)
        assert r.status_code == 401 and isinstance(r.json()["detail"], str)
        assert client.get(f"{API}/jobs", headers=headers).status_code == 401
        assert client.get(f"{API}/robots", headers=headers).status_code == 401
        assert client.get(f"{API}/sweeps", headers=headers).status_code == 401
        assert client.get(f"{API}/catalog", headers=headers).status_code == 401
    assert row_counts(ctx)["jobs"] == 0


def test_lifecycle_read_back(client: TestClient, ctx: ApiContext, alice: dict[str, str]) -> None:
    job = submit(client, alice, {"problem": {"kind": KINDS[0]}})
    jid = job["id"]
    r = client.get(f"{API}/jobs/{jid}/result", headers=alice)
    assert r.status_code == 404 and "queued" in r.json()["detail"]
    r = client.get(f"{API}/jobs/{jid}/recording", headers=alice)
    assert r.status_code == 404 and "no recording" in r.json()["detail"]

    finish_like_a_worker(ctx, jid, generations=3, n_pareto=300)

    got = client.get(f"{API}/jobs/{jid}", headers=alice).json()
    assert got["status"] == "succeeded" and got["progress"] == 1.0
    assert got["generation"] == got["total_generations"] == job["total_generations"]
    assert got["attempts"] == 1
    assert got["best_objective"] == [0.25, 2.0]
    assert got["started_at"] and got["finished_at"]

    result = client.get(f"{API}/jobs/{jid}/result", headers=alice).json()
    assert result["objective_names"] == ["energy", "time"]
    assert result["objectives"]["values"] == {"energy": 1.5, "time": 2.0}
    assert result["metrics"]["energy_J"] == 1.5
    assert result["baselines"] == [
        {"name": "parabolic", "metrics": {"energy_J": 3.0}, "feasible": None, "violations": []}
    ]  # (a baseline stored without its verdict: not checked)
    assert result["feasible"] is None and result["violations"] == [] and result["task"] is None
    assert [a["kind"] for a in result["artifacts"]] == ["recording"]

    t0 = time.perf_counter()
    full = client.get(f"{API}/jobs/{jid}/pareto?limit=1000", headers=alice)
    assert time.perf_counter() - t0 < 1.0
    assert full.json()["total"] == 300 and len(full.json()["items"]) == 300
    assert full.json()["objective_names"] == ["energy", "time"]
    page = client.get(f"{API}/jobs/{jid}/pareto?limit=100&offset=250", headers=alice).json()
    assert [p["index"] for p in page["items"]] == list(range(250, 300))
    assert page["items"][0]["objectives"] == [250.0, 50.0]

    gens = client.get(f"{API}/jobs/{jid}/generations", headers=alice).json()
    assert [g["generation"] for g in gens["items"]] == [0, 1, 2, 3]
    assert gens["next_after"] == 3
    later = client.get(f"{API}/jobs/{jid}/generations?after=1&limit=1", headers=alice).json()
    assert [g["generation"] for g in later["items"]] == [2] and later["next_after"] == 2

    rec = client.get(f"{API}/jobs/{jid}/recording", headers=alice)
    assert rec.status_code == 200
    assert rec.headers["content-type"] == "application/octet-stream"
    assert rec.content == b"RRF2-fake-recording"

    # a corrupted file is refused, not served
    rel = result["artifacts"][0]
    path = next(ctx.settings.artifact_dir.rglob("recording.rrd"))
    path.write_bytes(b"tampered")
    bad = client.get(f"{API}/jobs/{jid}/recording", headers=alice)
    assert bad.status_code == 500 and "corrupted" in bad.json()["detail"]
    assert rel["sha256"] in bad.json()["detail"]
    path.unlink()
    gone = client.get(f"{API}/jobs/{jid}/recording", headers=alice)
    assert gone.status_code == 404 and "missing" in gone.json()["detail"]  # never a 500

    r = client.post(f"{API}/jobs/{jid}/cancel", headers=alice)
    assert r.status_code == 409 and "succeeded" in r.json()["detail"]


def test_recording_disabled_or_missing(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    off = submit(client, alice, {"problem": {"kind": KINDS[0]}, "record": False})
    finish_like_a_worker(ctx, off["id"], recording=None, n_pareto=0)
    r = client.get(f"{API}/jobs/{off['id']}/recording", headers=alice)
    assert r.status_code == 404 and "record: false" in r.json()["detail"]
    on = submit(client, alice, {"problem": {"kind": KINDS[0]}})
    finish_like_a_worker(ctx, on["id"], recording=None, n_pareto=0)
    r = client.get(f"{API}/jobs/{on['id']}/recording", headers=alice)
    assert r.status_code == 404 and "no recording" in r.json()["detail"]
    pareto = client.get(f"{API}/jobs/{on['id']}/pareto", headers=alice).json()
    assert pareto["items"] == [] and pareto["total"] == 0


def test_failed_job_shows_its_error(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    jid = submit(client, alice, {"problem": {"kind": KINDS[0]}})["id"]
    with ctx.write() as s:
        claim_job(s, jid, "w", 60.0)
        fail_job(s, jid, "w", "the obstacle intersects the start pose: move it")
    got = client.get(f"{API}/jobs/{jid}", headers=alice).json()
    assert got["status"] == "failed" and "obstacle" in got["error"]
    r = client.get(f"{API}/jobs/{jid}/result", headers=alice)
    assert r.status_code == 404 and "obstacle" in r.json()["detail"]


def test_cancel(client: TestClient, ctx: ApiContext, alice: dict[str, str]) -> None:
    queued = submit(client, alice, {"problem": {"kind": KINDS[0]}})["id"]
    r = client.post(f"{API}/jobs/{queued}/cancel", headers=alice)
    assert r.status_code == 202 and r.json()["status"] == "cancelled"
    running = submit(client, alice, {"problem": {"kind": KINDS[0]}})["id"]
    with ctx.write() as s:
        claim_job(s, running, "w", 60.0)
    r = client.post(f"{API}/jobs/{running}/cancel", headers=alice)
    assert r.status_code == 202
    assert r.json()["status"] == "running" and r.json()["cancel_requested"] is True
    r = client.post(f"{API}/jobs/{queued}/cancel", headers=alice)
    assert r.status_code == 409
    assert client.post(f"{API}/jobs/nope/cancel", headers=alice).status_code == 404


def test_broker_down_at_submit_keeps_the_job_queued_and_due(
    settings: Any, ctx: ApiContext, alice: dict[str, str]
) -> None:
    """An accepted job is never lost: with the broker down the job stays queued and due, and
    the dispatcher sends it once the broker answers (before: cancelled with a 503)."""
    from services.api.app import create_app
    from services.store.dispatcher import dispatch_pass

    def broken(_job_id: str) -> None:
        raise ConnectionError("broker down")

    with TestClient(create_app(settings, enqueue=broken)) as c:
        r = c.post(f"{API}/jobs", json={"problem": {"kind": KINDS[0]}}, headers=alice)
        assert r.status_code == 202
        job_id = r.json()["id"]
        jobs = c.get(f"{API}/jobs", headers=alice).json()["items"]
    assert [j["status"] for j in jobs] == ["queued"]
    sent: list[str] = []
    later = datetime.now(UTC) + timedelta(seconds=settings.dispatch_period_s + 1)
    report = dispatch_pass(
        sent.append, lambda: 0, actor="t", settings=settings, now=later, bind=ctx.session_factory
    )
    assert report.leader and sent == [job_id]


def test_another_key_gets_404_everywhere(
    client: TestClient, ctx: ApiContext, alice: dict[str, str], bob: dict[str, str]
) -> None:
    jid = submit(client, alice, {"problem": {"kind": KINDS[0]}})["id"]
    finish_like_a_worker(ctx, jid, n_pareto=5)
    for path in ("", "/result", "/pareto", "/generations", "/recording"):
        r = client.get(f"{API}/jobs/{jid}{path}", headers=bob)
        assert r.status_code == 404, path
        assert jid in r.json()["detail"] and "energy" not in r.text
    assert client.post(f"{API}/jobs/{jid}/cancel", headers=bob).status_code == 404
    assert client.get(f"{API}/jobs", headers=bob).json() == {
        "items": [],
        "total": 0,
        "total_exact": True,
        "limit": 50,
        "offset": 0,
    }
    # bob cannot run alice's stored robot either: it is unknown to him
    kind, spec = serial_study()
    rid = client.post(f"{API}/robots", json={"name": "r", "spec": spec}, headers=alice).json()["id"]
    r = client.post(f"{API}/jobs", json={"problem": {"kind": kind}, "robot": rid}, headers=bob)
    assert locs(r) == [["body", "robot"]]


def test_list_jobs_filters_and_pagination(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    ids = [
        submit(client, alice, {"problem": {"kind": KINDS[0]}, "seed": i})["id"] for i in range(5)
    ]
    client.post(f"{API}/jobs/{ids[0]}/cancel", headers=alice)
    everything = client.get(f"{API}/jobs", headers=alice).json()
    assert everything["total"] == 5
    assert [j["id"] for j in everything["items"]] == ids[::-1]  # newest first
    page = client.get(f"{API}/jobs?limit=2&offset=1", headers=alice).json()
    assert [j["id"] for j in page["items"]] == ids[::-1][1:3]
    cancelled = client.get(f"{API}/jobs?status=cancelled", headers=alice).json()
    assert [j["id"] for j in cancelled["items"]] == [ids[0]]
    both = client.get(f"{API}/jobs?status=cancelled&status=queued", headers=alice).json()
    assert both["total"] == 5
    assert client.get(f"{API}/jobs?status=bogus", headers=alice).status_code == 422
    assert client.get(f"{API}/jobs?sweep_id=none", headers=alice).json()["total"] == 0
    assert client.get(f"{API}/jobs?limit=1001", headers=alice).status_code == 422


def test_list_jobs_says_when_its_count_stopped_at_the_cap(
    client: TestClient, alice: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``total`` is counted up to ``COUNT_CAP + 1``; ``total_exact`` says which it is."""
    from services.api.routes import jobs as job_routes
    from services.store import repository

    for i in range(4):
        submit(client, alice, {"problem": {"kind": KINDS[0]}, "seed": 100 + i})
    exact = client.get(f"{API}/jobs", headers=alice).json()
    assert exact["total_exact"] is True and exact["total"] >= 4
    for module in (job_routes, repository):
        monkeypatch.setattr(module, "COUNT_CAP", 2)
    capped = client.get(f"{API}/jobs?limit=1", headers=alice).json()
    assert capped["total"] == 3 and capped["total_exact"] is False


def test_keys_are_isolated_by_listing(client: TestClient, ctx: ApiContext) -> None:
    raw, _ = new_key(ctx, "carol")
    headers = {"X-API-Key": raw}
    submit(client, headers, {"problem": {"kind": KINDS[0]}})
    assert client.get(f"{API}/jobs", headers=headers).json()["total"] == 1
