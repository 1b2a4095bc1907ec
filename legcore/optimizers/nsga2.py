"""NSGA-II (Deb, Pratap, Agarwal & Meyarivan 2002), vectorised, for comparison with MOEA/D.

Per generation:

1. **Mating selection**: binary tournaments between contestants paired off from random
   permutations of the population (each individual fights twice per generation): the lower
   constraint violation wins; between feasible ones, the Pareto-dominating one, else the larger
   crowding distance (pymoo's ``comp_by_dom_and_crowding``; Deb 2002 compares ranks instead —
   dominance between the two contestants kept ZDT2 runs from collapsing in our tests).
2. **Variation**: SBX (``eta_c = 15``, probability 0.9 per pair, 0.5 per variable) and polynomial
   mutation (``eta_m = 20``, probability ``1 / n_var`` per variable) — Deb 2002's settings and
   pymoo's NSGA2 defaults, except that pymoo mutates an offspring only with probability 0.9
   (``prob_mutant=0.9`` here).
   Integer-coded problems are rounded to the grid.
3. **Evaluation** of the ``pop_size`` offspring as one batch.
4. **Survival**: parents and offspring merged, sorted into fronts (Deb's constrained domination:
   feasible first, infeasible by increasing violation), fronts added in order, the last one
   truncated by decreasing crowding distance (computed once on that front; ties keep the
   earlier index). The survivors keep the crowding distance of their whole front for the next
   tournament (Deb 2002; pymoo does the same).

Offspring identical to a parent or to an earlier offspring are discarded and re-drawn (up to 10
rounds), as pymoo does; duplicates would let a run collapse onto clones (ZDT2). The front
reported is the first front of the population restricted to feasible points, without duplicates.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from legcore.optimizers.base import Algorithm
from legcore.optimizers.nsga2_kernels import (
    novel_rows_kernel,
    survivors_kernel,
    tournament_kernel,
    unique_rows_kernel,
)
from legcore.optimizers.operators import polynomial_mutation, sbx
from legcore.optimizers.params import check_float, check_int, check_optional_float

__all__ = ["NSGA2"]

_MAX_ROUNDS = 10


class NSGA2(Algorithm):
    """NSGA-II with SBX + polynomial mutation (any number of objectives, constraints allowed).

    Args:
        pop_size: population and offspring size (>= 4, even or odd). Default 100.
        eta_c: SBX distribution index. Default 15.
        prob_crossover: probability that a pair is crossed. Default 0.9.
        prob_var_crossover: per-variable SBX probability within a crossed pair. Default 0.5.
        eta_m: polynomial mutation distribution index. Default 20.
        prob_mutation: per-variable mutation probability; ``None`` = ``1 / n_var``.
        prob_mutant: probability that an offspring is mutated at all. Default 1 (Deb 2002);
            pymoo's NSGA2 uses 0.9.
    """

    kind: ClassVar[str] = "nsga2"
    n_obj_range: ClassVar[tuple[int, int | None]] = (1, None)

    def __init__(
        self,
        pop_size: int = 100,
        eta_c: float = 15.0,
        prob_crossover: float = 0.9,
        prob_var_crossover: float = 0.5,
        eta_m: float = 20.0,
        prob_mutation: float | None = None,
        prob_mutant: float = 1.0,
    ) -> None:
        super().__init__()
        self._params = {
            "pop_size": check_int("pop_size", pop_size, 4),
            "eta_c": check_float("eta_c", eta_c, 0.0, low_open=True),
            "prob_crossover": check_float("prob_crossover", prob_crossover, 0.0, 1.0),
            "prob_var_crossover": check_float("prob_var_crossover", prob_var_crossover, 0.0, 1.0),
            "eta_m": check_float("eta_m", eta_m, 0.0, low_open=True),
            "prob_mutation": check_optional_float("prob_mutation", prob_mutation, 0.0, high=1.0),
            "prob_mutant": check_float("prob_mutant", prob_mutant, 0.0, 1.0),
        }
        self._X = np.zeros((0, 0))
        self._F = np.zeros((0, 0))
        self._cv = np.zeros(0)
        self._rank = np.zeros(0, dtype=np.int64)
        self._crowd = np.zeros(0)

    @property
    def population(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(X, F, cv)`` of the current population (copies)."""
        return self._X.copy(), self._F.copy(), self._cv.copy()

    def _setup(self) -> None:
        p = self.problem
        self._X = np.zeros((0, p.n_var))
        self._F = np.zeros((0, p.n_obj))
        self._cv = np.zeros(0)
        self._rank = np.zeros(0, dtype=np.int64)
        self._crowd = np.zeros(0)

    def _tournament(self, n: int) -> np.ndarray:
        """``n`` binary-tournament winners; contestants paired from random permutations."""
        size = self._X.shape[0]
        n_perm = -(-2 * n // size)
        perm = np.concatenate([self._rng.permutation(size) for _ in range(n_perm)])[: 2 * n]
        winners = np.empty(n, dtype=np.int64)
        tournament_kernel(perm, self._F, self._cv, self._crowd, winners)
        return winners

    def _offspring(self, n: int) -> np.ndarray:
        p = self.problem
        n_pairs = (n + 1) // 2
        parents = self._tournament(2 * n_pairs)
        c1, c2 = sbx(self._X[parents[:n_pairs]], self._X[parents[n_pairs:]], p.xl, p.xu,
                     self._rng, eta=self._params["eta_c"], prob=self._params["prob_crossover"],
                     prob_var=self._params["prob_var_crossover"])
        children = np.empty((2 * n_pairs, p.n_var))
        children[0::2], children[1::2] = c1, c2
        Y = polynomial_mutation(children[:n], p.xl, p.xu, self._rng, eta=self._params["eta_m"],
                                prob_var=self._params["prob_mutation"],
                                prob=self._params["prob_mutant"])
        return p.snap(Y)

    def _ask(self) -> np.ndarray:
        n = self._params["pop_size"]
        if self._X.shape[0] == 0:
            return self._initial_population(n)
        # offspring identical (bitwise) to a parent or to another offspring are discarded and
        # re-drawn (up to _MAX_ROUNDS rounds; then duplicates fill the batch) as pymoo does
        parents = np.ascontiguousarray(self._X).view(np.int64)
        pool = np.empty((parents.shape[0] + _MAX_ROUNDS * n, parents.shape[1]), dtype=np.int64)
        pool[: parents.shape[0]] = parents
        n_pool = parents.shape[0]
        kept: list[np.ndarray] = []
        spare: list[np.ndarray] = []
        n_kept = 0
        for _ in range(_MAX_ROUNDS):
            Y = np.ascontiguousarray(self._offspring(n))
            novel = np.empty(n, dtype=np.bool_)
            n_pool = novel_rows_kernel(pool, n_pool, Y.view(np.int64), novel)
            kept.append(Y[novel])
            spare.append(Y[~novel])
            n_kept += kept[-1].shape[0]
            if n_kept >= n:
                break
        return np.concatenate(kept + spare)[:n]

    def _tell(self, X: np.ndarray, F: np.ndarray, cv: np.ndarray) -> None:
        X = np.vstack([self._X, X])
        F = np.ascontiguousarray(np.vstack([self._F, F]))
        cv = np.concatenate([self._cv, cv])
        keep = np.empty(X.shape[0], dtype=np.bool_)
        rank = np.empty(X.shape[0], dtype=np.int64)
        crowd = np.empty(X.shape[0])
        survivors_kernel(F, cv, self._params["pop_size"], keep, rank, crowd)
        if not keep.all():
            # ranks are unchanged by removing worse fronts / part of the last front; crowding
            # distances stay those of the whole front (Deb 2002, and pymoo)
            X, F, cv, rank, crowd = X[keep], F[keep], cv[keep], rank[keep], crowd[keep]
        self._X, self._F, self._cv, self._rank, self._crowd = X, F, cv, rank, crowd

    def _front(self) -> tuple[np.ndarray, np.ndarray]:
        sel = (self._rank == 0) & (self._cv <= 0.0)
        X, F = self._X[sel], self._F[sel]
        first = np.empty(F.shape[0], dtype=np.bool_)
        unique_rows_kernel(F, first)  # equal objective vectors: the first one only
        return X[first], F[first]

    def _get_state(self) -> dict[str, Any]:
        return {"X": self._X, "F": self._F, "cv": self._cv, "rank": self._rank,
                "crowd": self._crowd}

    def _set_state(self, data: dict[str, Any]) -> None:
        p = self.problem
        self._X = np.asarray(data["X"], dtype=float).reshape(-1, p.n_var).copy()
        self._F = np.asarray(data["F"], dtype=float).reshape(-1, p.n_obj).copy()
        self._cv = np.asarray(data["cv"], dtype=float).copy()
        self._rank = np.asarray(data["rank"], dtype=np.int64).copy()
        self._crowd = np.asarray(data["crowd"], dtype=float).copy()
