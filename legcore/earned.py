"""What the optimiser earned: the optimum beside where the search started.

A headline "−99.5 % energy" means little if the encoding's zero already scores that well.
Every result therefore carries

- ``initial``: the best of the first generation (the initial population) — what random or
  seeded initialisation gave before any selection or variation;
- ``free``: the solution the problem's encoding gives with no search at all
  (`StudyProblem.free_start`, e.g. the coordinated motion of all-zero deviation genes), when
  the study has one;
- per objective (minimised, as the optimiser sees them) the optimum, both starts and the change
  from each: ``earned_pct`` is the optimiser's own improvement over its initial population,
  ``earned_over_free_pct`` over the free solution (≤ 0 when the search added nothing).

Pure: takes decoded solutions, returns JSON-able dicts.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["earned_summary", "change_pct"]


def change_pct(start: float, end: float) -> float | None:
    """Relative improvement (%) of a minimised value from ``start`` to ``end``: positive when
    ``end`` is lower. ``None`` when undefined (non-finite or a zero start)."""
    if not (math.isfinite(start) and math.isfinite(end)) or start == 0.0:
        return None
    return 100.0 * (start - end) / abs(start)


def earned_summary(
    objective_names: tuple[str, ...],
    optimum_f: np.ndarray,
    optimum_cv: float,
    initial: tuple[np.ndarray, float] | None,
    free: tuple[str, np.ndarray, float] | None,
) -> dict[str, Any]:
    """The ``start`` block of a result.

    Args:
        objective_names: the minimised objectives' names (F's columns).
        optimum_f: (n_obj,) the optimum's objectives; ``optimum_cv`` its constraint violation.
        initial: ``(f, cv)`` of the initial population's best, or None (unknown).
        free: ``(what, f, cv)`` of the encoding's free solution, or None.
    """
    rows = []
    for j, name in enumerate(objective_names):
        row: dict[str, Any] = {"objective": name, "optimum": float(optimum_f[j])}
        if initial is not None:
            row["initial"] = float(initial[0][j])
            row["earned_pct"] = change_pct(float(initial[0][j]), float(optimum_f[j]))
        if free is not None:
            row["free"] = float(free[1][j])
            row["earned_over_free_pct"] = change_pct(float(free[1][j]), float(optimum_f[j]))
        rows.append(row)
    out: dict[str, Any] = {
        "objectives": rows,
        "optimum_cv": float(optimum_cv),
        "initial": None if initial is None else {
            "what": "best of the initial population", "cv": float(initial[1])},
        "free": None if free is None else {"what": free[0], "cv": float(free[2])},
    }
    out["verdict"] = _verdict(rows, initial, free, optimum_cv)
    return out


def _verdict(
    rows: list[dict[str, Any]],
    initial: tuple[np.ndarray, float] | None,
    free: tuple[str, np.ndarray, float] | None,
    optimum_cv: float,
) -> str:
    """One sentence: what the search added (first objective for a single-objective problem)."""
    if len(rows) != 1:
        return "multi-objective: compare the fronts (hypervolume per generation)"
    r = rows[0]
    parts = []
    if initial is not None and r.get("earned_pct") is not None:
        feas = "" if initial[1] <= 0 or optimum_cv > 0 else " (and made it feasible)"
        parts.append(f"{r['earned_pct']:+.3g} % over the initial population's best{feas}")
    if free is not None and free[2] > 0 and optimum_cv <= 0:
        parts.append(f"{free[0]} (no search) violates the constraints (by {free[2]:.3g})")
    elif free is not None and r.get("earned_over_free_pct") is not None:
        pct = r["earned_over_free_pct"]
        if abs(pct) < 1e-6 and free[2] <= 0:
            parts.append(f"nothing over {free[0]}, which the encoding gives without search")
        else:
            parts.append(f"{pct:+.3g} % over {free[0]} (no search)")
    return "; ".join(parts) if parts else "no start point recorded"
