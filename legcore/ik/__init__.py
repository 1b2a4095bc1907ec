"""Inverse kinematics: one entry point for any serial robot, and the closed forms behind it.

:func:`solve` (``legcore.ik.solve(robot, targets, task=..., path=...)``) solves positions, tool
axes or full poses for any robot, batched and warm-started along paths: closed forms where the
robot's ``ik_family`` has one (fast path), the numerical solver :func:`solve_numeric` otherwise.
The closed-form modules (``puma560``, ``arm5``, ``leg3``, ``leg2``) stay importable on their own;
each returns ``(q, reachable)``-style results with q NaN where the target cannot be reached.
Targets are never clipped.
"""

from legcore.ik.leg2 import (
    ELBOW_BACK,
    KNEE_FORWARD,
    leg2_fk,
    leg2_ik,
    leg2_link_angles_deg,
    leg2_q_from_link_angles_deg,
)
from legcore.ik.leg3 import KNEE_DOWN, KNEE_UP, leg3_fk, leg3_ik
from legcore.ik.numeric import solve_numeric
from legcore.ik.solver import solve
from legcore.ik.targets import IKSolution

__all__ = [
    "ELBOW_BACK",
    "IKSolution",
    "KNEE_DOWN",
    "KNEE_FORWARD",
    "KNEE_UP",
    "leg2_fk",
    "leg2_ik",
    "leg2_link_angles_deg",
    "leg2_q_from_link_angles_deg",
    "leg3_fk",
    "leg3_ik",
    "solve",
    "solve_numeric",
]
