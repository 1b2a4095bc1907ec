"""Submissions are validated in a validation process, one at a time per API key (issue 22
item 4): the check really runs in another process, a key's second concurrent submission gets
429 + Retry-After while its first is validated, too many admitted gets 503, and a validation
process that dies or overruns its time gives a 422 at the robot — and the next request works;
and a large body costs more request-rate tokens.

The probes below replace the pool's job check (``validation_pool._check_job``); they are
module-level functions, so the validation process imports them from this module by name.
"""

from __future__ import annotations

import functools
import os
import re
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from api_helpers import dh_spec, new_key
from fastapi import HTTPException
from fastapi.testclient import TestClient

from services.api import validation_pool
from services.api.app import create_app
from services.api.errors import invalid
from services.api.rate_limit import COST_BYTES, RateLimiter, request_cost
from services.api.validation import CheckedJob, check_job_spec
from services.api.validation_pool import ValidationPool
from services.store.settings import Settings
from tests.patience import Patience

API = "/api/v1"
JOB = {"problem": {"kind": "swing_energy"}, "robot": "calderon_leg", "budget": {"generations": 2}}

# --------------------------------------------------------------------------- probes (in the child)


def _report_pid(doc: Any, table: dict[str, Any], settings: Settings) -> CheckedJob:
    raise invalid(("body", "robot"), f"validated by pid {os.getpid()}")


def _crash(doc: Any, table: dict[str, Any], settings: Settings) -> CheckedJob:
    os._exit(1)


def _blocking(
    started: str, release: str, doc: Any, table: dict[str, Any], settings: Settings
) -> CheckedJob:
    """Say it started (a file), then wait for the test's go (another file) and check."""
    Path(started).touch()
    patience = Patience(120)
    while not Path(release).exists() and not patience.expired():
        time.sleep(0.01)
    return check_job_spec(doc, settings=settings, lookup=table.get)


# --------------------------------------------------------------------------- helpers


def _wait_for(path: Path) -> None:
    patience = Patience(120)
    while not path.exists():
        assert not patience.expired(), f"the validation never started ({patience})"
        time.sleep(0.01)


def _error(response: Any) -> dict[str, Any]:
    assert response.status_code == 422, response.text
    (err,) = response.json()["detail"]
    return dict(err)


@pytest.fixture
def impatient(settings: Settings) -> Iterator[tuple[TestClient, TestClient, dict[str, str]]]:
    """An app whose validations may run 1 s at most, a patient app over the same store and the
    same validation processes (the next request must work, however busy the machine), and an
    API key's headers."""
    app = create_app(settings.with_overrides(validation_timeout_s=1.0), enqueue=lambda _j: None)
    patient = create_app(settings, enqueue=lambda _j: None)
    with TestClient(app) as c, TestClient(patient) as p:
        yield c, p, {"X-API-Key": new_key(app.state.context, "alice")[0]}


# --------------------------------------------------------------------------- tests


def test_validation_runs_in_another_process(
    client: TestClient, alice: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(validation_pool, "_check_job", _report_pid)
    err = _error(client.post(f"{API}/jobs", json=JOB, headers=alice))
    assert err["loc"] == ["body", "robot"]
    match = re.fullmatch(r"validated by pid (\d+)", err["msg"])
    assert match is not None, err
    assert int(match.group(1)) != os.getpid()


@pytest.mark.slow  # the quick lane keeps test_validation_runs_in_another_process
def test_a_crashing_child_is_a_422_and_the_next_request_works(
    client: TestClient, alice: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    with monkeypatch.context() as patch:
        patch.setattr(validation_pool, "_check_job", _crash)
        err = _error(client.post(f"{API}/jobs", json=JOB, headers=alice))
    assert err["loc"] == ["body", "robot"] and err["type"] == "model_not_validated", err
    assert "could not be validated" in err["msg"] and "died" in err["msg"]
    r = client.post(f"{API}/jobs", json=JOB, headers=alice)
    assert r.status_code == 202, r.text


@pytest.mark.slow  # the quick lane keeps test_validation_runs_in_another_process
def test_an_overrunning_child_is_killed_a_422_and_the_next_request_works(
    impatient: tuple[TestClient, TestClient, dict[str, str]],
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
) -> None:
    slow_client, patient_client, alice = impatient
    never = functools.partial(_blocking, str(tmp_path / "started"), str(tmp_path / "never"))
    with monkeypatch.context() as patch:
        patch.setattr(validation_pool, "_check_job", never)
        err = _error(slow_client.post(f"{API}/jobs", json=JOB, headers=alice))
    assert err["loc"] == ["body", "robot"] and err["type"] == "model_not_validated", err
    assert "longer than 1 s" in err["msg"]
    r = patient_client.post(f"{API}/jobs", json=JOB, headers=alice)
    assert r.status_code == 202, r.text


def test_same_key_second_concurrent_submission_gets_429(
    client: TestClient,
    alice: dict[str, str],
    bob: dict[str, str],
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
) -> None:
    started, release = tmp_path / "started", tmp_path / "release"
    monkeypatch.setattr(
        validation_pool, "_check_job", functools.partial(_blocking, str(started), str(release))
    )
    first: list[Any] = []
    thread = threading.Thread(
        target=lambda: first.append(client.post(f"{API}/jobs", json=JOB, headers=alice))
    )
    thread.start()
    try:
        _wait_for(started)  # alice's first submission is being validated now
        for path, body in (("/jobs", JOB), ("/robots/validate", {"spec": dh_spec()})):
            r = client.post(f"{API}{path}", json=body, headers=alice)
            assert r.status_code == 429, r.text
            assert int(r.headers["retry-after"]) >= 1
            assert "one at a time per key" in r.json()["detail"]
    finally:
        release.touch()
        thread.join()
    assert first[0].status_code == 202, first[0].text
    r = client.post(f"{API}/robots/validate", json={"spec": dh_spec()}, headers=bob)
    assert r.status_code == 200, r.text


def test_admission_one_per_key_and_a_bounded_number_overall() -> None:
    gate = ValidationPool(1)
    gate.admit("alice")
    with pytest.raises(HTTPException) as exc:
        gate.admit("alice")
    assert exc.value.status_code == 429 and exc.value.headers is not None
    assert int(exc.value.headers["Retry-After"]) >= 1
    others = [f"key{i}" for i in range(gate.max_admitted - 1)]
    for key in others:
        gate.admit(key)
    with pytest.raises(HTTPException) as exc:
        gate.admit("carol")
    assert exc.value.status_code == 503 and exc.value.headers is not None
    assert int(exc.value.headers["Retry-After"]) >= 1
    gate.release("alice")
    gate.admit("carol")  # in alice's place
    with pytest.raises(HTTPException) as exc:
        gate.admit("alice")
    assert exc.value.status_code == 503


def test_a_large_body_costs_more_rate_tokens() -> None:
    assert request_cost(None) == 1 and request_cost("bogus") == 1
    assert request_cost(str(COST_BYTES - 1)) == 1 and request_cost(str(2 * COST_BYTES)) == 3
    limiter = RateLimiter(rate_per_s=1.0, burst=10)
    assert limiter.acquire("k", now=0.0, cost=3) == 0.0  # 7 tokens left
    assert limiter.acquire("k", now=0.0, cost=8) == 1.0  # one token short: 1 s at 1/s
    assert limiter.acquire("k", now=3.0, cost=50) == 0.0  # capped at the burst (all 10)


def test_no_transaction_stays_open_while_a_submission_is_validated(
    client: TestClient, alice: dict[str, str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A validation may take seconds: the routes read what it needs (the stored robots a spec
    names) in a short transaction, then validate with none open (an open read would pin a
    PostgreSQL connection and hold back SQLite's checkpoints for that long)."""
    import contextlib

    from services.api.routes import jobs as jobs_route
    from services.api.routes import sweeps as sweeps_route

    ctx = client.app.state.context  # type: ignore[attr-defined]
    open_now = [0]
    seen: list[int] = []

    def counted(scope: Any) -> Any:
        @contextlib.contextmanager
        def wrapper() -> Iterator[Any]:
            open_now[0] += 1
            try:
                with scope() as session:
                    yield session
            finally:
                open_now[0] -= 1

        return wrapper

    monkeypatch.setattr(ctx, "read", counted(ctx.read))
    monkeypatch.setattr(ctx, "write", counted(ctx.write))

    def watched(check: Any) -> Any:
        def run(*args: Any, **kwargs: Any) -> Any:
            seen.append(open_now[0])
            return check(*args, **kwargs)

        return run

    monkeypatch.setattr(jobs_route, "check_job", watched(jobs_route.check_job))
    monkeypatch.setattr(sweeps_route, "check_sweep", watched(sweeps_route.check_sweep))
    r = client.post(f"{API}/jobs", json=JOB, headers=alice)
    assert r.status_code == 202, r.text
    sweep = {"base": JOB, "seeds": [1, 2]}
    r = client.post(f"{API}/sweeps", json=sweep, headers=alice)
    assert r.status_code == 202, r.text
    assert seen == [0, 0]
