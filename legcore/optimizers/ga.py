"""Genetic algorithm of seed 000 (Calderón, Bedolla & Szwedowicz 2015, §3).

Single objective, minimised. Per generation:

1. **Coding.** Integer genes at each variable's control resolution: ``x_j = k_j * resolution_j``
   (``Problem.resolution``), so every solution is reachable by the controller. A problem without
   a resolution is coded with real genes in ``[xl, xu]``.
2. **Cost.** ``c = f`` for feasible individuals. Constraints: with ``penalty = None`` (default)
   Deb's parameterless rule, ``c = f_worst_feasible + CV`` for an infeasible individual (so
   feasible beats infeasible, less violation beats more); with a number ``w``,
   ``c = f + w * CV`` (the static penalty of seed 001).
3. **Roulette-wheel selection** (the seed's "método de la ruleta"): parents drawn with
   probability proportional to a fitness ``phi >= 0``:

   - ``fitness="window"`` (default, any sign of ``f``): ``phi = c_worst - c + eps`` with
     ``eps = 0.01 (c_worst - c_best)`` (every individual keeps a small chance; all equal ->
     uniform);
   - ``fitness="negated"``: ``phi = max(-c, 0)``: exactly the seed's roulette on its score when
     the problem reports ``f = -score`` with ``score >= 0`` (seed 000: score in [0, 10]).
     A feasible ``f > 0`` is an error in this mode.
4. **Crossover** (with probability ``crossover_rate`` per pair, otherwise the parents are
   copied): one point ``c`` is drawn uniformly among the genes; genes before ``c`` stay with
   their parent, genes after ``c`` are exchanged, and the gene at ``c`` is "divided in two random
   percentages added to the percentages of the other individual":
   ``child1_c = r a_c + (1 - r) b_c``, ``child2_c = (1 - r) a_c + r b_c``, ``r ~ U(0, 1)``,
   rounded to the nearest integer gene (the blend of two valid genes is a valid gene).
5. **Mutation**: each gene is replaced with probability ``mutation_rate`` (3 %) by a fresh value
   drawn uniformly over its whole range.
6. **Elitism** (default on, ``elitism=2``): the ``elitism`` lowest-cost individuals are copied
   unchanged into the next generation (and not re-evaluated); ``elitism=0`` is the plain
   generational GA.

Defaults follow the seed: population 100, 100 generations, mutation 3 %. The seed does not give
a crossover rate; 0.9 is used.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np

from legcore.optimizers.base import Algorithm
from legcore.optimizers.params import check_choice, check_float, check_int, check_optional_float

__all__ = ["GA", "scalar_cost", "roulette_weights", "roulette_select", "blend_crossover"]

_WINDOW_EPS = 0.01


def scalar_cost(f: np.ndarray, cv: np.ndarray, penalty: float | None) -> np.ndarray:
    """One cost per individual from objective ``f (n,)`` and violation ``cv (n,)``.

    ``penalty=None``: Deb's parameterless rule (feasible: ``f``; infeasible: worst feasible
    ``f`` of the batch, or 0 if none, plus ``cv``). Otherwise ``f + penalty * cv``.
    """
    if penalty is not None:
        return f + penalty * cv
    feasible = cv <= 0.0
    if feasible.all():
        return f.copy()
    worst = float(f[feasible].max()) if feasible.any() else 0.0
    return np.where(feasible, f, worst + cv)


def roulette_weights(cost: np.ndarray, fitness: str = "window") -> np.ndarray:
    """Selection probabilities ``phi / sum(phi)`` of a population with scalar ``cost``.

    ``"window"``: ``phi = c_worst - c + 0.01 (c_worst - c_best)``; ``"negated"``:
    ``phi = max(-c, 0)``. If every ``phi`` is 0 the wheel is uniform.
    """
    if fitness == "negated":
        phi = np.maximum(-cost, 0.0)
    elif fitness == "window":
        worst, best = float(cost.max()), float(cost.min())
        phi = (worst - cost) + _WINDOW_EPS * (worst - best)
    else:
        raise ValueError(f"fitness: expected 'window' or 'negated', got {fitness!r}")
    total = float(phi.sum())
    if not np.isfinite(total) or total <= 0.0:
        return np.full(cost.size, 1.0 / cost.size)
    return phi / total


def roulette_select(weights: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` indices drawn with replacement with probabilities ``weights`` (one spin each)."""
    cum = np.cumsum(weights)
    idx = np.searchsorted(cum, rng.random(n) * cum[-1], side="right")
    return np.minimum(idx, weights.size - 1)


def blend_crossover(
    A: np.ndarray, B: np.ndarray, rng: np.random.Generator, rate: float, *, integer: bool
) -> tuple[np.ndarray, np.ndarray]:
    """Seed 000's crossover of parent rows ``A`` and ``B`` (see the module docstring).

    For each pair, with probability ``rate``: a cut gene ``c`` (uniform), genes after ``c``
    exchanged, gene ``c`` blended ``r a + (1 - r) b`` / ``(1 - r) a + r b`` (rounded if
    ``integer``). Otherwise the children are copies of the parents.
    """
    n, d = int(A.shape[0]), int(A.shape[1])
    do = rng.random(n) < rate
    cut = rng.integers(0, d, size=n)
    r = rng.random(n)
    after = (np.arange(d)[None, :] > cut[:, None]) & do[:, None]
    C1 = np.where(after, B, A)
    C2 = np.where(after, A, B)
    rows = np.flatnonzero(do)
    c = cut[rows]
    a, b, rr = A[rows, c], B[rows, c], r[rows]
    g1, g2 = rr * a + (1.0 - rr) * b, (1.0 - rr) * a + rr * b
    if integer:
        g1, g2 = np.rint(g1), np.rint(g2)
    C1[rows, c] = g1
    C2[rows, c] = g2
    return C1, C2


class GA(Algorithm):
    """Integer-coded GA with roulette selection, blend one-point crossover, fresh-value mutation.

    Args:
        pop_size: individuals per generation (>= 2). Default 100.
        crossover_rate: probability that a selected pair is crossed (else copied). Default 0.9.
        mutation_rate: per-gene probability of drawing a fresh value. Default 0.03.
        elitism: best individuals copied unchanged to the next generation (0 disables).
            Default 2.
        fitness: ``"window"`` or ``"negated"`` roulette fitness (see module docstring).
        penalty: ``None`` (Deb's feasibility rule) or a static penalty weight ``>= 0``.
    """

    kind: ClassVar[str] = "ga"

    def __init__(
        self,
        pop_size: int = 100,
        crossover_rate: float = 0.9,
        mutation_rate: float = 0.03,
        elitism: int = 2,
        fitness: str = "window",
        penalty: float | None = None,
    ) -> None:
        super().__init__()
        pop_size = check_int("pop_size", pop_size, 2)
        self._params = {
            "pop_size": pop_size,
            "crossover_rate": check_float("crossover_rate", crossover_rate, 0.0, 1.0),
            "mutation_rate": check_float("mutation_rate", mutation_rate, 0.0, 1.0),
            "elitism": check_int("elitism", elitism, 0, pop_size - 1),
            "fitness": check_choice("fitness", fitness, ("window", "negated")),
            "penalty": check_optional_float("penalty", penalty, 0.0),
        }
        self._genes = np.zeros((0, 0))
        self._f = np.zeros(0)
        self._cv = np.zeros(0)

    # ------------------------------------------------------------------ coding
    def _gene_range(self) -> tuple[np.ndarray, np.ndarray]:
        p = self.problem
        if p.resolution is not None:
            k_lo, k_hi = p.gene_bounds()
            return k_lo.astype(float), k_hi.astype(float)
        return p.xl.astype(float), p.xu.astype(float)

    def _decode(self, genes: np.ndarray) -> np.ndarray:
        p = self.problem
        return genes * p.resolution if p.resolution is not None else genes.copy()

    def _encode(self, X: np.ndarray) -> np.ndarray:
        p = self.problem
        return np.rint(X / p.resolution) if p.resolution is not None else X.copy()

    def _fresh_genes(self, shape: tuple[int, int]) -> np.ndarray:
        lo, hi = self._gene_range()
        if self.problem.resolution is not None:
            return self._rng.integers(lo.astype(np.int64), hi.astype(np.int64) + 1,
                                      size=shape).astype(float)
        return lo + self._rng.random(shape) * (hi - lo)

    # ------------------------------------------------------------------ operators
    def _mutate(self, genes: np.ndarray) -> np.ndarray:
        mask = self._rng.random(genes.shape) < self._params["mutation_rate"]
        fresh = self._fresh_genes(genes.shape)
        return np.where(mask, fresh, genes)

    # ------------------------------------------------------------------ hooks
    def _setup(self) -> None:
        self._genes = np.zeros((0, self.problem.n_var))
        self._f = np.zeros(0)
        self._cv = np.zeros(0)

    def _elite_index(self) -> np.ndarray:
        cost = scalar_cost(self._f, self._cv, self._params["penalty"])
        return np.argsort(cost, kind="stable")[: self._params["elitism"]]

    def _ask(self) -> np.ndarray:
        n = self._params["pop_size"]
        if self._genes.shape[0] == 0:
            if self._initial_points() is not None:
                return self._initial_population(n)
            return self._decode(self._fresh_genes((n, self.problem.n_var)))
        n_child = n - self._params["elitism"]
        n_pairs = (n_child + 1) // 2
        cost = scalar_cost(self._f, self._cv, self._params["penalty"])
        weights = roulette_weights(cost, self._params["fitness"])
        parents = roulette_select(weights, 2 * n_pairs, self._rng)
        A, B = self._genes[parents[:n_pairs]], self._genes[parents[n_pairs:]]
        C1, C2 = blend_crossover(A, B, self._rng, self._params["crossover_rate"],
                                 integer=self.problem.resolution is not None)
        children = np.empty((2 * n_pairs, A.shape[1]))
        children[0::2], children[1::2] = C1, C2
        children = self._mutate(children[:n_child])
        return self._decode(children)

    def _tell(self, X: np.ndarray, F: np.ndarray, cv: np.ndarray) -> None:
        genes, f = self._encode(X), F[:, 0]
        if self._params["fitness"] == "negated":
            positive = (cv <= 0.0) & (f > 0.0)
            if positive.any():
                raise ValueError("fitness: 'negated' needs F <= 0 (the problem reports -score), "
                                 f"got F = {float(f[positive].max())}")
        if self._genes.shape[0]:
            elite = self._elite_index()
            genes = np.vstack([self._genes[elite], genes])
            f = np.concatenate([self._f[elite], f])
            cv = np.concatenate([self._cv[elite], cv])
        self._genes, self._f, self._cv = genes, f.copy(), cv.copy()

    def _get_state(self) -> dict[str, Any]:
        return {"genes": self._genes, "f": self._f, "cv": self._cv}

    def _set_state(self, data: dict[str, Any]) -> None:
        self._genes = np.asarray(data["genes"], dtype=float).reshape(-1, self.problem.n_var)
        self._f = np.asarray(data["f"], dtype=float)
        self._cv = np.asarray(data["cv"], dtype=float)

    @property
    def population(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(X, f, cv)`` of the current population (copies)."""
        return self._decode(self._genes), self._f.copy(), self._cv.copy()
