"""Engines and transactional session scopes.

SQLite (the embedded default) gets, on every connection: WAL journal mode (readers never block
the writer), a ``busy_timeout`` (writers wait for the lock instead of failing), foreign keys ON
and SQLAlchemy-controlled ``BEGIN`` so that SAVEPOINTs and transactional DDL work with the
``sqlite3`` driver (see SQLAlchemy's "Transactions with SQLite and the sqlite3 driver").
``session_scope(immediate=True)`` takes the SQLite write lock at ``BEGIN`` (``BEGIN IMMEDIATE``),
which a transaction that reads before it writes needs to avoid ``database is locked`` when
another writer commits in between; on PostgreSQL the flag does nothing.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from sqlalchemy import Engine, create_engine, event
from sqlalchemy.engine import URL, Connection, make_url
from sqlalchemy.orm import Session, sessionmaker
from sqlalchemy.pool import StaticPool

from services.store.settings import Settings, get_settings

_BEGIN_OPTION = "legopt_sqlite_begin"


def _is_memory_sqlite(url: URL) -> bool:
    return url.get_backend_name() == "sqlite" and url.database in (None, "", ":memory:")


def ensure_sqlite_dir(url: str | URL) -> None:
    """Create the parent directory of a SQLite database file (no-op for other backends)."""
    url = make_url(url)
    if url.get_backend_name() == "sqlite" and not _is_memory_sqlite(url):
        assert url.database is not None
        Path(url.database).parent.mkdir(parents=True, exist_ok=True)


def normalize_url(url: str | URL) -> URL:
    """Parse ``url``; ``postgres://`` and ``postgresql://`` select the installed psycopg 3."""
    if isinstance(url, str) and url.startswith("postgres://"):
        url = "postgresql://" + url[len("postgres://") :]
    url = make_url(url)
    if url.drivername == "postgresql":
        url = url.set(drivername="postgresql+psycopg")
    return url


def make_engine(
    url: str | URL,
    *,
    echo: bool = False,
    sqlite_busy_timeout_ms: int = 30_000,
    sqlite_foreign_keys: bool = True,
    **kwargs: Any,
) -> Engine:
    """Create an engine for ``url`` with the SQLite pragmas described in the module docstring.

    For a SQLite file the parent directory is created. ``sqlite://`` (in memory) uses one
    shared connection, which is only suitable for single-threaded tests.
    ``sqlite_foreign_keys=False`` is for migrations (batch mode recreates tables).
    Extra ``kwargs`` go to ``sqlalchemy.create_engine``.
    """
    url = normalize_url(url)
    if url.get_backend_name() != "sqlite":
        kwargs.setdefault("pool_pre_ping", True)
        return create_engine(url, echo=echo, **kwargs)

    ensure_sqlite_dir(url)
    connect_args = dict(kwargs.pop("connect_args", {}))
    connect_args.setdefault("check_same_thread", False)
    # sqlite3's own lock wait (seconds); busy_timeout below says the same in milliseconds.
    connect_args.setdefault("timeout", sqlite_busy_timeout_ms / 1000.0)
    if _is_memory_sqlite(url):
        kwargs.setdefault("poolclass", StaticPool)
    engine = create_engine(url, echo=echo, connect_args=connect_args, **kwargs)
    memory = _is_memory_sqlite(url)

    @event.listens_for(engine, "connect")
    def _on_connect(dbapi_connection: Any, _record: Any) -> None:
        dbapi_connection.isolation_level = None  # SQLAlchemy emits BEGIN itself (below)
        cursor = dbapi_connection.cursor()
        try:
            if not memory:
                cursor.execute("PRAGMA journal_mode=WAL")
                cursor.execute("PRAGMA synchronous=NORMAL")
            cursor.execute(f"PRAGMA busy_timeout={int(sqlite_busy_timeout_ms)}")
            cursor.execute(f"PRAGMA foreign_keys={'ON' if sqlite_foreign_keys else 'OFF'}")
        finally:
            cursor.close()

    @event.listens_for(engine, "begin")
    def _on_begin(conn: Connection) -> None:
        mode = conn.get_execution_options().get(_BEGIN_OPTION, "DEFERRED")
        conn.exec_driver_sql(f"BEGIN {'IMMEDIATE' if mode == 'IMMEDIATE' else 'DEFERRED'}")

    return engine


def engine_from_settings(settings: Settings) -> Engine:
    """An engine for ``settings.database_url`` (see ``make_engine``)."""
    return make_engine(
        settings.database_url,
        echo=settings.db_echo,
        sqlite_busy_timeout_ms=settings.sqlite_busy_timeout_ms,
    )


def make_session_factory(engine: Engine) -> sessionmaker[Session]:
    """Session factory bound to ``engine``; objects are not expired on commit."""
    return sessionmaker(bind=engine, expire_on_commit=False, autoflush=True)


class _ProcessEngine:
    """The engine and session factory of this process, rebuilt in a forked child.

    A child process (Celery prefork, multiprocessing) must not use connections opened by its
    parent, so when the pid changes the inherited pool is dropped without closing the parent's
    connections (``dispose(close=False)``) and a new engine is made.

    No lock is held across a fork: a thread of the parent (the dispatcher, a heartbeat) may
    hold ``_lock`` at the instant billiard forks a pool child, and the child — which has only
    the forking thread — would then wait for it forever. ``os.register_at_fork`` gives the child
    a fresh lock and forgets the parent's engine (never touching its pool or connections).
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._pid: int | None = None
        self._engine: Engine | None = None
        self._factory: sessionmaker[Session] | None = None

    def after_fork_in_child(self) -> None:
        """Called in a forked child: fresh lock, no inherited engine (see the class doc)."""
        self._lock = threading.Lock()
        self._pid = self._engine = self._factory = None

    def get(self) -> tuple[Engine, sessionmaker[Session]]:
        with self._lock:
            if self._engine is None or self._factory is None or self._pid != os.getpid():
                if self._engine is not None:
                    self._engine.dispose(close=False)
                self._engine = engine_from_settings(get_settings())
                self._factory = make_session_factory(self._engine)
                self._pid = os.getpid()
            return self._engine, self._factory

    def reset(self) -> None:
        with self._lock:
            if self._engine is not None:
                self._engine.dispose(close=self._pid == os.getpid())
            self._pid = self._engine = self._factory = None


_PROCESS = _ProcessEngine()
if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_PROCESS.after_fork_in_child)


def get_engine() -> Engine:
    """The process-wide engine built from ``get_settings()`` (cached per process)."""
    return _PROCESS.get()[0]


def get_session_factory() -> sessionmaker[Session]:
    """The process-wide session factory over ``get_engine()``."""
    return _PROCESS.get()[1]


def reset_engine() -> None:
    """Dispose of the process-wide engine; the next use builds one from the current settings
    (call after ``get_settings.cache_clear()``)."""
    _PROCESS.reset()


@contextmanager
def session_scope(
    bind: Engine | sessionmaker[Session] | None = None, *, immediate: bool = False
) -> Iterator[Session]:
    """One transaction: commit when the block ends, roll back if it raises.

    ``bind`` is an engine or a session factory; default: the process-wide one. Repository
    functions never commit, so everything called inside one scope is one transaction.
    ``immediate=True`` starts the transaction with ``BEGIN IMMEDIATE`` on SQLite.
    """
    if bind is None:
        factory = get_session_factory()
    elif isinstance(bind, Engine):
        factory = make_session_factory(bind)
    else:
        factory = bind
    session = factory()
    try:
        if immediate:
            session.connection(execution_options={_BEGIN_OPTION: "IMMEDIATE"})
        yield session
        session.commit()
    except BaseException:
        session.rollback()
        raise
    finally:
        session.close()
