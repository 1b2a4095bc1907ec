"""The ``swing_energy`` study's descriptor: ``build`` (the problem from a robot and the
study's parameters, robot-relative ones first derived) and ``STUDY`` (what the registry
lists: parameters, defaults, what it needs from a robot, its robot-relative defaults and
its paper's preset)."""

from __future__ import annotations

from typing import Any

from legcore.robots.capabilities import Needs
from legcore.studies.study import Study
from legcore.studies.swing_energy.defaults import derive
from legcore.studies.swing_energy.params import Params
from legcore.studies.swing_energy.preset import PRESET
from legcore.studies.swing_energy.problem import SwingEnergyProblem, incomplete

__all__ = ["STUDY", "build"]


def build(robot: Any, params: Any) -> SwingEnergyProblem:
    """The study's problem for ``robot`` (a serial leg, or a legged robot with ``params.leg``)
    and ``params`` (:class:`Params`); fields left to the robot (None) are first derived by
    :meth:`Study.task` (the preset on seed 000's leg, else :mod:`.defaults`)."""
    if not isinstance(params, Params):
        params = Params.model_validate(params)
    if incomplete(robot, params):
        params = STUDY.task(robot, params).params
    return SwingEnergyProblem(robot, params)


STUDY = Study(
    kind="swing_energy",
    title="Energy-optimal swing (transfer) phase of a leg (seed 000)",
    seed_paper="000",
    params=Params,
    default_robot="calderon_leg",
    default_optimizer={
        "kind": "ga",
        "params": {"pop_size": 100, "mutation_rate": 0.03, "crossover_rate": 0.9,
                   "elitism": 2, "fitness": "negated", "penalty": 300.0},
    },
    default_generations=100,
    build=build,
    robot_kinds=("serial", "legged"),
    derive=derive,
    preset=PRESET,
    robot_relative=(
        'leg', 'q_start', 'q_end', 'exact_ends', 'step_height', 'w_d', 'w_a',
        'search_range', 'tube', 'lift_only',
    ),
    needs=(
        Needs(serial=True, min_joints=2, max_joints=6, revolute=True),
        Needs(legged=True, leg_joints=(2, 6), revolute=True),
    ),
    description=(
        "One leg (a serial chain of 2-6 revolute joints, or one leg of a legged robot: "
        "problem.leg, by default its first front leg) swings one step forward in body axes "
        "(from half a step behind a nominal stance to half a step ahead, scaled to the leg's "
        "length) or from a given start to a given end foot position or configuration, through "
        "joint via points on a control grid; the GA maximises seed 000's coordination score "
        "(or a baseline's criterion) with the foot and links above the ground and clear of "
        "box obstacles. Reports the mechanical energy and seed 000's per-joint table."
    ),
)
