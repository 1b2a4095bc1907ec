"""Every evaluated solution of a job, kept for the trial table (``evaluations`` rows).

A worker stores, per generation it keeps, the solutions that generation evaluated: decision
vectors, objectives (minimised form, as the optimiser saw them) and constraint violation, as
packed float64 matrices (``services.store.front_codec``). The size bound is
``MAX_STORED_EVALUATIONS`` solutions per job: a job whose population × generations exceeds it
keeps every ``stride``-th generation (``evaluation_stride``) and always its last one, so the
table spans the whole run evenly. A resumed job re-running generations writes nothing twice
(one row per job and generation, duplicates ignored).

Writes happen in the worker's progress transaction, right after ``record_generations`` checked
the lease, so a worker that lost its job writes no rows.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from sqlalchemy import select
from sqlalchemy.orm import Session

from services.store.front_codec import decode_front_array, encode_front
from services.store.sql import insert_many_ignoring_duplicates
from services.store.tables import EVALUATIONS

#: At most this many evaluated solutions are stored per job (about 20,000 × (n_var + n_obj + 1)
#: × 8 bytes: 5 MB for 30 variables and 2 objectives).
MAX_STORED_EVALUATIONS = 20_000


@dataclass(frozen=True)
class EvaluationsIn:
    """One generation's evaluated solutions: ``X`` (n, n_var), ``F`` (n, n_obj), ``cv`` (n,)."""

    generation: int
    X: np.ndarray
    F: np.ndarray
    cv: np.ndarray


@dataclass(frozen=True)
class Evaluations:
    """A job's stored evaluations, in generation order (arrays, one row per solution).

    Attributes:
        generation: ``(N,)`` the generation that evaluated each solution (1 = initial).
        X: ``(N, n_var)`` decision vectors.
        F: ``(N, n_obj)`` objectives, minimised form (NaN where not finite).
        cv: ``(N,)`` total constraint violation (0 = feasible).
    """

    generation: np.ndarray
    X: np.ndarray
    F: np.ndarray
    cv: np.ndarray

    def __len__(self) -> int:
        return int(self.generation.shape[0])

    @classmethod
    def empty(cls, n_var: int, n_obj: int) -> Evaluations:
        """No evaluations, with ``n_var`` variables and ``n_obj`` objectives (a job that has
        stored none yet)."""
        return cls(np.zeros(0, dtype=int), np.zeros((0, n_var)), np.zeros((0, n_obj)), np.zeros(0))


def evaluation_stride(population: int, generations: int,
                      bound: int = MAX_STORED_EVALUATIONS) -> int:  # fmt: skip
    """Keep every ``stride``-th generation so that ``population × generations / stride``
    solutions fit in ``bound`` (1: every generation)."""
    total = max(1, int(population)) * max(1, int(generations))
    return max(1, -(-total // max(1, int(bound))))


def keeps_generation(generation: int, stride: int, last: bool) -> bool:
    """True if generation ``generation`` (1-based) is stored: the first, every ``stride``-th
    after it, and the run's last (``last``)."""
    return last or (int(generation) - 1) % max(1, int(stride)) == 0


def record_evaluations(session: Session, job_id: str, batches: Sequence[EvaluationsIn]) -> None:
    """Insert the generations' evaluated solutions in one statement (already-stored generations
    are skipped). Call in the transaction whose ``record_generations`` checked the lease."""
    rows = []
    for b in batches:
        X = np.atleast_2d(np.asarray(b.X, dtype=float))
        if X.shape[0] == 0:
            continue
        F = np.atleast_2d(np.asarray(b.F, dtype=float))
        cv = np.asarray(b.cv, dtype=float).reshape(-1, 1)
        rows.append({
            "job_id": job_id,
            "generation": int(b.generation),
            "n": int(X.shape[0]),
            "x_packed": encode_front(X),
            "f_packed": encode_front(F),
            "cv_packed": encode_front(cv),
        })
    insert_many_ignoring_duplicates(session, EVALUATIONS, rows, ("job_id", "generation"))


def load_evaluations(session: Session, job_id: str) -> Evaluations | None:
    """Every stored evaluation of a job, or None when it has none (a job stored before they
    were kept, or one that has not finished a kept generation yet)."""
    rows = session.execute(
        select(
            EVALUATIONS.c.generation,
            EVALUATIONS.c.x_packed,
            EVALUATIONS.c.f_packed,
            EVALUATIONS.c.cv_packed,
        )
        .where(EVALUATIONS.c.job_id == job_id)
        .order_by(EVALUATIONS.c.generation)
    ).all()
    if not rows:
        return None
    xs = [decode_front_array(r.x_packed) for r in rows]
    return Evaluations(
        generation=np.concatenate(
            [np.full(x.shape[0], int(r.generation)) for r, x in zip(rows, xs, strict=True)]
        ),
        X=np.concatenate(xs),
        F=np.concatenate([decode_front_array(r.f_packed) for r in rows]),
        cv=np.concatenate([decode_front_array(r.cv_packed)[:, 0] for r in rows]),
    )


__all__ = [
    "MAX_STORED_EVALUATIONS",
    "Evaluations",
    "EvaluationsIn",
    "evaluation_stride",
    "keeps_generation",
    "load_evaluations",
    "record_evaluations",
]
