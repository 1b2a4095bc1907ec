"""A job's verdict in words: whether its reported optimum is feasible and what it violates.

A succeeded job carries ``feasible`` (True, False, or None when it was not checked) and its
``violations``: ``[{"constraint", "amount", "unit", "text"}, ...]``
(``legcore.studies.task.Violation.as_dict``). The CLI, the exports and the API's readers all
word them with :func:`violation_text`, so a violation reads the same everywhere.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

__all__ = ["Verdict", "verdict_word", "violation_text", "violations_text"]


@dataclass(frozen=True)
class Verdict:
    """Whether a solution meets every constraint (None: not checked) and what it violates
    (``[{"constraint", "amount", "unit", "text"}, ...]``)."""

    feasible: bool | None = None
    violations: tuple[dict[str, Any], ...] = ()

    @classmethod
    def of(cls, doc: Any, feasible: Any = None, violations: Any = None) -> Verdict:
        """From a solution summary (its ``feasible`` and ``violations``, as result.json and the
        stored baselines have them), else from the values given."""
        if isinstance(doc, dict):
            feasible = doc.get("feasible", feasible)
            violations = doc.get("violations", violations)
        flag = feasible if isinstance(feasible, bool) else None
        rows = tuple(v for v in violations if isinstance(v, dict)) \
            if isinstance(violations, list) else ()  # fmt: skip
        return cls(flag, rows)


def _number(v: float) -> str:
    """4 significant digits (as ``services.cli.result_view.fmt``)."""
    if not math.isfinite(v):
        return "—"
    return "0" if v == 0 else f"{v:.4g}"


def violation_text(v: Mapping[str, Any]) -> str:
    """One violation with its amount and unit: ``stability_margin over its limit by 0.02 m``,
    then the study's own words when it gave any (``… — peak joint speed 12 % over its limit``).
    """
    name = str(v.get("constraint") or "constraint")
    amount = v.get("amount")
    unit = str(v.get("unit") or "")
    size = "?"
    if isinstance(amount, int | float) and not isinstance(amount, bool):
        size = _number(float(amount)) + (f" {unit}" if unit else "")
    out = f"{name} over its limit by {size}"
    text = str(v.get("text") or "").strip()
    if text:  # the study's own words
        out += f" — {text}"
    return out


def violations_text(violations: Iterable[Mapping[str, Any]] | None, sep: str = "; ") -> str:
    """Every violation by :func:`violation_text`, joined by ``sep`` ('' for none)."""
    return sep.join(violation_text(v) for v in violations or () if isinstance(v, Mapping))


def verdict_word(feasible: bool | None) -> str:
    """``feasible`` / ``infeasible`` / ``not checked``."""
    if feasible is None:
        return "not checked"
    return "feasible" if feasible else "infeasible"
