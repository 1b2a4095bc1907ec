"""Driving an algorithm on a problem: `Run` (step by step, checkpointable) and `minimize`.

``minimize`` is the one-call form::

    result = minimize(problem, get_algorithm("ga"), MaxGenerations(100), seed=1)
    result.x, result.F, result.front_F, result.history

``Run`` is the same loop one generation at a time, for a worker that reports progress, saves
checkpoints and resumes::

    run = Run(problem, algorithm, termination, seed=job.seed, state=saved_or_None)
    while not run.done:
        progress = run.step()
        store_progress(progress)
        if progress.generation % 5 == 0:
            store_checkpoint(to_jsonable(run.state_dict()))
    result = run.result()

A run resumed from ``run.state_dict()`` (taken after any generation) produces the same result,
bit for bit, as the uninterrupted run (wall-time fields aside).

Run state format (``Run.state_dict()``): ``{"format": "legcore.run", "version": 1, "seed",
"elapsed", "stop_reason", "history": [GenerationRecord.to_dict(), ...], "algorithm":
Algorithm.state_dict()}``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from legcore.optimizers.base import Algorithm, from_jsonable
from legcore.optimizers.callback import Batch, Callback, GenerationRecord, Progress
from legcore.optimizers.termination import Termination
from legcore.problems.base import Problem, constraint_violation

__all__ = ["Result", "Run", "minimize"]

RUN_FORMAT = "legcore.run"
RUN_VERSION = 1


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.flags.writeable = False
    return a


@dataclass(frozen=True)
class Result:
    """The outcome of a run (arrays are read-only).

    Attributes:
        x: ``(n_var,)`` best solution (one objective: the best found; several: the knee point
            of the final front, or the least-violating solution if nothing feasible was found).
        F: ``(n_obj,)`` its objectives.
        cv: its constraint violation (0 = feasible).
        front_X, front_F: the final non-dominated feasible set ``(k, n_var)`` / ``(k, n_obj)``
            (MOEA/D: its external archive; NSGA-II: the first front of the population; one
            objective: the best solution if feasible).
        history: one `GenerationRecord` per generation.
        initial_x, initial_f, initial_cv: the best of the first generation (the initial
            population) — where the optimiser started, so that a result can say what it earned
            (``None`` for a run resumed from a checkpoint that predates them).
        n_gen, n_evals, elapsed: generations, evaluations and wall time (s) spent.
        reason: why the run stopped.
        algorithm, params, seed: what produced it.
    """

    x: np.ndarray
    F: np.ndarray
    cv: float
    front_X: np.ndarray
    front_F: np.ndarray
    history: tuple[GenerationRecord, ...]
    n_gen: int
    n_evals: int
    elapsed: float
    reason: str
    algorithm: str
    params: dict[str, Any]
    seed: int | None
    initial_x: np.ndarray | None = None
    initial_f: np.ndarray | None = None
    initial_cv: float | None = None

    @property
    def feasible(self) -> bool:
        """True when ``x`` satisfies every constraint."""
        return self.cv <= 0.0


class Run:
    """One optimisation run, advanced a generation at a time.

    Args:
        problem: the problem (evaluated one whole batch per generation).
        algorithm: a fresh or reusable algorithm; ``Run`` calls ``algorithm.setup``.
        termination: stopping rule; ``None`` uses ``algorithm.default_termination()``.
        seed: integer seed (recorded in the result) or ``None`` for fresh entropy.
        state: a ``Run.state_dict()`` (or its ``to_jsonable`` form) to resume from.
    """

    def __init__(
        self,
        problem: Problem,
        algorithm: Algorithm,
        termination: Termination | None = None,
        *,
        seed: int | None = None,
        state: dict[str, Any] | None = None,
    ) -> None:
        if not isinstance(algorithm, Algorithm):
            raise ValueError(f"algorithm: expected an Algorithm, got {type(algorithm).__name__}")
        if termination is None:
            termination = algorithm.default_termination()
        if not isinstance(termination, Termination):
            raise ValueError(f"termination: expected a Termination, "
                             f"got {type(termination).__name__}")
        if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int | np.integer)):
            raise ValueError(f"seed: expected an integer or None, got {seed!r}")
        self.problem = problem
        self.algorithm = algorithm
        self.termination = termination
        self.seed = None if seed is None else int(seed)
        self._history: list[GenerationRecord] = []
        self._elapsed = 0.0
        self._reason: str | None = None
        self._progress: Progress | None = None
        self._initial: tuple[np.ndarray, np.ndarray, float] | None = None
        algorithm.setup(problem, self.seed)
        if state is not None:
            self._load(from_jsonable(state))

    # ------------------------------------------------------------------ stepping
    @property
    def done(self) -> bool:
        """True once a termination rule, the algorithm itself or ``stop()`` ended the run."""
        return self._reason is not None

    @property
    def reason(self) -> str | None:
        """Why the run stopped, or ``None`` while it runs."""
        return self._reason

    @property
    def history(self) -> tuple[GenerationRecord, ...]:
        """One record per completed generation."""
        return tuple(self._history)

    def stop(self, reason: str) -> None:
        """End the run now (e.g. cancelled by the user)."""
        if self._reason is None:
            self._reason = str(reason)

    def step(self) -> Progress:
        """Run one generation: ask, evaluate the whole batch once, tell, check termination."""
        if self._reason is not None:
            raise RuntimeError(f"step: the run has stopped ({self._reason})")
        t0 = time.perf_counter()
        algo = self.algorithm
        X = algo.ask()
        F, G = self.problem.evaluate(X)
        algo.tell(X, F, G)
        progress = self._make_progress(
            self._elapsed + (time.perf_counter() - t0), Batch(X, F, constraint_violation(G))
        )
        if self._initial is None and not self._history:
            self._initial = (progress.best_x.copy(), progress.best_f.copy(), progress.best_cv)
        self._elapsed = progress.elapsed
        self._history.append(GenerationRecord.from_progress(progress))
        self._progress = progress
        self._reason = algo.stop_reason or self.termination.check(progress, self._history)
        return progress

    def progress(self) -> Progress:
        """The `Progress` after the last completed generation."""
        if self._progress is None:
            if self.algorithm.generation == 0:
                raise RuntimeError("progress: no generation has been run yet")
            self._progress = self._make_progress(self._elapsed)
        return self._progress

    def result(self) -> Result:
        """The `Result` so far (normally called once ``done``)."""
        p = self.progress()
        return Result(
            x=_frozen(p.best_x),
            F=_frozen(p.best_f),
            cv=float(p.best_cv),
            front_X=_frozen(p.front_X),
            front_F=_frozen(p.front_F),
            history=tuple(self._history),
            n_gen=self.algorithm.generation,
            n_evals=self.algorithm.n_evals,
            elapsed=self._elapsed,
            reason=self._reason or "not finished",
            algorithm=self.algorithm.kind,
            params=self.algorithm.params,
            seed=self.seed,
            initial_x=None if self._initial is None else _frozen(self._initial[0]),
            initial_f=None if self._initial is None else _frozen(self._initial[1]),
            initial_cv=None if self._initial is None else float(self._initial[2]),
        )

    # ------------------------------------------------------------------ checkpoint
    def state_dict(self) -> dict[str, Any]:
        """A checkpoint of the run (algorithm state + history); see the module docstring."""
        return {
            "format": RUN_FORMAT,
            "version": RUN_VERSION,
            "seed": self.seed,
            "elapsed": self._elapsed,
            "stop_reason": self._reason,
            "history": [r.to_dict() for r in self._history],
            "algorithm": self.algorithm.state_dict(),
            "initial": None if self._initial is None else {
                "x": self._initial[0], "f": self._initial[1], "cv": self._initial[2]
            },
        }

    def _load(self, state: dict[str, Any]) -> None:
        if not isinstance(state, dict) or state.get("format") != RUN_FORMAT:
            raise ValueError("state: not a legcore run state (Run.state_dict())")
        if state.get("version") != RUN_VERSION:
            raise ValueError(f"state: unsupported run state version {state.get('version')!r}")
        saved_seed = state.get("seed")
        if self.seed is not None and saved_seed is not None and int(saved_seed) != self.seed:
            raise ValueError(f"seed: the state was saved with seed {saved_seed}, got {self.seed}")
        if self.seed is None and saved_seed is not None:
            self.seed = int(saved_seed)
        self.algorithm.load_state_dict(state["algorithm"])
        self._history = [GenerationRecord.from_dict(d) for d in state["history"]]
        self._elapsed = float(state["elapsed"])
        self._reason = state.get("stop_reason")
        self._progress = None
        init = state.get("initial")
        self._initial = None if not init else (
            np.asarray(init["x"], dtype=float), np.asarray(init["f"], dtype=float),
            float(init["cv"]),
        )

    def _make_progress(self, elapsed: float, batch: Batch | None = None) -> Progress:
        algo = self.algorithm
        x, f, cv = algo.best()
        front_X, front_F = algo.front()
        return Progress(
            generation=algo.generation,
            n_evals=algo.n_evals,
            elapsed=elapsed,
            best_x=x,
            best_f=f,
            best_cv=cv,
            front_X=front_X,
            front_F=front_F,
            batch=batch,
        )


def minimize(
    problem: Problem,
    algorithm: Algorithm,
    termination: Termination | None = None,
    *,
    seed: int | None = None,
    callback: Callback | None = None,
    state: dict[str, Any] | None = None,
    checkpoint: Callable[[dict[str, Any]], None] | None = None,
    checkpoint_every: int = 1,
) -> Result:
    """Minimise ``problem`` with ``algorithm`` until ``termination`` fires.

    Args:
        problem: the problem; evaluated as one batch per generation.
        algorithm: from ``get_algorithm``; it is set up (reset) by this call.
        termination: e.g. ``MaxGenerations(100) | MaxTime(60)``; ``None`` uses the algorithm's
            default (100 generations; HKA also stops on its own spread rule).
        seed: integer seed; the same seed gives the same result.
        callback: ``callback(progress)`` after every generation; returning ``True`` stops the run.
        state: a ``Run.state_dict()`` (or its JSON form) to resume from.
        checkpoint: ``checkpoint(run_state)`` every ``checkpoint_every`` generations and at the
            end; ``run_state`` is ``Run.state_dict()`` (use ``to_jsonable`` to store it as JSON).
        checkpoint_every: generations between checkpoints (>= 1).

    Returns:
        The frozen `Result`.
    """
    if isinstance(checkpoint_every, bool) or not isinstance(checkpoint_every, int) \
            or checkpoint_every < 1:
        raise ValueError(f"checkpoint_every: expected an integer >= 1, got {checkpoint_every!r}")
    run = Run(problem, algorithm, termination, seed=seed, state=state)
    while not run.done:
        progress = run.step()
        if callback is not None and callback(progress) is True:
            run.stop("stopped by the callback")
        if checkpoint is not None and (run.done or progress.generation % checkpoint_every == 0):
            checkpoint(run.state_dict())
    return run.result()
