"""The metrics of every point of a job's front (the front table's and export's columns),
decoded on demand by the API together, once — one problem built, then milliseconds per point —
and kept as the job's artifact ``front-metrics`` (JSON), on the point thread of
:mod:`services.api.points` (same bounds: one piece of work at a time, 503 + Retry-After past
``WAIT_S``). A cached file whose file or object is gone or corrupted is made again; an
artifact store that cannot be reached leaves the metrics ``unavailable``."""

from __future__ import annotations

import json
from typing import Any

import numpy as np
from fastapi import HTTPException, status

from services.api.deps import ApiContext
from services.api.points import attempt_dir, point_conflict, run_point_work
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.errors import ArtifactError, ArtifactMissingError, ChecksumMismatchError
from services.store.records import ArtifactRecord, JobRecord
from services.store.states import JobStatus

__all__ = ["FRONT_METRICS", "front_metrics", "point_metrics"]

FRONT_METRICS = "front-metrics"


def _metric_values(metrics: Any) -> dict[str, float | None]:
    """A solution's numeric metrics (flags as 0/1), non-finite values as None."""
    out: dict[str, float | None] = {}
    for k, v in (metrics or {}).items():
        if isinstance(v, int | float):
            f = float(v)
            out[str(k)] = f if np.isfinite(f) else None
    return out


def _read_front_metrics(
    ctx: ApiContext, art: ArtifactRecord | None
) -> dict[int, dict[str, Any] | None] | None:
    """The stored front metrics; None when there are none, or their file or object is gone
    or corrupted (its row is then removed: they are made again)."""
    if art is None:
        return None
    try:
        doc = json.loads(ctx.artifacts.read(art.relative_path, art.sha256))
    except (ArtifactMissingError, ChecksumMismatchError):
        with ctx.write() as session:
            oq.forget_artifact(session, art.job_id, art.kind, art.sha256)
        return None
    return {int(k): v for k, v in (doc.get("points") or {}).items()}


def front_metrics(ctx: ApiContext, job: JobRecord) -> dict[int, dict[str, Any] | None]:
    """``{point index: its metrics}`` of every point of a succeeded job's front (None for a
    point that cannot be decoded), decoded from the points' stored decision vectors the first
    time (one problem built, then milliseconds per point) and kept as the job's artifact
    ``front-metrics`` (JSON). 409 when the job's spec cannot be prepared again, 503 while
    they are being computed (longer than ``WAIT_S``)."""
    with ctx.read() as session:
        existing = oq.get_artifact(session, job.id, FRONT_METRICS)
    stored = _read_front_metrics(ctx, existing)
    if stored is not None:
        return stored

    def make() -> dict[int, dict[str, Any] | None]:
        from services.recording.point import PointError, decode_point, prepare_cached

        with ctx.read() as session:
            done = oq.get_artifact(session, job.id, FRONT_METRICS)
        again = _read_front_metrics(ctx, done)
        if again is not None:
            return again
        with ctx.read() as session:
            spec = repo.job_spec(session, job)
            points = oq.list_pareto(session, job.id)
        if not points:
            return {}
        try:
            prepare_cached(spec)
        except ValueError as exc:
            raise point_conflict(
                PointError(f"the job's spec cannot be prepared again: {exc}")
            ) from None
        values: dict[int, dict[str, Any] | None] = {}
        for p in points:
            try:
                values[p.index] = _metric_values(decode_point(spec, p.x or []).solution.metrics)
            except PointError:
                values[p.index] = None
        doc = {"points": {str(k): v for k, v in values.items()}}
        data = json.dumps(doc, allow_nan=False, separators=(",", ":")).encode()
        stored = ctx.artifacts.put(
            job.id, FRONT_METRICS, data, suffix=".json", attempt=attempt_dir(ctx, job.id)
        )
        with ctx.write() as session:  # a concurrent copy (another API process) is identical
            oq.add_artifact(session, job.id, FRONT_METRICS, *stored)
        return values

    return run_point_work((job.id, FRONT_METRICS), make)


def point_metrics(
    ctx: ApiContext, job: JobRecord, any_points: bool
) -> tuple[dict[int, dict[str, Any] | None], str, str | None]:
    """``(metrics by point index, state, note)`` of a job's front (``FrontOut.point_metrics``):
    computed once and cached (:func:`front_metrics`); pending when that takes
    longer than a request waits, unavailable when the spec cannot be decoded again."""
    if not any_points or job.status is not JobStatus.SUCCEEDED:
        return {}, "ready", None
    try:
        return front_metrics(ctx, job), "ready", None
    except ArtifactError as exc:  # the store cannot be reached: the rest of the page can
        return {}, "unavailable", f"the points' metrics cannot be read now: {exc}"
    except HTTPException as exc:
        if exc.status_code == status.HTTP_503_SERVICE_UNAVAILABLE:
            return {}, "pending", "the points' metrics are being computed: ask again shortly"
        if exc.status_code == status.HTTP_409_CONFLICT:
            return {}, "unavailable", str(exc.detail)
        raise
