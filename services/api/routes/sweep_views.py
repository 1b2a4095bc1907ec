"""A sweep as the dashboard shows it: the grid of cells (mean ± sd over seeds) and the fronts
of chosen cells for an overlay."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query

from services.api.dashboard_schemas import (
    CellFront,
    CellFrontJob,
    CellStat,
    SweepCell,
    SweepCellsOut,
    SweepFrontsOut,
    quantities,
)
from services.api.deps import Context, CurrentKey
from services.api.errors import invalid
from services.api.lookups import cell_table, study_kind
from services.api.schemas import ErrorOut
from services.api.sweep_cells import mean_sd
from services.store import output_queries as oq

router = APIRouter(tags=["dashboard"])

_404: dict[int | str, dict[str, Any]] = {
    404: {"model": ErrorOut, "description": "No such sweep (among yours)."}
}


@router.get(
    "/sweeps/{sweep_id}/cells",
    response_model=SweepCellsOut,
    summary="The sweep as a grid of cells: mean ± sd over seeds, best cell per column",
    responses=_404,
)
def get_sweep_cells(sweep_id: str, key: CurrentKey, ctx: Context) -> SweepCellsOut:
    """One cell per combination of swept values (the seed excluded): its jobs, seeds and
    statuses, and for each objective, metric and the hypervolume (against one sweep-wide
    reference point, given) the mean and sample standard deviation over its succeeded jobs.
    Each quantity is one column under its own name, in its own sign (a maximised objective,
    which a result stores negated as ``neg_<m>``, is ``<m>``). ``best`` names the best cell per
    objective (least mean; largest for a maximised one) and hypervolume (largest)."""
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
        objective_names=table.objective_columns,
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
            CellFrontJob(job_id=j, seed=s, points=[p.objectives for p in fronts.get(j, [])])
            for j, s in zip(c.job_ids, c.seeds, strict=True)
            if fronts.get(j)
        ]
        out.append(CellFront(cell=i, label=_cell_label(c.values), jobs=jobs))
    return SweepFrontsOut(
        sweep_id=sweep.id,
        objectives=quantities(table.objective_names, study_kind(sweep)),
        cells=out,
    )
