"""Batched forward kinematics of serial chains: tool poses, Jacobians and link frames.

Conventions (see ``docs/kinematics.md``):

- Configurations ``q`` have shape ``(..., n)`` (rad for revolute, m for prismatic joints): one
  configuration ``(n,)``, a batch ``(B, n)`` or a batch of trajectories ``(B, K, n)``. Every
  result keeps the leading batch shape: ``fk`` → ``(..., 4, 4)``, ``jacobian`` → ``(..., 6, n)``.
- Poses ``T`` are 4×4 homogeneous transforms in the world frame (m).
- ``jacobian`` is the geometric Jacobian ``[v; ω]`` of the tool frame with ``v`` the linear
  velocity of the tool point (m/s per joint unit) and ``ω`` the angular velocity (rad/s per
  joint unit), both in world-aligned axes — Pinocchio's ``LOCAL_WORLD_ALIGNED`` at the tool.

Fast path: one numba kernel (:mod:`legcore.fk_kernel`) loops over the (flattened) batch on
:class:`~legcore.robots.Chain` arrays, which are taken from the Pinocchio model, so DH and URDF
robots share it. Positions only (no 4×4 poses): :func:`legcore.chain_points.chain_points`.

The rest of the kinematics lives next door, each module named after what it does:

- :mod:`legcore.kinematics_reference`: the per-sample Pinocchio loops the fast path is tested
  against (``fk_reference``, ``frames_reference``, ``jacobian_reference``; equal to ~1e-15);
- :mod:`legcore.manipulability`: Yoshikawa's measure and seed 001's split ``(w, w_A, w_W)``;
- :mod:`legcore.transforms`: rotation vectors and pose errors (``log3``, ``pose_error``);
- :mod:`legcore.joint_angles`: 2π wrapping of revolute angles into the joint limits;
- :mod:`legcore.ik.dispatch` (``ik``: closed forms by ``robot.ik_family``, else DLS),
  :mod:`legcore.ik.dls` (``ik_dls``) and :mod:`legcore.ik.result` (``IKResult``).
"""

from __future__ import annotations

import weakref

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.fk_kernel import _chain_kernel
from legcore.robots.model import Robot
from legcore.robots.spec import DHRobotSpec

__all__ = [
    "fk",
    "fk_jacobian",
    "frames",
    "jacobian",
]

FloatArray = NDArray[np.float64]


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
