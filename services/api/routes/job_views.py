"""One job as the dashboard shows it: its spec as YAML, its front with labelled objectives and
baselines, any solution's motion decoded again, and a front point's Rerun recording."""

from __future__ import annotations

from typing import Annotated, Any
from urllib.parse import quote

import yaml
from fastapi import APIRouter, HTTPException, Query, Response, status
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import FileResponse

from services.api.artifact_download import artifact_response
from services.api.dashboard_schemas import FrontOut, MotionOut
from services.api.deps import ApiContext, Context, CurrentKey
from services.api.front_metrics import point_metrics
from services.api.front_view import front_out
from services.api.lookups import OwnedJob, owned_job, path_index
from services.api.points import baseline_recording, point_motion, point_recording
from services.api.schemas import ErrorOut
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.records import JobRecord
from services.store.states import JobStatus

router = APIRouter(tags=["dashboard"])

_404: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "No such job (among yours), or no such point."}
}
_POINT_ERRORS: dict[int | str, dict[str, Any]] = {
    **_404,
    409: {"model": ErrorOut, "description": "The job has no result, or the point cannot be "
          "decoded with its spec."},
    503: {"model": ErrorOut, "description": "Still being made (one at a time): retry after "
          "`Retry-After` seconds."},
}  # fmt: skip


def _succeeded(job: JobRecord, what: str) -> None:
    if job.status is not JobStatus.SUCCEEDED:
        raise HTTPException(
            status.HTTP_409_CONFLICT,
            f"job {job.id} is {job.status.value}: {what} exists once it succeeded",
        )


@router.get(
    "/jobs/{job_id}/spec.yaml",
    summary="The job's spec as YAML (what `legopt run` and `legopt submit` take)",
    responses={200: {"content": {"application/yaml": {}}}, **_404},
)
def get_spec_yaml(job_id: str, key: CurrentKey, ctx: Context) -> Response:
    """The spec the job runs (stored robots substituted), as a downloadable YAML file."""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
        spec = repo.job_spec(session, job)
    text = yaml.safe_dump(spec, sort_keys=False, allow_unicode=True)
    return Response(
        text,
        media_type="application/yaml",
        headers={"Content-Disposition": f'attachment; filename="job-{job.id[:8]}.yaml"'},
    )


@router.get(
    "/jobs/{job_id}/front",
    response_model=FrontOut,
    summary="The final front with labelled objectives, the best point and the baselines",
    responses=_404,
)
def get_front(job_id: str, key: CurrentKey, ctx: Context) -> FrontOut:
    """Every point of the final front (objectives, decision vector and metrics), the
    objectives' and metrics' readable names and units, the index of the reported optimum on
    the front, the baselines (the study's reference solutions, e.g. the paper's) by objective,
    and the reference point of the job's hypervolumes. Empty until the job succeeded.

    The points' metrics are decoded again from their stored decision vectors on the first
    request (the same deterministic decode as a point's motion) and cached as the job's
    artifact ``front-metrics``; a large front may answer ``point_metrics: pending`` first."""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
        points = oq.list_pareto(session, job.id)
        result = oq.get_result(session, job.id)
        baselines = oq.list_baselines(session, job.id)
        ref = oq.get_hypervolume_ref(session, job.id)
        spec = repo.job_spec(session, job)
    per_point, state, note = point_metrics(ctx, job, bool(points))
    return front_out(job, spec, points, result, baselines, ref, (per_point, state, note))


@router.get(
    "/jobs/{job_id}/motion",
    response_model=MotionOut,
    summary="One solution's motion, decoded again: a front point, a baseline, or the optimum",
    responses=_POINT_ERRORS,
)
async def get_motion(
    job: OwnedJob,
    ctx: Context,
    point: Annotated[int | None, Query(ge=0, le=10**9, description="Front point index.")] = None,
    baseline: Annotated[str | None, Query(max_length=200, description="Baseline name.")] = None,
    trial: Annotated[
        int | None, Query(ge=0, le=10**9, description="Stored trial (`GET .../trials`).")
    ] = None,
) -> MotionOut:
    """The joint signals (q, qd, qdd, jerk, τ, power per joint, at most 400 samples), the
    cumulative energy, objectives and metrics of the front point ``point`` or the baseline
    ``baseline`` (neither: the reported optimum), decoded from its stored decision vector."""
    _succeeded(job, "its motion")
    payload = await run_in_threadpool(
        point_motion, ctx, job, point=point, baseline=baseline, trial=trial
    )
    out = MotionOut(**payload)
    if trial is not None and point is None and baseline is None:
        out.recording_url = f"{ctx.prefix}/jobs/{job.id}/trials/{trial}/recording"
    elif point is not None:
        out.recording_url = f"{ctx.prefix}/jobs/{job.id}/pareto/{point}/recording"
    elif baseline is not None:
        out.recording_url = (
            f"{ctx.prefix}/jobs/{job.id}/baselines/{quote(baseline, safe='')}/recording"
        )
    return out


@router.get(
    "/jobs/{job_id}/pareto/{k}/recording",
    response_class=FileResponse,
    summary="The Rerun recording of front point k (made on demand, then cached)",
    responses={
        200: {"content": {"application/octet-stream": {}}, "description": "The .rrd file."},
        **_POINT_ERRORS,
    },
)
async def get_point_recording(job_id: str, k: str, key: CurrentKey, ctx: Context) -> Response:
    """The ``.rrd`` of the job's recording with front point ``k`` as its motion (the same
    baselines, history and fronts), decoded from the point's stored decision vector on the
    first request and kept as the job's artifact ``point-<k>``; checked against its SHA-256
    before it is sent (``X-Checksum-SHA256``). Also ``legopt replay JOB --point K``."""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
    index = path_index(job, k, "front point")
    _succeeded(job, "a point's recording")
    artifact = await run_in_threadpool(point_recording, ctx, job, index)
    return _rrd(ctx, job, artifact, f"point {k}", f"{job.id}-point-{index}.rrd")


def _rrd(ctx: ApiContext, job: JobRecord, artifact: Any, what: str, name: str) -> Response:
    return artifact_response(
        ctx, artifact, filename=name, what=f"the recording of {what} of job {job.id}"
    )


@router.get(
    "/jobs/{job_id}/baselines/{name}/recording",
    response_class=FileResponse,
    summary="The Rerun recording of one baseline (made on demand, then cached)",
    responses={
        200: {"content": {"application/octet-stream": {}}, "description": "The .rrd file."},
        **_POINT_ERRORS,
    },
)
async def get_baseline_recording(job_id: str, name: str, key: CurrentKey, ctx: Context) -> Response:
    """The ``.rrd`` of the job's recording with the baseline ``name`` (a study's reference
    solution, as `GET /jobs/{id}/front` lists them) as its motion, decoded again on the first
    request and kept as a job artifact, like a front point's. Made whether or not the job
    recorded itself (``record``)."""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
    if len(name) > 200:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"job {job.id} has no such baseline")
    _succeeded(job, "a baseline's recording")
    artifact = await run_in_threadpool(baseline_recording, ctx, job, name)
    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in name)[:60]
    return _rrd(ctx, job, artifact, f"baseline {name}", f"{job.id}-baseline-{safe}.rrd")
