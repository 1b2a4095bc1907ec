"""How the ``hexapod_workspace`` study's result keys are shown: readable names, SI units, which
way is better, the paper's symbols (:mod:`legcore.studies.metric_names` looks them up)."""

from __future__ import annotations

import re

from legcore.studies.naming import MetricName, StudyDisplay

__all__ = ["BASELINES", "DISPLAY", "METRICS", "PATTERNS"]

M = MetricName

#: Result key -> how it is shown (objective keys under their displayed name).
METRICS: dict[str, MetricName] = {
    "f1_beta1": M("error of the triangle angle β1", "rad", "min", "f1"),
    "f2_beta5": M("error of the triangle angle β5", "rad", "min", "f2"),
    "f3_perimeter": M("error of the triangle perimeter", "m", "min", "f3"),
    "beta1": M("support-triangle angle β1", "rad"),
    "beta5": M("support-triangle angle β5", "rad"),
    "perimeter": M("support-triangle perimeter", "m"),
    "S_f": M("front stability distance", "m", "", "S_f"),
    "S_b": M("back stability distance", "m", "", "S_b"),
    "S_f_unbounded": M("front stability distance unbounded (null)", kind="flag"),
    "S_b_unbounded": M("back stability distance unbounded (null)", kind="flag"),
    "stable": M("statically stable", kind="flag"),
    "stability_margin": M("stability margin", "m", "max"),
    "body_dx": M("body shift x", "m"),
    "body_dy": M("body shift y", "m"),
    "body_dyaw": M("body yaw", "rad"),
    "foot_slip_max": M("largest foot slip", "m", "min"),
    "exact_reachable": M("reachable with θ2, θ3 free", kind="flag"),
    "theta2_exact_max_dev": M("largest θ2 change for that pose", "rad"),
    "theta3_exact_max_dev": M("largest θ3 change for that pose", "rad"),
    "motion_feet_fixed": M("a body motion keeps the feet", kind="flag"),
}

#: Key patterns (regex, label template with the groups, unit).
PATTERNS: tuple[tuple[re.Pattern[str], str, str], ...] = (
    (re.compile(r"theta1_L(\d+)$"), "coxa angle θ1 of leg {0}", "rad"),
)

#: Baseline name -> readable label.
BASELINES: dict[str, str] = {
    "start": "start stance",
    "straight_walk": "straight walk (5°)",
    "paper_a": "paper's solution a",
    "paper_b": "paper's solution b",
    "paper_c": "paper's solution c",
    "paper_d": "paper's solution d",
}

#: What the study's one-block summary shows.
DISPLAY = StudyDisplay(
    "the coxa angles θ1 of the three stance legs",
    "start",
    ("foot_slip_max", "stable"),
)
