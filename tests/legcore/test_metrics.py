"""Metrics: non-dominated sorting, crowding, hypervolume, IGD and knee point."""

from __future__ import annotations

import numpy as np
import pytest

from legcore.metrics import (
    covers,
    crowding_distance,
    dominance_matrix,
    fronts,
    hypervolume,
    igd,
    knee_point,
    non_dominated_mask,
    non_dominated_sort,
    reference_point,
)


def _brute_force_ranks(F: np.ndarray) -> np.ndarray:
    """O(n^2) reference: peel off the points no remaining point dominates."""
    n = len(F)
    dom = np.zeros((n, n), dtype=bool)
    for i in range(n):
        for j in range(n):
            dom[i, j] = bool(np.all(F[i] <= F[j]) and np.any(F[i] < F[j]))
    ranks = np.full(n, -1)
    remaining = set(range(n))
    r = 0
    while remaining:
        front = [j for j in remaining if not any(dom[i, j] for i in remaining)]
        for j in front:
            ranks[j] = r
        remaining -= set(front)
        r += 1
    return ranks


@pytest.mark.parametrize("m", [2, 3, 4])
@pytest.mark.parametrize("seed", [0, 1])
def test_non_dominated_sort_matches_brute_force(m: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    F = np.round(rng.random((120, m)), 1)  # rounding creates ties and duplicates
    ranks = non_dominated_sort(F)
    np.testing.assert_array_equal(ranks, _brute_force_ranks(F))
    np.testing.assert_array_equal(non_dominated_mask(F), ranks == 0)


def _crowding_reference(F: np.ndarray, ranks: np.ndarray) -> np.ndarray:
    """The vectorised numpy formulation the compiled kernel replaced (per objective, one
    lexsort by front then value; ends of each front inf)."""
    n, m = F.shape
    cd = np.zeros(n)
    for k in range(m):
        order = np.lexsort((F[:, k], ranks))
        r, f = ranks[order], F[order, k]
        first = np.r_[True, r[1:] != r[:-1]]
        last = np.r_[r[1:] != r[:-1], True]
        start = np.maximum.accumulate(np.where(first, np.arange(n), 0))
        end = np.minimum.accumulate(np.where(last, np.arange(n), n)[::-1])[::-1]
        span = f[end] - f[start]
        prev, nxt = np.r_[f[0], f[:-1]], np.r_[f[1:], f[-1]]
        with np.errstate(invalid="ignore", divide="ignore"):
            gap = np.where(span > 0, (nxt - prev) / np.where(span > 0, span, 1.0), 0.0)
        cd[order] += np.where(first | last, np.inf, gap)
    return cd


@pytest.mark.parametrize("m", [2, 3])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_crowding_distance_equals_the_numpy_formulation(m: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    for F in (rng.random((200, m)), np.round(rng.random((200, m)), 1), np.ones((5, m))):
        cv = np.where(rng.random(len(F)) < 0.2, rng.integers(1, 4, len(F)), 0).astype(float)
        ranks = non_dominated_sort(F, cv)
        np.testing.assert_array_equal(crowding_distance(F, ranks), _crowding_reference(F, ranks))
        np.testing.assert_array_equal(crowding_distance(F), _crowding_reference(F, 0 * ranks))


def _constrained_ranks_reference(F: np.ndarray, cv: np.ndarray) -> np.ndarray:
    """The numpy formulation the compiled kernel replaced: feasible rows by Pareto fronts,
    infeasible ones after them by dense rank of the violation."""
    ranks = np.zeros(len(F), dtype=np.int64)
    feasible = cv <= 0.0
    n_fronts = 0
    if feasible.any():
        ranks[feasible] = _brute_force_ranks(F[feasible])
        n_fronts = int(ranks[feasible].max()) + 1
    if not feasible.all():
        _, dense = np.unique(cv[~feasible], return_inverse=True)
        ranks[~feasible] = n_fronts + dense
    return ranks


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_constrained_sort_equals_the_numpy_formulation(seed: int) -> None:
    rng = np.random.default_rng(seed)
    F = np.round(rng.random((90, 3)), 1)
    for share in (0.0, 0.3, 1.0):
        cv = np.where(rng.random(len(F)) < share, rng.integers(1, 5, len(F)), 0).astype(float)
        np.testing.assert_array_equal(non_dominated_sort(F, cv),
                                      _constrained_ranks_reference(F, cv))  # fmt: skip


def test_dominance_matrix_small_case() -> None:
    F = np.array([[1.0, 1.0], [1.0, 2.0], [1.0, 1.0], [0.0, 3.0]])
    D = dominance_matrix(F)
    assert D[0, 1] and D[2, 1]
    assert not D[0, 2] and not D[2, 0]  # equal points do not dominate each other
    assert not D[3].any() and not D[:, 3].any()
    np.testing.assert_array_equal(covers(F[:1], F), [[True, True, True, False]])


def test_constrained_sort_puts_feasible_first_then_by_violation() -> None:
    F = np.array([[0.0, 0.0], [5.0, 5.0], [1.0, 1.0], [0.5, 0.5], [9.0, 9.0]])
    cv = np.array([2.0, 0.0, 0.0, 1.0, 2.0])
    ranks = non_dominated_sort(F, cv)
    # feasible: [1] dominated by [2] -> ranks 1 and 0; infeasible by violation: cv 1 -> 2, cv 2 -> 3
    np.testing.assert_array_equal(ranks, [3, 1, 0, 2, 3])
    assert [list(f) for f in fronts(ranks)] == [[2], [1], [3], [0, 4]]


def test_crowding_distance_hand_computed() -> None:
    F = np.array([[0.0, 4.0], [1.0, 2.0], [2.0, 1.0], [4.0, 0.0]])
    cd = crowding_distance(F)
    assert np.isinf(cd[0]) and np.isinf(cd[3])
    # point 1: (2 - 0)/4 + (4 - 1)/4 = 1.25; point 2: (4 - 1)/4 + (2 - 0)/4 = 1.25
    np.testing.assert_allclose(cd[1:3], [1.25, 1.25])
    # per front: two fronts computed independently
    F2 = np.vstack([F, F + 10.0])
    cd2 = crowding_distance(F2, np.r_[np.zeros(4, int), np.ones(4, int)])
    np.testing.assert_allclose(cd2[:4], cd)
    np.testing.assert_allclose(cd2[4:], cd)


def test_hypervolume_of_a_2d_staircase_by_hand() -> None:
    F = np.array([[1.0, 3.0], [2.0, 2.0], [3.0, 1.0]])
    hv = hypervolume(F, [4.0, 4.0])
    # columns: x in [1,2): 4-3=1, [2,3): 2, [3,4): 3  -> 1 + 2 + 3 = 6
    assert hv.value == pytest.approx(6.0)
    assert hv.ref_point == (4.0, 4.0) and hv.n_points == 3
    # dominated and outside points add nothing
    F_more = np.vstack([F, [[2.5, 2.5], [5.0, 0.0]]])
    assert float(hypervolume(F_more, [4.0, 4.0])) == pytest.approx(6.0)
    assert hypervolume(np.array([[5.0, 5.0]]), [4.0, 4.0]).value == 0.0


def test_hypervolume_of_a_3d_box_and_union() -> None:
    F = np.array([[0.0, 0.0, 0.0]])
    assert hypervolume(F, [1.0, 2.0, 3.0]).value == pytest.approx(6.0)
    F = np.array([[0.0, 1.0, 1.0], [1.0, 0.0, 1.0], [1.0, 1.0, 0.0]])
    # three boxes of volume 2*1*1; every pair and the triple intersect in [1,2]^3:
    # inclusion-exclusion 3*2 - 3*1 + 1 = 4
    assert hypervolume(F, [2.0, 2.0, 2.0]).value == pytest.approx(4.0)


def test_hypervolume_rejects_wrong_reference_point() -> None:
    with pytest.raises(ValueError, match="ref_point"):
        hypervolume(np.zeros((2, 2)), [1.0, 1.0, 1.0])


def test_reference_point_adds_margin() -> None:
    F = np.array([[0.0, 2.0], [1.0, 0.0]])
    np.testing.assert_allclose(reference_point(F, 0.1), [1.1, 2.2])


def test_igd_zero_on_the_front_and_grows_with_offset() -> None:
    f1 = np.linspace(0, 1, 201)
    front = np.column_stack([f1, 1 - np.sqrt(f1)])
    assert igd(front, front) == pytest.approx(0.0)
    flat = np.column_stack([f1, np.zeros_like(f1)])
    assert igd(flat + [0.0, 0.1], flat) == pytest.approx(0.1, rel=1e-12)
    # one end point: mean distance to the points of a straight front = mean of |f1|
    assert igd(flat[:1], flat) == pytest.approx(0.5, rel=1e-12)


def test_knee_point_of_a_convex_front() -> None:
    f1 = np.linspace(0, 1, 101)
    front = np.column_stack([f1, (1 - np.sqrt(f1)) ** 2])  # symmetric about f1 = f2
    k = knee_point(front)
    assert front[k, 0] == pytest.approx(0.25, abs=0.011)  # sqrt(f1) = 1/2
    assert front[k, 1] == pytest.approx(0.25, abs=0.011)
    # order does not matter
    perm = np.random.default_rng(0).permutation(len(front))
    assert perm[knee_point(front[perm])] == k


def test_knee_point_of_a_3d_front() -> None:
    rng = np.random.default_rng(1)
    W = rng.random((400, 3))
    sphere = W / np.linalg.norm(W, axis=1, keepdims=True)
    sphere = np.vstack([sphere, np.eye(3)])
    k = knee_point(1.0 - sphere)  # concave in minimisation terms -> the bulge is (1,1,1)/sqrt(3)
    np.testing.assert_allclose(sphere[k], np.full(3, 1 / np.sqrt(3)), atol=0.08)


def test_knee_point_degenerate_inputs() -> None:
    assert knee_point(np.array([[1.0, 2.0]])) == 0
    same = np.array([[1.0, 1.0], [1.0, 1.0]])
    assert knee_point(same) in (0, 1)
    with pytest.raises(ValueError, match="F"):
        knee_point(np.zeros((0, 2)))


def _knee_reference(F: np.ndarray) -> int:
    """The numpy formulation the compiled kernel replaced."""
    n, m = F.shape
    if n == 1:
        return 0
    ideal, nadir = F.min(axis=0), F.max(axis=0)
    span = np.where(nadir > ideal, nadir - ideal, 1.0)
    Z = (F - ideal) / span
    total = Z.sum(axis=1)
    extremes = np.array([np.lexsort((total, Z[:, k]))[0] for k in range(m)])
    fallback = int(np.argmin(np.linalg.norm(Z, axis=1)))
    if np.unique(extremes).size < m:
        return fallback
    try:
        normal = np.linalg.solve(Z[extremes], np.ones(m))
    except np.linalg.LinAlgError:
        return fallback
    norm = float(np.linalg.norm(normal))
    if not np.isfinite(norm) or norm == 0.0 or np.any(normal <= 0):
        return fallback
    dist = (1.0 - Z @ normal) / norm
    return int(np.flatnonzero(dist > dist.max() - 1e-12)[0])  # ties within rounding: first


@pytest.mark.parametrize("m", [2, 3, 4])
def test_knee_point_equals_the_numpy_formulation(m: int) -> None:
    rng = np.random.default_rng(m)
    for trial in range(60):
        n = int(rng.integers(1, 40))
        W = rng.random((n, m)) + 1e-3
        F = 1.0 - W / np.linalg.norm(W, axis=1, keepdims=True) if trial % 3 else W
        if trial % 4 == 0:
            F = np.round(F, 1)  # ties, repeated extremes, singular planes
        assert knee_point(F) == _knee_reference(F), (trial, F)
