"""The audit trail of jobs: one ``job_events`` row per state change, written by the same
transaction that makes the change (so a rolled-back change leaves no event).

Kinds (``JobEventKind``): ``submitted`` (created, due for dispatch), ``dispatched`` (a queue
message was sent), ``claimed`` (a worker took the lease; ``attempt`` is the claim number),
``requeued`` (its worker's lease expired), and the terminal ``succeeded`` / ``failed`` /
``cancelled`` — exactly one of them per job, because every terminal transition is a
conditional UPDATE out of a non-terminal state.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from datetime import datetime

from sqlalchemy import func, insert, select
from sqlalchemy.orm import Session

from services.store.records import JobEventRecord
from services.store.sql import fetch_all, now_utc
from services.store.states import JobEventKind
from services.store.tables import JOB_EVENTS, JOBS


def add_events(
    session: Session,
    kind: JobEventKind,
    job_ids: Iterable[str],
    *,
    actor: str | None = None,
    detail: str | None = None,
    attempts: Sequence[int] | None = None,
    now: datetime | None = None,
) -> None:
    """Record ``kind`` for each of ``job_ids`` (``attempts``: one per job; default: read from
    the job rows, i.e. the attempt the change belongs to)."""
    ids = list(job_ids)
    if not ids:
        return
    if attempts is None:
        rows = session.execute(select(JOBS.c.id, JOBS.c.attempt_count).where(JOBS.c.id.in_(ids)))
        found = {str(r[0]): int(r[1]) for r in rows}
        attempts = [int(found.get(i, 0)) for i in ids]
    at = now_utc(now)
    session.execute(
        insert(JOB_EVENTS),
        [
            {
                "job_id": job_id,
                "at": at,
                "kind": kind,
                "attempt": int(attempt),
                "actor": actor,
                "detail": detail,
            }
            for job_id, attempt in zip(ids, attempts, strict=True)
        ],
    )


def list_events(session: Session, job_id: str) -> tuple[JobEventRecord, ...]:
    """Events of one job in the order they were written."""
    stmt = select(JOB_EVENTS).where(JOB_EVENTS.c.job_id == job_id).order_by(JOB_EVENTS.c.id)
    return fetch_all(session, JobEventRecord, stmt)


def count_events(session: Session, kind: JobEventKind, job_ids: Iterable[str]) -> dict[str, int]:
    """``{job_id: number of events of kind}`` for the given jobs (0 when none)."""
    ids = list(job_ids)
    counts = {i: 0 for i in ids}
    if not ids:
        return counts
    stmt = (
        select(JOB_EVENTS.c.job_id, func.count())
        .where(JOB_EVENTS.c.kind == kind, JOB_EVENTS.c.job_id.in_(ids))
        .group_by(JOB_EVENTS.c.job_id)
    )
    for job_id, n in session.execute(stmt):
        counts[job_id] = int(n)
    return counts


__all__ = ["add_events", "count_events", "list_events"]
