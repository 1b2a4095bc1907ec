"""Kinematics of one sample for the compiled IK loop: tool pose + Jacobian, task errors.

The IK loop runs on the chain re-expressed by :func:`z_chain` (every joint turning about its
frame's z axis; the conventions of :mod:`legcore.kinematics`: joint i's world pose is
``pose_{i-1} · (R_i, p_i) · exp(axis_i q_i)``, Jacobian rows ``[v; ω]`` world-aligned at the
tool point): :func:`fk_z` (tool pose, a joint a turn of two frame columns instead of Rodrigues
+ a 3×3 product) and :func:`jac_z` (the Jacobian from the frames ``fk_z`` leaves, computed
only when a step needs it); ``tests/legcore/ik_numeric/test_ik_numeric.py`` checks them against
:func:`legcore.kinematics.fk_jacobian` and a plain per-sample reference.
:func:`task_error` turns a tool pose into the error of an IK task
(``TASK_POSITION`` 3, ``TASK_AXIS`` 5, ``TASK_POSE`` 6 rows), :func:`task_rows` gives its
Jacobian rows (:func:`errors`: both); :func:`interp_target` interpolates between two targets
(continuation along a path).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

__all__ = [
    "TASK_AXIS",
    "TASK_POSE",
    "TASK_POSITION",
    "errors",
    "fk_z",
    "interp_target",
    "jac_z",
    "task_error",
    "task_rows",
    "z_chain",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

TASK_POSITION = 3
TASK_AXIS = 5
TASK_POSE = 6


def z_chain(
    R: FloatArray, p: FloatArray, axis: FloatArray, tool_R: FloatArray, tool_p: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """The same chain with every joint frame turned so that its motion axis is its z axis.

    Joint frame i is replaced by ``F_i S_i`` with ``S_i`` a rotation taking ``e_z`` to
    ``axis_i``; returns ``(R', p', tool_R', tool_p')`` (axes all ``e_z``) with
    ``R'_i = S_{i-1}ᵀ R_i S_i``, ``p'_i = S_{i-1}ᵀ p_i`` (``S_{-1} = I``) and the tool placement
    ``S_{n-1}ᵀ (tool_R, tool_p)``: the tool pose and the Jacobian of every ``q`` are unchanged,
    and a joint's rotation is a turn about z (:func:`fk_z`, cheaper than Rodrigues).
    """
    n = R.shape[0]
    S = np.empty((n, 3, 3))
    for i in range(n):
        a = axis[i] / np.linalg.norm(axis[i])
        ez = np.array([0.0, 0.0, 1.0])
        v = np.cross(ez, a)
        s, c = float(np.linalg.norm(v)), float(a[2])
        if s < 1e-12:  # along ±z: identity, or a half turn about x
            S[i] = np.eye(3) if c > 0.0 else np.diag([1.0, -1.0, -1.0])
            continue
        k = v / s
        Kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
        S[i] = np.eye(3) + s * Kx + (1.0 - c) * (Kx @ Kx)
    prev = np.concatenate([np.eye(3)[None], S[:-1]])
    Rz = np.ascontiguousarray(np.swapaxes(prev, 1, 2) @ R @ S)
    pz = np.ascontiguousarray(np.einsum("iba,ib->ia", prev, p))
    last = S[n - 1].T
    return Rz, pz, np.ascontiguousarray(last @ tool_R), np.ascontiguousarray(last @ tool_p)


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def fk_z(
    q: FloatArray,
    R: FloatArray,
    p: FloatArray,
    prismatic: BoolArray,
    tool_R: FloatArray,
    tool_p: FloatArray,
    Rw: FloatArray,
    pw: FloatArray,
    T: FloatArray,
) -> None:  # pragma: no cover - compiled
    """Tool pose ``T`` (4, 4) of ``q`` (n,) on a chain from :func:`z_chain` (axes along z).

    Leaves the joint frames in ``Rw`` (n, 3, 3) and ``pw`` (n, 3) for :func:`jac_z`.
    """
    n = q.shape[0]
    for i in range(n):  # no array views here: each would cost a reference count
        if i == 0:
            for a in range(3):
                pw[0, a] = p[0, a]
                for c in range(3):
                    Rw[0, a, c] = R[0, a, c]
        else:
            for a in range(3):
                g0, g1, g2 = Rw[i - 1, a, 0], Rw[i - 1, a, 1], Rw[i - 1, a, 2]
                pw[i, a] = pw[i - 1, a] + g0 * p[i, 0] + g1 * p[i, 1] + g2 * p[i, 2]
                for c in range(3):
                    Rw[i, a, c] = g0 * R[i, 0, c] + g1 * R[i, 1, c] + g2 * R[i, 2, c]
        qi = q[i]
        if prismatic[i]:
            for a in range(3):
                pw[i, a] += Rw[i, a, 2] * qi
        else:  # Rw[i] ← Rw[i] · Rot_z(q)
            cq, sq = math.cos(qi), math.sin(qi)
            for a in range(3):
                b0, b1 = Rw[i, a, 0], Rw[i, a, 1]
                Rw[i, a, 0] = b0 * cq + b1 * sq
                Rw[i, a, 1] = b1 * cq - b0 * sq
    k = n - 1
    for a in range(3):
        l0, l1, l2 = Rw[k, a, 0], Rw[k, a, 1], Rw[k, a, 2]
        for c in range(3):
            T[a, c] = l0 * tool_R[0, c] + l1 * tool_R[1, c] + l2 * tool_R[2, c]
        T[a, 3] = pw[k, a] + l0 * tool_p[0] + l1 * tool_p[1] + l2 * tool_p[2]
    T[3, 0] = 0.0
    T[3, 1] = 0.0
    T[3, 2] = 0.0
    T[3, 3] = 1.0


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def jac_z(
    Rw: FloatArray, pw: FloatArray, T: FloatArray, prismatic: BoolArray, J: FloatArray
) -> None:  # pragma: no cover - compiled
    """Jacobian ``J`` (6, n) (rows ``[v; ω]``, world-aligned at the tool point) from the joint
    frames and tool pose that :func:`fk_z` left (joint axes = the frames' z columns)."""
    ox, oy, oz = T[0, 3], T[1, 3], T[2, 3]
    for i in range(prismatic.shape[0]):
        wx, wy, wz = Rw[i, 0, 2], Rw[i, 1, 2], Rw[i, 2, 2]
        if prismatic[i]:
            J[0, i], J[1, i], J[2, i] = wx, wy, wz
            J[3, i], J[4, i], J[5, i] = 0.0, 0.0, 0.0
        else:
            dx, dy, dz = ox - pw[i, 0], oy - pw[i, 1], oz - pw[i, 2]
            J[0, i] = wy * dz - wz * dy
            J[1, i] = wz * dx - wx * dz
            J[2, i] = wx * dy - wy * dx
            J[3, i], J[4, i], J[5, i] = wx, wy, wz


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _log3(Rm: FloatArray, out: FloatArray, o: int = 0) -> float:  # pragma: no cover - compiled
    """Rotation vector of the 3×3 rotation ``Rm`` into ``out[o:o + 3]``; returns the angle (rad)."""
    vx = Rm[2, 1] - Rm[1, 2]
    vy = Rm[0, 2] - Rm[2, 0]
    vz = Rm[1, 0] - Rm[0, 1]
    s = 0.5 * math.sqrt(vx * vx + vy * vy + vz * vz)
    c = 0.5 * (Rm[0, 0] + Rm[1, 1] + Rm[2, 2] - 1.0)
    th = math.atan2(s, c)
    if th < 1e-8:
        f = 0.5 + th * th / 12.0
        out[o + 0] = f * vx
        out[o + 1] = f * vy
        out[o + 2] = f * vz
    elif th < math.pi - 1e-3:
        f = 0.5 * th / s
        out[o + 0] = f * vx
        out[o + 1] = f * vy
        out[o + 2] = f * vz
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
            out[o + i] = a
            nrm += a * a
        nrm = math.sqrt(nrm)
        sgn = 1.0 if out[o + 0] * vx + out[o + 1] * vy + out[o + 2] * vz >= 0.0 else -1.0
        for i in range(3):
            out[o + i] *= sgn * th / nrm
    return th


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def task_error(
    T: FloatArray, tp: FloatArray, tR: FloatArray, task: int, w: float, e: FloatArray,
    tmp: FloatArray,
) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """Fill the task error ``e`` (m,) at tool pose ``T`` (orientation rows scaled by ``w``).

    Returns ``(|e|², position error (m), orientation error (rad))`` — the squared norm weighted,
    the two errors not. ``tmp`` (3, 3) is scratch space.
    """
    ep2 = 0.0
    for a in range(3):
        e[a] = tp[a] - T[a, 3]
        ep2 += e[a] * e[a]
    if task == TASK_POSITION:
        return ep2, math.sqrt(ep2), 0.0
    if task == TASK_POSE:
        for a in range(3):  # tmp = tR · Rᵀ
            for b in range(3):
                tmp[a, b] = tR[a, 0] * T[b, 0] + tR[a, 1] * T[b, 1] + tR[a, 2] * T[b, 2]
        th = _log3(tmp, e, 3)
        u0, u1, u2 = e[3], e[4], e[5]
        e[3], e[4], e[5] = w * u0, w * u1, w * u2
        return ep2 + e[3] * e[3] + e[4] * e[4] + e[5] * e[5], math.sqrt(ep2), th
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
        e[3 + r] = w * (T[0, r] * ux + T[1, r] * uy + T[2, r] * uz)
        f += e[3 + r] * e[3 + r]
    return f, math.sqrt(ep2), th


@numba.njit(cache=True, nogil=True, error_model="numpy", inline="always")
def task_rows(
    T: FloatArray, J: FloatArray, task: int, w: float, A: FloatArray
) -> None:  # pragma: no cover - compiled
    """Fill the task Jacobian ``A`` (m, n) from the tool pose ``T`` and Jacobian ``J`` (6, n)."""
    n = J.shape[1]
    for a in range(3):
        for j in range(n):
            A[a, j] = J[a, j]
    if task == TASK_POSE:
        for a in range(3):
            for j in range(n):
                A[3 + a, j] = w * J[3 + a, j]
    elif task == TASK_AXIS:
        for r in range(2):
            bx, by, bz = T[0, r], T[1, r], T[2, r]
            for j in range(n):
                A[3 + r, j] = w * (bx * J[3, j] + by * J[4, j] + bz * J[5, j])


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
    """Task error ``e`` (m,) and Jacobian ``A`` (m, n) at tool pose ``T``, Jacobian ``J``:
    :func:`task_error` and :func:`task_rows` together (same return value)."""
    task_rows(T, J, task, w, A)
    return task_error(T, tp, tR, task, w, e, tmp)


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
