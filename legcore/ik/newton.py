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
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

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
    "track",
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


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _factor(
    Af: FloatArray, lam: float, M: FloatArray, dinv: FloatArray
) -> None:  # pragma: no cover - compiled
    """Lower Cholesky factor of ``Af Afᵀ + λ² I`` (m×m) into ``M``, its inverse diagonal into
    ``dinv`` (the Gram matrix formed row by row as the factorisation needs it)."""
    m, n = Af.shape
    lam2 = lam * lam
    for i in range(m):
        for k in range(i + 1):
            s = 0.0
            for j in range(n):
                s += Af[i, j] * Af[k, j]
            for t in range(k):
                s -= M[i, t] * M[k, t]
            if i == k:
                d = math.sqrt(max(s + lam2, 1e-300))
                M[i, i] = d
                dinv[i] = 1.0 / d
            else:
                M[i, k] = s * dinv[k]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _chol_solve(
    M: FloatArray, dinv: FloatArray, b: FloatArray, x: FloatArray
) -> None:  # pragma: no cover - compiled
    """Solve ``M Mᵀ x = b`` with the factor of :func:`_factor`."""
    m = b.shape[0]
    for i in range(m):
        s = b[i]
        for k in range(i):
            s -= M[i, k] * x[k]
        x[i] = s * dinv[i]
    for i in range(m - 1, -1, -1):
        s = x[i]
        for k in range(i + 1, m):
            s -= M[k, i] * x[k]
        x[i] = s * dinv[i]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _step(
    q: FloatArray,
    A: FloatArray,
    e: FloatArray,
    lam: float,
    lo: FloatArray,
    hi: FloatArray,
    rest: FloatArray,
    gain: float,
    use_null: bool,
    dq: FloatArray,
    M: FloatArray,
    free: BoolArray,
    r: FloatArray,
    y: FloatArray,
    b: FloatArray,
    Af: FloatArray,
    dinv: FloatArray,
) -> float:  # pragma: no cover - compiled
    """Damped step into ``dq`` with limit freezing; returns max |null-space pull| (0 if unused).

    ``Af`` is ``A`` with the frozen joints' columns zeroed; on return ``M``/``dinv`` hold the
    factor of ``Af Afᵀ + λ² I`` (reused by :func:`track` when no joint was frozen).
    """
    m, n = A.shape
    for a in range(m):
        for j in range(n):
            Af[a, j] = A[a, j]
    for j in range(n):
        free[j] = True
    null_size = 0.0
    for _ in range(n + 1):
        _factor(Af, lam, M, dinv)
        _chol_solve(M, dinv, e, y)
        for j in range(n):
            s = 0.0
            for a in range(m):
                s += Af[a, j] * y[a]
            dq[j] = s
        null_size = 0.0
        if use_null:
            for j in range(n):
                r[j] = gain * (rest[j] - q[j]) if free[j] else 0.0
            for a in range(m):
                s = 0.0
                for j in range(n):
                    s += Af[a, j] * r[j]
                b[a] = s
            _chol_solve(M, dinv, b, y)
            for j in range(n):  # frozen joints: r = 0 and a zero column, so s = 0
                s = r[j]
                for a in range(m):
                    s -= Af[a, j] * y[a]
                dq[j] += s
                null_size = max(null_size, abs(s))
        changed = False
        for j in range(n):
            if free[j] and (
                (q[j] <= lo[j] and dq[j] < 0.0) or (q[j] >= hi[j] and dq[j] > 0.0)
            ):
                free[j] = False
                changed = True
                for a in range(m):
                    Af[a, j] = 0.0
        if not changed:
            break
    return null_size


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


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _lu_step(
    A: FloatArray,
    e: FloatArray,
    q: FloatArray,
    rest: FloatArray,
    gain: float,
    use_null: bool,
    dq: FloatArray,
    U: FloatArray,
    c: FloatArray,
    piv: NDArray[np.int64],
    x: FloatArray,
    z: FloatArray,
) -> float:  # pragma: no cover - compiled
    """The undamped step of :func:`_step` (no joint frozen) for n = m or n = m + 1 joints, from
    one LU factorisation of ``A`` itself (complete pivoting) instead of ``A Aᵀ``.

    n = m: ``dq = A⁻¹ e``. n = m + 1: the null space of ``A`` is the line of ``z`` (from the
    same factorisation), ``N = z zᵀ / |z|²``; ``dq = A⁺ e`` (a particular solution minus its
    component along ``z``) plus, with ``use_null``, ``g N (q_rest − q)``. Returns the max
    |null-space pull| (0 without ``use_null``), or −1 when ``A`` is (numerically) rank-deficient.
    ``U`` (m, n), ``c`` (m), ``piv`` (n) int, ``x`` (n), ``z`` (n) are scratch.
    """
    m, n = A.shape
    for a in range(m):
        c[a] = e[a]
        for j in range(n):
            U[a, j] = A[a, j]
    for j in range(n):
        piv[j] = j
    for k in range(m):
        big, bi, bj = -1.0, k, k
        for a in range(k, m):
            for j in range(k, n):
                t = abs(U[a, j])
                if t > big:
                    big, bi, bj = t, a, j
        if not (big > 1e-300 and math.isfinite(big)):
            return -1.0
        if bi != k:
            for j in range(k, n):
                U[k, j], U[bi, j] = U[bi, j], U[k, j]
            c[k], c[bi] = c[bi], c[k]
        if bj != k:
            for a in range(m):
                U[a, k], U[a, bj] = U[a, bj], U[a, k]
            piv[k], piv[bj] = piv[bj], piv[k]
        inv = 1.0 / U[k, k]
        for a in range(k + 1, m):
            f = U[a, k] * inv
            for j in range(k + 1, n):
                U[a, j] -= f * U[k, j]
            c[a] -= f * c[k]
    # in pivoted order: U1 x = c (x_m = 0), and z = [−U1⁻¹ u_m; 1] spans the null space
    for a in range(m - 1, -1, -1):
        s = c[a]
        t = U[a, m] if n > m else 0.0
        for j in range(a + 1, m):
            s -= U[a, j] * x[j]
            t -= U[a, j] * z[j]
        inv = 1.0 / U[a, a]
        x[a] = s * inv
        z[a] = t * inv
    if n == m:
        for j in range(n):
            dq[piv[j]] = x[j]
        return 0.0
    x[m] = 0.0
    z2 = 1.0
    zx = 0.0
    zr = 0.0
    zmax = 1.0
    for j in range(m):
        z[j] = -z[j]
        z2 += z[j] * z[j]
        zx += z[j] * x[j]
        zmax = max(zmax, abs(z[j]))
    z[m] = 1.0
    if use_null:
        for j in range(n):
            zr += z[j] * gain * (rest[piv[j]] - q[piv[j]])
    coef = (zr - zx) / z2  # remove the null part of x, add the projected rest pull
    for j in range(n):
        dq[piv[j]] = x[j] + coef * z[j]
    return abs(zr) / z2 * zmax


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
