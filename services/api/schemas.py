"""Request and response models of the API (what goes in, what comes out).

Input models forbid unknown fields. Job specs and robot specs are received as plain JSON
objects and validated by legcore itself (``services.api.validation``) so that errors name the
spec's own fields; their OpenAPI schemas are legcore's (``JobSpec``, ``RobotSpec``), inlined.
Output models are built from the store's frozen records by the ``from_record`` helpers.
"""

from __future__ import annotations

from datetime import datetime
from functools import cache
from typing import Annotated, Any, Generic, Literal, TypeVar

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    StrictInt,
    TypeAdapter,
    WithJsonSchema,
    model_validator,
)

from legcore.jobspec import JobSpec
from legcore.robots import RobotSpec
from services.api.validation import RobotSummary
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
    GenerationRecord,
    JobRecord,
    ParetoPointRecord,
    ResultRecord,
    SweepRecord,
)
from services.store.tables import JobStatus

T = TypeVar("T")

#: Default and maximum page sizes of every listing.
DEFAULT_LIMIT = 50
MAX_LIMIT = 1000


def inline_json_schema(schema: dict[str, Any]) -> dict[str, Any]:
    """``schema`` with every ``#/$defs/...`` reference replaced by its definition.

    OpenAPI components and pydantic's ``$defs`` do not mix inside a plain ``dict`` field, so
    the spec schemas are inlined; ``discriminator`` keywords (whose mappings point into
    ``$defs``) are dropped: each member's ``kind`` is a ``const`` anyway.
    """
    defs: dict[str, Any] = schema.get("$defs", {})

    def resolve(node: Any, seen: tuple[str, ...]) -> Any:
        if isinstance(node, dict):
            ref = node.get("$ref")
            if isinstance(ref, str) and ref.startswith("#/$defs/"):
                name = ref.split("/")[-1]
                if name in seen:  # recursive model: stop expanding
                    return {"type": "object"}
                target = resolve(defs[name], (*seen, name))
                extra = {k: v for k, v in node.items() if k != "$ref"}
                return {**target, **resolve(extra, seen)}
            return {
                k: resolve(v, seen) for k, v in node.items() if k not in ("$defs", "discriminator")
            }
        if isinstance(node, list):
            return [resolve(v, seen) for v in node]
        return node

    return resolve(schema, ())


@cache
def job_spec_schema() -> dict[str, Any]:
    """The JSON schema of a job spec (legcore's ``JobSpec``), inlined."""
    schema = inline_json_schema(TypeAdapter(JobSpec).json_schema())
    schema["description"] = (
        "The job spec of `legopt run`. `robot`: a catalog name, the id (or name) of one of your "
        "stored robots, or an inline DH/URDF robot spec."
    )
    return schema


@cache
def robot_spec_schema() -> dict[str, Any]:
    """The JSON schema of an inline robot spec (legcore's ``RobotSpec``: DH or URDF), inlined."""
    return inline_json_schema(TypeAdapter(RobotSpec).json_schema())


#: A job spec document (validated by legcore in the route, so errors name its fields).
JobSpecDoc = Annotated[dict[str, Any], WithJsonSchema(job_spec_schema())]
#: An inline robot spec document (validated and built by legcore in the route).
RobotSpecDoc = Annotated[dict[str, Any], WithJsonSchema(robot_spec_schema())]


class _In(BaseModel):
    model_config = ConfigDict(extra="forbid")


class ErrorOut(BaseModel):
    """Every non-validation error: ``{"detail": "message"}``."""

    detail: str


class Page(BaseModel, Generic[T]):
    """One page of a listing."""

    items: list[T]
    total: int = Field(description="Number of matching items (all pages).")
    limit: int
    offset: int


# --------------------------------------------------------------------------- robots

_DH_EXAMPLE: Any = {
    "kind": "dh",
    "name": "two_link",
    "joints": [
        {
            "a": 0.3,
            "mass": 1.0,
            "com": [-0.15, 0, 0],
            "inertia": [[0.001, 0, 0], [0, 0.008, 0], [0, 0, 0.008]],
        },
        {
            "a": 0.25,
            "mass": 0.8,
            "com": [-0.125, 0, 0],
            "inertia": [[0.001, 0, 0], [0, 0.005, 0], [0, 0, 0.005]],
        },
    ],
}


class RobotValidate(_In):
    """A robot model: an inline DH/URDF ``spec`` or a ``catalog`` name (exactly one)."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={"examples": [{"spec": _DH_EXAMPLE}, {"catalog": "puma560"}]},
    )

    spec: RobotSpecDoc | None = Field(default=None, description="Inline DH or URDF robot spec.")
    catalog: str | None = Field(default=None, max_length=64, description="A catalog robot name.")

    @model_validator(mode="after")
    def _exactly_one(self) -> RobotValidate:
        if (self.spec is None) == (self.catalog is None):
            raise ValueError("give exactly one of 'spec' (an inline robot) or 'catalog' (a name)")
        return self


class RobotCreate(RobotValidate):
    """A robot to store under ``name`` (unique per API key)."""

    model_config = ConfigDict(
        extra="forbid",
        json_schema_extra={
            "examples": [
                {"name": "my_arm", "spec": _DH_EXAMPLE},
                {"name": "puma", "catalog": "puma560"},
            ]
        },
    )

    name: str = Field(min_length=1, max_length=200)


class RobotSummaryOut(BaseModel):
    """What the built model looks like."""

    name: str
    kind: Literal["serial", "legged"]
    nq: int = Field(description="Degrees of freedom (all legs together for a legged robot).")
    joint_names: list[str]
    n_legs: int
    mass_kg: float = Field(description="Total mass of the links (and body), kg.")
    electrical_motors: int = Field(description="Joints with a full DC motor model (Kt, Ke, R).")

    @classmethod
    def from_summary(cls, s: RobotSummary) -> RobotSummaryOut:
        return cls(
            name=s.name,
            kind=s.kind,  # type: ignore[arg-type]
            nq=s.nq,
            joint_names=list(s.joint_names),
            n_legs=s.n_legs,
            mass_kg=s.mass_kg,
            electrical_motors=s.electrical_motors,
        )


RobotSource = Literal["catalog", "dh", "urdf"]


class RobotOut(BaseModel):
    """A robot in a listing. Catalog entries have ``builtin`` true and their name as id."""

    id: str
    name: str
    source: RobotSource
    catalog: str | None = Field(default=None, description="The catalog name (catalog robots).")
    builtin: bool = False
    created_at: datetime | None = None


class RobotDetail(RobotOut):
    """A robot with its spec and the summary of its built model."""

    spec: Any = Field(description="The inline spec, or {'catalog': name}.")
    inline_spec: Any = Field(
        default=None,
        description="The model as an inline DH/URDF spec (serial robots, catalog ones too, and "
        "URDF legged robots): copy it to modify the robot, or use it as a sweep base to sweep "
        "its parameters. Null for the catalog's legged robots.",
    )
    summary: RobotSummaryOut


class RobotValidation(BaseModel):
    """Result of ``POST /robots/validate``: the model was validated and built."""

    valid: Literal[True] = True
    source: RobotSource
    summary: RobotSummaryOut


class CatalogEntry(BaseModel):
    """A robot of the catalog (from the seed papers)."""

    name: str
    kind: Literal["serial", "legged"]
    nq: int
    n_legs: int
    joint_names: list[str]
    source: str = Field(description="Provenance: the seed paper, tables and assumed values.")


# --------------------------------------------------------------------------- jobs


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
    best_objective: Any = Field(default=None, description="Best objective(s) so far.")
    feasible: bool | None = Field(default=None, description=FEASIBLE_DESCRIPTION)
    violations: list[ViolationOut] = Field(
        default_factory=list, description=VIOLATIONS_DESCRIPTION
    )
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

    spec: Any

    @classmethod
    def from_record(cls, job: JobRecord, spec: Any = None) -> JobDetail:
        """``spec``: the job's full spec (``repository.job_spec``; default: the record's)."""
        spec = spec if spec is not None else job.spec
        return cls(**JobOut.from_record(job, spec).model_dump(), spec=spec)


class BaselineOut(BaseModel):
    """A baseline solution of the study (the seed paper's references) and its metrics."""

    name: str
    metrics: Any = Field(
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
    violations: list[ViolationOut] = Field(
        default_factory=list, description=VIOLATIONS_DESCRIPTION
    )
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
    objectives: Any = Field(
        description="Objectives of the best solution as stored by the worker: "
        '{"names": [...], "values": {name: value}}.'
    )
    best_x: Any = Field(description="Decision vector of the best solution.")
    metrics: Any = Field(description="Key metrics of the best solution (energy J, ...).")
    summary: Any = Field(description="Per-joint table, study extras, optimizer info, history.")
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


class ParetoPointOut(BaseModel):
    """One point of the final Pareto front."""

    index: int
    x: Any
    objectives: Any

    @classmethod
    def from_record(cls, p: ParetoPointRecord) -> ParetoPointOut:
        return cls(index=p.index, x=p.x, objectives=p.objectives)


class ParetoPage(Page[ParetoPointOut]):
    """A page of the Pareto front, with the objective names of the columns."""

    objective_names: list[str]


class GenerationOut(BaseModel):
    """Progress of one generation."""

    generation: int
    n_evals: int
    best: Any = Field(
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


# --------------------------------------------------------------------------- sweeps

_SWEEP_EXAMPLE: Any = {
    "base": {"problem": {"kind": "swing_energy"}, "optimizer": {"kind": "ga"}},
    "grid": {"optimizer.params.mutation_rate": [0.01, 0.03]},
    "seeds": [1, 2, 3],
}


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
    overrides: dict[str, Any] = Field(description="Value of every swept path in this job.")
    progress: float
    best_objective: Any = None
    objectives: Any = Field(default=None, description="Final objectives (succeeded jobs).")
    metrics: Any = Field(default=None, description="Final key metrics (succeeded jobs).")
    feasible: bool | None = Field(default=None, description=FEASIBLE_DESCRIPTION)
    error: str | None = None


class SweepOut(SweepSummary):
    """A sweep: base spec, axes, counts and the table of its jobs (paginated)."""

    base: Any
    axes: Any
    columns: list[str] = Field(description="The swept paths (keys of each row's overrides).")
    objective_names: list[str]
    table: Page[SweepRow]


# --------------------------------------------------------------------------- health


class HealthOut(BaseModel):
    """Liveness."""

    status: Literal["ok"] = "ok"


class ReadyOut(BaseModel):
    """Readiness: the database answers and its schema is at the head revision."""

    status: Literal["ready"] = "ready"
    revision: str


__all__ = [
    "DEFAULT_LIMIT",
    "MAX_LIMIT",
    "ArtifactOut",
    "JobFacts",
    "BaselineOut",
    "CatalogEntry",
    "ErrorOut",
    "GenerationOut",
    "GenerationPage",
    "HealthOut",
    "JobDetail",
    "JobOut",
    "JobSpecDoc",
    "Page",
    "ParetoPage",
    "ParetoPointOut",
    "ReadyOut",
    "ResultOut",
    "RobotCreate",
    "RobotDetail",
    "RobotOut",
    "RobotSpecDoc",
    "RobotSummaryOut",
    "RobotValidate",
    "RobotValidation",
    "SweepCreate",
    "SweepCreated",
    "SweepOut",
    "SweepRow",
    "SweepSummary",
    "TaskOut",
    "ViolationOut",
    "feasible_of",
    "inline_json_schema",
    "job_spec_schema",
    "objective_names",
    "robot_spec_schema",
    "violations_out",
]
