"""MOEA/D: weight vectors, batched generations, exact vectorised replacement, archive, quality."""

from __future__ import annotations

import math

import numpy as np
import pytest

from legcore.metrics import hypervolume, igd, non_dominated_mask
from legcore.optimizers import MOEAD, MaxGenerations, get_algorithm, minimize
from legcore.optimizers.moead import lattice_divisions, simplex_lattice
from legcore.problems import Problem
from legcore.problems.benchmarks import DTLZ2, ZDT1, Sphere


@pytest.mark.parametrize(("m", "n", "expected"), [(2, 100, 100), (2, 7, 7), (3, 300, 300),
                                                 (3, 100, 105), (3, 91, 91), (4, 120, 120)])
def test_simplex_lattice_sizes(m: int, n: int, expected: int) -> None:
    W = simplex_lattice(m, n)
    assert W.shape == (expected, m)
    np.testing.assert_allclose(W.sum(axis=1), 1.0)
    assert W.min() >= 0.0
    assert len(np.unique(np.round(W, 12), axis=0)) == expected
    h = lattice_divisions(m, n)
    np.testing.assert_allclose(W * h, np.rint(W * h), atol=1e-9)  # on the lattice 1/H
    assert math.comb(h + m - 1, m - 1) == expected


def test_seed002_configuration() -> None:
    algo = MOEAD().setup(DTLZ2(3, 3), seed=0)  # 3 objectives like the hexapod problem
    assert algo.pop_size == 300 and algo.neighbors.shape == (300, 20)
    assert np.array_equal(algo.neighbors[:, 0], np.arange(300))  # each is its own neighbour
    d = np.linalg.norm(algo.weights[:, None] - algo.weights[None], axis=2)
    kth = np.sort(d, axis=1)[:, 19]
    inside = d[np.arange(300)[:, None], algo.neighbors]
    assert np.all(inside <= kth[:, None] + 1e-12)


class CountingZDT1(ZDT1):
    def __init__(self) -> None:
        super().__init__(30)
        self.calls = 0
        self.rows = 0

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, None]:
        self.calls += 1
        self.rows += X.shape[0]
        return super()._evaluate(X)


def test_each_generation_is_one_batch_call() -> None:
    problem = CountingZDT1()
    r = minimize(problem, MOEAD(n_subproblems=50), MaxGenerations(20), seed=0)
    assert problem.calls == 20
    assert problem.rows == 20 * 50 == r.n_evals


def _sequential_replacement(algo: MOEAD, Y, FY, cvY):  # type: ignore[no-untyped-def]
    """Reference: the paper's loop over i with z fixed (already updated with the batch)."""
    X, F, cv = algo._X.copy(), algo._F.copy(), algo._cv.copy()
    W, z = algo.weights, algo._z
    for i in range(len(Y)):
        for j in algo.neighbors[i]:
            gy = np.max(W[j] * np.abs(FY[i] - z))
            gx = np.max(W[j] * np.abs(F[j] - z))
            if cvY[i] < cv[j] or (cvY[i] == cv[j] and gy < gx):
                X[j], F[j], cv[j] = Y[i], FY[i], cvY[i]
    return X, F, cv


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_vectorised_replacement_equals_the_sequential_loop(seed: int) -> None:
    rng = np.random.default_rng(seed)
    problem = ZDT1(5)
    algo = MOEAD(n_subproblems=40, n_neighbors=8).setup(problem, seed=seed)
    n = algo.pop_size
    # coarse values create ties in g and in the violation
    algo._X = rng.random((n, 5))
    algo._F = np.round(rng.random((n, 2)), 1)
    algo._cv = np.where(rng.random(n) < 0.3, np.round(rng.random(n), 1), 0.0)
    Y = rng.random((n, 5))
    FY = np.round(rng.random((n, 2)), 1)
    cvY = np.where(rng.random(n) < 0.3, np.round(rng.random(n), 1), 0.0)
    algo._z = np.minimum(algo._F.min(axis=0), FY.min(axis=0))
    expected = _sequential_replacement(algo, Y, FY, cvY)
    algo._replace(Y, FY, cvY)
    for got, want in zip((algo._X, algo._F, algo._cv), expected, strict=True):
        np.testing.assert_array_equal(got, want)


def test_ideal_point_and_archive_invariants() -> None:
    problem = ZDT1(10)
    algo = MOEAD(n_subproblems=60).setup(problem, seed=4)
    seen_min = np.full(2, np.inf)
    for _ in range(25):
        X = algo.ask()
        F, G = problem.evaluate(X)
        seen_min = np.minimum(seen_min, F.min(axis=0))
        algo.tell(X, F, G)
        np.testing.assert_array_equal(algo.ideal, seen_min)
        AX, AF = algo.front()
        assert len(AF) <= 60
        assert non_dominated_mask(AF).all()
        assert len(np.unique(AF, axis=0)) == len(AF)
        np.testing.assert_allclose(problem.evaluate(AX)[0], AF)


def test_moead_on_zdt1_reaches_the_front() -> None:
    problem = ZDT1()
    r = minimize(problem, MOEAD(n_subproblems=100), MaxGenerations(100), seed=0)
    # pymoo's MOEAD, same budget: HV 0.828 +- 0.024 (10 seeds); the true front has 0.8767
    assert hypervolume(r.front_F, [1.1, 1.1]).value > 0.80
    assert igd(r.front_F, problem.pareto_front()) < 0.06


def test_moead_on_dtlz2_with_the_seed_budget() -> None:
    problem = DTLZ2(12, 3)
    r = minimize(problem, MOEAD(), MaxGenerations(100), seed=0)
    # pymoo's MOEAD with Tchebycheff, 300 x 100: HV 0.751 (3 seeds)
    assert hypervolume(r.front_F, [1.1, 1.1, 1.1]).value > 0.74
    assert igd(r.front_F, problem.pareto_front(500)) < 0.06
    assert r.n_evals == 300 * 100


class GridZDT1(Problem):
    """ZDT1 with variables on a 0.01 grid."""

    def __init__(self) -> None:
        super().__init__(6, 2, 0, xl=0.0, xu=1.0, resolution=0.01)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, None]:
        return ZDT1(6).evaluate(X)[0], None


def test_integer_coded_offspring_stay_on_the_grid() -> None:
    p = GridZDT1()
    algo = MOEAD(n_subproblems=30, n_neighbors=5).setup(p, seed=0)
    for _ in range(5):
        X = algo.ask()
        assert np.all((X >= 0) & (X <= 1))
        np.testing.assert_allclose(X * 100, np.rint(X * 100), atol=1e-9)
        algo.tell(X, *p.evaluate(X))


class ConstrainedZDT1(Problem):
    """ZDT1 with x1 >= 0.3: the feasible front starts at f1 = 0.3."""

    def __init__(self) -> None:
        super().__init__(10, 2, 1, xl=0.0, xu=1.0)
        self.zdt = ZDT1(10)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        F, _ = self.zdt.evaluate(X)
        return F, 0.3 - X[:, :1]


def test_constraints_keep_the_front_feasible() -> None:
    r = minimize(ConstrainedZDT1(), MOEAD(n_subproblems=50), MaxGenerations(60), seed=0)
    assert len(r.front_F) > 10
    assert r.front_F[:, 0].min() >= 0.3 - 1e-12
    assert r.cv == 0.0


def test_archive_can_be_disabled() -> None:
    r = minimize(ZDT1(10), MOEAD(n_subproblems=40, archive_size=0), MaxGenerations(20), seed=0)
    assert 0 < len(r.front_F) <= 40 and non_dominated_mask(r.front_F).all()


@pytest.mark.parametrize(
    ("params", "name"),
    [({"n_subproblems": 1}, "n_subproblems"), ({"n_neighbors": 1}, "n_neighbors"),
     ({"prob_neighbor_mating": 2.0}, "prob_neighbor_mating"), ({"variation": "de"}, "variation"),
     ({"eta_c": 0}, "eta_c"), ({"archive_size": -1}, "archive_size"), ({"T": 20}, "T")],
)
def test_bad_parameters_name_the_parameter(params: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        get_algorithm("moead", **params)


def test_setup_errors() -> None:
    with pytest.raises(ValueError, match="n_neighbors"):
        MOEAD(n_subproblems=10, n_neighbors=20).setup(ZDT1(), seed=0)
    with pytest.raises(ValueError, match="problem"):
        MOEAD().setup(Sphere(3), seed=0)
