"""How the ``path_placement`` study's result keys are shown: readable names, SI units, which
way is better, the paper's symbols (:mod:`legcore.studies.metric_names` looks them up)."""

from __future__ import annotations

import re

from legcore.studies.naming import MetricName, StudyDisplay

__all__ = ["BASELINES", "DISPLAY", "METRICS", "PATTERNS"]

M = MetricName

#: Result key -> how it is shown (objective keys under their displayed name).
METRICS: dict[str, MetricName] = {
    "J": M("cost J = energy + manipulability terms", "", "min", "J"),
    "energy_J": M("energy", "J", "min", "E",
                  note="electrical where the robot has motor data, else mechanical "
                  "(extra.energy_kind says which)"),
    "energy_kWh": M("energy", "kWh", same_as="energy_J"),
    "mean_manipulability": M("mean manipulability", "m³", "max", "w̄"),
    "mean_manipulability_ratio": M("mean manipulability / its maximum", "", "max"),
    "time_s": M("path time", "s"),
    "mean_power_W": M("mean power", "W"),
    "peak_power_W": M("peak power", "W"),
    "J_energy_term": M("energy term of J", ""),
    "J_manipulability_term": M("manipulability term of J", ""),
    "constraint_violation": M("constraint violation", ""),
    "unreachable_fraction": M("unreachable path points (fraction)", ""),
    "R": M("placement distance R", "m"),
    "gamma": M("placement angle γ", "rad"),
    "phi": M("placement angle φ", "rad"),
    "branch_index": M("IK branch (index)", ""),
    "energy_change_pct": M("energy change vs the original placement", "%", "min"),
    "manipulability_change_pct": M(
        "manipulability change vs the original placement", "%", "max"
    ),
    "time_change_pct": M("time change vs the original placement", "%"),
    "paper_energy_pct": M("energy saved", "%", same_as="energy_change_pct"),
    "paper_time_pct": M("time saved", "%", same_as="time_change_pct"),
    "paper_manipulability_pct": M(
        "manipulability gain / optimised value",
        "%",
        "max",
        "% w",
        note="(optimised − original) / optimised, the paper's formula for both columns",
    ),
}

#: Key patterns (regex, label template with the groups, unit).
PATTERNS: tuple[tuple[re.Pattern[str], str, str], ...] = ()

#: Baseline name -> readable label.
BASELINES: dict[str, str] = {
    "original": "original placement",
}

#: What the study's one-block summary shows.
DISPLAY = StudyDisplay(
    "where the welding path sits in front of the arm (R, γ, φ)",
    "original",
    ("energy_J", "mean_manipulability", "time_s"),
)
