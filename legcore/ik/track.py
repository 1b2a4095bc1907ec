"""Path tracking with the damped Newton IK of :mod:`legcore.ik.newton`, compiled with numba:
:func:`track` solves one sample from the previous sample's solution (a predictor already near
the target) by one cheap undamped step and its check, falling back to :func:`newton`."""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from legcore.ik.newton import (
    PRM_MAX_STEP,
    PRM_NEAR,
    PRM_NULL_GAIN,
    PRM_NULL_TOL,
    PRM_TOL_P,
    PRM_TOL_R,
    PRM_W,
    _evaluate_error,
    _rows,
    newton,
)
from legcore.ik.newton_step import _lu_step, _step

__all__ = ["track"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _track_step(
    q: FloatArray,
    A: FloatArray,
    e: FloatArray,
    lam: float,
    lo: FloatArray,
    hi: FloatArray,
    rest: FloatArray,
    gain: float,
    use_null: bool,
    ws: tuple,
) -> float:  # pragma: no cover - compiled
    """:func:`_step` (undamped, λ = ``lam`` tiny) into ``ws[9]``, by :func:`_lu_step` when no
    joint is at a limit and n ≤ m + 1 (n = m + 1 only with the rest pull); −1 if that fails."""
    m, n = A.shape
    interior = True
    for j in range(n):
        interior = interior and lo[j] < q[j] < hi[j]
    if interior and (n == m or (use_null and n == m + 1)):
        return _lu_step(
            A, e, q, rest, gain, use_null, ws[9], ws[7], ws[14], ws[18], ws[19], ws[20]
        )
    return _step(
        q, A, e, lam, lo, hi, rest, gain, use_null, ws[9], ws[10], ws[11], ws[12], ws[13],
        ws[14], ws[7], ws[17],
    )


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def track(
    q: FloatArray,
    tp: FloatArray,
    tR: FloatArray,
    task: int,
    lo: FloatArray,
    hi: FloatArray,
    rest: FloatArray,
    use_rest: bool,
    R: FloatArray,
    p: FloatArray,
    prismatic: BoolArray,
    tool_R: FloatArray,
    tool_p: FloatArray,
    prm: FloatArray,
    max_iter: int,
    ws: tuple,
) -> tuple[bool, int, float, float]:  # pragma: no cover - compiled
    """:func:`newton` from a path predictor ``q`` already near the solution: the near-target
    Newton step of :func:`newton` and its check, done at the least cost; the full
    :func:`newton` (from the better of the predictor and the step) only when that fails.

    Same arguments, convergence test and return value as :func:`newton`. For n = m (a 6-DOF
    arm on poses) and n = m + 1 with a rest posture (a 7-DOF arm on poses) only — other shapes
    go straight to :func:`newton`. The step: undamped, with the rest pull when redundant, from
    one LU factorisation of ``A`` (:func:`_lu_step`; :func:`_step` when a joint is at a limit).
    The check: the task error at the result (FK only — a chain that is not redundant needs no
    Jacobian there) and, when redundant, ``|N (q_rest − q)|`` (one more LU).
    """
    n = q.shape[0]
    m = task
    tol_p = prm[PRM_TOL_P]
    tol_r = prm[PRM_TOL_R]
    w = prm[PRM_W]
    lam_min = 1e-9 * w
    gain = prm[PRM_NULL_GAIN]
    null_tol = prm[PRM_NULL_TOL] * gain
    max_step = prm[PRM_MAX_STEP]
    near2 = prm[PRM_NEAR] ** 2
    redundant = use_rest and n > m
    e, A, dq, q_t = ws[4], ws[5], ws[9], ws[15]

    if not (n == m or (redundant and n == m + 1)):  # other shapes: newton's own iteration
        return newton(
            q, tp, tR, task, lo, hi, rest, use_rest, R, p, prismatic, tool_R, tool_p, prm,
            max_iter, ws,
        )
    for j in range(n):
        q[j] = min(max(q[j], lo[j]), hi[j])
    f, ep, er = _evaluate_error(q, ws, tp, tR, task, w, e, R, p, prismatic, tool_R, tool_p)
    done = 0
    if f <= near2:
        conv = ep <= tol_p and er <= tol_r
        if conv and not redundant:
            return True, 0, ep, er
        _rows(ws, task, w, A, prismatic)
        null_size = _track_step(q, A, e, lam_min, lo, hi, rest, gain, redundant, ws)
        if conv and 0.0 <= null_size <= null_tol:
            return True, 0, ep, er
        inside = null_size >= 0.0
        for j in range(n):
            q_t[j] = q[j] + dq[j]
            inside = inside and abs(dq[j]) <= max_step and lo[j] <= q_t[j] <= hi[j]
        if inside:
            f_t, ep_t, er_t = _evaluate_error(
                q_t, ws, tp, tR, task, w, e, R, p, prismatic, tool_R, tool_p
            )
            done = 1
            if f_t < f:  # else newton starts again from the predictor
                for j in range(n):
                    q[j] = q_t[j]
                if ep_t <= tol_p and er_t <= tol_r:
                    if not redundant:
                        return True, 1, ep_t, er_t
                    _rows(ws, task, w, A, prismatic)
                    null_size = _track_step(q, A, e, lam_min, lo, hi, rest, gain, True, ws)
                    if 0.0 <= null_size <= null_tol:  # |N (q_rest − q)| ≤ null_tol
                        return True, 1, ep_t, er_t
    conv, it, ep, er = newton(
        q, tp, tR, task, lo, hi, rest, use_rest, R, p, prismatic, tool_R, tool_p, prm,
        max_iter, ws,
    )
    return conv, it + done, ep, er
