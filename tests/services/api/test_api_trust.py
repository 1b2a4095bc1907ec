"""Issue 8 on the API: idempotent submission (defect 11), quotas and rate limits, sweeps that
store their spec once (defect 9), deleting jobs, and key roles, expiry and revocation
(defect 12)."""

from __future__ import annotations

import json
from datetime import timedelta
from typing import Any

from api_helpers import new_key
from fastapi.testclient import TestClient
from sqlalchemy import func, select

from legcore.studies.registry import studies
from services.api.app import create_app
from services.api.deps import ApiContext
from services.store import api_keys
from services.store import repository as repo
from services.store.keys import generate_api_key
from services.store.lifecycle import claim_job, fail_job
from services.store.settings import Settings
from services.store.states import KeyRole
from services.store.tables import JOBS, SWEEPS
from tests.services.api.test_api_jobs import serial_study

API = "/api/v1"
KIND = sorted(studies())[0]


def _job(extra: dict[str, Any] | None = None) -> dict[str, Any]:
    return {"problem": {"kind": KIND}, **(extra or {})}


# ----------------------------------------------------------------------- idempotency keys


def test_same_idempotency_key_returns_the_same_job(
    client: TestClient, alice: dict[str, str], sent: list[str]
) -> None:
    """Defect 11: a client whose POST was cut off retries with the same key and gets the job
    it created, not a second one."""
    h = {**alice, "Idempotency-Key": "retry-me-1"}
    first = client.post(f"{API}/jobs", json=_job(), headers=h)
    again = client.post(f"{API}/jobs", json=_job(), headers=h)
    assert first.status_code == again.status_code == 202
    assert first.json()["id"] == again.json()["id"]
    assert again.headers.get("Idempotent-Replayed") == "true"
    assert client.get(f"{API}/jobs", headers=alice).json()["total"] == 1
    assert sent == [first.json()["id"]]  # one message


def test_idempotency_key_reused_for_another_body_is_422(
    client: TestClient, alice: dict[str, str]
) -> None:
    h = {**alice, "Idempotency-Key": "k-2"}
    assert client.post(f"{API}/jobs", json=_job({"seed": 1}), headers=h).status_code == 202
    r = client.post(f"{API}/jobs", json=_job({"seed": 2}), headers=h)
    assert r.status_code == 422
    assert r.json()["detail"][0]["loc"] == ["header", "Idempotency-Key"]
    assert "different request" in r.json()["detail"][0]["msg"]


def test_idempotency_keys_are_per_api_key(
    client: TestClient, alice: dict[str, str], bob: dict[str, str]
) -> None:
    a = client.post(f"{API}/jobs", json=_job(), headers={**alice, "Idempotency-Key": "same"})
    b = client.post(f"{API}/jobs", json=_job(), headers={**bob, "Idempotency-Key": "same"})
    assert a.status_code == b.status_code == 202 and a.json()["id"] != b.json()["id"]


def test_sweep_idempotency(client: TestClient, alice: dict[str, str], sent: list[str]) -> None:
    body = {"base": _job(), "seeds": [1, 2, 3]}
    h = {**alice, "Idempotency-Key": "sweep-1"}
    first = client.post(f"{API}/sweeps", json=body, headers=h)
    again = client.post(f"{API}/sweeps", json=body, headers=h)
    assert first.status_code == again.status_code == 202
    assert first.json()["id"] == again.json()["id"]
    assert first.json()["job_ids"] == again.json()["job_ids"]
    assert len(sent) == 3
    bad = client.post(f"{API}/jobs", json=_job(), headers=h)  # a sweep's key on /jobs
    assert bad.status_code == 422


# ----------------------------------------------------------------------- sweeps store once


def test_sweep_stores_its_spec_once(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    """Defect 9: a 201 KB sweep stored 394 MB — the full spec, inline URDF included, copied
    into every job row. Now the base is stored once and each job keeps only its overrides."""
    kind, robot = serial_study()
    robot["description"] = "x" * 3000  # a bulky inline robot, like a pasted URDF
    body = {"base": {"problem": {"kind": kind}, "robot": robot}, "seeds": list(range(12))}
    r = client.post(f"{API}/sweeps", json=body, headers=alice)
    assert r.status_code == 202, r.text
    base_bytes = len(json.dumps(body["base"]))
    with ctx.read() as s:
        specs = s.execute(select(JOBS.c.spec, JOBS.c.overrides)).all()
        assert s.execute(select(func.count()).select_from(SWEEPS)).scalar_one() == 1
    assert all(spec is None for spec, _ in specs)
    assert all(len(json.dumps(o)) < 100 for _, o in specs)
    stored = sum(len(json.dumps(o)) for _, o in specs)
    assert stored < base_bytes  # twelve jobs cost less than one copy of the base
    # each job still reads back its full spec
    job_id = r.json()["job_ids"][5]
    detail = client.get(f"{API}/jobs/{job_id}", headers=alice).json()
    assert detail["spec"]["seed"] == 5 and detail["kind"] == kind
    assert detail["spec"]["robot"]["description"] == robot["description"]
    rows = client.get(f"{API}/sweeps/{r.json()['id']}", headers=alice).json()["table"]["items"]
    assert [row["overrides"]["seed"] for row in rows] == list(range(12))


# ----------------------------------------------------------------------- quotas and limits


def _app(settings: Settings, **overrides: Any) -> TestClient:
    return TestClient(create_app(settings.with_overrides(**overrides), enqueue=lambda _i: None))


def test_active_jobs_quota_is_429_with_what_to_do(settings: Settings) -> None:
    with _app(settings, quota_active_jobs=2) as c:
        ctx: ApiContext = c.app.state.context  # type: ignore[attr-defined]
        h = {"X-API-Key": new_key(ctx, "q")[0]}
        for _ in range(2):
            assert c.post(f"{API}/jobs", json=_job(), headers=h).status_code == 202
        r = c.post(f"{API}/jobs", json=_job(), headers=h)
        assert r.status_code == 429
        assert "2 jobs queued or running" in r.json()["detail"] and "cancel" in r.json()["detail"]
        r = c.post(f"{API}/sweeps", json={"base": _job(), "seeds": [1, 2]}, headers=h)
        assert r.status_code == 429
        me = c.get(f"{API}/keys/me", headers=h).json()
        assert me["active_jobs"] == 2 and me["max_active_jobs"] == 2


def test_storage_quota_and_delete_frees_it(settings: Settings) -> None:
    with _app(settings, quota_storage_bytes=200) as c:
        ctx: ApiContext = c.app.state.context  # type: ignore[attr-defined]
        h = {"X-API-Key": new_key(ctx, "s")[0]}
        job_id = c.post(f"{API}/jobs", json=_job(), headers=h).json()["id"]
        big = _job({"name": "n" * 150})
        r = c.post(f"{API}/jobs", json=big, headers=h)
        assert r.status_code == 429 and "DELETE /jobs" in r.json()["detail"]
        assert c.delete(f"{API}/jobs/{job_id}", headers=h).status_code == 409  # queued
        with ctx.write() as s:
            claim_job(s, job_id, "w", 60.0)
            fail_job(s, job_id, "w", "x")
        assert c.delete(f"{API}/jobs/{job_id}", headers=h).status_code == 204
        assert c.get(f"{API}/jobs/{job_id}", headers=h).status_code == 404
        assert c.post(f"{API}/jobs", json=big, headers=h).status_code == 202


def test_cpu_quota_per_hour(settings: Settings) -> None:
    from services.store.quotas import add_cpu_seconds

    with _app(settings, quota_cpu_seconds_per_hour=10.0) as c:
        ctx: ApiContext = c.app.state.context  # type: ignore[attr-defined]
        h = {"X-API-Key": new_key(ctx, "c")[0]}
        job_id = c.post(f"{API}/jobs", json=_job(), headers=h).json()["id"]
        with ctx.write() as s:
            add_cpu_seconds(s, job_id, 11.0)
        r = c.post(f"{API}/jobs", json=_job(), headers=h)
        assert r.status_code == 429 and "CPU seconds" in r.json()["detail"]
        assert c.get(f"{API}/keys/me", headers=h).json()["cpu_seconds_this_hour"] == 11.0


def test_rate_limit_is_429_with_retry_after(settings: Settings) -> None:
    with _app(settings, rate_limit_per_s=0.01, rate_limit_burst=3) as c:
        ctx: ApiContext = c.app.state.context  # type: ignore[attr-defined]
        h = {"X-API-Key": new_key(ctx, "r")[0]}
        codes = [c.get(f"{API}/jobs", headers=h).status_code for _ in range(4)]
        assert codes == [200, 200, 200, 429]
        r = c.get(f"{API}/jobs", headers=h)
        assert int(r.headers["Retry-After"]) >= 1 and "per second" in r.json()["detail"]
        other = {"X-API-Key": new_key(ctx, "r2")[0]}
        assert c.get(f"{API}/jobs", headers=other).status_code == 200  # per key


# ----------------------------------------------------------------------- keys


def _admin(ctx: ApiContext) -> dict[str, str]:
    raw, key_hash = generate_api_key()
    with ctx.write() as s:
        api_keys.create_api_key(s, name="root", key_hash=key_hash, role=KeyRole.ADMIN)
    return {"X-API-Key": raw}


def test_admin_creates_lists_and_revokes_keys(
    client: TestClient, ctx: ApiContext, alice: dict[str, str]
) -> None:
    admin = _admin(ctx)
    assert client.get(f"{API}/keys", headers=alice).status_code == 403
    assert client.post(f"{API}/keys", json={"name": "x"}, headers=alice).status_code == 403
    r = client.post(f"{API}/keys", json={"name": "carol", "max_active_jobs": 5}, headers=admin)
    assert r.status_code == 201 and r.json()["key"].startswith("lgo_")
    carol = {"X-API-Key": r.json()["key"]}
    assert client.get(f"{API}/keys/me", headers=carol).json()["max_active_jobs"] == 5
    names = [k["name"] for k in client.get(f"{API}/keys", headers=admin).json()["items"]]
    assert {"alice", "root", "carol"} <= set(names)
    r = client.post(f"{API}/keys/{r.json()['id']}/revoke", headers=admin)
    assert r.status_code == 200 and r.json()["revoked_at"]
    r = client.get(f"{API}/jobs", headers=carol)
    assert r.status_code == 401 and "revoked" in r.json()["detail"]


def test_expired_key_is_refused(client: TestClient, ctx: ApiContext) -> None:
    raw, key_hash = generate_api_key()
    with ctx.write() as s:
        api_keys.create_api_key(
            s, name="old", key_hash=key_hash, expires_at=repo.now_utc() - timedelta(seconds=1)
        )
    r = client.get(f"{API}/jobs", headers={"X-API-Key": raw})
    assert r.status_code == 401 and "expired" in r.json()["detail"]


def test_client_retry_after_a_lost_answer_creates_one_job(
    client: TestClient, alice: dict[str, str], sent: list[str]
) -> None:
    """Defect 11 from the client's side: the first answer is lost after the server created the
    job; ``Client.submit`` retries with the same Idempotency-Key and gets that job."""
    import httpx

    from services.client import Client

    inner = client._transport  # type: ignore[attr-defined]
    calls = {"n": 0}

    class LosesFirstAnswer(httpx.BaseTransport):
        def handle_request(self, request: httpx.Request) -> httpx.Response:
            response = inner.handle_request(request)
            calls["n"] += 1
            if calls["n"] == 1:
                raise httpx.ReadError("connection reset", request=request)
            return response

    c = Client("http://testserver", alice["X-API-Key"])
    c.http = httpx.Client(
        base_url="http://testserver/api/v1", headers=c.http.headers, transport=LosesFirstAnswer()
    )
    job = c.submit(_job())
    assert calls["n"] == 2 and len(sent) == 1 and sent[0] == job["id"]
    assert client.get(f"{API}/jobs", headers=alice).json()["total"] == 1


def test_client_waits_out_a_short_429_and_not_a_quota(
    client: TestClient, alice: dict[str, str], sent: list[str], monkeypatch: Any
) -> None:
    """A timed-out submission's retry finds the first attempt still being validated (429,
    ``Retry-After: 1``): ``Client.submit`` waits and asks again with the same Idempotency-Key,
    getting the one job. A 429 with a quota's ``Retry-After`` (30 s) is raised at once."""
    import httpx

    import services.client as C

    inner = client._transport  # type: ignore[attr-defined]
    waits: list[float] = []
    monkeypatch.setattr(C.time, "sleep", waits.append)
    answers = {"retry_after": "1", "n": 0}

    class BusyFirst(httpx.BaseTransport):
        def handle_request(self, request: httpx.Request) -> httpx.Response:
            answers["n"] += 1
            if answers["n"] == 1:
                return httpx.Response(429, json={"detail": "validating"},
                                      headers={"Retry-After": answers["retry_after"]})  # fmt: skip
            return inner.handle_request(request)

    c = C.Client("http://testserver", alice["X-API-Key"])
    c.http = httpx.Client(
        base_url="http://testserver/api/v1", headers=c.http.headers, transport=BusyFirst()
    )
    job = c.submit(_job())
    assert waits == [1.0] and answers["n"] == 2 and sent == [job["id"]]
    # a validation slower than a few Retry-Afters (a busy machine): it keeps coming back
    busy = {"left": C.CREATE_ATTEMPTS + 3}

    class BusyLong(httpx.BaseTransport):
        def handle_request(self, request: httpx.Request) -> httpx.Response:
            if busy["left"] > 0:
                busy["left"] -= 1
                return httpx.Response(429, json={"detail": "validating"},
                                      headers={"Retry-After": "2"})  # fmt: skip
            return inner.handle_request(request)

    c.http = httpx.Client(
        base_url="http://testserver/api/v1", headers=c.http.headers, transport=BusyLong()
    )
    again = c.submit(_job({"seed": 6}))
    assert waits[1:] == [2.0] * (C.CREATE_ATTEMPTS + 3) and sent[-1] == again["id"]
    del waits[1:]
    c.http = httpx.Client(
        base_url="http://testserver/api/v1", headers=c.http.headers, transport=BusyFirst()
    )
    answers.update(retry_after="30", n=0)
    try:
        c.submit(_job({"seed": 5}))
    except C.ApiError as exc:
        assert exc.status == 429 and exc.retry_after == 30.0
    else:
        raise AssertionError("a quota's 429 must reach the caller")
    assert answers["n"] == 1 and waits == [1.0]
