"""Small helpers of the recording builders: entity names, quaternions, radii."""

from __future__ import annotations

import re
from collections.abc import Iterable
from typing import TYPE_CHECKING, Any

import numpy as np

from legcore.recording.model import FloatArray

if TYPE_CHECKING:
    from legcore.robots.legged import LeggedRobot
    from legcore.robots.model import Robot

# ---------------------------------------------------------------------------------------------
# helpers
# ---------------------------------------------------------------------------------------------

_PART_RE = re.compile(r"[^A-Za-z0-9_\-]+")


def entity_part(name: str) -> str:
    """``name`` as one entity-path part: runs of characters other than letters, digits, ``_``
    and ``-`` become ``_`` (``"L1.θ2"`` → ``"L1_2"``); empty → ``"_"``."""
    s = _PART_RE.sub("_", str(name)).strip("_")
    return s or "_"


def unique_parts(names: Iterable[str]) -> list[str]:
    """:func:`entity_part` of each name, duplicates suffixed ``_2``, ``_3``, ..."""
    out: list[str] = []
    seen: set[str] = set()
    for n in names:
        p = entity_part(n)
        base, k = p, 2
        while p in seen:
            p = f"{base}_{k}"
            k += 1
        seen.add(p)
        out.append(p)
    return out


def _cumtrapz(y: FloatArray, t: FloatArray) -> FloatArray:
    """Cumulative trapezoid integral of ``y`` (K, ...) over ``t`` (K,), starting at 0."""
    out = np.zeros_like(y, dtype=float)
    if y.shape[0] > 1:
        dt = np.diff(t).reshape((-1,) + (1,) * (y.ndim - 1))
        out[1:] = np.cumsum(0.5 * (y[1:] + y[:-1]) * dt, axis=0)
    return out


def _z_to(d: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Rotations (N, 3, 3) taking +z onto the directions ``d`` (N, 3), and the lengths |d| (N,).

    Zero-length directions give the identity."""
    L = np.linalg.norm(d, axis=-1)
    safe = L > 1e-12
    u = np.where(safe[:, None], d / np.where(safe, L, 1.0)[:, None], np.array([0.0, 0.0, 1.0]))
    c = u[:, 2]
    v = np.stack([-u[:, 1], u[:, 0], np.zeros_like(c)], axis=-1)  # z × u
    Vx = np.zeros((u.shape[0], 3, 3))
    Vx[:, 0, 1], Vx[:, 0, 2] = -v[:, 2], v[:, 1]
    Vx[:, 1, 0], Vx[:, 1, 2] = v[:, 2], -v[:, 0]
    Vx[:, 2, 0], Vx[:, 2, 1] = -v[:, 1], v[:, 0]
    opposite = c < -1.0 + 1e-9
    k = np.where(opposite, 0.0, 1.0 / np.where(opposite, 1.0, 1.0 + c))
    R = np.eye(3)[None] + Vx + (Vx @ Vx) * k[:, None, None]
    R[opposite] = np.diag([1.0, -1.0, -1.0])
    return R, L


def quaternion_xyzw(R: FloatArray) -> FloatArray:
    """Unit quaternions (..., 4) as (x, y, z, w), w >= 0, of rotation matrices ``R`` (..., 3, 3)
    (Shepperd's method: the largest of the four squared components is taken as the pivot)."""
    R = np.asarray(R, dtype=float)
    m00, m11, m22 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    tr = m00 + m11 + m22
    cand = np.stack([tr, m00, m11, m22], axis=-1)
    k = np.argmax(cand, axis=-1)
    q = np.empty(R.shape[:-2] + (4,))
    # case w largest
    s = np.sqrt(np.maximum(1.0 + cand[..., 0], 1e-300)) * 2.0
    qw = np.stack(
        [
            (R[..., 2, 1] - R[..., 1, 2]) / s,
            (R[..., 0, 2] - R[..., 2, 0]) / s,
            (R[..., 1, 0] - R[..., 0, 1]) / s,
            0.25 * s,
        ],
        axis=-1,
    )
    s = np.sqrt(np.maximum(1.0 + m00 - m11 - m22, 1e-300)) * 2.0
    qx = np.stack(
        [
            0.25 * s,
            (R[..., 0, 1] + R[..., 1, 0]) / s,
            (R[..., 0, 2] + R[..., 2, 0]) / s,
            (R[..., 2, 1] - R[..., 1, 2]) / s,
        ],
        axis=-1,
    )
    s = np.sqrt(np.maximum(1.0 - m00 + m11 - m22, 1e-300)) * 2.0
    qy = np.stack(
        [
            (R[..., 0, 1] + R[..., 1, 0]) / s,
            0.25 * s,
            (R[..., 1, 2] + R[..., 2, 1]) / s,
            (R[..., 0, 2] - R[..., 2, 0]) / s,
        ],
        axis=-1,
    )
    s = np.sqrt(np.maximum(1.0 - m00 - m11 + m22, 1e-300)) * 2.0
    qz = np.stack(
        [
            (R[..., 0, 2] + R[..., 2, 0]) / s,
            (R[..., 1, 2] + R[..., 2, 1]) / s,
            0.25 * s,
            (R[..., 1, 0] - R[..., 0, 1]) / s,
        ],
        axis=-1,
    )
    q = np.where(
        (k == 0)[..., None],
        qw,
        np.where((k == 1)[..., None], qx, np.where((k == 2)[..., None], qy, qz)),
    )
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., 3:4] < 0, -q, q)


def _fill_nan_rows(a: FloatArray) -> tuple[FloatArray, int]:
    """Forward- (then backward-) fill rows of ``a`` (N, ...) that contain NaN; count of them."""
    flat = a.reshape(a.shape[0], -1)
    bad = ~np.all(np.isfinite(flat), axis=1)
    n_bad = int(bad.sum())
    if n_bad == 0 or n_bad == a.shape[0]:
        return a, n_bad
    good = np.flatnonzero(~bad)
    pos = np.arange(a.shape[0])
    src = good[np.clip(np.searchsorted(good, pos, side="right") - 1, 0, None)]
    src = np.where(pos < good[0], good[0], src)
    return a[src], n_bad


def _chain_scale(robot: Robot) -> float:
    """Sum of the distances between consecutive frame origins (and the tool) at ``home`` (m)."""
    from legcore.kinematics import fk, frames

    F = frames(robot, robot.home)
    p = np.concatenate([F[:, :3, 3], fk(robot, robot.home)[None, :3, 3]])
    return float(np.sum(np.linalg.norm(np.diff(p, axis=0), axis=-1)))


def link_radius(robot: Robot | LeggedRobot) -> float:
    """Drawing radius of the links (m): 3.5 % of the longest chain's length at home
    (PUMA 560 ≈ 6 cm, the CITEDI hexapod's legs ≈ 4 mm), at least 1 mm."""
    chains = [leg.robot for leg in robot.legs] if hasattr(robot, "legs") else [robot]
    scale = max(_chain_scale(c) for c in chains)
    return max(0.035 * scale, 1e-3)


def _as_float(a: Any) -> FloatArray | None:
    try:
        out = np.asarray(a, dtype=float)
    except (TypeError, ValueError):
        return None
    return out
