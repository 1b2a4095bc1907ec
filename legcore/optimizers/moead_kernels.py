"""Compiled MOEA/D replacement and external-archive update (:mod:`legcore.optimizers.moead`).

Each returns exactly what its numpy formulation in :mod:`legcore.optimizers.moead_reference`
returns — the same subproblems replaced by the same offspring, the same archive rows in the
same order — without that formulation's (n·T) sort, (n, n) dominance matrices and row-unique
sort: one pass over the neighbourhoods; the batch's rows checked against the non-dominated ones
found so far, then its candidates against the archive's rows, then the crowding truncation.
A generation of seed 002 (300 offspring, archive of 300): replacement ~0.03 ms instead of
~0.8 ms, archive update ~0.2 ms instead of ~0.5 ms; with a small archive ~20× less.
``tests/legcore/optimizers/test_moead_kernels.py`` checks them against the references on random,
tied, infinite and constrained inputs and over whole seeded runs (bit-identical populations and
archives). Neither draws random numbers, so a run's random stream is unchanged.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from legcore.optimizers.nsga2_kernels import unique_rows_kernel
from legcore.pareto_kernels import crowding_kernel

__all__ = ["archive_merge_kernel", "replace", "replace_kernel", "update_archive"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


@numba.njit(cache=True, nogil=True, inline="always")
def _before(a: float, b: float) -> bool:  # pragma: no cover - compiled
    """``a`` sorts before ``b`` in numpy's order (NaN last; two NaNs tie)."""
    return a < b or (b != b and a == a)


@numba.njit(cache=True, nogil=True)
def replace_kernel(
    neighbors: IntArray, weights: FloatArray, z: FloatArray, F: FloatArray, cv: FloatArray,
    FY: FloatArray, cvY: FloatArray, win: IntArray,
) -> None:  # pragma: no cover - compiled
    """``win[j]``: the offspring replacing subproblem ``j``'s solution, or −1.

    Offspring ``i`` competes for every ``j`` in ``neighbors[i]``; ``j`` takes the competitor
    first in the order (violation ``cvY``, Tchebycheff value ``max_k w_jk |FY_ik − z_k|``,
    ``i``) — numpy's sort order, NaN last — if it beats the current solution (``cv[j]`` lower,
    or equal and a lower Tchebycheff value of ``F[j]``)."""
    n, t = neighbors.shape
    m = z.shape[0]
    best_c = np.empty(n)
    best_g = np.empty(n)
    win[:] = -1
    for i in range(n):
        c = cvY[i]
        for a in range(t):
            j = neighbors[i, a]
            g = weights[j, 0] * abs(FY[i, 0] - z[0])
            for k in range(1, m):
                v = weights[j, k] * abs(FY[i, k] - z[k])
                if g == g and (v > g or v != v):  # np.max: NaN wins
                    g = v
            b = win[j]
            if b < 0 or _before(c, best_c[j]) or (
                    not _before(best_c[j], c) and _before(g, best_g[j])):
                win[j] = i
                best_c[j] = c
                best_g[j] = g
    for j in range(n):
        if win[j] < 0:
            continue
        g_cur = weights[j, 0] * abs(F[j, 0] - z[0])
        for k in range(1, m):
            v = weights[j, k] * abs(F[j, k] - z[k])
            if g_cur == g_cur and (v > g_cur or v != v):
                g_cur = v
        c = best_c[j]
        if not (c < cv[j] or (c == cv[j] and best_g[j] < g_cur)):
            win[j] = -1


def replace(
    neighbors: IntArray, weights: FloatArray, z: FloatArray, F: FloatArray, cv: FloatArray,
    FY: FloatArray, cvY: FloatArray,
) -> tuple[IntArray, IntArray]:
    """:func:`legcore.optimizers.moead_reference.replace_reference` compiled: ``(j, i)``, the
    subproblems replaced (ascending) and the offspring replacing each."""
    f64 = np.float64
    win = np.empty(neighbors.shape[0], dtype=np.int64)
    replace_kernel(np.ascontiguousarray(neighbors, dtype=np.int64),
                   np.ascontiguousarray(weights, dtype=f64), np.ascontiguousarray(z, dtype=f64),
                   np.ascontiguousarray(F, dtype=f64), np.ascontiguousarray(cv, dtype=f64),
                   np.ascontiguousarray(FY, dtype=f64), np.ascontiguousarray(cvY, dtype=f64),
                   win)
    j = np.flatnonzero(win >= 0)
    return j, win[j]


@numba.njit(cache=True, nogil=True, inline="always")
def _covers(A: FloatArray, i: int, B: FloatArray, j: int) -> bool:  # pragma: no cover
    """``A[i] <= B[j]`` in every objective."""
    for k in range(A.shape[1]):
        if not A[i, k] <= B[j, k]:
            return False
    return True


@numba.njit(cache=True, nogil=True)
def archive_merge_kernel(
    F: FloatArray, cv: FloatArray, A: FloatArray, cap: int, new: BoolArray, old: BoolArray,
) -> int:  # pragma: no cover - compiled
    """Which rows of a batch ``F`` (n, m) with violations ``cv`` join the archive ``A`` (a, m)
    (``new``) and which archive rows stay (``old``); returns the number of feasible rows.

    Joining: feasible (``cv <= 0``), not dominated by another feasible row, the first of equal
    objective vectors (``==``), and covered (``<=`` everywhere) by no archive row. Leaving: an
    archive row dominated by a joining candidate (a row of the previous step before the
    archive's cover test). Then, if the staying and joining rows (in that order) are more than
    ``cap``, only the ``cap`` of largest crowding distance among them stay or join (ties: the
    earlier row; numpy's stable sort of the negated distances)."""
    feas = np.flatnonzero(cv <= 0.0)
    nf = feas.shape[0]
    new[:] = False
    old[:] = True
    if nf == 0:
        return 0
    m = F.shape[1]
    Fn = np.empty((nf, m))
    for a in range(nf):
        Fn[a, :] = F[feas[a], :]
    nd = np.zeros(nf, dtype=np.bool_)  # the non-dominated rows among those seen so far
    front = np.empty(nf, dtype=np.int64)
    size = 0
    for a in range(nf):  # a row dominated by another is dominated by a non-dominated one
        beaten = False
        for p in range(size):
            b = front[p]
            if _covers(Fn, b, Fn, a) and not _covers(Fn, a, Fn, b):
                beaten = True
                break
        if beaten:
            continue
        kept = 0
        for p in range(size):  # the rows ``a`` dominates leave
            b = front[p]
            if _covers(Fn, a, Fn, b) and not _covers(Fn, b, Fn, a):
                nd[b] = False
            else:
                front[kept] = b
                kept += 1
        front[kept] = a
        nd[a] = True
        size = kept + 1
    cand = np.flatnonzero(nd)
    Fc = np.empty((cand.shape[0], m))
    for a in range(cand.shape[0]):
        Fc[a, :] = Fn[cand[a], :]
    first = np.empty(cand.shape[0], dtype=np.bool_)
    unique_rows_kernel(Fc, first)
    for a in range(cand.shape[0]):
        if not first[a]:
            continue
        covered = False
        for j in range(A.shape[0]):
            le = True  # candidate <= archive row j everywhere
            ge = True  # candidate >= archive row j everywhere (the row covers it)
            for k in range(m):
                u = Fc[a, k]
                v = A[j, k]
                le = le and u <= v
                ge = ge and u >= v
                if not (le or ge):
                    break
            if le and not ge:
                old[j] = False
            covered = covered or ge
        new[feas[cand[a]]] = not covered
    rows = np.concatenate((np.flatnonzero(old), np.flatnonzero(new)))
    n_old = rows.shape[0] - np.count_nonzero(new)
    if rows.shape[0] > cap:  # crowding_distance(merged) and its stable order, truncated
        M = np.empty((rows.shape[0], m))
        for r in range(rows.shape[0]):
            M[r, :] = A[rows[r], :] if r < n_old else F[rows[r], :]
        cd = np.empty(rows.shape[0])
        crowding_kernel(M, np.zeros(rows.shape[0], dtype=np.int64), cd)
        order = np.argsort(-cd, kind="mergesort")
        old[:] = False
        new[:] = False
        for r in order[:cap]:
            if r < n_old:
                old[rows[r]] = True
            else:
                new[rows[r]] = True
    return nf


def update_archive(
    X: FloatArray, F: FloatArray, cv: FloatArray, AX: FloatArray, AF: FloatArray, cap: int,
) -> tuple[FloatArray, FloatArray] | None:
    """:func:`legcore.optimizers.moead_reference.archive_reference` compiled: the archive
    ``(AX, AF)`` after merging the batch ``(X, F, cv)`` (capped at ``cap`` rows by crowding),
    or None when the batch has no feasible row (the archive unchanged)."""
    f64 = np.float64
    new = np.empty(F.shape[0], dtype=np.bool_)
    old = np.empty(AF.shape[0], dtype=np.bool_)
    nf = archive_merge_kernel(np.ascontiguousarray(F, dtype=f64),
                              np.ascontiguousarray(cv, dtype=f64),
                              np.ascontiguousarray(AF, dtype=f64), int(cap), new, old)
    if nf == 0:
        return None
    if AF.shape[0] == 0:
        return X[new], F[new]
    return np.concatenate((AX[old], X[new])), np.concatenate((AF[old], F[new]))
