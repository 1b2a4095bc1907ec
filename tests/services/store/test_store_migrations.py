"""Alembic: upgrade an empty database to head and back to base; models == migrated schema."""

from __future__ import annotations

import argparse
from pathlib import Path

import pytest
from alembic import command
from alembic.autogenerate import compare_metadata
from alembic.config import Config
from alembic.runtime.migration import MigrationContext
from sqlalchemy import inspect
from sqlalchemy.pool import NullPool
from store_testdb import requires_postgres, sqlite_url

from services.store import migrate
from services.store.search_index import is_search_index
from services.store.session import make_engine
from services.store.tables import Base

ROOT = Path(__file__).resolve().parents[3]
TABLES = {t.name for t in Base.metadata.sorted_tables}


def _diff(url: str) -> list[object]:
    engine = make_engine(url, poolclass=NullPool)
    try:
        with engine.connect() as conn:
            # the word search's index (FTS5 / pg_trgm, revision 0009) is outside the model
            opts = {"compare_type": True, "include_name": lambda n, *_: not is_search_index(n)}
            ctx = MigrationContext.configure(conn, opts=opts)
            return list(compare_metadata(ctx, Base.metadata))
    finally:
        engine.dispose()


def _tables(url: str) -> set[str]:
    engine = make_engine(url, poolclass=NullPool)
    try:
        return set(inspect(engine).get_table_names())
    finally:
        engine.dispose()


def _round_trip(url: str) -> None:
    assert migrate.current_revision(url) is None
    assert _diff(url), "an empty database must differ from the models"

    migrate.upgrade(url)
    assert migrate.current_revision(url) == migrate.head_revision() == "0011"
    assert migrate.is_up_to_date(url)
    assert TABLES <= _tables(url)
    assert _diff(url) == []

    engine = make_engine(url, poolclass=NullPool)
    indexes = {ix["name"] for ix in inspect(engine).get_indexes("jobs")}
    engine.dispose()
    assert {"ix_jobs_status", "ix_jobs_owner_key_id", "ix_jobs_sweep_id"} <= indexes

    migrate.downgrade(url, "base")
    assert _tables(url) & TABLES == set()
    assert migrate.current_revision(url) is None

    migrate.upgrade(url)  # and up again: downgrade left nothing behind
    assert _diff(url) == []


def test_sqlite_upgrade_downgrade_and_no_drift(tmp_path: Path) -> None:
    url = sqlite_url(tmp_path / "nested" / "dir")  # parent directories are created
    _round_trip(url)


@requires_postgres
def test_postgres_upgrade_downgrade_and_no_drift(pg_empty_url: str) -> None:
    _round_trip(pg_empty_url)


def test_alembic_ini_takes_the_url_from_x_argument(tmp_path: Path) -> None:
    ini = ROOT / "alembic.ini"
    assert "sqlalchemy.url" not in {
        line.split("=")[0].strip() for line in ini.read_text().splitlines()
    }
    url = sqlite_url(tmp_path)
    cfg = Config(str(ini), cmd_opts=argparse.Namespace(x=[f"url={url}"]))
    cfg.attributes["configure_logger"] = False
    command.upgrade(cfg, "head")
    assert migrate.current_revision(url) == "0011"
    command.downgrade(cfg, "base")
    assert migrate.current_revision(url) is None


def test_default_url_comes_from_the_settings(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from services.store.settings import get_settings

    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("LEGOPT_DATABASE_URL", raising=False)
    monkeypatch.delenv("LEGOPT_DATA_DIR", raising=False)
    get_settings.cache_clear()
    try:
        migrate.upgrade()
        assert (tmp_path / "legopt-data" / "legopt.db").is_file()
        assert migrate.is_up_to_date()
    finally:
        get_settings.cache_clear()


def test_offline_sql_renders(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # Offline (--sql) mode renders for PostgreSQL; SQLite's batch ALTERs need a live database.
    url = "postgresql+psycopg://legopt@127.0.0.1:5432/offline"
    command.upgrade(migrate.alembic_config(url), "head", sql=True)
    out = capsys.readouterr().out
    assert "CREATE TABLE jobs" in out
    assert "CREATE INDEX ix_jobs_status" in out
