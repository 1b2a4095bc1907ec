"""Feasibility is part of a job's answer (issue 25, item 2).

Revision ID: 0008
Revises: 0007
Create Date: 2026-11-28

``jobs.feasible`` (nullable boolean) and ``jobs.violations`` (JSON: ``[{"constraint",
"amount", "unit", "text"}, ...]``) hold the verdict of a succeeded job's reported optimum,
written by ``finish_job`` with the result: NULL until a job succeeds. Jobs that succeeded
before this revision keep NULL (their optimum was never checked; nothing here can check it),
which every view shows as "not checked", never as feasible. The index
``(owner_key_id, feasible, created_at, id)`` serves the jobs list's ``feasible`` filter in
the page order. Mirrors ``services.store.tables`` (the suite compares autogenerate with the
models).
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0008"
down_revision: str | Sequence[str] | None = "0007"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

INDEX = ("owner_key_id", "feasible", "created_at", "id")


def _name(table: str, columns: Sequence[str]) -> str:
    return f"ix_{table}_{'_'.join(columns)}"


def upgrade() -> None:
    """Add ``jobs.feasible`` and ``jobs.violations`` (NULL: not checked) and their index."""
    with op.batch_alter_table("jobs") as batch:
        batch.add_column(sa.Column("feasible", sa.Boolean(), nullable=True))
        batch.add_column(sa.Column("violations", sa.JSON(), nullable=True))
        batch.create_index(_name("jobs", INDEX), list(INDEX))


def downgrade() -> None:
    """Drop the index, ``jobs.violations`` and ``jobs.feasible``."""
    with op.batch_alter_table("jobs") as batch:
        batch.drop_index(_name("jobs", INDEX))
        batch.drop_column("violations")
        batch.drop_column("feasible")
