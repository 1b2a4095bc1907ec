"""The jobs page's word search reads an index (issue 23, item 3).

Revision ID: 0009
Revises: 0008
Create Date: 2026-11-29

Word search was ``job_labels.search LIKE '%word%'``: a scan of the key's labels (27 ms on
SQLite, 38 ms on PostgreSQL at 10^5 jobs, growing linearly). This revision adds a substring
index on that text (what ``services.store.search_index`` describes). It is
not part of the portable model: a comparison with the models leaves it out
(``include_name``: ``services.store.search_index.is_search_index``, as the migration test does).

- PostgreSQL: ``CREATE EXTENSION IF NOT EXISTS pg_trgm`` and a GIN index
  ``ix_job_labels_search_trgm (search gin_trgm_ops)``; the planner answers the unchanged
  ``LIKE`` from it. If the extension cannot be created (a role without the right, a server
  without the contrib package) the revision still applies, without the index, and logs what
  an administrator can run later; the search then scans, as before, with the same results.
  The index is built with a write lock on ``job_labels`` (seconds at 10^6 labels). Downgrade
  drops the index, not the extension (other schemas may use it).
- SQLite >= 3.34 with FTS5: the FTS5 table ``job_labels_fts`` over ``job_labels.search``
  (trigram tokenizer, case-sensitive: text and words are lower-cased, so a phrase matches
  exactly where the LIKE it replaces does; external content, by the label's rowid), built
  from the labels there are, and three triggers that keep it in step with ``job_labels``
  (insert, update, delete — cascaded deletes included). An older SQLite gets nothing and
  keeps the LIKE scan.

A later migration that rebuilds ``job_labels`` on SQLite (batch mode) must create these
again: the copy has new rowids, and the triggers go with the old table.
"""

import logging
from collections.abc import Sequence

from alembic import context, op
from sqlalchemy.exc import DBAPIError

revision: str = "0009"
down_revision: str | Sequence[str] | None = "0008"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

log = logging.getLogger("alembic.runtime.migration")

FTS = "job_labels_fts"
TRGM_INDEX = "ix_job_labels_search_trgm"
TRIGGERS = (f"{FTS}_insert", f"{FTS}_delete", f"{FTS}_update")
SQLITE = (
    f"CREATE VIRTUAL TABLE {FTS} USING fts5(search, content = 'job_labels', "
    "content_rowid = 'rowid', tokenize = 'trigram case_sensitive 1')",
    f"CREATE TRIGGER {FTS}_insert AFTER INSERT ON job_labels BEGIN "
    f"INSERT INTO {FTS} (rowid, search) VALUES (new.rowid, new.search); END",
    f"CREATE TRIGGER {FTS}_delete AFTER DELETE ON job_labels BEGIN "
    f"INSERT INTO {FTS} ({FTS}, rowid, search) VALUES ('delete', old.rowid, old.search); END",
    f"CREATE TRIGGER {FTS}_update AFTER UPDATE OF search ON job_labels BEGIN "
    f"INSERT INTO {FTS} ({FTS}, rowid, search) VALUES ('delete', old.rowid, old.search); "
    f"INSERT INTO {FTS} (rowid, search) VALUES (new.rowid, new.search); END",
    f"INSERT INTO {FTS} ({FTS}) VALUES ('rebuild')",  # the labels there are
)
EXTENSION = "CREATE EXTENSION IF NOT EXISTS pg_trgm"
POSTGRESQL_INDEX = f"CREATE INDEX {TRGM_INDEX} ON job_labels USING gin (search gin_trgm_ops)"


def _sqlite_has_trigram_fts() -> bool:
    bind = op.get_bind()
    version = str(bind.exec_driver_sql("SELECT sqlite_version()").scalar_one())
    options = {str(r[0]) for r in bind.exec_driver_sql("PRAGMA compile_options")}
    major_minor = tuple(int(p) for p in version.split(".")[:2])
    if major_minor >= (3, 34) and "ENABLE_FTS5" in options:
        return True
    log.warning(
        "SQLite %s has no FTS5 trigram tokenizer (needs 3.34+ with FTS5): no search index, "
        "the jobs page's word search scans the labels as before", version,
    )  # fmt: skip
    return False


def _postgresql_upgrade() -> None:
    if context.is_offline_mode():  # a script for an administrator: both statements
        op.execute(EXTENSION)
        op.execute(POSTGRESQL_INDEX)
        return
    bind = op.get_bind()
    try:
        with bind.begin_nested():
            bind.exec_driver_sql(EXTENSION)
    except DBAPIError as exc:
        reason = str(exc.orig).strip().splitlines()[0] if exc.orig else str(exc)
        log.warning(
            "pg_trgm could not be created (%s): no search index, the jobs page's word search "
            "scans the labels as before (same results). To add it later, a role allowed to "
            "create extensions runs in this database: %s; %s;", reason, EXTENSION,
            POSTGRESQL_INDEX,
        )  # fmt: skip
        return
    op.execute(POSTGRESQL_INDEX)


def upgrade() -> None:
    """Create the word search's index of this backend (none where it cannot exist)."""
    dialect = op.get_context().dialect.name
    if dialect == "postgresql":
        _postgresql_upgrade()
    elif dialect == "sqlite" and _sqlite_has_trigram_fts():
        for stmt in SQLITE:
            op.execute(stmt)


def downgrade() -> None:
    """Drop the search index (PostgreSQL keeps the extension)."""
    dialect = op.get_context().dialect.name
    if dialect == "postgresql":
        op.execute(f"DROP INDEX IF EXISTS {TRGM_INDEX}")
    elif dialect == "sqlite":
        for trigger in TRIGGERS:
            op.execute(f"DROP TRIGGER IF EXISTS {trigger}")
        op.execute(f"DROP TABLE IF EXISTS {FTS}")
