"""``citedi_hexapod`` — the CITEDI-IPN laboratory hexapod of seed 002.

Source: seed 002 (Domínguez, Sepúlveda, Montiel, Castillo — "Identificación del campo de trabajo
de un robot hexápodo utilizando optimización multiobjetivo"), Table 1 (DH of a leg), eqs (5)–(10),
§4: l1 = 1 cm, l2 = 3.5 cm, l3 = 6 cm, body width W = 10 cm, length L = 7 cm, initial posture
θ1 = 0, θ2 = −π/8, θ3 = −π/4 (foot height z = −6.8827 cm), search range θ1 ∈ [−π/6, π/6];
Fig. 3 (tripod gait, see :data:`legcore.gaits.TRIPOD`).

Legs: each is the 3-DOF chain of :mod:`legcore.ik.leg3` — standard DH a = (L1, L2, L3),
α = (+90°, 0, 0), d = 0, leg base frame z up and x along the leg at θ1 = 0. Table 1 prints
α1 = ±90°; +90° is the sign for which eqs (5)–(7) hold with z up (we mirror legs by a yaw of π
instead of flipping α).

Body frame — the paper's (DESIGN.md): **the robot walks along +y**, x is lateral, z up. (This
differs from the x-forward default of :mod:`legcore.robots.legged`; ``meta["forward"]`` says so.)
Hips, in cm (DESIGN.md, verified against Table 2 — its 24 printed foot coordinates of solutions
a–d are reproduced from their θ1 to ±0.001 cm):

    leg  hip (x, y)     leg points     leg  hip (x, y)     leg points
    L1   (+3.5, +5)     +x             L4   (−3.5, +5)     −x  (yaw π)
    L2   (+3.5,  0)     +x             L5   (−3.5,  0)     −x  (yaw π)
    L3   (+3.5, −5)     +x             L6   (−3.5, −5)     −x  (yaw π)

Legs 1, 3, 5 and the body come from the paper; "legs 2, 4, 6 mirrored": leg 2 is the paper's
central leg on the side of legs 1 and 3 (its text), while which of 4 and 6 is in front is not in
the text (Fig. 1 is an image) — we assume leg 4 front (mirror of 1) and leg 6 back (mirror of 3).
The paper calls the side of legs 1, 3 "left"; with z up and forward +y that is geometrically the
robot's right — we keep the paper's numbering and coordinates and avoid the words in code.
Stance 1-3-5 advances with θ1,1 and θ1,3 decreasing and θ1,5 increasing (seed 002 §3), which moves
the feet towards −y in the body frame: forward is +y, so leg 1 is front, 3 back, 5 middle.

Assumed (not in the paper): joint limits θ1 ∈ [−π/6, π/6] (the paper's search range), θ2, θ3 ∈
[−π/2, π/2] (hobby-servo range); 5 rad/s; 0.18 N·m (a 9 g micro servo); masses coxa 10 g,
femur 12 g, tibia 8 g (servo-scale), COM mid-link, solid-rod inertia of radius 5 mm; body 0.25 kg
and 2 cm thick.
"""

from __future__ import annotations

import math

import numpy as np

from legcore.robots.build import build_robot
from legcore.robots.catalog._shapes import rod_inertia
from legcore.robots.legged import Leg, LeggedRobot
from legcore.robots.spec import DHJoint, DHRobotSpec

__all__ = [
    "BODY_SIZE",
    "HIPS",
    "LEG_NAMES",
    "LINKS",
    "STANCE_135",
    "STANCE_246",
    "THETA2_0",
    "THETA3_0",
    "build",
    "hip",
    "leg_spec",
]

LINKS = (0.01, 0.035, 0.06)  # L1, L2, L3 (m) — seed 002 §4
BODY_SIZE = (0.07, 0.10, 0.02)  # extent along x (L = 7 cm), y (W = 10 cm), z (assumed) (m)
THETA2_0 = -math.pi / 8  # rad — seed 002 §4 initial / constant femur angle
THETA3_0 = -math.pi / 4  # rad — seed 002 §4 initial / constant tibia angle
LEG_NAMES = ("L1", "L2", "L3", "L4", "L5", "L6")
# hip (x, y) in m and the yaw of the leg base frame (rad)
HIPS: dict[str, tuple[float, float, float]] = {
    "L1": (0.035, 0.05, 0.0),
    "L2": (0.035, 0.0, 0.0),
    "L3": (0.035, -0.05, 0.0),
    "L4": (-0.035, 0.05, math.pi),
    "L5": (-0.035, 0.0, math.pi),
    "L6": (-0.035, -0.05, math.pi),
}
STANCE_135 = {"front": "L1", "middle": "L5", "back": "L3"}  # tripod of states 1–2 (Fig. 3)
STANCE_246 = {"front": "L4", "middle": "L2", "back": "L6"}  # tripod of states 4–5

_MASS = (0.010, 0.012, 0.008)  # kg (assumed)
_LIMITS = ((-math.pi / 6, math.pi / 6), (-math.pi / 2, math.pi / 2), (-math.pi / 2, math.pi / 2))
_NAMES = ("coxa_yaw", "femur_pitch", "tibia_pitch")


def hip(name: str) -> np.ndarray:
    """4×4 placement (m) of leg ``name``'s base frame in the body frame."""
    if name not in HIPS:
        raise KeyError(f"no leg named {name!r}; legs are {list(HIPS)}")
    x, y, yaw = HIPS[name]
    c, s = math.cos(yaw), math.sin(yaw)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:2, 3] = (x, y)
    return T


def leg_spec() -> DHRobotSpec:
    """The DH specification of one leg (all six are identical chains)."""
    alphas = (math.pi / 2, 0.0, 0.0)
    joints = [
        DHJoint(
            name=name,
            d=0.0,
            a=a,
            alpha=alpha,
            q_min=lo,
            q_max=hi,
            qd_max=5.0,
            tau_max=0.18,
            mass=m,
            com=[-a / 2.0, 0.0, 0.0],
            inertia=rod_inertia(m, a, 0, 0.005),
        )
        for name, a, alpha, m, (lo, hi) in zip(_NAMES, LINKS, alphas, _MASS, _LIMITS, strict=True)
    ]
    return DHRobotSpec(
        name="citedi_hexapod_leg",
        joints=joints,
        ik="leg3",
        home=[0.0, THETA2_0, THETA3_0],
        description=(
            "One 3-DOF leg of the seed 002 hexapod (L = 1, 3.5, 6 cm; alpha1 = +90 deg). "
            "Masses, limits and speeds assumed; see legcore.robots.catalog.citedi_hexapod."
        ),
    )


def build() -> LeggedRobot:
    robot = build_robot(leg_spec())
    legs = tuple(Leg(name=n, robot=robot, hip=hip(n)) for n in LEG_NAMES)
    return LeggedRobot(
        name="citedi_hexapod",
        legs=legs,
        body_size=BODY_SIZE,
        body_mass=0.25,
        meta={
            "source": "seed 002 Table 1, eqs (5)-(10), section 4",
            "forward": (0.0, 1.0, 0.0),
            "links": LINKS,
            "theta2_0": THETA2_0,
            "theta3_0": THETA3_0,
            "tripods": (("L1", "L3", "L5"), ("L2", "L4", "L6")),
            "stance_135": STANCE_135,
            "stance_246": STANCE_246,
            "gait": "tripod",
        },
    )
