"""Seed 003's settings on its own robot, the catalog's ``animatronic_quadruped``: the preset that
fills the robot-relative fields of ``quadruped_gait`` there (instead of the rules of
:mod:`legcore.studies.quadruped_gait.defaults`), so that every seed number is reproduced with
the defaults (``examples/003_quadruped_gait.yaml`` states the same values).

Table 2's first and last printed positions give the stance stroke: depth H = 0.1648 m below the
hip, step length 0.119 m centred 1.2 mm behind the hip. The paper gives no timing, step height,
search box or margin: 0.03 m/s, h = 0.03 m, s ∈ [0.04, 0.13] m, h ∈ [0.01, 0.05] m (≥ 1 cm
ground clearance) and the 1 mm static margin are ours (docs/studies.md (seed 003)).
"""

from __future__ import annotations

from legcore.studies.task import Preset

__all__ = ["PRESET"]

PRESET = Preset(
    robot="animatronic_quadruped",
    params={
        "step_length": 0.119,
        "step_height": 0.03,
        "step_length_bounds": (0.04, 0.13),
        "step_height_bounds": (0.01, 0.05),
        "speed": 0.03,
        "depth": 0.1648,
        "stroke_center": -0.0012,
        "stability_margin": 0.001,
    },
    source=("seed 003 (Pailos, Bima, Libal 2017), Table 2: stance depth 0.1648 m, stroke "
            "0.119 m centred 1.2 mm behind the hip; speed 0.03 m/s, step height 0.03 m, the "
            "search box and the 1 mm margin are ours"),
)
