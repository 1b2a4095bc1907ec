"""How the ``swing_energy`` study's result keys are shown: readable names, SI units, which
way is better, the paper's symbols (:mod:`legcore.studies.metric_names` looks them up)."""

from __future__ import annotations

import re

from legcore.studies.naming import MetricName, StudyDisplay

__all__ = ["BASELINES", "DISPLAY", "METRICS", "PATTERNS"]

M = MetricName

#: Result key -> how it is shown (objective keys under their displayed name).
METRICS: dict[str, MetricName] = {
    "score": M("score F = w1·f_d + w2·f_a (best 10)", "", "max", "F"),
    "f_d": M("joint displacement criterion", "", "max", "f_d"),
    "f_a": M("joint acceleration criterion", "", "max", "f_a"),
    "theta_total": M("total joint travel", "rad", "min", "θ_T"),
    "path_length": M("foot path length", "m", "min", "D_PFE"),
    "energy_total": M("swing energy ∫|τ·ω|dt", "J", "min", "E_T"),
    "tau_sq_total": M("squared-torque integral ∫τ²dt", "N²·m²·s", "min", "T_cuad"),
    "duration": M("swing duration", "s", "", "T"),
    "criterion": M("the GA's criterion", same_as="score"),
    "ground_clearance": M("least ground clearance", "m"),
    "on_grid": M("on the control-resolution grid", kind="flag"),
    "lift_height": M("foot lift height", "m"),
    "g_ground": M("ground constraint g (≤ 0 holds)", "m"),
    "g_obstacle": M("obstacle constraint g (≤ 0 holds)", "m"),
    "obstacle_clearance": M("least obstacle clearance", "m"),
}

#: Key patterns (regex, label template with the groups, unit).
PATTERNS: tuple[tuple[re.Pattern[str], str, str], ...] = ()

#: Baseline name -> readable label.
BASELINES: dict[str, str] = {
    "calderon2008_parabolic": "parabolic swing (Calderón 2008)",
    "tian_collins2004_min_displacement": "least joint travel (Tian & Collins 2004)",
    "shankar_kaur2011_min_distance": "shortest foot path (Shankar & Kaur 2011)",
    "solteiro2007_multi_criteria": "multi-criteria (Solteiro 2007)",
    "perez2010_min_energy": "least energy (Pérez 2010)",
    "gradient_min_energy": "least energy, gradient (SLSQP)",
}

#: What the study's one-block summary shows.
DISPLAY = StudyDisplay(
    "the swing trajectory of one leg (joint via points)",
    "calderon2008_parabolic",
    ("energy_total", "theta_total", "path_length"),
)
