"""Kinematics of one sample for the compiled IK loop: tool pose + Jacobian, task errors.

:func:`fk_jac_one` is the per-sample, allocation-free form of the batched kernel of
:mod:`legcore.kinematics` (same conventions: joint i's world pose is
``pose_{i-1} · (R_i, p_i) · exp(axis_i q_i)``, Jacobian rows ``[v; ω]`` world-aligned at the
tool point); ``tests/legcore/test_ik_numeric.py`` checks it against
:func:`legcore.kinematics.fk_jacobian`. :func:`errors` turns a tool pose into the error and
Jacobian rows of an IK task (``TASK_POSITION`` 3, ``TASK_AXIS`` 5, ``TASK_POSE`` 6 rows);
:func:`interp_target` interpolates between two targets (continuation along a path).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = ["TASK_AXIS", "TASK_POSE", "TASK_POSITION", "errors", "fk_jac_one", "interp_target"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

TASK_POSITION = 3
TASK_AXIS = 5
TASK_POSE = 6


@numba.njit(cache=True, nogil=True, error_model="numpy")
def fk_jac_one(
    q: FloatArray,
    R: FloatArray,
    p: FloatArray,
    axis: FloatArray,
    prismatic: BoolArray,
    tool_R: FloatArray,
    tool_p: FloatArray,
    Rw: FloatArray,
    pw: FloatArray,
    T: FloatArray,
    J: FloatArray,
) -> None:  # pragma: no cover - compiled
    """Tool pose ``T`` (4, 4) and Jacobian ``J`` (6, n) of ``q`` (n,) on chain arrays.

    ``Rw`` (n, 3, 3) and ``pw`` (n, 3) are scratch: the joint frames in the world.
    """
    n = q.shape[0]
    for i in range(n):
        r = R[i]
        if i == 0:
            for a in range(3):
                pw[0, a] = p[0, a]
                for c in range(3):
                    Rw[0, a, c] = r[a, c]
        else:
            for a in range(3):
                g0, g1, g2 = Rw[i - 1, a, 0], Rw[i - 1, a, 1], Rw[i - 1, a, 2]
                pw[i, a] = pw[i - 1, a] + g0 * p[i, 0] + g1 * p[i, 1] + g2 * p[i, 2]
                for c in range(3):
                    Rw[i, a, c] = g0 * r[0, c] + g1 * r[1, c] + g2 * r[2, c]
        ax, ay, az = axis[i, 0], axis[i, 1], axis[i, 2]
        qi = q[i]
        if prismatic[i]:
            for a in range(3):
                pw[i, a] += (Rw[i, a, 0] * ax + Rw[i, a, 1] * ay + Rw[i, a, 2] * az) * qi
        else:  # Rodrigues: Rw[i] ← Rw[i] · exp([a]× q)
            cq, sq = math.cos(qi), math.sin(qi)
            vq = 1.0 - cq
            e00 = cq + ax * ax * vq
            e01 = ax * ay * vq - az * sq
            e02 = ax * az * vq + ay * sq
            e10 = ay * ax * vq + az * sq
            e11 = cq + ay * ay * vq
            e12 = ay * az * vq - ax * sq
            e20 = az * ax * vq - ay * sq
            e21 = az * ay * vq + ax * sq
            e22 = cq + az * az * vq
            for a in range(3):
                b0, b1, b2 = Rw[i, a, 0], Rw[i, a, 1], Rw[i, a, 2]
                Rw[i, a, 0] = b0 * e00 + b1 * e10 + b2 * e20
                Rw[i, a, 1] = b0 * e01 + b1 * e11 + b2 * e21
                Rw[i, a, 2] = b0 * e02 + b1 * e12 + b2 * e22
    L = Rw[n - 1]
    for a in range(3):
        for c in range(3):
            T[a, c] = L[a, 0] * tool_R[0, c] + L[a, 1] * tool_R[1, c] + L[a, 2] * tool_R[2, c]
        T[a, 3] = pw[n - 1, a] + L[a, 0] * tool_p[0] + L[a, 1] * tool_p[1] + L[a, 2] * tool_p[2]
    T[3, 0] = 0.0
    T[3, 1] = 0.0
    T[3, 2] = 0.0
    T[3, 3] = 1.0
    ox, oy, oz = T[0, 3], T[1, 3], T[2, 3]
    for i in range(n):
        ax, ay, az = axis[i, 0], axis[i, 1], axis[i, 2]
        wx = Rw[i, 0, 0] * ax + Rw[i, 0, 1] * ay + Rw[i, 0, 2] * az
        wy = Rw[i, 1, 0] * ax + Rw[i, 1, 1] * ay + Rw[i, 1, 2] * az
        wz = Rw[i, 2, 0] * ax + Rw[i, 2, 1] * ay + Rw[i, 2, 2] * az
        if prismatic[i]:
            J[0, i], J[1, i], J[2, i] = wx, wy, wz
            J[3, i], J[4, i], J[5, i] = 0.0, 0.0, 0.0
        else:
            dx, dy, dz = ox - pw[i, 0], oy - pw[i, 1], oz - pw[i, 2]
            J[0, i] = wy * dz - wz * dy
            J[1, i] = wz * dx - wx * dz
            J[2, i] = wx * dy - wy * dx
            J[3, i], J[4, i], J[5, i] = wx, wy, wz


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _log3(Rm: FloatArray, out: FloatArray) -> float:  # pragma: no cover - compiled
    """Rotation vector of the 3×3 rotation ``Rm`` into ``out`` (3,); returns the angle (rad)."""
    vx = Rm[2, 1] - Rm[1, 2]
    vy = Rm[0, 2] - Rm[2, 0]
    vz = Rm[1, 0] - Rm[0, 1]
    s = 0.5 * math.sqrt(vx * vx + vy * vy + vz * vz)
    c = 0.5 * (Rm[0, 0] + Rm[1, 1] + Rm[2, 2] - 1.0)
    th = math.atan2(s, c)
    if th < 1e-8:
        f = 0.5 + th * th / 12.0
        out[0] = f * vx
        out[1] = f * vy
        out[2] = f * vz
    elif th < math.pi - 1e-3:
        f = 0.5 * th / s
        out[0] = f * vx
        out[1] = f * vy
        out[2] = f * vz
    else:  # near π: axis from the symmetric part (R + Rᵀ)/2 = c I + (1 − c) a aᵀ
        k = 0
        best = -1.0
        for i in range(3):
            d = (Rm[i, i] - c) / (1.0 - c)
            if d > best:
                best = d
                k = i
        nrm = 0.0
        for i in range(3):
            a = 0.5 * (Rm[k, i] + Rm[i, k]) / (1.0 - c)
            if i == k:
                a -= c / (1.0 - c)
            out[i] = a
            nrm += a * a
        nrm = math.sqrt(nrm)
        sgn = 1.0 if out[0] * vx + out[1] * vy + out[2] * vz >= 0.0 else -1.0
        for i in range(3):
            out[i] *= sgn * th / nrm
    return th


@numba.njit(cache=True, nogil=True, error_model="numpy")
def errors(
    T: FloatArray,
    J: FloatArray,
    tp: FloatArray,
    tR: FloatArray,
    task: int,
    w: float,
    e: FloatArray,
    A: FloatArray,
    tmp: FloatArray,
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """Fill the task error ``e`` (m,) and Jacobian ``A`` (m, n) at tool pose ``T``, Jacobian ``J``.

    Returns ``(|e|², position error (m), orientation error (rad))`` — the squared norm weighted,
    the two errors not. ``tmp`` (3, 3) is scratch space.
    """
    n = J.shape[1]
    ep2 = 0.0
    for a in range(3):
        e[a] = tp[a] - T[a, 3]
        ep2 += e[a] * e[a]
        for j in range(n):
            A[a, j] = J[a, j]
    if task == TASK_POSITION:
        return ep2, math.sqrt(ep2), 0.0
    if task == TASK_POSE:
        for a in range(3):  # tmp = tR · Rᵀ
            for b in range(3):
                tmp[a, b] = tR[a, 0] * T[b, 0] + tR[a, 1] * T[b, 1] + tR[a, 2] * T[b, 2]
        th = _log3(tmp, e[3:])
        u0, u1, u2 = e[3], e[4], e[5]
        e[3], e[4], e[5] = w * u0, w * u1, w * u2
        f = ep2 + e[3] * e[3] + e[4] * e[4] + e[5] * e[5]
        for a in range(3):
            for j in range(n):
                A[3 + a, j] = w * J[3 + a, j]
        return f, math.sqrt(ep2), th
    # TASK_AXIS: rotate the tool z axis onto the target axis; rows along the tool x and y axes
    zx, zy, zz = T[0, 2], T[1, 2], T[2, 2]
    ax, ay, az = tR[0, 2], tR[1, 2], tR[2, 2]
    cx = zy * az - zz * ay
    cy = zz * ax - zx * az
    cz = zx * ay - zy * ax
    s = math.sqrt(cx * cx + cy * cy + cz * cz)
    c = zx * ax + zy * ay + zz * az
    th = math.atan2(s, c)
    if s > 1e-300:
        ux, uy, uz = cx * th / s, cy * th / s, cz * th / s
    elif c > 0.0:
        ux, uy, uz = 0.0, 0.0, 0.0
    else:  # opposite axes: turn about the tool x axis
        ux, uy, uz = th * T[0, 0], th * T[1, 0], th * T[2, 0]
    f = ep2
    for r in range(2):
        bx, by, bz = T[0, r], T[1, r], T[2, r]
        e[3 + r] = w * (bx * ux + by * uy + bz * uz)
        f += e[3 + r] * e[3 + r]
        for j in range(n):
            A[3 + r, j] = w * (bx * J[3, j] + by * J[4, j] + bz * J[5, j])
    return f, math.sqrt(ep2), th


@numba.njit(cache=True, nogil=True, error_model="numpy")
def interp_target(
    task: int,
    p0: FloatArray,
    R0: FloatArray,
    p1: FloatArray,
    R1: FloatArray,
    t: float,
    p: FloatArray,
    Rm: FloatArray,
) -> None:  # pragma: no cover - compiled
    """Target at fraction ``t`` from (p0, R0) to (p1, R1) into (p, Rm): lerp + geodesic."""
    for a in range(3):
        p[a] = (1.0 - t) * p0[a] + t * p1[a]
    if task == TASK_AXIS:  # slerp of the axes (column 2)
        c = R0[0, 2] * R1[0, 2] + R0[1, 2] * R1[1, 2] + R0[2, 2] * R1[2, 2]
        th = math.acos(min(1.0, max(-1.0, c)))
        if th < 1e-9:
            w0, w1 = 1.0 - t, t
        else:
            w0, w1 = math.sin((1.0 - t) * th) / math.sin(th), math.sin(t * th) / math.sin(th)
        nrm = 0.0
        for a in range(3):
            Rm[a, 2] = w0 * R0[a, 2] + w1 * R1[a, 2]
            nrm += Rm[a, 2] * Rm[a, 2]
        nrm = math.sqrt(nrm)
        for a in range(3):
            Rm[a, 2] /= nrm
    elif task == TASK_POSE:  # R(t) = exp(t log(R1 R0ᵀ)) R0
        D = np.empty((3, 3))
        for a in range(3):
            for b in range(3):
                D[a, b] = R1[a, 0] * R0[b, 0] + R1[a, 1] * R0[b, 1] + R1[a, 2] * R0[b, 2]
        vx = D[2, 1] - D[1, 2]
        vy = D[0, 2] - D[2, 0]
        vz = D[1, 0] - D[0, 1]
        s = 0.5 * math.sqrt(vx * vx + vy * vy + vz * vz)
        c = 0.5 * (D[0, 0] + D[1, 1] + D[2, 2] - 1.0)
        th = math.atan2(s, c)
        if s < 1e-12:  # tiny step (or a half turn, not a continuation step): go straight
            for a in range(3):
                for b in range(3):
                    Rm[a, b] = R1[a, b] if t > 0.5 else R0[a, b]
            return
        kx, ky, kz = vx / (2.0 * s), vy / (2.0 * s), vz / (2.0 * s)
        ct, st = math.cos(t * th), math.sin(t * th)
        vt = 1.0 - ct
        E = np.empty((3, 3))
        E[0, 0] = ct + kx * kx * vt
        E[0, 1] = kx * ky * vt - kz * st
        E[0, 2] = kx * kz * vt + ky * st
        E[1, 0] = ky * kx * vt + kz * st
        E[1, 1] = ct + ky * ky * vt
        E[1, 2] = ky * kz * vt - kx * st
        E[2, 0] = kz * kx * vt - ky * st
        E[2, 1] = kz * ky * vt + kx * st
        E[2, 2] = ct + kz * kz * vt
        for a in range(3):
            for b in range(3):
                Rm[a, b] = E[a, 0] * R0[0, b] + E[a, 1] * R0[1, b] + E[a, 2] * R0[2, b]
