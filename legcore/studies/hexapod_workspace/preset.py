"""Seed 002's settings on its own robot (``citedi_hexapod``): the paper's values of every
robot-relative field of ``hexapod_workspace``, and its post-hoc stability and Table 2
baselines. :meth:`legcore.studies.study.Study.task` fills the fields a job leaves unset from
:data:`PRESET` when the robot is that catalog robot (or the parametric ``hexapod`` with all of
its geometry, which is the same model), so every seed number is reproduced with the defaults.
"""

from __future__ import annotations

import math

from legcore.studies.hexapod_workspace.params import HV_REF
from legcore.studies.task import Preset

__all__ = ["PRESET"]

PRESET = Preset(
    robot="citedi_hexapod",
    params={
        # §4: search range of each θ1, and the constant femur/tibia angles of the stance legs
        "theta1_min": -math.pi / 6,
        "theta1_max": math.pi / 6,
        "theta2": -math.pi / 8,
        "theta3": -math.pi / 4,
        # the exact pose-workspace grid (ours, beyond the paper): ±4 cm by 1 mm, ±30° by 5°
        "pose_x_extent": 0.04,
        "pose_y_extent": 0.04,
        "pose_xy_step": 0.001,
        "pose_yaw_extent": math.pi / 6,
        "pose_yaw_step": math.pi / 36,
        # hypervolume box (1°, 1°, 1 mm), fixed so that runs on this robot compare
        "hv_ref_point": HV_REF,
        # Fig. 9b: stability classified after the optimisation (the front keeps unstable points)
        "stability": "classify",
        # Table 2's solutions a–d (θ1 values of this robot)
        "paper_baselines": True,
    },
    source="seed 002 (Domínguez et al.), §4, Table 2, Figs 6–9",
)
