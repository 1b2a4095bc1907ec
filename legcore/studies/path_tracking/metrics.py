"""How the ``path_tracking`` study's result keys are shown: readable names, SI units, which
way is better, the paper's symbols (:mod:`legcore.studies.metric_names` looks them up)."""

from __future__ import annotations

import re

from legcore.studies.naming import MetricName, StudyDisplay

__all__ = ["BASELINES", "DISPLAY", "METRICS", "PATTERNS"]

M = MetricName

#: Result key -> how it is shown (objective keys under their displayed name).
METRICS: dict[str, MetricName] = {
    "energy": M("mechanical energy ∫|τ·ω|dt", "J", "min"),
    "energy_shared": M("energy with a shared supply ∫max(Στ·ω, 0)dt", "J"),
    "energy_net": M("net work ∫Στ·ω dt (perfect regeneration)", "J"),
    "tool_speed_max": M("largest tool speed", "m/s"),
    "qd_use_max": M("joint speed / limit (max)", ""),
    "qdd_use_max": M("joint acceleration / limit (max)", ""),
    "tau_use_max": M("joint torque / limit (max)", ""),
    "t_a": M("start ramp time t_a", "s", "", "t_a"),
    "t_d": M("stop ramp time t_d", "s", "", "t_d"),
    "t_b": M("blend time t_b", "s"),
    "ramp_shrink": M("ramp scale (1: as asked)", ""),
    "v_peak": M("peak tool speed of the profile", "m/s"),
    "limit_scale": M("limits × (to hold between gridpoints)", ""),
}

#: Key patterns (regex, label template with the groups, unit).
PATTERNS: tuple[tuple[re.Pattern[str], str, str], ...] = (
    (re.compile(r"T_(\d+)$"), "time on segment {0}", "s"),
    (re.compile(r"V_(\d+)$"), "cruise speed on segment {0}", "m/s"),
)

#: Baseline name -> readable label.
BASELINES: dict[str, str] = {
    "time_optimal": "physical minimum (TOPP-RA)",
    "seed": "paper's time law",
    "seed_max_V": "paper's law at its top speed",
}

#: What the study's one-block summary shows.
DISPLAY = StudyDisplay(
    "the speed of each path segment and the ramp times",
    "seed",
    ("time", "energy"),
)
