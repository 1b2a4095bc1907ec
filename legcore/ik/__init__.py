"""Closed-form inverse kinematics (analytic where the seeds give it), vectorised over a batch.

Each solver returns ``(q, reachable)``: q is NaN where the target cannot be reached; targets
are never clipped.
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

__all__ = [
    "ELBOW_BACK",
    "KNEE_DOWN",
    "KNEE_FORWARD",
    "KNEE_UP",
    "leg2_fk",
    "leg2_ik",
    "leg2_link_angles_deg",
    "leg2_q_from_link_angles_deg",
    "leg3_fk",
    "leg3_ik",
]
