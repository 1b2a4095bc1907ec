"""The robot-relative defaults of ``quadruped_gait`` and its pre-flight check (DESIGN §5: a gait
is scaled by the leg length so that it is statically feasible on any quadruped that can stand).

``derive(robot, params) -> Task`` fills every robot-relative field left unset (None), by these
rules, recording each with its numbers in ``Task.rules`` (SI units):

* **leg length** L: the shortest leg's length, a leg's length being the greatest depth below its
  hip at which its foot can stand under the hip (at its lateral offset λ) inside the joint
  limits — the leg stretched (:func:`~legcore.studies.quadruped_gait.stance.leg_length`); λ is
  the foot's lateral offset at the leg's home posture (or ``foot_lateral``, or at a given
  ``q_ref``);
* ``depth`` H = 0.75 L (the body carried at three quarters of its stretched height: knees well
  bent, feet far from the edge of reach);
* ``q_ref``: each leg's standing posture with the foot at the stroke centre, H below the hip,
  its knee toward the body centre where the joint limits allow it (else on the side they
  allow), nearest the leg's home (:func:`~legcore.studies.quadruped_gait.stance.
  standing_posture`). No such posture: refused (``depth``);
* ``stroke_center`` c: the whole robot's centre of mass (body + legs standing) ahead of the
  hips' centre, so the feet's support pattern is centred under it (Go1's knees, all behind the
  feet, put it 10 mm behind the hips);
* ``step_length`` s = 0.4 L within ``step_length_bounds`` [0.1 L, 0.6 L]; ``step_height``
  h = 0.1 L within ``step_height_bounds`` [0.05 L, 0.2 L] (seed 003's robot walks s = 0.67 L,
  h = 0.17 L; a stride s/β = 0.5 L is what animals walk at this speed, Alexander 1984);
* ``speed``: Froude number Fr = v² / (g L) = 0.01, i.e. v = 0.1 √(g L) — a slow walk (animals
  change from walk to trot near Fr = 0.5) — lowered, when the default step would need more,
  until its peak joint speed is half the joint's limit (the search box's other steps need the
  rest). On seed 003's servos the rule gives 0.029 m/s; the paper's value is 0.03 m/s;
* ``stability_margin``: 0.25 % of L (≈ 1 mm on a 0.4 m leg); the default step at duty 0.8
  keeps 0.58–0.82 % of L on seed 003's robot, Solo12, ANYmal, Go1 and five more quadrupeds
  of example-robot-data.

Pre-flight (``ValueError("<field>: <why>; <what to change>")``, before anything is queued; one
evaluation of the default step, ~10–50 ms): refused when no leg reaches below its hip
(``robot``), a leg has no standing posture at the depth (``depth``), the default step puts a
stance foot out of reach (``step_length``; also without simulating, by geometry, a step longer
than any stroke the legs can make); and, when the user gave none of the gait's fields (so the
defaults are the rules'), when the default step is not feasible: a swing foot out of reach
(``step_height``), the margin (``stability_margin``), a foot pulling on the ground
(``stroke_center``), a joint over its speed (``speed``) or torque limit (``depth``). A value the
user gives is used as given: a given gait whose default step is infeasible with its stance
stroke in reach runs, and its result says what its baseline violates (seed 003 at duty 0.2
walks airborne on purpose).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from legcore.robots.legged import LeggedRobot
from legcore.studies.quadruped_gait.feasibility import StepReport, step_report
from legcore.studies.quadruped_gait.legs import GaitLeg, gait_legs
from legcore.studies.quadruped_gait.params import ROBOT_RELATIVE, Params
from legcore.studies.quadruped_gait.stance import (
    LegStance,
    length_bound,
    robot_com,
    shallowest_depth,
    standing_posture,
)
from legcore.studies.quadruped_gait.stance import leg_length as stance_leg_length
from legcore.studies.task import Task

__all__ = [
    "DEPTH_FRACTION",
    "FROUDE",
    "GAIT_FIELDS",
    "HEIGHT_BOUNDS",
    "HEIGHT_FRACTION",
    "JOINT_SPEED_SHARE",
    "MARGIN_FRACTION",
    "STEP_BOUNDS",
    "STEP_FRACTION",
    "derive",
    "leg_length",
]

DEPTH_FRACTION = 0.75
STEP_FRACTION = 0.4
STEP_BOUNDS = (0.1, 0.6)
HEIGHT_FRACTION = 0.1
HEIGHT_BOUNDS = (0.05, 0.2)
FROUDE = 0.01
JOINT_SPEED_SHARE = 0.5
MARGIN_FRACTION = 0.0025

#: The fields that shape the default step: when the user gives none, the default step is the
#: rules' and must be feasible (pre-flight).
GAIT_FIELDS = (*ROBOT_RELATIVE, "duty", "q_ref", "foot_lateral", "com_offset", "swing_points",
               "stance_load")


def _mm(v: float) -> str:
    return f"{v * 1e3:.3g} mm"


def _legs_length(legs: tuple[GaitLeg, ...]) -> tuple[float, str]:
    """(L, the shortest leg's name); L in m, rounded to 0.1 mm."""
    lengths = {g.name: stance_leg_length(g.leg, g.lateral) for g in legs}
    name = min(lengths, key=lambda n: lengths[n])
    return round(lengths[name], 4), name


def leg_length(robot: LeggedRobot) -> float:
    """The quadruped's leg length L (m) the rules scale by (module docstring), with each foot at
    its lateral offset at the leg's home posture."""
    return _legs_length(gait_legs(robot, None, None))[0]


def _stand(legs: tuple[GaitLeg, ...], H: float, c: float,
           given: dict[str, tuple[float, ...]], depth_given: bool) -> dict[str, LegStance]:
    """Each leg not in ``given`` standing with its foot c ahead of and H below its hip."""
    out: dict[str, LegStance] = {}
    for g in legs:
        if g.name in given:
            continue
        target = g.leg.hip[:3, 3] + np.array([c, g.lateral, -H])
        st = standing_posture(g, target)
        if st is None:
            lo = shallowest_depth(g.leg, g.lateral, c)
            hi = stance_leg_length(g.leg, g.lateral, c)
            which = "the given" if depth_given else f"the default ({DEPTH_FRACTION} × L)"
            where = ("it reaches no point under its hip" if math.isnan(lo) else
                     f"under its hip it stands from {lo:.4g} m (folded) to {hi:.4g} m "
                     "(stretched) below it")
            raise ValueError(
                f"depth: leg {g.name} cannot stand with its foot {H:.4g} m below its hip "
                f"({which} depth) inside its joint limits; {where}: give a depth in that "
                "range")
        out[g.name] = st
    return out


def derive(robot: Any, params: Params) -> Task:
    """``params`` with every unset robot-relative field derived from ``robot`` (module
    docstring), the rule of each in ``Task.rules``; ``ValueError`` naming the field when the
    task cannot work on this robot."""
    if not isinstance(robot, LeggedRobot):
        raise ValueError("robot: quadruped_gait needs a legged robot")
    unset = {f for f in ROBOT_RELATIVE if getattr(params, f) is None}
    given_q = dict(params.q_ref or {})
    legs = gait_legs(robot, params.q_ref, params.foot_lateral)
    L, shortest = _legs_length(legs)
    if L <= 0.0:
        raise ValueError(f"robot: no foot of {robot.name} reaches below its hip inside the "
                         "joint limits; quadruped_gait needs legs that can stand")
    words = (f"leg length L = {L:.4g} m (leg {shortest} stretched: the deepest its foot "
             "reaches under its hip inside the joint limits)")
    values: dict[str, Any] = {}
    rules: dict[str, str] = {}
    H = params.depth if params.depth is not None else DEPTH_FRACTION * L
    if params.depth is None:
        values["depth"] = H
        rules["depth"] = f"{DEPTH_FRACTION} × {words} = {H:.4g} m below the hips"
    depth_given = params.depth is not None
    # standing postures and the stroke centre under the whole robot's COM
    c = params.stroke_center if params.stroke_center is not None else 0.0
    stances = _stand(legs, H, c, given_q, depth_given)
    if params.stroke_center is None:
        com = _com(robot, legs, params, given_q, stances)
        hips_x = float(np.mean([g.leg.hip[0, 3] for g in legs]))
        c = round(float(com[0] - hips_x), 4) + 0.0  # 0.1 mm; no −0
        stances = _stand(legs, H, c, given_q, depth_given)
        values["stroke_center"] = c
        where = ("at" if c == 0.0 else f"{_mm(abs(c))} ahead of" if c > 0.0
                 else f"{_mm(abs(c))} behind")
        rules["stroke_center"] = (
            f"the whole robot's centre of mass, standing, is {where} the hips' centre: the "
            f"strokes are centred under it, c = {c:.4g} m")
    if any(g.name not in given_q for g in legs):
        values["q_ref"] = {**given_q, **{n: tuple(float(v) for v in st.q)
                                         for n, st in stances.items()}}
        rules["q_ref"] = (f"standing postures with the feet {H:.4g} m below the hips: "
                          + "; ".join(st.words() for st in stances.values()))
    for name, frac, what in (("step_length", STEP_FRACTION, "L"),
                             ("step_height", HEIGHT_FRACTION, "L")):
        if name in unset:
            values[name] = frac * L
            rules[name] = f"{frac} × {what} ({L:.4g} m) = {frac * L:.4g} m"
    for name, (lo, hi) in (("step_length_bounds", STEP_BOUNDS),
                           ("step_height_bounds", HEIGHT_BOUNDS)):
        if name in unset:
            values[name] = (lo * L, hi * L)
            rules[name] = f"[{lo}, {hi}] × L ({L:.4g} m) = [{lo * L:.4g}, {hi * L:.4g}] m"
    if "stability_margin" in unset:
        values["stability_margin"] = MARGIN_FRACTION * L
        rules["stability_margin"] = (f"{MARGIN_FRACTION:.2%} of L ({L:.4g} m) = "
                                     f"{_mm(MARGIN_FRACTION * L)}")
    g_acc = float(np.linalg.norm(legs[0].leg.robot.chain.gravity))
    v0 = math.sqrt(FROUDE * g_acc * L)
    if "speed" in unset:
        values["speed"] = v0
    full = _with(params, values)
    _check_reach(full, legs, robot)
    report = _report(robot, full)
    if "speed" in unset:
        rule = (f"Froude number v²/(g L) = {FROUDE}: v = {math.sqrt(FROUDE):.2g} √({g_acc:.3g} "
                f"× {L:.4g}) = {v0:.4g} m/s")
        if report.qd_ratio > JOINT_SPEED_SHARE:
            v = v0 * JOINT_SPEED_SHARE / report.qd_ratio
            full = _with(full, {"speed": v})
            report = _report(robot, full)
            rule += (f", lowered to {v:.4g} m/s so that the default step's fastest joint "
                     f"({report.qd_joint}) runs at {JOINT_SPEED_SHARE:.0%} of its limit "
                     f"{report.qd_limit:.4g} rad/s")
        rules["speed"] = rule
    _check_default_step(full, report, params)
    return Task(full, rules)


def _with(params: Params, values: dict[str, Any]) -> Params:
    """``params`` with ``values`` set (validated)."""
    return Params.model_validate({**params.model_dump(exclude_unset=True), **values})


def _com(robot: LeggedRobot, legs: tuple[GaitLeg, ...], params: Params,
         given_q: dict[str, tuple[float, ...]], stances: dict[str, LegStance]) -> Any:
    postures = {g.name: np.asarray(given_q[g.name], dtype=float) if g.name in given_q
                else stances[g.name].q for g in legs}
    body = np.array([params.com_offset[0], params.com_offset[1], 0.0])
    com, _ = robot_com(legs, postures, float(robot.body_mass), body)
    return com


def _check_reach(p: Params, legs: tuple[GaitLeg, ...], robot: LeggedRobot) -> None:
    """A step no leg can make at the depth, by geometry alone (no simulation): longer than
    ``2 √(R² − H²)``, R the largest hip-to-foot distance any leg could have (the sum of its
    link offsets), H the depth."""
    s, H = float(p.need("step_length")), float(p.need("depth"))
    R = max(length_bound(g.leg) for g in legs)
    stride = 2.0 * math.sqrt(max(R * R - H * H, 0.0))
    if s > stride:
        raise ValueError(
            f"step_length: {s:.4g} m is longer than any stroke the legs of {robot.name} can "
            f"make with the feet {H:.4g} m below the hips (at most 2 √(R² − H²) = "
            f"{stride:.4g} m, R = {R:.4g} m the legs' full length); give a shorter "
            "step_length")


def _report(robot: LeggedRobot, p: Params) -> StepReport:
    from legcore.studies.quadruped_gait.problem import QuadrupedGaitProblem

    problem = QuadrupedGaitProblem(robot, p)
    return step_report(problem, problem.default_x)


def _check_default_step(p: Params, r: StepReport, given: Params) -> None:
    """Refuse a default step out of reach (always) or, when the defaults are the rules', one
    that violates anything (module docstring)."""
    s, h, H = p.need("step_length"), p.need("step_height"), p.need("depth")
    chose = any(f in given.model_fields_set for f in GAIT_FIELDS)
    if r.unreachable > 0.0 and (r.unreachable_in_stance or not chose):
        field, change = (("step_length", "a shorter step_length or another depth")
                         if r.unreachable_in_stance else ("step_height", "a lower step_height"))
        raise ValueError(
            f"{field}: the default step (s = {s:.4g} m, h = {h:.4g} m at depth {H:.4g} m) "
            f"puts {r.unreachable:.0%} of the foot positions of legs "
            f"{', '.join(r.unreachable_legs)} out of reach or outside their joint limits"
            f"{' in stance' if r.unreachable_in_stance else ' in the swing'}; give {change}")
    if chose:
        return
    step = f"the default step (s = {s:.4g} m, h = {h:.4g} m, duty {p.duty})"
    if r.G[0] > 0.0:
        raise ValueError(
            f"stability_margin: {step} keeps a static margin of only {_mm(r.margin)}, below "
            f"the required {_mm(r.required)}; give a smaller stability_margin, a longer "
            "step_length or a larger duty")
    if r.G[4] > 0.0:
        raise ValueError(
            f"stroke_center: in {step} foot {r.pull_leg} pulls on the ground with "
            f"{r.pull:.3g} N; give a stroke_center or com_offset that puts the feet around "
            "the centre of mass")
    if r.G[2] > 0.0:
        raise ValueError(
            f"speed: {step} drives joint {r.qd_joint} at {r.qd_ratio:.0%} of its speed limit "
            f"{r.qd_limit:.4g} rad/s; give a lower speed")
    if r.G[3] > 0.0:
        raise ValueError(
            f"depth: {step} needs {r.tau_ratio:.0%} of joint {r.tau_joint}'s torque limit "
            f"{r.tau_limit:.4g} N·m; give a larger depth (straighter legs) or a lower speed")
