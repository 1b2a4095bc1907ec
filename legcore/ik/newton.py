"""Damped Newton (Levenberg–Marquardt) inverse kinematics of one sample, compiled with numba.

The building block of :mod:`legcore.ik.numeric`: :func:`newton` moves one configuration ``q``
(n,) in place until the tool reaches one target, on the serial-chain arrays of
:class:`~legcore.robots.Chain` (:mod:`legcore.ik.sample_kinematics`). Tasks, by their number of
rows m: ``TASK_POSITION`` (3), ``TASK_AXIS`` (5: position + tool z axis, the spin about it
free), ``TASK_POSE`` (6).

Far from the target (error above ``near``, default 1e-3 × the robot's reach): Levenberg–Marquardt
on the task, ``Δq = Aᵀ (A Aᵀ + λ² I)⁻¹ e`` (``e`` (m,) the task error, ``A`` (m, n) its Jacobian,
orientation rows scaled by ``w`` m/rad). A step that lowers ``|e|²`` is accepted (λ ← λ/10); if
not, the half and the quarter step are tried, then λ ← 10 λ. An attempt whose ``|e|²`` did not
halve over 10 iterations has stalled (a local minimum, often against a limit) and gives up.

Near the target, on a chain redundant for the task (n > m) with a rest posture: each step is the
undamped Newton step plus the move along the self-motion manifold toward the rest posture,
``N g (q_rest − q)`` with ``N = I − A⁺A`` (gain g halved whenever that move stops shrinking) —
the iteration for the configuration nearest ``q_rest`` among those on target.

Joint limits: a joint at a limit whose step points outward is frozen (its column removed) and the
step recomputed; the step is scaled to at most ``max_step`` (rad or m) per joint and clamped into
the limits, so ``q`` never leaves them. Converged: position error ≤ ``tol_p`` (m), orientation
error ≤ ``tol_r`` (rad) and, when redundant, ``|N (q_rest − q)| ≤ null_tol`` (rad); the last
10 iterations of an attempt only finish the task. Not converged within ``max_iter``, stalled, or
λ > ``lam_max``: unreachable from this start.

The linear algebra of one step (damped Cholesky with limit freezing, undamped LU) is in
:mod:`legcore.ik.newton_step`; the cheap path-tracking variant :func:`legcore.ik.track.track`
builds on :func:`newton`.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from legcore.ik.newton_step import _step
from legcore.ik.sample_kinematics import (
    TASK_AXIS,
    TASK_POSE,
    TASK_POSITION,
    errors,
    fk_z,
    jac_z,
    task_error,
    task_rows,
)

__all__ = [
    "PRM_LAM0",
    "PRM_LAM_MAX",
    "PRM_MAX_STEP",
    "PRM_NEAR",
    "PRM_NULL_GAIN",
    "PRM_NULL_TOL",
    "PRM_SIZE",
    "PRM_TOL_P",
    "PRM_TOL_R",
    "PRM_W",
    "TASK_AXIS",
    "TASK_POSE",
    "TASK_POSITION",
    "errors",
    "newton",
    "workspace",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

# indices into the float parameter vector ``prm``
PRM_TOL_P = 0  # m
PRM_TOL_R = 1  # rad
PRM_W = 2  # m/rad, weight of the orientation rows
PRM_LAM0 = 3  # initial damping (m)
PRM_LAM_MAX = 4  # give up above this damping
PRM_NULL_GAIN = 5  # gain g of the rest-posture pull (1 = full projected step)
PRM_NULL_TOL = 6  # rad (or m): converged when the null-space pull is below this
PRM_MAX_STEP = 7  # rad (or m): largest joint step per iteration
PRM_NEAR = 8  # m: below this error the rest pull joins the Newton step
PRM_SIZE = 9

_BACKTRACK = 3  # step lengths tried before more damping
_RESERVE = 10  # the last iterations of an attempt only finish the task, no more rest pull
_STALL_WINDOW = 10  # iterations
_STALL_RATIO = 0.5  # an attempt whose |e|² did not halve over a window has stalled


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def workspace(n: int, m: int) -> tuple:  # pragma: no cover
    """Scratch arrays of :func:`newton` for n joints and m task rows (allocate once, reuse)."""
    return (
        np.empty((n, 3, 3)),  # 0 joint frames (world rotations)
        np.empty((n, 3)),  # 1 joint origins
        np.empty((4, 4)),  # 2 tool pose
        np.empty((6, n)),  # 3 Jacobian
        np.empty(m),  # 4 e
        np.empty((m, n)),  # 5 A
        np.empty(m),  # 6 e trial
        np.empty((m, n)),  # 7 A with the frozen columns zeroed (see _step)
        np.empty((3, 3)),  # 8 tmp
        np.empty(n),  # 9 dq
        np.empty((m, m)),  # 10 M (Cholesky factor)
        np.empty(n, dtype=np.bool_),  # 11 free
        np.empty(n),  # 12 r
        np.empty(m),  # 13 y
        np.empty(m),  # 14 b
        np.empty(n),  # 15 q trial
        np.empty(n),  # 16 q best
        np.empty(m),  # 17 inverse diagonal of M
        np.empty(n, dtype=np.int64),  # 18 column permutation (_lu_step)
        np.empty(n),  # 19 x (_lu_step)
        np.empty(n),  # 20 z (_lu_step)
    )


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _evaluate_error(
    qv: FloatArray, ws: tuple, tp: FloatArray, tR: FloatArray, task: int, w: float,
    e: FloatArray, R: FloatArray, p: FloatArray, prismatic: BoolArray, tool_R: FloatArray,
    tool_p: FloatArray,
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """Task error of configuration ``qv`` into ``e``; returns (|e|², ep, er). The joint frames
    stay in ``ws`` for :func:`_rows` (the Jacobian, when a step needs it)."""
    T = ws[2]
    fk_z(qv, R, p, prismatic, tool_R, tool_p, ws[0], ws[1], T)
    return task_error(T, tp, tR, task, w, e, ws[8])


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _rows(
    ws: tuple, task: int, w: float, A: FloatArray, prismatic: BoolArray
) -> None:  # pragma: no cover - compiled
    """Task Jacobian ``A`` at the configuration of the last :func:`_evaluate_error`."""
    T, J = ws[2], ws[3]
    jac_z(ws[0], ws[1], T, prismatic, J)
    task_rows(T, J, task, w, A)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _evaluate(
    qv: FloatArray, ws: tuple, tp: FloatArray, tR: FloatArray, task: int, w: float,
    e: FloatArray, A: FloatArray, R: FloatArray, p: FloatArray, prismatic: BoolArray,
    tool_R: FloatArray, tool_p: FloatArray,
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """Task error and Jacobian of configuration ``qv`` into (e, A); returns (|e|², ep, er)."""
    out = _evaluate_error(qv, ws, tp, tR, task, w, e, R, p, prismatic, tool_R, tool_p)
    _rows(ws, task, w, A, prismatic)
    return out


@numba.njit(cache=True, nogil=True, error_model="numpy")
def newton(
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
    """Solve one target from ``q`` (n,), in place.

    ``tp`` (3,) target position (m); ``tR`` (3, 3) target rotation (``TASK_POSE``) or a matrix
    whose column 2 is the target unit axis (``TASK_AXIS``); ``lo``/``hi`` (n,) joint limits;
    ``rest`` (n,) rest posture, used when ``use_rest`` and n > m; chain arrays of
    :func:`~legcore.ik.sample_kinematics.z_chain` (joint axes along z); ``prm`` the ``PRM_*``
    parameters; ``ws`` from :func:`workspace`. ``q`` is clamped into the limits first and stays
    inside them. Returns ``(converged, iterations, position error m, orientation error rad)``;
    iterations count FK evaluations after the first.
    """
    n = q.shape[0]
    m = task
    tol_p = prm[PRM_TOL_P]
    tol_r = prm[PRM_TOL_R]
    w = prm[PRM_W]
    lam_max = prm[PRM_LAM_MAX]
    lam_min = 1e-9 * w
    gain = prm[PRM_NULL_GAIN]
    null_tol = prm[PRM_NULL_TOL]
    max_step = prm[PRM_MAX_STEP]
    near2 = prm[PRM_NEAR] ** 2
    redundant = use_rest and n > m
    e, A, e_t, dq, M, free = ws[4], ws[5], ws[6], ws[9], ws[10], ws[11]
    r, y, b, q_t, q_best, Af, dinv = ws[12], ws[13], ws[14], ws[15], ws[16], ws[7], ws[17]

    for j in range(n):
        q[j] = min(max(q[j], lo[j]), hi[j])
    f, ep, er = _evaluate(q, ws, tp, tR, task, w, e, A, R, p, prismatic, tool_R, tool_p)
    lam = prm[PRM_LAM0]
    it = 0
    f_window = f
    it_window = 0
    null_prev = math.inf
    have_best = False
    ep_best, er_best = math.inf, math.inf
    while it < max_iter:
        conv = ep <= tol_p and er <= tol_r
        if redundant and f <= near2 and it < max_iter - _RESERVE:
            # near the target: Newton step plus a step along the self-motion manifold toward
            # the rest posture, taken together; converged when both are below tolerance
            # undamped (λ_min): damping would leak the rest pull into the task rows
            null_size = _step(
                q, A, e, lam_min, lo, hi, rest, gain, True, dq, M, free, r, y, b, Af, dinv
            )
            if conv:
                if null_size <= null_tol * gain:  # |N (q_rest − q)| ≤ null_tol
                    return True, it, ep, er
                for j in range(n):  # keep the solution in case the walk goes astray
                    q_best[j] = q[j]
                have_best = True
                ep_best, er_best = ep, er
            if null_size >= null_prev:  # the pull is not shrinking (overshoot): smaller steps
                gain *= 0.5
            null_prev = null_size
            big = 0.0
            for j in range(n):
                big = max(big, abs(dq[j]))
            alpha = max_step / big if big > max_step else 1.0
            for j in range(n):
                q[j] = min(max(q[j] + alpha * dq[j], lo[j]), hi[j])
            f, ep, er = _evaluate(q, ws, tp, tR, task, w, e, A, R, p, prismatic, tool_R, tool_p)
            it += 1
            f_window = f
            it_window = it
            continue
        if conv:
            return True, it, ep, er
        if it >= it_window + _STALL_WINDOW:  # give up a stalled attempt (a local minimum)
            if f > _STALL_RATIO * f_window:
                break
            f_window = f
            it_window = it
        _step(q, A, e, lam, lo, hi, rest, gain, False, dq, M, free, r, y, b, Af, dinv)
        big = 0.0
        for j in range(n):
            big = max(big, abs(dq[j]))
        if not math.isfinite(big):  # a numerically singular system: damp more
            lam *= 10.0
            it += 1
            if lam > lam_max:
                break
            continue
        alpha = max_step / big if big > max_step else 1.0
        accepted = False
        f_t, ep_t, er_t = f, ep, er
        for _ in range(_BACKTRACK):  # α, α/2, α/4: curvature (near a singularity) shortens it
            for j in range(n):
                q_t[j] = min(max(q[j] + alpha * dq[j], lo[j]), hi[j])
            f_t, ep_t, er_t = _evaluate_error(
                q_t, ws, tp, tR, task, w, e_t, R, p, prismatic, tool_R, tool_p
            )
            it += 1
            if f_t < f:
                accepted = True
                break
            alpha *= 0.5
        if accepted:
            for j in range(n):
                q[j] = q_t[j]
            for a in range(m):
                e[a] = e_t[a]
            f, ep, er = f_t, ep_t, er_t
            lam = max(0.1 * lam, lam_min)
            if ep <= tol_p and er <= tol_r and not (
                redundant and f <= near2 and it < max_iter - _RESERVE
            ):
                return True, it, ep, er  # converged: the Jacobian here is not needed
            _rows(ws, task, w, A, prismatic)  # the frames are those of q_t
        else:
            lam *= 10.0
            if lam > lam_max:
                break
    conv = ep <= tol_p and er <= tol_r
    if not conv and have_best:
        for j in range(n):
            q[j] = q_best[j]
        conv = True
        ep, er = ep_best, er_best
    return conv, it, ep, er
