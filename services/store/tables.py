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
    event,
)
from sqlalchemy.engine import Connection
from sqlalchemy.orm import DeclarativeBase, Mapped, mapped_column

from services.store.search_index import SEARCH_FTS, create_search_index
from services.store.states import JobEventKind, JobStatus, KeyRole, RobotSource
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
    role: Mapped[KeyRole] = mapped_column(
        _enum_type(KeyRole, "key_role"), default=KeyRole.USER, server_default=KeyRole.USER.value
    )
    expires_at: Mapped[datetime | None]
    revoked_at: Mapped[datetime | None]
    # Per-key quotas; NULL: the settings' default (``Settings.quota_*``).
    max_active_jobs: Mapped[int | None] = mapped_column(Integer)
    max_cpu_seconds_per_hour: Mapped[float | None] = mapped_column(Float)
    max_storage_bytes: Mapped[int | None] = mapped_column(BigInteger)


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
    """One optimisation run: spec, lifecycle, lease of the worker running it, progress.

    A job of a sweep stores only its ``overrides`` (dotted path -> value); its spec is the
    sweep's ``base_spec`` with them applied (``repository.job_spec``), so a sweep's spec is
    stored once. A job outside a sweep stores its whole ``spec``.

    Dispatch (the transactional outbox): ``dispatch_due_at`` is when the job's queue message is
    due to be (re)sent — set in the transaction that creates or requeues the job; a sender
    claims it with a conditional UPDATE (``services.store.dispatch``) that moves it to the next
    re-send time, so one message is sent per due time whoever sends it.
    """

    __tablename__ = "jobs"
    __table_args__ = (
        Index(None, "status"),
        Index(None, "owner_key_id"),
        Index(None, "sweep_id"),
        Index(None, "status", "dispatch_due_at"),
        # the dashboard's jobs page (services.store.dashboard_queries): newest first, and one
        # index per sortable column ending in the page order's tie-break (created_at, id)
        Index(None, "owner_key_id", "created_at"),
        Index(None, "owner_key_id", "status", "created_at", "id"),
        Index(None, "owner_key_id", "finished_at", "created_at", "id"),
        Index(None, "owner_key_id", "progress_generation", "created_at", "id"),
        Index(None, "owner_key_id", "best_value", "created_at", "id"),
        Index(None, "owner_key_id", "feasible", "created_at", "id"),
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
    spec: Mapped[Any | None] = mapped_column(JSONValue())
    overrides: Mapped[Any | None] = mapped_column(JSONValue())
    spec_bytes: Mapped[int] = mapped_column(BigInteger, default=0, server_default="0")

    progress_generation: Mapped[int] = mapped_column(Integer, default=0)
    total_generations: Mapped[int] = mapped_column(Integer, default=0)
    best_objective: Mapped[Any | None] = mapped_column(JSONValue())
    # The first objective of ``best_objective`` as a number (NULL before generation 1 or when
    # not finite), written with it: what the jobs page sorts by "best".
    best_value: Mapped[float | None] = mapped_column(Float)

    lease_owner: Mapped[str | None] = mapped_column(String(200))
    lease_expires_at: Mapped[datetime | None]
    heartbeat_at: Mapped[datetime | None]
    attempt_count: Mapped[int] = mapped_column(Integer, default=0)
    cancel_requested: Mapped[bool] = mapped_column(Boolean, default=False)
    cpu_seconds: Mapped[float] = mapped_column(Float, default=0.0, server_default="0")

    dispatch_due_at: Mapped[datetime | None]
    last_dispatch_at: Mapped[datetime | None]
    dispatch_count: Mapped[int] = mapped_column(Integer, default=0, server_default="0")

    error_message: Mapped[str | None] = mapped_column(Text)
    warnings: Mapped[Any] = mapped_column(JSONValue(), default=list)
    # The verdict of a succeeded job (written by ``finish_job`` with its result): whether its
    # reported optimum meets every constraint of the study, and if not what it violates
    # (``[{"constraint", "amount", "unit", "text"}, ...]``, ``legcore.studies.task.Violation``).
    # NULL until the job succeeds, and for jobs finished before revision 0008 (not checked).
    # The status stays ``succeeded`` (the run completed): an infeasible answer is a verdict.
    feasible: Mapped[bool | None] = mapped_column(Boolean, default=None)
    violations: Mapped[Any | None] = mapped_column(JSONValue(), default=None)
    #: What submission learned of the job, stored once so nothing re-derives it: ``kind``,
    #: ``robot``, ``optimizer`` (resolved: the study's defaults filled in), ``objectives``
    #: (names, minimised), ``n_var`` (``services.api.validation.job_facts``). NULL for jobs
    #: stored before revision 0010.
    facts: Mapped[Any | None] = mapped_column(JSONValue(), default=None)
    # The point the per-generation hypervolumes are measured against (objective space, the
    # worker sets it once from the first front: ``services.worker.hypervolume``).
    hypervolume_ref: Mapped[Any | None] = mapped_column(JSONValue(), default=None)

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
    front: Mapped[Any | None] = mapped_column(JSONValue(), default=None)  # rows before 0005
    front_packed: Mapped[bytes | None] = mapped_column(LargeBinary, default=None)


class Evaluation(Base):
    """The solutions one generation of a job evaluated (the trial table's rows), as packed
    float64 matrices (``services.store.front_codec``): ``x`` (n, n_var), ``f`` (n, n_obj,
    minimised form) and ``cv`` (n, 1). Kept for at most ``evaluations.MAX_STORED_EVALUATIONS``
    solutions per job (``services.store.evaluations``)."""

    __tablename__ = "evaluations"
    __table_args__ = (UniqueConstraint("job_id", "generation"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    job_id: Mapped[str] = mapped_column(String(ID_LENGTH), _job_fk())
    generation: Mapped[int] = mapped_column(Integer)
    n: Mapped[int] = mapped_column(Integer)
    x_packed: Mapped[bytes] = mapped_column(LargeBinary)
    f_packed: Mapped[bytes] = mapped_column(LargeBinary)
    cv_packed: Mapped[bytes] = mapped_column(LargeBinary)


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


class JobEvent(Base):
    """One state change of a job, written in the transaction that makes it (an audit trail:
    a job is terminal exactly once, and ``dispatched`` rows count the queue messages sent)."""

    __tablename__ = "job_events"

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    job_id: Mapped[str] = mapped_column(String(ID_LENGTH), _job_fk(), index=True)
    at: Mapped[datetime] = mapped_column(default=utcnow)
    kind: Mapped[JobEventKind] = mapped_column(_enum_type(JobEventKind, "job_event_kind"))
    attempt: Mapped[int] = mapped_column(Integer, default=0)
    actor: Mapped[str | None] = mapped_column(String(200))
    detail: Mapped[str | None] = mapped_column(Text)


class ServiceLease(Base):
    """A named role held by one process at a time (e.g. the ``dispatcher``), elected through
    the database: the holder renews ``expires_at``; anyone may take an expired lease."""

    __tablename__ = "service_leases"

    name: Mapped[str] = mapped_column(String(64), primary_key=True)
    owner: Mapped[str] = mapped_column(String(200))
    expires_at: Mapped[datetime]


class IdempotencyKey(Base):
    """The resource a POST with an ``Idempotency-Key`` header created, so a retried request
    returns it instead of creating another (per API key; the request body's hash must match)."""

    __tablename__ = "idempotency_keys"
    __table_args__ = (UniqueConstraint("owner_key_id", "key"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    owner_key_id: Mapped[str] = mapped_column(
        String(ID_LENGTH), ForeignKey("api_keys.id", ondelete="CASCADE")
    )
    key: Mapped[str] = mapped_column(String(200))
    request_sha256: Mapped[str] = mapped_column(String(64))
    resource_kind: Mapped[str] = mapped_column(String(16))
    resource_id: Mapped[str] = mapped_column(String(ID_LENGTH))
    created_at: Mapped[datetime] = mapped_column(default=utcnow)


class KeyUsage(Base):
    """CPU seconds spent by the jobs of one API key in one UTC hour (for the hourly quota)."""

    __tablename__ = "key_usage"
    __table_args__ = (UniqueConstraint("owner_key_id", "hour"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True, autoincrement=True)
    owner_key_id: Mapped[str] = mapped_column(
        String(ID_LENGTH), ForeignKey("api_keys.id", ondelete="CASCADE")
    )
    hour: Mapped[datetime]
    cpu_seconds: Mapped[float] = mapped_column(Float, default=0.0)


class JobLabel(Base):
    """What the dashboard lists, filters, sorts and searches jobs by, one row per job: the spec
    fields a listing shows, read once (a job's spec never changes) by
    ``services.store.dashboard_queries.sync_labels``, so a page of 10^5 jobs is an indexed
    query instead of a walk over specs. ``search``: the lower-cased text a search matches,
    read from a substring index outside the model (``SEARCH_FTS``, ``SEARCH_TRGM_INDEX``)."""

    __tablename__ = "job_labels"
    __table_args__ = (
        Index(None, "owner_key_id", "created_at"),
        Index(None, "owner_key_id", "kind", "created_at", "job_id"),
        Index(None, "owner_key_id", "robot", "created_at", "job_id"),
        Index(None, "owner_key_id", "optimizer", "created_at", "job_id"),
    )

    job_id: Mapped[str] = mapped_column(String(ID_LENGTH), _job_fk(), primary_key=True)
    owner_key_id: Mapped[str] = mapped_column(
        String(ID_LENGTH), ForeignKey("api_keys.id", ondelete="CASCADE")
    )
    created_at: Mapped[datetime]
    name: Mapped[str | None] = mapped_column(String(200))
    kind: Mapped[str] = mapped_column(String(64))
    robot: Mapped[str] = mapped_column(String(200))
    optimizer: Mapped[str] = mapped_column(String(32))
    seed: Mapped[int] = mapped_column(BigInteger, default=0)
    tags: Mapped[str] = mapped_column(Text, default="")
    search: Mapped[str] = mapped_column(Text, default="")


class RobotDocument(Base):
    """A robot document a job or sweep runs on (an inline spec, or a stored robot's document as
    it was at submission), stored once by the SHA-256 of its canonical JSON: stored specs refer
    to it as ``{"$robot_document": sha256}`` (``services.store.robot_documents``), so a URDF is
    not copied into every job row. Immutable and shared by content; never updated."""

    __tablename__ = "robot_documents"

    sha256: Mapped[str] = mapped_column(String(64), primary_key=True)
    spec: Mapped[Any] = mapped_column(JSONValue())
    size_bytes: Mapped[int] = mapped_column(BigInteger)
    created_at: Mapped[datetime] = mapped_column(default=utcnow)


# Core handles on the tables (the repository issues Core statements, see repository.py).
API_KEYS = cast(Table, ApiKey.__table__)
ROBOTS = cast(Table, Robot.__table__)
SWEEPS = cast(Table, Sweep.__table__)
JOBS = cast(Table, Job.__table__)
GENERATIONS = cast(Table, Generation.__table__)
EVALUATIONS = cast(Table, Evaluation.__table__)
CHECKPOINTS = cast(Table, Checkpoint.__table__)
RESULTS = cast(Table, Result.__table__)
PARETO_POINTS = cast(Table, ParetoPoint.__table__)
BASELINES = cast(Table, Baseline.__table__)
ARTIFACTS = cast(Table, Artifact.__table__)
JOB_EVENTS = cast(Table, JobEvent.__table__)
SERVICE_LEASES = cast(Table, ServiceLease.__table__)
IDEMPOTENCY_KEYS = cast(Table, IdempotencyKey.__table__)
ROBOT_DOCUMENTS = cast(Table, RobotDocument.__table__)
KEY_USAGE = cast(Table, KeyUsage.__table__)
JOB_LABELS = cast(Table, JobLabel.__table__)


# The word search's index is backend-specific DDL outside the portable model
# (``services.store.search_index``); ``create_all`` (the tests) makes it through these listeners.


def _after_create_job_labels(target: Table, connection: Connection, **_: Any) -> None:
    create_search_index(connection)


def _before_drop_job_labels(target: Table, connection: Connection, **_: Any) -> None:
    if connection.dialect.name == "sqlite":  # triggers and the GIN index go with the table
        connection.exec_driver_sql(f"DROP TABLE IF EXISTS {SEARCH_FTS}")


event.listen(JOB_LABELS, "after_create", _after_create_job_labels)
event.listen(JOB_LABELS, "before_drop", _before_drop_job_labels)
