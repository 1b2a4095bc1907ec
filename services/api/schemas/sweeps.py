"""Sweeps: what ``POST /sweeps`` takes (a base spec fanned out over a grid, a list and seeds),
and a sweep with its counts, axes and the table of its jobs."""

from __future__ import annotations

from datetime import datetime
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, JsonValue, StrictInt, with_config
from typing_extensions import TypedDict

from services.api.schemas.common import (
    STORED_DOC,
    BestObjective,
    JobSpecDoc,
    JobSpecOut,
    Page,
    _In,
)
from services.api.verdict_schemas import FEASIBLE_DESCRIPTION
from services.store.records import SweepRecord
from services.store.states import JobStatus

_SWEEP_EXAMPLE: dict[str, JsonValue] = {
    "base": {"problem": {"kind": "swing_energy"}, "optimizer": {"kind": "ga"}},
    "grid": {"optimizer.params.mutation_rate": [0.01, 0.03]},
    "seeds": [1, 2, 3],
}

#: A swept path's value: whatever JSON the spec takes at that path (a number, a name, a list,
#: a robot document), so any JSON.
SweptValue = JsonValue


class SweepCreate(_In):
    """A base job spec fanned out over a grid, a list of override sets and seeds.

    Jobs = grid points × list entries × seeds. Keys of ``grid`` and of each ``list`` entry are
    dotted paths into the spec (``optimizer.params.mutation_rate``, ``problem.weights.0``,
    ``seed``, ``robot.joints.1.mass`` for inline or stored robots).
    """

    model_config = ConfigDict(
        extra="forbid",
        populate_by_name=True,
        json_schema_extra={"examples": [_SWEEP_EXAMPLE]},
    )

    base: JobSpecDoc
    grid: dict[str, list[Any]] = Field(default_factory=dict, description="path -> values")
    entries: list[dict[str, Any]] = Field(
        default_factory=list, alias="list", description="Explicit override sets (path -> value)."
    )
    seeds: list[StrictInt] = Field(default_factory=list, description="Each point once per seed.")


@with_config(STORED_DOC)
class SweepAxes(TypedDict, total=False):
    """What a sweep was fanned out over, as ``POST /sweeps`` received it."""

    grid: Annotated[dict[str, list[SweptValue]], Field(description="path -> values")]
    list: Annotated[
        list[dict[str, SweptValue]], Field(description="Explicit override sets (path -> value).")
    ]
    seeds: list[int]
    n_jobs: Annotated[int, Field(description="Jobs the sweep expanded to.")]


SweepState = Literal["empty", "queued", "running", "finished"]


def sweep_state(counts: dict[JobStatus, int]) -> SweepState:
    """``finished`` when every job is terminal, ``running`` when any started, else ``queued``."""
    total = sum(counts.values())
    if total == 0:
        return "empty"
    done = sum(n for s, n in counts.items() if s.is_terminal)
    if done == total:
        return "finished"
    if counts.get(JobStatus.RUNNING, 0) or done:
        return "running"
    return "queued"


class SweepSummary(BaseModel):
    """A sweep with its job counts per status."""

    id: str
    created_at: datetime
    n_jobs: int
    state: SweepState
    counts: dict[JobStatus, int]

    @classmethod
    def from_record(cls, sweep: SweepRecord, counts: dict[JobStatus, int]) -> SweepSummary:
        return cls(
            id=sweep.id,
            created_at=sweep.created_at,
            n_jobs=sum(counts.values()),
            state=sweep_state(counts),
            counts={s: counts.get(s, 0) for s in JobStatus},
        )


class SweepCreated(SweepSummary):
    """The answer to ``POST /sweeps``: the sweep and the ids of its queued jobs, in order."""

    job_ids: list[str]


class SweepRow(BaseModel):
    """One job of a sweep's table."""

    job_id: str
    status: JobStatus
    overrides: dict[str, SweptValue] = Field(description="Value of every swept path in this job.")
    progress: float
    best_objective: BestObjective = None
    objectives: dict[str, float | None] | None = Field(
        default=None, description="Final objectives (succeeded jobs)."
    )
    metrics: dict[str, float | None] | None = Field(
        default=None, description="Final key metrics (succeeded jobs)."
    )
    feasible: bool | None = Field(default=None, description=FEASIBLE_DESCRIPTION)
    error: str | None = None


class SweepOut(SweepSummary):
    """A sweep: base spec, axes, counts and the table of its jobs (paginated)."""

    base: JobSpecOut = Field(description="The base spec (robot references resolved).")
    axes: SweepAxes = Field(description="What the base was fanned out over.")
    columns: list[str] = Field(description="The swept paths (keys of each row's overrides).")
    objective_names: list[str]
    table: Page[SweepRow]
