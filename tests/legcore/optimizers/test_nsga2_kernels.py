"""The compiled NSGA-II kernels against the plain formulations they replaced."""

from __future__ import annotations

import numpy as np
import pytest

from legcore.metrics import crowding_distance, non_dominated_sort
from legcore.optimizers.nsga2_kernels import (
    novel_rows_kernel,
    survivors_kernel,
    tournament_kernel,
    unique_rows_kernel,
)


def test_tournament_kernel_equals_the_numpy_formulation() -> None:
    rng = np.random.default_rng(3)
    n = 60
    F = np.round(rng.random((n, 3)), 1)  # ties and duplicates
    cv = np.where(rng.random(n) < 0.3, rng.integers(0, 3, n), 0).astype(float)
    crowd = np.where(rng.random(n) < 0.2, np.inf, np.round(rng.random(n), 1))
    perm = np.concatenate([rng.permutation(n) for _ in range(4)])
    a, b = perm[0::2], perm[1::2]
    Fa, Fb = F[a], F[b]
    a_dom = np.all(Fa <= Fb, axis=1) & np.any(Fa < Fb, axis=1)
    b_dom = np.all(Fb <= Fa, axis=1) & np.any(Fb < Fa, axis=1)
    by_pareto = a_dom | (~b_dom & (crowd[a] >= crowd[b]))
    want = np.where(np.where((cv[a] > 0) | (cv[b] > 0), cv[a] <= cv[b], by_pareto), a, b)
    got = np.empty(len(a), dtype=np.int64)
    tournament_kernel(perm, F, cv, crowd, got)
    np.testing.assert_array_equal(got, want)


def test_novel_rows_kernel_equals_a_set_of_bytes() -> None:
    rng = np.random.default_rng(0)
    parents = np.round(rng.random((30, 4)), 1)
    pool = np.empty((30 + 3 * 40, 4), dtype=np.int64)
    pool[:30] = parents.view(np.int64)
    n_pool = 30
    seen = {row.tobytes() for row in parents}
    for _ in range(3):
        cand = np.round(rng.random((40, 4)), 1)
        cand[::7] = parents[rng.integers(0, 30, len(cand[::7]))]  # copies of parents
        cand[5] = -0.0 * cand[5]  # -0.0 differs bitwise from 0.0, as tobytes keys do
        want = []
        for row in cand:
            want.append(row.tobytes() not in seen)
            seen.add(row.tobytes())
        novel = np.empty(len(cand), dtype=np.bool_)
        n_pool = novel_rows_kernel(pool, n_pool, cand.view(np.int64), novel)
        np.testing.assert_array_equal(novel, want)
        assert n_pool == len(seen)


def test_unique_rows_kernel_equals_numpy_unique() -> None:
    rng = np.random.default_rng(1)
    for F in (np.round(rng.random((80, 3)), 1), rng.random((20, 2)), np.zeros((0, 2))):
        first = np.empty(len(F), dtype=np.bool_)
        unique_rows_kernel(F, first)
        want = np.zeros(len(F), dtype=bool)
        if len(F):
            want[np.unique(F, axis=0, return_index=True)[1]] = True
        np.testing.assert_array_equal(first, want)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_survivors_kernel_equals_the_lexsort_formulation(seed: int) -> None:
    rng = np.random.default_rng(seed)
    size, n = 150, 75
    F = np.round(rng.random((size, 3)), 1 + seed % 2)
    cv = np.where(rng.random(size) < 0.2 * seed, rng.integers(1, 4, size), 0).astype(float)
    rank = non_dominated_sort(F, cv)
    crowd = crowding_distance(F, rank)
    order = np.lexsort((np.arange(size), -crowd, rank))
    want = np.zeros(size, dtype=bool)
    want[order[:n]] = True
    keep = np.empty(size, dtype=np.bool_)
    got_rank = np.empty(size, dtype=np.int64)
    got_crowd = np.empty(size)
    survivors_kernel(F, cv, n, keep, got_rank, got_crowd)
    np.testing.assert_array_equal(keep, want)
    np.testing.assert_array_equal(got_rank, rank)
    np.testing.assert_array_equal(got_crowd, crowd)  # of the whole fronts, before truncation
    survivors_kernel(F[:n], cv[:n], n, keep[:n], got_rank[:n], got_crowd[:n])  # none removed
    assert keep[:n].all()
