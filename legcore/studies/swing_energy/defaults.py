"""Robot-relative defaults of ``swing_energy`` and its pre-flight check: ``derive(robot, params)``.

The swing is a *step in body axes*: the foot moves forward along the body's forward axis from
half a step behind a nominal stance to half a step ahead of it, at the stance's height, lifted
in between. Every value the user leaves out is derived from the leg by these rules (``Task.rules``
says which rule gave each value, with the numbers); a value the user gives is used as given.

Leg (``leg``)
    A legged robot swings its first front leg (:func:`~.stance.front_leg`: of the legs whose
    hips lie furthest forward along the body's forward axis — ``meta["forward"]``, else x —
    within 1 mm, the first in the robot's order; the leg's base frame is its hip). A serial chain
    is the leg; its base frame is taken as the body frame (x forward, z up).

Leg length ``L``
    The stretched leg below the hip: the largest distance from the hip's pitch joint (the second
    joint; the first of a 2-joint leg) to the foot, joint limits ignored
    (:func:`~.stance.leg_length`; Solo12 0.323 m, ANYmal B 0.593 m, Go1 0.426 m, seed 000's
    leg ``L₀`` = 0.225 m).

Nominal stance
    The foot under the hip's pitch joint (its forward coordinate in the home posture), at the
    lateral offset the foot has in the home posture (the leg's own sideways offset), ``0.7 L``
    from that joint — at most 45° out from under it: a leg that reaches out sideways at home
    (seed 000's, a hexapod's) stands with its foot 45° below and out from that joint. If the
    stance or a step end is out of reach inside the joint limits, or near a singular posture
    (the foot Jacobian's smallest singular value < 0.05 L m/rad), the nearest fraction of
    0.5–0.9 L (steps of 0.05) that works is taken. The posture is on the leg's own knee branch
    (:func:`~.stance.branch_of`): the only branch the IK finds inside the joint limits (Go1),
    else the bend of its home posture (ANYmal B: a front knee behind, a rear knee ahead), else —
    a straight home posture (Solo12) — the convention of ``quadruped_gait``: the knee toward the
    body's centre (a front leg's behind the hip–foot line, a rear leg's ahead; a serial chain's
    behind; for a leg bending sideways, up).

Step (``q_start``/``q_end``, ``exact_ends``)
    Start = stance − ½ s · forward, end = stance + ½ s · forward (same height and lateral
    offset), step length ``s = 0.5 L``; solved by IK on the same branch, nearest the stance
    posture, and given as joint values kept exactly (``exact_ends`` true) so that the foot
    starts and ends on the step to 1e-9 m. With one end given, the other is one step ahead of
    (behind) it, on the given end's branch.

Lengths (``step_height``, ``obstacle``)
    The parabolic baseline's apex ``0.2 L``; the ``obstacle: true`` box is seed 000's
    60 × 40 × 26 mm box with its 2 mm margin scaled by ``L / L₀``.

Per joint and search (``w_d``, ``w_a``, ``search_range``, ``tube``, ``lift_only``)
    Equal link weights 1/n; a search range of 0.3 rad per joint. The search is centred on the
    coordinated motion (seed 000) unless that dips into the ground or an obstacle — a forward
    step of a knee leg does, its joints' straight line sags — then on the shortest foot path
    that clears them, with two-sided deviations.

Not a leg
    With neither end given, a chain of 5–6 joints whose end does not hang at least ``L/4`` below
    its hip's (shoulder's) pitch joint in its home posture (UR5, Kinova, Z1, SO-100) is an arm
    and is refused naming ``foot_start``: there is no stance to step from; give
    ``foot_start``/``foot_end`` (or ``q_start``/``q_end``).

Seed 000's own leg (``calderon_leg``) takes its settings from its preset
(:mod:`legcore.studies.swing_energy.preset`); only the ``obstacle: true`` box is derived there
(exactly the seed's: ``L = L₀``).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from legcore.chain_points import chain_points
from legcore.kinematics import fk
from legcore.robots.legged import LeggedRobot
from legcore.robots.model import Robot
from legcore.studies.swing_energy.geometry import chain_clearance
from legcore.studies.swing_energy.params import GENERIC_SEARCH_RANGE, Obstacle, Params
from legcore.studies.swing_energy.setup import boxes, configuration, swing_leg
from legcore.studies.swing_energy.stance import (
    Branch,
    bend,
    branch_of,
    front_leg,
    hip_index,
    joint_origins,
    knee_toward_centre,
    leg_forward,
    leg_length,
    reference_posture,
    sigma_min,
    solve_on_branch,
)
from legcore.studies.task import Task, fill

__all__ = [
    "ARM_JOINTS",
    "FRACTIONS",
    "LIFT",
    "NOT_A_LEG",
    "SEED_BOX",
    "SEED_LEG",
    "SEED_MARGIN",
    "SINGULAR",
    "STEP_LENGTH",
    "Step",
    "derive",
    "coordinated_violates",
    "ik_reference",
    "leg_length_of",
    "nominal_step",
]

FloatArray = NDArray[np.float64]

#: The stance's distance from the hip (× L): the nominal one first, then the fallbacks.
FRACTIONS = (0.7, 0.65, 0.75, 0.6, 0.8, 0.55, 0.85, 0.5, 0.9)
#: A posture whose foot Jacobian has a singular value below this (× L, m/rad) is singular.
SINGULAR = 0.05
#: A chain of this many joints or more whose end does not hang at least NOT_A_LEG × L below
#: its hip's (shoulder's) pitch joint in its home posture is an arm.
ARM_JOINTS = 5
NOT_A_LEG = 0.25
#: The step length and the parabolic baseline's apex (× L).
STEP_LENGTH = 0.5
LIFT = 0.2
#: Seed 000's leg and its box (m), scaled to a leg by L / L₀.
SEED_LEG = "calderon_leg"
SEED_BOX = (0.060, 0.040, 0.026)
SEED_MARGIN = 0.002
_UP = np.array([0.0, 0.0, 1.0])
_LENGTHS: dict[str, float] = {}


def leg_length_of(chain: Robot) -> float:
    """:func:`~.stance.leg_length` of ``chain``, cached per model (m)."""
    key = chain.spec.model_dump_json() + f"\0{chain.tool_frame}"
    L = _LENGTHS.get(key)
    if L is None:
        L = leg_length(chain)
        if len(_LENGTHS) >= 64:
            _LENGTHS.clear()
        _LENGTHS[key] = L
    return L


@functools.cache
def _seed_length() -> float:
    from legcore.robots import catalog

    seed = catalog.get(SEED_LEG)
    assert isinstance(seed, Robot)
    return leg_length_of(seed)


def _v(p: FloatArray) -> str:
    return "(" + ", ".join(f"{round(float(c), 9) + 0.0:.4g}" for c in p) + ")"


@dataclass(frozen=True, eq=False)
class Step:
    """The nominal step of a leg (module docstring), all in its base frame (m, rad):
    ``stance`` (3,), ``fraction`` (its distance from the hip, × L), ``branch``, ``q_stance``,
    ``start``/``end`` (3,) foot positions and ``q_start``/``q_end`` (n,), ``length`` (m)."""

    stance: FloatArray
    fraction: float
    branch: Branch
    q_stance: FloatArray
    start: FloatArray
    end: FloatArray
    q_start: FloatArray
    q_end: FloatArray
    length: float


def nominal_step(chain: Robot, forward: FloatArray, L: float, label: str, prefer: int = 1
                 ) -> Step:
    """The leg's nominal step (module docstring), or ``ValueError("foot_start: …")`` when it
    has none (an arm; no stance 0.5–0.9 L below the hip reachable inside the limits)."""
    home = np.clip(np.asarray(chain.home, dtype=float), chain.q_min, chain.q_max)
    foot = fk(chain, home)[:3, 3]
    hip = joint_origins(chain, home)[0, hip_index(chain)]
    if chain.nq >= ARM_JOINTS and foot[2] > hip[2] - NOT_A_LEG * L:
        where = "above" if foot[2] > hip[2] else "below"
        raise ValueError(
            f"foot_start: {label} is an arm, not a leg: {chain.nq} joints, its end "
            f"{abs(foot[2] - hip[2]):.3g} m {where} its shoulder in its home posture (a leg's "
            f"foot hangs at least L/4 = {NOT_A_LEG * L:.3g} m below its hip, L = {L:.3g} m): "
            "there is no stance to step from; give foot_start and foot_end (m, in its base "
            "frame) or q_start and q_end")
    lateral = np.cross(_UP, forward)
    y_foot = float(foot @ lateral)
    dy = y_foot - float(hip @ lateral)
    s = STEP_LENGTH * L
    tried = []
    for frac in FRACTIONS:
        r = frac * L
        side = math.copysign(min(abs(dy), r * math.sqrt(0.5)), dy)  # at most 45° out
        depth = math.sqrt(r * r - side * side)
        y_stance = float(hip @ lateral) + side
        stance = float(hip @ forward) * forward + y_stance * lateral + (hip[2] - depth) * _UP
        tried.append(f"{frac:g}")
        got = branch_of(chain, stance, forward, L, prefer)
        if got is None or sigma_min(chain, got[1]) < SINGULAR * L:
            continue
        branch, q_s = got
        start, end = stance - 0.5 * s * forward, stance + 0.5 * s * forward
        q_a = solve_on_branch(chain, start, branch, q_s, forward, L)
        q_b = solve_on_branch(chain, end, branch, q_s, forward, L)
        if q_a is None or q_b is None or min(sigma_min(chain, q_a),
                                             sigma_min(chain, q_b)) < SINGULAR * L:
            continue
        return Step(stance, frac, branch, q_s, start, end, q_a, q_b, s)
    raise ValueError(
        f"foot_start: {label} has no nominal step: with the foot {', '.join(tried)} × L "
        f"(L = {L:.3g} m) from its hip's pitch joint, under it and {dy:.3g} m to its side, the "
        f"stance or a step end {s:.3g} m long is out of reach inside the joint limits or "
        "singular; give foot_start and foot_end (m, in the leg's base frame) or q_start and "
        "q_end")


def ik_reference(robot: object, params: Params, chain: Robot) -> FloatArray:
    """The posture the IK of a given foot position starts from: the leg's own branch
    (:func:`~.stance.reference_posture`)."""
    L = leg_length_of(chain)
    forward = leg_forward(robot, params.leg, L)
    prefer = knee_toward_centre(robot, params.leg)
    return reference_posture(chain, forward, L, prefer)[0]


def _ends(robot: object, params: Params, chain: Robot, label: str, values: dict[str, Any],
          rules: dict[str, str]) -> tuple[FloatArray, FloatArray]:
    """Fill ``q_start``/``q_end`` (and ``exact_ends``) when not given; check the given ends.
    Returns the start and end configurations (n,) rad as the problem will use them."""
    L = leg_length_of(chain)
    forward = leg_forward(robot, params.leg, L)
    res = float(params.resolution)
    start_given = params.q_start is not None or params.foot_start is not None
    end_given = params.q_end is not None or params.foot_end is not None
    exact = bool(params.exact_ends) if params.exact_ends is not None else not (
        start_given and end_given)
    fwd = _v(forward)
    if not start_given and not end_given:
        st = nominal_step(chain, forward, L, label, knee_toward_centre(robot, params.leg))
        values["q_start"] = tuple(float(v) for v in st.q_start)
        values["q_end"] = tuple(float(v) for v in st.q_end)
        q_s, q_e = st.q_start, st.q_end
        stance = (f"nominal stance {_v(st.stance)} m (the foot under the hip's pitch joint "
                  f"along the forward axis {fwd}, at its home lateral offset (at most 45° out), "
                  f"{st.fraction:g} × L"
                  f" = {st.fraction * L:.4g} m from the joint, L = {L:.4g} m the stretched leg), "
                  f"knee branch: {st.branch.why}")
        for end, p, q in (("start", st.start, st.q_start), ("end", st.end, st.q_end)):
            sign = "behind" if end == "start" else "ahead of"
            rules[f"q_{end}"] = (
                f"foot at {_v(p)} m, half a step ({st.length / 2:.4g} m) {sign} the {stance}; "
                f"q_{end} = {_v(q)} rad by IK on that branch")
    elif start_given != end_given:
        ref = ik_reference(robot, params, chain)
        which, other = ("start", "end") if start_given else ("end", "start")
        q_given, _ = configuration(chain, which, getattr(params, f"q_{which}"),
                                   getattr(params, f"foot_{which}"), ref, res, exact)
        p = fk(chain, q_given)[:3, 3]
        s = STEP_LENGTH * L
        target = p + (s if which == "start" else -s) * forward
        b = float(bend(chain, q_given, forward)[0])
        branch = Branch(1 if b >= 0 else -1, q_given, "the given end's")
        q_other = solve_on_branch(chain, target, branch, q_given, forward, L)
        if q_other is None:
            raise ValueError(
                f"foot_{other}: one step ({s:.3g} m = {STEP_LENGTH:g} L, L = {L:.3g} m) "
                f"{'ahead of' if which == 'start' else 'behind'} the given {which}, the foot at "
                f"{_v(target)} m is out of reach of {label} inside its joint limits; give "
                f"foot_{other} or q_{other}")
        values[f"q_{other}"] = tuple(float(v) for v in q_other)
        q_s, q_e = (q_given, q_other) if which == "start" else (q_other, q_given)
        rules[f"q_{other}"] = (
            f"foot at {_v(target)} m, one step ({s:.4g} m = {STEP_LENGTH:g} L, L = {L:.4g} m) "
            f"{'ahead of' if which == 'start' else 'behind'} the given {which} along the forward "
            f"axis {fwd}; q_{other} = {_v(q_other)} rad by IK on the given end's knee branch")
    else:  # both given: the pre-flight check of the problem's own set-up
        ref = ik_reference(robot, params, chain) if (
            params.foot_start is not None or params.foot_end is not None) else chain.home
        q_s, _ = configuration(chain, "start", params.q_start, params.foot_start, ref, res,
                               exact)
        q_e, _ = configuration(chain, "end", params.q_end, params.foot_end, q_s, res, exact)
    if params.exact_ends is None:
        values["exact_ends"] = exact
        rules["exact_ends"] = (
            "true: the derived end is kept exactly (not rounded onto the control grid), so the "
            "foot starts and ends on the step" if exact else
            "false: the given ends are rounded onto the control grid (seed 000)")
    return q_s, q_e


def _lengths(robot: object, params: Params, chain: Robot, values: dict[str, Any],
             rules: dict[str, str]) -> Obstacle | None:
    """``step_height`` (0.2 L) and the ``obstacle: true`` box (seed 000's × L / L₀)."""
    box = params.box
    sizes = ("length", "width", "height", "margin")
    need_box = box is not None and any(getattr(box, k) is None for k in sizes)
    if params.step_height is None:
        L = leg_length_of(chain)
        values["step_height"] = LIFT * L
        rules["step_height"] = f"{LIFT:g} × L = {LIFT * L:.4g} m (L = {L:.4g} m the stretched leg)"
    if not need_box:
        return None
    assert box is not None
    L, L0 = leg_length_of(chain), _seed_length()
    k = L / L0
    seed = dict(zip(sizes, (*SEED_BOX, SEED_MARGIN), strict=True))
    box = box.model_copy(update={n: seed[n] * k for n in sizes if getattr(box, n) is None})
    rules["obstacle"] = (
        f"{' × '.join(f'{1e3 * getattr(box, n):.3g}' for n in sizes[:3])} mm box, "
        f"{1e3 * float(box.margin or 0.0):.3g} mm margin: seed 000's 60 × 40 × 26 mm box "
        f"(2 mm margin) scaled by L / L₀ = {k:.4g} (L = {L:.4g} m, L₀ = {L0:.4g} m seed 000's "
        "leg)")
    return box


def coordinated_violates(chain: Robot, params: Params, q_s: FloatArray, q_e: FloatArray
                         ) -> str | None:
    """What the coordinated motion (the rest-to-rest cubic from ``q_s`` to ``q_e``, 61 samples)
    violates — ``"dips 12.3 mm below the ground"``, ``"enters the obstacle 4 mm deep"`` — or
    None (the ground and boxes of the problem, :mod:`.setup`)."""
    tau = np.linspace(0.0, 1.0, 61)[:, None]
    q = q_s + (q_e - q_s) * (3.0 * tau**2 - 2.0 * tau**3)
    P = chain_points(chain, q, tool=True)[None]  # (1, K, M, 3)
    feet = fk(chain, np.stack([q_s, q_e]))[:, :3, 3]
    z_ground = (float(feet[:, 2].min()) if params.ground_height is None
                else float(params.ground_height))
    box = params.box
    found, margins = boxes(box if box is not None and None not in (
        box.length, box.width, box.height, box.margin) else None,
        params.obstacles, feet[0], feet[1], z_ground)
    if found:
        c = np.array([b.center for b in found])
        h = np.array([np.asarray(b.half_size) + m for b, m in zip(found, margins, strict=True)])
        depth, z_min = chain_clearance(P, c, h)
    else:
        depth, z_min = chain_clearance(P)
    dip = z_ground - params.ground_tolerance - float(z_min[0])
    if params.ground and dip > 0.0:
        return f"dips {1e3 * (dip + params.ground_tolerance):.3g} mm below the ground"
    if depth[0] > 0.0:
        return f"enters an obstacle {1e3 * depth[0]:.3g} mm deep"
    return None


def _tube(params: Params, chain: Robot, q_s: FloatArray, q_e: FloatArray,
          values: dict[str, Any], rules: dict[str, str]) -> None:
    """``tube`` and ``lift_only``: around the shortest foot path that clears the ground when the
    coordinated motion violates the ground or an obstacle, else around the coordinated motion
    (seed 000)."""
    tube = params.tube
    if tube is None:
        why = coordinated_violates(chain, params, q_s, q_e)
        tube = "shortest" if why is not None else "coordinated"
        values["tube"] = tube
        rules["tube"] = (
            f"shortest: the coordinated motion (the joints' straight line) {why}; the search is "
            "centred on the shortest foot path that clears it" if why is not None else
            "coordinated: the coordinated motion (the joints' straight line) clears the ground "
            "and obstacles (seed 000)")
    if params.lift_only is None:
        values["lift_only"] = tube == "coordinated"
        rules["lift_only"] = ("true: around the coordinated motion the lifting joints deviate "
                              "only upward (seed 000)" if tube == "coordinated" else
                              "false: around the shortest path a joint may deviate either way "
                              "(the ground constraint refuses what dips)")


def derive(robot: object, params: Params) -> Task:
    """``params`` made concrete for ``robot`` (module docstring), with the rule of each derived
    value; ``ValueError("<field>: …")`` when the swing cannot work on this robot."""
    values: dict[str, Any] = {}
    rules: dict[str, str] = {}
    if isinstance(robot, LeggedRobot) and params.leg is None:
        values["leg"], rules["leg"] = front_leg(robot)
        params = fill(params, values)
    chain, label = swing_leg(robot, params)
    g = chain.chain.gravity
    if not np.allclose(g / max(float(np.linalg.norm(g)), 1e-300), [0.0, 0.0, -1.0], atol=1e-6):
        raise ValueError(f"robot: swing_energy needs the leg's base frame with z up (gravity "
                         f"along -z); {label} has gravity {g.round(4).tolist()}")
    n = chain.nq
    for name in ("w_d", "w_a", "search_range"):
        value = getattr(params, name)
        if value is None:
            generic = GENERIC_SEARCH_RANGE if name == "search_range" else 1.0 / n
            values[name] = (generic,) * n
            rules[name] = (f"{generic:.4g} rad per joint" if name == "search_range" else
                           f"1/n = {generic:.4g} per joint (equal link weights)")
        elif len(value) != n:
            raise ValueError(f"{name}: {len(value)} values for a leg of {n} joints; give one "
                             "per joint")
    q_s, q_e = _ends(robot, params, chain, label, values, rules)
    box = _lengths(robot, params, chain, values, rules)
    out = fill(params, values)
    if box is not None:
        out = type(out).model_validate({**out.model_dump(exclude_unset=True),
                                        "obstacle": box.model_dump()})
    values.clear()
    _tube(out, chain, q_s, q_e, values, rules)
    return Task(fill(out, values), rules)
