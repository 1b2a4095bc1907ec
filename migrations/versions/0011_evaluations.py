"""Every evaluated solution kept for the trial table (issue 21, item 1).

Revision ID: 0011
Revises: 0010
Create Date: 2026-11-29

``evaluations``: one row per (job, generation) holding the solutions that generation evaluated
as packed float64 matrices (decision vectors, objectives in minimised form, constraint
violation); at most ``services.store.evaluations.MAX_STORED_EVALUATIONS`` solutions per job.
Jobs stored before this revision have none. Mirrors ``services.store.tables`` (the suite
compares autogenerate with the models).
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0011"
down_revision: str | Sequence[str] | None = "0010"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    """Create ``evaluations``."""
    op.create_table(
        "evaluations",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("job_id", sa.String(length=36), nullable=False),
        sa.Column("generation", sa.Integer(), nullable=False),
        sa.Column("n", sa.Integer(), nullable=False),
        sa.Column("x_packed", sa.LargeBinary(), nullable=False),
        sa.Column("f_packed", sa.LargeBinary(), nullable=False),
        sa.Column("cv_packed", sa.LargeBinary(), nullable=False),
        sa.ForeignKeyConstraint(
            ["job_id"], ["jobs.id"], name=op.f("fk_evaluations_job_id_jobs"), ondelete="CASCADE"
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_evaluations")),
        sa.UniqueConstraint("job_id", "generation", name=op.f("uq_evaluations_job_id_generation")),
    )


def downgrade() -> None:
    """Drop ``evaluations``."""
    op.drop_table("evaluations")
