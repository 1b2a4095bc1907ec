"""The ``path_placement`` study's descriptor: ``build`` (the problem from a robot and the
study's parameters, robot-relative ones first derived) and ``STUDY`` (what the registry
lists: parameters, defaults, what it needs from a robot, its robot-relative defaults and
its paper's preset)."""

from __future__ import annotations

from typing import Any

from legcore.robots.model import Robot
from legcore.studies.path_placement.defaults import derive
from legcore.studies.path_placement.params import Params
from legcore.studies.path_placement.preset import PRESET
from legcore.studies.path_placement.problem import NEEDS, PathPlacementProblem
from legcore.studies.study import Study

__all__ = ["STUDY", "build"]


def build(robot: Robot, params: Params) -> PathPlacementProblem:
    """The problem for ``robot`` (a serial arm of ≥ 6 joints) and validated ``params``; the
    fields left None are filled as a submission fills them (``STUDY.task``: the preset on the
    seed's PUMA 560, the robot-relative rules elsewhere) when the caller did not."""
    if not isinstance(params, Params):
        params = Params.model_validate(params)
    if isinstance(robot, Robot) and robot.nq >= 6 and (
            params.nominal_power_kw is None or params.path_scale is None):
        params = STUDY.task(robot, params).params
    return PathPlacementProblem(robot, params)


#: HKA settings of this study: seed 001 does not publish N, N_ξ, α, its survey step nor ϖ
#: (``penalty``); these converge in ~20 generations on both built-in paths (see the docs).
HKA_PARAMS: dict[str, Any] = {
    "n_samples": 30,
    "n_best": 6,
    "alpha": 0.6,
    "init": "survey",
    "survey_size": 216,
    "survey_best": 5,
    "penalty": 1e3,
    "spread_tol": 1e-4,
}

STUDY = Study(
    kind="path_placement",
    title="Placement of a tool path for energy and manipulability, any arm of ≥ 6 joints "
          "(seed 001)",
    seed_paper="001",
    params=Params,
    default_robot="puma560",
    default_optimizer={"kind": "hka", "params": dict(HKA_PARAMS)},
    default_generations=30,
    build=build,
    robot_kinds=("serial",),
    needs=(NEEDS,),
    derive=derive,
    preset=PRESET,
    robot_relative=(
        'path_scale', 'path_axis', 'spin', 'original', 'region', 'postures', 'duration',
        'nominal_power_kw',
    ),
    description=(
        "Where to put a tool path (welding seam, CSV of poses) in front of an arm so that it "
        "runs it with the least energy — electrical where the robot has motor data, "
        "mechanical otherwise — and the best manipulability, under joint position, speed and "
        "power limits. The anchor goes in a sphere, spherical shell or box of the base frame. "
        "Default: the paper's path scaled to the arm's reach, in a well-conditioned region "
        "around a reachable and feasible original placement. Preset: seed 001's pan and jar "
        "paths on the PUMA 560 with HKA."
    ),
)
