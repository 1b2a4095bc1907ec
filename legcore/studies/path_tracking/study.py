"""The ``path_tracking`` study's descriptor: ``build`` (the problem from a robot and the
study's parameters, robot-relative ones first derived) and ``STUDY`` (what the registry
lists: parameters, defaults, what it needs from a robot, its robot-relative defaults and
its paper's preset)."""

from __future__ import annotations

from typing import Any

from legcore.robots.model import Robot
from legcore.studies.path_tracking.defaults import derive
from legcore.studies.path_tracking.params import Params
from legcore.studies.path_tracking.preset import PRESET
from legcore.studies.path_tracking.problem import NEEDS, PathTrackingProblem
from legcore.studies.study import Study

__all__ = ["STUDY", "build"]


def build(robot: Any, params: Any) -> PathTrackingProblem:
    """``Study.build``: the problem for ``robot`` (a serial arm of ≥ 5 joints) and ``params``
    (robot-relative fields left None are derived here when the caller did not: no preset)."""
    if not isinstance(params, Params):
        params = Params.model_validate(params)
    if isinstance(robot, Robot) and not params.concrete():
        params = derive(robot, params).params
    return PathTrackingProblem(robot, params)


STUDY = Study(
    kind="path_tracking",
    title="Timing of a line/arc path in a plane, run by an arm of ≥ 5 joints (seed 004)",
    seed_paper="004",
    params=Params,
    default_robot="articulated_5dof",
    default_optimizer={"kind": "nsga2", "params": {"pop_size": 40}},
    default_generations=60,
    build=build,
    robot_kinds=("serial",),
    needs=(NEEDS,),
    derive=derive,
    preset=PRESET,
    robot_relative=(
        'segments', 'plane_origin', 'plane_e1', 'plane_e2', 'orientation', 'rest', 'V',
        'V_bounds',
    ),
    description=(
        "An arm runs a fixed path of lines and arcs in any plane, its tool pointing down, "
        "along a fixed axis or free; the cruise speed of each segment and the ramp times are "
        "optimised for cycle time and/or mechanical energy under the joint speed, "
        "acceleration and torque limits. Default: seed 004's capsule scaled to the arm's reach, "
        "where it is well conditioned, with a tool orientation it can hold. Preset: seed 004's "
        "capsule on articulated_5dof."
    ),
)
