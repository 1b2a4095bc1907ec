"""What submission learned of a job, stored once (issue 24, item 3).

Revision ID: 0010
Revises: 0009
Create Date: 2026-11-28

``jobs.facts`` (JSON, nullable): the job's study kind, resolved robot and optimizer (the
study's defaults filled in), objective names and number of decision variables, as the API's
validation found them (``services.api.validation.job_facts``). Readers (the dashboard's
labels, the CLI's tables) take them from here instead of rebuilding the study. Jobs stored
before this revision keep NULL; their readers fall back to what they did before. Mirrors
``services.store.tables`` (the suite compares autogenerate with the models).
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0010"
down_revision: str | Sequence[str] | None = "0009"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    """Add ``jobs.facts`` (NULL: stored before it was kept)."""
    with op.batch_alter_table("jobs") as batch:
        batch.add_column(sa.Column("facts", sa.JSON(), nullable=True))


def downgrade() -> None:
    """Drop ``jobs.facts``."""
    with op.batch_alter_table("jobs") as batch:
        batch.drop_column("facts")
