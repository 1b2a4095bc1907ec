"""Batched inverse dynamics of serial chains: recursive Newton–Euler (RNEA) compiled with numba.

``inverse_dynamics(robot, q, qd, qdd)`` returns the joint torques (N·m; N for prismatic joints)
that realise the motion ``q, qd, qdd`` (rad, rad/s, rad/s²; shapes ``(..., n)``, e.g. a batch of
trajectories ``(B, K, n)``), including gravity (``robot.chain.gravity``, from the Pinocchio model)
and the reflected rotor inertia ``armature · qdd`` (armature = Jm·G²). With ``friction=True`` the
joint friction of the motors is added (:func:`joint_friction`).

The fast path runs on :class:`~legcore.robots.model.Chain` (taken from the Pinocchio model, so
standard DH, modified DH and URDF robots share it) and is tested against
:func:`inverse_dynamics_reference`, a plain loop over ``pinocchio.rnea`` (agreement ~1e-14 N·m).
Implementation notes: each joint frame is first rotated (once per robot) so that its axis is the
local z axis (identity for DH robots); the kernel is scalar component-wise code in a numba loop
over the flattened samples; the sines/cosines of a block of samples are computed in one
vectorisable loop (:func:`_sincos`). Large batches (≥ 131072 samples) run on
``numba.get_num_threads()`` threads in chunks; results are bit-identical to the serial kernel.
Multi-process workers should set ``NUMBA_NUM_THREADS=1`` (or pass ``parallel=False``) so that
threads do not oversubscribe the cores.

Recursion (all vectors in the moving joint frame i; ``E_i`` = rotation of frame i in frame i-1,
``d_i`` = origin of frame i in frame i-1, ``a_i`` = unit joint axis)::

    ω_i  = E_iᵀ ω_{i-1} + a_i q̇_i                                 (revolute)
    ω̇_i  = E_iᵀ ω̇_{i-1} + (E_iᵀ ω_{i-1}) × a_i q̇_i + a_i q̈_i
    v̇_i  = E_iᵀ (v̇_{i-1} + ω̇_{i-1} × d_i + ω_{i-1} × (ω_{i-1} × d_i))
           [+ 2 ω_i × a_i q̇_i + a_i q̈_i for a prismatic joint]    v̇_0 = −g
    F_i  = m_i (v̇_i + ω̇_i × c_i + ω_i × (ω_i × c_i)),   N_i = I_i ω̇_i + ω_i × I_i ω_i
    f_i  = F_i + E_{i+1} f_{i+1}
    n_i  = N_i + c_i × F_i + E_{i+1} n_{i+1} + d_{i+1} × E_{i+1} f_{i+1}
    τ_i  = a_iᵀ n_i (revolute) or a_iᵀ f_i (prismatic)  + armature_i q̈_i
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numba
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from legcore.robots.model import Robot

__all__ = [
    "COULOMB_DEAD_BAND",
    "inverse_dynamics",
    "inverse_dynamics_reference",
    "joint_friction",
]

FloatArray = NDArray[np.float64]

# Samples per work chunk of the parallel kernel: each chunk allocates its own scratch arrays once.
_CHUNK = 2048
# Below this many samples the serial kernel is used (thread start-up would dominate).
_PARALLEL_MIN = 64 * _CHUNK  # 131072


def _as_motion(robot: Robot, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> tuple[
    FloatArray, FloatArray, FloatArray
]:
    """Validate ``q, qd, qdd`` (same shape ``(..., nq)``) and return them as float arrays."""
    arrays = []
    for name, x in (("q", q), ("qd", qd), ("qdd", qdd)):
        a = np.asarray(x, dtype=np.float64)
        if a.ndim == 0 or a.shape[-1] != robot.nq:
            raise ValueError(
                f"{name}: last axis must have length nq = {robot.nq} for {robot.name!r}, "
                f"got shape {a.shape}"
            )
        arrays.append(a)
    if not arrays[0].shape == arrays[1].shape == arrays[2].shape:
        raise ValueError(
            f"q, qd, qdd: shapes must be equal, got {arrays[0].shape}, {arrays[1].shape}, "
            f"{arrays[2].shape}"
        )
    return arrays[0], arrays[1], arrays[2]


#: Joint speeds (rad/s or m/s) at or below which a joint is at rest for Coulomb friction.
COULOMB_DEAD_BAND = 1e-9


def joint_friction(robot: Robot, qd: ArrayLike) -> FloatArray:
    """Joint-side friction torque (N·m) of the motors+gears at joint speeds ``qd`` (..., n) rad/s.

    ``τ_f = G²·B·q̇ + |G|·Tc(q̇)`` with ``Tc = Tc_pos`` for q̇ > 0, ``Tc_neg`` (≤ 0) for q̇ < 0 and 0
    at rest, i.e. for ``|q̇| ≤ COULOMB_DEAD_BAND`` (1e-9 rad/s: a joint that stops or reverses
    has a speed of round-off size there, whose sign would switch the full Coulomb torque on
    and off) — the torque the actuator must *add* to overcome friction (roboticstoolbox
    ``Link.friction`` with the opposite sign; see ``robots/data/puma560.json`` "conventions").
    ``B`` (N·m·s/rad) and ``Tc`` (N·m) are motor-side values from ``robot.motors``; joints without
    a motor have zero friction.
    """
    qd = np.asarray(qd, dtype=np.float64)
    if qd.ndim == 0 or qd.shape[-1] != robot.nq:
        raise ValueError(f"qd: last axis must have length nq = {robot.nq}, got shape {qd.shape}")
    m = robot.motors
    band = COULOMB_DEAD_BAND
    coulomb = np.where(qd > band, m.Tc_pos, np.where(qd < -band, m.Tc_neg, 0.0))
    return m.G**2 * m.B * qd + np.abs(m.G) * coulomb


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


# sin/cos of the joint angles, block-wise and vectorisable (libm's scalar sin+cos took ~70 % of
# the kernel): Cody–Waite reduction by π/2 in three parts (fdlibm constants; exact k·P1 for
# |k| < 2^20) and fdlibm's minimax kernels on [-π/4, π/4]; agrees with libm to ~1e-16 absolute.
# Angles beyond |q| > 1e5 rad (and non-finite ones) fall back to math.sin/math.cos.
_TWO_OVER_PI = 6.36619772367581382433e-01
_PIO2_1 = 1.57079632673412561417e00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_3 = 2.02226624871116645580e-21
_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10
_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11
_TRIG_BIG = 1.0e5
_BLOCK = 64  # samples per trig block


@numba.njit(cache=True, nogil=True)
def _sincos(x: FloatArray, lo: int, hi: int, c: FloatArray, s: FloatArray) -> None:
    """``c[j-lo], s[j-lo] = cos(x[j]), sin(x[j])`` for j in lo..hi-1 (x 1-D)."""
    for j in range(lo, hi):
        xj = x[j]
        k = np.rint(xj * _TWO_OVER_PI)
        r = ((xj - k * _PIO2_1) - k * _PIO2_2) - k * _PIO2_3
        z = r * r
        sr = r + r * z * (_S1 + z * (_S2 + z * (_S3 + z * (_S4 + z * (_S5 + z * _S6)))))
        hz = 0.5 * z
        w = 1.0 - hz
        cr = w + (
            ((1.0 - w) - hz)
            + z * z * (_C1 + z * (_C2 + z * (_C3 + z * (_C4 + z * (_C5 + z * _C6)))))
        )
        quad = np.int64(k) & 3
        odd = (quad & 1) == 1
        a = cr if odd else sr
        b = sr if odd else cr
        s[j - lo] = -a if (quad & 2) == 2 else a
        c[j - lo] = -b if ((quad + 1) & 2) == 2 else b
    for j in range(lo, hi):
        if not abs(x[j]) <= _TRIG_BIG:  # also catches NaN / inf
            c[j - lo] = math.cos(x[j])
            s[j - lo] = math.sin(x[j])


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


def inverse_dynamics(
    robot: Robot,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    *,
    friction: bool = False,
    parallel: bool | None = None,
) -> FloatArray:
    """Joint torques (N·m, N for prismatic joints) for the motion ``q, qd, qdd``.

    ``q`` (rad or m), ``qd`` (rad/s), ``qdd`` (rad/s²): equal shapes ``(..., n)`` — one sample
    ``(n,)``, a trajectory ``(K, n)`` or a batch ``(B, K, n)``; returns the same shape. Includes
    gravity, rotor inertia (``armature · qdd``) and, with ``friction=True``,
    :func:`joint_friction`. ``parallel``: None picks the multi-threaded kernel for large batches;
    both kernels give bit-identical results.
    """
    q_a, qd_a, qdd_a = _as_motion(robot, q, qd, qdd)
    shape = q_a.shape
    n = robot.nq
    Q = np.ascontiguousarray(q_a.reshape(-1, n))
    QD = np.ascontiguousarray(qd_a.reshape(-1, n))
    QDD = np.ascontiguousarray(qdd_a.reshape(-1, n))
    tau = np.empty_like(Q)
    ch = _kernel_chain(robot)
    args = (
        Q,
        QD,
        QDD,
        ch.R,
        ch.p,
        ch.prismatic,
        ch.mass,
        ch.com,
        ch.I_com,
        ch.armature,
        ch.gravity,
        tau,
    )
    total = Q.shape[0]
    if parallel is None:
        parallel = total >= _PARALLEL_MIN and numba.get_num_threads() > 1
    if parallel:
        _rnea_parallel(*args, _CHUNK)
    else:
        _rnea_range(0, total, *args)
    out = tau.reshape(shape)
    if friction:
        out = out + joint_friction(robot, qd_a)
    return out


def inverse_dynamics_reference(
    robot: Robot,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    *,
    friction: bool = False,
) -> FloatArray:
    """Reference: a plain Python loop over ``pinocchio.rnea`` (includes armature; same I/O)."""
    q_a, qd_a, qdd_a = _as_motion(robot, q, qd, qdd)
    shape = q_a.shape
    n = robot.nq
    Q, QD, QDD = (np.ascontiguousarray(x.reshape(-1, n)) for x in (q_a, qd_a, qdd_a))
    tau = np.empty_like(Q)
    model, data = robot.model, robot.data()
    for s in range(Q.shape[0]):
        tau[s] = pin.rnea(model, data, Q[s], QD[s], QDD[s])
    out = tau.reshape(shape)
    if friction:
        out = out + joint_friction(robot, qd_a)
    return out
