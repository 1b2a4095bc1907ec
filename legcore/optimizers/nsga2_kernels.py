"""Compiled pieces of an NSGA-II generation (:mod:`legcore.optimizers.nsga2`).

Each kernel returns exactly what the plain NumPy/Python formulation it replaced returns (same
indices, same order); ``tests/legcore/optimizers/test_nsga2_kernels.py`` checks them against
those formulations on random, tied and constrained sets. Together they take an NSGA-II
generation of 100 + 100 points from ~1 ms of interpreter overhead to a few tens of µs.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from legcore.pareto_kernels import constrained_ranks_kernel, crowding_kernel

__all__ = ["novel_rows_kernel", "survivors_kernel", "tournament_kernel", "unique_rows_kernel"]


@numba.njit(cache=True, nogil=True)
def tournament_kernel(
    perm: NDArray[np.int64], F: NDArray[np.float64], cv: NDArray[np.float64],
    crowd: NDArray[np.float64], out: NDArray[np.int64],
) -> None:  # pragma: no cover - compiled
    """Winner of each pair ``(perm[2k], perm[2k+1])``: the lower violation if either violates,
    else the Pareto-dominating one, else the larger crowding distance (ties: the first)."""
    m = F.shape[1]
    for k in range(out.shape[0]):
        a = perm[2 * k]
        b = perm[2 * k + 1]
        if cv[a] > 0 or cv[b] > 0:
            out[k] = a if cv[a] <= cv[b] else b
            continue
        a_le = True  # F[a] <= F[b] everywhere
        b_le = True
        a_lt = False  # F[a] < F[b] somewhere
        b_lt = False
        for j in range(m):
            fa = F[a, j]
            fb = F[b, j]
            if fa > fb:
                a_le = False
                b_lt = True
            elif fa < fb:
                b_le = False
                a_lt = True
            elif not (fa == fb):  # NaN: neither side is <= the other
                a_le = False
                b_le = False
        a_dom = a_le and a_lt
        b_dom = b_le and b_lt
        out[k] = a if a_dom or (not b_dom and crowd[a] >= crowd[b]) else b


@numba.njit(cache=True, nogil=True, inline="always")
def _same_row(
    A: NDArray[np.int64], i: int, B: NDArray[np.int64], j: int
) -> bool:  # pragma: no cover
    for k in range(A.shape[1]):
        if A[i, k] != B[j, k]:
            return False
    return True


@numba.njit(cache=True, nogil=True)
def novel_rows_kernel(
    pool: NDArray[np.int64], n_pool: int, cand: NDArray[np.int64], novel: NDArray[np.bool_]
) -> int:  # pragma: no cover - compiled
    """Mark the candidates whose bits differ from every row of ``pool[:n_pool]`` and from every
    earlier novel candidate; novel rows are appended to ``pool``. Returns the new pool size.

    Rows are float64 vectors viewed as int64 (bitwise equality, as ``tobytes`` keys compare).
    ``pool`` must have room for ``n_pool + len(cand)`` rows.
    """
    for i in range(cand.shape[0]):
        seen = False
        for j in range(n_pool):
            if _same_row(cand, i, pool, j):
                seen = True
                break
        novel[i] = not seen
        if not seen:
            pool[n_pool, :] = cand[i, :]
            n_pool += 1
    return n_pool


@numba.njit(cache=True, nogil=True)
def unique_rows_kernel(
    F: NDArray[np.float64], first: NDArray[np.bool_]
) -> None:  # pragma: no cover
    """``first[i]``: row ``i`` of ``F`` equals (``==``, every column) no earlier row."""
    n, m = F.shape
    for i in range(n):
        first[i] = True
        for j in range(i):
            if first[j]:
                same = True
                for k in range(m):
                    if not (F[i, k] == F[j, k]):
                        same = False
                        break
                if same:
                    first[i] = False
                    break


@numba.njit(cache=True, nogil=True)
def survivors_kernel(
    F: NDArray[np.float64], cv: NDArray[np.float64], n: int, keep: NDArray[np.bool_],
    rank: NDArray[np.int64], crowd: NDArray[np.float64],
) -> None:  # pragma: no cover - compiled
    """NSGA-II environmental selection of ``n`` rows of ``F`` (with violations ``cv``) into the
    mask ``keep``: fronts of Deb's constrained domination (written to ``rank``) taken in order,
    the front that does not fit whole truncated by decreasing crowding distance (ties: the
    lower index). ``crowd``: each row's crowding distance within its whole front, as assigned
    before the truncation (Deb 2002; what the next tournament compares)."""
    size = F.shape[0]
    constrained_ranks_kernel(F, cv, rank)
    crowding_kernel(F, rank, crowd)
    if size <= n:
        keep[:] = True
        return
    counts = np.zeros(rank.max() + 2, dtype=np.int64)
    for i in range(size):
        counts[rank[i]] += 1
    split = 0
    taken = 0
    while taken + counts[split] <= n:
        taken += counts[split]
        split += 1
    for i in range(size):
        keep[i] = rank[i] < split
    room = n - taken
    if room == 0:
        return
    members = np.flatnonzero(rank == split)
    neg = np.empty(members.size)
    for a in range(members.size):
        neg[a] = -crowd[members[a]]
    order = np.argsort(neg, kind="mergesort")  # stable: ties keep the lower index
    for a in range(room):
        keep[members[order[a]]] = True
