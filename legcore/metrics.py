"""Multi-objective metrics: non-dominated sorting, hypervolume, IGD and knee point.

All objectives are minimised. ``F`` is always an ``(n, m)`` array of objective vectors.

- ``non_dominated_sort`` ranks points into fronts (0 = non-dominated): Deb's fast sort, compiled
  (``legcore.pareto_kernels``); with ``cv`` it applies Deb's constrained domination (feasible
  first, then by violation). ``crowding_distance`` is compiled too.
- ``hypervolume`` is exact (moocore, what pymoo's indicator calls) and returns the value together
  with the reference point it was measured against, so a number is never reported without it.
- ``igd`` is the mean distance from each point of a reference front to its nearest point in ``F``.
- ``knee_point`` is the point of a front farthest (on the ideal side) from the hyperplane through
  the front's extreme points, in objectives normalised by the front's ideal and nadir.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.distance import cdist

from legcore.pareto_kernels import (
    constrained_ranks_kernel,
    crowding_kernel,
    knee_kernel,
    pareto_ranks_kernel,
)

__all__ = [
    "covers",
    "dominance_matrix",
    "non_dominated_sort",
    "non_dominated_mask",
    "fronts",
    "crowding_distance",
    "Hypervolume",
    "hypervolume",
    "hypervolume_value",
    "reference_point",
    "igd",
    "knee_point",
]

# Elements of the temporaries built per block (about 32 MB of floats / 4 MB of booleans).
_BLOCK_ELEMENTS = 4_000_000


def _as_F(F: ArrayLike, name: str = "F") -> np.ndarray:
    F = np.asarray(F, dtype=float)
    if F.ndim != 2:
        raise ValueError(f"{name}: expected a 2-D array (n, n_obj), got shape {F.shape}")
    if np.any(np.isnan(F)):
        raise ValueError(f"{name}: contains NaN")
    return F


def covers(A: ArrayLike, B: ArrayLike) -> np.ndarray:
    """``C[i, j]`` is True when ``A[i] <= B[j]`` in every objective (weak dominance or equality).

    Computed objective by objective over row blocks (``(len(A), len(B))`` booleans).
    """
    A, B = _as_F(A, "A"), _as_F(B, "B")
    if A.shape[1] != B.shape[1]:
        raise ValueError(f"A/B: different numbers of objectives ({A.shape[1]}, {B.shape[1]})")
    na, nb = A.shape[0], B.shape[0]
    out = np.empty((na, nb), dtype=bool)
    if na == 0 or nb == 0:
        return out
    block = max(1, _BLOCK_ELEMENTS // nb)
    for s in range(0, na, block):
        rows, o = A[s:s + block], out[s:s + block]
        np.less_equal(rows[:, 0, None], B[None, :, 0], out=o)
        for k in range(1, A.shape[1]):
            o &= rows[:, k, None] <= B[None, :, k]
    return out


def dominance_matrix(F: ArrayLike) -> np.ndarray:
    """``D[i, j]`` is True when point ``i`` Pareto-dominates point ``j`` (minimisation).

    ``i`` dominates ``j`` when ``F[i] <= F[j]`` in every objective and ``F[i] != F[j]``.
    Memory: ``n^2`` booleans.
    """
    le = covers(F, F)
    # all(Fi <= Fj) and not all(Fj <= Fi)  <=>  Fi <= Fj everywhere and Fi < Fj somewhere
    return le & ~le.T


def non_dominated_sort(F: ArrayLike, cv: ArrayLike | None = None) -> np.ndarray:
    """Front index of every point (0 = non-dominated), Deb et al. 2002.

    Args:
        F: ``(n, m)`` objective values.
        cv: optional ``(n,)`` constraint violations (``0`` = feasible). With it, feasible points
            are ranked first by Pareto dominance; infeasible points follow, ranked by increasing
            violation (equal violations share a front) — Deb's constrained domination.

    Returns:
        ``(n,)`` int64 ranks.
    """
    F = np.ascontiguousarray(_as_F(F))
    n = F.shape[0]
    ranks = np.zeros(n, dtype=np.int64)
    if n == 0:
        return ranks
    if cv is None:
        pareto_ranks_kernel(F, ranks)
        return ranks
    cv = np.ascontiguousarray(cv, dtype=float)
    if cv.shape != (n,):
        raise ValueError(f"cv: expected shape ({n},), got {cv.shape}")
    constrained_ranks_kernel(F, cv, ranks)
    return ranks


def non_dominated_mask(F: ArrayLike) -> np.ndarray:
    """Boolean mask of the non-dominated points of ``F`` (duplicates are all kept)."""
    F = _as_F(F)
    if F.shape[0] == 0:
        return np.zeros(0, dtype=bool)
    return np.asarray(~dominance_matrix(F).any(axis=0))


def fronts(ranks: ArrayLike) -> list[np.ndarray]:
    """Indices of each front, in order, from the ranks of ``non_dominated_sort``."""
    ranks = np.asarray(ranks)
    if ranks.size == 0:
        return []
    order = np.argsort(ranks, kind="stable")
    splits = np.flatnonzero(np.diff(ranks[order])) + 1
    return np.split(order, splits)


def crowding_distance(F: ArrayLike, ranks: ArrayLike | None = None) -> np.ndarray:
    """NSGA-II crowding distance of every point within its front (Deb et al. 2002).

    For each objective the points of a front are sorted; a point gets the normalised gap between
    its two neighbours (objective range of its front), summed over objectives. The extremes of
    every objective get ``inf``; so do fronts of one or two points.

    Args:
        F: ``(n, m)`` objective values.
        ranks: front index per point (default: all in one front).

    Returns:
        ``(n,)`` float array.
    """
    F = _as_F(F)
    n, m = F.shape
    if ranks is None:
        ranks = np.zeros(n, dtype=np.int64)
    ranks = np.asarray(ranks)
    if ranks.shape != (n,):
        raise ValueError(f"ranks: expected shape ({n},), got {ranks.shape}")
    cd = np.zeros(n)
    if n == 0:
        return cd
    crowding_kernel(np.ascontiguousarray(F), np.ascontiguousarray(ranks, dtype=np.int64), cd)
    return cd


@dataclass(frozen=True)
class Hypervolume:
    """A hypervolume value together with the reference point it was measured against."""

    value: float
    ref_point: tuple[float, ...]
    n_points: int

    def __float__(self) -> float:
        return self.value


def reference_point(F: ArrayLike, margin: float = 0.1) -> np.ndarray:
    """A reference point ``nadir + margin * (nadir - ideal)`` of ``F`` (fixed once per study)."""
    F = _as_F(F)
    if F.shape[0] == 0:
        raise ValueError("F: cannot derive a reference point from an empty set")
    ideal, nadir = F.min(axis=0), F.max(axis=0)
    span = np.where(nadir > ideal, nadir - ideal, 1.0)
    return nadir + margin * span


def hypervolume(F: ArrayLike, ref_point: ArrayLike) -> Hypervolume:
    """Exact hypervolume dominated by ``F`` and bounded by ``ref_point`` (minimisation).

    Points that do not strictly dominate ``ref_point`` contribute nothing. Compare runs only
    with the same reference point; it is recorded in the result.
    """
    F = _as_F(F)
    ref = np.asarray(ref_point, dtype=float).ravel()
    if ref.shape != (F.shape[1],):
        raise ValueError(f"ref_point: expected {F.shape[1]} coordinates, got {ref.shape[0]}")
    if not np.all(np.isfinite(ref)):
        raise ValueError("ref_point: must be finite")
    n_inside = int(np.all(F < ref, axis=1).sum())
    value = hypervolume_value(F, ref) if n_inside else 0.0
    return Hypervolume(value=value, ref_point=tuple(float(r) for r in ref), n_points=n_inside)


def hypervolume_value(F: np.ndarray, ref: np.ndarray) -> float:
    """:func:`hypervolume`'s value without its checks, for a caller that measures many fronts
    against one checked reference point (the worker, every generation): ``F`` (n, m) float64
    without NaN, ``ref`` (m,) finite. Points that do not strictly dominate ``ref`` contribute
    nothing (moocore, what pymoo's indicator calls, ignores them)."""
    from moocore import hypervolume as exact_hypervolume

    return float(exact_hypervolume(F, ref=ref)) if F.shape[0] else 0.0


def igd(F: ArrayLike, reference_front: ArrayLike) -> float:
    """Inverted generational distance: mean over the reference front of the distance to ``F``."""
    F = _as_F(F)
    R = _as_F(reference_front, "reference_front")
    if F.shape[1] != R.shape[1]:
        raise ValueError(f"reference_front: {R.shape[1]} objectives, F has {F.shape[1]}")
    if F.shape[0] == 0 or R.shape[0] == 0:
        raise ValueError("F/reference_front: both must be non-empty")
    d = np.empty(R.shape[0])
    block = max(1, _BLOCK_ELEMENTS // F.shape[0])
    for s in range(0, R.shape[0], block):
        d[s:s + block] = cdist(R[s:s + block], F).min(axis=1)
    return float(d.mean())


def knee_point(F: ArrayLike) -> int:
    """Index of the knee of a front: max distance to the hyperplane through its extremes.

    Objectives are normalised to ``[0, 1]`` by the front's ideal and nadir. The extreme points are
    the minimisers of each objective (ties broken by the smallest normalised sum). The knee is the
    point with the largest signed distance from the hyperplane through them, on the ideal side
    (for two objectives: the line through the two end points of the front). When the extremes do
    not span a hyperplane (fewer than ``m`` distinct extremes, or a plane through the ideal), the
    knee falls back to the point closest to the ideal point in the normalised space. Distances
    within 1e-12 of each other are a tie, won by the first point.

    Dominated points in ``F`` are allowed but the result is only meaningful for a front.
    """
    F = np.ascontiguousarray(_as_F(F))
    if F.shape[0] == 0:
        raise ValueError("F: cannot take the knee of an empty set")
    return int(knee_kernel(F))
