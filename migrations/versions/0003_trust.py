"""Trust: dispatch outbox, job events, elected service roles, idempotency keys, key roles,
expiry, revocation and quotas; sweep jobs store only their overrides.

Revision ID: 0003
Revises: 0002
Create Date: 2026-11-23

Mirrors ``services.store.tables`` (the test suite compares autogenerate with the models on
SQLite and PostgreSQL). Jobs that are queued when this runs are made due for dispatch at once,
so a database upgraded with work in it loses none.
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0003"
down_revision: str | Sequence[str] | None = "0002"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

ID = sa.String(36)
KEY_ROLES = ("user", "admin")
EVENT_KINDS = (
    "submitted",
    "dispatched",
    "claimed",
    "requeued",
    "succeeded",
    "failed",
    "cancelled",
)


def _in(column: str, values: Sequence[str]) -> str:
    return f"{column} IN ({', '.join(repr(v) for v in values)})"


def _timestamp(name: str, nullable: bool = False) -> sa.Column:
    return sa.Column(name, sa.DateTime(timezone=True), nullable=nullable)


def _owner_fk(table: str) -> sa.ForeignKeyConstraint:
    return sa.ForeignKeyConstraint(
        ["owner_key_id"],
        ["api_keys.id"],
        name=op.f(f"fk_{table}_owner_key_id_api_keys"),
        ondelete="CASCADE",
    )


def upgrade() -> None:
    """Add the columns and tables; make queued jobs due for dispatch."""
    with op.batch_alter_table("api_keys") as batch:
        batch.add_column(
            sa.Column("role", sa.String(16), nullable=False, server_default="user")
        )
        batch.add_column(_timestamp("expires_at", nullable=True))
        batch.add_column(_timestamp("revoked_at", nullable=True))
        batch.add_column(sa.Column("max_active_jobs", sa.Integer(), nullable=True))
        batch.add_column(sa.Column("max_cpu_seconds_per_hour", sa.Float(), nullable=True))
        batch.add_column(sa.Column("max_storage_bytes", sa.BigInteger(), nullable=True))
        batch.create_check_constraint(op.f("ck_api_keys_key_role"), _in("role", KEY_ROLES))
    with op.batch_alter_table("jobs") as batch:
        batch.alter_column("spec", existing_type=sa.JSON(), nullable=True)
        batch.add_column(sa.Column("overrides", sa.JSON(), nullable=True))
        batch.add_column(
            sa.Column("spec_bytes", sa.BigInteger(), nullable=False, server_default="0")
        )
        batch.add_column(sa.Column("cpu_seconds", sa.Float(), nullable=False, server_default="0"))
        batch.add_column(_timestamp("dispatch_due_at", nullable=True))
        batch.add_column(_timestamp("last_dispatch_at", nullable=True))
        batch.add_column(
            sa.Column("dispatch_count", sa.Integer(), nullable=False, server_default="0")
        )
        batch.create_index(batch.f("ix_jobs_status_dispatch_due_at"), ["status", "dispatch_due_at"])
    op.execute(
        "UPDATE jobs SET dispatch_due_at = created_at "
        "WHERE status = 'queued' AND cancel_requested = false"
    )
    op.create_table(
        "job_events",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("job_id", ID, nullable=False),
        _timestamp("at"),
        sa.Column("kind", sa.String(16), nullable=False),
        sa.Column("attempt", sa.Integer(), nullable=False),
        sa.Column("actor", sa.String(200), nullable=True),
        sa.Column("detail", sa.Text(), nullable=True),
        sa.CheckConstraint(_in("kind", EVENT_KINDS), name=op.f("ck_job_events_job_event_kind")),
        sa.ForeignKeyConstraint(
            ["job_id"], ["jobs.id"], name=op.f("fk_job_events_job_id_jobs"), ondelete="CASCADE"
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_job_events")),
    )
    op.create_index(op.f("ix_job_events_job_id"), "job_events", ["job_id"])
    op.create_table(
        "service_leases",
        sa.Column("name", sa.String(64), nullable=False),
        sa.Column("owner", sa.String(200), nullable=False),
        _timestamp("expires_at"),
        sa.PrimaryKeyConstraint("name", name=op.f("pk_service_leases")),
    )
    op.create_table(
        "idempotency_keys",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("owner_key_id", ID, nullable=False),
        sa.Column("key", sa.String(200), nullable=False),
        sa.Column("request_sha256", sa.String(64), nullable=False),
        sa.Column("resource_kind", sa.String(16), nullable=False),
        sa.Column("resource_id", ID, nullable=False),
        _timestamp("created_at"),
        _owner_fk("idempotency_keys"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_idempotency_keys")),
        sa.UniqueConstraint(
            "owner_key_id", "key", name=op.f("uq_idempotency_keys_owner_key_id_key")
        ),
    )
    op.create_table(
        "key_usage",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("owner_key_id", ID, nullable=False),
        _timestamp("hour"),
        sa.Column("cpu_seconds", sa.Float(), nullable=False),
        _owner_fk("key_usage"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_key_usage")),
        sa.UniqueConstraint("owner_key_id", "hour", name=op.f("uq_key_usage_owner_key_id_hour")),
    )


def downgrade() -> None:
    """Drop what ``upgrade`` added (sweep jobs get their materialised spec back first)."""
    op.drop_table("key_usage")
    op.drop_table("idempotency_keys")
    op.drop_table("service_leases")
    op.drop_index(op.f("ix_job_events_job_id"), table_name="job_events")
    op.drop_table("job_events")
    _materialise_sweep_job_specs()
    with op.batch_alter_table("jobs") as batch:
        batch.drop_index(batch.f("ix_jobs_status_dispatch_due_at"))
        batch.drop_column("dispatch_count")
        batch.drop_column("last_dispatch_at")
        batch.drop_column("dispatch_due_at")
        batch.drop_column("cpu_seconds")
        batch.drop_column("spec_bytes")
        batch.drop_column("overrides")
        batch.alter_column("spec", existing_type=sa.JSON(), nullable=False)
    with op.batch_alter_table("api_keys") as batch:
        batch.drop_constraint(op.f("ck_api_keys_key_role"), type_="check")
        batch.drop_column("max_storage_bytes")
        batch.drop_column("max_cpu_seconds_per_hour")
        batch.drop_column("max_active_jobs")
        batch.drop_column("revoked_at")
        batch.drop_column("expires_at")
        batch.drop_column("role")


def _materialise_sweep_job_specs() -> None:
    """Write each sweep job's full spec (base + overrides) back into ``jobs.spec``."""
    from services.store.specs import apply_overrides

    conn = op.get_bind()
    jobs = sa.table(
        "jobs",
        sa.column("id", ID),
        sa.column("sweep_id", ID),
        sa.column("spec", sa.JSON()),
        sa.column("overrides", sa.JSON()),
    )
    sweeps = sa.table("sweeps", sa.column("id", ID), sa.column("base_spec", sa.JSON()))
    rows = conn.execute(
        sa.select(jobs.c.id, jobs.c.overrides, sweeps.c.base_spec)
        .join(sweeps, sweeps.c.id == jobs.c.sweep_id)
        .where(jobs.c.spec.is_(None))
    ).all()
    for job_id, overrides, base in rows:
        spec = apply_overrides(base or {}, overrides or {})
        conn.execute(sa.update(jobs).where(jobs.c.id == job_id).values(spec=spec))
    conn.execute(sa.update(jobs).where(jobs.c.spec.is_(None)).values(spec={}))
