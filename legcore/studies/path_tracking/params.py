"""Parameters of the ``path_tracking`` study: the path, the tool orientation, the time law and
the limits.

Units: m, rad, s. The path is a chain of lines and arcs in plane coordinates (u, v), placed in
the world by ``plane_origin`` + u ``plane_e1`` + v ``plane_e2`` — any plane. The fields that
depend on the arm (the path, its plane, the tool orientation, the rest posture, the reference
speed and the speed box) default to None: derived from the robot by
:mod:`legcore.studies.path_tracking.defaults` (seed 004's capsule scaled to the arm's reach, in
a well-conditioned part of its workspace); on seed 004's own arm the preset
(:mod:`legcore.studies.path_tracking.preset`) gives the paper's values.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, StrictInt, model_validator

from legcore.studies.path_tracking.joints import ToolOrientation
from legcore.studies.study import StudyParams
from legcore.trajectories.paths import JOIN_TOL, Arc, Line, Plane

__all__ = [
    "CAPSULE",
    "DEFAULT_QDD_MAX",
    "SEED_T_A",
    "SEED_T_D",
    "SEED_V",
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


def _ortho(v: tuple[float, float, float] | None) -> tuple[float, float, float]:
    """A unit vector ⊥ ``v`` (to check one given plane axis alone)."""
    a = np.asarray(v, dtype=float)
    e = np.eye(3)[int(np.argmin(np.abs(a)))]
    b = np.cross(a, e)
    n = float(np.linalg.norm(b))
    return (1.0, 0.0, 0.0) if n == 0.0 else (float(b[0] / n), float(b[1] / n), float(b[2] / n))


class Params(StudyParams):
    """Parameters of the ``path_tracking`` study. None: derived from the robot
    (:mod:`~legcore.studies.path_tracking.defaults`, the rule in ``Task.rules``); seed 004's
    values on its own arm (the preset).

    - ``segments``: the path, consecutive lines/arcs in plane coordinates (m, rad); None: seed
      004's capsule (arcs r = 0.10 m about (±0.20, 0.30) m, lines at v = 0.40 and 0.20 m,
      counter-clockwise from (0.20, 0.20) m) scaled to the arm's reach, centred on the plane
      origin. Each segment must start where the previous ends, in the same direction (no
      corner: the tool does not stop between segments).
    - ``plane_origin``, ``plane_e1``, ``plane_e2``: the plane in the world (m; orthonormal axes);
      None: through a well-conditioned point of the arm's workspace, normal to the tool axis
      (horizontal for a free orientation), e1 across and e2 away from the arm (seed: the
      horizontal plane z = 0.50 m, "a una altura de 50cm").
    - ``orientation``: ``"down"`` (the tool z axis points straight down, the seed), ``"axis"``
      (along ``tool_axis``, any fixed world direction) or ``"free"`` (position only); None: the
      first the arm can hold along the whole path of down, forward (away from the arm,
      horizontal), up, free.
    - ``tool_yaw``: with an axis, None leaves the spin about it free (the seed: joint 5 stays
      at its rest value); a heading (rad) holds the tool's x axis fixed in the world too.
    - ``rest``: the posture (rad, one value per joint) the IK starts the path from — its branch
      is followed — and a redundant arm is pulled toward; None: with a derived path, the
      well-conditioned posture the path is centred on; with a given path, the robot's home.
    - ``objective``: ``"time"`` (T), ``"energy"`` (E) or ``"energy_time"`` (both).
    - ``speeds``: ``"per_segment"`` (one cruise speed per segment + t_a, t_d, t_b),
      ``"single"`` (one speed, t_a, t_d — the seed's scheme) or ``"profile"`` (the tool's speed
      at ``profile_intervals`` + 1 knots along the path, constant acceleration between them:
      it can follow the time-optimal profile, TOPP-RA's, which the two others cannot; the
      population starts from it).
    - ``profile_intervals``: with ``"profile"``, about this many equal intervals over the
      path (at least 2 per segment): as many decision variables, less one.
    - ``ramp``: speed-ramp shape, ``"linear"`` (the seed's trapezoid) or ``"cubic"`` (not used
      by ``"profile"``).
    - ``V``, ``t_a``, ``t_d``: the seed's law (m/s, s, s) used as the ``seed`` baseline; V
      None: 0.10 m/s scaled with the path, at most half the fastest speed the arm's joint
      speed limits allow everywhere on it (t_a = t_d = 3 s: a path scaled with its speeds
      keeps its times).
    - ``V_bounds`` (m/s), ``ramp_bounds`` (s, for t_a, t_d, t_b): the decision box (each
      segment's speed bound is lowered further to the fastest speed at which the arm's joint
      speed limits can hold somewhere on it: faster is infeasible); V_bounds None: (V/10,
      10 V), the seed's (0.01, 1.0) m/s about its V = 0.10 m/s.
    - ``T_max``: optional cycle-time cap (s), a constraint.
    - ``qdd_max``: joint acceleration limits (rad/s²), one for every joint or one per joint;
      ``"robot"`` (default): the robot's own (``qdd_max`` of its DH joints, or of its URDF
      spec by joint name), :data:`DEFAULT_QDD_MAX` (assumed) for joints without one; null: no
      acceleration limit (then a time optimum has millisecond ramps — physically
      meaningless). Speed and torque limits are the robot's.
    - ``n_samples``: time samples per candidate trajectory (evaluation and decoding).
    - ``limit_check``: the joint limits are checked on the ``n_samples`` samples, just before
      every speed-ramp boundary and on both sides of every segment join (where q̈ jumps) and,
      for a candidate within 2 % of a limit, again on ``limit_check`` × ``n_samples`` samples
      (so that the optimum keeps its limits between the samples too); 1: on the samples only
      (seed 004's evaluation, its preset).
    """

    kind: Literal["path_tracking"] = "path_tracking"
    segments: tuple[PathSegment, ...] | None = Field(default=None, min_length=1, max_length=64)
    plane_origin: Point3 | None = None
    plane_e1: Point3 | None = None
    plane_e2: Point3 | None = None
    orientation: Literal["down", "axis", "free"] | None = None
    tool_axis: Point3 | None = None
    tool_yaw: Finite | None = None
    rest: tuple[Finite, ...] | None = Field(default=None, min_length=1, max_length=12)
    objective: Literal["time", "energy", "energy_time"] = "time"
    speeds: Literal["per_segment", "single", "profile"] = "per_segment"
    profile_intervals: StrictInt = Field(default=256, ge=4, le=1000)
    ramp: Literal["linear", "cubic"] = "linear"
    V: Finite | None = Field(default=None, gt=0.0)
    t_a: Finite = Field(default=SEED_T_A, gt=0.0)
    t_d: Finite = Field(default=SEED_T_D, gt=0.0)
    V_bounds: tuple[Finite, Finite] | None = None
    ramp_bounds: tuple[Finite, Finite] = (0.005, 5.0)
    T_max: Finite | None = Field(default=None, gt=0.0)
    qdd_max: Positive | tuple[Positive, ...] | Literal["robot"] | None = "robot"
    n_samples: StrictInt = Field(default=400, ge=20, le=20_000)
    limit_check: StrictInt = Field(default=10, ge=1, le=50)

    @model_validator(mode="after")
    def _check(self) -> Params:
        for name in ("V_bounds", "ramp_bounds"):
            bounds = getattr(self, name)
            if bounds is None:
                continue
            lo, hi = bounds
            if not 0.0 < lo <= hi:
                raise ValueError(f"{name}: need 0 < lower <= upper, got ({lo}, {hi})")
        if self.plane_e1 is not None or self.plane_e2 is not None:
            e1 = self.plane_e1 if self.plane_e1 is not None else _ortho(self.plane_e2)
            e2 = self.plane_e2 if self.plane_e2 is not None else _ortho(self.plane_e1)
            try:
                Plane(np.zeros(3), np.array(e1), np.array(e2))
            except ValueError as exc:
                raise ValueError(f"plane_e1/plane_e2: {exc}") from None
        if self.tool_axis is not None and self.orientation not in (None, "axis"):
            raise ValueError("tool_axis: give it with orientation 'axis' (and only then)")
        if self.orientation == "axis" and self.tool_axis is None:
            raise ValueError("tool_axis: give it with orientation 'axis' (and only then)")
        if self.orientation == "free" and self.tool_yaw is not None:
            raise ValueError("tool_yaw: a heading needs a tool axis, not orientation 'free'")
        if self.orientation is not None:
            try:
                self.tool()
            except ValueError as exc:
                raise ValueError(str(exc)) from None
        if isinstance(self.qdd_max, tuple) and not 1 <= len(self.qdd_max) <= 12:
            raise ValueError("qdd_max: one value, or one per joint (1 to 12)")
        if self.segments is None:
            return self
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

    def concrete(self) -> bool:
        """True when every robot-relative field is set (the task of a robot; else
        ``Study.task`` derives the missing ones)."""
        return None not in (self.segments, self.plane_origin, self.plane_e1, self.plane_e2,
                            self.orientation, self.V, self.V_bounds)

    def plane(self) -> Plane:
        """The path's plane (ValueError while it is still to be derived from the robot)."""
        if self.plane_origin is None or self.plane_e1 is None or self.plane_e2 is None:
            raise ValueError("plane_origin: not set (derived from the robot by Study.task)")
        return Plane(np.array(self.plane_origin), np.array(self.plane_e1), np.array(self.plane_e2))

    def tool(self) -> ToolOrientation:
        """The tool orientation these parameters ask for."""
        if self.orientation is None:
            raise ValueError("orientation: not set (derived from the robot by Study.task)")
        if self.orientation == "free":
            return ToolOrientation(None)
        axis = (0.0, 0.0, -1.0) if self.orientation == "down" else self.tool_axis
        return ToolOrientation(axis, self.tool_yaw)
