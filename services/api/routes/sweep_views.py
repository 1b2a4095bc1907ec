"""A sweep as the dashboard shows it: the grid of cells (mean ± sd over seeds) and the fronts
of chosen cells for an overlay."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query
from sqlalchemy.orm import Session

from services.api.dashboard_schemas import (
    CellFront,
    CellStat,
    SweepCell,
    SweepCellsOut,
    SweepFrontsOut,
    quantities,
)
from services.api.deps import Context, CurrentKey
from services.api.errors import invalid, not_found
from services.api.quantities import describe
from services.api.schemas import ErrorOut
from services.api.sweep_cells import CellTable, build_cells, mean_sd
from services.api.sweeps import swept_paths
from services.store import output_queries as oq
from services.store import repository as repo
from services.store.records import JobRecord, SweepRecord
from services.store.specs import shown_value, spec_value
from services.store.tables import JobStatus

router = APIRouter(tags=["dashboard"])

_404: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "No such sweep (among yours)."}
}
#: Jobs a sweep can have (``services.api.sweeps.MAX_SWEEP_JOBS``); read in one page.
_ALL = 1000


def _sweep_jobs(
    session: Session, key_id: str, sweep_id: str
) -> tuple[SweepRecord, list[JobRecord]]:
    sweep = repo.get_sweep(session, sweep_id, owner_key_id=key_id)
    if sweep is None:
        raise not_found("sweep", sweep_id)
    page = repo.list_jobs(session, owner_key_id=key_id, sweep_id=sweep.id, limit=_ALL, offset=0)
    return sweep, list(reversed(page.items))  # sweep order


def cell_table(ctx: Any, key_id: str, sweep_id: str) -> tuple[SweepRecord, CellTable]:
    """The sweep and its cells (shared by the page and the export)."""
    with ctx.read() as session:
        sweep, jobs = _sweep_jobs(session, key_id, sweep_id)
        done = [j.id for j in jobs if j.status is JobStatus.SUCCEEDED]
        results = repo.result_briefs(session, done)
        fronts = oq.fronts_of(session, done)
    axes = sweep.axes if isinstance(sweep.axes, dict) else {}
    swept = swept_paths(axes.get("grid"), axes.get("list"), axes.get("seeds"))

    def value(job: JobRecord, path: str) -> Any:
        return shown_value(job.spec or sweep.base_spec, job.overrides, path)

    kind = study_kind(sweep)
    table = build_cells(
        jobs, value, swept, results, fronts, sense=lambda n: describe(n, kind)["sense"]
    )
    return sweep, table


def study_kind(sweep: SweepRecord) -> str | None:
    """The study kind of a sweep's base spec."""
    return spec_value(sweep.base_spec, None, "problem.kind")


@router.get(
    "/sweeps/{sweep_id}/cells",
    response_model=SweepCellsOut,
    summary="The sweep as a grid of cells: mean ± sd over seeds, best cell per column",
    responses=_404,
)
def get_sweep_cells(sweep_id: str, key: CurrentKey, ctx: Context) -> SweepCellsOut:
    """One cell per combination of swept values (the seed excluded): its jobs, seeds and
    statuses, and for each objective, metric and the hypervolume (against one sweep-wide
    reference point, given) the mean and sample standard deviation over its succeeded jobs;
    ``best`` names the best cell per objective (least mean) and hypervolume (largest)."""
    sweep, table = cell_table(ctx, key.id, sweep_id)
    cells = []
    for c in table.cells:
        stats = {}
        for col in table.stat_columns:
            samples = c.samples.get(col, [])
            mean, sd = mean_sd(samples)
            stats[col] = CellStat(mean=mean, sd=sd, n=len(samples))
        cells.append(
            SweepCell(
                index=c.index,
                values=c.values,
                job_ids=c.job_ids,
                seeds=c.seeds,
                counts=c.counts,
                stats=stats,
            )  # fmt: skip
        )
    return SweepCellsOut(
        sweep_id=sweep.id,
        columns=table.columns,
        stat_columns=quantities(table.stat_columns, study_kind(sweep)),
        objective_names=table.objective_names,
        cells=cells,
        best=table.best,
        hypervolume_ref=table.hypervolume_ref,
    )


def _cell_label(values: dict[str, Any]) -> str:
    return ", ".join(f"{k.split('.')[-1]}={v}" for k, v in values.items()) or "all jobs"


@router.get(
    "/sweeps/{sweep_id}/fronts",
    response_model=SweepFrontsOut,
    summary="The final fronts of chosen cells, for an overlay plot",
    responses=_404,
)
def get_sweep_fronts(
    sweep_id: str,
    key: CurrentKey,
    ctx: Context,
    cell: Annotated[
        list[int] | None, Query(description="Cell indexes (default: the first 8 cells).")
    ] = None,
) -> SweepFrontsOut:
    """Per chosen cell, the final front (objective vectors) of each of its succeeded jobs."""
    sweep, table = cell_table(ctx, key.id, sweep_id)
    chosen = list(cell) if cell else [c.index for c in table.cells[:8]]
    by_index = {c.index: c for c in table.cells}
    unknown = [i for i in chosen if i not in by_index]
    if unknown:
        raise invalid(("query", "cell"), f"no cells {unknown}: the sweep has {len(by_index)}")
    ids = [j for i in chosen for j in by_index[i].job_ids]
    with ctx.read() as session:
        fronts = oq.fronts_of(session, ids)
    out = []
    for i in chosen:
        c = by_index[i]
        jobs = [
            {"job_id": j, "seed": s, "points": [p.objectives for p in fronts.get(j, [])]}
            for j, s in zip(c.job_ids, c.seeds, strict=True)
            if fronts.get(j)
        ]
        out.append(CellFront(cell=i, label=_cell_label(c.values), jobs=jobs))
    return SweepFrontsOut(
        sweep_id=sweep.id,
        objectives=quantities(table.objective_names, study_kind(sweep)),
        cells=out,
    )
