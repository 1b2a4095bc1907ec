"""``articulated_5dof`` — the 5-DOF articulated arm of seed 004 (Fig. 18).

Standard DH from seed 004 Fig. 18: d1 = 0.50 m, a2 = a3 = 0.40 m, d5 = 0.20 m,
α = (90°, 0, 0, 90°, 0); home (0, 90°, −90°, 90°, 0). The paper gives no masses, limits or
motors; for dynamics we assume light aluminium-tube links (masses 2.0, 1.5, 1.2, 0.4, 0.3 kg,
COM mid-link, solid-cylinder inertia of radius 3 cm), joint limits ±180°, speed limits 1.5 rad/s
and torque limits (40, 40, 20, 5, 2) N·m. All assumed; the kinematics are the paper's.
"""

from __future__ import annotations

import math

from legcore.robots.build import build_robot
from legcore.robots.catalog._shapes import rod_inertia
from legcore.robots.model import Robot
from legcore.robots.spec import DHJoint, DHRobotSpec

D1, A2, A3, D5 = 0.50, 0.40, 0.40, 0.20  # m
_MASS = (2.0, 1.5, 1.2, 0.4, 0.3)  # kg (assumed)
_TAU_MAX = (40.0, 40.0, 20.0, 5.0, 2.0)  # N·m (assumed)


def spec() -> DHRobotSpec:
    m = _MASS
    # COM of each link in its own (distal) DH frame: the column of link 1 runs along −y1,
    # links 2 and 3 along −x, the wrist link 5 along −z5.
    rows = [
        (D1, 0.0, math.pi / 2, [0.0, -D1 / 2, 0.0], rod_inertia(m[0], D1, 1, 0.03)),
        (0.0, A2, 0.0, [-A2 / 2, 0.0, 0.0], rod_inertia(m[1], A2, 0, 0.03)),
        (0.0, A3, 0.0, [-A3 / 2, 0.0, 0.0], rod_inertia(m[2], A3, 0, 0.03)),
        (0.0, 0.0, math.pi / 2, [0.0, 0.0, 0.0], rod_inertia(m[3], 0.06, 2, 0.03)),
        (D5, 0.0, 0.0, [0.0, 0.0, -D5 / 2], rod_inertia(m[4], D5, 2, 0.02)),
    ]
    joints = [
        DHJoint(
            name=f"joint_{i + 1}",
            d=d,
            a=a,
            alpha=alpha,
            q_min=-math.pi,
            q_max=math.pi,
            qd_max=1.5,
            tau_max=_TAU_MAX[i],
            mass=m[i],
            com=com,
            inertia=inertia,
        )
        for i, (d, a, alpha, com, inertia) in enumerate(rows)
    ]
    return DHRobotSpec(
        name="articulated_5dof",
        joints=joints,
        ik="arm5_down",
        home=[0.0, math.pi / 2, -math.pi / 2, math.pi / 2, 0.0],
        description=__doc__ or "",
    )


def build() -> Robot:
    return build_robot(spec())
