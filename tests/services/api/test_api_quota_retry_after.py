"""Every quota 429 of POST /jobs and POST /sweeps carries ``Retry-After`` in whole seconds
(issue 22 item 1): 30 for active jobs, 60 for storage, the seconds until the next UTC hour for
worker CPU seconds."""

from __future__ import annotations

from typing import Any

from api_helpers import new_key
from fastapi.testclient import TestClient

from legcore.studies.registry import studies
from services.api.app import create_app
from services.api.deps import ApiContext
from services.store.quotas import (
    ACTIVE_JOBS_RETRY_AFTER_S,
    STORAGE_RETRY_AFTER_S,
    add_cpu_seconds,
)
from services.store.settings import Settings

API = "/api/v1"
KIND = sorted(studies())[0]


def _job(extra: dict[str, Any] | None = None) -> dict[str, Any]:
    return {"problem": {"kind": KIND}, **(extra or {})}


def _app(settings: Settings, **overrides: Any) -> TestClient:
    return TestClient(create_app(settings.with_overrides(**overrides), enqueue=lambda _i: None))


def _headers(c: TestClient, name: str) -> tuple[ApiContext, dict[str, str]]:
    ctx: ApiContext = c.app.state.context  # type: ignore[attr-defined]
    return ctx, {"X-API-Key": new_key(ctx, name)[0]}


def _retry_after(response: Any) -> int:
    """The ``Retry-After`` of a quota 429, checked to be a whole number of seconds >= 1."""
    assert response.status_code == 429, response.text
    assert response.json()["detail"].startswith("quota exceeded: ")
    value = response.headers["Retry-After"]
    assert value.isdigit() and int(value) >= 1, value
    return int(value)


def test_active_jobs_quota_429_has_retry_after(settings: Settings) -> None:
    with _app(settings, quota_active_jobs=1) as c:
        _, h = _headers(c, "active")
        assert c.post(f"{API}/jobs", json=_job(), headers=h).status_code == 202
        job = c.post(f"{API}/jobs", json=_job(), headers=h)
        assert _retry_after(job) == ACTIVE_JOBS_RETRY_AFTER_S
        sweep = c.post(f"{API}/sweeps", json={"base": _job(), "seeds": [1, 2]}, headers=h)
        assert _retry_after(sweep) == ACTIVE_JOBS_RETRY_AFTER_S


def test_storage_quota_429_has_retry_after(settings: Settings) -> None:
    with _app(settings, quota_storage_bytes=200) as c:
        _, h = _headers(c, "storage")
        assert c.post(f"{API}/jobs", json=_job(), headers=h).status_code == 202
        r = c.post(f"{API}/jobs", json=_job({"name": "n" * 150}), headers=h)
        assert _retry_after(r) == STORAGE_RETRY_AFTER_S


def test_cpu_quota_429_retries_within_the_hour(settings: Settings) -> None:
    with _app(settings, quota_cpu_seconds_per_hour=10.0) as c:
        ctx, h = _headers(c, "cpu")
        job_id = c.post(f"{API}/jobs", json=_job(), headers=h).json()["id"]
        with ctx.write() as s:
            add_cpu_seconds(s, job_id, 11.0)
        r = c.post(f"{API}/jobs", json=_job(), headers=h)
        assert "CPU seconds" in r.json()["detail"]
        assert _retry_after(r) <= 3600  # the usage resets at the next UTC hour
