"""Sweeps: one base spec fanned out over a grid, a list and seeds; the aggregated table."""

from __future__ import annotations

from typing import Annotated, Any, cast

from fastapi import APIRouter, HTTPException, Query, Response, status
from fastapi.responses import FileResponse

from services.api.deps import Context, CurrentKey, IdPrefix, Pagination
from services.api.errors import VALIDATION_ERROR_SCHEMA, invalid, not_found
from services.api.lookups import robot_lookup
from services.api.merged_recordings import merged_recording, stored_members
from services.api.schemas import (
    ErrorOut,
    Page,
    SweepAxes,
    SweepCreate,
    SweepCreated,
    SweepOut,
    SweepRow,
    SweepSummary,
    objective_names,
)
from services.api.submission import (
    IdempotencyKey,
    Replay,
    check_quota,
    check_replay,
    remember,
    replay_headers,
)
from services.api.sweeps import SweepError, SweepPoint, expand, swept_paths
from services.api.validation import CheckedJob, resolve_robot, stored_references
from services.api.validation_pool import check_sweep
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.errors import ArtifactError
from services.store.idempotency import request_fingerprint
from services.store.records import JobRecord
from services.store.specs import json_size, shown_value
from services.store.states import JobStatus

router = APIRouter(tags=["sweeps"])

_404: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "No such sweep (among yours)."}
}
_BASE = ("body", "base")


def _relocate(errors: list[dict[str, Any]], point: SweepPoint) -> list[dict[str, Any]]:
    """Errors of a generated spec (located under ``body.base``), moved to the override that
    caused them (``body.grid.<path>.<i>``, ``body.list.<k>.<path>``, ``body.seeds.<j>``)."""
    out = []
    for err in errors:
        field = err["loc"][len(_BASE) :] if err["loc"][: len(_BASE)] == list(_BASE) else None
        source = point.source_of(field) if field is not None else None
        if source is None:
            out.append(err)
            continue
        where = ".".join(str(p) for p in field) if field else "spec"
        overrides = ", ".join(f"{k}={v!r}" for k, v in point.overrides.items())
        out.append(
            {
                **err,
                "loc": ["body", *source],
                "msg": f"job {point.index} ({overrides}): {where}: {err['msg']}",
            }
        )
    return out


@router.post(
    "/sweeps",
    status_code=status.HTTP_202_ACCEPTED,
    response_model=SweepCreated,
    summary="Create a sweep: one job per grid point × list entry × seed",
    responses={429: {"model": ErrorOut, "description": "Over a quota or the request rate limit."}},
)
def create_sweep(
    body: SweepCreate,
    key: CurrentKey,
    ctx: Context,
    response: Response,
    idempotency_key: IdempotencyKey = None,
) -> SweepCreated:
    """Expand the sweep, validate EVERY generated spec (nothing is stored if one fails), store
    the sweep (its base spec once) and its jobs (their overrides) in one transaction, then
    queue them. An ``Idempotency-Key`` header makes retries safe."""
    fingerprint = request_fingerprint(body.model_dump(mode="json", by_alias=True))
    try:
        with ctx.read() as session:  # short: no transaction stays open while validating
            check_replay(session, key, idempotency_key, fingerprint, "sweep")
            base, points, references = _expand(body, key.id, ctx, session)
        checked = check_sweep(
            points, relocate=_relocate, settings=ctx.settings, key_id=key.id,
            references=references, prefix=_BASE,
        )  # fmt: skip
        axes = {"grid": body.grid, "list": body.entries, "seeds": body.seeds, "n_jobs": len(points)}
        overrides = [_resolved(p, c) for p, c in zip(points, checked, strict=True)]
        new_bytes = json_size(base) + sum(json_size(o) for o in overrides)
        with ctx.write() as session:
            check_replay(session, key, idempotency_key, fingerprint, "sweep")
            check_quota(session, key, ctx.settings, new_jobs=len(points), new_bytes=new_bytes)
            sweep = repo.create_sweep(session, owner_key_id=key.id, base_spec=base, axes=axes)
            job_ids = repo.create_jobs(
                session,
                owner_key_id=key.id,
                overrides=overrides,
                total_generations=[c.total_generations for c in checked],
                sweep_id=sweep.id,
                facts=[c.facts for c in checked],
            )
            remember(session, key, idempotency_key, fingerprint, "sweep", sweep.id)
    except Replay as replay:
        response.headers.update(replay_headers())
        return _created(ctx, key.id, replay.record.resource_id, response)
    ctx.send_jobs(job_ids)
    return _created(ctx, key.id, sweep.id, response, job_ids)


def _resolved(point: SweepPoint, checked: CheckedJob) -> dict[str, Any]:
    """The overrides to store for ``point``: a swept ``robot`` (a stored robot's id or name)
    replaced by what it resolved to at validation, so the job runs that robot (the store keeps
    a robot document once, by reference)."""
    if "robot" not in point.overrides:
        return point.overrides
    return {**point.overrides, "robot": checked.spec.get("robot")}


def _expand(
    body: SweepCreate, key_id: str, ctx: Any, session: Any
) -> tuple[dict[str, Any], list[SweepPoint], dict[str, Any]]:
    """The sweep's base (robot reference resolved), its points and the stored robots they
    name (``stored_references``); a 422 for a sweep that cannot be expanded."""
    lookup = robot_lookup(session, key_id)
    base = resolve_robot(body.base, lookup, _BASE)
    try:
        points = expand(base, body.grid, body.entries, body.seeds, max_jobs=ctx.max_sweep_jobs)
    except SweepError as exc:
        raise invalid(("body", *exc.loc), exc.message) from None
    return base, points, stored_references([p.spec for p in points], lookup)


def _created(
    ctx: Any, key_id: str, sweep_id: str, response: Response, job_ids: list[str] | None = None
) -> SweepCreated:
    with ctx.read() as session:
        sweep = repo.get_sweep(session, sweep_id, owner_key_id=key_id)
        if sweep is None:
            raise not_found("sweep", sweep_id)
        counts = repo.count_jobs_by_status(session, owner_key_id=key_id, sweep_id=sweep.id)
        if job_ids is None:
            total = sum(counts.values())
            job_ids = [j.id for j in _jobs_in_order(session, key_id, sweep.id, total, total, 0)]
    response.headers["Location"] = f"{ctx.prefix}/sweeps/{sweep.id}"
    return SweepCreated(**SweepSummary.from_record(sweep, counts).model_dump(), job_ids=job_ids)


@router.get("/sweeps", response_model=Page[SweepSummary], summary="List your sweeps (newest first)")
def list_sweeps(
    key: CurrentKey, ctx: Context, page: Pagination, id_prefix: IdPrefix = None
) -> Page[SweepSummary]:
    """Your sweeps with their job counts per status; ``id_prefix``: only ids starting with it."""
    with ctx.read() as session:
        sweeps = repo.list_sweeps(
            session, owner_key_id=key.id, limit=page.limit, offset=page.offset,
            id_prefix=id_prefix or None,
        )  # fmt: skip
        items = [
            SweepSummary.from_record(
                s, repo.count_jobs_by_status(session, owner_key_id=key.id, sweep_id=s.id)
            )
            for s in sweeps.items
        ]
    return Page[SweepSummary](items=items, total=sweeps.total, limit=page.limit, offset=page.offset)


def _jobs_in_order(
    session: Any, owner_key_id: str, sweep_id: str, total: int, limit: int, offset: int
) -> list[JobRecord]:
    """Jobs ``offset .. offset+limit`` of a sweep in creation order (the store lists newest
    first, so the window is taken from the other end and reversed)."""
    n = min(limit, total - offset)
    if n <= 0:
        return []
    page = repo.list_jobs(
        session,
        owner_key_id=owner_key_id,
        sweep_id=sweep_id,
        limit=n,
        offset=total - offset - n,
    )
    return list(reversed(page.items))


@router.get(
    "/sweeps/{sweep_id}",
    response_model=SweepOut,
    summary="A sweep: counts per status and the table of its jobs",
    responses=_404,
)
def get_sweep(sweep_id: str, key: CurrentKey, ctx: Context, page: Pagination) -> SweepOut:
    """One row per job (paginated, in sweep order): the value of every swept path, status,
    best objective so far, and the final objectives and key metrics of succeeded jobs."""
    with ctx.read() as session:
        sweep = repo.get_sweep(session, sweep_id, owner_key_id=key.id)
        if sweep is None:
            raise not_found("sweep", sweep_id)
        counts = repo.count_jobs_by_status(session, owner_key_id=key.id, sweep_id=sweep.id)
        total = sum(counts.values())
        jobs = _jobs_in_order(session, key.id, sweep.id, total, page.limit, page.offset)
        results = oq.result_briefs(
            session, [j.id for j in jobs if j.status is JobStatus.SUCCEEDED]
        )
        base = repo.sweep_base_spec(session, sweep)
    axes = sweep.axes if isinstance(sweep.axes, dict) else {}
    columns = swept_paths(axes.get("grid"), axes.get("list"), axes.get("seeds"))
    names: list[str] = []
    rows = []
    for job in jobs:
        brief = results.get(job.id)
        objectives = metrics = None
        if brief is not None:
            objectives, metrics = brief
            names = names or objective_names(objectives)
            if isinstance(objectives, dict) and "values" in objectives:
                objectives = objectives["values"]
        rows.append(
            SweepRow(
                job_id=job.id,
                status=job.status,
                overrides={
                    path: shown_value(job.spec or sweep.base_spec, job.overrides, path)
                    for path in columns
                },
                progress=job.progress,
                best_objective=job.best_objective,
                objectives=objectives,
                metrics=metrics,
                feasible=job.feasible,
                error=job.error_message,
            )
        )
    summary = SweepSummary.from_record(sweep, counts)
    return SweepOut(
        **summary.model_dump(),
        base=base,
        axes=cast(SweepAxes, axes),  # as stored: SweepOut validates it
        columns=columns,
        objective_names=names,
        table=Page[SweepRow](items=rows, total=total, limit=page.limit, offset=page.offset),
    )


MAX_MERGED_JOBS = 32


@router.get(
    "/sweeps/{sweep_id}/recording",
    response_class=FileResponse,
    summary="One Rerun recording merging chosen jobs of a sweep, side by side",
    responses={
        200: {"content": {"application/octet-stream": {}}, "description": "The merged .rrd."},
        **_404,
        422: {
            "description": "A chosen job is not in the sweep or has no recording, or too many "
            "jobs (a validation error located at `query.jobs`).",
            "content": {"application/json": {"schema": VALIDATION_ERROR_SCHEMA}},
        },
    },
)
def get_sweep_recording(
    sweep_id: str,
    key: CurrentKey,
    ctx: Context,
    jobs: Annotated[
        list[str] | None,
        Query(description="Job ids to merge (default: every succeeded job with a recording)."),
    ] = None,
) -> FileResponse:
    """Each job's recording under ``/jobs/<n>_<job id prefix>/…`` in one file, with a blueprint
    overlaying the fronts, energies and best objectives (``rerun FILE.rrd``)."""
    with ctx.read() as session:
        sweep = repo.get_sweep(session, sweep_id, owner_key_id=key.id)
        if sweep is None:
            raise not_found("sweep", sweep_id)
        members = repo.sweep_jobs(session, sweep.id, owner_key_id=key.id)
        by_id = {j.id: j for j in members}
        chosen = list(jobs) if jobs else [j.id for j in members]
        unknown = [j for j in chosen if j not in by_id]
        if unknown:
            raise invalid(("query", "jobs"), f"not jobs of sweep {sweep.id}: {', '.join(unknown)}")
        artifacts = []
        for job_id in chosen:
            art = oq.get_artifact(session, job_id, "recording")
            if art is not None:
                artifacts.append((job_id, art))
            elif jobs:
                raise invalid(("query", "jobs"), f"job {job_id} has no recording (yet)")
    if not artifacts:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"sweep {sweep.id} has no recordings yet")
    if len(artifacts) > MAX_MERGED_JOBS:
        raise invalid(
            ("query", "jobs"),
            f"at most {MAX_MERGED_JOBS} jobs per merged recording, got {len(artifacts)}: "
            "choose them with ?jobs=…",
        )
    recordings = stored_members(ctx.artifacts, artifacts)  # verified (downloaded) when merged
    names = [f"{i + 1}_{job_id[:8]}" for i, (job_id, _) in enumerate(artifacts)]
    digests = [art.sha256 for _, art in artifacts]
    try:
        out = merged_recording(recordings, names, digests, ctx.settings.cache_dir)
    except RuntimeError as exc:
        raise ArtifactError(
            f"the recordings of sweep {sweep.id} could not be merged ({exc}); download them "
            "one by one from /jobs/{id}/recording"
        ) from None
    return FileResponse(
        out, media_type="application/octet-stream", filename=f"sweep-{sweep.id}.rrd"
    )
