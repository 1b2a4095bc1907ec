"""Seed 002's support triangle of a hexapod's tripod: :func:`support_triangle` (β1, β5,
perimeter p, its eqs 12–14), :func:`tripod_feet`, :func:`tripod_triangle` (both vectorised over
a population of θ1 triples) and :func:`tripod_stability` (its S_f, S_b). Units: m and rad.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.ik.leg3 import leg3_fk
from legcore.support_polygon import _cross

__all__ = [
    "UNBOUNDED_SPANS",
    "support_triangle",
    "tripod_feet",
    "tripod_stability",
    "tripod_triangle",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


def _xy(p: ArrayLike, name: str) -> FloatArray:
    arr = np.asarray(p, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] not in (2, 3):
        raise ValueError(f"{name}: expected shape (..., 2) or (..., 3), got {arr.shape}")
    return arr[..., :2]


def support_triangle(
    p1: ArrayLike,
    p3: ArrayLike,
    p5: ArrayLike,
    formula: Literal["interior", "paper"] = "interior",
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Seed 002 eqs (12)–(14): angles β1 (at foot 1), β5 (at foot 5) and perimeter p of the
    support triangle of feet 1, 3, 5 (each (..., 2|3), m; x, y used).

    ``d1 = |p1 − p3|``, ``d2 = |p3 − p5|``, ``d3 = |p1 − p5|``, ``p = d1 + d2 + d3`` (eq 14).

    ``formula="interior"`` (default): the triangle's interior angles at feet 1 and 5
    (``atan2(|u × v|, u · v)``), invariant to how the triangle sits in the plane.
    ``formula="paper"``: eq (12) and (13) literally,
    ``β1 = atan((x1−x5)/(y1−y5)) + atan((x1−x3)/(y1−y3))``, ``β5 = asin(sin β1 · d1/d2)``.
    The two agree when foot 3 is straight behind foot 1 (``x1 = x3``, as in the paper's initial
    stance); otherwise eq (12)'s "+" would need to be "−" (the second term measures the tilt of
    edge 1–3, which *reduces* the angle) and eq (13)'s arcsine cannot return an obtuse β5.

    Returns:
        ``(beta1, beta5, perimeter)`` each of the broadcast batch shape (rad, rad, m).
    """
    a, b, c = _xy(p1, "p1"), _xy(p3, "p3"), _xy(p5, "p5")
    d1 = np.linalg.norm(a - b, axis=-1)
    d2 = np.linalg.norm(b - c, axis=-1)
    d3 = np.linalg.norm(a - c, axis=-1)
    perimeter = d1 + d2 + d3
    if formula == "interior":
        u, v = b - a, c - a
        beta1 = np.arctan2(np.abs(_cross(u, v)), np.sum(u * v, axis=-1))
        u, v = a - c, b - c
        beta5 = np.arctan2(np.abs(_cross(u, v)), np.sum(u * v, axis=-1))
    elif formula == "paper":
        with np.errstate(divide="ignore", invalid="ignore"):
            beta1 = np.arctan((a[..., 0] - c[..., 0]) / (a[..., 1] - c[..., 1])) + np.arctan(
                (a[..., 0] - b[..., 0]) / (a[..., 1] - b[..., 1])
            )
            beta5 = np.arcsin(np.sin(beta1) * d1 / d2)
    else:
        raise ValueError(f"formula: must be 'interior' or 'paper', got {formula!r}")
    return beta1, beta5, perimeter


def tripod_feet(
    theta1: ArrayLike,
    hips: ArrayLike,
    L: ArrayLike,
    theta2: ArrayLike,
    theta3: ArrayLike,
) -> FloatArray:
    """Body-frame foot positions of three 3-DOF legs for a batch of coxa angles.

    Args:
        theta1: coxa angles (..., 3) rad, one per leg (seed 002: legs 1, 3, 5 in that order).
        hips: (3, 4, 4) hip placements of those legs in the body frame (m).
        L: link lengths (3,) m.
        theta2, theta3: femur and tibia angles (rad), scalars or broadcastable to (..., 3).

    Returns:
        feet (..., 3, 3): foot k of sample b at ``feet[b, k]`` (m), via eqs (5)–(7).
    """
    th1 = np.asarray(theta1, dtype=float)
    if th1.ndim == 0 or th1.shape[-1] != 3:
        raise ValueError(f"theta1: expected shape (..., 3), got {th1.shape}")
    H = np.asarray(hips, dtype=float)
    if H.shape != (3, 4, 4):
        raise ValueError(f"hips: expected shape (3, 4, 4), got {H.shape}")
    th2, th3 = np.broadcast_arrays(th1, np.asarray(theta2, float), np.asarray(theta3, float))[1:]
    p_leg = leg3_fk(np.stack((th1, th2, th3), -1), L)  # (..., 3, 3) in each hip frame
    return np.einsum("kij,...kj->...ki", H[:, :3, :3], p_leg) + H[:, :3, 3]


def tripod_triangle(
    theta1: ArrayLike,
    hips: ArrayLike,
    L: ArrayLike,
    theta2: ArrayLike,
    theta3: ArrayLike,
    formula: Literal["interior", "paper"] = "interior",
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """β1, β5, perimeter (seed 002 eqs 12–14) for a population of θ1 triples (..., 3) of legs
    1, 3, 5 — :func:`tripod_feet` followed by :func:`support_triangle`."""
    F = tripod_feet(theta1, hips, L, theta2, theta3)
    return support_triangle(F[..., 0, :], F[..., 1, :], F[..., 2, :], formula=formula)


UNBOUNDED_SPANS = 100.0
"""A tripod stability distance beyond this many tripod spans is reported as unbounded (inf)."""


def tripod_stability(
    front: ArrayLike,
    middle: ArrayLike,
    back: ArrayLike,
    c: ArrayLike | None = None,
    axis: ArrayLike = (1.0, 0.0),
) -> tuple[FloatArray, FloatArray]:
    """Seed 002's stability distances S_f and S_b of a tripod (its Fig. 6).

    ``S_f`` is the distance, measured along ``axis`` (default the body x axis, as the paper says:
    "la distancia S_f sobre el eje x"), from the body centre ``c`` to the diagonal through the
    middle foot and the front foot; ``S_b`` the same for the diagonal through the middle and back
    feet. Each is signed positive when ``c`` is on the triangle's side of that diagonal (the
    side of the third foot), so the robot is statically stable while ``S_f > 0`` and ``S_b > 0``.

    Args:
        front, middle, back: foot positions (..., 2|3) (m); for stance 1-3-5 of seed 002's
            hexapod front = leg 1, middle = leg 5, back = leg 3.
        c: body centre / COM ground projection, default the origin.
        axis: measuring direction (2,) in the ground plane (normalised here).

    Returns:
        ``(S_f, S_b)`` (m); ±inf where the distance is unbounded: a diagonal parallel to
        ``axis``, or so nearly parallel that the distance exceeds ``UNBOUNDED_SPANS`` (100) times
        the tripod's span (the largest of |front − middle|, |back − middle|, |c − middle|) — a
        number like 16 642.8 m measures how parallel the lines are, not how stable the body is.
    """
    f, m, b = _xy(front, "front"), _xy(middle, "middle"), _xy(back, "back")
    C = np.zeros(2) if c is None else _xy(c, "c")
    u = np.asarray(axis, dtype=float)
    if u.shape != (2,) or not np.all(np.isfinite(u)) or np.linalg.norm(u) == 0.0:
        raise ValueError(f"axis: expected a non-zero finite 2-vector, got {u}")
    u = u / np.linalg.norm(u)

    def along(end: FloatArray, other: FloatArray) -> FloatArray:
        d = end - m
        side_c = _cross(d, C - m)
        side_o = _cross(d, other - m)
        denom = np.abs(_cross(d, np.broadcast_to(u, d.shape)))
        with np.errstate(divide="ignore", invalid="ignore"):
            dist = np.abs(side_c) / denom
        span = np.maximum(
            np.linalg.norm(d, axis=-1),
            np.maximum(np.linalg.norm(other - m, axis=-1), np.linalg.norm(C - m, axis=-1)),
        )
        dist = np.where(dist > UNBOUNDED_SPANS * span, np.inf, dist)
        dist = np.where(side_c == 0.0, 0.0, dist)
        return np.where(side_c * side_o >= 0.0, dist, -dist)

    return along(f, b), along(b, f)
