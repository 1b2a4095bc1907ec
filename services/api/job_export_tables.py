"""A job's final front and per-generation history as the exports' tables (``GET
/jobs/{id}/front/export``, ``GET /jobs/{id}/history/export``): columns, rows and units, each
objective once in its own sign (:func:`services.api.export_tables.shown_keys`). Pure: the route
reads the records and hands them in."""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from services.api.convergence import ConvergenceRow
from services.api.dashboard_schemas import BaselineMark
from services.api.export_tables import shown_keys, unit_of
from services.store.records import (
    BaselineRecord,
    GenerationRecord,
    JobRecord,
    ParetoPointRecord,
)

__all__ = ["ExportTable", "front_table", "history_table", "job_kind"]


@dataclass(frozen=True)
class ExportTable:
    """A download's columns, its rows (a list, or an iterator read while the file streams)
    and the ``(unit, label)`` of its columns that have one."""

    columns: list[str]
    rows: Iterable[Sequence[Any]]
    units: dict[str, tuple[str, str]]


def job_kind(job: JobRecord) -> str | None:
    """The study kind of a job (from its facts), or None."""
    facts = job.facts if isinstance(job.facts, dict) else {}
    return facts.get("kind") if isinstance(facts.get("kind"), str) else None


def _signed(values: Any, flip: list[bool]) -> list[Any]:
    return [-v if f and isinstance(v, int | float) else v
            for v, f in zip(values, flip, strict=False)]  # fmt: skip


def _pad(values: Any, n: int) -> list[Any]:
    values = list(values or [])
    return values + [None] * (n - len(values))


def front_table(
    job: JobRecord,
    names: list[str],
    points: Sequence[ParetoPointRecord],
    baselines: Sequence[BaselineRecord],
    per_point: Mapping[int, Any],
) -> ExportTable:
    """One row per front point (index, objectives by name, ``metric.<name>`` of
    ``per_point``, x1…), then one per baseline (no index, its name in ``baseline``)."""
    m = max((len(p.objectives or []) for p in points), default=len(names))
    names = names if len(names) == m else [f"f{i + 1}" for i in range(m)]
    shown, flip = shown_keys(names)
    n = max((len(p.x or []) for p in points), default=0)
    # a metric that is also an objective is the objective's column (one column per quantity)
    metrics = [k for k in dict.fromkeys(k for v in per_point.values() if v for k in v)
               if k not in shown]  # fmt: skip
    columns = ["index", *shown, *[f"metric.{k}" for k in metrics], *[f"x{i + 1}" for i in range(n)],
               "baseline"]  # fmt: skip
    kind = job_kind(job)
    units: dict[str, tuple[str, str]] = {c: unit_of(c, kind) for c in shown}
    units.update({f"metric.{k}": unit_of(k, kind) for k in metrics})
    rows = [
        (p.index, *_signed(_pad(p.objectives, m), flip),
         *[(per_point.get(p.index) or {}).get(k) for k in metrics], *_pad(p.x, n), None)
        for p in points
    ]  # fmt: skip
    for b in baselines:
        mark = BaselineMark.from_record(b, names)
        rows.append((None, *_signed(_pad(mark.objectives, m), flip),
                     *[mark.metrics.get(k) for k in metrics], *[None] * n, b.name))  # fmt: skip
    return ExportTable(columns, rows, units)


def history_table(
    job: JobRecord,
    names: list[str],
    generations: Sequence[GenerationRecord],
    conv: Sequence[ConvergenceRow],
) -> ExportTable:
    """One row per generation: evaluations, ``best_<name>`` so far, hypervolume, wall time;
    for several objectives also ``front_min_<name>`` and ``compromise_<name>``."""
    m = max(
        (len(g.best) if isinstance(g.best, list) else 1 for g in generations), default=len(names)
    )
    names = names if len(names) == m else [f"f{i + 1}" for i in range(m)]
    shown, flip = shown_keys(names)
    several = m > 1
    columns = ["generation", "n_evals", *[f"best_{n}" for n in shown], "hypervolume",
               "wall_time_s"]  # fmt: skip
    if several:
        columns += [f"front_min_{n}" for n in shown] + [f"compromise_{n}" for n in shown]
    kind = job_kind(job)
    units: dict[str, tuple[str, str]] = {"wall_time_s": ("s", "wall time of the generation")}
    for n in shown:
        unit, label = unit_of(n, kind)
        units[f"best_{n}"] = (unit, f"best {label} so far")
        units[f"front_min_{n}"] = (unit, f"least {label} on the generation's front")
        units[f"compromise_{n}"] = (unit, f"{label} of the reported compromise point")

    def rows() -> Iterator[tuple[Any, ...]]:
        for g, c in zip(generations, conv, strict=True):
            reported = _pad(g.best if isinstance(g.best, list) else [g.best], m)
            row = (g.generation, g.n_evals, *_signed(_pad(c.best_so_far, m), flip),
                   g.hypervolume, g.wall_time_s)  # fmt: skip
            if several:
                row = (*row, *_signed(_pad(c.front_min, m), flip), *_signed(reported, flip))
            yield row

    return ExportTable(columns, rows(), units)
