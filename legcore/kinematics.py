"""Batched kinematics of serial chains: forward kinematics, Jacobians, manipulability and IK.

Conventions (see ``docs/kinematics.md``):

- Configurations ``q`` have shape ``(..., n)`` (rad for revolute, m for prismatic joints): one
  configuration ``(n,)``, a batch ``(B, n)`` or a batch of trajectories ``(B, K, n)``. Every
  result keeps the leading batch shape: ``fk`` → ``(..., 4, 4)``, ``jacobian`` → ``(..., 6, n)``.
- Poses ``T`` are 4×4 homogeneous transforms in the world frame (m).
- ``jacobian`` is the geometric Jacobian ``[v; ω]`` of the tool frame with ``v`` the linear
  velocity of the tool point (m/s per joint unit) and ``ω`` the angular velocity (rad/s per
  joint unit), both in world-aligned axes — Pinocchio's ``LOCAL_WORLD_ALIGNED`` at the tool.

Fast path: one numba kernel loops over the (flattened) batch on :class:`~legcore.robots.Chain`
arrays, which are taken from the Pinocchio model, so DH and URDF robots share it. Joint ``i``'s
world pose is ``pose_{i-1} · (R_i, p_i) · exp(axis_i q_i)``; the joint sines/cosines of a block
of samples are computed in one vectorisable loop (``legcore.dynamics._sincos``, ~1e-16 from
libm). Positions only (no 4×4 poses): :func:`legcore.chain_points.chain_points`. The per-sample
Pinocchio loops :func:`fk_reference`, :func:`frames_reference` and :func:`jacobian_reference`
are the reference the fast path is tested against (equal to ~1e-15).

Inverse kinematics: :func:`ik` dispatches on ``robot.ik_family`` to the closed forms
(``legcore.ik.puma560``, ``legcore.ik.arm5``, ``legcore.ik.leg3``, ``legcore.ik.leg2``) and to
damped least squares (:func:`ik_dls`) otherwise. Unreachable targets are reported per sample
(``reachable`` False, ``q`` NaN); joint limits are reported (``within_limits``), never enforced by
clipping.
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numba
import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from legcore.dynamics import _BLOCK, _sincos
from legcore.robots.model import Robot
from legcore.robots.spec import DHRobotSpec

__all__ = [
    "IKResult",
    "fk",
    "fk_jacobian",
    "fk_reference",
    "frames",
    "frames_reference",
    "ik",
    "ik_dls",
    "jacobian",
    "jacobian_reference",
    "log3",
    "manipulability",
    "manipulability_split",
    "pose_error",
    "wrap_to_limits",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]


# ---------------------------------------------------------------------------------------------
# input handling
# ---------------------------------------------------------------------------------------------


def _as_q(robot: Robot, q: ArrayLike, name: str = "q") -> tuple[FloatArray, tuple[int, ...]]:
    """``q`` (..., n) → (flat (N, n) C-contiguous float array, batch shape).

    NaN entries are allowed and propagate (an IK result's unreachable samples stay NaN).
    """
    a = np.asarray(q, dtype=np.float64)
    if a.ndim == 0 or a.shape[-1] != robot.nq:
        raise ValueError(
            f"{name}: last axis must have length nq = {robot.nq} for {robot.name!r}, "
            f"got shape {a.shape}"
        )
    batch = a.shape[:-1]
    return np.ascontiguousarray(a.reshape(-1, robot.nq)), batch


# Link-frame placements (in the joint frame) and the base pose, per robot. Robots are immutable,
# so this is computed once; the weak keys let robots be garbage collected.
_LINK_CACHE: weakref.WeakKeyDictionary[Robot, tuple[FloatArray, FloatArray, FloatArray]] = (
    weakref.WeakKeyDictionary()
)


def _link_placements(robot: Robot) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(link_R (n,3,3), link_p (n,3), base (4,4)) of the link frames drawn by :func:`frames`."""
    cached = _LINK_CACHE.get(robot)
    if cached is not None:
        return cached
    n = robot.nq
    link_R = np.zeros((n, 3, 3))
    link_p = np.zeros((n, 3))
    for i, fid in enumerate(robot.link_frames):
        frame = robot.model.frames[fid]
        if frame.parentJoint != i + 1:
            raise ValueError(
                f"link frame {frame.name!r} must be attached to joint {i + 1}, "
                f"found joint {frame.parentJoint}"
            )
        link_R[i] = frame.placement.rotation
        link_p[i] = frame.placement.translation
    spec = robot.spec
    if isinstance(spec, DHRobotSpec) and spec.base is not None:
        base = np.asarray(spec.base, dtype=float)
    else:
        base = np.eye(4)
    out = (link_R, link_p, base)
    _LINK_CACHE[robot] = out
    return out


# ---------------------------------------------------------------------------------------------
# numba fast path
# ---------------------------------------------------------------------------------------------


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


def _run(
    robot: Robot, qf: FloatArray, want_J: bool, want_frames: bool
) -> tuple[FloatArray, FloatArray, FloatArray]:
    c = robot.chain
    N, n = qf.shape
    T = np.empty((N, 4, 4))
    J = np.empty((N, 6, n) if want_J else (0, 6, n))
    if want_frames:
        link_R, link_p, base = _link_placements(robot)
        F = np.empty((N, n + 1, 4, 4))
    else:
        link_R, link_p, base = np.zeros((n, 3, 3)), np.zeros((n, 3)), np.eye(4)
        F = np.empty((0, n + 1, 4, 4))
    _chain_kernel(
        qf,
        c.R,
        c.p,
        c.axis,
        c.prismatic,
        c.tool_R,
        c.tool_p,
        link_R,
        link_p,
        base,
        want_J,
        want_frames,
        T,
        J,
        F,
    )
    return T, J, F


def fk(robot: Robot, q: ArrayLike) -> FloatArray:
    """Tool pose ``T`` (..., 4, 4) in the world frame (m) for configurations ``q`` (..., n)."""
    qf, batch = _as_q(robot, q)
    T, _, _ = _run(robot, qf, False, False)
    return T.reshape(*batch, 4, 4)


def jacobian(robot: Robot, q: ArrayLike) -> FloatArray:
    """Geometric tool Jacobian ``J`` (..., 6, n): rows ``[v; ω]`` in world-aligned axes.

    ``v`` is the velocity of the tool point (m/s per rad/s, or per m/s for a prismatic joint)
    and ``ω`` the angular velocity (rad/s per joint unit) — Pinocchio ``LOCAL_WORLD_ALIGNED``.
    """
    qf, batch = _as_q(robot, q)
    _, J, _ = _run(robot, qf, True, False)
    return J.reshape(*batch, 6, robot.nq)


def fk_jacobian(robot: Robot, q: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Tool pose (..., 4, 4) and tool Jacobian (..., 6, n) in one pass (see :func:`jacobian`)."""
    qf, batch = _as_q(robot, q)
    T, J, _ = _run(robot, qf, True, False)
    return T.reshape(*batch, 4, 4), J.reshape(*batch, 6, robot.nq)


def frames(robot: Robot, q: ArrayLike) -> FloatArray:
    """World poses (..., n+1, 4, 4) of the base frame and the link frames 1..n (m).

    Index 0 is the base (DH frame 0 = the spec's ``base``, identity for URDF robots); index i is
    ``robot.link_frames[i-1]`` (DH frame i for DH robots, the child-link body frame for URDF).
    """
    qf, batch = _as_q(robot, q)
    _, _, F = _run(robot, qf, False, True)
    return F.reshape(*batch, robot.nq + 1, 4, 4)


# ---------------------------------------------------------------------------------------------
# Pinocchio reference (per-sample loops; slow, for tests and benchmarks)
# ---------------------------------------------------------------------------------------------


def fk_reference(robot: Robot, q: ArrayLike) -> FloatArray:
    """Same as :func:`fk`, one ``pinocchio.framesForwardKinematics`` call per sample."""
    qf, batch = _as_q(robot, q)
    model, data = robot.model, robot.data()
    out = np.empty((qf.shape[0], 4, 4))
    for s in range(qf.shape[0]):
        pin.framesForwardKinematics(model, data, qf[s])
        out[s] = data.oMf[robot.tool_frame].homogeneous
    return out.reshape(*batch, 4, 4)


def jacobian_reference(robot: Robot, q: ArrayLike) -> FloatArray:
    """Same as :func:`jacobian`, by ``pinocchio.computeFrameJacobian`` per sample."""
    qf, batch = _as_q(robot, q)
    model, data = robot.model, robot.data()
    out = np.empty((qf.shape[0], 6, robot.nq))
    rf = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    for s in range(qf.shape[0]):
        pin.framesForwardKinematics(model, data, qf[s])
        out[s] = pin.computeFrameJacobian(model, data, qf[s], robot.tool_frame, rf)
    return out.reshape(*batch, 6, robot.nq)


def frames_reference(robot: Robot, q: ArrayLike) -> FloatArray:
    """Same as :func:`frames`, by ``pinocchio.framesForwardKinematics`` per sample."""
    qf, batch = _as_q(robot, q)
    model, data = robot.model, robot.data()
    _, _, base = _link_placements(robot)
    out = np.empty((qf.shape[0], robot.nq + 1, 4, 4))
    for s in range(qf.shape[0]):
        pin.framesForwardKinematics(model, data, qf[s])
        out[s, 0] = base
        for i, fid in enumerate(robot.link_frames):
            out[s, i + 1] = data.oMf[fid].homogeneous
    return out.reshape(*batch, robot.nq + 1, 4, 4)


# ---------------------------------------------------------------------------------------------
# manipulability
# ---------------------------------------------------------------------------------------------

Rows = Literal["all", "translational", "rotational"]


def manipulability(robot: Robot, q: ArrayLike, rows: Rows | None = None) -> FloatArray:
    """Yoshikawa's manipulability (..., ) of the tool Jacobian rows selected by ``rows``.

    ``w = sqrt(det(J_r J_rᵀ))`` with ``J_r`` the selected rows of :func:`jacobian` (m rows × n
    joints). ``rows``: ``"all"`` (6 rows), ``"translational"`` (``v``, 3 rows, unit m³ for a
    revolute 3-row measure) or ``"rotational"`` (``ω``, 3 rows). Default: ``"all"`` for n ≥ 6,
    ``"translational"`` for n < 6 (a 5-DOF arm or a leg cannot span all six twist directions,
    and the tool position is what such robots are asked to place). When n < m (e.g. all six
    rows of the 5-DOF arm, or a planar 2-DOF leg: 3 rows × 2 joints) ``det(J_r J_rᵀ)`` is
    identically 0, so the measure is the product of the n singular values,
    ``sqrt(det(J_rᵀ J_r))`` — the n-dimensional volume of the manipulability ellipsoid (0 only at
    a singularity). For n = m both forms are ``|det J_r|``.
    """
    n = robot.nq
    if rows is None:
        rows = "all" if n >= 6 else "translational"
    if rows == "all":
        sl = slice(0, 6)
    elif rows == "translational":
        sl = slice(0, 3)
    elif rows == "rotational":
        sl = slice(3, 6)
    else:
        raise ValueError(f"rows: must be 'all', 'translational' or 'rotational', got {rows!r}")
    J = jacobian(robot, q)[..., sl, :]
    m = J.shape[-2]
    Jt = np.swapaxes(J, -1, -2)
    G = J @ Jt if m <= n else Jt @ J
    return np.sqrt(np.clip(np.linalg.det(G), 0.0, None))


def _spherical_wrist_params(robot: Robot) -> tuple[float, float, float, float, FloatArray]:
    """(a1, a2, a3, d4, offset) of a PUMA-type 6R arm with a spherical wrist; ValueError else."""
    spec = robot.spec
    if not isinstance(spec, DHRobotSpec) or spec.convention != "standard":
        raise ValueError("robot: manipulability_split needs a standard-DH robot spec")
    j = spec.joints
    if len(j) != 6 or any(x.type != "revolute" for x in j):
        raise ValueError("robot: manipulability_split needs a 6R arm (6 revolute joints)")
    half = math.pi / 2
    alphas = (half, 0.0, -half, half, -half)
    tol = 1e-9
    if any(abs(x.alpha - al) > tol for x, al in zip(j[:5], alphas, strict=False)):
        raise ValueError(
            "robot: manipulability_split needs the PUMA-type DH twists "
            "α1..α5 = (90°, 0, −90°, 90°, −90°) of seed 001"
        )
    if abs(j[3].a) > tol or abs(j[4].a) > tol or abs(j[4].d) > tol:
        raise ValueError("robot: not a spherical wrist (needs a4 = a5 = d5 = 0)")
    offset = np.array([x.offset for x in j])
    return j[0].a, j[1].a, j[2].a, j[3].d, offset


def manipulability_split(robot: Robot, q: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Seed 001 eqs (6)–(8): ``(w, w_A, w_W)``, each (...,), for a spherical-wrist 6R arm.

    With ``θ_i = q_i + offset_i`` and the standard-DH lengths of the PUMA-type arm::

        w_A = a2 (d4 cos θ3 + a3 sin θ3) (a1 + a3 cos(θ2+θ3) − d4 sin(θ2+θ3) + a2 cos θ2)   (7)
        w_W = sin θ5                                                                      (8)
        w   = w_A · w_W                                                                   (6)

    The paper writes them signed; here all three are returned as absolute values (a measure is
    ≥ 0): ``w_A = |eq 7|`` (m³) is |det| of the 3×3 Jacobian of the wrist-centre position w.r.t.
    θ1..θ3 (Yoshikawa's translational manipulability of the arm), ``w_W = |sin θ5|`` that of the
    wrist's three unit axes, and ``w = w_A·w_W`` equals Yoshikawa's ``sqrt(det(J Jᵀ)) = |det J|``
    of the full 6×6 Jacobian at any tool point (moving the reference point or rotating the axes
    multiplies J by a matrix of determinant ±1). Raises ``ValueError`` unless the robot is a
    standard-DH 6R arm with α1..α5 = (90°, 0, −90°, 90°, −90°) and a4 = a5 = d5 = 0.
    """
    a1, a2, a3, d4, offset = _spherical_wrist_params(robot)
    qa = np.asarray(q, dtype=float)
    if qa.ndim == 0 or qa.shape[-1] != 6:
        raise ValueError(f"q: last axis must have length 6, got shape {qa.shape}")
    th = qa + offset
    t2, t3, t5 = th[..., 1], th[..., 2], th[..., 4]
    t23 = t2 + t3
    w_A = np.abs(
        a2
        * (d4 * np.cos(t3) + a3 * np.sin(t3))
        * (a1 + a3 * np.cos(t23) - d4 * np.sin(t23) + a2 * np.cos(t2))
    )
    w_W = np.abs(np.sin(t5))
    return w_A * w_W, w_A, w_W


# ---------------------------------------------------------------------------------------------
# pose errors and angle wrapping
# ---------------------------------------------------------------------------------------------


def log3(Rm: ArrayLike) -> FloatArray:
    """Rotation vector (..., 3) (rad) of rotation matrices (..., 3, 3): ``exp([ω]×) = R``.

    Robust at 0 and near π (the axis then comes from the symmetric part ``(R + I)/2``).
    """
    Rm = np.asarray(Rm, dtype=float)
    tr = Rm[..., 0, 0] + Rm[..., 1, 1] + Rm[..., 2, 2]
    vee = np.stack(
        [
            Rm[..., 2, 1] - Rm[..., 1, 2],
            Rm[..., 0, 2] - Rm[..., 2, 0],
            Rm[..., 1, 0] - Rm[..., 0, 1],
        ],
        axis=-1,
    )  # = 2 sin θ · axis
    sin_t = 0.5 * np.linalg.norm(vee, axis=-1)
    cos_t = 0.5 * (tr - 1.0)
    theta = np.arctan2(sin_t, cos_t)  # accurate at 0 and at π, unlike arccos
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = np.where(theta < 1e-8, 0.5 + theta**2 / 12.0, 0.5 * theta / sin_t)
    out = factor[..., None] * vee
    near_pi = theta > math.pi - 1e-3
    if np.any(near_pi):
        # axis from the symmetric part: (R + Rᵀ)/2 = cos θ I + (1 − cos θ) a aᵀ
        Rn = Rm[near_pi]
        c = cos_t[near_pi]
        S = (0.5 * (Rn + np.swapaxes(Rn, -1, -2)) - c[:, None, None] * np.eye(3)) / (1.0 - c)[
            :, None, None
        ]
        diag = np.stack([S[:, 0, 0], S[:, 1, 1], S[:, 2, 2]], axis=-1)
        k = np.argmax(diag, axis=-1)
        idx = np.arange(Rn.shape[0])
        a = S[idx, k, :] / np.sqrt(np.clip(diag[idx, k], 1e-300, None))[:, None]
        a /= np.linalg.norm(a, axis=-1, keepdims=True)
        sign = np.where(np.sum(a * vee[near_pi], axis=-1) < 0.0, -1.0, 1.0)
        out[near_pi] = (sign * theta[near_pi])[:, None] * a
    return out


def pose_error(T: ArrayLike, T_target: ArrayLike) -> FloatArray:
    """World-aligned error (..., 6) that takes pose ``T`` to ``T_target``: ``[Δp; Δω]``.

    ``Δp = p_target − p`` (m); ``Δω = log3(R_target Rᵀ)`` (rad), a world-frame rotation vector —
    so that for a small joint step ``J Δq ≈ error`` with :func:`jacobian`'s convention.
    """
    T = np.asarray(T, dtype=float)
    T_target = np.asarray(T_target, dtype=float)
    dp = T_target[..., :3, 3] - T[..., :3, 3]
    Rerr = T_target[..., :3, :3] @ np.swapaxes(T[..., :3, :3], -1, -2)
    return np.concatenate([dp, log3(Rerr)], axis=-1)


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


# ---------------------------------------------------------------------------------------------
# inverse kinematics
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class IKResult:
    """Inverse-kinematics result for targets of batch shape ``S`` (e.g. (B,) or (B, K)).

    ``q`` (*S, n): joint values (rad / m), NaN where ``reachable`` is False.
    ``reachable`` (*S,): a solution exists (closed form) / DLS converged to ``tol``.
    ``within_limits`` (*S,): ``q`` lies inside [q_min, q_max] (False where unreachable).
    ``branch`` (*S,) int: index into ``branch_names`` of the returned solution, −1 if none.
    ``error`` (*S,): residual ``|pose_error(FK(q), target)|`` over the rows the solver matched
    (position in m, plus orientation in rad when the target has one); NaN where unreachable.
    ``iterations`` (*S,) int: DLS iterations (0 for a closed form).
    ``method``: ``"puma560"``, ``"arm5_down"``, ``"leg3"``, ``"leg2"`` or ``"dls"``.
    """

    q: FloatArray
    reachable: BoolArray
    within_limits: BoolArray
    branch: IntArray
    error: FloatArray
    iterations: IntArray
    branch_names: tuple[str, ...]
    method: str

    @property
    def ok(self) -> BoolArray:
        """(*S,) reachable and within the joint limits."""
        return self.reachable & self.within_limits

    @property
    def converged(self) -> BoolArray:
        """(*S,) alias of ``reachable`` (the DLS convergence flag)."""
        return self.reachable


def _as_target(target: ArrayLike) -> tuple[FloatArray, bool, tuple[int, ...]]:
    """Target poses (..., 4, 4) or positions (..., 3) → (flat array, is_pose, batch shape)."""
    t = np.asarray(target, dtype=float)
    if t.ndim >= 2 and t.shape[-2:] == (4, 4):
        if not np.all(np.isfinite(t)):
            raise ValueError("target: poses must be finite")
        return np.ascontiguousarray(t.reshape(-1, 4, 4)), True, t.shape[:-2]
    if t.ndim >= 1 and t.shape[-1] == 3:
        if not np.all(np.isfinite(t)):
            raise ValueError("target: positions must be finite")
        return np.ascontiguousarray(t.reshape(-1, 3)), False, t.shape[:-1]
    raise ValueError(f"target: expected poses (..., 4, 4) or positions (..., 3), got {t.shape}")


def _select_branch(
    sols: FloatArray,
    reach: BoolArray,
    within: BoolArray,
    branch: int | str | None,
    names: tuple[str, ...],
    q_ref: FloatArray,
) -> tuple[FloatArray, BoolArray, BoolArray, IntArray]:
    """Pick one solution per sample from (N, k, n) candidates."""
    N, k, n = sols.shape
    if branch is not None:
        if isinstance(branch, str):
            if branch not in names:
                raise ValueError(f"branch: unknown {branch!r}; one of {names}")
            b = names.index(branch)
        else:
            b = int(branch)
            if not 0 <= b < k:
                raise ValueError(f"branch: must be in 0..{k - 1}, got {branch}")
        idx = np.full(N, b, dtype=np.int64)
    else:
        # prefer reachable & within limits, then reachable; then the nearest q_ref (L1)
        d = np.sum(np.abs(sols - q_ref[:, None, :]), axis=-1)
        d = np.where(np.isnan(d), np.inf, d)
        score = d + np.where(within, 0.0, 1e6) + np.where(reach, 0.0, 1e12)
        idx = np.argmin(score, axis=-1).astype(np.int64)
    rows = np.arange(N)
    q = sols[rows, idx]
    r = reach[rows, idx]
    w = within[rows, idx] & r
    q = np.where(r[:, None], q, np.nan)
    idx = np.where(r, idx, -1)
    return q, r, w, idx


def _ref_config(robot: Robot, q_ref: ArrayLike | None, batch: tuple[int, ...]) -> FloatArray:
    """``q_ref`` (default ``robot.home``) broadcast to the targets' batch, flattened (N, n)."""
    n = robot.nq
    a = robot.home if q_ref is None else np.asarray(q_ref, dtype=float)
    if a.shape[-1:] != (n,):
        raise ValueError(f"q_ref: last axis must have length nq = {n}, got {a.shape}")
    try:
        return np.array(np.broadcast_to(a, (*batch, n)).reshape(-1, n), dtype=float)
    except ValueError:
        raise ValueError(
            f"q_ref: shape {a.shape} does not broadcast to the targets' batch {(*batch, n)}"
        ) from None


def _residual(robot: Robot, q: FloatArray, target: FloatArray, is_pose: bool) -> FloatArray:
    """|pose error| (N,) of FK(q) against poses (N,4,4) or positions (N,3); NaN where q is NaN."""
    ok = ~np.any(np.isnan(q), axis=-1)
    out = np.full(q.shape[0], np.nan)
    if np.any(ok):
        T = fk(robot, q[ok])
        if is_pose:
            e = pose_error(T, target[ok])
        else:
            e = target[ok] - T[:, :3, 3]
        out[ok] = np.linalg.norm(e, axis=-1)
    return out


def ik(
    robot: Robot,
    target: ArrayLike,
    *,
    branch: int | str | None = None,
    q_ref: ArrayLike | None = None,
    yaw: ArrayLike | None = None,
    **dls_options: float | int | bool,
) -> IKResult:
    """Inverse kinematics of ``target`` — poses (..., 4, 4) or tool positions (..., 3), world, m.

    Dispatches on ``robot.ik_family``:

    - ``"puma560"`` (poses): all 8 closed-form branches (:mod:`legcore.ik.puma560`);
    - ``"arm5_down"`` (positions, or poses whose tool z axis points straight down): the 5-DOF arm
      of seed 004 with the tool pointing down; ``yaw`` (...,) rad is the heading of the tool x
      axis in the world xy plane (from the pose when one is given; joint 5 = 0 when neither);
      a pose that is not pointing down is reported unreachable;
    - ``"leg3"`` / ``"leg2"`` (positions; poses use their translation): the leg closed forms;
    - ``"dls"`` or None: :func:`ik_dls` from ``q_ref`` (default ``robot.home``), with
      ``dls_options`` passed on.

    Closed forms return the branch ``branch`` (index or name, see ``result.branch_names``) or,
    when None, per sample the reachable solution inside the joint limits nearest ``q_ref``
    (default ``robot.home``) in the L1 joint distance, falling back to one outside the limits.
    Revolute angles are shifted by 2π into the limits where possible (:func:`wrap_to_limits`).
    """
    family = robot.ik_family
    if family in (None, "dls"):
        if branch is not None or yaw is not None:
            raise ValueError("branch/yaw: only meaningful for closed-form IK families")
        q0 = robot.home if q_ref is None else q_ref
        return ik_dls(robot, target, q0, **dls_options)  # type: ignore[arg-type]
    if dls_options:
        raise ValueError(f"{sorted(dls_options)}: options of ik_dls, not of {family!r} IK")
    tf, is_pose, batch = _as_target(target)
    N = tf.shape[0]
    ref = _ref_config(robot, q_ref, batch)
    revolute = ~robot.chain.prismatic
    if family == "puma560":
        from legcore.ik.puma560 import BRANCH_NAMES, puma560_geometry, puma560_ik

        if not is_pose:
            raise ValueError("target: the PUMA 560 IK needs poses (..., 4, 4), not positions")
        if yaw is not None:
            raise ValueError("yaw: not used by the PUMA 560 IK (give full poses)")
        sol = puma560_ik(tf, puma560_geometry(robot.spec), robot.q_min, robot.q_max, ref[:, None])
        names: tuple[str, ...] = BRANCH_NAMES
        sols, reach, within = sol.q, sol.reachable, sol.within_limits
    elif family == "arm5_down":
        from legcore.ik.arm5 import BRANCH_NAMES as ARM5_NAMES
        from legcore.ik.arm5 import arm5_geometry, arm5_ik_down

        geo = arm5_geometry(robot.spec)
        if is_pose:
            if yaw is not None:
                raise ValueError("yaw: give it only with positions; poses carry their own yaw")
            p = tf[:, :3, 3]
            down = (np.hypot(tf[:, 0, 2], tf[:, 1, 2]) < 1e-9) & (tf[:, 2, 2] < 0.0)
            yaw_arr: FloatArray | None = np.arctan2(tf[:, 1, 0], tf[:, 0, 0])
        else:
            p = tf
            down = np.ones(N, dtype=bool)
            yaw_arr = None
            if yaw is not None:
                yaw_arr = np.broadcast_to(np.asarray(yaw, dtype=float), batch).reshape(-1)
        sol5 = arm5_ik_down(p, geo, yaw_arr, robot.q_min, robot.q_max, ref[:, None])
        names = ARM5_NAMES
        sols, reach, within = sol5.q, sol5.reachable & down[:, None], sol5.within_limits
        within = within & down[:, None]
    elif family in ("leg3", "leg2"):
        if yaw is not None:
            raise ValueError(f"yaw: not used by the {family!r} IK")
        p = tf[:, :3, 3] if is_pose else tf
        sols, reach, names = _leg_ik(robot, family, p)
        sols = wrap_to_limits(sols, robot.q_min, robot.q_max, ref[:, None], revolute)
        within = reach & robot.within_limits(sols)
        is_pose = False  # legs match positions only
        tf = p
    else:  # pragma: no cover - spec validation restricts the families
        raise ValueError(f"robot: unknown ik_family {family!r}")
    q, r, w, idx = _select_branch(sols, reach, within, branch, names, ref)
    err = _residual(robot, q, tf, is_pose)
    return IKResult(
        q=q.reshape(*batch, robot.nq),
        reachable=r.reshape(batch),
        within_limits=w.reshape(batch),
        branch=idx.reshape(batch),
        error=err.reshape(batch),
        iterations=np.zeros(batch, dtype=np.int64),
        branch_names=names,
        method=family,
    )


def _leg_ik(
    robot: Robot, family: str, p: FloatArray
) -> tuple[FloatArray, BoolArray, tuple[str, ...]]:
    """Both knee branches (N, 2, n) of the leg closed forms in ``legcore.ik.leg3`` / ``leg2``.

    The robot must be the standard-DH chain those modules solve (``d = 0``; α = (90°, 0, 0) for
    ``leg3``, (0, 0) for ``leg2``; link lengths = the spec's ``a``; no tool offset). Targets are
    mapped into the leg base frame with the spec's ``base``; DH offsets are subtracted.
    """
    spec = robot.spec
    if not isinstance(spec, DHRobotSpec) or spec.convention != "standard":
        raise ValueError(f"robot: the {family!r} closed form needs a standard-DH robot spec")
    j = spec.joints
    alphas = (math.pi / 2, 0.0, 0.0) if family == "leg3" else (0.0, 0.0)
    if len(j) != len(alphas) or any(x.type != "revolute" for x in j):
        raise ValueError(f"robot: the {family!r} closed form needs {len(alphas)} revolute joints")
    for i, (x, al) in enumerate(zip(j, alphas, strict=True)):
        if abs(x.alpha - al) > 1e-9 or abs(x.d) > 1e-12:
            raise ValueError(
                f"spec.joints.{i}: the {family!r} closed form needs d = 0 and "
                f"α = {tuple(round(math.degrees(a)) for a in alphas)}°"
            )
    if spec.tool is not None and np.abs(np.asarray(spec.tool)[:3, 3]).max() > 1e-12:
        raise ValueError(f"spec.tool: the {family!r} closed form needs the tool at the foot")
    L = np.array([x.a for x in j])
    offset = np.array([x.offset for x in j])
    if spec.base is not None:
        base = np.asarray(spec.base, dtype=float)
        p = (p - base[:3, 3]) @ base[:3, :3]
    if family == "leg3":
        from legcore.ik.leg3 import KNEE_DOWN, KNEE_UP, leg3_ik

        branches = ((KNEE_UP, "knee-up"), (KNEE_DOWN, "knee-down"))
        solve: Callable[..., tuple[FloatArray, BoolArray]] = leg3_ik
    else:
        from legcore.ik.leg2 import ELBOW_BACK, KNEE_FORWARD, leg2_ik

        branches = ((ELBOW_BACK, "elbow-back"), (KNEE_FORWARD, "knee-forward"))
        solve = leg2_ik
    qs, oks = [], []
    lo, hi = robot.q_min + offset, robot.q_max + offset
    for b, _ in branches:
        # the solvers pick, per branch, a yaw family inside the limits when one exists
        q_lim, ok_lim = solve(p, L, b, lo, hi)
        q_free, ok_free = solve(p, L, b)
        qs.append(np.where(ok_lim[:, None], q_lim, q_free) - offset)
        oks.append(ok_lim | ok_free)
    return np.stack(qs, axis=1), np.stack(oks, axis=1), tuple(name for _, name in branches)


def ik_dls(
    robot: Robot,
    target: ArrayLike,
    q0: ArrayLike,
    *,
    orientation: bool | None = None,
    tol: float = 1e-10,
    max_iter: int = 200,
    damping: float = 1e-2,
    damping_min: float = 1e-9,
    damping_max: float = 1e3,
    rot_weight: float = 1.0,
) -> IKResult:
    """Damped-least-squares (Levenberg–Marquardt) IK on the robot's kinematic model.

    ``target``: poses (..., 4, 4) or tool positions (..., 3) in the world frame (m).
    ``q0``: start configuration(s), broadcastable to (..., n).
    ``orientation``: match the orientation too (rows ``[v; ω]`` of the Jacobian); default True
    for pose targets on robots with n ≥ 6, False otherwise (position only, rows ``v``).

    All samples iterate together; each iteration computes the tool pose and Jacobian of the whole
    active batch with the numba fast path, proposes ``Δq = Jᵀ (J Jᵀ + λ² I)⁻¹ e`` per sample
    (``e`` = :func:`pose_error`, orientation rows scaled by ``rot_weight`` m/rad), accepts it if
    the error decreases (λ ← λ/3, down to ``damping_min``) and otherwise rejects it (λ ← 3λ).
    A sample stops when ``|e| < tol`` (converged) or λ exceeds ``damping_max`` / ``max_iter`` is
    reached (not converged: an unreachable target). Joint limits are not enforced: angles are
    shifted by 2π into the limits where possible and ``within_limits`` reports the rest.
    Returns :class:`IKResult` with ``reachable`` = converged, ``q`` NaN where not converged and
    ``error`` the unweighted residual of the matched rows.
    """
    tf, is_pose, batch = _as_target(target)
    N = tf.shape[0]
    n = robot.nq
    if orientation is None:
        orientation = is_pose and n >= 6
    if orientation and not is_pose:
        raise ValueError("orientation: needs pose targets (..., 4, 4)")
    for name, v in (("tol", tol), ("damping", damping), ("rot_weight", rot_weight)):
        if not (math.isfinite(v) and v > 0.0):
            raise ValueError(f"{name}: must be a finite value > 0, got {v!r}")
    if int(max_iter) < 1:
        raise ValueError(f"max_iter: must be >= 1, got {max_iter}")
    q0a = np.asarray(q0, dtype=float)
    if q0a.shape[-1:] != (n,) or not np.all(np.isfinite(q0a)):
        raise ValueError(f"q0: must be finite with last axis nq = {n}, got shape {q0a.shape}")
    try:
        q = np.array(np.broadcast_to(q0a, (*batch, n)).reshape(N, n))
    except ValueError:
        raise ValueError(
            f"q0: shape {q0a.shape} does not broadcast to the targets' batch {(*batch, n)}"
        ) from None
    rows = slice(0, 6) if orientation else slice(0, 3)
    m = 6 if orientation else 3
    wvec = np.ones(m)
    if orientation:
        wvec[3:] = rot_weight

    def err_of(T: FloatArray, tgt: FloatArray) -> FloatArray:
        if is_pose:
            e = pose_error(T, tgt)[:, rows]
        else:
            e = tgt - T[:, :3, 3]
        return e * wvec

    lam = np.full(N, float(damping))
    converged = np.zeros(N, dtype=bool)
    iters = np.zeros(N, dtype=np.int64)
    active = np.ones(N, dtype=bool)
    T, J = fk_jacobian(robot, q)
    e = err_of(T, tf)
    enorm = np.linalg.norm(e, axis=-1)
    eye = np.eye(m)
    for _ in range(int(max_iter)):
        converged |= active & (enorm < tol)
        active &= ~converged & (lam <= damping_max)
        if not np.any(active):
            break
        ia = np.flatnonzero(active)
        Ja = J[ia][:, rows, :] * wvec[:, None]
        A = Ja @ np.swapaxes(Ja, -1, -2) + (lam[ia] ** 2)[:, None, None] * eye
        y = np.linalg.solve(A, e[ia][..., None])
        dq = (np.swapaxes(Ja, -1, -2) @ y)[..., 0]
        q_try = q[ia] + dq
        T_try, J_try = fk_jacobian(robot, q_try)
        e_try = err_of(T_try, tf[ia])
        n_try = np.linalg.norm(e_try, axis=-1)
        better = n_try < enorm[ia]
        acc = ia[better]
        q[acc] = q_try[better]
        J[acc] = J_try[better]
        e[acc] = e_try[better]
        enorm[acc] = n_try[better]
        lam[acc] = np.maximum(lam[acc] / 3.0, damping_min)
        rej = ia[~better]
        lam[rej] *= 3.0
        iters[ia] += 1
    converged |= enorm < tol
    q_out = wrap_to_limits(q, robot.q_min, robot.q_max, None, ~robot.chain.prismatic)
    q_out = np.where(converged[:, None], q_out, np.nan)
    within = converged & robot.within_limits(np.where(converged[:, None], q_out, 0.0))
    if orientation:
        error = _residual(robot, q_out, tf, True)
    else:
        error = _residual(robot, q_out, tf[:, :3, 3] if is_pose else tf, False)
    return IKResult(
        q=q_out.reshape(*batch, n),
        reachable=converged.reshape(batch),
        within_limits=within.reshape(batch),
        branch=np.where(converged, 0, -1).astype(np.int64).reshape(batch),
        error=error.reshape(batch),
        iterations=iters.reshape(batch),
        branch_names=("dls",),
        method="dls",
    )
