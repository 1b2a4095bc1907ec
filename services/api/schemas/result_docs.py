"""The documents a worker stores with a result, typed as they are stored and passed on.

A result's ``objectives``, its ``summary`` (the optimum's per-joint table and extras, the
optimiser's run, what the search earned, the history, the task and the gap) and each
baseline's decoded solution are written once by the worker
(``services.worker.execute._store_attempt`` from ``legcore.runner.RunResult.to_dict``) and read
back as JSON. They are ``TypedDict`` s (:data:`STORED_DOC`) so that a response carries exactly
the keys stored: an older row without a newer key is passed on without it, and a key a study
adds (a plug-in's) is passed on too. Numbers are ``float | None``: the worker writes every
non-finite value as null.

Where a value's shape belongs to a study or an optimiser (a study's ``extra`` and ``extras``,
an optimiser's ``params``, a study's task parameters), it is ``JsonValue``: any JSON, its keys
documented by that study or optimiser (``GET /studies``), not by the API.
"""

from __future__ import annotations

from typing import Annotated, Required

from pydantic import Field, JsonValue, with_config
from typing_extensions import TypedDict

from services.api.schemas.common import STORED_DOC

__all__ = [
    "EarnedRow",
    "EarnedStart",
    "GapDoc",
    "HistoryRow",
    "ObjectivesDoc",
    "OptimizerRun",
    "RefineDoc",
    "ResultSummary",
    "SolutionDoc",
    "StartPoint",
    "TableRow",
    "TaskDoc",
    "ViolationDoc",
]

_EXTRA = "The study's own outputs of this solution (servo table, workspace, ...): any JSON."


@with_config(STORED_DOC)
class ObjectivesDoc(TypedDict):
    """The objectives of a result's optimum: their names (minimised, in the front's column
    order) and the optimum's value of each, as the study states it."""

    names: list[str]
    values: dict[str, float | None]


@with_config(STORED_DOC)
class TableRow(TypedDict, total=False):
    """One row of a solution's per-joint table (``legcore`` ``Solution.table``): a value per
    joint (``values``) or one for the whole robot (``total``)."""

    metric: Required[str]
    key: str
    unit: str
    values: list[float | None]
    total: float | None


@with_config(STORED_DOC)
class ViolationDoc(TypedDict, total=False):
    """A violated constraint as stored with a solution (``legcore`` ``Violation.as_dict``)."""

    constraint: str
    amount: float | None
    unit: str
    text: str


@with_config(STORED_DOC)
class SolutionDoc(TypedDict, total=False):
    """A decoded solution as stored (``legcore`` ``Solution.summary``): decision vector,
    objectives, metrics (SI, flags as 0/1), per-joint table, the study's extra outputs, and,
    when it was checked, whether it is feasible and what it violates."""

    x: list[float | None] | None
    objectives: dict[str, float | None]
    metrics: dict[str, float | None]
    table: list[TableRow]
    extra: Annotated[dict[str, JsonValue], Field(description=_EXTRA)]
    feasible: bool
    violations: list[ViolationDoc]


@with_config(STORED_DOC)
class RefineDoc(TypedDict, total=False):
    """The local refinement of the optimum (``optimizer.refine`` of a spec;
    ``legcore.optimizers.refine.RefineResult.summary``)."""

    before: float | None
    after: float | None
    cv_before: float | None
    cv_after: float | None
    relaxed: float | None
    n_evals: int
    elapsed_s: float | None
    success: bool
    improved: bool
    skipped: bool
    message: str


@with_config(STORED_DOC)
class OptimizerRun(TypedDict, total=False):
    """What the optimiser did: its kind and parameters, generations, evaluations, wall time,
    why it stopped, whether its optimum is feasible, and the refinement when asked for."""

    kind: str
    params: Annotated[
        dict[str, JsonValue],
        Field(description="The optimiser's own parameters (its kind's; any JSON)."),
    ]
    n_gen: int
    n_evals: int
    elapsed_s: float | None
    reason: str
    feasible: bool
    refine: RefineDoc


@with_config(STORED_DOC)
class EarnedRow(TypedDict, total=False):
    """One objective: the optimum, the initial population's best and the no-search solution,
    and what the optimiser earned over each in % (``legcore.earned``)."""

    objective: Required[str]
    optimum: Required[float | None]
    initial: float | None
    earned_pct: float | None
    free: float | None
    earned_over_free_pct: float | None


@with_config(STORED_DOC)
class StartPoint(TypedDict):
    """A start the optimum is compared with: what it is, and its constraint violation."""

    what: str
    cv: float | None


@with_config(STORED_DOC)
class EarnedStart(TypedDict, total=False):
    """Where the search started and what it earned (``legcore.earned.earned_summary``)."""

    objectives: list[EarnedRow]
    optimum_cv: float | None
    initial: StartPoint | None
    free: StartPoint | None
    verdict: str


@with_config(STORED_DOC)
class HistoryRow(TypedDict, total=False):
    """One generation of the optimiser's own history (``legcore`` ``GenerationRecord``)."""

    generation: int
    n_evals: int
    elapsed: float | None
    best_f: list[float | None]
    best_cv: float | None
    front_size: int
    ideal: list[float | None]
    nadir: list[float | None]


@with_config(STORED_DOC)
class TaskDoc(TypedDict, total=False):
    """The task as stored (``legcore`` ``Task.as_dict``; ``ResultOut.task`` reads it)."""

    params: Annotated[
        dict[str, JsonValue],
        Field(description="The study's parameters (`GET /studies`: `params_schema` of its kind)."),
    ]
    rules: dict[str, str]
    preset: str | None


@with_config(STORED_DOC)
class GapDoc(TypedDict, total=False):
    """The gap as stored (``legcore.optimality_gap``; ``ResultOut.gap`` reads it)."""

    objective: str | None
    value: float | None
    reference: float | None
    kind: str
    method: str
    pct: float | None
    reason: str


@with_config(STORED_DOC)
class ResultSummary(TypedDict, total=False):
    """The rest of a result: the optimum's per-joint table and extra outputs, the study's
    extras, the optimiser's run, what it earned (``start``), its history, the task, the gap
    and the optimum's place on the front (null when not on it, e.g. refined)."""

    table: list[TableRow]
    extra: Annotated[dict[str, JsonValue], Field(description=_EXTRA)]
    optimizer: OptimizerRun
    start: EarnedStart | None
    history: list[HistoryRow]
    task: TaskDoc | None
    gap: GapDoc | None
    best_index: int | None
    extras: Annotated[
        dict[str, JsonValue],
        Field(
            description="The study's outputs computed from the final front (workspaces, masks, "
            "the hexapod's stable/unstable split): any JSON, the study's own."
        ),
    ]
    extras_warning: Annotated[
        str, Field(description="Why `extras` is empty: the file holding them is unavailable.")
    ]
