"""Trajectories: velocity profiles, Cartesian paths, joint via-point splines, swing curves.

See ``docs/trajectories.md`` for the equations (seed 004 profiles and paths, seed 000
swing baselines) and an example.
"""

from __future__ import annotations

from legcore.trajectories.joint_splines import ViaPointSpline
from legcore.trajectories.paths import (
    Arc,
    CompositePath,
    Line,
    PlanarCurve,
    Plane,
    Segment,
    capsule_path,
    constant_speed_path,
)
from legcore.trajectories.profiles import (
    AccelProfile,
    ConstantProfile,
    DecelProfile,
    Profile,
    QuinticProfile,
    SCurveProfile,
    TrapezoidalProfile,
    segment_time,
)
from legcore.trajectories.sampling import JointSample, PathSample, compose_time_law, time_grid
from legcore.trajectories.swing import SEED000_HEIGHT, SEED000_STEP, SEED000_T, SwingCurve

__all__ = [
    "SEED000_HEIGHT",
    "SEED000_STEP",
    "SEED000_T",
    "AccelProfile",
    "Arc",
    "CompositePath",
    "ConstantProfile",
    "DecelProfile",
    "JointSample",
    "Line",
    "PathSample",
    "PlanarCurve",
    "Plane",
    "Profile",
    "QuinticProfile",
    "SCurveProfile",
    "Segment",
    "SwingCurve",
    "TrapezoidalProfile",
    "ViaPointSpline",
    "capsule_path",
    "compose_time_law",
    "constant_speed_path",
    "segment_time",
    "time_grid",
]
