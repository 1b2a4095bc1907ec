"""The numba forward-kinematics kernel of :mod:`legcore.kinematics`: tool poses, Jacobians and
link frames of a flattened batch of configurations, in one pass per sample.

Joint ``i``'s world pose is ``pose_{i-1} · (R_i, p_i) · exp(axis_i q_i)``; the joint
sines/cosines of a block of samples are computed in one vectorisable loop
(``legcore.sincos._sincos``, ~1e-16 from libm).
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from legcore.sincos import _BLOCK, _sincos

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@numba.njit(cache=True, nogil=True)
def _chain_kernel(
    q: FloatArray,
    R: FloatArray,
    p: FloatArray,
    axis: FloatArray,
    prismatic: BoolArray,
    tool_R: FloatArray,
    tool_p: FloatArray,
    link_R: FloatArray,
    link_p: FloatArray,
    base: FloatArray,
    want_J: bool,
    want_frames: bool,
    T_out: FloatArray,
    J_out: FloatArray,
    F_out: FloatArray,
) -> None:  # pragma: no cover - compiled
    """Tool pose (N,4,4) [+ Jacobian (N,6,n)] [+ frames (N,n+1,4,4)] of the samples q (N,n)."""
    N = q.shape[0]
    n = q.shape[1]
    Rw = np.empty((n, 3, 3))  # world rotation of joint frame i
    pw = np.empty((n, 3))  # world origin of joint frame i
    qflat = q.reshape(-1)
    C = np.empty(_BLOCK * n)  # cos / sin of a block of samples' joint angles
    S = np.empty(_BLOCK * n)
    for s in range(N):
        if s % _BLOCK == 0:
            _sincos(qflat, s * n, min(s + _BLOCK, N) * n, C, S)
        jb = (s % _BLOCK) * n
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
            # placement of joint i in joint i-1: B = P · R_i, t = pp + P · p_i
            r = R[i]
            b00 = P00 * r[0, 0] + P01 * r[1, 0] + P02 * r[2, 0]
            b01 = P00 * r[0, 1] + P01 * r[1, 1] + P02 * r[2, 1]
            b02 = P00 * r[0, 2] + P01 * r[1, 2] + P02 * r[2, 2]
            b10 = P10 * r[0, 0] + P11 * r[1, 0] + P12 * r[2, 0]
            b11 = P10 * r[0, 1] + P11 * r[1, 1] + P12 * r[2, 1]
            b12 = P10 * r[0, 2] + P11 * r[1, 2] + P12 * r[2, 2]
            b20 = P20 * r[0, 0] + P21 * r[1, 0] + P22 * r[2, 0]
            b21 = P20 * r[0, 1] + P21 * r[1, 1] + P22 * r[2, 1]
            b22 = P20 * r[0, 2] + P21 * r[1, 2] + P22 * r[2, 2]
            tx = px + P00 * p[i, 0] + P01 * p[i, 1] + P02 * p[i, 2]
            ty = py + P10 * p[i, 0] + P11 * p[i, 1] + P12 * p[i, 2]
            tz = pz + P20 * p[i, 0] + P21 * p[i, 1] + P22 * p[i, 2]
            ax = axis[i, 0]
            ay = axis[i, 1]
            az = axis[i, 2]
            qi = q[s, i]
            if prismatic[i]:
                tx += (b00 * ax + b01 * ay + b02 * az) * qi
                ty += (b10 * ax + b11 * ay + b12 * az) * qi
                tz += (b20 * ax + b21 * ay + b22 * az) * qi
                P00, P01, P02 = b00, b01, b02
                P10, P11, P12 = b10, b11, b12
                P20, P21, P22 = b20, b21, b22
            else:
                # Rodrigues: E = exp([a]× q)
                cq = C[jb + i]
                sq = S[jb + i]
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
                P00 = b00 * e00 + b01 * e10 + b02 * e20
                P01 = b00 * e01 + b01 * e11 + b02 * e21
                P02 = b00 * e02 + b01 * e12 + b02 * e22
                P10 = b10 * e00 + b11 * e10 + b12 * e20
                P11 = b10 * e01 + b11 * e11 + b12 * e21
                P12 = b10 * e02 + b11 * e12 + b12 * e22
                P20 = b20 * e00 + b21 * e10 + b22 * e20
                P21 = b20 * e01 + b21 * e11 + b22 * e21
                P22 = b20 * e02 + b21 * e12 + b22 * e22
            px = tx
            py = ty
            pz = tz
            Rw[i, 0, 0] = P00
            Rw[i, 0, 1] = P01
            Rw[i, 0, 2] = P02
            Rw[i, 1, 0] = P10
            Rw[i, 1, 1] = P11
            Rw[i, 1, 2] = P12
            Rw[i, 2, 0] = P20
            Rw[i, 2, 1] = P21
            Rw[i, 2, 2] = P22
            pw[i, 0] = px
            pw[i, 1] = py
            pw[i, 2] = pz
        # tool frame
        T = T_out[s]
        for a in range(3):
            Pa0 = Rw[n - 1, a, 0]
            Pa1 = Rw[n - 1, a, 1]
            Pa2 = Rw[n - 1, a, 2]
            for c in range(3):
                T[a, c] = Pa0 * tool_R[0, c] + Pa1 * tool_R[1, c] + Pa2 * tool_R[2, c]
            T[a, 3] = pw[n - 1, a] + Pa0 * tool_p[0] + Pa1 * tool_p[1] + Pa2 * tool_p[2]
        T[3, 0] = 0.0
        T[3, 1] = 0.0
        T[3, 2] = 0.0
        T[3, 3] = 1.0
        if want_J:
            ox = T[0, 3]
            oy = T[1, 3]
            oz = T[2, 3]
            J = J_out[s]
            for i in range(n):
                ax = axis[i, 0]
                ay = axis[i, 1]
                az = axis[i, 2]
                wx = Rw[i, 0, 0] * ax + Rw[i, 0, 1] * ay + Rw[i, 0, 2] * az
                wy = Rw[i, 1, 0] * ax + Rw[i, 1, 1] * ay + Rw[i, 1, 2] * az
                wz = Rw[i, 2, 0] * ax + Rw[i, 2, 1] * ay + Rw[i, 2, 2] * az
                if prismatic[i]:
                    J[0, i] = wx
                    J[1, i] = wy
                    J[2, i] = wz
                    J[3, i] = 0.0
                    J[4, i] = 0.0
                    J[5, i] = 0.0
                else:
                    dx = ox - pw[i, 0]
                    dy = oy - pw[i, 1]
                    dz = oz - pw[i, 2]
                    J[0, i] = wy * dz - wz * dy
                    J[1, i] = wz * dx - wx * dz
                    J[2, i] = wx * dy - wy * dx
                    J[3, i] = wx
                    J[4, i] = wy
                    J[5, i] = wz
        if want_frames:
            F = F_out[s]
            for a in range(4):
                for c in range(4):
                    F[0, a, c] = base[a, c]
            for i in range(n):
                for a in range(3):
                    Pa0 = Rw[i, a, 0]
                    Pa1 = Rw[i, a, 1]
                    Pa2 = Rw[i, a, 2]
                    for c in range(3):
                        F[i + 1, a, c] = (
                            Pa0 * link_R[i, 0, c] + Pa1 * link_R[i, 1, c] + Pa2 * link_R[i, 2, c]
                        )
                    F[i + 1, a, 3] = (
                        pw[i, a] + Pa0 * link_p[i, 0] + Pa1 * link_p[i, 1] + Pa2 * link_p[i, 2]
                    )
                F[i + 1, 3, 0] = 0.0
                F[i + 1, 3, 1] = 0.0
                F[i + 1, 3, 2] = 0.0
                F[i + 1, 3, 3] = 1.0
