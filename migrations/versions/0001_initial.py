"""Initial schema: API keys, robots, sweeps, jobs and their outputs.

Revision ID: 0001
Revises:
Create Date: 2026-05-01

Written by hand to mirror ``services.store.tables`` (the test suite checks, on SQLite and
PostgreSQL, that autogenerate finds no difference after upgrading). Enums are VARCHAR + CHECK
(no PostgreSQL enum types to create or drop); datetimes are timezone-aware.
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

# revision identifiers, used by Alembic.
revision: str = "0001"
down_revision: str | Sequence[str] | None = None
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

ID = sa.String(36)
JOB_STATUSES = ("queued", "running", "succeeded", "failed", "cancelled")
ROBOT_SOURCES = ("catalog", "dh", "urdf")


def _timestamp(name: str, nullable: bool = False) -> sa.Column:
    return sa.Column(name, sa.DateTime(timezone=True), nullable=nullable)


def _in(column: str, values: Sequence[str]) -> str:
    return f"{column} IN ({', '.join(repr(v) for v in values)})"


def _job_id() -> sa.Column:
    return sa.Column("job_id", ID, nullable=False)


def _job_fk(table: str) -> sa.ForeignKeyConstraint:
    return sa.ForeignKeyConstraint(
        ["job_id"], ["jobs.id"], name=op.f(f"fk_{table}_job_id_jobs"), ondelete="CASCADE"
    )


def upgrade() -> None:
    """Create every table."""
    op.create_table(
        "api_keys",
        sa.Column("id", ID, nullable=False),
        sa.Column("name", sa.String(200), nullable=False),
        sa.Column("key_hash", sa.String(128), nullable=False),
        _timestamp("created_at"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_api_keys")),
        sa.UniqueConstraint("key_hash", name=op.f("uq_api_keys_key_hash")),
    )
    op.create_table(
        "robots",
        sa.Column("id", ID, nullable=False),
        sa.Column("owner_key_id", ID, nullable=False),
        sa.Column("name", sa.String(200), nullable=False),
        sa.Column("source_kind", sa.String(16), nullable=False),
        sa.Column("spec", sa.JSON(), nullable=False),
        _timestamp("created_at"),
        sa.CheckConstraint(_in("source_kind", ROBOT_SOURCES), name=op.f("ck_robots_robot_source")),
        sa.ForeignKeyConstraint(
            ["owner_key_id"],
            ["api_keys.id"],
            name=op.f("fk_robots_owner_key_id_api_keys"),
            ondelete="CASCADE",
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_robots")),
        sa.UniqueConstraint("owner_key_id", "name", name=op.f("uq_robots_owner_key_id_name")),
    )
    op.create_table(
        "sweeps",
        sa.Column("id", ID, nullable=False),
        sa.Column("owner_key_id", ID, nullable=False),
        sa.Column("base_spec", sa.JSON(), nullable=False),
        sa.Column("axes", sa.JSON(), nullable=False),
        _timestamp("created_at"),
        sa.ForeignKeyConstraint(
            ["owner_key_id"],
            ["api_keys.id"],
            name=op.f("fk_sweeps_owner_key_id_api_keys"),
            ondelete="CASCADE",
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_sweeps")),
    )
    op.create_index(op.f("ix_sweeps_owner_key_id"), "sweeps", ["owner_key_id"])
    op.create_table(
        "jobs",
        sa.Column("id", ID, nullable=False),
        sa.Column("owner_key_id", ID, nullable=False),
        sa.Column("sweep_id", ID, nullable=True),
        sa.Column("status", sa.String(16), nullable=False),
        sa.Column("spec", sa.JSON(), nullable=False),
        sa.Column("progress_generation", sa.Integer(), nullable=False),
        sa.Column("total_generations", sa.Integer(), nullable=False),
        sa.Column("best_objective", sa.JSON(), nullable=True),
        sa.Column("lease_owner", sa.String(200), nullable=True),
        _timestamp("lease_expires_at", nullable=True),
        _timestamp("heartbeat_at", nullable=True),
        sa.Column("attempt_count", sa.Integer(), nullable=False),
        sa.Column("cancel_requested", sa.Boolean(), nullable=False),
        sa.Column("error_message", sa.Text(), nullable=True),
        sa.Column("warnings", sa.JSON(), nullable=False),
        _timestamp("created_at"),
        _timestamp("started_at", nullable=True),
        _timestamp("finished_at", nullable=True),
        sa.CheckConstraint(_in("status", JOB_STATUSES), name=op.f("ck_jobs_job_status")),
        sa.ForeignKeyConstraint(
            ["owner_key_id"],
            ["api_keys.id"],
            name=op.f("fk_jobs_owner_key_id_api_keys"),
            ondelete="CASCADE",
        ),
        sa.ForeignKeyConstraint(
            ["sweep_id"], ["sweeps.id"], name=op.f("fk_jobs_sweep_id_sweeps"), ondelete="SET NULL"
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_jobs")),
    )
    op.create_index(op.f("ix_jobs_status"), "jobs", ["status"])
    op.create_index(op.f("ix_jobs_owner_key_id"), "jobs", ["owner_key_id"])
    op.create_index(op.f("ix_jobs_sweep_id"), "jobs", ["sweep_id"])
    op.create_table(
        "generations",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        _job_id(),
        sa.Column("generation", sa.Integer(), nullable=False),
        sa.Column("n_evals", sa.Integer(), nullable=False),
        sa.Column("best", sa.JSON(), nullable=True),
        sa.Column("hypervolume", sa.Float(), nullable=True),
        sa.Column("wall_time_s", sa.Float(), nullable=False),
        _timestamp("created_at"),
        _job_fk("generations"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_generations")),
        sa.UniqueConstraint("job_id", "generation", name=op.f("uq_generations_job_id_generation")),
    )
    op.create_table(
        "checkpoints",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        _job_id(),
        sa.Column("generation", sa.Integer(), nullable=False),
        sa.Column("state", sa.LargeBinary(), nullable=False),
        _timestamp("created_at"),
        _job_fk("checkpoints"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_checkpoints")),
        sa.UniqueConstraint("job_id", name=op.f("uq_checkpoints_job_id")),
    )
    op.create_table(
        "results",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        _job_id(),
        sa.Column("best_x", sa.JSON(), nullable=True),
        sa.Column("objectives", sa.JSON(), nullable=True),
        sa.Column("metrics", sa.JSON(), nullable=True),
        sa.Column("summary", sa.JSON(), nullable=True),
        _timestamp("created_at"),
        _job_fk("results"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_results")),
        sa.UniqueConstraint("job_id", name=op.f("uq_results_job_id")),
    )
    op.create_table(
        "pareto_points",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        _job_id(),
        sa.Column("index", sa.Integer(), nullable=False),
        sa.Column("x", sa.JSON(), nullable=False),
        sa.Column("objectives", sa.JSON(), nullable=False),
        _job_fk("pareto_points"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_pareto_points")),
        sa.UniqueConstraint("job_id", "index", name=op.f("uq_pareto_points_job_id_index")),
    )
    op.create_table(
        "baselines",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        _job_id(),
        sa.Column("name", sa.String(200), nullable=False),
        sa.Column("metrics", sa.JSON(), nullable=False),
        _job_fk("baselines"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_baselines")),
        sa.UniqueConstraint("job_id", "name", name=op.f("uq_baselines_job_id_name")),
    )
    op.create_table(
        "artifacts",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        _job_id(),
        sa.Column("kind", sa.String(64), nullable=False),
        sa.Column("relative_path", sa.String(500), nullable=False),
        sa.Column("sha256", sa.String(64), nullable=False),
        sa.Column("size_bytes", sa.BigInteger(), nullable=False),
        _timestamp("created_at"),
        _job_fk("artifacts"),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_artifacts")),
        sa.UniqueConstraint("job_id", "kind", name=op.f("uq_artifacts_job_id_kind")),
    )


def downgrade() -> None:
    """Drop every table (children first)."""
    for table in (
        "artifacts",
        "baselines",
        "pareto_points",
        "results",
        "checkpoints",
        "generations",
    ):
        op.drop_table(table)
    op.drop_index(op.f("ix_jobs_sweep_id"), table_name="jobs")
    op.drop_index(op.f("ix_jobs_owner_key_id"), table_name="jobs")
    op.drop_index(op.f("ix_jobs_status"), table_name="jobs")
    op.drop_table("jobs")
    op.drop_index(op.f("ix_sweeps_owner_key_id"), table_name="sweeps")
    op.drop_table("sweeps")
    op.drop_table("robots")
    op.drop_table("api_keys")
