"""The jobs page's orders (services.store.dashboard_queries): every sort key, both directions,
paged by keyset cursor and by offset, equals a reference sort in Python — NULLs last, ties
broken newest first by (created_at, id) — on SQLite and PostgreSQL; and each keyset page is an
index range scan (the query plan names the sort column's index, no full sort)."""

from __future__ import annotations

import math
from datetime import datetime, timedelta
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy import Engine, bindparam, text, update
from sqlalchemy.orm import Session, sessionmaker
from store_testdb import sqlite_url

from services.api.lookups import study_defaults
from services.store import api_keys
from services.store import dashboard_queries as dq
from services.store import repository as repo
from services.store.progress import first_objective
from services.store.session import make_engine
from services.store.states import JobStatus
from services.store.tables import JOBS, Base

KINDS = ["path_tracking", "swing_energy", "quadruped_gait"]
STATUSES = [JobStatus.SUCCEEDED, JobStatus.FAILED, JobStatus.QUEUED, JobStatus.RUNNING]
N = 37


def _fill(session: Session, key_id: str) -> None:
    """N jobs, several per created_at (ties), with repeated and missing best values and
    finishing times, kinds, robots and optimizers."""
    base = datetime(2026, 1, 1, tzinfo=repo.now_utc().tzinfo)
    for i in range(N):
        spec = {"problem": {"kind": KINDS[i % 3]}, "robot": f"arm{i % 4}",
                "optimizer": {"kind": ["ga", "nsga2"][i % 2]}, "seed": i}  # fmt: skip
        repo.create_jobs(
            session, owner_key_id=key_id, specs=[spec], total_generations=[10],
            now=base + timedelta(minutes=i // 3),
        )  # fmt: skip
    ids = [j.id for j in repo.list_jobs(session, owner_key_id=key_id, limit=100).items]
    rows = []
    for i, job_id in enumerate(sorted(ids)):
        best = None if i % 5 == 0 else [float((i * 7) % 6), 1.0]
        rows.append({
            "jid": job_id, "st": STATUSES[i % 4], "g": i % 4,
            "best": best, "bv": first_objective(best),
            "fin": None if i % 4 in (2, 3) else base + timedelta(hours=1, minutes=i % 3),
        })  # fmt: skip
    stmt = (
        update(JOBS)
        .where(JOBS.c.id == bindparam("jid"))
        .values(status=bindparam("st"), progress_generation=bindparam("g"),
                best_objective=bindparam("best", type_=JOBS.c.best_objective.type),
                best_value=bindparam("bv"),
                finished_at=bindparam("fin", type_=JOBS.c.finished_at.type))
    )  # fmt: skip
    session.connection().execute(stmt, rows)
    dq.sync_labels(session, key_id, study_defaults)


def _value(row: dq.JobRow, sort: str) -> Any:
    j = row.job
    return {
        "created": None, "finished": j.finished_at, "status": j.status.value, "kind": row.kind,
        "robot": row.robot, "optimizer": row.optimizer, "progress": j.progress_generation,
        "best": first_objective(j.best_objective),
    }[sort]  # fmt: skip


def _reference(rows: list[dq.JobRow], sort: str, descending: bool) -> list[str]:
    """The page order in Python: the column (NULLs last), then created_at, then id, all in
    the same direction."""
    ordered = sorted(rows, key=lambda r: (r.job.created_at, r.job.id), reverse=descending)
    present = [r for r in ordered if _value(r, sort) is not None or sort == "created"]
    missing = [r for r in ordered if _value(r, sort) is None and sort != "created"]
    present.sort(key=lambda r: _value(r, sort) or 0, reverse=descending)  # stable: ties keep
    return [r.job.id for r in present + missing]


@pytest.fixture
def filled(engine: Engine) -> tuple[sessionmaker[Session], str]:
    factory = sessionmaker(engine)
    with factory.begin() as s:
        key_id = api_keys.create_api_key(s, name="pages", key_hash="h" * 64).id
        _fill(s, key_id)
    return factory, key_id


@pytest.mark.parametrize("descending", [True, False])
def test_every_order_pages_by_cursor_and_offset_like_the_reference(
    filled: tuple[sessionmaker[Session], str], descending: bool
) -> None:
    factory, key_id = filled
    with factory() as s:
        everything = list(dq.list_job_rows(s, key_id, limit=100).items)
        assert len(everything) == N
        for sort in dq.SORT_KEYS:
            want = _reference(everything, sort, descending)
            by_cursor: list[str] = []
            cursor = None
            for _ in range(N):
                page = dq.list_job_rows(
                    s, key_id, sort=sort, descending=descending, limit=4, cursor=cursor
                )
                by_cursor += [r.job.id for r in page.items]
                cursor = page.next_cursor
                if cursor is None:
                    break
            assert by_cursor == want, sort
            by_offset = [
                r.job.id
                for offset in range(0, N, 5)
                for r in dq.list_job_rows(
                    s, key_id, sort=sort, descending=descending, limit=5, offset=offset
                ).items
            ]
            assert by_offset == want, sort


def test_a_cursor_belongs_to_its_order(filled: tuple[sessionmaker[Session], str]) -> None:
    factory, key_id = filled
    with factory() as s:
        page = dq.list_job_rows(s, key_id, sort="best", limit=3)
        assert page.next_cursor is not None
        with pytest.raises(ValueError, match="sort 'best', not 'finished'"):
            dq.list_job_rows(s, key_id, sort="finished", cursor=page.next_cursor)
        with pytest.raises(ValueError, match="not a cursor"):
            dq.list_job_rows(s, key_id, cursor="bm9wZQ")
        last = dq.list_job_rows(s, key_id, limit=N)
        assert last.next_cursor is None and len(last.items) == N


def test_first_objective_is_the_sorted_number() -> None:
    assert first_objective([2.5, 1.0]) == 2.5
    assert first_objective(-3) == -3.0
    assert first_objective(None) is None and first_objective([]) is None
    assert first_objective([math.inf]) is None and first_objective(True) is None


def test_keyset_pages_scan_the_sort_columns_index(tmp_path: Path) -> None:
    """The planner answers a deep keyset page of each jobs-table order from that column's
    index, without sorting the key's jobs (SQLite's plan, which names the index it uses;
    PostgreSQL picks by statistics: bench_dashboard.py measures it at 10^5 jobs)."""
    engine = make_engine(sqlite_url(tmp_path))
    Base.metadata.create_all(engine)
    factory = sessionmaker(engine)
    with factory.begin() as s:
        key_id = api_keys.create_api_key(s, name="plan", key_hash="p" * 64).id
        _fill(s, key_id)
    with factory() as s:
        for sort, index in [
            ("best", "ix_jobs_owner_key_id_best_value_created_at_id"),
            ("finished", "ix_jobs_owner_key_id_finished_at_created_at_id"),
            ("progress", "ix_jobs_owner_key_id_progress_generation_created_at_id"),
            ("status", "ix_jobs_owner_key_id_status_created_at_id"),
        ]:
            cursor = dq.list_job_rows(s, key_id, sort=sort, limit=3).next_cursor
            assert cursor is not None
            plans = _plans(s, key_id, sort, cursor)
            assert plans and all(index in p and "TEMP B-TREE" not in p for p in plans), plans
    engine.dispose()


def _plans(s: Session, key_id: str, sort: str, cursor: str) -> list[str]:
    """SQLite's query plan of each statement a keyset page issues."""
    statements: list[tuple[str, Any]] = []
    conn = s.connection()

    from sqlalchemy import event

    def capture(_c: Any, _cur: Any, statement: str, params: Any, _ctx: Any, _many: bool) -> None:
        if statement.lstrip().upper().startswith("SELECT") and "ORDER BY" in statement:
            statements.append((statement, params))

    event.listen(conn, "before_cursor_execute", capture)
    try:
        dq.list_job_rows(s, key_id, sort=sort, limit=3, cursor=cursor, count=False)
    finally:
        event.remove(conn, "before_cursor_execute", capture)
    out = []
    for statement, params in statements:
        raw = conn.connection.dbapi_connection
        assert raw is not None
        plan = raw.execute(f"EXPLAIN QUERY PLAN {statement}", params).fetchall()
        out.append(" | ".join(str(row[-1]) for row in plan))
    return out


def test_migration_fills_best_value(tmp_path: Any) -> None:
    """Revision 0006 writes ``best_value`` of jobs stored before it."""
    from sqlalchemy import create_engine

    from services.store import migrate

    url = f"sqlite:///{tmp_path / 'old.db'}"
    migrate.upgrade(url, revision="0005")
    eng = create_engine(url)
    with sessionmaker(eng).begin() as s:  # api_keys is the same at 0005 and head
        key_id = api_keys.create_api_key(s, name="old", key_hash="o" * 64).id
    with eng.begin() as c:
        for i, best in enumerate(["[4.5, 1]", "7", None, '["x"]']):
            c.execute(
                text("INSERT INTO jobs (id, owner_key_id, status, progress_generation, "
                     "total_generations, best_objective, attempt_count, cancel_requested, "
                     "cpu_seconds, dispatch_count, warnings, spec_bytes, created_at) VALUES "
                     "(:id, :k, 'queued', 0, 1, :b, 0, 0, 0, 0, '[]', 0, '2026-01-01')"),
                {"id": f"j{i}", "k": key_id, "b": best},
            )  # fmt: skip
    eng.dispose()
    migrate.upgrade(url)
    eng = create_engine(url)
    with eng.connect() as c:
        got: dict[str, float | None] = {
            r[0]: r[1] for r in c.execute(text("SELECT id, best_value FROM jobs"))
        }
    eng.dispose()
    assert got == {"j0": 4.5, "j1": 7.0, "j2": None, "j3": None}
