"""Geometry of seed 002's tripod stance: the support triangle's rigid fit, mirrors, and the
exact workspace of body poses with the stance feet fixed.

Frames and units: SI (m, rad). The *world* frame is the body frame at stance ``t`` (before the
body moves): the robot walks along +y, x is lateral, z up, the feet are on the ground at
``z = z_foot < 0`` (seed 002: −6.8827 cm below the hips). A body pose at ``t+1`` is a planar
rigid motion ``(x, y, yaw)`` of the body at constant height: a point ``p_b`` of the body frame
is at ``Rz(yaw) p_b + (x, y, 0)`` in the world.

Everything is vectorised over leading batch axes; leg order is the decision vector's
``(front, back, middle)`` — for stance 1-3-5 of ``citedi_hexapod`` that is ``(L1, L3, L5)``, the
``p1, p3, p5`` of the paper's eqs (12)–(14).

- :func:`tripod_from_robot` — the stance legs (hips, chains, joint limits) of a tripod
  (:mod:`legcore.studies.hexapod_workspace.legs`, re-exported here).
- :func:`fit_body_motion` — the planar rigid motion that best carries the feet of ``t+1``
  (body frame) onto the fixed feet of ``t`` (2-D Kabsch): the body displacement a solution
  stands for, and the residual foot slip (zero only for a congruent triangle).
- :func:`mirror_front_back`, :func:`mirror_left_right` — the robot's two mirror symmetries.
- :func:`body_pose_ik`, :func:`pose_workspace` — beyond the paper: the exact set of body poses
  reachable with the three feet fixed, by the leg IK with θ1, θ2, θ3 free (the closed form of
  eqs 8–10 for seed 002's legs, :func:`legcore.ik.solve` for others).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.ik.leg3 import KNEE_DOWN, KNEE_UP
from legcore.studies.hexapod_workspace.legs import (
    OTHER_STANCE,
    STANCES,
    Tripod,
    is_mirror_symmetric,
    tripod_from_robot,
)
from legcore.studies.hexapod_workspace.pose_kernel import (
    ClosedFormTripod,
    closed_form_pose_ik,
    closed_form_reach,
)

__all__ = [
    "OTHER_STANCE",
    "STANCES",
    "PoseWorkspace",
    "Tripod",
    "body_pose_ik",
    "body_pose_ik_reference",
    "fit_body_motion",
    "is_mirror_symmetric",
    "mirror_front_back",
    "mirror_left_right",
    "pose_workspace",
    "tripod_from_robot",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

# ----------------------------------------------------------------------------------------------
# Rigid fit of the support triangle
# ----------------------------------------------------------------------------------------------


def fit_body_motion(
    P_world: ArrayLike, Q_body: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Planar rigid motion of the body that keeps the feet where they were (least squares).

    Finds ``(d, yaw)`` minimising ``Σ_k |Rz(yaw) Q_k + d − P_k|²`` (2-D Kabsch; no reflection).

    Args:
        P_world: fixed feet (..., 3, 2|3) in the world (= body frame at ``t``), m.
        Q_body: the same feet (..., 3, 2|3) in the body frame at ``t+1``, m.

    Returns:
        ``d`` (..., 2) body displacement (m), ``yaw`` (...,) body rotation (rad), ``slip``
        (..., 3) distance each foot would have to slide (m) — all zero iff the two triangles are
        congruent (same orientation).
    """
    P = np.asarray(P_world, dtype=float)[..., :2]
    Q = np.asarray(Q_body, dtype=float)[..., :2]
    pc, qc = P.mean(axis=-2), Q.mean(axis=-2)
    Pc, Qc = P - pc[..., None, :], Q - qc[..., None, :]
    sxx = np.sum(Qc[..., 0] * Pc[..., 0], axis=-1)
    syy = np.sum(Qc[..., 1] * Pc[..., 1], axis=-1)
    sxy = np.sum(Qc[..., 0] * Pc[..., 1], axis=-1)
    syx = np.sum(Qc[..., 1] * Pc[..., 0], axis=-1)
    yaw = np.arctan2(sxy - syx, sxx + syy)
    c, s = np.cos(yaw), np.sin(yaw)
    RQ = np.stack((c[..., None] * Q[..., 0] - s[..., None] * Q[..., 1],
                   s[..., None] * Q[..., 0] + c[..., None] * Q[..., 1]), axis=-1)
    d = pc - RQ.mean(axis=-2)
    slip = np.linalg.norm(RQ + d[..., None, :] - P, axis=-1)
    return d, yaw, slip


# ----------------------------------------------------------------------------------------------
# Mirrors
# ----------------------------------------------------------------------------------------------


def mirror_front_back(theta1: ArrayLike) -> FloatArray:
    """Mirror y → −y (across the body's lateral x axis), same tripod: front and back legs swap
    and every coxa angle changes sign, ``(θ_f, θ_b, θ_m) → (−θ_b, −θ_f, −θ_m)``.

    The body displacement ``(x, y, yaw)`` becomes ``(x, −y, −yaw)``: a step forward becomes a
    step backward. (Seed 002 builds its full workspace from "symmetric solutions"; its Table 2
    solution c is a with every θ1 negated but without the front/back swap — only a symmetry
    when θ_f = θ_b.)
    """
    t = np.asarray(theta1, dtype=float)
    return -t[..., [1, 0, 2]]


def mirror_left_right(theta1: ArrayLike) -> FloatArray:
    """Mirror x → −x (across the walking axis y): the other tripod (1-3-5 ↔ 4-6-2, in the order
    front, back, middle) with every coxa angle negated, ``θ → −θ``.

    Objectives are preserved exactly (front ↔ front, middle ↔ middle); the body displacement
    ``(x, y, yaw)`` becomes ``(−x, y, −yaw)``.
    """
    return -np.asarray(theta1, dtype=float)


def mirror_pose_front_back(pose: ArrayLike) -> FloatArray:
    """``(x, y, yaw) → (x, −y, −yaw)`` for poses (..., 3)."""
    p = np.asarray(pose, dtype=float)
    return p * np.array([1.0, -1.0, -1.0])


def mirror_pose_left_right(pose: ArrayLike) -> FloatArray:
    """``(x, y, yaw) → (−x, y, −yaw)`` for poses (..., 3)."""
    p = np.asarray(pose, dtype=float)
    return p * np.array([-1.0, 1.0, -1.0])


# ----------------------------------------------------------------------------------------------
# Exact body-pose workspace (beyond the paper)
# ----------------------------------------------------------------------------------------------


def body_pose_ik(
    tripod: Tripod,
    feet_world: ArrayLike,
    x: ArrayLike,
    y: ArrayLike,
    yaw: ArrayLike,
    knee: str = "up",
    q_ref: ArrayLike | None = None,
) -> tuple[FloatArray, BoolArray]:
    """Joint angles of the three stance legs for body poses ``(x, y, yaw)`` with the feet fixed.

    Args:
        tripod: the stance legs.
        feet_world: fixed feet (3, 3) in the world frame (m).
        x, y, yaw: body poses (broadcast together to a batch shape ``S``), m, m, rad.
        knee: ``"up"`` (θ3 ≤ 0, seed 002's posture), ``"down"`` or ``"either"`` (per leg, the
            knee-up solution when it is within the limits, else knee-down) — closed-form legs;
            other legs take the solution nearest ``q_ref``.
        q_ref: (3, 3) reference posture of the numerical IK (default: each leg's home).

    Returns:
        ``q`` (*S, 3, 3) rad (leg-major, NaN where a leg cannot reach) and ``reachable``
        (*S, 3) per leg: the closed form of eqs (8)–(10) inside the joint limits.

    Closed-form legs go through the compiled
    :func:`~legcore.studies.hexapod_workspace.pose_kernel.closed_form_pose_ik` (the same
    numbers as :func:`body_pose_ik_reference`, its numpy formulation); other legs through
    :func:`body_pose_ik_reference` (the numerical IK).
    """
    P = _feet(feet_world)
    _check_knee(knee)
    if not _compiled(tripod):
        return body_pose_ik_reference(tripod, P, x, y, yaw, knee, q_ref)
    x, y, yaw = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, yaw)))
    return closed_form_pose_ik(*_kernel_args(tripod, P, knee), x, y, yaw)


def _feet(feet_world: ArrayLike) -> FloatArray:
    P = np.asarray(feet_world, dtype=float)
    if P.shape != (3, 3):
        raise ValueError(f"feet_world: expected shape (3, 3), got {P.shape}")
    return P


def _check_knee(knee: str) -> None:
    if knee not in ("up", "down", "either"):
        raise ValueError(f"knee: expected 'up', 'down' or 'either', got {knee!r}")


def _compiled(tripod: Tripod) -> bool:
    """The tripod's legs take the closed form (``Tripod.ik``'s rule): the compiled path."""
    return tripod.closed_form or tripod.robots is None


def _kernel_args(tripod: Tripod, P: FloatArray, knee: str) -> ClosedFormTripod:
    """The closed-form tripod of :mod:`~legcore.studies.hexapod_workspace.pose_kernel`: legs,
    fixed feet ``P`` (3, 3) m, knee branch and whether to try the other one."""
    branch = KNEE_DOWN if knee == "down" else KNEE_UP
    return (tripod.hips, tripod.L, tripod.q_min, tripod.q_max, P, float(branch),
            knee == "either" and tripod.closed_form)


def body_pose_ik_reference(
    tripod: Tripod,
    feet_world: ArrayLike,
    x: ArrayLike,
    y: ArrayLike,
    yaw: ArrayLike,
    knee: str = "up",
    q_ref: ArrayLike | None = None,
) -> tuple[FloatArray, BoolArray]:
    """:func:`body_pose_ik` in numpy, through ``Tripod.to_leg_frames`` and ``Tripod.ik``: the
    path of numerical-IK legs, and the reference the compiled closed-form path is tested
    against (same arguments and results)."""
    P = _feet(feet_world)
    _check_knee(knee)
    x, y, yaw = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, yaw)))
    c, s = np.cos(yaw)[..., None], np.sin(yaw)[..., None]
    dx, dy = P[:, 0] - x[..., None], P[:, 1] - y[..., None]
    p_body = np.stack((c * dx + s * dy, -s * dx + c * dy, np.broadcast_to(P[:, 2], dx.shape)), -1)
    p_leg = tripod.to_leg_frames(p_body)
    branch = KNEE_DOWN if knee == "down" else KNEE_UP
    if q_ref is None:
        ref = np.stack([rb.home for rb in tripod.robots] if tripod.robots else [np.zeros(3)] * 3)
    else:
        ref = np.asarray(q_ref, dtype=float)
    q, ok = tripod.ik(p_leg, branch, ref)
    if knee == "either" and tripod.closed_form and not np.all(ok):
        q2, ok2 = tripod.ik(p_leg, KNEE_DOWN, ref)
        use = ~ok & ok2
        q = np.where(use[..., None], q2, q)
        ok = ok | ok2
    return q, ok


@dataclass(frozen=True, eq=False)
class PoseWorkspace:
    """Body poses on a grid, reachable with the three stance feet fixed.

    ``x`` (nx,), ``y`` (ny,) m and ``yaw`` (nyaw,) rad grid axes; ``reachable`` (nyaw, ny, nx)
    bool (all three legs inside their joint limits); ``feet_world`` (3, 3) the fixed feet;
    ``knee`` the branch rule; ``angles`` gives :attr:`q`.
    """

    x: FloatArray
    y: FloatArray
    yaw: FloatArray
    reachable: BoolArray
    feet_world: FloatArray
    knee: str
    angles: Callable[[], FloatArray] = field(repr=False)

    @cached_property
    def q(self) -> FloatArray:
        """(nyaw, ny, nx, 3, 3) joint angles, rad (NaN where not reachable); closed-form legs
        compute them on first access (the masks and areas do not need them)."""
        return self.angles()

    @property
    def cell_area(self) -> float:
        """Area of one (x, y) grid cell, m²."""
        dx = float(self.x[1] - self.x[0]) if self.x.size > 1 else 0.0
        dy = float(self.y[1] - self.y[0]) if self.y.size > 1 else 0.0
        return dx * dy

    def area(self) -> FloatArray:
        """(nyaw,) reachable area per yaw (m²): reachable cells × cell area."""
        return self.reachable.sum(axis=(1, 2)) * self.cell_area

    def extent(self) -> FloatArray:
        """(nyaw, 4) ``[x_min, x_max, y_min, y_max]`` of the reachable positions per yaw (m);
        NaN for a yaw with no reachable position."""
        X = np.broadcast_to(self.x, self.reachable.shape)
        Y = np.broadcast_to(self.y[:, None], self.reachable.shape)
        r = self.reachable
        with np.errstate(invalid="ignore"):
            out = np.stack([
                np.where(r, X, np.inf).min(axis=(1, 2)), np.where(r, X, -np.inf).max(axis=(1, 2)),
                np.where(r, Y, np.inf).min(axis=(1, 2)), np.where(r, Y, -np.inf).max(axis=(1, 2)),
            ], axis=-1)
        return np.where(np.isfinite(out), out, np.nan)

    def touches_edge(self) -> bool:
        """True when a reachable pose lies on the border of the (x, y) grid (grid too small)."""
        r = self.reachable
        return bool(r[:, 0, :].any() or r[:, -1, :].any() or r[:, :, 0].any() or r[:, :, -1].any())

    def summary(self, masks: bool = True) -> dict[str, Any]:
        """JSON-able: grid, per-yaw area (m²) / extent / count, and (optionally) the masks as
        one string of '0'/'1' per grid row (``masks[yaw][iy][ix]``)."""
        ext = self.extent()
        out: dict[str, Any] = {
            "frame": "world = body frame at stance t; pose = body displacement (x, y, yaw)",
            "knee": self.knee,
            "x": self.x.tolist(),
            "y": self.y.tolist(),
            "yaw": self.yaw.tolist(),
            "feet_world": self.feet_world.tolist(),
            "n_reachable": self.reachable.sum(axis=(1, 2)).tolist(),
            "area_m2": self.area().tolist(),
            "x_range": ext[:, :2].tolist(),
            "y_range": ext[:, 2:].tolist(),
            "touches_grid_edge": self.touches_edge(),
        }
        if masks:  # one '0'/'1' character per cell, cut into rows (no loop over cells)
            nyaw, ny, nx = self.reachable.shape
            text = (np.asarray(self.reachable, dtype=np.uint8) + 48).tobytes().decode("ascii")
            rows = [text[i:i + nx] for i in range(0, nyaw * ny * nx, nx)]
            out["masks"] = [rows[k * ny:(k + 1) * ny] for k in range(nyaw)]
        return out


def pose_workspace(
    tripod: Tripod,
    feet_world: ArrayLike,
    x: ArrayLike,
    y: ArrayLike,
    yaw: ArrayLike,
    knee: str = "up",
    q_ref: ArrayLike | None = None,
) -> PoseWorkspace:
    """The exact workspace of body poses on the grid ``yaw × y × x`` (one batched IK call per
    leg over the whole grid): a pose is reachable when all three legs reach their fixed feet
    inside the joint limits (θ1, θ2, θ3 all free)."""
    xs, ys, yaws = (np.asarray(v, dtype=float).ravel() for v in (x, y, yaw))
    for name, v in (("x", xs), ("y", ys), ("yaw", yaws)):
        if v.size == 0 or not np.all(np.isfinite(v)):
            raise ValueError(f"{name}: expected a non-empty finite grid axis")
    Yaw, Y, X = np.meshgrid(yaws, ys, xs, indexing="ij")
    P = _feet(feet_world).copy()  # the workspace's own: its q may be computed later
    _check_knee(knee)
    if _compiled(tripod):
        args = _kernel_args(tripod, P, knee)
        reach = closed_form_reach(*args, X, Y, Yaw)

        def angles() -> FloatArray:
            Yaw, Y, X = np.meshgrid(yaws, ys, xs, indexing="ij")
            return closed_form_pose_ik(*args, X, Y, Yaw, all_legs=False)[0]
    else:
        q, ok = body_pose_ik_reference(tripod, P, X, Y, Yaw, knee=knee, q_ref=q_ref)
        reach = np.asarray(ok.all(axis=-1), dtype=bool)
        q = np.where(reach[..., None, None], q, np.nan)

        def angles() -> FloatArray:
            return q
    return PoseWorkspace(xs, ys, yaws, reach, P, knee, angles)
