"""The result of a succeeded job: its optimum (decision vector, objectives, metrics, the rest
of its summary), its verdict and task, the baselines it is compared with and its files."""

from __future__ import annotations

from datetime import datetime
from typing import Any

from pydantic import BaseModel, Field

from services.api.schemas.result_docs import ObjectivesDoc, ResultSummary, SolutionDoc
from services.api.verdict_schemas import (
    FEASIBLE_DESCRIPTION,
    VIOLATIONS_DESCRIPTION,
    GapOut,
    TaskOut,
    ViolationOut,
    feasible_of,
    violations_out,
)
from services.store.records import (
    ArtifactRecord,
    BaselineRecord,
    JobRecord,
    ResultRecord,
)


class BaselineOut(BaseModel):
    """A baseline solution of the study (the seed paper's references) and its metrics."""

    name: str
    metrics: SolutionDoc = Field(
        description="The decoded solution as stored: {x, objectives, metrics, table, extra, "
        "feasible, violations}."
    )
    feasible: bool | None = Field(
        default=None,
        description="Whether this baseline meets every constraint on the job's robot (null: "
        "not checked). A change in % is computed against it only when it is feasible.",
    )
    violations: list[ViolationOut] = Field(
        default_factory=list, description="What this baseline violates."
    )

    @classmethod
    def from_record(cls, b: BaselineRecord) -> BaselineOut:
        doc = b.metrics if isinstance(b.metrics, dict) else {}
        return cls(name=b.name, metrics=b.metrics, feasible=feasible_of(doc),
                   violations=violations_out(doc.get("violations")))  # fmt: skip


class ArtifactOut(BaseModel):
    """A file stored with a job's result (``recording``: the Rerun ``.rrd``)."""

    kind: str
    size_bytes: int
    sha256: str
    created_at: datetime

    @classmethod
    def from_record(cls, a: ArtifactRecord) -> ArtifactOut:
        return cls(kind=a.kind, size_bytes=a.size_bytes, sha256=a.sha256, created_at=a.created_at)


def objective_names(result: ResultRecord | dict[str, Any] | None) -> list[str]:
    """Objective names stored with a result (``objectives = {"names": [...], ...}``); takes
    the result record or just its ``objectives`` JSON."""
    objectives = result.objectives if isinstance(result, ResultRecord) else result
    if not isinstance(objectives, dict):
        return []
    names = objectives.get("names")
    return [str(n) for n in names] if isinstance(names, list) else []


class ResultOut(BaseModel):
    """The final result of a succeeded job, with its verdict and the task it ran."""

    job_id: str
    feasible: bool | None = Field(default=None, description=FEASIBLE_DESCRIPTION)
    violations: list[ViolationOut] = Field(default_factory=list, description=VIOLATIONS_DESCRIPTION)
    task: TaskOut | None = Field(
        default=None,
        description="The study parameters the job ran with on its robot and the rule behind "
        "each derived value (null for jobs stored before tasks were recorded).",
    )
    gap: GapOut | None = Field(
        default=None,
        description="How far the optimum is from the best the problem allows (single "
        "objective; null for jobs stored before gaps were recorded).",
    )
    objective_names: list[str]
    objectives: ObjectivesDoc | None = Field(
        description="Objectives of the best solution as stored by the worker: "
        '{"names": [...], "values": {name: value}}.'
    )
    best_x: list[float | None] | None = Field(description="Decision vector of the best solution.")
    metrics: dict[str, float | None] | None = Field(
        description="Key metrics of the best solution (energy J, ...)."
    )
    summary: ResultSummary | None = Field(
        description="Per-joint table, study extras, optimizer info, history."
    )
    baselines: list[BaselineOut]
    artifacts: list[ArtifactOut]
    created_at: datetime

    @classmethod
    def from_records(
        cls,
        result: ResultRecord,
        baselines: tuple[BaselineRecord, ...],
        artifacts: tuple[ArtifactRecord, ...],
        job: JobRecord | None = None,
    ) -> ResultOut:
        """``job``: the job the result is of (its verdict; without it: not checked)."""
        summary = result.summary if isinstance(result.summary, dict) else {}
        return cls(
            job_id=result.job_id,
            feasible=None if job is None else job.feasible,
            violations=[] if job is None else violations_out(job.violations),
            task=TaskOut.from_doc(summary.get("task")),
            gap=GapOut.from_doc(summary.get("gap")),
            objective_names=objective_names(result),
            objectives=result.objectives,
            best_x=result.best_x,
            metrics=result.metrics,
            summary=result.summary,
            baselines=[BaselineOut.from_record(b) for b in baselines],
            artifacts=[ArtifactOut.from_record(a) for a in artifacts],
            created_at=result.created_at,
        )
