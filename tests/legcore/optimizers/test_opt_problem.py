"""The Problem base class and the analytic benchmarks."""

from __future__ import annotations

import numpy as np
import pytest

from legcore.problems import Problem, constraint_violation
from legcore.problems.benchmarks import (
    DTLZ2,
    ZDT1,
    ZDT2,
    Rastrigin,
    Rosenbrock,
    Sphere,
    get_benchmark,
)


class Disk(Problem):
    """Minimise x + y inside the unit disk (one constraint)."""

    def __init__(self) -> None:
        super().__init__(2, 1, 1, xl=-2.0, xu=2.0)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return X.sum(axis=1), (X ** 2).sum(axis=1) - 1.0


def test_evaluate_shapes_and_validation() -> None:
    p = Disk()
    F, G = p.evaluate(np.array([[0.0, 0.0], [1.0, 1.0]]))
    assert F.shape == (2, 1) and G.shape == (2, 1)
    np.testing.assert_allclose(G[:, 0], [-1.0, 1.0])
    np.testing.assert_allclose(constraint_violation(G), [0.0, 1.0])
    F1, _ = p.evaluate(np.array([0.5, 0.5]))  # one vector = batch of one
    assert F1.shape == (1, 1)
    with pytest.raises(ValueError, match="X: expected shape"):
        p.evaluate(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="X: contains NaN"):
        p.evaluate(np.array([[np.nan, 0.0]]))


def test_unconstrained_problem_has_empty_G() -> None:
    F, G = Sphere(3).evaluate(np.ones((4, 3)))
    assert G.shape == (4, 0)
    np.testing.assert_allclose(F[:, 0], 3.0)
    assert constraint_violation(G).tolist() == [0.0] * 4


def test_bad_problem_definitions_name_the_argument() -> None:
    with pytest.raises(ValueError, match="xl/xu"):
        Sphere(2, xl=1.0, xu=0.0)
    with pytest.raises(ValueError, match="xl: expected shape"):
        Sphere(3, xl=np.zeros(2), xu=1.0)
    with pytest.raises(ValueError, match="resolution"):
        Sphere(2, resolution=-0.1)
    with pytest.raises(ValueError, match="resolution: no multiple"):
        Sphere(1, xl=0.11, xu=0.19, resolution=0.1)
    with pytest.raises(ValueError, match="n_var"):
        Sphere(0)


def test_bad_evaluate_output_is_reported() -> None:
    class Wrong(Problem):
        def __init__(self) -> None:
            super().__init__(2, 2, 0, xl=0.0, xu=1.0)

        def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, None]:
            return X[:, :1], None

    with pytest.raises(ValueError, match=r"F: Wrong returned shape \(3, 1\)"):
        Wrong().evaluate(np.zeros((3, 2)))


def test_integer_coding_gene_bounds_and_snap() -> None:
    p = Sphere(3, xl=-0.3, xu=0.35, resolution=0.1)
    k_lo, k_hi = p.gene_bounds()
    assert k_lo.tolist() == [-3] * 3 and k_hi.tolist() == [3] * 3  # -0.3 is on the grid
    X = p.snap(np.array([[0.04, 0.06, 9.0], [-0.31, -0.29, 0.26]]))
    np.testing.assert_allclose(X, [[0.0, 0.1, 0.3], [-0.3, -0.3, 0.3]])
    np.testing.assert_allclose(X / 0.1, np.rint(X / 0.1), atol=1e-9)


def test_decode_and_baselines_defaults() -> None:
    p = Rosenbrock(4)
    assert np.array_equal(p.decode(np.ones(4))["x"], np.ones(4))
    np.testing.assert_allclose(p.evaluate(p.baselines()["optimum"])[0], 0.0)
    with pytest.raises(ValueError, match="x: expected shape"):
        p.decode(np.ones(3))


@pytest.mark.parametrize("cls", [Sphere, Rosenbrock, Rastrigin])
def test_single_objective_optimum(cls: type) -> None:
    p = cls(10)
    F, _ = p.evaluate(np.vstack([p.x_opt, p.x_opt + 0.1]))
    assert F[0, 0] == pytest.approx(p.f_opt, abs=1e-12)
    assert F[1, 0] > F[0, 0]


def test_rastrigin_values() -> None:
    F, _ = Rastrigin(2).evaluate(np.array([[1.0, 0.0], [0.5, 0.5]]))
    np.testing.assert_allclose(F[:, 0], [1.0, 20 + 2 * (0.25 + 10)])


@pytest.mark.parametrize("cls", [ZDT1, ZDT2])
def test_zdt_front_points_are_attained_with_g_equal_one(cls: type) -> None:
    p = cls(30)
    x1 = np.linspace(0, 1, 11)
    X = np.zeros((11, 30))
    X[:, 0] = x1
    F, _ = p.evaluate(X)
    front = p.pareto_front(11)
    np.testing.assert_allclose(F, front, atol=1e-12)


def test_dtlz2_front_is_the_unit_sphere() -> None:
    p = DTLZ2(12, 3)
    X = np.random.default_rng(0).random((50, 12))
    X[:, 2:] = 0.5  # g = 0
    F, _ = p.evaluate(X)
    np.testing.assert_allclose(np.linalg.norm(F, axis=1), 1.0)
    pf = p.pareto_front(300)
    assert pf.shape == (300, 3)
    np.testing.assert_allclose(np.linalg.norm(pf, axis=1), 1.0)
    # off the front: norm = 1 + g
    X[:, 2:] = 0.0
    F, _ = p.evaluate(X)
    np.testing.assert_allclose(np.linalg.norm(F, axis=1), 1.0 + 10 * 0.25)


def test_get_benchmark_by_name() -> None:
    assert isinstance(get_benchmark("ZDT1", n_var=5), ZDT1)
    with pytest.raises(ValueError, match="name: unknown benchmark"):
        get_benchmark("nope")
