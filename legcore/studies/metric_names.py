"""Readable names and units of the studies' result keys (data for the CLI, API and dashboard).

The studies name their objectives and metrics with short keys, many of them the papers' own
symbols (``T_cuad``, ``D_PFE``, ``f_d``, ``f_a``, ``energy_total``). This module maps each key
to what a reader needs: a name, an SI unit, whether a user wants it small or large, and the
paper's symbol. It changes nothing the studies compute.

Sign convention for display: every objective is *minimised* by the optimisers; an objective
key ``neg_<m>`` is the negation of a quantity ``<m>`` the user *maximises* (the seed 000 score),
and is shown as ``<m>`` with its positive value. :func:`display_objective` applies that rule.

Keys not listed here get a name from their unit suffix (``peak_power_W`` → "peak power", W)
or stay as they are (:func:`metric_name` never fails). A metric whose
``same_as`` is set repeats another key's number (a unit conversion, a sign flip, the
objective under another name) and is left out of tables (``--json`` keeps it).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Literal

__all__ = [
    "BASELINE_NAMES",
    "JOINT_ROW_NAMES",
    "METRICS",
    "NEGATED_PREFIX",
    "STUDY_DISPLAY",
    "MetricName",
    "StudyDisplay",
    "baseline_name",
    "display_objective",
    "joint_row_name",
    "metric_name",
]

Sense = Literal["min", "max", ""]
Kind = Literal["value", "flag"]

#: Prefix of an objective that is the negation of a maximised quantity.
NEGATED_PREFIX = "neg_"


@dataclass(frozen=True)
class MetricName:
    """How to show one result key.

    ``label``: readable name; ``unit``: SI unit ("" when dimensionless); ``sense``: "min" or
    "max" when smaller/larger is better, "" otherwise; ``paper``: the paper's own symbol;
    ``kind``: "flag" for 0/1 values (shown yes/no); ``same_as``: the key whose number this
    repeats (then hidden in tables); ``note``: what a reader must know (a different formula).
    """

    label: str
    unit: str = ""
    sense: Sense = ""
    paper: str = ""
    kind: Kind = "value"
    same_as: str | None = None
    note: str = ""


M = MetricName

#: Keys shared by several studies (a study's own entry below wins).
_COMMON: dict[str, MetricName] = {
    "feasible": M("feasible (all constraints hold)", kind="flag"),
    "duration": M("duration", "s"),
    "theta_total": M("total joint travel", "rad"),
    "path_length": M("tool path length", "m"),
    "time": M("cycle time", "s", "min"),
    "energy": M("mechanical energy ∫|τ·ω|dt", "J", "min"),
    "cv": M("constraint violation", ""),
}

#: kind -> key -> name. Objective keys appear under their displayed name (``score``, not
#: ``neg_score``).
METRICS: dict[str, dict[str, MetricName]] = {
    "swing_energy": {
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
    },
    "path_placement": {
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
    },
    "hexapod_workspace": {
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
    },
    "quadruped_gait": {
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
    },
    "path_tracking": {
        "energy": M("mechanical energy ∫|τ·ω|dt", "J", "min"),
        "tool_speed_max": M("largest tool speed", "m/s"),
        "qd_use_max": M("joint speed / limit (max)", ""),
        "qdd_use_max": M("joint acceleration / limit (max)", ""),
        "tau_use_max": M("joint torque / limit (max)", ""),
        "t_a": M("start ramp time t_a", "s", "", "t_a"),
        "t_d": M("stop ramp time t_d", "s", "", "t_d"),
        "t_b": M("blend time t_b", "s"),
        "ramp_shrink": M("ramp scale (1: as asked)", ""),
    },
}

#: Key patterns (kind, regex, label template with the groups, unit).
_PATTERNS: tuple[tuple[str, re.Pattern[str], str, str], ...] = (
    ("path_tracking", re.compile(r"T_(\d+)$"), "time on segment {0}", "s"),
    ("path_tracking", re.compile(r"V_(\d+)$"), "cruise speed on segment {0}", "m/s"),
    ("quadruped_gait", re.compile(r"energy_(\w+)_J$"), "energy of leg {0}", "J"),
    ("hexapod_workspace", re.compile(r"theta1_L(\d+)$"), "coxa angle θ1 of leg {0}", "rad"),
)

#: Unit suffixes of keys no table names (longest first): suffix -> unit.
_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_J_per_m", "J/m"), ("_rad_s", "rad/s"), ("_m_s", "m/s"), ("_kWh", "kWh"),
    ("_pct", "%"), ("_Nm", "N·m"), ("_rad", "rad"), ("_deg", "°"), ("_kg", "kg"),
    ("_J", "J"), ("_W", "W"), ("_N", "N"), ("_m", "m"), ("_s", "s"),
)  # fmt: skip

#: Baseline names → readable labels.
BASELINE_NAMES: dict[str, str] = {
    "calderon2008_parabolic": "parabolic swing (Calderón 2008)",
    "tian_collins2004_min_displacement": "least joint travel (Tian & Collins 2004)",
    "shankar_kaur2011_min_distance": "shortest foot path (Shankar & Kaur 2011)",
    "solteiro2007_multi_criteria": "multi-criteria (Solteiro 2007)",
    "perez2010_min_energy": "least energy (Pérez 2010)",
    "original": "original placement",
    "start": "start stance",
    "straight_walk": "straight walk (5°)",
    "paper_a": "paper's solution a",
    "paper_b": "paper's solution b",
    "paper_c": "paper's solution c",
    "paper_d": "paper's solution d",
    "default_step": "default step",
    "paper_walk": "paper's walk (β = 0.75)",
    "seed": "paper's time law",
    "seed_max_V": "paper's law at its top speed",
}


#: Row labels of the per-joint tables (seed 000 Table 2 notation and the studies' own) →
#: readable names; the label itself is printed beside as the paper's symbol.
JOINT_ROW_NAMES: dict[str, str] = {
    "θ": "joint travel",
    "θ_min": "net displacement, start to end",
    "ω_max": "peak speed",
    "α_max": "peak acceleration",
    "α_min": "peak deceleration",
    "Jerk": "peak jerk",
    "τ_max": "peak torque",
    "T_cuad": "squared-torque integral ∫τ²dt",
    "E": "energy ∫|τ·ω|dt",
    "θ_T": "total joint travel",
    "D_PFE": "foot path length",
    "T": "duration",
    "q_min": "lowest angle",
    "q_max": "highest angle",
    "|qd|_max": "peak speed",
    "qd_limit": "speed limit",
    "|tau|_max": "peak torque",
    "E_electrical": "electrical energy of the motor",
    "E_mechanical": "mechanical energy ∫|τ·ω|dt",
    "ω_max/ω_lim": "peak speed / limit",
    "α_max/α_lim": "peak acceleration / limit",
    "τ_max/τ_lim": "peak torque / limit",
    "theta1": "coxa angle θ1",
    "foot_x": "foot x",
    "foot_y": "foot y",
    "foot_slip": "foot slip",
    "theta2_exact": "θ2 for the exact pose",
    "theta3_exact": "θ3 for the exact pose",
}


def joint_row_name(symbol: str) -> str:
    """``readable name (symbol)`` of a per-joint table row (the symbol alone when unknown)."""
    name = JOINT_ROW_NAMES.get(symbol)
    return f"{name} ({symbol})" if name and name != symbol else symbol


@dataclass(frozen=True)
class StudyDisplay:
    """What a study's one-block summary shows.

    ``task``: what the optimiser chooses; ``start``: the baseline shown as the starting point
    (the solution the optimum improves on); ``headline``: the metric keys shown after the
    objectives, in order.
    """

    task: str
    start: str | None
    headline: tuple[str, ...]


STUDY_DISPLAY: dict[str, StudyDisplay] = {
    "swing_energy": StudyDisplay(
        "the swing trajectory of one leg (joint via points)",
        "calderon2008_parabolic",
        ("energy_total", "theta_total", "path_length"),
    ),
    "path_placement": StudyDisplay(
        "where the welding path sits in front of the arm (R, γ, φ)",
        "original",
        ("energy_J", "mean_manipulability", "time_s"),
    ),
    "hexapod_workspace": StudyDisplay(
        "the coxa angles θ1 of the three stance legs",
        "start",
        ("foot_slip_max", "stable"),
    ),
    "quadruped_gait": StudyDisplay(
        "step length, step height and duty factor of the walk",
        "default_step",
        ("step_length_m", "step_height_m", "duty", "min_stability_margin_m"),
    ),
    "path_tracking": StudyDisplay(
        "the speed of each path segment and the ramp times",
        "seed",
        ("time", "energy"),
    ),
}


def metric_name(key: str, kind: str | None = None) -> MetricName:
    """The display name of ``key`` (a study ``kind``'s own entry first, then shared ones)."""
    own = METRICS.get(kind or "", {})
    if key in own:
        return own[key]
    if key in _COMMON:
        return _COMMON[key]
    for k, pattern, label, unit in _PATTERNS:
        if kind in (None, k):
            m = pattern.match(key)
            if m:
                return MetricName(label.format(*m.groups()), unit)
    for suffix, unit in _SUFFIXES:
        if key.endswith(suffix) and len(key) > len(suffix):
            return MetricName(key[: -len(suffix)].replace("_", " "), unit)
    return MetricName(key.replace("_", " ") if len(key) > 3 else key)


def baseline_name(name: str) -> str:
    """Readable label of a baseline (its name when unknown)."""
    return BASELINE_NAMES.get(name, name.replace("_", " "))


def display_objective(name: str, value: float | None) -> tuple[str, float | None]:
    """``(shown key, shown value)`` of a minimised objective: ``neg_<m>`` becomes ``<m>`` with
    the sign flipped (a maximised quantity is shown positive); others are unchanged."""
    if name.startswith(NEGATED_PREFIX):
        return name[len(NEGATED_PREFIX) :], None if value is None else -value
    return name, value
