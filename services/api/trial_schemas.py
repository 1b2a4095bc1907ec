"""Response models of a job's trials: every stored evaluation (``GET /jobs/{id}/trials``),
their columns for a parallel-coordinates plot and the parameters' importance."""

from __future__ import annotations

from pydantic import BaseModel, Field

from services.api.dashboard_schemas import Quantity


class TrialOut(BaseModel):
    """One evaluated solution."""

    trial: int = Field(description="Its number among the job's stored evaluations (0-based, "
                       "generation order); the id to ask its motion or recording by.")  # fmt: skip
    generation: int = Field(description="The generation that evaluated it (1 = initial).")
    x: list[float | None] = Field(description="Decision variables, as `variables` name them.")
    objectives: list[float | None] = Field(
        description="Objectives as the front holds them (minimised), as `objectives` name them."
    )
    cv: float = Field(description="Total constraint violation (0 = feasible).")
    feasible: bool


class TrialsMeta(BaseModel):
    """What a job's trials are and how many are kept."""

    job_id: str
    objectives: list[Quantity]
    variables: list[Quantity]
    stored: int = Field(description="Evaluations stored for the job.")
    bound: int = Field(description="At most this many are stored per job (plus its last "
                       "generation's): beyond it, every stride-th generation is kept.")  # fmt: skip
    generations: list[int] = Field(description="The generations stored, ascending.")


class TrialPage(TrialsMeta):
    """A page of a job's trials, filtered and sorted."""

    matched: int = Field(description="Trials that pass the filters.")
    offset: int
    limit: int
    sort: str
    descending: bool
    items: list[TrialOut]


class TrialColumns(TrialsMeta):
    """Columns of (a sample of) the matched trials, for a parallel-coordinates plot: one value
    list per variable and objective, in ``trial`` order."""

    matched: int
    trial: list[int]
    feasible: list[bool]
    x_values: list[list[float | None]] = Field(description="Per variable, its values.")
    objective_values: list[list[float | None]] = Field(
        description="Per objective, its values (as the front holds them)."
    )


class ImportanceOut(BaseModel):
    """How much each decision variable explains of each objective, over the stored trials."""

    job_id: str
    method: str = Field(description="The estimator and how it was fitted.")
    trials: int = Field(description="Feasible trials the estimate is fitted on.")
    variables: list[Quantity]
    objectives: list[Quantity]
    importance: list[list[float]] = Field(
        description="Per objective, per variable: its share (they sum to 1 per objective)."
    )


__all__ = ["ImportanceOut", "TrialColumns", "TrialOut", "TrialPage", "TrialsMeta"]
