"""The metrics of every point of a job's front (the front table's and export's columns),
decoded on demand by the API together, once — one problem built, then milliseconds per point —
and kept as the job's artifact ``front-metrics`` (:mod:`services.api.cached_json`: made on the
point thread, made again when its file is gone or corrupted); an artifact store that cannot be
reached leaves the metrics ``unavailable``."""

from __future__ import annotations

from typing import Any

import numpy as np
from fastapi import HTTPException, status

from services.api.cached_json import cached_json
from services.api.deps import ApiContext
from services.api.points import point_conflict
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.errors import ArtifactError
from services.store.records import JobRecord
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


def front_metrics(ctx: ApiContext, job: JobRecord) -> dict[int, dict[str, Any] | None]:
    """``{point index: its metrics}`` of every point of a succeeded job's front (None for a
    point that cannot be decoded), decoded from the points' stored decision vectors the first
    time (one problem built, then milliseconds per point) and kept as the job's artifact
    ``front-metrics`` (JSON: :func:`services.api.cached_json.cached_json`). 409 when the job's
    spec cannot be prepared again, 503 while they are being computed (longer than
    ``WAIT_S``)."""

    def make() -> dict[str, Any]:
        from services.recording.point import PointError, decode_point, prepare_cached

        with ctx.read() as session:
            spec = repo.job_spec(session, job)
            points = oq.list_pareto(session, job.id)
        if not points:
            return {"points": {}}
        try:
            prepare_cached(spec)
        except ValueError as exc:
            raise point_conflict(
                PointError(f"the job's spec cannot be prepared again: {exc}")
            ) from None
        values: dict[str, dict[str, Any] | None] = {}
        for p in points:
            try:
                values[str(p.index)] = _metric_values(
                    decode_point(spec, p.x or []).solution.metrics
                )
            except PointError:
                values[str(p.index)] = None
        return {"points": values}

    doc = cached_json(ctx, job.id, FRONT_METRICS, make)
    return {int(k): v for k, v in (doc.get("points") or {}).items()}


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
