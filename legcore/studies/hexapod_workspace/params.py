"""Parameters of the ``hexapod_workspace`` study (see
:mod:`legcore.studies.hexapod_workspace.problem`); every default is seed 002's setting."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, model_validator

from legcore.studies.hexapod_workspace.robot import HexapodGeometry
from legcore.studies.study import StudyParams

__all__ = ["HV_REF", "Params"]

FloatArray = NDArray[np.float64]

#: Hypervolume reference point (f1 rad, f2 rad, f3 m): 1° of β1, 1° of β5, 1 mm of perimeter —
#: the errors up to which a point is counted (fixed for the study so that runs compare).
HV_REF: tuple[float, float, float] = (math.radians(1.0), math.radians(1.0), 1.0e-3)

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


def _grid_too_large(p: Params, nyaw: int, ny: int, nx: int) -> str:
    """Message of a refused pose grid, naming the step to change and its allowed range."""
    total = nyaw * ny * nx
    size = (f"more than {_MAX_GRID}" if max(nyaw, ny, nx) > 2 * _MAX_GRID else str(total))
    axes = " × ".join(f"{name} {n if n <= 2 * _MAX_GRID else f'> {2 * _MAX_GRID}'}"
                      for name, n in (("yaw", nyaw), ("y", ny), ("x", nx)))
    shape = f"{size} poses ({axes}; at most {_MAX_GRID})"
    if nx * ny >= nyaw:  # the (x, y) grid is the larger factor: blame its step
        cells = _MAX_GRID // nyaw
        if cells >= 9:
            lo = _min_xy_step(p.pose_x_extent, p.pose_y_extent, cells)
            return (f"pose_xy_step: {p.pose_xy_step!r} m makes a pose grid of {shape}; with "
                    f"these extents and yaw grid use a step >= {lo:.3g} m (allowed range "
                    f"[{lo:.3g}, 1] m), or smaller pose_x_extent/pose_y_extent")
    else:
        k = (_MAX_GRID // (nx * ny) - 1) // 2  # yaw values each side of 0 that fit
        if k >= 1:
            lo = _round_up(p.pose_yaw_extent / k)
            return (f"pose_yaw_step: {p.pose_yaw_step!r} rad makes a pose grid of {shape}; "
                    f"with pose_yaw_extent = {p.pose_yaw_extent:.4g} rad and this xy grid use a "
                    f"step >= {lo:.3g} rad (allowed range [{lo:.3g}, π] rad), or a smaller "
                    "extent")
    return (f"pose_xy_step: {p.pose_xy_step!r} m makes a pose grid of {shape}; use coarser "
            "pose_xy_step and pose_yaw_step, or smaller extents")


class Params(StudyParams):
    """Parameters of the seed 002 study (defaults = the paper's settings; SI units).

    - ``theta1_min``/``theta1_max``: bounds of each decision θ1 (rad), paper ±π/6.
    - ``theta2``, ``theta3``: fixed femur/tibia angles of the stance legs (rad), paper −π/8, −π/4.
    - ``theta1_start``: θ1 of (front, back, middle) at stance t (rad), paper (0, 0, 0).
    - ``stance``: "135" (legs L1, L3, L5 — the paper's experiment) or "246" (L4, L6, L2).
    - ``triangle_formula``: "interior" (exact angles) or "paper" (eqs 12–13 as printed).
    - ``stability``: "classify" (post hoc, as the paper) or "constraint" (S_f, S_b > 0 as G).
    - ``pose_x_extent``, ``pose_y_extent`` (m), ``pose_xy_step`` (m), ``pose_yaw_extent``,
      ``pose_yaw_step`` (rad): grid of body displacements for the exact pose workspace
      (``[−extent, extent]`` each, 2⌊extent/step⌋ + 1 values per axis, at most 2,000,000
      poses in all: a smaller step is refused naming the smallest one that fits); ``knee``:
      IK branch there and in the motion ("up" = the paper's posture θ3 ≤ 0, "down", or
      "either").
    - ``duration`` (s) and ``motion_samples``: the decoded body motion from t to t+1.
    - ``hv_ref_point``: (f1 rad, f2 rad, f3 m) reference point of the reported hypervolume.
    - ``straight_step``: Δθ1 (rad) of the straight-walk baseline of §3 (θ1 of the front and
      back legs −Δθ1, of the middle leg +Δθ1); the paper gives no value, default 5°.
    - ``paper_baselines``: add seed 002's Table 2 solutions a–d as baselines (its θ1 values).
    - ``hexapod``: a parametric hexapod (:class:`~legcore.studies.hexapod_workspace.robot.
      HexapodGeometry`: leg lengths, hip layout, limits; seed 002's robot where left out) that
      the study runs on instead of the job's robot (leave ``robot`` out).
    - Any robot: ``stance`` "135" is the tripod of the front and back legs on one side (study
      x > 0) with the middle leg of the other (seed 002's legs 1, 3, 5); ``theta2``/``theta3``
      hold the 2nd and 3rd joint of every stance leg; for legs without seed 002's closed form
      ``knee`` does not apply (the IK takes the solution nearest the stance posture).
    """

    kind: Literal["hexapod_workspace"] = "hexapod_workspace"
    theta1_min: float = Field(default=-math.pi / 6, ge=-math.pi, le=math.pi)
    theta1_max: float = Field(default=math.pi / 6, ge=-math.pi, le=math.pi)
    theta2: float = Field(default=-math.pi / 8, ge=-math.pi, le=math.pi)
    theta3: float = Field(default=-math.pi / 4, ge=-math.pi, le=math.pi)
    theta1_start: tuple[float, float, float] = (0.0, 0.0, 0.0)
    stance: Literal["135", "246"] = "135"
    triangle_formula: Literal["interior", "paper"] = "interior"
    stability: Literal["classify", "constraint"] = "classify"
    pose_x_extent: float = Field(default=0.04, gt=0.0, le=1.0)
    pose_y_extent: float = Field(default=0.04, gt=0.0, le=1.0)
    pose_xy_step: float = Field(default=0.001, gt=0.0, le=1.0)
    pose_yaw_extent: float = Field(default=math.pi / 6, ge=0.0, le=math.pi)
    pose_yaw_step: float = Field(default=math.pi / 36, gt=0.0, le=math.pi)
    knee: Literal["up", "down", "either"] = "up"
    duration: float = Field(default=1.0, gt=0.0, le=3600.0)
    motion_samples: int = Field(default=51, ge=2, le=5000)
    hv_ref_point: tuple[float, float, float] = HV_REF
    straight_step: float = Field(default=math.radians(5.0), gt=0.0, le=math.pi / 2)
    paper_baselines: bool = True
    hexapod: HexapodGeometry | None = None

    @model_validator(mode="after")
    def _check(self) -> Params:
        if not self.theta1_min < self.theta1_max:
            raise ValueError(f"theta1_min: must be below theta1_max "
                             f"({self.theta1_min} >= {self.theta1_max})")
        for name, v in (("theta1_start", self.theta1_start), ("hv_ref_point", self.hv_ref_point)):
            if not all(math.isfinite(t) for t in v):
                raise ValueError(f"{name}: values must be finite")
        if not all(t > 0.0 for t in self.hv_ref_point):
            raise ValueError("hv_ref_point: every coordinate must be > 0")
        if any(abs(t) > math.pi for t in self.theta1_start):
            raise ValueError("theta1_start: angles must lie in [-pi, pi] rad")
        nyaw, ny, nx = self.pose_grid_shape
        if nyaw * ny * nx > _MAX_GRID:
            raise ValueError(_grid_too_large(self, nyaw, ny, nx))
        return self

    @property
    def pose_grid_shape(self) -> tuple[int, int, int]:
        """(nyaw, ny, nx) of the pose-workspace grid; an axis of more than ``_MAX_GRID``
        values (e.g. a step of 1e-300, whose extent/step overflows) counts as
        ``2 * _MAX_GRID + 1``, which the validator refuses."""
        return (_axis_count(self.pose_yaw_extent, self.pose_yaw_step),
                _axis_count(self.pose_y_extent, self.pose_xy_step),
                _axis_count(self.pose_x_extent, self.pose_xy_step))

    def pose_grid(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Grid axes (x, y, yaw), symmetric about 0 (m, m, rad)."""
        nyaw, ny, nx = self.pose_grid_shape
        step = self.pose_xy_step
        x = (np.arange(nx, dtype=float) - nx // 2) * step
        y = (np.arange(ny, dtype=float) - ny // 2) * step
        yaw = (np.arange(nyaw, dtype=float) - nyaw // 2) * self.pose_yaw_step
        return x, y, yaw
