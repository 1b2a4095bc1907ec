"""Heuristic Kalman Algorithm: the update equations, the survey start, constraints, benchmarks."""

from __future__ import annotations

import numpy as np
import pytest

import legcore.optimizers.hka as hka_module
from legcore.optimizers import HKA, MaxEvaluations, MaxGenerations, get_algorithm, minimize
from legcore.optimizers.hka import kalman_update
from legcore.problems import Problem
from legcore.problems.benchmarks import Rastrigin, Rosenbrock, Sphere

# median over 3 seeds of the best f with 10 000 evaluations. Measured: sphere 0 (1e-16),
# Rosenbrock <= 7.9, Rastrigin <= 2.0; with the gain sign flipped: 2.3 / 40 / 40; with sigma
# never updated: 2.0 / 33 / 34.
THRESHOLDS = {"sphere": 1e-6, "rosenbrock": 15.0, "rastrigin": 8.0}
PROBLEMS = {"sphere": Sphere, "rosenbrock": Rosenbrock, "rastrigin": Rastrigin}


def _median_best(name: str) -> float:
    problem = PROBLEMS[name](10)
    return float(np.median([minimize(problem, HKA(), MaxEvaluations(10_000), seed=s).F[0]
                            for s in range(3)]))


@pytest.mark.parametrize("name", sorted(THRESHOLDS))
def test_hka_solves_benchmarks(name: str) -> None:
    assert _median_best(name) < THRESHOLDS[name]


def test_thresholds_catch_a_flipped_kalman_gain(monkeypatch: pytest.MonkeyPatch) -> None:
    good = hka_module.kalman_update

    def flipped(m, sigma, best, alpha):  # type: ignore[no-untyped-def]
        m_new, s_new, v = good(m, sigma, best, alpha)
        return m - (m_new - m), s_new, v

    monkeypatch.setattr(hka_module, "kalman_update", flipped)
    for name in THRESHOLDS:
        assert _median_best(name) > THRESHOLDS[name], name


def test_kalman_update_by_hand() -> None:
    m = np.array([0.0, 1.0])
    sigma = np.array([2.0, 1.0])
    best = np.array([[1.0, 1.0], [3.0, 2.0]])
    # xi = (2, 1.5), v = (1, 0.25); L = (4/5, 1/1.25 = 0.8)
    # m+ = (0 + 0.8*2, 1 + 0.8*0.5) = (1.6, 1.4); p+ = (0.2*4, 0.2*1) = (0.8, 0.2)
    # c = min(1, mean(1, 0.5)) = 0.75; a = 0.5 * 0.5625 / (0.5625 + 0.8)
    m_new, s_new, v = kalman_update(m, sigma, best, alpha=0.5)
    np.testing.assert_allclose(v, [1.0, 0.25])
    np.testing.assert_allclose(m_new, [1.6, 1.4])
    a = 0.5 * 0.5625 / (0.5625 + 0.8)
    np.testing.assert_allclose(s_new, sigma + a * (np.sqrt([0.8, 0.2]) - sigma))


def test_kalman_update_with_zero_spread_keeps_the_mean() -> None:
    m_new, s_new, v = kalman_update(np.zeros(2), np.zeros(2), np.ones((3, 2)), 0.9)
    np.testing.assert_array_equal(m_new, [0.0, 0.0])
    np.testing.assert_array_equal(s_new, [0.0, 0.0])


def test_initialisation_is_eq16() -> None:
    problem = Sphere(3, xl=[0.0, -1.0, 2.0], xu=[6.0, 1.0, 2.6])
    algo = HKA().setup(problem, seed=0)
    np.testing.assert_allclose(algo.mean, [3.0, 0.0, 2.3])
    np.testing.assert_allclose(algo.sigma, [1.0, 2.0 / 6, 0.1])


def test_samples_follow_the_generator_and_stay_in_bounds() -> None:
    problem = Sphere(2, xl=-1.0, xu=1.0)
    algo = HKA(n_samples=20_000).setup(problem, seed=0)
    X = algo.ask()
    assert X.shape == (20_000, 2)
    assert X.min() >= -1.0 and X.max() <= 1.0
    np.testing.assert_allclose(X.mean(axis=0), 0.0, atol=0.01)
    np.testing.assert_allclose(X.std(axis=0), 1.0 / 3, rtol=0.02)  # clipping beyond 3 sigma


def test_stops_itself_when_the_best_collapse() -> None:
    r = minimize(Sphere(3), HKA(spread_tol=1e-6), MaxGenerations(1000), seed=0)
    assert "spread" in r.reason and r.n_gen < 1000
    assert r.F[0] < 1e-10


class TwoBasins(Problem):
    """A broad local minimum (-0.5) at the centre, a narrow global one (-1) near a corner."""

    target = np.array([3.5, 3.5, -3.5])

    def __init__(self) -> None:
        super().__init__(3, 1, 0, xl=-5.0, xu=5.0)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, None]:
        local = 0.5 * np.exp(-np.sum(X ** 2, axis=1) / 8.0)
        glob = np.exp(-np.sum((X - self.target) ** 2, axis=1) / (2 * 0.5 ** 2))
        return -(local + glob), None


def test_survey_initialisation_escapes_the_local_minimum() -> None:
    problem = TwoBasins()
    centre = [minimize(problem, HKA(), MaxGenerations(60), seed=s).F[0] for s in range(3)]
    survey = [minimize(problem, HKA(init="survey", survey_best=1), MaxGenerations(60),
                       seed=s).F[0] for s in range(3)]
    assert max(centre) > -0.6  # the original start converges to the centre basin
    assert max(survey) < -0.99  # the coarse survey finds the narrow global basin


def test_survey_generation_is_a_grid() -> None:
    problem = Sphere(3, xl=0.0, xu=10.0)
    algo = HKA(init="survey", survey_size=1000, survey_best=5).setup(problem, seed=0)
    X = algo.ask()
    assert X.shape == (1000, 3)
    assert np.array_equal(np.unique(X[:, 0]), np.arange(10) + 0.5)  # cell centres, step 1
    algo.tell(X, *problem.evaluate(X))
    # best 5 cells of the sphere are (0.5,0.5,0.5) and its neighbours -> box [0, 2]^3
    np.testing.assert_allclose(algo.mean, 1.0)
    np.testing.assert_allclose(algo.sigma, 2.0 / 6)
    # in 12 dimensions 2^12 > 1000 cells: a random subset of the 2-level grid
    algo12 = HKA(init="survey").setup(Sphere(12, xl=0.0, xu=4.0), seed=0)
    X12 = algo12.ask()
    assert X12.shape == (1000, 12) and set(np.unique(X12)) == {1.0, 3.0}


class Penalised(Problem):
    """Minimise sum(x) subject to sum(x^2) <= 1 (optimum -sqrt(3) in 3-D)."""

    def __init__(self) -> None:
        super().__init__(3, 1, 1, xl=-2.0, xu=2.0)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return X.sum(axis=1), (X ** 2).sum(axis=1) - 1.0


@pytest.mark.parametrize("penalty", [1e3, None])
def test_constraints_by_penalty_or_feasibility_rule(penalty: float | None) -> None:
    r = minimize(Penalised(), HKA(penalty=penalty), MaxEvaluations(10_000), seed=1)
    assert r.cv < 1e-3
    assert r.F[0] == pytest.approx(-np.sqrt(3), abs=0.01)


def test_integer_coded_problem_stays_on_the_grid() -> None:
    problem = Sphere(4, resolution=0.05)
    algo = HKA().setup(problem, seed=0)
    for _ in range(5):
        X = algo.ask()
        np.testing.assert_allclose(X / 0.05, np.rint(X / 0.05), atol=1e-9)
        algo.tell(X, *problem.evaluate(X))


@pytest.mark.parametrize(
    ("params", "name"),
    [({"n_samples": 1}, "n_samples"), ({"n_best": 500}, "n_best"), ({"alpha": 0.0}, "alpha"),
     ({"alpha": 1.5}, "alpha"), ({"init": "grid"}, "init"), ({"spread_tol": -1}, "spread_tol"),
     ({"survey_best": 0}, "survey_best"), ({"penalty": "big"}, "penalty")],
)
def test_bad_parameters_name_the_parameter(params: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        get_algorithm("hka", **params)
