"""Issue 12: a job whose predicted peak memory exceeds the per-worker limit is a 422 that names
the population and samples fields, the predicted MiB and the limit."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest
from api_helpers import locs
from fastapi.testclient import TestClient

from legcore.memory import predicted_peak_bytes
from legcore.runner import job_size, prepare
from services.api.app import create_app
from services.store.settings import Settings

API = "/api/v1"
SPEC: dict[str, Any] = {
    "problem": {"kind": "swing_energy", "dt": 0.001},  # 3001 samples
    "optimizer": {"kind": "ga", "params": {"pop_size": 400}},
    "budget": {"generations": 2},
}


@pytest.fixture
def low_client(settings: Settings, sent: list[str]) -> Iterator[TestClient]:
    """An app whose workers may use 400 MiB per job."""
    app = create_app(settings.with_overrides(worker_memory_limit_mb=400), enqueue=sent.append)
    with TestClient(app) as c:
        yield c


def test_settings_check_the_predicted_peak() -> None:
    s = Settings.from_env(env={}, worker_memory_limit_mb=100)
    assert s.check_job_size(10, 10, 10, peak_bytes=100 * 1024**2) is None
    reason = s.check_job_size(10, 10, 10, peak_bytes=150 * 1024**2) or ""
    assert reason.startswith("memory: predicted peak 150 MiB exceeds the per-worker limit 100")
    assert Settings.from_env(env={}).worker_memory_limit_mb == 2048


def test_job_size_carries_the_prediction() -> None:
    prepared = prepare(SPEC)
    size = job_size(prepared)
    assert size.peak_bytes == predicted_peak_bytes(prepared.problem, 400)
    assert size.peak_bytes > 400 * 1024**2


def test_over_the_memory_limit_is_422_naming_the_fields(
    low_client: TestClient, alice: dict[str, str], sent: list[str]
) -> None:
    r = low_client.post(f"{API}/jobs", json=SPEC, headers=alice)
    assert locs(r) == [
        ["body", "optimizer", "params", "pop_size"],
        ["body", "problem"],
    ]
    msg = r.json()["detail"][0]["msg"]
    mib = predicted_peak_bytes(prepare(SPEC).problem, 400) / 1024**2
    assert f"predicted peak {mib:.0f} MiB" in msg
    assert "limit 400 MiB" in msg
    assert "optimizer.params.pop_size = 400" in msg and "3001 samples" in msg
    assert r.json()["detail"][0]["type"] == "job_too_large"
    assert sent == []


def test_within_the_memory_limit_is_accepted(low_client: TestClient, alice: dict[str, str]) -> None:
    small = {
        **SPEC,
        "problem": {"kind": "swing_energy"},
        "optimizer": {"kind": "ga", "params": {"pop_size": 50}},
    }
    r = low_client.post(f"{API}/jobs", json=small, headers=alice)
    assert r.status_code == 202, r.text


def test_default_limit_accepts_the_largest_chunked_job(
    client: TestClient, alice: dict[str, str]
) -> None:
    """Chunked evaluation bounds the peak: 2000 individuals × 6001 samples fit 2 GiB."""
    big = {
        **SPEC,
        "problem": {"kind": "swing_energy", "dt": 0.0005},
        "optimizer": {"kind": "ga", "params": {"pop_size": 2000}},
        "budget": {"generations": 1},
    }
    assert job_size(prepare(big)).peak_bytes < 1024 * 1024**2
    r = client.post(f"{API}/jobs", json=big, headers=alice)
    assert r.status_code == 202, r.text
