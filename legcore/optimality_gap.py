"""How far a result is from the best its problem allows: the optimality gap.

A study may know, for its single objective, a value no answer can beat — an exact solution of
the same problem (``path_tracking``'s cycle time: TOPP-RA's time-optimal profile under the
same limits, the *physical minimum*) — through ``StudyProblem.reference_optimum()``. Every
single-objective result then says how far its optimum is from it; every other result says why
it has no gap. Pure: takes the problem's reference and the optimum's objectives, returns a
JSON-able dict (``result.json``'s ``gap``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

__all__ = ["NO_REFERENCE", "optimality_gap"]

#: Why a single-objective result of a study without a reference has no gap.
NO_REFERENCE = ("no exact or gradient solution of this problem to compare with "
                "(optimizer.refine polishes the optimum with a gradient method)")


def optimality_gap(objective_names: tuple[str, ...], objectives: Mapping[str, float],
                   reference: Mapping[str, Any] | None) -> dict[str, Any]:
    """The gap of an optimum (``objectives``: name → value in the objective's own units) to
    the problem's ``reference`` (``{"objective", "value", "kind", "method"[, "sense"]}``, a
    minimised objective unless ``sense`` is ``"max"``): ``{"objective", "value",
    "reference", "kind", "method", "pct"}`` with ``pct`` = 100 (value − reference) / |reference|
    for a minimised objective (≥ 0 unless the optimum beats the reference); without a
    reference (or with several objectives) ``{"reference": None, "reason": …}``."""
    if len(objective_names) != 1:
        return {"reference": None,
                "reason": "several objectives: a front has no single gap (its fastest or "
                          "cheapest point is compared with the baselines)"}
    name = objective_names[0]
    if reference is None or reference.get("objective") != name:
        return {"objective": name, "reference": None, "reason": NO_REFERENCE}
    value, ref = float(objectives[name]), float(reference["value"])
    sign = -1.0 if reference.get("sense") == "max" else 1.0
    pct = (100.0 * sign * (value - ref) / abs(ref)
           if math.isfinite(value) and math.isfinite(ref) and ref != 0.0 else None)
    return {"objective": name, "value": value, "reference": ref,
            "kind": str(reference.get("kind", "reference")),
            "method": str(reference.get("method", "")), "pct": pct}
