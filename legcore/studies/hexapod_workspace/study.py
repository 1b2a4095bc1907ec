"""The ``hexapod_workspace`` study's descriptor: ``build`` (the problem from a robot and the
study's parameters, robot-relative ones first derived) and ``STUDY`` (what the registry
lists: parameters, defaults, what it needs from a robot, its robot-relative defaults and
its paper's preset)."""

from __future__ import annotations

from typing import Any

from legcore.robots.capabilities import Needs
from legcore.studies.hexapod_workspace.defaults import HexapodStudy, derive
from legcore.studies.hexapod_workspace.params import ROBOT_RELATIVE, Params
from legcore.studies.hexapod_workspace.preset import PRESET
from legcore.studies.hexapod_workspace.problem import HexapodWorkspaceProblem

__all__ = ["STUDY", "build"]


def build(robot: Any, params: Params) -> HexapodWorkspaceProblem:
    """The study problem for ``robot`` (a hexapod with 3-joint legs, or the parametric one of
    ``params.hexapod``) and ``params``; robot-relative fields left unset are first derived
    (``STUDY.task``: the paper's preset on its robot, else the rules of
    :mod:`~legcore.studies.hexapod_workspace.defaults`, with the pre-flight check)."""
    if not isinstance(params, Params):
        params = Params.model_validate(params)
    if not params.concrete:
        params = STUDY.task(robot, params).params
    return HexapodWorkspaceProblem(robot, params)


STUDY = HexapodStudy(
    kind="hexapod_workspace",
    title="Hexapod tripod workspace by MOEA/D (seed 002)",
    seed_paper="002",
    params=Params,
    default_robot="citedi_hexapod",
    default_optimizer={"kind": "moead", "params": {"n_subproblems": 300, "n_neighbors": 20}},
    default_generations=100,
    build=build,
    derive=derive,
    preset=PRESET,
    robot_relative=ROBOT_RELATIVE,
    robot_kinds=("legged",),
    needs=(Needs(legged=True, n_legs=(6,), leg_joints=(3, 3), revolute=True),),
    description=(
        "A hexapod (six legs of 3 joints, three on each side) stands on a tripod; the decision "
        "is the first (coxa) joint of the three stance legs, the others held. MOEA/D minimises "
        "the errors of the support triangle's two angles and perimeter (the body can move with "
        "the feet fixed); reports the front, its stable/unstable split, the mirrored workspace "
        "and the exact (x, y, yaw) workspace of the body with the feet fixed. A parametric "
        "hexapod (problem.hexapod: leg lengths, hip layout) replaces the robot. Defaults come "
        "from the robot: the stance posture puts each foot 45° below its hip halfway along "
        "the leg's reach, the coxa swing keeps clear of the neighbouring feet, the pose grid "
        "covers the legs' reach; a stance that is not stable is refused, and an unstable "
        "optimum is reported infeasible. Seed 002's settings are its preset on citedi_hexapod."
    ),
)
