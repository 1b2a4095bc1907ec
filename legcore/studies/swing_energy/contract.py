"""What the ``swing_energy`` study's decoding and baselines read of its problem: a protocol.

:class:`legcore.studies.swing_energy.problem.SwingEnergyProblem` imports
:mod:`~legcore.studies.swing_energy.decode` and :mod:`~legcore.studies.swing_energy.baselines`;
they read the problem through :class:`SwingProblem` (and build its variants with
:meth:`SwingProblem.variant`) instead of importing it, so the three are no import circle.
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from legcore.robots.model import Robot
from legcore.studies.study import Box, Solution
from legcore.studies.swing_energy.params import Params

__all__ = ["SwingProblem"]

FloatArray = NDArray[np.float64]


class SwingProblem(Protocol):
    """The swing-phase problem as its decoding and baselines see it (all SI, n joints; the
    attributes are documented on :class:`~legcore.studies.swing_energy.problem.SwingEnergyProblem`).
    """

    source: Any
    robot: Robot
    robot_name: str
    label: str
    hip: FloatArray | None
    params: Params
    criterion: str
    n_var: int
    n_via: int
    n_joints: int
    res: float
    t: FloatArray
    q_start: FloatArray
    q_end: FloatArray
    start_steps: NDArray[np.int64]
    end_steps: NDArray[np.int64]
    foot_start: FloatArray
    foot_end: FloatArray
    z_ground: float
    boxes: tuple[Box, ...]
    margins: tuple[float, ...]
    box: Box | None
    margin: float
    acc_coordinated: FloatArray
    theta_min: FloatArray
    tube: str
    constraint_names: tuple[str, ...]

    def evaluate(self, X: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(F (B, 1), G (B, n_constr)) of decision vectors X (B, n_var)."""
        ...

    def trajectories(
        self, X: FloatArray, orders: tuple[int, ...] = (0, 1, 2, 3)
    ) -> list[FloatArray]:
        """Sampled q, q̇, q̈, jerk (the orders asked for), each (B, K, n)."""
        ...

    def score_parts(self, q: FloatArray, qdd: FloatArray) -> tuple[FloatArray, FloatArray]:
        """(f_d, f_a) per trajectory (B,)."""
        ...

    def energy(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray:
        """Mechanical energy (B,) J."""
        ...

    def chain_points(self, q: FloatArray) -> FloatArray:
        """Points along the leg (..., M, 3) m, the foot last."""
        ...

    def genes(self, x: FloatArray) -> NDArray[np.int64]:
        """Integer genes (n_via, n) of a decision vector."""
        ...

    def via_steps(self, X: FloatArray) -> NDArray[np.int64]:
        """Intermediate via points (B, n_via, n) in resolution steps."""
        ...

    def encode(self, via: FloatArray) -> FloatArray:
        """Decision vector (n_var,) whose via points are ``via`` (n_via, n) rad."""
        ...

    def coordinated_x(self) -> FloatArray:
        """Decision vector of the coordinated start→end motion."""
        ...

    def solution(self, x: FloatArray, label: str | None = None) -> Solution:
        """The decoded trajectory of ``x`` with its metrics."""
        ...

    def baseline_solutions(self) -> dict[str, Solution]:
        """The seed's comparison trajectories, by name."""
        ...

    def variant(self, criterion: str, refs: dict[str, float] | None = None) -> SwingProblem:
        """The same leg, start, end and parameters with ``criterion`` as F (a
        :class:`~legcore.problems.base.Problem` too: the baselines optimise it)."""
        ...
