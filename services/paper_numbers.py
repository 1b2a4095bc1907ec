"""The seed papers' own numbers, printed beside ours (``examples/papers/paper_numbers.yaml``).

Each entry of the YAML file names the paper (``source``), the paper's robot (``robot``: a
catalog name), which jobs it applies to (``match``: dotted spec paths and their values), the
baseline of ours that plays the paper's starting solution (``start``) and rows: our metric
key, the paper's values at its start and optimum in our unit, its symbol and a note where the
formulas differ.

A paper's numbers are shown only beside a job on the paper's robot with the paper's settings:
the job's ``robot`` is the entry's catalog name (or the job names none and the study's default
robot is it), its spec satisfies ``match``, and it gives no other value to a parameter the
study's paper preset sets (``legcore.studies.task.Preset``: the paper's own settings on its
robot). A job on any other robot — an inline model, a stored URDF, another catalog robot — gets
none, whatever its settings.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import yaml

__all__ = [
    "PAPER_NUMBERS",
    "PaperEntry",
    "PaperRow",
    "dotted",
    "job_robot",
    "keeps_preset",
    "paper_entry",
]

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
    """The paper's numbers for the jobs on the paper's ``robot`` (a catalog name) whose spec
    matches ``match`` (dotted path → value)."""

    source: str
    match: dict[str, Any]
    rows: tuple[PaperRow, ...] = ()
    start: str | None = None
    note: str = ""
    robot: str = ""

    def matches(self, spec: dict[str, Any], task: Any = None) -> bool:
        """The job runs on the paper's robot (:func:`job_robot`) with the paper's settings
        (:func:`keeps_preset`; ``task``: the task it ran, when known) and every path has its
        value: equal, one of a list, or any but null/false for "*"."""
        if job_robot(spec) != self.robot or not keeps_preset(spec, task):
            return False
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


def job_robot(spec: dict[str, Any]) -> str | None:
    """The catalog robot a job spec runs on: its ``robot`` when that is a catalog name, the
    study's default robot when it names none; None for an inline or stored model (never a
    paper's robot, even when it copies one: its numbers would not be the paper's)."""
    robot = spec.get("robot")
    if robot is None:
        kind = dotted(spec, "problem.kind")
        from legcore.studies.registry import studies

        study = studies().get(kind) if isinstance(kind, str) else None
        return None if study is None else study.default_robot
    if isinstance(robot, str):
        from legcore.robots import catalog

        return robot if robot in catalog.names() else None
    return None


def _same(given: Any, paper: Any) -> bool:
    """A value of the spec equals the preset's (lists and tuples alike; numbers to 1e-9)."""
    if isinstance(paper, list | tuple) and isinstance(given, list | tuple):
        return len(given) == len(paper) and all(map(_same, given, paper))
    if isinstance(paper, dict) and isinstance(given, dict):
        return given.keys() == paper.keys() and all(_same(given[k], paper[k]) for k in paper)
    numbers = (int, float)
    if isinstance(given, numbers) and isinstance(paper, numbers) \
            and not isinstance(given, bool) and not isinstance(paper, bool):  # fmt: skip
        return math.isclose(float(given), float(paper), rel_tol=1e-9, abs_tol=1e-12)
    return bool(given == paper)


def keeps_preset(spec: dict[str, Any], task: Any = None) -> bool:
    """True unless the job ran a parameter of its study's paper preset with another value than
    the paper's (a study without a preset: True). ``task``: the task the job ran (``{"params":
    {...}}``, stored with its result): its values are compared; without it, the values the spec
    gives (null: derived, i.e. the preset's on the paper's robot)."""
    from legcore.studies.registry import studies

    kind = dotted(spec, "problem.kind")
    study = studies().get(kind) if isinstance(kind, str) else None
    preset = getattr(study, "preset", None)
    ran = task.get("params") if isinstance(task, dict) else None
    values = ran if isinstance(ran, dict) else spec.get("problem")
    if preset is None or not isinstance(values, dict):
        return True
    given = {k: v for k, v in values.items() if v is not None or ran is not None}
    return all(_same(given[k], v) for k, v in preset.params.items() if k in given)


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
                              e.get("note", ""), str(e["robot"])))  # fmt: skip
    return tuple(out)


def paper_entry(spec: dict[str, Any] | None, task: Any = None) -> PaperEntry | None:
    """The first entry of ``examples/papers/paper_numbers.yaml`` the spec matches (the
    paper's robot and settings; ``task``: the task the job ran, when known), or None."""
    if not isinstance(spec, dict):
        return None
    return next((e for e in _paper_entries() if e.matches(spec, task)), None)
