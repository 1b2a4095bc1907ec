"""Two runs of seed 003's walk whose verdicts are known, for tests of the feasibility verdict
(issue 25): every parameter is given, so they do not depend on the study's robot-relative
defaults; two generations of a small HKA, a few seconds of a worker.

``GAIT`` meets its 1 mm static margin (feasible); ``UNSTABLE`` asks for 20 mm, which no step of
its search box has (the best keeps ~2.4 mm): it succeeds with an infeasible optimum.
"""

from __future__ import annotations

from typing import Any

__all__ = ["GAIT", "UNSTABLE"]

GAIT: dict[str, Any] = {
    "robot": "animatronic_quadruped",
    "problem": {
        "kind": "quadruped_gait", "stability_margin": 0.001, "step_length": 0.08,
        "step_height": 0.03, "duty": 0.8, "speed": 0.03, "depth": 0.1648,
        "stroke_center": -0.0012, "step_length_bounds": [0.04, 0.13],
        "step_height_bounds": [0.01, 0.05], "duty_bounds": [0.75, 0.9],
    },
    "optimizer": {"kind": "hka", "params": {"n_samples": 20, "survey_size": 40}},
    "budget": {"generations": 2},
    "seed": 1,
    "record": False,
}  # fmt: skip
UNSTABLE: dict[str, Any] = {**GAIT, "problem": {**GAIT["problem"], "stability_margin": 0.02}}
