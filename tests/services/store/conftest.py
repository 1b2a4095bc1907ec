"""Fixtures of the store tests: a fresh database per test on SQLite (always) and PostgreSQL
(when a server answers, see ``store_testdb``)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from sqlalchemy import Engine, text
from sqlalchemy.pool import NullPool
from store_testdb import create_pg_database, drop_pg_database, requires_postgres, sqlite_url

from services.store.session import make_engine
from services.store.tables import Base


@pytest.fixture
def pg_empty_url() -> Iterator[str]:
    """URL of a new empty PostgreSQL database, dropped after the test."""
    url = create_pg_database()
    try:
        yield url
    finally:
        drop_pg_database(url)


@pytest.fixture(scope="session")
def pg_tables_url() -> Iterator[str]:
    """URL of a PostgreSQL database with the tables, shared by this run's tests."""
    url = create_pg_database()
    engine = make_engine(url, poolclass=NullPool)
    Base.metadata.create_all(engine)
    engine.dispose()
    try:
        yield url
    finally:
        drop_pg_database(url)


@pytest.fixture(params=["sqlite", pytest.param("postgresql", marks=requires_postgres)])
def engine(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[Engine]:
    """An engine on an empty schema: a new SQLite file, or the run's PostgreSQL database
    with every table emptied."""
    if request.param == "sqlite":
        eng = make_engine(sqlite_url(tmp_path))
        Base.metadata.create_all(eng)
    else:
        eng = make_engine(request.getfixturevalue("pg_tables_url"))
        names = ", ".join(t.name for t in Base.metadata.sorted_tables)
        with eng.begin() as conn:
            conn.execute(text(f"TRUNCATE {names} CASCADE"))
    try:
        yield eng
    finally:
        eng.dispose()
