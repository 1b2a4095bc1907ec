"""``animatronic_quadruped`` — the animatronic dog platform of seed 003.

Source: seed 003 (Pailos, Bima, Libal — "Plataforma de Emulación de Animales Cuadrúpedos:
Cinemática de las Patas", IX Jornadas Argentinas de Robótica 2017): DH Table 1 and eqs (1)–(3)
(front right leg), law-of-cosines IK eqs (5)–(9), Fig. 1 (front legs elbow back, rear legs knee
forward), Fig. 8 (gait, see :mod:`legcore.gaits`), Table 2 (servo angle sequence).

Body frame x forward, y left, z up (m). The paper's platform frame has x forward, y up and z to
the right (its legs move in its x–y plane); we convert once here.

Each leg is the planar 2-DOF chain of :mod:`legcore.ik.leg2`: base frame at the hip/shoulder
joint with **x down, y forward, z to the robot's right** (the paper's frame 2, after Table 1's
fixed θ = 3π/2), standard DH a = (l1, l2), α = 0, d = 0. All four legs use the same orientation,
so a positive angle always swings the foot forward and the branch is the sign of q4:
front legs (FL, FR) ``q4 ≥ 0`` (elbow back), rear legs (RL, RR) ``q4 ≤ 0`` (knee forward).
The joint limits encode the branch.

Hip placement (Table 1, front right): 0.11 m forward, d0 = 0.063 m to the side, then a1 = 0.02 m
down along the rotated x — hips at (±0.11, ±0.063, −0.02) m.

Paper inconsistencies and our choices:

* Thigh length: Table 1 says a2 = 0.065 m, the matrix ²A₃ of eq (1) uses 0.085 m. We take
  **0.085 m**: with it Table 2's stroke is level — the foot depth below the hip at the first and
  last printed positions (1 and 48) is 0.1649/0.1648 m (front) and 0.1647/0.1648 m (rear), the
  same for front and rear legs; with 0.065 m the two ends differ by 2.1–2.2 mm and the front
  and rear legs by 2.3 mm (a tilted body, dragging feet). Shank 0.0925 m (both agree).
* Hip offset: Table 1 puts 0.063 m along z (sideways); ⁰A₁ in eq (2) puts 0.088 m along the
  paper's y (up) and nothing sideways, which would mount the hips above the platform. We keep
  Table 1's lateral 0.063 m (Table 2 cannot decide this one: it does not affect leg angles).
* ¹A₂ in eq (2) has a −1 in its (2,2) entry; Rz(3π/2) has 0 there (the printed matrix is not a
  rotation). We use Rz(3π/2), i.e. Table 1.
* The torque is printed "0.012 kg./m."; we read it as 0.012 kgf·m = 0.118 N·m (``tau_max``).

Servo mapping (Table 2): the servos are driven from the *link angles* ``Ang3 = 90° − q3`` (thigh)
and ``Ang4 = 90° − (q3 + q4)`` (shank), measured from the forward horizontal turning down; every
printed row satisfies ``q3 = 90° − Ang3`` and ``q4 = Ang3 − Ang4`` (mod 360°). Physically
mirrored servos then need a per-servo offset and direction (the paper's "mapear" + offset tests),
stored in ``meta["servo"]``. See :func:`legcore.ik.leg2.leg2_link_angles_deg`.

Assumed (not in the paper): masses thigh 25 g, shank 12 g (COM mid-link, solid rod of radius
8 mm), body 0.30 kg of 0.24 × 0.126 × 0.02 m; joint limits q3 ∈ [−90°, 90°] (Ang3 ∈ [0°, 180°],
a standard servo's travel) and q4 ∈ [0°, 135°] front / [−135°, 0°] rear; 5 rad/s. Home: the
foot 0.175 m straight below the hip on each leg's branch (|q4| = 19.3°: Table 2 keeps the
hip–foot distance near 0.175 m, |q4| = 17°–20°, through its stroke).
"""

from __future__ import annotations

import math

import numpy as np

from legcore.ik.leg2 import ELBOW_BACK, KNEE_FORWARD, leg2_ik
from legcore.robots.build import build_robot
from legcore.robots.catalog._shapes import rod_inertia
from legcore.robots.legged import Leg, LeggedRobot
from legcore.robots.spec import DHJoint, DHRobotSpec

__all__ = [
    "BODY_SIZE",
    "BRANCH",
    "HIPS",
    "HOME_DEPTH",
    "LEG_NAMES",
    "LINKS",
    "PAPER_NAMES",
    "R_LEG",
    "TABLE2",
    "build",
    "hip",
    "leg_spec",
]

LINKS = (0.085, 0.0925)  # l1 thigh/upper arm, l2 shank/forearm (m) — eq (1), see docstring
BODY_SIZE = (0.24, 0.126, 0.02)  # m (assumed; Fig. 3 with the dimensions is an image)
HOME_DEPTH = 0.175  # m, foot below the hip at home (|q4| ≈ 19°, as in Table 2)
LEG_NAMES = ("FL", "FR", "RL", "RR")
PAPER_NAMES = {"FL": "PDI", "FR": "PDD", "RL": "PTI", "RR": "PTD"}
BRANCH = {"FL": ELBOW_BACK, "FR": ELBOW_BACK, "RL": KNEE_FORWARD, "RR": KNEE_FORWARD}
HIPS: dict[str, tuple[float, float, float]] = {  # hip joint position in the body frame (m)
    "FL": (0.11, 0.063, -0.02),
    "FR": (0.11, -0.063, -0.02),
    "RL": (-0.11, 0.063, -0.02),
    "RR": (-0.11, -0.063, -0.02),
}
# Leg base axes in the body frame: columns x_leg = down, y_leg = forward, z_leg = right.
R_LEG = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [-1.0, 0.0, 0.0]])

# Seed 003 Table 2 (printed rows): position, front (Ang3, Ang4, q3DA, q4DA),
# rear (Ang3, Ang4, q3TA, q4TA) — degrees.
TABLE2 = (
    (1, (81, 61, 369, 20), (60, 80, 30, 340)),
    (2, (82, 62, 368, 20), (61, 81, 29, 340)),
    (3, (83, 63, 367, 20), (62, 82, 28, 340)),
    (4, (84, 64, 366, 20), (63, 83, 27, 340)),
    (45, (116, 99, 334, 17), (99, 115, 351, 344)),
    (46, (117, 100, 333, 17), (100, 116, 350, 344)),
    (47, (118, 101, 332, 17), (101, 117, 349, 344)),
    (48, (119, 102, 331, 17), (102, 118, 348, 344)),
)

_MASS = (0.025, 0.012)  # kg (assumed)
_TAU_MAX = 0.012 * 9.80665  # N·m: 0.012 kgf·m as printed
_Q4_LIMITS = {ELBOW_BACK: (0.0, 3.0 * math.pi / 4.0), KNEE_FORWARD: (-3.0 * math.pi / 4.0, 0.0)}


def hip(name: str) -> np.ndarray:
    """4×4 placement (m) of leg ``name``'s base frame (x down, y forward, z right) in the body."""
    if name not in HIPS:
        raise KeyError(f"no leg named {name!r}; legs are {list(HIPS)}")
    T = np.eye(4)
    T[:3, :3] = R_LEG
    T[:3, 3] = HIPS[name]
    return T


def leg_spec(front: bool) -> DHRobotSpec:
    """DH specification of a front (elbow-back) or rear (knee-forward) leg."""
    branch = ELBOW_BACK if front else KNEE_FORWARD
    q4_lo, q4_hi = _Q4_LIMITS[branch]
    limits = ((-math.pi / 2.0, math.pi / 2.0), (q4_lo, q4_hi))
    names = ("shoulder", "elbow") if front else ("hip", "knee")
    q_home, ok = leg2_ik([HOME_DEPTH, 0.0], LINKS, branch)
    if not bool(ok):  # pragma: no cover - constant data
        raise RuntimeError("HOME_DEPTH is out of the leg's reach")
    joints = [
        DHJoint(
            name=name,
            d=0.0,
            a=a,
            alpha=0.0,
            q_min=lo,
            q_max=hi,
            qd_max=5.0,
            tau_max=_TAU_MAX,
            mass=m,
            com=[-a / 2.0, 0.0, 0.0],
            inertia=rod_inertia(m, a, 0, 0.008),
        )
        for name, a, m, (lo, hi) in zip(names, LINKS, _MASS, limits, strict=True)
    ]
    return DHRobotSpec(
        name="animatronic_quadruped_" + ("front_leg" if front else "rear_leg"),
        joints=joints,
        ik="leg2",
        gravity=[9.81, 0.0, 0.0],  # the leg base frame has x pointing down
        home=[float(v) for v in q_home],
        description=(
            "2-DOF leg of the seed 003 quadruped (l = 0.085, 0.0925 m), base frame x down, "
            "y forward, z right; "
            + ("front: elbow back, q4 >= 0." if front else "rear: knee forward, q4 <= 0.")
            + " Masses and limits assumed; see legcore.robots.catalog.animatronic_quadruped."
        ),
    )


def build() -> LeggedRobot:
    front = build_robot(leg_spec(front=True))
    rear = build_robot(leg_spec(front=False))
    legs = tuple(
        Leg(name=n, robot=front if n.startswith("F") else rear, hip=hip(n)) for n in LEG_NAMES
    )
    return LeggedRobot(
        name="animatronic_quadruped",
        legs=legs,
        body_size=BODY_SIZE,
        body_mass=0.30,
        meta={
            "source": "seed 003 Table 1, eqs (1)-(9), Fig. 8, Table 2",
            "forward": (1.0, 0.0, 0.0),
            "links": LINKS,
            "branch": dict(BRANCH),
            "paper_names": dict(PAPER_NAMES),
            "gait": "quadruped_walk",
            "servo": {
                # link angles (deg) from q (deg): Ang = offset + matrix @ q  (Table 2)
                "link_angle_offset_deg": (90.0, 90.0),
                "link_angle_matrix": ((-1.0, 0.0), (-1.0, -1.0)),
                # per-servo mounting, applied to the link angles; the paper gives no values
                # for its mirrored servos, so identity here (offset 0, direction +1)
                "servo_offset_deg": {n: (0.0, 0.0) for n in LEG_NAMES},
                "servo_direction": {n: (1, 1) for n in LEG_NAMES},
            },
        },
    )
