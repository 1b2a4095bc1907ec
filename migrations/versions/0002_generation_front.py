"""Per-generation Pareto front (objective vectors) for the recordings' generation timeline.

Revision ID: 0002
Revises: 0001
Create Date: 2026-11-21
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0002"
down_revision: str | Sequence[str] | None = "0001"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    """Add the nullable ``generations.front`` JSON column."""
    with op.batch_alter_table("generations") as batch:
        batch.add_column(sa.Column("front", sa.JSON(), nullable=True))


def downgrade() -> None:
    """Drop ``generations.front``."""
    with op.batch_alter_table("generations") as batch:
        batch.drop_column("front")
