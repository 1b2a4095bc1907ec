"""Parameters of the ``hexapod_workspace`` study (see
:mod:`legcore.studies.hexapod_workspace.problem`).

The robot-relative fields (:data:`ROBOT_RELATIVE`) default to None: derived from the robot by
:mod:`legcore.studies.hexapod_workspace.defaults`, or seed 002's settings
(:mod:`legcore.studies.hexapod_workspace.preset`) on its own robot ``citedi_hexapod``."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, StrictInt, model_validator

from legcore.studies.hexapod_workspace.robot import HexapodGeometry
from legcore.studies.study import StudyParams

__all__ = ["HV_REF", "ROBOT_RELATIVE", "Params", "PoseGrid"]

FloatArray = NDArray[np.float64]

#: Seed 002's hypervolume reference point (f1 rad, f2 rad, f3 m): 1° of β1, 1° of β5, 1 mm of
#: perimeter — the errors up to which a point is counted (its preset's ``hv_ref_point``; on
#: another robot the perimeter's is scaled to its stance triangle).
HV_REF: tuple[float, float, float] = (math.radians(1.0), math.radians(1.0), 1.0e-3)

#: The fields derived from the robot when left unset (None).
ROBOT_RELATIVE = ("theta1_min", "theta1_max", "theta2", "theta3", "pose_x_extent",
                  "pose_y_extent", "pose_xy_step", "pose_yaw_extent", "pose_yaw_step",
                  "hv_ref_point")

#: Most poses (yaw × y × x) of the exact pose-workspace grid.
_MAX_GRID = 2_000_000


def _axis_count(extent: float, step: float) -> int:
    """Values of a grid axis on [−extent, extent] with spacing ``step``: 2⌊extent/step⌋ + 1,
    capped at 2·_MAX_GRID + 1 (an overflowing or huge ratio never becomes an integer)."""
    ratio = extent / step
    if not ratio < _MAX_GRID:  # also inf (step near 0) and nan
        return 2 * _MAX_GRID + 1
    return 2 * int(math.floor(ratio + 1e-9)) + 1


def _round_up(value: float) -> float:
    """``value`` rounded up to 3 significant digits (for messages giving a lower bound)."""
    quantum = 10.0 ** (math.floor(math.log10(value)) - 2)
    return math.ceil(value / quantum * (1 - 1e-12)) * quantum


def _min_xy_step(x_extent: float, y_extent: float, max_cells: int) -> float:
    """Smallest xy step (m) giving at most ``max_cells`` (x, y) grid cells: the positive root
    of (2·ex/s + 1)(2·ey/s + 1) = max_cells in u = 1/s, which bounds the floored counts."""
    a, b, c = 4.0 * x_extent * y_extent, 2.0 * (x_extent + y_extent), 1.0 - max_cells
    u = (-b + math.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)
    return _round_up(1.0 / u)



@dataclass(frozen=True)
class PoseGrid:
    """The grid of body displacements of the exact pose workspace: ``[−extent, extent]`` on
    each axis (x, y in m, yaw in rad) with spacing ``xy_step`` (m) / ``yaw_step`` (rad),
    2⌊extent/step⌋ + 1 values per axis, at most 2,000,000 poses."""

    x_extent: float
    y_extent: float
    xy_step: float
    yaw_extent: float
    yaw_step: float

    @property
    def shape(self) -> tuple[int, int, int]:
        """(nyaw, ny, nx); an axis of more than ``_MAX_GRID`` values (e.g. a step of 1e-300,
        whose extent/step overflows) counts as ``2 * _MAX_GRID + 1``."""
        return (_axis_count(self.yaw_extent, self.yaw_step),
                _axis_count(self.y_extent, self.xy_step),
                _axis_count(self.x_extent, self.xy_step))

    def axes(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Grid axes (x, y, yaw), symmetric about 0 (m, m, rad)."""
        nyaw, ny, nx = self.shape
        x = (np.arange(nx, dtype=float) - nx // 2) * self.xy_step
        y = (np.arange(ny, dtype=float) - ny // 2) * self.xy_step
        yaw = (np.arange(nyaw, dtype=float) - nyaw // 2) * self.yaw_step
        return x, y, yaw

    def error(self) -> str | None:
        """``"<step field>: …"`` when the grid has more than 2,000,000 poses (naming the step
        to change and its allowed range), else None."""
        nyaw, ny, nx = self.shape
        if nyaw * ny * nx <= _MAX_GRID:
            return None
        total = nyaw * ny * nx
        size = (f"more than {_MAX_GRID}" if max(nyaw, ny, nx) > 2 * _MAX_GRID else str(total))
        axes = " × ".join(f"{name} {n if n <= 2 * _MAX_GRID else f'> {2 * _MAX_GRID}'}"
                          for name, n in (("yaw", nyaw), ("y", ny), ("x", nx)))
        shape = f"{size} poses ({axes}; at most {_MAX_GRID})"
        if nx * ny >= nyaw:  # the (x, y) grid is the larger factor: blame its step
            cells = _MAX_GRID // nyaw
            if cells >= 9:
                lo = _min_xy_step(self.x_extent, self.y_extent, cells)
                return (f"pose_xy_step: {self.xy_step!r} m makes a pose grid of {shape}; with "
                        f"these extents and yaw grid use a step >= {lo:.3g} m (allowed range "
                        f"[{lo:.3g}, 10] m), or smaller pose_x_extent/pose_y_extent")
        else:
            k = (_MAX_GRID // (nx * ny) - 1) // 2  # yaw values each side of 0 that fit
            if k >= 1:
                lo = _round_up(self.yaw_extent / k)
                return (f"pose_yaw_step: {self.yaw_step!r} rad makes a pose grid of {shape}; "
                        f"with pose_yaw_extent = {self.yaw_extent:.4g} rad and this xy grid use "
                        f"a step >= {lo:.3g} rad (allowed range [{lo:.3g}, π] rad), or a "
                        "smaller extent")
        return (f"pose_xy_step: {self.xy_step!r} m makes a pose grid of {shape}; use coarser "
                "pose_xy_step and pose_yaw_step, or smaller extents")


def _derived(what: str) -> str:
    return f"{what} (None: derived from the robot, see hexapod_workspace.defaults)"


class Params(StudyParams):
    """Parameters of the ``hexapod_workspace`` study (SI units).

    **Robot-relative fields** (default None = derived from the robot by the rules of
    :mod:`legcore.studies.hexapod_workspace.defaults`; on seed 002's ``citedi_hexapod`` — or a
    parametric ``hexapod`` with all of seed 002's geometry — the paper's values of
    :mod:`~legcore.studies.hexapod_workspace.preset` instead; a value given is used as given):

    - ``theta1_min``/``theta1_max``: bounds of each decision θ1 (rad) (paper ±π/6; derived: the
      coxa swing that keeps each stance foot out of half the gap to its neighbour's foot,
      inside the coxa limits).
    - ``theta2``, ``theta3``: fixed femur/tibia angles of the stance legs (rad) (paper −π/8,
      −π/4; derived: the foot 45° below the hip, halfway along the leg's reach on that line).
    - ``pose_x_extent``, ``pose_y_extent`` (m), ``pose_xy_step`` (m), ``pose_yaw_extent``,
      ``pose_yaw_step`` (rad): grid of body displacements for the exact pose workspace
      (``[−extent, extent]`` each, 2⌊extent/step⌋ + 1 values per axis, at most 2,000,000
      poses in all: a smaller step is refused naming the smallest one that fits) (paper
      ±4 cm by 1 mm, ±π/6 by π/36; derived: the box the legs' reach allows, 41 × 41 × 13).
    - ``hv_ref_point``: (f1 rad, f2 rad, f3 m) reference point of the reported hypervolume
      (paper robot (1°, 1°, 1 mm); derived: (1°, 1°, 0.2 % of the stance triangle's
      perimeter)).

    Robot-independent:

    - ``theta1_start``: θ1 of (front, back, middle) at stance t (rad), (0, 0, 0).
    - ``stance``: "135" (legs L1, L3, L5 — the paper's experiment) or "246" (L4, L6, L2).
    - ``triangle_formula``: "interior" (exact angles) or "paper" (eqs 12–13 as printed).
    - ``stability``: "constraint" (S_f, S_b > 0 as G: the front holds only stable stances) or
      "classify" (post hoc, as the paper — its preset). Either way a run's ``feasible`` says
      whether the optimum is stable (``HexapodWorkspaceProblem.violations``).
    - ``knee``: IK branch of the pose workspace and the motion ("up" = the paper's posture
      θ3 ≤ 0, "down", or "either"); the derived stance posture is on that branch.
    - ``duration`` (s) and ``motion_samples``: the decoded body motion from t to t+1.
    - ``straight_step``: Δθ1 (rad) of the straight-walk baseline of §3 (θ1 of the front and
      back legs −Δθ1, of the middle leg +Δθ1); the paper gives no value, default 5°.
    - ``paper_baselines``: add seed 002's Table 2 solutions a–d as baselines (its θ1 values;
      default off, on in the paper's preset).
    - ``hexapod``: a parametric hexapod (:class:`~legcore.studies.hexapod_workspace.robot.
      HexapodGeometry`: leg lengths, hip layout, limits; seed 002's robot where left out) that
      the study runs on instead of the job's robot (leave ``robot`` out); the defaults are
      derived from it.
    - Any robot: ``stance`` "135" is the tripod of the front and back legs on one side (study
      x > 0) with the middle leg of the other (seed 002's legs 1, 3, 5); ``theta2``/``theta3``
      hold the 2nd and 3rd joint of every stance leg; for legs without seed 002's closed form
      ``knee`` does not apply (the IK takes the solution nearest the stance posture).
    """

    kind: Literal["hexapod_workspace"] = "hexapod_workspace"
    theta1_min: float | None = Field(default=None, ge=-math.pi, le=math.pi,
                                     description=_derived("lower bound of each θ1, rad"))
    theta1_max: float | None = Field(default=None, ge=-math.pi, le=math.pi,
                                     description=_derived("upper bound of each θ1, rad"))
    theta2: float | None = Field(default=None, ge=-math.pi, le=math.pi,
                                 description=_derived("femur angle of the stance legs, rad"))
    theta3: float | None = Field(default=None, ge=-math.pi, le=math.pi,
                                 description=_derived("tibia angle of the stance legs, rad"))
    theta1_start: tuple[float, float, float] = (0.0, 0.0, 0.0)
    stance: Literal["135", "246"] = "135"
    triangle_formula: Literal["interior", "paper"] = "interior"
    stability: Literal["classify", "constraint"] = "constraint"
    pose_x_extent: float | None = Field(default=None, gt=0.0, le=10.0,
                                        description=_derived("pose grid half-width in x, m"))
    pose_y_extent: float | None = Field(default=None, gt=0.0, le=10.0,
                                        description=_derived("pose grid half-width in y, m"))
    pose_xy_step: float | None = Field(default=None, gt=0.0, le=10.0,
                                       description=_derived("pose grid step in x and y, m"))
    pose_yaw_extent: float | None = Field(default=None, ge=0.0, le=math.pi,
                                          description=_derived("pose grid half-width in yaw, "
                                                               "rad"))
    pose_yaw_step: float | None = Field(default=None, gt=0.0, le=math.pi,
                                        description=_derived("pose grid step in yaw, rad"))
    knee: Literal["up", "down", "either"] = "up"
    duration: float = Field(default=1.0, gt=0.0, le=3600.0)
    motion_samples: StrictInt = Field(default=51, ge=2, le=5000)
    hv_ref_point: tuple[float, float, float] | None = Field(
        default=None, description=_derived("hypervolume reference (f1 rad, f2 rad, f3 m)"))
    straight_step: float = Field(default=math.radians(5.0), gt=0.0, le=math.pi / 2)
    paper_baselines: bool = False
    hexapod: HexapodGeometry | None = None

    @model_validator(mode="after")
    def _check(self) -> Params:
        if (self.theta1_min is not None and self.theta1_max is not None
                and not self.theta1_min < self.theta1_max):
            raise ValueError(f"theta1_min: must be below theta1_max "
                             f"({self.theta1_min} >= {self.theta1_max})")
        if not all(math.isfinite(t) for t in self.theta1_start):
            raise ValueError("theta1_start: values must be finite")
        if self.hv_ref_point is not None:
            if not all(math.isfinite(t) for t in self.hv_ref_point):
                raise ValueError("hv_ref_point: values must be finite")
            if not all(t > 0.0 for t in self.hv_ref_point):
                raise ValueError("hv_ref_point: every coordinate must be > 0")
        if any(abs(t) > math.pi for t in self.theta1_start):
            raise ValueError("theta1_start: angles must lie in [-pi, pi] rad")
        grid = self.grid()
        error = None if grid is None else grid.error()
        if error is not None:
            raise ValueError(error)
        return self

    @property
    def concrete(self) -> bool:
        """True when no robot-relative field is left to derive."""
        return all(getattr(self, name) is not None for name in ROBOT_RELATIVE)

    def value(self, name: str) -> float:
        """The robot-relative scalar ``name``; ``ValueError`` if it was not derived yet
        (``Study.task`` derives it)."""
        v = getattr(self, name)
        if v is None:
            raise ValueError(f"{name}: not derived from the robot yet (use STUDY.task or "
                             "STUDY.build)")
        return float(v)

    def hv_ref(self) -> tuple[float, float, float]:
        """``hv_ref_point`` (f1 rad, f2 rad, f3 m), once derived."""
        if self.hv_ref_point is None:
            raise ValueError("hv_ref_point: not derived from the robot yet (use STUDY.task or "
                             "STUDY.build)")
        return self.hv_ref_point

    def grid(self) -> PoseGrid | None:
        """The pose grid, or None while one of its fields is left to derive."""
        values = (self.pose_x_extent, self.pose_y_extent, self.pose_xy_step,
                  self.pose_yaw_extent, self.pose_yaw_step)
        if any(v is None for v in values):
            return None
        return PoseGrid(*(float(v) for v in values if v is not None))

    @property
    def pose_grid_shape(self) -> tuple[int, int, int]:
        """(nyaw, ny, nx) of the pose-workspace grid (see :class:`PoseGrid`)."""
        grid = self.grid()
        if grid is None:
            raise ValueError("pose_xy_step: the pose grid is not derived from the robot yet")
        return grid.shape

    def pose_grid(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Grid axes (x, y, yaw), symmetric about 0 (m, m, rad)."""
        grid = self.grid()
        if grid is None:
            raise ValueError("pose_xy_step: the pose grid is not derived from the robot yet")
        return grid.axes()
