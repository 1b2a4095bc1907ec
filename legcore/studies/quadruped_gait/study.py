"""The ``quadruped_gait`` study's descriptor: ``build`` (the problem from a robot and the
study's parameters, robot-relative ones first derived) and ``STUDY`` (what the registry
lists: parameters, defaults, what it needs from a robot, its robot-relative defaults and
its paper's preset)."""

from __future__ import annotations

from typing import Any

from legcore.robots.capabilities import Needs
from legcore.studies.quadruped_gait.defaults import derive
from legcore.studies.quadruped_gait.params import ROBOT_RELATIVE, Params
from legcore.studies.quadruped_gait.preset import PRESET
from legcore.studies.quadruped_gait.problem import QuadrupedGaitProblem
from legcore.studies.study import Study

__all__ = ["STUDY", "build"]


def build(robot: Any, params: Params) -> QuadrupedGaitProblem:
    """The study's problem for ``robot`` (a quadruped :class:`LeggedRobot`) and ``params``;
    robot-relative fields left unset are first made concrete by :meth:`Study.task` (the
    paper's preset on its robot, else the rules of :mod:`.defaults`, with the pre-flight)."""
    if not isinstance(params, Params):
        params = Params.model_validate(params)
    if any(getattr(params, f) is None for f in ROBOT_RELATIVE):
        params = STUDY.task(robot, params).params
    return QuadrupedGaitProblem(robot, params)


STUDY = Study(
    kind="quadruped_gait",
    title="Quadruped 4-beat walk: servo table and minimum-energy step under a stability margin",
    seed_paper="003",
    params=Params,
    default_robot="animatronic_quadruped",
    default_optimizer={
        "kind": "hka",
        "params": {
            "n_samples": 50,
            "n_best": 5,
            "alpha": 0.9,
            "init": "survey",
            "survey_size": 300,
            "survey_best": 3,
            "penalty": 1e3,
        },
    },
    default_generations=40,
    build=build,
    robot_kinds=("legged",),
    derive=derive,
    preset=PRESET,
    robot_relative=(*ROBOT_RELATIVE, "q_ref"),
    needs=(Needs(legged=True, n_legs=(4,), leg_joints=(2, 3), revolute=True),),
    description=(
        "A quadruped (four legs of 2-3 joints, one at each corner) walks the 4-beat walk; "
        "every foot follows a level stance stroke and a smooth swing, solved by IK per sample. "
        "The optimiser picks step length, step height and duty factor for the least "
        "mechanical energy per metre under a static stability margin, joint speed and torque "
        "limits. Reports the servo table per time step."
    ),
)
