"""Downloads as CSV, JSON or Parquet: the job list (with the jobs page's filters), a job's
front and history, a sweep's cell table and its jobs one row each. ``legopt export`` calls the
same routes. Every download is named ``legopt-<what>[-<id8>].<format>``
(:func:`services.api.export_formats.filename`)."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Query, status
from fastapi.responses import StreamingResponse

from services.api.convergence import ConvergenceRow, convergence
from services.api.dashboard_schemas import named_best
from services.api.deps import ApiContext, Context, CurrentKey
from services.api.errors import VALIDATION_ERROR_SCHEMA, invalid
from services.api.export_formats import MEDIA_TYPES, ExportFormat, Units, encode, filename
from services.api.export_tables import quantities, sweep_job_table, unit_of
from services.api.front_metrics import point_metrics
from services.api.job_export_tables import front_table, history_table
from services.api.lookups import Filters, cell_table, owned_job, study_kind, sync_labels
from services.api.schemas import ErrorOut, objective_names
from services.api.sweep_cells import mean_sd
from services.store import dashboard_queries as dq
from services.store import output_queries as oq
from services.store import repository as repo
from services.verdict import violations_text

router = APIRouter(tags=["exports"])

FormatQuery = Annotated[ExportFormat, Query(description="csv, json or parquet.")]
_FILE: dict[int | str, dict[str, Any]] = {
    200: {"content": {m: {} for m in MEDIA_TYPES.values()}, "description": "The file."},
    404: {"model": ErrorOut, "description": "Not found (among yours)."},
}
JOB_COLUMNS = (
    "id", "name", "kind", "robot", "optimizer", "seed", "tags", "status", "feasible",
    "violations", "sweep_id", "generation", "total_generations", "progress", "best",
    "best_quantity", "best_unit", "created_at", "started_at", "finished_at", "error",
)  # fmt: skip
#: The job list's one quantity: each row names its own (the jobs are of several studies).
JOB_UNITS: dict[str, tuple[str, str]] = {
    "best": ("", "best value so far of the job's first objective, in its own sign (its "
             "quantity: best_quantity, its unit: best_unit)"),
    "progress": ("", "fraction of the generations done (0 to 1)"),
}  # fmt: skip
#: The sweep job export's columns between the swept values and the quantities, and after them.
SWEEP_JOB_STATE = ("seed", "status", "feasible", "violations")
SWEEP_JOB_TAIL = (
    "generation", "total_generations", "created_at", "started_at", "finished_at", "error",
)  # fmt: skip
#: Jobs read per query while the job list streams.
EXPORT_PAGE = 1000


def _download(
    fmt: str, what: str, ident: str | None, columns: Any, rows: Any, units: Units | None = None
) -> StreamingResponse:
    """The table as a file named ``legopt-<what>[-<first 8 of ident>].<fmt>``."""
    name = filename(what, fmt, ident)
    return StreamingResponse(
        encode(fmt, list(columns), rows, units),
        media_type=MEDIA_TYPES[fmt],
        headers={"Content-Disposition": f'attachment; filename="{name}"'},
    )


def _first(best: Any) -> Any:
    return best[0] if isinstance(best, list) and best else best


def _violations(raw: Any) -> list[dict[str, Any]]:
    return [v for v in raw if isinstance(v, dict)] if isinstance(raw, list) else []


def _verdict(job: Any) -> str | None:
    """The violations of a checked job in words (None when not checked)."""
    return None if job.feasible is None else violations_text(_violations(job.violations))


def _check_filters(ctx: ApiContext, key_id: str, filters: dq.JobFilter) -> None:
    """422 naming the filter, rather than an empty file, for a ``sweep_id`` that is none of the
    caller's sweeps (as any unknown id in a query) or a ``robot`` that no catalog entry, none of
    the caller's robots (by name or id) and none of their jobs is called."""
    from legcore.robots import catalog

    with ctx.read() as session:
        sweep_id = filters.sweep_id
        if sweep_id and repo.get_sweep(session, sweep_id, owner_key_id=key_id) is None:
            raise invalid(
                ("query", "sweep_id"),
                f"no sweep {sweep_id!r} among yours (a whole id: "
                "GET /sweeps?id_prefix= finds one from a prefix)",
            )
        robot = filters.robot
        if not robot or robot in catalog.names():
            return
        if repo.get_robot(session, robot, owner_key_id=key_id) is not None:
            return
        if repo.get_robot_by_name(session, owner_key_id=key_id, name=robot) is not None:
            return
        ran = dq.list_job_rows(session, key_id, dq.JobFilter(robot=robot), limit=1, count=False)
        if not ran.items:
            raise invalid(
                ("query", "robot"),
                f"no robot {robot!r} among the catalog, your robots or your jobs' robots "
                "(GET /robots?include_catalog=true lists them)",
            )


def job_rows(ctx: ApiContext, key_id: str, filters: dq.JobFilter) -> Iterator[tuple[Any, ...]]:
    """Every job matching ``filters``, newest first, read by keyset pages."""
    cursor: str | None = None
    while True:
        with ctx.read() as session:
            page = dq.list_job_rows(
                session, key_id, filters, limit=EXPORT_PAGE, cursor=cursor, count=False
            )
        for r in page.items:
            j = r.job
            named = named_best(j.best_objective, j.facts, r.kind)
            best = (named[0].value, named[0].name, named[0].unit) if named else (
                _first(j.best_objective), None, None)  # fmt: skip
            yield (
                j.id, r.name, r.kind, r.robot, r.optimizer, r.seed, ",".join(r.tags),
                j.status.value, j.feasible, _verdict(j), j.sweep_id, j.progress_generation,
                j.total_generations, round(j.progress, 6), *best, j.created_at, j.started_at,
                j.finished_at, j.error_message,
            )  # fmt: skip
        if page.next_cursor is None:
            return
        cursor = page.next_cursor


@router.get(
    "/export/jobs",
    summary="Your job list as CSV, JSON or Parquet",
    responses={
        **_FILE,
        422: {
            "description": "A bad query, or a filter naming no sweep of yours (`query.sweep_id`) "
            "or no robot (`query.robot`), or a search of only words shorter than 3 characters "
            "(`query.q`).",
            "content": {"application/json": {"schema": VALIDATION_ERROR_SCHEMA}},
        },
    },
    response_class=StreamingResponse,
)
def export_jobs(
    key: CurrentKey, ctx: Context, filters: Filters, format: FormatQuery = "csv"
) -> StreamingResponse:
    """Every job matching the jobs page's filters (newest first): labels, status, the verdict
    of a succeeded job (``feasible``: true / false, empty when not checked; ``violations``: each
    violated constraint with its amount and unit, in words, ``; ``-separated), progress, best
    value so far of the first objective in its own sign (``best``; the jobs are of several
    studies, so each row names its quantity, ``best_quantity``, and SI unit, ``best_unit``)
    and times. A ``sweep_id`` that is none of your sweeps, or a ``robot`` that names no robot
    of the catalog, of yours or of your jobs, is a 422 naming it (not an empty file)."""
    sync_labels(ctx, key.id)
    _check_filters(ctx, key.id, filters)
    return _download(format, "jobs", None, JOB_COLUMNS, job_rows(ctx, key.id, filters), JOB_UNITS)


@router.get(
    "/jobs/{job_id}/front/export",
    summary="A job's final front as CSV, JSON or Parquet",
    responses=_FILE,
    response_class=StreamingResponse,
)
def export_front(
    job_id: str, key: CurrentKey, ctx: Context, format: FormatQuery = "csv"
) -> StreamingResponse:
    """One row per front point: its index, each objective (by name), each of its metrics
    (``metric.<name>``, SI units: the labels and units are those of `GET /jobs/{id}/front`'s
    ``metrics``; decoded again from the point's decision vector the first time, then cached —
    503 with ``Retry-After`` while a large front's are being computed; left out when the job's
    spec cannot be decoded any more) and each decision variable (x1, x2, …); then one row per
    baseline (the study's references, e.g. the paper's law or the physical minimum: no index,
    its name in the last column, ``baseline``)."""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
        points = oq.list_pareto(session, job.id)
        names = objective_names(oq.get_result_objectives(session, job.id))
        baselines = oq.list_baselines(session, job.id)
    per_point, state, _note = point_metrics(ctx, job, bool(points))
    if state == "pending":
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            f"the metrics of job {job.id}'s front points are being computed: retry shortly",
            headers={"Retry-After": "5"},
        )
    table = front_table(job, names, points, baselines, per_point)
    return _download(format, "front", job.id, table.columns, table.rows, table.units)


@router.get(
    "/jobs/{job_id}/history/export",
    summary="A job's per-generation history as CSV, JSON or Parquet",
    responses=_FILE,
    response_class=StreamingResponse,
)
def export_history(
    job_id: str, key: CurrentKey, ctx: Context, format: FormatQuery = "csv"
) -> StreamingResponse:
    """One row per generation: evaluations so far, the best value of each objective so far
    (``best_<name>``: the least on the fronts so far, as the page's convergence plot), the
    hypervolume (against the job's reference point) and the generation's wall time (s); for
    several objectives also the least value of each on that generation's front
    (``front_min_<name>``) and the objectives of the optimiser's reported compromise point
    (``compromise_<name>``: the knee of that front, not a best per objective)."""
    with ctx.read() as session:
        job = owned_job(session, job_id, key.id)
        names = objective_names(oq.get_result_objectives(session, job.id))
        generations: list[Any] = []
        conv: list[ConvergenceRow] = []
        after: int | None = None
        while True:
            chunk = oq.list_generations(session, job.id, after=after, limit=1000)
            conv.extend(convergence(session, job.id, chunk, after=after))
            generations.extend(chunk)
            if len(chunk) < 1000:
                break
            after = chunk[-1].generation
    table = history_table(job, names, generations, conv)
    return _download(format, "history", job.id, table.columns, table.rows, table.units)


@router.get(
    "/sweeps/{sweep_id}/cells/export",
    summary="A sweep's cell table as CSV, JSON or Parquet",
    responses=_FILE,
    response_class=StreamingResponse,
)
def export_cells(
    sweep_id: str, key: CurrentKey, ctx: Context, format: FormatQuery = "csv"
) -> StreamingResponse:
    """One row per cell: the swept values, job counts, then ``<column>_mean``, ``<column>_sd``
    and ``<column>_n`` of each objective, the hypervolume and each metric."""
    sweep, table = cell_table(ctx, key.id, sweep_id)
    shown = quantities(table.stat_columns, table.objective_columns)
    stats = [f"{q.name}_{s}" for q in shown for s in ("mean", "sd", "n")]
    columns = ["cell", *table.columns, "jobs", "succeeded", "seeds", *stats]
    kind = study_kind(sweep)
    units: dict[str, tuple[str, str]] = {}
    for q in shown:
        unit, label = unit_of(q.name, kind)
        units[f"{q.name}_mean"] = (unit, f"mean of {label} over the cell's seeds")
        units[f"{q.name}_sd"] = (unit, f"standard deviation of {label} over the cell's seeds")
        units[f"{q.name}_n"] = ("", f"succeeded seeds with {label}")
    rows = []
    for c in table.cells:
        row: list[Any] = [c.index, *[c.values.get(p) for p in table.columns], len(c.job_ids),
                          c.counts.get("succeeded", 0), c.seeds]  # fmt: skip
        for q in shown:
            samples = q.samples(c.samples)
            row += [*mean_sd(samples), len(samples)]
        rows.append(row)
    return _download(format, "cells", sweep.id, columns, rows, units)


@router.get(
    "/sweeps/{sweep_id}/jobs/export",
    summary="A sweep's jobs, one row each beside its cells, as CSV, JSON or Parquet",
    responses=_FILE,
    response_class=StreamingResponse,
)
def export_sweep_jobs(
    sweep_id: str, key: CurrentKey, ctx: Context, format: FormatQuery = "csv"
) -> StreamingResponse:
    """One row per job of the sweep, in sweep order: its id, its ``cell`` (the index of the
    cell export's rows), the cell's swept values, its seed, status and verdict (``feasible``,
    ``violations``), then each objective (by name), the hypervolume and each metric
    (``metric.<name>``) of its result in SI units — the quantities the cell export aggregates:
    a cell's ``<name>_mean`` is the mean of its succeeded jobs' ``<name>`` (or
    ``metric.<name>``); empty until the job has succeeded — then its progress, times and
    error."""
    table = sweep_job_table(ctx, key.id, sweep_id)
    shown = quantities(table.stat_columns, table.objective_columns)
    names = [f"metric.{q.name}" if q.metric else q.name for q in shown]
    units = {n: unit_of(q.name, table.kind) for n, q in zip(names, shown, strict=True)}
    units["cell"] = ("", "index of the job's cell (the cell export's `cell`)")
    columns = ["id", "cell", *table.columns, *SWEEP_JOB_STATE, *names, *SWEEP_JOB_TAIL]

    def data() -> Iterator[tuple[Any, ...]]:
        for row in table.jobs:
            j, swept = row.job, table.cell_values.get(row.cell, {})
            yield (
                j.id, row.cell, *[swept.get(p) for p in table.columns], row.seed,
                j.status.value, j.feasible, _verdict(j), *[q.value(row.values) for q in shown],
                j.progress_generation, j.total_generations, j.created_at, j.started_at,
                j.finished_at, j.error_message,
            )  # fmt: skip

    return _download(format, "sweep-jobs", table.sweep.id, columns, data(), units)
