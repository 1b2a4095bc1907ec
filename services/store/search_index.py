"""The jobs page's word search (``services.store.job_search_paging``) is a substring match on
``job_labels.search``. Its index is backend-specific, so it is not part of the portable model
(nor of what autogenerate compares): revision 0009 creates it, and ``create_all`` (the tests)
through the listeners in ``services.store.tables``.

- PostgreSQL: a pg_trgm GIN index, ``SEARCH_TRGM_INDEX``; the planner answers the same
  ``search LIKE '%word%'`` from it. Where the extension cannot be created the search scans,
  as before (same results).
- SQLite >= 3.34 with FTS5: the FTS5 table ``SEARCH_FTS`` (trigram tokenizer, case-sensitive:
  the text and the words are lower-cased already, so a phrase matches exactly where the LIKE
  it replaces does), an index over ``job_labels.search`` by the label's rowid (external
  content: the text is not stored twice), kept in step by triggers on insert, update and
  delete (deletes cascaded from jobs and api_keys included). Without FTS5 or the trigram
  tokenizer nothing is created and the search scans, as before.

A migration that rebuilds ``job_labels`` on SQLite (Alembic's batch mode copies the table:
new rowids, and the triggers go with the old table) must create the triggers again and
rebuild the index (``search_index_ddl("sqlite")``: drop ``SEARCH_FTS`` first).
"""

from __future__ import annotations

import logging

from sqlalchemy.engine import Connection
from sqlalchemy.exc import DBAPIError

_log = logging.getLogger("legopt.store")


#: SQLite: the FTS5 table of the word search (and the prefix of its shadow tables).
SEARCH_FTS = "job_labels_fts"
#: PostgreSQL: the pg_trgm GIN index of the word search.
SEARCH_TRGM_INDEX = "ix_job_labels_search_trgm"
#: Words shorter than this are matched by LIKE: a trigram index cannot answer them.
MIN_INDEXED_WORD = 3

_SQLITE_SEARCH_DDL = (
    f"CREATE VIRTUAL TABLE {SEARCH_FTS} USING fts5(search, content = 'job_labels', "
    "content_rowid = 'rowid', tokenize = 'trigram case_sensitive 1')",
    f"CREATE TRIGGER {SEARCH_FTS}_insert AFTER INSERT ON job_labels BEGIN "
    f"INSERT INTO {SEARCH_FTS} (rowid, search) VALUES (new.rowid, new.search); END",
    f"CREATE TRIGGER {SEARCH_FTS}_delete AFTER DELETE ON job_labels BEGIN "
    f"INSERT INTO {SEARCH_FTS} ({SEARCH_FTS}, rowid, search) "
    "VALUES ('delete', old.rowid, old.search); END",
    f"CREATE TRIGGER {SEARCH_FTS}_update AFTER UPDATE OF search ON job_labels BEGIN "
    f"INSERT INTO {SEARCH_FTS} ({SEARCH_FTS}, rowid, search) "
    "VALUES ('delete', old.rowid, old.search); "
    f"INSERT INTO {SEARCH_FTS} (rowid, search) VALUES (new.rowid, new.search); END",
    f"INSERT INTO {SEARCH_FTS} ({SEARCH_FTS}) VALUES ('rebuild')",
)
_POSTGRESQL_SEARCH_DDL = (
    "CREATE EXTENSION IF NOT EXISTS pg_trgm",
    f"CREATE INDEX {SEARCH_TRGM_INDEX} ON job_labels USING gin (search gin_trgm_ops)",
)


def search_index_ddl(dialect: str) -> tuple[str, ...]:
    """The statements creating the word search's index on ``dialect`` (and, on SQLite,
    filling it from the labels there are); empty for other backends."""
    return {"sqlite": _SQLITE_SEARCH_DDL, "postgresql": _POSTGRESQL_SEARCH_DDL}.get(dialect, ())


def sqlite_has_trigram_fts(connection: Connection) -> bool:
    """True if this SQLite library has FTS5 with the trigram tokenizer (3.34 and later)."""
    version = connection.exec_driver_sql("SELECT sqlite_version()").scalar_one()
    if tuple(int(p) for p in str(version).split(".")[:2]) < (3, 34):
        return False
    options = {str(r[0]) for r in connection.exec_driver_sql("PRAGMA compile_options")}
    return "ENABLE_FTS5" in options


def is_search_index(name: str | None) -> bool:
    """True for the word search's objects outside the model (for autogenerate comparisons:
    ``include_name``)."""
    return bool(name) and (name == SEARCH_TRGM_INDEX or str(name).startswith(SEARCH_FTS))


def create_search_index(connection: Connection) -> bool:
    """Create the word search's index on ``connection`` (after ``job_labels``); False, with a
    warning, where the backend cannot have it (the search then scans, as before)."""
    dialect = connection.dialect.name
    if dialect == "sqlite" and not sqlite_has_trigram_fts(connection):
        _log.warning(
            "SQLite %s has no FTS5 trigram tokenizer (3.34+): the jobs page's word search "
            "scans the labels", connection.exec_driver_sql("SELECT sqlite_version()").scalar(),
        )  # fmt: skip
        return False
    statements = search_index_ddl(dialect)
    if dialect != "postgresql":
        for stmt in statements:
            connection.exec_driver_sql(stmt)
        return bool(statements)
    try:
        with connection.begin_nested():
            for stmt in statements:
                connection.exec_driver_sql(stmt)
    except DBAPIError as exc:
        _log.warning(
            "no pg_trgm index for the jobs page's word search (%s): it scans the labels; "
            "a superuser can run %s; then %s", str(exc.orig).strip().splitlines()[0],
            *statements,
        )  # fmt: skip
        return False
    return True
