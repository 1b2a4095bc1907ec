"""A sweep as a grid of cells: the jobs that share every swept value but the seed, with the
mean ± sd over their seeds of each objective, metric and hypervolume.

Hypervolumes of different jobs are comparable only against one reference point, so the cells'
hypervolumes are measured here against a sweep-wide one: ``nadir + 10 %`` of the union of the
sweep's final fronts (:func:`legcore.metrics.reference_point`), returned with the table. A
sweep has at most ``MAX_SWEEP_JOBS`` jobs, so this reads all of its fronts at once.

Each quantity is one column, under its own name and in its own sign: a result names a
maximised objective as the optimiser minimises it (``neg_score``) while the study may key its
value by the quantity's own name (``score``); the cell's column is ``score``, positive, and
larger is better (:func:`job_values`, which the sweep job export uses too).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from services.store.records import JobRecord, ParetoPointRecord

__all__ = [
    "Cell",
    "CellTable",
    "HYPERVOLUME",
    "build_cells",
    "cell_columns",
    "job_values",
    "mean_sd",
]

#: Column name of the hypervolume in a cell's stats.
HYPERVOLUME = "hypervolume"
#: Swept paths that vary over seeds inside a cell, not across cells.
SEED_PATHS = frozenset({"seed"})


@dataclass
class Cell:
    """One cell: its swept values, its jobs (in sweep order), their seeds and statuses, and
    the per-job values of every column (None where a job has none)."""

    index: int
    values: dict[str, Any]
    job_ids: list[str] = field(default_factory=list)
    seeds: list[Any] = field(default_factory=list)
    counts: dict[str, int] = field(default_factory=dict)
    samples: dict[str, list[float]] = field(default_factory=dict)


@dataclass
class CellTable:
    """The cells of a sweep, the stat columns (objectives first, then hypervolume, then
    metrics; each quantity once, under its own name), the objective names as the results and
    fronts store them (``neg_score``), the best cell per column, the hypervolume reference and
    the objectives' columns (``score``)."""

    columns: list[str]
    stat_columns: list[str]
    objective_names: list[str]
    cells: list[Cell]
    best: dict[str, int]
    hypervolume_ref: list[float] | None
    objective_columns: list[str] = field(default_factory=list)


def cell_columns(swept: Sequence[str]) -> list[str]:
    """The swept paths that make a cell (every swept path but the seed)."""
    return [p for p in swept if p not in SEED_PATHS]


def mean_sd(values: Sequence[float]) -> tuple[float | None, float | None]:
    """Mean and sample standard deviation (ddof 1; 0 for one value; None for none)."""
    finite = [v for v in values if v is not None and math.isfinite(v)]
    if not finite:
        return None, None
    a = np.asarray(finite, dtype=float)
    return float(a.mean()), float(a.std(ddof=1)) if a.size > 1 else 0.0


def _numeric(d: Any) -> dict[str, float]:
    if not isinstance(d, Mapping):
        return {}
    return {
        str(k): float(v)
        for k, v in d.items()
        if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
    }


def job_values(objectives: Any, metrics: Any) -> tuple[list[str], list[bool], dict[str, float]]:
    """One result's ``(objective columns, which are maximised, values)``: each objective under
    its quantity's own name and in its own sign (``neg_score`` stored as ``neg_score`` is
    negated; stored under ``score``, the study's key, it is taken as it is), then each finite
    metric that is not already an objective's column."""
    from legcore.studies.metric_names import display_objective

    doc = objectives if isinstance(objectives, Mapping) else {}
    stored = _numeric(doc.get("values"))
    shown: list[str] = []
    maximised: list[bool] = []
    row: dict[str, float] = {}
    for name in [str(n) for n in doc.get("names") or []]:
        own = display_objective(name, None)[0]
        shown.append(own)
        maximised.append(own != name)
        if name in stored:
            row[own] = -stored[name] if own != name else stored[name]
        elif own in stored:
            row[own] = stored[own]
    for k, v in _numeric(metrics).items():
        row.setdefault(k, v)
    return shown, maximised, row


def _hypervolumes(
    fronts: Mapping[str, Sequence[ParetoPointRecord]],
) -> tuple[dict[str, float], list[float] | None]:
    """Each job's final-front hypervolume against the union's reference point."""
    from legcore.metrics import hypervolume, reference_point

    arrays = {}
    for job_id, pts in fronts.items():
        F = np.asarray([p.objectives for p in pts if p.objectives], dtype=float)
        if F.ndim == 2 and F.shape[0] and F.shape[1] >= 2:
            F = F[np.all(np.isfinite(F), axis=1)]
            if F.shape[0]:
                arrays[job_id] = F
    widths = {F.shape[1] for F in arrays.values()}
    if not arrays or len(widths) != 1:
        return {}, None
    ref = reference_point(np.concatenate(list(arrays.values())))
    return {j: float(hypervolume(F, ref).value) for j, F in arrays.items()}, [float(v) for v in ref]


def build_cells(
    jobs: Sequence[JobRecord],
    values_of: Any,
    swept: Sequence[str],
    results: Mapping[str, tuple[Any, Any]],
    fronts: Mapping[str, Sequence[ParetoPointRecord]],
    sense: Callable[[str], str] = lambda _name: "",
) -> CellTable:
    """Group ``jobs`` (in sweep order) into cells. ``values_of(job, path)``: a job's value of a
    swept path; ``results``: ``{job_id: (objectives, metrics)}`` of succeeded jobs
    (``repository.result_briefs``); ``fronts``: their final fronts; ``sense(metric)``: "min"
    or "max" when smaller or larger is better (the best cell of such a metric is named too;
    an objective is best least, a maximised one (``neg_<m>``, shown as ``<m>``) largest, the
    hypervolume largest)."""
    columns = cell_columns(swept)
    hv, ref = _hypervolumes(fronts)
    names: list[str] = []
    shown: list[str] = []
    maximised: list[bool] = []
    metric_names: list[str] = []
    cells: dict[str, Cell] = {}
    for job in jobs:
        values = {p: values_of(job, p) for p in columns}
        key = json.dumps(values, sort_keys=True, default=str)
        cell = cells.get(key)
        if cell is None:
            cell = cells[key] = Cell(index=len(cells), values=values)
        cell.job_ids.append(job.id)
        cell.seeds.append(values_of(job, "seed"))
        cell.counts[job.status.value] = cell.counts.get(job.status.value, 0) + 1
        brief = results.get(job.id)
        if brief is None:
            continue
        objectives, metrics = brief
        job_shown, job_maximised, row = job_values(objectives, metrics)
        if not names and job_shown:
            names = [str(n) for n in objectives["names"]]
            shown, maximised = job_shown, job_maximised
        if job.id in hv:
            row[HYPERVOLUME] = hv[job.id]
        for k in _numeric(metrics):
            if k not in metric_names and k not in job_shown:
                metric_names.append(k)
        for k, v in row.items():
            cell.samples.setdefault(k, []).append(v)
    stat_columns = [*shown, *([HYPERVOLUME] if hv else []), *metric_names]
    senses = {n: "max" if up else "min" for n, up in zip(shown, maximised, strict=True)}
    senses |= {HYPERVOLUME: "max"} if hv else {}
    senses |= {m: s for m in metric_names if m not in senses and (s := sense(m)) in ("min", "max")}
    best: dict[str, int] = {}
    for col, direction in senses.items():
        means = [(mean_sd(c.samples.get(col, []))[0], c.index) for c in cells.values()]
        scored = [(m, i) for m, i in means if m is not None]
        if len({m for m, _ in scored}) > 1:  # a tie everywhere is no "best"
            pick = max(scored) if direction == "max" else min(scored)
            best[col] = pick[1]
    return CellTable(columns, stat_columns, names, list(cells.values()), best, ref, shown)
