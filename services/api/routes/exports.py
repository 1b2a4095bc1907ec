"""Downloads as CSV, JSON or Parquet: the job list (with the jobs page's filters), a job's
front and history, a sweep's cell table. ``legopt export`` calls the same routes."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Annotated, Any

from fastapi import APIRouter, HTTPException, Query, status
from fastapi.responses import StreamingResponse

from services.api.convergence import ConvergenceRow, convergence
from services.api.dashboard_schemas import BaselineMark
from services.api.deps import ApiContext, Context, CurrentKey
from services.api.export_formats import MEDIA_TYPES, ExportFormat, Units, encode, filename
from services.api.lookups import Filters, cell_table, owned_job, sync_labels
from services.api.points import point_metrics
from services.api.quantities import describe
from services.api.schemas import ErrorOut, objective_names
from services.api.sweep_cells import mean_sd
from services.store import dashboard_queries as dq
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
    "created_at", "started_at", "finished_at", "error",
)  # fmt: skip
#: Jobs read per query while the job list streams.
EXPORT_PAGE = 1000


def _download(
    fmt: str, stem: str, columns: Any, rows: Any, units: Units | None = None
) -> StreamingResponse:
    return StreamingResponse(
        encode(fmt, list(columns), rows, units),
        media_type=MEDIA_TYPES[fmt],
        headers={"Content-Disposition": f'attachment; filename="{filename(stem, fmt)}"'},
    )


def _unit(key: str, kind: str | None) -> tuple[str, str]:
    """``(unit, label)`` of a result key (a ``neg_`` objective: of the quantity it negates)."""
    from legcore.studies.metric_names import display_objective

    d = describe(display_objective(key, None)[0], kind)
    return d["unit"], d["label"]


def _shown(names: list[str]) -> tuple[list[str], list[bool]]:
    """The objectives' exported keys (``neg_<m>`` as ``<m>``: one sign per quantity, the
    quantity's own) and which of them are flipped."""
    from legcore.studies.metric_names import display_objective

    shown = [display_objective(n, None)[0] for n in names]
    return shown, [s != n for s, n in zip(shown, names, strict=True)]


def _signed(values: Any, flip: list[bool]) -> list[Any]:
    return [-v if f and isinstance(v, int | float) else v
            for v, f in zip(values, flip, strict=False)]  # fmt: skip


def _kind(job: Any) -> str | None:
    facts = job.facts if isinstance(job.facts, dict) else {}
    return facts.get("kind") if isinstance(facts.get("kind"), str) else None


def _first(best: Any) -> Any:
    return best[0] if isinstance(best, list) and best else best


def _violations(raw: Any) -> list[dict[str, Any]]:
    return [v for v in raw if isinstance(v, dict)] if isinstance(raw, list) else []


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
            yield (
                j.id, r.name, r.kind, r.robot, r.optimizer, r.seed, ",".join(r.tags),
                j.status.value, j.feasible,
                None if j.feasible is None else violations_text(_violations(j.violations)),
                j.sweep_id, j.progress_generation, j.total_generations,
                round(j.progress, 6), _first(j.best_objective), j.created_at, j.started_at,
                j.finished_at, j.error_message,
            )  # fmt: skip
        if page.next_cursor is None:
            return
        cursor = page.next_cursor


@router.get(
    "/export/jobs", summary="Your job list as CSV, JSON or Parquet", responses=_FILE,
    response_class=StreamingResponse,
)  # fmt: skip
def export_jobs(
    key: CurrentKey, ctx: Context, filters: Filters, format: FormatQuery = "csv"
) -> StreamingResponse:
    """Every job matching the jobs page's filters (newest first): labels, status, the verdict
    of a succeeded job (``feasible``: true / false, empty when not checked; ``violations``: each
    violated constraint with its amount and unit, in words, ``; ``-separated), progress, best
    value so far (first objective) and times."""
    sync_labels(ctx, key.id)
    return _download(format, "jobs", JOB_COLUMNS, job_rows(ctx, key.id, filters))


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
        points = repo.list_pareto(session, job.id)
        names = objective_names(repo.get_result_objectives(session, job.id))
        baselines = repo.list_baselines(session, job.id)
    per_point, state, _note = point_metrics(ctx, job, bool(points))
    if state == "pending":
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            f"the metrics of job {job.id}'s front points are being computed: retry shortly",
            headers={"Retry-After": "5"},
        )
    m = max((len(p.objectives or []) for p in points), default=len(names))
    names = names if len(names) == m else [f"f{i + 1}" for i in range(m)]
    shown, flip = _shown(names)
    n = max((len(p.x or []) for p in points), default=0)
    # a metric that is also an objective is the objective's column (one column per quantity)
    metrics = [k for k in dict.fromkeys(k for v in per_point.values() if v for k in v)
               if k not in shown]  # fmt: skip
    columns = ["index", *shown, *[f"metric.{k}" for k in metrics], *[f"x{i + 1}" for i in range(n)],
               "baseline"]  # fmt: skip
    kind = _kind(job)
    units: dict[str, tuple[str, str]] = {c: _unit(c, kind) for c in shown}
    units.update({f"metric.{k}": _unit(k, kind) for k in metrics})
    rows = [
        (p.index, *_signed(_pad(p.objectives, m), flip),
         *[(per_point.get(p.index) or {}).get(k) for k in metrics], *_pad(p.x, n), None)
        for p in points
    ]  # fmt: skip
    for b in baselines:
        mark = BaselineMark.from_record(b, names)
        rows.append((None, *_signed(_pad(mark.objectives, m), flip),
                     *[mark.metrics.get(k) for k in metrics], *[None] * n, b.name))  # fmt: skip
    return _download(format, f"job-{job.id[:8]}-front", columns, rows, units)


def _pad(values: Any, n: int) -> list[Any]:
    values = list(values or [])
    return values + [None] * (n - len(values))


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
        names = objective_names(repo.get_result_objectives(session, job.id))
        rows: list[Any] = []
        conv: list[ConvergenceRow] = []
        after: int | None = None
        while True:
            chunk = repo.list_generations(session, job.id, after=after, limit=1000)
            conv.extend(convergence(session, job.id, chunk, after=after))
            rows.extend(chunk)
            if len(chunk) < 1000:
                break
            after = chunk[-1].generation
    m = max((len(g.best) if isinstance(g.best, list) else 1 for g in rows), default=len(names))
    names = names if len(names) == m else [f"f{i + 1}" for i in range(m)]
    shown, flip = _shown(names)
    several = m > 1
    columns = ["generation", "n_evals", *[f"best_{n}" for n in shown], "hypervolume",
               "wall_time_s"]  # fmt: skip
    if several:
        columns += [f"front_min_{n}" for n in shown] + [f"compromise_{n}" for n in shown]
    kind = _kind(job)
    units: dict[str, tuple[str, str]] = {"wall_time_s": ("s", "wall time of the generation")}
    for n in shown:
        unit, label = _unit(n, kind)
        units[f"best_{n}"] = (unit, f"best {label} so far")
        units[f"front_min_{n}"] = (unit, f"least {label} on the generation's front")
        units[f"compromise_{n}"] = (unit, f"{label} of the reported compromise point")

    def data() -> Iterator[tuple[Any, ...]]:
        for g, c in zip(rows, conv, strict=True):
            reported = _pad(g.best if isinstance(g.best, list) else [g.best], m)
            row = (g.generation, g.n_evals, *_signed(_pad(c.best_so_far, m), flip),
                   g.hypervolume, g.wall_time_s)  # fmt: skip
            if several:
                row = (*row, *_signed(_pad(c.front_min, m), flip), *_signed(reported, flip))
            yield row

    return _download(format, f"job-{job.id[:8]}-history", columns, data(), units)


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
    shown, flip = _shown(list(table.stat_columns))
    stats = [f"{c}_{s}" for c in shown for s in ("mean", "sd", "n")]
    columns = ["cell", *table.columns, "jobs", "succeeded", "seeds", *stats]
    base = sweep.base_spec if isinstance(sweep.base_spec, dict) else {}
    problem = base.get("problem")
    kind = problem.get("kind") if isinstance(problem, dict) else None
    kind = kind if isinstance(kind, str) else None
    units: dict[str, tuple[str, str]] = {}
    for q in shown:
        unit, label = _unit(q, kind)
        units[f"{q}_mean"] = (unit, f"mean of {label} over the cell's seeds")
        units[f"{q}_sd"] = (unit, f"standard deviation of {label} over the cell's seeds")
        units[f"{q}_n"] = ("", f"succeeded seeds with {label}")
    rows = []
    for c in table.cells:
        row: list[Any] = [c.index, *[c.values.get(p) for p in table.columns], len(c.job_ids),
                          c.counts.get("succeeded", 0), c.seeds]  # fmt: skip
        for col, flipped in zip(table.stat_columns, flip, strict=True):
            samples = c.samples.get(col, [])
            mean, sd = mean_sd(samples)
            row += [-mean if flipped and mean is not None else mean, sd, len(samples)]
        rows.append(row)
    return _download(format, f"sweep-{sweep.id[:8]}-cells", columns, rows, units)
