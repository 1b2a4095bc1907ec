"""How a quadruped stands, for the robot-relative defaults of ``quadruped_gait``: each leg's
length, its standing posture on its own knee branch, and the whole robot's centre of mass.

Frames and units as in :mod:`legcore.studies.quadruped_gait.legs` (body frame x forward, y left,
z up; m, rad). A foot "under the hip" is at the hip's x, at the leg's lateral offset λ (body y
from its hip) — the plane the leg swings in.

- **Leg length** L of one leg (:func:`leg_length`): the greatest depth below its hip at which
  the foot can stand under the hip (at λ) inside the joint limits — the leg stretched
  downwards (:func:`shallowest_depth`: the least, the leg folded). Found with the numerical IK
  on a grid of 33 depths up to the chain's length bound (the sum of its link offsets), then
  refined three times between the last reachable depth and the next one (17 depths each:
  resolution ≈ 3·10⁻⁶ of the bound).
- **Knee side** (:func:`knee_side`): the knee is the chain point farthest from the hip–foot line
  in the body's x–z plane; it lies ahead of the line (+1) or behind it (−1).
- **Standing posture** (:func:`standing_posture`): the IK solution with the foot at the
  standing point whose knee points toward the body's centre (a front leg's knee behind the
  foot, a rear leg's ahead — ANYmal's and Solo12's stance, seed 003's "front elbow back, rear
  knee forward") when the joint limits allow one, else on the other side (Go1: every knee
  behind); among the solutions on a side, the one nearest the leg's home posture. A 2-joint
  closed-form leg (seed 003) takes its own branch (``robot.meta["branch"]`` or its limits).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from legcore.chain_points import chain_points
from legcore.ik import solve
from legcore.ik.leg2 import leg2_ik
from legcore.kinematics import fk
from legcore.robots.legged import Leg
from legcore.studies.quadruped_gait.legs import GaitLeg

__all__ = ["LegStance", "knee_side", "leg_length", "length_bound", "robot_com",
           "shallowest_depth", "standing_posture"]

FloatArray = NDArray[np.float64]

_N_SEEDS = 2048  # joint configurations sampled for the standing posture's IK seeds
_N_TRIES = 8  # of them, the nearest to the target on each knee side are tried
_DEPTHS = 32  # depths of the first grid of the leg-length search
_REFINE = 16  # depths of each finer grid
_RESTARTS = 8  # restart seeds of the IK per depth (each leg is 2-3 joints)


@dataclass(frozen=True)
class LegStance:
    """One leg standing: ``q`` (n,) rad with the foot at the standing point, ``knee`` (+1 knee
    ahead of the hip–foot line, −1 behind), ``toward_centre`` (the knee points toward the
    body's centre)."""

    name: str
    q: FloatArray
    knee: float
    toward_centre: bool

    def words(self) -> str:
        where = "ahead of" if self.knee > 0 else "behind"
        side = "toward the body centre" if self.toward_centre else \
            "away from the body centre (its joint limits allow no other)"
        angles = ", ".join(f"{round(float(v), 3) + 0.0:.3f}" for v in self.q)  # no −0.000
        return f"{self.name}: knee {where} the foot, {side}, ({angles}) rad"


def _box(leg: Leg) -> tuple[FloatArray, FloatArray]:
    """The joint box, wide limits clipped to ±π (rad)."""
    rb = leg.robot
    return np.maximum(rb.q_min, -np.pi), np.minimum(rb.q_max, np.pi)


def length_bound(leg: Leg) -> float:
    """An upper bound (m) of the hip-to-foot distance: the sum of the chain's link offsets."""
    c = leg.robot.chain
    return float(np.linalg.norm(c.p, axis=-1).sum() + np.linalg.norm(c.tool_p))


def _reachable(leg: Leg, body_points: FloatArray) -> FloatArray:
    """(k,) bool: body-frame foot targets (k, 3) the leg reaches inside its limits."""
    sol = solve(leg.robot, leg.foot_in_leg(body_points), "position", method="numeric",
                restarts=_RESTARTS)
    return np.asarray(sol.reachable, dtype=bool)


def _edge(leg: Leg, lateral: float, forward: float, deepest: bool) -> float:
    """The deepest (``deepest``) or the shallowest depth (m) on the vertical line under the hip
    that the foot reaches: a grid of depths up to :func:`length_bound`, then three finer grids
    between the last reachable depth and the next; NaN when none is reachable."""
    hip = leg.hip[:3, 3]
    lo, hi, n = 0.0, length_bound(leg), _DEPTHS
    found = math.nan
    for _ in range(4):
        d = np.linspace(lo, hi, n + 1)
        pts = hip + np.stack((np.full_like(d, forward), np.full_like(d, lateral), -d), -1)
        ok = np.flatnonzero(_reachable(leg, pts))
        if ok.size == 0:
            break
        k = int(ok[-1] if deepest else ok[0])
        found = float(d[k])
        j = k + 1 if deepest else k - 1
        if not 0 <= j < d.size:
            break
        lo, hi = sorted((float(d[k]), float(d[j])))
        n = _REFINE
    return found


def leg_length(leg: Leg, lateral: float, forward: float = 0.0) -> float:
    """The leg's length L (m): the deepest point below its hip, ``forward`` ahead of it and
    ``lateral`` beside it, that its foot reaches inside the joint limits (module docstring);
    0 when it reaches none."""
    found = _edge(leg, lateral, forward, deepest=True)
    return 0.0 if math.isnan(found) else found


def shallowest_depth(leg: Leg, lateral: float, forward: float = 0.0) -> float:
    """The least depth (m) below the hip at which the foot reaches under it (the leg folded as
    far as its limits allow); NaN when it reaches none."""
    return _edge(leg, lateral, forward, deepest=False)


def knee_side(leg: Leg, q: FloatArray) -> FloatArray:
    """(...,) +1 where the knee (the chain point farthest from the hip–foot line in the body's
    x–z plane) lies ahead of that line, −1 behind, for postures ``q`` (..., n)."""
    pts = leg.foot_in_body(chain_points(leg.robot, q, tool=True))[..., [0, 2]]  # (..., M, 2)
    hip, foot, inner = pts[..., :1, :], pts[..., -1:, :], pts[..., 1:-1, :]
    d = foot - hip
    dd = np.maximum(np.einsum("...ki,...ki->...k", d, d), 1e-300)
    t = np.clip(np.einsum("...ki,...ki->...k", inner - hip, d) / dd, 0.0, 1.0)
    off = inner - (hip + t[..., None] * d)
    k = np.argmax(np.linalg.norm(off, axis=-1), axis=-1)
    ox = np.take_along_axis(off[..., 0], k[..., None], -1)[..., 0]
    return np.where(ox >= 0.0, 1.0, -1.0)


def standing_posture(g: GaitLeg, target: FloatArray) -> LegStance | None:
    """The posture of leg ``g`` with its foot at ``target`` (3,) (body frame), on the knee side
    of the module's rule, or None when the foot cannot stand there inside the joint limits."""
    leg, rb = g.leg, g.leg.robot
    toward = -1.0 if leg.hip[0, 3] > 0.0 else 1.0  # the knee side toward the body centre
    if g.closed_form:
        p_leg = leg.foot_in_leg(target)
        q, ok = leg2_ik(p_leg[None, :2], g.L, g.branch, rb.q_min, rb.q_max)
        if not ok[0] or abs(p_leg[2]) > 1e-9:
            return None
        side = float(knee_side(leg, q[0]))
        return LegStance(leg.name, q[0], side, side == toward)
    lo, hi = _box(leg)
    rng = np.random.default_rng(0)
    Q = np.concatenate((rb.home[None, :], lo + (hi - lo) * rng.random((_N_SEEDS, rb.nq))))
    err = np.linalg.norm(leg.foot_in_body(fk(rb, Q)[:, :3, 3]) - target, axis=-1)
    sides = knee_side(leg, Q)
    p_leg = leg.foot_in_leg(target)
    for side in (toward, -toward):
        idx = np.flatnonzero(sides == side)
        if idx.size == 0:
            continue
        seeds = Q[idx[np.argsort(err[idx], kind="stable")[:_N_TRIES]]]
        sol = solve(rb, np.broadcast_to(p_leg, seeds.shape[:1] + (3,)), "position", q0=seeds,
                    method="numeric", restarts=0)
        ok = np.asarray(sol.reachable, dtype=bool)
        if not ok.any():
            continue
        q = np.asarray(sol.q)[ok]
        q = q[knee_side(leg, q) == side]
        if q.shape[0]:
            best = q[int(np.argmin(np.linalg.norm(q - rb.home, axis=-1)))]
            return LegStance(leg.name, best, side, side == toward)
    return None


def robot_com(legs: tuple[GaitLeg, ...], postures: dict[str, FloatArray], body_mass: float,
              body_com: FloatArray) -> tuple[FloatArray, float]:
    """The whole robot's centre of mass (3,) m in the body frame and its mass (kg): the body
    (``body_mass`` at ``body_com``) plus every leg's links at ``postures``."""
    num = body_mass * np.asarray(body_com, dtype=float)
    mass = body_mass
    for g in legs:
        rb = g.leg.robot
        c = chain_points(rb, postures[g.name], offsets=g.com_link)[1:]
        num = num + rb.chain.mass @ g.leg.foot_in_body(c)
        mass += float(rb.chain.mass.sum())
    return num / mass, mass
