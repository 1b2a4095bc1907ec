"""Robots by reference: robot documents stored once by content (issue 8).

Revision ID: 0007
Revises: 0006
Create Date: 2026-11-27

``robot_documents`` holds each distinct robot document (an inline spec or a stored robot's
document as submitted) once, keyed by the SHA-256 of its canonical JSON; job and sweep specs
stored from now on refer to it (``services.store.robot_documents``). Specs stored before keep
their documents inline and read back unchanged, so no data moves here.
Mirrors ``services.store.tables`` (the suite compares autogenerate with the models).
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0007"
down_revision: str | Sequence[str] | None = "0006"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    """Create ``robot_documents``."""
    op.create_table(
        "robot_documents",
        sa.Column("sha256", sa.String(64), nullable=False),
        sa.Column("spec", sa.JSON(), nullable=False),
        sa.Column("size_bytes", sa.BigInteger(), nullable=False),
        sa.Column("created_at", sa.DateTime(timezone=True), nullable=False),
        sa.PrimaryKeyConstraint("sha256", name=op.f("pk_robot_documents")),
    )


def downgrade() -> None:
    """Drop ``robot_documents`` after putting the documents back into the specs that refer to
    them (a downgraded store must read without this table)."""
    _inline_documents()
    op.drop_table("robot_documents")


def _inline_documents() -> None:
    if op.get_context().as_sql:
        return
    conn = op.get_bind()
    docs = sa.table("robot_documents", sa.column("sha256", sa.String()),
                    sa.column("spec", sa.JSON()))  # fmt: skip
    found = {r.sha256: r.spec for r in conn.execute(sa.select(docs.c.sha256, docs.c.spec))}
    if not found:
        return
    for table, column in (("jobs", "spec"), ("jobs", "overrides"), ("sweeps", "base_spec")):
        t = sa.table(table, sa.column("id", sa.String()), sa.column(column, sa.JSON()))
        col = t.c[column]
        for row in conn.execute(sa.select(t.c.id, col).where(col.is_not(None))).all():
            spec = row[1]
            robot = spec.get("robot") if isinstance(spec, dict) else None
            sha = robot.get("$robot_document") if isinstance(robot, dict) else None
            if sha in found:
                inlined = {**spec, "robot": found[sha]}
                conn.execute(t.update().where(t.c.id == row[0]).values({column: inlined}))
