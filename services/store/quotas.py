"""Per-API-key usage and quotas: active jobs, worker CPU seconds per UTC hour, stored bytes.

Workers add the CPU time of each job as it runs (``add_cpu_seconds``, in the transaction that
writes its progress); the API checks a key's usage before it stores new jobs
(``quota_refusal``), and refuses with a message saying what is used, what the limit is and
what to do, and how many seconds to wait before trying again (``QuotaRefusal``). A key's own
limits (``api_keys.max_*``) override the settings' defaults.

The check and the insert are atomic when both run in ONE transaction: ``quota_refusal`` first
locks the key (``lock_key``), so concurrent submissions of one key queue up, and each counts
the jobs and bytes the previous ones committed. On PostgreSQL the lock is the key's
``api_keys`` row taken ``FOR NO KEY UPDATE`` until commit or rollback (it does not block the
foreign-key checks of rows that refer to the key, e.g. a worker's usage row, nor other keys);
the default READ COMMITTED isolation gives every statement after it a fresh snapshot. On SQLite
the clause is not emitted: the API's write transaction holds the database's write lock from
``BEGIN IMMEDIATE`` (``session_scope(immediate=True)``), and a deferred transaction whose read
went stale fails at its first write instead of storing past the limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime, timedelta

from sqlalchemy import func, select, update
from sqlalchemy.orm import Session

from services.store.records import ApiKeyRecord
from services.store.settings import Settings
from services.store.sql import insert_ignoring_duplicates, now_utc, rowcount
from services.store.states import JobStatus
from services.store.tables import API_KEYS, ARTIFACTS, JOBS, KEY_USAGE

#: ``Retry-After`` of an active-jobs refusal (s): a slot frees when one of the key's jobs ends,
#: which the API cannot foresee; jobs run for tens of seconds to minutes, so half a minute
#: between attempts finds a free slot soon without hammering the API.
ACTIVE_JOBS_RETRY_AFTER_S = 30
#: ``Retry-After`` of a storage refusal (s): bytes are freed only by deleting jobs
#: (``DELETE /jobs/{id}``), so an automatic retry waits a minute for the client to do that.
STORAGE_RETRY_AFTER_S = 60


def hour_of(now: datetime) -> datetime:
    """The UTC clock hour containing ``now`` (minutes, seconds and microseconds zeroed)."""
    return now_utc(now).replace(minute=0, second=0, microsecond=0)


def add_cpu_seconds(
    session: Session, job_id: str, seconds: float, *, now: datetime | None = None
) -> None:
    """Charge ``seconds`` of worker CPU time to the job and to its key's current hour."""
    if seconds <= 0:
        return
    now = now_utc(now)
    owner = session.execute(
        update(JOBS)
        .where(JOBS.c.id == job_id)
        .values(cpu_seconds=JOBS.c.cpu_seconds + float(seconds))
        .returning(JOBS.c.owner_key_id)
    ).scalar_one_or_none()
    if owner is None:
        return
    hour = hour_of(now)
    bumped = session.execute(
        update(KEY_USAGE)
        .where(KEY_USAGE.c.owner_key_id == owner, KEY_USAGE.c.hour == hour)
        .values(cpu_seconds=KEY_USAGE.c.cpu_seconds + float(seconds))
    )
    if rowcount(bumped) == 0:
        inserted = insert_ignoring_duplicates(
            session,
            KEY_USAGE,
            {"owner_key_id": owner, "hour": hour, "cpu_seconds": float(seconds)},
            ("owner_key_id", "hour"),
        )
        if not inserted:  # a concurrent writer created the row first
            session.execute(
                update(KEY_USAGE)
                .where(KEY_USAGE.c.owner_key_id == owner, KEY_USAGE.c.hour == hour)
                .values(cpu_seconds=KEY_USAGE.c.cpu_seconds + float(seconds))
            )


@dataclass(frozen=True, slots=True)
class Usage:
    """What one API key uses now."""

    active_jobs: int
    cpu_seconds_this_hour: float
    stored_bytes: int


def usage(session: Session, owner_key_id: str, *, now: datetime | None = None) -> Usage:
    """Active (queued + running) jobs, CPU seconds in the current UTC hour, stored bytes
    (artifacts plus the stored specs of jobs) of ``owner_key_id``."""
    active = session.execute(
        select(func.count())
        .select_from(JOBS)
        .where(
            JOBS.c.owner_key_id == owner_key_id,
            JOBS.c.status.in_([JobStatus.QUEUED, JobStatus.RUNNING]),
        )
    ).scalar_one()
    cpu = session.execute(
        select(KEY_USAGE.c.cpu_seconds).where(
            KEY_USAGE.c.owner_key_id == owner_key_id, KEY_USAGE.c.hour == hour_of(now_utc(now))
        )
    ).scalar_one_or_none()
    artifacts = session.execute(
        select(func.coalesce(func.sum(ARTIFACTS.c.size_bytes), 0))
        .select_from(ARTIFACTS.join(JOBS, JOBS.c.id == ARTIFACTS.c.job_id))
        .where(JOBS.c.owner_key_id == owner_key_id)
    ).scalar_one()
    specs = session.execute(
        select(func.coalesce(func.sum(JOBS.c.spec_bytes), 0)).where(
            JOBS.c.owner_key_id == owner_key_id
        )
    ).scalar_one()
    return Usage(int(active), float(cpu or 0.0), int(artifacts) + int(specs))


@dataclass(frozen=True, slots=True)
class QuotaRefusal:
    """Why a submission is refused (``message``: what is used, the limit, what to do) and how
    long to wait before trying again (``retry_after_s``: whole seconds, >= 1; the API's
    ``Retry-After``)."""

    message: str
    retry_after_s: int


def lock_key(session: Session, owner_key_id: str) -> None:
    """Hold ``owner_key_id``'s quota lock until the transaction of ``session`` ends (see the
    module docstring): a concurrent caller blocks here until this transaction commits or rolls
    back. A no-op statement on SQLite, whose write transactions are serialised already."""
    session.execute(
        select(API_KEYS.c.id).where(API_KEYS.c.id == owner_key_id).with_for_update(key_share=True)
    )


def quota_refusal(
    session: Session,
    key: ApiKeyRecord,
    settings: Settings,
    *,
    new_jobs: int,
    new_bytes: int,
    now: datetime | None = None,
) -> QuotaRefusal | None:
    """Why ``key`` may not add ``new_jobs`` jobs of ``new_bytes`` stored bytes, or None.

    Locks the key first (``lock_key``): store the jobs in the same transaction, so that no
    concurrent submission of the key counts before they are committed.
    ``retry_after_s`` is ``ACTIVE_JOBS_RETRY_AFTER_S`` (active jobs), the seconds until the
    next UTC hour (CPU seconds per hour) or ``STORAGE_RETRY_AFTER_S`` (stored bytes).
    """
    now = now_utc(now)
    lock_key(session, key.id)
    used = usage(session, key.id, now=now)
    max_active = key.max_active_jobs or settings.quota_active_jobs
    max_cpu = key.max_cpu_seconds_per_hour or settings.quota_cpu_seconds_per_hour
    max_bytes = key.max_storage_bytes or settings.quota_storage_bytes
    if used.active_jobs + new_jobs > max_active:
        return QuotaRefusal(
            f"this API key has {used.active_jobs} jobs queued or running and asks for "
            f"{new_jobs} more; its limit is {max_active} at a time: wait for some to finish "
            "or cancel them (POST /jobs/{id}/cancel)",
            ACTIVE_JOBS_RETRY_AFTER_S,
        )
    if used.cpu_seconds_this_hour >= max_cpu:
        reset = hour_of(now) + timedelta(hours=1)
        return QuotaRefusal(
            f"this API key's jobs used {used.cpu_seconds_this_hour:.0f} worker CPU seconds "
            f"this hour; its limit is {max_cpu:.0f} per hour: submit again after "
            f"{reset.strftime('%H:%M')} UTC",
            max(1, math.ceil((reset - now).total_seconds())),
        )
    if used.stored_bytes + new_bytes > max_bytes:
        return QuotaRefusal(
            f"this API key stores {used.stored_bytes} bytes and the request adds {new_bytes}; "
            f"its limit is {max_bytes} bytes: delete finished jobs you no longer need "
            "(DELETE /jobs/{id})",
            STORAGE_RETRY_AFTER_S,
        )
    return None


__all__ = [
    "ACTIVE_JOBS_RETRY_AFTER_S",
    "STORAGE_RETRY_AFTER_S",
    "QuotaRefusal",
    "Usage",
    "add_cpu_seconds",
    "hour_of",
    "lock_key",
    "quota_refusal",
    "usage",
]
