"""The seed papers' own numbers, printed beside ours (``examples/papers/paper_numbers.yaml``).

Each entry of the YAML file names the paper (``source``), which jobs it applies to (``match``:
dotted spec paths and their values), the baseline of ours that plays the paper's starting
solution (``start``) and rows: our metric key, the paper's values at its start and optimum in
our unit, its symbol and a note where the formulas differ.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import yaml

__all__ = ["PAPER_NUMBERS", "PaperEntry", "PaperRow", "dotted", "paper_entry"]

PAPER_NUMBERS = Path(__file__).resolve().parents[1] / "examples" / "papers" / "paper_numbers.yaml"


@dataclass(frozen=True)
class PaperRow:
    """One number of the paper beside ours: our ``metric`` key, the paper's values at the
    start and at its optimum (our units; None when not printed), its symbol and a note."""

    metric: str
    start: float | None = None
    optimum: float | None = None
    paper: str = ""
    note: str = ""
    at_optimum: bool = False

    def symbol(self, kind: str | None) -> str:
        """The paper's name for the quantity: the row's own, else the metric's (its
        ``legcore.studies.metric_names`` entry for the study ``kind``); '' when it has none."""
        from legcore.studies.metric_names import metric_name

        return self.paper or metric_name(self.metric, kind).paper


@dataclass(frozen=True)
class PaperEntry:
    """The paper's numbers for the jobs whose spec matches ``match`` (dotted path → value)."""

    source: str
    match: dict[str, Any]
    rows: tuple[PaperRow, ...] = ()
    start: str | None = None
    note: str = ""

    def matches(self, spec: dict[str, Any]) -> bool:
        """Every path has its value: equal, one of a list, or any but null/false for "*"."""
        for path, want in self.match.items():
            got = dotted(spec, path)
            if want == "*":
                if got is None or got is False:
                    return False
            elif isinstance(want, list):
                if got not in want:
                    return False
            elif got != want:
                return False
        return True


def dotted(doc: Any, path: str) -> Any:
    """The value at a dotted path (``problem.kind``) of a nested dict, or None."""
    for part in path.split("."):
        if not isinstance(doc, dict) or part not in doc:
            return None
        doc = doc[part]
    return doc


@cache
def _paper_entries() -> tuple[PaperEntry, ...]:
    if not PAPER_NUMBERS.exists():
        return ()
    out = []
    for e in yaml.safe_load(PAPER_NUMBERS.read_text()) or []:
        rows = tuple(PaperRow(**r) for r in e.get("rows", []))
        out.append(PaperEntry(e["source"], dict(e["match"]), rows, e.get("start"),
                              e.get("note", "")))  # fmt: skip
    return tuple(out)


def paper_entry(spec: dict[str, Any] | None) -> PaperEntry | None:
    """The first entry of ``examples/papers/paper_numbers.yaml`` the spec matches."""
    if not isinstance(spec, dict):
        return None
    return next((e for e in _paper_entries() if e.matches(spec)), None)
