"""Parameters of the ``quadruped_gait`` study (see
:mod:`legcore.studies.quadruped_gait.problem`)."""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import Field, StrictInt, field_validator, model_validator

from legcore.studies.quadruped_gait.cycle import SwingShape
from legcore.studies.study import StudyParams

__all__ = ["ROBOT_RELATIVE", "Pair", "Params"]

Pair = tuple[float, float]
#: One value per joint of a leg (2 or 3 joints).
PerJoint = Annotated[tuple[float, ...], Field(min_length=2, max_length=3)]
PerJointSign = Annotated[tuple[StrictInt, ...], Field(min_length=2, max_length=3)]

#: The scalar and pair fields derived from the robot when left unset (None); ``q_ref`` too.
ROBOT_RELATIVE = ("step_length", "step_height", "step_length_bounds", "step_height_bounds",
                  "speed", "depth", "stroke_center", "stability_margin")


def _finite(name: str, v: float) -> float:
    if not math.isfinite(v):
        raise ValueError(f"{name}: must be a finite number, got {v}")
    return v


class Params(StudyParams):
    """Parameters of the ``quadruped_gait`` study (SI units).

    **Robot-relative fields** (default None = derived from the robot by the rules of
    :mod:`legcore.studies.quadruped_gait.defaults`, scaled to its leg length L; on seed 003's
    ``animatronic_quadruped`` the paper's values of :mod:`~legcore.studies.quadruped_gait.preset`
    instead): ``step_length`` s (m) and ``step_height`` h (m) of the default step (the
    ``default_step`` baseline, what the optimum is compared with), their search boxes
    ``step_length_bounds`` / ``step_height_bounds`` (m), ``speed`` body speed v (m/s), ``depth``
    foot depth below the hip in stance H (m), ``stroke_center`` c (m, forward of the hip),
    ``stability_margin`` required static margin (m), ``q_ref`` a reference (standing) posture per
    leg (leg name → one angle per joint, rad; the IK takes the branch nearest it, then follows
    the path; legs not named get the derived standing posture). A value given is used as given.

    Robot-independent: ``duty`` β of the default step and ``duty_bounds``;
    ``swing_points`` optional user swing profile ``[(ξ, η), …]`` (ξ from −0.5 at lift-off to 0.5
    at touch-down, η ≥ 0 lift, 0 at both ends, scaled so its peak is h); ``samples_per_cycle``
    K (multiple of 4: the beats fall on the grid); ``com_offset`` body COM from the body centre
    (x, y) m; ``stance_load`` "body_weight" or "none"; ``energy_model`` "mechanical" (∫|τ q̇|)
    or "positive_work" (∫max(τ q̇, 0)); ``objective`` "energy_per_metre" (J/m) or
    "energy_per_cycle" (J); ``servo_offset_deg`` / ``servo_direction`` per leg (one servo per
    joint) override the robot's ``meta["servo"]``; ``table_positions`` number of stroke
    positions of the Table 2-like output (the paper's 48; 2-joint closed-form legs only) and
    ``compare_table2`` whether to print seed 003's Table 2 beside it; ``foot_lateral`` the
    feet's lateral distance from their hips (m, outward; default each leg's own at its home
    posture, or at the given ``q_ref``); ``ik`` "auto" (the 2-joint closed form where it
    applies, else :func:`legcore.ik.solve`) or "numeric" (always the numerical solver).
    """

    kind: Literal["quadruped_gait"] = "quadruped_gait"
    step_length: float | None = Field(
        default=None, gt=0.0, le=10.0,
        description="default step length s, m (None: 0.4 × leg length)")
    step_height: float | None = Field(
        default=None, ge=0.0, le=10.0,
        description="default step height h, m (None: 0.1 × leg length)")
    duty: float = Field(default=0.8, gt=0.0, lt=1.0)
    step_length_bounds: Pair | None = Field(
        default=None, description="search box of s, m (None: 0.1–0.6 × leg length)")
    step_height_bounds: Pair | None = Field(
        default=None, description="search box of h, m (None: 0.05–0.2 × leg length)")
    duty_bounds: Pair = (0.75, 0.9)
    speed: float | None = Field(
        default=None, gt=0.0, le=10.0,
        description="body speed v, m/s (None: Froude number 0.01, v = 0.1·√(g·L), lowered "
                    "until the default step's peak joint speed is half its limit)")
    depth: float | None = Field(
        default=None, gt=0.0, le=10.0,
        description="foot depth below the hip in stance H, m (None: 0.75 × leg length)")
    stroke_center: float | None = Field(
        default=None, ge=-10.0, le=10.0,
        description="stroke centre c forward of the hip, m (None: the whole robot's COM "
                    "offset from the hips' centre at the standing posture)")
    swing_points: tuple[Pair, ...] | None = Field(default=None, max_length=1000)
    samples_per_cycle: StrictInt = Field(default=64, ge=16, le=4096)
    stability_margin: float | None = Field(
        default=None, ge=-1.0, le=1.0,
        description="required static stability margin, m (None: 0.25 % of the leg length)")
    com_offset: Pair = (0.0, 0.0)
    stance_load: Literal["body_weight", "none"] = "body_weight"
    energy_model: Literal["mechanical", "positive_work"] = "mechanical"
    objective: Literal["energy_per_metre", "energy_per_cycle"] = "energy_per_metre"
    servo_offset_deg: dict[str, PerJoint] | None = Field(default=None, max_length=8)
    servo_direction: dict[str, PerJointSign] | None = Field(default=None, max_length=8)
    table_positions: StrictInt = Field(default=48, ge=2, le=1000)
    compare_table2: bool = True
    q_ref: dict[str, PerJoint] | None = Field(
        default=None, max_length=8,
        description="reference posture per leg, rad (None: each leg's standing posture at the "
                    "depth, knee toward the body centre where its limits allow)")
    foot_lateral: float | None = Field(default=None, ge=0.0, le=10.0)
    ik: Literal["auto", "numeric"] = "auto"

    @field_validator(
        "step_length", "step_height", "duty", "speed", "depth", "stroke_center", "stability_margin"
    )
    @classmethod
    def _finite_scalar(cls, v: float | None) -> float | None:
        return v if v is None else _finite("value", v)

    @field_validator("com_offset")
    @classmethod
    def _finite_pair(cls, v: Pair) -> Pair:
        if not all(math.isfinite(a) and abs(a) <= 10.0 for a in v):
            raise ValueError(f"must be two finite numbers within ±10 m, got {v}")
        return v

    @field_validator("samples_per_cycle")
    @classmethod
    def _multiple_of_4(cls, v: int) -> int:
        if v % 4:
            raise ValueError(f"must be a multiple of 4 (the four beats of the walk), got {v}")
        return v

    @field_validator("swing_points")
    @classmethod
    def _swing_points(cls, v: tuple[Pair, ...] | None) -> tuple[Pair, ...] | None:
        if v is not None:
            SwingShape(tuple(v))  # raises ValueError with the reason
        return v

    @field_validator("servo_direction")
    @classmethod
    def _directions(cls, v: dict[str, tuple[int, ...]] | None) -> Any:
        if v is not None:
            for leg, d in v.items():
                if any(x not in (-1, 1) for x in d):
                    raise ValueError(f"{leg}: directions must be +1 or -1, got {d}")
        return v

    @field_validator("servo_offset_deg")
    @classmethod
    def _offsets(cls, v: dict[str, tuple[float, ...]] | None) -> Any:
        if v is not None:
            for leg, o in v.items():
                if not all(math.isfinite(a) for a in o):
                    raise ValueError(f"{leg}: offsets must be finite degrees, got {o}")
        return v

    @field_validator("q_ref")
    @classmethod
    def _postures(cls, v: dict[str, tuple[float, ...]] | None) -> Any:
        if v is not None:
            for leg, q in v.items():
                if not all(math.isfinite(a) for a in q):
                    raise ValueError(f"{leg}: angles must be finite, got {q}")
        return v

    @model_validator(mode="after")
    def _bounds(self) -> Params:
        limits = {
            "step_length_bounds": (0.0, 10.0, False),
            "step_height_bounds": (0.0, 10.0, True),
            "duty_bounds": (0.0, 1.0, False),
        }
        for name, (lo_min, hi_max, closed) in limits.items():
            pair = getattr(self, name)
            if pair is None:
                continue
            lo, hi = pair
            if not (math.isfinite(lo) and math.isfinite(hi)):
                raise ValueError(f"{name}: must be finite, got {(lo, hi)}")
            if lo > hi:
                raise ValueError(f"{name}: lower bound {lo} above upper bound {hi}")
            low_ok = lo >= lo_min if closed else lo > lo_min
            if not low_ok or hi > hi_max or (name == "duty_bounds" and hi >= 1.0):
                raise ValueError(
                    f"{name}: must lie in {'[' if closed else '('}{lo_min}, {hi_max}"
                    f"{')' if name == 'duty_bounds' else ']'}, got {(lo, hi)}"
                )
        return self

    def need(self, name: str) -> Any:
        """The value of the robot-relative field ``name``, which must have been derived
        (:mod:`legcore.studies.quadruped_gait.defaults`); ``ValueError`` naming it if None."""
        value = getattr(self, name)
        if value is None:
            raise ValueError(f"{name}: not set; it is derived from the robot by "
                             "STUDY.task / STUDY.build (legcore.studies.quadruped_gait.defaults)")
        return value
