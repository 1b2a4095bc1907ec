"""A job's verdict in the store (issue 25, item 2): ``finish_job`` writes ``feasible`` and the
optimum's ``violations`` on the job row in the UPDATE that makes it succeeded (never one without
the other), NULL until then; the job lists filter by it (repository and dashboard pages, on the
``(owner, feasible, created_at, id)`` index); revision 0008 adds the columns to a store with
jobs in it and takes them away again."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest
from sqlalchemy import Engine, create_engine, text
from sqlalchemy.orm import sessionmaker
from store_testdb import sqlite_url

from services.api.lookups import study_defaults
from services.store import api_keys, migrate
from services.store import dashboard_queries as dq
from services.store import repository as repo
from services.store.lifecycle import claim_job, finish_job
from services.store.records import JobRecord, ParetoPointIn, ResultIn
from services.store.session import make_engine, session_scope
from services.store.states import JobStatus
from services.store.tables import Base

T0 = datetime(2026, 3, 1, 8, 0, tzinfo=UTC)
#: What legcore.runner writes for an optimum that misses a 20 mm stability margin by 16 mm.
VIOLATIONS = [
    {"constraint": "stability_margin", "amount": 0.016, "unit": "m",
     "text": "static stability margin 16 mm short of the 20 mm asked"},
    {"constraint": "joint_speed", "amount": 0.17, "unit": "", "text": ""},
]  # fmt: skip


def _jobs(engine: Engine, n: int) -> tuple[str, list[str]]:
    """A key with ``n`` running jobs (claimed by worker w1); the key id and the job ids."""
    with session_scope(engine) as s:
        key = api_keys.create_api_key(s, name="k", key_hash=f"h-{datetime.now().timestamp()}")
        ids = repo.create_jobs(
            s, owner_key_id=key.id, total_generations=[5] * n, now=T0,
            specs=[{"problem": {"kind": "quadruped_gait"}, "seed": i} for i in range(n)],
        )  # fmt: skip
        for jid in ids:
            assert claim_job(s, jid, "w1", 60.0, now=T0) is not None
    return key.id, ids


def _finish(
    engine: Engine, job_id: str, result: ResultIn, pareto: list[int] | None = None
) -> JobRecord:
    with session_scope(engine) as s:
        return finish_job(
            s, job_id, "w1", result=result, now=T0 + timedelta(seconds=9),
            pareto=[ParetoPointIn(i, [0.0], [float(i)]) for i in pareto or []],
        )  # fmt: skip


def test_finish_job_writes_the_verdict_and_the_lists_filter_by_it(engine: Engine) -> None:
    key_id, (bad, good, unchecked, queued) = _jobs(engine, 4)
    with session_scope(engine) as s:  # one job not claimed: back to queued for this test
        s.execute(text("UPDATE jobs SET status = 'queued' WHERE id = :j"), {"j": queued})
    with session_scope(engine) as s:
        assert repo.get_job(s, bad).feasible is None  # type: ignore[union-attr]  # running

    done = _finish(engine, bad, ResultIn(best_x=[1.0], feasible=False, violations=VIOLATIONS))
    assert done.status is JobStatus.SUCCEEDED  # the run completed: the verdict is separate
    assert done.feasible is False and done.violations == VIOLATIONS
    assert _finish(engine, good, ResultIn(best_x=[1.0], feasible=True, violations=[])).feasible
    old = _finish(engine, unchecked, ResultIn(best_x=[1.0], violations=VIOLATIONS))
    assert old.feasible is None and old.violations is None  # not checked: nothing claimed

    with session_scope(engine) as s:
        got = repo.get_job(s, good)
        assert got is not None and got.feasible is True and got.violations == []
        listed = {f: [j.id for j in repo.list_jobs(s, owner_key_id=key_id, feasible=f).items]
                  for f in (None, True, False)}  # fmt: skip
        dq.sync_labels(s, key_id, study_defaults)
        pages = {
            f: [r.job.id for r in dq.list_job_rows(s, key_id, dq.JobFilter(feasible=f)).items]
            for f in (True, False)
        }
        total = dq.list_job_rows(s, key_id, dq.JobFilter(feasible=False, kind="quadruped_gait"))
    assert sorted(listed[None]) == sorted([bad, good, unchecked, queued])
    assert listed[True] == [good] and listed[False] == [bad]
    assert pages == {True: [good], False: [bad]}
    assert [r.job.id for r in total.items] == [bad] and total.total == 1  # labels + verdict
    assert total.items[0].job.violations == VIOLATIONS


def test_a_failed_finish_writes_no_verdict(engine: Engine) -> None:
    _, (job,) = _jobs(engine, 1)
    result = ResultIn(best_x=[1.0], feasible=False, violations=VIOLATIONS)
    with pytest.raises(Exception, match="(?i)unique|duplicate"):
        _finish(engine, job, result, pareto=[0, 0])  # two points with one index: all undone
    with session_scope(engine) as s:
        rec = repo.get_job(s, job)
    assert rec is not None and rec.status is JobStatus.RUNNING
    assert rec.feasible is None and rec.violations is None


def test_the_feasible_filter_reads_its_index(tmp_path: Path) -> None:
    """SQLite answers a jobs page filtered by verdict from ``(owner, feasible, created_at,
    id)``, without sorting the key's jobs."""
    engine = make_engine(sqlite_url(tmp_path))
    Base.metadata.create_all(engine)
    key_id, ids = _jobs(engine, 3)
    for jid in ids:
        _finish(engine, jid, ResultIn(best_x=[0.0], feasible=jid != ids[0], violations=[]))
    statements: list[tuple[str, object]] = []
    from sqlalchemy import event

    with sessionmaker(engine)() as s:
        dq.sync_labels(s, key_id, study_defaults)
        conn = s.connection()

        def capture(_c: object, _cur: object, stmt: str, params: object, *_: object) -> None:
            if stmt.lstrip().upper().startswith("SELECT") and "ORDER BY" in stmt:
                statements.append((stmt, params))

        event.listen(conn, "before_cursor_execute", capture)
        page = dq.list_job_rows(s, key_id, dq.JobFilter(feasible=False), count=False)
        event.remove(conn, "before_cursor_execute", capture)
        raw = conn.connection.dbapi_connection
        assert raw is not None
        plans = [" | ".join(str(r[-1]) for r in raw.execute(f"EXPLAIN QUERY PLAN {q}", p))
                 for q, p in statements]  # fmt: skip
    engine.dispose()
    assert [r.job.id for r in page.items] == [ids[0]]
    index = "ix_jobs_owner_key_id_feasible_created_at_id"
    assert plans and all(index in p and "TEMP B-TREE" not in p for p in plans), plans


def test_revision_0008_adds_the_verdict_to_a_store_with_jobs(tmp_path: Path) -> None:
    """Jobs stored at 0007 read back at 0008 with no verdict (not checked, not feasible), and
    downgrading keeps them."""
    url = f"sqlite:///{tmp_path / 'old.db'}"
    migrate.upgrade(url, revision="0007")
    eng = create_engine(url)
    with sessionmaker(eng).begin() as s:  # api_keys is the same at 0007 and head
        key_id = api_keys.create_api_key(s, name="old", key_hash="o" * 64).id
    with eng.begin() as c:
        c.execute(
            text("INSERT INTO jobs (id, owner_key_id, status, progress_generation, "
                 "total_generations, attempt_count, cancel_requested, cpu_seconds, "
                 "dispatch_count, warnings, spec_bytes, created_at) VALUES "
                 "('j0', :k, 'succeeded', 5, 5, 1, 0, 0, 0, '[]', 0, '2026-01-01')"),
            {"k": key_id},
        )  # fmt: skip
    eng.dispose()
    migrate.upgrade(url)
    head = make_engine(url)
    with session_scope(head) as s:
        job = repo.get_job(s, "j0")
    head.dispose()
    assert job is not None and job.status is JobStatus.SUCCEEDED
    assert job.feasible is None and job.violations is None
    migrate.downgrade(url, "0007")
    eng = create_engine(url)
    with eng.connect() as c:
        assert c.execute(text("SELECT id, status FROM jobs")).all() == [("j0", "succeeded")]
        columns = {r[1] for r in c.execute(text("PRAGMA table_info(jobs)"))}
    eng.dispose()
    assert "feasible" not in columns and "violations" not in columns
