"""The states and kinds the store's rows take, as string enums stored by value (portable
``VARCHAR`` + ``CHECK`` columns, ``services.store.tables``): a job's lifecycle, an API key's
role, a job event's kind and how a robot was given. Plain data, importable without the
schema."""

from __future__ import annotations

import enum

__all__ = ["JobEventKind", "JobStatus", "KeyRole", "RobotSource"]


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


class KeyRole(enum.StrEnum):
    """What an API key may do: ``user`` (its own resources) or ``admin`` (also manage keys)."""

    USER = "user"
    ADMIN = "admin"


class JobEventKind(enum.StrEnum):
    """One state change of a job, as recorded in ``job_events`` (see ``JobEvent``)."""

    SUBMITTED = "submitted"
    DISPATCHED = "dispatched"
    CLAIMED = "claimed"
    REQUEUED = "requeued"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    CANCELLED = "cancelled"


class RobotSource(enum.StrEnum):
    """How a stored robot model was given."""

    CATALOG = "catalog"
    DH = "dh"
    URDF = "urdf"
