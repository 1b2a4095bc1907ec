"""How the ``quadruped_gait`` study's result keys are shown: readable names, SI units, which
way is better, the paper's symbols (:mod:`legcore.studies.metric_names` looks them up)."""

from __future__ import annotations

import re

from legcore.studies.naming import MetricName, StudyDisplay

__all__ = ["BASELINES", "DISPLAY", "METRICS", "PATTERNS"]

M = MetricName

#: Result key -> how it is shown (objective keys under their displayed name).
METRICS: dict[str, MetricName] = {
    "energy_per_metre": M("energy per metre walked", "J/m", "min"),
    "energy_per_cycle": M("energy per gait cycle", "J", "min"),
    "energy_per_metre_J_per_m": M("energy per metre walked", "J/m", same_as="energy_per_metre"),
    "energy_per_cycle_J": M("energy per gait cycle", "J", same_as="energy_per_cycle"),
    "energy_swing_J": M("energy of the swing phases", "J"),
    "energy_stance_J": M("energy of the stance phases", "J"),
    "cycle_time_s": M("cycle time", "s"),
    "distance_per_cycle_m": M("distance per cycle", "m"),
    "speed_m_s": M("body speed", "m/s"),
    "step_length_m": M("step length", "m"),
    "step_height_m": M("step height", "m"),
    "duty": M("duty factor β", ""),
    "min_stability_margin_m": M("least static stability margin", "m", "max"),
    "airborne": M("no foot on the ground at some instant (margin null)", kind="flag"),
    "required_stability_margin_m": M("required stability margin", "m"),
    "max_joint_speed_ratio": M("joint speed / limit (max)", ""),
    "max_torque_ratio": M("torque / servo torque (max)", ""),
    "max_torque_Nm": M("largest joint torque", "N·m"),
    "max_joint_speed_rad_s": M("largest joint speed", "rad/s"),
    "max_foot_load_N": M("largest foot load", "N"),
    "min_foot_load_N": M("least foot load", "N"),
    "reachable": M("every sample reachable", kind="flag"),
}

#: Key patterns (regex, label template with the groups, unit).
PATTERNS: tuple[tuple[re.Pattern[str], str, str], ...] = (
    (re.compile(r"energy_(\w+)_J$"), "energy of leg {0}", "J"),
)

#: Baseline name -> readable label.
BASELINES: dict[str, str] = {
    "default_step": "default step",
    "paper_walk": "paper's walk (β = 0.75)",
}

#: What the study's one-block summary shows.
DISPLAY = StudyDisplay(
    "step length, step height and duty factor of the walk",
    "default_step",
    ("step_length_m", "step_height_m", "duty", "min_stability_margin_m"),
)
