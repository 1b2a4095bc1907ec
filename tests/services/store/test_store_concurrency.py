"""Concurrent claims: several threads or processes race for the same jobs; one wins each."""

from __future__ import annotations

import multiprocessing
import threading
from pathlib import Path

from sqlalchemy import Engine
from sqlalchemy.pool import NullPool
from store_testdb import sqlite_url

from services.store import (
    JobRecord,
    JobStatus,
    ResultIn,
    claim_job,
    create_api_key,
    create_job,
    finish_job,
    get_job,
    list_jobs,
    make_engine,
    session_scope,
)
from services.store.tables import Base

N_THREADS = 6
N_JOBS = 5


def _jobs(engine: Engine, n: int) -> list[JobRecord]:
    with session_scope(engine) as s:
        key = create_api_key(s, name="race", key_hash="race-hash")
        return [create_job(s, owner_key_id=key.id, spec={"i": i}) for i in range(n)]


def _race(engine: Engine, job_id: str) -> list[str]:
    """N_THREADS threads claim ``job_id`` at the same moment; the names of the winners."""
    barrier = threading.Barrier(N_THREADS)
    winners: list[str] = []
    errors: list[BaseException] = []

    def race(worker: str) -> None:
        try:
            barrier.wait(timeout=10)
            with session_scope(engine) as s:
                if claim_job(s, job_id, worker, 60.0) is not None:
                    winners.append(worker)
        except BaseException as exc:  # reported below
            errors.append(exc)

    threads = [threading.Thread(target=race, args=(f"w{i}",)) for i in range(N_THREADS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=30)
    assert errors == []
    return winners


def test_threads_claiming_the_same_job_one_wins(engine: Engine) -> None:
    for job in _jobs(engine, N_JOBS):
        winners = _race(engine, job.id)
        assert len(winners) == 1
        with session_scope(engine) as s:
            rec = get_job(s, job.id)
        assert rec is not None and rec.lease_owner == winners[0] and rec.attempt_count == 1


def test_worker_threads_drain_a_queue_without_double_claims(engine: Engine) -> None:
    jobs = _jobs(engine, 12)
    claimed: dict[str, list[str]] = {j.id: [] for j in jobs}
    lock = threading.Lock()
    errors: list[BaseException] = []

    def worker(name: str) -> None:
        try:
            for job in jobs:  # every worker tries every job, like re-delivered messages
                with session_scope(engine) as s:
                    if claim_job(s, job.id, name, 60.0) is None:
                        continue
                with lock:
                    claimed[job.id].append(name)
                with session_scope(engine) as s:
                    finish_job(s, job.id, name, result=ResultIn(objectives=[1.0]))
        except BaseException as exc:
            errors.append(exc)

    threads = [threading.Thread(target=worker, args=(f"w{i}",)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(timeout=60)
    assert errors == []
    assert all(len(names) == 1 for names in claimed.values())
    with session_scope(engine) as s:
        assert list_jobs(s, status=JobStatus.SUCCEEDED, limit=100).total == len(jobs)


def _claim_in_process(url: str, job_id: str, worker: str, start: object, out: object) -> None:
    engine = make_engine(url, poolclass=NullPool)
    try:
        start.wait(10)  # type: ignore[attr-defined]
        with session_scope(engine) as s:
            won = claim_job(s, job_id, worker, 60.0) is not None
        out.put((worker, won))  # type: ignore[attr-defined]
    finally:
        engine.dispose()


def test_processes_claiming_the_same_job_on_sqlite_one_wins(tmp_path: Path) -> None:
    url = sqlite_url(tmp_path)
    engine = make_engine(url)
    Base.metadata.create_all(engine)
    (job,) = _jobs(engine, 1)
    engine.dispose()

    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn"
    ctx = multiprocessing.get_context(method)
    start, out = ctx.Event(), ctx.Queue()
    procs = [
        ctx.Process(target=_claim_in_process, args=(url, job.id, f"p{i}", start, out))
        for i in range(3)
    ]
    for p in procs:
        p.start()
    start.set()
    results = [out.get(timeout=30) for _ in procs]
    for p in procs:
        p.join(timeout=30)
        assert p.exitcode == 0
    winners = [w for w, won in results if won]
    assert len(winners) == 1
    engine = make_engine(url)
    with session_scope(engine) as s:
        rec = get_job(s, job.id)
    engine.dispose()
    assert rec is not None and rec.lease_owner == winners[0]
