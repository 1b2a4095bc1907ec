"""NSGA-II: survival, duplicates, constraints and quality on ZDT1."""

from __future__ import annotations

import numpy as np
import pytest

from legcore.metrics import hypervolume, igd, non_dominated_sort
from legcore.optimizers import NSGA2, MaxGenerations, get_algorithm, minimize
from legcore.optimizers.operators import polynomial_mutation, sbx
from legcore.problems import Problem
from legcore.problems.benchmarks import ZDT1, ZDT2, Sphere


def test_nsga2_on_zdt1() -> None:
    problem = ZDT1()
    r = minimize(problem, NSGA2(), MaxGenerations(100), seed=0)
    # pymoo's NSGA2, same budget: HV 0.8485 +- 0.003 (5 seeds); true front 0.8767
    assert hypervolume(r.front_F, [1.1, 1.1]).value > 0.83
    assert igd(r.front_F, problem.pareto_front()) < 0.03
    assert r.n_evals == 100 * 100


def test_nsga2_on_zdt2_keeps_a_spread_front() -> None:
    hv = [hypervolume(minimize(ZDT2(), NSGA2(), MaxGenerations(100), seed=s).front_F,
                      [1.1, 1.1]).value for s in range(3)]
    assert np.median(hv) > 0.45  # collapsing onto f1 = 0 gives ~0.11-0.2


def test_survival_keeps_best_fronts_then_most_isolated() -> None:
    class Identity(Problem):
        def __init__(self) -> None:
            super().__init__(2, 2, 0, xl=0.0, xu=10.0)

        def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, None]:
            return X.copy(), None

    algo = NSGA2(pop_size=4).setup(Identity(), seed=0)
    first = np.array([[0.0, 4.0], [1.0, 3.0], [1.1, 2.9], [4.0, 0.0]])  # one front
    X = algo.ask()
    algo.tell(X, *Identity().evaluate(X))
    # hand the merged population directly to survival
    algo._X = first
    algo._F = first.copy()
    algo._cv = np.zeros(4)
    algo._tell(np.array([[5.0, 5.0], [2.0, 2.0], [6.0, 6.0], [7.0, 7.0]]),
               np.array([[5.0, 5.0], [2.0, 2.0], [6.0, 6.0], [7.0, 7.0]]), np.zeros(4))
    X, F, _ = algo.population
    # front 0 = the 4 first points + (2,2); the crowded one of (1,3)/(1.1,2.9) is dropped
    kept = {tuple(row) for row in F}
    assert (5.0, 5.0) not in kept and (2.0, 2.0) in kept
    assert (0.0, 4.0) in kept and (4.0, 0.0) in kept
    assert len(kept & {(1.0, 3.0), (1.1, 2.9)}) == 1


def test_population_ranks_are_consistent() -> None:
    problem = ZDT1(8)
    algo = NSGA2(pop_size=40).setup(problem, seed=1)
    for _ in range(10):
        X = algo.ask()
        algo.tell(X, *problem.evaluate(X))
    X, F, cv = algo.population
    np.testing.assert_array_equal(algo._rank, non_dominated_sort(F, cv))


def test_offspring_are_not_duplicates_of_the_population() -> None:
    problem = Sphere(6, xl=-1.0, xu=1.0, resolution=0.01)
    algo = NSGA2(pop_size=30).setup(problem, seed=0)
    for _ in range(10):
        X = algo.ask()
        pop = {row.tobytes() for row in algo.population[0]}
        keys = [row.tobytes() for row in X]
        assert len(set(keys)) == len(keys)
        assert not pop & set(keys)
        np.testing.assert_allclose(X * 100, np.rint(X * 100), atol=1e-9)
        algo.tell(X, *problem.evaluate(X))


class Constrained(Problem):
    """Minimise (x0, x1) subject to x0 + x1 >= 1 (front: the segment x0 + x1 = 1)."""

    def __init__(self) -> None:
        super().__init__(2, 2, 1, xl=0.0, xu=1.0)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return X.copy(), 1.0 - X.sum(axis=1)


def test_constrained_front() -> None:
    r = minimize(Constrained(), NSGA2(pop_size=40), MaxGenerations(40), seed=0)
    assert len(r.front_F) > 20
    s = r.front_F.sum(axis=1)
    assert np.all(s >= 1.0 - 1e-12) and s.mean() < 1.02 and s.max() < 1.06


def test_single_objective_use() -> None:
    r = minimize(Sphere(5), NSGA2(pop_size=40), MaxGenerations(60), seed=0)
    assert r.F[0] < 1e-2 and r.front_F.shape == (1, 1)


def test_operators_stay_in_bounds_and_preserve_identical_parents() -> None:
    rng = np.random.default_rng(0)
    xl, xu = np.zeros(4), np.array([1.0, 2.0, 3.0, 0.0])  # last variable fixed
    P1 = rng.random((500, 4)) * xu
    P2 = rng.random((500, 4)) * xu
    C1, C2 = sbx(P1, P2, xl, xu, rng, eta=15, prob=1.0, prob_var=1.0)
    for C in (C1, C2):
        assert np.all(C >= xl) and np.all(C <= xu)
    changed = np.mean(C1[:, :3] != P1[:, :3])
    assert 0.9 < changed  # prob_var = 1: every free variable of distinct parents is crossed
    np.testing.assert_array_equal(C1[:, 3], P1[:, 3])
    same, _ = sbx(P1, P1, xl, xu, rng)
    np.testing.assert_array_equal(same, P1)
    M = polynomial_mutation(P1, xl, xu, rng, eta=20, prob_var=1.0)
    assert np.all(M >= xl) and np.all(M <= xu)
    assert np.mean(M[:, :3] != P1[:, :3]) > 0.99
    np.testing.assert_array_equal(M[:, 3], P1[:, 3])


@pytest.mark.parametrize(
    ("params", "name"),
    [({"pop_size": 2}, "pop_size"), ({"eta_c": -1}, "eta_c"),
     ({"prob_crossover": 1.1}, "prob_crossover"), ({"prob_mutation": 2.0}, "prob_mutation"),
     ({"n_gen": 5}, "n_gen")],
)
def test_bad_parameters_name_the_parameter(params: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        get_algorithm("nsga2", **params)
