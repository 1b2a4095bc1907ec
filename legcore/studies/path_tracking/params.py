"""Parameters of the ``path_tracking`` study: the path, the tool orientation, the time law and
the limits (defaults: seed 004's capsule and law on its 5-DOF arm — the preset).

Units: m, rad, s. The path is a chain of lines and arcs in plane coordinates (u, v), placed in
the world by ``plane_origin`` + u ``plane_e1`` + v ``plane_e2`` — any plane.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from legcore.studies.path_tracking.joints import ToolOrientation
from legcore.studies.study import StudyParams
from legcore.trajectories.paths import JOIN_TOL, Arc, Line, Plane

__all__ = [
    "CAPSULE",
    "DEFAULT_QDD_MAX",
    "SEED_SEGMENT_TIMES",
    "ArcSegment",
    "LineSegment",
    "Params",
]

Finite = Annotated[float, Field(allow_inf_nan=False)]
Positive = Annotated[float, Field(gt=0.0, allow_inf_nan=False)]
Point2 = tuple[Finite, Finite]
Point3 = tuple[Finite, Finite, Finite]

#: Seed 004 §V in SI: the capsule's segment times at its law.
SEED_SEGMENT_TIMES = (1.5 + math.pi, 4.0, math.pi, 5.5)  # s: 4.6416, 4, 3.1416, 5.5
SEED_V, SEED_T_A, SEED_T_D = 0.10, 3.0, 3.0  # m/s, s, s

#: Joint acceleration limit (rad/s²) of every joint unless the spec gives others. Assumed (the
#: seed gives none): a joint reaches a 1.5 rad/s speed limit in 0.3 s. For comparison: Universal
#: Robots' MoveIt configuration uses 5 rad/s² on every joint ("the robot has no acceleration
#: limit of its own, only torques; chosen conservatively"), the Franka Panda's hardware limits are
#: 7.5–20 rad/s² (libfranka), its MoveIt configuration a quarter of those. See docs/studies.md.
DEFAULT_QDD_MAX = 5.0


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class LineSegment(_Strict):
    """Straight segment from ``start`` to ``end`` (plane coordinates u, v in m; seed eq 14)."""

    type: Literal["line"] = "line"
    start: Point2
    end: Point2

    @model_validator(mode="after")
    def _length(self) -> LineSegment:
        if math.dist(self.start, self.end) <= 1e-9:
            raise ValueError("start and end must differ (a line needs a length > 0)")
        return self

    def curve(self) -> Line:
        return Line(np.array(self.start), np.array(self.end))


class ArcSegment(_Strict):
    """Arc about ``center`` (u, v m) of radius ``r`` (m) from angle ``beta`` sweeping ``phi``
    (rad, > 0 counter-clockwise about the plane normal; seed eq 17)."""

    type: Literal["arc"] = "arc"
    center: Point2
    r: Finite = Field(gt=0.0)
    beta: Finite
    phi: Finite = Field(ge=-2.0 * math.pi, le=2.0 * math.pi)

    @model_validator(mode="after")
    def _sweep(self) -> ArcSegment:
        if abs(self.phi) < 1e-9:
            raise ValueError("phi must be non-zero (an arc needs a sweep)")
        return self

    def curve(self) -> Arc:
        return Arc(np.array(self.center), self.r, self.beta, self.phi)


PathSegment = Annotated[LineSegment | ArcSegment, Field(discriminator="type")]

CAPSULE: tuple[LineSegment | ArcSegment, ...] = (
    ArcSegment(center=(0.20, 0.30), r=0.10, beta=-math.pi / 2, phi=math.pi),
    LineSegment(start=(0.20, 0.40), end=(-0.20, 0.40)),
    ArcSegment(center=(-0.20, 0.30), r=0.10, beta=math.pi / 2, phi=math.pi),
    LineSegment(start=(-0.20, 0.20), end=(0.20, 0.20)),
)

_CORNER_TOL = 1e-6  # rad: a join turning the path's tangent more than this is a corner


class Params(StudyParams):
    """Parameters of the ``path_tracking`` study (defaults: seed 004's own settings).

    - ``segments``: the path, consecutive lines/arcs in plane coordinates (m, rad); default the
      seed's capsule (arcs r = 0.10 m about (±0.20, 0.30) m, lines at v = 0.40 and 0.20 m,
      counter-clockwise from (0.20, 0.20) m). Each segment must start where the previous ends,
      in the same direction (no corner: the tool does not stop between segments).
    - ``plane_origin``, ``plane_e1``, ``plane_e2``: the plane in the world (m; orthonormal axes);
      default the horizontal plane z = 0.50 m ("a una altura de 50cm").
    - ``orientation``: ``"down"`` (the tool z axis points straight down, the seed), ``"axis"``
      (along ``tool_axis``, any fixed world direction) or ``"free"`` (position only).
    - ``tool_yaw``: with an axis, None leaves the spin about it free (the seed: joint 5 stays
      at its rest value); a heading (rad) holds the tool's x axis fixed in the world too.
    - ``rest``: the posture (rad, one value per joint) the IK starts the path from — its branch
      is followed — and a redundant arm is pulled toward; default the robot's home.
    - ``objective``: ``"time"`` (T), ``"energy"`` (E) or ``"energy_time"`` (both).
    - ``speeds``: ``"per_segment"`` (one cruise speed per segment + t_a, t_d, t_b) or
      ``"single"`` (one speed, t_a, t_d — the seed's scheme).
    - ``ramp``: speed-ramp shape, ``"linear"`` (the seed's trapezoid) or ``"cubic"``.
    - ``V``, ``t_a``, ``t_d``: the seed's law (m/s, s, s) used as the ``seed`` baseline.
    - ``V_bounds`` (m/s), ``ramp_bounds`` (s, for t_a, t_d, t_b): the decision box (each
      segment's speed bound is lowered further to the fastest speed at which the arm's joint
      speed limits can hold somewhere on it: faster is infeasible).
    - ``T_max``: optional cycle-time cap (s), a constraint.
    - ``qdd_max``: joint acceleration limits (rad/s²), one for every joint or one per joint;
      ``"robot"`` (default): the robot's own (``qdd_max`` of its DH joints, or of its URDF
      spec by joint name), :data:`DEFAULT_QDD_MAX` (assumed) for joints without one; null: no
      acceleration limit (then a time optimum has millisecond ramps — physically
      meaningless). Speed and torque limits are the robot's.
    - ``n_samples``: time samples per candidate trajectory (evaluation and decoding).
    """

    kind: Literal["path_tracking"] = "path_tracking"
    segments: tuple[PathSegment, ...] = Field(default=CAPSULE, min_length=1, max_length=64)
    plane_origin: Point3 = (0.0, 0.0, 0.50)
    plane_e1: Point3 = (1.0, 0.0, 0.0)
    plane_e2: Point3 = (0.0, 1.0, 0.0)
    orientation: Literal["down", "axis", "free"] = "down"
    tool_axis: Point3 | None = None
    tool_yaw: Finite | None = None
    rest: tuple[Finite, ...] | None = Field(default=None, min_length=1, max_length=12)
    objective: Literal["time", "energy", "energy_time"] = "time"
    speeds: Literal["per_segment", "single"] = "per_segment"
    ramp: Literal["linear", "cubic"] = "linear"
    V: Finite = Field(default=SEED_V, gt=0.0)
    t_a: Finite = Field(default=SEED_T_A, gt=0.0)
    t_d: Finite = Field(default=SEED_T_D, gt=0.0)
    V_bounds: tuple[Finite, Finite] = (0.01, 1.0)
    ramp_bounds: tuple[Finite, Finite] = (0.005, 5.0)
    T_max: Finite | None = Field(default=None, gt=0.0)
    qdd_max: Positive | tuple[Positive, ...] | Literal["robot"] | None = "robot"
    n_samples: int = Field(default=400, ge=20, le=20_000)

    @model_validator(mode="after")
    def _check(self) -> Params:
        for name in ("V_bounds", "ramp_bounds"):
            lo, hi = getattr(self, name)
            if not 0.0 < lo <= hi:
                raise ValueError(f"{name}: need 0 < lower <= upper, got ({lo}, {hi})")
        try:
            self.plane()
        except ValueError as exc:
            raise ValueError(f"plane_e1/plane_e2: {exc}") from None
        if (self.orientation == "axis") != (self.tool_axis is not None):
            raise ValueError("tool_axis: give it with orientation 'axis' (and only then)")
        if self.orientation == "free" and self.tool_yaw is not None:
            raise ValueError("tool_yaw: a heading needs a tool axis, not orientation 'free'")
        try:
            self.tool()
        except ValueError as exc:
            raise ValueError(str(exc)) from None
        if isinstance(self.qdd_max, tuple) and not 1 <= len(self.qdd_max) <= 12:
            raise ValueError("qdd_max: one value, or one per joint (1 to 12)")
        curves = [s.curve() for s in self.segments]
        for k in range(1, len(curves)):
            a, b = curves[k - 1], curves[k]
            gap = float(np.linalg.norm(a.end - b.start))
            if gap > JOIN_TOL:
                raise ValueError(
                    f"segments.{k}: starts {gap:.3g} m away from the end of segments.{k - 1} "
                    f"(at {np.round(a.end, 6).tolist()} m)"
                )
            t_end, t_start = a.derivatives(np.array([1.0]))[1, 0], b.derivatives(
                np.array([0.0]))[1, 0]
            cos = float(t_end @ t_start / (np.linalg.norm(t_end) * np.linalg.norm(t_start)))
            turn = math.acos(min(1.0, max(-1.0, cos)))
            if turn > _CORNER_TOL:
                raise ValueError(
                    f"segments.{k}: turns the path by {math.degrees(turn):.3g}° at its start (a "
                    f"corner the tool would have to take at a stop); join the segments tangent "
                    f"to each other (e.g. an arc between two lines)"
                )
        return self

    def plane(self) -> Plane:
        return Plane(np.array(self.plane_origin), np.array(self.plane_e1), np.array(self.plane_e2))

    def tool(self) -> ToolOrientation:
        """The tool orientation these parameters ask for."""
        if self.orientation == "free":
            return ToolOrientation(None)
        axis = (0.0, 0.0, -1.0) if self.orientation == "down" else self.tool_axis
        return ToolOrientation(axis, self.tool_yaw)
