"""A running job's progress, written by its worker: generations and checkpoints.

``record_generation(s)`` and ``save_checkpoint`` raise ``LeaseLostError`` when the caller no
longer owns the lease (``leases``), and then write nothing. Like the repository, functions take
the ``Session`` first and never commit. Generation numbers: 0 is the initial population,
1..total_generations the following ones; ``progress_generation`` is the highest generation
recorded.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from datetime import datetime
from typing import Any

from sqlalchemy import select, update
from sqlalchemy.orm import Session

from services.store.errors import LeaseLostError
from services.store.front_codec import encode_front
from services.store.leases import _owned_by, _require_owner
from services.store.records import CheckpointRecord, GenerationIn
from services.store.sql import (
    fetch_one,
    insert_ignoring_duplicates,
    insert_many_ignoring_duplicates,
    now_utc,
    rowcount,
)
from services.store.tables import CHECKPOINTS, GENERATIONS, JOBS


def _finite_or_none(value: float | None) -> float | None:
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def first_objective(best: Any) -> float | None:
    """``jobs.best_value``: the number the jobs page sorts "best" by — ``best`` itself or its
    first element (a job's best objective(s) so far, JSON), None when missing or not finite."""
    if isinstance(best, list | tuple):
        best = best[0] if best else None
    if isinstance(best, bool) or not isinstance(best, int | float):
        return None
    return _finite_or_none(best)


def _check_owner(session: Session, job_id: str, worker_id: str) -> None:
    """Raise LeaseLostError unless ``worker_id`` holds the lease of the running job."""
    owned = session.execute(select(JOBS.c.id).where(_owned_by(job_id, worker_id))).first()
    if owned is None:
        raise LeaseLostError(f"worker {worker_id!r} does not hold the lease of job {job_id}")


def record_generation(
    session: Session,
    job_id: str,
    worker_id: str,
    *,
    generation: int,
    n_evals: int,
    best: Any,
    wall_time_s: float,
    hypervolume: float | None = None,
    front: Any = None,
    now: datetime | None = None,
) -> bool:
    """Record one generation and advance the job's progress; idempotent per generation.

    ``front`` (optional, (k, m) array-like) is the objective vectors of the current front, kept
    (as float64 bytes) for the recording's per-generation Pareto view.

    ``best`` is the best objective(s) so far (a number or a list, JSON); it also becomes the
    job's ``best_objective`` unless a later generation was already recorded. A generation that
    already has a row (a resumed job re-running it) is ignored: returns False; True when a row
    was written. Raises LeaseLostError (writing nothing) if ``worker_id`` lost the lease.
    """
    now = now_utc(now)
    generation = int(generation)
    advance = (
        update(JOBS)
        .where(_owned_by(job_id, worker_id), JOBS.c.progress_generation <= generation)
        .values(
            progress_generation=generation,
            best_objective=best,
            best_value=first_objective(best),
        )
    )
    if rowcount(session.execute(advance)) == 0:
        _check_owner(session, job_id, worker_id)  # owner, but a later generation is recorded
    row = GenerationIn(generation, n_evals, best, wall_time_s, hypervolume, front)
    return insert_ignoring_duplicates(
        session, GENERATIONS, _generation_row(job_id, row, now), ("job_id", "generation")
    )


def _generation_row(job_id: str, g: GenerationIn, now: datetime) -> dict[str, Any]:
    return {
        "job_id": job_id,
        "generation": int(g.generation),
        "n_evals": int(g.n_evals),
        "best": g.best,
        "hypervolume": _finite_or_none(g.hypervolume),
        "wall_time_s": float(g.wall_time_s),
        "created_at": now,
        "front_packed": encode_front(g.front),
    }


def record_generations(
    session: Session,
    job_id: str,
    worker_id: str,
    rows: Sequence[GenerationIn],
    *,
    now: datetime | None = None,
) -> bool:
    """Record a batch of generations at once (``record_generation`` for many rows: one UPDATE
    of the job's progress, one multi-row INSERT); returns the job's ``cancel_requested``, read
    by the same UPDATE, so a worker needs no query of its own to notice a cancellation.

    Generations already recorded (a resumed job re-running them) are skipped. Raises
    LeaseLostError, writing nothing, if ``worker_id`` lost the lease.
    """
    now = now_utc(now)
    owned = _owned_by(job_id, worker_id)
    flag = None
    if rows:
        last = max(rows, key=lambda g: int(g.generation))
        advance = (
            update(JOBS)
            .where(owned, JOBS.c.progress_generation <= int(last.generation))
            .values(
                progress_generation=int(last.generation),
                best_objective=last.best,
                best_value=first_objective(last.best),
            )
            .returning(JOBS.c.cancel_requested)
        )
        flag = session.execute(advance).first()
    if flag is None:  # nothing to advance, or a later generation is recorded: is it still ours?
        flag = session.execute(select(JOBS.c.cancel_requested).where(owned)).first()
        if flag is None:
            raise LeaseLostError(f"worker {worker_id!r} does not hold the lease of job {job_id}")
    values = [_generation_row(job_id, g, now) for g in rows]
    insert_many_ignoring_duplicates(session, GENERATIONS, values, ("job_id", "generation"))
    return bool(flag[0])


def save_checkpoint(
    session: Session,
    job_id: str,
    worker_id: str,
    *,
    generation: int,
    state: bytes,
    now: datetime | None = None,
) -> None:
    """Store the optimiser state after ``generation``, replacing an older checkpoint.

    One checkpoint per job is kept (the latest); a checkpoint older than the stored one is
    ignored. ``state`` is opaque bytes (the worker chooses the encoding).
    Raises LeaseLostError (writing nothing) if ``worker_id`` lost the lease.
    """
    now = now_utc(now)
    generation = int(generation)
    _require_owner(session, job_id, worker_id, {"heartbeat_at": now})
    replaced = session.execute(
        update(CHECKPOINTS)
        .where(CHECKPOINTS.c.job_id == job_id, CHECKPOINTS.c.generation <= generation)
        .values(generation=generation, state=bytes(state), created_at=now)
    )
    if rowcount(replaced) == 0:
        insert_ignoring_duplicates(
            session,
            CHECKPOINTS,
            {"job_id": job_id, "generation": generation, "state": bytes(state), "created_at": now},
            ("job_id",),
        )


def latest_checkpoint(session: Session, job_id: str) -> CheckpointRecord | None:
    """The job's latest checkpoint, or None (start from scratch)."""
    stmt = select(CHECKPOINTS).where(CHECKPOINTS.c.job_id == job_id)
    return fetch_one(session, CheckpointRecord, stmt)
