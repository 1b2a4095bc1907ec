"""Parameters of the ``swing_energy`` study (see :mod:`legcore.studies.swing_energy.problem`).

A default is either robot-independent (seed 000's setting: the swing time, via points, grid,
criterion weights, …) or ``None``: *derived from the robot* by
:func:`legcore.studies.swing_energy.defaults.derive` — the leg, its start and end (a step in
body axes from a nominal stance), the link weights, the search range, the parabolic baseline's
apex and the obstacle box's size. Seed 000's own values of those live in its preset
(:mod:`legcore.studies.swing_energy.preset`), applied on its catalog robot ``calderon_leg``.
A user-given per-joint value must have one entry per joint.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, StrictInt, model_validator

from legcore.studies.study import StudyParams

__all__ = [
    "BASELINES",
    "GENERIC_SEARCH_RANGE",
    "RESOLUTION",
    "BaselineName",
    "BoxSpec",
    "Obstacle",
    "Params",
]

#: Seed 000's control resolution (rad) — genes are integer multiples of it.
RESOLUTION = 0.00174
#: The search range (rad per joint) of a leg without a given one.
GENERIC_SEARCH_RANGE = 0.3

#: Baseline name → (criterion it optimises, reference in seed 000).
BASELINES: dict[str, tuple[str, str]] = {
    "calderon2008_parabolic": ("parabolic", "Calderón 2008: parabolic swing"),
    "tian_collins2004_min_displacement": (
        "theta_total", "Tian & Collins 2004: minimum total angular displacement"),
    "shankar_kaur2011_min_distance": (
        "foot_distance", "Shankar & Kaur 2011: shortest foot (end-effector) path"),
    "solteiro2007_multi_criteria": (
        "multi_criteria",
        "Solteiro 2007: displacement + foot distance + foot and joint speeds + energy"),
    "perez2010_min_energy": ("energy", "Pérez 2010: minimum mechanical energy"),
    "gradient_min_energy": (
        "energy_gradient",
        "minimum mechanical energy by a gradient method (SLSQP on the via points, from the "
        "coordinated motion and every other baseline): the metaheuristics' reference"),
}
BaselineName = Literal[
    "calderon2008_parabolic",
    "tian_collins2004_min_displacement",
    "shankar_kaur2011_min_distance",
    "solteiro2007_multi_criteria",
    "perez2010_min_energy",
    "gradient_min_energy",
]
Vec3 = tuple[float, float, float]
#: One value per joint of the leg (2 to 6 joints).
PerJoint = Annotated[tuple[float, ...], Field(min_length=2, max_length=6)]
LegName = Annotated[str, Field(min_length=1, max_length=32, pattern=r"^[A-Za-z0-9_\-]+$")]


class Obstacle(BaseModel):
    """A box on the ground, mid-stride (seed 000 case 2: 60 × 40 × 26 mm on its 0.29 m leg).

    ``length`` along the step, ``width`` across it, ``height`` (m). Its centre lies on the
    start→end foot chord at the fraction ``along`` (0.5: "halfway between the initial and final
    points", seed 000 §5.2), shifted ``lateral`` m horizontally to the left of the step
    direction; its base is on the ground. The box is axis-aligned: its length is laid along the
    world axis (x or y) nearest the step direction.
    ``margin`` (m): the links and foot must stay this far out of it (link thickness).
    A size left out (None) is seed 000's scaled by the leg's length: × L / L₀ (``derive``).
    """

    model_config = ConfigDict(extra="forbid", frozen=True)
    length: float | None = Field(default=None, gt=0.0, le=2.0,
                                 description="m; None: seed 000's 0.060 m × L / L₀")
    width: float | None = Field(default=None, gt=0.0, le=2.0,
                                description="m; None: seed 000's 0.040 m × L / L₀")
    height: float | None = Field(default=None, gt=0.0, le=2.0,
                                 description="m; None: seed 000's 0.026 m × L / L₀")
    along: float = Field(default=0.5, ge=0.0, le=1.0)
    lateral: float = Field(default=0.0, ge=-2.0, le=2.0)
    margin: float | None = Field(default=None, ge=0.0, le=0.5,
                                 description="m; None: seed 000's 0.002 m × L / L₀")


class BoxSpec(BaseModel):
    """An axis-aligned box obstacle placed by the user in the leg's base frame (m): ``center``,
    full ``size`` (x, y, z) and the clearance ``margin`` the links and foot keep from it."""

    model_config = ConfigDict(extra="forbid", frozen=True)
    center: tuple[
        Annotated[float, Field(ge=-10.0, le=10.0)],
        Annotated[float, Field(ge=-10.0, le=10.0)],
        Annotated[float, Field(ge=-10.0, le=10.0)],
    ]
    size: tuple[
        Annotated[float, Field(gt=0.0, le=10.0)],
        Annotated[float, Field(gt=0.0, le=10.0)],
        Annotated[float, Field(gt=0.0, le=10.0)],
    ]
    margin: float = Field(default=0.002, ge=0.0, le=0.5, description="m, seed 000's value")


class Params(StudyParams):
    """Parameters of the ``swing_energy`` study (s, rad, m). A ``None`` default is derived from
    the robot (:mod:`legcore.studies.swing_energy.defaults`, the rule of each value in the job's
    ``task.rules``); the other defaults are seed 000's robot-independent settings. On seed 000's
    leg ``calderon_leg`` its preset gives the paper's values.

    - ``leg``: the leg that swings, for a legged robot (its name, e.g. ``LF``; None: its first
      front leg); a serial robot is the leg itself. ``foot_frame``: the frame (link) of the
      chain that is the foot, when it is not the robot's tool/end frame (it must hang from the
      last joint).
    - ``T`` swing time (3 s), ``n_via`` intermediate via points (10), ``dt`` sampling step
      (0.01 s; T must be a whole number of steps), ``resolution`` control resolution (0.00174).
    - ``q_start``/``q_end`` (rad, one value per joint) or ``foot_start``/``foot_end`` (m, in
      the leg's base frame — the hip, body axes, for a leg of a legged robot; IK on the leg's
      own knee branch, then from the start). None: a step in body axes — from half a step
      behind a nominal stance to half a step ahead of it (``derive``). Given ends are rounded
      onto the control grid unless ``exact_ends`` (then the foot starts and ends exactly where
      asked, to 1e-9 m); None: exact when an end is derived, rounded when both are given.
    - ``w1``, ``w2`` criterion weights (5, 5); ``w_d``, ``w_a`` link weights (None: 1/n each;
      seed 000's (0.25, 0.5, 0.25) in its preset); ``ratio_eps`` ε of the ratios in
      resolution steps (1; 0 = eqs 2/5 with 0/0 := 1).
    - ``obstacle``: False (flat ground, case 1), True (the seed's 60 × 40 × 26 mm box
      mid-stride, case 2, scaled to the leg) or an :class:`Obstacle`; ``obstacles``: more
      boxes, placed by coordinates (:class:`BoxSpec`). ``ground``/``ground_tolerance``: keep the
      leg above the ground (1 mm tolerance); ``ground_height``: its z (m, leg base frame;
      default the lower of the start and end feet, as seed 000).
    - ``encoding``, ``tube``, ``search_range`` (per joint, rad; None: 0.3 each; seed 000's
      (0.05, 0.3, 0.4) in its preset), ``dead_band`` (× search_range), ``lift_only``: the gene
      coding. ``tube``: the motion the search is centred on (all-zero genes): ``coordinated``
      (seed 000) or ``shortest`` (the shortest foot path that clears the ground and obstacles:
      a feasible swing; the coordinated motion when no path raised by up to 50 mm does); None:
      coordinated unless the coordinated motion violates the ground or an obstacle (a leg's
      forward step, whose joint-space straight line dips the foot), then shortest.
      ``lift_only`` None: true around the coordinated motion (seed 000), false around the
      shortest path.
    - ``step_height``: apex of the parabolic baseline (m; None: 0.2 L, the leg's stretched
      length below the hip; seed 000's 0.065 m in its preset).
      ``baselines``: which baselines to compute (all five);
      ``baseline_generations``/``baseline_pop_size``/``baseline_seed``: the GA budget and seed
      of the GA baselines (100 × 100, seed 0).
    """

    kind: Literal["swing_energy"] = "swing_energy"
    leg: LegName | None = None
    foot_frame: str | None = Field(default=None, min_length=1, max_length=200)
    T: float = Field(default=3.0, gt=0.0, le=60.0, description="swing duration, s")
    n_via: StrictInt = Field(default=10, ge=1, le=40, description="intermediate via points")
    dt: float = Field(default=0.01, gt=0.0, le=1.0, description="sampling step, s")
    resolution: float = Field(default=RESOLUTION, ge=1e-6, le=0.1, description="rad")
    q_start: PerJoint | None = None
    q_end: PerJoint | None = None
    foot_start: Vec3 | None = None
    foot_end: Vec3 | None = None
    exact_ends: bool | None = None
    w1: float = Field(default=5.0, ge=0.0, le=1e3)
    w2: float = Field(default=5.0, ge=0.0, le=1e3)
    w_d: PerJoint | None = None
    w_a: PerJoint | None = None
    ratio_eps: float = Field(default=1.0, ge=0.0, le=1e3, description="ε in resolution steps")
    obstacle: bool | Obstacle = False
    obstacles: tuple[BoxSpec, ...] = Field(default=(), max_length=20)
    ground: bool = True
    ground_height: float | None = Field(default=None, ge=-10.0, le=10.0, description="m")
    ground_tolerance: float = Field(default=0.001, ge=0.0, le=1.0, description="m")
    encoding: Literal["deviation", "absolute"] = "deviation"
    tube: Literal["coordinated", "shortest"] | None = None
    search_range: PerJoint | None = None
    dead_band: float = Field(default=2.0, ge=0.0, le=100.0, description="× search_range")
    lift_only: bool | None = None
    step_height: float | None = Field(default=None, ge=0.0, le=1.0,
                                      description="m; None: 0.2 × the leg's length")
    baselines: tuple[BaselineName, ...] = (
        "calderon2008_parabolic",
        "tian_collins2004_min_displacement",
        "shankar_kaur2011_min_distance",
        "solteiro2007_multi_criteria",
        "perez2010_min_energy",
    )
    baseline_generations: StrictInt = Field(default=100, ge=1, le=1000)
    baseline_pop_size: StrictInt = Field(default=100, ge=4, le=2000)
    baseline_seed: StrictInt = Field(default=0, ge=0, le=2**32 - 1)

    @model_validator(mode="after")
    def _consistent(self) -> Params:
        if self.search_range is not None and any(
                not math.isfinite(v) or v < 0.0 or v > 2 * math.pi for v in self.search_range):
            raise ValueError(f"search_range: per-joint ranges must be in [0, 2π] rad, "
                             f"got {self.search_range}")
        for name in ("w_d", "w_a"):
            w = getattr(self, name)
            if w is not None and any(not math.isfinite(v) or v < 0.0 for v in w):
                raise ValueError(f"{name}: link weights must be finite and >= 0, got {w}")
        if self.w1 + self.w2 <= 0.0:
            raise ValueError("w1, w2: at least one criterion weight must be > 0")
        steps = self.T / self.dt
        if not steps <= 6000:
            raise ValueError(
                f"dt: T/dt = {steps:.3g} steps, at most 6000; use dt >= {self.T / 6000:.3g} s"
            )
        if abs(steps - round(steps)) > 1e-6 * max(1.0, steps):
            raise ValueError(f"dt: T = {self.T} s must be a whole number of steps dt = {self.dt} s")
        if round(steps) + 1 > 6001:
            raise ValueError(f"dt: {round(steps) + 1} samples per trajectory, at most 6001")
        for a, b in (("q_start", "foot_start"), ("q_end", "foot_end")):
            if getattr(self, a) is not None and getattr(self, b) is not None:
                raise ValueError(f"{b}: give either {a} or {b}, not both")
        for name in ("q_start", "q_end", "foot_start", "foot_end"):
            v = getattr(self, name)
            if v is not None and not all(math.isfinite(c) for c in v):
                raise ValueError(f"{name}: values must be finite, got {v}")
        for box in self.obstacles:
            if not all(math.isfinite(c) for c in (*box.center, *box.size)):
                raise ValueError("obstacles: box centers and sizes must be finite")
        if len(set(self.baselines)) != len(self.baselines):
            raise ValueError("baselines: each baseline may be listed once")
        return self

    @property
    def box(self) -> Obstacle | None:
        """The mid-stride obstacle (None in the flat case)."""
        if self.obstacle is True:
            return Obstacle()
        return self.obstacle or None

    def per_joint(self, name: str, n: int) -> tuple[float, ...]:
        """The per-joint parameter ``name`` (``w_d``, ``w_a``, ``search_range``) for a leg of
        ``n`` joints: as given (it must have n values: ``ValueError`` naming the field); when
        left out (None), 1/n per joint (weights) or 0.3 rad (search range)."""
        value: tuple[float, ...] | None = getattr(self, name)
        if value is None:
            return (GENERIC_SEARCH_RANGE,) * n if name == "search_range" else (1.0 / n,) * n
        if len(value) != n:
            raise ValueError(f"{name}: {len(value)} values for a leg of {n} joints; give one "
                             "per joint")
        return value
