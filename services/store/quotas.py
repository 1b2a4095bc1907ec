"""Per-API-key usage and quotas: active jobs, worker CPU seconds per UTC hour, stored bytes.

Workers add the CPU time of each job as it runs (``add_cpu_seconds``, in the transaction that
writes its progress); the API checks a key's usage before it stores new jobs
(``quota_refusal``), and refuses with a message saying what is used, what the limit is and
what to do. A key's own limits (``api_keys.max_*``) override the settings' defaults.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timedelta

from sqlalchemy import func, select, update
from sqlalchemy.orm import Session

from services.store.lifecycle import insert_ignoring_duplicates
from services.store.records import ApiKeyRecord
from services.store.repository import now_utc, rowcount
from services.store.settings import Settings
from services.store.tables import ARTIFACTS, JOBS, KEY_USAGE, JobStatus


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


def quota_refusal(
    session: Session,
    key: ApiKeyRecord,
    settings: Settings,
    *,
    new_jobs: int,
    new_bytes: int,
    now: datetime | None = None,
) -> str | None:
    """Why ``key`` may not add ``new_jobs`` jobs of ``new_bytes`` stored bytes, or None."""
    now = now_utc(now)
    used = usage(session, key.id, now=now)
    max_active = key.max_active_jobs or settings.quota_active_jobs
    max_cpu = key.max_cpu_seconds_per_hour or settings.quota_cpu_seconds_per_hour
    max_bytes = key.max_storage_bytes or settings.quota_storage_bytes
    if used.active_jobs + new_jobs > max_active:
        return (
            f"this API key has {used.active_jobs} jobs queued or running and asks for "
            f"{new_jobs} more; its limit is {max_active} at a time: wait for some to finish "
            "or cancel them (POST /jobs/{id}/cancel)"
        )
    if used.cpu_seconds_this_hour >= max_cpu:
        reset = hour_of(now) + timedelta(hours=1)
        return (
            f"this API key's jobs used {used.cpu_seconds_this_hour:.0f} worker CPU seconds "
            f"this hour; its limit is {max_cpu:.0f} per hour: submit again after "
            f"{reset.strftime('%H:%M')} UTC"
        )
    if used.stored_bytes + new_bytes > max_bytes:
        return (
            f"this API key stores {used.stored_bytes} bytes and the request adds {new_bytes}; "
            f"its limit is {max_bytes} bytes: delete finished jobs you no longer need "
            "(DELETE /jobs/{id})"
        )
    return None


__all__ = ["Usage", "add_cpu_seconds", "hour_of", "quota_refusal", "usage"]
