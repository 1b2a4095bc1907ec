"""The legs of any hexapod for the ``hexapod_workspace`` study: the two tripods, in seed 002's
frame, with their kinematics (closed form where the legs are seed 002's, numerical otherwise).

**Study frame** (seed 002's): the robot walks along +y, x is lateral, z up. A robot whose body
frame has x forward (URDF robots; ``meta["forward"]`` says otherwise, as the catalog's
``citedi_hexapod`` does) is turned by +90° about z into it.

**Roles.** The six legs are found by their hips: three on each side of the walking axis (side A:
study x > 0), each side's sorted front, middle, back by y. Seed 002's numbering is
``L1, L2, L3`` = side A front/middle/back and ``L4, L5, L6`` = side B; the tripod ``"135"`` is
the front and back legs of side A with the middle leg of side B (its experiment), ``"246"`` the
other one. Decision-vector order is (front, back, middle).

**Kinematics.** Each leg is a chain of 3 joints, the first (coxa) being the decision θ1, the two
others held at θ2, θ3 in stance. Where all three stance legs are seed 002's (standard DH with
α = (90°, 0, 0), d = 0, the :mod:`legcore.ik.leg3` closed form, equal lengths) the closed forms
are used (fast path); any other leg uses :func:`legcore.kinematics.fk` and
:func:`legcore.ik.solve`. Both give the same answers where both apply (tests).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from legcore.ik import solve
from legcore.ik.leg3 import leg3_fk, leg3_ik
from legcore.kinematics import fk, frames
from legcore.robots.legged import LeggedRobot
from legcore.robots.model import Robot
from legcore.robots.spec import DHRobotSpec

__all__ = [
    "OTHER_STANCE",
    "SEED_NAMES",
    "STANCES",
    "Tripod",
    "is_mirror_symmetric",
    "leg_roles",
    "tripod_from_robot",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Restarts of the numerical IK per target (a workspace map has many unreachable targets; the
#: solution sought is the one near the stance posture).
_RESTARTS = 1
#: Seed 002's leg numbering of the six roles (side A: study x > 0).
SEED_NAMES: dict[str, str] = {"A_front": "L1", "A_middle": "L2", "A_back": "L3",
                              "B_front": "L4", "B_middle": "L5", "B_back": "L6"}
#: The two tripods of seed 002's Fig. 3 as roles, in the decision order (front, back, middle).
STANCE_ROLES: dict[str, tuple[str, str, str]] = {
    "135": ("A_front", "A_back", "B_middle"),
    "246": ("B_front", "B_back", "A_middle"),
}
#: The same in seed 002's leg names (the catalog robot's).
STANCES: dict[str, tuple[str, str, str]] = {
    k: tuple(SEED_NAMES[r] for r in v)  # type: ignore[misc]
    for k, v in STANCE_ROLES.items()
}
#: The tripod a left/right mirror (x → −x) maps each stance onto.
OTHER_STANCE = {"135": "246", "246": "135"}


def study_rotation(robot: LeggedRobot) -> FloatArray:
    """4×4 rotation from the robot's body frame to the study frame (forward → +y)."""
    fwd = np.asarray((robot.meta or {}).get("forward", (1.0, 0.0, 0.0)), dtype=float)[:2]
    yaw = math.pi / 2 - math.atan2(fwd[1], fwd[0])
    c, s = math.cos(yaw), math.sin(yaw)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    return T


def leg_roles(robot: Any) -> dict[str, str]:
    """Role (``A_front`` … ``B_back``) → leg name of a six-legged robot; ``ValueError`` naming
    ``robot`` otherwise (not legged, not six legs, not three on each side)."""
    if not isinstance(robot, LeggedRobot):
        raise ValueError("robot: the hexapod_workspace study needs a legged robot")
    if len(robot.legs) != 6:
        raise ValueError(f"robot: hexapod_workspace needs 6 legs; robot {robot.name} has "
                         f"{len(robot.legs)}")
    R = study_rotation(robot)
    pos = {leg.name: (R @ leg.hip)[:2, 3] for leg in robot.legs}
    sides = {"A": [n for n, p in pos.items() if p[0] > 1e-9],
             "B": [n for n, p in pos.items() if p[0] < -1e-9]}
    if len(sides["A"]) != 3 or len(sides["B"]) != 3:
        raise ValueError(f"robot: hexapod_workspace needs three legs on each side of the walking "
                         f"axis; robot {robot.name} has {len(sides['A'])} and {len(sides['B'])}")
    out: dict[str, str] = {}
    for side, names in sides.items():
        ordered = sorted(names, key=lambda n: -pos[n][1])
        for where, n in zip(("front", "middle", "back"), ordered, strict=True):
            out[f"{side}_{where}"] = n
    return out


@dataclass(frozen=True, eq=False)
class Tripod:
    """The three stance legs of a tripod, in the order (front, back, middle), study frame.

    ``hips`` (3, 4, 4) leg base frames in the study frame (m); ``robots`` the three chains;
    ``closed_form`` the leg3 closed forms apply (then ``L`` (3,) are the link lengths L1, L2, L3,
    m, identical legs; zeros otherwise); ``q_min``/``q_max`` (3, 3) joint limits per leg (rad).
    """

    legs: tuple[str, str, str]
    hips: FloatArray
    L: FloatArray
    q_min: FloatArray
    q_max: FloatArray
    robots: tuple[Robot, Robot, Robot] | None = None
    closed_form: bool = True

    def feet(self, q: ArrayLike) -> FloatArray:
        """Study-frame feet (..., 3, 3) of joint angles ``q`` (..., 3, 3) (leg-major)."""
        q = np.asarray(q, dtype=float)
        if self.closed_form or self.robots is None:
            p_leg = leg3_fk(q, self.L)
        else:
            p_leg = np.stack([fk(rb, q[..., k, :])[..., :3, 3]
                              for k, rb in enumerate(self.robots)], -2)
        return np.einsum("kij,...kj->...ki", self.hips[:, :3, :3], p_leg) + self.hips[:, :3, 3]

    def to_leg_frames(self, p_body: ArrayLike) -> FloatArray:
        """Feet (..., 3, 3) from the study frame to each leg's base frame."""
        d = np.asarray(p_body, dtype=float) - self.hips[:, :3, 3]
        return np.einsum("kji,...kj->...ki", self.hips[:, :3, :3], d)

    def ik(self, p_leg: FloatArray, branch: int, q_ref: FloatArray) -> tuple[FloatArray, BoolArray]:
        """Joint angles (..., 3, 3) and reachability (..., 3) of leg-frame feet (..., 3, 3):
        the closed form on ``branch``, or :func:`legcore.ik.solve` from ``q_ref`` (3, 3)."""
        qs, oks = [], []
        for k in range(3):  # three legs, each with its own limits; the batch is vectorised
            if self.closed_form or self.robots is None:
                q, ok = leg3_ik(p_leg[..., k, :], self.L, branch, self.q_min[k], self.q_max[k])
            else:
                sol = solve(self.robots[k], p_leg[..., k, :], "position", q0=q_ref[k],
                            rest=q_ref[k], restarts=_RESTARTS)
                q, ok = sol.q, np.asarray(sol.reachable, dtype=bool)
            qs.append(q)
            oks.append(ok)
        return np.stack(qs, axis=-2), np.stack(oks, axis=-1)


def _seed_leg_lengths(rb: Robot) -> FloatArray | None:
    """Link lengths of a seed 002 leg (the leg3 closed form applies), else None."""
    spec = rb.spec
    if rb.ik_family != "leg3" or not isinstance(spec, DHRobotSpec):
        return None
    if spec.convention != "standard" or len(spec.joints) != 3:
        return None
    for x, al in zip(spec.joints, (math.pi / 2, 0.0, 0.0), strict=True):
        if x.type != "revolute" or abs(x.alpha - al) > 1e-9 or abs(x.d) > 1e-12 \
                or abs(x.offset) > 1e-12:
            return None
    for mat in (spec.base, spec.tool):
        if mat is not None and not np.allclose(np.asarray(mat, dtype=float), np.eye(4)):
            return None
    return np.array([x.a for x in spec.joints])


def tripod_from_robot(robot: Any, stance: str = "135") -> Tripod:
    """The tripod ``stance`` ("135" or "246", see the module docstring) of a six-legged robot
    with 3-joint legs, in the study frame.

    Raises:
        ValueError: ``robot: …`` if the robot is not such a hexapod, ``stance: …`` if unknown.
    """
    if stance not in STANCE_ROLES:
        raise ValueError(f"stance: expected one of {sorted(STANCE_ROLES)}, got {stance!r}")
    roles = leg_roles(robot)
    names = tuple(roles[r] for r in STANCE_ROLES[stance])
    R = study_rotation(robot)
    robots = tuple(robot.leg(n).robot for n in names)
    for n, rb in zip(names, robots, strict=True):
        if rb.nq != 3:
            raise ValueError(f"robot: hexapod_workspace needs legs of 3 joints; leg {n} of "
                             f"robot {robot.name} has {rb.nq}")
    hips = np.stack([R @ np.asarray(robot.leg(n).hip, dtype=float) for n in names])
    if not np.allclose(hips[:, :3, 2], [0.0, 0.0, 1.0]):
        raise ValueError("robot: the stance legs' hips must be level (turned about z only)")
    found = [_seed_leg_lengths(rb) for rb in robots]
    lengths = [L for L in found if L is not None]
    closed = len(lengths) == 3 and all(np.allclose(L, lengths[0]) for L in lengths)
    closed = closed and bool(np.allclose(hips[:, 2, 3], 0.0))
    return Tripod(
        legs=names,  # type: ignore[arg-type]
        hips=hips,
        L=lengths[0] if closed else np.zeros(3),
        q_min=np.stack([rb.q_min for rb in robots]),
        q_max=np.stack([rb.q_max for rb in robots]),
        robots=robots,
        closed_form=closed,
    )


def is_mirror_symmetric(robot: Any) -> dict[str, bool]:
    """Which of the two mirror symmetries the robot's hips have (study frame; roles as in the
    module docstring): ``front_back`` (y → −y: front ↔ back on each side, middles on the x axis)
    and ``left_right`` (x → −x: side A ↔ side B). Joint limits of θ1 must be symmetric
    (q_min = −q_max) for either."""
    try:
        roles = leg_roles(robot)
    except ValueError:
        return {"front_back": False, "left_right": False}
    R = study_rotation(robot)

    def pose(role: str) -> tuple[float, float, float]:
        leg = robot.leg(roles[role])  # hip position, and the heading of the leg at θ = 0
        H = R @ np.asarray(leg.hip, dtype=float)
        T = H @ frames(leg.robot, np.zeros(leg.robot.nq))[1]
        return float(H[0, 3]), float(H[1, 3]), math.atan2(T[1, 0], T[0, 0])

    def same(a: tuple[float, float, float], b: tuple[float, float, float]) -> bool:
        dyaw = (a[2] - b[2] + math.pi) % (2 * math.pi) - math.pi
        return abs(a[0] - b[0]) < 1e-9 and abs(a[1] - b[1]) < 1e-9 and abs(dyaw) < 1e-9

    def flip_y(p: tuple[float, float, float]) -> tuple[float, float, float]:
        return (p[0], -p[1], -p[2])

    def flip_x(p: tuple[float, float, float]) -> tuple[float, float, float]:
        return (-p[0], p[1], math.pi - p[2])

    P = {r: pose(r) for r in roles}
    lim_ok = all(np.allclose(robot.leg(n).robot.q_min[0], -robot.leg(n).robot.q_max[0])
                 for n in roles.values())
    fb = lim_ok and all(same(flip_y(P[a]), P[b]) for a, b in (
        ("A_front", "A_back"), ("A_back", "A_front"), ("B_front", "B_back"),
        ("B_middle", "B_middle"), ("A_middle", "A_middle")))
    lr = lim_ok and all(same(flip_x(P[a]), P[b]) for a, b in (
        ("A_front", "B_front"), ("A_back", "B_back"), ("B_middle", "A_middle"),
        ("A_middle", "B_middle")))
    return {"front_back": bool(fb), "left_right": bool(lr)}
