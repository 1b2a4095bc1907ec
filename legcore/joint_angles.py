"""Joint-angle wrapping: revolute angles to their principal value, or shifted by 2π into the
joint limits (never clipped), for IK solutions and closed-form branches."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["principal_angle", "wrap_branch_solutions", "wrap_to_limits"]

FloatArray = NDArray[np.float64]


def principal_angle(q: ArrayLike) -> FloatArray:
    """Angles (rad) mapped to (−π, π] (NaN stays NaN)."""
    q = np.asarray(q, dtype=float)
    two_pi = 2.0 * math.pi
    out = q - two_pi * np.floor((q + math.pi) / two_pi)
    return np.where(out <= -math.pi, out + two_pi, out)


def wrap_branch_solutions(
    q: FloatArray,
    reachable: NDArray[np.bool_],
    q_min: ArrayLike | None,
    q_max: ArrayLike | None,
    q_ref: ArrayLike | None = None,
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Closed-form IK branches ``q`` (N, n_branch, n) → wrapped angles and ``within_limits``.

    With limits, each angle becomes its 2π-equivalent inside the limits nearest ``q_ref``
    (:func:`wrap_to_limits`) and ``within_limits`` says whether all joints made it; without
    limits angles go to (−π, π] and ``within_limits`` equals ``reachable``. Unreachable
    branches are NaN.
    """
    q = np.where(reachable[..., None], q, np.nan)
    if q_min is None or q_max is None:
        return principal_angle(q), reachable.copy()
    ref = None if q_ref is None else np.broadcast_to(np.asarray(q_ref, float), q.shape)
    q = wrap_to_limits(q, q_min, q_max, ref)
    lo = np.asarray(q_min, dtype=float)
    hi = np.asarray(q_max, dtype=float)
    within = reachable & np.all((q >= lo - 1e-12) & (q <= hi + 1e-12), axis=-1)
    return q, within


def wrap_to_limits(
    q: ArrayLike,
    q_min: ArrayLike,
    q_max: ArrayLike,
    q_ref: ArrayLike | None = None,
    revolute: ArrayLike | None = None,
    tol: float = 1e-12,
) -> FloatArray:
    """Shift revolute angles by multiples of 2π into ``[q_min, q_max]`` when possible.

    ``q`` (..., n) rad; each revolute joint is replaced by the equivalent angle ``q + 2πk``
    inside its limits — the one nearest ``q_ref`` (broadcastable to ``q``) if given, otherwise
    the one nearest the principal value in (−π, π]. Angles with no equivalent inside the limits
    are returned as their principal value (they stay out of limits: reported, never clipped).
    Prismatic joints (``revolute`` False) and NaN entries are left unchanged. The pose is the
    same for every choice.
    """
    q = np.asarray(q, dtype=float)
    lo = np.asarray(q_min, dtype=float)
    hi = np.asarray(q_max, dtype=float)
    two_pi = 2.0 * math.pi
    principal = principal_angle(q)
    # Fast path: the candidate nearest q_ref (or the principal value) is almost always inside.
    if q_ref is None:
        out = principal.copy()
    else:
        ref = np.broadcast_to(np.asarray(q_ref, dtype=float), q.shape)
        out = principal + two_pi * np.round((ref - principal) / two_pi)
    lo_b = np.broadcast_to(lo, q.shape)
    hi_b = np.broadcast_to(hi, q.shape)
    slow = ~((out >= lo_b - tol) & (out <= hi_b + tol)) & ~np.isnan(q)
    if slow.any():  # search the 2π shifts of the few entries whose first choice is outside
        ks = np.arange(-3, 4, dtype=float)
        cand = principal[slow][:, None] + two_pi * ks  # (m, 7)
        inside = (cand >= lo_b[slow][:, None] - tol) & (cand <= hi_b[slow][:, None] + tol)
        if q_ref is None:
            score = np.abs(ks) * np.ones_like(cand)
        else:
            score = np.abs(cand - ref[slow][:, None])
        score = np.where(inside, score, np.inf)
        chosen = np.take_along_axis(cand, np.argmin(score, axis=-1)[:, None], axis=-1)[:, 0]
        out[slow] = np.where(np.any(inside, axis=-1), chosen, principal[slow])
    if revolute is not None:
        out = np.where(np.asarray(revolute, dtype=bool), out, q)
    return np.where(np.isnan(q), np.nan, out)
