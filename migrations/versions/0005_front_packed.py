"""Per-generation fronts in a compact binary column (issue 12: job overhead).

Revision ID: 0005
Revises: 0004
Create Date: 2026-11-23

``generations.front_packed`` holds the front as float64 bytes
(:mod:`services.store.front_codec`); the JSON ``generations.front`` column stays for rows
written before this revision (readers fall back to it) and is no longer written.
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0005"
down_revision: str | Sequence[str] | None = "0004"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    """Add the nullable ``generations.front_packed`` binary column."""
    with op.batch_alter_table("generations") as batch:
        batch.add_column(sa.Column("front_packed", sa.LargeBinary(), nullable=True))


def downgrade() -> None:
    """Drop ``generations.front_packed``."""
    with op.batch_alter_table("generations") as batch:
        batch.drop_column("front_packed")
