"""A hexapod leg's reach, for the ``hexapod_workspace`` defaults
(:mod:`legcore.studies.hexapod_workspace.defaults`): the stance posture (foot 45° below the
hip, halfway along the leg's reach on that line), the coxa swing that keeps a stance foot out
of its neighbour's half of the gap, and the box of body poses the three stance legs can reach.

Any 3-joint leg: the foot comes from the leg's own FK over its joint box (the numba
:func:`legcore.chain_points.chain_points`, also giving the joint origins), in the leg's base
frame at the hip (z up); *s* is the foot's horizontal distance out from the hip along the
direction the leg points (the mean of its foot positions), *v* its height. A leg whose first
joint turns about the vertical sweeps that (s, v) plane around the hip. SI units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.chain_points import chain_points
from legcore.kinematics import fk
from legcore.robots.legged import LeggedRobot
from legcore.robots.model import Robot
from legcore.studies.hexapod_workspace.legs import Tripod, study_rotation

__all__ = ["N_POSTURE", "STANCE_DEPRESSION", "StancePosture", "pose_box", "stance_posture",
           "theta1_swing"]

FloatArray = NDArray[np.float64]

#: Direction of the stance foot below the hip's horizontal (rad): as far below as out.
STANCE_DEPRESSION = math.pi / 4
#: Values per joint of the posture grids.
N_POSTURE = 161
#: Angular half-width (rad) of the band around the 45° line where ρ_min, ρ_max are read.
_RAY_TOL = math.radians(2.0)


def _joint_offsets(rb: Robot) -> FloatArray:
    """(n, 3): each joint's origin in its link frame (so that :func:`chain_points` gives the
    joint origins — points on the joint axes — instead of the link frames')."""
    out = np.zeros((rb.nq, 3))
    for i, fid in enumerate(rb.link_frames):
        placement = rb.model.frames[fid].placement
        out[i] = -np.asarray(placement.rotation).T @ np.asarray(placement.translation)
    return out


@dataclass(frozen=True, eq=False)
class _Plane:
    """Foot samples of one leg at fixed θ1 (leg base frame = hip, z up): joint angles ``q``
    (M, 3); ``s`` (M,) outward horizontal distance from the coxa axis along ``u`` (2,), m;
    ``v`` (M,) height from the hip, m; ``up`` (M,) knee-up flags; ``reach`` the largest
    hip-to-foot distance, m."""

    q: FloatArray
    s: FloatArray
    v: FloatArray
    up: NDArray[np.bool_]
    u: FloatArray
    reach: float


def _plane(rb: Robot, theta1: float, t2: FloatArray, t3: FloatArray,
           closed_form: bool) -> _Plane:
    T2, T3 = np.meshgrid(t2, t3, indexing="ij")
    q = np.column_stack((np.full(T2.size, theta1), T2.ravel(), T3.ravel()))
    pts = chain_points(rb, q, tool=True, offsets=_joint_offsets(rb))  # base, j1, j2, j3, foot
    foot, femur, knee = pts[:, -1], pts[:, 2], pts[:, 3]
    mean = foot[:, :2].mean(axis=0)
    norm = float(np.linalg.norm(mean))
    if norm < 1e-9 * max(float(np.abs(foot).max()), 1e-300):
        raise ValueError("theta2: the leg has no outward direction at theta1_start (its feet "
                         "surround the hip); give theta2 and theta3")
    u = mean / norm
    s = foot[:, :2] @ u
    v = foot[:, 2]
    if closed_form:  # the study's branch: θ3 ≤ 0 is knee up (seed 002's posture)
        up = q[:, 2] <= 0.0
    else:  # the knee above (or on) the line from the femur joint to the foot
        a_s, a_v = (foot - femur)[:, :2] @ u, (foot - femur)[:, 2]
        b_s, b_v = (knee - femur)[:, :2] @ u, (knee - femur)[:, 2]
        scale = float(np.abs(foot).max()) ** 2
        up = a_s * b_v - a_v * b_s >= -1e-12 * scale  # a straight knee counts for both
    return _Plane(q, s, v, up, u, float(np.linalg.norm(foot, axis=-1).max()))


@dataclass(frozen=True)
class StancePosture:
    """A derived stance posture: ``theta2``, ``theta3`` (rad); the foot at ``s`` out and ``v``
    up from the hip (m); ρ_min, ρ_max, ρ (m) the reach along the 45° line (NaN when one angle
    was given); ``rule`` in words."""

    theta2: float
    theta3: float
    s: float
    v: float
    rho_min: float
    rho_max: float
    rho: float
    rule: str


def _foot_sv(rb: Robot, theta1: float, t23: FloatArray, u: FloatArray) -> FloatArray:
    p = fk(rb, np.array([theta1, t23[0], t23[1]]))[:3, 3]
    return np.array([float(p[:2] @ u), float(p[2])])


def _refine(rb: Robot, theta1: float, t23: FloatArray, free: list[int], u: FloatArray,
            residual: Any, lo: FloatArray, hi: FloatArray) -> FloatArray:
    """Gauss–Newton on the free joints (indices into (θ2, θ3)) of ``residual(s, v)``, kept in
    the limits ``lo``/``hi``."""
    x = np.array(t23, dtype=float)
    h = 1e-7
    for _ in range(40):
        r = np.atleast_1d(residual(_foot_sv(rb, theta1, x, u)))
        if float(np.abs(r).max()) < 1e-13:
            break
        J = np.zeros((r.size, len(free)))
        for c, j in enumerate(free):
            xp, xm = x.copy(), x.copy()
            xp[j] += h
            xm[j] -= h
            J[:, c] = (np.atleast_1d(residual(_foot_sv(rb, theta1, xp, u)))
                       - np.atleast_1d(residual(_foot_sv(rb, theta1, xm, u)))) / (2 * h)
        step = np.linalg.lstsq(J, -r, rcond=None)[0]
        x[free] = np.clip(x[free] + step, lo[free], hi[free])
    return x


def stance_posture(rb: Robot, theta1: float, closed_form: bool, knee: str,
                   theta2: float | None = None, theta3: float | None = None) -> StancePosture:
    """The stance posture of leg ``rb`` at coxa angle ``theta1`` (module docstring rule);
    a given ``theta2`` or ``theta3`` is kept. ``ValueError`` naming the field when no posture
    of the leg puts its foot on the 45° line below the hip."""
    lo, hi = np.asarray(rb.q_min, dtype=float)[1:], np.asarray(rb.q_max, dtype=float)[1:]
    if theta2 is not None and theta3 is not None:
        raise ValueError("theta2: both stance angles are given; nothing to derive")
    n = N_POSTURE if theta2 is None and theta3 is None else 4 * N_POSTURE
    t2 = np.array([theta2]) if theta2 is not None else np.linspace(lo[0], hi[0], n)
    t3 = np.array([theta3]) if theta3 is not None else np.linspace(lo[1], hi[1], n)
    P = _plane(rb, theta1, t2, t3, closed_form)
    branch = P.up if knee != "down" else ~P.up
    c, sn = math.cos(STANCE_DEPRESSION), math.sin(STANCE_DEPRESSION)
    field = "theta3" if theta3 is None else "theta2"
    side = "knee up" if knee != "down" else "knee down"
    if theta2 is None and theta3 is None:
        beta = np.arctan2(-P.v, P.s)
        rho_all = np.hypot(P.s, P.v)
        near = branch & (P.s > 0.0) & (np.abs(beta - STANCE_DEPRESSION) < _RAY_TOL)
        if not near.any():
            raise ValueError("theta2: no posture of the leg inside its joint limits puts the "
                             f"foot 45° below the hip ({side}); give theta2 and theta3")
        rho_min, rho_max = float(rho_all[near].min()), float(rho_all[near].max())
        rho = 0.5 * (rho_min + rho_max)
        target = np.array([rho * c, -rho * sn])
        i = int(np.argmin(np.where(branch, np.hypot(P.s - target[0], P.v - target[1]),
                                   np.inf)))
        x = _refine(rb, theta1, P.q[i, 1:], [0, 1], P.u, lambda sv: sv - target, lo, hi)
        rule = (f"foot 45° below the hip, halfway along the leg's reach on that line "
                f"(ρ = {rho:.4g} m between {rho_min:.4g} and {rho_max:.4g} m), {side}")
    else:
        dist = np.abs(P.s * sn + P.v * c)  # distance to the 45° line (s > 0 half)
        score = np.where(branch & (P.s > 0.0), dist, np.inf)
        i = int(np.argmin(score))
        if not np.isfinite(score[i]):
            raise ValueError(f"{field}: no {field} inside the joint limits puts the foot out "
                             f"and below the hip ({side}) with the given angle; give {field}")
        free = [1] if theta3 is None else [0]
        x = _refine(rb, theta1, P.q[i, 1:], free, P.u, lambda sv: sv[0] * sn + sv[1] * c,
                    lo, hi)
        rho_min = rho_max = rho = float("nan")
        rule = f"foot on the line 45° below the hip with the given angle, {side}"
    x = np.clip(np.round(x, 4), lo, hi)
    s, v = _foot_sv(rb, theta1, x, P.u)
    return StancePosture(float(x[0]), float(x[1]), float(s), float(v), rho_min, rho_max, rho,
                         rule)


def _all_feet(robot: LeggedRobot, tripod: Tripod, theta_start: FloatArray, t2: float,
              t3: float) -> dict[str, tuple[FloatArray, FloatArray]]:
    """Leg name → (hip, foot) (2,) each in the study frame, all six legs at the stance posture
    (the stance legs at ``theta_start``, the others at θ1 = 0)."""
    R = study_rotation(robot)
    out = {}
    for leg in robot.legs:
        th1 = theta_start[tripod.legs.index(leg.name)] if leg.name in tripod.legs else 0.0
        H = R @ np.asarray(leg.hip, dtype=float)
        q = np.zeros(leg.robot.nq)
        q[:3] = (th1, t2, t3)[:leg.robot.nq]
        foot = (H @ fk(leg.robot, q))[:3, 3]
        out[leg.name] = (H[:2, 3], foot[:2])
    return out


def theta1_swing(robot: LeggedRobot, tripod: Tripod, theta_start: FloatArray, t2: float,
                  t3: float) -> tuple[float, str]:
    """Largest coxa swing Δθ1 (rad) and its rule: each stance foot sweeps at most half the gap
    to its nearest neighbouring foot."""
    feet = _all_feet(robot, tripod, theta_start, t2, t3)
    best, words = math.inf, ""
    for name in tripod.legs:
        hip, foot = feet[name]
        gap = min(float(np.linalg.norm(foot - other)) for n, (_, other) in feet.items()
                  if n != name)
        s = float(np.linalg.norm(foot - hip))
        delta = 2.0 * math.asin(min(1.0, gap / (4.0 * s))) if s > 0 else math.pi
        if delta < best:
            best = delta
            words = (f"leg {name}'s foot {s:.4g} m from its coxa axis, {gap:.4g} m from the "
                     f"nearest foot: sweeps at most half that gap, 2·asin(gap/(4s))")
    return math.floor(best * 1e4) / 1e4, words


def _level_cut(S: FloatArray, V: FloatArray) -> FloatArray:
    """The values of ``S`` where ``V`` (same (n2, n3) grid over θ2, θ3) crosses 0, by linear
    interpolation along both grid directions: the horizontal distances at which the foot is
    at the stance height."""
    out = []
    for s, v in ((S, V), (S.T, V.T)):
        v0, v1, s0, s1 = v[:, :-1], v[:, 1:], s[:, :-1], s[:, 1:]
        cross = (v0 * v1 <= 0.0) & (v0 != v1)
        t = v0[cross] / (v0[cross] - v1[cross])
        out.append(s0[cross] + t * (s1[cross] - s0[cross]))
    return np.concatenate(out)


def pose_box(tripod: Tripod, feet: FloatArray, theta_start: FloatArray, t2: float, t3: float,
              yaws: FloatArray) -> tuple[float, float]:
    """Half-widths (x, y) in m of a box holding every body pose (d, ψ) of the ``yaws`` that
    keeps the three stance feet ``feet`` (3, 3) inside the legs' reach (module docstring)."""
    assert tripod.robots is not None
    boxes = []
    for k, rb in enumerate(tripod.robots):
        lim_lo, lim_hi = np.asarray(rb.q_min, dtype=float), np.asarray(rb.q_max, dtype=float)
        P = _plane(rb, float(theta_start[k]), np.linspace(lim_lo[1], lim_hi[1], N_POSTURE),
                   np.linspace(lim_lo[2], lim_hi[2], N_POSTURE), True)
        H = tripod.hips[k]
        p0 = fk(rb, np.array([theta_start[k], t2, t3]))[:3, 3]   # leg frame
        s0, v0 = float(p0[:2] @ P.u), float(p0[2])
        cut = _level_cut(P.s.reshape(N_POSTURE, N_POSTURE),
                         P.v.reshape(N_POSTURE, N_POSTURE) - v0)
        s_lo, s_hi = float(min(cut.min(initial=s0), s0)), float(max(cut.max(initial=s0), s0))
        w = p0[:2] - s0 * P.u                                      # lateral offset of the foot
        phi = np.linspace(lim_lo[0], lim_hi[0], 61) - theta_start[k]
        S = np.linspace(s_lo, s_hi, 25)
        Ph, Sg = np.meshgrid(phi, S, indexing="ij")
        a_leg = Sg.ravel()[:, None] * P.u + w                      # (M, 2) leg frame, θ1 start
        c, s = np.cos(Ph.ravel()), np.sin(Ph.ravel())
        a_leg = np.column_stack((c * a_leg[:, 0] - s * a_leg[:, 1],
                                 s * a_leg[:, 0] + c * a_leg[:, 1]))
        a = a_leg @ H[:2, :2].T + H[:2, 3]                         # body frame (h_k + a)
        cy, sy = np.cos(yaws)[:, None], np.sin(yaws)[:, None]
        dx = feet[k, 0] - (cy * a[:, 0] - sy * a[:, 1])            # (nyaw, M)
        dy = feet[k, 1] - (sy * a[:, 0] + cy * a[:, 1])
        boxes.append(np.stack((dx.min(1), dx.max(1), dy.min(1), dy.max(1)), -1))
    B = np.stack(boxes)                                            # (3, nyaw, 4)
    lo_x, hi_x = B[:, :, 0].max(0), B[:, :, 1].min(0)
    lo_y, hi_y = B[:, :, 2].max(0), B[:, :, 3].min(0)
    ok = (lo_x <= hi_x) & (lo_y <= hi_y)
    ex = float(np.maximum(np.abs(lo_x), np.abs(hi_x))[ok].max())
    ey = float(np.maximum(np.abs(lo_y), np.abs(hi_y))[ok].max())
    return ex, ey
