"""``calderon_leg`` — one 3-DOF leg of the electro-hydraulic hexapod of seed 000.

Source: seed 000 (GA energy optimisation of a walking-robot leg), Table 1 "Parámetros estructurales
del robot caminante electro-hidráulico" (Calderón, 2008): pelvis 0.065 m / 0.175 kg, thigh
0.075 m / 0.13 kg, shank 0.15 m / 0.11 kg, with centres of mass and inertia tensors.

Kinematics (standard DH, hip frame: z up, x along the leg at q = 0): joint 1 yaws about the
vertical (a1 = 0.065 m, α1 = +90°), joints 2 and 3 pitch (a2 = 0.075 m, a3 = 0.15 m).

Frame choice (the paper draws its frames in a figure we do not have): Table 1 gives each COM
from the link's *proximal* joint with x along the link (e.g. thigh COM x = 0.0242 m of a
0.075 m link, shank 0.0995 m of 0.15 m). We read those coordinates in axes parallel to DH frame
i and shift them by −a_i along x to express them in DH frame i (the distal frame Pinocchio and
DESIGN.md use). Inertia tensors are about the COM, so the shift leaves them unchanged.
Joint limits and speeds are not in the paper: ±180° (yaw ±90°) and 5 rad/s are assumed.
"""

from __future__ import annotations

import math

from legcore.robots.build import build_robot
from legcore.robots.model import Robot
from legcore.robots.spec import DHJoint, DHRobotSpec

# (a, alpha, mass, COM from the proximal joint, inertia about the COM) — seed 000 Table 1.
_TABLE1 = [
    (0.065, math.pi / 2, 0.175, (0.0305, 0.0, 0.015),
     ((0.000186, 0.0, 0.0), (0.0, 0.0001, -0.000031), (0.0, -0.000031, 0.000173))),
    (0.075, 0.0, 0.13, (0.0242, -0.0036, 0.0),
     ((0.000037, -0.000006, 0.0), (-0.000006, 0.000085, 0.0), (0.0, 0.0, 0.000084))),
    (0.15, 0.0, 0.11, (0.0995, 0.005, 0.0),
     ((0.000053, -0.000039, 0.0), (-0.000039, 0.000199, 0.0), (0.0, 0.0, 0.000182))),
]
_LIMITS = [(-math.pi / 2, math.pi / 2), (-math.pi, math.pi), (-math.pi, math.pi)]
_NAMES = ["hip_yaw", "hip_pitch", "knee_pitch"]


def spec() -> DHRobotSpec:
    joints = []
    for (a, alpha, m, com, inertia), (lo, hi), name in zip(_TABLE1, _LIMITS, _NAMES, strict=True):
        joints.append(
            DHJoint(
                name=name,
                d=0.0,
                a=a,
                alpha=alpha,
                q_min=lo,
                q_max=hi,
                qd_max=5.0,
                mass=m,
                com=[com[0] - a, com[1], com[2]],
                inertia=[list(r) for r in inertia],
            )
        )
    return DHRobotSpec(
        name="calderon_leg",
        joints=joints,
        ik="leg3",
        home=[0.0, math.pi / 8, -math.pi / 2],
        description=__doc__ or "",
    )


def build() -> Robot:
    return build_robot(spec())
