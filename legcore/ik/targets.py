"""IK tasks, their targets and the result of :func:`legcore.ik.solve`.

A task says what the tool must match:

- ``"position"``: the tool point; targets ``(..., 3)`` (m) or poses ``(..., 4, 4)`` (their
  translation);
- ``"axis"``: the tool point and the direction of the tool z axis (the spin about it is free);
  targets ``(..., 6)`` = ``[p (m), axis]`` (the axis need not be unit) or poses ``(..., 4, 4)``
  (their translation and z column);
- ``"pose"``: the tool point and orientation; targets poses ``(..., 4, 4)``.

All in the world frame. The leading shape ``S`` of the targets is the batch; with ``path=True``
its last axis is the path (samples in order) and the axes before it index independent paths.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.ik.newton import TASK_AXIS, TASK_POSE, TASK_POSITION
from legcore.ik.result import IKResult
from legcore.transforms import log3

__all__ = ["TASK_ROWS", "IKSolution", "Task", "parse_targets", "task_errors"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

Task = Literal["position", "axis", "pose"]
TASK_ROWS: dict[str, int] = {"position": TASK_POSITION, "axis": TASK_AXIS, "pose": TASK_POSE}


@dataclass(frozen=True, eq=False)
class IKSolution(IKResult):
    """:class:`~legcore.ik.result.IKResult` of :func:`legcore.ik.solve`, plus path information.

    Here ``reachable`` means *solved inside the joint limits* to the tolerance (so
    ``within_limits`` equals it): a target that is only reachable outside the limits is
    unreachable, never returned outside them. ``q`` is NaN where unreachable.

    ``flip`` (*S,) bool: along a path, True at a sample whose joints jump from the previous
    reachable sample by more than ``flip_tol`` in some joint (a change of IK branch: forced when
    the continuous branch left the limits or the workspace); always False without a path.
    ``position_error`` (*S,) m and ``rotation_error`` (*S,) rad (angle between the tool axes for
    ``"axis"``, 0 for ``"position"``) of FK(q) against the targets; NaN where unreachable.
    ``task``: ``"position"``, ``"axis"`` or ``"pose"``.
    """

    flip: BoolArray
    position_error: FloatArray
    rotation_error: FloatArray
    task: str


def parse_targets(task: str, targets: ArrayLike) -> tuple[FloatArray, FloatArray, tuple[int, ...]]:
    """Targets of ``task`` → (positions (N, 3) m, rotations (N, 3, 3), batch shape S).

    For ``"axis"`` the rotation's column 2 is the unit target axis (columns 0 and 1 complete it
    to a rotation); for ``"position"`` the rotations are identities (unused). Raises
    ``ValueError`` naming ``task`` or ``targets``.
    """
    if task not in TASK_ROWS:
        raise ValueError(f"task: must be one of {sorted(TASK_ROWS)}, got {task!r}")
    t = np.asarray(targets, dtype=float)
    is_pose = t.ndim >= 2 and t.shape[-2:] == (4, 4)
    flat: FloatArray
    if is_pose:
        batch = t.shape[:-2]
        flat = t.reshape(-1, 4, 4)
    elif task == "position" and t.ndim >= 1 and t.shape[-1] == 3:
        batch = t.shape[:-1]
        flat = t.reshape(-1, 3)
    elif task == "axis" and t.ndim >= 1 and t.shape[-1] == 6:
        batch = t.shape[:-1]
        flat = t.reshape(-1, 6)
    else:
        want = {"position": "(..., 3)", "axis": "(..., 6) = [p, axis]", "pose": ""}[task]
        alt = f"{want} or " if want else ""
        raise ValueError(f"targets: task {task!r} needs {alt}poses (..., 4, 4), got {t.shape}")
    if not np.all(np.isfinite(flat)):
        raise ValueError("targets: must be finite")
    N = flat.shape[0]
    if is_pose:
        p = flat[:, :3, 3].copy()
        if task == "pose":
            Rt = np.ascontiguousarray(flat[:, :3, :3])
            dev, det_min = _rotation_defect(Rt)
            if not (dev <= 1e-6 and det_min >= 0.0):
                raise ValueError("targets: the 3×3 blocks of the poses must be rotations")
            return p, Rt, batch
        a = flat[:, :3, 2]
    elif task == "axis":
        p = flat[:, :3].copy()
        a = flat[:, 3:]
    else:
        return flat.copy(), np.broadcast_to(np.eye(3), (N, 3, 3)).copy(), batch
    if task == "position":
        return p, np.broadcast_to(np.eye(3), (N, 3, 3)).copy(), batch
    norm = np.linalg.norm(a, axis=-1)
    if np.any(norm < 1e-12):
        raise ValueError("targets: the tool axis must be a non-zero vector")
    Rt = _frame_with_z(a / norm[:, None])
    return p, Rt, batch


@numba.njit(cache=True, nogil=True)
def _rotation_defect(Rt: FloatArray) -> tuple[float, float]:  # pragma: no cover - compiled
    """(max |R Rᵀ − I| over the element, smallest det R) of rotations ``Rt`` (N, 3, 3)."""
    dev = 0.0
    det_min = math.inf
    for k in range(Rt.shape[0]):
        for a in range(3):
            for b in range(a, 3):
                s = Rt[k, a, 0] * Rt[k, b, 0] + Rt[k, a, 1] * Rt[k, b, 1]
                s += Rt[k, a, 2] * Rt[k, b, 2]
                dev = max(dev, abs(s - 1.0) if a == b else abs(s))
        d = (
            Rt[k, 0, 0] * (Rt[k, 1, 1] * Rt[k, 2, 2] - Rt[k, 2, 1] * Rt[k, 1, 2])
            - Rt[k, 1, 0] * (Rt[k, 0, 1] * Rt[k, 2, 2] - Rt[k, 2, 1] * Rt[k, 0, 2])
            + Rt[k, 2, 0] * (Rt[k, 0, 1] * Rt[k, 1, 2] - Rt[k, 1, 1] * Rt[k, 0, 2])
        )
        det_min = min(det_min, d)
    return dev, det_min


def _frame_with_z(z: FloatArray) -> FloatArray:
    """Rotations (N, 3, 3) whose column 2 is the unit vector ``z`` (N, 3)."""
    helper = np.where(np.abs(z[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-1)


def task_errors(task: str, T: FloatArray, p: FloatArray, Rt: FloatArray) -> tuple[
    FloatArray, FloatArray
]:
    """(position error (N,) m, orientation error (N,) rad) of tool poses ``T`` (N, 4, 4)."""
    ep = np.linalg.norm(p - T[:, :3, 3], axis=-1)
    if task == "position":
        return ep, np.zeros_like(ep)
    if task == "axis":
        z, a = T[:, :3, 2], Rt[:, :, 2]
        er = np.arctan2(np.linalg.norm(np.cross(z, a), axis=-1), np.sum(z * a, axis=-1))
        return ep, er
    er = np.linalg.norm(log3(Rt @ np.swapaxes(T[:, :3, :3], -1, -2)), axis=-1)
    return ep, er
