"""The compiled MOEA/D replacement and archive update equal their numpy formulation (issue 23):
the same subproblems replaced by the same offspring, the same archive rows in the same order —
on random inputs with ties, infinities and constraints, and over whole seeded runs (populations,
archives, ideal point and the random generator's state compared bit for bit each generation)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from legcore.optimizers import MOEAD
from legcore.optimizers.moead_kernels import replace, update_archive
from legcore.optimizers.moead_reference import archive_reference, replace_reference
from legcore.problems import Problem
from legcore.problems.benchmarks import DTLZ2, ZDT1


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal shapes, dtypes and bits (so -0.0 differs from 0.0, and NaN equals NaN)."""
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()


def _values(rng: np.random.Generator, shape: tuple[int, ...], kind: str) -> np.ndarray:
    """Objective values: continuous, coarse (many ties and duplicate rows), or with ±0 / inf."""
    if kind == "continuous":
        return rng.random(shape)
    v = np.round(rng.random(shape), 1)
    if kind == "special":
        v = np.where(rng.random(shape) < 0.05, np.inf, v)
        v = np.where(v == 0.0, -0.0, v)
    return v


def _violations(rng: np.random.Generator, n: int, share: float) -> np.ndarray:
    return np.where(rng.random(n) < share, np.round(rng.random(n), 1), 0.0)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("kind", ["continuous", "coarse", "special"])
@pytest.mark.parametrize(("n_obj", "n", "t"), [(2, 40, 8), (3, 91, 20), (3, 15, 15)])
def test_replace_equals_the_numpy_reference(seed: int, kind: str, n_obj: int, n: int,
                                            t: int) -> None:
    rng = np.random.default_rng(seed)
    algo = MOEAD(n_subproblems=n, n_neighbors=t).setup(DTLZ2(6, n_obj) if n_obj == 3
                                                       else ZDT1(6), seed=seed)
    n = algo.pop_size
    F, FY = _values(rng, (n, n_obj), kind), _values(rng, (n, n_obj), kind)
    cv, cvY = _violations(rng, n, 0.3 * (seed % 3)), _violations(rng, n, 0.3 * (seed % 3))
    z = np.minimum(F.min(axis=0), FY.min(axis=0))  # with inf rows: 0 * inf = NaN values of g
    with np.errstate(invalid="ignore"):
        want = replace_reference(algo.neighbors, algo.weights, z, F, cv, FY, cvY)
    got = replace(algo.neighbors, algo.weights, z, F, cv, FY, cvY)
    assert len(want[0]) > 0
    for g, w in zip(got, want, strict=True):
        assert _same(g, w)


def test_replace_orders_nan_tchebycheff_values_last() -> None:
    # an infinite objective against an infinite ideal point: |inf - inf| = NaN, which numpy's
    # sort puts last and no comparison prefers
    nb = np.array([[0, 1], [1, 0]], dtype=np.int64)
    W = np.array([[1.0, 0.0], [0.0, 1.0]])
    z = np.array([np.inf, 0.0])
    F = np.array([[np.inf, 1.0], [np.inf, 1.0]])
    FY = np.array([[np.inf, 0.5], [np.inf, 2.0]])
    zero = np.zeros(2)
    with np.errstate(invalid="ignore"):
        want = replace_reference(nb, W, z, F, zero, FY, zero)
    got = replace(nb, W, z, F, zero, FY, zero)
    for g, w in zip(got, want, strict=True):
        assert _same(g, w)


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("kind", ["continuous", "coarse", "special"])
@pytest.mark.parametrize("n_obj", [2, 3])
def test_archive_update_equals_the_numpy_reference(seed: int, kind: str, n_obj: int) -> None:
    rng = np.random.default_rng(seed)
    n_var = 4
    AX, AF = np.zeros((0, n_var)), np.zeros((0, n_obj))
    cap = int(rng.integers(5, 40))
    for step in range(6):  # the archive grows, saturates and is truncated
        n = int(rng.integers(1, 60))
        X = rng.random((n, n_var))
        F = _values(rng, (n, n_obj), kind)
        if kind != "continuous" and step > 0 and len(AF):  # rows equal to archive rows
            take = rng.integers(0, len(AF), min(n, 5))
            F[: len(take)] = AF[take]
        cv = _violations(rng, n, [0.0, 0.5, 1.0][(seed + step) % 3])
        want = archive_reference(X, F, cv, AX, AF, cap)
        got = update_archive(X, F, cv, AX, AF, cap)
        if want is None:
            assert got is None
            continue
        assert got is not None
        for g, w in zip(got, want, strict=True):
            assert _same(g, w)
        AX, AF = want


class _ReferenceMOEAD(MOEAD):
    """Today's MOEA/D with the numpy replacement and archive update."""

    replace_step = staticmethod(replace_reference)
    archive_step = staticmethod(archive_reference)


class _Constrained(Problem):
    """DTLZ2 (3 objectives) with x1 >= 0.4 and objectives on a coarse grid (ties, duplicates)."""

    def __init__(self) -> None:
        super().__init__(7, 3, 1, xl=0.0, xu=1.0)

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return np.round(DTLZ2(7, 3).evaluate(X)[0], 2), 0.4 - X[:, :1]


def _run_both(problem: Problem, seed: int, generations: int, **params: Any) -> None:
    ours = MOEAD(**params).setup(problem, seed=seed)
    ref = _ReferenceMOEAD(**params).setup(problem, seed=seed)
    for _ in range(generations):
        X = ours.ask()
        assert _same(X, ref.ask())  # the same random draws
        F, G = problem.evaluate(X)
        ours.tell(X, F, G)
        ref.tell(X, F, G)
        for a, b in zip(ours._get_state().values(), ref._get_state().values(), strict=True):
            assert _same(a, b)
        assert ours.rng.bit_generator.state == ref.rng.bit_generator.state


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_runs_equal_the_numpy_moead_generation_by_generation(seed: int) -> None:
    _run_both(ZDT1(8), seed, 15, n_subproblems=40, n_neighbors=8)
    _run_both(_Constrained(), seed, 15, n_subproblems=91, n_neighbors=12, archive_size=30)


@pytest.mark.parametrize("seed", [1, 7])
def test_seed002_runs_equal_the_numpy_moead(seed: int) -> None:
    from legcore.robots import catalog
    from legcore.studies.hexapod_workspace.problem import Params
    from legcore.studies.hexapod_workspace.study import build

    problem = build(catalog.get("citedi_hexapod"), Params())
    _run_both(problem, seed, 8, n_subproblems=300, n_neighbors=20)
