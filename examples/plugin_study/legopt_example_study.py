"""``holding_torque`` — an example LegOpt study kind from a lab's own package (docs/plugins.md).

The task: hold a serial robot's tool point at ``target`` (m, base frame) in the posture that
needs the least static joint torque — ``minimise Σ_i τ_i(q)²`` (N²·m²) with ``τ = RNEA(q, 0, 0)``
(gravity only), subject to ``|p_tool(q) − target| ≤ tolerance``. Any serial chain of ≥ 2
revolute joints will do (the study says so in ``needs``; LegOpt refuses other robots by naming
what is missing).

What a study kind provides (all from ``legcore``'s public API):

- ``Params``: a :class:`~legcore.studies.study.StudyParams` subclass whose ``kind`` is a
  ``Literal`` of the kind's name — the API validates a job's ``problem`` by it;
- a :class:`~legcore.studies.study.StudyProblem`: bounds, a vectorised ``_evaluate(X)`` over
  the whole population, ``solution(x)`` decoding a decision vector (metrics + a
  :class:`~legcore.studies.study.Motion` for the recording);
- ``STUDY``: the :class:`~legcore.studies.study.Study` descriptor the entry point names.
"""

from __future__ import annotations

import math
from typing import Any, Literal

import numpy as np
from pydantic import Field

from legcore.dynamics import inverse_dynamics
from legcore.kinematics import fk
from legcore.robots.capabilities import Needs
from legcore.studies.study import Motion, Solution, Study, StudyParams, StudyProblem

__all__ = ["STUDY", "HoldingTorqueProblem", "Params"]


class Params(StudyParams):
    """``target`` tool point (m, base frame); ``tolerance`` how close the tool must be (m);
    ``duration`` of the recorded move from home to the posture (s)."""

    kind: Literal["holding_torque"] = "holding_torque"
    target: tuple[float, float, float] = (0.4, 0.1, 0.3)
    tolerance: float = Field(default=0.005, gt=0.0, le=1.0, description="m")
    duration: float = Field(default=1.0, gt=0.0, le=60.0, description="s")


class HoldingTorqueProblem(StudyProblem):
    """x = q (n,) rad; F = Σ τ² (N²·m²); G = |p_tool − target| − tolerance (m)."""

    objective_names = ("tau_sq",)
    constraint_names = ("tool_distance",)
    n_samples = 1

    def __init__(self, robot: Any, params: Params) -> None:
        if not all(math.isfinite(v) for v in params.target):
            raise ValueError("target: must be finite")
        self.robot = robot
        self.params = params
        self.target = np.asarray(params.target, dtype=float)
        xl = np.maximum(robot.q_min, -math.pi)
        xu = np.minimum(robot.q_max, math.pi)
        super().__init__(robot.nq, 1, 1, xl=xl, xu=xu, name="holding_torque")

    def _evaluate(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        zero = np.zeros_like(X)
        tau = inverse_dynamics(self.robot, X, zero, zero)
        dist = np.linalg.norm(fk(self.robot, X)[:, :3, 3] - self.target, axis=-1)
        return (tau**2).sum(-1)[:, None], (dist - self.params.tolerance)[:, None]

    def solution(self, x: np.ndarray) -> Solution:
        x = np.asarray(x, dtype=float)
        F, G = self.evaluate(x[None])
        t = np.linspace(0.0, self.params.duration, 51)
        s = (t / self.params.duration)[:, None]
        home = np.clip(self.robot.home, self.xl, self.xu)
        q = home + s * (x - home)
        zero = np.zeros_like(q)
        tau = inverse_dynamics(self.robot, q, zero, zero)
        tool = fk(self.robot, q)[:, :3, 3]
        names = tuple(list(self.robot.model.names)[1:])
        motion = Motion(t=t, q=q, joint_names=names, tau=tau, tool=tool, robot=self.robot.name,
                        scene={"targets": self.target[None]})
        hold = tau[-1]
        return Solution(
            x=x.copy(),
            objectives={"tau_sq": float(F[0, 0])},
            metrics={"tau_sq": float(F[0, 0]), "tool_distance": float(G[0, 0]
                                                                      + self.params.tolerance),
                     "max_torque": float(np.abs(hold).max()), "feasible": float(G[0, 0] <= 0)},
            table=[{"metric": "holding torque", "key": "tau", "unit": "N·m",
                    "values": hold.tolist()}],
            motion=motion,
        )

    def baseline_solutions(self) -> dict[str, Solution]:
        return {"home": self.solution(np.clip(self.robot.home, self.xl, self.xu))}


def build(robot: Any, params: Any) -> HoldingTorqueProblem:
    """The problem for ``robot`` (a serial chain) and ``params``."""
    if not isinstance(params, Params):
        params = Params.model_validate(params)
    return HoldingTorqueProblem(robot, params)


STUDY = Study(
    kind="holding_torque",
    title="Posture that holds the tool at a point with the least gravity torque (example plug-in)",
    seed_paper="",
    params=Params,
    default_robot="puma560",
    default_optimizer={"kind": "hka", "params": {"n_samples": 60, "n_best": 8, "penalty": 1e4}},
    default_generations=30,
    build=build,
    robot_kinds=("serial",),
    needs=(Needs(serial=True, min_joints=2, revolute=True),),
    description="Example plug-in (examples/plugin_study): minimise the sum of squared static "
    "joint torques holding the tool point at problem.target, within problem.tolerance.",
)
