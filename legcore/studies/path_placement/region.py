"""Where ``path_placement`` may put a path: placement regions, and the arm's best manipulability.

A region maps the decision vector x (3,) to the world point p(x) where the path's anchor goes:

- :class:`SphericalWorkspace` — a spherical shell (or a ball, ``R_min = 0``) about ``origin``,
  x = (R, γ, φ): distance (m), colatitude-like elevation γ (rad; −π/2 straight up, 0
  horizontal, > 0 below the horizontal) and azimuth φ (rad), seed 001's eq 5::

      p = origin + base_R · (cos φ |R cos γ|, sin φ |R cos γ|, −R sin γ)

- :class:`BoxRegion` — an axis-aligned box, x = (x, y, z) (m).

Both are in the robot's base coordinates (``base_R``/``origin``, or ``base`` for the box).
Users give one with :class:`SphereSpec`, :class:`ShellSpec` or :class:`BoxSpec`; without one
the study uses, for a PUMA-type spherical-wrist 6R arm, seed 001's simplified workspace
(:func:`simplified_workspace`, eqs 1–5: the preset) and for any other arm :func:`reach_shell`,
a shell about its shoulder spanning the reach measured by forward kinematics.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Annotated, Any, Literal

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray
from pydantic import BaseModel, ConfigDict, Field, model_validator

from legcore.ik.numeric import halton_seeds
from legcore.ik.puma560 import puma560_geometry
from legcore.kinematics import fk, frames
from legcore.manipulability import manipulability_split
from legcore.robots.model import Robot

__all__ = [
    "BoxRegion",
    "BoxSpec",
    "RegionSpec",
    "ShellSpec",
    "SphereSpec",
    "SphericalWorkspace",
    "is_puma_type",
    "reach_shell",
    "region_of",
    "simplified_workspace",
]

FloatArray = NDArray[np.float64]
Finite = Annotated[float, Field(allow_inf_nan=False)]
Point3 = tuple[Finite, Finite, Finite]


# ---------------------------------------------------------------------------------------------
# regions
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class SphericalWorkspace:
    """A spherical shell region, x = (R, γ, φ) (see the module docstring for eq 5).

    ``origin`` (3,) world m; ``base_R`` (3, 3) the axes of eq 5; R in [``R_min``, ``R_max``] m,
    γ in [``gamma_up``, ``gamma_low``], φ in [``phi_low``, ``phi_up``] rad. ``source`` says
    where it comes from; ``q_far``/``q_near`` (6,) are the configurations seed 001's RM_y/γ_RI
    and RM_n were measured at (None for other regions).
    """

    origin: FloatArray
    base_R: FloatArray
    R_min: float
    R_max: float
    gamma_up: float
    gamma_low: float
    phi_low: float
    phi_up: float
    q_far: FloatArray | None = None
    q_near: FloatArray | None = None
    source: str = "shell"

    variable_names = ("R", "gamma", "phi")

    @property
    def xl(self) -> FloatArray:
        """Lower bounds of (R, γ, φ)."""
        return np.array([self.R_min, self.gamma_up, self.phi_low])

    @property
    def xu(self) -> FloatArray:
        """Upper bounds of (R, γ, φ)."""
        return np.array([self.R_max, self.gamma_low, self.phi_up])

    def point(self, x: ArrayLike) -> FloatArray:
        """Eq 5: world points (..., 3) m of ``x = (R, γ, φ)`` (..., 3)::

            p_x = cos φ |R cos γ|,  p_y = sin φ |R cos γ|,  p_z = −R sin γ + d1
        """
        x = np.asarray(x, dtype=float)
        R, g, f = x[..., 0], x[..., 1], x[..., 2]
        rho = np.abs(R * np.cos(g))
        local = np.stack([np.cos(f) * rho, np.sin(f) * rho, -R * np.sin(g)], axis=-1)
        return self.origin + local @ self.base_R.T

    def centre(self) -> FloatArray:
        """The world point (3,) the region is drawn around (m): the shell's origin."""
        return self.origin.copy()

    def coords(self, p: ArrayLike) -> FloatArray:
        """Inverse of :meth:`point`: ``(R, γ, φ)`` (..., 3) of world points ``p`` (..., 3)."""
        d = (np.asarray(p, dtype=float) - self.origin) @ self.base_R
        rho = np.hypot(d[..., 0], d[..., 1])
        R = np.hypot(rho, d[..., 2])
        return np.stack([R, np.arctan2(-d[..., 2], rho), np.arctan2(d[..., 1], d[..., 0])], axis=-1)

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "kind": "shell",
            "source": self.source,
            "origin": self.origin.tolist(),
            "RM_n": self.R_min,
            "RM_y": self.R_max,
            "gamma_RS": self.gamma_up,
            "gamma_RI": self.gamma_low,
            "phi_RI": self.phi_low,
            "phi_RS": self.phi_up,
        }
        if self.q_far is not None and self.q_near is not None:
            out |= {"q_far": self.q_far.tolist(), "q_near": self.q_near.tolist()}
        return out


@dataclass(frozen=True, eq=False)
class BoxRegion:
    """An axis-aligned box in base coordinates, x = (x, y, z) in [``lo``, ``hi``] (m);
    ``base`` (4, 4) the robot base in the world."""

    lo: FloatArray
    hi: FloatArray
    base: FloatArray
    source: str = "box"

    variable_names = ("x", "y", "z")

    @property
    def xl(self) -> FloatArray:
        return self.lo.copy()

    @property
    def xu(self) -> FloatArray:
        return self.hi.copy()

    def point(self, x: ArrayLike) -> FloatArray:
        """World points (..., 3) of base-frame points ``x`` (..., 3) m."""
        return np.asarray(x, dtype=float) @ self.base[:3, :3].T + self.base[:3, 3]

    def centre(self) -> FloatArray:
        """The world point (3,) the region is drawn around (m): the box's centre."""
        return self.point(0.5 * (self.lo + self.hi))

    def coords(self, p: ArrayLike) -> FloatArray:
        """Base-frame coordinates (..., 3) of world points ``p`` (..., 3)."""
        return (np.asarray(p, dtype=float) - self.base[:3, 3]) @ self.base[:3, :3]

    def as_dict(self) -> dict[str, Any]:
        return {"kind": "box", "source": self.source, "lo": self.lo.tolist(),
                "hi": self.hi.tolist()}


Region = SphericalWorkspace | BoxRegion


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class SphereSpec(_Strict):
    """A ball of ``radius`` (m) about ``center`` (base coordinates, m): x = (R, γ, φ)."""

    kind: Literal["sphere"] = "sphere"
    center: Point3
    radius: Finite = Field(gt=0.0)


class ShellSpec(_Strict):
    """A spherical shell about ``center`` (base coordinates, m): x = (R, γ, φ) within ``R``
    (m), ``gamma`` and ``phi`` (rad) — seed 001's simplified workspace is one."""

    kind: Literal["shell"] = "shell"
    center: Point3
    R: tuple[Finite, Finite]
    gamma: tuple[Finite, Finite] = (-math.pi / 2, math.pi / 2)
    phi: tuple[Finite, Finite] = (-math.pi, math.pi)

    @model_validator(mode="after")
    def _ranges(self) -> ShellSpec:
        if not 0.0 <= self.R[0] < self.R[1]:
            raise ValueError(f"R: need 0 <= R_min < R_max (m), got {self.R}")
        if not -math.pi / 2 <= self.gamma[0] < self.gamma[1] <= math.pi / 2:
            raise ValueError(f"gamma: need −π/2 <= low < high <= π/2 (rad), got {self.gamma}")
        if not -2 * math.pi <= self.phi[0] < self.phi[1] <= 2 * math.pi:
            raise ValueError(f"phi: need −2π <= low < high <= 2π (rad), got {self.phi}")
        return self


class BoxSpec(_Strict):
    """An axis-aligned box from ``lo`` to ``hi`` (base coordinates, m): x = (x, y, z)."""

    kind: Literal["box"] = "box"
    lo: Point3
    hi: Point3

    @model_validator(mode="after")
    def _ordered(self) -> BoxSpec:
        if not all(a < b for a, b in zip(self.lo, self.hi, strict=True)):
            raise ValueError(f"lo/hi: need lo < hi on every axis, got {self.lo}, {self.hi}")
        return self


RegionSpec = Annotated[SphereSpec | ShellSpec | BoxSpec, Field(discriminator="kind")]


def _base(robot: Robot) -> FloatArray:
    """The robot base (4, 4) in the world (DH ``base``; identity for a URDF robot)."""
    return np.asarray(frames(robot, robot.home)[0])


def region_of(spec: SphereSpec | ShellSpec | BoxSpec, robot: Robot) -> Region:
    """The region a spec describes, in ``robot``'s base coordinates."""
    base = _base(robot)
    if isinstance(spec, BoxSpec):
        return BoxRegion(np.asarray(spec.lo, float), np.asarray(spec.hi, float), base)
    origin = base[:3, :3] @ np.asarray(spec.center, float) + base[:3, 3]
    if isinstance(spec, SphereSpec):
        return SphericalWorkspace(origin, base[:3, :3].copy(), 0.0, float(spec.radius),
                                  -math.pi / 2, math.pi / 2, -math.pi, math.pi, source="sphere")
    return SphericalWorkspace(origin, base[:3, :3].copy(), spec.R[0], spec.R[1], spec.gamma[0],
                              spec.gamma[1], spec.phi[0], spec.phi[1], source="shell")


# ---------------------------------------------------------------------------------------------
# the seed's simplified workspace (PUMA-type arms) and the generic reach shell
# ---------------------------------------------------------------------------------------------


def is_puma_type(robot: Robot) -> bool:
    """True for a PUMA-type spherical-wrist 6R arm with its closed-form IK (``ik: puma560``):
    seed 001's closed forms (IK, eqs 1–5 and 6–8) apply to it."""
    if robot.ik_family != "puma560":
        return False
    try:
        puma560_geometry(robot.spec)
        manipulability_split(robot, robot.home)
    except ValueError:
        return False
    return True


def simplified_workspace(robot: Robot) -> SphericalWorkspace:
    """The simplified spherical workspace of a PUMA-type arm, measured by forward kinematics
    at the configurations of seed 001 §2.2 (see the study docs for the sign conventions).

    - ``RM_y`` (eq 1) and ``γ_RI`` (eq 3): wrist centre at θ1 = 0, θ2 = the joint-2 limit that
      points the stretched arm lowest in front of the robot (the paper's θ2S; in the
      roboticstoolbox convention of our PUMA θ2 turns the other way, so it is our lower limit
      −45°), θ3 = the middle of the joint-3 range (the paper prints θ3 = θ3S + θ3I, which
      folds the arm back; (θ3S + θ3I)/2 = −90° is the stretched elbow), θ4..θ6 = (π, 0, 0);
      ``RM_y = sqrt(x² + (z − d1)²)``, ``γ_RI = acos(x / RM_y)``.
    - ``RM_n`` (eq 2, printed with RM_y on its left): θ2 with the upper arm vertical (the
      paper's −90°, our +90°), θ3 = the joint-3 upper limit θ3S.
    - ``γ_RS = −π/2``; ``φ_RI, φ_RS`` = joint 1 limits (eq 4).

    Coordinates are taken in the base frame relative to O_s = base·(0, 0, d1); like eq 1 they
    ignore the shoulder offset (y). ``ValueError("robot: …")`` for another kind of arm.
    """
    if not is_puma_type(robot):
        raise ValueError(
            f"robot: seed 001's simplified workspace needs a PUMA-type spherical-wrist 6R arm "
            f"(ik: puma560); give a placement 'region' for {robot.name}"
        )
    geo = puma560_geometry(robot.spec)
    base = geo.base
    origin = (base @ np.array([0.0, 0.0, geo.d1, 1.0]))[:3]
    base_R = base[:3, :3]
    off = geo.offset
    q_min, q_max = robot.q_min, robot.q_max

    def local(q: FloatArray) -> FloatArray:
        pw = frames(robot, q)[..., 4, :3, 3]  # DH frame 4 origin = wrist centre
        return (pw - origin) @ base_R

    mid3 = 0.5 * (q_min[2] + q_max[2])
    cands = np.array([[0.0, q2, mid3, math.pi, 0.0, 0.0] for q2 in (q_min[1], q_max[1])])
    cands[:, 0] -= off[0]
    loc = local(cands)
    front = loc[:, 0] > 0.0
    order = np.lexsort((loc[:, 2], ~front))  # in front first, then lowest
    q_far = cands[order[0]]
    d_far = loc[order[0]]
    R_max = float(math.hypot(d_far[0], d_far[2]))
    gamma_low = float(math.acos(np.clip(d_far[0] / R_max, -1.0, 1.0)))
    q_near = np.array([-off[0], math.pi / 2 - off[1], q_max[2], math.pi, 0.0, 0.0])
    d_near = local(q_near)
    R_min = float(math.hypot(d_near[0], d_near[2]))
    if not R_min < R_max:
        raise ValueError(f"robot: degenerate simplified workspace (RM_n = {R_min:.4g} m >= "
                         f"RM_y = {R_max:.4g} m)")
    return SphericalWorkspace(
        origin=origin, base_R=base_R, R_min=R_min, R_max=R_max, gamma_up=-math.pi / 2,
        gamma_low=gamma_low, phi_low=float(q_min[0] + off[0]), phi_up=float(q_max[0] + off[0]),
        q_far=q_far, q_near=q_near, source="seed 001 simplified workspace (eqs 1–5)",
    )


_REACH_SAMPLES = 4096


def reach_shell(robot: Robot) -> SphericalWorkspace:
    """A shell about the shoulder of any arm, spanning its reach.

    Centre: the point of joint 1's axis nearest joint 2's origin at home (for a PUMA-type arm
    the seed's O_s). R from the 5th percentile to the largest distance of the tool point from
    it over 4096 Halton configurations inside the joint limits; γ over [−π/2, π/2]; φ over
    joint 1's range (at most one turn) when its axis is the base z axis, else a full turn.
    """
    model, data = robot.model, robot.model.createData()
    pin.forwardKinematics(model, data, robot.home)
    o1 = np.asarray(data.oMi[1].translation)
    a1 = np.asarray(data.oMi[1].rotation) @ robot.chain.axis[0]
    o2 = np.asarray(data.oMi[2].translation) if robot.nq > 1 else o1
    center = o1 + a1 * float((o2 - o1) @ a1)
    seeds = halton_seeds(_REACH_SAMPLES, robot.q_min, robot.q_max, robot.home)
    seeds[:, 0] = robot.home[0]
    d = np.linalg.norm(fk(robot, seeds)[:, :3, 3] - center, axis=-1)
    base = _base(robot)
    R_lo, R_hi = float(np.quantile(d, 0.05)), float(d.max())
    phi_lo, phi_hi = -math.pi, math.pi
    if np.allclose(a1, base[:3, 2], atol=1e-9) and robot.q_max[0] - robot.q_min[0] < 2 * math.pi:
        phi_lo, phi_hi = float(robot.q_min[0]), float(robot.q_max[0])
    return SphericalWorkspace(center, base[:3, :3].copy(), R_lo, R_hi, -math.pi / 2, math.pi / 2,
                              phi_lo, phi_hi, source="reach shell about the shoulder")
