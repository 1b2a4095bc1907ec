"""Alembic environment: the tables of ``services.store.tables``, the URL of the settings.

URL, first found wins: ``alembic -x url=...``; the ``sqlalchemy.url`` main option (set by
``services.store.migrate``); ``LEGOPT_DATABASE_URL`` / the default of the settings object.
A caller may also pass an open connection as ``config.attributes["connection"]``.
SQLite runs in batch mode (ALTER TABLE through table copies) with foreign keys off, and
in one transaction per run like PostgreSQL.
"""

from __future__ import annotations

from logging.config import fileConfig
from typing import Any, Literal

from alembic import context
from sqlalchemy.engine import Connection
from sqlalchemy.pool import NullPool

from services.store.search_index import is_search_index
from services.store.session import make_engine, normalize_url
from services.store.settings import get_settings
from services.store.tables import Base
from services.store.types import JSONValue, UTCDateTime

config = context.config
if config.config_file_name is not None and config.attributes.get("configure_logger", True):
    fileConfig(config.config_file_name, disable_existing_loggers=False)

target_metadata = Base.metadata


def database_url() -> str:
    """The URL to migrate (see the module docstring for the order)."""
    x_url = context.get_x_argument(as_dictionary=True).get("url")
    if x_url:
        return x_url
    main_url = config.get_main_option("sqlalchemy.url")
    if main_url:
        return main_url
    return get_settings().database_url


def render_item(type_: str, obj: Any, autogen_context: Any) -> str | Literal[False]:
    """Render the portable column types as plain SQLAlchemy types in new revisions."""
    if type_ == "type" and isinstance(obj, UTCDateTime):
        return "sa.DateTime(timezone=True)"
    if type_ == "type" and isinstance(obj, JSONValue):
        return "sa.JSON()"
    return False


def include_name(name: str | None, type_: str, parent_names: Any) -> bool:
    """Leave the word search's index (revision 0009: an FTS5 table and its triggers on SQLite,
    a pg_trgm index on PostgreSQL) out of autogenerate: it lives outside the models."""
    return not is_search_index(name)


def _configure(**kwargs: Any) -> None:
    context.configure(
        target_metadata=target_metadata,
        compare_type=True,
        render_item=render_item,
        include_name=include_name,
        **kwargs,
    )


def run_migrations_offline() -> None:
    """Emit SQL to stdout (``alembic upgrade head --sql``)."""
    url = normalize_url(database_url())
    _configure(
        url=url,
        literal_binds=True,
        dialect_opts={"paramstyle": "named"},
        render_as_batch=url.get_backend_name() == "sqlite",
    )
    with context.begin_transaction():
        context.run_migrations()


def _run_on(connection: Connection, *, own_engine: bool) -> None:
    options: dict[str, Any] = {"render_as_batch": connection.dialect.name == "sqlite"}
    if own_engine:
        # make_engine has SQLAlchemy emit BEGIN on SQLite, so DDL there is transactional too:
        # a failing migration leaves the database as it was.
        options["transactional_ddl"] = True
    _configure(connection=connection, **options)
    with context.begin_transaction():
        context.run_migrations()


def run_migrations_online() -> None:
    """Migrate through a connection (given, or from the URL)."""
    connection = config.attributes.get("connection")
    if connection is not None:
        _run_on(connection, own_engine=False)
        return
    engine = make_engine(database_url(), poolclass=NullPool, sqlite_foreign_keys=False)
    try:
        with engine.connect() as conn:
            _run_on(conn, own_engine=True)
    finally:
        engine.dispose()


if context.is_offline_mode():
    run_migrations_offline()
else:
    run_migrations_online()
