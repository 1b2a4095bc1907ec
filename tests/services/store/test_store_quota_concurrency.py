"""Quotas under concurrent submissions (issue 22 item 1): the check and the insert are atomic.

Each submitter runs what ``POST /jobs`` runs — ``quota_refusal`` then ``create_job`` in one
``session_scope(immediate=True)`` — on its own connection. Counting then inserting without a
lock let 12 of 30 concurrent submissions through a limit of 5 on PostgreSQL.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import Engine, func, select, text
from sqlalchemy.pool import NullPool
from store_testdb import requires_postgres

from services.store import create_api_key, create_job, make_engine, session_scope
from services.store.quotas import quota_refusal
from services.store.records import ApiKeyRecord
from services.store.settings import Settings
from services.store.tables import JOBS
from tests.patience import Patience

N_SUBMITTERS = 30
LIMIT = 5
SPEC = {"problem": {"kind": "race"}}
#: Quiet-machine seconds after which a wait counts as a hang (see ``tests.patience``).
HANG_S = 120.0


@pytest.fixture
def own_connections(engine: Engine) -> Iterator[Engine]:
    """An engine on the same database that opens a new connection per session (no pool), so
    every submitter has a connection of its own."""
    eng = make_engine(engine.url.render_as_string(hide_password=False), poolclass=NullPool)
    try:
        yield eng
    finally:
        eng.dispose()


def _settings(tmp_path: Path) -> Settings:
    """Default settings; the tests' limits are the key's own (``api_keys.max_*``)."""
    return Settings.from_env(env={}, data_dir=tmp_path)


def _key(
    engine: Engine, *, max_active_jobs: int | None = None, max_storage_bytes: int | None = None
) -> ApiKeyRecord:
    with session_scope(engine) as s:
        return create_api_key(
            s,
            name="quota",
            key_hash="quota-hash",
            max_active_jobs=max_active_jobs,
            max_storage_bytes=max_storage_bytes,
        )


def _submit(engine: Engine, key: ApiKeyRecord, settings: Settings) -> str | None:
    """One submission as the API makes it: the id of the stored job, or None when refused."""
    with session_scope(engine, immediate=True) as s:
        if quota_refusal(s, key, settings, new_jobs=1, new_bytes=64) is not None:
            return None
        return create_job(s, owner_key_id=key.id, spec=SPEC).id


def _join(threads: list[threading.Thread]) -> None:
    patience = Patience(HANG_S)
    for t in threads:
        while t.is_alive() and not patience.expired():
            t.join(0.05)
        assert not t.is_alive(), f"a submitter still runs after {patience}"


def _stored_jobs(engine: Engine, key_id: str) -> int:
    with session_scope(engine) as s:
        stmt = select(func.count()).select_from(JOBS).where(JOBS.c.owner_key_id == key_id)
        return int(s.execute(stmt).scalar_one())


def test_concurrent_submissions_accept_exactly_the_active_jobs_limit(
    own_connections: Engine, tmp_path: Path
) -> None:
    """30 submitters released at once against a limit of 5: exactly 5 jobs are stored."""
    key = _key(own_connections, max_active_jobs=LIMIT)
    settings = _settings(tmp_path)
    barrier = threading.Barrier(N_SUBMITTERS)
    accepted: list[str] = []
    refused: list[int] = []
    errors: list[BaseException] = []

    def submit(i: int) -> None:
        try:
            barrier.wait()
            job_id = _submit(own_connections, key, settings)
            (refused.append(i) if job_id is None else accepted.append(job_id))
        except BaseException as exc:  # reported below
            errors.append(exc)
            barrier.abort()

    threads = [threading.Thread(target=submit, args=(i,)) for i in range(N_SUBMITTERS)]
    for t in threads:
        t.start()
    _join(threads)
    assert errors == []
    assert (len(accepted), len(refused)) == (LIMIT, N_SUBMITTERS - LIMIT)
    assert _stored_jobs(own_connections, key.id) == LIMIT


def test_concurrent_submissions_respect_the_storage_limit(
    own_connections: Engine, tmp_path: Path
) -> None:
    """The storage quota holds too: 30 submissions of 64 bytes each under 5 × 64 bytes."""
    key = _key(own_connections, max_storage_bytes=LIMIT * 64)
    settings = _settings(tmp_path)
    barrier = threading.Barrier(N_SUBMITTERS)
    accepted: list[str] = []
    errors: list[BaseException] = []

    def submit() -> None:
        try:
            barrier.wait()
            with session_scope(own_connections, immediate=True) as s:
                if quota_refusal(s, key, settings, new_jobs=1, new_bytes=64) is None:
                    # a job whose stored spec is exactly the 64 bytes it asked for
                    spec = {"pad": "x" * 54}
                    accepted.append(create_job(s, owner_key_id=key.id, spec=spec).id)
        except BaseException as exc:  # reported below
            errors.append(exc)
            barrier.abort()

    threads = [threading.Thread(target=submit) for _ in range(N_SUBMITTERS)]
    for t in threads:
        t.start()
    _join(threads)
    assert errors == []
    assert len(accepted) == LIMIT
    assert _stored_jobs(own_connections, key.id) == LIMIT


@requires_postgres
@pytest.mark.parametrize("engine", ["postgresql"], indirect=True)
def test_a_second_submitter_waits_for_the_first_to_commit(
    own_connections: Engine, tmp_path: Path
) -> None:
    """Deterministic form of the race on PostgreSQL: while one transaction has checked the
    quota and not yet committed, a second submission blocks on the key's lock (seen in
    ``pg_stat_activity``) and, once the first commits, is refused — instead of counting the
    same free slot."""
    key = _key(own_connections, max_active_jobs=1)
    settings = _settings(tmp_path)
    second: dict[str, object] = {}
    done = threading.Event()

    def submit_second() -> None:
        try:
            with session_scope(own_connections, immediate=True) as s:
                second["pid"] = s.execute(text("SELECT pg_backend_pid()")).scalar_one()
                started.set()
                refusal = quota_refusal(s, key, settings, new_jobs=1, new_bytes=64)
                second["refused"] = refusal is not None
                if refusal is None:
                    create_job(s, owner_key_id=key.id, spec=SPEC)
        except BaseException as exc:  # reported below
            second["error"] = exc
        finally:
            started.set()
            done.set()

    started = threading.Event()
    with session_scope(own_connections, immediate=True) as first:
        assert quota_refusal(first, key, settings, new_jobs=1, new_bytes=64) is None
        thread = threading.Thread(target=submit_second)
        thread.start()
        started.wait()
        patience = Patience(HANG_S)
        with own_connections.connect() as monitor:
            while not done.is_set() and not patience.expired():
                waiting = monitor.execute(
                    text("SELECT wait_event_type FROM pg_stat_activity WHERE pid = :pid"),
                    {"pid": second.get("pid")},
                ).scalar_one_or_none()
                monitor.commit()  # a fresh snapshot of pg_stat_activity for the next poll
                if waiting == "Lock":
                    break
                done.wait(0.01)
        assert not done.is_set(), f"the second submission did not wait: {second}"
        create_job(first, owner_key_id=key.id, spec=SPEC)
    _join([thread])
    assert "error" not in second, second
    assert second["refused"] is True
    assert _stored_jobs(own_connections, key.id) == 1
