"""Engines and session scopes: SQLite pragmas, BEGIN modes, URL handling, cached engine."""

from __future__ import annotations

import multiprocessing
from pathlib import Path

import pytest
from sqlalchemy import event, text
from store_testdb import sqlite_url

from services.store import session as session_module
from services.store.session import make_engine, normalize_url, session_scope
from services.store.settings import get_settings


def test_sqlite_pragmas(tmp_path: Path) -> None:
    engine = make_engine(sqlite_url(tmp_path / "sub"), sqlite_busy_timeout_ms=1234)
    with engine.connect() as conn:
        assert conn.exec_driver_sql("PRAGMA journal_mode").scalar() == "wal"
        assert conn.exec_driver_sql("PRAGMA foreign_keys").scalar() == 1
        assert conn.exec_driver_sql("PRAGMA busy_timeout").scalar() == 1234
    engine.dispose()
    assert (tmp_path / "sub" / "legopt.db").is_file()


def test_begin_modes_and_savepoints(tmp_path: Path) -> None:
    engine = make_engine(sqlite_url(tmp_path))
    seen: list[str] = []

    @event.listens_for(engine, "begin")
    def _spy(conn: object) -> None:
        seen.append("begin")

    with session_scope(engine, immediate=True) as s:
        s.execute(text("CREATE TABLE t (x INTEGER)"))
        with pytest.raises(RuntimeError):
            with s.begin_nested():
                s.execute(text("INSERT INTO t VALUES (1)"))
                raise RuntimeError
        s.execute(text("INSERT INTO t VALUES (2)"))
    with session_scope(engine) as s:
        assert s.execute(text("SELECT x FROM t")).scalars().all() == [2]
    assert seen == ["begin", "begin"]
    engine.dispose()


def test_begin_immediate_is_emitted(tmp_path: Path) -> None:
    engine = make_engine(sqlite_url(tmp_path))
    sent: list[str] = []
    event.listen(engine, "before_cursor_execute", lambda c, cur, stmt, *a: sent.append(stmt))
    with session_scope(engine, immediate=True) as s:
        s.execute(text("SELECT 1"))
    with session_scope(engine) as s:
        s.execute(text("SELECT 1"))
    assert sent.count("BEGIN IMMEDIATE") == 1 and sent.count("BEGIN DEFERRED") == 1
    engine.dispose()


def test_postgres_urls_select_psycopg() -> None:
    assert normalize_url("postgresql://u@h/db").drivername == "postgresql+psycopg"
    assert normalize_url("postgres://u@h/db").drivername == "postgresql+psycopg"
    assert normalize_url("postgresql+psycopg://u@h/db").drivername == "postgresql+psycopg"
    assert normalize_url("sqlite:///x.db").drivername == "sqlite"


def test_memory_sqlite_works_single_threaded() -> None:
    engine = make_engine("sqlite://")
    with session_scope(engine) as s:
        assert s.execute(text("SELECT 41 + 1")).scalar() == 42
    engine.dispose()


def test_process_wide_engine_follows_the_settings(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("LEGOPT_DATABASE_URL", sqlite_url(tmp_path))
    get_settings.cache_clear()
    session_module.reset_engine()
    try:
        with session_scope() as s:
            assert s.execute(text("SELECT 1")).scalar() == 1
        assert session_module.get_engine().url.database == f"{tmp_path.as_posix()}/legopt.db"
    finally:
        session_module.reset_engine()
        get_settings.cache_clear()


def _child_uses_the_engine(out: object) -> None:
    with session_scope() as s:
        s.execute(text("INSERT INTO t VALUES (2)"))
    out.put(session_module.get_engine() is not None)  # type: ignore[attr-defined]


@pytest.mark.skipif(
    "fork" not in multiprocessing.get_all_start_methods(), reason="needs the fork start method"
)
def test_forked_child_gets_its_own_engine(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("LEGOPT_DATABASE_URL", sqlite_url(tmp_path))
    get_settings.cache_clear()
    session_module.reset_engine()
    try:
        parent_engine = session_module.get_engine()
        with session_scope() as s:
            s.execute(text("CREATE TABLE t (x INTEGER)"))
            s.execute(text("INSERT INTO t VALUES (1)"))
        ctx = multiprocessing.get_context("fork")
        out = ctx.Queue()
        child = ctx.Process(target=_child_uses_the_engine, args=(out,))
        child.start()
        assert out.get(timeout=30) is True
        child.join(timeout=30)
        assert child.exitcode == 0
        assert session_module.get_engine() is parent_engine  # the parent keeps its pool
        with session_scope() as s:
            assert s.execute(text("SELECT x FROM t ORDER BY x")).scalars().all() == [1, 2]
    finally:
        session_module.reset_engine()
        get_settings.cache_clear()
