"""When a run stops: by generations, evaluations, wall time or objective tolerance; combinable.

A termination is a stateless rule over the run's `Progress` and history, so a resumed run stops
exactly where the uninterrupted one would (wall time is accumulated across sessions by the run).
Combine rules with ``|`` (stop when any fires) and ``&`` (stop when all fire)::

    MaxGenerations(100) | MaxTime(600.0)

Budgets are checked after each generation, so an evaluation budget can be exceeded by at most
one generation (the same as pymoo).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence

import numpy as np

from legcore.optimizers.callback import GenerationRecord, Progress

__all__ = [
    "Termination",
    "MaxGenerations",
    "MaxEvaluations",
    "MaxTime",
    "Tolerance",
    "AnyOf",
    "AllOf",
    "termination_from_budget",
]


class Termination(ABC):
    """A stopping rule. ``check`` returns a human-readable reason to stop, or ``None``."""

    @abstractmethod
    def check(self, progress: Progress, history: Sequence[GenerationRecord]) -> str | None:
        """Reason to stop after the generation described by ``progress``, or ``None``."""

    def __or__(self, other: Termination) -> AnyOf:
        return AnyOf(self, other)

    def __and__(self, other: Termination) -> AllOf:
        return AllOf(self, other)


def _positive_int(name: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ValueError(f"{name}: expected an integer >= 1, got {value!r}")
    return int(value)


def _positive_float(name: str, value: float, allow_zero: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise ValueError(f"{name}: expected a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value) or value < 0 or (value == 0 and not allow_zero):
        raise ValueError(f"{name}: expected a finite number {'>=' if allow_zero else '>'} 0, "
                         f"got {value!r}")
    return value


class MaxGenerations(Termination):
    """Stop after ``n_gen`` generations (the initial population counts as generation 1)."""

    def __init__(self, n_gen: int) -> None:
        self.n_gen = _positive_int("n_gen", n_gen)

    def check(self, progress: Progress, history: Sequence[GenerationRecord]) -> str | None:
        if progress.generation >= self.n_gen:
            return f"reached {self.n_gen} generations"
        return None

    def __repr__(self) -> str:
        return f"MaxGenerations({self.n_gen})"


class MaxEvaluations(Termination):
    """Stop once ``n_evals`` objective evaluations have been spent."""

    def __init__(self, n_evals: int) -> None:
        self.n_evals = _positive_int("n_evals", n_evals)

    def check(self, progress: Progress, history: Sequence[GenerationRecord]) -> str | None:
        if progress.n_evals >= self.n_evals:
            return f"reached {self.n_evals} evaluations"
        return None

    def __repr__(self) -> str:
        return f"MaxEvaluations({self.n_evals})"


class MaxTime(Termination):
    """Stop once ``seconds`` of wall time have been spent (summed over resumed sessions)."""

    def __init__(self, seconds: float) -> None:
        self.seconds = _positive_float("seconds", seconds)

    def check(self, progress: Progress, history: Sequence[GenerationRecord]) -> str | None:
        if progress.elapsed >= self.seconds:
            return f"reached the time limit of {self.seconds:g} s"
        return None

    def __repr__(self) -> str:
        return f"MaxTime({self.seconds})"


class Tolerance(Termination):
    """Stop when the objectives have stalled for ``window`` consecutive generations.

    Stalled means: between every two consecutive generations of the last ``window + 1``, each
    tracked value changed by at most ``ftol`` (absolute). Tracked values: ``best_f`` and
    ``best_cv`` for one objective; the front's ``ideal`` and ``nadir`` for several. This is the
    stopping rule of seed 001 (10 consecutive iterations with changes below a threshold).
    """

    def __init__(self, ftol: float = 1e-6, window: int = 10) -> None:
        self.ftol = _positive_float("ftol", ftol, allow_zero=True)
        self.window = _positive_int("window", window)

    @staticmethod
    def _tracked(rec: GenerationRecord) -> np.ndarray:
        if len(rec.best_f) == 1:
            return np.array([*rec.best_f, rec.best_cv])
        return np.array([*rec.ideal, *rec.nadir])

    def check(self, progress: Progress, history: Sequence[GenerationRecord]) -> str | None:
        if len(history) < self.window + 1:
            return None
        values = np.array([self._tracked(r) for r in history[-(self.window + 1):]])
        if not np.all(np.isfinite(values)):
            return None
        if np.all(np.abs(np.diff(values, axis=0)) <= self.ftol):
            return f"objectives changed by at most {self.ftol:g} over {self.window} generations"
        return None

    def __repr__(self) -> str:
        return f"Tolerance(ftol={self.ftol}, window={self.window})"


class AnyOf(Termination):
    """Stop as soon as any of the rules fires (reason: the first that fired)."""

    def __init__(self, *rules: Termination) -> None:
        if not rules or not all(isinstance(r, Termination) for r in rules):
            raise ValueError("rules: expected one or more Termination instances")
        self.rules = tuple(rules)

    def check(self, progress: Progress, history: Sequence[GenerationRecord]) -> str | None:
        for rule in self.rules:
            reason = rule.check(progress, history)
            if reason is not None:
                return reason
        return None

    def __repr__(self) -> str:
        return " | ".join(repr(r) for r in self.rules)


class AllOf(Termination):
    """Stop when every rule fires at the same generation (reasons joined with ``and``)."""

    def __init__(self, *rules: Termination) -> None:
        if not rules or not all(isinstance(r, Termination) for r in rules):
            raise ValueError("rules: expected one or more Termination instances")
        self.rules = tuple(rules)

    def check(self, progress: Progress, history: Sequence[GenerationRecord]) -> str | None:
        reasons = [rule.check(progress, history) for rule in self.rules]
        if all(r is not None for r in reasons):
            return " and ".join(r for r in reasons if r is not None)
        return None

    def __repr__(self) -> str:
        return " & ".join(repr(r) for r in self.rules)


def termination_from_budget(
    n_gen: int | None = None,
    n_evals: int | None = None,
    seconds: float | None = None,
    ftol: float | None = None,
    window: int = 10,
) -> Termination:
    """Build ``AnyOf`` of the given limits (at least one is required), e.g. from a job spec."""
    rules: list[Termination] = []
    if n_gen is not None:
        rules.append(MaxGenerations(n_gen))
    if n_evals is not None:
        rules.append(MaxEvaluations(n_evals))
    if seconds is not None:
        rules.append(MaxTime(seconds))
    if ftol is not None:
        rules.append(Tolerance(ftol, window))
    if not rules:
        raise ValueError("budget: give at least one of n_gen, n_evals, seconds, ftol")
    return rules[0] if len(rules) == 1 else AnyOf(*rules)
