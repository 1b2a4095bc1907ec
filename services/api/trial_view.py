"""A job's stored evaluations as the trial table, the parallel-coordinates plot and the
importance view read them: filter, sort, page, sample. Pure (arrays in, response models out);
the route reads ``services.store.evaluations.load_evaluations`` and hands it in (``trial_set``).

Columns are named as on the dashboard: ``trial``, ``generation``, ``cv``, ``f1``… (objectives
in the front's order, also by their result key, e.g. ``T_1``) and ``x1``… (variables).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from services.api.dashboard_schemas import Quantity, quantities
from services.api.trial_schemas import TrialColumns, TrialOut, TrialPage, TrialsMeta
from services.store.evaluations import MAX_STORED_EVALUATIONS, Evaluations
from services.store.records import JobRecord


class TrialQueryError(ValueError):
    """A filter or sort the trials cannot answer; ``field`` names the query parameter."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field


@dataclass(frozen=True)
class ValueRange:
    """Keep trials whose ``column`` lies in ``[low, high]`` (None: unbounded)."""

    column: str
    low: float | None
    high: float | None


def parse_range(text: str) -> ValueRange:
    """``"f1:0:2.5"``, ``"x3:-1:"`` or ``"cv::0"`` as a `ValueRange`."""
    parts = text.split(":")
    if len(parts) != 3 or not parts[0]:
        raise TrialQueryError("range", f"range {text!r}: write COLUMN:LOW:HIGH, e.g. f1:0:2.5 "
                              "(leave LOW or HIGH empty for no bound)")  # fmt: skip
    bounds: list[float | None] = []
    for p in parts[1:]:
        try:
            v = float(p) if p.strip() else None
        except ValueError:
            raise TrialQueryError("range", f"range {text!r}: {p!r} is not a number") from None
        if v is not None and not math.isfinite(v):
            raise TrialQueryError("range", f"range {text!r}: bounds must be finite")
        bounds.append(v)
    return ValueRange(parts[0], bounds[0], bounds[1])


@dataclass(frozen=True)
class TrialSet:
    """A job's evaluations with their column names (objective keys in the front's order)."""

    job_id: str
    ev: Evaluations
    objective_names: tuple[str, ...]
    kind: str | None = None

    def objectives(self) -> list[Quantity]:
        names = list(self.objective_names)
        if len(names) != self.ev.F.shape[1]:
            names = [f"f{j + 1}" for j in range(self.ev.F.shape[1])]
        return quantities(names, self.kind)

    def variables(self) -> list[Quantity]:
        n = self.ev.X.shape[1]
        return [Quantity(name=f"x{i + 1}", label=f"x{i + 1}", unit="", axis=f"x{i + 1}")
                for i in range(n)]  # fmt: skip

    def column(self, name: str, field: str) -> np.ndarray:
        """The values of column ``name`` (see the module docstring); TrialQueryError names
        ``field`` for an unknown one."""
        ev = self.ev
        if name == "trial":
            return np.arange(len(ev), dtype=float)
        if name == "generation":
            return ev.generation.astype(float)
        if name == "cv":
            return ev.cv
        m, n = ev.F.shape[1], ev.X.shape[1]
        if name in self.objective_names and len(self.objective_names) == m:
            return ev.F[:, self.objective_names.index(name)]
        for prefix, count, data in (("f", m, ev.F), ("x", n, ev.X)):
            digits = name[1:]
            ascii_number = digits.isascii() and digits.isdigit()
            if name.startswith(prefix) and ascii_number and 1 <= int(digits) <= count:
                return data[:, int(digits) - 1]
        known = ["trial", "generation", "cv", f"f1…f{m}", f"x1…x{n}", *self.objective_names]
        raise TrialQueryError(field, f"no column {name!r}; columns: {', '.join(known)}")

    def meta(self) -> dict[str, object]:
        return {
            "job_id": self.job_id,
            "objectives": self.objectives(),
            "variables": self.variables(),
            "stored": len(self.ev),
            "bound": MAX_STORED_EVALUATIONS,
            "generations": sorted({int(g) for g in self.ev.generation.tolist()}),
        }


def trial_set(job: JobRecord, ev: Evaluations | None) -> TrialSet:
    """The trials of ``job`` from its stored evaluations (None: none stored yet, an empty set
    of the job's width), named by the objectives of the job's facts."""
    facts = job.facts if isinstance(job.facts, dict) else {}
    names = tuple(str(n) for n in facts.get("objectives") or ())
    kind = facts.get("kind") if isinstance(facts.get("kind"), str) else None
    if ev is None:
        ev = Evaluations.empty(int(facts.get("n_var") or 0), len(names))
    return TrialSet(job.id, ev, names, kind)


def matching(
    trials: TrialSet,
    feasible: bool | None,
    generation: int | None,
    ranges: Sequence[str] | None,
) -> np.ndarray:
    """Indices of the trials that pass the query's filters (``ranges`` as written,
    :func:`parse_range`), in trial order; TrialQueryError names a bad one."""
    parsed = [parse_range(r) for r in ranges or ()]
    return select(trials, feasible=feasible, generation=generation, ranges=parsed)


def select(
    trials: TrialSet,
    *,
    feasible: bool | None = None,
    generation: int | None = None,
    ranges: Sequence[ValueRange] = (),
) -> np.ndarray:
    """Indices of the trials that pass every filter, in trial order."""
    keep = np.ones(len(trials.ev), dtype=bool)
    if feasible is not None:
        keep &= (trials.ev.cv <= 0.0) == feasible
    if generation is not None:
        keep &= trials.ev.generation == generation
    for r in ranges:
        values = trials.column(r.column, "range")
        with np.errstate(invalid="ignore"):
            if r.low is not None:
                keep &= values >= r.low
            if r.high is not None:
                keep &= values <= r.high
    return np.flatnonzero(keep)


def order(trials: TrialSet, idx: np.ndarray, sort: str, descending: bool) -> np.ndarray:
    """``idx`` sorted by column ``sort`` (stable; trials without a finite value last)."""
    values = trials.column(sort, "sort")[idx]
    key = -values if descending else values
    key = np.where(np.isfinite(key), key, np.inf)
    return idx[np.argsort(key, kind="stable")]


def _cells(values: np.ndarray) -> list[Any]:
    """``values`` as (nested) lists of floats, None (JSON null) where not finite."""
    cells = values.astype(object)
    cells[~np.isfinite(values)] = None
    return cells.tolist()


def trial_rows(trials: TrialSet, idx: np.ndarray) -> list[TrialOut]:
    """The trials ``idx`` as rows."""
    ev = trials.ev
    cv = ev.cv[idx]
    return [
        TrialOut(trial=i, generation=g, x=x, objectives=f, cv=c, feasible=ok)
        for i, g, x, f, c, ok in zip(
            idx.tolist(), ev.generation[idx].tolist(), _cells(ev.X[idx]), _cells(ev.F[idx]),
            cv.tolist(), (cv <= 0.0).tolist(), strict=True,
        )
    ]  # fmt: skip


def trial_page(
    trials: TrialSet, idx: np.ndarray, *, sort: str, descending: bool, offset: int, limit: int
) -> TrialPage:
    """One page of the filtered trials ``idx`` sorted by ``sort``."""
    ordered = order(trials, idx, sort, descending)
    return TrialPage(
        **trials.meta(),  # type: ignore[arg-type]
        matched=int(idx.size),
        offset=offset,
        limit=limit,
        sort=sort,
        descending=descending,
        items=trial_rows(trials, ordered[offset : offset + limit]),
    )


def sample(idx: np.ndarray, max_rows: int) -> np.ndarray:
    """At most ``max_rows`` of ``idx``, evenly strided (the last always kept)."""
    if idx.size <= max_rows:
        return idx
    pick = np.unique(np.linspace(0, idx.size - 1, max_rows).round().astype(int))
    return idx[pick]


def trial_columns(trials: TrialSet, idx: np.ndarray, max_rows: int) -> TrialColumns:
    """Columns of at most ``max_rows`` of the filtered trials ``idx``."""
    ev = trials.ev
    picked = sample(idx, max_rows)
    return TrialColumns(
        **trials.meta(),  # type: ignore[arg-type]
        matched=int(idx.size),
        trial=picked.tolist(),
        feasible=(ev.cv[picked] <= 0.0).tolist(),
        x_values=_cells(ev.X[picked].T),
        objective_values=_cells(ev.F[picked].T),
    )


def meta_only(trials: TrialSet) -> TrialsMeta:
    """What the job's trials are, without rows."""
    return TrialsMeta(**trials.meta())  # type: ignore[arg-type]


__all__ = [
    "TrialQueryError",
    "TrialSet",
    "ValueRange",
    "matching",
    "meta_only",
    "order",
    "parse_range",
    "sample",
    "select",
    "trial_columns",
    "trial_page",
    "trial_rows",
    "trial_set",
]
