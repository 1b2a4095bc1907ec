"""What a running job keeps of each generation besides its progress row: the evaluated
solutions stored for the trial table (``TrialKeeper``, bounded by
``services.store.evaluations.MAX_STORED_EVALUATIONS``) and the thinned Pareto fronts its
recording draws (``thin_front``, ``recording_fronts``). Objective values are in the study's
units (minimised form)."""

from __future__ import annotations

from typing import Any

import numpy as np

from legcore.runner import job_shape
from services.store.evaluations import (
    MAX_STORED_EVALUATIONS,
    EvaluationsIn,
    evaluation_stride,
    keeps_generation,
)
from services.store.output_queries import list_generations
from services.store.session import session_scope


class TrialKeeper:
    """The generations' evaluated solutions to store (``services.store.evaluations``): every
    ``stride``-th generation and the last, at most ``MAX_STORED_EVALUATIONS`` solutions plus
    the last generation's."""

    def __init__(self, prepared: Any) -> None:
        self.stride = evaluation_stride(*job_shape(prepared))
        self.kept = 0
        self.pending: list[EvaluationsIn] = []

    def add(self, progress: Any, *, last: bool) -> None:
        batch = progress.batch
        if batch is None or not keeps_generation(progress.generation, self.stride, last):
            return
        n = int(batch.X.shape[0])
        if not last and self.kept + n > MAX_STORED_EVALUATIONS:
            return
        self.kept += n
        self.pending.append(EvaluationsIn(progress.generation, batch.X, batch.F, batch.cv))

    def take(self) -> list[EvaluationsIn]:
        out, self.pending = self.pending, []
        return out


MAX_FRONT_POINTS = 300


def thin_front(F: Any) -> Any:
    """The objective vectors of a front, at most ``MAX_FRONT_POINTS`` (evenly strided, plus
    the point of least value of each objective, so that the stored front's per-objective
    minimum is the whole front's: the dashboard's best-so-far curves are read from it), as a
    float (k, m) array (NaN where not finite: what the store keeps), or None for a
    single-objective run (its front is just the best point)."""
    F = np.asarray(F, dtype=float)
    if F.ndim != 2 or F.shape[1] < 2 or F.shape[0] == 0:
        return None
    if F.shape[0] > MAX_FRONT_POINTS:
        finite = np.where(np.isfinite(F), F, np.inf)
        extremes = {int(np.argmin(finite[:, j])) for j in range(F.shape[1])}
        n = max(MAX_FRONT_POINTS - len(extremes), 2)
        strided = set(np.linspace(0, F.shape[0] - 1, n).round().astype(int).tolist())
        F = F[sorted(strided | extremes)]  # at most MAX_FRONT_POINTS rows
    return np.where(np.isfinite(F), F, np.nan)


def recording_fronts(
    job_id: str, resumed_from: int | None, fronts: dict[int, Any]
) -> dict[int, Any] | None:
    """{generation: F} of every generation with a front, across resumes: this attempt's from
    memory; a resumed job reads those of its earlier attempts (up to its checkpoint) back."""
    out: dict[int, Any] = {}
    if resumed_from is not None:
        after: int | None = None
        with session_scope() as s:
            while True:
                rows = list_generations(s, job_id, after=after, limit=1000)
                out.update(
                    (g.generation, np.asarray(g.front, dtype=float))
                    for g in rows
                    if g.front and g.generation <= resumed_from
                )
                if len(rows) < 1000 or rows[-1].generation >= resumed_from:
                    break
                after = rows[-1].generation
    out.update((g, np.asarray(F, dtype=float)) for g, F in fronts.items())
    return out or None
