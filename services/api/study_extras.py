"""A job's study extras (``StudyProblem.extras`` of its final front: a hexapod's workspaces and
masks, a path's limits, … — up to ~0.5 MB), made by the API the first time they are asked for
instead of by the worker at the end of every job (issue 23: a job costs what its evaluation
costs).

Where they come from, in order: the job's artifact ``extras`` (made before, by
:func:`services.api.cached_json.cached_json`); the ``extras`` of its ``result.json`` (jobs that
finished before the worker stopped writing them); else made now from the job's spec and its
stored front (one problem built — :func:`services.recording.point.prepare_cached` — then the
study's extras; ~15 ms for seed 002's 300 points once built) and kept as the artifact
``extras``. The stored front's decision vectors are the worker's to the last bit (JSON floats
round-trip), so the extras are the ones the worker would have made."""

from __future__ import annotations

import json
import logging
from typing import Any

import numpy as np
from fastapi import HTTPException, status

from services.api.cached_json import cached_json
from services.api.deps import ApiContext
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.errors import ArtifactError, ArtifactMissingError, ChecksumMismatchError
from services.store.records import ArtifactRecord, JobRecord
from services.store.types import json_safe

__all__ = ["EXTRAS", "study_extras"]

log = logging.getLogger(__name__)

#: The artifact kind of the extras made on demand.
EXTRAS = "extras"


def _from_result_json(ctx: ApiContext, art: ArtifactRecord | None) -> dict[str, Any] | None:
    """The extras a job's ``result.json`` holds (jobs of older workers); None when it holds
    none or is gone. Raises ``ArtifactError`` when the store cannot be reached."""
    if art is None:
        return None
    try:
        doc = json.loads(ctx.artifacts.read(art.relative_path, art.sha256))
    except (ArtifactMissingError, ChecksumMismatchError):
        return None  # made again from the database's spec and front
    extras = doc.get("extras") if isinstance(doc, dict) else None
    return extras if isinstance(extras, dict) else None


def _make(ctx: ApiContext, job: JobRecord) -> dict[str, Any]:
    """The extras of the job's stored front (409 when its spec cannot be prepared again)."""
    from services.recording.point import prepare_cached

    with ctx.read() as session:
        spec = repo.job_spec(session, job)
        points = oq.list_pareto(session, job.id)
    try:
        problem = prepare_cached(spec).problem
    except ValueError as exc:
        raise HTTPException(
            status.HTTP_409_CONFLICT, f"the job's spec cannot be prepared again: {exc}"
        ) from None
    shape_X, shape_F = (len(points), int(problem.n_var)), (len(points), int(problem.n_obj))
    try:
        front_X = np.asarray([p.x for p in points], dtype=float).reshape(shape_X)
        front_F = np.asarray([p.objectives for p in points], dtype=float).reshape(shape_F)
    except (TypeError, ValueError):
        raise HTTPException(
            status.HTTP_409_CONFLICT,
            f"the job's stored front does not fit its problem ({shape_X[1]} variables, "
            f"{shape_F[1]} objectives)",
        ) from None
    try:
        extras = problem.extras(front_X, front_F)
    except Exception as exc:  # a study's (a plug-in's) own code: never a 500 of the API
        log.exception("study extras of job %s failed", job.id)
        raise HTTPException(
            status.HTTP_409_CONFLICT, f"the study's extras failed: {type(exc).__name__}: {exc}"
        ) from None
    return {"extras": json_safe(extras)}


def study_extras(
    ctx: ApiContext, job: JobRecord, artifacts: tuple[ArtifactRecord, ...]
) -> tuple[dict[str, Any], str | None]:
    """``(extras, warning)`` of a succeeded job: ``{}`` with a warning saying why when they
    cannot be had now (the artifact store cannot be reached, the spec cannot be prepared
    again, they are still being made after a request's wait — ask again)."""
    result_art = next((a for a in artifacts if a.kind == "result"), None)
    try:
        if not any(a.kind == EXTRAS for a in artifacts):
            old = _from_result_json(ctx, result_art)
            if old is not None:
                return old, None
        doc = cached_json(ctx, job.id, EXTRAS, lambda: _make(ctx, job))
    except ArtifactError as exc:
        where = result_art.relative_path if result_art is not None else "the artifact store"
        log.warning("study extras of %s unavailable: %s", job.id, exc)
        return {}, f"the study's extras (from {where}) are unavailable: {exc}"
    except HTTPException as exc:
        if exc.status_code == status.HTTP_503_SERVICE_UNAVAILABLE:
            return {}, "the study's extras are being made: ask again shortly"
        return {}, f"the study's extras cannot be made: {exc.detail}"
    extras = doc.get("extras")
    return (extras if isinstance(extras, dict) else {}), None
