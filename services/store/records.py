"""Frozen dataclasses handed out by the repository, and the inputs of the worker's writes.

Records are snapshots of rows: assigning an attribute raises ``FrozenInstanceError``; no live
ORM object ever leaves the store. JSON fields are fresh plain ``dict``/``list`` copies (so a
caller mutating one cannot affect the store); collections of rows are tuples. Datetimes are
timezone-aware UTC.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime
from typing import Any, Generic, TypeVar

from services.store.states import JobEventKind, JobStatus, KeyRole, RobotSource

T = TypeVar("T")


@dataclass(frozen=True, slots=True)
class Page(Generic[T]):
    """One page of a listing: ``items`` plus the ``total`` number of matching rows."""

    items: tuple[T, ...]
    total: int
    limit: int
    offset: int


@dataclass(frozen=True, slots=True)
class ApiKeyRecord:
    """An API key (the hash stays in the store), its role, validity and quotas."""

    id: str
    name: str
    created_at: datetime
    role: KeyRole
    expires_at: datetime | None
    revoked_at: datetime | None
    max_active_jobs: int | None
    max_cpu_seconds_per_hour: float | None
    max_storage_bytes: int | None

    @property
    def is_admin(self) -> bool:
        """True for an admin key (may manage keys)."""
        return self.role is KeyRole.ADMIN

    def invalid_reason(self, now: datetime) -> str | None:
        """Why the key may not be used at ``now`` (revoked, expired), or None."""
        if self.revoked_at is not None:
            return f"API key {self.name!r} was revoked at {self.revoked_at.isoformat()}"
        if self.expires_at is not None and self.expires_at <= now:
            return f"API key {self.name!r} expired at {self.expires_at.isoformat()}"
        return None


@dataclass(frozen=True, slots=True)
class RobotRecord:
    """A stored robot model."""

    id: str
    owner_key_id: str
    name: str
    source_kind: RobotSource
    spec: Any
    created_at: datetime


@dataclass(frozen=True, slots=True)
class SweepRecord:
    """A sweep: base spec plus axes; its jobs carry ``sweep_id``."""

    id: str
    owner_key_id: str
    base_spec: Any
    axes: Any
    created_at: datetime


@dataclass(frozen=True, slots=True)
class JobRecord:
    """A job row: spec, lifecycle, lease, progress and dispatch.

    ``spec`` is None for a job of a sweep, which stores only its ``overrides`` of the sweep's
    base spec: read its spec with ``repository.job_spec``.
    """

    id: str
    owner_key_id: str
    sweep_id: str | None
    status: JobStatus
    spec: Any
    overrides: Any
    progress_generation: int
    total_generations: int
    best_objective: Any
    lease_owner: str | None
    lease_expires_at: datetime | None
    heartbeat_at: datetime | None
    attempt_count: int
    cancel_requested: bool
    error_message: str | None
    warnings: list[str]
    created_at: datetime
    started_at: datetime | None
    finished_at: datetime | None
    cpu_seconds: float = 0.0
    dispatch_due_at: datetime | None = None
    last_dispatch_at: datetime | None = None
    dispatch_count: int = 0
    #: The verdict of a succeeded job: its optimum meets every constraint (True), violates
    #: ``violations`` (False), or None (not succeeded, or finished before it was checked).
    feasible: bool | None = None
    violations: Any = None
    #: What submission learned (``kind``, ``robot``, ``optimizer``, ``objectives``, ``n_var``);
    #: None for a job stored before it was kept.
    facts: Any = None

    @property
    def is_terminal(self) -> bool:
        """True once the job succeeded, failed or was cancelled."""
        return self.status.is_terminal

    @property
    def progress(self) -> float:
        """Fraction of generations done, in [0, 1] (1 for a succeeded job)."""
        if self.status is JobStatus.SUCCEEDED:
            return 1.0
        if self.total_generations <= 0:
            return 0.0
        return min(1.0, self.progress_generation / self.total_generations)


@dataclass(frozen=True, slots=True)
class GenerationRecord:
    """Progress of one generation."""

    job_id: str
    generation: int
    n_evals: int
    best: Any
    hypervolume: float | None
    wall_time_s: float
    created_at: datetime
    front: Any = None  # objective vectors of the front at this generation (may be thinned)


@dataclass(frozen=True, slots=True)
class CheckpointRecord:
    """The latest optimiser state of a job (opaque bytes written by the worker)."""

    job_id: str
    generation: int
    state: bytes
    created_at: datetime


@dataclass(frozen=True, slots=True)
class ResultRecord:
    """Final result of a succeeded job."""

    job_id: str
    best_x: Any
    objectives: Any
    metrics: Any
    summary: Any
    created_at: datetime


@dataclass(frozen=True, slots=True)
class ParetoPointRecord:
    """One point of a job's final Pareto front."""

    job_id: str
    index: int
    x: Any
    objectives: Any


@dataclass(frozen=True, slots=True)
class BaselineRecord:
    """A baseline solution's metrics."""

    job_id: str
    name: str
    metrics: Any


@dataclass(frozen=True, slots=True)
class ArtifactRecord:
    """A file of a job in the artifact store."""

    job_id: str
    kind: str
    relative_path: str
    sha256: str
    size_bytes: int
    created_at: datetime


@dataclass(frozen=True, slots=True)
class JobEventRecord:
    """One state change of a job (``job_events``)."""

    job_id: str
    at: datetime
    kind: JobEventKind
    attempt: int
    actor: str | None
    detail: str | None


@dataclass(frozen=True, slots=True)
class IdempotencyRecord:
    """What a POST with an ``Idempotency-Key`` created (``resource_kind``: job or sweep)."""

    owner_key_id: str
    key: str
    request_sha256: str
    resource_kind: str
    resource_id: str
    created_at: datetime


@dataclass(frozen=True, slots=True)
class ReapReport:
    """What ``requeue_expired`` did with the jobs whose lease had expired."""

    requeued: tuple[str, ...]
    failed: tuple[str, ...]
    cancelled: tuple[str, ...]


# Inputs of the worker's writes (the worker builds these; JSON fields may hold numpy values).


@dataclass(frozen=True, slots=True)
class GenerationIn:
    """One generation's progress for ``record_generations`` (``front``: (k, m) objective
    vectors or None; stored as float64 bytes, see ``services.store.front_codec``)."""

    generation: int
    n_evals: int
    best: Any
    wall_time_s: float
    hypervolume: float | None = None
    front: Any = None


@dataclass(frozen=True, slots=True)
class ResultIn:
    """The final result to store with ``finish_job``. ``feasible`` and ``violations`` (the
    optimum's violated constraints, ``[{"constraint", "amount", "unit", "text"}, ...]``) are
    the job's verdict, written on the job row; None: not checked."""

    best_x: Any = None
    objectives: Any = None
    metrics: Any = None
    summary: Any = None
    feasible: bool | None = None
    violations: Any = None


@dataclass(frozen=True, slots=True)
class ParetoPointIn:
    """A Pareto point to store with ``finish_job`` (``index`` unique per job)."""

    index: int
    x: Any
    objectives: Any


@dataclass(frozen=True, slots=True)
class BaselineIn:
    """A baseline to store with ``finish_job`` (``name`` unique per job)."""

    name: str
    metrics: Any


@dataclass(frozen=True, slots=True)
class ArtifactIn:
    """An artifact row to store with ``finish_job``; fields as returned by ``ArtifactStore.put``."""

    kind: str
    relative_path: str
    sha256: str
    size_bytes: int
