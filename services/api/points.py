"""Front points made on demand by the API: a point's decoded motion and its Rerun recording,
and a baseline's recording (the metrics of a front's points: :mod:`services.api.front_metrics`).

Where the work runs — the API, in-process, not a worker: decoding one point is one trajectory
evaluation of a problem whose size was checked at submission (``LEGOPT_MAX_*``), and its
recording is capped by the writer's size budget, so it takes well under a second once the
problem is built (seconds for the first point of a spec, which builds the problem and may
compile numba kernels). A worker would add a queue round trip to every click and compete with
optimisations for the job slots.

Bounds: ONE point is made at a time per API process (a single-thread executor); a request
waits for its point at most ``WAIT_S`` seconds and then gets 503 with ``Retry-After`` while the
work finishes in the background — its result is kept, so the retry is served from the cache.
Two requests for the same point share one piece of work. Recordings are cached in the
artifact store as the job's artifact ``point-<k>`` (``.rrd``, SHA-256 recorded), inside the
directory of the attempt whose result they decode, so they are deleted with the job and count
against the key's storage quota; motions are kept in a small in-process LRU. A baseline's
recording is kept the same way as ``baseline-<i>`` (its position among the job's baselines by
name). The metrics of a front's points (the front table's and export's columns) are decoded
together, once — one problem built, then milliseconds per point (about 2 ms for seed 002, 10
ms for seed 004 on the development machine) — and kept as the artifact ``front-metrics``
(JSON). A cached file whose file or object is gone (or corrupted, for the metrics) is made
again; an artifact store that cannot be reached leaves the metrics ``unavailable``.
"""

from __future__ import annotations

import tempfile
import threading
from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from fastapi import HTTPException, status

from services.api.bounded_work import BoundedWork
from services.api.deps import ApiContext
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.records import ArtifactRecord, JobRecord
from services.store.states import JobStatus

T = TypeVar("T")

#: Longest a request waits for a point being made before it gets 503 + Retry-After (s).
WAIT_S = 30.0
#: Decoded motions kept per process.
MOTION_CACHE_SIZE = 64
#: Generations whose fronts a point recording replays (the most recent ones beyond this).
MAX_FRONT_GENERATIONS = 2000

_work = BoundedWork("legopt-point", workers=1, wait_s=WAIT_S)
_motions: OrderedDict[tuple[str, str], dict[str, Any]] = OrderedDict()
_lock = threading.Lock()


def point_kind(k: int) -> str:
    """The artifact kind of front point ``k``'s recording."""
    return f"point-{k}"


def run_point_work(key: tuple[str, str], work: Callable[[], T]) -> T:
    """Run ``work`` on the process's point thread (shared by identical concurrent requests);
    503 with Retry-After when it takes longer than ``WAIT_S``."""
    return _work.run(key, work, f"{key[1]} of job {key[0]}")


def point_conflict(exc: Exception) -> HTTPException:
    return HTTPException(status.HTTP_409_CONFLICT, str(exc))


def attempt_dir(ctx: ApiContext, job_id: str) -> str | None:
    """The attempt directory of the job's stored result (``<job>/<attempt>/result.json``)."""
    with ctx.read() as session:
        art = oq.get_artifact(session, job_id, "result")
    if art is None:
        return None
    parts = art.relative_path.split("/")
    return parts[1] if len(parts) == 3 else None


def _still_stored(ctx: ApiContext, record: ArtifactRecord | None) -> ArtifactRecord | None:
    """``record`` (a file made on demand) while its file or object is stored; None — its row
    removed, so that it is made again — when it is gone."""
    if record is None or ctx.artifacts.exists(record.relative_path):
        return record
    with ctx.write() as session:
        oq.forget_artifact(session, record.job_id, record.kind, record.sha256)
    return None


def _fronts(ctx: ApiContext, job_id: str) -> dict[int, Any] | None:
    """{generation: F} of the job's stored per-generation fronts (the latest ones)."""
    fronts: dict[int, Any] = {}
    after: int | None = None
    with ctx.read() as session:
        while len(fronts) < MAX_FRONT_GENERATIONS:
            rows = oq.list_generations(session, job_id, after=after, limit=1000)
            for g in rows:
                if g.front:
                    fronts[g.generation] = np.asarray(g.front, dtype=float)
            if len(rows) < 1000:
                break
            after = rows[-1].generation
    return fronts or None


def point_recording(ctx: ApiContext, job: JobRecord, k: int) -> ArtifactRecord:
    """The stored recording of front point ``k`` of a succeeded job, made first if needed.
    404 for no such point, 409 when the point cannot be decoded, 503 while it is being made."""
    kind = point_kind(k)
    with ctx.read() as session:
        existing = oq.get_artifact(session, job.id, kind)
        point = oq.get_pareto_point(session, job.id, k)
    existing = _still_stored(ctx, existing)
    if existing is not None:
        return existing
    if point is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"job {job.id} has no front point {k}")
    x = list(point.x or [])

    def decode(spec: Any) -> Any:
        from services.recording.point import decode_point

        return decode_point(spec, x)

    return _solution_recording(ctx, job, kind, f"front point {k}", decode)


def trial_kind(t: int) -> str:
    """The artifact kind of trial ``t``'s recording."""
    return f"trial-{int(t)}"


def trial_x(ctx: ApiContext, job: JobRecord, t: int) -> list[float]:
    """The decision vector of the job's stored trial ``t``; 404 when there is no such trial."""
    from services.store.evaluations import load_evaluations

    with ctx.read() as session:
        ev = load_evaluations(session, job.id)
    if ev is None or not 0 <= t < len(ev):
        stored = 0 if ev is None else len(ev)
        raise HTTPException(
            status.HTTP_404_NOT_FOUND, f"job {job.id} has no trial {t} ({stored} stored)"
        )
    return [float(v) for v in ev.X[t]]


def trial_recording(ctx: ApiContext, job: JobRecord, t: int) -> ArtifactRecord:
    """The stored recording of trial ``t`` (any evaluated solution) of a succeeded job, made
    first if needed; 404 for no such trial, 409 when it cannot be decoded, 503 while made."""
    if job.status is not JobStatus.SUCCEEDED:
        raise HTTPException(
            status.HTTP_409_CONFLICT,
            f"job {job.id} is {job.status.value}: a trial's recording exists once it succeeded",
        )
    kind = trial_kind(t)
    with ctx.read() as session:
        existing = oq.get_artifact(session, job.id, kind)
    existing = _still_stored(ctx, existing)
    if existing is not None:
        return existing
    x = trial_x(ctx, job, t)

    def decode(spec: Any) -> Any:
        from services.recording.point import decode_point

        return decode_point(spec, x)

    return _solution_recording(ctx, job, kind, f"trial {t}", decode)


def baseline_kind(names: list[str], name: str) -> str:
    """The artifact kind of the recording of baseline ``name`` among the job's baselines
    ``names`` (by its position in their sorted order: a name need not be a safe file name)."""
    return f"baseline-{sorted(names).index(name)}"


def baseline_recording(ctx: ApiContext, job: JobRecord, name: str) -> ArtifactRecord:
    """The stored recording of the job's baseline ``name`` (the job's recording with that
    baseline as its motion), made first if needed; 404 for no such baseline, 409 when it
    cannot be decoded again, 503 while it is being made."""
    with ctx.read() as session:
        names = [b.name for b in oq.list_baselines(session, job.id)]
    if name not in names:
        known = ", ".join(sorted(names)) or "none"
        raise HTTPException(
            status.HTTP_404_NOT_FOUND, f"job {job.id} has no baseline {name!r} (baselines: {known})"
        )
    kind = baseline_kind(names, name)
    with ctx.read() as session:
        existing = oq.get_artifact(session, job.id, kind)
    existing = _still_stored(ctx, existing)
    if existing is not None:
        return existing

    def decode(spec: Any) -> Any:
        from services.recording.point import decode_baseline

        return decode_baseline(spec, name)

    return _solution_recording(ctx, job, kind, f"baseline {name}", decode)


def _solution_recording(
    ctx: ApiContext, job: JobRecord, kind: str, what: str, decode: Callable[[Any], Any]
) -> ArtifactRecord:
    """Make (once, on the point thread) and store as artifact ``kind`` the recording of the
    solution ``decode(spec)`` of a succeeded job, titled ``what``."""

    def make() -> ArtifactRecord:
        from services.recording.point import PointError, write_point_recording

        with ctx.read() as session:
            done = oq.get_artifact(session, job.id, kind)
            if done is not None:
                return done
            spec = repo.job_spec(session, job)
            result = oq.get_result(session, job.id)
            points = oq.list_pareto(session, job.id)
        summary = result.summary if result is not None and isinstance(result.summary, dict) else {}
        try:
            decoded = decode(spec)
        except PointError as exc:
            raise point_conflict(exc) from None
        store = ctx.artifacts
        attempt = attempt_dir(ctx, job.id)
        with tempfile.TemporaryDirectory(prefix="legopt-point-") as tmp:
            path = Path(tmp) / f"{kind}.rrd"
            write_point_recording(
                decoded,
                path,
                title=f"{(spec or {}).get('name') or job.id[:8]}: {what}",
                recording_id=f"{job.id}-{kind}",
                pareto=[{"x": p.x, "objectives": p.objectives} for p in points],
                history=list(summary.get("history") or []),
                fronts=_fronts(ctx, job.id),
            )
            stored = store.put(job.id, kind, path, attempt=attempt)
        with ctx.write() as session:
            oq.add_artifact(session, job.id, kind, *stored)
            record = oq.get_artifact(session, job.id, kind)
        assert record is not None
        return record

    return run_point_work((job.id, kind), make)


def point_motion(
    ctx: ApiContext,
    job: JobRecord,
    *,
    point: int | None,
    baseline: str | None,
    trial: int | None = None,
) -> dict[str, Any]:
    """The decoded solution (front point, baseline, stored trial, or the reported best when
    none) of a succeeded job: its objectives, metrics and joint signals (``MotionOut``)."""
    source = (
        "point" if point is not None
        else "baseline" if baseline is not None
        else "trial" if trial is not None
        else "best"
    )  # fmt: skip
    index = point if point is not None else trial
    ident = f"motion:{source}:{index if index is not None else baseline or ''}"
    key = (job.id, ident)
    with _lock:
        cached = _motions.get(key)
        if cached is not None:
            _motions.move_to_end(key)
            return cached
    with ctx.read() as session:
        spec = repo.job_spec(session, job)
        result = oq.get_result(session, job.id)
        stored = oq.get_pareto_point(session, job.id, point) if point is not None else None
    if result is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"job {job.id} has no result yet")
    if point is not None and stored is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"job {job.id} has no front point {point}")
    trial_vector = trial_x(ctx, job, trial) if trial is not None else None

    def make() -> dict[str, Any]:
        from services.recording.point import (
            PointError,
            decode_baseline,
            decode_point,
            motion_payload,
        )

        try:
            if baseline is not None:
                decoded = decode_baseline(spec, baseline)
            else:
                x = stored.x if stored is not None else trial_vector or result.best_x
                decoded = decode_point(spec, x or [])
        except PointError as exc:
            raise point_conflict(exc) from None
        sol = decoded.solution
        return {
            "job_id": job.id,
            "source": source,
            "index": index,
            "name": baseline,
            "x": None if sol.x is None else [float(v) for v in sol.x],
            "objectives": {k: float(v) for k, v in sol.objectives.items()},
            "metrics": {
                k: float(v)
                for k, v in sol.metrics.items()
                if isinstance(v, int | float) and np.isfinite(v)
            },
            **motion_payload(sol.motion),
        }

    payload = run_point_work(key, make)
    with _lock:
        _motions[key] = payload
        while len(_motions) > MOTION_CACHE_SIZE:
            _motions.popitem(last=False)
    return payload


__all__ = [
    "WAIT_S",
    "attempt_dir",
    "baseline_kind",
    "baseline_recording",
    "point_conflict",
    "point_kind",
    "point_motion",
    "point_recording",
    "run_point_work",
]
