"""A parametric hexapod for the ``hexapod_workspace`` study: leg lengths and hip layout as data.

:class:`HexapodGeometry` (the study's ``hexapod`` parameter) describes six identical 3-joint
legs of seed 002's kind (coxa yaw, femur and tibia pitch: standard DH a = (L1, L2, L3),
α = (90°, 0, 0)) and where their hips are. Every field left out is seed 002's robot's (the
catalog's ``citedi_hexapod``). Two equivalent models of it:

- :func:`parametric_hexapod` — DH legs with the :mod:`legcore.ik.leg3` closed form (the fast
  path the study uses);
- :func:`hexapod_urdf` — the same robot as URDF text (a body link and six leg chains, x
  forward), for users' tools and for checking the study's numerical path against the closed
  form: built with ``legs: auto`` it has the same kinematics and inertias.

Layout units: m and rad, seed 002's frame (the robot walks along +y, x lateral, z up).
"""

from __future__ import annotations

import math
from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from legcore.robots.build import build_robot
from legcore.robots.catalog import citedi_hexapod as seed002
from legcore.robots.catalog._shapes import rod_inertia
from legcore.robots.legged import Leg, LeggedRobot
from legcore.robots.spec import DHJoint

__all__ = ["HexapodGeometry", "hexapod_urdf", "parametric_hexapod"]

Length = Annotated[float, Field(gt=0.0, le=10.0)]
Coord = Annotated[float, Field(ge=-10.0, le=10.0)]
Angle = Annotated[float, Field(ge=-2 * math.pi, le=2 * math.pi)]
LegName = Annotated[str, Field(min_length=1, max_length=32, pattern=r"^[A-Za-z0-9_\-]+$")]


class HexapodGeometry(BaseModel):
    """Six identical 3-joint legs and their hips (defaults: seed 002's robot).

    ``link_lengths`` (L1, L2, L3) m; ``hips``: leg name → (x, y, yaw) of its base frame (m, m,
    rad; the robot walks along +y; yaw 0 points the leg along +x); ``q_min``/``q_max``: joint
    limits (rad) of coxa, femur, tibia; ``link_masses`` kg; ``body_mass`` kg; ``body_size``
    (x, y, z extent, m); ``qd_max`` rad/s and ``tau_max`` N·m of every joint.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)
    link_lengths: tuple[Length, Length, Length] = seed002.LINKS
    hips: dict[LegName, tuple[Coord, Coord, Angle]] = Field(
        default_factory=lambda: dict(seed002.HIPS), min_length=6, max_length=6)
    q_min: tuple[Angle, Angle, Angle] = (-math.pi / 6, -math.pi / 2, -math.pi / 2)
    q_max: tuple[Angle, Angle, Angle] = (math.pi / 6, math.pi / 2, math.pi / 2)
    link_masses: tuple[Annotated[float, Field(ge=0.0, le=1e3)], ...] = Field(
        default=(0.010, 0.012, 0.008), min_length=3, max_length=3)
    body_mass: float = Field(default=0.25, ge=0.0, le=1e4)
    body_size: tuple[Length, Length, Length] = seed002.BODY_SIZE
    qd_max: float = Field(default=5.0, gt=0.0, le=1e3)
    tau_max: float = Field(default=0.18, gt=0.0, le=1e5)

    @model_validator(mode="after")
    def _limits(self) -> HexapodGeometry:
        for i, (lo, hi) in enumerate(zip(self.q_min, self.q_max, strict=True)):
            if not lo < hi:
                raise ValueError(f"q_min: joint {i} limits must satisfy q_min < q_max, got "
                                 f"({lo}, {hi})")
        return self


def _joints(g: HexapodGeometry) -> list[DHJoint]:
    names = ("coxa_yaw", "femur_pitch", "tibia_pitch")
    alphas = (math.pi / 2, 0.0, 0.0)
    return [
        DHJoint(name=n, a=a, alpha=al, q_min=lo, q_max=hi, qd_max=g.qd_max, tau_max=g.tau_max,
                mass=m, com=[-a / 2.0, 0.0, 0.0], inertia=rod_inertia(m, a, 0, 0.005))
        for n, a, al, lo, hi, m in zip(names, g.link_lengths, alphas, g.q_min, g.q_max,
                                        g.link_masses, strict=True)
    ]


def _hip(x: float, y: float, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    T = np.eye(4)
    T[:2, :2] = [[c, -s], [s, c]]
    T[:2, 3] = (x, y)
    return T


def parametric_hexapod(g: HexapodGeometry, name: str = "parametric_hexapod") -> LeggedRobot:
    """The hexapod ``g`` with DH legs (the leg3 closed form applies), seed 002's frame."""
    spec = seed002.leg_spec().model_copy(update={
        "name": f"{name}_leg", "joints": _joints(g),
        "home": [0.0, max(min(seed002.THETA2_0, g.q_max[1]), g.q_min[1]),
                 max(min(seed002.THETA3_0, g.q_max[2]), g.q_min[2])],
    })
    leg = build_robot(spec.model_validate(spec.model_dump()))
    legs = tuple(Leg(name=n, robot=leg, hip=_hip(*h)) for n, h in g.hips.items())
    return LeggedRobot(name=name, legs=legs, body_size=g.body_size, body_mass=g.body_mass,
                       meta={"source": "parametric hexapod (hexapod_workspace params)",
                             "forward": (0.0, 1.0, 0.0)})


def _inertial(mass: float, com: tuple[float, float, float], inertia: list[list[float]]) -> str:
    I = [[float(v) for v in row] for row in inertia]
    return (f'<inertial><origin xyz="{com[0]!r} {com[1]!r} {com[2]!r}"/><mass value="{mass!r}"/>'
            f'<inertia ixx="{I[0][0]!r}" ixy="{I[0][1]!r}" ixz="{I[0][2]!r}" iyy="{I[1][1]!r}" '
            f'iyz="{I[1][2]!r}" izz="{I[2][2]!r}"/></inertial>')


def hexapod_urdf(g: HexapodGeometry, name: str = "parametric_hexapod") -> str:
    """URDF text of the hexapod ``g`` in the URDF convention (body x forward, y left): hips
    turned by −90° from seed 002's frame. Joints ``<leg>_coxa``, ``<leg>_femur``,
    ``<leg>_tibia``, feet ``<leg>_foot``; build it with ``legs: auto``."""
    bx, by, bz = g.body_size
    body_I = np.diag([g.body_mass * (by**2 + bz**2), g.body_mass * (bx**2 + bz**2),
                      g.body_mass * (bx**2 + by**2)]) / 12.0
    parts = [f'<robot name="{name}">',
             f'<link name="body">{_inertial(g.body_mass, (0.0, 0.0, 0.0), body_I.tolist())}'
             "</link>"]
    names = ("coxa", "femur", "tibia")
    for leg, (x, y, yaw) in g.hips.items():
        origins = [(float(y), -float(x), 0.0, 0.0, 0.0, float(yaw) - math.pi / 2),  # x forward
                   (float(g.link_lengths[0]), 0.0, 0.0, math.pi / 2, 0.0, 0.0),
                   (float(g.link_lengths[1]), 0.0, 0.0, 0.0, 0.0, 0.0)]
        parent = "body"
        for k, (jn, o) in enumerate(zip(names, origins, strict=True)):
            a, m = g.link_lengths[k], g.link_masses[k]
            link = f"{leg}_{jn}_link"
            parts.append(f'<link name="{link}">'
                         f"{_inertial(m, (a / 2.0, 0.0, 0.0), rod_inertia(m, a, 0, 0.005))}"
                         "</link>")
            parts.append(
                f'<joint name="{leg}_{jn}" type="revolute"><parent link="{parent}"/>'
                f'<child link="{link}"/><origin xyz="{o[0]!r} {o[1]!r} {o[2]!r}" '
                f'rpy="{o[3]!r} {o[4]!r} {o[5]!r}"/><axis xyz="0 0 1"/>'
                f'<limit lower="{g.q_min[k]!r}" upper="{g.q_max[k]!r}" '
                f'effort="{g.tau_max!r}" velocity="{g.qd_max!r}"/></joint>')
            parent = link
        parts.append(f'<link name="{leg}_foot"/>')
        parts.append(f'<joint name="{leg}_foot_fixed" type="fixed"><parent link="{parent}"/>'
                     f'<child link="{leg}_foot"/><origin xyz="{g.link_lengths[2]!r} 0 0"/>'
                     "</joint>")
    parts.append("</robot>")
    return "\n".join(parts)
