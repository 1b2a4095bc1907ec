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

- :func:`tripod_from_robot` — validated leg data (hips, link lengths, joint limits) of a stance.
- :func:`fit_body_motion` — the planar rigid motion that best carries the feet of ``t+1``
  (body frame) onto the fixed feet of ``t`` (2-D Kabsch): the body displacement a solution
  stands for, and the residual foot slip (zero only for a congruent triangle).
- :func:`mirror_front_back`, :func:`mirror_left_right` — the robot's two mirror symmetries.
- :func:`body_pose_ik`, :func:`pose_workspace` — beyond the paper: the exact set of body poses
  reachable with the three feet fixed, by the closed-form leg IK (eqs 8–10) with θ2, θ3 free.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.ik.leg3 import KNEE_DOWN, KNEE_UP, leg3_fk, leg3_ik
from legcore.robots.legged import LeggedRobot
from legcore.robots.spec import DHRobotSpec

__all__ = [
    "STANCES",
    "PoseWorkspace",
    "Tripod",
    "body_pose_ik",
    "fit_body_motion",
    "mirror_front_back",
    "mirror_left_right",
    "pose_workspace",
    "tripod_from_robot",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: The two tripods of seed 002's Fig. 3 in the decision-vector order (front, back, middle).
STANCES: dict[str, tuple[str, str, str]] = {"135": ("L1", "L3", "L5"), "246": ("L4", "L6", "L2")}
#: The tripod a left/right mirror (x → −x) maps each stance onto.
OTHER_STANCE = {"135": "246", "246": "135"}


@dataclass(frozen=True, eq=False)
class Tripod:
    """The three stance legs of a tripod, in the order (front, back, middle).

    ``hips`` (3, 4, 4) leg base frames in the body frame (m); ``L`` (3,) link lengths L1, L2, L3
    (m, identical legs); ``q_min``/``q_max`` (3, 3) joint limits per leg (rad).
    """

    legs: tuple[str, str, str]
    hips: FloatArray
    L: FloatArray
    q_min: FloatArray
    q_max: FloatArray

    def feet(self, q: ArrayLike) -> FloatArray:
        """Body-frame feet (..., 3, 3) of joint angles ``q`` (..., 3, 3) (leg-major), eqs 5–7."""
        p_leg = leg3_fk(q, self.L)
        return np.einsum("kij,...kj->...ki", self.hips[:, :3, :3], p_leg) + self.hips[:, :3, 3]

    def to_leg_frames(self, p_body: ArrayLike) -> FloatArray:
        """Feet (..., 3, 3) from the body frame to each leg's base frame."""
        d = np.asarray(p_body, dtype=float) - self.hips[:, :3, 3]
        return np.einsum("kji,...kj->...ki", self.hips[:, :3, :3], d)


def _leg_chain_lengths(robot: LeggedRobot, name: str) -> tuple[FloatArray, FloatArray, FloatArray]:
    leg = robot.leg(name)
    spec = leg.robot.spec
    if not isinstance(spec, DHRobotSpec) or spec.convention != "standard":
        raise ValueError(f"robot: leg {name} must be a standard-DH 3-DOF leg (seed 002 Table 1)")
    j = spec.joints
    alphas = (math.pi / 2, 0.0, 0.0)
    if len(j) != 3 or any(x.type != "revolute" for x in j):
        raise ValueError(f"robot: leg {name} must have 3 revolute joints (coxa, femur, tibia)")
    for i, (x, al) in enumerate(zip(j, alphas, strict=True)):
        if abs(x.alpha - al) > 1e-9 or abs(x.d) > 1e-12 or abs(x.offset) > 1e-12:
            raise ValueError(
                f"robot: leg {name} joint {i} must have d = 0, offset = 0 and alpha = "
                f"{math.degrees(al):.0f} deg (the leg of seed 002 eqs 5-10)"
            )
    for mat, what in ((spec.base, "base"), (spec.tool, "tool")):
        if mat is not None and not np.allclose(np.asarray(mat, dtype=float), np.eye(4)):
            raise ValueError(f"robot: leg {name} must have no {what} transform (foot = DH frame 3)")
    return np.array([x.a for x in j]), leg.robot.q_min.copy(), leg.robot.q_max.copy()


def tripod_from_robot(robot: Any, stance: str = "135") -> Tripod:
    """The validated tripod ``stance`` ("135" or "246") of a six-legged robot with seed 002's
    legs (named L1…L6, each the 3-DOF chain of :mod:`legcore.ik.leg3`, identical lengths).

    Raises:
        ValueError: ``robot: …`` if the robot is not such a hexapod, ``stance: …`` if unknown.
    """
    if stance not in STANCES:
        raise ValueError(f"stance: expected one of {sorted(STANCES)}, got {stance!r}")
    if not isinstance(robot, LeggedRobot):
        raise ValueError("robot: the hexapod_workspace study needs a legged robot")
    names = STANCES[stance]
    have = {leg.name for leg in robot.legs}
    missing = [n for n in names if n not in have]
    if missing:
        raise ValueError(f"robot: {robot.name!r} has no leg(s) {missing}; expected legs L1..L6")
    data = [_leg_chain_lengths(robot, n) for n in names]
    L = data[0][0]
    if any(not np.allclose(d[0], L) for d in data):
        raise ValueError("robot: the three stance legs must have the same link lengths")
    hips = np.stack([np.asarray(robot.leg(n).hip, dtype=float) for n in names])
    if not np.allclose(hips[:, :3, 2], [0.0, 0.0, 1.0]) or not np.allclose(hips[:, 2, 3], 0.0):
        raise ValueError("robot: the stance legs' hips must be level (yaw only) at body height 0")
    return Tripod(
        legs=names,
        hips=hips,
        L=L,
        q_min=np.stack([d[1] for d in data]),
        q_max=np.stack([d[2] for d in data]),
    )


def is_mirror_symmetric(robot: Any) -> dict[str, bool]:
    """Which of the two mirror symmetries the robot's hips have (see the mirror functions).

    ``front_back``: L1 ↔ L3 and L4 ↔ L6 under y → −y, L5 and L2 on the x axis;
    ``left_right``: L1 ↔ L4, L3 ↔ L6, L5 ↔ L2 under x → −x. Joint limits of θ1 must be
    symmetric (q_min = −q_max) for either.
    """

    def pose(n: str) -> tuple[float, float, float]:
        T = np.asarray(robot.leg(n).hip, dtype=float)
        return float(T[0, 3]), float(T[1, 3]), math.atan2(T[1, 0], T[0, 0])

    def same(a: tuple[float, float, float], b: tuple[float, float, float]) -> bool:
        dyaw = (a[2] - b[2] + math.pi) % (2 * math.pi) - math.pi
        return abs(a[0] - b[0]) < 1e-9 and abs(a[1] - b[1]) < 1e-9 and abs(dyaw) < 1e-9

    def flip_y(p: tuple[float, float, float]) -> tuple[float, float, float]:
        return (p[0], -p[1], -p[2])

    def flip_x(p: tuple[float, float, float]) -> tuple[float, float, float]:
        return (-p[0], p[1], math.pi - p[2])

    try:
        P = {n: pose(n) for n in ("L1", "L2", "L3", "L4", "L5", "L6")}
        lim_ok = all(
            np.allclose(robot.leg(n).robot.q_min[0], -robot.leg(n).robot.q_max[0]) for n in P
        )
    except KeyError:
        return {"front_back": False, "left_right": False}
    fb = lim_ok and all(same(flip_y(P[a]), P[b]) for a, b in
                        (("L1", "L3"), ("L3", "L1"), ("L4", "L6"), ("L5", "L5"), ("L2", "L2")))
    lr = lim_ok and all(same(flip_x(P[a]), P[b]) for a, b in
                        (("L1", "L4"), ("L3", "L6"), ("L5", "L2"), ("L2", "L5")))
    return {"front_back": bool(fb), "left_right": bool(lr)}


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
) -> tuple[FloatArray, BoolArray]:
    """Joint angles of the three stance legs for body poses ``(x, y, yaw)`` with the feet fixed.

    Args:
        tripod: the stance legs.
        feet_world: fixed feet (3, 3) in the world frame (m).
        x, y, yaw: body poses (broadcast together to a batch shape ``S``), m, m, rad.
        knee: ``"up"`` (θ3 ≤ 0, seed 002's posture), ``"down"`` or ``"either"`` (per leg, the
            knee-up solution when it is within the limits, else knee-down).

    Returns:
        ``q`` (*S, 3, 3) rad (leg-major, NaN where a leg cannot reach) and ``reachable``
        (*S, 3) per leg: the closed form of eqs (8)–(10) inside the joint limits.
    """
    P = np.asarray(feet_world, dtype=float)
    if P.shape != (3, 3):
        raise ValueError(f"feet_world: expected shape (3, 3), got {P.shape}")
    x, y, yaw = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (x, y, yaw)))
    c, s = np.cos(yaw)[..., None], np.sin(yaw)[..., None]
    dx, dy = P[:, 0] - x[..., None], P[:, 1] - y[..., None]
    p_body = np.stack((c * dx + s * dy, -s * dx + c * dy, np.broadcast_to(P[:, 2], dx.shape)), -1)
    p_leg = tripod.to_leg_frames(p_body)
    if knee not in ("up", "down", "either"):
        raise ValueError(f"knee: expected 'up', 'down' or 'either', got {knee!r}")
    branch = KNEE_DOWN if knee == "down" else KNEE_UP
    q, ok = _leg_ik_limits(tripod, p_leg, branch)
    if knee == "either" and not np.all(ok):
        q2, ok2 = _leg_ik_limits(tripod, p_leg, KNEE_DOWN)
        use = ~ok & ok2
        q = np.where(use[..., None], q2, q)
        ok = ok | ok2
    return q, ok


def _leg_ik_limits(tripod: Tripod, p_leg: FloatArray, branch: int) -> tuple[FloatArray, BoolArray]:
    qs, oks = [], []
    for k in range(3):  # three legs, each with its own limits; the batch is vectorised
        q, ok = leg3_ik(p_leg[..., k, :], tripod.L, branch, tripod.q_min[k], tripod.q_max[k])
        qs.append(q)
        oks.append(ok)
    return np.stack(qs, axis=-2), np.stack(oks, axis=-1)


@dataclass(frozen=True, eq=False)
class PoseWorkspace:
    """Body poses on a grid, reachable with the three stance feet fixed.

    ``x`` (nx,), ``y`` (ny,) m and ``yaw`` (nyaw,) rad grid axes; ``reachable`` (nyaw, ny, nx)
    bool (all three legs inside their joint limits); ``q`` (nyaw, ny, nx, 3, 3) joint angles
    (NaN where not reachable); ``feet_world`` (3, 3) the fixed feet; ``knee`` the branch rule.
    """

    x: FloatArray
    y: FloatArray
    yaw: FloatArray
    reachable: BoolArray
    q: FloatArray
    feet_world: FloatArray
    knee: str

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
        if masks:
            out["masks"] = [
                ["".join("1" if v else "0" for v in row) for row in plane]
                for plane in self.reachable
            ]
        return out


def pose_workspace(
    tripod: Tripod,
    feet_world: ArrayLike,
    x: ArrayLike,
    y: ArrayLike,
    yaw: ArrayLike,
    knee: str = "up",
) -> PoseWorkspace:
    """The exact workspace of body poses on the grid ``yaw × y × x`` (one batched IK call per
    leg over the whole grid): a pose is reachable when all three legs reach their fixed feet
    inside the joint limits (θ1, θ2, θ3 all free)."""
    xs, ys, yaws = (np.asarray(v, dtype=float).ravel() for v in (x, y, yaw))
    for name, v in (("x", xs), ("y", ys), ("yaw", yaws)):
        if v.size == 0 or not np.all(np.isfinite(v)):
            raise ValueError(f"{name}: expected a non-empty finite grid axis")
    Yaw, Y, X = np.meshgrid(yaws, ys, xs, indexing="ij")
    q, ok = body_pose_ik(tripod, feet_world, X, Y, Yaw, knee=knee)
    reach: BoolArray = np.asarray(ok.all(axis=-1), dtype=bool)
    q = np.where(reach[..., None, None], q, np.nan)
    return PoseWorkspace(xs, ys, yaws, reach, q, np.asarray(feet_world, dtype=float).copy(), knee)
