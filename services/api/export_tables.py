"""What the exports' tables are made of: each quantity once, in its own sign, with its unit
and label; and a sweep's jobs one row each, beside its cells (``GET /sweeps/{id}/jobs/export``).

A result stores its objectives as the optimiser minimises them (``neg_score``: a maximised
quantity negated); an export shows each quantity once, under its own name and sign (``score``,
positive). A sweep's stat columns already are (``sweep_cells.job_values``, which the job rows
below use too); a front's and a history's objectives are flipped by :func:`shown_keys`.

Each job's row names its cell (the index of ``GET /sweeps/{id}/cells`` and of the cell export),
the cell's swept values and the job's seed, and holds the job's own value of every column the
cell table aggregates: each objective and metric of its result, and its final front's
hypervolume against the same sweep-wide reference point the cells use (``nadir + 10 %`` of the
union of the sweep's final fronts), so that the mean over a cell's succeeded jobs is the cell's
``<column>_mean``. Values are in the result's SI units (the export labels them); a job without
a result (queued, running, failed, cancelled) has none.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np

from services.api.deps import ApiContext
from services.api.lookups import sweep_cells
from services.api.quantities import describe
from services.api.sweep_cells import HYPERVOLUME, job_values
from services.store.records import JobRecord, ParetoPointRecord, SweepRecord

__all__ = [
    "Quantity",
    "SweepJob",
    "SweepJobTable",
    "quantities",
    "shown_keys",
    "sweep_job_table",
    "unit_of",
]


def unit_of(key: str, kind: str | None) -> tuple[str, str]:
    """``(SI unit, label)`` of a result key of the study ``kind`` (unit "" when dimensionless;
    a ``neg_`` objective: of the quantity it negates)."""
    from legcore.studies.metric_names import display_objective

    d = describe(display_objective(key, None)[0], kind)
    return d["unit"], d["label"]


def shown_keys(names: Sequence[str]) -> tuple[list[str], list[bool]]:
    """The objectives' exported keys (``neg_<m>`` as ``<m>``: one sign per quantity, the
    quantity's own) and which of them are flipped."""
    from legcore.studies.metric_names import display_objective

    shown = [display_objective(n, None)[0] for n in names]
    return shown, [s != n for s, n in zip(shown, names, strict=True)]


class Quantity(NamedTuple):
    """A column of a sweep's stat table as exported: the quantity's own name (the cell
    table's column, in its own sign) and whether it is a metric (not an objective, not the
    hypervolume)."""

    name: str
    metric: bool

    def value(self, values: Mapping[str, Any]) -> Any:
        """Its value in a job's ``values`` (None when absent)."""
        return values.get(self.name)

    def samples(self, samples: Mapping[str, Sequence[float]]) -> list[float]:
        """Its samples (a cell's)."""
        return list(samples.get(self.name, []))


def quantities(stat_columns: Sequence[str], objective_columns: Sequence[str]) -> list[Quantity]:
    """A sweep's stat columns (``CellTable.stat_columns``, each quantity once) as exported."""
    return [Quantity(c, c not in objective_columns and c != HYPERVOLUME) for c in stat_columns]


@dataclass
class SweepJob:
    """One job of a sweep: its record, its cell's index, its seed and its value of each stat
    column (objectives and metrics in the result's units, the hypervolume; absent when the job
    has none)."""

    job: JobRecord
    cell: int
    seed: Any
    values: dict[str, float] = field(default_factory=dict)


@dataclass
class SweepJobTable:
    """A sweep's jobs in sweep order with what their rows share: the sweep, its study kind,
    the cell columns (swept paths but the seed), each cell's swept values by cell index, the
    stat columns (the cell table's: objectives, then hypervolume, then metrics) and the
    objectives' columns (their own names: ``score``, not ``neg_score``)."""

    sweep: SweepRecord
    kind: str | None
    columns: list[str]
    cell_values: dict[int, dict[str, Any]]
    stat_columns: list[str]
    objective_columns: list[str]
    jobs: list[SweepJob]


def _hypervolume(points: Sequence[ParetoPointRecord], ref: Sequence[float] | None) -> float | None:
    """The hypervolume of a final front against the sweep-wide reference ``ref`` (None when
    the front has no finite point of ``len(ref)`` objectives)."""
    from legcore.metrics import hypervolume

    if ref is None or not points:
        return None
    F = np.asarray([p.objectives for p in points if p.objectives], dtype=float)
    if F.ndim != 2 or F.shape[0] == 0 or F.shape[1] != len(ref):
        return None
    F = F[np.all(np.isfinite(F), axis=1)]
    return float(hypervolume(F, ref).value) if F.shape[0] else None


def sweep_job_table(ctx: ApiContext, key_id: str, sweep_id: str) -> SweepJobTable:
    """The caller's sweep ``sweep_id`` (404 when missing or another key's) as one row per job,
    grouped into cells exactly as ``lookups.cell_table`` groups them."""
    found = sweep_cells(ctx, key_id, sweep_id)
    sweep, jobs, results, fronts, kind, table = (
        found.sweep,
        found.jobs,
        found.results,
        found.fronts,
        found.kind,
        found.table,
    )
    where: dict[str, tuple[int, Any]] = {}
    for cell in table.cells:
        for job_id, seed in zip(cell.job_ids, cell.seeds, strict=True):
            where[job_id] = (cell.index, seed)
    rows = []
    for job in jobs:
        index, seed = where[job.id]
        values: dict[str, float] = {}
        brief = results.get(job.id)
        if brief is not None:
            values = job_values(*brief)[2]
            hv = _hypervolume(fronts.get(job.id, []), table.hypervolume_ref)
            if hv is not None:
                values[HYPERVOLUME] = hv
        rows.append(SweepJob(job=job, cell=index, seed=seed, values=values))
    return SweepJobTable(
        sweep=sweep,
        kind=kind,
        columns=table.columns,
        cell_values={c.index: c.values for c in table.cells},
        stat_columns=table.stat_columns,
        objective_columns=table.objective_columns,
        jobs=rows,
    )
