"""Pinocchio reference of :mod:`legcore.kinematics`: per-sample loops (slow, for tests and
benchmarks) that the numba fast path is tested against (equal to ~1e-15)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from legcore.kinematics import _as_q, _link_placements
from legcore.robots.model import Robot

__all__ = ["fk_reference", "frames_reference", "jacobian_reference"]

FloatArray = NDArray[np.float64]


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
