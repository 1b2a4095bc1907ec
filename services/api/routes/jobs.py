"""Jobs: submit (validated completely before anything is stored), list, read, outputs, cancel."""

from __future__ import annotations

import logging
from typing import Annotated, Any

from fastapi import APIRouter, Body, HTTPException, Query, Response, status
from fastapi.responses import FileResponse

from services.api.artifact_download import artifact_response
from services.api.convergence import convergence
from services.api.deps import (
    MAX_OFFSET,
    Context,
    CurrentKey,
    IdPrefix,
    Pagination,
)
from services.api.job_deletion import delete_jobs
from services.api.lookups import owned_job, robot_lookup
from services.api.schemas import (
    MAX_LIMIT,
    ErrorOut,
    GenerationOut,
    GenerationPage,
    JobDetail,
    JobOut,
    JobPage,
    JobSpecDoc,
    ParetoPage,
    ParetoPointOut,
    ResultOut,
    objective_names,
)
from services.api.study_extras import study_extras
from services.api.submission import (
    IdempotencyKey,
    Replay,
    check_quota,
    check_replay,
    remember,
    replay_headers,
)
from services.api.validation import example_specs, stored_references
from services.api.validation_pool import check_job
from services.store import lifecycle
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.idempotency import request_fingerprint
from services.store.records import JobRecord
from services.store.specs import json_size
from services.store.sql import COUNT_CAP
from services.store.states import JobStatus

router = APIRouter(tags=["jobs"])
log = logging.getLogger("legopt.api")

_404: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "No such job (among yours)."}
}

RECORDING = "recording"


def _spec_examples() -> dict[str, dict[str, object]]:
    examples: dict[str, dict[str, object]] = {
        kind: {"summary": f"{kind} with the seed paper's defaults", "value": spec}
        for kind, spec in example_specs().items()
    }
    return examples


@router.post(
    "/jobs",
    status_code=status.HTTP_202_ACCEPTED,
    response_model=JobDetail,
    summary="Submit a job (the same spec document as `legopt run`)",
    responses={
        429: {"model": ErrorOut, "description": "Over a quota or the request rate limit."}
    },
)
def submit_job(
    spec: Annotated[JobSpecDoc, Body(openapi_examples=_spec_examples())],
    key: CurrentKey,
    ctx: Context,
    response: Response,
    idempotency_key: IdempotencyKey = None,
) -> JobDetail:
    """Validate the spec exactly as a worker will run it (robot, problem, optimizer, size
    limits) — a rejected request stores nothing — then store the job and queue it.

    ``robot`` may be a catalog name, the id or name of one of your stored robots (its spec is
    substituted), or an inline robot spec. Send an ``Idempotency-Key`` header to make retries
    safe: the same key returns the job the first request created.
    """
    fingerprint = request_fingerprint(spec)
    try:
        with ctx.read() as session:  # short: no transaction stays open while validating
            check_replay(session, key, idempotency_key, fingerprint, "job")
            references = stored_references([spec], robot_lookup(session, key.id))
        checked = check_job(spec, settings=ctx.settings, key_id=key.id, references=references)
        with ctx.write() as session:
            check_replay(session, key, idempotency_key, fingerprint, "job")
            check_quota(
                session, key, ctx.settings, new_jobs=1, new_bytes=json_size(checked.spec)
            )
            job = repo.create_job(
                session,
                owner_key_id=key.id,
                spec=checked.spec,
                total_generations=checked.total_generations,
                facts=checked.facts,
            )
            remember(session, key, idempotency_key, fingerprint, "job", job.id)
    except Replay as replay:
        with ctx.read() as session:
            job = owned_job(session, replay.record.resource_id, key.id)
            detail = JobDetail.from_record(job, repo.job_spec(session, job))
        response.headers.update(replay_headers())
        response.headers["Location"] = f"{ctx.prefix}/jobs/{job.id}"
        return detail
    ctx.send_jobs([job.id])
    response.headers["Location"] = f"{ctx.prefix}/jobs/{job.id}"
    return JobDetail.from_record(job, checked.spec)


@router.get("/jobs", response_model=JobPage, summary="List your jobs (newest first)")
def list_jobs(
    key: CurrentKey,
    ctx: Context,
    page: Pagination,
    status_: Annotated[
        list[JobStatus] | None, Query(alias="status", description="Only these statuses.")
    ] = None,
    sweep_id: Annotated[str | None, Query(description="Only the jobs of this sweep.")] = None,
    id_prefix: IdPrefix = None,
    feasible: Annotated[
        bool | None,
        Query(
            description="Only succeeded jobs whose optimum is feasible (true) or infeasible "
            "(false)."
        ),
    ] = None,
) -> JobPage:
    """Your jobs, filtered by status (repeat the parameter for several), sweep, id prefix
    (what `legopt status 2253` resolves: a range scan of the primary key) and verdict
    (`feasible`). Each job carries its verdict once it succeeded: `feasible` and the
    `violations` of its optimum."""
    with ctx.read() as session:
        jobs = repo.list_jobs(
            session,
            owner_key_id=key.id,
            status=status_ or None,
            sweep_id=sweep_id,
            id_prefix=id_prefix or None,
            feasible=feasible,
            limit=page.limit,
            offset=page.offset,
        )
        labels = repo.job_labels(session, jobs.items)
    return JobPage(
        items=[JobOut.from_record(j, labels[j.id]) for j in jobs.items],
        total=jobs.total,
        total_exact=jobs.total <= COUNT_CAP,
        limit=jobs.limit,
        offset=jobs.offset,
    )


@router.get("/jobs/{job_id}", response_model=JobDetail, summary="One job", responses=_404)
def get_job(job_id: str, key: CurrentKey, ctx: Context) -> JobDetail:
    """Status, progress (generation / total), best objective so far, the verdict once it
    succeeded (`feasible`, `violations`), attempts, error, warnings, timestamps and the spec."""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
        return JobDetail.from_record(job, repo.job_spec(session, job))


def _no_output(job: JobRecord, what: str) -> HTTPException:
    message = f"job {job.id} has no {what}: it is {job.status.value}"
    if job.status is JobStatus.FAILED and job.error_message:
        message += f" ({job.error_message})"
    elif not job.is_terminal:
        message += "; it is written when the job succeeds"
    return HTTPException(status.HTTP_404_NOT_FOUND, message)


@router.get(
    "/jobs/{job_id}/result",
    response_model=ResultOut,
    summary="Final result of a succeeded job",
    responses=_404,
)
def get_result(job_id: str, key: CurrentKey, ctx: Context) -> ResultOut:
    """Best solution (x, objectives, metrics, per-joint table), its verdict (`feasible`, the
    `violations` with their amounts), the task it ran (`task`: parameters and the rules that
    derived them from the robot), baselines (each with its own verdict), artifacts."""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
        result = oq.get_result(session, job.id)
        if result is None:
            raise _no_output(job, "result")
        baselines = oq.list_baselines(session, job.id)
        artifacts = oq.list_artifacts(session, job.id)
    out = ResultOut.from_records(result, baselines, artifacts, job)
    summary = out.summary
    if isinstance(summary, dict) and "extras" not in summary:
        extras, warning = study_extras(ctx, job, artifacts)
        out.summary = {**summary, "extras": extras}
        if warning is not None:
            out.summary["extras_warning"] = warning
    return out


@router.get(
    "/jobs/{job_id}/pareto",
    response_model=ParetoPage,
    summary="Final Pareto front (paginated; empty until the job succeeded)",
    responses=_404,
)
def get_pareto(job_id: str, key: CurrentKey, ctx: Context, page: Pagination) -> ParetoPage:
    """Points of the front by index: decision vector ``x`` and ``objectives``."""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
        points = oq.list_pareto(session, job.id)
        names = objective_names(oq.get_result_objectives(session, job.id))
    chosen = points[page.offset : page.offset + page.limit]
    return ParetoPage(
        items=[ParetoPointOut.from_record(p) for p in chosen],
        total=len(points),
        limit=page.limit,
        offset=page.offset,
        objective_names=names,
    )


@router.get(
    "/jobs/{job_id}/generations",
    response_model=GenerationPage,
    summary="Per-generation progress (poll with `after`)",
    responses=_404,
)
def get_generations(
    job_id: str,
    key: CurrentKey,
    ctx: Context,
    after: Annotated[
        int | None, Query(ge=-1, le=MAX_OFFSET, description="Only generations after this one.")
    ] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_LIMIT)] = MAX_LIMIT,
) -> GenerationPage:
    """Generation rows in order (0 is the initial population): evaluations, the reported
    solution's objectives (`best`), the least value of each objective on the generation's
    front (`front_min`) and so far (`best_so_far`: what the convergence plot shows), the
    hypervolume and the wall time."""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
        rows = oq.list_generations(session, job.id, after=after, limit=limit)
        conv = convergence(session, job.id, rows, after=after)
    return GenerationPage(
        items=[
            GenerationOut.from_record(g, best_so_far=c.best_so_far, front_min=c.front_min)
            for g, c in zip(rows, conv, strict=True)
        ],
        limit=limit,
        after=after,
        next_after=rows[-1].generation if rows else after,
    )


@router.get(
    "/jobs/{job_id}/recording",
    response_class=FileResponse,
    summary="The Rerun recording (.rrd) of a succeeded job",
    responses={
        200: {"content": {"application/octet-stream": {}}, "description": "The .rrd file."},
        **_404,
    },
)
def get_recording(job_id: str, key: CurrentKey, ctx: Context) -> Response:
    """The ``.rrd`` file, checked against its recorded SHA-256 first (``X-Checksum-SHA256``;
    ``Range`` requests answered 206). Open it with ``rerun FILE.rrd`` (or ``legopt replay
    JOB``). 404 naming it when its file or object is gone, 503 when the artifact store cannot
    be reached."""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
        artifact = oq.get_artifact(session, job.id, RECORDING)
        labels = repo.job_labels(session, [job])[job.id]
    if artifact is None:
        if labels.get("record") is False:
            raise HTTPException(
                status.HTTP_404_NOT_FOUND,
                f"job {job.id} has no recording: recording is disabled in its spec (record: false)",
            )
        if job.status is JobStatus.SUCCEEDED:
            why = "; ".join(w for w in job.warnings if "record" in w) or "none was written"
            raise HTTPException(status.HTTP_404_NOT_FOUND, f"job {job.id} has no recording: {why}")
        raise _no_output(job, "recording")
    return artifact_response(
        ctx, artifact, filename=f"{job.id}.rrd", what=f"the recording of job {job.id}"
    )


@router.post(
    "/jobs/{job_id}/cancel",
    status_code=status.HTTP_202_ACCEPTED,
    response_model=JobOut,
    summary="Cancel a job",
    responses={
        **_404,
        409: {"model": ErrorOut, "description": "The job already finished."},
    },
)
def cancel_job(job_id: str, key: CurrentKey, ctx: Context) -> JobOut:
    """A queued job is cancelled at once; a running job is flagged and its worker stops after
    the current generation (``cancel_requested``); a finished job is a 409."""
    with ctx.write() as session:
        job = owned_job(session, job_id, key.id)
        if job.is_terminal:
            raise HTTPException(
                status.HTTP_409_CONFLICT, f"job {job.id} already finished: it is {job.status.value}"
            )
        updated = lifecycle.request_cancel(session, job.id, owner_key_id=key.id)
    assert updated is not None
    return JobOut.from_record(updated)


@router.delete(
    "/jobs/{job_id}",
    status_code=status.HTTP_204_NO_CONTENT,
    summary="Delete a finished job and everything stored for it",
    responses={
        **_404,
        409: {"model": ErrorOut, "description": "The job is still queued or running."},
    },
)
def delete_job(job_id: str, key: CurrentKey, ctx: Context) -> Response:
    """Removes the job's rows (progress, front, result, events) and its artifact files, which
    frees storage quota. A queued or running job must be cancelled first (409)."""
    delete_jobs(ctx, key.id, lambda session: [owned_job(session, job_id, key.id)])
    return Response(status_code=status.HTTP_204_NO_CONTENT)
