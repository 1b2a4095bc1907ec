"""Job lifecycle for workers and the reaper: claims, leases, cancellation, outcome, reaper.

A worker owns a running job through its *lease*: ``lease_owner`` (the worker id) and
``lease_expires_at`` (the conditions are in ``leases``). Every transition is ONE conditional
UPDATE whose WHERE clause states the expected state, so two workers (or a re-delivered Celery
message) can never both win:

- ``claim_job``: queued -> running, or running with an expired lease -> running (attempt + 1);
- ``heartbeat`` / ``renew_lease``: extends the lease, only for the lease owner (``renew_lease``
  also answers ``cancel_requested``, so a worker needs no query per generation to cancel);
- ``finish_job`` / ``fail_job`` / ``mark_cancelled``: running -> terminal, only for the owner;
- ``requeue_expired``: running with an expired lease -> queued (or failed / cancelled).

Worker writes (``finish_job``, ``fail_job``, ``mark_cancelled``; the progress writes are in
``progress``) raise ``LeaseLostError`` when the caller no longer owns the lease, and then
write nothing; ``heartbeat`` returns False and ``claim_job`` returns None instead.
Each function starts with its write statement, so on SQLite it takes the write lock first.

Like the repository, functions take the ``Session`` first and never commit. ``finish_job``
runs inside a SAVEPOINT, so it is all-or-nothing even within a larger transaction.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from datetime import datetime
from typing import Any

from sqlalchemy import ColumnElement, and_, case, func, insert, literal, select, update
from sqlalchemy.orm import Session

from services.store.errors import LeaseLostError
from services.store.events import add_events
from services.store.leases import _RUNNING, _expired, _lease_until, _owned_by, _require_owner
from services.store.records import (
    ArtifactIn,
    BaselineIn,
    JobRecord,
    ParetoPointIn,
    ReapReport,
    ResultIn,
)
from services.store.repository import get_job
from services.store.sql import now_utc, rowcount
from services.store.states import JobEventKind, JobStatus
from services.store.tables import ARTIFACTS, BASELINES, JOBS, PARETO_POINTS, RESULTS
from services.store.types import UTCDateTime

# --------------------------------------------------------------------------- claims and leases


def claim_job(
    session: Session,
    job_id: str,
    worker_id: str,
    lease_s: float,
    *,
    max_attempts: int | None = None,
    now: datetime | None = None,
) -> JobRecord | None:
    """Claim a job for ``worker_id`` with one conditional UPDATE; the claimed job, or None.

    Succeeds for a queued job, or a running job whose lease expired before ``now`` (its worker
    is presumed dead; only if fewer than ``max_attempts`` claims were made when given). Each
    claim increments ``attempt_count`` (1 on the first). A cancel-requested job is never
    claimed. None means: someone else has it, it is finished, or it does not exist, so a
    re-delivered message is harmless. Read the checkpoint after a claim to resume.
    """
    now = now_utc(now)
    reclaimable = _expired(now)
    if max_attempts is not None:
        reclaimable = and_(reclaimable, JOBS.c.attempt_count < max_attempts)
    stmt = (
        update(JOBS)
        .where(
            JOBS.c.id == job_id,
            JOBS.c.cancel_requested.is_(False),
            (JOBS.c.status == JobStatus.QUEUED) | reclaimable,
        )
        .values(
            status=_RUNNING,
            lease_owner=worker_id,
            lease_expires_at=_lease_until(now, lease_s),
            heartbeat_at=now,
            attempt_count=JOBS.c.attempt_count + 1,
            started_at=func.coalesce(JOBS.c.started_at, literal(now, UTCDateTime())),
            dispatch_due_at=None,
        )
    )
    if rowcount(session.execute(stmt)) == 0:
        return None
    job = get_job(session, job_id)
    assert job is not None
    add_events(
        session, JobEventKind.CLAIMED, [job_id], actor=worker_id, attempts=[job.attempt_count],
        now=now,
    )  # fmt: skip
    return job


def heartbeat(
    session: Session, job_id: str, worker_id: str, lease_s: float, *, now: datetime | None = None
) -> bool:
    """Extend the lease to ``now + lease_s``; False if ``worker_id`` no longer owns the job."""
    return renew_lease(session, job_id, worker_id, lease_s, now=now) is not None


def renew_lease(
    session: Session, job_id: str, worker_id: str, lease_s: float, *, now: datetime | None = None
) -> bool | None:
    """``heartbeat`` that also answers whether cancellation was requested, in the same UPDATE:
    None if ``worker_id`` no longer owns the job, else the job's ``cancel_requested``."""
    now = now_utc(now)
    stmt = (
        update(JOBS)
        .where(_owned_by(job_id, worker_id))
        .values(lease_expires_at=_lease_until(now, lease_s), heartbeat_at=now)
        .returning(JOBS.c.cancel_requested)
    )
    flag = session.execute(stmt).first()
    return None if flag is None else bool(flag[0])


# --------------------------------------------------------------------------- cancellation


def request_cancel(
    session: Session,
    job_id: str,
    *,
    owner_key_id: str | None = None,
    now: datetime | None = None,
) -> JobRecord | None:
    """Ask for a job to stop; the job afterwards, or None if missing (or another owner's).

    A queued job is cancelled at once; a running job gets ``cancel_requested`` and its worker
    stops after its next progress write or heartbeat (``record_generations`` and
    ``renew_lease`` answer the flag, then ``mark_cancelled``); a finished job is left as it is.
    """
    request_cancels(session, [job_id], owner_key_id=owner_key_id, now=now)
    return get_job(session, job_id, owner_key_id=owner_key_id)


def request_cancels(
    session: Session,
    job_ids: Sequence[str],
    *,
    owner_key_id: str | None = None,
    now: datetime | None = None,
) -> tuple[list[str], list[str]]:
    """:func:`request_cancel` for many jobs in two statements: ``(cancelled, stopping)`` — the
    queued jobs now cancelled and the running ones now asked to stop; missing, other owners'
    and finished jobs are left as they are."""
    if not job_ids:
        return [], []
    now = now_utc(now)
    ids = JOBS.c.id.in_(list(job_ids))
    owner = [] if owner_key_id is None else [JOBS.c.owner_key_id == owner_key_id]
    cancelled = list(
        session.execute(
            update(JOBS)
            .where(ids, JOBS.c.status == JobStatus.QUEUED, *owner)
            .values(
                status=JobStatus.CANCELLED,
                cancel_requested=True,
                finished_at=now,
                dispatch_due_at=None,
            )
            .returning(JOBS.c.id)
        ).scalars()
    )
    add_events(session, JobEventKind.CANCELLED, cancelled, detail="cancelled while queued", now=now)
    stopping = list(
        session.execute(
            update(JOBS)
            .where(ids, JOBS.c.status == _RUNNING, *owner)
            .values(cancel_requested=True)
            .returning(JOBS.c.id)
        ).scalars()
    )
    return cancelled, stopping


def is_cancel_requested(session: Session, job_id: str) -> bool:
    """True if the job's cancellation was requested (or the job no longer exists: stop)."""
    flag = session.execute(select(JOBS.c.cancel_requested).where(JOBS.c.id == job_id)).first()
    return True if flag is None else bool(flag[0])


# --------------------------------------------------------------------------- outcomes


def _terminal_values(status: JobStatus, now: datetime, **extra: Any) -> dict[str, Any]:
    return {
        "status": status,
        "finished_at": now,
        "lease_expires_at": None,
        "dispatch_due_at": None,
        **extra,
    }


def mark_cancelled(
    session: Session, job_id: str, worker_id: str, *, now: datetime | None = None
) -> JobRecord:
    """running -> cancelled by the lease owner (after it saw ``is_cancel_requested``).

    Raises LeaseLostError if ``worker_id`` does not own the lease.
    """
    now = now_utc(now)
    _require_owner(session, job_id, worker_id, _terminal_values(JobStatus.CANCELLED, now))
    add_events(session, JobEventKind.CANCELLED, [job_id], actor=worker_id, now=now)
    record = get_job(session, job_id)
    assert record is not None
    return record


def fail_job(
    session: Session,
    job_id: str,
    worker_id: str | None,
    message: str,
    *,
    now: datetime | None = None,
) -> JobRecord:
    """running -> failed with ``message`` (say what the user can change).

    ``worker_id`` must own the lease (LeaseLostError otherwise); ``None`` fails a queued or
    running job whoever holds it (CLI, API, admin), and raises LeaseLostError if it is already
    finished.
    """
    now = now_utc(now)
    values = _terminal_values(JobStatus.FAILED, now, error_message=str(message))
    if worker_id is not None:
        _require_owner(session, job_id, worker_id, values)
    else:
        stmt = (
            update(JOBS)
            .where(JOBS.c.id == job_id, JOBS.c.status.in_([JobStatus.QUEUED, _RUNNING]))
            .values(**values)
        )
        if rowcount(session.execute(stmt)) == 0:
            raise LeaseLostError(f"job {job_id} is missing or already finished")
    add_events(
        session, JobEventKind.FAILED, [job_id], actor=worker_id, detail=str(message)[:2000],
        now=now,
    )  # fmt: skip
    record = get_job(session, job_id)
    assert record is not None
    return record


def finish_job(
    session: Session,
    job_id: str,
    worker_id: str,
    *,
    result: ResultIn,
    pareto: Iterable[ParetoPointIn] = (),
    baselines: Iterable[BaselineIn] = (),
    artifacts: Iterable[ArtifactIn] = (),
    warnings: Iterable[str] = (),
    now: datetime | None = None,
) -> JobRecord:
    """running -> succeeded, writing result, Pareto front, baselines and artifact rows at once.

    The job's verdict (``result.feasible`` and ``result.violations``) is written on the job
    row by the same UPDATE that makes it succeeded: a succeeded job never lacks the verdict
    its worker found (None only when the result was not checked). All-or-nothing (inside a
    SAVEPOINT): if any row fails (e.g. two Pareto points with the same index) the exception
    propagates and neither the rows nor the status change are kept. ``warnings`` are appended
    to the job's warnings. Raises LeaseLostError, writing nothing, if ``worker_id`` does not
    own the lease.
    """
    now = now_utc(now)
    feasible = None if result.feasible is None else bool(result.feasible)
    violations = None if feasible is None else list(result.violations or [])
    with session.begin_nested():
        _require_owner(
            session,
            job_id,
            worker_id,
            _terminal_values(
                JobStatus.SUCCEEDED,
                now,
                feasible=feasible,
                violations=violations,
                progress_generation=case(
                    (
                        JOBS.c.progress_generation < JOBS.c.total_generations,
                        JOBS.c.total_generations,
                    ),
                    else_=JOBS.c.progress_generation,
                ),
            ),
        )
        extra = [str(w) for w in warnings]
        if extra:
            current = session.execute(select(JOBS.c.warnings).where(JOBS.c.id == job_id)).scalar()
            session.execute(
                update(JOBS).where(JOBS.c.id == job_id).values(warnings=[*(current or []), *extra])
            )
        session.execute(
            insert(RESULTS).values(
                job_id=job_id,
                best_x=result.best_x,
                objectives=result.objectives,
                metrics=result.metrics,
                summary=result.summary,
                created_at=now,
            )
        )
        rows = [
            {"job_id": job_id, "index": int(p.index), "x": p.x, "objectives": p.objectives}
            for p in pareto
        ]
        if rows:
            session.execute(insert(PARETO_POINTS), rows)
        rows = [{"job_id": job_id, "name": b.name, "metrics": b.metrics} for b in baselines]
        if rows:
            session.execute(insert(BASELINES), rows)
        rows = [
            {
                "job_id": job_id,
                "kind": a.kind,
                "relative_path": a.relative_path,
                "sha256": a.sha256,
                "size_bytes": int(a.size_bytes),
                "created_at": now,
            }
            for a in artifacts
        ]
        if rows:
            session.execute(insert(ARTIFACTS), rows)
        add_events(session, JobEventKind.SUCCEEDED, [job_id], actor=worker_id, now=now)
    record = get_job(session, job_id)
    assert record is not None
    return record


# --------------------------------------------------------------------------- reaper


def expired_leases(session: Session, now: datetime | None = None) -> tuple[str, ...]:
    """Ids of running jobs whose lease expired before ``now`` (their workers are presumed dead)."""
    stmt = select(JOBS.c.id).where(_expired(now_utc(now))).order_by(JOBS.c.lease_expires_at)
    return tuple(session.execute(stmt).scalars())


def requeue_expired(
    session: Session,
    now: datetime | None = None,
    *,
    max_attempts: int | None = None,
    actor: str | None = None,
) -> ReapReport:
    """Put running jobs with an expired lease back to queued; returns what happened to whom.

    Jobs whose cancellation was requested become cancelled; with ``max_attempts``, jobs
    already claimed that many times become failed (a job that keeps killing its worker).
    Requeued jobs are due for dispatch at once (in this transaction), so their message is sent
    by whoever dispatches next, once. Each step is one conditional UPDATE, so a concurrent
    ``claim_job`` or ``heartbeat`` cannot be overwritten.
    """
    now = now_utc(now)

    def _update(condition: ColumnElement[bool], values: dict[str, Any]) -> tuple[str, ...]:
        stmt = update(JOBS).where(_expired(now), condition).values(**values).returning(JOBS.c.id)
        return tuple(sorted(session.execute(stmt).scalars()))

    cancelled = _update(
        JOBS.c.cancel_requested.is_(True), _terminal_values(JobStatus.CANCELLED, now)
    )
    add_events(session, JobEventKind.CANCELLED, cancelled, actor=actor, now=now)
    failed: tuple[str, ...] = ()
    if max_attempts is not None:
        message = (
            f"the worker running this job stopped responding {max_attempts} times "
            "(lease expired); it may need more memory or time: reduce the population, "
            "generations or samples, or raise the worker limits"
        )
        failed = _update(
            JOBS.c.attempt_count >= max_attempts,
            _terminal_values(JobStatus.FAILED, now, error_message=message),
        )
        add_events(session, JobEventKind.FAILED, failed, actor=actor, detail=message, now=now)
    requeued = _update(
        JOBS.c.id.is_not(None),
        {
            "status": JobStatus.QUEUED,
            "lease_owner": None,
            "lease_expires_at": None,
            "dispatch_due_at": now,
            "dispatch_count": 0,  # a new wait in the queue: its message is due (dispatch)
        },
    )
    add_events(
        session, JobEventKind.REQUEUED, requeued, actor=actor, detail="lease expired", now=now
    )
    return ReapReport(requeued=requeued, failed=failed, cancelled=cancelled)
