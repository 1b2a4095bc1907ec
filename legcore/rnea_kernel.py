"""The numba RNEA kernels of :mod:`legcore.dynamics` (serial and chunked-parallel) and the
chain they run on, re-expressed so that every joint moves along/about its local z axis (once
per robot, cached)."""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import NDArray

from legcore.robots.model import Robot
from legcore.sincos import _BLOCK, _sincos

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class _KernelChain:
    """:class:`Chain` re-expressed so that every joint moves along/about its local z axis.

    Frame i' = frame i · Q_i with Q_i e_z = axis_i, hence ``R'_i = Q_{i-1}ᵀ R_i Q_i``,
    ``p'_i = Q_{i-1}ᵀ p_i``, ``c'_i = Q_iᵀ c_i``, ``I'_i = Q_iᵀ I_i Q_i``. Joints whose axis is
    already +z (every DH robot) keep Q_i = I, so their numbers are untouched.
    """

    R: FloatArray
    p: FloatArray
    prismatic: NDArray[np.bool_]
    mass: FloatArray
    com: FloatArray
    I_com: FloatArray
    armature: FloatArray
    gravity: FloatArray


def _z_to(a: FloatArray) -> FloatArray:
    """A rotation Q with Q e_z = a (unit a); the identity when a is exactly e_z."""
    z = np.array([0.0, 0.0, 1.0])
    if np.array_equal(a, z):
        return np.eye(3)
    if np.allclose(a, -z, atol=1e-15):
        return np.diag([1.0, -1.0, -1.0])  # π about x
    v = np.cross(z, a)
    c = float(z @ a)
    vx = np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])
    return np.eye(3) + vx + vx @ vx / (1.0 + c)


_KERNEL_CHAINS: weakref.WeakKeyDictionary[Robot, _KernelChain] = weakref.WeakKeyDictionary()


def _kernel_chain(robot: Robot) -> _KernelChain:
    kc = _KERNEL_CHAINS.get(robot)
    if kc is not None:
        return kc
    ch = robot.chain
    n = ch.n
    Q = [_z_to(ch.axis[i] / np.linalg.norm(ch.axis[i])) for i in range(n)]
    R = np.empty((n, 3, 3))
    p = np.empty((n, 3))
    com = np.empty((n, 3))
    I_com = np.empty((n, 3, 3))
    prev = np.eye(3)
    for i in range(n):
        R[i] = prev.T @ ch.R[i] @ Q[i]
        p[i] = prev.T @ ch.p[i]
        com[i] = Q[i].T @ ch.com[i]
        I_com[i] = Q[i].T @ ch.I_com[i] @ Q[i]
        prev = Q[i]
    kc = _KernelChain(
        R=np.ascontiguousarray(R),
        p=np.ascontiguousarray(p),
        prismatic=np.ascontiguousarray(ch.prismatic, dtype=np.bool_),
        mass=np.ascontiguousarray(ch.mass, dtype=np.float64),
        com=np.ascontiguousarray(com),
        I_com=np.ascontiguousarray(I_com),
        armature=np.ascontiguousarray(ch.armature, dtype=np.float64),
        gravity=np.ascontiguousarray(ch.gravity, dtype=np.float64),
    )
    _KERNEL_CHAINS[robot] = kc
    return kc


@numba.njit(cache=True, nogil=True)
def _rnea_range(
    lo: int,
    hi: int,
    q: FloatArray,
    qd: FloatArray,
    qdd: FloatArray,
    R: FloatArray,
    p: FloatArray,
    prismatic: NDArray[np.bool_],
    mass: FloatArray,
    com: FloatArray,
    I_com: FloatArray,
    armature: FloatArray,
    gravity: FloatArray,
    tau: FloatArray,
) -> None:  # pragma: no cover - compiled
    """RNEA for samples ``lo..hi-1`` of the flattened (N, n) arrays, written into ``tau``.

    Joint axes are the local z axes (see :class:`_KernelChain`).
    """
    n = q.shape[1]
    qflat = q.reshape(-1)
    C = np.empty(_BLOCK * n)  # cos / sin of the block's joint angles
    S = np.empty(_BLOCK * n)
    E = np.empty((n, 3, 3))  # rotation of frame i in frame i-1
    d = np.empty((n, 3))  # origin of frame i in frame i-1
    F = np.empty((n, 3))  # net force on link i (frame i)
    N = np.empty((n, 3))  # net moment about the COM (frame i)
    for s in range(lo, hi):
        if (s - lo) % _BLOCK == 0:
            _sincos(qflat, s * n, min(s + _BLOCK, hi) * n, C, S)
        jb = ((s - lo) % _BLOCK) * n
        # ---- forward pass -------------------------------------------------------------------
        w0x = 0.0
        w0y = 0.0
        w0z = 0.0
        a0x = 0.0
        a0y = 0.0
        a0z = 0.0
        vdx = -gravity[0]
        vdy = -gravity[1]
        vdz = -gravity[2]
        for i in range(n):
            qi = q[s, i]
            dqi = qd[s, i]
            ddqi = qdd[s, i]
            pri = prismatic[i]
            if pri:
                for r in range(3):
                    E[i, r, 0] = R[i, r, 0]
                    E[i, r, 1] = R[i, r, 1]
                    E[i, r, 2] = R[i, r, 2]
                    d[i, r] = p[i, r] + R[i, r, 2] * qi
            else:
                # E = R_i · Rz(q)
                cq = C[jb + i]
                sq = S[jb + i]
                for r in range(3):
                    b0 = R[i, r, 0]
                    b1 = R[i, r, 1]
                    E[i, r, 0] = b0 * cq + b1 * sq
                    E[i, r, 1] = b1 * cq - b0 * sq
                    E[i, r, 2] = R[i, r, 2]
                    d[i, r] = p[i, r]
            dx = d[i, 0]
            dy = d[i, 1]
            dz = d[i, 2]
            # linear acceleration of the new origin, still in the parent frame
            cx = w0y * dz - w0z * dy
            cy = w0z * dx - w0x * dz
            cz = w0x * dy - w0y * dx
            ux = vdx + (a0y * dz - a0z * dy) + (w0y * cz - w0z * cy)
            uy = vdy + (a0z * dx - a0x * dz) + (w0z * cx - w0x * cz)
            uz = vdz + (a0x * dy - a0y * dx) + (w0x * cy - w0y * cx)
            # rotate parent quantities into frame i: x_i = Eᵀ x_{i-1}
            e00 = E[i, 0, 0]
            e01 = E[i, 0, 1]
            e02 = E[i, 0, 2]
            e10 = E[i, 1, 0]
            e11 = E[i, 1, 1]
            e12 = E[i, 1, 2]
            e20 = E[i, 2, 0]
            e21 = E[i, 2, 1]
            e22 = E[i, 2, 2]
            wpx = e00 * w0x + e10 * w0y + e20 * w0z
            wpy = e01 * w0x + e11 * w0y + e21 * w0z
            wpz = e02 * w0x + e12 * w0y + e22 * w0z
            apx = e00 * a0x + e10 * a0y + e20 * a0z
            apy = e01 * a0x + e11 * a0y + e21 * a0z
            apz = e02 * a0x + e12 * a0y + e22 * a0z
            vdx = e00 * ux + e10 * uy + e20 * uz
            vdy = e01 * ux + e11 * uy + e21 * uz
            vdz = e02 * ux + e12 * uy + e22 * uz
            if pri:
                w0x = wpx
                w0y = wpy
                w0z = wpz
                a0x = apx
                a0y = apy
                a0z = apz
                # Coriolis 2 ω × (e_z q̇) and the joint acceleration e_z q̈
                vdx += 2.0 * (w0y * dqi)
                vdy -= 2.0 * (w0x * dqi)
                vdz += ddqi
            else:
                w0x = wpx
                w0y = wpy
                w0z = wpz + dqi
                # ω̇ = Eᵀω̇_{i-1} + (Eᵀω_{i-1}) × e_z q̇ + e_z q̈
                a0x = apx + wpy * dqi
                a0y = apy - wpx * dqi
                a0z = apz + ddqi
            # COM acceleration and link wrench
            ccx = com[i, 0]
            ccy = com[i, 1]
            ccz = com[i, 2]
            tx = w0y * ccz - w0z * ccy
            ty = w0z * ccx - w0x * ccz
            tz = w0x * ccy - w0y * ccx
            m = mass[i]
            F[i, 0] = m * (vdx + (a0y * ccz - a0z * ccy) + (w0y * tz - w0z * ty))
            F[i, 1] = m * (vdy + (a0z * ccx - a0x * ccz) + (w0z * tx - w0x * tz))
            F[i, 2] = m * (vdz + (a0x * ccy - a0y * ccx) + (w0x * ty - w0y * tx))
            I00 = I_com[i, 0, 0]
            I01 = I_com[i, 0, 1]
            I02 = I_com[i, 0, 2]
            I10 = I_com[i, 1, 0]
            I11 = I_com[i, 1, 1]
            I12 = I_com[i, 1, 2]
            I20 = I_com[i, 2, 0]
            I21 = I_com[i, 2, 1]
            I22 = I_com[i, 2, 2]
            hx = I00 * w0x + I01 * w0y + I02 * w0z
            hy = I10 * w0x + I11 * w0y + I12 * w0z
            hz = I20 * w0x + I21 * w0y + I22 * w0z
            N[i, 0] = I00 * a0x + I01 * a0y + I02 * a0z + (w0y * hz - w0z * hy)
            N[i, 1] = I10 * a0x + I11 * a0y + I12 * a0z + (w0z * hx - w0x * hz)
            N[i, 2] = I20 * a0x + I21 * a0y + I22 * a0z + (w0x * hy - w0y * hx)
        # ---- backward pass ------------------------------------------------------------------
        fx = 0.0
        fy = 0.0
        fz = 0.0
        nx = 0.0
        ny = 0.0
        nz = 0.0
        for i in range(n - 1, -1, -1):
            if i < n - 1:
                # child wrench (frame i+1) -> frame i, moment carried to origin i
                e00 = E[i + 1, 0, 0]
                e01 = E[i + 1, 0, 1]
                e02 = E[i + 1, 0, 2]
                e10 = E[i + 1, 1, 0]
                e11 = E[i + 1, 1, 1]
                e12 = E[i + 1, 1, 2]
                e20 = E[i + 1, 2, 0]
                e21 = E[i + 1, 2, 1]
                e22 = E[i + 1, 2, 2]
                gx = e00 * fx + e01 * fy + e02 * fz
                gy = e10 * fx + e11 * fy + e12 * fz
                gz = e20 * fx + e21 * fy + e22 * fz
                mx = e00 * nx + e01 * ny + e02 * nz
                my = e10 * nx + e11 * ny + e12 * nz
                mz = e20 * nx + e21 * ny + e22 * nz
                dx = d[i + 1, 0]
                dy = d[i + 1, 1]
                dz = d[i + 1, 2]
                mx += dy * gz - dz * gy
                my += dz * gx - dx * gz
                mz += dx * gy - dy * gx
            else:
                gx = 0.0
                gy = 0.0
                gz = 0.0
                mx = 0.0
                my = 0.0
                mz = 0.0
            Fx = F[i, 0]
            Fy = F[i, 1]
            Fz = F[i, 2]
            ccx = com[i, 0]
            ccy = com[i, 1]
            ccz = com[i, 2]
            fx = gx + Fx
            fy = gy + Fy
            fz = gz + Fz
            nx = mx + N[i, 0] + (ccy * Fz - ccz * Fy)
            ny = my + N[i, 1] + (ccz * Fx - ccx * Fz)
            nz = mz + N[i, 2] + (ccx * Fy - ccy * Fx)
            t = fz if prismatic[i] else nz
            tau[s, i] = t + armature[i] * qdd[s, i]


@numba.njit(cache=True, parallel=True, nogil=True)
def _rnea_parallel(
    q: FloatArray,
    qd: FloatArray,
    qdd: FloatArray,
    R: FloatArray,
    p: FloatArray,
    prismatic: NDArray[np.bool_],
    mass: FloatArray,
    com: FloatArray,
    I_com: FloatArray,
    armature: FloatArray,
    gravity: FloatArray,
    tau: FloatArray,
    chunk: int,
) -> None:  # pragma: no cover - compiled
    """Chunks of samples in parallel; every sample runs the same code as the serial kernel."""
    total = q.shape[0]
    n_chunks = (total + chunk - 1) // chunk
    for c in numba.prange(n_chunks):
        lo = c * chunk
        hi = min(lo + chunk, total)
        _rnea_range(lo, hi, q, qd, qdd, R, p, prismatic, mass, com, I_com, armature, gravity, tau)
