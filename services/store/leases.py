"""The lease conditions shared by the job lifecycle (``lifecycle``) and the worker's progress
writes (``progress``): who owns a running job, when its lease ends, when it ran out.

A worker owns a running job through its *lease*: ``lease_owner`` (the worker id) and
``lease_expires_at``; every write of the lease owner is a conditional UPDATE on ``_owned_by``.
"""

from __future__ import annotations

from datetime import datetime, timedelta
from typing import Any

from sqlalchemy import ColumnElement, and_, update
from sqlalchemy.orm import Session

from services.store.errors import LeaseLostError
from services.store.sql import rowcount
from services.store.states import JobStatus
from services.store.tables import JOBS

_RUNNING = JobStatus.RUNNING


def _lease_until(now: datetime, lease_s: float) -> datetime:
    if lease_s <= 0:
        raise ValueError(f"lease_s must be > 0, got {lease_s}")
    return now + timedelta(seconds=lease_s)


def _owned_by(job_id: str, worker_id: str) -> ColumnElement[bool]:
    """The job is running and ``worker_id`` holds its lease."""
    return and_(JOBS.c.id == job_id, JOBS.c.status == _RUNNING, JOBS.c.lease_owner == worker_id)


def _expired(now: datetime) -> ColumnElement[bool]:
    """The job is running and its lease ran out before ``now``."""
    return and_(JOBS.c.status == _RUNNING, JOBS.c.lease_expires_at < now)


def _require_owner(session: Session, job_id: str, worker_id: str, values: dict[str, Any]) -> None:
    """UPDATE the job with ``values`` if ``worker_id`` owns it, else raise LeaseLostError."""
    stmt = update(JOBS).where(_owned_by(job_id, worker_id)).values(**values)
    if rowcount(session.execute(stmt)) == 0:
        raise LeaseLostError(f"worker {worker_id!r} does not hold the lease of job {job_id}")
