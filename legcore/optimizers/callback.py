"""What a run reports after every generation: `Progress`, `GenerationRecord` and the callback type.

A callback is any callable ``callback(progress) -> bool | None``. It is called once per generation
by :func:`legcore.optimizers.minimize` after the generation is told to the algorithm; returning
``True`` asks the run to stop (reason ``"callback"``), e.g. when a job is cancelled. The worker
uses it to write a progress row and to log the current front.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

__all__ = ["Batch", "Progress", "GenerationRecord", "Callback"]


@dataclass(frozen=True)
class Batch:
    """The solutions one generation evaluated (what a trial table shows).

    Attributes:
        X: ``(B, n_var)`` decision vectors.
        F: ``(B, n_obj)`` their objectives (minimised form).
        cv: ``(B,)`` their total constraint violation (0 = feasible).
    """

    X: np.ndarray
    F: np.ndarray
    cv: np.ndarray


@dataclass(frozen=True)
class Progress:
    """The state of a run after a generation.

    Attributes:
        generation: number of completed generations (1 after the initial population).
        n_evals: objective evaluations so far (rows passed to ``problem.evaluate``).
        elapsed: wall time in seconds spent in the run so far (summed over resumed sessions).
        best_x: ``(n_var,)`` the best solution so far: for one objective the lowest objective
            among the least-violating solutions; for several objectives the knee point of the
            current front (see :func:`legcore.metrics.knee_point`).
        best_f: ``(n_obj,)`` its objectives.
        best_cv: its constraint violation (0 = feasible).
        front_X: ``(k, n_var)`` the current non-dominated feasible set (the single best for one
            objective; empty while nothing feasible has been found).
        front_F: ``(k, n_obj)`` its objectives.
        batch: the solutions this generation evaluated (``None`` for a progress rebuilt
            without a step, e.g. right after a resume).
    """

    generation: int
    n_evals: int
    elapsed: float
    best_x: np.ndarray
    best_f: np.ndarray
    best_cv: float
    front_X: np.ndarray
    front_F: np.ndarray
    batch: Batch | None = None


@dataclass(frozen=True)
class GenerationRecord:
    """One row of a run's history (plain python values, JSON-able via ``to_dict``).

    ``ideal`` and ``nadir`` are the per-objective min / max over the current front (equal to
    ``best_f`` for one objective; ``nan`` while the front is empty).
    """

    generation: int
    n_evals: int
    elapsed: float
    best_f: tuple[float, ...]
    best_cv: float
    front_size: int
    ideal: tuple[float, ...]
    nadir: tuple[float, ...]

    @classmethod
    def from_progress(cls, p: Progress) -> GenerationRecord:
        """Summarise a `Progress`."""
        if p.front_F.shape[0]:
            ideal = tuple(float(v) for v in p.front_F.min(axis=0))
            nadir = tuple(float(v) for v in p.front_F.max(axis=0))
        else:
            ideal = nadir = tuple(float("nan") for _ in p.best_f)
        return cls(
            generation=int(p.generation),
            n_evals=int(p.n_evals),
            elapsed=float(p.elapsed),
            best_f=tuple(float(v) for v in p.best_f),
            best_cv=float(p.best_cv),
            front_size=int(p.front_F.shape[0]),
            ideal=ideal,
            nadir=nadir,
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain dict, strict-JSON safe (tuples as lists, ``nan`` as ``None``)."""
        return {
            "generation": self.generation,
            "n_evals": self.n_evals,
            "elapsed": self.elapsed,
            "best_f": _list(self.best_f),
            "best_cv": self.best_cv,
            "front_size": self.front_size,
            "ideal": _list(self.ideal),
            "nadir": _list(self.nadir),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> GenerationRecord:
        """Inverse of ``to_dict``."""
        return cls(
            generation=int(d["generation"]),
            n_evals=int(d["n_evals"]),
            elapsed=float(d["elapsed"]),
            best_f=_tuple(d["best_f"]),
            best_cv=float(d["best_cv"]),
            front_size=int(d["front_size"]),
            ideal=_tuple(d["ideal"]),
            nadir=_tuple(d["nadir"]),
        )


def _list(values: tuple[float, ...]) -> list[float | None]:
    return [None if v != v else v for v in values]


def _tuple(values: list[float | None]) -> tuple[float, ...]:
    return tuple(float("nan") if v is None else float(v) for v in values)


class Callback(Protocol):
    """``callback(progress)``; return ``True`` to stop the run after this generation."""

    def __call__(self, progress: Progress) -> bool | None: ...
