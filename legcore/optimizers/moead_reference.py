"""MOEA/D's replacement and external-archive update in numpy: the reference formulation.

:mod:`legcore.optimizers.moead` runs the compiled :mod:`legcore.optimizers.moead_kernels`;
these are the vectorised numpy versions they replaced (issue 23), kept as the definition the
kernels are checked against (``tests/legcore/optimizers/test_moead_kernels.py``: equal
populations and archives, bit for bit, over whole seeded runs) and as the "before" of
``benchmarks/bench_finishing.py``. Neither draws random numbers.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from legcore.metrics import covers, crowding_distance, non_dominated_mask

__all__ = ["archive_reference", "replace_reference", "tchebycheff"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def tchebycheff(F: FloatArray, W: FloatArray, z: FloatArray) -> FloatArray:
    """``max_k W_k |F_k - z_k|`` over the last axis (rows of ``F`` against rows of ``W``)."""
    return np.asarray(np.max(W * np.abs(F - z), axis=-1))


def replace_reference(
    neighbors: IntArray, weights: FloatArray, z: FloatArray, F: FloatArray, cv: FloatArray,
    FY: FloatArray, cvY: FloatArray,
) -> tuple[IntArray, IntArray]:
    """Subproblems ``j`` whose solution is replaced and the offspring ``i`` replacing each.

    Offspring ``i`` (objectives ``FY``, violations ``cvY``) competes for every subproblem of its
    neighbourhood ``neighbors[i]`` (n, T); each subproblem takes the best competitor — least
    violation, then least Tchebycheff value against its weights (n, m) and the ideal point
    ``z`` (m,), then the lowest ``i`` — when it beats its current solution (``F``, ``cv``)."""
    n, t = neighbors.shape
    src = np.repeat(np.arange(n), t)          # offspring i ...
    dst = neighbors.ravel()                   # ... competing for subproblem j in B(i)
    g = tchebycheff(FY[src], weights[dst], z)
    c = cvY[src]
    order = np.lexsort((src, g, c, dst))      # by j, then violation, then g, then i
    first = np.r_[True, dst[order][1:] != dst[order][:-1]]
    win = order[first]
    j, i = dst[win], src[win]
    g_cur = tchebycheff(F[j], weights[j], z)
    c_cur = cv[j]
    better = (c[win] < c_cur) | ((c[win] == c_cur) & (g[win] < g_cur))
    return j[better], i[better]


def archive_reference(
    X: FloatArray, F: FloatArray, cv: FloatArray, AX: FloatArray, AF: FloatArray, cap: int,
) -> tuple[FloatArray, FloatArray] | None:
    """The external archive ``(AX, AF)`` after merging a batch ``(X, F, cv)``, or None when the
    batch has no feasible row (the archive is then unchanged).

    The batch's feasible non-dominated rows (the first of equal objective vectors) join the
    archive unless an archive point covers them (dominates or equals); archive points they
    dominate leave. Over ``cap`` points, the most crowded leave (NSGA-II crowding distance;
    ties: the later point)."""
    feas = cv <= 0.0
    if not feas.any():
        return None
    Xn, Fn = X[feas], F[feas]
    keep = non_dominated_mask(Fn)
    Xn, Fn = Xn[keep], Fn[keep]
    _, first = np.unique(Fn, axis=0, return_index=True)
    first = np.sort(first)
    Xn, Fn = Xn[first], Fn[first]
    A = AF
    if A.shape[0]:
        le_na = covers(Fn, A)  # new <= archive
        le_an = covers(A, Fn)  # archive <= new
        a_dominated = (le_na & ~le_an.T).any(axis=0)
        n_covered = le_an.any(axis=0)                           # dominated or equal
        AX = np.vstack([AX[~a_dominated], Xn[~n_covered]])
        A = np.vstack([A[~a_dominated], Fn[~n_covered]])
    else:
        AX, A = Xn, Fn
    if A.shape[0] > cap:
        cd = crowding_distance(A)
        keep_idx = np.sort(np.argsort(-cd, kind="stable")[:cap])
        AX, A = AX[keep_idx], A[keep_idx]
    return AX, A
