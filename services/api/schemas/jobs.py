"""Jobs as the API shows them: a job with its status, progress and verdict (and its spec), its
generations, and the points of its final Pareto front."""

from __future__ import annotations

from datetime import datetime
from typing import Any

from pydantic import BaseModel, Field

from services.api.schemas.common import BestObjective, JobSpecOut, Page
from services.api.verdict_schemas import (
    FEASIBLE_DESCRIPTION,
    VIOLATIONS_DESCRIPTION,
    ViolationOut,
    violations_out,
)
from services.store.records import GenerationRecord, JobRecord, ParetoPointRecord
from services.store.sql import COUNT_CAP
from services.store.states import JobStatus


class JobFacts(BaseModel):
    """What the job is, as its validation found it at submission (stored once)."""

    kind: str = Field(description="The study kind.")
    robot: str = Field(description="The robot's name (the study's default when none given).")
    optimizer: str = Field(description="The optimizer kind (the study's default when none).")
    objectives: list[str] = Field(
        description="Objective names, in the order of best_objective and of the front's "
        "columns (all minimised)."
    )
    n_var: int = Field(description="Number of decision variables.")

    @classmethod
    def from_stored(cls, facts: Any) -> JobFacts | None:
        """The stored facts of a job, or None (a job stored before they were kept)."""
        if not isinstance(facts, dict):
            return None
        try:
            return cls.model_validate(facts)
        except ValueError:
            return None


class JobOut(BaseModel):
    """A job: status, progress, best objective so far, the verdict (``feasible``, ``violations``)
    once it succeeded, attempts, error, warnings, times."""

    id: str
    name: str | None = None
    kind: str | None = Field(default=None, description="The study kind (problem.kind).")
    status: JobStatus
    sweep_id: str | None = None
    generation: int = Field(description="Highest generation recorded so far (0: initial).")
    total_generations: int
    progress: float = Field(ge=0, le=1, description="generation / total_generations.")
    best_objective: BestObjective = Field(
        default=None,
        description="Best objective(s) so far: the latest generation's `best`.",
    )
    feasible: bool | None = Field(default=None, description=FEASIBLE_DESCRIPTION)
    violations: list[ViolationOut] = Field(default_factory=list, description=VIOLATIONS_DESCRIPTION)
    attempts: int = Field(description="Times a worker claimed the job.")
    cancel_requested: bool
    error: str | None = Field(default=None, description="Why the job failed.")
    warnings: list[str]
    created_at: datetime
    started_at: datetime | None = None
    finished_at: datetime | None = None
    facts: JobFacts | None = Field(
        default=None,
        description="What the job is (kind, robot, optimizer, objective names, n_var), as "
        "found at submission; null for jobs stored before it was kept.",
    )

    @classmethod
    def from_record(cls, job: JobRecord, spec: Any = None) -> JobOut:
        """``spec``: the job's spec (or the fields ``repository.job_labels`` gives) when the
        record holds none (a job of a sweep)."""
        spec = spec if isinstance(spec, dict) else job.spec
        spec = spec if isinstance(spec, dict) else {}
        problem = spec.get("problem")
        return cls(
            id=job.id,
            name=spec.get("name"),
            kind=problem.get("kind") if isinstance(problem, dict) else None,
            status=job.status,
            sweep_id=job.sweep_id,
            generation=job.progress_generation,
            total_generations=job.total_generations,
            progress=job.progress,
            best_objective=job.best_objective,
            feasible=job.feasible,
            violations=violations_out(job.violations),
            attempts=job.attempt_count,
            cancel_requested=job.cancel_requested,
            error=job.error_message,
            warnings=list(job.warnings),
            created_at=job.created_at,
            started_at=job.started_at,
            finished_at=job.finished_at,
            facts=JobFacts.from_stored(job.facts),
        )


class JobDetail(JobOut):
    """A job with the spec it runs (robot references resolved)."""

    spec: JobSpecOut

    @classmethod
    def from_record(cls, job: JobRecord, spec: Any = None) -> JobDetail:
        """``spec``: the job's full spec (``repository.job_spec``; default: the record's)."""
        spec = spec if spec is not None else job.spec
        return cls(**JobOut.from_record(job, spec).model_dump(), spec=spec)


class ParetoPointOut(BaseModel):
    """One point of the final Pareto front."""

    index: int
    x: list[float | None] = Field(description="Its decision vector.")
    objectives: list[float | None] = Field(
        description="Its objectives (minimised), in the order of `objective_names`."
    )

    @classmethod
    def from_record(cls, p: ParetoPointRecord) -> ParetoPointOut:
        return cls(index=p.index, x=p.x, objectives=p.objectives)


class JobPage(Page[JobOut]):
    """A page of your jobs (``GET /jobs``)."""

    total: int = Field(
        description=f"Jobs matching the filters (all pages), counted up to {COUNT_CAP + 1}: "
        f"when `total_exact` is false, more than {COUNT_CAP} match (an exact count would cost "
        "more than the page as the store grows)."
    )
    total_exact: bool = Field(
        description="True when `total` is the number of matching jobs; false when the count "
        f"stopped at {COUNT_CAP + 1} (page on while `items` is full)."
    )


class ParetoPage(Page[ParetoPointOut]):
    """A page of the Pareto front, with the objective names of the columns."""

    objective_names: list[str]


class GenerationOut(BaseModel):
    """Progress of one generation."""

    generation: int
    n_evals: int
    best: BestObjective = Field(
        description="The optimiser's reported solution's objectives: for one objective the "
        "best so far; for several the compromise (knee) point of the current front, which "
        "can get worse in any one objective — see `best_so_far`."
    )
    best_so_far: list[float | None] | None = Field(
        default=None,
        description="The least value of each objective found so far (minimised, as stored): "
        "the running minimum of `front_min` over the generations up to this one (for one "
        "objective: `best`); null before the first feasible front.",
    )
    front_min: list[float | None] | None = Field(
        default=None,
        description="The least value of each objective on this generation's front (null "
        "without a stored front: one objective, or nothing feasible yet).",
    )
    hypervolume: float | None = None
    wall_time_s: float
    created_at: datetime

    @classmethod
    def from_record(
        cls,
        g: GenerationRecord,
        *,
        best_so_far: list[float | None] | None = None,
        front_min: list[float | None] | None = None,
    ) -> GenerationOut:
        return cls(
            generation=g.generation,
            n_evals=g.n_evals,
            best=g.best,
            best_so_far=best_so_far,
            front_min=front_min,
            hypervolume=g.hypervolume,
            wall_time_s=g.wall_time_s,
            created_at=g.created_at,
        )


class GenerationPage(BaseModel):
    """Generations after ``after`` (cursor pagination: pass ``next_after`` to poll on)."""

    items: list[GenerationOut]
    limit: int
    after: int | None
    next_after: int | None = Field(description="Last generation returned (or `after`).")
