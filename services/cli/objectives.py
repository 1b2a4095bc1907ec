"""A job's objective names as the CLI reads them (stored facts first; a study built here only
for a job stored before submissions kept them) and the progress line's best-so-far."""

from __future__ import annotations

from functools import cache
from typing import Any

from legcore.studies.metric_names import display_objective
from services.cli.result_view import fmt
from services.paper_numbers import dotted

__all__ = ["best_text", "objective_names_for", "objective_names_of"]


def objective_names_of(job: dict[str, Any]) -> list[str] | None:
    """The objective names of a job as the API answers it: from what its submission stored
    (``facts``); for a job stored before that, from its spec or its study kind (which builds
    the study here)."""
    facts = job.get("facts")
    if isinstance(facts, dict) and isinstance(facts.get("objectives"), list):
        return [str(n) for n in facts["objectives"]]
    spec = job.get("spec")
    return objective_names_for(spec if isinstance(spec, dict) else job.get("kind"))


def objective_names_for(spec: dict[str, Any] | str | None) -> list[str] | None:
    """The objective names of a job spec (or of a study kind's defaults), from the study itself
    (cached; None when the spec cannot be built here, e.g. it names a stored robot)."""
    if isinstance(spec, str):
        return _kind_objectives(spec)
    if not isinstance(spec, dict):
        return None
    try:
        from legcore.runner import prepare

        return list(prepare(spec).problem.objective_names)
    except Exception:
        kind = dotted(spec, "problem.kind")
        return _kind_objectives(kind) if isinstance(kind, str) else None


@cache
def _kind_objectives(kind: str) -> list[str] | None:
    try:
        from legcore.runner import prepare

        return list(prepare({"problem": {"kind": kind}}).problem.objective_names)
    except Exception:
        return None


def best_text(names: list[str] | None, best: Any) -> str:
    """The progress line's best-so-far: ``score 9.681`` (maximised shown positive)."""
    if best is None:
        return ""
    values = best if isinstance(best, list) else [best]
    if not names or len(names) != len(values):
        return "best " + ", ".join(fmt(v) for v in values)
    parts = []
    for n, v in zip(names, values, strict=True):
        key, shown = display_objective(n, v)
        parts.append(f"{key} {fmt(shown)}")
    return ", ".join(parts)
