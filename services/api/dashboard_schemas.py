"""Response models of the dashboard's routes (jobs page, fronts, motions, sweep cells, robots)."""

from __future__ import annotations

import math
from datetime import datetime
from typing import Any

from pydantic import BaseModel, Field, JsonValue

from services.api.schemas.common import BestObjective
from services.api.verdict_schemas import (
    FEASIBLE_DESCRIPTION,
    VIOLATIONS_DESCRIPTION,
    ViolationOut,
    violations_out,
)
from services.store.dashboard_queries import JobRow
from services.store.records import BaselineRecord
from services.store.sql import COUNT_CAP
from services.store.states import JobStatus


class Quantity(BaseModel):
    """An objective, metric or decision variable with its readable label and SI unit."""

    name: str
    label: str
    unit: str = Field(description="SI unit ('' when dimensionless or unknown).")
    axis: str = Field(description="label [unit], as plots show it.")
    sense: str = Field(default="", description="min / max when smaller / larger is better.")


def quantities(names: list[str] | tuple[str, ...], kind: str | None = None) -> list[Quantity]:
    """Readable labels and units of the result keys ``names`` of the study ``kind``."""
    from services.api.quantities import describe_all

    return [Quantity(**d) for d in describe_all(names, kind)]


class NamedValue(BaseModel):
    """A quantity's value in its own sign, with its name and SI unit."""

    name: str = Field(description="Its key (a maximised quantity under its own name).")
    label: str
    unit: str = Field(description="SI unit ('' when dimensionless).")
    value: float | None


def named_best(best: BestObjective, facts: object, kind: str | None) -> list[NamedValue]:
    """The best-so-far objectives named, each in its own sign and unit (``neg_score`` becomes
    ``score``, positive); [] when the job's objective names are not known."""
    from legcore.studies.metric_names import display_objective

    names = facts.get("objectives") if isinstance(facts, dict) else None
    values = best if isinstance(best, list) else [best] if best is not None else []
    if not isinstance(names, list) or len(names) != len(values):
        return []
    out = []
    for name, value in zip(names, values, strict=True):
        shown, signed = display_objective(str(name), value)
        q = quantities([shown], kind)[0]
        out.append(NamedValue(name=shown, label=q.label, unit=q.unit, value=signed))
    return out


class JobRowOut(BaseModel):
    """One line of the jobs page."""

    id: str
    name: str | None
    kind: str
    robot: str
    optimizer: str
    seed: int
    tags: list[str]
    status: JobStatus
    sweep_id: str | None
    generation: int
    total_generations: int
    progress: float
    best_objective: BestObjective = None
    best_named: list[NamedValue] = Field(
        default_factory=list,
        description="`best_objective` named, each value in its own sign and unit (a maximised "
        "quantity positive, under its own name); empty when the objectives are not known.",
    )
    feasible: bool | None = Field(default=None, description=FEASIBLE_DESCRIPTION)
    violations: list[ViolationOut] = Field(default_factory=list, description=VIOLATIONS_DESCRIPTION)
    attempts: int
    cancel_requested: bool
    error: str | None
    created_at: datetime
    started_at: datetime | None
    finished_at: datetime | None

    @classmethod
    def from_row(cls, row: JobRow) -> JobRowOut:
        job = row.job
        return cls(
            id=job.id,
            name=row.name,
            kind=row.kind,
            robot=row.robot,
            optimizer=row.optimizer,
            seed=row.seed,
            tags=list(row.tags),
            status=job.status,
            sweep_id=job.sweep_id,
            generation=job.progress_generation,
            total_generations=job.total_generations,
            progress=job.progress,
            best_objective=job.best_objective,
            best_named=named_best(job.best_objective, job.facts, row.kind),
            feasible=job.feasible,
            violations=violations_out(job.violations),
            attempts=job.attempt_count,
            cancel_requested=job.cancel_requested,
            error=job.error_message,
            created_at=job.created_at,
            started_at=job.started_at,
            finished_at=job.finished_at,
        )


#: The jobs page's count cap, as the docs write numbers (1 000).
_CAP, _CAP_1 = (f"{n:,}".replace(",", " ") for n in (COUNT_CAP, COUNT_CAP + 1))


class JobRowPage(BaseModel):
    """A page of the jobs page: rows, how many match, and the cursor of the next page."""

    items: list[JobRowOut]
    total: int = Field(
        description=f"Jobs matching the filters (all pages), counted up to {_CAP_1}: when "
        f"`total_exact` is false, more than {_CAP} match (an exact count would cost what every "
        "match costs, more as the store grows)."
    )
    total_exact: bool = Field(
        description="True when `total` is the number of matching jobs; false when the count "
        f'stopped at {_CAP_1} (show "more than {COUNT_CAP:,}").'
    )
    limit: int
    offset: int
    next_cursor: str | None = Field(
        default=None,
        description="Pass as `cursor` for the next page (same sort and order); null on the "
        "last page.",
    )


class Choice(BaseModel):
    """A value a filter of the jobs page can take."""

    value: str
    label: str


class DashboardOptions(BaseModel):
    """What the jobs page's filters offer."""

    kinds: list[Choice]
    optimizers: list[Choice]
    statuses: list[str]
    sorts: list[str]


class FrontPointOut(BaseModel):
    """One point of a job's final front: objectives and decision vector by position, and its
    metrics by name (labelled in the front's ``metrics``)."""

    index: int
    objectives: list[float | None]
    x: list[float | None]
    metrics: dict[str, float | None] | None = Field(
        default=None,
        description="The point's metrics (SI, flags as 0/1), decoded again from its decision "
        "vector; null while they are being computed (`point_metrics`: pending) or when the "
        "point cannot be decoded.",
    )


class BaselineMark(BaseModel):
    """A baseline (the study's reference solution, e.g. the paper's own) on the front plot."""

    name: str
    objectives: list[float | None] = Field(description="In the order of `objectives`.")
    metrics: dict[str, bool | int | float | str] = Field(
        description="Its scalar metrics by name (labelled in the front's `metrics`)."
    )

    @classmethod
    def from_record(cls, b: BaselineRecord, names: list[str]) -> BaselineMark:
        """A stored baseline (its decoded summary) with its objectives in the order of
        ``names`` (None where it has none, or not a finite number) and its scalar metrics."""
        doc: dict[str, Any] = b.metrics if isinstance(b.metrics, dict) else {}
        raw_obj, raw_met = doc.get("objectives"), doc.get("metrics")
        objectives: dict[str, Any] = raw_obj if isinstance(raw_obj, dict) else {}
        metrics: dict[str, Any] = raw_met if isinstance(raw_met, dict) else doc
        return cls(
            name=b.name,
            objectives=[finite_or_none(objectives.get(n)) for n in names],
            metrics={k: v for k, v in metrics.items() if isinstance(v, int | float | str | bool)},
        )


def finite_or_none(v: Any) -> float | None:
    """``v`` as a float when it is a finite number (not a bool), else None."""
    if isinstance(v, bool) or not isinstance(v, int | float):
        return None
    return float(v) if math.isfinite(v) else None


class PaperMark(BaseModel):
    """The paper's own solution (its start or its optimum) on the front plot, in the order of
    ``objectives``; only when the paper printed a value for every objective."""

    label: str = Field(description="paper's start | paper's optimum")
    objectives: list[float]


class PaperValue(BaseModel):
    """The paper's own number for one metric (our unit): at its start and at its optimum."""

    symbol: str = Field(description="The paper's name for it ('' when it is ours).")
    start: float | None
    optimum: float | None
    note: str = ""


class PaperOut(BaseModel):
    """The seed paper's own numbers for this job (``examples/papers/paper_numbers.yaml``)."""

    source: str
    marks: list[PaperMark]
    metrics: dict[str, PaperValue]


class FrontOut(BaseModel):
    """Everything the front plot and table of one job need."""

    job_id: str
    status: JobStatus
    objectives: list[Quantity]
    variables: list[Quantity]
    metrics: list[Quantity] = Field(
        description="Labels of the metrics of the result and of the front's points."
    )
    points: list[FrontPointOut]
    point_metrics: str = Field(
        default="ready",
        description="ready: every point's `metrics` is given; pending: being computed (the "
        "first request for a large front): ask again after a few seconds; unavailable: the "
        "job's spec cannot be decoded again (`point_metrics_note` says why).",
    )
    point_metrics_note: str | None = None
    best_index: int | None = Field(description="The point closest to the reported optimum.")
    baselines: list[BaselineMark]
    hypervolume_ref: list[float] | None
    paper: PaperOut | None = Field(
        default=None, description="The seed paper's own numbers, when the job is one of its cases."
    )


class MotionSignal(BaseModel):
    """One joint signal: ``values[j][i]`` is joint j at sample i."""

    name: str
    label: str
    unit: str
    values: list[list[float | None]]


class MotionOut(BaseModel):
    """One solution decoded again: which one, its objectives and metrics, its joint signals."""

    job_id: str
    source: str = Field(description="point | baseline | trial | best")
    index: int | None = None
    name: str | None = None
    x: list[float] | None
    objectives: dict[str, float]
    metrics: dict[str, float]
    t: list[float]
    joint_names: list[str]
    signals: list[MotionSignal]
    energy: list[float | None] | None
    source_samples: int = Field(default=0, description="Samples of the motion before thinning.")
    power_kind: str = "mechanical"
    recording_url: str | None = Field(
        default=None,
        description="Where this solution's Rerun recording is (front points and baselines).",
    )


class CellStat(BaseModel):
    """Mean and sample standard deviation over the jobs of a cell that have the value."""

    mean: float | None
    sd: float | None
    n: int


class SweepCell(BaseModel):
    """One cell of a sweep's grid: the jobs sharing every swept value but the seed."""

    index: int
    values: dict[str, JsonValue] = Field(
        description="The swept values (seed excluded): whatever JSON the spec takes at each "
        "path (a number, a name, a list, a robot's name)."
    )
    job_ids: list[str]
    seeds: list[int | None] = Field(description="Each job's seed (null: none set).")
    counts: dict[str, int]
    stats: dict[str, CellStat] = Field(description="Column name -> mean ± sd.")


class SweepCellsOut(BaseModel):
    """A sweep as a grid of cells; ``best`` names, per column, the index of the best cell
    (least mean for objectives, largest for a maximised objective and the hypervolume)."""

    sweep_id: str
    columns: list[str] = Field(description="The swept paths that make a cell (seed excluded).")
    stat_columns: list[Quantity]
    objective_names: list[str]
    cells: list[SweepCell]
    best: dict[str, int]
    hypervolume_ref: list[float] | None = Field(
        description="The sweep-wide reference point of the cells' hypervolumes."
    )


class CellFrontJob(BaseModel):
    """One job of a cell and its final front."""

    job_id: str
    seed: int | None
    points: list[list[float | None]] = Field(description="The front's objective vectors.")


class CellFront(BaseModel):
    """The final fronts of one cell's jobs (objective vectors)."""

    cell: int
    label: str
    jobs: list[CellFrontJob]


class SweepFrontsOut(BaseModel):
    """Fronts of chosen cells, for an overlay plot."""

    sweep_id: str
    objectives: list[Quantity]
    cells: list[CellFront]


class JointOut(BaseModel):
    """One joint of a robot: limits (SI) and the mass of the link it moves."""

    name: str
    leg: str | None = None
    lower: float | None
    upper: float | None
    velocity: float | None
    acceleration: float | None = Field(
        default=None, description="rad/s² (m/s²); null when the robot gives none."
    )
    effort: float | None
    link_mass_kg: float | None


class StudyFit(BaseModel):
    """Whether a study kind accepts the robot with its default task, and why not (what to
    change: ``field``); when it does, the rules its default task was derived by."""

    kind: str
    title: str
    accepts: bool
    field: str | None = None
    reason: str | None = None
    rules: dict[str, str] = Field(default_factory=dict)
    preset: str | None = None


class RobotView(BaseModel):
    """A robot's joints, limits, masses and the study kinds that accept it."""

    id: str
    name: str
    kind: str
    nq: int
    mass_kg: float
    legs: list[str]
    joints: list[JointOut]
    studies: list[StudyFit]
