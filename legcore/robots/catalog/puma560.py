"""``puma560`` — Unimation PUMA 560 with a welding gun (seed 001).

Source of the model: ``data/puma560.json`` (a copy of ``shared/reference/puma560.json``):
standard DH, masses, COMs and inertias (Armstrong, Khatib & Burdick 1986 in Corke's standard-DH
form), rotor inertia Jm, gear ratio G and motor-side friction B/Tc (Corke & Armstrong-Hélouvry
1994), as packaged by roboticstoolbox-python 1.5.0 (`rtb.models.DH.Puma560`, pedestal folded
into d1 = 0.67183 m). Rotor inertia enters as Pinocchio armature ``Jm·G²``.

Assumed values (the seed itself says these are rarely published):
- DC motors of joints 1–3: Kt = Ke = 0.228 N·m/A, R = 1.6 Ω (Corke's joint-2 value, used for
  all three); joints 4–6 have no electrical data, so electrical energy covers joints 1–3.
- Joint speed limits (rad/s): 2.5 for joints 1–3, 5.0 for the wrist — typical of the arm, not
  from the seed.
- Link 1 inertia: the reference's massless I_yy = 0.35 kg·m² gets I_xx = I_zz = 0.175 kg·m² so
  that it is a physical rigid body; link 1 only spins about y1, so joint torques are unchanged.
- Link 3 inertia: the reference (0.066, 0.086, 0.0125) kg·m² violates the triangle inequality
  (0.066 + 0.0125 < 0.086); I_zz is raised to 0.020 kg·m², the smallest physical value. This
  does change the dynamics slightly (joint 1's too: M[0,0] by up to 0.0075 kg·m²).
- Welding gun (Tough Gun G2 in seed 001, whose catalogue data we do not have): a rigid tool of
  1.0 kg whose tip is 0.20 m along z6 from the wrist centre, COM at 0.10 m; its mass is added to
  link 6. ``build(tool=False)`` gives the bare arm.
"""

from __future__ import annotations

import json
from importlib import resources
from typing import Any

import numpy as np

from legcore.robots.build import build_robot
from legcore.robots.model import Robot
from legcore.robots.spec import DHJoint, DHRobotSpec, MotorSpec

KT = 0.228  # N·m/A (assumed, see module docstring)
KE = 0.228  # V·s/rad
R_ARMATURE = 1.6  # Ω
QD_MAX = (2.5, 2.5, 2.5, 5.0, 5.0, 5.0)  # rad/s (assumed)
GUN_MASS = 1.0  # kg (assumed)
GUN_TIP = 0.20  # m along z6 (assumed)
GUN_COM = 0.10  # m along z6 (assumed)


def reference() -> dict[str, Any]:
    """The packaged PUMA 560 reference parameters (SI, standard DH)."""
    text = resources.files("legcore.robots").joinpath("data/puma560.json").read_text()
    data: dict[str, Any] = json.loads(text)
    return data


def _with_gun(
    m: float, com: np.ndarray, inertia: np.ndarray
) -> tuple[float, np.ndarray, np.ndarray]:
    """Combine link 6 with a point-mass gun on z6 (parallel-axis theorem)."""
    gun = np.array([0.0, 0.0, GUN_COM])
    mt = m + GUN_MASS
    c = (m * com + GUN_MASS * gun) / mt

    def shift(mass: float, r: np.ndarray) -> np.ndarray:
        return mass * (float(r @ r) * np.eye(3) - np.outer(r, r))

    I = inertia + shift(m, com - c) + shift(GUN_MASS, gun - c)
    return mt, c, I


def spec(tool: bool = True) -> DHRobotSpec:
    ref = reference()
    joints = []
    for i, link in enumerate(ref["links"]):
        m = float(link["m"])
        com = np.asarray(link["r_com"], dtype=float)
        inertia = np.asarray(link["I_com"], dtype=float)
        if i == 0:
            # Link 1 is given as a massless I_yy = 0.35 kg·m² about the joint-1 axis (y1), which
            # no rigid body has (triangle inequality). Link 1 only ever spins about y1, so
            # I_xx = I_zz = I_yy / 2 makes it physical without changing any joint torque.
            inertia = np.diag([inertia[1, 1] / 2, inertia[1, 1], inertia[1, 1] / 2])
        if i == 2:
            # AKB86's link 3 (0.066, 0.086, 0.0125) violates I_xx + I_zz >= I_yy; raise I_zz to
            # the smallest physical value, 0.020 kg·m² (it only weighs rotation about the forearm).
            inertia[2, 2] = max(inertia[2, 2], inertia[1, 1] - inertia[0, 0])
        if tool and i == 5:
            m, com, inertia = _with_gun(m, com, inertia)
        electrical = i < 3
        joints.append(
            DHJoint(
                name=f"joint_{i + 1}",
                d=link["d"],
                a=link["a"],
                alpha=link["alpha"],
                offset=link["offset"],
                q_min=link["qlim"][0],
                q_max=link["qlim"][1],
                qd_max=QD_MAX[i],
                mass=m,
                com=com.tolist(),
                inertia=inertia.tolist(),
                motor=MotorSpec(
                    G=link["G"],
                    Jm=link["Jm"],
                    B=link["B"],
                    Tc_pos=link["Tc_pos"],
                    Tc_neg=link["Tc_neg"],
                    Kt=KT if electrical else None,
                    Ke=KE if electrical else None,
                    R=R_ARMATURE if electrical else None,
                ),
            )
        )
    tool_T = np.eye(4)
    if tool:
        tool_T[2, 3] = GUN_TIP
    return DHRobotSpec(
        name="puma560",
        joints=joints,
        tool=tool_T.tolist(),
        ik="puma560",
        home=list(ref["named_poses"]["qn"]),
        description=__doc__ or "",
    )


def build(tool: bool = True) -> Robot:
    return build_robot(spec(tool=tool))
