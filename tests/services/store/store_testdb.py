"""Database helpers of the store tests (imported by conftest.py and the test modules).

PostgreSQL tests run only when a server answers at ``LEGOPT_TEST_POSTGRES_URL`` (default
``postgresql+psycopg://postgres@127.0.0.1:5432/test``); each run works in its own uniquely
named databases, dropped afterwards, so parallel runs do not interfere.
"""

from __future__ import annotations

import os
import uuid
from functools import lru_cache
from pathlib import Path

import pytest
from sqlalchemy import Engine, text
from sqlalchemy.engine import make_url
from sqlalchemy.pool import NullPool

from services.store.session import make_engine

PG_ADMIN_URL = os.environ.get(
    "LEGOPT_TEST_POSTGRES_URL", "postgresql+psycopg://postgres@127.0.0.1:5432/test"
)


@lru_cache(maxsize=1)
def postgres_available() -> bool:
    """Quick probe (1 s timeout) of the PostgreSQL server used by the tests."""
    try:
        import psycopg
    except ImportError:
        return False
    url = make_url(PG_ADMIN_URL)
    try:
        conn = psycopg.connect(
            host=url.host or "127.0.0.1",
            port=url.port or 5432,
            user=url.username,
            password=url.password,
            dbname=url.database,
            connect_timeout=1,
        )
    except Exception:
        return False
    conn.close()
    return True


#: Skip where no PostgreSQL answers — except under ``LEGOPT_REQUIRE_SERVICES=1`` (CI, when the
#: servers are up): there the test runs and fails on the missing server instead of skipping.
requires_postgres = pytest.mark.skipif(
    not postgres_available() and os.environ.get("LEGOPT_REQUIRE_SERVICES") != "1",
    reason=f"no PostgreSQL server at {PG_ADMIN_URL}",
)


def _admin_engine() -> Engine:
    return make_engine(PG_ADMIN_URL, poolclass=NullPool, isolation_level="AUTOCOMMIT")


def create_pg_database() -> str:
    """Create an empty, uniquely named database; its URL."""
    name = f"legopt_test_{uuid.uuid4().hex[:12]}"
    admin = _admin_engine()
    try:
        with admin.connect() as conn:
            conn.execute(text(f'CREATE DATABASE "{name}"'))
    finally:
        admin.dispose()
    return make_url(PG_ADMIN_URL).set(database=name).render_as_string(hide_password=False)


def drop_pg_database(url: str) -> None:
    """Drop a database made by ``create_pg_database`` (disconnecting its sessions)."""
    name = make_url(url).database
    admin = _admin_engine()
    try:
        with admin.connect() as conn:
            conn.execute(text(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)'))
    finally:
        admin.dispose()


def sqlite_url(directory: Path) -> str:
    """URL of a SQLite file in ``directory``."""
    return f"sqlite:///{directory.as_posix()}/legopt.db"
