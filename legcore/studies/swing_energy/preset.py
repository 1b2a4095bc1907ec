"""Seed 000's settings on its own leg (``calderon_leg``): the paper's values as data.

Calderón, Bedolla & Szwedowicz (2015): the transfer phase of one 3-DOF leg of an
electro-hydraulic hexapod (Table 1). On that catalog robot's kinematics (whatever its name,
masses or motors) ``PRESET`` fills every field the user leaves out before the robot-relative
rules of :mod:`legcore.studies.swing_energy.defaults` run, so the seed's numbers are reproduced
with the defaults (``examples/000_swing_energy_*.yaml`` also state them):

- start/end: the derived configurations of the seed (it gives neither; see
  ``docs/studies.md (seed 000)``) — start (−185, 384, −782), end (186, 384, −780) steps of
  0.00174 rad; with an obstacle (case 2) the end keeps joint 3 where it started (−782: Tables
  4–5, Solteiro's θ3 = 0). An end the user gives (as joints or as a foot position) is kept.
- link weights w_d = w_a = (0.25, 0.5, 0.25) (by torque demand, §4), search range
  (0.05, 0.3, 0.4) rad (the knee's larger: its lever arm to the foot is 2/3 of the hip
  pitch's), the parabolic baseline's apex 0.065 m, and the search tube around the coordinated
  motion with one-sided lifting deviations (our coding of the seed's GA, also with the box).

The obstacle box of ``obstacle: true`` (60 × 40 × 26 mm, 2 mm margin) needs no entry: the
robot-relative rule scales the seed's box by L / L₀, exactly 1 on this leg.
"""

from __future__ import annotations

from typing import Any

from legcore.studies.swing_energy.params import RESOLUTION, Params
from legcore.studies.task import Preset

__all__ = [
    "DEFAULT_END_STEPS",
    "DEFAULT_END_STEPS_OBSTACLE",
    "DEFAULT_START_STEPS",
    "PRESET",
    "SEED_SEARCH_RANGE",
    "seed_ends",
]

#: Seed 000's derived start/end configurations of its 3-joint leg, in resolution steps.
DEFAULT_START_STEPS = (-185, 384, -782)
DEFAULT_END_STEPS = (186, 384, -780)
DEFAULT_END_STEPS_OBSTACLE = (186, 384, -782)
#: Seed 000's per-joint search range (rad) and link weights.
SEED_SEARCH_RANGE = (0.05, 0.3, 0.4)
SEED_LINK_WEIGHTS = (0.25, 0.5, 0.25)


def _q(steps: tuple[int, ...]) -> tuple[float, ...]:
    return tuple(float(k * RESOLUTION) for k in steps)


def seed_ends(params: Params) -> dict[str, Any]:
    """The seed's start and end configurations for what the user gave: each end left out
    (neither joints nor foot position) is the seed's; case 2's end when there is an obstacle."""
    out: dict[str, Any] = {}
    if params.q_start is None and params.foot_start is None:
        out["q_start"] = _q(DEFAULT_START_STEPS)
    if params.q_end is None and params.foot_end is None:
        out["q_end"] = _q(DEFAULT_END_STEPS if params.box is None else DEFAULT_END_STEPS_OBSTACLE)
    return out


PRESET = Preset(
    robot="calderon_leg",
    params={
        "w_d": SEED_LINK_WEIGHTS,
        "w_a": SEED_LINK_WEIGHTS,
        "search_range": SEED_SEARCH_RANGE,
        "step_height": 0.065,
        "tube": "coordinated",
        "lift_only": True,
    },
    source=("Calderón, Bedolla & Szwedowicz 2015 (seed 000): Table 1's leg, the derived start "
            "and end of cases 1 and 2 (Tables 2–5), link weights (0.25, 0.5, 0.25), search range "
            "(0.05, 0.3, 0.4) rad, parabolic apex 0.065 m"),
    cases=seed_ends,
)
