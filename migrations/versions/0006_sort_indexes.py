"""Jobs page: every sort order on an index (issue 10: paging flat at 10^5 jobs).

Revision ID: 0006
Revises: 0005
Create Date: 2026-11-27

``jobs.best_value`` holds the first objective of ``best_objective`` as a number (the "best"
sort read it from JSON, scanning every job of the key); each sortable column gets an index
ending in the page order's tie-break ``(created_at, id)``, so a page by keyset costs the same
at any depth. Existing jobs' ``best_value`` is filled here from their ``best_objective``.
Mirrors ``services.store.tables`` (the suite compares autogenerate with the models).
"""

import math
from collections.abc import Sequence
from typing import Any

import sqlalchemy as sa
from alembic import op

revision: str = "0006"
down_revision: str | Sequence[str] | None = "0005"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: Indexes of revision 0004 that the longer ones below replace.
Columns = tuple[str, ...]
OLD_JOB_INDEXES: tuple[Columns, ...] = (
    ("owner_key_id", "status", "created_at"),
    ("owner_key_id", "finished_at"),
)
JOB_INDEXES: tuple[Columns, ...] = (
    ("owner_key_id", "status", "created_at", "id"),
    ("owner_key_id", "finished_at", "created_at", "id"),
    ("owner_key_id", "progress_generation", "created_at", "id"),
    ("owner_key_id", "best_value", "created_at", "id"),
)
OLD_LABEL_INDEXES: tuple[Columns, ...] = (("owner_key_id", "kind", "created_at"),)
LABEL_INDEXES: tuple[Columns, ...] = (
    ("owner_key_id", "kind", "created_at", "job_id"),
    ("owner_key_id", "robot", "created_at", "job_id"),
    ("owner_key_id", "optimizer", "created_at", "job_id"),
)


def _name(table: str, columns: Sequence[str]) -> str:
    return f"ix_{table}_{'_'.join(columns)}"


def first_objective(best: Any) -> float | None:
    """The number the jobs page sorts by: ``best`` itself or its first element, if finite
    (a copy of ``services.store.progress.first_objective``: a migration does not import the
    application)."""
    if isinstance(best, list | tuple):
        best = best[0] if best else None
    if isinstance(best, bool) or not isinstance(best, int | float):
        return None
    value = float(best)
    return value if math.isfinite(value) else None


#: The fill in SQL, for offline (``--sql``) PostgreSQL scripts: the first element of an array
#: or the number itself (JSON numbers are finite).
PG_FILL = """
UPDATE jobs SET best_value = CASE json_typeof(best_objective)
    WHEN 'number' THEN (best_objective::text)::double precision
    WHEN 'array' THEN CASE json_typeof(best_objective -> 0)
        WHEN 'number' THEN ((best_objective -> 0)::text)::double precision END
    END
WHERE best_objective IS NOT NULL
"""


def _fill_best_values() -> None:
    if op.get_context().as_sql:
        if op.get_context().dialect.name == "postgresql":
            op.execute(PG_FILL)
        return
    jobs = sa.table(
        "jobs", sa.column("id", sa.String()), sa.column("best_objective", sa.JSON()),
        sa.column("best_value", sa.Float()),
    )  # fmt: skip
    conn = op.get_bind()
    rows = conn.execute(
        sa.select(jobs.c.id, jobs.c.best_objective).where(jobs.c.best_objective.is_not(None))
    ).all()
    values = [{"jid": r.id, "v": first_objective(r.best_objective)} for r in rows]
    values = [v for v in values if v["v"] is not None]
    stmt = (
        jobs.update().where(jobs.c.id == sa.bindparam("jid")).values(best_value=sa.bindparam("v"))
    )
    for start in range(0, len(values), 1000):
        conn.execute(stmt, values[start : start + 1000])


def upgrade() -> None:
    """Add ``jobs.best_value`` (filled from ``best_objective``) and the sort indexes."""
    with op.batch_alter_table("jobs") as batch:
        batch.add_column(sa.Column("best_value", sa.Float(), nullable=True))
    _fill_best_values()
    with op.batch_alter_table("jobs") as batch:
        for columns in OLD_JOB_INDEXES:
            batch.drop_index(_name("jobs", columns))
        for columns in JOB_INDEXES:
            batch.create_index(_name("jobs", columns), list(columns))
    for columns in OLD_LABEL_INDEXES:
        op.drop_index(_name("job_labels", columns), table_name="job_labels")
    for columns in LABEL_INDEXES:
        op.create_index(_name("job_labels", columns), "job_labels", list(columns))


def downgrade() -> None:
    """Back to revision 0005's indexes; drop ``jobs.best_value``."""
    for columns in LABEL_INDEXES:
        op.drop_index(_name("job_labels", columns), table_name="job_labels")
    for columns in OLD_LABEL_INDEXES:
        op.create_index(_name("job_labels", columns), "job_labels", list(columns))
    with op.batch_alter_table("jobs") as batch:
        for columns in JOB_INDEXES:
            batch.drop_index(_name("jobs", columns))
        for columns in OLD_JOB_INDEXES:
            batch.create_index(_name("jobs", columns), list(columns))
        batch.drop_column("best_value")
