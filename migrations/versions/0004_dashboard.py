"""Dashboard: job labels (what the jobs page filters, sorts and searches by), the newest-first
index of a key's jobs, and the reference point of the per-generation hypervolumes.

Revision ID: 0004
Revises: 0003
Create Date: 2026-11-23

Mirrors ``services.store.tables`` (the test suite compares autogenerate with the models on
SQLite and PostgreSQL). Labels of jobs that exist when this runs are written on the first read
of the dashboard (``services.store.dashboard_queries.sync_labels``), not here: a migration
stays a schema change.
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0004"
down_revision: str | Sequence[str] | None = "0003"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

ID = sa.String(36)
#: Indexes of the jobs page on ``jobs``: newest first, by status, by finishing time.
JOB_INDEXES = (
    ("owner_key_id", "created_at"),
    ("owner_key_id", "status", "created_at"),
    ("owner_key_id", "finished_at"),
)


def upgrade() -> None:
    """Create ``job_labels``; add ``jobs.hypervolume_ref`` and the jobs page's indexes."""
    with op.batch_alter_table("jobs") as batch:
        batch.add_column(sa.Column("hypervolume_ref", sa.JSON(), nullable=True))
        for columns in JOB_INDEXES:
            batch.create_index(batch.f(f"ix_jobs_{'_'.join(columns)}"), list(columns))
    op.create_table(
        "job_labels",
        sa.Column("job_id", ID, nullable=False),
        sa.Column("owner_key_id", ID, nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.Column("name", sa.String(200), nullable=True),
        sa.Column("kind", sa.String(64), nullable=False),
        sa.Column("robot", sa.String(200), nullable=False),
        sa.Column("optimizer", sa.String(32), nullable=False),
        sa.Column("seed", sa.BigInteger(), nullable=False),
        sa.Column("tags", sa.Text(), nullable=False),
        sa.Column("search", sa.Text(), nullable=False),
        sa.ForeignKeyConstraint(
            ["job_id"], ["jobs.id"], name=op.f("fk_job_labels_job_id_jobs"), ondelete="CASCADE"
        ),
        sa.ForeignKeyConstraint(
            ["owner_key_id"],
            ["api_keys.id"],
            name=op.f("fk_job_labels_owner_key_id_api_keys"),
            ondelete="CASCADE",
        ),
        sa.PrimaryKeyConstraint("job_id", name=op.f("pk_job_labels")),
    )
    op.create_index(
        op.f("ix_job_labels_owner_key_id_created_at"), "job_labels", ["owner_key_id", "created_at"]
    )
    op.create_index(
        op.f("ix_job_labels_owner_key_id_kind_created_at"),
        "job_labels",
        ["owner_key_id", "kind", "created_at"],
    )


def downgrade() -> None:
    """Drop what ``upgrade`` added."""
    op.drop_index(op.f("ix_job_labels_owner_key_id_kind_created_at"), table_name="job_labels")
    op.drop_index(op.f("ix_job_labels_owner_key_id_created_at"), table_name="job_labels")
    op.drop_table("job_labels")
    with op.batch_alter_table("jobs") as batch:
        for columns in JOB_INDEXES:
            batch.drop_index(batch.f(f"ix_jobs_{'_'.join(columns)}"))
        batch.drop_column("hypervolume_ref")
