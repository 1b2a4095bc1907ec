"""What the ``path_tracking`` study's helpers read of its problem: a protocol, and the record of
the physical minimum.

:class:`legcore.studies.path_tracking.problem.PathTrackingProblem` imports
:mod:`~legcore.studies.path_tracking.baselines`, :mod:`~legcore.studies.path_tracking.decode`,
:mod:`~legcore.studies.path_tracking.limits` and :mod:`~legcore.studies.path_tracking.optimal`;
they read it through :class:`TrackingProblem` instead of importing it, so the five are no
import circle.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from legcore.robots.model import Robot
from legcore.studies.path_tracking.encodings import SegmentSpeeds, SpeedProfile
from legcore.studies.path_tracking.joints import JointPath
from legcore.studies.path_tracking.kin import ArcLengthPath
from legcore.studies.path_tracking.params import Params, ToolOrientation
from legcore.studies.path_tracking.timelaw import RampShape, TimeLaw
from legcore.studies.study import Solution
from legcore.studies.task import Violation

__all__ = ["PhysicalMinimum", "TrackingProblem"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class PhysicalMinimum:
    """A time-optimal profile that keeps every limit on a dense resampling: ``grid`` (N + 1,)
    m, ``speed`` (N + 1,) m/s, ``T`` s; ``scale`` the factor (≤ 1) the limits were multiplied
    by for it, ``T_at_limits`` s TOPP-RA's time at the limits themselves (kept at the
    gridpoints only); ``law`` the profile as a time law (B = 1)."""

    grid: FloatArray
    speed: FloatArray
    T: float
    scale: float
    T_at_limits: float
    law: TimeLaw

    def as_dict(self) -> dict[str, Any]:
        return {"T": self.T, "T_at_limits": self.T_at_limits, "limit_scale": self.scale,
                "intervals": int(self.grid.size - 1), "method": "TOPP-RA",
                "v_peak": float(self.speed.max())}


class TrackingProblem(Protocol):
    """The path-timing problem as its helpers see it (attributes and methods documented on
    :class:`~legcore.studies.path_tracking.problem.PathTrackingProblem`)."""

    robot: Robot
    params: Params
    path: ArcLengthPath
    tool: ToolOrientation
    qdd_max: FloatArray
    rest: FloatArray
    n_seg: int
    n_samples: int
    joints: JointPath
    trapezoid: SegmentSpeeds
    encoding: SegmentSpeeds | SpeedProfile
    limit_check: int
    variable_names: tuple[str, ...]
    constraint_names: tuple[str, ...]
    objective_names: tuple[str, ...]
    xl: FloatArray
    xu: FloatArray

    @property
    def seed_max_V(self) -> float:
        """Largest single V (m/s) for which the seed's scheme holds every limit."""
        ...

    @property
    def time_optimal(self) -> PhysicalMinimum | None:
        """The physical minimum (TOPP-RA), None when none exists."""
        ...

    def seed_law(self, V: FloatArray | float | None = None) -> TimeLaw:
        """The seed's law at one speed ``V`` on every segment."""
        ...

    def time_law(self, X: FloatArray, shape: RampShape | None = None) -> TimeLaw:
        """The arc-length laws of a batch."""
        ...

    def simulate(
        self, X: FloatArray | TimeLaw, shape: RampShape | None = None, full: bool = True,
        samples: int | None = None, extra_times: bool = False,
    ) -> dict[str, Any]:
        """Whole-batch motion of decision vectors or time laws."""
        ...

    def objectives(self, sim: dict[str, Any]) -> FloatArray:
        """F (B, n_obj) of a simulation."""
        ...

    def dense_limits(self, X: FloatArray | TimeLaw, G: FloatArray, factor: int,
                     shape: RampShape | None = None, every: bool = False) -> FloatArray:
        """G with the limits checked on a denser resampling."""
        ...

    def decode_law(self, law: TimeLaw, x: FloatArray | None = None,
                   encoded: dict[str, float] | None = None, shape: RampShape | None = None
                   ) -> Solution:
        """The Solution of one time law."""
        ...

    def seed_violations(self) -> tuple[Violation, ...]:
        """What the seed law violates on this arm."""
        ...
