"""Reads and writes of a job's outputs: its generations, result, front, baselines and
artifacts as the worker stored them (``list_generations``, ``get_result``, …), and what the
dashboard and the worker add to the store: the final hypervolume of jobs, points of a front,
fronts of several jobs, artifacts made after a job finished (a front point's recording), the
reference point of a job's hypervolumes, and the per-objective minimum of a job's stored fronts
(its convergence view).

Like ``services.store.repository``: every function takes the ``Session`` first and never
commits.
"""

from __future__ import annotations

import copy
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from sqlalchemy import and_, delete, func, or_, select, update
from sqlalchemy.orm import Session

from services.store.front_codec import decode_front, decode_front_array
from services.store.records import (
    ArtifactRecord,
    BaselineRecord,
    GenerationRecord,
    ParetoPointRecord,
    ResultRecord,
)
from services.store.sql import (
    MAX_PAGE_SIZE,
    check_page,
    fetch_all,
    fetch_one,
    insert_ignoring_duplicates,
    now_utc,
    to_record,
)
from services.store.states import JobStatus
from services.store.tables import ARTIFACTS, BASELINES, GENERATIONS, JOBS, PARETO_POINTS, RESULTS


def list_generations(
    session: Session, job_id: str, *, after: int | None = None, limit: int = MAX_PAGE_SIZE
) -> tuple[GenerationRecord, ...]:
    """Generation rows of a job in order; ``after`` returns only later generations (polling)."""
    check_page(limit, 0)
    stmt = select(GENERATIONS).where(GENERATIONS.c.job_id == job_id)
    if after is not None:
        stmt = stmt.where(GENERATIONS.c.generation > after)
    stmt = stmt.order_by(GENERATIONS.c.generation).limit(limit)
    records = []
    for row in session.execute(stmt).mappings():
        packed = row["front_packed"]
        values = dict(row) if packed is None else {**row, "front": decode_front(packed)}
        records.append(to_record(GenerationRecord, values))
    return tuple(records)


def get_result(session: Session, job_id: str) -> ResultRecord | None:
    """The final result of a job, or None until it has succeeded."""
    return fetch_one(session, ResultRecord, select(RESULTS).where(RESULTS.c.job_id == job_id))


def result_briefs(session: Session, job_ids: Iterable[str]) -> dict[str, tuple[Any, Any]]:
    """``{job_id: (objectives, metrics)}`` of the given jobs' results in one query (jobs without
    a result are absent) — the sweep table's columns, without the summaries."""
    ids = list(job_ids)
    if not ids:
        return {}
    stmt = select(RESULTS.c.job_id, RESULTS.c.objectives, RESULTS.c.metrics).where(
        RESULTS.c.job_id.in_(ids)
    )
    return {
        r.job_id: (copy.deepcopy(r.objectives), copy.deepcopy(r.metrics))
        for r in session.execute(stmt)
    }


def get_result_objectives(session: Session, job_id: str) -> Any:
    """Only the ``objectives`` JSON of a job's result (None until it has succeeded) — without
    the (possibly large) summary, for the front and sweep views."""
    row = session.execute(select(RESULTS.c.objectives).where(RESULTS.c.job_id == job_id)).first()
    return None if row is None else copy.deepcopy(row[0])


def list_pareto(session: Session, job_id: str) -> tuple[ParetoPointRecord, ...]:
    """The final Pareto front of a job, by index (empty until it has succeeded)."""
    stmt = (
        select(PARETO_POINTS)
        .where(PARETO_POINTS.c.job_id == job_id)
        .order_by(PARETO_POINTS.c.index)
    )
    return fetch_all(session, ParetoPointRecord, stmt)


def list_baselines(session: Session, job_id: str) -> tuple[BaselineRecord, ...]:
    """Baselines stored with a job's result, by name."""
    stmt = select(BASELINES).where(BASELINES.c.job_id == job_id).order_by(BASELINES.c.name)
    return fetch_all(session, BaselineRecord, stmt)


def list_artifacts(session: Session, job_id: str) -> tuple[ArtifactRecord, ...]:
    """Artifacts of a job, by kind."""
    stmt = select(ARTIFACTS).where(ARTIFACTS.c.job_id == job_id).order_by(ARTIFACTS.c.kind)
    return fetch_all(session, ArtifactRecord, stmt)


def get_artifact(session: Session, job_id: str, kind: str) -> ArtifactRecord | None:
    """The artifact of ``kind`` (e.g. ``"recording"``) of a job, or None."""
    stmt = select(ARTIFACTS).where(ARTIFACTS.c.job_id == job_id, ARTIFACTS.c.kind == kind)
    return fetch_one(session, ArtifactRecord, stmt)


def final_hypervolumes(session: Session, job_ids: Sequence[str]) -> dict[str, float]:
    """``{job_id: hypervolume of its last generation that has one}`` (jobs without one are
    absent). Each is measured against its job's own reference point."""
    ids = list(job_ids)
    if not ids:
        return {}
    last = (
        select(GENERATIONS.c.job_id, func.max(GENERATIONS.c.generation).label("g"))
        .where(GENERATIONS.c.job_id.in_(ids), GENERATIONS.c.hypervolume.is_not(None))
        .group_by(GENERATIONS.c.job_id)
        .subquery()
    )
    stmt = select(GENERATIONS.c.job_id, GENERATIONS.c.hypervolume).join(
        last, and_(GENERATIONS.c.job_id == last.c.job_id, GENERATIONS.c.generation == last.c.g)
    )
    return {r[0]: float(r[1]) for r in session.execute(stmt)}


def get_pareto_point(session: Session, job_id: str, index: int) -> ParetoPointRecord | None:
    """Point ``index`` of a job's final front, or None."""
    stmt = select(PARETO_POINTS).where(
        PARETO_POINTS.c.job_id == job_id, PARETO_POINTS.c.index == index
    )
    return fetch_one(session, ParetoPointRecord, stmt)


def fronts_of(session: Session, job_ids: Iterable[str]) -> dict[str, list[ParetoPointRecord]]:
    """The final fronts of several jobs in one query, by index."""
    ids = list(job_ids)
    out: dict[str, list[ParetoPointRecord]] = {i: [] for i in ids}
    if not ids:
        return out
    stmt = (
        select(PARETO_POINTS)
        .where(PARETO_POINTS.c.job_id.in_(ids))
        .order_by(PARETO_POINTS.c.job_id, PARETO_POINTS.c.index)
    )
    for p in fetch_all(session, ParetoPointRecord, stmt):
        out[p.job_id].append(p)
    return out


def add_artifact(
    session: Session, job_id: str, kind: str, relative_path: str, sha256: str, size_bytes: int
) -> bool:
    """Record a file made after the job finished (a point's recording); False if an artifact
    of this kind already exists (made by a concurrent request: keep the first)."""

    return insert_ignoring_duplicates(
        session,
        ARTIFACTS,
        {
            "job_id": job_id,
            "kind": kind,
            "relative_path": relative_path,
            "sha256": sha256,
            "size_bytes": int(size_bytes),
            "created_at": now_utc(),
        },
        ["job_id", "kind"],
    )


def forget_artifact(session: Session, job_id: str, kind: str, sha256: str) -> bool:
    """Remove the row of a file made after the job finished whose file or object is gone (it
    is then made again on demand); only the row with this ``sha256`` (not a remade one)."""
    done = session.execute(
        delete(ARTIFACTS).where(
            ARTIFACTS.c.job_id == job_id, ARTIFACTS.c.kind == kind, ARTIFACTS.c.sha256 == sha256
        )
    )
    return bool(getattr(done, "rowcount", 0))


# --------------------------------------------------------------------------- convergence


def front_minimum(front: Any) -> np.ndarray | None:
    """Per-objective minimum of a stored front ((k, m) rows, ``None``/NaN where not finite),
    NaN for an objective without a finite value; None without a front."""
    if front is None:
        return None
    F = front if isinstance(front, np.ndarray) else np.asarray(front, dtype=float)
    if F.ndim != 2 or F.size == 0:
        return None
    F = np.where(np.isfinite(F), F, np.inf)
    low = F.min(axis=0)
    return np.where(np.isfinite(low), low, np.nan)


def fold_minimum(best: np.ndarray | None, low: np.ndarray | None) -> np.ndarray | None:
    """The running per-objective minimum ``best`` updated with a front's minimum ``low``
    (NaN-ignoring; a front of another width starts it again)."""
    if low is None:
        return best
    if best is None or best.shape != low.shape:
        return low
    return np.fmin(best, low)


def best_front_minimum(session: Session, job_id: str, *, upto: int) -> np.ndarray | None:
    """Per-objective minimum over the stored fronts of generations ``<= upto`` (NaN for an
    objective without a finite value), or None when none of them has a front — what the
    convergence view continues from when a page starts after ``upto``. Reads the fronts'
    bytes without building Python lists."""
    stmt = select(GENERATIONS.c.front_packed, GENERATIONS.c.front).where(
        GENERATIONS.c.job_id == job_id,
        GENERATIONS.c.generation <= upto,
        or_(GENERATIONS.c.front_packed.is_not(None), GENERATIONS.c.front.is_not(None)),
    )
    best: np.ndarray | None = None
    for packed, legacy in session.execute(stmt):
        best = fold_minimum(
            best, front_minimum(decode_front_array(packed) if packed is not None else legacy)
        )
    return best


# --------------------------------------------------------------------------- hypervolume


def get_hypervolume_ref(session: Session, job_id: str) -> list[float] | None:
    """The reference point of a job's per-generation hypervolumes, or None (not set yet, or a
    single-objective job)."""
    value = session.execute(
        select(JOBS.c.hypervolume_ref).where(JOBS.c.id == job_id)
    ).scalar_one_or_none()
    return None if value is None else [float(v) for v in value]


def set_hypervolume_ref(
    session: Session, job_id: str, worker_id: str, ref: Sequence[float]
) -> bool:
    """Record a running job's hypervolume reference point once (only its lease holder, only
    while none is set); True if written."""
    stmt = (
        update(JOBS)
        .where(
            JOBS.c.id == job_id,
            JOBS.c.status == JobStatus.RUNNING,
            JOBS.c.lease_owner == worker_id,
            JOBS.c.hypervolume_ref.is_(None),
        )
        .values(hypervolume_ref=[float(v) for v in ref])
    )
    return int(session.execute(stmt).rowcount) > 0  # type: ignore[attr-defined]


__all__ = [
    "add_artifact",
    "best_front_minimum",
    "final_hypervolumes",
    "fold_minimum",
    "forget_artifact",
    "front_minimum",
    "fronts_of",
    "get_artifact",
    "get_hypervolume_ref",
    "get_pareto_point",
    "get_result",
    "get_result_objectives",
    "list_artifacts",
    "list_baselines",
    "list_generations",
    "list_pareto",
    "result_briefs",
    "set_hypervolume_ref",
]
