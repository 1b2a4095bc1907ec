"""Parameters of the ``path_placement`` study. The fields that depend on the arm (the path's
size and duration, the placement region, the original placement, the start postures, the
nominal power) default to None: derived from the robot by
:mod:`legcore.studies.path_placement.defaults`; on seed 001's PUMA 560 the preset
(:mod:`legcore.studies.path_placement.preset`) gives the paper's settings (docs/studies.md)."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import Field, model_validator

from legcore.studies.path_placement.paths import (
    MAX_CSV_CHARS,
    ToolPath,
    builtin_path,
    oriented,
    parse_path_csv,
)
from legcore.studies.path_placement.region import BoxSpec, RegionSpec
from legcore.studies.study import StudyParams

__all__ = ["CONSTRAINT_NAMES", "PAPER", "PUMA560_NOMINAL_POWER_KW", "Params", "constraint_names"]

Finite = Annotated[float, Field(allow_inf_nan=False)]
Point3 = tuple[Finite, Finite, Finite]


def constraint_names(n: int, torque: bool = False) -> tuple[str, ...]:
    """Names of the constraints of an n-joint arm: joint positions, speeds, (``torque``: the
    joint torques, for an arm with torque limits) and the nominal power — 2n + 1 (3n + 1)."""
    return (*(f"q{i}_limit" for i in range(1, n + 1)),
            *(f"qd{i}_limit" for i in range(1, n + 1)),
            *((f"tau{i}_limit" for i in range(1, n + 1)) if torque else ()), "nominal_power")


#: The seed's 13 constraints (a 6-joint arm).
CONSTRAINT_NAMES: tuple[str, ...] = constraint_names(6)

#: The paper's results (seed 001 Tables 2, 3; §3.3): original vs optimised, its units.
PAPER: dict[str, dict[str, Any]] = {
    "pan": {
        "name": "Robotworks",
        "points": 225,
        "iterations": 20,
        "x_opt": (0.61642617, 0.51938117, -2.34115865),
        "time_s": (1.01205355, 0.87839920),
        "energy_kwh": (5.15545e-06, 2.38541e-06),
        "mean_w": (0.05889245, 0.11868260),
        "pct": {"time": 13.21, "energy": 53.73, "w": 50.38},
    },
    "jar": {
        "name": "Tarro Inclinado",
        "points": 413,
        "iterations": 27,
        "x_opt": (0.77493786, 0.438154, -0.05930750),
        "time_s": (1.66888271, 1.65655682),
        "energy_kwh": (2.28492e-05, 1.5657e-05),
        "mean_w": (0.02860888, 0.1060444),
        "pct": {"time": 0.74, "energy": 31.48, "w": 73.02},
    },
}

#: Default nominal power P_n of the PUMA 560 (kW), see ``Params.nominal_power_kw``.
PUMA560_NOMINAL_POWER_KW = 0.4

BranchName = Literal[
    "best",
    "left-up-noflip",
    "left-up-flip",
    "left-down-noflip",
    "left-down-flip",
    "right-up-noflip",
    "right-up-flip",
    "right-down-noflip",
    "right-down-flip",
]


class Params(StudyParams):
    """Parameters of the ``path_placement`` study (defaults: seed 001's own settings, where it
    gives them; see docs/studies.md (seed 001) for the chosen ones).

    - ``path``: ``"pan"`` (Robotworks stand-in, 225 points), ``"jar"`` (tilted jar, 413
      points) or ``"csv"`` (the text in ``csv``, see :func:`parse_path_csv`).
    - ``path_scale``: size of a built-in path relative to the paper's (pan radius 0.08 m, jar
      r 0.06 m × h 0.15 m); None: the arm's reach / the PUMA 560's (1 on the preset).
    - ``path_axis``: turn the path rigidly about its centroid so that its mean tool axis
      points along this world direction (a seam on a table onto a wall); None: as drawn.
      Unset: the first of as drawn, down, forward (away from the arm), up that the arm holds
      (as drawn on the preset).
    - ``spin`` (rad): every tool pose turned about its own axis (a torch's spin is free: the
      same weld; 0: the built-in paths' x axis along the world x projected); unset: the first
      of 0, π/2, π, −π/2 at which the arm reaches the most of the path at the original
      placement (0 on the preset).
    - ``duration`` (s): the path's duration when it has no time stamps (CSV without ``t``;
      for a built-in path it overrides the paper's time); None for a built-in path: the
      paper's, stretched until the arm's joints stay within half their speed limits at the
      original placement (the paper's on the preset).
    - ``timing``: ``"path"`` (the path's time stamps) or ``"joint_limited"`` (segments
      stretched so no joint exceeds ``speed_fraction·q̇_max``; the duration then varies).
    - ``region``: where the anchor may go, in the robot's base coordinates: a ``sphere``
      (``center``, ``radius``), a spherical ``shell`` (``center``, ``R``, ``gamma``, ``phi``)
      — decision x = (R, γ, φ) — or a ``box`` (``lo``, ``hi``) — x = (x, y, z). None: a
      sector of a shell about the shoulder around a well-conditioned placement, as large as
      the path stays reachable over (the preset: seed 001's simplified spherical workspace,
      eqs 1–5).
    - ``anchor``: the path point placed at p(x): ``"first"`` (the paper) or ``"centroid"``.
    - ``original``: x of the original placement (region coordinates), the reference of the %
      changes and a start of the search; None: the centre of the derived region, where the
      path is reachable and every constraint holds (the preset: where the path is written).
    - ``energy``: ``"electrical"`` (DC motors, eqs 9–14; joints with Kt, Ke, R only — the seed),
      ``"mechanical"`` (Σ ∫|τ_i q̇_i| dt) or ``"auto"`` (electrical when some joint has motor
      data, else mechanical). The result says which (``extra.energy_kind``).
    - ``energy_weight``: PC of eq 15 in [0, 1] (PM = 1 − PC). The paper does not give it.
    - ``nominal_power_kw``: P_n of eq 15 and of the power constraint (kW); None: Σ τ_max,i
      q̇_max,i of the arm's joints (their combined peak mechanical power; the power constraint
      then follows from the torque and speed limits; a joint without a torque limit counts
      with 2 × its largest gravity torque) (the preset: 0.4 kW, assumed for the PUMA 560).
    - ``max_manipulability``: w_M of eq 15 (m³); default: computed from the robot.
    - ``branch``: ``"best"`` (per candidate, the best IK branch for the whole path) or one of
      the PUMA-type closed form's 8 branch names.
    - ``postures``: start postures of the numerical IK (an arm without a closed form): each
      gives one candidate branch; None: the well-conditioned posture the derived region is
      centred on (the robot's home when the region is given). The first is also the rest
      posture a redundant arm is pulled toward.
    - ``friction``: motor/gear friction in the torques; ``regenerative``: integrate the signed
      electrical power (eq 14, braking returns energy) or only its positive part per motor.
    """

    kind: Literal["path_placement"] = "path_placement"
    path: Literal["pan", "jar", "csv"] = "pan"
    csv: str | None = Field(default=None, max_length=MAX_CSV_CHARS)
    path_scale: float | None = Field(default=None, gt=0.0, le=10.0)
    path_axis: Point3 | None = None
    spin: Finite | None = Field(default=None, ge=-2 * math.pi, le=2 * math.pi)
    duration: float | None = Field(default=None, gt=0.0, le=3600.0)
    timing: Literal["path", "joint_limited"] = "path"
    speed_fraction: float = Field(default=1.0, gt=0.0, le=1.0)
    region: RegionSpec | None = None
    anchor: Literal["first", "centroid"] = "first"
    original: tuple[Finite, Finite, Finite] | None = None
    energy: Literal["auto", "electrical", "mechanical"] = "auto"
    energy_weight: float = Field(default=0.5, ge=0.0, le=1.0)
    nominal_power_kw: float | None = Field(default=None, gt=0.0, le=1000.0)
    max_manipulability: float | None = Field(default=None, gt=0.0)
    branch: BranchName = "best"
    postures: tuple[tuple[Finite, ...], ...] | None = Field(default=None, min_length=1,
                                                            max_length=8)
    friction: bool = True
    regenerative: bool = True

    @model_validator(mode="after")
    def _check(self) -> Params:
        if self.path == "csv":
            if self.csv is None:
                raise ValueError("csv: required when path is 'csv'")
            parse_path_csv(self.csv, self.duration)  # raises ValueError("csv: ...")
            if self.path_scale not in (None, 1.0):
                raise ValueError("path_scale: only for the built-in paths (a CSV path is "
                                 "placed as written)")
        elif self.csv is not None:
            raise ValueError(f"csv: only used with path='csv', not path={self.path!r}")
        if self.path_axis is not None and math.hypot(*self.path_axis) < 1e-9:
            raise ValueError("path_axis: must be a non-zero direction")
        if self.original is not None and not isinstance(self.region, BoxSpec):
            R, gamma, phi = self.original
            if R <= 0.0:
                raise ValueError(f"original: R must be > 0 m, got {R}")
            if abs(gamma) > math.pi / 2:
                raise ValueError(f"original: γ must lie in [−π/2, π/2] rad, got {gamma}")
            if abs(phi) > 2 * math.pi:
                raise ValueError(f"original: φ must lie in [−2π, 2π] rad, got {phi}")
        return self

    def tool_path(self) -> ToolPath:
        """The path these parameters describe (at its original location), turned by
        ``path_axis`` and ``spin``."""
        if self.path == "csv":
            assert self.csv is not None
            path = parse_path_csv(self.csv, self.duration)
        else:
            path = builtin_path(self.path, self.duration,
                                1.0 if self.path_scale is None else self.path_scale)
        return oriented(path, self.path_axis, 0.0 if self.spin is None else self.spin)
