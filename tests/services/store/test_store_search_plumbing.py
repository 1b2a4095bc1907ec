"""The jobs page's search index itself (issue 23, item 3; what it finds:
``test_store_search_index``): the FTS table follows every write of the labels (triggers:
insert, update, deletes cascaded from jobs and keys); the query plans read the index, not the
key's labels, on both stores — and a word shaped like an id the primary key and the sweep
index, not the trigram index; a store without the index (no pg_trgm, no FTS5) still searches,
by LIKE, with the same results."""

from __future__ import annotations

import re
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from search_jobs import KINDS, _fill, _fill_sweep, _ids, _texts
from sqlalchemy import Engine, event, text, update
from sqlalchemy.engine import make_url
from sqlalchemy.orm import Session, sessionmaker
from sqlalchemy.pool import NullPool
from store_testdb import PG_ADMIN_URL, requires_postgres, sqlite_url

from services.api.lookups import study_defaults
from services.store import api_keys, migrate, search_index
from services.store import dashboard_queries as dq
from services.store import repository as repo
from services.store.search_index import SEARCH_FTS, SEARCH_TRGM_INDEX
from services.store.session import make_engine
from services.store.states import JobStatus
from services.store.tables import JOB_LABELS, Base


def _fts_rows(s: Session, phrase: str) -> set[int]:
    """Rowids of the labels whose text contains ``phrase`` (3 characters or more), by FTS."""
    q = f"SELECT rowid FROM {SEARCH_FTS} WHERE {SEARCH_FTS} MATCH :q"
    return {r[0] for r in s.execute(text(q), {"q": '"' + phrase.replace('"', '""') + '"'})}


def test_the_fts_table_follows_the_labels(tmp_path: Path) -> None:
    engine = make_engine(sqlite_url(tmp_path))
    Base.metadata.create_all(engine)
    factory = sessionmaker(engine)
    with factory.begin() as s:
        key_id = api_keys.create_api_key(s, name="k", key_hash="k" * 64).id
        gone_key = api_keys.create_api_key(s, name="gone", key_hash="g" * 64).id
        ids = _fill(s, key_id, n=6)
        _fill(s, gone_key, n=4)
    with factory.begin() as s:
        assert len(_fts_rows(s, "seed=")) == 10  # every label, by its rowid
        assert repo.delete_job(s, ids[0])  # cascades to its label, and to the index
        s.execute(
            update(JOB_LABELS).where(JOB_LABELS.c.job_id == ids[1]).values(search="renamed xyz")
        )
        assert api_keys.delete_api_key(s, gone_key)  # cascades through jobs to labels
    with factory() as s:
        assert len(_fts_rows(s, "seed=")) == 4
        assert _ids(dq.list_job_rows(s, key_id, dq.JobFilter(search="xyz"))) == [ids[1]]
        assert ids[1] not in _ids(dq.list_job_rows(s, key_id, dq.JobFilter(search="seed=")))
        assert ids[0] not in _ids(dq.list_job_rows(s, key_id, dq.JobFilter(search=ids[0][:8])))
        # the index and the labels agree row for row
        s.execute(text(f"INSERT INTO {SEARCH_FTS} ({SEARCH_FTS}) VALUES ('integrity-check')"))
        labelled = s.execute(text("SELECT rowid, search FROM job_labels")).all()
        for rowid, search in labelled:
            assert rowid in _fts_rows(s, search[:12])
    engine.dispose()


def _plans(engine: Engine, run: Any) -> list[tuple[str, str]]:
    """``(statement, plan)`` of every SELECT ``run(session)`` issues (SQLite: EXPLAIN QUERY
    PLAN; PostgreSQL: EXPLAIN)."""
    statements: list[tuple[str, Any]] = []

    def capture(_c: object, _cur: object, stmt: str, params: Any, *_: object) -> None:
        if stmt.lstrip().upper().startswith("SELECT") and "FROM" in stmt:
            statements.append((stmt, params))

    with sessionmaker(engine)() as s:
        conn = s.connection()
        event.listen(conn, "before_cursor_execute", capture)
        run(s)
        event.remove(conn, "before_cursor_execute", capture)
        raw = conn.connection.dbapi_connection
        assert raw is not None
        out = []
        for stmt, params in statements:
            cur = raw.cursor()
            if engine.dialect.name == "sqlite":
                cur.execute(f"EXPLAIN QUERY PLAN {stmt}", params)
                plan = " | ".join(str(r[-1]) for r in cur.fetchall())
            else:  # as on a large table: an index wherever one can answer
                cur.execute("SET LOCAL enable_seqscan = off")
                cur.execute(f"EXPLAIN {stmt}", params)
                plan = " | ".join(str(r[0]).strip() for r in cur.fetchall())
            out.append((stmt, plan))
        return out


def test_sqlite_search_and_first_page_read_indexes(tmp_path: Path) -> None:
    """The search's statements start from the FTS table and reach labels by rowid (never a
    walk of the key's labels); page 1 and its count read the key's index of jobs; a word of
    two letters is a LIKE (no trigram can answer it)."""
    engine = make_engine(sqlite_url(tmp_path))
    Base.metadata.create_all(engine)
    with sessionmaker(engine).begin() as s:
        key_id = api_keys.create_api_key(s, name="k", key_hash="p" * 64).id
        _fill(s, key_id)

    for f, sort in [
        (dq.JobFilter(search="seed=1"), "created"),
        (dq.JobFilter(search="calderon leg"), "best"),
        (dq.JobFilter(search="seed=1", status=(JobStatus.FAILED,)), "created"),
    ]:
        plans = _plans(engine, lambda s, f=f, sort=sort: dq.list_job_rows(s, key_id, f, sort=sort))
        search = [p for q, p in plans if SEARCH_FTS in q]
        # the count, the page's ids (by best: with a value, then without), then rows by id
        assert len(search) >= 2, plans
        for plan in search:
            tables_read = [x for x in plan.split(" | ") if " anon_" not in x and "B-TREE" not in x]
            assert tables_read[0].startswith(f"SCAN {SEARCH_FTS} VIRTUAL TABLE INDEX"), plan
            assert "SEARCH job_labels USING INTEGER PRIMARY KEY (rowid=?)" in plan, plan
            assert not re.search(r"job_labels USING (COVERING )?INDEX", plan), plan
            assert not re.search(r"SCAN (job_labels|jobs)\b(?!_)", plan), plan
        by_id = [p for q, p in plans if SEARCH_FTS not in q and "job_labels" in q]
        assert by_id and all("(job_id=?)" in p and "SCAN" not in p for p in by_id), by_id

    plans = _plans(engine, lambda s: dq.list_job_rows(s, key_id))
    index = re.compile(r"SEARCH jobs USING (COVERING )?INDEX ix_jobs_owner_key_id")
    assert len(plans) == 2 and all(index.search(p) for _, p in plans), plans
    # (ties of created_at are put in id order: "RIGHT PART OF ORDER BY", never a full sort)
    assert all("SCAN jobs" not in p and "B-TREE FOR ORDER BY" not in p for _, p in plans), plans

    plans = _plans(engine, lambda s: dq.list_job_rows(s, key_id, dq.JobFilter(search="ga")))
    assert not any(SEARCH_FTS in q for q, _ in plans)
    assert any("LIKE" in q for q, _ in plans)

    # a word shaped like an id: the primary key's and the sweep index's ranges drive the count
    # and the page, then the labels and jobs by key (never the FTS table, never a scan)
    with sessionmaker(engine).begin() as s:
        sweep, sweep_jobs = _fill_sweep(s, key_id)
    for f, sort in [
        (dq.JobFilter(search=sweep_jobs[1]), "created"),
        (dq.JobFilter(search=f"{sweep[:13]} seed", status=(JobStatus.QUEUED,)), "best"),
        (dq.JobFilter(search=f"nsga2 {sweep}", kind="path_tracking"), "kind"),
    ]:
        plans = _plans(engine, lambda s, f=f, sort=sort: dq.list_job_rows(s, key_id, f, sort=sort))
        by_id = [p for q, p in plans if "id_hits" in q]
        assert len(by_id) >= 2 and not any(SEARCH_FTS in q for q, _ in plans), plans
        for plan in by_id:
            assert plan.startswith("MULTI-INDEX OR") or "| MULTI-INDEX OR |" in plan, plan
            assert re.search(r"SEARCH by_id USING (COVERING )?INDEX sqlite_autoindex_jobs", plan)
            assert re.search(r"SEARCH by_id USING (COVERING )?INDEX ix_jobs_sweep_id", plan)
            assert "SEARCH job_labels USING INDEX sqlite_autoindex_job_labels" in plan, plan
            assert not re.search(r"SCAN (by_id|job_labels|jobs)\b(?!_)", plan), plan
    engine.dispose()


def _pg_indexes(conn: Any) -> set[str]:
    q = text("SELECT indexname FROM pg_indexes WHERE tablename = 'job_labels'")
    return set(conn.execute(q).scalars())


@pytest.fixture
def pg_migrated(pg_empty_url: str) -> Iterator[Engine]:
    """A PostgreSQL database migrated to head (revision 0009 made the pg_trgm index)."""
    migrate.upgrade(pg_empty_url)
    engine = make_engine(pg_empty_url, poolclass=NullPool)
    try:
        yield engine
    finally:
        engine.dispose()


@requires_postgres
def test_postgres_search_and_first_page_read_indexes(pg_migrated: Engine) -> None:
    """The count and the page of a search for a rare word read the trigram index (after
    VACUUM ANALYZE, sequential scans off as the planner would on a large table); page 1
    and its count read the key's index of jobs."""
    engine = pg_migrated
    with engine.connect() as c:
        assert SEARCH_TRGM_INDEX in _pg_indexes(c)
    factory = sessionmaker(engine)
    with factory.begin() as s:
        key_id = api_keys.create_api_key(s, name="k", key_hash="q" * 64).id
        specs = [
            {"name": f"job {i}", "problem": {"kind": KINDS[i % 3]}, "seed": i % 97}
            for i in range(3000)
        ]
        repo.create_jobs(s, owner_key_id=key_id, specs=specs, total_generations=[5] * 3000)
        dq.sync_labels(s, key_id, study_defaults)
    with engine.connect().execution_options(isolation_level="AUTOCOMMIT") as c:
        c.execute(text("VACUUM ANALYZE"))  # as autovacuum: GIN's pending list merged

    f = dq.JobFilter(search="1234")  # job 1234 (and ids with those digits)
    plans = _plans(engine, lambda s: dq.list_job_rows(s, key_id, f))
    search = [p for q, p in plans if "LIKE" in q]
    assert len(search) == 2 and all(SEARCH_TRGM_INDEX in p for p in search), plans
    with factory() as s:
        page = dq.list_job_rows(s, key_id, f)
        assert page.total >= 1 and "job 1234" in [r.name for r in page.items]

    plans = _plans(engine, lambda s: dq.list_job_rows(s, key_id))
    assert len(plans) == 2, plans
    index = re.compile(r"Index (Only )?Scan (Backward )?using ix_jobs_owner_key_id")
    assert all(index.search(p) and "Seq Scan" not in p for _, p in plans), plans

    # a word shaped like an id: the primary key and the sweep index, not the trigram index
    with factory.begin() as s:
        sweep, sweep_jobs = _fill_sweep(s, key_id)
        job = s.execute(text("SELECT job_id FROM job_labels WHERE name = 'job 77'")).scalar_one()
    with engine.connect().execution_options(isolation_level="AUTOCOMMIT") as c:
        c.execute(text("VACUUM ANALYZE"))
    for f in (
        dq.JobFilter(search=job),
        dq.JobFilter(search=f"{job[:13]} seed=77"),
        dq.JobFilter(search=f"{sweep} nsga2", status=(JobStatus.QUEUED,)),
    ):
        plans = _plans(engine, lambda s, f=f: dq.list_job_rows(s, key_id, f))
        by_id = [p for q, p in plans if "id_hits" in q]
        assert len(by_id) == 2, plans
        for plan in by_id:
            assert "pk_jobs" in plan and "ix_jobs_sweep_id" in plan, plan
            assert SEARCH_TRGM_INDEX not in plan and "Seq Scan" not in plan, plan
        with factory() as s:
            scan = dq.list_job_rows(s, key_id, f, search_index=False)
            page = dq.list_job_rows(s, key_id, f)
            assert _ids(page) == _ids(scan) and page.total == scan.total >= 1, f


def test_sqlite_without_trigram_fts_searches_by_like(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An SQLite without FTS5 / the trigram tokenizer gets no FTS table and the same results
    (an id word still by the primary key)."""
    monkeypatch.setattr(search_index, "sqlite_has_trigram_fts", lambda _c: False)
    engine = make_engine(sqlite_url(tmp_path))
    Base.metadata.create_all(engine)
    factory = sessionmaker(engine)
    with factory.begin() as s:
        key_id = api_keys.create_api_key(s, name="k", key_hash="n" * 64).id
        _fill(s, key_id, n=12)
    with factory() as s:
        assert (
            s.execute(text(f"SELECT 1 FROM sqlite_master WHERE name = '{SEARCH_FTS}'")).all() == []
        )
        texts = _texts(s, key_id)
        job = sorted(texts)[3]  # an id word: by the primary key there too
        for q in ("seed=1", "calderon", "ga", job, job[:13]):
            want = {j for j, t in texts.items() if q in t}
            assert set(_ids(dq.list_job_rows(s, key_id, dq.JobFilter(search=q)))) == want
    engine.dispose()


def test_revision_0009_indexes_the_labels_there_are(tmp_path: Path) -> None:
    """Labels stored at 0008 are in the FTS table after the upgrade (and stay in step through
    the later revisions: the search by index at head finds them); the downgrade takes the table
    and its triggers away and leaves the labels."""
    url = sqlite_url(tmp_path)
    migrate.upgrade(url, revision="0008")
    engine = make_engine(url)
    with engine.begin() as c:  # the tables as they are at 0008, in SQL
        c.execute(text("INSERT INTO api_keys (id, name, key_hash, created_at, role) "
                       "VALUES ('k', 'old', 'h', '2026-01-01', 'user')"))  # fmt: skip
        for i in range(9):
            at = f"2026-01-01 00:0{i}:00"
            c.execute(
                text("INSERT INTO jobs (id, owner_key_id, status, progress_generation, "
                     "total_generations, attempt_count, cancel_requested, cpu_seconds, "
                     "dispatch_count, warnings, spec_bytes, created_at) VALUES "
                     "(:j, 'k', 'queued', 0, 5, 0, 0, 0, 0, '[]', 0, :at)"),
                {"j": f"j{i}", "at": at},
            )  # fmt: skip
            c.execute(
                text("INSERT INTO job_labels (job_id, owner_key_id, created_at, name, kind, "
                     "robot, optimizer, seed, tags, search) VALUES (:j, 'k', :at, NULL, "
                     "'path_tracking', 'arm', 'ga', :seed, '', :search)"),
                {"j": f"j{i}", "at": at, "seed": i, "search": f"path_tracking arm seed={i} j{i}"},
            )  # fmt: skip
    engine.dispose()

    migrate.upgrade(url, revision="0009")
    engine = make_engine(url)
    with sessionmaker(engine)() as s:
        assert len(_fts_rows(s, "seed=")) == 9 and len(_fts_rows(s, "seed=3")) == 1
    engine.dispose()

    migrate.upgrade(url)
    engine = make_engine(url)
    with sessionmaker(engine)() as s:
        f = dq.JobFilter(search="seed=3 arm")
        assert _ids(dq.list_job_rows(s, "k", f)) == ["j3"]
        plans = _plans(engine, lambda s: dq.list_job_rows(s, "k", f))
        assert any(SEARCH_FTS in q for q, _ in plans)
    engine.dispose()

    migrate.downgrade(url, "0008")
    engine = make_engine(url)
    with engine.connect() as c:
        objects = c.execute(text("SELECT name FROM sqlite_master WHERE name LIKE '%fts%'"))
        assert objects.all() == []
        assert c.execute(text("SELECT count(*) FROM job_labels")).scalar_one() == 9
    engine.dispose()


@requires_postgres
def test_postgres_without_pg_trgm_migrates_and_searches_by_like(pg_empty_url: str) -> None:
    """A role that may not create extensions: revision 0009 applies without the index (and
    says so), and the search answers by LIKE."""
    role = f"legopt_noext_{uuid.uuid4().hex[:8]}"
    admin = make_engine(PG_ADMIN_URL, poolclass=NullPool, isolation_level="AUTOCOMMIT")
    db = make_url(pg_empty_url).database
    with admin.connect() as c:
        c.execute(text(f"CREATE ROLE {role} LOGIN PASSWORD 'noext'"))
    owner = make_engine(pg_empty_url, poolclass=NullPool, isolation_level="AUTOCOMMIT")
    try:
        with owner.connect() as c:  # tables in public, but no CREATE on the database
            c.execute(text(f"GRANT CREATE, USAGE ON SCHEMA public TO {role}"))
            c.execute(text(f'REVOKE CREATE ON DATABASE "{db}" FROM PUBLIC'))
        url = make_url(pg_empty_url).set(username=role, password="noext")
        as_role = url.render_as_string(hide_password=False)
        migrate.upgrade(as_role)
        assert migrate.current_revision(as_role) == migrate.head_revision()
        engine = make_engine(as_role, poolclass=NullPool)
        with engine.connect() as c:
            names = c.execute(
                text("SELECT indexname FROM pg_indexes WHERE tablename = 'job_labels'")
            )
            assert SEARCH_TRGM_INDEX not in set(names.scalars())
        factory = sessionmaker(engine)
        with factory.begin() as s:
            key_id = api_keys.create_api_key(s, name="k", key_hash="r" * 64).id
            _fill(s, key_id, n=9)
        with factory() as s:
            texts = _texts(s, key_id)
            want = {j for j, t in texts.items() if "seed=1" in t}
            assert set(_ids(dq.list_job_rows(s, key_id, dq.JobFilter(search="seed=1")))) == want
        engine.dispose()
    finally:
        owner.dispose()
        from store_testdb import drop_pg_database

        drop_pg_database(pg_empty_url)  # before the role that owns its tables
        with admin.connect() as c:
            c.execute(text(f"DROP ROLE IF EXISTS {role}"))
        admin.dispose()
