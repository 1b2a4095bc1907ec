"""What the ``quadruped_gait`` study's decoding and feasibility report read of its problem: a
protocol (:class:`legcore.studies.quadruped_gait.problem.QuadrupedGaitProblem` imports both
modules; they read it through :class:`GaitProblem` instead of importing it)."""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from legcore.gaits import Gait
from legcore.robots.legged import Leg, LeggedRobot
from legcore.studies.quadruped_gait.legs import GaitLeg
from legcore.studies.quadruped_gait.params import Params

__all__ = ["GaitProblem"]

FloatArray = NDArray[np.float64]


class GaitProblem(Protocol):
    """The walk problem as its helpers see it (SI units; documented on
    :class:`~legcore.studies.quadruped_gait.problem.QuadrupedGaitProblem`)."""

    robot: LeggedRobot
    params: Params
    gait: Gait
    gait_legs: tuple[GaitLeg, ...]
    legs: tuple[Leg, ...]
    leg_names: tuple[str, ...]
    roles: tuple[str, ...]
    numeric: bool
    mass: float
    g: float
    joint_names: tuple[str, ...]
    n_joints: tuple[int, ...]
    speed: float
    depth: float
    required_margin: float
    constraint_names: tuple[str, ...]

    def simulate(self, X: FloatArray, detail: bool = False) -> dict[str, Any]:
        """One cycle of each step of X (B, 3): energies, margins, loads (and signals)."""
        ...

    def objective_constraints(self, r: dict[str, Any]) -> tuple[FloatArray, FloatArray]:
        """(F (B, 1), G (B, 5)) of a simulation."""
        ...

    def servo_table(self, t: FloatArray, q: FloatArray) -> dict[str, Any]:
        """Servo commands (deg) per time step and servo over one cycle."""
        ...

    def table2(self, s: float, positions: int | None = None) -> dict[str, Any] | None:
        """Seed 003 Table 2 layout of the stance stroke of step length ``s`` (m)."""
        ...
