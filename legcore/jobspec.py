"""The job specification: one document for `legopt run`, `POST /api/v1/jobs` and the worker.

    {"robot": "calderon_leg",                      # catalog name, or an inline robot spec
     "problem": {"kind": "swing_energy", ...},     # study kind + its parameters
     "optimizer": {"kind": "ga", "params": {...}}, # optional: the seed's own by default
     "seed": 1, "tags": ["study-a"],               # optional: labels for the dashboard
     "budget": {"generations": 100},               # optional: the seed's own by default
     "record": true}

Unknown keys are rejected everywhere; every error names its field (``problem.obstacle``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any, Literal, Union

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    StrictInt,
    TypeAdapter,
    ValidationError,
    model_validator,
)

from legcore.optimizers import get_algorithm
from legcore.robots.spec import RobotSpec
from legcore.studies.registry import studies
from legcore.studies.study import StudyParams

__all__ = [
    "Budget",
    "JobSpec",
    "OptimizerSpec",
    "ProblemSpec",
    "parse_job_spec",
    "spec_error_locations",
]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class OptimizerSpec(_Strict):
    """An optimiser by kind with its parameters (see docs/optimizers.md for each kind's).

    ``refine``: polish the best solution by gradient-based SLSQP on the problem's continuous
    relaxation (at most ``refine_max_iter`` iterations) before it is decoded; single-objective
    problems only (:mod:`legcore.optimizers.refine`; never returns a worse point)."""

    kind: Literal["ga", "hka", "moead", "nsga2"]
    params: dict[str, Any] = Field(default_factory=dict)
    refine: bool = False
    refine_max_iter: StrictInt = Field(default=100, ge=1, le=1000)

    @model_validator(mode="after")
    def _params_valid(self) -> OptimizerSpec:
        try:
            get_algorithm(self.kind, **self.params)
        except (ValueError, TypeError) as exc:
            raise ValueError(f"params.{exc}") from None
        return self


class Budget(_Strict):
    """When to stop: the first of the given limits (none given → the study's default
    generations). ``ftol``: stop when the best objective improved by less than ``ftol`` over the
    last ``window`` generations (seed 001's stall rule)."""

    generations: StrictInt | None = Field(default=None, ge=1, le=100_000)
    evaluations: StrictInt | None = Field(default=None, ge=1, le=10**9)
    wall_time_s: float | None = Field(default=None, gt=0, le=7 * 24 * 3600)
    ftol: float | None = Field(default=None, gt=0)
    window: StrictInt = Field(default=10, ge=1, le=10_000)


def _problem_union() -> Any:
    params = [s.params for s in studies().values()]
    if not params:
        raise RuntimeError("no study kinds are available")
    union = params[0] if len(params) == 1 else Union[tuple(params)]  # noqa: UP007
    return Annotated[union, Field(discriminator="kind")]


ProblemSpec = _problem_union()


Tag = Annotated[str, Field(min_length=1, max_length=40, pattern=r"^[A-Za-z0-9_.:-]+$")]
"""A job tag: letters, digits, ``_ - . :`` (no spaces or commas), 1–40 characters."""


class JobSpec(_Strict):
    """A whole job. ``robot`` None means the study's default robot; ``optimizer`` None the
    seed's algorithm and settings; an empty ``budget`` the seed's number of generations."""

    name: str | None = Field(default=None, max_length=200)
    tags: list[Tag] = Field(
        default_factory=list,
        max_length=16,
        description="labels to find the job by (dashboard filter and search): up to 16, each "
        "1-40 characters of letters, digits, '_', '-', '.', ':'",
    )
    robot: str | RobotSpec | None = None
    if TYPE_CHECKING:
        problem: StudyParams
    else:
        problem: ProblemSpec
    optimizer: OptimizerSpec | None = None
    seed: StrictInt = Field(default=0, ge=0, le=2**32 - 1)
    budget: Budget = Field(default_factory=Budget)
    record: bool = True


_ADAPTER = TypeAdapter(JobSpec)


def parse_job_spec(data: dict[str, Any] | JobSpec) -> JobSpec:
    """Validate a mapping (from JSON/YAML) into a :class:`JobSpec` (pydantic ValidationError)."""
    if isinstance(data, JobSpec):
        return data
    return _ADAPTER.validate_python(data)


def spec_error_locations(exc: ValidationError, data: Any) -> list[tuple[list[str | int], str]]:
    """``(loc, message)`` of each error of a job spec, without the study kind pydantic inserts
    in ``problem`` locations (``problem.swing_energy.obstacle`` → ``problem.obstacle``)."""
    problem = data.get("problem") if isinstance(data, dict) else None
    kind = problem.get("kind") if isinstance(problem, dict) else None
    out = []
    for err in exc.errors():
        loc = list(err["loc"])
        if kind is not None and loc[:2] == ["problem", kind]:
            del loc[1]
        out.append((loc, str(err["msg"])))
    return out
