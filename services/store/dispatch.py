"""The dispatch outbox and elected service roles, in the database (the source of truth).

A queued job carries ``dispatch_due_at``: the time its queue message is due to be (re)sent.
It is set in the transaction that creates the job (``repository.create_jobs``) or requeues it
(``lifecycle.requeue_expired``), so no crash between a commit and a send can lose a job.

Whoever sends — the API right after its commit, or the elected dispatcher — first *claims the
send* with one conditional UPDATE (``claim_sends``): it moves ``dispatch_due_at`` to the next
re-send time and counts the message, so one message goes out per due time, never one per
process per pass. The next re-send time backs off (``backoff_s[count]``), but timed re-sends
go out only where the broker cannot say how many messages it holds (``resend``). Where it
can, a job waiting behind busy workers gets no duplicate at all, and a message that was lost
(killed worker, broker restart) is re-sent when the broker holds fewer messages than there
are queued jobs sent (``stale_before`` / ``stale_limit``). ``dispatch_count`` counts the
messages of the job's current wait in the queue: a requeue starts it again at 0.

A *service lease* elects one holder of a named role (``try_lead``), so one dispatcher runs at
a time among all workers and servers.
"""

from __future__ import annotations

from collections.abc import Sequence
from datetime import datetime, timedelta

from sqlalchemy import ColumnElement, case, delete, func, literal, or_, select, update
from sqlalchemy.orm import Session

from services.store.events import add_events
from services.store.sql import insert_ignoring_duplicates, now_utc, rowcount
from services.store.states import JobEventKind, JobStatus
from services.store.tables import JOB_EVENTS, JOBS, SERVICE_LEASES
from services.store.types import UTCDateTime

#: Seconds from a send to the next re-send of a still-queued job, by messages sent so far;
#: the last value repeats. Multiplied by the lease length (``backoff_schedule``).
BACKOFF_LEASES = (2.0, 4.0, 8.0, 16.0, 32.0)


def backoff_schedule(lease_s: float) -> tuple[float, ...]:
    """Re-send delays (s) for a lease of ``lease_s`` seconds: 2, 4, 8, 16, 32 leases."""
    return tuple(k * lease_s for k in BACKOFF_LEASES)


def and_queued(condition: ColumnElement[bool]) -> ColumnElement[bool]:
    """``condition`` and the job is queued without a cancellation request."""
    return (JOBS.c.status == JobStatus.QUEUED) & JOBS.c.cancel_requested.is_(False) & condition


def _next_due(now: datetime, backoff_s: Sequence[float]) -> ColumnElement[datetime]:
    """``now + backoff_s[dispatch_count]`` (the last delay repeats), as one SQL CASE."""
    if not backoff_s:
        raise ValueError("backoff_s needs at least one delay")
    whens = [
        (JOBS.c.dispatch_count == i, literal(now + timedelta(seconds=s), UTCDateTime()))
        for i, s in enumerate(backoff_s[:-1])
    ]
    last = literal(now + timedelta(seconds=backoff_s[-1]), UTCDateTime())
    return case(*whens, else_=last) if whens else last


def claim_sends(
    session: Session,
    *,
    backoff_s: Sequence[float],
    job_ids: Sequence[str] | None = None,
    stale_before: datetime | None = None,
    stale_limit: int = 0,
    resend: bool = True,
    limit: int = 1000,
    actor: str | None = None,
    now: datetime | None = None,
) -> list[str]:
    """Claim the sending of due messages; the ids whose message the caller must send now.

    Due: queued, not cancel-requested, ``dispatch_due_at <= now`` (restricted to ``job_ids``
    when given); with ``resend`` False only the jobs not sent since they were queued
    (``dispatch_count`` 0: new or requeued), so no timed re-send goes out while the caller
    knows from the broker that no message is missing. Also, up to ``stale_limit`` queued jobs
    last sent before ``stale_before`` (the broker holds fewer messages than queued jobs:
    theirs were lost), oldest send first.
    Each claimed job's ``dispatch_due_at`` moves to ``now + backoff_s[dispatch_count]`` and its
    count grows by one, in one conditional UPDATE, so a concurrent sender cannot claim it too.
    The claimed jobs' ``dispatched`` events (by ``actor``, at ``now``) are recorded in the same
    transaction, before anything is published: a sender killed right after its publish still
    leaves the event; one killed before it leaves an event without a message (the job stays
    due and is sent again), and a failed publish withdraws it (``release_sends``).
    """
    now = now_utc(now)
    ids: list[str] = []
    due = select(JOBS.c.id).where(and_queued(JOBS.c.dispatch_due_at <= now))
    if not resend:
        due = due.where(JOBS.c.dispatch_count == 0)
    if job_ids is not None:
        if not job_ids:
            return []
        due = due.where(JOBS.c.id.in_(list(job_ids)))
    ids.extend(session.execute(due.order_by(JOBS.c.dispatch_due_at).limit(limit)).scalars())
    if stale_before is not None and stale_limit > 0 and job_ids is None:
        # not those the due path above took: with ``resend`` the due ones, without it the new
        # ones (a sent job past its timed re-send is only re-sent here: it may have been lost)
        not_taken = JOBS.c.dispatch_due_at > now if resend else JOBS.c.dispatch_count > 0
        stale = (
            select(JOBS.c.id)
            .where(and_queued(JOBS.c.last_dispatch_at < stale_before), not_taken)
            .order_by(JOBS.c.last_dispatch_at)
            .limit(stale_limit)
        )
        ids.extend(session.execute(stale).scalars())
    if not ids:
        return []
    claimable = JOBS.c.dispatch_due_at <= now
    if stale_before is not None:
        claimable = or_(claimable, JOBS.c.last_dispatch_at < stale_before)
    stmt = (
        update(JOBS)
        .where(JOBS.c.id.in_(ids), and_queued(claimable))
        .values(
            dispatch_due_at=_next_due(now, backoff_s),
            last_dispatch_at=now,
            dispatch_count=JOBS.c.dispatch_count + 1,
        )
        .returning(JOBS.c.id)
    )
    claimed = set(session.execute(stmt).scalars())
    out = [i for i in ids if i in claimed]
    if out:
        add_events(session, JobEventKind.DISPATCHED, out, actor=actor, now=now)
    return out


def release_sends(
    session: Session,
    job_ids: Sequence[str],
    *,
    retry_at: datetime,
    actor: str | None = None,
    claimed_at: datetime | None = None,
) -> None:
    """Give back claimed sends that failed (broker down): due again at ``retry_at``; their
    ``dispatched`` events (``actor``'s, at ``claimed_at``) are withdrawn."""
    if not job_ids:
        return
    if claimed_at is not None:
        session.execute(
            delete(JOB_EVENTS).where(
                JOB_EVENTS.c.job_id.in_(list(job_ids)),
                JOB_EVENTS.c.kind == JobEventKind.DISPATCHED,
                JOB_EVENTS.c.at == now_utc(claimed_at),
                JOB_EVENTS.c.actor == actor,
            )
        )
    session.execute(
        update(JOBS)
        .where(JOBS.c.id.in_(list(job_ids)), JOBS.c.status == JobStatus.QUEUED)
        .values(
            dispatch_due_at=retry_at,
            dispatch_count=case((JOBS.c.dispatch_count > 0, JOBS.c.dispatch_count - 1), else_=0),
        )
    )


def queued_sent_count(session: Session) -> int:
    """Queued jobs (not cancel-requested) whose message was sent at least once."""
    stmt = select(func.count()).select_from(JOBS).where(and_queued(JOBS.c.dispatch_count > 0))
    return int(session.execute(stmt).scalar_one())


# --------------------------------------------------------------------------- service leases


def try_lead(
    session: Session, name: str, owner: str, ttl_s: float, *, now: datetime | None = None
) -> bool:
    """Hold the role ``name`` for ``ttl_s`` seconds more; True if ``owner`` holds it now.

    One conditional UPDATE takes the lease when ``owner`` already holds it or it expired; the
    first caller ever INSERTs it. A paused holder finds, when it resumes, that it lost it.
    """
    if ttl_s <= 0:
        raise ValueError(f"ttl_s must be > 0, got {ttl_s}")
    now = now_utc(now)
    until = now + timedelta(seconds=ttl_s)
    stmt = (
        update(SERVICE_LEASES)
        .where(
            SERVICE_LEASES.c.name == name,
            or_(SERVICE_LEASES.c.owner == owner, SERVICE_LEASES.c.expires_at < now),
        )
        .values(owner=owner, expires_at=until)
    )
    if rowcount(session.execute(stmt)) > 0:
        return True
    return insert_ignoring_duplicates(
        session, SERVICE_LEASES, {"name": name, "owner": owner, "expires_at": until}, ("name",)
    )


def release_lead(session: Session, name: str, owner: str) -> None:
    """Give up the role ``name`` if ``owner`` holds it (a clean shutdown)."""
    session.execute(
        delete(SERVICE_LEASES).where(SERVICE_LEASES.c.name == name, SERVICE_LEASES.c.owner == owner)
    )


def lead_holder(session: Session, name: str) -> tuple[str, datetime] | None:
    """``(owner, expires_at)`` of the role ``name``, or None."""
    row = session.execute(
        select(SERVICE_LEASES.c.owner, SERVICE_LEASES.c.expires_at).where(
            SERVICE_LEASES.c.name == name
        )
    ).first()
    return None if row is None else (str(row[0]), row[1])


__all__ = [
    "BACKOFF_LEASES",
    "and_queued",
    "backoff_schedule",
    "claim_sends",
    "lead_holder",
    "queued_sent_count",
    "release_lead",
    "release_sends",
    "try_lead",
]
