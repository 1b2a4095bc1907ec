"""Convergence of a job, as its page and its history export show it: the best value of each
objective found so far, per generation.

What a generation row stores as ``best`` is the optimiser's *reported* solution: for one
objective the incumbent (already the best so far, feasibility first), but for several
objectives the knee — the compromise point — of the current front (``legcore`` ``Progress
.best_f``), whose coordinates can get worse from one generation to the next as the front
spreads (a best cycle time rising 10 → 13 s). The best of each objective so far is instead the
running minimum, over generations, of the minimum of each generation's front
(``front_min``), read from the stored fronts: the worker keeps every objective's extreme
point when it thins a front (``services.worker.generation_keep.thin_front``), so that minimum is the
whole front's; for rows written before it did, it is that of the thinned front.

Values are shown as stored: every objective is minimised (an objective ``neg_<m>`` is the
negation of a maximised quantity and is labelled so), so the best is always the least.

A page after generation ``a`` continues from the running minimum at ``a``, read back from the
stored fronts (``output_queries.best_front_minimum``: their packed bytes, no Python lists).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from sqlalchemy.orm import Session

from services.store import output_queries as oq
from services.store.records import GenerationRecord

__all__ = ["ConvergenceRow", "convergence"]


@dataclass(frozen=True)
class ConvergenceRow:
    """One generation's ``front_min`` (its front's least value of each objective; None
    without a stored front) and ``best_so_far`` (the least value of each objective over the
    fronts so far; for one objective the stored incumbent)."""

    front_min: list[float | None] | None
    best_so_far: list[float | None] | None


def _values(best: Any) -> list[float]:
    items = best if isinstance(best, list | tuple) else [best]
    return [float(v) if isinstance(v, int | float) else float("nan") for v in items]


def _json(a: np.ndarray | None) -> list[float | None] | None:
    if a is None:
        return None
    return [float(v) if np.isfinite(v) else None for v in a]


def convergence(
    session: Session, job_id: str, rows: Sequence[GenerationRecord], *, after: int | None
) -> list[ConvergenceRow]:
    """The convergence of ``rows``, the generations of job ``job_id`` after ``after`` in
    order (the running minimum starts from the stored fronts up to ``after``)."""
    if not rows:
        return []
    several = max(len(_values(g.best)) for g in rows) > 1 or any(g.front for g in rows)
    if not several:  # one objective: the stored best is the incumbent, the best so far
        return [ConvergenceRow(None, _json(np.asarray(_values(g.best)))) for g in rows]
    running = None if after is None else oq.best_front_minimum(session, job_id, upto=after)
    out = []
    for g in rows:
        low = oq.front_minimum(g.front)
        running = oq.fold_minimum(running, low)
        out.append(ConvergenceRow(_json(low), _json(running)))
    return out
