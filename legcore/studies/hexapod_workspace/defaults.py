"""The ``hexapod_workspace`` task on any hexapod: defaults derived from the robot, and the
pre-flight check (DESIGN §5, :mod:`legcore.studies.task`).

``derive(robot, params) -> Task`` fills every robot-relative field the user left unset
(:data:`~legcore.studies.hexapod_workspace.params.ROBOT_RELATIVE`) from the hexapod the study
runs on (the job's robot, or the parametric ``hexapod``), each by a rule stated in
``Task.rules`` with its numbers, then refuses a task that cannot work. Lengths come from the
legs' own kinematics (FK over their joint boxes), so a robot five times larger gets five times
larger lengths and the same angles. All in the study frame (walking along +y, z up), SI units.

Rules (s: a foot's horizontal distance out from its hip's coxa axis, v: its height from the
hip, both in the plane the leg moves in at θ1 = ``theta1_start``):

- ``theta2``, ``theta3`` — the stance posture: the foot **45° below the hip** (as far below
  it as out from it) and **halfway along the leg's reach on that line**, ρ = (ρ_min + ρ_max)/2
  with ρ_min, ρ_max the nearest and farthest foot points on the line inside the joint limits
  (equal room to stretch and fold the leg, equal room to lower and to shift the body), on the
  ``knee`` branch (closed-form legs: θ3 ≤ 0 for "up"; other legs: the knee above the line from
  the femur joint to the foot). With one of the two given, the other puts the foot on the 45°
  line. Searched on a 161 × 161 grid of the joint box of the front stance leg, refined by
  Gauss–Newton, rounded to 1e-4 rad.
- ``theta1_min``, ``theta1_max`` — each stance foot may sweep at most half the gap to its
  nearest neighbouring foot (all six legs at the stance posture, the others at θ1 = 0):
  |Δθ1| ≤ 2·asin(gap / (4 s)), the smallest over the stance legs, about ``theta1_start``,
  inside every stance leg's coxa limits.
- ``pose_yaw_extent`` — half the coxa range (the body turns with the feet fixed about as far as
  a coxa turns), the narrowest stance leg's; ``pose_yaw_step`` = extent / 6 (13 yaws).
- ``pose_x_extent``, ``pose_y_extent`` — the box that must hold every reachable body pose: a
  body displaced by d and turned by ψ keeps foot k only if the foot is in that leg's reach at
  the stance height (s between the leg's nearest and farthest reach at that height, the coxa
  inside its limits); per yaw of the grid, the intersection of the three legs' boxes, the
  largest over the yaws, + 5 %; ``pose_xy_step`` = 1/20 of the larger one (rounded up to 2
  significant digits), each extent rounded up to a whole number of steps (at most 41 × 41
  positions, the outermost beyond every reachable pose).
- ``hv_ref_point`` — (1°, 1°, 0.2 % of the stance triangle's perimeter): the angle errors are
  scale-free, the perimeter's tolerance scales with the robot (seed 002's robot: 1.03 mm; its
  preset keeps 1 mm).

:class:`HexapodStudy` is the study descriptor's class: its ``task`` derives from the robot the
study runs on (the parametric ``hexapod`` when given; seed 002's preset applies to one with all
of seed 002's geometry). Leg geometry: :mod:`legcore.studies.hexapod_workspace.reach`.

Pre-flight (``ValueError("<field>: …")``): the θ1 bounds, ``theta1_start``, ``theta2`` and
``theta3`` inside every stance leg's joint limits; the stance feet below the hips by more than
half the body's height and on one ground plane (heights within 1 % of the hip-to-foot
distance); the body centre inside the support triangle at the stance (S_f, S_b > 0, seed 002's
Fig. 6); the pose grid at most 2,000,000 poses.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import ValidationError

from legcore.robots import catalog
from legcore.robots.legged import LeggedRobot
from legcore.studies.hexapod_workspace.legs import Tripod, tripod_from_robot
from legcore.studies.hexapod_workspace.params import HV_REF, PoseGrid
from legcore.studies.hexapod_workspace.preset import PRESET
from legcore.studies.hexapod_workspace.reach import pose_box, stance_posture, theta1_swing
from legcore.studies.hexapod_workspace.robot import HexapodGeometry, parametric_hexapod
from legcore.studies.study import Study
from legcore.studies.task import Task, fill, validation_message
from legcore.tripod_stability import support_triangle, tripod_stability

__all__ = ["HexapodStudy", "derive", "study_robot"]

FloatArray = NDArray[np.float64]

#: Pose grid cells each side of 0: x/y (41 values), yaw (13 values).
XY_CELLS, YAW_CELLS = 20, 6
#: Margin added to the pose box (the reach is sampled).
_BOX_MARGIN = 0.05
#: f3's hypervolume reference as a fraction of the stance triangle's perimeter.
HV_PERIMETER_FRACTION = 0.002
#: Stance feet on one ground plane: heights within this fraction of the hip-to-foot distance.
LEVEL_TOL = 0.01

_PARAMETRIC: dict[str, LeggedRobot] = {}


def study_robot(robot: Any, params: Any) -> Any:
    """The robot the study runs on: the parametric ``params.hexapod`` when given (cached per
    geometry), else ``robot``."""
    g: HexapodGeometry | None = getattr(params, "hexapod", None)
    if g is None:
        return robot
    key = g.model_dump_json()
    hit = _PARAMETRIC.get(key)
    if hit is None:
        if len(_PARAMETRIC) > 32:
            _PARAMETRIC.clear()
        hit = _PARAMETRIC[key] = parametric_hexapod(g)
    return hit


class HexapodStudy(Study):
    """The study descriptor, whose task is derived from the robot the study runs on: the
    parametric ``hexapod`` when one is given (seed 002's preset applies to it when it has all
    of seed 002's geometry — the same model as ``citedi_hexapod``)."""

    def task(self, robot: Any, params: Any) -> Task:
        g = getattr(params, "hexapod", None)
        if g is not None:
            robot = catalog.get(PRESET.robot) if g == HexapodGeometry() else study_robot(
                robot, params)
        return super().task(robot, params)


# ----------------------------------------------------------------------------------------------
# The pieces of the task
# ----------------------------------------------------------------------------------------------


def _ceil_sig(value: float, digits: int = 2) -> float:
    """``value`` > 0 rounded up to ``digits`` significant digits."""
    quantum = 10.0 ** (math.floor(math.log10(value)) - digits + 1)
    return float(f"{math.ceil(value / quantum * (1 - 1e-12)) * quantum:.{digits}g}")


def _pose_xy(params: Any, tripod: Tripod, feet: FloatArray, th_s: FloatArray, t2: float,
             t3: float, yaw_ext: float, yaw_step: float, values: dict[str, Any],
             rules: dict[str, str]) -> None:
    """``pose_x_extent``, ``pose_y_extent`` and ``pose_xy_step`` left unset: the reach box
    (:func:`~legcore.studies.hexapod_workspace.reach.pose_box`) + 5 %; the step 1/20 of the
    larger one (2 significant digits) and each extent a whole number of steps (rounded up), so
    that the grid's outermost values lie beyond every reachable pose; a given step or extent
    is kept."""
    names = ("pose_x_extent", "pose_y_extent")
    unset = [n for n in names if getattr(params, n) is None]
    step = params.pose_xy_step
    if unset:
        n = int(math.floor(yaw_ext / yaw_step + 1e-9)) if yaw_ext > 0 else 0
        yaws: FloatArray = np.arange(-n, n + 1, dtype=float) * yaw_step
        box = dict(zip(names, pose_box(tripod, feet, th_s, t2, t3, yaws), strict=True))
        margined = {n: e * (1.0 + _BOX_MARGIN) for n, e in box.items()}
        if step is None:
            larger = max(margined[n] if n in unset else float(getattr(params, n))
                         for n in names)
            step = _ceil_sig(larger / XY_CELLS)
            values["pose_xy_step"] = step
            rules["pose_xy_step"] = (f"{step:.3g} m: 1/{XY_CELLS} of the larger extent, "
                                     "rounded up")
        for name in unset:
            v = round(step * math.ceil(margined[name] / step * (1 - 1e-12)), 12)
            values[name] = v
            rules[name] = (f"{v:.4g} m: the farthest body shift in {name[5]} "
                           f"({box[name]:.4g} m) that keeps the three stance feet inside their "
                           f"legs' reach at the stance height, over the {yaws.size} yaws, "
                           "+ 5 %, rounded up to a whole number of pose_xy_step")
    elif step is None:
        larger = max(float(params.pose_x_extent), float(params.pose_y_extent))
        values["pose_xy_step"] = step = larger / XY_CELLS
        rules["pose_xy_step"] = f"{step:.4g} m: the larger extent / {XY_CELLS}"


def _stance_feet(tripod: Tripod, theta_start: FloatArray, t2: float, t3: float) -> FloatArray:
    q = np.column_stack((theta_start, np.full(3, t2), np.full(3, t3)))
    return tripod.feet(q)


# ----------------------------------------------------------------------------------------------
# derive
# ----------------------------------------------------------------------------------------------


def derive(robot: Any, params: Any) -> Task:
    """The task of ``params`` on ``robot`` (the parametric ``params.hexapod`` when given): every
    robot-relative field left unset derived by the module's rules, then the pre-flight check.
    ``ValueError("<field>: …")`` when the task cannot work on this robot."""
    robot = study_robot(robot, params)
    tripod = tripod_from_robot(robot, params.stance)          # robot: / stance: refusals
    assert tripod.robots is not None
    rules: dict[str, str] = {}
    values: dict[str, Any] = {}
    th_s = np.asarray(params.theta1_start, dtype=float)
    legs = tripod.legs

    # stance posture (the front stance leg's; every stance leg holds the same θ2, θ3)
    t2, t3 = params.theta2, params.theta3
    if t2 is None or t3 is None:
        post = stance_posture(tripod.robots[0], float(th_s[0]), tripod.closed_form, params.knee,
                              t2, t3)
        where = (f"leg {legs[0]}: foot {post.s:.4g} m out, {-post.v:.4g} m below the hip")
        if t2 is None:
            values["theta2"] = t2 = post.theta2
            rules["theta2"] = f"{post.theta2:.4f} rad: {post.rule}; {where}"
        if t3 is None:
            values["theta3"] = t3 = post.theta3
            rules["theta3"] = f"{post.theta3:.4f} rad: {post.rule}; {where}"
    t2, t3 = float(t2), float(t3)
    _check_joint_limits(tripod, params, th_s, t2, t3)

    # θ1 bounds
    lo = float(tripod.q_min[:, 0].max())
    hi = float(tripod.q_max[:, 0].min())
    if params.theta1_min is None or params.theta1_max is None:
        delta, why = theta1_swing(robot, tripod, th_s, t2, t3)
        if params.theta1_min is None:
            values["theta1_min"] = v_min = max(lo, float(th_s.min()) - delta)
            rules["theta1_min"] = (f"{v_min:.4f} rad: theta1_start − {delta:.4f} rad ({why}), "
                                   f"not below the coxa limit {lo:.4f} rad")
        if params.theta1_max is None:
            values["theta1_max"] = v_max = min(hi, float(th_s.max()) + delta)
            rules["theta1_max"] = (f"{v_max:.4f} rad: theta1_start + {delta:.4f} rad ({why}), "
                                   f"not above the coxa limit {hi:.4f} rad")

    # pose grid
    yaw_ext = params.pose_yaw_extent
    if yaw_ext is None:
        yaw_ext = values["pose_yaw_extent"] = min(
            math.pi, float(np.min(tripod.q_max[:, 0] - tripod.q_min[:, 0])) / 2.0)
        rules["pose_yaw_extent"] = (f"{yaw_ext:.4f} rad: half the coxa range (the body turns "
                                    "with the feet fixed about as far as a coxa turns)")
    if params.pose_yaw_step is None:
        yaw_step = values["pose_yaw_step"] = yaw_ext / YAW_CELLS if yaw_ext > 0 else math.pi
        rules["pose_yaw_step"] = f"{yaw_step:.4f} rad: pose_yaw_extent / {YAW_CELLS}"
    yaw_step = float(values.get("pose_yaw_step", params.pose_yaw_step))
    feet = _stance_feet(tripod, th_s, t2, t3)
    _pose_xy(params, tripod, feet, th_s, t2, t3, yaw_ext, yaw_step, values, rules)

    # hypervolume reference
    if params.hv_ref_point is None:
        per = float(support_triangle(feet[0], feet[1], feet[2],
                                     formula=params.triangle_formula)[2])
        f3 = float(f"{HV_PERIMETER_FRACTION * per:.3g}")
        values["hv_ref_point"] = (HV_REF[0], HV_REF[1], f3)
        rules["hv_ref_point"] = (f"(1°, 1°, {f3:.3g} m): angle errors of 1°, and "
                                 f"{100 * HV_PERIMETER_FRACTION:.1f} % of the stance triangle's "
                                 f"perimeter ({per:.4g} m)")

    _check_grid(params, values)
    try:
        filled = fill(params, values)
    except ValidationError as exc:
        raise ValueError(validation_message(exc)) from None
    _check_bounds(tripod, filled, th_s)
    _check_stance(robot, tripod, feet, legs)
    return Task(filled, rules)


# ----------------------------------------------------------------------------------------------
# pre-flight checks
# ----------------------------------------------------------------------------------------------


def _check_joint_limits(tripod: Tripod, params: Any, th_s: FloatArray, t2: float,
                        t3: float) -> None:
    for k, leg in enumerate(tripod.legs):
        lo, hi = tripod.q_min[k], tripod.q_max[k]
        for name, j, v in (("theta1_start", 0, th_s[k]), ("theta2", 1, t2), ("theta3", 2, t3)):
            if not lo[j] - 1e-9 <= v <= hi[j] + 1e-9:
                raise ValueError(f"{name}: {v:.4f} rad is outside the joint limits "
                                 f"[{lo[j]:.4f}, {hi[j]:.4f}] rad of leg {leg}; give a value "
                                 "inside them")


def _check_grid(params: Any, values: dict[str, Any]) -> None:
    names = ("pose_x_extent", "pose_y_extent", "pose_xy_step", "pose_yaw_extent",
             "pose_yaw_step")
    grid = PoseGrid(*(float(values.get(n, getattr(params, n))) for n in names))
    error = grid.error()
    if error is not None:
        raise ValueError(error)


def _check_bounds(tripod: Tripod, p: Any, th_s: FloatArray) -> None:
    lo_all, hi_all = float(tripod.q_min[:, 0].max()), float(tripod.q_max[:, 0].min())
    if not p.theta1_min < p.theta1_max:
        raise ValueError(f"theta1_min: must be below theta1_max ({p.theta1_min:.4f} >= "
                         f"{p.theta1_max:.4f} rad)")
    for name, v in (("theta1_min", p.theta1_min), ("theta1_max", p.theta1_max)):
        if not lo_all - 1e-9 <= v <= hi_all + 1e-9:
            raise ValueError(f"{name}: {v:.4f} rad is outside the coxa limits "
                             f"[{lo_all:.4f}, {hi_all:.4f}] rad of the stance legs "
                             f"{', '.join(tripod.legs)}; give θ1 bounds inside them")


def _check_stance(robot: Any, tripod: Tripod, feet: FloatArray, legs: tuple[str, ...]) -> None:
    """The stance stands: feet below the hips (clear of the body), on one plane, body stable."""
    assert tripod.robots is not None
    depth = tripod.hips[:, 2, 3] - feet[:, 2]
    reach = float(np.linalg.norm(feet - tripod.hips[:, :3, 3], axis=1).max())
    body_z = float(getattr(robot, "body_size", (0.0, 0.0, 0.0))[2])
    if not np.all(depth > max(0.5 * body_z, 0.0)):
        k = int(np.argmin(depth))
        raise ValueError(f"theta2: at the stance posture the foot of leg {legs[k]} is "
                         f"{depth[k]:.4g} m below its hip, but the body is {body_z:.4g} m high: "
                         "it would rest on the ground; give theta2/theta3 that stand higher")
    spread = float(feet[:, 2].max() - feet[:, 2].min())
    if spread > LEVEL_TOL * max(reach, 1e-12):
        raise ValueError(f"theta2: the stance feet are at different heights (spread "
                         f"{spread:.4g} m, more than 1 % of the hip-to-foot distance "
                         f"{reach:.4g} m): the stance legs' joints differ, the tripod does not "
                         "stand on flat ground")
    S_f, S_b = tripod_stability(feet[0], feet[2], feet[1])
    if not (S_f > 0.0 and S_b > 0.0):
        raise ValueError(f"theta1_start: the body centre is outside the support triangle of "
                         f"legs {', '.join(legs)} at the stance (S_f = {float(S_f):.4g} m, "
                         f"S_b = {float(S_b):.4g} m, seed 002's Fig. 6): the stance is not "
                         "statically stable; give theta1_start (or theta2/theta3) that put the "
                         "feet around the body centre")

