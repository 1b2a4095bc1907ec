"""Support polygons and static stability of legged robots: :func:`support_polygon` (convex hull
of the stance feet in the ground plane, counter-clockwise) and :func:`stability_margin` (minimum
signed distance from the body centre / COM projection to the hull's edge lines, positive
inside). Units: m (any consistent length unit works).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["stability_margin", "support_polygon"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _prepare(feet: ArrayLike, support: ArrayLike | None) -> tuple[FloatArray, BoolArray, float]:
    P = np.asarray(feet, dtype=float)
    if P.ndim < 2 or P.shape[-1] not in (2, 3):
        raise ValueError(f"feet: expected shape (..., k, 2) or (..., k, 3), got {P.shape}")
    P = P[..., :2]
    if support is None:
        S = np.ones(P.shape[:-1], dtype=bool)
    else:
        S = np.asarray(support, dtype=bool)
        try:
            S = np.broadcast_to(S, P.shape[:-1])
        except ValueError:
            raise ValueError(
                f"support: shape {S.shape} does not match feet {P.shape[:-1]} (..., k)"
            ) from None
    S = S & np.all(np.isfinite(P), axis=-1)
    finite = P[np.broadcast_to(S[..., None], P.shape)]
    scale = float(np.abs(finite).max()) if finite.size else 1.0
    return P, S, max(scale, 1e-300)


def _hull_edges(P: FloatArray, S: BoolArray, eps_area: float, eps_len: float) -> BoolArray:
    """(..., k, k) True where i→j is a counter-clockwise edge line of the stance hull (every
    stance foot on its left or on it)."""
    k = P.shape[-2]
    d = P[..., None, :, :] - P[..., :, None, :]  # d[..., i, j] = P_j − P_i
    rel = P[..., None, :, :] - P[..., :, None, :]  # rel[..., i, m] = P_m − P_i
    cr = _cross(d[..., :, :, None, :], rel[..., :, None, :, :])  # (..., i, j, m)
    left = (cr >= -eps_area) | ~S[..., None, None, :]
    pair = S[..., :, None] & S[..., None, :] & ~np.eye(k, dtype=bool)
    pair &= np.linalg.norm(d, axis=-1) > eps_len
    return pair & np.all(left, axis=-1)


def _degenerate(P: FloatArray, S: BoolArray, eps_area: float) -> BoolArray:
    """(...,) True where fewer than three stance feet or all stance feet are collinear."""
    rel = P[..., None, :, :] - P[..., :, None, :]  # (..., i, m)
    cr = _cross(rel[..., :, :, None, :], rel[..., :, None, :, :])  # (..., i, j, m)
    mask = S[..., :, None, None] & S[..., None, :, None] & S[..., None, None, :]
    area = np.where(mask, np.abs(cr), 0.0).max(axis=(-3, -2, -1), initial=0.0)
    return (S.sum(axis=-1) < 3) | (area <= eps_area)


def support_polygon(
    feet: ArrayLike, support: ArrayLike | None = None
) -> tuple[FloatArray, NDArray[np.int64]]:
    """Convex hull of the stance feet projected on the ground plane (x, y).

    Args:
        feet: foot positions (..., k, 2|3) (m); only x and y are used.
        support: (..., k) bool, True for feet on the ground (default: all).

    Returns:
        ``(vertices, n)``: vertices (..., k, 2) counter-clockwise, padded with NaN after the
        first ``n`` rows; n (...,) the number of hull vertices (collinear stance feet give the
        two end points, coincident feet count once).
    """
    P, S, scale = _prepare(feet, support)
    k = P.shape[-2]
    eps_len = 1e-12 * scale
    eps_area = 1e-12 * scale * scale
    edges = _hull_edges(P, S, eps_area, eps_len)
    # Drop feet lying strictly inside a hull edge (collinear middle points) and duplicates.
    d = P[..., None, :, :] - P[..., :, None, :]  # (..., i, j)
    rel = P[..., None, :, :] - P[..., :, None, :]  # (..., i, m)
    cr = _cross(d[..., :, :, None, :], rel[..., :, None, :, :])  # (..., i, j, m)
    dd = np.sum(d * d, axis=-1)[..., None]
    t = np.sum(d[..., :, :, None, :] * rel[..., :, None, :, :], axis=-1) / np.where(dd > 0, dd, 1.0)
    inner = (np.abs(cr) <= eps_area) & (t > 1e-12) & (t < 1.0 - 1e-12) & edges[..., None]
    inner = inner.any(axis=(-3, -2))
    close = np.linalg.norm(rel, axis=-1) <= eps_len  # (..., i, m)
    earlier = np.tril(np.ones((k, k), dtype=bool), -1)  # i < m  ->  [m, i] lower triangle
    dup = np.any(close.swapaxes(-1, -2) & earlier & S[..., None, :], axis=-1)
    vert = S & ~inner & ~dup & (edges.any(axis=-1) | (S.sum(axis=-1, keepdims=True) == 1))
    n = vert.sum(axis=-1)
    # Counter-clockwise order by angle about the vertex centroid.
    w = vert.astype(float)
    centre = np.sum(P * w[..., None], axis=-2) / np.maximum(n, 1)[..., None]
    ang = np.arctan2(P[..., 1] - centre[..., None, 1], P[..., 0] - centre[..., None, 0])
    ang = np.where(vert, ang, np.inf)
    order = np.argsort(ang, axis=-1, kind="stable")
    V = np.take_along_axis(P, order[..., None], axis=-2)
    keep = np.arange(k) < n[..., None]
    V = np.where(keep[..., None], V, np.nan)
    return V, n.astype(np.int64)


def stability_margin(
    feet: ArrayLike, support: ArrayLike | None = None, c: ArrayLike | None = None
) -> FloatArray:
    """Static stability margin: minimum signed distance from ``c`` to the support-polygon edges.

    Args:
        feet: foot positions (..., k, 2|3) (m), x and y used.
        support: (..., k) bool, True for feet on the ground (default: all).
        c: body centre / COM ground projection (2,) or (..., 2|3) (m); default the origin.

    Returns:
        (...,) margin in m. Inside the polygon it is the distance to the nearest edge (> 0);
        outside it is negative (the largest excursion beyond an edge line). With fewer than three
        stance feet or collinear ones (zero-area support) it is minus the distance to the
        support segment/point (≤ 0); with no foot on the ground −inf.
    """
    P, S, scale = _prepare(feet, support)
    C = np.zeros(2) if c is None else np.asarray(c, dtype=float)
    if C.ndim == 0 or C.shape[-1] not in (2, 3):
        raise ValueError(f"c: expected shape (2,) or (..., 2|3), got {C.shape}")
    C = C[..., :2]
    scale = max(scale, float(np.abs(C).max()) if C.size else 0.0)
    eps_len = 1e-12 * scale
    eps_area = 1e-12 * scale * scale
    batch = np.broadcast_shapes(P.shape[:-2], C.shape[:-1])
    P = np.broadcast_to(P, batch + P.shape[-2:])
    S = np.broadcast_to(S, batch + S.shape[-1:])
    C = np.broadcast_to(C, batch + (2,))

    edges = _hull_edges(P, S, eps_area, eps_len)
    d = P[..., None, :, :] - P[..., :, None, :]  # (..., i, j)
    rc = C[..., None, :] - P  # (..., i, 2): c − P_i
    length = np.linalg.norm(d, axis=-1)
    signed = _cross(d, rc[..., :, None, :]) / np.where(length > 0, length, 1.0)
    m_poly = np.where(edges, signed, np.inf).min(axis=(-2, -1), initial=np.inf)

    # Degenerate support: minus the distance to the segment hull of the stance feet.
    dd = length**2
    t = np.sum(d * rc[..., :, None, :], axis=-1) / np.where(dd > 0, dd, 1.0)
    t = np.clip(t, 0.0, 1.0)
    gap = rc[..., :, None, :] - t[..., None] * d
    dist = np.linalg.norm(gap, axis=-1)
    pair = S[..., :, None] & S[..., None, :]
    m_seg = -np.where(pair, dist, np.inf).min(axis=(-2, -1), initial=np.inf)

    degenerate = _degenerate(P, S, eps_area)
    return np.where(degenerate, m_seg, m_poly)
