"""SQLAlchemy 2.0 tables of the service (the schema Alembic migrates).

Identifiers: API keys, robots, sweeps and jobs have string UUIDs (``str(uuid4())``, 36 chars)
made by the application, so ids can be handed out before the insert, are not guessable across
owners and are the same on every backend. Child rows (generations, checkpoints, results, ...)
have integer surrogate keys and are addressed by ``(job_id, ...)`` unique constraints.

Narrow tables with unique constraints (as Optuna's storage): one row per generation, Pareto
point, baseline and artifact; the job row carries the lifecycle, the lease and the progress.
All constraints are named by ``NAMING_CONVENTION`` so migrations are stable on both backends.
"""

from __future__ import annotations

import enum
import uuid
from datetime import datetime
from typing import Any, cast

from sqlalchemy import (
    BigInteger,
    Boolean,
    Enum,
    Float,
    ForeignKey,
    Index,
    Integer,
    LargeBinary,
    MetaData,
    String,
    Table,
    Text,
    UniqueConstraint,
)
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column

from services.store.types import JSONValue, UTCDateTime, utcnow

NAMING_CONVENTION = {
    "ix": "ix_%(table_name)s_%(column_0_N_name)s",
    "uq": "uq_%(table_name)s_%(column_0_N_name)s",
    "ck": "ck_%(table_name)s_%(constraint_name)s",
    "fk": "fk_%(table_name)s_%(column_0_name)s_%(referred_table_name)s",
    "pk": "pk_%(table_name)s",
}

ID_LENGTH = 36


def new_id() -> str:
    """A new resource id (random UUID as a 36-character string)."""
    return str(uuid.uuid4())


class JobStatus(enum.StrEnum):
    """Lifecycle of a job: queued -> running -> succeeded | failed | cancelled."""

    QUEUED = "queued"
    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"

    @property
    def is_terminal(self) -> bool:
        """True for succeeded, failed and cancelled."""
        return self in (JobStatus.SUCCEEDED, JobStatus.FAILED, JobStatus.CANCELLED)


class RobotSource(enum.StrEnum):
    """How a stored robot model was given."""

    CATALOG = "catalog"
    DH = "dh"
    URDF = "urdf"


def _enum_type(cls: type[enum.Enum], name: str) -> Enum:
    """A portable enum column: VARCHAR + named CHECK constraint, stored by value."""
    return Enum(
        cls,
        name=name,
        native_enum=False,
        create_constraint=True,
        length=16,
        validate_strings=True,
        values_callable=lambda e: [m.value for m in e],
    )


class Base(DeclarativeBase):
    """Declarative base; its ``metadata`` is what Alembic compares against."""

    metadata = MetaData(naming_convention=NAMING_CONVENTION)
    type_annotation_map = {datetime: UTCDateTime()}


def _job_fk() -> ForeignKey:
    return ForeignKey("jobs.id", ondelete="CASCADE")


class ApiKey(Base):
    """A client of the API. Only a hash of the key is stored (``keys.hash_api_key``)."""

    __tablename__ = "api_keys"

    id: Mapped[str] = mapped_column(String(ID_LENGTH), primary_key=True, default=new_id)
    name: Mapped[str] = mapped_column(String(200))
    key_hash: Mapped[str] = mapped_column(String(128), unique=True)
    created_at: Mapped[datetime] = mapped_column(default=utcnow)


class Robot(Base):
    """A robot model stored by an owner, referred to from job specs by id."""

    __tablename__ = "robots"
    __table_args__ = (UniqueConstraint("owner_key_id", "name"),)

    id: Mapped[str] = mapped_column(String(ID_LENGTH), primary_key=True, default=new_id)
    owner_key_id: Mapped[str] = mapped_column(
        String(ID_LENGTH), ForeignKey("api_keys.id", ondelete="CASCADE")
    )
    name: Mapped[str] = mapped_column(String(200))
    source_kind: Mapped[RobotSource] = mapped_column(_enum_type(RobotSource, "robot_source"))
    spec: Mapped[Any] = mapped_column(JSONValue())
    created_at: Mapped[datetime] = mapped_column(default=utcnow)


class Sweep(Base):
    """A base spec and the axes it is fanned out over (one job per point)."""

    __tablename__ = "sweeps"

    id: Mapped[str] = mapped_column(String(ID_LENGTH), primary_key=True, default=new_id)
    owner_key_id: Mapped[str] = mapped_column(
        String(ID_LENGTH), ForeignKey("api_keys.id", ondelete="CASCADE"), index=True
    )
    base_spec: Mapped[Any] = mapped_column(JSONValue())
    axes: Mapped[Any] = mapped_column(JSONValue())
    created_at: Mapped[datetime] = mapped_column(default=utcnow)


class Job(Base):
    """One optimisation run: spec, lifecycle, lease of the worker running it, progress."""

    __tablename__ = "jobs"
    __table_args__ = (
        Index(None, "status"),
        Index(None, "owner_key_id"),
        Index(None, "sweep_id"),
    )

    id: Mapped[str] = mapped_column(String(ID_LENGTH), primary_key=True, default=new_id)
    owner_key_id: Mapped[str] = mapped_column(
        String(ID_LENGTH), ForeignKey("api_keys.id", ondelete="CASCADE")
    )
    sweep_id: Mapped[str | None] = mapped_column(
        String(ID_LENGTH), ForeignKey("sweeps.id", ondelete="SET NULL")
    )
    status: Mapped[JobStatus] = mapped_column(
        _enum_type(JobStatus, "job_status"), default=JobStatus.QUEUED
    )
    spec: Mapped[Any] = mapped_column(JSONValue())

    progress_generation: Mapped[int] = mapped_column(Integer, default=0)
    total_generations: Mapped[int] = mapped_column(Integer, default=0)
    best_objective: Mapped[Any | None] = mapped_column(JSONValue())

    lease_owner: Mapped[str | None] = mapped_column(String(200))
    lease_expires_at: Mapped[datetime | None]
    heartbeat_at: Mapped[datetime | None]
    attempt_count: Mapped[int] = mapped_column(Integer, default=0)
    cancel_requested: Mapped[bool] = mapped_column(Boolean, default=False)

    error_message: Mapped[str | None] = mapped_column(Text)
    warnings: Mapped[Any] = mapped_column(JSONValue(), default=list)

    created_at: Mapped[datetime] = mapped_column(default=utcnow)
    started_at: Mapped[datetime | None]
    finished_at: Mapped[datetime | None]


class Generation(Base):
    """Progress of one generation of a job (one row per generation, written idempotently)."""

    __tablename__ = "generations"
    __table_args__ = (UniqueConstraint("job_id", "generation"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    job_id: Mapped[str] = mapped_column(String(ID_LENGTH), _job_fk())
    generation: Mapped[int] = mapped_column(Integer)
    n_evals: Mapped[int] = mapped_column(Integer)
    best: Mapped[Any | None] = mapped_column(JSONValue())
    hypervolume: Mapped[float | None] = mapped_column(Float)
    wall_time_s: Mapped[float] = mapped_column(Float)
    created_at: Mapped[datetime] = mapped_column(default=utcnow)
    front: Mapped[Any | None] = mapped_column(JSONValue(), default=None)


class Checkpoint(Base):
    """Latest optimiser state of a job (one row per job, replaced on save)."""

    __tablename__ = "checkpoints"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    job_id: Mapped[str] = mapped_column(String(ID_LENGTH), _job_fk(), unique=True)
    generation: Mapped[int] = mapped_column(Integer)
    state: Mapped[bytes] = mapped_column(LargeBinary)
    created_at: Mapped[datetime] = mapped_column(default=utcnow)


class Result(Base):
    """Final result of a succeeded job."""

    __tablename__ = "results"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    job_id: Mapped[str] = mapped_column(String(ID_LENGTH), _job_fk(), unique=True)
    best_x: Mapped[Any | None] = mapped_column(JSONValue())
    objectives: Mapped[Any | None] = mapped_column(JSONValue())
    metrics: Mapped[Any | None] = mapped_column(JSONValue())
    summary: Mapped[Any | None] = mapped_column(JSONValue())
    created_at: Mapped[datetime] = mapped_column(default=utcnow)


class ParetoPoint(Base):
    """One point of the final Pareto front (decision vector and objective vector)."""

    __tablename__ = "pareto_points"
    __table_args__ = (UniqueConstraint("job_id", "index"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    job_id: Mapped[str] = mapped_column(String(ID_LENGTH), _job_fk())
    index: Mapped[int] = mapped_column(Integer)
    x: Mapped[Any] = mapped_column(JSONValue())
    objectives: Mapped[Any] = mapped_column(JSONValue())


class Baseline(Base):
    """A reference solution reported next to the optimum (e.g. the parabolic swing)."""

    __tablename__ = "baselines"
    __table_args__ = (UniqueConstraint("job_id", "name"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    job_id: Mapped[str] = mapped_column(String(ID_LENGTH), _job_fk())
    name: Mapped[str] = mapped_column(String(200))
    metrics: Mapped[Any] = mapped_column(JSONValue())


class Artifact(Base):
    """A file of a job in the artifact store (path relative to the store root)."""

    __tablename__ = "artifacts"
    __table_args__ = (UniqueConstraint("job_id", "kind"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    job_id: Mapped[str] = mapped_column(String(ID_LENGTH), _job_fk())
    kind: Mapped[str] = mapped_column(String(64))
    relative_path: Mapped[str] = mapped_column(String(500))
    sha256: Mapped[str] = mapped_column(String(64))
    size_bytes: Mapped[int] = mapped_column(BigInteger)
    created_at: Mapped[datetime] = mapped_column(default=utcnow)


# Core handles on the tables (the repository issues Core statements, see repository.py).
API_KEYS = cast(Table, ApiKey.__table__)
ROBOTS = cast(Table, Robot.__table__)
SWEEPS = cast(Table, Sweep.__table__)
JOBS = cast(Table, Job.__table__)
GENERATIONS = cast(Table, Generation.__table__)
CHECKPOINTS = cast(Table, Checkpoint.__table__)
RESULTS = cast(Table, Result.__table__)
PARETO_POINTS = cast(Table, ParetoPoint.__table__)
BASELINES = cast(Table, Baseline.__table__)
ARTIFACTS = cast(Table, Artifact.__table__)
