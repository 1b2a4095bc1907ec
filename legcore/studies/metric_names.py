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

import importlib
import re

from legcore.studies.naming import MetricName, StudyDisplay

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

M = MetricName

#: Prefix of an objective that is the negation of a maximised quantity.
NEGATED_PREFIX = "neg_"

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

#: The study packages whose ``metrics.py`` name their keys (plug-ins' keys get generic names).
_STUDY_KINDS = ("swing_energy", "path_placement", "hexapod_workspace", "quadruped_gait",
                "path_tracking")


def _load() -> tuple[dict[str, dict[str, MetricName]],
                     tuple[tuple[str, re.Pattern[str], str, str], ...],
                     dict[str, str], dict[str, StudyDisplay]]:
    metrics, patterns, baselines, display = {}, [], {}, {}
    for kind in _STUDY_KINDS:
        mod = importlib.import_module(f"legcore.studies.{kind}.metrics")
        metrics[kind] = dict(mod.METRICS)
        patterns += [(kind, rx, label, unit) for rx, label, unit in mod.PATTERNS]
        baselines.update(mod.BASELINES)
        display[kind] = mod.DISPLAY
    return metrics, tuple(patterns), baselines, display


#: kind -> key -> name (each study's ``metrics.py``). Objective keys appear under their
#: displayed name (``score``, not ``neg_score``).
METRICS: dict[str, dict[str, MetricName]]
#: Key patterns (kind, regex, label template with the groups, unit).
_PATTERNS: tuple[tuple[str, re.Pattern[str], str, str], ...]
#: Baseline names → readable labels.
BASELINE_NAMES: dict[str, str]
#: kind → what its one-block summary shows.
STUDY_DISPLAY: dict[str, StudyDisplay]
METRICS, _PATTERNS, BASELINE_NAMES, STUDY_DISPLAY = _load()

#: Unit suffixes of keys no table names (longest first): suffix -> unit.
_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_J_per_m", "J/m"), ("_rad_s", "rad/s"), ("_m_s", "m/s"), ("_kWh", "kWh"),
    ("_pct", "%"), ("_Nm", "N·m"), ("_rad", "rad"), ("_deg", "°"), ("_kg", "kg"),
    ("_J", "J"), ("_W", "W"), ("_N", "N"), ("_m", "m"), ("_s", "s"),
)  # fmt: skip

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
