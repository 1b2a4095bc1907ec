"""Joint trajectories of a batch of placed tool paths, for ``path_placement``.

:func:`placed_path_joints` turns tool poses (B, K, 4, 4) — B placements of a K-point path —
into per-candidate IK *branches* (B, nb, K, n): one continuous joint trajectory per branch, with
the points the branch cannot reach marked and filled from their reachable neighbours (the
problem penalises them).

- Closed form (a PUMA-type arm, seed 001): all 8 branches of
  :func:`legcore.ik.puma560.puma560_ik` at once, unwrapped along the path and each joint's
  whole trajectory shifted by 2π into its limits where possible (outside: the position
  constraints measure by how much).
- Numerical (any other arm): :func:`legcore.ik.solve` along each path (``path=True``: warm
  start, continuous branch, joint limits kept), once per start posture — each start is one
  "branch"; every candidate and start is one path of the same batched call.

:func:`gradient` differentiates on the (non-uniform) time grid; :func:`placed_path_joints`
and the helpers are pure numpy over the batch.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from legcore.ik import solve
from legcore.ik.puma560 import puma560_geometry, puma560_ik
from legcore.robots.model import Robot

__all__ = ["NUMERIC_OPTIONS", "fill_unreachable", "gradient", "placed_path_joints",
           "shift_into_limits"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Options of the numerical IK for placed paths: few restarts — a placement whose path leaves
#: the workspace is penalised, not searched for (it would cost 32 restarts per point).
NUMERIC_OPTIONS: dict[str, float | int] = {"restarts": 4, "max_substeps": 4, "max_iter": 60}


def gradient(y: FloatArray, t: FloatArray) -> FloatArray:
    """d y / d t along axis −2 of ``y`` (..., K, n) on the grid ``t`` (K,) or (..., K).

    Second-order central differences inside (non-uniform grid, as ``numpy.gradient``), first
    order at the ends.
    """
    t = np.asarray(t, dtype=float)
    h = np.diff(t, axis=-1)[..., None]  # (..., K-1, 1)
    out = np.empty_like(y)
    h1 = h[..., :-1, :]
    h2 = h[..., 1:, :]
    out[..., 1:-1, :] = (
        h1**2 * y[..., 2:, :] - h2**2 * y[..., :-2, :] + (h2**2 - h1**2) * y[..., 1:-1, :]
    ) / (h1 * h2 * (h1 + h2))
    out[..., 0, :] = (y[..., 1, :] - y[..., 0, :]) / h[..., 0, :]
    out[..., -1, :] = (y[..., -1, :] - y[..., -2, :]) / h[..., -1, :]
    return out


def fill_unreachable(q: FloatArray, ok: BoolArray, home: FloatArray) -> FloatArray:
    """Replace the samples of ``q`` (..., K, n) where ``ok`` (..., K) is False by the nearest
    earlier reachable sample (else the nearest later one; ``home`` if none is reachable)."""
    K = q.shape[-2]
    idx = np.arange(K)
    fwd = np.maximum.accumulate(np.where(ok, idx, -1), axis=-1)
    bwd = np.flip(np.minimum.accumulate(np.flip(np.where(ok, idx, K), axis=-1), axis=-1), axis=-1)
    src = np.where(fwd >= 0, fwd, bwd)
    none = src >= K
    src = np.where(none, 0, src)
    out = np.take_along_axis(q, src[..., None], axis=-2)
    return np.where(none[..., None], home, out)


def shift_into_limits(q: FloatArray, lo: FloatArray, hi: FloatArray) -> FloatArray:
    """Shift each joint's whole trajectory in ``q`` (..., K, n) by a multiple of 2π so that it
    violates its limits least (ties: closest to the middle of the range)."""
    qmin = q.min(axis=-2)[..., None]  # (..., n, 1)
    qmax = q.max(axis=-2)[..., None]
    ks = 2.0 * math.pi * np.arange(-2, 3, dtype=float)  # (5,)
    lo_ = lo[:, None]
    hi_ = hi[:, None]
    viol = np.maximum(lo_ - (qmin + ks), 0.0) + np.maximum(qmax + ks - hi_, 0.0)
    centre = np.abs(0.5 * (qmin + qmax) + ks - 0.5 * (lo_ + hi_))
    score = np.round(viol, 12) * 1e3 + centre
    k = np.argmin(score, axis=-1)  # (..., n)
    return q + ks[k][..., None, :]


def placed_path_joints(
    robot: Robot,
    T: FloatArray,
    *,
    closed_form: bool,
    branches: tuple[int, ...],
    starts: FloatArray,
    rest: FloatArray,
) -> tuple[FloatArray, BoolArray]:
    """Joint trajectories of tool poses ``T`` (B, K, 4, 4): ``(q (B, nb, K, n), ok (B, nb, K))``.

    ``closed_form``: the PUMA-type closed form, branches ``branches`` (indices into its 8);
    otherwise the numerical IK from each posture of ``starts`` (S, n) (nb = S), redundancy
    pulled toward ``rest`` (n,). ``ok`` marks the reachable points (inside the joint limits
    for the numerical IK); ``q`` is filled there from the reachable neighbours.
    """
    B, K = T.shape[:2]
    if closed_form:
        br = np.asarray(branches)
        sol = puma560_ik(T, puma560_geometry(robot.spec))  # principal values, (B, K, 8, 6)
        q = np.moveaxis(sol.q[:, :, br, :], 1, 2)  # (B, nb, K, 6)
        ok = np.moveaxis(sol.reachable[:, :, br], 1, 2)
        q = fill_unreachable(q, ok, robot.home)
        q = np.unwrap(q, axis=-2)
        return shift_into_limits(q, robot.q_min, robot.q_max), ok
    S, n = starts.shape
    Tb = np.broadcast_to(T[:, None], (B, S, K, 4, 4))
    q0 = np.broadcast_to(starts, (B, S, n))
    res = solve(robot, Tb, "pose", q0=q0, rest=rest, path=True, method="numeric",
                **NUMERIC_OPTIONS)
    return fill_unreachable(res.q, res.reachable, robot.home), res.reachable
