"""Create and read functions of the store (robots, sweeps, jobs; API keys: ``api_keys``).

Every function takes the ``Session`` first and never commits: wrap calls in
``session_scope()``, which makes everything inside one transaction. Rows come back as frozen
records (``services.store.records``), never as live ORM objects. Statements are Core
statements on the mapped tables, so no ORM identity map can hand out stale rows after the
conditional UPDATEs of ``services.store.lifecycle``.

``owner_key_id`` arguments of the getters scope a lookup to one API key: a row of another owner
reads as missing (the API answers 404 rather than 403, so ids of others do not leak).
"""

from __future__ import annotations

import copy
from collections.abc import Iterable, Mapping, Sequence
from datetime import datetime, timedelta
from typing import Any

from sqlalchemy import ColumnElement, Table, delete, func, insert, select
from sqlalchemy.orm import Session

from services.store.events import add_events
from services.store.id_prefix import owned_with_prefix
from services.store.records import (
    JobRecord,
    Page,
    RobotRecord,
    SweepRecord,
)
from services.store.robot_documents import by_reference, expand
from services.store.specs import apply_overrides, json_size, spec_value
from services.store.sql import (
    COUNT_CAP,
    fetch_all,
    fetch_one,
    fetch_page,
    insert_or_conflict,
    now_utc,
    rowcount,
)
from services.store.states import JobEventKind, JobStatus, RobotSource
from services.store.tables import JOBS, ROBOTS, SWEEPS, new_id


def _owned(table: Table, owner_key_id: str | None) -> list[ColumnElement[bool]]:
    return [] if owner_key_id is None else [table.c.owner_key_id == owner_key_id]


# --------------------------------------------------------------------------- robots


def create_robot(
    session: Session,
    *,
    owner_key_id: str,
    name: str,
    source_kind: RobotSource | str,
    spec: Any,
    now: datetime | None = None,
) -> RobotRecord:
    """Store a robot model; ConflictError if the owner already has a robot of this name."""
    robot_id = new_id()
    insert_or_conflict(
        session,
        ROBOTS,
        {
            "id": robot_id,
            "owner_key_id": owner_key_id,
            "name": name,
            "source_kind": RobotSource(source_kind),
            "spec": spec,
            "created_at": now_utc(now),
        },
        f"a robot named {name!r} already exists",
    )
    record = get_robot(session, robot_id)
    assert record is not None
    return record


def get_robot(
    session: Session, robot_id: str, *, owner_key_id: str | None = None
) -> RobotRecord | None:
    """The robot with this id (of this owner when given), or None."""
    stmt = select(ROBOTS).where(ROBOTS.c.id == robot_id, *_owned(ROBOTS, owner_key_id))
    return fetch_one(session, RobotRecord, stmt)


def get_robot_by_name(session: Session, *, owner_key_id: str, name: str) -> RobotRecord | None:
    """The owner's robot called ``name``, or None."""
    stmt = select(ROBOTS).where(ROBOTS.c.owner_key_id == owner_key_id, ROBOTS.c.name == name)
    return fetch_one(session, RobotRecord, stmt)


def list_robots(
    session: Session, *, owner_key_id: str | None = None, limit: int = 50, offset: int = 0
) -> Page[RobotRecord]:
    """Robots (of one owner when given), by name."""
    stmt = select(ROBOTS).where(*_owned(ROBOTS, owner_key_id))
    return fetch_page(session, RobotRecord, stmt, (ROBOTS.c.name, ROBOTS.c.id), limit, offset)


def delete_robot(session: Session, robot_id: str, *, owner_key_id: str | None = None) -> bool:
    """Delete a robot (of this owner when given). True if a row was deleted."""
    stmt = delete(ROBOTS).where(ROBOTS.c.id == robot_id, *_owned(ROBOTS, owner_key_id))
    return rowcount(session.execute(stmt)) > 0


# --------------------------------------------------------------------------- sweeps


def create_sweep(
    session: Session,
    *,
    owner_key_id: str,
    base_spec: Any,
    axes: Any,
    now: datetime | None = None,
) -> SweepRecord:
    """Store a sweep; create its jobs with ``create_job(..., sweep_id=sweep.id)`` in the same
    ``session_scope`` so the sweep and its jobs appear together."""

    sweep_id = new_id()
    session.execute(
        insert(SWEEPS).values(
            id=sweep_id,
            owner_key_id=owner_key_id,
            base_spec=by_reference(session, base_spec),
            axes=axes,
            created_at=now_utc(now),
        )
    )
    record = get_sweep(session, sweep_id)
    assert record is not None
    return record


def get_sweep(
    session: Session, sweep_id: str, *, owner_key_id: str | None = None
) -> SweepRecord | None:
    """The sweep with this id (of this owner when given), or None."""
    stmt = select(SWEEPS).where(SWEEPS.c.id == sweep_id, *_owned(SWEEPS, owner_key_id))
    return fetch_one(session, SweepRecord, stmt)


def list_sweeps(
    session: Session,
    *,
    owner_key_id: str | None = None,
    limit: int = 50,
    offset: int = 0,
    id_prefix: str | None = None,
) -> Page[SweepRecord]:
    """Sweeps (of one owner when given; whose id starts with ``id_prefix`` when given, on the
    primary key's index), newest first."""
    conditions = _owned(SWEEPS, owner_key_id)
    if id_prefix:
        conditions = owned_with_prefix(SWEEPS, owner_key_id, id_prefix)
    stmt = select(SWEEPS).where(*conditions)
    return fetch_page(
        session,
        SweepRecord,
        stmt,
        (SWEEPS.c.created_at.desc(), SWEEPS.c.id),
        limit,
        offset,
    )


def delete_sweep(session: Session, sweep_id: str, *, owner_key_id: str | None = None) -> bool:
    """Delete a sweep's row; True if it existed. Delete its jobs first (``delete_job``): a
    job's spec is the sweep's base spec with its overrides."""
    stmt = delete(SWEEPS).where(SWEEPS.c.id == sweep_id, *_owned(SWEEPS, owner_key_id))
    return rowcount(session.execute(stmt)) > 0


# --------------------------------------------------------------------------- jobs


def create_job(
    session: Session,
    *,
    owner_key_id: str,
    spec: Any,
    total_generations: int = 0,
    sweep_id: str | None = None,
    warnings: Iterable[str] = (),
    facts: Any = None,
    now: datetime | None = None,
) -> JobRecord:
    """Store a queued job, due for dispatch (its ``submitted`` event in the same transaction).

    The queue message is sent after the commit (``services.store.dispatch``); if that never
    happens (the process died, the broker was down) the dispatcher sends it.
    """
    (job_id,) = create_jobs(
        session,
        owner_key_id=owner_key_id,
        specs=[spec],
        total_generations=[total_generations],
        sweep_id=sweep_id,
        warnings=warnings,
        facts=[facts],
        now=now,
    )
    record = get_job(session, job_id)
    assert record is not None
    return record


def create_jobs(
    session: Session,
    *,
    owner_key_id: str,
    specs: Sequence[Any] | None = None,
    overrides: Sequence[Mapping[str, Any]] | None = None,
    total_generations: Sequence[int],
    sweep_id: str | None = None,
    warnings: Iterable[str] = (),
    facts: Sequence[Any] | None = None,
    now: datetime | None = None,
) -> list[str]:
    """Store several queued jobs in one INSERT; their ids in order.

    Give either whole ``specs`` or, for the jobs of sweep ``sweep_id``, their ``overrides`` of
    the sweep's base spec (the spec is then stored once, in the sweep). A spec's robot document
    is stored once by content and referred to (``services.store.robot_documents``);
    ``spec_bytes`` counts the whole spec, robot included. ``facts``: per job what its
    validation learned (``JobRecord.facts``), or None.
    """

    if (specs is None) == (overrides is None):
        raise ValueError("give either specs or overrides")
    if overrides is not None and sweep_id is None:
        raise ValueError("overrides need the sweep_id whose base spec they modify")
    docs: Sequence[Any] = specs if specs is not None else overrides  # type: ignore[assignment]
    if len(docs) != len(total_generations):
        raise ValueError("one total_generations per job")
    if facts is not None and len(facts) != len(docs):
        raise ValueError("one facts per job")
    at = now_utc(now)
    notes = [str(w) for w in warnings]
    rows = []
    for i, (doc, total) in enumerate(zip(docs, total_generations, strict=True)):
        rows.append(
            {
                "id": new_id(),
                "owner_key_id": owner_key_id,
                "sweep_id": sweep_id,
                "status": JobStatus.QUEUED,
                "spec": by_reference(session, doc) if specs is not None else None,
                "overrides": by_reference(session, dict(doc)) if overrides is not None else None,
                "spec_bytes": json_size(doc),
                "progress_generation": 0,
                "total_generations": int(total),
                "attempt_count": 0,
                "cancel_requested": False,
                "warnings": notes,
                # one microsecond apart: listings ordered by creation keep the given order
                "created_at": at + timedelta(microseconds=i),
                "dispatch_due_at": at,
                "dispatch_count": 0,
                "cpu_seconds": 0.0,
                "facts": facts[i] if facts is not None else None,
            }
        )
    if rows:
        session.execute(insert(JOBS), rows)
    ids = [str(r["id"]) for r in rows]
    add_events(session, JobEventKind.SUBMITTED, ids, attempts=[0] * len(ids), now=at)
    return ids


def job_labels(session: Session, jobs: Iterable[JobRecord]) -> dict[str, dict[str, Any]]:
    """``{job_id: {"name": ..., "problem": {"kind": ...}}}``: the spec fields a listing shows,
    read for the jobs of sweeps from their sweep's base and overrides without building specs."""

    jobs = list(jobs)
    sweep_ids = {j.sweep_id for j in jobs if j.spec is None and j.sweep_id is not None}
    bases: dict[str, Any] = {}
    if sweep_ids:
        rows = session.execute(
            select(SWEEPS.c.id, SWEEPS.c.base_spec).where(SWEEPS.c.id.in_(sweep_ids))
        )
        bases = {r[0]: r[1] for r in rows}
    labels: dict[str, dict[str, Any]] = {}
    for job in jobs:
        base = job.spec if job.spec is not None else bases.get(job.sweep_id or "", {})
        overrides = None if job.spec is not None else job.overrides
        labels[job.id] = {
            "name": spec_value(base, overrides, "name"),
            "problem": {"kind": spec_value(base, overrides, "problem.kind")},
            "record": spec_value(base, overrides, "record"),
        }
    return labels


def job_spec(session: Session, job: JobRecord) -> Any:
    """The spec document of a job: its own, or its sweep's base with its overrides applied;
    its robot document in place of the stored reference."""

    if job.spec is not None or job.sweep_id is None:
        return copy.deepcopy(expand(session, job.spec))

    base = session.execute(
        select(SWEEPS.c.base_spec).where(SWEEPS.c.id == job.sweep_id)
    ).scalar_one_or_none()
    return apply_overrides(expand(session, base or {}), expand(session, job.overrides or {}))


def sweep_base_spec(session: Session, sweep: SweepRecord) -> Any:
    """A sweep's base spec with its robot document in place of the stored reference."""

    return copy.deepcopy(expand(session, sweep.base_spec))


def get_job(session: Session, job_id: str, *, owner_key_id: str | None = None) -> JobRecord | None:
    """The job with this id (of this owner when given), or None."""
    stmt = select(JOBS).where(JOBS.c.id == job_id, *_owned(JOBS, owner_key_id))
    return fetch_one(session, JobRecord, stmt)


def delete_job(session: Session, job_id: str, *, owner_key_id: str | None = None) -> bool:
    """Delete a job and its rows (cascade); True if it existed. Its files are the caller's to
    remove (``ArtifactStore.delete_job``) after the commit."""
    stmt = delete(JOBS).where(JOBS.c.id == job_id, *_owned(JOBS, owner_key_id))
    return rowcount(session.execute(stmt)) > 0


def _statuses(status: JobStatus | str | Iterable[JobStatus | str]) -> list[JobStatus]:
    if isinstance(status, str):
        return [JobStatus(status)]
    return [JobStatus(s) for s in status]


def list_jobs(
    session: Session,
    *,
    owner_key_id: str | None = None,
    status: JobStatus | str | Iterable[JobStatus | str] | None = None,
    sweep_id: str | None = None,
    limit: int = 50,
    offset: int = 0,
    id_prefix: str | None = None,
    feasible: bool | None = None,
) -> Page[JobRecord]:
    """Jobs filtered by owner, status (one or several), sweep, id prefix (a range of the
    primary key's index: ``services.store.id_prefix``) and verdict (``feasible`` True or
    False: only succeeded jobs whose optimum was found feasible / infeasible), newest first.
    ``total`` counts up to ``COUNT_CAP + 1`` (``services.store.sql``: "more than")."""
    conditions = _owned(JOBS, owner_key_id)
    if id_prefix:
        conditions = owned_with_prefix(JOBS, owner_key_id, id_prefix)
    if status is not None:
        conditions.append(JOBS.c.status.in_(_statuses(status)))
    if sweep_id is not None:
        conditions.append(JOBS.c.sweep_id == sweep_id)
    if feasible is not None:
        conditions.append(JOBS.c.feasible == bool(feasible))
    stmt = select(JOBS).where(*conditions)
    order = (JOBS.c.created_at.desc(), JOBS.c.id)
    return fetch_page(session, JobRecord, stmt, order, limit, offset, count_cap=COUNT_CAP)


def sweep_jobs(
    session: Session, sweep_id: str, *, owner_key_id: str | None = None
) -> tuple[JobRecord, ...]:
    """Every job of sweep ``sweep_id`` in the sweep's order (the order they were created in);
    a sweep has at most ``Settings.max_sweep_jobs`` jobs."""
    conditions = [*_owned(JOBS, owner_key_id), JOBS.c.sweep_id == sweep_id]
    stmt = select(JOBS).where(*conditions).order_by(JOBS.c.created_at, JOBS.c.id)
    return fetch_all(session, JobRecord, stmt)


def count_jobs_by_status(
    session: Session, *, owner_key_id: str | None = None, sweep_id: str | None = None
) -> dict[JobStatus, int]:
    """Number of jobs in each status (every status present, zero when none)."""
    conditions = _owned(JOBS, owner_key_id)
    if sweep_id is not None:
        conditions.append(JOBS.c.sweep_id == sweep_id)
    stmt = select(JOBS.c.status, func.count()).where(*conditions).group_by(JOBS.c.status)
    counts = {s: 0 for s in JobStatus}
    for status, n in session.execute(stmt):
        counts[JobStatus(status)] = int(n)
    return counts


__all__ = [
    "count_jobs_by_status",
    "create_job",
    "create_jobs",
    "create_robot",
    "create_sweep",
    "delete_job",
    "delete_robot",
    "get_job",
    "get_robot",
    "get_robot_by_name",
    "get_sweep",
    "job_labels",
    "job_spec",
    "list_jobs",
    "list_robots",
    "list_sweeps",
    "sweep_base_spec",
]
