"""Positions of a serial chain's frame origins for a batch of configurations (no 4×4 poses).

:func:`chain_points` returns, for configurations ``q`` (..., n), the world positions (m) of the
base frame, the n link frames and (optionally) the tool frame, shape (..., n+1[+1], 3) — the
translations of :func:`legcore.kinematics.frames` and :func:`legcore.kinematics.fk`, without
materialising the (..., n+1, 4, 4) poses (5× less memory written; the swing study's constraints
need only these points).

Implementation: one numba pass over the flattened batch with the recursion of the pose kernel
of :mod:`legcore.kinematics` (joint ``i``'s world pose is ``pose_{i-1} · (R_i, p_i) ·
exp(axis_i q_i)``), where each revolute joint's rotation ``R_i exp([a_i]× q)`` is
``Q0_i + cos q · Qc_i + sin q · Qs_i`` with the three 3×3 matrices computed once per robot
(Rodrigues; a quarter fewer flops than rotating by ``R_i`` and then by the exponential), and the
joint sines/cosines computed block-wise by the vectorisable :func:`legcore.sincos._sincos`
(agrees with libm to ~1e-16). The result equals ``frames(robot, q)[..., :3, 3]`` (and
``fk(robot, q)[..., :3, 3]`` for the tool) to ~1e-15 m; ``tests/legcore/test_fast_evaluation.py``
checks it to 1e-12 on the catalog robots and a URDF arm with a prismatic joint.
"""

from __future__ import annotations

import weakref

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.kinematics import _as_q, _link_placements
from legcore.robots.model import Robot
from legcore.sincos import _BLOCK, _sincos

__all__ = ["chain_points"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


# Per robot: each revolute joint's rotation R_i·exp([a_i]× q) = Q0_i + cos q·Qc_i + sin q·Qs_i
# (Rodrigues: exp([a]× q) = a aᵀ + cos q (I − a aᵀ) + sin q [a]×), computed once.
_TERMS: weakref.WeakKeyDictionary[Robot, tuple[FloatArray, FloatArray, FloatArray]] = (
    weakref.WeakKeyDictionary()
)


def _rotation_terms(robot: Robot) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(Q0, Qc, Qs), each (n, 3, 3): the joint rotations' constant, cos and sin parts."""
    cached = _TERMS.get(robot)
    if cached is not None:
        return cached
    c = robot.chain
    n = c.axis.shape[0]
    Q0 = np.empty((n, 3, 3))
    Qc = np.empty((n, 3, 3))
    Qs = np.empty((n, 3, 3))
    for i in range(n):
        a = np.asarray(c.axis[i], dtype=float)
        skew = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        Q0[i] = c.R[i] @ np.outer(a, a)
        Qc[i] = c.R[i] - Q0[i]
        Qs[i] = c.R[i] @ skew
    out = (Q0, Qc, Qs)
    _TERMS[robot] = out
    return out


@numba.njit(cache=True, nogil=True)
def _points_kernel(
    q: FloatArray,
    R: FloatArray,
    Q0: FloatArray,
    Qc: FloatArray,
    Qs: FloatArray,
    p: FloatArray,
    axis: FloatArray,
    prismatic: BoolArray,
    link_p: FloatArray,
    base_p: FloatArray,
    tool_p: FloatArray,
    with_tool: bool,
    out: FloatArray,
) -> None:  # pragma: no cover - compiled
    """Origins (N, M, 3) of base, link frames [and tool] for the samples q (N, n) (C order)."""
    N = q.shape[0]
    n = q.shape[1]
    qflat = q.reshape(-1)
    C = np.empty(_BLOCK * n)
    S = np.empty(_BLOCK * n)
    for s in range(N):
        if s % _BLOCK == 0:
            _sincos(qflat, s * n, min(s + _BLOCK, N) * n, C, S)
        jb = (s % _BLOCK) * n
        out[s, 0, 0] = base_p[0]
        out[s, 0, 1] = base_p[1]
        out[s, 0, 2] = base_p[2]
        # world rotation P and origin (px, py, pz) of joint frame i
        P00 = 1.0
        P01 = 0.0
        P02 = 0.0
        P10 = 0.0
        P11 = 1.0
        P12 = 0.0
        P20 = 0.0
        P21 = 0.0
        P22 = 1.0
        px = 0.0
        py = 0.0
        pz = 0.0
        for i in range(n):
            px = px + P00 * p[i, 0] + P01 * p[i, 1] + P02 * p[i, 2]
            py = py + P10 * p[i, 0] + P11 * p[i, 1] + P12 * p[i, 2]
            pz = pz + P20 * p[i, 0] + P21 * p[i, 1] + P22 * p[i, 2]
            if prismatic[i]:
                qi = q[s, i]
                a00 = R[i, 0, 0]
                a01 = R[i, 0, 1]
                a02 = R[i, 0, 2]
                a10 = R[i, 1, 0]
                a11 = R[i, 1, 1]
                a12 = R[i, 1, 2]
                a20 = R[i, 2, 0]
                a21 = R[i, 2, 1]
                a22 = R[i, 2, 2]
                wx = a00 * axis[i, 0] + a01 * axis[i, 1] + a02 * axis[i, 2]
                wy = a10 * axis[i, 0] + a11 * axis[i, 1] + a12 * axis[i, 2]
                wz = a20 * axis[i, 0] + a21 * axis[i, 1] + a22 * axis[i, 2]
                px += (P00 * wx + P01 * wy + P02 * wz) * qi
                py += (P10 * wx + P11 * wy + P12 * wz) * qi
                pz += (P20 * wx + P21 * wy + P22 * wz) * qi
            else:
                cq = C[jb + i]
                sq = S[jb + i]
                a00 = Q0[i, 0, 0] + cq * Qc[i, 0, 0] + sq * Qs[i, 0, 0]
                a01 = Q0[i, 0, 1] + cq * Qc[i, 0, 1] + sq * Qs[i, 0, 1]
                a02 = Q0[i, 0, 2] + cq * Qc[i, 0, 2] + sq * Qs[i, 0, 2]
                a10 = Q0[i, 1, 0] + cq * Qc[i, 1, 0] + sq * Qs[i, 1, 0]
                a11 = Q0[i, 1, 1] + cq * Qc[i, 1, 1] + sq * Qs[i, 1, 1]
                a12 = Q0[i, 1, 2] + cq * Qc[i, 1, 2] + sq * Qs[i, 1, 2]
                a20 = Q0[i, 2, 0] + cq * Qc[i, 2, 0] + sq * Qs[i, 2, 0]
                a21 = Q0[i, 2, 1] + cq * Qc[i, 2, 1] + sq * Qs[i, 2, 1]
                a22 = Q0[i, 2, 2] + cq * Qc[i, 2, 2] + sq * Qs[i, 2, 2]
            b00 = P00 * a00 + P01 * a10 + P02 * a20
            b01 = P00 * a01 + P01 * a11 + P02 * a21
            b02 = P00 * a02 + P01 * a12 + P02 * a22
            b10 = P10 * a00 + P11 * a10 + P12 * a20
            b11 = P10 * a01 + P11 * a11 + P12 * a21
            b12 = P10 * a02 + P11 * a12 + P12 * a22
            b20 = P20 * a00 + P21 * a10 + P22 * a20
            b21 = P20 * a01 + P21 * a11 + P22 * a21
            b22 = P20 * a02 + P21 * a12 + P22 * a22
            P00, P01, P02 = b00, b01, b02
            P10, P11, P12 = b10, b11, b12
            P20, P21, P22 = b20, b21, b22
            lx = link_p[i, 0]
            ly = link_p[i, 1]
            lz = link_p[i, 2]
            out[s, i + 1, 0] = px + P00 * lx + P01 * ly + P02 * lz
            out[s, i + 1, 1] = py + P10 * lx + P11 * ly + P12 * lz
            out[s, i + 1, 2] = pz + P20 * lx + P21 * ly + P22 * lz
        if with_tool:
            lx = tool_p[0]
            ly = tool_p[1]
            lz = tool_p[2]
            out[s, n + 1, 0] = px + P00 * lx + P01 * ly + P02 * lz
            out[s, n + 1, 1] = py + P10 * lx + P11 * ly + P12 * lz
            out[s, n + 1, 2] = pz + P20 * lx + P21 * ly + P22 * lz


def chain_points(
    robot: Robot, q: ArrayLike, tool: bool = False, offsets: ArrayLike | None = None
) -> FloatArray:
    """World origins (..., M, 3) (m) of the base, link frames 1..n and, with ``tool``, the tool.

    ``q`` (..., n) rad (m for prismatic joints). M = n + 1 (+ 1 with ``tool``); row 0 is the
    base (DH frame 0 / the URDF root), row i the origin of ``robot.link_frames[i-1]``, the last
    row with ``tool`` the tool point. Equals ``frames(robot, q)[..., :3, 3]`` followed by
    ``fk(robot, q)[..., :3, 3]``; the result is C-contiguous.

    ``offsets`` (n, 3) m: row i is instead the point fixed in link frame i at these link-frame
    coordinates (e.g. the links' centres of mass): ``F_i[:3, :3] @ offsets[i-1] + F_i[:3, 3]``
    for ``F = frames(robot, q)``, still without the 4×4 poses.
    """
    qf, batch = _as_q(robot, q)
    c = robot.chain
    link_R, link_p, base = _link_placements(robot)
    if offsets is not None:
        off = np.asarray(offsets, dtype=float)
        if off.shape != (robot.nq, 3):
            raise ValueError(f"offsets: expected shape ({robot.nq}, 3), got {off.shape}")
        link_p = np.ascontiguousarray(link_p + np.einsum("lij,lj->li", link_R, off))
    Q0, Qc, Qs = _rotation_terms(robot)
    n = robot.nq
    out = np.empty((qf.shape[0], n + 1 + int(tool), 3))
    _points_kernel(
        qf,
        c.R,
        Q0,
        Qc,
        Qs,
        c.p,
        c.axis,
        c.prismatic,
        link_p,
        np.ascontiguousarray(base[:3, 3]),
        c.tool_p,
        bool(tool),
        out,
    )
    return out.reshape(*batch, out.shape[1], 3)
