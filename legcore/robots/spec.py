"""Robot model specifications (JSON/YAML-able) and their physical validation.

A specification is plain data: it is what a user submits and what the store keeps. `build_robot`
(in :mod:`legcore.robots.build`) turns a valid specification into a Pinocchio model.

Units: lengths in m, angles in rad, masses in kg, inertias in kg·m², velocities in rad/s (m/s for
prismatic joints), motor constants in SI (N·m/A, V·s/rad, Ω, N·m·s/rad, N·m).

Every rule rejects bad input with a message that names the field and the reason, e.g.
``joints.1.inertia: not positive semi-definite (smallest eigenvalue -2.0e-03 kg·m²)``.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    Tag,
    field_validator,
    model_validator,
)

__all__ = [
    "FiniteFloat",
    "MotorSpec",
    "DHJoint",
    "DHRobotSpec",
    "LegSpec",
    "URDFRobotSpec",
    "RobotSpec",
    "validate_inertia",
]

FiniteFloat = Annotated[float, Field(allow_inf_nan=False)]
Vec3 = Annotated[list[FiniteFloat], Field(min_length=3, max_length=3)]
Row3 = Annotated[list[FiniteFloat], Field(min_length=3, max_length=3)]
Row4 = Annotated[list[FiniteFloat], Field(min_length=4, max_length=4)]
Matrix3 = Annotated[list[Row3], Field(min_length=3, max_length=3)]
Matrix4 = Annotated[list[Row4], Field(min_length=4, max_length=4)]

_INERTIA_TOL = 1e-12  # kg·m², absolute slack for symmetry / PSD / triangle checks


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


def validate_inertia(inertia: np.ndarray, tol: float = 0.0) -> None:
    """Check a 3×3 rotational inertia about the COM (kg·m²) for physical consistency.

    Raises ``ValueError`` if it is not symmetric, not positive semi-definite, or its principal
    moments violate the triangle inequality ``I_a + I_b >= I_c`` by more than the slack: the
    larger of ``tol`` (kg·m², e.g. a tolerance relative to the whole robot's scale) and 1e-12
    times ``max(1, max |I_ij|)`` (rounding).
    """
    inertia = np.asarray(inertia, dtype=float)
    if inertia.shape != (3, 3):
        raise ValueError(f"must be a 3x3 matrix, got shape {inertia.shape}")
    slack = max(float(tol), _INERTIA_TOL * max(1.0, float(np.abs(inertia).max())))
    asym = float(np.abs(inertia - inertia.T).max())
    if asym > slack:
        raise ValueError(f"not symmetric (max |I - I^T| = {asym:.3e} kg·m²)")
    eig = np.linalg.eigvalsh(0.5 * (inertia + inertia.T))
    if eig[0] < -slack:
        raise ValueError(f"not positive semi-definite (smallest eigenvalue {eig[0]:.3e} kg·m²)")
    a, b, c = eig  # ascending
    if a + b < c - slack:
        raise ValueError(
            f"principal moments ({a:.3e}, {b:.3e}, {c:.3e}) kg·m² violate the triangle "
            f"inequality I_a + I_b >= I_c by {c - a - b:.3e} kg·m²"
        )


class MotorSpec(_Strict):
    """Actuator behind one joint (seed 001 eqs 9–14; friction as in the PUMA 560 reference).

    ``G`` is the gear ratio (motor turns per joint turn, may be negative), ``Jm`` the rotor inertia
    on the motor side (kg·m²; reflected to the joint as ``Jm·G²`` = Pinocchio armature), ``Kt``
    torque constant (N·m/A), ``Ke`` back-EMF constant (V·s/rad), ``R`` armature resistance (Ω),
    ``B`` viscous friction (N·m·s/rad, motor side), ``Tc_pos``/``Tc_neg`` Coulomb friction
    (N·m, motor side) for positive / negative motor velocity.
    """

    G: FiniteFloat = 1.0
    Jm: FiniteFloat = 0.0
    Kt: FiniteFloat | None = None
    Ke: FiniteFloat | None = None
    R: FiniteFloat | None = None
    B: FiniteFloat = 0.0
    Tc_pos: FiniteFloat = 0.0
    Tc_neg: FiniteFloat = 0.0

    @field_validator("G")
    @classmethod
    def _nonzero_ratio(cls, v: float) -> float:
        if v == 0.0:
            raise ValueError("gear ratio must be non-zero")
        return v

    @field_validator("Jm", "B")
    @classmethod
    def _nonnegative(cls, v: float) -> float:
        if v < 0.0:
            raise ValueError("must be >= 0")
        return v

    @field_validator("Kt", "Ke", "R")
    @classmethod
    def _positive(cls, v: float | None) -> float | None:
        if v is not None and v <= 0.0:
            raise ValueError("must be > 0")
        return v

    @property
    def electrical(self) -> bool:
        """True when Kt, Ke and R are all known (electrical energy can be computed)."""
        return self.Kt is not None and self.Ke is not None and self.R is not None


class DHJoint(_Strict):
    """One joint + the link it moves, in Denavit–Hartenberg parameters.

    Standard DH (distal): ``A_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i)``, ``θ_i = q_i + offset`` for a
    revolute joint, ``d_i = d + q_i`` for a prismatic one. Modified DH (Craig):
    ``A_i = Rx(α_{i-1}) Tx(a_{i-1}) Rz(θ_i) Tz(d_i)`` where ``a``/``alpha`` of this entry are the
    ones *before* the joint. ``com`` (m) and ``inertia`` (kg·m², about the COM, axes parallel to the
    frame) are expressed in the link frame: DH frame i (after the transform) for standard DH, the
    joint frame for modified DH.
    """

    type: Literal["revolute", "prismatic"] = "revolute"
    name: str | None = Field(default=None, max_length=64)
    d: FiniteFloat = 0.0
    a: FiniteFloat = 0.0
    alpha: FiniteFloat = 0.0
    offset: FiniteFloat = 0.0
    q_min: FiniteFloat = -math.pi
    q_max: FiniteFloat = math.pi
    qd_max: FiniteFloat = 10.0
    qdd_max: FiniteFloat | None = None
    tau_max: FiniteFloat | None = None
    mass: FiniteFloat = 0.0
    com: Vec3 = Field(default_factory=lambda: [0.0, 0.0, 0.0])
    inertia: Matrix3 = Field(default_factory=lambda: [[0.0] * 3 for _ in range(3)])
    motor: MotorSpec | None = None

    @field_validator("mass")
    @classmethod
    def _mass_nonnegative(cls, v: float) -> float:
        if v < 0.0:
            raise ValueError(f"mass must be >= 0 kg, got {v}")
        return v

    @field_validator("qd_max")
    @classmethod
    def _speed_positive(cls, v: float) -> float:
        if v <= 0.0:
            raise ValueError(f"must be > 0, got {v}")
        return v

    @field_validator("tau_max", "qdd_max")
    @classmethod
    def _torque_positive(cls, v: float | None) -> float | None:
        if v is not None and v <= 0.0:
            raise ValueError(f"must be > 0, got {v}")
        return v

    @field_validator("inertia")
    @classmethod
    def _inertia_physical(cls, v: list[list[float]]) -> list[list[float]]:
        validate_inertia(np.asarray(v, dtype=float))
        return v

    @model_validator(mode="after")
    def _limits_ordered(self) -> DHJoint:
        if not self.q_min < self.q_max:
            raise ValueError(f"q_min ({self.q_min}) must be < q_max ({self.q_max})")
        return self


def _check_homogeneous(T: list[list[float]] | None, field: str) -> None:
    if T is None:
        return
    M = np.asarray(T, dtype=float)
    R = M[:3, :3]
    if not np.allclose(M[3], [0.0, 0.0, 0.0, 1.0], atol=1e-9):
        raise ValueError(f"{field}: last row must be [0, 0, 0, 1]")
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0.0:
        raise ValueError(f"{field}: upper-left 3x3 block must be a rotation matrix")


class DHRobotSpec(_Strict):
    """A serial chain given by a DH table (1–12 joints)."""

    kind: Literal["dh"] = "dh"
    name: str = Field(min_length=1, max_length=64)
    convention: Literal["standard", "modified"] = "standard"
    joints: list[DHJoint] = Field(min_length=1, max_length=12)
    base: Matrix4 | None = None
    tool: Matrix4 | None = None
    gravity: Vec3 = Field(default_factory=lambda: [0.0, 0.0, -9.81])
    home: list[FiniteFloat] | None = None
    ik: Literal["puma560", "leg3", "leg2", "arm5_down", "dls"] | None = None
    description: str = Field(default="", max_length=4000)

    @model_validator(mode="after")
    def _consistent(self) -> DHRobotSpec:
        _check_homogeneous(self.base, "base")
        _check_homogeneous(self.tool, "tool")
        if self.home is not None:
            if len(self.home) != len(self.joints):
                raise ValueError(
                    f"home: has {len(self.home)} values but the robot has {len(self.joints)} joints"
                )
            for i, (qh, j) in enumerate(zip(self.home, self.joints, strict=True)):
                if not j.q_min <= qh <= j.q_max:
                    raise ValueError(f"home.{i}: {qh} outside [q_min, q_max] of joint {i}")
        return self


#: A leg name (also the prefix of its joints' names in listings and recordings).
LegName = Annotated[str, Field(min_length=1, max_length=32, pattern=r"^[A-Za-z0-9_\-]+$")]
#: A joint, link or frame name of a URDF.
URDFName = Annotated[str, Field(min_length=1, max_length=200)]


class LegSpec(_Strict):
    """One leg of a legged URDF robot, named by its ``foot`` (a link or frame: the leg is the
    chain of moving joints from the base down to it), by its ``hip`` joint (the leg is that joint
    and the joints below it, down to the leaf of its subtree, whose end frame is the foot), or by
    both (the chain from ``hip`` to ``foot``)."""

    hip: URDFName | None = None
    foot: URDFName | None = None

    @model_validator(mode="after")
    def _named(self) -> LegSpec:
        if self.hip is None and self.foot is None:
            raise ValueError("name the leg by its 'hip' joint, its 'foot' frame, or both")
        return self


class URDFRobotSpec(_Strict):
    """A robot given as URDF text: a serial chain, or a legged robot when ``legs`` is given.

    Only kinematics and inertias are read; meshes and every other file name in the text stay
    strings (never opened). ``continuous`` joints become revolute joints limited to ±2π rad.

    ``locked_joints`` — joints the study does not move (gripper fingers, a head, the other legs
    …), each held at the given value (rad or m) or, when the value is null, at its home value
    (zero clipped to the joint's limits). A ``<mimic>`` joint follows its master: it is locked
    with it (at ``multiplier · master + offset``) and cannot move on its own.

    ``tool_frame`` — a serial chain's end frame (a link or frame attached to its last moving
    joint); by default the leaf of the chain's end: the frame attached to the last joint that
    no other frame hangs from, the one farthest from that joint on a tie.

    ``legs`` — a legged robot: a floating base (the root link) carrying legs, each a serial
    chain of moving joints; ``"auto"`` finds one leg per leaf of the joint tree (named by the
    common prefix of its joints' names, e.g. ``FL`` for ``FL_HAA, FL_HFE, FL_KFE``, else by its
    foot). Every moving joint must belong to exactly one leg (lock the others). ``leg`` — build
    only that leg, as a fixed-base serial chain whose base frame sits at its hip joint (axes of
    the body), for the single-leg studies.
    """

    kind: Literal["urdf"] = "urdf"
    name: str = Field(min_length=1, max_length=64)
    urdf: str = Field(min_length=1, max_length=2_000_000)
    tool_frame: URDFName | None = None
    locked_joints: dict[URDFName, FiniteFloat | None] = Field(default_factory=dict, max_length=500)
    legs: dict[LegName, LegSpec] | Literal["auto"] | None = None
    leg: LegName | None = None
    motors: dict[str, MotorSpec] = Field(default_factory=dict)
    qdd_max: dict[URDFName, FiniteFloat] = Field(default_factory=dict, max_length=500)
    gravity: Vec3 = Field(default_factory=lambda: [0.0, 0.0, -9.81])
    description: str = Field(default="", max_length=4000)

    @field_validator("qdd_max")
    @classmethod
    def _accelerations_positive(cls, v: dict[str, float]) -> dict[str, float]:
        bad = {k: x for k, x in v.items() if not x > 0.0}
        if bad:
            raise ValueError(f"acceleration limits must be > 0 rad/s² (m/s²), got {bad}")
        return v

    @field_validator("legs")
    @classmethod
    def _some_legs(cls, v: dict[str, LegSpec] | str | None) -> dict[str, LegSpec] | str | None:
        if isinstance(v, dict) and not 1 <= len(v) <= 8:
            raise ValueError(f"a legged robot has 1 to 8 legs, got {len(v)}")
        return v

    @model_validator(mode="after")
    def _legs_consistent(self) -> URDFRobotSpec:
        if self.legs is not None and self.tool_frame is not None:
            raise ValueError(
                "tool_frame: a legged robot's legs end at their feet; name them in "
                "legs.<leg>.foot instead"
            )
        if self.leg is not None:
            if self.legs is None:
                raise ValueError(
                    f"leg: {self.leg!r} names a leg of a legged robot; give 'legs' too "
                    "(e.g. legs: auto)"
                )
            if isinstance(self.legs, dict) and self.leg not in self.legs:
                raise ValueError(f"leg: no leg {self.leg!r} in legs {sorted(self.legs)}")
        return self


def _robot_kind(value: object) -> str | None:
    """The ``kind`` tag of a robot spec; a mapping without one is a DH spec (the default)."""
    if isinstance(value, dict):
        kind = value.get("kind", "dh")
        return kind if isinstance(kind, str) else None
    return getattr(value, "kind", None)


RobotSpec = Annotated[
    Annotated[DHRobotSpec, Tag("dh")] | Annotated[URDFRobotSpec, Tag("urdf")],
    Discriminator(_robot_kind),
]
