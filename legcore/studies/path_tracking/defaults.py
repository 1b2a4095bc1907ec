"""``path_tracking`` defaults relative to the arm it is given, and the pre-flight check.

``derive(robot, params) -> Task`` (the contract of :mod:`legcore.studies.task`) fills every
field the user left None, by these rules (recorded with their numbers in ``Task.rules``):

- **tool orientation** (``orientation``, ``tool_axis``): the first of *down*, *forward* (the
  horizontal direction away from the arm at home: drawing on a wall), *up* and *free* that the
  arm can hold along the whole path below;
- **where** (``plane_origin``): the most dexterous configuration holding that orientation
  (:func:`legcore.studies.arm_workspace.centres`: sampled FK and the task Jacobian's
  conditioning, :data:`~legcore.studies.arm_workspace.MIN_MARGIN` of every joint range free,
  at least 0.1 × the reach above the arm's base) whose whole path passes the check below;
- **the plane** (``plane_e1``, ``plane_e2``): normal to the tool axis (horizontal for a free
  orientation); e1 across the arm (horizontal, ⊥ the direction from the base axis to the
  centre), e2 = normal × e1 (away from the arm, or up on a wall);
- **the path** (``segments``): seed 004's capsule — two semicircles and two lines, 0.6 × 0.2 m,
  run counter-clockwise — scaled to a length of 0.4 (else 0.3, 0.2, 0.1) × the arm's reach
  (seed: 0.6 × its arm's 1 m) and centred on the plane origin; the largest that passes;
- **rest**: the centre's configuration (the IK follows the branch it starts on);
- **the time law**: ``V`` = 0.10 m/s (the seed's) scaled with the path, at most half the
  fastest tool speed at which every joint keeps its speed limit everywhere on the path;
  ``V_bounds`` = (V/10, 10 V), the seed's box (0.01, 1.0) m/s about its V (the problem lowers
  each segment's bound further to the fastest speed its joint speed limits allow; on the
  matrix arms the time optimum's speeds stay below 10 V);
  ``t_a``, ``t_d``, ``ramp_bounds`` keep the seed's values (a path scaled together with its
  speeds keeps its times).

A path passes when, at 16 IK nodes per segment (the coarse pass the build starts with), every
node is reachable inside the joint limits with the tool orientation, the joints never jump
branch (0.5 rad between nodes), every node keeps half the centre's dexterity for moves in the
plane and 2 % of every joint range free, and holding the arm still there needs at most 80 % of
each joint's torque limit against gravity.

Pre-flight (also for a path the user gives): the reach, the coarse IK of the path, the branch
jumps and the gravity torques, each a ``ValueError("segments.k: …")`` naming where; no
placement found → ``ValueError("segments: …")``. Cost: ~20-200 ms (cached per robot in
:func:`legcore.studies.fit.fit`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.dynamics import inverse_dynamics
from legcore.ik import solve
from legcore.robots.model import Robot
from legcore.studies.arm_workspace import (
    ArmWorkspace,
    Centre,
    arm_workspace,
    centres,
    dexterity,
    limit_margin,
)
from legcore.studies.path_tracking.joints import (
    _MIN_INTERVALS,
    ToolOrientation,
    _check_reach,
    _check_solution,
    _nodes,
)
from legcore.studies.path_tracking.kin import ArcLengthPath
from legcore.studies.path_tracking.params import (
    SEED_V,
    ArcSegment,
    LineSegment,
    Params,
)
from legcore.studies.task import Task

__all__ = ["LENGTHS", "capsule", "derive"]

FloatArray = NDArray[np.float64]

#: Capsule lengths tried, as fractions of the arm's reach (largest first).
LENGTHS = (0.4, 0.3, 0.2, 0.1)
#: The seed capsule's length (m) and total path length (m): 0.6 m across, 0.8 + 0.2π m around.
SEED_LENGTH = 0.6
SEED_PATH_LENGTH = 0.8 + 0.2 * math.pi
#: A node keeps this fraction of the centre's dexterity; of every joint range; of τ_max.
DEXTERITY_KEPT = 0.5
MARGIN_KEPT = 0.02
GRAVITY_SHARE = 0.8
#: Centres tried per orientation and length.
CENTRES_TRIED = 4
_FLIP = 0.5  # rad between coarse nodes: a branch jump


def capsule(length: float) -> tuple[ArcSegment | LineSegment, ...]:
    """Seed 004's capsule scaled to ``length`` (m across) and centred on (0, 0): arcs of radius
    length/6 about (±length/3, 0), lines at v = ±length/6, counter-clockwise from the lower
    right (the seed's (0.20, 0.20) m)."""
    k = length / SEED_LENGTH
    a, r = 0.2 * k, 0.1 * k
    return (
        ArcSegment(center=(a, 0.0), r=r, beta=-math.pi / 2, phi=math.pi),
        LineSegment(start=(a, r), end=(-a, r)),
        ArcSegment(center=(-a, 0.0), r=r, beta=math.pi / 2, phi=math.pi),
        LineSegment(start=(-a, -r), end=(a, -r)),
    )


@dataclass(frozen=True)
class _Layout:
    """One candidate task: path, tool, rest and what the check measured."""

    segments: tuple[Any, ...]
    origin: FloatArray
    e1: FloatArray
    e2: FloatArray
    tool: ToolOrientation
    orientation: str
    rest: FloatArray
    q: FloatArray  # coarse IK nodes (N, n)
    sigma: FloatArray  # their arc lengths (N,)
    length: float  # path length, m
    across: float  # the capsule's length across, m (0 for a given path)


def _orientations(ws: ArmWorkspace, params: Params) -> list[tuple[str, Any, str]]:
    """(orientation, tool_axis, words) candidates in the order tried."""
    if params.orientation is not None:
        axis = None if params.orientation == "free" else (
            tuple(ws.down) if params.orientation == "down" else params.tool_axis)
        return [(params.orientation, axis, "as given")]
    out: list[tuple[str, Any, str]] = [("down", tuple(ws.down), "down")]
    out.append(("axis", tuple(np.round(ws.forward, 12)), "forward (horizontal, away from the arm)"))
    out.append(("axis", tuple(ws.up), "up"))
    if params.tool_yaw is None:
        out.append(("free", None, "free"))
    return out


def _plane_axes(ws: ArmWorkspace, centre: FloatArray, normal: FloatArray) -> tuple[
        FloatArray, FloatArray]:
    """e1 across the arm (⊥ the radial direction and the normal), e2 = normal × e1 pointing away
    from the arm or up."""
    radial = ws.radial(centre)
    e1 = np.cross(radial, ws.up)
    e1 -= (e1 @ normal) * normal
    if np.linalg.norm(e1) < 1e-6:  # the normal is across the arm: e1 along the radial
        e1 = radial - (radial @ normal) * normal
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    if e2 @ (radial + ws.up) < 0.0:
        e1, e2 = -e1, -e2
    return e1, e2


def _coarse(robot: Robot, path: ArcLengthPath, tool: ToolOrientation, rest: FloatArray,
            *, raise_errors: bool) -> tuple[FloatArray, FloatArray] | None:
    """IK of the path's coarse nodes (16 per segment) from ``rest``: (q (N, n), σ (N,)), or
    None when a node is out of reach or the joints jump branch. ``raise_errors`` (a path the
    user gave): the ValueError of :mod:`.joints` for a node out of reach instead (the build's
    dense pass then names a branch jump or a singularity, as it always has)."""
    D = path.lengths
    sig, seg = _nodes(D, np.full(D.size, _MIN_INTERVALS))
    p = path.derivatives(sig)[0]
    try:
        _check_reach(robot, p, seg)
        sol = solve(robot, tool.targets(p), tool.task, q0=rest, rest=rest, path=True,
                    flip_tol=_FLIP)
        _check_solution(robot, tool, sol, seg, p, flips=not raise_errors)
    except ValueError:
        if raise_errors:
            raise
        return None
    return sol.q, sig


def _gravity(robot: Robot, q: FloatArray, path: ArcLengthPath, sigma: FloatArray, *,
             share: float) -> str | None:
    """Why holding the arm still at the nodes ``q`` (N, n) is beyond ``share`` of a joint's
    torque limit (a ``segments.k: …`` text), or None."""
    tau = np.abs(inverse_dynamics(robot, q, np.zeros_like(q), np.zeros_like(q)))
    use = tau / robot.tau_max
    if not np.any(use > share):
        return None
    i, j = (int(v) for v in np.unravel_index(int(np.argmax(use)), use.shape))
    k = int(np.searchsorted(np.cumsum(path.lengths)[:-1], sigma[i], side="right"))
    p = np.round(path.derivatives(sigma[i:i + 1])[0][0], 4).tolist()
    return (f"segments.{k}: holding the tool still at {p} m takes {tau[i, j]:.3g} N·m of joint "
            f"{robot.model.names[j + 1]} against gravity, {100 * use[i, j]:.0f} % of its limit "
            f"{robot.tau_max[j]:g} N·m (at most {100 * share:.0f} %); move the path")


def _rates(q: FloatArray, sigma: FloatArray) -> FloatArray:
    """|dq/dσ| (N−1, n) rad/m between consecutive coarse nodes of one segment or the next
    (the joins' zero-length steps left out)."""
    ds = np.diff(sigma)
    keep = ds > 0.0
    return np.abs(np.diff(q, axis=0)[keep]) / ds[keep, None]


def _speed_caps(robot: Robot, q: FloatArray, sigma: FloatArray) -> tuple[float, float]:
    """(slowest, fastest) over the coarse nodes of the largest tool speed (m/s) at which every
    joint keeps its speed limit there (finite differences of q(σ))."""
    rates = _rates(q, sigma)
    if rates.shape[0] == 0:
        return math.inf, math.inf
    with np.errstate(divide="ignore"):
        v = np.min(robot.qd_max / rates, axis=1)
    return float(v.min()), float(v.max())


def _search(robot: Robot, ws: ArmWorkspace, params: Params) -> tuple[_Layout, float, str]:
    """The first layout that passes (module docstring): (layout, centre dexterity, the
    orientation's words). ValueError("segments: …") when none does."""
    rest_given = None if params.rest is None else np.asarray(params.rest, dtype=float)
    lengths = [None] if params.segments is not None else [
        round(f * ws.reach, 3) for f in LENGTHS]
    tried: list[str] = []
    base_h = float(robot_base(robot) @ ws.up)
    for orientation, axis, words in _orientations(ws, params):
        tool = ToolOrientation(axis, params.tool_yaw)
        normal = (np.cross(params.plane_e1, params.plane_e2) if params.plane_e1 is not None
                  and params.plane_e2 is not None else ws.up if axis is None
                  else np.asarray(axis, dtype=float))
        cands: list[Centre]
        if params.plane_origin is not None:
            cands = [_centre_at(robot, ws, np.asarray(params.plane_origin, float), axis)]
        else:
            cands = [c for c in centres(robot, axis, normal)
                     if c.p @ ws.up >= base_h + 0.1 * ws.reach][:CENTRES_TRIED]
        if not cands:
            tried.append(f"{words}: held nowhere above the base")
            continue
        for length in lengths:
            for c in cands:
                e1, e2 = _plane_axes(ws, c.p, normal)
                if params.plane_e1 is not None and params.plane_e2 is not None:
                    e1, e2 = np.asarray(params.plane_e1, float), np.asarray(params.plane_e2, float)
                segs = capsule(length) if length is not None else params.segments or ()
                path = ArcLengthPath(tuple(s.curve() for s in segs),
                                     _plane(c.p, e1, e2))
                rest = c.q if rest_given is None else rest_given
                got = _coarse(robot, path, tool, rest, raise_errors=False)
                if got is None:
                    continue
                q, sig = got
                d = dexterity(robot, q, axis, ws.reach, np.stack([e1, e2], axis=1))
                if d.min() < DEXTERITY_KEPT * c.dexterity or \
                        limit_margin(robot, q).min() < MARGIN_KEPT:
                    continue
                if _gravity(robot, q, path, sig, share=GRAVITY_SHARE) is not None:
                    continue
                return (_Layout(segs, c.p, e1, e2, tool, orientation, rest, q, sig, path.length,
                                length or 0.0), c.dexterity, words)
        tried.append(f"{words}: no path passed")
    fixed = [f for f in ("orientation", "plane_origin", "plane_e1", "plane_e2", "rest")
             if getattr(params, f) is not None]
    what = ("seed 004's capsule" if params.segments is None else "the given segments") + (
        f" with the given {', '.join(fixed)}" if fixed else "")
    raise ValueError(
        f"segments: {what}, {', '.join(f'{f:g}' for f in LENGTHS)} × the reach of "
        f"{robot.name} ({ws.reach:.3g} m) long, fits in no well-conditioned part of its "
        f"workspace ({'; '.join(tried)}); give segments and their plane (plane_origin, "
        f"plane_e1, plane_e2) and orientation")


def robot_base(robot: Robot) -> FloatArray:
    """The robot's base origin (3,) in the world, m (its mounting point)."""
    from legcore.kinematics import frames

    return np.asarray(frames(robot, robot.home)[0][:3, 3])


def _centre_at(robot: Robot, ws: ArmWorkspace, p: FloatArray, axis: Any) -> Centre:
    """The given plane origin as a centre: a configuration holding ``axis`` there (from the
    best centre for that axis, else home), its dexterity in every direction."""
    best = centres(robot, axis)
    q0 = best[0].q if best else robot.home
    task = "position" if axis is None else "axis"
    target = p if axis is None else np.concatenate([p, np.asarray(axis, float)])
    sol = solve(robot, target, task, q0=q0, rest=q0)
    q = sol.q if bool(sol.reachable) else robot.home
    return Centre(np.asarray(q, float), p, None if axis is None else np.asarray(axis, float),
                  float(dexterity(robot, q, axis, ws.reach)), float(limit_margin(robot, q)))


def _plane(origin: FloatArray, e1: FloatArray, e2: FloatArray) -> Any:
    from legcore.trajectories.paths import Plane

    return Plane(np.asarray(origin, float), np.asarray(e1, float), np.asarray(e2, float))


def _vec(v: FloatArray) -> str:
    return "(" + ", ".join(f"{x:.3f}" for x in np.asarray(v, float)) + ")"


def derive(robot: Any, params: Params) -> Task:
    """The robot-relative fields of ``params`` that are None, by the rules of the module
    docstring, and the pre-flight check of the whole task (``ValueError("<field>: …")``)."""
    if not isinstance(robot, Robot):  # a legged robot is refused by the study's needs
        return Task(params, {})
    ws = arm_workspace(robot)
    rules: dict[str, str] = {}
    values: dict[str, Any] = {}
    layout_given = None not in (params.segments, params.plane_origin, params.plane_e1,
                                params.plane_e2, params.orientation)
    if layout_given:
        path = ArcLengthPath(tuple(s.curve() for s in params.segments or ()), params.plane())
        tool = params.tool()
        rest = robot.home if params.rest is None else np.asarray(params.rest, dtype=float)
        if rest.shape != (robot.nq,):
            raise ValueError(f"rest: {rest.size} values for the {robot.nq} joints of "
                             f"{robot.name}")
        got = _coarse(robot, path, tool, rest, raise_errors=True)
        assert got is not None
        q, sig = got
        why = _gravity(robot, q, path, sig, share=1.0)
        if why is not None:
            raise ValueError(why)
        if np.any(np.isnan(q)) or np.any(np.abs(np.diff(q, axis=0)) > _FLIP):
            q, sig = q[:1], sig[:1]  # a jump: the build names it; no speed from these nodes
        length = path.length
    else:
        lay, d_centre, words = _search(robot, ws, params)
        q, sig, length = lay.q, lay.sigma, lay.length
        if params.orientation is None:
            values["orientation"] = lay.orientation
            if lay.orientation == "axis":
                values["tool_axis"] = tuple(float(v) for v in lay.tool.axis or ())
            rules["orientation"] = (
                f"{words}: the first of down, forward, up, free that {robot.name} holds along "
                f"the whole path")
        if params.plane_origin is None:
            values["plane_origin"] = tuple(float(v) for v in np.round(lay.origin, 6))
            rel = lay.origin - ws.shoulder
            height = float(rel @ ws.up)
            rho = float(np.linalg.norm(rel - height * ws.up))
            rules["plane_origin"] = (
                f"{_vec(lay.origin)} m, {rho:.3f} m from the base axis and {height:+.3f} m "
                f"above the shoulder: the most dexterous posture holding the tool orientation "
                f"(dexterity {d_centre:.3f}; every joint range ≥ 10 % free; ≥ 0.1 × reach "
                f"above the base) whose whole path passes the check")
        if params.plane_e1 is None or params.plane_e2 is None:
            values["plane_e1"] = tuple(float(v) for v in lay.e1)
            values["plane_e2"] = tuple(float(v) for v in lay.e2)
            rules["plane_e1"] = (f"{_vec(lay.e1)}: across the arm, in the plane normal to "
                                 f"the tool axis (horizontal for a free orientation)")
            rules["plane_e2"] = f"{_vec(lay.e2)}: normal × e1, away from the arm (or up)"
        if params.segments is None:
            values["segments"] = tuple(s.model_dump() for s in lay.segments)
            rules["segments"] = (
                f"seed 004's capsule scaled to {lay.across:.3f} m across "
                f"({lay.across / ws.reach:.1f} × the reach {ws.reach:.3f} m; the seed: 0.6 m "
                f"on its 1 m arm), {length:.3f} m around: the largest of "
                f"{', '.join(f'{f:g}' for f in LENGTHS)} × reach that passes the check")
        if params.rest is None:
            values["rest"] = tuple(float(v) for v in lay.rest)
            rules["rest"] = "the centre's posture: the IK follows its branch"
    v_slow, v_fast = _speed_caps(robot, q, sig)
    if params.V is None:
        v_seed = SEED_V * length / SEED_PATH_LENGTH
        V = float(min(v_seed, 0.5 * v_slow))
        V = float(f"{V:.3g}")
        values["V"] = V
        rules["V"] = (f"{V:.3g} m/s: the seed's 0.10 m/s × path length {length:.3f} / "
                      f"{SEED_PATH_LENGTH:.3f} m = {v_seed:.3g} m/s, at most half the "
                      f"{v_slow:.3g} m/s at which every joint keeps its speed limit everywhere "
                      f"on the path")
    else:
        V = float(params.V)
    if params.V_bounds is None:
        lo, hi = float(f"{V / 10:.3g}"), float(f"{10 * V:.3g}")
        values["V_bounds"] = (lo, hi)
        rules["V_bounds"] = (
            f"({lo:.3g}, {hi:.3g}) m/s = (V/10, 10 V): the seed's box (0.01, 1.0) m/s about its "
            f"0.10 m/s; each segment's bound is lowered further to the fastest speed its joint "
            f"speed limits allow ({v_fast:.3g} m/s at most on this path)")
    if not values:
        return Task(params, rules)
    new = Params.model_validate({**params.model_dump(exclude_unset=True), **values})
    return Task(new, rules)
