"""Geometry helpers of the ``swing_energy`` study (seed 000): via-point basis, box clearance.

- :func:`via_basis` — the clamped cubic spline of :class:`~legcore.trajectories.ViaPointSpline`
  is *linear* in its via-point values (the end conditions q̇ = 0 are homogeneous), so sampling it
  once on the unit vectors gives matrices ``N_d`` (K, J) with ``q^(d)(t_k) = Σ_j N_d[k, j] q_j``.
  A whole population is then one matrix product (no spline object per individual).
- :func:`segment_box_depth` — exact "does segment a→b enter the (grown) box" by the slab method,
  with a penetration depth (≥ 0, 0 = no interior intersection) for the constraint.
- :func:`point_box_distance` — signed distance of points to a box (negative inside), used to
  report the clearance of a decoded trajectory.
- :func:`chain_clearance` — the same slab test compiled with numba over a whole batch of
  sampled chains and all boxes in one pass (the GA's constraint evaluation), plus the lowest
  joint height.
- :func:`travel_and_peak` — per-joint travel Σ|Δq| and peak |q̈| of a batch in one pass (the
  score's reductions over the time axis).

Shapes: points ``(..., 3)`` m; boxes are axis-aligned, ``center`` (3,) and ``half`` (3,) m.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.trajectories import ViaPointSpline

__all__ = [
    "chain_clearance",
    "point_box_distance",
    "segment_box_depth",
    "travel_and_peak",
    "via_basis",
]

FloatArray = NDArray[np.float64]


def via_basis(t_via: ArrayLike, t: ArrayLike) -> FloatArray:
    """Basis matrices (4, K, J) of the clamped cubic via-point spline.

    ``t_via`` (J,) s: via-point times (start and end included); ``t`` (K,) s: sample times.
    Row d of the result maps the J via-point values to the d-th time derivative at ``t``
    (d = 0: q, 1: q̇, 2: q̈, 3: jerk), i.e. ``ViaPointSpline(t_via, q_via).evaluate(t)`` equals
    ``einsum("dkj,bjn->dbkn", N, q_via)``.
    """
    t_via = np.asarray(t_via, dtype=float)
    J = t_via.shape[0]
    spline = ViaPointSpline(t_via, np.eye(J)[:, :, None], kind="cubic")  # batch of unit vectors
    s = spline.evaluate(np.asarray(t, dtype=float))
    # each is (J, K, 1): basis function j sampled at t
    return np.stack([s.q[..., 0].T, s.qd[..., 0].T, s.qdd[..., 0].T, s.qddd[..., 0].T])


def segment_box_depth(
    a: ArrayLike, b: ArrayLike, center: ArrayLike, half: ArrayLike
) -> FloatArray:
    """Penetration depth (m) of segments ``a→b`` (each (..., 3)) into an axis-aligned box.

    Slab method: the part of the segment inside the box is ``λ ∈ [λ_in, λ_out]``; where it is
    not empty the depth is ``min_axis(half − |p − center|)`` at its midpoint (> 0 exactly when
    the segment passes through the box interior), else 0. Returns (...,) ≥ 0.
    """
    a = np.asarray(a, dtype=float)
    d = np.asarray(b, dtype=float) - a
    c = np.asarray(center, dtype=float)
    h = np.asarray(half, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t1 = (c - h - a) * inv
        t2 = (c + h - a) * inv
    flat = np.abs(d) < 1e-15  # segment parallel to the slab: inside it or never
    inside_slab = np.abs(a - c) <= h
    lo = np.where(flat, np.where(inside_slab, -np.inf, np.inf), np.minimum(t1, t2))
    hi = np.where(flat, np.where(inside_slab, np.inf, -np.inf), np.maximum(t1, t2))
    lam_in = np.clip(lo.max(axis=-1), 0.0, 1.0)
    lam_out = np.clip(hi.min(axis=-1), 0.0, 1.0)
    hit = lam_in < lam_out
    lam = 0.5 * (lam_in + lam_out)
    p = a + lam[..., None] * d
    depth = np.min(h - np.abs(p - c), axis=-1)
    return np.where(hit, np.maximum(depth, 0.0), 0.0)


def point_box_distance(p: ArrayLike, center: ArrayLike, half: ArrayLike) -> FloatArray:
    """Signed distance (m) of points ``p`` (..., 3) to an axis-aligned box: > 0 outside (the
    Euclidean distance), < 0 inside (minus the distance to the nearest face)."""
    q = np.abs(np.asarray(p, dtype=float) - np.asarray(center, dtype=float)) - np.asarray(half)
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=-1)
    inside = np.minimum(q.max(axis=-1), 0.0)
    return outside + inside


@numba.njit(cache=True, nogil=True)
def _segment_depth(a: FloatArray, b: FloatArray, c: FloatArray, h: FloatArray) -> float:
    """:func:`segment_box_depth` of one segment (slab method; 0 when it misses the box)."""
    lam_in, lam_out = 0.0, 1.0
    for ax in range(3):
        d = b[ax] - a[ax]
        lo_face = c[ax] - h[ax]
        hi_face = c[ax] + h[ax]
        if abs(d) < 1e-15:
            if a[ax] < lo_face or a[ax] > hi_face:
                return 0.0
            continue
        t1 = (lo_face - a[ax]) / d
        t2 = (hi_face - a[ax]) / d
        if t1 > t2:
            t1, t2 = t2, t1
        lam_in = max(lam_in, t1)
        lam_out = min(lam_out, t2)
        if lam_in >= lam_out:
            return 0.0
    lam = 0.5 * (lam_in + lam_out)
    depth = np.inf
    for ax in range(3):
        p = a[ax] + lam * (b[ax] - a[ax])
        depth = min(depth, h[ax] - abs(p - c[ax]))
    return max(depth, 0.0)


@numba.njit(cache=True, nogil=True)
def _chain_kernel(P: FloatArray, c: FloatArray, h: FloatArray,
                  depth: FloatArray, zmin: FloatArray) -> None:  # pragma: no cover - compiled
    """depth (B,): max segment depth over the boxes c/h (nb, 3); zmin (B,): lowest point z."""
    B, K, M, _ = P.shape
    nb = c.shape[0]
    lo = c - h
    hi = c + h
    for b in range(B):
        dmax = 0.0
        z = np.inf
        for k in range(K):
            Pk = P[b, k]
            for m in range(1, M):
                z = min(z, Pk[m, 2])
                for j in range(nb):
                    # bounding boxes apart on an axis: the slab test gives 0 too (exactly)
                    miss = False
                    for ax in range(3):
                        u = Pk[m - 1, ax]
                        v = Pk[m, ax]
                        if (u < lo[j, ax] and v < lo[j, ax]) or (u > hi[j, ax] and v > hi[j, ax]):
                            miss = True
                            break
                    if not miss:
                        dmax = max(dmax, _segment_depth(Pk[m - 1], Pk[m], c[j], h[j]))
        depth[b] = dmax
        zmin[b] = z


def chain_clearance(
    P: ArrayLike, center: ArrayLike | None = None, half: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """Box penetration and lowest point of sampled chains.

    ``P`` (B, K, M, 3) m: M points along each chain (joint origins, base first) at K samples
    (C-contiguous avoids a copy). ``center``/``half`` (3,) m: one box, or (nb, 3): several.
    Returns ``(depth, z_min)``, each (B,). ``depth``: the largest :func:`segment_box_depth` of
    the M − 1 segments over the K samples into the boxes (0 when nothing enters, 0 without a
    box). ``z_min``: the lowest z of points 1..M−1 (the base point is left out). One pass over
    ``P`` for all boxes; a segment whose bounding box misses a box is skipped.
    """
    P = np.ascontiguousarray(P, dtype=np.float64)
    if P.ndim != 4 or P.shape[-1] != 3 or P.shape[2] < 2:
        raise ValueError(f"P: expected shape (B, K, M >= 2, 3), got {P.shape}")
    if center is None:
        c = np.zeros((0, 3))
        h = np.zeros((0, 3))
    else:
        c = np.ascontiguousarray(np.asarray(center, dtype=np.float64).reshape(-1, 3))
        h = np.ascontiguousarray(np.broadcast_to(
            np.asarray(half if half is not None else np.zeros(3), dtype=np.float64), c.shape))
    depth = np.empty(P.shape[0])
    zmin = np.empty(P.shape[0])
    _chain_kernel(P, c, h, depth, zmin)
    return depth, zmin


@numba.njit(cache=True, nogil=True)
def _travel_peak_kernel(q: FloatArray, qdd: FloatArray, theta: FloatArray,
                        acc: FloatArray) -> None:  # pragma: no cover - compiled
    B, K, n = q.shape
    for b in range(B):
        for i in range(n):
            theta[b, i] = 0.0
            acc[b, i] = 0.0
        for i in range(n):
            acc[b, i] = abs(qdd[b, 0, i])
        for k in range(1, K):
            for i in range(n):
                theta[b, i] += abs(q[b, k, i] - q[b, k - 1, i])
                a = abs(qdd[b, k, i])
                if a > acc[b, i]:
                    acc[b, i] = a


def travel_and_peak(q: ArrayLike, qdd: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Per joint: travel ``Σ_k |q_k − q_{k−1}|`` (rad) and peak ``max_k |q̈_k|`` (rad/s²).

    ``q``, ``qdd`` (B, K, n) → two (B, n) arrays (one pass, summed in k order: equal to
    ``np.sum(np.abs(np.diff(q, axis=1)), axis=1)`` and ``np.max(np.abs(qdd), axis=1)``).
    """
    q = np.ascontiguousarray(q, dtype=np.float64)
    qdd = np.ascontiguousarray(qdd, dtype=np.float64)
    if q.ndim != 3 or q.shape != qdd.shape or q.shape[1] < 1:
        raise ValueError(f"q, qdd: expected equal shapes (B, K >= 1, n), got {q.shape}, "
                         f"{qdd.shape}")
    theta = np.empty((q.shape[0], q.shape[2]))
    acc = np.empty((q.shape[0], q.shape[2]))
    _travel_peak_kernel(q, qdd, theta, acc)
    return theta, acc
