"""What an inverse-kinematics call returns (:class:`IKResult`), the target shapes it accepts
(poses (..., 4, 4) or tool positions (..., 3)) and the residual it reports."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.kinematics import fk
from legcore.robots.model import Robot
from legcore.transforms import pose_error

__all__ = ["IKResult"]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]


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
