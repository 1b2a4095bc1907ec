"""MOEA/D (Zhang & Li 2007) with Tchebycheff decomposition, one batch evaluation per generation.

The problem is decomposed into ``N`` scalar subproblems, one per weight vector ``lambda^i``:

    g_te(x | lambda, z*) = max_k lambda_k |f_k(x) - z*_k|

with the ideal point ``z*`` (best value seen of each objective). Each subproblem ``i`` keeps one
solution and mates within its ``T`` nearest weight vectors ``B(i)``. Per generation:

1. **Reproduction** (all ``N`` subproblems at once): for each ``i``, two distinct parents from
   ``B(i)`` (with probability ``prob_neighbor_mating``, else from the whole population), then
   SBX (one of its two children, at random) and polynomial mutation — the operators of pymoo's
   MOEAD. Integer-coded problems are rounded to the grid.
2. **Evaluation** of the ``N`` offspring as ONE batch (``ask``/``tell``).
3. **Update of z*** with the whole batch.
4. **Replacement**: offspring ``y_i`` replaces the solution of every neighbour ``j in B(i)`` it
   improves, ``g_te(y_i | lambda^j, z*) < g_te(x^j | lambda^j, z*)``. With constraints the
   comparison is by violation first, then by ``g_te``.
5. **External archive** (EP): the non-dominated feasible solutions found so far.

Difference from the sequential algorithm of the paper (and of pymoo, which evaluates one
offspring at a time): all offspring of a generation are produced from the population at the
start of the generation, and ``z*`` is updated with the whole batch before the replacements.
Given that, the replacement is computed exactly, vectorised: each subproblem ends with the best
of its current solution and of all offspring whose neighbourhood contains it, ties going to the
earlier subproblem — the same outcome as the paper's loop over ``i = 1..N`` with ``z*`` fixed.
(The paper's ``z`` update in seed 002's listing reads ``if z_j < f_j(y')``; for minimisation
the ideal point takes the *smaller* value, as in Zhang & Li.)

Weight vectors: the uniform simplex lattice of Das & Dennis, ``lambda_k = h_k / H`` with
``sum h_k = H``, which has ``C(H + m - 1, m - 1)`` points. ``H`` is chosen so that this number is
as close as possible to the requested ``n_subproblems`` (ties: the larger); for 2 objectives it
is exact, and for 3 objectives 300 subproblems (seed 002) is exact (``H = 23``). The actual
number is ``pop_size`` after ``setup``.

The replacement and the archive update are compiled (:mod:`legcore.optimizers.moead_kernels`;
their numpy formulation, the reference they are tested against, is
:mod:`legcore.optimizers.moead_reference`).

Archive: the non-dominated feasible offspring are merged into EP every generation;
``archive_size`` (default: the population size) caps it by dropping the most crowded points
(NSGA-II crowding distance); ``archive_size=0`` disables EP and the front is the non-dominated
feasible part of the population.
"""

from __future__ import annotations

import itertools
import math
from typing import Any, ClassVar

import numpy as np
from scipy.spatial.distance import cdist

from legcore.metrics import non_dominated_mask
from legcore.optimizers.base import Algorithm
from legcore.optimizers.moead_kernels import replace, update_archive
from legcore.optimizers.operators import polynomial_mutation, sbx
from legcore.optimizers.params import check_float, check_int, check_optional_float

__all__ = ["MOEAD", "simplex_lattice", "lattice_divisions"]


def lattice_divisions(n_obj: int, n_points: int) -> int:
    """Divisions ``H`` whose lattice size ``C(H+m-1, m-1)`` is closest to ``n_points``."""
    if n_obj < 1 or n_points < 1:
        raise ValueError(f"n_obj/n_points: must be >= 1, got {n_obj}, {n_points}")
    if n_obj == 1:
        return 0
    h, prev = 1, None
    while True:
        size = math.comb(h + n_obj - 1, n_obj - 1)
        if size >= n_points:
            if prev is not None and n_points - prev < size - n_points:
                return h - 1
            return h
        prev, h = size, h + 1


def simplex_lattice(n_obj: int, n_points: int) -> np.ndarray:
    """Das–Dennis uniform weight vectors on the unit simplex, about ``n_points`` of them.

    Returns ``(C(H+m-1, m-1), m)`` rows summing to 1 (see `lattice_divisions`).
    """
    h = lattice_divisions(n_obj, n_points)
    if n_obj == 1:
        return np.ones((1, 1))
    # stars and bars: positions of m-1 bars among H + m - 1 slots
    bars = np.array(list(itertools.combinations(range(h + n_obj - 1), n_obj - 1)))
    edges = np.column_stack([np.full(len(bars), -1), bars, np.full(len(bars), h + n_obj - 1)])
    parts = np.diff(edges, axis=1) - 1
    return parts[::-1] / h


def _distinct_pairs(rng: np.random.Generator, n: int, size: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` pairs of distinct integers in ``[0, size)``."""
    a = rng.integers(0, size, n)
    b = rng.integers(0, size - 1, n)
    b = b + (b >= a)
    return a, b


class MOEAD(Algorithm):
    """MOEA/D with Tchebycheff decomposition and batched generations.

    Args:
        n_subproblems: requested number of weight vectors ``N`` (the population size; the
            lattice size closest to it is used). Default 300 (seed 002).
        n_neighbors: ``T``, neighbourhood size including the subproblem itself (>= 2).
            Default 20 (seed 002).
        prob_neighbor_mating: probability of mating within the neighbourhood. Default 0.9.
        eta_c: SBX distribution index. Default 20.
        eta_m: polynomial mutation distribution index. Default 20.
        prob_mutation: per-variable mutation probability; ``None`` = ``1 / n_var``.
        archive_size: cap of the external archive; ``None`` = population size; 0 = no archive.
    """

    kind: ClassVar[str] = "moead"
    n_obj_range: ClassVar[tuple[int, int | None]] = (2, None)

    def __init__(
        self,
        n_subproblems: int = 300,
        n_neighbors: int = 20,
        prob_neighbor_mating: float = 0.9,
        eta_c: float = 20.0,
        eta_m: float = 20.0,
        prob_mutation: float | None = None,
        archive_size: int | None = None,
    ) -> None:
        super().__init__()
        self._params = {
            "n_subproblems": check_int("n_subproblems", n_subproblems, 2),
            "n_neighbors": check_int("n_neighbors", n_neighbors, 2),
            "prob_neighbor_mating": check_float("prob_neighbor_mating", prob_neighbor_mating,
                                                0.0, 1.0),
            "eta_c": check_float("eta_c", eta_c, 0.0, low_open=True),
            "eta_m": check_float("eta_m", eta_m, 0.0, low_open=True),
            "prob_mutation": check_optional_float("prob_mutation", prob_mutation, 0.0, high=1.0),
            "archive_size": None if archive_size is None
            else check_int("archive_size", archive_size, 0),
        }
        self.weights = np.zeros((0, 0))
        self.neighbors = np.zeros((0, 0), dtype=np.int64)
        self._X = np.zeros((0, 0))
        self._F = np.zeros((0, 0))
        self._cv = np.zeros(0)
        self._z = np.zeros(0)
        self._AX = np.zeros((0, 0))
        self._AF = np.zeros((0, 0))

    @property
    def pop_size(self) -> int:
        """Actual number of subproblems (weight vectors) after ``setup``."""
        return int(self.weights.shape[0])

    @property
    def ideal(self) -> np.ndarray:
        """Current ideal point ``z*``."""
        return self._z.copy()

    @property
    def population(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(X, F, cv)`` of the subproblems' current solutions (copies)."""
        return self._X.copy(), self._F.copy(), self._cv.copy()

    # ------------------------------------------------------------------ hooks
    def _setup(self) -> None:
        p = self.problem
        self.weights = simplex_lattice(p.n_obj, self._params["n_subproblems"])
        n = self.weights.shape[0]
        t = self._params["n_neighbors"]
        if t > n:
            raise ValueError(f"n_neighbors: {t} exceeds the {n} weight vectors")
        dist = cdist(self.weights, self.weights)
        self.neighbors = np.argsort(dist, axis=1, kind="stable")[:, :t].astype(np.int64)
        self._X = np.zeros((0, p.n_var))
        self._F = np.zeros((0, p.n_obj))
        self._cv = np.zeros(0)
        self._z = np.full(p.n_obj, np.inf)
        self._AX = np.zeros((0, p.n_var))
        self._AF = np.zeros((0, p.n_obj))

    def _ask(self) -> np.ndarray:
        p = self.problem
        n = self.pop_size
        if self._X.shape[0] == 0:
            return self._initial_population(n)
        rng = self._rng
        t = self._params["n_neighbors"]
        local = rng.random(n) < self._params["prob_neighbor_mating"]
        ka, kb = _distinct_pairs(rng, n, t)
        ga, gb = _distinct_pairs(rng, n, n)
        rows = np.arange(n)
        a = np.where(local, self.neighbors[rows, ka], ga)
        b = np.where(local, self.neighbors[rows, kb], gb)
        c1, c2 = sbx(self._X[a], self._X[b], p.xl, p.xu, rng,
                     eta=self._params["eta_c"], prob=1.0, prob_var=0.5)
        Y = np.where((rng.random(n) < 0.5)[:, None], c1, c2)
        Y = polynomial_mutation(Y, p.xl, p.xu, rng, eta=self._params["eta_m"],
                                prob_var=self._params["prob_mutation"])
        return p.snap(Y)

    def _tell(self, X: np.ndarray, F: np.ndarray, cv: np.ndarray) -> None:
        self._z = np.minimum(self._z, F.min(axis=0))
        if self._X.shape[0] == 0:
            self._X, self._F, self._cv = X.copy(), F.copy(), cv.copy()
        else:
            self._replace(X, F, cv)
        self._update_archive(X, F, cv)

    #: The replacement and archive update (compiled, :mod:`~legcore.optimizers.moead_kernels`;
    #: the numpy versions of :mod:`~legcore.optimizers.moead_reference` give the same results).
    replace_step = staticmethod(replace)
    archive_step = staticmethod(update_archive)

    def _replace(self, Y: np.ndarray, FY: np.ndarray, cvY: np.ndarray) -> None:
        j, i = self.replace_step(self.neighbors, self.weights, self._z, self._F, self._cv, FY, cvY)
        self._X[j] = Y[i]
        self._F[j] = FY[i]
        self._cv[j] = cvY[i]

    def _update_archive(self, X: np.ndarray, F: np.ndarray, cv: np.ndarray) -> None:
        cap = self._params["archive_size"]
        if cap == 0:
            return
        merged = self.archive_step(X, F, cv, self._AX, self._AF,
                                   self.pop_size if cap is None else cap)
        if merged is not None:
            self._AX, self._AF = merged

    def _front(self) -> tuple[np.ndarray, np.ndarray]:
        if self._params["archive_size"] != 0:
            return self._AX, self._AF
        feas = self._cv <= 0.0
        X, F = self._X[feas], self._F[feas]
        if F.shape[0] == 0:
            return X, F
        keep = non_dominated_mask(F)
        X, F = X[keep], F[keep]
        _, first = np.unique(F, axis=0, return_index=True)
        first = np.sort(first)
        return X[first], F[first]

    def _get_state(self) -> dict[str, Any]:
        return {"X": self._X, "F": self._F, "cv": self._cv, "z": self._z,
                "archive_X": self._AX, "archive_F": self._AF}

    def _set_state(self, data: dict[str, Any]) -> None:
        p = self.problem
        self._X = np.asarray(data["X"], dtype=float).reshape(-1, p.n_var).copy()
        self._F = np.asarray(data["F"], dtype=float).reshape(-1, p.n_obj).copy()
        self._cv = np.asarray(data["cv"], dtype=float).copy()
        self._z = np.asarray(data["z"], dtype=float).copy()
        self._AX = np.asarray(data["archive_X"], dtype=float).reshape(-1, p.n_var).copy()
        self._AF = np.asarray(data["archive_F"], dtype=float).reshape(-1, p.n_obj).copy()
