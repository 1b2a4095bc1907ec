"""Every evaluated solution of a job: the trial table (filter, sort, page), the columns of a
parallel-coordinates plot, and a trial's Rerun recording. Stored while the job runs
(``services.store.evaluations``), so a running job's trials grow page by page."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query
from fastapi.concurrency import run_in_threadpool
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse

from services.api.artifact_download import artifact_response
from services.api.deps import ApiContext, Context, CurrentKey, Pagination
from services.api.errors import invalid
from services.api.lookups import OwnedJob, owned_job, path_index
from services.api.points import trial_recording
from services.api.schemas import ErrorOut
from services.api.trial_schemas import ImportanceOut, TrialColumns, TrialPage
from services.api.trial_view import (
    TrialQueryError,
    TrialSet,
    matching,
    trial_columns,
    trial_page,
    trial_set,
)
from services.lru import BuiltCache
from services.store.evaluations import load_evaluations
from services.store.records import JobRecord

router = APIRouter(tags=["dashboard"])

_404: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "No such job (among yours), or no such trial."}
}

#: Trials of finished jobs (they no longer change), by job id.
_finished: BuiltCache[TrialSet] = BuiltCache(8)

Feasible = Annotated[
    bool | None, Query(description="Only feasible (true) or only infeasible (false) trials.")
]
Generation = Annotated[
    int | None, Query(ge=1, le=10**9, description="Only the trials of this generation.")
]
Ranges = Annotated[
    list[str] | None,
    Query(
        max_length=64,
        description="Keep trials with COLUMN in [LOW, HIGH]: `f1:0:2.5`, `x3:-1:`, `cv::0` "
        "(repeat for several columns).",
    ),
]


def _trials(ctx: ApiContext, job: JobRecord) -> TrialSet:
    def load() -> TrialSet:
        with ctx.read() as session:
            return trial_set(job, load_evaluations(session, job.id))

    if job.status.is_terminal:
        return _finished.get_or_build(job.id, load)
    return load()


def _invalid(exc: TrialQueryError) -> RequestValidationError:
    """The 422 of a filter or sort the trials cannot answer, naming its query parameter."""
    return invalid(("query", exc.field), str(exc))


@router.get(
    "/jobs/{job_id}/trials",
    response_model=TrialPage,
    summary="Every evaluated solution (filter, sort, page)",
    responses=_404,
)
async def get_trials(
    job: OwnedJob,
    ctx: Context,
    page: Pagination,
    feasible: Feasible = None,
    generation: Generation = None,
    range: Ranges = None,  # noqa: A002 - the query parameter's name
    sort: Annotated[str, Query(max_length=64, description="Column to sort by: trial, "
                               "generation, cv, f1…, x1… or an objective's key.")] = "trial",
    descending: bool = False,
) -> TrialPage:  # fmt: skip
    """The job's stored evaluations (decision variables, objectives as the front holds them,
    constraint violation), filtered by feasibility, generation and value ranges."""

    def work() -> TrialPage:
        trials = _trials(ctx, job)
        try:
            idx = matching(trials, feasible, generation, range)
            return trial_page(trials, idx, sort=sort, descending=descending,
                              offset=page.offset, limit=page.limit)  # fmt: skip
        except TrialQueryError as exc:
            raise _invalid(exc) from None

    return await run_in_threadpool(work)


@router.get(
    "/jobs/{job_id}/trials/columns",
    response_model=TrialColumns,
    summary="The trials as columns, for a parallel-coordinates plot",
    responses=_404,
)
async def get_trial_columns(
    job: OwnedJob,
    ctx: Context,
    feasible: Feasible = None,
    generation: Generation = None,
    range: Ranges = None,  # noqa: A002 - the query parameter's name
    max_rows: Annotated[int, Query(ge=2, le=20_000, description="At most this many trials, "
                                   "evenly strided over the matched ones.")] = 2000,
) -> TrialColumns:  # fmt: skip
    """One value list per variable and objective of (a sample of) the matched trials."""

    def work() -> TrialColumns:
        trials = _trials(ctx, job)
        try:
            idx = matching(trials, feasible, generation, range)
        except TrialQueryError as exc:
            raise _invalid(exc) from None
        return trial_columns(trials, idx, max_rows)

    return await run_in_threadpool(work)


#: Importance of finished jobs, by job id (a forest per objective takes a second or two).
_importance: BuiltCache[ImportanceOut] = BuiltCache(16)


@router.get(
    "/jobs/{job_id}/trials/importance",
    response_model=ImportanceOut,
    summary="Each decision variable's importance for each objective",
    responses=_404,
)
async def get_importance(job: OwnedJob, ctx: Context) -> ImportanceOut:
    """A random forest per objective over the stored trials (``services.api.importance``
    says which estimator and how): the share of each variable, summing to 1 per objective."""
    from services.api.importance import importance

    def work() -> ImportanceOut:
        trials = _trials(ctx, job)
        if job.status.is_terminal:
            return _importance.get_or_build(job.id, lambda: importance(trials))
        return importance(trials)

    return await run_in_threadpool(work)


@router.get(
    "/jobs/{job_id}/trials/{t}/recording",
    response_class=FileResponse,
    summary="The Rerun recording of one trial (made on demand, then cached)",
    responses={
        200: {"content": {"application/octet-stream": {}}, "description": "The .rrd file."},
        **_404,
        409: {"model": ErrorOut, "description": "The job has not succeeded, or the trial "
              "cannot be decoded with its spec."},
        503: {"model": ErrorOut, "description": "Still being made: retry after `Retry-After`."},
    },
)  # fmt: skip
async def get_trial_recording(job_id: str, t: str, key: CurrentKey, ctx: Context) -> Any:
    """The job's recording with trial ``t`` as its motion. (``t`` is read as text: a job of
    another key is a 404 whatever ``t`` is.)"""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
    index = path_index(job, t, "trial")
    artifact = await run_in_threadpool(trial_recording, ctx, job, index)
    return artifact_response(
        ctx,
        artifact,
        filename=f"{job.id}-trial-{t}.rrd",
        what=f"the recording of trial {t} of job {job.id}",
    )


__all__ = ["router"]
