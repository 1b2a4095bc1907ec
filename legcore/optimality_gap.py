"""How far a result is from the best its problem allows: the optimality gap.

A study may know, for its single objective, a value no answer can beat — an exact solution of
the same problem (``path_tracking``'s cycle time: TOPP-RA's time-optimal profile under the
same limits, the *physical minimum*) — through ``StudyProblem.reference_optimum()``. Where it
knows none, a run with ``optimizer.refine`` has a best-known point: the optimiser's optimum
polished by a gradient method (:func:`refined_reference`), and the gap says how far the
optimiser ended from it. Every single-objective result then says how far it is; every other
result says why it has no gap. Pure: takes the problem's reference and the optimum's
objectives, returns a JSON-able dict (``result.json``'s ``gap``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from legcore.studies.metric_names import display_objective

__all__ = ["NO_REFERENCE", "optimality_gap", "refined_reference"]

#: Why a single-objective result of a study without a reference has no gap.
NO_REFERENCE = ("no exact solution to compare with; optimizer.refine: true gives a "
                "best-known point")


def refined_reference(objective_names: tuple[str, ...], refine: Mapping[str, Any] | None
                      ) -> dict[str, Any] | None:
    """A best-known reference from ``optimizer.refine`` (its record: ``before``/``after`` the
    minimised F, ``improved``, ``n_evals``): the optimiser's own optimum polished by SLSQP. The
    gap it gives is the *optimiser's* end point's (``value``: before refinement) to that polish;
    None without a refinement that improved a feasible point (or with several objectives)."""
    if len(objective_names) != 1 or not refine or not refine.get("improved"):
        return None
    after, before = refine.get("after"), refine.get("before")
    if not isinstance(after, int | float) or not isinstance(before, int | float):
        return None
    if float(refine.get("cv_after") or 0.0) > 0.0:
        return None
    key, shown_after = display_objective(objective_names[0], float(after))
    _, shown_before = display_objective(objective_names[0], float(before))
    return {"objective": key, "value": shown_after, "optimiser_value": shown_before,
            "sense": "min" if key == objective_names[0] else "max",
            "kind": "best known (the optimiser's optimum refined by SLSQP)",
            "method": f"{int(refine.get('n_evals') or 0)} more evaluations; the gap is the "
                      "optimiser's own end point's"}


def optimality_gap(objective_names: tuple[str, ...], objectives: Mapping[str, float],
                   reference: Mapping[str, Any] | None) -> dict[str, Any]:
    """The gap of an optimum (``objectives``: shown name → value in the objective's own units;
    a minimised ``neg_<m>`` is shown as ``<m>``, positive) to
    the problem's ``reference`` (``{"objective", "value", "kind", "method"[, "sense",
    "optimiser_value"]}``, a minimised objective unless ``sense`` is ``"max"``; with
    ``optimiser_value`` — :func:`refined_reference` — the gap is that value's):
    ``{"objective", "value", "reference", "kind", "method", "pct"}`` with ``pct`` =
    100 (value − reference) / |reference| for a minimised objective (≥ 0 unless the optimum
    beats the reference); without a reference (or with several objectives)
    ``{"reference": None, "reason": …}``."""
    if len(objective_names) != 1:
        return {"reference": None,
                "reason": "several objectives: a front has no single gap (its fastest or "
                          "cheapest point is compared with the baselines)"}
    name, _ = display_objective(objective_names[0], None)  # neg_<m> is shown as <m>
    if reference is None or reference.get("objective") not in (name, objective_names[0]):
        return {"objective": name, "reference": None, "reason": NO_REFERENCE}
    shown = objectives.get(name, objectives.get(objective_names[0], math.nan))
    value, ref = float(reference.get("optimiser_value", shown)), float(reference["value"])
    sign = -1.0 if reference.get("sense") == "max" else 1.0
    pct = (100.0 * sign * (value - ref) / abs(ref)
           if math.isfinite(value) and math.isfinite(ref) and ref != 0.0 else None)
    return {"objective": name, "value": value, "reference": ref,
            "kind": str(reference.get("kind", "reference")),
            "method": str(reference.get("method", "")), "pct": pct}
